"""The fast paths of the bench simulation give the per-sample values bit for bit."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from gonio.specs.ogam_draft.bench import load_bench
from gonio.specs.ogam_draft.bench.session import _Variant, _motion, _simulate_many, plan_session
from gonio.specs.ogam_draft.study import validation_protocol


def test_motion_on_runs_equals_the_timeline_sample_by_sample():
    p = validation_protocol()
    b = replace(load_bench("fog"), sample_rate_hz=20.0)
    blocks = plan_session(p, b, np.random.default_rng(3))
    dt = 1.0 / b.sample_rate_hz
    compressed = 0
    for blk in blocks:
        t = np.arange(blk.k_start, blk.k_end) * dt
        th_u, r_u, rep = _motion(blk, t)
        assert rep.sum() == t.size
        np.testing.assert_array_equal(np.repeat(th_u, rep), blk.timeline.angle_deg(t))
        np.testing.assert_array_equal(np.repeat(r_u, rep), blk.timeline.rate_dps(t))
        compressed += rep.size
    assert compressed < 0.25 * sum(blk.k_end - blk.k_start for blk in blocks)


def test_one_pass_over_two_instruments_equals_two_separate_passes():
    # The noisy run and its noise-free rerun share the table motion and deterministic
    # terms; each must equal a pass of its own (RLG trapezoid and FOG rectangle rule).
    p = validation_protocol()
    for name in ("rlg", "fog"):
        b = replace(load_bench(name), sample_rate_hz=20.0)
        blocks = plan_session(p, b, np.random.default_rng(1))
        both = _simulate_many(blocks, p, [_Variant(b, np.random.default_rng(9), dither_key=5),
                                          _Variant(b.random_off(), None)])
        alone = [_simulate_many(blocks, p, [_Variant(b, np.random.default_rng(9), dither_key=5)])[0],
                 _simulate_many(blocks, p, [_Variant(b.random_off(), None)])[0]]
        for x, y in zip(both, alone):
            np.testing.assert_array_equal(x.counts, y.counts)
            np.testing.assert_array_equal(x.true_deg, y.true_deg)
            assert x.comp_counts_s == y.comp_counts_s
        assert not np.array_equal(both[0].counts, both[1].counts)   # the noise is there


def test_readings_from_the_needed_samples_equal_those_from_every_sample():
    # Without a stream the integrator gives the angle only at the samples the readings need;
    # a stream makes it build every sample's angle (the whole-chunk expression). The readings,
    # the compensation and the captured record must be the same bit for bit (RLG and FOG).
    # Unquantised counts (K·φ as floats), so that any change of an angle shows.
    p = validation_protocol()
    for name in ("rlg", "fog"):
        b = replace(load_bench(name), sample_rate_hz=20.0)
        b = replace(b, instrument=replace(b.instrument, quantisation=False))
        blocks = plan_session(p, b, np.random.default_rng(2))
        seen = []
        every = _simulate_many(blocks, p, [_Variant(b, np.random.default_rng(4), dither_key=3,
                                                    stream=lambda t, c, tab: seen.append(t.size))])[0]
        needed = _simulate_many(blocks, p, [_Variant(b, np.random.default_rng(4), dither_key=3)])[0]
        assert sum(seen) == sum(blk.k_end - blk.k_start for blk in blocks)
        np.testing.assert_array_equal(every.counts, needed.counts)
        np.testing.assert_array_equal(every.true_deg, needed.true_deg)
        assert every.comp_counts_s == needed.comp_counts_s


def test_timeline_angle_rate_equals_angle_and_rate(monkeypatch):
    # Bit for bit (signed zeros included) on the run-by-run path and the element-wise one,
    # on sorted times (edges, before the first and after the last segment, included) and on
    # shuffled ones (a segment's times not in one run), on a scalar time and a 2-D grid.
    from gonio.physics import kinematics

    p = validation_protocol()
    b = replace(load_bench("rlg"), sample_rate_hz=50.0)
    shuffle = np.random.default_rng(6)
    for run_min in (1, 10**12):
        monkeypatch.setattr(kinematics, "_RUN_MIN", run_min)
        for blk in plan_session(p, b, np.random.default_rng(5)):
            t = np.arange(blk.k_start - 3, blk.k_end + 3) / b.sample_rate_hz  # edges included
            for times in (t, shuffle.permutation(t)):
                th, r = blk.timeline.angle_rate(times)
                assert th.tobytes() == blk.timeline.angle_deg(times).tobytes()
                assert r.tobytes() == blk.timeline.rate_dps(times).tobytes()
            for times in (t[len(t) // 2], t.reshape(1, -1)):   # a scalar, a grid
                th, r = blk.timeline.angle_rate(times)
                assert th.tobytes() == blk.timeline.angle_deg(times).tobytes()
                assert r.tobytes() == blk.timeline.rate_dps(times).tobytes()


def test_timeline_angle_is_the_integral_of_its_rate():
    """A check apart from the shared segment code: the table's angle between any two instants
    is the integral of its rate (cumulative trapezoid on a grid 100× finer than the samples),
    so a change of the angle's or the rate's formula that breaks kinematics fails here."""
    from scipy.integrate import cumulative_trapezoid

    p = validation_protocol()
    b = replace(load_bench("rlg"), sample_rate_hz=50.0)
    for blk in plan_session(p, b, np.random.default_rng(5)):
        t = np.arange(blk.k_start * 100, blk.k_end * 100 + 1) / (100.0 * b.sample_rate_hz)
        th, r = blk.timeline.angle_rate(t)
        integral = cumulative_trapezoid(r, t, initial=0.0)
        np.testing.assert_allclose(th - th[0], integral, atol=1e-5, rtol=0.0)
