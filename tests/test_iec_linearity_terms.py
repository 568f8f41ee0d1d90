"""IEC 62047-20 5.1.3.6 linearity: the budget terms for what moves the straight line's
residuals on the built-in programme besides the noise of the point means — the chamber's
temperature fluctuation moving K by T_c,SF while the 2n + 1 points are taken, and the bias's
drift between the points. Each closed form is checked against a Monte Carlo of that physics
(numpy.polyfit on each draw, FullScale from the draw's own end points), so a mutated term
fails."""

from __future__ import annotations

import numpy as np
import pytest

from gonio.specs.iec62047_20.items import linearity_drift_sd, linearity_fluctuation_sd

# the built-in programme's order (CCW max → rest → CW max), 30 samples + 10 s settling a point
X = np.array([-300, -240, -180, -120, -60, 0, 60, 120, 180, 240, 300], float)
T = 40.0 * np.arange(X.size) + 25.0
A_SF = 6.0                        # mV/(°/s), the ADXRS610 bench
C3 = 2e-9                         # a cubic nonlinearity (mV/(°/s)³), so the truth is not 0


def _L(y):
    """L_i of eq (8) for each row of y (one draw a row) by numpy.polyfit, FullScale measured
    from the draw's own end points."""
    a, b = np.polyfit(X, y.T, 1)
    fs = y[:, np.argmax(X)] - y[:, np.argmin(X)]
    return (y - (a[:, None] * X + b[:, None])) / fs[:, None]


def test_fluctuation_term_against_monte_carlo():
    rng = np.random.default_rng(11)
    base = A_SF * X + C3 * X ** 3
    fs = base[-1] - base[0]
    for amp, period in ((4.5e-5, 900.0), (1.5e-4, 300.0), (4.5e-5, 4000.0)):
        phi = rng.uniform(0, 2 * np.pi, 20_000)
        L = _L(base + A_SF * X * amp * np.sin(2 * np.pi * T / period + phi[:, None]))
        mc = L.std(axis=0)
        cf = linearity_fluctuation_sd(X, T, fs, A_SF, amp, period)
        np.testing.assert_allclose(cf, mc, rtol=0.03)
        # a stated period unknown: the bound holds over any period
        assert np.all(linearity_fluctuation_sd(X, T, fs, A_SF, amp, None) >= mc)
    # no fluctuation, no term; the term grows with the amplitude
    assert np.all(linearity_fluctuation_sd(X, T, fs, A_SF, 0.0, 900.0) == 0.0)


@pytest.mark.parametrize("kind", ["walk", "markov"])
def test_drift_term_against_monte_carlo(kind):
    """A rate random walk (D(τ) = q·τ) and a first-order Gauss–Markov drift
    (D(τ) = 2σ²(1 − e^{−τ/τc})), sampled at the points' times."""
    rng = np.random.default_rng(12)
    base = A_SF * X + C3 * X ** 3
    fs = base[-1] - base[0]
    n = 20_000
    if kind == "walk":
        q = 4e-7                      # (°/s)²/s
        steps = rng.normal(0, 1, (n, X.size)) * np.sqrt(np.diff(T, prepend=0.0) * q)
        d = np.cumsum(steps, axis=1)
        u_diff = lambda dt: np.sqrt(q * dt)                          # noqa: E731
    else:
        s, tc = 0.006, 200.0
        rho = np.exp(-np.diff(T) / tc)
        d = np.empty((n, X.size))
        d[:, 0] = rng.normal(0, s, n)
        for j in range(1, X.size):
            d[:, j] = rho[j - 1] * d[:, j - 1] + np.sqrt(1 - rho[j - 1] ** 2) * rng.normal(0, s, n)
        u_diff = lambda dt: np.sqrt(2 * s * s * (1 - np.exp(-dt / tc)))   # noqa: E731
    L = _L(base + A_SF * d)
    mc = L.std(axis=0)
    cf = linearity_drift_sd(X, T, fs, lambda dt: A_SF * u_diff(dt))
    np.testing.assert_allclose(cf, mc, rtol=0.04)
