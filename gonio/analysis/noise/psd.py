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

import numpy as np
from scipy import signal

from gonio.analysis.noise.stream import Record

__all__ = ["welch_psd", "WELCH_PIECE_SEGMENTS"]

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
