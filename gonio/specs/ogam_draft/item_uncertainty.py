"""An uncertainty for every calibrated item (draft clause 8), built on :mod:`uncertainty`.

Clause 8 asks the certificate to give "each item, its result and the corresponding
measurement uncertainty"; the draft's Annex A budgets only E. This module gives a
budget to each of the seven items, one documented function each:

==============================  ======  ===================================================
:func:`scale_factor_budget`     K       Type A scatter of K_i, table angle errors at the 7.1
                                        positions (their worst linear combination within
                                        the MPE, rectangular), count quantisation (7.1)
:func:`nonlinearity_corrected_budget`  K_l  the range corrected for its bias by noise and tilt
                                        (JCGM 101 Monte Carlo of the K_i's errors; stated:
                                        the standard's value, u the larger of its table
                                        readings' errors about it)
:func:`nonlinearity_budget`     K_l     the draft's range as measured: u of the largest and
                                        smallest K_i, and the spread noise alone gives n values
                                        (7.2; kept beside the stated value)
:func:`zero_stability_budget`   B_s     the draft's s(M)/T (7.3): the one-sided χ² interval with
                                        the readings' ν_eff (stated alone, no k)
:func:`zero_stability_model_budget`  B_s  the expected B_s of the fitted noise model of the 7.3
                                        record (the physically founded estimate)
:func:`angle_deviation_budget`  E       the Annex A budget (draft, or physical) as an item budget
:func:`repeatability_budget`    R       the largest of m standard deviations stated by its belt
                                        united over every pattern of the σ_i: one-sided,
                                        the χ² limit of one s (7.5; stated alone, no k)
:func:`consistency_budget`      C_v/C_g the two extreme conditions' deviations with their
                                        correlations (7.6, 7.7)
==============================  ======  ===================================================

Every budget is a GUM evaluation (JCGM 100 5, :func:`uncertainty.propagate`) of an
additive or linear model; the coverage factor is t_95 of the Welch–Satterthwaite ν_eff
(JCGM 100 G.4), or — where lines that are not normal carry more than 1/4 of u_c² (K's
arcsine table line at the MPE bound) — the 95 % half-width of the budget's combined
distribution over u_c (JCGM 101; ``k_source`` "jcgm101-convolution"), unless the
laboratory fixes k (``k=``): one rule, :func:`budget_k`. :meth:`ItemUncertainty.to_dict`
is the ``results.json`` form ``<item>.uncertainty``. The JCGM 101 Monte Carlo check is
:func:`monte_carlo_check`.

Components the draft does not have are flagged ``beyond_draft`` with the clause they
come from.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Sequence

import numpy as np

from gonio.errors import GonioError
from gonio.result.statement import coverage_k, signed_text
from gonio.specs.ogam_draft import table_calibration as tcal
from gonio.specs.ogam_draft.table_periodic import (TABLE_ZERO_READINGS, TABLE_ZERO_STATED,
                                                   periodic_response, programme_bound,
                                                   table_worst_bound, worst_order)
from gonio.units import ARCSEC_PER_DEG, PPM, S_PER_H
from uncertainty import (GumResult, MonteCarloResult, combined_coverage_factor, from_u,
                         monte_carlo, needs_combined_k, propagate, type_b, validate_gum)
from uncertainty.propagation import LinearModel
from uncertainty.stdev import (correlated_stdev_dof, expected_range_factor,
                               random_walk_stdev_dof, stdev_u)

__all__ = [
    "Component", "ItemUncertainty", "COVERAGE_PROBABILITY", "COUNT_QUANTUM_U", "budget_k",
    "K_SOURCE_COMBINED", "COMBINED_SEED",
    "ScaleFactorTableLine", "scale_factor_table_line", "TableCorrection",
    "scale_factor_table_coefficients", "scale_factor_table_u_rel", "scale_factor_table_bound_rel",
    "scale_factor_table_correction", "table_corrected_k_sensitivity", "ChamberLine",
    "table_round_sensitivity", "calibration_error_draws", "calibration_draw_dof",
    "calibration_draws_text",
    "CalibratedTable",
    "nonlinearity_calibrated_budget", "consistency_corrected_budget",
    "chamber_temperature_line",
    "scale_factor_budget", "nonlinearity_budget", "nonlinearity_corrected_budget", "range_table_bound",
    "shifted_belt",
    "round_noise", "RoundNoise", "zero_stability_budget", "zero_stability_model_budget",
    "angle_deviation_budget", "repeatability_budget", "consistency_budget",
    "selection_corrected_budget", "monte_carlo_check", "monte_carlo_item", "ItemMonteCarlo",
]

#: Coverage probability of every stated U (JCGM 100 6.2.2, 95 %).
COVERAGE_PROBABILITY = 0.95
#: ``k_source`` of a k from the budget's combined distribution (:func:`budget_k`).
K_SOURCE_COMBINED = "jcgm101-convolution"
#: ``k_source`` of a range stated by its confidence belt's interval alone
#: (:func:`uncertainty.stdev.range_belt_interval`; K_l, C_v, C_g): no coverage factor.
K_SOURCE_BELT = "neyman-belt"
#: Seed of that distribution's Monte Carlo (fixed: the same budget gives the same k).
COMBINED_SEED = 20261129
#: u of a pulse count C = floor(N(t_r)) − floor(N(t_z)): two floored readings, triangular
#: of half-width 1 count (JCGM 100 4.3.9), u = 1/√6 counts.
COUNT_QUANTUM_U = 1.0 / math.sqrt(6.0)


@dataclass(frozen=True)
class Component:
    """One line of an item's budget (``results.json``: ``<item>.uncertainty.components``)."""

    name: str
    symbol: str
    u: float                 # standard uncertainty of the item due to this input, item's unit
    unit: str
    type: str                # "A" or "B"
    distribution: str
    dof: float
    source: str
    beyond_draft: bool = False
    clause: str = ""

    def to_dict(self) -> dict:
        return {"name": self.name, "symbol": self.symbol, "u": float(self.u),
                "unit": self.unit, "type": self.type, "distribution": self.distribution,
                "dof": None if math.isinf(self.dof) else float(self.dof),
                "source": self.source, "beyond_draft": bool(self.beyond_draft),
                "clause": self.clause}


@dataclass(frozen=True)
class ItemUncertainty:
    """The uncertainty of one item: components, u_c, ν_eff, k, U (and an interval for σ's)."""

    item: str
    unit: str
    value: float
    components: tuple[Component, ...]
    u_c: float
    nu_eff: float
    k: float
    k_source: str
    interval: tuple[float, float] | None = None
    gum: GumResult | None = field(default=None, repr=False, compare=False)
    model: object = field(default=None, repr=False, compare=False)
    inputs: tuple = field(default=(), repr=False, compare=False)
    correlation: object = field(default=None, repr=False, compare=False)
    #: JCGM 101 draws of the measurand when its model is not the additive one of
    #: ``model`` (B_s: the χ² relation, the noise model's square root): f(rng, M) → array.
    sampler: object = field(default=None, repr=False, compare=False)
    model_kind: str = "linear"
    #: A quantity that cannot be negative (B_s, R, the ranges K_l, C_v, C_g): results.json
    #: marks the item
    #: ``nonnegative`` (its statement is then never an interval reaching below zero).
    nonnegative: bool = False
    #: The item is stated by ``interval`` alone (a dispersion: the one-sided χ² interval
    #: [0, upper limit], :func:`chi_square_statement`): no coverage factor exists for it, so
    #: results.json has ``k`` null, ``U`` the distance from the value to the upper limit
    #: (the guard band of a decision against an upper tolerance) and ``k_source``
    #: "chi-square"; ``k`` here stays the GUM's t-factor of the budget (JCGM 101 validation).
    stated_by_interval: bool = False
    #: Another reading of the same item kept beside the stated one (K_l: the draft's range as
    #: measured, :func:`nonlinearity_budget`, beside the bias-corrected range; C_v likewise).
    beside: object = field(default=None, repr=False, compare=False)
    #: The measured correction the value carries (K: the tilt estimate's
    #: :class:`gonio.specs.ogam_draft.budget_extra.TiltCorrection`), or None.
    correction: object = field(default=None, repr=False, compare=False)
    #: A range's measured value in the item's unit, the input its bias-corrected value is
    #: built from (K_l, C_v, C_g: the range of the readings as corrected for the stated
    #: reading — table and measured tilt where they apply), or None.
    measured: float | None = field(default=None, repr=False, compare=False)
    #: The standard uncertainty of ``interval``'s ends from the finite number of the
    #: Monte Carlo's draws (JCGM 101 7.9; the range belts of K_l, C_v, C_g:
    #: :func:`uncertainty.stdev.range_belt_numerical_u`), or None: the statement rule prints
    #: no digit of the ends a rerun of the draws would change.
    interval_numerical_u: float | None = None
    #: How many draws ``interval``'s ends come from (JCGM 101 7.2's M), or None.
    interval_draws: int | None = None

    @property
    def U(self) -> float:
        if self.stated_by_interval:
            return float(self.interval[1]) - self.value
        return self.k * self.u_c

    def to_dict(self) -> dict:
        """The ``results.json`` form (see the module docstring)."""
        by_iv = self.stated_by_interval
        d = {"components": [c.to_dict() for c in self.components],
             "u_c": float(self.u_c), "U": float(self.U),
             "k": None if by_iv else float(self.k),
             # ν_eff only where k is its t-factor (a k of the combined distribution has none)
             "nu_eff": None if (not math.isfinite(self.nu_eff)
                                or self.k_source == K_SOURCE_COMBINED) else float(self.nu_eff),
             "coverage_probability": COVERAGE_PROBABILITY, "unit": self.unit,
             "k_source": (self.k_source if self.k_source == K_SOURCE_BELT else "chi-square")
             if by_iv else self.k_source}
        if self.interval is not None:
            d["interval"] = [float(self.interval[0]), float(self.interval[1])]
        if self.nonnegative:
            d["nonnegative"] = True
        if self.interval_numerical_u is not None:
            d["interval_numerical_u"] = float(self.interval_numerical_u)
        if self.interval_draws is not None:
            d["interval_draws"] = int(self.interval_draws)
        return d


@dataclass(frozen=True)
class _Line:
    """An input of an additive model: its quantity and the reporting fields."""

    q: object               # uncertainty.InputQuantity, in the item's unit
    name: str
    beyond_draft: bool = False
    clause: str = ""


def budget_k(nu_eff: float, k: float | None, inputs: Sequence = (), coeffs: Sequence = (),
             correlation=None) -> tuple[float, str]:
    """The coverage factor of an additive item budget and where it comes from (its
    ``k_source``), one rule for every item:

    - ``k`` given: fixed by the laboratory (``"fixed by laboratory"``);
    - the budget's lines that are not normal (rectangular, triangular, arcsine, products)
      carry more than 1/4 of u_c² (:func:`uncertainty.needs_combined_k`, JCGM 101 5.7,
      JCGM 100 G.2.3): k = U_p/u_c of the budget's combined distribution — the convolution
      of its lines, each in its own distribution, the Type A lines as scaled-and-shifted t
      with their ν — computed numerically (JCGM 101 5.4), or by a JCGM 101 Monte Carlo of
      fixed M and seed where a line has no closed-form distribution function
      (:func:`uncertainty.combined_coverage_factor`; ``"jcgm101-convolution"``). K's table
      line at the MPE bound is such a line (arcsine, :func:`scale_factor_table_line`);
    - otherwise t_95 of the Welch–Satterthwaite ν_eff as stated (JCGM 100 G.4: its integer
      part, ∞ above 1000; NaN, WS not valid: the normal's; ``"welch-satterthwaite"``).

    >>> from uncertainty import type_b, from_u
    >>> k, src = budget_k(5.0, None, [from_u("s", 0.0, 1.0, dof=5)], [1.0])
    >>> round(k, 3), src
    (2.571, 'welch-satterthwaite')
    >>> k, src = budget_k(math.inf, None, [type_b("P", 0.0, 1.0, "arcsine")], [1.0])
    >>> round(k, 2), src
    (1.41, 'jcgm101-convolution')
    """
    if k is not None:
        return float(k), "fixed by laboratory"
    if inputs and needs_combined_k(inputs, coeffs, correlation):
        return (combined_coverage_factor(inputs, coeffs, p=COVERAGE_PROBABILITY,
                                         seed=COMBINED_SEED, correlation=correlation),
                K_SOURCE_COMBINED)
    return coverage_k(nu_eff, COVERAGE_PROBABILITY), "welch-satterthwaite"


def _budget(item: str, unit: str, value: float, lines: Sequence[_Line], *,
            k: float | None = None, correlation=None, coeffs: Sequence[float] | None = None,
            interval=None) -> ItemUncertainty:
    """y = value + Σ c_i X_i (X_i estimates 0), by the law of propagation (JCGM 100 5)."""
    cs = [1.0] * len(lines) if coeffs is None else list(coeffs)
    # additive: the coefficients are the sensitivities, no SymPy needed (a coverage study's
    # workers never import it); LinearModel.to_sympy() is the same model as an expression
    model = LinearModel(float(value), tuple(float(c) for c in cs),
                        tuple(ln.q.symbol for ln in lines))
    gum = propagate(model, [ln.q for ln in lines], correlation=correlation, k=2.0)
    kk, src = budget_k(gum.dof, k, [ln.q for ln in lines], cs, correlation)
    comps = tuple(Component(name=ln.name, symbol=ln.q.symbol, u=float(c.contribution),
                            unit=unit, type=ln.q.type, distribution=ln.q.distribution,
                            dof=float(ln.q.dof), source=ln.q.source,
                            beyond_draft=ln.beyond_draft, clause=ln.clause)
                  for ln, c in zip(lines, gum.contributions))
    return ItemUncertainty(item=item, unit=unit, value=float(value), components=comps,
                           u_c=float(gum.u_c), nu_eff=float(gum.dof), k=kk, k_source=src,
                           interval=interval, gum=gum, model=model,
                           inputs=tuple(ln.q for ln in lines), correlation=correlation)


def _expr(model):
    """The model for JCGM 101 sampling: an additive budget's model as the sympy expression it
    always was (the same Monte Carlo numbers), any other model as it is."""
    return model.to_sympy() if isinstance(model, LinearModel) else model


def monte_carlo_check(b: ItemUncertainty, trials: int = 200_000, seed: int = 0):
    """JCGM 101 propagation of the same inputs and its GUM validation (JCGM 101 8).

    Returns ``(MonteCarloResult, ValidationResult)``.

    With a Type A scatter of ν = 5 dominating, the Monte Carlo draws a scaled t₅, whose
    standard deviation is √(5/3) = 1.29 times u (JCGM 101 6.4.9.7), while both 95 %
    intervals are ≈ ±t_95(5)·u = ±2.57 u:

    >>> b = scale_factor_budget([3600.1, 3600.3, 3600.2, 3600.2, 3600.1, 3600.3],
    ...                         [60, 120, 180, 240, 300, 360], 0.1)
    >>> mc, v = monte_carlo_check(b, 200_000)
    >>> round(mc.u / b.u_c, 1), round((mc.high - mc.value) / b.u_c, 1), round(b.k, 2)
    (1.3, 2.6, 2.57)
    """
    mc = monte_carlo(_expr(b.model), list(b.inputs), int(trials), seed=seed,
                     correlation=b.correlation)
    return mc, validate_gum(b.gum, mc, ndig=1)


@dataclass(frozen=True)
class ItemMonteCarlo:
    """JCGM 101 propagation of one item's model and the GUM's validation against it (8.2)."""

    item: str
    model_kind: str          # "linear" (the additive budget) or "nonlinear"
    trials: int
    mc_value: float
    mc_u: float
    mc_interval: tuple[float, float]
    gum_interval: tuple[float, float]
    d_low: float
    d_high: float
    delta: float
    ndig: int
    passed: bool

    def to_dict(self) -> dict:
        return {"item": self.item, "model": self.model_kind, "trials": int(self.trials),
                "mc_value": float(self.mc_value), "mc_u": float(self.mc_u),
                "mc_interval": [float(x) for x in self.mc_interval],
                "gum_interval": [float(x) for x in self.gum_interval],
                "d_low": float(self.d_low), "d_high": float(self.d_high),
                "delta": float(self.delta), "ndig": int(self.ndig), "passed": bool(self.passed),
                "gum_contains_mc": bool(self.gum_interval[0] <= self.mc_interval[0]
                                        and self.mc_interval[1] <= self.gum_interval[1])}


def monte_carlo_item(b: ItemUncertainty, trials: int = 200_000, seed: int = 0,
                     ndig: int = 2) -> ItemMonteCarlo:
    """JCGM 101 Monte Carlo of item budget ``b`` (fixed M = ``trials``, 7.2) and the
    numerical tolerance test of its GUM interval against it (JCGM 101 8.2, 8.1.3: δ is half
    a unit of the ``ndig``-th significant digit of u_c).

    The additive budgets draw their own inputs (Type A lines as scaled-and-shifted t
    with their ν, JCGM 101 6.4.9; rectangular and triangular Type B lines as stated;
    correlated lines jointly, 6.4.8). B_s draws its measurand through its own model
    (``b.sampler``): for the draft's s(M)/T the χ² relation σ = s·√(ν/χ²_ν), whose
    95 % interval is the χ² interval; for the noise model's estimate the square root of
    the readings' expected variance with normal fitted coefficients.

    Examples
    --------
    A linear model with one dominant normal line: the MC u equals the GUM u_c (the
    closed form √Σc²u²) and the test passes:

    >>> b = repeatability_budget(0.096, 10, 12)
    >>> r = monte_carlo_item(b, 200_000)
    >>> r.passed, round(r.mc_u / b.u_c / math.sqrt(9 / 7), 2)
    (True, 1.0)

    The draft's B_s from a random walk's readings (ν = 2.45): the GUM's symmetric
    s ± t_95(ν)·u is not the skewed χ² distribution of σ, and the test fails — which is why
    the χ² interval is stated:

    >>> r = monte_carlo_item(zero_stability_budget(0.002, 15), 200_000)
    >>> r.passed, r.model_kind
    (False, 'nonlinear')
    """
    if b.gum is None:
        raise ValueError(f"{b.item}: no GUM result to validate")
    rng = np.random.default_rng(seed)
    if b.sampler is not None:
        y = np.asarray(b.sampler(rng, int(trials)), dtype=float)
        lo, hi = np.quantile(y, [(1 - COVERAGE_PROBABILITY) / 2, (1 + COVERAGE_PROBABILITY) / 2])
        mv, mu, mlo, mhi = float(np.mean(y)), float(np.std(y, ddof=1)), float(lo), float(hi)
        mc = MonteCarloResult(value=mv, u=mu, low=mlo, high=mhi, p=COVERAGE_PROBABILITY,
                              trials=int(trials), shortest=False)
    else:
        mc = monte_carlo(_expr(b.model), list(b.inputs), int(trials), rng=rng,
                         correlation=b.correlation)
    v = validate_gum(b.gum, mc, ndig=ndig)
    return ItemMonteCarlo(item=b.item, model_kind=b.model_kind, trials=int(trials),
                          mc_value=float(mc.value), mc_u=float(mc.u),
                          mc_interval=(float(mc.low), float(mc.high)),
                          gum_interval=tuple(float(x) for x in v.gum_interval),
                          d_low=float(v.d_low), d_high=float(v.d_high), delta=float(v.delta),
                          ndig=int(ndig), passed=bool(v.passed))


# --------------------------------------------------------------------------- 7.1, 7.2

def _single_round_u(k_i: np.ndarray, theta_deg: np.ndarray, table_mpe_arcsec: float):
    """u(K_i) of one round from the table (rectangular MPE) and the count quantum, counts/°."""
    th_arcsec = np.abs(theta_deg) * ARCSEC_PER_DEG
    u_tab = np.abs(k_i) * (table_mpe_arcsec / math.sqrt(3.0)) / th_arcsec
    u_q = COUNT_QUANTUM_U / np.abs(theta_deg)
    return u_tab, u_q


@dataclass(frozen=True)
class ScaleFactorTableLine:
    """K's table line at the 7.1 stops, relative to K, in its two readings
    (:func:`scale_factor_table_line`): the standard's (independent stops) and the one
    periodic error at the worst order beside it, and which one is certified."""

    u_rel_standard: float            # A.4.1 read per stop: MPE/√3 each, independent
    u_rel_harmonic: float            # one periodic error at the bound, worst order (arcsine)
    half_width_rel_harmonic: float   # its half-width: MPE·|Σ (e^{ihθ_k} − 1)/θ_k|/n
    order: int                       # that worst order h
    certified: str                   # "harmonic" or "standard": the larger u

    @property
    def u_rel(self) -> float:
        return max(self.u_rel_standard, self.u_rel_harmonic)


def scale_factor_table_line(theta_deg, table_mpe_arcsec: float,
                            max_order: int = 360) -> ScaleFactorTableLine:
    """u(K)/K from the table's angle errors at the 7.1 stops, two readings side by side.

    K = mean C_k/θ_k (7.1); the table turns from its zero to θ_k with error P(θ_k) − P(0)
    (A.4.1), so δK/K = (1/n) Σ (P(θ_k) − P(0))/θ_k (θ in arcseconds, signed).

    - The standard's reading (A.4.1 applied to 7.1): each stop's error independent,
      rectangular ±MPE: u = (MPE/√3)·√(Σ 1/θ_k²)/n (P(0) taken as part of each stop's error).
    - Beside it, the physical model: the table's error is one periodic curve, so the stops'
      errors are correlated and a low order does not average out. One periodic error
      P(x) = a·sin(h·x + φ) at the A.4.1 bound (a = MPE) of unknown order h (1 …
      ``max_order``), phase φ uniform: δK/K = a·Im(e^{iφ} Σ (e^{ihθ_k} − 1)/θ_k)/n, arcsine
      with half-width A = MPE·|Σ (e^{ihθ_k} − 1)/θ_k|/n at the worst order h, u = A/√2
      (JCGM 101 6.4.6). A curve Σ a_h sin(h x + φ_h) with Σ|a_h| ≤ MPE moves K by at most
      that A, so the line holds whatever the table's shape within its MPE. The search over
      orders is :mod:`gonio.specs.ogam_draft.table_periodic`'s (shared with K_l and E).

    The certified line is the larger u of the two (``certified``). With the draft's stops
    60°…360° and MPE 0.1″ the worst order is 3 and the harmonic reading is 3.1 times the
    standard's (the 360° stop carries no table error, P(360°) = P(0)):

    >>> t = scale_factor_table_line([60, 120, 180, 240, 300, 360], 0.1)
    >>> t.order, t.certified, round(t.u_rel_harmonic / t.u_rel_standard, 2)
    (3, 'harmonic', 3.08)
    >>> round(t.half_width_rel_harmonic / PPM, 4)     # 0.1″·(0.05111/3600)/6
    0.2366
    """
    th = np.asarray(theta_deg, dtype=float) * ARCSEC_PER_DEG
    n = th.size
    mpe = float(table_mpe_arcsec)
    u_std = (mpe / math.sqrt(3.0)) * float(np.sqrt(np.sum(1.0 / th ** 2))) / n
    g = np.abs((periodic_response(th / ARCSEC_PER_DEG, max_order) - 1.0) @ (1.0 / th))
    order = worst_order(g)
    hw = mpe * float(g[order - 1]) / n
    u_h = hw / math.sqrt(2.0)
    return ScaleFactorTableLine(u_std, u_h, hw, order,
                                "harmonic" if u_h > u_std else "standard")


def scale_factor_table_coefficients(theta_deg, stop_deg=None, zero_deg=None) -> dict:
    """K's relative sensitivity to the table's positioning error at each distinct position
    the 7.1 rounds reach (° mod 360, rounded to 1e-6°): {position: c}, δK/K = Σ c_p e(p),
    e in arcseconds (A.4.1 applied to 7.1).

    Round i is zeroed at z_i and stopped at s_i = z_i + θ_i (``stop_deg``, ``zero_deg``;
    None: every round zeroed at 0° and stopped at θ_i, the draft's 7.1); the table turns
    θ_i with the error e(s_i) − e(z_i), so K_i moves by (e(s_i) − e(z_i))/θ_i (θ in
    arcseconds, signed) relative and K = mean K_i by (1/n) Σ_i of that (7.1). A position
    reached by several rounds has one error, so its coefficients add: the common zero
    carries −(1/n) Σ 1/θ_i, and the 360° stop is the zero itself (e(360°) = e(0°): its two
    terms cancel). The same positions and rule as E's
    (:func:`gonio.specs.ogam_draft.budget_extra.table_error_coefficients`, whose K part is
    −θ times these) and as a calibrated table's correction (:func:`table_round_sensitivity`).

    >>> c = scale_factor_table_coefficients([60, 120, 180, 240, 300, 360])
    >>> sorted(c), round(c[0.0] * 6 * 216000, 4), round(c[60.0] * 6 * 216000, 4)
    ([0.0, 60.0, 120.0, 180.0, 240.0, 300.0], -2.2833, 1.0)
    """
    th = np.asarray(theta_deg, dtype=float)
    stop = th if stop_deg is None else np.asarray(stop_deg, dtype=float)
    zero = np.zeros_like(th) if zero_deg is None else np.asarray(zero_deg, dtype=float)
    n = th.size
    out: dict = {}

    def add(pos: float, c: float) -> None:
        key = tcal.position_key(pos)
        out[key] = out.get(key, 0.0) + c

    for t, s, z in zip(th, stop, zero):
        c = 1.0 / (n * float(t) * ARCSEC_PER_DEG)
        add(float(s), c)
        add(float(z), -c)
    return {p: c for p, c in sorted(out.items()) if abs(c) > 1e-18}


def scale_factor_table_u_rel(theta_deg, table_mpe_arcsec: float, stop_deg=None,
                             zero_deg=None) -> float:
    """u(K)/K from the table's positioning errors at the 7.1 positions known only by the
    MPE (A.4.1): each position's error rectangular ±MPE (JCGM 100 4.3.7), independent of
    the other positions', the common zero's shared by every round
    (:func:`scale_factor_table_coefficients`): u = (MPE/√3)·√(Σ c_p²) (JCGM 100 5.1.2).

    The draft's stops, MPE 0.1″: (0.1/√3)·√(Σ 1/θ_k² + (Σ 1/θ_k)²)/6 over θ_k = 60°…300°
    (the 360° stop is the zero), 0.05774·√(1.4636 + 5.2136)/(6·216000) = 0.1151 ppm:

    >>> round(scale_factor_table_u_rel([60, 120, 180, 240, 300, 360], 0.1) / PPM, 4)
    0.1151
    """
    c = np.array(list(scale_factor_table_coefficients(theta_deg, stop_deg, zero_deg).values()))
    return float(table_mpe_arcsec) / math.sqrt(3.0) * float(np.sqrt(np.sum(c * c)))


def scale_factor_table_bound_rel(theta_deg, table_mpe_arcsec: float, stop_deg=None,
                                 zero_deg=None, reading: str = TABLE_ZERO_STATED) -> float:
    """The largest |δK/K| the table's positioning errors can give when each position the 7.1
    rounds reach is known only to err within ±MPE (A.4.1) and nothing is known of how the
    positions' errors go together (one table's errors are one curve, correlated):
    δK/K = Σ c_p e(p) (:func:`scale_factor_table_coefficients`) is largest with every e(p)
    at ±MPE by the sign of c_p, MPE·Σ|c_p| (the zero at −MPE, every stop at +MPE, or the
    reverse). K's table line ``P_K`` is rectangular within it (JCGM 100 4.3.7: a quantity
    known by its bounds; F.2.4.4: the bounds of a correlated sum taken as one quantity's).

    The draft's stops, MPE 0.1″: 0.1·2·(Σ_{60°…300°} 1/θ_k)/6, 0.1·2·2.2833/(6·216000):

    >>> round(scale_factor_table_bound_rel([60, 120, 180, 240, 300, 360], 0.1) / PPM, 4)
    0.3524

    That is the physical reading of the MPE at the common zero (every position within ±MPE,
    the zero included); the draft's (A.4.1: the angle from the zero within ±MPE, the zero's
    own error 0) is ``reading="draft"``, half of it here (:func:`~gonio.specs.ogam_draft.
    table_periodic.table_worst_bound`, the one function of that ambiguity):

    >>> round(scale_factor_table_bound_rel([60, 120, 180, 240, 300, 360], 0.1,
    ...                                    reading="draft") / PPM, 4)
    0.1762
    """
    return table_worst_bound(scale_factor_table_coefficients(theta_deg, stop_deg, zero_deg),
                             table_mpe_arcsec, reading)


def _rounds(k_i, theta_deg, table_mpe_arcsec: float):
    """The 7.1 rounds as K_l's budgets take them (draft 7.2): (K_i, θ_k, n, mean K_i, u_tab,
    u_q) with the single rounds' table and count-quantum u (:func:`_single_round_u`);
    fewer than two rounds have no range (ValueError)."""
    k_i = np.asarray(k_i, dtype=float)
    th = np.asarray(theta_deg, dtype=float)
    if k_i.size < 2:
        raise ValueError("K_l needs at least two rounds")
    u_tab, u_q = _single_round_u(k_i, th, table_mpe_arcsec)
    return k_i, th, int(k_i.size), float(np.mean(k_i)), u_tab, u_q


@dataclass(frozen=True)
class ChamberLine:
    """K's chamber-temperature line ``K_T`` (relative to K): its half-width, distribution
    (with its shape ``beta`` for ``rectangular-shifted-product``) and u, which reading gave
    it and the thermometer's MPE it took (:func:`chamber_temperature_line`)."""

    half_width_rel: float
    distribution: str
    u_rel: float
    basis: str                 # "logged" or "tolerance"
    deviation_c: float | None  # the logged ΔT, °C (None: not logged)
    beta: float | None = None
    thermometer_mpe_c: float | None = None

    def to_dict(self) -> dict:
        return {"basis": self.basis, "deviation_c": self.deviation_c,
                "thermometer_mpe_c": self.thermometer_mpe_c,
                "half_width_ppm": self.half_width_rel / PPM, "distribution": self.distribution,
                "u_ppm": self.u_rel / PPM}


def chamber_temperature_line(coeff_bound_ppm_per_c: float, tolerance_c: float,
                             deviation_c: float | None = None,
                             thermometer_mpe_c: float = 0.0) -> ChamberLine:
    """K's chamber line ``K_T``: the relative change α_K ΔT of K between the chamber's
    temperature and the reference at which K is stated (draft Table 2), with α_K known only
    by its bound |α_K| ≤ α_max (``coeff_bound_ppm_per_c``), uniform within it.

    The draft allows ΔT within ± ``tolerance_c`` and says nothing about its effect on K; two
    readings (docs/draft-readings.md, "Table 2, environment"):

    - ``deviation_c`` given (the readings log the chamber's temperature; ΔT = logged minus the
      protocol's reference): the true deviation is ΔT + δ, δ the thermometer's error,
      rectangular within ± ``thermometer_mpe_c`` (m), independent of α_K. The line is
      α_K (ΔT + δ), the product of a zero-mean rectangular and a rectangular on
      [ΔT − m, ΔT + m]: mean 0 and u² = (α_max²/3)(ΔT² + m²/3) exactly (JCGM 100 5.1.2
      NOTE; with x₁ = α_K's estimate 0 only the terms in u²(x₁) remain), distribution
      ``rectangular-shifted-product`` with half-width α_max (|ΔT| + m) and β = m/(|ΔT| + m)
      (its Monte Carlo draws the product, JCGM 101). A logged ΔT of 0 leaves the
      thermometer's part, α_max·m/3 (β = 1, the ``rectangular-product``); m = 0 (a
      thermometer taken as exact) is the rectangular of half-width α_max|ΔT|, none at ΔT = 0;
    - not logged: ΔT is itself uniform within ± the tolerance, independent of α_K, and the
      product of the two zero-mean rectangulars has u = α_max·ΔT_max/3 (JCGM 100 5.1.2 NOTE:
      u²(x₁x₂) = u²(x₁)u²(x₂) when both estimates are zero; distribution
      ``rectangular-product``, whose Monte Carlo draws the product). Taking α_K ΔT as one
      rectangular of half-width α_max·ΔT_max instead (u = α_max·ΔT_max/√3) overstates u by
      √3 (a FOG's K: z spread 0.60 where 1 is right).

    >>> [round(x, 4) for x in (chamber_temperature_line(1.0, 1.0).u_rel / PPM,
    ...  chamber_temperature_line(1.0, 1.0, -0.6).u_rel / PPM,
    ...  chamber_temperature_line(1.0, 1.0, -0.6, 0.2).u_rel / PPM,
    ...  chamber_temperature_line(1.0, 1.0, 0.0, 0.2).u_rel / PPM)]
    [0.3333, 0.3464, 0.3528, 0.0667]
    >>> chamber_temperature_line(0.1, 1.0, 0.0).half_width_rel
    0.0
    """
    a = float(coeff_bound_ppm_per_c) * PPM
    if deviation_c is not None:
        dev, m = abs(float(deviation_c)), float(thermometer_mpe_c)
        hw = a * (dev + m)
        if m == 0.0:
            return ChamberLine(hw, "rectangular", hw / math.sqrt(3.0), "logged",
                               float(deviation_c), None, 0.0)
        u = a * math.sqrt((dev * dev + m * m / 3.0) / 3.0)
        if dev == 0.0:                     # β = 1: the product of two zero-mean rectangulars
            return ChamberLine(hw, "rectangular-product", u, "logged", 0.0, None, m)
        return ChamberLine(hw, "rectangular-shifted-product", u, "logged", float(deviation_c),
                           m / (dev + m), m)
    hw = a * float(tolerance_c)
    return ChamberLine(hw, "rectangular-product", hw / 3.0, "tolerance", None)


@dataclass(frozen=True)
class TableCorrection:
    """K's 7.1 rounds corrected by a calibrated table (:func:`scale_factor_table_correction`):
    the corrected K_i (counts/°), u(K) of the calibration's uncertainty through the
    correction (counts/°), its ν, and the line's source."""

    k_i_counts_per_deg: np.ndarray
    u_counts_per_deg: float
    dof: float
    source: str


def _refuse_blind(calibration, c) -> None:
    """Refuse a calibration that cannot see table errors K's correction is sensitive to.

    An equal-division comparison with fewer starts n than positions m has the table's
    harmonics of orders that are multiples of n removed and no uncertainty for them (IEC
    62047-20 A.3; :func:`gonio.specs.ogam_draft.table_calibration.from_equal_division`): where
    K's sensitivity c over the positions has a component in that subspace, the corrected K
    would keep those harmonics' error with no line for it. Raises :class:`GonioError` naming
    the orders K sees."""
    basis = getattr(calibration, "blind_basis", None)
    if basis is None or not np.any(c):
        return
    scale = float(np.linalg.norm(c))
    if float(np.linalg.norm(np.asarray(basis).T @ c)) <= 1e-9 * scale:
        return
    x = np.deg2rad(calibration.table_deg)
    seen = [h for h in calibration.blind_orders
            if abs(complex(np.exp(1j * h * x) @ c)) > 1e-9 * scale * math.sqrt(x.size)]
    orders = ", ".join(str(h) for h in (seen or calibration.blind_orders))
    raise GonioError(f"the {calibration.source} cannot see the table's harmonics of order "
                     f"{orders} (its starts cover fewer positions than it lists) and K's stops "
                     f"see them: K cannot be corrected by it (an equal-division comparison "
                     f"with a start at every position can, or keep the MPE line)",
                     key="table_calibration")


def table_round_sensitivity(k_i, theta_deg, stop_deg, zero_deg, calibration
                            ) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray,
                                       list[float]]:
    """K's 7.1 rounds corrected by a calibrated table (7.1 with A.4.1's error known; beyond
    the draft): (the corrected K_i, counts/°; each round's sensitivity to the calibration's
    error at each of its positions, an (n rounds × positions) matrix, counts/° per arcsec; the
    calibration's indices of the rounds' stops and zeroing positions; the positions it does not
    list, sorted). The first two are None where a stop or zero is not listed.

    Round i zeroed the table at ``zero_deg`` and stopped it at ``stop_deg`` (absolute
    positions, as :func:`gonio.specs.ogam_draft.calibration.round_positions` gives them) and
    the table read θ_i (``theta_deg``). Its correction Δe_i = e(s_i) − e(z_i) is the one every
    item takes (:func:`gonio.specs.ogam_draft.table_calibration.turned_error_arcsec`, with E's
    and C_v's, C_g's): K's rule is not different: its zero is the round's start as theirs is
    (the series' first start where the item does not re-zero), stops are looked up by absolute
    position modulo 360°, and a full round 0° → 360° reads e(0°) − e(0°) = 0, as a round from
    a position to itself does. What is K's own is only what follows from Δe_i:
    K_i,c = K_i θ_i/(θ_i − Δe_i/3600) and ∂K_i,c/∂e(s_i) = −∂K_i,c/∂e(z_i) =
    K_i,c/(3600 θ_i − Δe_i) (none where s_i and z_i are one position).

    >>> from gonio.specs.ogam_draft.table_calibration import TableCalibration
    >>> cal = TableCalibration([0, 60, 120], [0.0, 0.36, -0.18], [0.02] * 3, "t")
    >>> k_c, s, idx, miss = table_round_sensitivity([3600.0] * 2, [60.0, 360.0], [60.0, 360.0],
    ...                                             [0.0, 0.0], cal)
    >>> [round(float(x), 6) for x in k_c], idx.tolist(), miss     # 3600·60/(60 − 0.0001)
    ([3600.006, 3600.0], [1, 0, 0, 0], [])
    >>> s[1].tolist(), table_round_sensitivity([3600.0], [45.0], [45.0], [0.0], cal)[::3]
    ([0.0, 0.0, 0.0], (None, [45.0]))
    """
    k_i = np.asarray(k_i, dtype=float)
    th = np.asarray(theta_deg, dtype=float)
    delta, i_s, i_z, missing = tcal.turned_error_arcsec(calibration, stop_deg, zero_deg)
    idx = np.r_[i_s, i_z]
    if missing:
        return None, None, idx, missing
    th_true = th - delta / ARCSEC_PER_DEG
    k_c = k_i * th / th_true
    sens = k_c / (ARCSEC_PER_DEG * th_true)                  # ∂K_i/∂Δe_i, counts/° per arcsec
    s = np.zeros((k_i.size, calibration.table_deg.size))
    rows = np.arange(k_i.size)
    np.add.at(s, (rows, i_s), sens)
    np.add.at(s, (rows, i_z), -sens)
    return k_c, s, idx, []


def table_corrected_k_sensitivity(k_i, theta_deg, stop_deg, zero_deg, calibration
                                  ) -> tuple[np.ndarray | None, np.ndarray | None, list[float]]:
    """(the corrected K_i, counts/°; K's sensitivity to the calibration's error at each of its
    positions, counts/° per arcsec; the positions the calibration does not list) for the 7.1
    rounds zeroed at ``zero_deg`` and stopped at ``stop_deg`` (absolute positions;
    :func:`scale_factor_table_correction`, 7.1): K = mean K_i, so its sensitivity is the mean
    of the rounds' (:func:`table_round_sensitivity`); None, None where a position is not
    listed."""
    k_c, s, _, missing = table_round_sensitivity(k_i, theta_deg, stop_deg, zero_deg,
                                                 calibration)
    return k_c, (None if s is None else s.mean(axis=0)), missing


def calibration_error_draws(calibration, rng, draws: int) -> np.ndarray:
    """Draws of the calibration's errors about its stated values, (draws × positions), arcsec:
    the one distribution every Monte Carlo of a calibrated table draws from (K_l's, C_v's and
    C_g's range and the choice of C_v's and C_g's extremes). It honours the calibration's
    degrees of freedom as the GUM lines of K and E do (:meth:`TableCalibration.combine`):

    - no ``dof`` (ν = ∞): normal with the covariance V (JCGM 101 6.4.8; V = Q Λ Qᵀ,
      δe = Q √Λ z, so a singular V, an equal-division comparison's gauge, draws within its
      range);
    - a covariance given (one joint estimate, V = s²·M with one s² of ν degrees of freedom,
      :func:`~gonio.specs.ogam_draft.table_calibration.from_equal_division`): the
      multivariate t of that V and ν, δe = Q √Λ z · √(ν/w), one w ~ χ²_ν per draw shared by
      every position (JCGM 101 6.4.9 for a vector: the joint scale s²/σ² is one χ²_ν/ν;
      JCGM 102's multivariate t). Positions with different ν under one covariance: the
      smallest (conservative, as ``combine``);
    - positions independent (no covariance), position p with its own ν_p: each drawn as its
      own scaled-and-shifted t, u_p · t_p (JCGM 101 6.4.9), t_p ~ t_{ν_p} drawn from the
      same z_p as the normal draws by its quantile (:func:`_t_of_normal`), so every position's
      |δe| rises draw by draw as ν falls: independent positions, each its own χ² in effect
      (a certificate's one pooled s is not modelled apart: docs/formats.md, "Table
      calibration").

    The scale is u (the Type A standard uncertainty), so the draws' variance is
    ν/(ν − 2)·u². ν ≥ 3 only (:func:`~gonio.specs.ogam_draft.table_calibration.
    draw_dof_refusal`: ν ≤ 2 has no variance, and the Monte Carlos' means and spreads would be
    noise). The z are drawn from ``rng`` exactly as for the normal draws (same seed, same
    draws) and a covariance's one χ² from a child stream (:func:`_chi2_stream`), so ``rng``
    continues the same whatever ν (common random numbers). The draws are centred: δe about e.

    Two independent positions, u = 0.02″ with ν = 4 and u = 0.03″ with ν = ∞: the first's
    sd is 0.02·√2 (ν/(ν − 2) = 2), the second's 0.03:

    >>> from gonio.specs.ogam_draft.table_calibration import TableCalibration
    >>> cal = TableCalibration([0, 60], [0.0, 0.0], [0.02, 0.03], "t", dof=[4, math.inf])
    >>> d = calibration_error_draws(cal, np.random.default_rng(1), 400_000)
    >>> [round(float(x), 3) for x in np.std(d, axis=0)]
    [0.028, 0.03]
    """
    nu = calibration_draw_dof(calibration)
    if nu is not None and np.ndim(nu) == 1:   # independent positions, each its own ν
        u = np.asarray(calibration.u_arcsec, dtype=float)
        fin = np.isfinite(nu)
        z = rng.standard_normal((draws, u.size))
        t = z.copy()
        t[:, fin] = _t_of_normal(z[:, fin], nu[fin])
        return t * u
    lam, q = np.linalg.eigh(calibration.covariance())
    root = q * np.sqrt(np.clip(lam, 0.0, None))
    d = rng.standard_normal((draws, lam.size)) @ root.T
    if nu is None:
        return d
    # one joint estimate: one χ²
    return d * np.sqrt(nu / _chi2_stream(rng).chisquare(nu, (draws, 1)))


def _t_of_normal(z: np.ndarray, nu) -> np.ndarray:
    """Student's t_ν draws of standard normal draws ``z`` by their quantile, T_ν⁻¹(Φ(z))
    (the inversion method, JCGM 101 C.2; the tail taken from the near side, so no precision
    is lost at |z| large): the same z give the normal draws at ν = ∞, and |T_ν⁻¹(Φ(z))| ≥ |z|,
    rising as ν falls (t_ν's quantiles above 1/2 decrease with ν), draw by draw.

    >>> z = np.array([-3.0, -0.5, 1.0, 6.0])
    >>> _t_of_normal(z, 3.0).round(3).tolist()
    [-9.219, -0.556, 1.197, 1037.77]
    """
    from scipy import stats

    return -np.sign(z) * stats.t.ppf(stats.norm.cdf(-np.abs(z)), nu)


def _chi2_stream(rng):
    """The generator of the t draws' χ² scales: a child stream of ``rng`` (its seed sequence
    spawned; ``rng`` itself does not advance), so a Monte Carlo draws every other quantity
    identically whatever the calibration's ν (common random numbers: its result moves with
    ν only by the t's tails, not by the other draws' reshuffling, and ν → ∞ meets the normal
    draws)."""
    return rng.spawn(1)[0]


def calibration_draw_dof(calibration):
    """The ν :func:`calibration_error_draws` draws with: None (no ``dof``, or none finite:
    normal), one number (a covariance given: one joint estimate, the smallest of its
    positions' ν), or one ν per position (independent positions; ∞ where a position states
    none: normal there)."""
    dof = getattr(calibration, "dof", None)
    if dof is None or not np.any(np.isfinite(np.asarray(dof, dtype=float))):
        return None
    dof = np.asarray(dof, dtype=float)
    from gonio.specs.ogam_draft.table_calibration import draw_dof_refusal

    why = draw_dof_refusal(dof)
    if why:
        raise GonioError(f"{why} ({calibration.source})")
    if getattr(calibration, "cov_arcsec2", None) is not None:
        return float(np.min(dof))
    return dof


def calibration_draw_cov(calibration) -> np.ndarray:
    """The covariance of :func:`calibration_error_draws`, arcsec² (closed form, not the
    draws'): V with each ν's t factor ν/(ν − 2) (JCGM 101 6.4.9; ν ≥ 3, so it exists),
    per position for independent positions, one for a covariance given.

    >>> from gonio.specs.ogam_draft.table_calibration import TableCalibration
    >>> cal = TableCalibration([0, 60], [0.0, 0.0], [0.02, 0.03], "t", dof=[4, math.inf])
    >>> np.sqrt(np.diag(calibration_draw_cov(cal))).round(4).tolist()   # 0.02·√2, 0.03
    [0.0283, 0.03]
    """
    cov = np.asarray(calibration.covariance(), dtype=float)
    nu = calibration_draw_dof(calibration)
    if nu is None:
        return cov
    nu = np.asarray(nu, dtype=float)
    f = np.where(np.isfinite(nu), nu / (np.where(np.isfinite(nu), nu, 3.0) - 2.0), 1.0)
    if f.ndim == 0:
        return cov * float(f)
    r = np.sqrt(f)
    return cov * np.outer(r, r)


def calibration_draws_text(calibration) -> str:
    """How :func:`calibration_error_draws` drew a calibration's errors, for a Monte Carlo
    line's source: "drawn with their covariance" (normal), and the t's ν where it has one."""
    nu = calibration_draw_dof(calibration)
    if nu is None:
        return "drawn with their covariance (normal)"
    if np.ndim(nu) == 0:
        return (f"drawn with their covariance as a multivariate t with the calibration's "
                f"nu = {float(nu):.3g} (JCGM 101 6.4.9)")
    fin = np.asarray(nu)[np.isfinite(nu)]
    lo, hi = float(np.min(fin)), float(np.max(fin))
    nus = f"{lo:.3g}" if math.isclose(lo, hi) else f"{lo:.3g}-{hi:.3g}"
    return (f"drawn per position as t with the calibration's nu = {nus} "
            f"(JCGM 101 6.4.9)")


@dataclass(frozen=True)
class CalibratedTable:
    """A calibrated table as it enters angles turned from a zeroing position and read with the
    table-corrected 7.1 K (7.6, 7.7 with A.4.1's error known; beyond the draft): an angle θ
    turned from z (the table stopping at z + θ) carries the calibration's error
    δe(z + θ) − δe(z), and one read through K_c the K's, −3600·θ·(c_K·δe)/K_c (c_K of :func:`table_corrected_k_sensitivity`; None:
    angles not read through the 7.1 K). ``source``: the calibration's one-line description."""

    calibration: object
    c_k: np.ndarray | None = None
    k_c: float | None = None

    @property
    def source(self) -> str:
        return self.calibration.describe()

    def coefficients(self, turned_deg, zero_deg) -> np.ndarray:
        """(angles × calibration positions): the sensitivity to the calibration's errors of
        each angle θ turned from the zeroing position z (a reading's ``table_deg``, 7.4): the
        table stops at z + θ (modulo 360°), so δe(z + θ) − δe(z), and θ's K part (a position
        reached twice has one error: coefficients add). ValueError where the calibration does
        not list a position.

        Zeroed at 90°, 30° turned reads the error at 120°, not at 30°:

        >>> from gonio.specs.ogam_draft.table_calibration import TableCalibration
        >>> ct = CalibratedTable(TableCalibration([0, 30, 90, 120], [0.0] * 4, [0.1] * 4, "t"))
        >>> ct.coefficients([30.0, 270.0], 90.0).tolist()
        [[0.0, 0.0, -1.0, 1.0], [1.0, 0.0, -1.0, 0.0]]
        """
        cal = self.calibration
        pos = np.atleast_1d(np.asarray(turned_deg, dtype=float))
        z = np.broadcast_to(np.asarray(zero_deg, dtype=float), pos.shape)
        _, i_p, i_z, miss = tcal.turned_error_arcsec(cal, z + pos, z)   # stops looked up as Δ's
        if miss:
            raise ValueError(f"not calibrated: {miss}")
        a = np.zeros((pos.size, cal.table_deg.size))
        rows = np.arange(pos.size)
        np.add.at(a, (rows, i_p), 1.0)
        np.add.at(a, (rows, i_z), -1.0)
        if self.c_k is not None:
            a -= np.outer(ARCSEC_PER_DEG * pos / self.k_c, self.c_k)
        return a

    def blind(self, a: np.ndarray) -> bool:
        """Whether coefficients ``a`` see a part of the table the calibration cannot (an
        equal-division comparison's blind harmonics)."""
        basis = getattr(self.calibration, "blind_basis", None)
        return basis is not None and bool(np.linalg.norm(a @ np.asarray(basis)) >
                                          1e-9 * max(float(np.linalg.norm(a)), 1e-300))

    def draws(self, rng, draws: int) -> np.ndarray:
        """:func:`calibration_error_draws` of its calibration."""
        return calibration_error_draws(self.calibration, rng, draws)


def scale_factor_table_correction(k_i, theta_deg, stop_deg, zero_deg, calibration
                                  ) -> tuple[TableCorrection | None, list[float]]:
    """K's rounds corrected by the table's calibrated error e = indicated − true, arcsec
    (:class:`gonio.specs.ogam_draft.table_calibration.TableCalibration`; beyond the draft).

    Round i turns the table from its zeroing position z_i to the stop s_i; the table reads
    θ_i but turned θ_i − (e(s_i) − e(z_i))/3600 (A.4.1's error, now known), so
    K_i = C_i/θ_i becomes K_i θ_i/(θ_i − Δe_i/3600) (7.1). K = mean K_i; its sensitivity to
    e(x_p) is c_p = (1/n) Σ_i K_i/(3600 θ_i − Δe_i) · ([s_i = x_p] − [z_i = x_p]) (K_i the
    corrected ones), u(K)² = cᵀ V c with V the calibration's covariance (diagonal u² where
    none is given, JCGM 100 5.1.2; 5.2.2 with it), ν of that combination
    (:meth:`~gonio.specs.ogam_draft.table_calibration.TableCalibration.combine`: Welch–
    Satterthwaite over independent positions, a joint estimate's own ν, ∞ where the
    calibration states none). Positions are taken modulo 360°. Returns
    (None, missing positions) where the calibration does not cover a stop or zero.

    Six rounds 0 → 60°…360° at K = 3600 counts/°, e(60°) = 0.1″, the rest 0: round 1 turned
    60° − 0.1″, K_1 = 3600·60/(60 − 0.1/3600) = 3600.00167; u 0.02″ at every position,
    independent: c(θ) ≈ 1/(6θ) at the stops 60°…300°, c(0°) = −Σ of those (the zeroing
    position of rounds 1–5; round 6 stops at 360° = 0° and carries no table error), so
    u = 0.02·√(Σ c_p² + (Σ c_p)²) counts/°:

    >>> from gonio.specs.ogam_draft.table_calibration import TableCalibration
    >>> cal = TableCalibration([0, 60, 120, 180, 240, 300], [0, 0.1, 0, 0, 0, 0], [0.02] * 6, "t")
    >>> th = [60.0, 120.0, 180.0, 240.0, 300.0, 360.0]
    >>> c, _ = scale_factor_table_correction([3600.0] * 6, th, th, [0.0] * 6, cal)
    >>> round(float(c.k_i_counts_per_deg[0]), 5), [float(x) for x in c.k_i_counts_per_deg[1:]] == [3600.0] * 5
    (3600.00167, True)
    >>> g = np.array([1/60, 1/120, 1/180, 1/240, 1/300])    # c_p·6 at 60°…300°, per K/3600
    >>> round(c.u_counts_per_deg, 8) == round(0.02 * 3600 / 3600 / 6 * math.sqrt(np.sum(g ** 2) + np.sum(g) ** 2), 8)
    True
    >>> scale_factor_table_correction([3600.0], [45.0], [45.0], [0.0], cal)
    (None, [45.0])
    """
    k_c, c, missing = table_corrected_k_sensitivity(k_i, theta_deg, stop_deg, zero_deg,
                                                    calibration)
    if k_c is None:
        return None, missing
    _refuse_blind(calibration, c)
    u, dof = calibration.combine(c)
    return TableCorrection(k_c, u, dof, calibration.describe()), []


def _scale_factor_table_lines_of(k_i, th, table_mpe_arcsec: float, table_correction,
                                 table_note: str, stop_deg=None, zero_deg=None,
                                 programme=None) -> list:
    """K's table line (:func:`scale_factor_budget`): the calibration's where the table is
    calibrated, else ``P_K``: the table's errors at the positions the 7.1 rounds reach, each
    within ±MPE (A.4.1) and correlated as one table's errors are in a way the laboratory does
    not know, so their worst linear combination (:func:`scale_factor_table_bound_rel`) taken
    as one rectangular line (JCGM 100 4.3.7, F.2.4.4). The positions-independent reading
    (:func:`scale_factor_table_u_rel`) and the periodic one (:func:`scale_factor_table_line`)
    are named in the line's source, not stated. ``programme``: (θ, stops, zeros) of the
    programme's 7.1 rounds (None: the rounds read): the bound is the larger of theirs and the
    rounds read's (:func:`~gonio.specs.ogam_draft.table_periodic.programme_bound`)."""
    if table_correction is not None:
        tc_ = table_correction
        return [_Line(from_u("P_Kc", 0.0, tc_.u_counts_per_deg, dof=tc_.dof, type="B",
                             source=f"table angle error at the stops corrected by the "
                                    f"{tc_.source}; u of the correction propagated "
                                    f"(stops − zeroing positions)"),
                      "table angle (calibrated table)", True,
                      "A.4.1 applied to 7.1, calibrated table")]
    kbar = abs(float(np.mean(k_i)))
    tl = scale_factor_table_line(th, table_mpe_arcsec)
    coeffs = scale_factor_table_coefficients(th, stop_deg, zero_deg)

    def bound_of(rounds, reading=TABLE_ZERO_STATED):
        return scale_factor_table_bound_rel(*rounds[:1], table_mpe_arcsec, *rounds[1:],
                                            reading=reading)

    read = (th, stop_deg, zero_deg)
    bound = programme_bound(bound_of, read, programme)
    u_ind = scale_factor_table_u_rel(th, table_mpe_arcsec, stop_deg, zero_deg)
    beside = (f"beside, not stated: the positions independent u = {u_ind / PPM:.3g} ppm; one "
              f"periodic error at the MPE, worst order {tl.order}, half-width "
              f"{tl.half_width_rel_harmonic / PPM:.3g} ppm; the draft's reading of the MPE at "
              f"the zero (the angle from the zero within the MPE) "
              f"±{programme_bound(lambda r: bound_of(r, 'draft'), read, programme) / PPM:.3g}"
              " ppm")
    if bound > bound_of(read):
        beside += (f"; the bound of the programme's {len(programme[0])} rounds, not of the "
                   f"{th.size} read: a round set aside never lowers it")
    if table_note:
        beside += f"; {table_note}"
    pos = ", ".join(f"{p:g}" for p in coeffs)
    return [_Line(type_b("P_K", 0.0, kbar * bound, "rectangular",
                         source=f"table angle errors at {pos} deg (the 7.1 rounds' stops and "
                                f"zero), each within the MPE ±{table_mpe_arcsec:g}″, correlated "
                                f"as one table's errors (shape not known): their worst linear "
                                f"combination ±{bound / PPM:.3g} ppm of K, rectangular; "
                                + beside),
                  "table angle at the 7.1 positions", True, "A.4.1 applied to 7.1")]


def scale_factor_budget(k_i, theta_deg, table_mpe_arcsec: float, *,
                        k: float | None = None,
                        tilt_bias_arcsec_per_deg: float = 0.0,
                        chamber: ChamberLine | None = None,
                        tilt_correction=None,
                        table_correction: TableCorrection | None = None,
                        table_note: str = "", stop_deg=None,
                        zero_deg=None, programme=None) -> ItemUncertainty:
    """u(K) of K = mean K_i, K_i = C_i/θ_i (draft 7.1), counts/°.

    Components: the scatter of the n rounds (Type A, s(K_i)/√n, ν = n − 1, 7.1); the
    table's angle errors at the positions the rounds reach, one line ``P_K`` (A.4.1 applied
    to 7.1, :func:`scale_factor_table_coefficients`): round i turns the table from its zero
    z_i to its stop s_i with the error e(s_i) − e(z_i), so δK/K = Σ c_p e(p); each position's
    error is known only by the MPE and the positions' errors are one table's curve, correlated
    in a way the laboratory does not know, so the line is rectangular within their worst
    linear combination MPE·Σ|c_p| (:func:`scale_factor_table_bound_rel`; JCGM 100 4.3.7,
    F.2.4.4): it holds for every table within its MPE, the zero at −MPE and every stop at
    +MPE included, and is over-wide for a table well inside it (docs/draft-readings.md 7.1,
    "K's table line"). ``stop_deg``/``zero_deg``: the rounds' positions (None: zeroed at 0°,
    stopped at θ_i; the 360° stop is the zero; ``programme``: the programme's rounds, the bound
    never below theirs). The positions-independent reading and the periodic one are named in
    the line's source. The count quantisation, triangular ±1 count:
    u = (1/n)√Σ(u_C/θ_i)². The Type A scatter also holds the table's per-visit scatter.

    ``tilt_bias_arcsec_per_deg`` (A_K of :func:`gonio.specs.ogam_draft.budget_extra.scale_factor_tilt_bias`,
    at the tilt bound of A.1): the sensing plane tilted by ψ against the table couples the
    Earth rate into every 7.1 round, a bias of K that is the same in every round (the Type A
    scatter does not see it) and whose sign depends on the tilt's unknown azimuth: the
    ``K_tilt`` line, arcsine with half-width |K|·A_K/3600 (A_K″ per degree of angle is a
    relative error A_K/3600 of K). It is not in the draft's budget (``beyond_standard``).

    ``chamber`` (a :class:`ChamberLine` of :func:`chamber_temperature_line`): K is stated at
    the reference temperature of Table 2 and measured in a chamber ΔT away; the instrument's
    K moves by α_K ΔT, the same in every round: the ``K_T`` line, half-width |K| times the
    line's relative half-width, in its distribution (rectangular at a logged ΔT, the product
    of two rectangulars where ΔT is known only by the tolerance). Not in the draft's budget;
    absent where its half-width is zero (a logged ΔT of 0).

    ``table_correction`` (a :class:`TableCorrection` of :func:`scale_factor_table_correction`,
    a calibrated table): K is the mean of the corrected K_i and the ``P_K`` line at the MPE
    is replaced by the calibration's, ``P_Kc``, normal with its propagated u (beyond the
    draft). ``table_note``: why a calibration given is not used (positions it does not
    cover), appended to the MPE line's source.

    ``tilt_correction`` (a :class:`gonio.specs.ogam_draft.budget_extra.TiltCorrection`: the
    coupling's relative bias δ at the tilt ψ and azimuth α the in-situ tilt estimate
    measured, and u(δ)): K is corrected, K = mean K_i/(1 + δ), and the ``K_tilt`` line at
    the bound is replaced by the correction's own, ``K_te``, normal with u = |K|·u(δ) and
    ν = N − 3 of the estimate's fit (Type A: the estimate's scatter). Beyond the draft.

    Examples
    --------
    The draft's six rounds 60°…360° with K_i = 3600.1, 3600.3, 3600.2, 3600.2, 3600.1,
    3600.3 counts/°, table MPE 0.1″ (A.4.1): s(K_i) = 0.0894, s/√6 = 0.0365;
    the table: the zero's coefficient −2.2833/1296000, the stops' 1/1296000, 1/2, …, 1/5 of
    it, so the worst combination is 0.1·4.5667/1296000 = 0.3524 ppm, u = 3600.2·0.3524e-6/√3
    = 7.32e-4 counts/°; quantisation (1/√6)/6·√Σ1/θ_i² = 0.0680·0.02034 = 0.00138 counts/°.

    >>> b = scale_factor_budget([3600.1, 3600.3, 3600.2, 3600.2, 3600.1, 3600.3],
    ...                         [60, 120, 180, 240, 300, 360], 0.1)
    >>> [(c.symbol, round(c.u, 5)) for c in b.components]
    [('s_K', 0.03651), ('P_K', 0.00073), ('q_K', 0.00138)]
    >>> b.components[1].distribution
    'rectangular'
    >>> round(b.u_c, 4), b.nu_eff > 4, b.k_source
    (0.0365, True, 'welch-satterthwaite')
    """
    k_i = np.asarray(k_i, dtype=float)
    th = np.asarray(theta_deg, dtype=float)
    if table_correction is not None:
        k_i = np.asarray(table_correction.k_i_counts_per_deg, dtype=float)
    n = k_i.size
    _, u_q = _single_round_u(k_i, th, table_mpe_arcsec)
    lines = []
    if n >= 2:
        s = float(np.std(k_i, ddof=1))
        lines.append(_Line(from_u("s_K", 0.0, s / math.sqrt(n), dof=n - 1, type="A",
                                  source=f"scatter of the {n} rounds' K_i, s/√n"),
                           "scatter of K_i", False, "7.1"))
    lines.extend(_scale_factor_table_lines_of(k_i, th, table_mpe_arcsec, table_correction,
                                              table_note, stop_deg, zero_deg, programme))
    lines.append(_Line(from_u("q_K", 0.0, float(np.sqrt(np.sum(u_q ** 2))) / n, type="B",
                              source="count quantisation, ±1 count triangular per C_i"),
                       "count quantisation", True, "7.1 (pulse count)"))
    # from_u marks distribution "normal"; the quantisation line is not normal
    lines[-1] = _Line(_as_dist(lines[-1].q, "triangular"), *_rest(lines[-1]))
    value = float(np.mean(k_i))
    if tilt_correction is not None:
        tc = tilt_correction
        value /= 1.0 + tc.delta_rel
        corr_ppm = -tc.delta_rel / (1.0 + tc.delta_rel) / PPM
        lines.append(_Line(from_u("K_te", 0.0, abs(value) * tc.u_delta_rel, dof=tc.dof, type="A",
                                  source=f"K corrected by {corr_ppm:+.3g} "
                                         f"ppm for the tilt x Earth-rate coupling of the 7.1 "
                                         f"rounds at the measured tilt psi = {tc.tilt_deg:.3g} deg "
                                         f"(u {tc.u_tilt_deg:.2g}), azimuth {tc.azimuth_deg:.1f} "
                                         f"deg (u {tc.u_azimuth_deg:.2g}), r = "
                                         f"{tc.r_tilt_azimuth:.2f}; u of the correction"),
                           "tilt correction of K", True, "A.1 applied to 7.1"))
    elif tilt_bias_arcsec_per_deg:
        a_k = float(tilt_bias_arcsec_per_deg)
        lines.append(_Line(type_b("K_tilt", 0.0, abs(float(np.mean(k_i))) * a_k / ARCSEC_PER_DEG,
                                  "arcsine",
                                  source=f"tilt x Earth-rate coupling of the 7.1 rounds, A_K = "
                                         f"{a_k:.3g}″/° at the A.1 bound, worst azimuth"),
                           "tilt bias of K", True, "A.1 applied to 7.1"))
    if chamber is not None and chamber.half_width_rel > 0.0:
        m = chamber.thermometer_mpe_c
        src = (f"chamber temperature logged {signed_text(chamber.deviation_c)} °C from the "
               "reference" + (f", thermometer MPE ±{m:g} °C rectangular" if m else "")
               + ", alpha_K uniform within its bound"
               + (" (product): |alpha_K|max (|dT| + MPE) = " if m else ": |alpha_K|max |dT| = ")
               if chamber.basis == "logged" else
               "chamber temperature within its tolerance, alpha_K and dT independent uniforms "
               "(product): |alpha_K|max dT_max = ") + f"{chamber.half_width_rel:.3g}"
        lines.append(_Line(type_b("K_T", 0.0, abs(float(np.mean(k_i))) * chamber.half_width_rel,
                                  chamber.distribution, beta=chamber.beta, source=src),
                           "chamber temperature", True, "Table 2 applied to 7.1"))
    return _budget("scale_factor", "counts/deg", value, lines, k=k)


def without_tilt_u_rel(b: ItemUncertainty) -> float:
    """u(K)/K of a :func:`scale_factor_budget` less its ``K_tilt`` (or ``K_te``) and ``K_T`` lines: the
    part of u(K) an item that carries the tilt bias of K by its own ``K_tilt`` line takes as
    normal (the chamber's temperature moves K and the counts it divides alike, so it does not
    enter an angle read with that K in the same chamber)."""
    u2 = b.u_c ** 2 - sum(c.u ** 2 for c in b.components
                          if c.symbol in ("K_tilt", "K_te", "K_T"))
    return math.sqrt(max(u2, 0.0)) / abs(b.value) if b.value else 0.0


def _rest(ln: _Line):
    return ln.name, ln.beyond_draft, ln.clause


def _as_dist(q, name: str):
    """The same u as a rectangular/triangular quantity (half-width = u·divisor)."""
    div = {"rectangular": math.sqrt(3.0), "triangular": math.sqrt(6.0)}[name]
    return type_b(q.symbol, q.value, q.u * div, name, source=q.source)


def nonlinearity_budget(k_i, theta_deg, table_mpe_arcsec: float, *,
                        k: float | None = None,
                        tilt_bias_arcsec_per_deg: float = 0.0) -> ItemUncertainty:
    """u(K_l) of K_l = (max K_i − min K_i)/K · 100 % (draft 7.2), in %.

    Components: u(K_max) and u(K_min) of single rounds (table angle at the stop,
    rectangular MPE, and count quantisation, triangular), independent; and the spread
    that noise alone gives n values, d₂(n)·ū(K_i) (Tippett; :func:`uncertainty.stdev.
    expected_range_factor`), taken as a rectangular half-width: a range is biased
    upwards by noise, so the true K_l lies below the measured one by up to about that.

    ``tilt_bias_arcsec_per_deg`` (A_l of :func:`gonio.specs.ogam_draft.budget_extra.nonlinearity_tilt_bias`
    for the largest and smallest round, at the A.1 tilt bound): the tilt × Earth-rate
    coupling moves each round's K_i by its own amount (it grows with the time from zeroing
    to reading), so it enters K_l where it does not cancel between the two extreme rounds:
    the ``K_tilt`` line, arcsine (unknown azimuth) with half-width 100·A_l/3600 %. Beyond
    the draft's budget, like K's.

    Examples
    --------
    Two rounds at 100° and 200°, K_i = 3600.00 and 3600.18 (the doctest of
    :func:`gonio.characteristics.scale_factor_nonlinearity`), MPE 0.1″: u(K at 100°) =
    √((3600·0.0577/360000)² + (0.408/100)²) = 0.00412; at 200° 0.00206; in % (/3600.09·100):
    1.145e-4 (K_min) and 0.573e-4 (K_max); range term d₂(2) = 1.128 × mean u 0.00309 / √3
    → 0.56e-4 %.

    >>> b = nonlinearity_budget([3600.0, 3600.18], [100.0, 200.0], 0.1)
    >>> [round(c.u * 1e4, 3) for c in b.components]
    [0.573, 1.145, 0.56]
    """
    k_i, th, n, kbar, u_tab, u_q = _rounds(k_i, theta_deg, table_mpe_arcsec)
    u_i = np.sqrt(u_tab ** 2 + u_q ** 2)
    i_max, i_min = int(np.argmax(k_i)), int(np.argmin(k_i))
    to_pct = 100.0 / kbar
    half = expected_range_factor(n) * float(np.mean(u_i)) * to_pct
    lines = [
        _Line(from_u("K_max", 0.0, float(u_i[i_max]) * to_pct, type="B",
                     source=f"K_i at {th[i_max]:g}°: table angle and count quantisation"),
              "largest K_i", True, "7.2 (A.4.1 applied to 7.1)"),
        _Line(from_u("K_min", 0.0, float(u_i[i_min]) * to_pct, type="B",
                     source=f"K_i at {th[i_min]:g}°: table angle and count quantisation"),
              "smallest K_i", True, "7.2 (A.4.1 applied to 7.1)"),
        _Line(type_b("K_rng", 0.0, half, "rectangular",
                     source=f"spread noise alone gives {n} values, d2({n})·mean u(K_i)"),
              "range inflation by noise", True, "7.2"),
    ]
    if tilt_bias_arcsec_per_deg:
        a_l = float(tilt_bias_arcsec_per_deg)
        lines.append(_Line(type_b("K_tilt", 0.0, 100.0 * a_l / ARCSEC_PER_DEG, "arcsine",
                                  source=f"tilt x Earth-rate coupling of the rounds at "
                                         f"{th[i_max]:g}° and {th[i_min]:g}°, A_l = "
                                         f"{a_l:.3g}″/° at the A.1 bound, worst azimuth"),
                           "tilt bias of the spread of K_i", True, "A.1 applied to 7.2"))
    value = float((k_i.max() - k_i.min()) / kbar * 100.0)
    # a range: it cannot be negative, so a U above it is stated as its upper bound alone
    return replace(_budget("scale_factor_nonlinearity", "%", value, lines, k=k),
                   nonnegative=value >= 0)


@dataclass(frozen=True)
class RoundNoise:
    """The gyro's own angle noise over a zero-to-reading round, from the 7.4 repeats
    (:func:`round_noise`): ``n2_arcsec2_per_s`` the angle random walk's N² (″²/s),
    ``static_s`` the static phase whose mean rate compensates the Earth rate (None when the
    compensation is not measured), ``dof`` the pooled degrees of freedom of the repeats."""
    n2_arcsec2_per_s: float
    static_s: float | None
    dof: int


def round_noise(e_arcsec, position, time_s, quantum_u_arcsec: float,
                static_s: float | None = None) -> RoundNoise:
    """N² of the gyro's angle noise over a round, ″²/s, from the series of 7.4 (draft 7.5).

    A round (7.1 or 7.4) zeroes the counter at rest, turns and reads after its delay; the
    gyro's angle random walk adds N²t to the reading's variance (t from zeroing to reading,
    IEEE Std 952 angle random walk), the rate error of a compensation measured over a static
    phase of T_s (the mean of the same walk over T_s, u = N/√T_s, one per series) adds
    N²t²/T_s, and the count quantisation u_q² (triangular ±1 count). The 7.4 series repeat
    the same rounds, so the variance of E_ij over the series j at position i is
    u_q² + N²(t_i + t_i²/T_s), and N² is their pooled moment estimate:
    N² = Σ ν_i (s_i² − u_q²) / Σ ν_i (t_i + t_i²/T_s), ν_i = n_i − 1 (0 where the
    quantisation alone explains the spread). Beyond the draft (its Annex A takes u(r) as is).

    Two positions read at 10 s and 20 s with T_s = 60 s, each s² = u_q² + N²(t + t²/60) at
    N² = 4e-4 ″²/s, u_q = 0.02″: the estimate gives N² back.

    >>> q, n2 = 0.02, 4e-4
    >>> s = [math.sqrt(q * q + n2 * (t + t * t / 60)) for t in (10.0, 20.0)]
    >>> e = [v * x / math.sqrt(2) for v in s for x in (-1.0, 1.0)]   # two series each
    >>> r = round_noise(e, [1, 1, 2, 2], [10.0, 10.0, 20.0, 20.0], q, 60.0)
    >>> round(r.n2_arcsec2_per_s, 10), r.dof
    (0.0004, 2)
    """
    import pandas as pd

    d = pd.DataFrame({"e": np.asarray(e_arcsec, dtype=float), "p": list(position),
                      "t": np.asarray(time_s, dtype=float)})
    d = d[np.isfinite(d["e"]) & np.isfinite(d["t"])]
    g = d.groupby("p")
    nu = (g["e"].count() - 1).clip(lower=0)
    s2 = g["e"].var(ddof=1).fillna(0.0)
    t = g["t"].mean()
    ok = nu > 0
    if not ok.any():
        raise ValueError("round_noise needs a position read in at least two series")
    grow = t + (t * t / float(static_s) if static_s else 0.0)
    num = float((nu[ok] * (s2[ok] - quantum_u_arcsec ** 2)).sum())
    den = float((nu[ok] * grow[ok]).sum())
    return RoundNoise(max(num, 0.0) / den if den > 0 else 0.0,
                      float(static_s) if static_s else None, int(nu[ok].sum()))


@dataclass(frozen=True)
class RangeTableOrder:
    """The table's worst order for K_l's range (:func:`nonlinearity_table_order`)."""

    order: int                   # the worst order h
    half_range_rel: float        # the largest range one periodic error at the bound adds, /2


def nonlinearity_table_order(theta_deg, table_mpe_arcsec: float,
                             max_order: int = 360) -> RangeTableOrder:
    """The order of one periodic table error at the A.4.1 bound that spreads the 7.1 rounds'
    K_i most (draft 7.2: K_l is the range of the K_i).

    Round k's K_i = C_k/θ_k carries the table's error (P(θ_k) − P(0))/θ_k (A.4.1 applied to
    7.1), relative. For one periodic error P(x) = a·sin(h·x + φ), a = MPE, that is
    a·Im(e^{iφ} v_k), v_k = (e^{ihθ_k} − 1)/θ_k (θ in arcseconds): all rounds from the same
    curve, correlated. The range it adds between rounds k and j is a·Im(e^{iφ}(v_k − v_j)),
    at most a·|v_k − v_j| over the phase, so the worst order is the one with the largest
    diameter max_{k,j} |v_k − v_j| of the v_k (not K's order, which maximises |Σ v_k|). A
    curve Σ a_h sin(h x + φ_h) with Σ|a_h| ≤ MPE adds at most MPE times that diameter
    (triangle inequality), so the order bounds every table shape within its MPE. The search
    over orders is :mod:`gonio.specs.ogam_draft.table_periodic`'s (shared with K and E).

    The draft's stops 60°…360°, MPE 0.1″: order 3 puts the 60° stop at −2a/θ and the 360°
    stop at 0: half-range 0.1/216000 = 0.463 ppm.

    >>> t = nonlinearity_table_order([60, 120, 180, 240, 300, 360], 0.1)
    >>> t.order, round(t.half_range_rel / PPM, 3)
    (3, 0.463)
    """
    th = np.asarray(theta_deg, dtype=float) * ARCSEC_PER_DEG
    v = (periodic_response(th / ARCSEC_PER_DEG, max_order) - 1.0) / th
    diam = np.abs(v[:, :, None] - v[:, None, :]).max(axis=(1, 2))
    order = worst_order(diam)
    return RangeTableOrder(order, 0.5 * float(table_mpe_arcsec) * float(diam[order - 1]))


#: K_l's table readings (:func:`nonlinearity_corrected_budget`): the stated one (the table's
#: worst shift of the range within the MPE, :func:`range_table_bound`, added to the noise
#: belt's ends: it holds every table within its MPE), the positions independent (each
#: position the 7.1 rounds reach rectangular ±MPE, the common zero shared: the stated one
#: until the corner table was found to escape it), the standard's per stop (each stop's turn
#: independent, the zero inside it) and one periodic error at the bound, the last three kept
#: for comparison.
TABLE_READINGS = ("stated", "independent", "standard", "periodic")

#: Draws of the JCGM 101 Monte Carlo of K_l's range (:func:`nonlinearity_corrected_budget`)
#: and its fixed seed (the same 7.1 data give the same K_l and u).
RANGE_DRAWS = 4000
RANGE_SEED = 20261129


def range_table_positions(theta_deg, stop_deg=None, zero_deg=None):
    """The distinct table positions the 7.1 rounds reach (° mod 360, rounded to 1e-6°) and the
    (n, P) matrix that turns their errors into the rounds' turned-angle errors: round i turns
    from its zero z_i to its stop s_i = z_i + θ_i with the error e(s_i) − e(z_i) (A.4.1
    applied to 7.1), so its row holds +1 at s_i and −1 at z_i; a position reached by several
    rounds is one column (one error), and a stop at the zero's own position (the 360° stop of
    a round zeroed at 0°) cancels. The positions and rule of K's table lines
    (:func:`scale_factor_table_coefficients`, whose coefficients are this matrix's rows over
    nθ_i) and of E's.

    >>> pos, m = range_table_positions([60, 120, 360])
    >>> pos, m.tolist()
    ([0.0, 60.0, 120.0], [[-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0], [0.0, 0.0, 0.0]])
    """
    th = np.asarray(theta_deg, dtype=float)
    stop = th if stop_deg is None else np.asarray(stop_deg, dtype=float)
    zero = np.zeros_like(th) if zero_deg is None else np.asarray(zero_deg, dtype=float)
    key = tcal.position_key
    pos = sorted({key(x) for x in np.concatenate([stop, zero])})
    col = {p: j for j, p in enumerate(pos)}
    m = np.zeros((th.size, len(pos)))
    for i, (s_, z_) in enumerate(zip(stop, zero)):
        m[i, col[key(s_)]] += 1.0
        m[i, col[key(z_)]] -= 1.0
    return pos, m


def range_table_bound(k_i, theta_deg, table_mpe_arcsec: float, stop_deg=None,
                      zero_deg=None, reading: str = TABLE_ZERO_STATED) -> float:
    """The largest shift of K_l's range (draft 7.2), in %, that any table within its MPE can
    give the 7.1 rounds: the half-width of K_l's table line in its stated reading
    (:func:`nonlinearity_corrected_budget`), the analogue of K's MPE·Σ|c_p|
    (:func:`scale_factor_table_bound_rel`, JCGM 100 4.3.7: a quantity known only by its
    bound).

    Round i's K_i moves by δ_i = 100·(K_i/K̄)·(e(s_i) − e(z_i))/θ_i % (A.4.1 applied to 7.1;
    :func:`range_table_positions`: w_i·e with w_i its row over θ_i). A range moves by at most
    the range of its shifts, |range(t + δ) − range(t)| ≤ max_{i,j}(δ_i − δ_j) (max(t + δ) ≤
    max t + max δ, min(t + δ) ≥ min t + min δ), with equality for equal true K_i; δ_i − δ_j =
    (w_i − w_j)·e is largest over the box |e_p| ≤ MPE at its vertex sign(w_i − w_j), so

        D = MPE · max_{i,j} Σ_p |w_{i,p} − w_{j,p}|

    (tests/test_kl_table_line.py checks it against every vertex of the box). The draft's stops
    60°…360° zeroed at 0°: the 60° round against the 360° one (whose stop is its zero: no
    table error), 2·MPE/60°: 9.26·10⁻⁵ % at MPE 0.1″ — the bound the one periodic error of
    order 3 reaches (:func:`nonlinearity_table_order`, 2 × its half-range).

    >>> th = [60.0, 120.0, 180.0, 240.0, 300.0, 360.0]
    >>> round(range_table_bound([3600.0] * 6, th, 0.1) * 1e5, 4)
    9.2593

    In the draft's reading of the MPE at the zero (:func:`~gonio.specs.ogam_draft.
    table_periodic.table_worst_bound`) the zero's terms go; the widest pair is then the 60°
    round against the 120° one, MPE·(1/60° + 1/120°):

    >>> round(range_table_bound([3600.0] * 6, th, 0.1, reading="draft") * 1e5, 4)
    6.9444
    """
    k_i = np.asarray(k_i, dtype=float)
    th = np.asarray(theta_deg, dtype=float)
    pos, m = range_table_positions(th, stop_deg, zero_deg)
    w = m / (th * ARCSEC_PER_DEG)[:, None] * (k_i / float(np.mean(k_i)))[:, None] * 100.0
    return max(table_worst_bound(dict(zip(pos, w[i] - w[j])), table_mpe_arcsec, reading)
               for i in range(th.size) for j in range(th.size))


def _range_table_errors(k_i, th, table_mpe_arcsec: float, u_tab, rng, draws: int,
                        reading: str = "stated", stop_deg=None, zero_deg=None):
    """Draws of the rounds' table errors of K_i (counts/°) in one of K_l's readings
    (:func:`nonlinearity_corrected_budget`, A.4.1 applied to 7.1), and the worst order of one
    periodic error (:func:`nonlinearity_table_order`):

    - ``stated``: the error at every position the rounds reach rectangular ±MPE (JCGM 100
      4.3.7), independent of the other positions', round i moved by
      K_i·(e(s_i) − e(z_i))/θ_i (:func:`range_table_positions`: the common zero shared by every
      round, the 360° stop cancelling) — K's table lines (:func:`scale_factor_table_u_rel`);
    - ``standard``: each stop's turn independent, rectangular ±MPE (u_tab per round);
    - ``periodic``: one periodic error at the bound of the worst order,
      K_i·MPE·(sin(hθ_i + φ) − sin φ)/θ_i, φ uniform per draw (its own generator).

    The first two draw from ``rng``."""
    n = k_i.size
    worst = nonlinearity_table_order(th, table_mpe_arcsec)
    if reading == "standard":
        return rng.uniform(-1.0, 1.0, (draws, n)) * (u_tab * math.sqrt(3.0)), worst
    if reading == "periodic":
        phi = np.random.default_rng(RANGE_SEED + 1).uniform(0.0, 2.0 * math.pi, (draws, 1))
        x = np.radians(th)
        return (float(table_mpe_arcsec) * (np.sin(worst.order * x + phi) - np.sin(phi))
                / (th * ARCSEC_PER_DEG) * k_i), worst
    _, m = range_table_positions(th, stop_deg, zero_deg)
    e = rng.uniform(-1.0, 1.0, (draws, m.shape[1])) * float(table_mpe_arcsec)
    return (e @ m.T) / (th * ARCSEC_PER_DEG) * k_i, worst


def _round_errors(k_i, th, errs, rng, draws: int, tilt_measured, tilt_round_coupling, noise,
                  time_s):
    """The rounds' errors beyond the table's, added to each reading's draws ``errs`` (%) in
    :func:`nonlinearity_corrected_budget`: the tilt coupling (at the measured tilt, K_i then
    corrected, or at the A.1 bound) and the gyro's noise over each round; (K_i, errs, source)."""
    src = "count quantisation (triangular ±1 count)"
    if tilt_measured is not None:
        tm = tilt_measured
        k_i = k_i / (1.0 + tm.rel_error())
        d = rng.multivariate_normal([tm.psi_rad, tm.gamma_rad], tm.cov_rad2, draws)
        add = (tm.rel_error(d[:, :1], d[:, 1:]) - tm.rel_error()) * 100.0
        errs = {r: e + add for r, e in errs.items()}
        src += (f", corrected for the tilt x Earth-rate coupling of each round at the measured "
                f"tilt psi = {math.degrees(tm.psi_rad):.3g} deg (the correction's error from "
                f"the estimate's covariance, nu = {tm.dof})")
    elif tilt_round_coupling is not None:
        a, b = (np.asarray(v, dtype=float) * 100.0 / ARCSEC_PER_DEG for v in tilt_round_coupling)
        alpha = rng.uniform(0.0, 2.0 * math.pi, (draws, 1))
        errs = {r: e + a * np.cos(alpha) - b * np.sin(alpha) for r, e in errs.items()}
        src += ", tilt x Earth-rate coupling at the A.1 bound (azimuth uniform)"
    if noise is not None and time_s is not None and noise.n2_arcsec2_per_s > 0:
        t = np.asarray(time_s, dtype=float)
        n_arw = math.sqrt(noise.n2_arcsec2_per_s)
        ang = rng.standard_normal((draws, t.size)) * (n_arw * np.sqrt(t))
        src += (f", the gyro's angle random walk over each round (N = {n_arw:.3g}″/√s from the "
                f"7.4 series, ν = {noise.dof})")
        if noise.static_s:
            ang = ang + rng.standard_normal((draws, 1)) * (n_arw / math.sqrt(noise.static_s)) * t
            src += f" and the compensation's rate error over its {noise.static_s:g} s static phase"
        errs = {r: e + ang / (th * ARCSEC_PER_DEG) * 100.0 for r, e in errs.items()}
    return k_i, errs, src


def shifted_belt(x, errors, shift: float) -> tuple[float, float]:
    """The range belt's interval (:func:`uncertainty.stdev.range_belt_interval`) for values
    ``x`` whose measured range r may differ from the one the belt's ``errors`` alone would
    give by up to ``shift`` (K_l's table: any table within its MPE moves the range by at
    most D, :func:`range_table_bound`): [R_lo(r − D), R_hi(r + D)], the belt inverted at the
    two ends of the ranges the table-free measurement can have had, along the measured
    pattern (the robust belt holds every pattern). R_lo and R_hi rise with r, so whenever the
    table-free range lies in the belt of the true R, R lies in this interval: ≥ 95 % for every
    table within the MPE. Moving the belt's ends out by D, [R_lo(r) − D, R_hi(r) + D], holds
    only where they rise no faster than r; near the noise floor R_hi rises about twice as fast
    (tests/test_kl_belt_shift.py). r − D ≤ 0: the lower end is 0.

    >>> rng = np.random.default_rng(1)
    >>> e = rng.normal(0.0, 1.0, (20_000, 2))
    >>> from uncertainty.stdev import range_belt_interval
    >>> shifted_belt([0.0, 4.0], e, 0.0) == range_belt_interval([0.0, 4.0], e)
    True
    >>> lo, hi = shifted_belt([0.0, 4.0], e, 1.0)
    >>> lo == range_belt_interval([0.5, 3.5], e)[0], hi == range_belt_interval([-0.5, 4.5], e)[1]
    (True, True)
    """
    from uncertainty.stdev import range_belt_interval

    if shift <= 0.0:
        return range_belt_interval(x, errors)
    below, above = _shifted_values(x, shift)
    lo = 0.0 if below is None else range_belt_interval(below, errors)[0]
    return float(lo), float(range_belt_interval(above, errors)[1])


def shifted_belt_numerical_u(x, errors, shift: float) -> float:
    """The standard uncertainty of :func:`shifted_belt`'s ends from the finite number of
    ``errors`` draws (JCGM 101 7.9; :func:`uncertainty.stdev.range_belt_numerical_u` of the
    belt each end is taken from), the larger of the two: the decimal place the interval is
    stated at (:func:`gonio.result.statement.state_interval`).

    >>> from uncertainty.stdev import range_belt_numerical_u
    >>> e = np.random.default_rng(1).normal(0.0, 1.0, (4000, 2))
    >>> shifted_belt_numerical_u([0.0, 4.0], e, 0.0) == max(range_belt_numerical_u([0.0, 4.0], e))
    True
    """
    from uncertainty.stdev import range_belt_numerical_u

    if shift <= 0.0:
        return float(max(range_belt_numerical_u(x, errors)))
    below, above = _shifted_values(x, shift)
    u_lo = 0.0 if below is None else range_belt_numerical_u(below, errors)[0]
    return float(max(u_lo, range_belt_numerical_u(above, errors)[1]))


def _shifted_values(x, shift: float):
    """The values of :func:`shifted_belt`'s two belts (``shift`` > 0): ``x`` with its range r
    moved to r − ``shift`` (None where that is ≤ 0: the lower end is 0) and to r + ``shift``,
    along the measured pattern."""
    x = np.asarray(x, dtype=float)
    m, r = float(x.mean()), float(x.max() - x.min())
    if r > 0:
        unit = (x - m) / r
    else:                       # as range_belt_interval: one value apart from the rest
        unit = np.zeros(x.size)
        unit[-1] = 1.0
        unit -= unit.mean()
    return (None if r - shift <= 0.0 else m + (r - shift) * unit), m + (r + shift) * unit


def _range_table_line(bound: float, belt, worst: RangeTableOrder) -> _Line:
    """K_l's table line ``K_tab`` (:func:`nonlinearity_corrected_budget`): rectangular with
    the half-width ``bound`` of :func:`range_table_bound` (JCGM 100 4.3.7), its source naming
    the noise's belt ``belt`` it widens and the worst order's range beside."""
    return _Line(type_b(
        "K_tab", 0.0, bound, "rectangular",
        source=f"table angle at every position the 7.1 rounds reach within the A.4.1 MPE: "
               f"the largest shift of the range over every table within it, MPE·max_ij "
               f"Σ_p|w_ip − w_jp| = {bound:.3g} % (the common zero shared, the 360° stop "
               f"cancelling; JCGM 100 4.3.7: known by its bound): the noise's belt "
               f"[{belt[0]:.4g}, {belt[1]:.4g}] % at the measured range is evaluated at the "
               f"measured range −/+ it; one periodic error of order "
               f"{worst.order} at the bound reaches {200.0 * worst.half_range_rel:.3g} %; the "
               f"positions drawn independent (the former stated reading) do not hold the "
               f"corner table"),
        "table angle errors within the MPE, bound", True, "7.2 (A.4.1 applied to 7.1)")


def nonlinearity_corrected_budget(k_i, theta_deg, table_mpe_arcsec: float, *,
                                  k: float | None = None, tilt_round_coupling=None,
                                  noise: RoundNoise | None = None, time_s=None,
                                  draws: int = RANGE_DRAWS,
                                  tilt_measured=None,
                                  table_reading: str = "stated", stop_deg=None,
                                  zero_deg=None) -> ItemUncertainty:
    """K_l (draft 7.2) corrected for the range's bias, and its u, in %: the stated K_l.

    The draft's K_l = (max K_i − min K_i)/K · 100 % is a range of measured values, and a
    range of noisy values is biased upwards (order statistics: n equal values with errors of
    σ spread by d₂(n)·σ on average, Tippett 1925). :func:`nonlinearity_budget` widens U for it
    (the ``K_rng`` line); here the bias is corrected (:func:`uncertainty.stdev.corrected_range`):
    the errors of the K_i are drawn from the measurement model (JCGM 101 5.1, 7.2), each round
    its table angle error (below) and its count quantisation (triangular ±1 count), and — when
    ``tilt_round_coupling`` gives the rounds' coupling at the A.1 bound ((a_k, b_k), arcsec per
    degree, :func:`gonio.specs.ogam_draft.budget_extra.scale_factor_round_coupling`) — the
    tilt × Earth-rate coupling, the same tilt for every round: relative error
    (a_k cos α − b_k sin α)/3600 with the azimuth α uniform (the bound at an unknown azimuth,
    as K's ``K_tilt`` line) — and, when ``noise`` (:func:`round_noise`, from the 7.4 series)
    and the rounds' times from zeroing to reading ``time_s`` are given, the gyro's own angle
    noise over each round: its angle random walk, normal with u = N√t_k, independent between
    rounds, and the measured Earth-rate compensation's rate error, normal with u = N/√T_s, the
    same for every round, times t_k (relative errors: the angle over θ_k). Where the in-situ
    tilt estimate measured ψ and its azimuth, ``tilt_measured`` (a
    :class:`gonio.specs.ogam_draft.budget_extra.MeasuredRoundTilt`) replaces
    ``tilt_round_coupling``: each K_i is corrected for its own coupling at the measured tilt,
    K_i/(1 + e_k(ψ, γ)) (JCGM 100 3.2.4), and the draws carry the correction's error
    e_k(ψ', γ') − e_k(ψ, γ), (ψ', γ') normal about the estimate with its covariance (JCGM 101
    6.4.8).

    The table's errors (A.4.1 applied to 7.1), stated (``table_reading="stated"``): known by
    the MPE, one curve for every round (the corner — zero at −MPE, every stop at +MPE —
    spreads the K_i alike each session: the scatter cannot see it), so not drawn: the belt
    and correction come from the other errors, and the table's largest shift of the range
    within the MPE (:func:`range_table_bound`; rounds zeroed at ``zero_deg``, stopped at
    ``stop_deg``; None: the draft's 7.1) widens the belt, evaluated at the measured range
    −/+ it (:func:`shifted_belt`; bounded draw by draw: ≥ 95 % for every table within the
    MPE) and is the rectangular line ``K_tab`` in u_c
    (JCGM 100 4.3.7, as K's MPE·Σ|c_p|, :func:`scale_factor_table_bound_rel`). K_l is the
    range whose expected measured range equals the one measured
    (:func:`uncertainty.stdev.corrected_range`; the table's shift, of unknown sign, not
    corrected), ``K_rng`` the estimator's spread. Beside, for comparison: ``independent``
    (each position ±MPE drawn, the zero shared: the former statement; it covered the corner
    35/40 and the worst harmonic 187/200), ``standard`` (each stop's turn ±MPE, the zero
    inside) and ``periodic`` (one curve at the bound, :func:`nonlinearity_table_order`). The
    draft's own reading (7.2) is :func:`nonlinearity_budget`.

    The statement is one 95 % interval, not value ± k·u (skewed and bounded where the true
    range is a few σ of the errors): the range's confidence belt inverted at the measured
    range (:func:`uncertainty.stdev.range_belt_interval`) on the same draws; u_c stays the
    estimator's sd; a value below 0 is stated by the upper end. Beyond the draft.

    Examples
    --------
    Six equal K_i (3600 counts/°), MPE 0.1″, no tilt: measured range 0, the count errors alone
    (±1 count over 60°) give 2.34·10⁻⁴ % on average, so K_l is negative, stated by [0, upper],
    the upper end the belt's at the measured range plus the table's bound 0.926·10⁻⁴ %:

    >>> th = [60.0, 120.0, 180.0, 240.0, 300.0, 360.0]
    >>> b = nonlinearity_corrected_budget([3600.0] * 6, th, 0.1, k=2.0)
    >>> round(b.value * 1e4, 2), [round(x * 1e4, 2) for x in b.interval], round(b.u_c * 1e4, 2)
    (-2.34, [0.0, 3.19], 1.2)
    >>> [c.symbol for c in b.components]
    ['K_rng', 'K_tab']

    One round 0.5 counts/° above five equal ones: nearly the measured range, wider above:

    >>> b = nonlinearity_corrected_budget([3600.0] * 5 + [3600.5], th, 0.1, k=2.0)
    >>> measured = 0.5 / 3600.0833 * 100
    >>> round(measured, 5), round(b.value, 5), [round(x * 1e4, 2) for x in b.interval]
    (0.01389, 0.01377, [133.49, 143.96])
    """
    from uncertainty.stdev import corrected_range

    if table_reading not in TABLE_READINGS:
        raise ValueError(f"table_reading must be one of {', '.join(TABLE_READINGS)}")
    k_i, th, n, kbar, u_tab, u_q = _rounds(k_i, theta_deg, table_mpe_arcsec)
    to_pct = 100.0 / kbar
    rng = np.random.default_rng(RANGE_SEED)
    if table_reading == "stated":          # the table enters as its bound, not drawn
        tab, worst = np.zeros((draws, n)), nonlinearity_table_order(th, table_mpe_arcsec)
    else:
        tab, worst = _range_table_errors(k_i, th, table_mpe_arcsec, u_tab, rng, draws,
                                         table_reading, stop_deg, zero_deg)
    bound = range_table_bound(k_i, th, table_mpe_arcsec, stop_deg, zero_deg)
    quant = rng.triangular(-1.0, 0.0, 1.0, (draws, n)) * (u_q * math.sqrt(6.0))
    k_i, errs, src = _round_errors(k_i, th, {table_reading: (tab + quant) * to_pct}, rng,
                                   draws, tilt_measured, tilt_round_coupling, noise, time_s)
    c = corrected_range(k_i * to_pct, errs[table_reading])
    tab_src = {
        "stated": "the table's angle errors not drawn: they enter as the line K_tab",
        "independent": "table angle at every position the rounds reach (A.4.1 per position, "
                       "rectangular ±MPE, independent, the common zero shared by every "
                       "round)",
        "standard": "table angle at the stops (A.4.1 per stop, independent rectangular ±MPE, "
                    "the zero inside each stop's error)",
        "periodic": f"table angle from one periodic error at the A.4.1 bound, order "
                    f"{worst.order}, phase drawn, rounds correlated"}[table_reading]
    if table_reading == "independent":
        tab_src += (f"; one periodic error at the bound of the order that spreads the K_i most "
                    f"(order {worst.order}) would add up to "
                    f"{200.0 * worst.half_range_rel:.3g} % to the range (a worst case, not "
                    f"stated)")
    lines = [_Line(from_u("K_rng", 0.0, c.u, type="B",
                          source=f"Monte Carlo ({draws} draws, JCGM 101) of the range of the {n} "
                                 f"K_i: {tab_src}, {src}; measured range {c.measured:.4g} %, of "
                                 f"the errors alone {c.noise_range:.4g} %, corrected "
                                 f"{c.value:.4g} %"),
                   "range of the K_i, bias corrected", True, "7.2 (A.4.1, A.1 applied to 7.1)")]
    lo, hi, shift = *c.interval, (bound if table_reading == "stated" else 0.0)
    if table_reading == "stated":   # a table within its MPE moves r by ≤ bound: belt at r ∓ it
        lo, hi = shifted_belt(k_i * to_pct, errs[table_reading], bound)
        lines.append(_range_table_line(bound, c.interval, worst))
    b = _budget("scale_factor_nonlinearity", "%", _in_belt(c.value, lo, hi), lines, k=k,
                interval=(lo, hi))
    return replace(b, nonnegative=True, stated_by_interval=True, k_source=K_SOURCE_BELT,
                   interval_numerical_u=shifted_belt_numerical_u(k_i * to_pct,
                                                                 errs[table_reading], shift),
                   interval_draws=len(errs[table_reading]))


def nonlinearity_calibrated_budget(k_i, theta_deg, round_sensitivity, calibration, *,
                                   k: float | None = None, tilt_round_coupling=None,
                                   noise: RoundNoise | None = None, time_s=None,
                                   draws: int = RANGE_DRAWS,
                                   tilt_measured=None) -> ItemUncertainty:
    """K_l (draft 7.2) of the 7.1 rounds corrected by a calibrated table, bias corrected, in %
    (beyond the draft; its reading at the MPE is :func:`nonlinearity_budget`).

    ``k_i``: the rounds' K_i corrected by the calibration (K's own correction,
    :func:`table_round_sensitivity`, whose matrix ``round_sensitivity`` gives each round's
    sensitivity to the calibration's errors). As :func:`nonlinearity_corrected_budget` with
    the table's errors at the MPE (A.4.1; the standard's and the periodic reading) replaced by
    the calibration's: per draw its errors δe with its covariance, as t with its ν
    (:func:`calibration_error_draws`; a position shared by rounds is one draw), each round
    moved by its sensitivity times δe (the same draws, so the rounds are correlated where
    they share a zeroing position); the count quantum, the tilt coupling (or its correction
    at the measured tilt) and the gyro's noise as there. K_l is the range whose expected
    measured range equals the one measured (:func:`uncertainty.stdev.corrected_range`), the
    statement its belt's 95 % interval (:func:`uncertainty.stdev.range_belt_interval`): one
    line, ``K_rng``.

    A calibration of a table without error, known exactly (u → 0): the draws hold only the
    count quantum, as the MPE reading at a vanishing MPE (other draws: equal within their
    Monte Carlo scatter, 1 %):

    >>> from gonio.specs.ogam_draft.table_calibration import TableCalibration
    >>> th = np.array([60.0, 120.0, 180.0, 240.0, 300.0, 360.0])
    >>> cal = TableCalibration([0, 60, 120, 180, 240, 300], [0.0] * 6, [1e-9] * 6, "t")
    >>> _, s, _, _ = table_round_sensitivity([3600.0] * 6, th, th, np.zeros(6), cal)
    >>> b = nonlinearity_calibrated_budget([3600.0] * 6, th, s, cal, k=2.0)
    >>> q = nonlinearity_corrected_budget([3600.0] * 6, th, 1e-12, k=2.0, table_reading="standard")
    >>> abs(b.value / q.value - 1.0) < 0.01, [c.symbol for c in b.components]
    (True, ['K_rng'])
    """
    from uncertainty.stdev import corrected_range, range_belt_numerical_u

    k_i, th, n, kbar, _, u_q = _rounds(k_i, theta_deg, 0.0)
    to_pct = 100.0 / kbar
    rng = np.random.default_rng(RANGE_SEED)
    tab = calibration_error_draws(calibration, rng, draws) @ np.asarray(round_sensitivity).T
    quant = rng.triangular(-1.0, 0.0, 1.0, (draws, n)) * (u_q * math.sqrt(6.0))
    k_i, errs, src = _round_errors(k_i, th, {"calibrated": (tab + quant) * to_pct}, rng, draws,
                                   tilt_measured, tilt_round_coupling, noise, time_s)
    c = corrected_range(k_i * to_pct, errs["calibrated"])
    sens = np.asarray(round_sensitivity, dtype=float)
    u_tab = float(np.mean(np.sqrt(np.einsum("ij,jk,ik->i", sens,
                                            calibration_draw_cov(calibration), sens)))) * to_pct
    src = (f"table angle at the stops and zeroing positions corrected by the "
           f"{calibration.describe()}, its errors {calibration_draws_text(calibration)} "
           f"(a round's sd from them {u_tab:.3g} %, the mean over rounds), " + src)
    lines = [_Line(from_u("K_rng", 0.0, c.u, type="B",
                          source=f"Monte Carlo ({draws} draws, JCGM 101) of the range of the {n} "
                                 f"K_i: {src}; measured range {c.measured:.4g} %, of the errors "
                                 f"alone {c.noise_range:.4g} %, corrected {c.value:.4g} %"),
                   "range of the K_i (calibrated table), bias corrected", True,
                   "7.2 (A.4.1 calibrated table, A.1 applied to 7.1)")]
    lo, hi = c.interval
    b = _budget("scale_factor_nonlinearity", "%", _in_belt(c.value, lo, hi), lines, k=k,
                interval=(lo, hi))
    return replace(b, nonnegative=True, stated_by_interval=True, k_source=K_SOURCE_BELT,
                   measured=float(c.measured),
                   interval_numerical_u=max(range_belt_numerical_u(k_i * to_pct,
                                                                   errs["calibrated"])),
                   interval_draws=len(errs["calibrated"]))


# --------------------------------------------------------------------------- 7.3, 7.5

def reading_resolution_deg(angles_deg=None, counts_per_deg: float | None = None) -> float:
    """The resolution δ of angle readings, °: one count (1/K) for readings given as counts,
    else the last decimal place the ``gyro_deg`` values carry (10⁻ᵈ, the smallest d ≤ 12 at
    which every value is a whole number of 10⁻ᵈ).

    >>> reading_resolution_deg(counts_per_deg=3600.0) == 1 / 3600
    True
    >>> reading_resolution_deg([0.0, 0.00005, 0.00002])
    1e-05
    """
    if counts_per_deg:
        return 1.0 / float(counts_per_deg)
    x = np.asarray([] if angles_deg is None else angles_deg, dtype=float)
    x = x[np.isfinite(x)]
    for d in range(13):
        y = x * 10.0 ** d
        if np.all(np.abs(y - np.round(y)) <= 1e-9 * np.maximum(1.0, np.abs(y))):
            return 10.0 ** -d
    return 1e-12


def zero_stability_budget(b_s_deg_per_h: float, n_readings: int, *,
                          readings: str = "random_walk", time_s=None,
                          compensation_time_s: float | None = None,
                          k: float | None = None,
                          resolution_deg: float | None = None) -> ItemUncertainty:
    """u(B_s) of B_s = s(M)/T (draft 7.3), °/h: a standard deviation of n readings.

    Type A, u = B_s/√(2ν) (JCGM 100 E.4.3). B_s is stated by its one-sided χ² interval
    [0, s·√(ν/χ²_0.05,ν)] alone (:func:`chi_square_statement`: s is skewed, no coverage
    factor exists for it; results.json ``k`` null, ``U`` the distance to the upper limit; a
    fixed k of the laboratory is not applied). ν depends on how the readings
    relate. The 7.3 readings are angles of an integrating gyro taken without
    re-zeroing, so they are a random walk, not independent samples: the default
    ``readings="random_walk"`` takes ν = ν_eff of the sample variance of a random walk
    (:func:`uncertainty.stdev.random_walk_stdev_dof`: 2.45 for 15 readings), the
    worst case for what the readings tell; ``"independent"`` takes ν = n − 1. With the
    readings' times (``time_s``) and the static phase of a measured Earth-rate
    compensation (``compensation_time_s`` T), whose error is a rate common to all the
    readings, the covariance is min(t_i, t_j) + t_i t_j / T and ν follows from it
    (:func:`uncertainty.stdev.correlated_stdev_dof`; ≈ 1 when the trend dominates).

    Examples
    --------
    15 readings (the draft's 7.3), B_s = 0.002 °/h, independent: u = 0.002/√28 =
    3.78e-4 °/h; interval [0, 0.002·√(14/6.571)] = [0, 0.00292] °/h (χ²_0.05(14) = 6.571),
    U = 0.00092 °/h. As a random walk, ν = 2.451: u = 0.002/√4.902 = 9.03e-4 °/h, stated
    ν 2: [0, 0.002·4.415] = [0, 0.00883] °/h.

    >>> b = zero_stability_budget(0.002, 15, readings="independent")
    >>> round(b.u_c * 1e4, 2), [round(x, 5) for x in b.interval], round(b.U, 5)
    (3.78, [0.0, 0.00292], 0.00092)
    >>> b = zero_stability_budget(0.002, 15)
    >>> round(b.u_c * 1e4, 2), round(b.interval[1], 5), b.to_dict()["k"]
    (9.03, 0.00883, None)
    """
    if readings == "random_walk" and time_s is not None:
        t = np.asarray(time_s, dtype=float)
        t = t - t.min()
        V = np.minimum.outer(t, t)
        if compensation_time_s:
            V = V + np.outer(t, t) / float(compensation_time_s)
        nu = correlated_stdev_dof(V)
        how = (f"readings of a random walk" + (f" with the compensation's rate error "
               f"(T = {compensation_time_s:g} s)" if compensation_time_s else "")
               + f", nu_eff = {nu:.3g}")
    elif readings == "random_walk":
        nu = random_walk_stdev_dof(int(n_readings))
        how = f"readings of a random walk, nu_eff = {nu:.3g}"
    elif readings == "independent":
        nu = int(n_readings) - 1
        how = f"independent readings, nu = {nu}"
    else:
        raise ValueError(f"readings must be random_walk or independent, got {readings!r}")
    s_obs = float(b_s_deg_per_h)
    u_s, s_int, floor_txt = stdev_u(b_s_deg_per_h, nu), s_obs, ""
    if resolution_deg and time_s is not None and len(time_s) >= 2:
        # Resolution floor (JCGM 100 F.2.2.1; EA-4/02 when the scatter is below the
        # resolution): each reading is two floored values, triangular ±δ, u = δ/√6, so
        # s(M)/T is not resolved below b_res = (δ/√6)/T. u(B_s) = max(B_s/√(2ν), b_res) and
        # the χ² interval from max(s, b_res): identical readings never give U = 0, and a
        # budget whose scatter exceeds the resolution is unchanged.
        dur_h = (float(np.max(time_s)) - float(np.min(time_s))) / S_PER_H
        b_res = float(resolution_deg) / math.sqrt(6.0) / dur_h
        if b_res > u_s:
            floor_txt = (f"; floored at the readings' resolution {resolution_deg:.3g}° over T "
                         f"(u = (δ/√6)/T = {b_res:.3g} °/h, JCGM 100 F.2.2.1)")
        u_s, s_int = max(u_s, b_res), max(s_obs, b_res)
    lines = [_Line(from_u("s_B", 0.0, u_s, dof=nu, type="A",
                          source=f"standard deviation of {n_readings} readings, chi-square "
                                 f"({how}){floor_txt}"),
                   "sampling of s(M)", True, "7.3")]
    b = _budget("zero_stability", "deg/h", b_s_deg_per_h, lines, k=None,
                interval=chi_square_statement(s_int, nu))
    # a fixed k of the laboratory is not applied: B_s is stated by its χ² interval
    return replace(b, model_kind="nonlinear", nonnegative=True, stated_by_interval=True,
                   sampler=lambda rng, m: s_int * np.sqrt(nu / rng.chisquare(nu, m)))


def chi_square_statement(s: float, nu: float) -> tuple[float, float]:
    """The one 95 % statement of a dispersion (B_s, R): the one-sided χ² interval of σ,
    [0, s·√(ν/χ²_0.05,ν)] (JCGM 100 E.4.3: ν s²/σ² ~ χ²(ν); :func:`uncertainty.stdev.
    stdev_upper`), with ν as stated (:func:`gonio.result.statement.chi2_nu`: the integer
    part, never ∞, so a reader recomputes the limit from the printed ν, never a narrower one).

    One-sided because the draft's tolerances of B_s and R are upper limits and conformity is
    decided on the same model (:func:`gonio.analysis.conformity.conformance_probability_chi2`,
    JCGM 106 7.3 with this distribution of σ): with a guard band of U = limit − s the guarded
    upper limit is passed exactly when the stated limit is below the tolerance. The same
    statement as the rate specifications' repeatabilities
    (:func:`gonio.result.gum.std_dev_uncertainty`).

    >>> [round(x, 3) for x in chi_square_statement(1.0, 9)]       # χ²_0.05(9) = 3.325
    [0.0, 1.645]
    >>> round(chi_square_statement(1.0, 2.45)[1], 3)              # ν stated 2: √(2/0.1026)
    4.415
    """
    from gonio.result.statement import chi2_nu
    from uncertainty.stdev import stdev_upper

    n = chi2_nu(nu)
    return 0.0, stdev_upper(s, nu if n is None else n, COVERAGE_PROBABILITY)


def zero_stability_model_budget(expected, *, k: float | None = None) -> ItemUncertainty:
    """u(B_s,pop) of the expected zero stability from the fitted noise model, °/h.

    ``expected`` is a :class:`gonio.specs.ogam_draft.zero_stability_noise.ExpectedZeroStability`:
    B_s,pop = √E[s²(M)]/T of the draft's 7.3 readings computed from the five-term fit
    of the instrument's continuous record over the 7.3 rest (the readings' covariance at
    their own times, with the measured compensation's static phase). One Type A line,
    u from the fit's bootstrap uncertainties, ν from Welch–Satterthwaite over the
    terms; k the laboratory's when fixed, else t_95(ν_eff).

    Examples
    --------
    Pure angle random walk N = 0.018 (°/h)√s (0.0003 °/√h), 15 readings 300 s apart
    after a 60 s compensation, u(N) = 0.0002 from 20 bootstrap records:
    V = N²(min(t_i, t_j) + t_i t_j/T_c) (the walk and the compensation's rate error), with
    tr(P·min) = Σt − ΣΣmin/n = 31500 − 20300 = 11200 s and tr(P·ttᵀ)/T_c = (Σt² −
    (Σt)²/n)/60 = 420000 s: E[s²] = 0.018²·431200/14 = 9.979 ((°/h)·s)², B_s,pop =
    √9.979/4200 = 7.52e-4 °/h; u = B_s,pop·u(N)/N = 8.4e-6 °/h, ν = 20 − 1 = 19:

    >>> from types import SimpleNamespace as NS
    >>> from gonio.specs.ogam_draft.zero_stability_noise import expected_zero_stability
    >>> fit = NS(Q=0.0, N=0.018, B=0.0, K=0.0, R=0.0, u_Q=0.0, u_N=0.0002, u_B=0.0,
    ...          u_K=0.0, u_R=0.0, n_bootstrap=20, kind="adev",
    ...          uncertainty_method="bootstrap")
    >>> ez = expected_zero_stability(fit, np.arange(15) * 300.0, 60.0)
    >>> b = zero_stability_model_budget(ez)
    >>> round(b.value * 1e4, 2), round(b.u_c * 1e6, 1), round(b.nu_eff), round(b.k, 2)
    (7.52, 8.4, 19, 2.09)
    """
    lines = [_Line(from_u("m_B", 0.0, float(expected.u), dof=float(expected.dof), type="A",
                          source=f"expected B_s of the readings from the noise model: "
                                 f"{expected.source}"),
                   "noise model of the 7.3 record", True, "7.3 (physical model)")]
    b = _budget("zero_stability", "deg/h", float(expected.value), lines, k=k)
    return replace(b, model_kind="nonlinear", sampler=expected.sample)


def repeatability_budget(r_arcsec: float, n_series: int, n_points: int, *,
                         k: float | None = None) -> ItemUncertainty:
    """u(R) of R = max_i s_i over m points, s_i from n series (draft 7.5), ″.

    Type A, u = R/√(2ν), ν = n − 1. The measurand is max σ_i, the largest of the m
    points' population standard deviations over the series (7.5's R_i estimates σ_i; the
    study's truth is the same, item_coverage). R is stated by one 95 % interval alone (a
    fixed k of the laboratory is not applied): the confidence belt of the largest s
    (R's own distribution, P(R ≤ r) = Π_i F_χ²(ν r²/σ_i²; ν)) united over every pattern
    of the σ_i, :func:`uncertainty.stdev.max_stdev_union_interval`, one-sided because
    7.5's tolerance is an upper limit: [0, R·√(ν/χ²_0.05,ν)], the same limit as
    :func:`chi_square_statement` (whose conformity model the decision uses). Beyond the
    draft, which states no interval.

    The pattern is unknown and the union is needed: the belt along the measured pattern
    (:func:`uncertainty.stdev.max_stdev_belt_interval`) or the equal-σ maximum's is exact
    where the σ_i are alike but, with one position poorer than the rest (σ 1 against eleven
    at 0.6, ν = 9), the belt covers about 73 %, the equal-σ maximum's one-sided (Šidák)
    limit R·√(ν/χ²_q,ν), q = 0.05^(1/m), 22.2 % and the upper end of its central interval
    (:func:`uncertainty.stdev.max_stdev_interval`) 26.7 % (closed form of R's distribution),
    because the other points' s_i scatter up to the largest and the pattern
    looks flat. The union's upper limit is exact at one dominant σ_i and no interval
    valid for every pattern can be lower there; where the σ_i are alike it holds
    max σ_i with nearly 1 and R, the largest of m, lies above max σ_i (the draft's
    value, stated as measured, not corrected for the choice of the largest: no
    correction is unbiased for every pattern) (tests/test_repeatability_interval.py,
    tests/test_repeatability_belt.py).

    Examples
    --------
    The draft's 10 series and 12 points, R = 0.096″ (A.4.4): u = 0.096/√18 = 0.0226″;
    interval [0, 0.096·√(9/3.325)] = [0, 0.1579]″.

    >>> b = repeatability_budget(0.096, 10, 12)
    >>> round(b.u_c, 4), [round(x, 4) for x in b.interval], round(b.U, 4)
    (0.0226, [0.0, 0.1579], 0.0619)
    """
    nu = int(n_series) - 1
    lines = [_Line(from_u("s_R", 0.0, stdev_u(r_arcsec, nu), dof=nu, type="A",
                          source=f"largest of {n_points} standard deviations of {n_series} "
                                 f"series, chi-square with nu = {nu}"),
                   "sampling of s_i", True, "7.5")]
    from uncertainty.stdev import max_stdev_union_interval

    b = _budget("repeatability", "arcsec", r_arcsec, lines, k=k,
                interval=max_stdev_union_interval(r_arcsec, nu, int(n_points),
                                                  COVERAGE_PROBABILITY))
    return replace(b, nonnegative=True, stated_by_interval=True)


# --------------------------------------------------------------------------- 7.4

#: Clause of origin of the physical budget's extra lines (validate.budget_extra_components).
EXTRA_CLAUSES = {
    "K_P": "7.1 (table error at the 7.1 stops carried into E through K)",
    "K_r": "7.1 (scatter of the 7.1 readings carried into E through K)",
    "tilt_E": "clause 7 preamble (Earth-rate compensation) with the A.1 tilt bound",
    "C_te": "clause 7 preamble (Earth-rate compensation) with the A.1 tilt bound",
    "tilt_Em": "clause 7 preamble (Earth-rate compensation), corrected at the tilt measured "
               "in situ (JCGM 100 3.2.4, 5.2)",
}
_ANNEX_NAMES = {"P": ("table positioning", "A.4.1"), "phi_e": ("sensing-plane tilt", "A.4.2"),
                "B_E": ("zero drift", "A.4.3"), "r": ("repeatability", "A.4.4")}


def angle_deviation_budget(annex, value_arcsec: float, *,
                           k_source: str = "welch-satterthwaite") -> ItemUncertainty:
    """E's budget (draft Annex A, or the physical one with extra lines) as an item budget.

    ``annex`` is a :class:`gonio.specs.ogam_draft.budget.AnnexABudget`; its four annex lines keep their
    clauses (A.4.1–A.4.4), the others are ``beyond_draft`` with their clause of origin.

    >>> from gonio.specs.ogam_draft.budget import annex_a_budget
    >>> b = angle_deviation_budget(annex_a_budget(), 0.2, k_source="fixed by laboratory")
    >>> [(c.symbol, c.clause, round(c.u, 4)) for c in b.components]
    [('P', 'A.4.1', 0.0577), ('phi_e', 'A.4.2', 0.0453), ('B_E', 'A.4.3', 0.0866), ('r', 'A.4.4', 0.096)]
    >>> round(b.U, 3), b.k
    (0.297, 2.0)
    """
    comps = []
    for c in annex.gum.contributions:
        if c.symbol in _ANNEX_NAMES:
            name, clause = _ANNEX_NAMES[c.symbol]
            beyond = False
        else:
            name = c.source.split(" [beyond the draft")[0]
            clause, beyond = EXTRA_CLAUSES.get(c.symbol, "beyond the draft"), True
        comps.append(Component(name=name, symbol=c.symbol, u=float(c.contribution),
                               unit="arcsec", type=c.type, distribution=c.distribution,
                               dof=float(c.dof), source=c.source, beyond_draft=beyond,
                               clause=clause))
    return ItemUncertainty(item="angle_deviation", unit="arcsec", value=float(value_arcsec),
                           components=tuple(comps), u_c=float(annex.u_c_arcsec),
                           nu_eff=float(annex.gum.dof), k=float(annex.k), k_source=k_source,
                           gum=annex.gum)


# --------------------------------------------------------------------------- 7.6, 7.7

@dataclass(frozen=True)
class ConditionDeviation:
    """E of one condition of 7.6/7.7 for :func:`consistency_budget`."""

    label: str
    e_arcsec: float          # E_v (signed extreme of the per-point means)
    position_deg: float      # where it was found
    u_single_arcsec: float   # standard deviation of one series' reading there
    n_series: int
    zero_deg: float = 0.0    # the table position its rounds were zeroed at


def _mean_u(c: ConditionDeviation) -> float:
    """u of a condition's mean E_v: one series' u over √(number of series)."""
    return c.u_single_arcsec / math.sqrt(max(c.n_series, 1))


def _series_dof(c: ConditionDeviation) -> float:
    """ν of a condition's mean: n_series − 1, or ∞ with one series (u from 7.5)."""
    return c.n_series - 1 if c.n_series >= 2 else math.inf


def _consistency_lines(a: ConditionDeviation, b: ConditionDeviation, n_conditions: int,
                       mean_u_arcsec: float, f: float, clause: str, table_mpe_arcsec: float,
                       drift_half_width_arcsec: float, scale_factor_u_rel: float,
                       scale_factor_tilt: float) -> list:
    """The budget lines of :func:`consistency_budget` for the extremes a (max E_v) and b
    (min E_v), in the order its sensitivity coefficients and correlation assume: r_a, r_b,
    P_a, P_b, B_a, B_b, C_rng, K_ab, K_tilt; ``f`` converts arcsec to the item's unit,
    ``mean_u_arcsec`` is the conditions' mean u(E_v)."""
    ends = (("a", a), ("b", b))
    return [
        *(_Line(from_u(f"r_{s}", 0.0, _mean_u(c) * f, dof=_series_dof(c), type="A",
                       source=f"mean of {c.n_series} series at {c.label}"),
                f"repeatability, {c.label}", True, clause + " (A.4.4)") for s, c in ends),
        *(_Line(type_b(f"P_{s}", 0.0, table_mpe_arcsec * f, "rectangular",
                       source=f"table at {c.position_deg:g}° ({c.label})"),
                f"table positioning, {c.label}", True, clause + " (A.4.1)") for s, c in ends),
        *(_Line(type_b(f"B_{s}", 0.0, drift_half_width_arcsec * f, "rectangular",
                       source=f"zero drift ({c.label})"),
                f"zero drift, {c.label}", True, clause + " (A.4.3)") for s, c in ends),
        _Line(type_b("C_rng", 0.0, expected_range_factor(n_conditions) * mean_u_arcsec * f,
                     "rectangular",
                     source=f"spread noise alone gives {n_conditions} conditions"),
              "range inflation by noise", True, clause),
        _Line(from_u("K_ab", 0.0, scale_factor_u_rel * abs(a.position_deg - b.position_deg)
                     * ARCSEC_PER_DEG * f, type="B",
                     source=f"u(K)/K = {scale_factor_u_rel:.3g} over "
                            f"{abs(a.position_deg - b.position_deg):g}° between the extremes"),
              "scale factor of 7.1 carried into the spread", True, clause + " (7.1)"),
        _Line(type_b("K_tilt", 0.0, scale_factor_tilt * abs(a.position_deg - b.position_deg)
                     * f, "arcsine",
                     source=f"tilt x Earth-rate coupling of the 7.1 rounds, A_K = "
                            f"{scale_factor_tilt:.3g}″/° at the A.1 bound"),
              "tilt bias of K carried into the spread", True, clause + " (A.1, 7.1)"),
    ]


def consistency_budget(item: str, conditions: Sequence[ConditionDeviation],
                       reference_angle_arcsec: float, scale: float, *,
                       table_mpe_arcsec: float, drift_half_width_arcsec: float,
                       scale_factor_u_rel: float = 0.0, scale_factor_tilt: float = 0.0,
                       curves=None, k: float | None = None) -> ItemUncertainty:
    """u(C) of C = (max E_v − min E_v)/reference · scale (draft 7.6: ppm, 7.7: %).

    Inputs, for the conditions a (max E_v) and b (min E_v): their Type A means
    u_single/√n_series (ν = n_series − 1, or ∞ with one series when u_single comes
    from 7.5); the table positioning error at their positions, rectangular with the
    MPE (A.4.1), *correlated* ρ = 1 when both extremes are at the same table position
    (the same table error enters both and cancels), 0 otherwise; the zero drift of
    each, rectangular (A.4.3), independent; and the spread noise alone gives the n
    conditions, d₂(n)·ū(E_v), rectangular (a range is biased upwards by noise); and the
    scale factor's error carried into the spread: every E_v is computed with the one K of
    7.1, so a relative error δ of K moves E_v by δ·θ at its position θ and the spread by
    δ·(θ_a − θ_b), normal with ``scale_factor_u_rel`` = u(K)/K (0 when a and b are at the
    same position: the term cancels like the table's). On a mount tilted within the A.1
    bound the coupling of the 7.1 rounds biases K too: ``scale_factor_tilt`` (A_K,
    arcsec per degree, :func:`gonio.specs.ogam_draft.budget_extra.scale_factor_tilt_bias`) gives the
    ``K_tilt`` line, arcsine with half-width A_K·|θ_a − θ_b|.

    ``curves`` (one ``(positions_deg, E_arcsec)`` per condition, as ``conditions``) adds the
    *choice of the extreme* (``C_sel``, :func:`extreme_selection_u`): noise can pick a
    curve's other excursion, which no linear line holds. This is the draft's reading, as
    measured; its selection bias (:func:`extreme_selection`) is subtracted in the stated
    reading (:func:`selection_corrected_budget`, :func:`consistency_corrected_budget`).

    Examples
    --------
    7.6 with two rates, E = +0.36″ and −0.36″ at 360°, one series each with u = 0.096″,
    reference 1296000″: the correlated table terms cancel; u² = 2·0.096² + 2·(0.15/√3)² +
    (1.128·0.096/√3)² = 0.03735″² → u = 0.1933″ = 0.1491 ppm; without the correlation the two
    table lines would add 2·(0.1/√3)²: 0.04402″² → 0.1619 ppm.

    >>> cs = [ConditionDeviation("60", 0.36, 360.0, 0.096, 1),
    ...       ConditionDeviation("10", -0.36, 330.0, 0.096, 1)]
    >>> round(consistency_budget("rate_consistency", cs, 1296000.0, 1e6, table_mpe_arcsec=0.1,
    ...                          drift_half_width_arcsec=0.15).u_c, 4)
    0.1619

    >>> cs = [ConditionDeviation("60", 0.36, 360.0, 0.096, 1),
    ...       ConditionDeviation("10", -0.36, 360.0, 0.096, 1)]
    >>> b = consistency_budget("rate_consistency", cs, 1296000.0, 1e6, table_mpe_arcsec=0.1,
    ...                        drift_half_width_arcsec=0.15)
    >>> round(b.u_c, 4), round(b.value, 4)
    (0.1491, 0.5556)

    K known to 0.2 ppm, extremes 30° apart (the first example): 0.2e-6·108000″ in quadrature:

    >>> cs[1] = ConditionDeviation("10", -0.36, 330.0, 0.096, 1)
    >>> kw = dict(table_mpe_arcsec=0.1, drift_half_width_arcsec=0.15)
    >>> u0 = consistency_budget("rate_consistency", cs, 1296000.0, 1e6, **kw).u_c
    >>> u1 = consistency_budget("rate_consistency", cs, 1296000.0, 1e6, **kw,
    ...                         scale_factor_u_rel=0.2e-6).u_c
    >>> round(u1, 4), abs(u1 - math.hypot(u0, 0.2e-6 * 30 * 3600 / 1.296)) < 1e-12
    (0.1627, True)
    """
    cs = list(conditions)
    if len(cs) < 2:
        raise ValueError("a consistency needs at least two conditions")
    e = np.array([c.e_arcsec for c in cs])
    a, b = cs[int(np.argmax(e))], cs[int(np.argmin(e))]
    f = scale / reference_angle_arcsec
    unit = "ppm" if item == "rate_consistency" else "%"
    clause = "7.6" if item == "rate_consistency" else "7.7"

    lines = _consistency_lines(a, b, len(cs), float(np.mean([_mean_u(c) for c in cs])), f,
                               clause, table_mpe_arcsec, drift_half_width_arcsec,
                               scale_factor_u_rel, scale_factor_tilt)
    if curves is not None:
        u_sel = extreme_selection_u(curves, [_mean_u(c) for c in cs], table_mpe_arcsec,
                                    drift_half_width_arcsec, scale_factor_u_rel) * f
        lines.append(_Line(from_u("C_sel", 0.0, u_sel, type="B",
                                  source="Monte Carlo of the signed extremes (JCGM 101)"),
                           "choice of each condition's extreme", True, clause))
    corr = np.eye(len(lines))
    if abs(a.position_deg - b.position_deg) < 1e-6:        # the same table error: ρ = 1
        corr[2, 3] = corr[3, 2] = 1.0
    coeffs = [1.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0, 1.0, 1.0, 1.0][:len(lines)]
    value = (a.e_arcsec - b.e_arcsec) * f
    return replace(_budget(item, unit, value, lines, k=k, correlation=corr, coeffs=coeffs),
                   nonnegative=value >= 0)      # a spread: U above it → its upper bound


def consistency_corrected_budget(item: str, conditions: Sequence[ConditionDeviation],
                                 reference_angle_arcsec: float, scale: float, *,
                                 table_mpe_arcsec: float, drift_half_width_arcsec: float,
                                 scale_factor_u_rel: float = 0.0, scale_factor_tilt: float = 0.0,
                                 curves=None, k: float | None = None,
                                 draws: int = RANGE_DRAWS, tilt_te=None,
                                 table_cal: CalibratedTable | None = None) -> ItemUncertainty:
    """C (draft 7.6: ppm, 7.7: %) corrected for the range's bias, and its u: the stated C.

    The draft's C = (max E_v − min E_v)/reference is a range of measured values, biased
    upwards by their errors; :func:`consistency_budget` widens U for it (the ``C_rng`` line).
    Here the bias is corrected (:func:`uncertainty.stdev.corrected_range`): the errors of the
    E_v are drawn from the measurement model of :func:`consistency_budget`'s lines (JCGM 101
    5.1, 7.2): each condition's mean (normal, u_single/√n_series, A.4.4), the table at its
    position (rectangular ±MPE, A.4.1, the same draw for conditions at the same position),
    its zero drift (rectangular, A.4.3, independent; a ramp over the turn as in
    :func:`extreme_selection`: the drift accumulated from the zeroing at 0° to the extreme's
    position θ_v, the bound's half-width times θ_v/360°), K's error δ·θ_v (normal, u(K)/K, the
    same δ for all, 7.1) and the tilt bias of K A_K·θ_v (arcsine, the same phase for all, A.1)
    — or, where the caller corrected the E_v for K's bias δ at the tilt the in-situ estimate
    measured (E_v + δ·θ_v, JCGM 100 3.2.4; ``tilt_te`` = (u(δ), ν of the estimate's fit)),
    the correction's error, normal u(δ)·θ_v, the same for all (beyond the draft).
    ``table_cal`` (a :class:`CalibratedTable`: the E_v corrected by a calibrated table and read
    with the table-corrected K): the table's draws at the MPE are replaced by the
    calibration's, δe with its covariance and ν (:func:`calibration_error_draws`: normal, or t
    with the calibration's ν), each E_v moved by its coefficients
    (δe(z_v + θ_v) − δe(z_v), the table stopping at z_v + θ_v, and K's part θ_v's,
    :meth:`CalibratedTable.coefficients`; a position shared
    by conditions, and by K's rounds, is one draw), and ``scale_factor_u_rel`` is then K's u
    without its calibrated table line (beyond the draft).
    C is the range whose expected measured range equals the one measured; u is the spread of
    the measured range there (line ``C_rng``, normal), with the choice of each condition's
    extreme (``C_sel``) beside it as in :func:`consistency_budget`; with ``curves`` the
    choice's expected-value shift (:func:`extreme_selection`'s ``bias``, JCGM 101 7.2 through
    the draft's functional) is subtracted too. The statement is one 95 % interval, as
    :func:`nonlinearity_corrected_budget`'s: the range's confidence belt inverted at the
    measured range (:func:`uncertainty.stdev.range_belt_interval`), shifted by the choice's
    bias, with the choice's own k·u_sel added to each of its sides in quadrature; a value
    below 0 is stated by the interval's upper end alone (results.json keeps it signed). Beyond the draft (its own
    reading, the range as measured, is kept beside it).

    Examples
    --------
    Three rates with equal E_v (one series each, u = 0.096″) at one position: the measured
    range 0 is below what the errors alone give (means and drifts, the table cancels), so the
    corrected range is negative (stated by the upper end of its interval [0, 0.366] ppm); with two
    rates 1″ apart C keeps nearly the measured 0.7716 ppm, the interval asymmetric about it:

    >>> cs = [ConditionDeviation(f"{v}", 0.0, 360.0, 0.096, 1) for v in (10, 30, 60)]
    >>> b = consistency_corrected_budget("rate_consistency", cs, 1296000.0, 1e6,
    ...                                  table_mpe_arcsec=0.1, drift_half_width_arcsec=0.15, k=2.0)
    >>> round(b.value, 3), [round(x, 3) for x in b.interval], b.nonnegative, b.k_source
    (-0.169, [0.0, 0.366], True, 'neyman-belt')
    >>> cs = [ConditionDeviation("60", 0.5, 360.0, 0.096, 1),
    ...       ConditionDeviation("10", -0.5, 360.0, 0.096, 1)]
    >>> b = consistency_corrected_budget("rate_consistency", cs, 1296000.0, 1e6,
    ...                                  table_mpe_arcsec=0.1, drift_half_width_arcsec=0.15, k=2.0)
    >>> 0.70 < b.value < 0.7716, [round(x, 2) for x in b.interval]
    (True, [0.48, 1.06])
    """
    from uncertainty.stdev import corrected_range, range_belt_numerical_u

    cs = list(conditions)
    if len(cs) < 2:
        raise ValueError("a consistency needs at least two conditions")
    f = scale / reference_angle_arcsec
    unit = "ppm" if item == "rate_consistency" else "%"
    clause = "7.6" if item == "rate_consistency" else "7.7"
    n = len(cs)
    x = np.array([c.e_arcsec for c in cs])
    pos = np.array([c.position_deg for c in cs])
    u_mean = np.array([c.u_single_arcsec / math.sqrt(max(c.n_series, 1)) for c in cs])
    rng = np.random.default_rng(RANGE_SEED)
    _, at = np.unique(np.round(pos, 6), return_inverse=True)
    if table_cal is not None:      # the calibration's errors, one draw per position
        table = table_cal.draws(rng, draws) @ np.concatenate(
            [table_cal.coefficients([c.position_deg], c.zero_deg) for c in cs]).T
    else:
        table = rng.uniform(-table_mpe_arcsec, table_mpe_arcsec,
                            (draws, int(at.max()) + 1))[:, at]
    ramp = np.clip(pos / 360.0, 0.0, 1.0)          # drift since the zeroing at 0°
    err = (rng.normal(0.0, 1.0, (draws, n)) * u_mean + table
           + rng.uniform(-drift_half_width_arcsec, drift_half_width_arcsec, (draws, n)) * ramp
           + rng.normal(0.0, scale_factor_u_rel, (draws, 1)) * pos * ARCSEC_PER_DEG
           + (rng.normal(0.0, tilt_te[0], (draws, 1)) * pos * ARCSEC_PER_DEG
              if tilt_te is not None else
              np.sin(rng.uniform(0.0, 2.0 * math.pi, (draws, 1))) * scale_factor_tilt * pos))
    c = corrected_range(x * f, err * f)
    kk = float(k) if k is not None else coverage_k(math.inf, COVERAGE_PROBABILITY)
    lines = [_Line(from_u("C_rng", 0.0, c.u, type="B",
                          source=f"Monte Carlo ({draws} draws, JCGM 101) of the range of the "
                                 f"{n} E_v: means, table"
                                 + (f" (corrected by the {table_cal.source}, its errors "
                                    f"{calibration_draws_text(table_cal.calibration)})"
                                    if table_cal else "")
                                 + f", zero drift, K and its tilt "
                                 f"{'correction' if tilt_te is not None else 'bias'}; "
                                 f"measured range {c.measured:.4g} {unit}, of the errors alone "
                                 f"{c.noise_range:.4g} {unit}, corrected {c.value:.4g} {unit}"),
                   "range of the E_v, bias corrected", True,
                   clause + " (A.4.1, A.4.3, A.4.4, 7.1)")]
    value, (lo, hi) = c.value, c.interval
    if curves is not None:
        u_sel, bias = extreme_selection(curves, list(u_mean), table_mpe_arcsec,
                                        drift_half_width_arcsec, scale_factor_u_rel,
                                        table_cal=table_cal, zeros=[c.zero_deg for c in cs])
        lines.append(_selection_line(u_sel * f, bias * f, unit, clause))
        value -= bias * f
        # the belt shifted by the bias, the choice's own spread (normal, k·u_sel) added to
        # each of its sides in quadrature
        w = kk * u_sel * f
        below, above = max(c.value - lo, 0.0), max(hi - c.value, 0.0)
        lo = max(max(value, lo - bias * f) - math.hypot(below, w), 0.0)
        hi = value + math.hypot(above, w)
    b = _budget(item, unit, _in_belt(value, lo, hi), lines, k=k, interval=(lo, hi))
    # the belt's ends' numerical u carried to the stated ends (the shift and the selection's
    # quadrature move each end by at most the belt's own end's change)
    return replace(b, nonnegative=True, stated_by_interval=True, k_source=K_SOURCE_BELT,
                   measured=float(c.measured), interval_draws=len(err),
                   interval_numerical_u=max(range_belt_numerical_u(x * f, err * f)))


def _in_belt(value: float, lo: float, hi: float) -> float:
    """The stated value of a range with its belt interval [lo, hi]: the corrected range,
    signed where it fell below 0 (lo is then 0; stated by the upper end alone), else held
    inside [lo, hi] (against the belt's own Monte Carlo)."""
    return min(value, hi) if value < 0.0 and lo == 0.0 else min(max(value, lo), hi)


def _selection_line(u_sel: float, bias: float, unit: str, clause: str) -> _Line:
    """The ``C_sel`` line (the choice of each condition's extreme, item's unit) and the bias
    subtracted for it, named in its source."""
    return _Line(from_u("C_sel", 0.0, u_sel, type="B",
                        source=f"Monte Carlo of the signed extremes (JCGM 101); selection "
                               f"bias {bias:.4g} {unit} subtracted"),
                 "choice of each condition's extreme, bias corrected", True, clause)


def selection_corrected_budget(draft: ItemUncertainty, curves, u_mean_arcsec, *,
                               reference_angle_arcsec: float, scale: float,
                               table_mpe_arcsec: float, drift_half_width_arcsec: float,
                               scale_factor_u_rel: float = 0.0,
                               k: float | None = None) -> ItemUncertainty:
    """The draft's consistency (:func:`consistency_budget`, C_g of 7.7) corrected for the
    *choice* of each condition's extreme: C − bias, ``bias`` the expected-value shift of the
    draft's functional "E = ± max|E_i|" at the measured curves (:func:`extreme_selection`:
    JCGM 101 7.2, the readings' noise drawn through the functional itself, the mean with the
    extremes chosen afresh less the mean at the estimate's own extreme points), with the
    draft's lines and u (the ``C_sel`` line now names the bias subtracted). A correction below
    zero is a non-negative quantity's estimate below zero (stated by its upper bound alone,
    :func:`gonio.result.statement.below_zero_bound`); when even C − bias + U ≤ 0 it is taken
    as 0, as :func:`consistency_corrected_budget`. The draft's reading is kept ``beside``.

    Examples
    --------
    Two orientations whose first curve has two excursions of nearly one size (+0.40″ at 30°,
    −0.38″ at 60°): noise picks either, and where it picks −0.38″ the spread to the other
    curve's −0.8″ shrinks, so the draft's C is low on average; the corrected C lies above it:

    >>> tie = [([30.0, 60.0], [0.4, -0.38]), ([30.0, 60.0], [-0.8, 0.0])]
    >>> cs = [ConditionDeviation("a", 0.4, 30.0, 0.05, 1),
    ...       ConditionDeviation("b", -0.8, 30.0, 0.05, 1)]
    >>> kw = dict(table_mpe_arcsec=0.1, drift_half_width_arcsec=0.0)
    >>> d = consistency_budget("pointing_consistency", cs, 1296000.0, 100.0, curves=tie, **kw)
    >>> c = selection_corrected_budget(d, tie, [0.05, 0.05], reference_angle_arcsec=1296000.0,
    ...                                scale=100.0, **kw)
    >>> bias = extreme_selection(tie, [0.05, 0.05], 0.1, 0.0)[1] * 100 / 1296000
    >>> math.isclose(c.value, d.value - bias), c.value > d.value, c.u_c == d.u_c
    (True, True, True)
    """
    f = scale / reference_angle_arcsec
    u_sel, bias = extreme_selection(curves, list(u_mean_arcsec), table_mpe_arcsec,
                                    drift_half_width_arcsec, scale_factor_u_rel)
    clause = "7.6" if draft.item == "rate_consistency" else "7.7"
    ln = _selection_line(u_sel * f, bias * f, draft.unit, clause)
    comps = tuple(replace(c, name=ln.name, source=ln.q.source) if c.symbol == "C_sel" else c
                  for c in draft.components)
    kk = float(k) if k is not None else draft.k
    value = draft.value - bias * f
    value = value if value + kk * draft.u_c > 0 else 0.0
    # the same additive model about the corrected value (its JCGM 101 draws centre there)
    return replace(draft, value=float(value), components=comps, nonnegative=True,
                   model=replace(draft.model, value=float(value)),
                   gum=replace(draft.gum, value=float(value)), beside=draft)


def extreme_selection_u(curves, u_mean_arcsec, table_mpe_arcsec: float,
                        drift_half_width_arcsec: float, scale_factor_u_rel: float = 0.0,
                        draws: int = 4000) -> float:
    """u (arcsec) of :func:`extreme_selection` (the first of its pair).

    >>> far = [([30.0, 60.0], [0.9, 0.1]), ([30.0, 60.0], [-0.8, 0.0])]
    >>> extreme_selection_u(far, [0.05, 0.05], 0.1, 0.0)
    0.0
    """
    return extreme_selection(curves, u_mean_arcsec, table_mpe_arcsec, drift_half_width_arcsec,
                             scale_factor_u_rel, draws)[0]


def extreme_selection(curves, u_mean_arcsec, table_mpe_arcsec: float,
                      drift_half_width_arcsec: float, scale_factor_u_rel: float = 0.0,
                      draws: int = 4000, table_cal: CalibratedTable | None = None,
                      zeros=None) -> tuple[float, float]:
    """(u, bias), arcsec, of the spread max E_v − min E_v from the *choice* of each E_v
    (7.6, 7.7).

    E_v is the signed value of largest magnitude of condition v's curve (the draft's
    "E = ± max |E_i|", :func:`gonio.specs.ogam_draft.items.signed_extreme`). Each draw
    perturbs every curve as the budget's lines say: each point by its mean's u
    (``u_mean_arcsec`` per condition, normal, independent), the table at each position
    (rectangular ±MPE, the same for every condition at that position), K (normal
    ``scale_factor_u_rel``·θ, the same for all) and each condition's zero drift (a
    rectangular ramp over its points). The spread is taken once with the extremes chosen
    afresh (the draft's functional) and once at the estimate's own extreme points (the
    linear model of the other lines), both between the estimate's largest and smallest
    condition (which condition is largest is the range's part, the ``C_rng`` line); u² is
    the first variance minus the second, 0 when noise never changes a choice. The choice is
    not only a spread: taking the larger of two excursions is biased away from zero, so the
    draft's functional's expectation differs from the linear one. Propagating the readings'
    noise through the functional itself (JCGM 101 5.1, 7.2: the model is the draft's, with
    its choice) gives that difference as ``bias`` = mean(free) − mean(held) over draws of
    the noise alone (the means' u; the table, drift and K lines are one offset per
    calibration, shared by the truth as mounted, so they make no selection bias of the
    estimator). It is the plug-in (bootstrap) estimate at the measured curves; the stated
    readings subtract it (:func:`consistency_corrected_budget` for C_v,
    :func:`selection_corrected_budget` for C_g) and the draft's reading, as measured, is kept
    beside them. At curves where noise has already flipped the choice the plug-in corrects
    the other way (a discontinuous functional's bootstrap bias), which the choice's spread in
    u (``C_sel``) allows for. Fixed seed: the same curves give the same (u, bias).
    A calibration with ν (t draws, ν ≥ 3): u is the larger of its value at the t draws and at
    normal draws of the same u (the same z, the χ² apart: common random numbers), since a
    difference of two sample variances of heavy-tailed draws is not monotone in ν at a
    Monte Carlo's size and a less well known table must not narrow the interval.
    ``table_cal`` (a :class:`CalibratedTable`) with each curve's zeroing position ``zeros``:
    the table's draws are the calibration's (:func:`consistency_corrected_budget`).

    >>> far = [([30.0, 60.0], [0.9, 0.1]), ([30.0, 60.0], [-0.8, 0.0])]
    >>> extreme_selection(far, [0.05, 0.05], 0.1, 0.0)
    (0.0, 0.0)
    >>> tie = [([30.0, 60.0], [0.4, -0.38]), ([30.0, 60.0], [-0.8, 0.0])]
    >>> u, bias = extreme_selection(tie, [0.05, 0.05], 0.1, 0.0)
    >>> 0.3 < u < 0.5, bias < -0.1
    (True, True)
    """
    nu = calibration_draw_dof(table_cal.calibration) if table_cal is not None else None
    args = (curves, u_mean_arcsec, table_mpe_arcsec, drift_half_width_arcsec,
            scale_factor_u_rel, draws, zeros)
    u_sel, bias = _extreme_selection_draws(*args, table_cal)
    if nu is None:
        return u_sel, bias
    # a calibration with ν: the choice's spread at the normal draws of the same u too, the
    # larger taken (the t's tails may only widen it; the bias is the noise's alone)
    normal = replace(table_cal, calibration=replace(table_cal.calibration, dof=None))
    return max(u_sel, _extreme_selection_draws(*args, normal)[0]), bias


def _extreme_selection_draws(curves, u_mean_arcsec, table_mpe_arcsec: float,
                             drift_half_width_arcsec: float, scale_factor_u_rel: float,
                             draws: int, zeros, table_cal) -> tuple[float, float]:
    """:func:`extreme_selection`'s (u, bias) from one set of draws (seed fixed; the table's
    draws of ``table_cal``, or at its MPE)."""
    rng = np.random.default_rng(20240607)
    pos_all = np.unique(np.concatenate([np.asarray(p, dtype=float) for p, _ in curves]))
    if table_cal is not None:
        de = table_cal.draws(rng, draws)
    else:
        table = rng.uniform(-table_mpe_arcsec, table_mpe_arcsec, (draws, pos_all.size))
    dk = rng.normal(0.0, scale_factor_u_rel, draws) if scale_factor_u_rel > 0 \
        else np.zeros(draws)
    free, held, free_n, held_n = [], [], [], []
    rows = np.arange(draws)
    for v, ((pos, e), u) in enumerate(zip(curves, u_mean_arcsec)):
        pos = np.asarray(pos, dtype=float)
        e = np.asarray(e, dtype=float)
        ok = ~np.isnan(e)
        pos, e = pos[ok], e[ok]
        ramp = np.arange(1, e.size + 1) / e.size
        noisy = e + rng.normal(0.0, u, (draws, e.size))
        tab = (de @ table_cal.coefficients(pos, (zeros or [0.0] * len(curves))[v]).T
               if table_cal is not None else table[:, np.searchsorted(pos_all, pos)])
        sim = (noisy + tab
               + dk[:, None] * pos * ARCSEC_PER_DEG
               + rng.uniform(-drift_half_width_arcsec, drift_half_width_arcsec,
                             draws)[:, None] * ramp)
        j = int(np.argmax(np.abs(e)))
        free.append(sim[rows, np.argmax(np.abs(sim), axis=1)])
        held.append(sim[:, j])
        free_n.append(noisy[rows, np.argmax(np.abs(noisy), axis=1)])
        held_n.append(noisy[:, j])
    e_hat = np.array([float(np.asarray(e, dtype=float)[~np.isnan(e)][
        int(np.argmax(np.abs(np.asarray(e, dtype=float)[~np.isnan(e)])))]) for _, e in curves])
    a, b = int(np.argmax(e_hat)), int(np.argmin(e_hat))
    free, held = np.array(free), np.array(held)
    c_free = free[a] - free[b]        # which condition is max/min: the C_rng line's part
    c_held = held[a] - held[b]
    free_n, held_n = np.array(free_n), np.array(held_n)
    bias = (free_n[a] - free_n[b]).mean() - (held_n[a] - held_n[b]).mean()
    return (float(math.sqrt(max(0.0, c_free.var() - c_held.var()))), float(bias))
