"""The drift line of a slope fitted to record means (IEC 62047-20 5.3.3.8): the variance of a
zero-sum combination of window means under the rate random walk
(:func:`gonio.specs._rate_family.formulas.window_combination_u_coef`) against a Monte Carlo of
the walk itself, sample by sample — a second algorithm, not the covariance formula again."""
import math

import numpy as np
import pytest

from gonio.errors import GonioError
from gonio.specs._rate_family.formulas import (record_difference_u_coef,
                                               window_combination_u_coef)


def _slope_weights(x: np.ndarray) -> np.ndarray:
    A = np.column_stack([np.ones_like(x), x, np.sin(np.arange(x.size))])
    return np.linalg.pinv(A)[1]


def test_slope_of_window_means_under_a_walk_matches_a_monte_carlo():
    """Twelve records of 40 samples at 0.1 s, irregular gaps (a tilting stand's turn), the
    slope against cos γ with a second regressor and an intercept: the walk's share of the
    slope, simulated 6000 times, has the variance the formula gives (within 6 %; the
    estimate's own relative sd is √(2/6000) = 1.8 %)."""
    rng = np.random.default_rng(20261203)
    dt, n, K = 0.1, 40, 0.03
    gaps = rng.uniform(5.0, 30.0, 12)
    starts = np.cumsum(gaps)
    x = np.cos(np.radians(np.arange(12) * 30.0))
    c = _slope_weights(x)
    # the walk on the whole time line, sample by sample; each record the mean of its samples
    t_end = starts[-1] + n * dt
    m = int(round(t_end / dt)) + 1
    idx = [np.round(s / dt).astype(int) + np.arange(n) for s in starts]
    trials = 6000
    coef = np.empty(trials)
    for i in range(trials):
        w = np.cumsum(rng.normal(0.0, K * math.sqrt(dt), m))
        coef[i] = c @ np.array([w[j].mean() for j in idx])
    windows = [(float(np.round(s / dt)) * dt, n * dt) for s in starts]
    u = window_combination_u_coef(K * K, 0.0, windows, c)
    assert abs(coef.var() / u ** 2 - 1.0) < 0.06, (coef.var(), u ** 2)
    # the crude rule it replaced, u_drift(duration)·√(2/n), is not this number
    crude = math.sqrt(K * K * (t_end - starts[0])) * math.sqrt(2.0 / 12)
    assert abs(crude / u - 1.0) > 0.2


def test_a_difference_is_the_two_record_rule():
    a, b = (0.0, 60.0), (300.0, 60.0)
    assert window_combination_u_coef(2e-6, 3e-4, [a, b], [-1, 1]) == pytest.approx(
        record_difference_u_coef(2e-6, 3e-4, a, b), rel=1e-12)


@pytest.mark.parametrize("weights, windows, what", [
    ([1.0, 1.0], [(0, 1), (2, 1)], "not 0"),
    ([1.0, -1.0], [(0, 1), (2, 0)], "each must be positive"),
    ([1.0, -1.0, 0.0], [(0, 1), (2, 1)], "3 weights for 2 windows"),
])
def test_refused_combinations(weights, windows, what):
    with pytest.raises(GonioError, match=what):
        window_combination_u_coef(1.0, 1.0, windows, weights)
