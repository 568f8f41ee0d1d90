"""The GUM engine against the guides' own worked examples and closed forms.

JCGM 100 Annex H.1 (end gauge) at the precision the GUM prints; JCGM 101 9.2
(additive model) within Monte Carlo noise at 10⁶ trials with a fixed seed, plus
exact quantiles (Irwin–Hall) for the rectangular case; adaptive MC on known answers.
"""

import math

import numpy as np
import pytest
import sympy
from scipy import stats

from uncertainty import (adaptive_monte_carlo, coverage_interval, from_u, monte_carlo,
                         numerical_tolerance, propagate, type_b, validate_gum)

# ----------------------------------------------------------------------------- JCGM 100 H.1
ls, d, a_s, th, da, dt = sympy.symbols("l_s d alpha_s theta delta_alpha delta_theta")
H1_MODEL = ls + d - ls * (da * th + a_s * dt)  # JCGM 100 H.1.2, eq. (H.1)


def _h1_inputs():
    return [
        # certificate: U = 0.075 um, k = 3, nu = 18 (H.1.3.1)
        type_b("l_s", 50_000_623.0, 75.0, "normal", k=3, dof=18),
        from_u("d", 215.0, 9.7, dof=25.6),                        # H.1.3.2
        type_b("alpha_s", 11.5e-6, 2e-6, "rectangular"),           # H.1.3.3
        from_u("theta", -0.1, 0.41, type="B"),                     # H.1.3.4
        type_b("delta_alpha", 0.0, 1e-6, "rectangular", dof=50),   # H.1.3.5
        type_b("delta_theta", 0.0, 0.05, "rectangular", dof=2),    # H.1.3.6
    ]


def test_gum_h1_end_gauge():
    r = propagate(H1_MODEL, _h1_inputs(), p=0.99, integer_dof=True)
    assert round(r.value) == 50_000_838            # l = 50.000 838 mm
    assert round(r.u_c) == 32                      # u_c(l) = 32 nm
    contrib = {c.symbol: c.contribution for c in r.contributions}
    assert round(contrib["l_s"]) == 25 and round(contrib["d"], 1) == 9.7
    assert round(contrib["delta_alpha"], 1) == 2.9 and round(contrib["delta_theta"], 1) == 16.6
    assert contrib["alpha_s"] == 0.0 and contrib["theta"] == 0.0   # first-order c_i = 0
    assert math.floor(r.dof) == 16                 # nu_eff(l) = 16
    assert round(r.k, 2) == 2.92                   # t_99(16) = 2.92
    assert round(round(r.k, 2) * round(r.u_c)) == 93   # U_99 = 2.92 x 32 nm = 93 nm


# ----------------------------------------------------------------------------- JCGM 101 9.2
X = sympy.symbols("x1:5")
ADD = sum(X)


def _irwin_hall_cdf(x, n):
    k = np.arange(0, int(math.floor(x)) + 1)
    return float(np.sum((-1.0) ** k * np.array([math.comb(n, int(i)) for i in k])
                        * (x - k) ** n) / math.factorial(n))


def test_jcgm101_922_normal_inputs():
    q = [type_b(f"x{i}", 0.0, 1.0, "normal", k=1) for i in range(1, 5)]
    gum = propagate(ADD, q, p=0.95)
    assert round(gum.u_c, 2) == 2.00 and round(gum.U, 2) == 3.92
    mc = monte_carlo(ADD, q, 10**6, seed=11)
    assert mc.u == pytest.approx(2.00, abs=0.01)       # published MCM: 2.00
    assert mc.low == pytest.approx(-3.92, abs=0.02)    # published MCM: [-3.92, 3.92]
    assert mc.high == pytest.approx(3.92, abs=0.02)
    assert validate_gum(gum, mc, ndig=2).passed


def test_jcgm101_923_rectangular_inputs():
    q = [type_b(f"x{i}", 0.0, math.sqrt(3.0), "rectangular") for i in range(1, 5)]
    gum = propagate(ADD, q, p=0.95)
    assert round(gum.u_c, 2) == 2.00 and round(gum.U, 2) == 3.92
    mc = monte_carlo(ADD, q, 10**6, seed=12)
    # exact 97.5 % point of the sum: Irwin-Hall(4) on [0, 4] scaled by 2*sqrt(3), shifted
    from scipy.optimize import brentq
    z = brentq(lambda s: _irwin_hall_cdf(s, 4) - 0.975, 2.0, 4.0)
    exact = (z - 2.0) * 2.0 * math.sqrt(3.0)
    assert round(exact, 2) == 3.88                     # published MCM interval [-3.88, 3.88]
    assert mc.u == pytest.approx(2.00, abs=0.01)
    assert mc.low == pytest.approx(-exact, abs=0.015)
    assert mc.high == pytest.approx(exact, abs=0.015)


def test_jcgm101_924_one_dominant_rectangular():
    q = [type_b(f"x{i}", 0.0, math.sqrt(3.0), "rectangular") for i in range(1, 4)]
    q.append(type_b("x4", 0.0, 10.0 * math.sqrt(3.0), "rectangular"))
    gum = propagate(ADD, q, p=0.95)
    assert round(gum.u_c, 2) == 10.15                  # sqrt(103)
    assert round(gum.U, 1) == 19.9                     # GUM interval [-19.9, 19.9]
    mc = monte_carlo(ADD, q, 10**6, seed=13)
    assert mc.u == pytest.approx(10.15, abs=0.03)
    assert mc.low == pytest.approx(-17.0, abs=0.06)    # published MCM [-17.0, 17.0]
    assert mc.high == pytest.approx(17.0, abs=0.06)
    assert not validate_gum(gum, mc, ndig=2).passed    # GUM framework not validated here


# ----------------------------------------------------------------------------- intervals
def test_symmetric_interval_matches_scipy_quantiles():
    y = np.random.default_rng(5).normal(size=200_001)
    lo, hi = coverage_interval(y, 0.95)
    qlo, qhi = np.quantile(y, [0.025, 0.975], method="inverted_cdf")
    assert lo == pytest.approx(qlo, abs=2e-3) and hi == pytest.approx(qhi, abs=2e-3)


def test_shortest_interval_exponential_known():
    # shortest 95 % interval of Exp(1) is [0, -ln 0.05] = [0, 2.996]
    y = np.random.default_rng(6).exponential(size=400_000)
    lo, hi = coverage_interval(y, 0.95, shortest=True)
    assert lo == pytest.approx(0.0, abs=1e-3)
    assert hi == pytest.approx(-math.log(0.05), abs=0.03)
    slo, shi = coverage_interval(y, 0.95)
    assert (shi - slo) > (hi - lo)


# ----------------------------------------------------------------------------- adaptive
def test_numerical_tolerance_jcgm101_examples():
    assert numerical_tolerance(0.0035, 2) == pytest.approx(5e-5)   # JCGM 101 7.9.2 example
    assert numerical_tolerance(2.0, 1) == pytest.approx(0.5)
    assert numerical_tolerance(0.0996, 2) == pytest.approx(0.005)


def test_adaptive_mc_rectangular_known_answer():
    # Y uniform on [-1, 1]: u = 1/sqrt(3) = 0.577, 95 % interval [-0.95, 0.95]
    x = sympy.Symbol("x")
    r = adaptive_monte_carlo(x, [type_b("x", 0.0, 1.0, "rectangular")], ndig=2, seed=7)
    delta = numerical_tolerance(1 / math.sqrt(3), 2)
    assert r.converged and r.trials % 10_000 == 0 and r.trials >= 20_000
    assert abs(r.u - 1 / math.sqrt(3)) <= delta
    assert abs(r.low + 0.95) <= delta and abs(r.high - 0.95) <= delta


def test_adaptive_mc_more_digits_needs_more_trials():
    x = sympy.Symbol("x")
    q = [type_b("x", 0.0, 1.0, "normal", k=1)]
    r1 = adaptive_monte_carlo(x, q, ndig=1, seed=8)
    r2 = adaptive_monte_carlo(x, q, ndig=2, seed=8)
    assert r2.trials > r1.trials
    assert abs(r2.high - stats.norm.ppf(0.975)) <= numerical_tolerance(1.0, 2)
