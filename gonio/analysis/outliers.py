"""Outliers of a record of samples (a static or bias record at rest, the gyro's output at a
fixed sample interval), shared by every specification that screens one:

* :func:`hampel_residuals` — each sample against its running median (the Hampel rule), with
  the limit beyond which one sample is set aside;
* :func:`too_many_outliers` — more than :data:`DENSE_SHARE` of a record beyond that limit:
  the record is damaged (refused), not a sample of the gyro with a few spikes;
* :func:`moderate_tail` — many samples each below the limit but beyond :data:`K_TAIL`
  robust σ: a tail no normal record has (refused with the record).

Plain arrays in, arrays out; the specifications turn them into findings.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import median_filter

#: Window (samples) of the running median of the Hampel rule, and of the local scale; its
#: threshold in robust σ (8σ: a normal sample exceeds it with probability 10⁻¹⁵).
HAMPEL_WINDOW, SCALE_WINDOW, K_HAMPEL = 21, 101, 8.0
#: Records of fewer samples are not judged by the Hampel rule: the local scale of a running
#: median is not reliable over a few tens of samples.
HAMPEL_MIN_ROWS = 200
#: Largest share of a record's samples set aside one by one; above it (and at least
#: DENSE_MIN_ROWS samples) the record is refused: a record that full of outliers is damaged
#: (a loose connector, a logger fault), and what is left of it is not a sample of the gyro.
DENSE_SHARE, DENSE_MIN_ROWS = 0.05, 3
#: The tail rule of a record: at least max(5, 0.1 % of its samples) beyond 5 robust σ (a
#: normal sample has a share 5.7·10⁻⁷ there; samples beyond the 8σ limit are set aside, not
#: counted) — spikes dense but each below the 8σ limit (±1 mV on 5 % of a bias record
#: raises its bias instability by a third) are refused with the record.
K_TAIL, TAIL_MIN_ROWS, TAIL_SHARE, TAIL_P = 5.0, 5, 1e-3, 5.7e-7


def quantum(y: np.ndarray) -> float:
    """The output's resolution: its smallest non-zero step (0 for a constant)."""
    steps = np.abs(np.diff(y))
    return float(steps[steps > 0].min()) if np.any(steps > 0) else 0.0


def quantum_floor(y: np.ndarray) -> float:
    """The smallest limit a departure is judged against: 3 quanta of the output
    (:func:`quantum`) and 10⁻⁹ of its size (a difference below it is rounding)."""
    return max(3.0 * quantum(y), 1e-9 * (1.0 + float(np.max(np.abs(y)))))


def hampel_residuals(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(d, limit) per sample of a record (dense ±1000 spikes in a bias record made a
    second-difference rule's local scale, median |r|, of spikes):
    d_i = y_i − median(y over the 21 samples around i), limit_i = 8·1.4826·max(median |d|
    over the 101 samples around i, the record's median |d|; where the output is quantised
    so coarsely that the median |d| is below one quantum, at least the rms of min(|d|, 5
    quanta): a clean record at 0.5 LSB noise would otherwise be refused), floored at 3
    quanta of the output and 10⁻⁹ of its size. The running median follows a smooth trend
    (a warm-up transient) and ignores up to 10 spikes among 21 samples; the scale is made
    of the good samples as long as they are the majority.

    >>> rng = np.random.default_rng(0)
    >>> y = rng.normal(0, 1, 400) + 50 * np.exp(-np.arange(400) / 60)
    >>> bad = rng.choice(400, 60, replace=False)                 # 15 % of the samples
    >>> y[bad] += rng.choice([-1000.0, 1000.0], 60)
    >>> d, lim = hampel_residuals(y)
    >>> sorted(np.flatnonzero(np.abs(d) > lim).tolist()) == sorted(bad.tolist())
    True
    """
    d = y - median_filter(y, size=HAMPEL_WINDOW, mode="nearest")
    a = np.abs(d)
    local = np.maximum(median_filter(a, size=SCALE_WINDOW, mode="nearest"), float(np.median(a)))
    scale = 1.4826 * local
    q = quantum(y)
    if q > 0 and 1.4826 * float(np.median(a)) < q:
        # coarse quantisation (noise ≲ 1 quantum): most d are exactly 0 and the median |d|
        # collapses; σ from the rms of |d| winsorised at 5 quanta (the rounding's q²/12 in it)
        scale = np.maximum(scale, math.sqrt(float(np.mean(np.minimum(a, 5.0 * q) ** 2))))
    return d, np.maximum(K_HAMPEL * scale, quantum_floor(y))


def too_many_outliers(count: int, n: int) -> bool:
    """True when ``count`` outliers among ``n`` samples are more than :data:`DENSE_SHARE` of
    them (and at least :data:`DENSE_MIN_ROWS`): the record is damaged, not a sample of the
    gyro with a few spikes to set aside.

    >>> too_many_outliers(2, 20), too_many_outliers(3, 20), too_many_outliers(3, 100)
    (False, True, False)
    """
    return count >= DENSE_MIN_ROWS and count > DENSE_SHARE * n


def moderate_tail(d: np.ndarray, lim: np.ndarray) -> np.ndarray | None:
    """The samples of a record (``d``, ``lim`` of :func:`hampel_residuals`) beyond
    :data:`K_TAIL` robust σ of their running median but within the 8σ limit, when they are
    at least max(:data:`TAIL_MIN_ROWS`, :data:`TAIL_SHARE`·n) — many moderate spikes, each
    below the limit that sets one sample aside, which a normal record of n samples has
    n·:data:`TAIL_P` of: the record is damaged. None when they are fewer.

    >>> d = np.zeros(1000); lim = np.full(1000, 8.0)
    >>> d[:6] = 6.0
    >>> int(moderate_tail(d, lim).sum()), moderate_tail(d[:-1] * 0, lim[:-1])
    (6, None)
    """
    a = np.abs(d)
    tail = (a > (K_TAIL / K_HAMPEL) * lim) & (a <= lim)
    return tail if tail.sum() >= max(TAIL_MIN_ROWS, TAIL_SHARE * d.size) else None
