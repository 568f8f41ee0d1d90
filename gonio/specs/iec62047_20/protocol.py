"""The IEC 62047-20 protocol (``protocols/iec62047-20.toml``): schema, loading, and the
programme on the virtual bench (:func:`plan`).

Order: bias records with power on/off cycles (5.3.3.1, 5.3.3.4), records from power-on
(5.3.3.5, 5.3.3.9), the scale factor at
T_BASE, V_BASE (5.1.3.1), its stability at constant rates (5.1.3.7), the supply points
(5.1.3.5; one power-up, the supply re-set between the runs as 5.1.4.1 c) allows, so the
power-cycle scatter of K and b is common to the runs and cancels in eqs (7) and (26)), cross-axis rotations about X and Y (5.2), the static noise record (5.4), the
frequency band (5.5), then the temperature programme base → max → base → min → base
(5.3.4.4 e)) with a scale-factor calibration at each of the m + 1 temperatures on the way
(5.1.3.3, 5.1.3.4) and a bias record, input axis horizontal east, at every visit (5.3.3.6,
5.3.3.7).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gonio.protocol.programme import Segment
from gonio.errors import GonioError
from gonio.protocol.programme import calibration_segments as sf_segments
from gonio.protocol.rate import NNFLOAT, PFLOAT, PINT, TEMP_C, read_sections
from gonio.formats.toml import Field

from gonio.specs.iec62047_20.keys import KEY  # noqa: E402  (the one copy)

SCHEMAS = {
    "protocol": {"spec": Field("str"), "name": Field("str", default=""),
                 "operating_min_c": TEMP_C, "operating_max_c": TEMP_C,
                 "sample_interval_s": PFLOAT, "warmup_s": NNFLOAT},
    "scale_factor": {"full_scale_dps": PFLOAT,
                     "divisions": Field("int", check=lambda x: 2 <= x <= 1000,
                                       expect="n in [2, 1000] (≥ 5 recommended)"),
                     "samples": PINT, "settle_s": NNFLOAT},
    "temperature": {"divisions": Field("int", check=lambda x: 2 <= x <= 1000,
                                      expect="m in [2, 1000] (≥ 4 recommended)"),
                    "ramp_c_per_min": PFLOAT, "soak_s": NNFLOAT, "bias_samples": PINT},
    "supply": {"voltages_v": Field("float_list", check=lambda x: x > 0, expect="> 0")},
    "stability": {"rates_dps": Field("float_list"), "samples": PINT},
    "cross_axis": {"rate_dps": PFLOAT, "revolutions": PINT, "rest_samples": PINT},
    "bias": {"records": PINT, "samples": PINT, "off_time_s": NNFLOAT},
    "power_on": {"records": PINT, "samples": PINT, "off_time_s": NNFLOAT,
                 "reference_samples": PINT, "smoothing_samples": PINT,
                 "startup_band_dps": PFLOAT, "nominal_bias_dps": Field("float", default=0.0)},
    "noise": {"sample_interval_s": PFLOAT, "samples": PINT, "band_hz": PFLOAT,
              "density_at_hz": Field("float_list", check=lambda x: x > 0, expect="> 0"),
              "broadband_high_hz": Field("float", default=0.0, check=lambda x: x >= 0,
                                         expect="≥ 0 (0: the Nyquist frequency)")},
    "g_sensitivity": {"step_deg": Field("float", default=45.0,
                                        check=lambda x: 0.1 <= x <= 120 and abs(360 / x - round(360 / x)) < 1e-9,
                                        expect="a divisor of 360° in [0.1, 120]"),
                      "samples": Field("int", default=60, check=lambda x: x >= 1, expect="≥ 1"),
                      "settle_s": Field("float", default=10.0, check=lambda x: x >= 0, expect="≥ 0")},
    "resolution": {"steps_dps": Field("float_list", default=[], check=lambda x: x > 0,
                                      expect="steps > 0, decreasing"),
                   "samples": Field("int", default=30, check=lambda x: x >= 1, expect="≥ 1"),
                   "rest_samples": Field("int", default=30, check=lambda x: x >= 1, expect="≥ 1")},
    "frequency": {"frequencies_hz": Field("float_list", check=lambda x: x > 0, expect="> 0"),
                  "rate_amplitude_dps": PFLOAT, "cycles": Field("int", check=lambda x: x >= 4,
                                                                 expect="≥ 4 periods (5.5.4)"),
                  "samples_per_cycle": PINT},
}


@dataclass(frozen=True)
class IECProtocol:
    """A validated IEC 62047-20 protocol."""

    sections: dict
    path: Path | None

    def __getitem__(self, key: str) -> dict:
        return self.sections[key]


def load_protocol(path: str | Path = KEY) -> IECProtocol:
    """Load and check an IEC 62047-20 protocol file (built-in name or path)."""
    secs, p = read_sections(path, SCHEMAS, KEY, (("protocol", "null_output"),
                                                 ("protocol", "latitude_deg"),
                                                 ("protocol", "nominal_scale_factor")))
    pr = secs["protocol"]
    if not pr["operating_min_c"] < pr["operating_max_c"]:
        raise GonioError("operating_min_c must be below operating_max_c", file=p,
                         key="protocol.operating_min_c")
    st = secs["resolution"]["steps_dps"]
    if any(b >= a for a, b in zip(st, st[1:])):
        raise GonioError("expected a strictly decreasing list", file=p, key="resolution.steps_dps")
    f = secs["frequency"]["frequencies_hz"]
    if any(b <= a for a, b in zip(f, f[1:])):
        raise GonioError("expected strictly increasing frequencies", file=p,
                         key="frequency.frequencies_hz")
    return IECProtocol(secs, p)


def t_base(proto: IECProtocol) -> float:
    """T_BASE = midpoint of the operating range (5.1.3.1)."""
    pr = proto["protocol"]
    return 0.5 * (pr["operating_min_c"] + pr["operating_max_c"])


def temperatures(proto: IECProtocol) -> list[float]:
    """T_1 … T_{m+1}: the operating range in m equal steps (5.1.3.3)."""
    pr = proto["protocol"]
    m = proto["temperature"]["divisions"]
    lo, hi = pr["operating_min_c"], pr["operating_max_c"]
    return [lo + i * (hi - lo) / m for i in range(m + 1)]


def sf_rates(proto: IECProtocol) -> list[float]:
    """The positive rates k·x_FS/n, k = 1…n (5.1.3.1); with their negatives and 0: 2n + 1."""
    sf = proto["scale_factor"]
    n = sf["divisions"]
    return [k * sf["full_scale_dps"] / n for k in range(1, n + 1)]


def temperature_visits(proto: IECProtocol) -> list[float]:
    """base → max → base → min → base through every grid temperature (5.3.4.4 e))."""
    T = temperatures(proto)
    tb = t_base(proto)
    up = [t for t in T if t > tb + 1e-9]
    dn = [t for t in T if t < tb - 1e-9]
    return [tb] + up + up[-2::-1] + [tb] + dn[::-1] + dn[1:] + [tb]


def g_stand_runs() -> tuple[tuple[str, str, str], ...]:
    """The two tilting-stand set-ups of 5.3.4.5 (reading taken): (up axis, north axis, stand
    axis) at γ = 0. Run 0, "parallel": input axis (body z) up, the stand turns about body x
    (horizontal, north), so the acceleration along the input axis is g cos γ. Run 1,
    "perpendicular": input axis horizontal (north), body x up, the stand turns about the
    input axis, so the transverse components are g cos γ (body x) and −g sin γ (body y)."""
    return (("+z", "+x", "+x"), ("+x", "+z", "+z"))


def stand_angles(proto: IECProtocol) -> list[float]:
    """γ = 0, step, 2·step … < 360° (a whole turn in equal steps, so cos γ, sin γ and the
    constant are orthogonal and a transverse term cannot leak into the slope)."""
    step = proto["g_sensitivity"]["step_deg"]
    return [k * step for k in range(int(round(360.0 / step)))]


def plan(proto: IECProtocol, bench) -> list[Segment]:
    """The programme as bench segments (see module docstring)."""
    P = proto.sections
    dt = P["protocol"]["sample_interval_s"]
    warm = P["protocol"]["warmup_s"]
    tb = t_base(proto)
    sf = P["scale_factor"]
    rates = sf_rates(proto)
    tp = P["temperature"]
    ramp = tp["ramp_c_per_min"]
    soak_base = tp["soak_s"] + abs(tb - 20.0) / ramp * 60.0
    segs: list[Segment] = []
    b = P["bias"]
    for k in range(b["records"]):
        segs.append(Segment("bias", k, 0, "record", b["samples"], dt, temperature_c=tb,
                            ramp_c_per_min=ramp, delay_s=warm + (soak_base if k == 0 else 0.0),
                            power_on=True, off_time_s=b["off_time_s"]))
    po = P["power_on"]
    for k in range(po["records"]):
        segs.append(Segment("warmup", k, 0, "record", po["samples"], dt, temperature_c=tb,
                            ramp_c_per_min=ramp, power_on=True, off_time_s=po["off_time_s"]))
    kw = dict(dt=dt, rest_samples=sf["samples"], n_low=sf["samples"], n_high=sf["samples"],
              settle_s=sf["settle_s"], order="iec", temperature_c=tb, ramp=ramp)
    segs += sf_segments("scale_factor", 0, rates, first_delay_s=warm, power_on=True,
                        off_time_s=600.0, **kw)
    st = P["stability"]
    for j, r in enumerate(st["rates_dps"]):
        if r == 0:
            continue
        segs.append(Segment("scale_factor", 1, j, "rate", st["samples"], dt, r, temperature_c=tb,
                            ramp_c_per_min=ramp, delay_s=sf["settle_s"]))
    for i, v in enumerate(P["supply"]["voltages_v"]):       # one power-up, supply re-set
        segs += sf_segments("ratiometric", i, rates, first_delay_s=warm if i == 0 else sf["settle_s"],
                            power_on=(i == 0), off_time_s=600.0, supply_v=v, **kw)
    ca = P["cross_axis"]
    n_rev = int(round(ca["revolutions"] * 360.0 / ca["rate_dps"] / dt))
    for run, (up, north) in enumerate((("+x", "+y"), ("+y", "+z"))):
        segs.append(Segment("cross_axis", run, 0, "rest", ca["rest_samples"], dt, 0.0, up, north,
                            temperature_c=tb, delay_s=warm, power_on=True, off_time_s=600.0))
        segs.append(Segment("cross_axis", run, 1, "rate", n_rev, dt, ca["rate_dps"], up, north,
                            temperature_c=tb, delay_s=sf["settle_s"]))
        segs.append(Segment("cross_axis", run, 2, "rate", n_rev, dt, -ca["rate_dps"], up, north,
                            temperature_c=tb, delay_s=sf["settle_s"]))
        segs.append(Segment("cross_axis", run, 3, "rest", ca["rest_samples"], dt, 0.0, up, north,
                            temperature_c=tb, delay_s=sf["settle_s"]))
    gs = P["g_sensitivity"]                                           # 5.3.3.8 (tilting stand)
    for run, (up, north, axis) in enumerate(g_stand_runs()):
        for j, gam in enumerate(stand_angles(proto)):
            segs.append(Segment("g_sensitivity", run, j, "position", gs["samples"], dt,
                                up_axis=up, north_axis=north, stand_deg=gam, stand_axis=axis,
                                temperature_c=tb, delay_s=warm if j == 0 else gs["settle_s"],
                                power_on=(j == 0), off_time_s=600.0))
    rs = P["resolution"]                                              # 5.6 (from rest)
    for run, sign in ((0, 1.0), (1, -1.0)):
        if not rs["steps_dps"]:
            break
        for j, r in enumerate(rs["steps_dps"]):
            segs.append(Segment("resolution", run, 2 * j, "rest", rs["rest_samples"], dt,
                                temperature_c=tb, delay_s=warm if (run, j) == (0, 0) else sf["settle_s"],
                                power_on=(run, j) == (0, 0), off_time_s=600.0))
            segs.append(Segment("resolution", run, 2 * j + 1, "increment", rs["samples"], dt,
                                sign * r, temperature_c=tb, delay_s=sf["settle_s"]))
        segs.append(Segment("resolution", run, 2 * len(rs["steps_dps"]), "rest",
                            rs["rest_samples"], dt, temperature_c=tb, delay_s=sf["settle_s"]))
    nz = P["noise"]
    segs.append(Segment("static", 0, 0, "record", nz["samples"], nz["sample_interval_s"],
                        temperature_c=tb, delay_s=warm, power_on=True, off_time_s=600.0))
    fr = P["frequency"]
    for j, f in enumerate(fr["frequencies_hz"]):
        segs.append(Segment("vibration", 0, j, "vibration", fr["cycles"] * fr["samples_per_cycle"],
                            1.0 / (fr["samples_per_cycle"] * f), freq_hz=f, temperature_c=tb,
                            vib_amplitude_dps=fr["rate_amplitude_dps"],
                            delay_s=warm if j == 0 else 2.0, power_on=(j == 0), off_time_s=600.0))
    grid = temperatures(proto)
    done: set = set()
    prev = tb
    for k, T in enumerate(temperature_visits(proto)):
        delay = (warm if k == 0 else 0.0) + tp["soak_s"] + abs(T - prev) / ramp * 60.0
        prev = T
        if not any(abs(T - g) < 1e-9 for g in done):
            segs += sf_segments("sf_temperature", grid.index(min(grid, key=lambda g: abs(g - T))),
                                rates, first_delay_s=delay, power_on=(k == 0), off_time_s=600.0,
                                **{**kw, "temperature_c": T})
            done.add(T)
            delay = sf["settle_s"]
        segs.append(Segment("bias_temperature", k, 0, "record", tp["bias_samples"], dt,
                            up_axis="+y", north_axis="+x", temperature_c=T, ramp_c_per_min=ramp,
                            delay_s=delay, power_on=(k == 0 and not segs[-1].test == "sf_temperature"),
                            off_time_s=600.0))
    return segs
