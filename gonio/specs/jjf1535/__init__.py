"""JJF 1535-2015, calibration specification for MEMS gyroscopes (微机电(MEMS)陀螺仪校准规范).

:func:`calibrate` computes the fifteen items of Table 3 (:mod:`.items`) from a rate
readings file; :func:`gonio.specs.jjf1535.budget.annex_a` reproduces Annex A;
:mod:`.protocol` reads ``protocols/jjf1535-2015.toml`` and plans the programme for the
virtual bench; :mod:`.truth` gives the bench's true value of every item;
:mod:`.certificate` holds the Annex B content (items grouped).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from gonio.errors import GonioError
from gonio.resources import protocol_provenance
from gonio.specs import lazy
from gonio.specs._rate_family import rate_specification
from gonio.specs.jjf1535.keys import ITEM_ROWS, KEY, MAGNITUDE_KEYS, NONNEGATIVE

if TYPE_CHECKING:
    from gonio.result.model import Result

TITLE_EN = "JJF 1535-2015 Calibration Specification for MEMS Gyroscopes"
TITLE_ZH = "JJF 1535-2015 微机电(MEMS)陀螺仪校准规范"

#: The readings taken that every results.json lists (docs/jjf1535-readings.md has them all).
READINGS_TAKEN = (
    "7.2.1: K is the mean of the Q least-squares K_m; the mean of the rests before and after "
    "each calibration is subtracted; rests are not fit points.",
    "7.2.2: the denominator of eq (6) is the fitted span K(Ω_max+ − Ω_max−) with Ω_max− signed; "
    "the noise's selection excess of the largest residual is removed at its midpoint, eq (6)'s "
    "reading is stated beside the value.",
    "7.2.3: K̄_m = (K+ + K−)/2, magnitude reported.",
    "7.2.6/7.2.7: the relation sign of eqs (13)/(14) is read two-sided, |…|/|F*| ≤ 50 %.",
    "7.2.8/7.2.12: the Earth-rate projection on the input axis is removed (the specification "
    "does not; at 40° N a true 5 (°/h)/g would read 14.7 (°/h)/g).",
    "7.2.9: warm-up time = earliest time after which every window meets the nominal stability.",
    "7.2.10: B_s is the root mean square of the records' standard deviations (eq (19)'s mean of "
    "standard deviations reads low; stated beside the value).",
    "7.2.13: eqs (22)-(24) as printed difference means one sample apart and fall as 2/k²; the "
    "ARW is taken from the overlapping Allan variance (IEEE 952) fitted with a band-limited "
    "bias instability (formula (25)'s flat-term reading stated beside it), the printed "
    "statistic is reported alongside, labelled.",
    "7.2.14: each B_i uses the scale factor calibrated at the same temperature.",
    "7.2.15: 0 dB = the lowest test frequency; −3 dB = ratio 10^(−3/20); log-f interpolation.",
    "Uncertainties are computed from the calibration's own data (GUM, k = t95(ν_eff)); Annex A "
    "is reproduced separately (gonio budget --spec jjf1535-2015).",
)


def make_context(rd, proto: JJFProtocol):
    """The :class:`~.items.Context` of a readings file: null, latitude, units from the metadata
    (the protocol's values when the metadata lacks them)."""
    from gonio.specs._rate_family.rate_records import metadata_number, stated_rate_table_u
    from gonio.specs.jjf1535 import items as _items_mod

    md = rd.metadata
    p = proto.sections
    null = metadata_number(md, "null_output",
                       None if p["protocol"]["null_output"] == "bench" else p["protocol"]["null_output"],
                       rd.path)
    lat = metadata_number(md, "latitude_deg",
                      None if p["bias"]["latitude_deg"] == "bench" else p["bias"]["latitude_deg"],
                      rd.path)
    return _items_mod.Context(
        df=rd.data, output_unit=md.get("output_unit", "output"), null_output=null,
        latitude_deg=lat,
        room_temperature_c=metadata_number(md, "room_temperature_c",
                                       p["protocol"]["room_temperature_c"], rd.path),
        protocol=p,
        rate_table_u_rel=stated_rate_table_u(md, rd.path),
        rate_table_ripple_rel=metadata_number(md, "rate_table_ripple_rel", 5.0e-4, rd.path),
        acquisition_u_rel=metadata_number(md, "acquisition_u_rel", 3.0e-5, rd.path),
        chamber_deviation_c=metadata_number(md, "chamber_deviation_bound_c", 2.0, rd.path),
        chamber_uniformity_c=metadata_number(md, "chamber_uniformity_c", 2.0, rd.path))


def calibrate(readings, protocol: str | Path | JJFProtocol | None = None,
              monte_carlo_trials: int = 0, findings: list | None = None,
              **options) -> Result:
    """Every JJF 1535 Table 3 item from a rate readings file (path or RateReadings).

    ``protocol``: file, built-in name or loaded protocol; default the readings' metadata
    ``protocol`` when it names a file that exists, else ``jjf1535-2015``. An item whose
    records are absent, or whose computation refuses the data, is reported not measured
    with the reason; nothing is dropped silently. ``monte_carlo_trials`` > 0 also propagates
    every item's budget by JCGM 101 Monte Carlo and validates the GUM interval against it.
    """
    from gonio.result.model import Result, source_info
    from gonio.specs._rate_family.rate_records import (calibrate_items, load_readings,
                                                       protocol_named)
    from gonio.specs._rate_family.screening import (screened, screening_extra,
                                                     unused_readings)
    from gonio.specs.jjf1535 import items as _items_mod
    from gonio.specs.jjf1535.budget import annex_a
    from gonio.specs.jjf1535.protocol import JJFProtocol, load_protocol
    from gonio.specs.jjf1535.screen import screen

    rd = load_readings(readings)
    spec = rd.metadata.get("spec", KEY)
    if spec != KEY:
        raise GonioError(f"the readings are for specification {spec!r}, not {KEY!r}",
                         file=rd.path, key="spec")
    proto = protocol if isinstance(protocol, JJFProtocol) else \
        load_protocol(protocol_named(rd, protocol, KEY))
    # the pipeline screens first (SPEC.screen) and hands the findings here
    given = rd
    rd, findings = screened(rd, screen(rd, proto) if findings is None else list(findings))
    ctx = make_context(rd, proto)
    items = calibrate_items(ctx, _items_mod, monte_carlo_trials)
    return Result(KEY, TITLE_EN, items, dict(rd.metadata), source_info(rd),
                  list(READINGS_TAKEN),
                  extra={"annex_a": annex_a().to_dict(),
                         **screening_extra(findings)},
                  findings=findings,
                  unused_readings=unused_readings(given, findings),
                  settings=protocol_provenance(proto.path))


#: The coverage study's programme over the built-in protocol (gonio validate --spec): small
#: sample counts and short waits, every item still measured. The study bench keeps the
#: gyro's power-on transient (``study_bench_options``): the wait after power-on is the
#: built-in 30 min (7.2.1.1 c)), by which the bench's transient (τ = 150 s) has died away
#: to e⁻¹² in every record but the warm-up's, and the warm-up window is the built-in W.
#: The static record (7.2.13) keeps the built-in 2 h at 10 Hz: its Allan fit gives the
#: bias-drift term of 7.2.12 and 7.2.14 over the hour and more between their records, and a
#: 600-s record bounds the rate random walk there only loosely (z sd 0.63–0.67 for 7.2.14);
#: at 1 s instead (7 200 samples) the ARW's fit loses its short τ and reads high (0.850).
STUDY_PROGRAMME = {
    "protocol": {"warmup_s": 1800.0},
    "scale_factor": {"samples_below_100_dps": 5, "samples_from_100_dps": 5, "rest_samples": 5,
                     "interval_s": 60.0},
    "temperature": {"soak_s": 1800.0, "bias_samples": 100},
    "threshold": {"samples": 5, "rest_samples": 5},
    "resolution": {"samples": 5},
    "bias": {"samples": 600, "off_time_s": 60.0},
    "warmup": {"samples": 600, "window_samples": 300, "off_time_s": 60.0},
    "g_sensitivity": {"samples": 60, "settle_s": 5.0},
    "arw": {"samples": 72000},
    "bandwidth": {"cycles": 8}}

SPEC = rate_specification(
    "gonio.specs.jjf1535", key=KEY, title_en=TITLE_EN, title_zh=TITLE_ZH,
    clause_doc="docs/jjf1535-readings.md", clauses=tuple(r[2] for r in ITEM_ROWS),
    item_keys=tuple(r[0] for r in ITEM_ROWS),
    magnitude_extremes=MAGNITUDE_KEYS, nonnegative_items=tuple(sorted(NONNEGATIVE)),
    default_protocol=KEY, load_protocol=lazy("gonio.specs.jjf1535.protocol:load_protocol"),
    calibrate=calibrate, screen=lazy("gonio.specs.jjf1535.screen:screen"),
    budget=lazy("gonio.specs.jjf1535.budget:annex_a"),
    acquisition=lazy("gonio.specs.jjf1535.acquisition:programme"),
    stream=0, reduced=STUDY_PROGRAMME, study_bench_options={"power_on_transient": True})
