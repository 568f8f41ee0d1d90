"""The JJF 1535-2015 protocol (``protocols/jjf1535-2015.toml``): schema, loading, and the
programme it runs on the virtual bench (:func:`plan`).

Every key is checked (unknown keys and sections refused, units in the names). The
programme follows the clauses in the order a laboratory runs them: bias records with
power cycles (7.2.8, 7.2.10, 7.2.11), warm-up records from power-on (7.2.9), the Q
scale-factor calibrations (7.2.1–7.2.4), threshold (7.2.6) and resolution (7.2.7), the
g-sensitivity positions (7.2.12), the static Allan record (7.2.13), the vibration-table
frequencies (7.2.15), and last the temperature points with a scale-factor calibration and
a bias record at each (7.2.5, 7.2.14) — last, so that no room-temperature item runs while
the chamber is still returning from the lower working temperature.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gonio.specs.jjf1535.formulas import bandwidth_grid
from gonio.protocol.programme import Segment
from gonio.errors import GonioError
from gonio.protocol.programme import calibration_segments as sf_segments
from gonio.protocol.rate import NNFLOAT, PFLOAT, PINT, TEMP_C, rate_series, read_sections
from gonio.formats.toml import Field

from gonio.specs.jjf1535.keys import KEY  # noqa: E402  (the one copy)

SCHEMAS = {
    "protocol": {"spec": Field("str"), "name": Field("str", default=""),
                 "room_temperature_c": Field("float", default=20.0, check=TEMP_C.check,
                                             expect=TEMP_C.expect),
                 "sample_interval_s": PFLOAT, "warmup_s": NNFLOAT},
    "scale_factor": {"lowest_rate_dps": PFLOAT, "highest_rate_dps": PFLOAT,
                     "rates_dps": Field("float_list", default=[], check=lambda x: x > 0,
                                        expect="rates > 0 (one direction)"),
                     "samples_below_100_dps": PINT, "samples_from_100_dps": PINT,
                     "rest_samples": PINT, "settle_s": NNFLOAT,
                     "calibrations": Field("int", check=lambda x: x >= 1, expect="Q ≥ 1"),
                     "interval_s": NNFLOAT, "power_off": Field("bool", default=True),
                     "order": Field("str", default="ascending", choices=("ascending", "alternating"))},
    "temperature": {"points_c": Field("float_list", default=[], check=TEMP_C.check,
                                         expect=TEMP_C.expect),
                    "ramp_c_per_min": PFLOAT, "soak_s": NNFLOAT, "bias_samples": PINT},
    "threshold": {"rates_dps": Field("float_list", check=lambda x: x > 0, expect="rates > 0"),
                  "samples": PINT, "rest_samples": PINT},
    "resolution": {"base_rate_dps": PFLOAT,
                   "increments_dps": Field("float_list", check=lambda x: x > 0, expect="> 0"),
                   "samples": PINT},
    "bias": {"records": PINT, "samples": PINT, "off_time_s": NNFLOAT,
             "stability_block_samples": PINT,
             "remove_earth_rate": Field("bool", default=True)},
    "warmup": {"records": PINT, "samples": PINT, "off_time_s": NNFLOAT, "window_samples": PINT,
               "block_samples": PINT, "nominal_stability_dph": PFLOAT},
    "g_sensitivity": {"samples": PINT, "settle_s": NNFLOAT},
    "arw": {"sample_interval_s": PFLOAT, "samples": PINT,
            "print_standard_statistic": Field("bool", default=True)},
    "bandwidth": {"estimated_bandwidth_hz": NNFLOAT, "rate_amplitude_dps": PFLOAT,
                  "cycles": PINT, "samples_per_cycle": PINT},
}


@dataclass(frozen=True)
class JJFProtocol:
    """A validated JJF 1535 protocol: the sections as dicts, and where it came from."""

    sections: dict
    path: Path | None

    def __getitem__(self, key: str) -> dict:
        return self.sections[key]

    def to_dict(self) -> dict:
        return self.sections


def load_protocol(path: str | Path = KEY) -> JJFProtocol:
    """Load and check a JJF 1535 protocol file (built-in name or path)."""
    secs, p = read_sections(path, SCHEMAS, KEY, (("protocol", "null_output"),
                                                 ("bias", "latitude_deg")))
    sf = secs["scale_factor"]
    rates = sf["rates_dps"]
    if rates and (len(rates) < 2 or len(set(rates)) != len(rates)):
        raise GonioError("expected at least 2 distinct rates of one direction (7.2.3 fits a "
                         "line through distinct rates)", file=p,
                         key="scale_factor.rates_dps")
    if not sf["rates_dps"] and not sf["lowest_rate_dps"] < sf["highest_rate_dps"]:
        raise GonioError("lowest_rate_dps must be below highest_rate_dps", file=p,
                         key="scale_factor.lowest_rate_dps")
    for sec, key in (("threshold", "rates_dps"), ("resolution", "increments_dps")):
        v = secs[sec][key]
        if any(b >= a for a, b in zip(v, v[1:])):
            raise GonioError("expected a strictly decreasing list", file=p, key=f"{sec}.{key}")
    b = secs["bias"]
    if 2 * b["stability_block_samples"] > b["samples"]:
        raise GonioError(f"need 2·stability_block_samples ≤ bias.samples = {b['samples']} "
                         "(eq (18) takes the standard deviation of at least two block means), "
                         f"got {b['stability_block_samples']}", file=p,
                         key="bias.stability_block_samples")
    w = secs["warmup"]
    if w["window_samples"] < 2 * w["block_samples"] or w["window_samples"] > w["samples"]:
        raise GonioError("need 2·block_samples ≤ window_samples ≤ samples", file=p,
                         key="warmup.window_samples")
    return JJFProtocol(secs, p)


def sf_rates(proto: JJFProtocol) -> list[float]:
    """The forward rates of 7.2.1.1 c) (R5 series or the explicit list)."""
    sf = proto["scale_factor"]
    return rate_series(sf["rates_dps"], sf["highest_rate_dps"], sf["lowest_rate_dps"])


def bandwidth_frequencies(proto: JJFProtocol, bench=None, *,
                          datasheet_bandwidth_hz: float | None = None) -> list[float]:
    """7.2.15.1 b) grid from f_est (the protocol's, else the gyro's datasheet value: the
    bench's, or ``datasheet_bandwidth_hz`` where there is no bench)."""
    f_est = proto["bandwidth"]["estimated_bandwidth_hz"] or (
        bench.gyro.datasheet_bandwidth_hz if bench is not None else datasheet_bandwidth_hz) or 0.0
    if not f_est > 0:
        raise GonioError("no estimated bandwidth: set bandwidth.estimated_bandwidth_hz",
                         key="bandwidth.estimated_bandwidth_hz")
    return bandwidth_grid(f_est)


def plan(proto: JJFProtocol, bench=None, *,
         datasheet_bandwidth_hz: float | None = None) -> list[Segment]:
    """The whole programme as bench segments (see module docstring for the order); the
    bench (or ``datasheet_bandwidth_hz``) only for the bandwidth's grid when the protocol
    sets no ``estimated_bandwidth_hz``."""
    P = proto.sections
    dt = P["protocol"]["sample_interval_s"]
    warm = P["protocol"]["warmup_s"]
    room = P["protocol"]["room_temperature_c"]
    segs: list[Segment] = []
    b = P["bias"]
    for m in range(b["records"]):                                    # 7.2.8, 7.2.10, 7.2.11
        segs.append(Segment("bias", m, 0, "record", b["samples"], dt, delay_s=warm,
                            power_on=True, off_time_s=b["off_time_s"]))
    w = P["warmup"]
    for n in range(w["records"]):                                    # 7.2.9
        segs.append(Segment("warmup", n, 0, "record", w["samples"], dt, power_on=True,
                            off_time_s=w["off_time_s"]))
    sf = P["scale_factor"]
    rates = sf_rates(proto)
    for m in range(sf["calibrations"]):                              # 7.2.1 – 7.2.4
        first = m == 0 or sf["power_off"]
        segs += sf_segments("scale_factor", m, rates, dt=dt, rest_samples=sf["rest_samples"],
                            n_low=sf["samples_below_100_dps"], n_high=sf["samples_from_100_dps"],
                            settle_s=sf["settle_s"], order=sf["order"],
                            first_delay_s=warm if first else sf["interval_s"],
                            power_on=first, off_time_s=sf["interval_s"] if m else 0.0)
    th = P["threshold"]                                              # 7.2.6
    for run, sign in ((0, 1.0), (1, -1.0)):
        step = 0
        for r in th["rates_dps"]:
            segs.append(Segment("threshold", run, step, "rest", th["rest_samples"], dt,
                                delay_s=sf["settle_s"]))
            segs.append(Segment("threshold", run, step + 1, "rate", th["samples"], dt,
                                sign * r, delay_s=sf["settle_s"]))
            step += 2
        segs.append(Segment("threshold", run, step, "rest", th["rest_samples"], dt,
                            delay_s=sf["settle_s"]))
    rs = P["resolution"]                                             # 7.2.7
    for run, sign in ((0, 1.0), (1, -1.0)):
        for j, d in enumerate(rs["increments_dps"]):
            segs.append(Segment("resolution", run, 2 * j, "base", rs["samples"], dt,
                                sign * rs["base_rate_dps"], delay_s=sf["settle_s"]))
            segs.append(Segment("resolution", run, 2 * j + 1, "increment", rs["samples"], dt,
                                sign * (rs["base_rate_dps"] + d), delay_s=sf["settle_s"]))
    gs = P["g_sensitivity"]                                          # 7.2.12
    positions = (("+x", "+y"), ("-x", "+y"), ("+y", "+z"), ("-y", "+z"), ("+z", "+x"),
                 ("-z", "+x"))
    for k, (up, north) in enumerate(positions):
        segs.append(Segment("g_sensitivity", 0, k, "position", gs["samples"], dt, up_axis=up,
                            north_axis=north, delay_s=warm if k == 0 else gs["settle_s"],
                            power_on=(k == 0), off_time_s=600.0))
    a = P["arw"]                                                     # 7.2.13
    segs.append(Segment("static", 0, 0, "record", a["samples"], a["sample_interval_s"],
                        delay_s=warm, power_on=True, off_time_s=600.0))
    bw = P["bandwidth"]                                              # 7.2.15
    for j, f in enumerate(bandwidth_frequencies(proto, bench,
                                                datasheet_bandwidth_hz=datasheet_bandwidth_hz)):
        fs = bw["samples_per_cycle"] * f
        segs.append(Segment("vibration", 0, j, "vibration", bw["cycles"] * bw["samples_per_cycle"],
                            1.0 / fs, freq_hz=f, vib_amplitude_dps=bw["rate_amplitude_dps"],
                            delay_s=warm if j == 0 else 2.0, power_on=(j == 0), off_time_s=600.0))
    t = P["temperature"]                                             # 7.2.5, 7.2.14
    temps = [None] + list(t["points_c"])
    for i, tc in enumerate(temps):
        delay = warm if i == 0 else t["soak_s"] + (abs(tc - (temps[i - 1] or room))
                                                   / t["ramp_c_per_min"] * 60.0)
        cal = sf_segments("sf_temperature", i, rates, dt=dt, rest_samples=sf["rest_samples"],
                          n_low=sf["samples_below_100_dps"], n_high=sf["samples_from_100_dps"],
                          settle_s=sf["settle_s"], order=sf["order"], first_delay_s=delay,
                          power_on=(i == 0), off_time_s=600.0, temperature_c=tc,
                          ramp=t["ramp_c_per_min"])
        segs += cal
        segs.append(Segment("bias_temperature", i, 0, "record", t["bias_samples"], dt,
                            temperature_c=tc, ramp_c_per_min=t["ramp_c_per_min"],
                            delay_s=sf["settle_s"]))
    return segs


def null_output(proto: JJFProtocol, bench) -> float:
    v = proto["protocol"]["null_output"]
    return float(bench.gyro.null_output) if v == "bench" else float(v)

