"""Issue 24: the IEC 62047-20 slopes' standard uncertainty (a_BASE, the temperature and
supply slopes) from the point means' noise and the bias drift between the points, each
checked against an independent computation."""

from __future__ import annotations

import numpy as np
import pytest

from gonio.specs.iec62047_20.items import slope_drift_u, slope_noise_u


def test_slope_noise_u_is_the_pseudo_inverse_row_propagated():
    rng = np.random.default_rng(3)
    x = np.array([-150.0, -100, -50, 0, 50, 100, 150, 10.0])
    u = rng.uniform(0.001, 0.01, x.size)
    row = np.linalg.pinv(np.column_stack([x, np.ones_like(x)]))[0]     # slope = row · y
    assert slope_noise_u(x, u) == pytest.approx(float(np.sqrt(np.sum(row ** 2 * u ** 2))),
                                                rel=1e-12)


def test_slope_drift_u_is_the_random_walk_covariance_propagated():
    # a random-walk drift: D(τ) = q τ, cov(d(t_i), d(t_j)) = q min(t_i, t_j) (+ a common
    # start offset that the slope's Σ w_i = 0 cancels)
    x = np.array([-150.0, -100, -50, 0, 50, 100, 170])          # mean ≠ 0 on purpose
    t = np.array([0.0, 40, 85, 130, 170, 215, 260]) + 30.0
    q = 2.5e-6
    w = np.linalg.pinv(np.column_stack([x, np.ones_like(x)]))[0]
    cov = q * np.minimum.outer(t, t) + 7.0
    assert slope_drift_u(x, t, lambda tau: np.sqrt(q * tau)) == pytest.approx(
        float(np.sqrt(w @ cov @ w)), rel=1e-10)
    # a drift the same at every point (D = 0) does not move a slope
    assert slope_drift_u(x, t, lambda tau: 0.0) == 0.0


def test_two_points_are_a_slope():
    # the smallest programme a slope has: two rates (noise: u√2/Δx; drift: half of u_diff·2/Δx)
    x, t = np.array([-1.0, 1.0]), np.array([0.0, 10.0])
    assert slope_noise_u(x, np.array([0.1, 0.1])) == pytest.approx(0.1 * np.sqrt(2) / 2)
    assert slope_drift_u(x, t, lambda tau: 0.1) == pytest.approx(0.05)
    assert np.isnan(slope_noise_u(x[:1], np.array([0.1]))) and np.isnan(
        slope_drift_u(x[:1], t[:1], lambda tau: 0.1))


def test_slope_degrees_of_freedom_from_the_points_blocks():
    """Review of stop 30: a slope's ν was 50 whatever its points held. Now Welch–
    Satterthwaite over the points (ν_i = blocks − 1), computed here from the variances
    of the slope's pseudo-inverse row; a programme of short points has few."""
    from gonio.specs.iec62047_20.items import slope_noise_dof
    rng = np.random.default_rng(5)
    x = np.array([-150.0, -100, -50, 0, 50, 100, 150])
    u = rng.uniform(0.001, 0.01, x.size)
    nu = rng.integers(1, 12, x.size).astype(float)
    row = np.linalg.pinv(np.column_stack([x, np.ones_like(x)]))[0]
    v = row ** 2 * u ** 2
    assert slope_noise_dof(x, u, nu) == pytest.approx(v.sum() ** 2 / np.sum(v ** 2 / nu),
                                                      rel=1e-10)
    assert slope_noise_dof(x, np.full(7, 0.01), np.full(7, 1.0)) < 7   # 1 dof a point
