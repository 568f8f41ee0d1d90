"""The coverage studies' per-trial equipment draw (issue 24): every type-B equipment error a
rate budget carries is drawn from the distribution its certificate states, from the trial's
seed, and reaches the readings; the truth stays the gyro's own."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from gonio.bench.equipment import Chamber, Equipment, Fixture, draw_equipment
from gonio.bench.rate_gyro import load_rate_bench


def test_draws_follow_the_stated_distributions():
    eq = load_rate_bench("mems-adxrs610").equipment
    d = [draw_equipment(eq, s) for s in range(400)]
    # normal with the certificates' u (Kolmogorov–Smirnov against scipy's normal)
    for vals, u in (([e.rate_table.rate_error_rel for e in d], eq.rate_table_u_rel),
                    ([e.acquisition.gain_error_rel for e in d], eq.acquisition_u_rel)):
        assert stats.kstest(np.array(vals) / u, "norm").pvalue > 1e-3
    # misalignment and per-point chamber deviation uniform within the stated bounds
    a, c = eq.axis_alignment_bound_deg, eq.chamber_deviation_bound_c
    for vals, hw in (([e.fixture.misalignment_x_deg for e in d], a),
                     ([e.fixture.misalignment_y_deg for e in d], a),
                     ([e.chamber.deviation_at(22.5) for e in d], c),
                     ([e.chamber.deviation_at(85.0) for e in d], c)):
        v = np.array(vals)
        assert np.all(np.abs(v) <= hw)
        assert stats.kstest(v, "uniform", args=(-hw, 2 * hw)).pvalue > 1e-3
    # the chamber's fluctuation: its phase uniform over the period (the IEC symmetry and
    # ratiometric budgets take it as unknown), amplitude and period as the bench states
    ph = np.array([e.chamber.fluctuation_phase_deg for e in d])
    assert np.all((ph >= 0.0) & (ph < 360.0))
    assert stats.kstest(ph, "uniform", args=(0.0, 360.0)).pvalue > 1e-3
    assert d[3].chamber.fluctuation_c == eq.chamber.fluctuation_c
    assert d[3].chamber.fluctuation_period_s == eq.chamber.fluctuation_period_s
    # each set point its own deviation (independent), the same on a second visit
    dev = np.array([[e.chamber.deviation_at(t) for t in (-40.0, 22.5, 85.0)] for e in d])
    assert abs(np.corrcoef(dev.T)[0, 1]) < 0.2 and abs(np.corrcoef(dev.T)[1, 2]) < 0.2
    assert d[5].chamber.deviation_at(85.0) == d[5].chamber.deviation_at(85.0)
    # same seed, same equipment; another seed, another
    assert draw_equipment(eq, 7) == draw_equipment(eq, 7) != draw_equipment(eq, 8)
    # what the bench file states stays: fixed terms, stated uncertainties
    assert d[0].rate_table.ripple_rel == eq.rate_table.ripple_rel
    assert d[0].rate_table_u_rel == eq.rate_table_u_rel


def test_chamber_deviation_and_fixture_by_hand():
    assert Chamber(deviation_c=0.5).deviation_at(-40.0) == 0.5
    assert np.allclose(Fixture().matrix(), np.eye(3))
    m = Fixture(0.0, 0.05).matrix()            # about body y: input axis (z) towards body x
    assert m @ np.array([0, 0, 1.0]) == pytest.approx(
        [math.sin(math.radians(0.05)), 0.0, math.cos(math.radians(0.05))])
    m = Fixture(0.05, 0.0).matrix()            # about body x: z towards −y
    assert (m @ np.array([0, 0, 1.0]))[1] == pytest.approx(-math.sin(math.radians(0.05)))
    assert Equipment(fixture=Fixture(0.1, 0.2)).ideal().fixture == Fixture()


def test_study_bench_draws_per_trial_and_truth_records_it():
    from gonio.specs import get
    from gonio.specs._rate_family.simulate import study_bench

    b = study_bench("mems-adxrs610")
    assert b.draw_equipment and not study_bench("mems-adxrs610", draw_equipment=False).draw_equipment
    t1, t2 = b.for_trial(11), b.for_trial(12)
    assert t1.equipment == draw_equipment(b.equipment, 11) and not t1.draw_equipment
    assert t1.equipment != t2.equipment and t1.gyro == b.gyro     # the gyro (truth) untouched
    assert study_bench("mems-adxrs610", draw_equipment=False).for_trial(11) \
        .equipment == b.equipment
    spec = get("iec62047-20")
    from gonio.pipeline.coverage import reduced_protocol
    import tempfile, pathlib
    with tempfile.TemporaryDirectory() as d:
        proto = str(reduced_protocol(spec.key, pathlib.Path(d) / "r.toml"))
        _, truth = spec.run_trial(b, proto, 11)
    eq = truth["equipment"]
    assert eq["rate_table"]["rate_error_rel"] == t1.equipment.rate_table.rate_error_rel
    assert eq["fixture"]["misalignment_y_deg"] == t1.equipment.fixture.misalignment_y_deg


def test_drawn_errors_reach_the_readings():
    """Noise-free sessions: the drawn rate error scales the turning-table output, the drawn
    chamber deviation moves the gyro temperature at a set point, the fixture tilt gives
    the input axis a component along a turning axis (what cross-axis reads)."""
    from gonio.bench.rate_session import run_rate_session
    from gonio.protocol.programme import Segment

    b = load_rate_bench("mems-adxrs610").without_noise()
    g = replace(b.gyro, thermal_tau_s=1.0, cross_axis_x=0.0, cross_axis_y=0.0,
                sf_asymmetry=0.0, sf_cubic_per_dps2=0.0)
    b = replace(b, gyro=g)
    seg = [Segment("t", 0, 0, "rate", 20, 1.0, 100.0, temperature_c=60.0, ramp_c_per_min=3.0,
                   delay_s=1000.0)]
    eq = replace(b.equipment, rate_table=replace(b.equipment.rate_table, rate_error_rel=1e-3),
                 chamber=Chamber(point_deviation_c=2.0, deviation_seed=5))
    r0 = run_rate_session(seg, b, 1, noise=False).truth["segments"][0]
    r1 = run_rate_session(seg, replace(b, equipment=eq), 1, noise=False).truth["segments"][0]
    assert r1["input_rate_dps"] - r0["input_rate_dps"] == pytest.approx(0.1, rel=1e-6)
    assert r1["gyro_temperature_c"] - r0["gyro_temperature_c"] == pytest.approx(
        eq.chamber.deviation_at(60.0), abs=1e-6)
    # rotation about body x (x up): the fixture's tilt about body y puts sin(0.05°) of the
    # table rate on the input axis
    seg = [Segment("c", 0, 0, "rate", 36, 1.0, 10.0, up_axis="+x", north_axis="+y")]
    eq = replace(b.equipment.ideal(), fixture=Fixture(0.0, 0.05))
    s0 = run_rate_session(seg, replace(b, equipment=b.equipment.ideal()), 1, noise=False)
    s1 = run_rate_session(seg, replace(b, equipment=eq), 1, noise=False)
    d = (s1.truth["segments"][0]["input_rate_dps"] - s0.truth["segments"][0]["input_rate_dps"])
    assert abs(d) == pytest.approx(10.0 * math.sin(math.radians(0.05)), rel=1e-3)


def test_ripple_phase_drawn_uniform_amplitude_kept():
    """The table's once-per-revolution ripple: its phase uniform in [0°, 360°) per trial
    (the JJF 7.2.3 budget takes it as unknown), drawn after every other error so those are
    as before; its amplitude the bench's, which the readings state as
    ``rate_table_ripple_rel``."""
    eq = load_rate_bench("mems-adxrs610").equipment
    d = [draw_equipment(eq, s) for s in range(400)]
    ph = np.array([e.rate_table.ripple_phase_deg for e in d])
    assert np.all((ph >= 0.0) & (ph < 360.0))
    assert stats.kstest(ph, "uniform", args=(0.0, 360.0)).pvalue > 1e-3
    assert all(e.rate_table.ripple_rel == eq.rate_table.ripple_rel for e in d)
    # the draw order: the ripple phase is the generator's last number, the chamber's
    # fluctuation phase the one before it (6 numbers of the stream before both)
    rng = np.random.default_rng([9, 24])
    rng.normal(), rng.normal(), rng.uniform(size=2), rng.integers(0, 2 ** 31), rng.uniform()
    fl, rp = rng.uniform(0.0, 360.0), rng.uniform(0.0, 360.0)
    e = draw_equipment(eq, 9)
    assert (e.chamber.fluctuation_phase_deg, e.rate_table.ripple_phase_deg) == (fl, rp)


def test_drawn_ripple_phase_reaches_the_readings():
    """Noise-free: a segment turning less than a revolution reads the ripple's mean,
    r·|Ω|·(cos φ − cos(φ + Δ))/Δ over the turn Δ from angle 0 (closed form), so the
    trials' phases give different readings."""
    from gonio.bench.rate_session import run_rate_session
    from gonio.protocol.programme import Segment

    b = load_rate_bench("mems-adxrs610").without_noise()
    b = replace(b, gyro=replace(b.gyro, cross_axis_x=0.0, cross_axis_y=0.0, thermal_tau_s=1.0))
    seg = [Segment("r", 0, 0, "rate", 10, 1.0, 20.0)]          # 10 s at 20 °/s: 200°
    ideal = b.equipment.ideal()
    base = run_rate_session(seg, replace(b, equipment=ideal), 1, noise=False)
    r, w, delta = 2e-4, 20.0, math.radians(200.0)
    for s in (3, 4):
        phi = math.radians(draw_equipment(b.equipment, s).rate_table.ripple_phase_deg)
        rt = replace(ideal.rate_table, ripple_rel=r, ripple_phase_deg=math.degrees(phi))
        got = run_rate_session(seg, replace(b, equipment=replace(ideal, rate_table=rt)), 1,
                               noise=False)
        d = got.truth["segments"][0]["input_rate_dps"] - base.truth["segments"][0]["input_rate_dps"]
        assert d == pytest.approx(r * w * (math.cos(phi) - math.cos(phi + delta)) / delta,
                                  rel=2e-3, abs=1e-9)
