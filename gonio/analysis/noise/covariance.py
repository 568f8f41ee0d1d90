"""Covariance of Allan-family variance estimates at several τ of one record, under the
five-term noise model — the weight of the five-term fit's uncertainties.

Estimates of one record at neighbouring τ share most of their data: treated as independent,
the least-squares covariance of the fitted coefficients is several times too small, and
any fixed inflation factor is a guess. Here the full covariance is computed.

Each term of an estimator is a linear combination of the angle (phase) samples,
d_k = Σ_a c_a x_{k+a} / τ, whose coefficients annihilate constants and lines (second
differences for the Allan variances, third for the Hadamard). For such combinations the
covariance of the noise model is that of its *generalised covariance* K(t) (Matheron's
intrinsic random functions of order 1: K is defined up to an even polynomial of degree 2,
which the coefficients annihilate):

=====================  =============================  =========================
term                   generalised covariance K(t)    checks (AVAR of the model)
=====================  =============================  =========================
Q white phase          Q²·[t = 0]                     3Q²/τ²
N white rate           −N²|t|/2                       N²/τ
B flicker rate         B²·t² ln|t| / (2π)             (2 ln 2/π) B²
K rate random walk     K²|t|³/12                      K²τ/3
R rate ramp            (deterministic: no variance)
=====================  =============================  =========================

(each row gives the module table of :mod:`.fit` through Var d = Σ c_a c_b K(t_a − t_b)/τ²).
Then Cov(d_k(m), d_l(m')) = Σ_a Σ_b c_a c'_b K((a − b − L)τ0)/(τ τ'), L = l − k, and for
Gaussian noise (Isserlis) the estimates σ̂²(m) = Σ_k d_k²/(c n_m) have

    Cov(σ̂²(m), σ̂²(m')) = 2 Σ_L cnt(L) Cov(d_k(m), d_{k+L}(m'))² / (c² n_m n_m'),

cnt(L) the number of term pairs at lag L. White, quantisation and rate-random-walk parts
vanish once the two terms' spans no longer overlap; the flicker part falls as L⁻² and is
summed to 16 spans beyond the overlap (the rest is below 10⁻⁴ of the sum).

The diagonal reproduces Greenhall's edf for the overlapping estimators (2σ⁴/edf), which
the tests check, with the Monte Carlo covariance of simulated records and ``allantools``.
The total variance has no stationary term structure (its reflected extension): its
estimates are given the overlapping Allan variance's correlation with their own
Greenhall variances on the diagonal.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

__all__ = ["generalised_covariance", "estimator_taps", "markov_structure", "variance_covariance"]

#: Flicker tail summed beyond the overlap of two terms' spans, in spans.
_FLICKER_TAIL_SPANS = 4
#: Lag weights summed term by term up to this many (beyond: an FFT correlation).
_DIRECT_TAPS = 32
#: Grid samples of K(t) computed at a time (bounded temporaries on long records).
_PIECE = 1 << 20


def generalised_covariance(t_samples: np.ndarray, coef, tau0_s: float,
                           markov=()) -> np.ndarray:
    """K(t) of the five-term model (module table) at t = ``t_samples``·τ0 (integers ≥ 0),
    ``coef`` = [Q², N², B², K², R²] (the ramp carries no variance). The flicker term is
    written t² ln(t/τ0): it differs from t² ln t by an even quadratic, which the
    estimators' coefficients annihilate. ``markov``: first-order Gauss–Markov rate terms
    (s², T_c) of variance s² and correlation time T_c, each −s²T_c²(|t|/T_c − 1 + e^{−|t|/T_c})
    (−∫₀^|t| (|t| − u) s² e^{−u/T_c} du, the angle's structure under the rate's covariance),
    written less its even quadratic s²t²/2 (:func:`markov_structure`): the band-limited
    flicker's terms reach T_c = 10⁴ record lengths, where x = |t|/T_c is 10⁻⁸ and the
    quadratic, which the estimators annihilate, is 10⁸ times the part they see — computed
    as x − 1 + e^{−x} it left the terms' rounding as the answer (the JJF ARW's u_N moved ±2 %
    with the sample interval changed by 10⁻¹²).

    Long grids are computed piece by piece (``_PIECE`` samples at a time) into one output
    array, so the temporaries stay bounded whatever the record's length; each element is
    the same arithmetic either way.
    """
    t_all = np.asarray(t_samples)
    if t_all.size <= _PIECE:
        return _generalised_covariance(t_all, coef, tau0_s, markov)
    flat = t_all.ravel()
    return _in_pieces(flat.size, lambda a, b: _generalised_covariance(
        flat[a:b], coef, tau0_s, markov)).reshape(t_all.shape)


def _in_pieces(size: int, piece) -> np.ndarray:
    """An array of ``size`` float64 filled ``_PIECE`` elements at a time: out[a:b] =
    ``piece(a, b)`` (bounded temporaries; each element the same arithmetic as in one piece)."""
    out = np.empty(size, dtype=np.float64)
    for a in range(0, size, _PIECE):
        b = min(a + _PIECE, size)
        out[a:b] = piece(a, b)
    return out


def _generalised_covariance(t_samples, coef, tau0_s: float, markov) -> np.ndarray:
    """:func:`generalised_covariance` on one piece of the grid."""
    q2, n2, b2, k2 = (float(c) for c in np.asarray(coef, dtype=np.float64)[:4])
    t = np.asarray(t_samples, dtype=np.float64)
    ts = t * tau0_s
    out = -0.5 * n2 * ts
    if k2:
        out += k2 * ts ** 3 / 12.0
    if b2:
        with np.errstate(divide="ignore", invalid="ignore"):
            fl = ts ** 2 * np.log(t)
        out += b2 / (2.0 * math.pi) * np.where(t > 0, fl, 0.0)
    for s2, tc in markov:
        out -= float(s2) * float(tc) ** 2 * markov_structure(ts / float(tc))
    if q2:
        out = out + q2 * (t == 0)
    return out


def markov_structure(x) -> np.ndarray:
    """x − 1 + e^{−x} − x²/2 (x ≥ 0), a first-order Gauss–Markov term's angle structure per
    s²T_c² less its quadratic (:func:`generalised_covariance`), to full relative precision:
    the alternating series Σ_{n≥3} (−x)ⁿ/n! below x = 1/2 (to n = 32: the first omitted
    term is below 10⁻⁴⁰ of the sum), the closed form above (the terms then O(1), the result
    at least 0.02 in magnitude).

    >>> v = markov_structure(np.array([0.0, 1e-9, 0.3]))
    >>> float(v[0]), round(float(v[1] / (-1e-27 / 6)), 9)              # −x³/6 at 10⁻⁹
    (0.0, 1.0)
    >>> import math; math.isclose(float(v[2]), 0.3 - 1 + math.exp(-0.3) - 0.045, rel_tol=1e-13)
    True
    >>> round(float(markov_structure(np.array([2.0]))[0]), 12)          # 2 − 1 + e⁻² − 2
    -0.864664716763
    """
    x = np.asarray(x, dtype=np.float64)
    out = np.empty_like(x)
    small = x < 0.5
    xs = x[small]
    term = -xs ** 3 / 6.0
    acc = term.copy()
    for n in range(4, 33):
        term = term * (-xs) / n
        acc += term
    out[small] = acc
    xl = x[~small]
    out[~small] = xl - 1.0 + np.exp(-xl) - 0.5 * xl * xl
    return out


def estimator_taps(kind: str, m: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(offsets, coefficients, c) of one term of the estimator ``kind`` at averaging
    factor m: d_k = Σ coef·x_{k+offset}/τ and σ̂² = Σ_k d_k²/(c·n) (SP 1065 eqs 11, 14,
    20; the total variance uses the overlapping Allan terms)."""
    m = int(m)
    if kind in ("adev", "totdev"):
        return np.array([0, m, 2 * m]), np.array([1.0, -2.0, 1.0]), 2.0
    if kind == "hdev":
        return np.array([0, m, 2 * m, 3 * m]), np.array([1.0, -3.0, 3.0, -1.0]), 6.0
    if kind == "mdev":
        # (1/m) Σ_{i<m} (x_{k+i+2m} − 2x_{k+i+m} + x_{k+i}): the second difference
        # convolved with a box of m ones
        c = np.zeros(3 * m)
        for a, w in ((0, 1.0), (m, -2.0), (2 * m, 1.0)):
            c[a: a + m] += w / m
        nz = np.flatnonzero(c)
        return nz, c[nz], 2.0
    raise ValueError(f"kind must be adev, mdev, hdev or totdev, not {kind!r}")


def _pair_lag_weights(offs_i, c_i, offs_j, c_j) -> tuple[np.ndarray, np.ndarray]:
    """g(s) = Σ_{a − b = s} c_a c'_b: the cross-correlation of two tap sets (s, g)."""
    s = (offs_i[:, None] - offs_j[None, :]).ravel()
    g = (c_i[:, None] * c_j[None, :]).ravel()
    if s.size <= _DIRECT_TAPS:      # equal lags kept apart (C sums them; the Q part merges)
        order = np.argsort(s, kind="stable")
        return s[order], g[order]
    us, inv = np.unique(s, return_inverse=True)
    return us, np.bincount(inv, weights=g)


def _lag_grid(lo: int, hi: int, s: np.ndarray, span_small: int) -> tuple[np.ndarray, np.ndarray]:
    """Integer lags in [lo, hi] and their weights for Σ_L f(L) ≈ Σ w·f: every lag near
    the kinks of C (L = s, within the smaller span) at a step of 1/32 of that span,
    elsewhere (where C is one smooth piece) at most 512 steps; trapezoid weights, which
    are all 1 where the step is 1."""
    fine = max(1, span_small // 32)
    coarse = max(fine, (hi - lo) // 512)
    parts = [np.arange(lo, hi + 1, coarse), np.array([hi])]
    for sv in s:
        a, b = max(lo, int(sv) - span_small - fine), min(hi, int(sv) + span_small + fine)
        if a <= b:
            parts.append(np.arange(a, b + 1, fine))
    lag = np.concatenate(parts)
    lag.sort()
    lag = lag[np.r_[True, lag[1:] != lag[:-1]]]
    if lag.size == 1:
        return lag, np.ones(1)
    d = np.diff(lag).astype(np.float64)
    w = np.empty(lag.size)
    w[1:-1] = (d[:-1] + d[1:]) / 2.0
    w[0], w[-1] = d[0] / 2.0 + 0.5, d[-1] / 2.0 + 0.5
    return lag, w


def _pair_covariance(ti, tj, n_i, n_j, kgrid, flicker: bool, q2: float) -> float:
    """Σ_L cnt(L)·C(L)² for one pair of τ (``ti``/``tj``: (offsets, coefs, c, τ));
    ``kgrid`` the generalised covariance without the quantisation, whose white-phase
    part ``q2``·[t = 0] reaches C only at the lags L = s and is added there exactly."""
    (oi, ci, _, tau_i), (oj, cj, _, tau_j) = ti, tj
    s, g = _pair_lag_weights(oi, ci, oj, cj)
    span_i, span_j = int(oi[-1]), int(oj[-1])
    # C(L) = Σ_s g(s) K(s − L) vanishes (but for flicker) once the spans [k, k + span_i]
    # and [k + L, k + L + span_j] no longer overlap
    lo, hi = -span_j, span_i
    if flicker:
        extra = _FLICKER_TAIL_SPANS * max(span_i, span_j)
        lo, hi = lo - extra, hi + extra
    lo, hi = max(lo, -(n_i - 1)), min(hi, n_j - 1)
    if hi < lo:
        return 0.0

    def count(lag):
        return np.clip(np.minimum(n_i, n_j - lag) - np.maximum(0, -lag), 0, None)

    def cov_at(lag):
        c = np.zeros(lag.size)
        for sv, gv in zip(s, g):
            c += gv * kgrid[np.abs(sv - lag)]
        return c / (tau_i * tau_j)

    if s.size <= _DIRECT_TAPS:
        lag, w = _lag_grid(lo, hi, s, min(span_i, span_j))
        c = cov_at(lag)
        total = float(np.sum(w * count(lag) * c * c))
    else:                   # the modified variance's dense taps: one FFT correlation
        lag, w = np.arange(lo, hi + 1), None
        dense = np.zeros(int(s[-1] - s[0]) + 1)
        dense[s - s[0]] = g
        kfull = kgrid[np.abs(np.arange(s[0] - hi, s[-1] - lo + 1))]
        c = signal.correlate(kfull, dense, mode="valid", method="fft")[::-1] / (tau_i * tau_j)
        total = float(np.sum(count(lag) * c * c))
    if q2:
        at = (s >= lo) & (s <= hi)
        ls, inv = np.unique(s[at], return_inverse=True)     # equal lags merged
        c0 = cov_at(ls)
        cq = q2 * np.bincount(inv, weights=g[at]) / (tau_i * tau_j)
        total += float(np.sum(count(ls) * ((c0 + cq) ** 2 - c0 ** 2)))
    return total


def variance_covariance(kind: str, m, n_terms, tau0_s: float, coef, markov=()) -> np.ndarray:
    """Covariance matrix of the variance estimates σ̂²(m_i) (``kind``: adev, mdev, hdev,
    totdev) of one gap-free record with ``n_terms`` terms at each m, under the five-term
    model ``coef`` = [Q², N², B², K², R²] (module docstring; Gaussian noise), plus the
    Gauss–Markov terms ``markov`` ((s², T_c) pairs, :func:`generalised_covariance`; their
    correlation beyond the spans' overlap is summed over the flicker tail's spans).

    >>> cov = variance_covariance("adev", [1], [10**6], 1.0, [0, 1.0, 0, 0, 0])
    >>> round(float(cov[0, 0]) * 10**6, 3)   # white rate noise, m = 1: 2σ⁴·(3/2)/n
    3.0
    """
    m = np.asarray(m, dtype=np.int64)
    n = np.asarray(n_terms, dtype=np.int64)
    coef = np.asarray(coef, dtype=np.float64)
    taps = []
    for mi in m:
        o, c, cn, = estimator_taps(kind, int(mi))
        taps.append((o, c, cn, float(mi) * tau0_s))
    span = max(int(t[0][-1]) for t in taps)
    markov = [(float(s2), float(tc)) for s2, tc in markov if s2 > 0]
    flicker = bool(coef[2] > 0) or bool(markov)
    # |s − L| ≤ span + (1 + tail)·span (lags are limited by the spans, not the record)
    kmax = min(int(n.max()) + 2 * span, (_FLICKER_TAIL_SPANS + 2) * span) + 2
    q2 = float(coef[0])
    # K(t) at t = 0 … kmax, piece by piece (no grid of indices as long as the record)
    no_q = np.r_[0.0, coef[1:]]
    kgrid = _in_pieces(kmax + 1, lambda a, b: _generalised_covariance(
        np.arange(a, b), no_q, tau0_s, markov))
    out = np.empty((m.size, m.size))
    for i in range(m.size):
        for j in range(i, m.size):
            v = _pair_covariance(taps[i], taps[j], int(n[i]), int(n[j]), kgrid, flicker, q2)
            out[i, j] = out[j, i] = 2.0 * v / (taps[i][2] * taps[j][2] * float(n[i]) * float(n[j]))
    return out
