"""Equivalent degrees of freedom, noise identification and χ² intervals.

Contents
--------
==============================  ===============================================
:func:`edf_greenhall`           Greenhall & Riley (2003) edf of a variance estimate
:func:`edf_for`                 the edf of one estimator kind (adev/mdev/hdev/totdev)
:func:`edf_simple`              SP 1065 Table 5 approximations (kept for reference)
:func:`edf_totdev`              total variance, SP 1065 Table 7
:func:`noise_id_lag1`           noise type by the lag-1 autocorrelation
:func:`noise_id_b1`             noise type by the B1 and R(n) ratios (cross-check)
:func:`rn_ratio_of_phase`       R(n) = MVAR/AVAR of a phase series at m
:func:`chi2_interval`           χ² interval of a variance with a given edf
==============================  ===============================================

Noise types are the exponent α of the rate (frequency) power spectral density
S_y(f) ∝ f^α: +2 white phase (quantisation), +1 flicker phase, 0 white rate (angle
random walk), −1 flicker rate (bias instability), −2 random-walk rate (rate random
walk), −3 flicker-walk rate, −4 random-run rate (NIST SP 1065 §5.2, Table 3).

References
----------
.. [GR2003] C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances
   based on finite differences", Proc. 35th PTTI (2003): eqs. (7)–(13), Tables 1–3
   (docs/references.md#gr2003).
.. [RG2004] W. J. Riley and C. A. Greenhall, "Power law noise identification using
   the lag 1 autocorrelation", Proc. 18th EFTF (2004) (docs/references.md#rg2004).
.. [SP1065] W. J. Riley, NIST SP 1065 (2008): §5.2.5 (R(n)), §5.3 (edf),
   §5.6 (noise identification, B1), Table 5, Table 7 (docs/references.md#sp1065).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy import stats
from scipy.special import comb

from gonio.errors import GonioError

__all__ = [
    "KINDS", "edf_greenhall", "edf_for", "edf_simple", "edf_totdev",
    "noise_id_lag1", "noise_id_b1", "b1_expected", "rn_expected", "rn_ratio_of_phase",
    "chi2_interval",
    "GR_TABLE1", "GR_TABLE2", "GR_TABLE3", "J_MAX",
]

#: Estimator kinds: (difference order d, modified, overlapping) for Greenhall's edf.
KINDS = {"adev": (2, False), "mdev": (2, True), "hdev": (3, False), "totdev": (2, False)}

#: Largest number of terms of the basic sum evaluated directly ([GR2003] §3).
J_MAX = 100

#: [GR2003] Table 1: (a0, a1) of 1/edf ≈ (a0 − a1/r)/r, modified variances (F = 1),
#: rows α = 2 … −4, columns d = 1, 2, 3 (None: α + 2d ≤ 1, not defined).
GR_TABLE1 = {
    2: ((2 / 3, 1 / 3), (7 / 9, 1 / 2), (22 / 25, 2 / 3)),
    1: ((0.840, 0.345), (0.997, 0.616), (1.141, 0.843)),
    0: ((1.079, 0.368), (1.033, 0.607), (1.184, 0.848)),
    -1: (None, (1.048, 0.534), (1.180, 0.816)),
    -2: (None, (1.302, 0.535), (1.175, 0.777)),
    -3: (None, None, (1.194, 0.703)),
    -4: (None, None, (1.489, 0.702)),
}
#: [GR2003] Table 2: (a0, a1), unmodified variances (F = m), same layout.
GR_TABLE2 = {
    2: ((3 / 2, 1 / 2), (35 / 18, 1.0), (231 / 100, 3 / 2)),
    1: ((78.6, 25.2), (790.0, 410.0), (9950.0, 6520.0)),
    0: ((2 / 3, 1 / 6), (2 / 3, 1 / 3), (7 / 9, 1 / 2)),
    -1: (None, (0.852, 0.375), (0.997, 0.617)),
    -2: (None, (1.079, 0.368), (1.033, 0.607)),
    -3: (None, None, (1.053, 0.553)),
    -4: (None, None, (1.302, 0.535)),
}
#: [GR2003] Table 3: (b0, b1) of sz(0, m) ≈ b0 + b1 ln m for α = +1, d = 1, 2, 3.
GR_TABLE3 = ((6.0, 4.0), (15.23, 12.0), (47.8, 40.0))


# ------------------------------------------------------------- Greenhall kernels
def _sw(t: np.ndarray, alpha: int) -> np.ndarray:
    """[GR2003] eq. (7): the generalised autocovariance of power-law noise α
    (up to a constant factor, which cancels in the edf); 0·ln 0 = 0."""
    a = np.abs(t)
    if alpha in (2, 0, -2, -4):
        return {2: -a, 0: a ** 3, -2: a ** 5, -4: a ** 7}[alpha]
    lg = np.zeros(a.shape)                   # the same values as ln a where a > 0, in one pass
    np.log(a, out=lg, where=a > 0)
    return {1: t ** 2 * lg, -1: t ** 4 * lg, -3: t ** 6 * lg}[alpha]


def _sx(t, f, alpha: int):
    """[GR2003] eq. (8): the phase-averaging filter of factor F (F = inf: limit)."""
    if f is None:
        return _sw(t, alpha + 2)
    inv = 1.0 / f
    return f ** 2 * (2.0 * _sw(t, alpha) - _sw(t - inv, alpha) - _sw(t + inv, alpha))


def _sz(t, f, alpha: int, d: int):
    """[GR2003] eq. (9): the d-th difference of :func:`_sx` at unit lag,
    Σ_k (−1)^k C(2d, d+k) sx(t + k)."""
    out = 0.0
    for k in range(-d, d + 1):
        out = out + (-1) ** abs(k) * comb(2 * d, d + k, exact=True) * _sx(t + k, f, alpha)
    return out


def _basic_sum(j_lim, m_terms, s, f, alpha, d):
    """[GR2003] eq. (10), vectorised over the estimator arrays (all 1-D, same shape):
    sz(0)² + (1 − J/M) sz(J/S)² + 2 Σ_{j=1}^{J−1} (1 − j/M) sz(j/S)²; rows are
    processed 128 at a time (bounded temporaries)."""
    j_lim = np.atleast_1d(np.asarray(j_lim, dtype=np.float64))
    rows = 128
    if j_lim.size > rows:
        m_terms = np.broadcast_to(np.asarray(m_terms, dtype=np.float64), j_lim.shape)
        s = np.broadcast_to(np.asarray(s, dtype=np.float64), j_lim.shape)
        fb = None if f is None else np.broadcast_to(np.asarray(f, dtype=np.float64),
                                                      j_lim.shape)
        out = np.empty(j_lim.size)
        for a in range(0, j_lim.size, rows):
            sl = slice(a, a + rows)
            out[sl] = _basic_sum(j_lim[sl], m_terms[sl], s[sl],
                                 None if fb is None else fb[sl], alpha, d)
        return out
    m_terms = np.asarray(m_terms, dtype=np.float64)
    s = np.asarray(s, dtype=np.float64)
    fcol = None if f is None else np.asarray(f, dtype=np.float64)[:, None]
    out = _sz(np.zeros((j_lim.size, 1)), fcol, alpha, d)[:, 0] ** 2
    out = out + (1.0 - j_lim / m_terms) * _sz((j_lim / s)[:, None], fcol, alpha, d)[:, 0] ** 2
    jmax = int(j_lim.max()) if j_lim.size else 0
    if jmax > 1:
        j = np.arange(1, jmax, dtype=np.float64)[None, :]
        z = _sz(j / s[:, None], fcol, alpha, d) ** 2
        w = np.where(j < j_lim[:, None], 2.0 * (1.0 - j / m_terms[:, None]), 0.0)
        out = out + np.sum(w * z, axis=1)
    return out


#: Above this many estimates in the capped branch, interpolate (see :func:`_capped`).
_CAPPED_EXACT = 512


#: Points of the capped branch's grid, uniform in ln r (see :func:`_capped`).
_CAPPED_GRID = 4096
#: The capped branch's grids, by (branch, α, d, lowest decade of r): computed once.
_CAPPED_CACHE: dict = {}


def _capped(r: np.ndarray, fn, key, d: int, n_phase: float) -> np.ndarray:
    """fn(r) for the capped branch of [GR2003] (J > J_MAX, r ≤ d + 1), where the
    basic sum depends on r = M/S alone. For many values (``taus="all"``) fn is
    evaluated once on a fixed grid — :data:`_CAPPED_GRID` values uniform in ln r from the
    decade below 1/``n_phase`` (no r = M/S is smaller) to d + 1, half as many more uniform
    in r on [1, d + 1], plus every r = J_MAX·k/j (j < J_MAX, k ≥ 1),
    where a term sz(j·r/J_MAX) crosses an integer and the sum has a kink — kept for the
    process (``key`` names the branch, α and d), and interpolated linearly in ln r
    (relative error below 2e-5 — checked in the tests — against the few per cent by
    which this branch of the algorithm itself approximates the edf).

    The grid depends on the record's length only (through the decade of 1/n), never on
    the chunk of τ or on the data (an earlier version rebuilt a grid for every chunk of
    16 384 τ, and how many chunks took this branch depended on the noise type identified
    at the largest τ, from a few terms, so by chance: 2 s for a white-noise record
    identified α = 2 there (closed form), 14 s for another of the same length identified
    α = 1)."""
    if r.size <= _CAPPED_EXACT:
        return fn(r)
    decade = min(math.floor(math.log10(1.0 / float(n_phase))),
                 math.floor(math.log10(float(r.min()))))
    ck = (key, decade, d)
    table = _CAPPED_CACHE.get(ck)
    if table is None:
        lo, hi = 10.0 ** decade, d + 1.0
        j = np.arange(1, J_MAX)
        kinks = np.concatenate([J_MAX * k / j for k in range(1, d + 2)])
        kinks = kinks[(kinks > lo) & (kinks < hi)]
        # uniform in ln r, and denser on [1, d + 1] where the kinks lie
        grid = np.unique(np.concatenate((np.geomspace(lo, hi, _CAPPED_GRID),
                                         np.linspace(1.0, hi, _CAPPED_GRID // 2), kinks)))
        table = (np.log(grid), fn(grid))
        _CAPPED_CACHE[ck] = table
    return np.interp(np.log(r), *table)


def _table(tab, alpha, d):
    row = tab.get(alpha)
    val = None if row is None else row[d - 1]
    if val is None:
        raise GonioError(f"edf not defined for noise alpha={alpha} with difference order "
                         f"d={d} (needs alpha + 2d > 1)", key="alpha")
    return val


def edf_greenhall(alpha: int, d: int, m, n_phase: int, *, modified: bool = False,
                  overlapping: bool = True) -> np.ndarray:
    """Equivalent degrees of freedom of a variance estimate by Greenhall's algorithm.

    [GR2003] (summarised in SP 1065 §5.3.3), for the d-th difference variances:
    d = 2 Allan (``modified`` False) or modified Allan (True), d = 3 Hadamard; noise
    type α with α + 2d > 1; averaging factors ``m`` (array); ``n_phase`` phase
    points; ``overlapping`` stride S = m (else 1). With F = 1 (modified) or m,
    L = m/F + m·d, M = 1 + ⌊S(N − L)/m⌋ terms, J = min(M, (d+1)S), r = M/S:

    * J ≤ J_MAX: 1/edf = BasicSum(J, M, S, F)/(M·sz(0, F)²), eq. (13) — exact;
      for the unmodified variances with α ≤ 0 and m(d+1) > J_MAX the filter limit
      F = ∞ is used (case 2b); for α = +1 F = m.
    * J > J_MAX and r > d + 1: 1/edf = (a0 − a1/r)/r with (a0, a1) from Table 1
      (modified) or Table 2, divided by (b0 + b1 ln m)² (Table 3) for α = +1
      unmodified.
    * otherwise: the basic sum with J = M = J_MAX and S = J_MAX/r.
    * α = +2 unmodified (case 4), in closed form: with ρ_k = C(2d, d−k)/C(2d, d),
      1/edf = (1/M)[1 + 2 Σ_{1≤k≤d, k<r} (1 − k/r) ρ_k²] — the basic sum, whose
      terms vanish except at j = k·m; for r > d it is (a0 − a1/r)/M of Table 2.

    >>> round(float(edf_greenhall(0, 2, 1, 1001)[0]), 2)   # white rate, m = 1
    782.03
    """
    alpha = int(alpha)
    d = int(d)
    if d not in (1, 2, 3):
        raise GonioError(f"difference order d must be 1, 2 or 3, not {d}", key="d")
    if alpha not in range(-4, 3) or alpha + 2 * d <= 1:
        raise GonioError(f"edf not defined for noise alpha={alpha} with difference order "
                         f"d={d} (needs alpha in 2..-4 and alpha + 2d > 1)", key="alpha")
    m = np.atleast_1d(np.asarray(m, dtype=np.float64))
    n = float(n_phase)
    f = np.ones_like(m) if modified else m.copy()
    s = m.copy() if overlapping else np.ones_like(m)
    length = m / f + m * d
    m_terms = 1.0 + np.floor(s * (n - length) / m)
    if np.any(m_terms < 1):
        raise GonioError(f"averaging factor too large for {n_phase} phase points", key="m")
    j = np.minimum(m_terms, (d + 1) * s)
    r = m_terms / s
    inv = np.full(m.shape, np.nan)

    if not modified and alpha == 2:
        rho2 = [(comb(2 * d, d - k) / comb(2 * d, d)) ** 2 for k in range(1, d + 1)]
        acc = np.ones_like(m)
        for k, q in enumerate(rho2, start=1):
            acc += np.where(k < r, 2.0 * (1.0 - k / r) * q, 0.0)
        return 1.0 / (acc / m_terms)

    direct = j <= J_MAX
    table = ~direct & (r > d + 1)
    capped = ~direct & ~table
    if modified:
        if direct.any():
            i = direct
            inv[i] = _basic_sum(j[i], m_terms[i], s[i], np.ones(i.sum()), alpha, d) / (
                _sz(0.0, 1.0, alpha, d) ** 2 * m_terms[i])
        if table.any():
            a0, a1 = _table(GR_TABLE1, alpha, d)
            inv[table] = (a0 - a1 / r[table]) / r[table]
        if capped.any():
            inv[capped] = _capped(r[capped], lambda rr: _basic_sum(
                np.full(rr.size, J_MAX), np.full(rr.size, J_MAX), J_MAX / rr,
                np.ones(rr.size), alpha, d) / (_sz(0.0, 1.0, alpha, d) ** 2 * J_MAX),
                ("modified", alpha), d, n)
        return 1.0 / inv

    if alpha <= 0:
        if direct.any():
            fin = direct & (m * (d + 1) <= J_MAX)
            inf = direct & ~fin
            if fin.any():
                sz0 = _sz(np.zeros(fin.sum()), m[fin], alpha, d)
                inv[fin] = _basic_sum(j[fin], m_terms[fin], s[fin], m[fin], alpha, d) / (
                    sz0 ** 2 * m_terms[fin])
            if inf.any():
                inv[inf] = _basic_sum(j[inf], m_terms[inf], s[inf], None, alpha, d) / (
                    _sz(0.0, None, alpha, d) ** 2 * m_terms[inf])
        if table.any():
            a0, a1 = _table(GR_TABLE2, alpha, d)
            inv[table] = (a0 - a1 / r[table]) / r[table]
        if capped.any():
            inv[capped] = _capped(r[capped], lambda rr: _basic_sum(
                np.full(rr.size, J_MAX), np.full(rr.size, J_MAX), J_MAX / rr, None,
                alpha, d) / (_sz(0.0, None, alpha, d) ** 2 * J_MAX), ("limit", alpha), d, n)
        return 1.0 / inv

    # alpha == +1, unmodified
    b0, b1 = GR_TABLE3[d - 1]
    if direct.any():
        i = direct
        sz0 = _sz(np.zeros(i.sum()), m[i], 1, d)
        inv[i] = _basic_sum(j[i], m_terms[i], s[i], m[i], 1, d) / (sz0 ** 2 * m_terms[i])
    if table.any():
        a0, a1 = _table(GR_TABLE2, 1, d)
        i = table
        inv[i] = (a0 - a1 / r[i]) / ((b0 + b1 * np.log(m[i])) ** 2 * r[i])
    if capped.any():
        i = capped
        g = _capped(r[i], lambda rr: _basic_sum(
            np.full(rr.size, J_MAX), np.full(rr.size, J_MAX), J_MAX / rr, J_MAX / rr, 1, d),
            ("flicker", 1), d, n)
        inv[i] = g / ((b0 + b1 * np.log(m[i])) ** 2 * J_MAX)
    return 1.0 / inv


def edf_totdev(n_phase: int, m, alpha) -> np.ndarray:
    """edf of the total variance, SP 1065 §5.2.11 Table 7: edf = b·T/τ − c with
    (b, c) = (1.50, 0), (1.17, 0.22), (0.93, 0.36) for α = 0, −1, −2, T/τ taken as
    (number of phase points)/m (the reading Stable32's printed intervals follow).
    Other noise types: the overlapping-Allan edf of :func:`edf_greenhall` (SP 1065
    gives no TOTVAR edf for them; TOTVAR ≥ AVAR in edf, so this is conservative).

    >>> round(float(edf_totdev(1001, 10, 0)[0]), 2)
    150.15
    """
    m = np.atleast_1d(np.asarray(m, dtype=np.float64))
    alpha = np.broadcast_to(np.asarray(alpha, dtype=np.int64), m.shape)
    out = np.empty(m.shape)
    tab = {0: (1.50, 0.0), -1: (1.17, 0.22), -2: (0.93, 0.36)}
    for a in np.unique(alpha):
        i = alpha == a
        if int(a) in tab:
            b, c = tab[int(a)]
            out[i] = b * float(n_phase) / m[i] - c
        else:
            out[i] = edf_greenhall(int(a), 2, m[i], n_phase)
    return out


def edf_for(kind: str, n_phase: int, m, alpha) -> np.ndarray:
    """edf of the estimator ``kind`` (``adev`` overlapping Allan, ``mdev`` modified
    Allan, ``hdev`` overlapping Hadamard: :func:`edf_greenhall`; ``totdev``:
    :func:`edf_totdev`) at averaging factors ``m`` with noise types ``alpha``
    (one per m). α outside the variance's range (α + 2d ≤ 1, e.g. −3 for the Allan
    variances) is clipped to the nearest defined type (the estimate is then
    dominated by its lowest-frequency content and the interval is approximate).

    >>> [round(float(v), 2) for v in edf_for("mdev", 1001, [1, 128], [0, 0])]
    [782.03, 5.32]
    """
    if kind not in KINDS:
        raise GonioError(f"estimator kind must be one of {', '.join(KINDS)}, not {kind!r}",
                         key="kind")
    m = np.atleast_1d(np.asarray(m, dtype=np.float64))
    alpha = np.broadcast_to(np.asarray(alpha, dtype=np.int64), m.shape)
    if kind == "totdev":
        return edf_totdev(n_phase, m, np.clip(alpha, -2, 2))
    d, modified = KINDS[kind]
    alpha = np.clip(alpha, 2 - 2 * d, 2)  # α + 2d > 1
    out = np.empty(m.shape)
    for a in np.unique(alpha):
        i = alpha == a
        out[i] = edf_greenhall(int(a), d, m[i], n_phase, modified=modified)
    return out


# -------------------------------------------------------------- SP 1065 Table 5
def edf_simple(n_phase: int, m, alpha) -> np.ndarray:
    """Equivalent degrees of freedom of the overlapping AVAR, SP 1065 Table 5.

    The simple approximations (Howe, Allan & Barnes 1981), kept for comparison with
    :func:`edf_greenhall`; α as in the module docstring. Limited below by 1.

    >>> float(np.round(edf_simple(1000, 10, 0), 3))
    146.029
    >>> float(np.round(edf_simple(1000, 10, -2), 3))
    97.232
    """
    n = float(n_phase)
    m = np.asarray(m, dtype=np.float64)
    alpha = np.broadcast_to(np.asarray(alpha), m.shape)
    edf = np.full(m.shape, np.nan)
    a2 = alpha == 2
    edf[a2] = (n + 1) * (n - 2 * m[a2]) / (2 * (n - m[a2]))
    a1 = alpha == 1
    with np.errstate(invalid="ignore", divide="ignore"):
        la = np.log((n - 1) / (2 * m[a1]))
        lb = np.log((2 * m[a1] + 1) * (n - 1) / 4)
        edf[a1] = np.exp(np.sqrt(np.clip(la * lb, 0, None)))
    a0 = alpha == 0
    edf[a0] = ((3 * (n - 1) / (2 * m[a0]) - 2 * (n - 2) / n)
               * 4 * m[a0] ** 2 / (4 * m[a0] ** 2 + 5))
    am1 = alpha == -1
    mm = m[am1]
    edf[am1] = np.where(mm == 1, 2 * (n - 2) ** 2 / (2.3 * n - 4.9),
                        5 * n ** 2 / (4 * mm * (n + 3 * mm)))
    am2 = alpha == -2
    mm = m[am2]
    edf[am2] = (n - 2) / mm * ((n - 1) ** 2 - 3 * mm * (n - 1) + 4 * mm ** 2) / (n - 3) ** 2
    if np.isnan(edf).any():
        raise GonioError("noise exponent alpha must be one of 2, 1, 0, -1, -2", key="alpha")
    return np.maximum(edf, 1.0)


# ----------------------------------------------------------- noise identification
#: Fewest points of the decimated series for the lag-1 method ([RG2004]: ≥ 30).
LAG1_MIN_POINTS = 30


def _lag1(z: np.ndarray) -> float:
    """Lag-1 autocorrelation r1 = Σ(z_i − z̄)(z_{i+1} − z̄)/Σ(z_i − z̄)² ([RG2004] eq. 2)."""
    c = z - z.mean()
    den = float(np.einsum("i,i->", c, c))
    return float(np.einsum("i,i->", c[:-1], c[1:]) / den) if den > 0 else 0.0


def _detrend(z: np.ndarray, deg: int, keep_basis: bool = False) -> np.ndarray:
    """z minus its least-squares quadratic (deg 2; the only degree used)."""
    assert deg == 2
    out = np.array(z, dtype=np.float64, copy=True)
    remove_quadratic(out, keep_basis=keep_basis)
    return out


def _quadratic_t(n: int, a: int, step: int) -> np.ndarray:
    """The points a … a + step − 1 of t = −1 + 2k/(n − 1) (linspace's own values for a
    record of one piece)."""
    return np.linspace(-1.0, 1.0, n)[a: a + step] if n <= step else \
        -1.0 + 2.0 * np.arange(a, min(n, a + step)) / (n - 1)


@functools.lru_cache(maxsize=64)
def _quadratic_gram(n: int, step: int) -> np.ndarray:
    """Σ t^(i+j), i, j ≤ 2, over the n points of t (:func:`remove_quadratic`), accumulated
    piece by piece; it depends on n alone, so it is formed once per length."""
    gram = np.zeros((3, 3))
    for a in range(0, n, step):
        t = _quadratic_t(n, a, step)
        tk = [np.ones_like(t), t, t * t]
        for i in range(3):
            for j in range(3):
                gram[i, j] += float(np.einsum("i,i->", tk[i], tk[j]))
    gram.flags.writeable = False
    return gram


def _fit_t(n: int, a: int, step: int) -> np.ndarray:
    """The points a … a + step − 1 of t = −1 + 2k/(n − 1) as the fit evaluates them."""
    return -1.0 + 2.0 * np.arange(a, min(n, a + step)) / (n - 1)


@functools.lru_cache(maxsize=1)
def _quadratic_piece(n: int) -> tuple[np.ndarray, ...]:
    """(1, t, t², t as the fit evaluates it) of a record of one piece of n points: the
    noise identification detrends many series of the same length (read-only arrays)."""
    t = _quadratic_t(n, 0, n)
    out = (np.ones_like(t), t, t * t, _fit_t(n, 0, n))
    for v in out:
        v.flags.writeable = False
    return out


def release_quadratic_basis() -> None:
    """Free the arrays :func:`remove_quadratic` keeps for the last length it saw."""
    _quadratic_piece.cache_clear()


def remove_quadratic(z: np.ndarray, *, keep_basis: bool = False) -> None:
    """Subtract from z (in place) its least-squares quadratic in t ∈ [−1, 1], from the
    moments Σ t^k z and Σ t^k (k ≤ 4) accumulated in chunks (no N×3 design matrix).
    ``keep_basis``: keep 1, t, t² of a record of one piece for the next record of its
    length (4 arrays of its size, until :func:`release_quadratic_basis`; the same values)."""
    n = z.size
    if n < 3:
        return
    step = 1 << 16
    mom = np.zeros(3)
    one = _quadratic_piece(n) if keep_basis and n <= step else None
    for a in range(0, n, step):
        if one is None:
            t = _quadratic_t(n, a, step)
            tk = (np.ones_like(t), t, t * t)
        else:
            tk = one[:3]
        for i in range(3):
            mom[i] += float(np.einsum("i,i->", tk[i], z[a: a + step]))
    c = np.linalg.solve(_quadratic_gram(n, step), mom)
    for a in range(0, n, step):
        t = one[3] if one is not None else _fit_t(n, a, step)
        fit = t * c[2]           # c0 + t·(c1 + t·c2), in place
        fit += c[1]
        fit *= t
        fit += c[0]
        z[a: a + step] -= fit


def noise_id_lag1(x: np.ndarray, m: int, *, d_max: int = 2,
                  keep_basis: bool = False) -> tuple[int, float] | None:
    """Noise type α at averaging factor m by the lag-1 autocorrelation ([RG2004];
    SP 1065 §5.6.1), from the phase series ``x`` (NaN-free).

    The phase is decimated by m (every m-th point), a quadratic (rate offset and
    ramp) removed, then differenced d = 0, 1, … times until δ = r1/(1 + r1) < 0.25
    or d = ``d_max`` (2 for the Allan variances, 3 for Hadamard); then
    p = −2(δ + d) and α = p + 2 (phase data), rounded: α = 2 − 2d − round(2δ).
    Returns (α rounded to 2 … 2 − 2·d_max, α unrounded), or None when the
    decimated series has fewer than :data:`LAG1_MIN_POINTS` points. ``keep_basis``: see
    :func:`remove_quadratic`.

    >>> rng = np.random.default_rng(0)
    >>> noise_id_lag1(np.cumsum(rng.standard_normal(5000)), 4)[0]   # white rate
    0
    """
    z = np.asarray(x, dtype=np.float64)[:: int(m)]
    if z.size < LAG1_MIN_POINTS:
        return None
    z = _detrend(z, 2, keep_basis)
    d = 0
    while True:
        r1 = _lag1(z)
        delta = r1 / (1.0 + r1)
        if delta < 0.25 or d >= d_max:
            p = -2.0 * (delta + d)
            a = p + 2.0
            a_int = int(np.clip(2 - 2 * d - round(2 * delta), 2 - 2 * d_max, 2))
            return a_int, float(a)
        z = np.diff(z)
        d += 1


def b1_expected(n: int, mu: float) -> float:
    """Expected B1 ratio (N-sample variance / two-sample variance) for N averages and
    AVAR ∝ τ^μ (Barnes 1969; SP 1065 §5.6.2):
    B1 = N(1 − N^μ)/(2(N − 1)(1 − 2^μ)), with the limits N ln N/(2(N−1) ln 2) at μ = 0
    and N/2 at μ = 1 (exact values of the same formula).

    >>> b1_expected(10, -1), round(b1_expected(10, 0), 4), b1_expected(10, 1)
    (1.0, 1.8455, 5.0)
    """
    n = float(n)
    if mu == 0:
        return n * math.log(n) / (2.0 * (n - 1.0) * math.log(2.0))
    return n * (1.0 - n ** mu) / (2.0 * (n - 1.0) * (1.0 - 2.0 ** mu))


def rn_expected(m: int, alpha: int) -> float:
    """Expected R(n) = MVAR/AVAR at n = m for white (α = 2) and flicker (α = 1) phase
    noise (SP 1065 §5.2.5 and Table 4): 1/m for white phase; for flicker phase
    the ratio of the two responses with the bandwidth f_h = 1/(2τ0):
    MVAR·τ²/h = 3 ln(256/27)/(8π²), AVAR·τ²/h = (1.038 + 3 ln(2π f_h τ))/(4π²).
    Other types (α ≤ 0): not used (the B1 ratio separates them).

    >>> rn_expected(8, 2)
    0.125
    """
    if alpha == 2:
        return 1.0 / m
    if alpha == 1:
        avar = (1.038 + 3.0 * math.log(2.0 * math.pi * 0.5 * m)) / (4.0 * math.pi ** 2)
        mvar = 3.0 * math.log(256.0 / 27.0) / (8.0 * math.pi ** 2)
        return mvar / avar
    raise GonioError("R(n) is used for alpha 2 and 1 only", key="alpha")


def noise_id_b1(x: np.ndarray, m: int, *, rn_ratio=None) -> int | None:
    """Noise type α at averaging factor m by the B1 ratio, with R(n) separating white
    from flicker phase noise (SP 1065 §5.6.2; the cross-check of :func:`noise_id_lag1`).

    The rate y = diff(x) is averaged over m (non-overlapping, N of them); B1 =
    (sample variance of the averages)/(non-overlapping AVAR at m). μ is the
    candidate (1, 0, −1, −2 for α = −2, −1, 0, ≥ 1) whose expected B1
    (:func:`b1_expected`) is nearest in log; boundaries at the geometric means.
    For μ = −2, R(n) = MVAR/AVAR is compared with :func:`rn_expected` for α = 2 and 1
    (boundary at the geometric mean). None when fewer than 8 averages. The N-sample
    variance spans the whole record, so with a mixture of noise types B1 leans to
    the redder one: a disagreement with the lag-1 result flags a mixture at that τ.

    >>> rng = np.random.default_rng(1)
    >>> noise_id_b1(np.cumsum(rng.standard_normal(20000)), 8)   # white rate
    0

    ``rn_ratio``: ``x`` is then the phase already decimated (``phase[::m]``) and
    ``rn_ratio()`` gives R(n) at m of the whole-resolution phase, or None where it cannot
    be formed (a record analysed in pieces, :mod:`gonio.analysis.noise.stream`).
    """
    x = np.asarray(x, dtype=np.float64)
    m = int(m)
    xd = x[::m] if rn_ratio is None else x
    nav = xd.size - 1
    if nav < 8:
        return None
    ybar = np.diff(xd) / m  # the rate averaged over each cluster of m samples
    avar = 0.5 * float(np.mean(np.diff(ybar) ** 2))
    if avar <= 0:
        return None
    b1 = float(np.var(ybar, ddof=1)) / avar
    cands = [(1, -2), (0, -1), (-1, 0), (-2, 2)]  # (μ, α)
    best = min(cands, key=lambda c: abs(math.log(max(b1, 1e-300)
                                                 / b1_expected(nav, c[0]))))
    if best[0] != -2 or m < 2:
        return best[1]
    rn = rn_ratio_of_phase(x, m) if rn_ratio is None else rn_ratio()
    if rn is None:
        return 2
    bound = math.sqrt(rn_expected(m, 2) * rn_expected(m, 1))
    return 2 if rn < bound else 1


def rn_ratio_of_phase(x: np.ndarray, m: int) -> float | None:
    """R(n) = MVAR/AVAR at m of the phase ``x``; None when too short or AVAR is 0."""
    n = x.size
    if n - 3 * m + 1 < 1:
        return None
    # One record-sized array at a time (the values and summation order of
    # sd = x[2m:] − 2x[m:n−m] + x[:n−2m]; avar = mean(sd²); c = [0, cumsum(sd)];
    # w = (c[m:] − c[:−m])/m; mvar = mean(w²)): sd whole for its mean, then c built
    # from sd recomputed piece by piece, and w written over c's head.
    sd = 2 * x[m:n - m]
    np.subtract(x[2 * m:], sd, out=sd)
    sd += x[: n - 2 * m]
    np.square(sd, out=sd)
    avar_o = float(np.mean(sd))
    size = sd.size
    del sd
    c = np.empty(size + 1)
    c[0] = 0.0
    step = 1 << 18
    for a in range(0, size, step):
        e = min(size, a + step)
        p = 2 * x[m + a: m + e]
        np.subtract(x[2 * m + a: 2 * m + e], p, out=p)
        p += x[a:e]
        p[0] += c[a]                     # the running sum continues across pieces
        np.cumsum(p, out=c[a + 1: e + 1])
    nw = c.size - m
    for a in range(0, nw, step):          # w[i] = c[i+m] − c[i], written over c[i]
        e = min(nw, a + step)
        c[a:e] = c[a + m: e + m] - c[a:e]
    w = c[:nw]
    w /= m
    np.square(w, out=w)
    mvar = float(np.mean(w))
    del w, c
    return mvar / avar_o if avar_o > 0 else None


# ---------------------------------------------------------------------- intervals
def chi2_interval(var, edf, confidence: float):
    """χ² interval of a variance estimate with ``edf`` degrees of freedom
    (SP 1065 §5.3.4): [var·edf/χ²_{(1+p)/2}, var·edf/χ²_{(1−p)/2}].

    >>> lo, hi = chi2_interval(1.0, 10.0, 0.683)
    >>> round(float(lo), 4), round(float(hi), 4)
    (0.6979, 1.761)
    """
    edf = np.asarray(edf, dtype=np.float64)
    lo_q = stats.chi2.ppf((1 + confidence) / 2, edf)
    hi_q = stats.chi2.ppf((1 - confidence) / 2, edf)
    var = np.asarray(var, dtype=np.float64)
    return var * edf / lo_q, var * edf / hi_q
