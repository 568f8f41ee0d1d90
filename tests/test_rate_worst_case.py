"""The rate coverage studies' worst-condition case (``gonio validate --spec jjf1535-2015 |
iec62047-20 --cases worst``): every Type B error of the equipment at the bound the procedure
allows, at the stated sign, reaching the bench's physics; the case reported beside ``typeb``;
a budget line that loses its value under-covers there."""

from __future__ import annotations

import json
import math
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from gonio.bench.equipment import Equipment, Fixture, draw_equipment, worst_equipment
from gonio.bench.rate_gyro import load_rate_bench
from gonio.formats.toml import read_toml
from gonio.resources import resolve
from gonio.specs import get

# JJF 1535-2015 Table 2, read off the standard (independent of gonio's constants):
# rate accuracy and smoothness 0.05 %, chamber deviation ±2 °C, fluctuation ±1 °C,
# uniformity 2 °C.
TABLE2_RATE = 5e-4
TABLE2_DEVIATION_C, TABLE2_FLUCTUATION_C, TABLE2_UNIFORMITY_C = 2.0, 1.0, 2.0


def _bench_file_equipment() -> dict:
    return read_toml(resolve("mems-adxrs610", kind="bench"))["equipment"]


def test_worst_equipment_sits_at_the_bounds_of_the_bench_file():
    raw = _bench_file_equipment()                 # the bench file as written, not gonio's model
    eq = load_rate_bench("mems-adxrs610").equipment
    w = worst_equipment(eq, 11, temperature_split_c=20.0, cross_axis=(0.01, -0.008))
    # the normal-certificate errors (the table's rate, the voltmeter's gain) are not bounds:
    # drawn per trial from their certificates, the same draw as typeb's from the same seed
    d0 = draw_equipment(eq, 11)
    assert w.rate_table.rate_error_rel == d0.rate_table.rate_error_rel
    assert w.acquisition.gain_error_rel == d0.acquisition.gain_error_rel
    rates = np.array([worst_equipment(eq, s, temperature_split_c=20.0).rate_table.rate_error_rel
                      for s in range(400)])
    gains = np.array([worst_equipment(eq, s, temperature_split_c=20.0).acquisition.gain_error_rel
                      for s in range(400)])
    assert np.std(rates) == pytest.approx(raw["rate_table_u_rel"], rel=0.15)
    assert np.std(gains) == pytest.approx(raw["acquisition_u_rel"], rel=0.15)
    assert abs(np.mean(rates)) < 3 * raw["rate_table_u_rel"] / 20
    # the chamber: every set point at ± the bound, + above the split, − at or below
    b = raw["chamber_deviation_bound_c"]
    assert b == TABLE2_DEVIATION_C
    assert [w.chamber.deviation_at(t) for t in (-40.0, -8.75, 20.0, 22.5, 53.75, 70.0, 85.0)] \
        == [-b, -b, -b, b, b, b, b]
    # Table 2's fluctuation, uniformity and smoothness where the bench states less
    assert raw["chamber"]["fluctuation_c"] < TABLE2_FLUCTUATION_C
    assert w.chamber.fluctuation_c == TABLE2_FLUCTUATION_C
    assert w.chamber.uniformity_c == TABLE2_UNIFORMITY_C
    assert w.chamber.position_offset() == TABLE2_UNIFORMITY_C / 2
    # the place in the volume follows the set point with the deviation's sign
    assert [w.chamber.position_at(t) for t in (-40.0, 20.0, 22.5, 85.0)] == \
        [-TABLE2_UNIFORMITY_C / 2, -TABLE2_UNIFORMITY_C / 2, TABLE2_UNIFORMITY_C / 2,
         TABLE2_UNIFORMITY_C / 2]
    # no certificate u stated: the table's rate error at Table 2's bound in the case, drawn
    # uniformly within it in typeb (sd bound/√3)
    bare = replace(eq, rate_table_u_rel=None)
    assert worst_equipment(bare, 11, temperature_split_c=20.0).rate_table.rate_error_rel \
        == TABLE2_RATE
    drawn = np.array([draw_equipment(bare, s).rate_table.rate_error_rel for s in range(2000)])
    assert np.abs(drawn).max() <= TABLE2_RATE
    assert np.std(drawn) == pytest.approx(TABLE2_RATE / math.sqrt(3), rel=0.06)
    assert w.rate_table.ripple_rel == TABLE2_RATE
    # a bench stating more than Table 2 keeps its own (never below what it states)
    big = replace(eq, chamber=replace(eq.chamber, fluctuation_c=1.5))
    assert worst_equipment(big, 1, temperature_split_c=20.0).chamber.fluctuation_c == 1.5
    # the fixture at ± its bound on both axes
    a = raw["axis_alignment_bound_deg"]
    assert abs(w.fixture.misalignment_x_deg) == a and abs(w.fixture.misalignment_y_deg) == a
    # phases: the typeb draw's, from the same seed; the case is deterministic
    d = draw_equipment(eq, 11)
    assert w.chamber.fluctuation_phase_deg == d.chamber.fluctuation_phase_deg
    assert w.rate_table.ripple_phase_deg == d.rate_table.ripple_phase_deg
    assert w == worst_equipment(eq, 11, temperature_split_c=20.0, cross_axis=(0.01, -0.008))


def _apparent_cross_axis(fix: Fixture, kx: float, ky: float) -> tuple[float, float]:
    """The gyro's output per unit rate about fixture x and fixture y: the body rate is
    Rᵀ·ω, the output ω_z + k_x ω_x + k_y ω_y (body axes)."""
    R = fix.matrix()
    out = []
    for axis in (np.array([1.0, 0, 0]), np.array([0, 1.0, 0])):
        wb = R.T @ axis
        out.append(wb[2] + kx * wb[0] + ky * wb[1])
    return out[0], out[1]


@pytest.mark.parametrize("kx, ky", [(0.01, -0.008), (-0.01, 0.008), (0.0, 0.0)])
def test_fixture_sign_raises_the_apparent_cross_axis_magnitude(kx, ky):
    w = worst_equipment(Equipment(), 0, temperature_split_c=20.0, cross_axis=(kx, ky)).fixture
    ax, ay = _apparent_cross_axis(w, kx, ky)
    flip = Fixture(-w.misalignment_x_deg, -w.misalignment_y_deg)
    fx, fy = _apparent_cross_axis(flip, kx, ky)
    if kx and ky:
        assert abs(ax) > abs(fx) and abs(ay) > abs(fy)
    else:                                   # no cross-axis: either sign as bad; + chosen
        assert w == Fixture(0.05, 0.05) and abs(ax) == pytest.approx(abs(fx))
    assert abs(ax) >= abs(kx) + 0.99 * math.radians(0.05)


@pytest.fixture(scope="module")
def worst_trials():
    """Two worst-case trials of JJF 1535's study programme: (readings, truth) each."""
    from gonio.pipeline.coverage import case_stream, reduced_protocol, study_bench
    from gonio.analysis.coverage import spawn_seed

    spec = get("jjf1535-2015")
    with tempfile.TemporaryDirectory() as d:
        proto = spec.load_protocol(str(reduced_protocol(spec.key, Path(d) / "r.toml")))
    bench = study_bench(spec, None, "worst")
    seeds = [spawn_seed(5, case_stream(spec, "worst"), i) for i in (0, 1)]
    return spec, proto, [spec.run_trial(bench, proto, s) for s in seeds]


def test_a_worst_trial_runs_at_the_bounds(worst_trials):
    spec, proto, trials = worst_trials
    assert spec.coverage.stream != \
        __import__("gonio.pipeline.coverage", fromlist=["x"]).case_stream(spec, "worst")
    for readings, truth in trials:
        e = truth["equipment"]
        # the bench states no certificate u for its table: the readings carry none, and
        # the table's rate error sits at Table 2's 0.05 % (a bound, not a certificate's 2u)
        assert e["rate_table"]["rate_error_rel"] == pytest.approx(TABLE2_RATE, rel=1e-12)
        assert "rate_table_u_rel" not in readings.metadata
        assert e["chamber"]["fluctuation_c"] == TABLE2_FLUCTUATION_C
        # the readings state the ripple at its bound: the budget is given what the table is
        assert float(readings.metadata["rate_table_ripple_rel"]) == TABLE2_RATE
        # the gyro's own temperature at each chamber set point: set point ± 2 °C (the
        # deviation's sign) ± 1 °C (its place in the volume, following the set point with
        # the deviation's sign), within the fluctuation's ±1 °C (the records are short
        # against its 900-s period)
        seen = {}
        for s in truth["segments"]:
            if s["test"] == "sf_temperature" and s["temperature_c"] != 20.0:
                seen.setdefault(s["temperature_c"], []).append(
                    s["gyro_temperature_c"] - s["temperature_c"])
        assert set(seen) == {70.0, -40.0}
        assert np.mean(seen[70.0]) == pytest.approx(TABLE2_DEVIATION_C + 1.0, abs=1.05)
        assert np.mean(seen[-40.0]) == pytest.approx(-TABLE2_DEVIATION_C - 1.0, abs=1.05)


def test_the_rate_table_without_a_stated_u_is_table_2s_bound(worst_trials):
    """A readings file stating no ``rate_table_u_rel`` is budgeted with Table 2's 0.05 % as
    a rectangular bound (u = 5·10⁻⁴/√3, read off the standard here), not as a certificate's
    u; one stating it keeps a normal line of that u. Mutation: the old default (2.5·10⁻⁴
    normal) fails the first assertion."""
    from gonio.formats.rate_readings import RateReadings
    from gonio.pipeline.dispatch import screen_and_calibrate

    spec, proto, trials = worst_trials
    readings, _ = trials[0]

    def line(md):
        rd = RateReadings(readings.data, md)
        it = screen_and_calibrate(spec, rd, proto).items["scale_factor"]
        return next(c for c in it.uncertainty.components if c["symbol"] == "e_table")

    bare = line(dict(readings.metadata))
    assert bare["u"] == pytest.approx(TABLE2_RATE / math.sqrt(3), rel=1e-12)
    assert "Table 2's 0.05 % as a rectangular bound" in bare["source"]
    stated = line({**readings.metadata, "rate_table_u_rel": "0.00025"})
    assert stated["u"] == pytest.approx(2.5e-4, rel=1e-12)
    assert "Table 2" not in stated["source"]


def _kt(spec, proto, readings, truth, **md):
    """K_t (7.2.5) of one trial calibrated with the readings' metadata changed by ``md``:
    (its stated interval, the truth)."""
    from gonio.formats.rate_readings import RateReadings
    from gonio.pipeline.dispatch import screen_and_calibrate
    rd = RateReadings(readings.data, {**readings.metadata, **md})
    it = screen_and_calibrate(spec, rd, proto).items["sf_temperature_sensitivity"]
    return tuple(it.uncertainty.interval), truth["items"]["sf_temperature_sensitivity"]["value"]


def test_a_budget_without_its_chamber_line_under_covers_at_the_bound(worst_trials):
    """The worst case finds a budget line that lost its value: K_t's chamber line (the
    readings' ``chamber_deviation_bound_c`` and ``chamber_uniformity_c``) set to 0 misses
    the truth in both trials, where the hot point's span is 3 °C longer than its set points
    say (the deviation's +2 °C and the volume's warm end's +1 °C); the budget as it is is
    wider."""
    spec, proto, trials = worst_trials
    for readings, truth in trials:
        (lo, hi), t = _kt(spec, proto, readings, truth)
        (lo0, hi0), _ = _kt(spec, proto, readings, truth, chamber_deviation_bound_c="0.0",
                            chamber_uniformity_c="0.0")
        assert not lo0 <= t <= hi0                  # the mutated budget misses the truth
        assert lo < lo0 and hi > hi0                # the line widens the interval
        assert lo0 > t                              # read high: the span is stretched


def test_k_t_line_adds_the_bounds_linearly(worst_trials):
    """The gyro's temperature error at a set point is one rectangular line of half-width
    deviation bound + half the uniformity (both bounded, both at their bounds at once in this
    case): readings stating (2 °C, 2 °C) give the same K_t statement as (3 °C, 0 °C), a
    quadrature of two lines would equal (√5 °C, 0 °C) instead; and the worst trial's
    readings state Table 2's uniformity."""
    spec, proto, trials = worst_trials
    readings, truth = trials[0]
    assert float(readings.metadata["chamber_uniformity_c"]) == TABLE2_UNIFORMITY_C
    a = _kt(spec, proto, readings, truth, chamber_deviation_bound_c="2.0",
            chamber_uniformity_c="2.0")[0]
    b = _kt(spec, proto, readings, truth, chamber_deviation_bound_c="3.0",
            chamber_uniformity_c="0.0")[0]
    q = _kt(spec, proto, readings, truth, chamber_deviation_bound_c=repr(math.sqrt(5.0)),
            chamber_uniformity_c="0.0")[0]
    assert a == pytest.approx(b, rel=1e-12)
    assert a[1] - a[0] > (q[1] - q[0]) * 1.02


def test_validate_reports_both_cases(capsys):
    from gonio.cli import main
    from gonio.pipeline.coverage import coverage_validate
    rep = coverage_validate("jjf1535-2015", 2, seed=5, workers=1, show_progress=False,
                            cases="typeb,worst")
    d = rep.to_dict()
    assert set(d["cases"]) == {"typeb", "worst"} and "items" not in d
    assert d["settings"]["fixed_condition_cases"] == ["worst"]
    # the worst case's trials are the module fixture's (same seeds, same spawn key)
    assert "case worst" in rep.table() and "case typeb" in rep.table()
    # the default: typeb alone, on the seed stream the study had before it had cases
    from gonio.pipeline.coverage import case_stream, study_cases
    spec = get("jjf1535-2015")
    assert study_cases(spec, None) == ["typeb"]
    assert case_stream(spec, "typeb") == spec.coverage.stream != case_stream(spec, "worst")
    capsys.readouterr()
    assert main(["validate", "--spec", "iec62047-20", "--trials", "2", "--cases", "hot"]) == 2
    assert "unknown case 'hot' of iec62047-20 (known: typeb, worst, cold)" in capsys.readouterr().err
