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
