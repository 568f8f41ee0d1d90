"""The rate specifications on the virtual bench: the hooks ``SPEC.simulate``,
``SPEC.run_trial`` and ``Coverage.study_bench`` both rate specifications share.

The simulation side (it imports :mod:`gonio.bench`); calibrating a laboratory's file never
imports this module. Each specification passes its own programme runner (its
``simulate`` module's ``simulate(bench, protocol, seed, noise=…)``).
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

from gonio.atomic import output_dir, write_text
from gonio.bench.rate_gyro import load_rate_bench
from gonio.formats.jsonsafe import json_safe
from gonio.formats.rate_readings import RateReadings, rate_readings_text
from gonio.formats.watermark import mark_text


def write_simulation(run, out: Path, *, protocol, bench, seed: int = 0,
                     noise: bool = True) -> dict[str, Path]:
    """Run ``run`` (a specification's programme runner) on the rate bench ``bench`` (name or
    file); write ``readings.csv`` (docs/formats.md#rate-gyro-readings-file) and
    ``truth.json`` into ``out``."""
    b = load_rate_bench(bench)
    res = run(b, protocol, seed, noise=noise)
    out = Path(out)
    with output_dir(out) as stage:
        # the bench's watermark in its measured values (gonio.formats.watermark)
        write_text(stage / "readings.csv", mark_text(rate_readings_text(res.data, res.metadata)))
        write_text(stage / "truth.json", json.dumps(json_safe(res.truth), indent=2,
                                                    ensure_ascii=False, allow_nan=False) + "\n")
    return {"readings": out / "readings.csv", "truth": out / "truth.json"}


def run_trial(run, bench, protocol, seed: int):
    """One simulated calibration in memory (noise on): (RateReadings, truth dict). A study
    bench (``bench.draw_equipment``) first draws its equipment's type-B errors from
    ``seed`` (:meth:`gonio.bench.rate_gyro.RateBench.for_trial`); the truth records them."""
    if getattr(bench, "draw_equipment", False):
        bench = bench.for_trial(int(seed))
    res = run(bench, protocol, int(seed), noise=True)
    return RateReadings(res.data, {k: str(v) for k, v in res.metadata.items()}), res.truth


def study_bench(name: str = "mems-adxrs610", *, draw_equipment: bool = True,
                cross_axis: bool = False, power_on_transient: bool = False,
                case: str = "typeb"):
    """The rate bench of the coverage study: ``name`` with the power-on transient, the thermal
    lag (τ = 1 s) and the cross-axis sensitivity switched off, the three deterministic,
    history-dependent effects the truth formulas leave out; every random term (noise,
    power-cycle scatter, quantisation) stays on.

    ``power_on_transient=True`` keeps the bench's own power-on transient (its
    ``warmup_bias_dps`` and ``warmup_tau_s``): JJF 1535's study, whose warm-up truth (7.2.9)
    is computed from them, and IEC 62047-20's, whose 5.3.3.5 drift and 5.3.3.9 start-up
    truths are; both programmes wait long enough after every other power-on for the
    transient to have died away (``warmup_s``). With it off the warm-up and start-up times
    are 0 and found 0 (value = truth in every trial, the coverage not measured at all) and
    the 5.3.3.5 drift is 0, a truth at the bound of a non-negative maximum.

    ``cross_axis=True`` keeps the gyro's own cross-axis sensitivity (IEC 62047-20's study,
    whose truths carry it: 5.2, the bias and 5.3.3.8 with cross-axis × Earth rate). With it
    off the 5.2 truth is 0 and the value the larger of two |misalignments|, a truth on the
    boundary of a largest absolute value whose z cannot spread (sd z 0.42 over 200 trials,
    1.00 with it on).

    ``draw_equipment`` (the default): each trial draws every equipment error a budget
    carries as type B from its seed — the rate table's rate error and the voltmeter's gain
    (normal, their certificates' u), the chamber's deviation per set point (uniform,
    ±2 °C), the gyro's misalignment in its fixture (uniform, ±0.05° about body x and
    y) and the phases of the chamber's fluctuation and of the table's once-per-revolution
    ripple (uniform); :func:`gonio.bench.equipment.draw_equipment`. Held at one value instead, a type-B
    error cannot spread z, and a U made of it always looks over-wide.
    ``draw_equipment=False``: the bench file's one realisation in every trial.

    ``case``: the study case (``gonio validate --cases``, :data:`gonio.specs._rate_family.STUDY_CASES`):
    ``"typeb"`` the draws above, ``"worst"`` every one of those errors at its bound instead
    (:func:`gonio.bench.equipment.worst_equipment`), ``"cold"`` as ``"worst"`` with the gyro
    cold at every set point (:func:`gonio.bench.equipment.cold_equipment`: the noise items'
    worst sign). In ``"worst"`` and ``"cold"`` the bench states no
    certificate u for its rate table (``rate_table_u_rel`` None): the readings then carry
    none, the budgets read JJF 1535 Table 2's 0.05 % as a rectangular bound
    (:func:`gonio.specs._rate_family.rate_records.rate_table_line`) and the table's error
    sits at that bound; ``"typeb"`` keeps the bench's certificate u, drawn from it."""
    from gonio.errors import GonioError
    from gonio.specs._rate_family import STUDY_CASES

    if case not in STUDY_CASES:
        raise GonioError(f"unknown case {case!r} (known: {', '.join(STUDY_CASES)})",
                         key="cases")
    b = load_rate_bench(name)
    g = replace(b.gyro, thermal_tau_s=1.0,
                warmup_bias_dps=b.gyro.warmup_bias_dps if power_on_transient else 0.0)
    if not cross_axis:
        g = replace(g, cross_axis_x=0.0, cross_axis_y=0.0)
    if case in ("worst", "cold"):   # the laboratory that knows its table by Table 2's bound
        b = replace(b, equipment=replace(b.equipment, rate_table_u_rel=None))
    return replace(b, gyro=g, draw_equipment=bool(draw_equipment) or case in ("worst", "cold"),
                   equipment_case=case)
