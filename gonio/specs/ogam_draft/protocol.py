"""The optical draft's procedures as data: loading and validating a protocol (TOML).

The optical draft's built-in protocol (``protocols/<its default_protocol>.toml``, named by
the registry, :mod:`gonio.specs`) restates clauses 6, 7.1–7.7 and Annex A of the draft as
data; a laboratory writes its own protocol (say 24 points at 15°, or
5 repeats) without touching code. :func:`load_protocol` validates every key:
an unknown key, a wrong type or an impossible value is a
:class:`~gonio.errors.GonioError` naming the file and the key.

Sections: ``protocol``, ``conditions`` (Tables 1 and 2), ``session`` (warm-up,
Earth-rate compensation), ``scale_factor`` (7.1, 7.2), ``zero_stability`` (7.3),
``angle_deviation`` (7.4, 7.5), ``rate_consistency`` (7.6),
``pointing_consistency`` (7.7), ``annex_a``. Every test section is optional: a
protocol may hold only some of the draft's items. The optional sections
``[equal_division]`` (:class:`EdaProtocol`, for
:mod:`gonio.specs.ogam_draft.equal_division`) and ``[tilt_estimate]``
(:class:`TiltEstimatePlan`, for :mod:`gonio.specs.ogam_draft.tilt_estimate`), at the end of
this module, are added with :func:`register_section`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

from gonio.physics.earth import NAMED_AXES
from gonio.errors import GonioError
from gonio.units import ARCSEC_PER_DEG
from gonio.units import h_to_s
from gonio.resources import resolve
from gonio.formats.toml import Field, non_negative, positive, read_toml, validate_table

ORIENTATIONS = tuple(NAMED_AXES)


@dataclass(frozen=True)
class Round:
    """One round (测回): the table turns from ``start_deg`` to ``stop_deg``."""

    start_deg: float
    stop_deg: float
    max_rotation_s: float | None = None


@dataclass(frozen=True)
class RotationItem:
    """A test made of rounds at one rate and orientation (7.1, 7.4; each condition of 7.6/7.7)."""

    test: str
    clause: str
    rate_dps: float
    orientation: str
    series: int
    rest_s: float
    read_delay_s: float
    return_to_zero: bool
    rezero: bool
    rounds: tuple[Round, ...]
    max_time_to_reading_s: float | None = None
    #: A reading's table_deg must equal its round's stop − start within this (degrees).
    position_tolerance_deg: float = 0.001
    #: What a reading that breaks the position or time-to-reading check becomes:
    #: "exclude" (listed in unused_readings with the reason) or "error".
    on_bad_reading: str = "exclude"


@dataclass(frozen=True)
class ZeroStability:
    """7.3: readings at rest, ``interval_s`` apart."""

    clause: str
    orientation: str
    readings: int
    interval_s: float


@dataclass(frozen=True)
class Session:
    """Clause 7 preamble: warm-up, Earth-rate compensation, returns."""

    warm_up_s: float
    earth_compensation: str
    static_s: float
    return_rate_dps: float
    settle_s: float
    #: Computed compensation only: the latitude the operator uses (None: the site's).
    compensation_latitude_deg: float | None = None
    #: Computed compensation only: error of the azimuth the operator assumes for the
    #: table axis (compensation computed for azimuth + error), degrees.
    compensation_azimuth_error_deg: float = 0.0


@dataclass(frozen=True)
class Conditions:
    """Draft clause 5 (Tables 1 and 2): what the table and the room must meet."""

    table_axis_wobble_max_arcsec: float = 0.3
    table_positioning_mpe_arcsec: float = 0.1
    table_angle_range_deg: float = 360.0
    table_rate_max_dps: float = 300.0
    table_rate_error_rel: float = 1e-5
    table_orientations: tuple[str, ...] = ORIENTATIONS
    temperature_c: float = 20.0
    temperature_tolerance_c: float = 1.0
    thermometer_mpe_c: float = 0.2
    soak_h: float = 4.0
    humidity_min_pct: float = 30.0
    humidity_max_pct: float = 75.0


@dataclass(frozen=True)
class AnnexA:
    """Draft Annex A settings: the budget's inputs (A.4.1–A.4.4) and coverage factor (A.7)."""

    table_mpe_arcsec: float = 0.1
    tilt_bound_deg: float = 0.1
    zero_stability_dph: float = 0.005
    duration_min: float = 0.5
    repeatability_arcsec: float = 0.096
    #: None: k = t_95(ν_eff) (Welch–Satterthwaite); a number: k fixed by the laboratory.
    coverage_factor: float | None = None
    #: The defaults, per gyro type, of the bound on the instrument's scale-factor temperature
    #: coefficient |α_K|, ppm/°C, used when the readings do not state the instrument's own
    #: (``gonio.specs.ogam_draft.calibration.temperature_coeff_bound``): with the logged
    #: chamber deviation, or Table 2's tolerance, it gives K's chamber-temperature line
    #: (``item_uncertainty.chamber_temperature_line``; not in the draft's budget).
    sf_temperature_coeff_bound_rlg_ppm_per_c: float = 0.1
    sf_temperature_coeff_bound_fog_ppm_per_c: float = 1.0


@dataclass(frozen=True)
class Protocol:
    """A validated protocol. Test items that the file does not hold are ``None``."""

    name: str
    title: str
    specification: str
    conditions: Conditions
    session: Session
    annex_a: AnnexA
    scale_factor: RotationItem | None = None
    zero_stability: ZeroStability | None = None
    angle_deviation: RotationItem | None = None
    rate_consistency: tuple[RotationItem, ...] = ()
    rate_reference_dps: float = 60.0
    pointing_consistency: tuple[RotationItem, ...] = ()
    pointing_reference: str = "up"
    extra: dict = field(default_factory=dict)
    path: str = ""

    @property
    def equal_division(self):
        """The ``[equal_division]`` section (:class:`~gonio.specs.ogam_draft.protocol.EdaProtocol`) or None."""
        return self.extra.get("equal_division")

    @property
    def tilt_estimate(self):
        """The ``[tilt_estimate]`` section (:class:`~gonio.specs.ogam_draft.protocol.TiltEstimatePlan`) or None."""
        return self.extra.get("tilt_estimate")

    def items(self) -> list[RotationItem]:
        """Every rotation item in the order the bench runs them."""
        out = [x for x in (self.scale_factor, self.angle_deviation) if x is not None]
        return out + list(self.rate_consistency) + list(self.pointing_consistency)


_ORIENT = Field("str", choices=ORIENTATIONS)
_ROUND = {
    "start_deg": Field("float", 0.0),
    "stop_deg": Field("float"),
    "max_rotation_s": Field("float", None, positive, "> 0"),
}
_ROTATION_COMMON = {
    "clause": Field("str"),
    "orientation": Field("str", "up", choices=ORIENTATIONS),
    "series": Field("int", 1, positive, "an integer ≥ 1"),
    "rest_s": Field("float", 60.0, non_negative, "≥ 0"),
    "read_delay_s": Field("float", 10.0, non_negative, "≥ 0"),
    "return_to_zero": Field("bool", True),
    "rezero": Field("bool", True),
    "rounds": Field("table_list", None, schema=_ROUND),
    "max_time_to_reading_s": Field("float", None, positive, "> 0"),
    "position_tolerance_deg": Field("float", 0.001, positive, "> 0"),
    "on_bad_reading": Field("str", "exclude", choices=("exclude", "error")),
}
SCHEMA: dict[str, dict[str, Field]] = {
    "protocol": {
        "name": Field("str"),
        "title": Field("str", ""),
        "specification": Field("str", ""),
    },
    "conditions": {
        "table_axis_wobble_max_arcsec": Field("float", 0.3, non_negative, "≥ 0"),
        "table_positioning_mpe_arcsec": Field("float", 0.1, positive, "> 0"),
        "table_angle_range_deg": Field("float", 360.0, positive, "> 0"),
        "table_rate_max_dps": Field("float", 300.0, positive, "> 0"),
        "table_rate_error_rel": Field("float", 1e-5, non_negative, "≥ 0"),
        "table_orientations": Field("str_list", list(ORIENTATIONS), choices=ORIENTATIONS),
        "temperature_c": Field("float", 20.0),
        "temperature_tolerance_c": Field("float", 1.0, non_negative, "≥ 0"),
        "thermometer_mpe_c": Field("float", 0.2, non_negative, "≥ 0"),
        "soak_h": Field("float", 4.0, non_negative, "≥ 0"),
        "humidity_min_pct": Field("float", 30.0, lambda x: 0 <= x <= 100, "0–100"),
        "humidity_max_pct": Field("float", 75.0, lambda x: 0 <= x <= 100, "0–100"),
    },
    "session": {
        "warm_up_s": Field("float", h_to_s(1.0), non_negative, "≥ 0"),
        "earth_compensation": Field("str", "measured", choices=("measured", "computed", "none")),
        "static_s": Field("float", 60.0, positive, "> 0"),
        "return_rate_dps": Field("float", 60.0, positive, "> 0"),
        "settle_s": Field("float", 2.0, non_negative, "≥ 0"),
        "compensation_latitude_deg": Field("float", None, lambda x: abs(x) <= 90, "within ±90"),
        "compensation_azimuth_error_deg": Field("float", 0.0, lambda x: abs(x) <= 180,
                                                "within ±180"),
    },
    "scale_factor": {**_ROTATION_COMMON, "clause": Field("str", "7.1"),
                     "rate_dps": Field("float", 60.0, positive, "> 0"),
                     "rounds": Field("table_list", schema=_ROUND)},
    "zero_stability": {
        "clause": Field("str", "7.3"),
        "orientation": Field("str", "up", choices=ORIENTATIONS),
        "readings": Field("int", 15, lambda n: n >= 2, "an integer ≥ 2"),
        "interval_s": Field("float", 300.0, positive, "> 0"),
    },
    "angle_deviation": {**_ROTATION_COMMON, "clause": Field("str", "7.4"),
                        "rate_dps": Field("float", 60.0, positive, "> 0"),
                        "rounds": Field("table_list", schema=_ROUND)},
    "rate_consistency": {**_ROTATION_COMMON, "clause": Field("str", "7.6"),
                         "rates_dps": Field("float_list", check=positive, expect="rates > 0"),
                         "reference_rate_dps": Field("float", 60.0, positive, "> 0"),
                         "reuse_reference": Field("bool", True)},
    "pointing_consistency": {**_ROTATION_COMMON, "clause": Field("str", "7.7"),
                             "orientations": Field("str_list", choices=ORIENTATIONS),
                             "reference_orientation": Field("str", "up", choices=ORIENTATIONS),
                             "reuse_reference": Field("bool", True),
                             "rate_dps": Field("float", 60.0, positive, "> 0")},
    "annex_a": {
        "table_mpe_arcsec": Field("float", 0.1, positive, "> 0"),
        "tilt_bound_deg": Field("float", 0.1, lambda x: 0 <= x < 90, "0 ≤ tilt < 90"),
        "zero_stability_dph": Field("float", 0.005, non_negative, "≥ 0"),
        "duration_min": Field("float", 0.5, non_negative, "≥ 0"),
        "repeatability_arcsec": Field("float", 0.096, non_negative, "≥ 0"),
        # absent: k = t_95(ν_eff) (Welch–Satterthwaite); set: k fixed by the laboratory
        "coverage_factor": Field("float", None, positive, "> 0"),
        "sf_temperature_coeff_bound_rlg_ppm_per_c": Field("float", 0.1, positive, "> 0"),
        "sf_temperature_coeff_bound_fog_ppm_per_c": Field("float", 1.0, positive, "> 0"),
    },
}
_EXTRA: dict[str, tuple[dict[str, Field], Callable[[dict], Any] | None]] = {}


def register_section(name: str, schema: dict[str, Field],
                     factory: Callable[[dict], Any] | None = None) -> None:
    """Let another module add an optional protocol section (validated like the others).

    The parsed section (through ``factory`` if given) lands in ``Protocol.extra[name]``.
    """
    _EXTRA[name] = (schema, factory)


def _rounds(raw: list[dict]) -> tuple[Round, ...]:
    return tuple(Round(r["start_deg"], r["stop_deg"], r["max_rotation_s"]) for r in raw)


def _item(test: str, sec: dict, rate: float, orientation: str,
          rounds: tuple[Round, ...]) -> RotationItem:
    return RotationItem(test=test, clause=sec["clause"], rate_dps=rate, orientation=orientation,
                        series=sec["series"], rest_s=sec["rest_s"],
                        read_delay_s=sec["read_delay_s"], return_to_zero=sec["return_to_zero"],
                        rezero=sec["rezero"], rounds=rounds,
                        max_time_to_reading_s=sec["max_time_to_reading_s"],
                        position_tolerance_deg=sec["position_tolerance_deg"],
                        on_bad_reading=sec["on_bad_reading"])


def _check_rounds(item: RotationItem, key: str, file) -> None:
    for i, r in enumerate(item.rounds):
        if r.stop_deg == r.start_deg:
            raise GonioError("a round must turn the table (stop_deg equals start_deg)",
                             file=file, key=f"{key}.rounds[{i}]")


def parse_protocol(raw: dict, file: str | Path | None = None) -> Protocol:
    """Validate a parsed protocol table and build a :class:`Protocol`."""
    if not isinstance(raw, dict):
        raise GonioError("a protocol must be a TOML table", file=file)
    known = set(SCHEMA) | set(_EXTRA)
    head = raw.get("protocol")
    if isinstance(head, dict) and isinstance(head.get("spec"), str):
        # another specification's protocol names it in protocol.spec (the
        # rate readings under --spec of the optical draft blamed 'unknown section')
        raise GonioError(f"this protocol is for {head['spec']!r}, not for this calibration's "
                         f"specification (--spec, or the readings' '# spec:'): give "
                         f"--spec {head['spec']} or a protocol of this specification",
                         file=file, key="protocol.spec")
    for key in raw:
        if key not in known:
            raise GonioError(f"unknown section (known: {', '.join(sorted(known))})",
                             file=file, key=key)
    if "protocol" not in raw:
        raise GonioError("required section is missing", file=file, key="protocol")
    sec = {}
    for name, schema in SCHEMA.items():
        if name in raw:
            if not isinstance(raw[name], dict):
                raise GonioError("expected a table", file=file, key=name)
            sec[name] = validate_table(raw[name], schema, name, file)
        elif name in ("conditions", "session", "annex_a"):
            sec[name] = validate_table({}, schema, name, file)
    s = sec["session"]
    kw: dict[str, Any] = {}
    if "scale_factor" in sec:
        x = sec["scale_factor"]
        kw["scale_factor"] = _item("scale_factor", x, x["rate_dps"], x["orientation"],
                                   _rounds(x["rounds"]))
        _check_rounds(kw["scale_factor"], "scale_factor", file)
    if "zero_stability" in sec:
        z = sec["zero_stability"]
        kw["zero_stability"] = ZeroStability(z["clause"], z["orientation"], z["readings"],
                                             z["interval_s"])
    ad_rounds: tuple[Round, ...] = ()
    if "angle_deviation" in sec:
        x = sec["angle_deviation"]
        ad_rounds = _rounds(x["rounds"])
        kw["angle_deviation"] = _item("angle_deviation", x, x["rate_dps"], x["orientation"],
                                      ad_rounds)
        _check_rounds(kw["angle_deviation"], "angle_deviation", file)
    for name, what in (("rate_consistency", "rates_dps"), ("pointing_consistency", "orientations")):
        if name not in sec:
            continue
        x = sec[name]
        if x["rounds"] is not None:
            rounds = _rounds(x["rounds"])
        elif ad_rounds:
            # 7.6/7.7 calibrate E as 7.4 does: its rounds, without the 60 °/s time limits.
            rounds = tuple(replace(r, max_rotation_s=None) for r in ad_rounds)
        else:
            raise GonioError("needs its own rounds when the protocol has no angle_deviation",
                             file=file, key=f"{name}.rounds")
        items = []
        have_ad = "angle_deviation" in kw
        if name == "rate_consistency":
            ref = x["reference_rate_dps"]
            kw["rate_reference_dps"] = ref
            if ref not in x["rates_dps"]:
                raise GonioError(f"reference rate {ref} is not among rates_dps", file=file,
                                 key=f"{name}.reference_rate_dps")
            for v in x["rates_dps"]:
                if v == ref and x["reuse_reference"] and have_ad:
                    continue
                items.append(_item(name, x, v, x["orientation"], rounds))
        else:
            ref = x["reference_orientation"]
            kw["pointing_reference"] = ref
            if ref not in x["orientations"]:
                raise GonioError(f"reference orientation {ref} is not among orientations",
                                 file=file, key=f"{name}.reference_orientation")
            for o in x["orientations"]:
                if o == ref and x["reuse_reference"] and have_ad:
                    continue
                items.append(_item(name, x, x["rate_dps"], o, rounds))
        kw[name] = tuple(items)
    extra = {}
    for name, (schema, factory) in _EXTRA.items():
        if name in raw:
            if not isinstance(raw[name], dict):
                raise GonioError("expected a table", file=file, key=name)
            v = validate_table(raw[name], schema, name, file)
            extra[name] = factory(v) if factory else v
    p = sec["protocol"]
    check_protocol_ranges(sec, raw, file)
    return Protocol(name=p["name"], title=p["title"], specification=p["specification"],
                    conditions=Conditions(**{**sec["conditions"], "table_orientations":
                                             tuple(sec["conditions"]["table_orientations"])}),
                    session=Session(s["warm_up_s"], s["earth_compensation"], s["static_s"],
                                    s["return_rate_dps"], s["settle_s"],
                                    s["compensation_latitude_deg"],
                                    s["compensation_azimuth_error_deg"]),
                    annex_a=AnnexA(**sec["annex_a"]), extra=extra, path=str(file or ""), **kw)


#: Plausible ranges of protocol values (docs/formats.md, "Plausible ranges"):
#: durations in s, rates in °/s, angles in °, counts of series, rounds, readings.
MAX_DURATION_S: float = 172_800.0       # any one rest, static, warm-up or interval: 2 days
RATE_RANGE_DPS: tuple[float, float] = (1e-3, 1e4)
MAX_ANGLE_DEG: float = 10 * 360.0       # a round's start or stop: ten turns
MAX_SERIES: int = 1000
MAX_ROUNDS: int = 1000
MAX_LIST: int = 100                      # rates_dps, orientations
MAX_ARCSEC: float = ARCSEC_PER_DEG       # any *_arcsec value (MPE, wobble, repeatability)
COVERAGE_RANGE: tuple[float, float] = (0.5, 10.0)


def check_protocol_ranges(sec: dict, raw: dict, file) -> None:
    """Refuse protocol values outside their plausible ranges, naming the key.

    Durations at most :data:`MAX_DURATION_S`; rates within :data:`RATE_RANGE_DPS`;
    round angles within ±:data:`MAX_ANGLE_DEG`; at most :data:`MAX_SERIES` series,
    :data:`MAX_ROUNDS` rounds, :data:`MAX_LIST` rates or orientations; the total
    number of readings at most ``GONIO_MAX_READINGS`` (:mod:`gonio.limits`).
    """
    from gonio.limits import limit

    def bad(key, msg):
        raise GonioError(msg, file=file, key=key)

    total = 0
    for name, x in sec.items():
        if not isinstance(x, dict):
            continue
        for key, v in x.items():
            where = f"{name}.{key}"
            if isinstance(v, bool) or v is None:
                continue
            if key.endswith("_s") and isinstance(v, (int, float)) and v > MAX_DURATION_S:
                bad(where, f"{v:g} s is over the plausible {MAX_DURATION_S:g} s")
            if key.endswith("_arcsec") and isinstance(v, (int, float)) and abs(v) > MAX_ARCSEC:
                bad(where, f"{v:g}″ is over the plausible {MAX_ARCSEC:g}″ (one degree)")
            if key == "coverage_factor" and not COVERAGE_RANGE[0] <= v <= COVERAGE_RANGE[1]:
                bad(where, f"{v:g} is outside the plausible range [{COVERAGE_RANGE[0]:g}, "
                    f"{COVERAGE_RANGE[1]:g}]")
            if key.endswith("_dph") and isinstance(v, (int, float)) and abs(v) > 1e4:
                bad(where, f"{v:g} °/h is over the plausible 1e4 °/h")
            if key == "duration_min" and v > MAX_DURATION_S / 60.0:
                bad(where, f"{v:g} min is over the plausible {MAX_DURATION_S / 60.0:g} min")
            if key.endswith("_dps") and isinstance(v, (int, float)) and \
                    not RATE_RANGE_DPS[0] <= v <= RATE_RANGE_DPS[1]:
                bad(where, f"{v:g} °/s is outside the plausible range "
                    f"[{RATE_RANGE_DPS[0]:g}, {RATE_RANGE_DPS[1]:g}] °/s")
            if key == "rates_dps" or key == "orientations":
                if len(v) > MAX_LIST:
                    bad(where, f"{len(v)} entries, over the limit of {MAX_LIST}")
                if len(set(v)) != len(v):
                    bad(where, "an entry is given twice")
                if key == "rates_dps":
                    for i, r in enumerate(v):
                        if not RATE_RANGE_DPS[0] <= r <= RATE_RANGE_DPS[1]:
                            bad(f"{where}[{i}]", f"{r:g} °/s is outside the plausible range "
                                f"[{RATE_RANGE_DPS[0]:g}, {RATE_RANGE_DPS[1]:g}] °/s")
            if key == "series" and isinstance(v, int) and v > MAX_SERIES:
                bad(where, f"{v} series, over the limit of {MAX_SERIES}")
            if key == "readings" and isinstance(v, int):
                total += v
            if key == "rounds" and isinstance(v, list):
                if len(v) > MAX_ROUNDS:
                    bad(where, f"{len(v)} rounds, over the limit of {MAX_ROUNDS}")
                for i, r in enumerate(v):
                    for a in ("start_deg", "stop_deg"):
                        if isinstance(r, dict) and abs(r.get(a) or 0.0) > MAX_ANGLE_DEG:
                            bad(f"{where}[{i}].{a}", f"{r[a]:g}° is outside the plausible "
                                f"±{MAX_ANGLE_DEG:g}°")
                n_cond = len(x.get("rates_dps") or x.get("orientations") or [1])
                total += len(v) * int(x.get("series") or 1) * n_cond
        if name in ("rate_consistency", "pointing_consistency") and x.get("rounds") is None:
            ad = sec.get("angle_deviation") or {}
            total += (len(ad.get("rounds") or []) * int(x.get("series") or 1)
                      * len(x.get("rates_dps") or x.get("orientations") or [1]))
    lim = limit("GONIO_MAX_READINGS")
    if total > lim:
        bad("protocol", f"{total} readings planned, over the limit of {lim:.0f} "
            "(set GONIO_MAX_READINGS to raise it)")


def load_protocol(path: str | Path) -> Protocol:
    """Load and validate a protocol file (a path, or a built-in name: a specification's
    ``default_protocol``; the caller names it, this layer knows no specification).

    >>> from gonio.specs import DEFAULT_KEY, get
    >>> p = load_protocol(get(DEFAULT_KEY).default_protocol)
    >>> [r.stop_deg for r in p.scale_factor.rounds]
    [60.0, 120.0, 180.0, 240.0, 300.0, 360.0]
    >>> p.angle_deviation.series, len(p.angle_deviation.rounds)
    (10, 12)
    >>> [it.rate_dps for it in p.rate_consistency]     # 60 °/s reuses 7.4 (draft 7.6)
    [1.0, 10.0, 100.0, 150.0, 200.0, 250.0, 300.0]
    >>> [it.orientation for it in p.pointing_consistency]
    ['north', 'east']
    """
    file = resolve(path, "protocol")
    return parse_protocol(read_toml(file), file)


# ------------------------------------------------ optional sections ([equal_division], [tilt_estimate])


@dataclass(frozen=True)
class EdaProtocol:
    """The ``[equal_division]`` protocol section (IEC 62047-20 Annex A.3 procedure).

    Attributes
    ----------
    starts, points, repeats : int
        ``n`` starts ``360°/n`` apart, ``m`` points per revolution, repeats.
    rate_dps, rest_s, read_delay_s : float
        Table rate, rest at each stop, reading delay after arrival.
    orientation : str
        Table-axis direction.
    """

    starts: int
    points: int
    repeats: int
    rate_dps: float
    rest_s: float
    read_delay_s: float
    orientation: str

    @property
    def step_deg(self) -> float:
        """The step ``Δ = 360°/m``."""
        return 360.0 / self.points

    @property
    def start_deg(self) -> np.ndarray:
        """Start positions ``k·360°/n``."""
        return np.arange(self.starts) * 360.0 / self.starts


def _is_int_ge(lo):
    return lambda x: x >= lo


EDA_PROTOCOL_SCHEMA: dict[str, Field] = {
    "starts": Field("int", 12, _is_int_ge(1), "an integer ≥ 1"),
    "points": Field("int", 12, _is_int_ge(2), "an integer ≥ 2"),
    "repeats": Field("int", 1, _is_int_ge(1), "an integer ≥ 1"),
    "rate_dps": Field("float", 60.0, positive, "> 0"),
    "rest_s": Field("float", 10.0, lambda x: x >= 0, "≥ 0"),
    "read_delay_s": Field("float", 5.0, lambda x: x >= 0, "≥ 0"),
    "orientation": Field("str", "up", choices=ORIENTATIONS),
}


def _eda_factory(v: dict) -> EdaProtocol:
    return EdaProtocol(**v)


register_section("equal_division", EDA_PROTOCOL_SCHEMA, _eda_factory)


@dataclass(frozen=True)
class TiltEstimatePlan:
    """The static multi-position test: N equally spaced rests of ``dwell_s`` each.

    Readings (one per position, test ``tilt_estimate``): ``round`` = the rest's place in
    the order taken (1…N, :attr:`order_deg`), ``table_deg`` = its position (a multiple of
    360°/N), ``time_s`` = dwell time,
    ``gyro_counts`` = pulses accumulated over the dwell, *not* Earth-rate
    compensated (the Earth rate is the signal).
    """

    clause: str = "in-situ tilt estimate (gonio; supports Annex A.1/A.4.2)"
    positions: int = 12
    dwell_s: float = 60.0
    settle_s: float = 5.0
    orientation: str = "up"
    rate_dps: float = 60.0

    @property
    def order_deg(self) -> list[float]:
        """The positions in the order the rests are taken (round 1, 2, …): with N even, in
        opposite pairs, each position followed by the one 180° from it — 0°, 180°, 30°,
        210°, … for N = 12 — so that the difference within a pair, two rests one dwell
        apart, carries the first harmonic twice and the bias's slow wander (its drift, its
        Gauss–Markov instability) hardly at all; with N odd, in order of θ. The pairs are
        what gives the estimate an honest uncertainty under a correlated bias
        (:func:`gonio.specs.ogam_draft.tilt_estimate.fit_first_harmonic`).

        >>> TiltEstimatePlan(positions=8).order_deg
        [0.0, 180.0, 45.0, 225.0, 90.0, 270.0, 135.0, 315.0]
        >>> TiltEstimatePlan(positions=5).order_deg
        [0.0, 72.0, 144.0, 216.0, 288.0]
        """
        n = self.positions
        if n % 2:
            return [360.0 * i / n for i in range(n)]
        return [360.0 * (i // 2 + (i % 2) * n // 2) / n for i in range(n)]


SECTION_SCHEMA = {
    "clause": Field("str", TiltEstimatePlan.clause),
    "positions": Field("int", 12, lambda n: n >= 4, "an integer ≥ 4"),
    "dwell_s": Field("float", 60.0, positive, "> 0"),
    "settle_s": Field("float", 5.0, non_negative, "≥ 0"),
    "orientation": Field("str", "up", choices=tuple(NAMED_AXES)),
    "rate_dps": Field("float", 60.0, positive, "> 0"),
}


def _plan(d: dict) -> TiltEstimatePlan:
    return TiltEstimatePlan(**d)


register_section("tilt_estimate", SECTION_SCHEMA, _plan)
