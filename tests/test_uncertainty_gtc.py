"""The law of propagation against GTC (an independent GUM implementation, test-only)."""

import math

import numpy as np
import pytest
import sympy

import GTC
from GTC import ureal

from uncertainty import from_u, propagate, sensitivity_coefficients

a, b, c, d = sympy.symbols("a b c d", real=True)
X = {"a": (1.3, 0.11, 7.0), "b": (2.7, 0.23, 12.0), "c": (0.6, 0.05, math.inf), "d": (4.1, 0.37, 4.0)}


def _ours(names):
    return [from_u(n, X[n][0], X[n][1], dof=X[n][2]) for n in names]


def _gtc(names, independent=True):
    return {n: ureal(X[n][0], X[n][1], X[n][2], label=n, independent=independent) for n in names}


MODELS = [
    ("linear", 2 * a - 3 * b + c + 0.5 * d, lambda g: 2 * g["a"] - 3 * g["b"] + g["c"] + 0.5 * g["d"]),
    ("product_quotient", a * b / (c * d), lambda g: g["a"] * g["b"] / (g["c"] * g["d"])),
    ("trig", a * sympy.sin(b) + sympy.cos(c) * d ** 2,
     lambda g: g["a"] * GTC.sin(g["b"]) + GTC.cos(g["c"]) * g["d"] ** 2),
    ("exp_log", sympy.exp(c) * sympy.log(d) - sympy.sqrt(a * b),
     lambda g: GTC.exp(g["c"]) * GTC.log(g["d"]) - GTC.sqrt(g["a"] * g["b"])),
]


@pytest.mark.parametrize("name,expr,gtc_model", MODELS, ids=[m[0] for m in MODELS])
def test_symbolic_matches_gtc(name, expr, gtc_model):
    names = ["a", "b", "c", "d"]
    ours = propagate(expr, _ours(names))
    ref = gtc_model(_gtc(names))
    assert ours.value == pytest.approx(ref.x, rel=1e-14)
    assert ours.u_c == pytest.approx(ref.u, rel=1e-12)
    assert ours.dof == pytest.approx(ref.df, rel=1e-12)
    # each component u_i(y) = |c_i| u(x_i) against GTC's component()
    g = _gtc(names)
    yv = gtc_model(g)
    for row in ours.contributions:
        assert row.contribution == pytest.approx(abs(GTC.component(yv, g[row.symbol])), rel=1e-12)


@pytest.mark.parametrize("name,expr,gtc_model", MODELS, ids=[m[0] for m in MODELS])
def test_callable_numeric_derivatives_match_gtc(name, expr, gtc_model):
    names = ["a", "b", "c", "d"]
    f = sympy.lambdify([a, b, c, d], expr, "numpy")
    ours = propagate(f, _ours(names))
    ref = gtc_model(_gtc(names))
    assert ours.u_c == pytest.approx(ref.u, rel=1e-8)
    assert ours.dof == pytest.approx(ref.df, rel=1e-7)


def test_correlated_inputs_match_gtc():
    # a, b correlated (infinite dof, as GTC requires outside an ensemble); c finite dof
    xa, xb, xc = (1.0, 0.1, math.inf), (2.0, 0.2, math.inf), (3.0, 0.3, 6.0)
    ga = ureal(*xa, label="a", independent=False)
    gb = ureal(*xb, label="b", independent=False)
    gc = ureal(*xc, label="c")
    GTC.set_correlation(0.7, ga, gb)
    for expr, gexpr in [(a * b + c, ga * gb + gc), (a / b - sympy.sin(c) * a, ga / gb - GTC.sin(gc) * ga)]:
        q = [from_u("a", *xa[:2]), from_u("b", *xb[:2]), from_u("c", xc[0], xc[1], dof=xc[2])]
        r = np.array([[1, 0.7, 0], [0.7, 1, 0], [0, 0, 1]])
        ours = propagate(expr, q, correlation=r)
        assert ours.u_c == pytest.approx(gexpr.u, rel=1e-12)
        assert ours.dof == pytest.approx(gexpr.df, rel=1e-12)
        # the same through a covariance matrix
        cov = r * np.outer([0.1, 0.2, 0.3], [0.1, 0.2, 0.3])
        assert propagate(expr, q, covariance=cov).u_c == pytest.approx(gexpr.u, rel=1e-12)


def test_correlated_finite_dof_gives_nan_dof():
    # GTC refuses this (not an ensemble); WS is not valid there, so we return NaN
    q = [from_u("a", 1.0, 0.1, dof=5), from_u("b", 2.0, 0.2, dof=5)]
    res = propagate(a + b, q, correlation=[[1, 0.5], [0.5, 1]])
    assert math.isnan(res.dof)
    assert res.u_c == pytest.approx(math.sqrt(0.01 + 0.04 + 2 * 0.5 * 0.02), rel=1e-14)


def test_sensitivities_symbolic_vs_numeric():
    q = _ours(["a", "b", "c", "d"])
    expr = a * sympy.sin(b) * sympy.exp(c) / d
    f = sympy.lambdify([a, b, c, d], expr, "numpy")
    np.testing.assert_allclose(sensitivity_coefficients(f, q), sensitivity_coefficients(expr, q),
                               rtol=1e-8)
