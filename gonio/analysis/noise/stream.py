"""Long records analysed in bounded pieces: a series that is never held whole.

=========================  =====================================================
:class:`Record`            a 1-D float64 series produced piece by piece (e.g. the
                           static record's rate computed from a readings column)
:class:`CumulativeSum`     c = [0, cumsum(y − offset)] of a record, regenerated block
                           by block from checkpoints: every slice equal bit for bit to
                           the same slice of the whole array
:func:`rows_where`         the rows of a frame that hold a record (found in pieces)
:func:`frame_column`       a column at those rows: an array, or for a long record a
                           :class:`Record` read from the frame piece by piece
:func:`value_range`        max − min of an array or a record
:data:`STREAM_MIN_SAMPLES` records at least this long are streamed by the callers
=========================  =====================================================

A :class:`Record` answers ``len``, ``.size`` and slicing ``r[a:b]`` (a fresh, writable
float64 array), which is all the direct Allan sums (:mod:`.allan`), the Welch density
(:mod:`.psd`) and the JJF 1535 direct forms ask of an array: they run on it unchanged, with
temporaries of one piece. The Allan phase of a rate record (``x = [0, cumsum(y − ȳ)]``,
:func:`gonio.analysis.noise.allan.angle_series`) is a :class:`CumulativeSum`: the first
time its blocks are built in order it stores the value at every block boundary and every
:data:`FINE` points (no pass of its own); a slice is then rebuilt from the nearest
checkpoint with the same sequential additions as ``np.cumsum`` (a few recently used blocks
are kept). Memory: the checkpoints (N/4096 numbers: 2 MB for 10⁹ samples) and a few blocks
of 65536 points, whatever the record's length.

CPU: a far piece read once (the chained far sums of
:func:`gonio.analysis.noise.allan._sums_far`, the sparse decimations of the noise
identification) is rebuilt from a fine checkpoint (:meth:`CumulativeSum.span`), so that
every point is rebuilt about once per averaging time rather than three times; a frame's
float64 column is read by numpy slices of its own array (no pandas call per piece).
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Callable

import numpy as np

from gonio.errors import GonioError

__all__ = ["STREAM_MIN_SAMPLES", "PIECE", "Record", "CumulativeSum", "value_range",
           "rows_where", "frame_column"]

#: Records at least this long (8 MB a float64 column) are analysed as a :class:`Record`
#: by the specifications' noise items; shorter ones as arrays, as before.
STREAM_MIN_SAMPLES = 1 << 20
#: Samples formed at a time.
PIECE = 1 << 16
#: Spacing of the fine checkpoints of a :class:`CumulativeSum` (a divisor of its block).
FINE = 1 << 12


def _slice(key, size: int) -> tuple[int, int, int]:
    if not isinstance(key, slice):
        raise TypeError("a streamed record is read by slices only")
    a, b, step = key.indices(size)
    if step < 1:
        raise TypeError("a streamed record is read forwards only")
    return a, max(a, b), step


class Record:
    """A 1-D float64 series of ``size`` samples, ``piece(a, b)`` giving samples a … b−1
    as a fresh array (the caller may change it)."""

    ndim = 1
    dtype = np.dtype(np.float64)

    def __init__(self, size: int, piece: Callable[[int, int], np.ndarray]):
        self.size = int(size)
        self.shape = (self.size,)
        self._piece = piece
        self._finite: bool | None = None

    def __len__(self) -> int:
        return self.size

    def __getitem__(self, key) -> np.ndarray:
        a, b, step = _slice(key, self.size)
        if step == 1:
            return np.asarray(self._piece(a, b), dtype=np.float64)
        out = [p[::step] for _, p in self.pieces(a, b, step)]   # pieces start on the series
        return np.concatenate(out) if out else np.empty(0)

    def pieces(self, a: int = 0, b: int | None = None, step: int = 1):
        """(start, samples) of consecutive pieces of a … b−1 (pieces a multiple of
        ``step`` long, so that every step-th sample is found in order)."""
        b = self.size if b is None else b
        size = max(1, PIECE // step) * step
        for s in range(a, b, size):
            yield s, self[s: min(b, s + size)]

    def __truediv__(self, divisor: float) -> "Record":
        """The record divided by a number, sample by sample (as ``array / divisor``)."""
        def piece(a, b):
            p = self._piece(a, b)
            p /= divisor
            return p
        return Record(self.size, piece)

    def total(self) -> float:
        """Σ samples (each piece summed pairwise, the pieces in order)."""
        return float(sum(float(np.sum(p)) for _, p in self.pieces()))

    def mean(self) -> float:
        return self.total() / self.size

    def all_finite(self) -> bool:
        if self._finite is None:
            self._finite = all(bool(np.isfinite(p).all()) for _, p in self.pieces())
        return self._finite

    def check_finite(self, name: str) -> None:
        """A GonioError naming ``name`` when a sample is NaN or infinite."""
        if not self.all_finite():
            raise GonioError(f"{name} holds a non-finite value", key=name)

    def block_means(self, block: int) -> np.ndarray:
        """Means of the complete non-overlapping blocks of ``block`` samples (as
        ``x[:n·P].reshape(n, P).mean(axis=1)``, bit for bit)."""
        n = self.size // block
        rows = max(1, PIECE // block)
        out = np.empty(n)
        for r in range(0, n, rows):
            e = min(n, r + rows)
            out[r:e] = self[r * block: e * block].reshape(e - r, block).mean(axis=1)
        return out

    def value_range(self) -> float:
        lo, hi = np.inf, -np.inf
        for _, p in self.pieces():
            lo, hi = min(lo, float(p.min())), max(hi, float(p.max()))
        return hi - lo

    def to_array(self) -> np.ndarray:
        """The whole record as one array (the fallback of estimators that need it)."""
        return self[0: self.size]


def rows_where(df, select) -> tuple[int, int, np.ndarray | None]:
    """(first row, count, row positions or None when the rows are first … first+count−1)
    of the rows of the frame ``df`` where ``select(piece)`` (a boolean Series of a piece of
    the frame) holds, found piece by piece (no record-long position array for one run of
    rows). Count 0 when there are none."""
    first, count, parts = 0, 0, None
    for a in range(0, len(df), PIECE):
        i = np.flatnonzero(np.asarray(select(df.iloc[a: a + PIECE]), dtype=bool)) + a
        if not i.size:
            continue
        if parts is None:
            first = int(i[0]) if count == 0 else first
            if i[0] == first + count and i[-1] == i[0] + i.size - 1:
                count += i.size                   # still one run of rows
                continue
            parts = [np.arange(first, first + count)]
        parts.append(i)
        count += i.size
    return first, count, None if parts is None else np.concatenate(parts)


def frame_column(df, column: str, rows: tuple[int, int, np.ndarray | None]):
    """Column ``column`` of the frame at ``rows`` (:func:`rows_where`) as float64: an array,
    or for one run of at least :data:`STREAM_MIN_SAMPLES` rows a :class:`Record` read from
    the frame piece by piece."""
    first, count, idx = rows
    if idx is not None:
        return df[column].to_numpy(dtype=float)[idx]
    if count < STREAM_MIN_SAMPLES:
        return df[column].to_numpy(dtype=float)[first: first + count].copy()
    col = df[column]
    if col.dtype == np.float64:
        # the frame's own float64 array (a view, no copy): pieces are numpy slices, without
        # pandas' cost per piece
        vals = col.to_numpy(copy=False)
        return Record(count, lambda a, b: vals[first + a: first + b].copy())
    return Record(count, lambda a, b: col.iloc[first + a: first + b].to_numpy(dtype=float,
                                                                             copy=True))


def value_range(x) -> float:
    """max − min (``np.ptp``) of an array or a :class:`Record`."""
    return x.value_range() if isinstance(x, Record) else float(np.ptp(x))


class CumulativeSum:
    """``c = [0, cumsum(y − offset)]`` of a :class:`Record` (``size`` = N + 1), never held
    whole (module docstring). Slices equal those of the whole array bit for bit: each
    block starts from the exact value the sequential sum has at its first point.

    The checkpoints are found lazily, as the blocks are first built in order (no pass of
    its own over the record): a block past the last one built is reached by building the
    blocks between. Besides the value at every block boundary the value every
    :data:`FINE` points is kept (N/FINE numbers), from which :meth:`span` rebuilds any
    slice with at most FINE − 1 points of overhead (the far pieces of a large averaging
    time, :func:`gonio.analysis.noise.allan._sums_far`)."""

    ndim = 1
    dtype = np.dtype(np.float64)

    def __init__(self, record: Record, offset: float = 0.0, *, block: int | None = None,
                 cache_blocks: int = 8):
        self.record, self.offset = record, float(offset)
        self.block = int(block or PIECE)
        self.size = record.size + 1
        self.shape = (self.size,)
        self._cache: OrderedDict[int, np.ndarray] = OrderedDict()
        self._keep = cache_blocks
        nb = -(-self.size // self.block)
        self._start = np.empty(nb)            # c at the first point of every block
        self._start[0] = 0.0
        self._done = 0                        # blocks built in order so far (checkpoints)
        self._fine_step = FINE if self.block % FINE == 0 else self.block
        self._fine = np.empty(-(-self.size // self._fine_step))   # c every _fine_step points
        self._fine[0] = 0.0

    def __len__(self) -> int:
        return self.size

    def _build(self, j: int) -> np.ndarray:
        """c[jB … min((j+1)B, N)] (one point past the block: the next block's start)."""
        while self._done < j:                 # the checkpoints up to block j, in order
            self._build(self._done)
        a = j * self.block
        b = min(a + self.block, self.size - 1)
        out = np.empty(b - a + 1)
        out[0] = self._start[j]
        np.subtract(self.record[a:b], self.offset, out=out[1:])
        np.cumsum(out, out=out)
        if j == self._done:                   # first time: its checkpoints
            f = self._fine_step
            self._fine[a // f: -(-(b + 1) // f)] = out[::f]
            if j + 1 < self._start.size:
                self._start[j + 1] = out[-1]
            self._done += 1
        return out

    def _get(self, j: int) -> np.ndarray:
        blk = self._cache.get(j)
        if blk is None:
            blk = self._build(j)[: self.block]
            self._cache[j] = blk
            if len(self._cache) > self._keep:
                self._cache.popitem(last=False)
        else:
            self._cache.move_to_end(j)
        return blk

    def span(self, a: int, b: int) -> np.ndarray:
        """c[a:b] (a fresh array, equal bit for bit to the slice of the whole array) rebuilt
        from the last fine checkpoint at or before ``a``, without the block cache: for
        pieces read once each at scattered places."""
        b = min(b, self.size)
        if b <= a:
            return np.empty(0)
        if a // self.block >= self._done:
            self._build(a // self.block)                   # checkpoints that far
        f = self._fine_step
        a0 = (a // f) * f
        out = np.empty(b - a0)
        out[0] = self._fine[a // f]
        if b - a0 > 1:
            np.subtract(self.record[a0: b - 1], self.offset, out=out[1:])
            np.cumsum(out, out=out)
        return out[a - a0:]

    def __getitem__(self, key) -> np.ndarray:
        a, b, step = _slice(key, self.size)
        B = self.block
        if step == 1:                               # straight into the result: one copy
            out = np.empty(b - a)
            i = a
            while i < b:
                j = i // B
                e = min(b, (j + 1) * B)
                out[i - a: e - a] = self._get(j)[i - j * B: e - j * B]
                i = e
            return out
        parts = []
        i = a
        while i < b:
            j = i // B
            blk = self._get(j)
            e = min(b, (j + 1) * B)
            parts.append(blk[i - j * B: e - j * B: step].copy())   # no view keeps a block
            # the next index of the series a, a + step, … at or past the block's end
            i = i + -(-(e - i) // step) * step
        if not parts:
            return np.empty(0)
        return parts[0] if len(parts) == 1 else np.concatenate(parts)

    def decimations(self, ranges) -> list[np.ndarray]:
        """``c[a:b:m]`` for every (a, b, m) of ``ranges``, in one pass over the blocks
        (the block cache untouched); a range whose step is at least the fine checkpoints'
        spacing point by point from them instead (:meth:`span` of one point: fewer than
        that spacing rebuilt per point, not every block)."""
        out: list[list[np.ndarray]] = [[] for _ in ranges]
        sparse = {k for k, (_, _, m) in enumerate(ranges) if m >= self._fine_step}
        for k in sparse:
            a, b, m = ranges[k]
            pts = range(a, min(b, self.size), m)
            out[k] = [np.array([self.span(i, i + 1)[0] for i in pts])] if len(pts) else []
        B = self.block
        for j in range(self._start.size if len(sparse) < len(ranges) else 0):
            lo = j * B
            hi = min(lo + B, self.size)
            need = [k for k, (a, b, _) in enumerate(ranges)
                    if k not in sparse and a < hi and min(b, self.size) > lo]
            if not need:
                continue
            blk = self._build(j)[:B]
            for k in need:
                a, b, m = ranges[k]
                first = a + max(0, -(-(lo - a) // m)) * m       # first index ≥ lo
                stop = min(b, hi)
                if first < stop:
                    out[k].append(blk[first - lo: stop - lo: m].copy())
        return [np.concatenate(p) if p else np.empty(0) for p in out]
