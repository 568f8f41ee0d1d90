"""Fixed-width pulse counters: what a 16/24/32/64-bit counter shows, signed or unsigned.

The bench writes wrapped counters; a stream reader unwraps them from the
differences modulo 2^bits (``docs/formats.md#stream-file``).
"""

from __future__ import annotations

import numpy as np


def wrap_counter(counts: np.ndarray, bits: int, signed: bool) -> np.ndarray:
    """What a ``bits``-wide counter shows for the unwrapped integer ``counts``.

    >>> wrap_counter(np.array([0, 32767, 32768, -32769]), 16, True).tolist()
    [0, 32767, -32768, 32767]
    >>> wrap_counter(np.array([65535, 65536, -1]), 16, False).tolist()
    [65535, 0, 65535]
    """
    c = np.asarray(counts).astype(np.int64)
    if bits >= 64:
        return c
    m = np.int64(1) << np.int64(bits)
    w = np.mod(c, m)
    if signed:
        w = np.where(w >= m // 2, w - m, w)
    return w
