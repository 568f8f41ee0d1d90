"""Welch power spectral density of a long record in bounded memory.

:func:`welch_psd` gives what ``scipy.signal.welch(x / divisor − mean, fs, nperseg=n)``
gives (Hann window, half-overlapping segments, each detrended by its own mean, one-sided
density, mean of the periodograms) without the whole-record temporaries scipy makes (the
scaled copy, the mean-removed copy, every segment and every segment's spectrum at once:
about six times the record): the segments are taken a group at a time from pieces of the
record, each group's mean periodogram from ``scipy.signal.welch`` itself, and the groups
averaged weighted by their segment counts. The result equals the one-shot call to
rounding (~1e-15 relative; tests/test_spec_noise_bounded.py).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

from gonio.analysis.noise.stream import Record

__all__ = ["welch_psd", "welch_band_rms_u_rel", "WELCH_PIECE_SEGMENTS"]

#: Segments whose periodograms are formed at a time.
WELCH_PIECE_SEGMENTS = 256


def _piece_mean(x: np.ndarray, divisor: float, piece: int) -> float:
    """Mean of x / divisor, summed piece by piece."""
    total = 0.0
    for a in range(0, x.size, piece):
        total += float(np.sum(x[a: a + piece] / divisor))
    return total / x.size


def welch_psd(x, fs: float, nperseg: int, *, divisor: float = 1.0,
              segments: int = WELCH_PIECE_SEGMENTS) -> tuple[np.ndarray, np.ndarray]:
    """(f, one-sided density) of ``x / divisor`` with its mean removed, as
    ``scipy.signal.welch(x / divisor - mean, fs=fs, nperseg=nperseg)``, in pieces of
    ``segments`` segments (module docstring).

    >>> rng = np.random.default_rng(0)
    >>> x = rng.standard_normal(100_000)
    >>> f, p = welch_psd(x, 10.0, 512, segments=7)
    >>> f0, p0 = signal.welch(x - x.mean(), fs=10.0, nperseg=512)
    >>> bool(np.array_equal(f, f0)), bool(np.allclose(p, p0, rtol=1e-12, atol=0))
    (True, True)
    """
    x = x if isinstance(x, Record) else np.asarray(x)   # a Record: read in pieces
    n = x.size
    nperseg = int(nperseg)
    if not 1 <= nperseg <= n:
        raise ValueError(f"nperseg must be in [1, {n}], got {nperseg}")
    step = nperseg - nperseg // 2
    nseg = (n - nperseg) // step + 1
    mean = _piece_mean(x, divisor, segments * step)
    acc, f = None, None
    for s0 in range(0, nseg, segments):
        g = min(segments, nseg - s0)
        a = s0 * step
        b = a + (g - 1) * step + nperseg
        piece = x[a:b] / divisor
        piece -= mean
        f, p = signal.welch(piece, fs=fs, nperseg=nperseg)
        acc = p * g if acc is None else acc + p * g
    return f, acc / nseg


def welch_band_rms_u_rel(n: int, nperseg: int, psd_band, df_hz: float, lag_lines: int = 6) -> float:
    """Relative standard uncertainty of rms = √(∫ S df) (trapezoid over contiguous lines
    ``psd_band`` of :func:`welch_psd`'s density, spacing ``df_hz``) from the estimate's own
    scatter, for a Gaussian record of ``n`` samples whose density is smooth across a few
    lines.

    Each segment's periodogram line k is exponential (variance S_k²); two lines k, k' of
    segments d samples apart correlate by |ρ(k − k', d)|², ρ(m, d) = Σ w_j w_{j+d}
    e^{−2πimj/N} / Σ w_j² for the Hann window w of N = ``nperseg`` (Percival & Walden,
    Spectral Analysis for Physical Applications, 1993, §6.17; Welch 1967). Over the K
    half-overlapping segments cov(S̄_k, S̄_k') = S_k S_k'·V_m, V_m = K⁻² Σ_{s,s'}
    |ρ(m, (s − s')·step)|², m = k − k', so var(Σ c_k S̄_k) = Σ_m V_m Σ_k c_k c_{k+m} S_k S_{k+m},
    with S_k S_{k+m} estimated without bias by S̄_k S̄_{k+m}/(1 + V_m); u(rms)/rms =
    ½·√var/Σ c_k S̄_k (first order). For one Hann segment Σ_m V_m = 1 + 2·(2/3)² + 2·(1/6)²
    = 35/18, so the relative u is ≈ 0.70/√lines.
    """
    ps = np.asarray(psd_band, dtype=float)
    nperseg = int(nperseg)
    step = nperseg - nperseg // 2
    nseg = (int(n) - nperseg) // step + 1
    c = np.full(ps.size, float(df_hz))
    c[[0, -1]] *= 0.5                                    # trapezoid weights
    total = float(np.sum(c * ps))
    if ps.size < 2 or total <= 0 or nseg < 1:
        return float("nan")
    w = signal.get_window("hann", nperseg)
    norm = float(np.sum(w * w)) ** 2
    cs = c * ps
    var = 0.0
    for m in range(-lag_lines, lag_lines + 1):           # line lag
        v = 0.0
        for j in range(-(nseg - 1), nseg):              # segment lag
            d = abs(j) * step
            if d < nperseg:
                ph = np.exp(-2j * np.pi * m * np.arange(nperseg - d) / nperseg)
                v += (nseg - abs(j)) * float(abs(np.sum(w[: nperseg - d] * w[d:] * ph)) ** 2)
        v /= norm * nseg * nseg
        a = abs(m)
        var += v / (1.0 + v) * float(np.sum(cs[: cs.size - a] * cs[a:]))
    return 0.5 * math.sqrt(max(var, 0.0)) / total
