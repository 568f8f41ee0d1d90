"""Uncertainty of a standard deviation and of a range (domain-free).

- :func:`stdev_interval` — the χ² confidence interval of a population standard
  deviation σ from a sample standard deviation s with ν = n − 1 degrees of
  freedom (normal population): ν s²/σ² ~ χ²(ν). The distribution of s is skewed,
  so the interval is stated, not only a standard uncertainty.
- :func:`stdev_upper` — the one-sided χ² upper confidence limit of σ,
  s·√(ν/χ²_{1−p}(ν)): P(σ ≤ limit) = p, the interval [0, limit] of a dispersion
  whose conformity is judged against an upper tolerance.
- :func:`stdev_u` — the standard uncertainty of s as an estimate of σ,
  u(s) ≈ s/√(2ν) (JCGM 100 E.4.3, Table E.1: relative uncertainty of an
  experimental standard deviation).
- :func:`max_stdev_interval` — the same for the largest of m sample standard
  deviations (each with ν) as an estimate of the largest σ_i: the quantiles are
  those of the maximum of m independent χ² variables (Šidák: probability
  p^(1/m) per member), since picking the largest s biases it upwards. Exact only
  when the σ_i are equal; below max σ_i where one σ_i dominates.
- :func:`max_stdev_cdf` — the exact distribution of the largest of m independent
  sample standard deviations, P(max s_i ≤ x) = Π_i F_χ²(ν x²/σ_i²; ν).
- :func:`max_stdev_quantile` — its quantiles.
- :func:`max_stdev_belt_interval` — the Neyman confidence belt of max σ_i along a
  given pattern of the σ_i (σ_i = θ·π_i), inverted at the measured maximum.
- :func:`max_stdev_union_interval` — the union of those belts over every pattern
  (the interval valid whatever the σ_i): the upper end from one σ_i alone, the lower
  end from m equal σ_i, both closed form.
- :func:`random_walk_stdev_dof` — the effective degrees of freedom of the sample
  variance of n equally spaced samples of a random walk (correlated samples carry
  far less information than n independent ones).
- :func:`expected_range_factor` — d₂(n) = E[range of n standard normal values]
  (Tippett 1925), by numerical integration: the mean by which noise of standard
  deviation σ alone spreads n values, d₂(n)·σ.
- :func:`corrected_range` — a range of noisy values corrected for its upward bias
  (the expected excess over the true range, by Monte Carlo of the values' errors,
  JCGM 101), with its standard uncertainty: the estimate instead of a widening, and
  its 95 % confidence interval from the measured range's own distribution (a Neyman
  belt, :func:`range_belt_interval`): skewed and bounded at 0 where the true range is a
  few σ of the errors, so value ± k·u is not a 95 % interval there. The value takes the
  true values along the measured pattern; the interval holds for every pattern of the
  true values (several tied at an extreme spread the measured range more than the
  measured pattern shows).

This module never imports ``gonio``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy import integrate, special, stats

__all__ = ["stdev_interval", "stdev_upper", "stdev_u", "max_stdev_interval", "max_stdev_cdf",
           "max_stdev_quantile", "max_stdev_belt_interval", "max_stdev_union_interval",
           "expected_range_factor",
           "random_walk_stdev_dof", "correlated_stdev_dof", "corrected_range", "RangeCorrection",
           "range_belt_interval", "range_belt_numerical_u", "BELT_PATTERNS"]


def _check(s: float, dof: float) -> None:
    if not (math.isfinite(s) and s >= 0):
        raise ValueError(f"standard deviation must be finite and >= 0, got {s}")
    if not (dof >= 1):
        raise ValueError(f"degrees of freedom must be >= 1, got {dof}")


def stdev_interval(s: float, dof: float, p: float = 0.95) -> tuple[float, float]:
    """Two-sided χ² interval for σ from s with ν degrees of freedom (normal population).

    [s·√(ν/χ²_{(1+p)/2}(ν)), s·√(ν/χ²_{(1−p)/2}(ν))].

    Examples
    --------
    s = 1 from n = 10 readings (ν = 9), 95 %: χ²_{0.975}(9) = 19.023, χ²_{0.025}(9) = 2.700,
    so [√(9/19.023), √(9/2.700)] = [0.688, 1.826] (the textbook values).

    >>> lo, hi = stdev_interval(1.0, 9)
    >>> round(lo, 3), round(hi, 3)
    (0.688, 1.826)
    """
    _check(s, dof)
    a = (1.0 - p) / 2.0
    return (s * math.sqrt(dof / stats.chi2.ppf(1.0 - a, dof)),
            s * math.sqrt(dof / stats.chi2.ppf(a, dof)))


def stdev_upper(s: float, dof: float, p: float = 0.95) -> float:
    """One-sided χ² upper confidence limit of σ from s with ν degrees of freedom (normal
    population; ν s²/σ² ~ χ²(ν)): s·√(ν/χ²_{1−p}(ν)), so that P(σ ≤ limit) = p and
    [0, limit] is a p coverage interval of σ.

    Examples
    --------
    s = 1, ν = 9, 95 %: χ²_{0.05}(9) = 3.325, √(9/3.325) = 1.645; ν = 2: χ²_{0.05}(2) =
    −2 ln 0.95 = 0.1026, √(2/0.1026) = 4.415.

    >>> round(stdev_upper(1.0, 9), 3), round(stdev_upper(1.0, 2), 3)
    (1.645, 4.415)
    """
    _check(s, dof)
    return s * math.sqrt(dof / stats.chi2.ppf(1.0 - p, dof))


def stdev_u(s: float, dof: float) -> float:
    """u(s) = s/√(2ν) (JCGM 100 E.4.3: σ[s]/σ ≈ 1/√(2ν)).

    >>> round(stdev_u(0.3, 9), 4)       # 0.3/√18
    0.0707
    """
    _check(s, dof)
    return s / math.sqrt(2.0 * dof)


def max_stdev_interval(s_max: float, dof: float, m: int, p: float = 0.95) -> tuple[float, float]:
    """Interval for max σ_i from the largest of m sample standard deviations, each with ν.

    When every σ_i equals σ, P(max s_i ≤ x) = F(x)^m with F the distribution of one
    s; the interval is the set of σ for which s_max lies between the (1−p)/2 and
    (1+p)/2 quantiles of that maximum. It is exact only for equal σ_i: where one σ_i
    dominates, s_max is about one s and this interval lies too low (its upper end is
    below s_max itself for m = 12, ν = 9), covering max σ_i far less than p; the interval
    valid for every pattern is :func:`max_stdev_union_interval`. m = 1 gives
    :func:`stdev_interval`.

    >>> lo, hi = max_stdev_interval(1.0, 9, 1)
    >>> round(lo, 3), round(hi, 3)
    (0.688, 1.826)

    Twelve points, ν = 9: quantiles 0.975^(1/12) = 0.99789 and 0.025^(1/12) = 0.73550 of
    χ²(9) are 25.92 and 11.16, so [√(9/25.92), √(9/11.16)] = [0.589, 0.898]:

    >>> lo, hi = max_stdev_interval(1.0, 9, 12)
    >>> round(lo, 3), round(hi, 3)
    (0.589, 0.898)
    """
    _check(s_max, dof)
    if int(m) != m or m < 1:
        raise ValueError(f"m must be an integer >= 1, got {m}")
    a = (1.0 - p) / 2.0
    q_hi = (1.0 - a) ** (1.0 / m)        # P(max ≤ x) = F(x)^m = 1 − a
    q_lo = a ** (1.0 / m)                # F(x)^m = a
    return (s_max * math.sqrt(dof / stats.chi2.ppf(q_hi, dof)),
            s_max * math.sqrt(dof / stats.chi2.ppf(q_lo, dof)))


def max_stdev_cdf(x: float, sigma, dof: float) -> float:
    """P(max_i s_i ≤ x) of m independent sample standard deviations s_i of normal
    populations with standard deviations σ_i, each with ν degrees of freedom:
    ν s_i²/σ_i² ~ χ²(ν) (JCGM 100 E.4.3) and, the s_i being independent,

        P(max s_i ≤ x) = Π_i F_χ²(ν x²/σ_i²; ν).

    A σ_i of 0 contributes a factor 1 (its s_i is 0). Decreasing in every σ_i.

    Examples
    --------
    One σ = 1, ν = 9: P(s ≤ √(3.325/9)) = F_χ²(3.325; 9) = 0.05; twelve equal σ = 1:
    0.05¹² ≈ 2.4·10⁻¹⁶:

    >>> x = math.sqrt(stats.chi2.ppf(0.05, 9) / 9)
    >>> round(max_stdev_cdf(x, [1.0], 9), 6), max_stdev_cdf(x, [1.0] * 12, 9) < 1e-15
    (0.05, True)
    """
    sig = np.asarray(sigma, dtype=float).ravel()
    if sig.size < 1 or not np.all(np.isfinite(sig)) or np.any(sig < 0):
        raise ValueError("max_stdev_cdf needs at least one finite sigma >= 0")
    if not (dof >= 1):
        raise ValueError(f"degrees of freedom must be >= 1, got {dof}")
    if x <= 0:
        return 0.0 if np.any(sig > 0) else 1.0
    pos = sig[sig > 0]
    return float(np.prod(stats.chi2.cdf(dof * x * x / pos ** 2, dof)))


def _max_quantile(pattern: np.ndarray, dof: float, q: float) -> float:
    """x with max_stdev_cdf(x, pattern, ν) = q (max pattern = 1): the q-quantile of max s_i
    at θ = 1, bracketed between the single σ's and m equal σ's quantiles (the cdf is
    bounded by F and F^m, F of one s at σ = 1)."""
    m = pattern.size
    lo = math.sqrt(stats.chi2.ppf(q, dof) / dof)
    hi = math.sqrt(stats.chi2.ppf(q ** (1.0 / m), dof) / dof)
    if hi - lo <= 1e-15 * hi:
        return lo
    from scipy.optimize import brentq

    def f(x: float) -> float:
        return max_stdev_cdf(x, pattern, dof) - q

    f_lo, f_hi = f(lo), f(hi)
    if f_lo >= 0.0:          # at an end within rounding (m equal, or one σ alone)
        return lo
    if f_hi <= 0.0:
        return hi
    return float(brentq(f, lo, hi, xtol=1e-14, rtol=1e-13))


def max_stdev_quantile(q: float, sigma, dof: float) -> float:
    """The q-quantile of max_i s_i (:func:`max_stdev_cdf`): x with P(max s_i ≤ x) = q.

    >>> round(max_stdev_quantile(0.05, [2.0], 9), 4)        # 2·√(3.325/9)
    1.2157
    >>> round(max_stdev_quantile(0.05 ** 12, [1.0] * 12, 9), 4)     # the same: F¹² = 0.05¹²
    0.6078
    """
    sig = np.asarray(sigma, dtype=float).ravel()
    if sig.size < 1 or not np.all(np.isfinite(sig)) or np.any(sig < 0) or sig.max() <= 0:
        raise ValueError("max_stdev_quantile needs finite sigma >= 0, the largest > 0")
    if not 0.0 < q < 1.0:
        raise ValueError(f"q must lie in (0, 1), got {q}")
    if not (dof >= 1):
        raise ValueError(f"degrees of freedom must be >= 1, got {dof}")
    return float(sig.max() * _max_quantile(sig / sig.max(), dof, q))


def max_stdev_belt_interval(s, dof: float, pattern=None, p: float = 0.95,
                            lower: bool = False) -> tuple[float, float]:
    """The confidence interval of θ = max σ_i from the measured s_i (each with ν): the
    Neyman belt (Neyman 1937) of T = max s_i with the σ_i taken along ``pattern``,
    σ_i = θ·π_i (π scaled to max 1; default the measured pattern π_i = s_i/T, as
    :func:`range_belt_interval` takes its values), inverted at the measured T.

    P(T ≤ x | θ) = G_π(x/θ), G_π = :func:`max_stdev_cdf` at σ = π: the belt is
    scale-invariant, so its ends are closed form, T/b and T/a with G_π(a) = 1 − p and
    G_π(b) = p one-sided (``lower=False``: [0, T/a], an upper limit), or G_π(a) = (1 − p)/2,
    G_π(b) = (1 + p)/2 central (``lower=True``: [T/b, T/a]). Exact when the σ_i are in
    the pattern's proportions. The pattern is not known: along the measured pattern the
    belt under-covers where one σ_i dominates (the s_i of the others scatter up to it and
    the pattern looks flatter than it is); :func:`max_stdev_union_interval` is the union
    over every pattern.

    Examples
    --------
    One value (m = 1) is the χ² interval of one s (:func:`stdev_upper`,
    :func:`stdev_interval`); twelve equal σ_i are the equal-σ maximum
    (:func:`max_stdev_interval`):

    >>> round(max_stdev_belt_interval([1.0], 9)[1], 3)
    1.645
    >>> [round(v, 3) for v in max_stdev_belt_interval([1.0], 9, lower=True)]
    [0.688, 1.826]
    >>> [round(v, 3) for v in max_stdev_belt_interval([1.0] * 12, 9, lower=True)]
    [0.589, 0.898]
    """
    s = np.asarray(s, dtype=float).ravel()
    if s.size < 1:
        raise ValueError("max_stdev_belt_interval needs at least one standard deviation")
    for v in s:
        _check(float(v), dof)
    if not 0.0 < p < 1.0:
        raise ValueError(f"p must lie in (0, 1), got {p}")
    t = float(s.max())
    pat = s if pattern is None else np.asarray(pattern, dtype=float).ravel()
    if pat.size < 1 or not np.all(np.isfinite(pat)) or np.any(pat < 0) or pat.max() <= 0:
        raise ValueError("max_stdev_belt_interval: the pattern needs a finite positive "
                         "largest value and no negative one")
    pat = pat / pat.max()
    a_lo, a_hi = ((1.0 - p) / 2.0, (1.0 + p) / 2.0) if lower else (1.0 - p, None)
    hi = t / _max_quantile(pat, dof, a_lo)
    lo = t / _max_quantile(pat, dof, a_hi) if lower else 0.0
    return float(lo), float(hi)


def max_stdev_union_interval(s_max: float, dof: float, m: int, p: float = 0.95,
                             lower: bool = False) -> tuple[float, float]:
    """The confidence interval of θ = max σ_i from T = the largest of m sample standard
    deviations (each with ν) that holds θ with at least p whatever the σ_i: the union of
    the belts of :func:`max_stdev_belt_interval` over every pattern of m σ_i.

    P(T ≤ x | σ) = Π_i F_χ²(ν x²/σ_i²; ν) decreases in every σ_i, so among the patterns
    with max σ_i = θ it is largest with the other σ_i → 0 (one s alone: F(ν x²/θ²)) and
    smallest with all σ_i = θ (F(ν x²/θ²)^m). The belt's lower edge (the upper limit)
    is therefore lowest at the first, its upper edge (the lower limit) highest at the
    second, and the union of the acceptance regions is [q_F(1 − p), q_{F^m}(p)]: upper
    limit T·√(ν/χ²_{1−p}(ν)) (one-sided; central: χ²_{(1−p)/2}), lower limit 0 (one-sided)
    or T·√(ν/χ²_{((1+p)/2)^{1/m}}(ν)) (central). Each tail is exact at its own extreme
    pattern (one σ_i for the upper limit, m equal for the lower) and conservative
    elsewhere; no interval valid for every pattern has a lower upper limit (at one σ_i
    with the others far below, T is one s and the single χ² limit is exact). Where the σ_i
    are alike the upper limit holds θ with nearly 1, the price of not knowing the
    pattern.

    Examples
    --------
    Twelve points, ten series (ν = 9), T = 1: upper limit √(9/3.325) = 1.645 (one-sided);
    central: [√(9/25.92), √(9/2.700)] = [0.589, 1.826]:

    >>> [round(v, 3) for v in max_stdev_union_interval(1.0, 9, 12)]
    [0.0, 1.645]
    >>> [round(v, 3) for v in max_stdev_union_interval(1.0, 9, 12, lower=True)]
    [0.589, 1.826]
    """
    _check(s_max, dof)
    if int(m) != m or m < 1:
        raise ValueError(f"m must be an integer >= 1, got {m}")
    if not 0.0 < p < 1.0:
        raise ValueError(f"p must lie in (0, 1), got {p}")
    if not lower:
        return 0.0, stdev_upper(s_max, dof, p)
    a = (1.0 - p) / 2.0
    return (s_max * math.sqrt(dof / stats.chi2.ppf((1.0 - a) ** (1.0 / m), dof)),
            s_max * math.sqrt(dof / stats.chi2.ppf(a, dof)))


@functools.lru_cache(maxsize=64)
def expected_range_factor(n: int) -> float:
    """d₂(n): the expected range of n independent standard normal values.

    d₂(n) = ∫ [1 − (1 − Φ(x))ⁿ − Φ(x)ⁿ] dx over the real line.
    Tabulated values: d₂(2) = 1.128, d₂(6) = 2.534, d₂(10) = 3.078.

    >>> [round(expected_range_factor(n), 3) for n in (2, 6, 10)]
    [1.128, 2.534, 3.078]
    """
    if int(n) != n or n < 1:
        raise ValueError(f"n must be an integer >= 1, got {n}")
    if n == 1:
        return 0.0
    def f(x: float) -> float:
        phi = special.ndtr(x)        # Φ(x): what stats.norm.cdf evaluates, without its wrapper
        return 1.0 - (1.0 - phi) ** n - phi ** n

    val, _ = integrate.quad(f, -np.inf, np.inf)
    return float(val)


@dataclass(frozen=True)
class RangeCorrection:
    """A range of noisy values corrected for its bias (:func:`corrected_range`)."""

    value: float              # the corrected range (negative: below what the errors alone give)
    u: float                  # its standard uncertainty: sd of the estimator there
    measured: float           # the range as measured, max − min
    noise_range: float        # E[range] of the errors alone (equal true values)
    shrink: float             # λ: the true values taken as mean + λ(x − mean)
    #: The 95 % confidence interval of the true range (the Neyman belt inverted at the
    #: measured range, :func:`range_belt_interval`, for every pattern of the true values):
    #: [lo, hi], 0 ≤ lo ≤ max(value, 0) ≤ hi (it holds the measured pattern's interval).
    interval: tuple[float, float] = (math.nan, math.nan)


def corrected_range(x, errors) -> RangeCorrection:
    """The range R = max t − min t of true values t from measured ones x = t + e, corrected for
    the upward bias of the measured range, with its standard uncertainty.

    max(t + e) − min(t + e) exceeds max t − min t on average (the range is convex; by order
    statistics, n equal values and independent normal e of σ give d₂(n)·σ, Tippett 1925), so
    a range of noisy values is biased upwards by an excess that depends on the errors and on
    the true values. ``errors`` is an (M, n) array of draws of e from the measurement model
    (JCGM 101 5.1, 7.2: each input from its own distribution, shared draws where the model
    shares an input); the same draws serve every evaluation below (common random numbers:
    the result is a smooth, monotone function of x). Method of moments along the measured
    pattern: the true values are taken as t(λ) = m + λ(x − m), m = mean x, and λ ∈ [0, 1] is
    the one whose expected measured range E[range(t(λ) + e)] equals the measured one; the
    corrected range is λ·(max x − min x). Where the measured range is below E[range(e)] (the
    errors alone would spread equal values more), λ = 0 and the corrected value is the
    measured range minus that expectation — negative, the unbiased estimate for equal true
    values.

    The value assumes the measured pattern. Where several true values tie at an extreme
    (six values three high, three low, as a third-order table error gives) the errors add
    more to the range than along the measured pattern (one value at each extreme, the
    others spread by the noise), so the value reads high there: mean (value − R)/u +0.85 at
    R = 4σ, +0.68 at 2.5σ, −0.25 … +0.36 for evenly spaced values
    (``scripts/range_belt_coverage.py``, docs/draft-readings.md 7.2). The stated interval
    (:func:`range_belt_interval`) holds whatever the pattern; the value is not corrected for
    an unknown one.

    u is the standard deviation of the estimator itself at the corrected value (a parametric
    bootstrap along the measured pattern, JCGM 101 5.9 applied to the estimator): the measured
    ranges r_j = range(t(λ) + e_j) of the draws are each mapped through the estimator —
    R̂(r) = f⁻¹(r), f(R) = E[range(m + (R/r)(x − m) + e)] tabulated on the same draws, and
    R̂(r) = r − E[range(e)] below E[range(e)] — and u = sd of the R̂(r_j). The spread of the
    measured range alone is not u: the estimate moves by dR̂/dr = 1/f'(R) per unit of the
    measured range, and f' = d E[measured]/d true lies in [0, 1] (0 at equal true values for
    symmetric errors, → 1 once the excess has vanished), so sd(r_j) understates u by that
    slope (u ≈ sd(r_j)/f'(R) where the slope is nearly constant over the spread).

    Two values, independent normal errors of σ: the measured range is |d + ε|, ε ~ N(0, 2σ²),
    whose mean is the folded normal's, s√(2/π) exp(−d²/2s²) + d(1 − 2Φ(−d/s)), s = σ√2; the
    correction inverts it (d = 1.5σ measured as that mean, 1.7097σ, is corrected back to 1.5σ):

    >>> s2, d = math.sqrt(2.0), 1.5
    >>> mean = s2 * math.sqrt(2 / math.pi) * math.exp(-d * d / 4) + d * (1 - 2 * stats.norm.cdf(-d / s2))
    >>> rng = np.random.default_rng(1)
    >>> c = corrected_range([0.0, mean], rng.normal(0.0, 1.0, (200_000, 2)))
    >>> round(float(mean), 4), round(c.value, 2), round(c.noise_range, 2)   # E|ε| = 2/√π = 1.128
    (1.7097, 1.5, 1.13)

    Six equal true values: d₂(6) = 2.534, and the range's sd d₃(6) = 0.848 (tabulated):

    >>> c = corrected_range(np.zeros(6), rng.normal(0.0, 1.0, (200_000, 6)))
    >>> round(c.value, 2), round(c.u, 2), c.shrink
    (-2.53, 0.85, 0.0)
    """
    x = np.asarray(x, dtype=float)
    e = np.asarray(errors, dtype=float)
    if x.ndim != 1 or x.size < 2 or e.ndim != 2 or e.shape[1] != x.size or e.shape[0] < 2:
        raise ValueError("corrected_range needs n >= 2 values and an (M, n) array of error draws")
    m = float(x.mean())
    d = x - m
    r = float(x.max() - x.min())
    cols = _columns(e)

    def ranges(lam: float) -> np.ndarray:
        return _row_ranges(cols, m + lam * d)        # the ranges of m + λd + e

    e0 = float(ranges(0.0).mean())
    if r <= e0:
        lam, value = 0.0, r - e0
    else:                   # E[range(t(λ) + e)] rises from e0 < r to ≥ r at λ = 1 (convexity)
        lo, hi = 0.0, 1.0
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if ranges(mid).mean() < r else (lo, mid)
        lam = 0.5 * (lo + hi)
        value = lam * r
    return RangeCorrection(float(value), _estimator_sd(ranges(lam), r, e0, ranges), r, e0,
                           float(lam), range_belt_interval(x, e))


#: Largest number of values whose two-level patterns (every split into a high and a low group,
#: 2ⁿ − 2 of them) :func:`range_belt_interval` enumerates; above it the upper quantile is taken
#: from the bound every pattern obeys draw by draw, R + range(e) (wider).
_SPLIT_MAX_N = 8
#: Above this many values the band's lower end takes the draw-by-draw bound R − range(e) in
#: place of every ordered pair's three-level pattern (n(n − 1) patterns of M draws each:
#: 10⁵ pairs of 4000 draws would take gigabytes), see :func:`_bounded_crossing`.
_PAIR_MAX_N = 24

#: The patterns :func:`range_belt_interval` may take the true values along.
BELT_PATTERNS = ("robust", "measured")


def range_belt_interval(x, errors, p: float = 0.95, *,
                        patterns: str = "robust") -> tuple[float, float]:
    """The confidence interval of the true range R of values measured as ``x`` with errors
    drawn as ``errors`` ((M, n), as :func:`corrected_range`): the Neyman confidence belt
    inverted at the measured range (Neyman 1937; the construction of Feldman & Cousins,
    Phys. Rev. D 57 (1998) 3873, with the central ordering), made to hold whatever the
    pattern of the true values.

    The measured range's distribution depends on the true range R *and* on how the true
    values lie between their extremes (one value at each extreme, or several tied there:
    max(t + e) − min(t + e) then takes the largest of several errors), and the data do not
    tell the pattern (the measured one is the truth's plus noise). For each candidate R the
    band [Q_lo(R), Q_hi(R)] is taken wide enough for every pattern of range R
    (``patterns="robust"``, the least favourable pattern at each R on each side):

    - Q_hi(R), the (1+p)/2 quantile: the largest over the measured pattern and every
      two-level pattern (the values of a group S at R, the rest at 0, each non-empty S of
      the n positions; per draw the range is convex in the true values, so over the box
      [0, R]ⁿ it is largest at such a vertex). Above ``_SPLIT_MAX_N`` values, the draw-by-draw
      bound R + range(e) (the largest range any pattern of range R can give with the draw e),
      valid for every pattern and wider.
    - Q_lo(R), the (1−p)/2 quantile: the smallest over the measured pattern, the splits and
      every ordered pair (a at R, b at 0) with the others at R/2, where they widen the range
      least (tests/test_range_belt_patterns.py); above ``_PAIR_MAX_N``, R − range(e).

    ``patterns="measured"``: along the measured pattern alone, t(R) = m + (R/r)(x − m) (as
    :func:`corrected_range`'s value), kept for comparison: it under-covers where several true
    values tie at the extremes (three high, three low: 86.5 % at 4σ).

    The band's tails are narrowed by twice the Monte Carlo uncertainty of a tail fraction
    from M draws, √(α(1 − α)/M) (JCGM 101 7.9, so that the draws' own quantile error does not
    narrow the band). The interval is the set of R ≥ 0 whose band holds the measured range
    r: [R_lo, R_hi] with Q_hi(R_lo) = r (R_lo = 0 where Q_hi(0) ≥ r already) and
    Q_lo(R_hi) = r. The band of every R whose Q_lo lies below the errors' own mean range
    e0 = E[range(e)] reaches down to 0 (a band only widened: coverage stays ≥ p; without it
    the central band gives a vanishing interval for the smallest measured ranges), i.e. R_hi
    is never below R_c, Q_lo(R_c) = e0. Whatever the true R and pattern, the band holds the
    measured range with probability ≥ p, so the interval holds R with probability ≥ p. The
    same draws serve every R (common random numbers; the quantiles are smooth and nearly
    monotone in R, each draw's range being convex, not monotone, in R), solved by bisection.
    n values all equal (r = 0): the measured pattern taken is one value apart from the rest.

    Two values have one pattern: r = |d + ε|, ε ~ N(0, 2σ²), P(r ≤ q | R) = Φ((q − R)/√2) −
    Φ((−q − R)/√2) for σ = 1. A measured range of 4: R_lo solves P(r ≤ 4 | R) = 0.975, R_hi
    solves P(r ≤ 4 | R) = 0.025 (closed form, brentq: 1.2255 and 6.7718):

    >>> rng = np.random.default_rng(1)
    >>> lo, hi = range_belt_interval([0.0, 4.0], rng.normal(0.0, 1.0, (100_000, 2)))
    >>> round(lo, 1), round(hi, 1)
    (1.2, 6.8)

    Six values, σ = 1, far apart: R_lo = r − (the band's upper quantile of max of three −
    min of the other three: three values high and three low spread the measured range the
    most), R_hi = r + (that of e_b − e_a, ~N(0, 2): one value at each extreme spreads it the
    least). With 20 000 draws the band's tail is 2.28 % (the Monte Carlo allowance), where the
    closed forms (the first by quadrature of 3φ(y)Φ(y)²(1 − Φ(y − q))³) give 3.889 and
    √2·z₀.₉₇₇₂ = 2.827 (the largest of the 20 equivalent splits' and the smallest of the 30 pairs'
    sample quantiles lie a few 0.01 beyond: conservative by the draws' own spread); the measured
    pattern alone (one value at each extreme) gives 2.87 and 2.82:

    >>> e = rng.normal(0.0, 1.0, (20_000, 6))
    >>> lo, hi = range_belt_interval([0.0, 20.0, 5.0, 10.0, 12.0, 3.0], e)
    >>> round(20.0 - lo, 2), round(hi - 20.0, 2)
    (3.93, 2.9)
    """
    x, e = _belt_checked(x, errors, p, patterns)
    return _belt_ends(x, e, _belt_tail(p, e.shape[0]), patterns)


def range_belt_numerical_u(x, errors, p: float = 0.95, *,
                           patterns: str = "robust") -> tuple[float, float]:
    """The standard uncertainty of :func:`range_belt_interval`'s two ends from the finite
    number M of ``errors`` draws (JCGM 101 7.9: the numerical precision of a Monte Carlo's
    interval ends), (u_lo, u_hi), for the same arguments.

    Each end is where a tail quantile of the measured range (the band's, at the tail
    fraction α the belt takes) reaches the measured range. The share of M draws below a
    quantile has the binomial standard deviation δ = √(α(1 − α)/M); carried through the
    draws as :func:`uncertainty.quantile_numerical_u` carries it through one sample, each end
    is found again with the band's tails at α − δ and α + δ, on the same draws, and u is
    half the distance between the two (distribution-free; the band's slope in R and every
    pattern's quantile included). An end held at 0 has none. Two more belts' work. An upper
    estimate: an end that is the largest (smallest) of several competing patterns'
    quantiles, or the floor, scatters less than one quantile does (over independent sets of
    draws 0.48–0.77 of it, tests/test_range_belt_numerical_u.py); used to choose the digits
    stated, it may keep one digit fewer than the draws would allow, never one more.

    Two values, σ = 1, far apart: the band is r = R + ε√2 at both tails (one pattern), so
    each end's u is the quantile's, √(α(1 − α)/M)/φ(z_α)·√2 — 0.065 at M = 4000 with the
    belt's α (0.025 less its allowance, 0.0200); the estimate scatters by about 15 % from one
    set of draws to another:

    >>> rng = np.random.default_rng(2)
    >>> u = range_belt_numerical_u([0.0, 20.0], rng.normal(0.0, 1.0, (4000, 2)))
    >>> a = 0.025 - 2 * math.sqrt(0.025 * 0.975 / 4000)
    >>> closed = math.sqrt(a * (1 - a) / 4000) / stats.norm.pdf(stats.norm.ppf(a)) * math.sqrt(2)
    >>> round(float(closed), 3), [round(v, 2) for v in u]
    (0.065, [0.06, 0.06])
    """
    x, e = _belt_checked(x, errors, p, patterns)
    m = e.shape[0]
    tail = _belt_tail(p, m)
    d = math.sqrt(tail * (1.0 - tail) / m)
    wide = _belt_ends(x, e, max(tail - d, 0.5 / m), patterns)
    narrow = _belt_ends(x, e, min(tail + d, 0.5), patterns)
    return abs(narrow[0] - wide[0]) / 2.0, abs(wide[1] - narrow[1]) / 2.0


def _belt_checked(x, errors, p: float, patterns: str) -> tuple[np.ndarray, np.ndarray]:
    """The values and draws of :func:`range_belt_interval` as arrays, its arguments checked."""
    x = np.asarray(x, dtype=float)
    e = np.asarray(errors, dtype=float)
    if x.ndim != 1 or x.size < 2 or e.ndim != 2 or e.shape[1] != x.size or e.shape[0] < 2:
        raise ValueError("range_belt_interval needs n >= 2 values and an (M, n) array of "
                         "error draws")
    if not 0.0 < p < 1.0:
        raise ValueError(f"p must lie in (0, 1), got {p}")
    if patterns not in BELT_PATTERNS:
        raise ValueError(f"patterns must be one of {', '.join(BELT_PATTERNS)}, got {patterns!r}")
    return x, e


def _belt_tail(p: float, draws: int) -> float:
    """The band's tail fraction of :func:`range_belt_interval`: (1 − p)/2 less twice the
    Monte Carlo's standard uncertainty of a tail fraction from M draws, √(α(1 − α)/M)
    (JCGM 101 7.9: the draws' quantiles are themselves uncertain; a band estimated too
    narrow by them under-covers, 94.3 % at large d for two values and M = 4000 without
    this), at least half a draw."""
    tail = 0.5 * (1.0 - p)
    return max(tail - 2.0 * math.sqrt(tail * (1.0 - tail) / draws), 0.5 / draws)


def _belt_ends(x: np.ndarray, e: np.ndarray, tail: float, patterns: str) -> tuple[float, float]:
    """:func:`range_belt_interval`'s [R_lo, R_hi] with the band's tails at ``tail``."""
    n, draws = x.size, e.shape[0]
    m = float(x.mean())
    r = float(x.max() - x.min())
    if r > 0:
        unit = (x - m) / r                       # the measured pattern, range 1
    else:
        unit = np.zeros(n)
        unit[-1] = 1.0
        unit -= unit.mean()
    q_lo_p, q_hi_p = tail, 1.0 - tail
    cols, e_range, e0, patterns_of = _draws_prepared(e)

    def own(big_r: float, q: float) -> float:
        return float(_quantile_rows(_row_ranges(cols, big_r * unit), q))   # of R·unit + e

    if patterns == "measured":
        def crossing(q: float, target: float) -> float:
            return _first_crossing(lambda big_r, idx: np.array([own(big_r, q)]), 1,
                                   target, False)
    elif n > _PAIR_MAX_N:                   # many values: R ± range(e) draw by draw
        crossing = _bounded_crossing(own, float(np.quantile(e_range, q_hi_p)))
    else:
        *fam, n_splits = patterns_of(n > _SPLIT_MAX_N)
        e_hi = float(np.quantile(e_range, q_hi_p)) if n > _SPLIT_MAX_N else -math.inf

        def crossing(q: float, target: float) -> float:
            # the upper quantile: the measured pattern and the splits (a middle value spreads
            # the range less than one at either extreme); the lower: every pattern
            count = 1 + (fam[0].shape[0] if q < 0.5 else n_splits)
            return _first_crossing(
                lambda big_r, idx: _pattern_quantiles(big_r, idx, q, own, fam, n_splits, e_hi),
                count, target, q < 0.5)

    # the floor R_c along the measured pattern (a data-dependent widening: coverage holds)
    floor = _first_crossing(lambda big_r, idx: np.array([own(big_r, q_lo_p)]), 1, e0, True)
    lo_end = crossing(q_hi_p, r)
    hi_end = max(crossing(q_lo_p, r), floor, lo_end)
    return float(lo_end), float(hi_end)


#: The draws most recently prepared by :func:`_draws_prepared` (their bytes and shape →
#: what depends on them alone): a study asks for thousands of intervals with one set of draws.
_PREPARED: dict = {}
_PREPARED_MAX = 2


def _draws_prepared(e: np.ndarray):
    """(the columns of the draws ``e`` (:func:`_columns`), each draw's range, their mean, a
    function of ``outliers_only`` giving :func:`_three_level_patterns` of ``e``): what depends
    on the draws alone, computed once for the same draws (equal bytes and shape; kept
    read-only) and reused by later calls, with the same numbers."""
    key = (e.shape, e.tobytes())
    hit = _PREPARED.get(key)
    if hit is None:
        own_e = e.copy()                    # the caller may change its array later
        cols = _columns(own_e)
        e_range = _row_ranges(cols)
        fams: dict = {}

        def patterns_of(outliers_only: bool):
            if outliers_only not in fams:
                fam = _three_level_patterns(own_e, outliers_only)
                for a in fam[:-1]:
                    a.flags.writeable = False
                fams[outliers_only] = fam
            return fams[outliers_only]

        cols.flags.writeable = False
        e_range.flags.writeable = False
        hit = (cols, e_range, float(np.mean(e_range)), patterns_of)
        while len(_PREPARED) >= _PREPARED_MAX:
            _PREPARED.pop(next(iter(_PREPARED)))
        _PREPARED[key] = hit
    return hit


def _bounded_crossing(own, e_hi: float):
    """``crossing(q, target)`` of :func:`range_belt_interval` for more than ``_PAIR_MAX_N``
    values: every pattern of true range R gives, draw by draw, a measured range within R ±
    range(e) (its extreme positions' t_a + e_a and t_b + e_b lie inside it), so each end of
    the band is taken at least as wide as that bound (``e_hi`` the band's upper-tail quantile
    of range(e)) beside the measured pattern's; memory O(M·n) where the pairs' three-level
    patterns would take n(n − 1)·M."""
    def crossing(q: float, target: float) -> float:
        if q < 0.5:
            return _first_crossing(
                lambda big_r, idx: np.array([own(big_r, q), big_r - e_hi])[idx], 2, target, True)
        return _first_crossing(
            lambda big_r, idx: np.array([max(own(big_r, q), big_r + e_hi)])[idx], 1, target,
            False)
    return crossing


def _pattern_quantiles(big_r: float, idx: np.ndarray, q: float, own, fam, n_splits: int,
                       e_hi: float) -> np.ndarray:
    """The q-quantiles at R of the patterns ``idx`` of :func:`range_belt_interval`: 0 the
    measured one (``own``; for the upper quantile at least the bound R + ``e_hi``), then the
    rows of ``fam`` (:func:`_three_level_patterns`: ``n_splits`` splits, then the pairs)."""
    rest = idx[idx > 0] - 1
    split, pair = rest[rest < n_splits], rest[rest >= n_splits]
    out = [_quantile_rows(_split_ranges(big_r, fam, split), q)]
    if pair.size:
        out.append(_quantile_rows(_pair_ranges(big_r, fam, pair), q))
    if idx[0] == 0:
        head = own(big_r, q) if q < 0.5 else max(own(big_r, q), big_r + e_hi)
        out.insert(0, [head])
    return np.concatenate(out)


def _three_level_patterns(e: np.ndarray, outliers_only: bool) -> tuple[np.ndarray, ...]:
    """Per draw, the largest and smallest error of each group of the true patterns
    :func:`range_belt_interval` takes beside the measured one, the true values at R (high
    group), R/2 (middle) and 0 (low): every split of the positions into a non-empty high and
    a non-empty low group (only the 2n one-outlier splits where ``outliers_only``), then
    every ordered pair (a high, b low) with the rest in the middle. Returns (high max, high
    min, middle max, middle min, low max, low min), each (patterns, M); an empty group
    ±inf, and the number of splits (the first rows)."""
    draws, n = e.shape
    cols = _columns(e)
    if outliers_only:
        hi_max = hi_min = e.T                                        # {a} high
        lo_max = np.vstack([_max_without(e, [a]) for a in range(n)])
        lo_min = -np.vstack([_max_without(-e, [a]) for a in range(n)])
        s_hi_max = np.concatenate([hi_max, lo_max])                  # and {a} low
        s_hi_min = np.concatenate([hi_min, lo_min])
        s_lo_max = np.concatenate([lo_max, hi_max])
        s_lo_min = np.concatenate([lo_min, hi_min])
    else:
        # max and min of every subset by its lowest member (bitmask recursion, O(2ⁿ M))
        full = 2 ** n - 1
        t_max = np.empty((full + 1, draws))
        t_min = np.empty((full + 1, draws))
        t_max[0], t_min[0] = -np.inf, np.inf
        for mask in range(1, full + 1):
            low = (mask & -mask).bit_length() - 1
            t_max[mask] = np.maximum(t_max[mask & (mask - 1)], cols[low])
            t_min[mask] = np.minimum(t_min[mask & (mask - 1)], cols[low])
        sub = np.arange(1, full)
        s_hi_max, s_hi_min = t_max[sub], t_min[sub]
        s_lo_max, s_lo_min = t_max[full ^ sub], t_min[full ^ sub]
    a_idx, b_idx = np.nonzero(~np.eye(n, dtype=bool))
    if outliers_only:
        mid_max = np.vstack([_max_without(e, [a, b]) for a, b in zip(a_idx, b_idx)])
        mid_min = -np.vstack([_max_without(-e, [a, b]) for a, b in zip(a_idx, b_idx)])
    else:
        rest = full ^ (1 << a_idx) ^ (1 << b_idx)
        mid_max, mid_min = t_max[rest], t_min[rest]
    return (np.concatenate([s_hi_max, cols[a_idx]]), np.concatenate([s_hi_min, cols[a_idx]]),
            np.concatenate([np.full_like(s_hi_max, -np.inf), mid_max]),
            np.concatenate([np.full_like(s_hi_max, np.inf), mid_min]),
            np.concatenate([s_lo_max, cols[b_idx]]), np.concatenate([s_lo_min, cols[b_idx]]),
            s_hi_max.shape[0])


def _split_ranges(big_r: float, fam, rows: np.ndarray) -> np.ndarray:
    """The draws' measured ranges (rows, M) of the two-level patterns ``rows`` at range R:
    max(R + high max, low max) − min(R + high min, low min), evaluated in two buffers (the
    same operations on the same numbers as the expression, without its three temporaries
    of rows × M values: the belt's bisection asks for this hundreds of times)."""
    if rows.size and rows[-1] - rows[0] + 1 == rows.size:         # contiguous: a view
        rows = slice(int(rows[0]), int(rows[-1]) + 1)
    top = np.add(fam[0][rows], big_r)
    np.maximum(top, fam[4][rows], out=top)
    bot = np.add(fam[1][rows], big_r)
    np.minimum(bot, fam[5][rows], out=bot)
    return np.subtract(top, bot, out=top)


def _pair_ranges(big_r: float, fam, rows: np.ndarray) -> np.ndarray:
    """The same for the three-level patterns ``rows`` (one value high, one low, the rest
    in the middle): max(R + top, R/2 + middle max, bottom) − min(R + top, R/2 + middle min,
    bottom), in the three gathered copies (``np.take``, always new arrays; the same
    operations as the expression)."""
    high = np.take(fam[0], rows, axis=0)
    high += big_r
    bot = fam[4][rows]
    top = np.take(fam[2], rows, axis=0)
    top += 0.5 * big_r
    np.maximum(high, top, out=top)
    np.maximum(top, bot, out=top)
    low = np.take(fam[3], rows, axis=0)
    low += 0.5 * big_r
    np.minimum(high, low, out=low)
    np.minimum(low, bot, out=low)
    return np.subtract(top, low, out=top)


def _quantile_rows(a: np.ndarray, q: float):
    """``np.quantile(a, q, axis=-1)`` (its default, linear method: Hyndman & Fan's 7th) with
    the same numbers, bit for bit, at less cost per call (the belt's bisection asks for
    thousands of quantiles of a few thousand draws): the same order statistics, at h =
    (M − 1)·q, its floor and the next (np.partition, as np.quantile), the same
    interpolation (a + (b − a)·γ, or b − (b − a)·(1 − γ) from γ = ½ on), NaN for a row
    holding a NaN. An h outside [0, M − 1) is left to np.quantile."""
    m = a.shape[-1]
    h = (m - 1) * q
    if not (m >= 2 and 0.0 <= h < m - 1):
        return np.quantile(a, q, axis=-1)
    lo = math.floor(h)
    gamma = h - lo
    part = np.partition(a, (lo, lo + 1, m - 1), axis=-1)
    below, above = part[..., lo], part[..., lo + 1]
    diff = above - below
    out = above - diff * (1.0 - gamma) if gamma >= 0.5 else below + diff * gamma
    nan = np.isnan(part[..., -1])               # NaN sorts last, as in np.quantile
    if np.any(nan):
        out = np.where(nan, np.nan, out)
    return out


def _columns(e: np.ndarray) -> np.ndarray:
    """The columns of the (M, n) draws ``e`` as the rows of a C-ordered (n, M) copy: each
    position's M draws contiguous, for :func:`_row_ranges` and the subsets' extremes."""
    return np.ascontiguousarray(e.T)


def _row_ranges(cols: np.ndarray, offset=None) -> np.ndarray:
    """Per draw i, max_j v_ij − min_j v_ij of v_ij = offset_j + e_ij (v = e without
    ``offset``), ``cols`` the columns of e (:func:`_columns`): the running maximum and
    minimum over the n columns, element-wise on M draws at a time, where ``v.max(axis=1)``
    loops over n values per row. The same values: each v_ij is the same sum (the offset's
    element plus the draw), and the largest and smallest of a row's values involve no
    rounding, whichever order they are compared in."""
    first = cols[0] if offset is None else offset[0] + cols[0]
    hi, lo = first.copy(), first
    for j in range(1, cols.shape[0]):
        v = cols[j] if offset is None else offset[j] + cols[j]
        np.maximum(hi, v, out=hi)
        lo = np.minimum(lo, v)
    return hi - lo


def _max_without(e: np.ndarray, drop: list[int]) -> np.ndarray:
    """Per draw (row of ``e``), the largest value of the columns not in ``drop`` (−inf where
    none is left)."""
    keep = np.ones(e.shape[1], dtype=bool)
    keep[drop] = False
    return e[:, keep].max(axis=1) if keep.any() else np.full(e.shape[0], -np.inf)


def _first_crossing(quantiles, count: int, target: float, lowest: bool) -> float:
    """The least R ≥ 0 at which the band's end reaches ``target``: the largest (``lowest``
    False: the upper quantile, the widest pattern) or the smallest (``lowest`` True: the
    lower quantile) over ``count`` patterns of ``quantiles(R, idx)``, the quantiles at R of
    the patterns ``idx``. Bracketed by doubling, then bisection; a pattern is dropped once
    it can no longer decide the end (the quantiles rising with R: for the upper quantile
    one still below the target where another has reached it crosses later; for the lower
    quantile one already at the target where the smallest has not crossed earlier)."""
    idx = np.arange(count)

    def reached(big_r: float) -> tuple[bool, np.ndarray]:
        qs = quantiles(big_r, idx)
        ok = qs >= target
        return (bool(ok.all()) if lowest else bool(ok.any())), ok

    done, ok = reached(0.0)
    if done:
        return 0.0
    if lowest:
        idx = idx[~ok]
    lo, hi = 0.0, max(target, 1e-300)
    for _ in range(200):
        done, ok = reached(hi)
        if done:
            break
        if lowest:
            idx = idx[~ok]
        lo, hi = hi, 2.0 * hi
    else:
        raise ValueError("range_belt_interval: the quantile does not reach the measured range")
    if not lowest:
        idx = idx[ok]
    tol = 1e-5 * hi
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        done, ok = reached(mid)
        if done:
            hi = mid
            if not lowest:
                idx = idx[ok]
        else:
            lo = mid
            if lowest:
                idx = idx[~ok]
    return 0.5 * (lo + hi)


#: Points of the table of E[measured range] against the true range (:func:`corrected_range`'s u).
_RANGE_GRID = 65


def _estimator_sd(r_j: np.ndarray, r: float, e0: float, ranges) -> float:
    """sd of :func:`corrected_range`'s estimate over measured ranges ``r_j`` (the estimator
    along the measured pattern of range ``r``; ``ranges(λ)`` the draws' ranges at t(λ))."""
    est = r_j - e0                                     # below E[range(e)]: slope 1
    above = r_j > e0
    if r > 0 and above.any():
        # R ≤ f(R) = E[range(t(R/r) + e)] ≤ R + e0, so f⁻¹ of the r_j above e0 lies in
        # [max(0, min r_j − e0), max r_j]: f tabulated there (monotone, convex)
        hi = float(r_j.max())
        true = np.linspace(max(0.0, float(r_j[above].min()) - e0), hi, _RANGE_GRID)
        f = np.maximum.accumulate([float(ranges(v / r).mean()) for v in true])
        est[above] = np.interp(r_j[above], f, true)
    return float(est.std(ddof=1))


def random_walk_stdev_dof(n: int) -> float:
    """Effective ν of s² from n equally spaced samples of a random walk (Satterthwaite).

    s² = xᵀAx is a quadratic form in the walk's independent increments x; matching
    the mean and variance of a scaled χ², ν_eff = 2E[s²]²/Var(s²) = (tr A)²/tr(A²)
    (Satterthwaite 1946). Independent samples would give n − 1.

    >>> round(random_walk_stdev_dof(15), 3), round(random_walk_stdev_dof(4), 3)
    (2.451, 1.923)
    """
    if int(n) != n or n < 2:
        raise ValueError(f"n must be an integer >= 2, got {n}")
    c = np.tril(np.ones((n - 1, n - 1)))
    c = np.vstack([np.zeros((1, n - 1)), c])           # first sample is the walk's origin
    p = (np.eye(n) - 1.0 / n) / (n - 1)
    a = c.T @ p @ c
    return float(np.trace(a) ** 2 / np.trace(a @ a))


def correlated_stdev_dof(cov) -> float:
    """Effective ν of the sample variance of n normal samples with covariance ``cov``.

    s² = yᵀPy/(n − 1), P the centring matrix; with y ~ N(μ, V), E[s²] ∝ tr(PV) and
    Var(s²) ∝ 2 tr((PV)²), so ν_eff = (tr PV)²/tr((PV)²) (Satterthwaite 1946).
    V = I gives n − 1; a random walk's min(t_i, t_j) gives
    :func:`random_walk_stdev_dof`.

    >>> round(correlated_stdev_dof(np.eye(5)), 9)
    4.0
    >>> t = np.arange(15.0)
    >>> round(correlated_stdev_dof(np.minimum.outer(t, t)), 3)
    2.451
    """
    v = np.asarray(cov, dtype=float)
    n = v.shape[0]
    if v.shape != (n, n) or n < 2:
        raise ValueError(f"cov must be a square matrix of size >= 2, got {v.shape}")
    pv = (np.eye(n) - 1.0 / n) @ v
    return float(np.trace(pv) ** 2 / np.trace(pv @ pv))
