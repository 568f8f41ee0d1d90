"""Inputs, rounding, tables and MC sampling of the GUM engine, against independent formulas."""

import math
import statistics

import numpy as np
import pytest
import sympy
from scipy import stats

from uncertainty import (COLUMNS, DISTRIBUTIONS, budget_table, coverage_factor, distribution,
                         from_u, monte_carlo, propagate, render_html, render_markdown,
                         render_text, sample_inputs, type_a,
                         type_b)

# scipy's own standard deviations for half-width a = 1 (independent of our divisors)
SCIPY_STD = {
    "rectangular": stats.uniform(loc=-1, scale=2).std(),
    "triangular": stats.triang(c=0.5, loc=-1, scale=2).std(),
    "arcsine": stats.arcsine(loc=-1, scale=2).std(),
    "normal": stats.norm(scale=0.5).std(),            # k = 2
    "trapezoidal": stats.trapezoid(c=0.25, d=0.75, loc=-1, scale=2).std(),  # beta = 0.5
}


@pytest.mark.parametrize("name", sorted(SCIPY_STD))
def test_divisor_and_samples_match_scipy(name):
    q = type_b("x", 3.0, 1.0, name, k=2 if name == "normal" else None,
               beta=0.5 if name == "trapezoidal" else None)
    assert q.u == pytest.approx(SCIPY_STD[name], rel=1e-12)
    x = q.sample(np.random.default_rng(1), 400_000)
    assert x.mean() == pytest.approx(3.0, abs=0.01)
    assert x.std() == pytest.approx(SCIPY_STD[name], rel=5e-3)
    if name != "normal":
        assert x.min() >= 2.0 and x.max() <= 4.0


def test_one_mapping_and_aliases():
    assert distribution("uniform").name == "rectangular"
    assert distribution("U-shaped").name == "arcsine"
    assert set(DISTRIBUTIONS) >= {"normal", "rectangular", "triangular", "arcsine", "trapezoidal"}
    with pytest.raises(ValueError, match="unknown distribution"):
        distribution("cauchy")
    with pytest.raises(ValueError):
        type_b("x", 0.0, -1.0)


def test_type_a_against_statistics_module():
    data = [10.03, 10.01, 9.98, 10.05, 10.00, 9.99, 10.02]
    q = type_a("x", data)
    assert q.value == pytest.approx(statistics.fmean(data), rel=1e-15)
    assert q.u == pytest.approx(statistics.stdev(data) / math.sqrt(len(data)), rel=1e-13)
    assert q.dof == len(data) - 1 and q.type == "A"
    assert type_a("x", data, of_mean=False).u == pytest.approx(statistics.stdev(data), rel=1e-13)


def test_type_a_samples_scaled_t():
    # JCGM 101 6.4.9: the MC variance of a Type A input with nu dof is u^2 nu/(nu - 2)
    q = from_u("x", 0.0, 2.0, dof=5)
    x = q.sample(np.random.default_rng(2), 1_000_000)
    assert x.std() == pytest.approx(2.0 * math.sqrt(5 / 3), rel=0.01)


def test_coverage_factor_against_tables():
    assert round(coverage_factor(math.inf, 0.95), 2) == 1.96      # JCGM 100 Table G.2
    assert round(coverage_factor(10, 0.95), 2) == 2.23
    assert round(coverage_factor(16.7, 0.99, integer_dof=True), 2) == 2.92
    assert coverage_factor(4.5, 0.95) == pytest.approx(stats.t.ppf(0.975, 4.5))


def test_fixed_k_and_p():
    x = sympy.Symbol("x")
    q = [from_u("x", 1.0, 0.5, dof=9)]
    assert propagate(x, q, k=2).U == pytest.approx(1.0)
    assert propagate(x, q, p=0.95).k == pytest.approx(stats.t.ppf(0.975, 9))
    with pytest.raises(ValueError):
        propagate(x, q, k=0)


def test_table_columns_and_renderings():
    x, y = sympy.symbols("x y")
    res = propagate(2 * x - y, [type_b("x", 1.0, 0.3, source="src<x>"), from_u("y", 0.0, 0.1, dof=4)])
    t = budget_table(res)
    assert tuple(t.columns) == COLUMNS
    np.testing.assert_allclose(t.contribution, np.abs(t.c_i) * t.u_xi, rtol=1e-15)
    assert t.contribution.iloc[0] == pytest.approx(2 * 0.3 / math.sqrt(3))
    txt = render_text(t)
    assert txt.splitlines()[0].split() == list(COLUMNS) and "∞" in txt
    md = render_markdown(t)
    assert md.count("\n") == 3 and md.startswith("| symbol |")
    html = render_html(t)
    assert "src&lt;x&gt;" in html and html.count("<tr>") == 3


def test_correlated_mc_sampling_covariance():
    q = [from_u("a", 1.0, 0.1), from_u("b", 2.0, 0.2), from_u("c", 0.0, 1.0)]
    r = np.array([[1, -0.6, 0], [-0.6, 1, 0], [0, 0, 1]])
    xs = sample_inputs(q, 400_000, np.random.default_rng(3), correlation=r)
    assert np.corrcoef(xs[0], xs[1])[0, 1] == pytest.approx(-0.6, abs=0.01)
    # MC of a + b with correlation agrees with the GUM's u_c (linear model)
    a, b = sympy.symbols("a b")
    gum = propagate(a + b, q[:2], correlation=r[:2, :2])
    mc = monte_carlo(a + b, q[:2], 400_000, seed=4, correlation=r[:2, :2])
    assert mc.u == pytest.approx(gum.u_c, rel=0.01)


def test_same_seed_same_bytes():
    x, y = sympy.symbols("x y")
    q = [type_b("x", 0, 1, "triangular"), type_b("y", 0, 1, "arcsine")]
    _, y1 = monte_carlo(x * y, q, 1000, seed=9, return_values=True)
    _, y2 = monte_carlo(x * y, q, 1000, seed=9, return_values=True)
    assert y1.tobytes() == y2.tobytes()
