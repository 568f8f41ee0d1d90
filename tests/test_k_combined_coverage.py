"""The coverage factor of a budget whose non-normal lines dominate comes from the budget's
combined distribution (JCGM 101), checked against a second algorithm: the exact probability
of the sum of a normal and an arcsine line by quadrature over the arcsine's phase, and
closed forms of single lines. K's budget, whose table line at the MPE bound is arcsine and
dominates u_c, states k from it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, optimize, stats

from gonio.specs.ogam_draft.item_uncertainty import (K_SOURCE_COMBINED, budget_k,
                                                     monte_carlo_check, scale_factor_budget)
from uncertainty import combined_coverage_factor, from_u, needs_combined_k, type_b
from uncertainty.combined import line_cdf, monte_carlo_coverage_factor


def _quadrature_k(share: float, p: float = 0.95) -> float:
    """k of Y = N(0, σ²) + A·sin φ (φ uniform), u_c = 1, the arcsine's share of u_c² =
    ``share``: P(|Y| ≤ U) = (1/π)∫₀^π [Φ((U − A cos φ)/σ) − Φ((−U − A cos φ)/σ)] dφ = p."""
    a = math.sqrt(2.0 * share)
    sigma = math.sqrt(1.0 - share)

    def prob(u):
        if sigma == 0.0:
            return 2.0 / math.pi * math.asin(min(u / a, 1.0))
        f = lambda phi: (stats.norm.cdf((u - a * math.cos(phi)) / sigma)
                         - stats.norm.cdf((-u - a * math.cos(phi)) / sigma))
        return integrate.quad(f, 0.0, math.pi, epsabs=1e-12, limit=200)[0] / math.pi

    return optimize.brentq(lambda u: prob(u) - p, 1e-6, 5.0, xtol=1e-10)


def _lines(share: float):
    return [type_b("A", 0.0, math.sqrt(2.0 * share), "arcsine"),
            from_u("n", 0.0, math.sqrt(1.0 - share), type="B")]


@pytest.mark.parametrize("share", [0.3, 0.6, 0.9, 0.97, 1.0])
def test_combined_k_is_the_exact_k_of_normal_plus_arcsine(share):
    lines = _lines(share)[:1] if share == 1.0 else _lines(share)
    k = combined_coverage_factor(lines, [1.0] * len(lines))
    assert k == pytest.approx(_quadrature_k(share), abs=1e-4), (share, k)
    # the Monte Carlo, the second algorithm, within its sampling error (about 0.1 %)
    assert monte_carlo_coverage_factor(lines, [1.0] * len(lines), seed=3) == pytest.approx(
        _quadrature_k(share), rel=0.004)


def test_rule_switches_where_the_gum_k_is_still_within_a_percent():
    """Below 1/4 of u_c² in non-normal lines the GUM's t-factor stays; just above it the
    combined k differs from 1.96 by under 1 % (exact), so the switch is no jump."""
    assert not needs_combined_k(_lines(0.24), [1.0, 1.0])
    assert needs_combined_k(_lines(0.26), [1.0, 1.0])
    k, src = budget_k(math.inf, None, _lines(0.24), [1.0, 1.0])
    assert src == "welch-satterthwaite" and k == pytest.approx(1.959964, abs=1e-5)
    k, src = budget_k(math.inf, None, _lines(0.26), [1.0, 1.0])
    assert src == K_SOURCE_COMBINED
    assert abs(_quadrature_k(0.26) / 1.959964 - 1.0) < 0.01
    assert k == pytest.approx(_quadrature_k(0.26), abs=0.006)
    # the laboratory's k wins over both
    assert budget_k(math.inf, 2.0, _lines(0.9), [1.0, 1.0]) == (2.0, "fixed by laboratory")


def test_with_a_type_a_line_of_few_dof_the_switch_moves_k_to_the_t_draws():
    """A Type A line of ν = 2 at 11 % of u_c²: the GUM folds it into ν_eff (k ≈ 1.97),
    JCGM 101 draws a scaled-and-shifted t₂ (6.4.9). Above the share k is the t draws', the
    same on both sides of the switch (the lines' distributions, not the rule, decide it),
    and checked against the exact probability of the sum by quadrature over the t₂."""
    def lines(share):
        return [type_b("R", 0.0, math.sqrt(3.0 * share), "rectangular"),
                from_u("s", 0.0, math.sqrt(0.11), dof=2),
                from_u("n", 0.0, math.sqrt(1.0 - share - 0.11), type="B")]

    k_ws, src = budget_k(165.0, None, lines(0.24), [1.0] * 3)
    assert src == "welch-satterthwaite" and k_ws == pytest.approx(1.974, abs=0.002)
    k_mc, src = budget_k(math.inf, None, lines(0.26), [1.0] * 3)
    assert src == K_SOURCE_COMBINED

    def prob(u, share=0.26):
        # Y = R + s·T₂ + N: P(|Y| ≤ u) = E_T[P(|R + N| ≤ u − s·t ...)] by quadrature over
        # t (t₂ density) and the rectangular's x, the normal in closed form
        a, s, sig = math.sqrt(3.0 * share), math.sqrt(0.11), math.sqrt(1.0 - share - 0.11)

        def inner(t):
            g = lambda x: (stats.norm.cdf((u - x - s * t) / sig)
                           - stats.norm.cdf((-u - x - s * t) / sig))
            return integrate.quad(g, -a, a, epsabs=1e-10)[0] / (2.0 * a)

        return integrate.quad(lambda t: inner(t) * stats.t.pdf(t, 2), -np.inf, np.inf,
                              epsabs=1e-9, limit=200)[0]

    exact = optimize.brentq(lambda u: prob(u) - 0.95, 1.0, 4.0, xtol=1e-6)
    assert exact > 2.2                       # the t₂ line, not the share, makes k large
    assert k_mc == pytest.approx(exact, rel=0.01)


def test_correlated_lines_that_cancel_carry_no_share_and_keep_the_gum_k():
    r = [[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    q = [type_b("a", 0.0, 1.0, "rectangular"), type_b("b", 0.0, 1.0, "rectangular"),
         from_u("s", 0.0, 0.2)]
    from uncertainty.combined import non_normal_share
    assert non_normal_share(q, [1.0, -1.0, 1.0], r) == pytest.approx(0.0, abs=1e-12)
    assert budget_k(math.inf, None, q, [1.0, -1.0, 1.0], r)[1] == "welch-satterthwaite"
    # correlated, not cancelling: the MC could only draw them normal, so the GUM's k stands
    assert not needs_combined_k(q, [1.0, 1.0, 1.0], r)


def test_combined_k_is_deterministic():
    q = _lines(0.8) + [from_u("s", 0.0, 0.3, dof=4), type_b("r", 0.0, 0.2, "rectangular")]
    a = combined_coverage_factor(q, [1.0, -1.0, 1.0, 1.0], seed=5)
    assert a == combined_coverage_factor(q, [1.0, -1.0, 1.0, 1.0], seed=5)


def _k_at_its_bound():
    """The draft's six rounds of a fine counter (3.6×10⁶ counts/°) with K_i nearly equal:
    the table lines (one rectangular per position, the zero shared; together 0.1151 ppm =
    0.41 counts/°) carry most of u_c²."""
    k_i = 3.6e6 + np.array([0.0, 0.4, -0.3, 0.2, 0.0, -0.3])
    return scale_factor_budget(k_i, [60, 120, 180, 240, 300, 360], 0.1)


def test_k_states_its_combined_distributions_k_and_the_jcgm101_check_agrees():
    b = _k_at_its_bound()
    share = sum(c.u ** 2 for c in b.components if c.distribution == "rectangular") / b.u_c ** 2
    assert share > 0.9
    assert b.k_source == K_SOURCE_COMBINED and b.k < 1.92
    d = b.to_dict()
    assert d["k_source"] == K_SOURCE_COMBINED and d["nu_eff"] is None
    assert d["U"] == pytest.approx(b.k * b.u_c, rel=1e-12)
    # a second, independent JCGM 101 propagation (the model as an expression, its own seed,
    # the probabilistically symmetric interval of JCGM 101 7.7): its half-width is U
    mc, _ = monte_carlo_check(b, 400_000, seed=3)
    assert (mc.high - mc.low) / 2 == pytest.approx(b.U, rel=0.01)
    # the GUM's t-factor would overstate it (a sum of rectangulars is shorter-tailed)
    assert 1.96 * b.u_c > 1.03 * b.U


def test_the_outputs_name_the_same_k_source():
    """The rendering side (stated.py, a pure function of results.json) names the k_source
    the budgets write; the note appears for a stated k of that source only."""
    from gonio.kit.render import labels
    from gonio.specs.ogam_draft import stated
    from gonio.specs.ogam_draft.phrases import LABELS

    assert stated.K_SOURCE_COMBINED == K_SOURCE_COMBINED
    b = _k_at_its_bound()
    res = {"items": {"scale_factor": {"measured": True, "clause": "7.1", "value": b.value,
                                      "unit": "counts/deg", "uncertainty": b.to_dict()}}}
    for lang in ("en", "zh"):
        note = stated.combined_k_note(res, labels(lang, LABELS))
        assert note and "JCGM 101" in note and "t95(ν_eff)" in note
    res["items"]["scale_factor"]["uncertainty"]["k_source"] = "welch-satterthwaite"
    assert stated.combined_k_note(res, labels("en", LABELS)) is None


@pytest.mark.parametrize("dist,beta", [("rectangular", None), ("triangular", None),
                                       ("arcsine", None), ("rectangular-product", None),
                                       ("rectangular-shifted-product", 0.3),
                                       ("rectangular-shifted-product", 0.8)])
def test_line_distribution_functions_against_their_draws(dist, beta):
    """Each line's closed-form distribution function (the convolution's input) against the
    empirical one of 4·10⁵ draws of the same line (Kolmogorov–Smirnov distance). A trapezoid
    is convolved as its two rectangulars (checked in the budgets' test below)."""
    q = type_b("X", 0.0, 1.3, dist, beta=beta)
    x = np.sort(q.sample(np.random.default_rng(11), 400_000))
    f = line_cdf(dist, x, scale=q.u, half_width=q.half_width, beta=beta)
    emp = np.arange(1, x.size + 1) / x.size
    assert float(np.max(np.abs(f - emp))) < 0.004


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_convolution_k_agrees_with_the_monte_carlo_on_k_like_budgets(seed):
    """Budgets shaped as K's (a t line, arcsine table and tilt lines, a triangular quantum, a
    rectangular product, a trapezoid), random sizes: the numerical convolution and the
    Monte Carlo of 10⁶ draws agree within the Monte Carlo's sampling error."""
    rng = np.random.default_rng(seed)
    s = rng.uniform(0.2, 1.0, 6)
    q = [from_u("s", 0.0, s[0], dof=int(rng.integers(3, 30))),
         type_b("P", 0.0, 2 * s[1], "arcsine"), type_b("q", 0.0, s[2], "triangular"),
         type_b("t", 0.0, s[3], "arcsine"), type_b("T", 0.0, s[4], "rectangular-product"),
         type_b("z", 0.0, s[5], "trapezoidal", beta=0.3)]
    c = list(rng.choice([-1.0, 1.0], 6) * rng.uniform(0.5, 2.0, 6))
    a = combined_coverage_factor(q, c)
    b = monte_carlo_coverage_factor(q, c, seed=seed)
    assert a == pytest.approx(b, rel=0.004), (a, b)


def test_correlated_normal_lines_combine_into_one_normal():
    """Two correlated normal lines beside an arcsine: the convolution takes them as one
    normal of variance cᵀVc; the Monte Carlo draws them jointly (JCGM 101 6.4.8)."""
    q = [from_u("a", 0.0, 0.6, type="B"), from_u("b", 0.0, 0.5, type="B"),
         type_b("P", 0.0, 1.5, "arcsine")]
    r = [[1.0, 0.7, 0.0], [0.7, 1.0, 0.0], [0.0, 0.0, 1.0]]
    a = combined_coverage_factor(q, [1.0, -1.0, 1.0], correlation=r)
    b = monte_carlo_coverage_factor(q, [1.0, -1.0, 1.0], seed=4, correlation=r)
    assert a == pytest.approx(b, rel=0.004)
