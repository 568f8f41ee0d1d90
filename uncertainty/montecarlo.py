"""Propagation of distributions by a Monte Carlo method (JCGM 101).

- :func:`monte_carlo` — M trials, model evaluated once on arrays (JCGM 101 7.2–7.6).
- :func:`coverage_interval` — probabilistically symmetric (JCGM 101 7.7) or
  shortest (JCGM 101 7.8) coverage interval from the M model values.
- :func:`numerical_tolerance` — δ from ndig significant digits (JCGM 101 7.9.2).
- :func:`adaptive_monte_carlo` — blocks of M trials until 2·s/√h ≤ δ for the
  estimate, u and both interval ends (JCGM 101 7.9.4).
- :func:`validate_gum` — compare the GUM interval with the MC one (JCGM 101 clause 8).

Correlated inputs (non-zero off-diagonal correlation) are drawn jointly from a
multivariate normal with covariance V (JCGM 101 6.4.8); independent inputs from their
own distributions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from uncertainty.propagation import GumResult, compile_model, coverage_factor
from uncertainty.quantities import InputQuantity

__all__ = ["MonteCarloResult", "ValidationResult", "monte_carlo", "adaptive_monte_carlo",
           "coverage_interval", "numerical_tolerance", "validate_gum", "sample_inputs"]


@dataclass(frozen=True)
class MonteCarloResult:
    """Summary of a JCGM 101 propagation: estimate, u, coverage interval (7.6–7.8)."""

    value: float
    u: float
    low: float
    high: float
    p: float
    trials: int
    shortest: bool
    converged: bool = True

    @property
    def interval(self) -> tuple[float, float]:
        return (self.low, self.high)


@dataclass(frozen=True)
class ValidationResult:
    """JCGM 101 8.2: d_low, d_high against the numerical tolerance δ."""

    d_low: float
    d_high: float
    delta: float
    passed: bool
    gum_interval: tuple[float, float]
    mc_interval: tuple[float, float]


def sample_inputs(inputs: Sequence[InputQuantity], trials: int, rng: np.random.Generator,
                  correlation=None) -> list[np.ndarray]:
    """One array of ``trials`` samples per input (JCGM 101 6.4).

    Inputs involved in a non-zero correlation are drawn together from the
    multivariate normal N(x, V) (JCGM 101 6.4.8).

    >>> from uncertainty.quantities import type_b
    >>> xs = sample_inputs([type_b("a", 1.0, 0.5)], 4, np.random.default_rng(0))
    >>> xs[0].shape
    (4,)
    """
    n = len(inputs)
    out: list[np.ndarray | None] = [None] * n
    if correlation is not None:
        r = np.asarray(correlation, dtype=float)
        off = (r != 0) & ~np.eye(n, dtype=bool)
        joint = np.flatnonzero(off.any(axis=0))
        if joint.size:
            u = np.array([inputs[i].u for i in joint])
            mean = np.array([inputs[i].value for i in joint])
            v = r[np.ix_(joint, joint)] * np.outer(u, u)
            # Cholesky-free: eigen-decomposition tolerates a singular (|r| = 1) matrix
            w, q = np.linalg.eigh(v)
            a = q * np.sqrt(np.clip(w, 0.0, None))
            z = rng.standard_normal((joint.size, trials))
            xs = mean[:, None] + a @ z
            for j, i in enumerate(joint):
                out[i] = xs[j]
    for i, q in enumerate(inputs):
        if out[i] is None:
            out[i] = q.sample(rng, trials)
    return out  # type: ignore[return-value]


def _pq(p: float, m: int) -> int:
    """q = pM if an integer, else ⌊pM + 1/2⌋ (JCGM 101 7.7.1)."""
    pm = p * m
    return int(round(pm)) if abs(pm - round(pm)) < 1e-9 else int(math.floor(pm + 0.5))


def coverage_interval(y: np.ndarray, p: float = 0.95, shortest: bool = False) -> tuple[float, float]:
    """Coverage interval from model values y (JCGM 101 7.7 symmetric, 7.8 shortest).

    Symmetric: [y_(r), y_(r+q)] with r = (M − q)/2 if integer else (M − q + 1)/2
    (1-based order statistics). Shortest: the r* that minimises y_(r+q) − y_(r).

    >>> y = np.arange(1.0, 1001.0)
    >>> coverage_interval(y, 0.95)
    (25.0, 975.0)
    """
    y = np.asarray(y, dtype=float).ravel()
    m = y.size
    q = _pq(p, m)
    if not 0 < q < m:
        raise ValueError(f"too few trials ({m}) for coverage probability {p}")
    if shortest:
        s = np.sort(y)
        widths = s[q:] - s[:m - q]
        r0 = int(np.argmin(widths))
        return float(s[r0]), float(s[r0 + q])
    r = (m - q) // 2 if (m - q) % 2 == 0 else (m - q + 1) // 2
    lo_i, hi_i = r - 1, r + q - 1  # 0-based
    part = np.partition(y, (lo_i, hi_i))
    return float(part[lo_i]), float(part[hi_i])


def numerical_tolerance(u: float, ndig: int = 2) -> float:
    """δ = ½·10^l where u = c × 10^l and c has ``ndig`` digits (JCGM 101 7.9.2).

    >>> numerical_tolerance(0.1487, 2)   # c = 15, l = -2
    0.005
    >>> numerical_tolerance(0.0035, 2)   # JCGM 101 7.9.2 example: c = 35, l = -4
    5e-05
    """
    if not u > 0:
        raise ValueError(f"u must be > 0, got {u}")
    l = math.floor(math.log10(u)) - (ndig - 1)
    c = round(u / 10.0 ** l)
    if c >= 10 ** ndig:  # 0.0996 with ndig=2 -> c = 100: one place further left
        l += 1
    return 0.5 * 10.0 ** l


def quantile_numerical_u(draws, probs) -> np.ndarray:
    """The standard uncertainty, from the finite number M of ``draws``, of their empirical
    quantiles at ``probs`` (JCGM 101 7.9: the numerical precision of a Monte Carlo's
    coverage interval ends): half the distance between the quantiles at p ± √(p(1 − p)/M),
    the binomial standard deviation of the share of draws below the p-quantile carried
    through the draws' own distribution (distribution-free; for large M it is
    √(p(1 − p)/M)/f(y_p), f the density at the quantile). The estimate scatters itself:
    about 40 % at M = 400 and p = 2.5 %.

    >>> rng = np.random.default_rng(1)
    >>> s = np.mean([quantile_numerical_u(rng.normal(size=400), [0.025, 0.975])
    ...              for _ in range(400)], axis=0)
    >>> [round(float(x), 2) for x in s]     # the spread of the quantiles themselves: 0.13
    [0.13, 0.13]
    """
    y = np.asarray(draws, dtype=float)
    p = np.asarray(probs, dtype=float)
    d = np.sqrt(p * (1.0 - p) / y.size)
    lo = np.quantile(y, np.clip(p - d, 0.0, 1.0))
    hi = np.quantile(y, np.clip(p + d, 0.0, 1.0))
    return (hi - lo) / 2.0


def _summarise(y: np.ndarray, p: float, shortest: bool) -> tuple[float, float, float, float]:
    lo, hi = coverage_interval(y, p, shortest)
    return float(np.mean(y)), float(np.std(y, ddof=1)), lo, hi


def _evaluate(model, inputs, trials, rng, correlation):
    names = tuple(q.symbol for q in inputs)
    f, _ = compile_model(model, names)
    xs = sample_inputs(inputs, trials, rng, correlation)
    y = np.asarray(f(*xs), dtype=float)
    if y.shape != (trials,):
        y = np.broadcast_to(y, (trials,)).copy()
    return y


def monte_carlo(model, inputs: Sequence[InputQuantity], trials: int = 1_000_000, *,
                seed: int | None = 0, rng: np.random.Generator | None = None, p: float = 0.95,
                shortest: bool = False, correlation=None,
                return_values: bool = False):
    """Propagate the input distributions through the model (JCGM 101 7).

    The model is evaluated once on arrays of ``trials`` samples. Returns a
    :class:`MonteCarloResult` (and the model values if ``return_values``).

    JCGM 101 9.2.2: Y = X1 + X2 + X3 + X4, each N(0, 1) → u(y) = 2.00, 95 % interval ±3.92.

    >>> import sympy
    >>> from uncertainty.quantities import type_b
    >>> xs = sympy.symbols("x1:5")
    >>> q = [type_b(f"x{i}", 0.0, 1.0, "normal", k=1) for i in range(1, 5)]
    >>> r = monte_carlo(sum(xs), q, 10**6, seed=0)
    >>> round(r.u, 2), round(r.low, 2), round(r.high, 2)
    (2.0, -3.92, 3.92)
    """
    if trials < 2:
        raise ValueError(f"trials must be >= 2, got {trials}")
    gen = rng if rng is not None else np.random.default_rng(seed)
    y = _evaluate(model, inputs, int(trials), gen, correlation)
    val, u, lo, hi = _summarise(y, p, shortest)
    res = MonteCarloResult(value=val, u=u, low=lo, high=hi, p=p, trials=int(trials),
                           shortest=shortest)
    return (res, y) if return_values else res


def adaptive_monte_carlo(model, inputs: Sequence[InputQuantity], *, ndig: int = 2,
                         p: float = 0.95, seed: int | None = 0,
                         rng: np.random.Generator | None = None, block: int | None = None,
                         shortest: bool = False, correlation=None,
                         max_trials: int = 50_000_000) -> MonteCarloResult:
    """Adaptive Monte Carlo procedure (JCGM 101 7.9.4).

    Runs blocks of M = max(100/(1−p), 10⁴) trials (7.9.4 a); after h ≥ 2 blocks
    computes the standard deviations s of the h block estimates, standard
    uncertainties and interval ends; stops when 2·s/√h ≤ δ for all four, δ being
    the numerical tolerance of u(y) to ``ndig`` significant digits (7.9.2). The
    result is taken from all h·M values (7.9.4 i).

    >>> import sympy
    >>> from uncertainty.quantities import type_b
    >>> x = sympy.Symbol("x")
    >>> r = adaptive_monte_carlo(x, [type_b("x", 0.0, 1.0, "normal", k=1)], ndig=1, seed=3)
    >>> r.converged, round(r.u, 1)
    (True, 1.0)
    """
    gen = rng if rng is not None else np.random.default_rng(seed)
    m = int(block) if block else max(int(math.ceil(100.0 / (1.0 - p))), 10_000)
    values: list[np.ndarray] = []
    stats_: list[tuple[float, float, float, float]] = []
    converged = False
    while True:
        y = _evaluate(model, inputs, m, gen, correlation)
        values.append(y)
        stats_.append(_summarise(y, p, shortest))
        h = len(stats_)
        if h >= 2:
            a = np.array(stats_)
            s = a.std(axis=0, ddof=1)
            u_all = float(np.std(np.concatenate(values), ddof=1))
            delta = numerical_tolerance(u_all, ndig)
            if np.all(2.0 * s / math.sqrt(h) <= delta):
                converged = True
                break
        if h * m >= max_trials:
            break
    y = np.concatenate(values)
    val, u, lo, hi = _summarise(y, p, shortest)
    return MonteCarloResult(value=val, u=u, low=lo, high=hi, p=p, trials=y.size,
                            shortest=shortest, converged=converged)


def validate_gum(gum: GumResult, mc: MonteCarloResult, ndig: int = 2) -> ValidationResult:
    """Validate the GUM uncertainty framework against MC (JCGM 101 8.2).

    The GUM interval for the MC coverage probability p is y ± k_p·u_c with
    k_p = t_p(ν_eff) (JCGM 100 G.4), whatever fixed k the budget states. It is
    validated when d_low = |y − U_p − y_low| and d_high = |y + U_p − y_high| are
    both ≤ δ, the numerical tolerance of u_c to ``ndig`` digits (JCGM 101 8.1.3).

    >>> import sympy
    >>> from uncertainty.quantities import type_b
    >>> from uncertainty.propagation import propagate
    >>> x = sympy.Symbol("x")
    >>> q = [type_b("x", 0.0, 1.0, "normal", k=1)]
    >>> v = validate_gum(propagate(x, q), monte_carlo(x, q, 10**6, seed=2), ndig=2)
    >>> v.passed, v.delta
    (True, 0.05)
    """
    kp = coverage_factor(gum.dof, mc.p)
    up = kp * gum.u_c
    lo, hi = gum.value - up, gum.value + up
    d_low = abs(lo - mc.low)
    d_high = abs(hi - mc.high)
    delta = numerical_tolerance(gum.u_c, ndig)
    return ValidationResult(d_low=d_low, d_high=d_high, delta=delta,
                            passed=bool(d_low <= delta and d_high <= delta),
                            gum_interval=(lo, hi), mc_interval=(mc.low, mc.high))
