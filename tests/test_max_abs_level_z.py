"""The statement's own z of E's extreme (:func:`uncertainty.extreme.max_abs_level_z`) against
the interval it belongs to and against its distribution where the interval is exact.

- Consistency with the stated interval: the 95 % interval (:func:`max_abs_interval`, normal
  factors) holds θ exactly when |z| ≤ Φ⁻¹(0.975), and z's sign says on which side it misses.
- One point: the folded normal's interval, z = (|x| − θ)/u in closed form (|x| ≫ u).
- The upper side's worst pattern (one point far above the others): |z| is half-normal there
  (the interval at p misses with 1 − p), so P(|z| ≤ 1.96) ≈ 0.95 and z's root mean square ≈ 1,
  from draws of the estimates (not from the formula of the factors); at twelve alike points it
  is narrower (the every-pattern interval's price)."""

from __future__ import annotations

import numpy as np
from scipy.stats import binomtest

from uncertainty.extreme import max_abs_interval, max_abs_level_z

Z95 = 1.959963984540054


def test_level_z_agrees_with_the_stated_interval():
    rng = np.random.default_rng(20261201)
    for _ in range(40):
        m = int(rng.integers(1, 13))
        mu = rng.normal(0.0, 2.0, m)
        u = rng.uniform(0.2, 1.0, m)
        x = mu + rng.normal(0.0, 1.0, m) * u
        theta = float(np.abs(mu).max())
        r = max_abs_interval(x, u)
        z = max_abs_level_z(x, u, theta)
        holds = r.lower <= theta <= r.upper
        assert holds == (abs(z) <= Z95 + 1e-6), (x, u, theta, z, r)
        if not holds:
            assert (z < 0) == (theta > r.upper)


def test_one_point_is_the_normal_z():
    for x, th in ((5.0, 4.2), (5.0, 6.1), (-7.0, 6.5)):
        assert abs(max_abs_level_z([x], [0.5], th) - (abs(x) - th) / 0.5) < 1e-6


def test_half_normal_at_the_dominant_pattern_and_narrower_where_alike():
    rng = np.random.default_rng(7)
    n = 300
    mu = np.array([20.0] + [0.0] * 11)
    z = np.array([max_abs_level_z(mu + rng.normal(0.0, 1.0, 12), np.ones(12), 20.0)
                  for _ in range(n)])
    inside = int(np.sum(np.abs(z) <= Z95))
    assert binomtest(inside, n, 0.95).pvalue > 0.01, inside
    assert 0.85 <= float(np.sqrt(np.mean(z * z))) <= 1.15
    alike = np.full(12, 20.0)
    za = np.array([max_abs_level_z(alike + rng.normal(0.0, 1.0, 12), np.ones(12), 20.0)
                   for _ in range(100)])
    assert float(np.sqrt(np.mean(za * za))) < 0.85


def test_miss_probability_equals_the_formula_with_norm_cdf():
    """max_abs_miss evaluates Φ by scipy.special.ndtr (for speed inside the root searches):
    bit for bit the formula written here with scipy.stats.norm.cdf, so every factor and z
    is the same number."""
    from scipy.stats import norm

    from uncertainty.extreme import max_abs_miss

    d = np.linspace(0.0, 10.0, 2001)
    rng = np.random.default_rng(3)
    for m in (1, 2, 12, 40):
        for cu, cl in zip(rng.uniform(-6.0, 9.0, 8), rng.uniform(0.0, 5.0, 8)):
            want = (norm.cdf(-cu) * norm.cdf(d - cu) ** (m - 1)
                    + (1.0 - norm.cdf(cl) * norm.cdf(cl + d) ** (m - 1)))
            assert np.array_equal(max_abs_miss(cu, cl, m, d), want)


def test_largest_miss_is_the_whole_grids_maximum():
    """The factors' root searches take the worst pattern's miss from a coarse grid and the
    stretches of δ that can still hold a larger one (:func:`uncertainty.extreme._largest_miss`):
    the same number, bit for bit, as the maximum of max_abs_miss over all 2001 δ, from the
    flat ends of c_H to maxima inside the grid (over a hundred of them here off the coarse grid)."""
    from uncertainty.extreme import _largest_miss, max_abs_miss

    d = np.linspace(0.0, 10.0, 2001)
    inside = 0
    for m in (2, 12):
        for cu in np.linspace(-6.0, 9.0, 31):
            for cl in np.linspace(0.0, 5.0, 11):
                full = max_abs_miss(cu, cl, m, d)
                inside += int(np.argmax(full)) % 25 != 0
                assert _largest_miss(cu, cl, m) == float(np.max(full)), (cu, cl, m)
    assert inside > 100, inside
