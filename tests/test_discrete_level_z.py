"""The level z of the discrete outcomes (IEC 62047-20 5.6 resolution, JJF 1535 7.2.6/7.2.7:
a 50 % rule's outcome on a tested grid) and the noise of IEC 5.6's referred steps.

- :func:`gonio.analysis.coverage.level_z_discrete` is the randomised probability integral
  transform: with the truth drawn from the stated distribution itself (atoms alone, and
  the maximum with a normal part), z is N(0, 1) — sd 1, 2.5 % above 1.96 — whatever the
  grid (the mid-value v = ½ gives sd 0.62 on a distribution with 90 % on one atom, which is
  why it is randomised). Drawn here with numpy, not by the function's formula.
- :func:`gonio.specs.iec62047_20.items.referred_step_sd` on a random walk matches the exact
  variance of m_k − (m_(k−1) + m_(k+1))/2 computed by linear algebra (the walk's
  cumulative-sum matrix), and σ_T·√1.5 on white noise. Taking the samples as white (the
  rule before: s/√n) is 3× too small on the walk: the first check fails with it.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from gonio.analysis.coverage import level_z_discrete
from gonio.specs.iec62047_20.items import referred_step_sd


def _draw_truths(dist, rng, n):
    a = np.asarray(dist["atoms"], float)
    x = rng.choice(a[:, 0], size=n, p=a[:, 1] / a[:, 1].sum())
    if dist["normal"]:
        x = np.maximum(x, dist["normal"][0] + dist["normal"][1] * rng.standard_normal(n))
    return x


@pytest.mark.parametrize("dist", [
    {"atoms": [[0.01, 0.05], [0.02, 0.9], [0.05, 0.05]], "normal": None},
    {"atoms": [[0.02, 0.3], [0.05, 0.6], [0.1, 0.1]], "normal": [0.03, 0.004]}])
def test_randomised_pit_is_normal_where_the_distribution_is_the_truths(dist):
    rng = np.random.default_rng(3)
    t = _draw_truths(dist, rng, 6000)
    z = np.array([level_z_discrete(dist, float(x), float(v))
                  for x, v in zip(t, rng.random(t.size))])
    assert z.std(ddof=1) == pytest.approx(1.0, abs=0.04)
    assert abs(z.mean()) < 0.05
    assert np.mean(z > stats.norm.ppf(0.975)) == pytest.approx(0.025, abs=0.006)
    if dist["normal"] is None:          # the mid-value alone cannot reach that spread
        zm = np.array([level_z_discrete(dist, float(x), 0.5) for x in t])
        assert zm.std(ddof=1) == pytest.approx(np.sqrt(0.1) * 1.959964, abs=0.05)


def test_referred_step_sd_of_a_random_walk_is_exact():
    q, P = 1.0, 20
    rng = np.random.default_rng(4)
    x = np.cumsum(q * rng.standard_normal(P * 20_000))
    got = referred_step_sd(x, P)
    # exact: d = w·x over three adjacent blocks, x = L e (L lower-triangular ones)
    w = np.concatenate([np.full(P, -0.5 / P), np.full(P, 1.0 / P), np.full(P, -0.5 / P)])
    L = np.tril(np.ones((3 * P, 3 * P)))
    exact = q * float(np.linalg.norm(L.T @ w))
    assert got == pytest.approx(exact, rel=0.03)
    # the samples' own s/√n of a block (about the block mean) is far below it
    blocks = x[: P * 1000].reshape(-1, P)
    white = float(np.mean(blocks.std(axis=1, ddof=1)) / np.sqrt(P) * np.sqrt(1.5))
    assert white < exact / 2


def test_referred_step_sd_white_and_refusal():
    rng = np.random.default_rng(5)
    assert referred_step_sd(2.0 * rng.standard_normal(300_000), 50) == pytest.approx(
        2.0 / np.sqrt(50) * np.sqrt(1.5), rel=0.03)
    with pytest.raises(Exception, match="3 blocks"):
        referred_step_sd(np.zeros(10), 5)
