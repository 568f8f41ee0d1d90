"""A 95 % interval for the largest absolute value of several estimated quantities.

A statement "E = ± max|E_i|" (an optical goniometer's angle deviation, the extreme over
its points) is about θ = max_i |μ_i|, the largest true |E_i|. max|E_i| is an extreme: its
distribution depends on the whole pattern of the μ_i, which is unknown. Stated as
max|E_i| ± U with U the largest point's (k·u of one point), it is centred on a biased
estimate where several points compete and over-wide where one dominates. The interval of
:func:`max_abs_interval` holds θ with probability ≥ p for EVERY pattern of the μ_i and every
correlation of the estimates (normal errors), and no interval of its form (each point
widened by its own u, one factor up and one down) with smaller factors does:

- upper limit H = max_i (|x_i| + c_H u_i): with j the point where |μ_j| = θ,
  P(H < θ) ≤ P(|x_j| + c_H u_j < |μ_j|) ≤ Φ(−c_H) whatever the others and their
  correlation (attained where one point dominates);
- lower limit L = max(0, max_i (|x_i| − c_L u_i)): P(L > θ) ≤ P(∃i: |x_i − μ_i| > c_L u_i)
  ≤ 1 − (2Φ(c_L) − 1)^m by Šidák's inequality (Šidák 1967, any correlation of a
  multivariate normal; equality at μ = 0 with independent points);
- the two misses are disjoint events. c_L is set so that the all-zero pattern misses with
  1 − p exactly; c_H so that the worst of the patterns "one point at θ, the others at
  θ − δ·u" (δ ≥ 0: from all equal to one dominant) misses with 1 − p exactly, both tails
  together. At m = 12, p = 0.95: c_H = 1.666, c_L = 2.858 (the ± U of one point: 1.96).

A point with finite ν_i (Welch–Satterthwaite, JCGM 100 G.4.1) takes the Student-t factor
of the same tail probability (the GUM's approximation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

__all__ = ["MaxAbsInterval", "max_abs_interval", "max_abs_factors", "max_abs_miss",
           "max_abs_level_z"]


@dataclass(frozen=True)
class MaxAbsInterval:
    """The interval [lower, upper] of max_i |μ_i| (the estimates' unit), the probability
    ``p``, the normal factors ``c_lower``/``c_upper`` and the estimate max|x_i|."""

    lower: float
    upper: float
    estimate: float
    p: float
    c_lower: float
    c_upper: float
    m: int

    def to_dict(self) -> dict:
        return {"lower": self.lower, "upper": self.upper, "estimate": self.estimate,
                "p": self.p, "c_lower": self.c_lower, "c_upper": self.c_upper, "m": self.m}


def max_abs_miss(c_upper: float, c_lower: float, m: int, delta) -> np.ndarray:
    """Miss probability of :func:`max_abs_interval`'s form (normal, independent points) on
    the patterns "one point at θ ≫ u, the m − 1 others at θ − δ·u" (u the same), both tails:
    Φ(−c_H)·Φ(δ − c_H)^(m−1) + 1 − Φ(c_L)·Φ(c_L + δ)^(m−1).

    >>> round(float(max_abs_miss(1.959964, 3.074636, 1, [0.0])[0]), 4)
    0.0261

    Φ is ``scipy.special.ndtr`` (what ``scipy.stats.norm.cdf`` evaluates, bit for bit,
    without its argument checks: this runs inside root searches).
    """
    up, lo = _miss_sides(c_upper, c_lower, m, delta)
    return up + lo


def _miss_sides(c_upper: float, c_lower: float, m: int, delta) -> tuple[np.ndarray, np.ndarray]:
    """The two tails of :func:`max_abs_miss` apart: (upper, lower), the upper one not
    decreasing in δ, the lower one not increasing."""
    from scipy.special import ndtr

    d = np.asarray(delta, dtype=float)
    up = ndtr(-c_upper) * ndtr(d - c_upper) ** (m - 1)
    lo = 1.0 - ndtr(c_lower) * ndtr(c_lower + d) ** (m - 1)
    return up, lo


#: The δ grid of the worst pattern's search (:func:`max_abs_factors`): 0 to 10 in steps of 0.005.
MISS_DELTA = np.linspace(0.0, 10.0, 2001)
MISS_DELTA.setflags(write=False)
_MISS_STEPS = (25, 1)              # the grids of :func:`_largest_miss`: every 25th δ, then every δ
_MISS_SLACK = 1e-12                 # far above the rounding of a tail (~1e-16), ≤ 2


def _largest_miss(c_upper: float, c_lower: float, m: int) -> float:
    """max over :data:`MISS_DELTA` of :func:`max_abs_miss` (the worst pattern's miss), the
    same number as the maximum over the whole grid, found without evaluating all of it:
    on every 25th δ first (:data:`_MISS_STEPS`), then on every δ only inside the stretches
    [δ_a, δ_b] whose bound up(δ_b) + lo(δ_a) (each tail monotone, :func:`_miss_sides`)
    reaches the largest miss found so far less :data:`_MISS_SLACK`; a stretch below it
    holds no δ above the maximum. Each δ's miss is the same arithmetic as on the whole
    grid."""
    d = MISS_DELTA
    starts, width, best = np.zeros(1, dtype=np.int64), d.size - 1, -math.inf
    for step in _MISS_STEPS:
        pts = starts[:, None] + step * np.arange(width // step + 1)[None, :]
        up, lo = _miss_sides(c_upper, c_lower, m, d[pts.ravel()])
        up, lo = up.reshape(pts.shape), lo.reshape(pts.shape)
        best = max(best, float(np.max(up + lo)))
        if step == 1:
            break
        keep = up[:, 1:] + lo[:, :-1] >= best - _MISS_SLACK
        starts, width = pts[:, :-1][keep], step
        if not starts.size:
            break
    return best


@lru_cache(maxsize=256)
def max_abs_factors(m: int, p: float = 0.95) -> tuple[float, float]:
    """(c_upper, c_lower), normal factors of :func:`max_abs_interval` for m points
    (module docstring: each side's worst pattern misses with 1 − p).

    >>> [round(c, 3) for c in max_abs_factors(12)]
    [1.666, 2.858]
    >>> [round(c, 3) for c in max_abs_factors(1)]        # one point: the two-sided normal
    [1.96, 1.96]
    """
    from scipy.optimize import brentq
    from scipy.stats import norm

    m = int(m)
    if m < 1 or not 0.0 < p < 1.0:
        raise ValueError(f"max_abs_factors needs m >= 1 and 0 < p < 1, got m={m}, p={p}")
    a = 1.0 - p
    if m == 1:
        c = float(norm.ppf(1.0 - a / 2.0))
        return c, c
    c_lower = float(norm.ppf((1.0 + p ** (1.0 / m)) / 2.0))
    c_upper = brentq(lambda c: _largest_miss(c, c_lower, m) - a, 0.5, 6.0, xtol=1e-10)
    return float(c_upper), c_lower


def max_abs_interval(x, u, dof=math.inf, p: float = 0.95, bound=0.0) -> MaxAbsInterval:
    """The interval of max_i |μ_i| from estimates ``x`` with standard uncertainties ``u``
    (ν ``dof``, one or per point): [max(0, max_i(|x_i| − c_L,i u_i)), max_i(|x_i| +
    c_H,i u_i)], c the normal factors of :func:`max_abs_factors` or, at finite ν_i, the
    Student-t quantiles of the same tail probabilities (module docstring).

    ``bound`` (one or per point, ≥ 0): a systematic error of each estimate known only by its
    bound b_i (|δ_i| ≤ b_i, not in u_i), added to each point's reach, [max(0, max_i(|x_i| −
    c_L u_i − b_i)), max_i(|x_i| + c_H u_i + b_i)]: the interval of max_i |μ_i + δ_i| from
    the u_i alone holds max_i |μ_i| for every δ within the bounds (above: the point j of the
    largest |μ_j| is a fixed point, |μ_j| ≤ |μ_j + δ_j| + b_j; below: Šidák's event for every
    point, |x_i| − c_L u_i ≤ |μ_i + δ_i| ≤ |μ_i| + b_i).

    >>> r = max_abs_interval([0.5], [0.1], bound=0.05)
    >>> round(r.lower, 4), round(r.upper, 4)
    (0.254, 0.746)

    One point is the usual two-sided interval folded at 0; twelve points with one far out:
    the upper limit 1.666 u above it, not 1.96 u:

    >>> r = max_abs_interval([0.5], [0.1])
    >>> round(r.lower, 4), round(r.upper, 4)
    (0.304, 0.696)
    >>> r = max_abs_interval([0.5] + [0.0] * 11, [0.1] * 12)
    >>> round(r.lower, 4), round(r.upper, 4)
    (0.2142, 0.6666)
    """
    from scipy.stats import norm, t as student

    x = np.abs(np.asarray(x, dtype=float))
    u = np.asarray(u, dtype=float)
    if x.ndim != 1 or x.size == 0 or u.shape != x.shape:
        raise ValueError("max_abs_interval needs one u per estimate (at least one)")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(u)) and np.all(u >= 0)):
        raise ValueError("max_abs_interval needs finite estimates and finite u >= 0")
    nu = np.broadcast_to(np.asarray(dof, dtype=float), x.shape)
    if np.any(~(nu >= 1.0)):
        raise ValueError("max_abs_interval needs every dof >= 1")
    b = np.broadcast_to(np.asarray(bound, dtype=float), x.shape)
    if not np.all(np.isfinite(b) & (b >= 0)):
        raise ValueError("max_abs_interval needs finite bounds >= 0")
    c_up, c_lo = max_abs_factors(x.size, p)

    def factor(c: float) -> np.ndarray:
        q = norm.cdf(c)
        return np.array([c if math.isinf(n) else float(student.ppf(q, n)) for n in nu])

    upper = float(np.max(x + factor(c_up) * u + b))
    lower = max(0.0, float(np.max(x - factor(c_lo) * u - b)))
    return MaxAbsInterval(lower=lower, upper=upper, estimate=float(np.max(x)), p=float(p),
                          c_lower=c_lo, c_upper=c_up, m=int(x.size))


def _lower_factor(m: int, p: float) -> float:
    """c_L of m > 1 points at level p: Šidák's Φ⁻¹((1 + p^(1/m))/2) (module docstring)."""
    from scipy.special import ndtri

    return float(ndtri((1.0 + p ** (1.0 / m)) / 2.0))


@lru_cache(maxsize=4096)
def _level_factors(m: int, p: float) -> tuple[float, float]:
    """:func:`max_abs_factors` at any level 0 < p < 1 (its root searched over c_H in [−6, 9]:
    below p ≈ 0.85 the upper factor of 12 points is under 0.5, negative below about 0.5)."""
    from scipy.optimize import brentq
    from scipy.stats import norm

    if m == 1:
        return max_abs_factors(1, p)
    c_lower = _lower_factor(m, p)
    c_upper = brentq(lambda c: _largest_miss(c, c_lower, m) - (1.0 - p), -6.0, 9.0, xtol=1e-10)
    return float(c_upper), c_lower


def max_abs_level_z(x, u, theta: float) -> float:
    """The z of a truth θ = max_i |μ_i| against :func:`max_abs_interval`'s own family of
    intervals (normal factors): the level p* at which the interval at p* just holds θ (the
    intervals are nested in p), z = ±Φ⁻¹((1 + p*)/2), positive where θ lies below the
    estimate max|x_i| (the estimate high), negative above. The interval at p holds θ exactly
    when |z| ≤ Φ⁻¹((1 + p)/2), so this is the z of the statement itself (for an interval
    stated as ± 1.96u of a normal estimate it is (estimate − θ)/u). At each side's worst
    pattern (the interval's miss probability 1 − p at every p) |z| is half-normal, its root
    mean square 1; at every other pattern |z| is smaller (the interval holds θ more often than
    p). Its sign is not symmetric (the worst pattern of the upper side misses on one side), so
    its root mean square, not its sd, is the measure of width (docs/validation-optical.md).
    |z| is capped at 5 (p* within 6·10⁻⁷ of 1).

    One point: the folded normal interval, z = (|x| − θ)/u where |x| ≫ u:

    >>> round(max_abs_level_z([5.0], [1.0], 4.0), 3), round(max_abs_level_z([5.0], [1.0], 6.5), 3)
    (1.0, -1.5)
    """
    from scipy.stats import norm

    x = np.abs(np.asarray(x, dtype=float))
    u = np.asarray(u, dtype=float)
    est = float(np.max(x))

    m = x.size

    def holds(p: float) -> bool:
        # the lower end first: its factor is closed form (_level_factors' own), and where it
        # is above θ the upper factor's root search is not needed
        if m > 1 and max(0.0, float(np.max(x - _lower_factor(m, p) * u))) > theta:
            return False
        c_up, c_lo = _level_factors(m, p)
        return (max(0.0, float(np.max(x - c_lo * u))) <= theta
                <= float(np.max(x + c_up * u)))

    cap = 5.0
    lo, hi = 1e-6, 1.0 - 2.0 * norm.sf(cap)
    if not holds(hi):
        z = cap
    elif holds(lo):
        z = 0.0
    else:
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if holds(mid) else (mid, hi)
        z = float(norm.ppf(0.5 * (1.0 + hi)))
    return z if theta <= est else -z
