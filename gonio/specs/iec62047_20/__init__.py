"""IEC 62047-20:2014 (JIS C 5630-20:2015), MEMS gyroscopes — measuring methods.

:func:`calibrate` computes the characteristics of :data:`.items.ITEMS` from a rate readings
file; :mod:`.protocol` reads ``protocols/iec62047-20.toml`` and plans the programme;
:func:`truth` gives the bench's true values. The standard has no uncertainty annex of the
JJF kind (its Annex A is about the accuracy of the angle and rate references), so
``SPEC.budget`` is None.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from gonio.errors import GonioError
from gonio.resources import protocol_provenance
from gonio.specs import lazy
from gonio.specs._rate_family import rate_specification
from gonio.specs.iec62047_20.keys import ITEM_ROWS, KEY, MAGNITUDE_KEYS, NONNEGATIVE

if TYPE_CHECKING:
    from gonio.result.model import Result

TITLE_EN = "IEC 62047-20:2014 Semiconductor devices — MEMS — Part 20: Gyroscopes (measuring methods)"
TITLE_ZH = "IEC 62047-20:2014 半导体器件 微机电器件 第20部分：陀螺仪（测量方法）"

READINGS_TAKEN = (
    "5.1.3.1: the rest point is a fit point (2n + 1 points), unlike JJF 1535.",
    "5.1.3.4: the temperature coefficient is reported as 100·T_c,SF/a_BASE in %/°C; the slope too.",
    "5.1.3.5: R = [a_V − a_BASE·V/V_BASE]/a_BASE (ratio V/V_BASE, zero for an ideal "
    "ratiometric gyro).",
    "5.1.3.6: FullScale = measured y(CW max) − y(CCW max); linearity = max |L_i|.",
    "5.1.3.8: signed (a_CW − a_CCW)/a_TYP from separate fits without the rest point.",
    "5.2: ω = (Out − Out,rest)/SF (the printed × SF is dimensionally wrong); whole revolutions; "
    "±ω half-difference as a bias-free refinement.",
    "5.3.3.1: the Earth-rate components printed with sin and cos swapped (erratum); the physics "
    "is used: axis up Ω_E sin λ, horizontal Ω_E cos λ cos φ.",
    "5.3.3.4: bias repeatability as the half range (max − min)/2 of the records.",
    "5.3.3.6: least-squares slope through every visit of base → max → base → min → base.",
    "5.4.5.2: slope −½ line fitted where the local slope is −½ ± 0.05 (the reading taken: "
    "the text gives no tolerance), read at 1 h; certified: that rule applied to the fitted "
    "noise model's curve and the line divided by the model's lift over it (the rule on the "
    "data, uncorrected, given beside).",
    "5.4.5.3: floor over τ with ≥ 10 clusters, divided by √(2 ln 2/π) (the standard's reading, "
    "given beside the results, not certified); the value is that reading less the rule's bias under the record's fitted "
    "noise model (other noise terms at the floor τ, minimum over τ), stated by the 95 % "
    "interval of that rule's distribution (2.5 % each side; no k).",
    "5.5: band = the lower of the −3 dB and the 90° lag frequencies, both reported.",
    "5.1.4.1 e) eq (18): a ratiometric gyro's outputs are referred to each run's own set "
    "voltage, y = y_RAW·V_set/V_actual, when the readings record the set voltage.",
    "5.3.3.3: the bias of each supply run is its rest output (null included); R in %, the "
    "departure in output units (Table 4's V) in the details.",
    "5.3.3.7: a visit is 'up' when reached from below, 'down' from above; hysteresis = "
    "max |B_up − B_down| (the reading, given beside the results, not certified); stated as that reading less the "
    "midpoint of a maximum's selection excess, with the interval [0, its one-sided 95 % upper limit].",
    "5.1.3.7: the standard's reading is max δ_i, the largest population spread at the "
    "constant rates (given beside the results, not certified); the value is the estimate of "
    "the largest true spread "
    "max σ_i: that reading less the bias of a maximum (the midpoint between Jensen's alone and "
    "the contending rates' full selection excess, scaled χ), stated by its 95 % interval (the "
    "upper end the largest of every record's own χ² upper bound at its own ν, the lower end "
    "no higher than the largest spread's χ² lower bound over that excess; no k).",
    "5.3.3.9: the reference output is the mean of the record's last fifth; the standard's "
    "reading (the last excursion beyond the band) is given beside the results, not "
    "certified; the value is the time "
    "outside the band (smoothed values beyond it × their step) less its late bias where the "
    "transient flattens, t''·var/2 (first-order transient; only for a record that leaves "
    "the band, and never below 0 s; a record always within the band is 0 s).",
    "5.3.3.8: a = g cos γ with γ = 0 at input axis up (eq (28)'s sin γ counts from the "
    "horizontal); the Earth rate removed at each angle; a whole turn in equal steps.",
    "5.4.5.1 c): broadband = rms over band_hz … broadband_high_hz of the one-sided density; the "
    "20 dB/dec value c of c/f (°/s^1.5) in the details.",
    "5.6: the filter is the mean over a step's samples; Noise,RMS = std of T-second means of "
    "the static record; resolution = max(Out,resolution, Noise,RMS).",
)


def calibrate(readings, protocol: str | Path | IECProtocol | None = None,
              monte_carlo_trials: int = 0, findings: list | None = None,
              **options) -> Result:
    """IEC 62047-20 characteristics from a rate readings file (path or RateReadings)."""
    from gonio.result.model import Result, source_info
    from gonio.specs._rate_family.rate_records import (calibrate_items, load_readings,
                                                       metadata_number, protocol_named,
                                                       stated_rate_table_u)
    from gonio.specs._rate_family.screening import (screened, screening_extra,
                                                     unused_readings)
    from gonio.specs.iec62047_20 import items as _items
    from gonio.specs.iec62047_20.protocol import IECProtocol, load_protocol, t_base
    from gonio.specs.iec62047_20.screen import screen

    rd = load_readings(readings)
    spec = rd.metadata.get("spec", KEY)
    if spec != KEY:
        raise GonioError(f"the readings are for specification {spec!r}, not {KEY!r}",
                         file=rd.path, key="spec")
    proto = protocol if isinstance(protocol, IECProtocol) else \
        load_protocol(protocol_named(rd, protocol, KEY))
    # the pipeline screens first (SPEC.screen) and hands the findings here
    given = rd
    rd, findings = screened(rd, screen(rd, proto) if findings is None else list(findings))
    md, P = rd.metadata, proto.sections
    ratiometric = str(md.get("ratiometric", "")).strip().lower() in ("true", "yes", "1")
    df, n_corr = _items.supply_correction(rd.data, ratiometric)
    ctx = _items.Context(
        df=df, output_unit=md.get("output_unit", "output"),
        null_output=metadata_number(md, "null_output", P["protocol"]["null_output"], rd.path),
        latitude_deg=metadata_number(md, "latitude_deg", P["protocol"]["latitude_deg"], rd.path),
        a_typ=metadata_number(md, "nominal_scale_factor", P["protocol"]["nominal_scale_factor"], rd.path),
        t_base_c=t_base(proto), v_base=metadata_number(md, "supply_nominal_v", 5.0, rd.path), protocol=P,
        rate_table_u_rel=stated_rate_table_u(md, rd.path),
        acquisition_u_rel=metadata_number(md, "acquisition_u_rel", 3.0e-5, rd.path),
        chamber_deviation_c=metadata_number(md, "chamber_deviation_bound_c", 2.0, rd.path),
        chamber_fluctuation_c=metadata_number(md, "chamber_fluctuation_c", 1.0, rd.path),
        chamber_uniformity_c=metadata_number(md, "chamber_uniformity_c", 2.0, rd.path),
        chamber_fluctuation_period_s=metadata_number(md, "chamber_fluctuation_period_s", 0.0,
                                                     rd.path) or None)
    items = calibrate_items(ctx, _items, monte_carlo_trials)
    # a_BASE without 5.1.3.4's T_c,SF: its chamber-deviation term is not bounded, said so
    unbounded = _items.chamber_effect_finding(items, _items.gyro_temperature_bound_c(ctx))
    findings = list(findings) + ([unbounded] if unbounded is not None else [])
    # the bias without 5.3.3.6's β: its e_TU is 0, said so
    bias_t = _items.bias_temperature_finding(items, _items.gyro_temperature_bound_c(ctx))
    findings = findings + ([bias_t] if bias_t is not None else [])
    # the noise items without a temperature line (no 5.3.3.6 visits): said so
    noise_t = _items.noise_temperature_finding(
        items, _items.static_record_temperature_c(ctx.df), _items.gyro_temperature_bound_c(ctx))
    findings = findings + ([noise_t] if noise_t is not None else [])
    return Result(KEY, TITLE_EN, items, dict(md), source_info(rd),
                  list(READINGS_TAKEN),
                  extra={"supply_correction_eq18": {
                      "ratiometric": ratiometric, "rows_corrected": n_corr},
                      **screening_extra(findings)},
                  findings=findings,
                  unused_readings=unused_readings(given, findings),
                  settings=protocol_provenance(proto.path))


#: The coverage study's programme over the built-in protocol (gonio validate --spec): small
#: sample counts and short waits, every item still measured. The study bench keeps the
#: gyro's power-on transient and its cross-axis sensitivity (``study_bench_options``): the
#: records from power-on (5.3.3.5, 5.3.3.9) then have the physical drift and start-up time
#: the truth computes from the bench's transient (without it both truths are 0, a drift
#: on the boundary of a non-negative maximum and a start-up time found 0 in every trial);
#: the wait after every other power-on is the built-in 30 min, by which the bench's
#: transient (τ = 150 s) has died away to e⁻¹².
STUDY_PROGRAMME = {
    "protocol": {"warmup_s": 1800.0},
    "scale_factor": {"samples": 5},
    "temperature": {"soak_s": 1800.0, "bias_samples": 60},
    "stability": {"samples": 50}, "bias": {"samples": 300, "off_time_s": 60.0},
    "power_on": {"samples": 900, "off_time_s": 60.0},
    "noise": {"samples": 72000}, "frequency": {"cycles": 8}}

SPEC = rate_specification(
    "gonio.specs.iec62047_20", key=KEY, title_en=TITLE_EN, title_zh=TITLE_ZH,
    clause_doc="docs/iec62047-20-readings.md", clauses=tuple(r[2] for r in ITEM_ROWS),
    item_keys=tuple(r[0] for r in ITEM_ROWS),
    magnitude_extremes=MAGNITUDE_KEYS, nonnegative_items=tuple(sorted(NONNEGATIVE)),
    default_protocol=KEY, load_protocol=lazy("gonio.specs.iec62047_20.protocol:load_protocol"),
    calibrate=calibrate, screen=lazy("gonio.specs.iec62047_20.screen:screen"),
    budget=None,
    # every IEC 62047-20 test runs in the chamber at a set point (T_BASE or the programme's):
    # no row logs the room, and "# room_temperature_c" is T_BASE (docs/formats.md)
    measured_conditions=None, room_temperature_keys=("temperature_c",),
    stream=1, reduced=STUDY_PROGRAMME, study_bench_options={"cross_axis": True, "power_on_transient": True})
