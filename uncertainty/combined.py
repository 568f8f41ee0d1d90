"""The coverage factor of an additive budget from its combined distribution (JCGM 101).

The GUM's k = t_p(ν_eff) (JCGM 100 G.4) takes the output Y as normal, or as a scaled and
shifted t with the Welch–Satterthwaite ν_eff. That holds when no line of the budget
dominates with a distribution far from normal (JCGM 100 G.2.3; JCGM 101 5.7: the conditions
for the GUM framework's interval). Where a rectangular, triangular, arcsine or product line
carries much of u_c², the distribution of Y is their convolution with the rest, and its
95 % half-width is not t_p(ν_eff)·u_c: an arcsine alone has a 95 % half-width of
0.997·A = 1.41·u, a rectangular 1.645·u, against 1.96·u.

- :func:`non_normal_share` — the fraction of u_c² carried by lines whose distribution is
  neither normal nor a Type A t;
- :func:`needs_combined_k` — the rule: k from the combined distribution when that share
  exceeds :data:`NON_NORMAL_SHARE` (1/4);
- :func:`combined_coverage_factor` — k_p = U_p/u_c, U_p the half-width about y of the
  interval holding probability p of the JCGM 101 distribution of Y = y + Σ c_i (X_i − x_i):
  the convolution of the lines, each drawn in its own distribution (Type A as scaled and
  shifted t with its ν, JCGM 101 6.4.9; correlated lines jointly, 6.4.8), evaluated by a
  Monte Carlo of fixed M and seed (JCGM 101 7.2), so the same budget gives the same k.

Why 1/4: at a share of 1/4 the combined distribution's k of a normal plus one arcsine (or
one rectangular) line is 1.950 (1.953) against 1.960, within 0.5 %; at a share of 1/2 the
GUM's k overstates by 3 % (1.90), at 0.97 (an arcsine table line at its bound) by 29 %
(1.52). Below the share the GUM's k is kept, so a budget of near-normal lines keeps its
t_p(ν_eff) and its ν_eff. Where every Type A line has many degrees of freedom the rule
therefore moves k by less than 0.5 % where it switches. A Type A line of few degrees of
freedom is another matter: the GUM folds it into ν_eff (Welch–Satterthwaite), JCGM 101
draws it as a scaled-and-shifted t (6.4.9), and the two differ whatever the share (a t₂
line at 11 % of u_c² beside a normal rest: WS k 1.97, the t draws 2.31); at the switch k
then moves by that difference, towards JCGM 101's, the better model (JCGM 101 5.7, 6.4.9).

This module never imports ``gonio``.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from scipy import special

from uncertainty.montecarlo import sample_inputs
from uncertainty.propagation import combined_uncertainty
from uncertainty.quantities import InputQuantity

__all__ = ["NON_NORMAL_SHARE", "COMBINED_TRIALS", "NORMAL_LIKE", "GRID_PER_UC",
           "non_normal_share", "needs_combined_k", "combined_coverage_factor",
           "line_cdf", "convolution_coverage_factor", "monte_carlo_coverage_factor"]

#: The share of u_c² above which the lines that are not normal decide k (see the module
#: docstring for why 1/4).
NON_NORMAL_SHARE = 0.25
#: Draws of :func:`combined_coverage_factor` (JCGM 101 7.2.2: M = 10⁶ gives a 95 % interval
#: to one or two significant digits; here k's sampling error is about 0.1 %).
COMBINED_TRIALS = 1_000_000
#: Distributions the GUM's t_p(ν_eff) models: normal Type B, Type A t (JCGM 100 G.4).
NORMAL_LIKE = ("normal", "t")
#: Grid steps per u_c of :func:`convolution_coverage_factor` (each line rounded to the grid
#: adds h²/12 to the variance: with h = u_c/1000 and ten lines, k moves by under 10⁻⁶; an arcsine alone, read linearly
#: between cells at its singular ends, is within 10⁻⁵ of its closed form).
GRID_PER_UC = 1000
#: Half-span of a line of unbounded support on the grid, in u_c (a t line's tails beyond it
#: are kept as mass at the grid's ends, so nothing is lost from the total).
SPAN_UC = 200.0


def _contributions(inputs: Sequence[InputQuantity], coeffs: Sequence[float]) -> np.ndarray:
    return np.array([float(c) * q.u for q, c in zip(inputs, coeffs)], dtype=float)


def _non_normal(inputs: Sequence[InputQuantity]) -> np.ndarray:
    return np.array([q.distribution not in NORMAL_LIKE for q in inputs], dtype=bool)


def _correlated(n: int, correlation) -> np.ndarray:
    """Which of ``n`` lines have a non-zero correlation with another line."""
    if correlation is None:
        return np.zeros(n, dtype=bool)
    r = np.asarray(correlation, dtype=float)
    return ((r != 0) & ~np.eye(n, dtype=bool)).any(axis=0)


def non_normal_share(inputs: Sequence[InputQuantity], coeffs: Sequence[float],
                     correlation=None) -> float:
    """The fraction of u_c² (JCGM 100 5.1.2, 5.2.2) carried by the lines whose distribution
    is not in :data:`NORMAL_LIKE`: c_Nᵀ V_NN c_N / cᵀ V c over those lines N, with their
    correlations (two correlated lines that cancel carry little); 0 when u_c is 0.

    >>> from uncertainty.quantities import type_b, from_u
    >>> q = [type_b("A", 0.0, math.sqrt(2.0), "arcsine"), from_u("s", 0.0, 1.0, dof=5)]
    >>> round(non_normal_share(q, [1.0, 1.0]), 12)
    0.5

    Two rectangular lines entering with +1 and −1 and fully correlated cancel:

    >>> r = [[1, 1, 0], [1, 1, 0], [0, 0, 1]]
    >>> q = [type_b("a", 0.0, 1.0, "rectangular"), type_b("b", 0.0, 1.0, "rectangular"),
    ...      from_u("s", 0.0, 0.1)]
    >>> non_normal_share(q, [1.0, -1.0, 1.0], r)
    0.0
    """
    cs = [float(c) for c in coeffs]
    uc = combined_uncertainty(cs, [q.u for q in inputs], correlation=correlation)
    if not uc > 0:
        return 0.0
    nn = _non_normal(inputs)
    ci = _contributions(inputs, cs)[nn]
    if correlation is None:
        non = float(np.sum(ci * ci))
    else:
        r = np.asarray(correlation, dtype=float)[np.ix_(nn, nn)]
        non = float(ci @ r @ ci)
    return max(non, 0.0) / uc ** 2


def needs_combined_k(inputs: Sequence[InputQuantity], coeffs: Sequence[float],
                     correlation=None, share: float = NON_NORMAL_SHARE) -> bool:
    """The rule: k of an additive budget comes from its combined distribution
    (:func:`combined_coverage_factor`, JCGM 101) when its lines that are not normal carry
    more than ``share`` of u_c² (:func:`non_normal_share`); otherwise the GUM's t_p(ν_eff)
    (JCGM 100 G.4) stands. JCGM 101 5.7 requires, for the GUM's interval, an output
    adequately approximated by a normal or scaled-shifted t distribution: a dominant
    non-normal line breaks that (JCGM 100 G.2.3).

    A line that is not normal and correlated with another cannot be drawn in its own
    distribution (JCGM 101 6.4.8 gives correlated inputs jointly as a multivariate normal
    only): where such a line is in the budget the convolution would not be the budget's, so
    the GUM's k stands.

    >>> from uncertainty.quantities import type_b, from_u
    >>> needs_combined_k([type_b("P", 0.0, 1.0, "arcsine"), from_u("s", 0.0, 0.1)], [1, 1])
    True
    >>> needs_combined_k([type_b("P", 0.0, 0.1, "rectangular"), from_u("s", 0.0, 1.0)], [1, 1])
    False
    >>> needs_combined_k([type_b("P", 0.0, 1.0, "arcsine"), from_u("s", 0.0, 0.1)], [1, 1],
    ...                  [[1.0, 0.5], [0.5, 1.0]])
    False
    """
    if (_non_normal(inputs) & _correlated(len(inputs), correlation)).any():
        return False
    return non_normal_share(inputs, coeffs, correlation) > share


def combined_coverage_factor(inputs: Sequence[InputQuantity], coeffs: Sequence[float], *,
                             p: float = 0.95, trials: int = COMBINED_TRIALS, seed: int = 0,
                             correlation=None) -> float:
    """k_p = U_p/u_c of Y = y + Σ c_i (X_i − x_i) from its combined distribution (JCGM 101).

    The distribution of Y is the convolution of its lines, each in its own distribution
    (Type A as scaled and shifted t with its ν, JCGM 101 6.4.9). Where every line's
    distribution function is known in closed form (:func:`line_cdf`) and no line is
    correlated with another except normal ones (which combine into one normal), the
    convolution is computed numerically (:func:`convolution_coverage_factor`, JCGM 101 5.4:
    the propagation of distributions by any method that is accurate enough): exact to about
    10⁻⁵ and the same on every machine. Otherwise the JCGM 101 Monte Carlo
    (:func:`monte_carlo_coverage_factor`, ``trials`` draws from generator ``seed``).

    >>> from uncertainty.quantities import type_b
    >>> k = combined_coverage_factor([type_b("P", 0.0, 1.0, "arcsine")], [1.0])
    >>> abs(k - math.sqrt(2.0) * math.sin(math.pi * 0.95 / 2)) < 2e-5     # 1.409854
    True
    """
    merged = _convolution_lines(inputs, coeffs, correlation)
    if merged is None:
        return monte_carlo_coverage_factor(inputs, coeffs, p=p, trials=trials, seed=seed,
                                           correlation=correlation)
    return convolution_coverage_factor(merged, p=p)


def _h_product(x: np.ndarray, a: float, lo: float, hi: float) -> np.ndarray:
    """∫_lo^hi P(a·U·w ≤ x) dw for x ≥ 0, U uniform on [−1, 1], 0 ≤ lo ≤ hi: below w = x/a
    the product's interval lies under x (probability 1), above it the probability is
    1/2 + x/(2aw)."""
    m = np.clip(x / a, lo, hi)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_term = np.where(m > 0, (x / (2.0 * a)) * np.log(hi / np.where(m > 0, m, 1.0)), 0.0)
    return (m - lo) + 0.5 * (hi - m) + log_term


def line_cdf(distribution: str, x, *, scale: float, half_width: float | None = None,
             dof: float = math.inf, beta: float | None = None) -> np.ndarray:
    """The distribution function at ``x`` of one zero-mean line c·(X − x): ``scale`` its
    standard uncertainty |c|·u (the t's scale for Type A, JCGM 101 6.4.9), ``half_width``
    |c|·a for the bounded ones (JCGM 100 4.3.7–4.3.9, JCGM 101 6.4.2–6.4.6).

    - normal Φ(x/u); Type A t: the t distribution function of ν at x/u;
    - rectangular (x + a)/2a; triangular; arcsine 1/2 + arcsin(x/a)/π;
    - rectangular-shifted-product a·U·W, W uniform on [1 − 2β, 1] (β = 1: the product of two
      rectangulars, F(x) = 1/2 + (x/2a)(1 + ln(a/|x|))): the mixture over W of rectangulars.

    >>> round(float(line_cdf("rectangular-product", 0.5, scale=1/3, half_width=1.0)), 6)
    0.923287
    >>> round(0.5 + 0.25 * (1 + math.log(2.0)), 6)
    0.923287
    """
    x = np.asarray(x, dtype=float)
    if distribution == "normal":
        return special.ndtr(x / scale)
    if distribution == "t":
        return special.stdtr(dof, x / scale)
    a = float(half_width)
    if distribution == "rectangular":
        return np.clip((x + a) / (2.0 * a), 0.0, 1.0)
    z = np.clip(x / a, -1.0, 1.0)
    if distribution == "triangular":
        return np.where(z < 0, 0.5 * (1.0 + z) ** 2, 1.0 - 0.5 * (1.0 - z) ** 2)
    if distribution == "arcsine":
        return 0.5 + np.arcsin(z) / math.pi
    if distribution in ("rectangular-product", "rectangular-shifted-product"):
        b = 1.0 if distribution == "rectangular-product" else float(beta)
        lo = 1.0 - 2.0 * b
        ax = np.abs(x)
        if lo >= 0.0:
            f = _h_product(ax, a, lo, 1.0) / (1.0 - lo)
        else:           # W < 0 mirrors a·U·W onto a·U·|W|: |W| on [0, −lo] counts twice
            f = (_h_product(ax, a, 0.0, 1.0) + _h_product(ax, a, 0.0, -lo)) / (1.0 - lo)
        return np.where(x >= 0, f, 1.0 - f)
    raise ValueError(f"no distribution function for {distribution!r}")


def _convolution_lines(inputs, coeffs, correlation):
    """The lines as (distribution, scale, half-width, ν, β) for :func:`line_cdf`, with the
    correlated normal lines combined into one normal of variance c_Sᵀ V_SS c_S (a sum of
    jointly normal variables is normal, JCGM 101 6.4.8); None where the convolution cannot be
    the budget's (a correlated line that is not normal, a t of ν < 2, a trapezoid's
    parameter missing)."""
    cs = [float(c) for c in coeffs]
    n = len(inputs)
    corr = _correlated(n, correlation)
    out, joint = [], []
    for i, (q, c) in enumerate(zip(inputs, cs)):
        if c == 0 or q.u == 0:
            continue
        dist = q.drawn_as                   # as the Monte Carlo draws it
        if corr[i]:
            if dist != "normal":
                return None
            joint.append(i)
            continue
        if dist == "t" and q.dof < 2:
            return None
        beta = q.shape_beta
        if dist == "trapezoidal":       # the sum of two rectangulars (JCGM 101 6.4.4.4)
            h = abs(c) * q.half_width
            for w in (0.5 * h * (1.0 + beta), 0.5 * h * (1.0 - beta)):
                if w > 0:
                    out.append(("rectangular", w / math.sqrt(3.0), w, math.inf, None))
            continue
        out.append((dist, abs(c) * q.u, abs(c) * q.half_width if q.half_width else None,
                    q.dof, beta))
    if joint:
        cj = np.array([cs[i] * inputs[i].u for i in joint])
        r = np.asarray(correlation, dtype=float)[np.ix_(joint, joint)]
        out.append(("normal", math.sqrt(max(float(cj @ r @ cj), 0.0)), None, math.inf, None))
    out = [ln for ln in out if ln[1] > 0]
    return out or None


def convolution_coverage_factor(lines, p: float = 0.95) -> float:
    """k_p = U_p/u_c of the sum of independent zero-mean symmetric lines, each given as
    (distribution, scale, half-width, ν, β) (:func:`line_cdf`), by numerical convolution.

    Each line is put on one grid of step h = u_c/:data:`GRID_PER_UC` as the probabilities of
    its cells [(j − ½)h, (j + ½)h] from its distribution function (the end cells take the
    tails, so no probability is lost); the cell probabilities are convolved (FFT), and the
    sum's distribution function is read between the cells' edges linearly. The sum of
    symmetric lines is symmetric about 0, so U_p is its (1 + p)/2 quantile (JCGM 101 7.7:
    the probabilistically symmetric interval). u_c is √Σ u_i², with a t line's u its scale
    as in the GUM (JCGM 100 G.4; the t's own variance ν/(ν − 2)·u² is wider, as in the
    Monte Carlo's draws).

    A normal plus an arcsine of equal u (share 1/2): quadrature of Φ over the arcsine's
    phase gives k = 1.901132 (tests/test_k_combined_coverage.py checks shares 0.3–1 to 10⁻⁴):

    >>> lines = [("normal", 1.0, None, math.inf, None),
    ...          ("arcsine", 1.0, math.sqrt(2.0), math.inf, None)]
    >>> round(convolution_coverage_factor(lines), 4)
    1.9011
    """
    uc = math.sqrt(sum(ln[1] ** 2 for ln in lines))
    if not uc > 0:
        raise ValueError("u_c is 0: no coverage factor")
    h = uc / GRID_PER_UC
    pmf = np.ones(1)
    for dist, scale, half, dof, beta in lines:
        if dist == "normal":
            reach = min(SPAN_UC * uc, 40.0 * scale)
        elif dist == "t":           # to a tail of 10⁻¹⁰, at most SPAN_UC·u_c
            reach = min(SPAN_UC * uc, scale * float(special.stdtrit(dof, 1.0 - 1e-10)))
        else:
            reach = half
        m = max(int(math.ceil(reach / h)) + 1, 1)
        edges = (np.arange(-m, m) + 0.5) * h               # 2m interior edges, 2m + 1 cells
        f = line_cdf(dist, edges, scale=scale, half_width=half, dof=dof, beta=beta)
        cells = np.diff(np.concatenate(([0.0], f, [1.0])))
        cells = np.maximum(0.5 * (cells + cells[::-1]), 0.0)   # symmetric to the last bit
        size = pmf.size + cells.size - 1
        nfft = 1 << (size - 1).bit_length()
        pmf = np.fft.irfft(np.fft.rfft(pmf, nfft) * np.fft.rfft(cells, nfft), nfft)[:size]
        pmf = np.maximum(pmf, 0.0)
    pmf /= pmf.sum()
    half_n = pmf.size // 2                              # cell half_n is y = 0
    cdf = np.cumsum(pmf)                                # F at the upper edge of each cell
    target = 0.5 * (1.0 + p)
    j = int(np.searchsorted(cdf, target))
    below = cdf[j - 1] if j > 0 else 0.0
    frac = (target - below) / pmf[j] if pmf[j] > 0 else 0.5
    y_p = (j - half_n - 0.5 + frac) * h
    return float(y_p / uc)


def monte_carlo_coverage_factor(inputs: Sequence[InputQuantity], coeffs: Sequence[float], *,
                             p: float = 0.95, trials: int = COMBINED_TRIALS, seed: int = 0,
                             correlation=None) -> float:
    """k_p = U_p/u_c of Y = y + Σ c_i (X_i − x_i) by a JCGM 101 Monte Carlo (the second
    algorithm beside :func:`convolution_coverage_factor`; any budget, correlated lines too).

    The lines are drawn in their own distributions (:func:`uncertainty.montecarlo.
    sample_inputs`: JCGM 101 6.4; Type A as scaled and shifted t, 6.4.9; correlated lines
    jointly, 6.4.8) with ``trials`` draws from generator ``seed`` (fixed: the same budget
    gives the same k, JCGM 101 7.2). U_p is the half-width of the interval y ± U_p that holds
    the fraction p of the draws: the pM-th smallest |Y − y| (JCGM 101 7.7.1's q = pM). For
    lines symmetric about their estimates — every line of an additive budget here — the PDF
    of Y is symmetric about y, and y ± U_p is JCGM 101 7.7's probabilistically symmetric
    interval; taking |Y − y| uses the draws of both tails at once. u_c is the GUM's
    (JCGM 100 5.1.2, 5.2.2: √(cᵀVc)), so that U = k·u_c is U_p.

    An arcsine line alone: U_p = A·sin(π·p/2) = 0.99692·A, k = √2·0.99692 = 1.4099; a
    rectangular alone: U_p = p·a, k = √3·0.95 = 1.6454; a normal alone: 1.9600:

    >>> from uncertainty.quantities import type_b
    >>> exact = {"arcsine": math.sqrt(2.0) * math.sin(math.pi * 0.95 / 2),
    ...          "rectangular": math.sqrt(3.0) * 0.95, "normal": 1.959964}
    >>> [abs(monte_carlo_coverage_factor([type_b("X", 0.0, 1.0, d, k=1)], [1.0]) - e) < 0.003
    ...  for d, e in exact.items()]
    [True, True, True]
    """
    m = int(trials)
    if m < 2:
        raise ValueError(f"trials must be >= 2, got {trials}")
    cs = [float(c) for c in coeffs]
    uc = combined_uncertainty(cs, [q.u for q in inputs], correlation=correlation)
    if not uc > 0:
        raise ValueError("u_c is 0: no coverage factor")
    xs = sample_inputs(inputs, m, np.random.default_rng(seed), correlation)
    dy = np.zeros(m)
    for c, q, x in zip(cs, inputs, xs):
        if c:
            # c·(x − x_i) in place on the line's own draws: the same operations on the same
            # operands as the expression, so the same bits, without two temporaries of M
            x -= q.value
            x *= c
            dy += x
    pm = p * m                                 # q = pM, or ⌊pM + 1/2⌋ (JCGM 101 7.7.1)
    q_p = int(round(pm)) if abs(pm - round(pm)) < 1e-9 else int(math.floor(pm + 0.5))
    a = np.abs(dy)
    u_p = float(np.partition(a, q_p - 1)[q_p - 1])
    return u_p / uc
