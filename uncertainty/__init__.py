"""uncertainty — a small, domain-free GUM engine.

Contents
========

Input quantities (:mod:`uncertainty.quantities`, :mod:`uncertainty.distributions`)
    :func:`type_b`            Type B from a half-width and a distribution (JCGM 100 4.3)
    :func:`type_a`            Type A from readings: mean, s or s/√n, ν = n − 1 (JCGM 100 4.2)
    :func:`from_u`            a quantity given by x, u(x), ν
    :func:`reliability_dof`   ν of a u judged reliable to Δu/u (JCGM 100 G.4.2, eq. G.3);
                              :data:`DOF_U_WITHIN_10PCT` = 50
    :data:`DISTRIBUTIONS`     the one name → distribution mapping (normal, rectangular,
                              triangular, arcsine, trapezoidal, rectangular-product,
                              rectangular-shifted-product)

Law of propagation (:mod:`uncertainty.propagation`)
    :func:`propagate`                 y, u_c, ν_eff, k, U → :class:`GumResult` (JCGM 100 5)
    :func:`sensitivity_coefficients`  symbolic (sympy) or central differences (callable)
    :func:`combined_uncertainty`      u_c² = cᵀVc, correlated inputs (JCGM 100 5.2.2)
    :func:`welch_satterthwaite`       ν_eff (JCGM 100 G.4.1)
    :func:`coverage_factor`           k = t_p(ν) (JCGM 100 G.3)
    (stating a result, U to two significant digits, is gonio's ``gonio.result.statement``)

Monte Carlo (:mod:`uncertainty.montecarlo`)
    :func:`monte_carlo`               propagation of distributions (JCGM 101 7)
    :func:`adaptive_monte_carlo`      adaptive number of trials (JCGM 101 7.9)
    :func:`coverage_interval`         symmetric (7.7) or shortest (7.8) interval
    :func:`numerical_tolerance`       δ from ndig digits (JCGM 101 7.9.2)
    :func:`quantile_numerical_u`      standard uncertainty of a Monte Carlo's quantiles from its
                                      finite number of draws (JCGM 101 7.9)
    :func:`validate_gum`              GUM vs MC, d_low, d_high ≤ δ (JCGM 101 8)

Coverage factor from the combined distribution (:mod:`uncertainty.combined`)
    :func:`needs_combined_k`          the rule: non-normal lines carry > 1/4 of u_c²
                                      (JCGM 101 5.7, JCGM 100 G.2.3)
    :func:`combined_coverage_factor`  k_p = U_p/u_c of an additive model's JCGM 101
                                      distribution (the convolution of its lines)
    :func:`non_normal_share`          the share of u_c² of the lines not normal or t

Budget tables (:mod:`uncertainty.table`)
    :func:`budget_table`              DataFrame: symbol … contribution, dof
    :func:`render_text`, :func:`render_markdown`, :func:`render_html`

This package never imports ``gonio``.

>>> import sympy
>>> x, y = sympy.symbols("x y")
>>> r = propagate(x + y, [type_b("x", 1.0, 0.3, "normal", k=1), type_b("y", 2.0, 0.4, "normal", k=1)])
>>> r.value, round(r.u_c, 12)
(3.0, 0.5)
"""

from uncertainty.combined import (combined_coverage_factor, needs_combined_k,
                                  non_normal_share)
from uncertainty.distributions import DISTRIBUTIONS, distribution
from uncertainty.montecarlo import (MonteCarloResult, ValidationResult, adaptive_monte_carlo,
                                    coverage_interval, monte_carlo, numerical_tolerance,
                                    quantile_numerical_u, sample_inputs, validate_gum)
from uncertainty.propagation import (Contribution, GumResult, coverage_factor,
                                     combined_uncertainty, compile_model, propagate,
                                     sensitivity_coefficients, welch_satterthwaite)
from uncertainty.quantities import (DOF_U_WITHIN_10PCT, InputQuantity, from_u, reliability_dof,
                                    type_a, type_b)
from uncertainty.table import (COLUMNS, budget_table, render_html, render_markdown,
                               render_text)

__all__ = [
    "DISTRIBUTIONS", "distribution", "InputQuantity", "type_a", "type_b", "from_u",
    "reliability_dof", "DOF_U_WITHIN_10PCT",
    "Contribution", "GumResult", "propagate", "sensitivity_coefficients", "combined_uncertainty",
    "welch_satterthwaite", "coverage_factor", "compile_model",
    "MonteCarloResult", "ValidationResult", "monte_carlo", "adaptive_monte_carlo",
    "coverage_interval", "numerical_tolerance", "quantile_numerical_u", "validate_gum", "sample_inputs",
    "combined_coverage_factor", "needs_combined_k", "non_normal_share",
    "COLUMNS", "budget_table", "render_text", "render_markdown", "render_html",
]
