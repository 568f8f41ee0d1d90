"""Coverage statistics of an uncertainty study, for any specification (the engines of
``gonio validate``, :mod:`gonio.pipeline.validate` and :mod:`gonio.pipeline.coverage`, and the
specifications' own studies feed them their trials).

:func:`two_sided` both sides of one item's coverage from its errors (result − truth), U and u_c
per comparison: coverage with its Clopper–Pearson interval, the spread of z = error/u_c and
the flags (under-covers, over-wide); :func:`within` and :func:`coverage` the fraction of
|error| ≤ U with its binomial u (:func:`binomial_u`) and, for clustered comparisons, the
standard error over trials; :func:`item_coverage` one item's row (:class:`ItemCoverage`)
from (value, truth, U, u_c) per trial with the Wilson interval (:func:`wilson_interval`).
Nothing here knows a specification: each says what its truth and its errors are.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from gonio.errors import GonioError

__all__ = ["MIN_COVERAGE", "MIN_SD_Z", "clopper_pearson", "coverage_flags", "two_sided",
           "within", "binomial_u", "coverage", "wilson_interval", "ItemCoverage",
           "item_coverage", "spawn_seed", "chi_square_z", "stated_record", "bound_record",
           "coverage_table_from", "format_coverage"]

#: Wilson-interval coverage factor (95 %).
_Z95 = 1.959963984540054

#: Below this coverage of U an item is flagged as under-covering.
MIN_COVERAGE = 0.90
#: Below this spread of z = (result − truth)/u_c an item's U is flagged as over-wide, where
#: the budget is gonio's own (a standard's prescribed annex budget is stated as it is).
MIN_SD_Z = 0.30


def clopper_pearson(hits: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """The exact (Clopper–Pearson) interval of a binomial proportion, through
    :func:`scipy.stats.binomtest` (``proportion_ci(method="exact")``).

    A study's report asks for the same (hits, n) for many of its items (every item that
    covered in all of its trials, say), and each answer is a root search over the binomial
    distribution: the interval is computed once per (hits, n, level) and kept
    (:func:`_clopper_pearson`; the same numbers, bit for bit).

    >>> [round(x, 4) for x in clopper_pearson(95, 100)]
    [0.8872, 0.9836]
    """
    if n < 1:
        return (math.nan, math.nan)
    return _clopper_pearson(int(hits), int(n), float(level))


@functools.lru_cache(maxsize=4096)
def _clopper_pearson(hits: int, n: int, level: float) -> tuple[float, float]:
    from scipy.stats import binomtest

    ci = binomtest(hits, n).proportion_ci(confidence_level=level, method="exact")
    return float(ci.low), float(ci.high)


def coverage_flags(coverage: float, sd_z: float | None, own_budget: bool = True) -> list[str]:
    """``under-covers`` (coverage < :data:`MIN_COVERAGE`) and ``over-wide`` (sd z <
    :data:`MIN_SD_Z`, only where the budget is gonio's own).

    >>> coverage_flags(0.85, 1.0), coverage_flags(1.0, 0.05), coverage_flags(1.0, 0.05, False)
    (['under-covers'], ['over-wide'], [])
    """
    flags = []
    if not coverage >= MIN_COVERAGE:
        flags.append("under-covers")
    if own_budget and sd_z is not None and math.isfinite(sd_z) and sd_z < MIN_SD_Z:
        flags.append("over-wide")
    return flags


def two_sided(errors, U, u_c, own_budget: bool = True) -> dict:
    """Both sides of an item's coverage from its trials: ``errors`` = result − truth,
    ``U`` and ``u_c`` per trial (arrays of the same shape; E's points flattened).

    ``coverage`` (|error| ≤ U) with ``hits``, ``n`` and the 95 % Clopper–Pearson interval
    (``cp_low``, ``cp_high``); ``z_mean`` and ``z_sd`` of z = error/u_c (an honest budget
    has z_mean ≈ 0 and z_sd ≈ 1: z_sd ≪ 1 is a U too wide, ≫ 1 too narrow); ``flags``
    (:func:`coverage_flags`); ``own_budget``.

    >>> r = two_sided([0.1, -0.2, 0.05, 0.3], [0.4] * 4, [0.2] * 4)
    >>> r["coverage"], r["hits"], round(r["z_sd"], 3), r["flags"]
    (1.0, 4, 1.028, [])
    >>> two_sided([0.1, -0.2, 0.05, 0.3], [8.0] * 4, [4.0] * 4)["flags"]
    ['over-wide']
    """
    e = np.asarray(errors, dtype=float).ravel()
    U = np.broadcast_to(np.asarray(U, dtype=float), np.shape(errors)).ravel()
    u = np.broadcast_to(np.asarray(u_c, dtype=float), np.shape(errors)).ravel()
    ok = np.isfinite(e) & np.isfinite(U)
    e, U, u = e[ok], U[ok], u[ok]
    n = int(e.size)
    hits = int(np.count_nonzero(np.abs(e) <= U))
    cov = hits / n if n else math.nan
    lo, hi = clopper_pearson(hits, n)
    zok = np.isfinite(u) & (u > 0)
    z = e[zok] / u[zok]
    z_mean = float(z.mean()) if z.size else None
    z_sd = float(z.std(ddof=1)) if z.size > 1 else None
    return {"n": n, "hits": hits, "coverage": cov, "cp_low": lo, "cp_high": hi,
            "z_mean": z_mean, "z_sd": z_sd, "own_budget": bool(own_budget),
            "flags": coverage_flags(cov, z_sd, own_budget)}


def chi_square_z(s, sigma, nu):
    """z of a standard deviation against its χ² model: Φ⁻¹(F_χ²(ν s²/σ²; ν)), N(0, 1) when
    ν s²/σ² ~ χ²(ν) (JCGM 100 E.4.3, the model a one-sided χ² interval is stated by); the
    spread of z = (s − σ)/u_c, u_c = s/√(2ν), is that of a ratio with s in the denominator,
    unbounded for small ν, and not a measure of the interval's width. The one-sided 95 %
    interval [0, s·√(ν/χ²_0.05,ν)] holds σ exactly when this z ≥ −z₀.₉₅ = −1.645.

    >>> rng = np.random.default_rng(0)
    >>> s = np.sqrt(rng.chisquare(2, 20000) / 2)            # σ = 1, ν = 2
    >>> z = chi_square_z(s, 1.0, 2.0)
    >>> abs(float(z.mean())) < 0.03, round(float(z.std()), 1)
    (True, 1.0)
    """
    from scipy.stats import chi2, norm

    s, sigma, nu = (np.asarray(x, dtype=float) for x in (s, sigma, nu))
    return norm.ppf(chi2.cdf(nu * (s / sigma) ** 2, nu))


def within(hits) -> dict:
    """Fraction of the comparisons ``hits`` (booleans) that hold, with its count and binomial u.

    >>> within([True, True, False, True])["fraction"]
    0.75
    """
    h = np.asarray(hits, dtype=bool)
    p = float(h.mean()) if h.size else math.nan
    return {"fraction": p, "n": int(h.size),
            "u_binomial": math.sqrt(p * (1 - p) / h.size) if h.size else math.nan}


def binomial_u(p: float, n: int) -> float:
    """Standard uncertainty of a coverage fraction p from n independent Bernoulli trials.

    u = √(p(1 − p)/n) (binomial distribution); for the clustered comparisons of a
    validation this is a lower bound (see ``u_trials`` in :func:`coverage`).

    >>> round(binomial_u(0.95, 200), 5)
    0.01541
    """
    return math.sqrt(p * (1.0 - p) / n) if n > 0 else math.nan


def coverage(abs_err: np.ndarray, U: np.ndarray) -> dict:
    """Coverage of |E − truth| ≤ U; axis 0 = trials, further axes pooled.

    Returns the overall fraction, its binomial u (:func:`binomial_u`, as if every
    comparison were independent), ``u_trials`` (standard error of the mean of the
    per-trial fractions: accounts for the correlation within a trial), the number
    of comparisons, and the fraction per point (last axis).

    A NaN error is a reading the calibration set aside (its screening): it is no comparison
    (neither a hit nor a miss); the fractions are over the readings used, and
    ``set_aside`` counts the others (the key only where there are any). So that a false
    set-aside (a good reading screened out, or a miss hidden by screening) is visible, a
    study with set-asides also reports them per point (``set_aside_per_point``) and the
    coverage with each set-aside counted as a miss (``fraction_set_aside_as_miss``) and as a
    hit (``fraction_set_aside_as_hit``): the coverage without them lies between.

    >>> c = coverage(np.array([[0.1, 0.5], [0.2, 0.1]]), np.array([0.3, 0.3]))
    >>> c["fraction"], c["n"], c["per_point"]
    (0.75, 4, [1.0, 0.5])
    >>> c = coverage(np.array([[0.1, np.nan], [0.2, 0.5]]), np.array([0.3, 0.3]))
    >>> round(c["fraction"], 4), c["n"], c["per_point"], c["set_aside"]
    (0.6667, 3, [1.0, 0.0], 1)
    >>> c["set_aside_per_point"], c["fraction_set_aside_as_miss"], c["fraction_set_aside_as_hit"]
    ([0, 1], 0.5, 0.75)
    """
    a = np.asarray(abs_err, dtype=float)
    u = np.asarray(U, dtype=float).reshape((-1,) + (1,) * (a.ndim - 1))
    used = np.isfinite(a)
    hit = (a <= u) & used
    n = int(used.sum())
    p = float(hit.sum() / n) if n else math.nan
    h_t, n_t = (x.reshape(x.shape[0], -1).sum(axis=1) for x in (hit, used))
    per_trial = h_t[n_t > 0] / n_t[n_t > 0]
    t = per_trial.size
    u_tr = float(per_trial.std(ddof=1) / math.sqrt(t)) if t > 1 else math.nan
    h_p, n_p = (x.reshape(-1, x.shape[-1]).sum(axis=0) for x in (hit, used))
    per_point = np.where(n_p > 0, h_p / np.maximum(n_p, 1), math.nan)
    out = {"fraction": p, "u_binomial": binomial_u(p, n), "u_trials": u_tr,
           "n": n, "per_point": [float(x) for x in per_point]}
    if n < a.size:
        out["set_aside"] = int(a.size - n)
        out["set_aside_per_point"] = [int(x) for x in
                                      (~used).reshape(-1, a.shape[-1]).sum(axis=0)]
        out["fraction_set_aside_as_miss"] = float(hit.sum() / a.size)
        out["fraction_set_aside_as_hit"] = float((hit.sum() + a.size - n) / a.size)
    return out


def spawn_seed(seed: int, key: int, index: int) -> int:
    """numpy SeedSequence(seed, spawn_key=(key, index)) as one 32-bit seed: the seed of
    trial ``index`` of study part ``key`` (a case, a specification's stream), independent of
    every other trial — the same number as the ``index``-th child of
    ``SeedSequence(seed, spawn_key=(key,)).spawn(...)``, so a trial's random stream does not
    depend on which other trials run, in which batch, on which worker, or in which order.

    >>> kid = np.random.SeedSequence(0, spawn_key=(2,)).spawn(5)[4]
    >>> spawn_seed(0, 2, 4) == int(kid.generate_state(1, np.uint32)[0])
    True
    """
    ss = np.random.SeedSequence(seed, spawn_key=(int(key), int(index)))
    return int(ss.generate_state(1, np.uint32)[0])


def wilson_interval(hits: int, n: int, z: float = _Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion.

    >>> [round(v, 4) for v in wilson_interval(95, 100)]
    [0.8882, 0.9785]
    """
    if n < 1:
        raise GonioError("a coverage needs at least one trial")
    p = hits / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return max(0.0, c - h), min(1.0, c + h)


@dataclass(frozen=True)
class ItemCoverage:
    """One item's coverage over the seeds. ``statistic``: what ``coverage`` and z are of —
    ``"u_c"``: |value − truth| ≤ U and z = (value − truth)/u_c; ``"chi-square"``: an item
    stated by its one-sided χ² interval alone (a standard deviation: no k), the truth inside
    that interval and z its χ² z (:func:`chi_square_z`), with z on u_c kept beside it
    (``z_uc_mean``, ``z_uc_sd``, ``max_norm_error_uc``); ``"interval"``: stated by another
    interval (a range, a rule's outcome range), the truth inside it, z on u_c; ``"level"``:
    an interval inverted from its estimator's distribution whose item gives its level table
    (:func:`level_z_at`), the truth inside it and z that interval's own level at the
    truth, z on u_c beside it; ``"mixed"``:
    trials of both kinds. ``p_stated``: the mean coverage probability the trials' intervals
    state (an outcome range states its own, above 95 %): coverage is judged against it
    (flag ``below its p`` where the Clopper–Pearson upper end is under it); for a
    discrete, skewed outcome z on u_c is not normal and its spread is information only.
    ``bound_trials``: the trials whose statement holds a bounded effect at its bound
    (:func:`bound_record`): their U is not k·u_c of a root-sum-square budget, so z on u_c
    sits well inside ±2 at conditions inside the bound and its spread below 1 is that bound
    held, by design (in a fixed case at the bound, the noise's spread alone)."""

    key: str
    clause: str
    n: int
    hits: int
    coverage: float
    u_coverage: float
    wilson_low: float
    wilson_high: float
    median_norm_error: float
    max_norm_error: float
    cp_low: float = math.nan
    cp_high: float = math.nan
    z_mean: float | None = None
    z_sd: float | None = None
    flags: tuple = ()
    statistic: str = "u_c"
    z_uc_mean: float | None = None
    z_uc_sd: float | None = None
    max_norm_error_uc: float | None = None
    p_stated: float | None = None
    bound_trials: int = 0


def _trial_judged(v: float, t: float, U: float, u: float, stated: dict | None):
    """(hit, z, z on u_c, |normalised error|, kind) of one trial: by its stated interval (``stated``:
    {"interval": [lo, hi], "nu": ν of its χ² model or None}) or by |v − t| ≤ U."""
    z_uc = (v - t) / u if u > 0 else math.nan        # no z where u_c is 0 (two_sided)
    ne = abs(v - t) / u if u > 0 else (0.0 if v == t else math.inf)
    iv = (stated or {}).get("interval")
    if iv is None:
        return abs(v - t) <= U, z_uc, z_uc, ne, "u_c"
    hit = iv[0] <= t <= iv[1]
    zl = stated.get("z_level")
    if zl is not None and math.isfinite(zl):
        return hit, float(zl), z_uc, abs(float(zl)), "level"
    nu = stated.get("nu")
    if nu and t > 0:
        z = float(chi_square_z(v, t, nu))
        return hit, z, z_uc, abs(z), "chi-square"
    return hit, z_uc, z_uc, ne, "interval"


def level_z_at(grid: dict | None, truth: float) -> float | None:
    """The level z of an interval statement at the truth, from the item's table of it
    (``{"value": [θ_i ascending], "z": [z_i]}``, the ``level_z_grid`` of an item's details:
    Φ⁻¹ of the probability integral transform of θ in the distribution the interval was
    inverted from, or the signed level of the smallest interval of its family holding θ),
    by linear interpolation; outside the table the end value; None without a table.

    >>> level_z_at({"value": [0.0, 1.0, 2.0], "z": [2.0, 0.0, -2.0]}, 1.5)
    -1.0
    >>> level_z_at({"value": [0.0, 1.0], "z": [2.0, 0.0]}, 5.0), level_z_at(None, 1.0)
    (0.0, None)
    """
    if not grid or truth is None or not math.isfinite(truth):
        return None
    x, z = np.asarray(grid["value"], float), np.asarray(grid["z"], float)
    if x.size < 2 or np.any(np.diff(x) <= 0):
        raise GonioError("a level table needs at least two ascending values")
    return float(np.interp(truth, x, z))


def level_z_discrete(dist: dict | None, truth: float, v: float) -> float | None:
    """The level z of a discrete (or mixed) stated distribution at the truth: the
    randomised probability integral transform (Brockwell 2007, Czado, Gneiting & Held 2009)
    u = F(t−) + v·(F(t) − F(t−)), v uniform on [0, 1] (drawn by the caller from the trial's
    seed), z = −Φ⁻¹(u) (positive where the truth lies low in the distribution: the value
    read high). F is that of max(A, B), A the atoms ``dist["atoms"]`` ([[x, p], …]) and B
    ~ N(m, s²) for ``dist["normal"]`` = [m, s] (None: A alone): F(x) = F_A(x)·Φ((x − m)/s).
    Where the distribution is the truth's, u is uniform and z N(0, 1) exactly, whatever the
    steps of the grid (the mid-value v = ½ would hold z at 0 when one outcome carries
    nearly all the probability: a spread a discrete outcome cannot reach). None without a
    distribution.

    >>> d = {"atoms": [[0.02, 0.25], [0.05, 0.5], [0.1, 0.25]], "normal": None}
    >>> abs(round(level_z_discrete(d, 0.05, 0.5), 6)), round(level_z_discrete(d, 0.02, 0.5), 3)
    (0.0, 1.15)
    >>> round(float(__import__("scipy").stats.norm.ppf(1 - 0.125)), 3)      # u = 0.25/2
    1.15
    """
    from scipy.stats import norm

    if not dist or truth is None or not math.isfinite(truth):
        return None
    a = np.asarray(dist["atoms"], float).reshape(-1, 2)
    w = a[:, 1] / a[:, 1].sum()
    tol = 1e-9 * max(abs(truth), 1e-300)
    fa_lt, fa_le = float(w[a[:, 0] < truth - tol].sum()), float(w[a[:, 0] <= truth + tol].sum())
    nb = dist.get("normal")
    g = 1.0 if not nb or not nb[1] > 0 else float(norm.cdf((truth - nb[0]) / nb[1]))
    if nb and not nb[1] > 0:
        g = 1.0 if truth >= nb[0] else 0.0
    u = fa_lt * g + float(v) * (fa_le - fa_lt) * g
    u = min(max(u, 1e-15), 1.0 - 1e-15)
    return float(np.clip(-norm.ppf(u), -8.0, 8.0))


def _spread(z) -> tuple[float | None, float | None]:
    z = np.asarray([x for x in z if math.isfinite(x)], dtype=float)
    return (float(z.mean()) if z.size else None), (float(z.std(ddof=1)) if z.size > 1 else None)


def item_coverage(records: list[tuple[float, float, float, float]], key: str = "",
                  clause: str = "", stated: list | None = None,
                  judge_spread: bool = True, bound: list | None = None) -> ItemCoverage:
    """Coverage of one item from (value, truth, U, u_c) per seed; ``stated`` (one entry per
    record, None for a value ± U) the interval a trial's item was stated by alone and the ν
    of its χ² model (:func:`_trial_judged`): the interval must hold the truth, and the
    spread is that of the χ² z (:func:`chi_square_z`), the statistic that interval's 95 %
    is a probability of; z on u_c (s in its denominator, unbounded for few degrees of
    freedom) is kept beside it. ``judge_spread`` False: no ``over-wide`` flag (a study case
    at one fixed condition, where a Type B line is one fixed offset and z's spread is the
    noise's alone: coverage is the test there). ``bound``: per record, whether its
    statement holds a bounded effect at its bound (:func:`bound_record`), counted in
    ``bound_trials``.

    >>> c = item_coverage([(1.0, 1.1, 0.2, 0.1), (1.0, 1.3, 0.2, 0.1)])
    >>> c.hits, c.coverage, round(c.u_coverage, 4)
    (1, 0.5, 0.3536)
    >>> c = item_coverage([(0.1, 1.0, 0.34, 0.05)], stated=[{"interval": [0.0, 0.44], "nu": 2}])
    >>> c.hits, c.statistic, round(c.max_norm_error, 2), round(c.max_norm_error_uc, 1)
    (0, 'chi-square', 2.33, 18.0)
    """
    n = len(records)
    if n == 0:
        raise GonioError(f"item {key!r}: no seed gave a measured value with a truth")
    judged = [_trial_judged(*r, st) for r, st in zip(records, stated or [None] * n)]
    hits = sum(bool(j[0]) for j in judged)
    c = hits / n
    lo, hi = wilson_interval(hits, n)
    ne = sorted(j[3] for j in judged)
    kinds = {j[4] for j in judged}
    statistic = kinds.pop() if len(kinds) == 1 else "mixed"
    z_mean, z_sd = _spread(j[1] for j in judged)
    cp_lo, cp_hi = clopper_pearson(hits, n)
    uc = {}
    ps = [st["p"] for st in (stated or []) if st and st.get("p") is not None]
    p_stated = float(np.mean(ps)) if ps else None
    flags = coverage_flags(c, z_sd, own_budget=judge_spread)
    if p_stated is not None and cp_hi < p_stated:
        flags.append("below its p")       # the intervals hold the truth less often than stated
    if statistic != "u_c":
        m, sd = _spread(j[2] for j in judged)
        uc = {"z_uc_mean": m, "z_uc_sd": sd,
              "max_norm_error_uc": max(abs(v - t) / u if u > 0 else math.inf
                                       for v, t, _, u in records)}
    return ItemCoverage(key, clause, n, hits, c, math.sqrt(c * (1 - c) / n), lo, hi,
                        ne[n // 2] if n % 2 else 0.5 * (ne[n // 2 - 1] + ne[n // 2]), ne[-1],
                        cp_lo, cp_hi, z_mean, z_sd,
                        tuple(flags), statistic, **uc, p_stated=p_stated,
                        bound_trials=sum(bool(b) for b in (bound or [])))


def stated_record(u) -> dict:
    """An item stated by its interval alone (k None: a dispersion, range or extreme,
    :func:`gonio.result.statement.state_interval`): {"interval": [lo, hi], "nu": ν}, ν the
    degrees of freedom its one-sided χ² limit was computed with (:func:`gonio.result.gum.
    std_dev_uncertainty`: ν; a dispersion with its own budget: the stated ν,
    :func:`gonio.result.statement.chi2_nu`, its integer part),
    None for an interval of another model (the half range's); {} for a value ± U."""
    from gonio.result.statement import chi2_nu

    if u.k is not None or u.interval is None:
        return {}
    nu = None
    if u.k_source == "chi-square" and u.nu_eff is not None and math.isfinite(u.nu_eff):
        nu = chi2_nu(u.nu_eff)
    p = u.coverage_probability
    return {"interval": [float(u.interval[0]), float(u.interval[1])], "nu": nu,
            **({"p": float(p)} if p is not None and math.isfinite(float(p)) else {})}


def bound_record(item) -> dict:
    """{"bound": True} for an item whose statement holds a bounded effect at its bound (its
    details' ``bound_condition``: :func:`gonio.result.gum.dispersion_bound_statement`,
    :func:`gonio.result.gum.max_magnitude_statement`'s ``bounded``, a value ± (a + k·u_rest)),
    {} otherwise: the study's table marks the item (:class:`ItemCoverage`'s ``bound_trials``).

    >>> from types import SimpleNamespace as NS
    >>> bound_record(NS(details={"bound_condition": {"U": 1.0}})), bound_record(NS(details={}))
    ({'bound': True}, {})
    """
    return {"bound": True} if (getattr(item, "details", None) or {}).get("bound_condition") \
        else {}


def coverage_table_from(trials: list[dict], items: tuple[str, ...] | None = None,
                        judge_spread: bool = True) -> "pd.DataFrame":
    """Per item over the trials (in order): :class:`ItemCoverage` rows. A trial is {item:
    {clause, value, truth, U, u_c}} with, for an item stated by its interval alone, {interval,
    nu} (:func:`stated_record`); value None: not measured or no truth in that trial.
    ``judge_spread``: as in :func:`item_coverage`."""
    import pandas as pd

    recs: dict[str, list] = {}
    stated: dict[str, list] = {}
    bounds: dict[str, list] = {}
    clauses: dict[str, str] = {}
    for tr in trials:
        for key, r in tr.items():
            if items is not None and key not in items:
                continue
            clauses[key] = r["clause"]
            if r["value"] is not None:
                recs.setdefault(key, []).append((r["value"], r["truth"], r["U"], r["u_c"]))
                stated.setdefault(key, []).append(
                    {"interval": r["interval"], "nu": r.get("nu"), "p": r.get("p"),
                     "z_level": r.get("z_level")}
                    if r.get("interval")
                    else None)
                bounds.setdefault(key, []).append(bool(r.get("bound")))
    rows = [item_coverage(v, k, clauses[k], stated[k], judge_spread, bounds[k]).__dict__
            for k, v in recs.items()]
    return pd.DataFrame(rows, columns=list(ItemCoverage.__dataclass_fields__))


_STAT_LABEL = {"chi-square": "chi2 z", "level": "level z"}


def format_coverage(df, title: str) -> str:
    """The per-item coverage table as printed by ``gonio validate --spec`` and the benchmark."""
    lines = [title, f"{'item':32s} {'clause':10s} {'n':>4s} {'cover':>6s} "
             f"{'Clopper-Pearson 95 %':>20s} {'z mean':>7s} {'z sd':>6s} {'max|z|':>7s}"]
    for r in df.itertuples():
        flag = f"  FLAG: {', '.join(r.flags)}" if len(r.flags) else ""
        zm = "—" if r.z_mean is None or r.z_mean != r.z_mean else f"{r.z_mean:+.2f}"
        zs = "—" if r.z_sd is None or r.z_sd != r.z_sd else f"{r.z_sd:.2f}"
        st = getattr(r, "statistic", "u_c")
        ps = getattr(r, "p_stated", None)
        p_txt = "" if ps is None or ps != ps else f", stated p {ps:.3f}"
        on_uc = "" if st in ("u_c", None) or st != st else (
            f"  [{_STAT_LABEL.get(st, st)}{p_txt}; z on u_c: mean "
            f"{r.z_uc_mean:+.2f}, sd {r.z_uc_sd:.2f}, max|z| {r.max_norm_error_uc:.2f}]")
        nb = int(getattr(r, "bound_trials", 0) or 0)
        bound = "" if not nb else (
            "  [bound held]" if nb == r.n else f"  [bound held in {nb} of {r.n}]")
        lines.append(f"{r.key:32s} {r.clause:10s} {r.n:4d} {r.coverage:6.3f} "
                     f"      [{r.cp_low:.3f}, {r.cp_high:.3f}] {zm:>7s} {zs:>6s} "
                     f"{r.max_norm_error:7.2f}{on_uc}{bound}{flag}")
    lines.append("cover: fraction of trials with |value - truth| <= U, or with the truth inside "
                 "the stated interval for an item stated by its interval alone (95 % "
                 "Clopper-Pearson interval); z = (value - truth)/u_c, or for a standard "
                 "deviation stated by its chi-square interval [chi2 z] Phi^-1(F_chi2(nu "
                 "value^2/truth^2; nu)) with z on u_c beside it, or for an interval "
                 "inverted from the estimator's distribution [level z] the interval's own "
                 "level at the truth (Phi^-1 of the truth's probability integral transform); "
                 "flagged: coverage < 90 % "
                 "(under-covers), sd z < 0.3 (over-wide U), the Clopper-Pearson upper end "
                 "below the mean probability the intervals state (below its p); "
                 "[bound held]: U holds a bounded effect at its bound (JCGM 100 4.3.7), not "
                 "a root-sum-square line, so z sd on u_c below 1 is that bound, by design")
    return "\n".join(lines) + "\n"
