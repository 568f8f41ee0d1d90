"""Rests of a continuous stream: where the table (or, without its encoder, the gyro) dwells.

Contents
========
=========================  ===================================================
:class:`Rest`              one dwell of the table (indices, level, edges)
:class:`RestFinder`        rest detection fed chunk by chunk (bounded memory)
:func:`find_rests`         rests of a whole stream, with sub-sample edges
:func:`rests_of`           the same on a sample source read once chunk by chunk
:class:`MemorySamples`     a stream in memory seen as a sample source
=========================  ===================================================

Shared by the optical draft's reduction of a stream to readings
(docs/formats.md#from-a-stream-to-readings) and the noise analysis of a stream's static
record (:mod:`gonio.analysis.noise.record`):

1. **Rests.** With ``table_deg``: the encoder angle, despiked by a 3-sample
   median (single-sample glitches vanish), is at rest where its rate over
   ``window_s`` is below ``rate_threshold_dps``. Without it: the same on the
   gyro angle ``counts / K`` (``K`` nominal scale factor) smoothed over a longer
   window; the threshold sits above the Earth-rate level (≤ 0.0042 °/s).
   Rests shorter than ``min_rest_s`` are dropped.
2. **Edges.** Departure (zeroing) and arrival times are refined below one sample
   from the first/last two moving samples: in the constant-acceleration part of
   a move the angle off the rest level is ``a(t − t₀)²/2``, so ``√|Δθ|`` is linear
   in ``t`` and its root is ``t₀``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gonio.errors import GonioError
from gonio.formats.streams import Stream, StreamChunk

#: Default rest threshold on the table encoder rate, °/s.
TABLE_RATE_THRESHOLD_DPS = 0.01
#: Default rest threshold on the gyro rate, °/s (Earth rate ≤ 0.0042 °/s).
GYRO_RATE_THRESHOLD_DPS = 0.05
#: Default smoothing window of the gyro rate, s.
GYRO_WINDOW_S = 0.5


@dataclass
class Rest:
    """One rest of the table: samples ``i_start``…``i_end`` (inclusive)."""

    i_start: int
    i_end: int
    t_start_s: float
    t_end_s: float
    level_deg: float
    t_arrive_s: float = math.nan    # refined arrival (first rest: t_start_s)
    t_depart_s: float = math.nan    # refined departure (last rest: t_end_s)

    @property
    def duration_s(self) -> float:
        """Length of the rest, s."""
        return self.t_end_s - self.t_start_s


def _median3(x: np.ndarray) -> np.ndarray:
    """Median of each sample and its two neighbours (interior samples only)."""
    a, b, c = x[:-2], x[1:-1], x[2:]
    lo = np.minimum(a, b)                 # max(min(a, b), min(max(a, b), c)), two arrays
    hi = np.maximum(a, b)
    np.minimum(hi, c, out=hi)
    return np.maximum(lo, hi, out=lo)


#: Samples the rest finder works at a time: its arrays of this length stay in the core's
#: cache (whole blocks of 2¹⁸ samples do not, and are four to eight times slower).
FEED_PIECE = 1 << 16


class RestFinder:
    """Rest detection fed chunk by chunk; the result does not depend on the chunking.

    Per sample ``i`` (``w`` = window in samples) the rest test is
    ``|y[i] − y[i−w]| < thr·(t[i] − t[i−w])`` on the despiked signal ``y``; a run
    of passing samples ``a…b`` is the rest ``a−w…b``. Memory: a few samples of
    carry plus the list of rests. Levels are run means (:func:`find_rests`
    refines them).

    >>> t = np.arange(0, 10, 0.1); x = np.where(t < 4, 0.0, np.minimum((t - 4) * 30, 90.0))
    >>> f = RestFinder(rate_threshold_dps=0.01, window=1, despike=True, min_rest_s=1.0)
    >>> f.feed(t[:37], x[:37]); f.feed(t[37:], x[37:])
    >>> [(r.i_start, r.i_end, r.level_deg) for r in f.finish()]
    [(0, 40, 0.0), (70, 99, 90.0)]
    """

    def __init__(self, *, rate_threshold_dps: float, window: int, despike: bool,
                 min_rest_s: float):
        self.thr, self.w, self.despike, self.min_rest_s = rate_threshold_dps, int(window), \
            despike, min_rest_s
        self._hold_t = np.empty(0)
        self._hold_x = np.empty(0)
        self._n_in = 0                 # raw samples received
        self._n_out = 0                # despiked samples emitted
        self._ct = np.empty(0)         # carry of the last w despiked samples
        self._cy = np.empty(0)
        self._open: dict | None = None   # the run in progress
        self.rests: list[Rest] = []

    def feed(self, time_s: np.ndarray, x: np.ndarray) -> None:
        """Add consecutive samples (worked :data:`FEED_PIECE` at a time, so that every
        pass over them stays in the core's cache; the result does not depend on it)."""
        t = np.asarray(time_s, dtype=np.float64)
        x = np.asarray(x, dtype=np.float64)
        for a in range(0, t.size, FEED_PIECE):
            self._feed(t[a:a + FEED_PIECE], x[a:a + FEED_PIECE])

    def _feed(self, t: np.ndarray, x: np.ndarray) -> None:
        if t.size == 0:
            return
        if not self.despike:
            self._n_in += t.size
            self._stage2(t, x)
            return
        # hold = the last two raw samples; the last of them is not yet emitted
        T = np.concatenate((self._hold_t, t))
        X = np.concatenate((self._hold_x, x))
        first = self._n_in == 0
        self._n_in += t.size
        if first:
            self._stage2(T[:1], X[:1])
        if T.size >= 3:
            # with a window of one the carried time is T[0]: T[:-1] is the stage's own
            # time axis, a view instead of a copy
            tz = T[:-1] if self.w == 1 and self._ct.size == 1 and self._ct[0] == T[0] \
                else None
            self._stage2(T[1:-1], _median3(X), tz)
        self._hold_t, self._hold_x = T[-2:].copy(), X[-2:].copy()

    def _stage2(self, t: np.ndarray, y: np.ndarray, tz: np.ndarray | None = None) -> None:
        """Rest test on despiked samples ``(t, y)``; ``tz``: the carried times followed by
        ``t`` when the caller has them in one array already."""
        if t.size == 0:
            return
        w = self.w
        g0 = self._n_out - self._ct.size       # global index of Z[0]
        T = np.concatenate((self._ct, t)) if tz is None else tz
        Z = np.concatenate((self._cy, y))
        self._n_out += t.size
        if Z.size > w:
            dz = np.subtract(Z[w:], Z[:-w])      # |ΔZ| < thr·ΔT, formed in place
            lim = np.subtract(T[w:], T[:-w])
            np.multiply(self.thr, lim, out=lim)
            n_ok = dz.size
            np.abs(dz, out=dz)
            ok = np.less(dz, lim)
            del dz, lim
            # runs of ok: cut where ok changes; every other segment, from the first true
            # one, is a run
            cuts = np.flatnonzero(ok[1:] != ok[:-1]) + 1
            bounds = np.concatenate(([0], cuts, [n_ok])).tolist()
            first = 0 if ok[0] else 1
            starts = bounds[first:-1:2]
            ends = [b - 1 for b in bounds[first + 1::2]]
            del ok, cuts
            if self._open is not None and not (starts and starts[0] == 0):
                self._close()
            Zw = Z[w:]
            for s, e in zip(starts, ends):
                part = float(Zw[s:e + 1].sum())
                if s == 0 and self._open is not None:
                    self._open["sum"] += part
                    self._open["cnt"] += e - s + 1
                else:
                    self._open = {"a": g0 + s + w, "t0": float(T[s]),
                                  "sum": part, "cnt": e - s + 1}
                self._open["b"], self._open["tb"] = g0 + e + w, float(T[e + w])
                if e < n_ok - 1:
                    self._close()
        self._ct, self._cy = T[-w:].copy(), Z[-w:].copy()

    def _close(self) -> None:
        o, self._open = self._open, None
        if o is not None and o["tb"] - o["t0"] >= self.min_rest_s:
            self.rests.append(Rest(o["a"] - self.w, o["b"], o["t0"], o["tb"],
                                   float(o["sum"] / o["cnt"])))

    def finish(self) -> list[Rest]:
        """Flush the last samples and return the rests found."""
        if self.despike and self._n_in >= 2:
            self._stage2(self._hold_t[-1:], self._hold_x[-1:])
        self._hold_t = self._hold_x = np.empty(0)
        self._close()
        return self.rests


#: A rest's level is the median over at most this many of its samples (evenly strided
#: beyond it), so a rest of any length is levelled in bounded memory.
LEVEL_MAX_SAMPLES = 1 << 21
#: Samples fetched at a time when levelling a long rest.
_LEVEL_PIECE = 1 << 18


def _dt(time_s: np.ndarray) -> float:
    d = np.diff(time_s[: min(time_s.size, 100_000)])
    return float(np.median(d)) if d.size else 1.0


class MemorySamples:
    """A :class:`Stream` held in memory, seen through the sample-access interface that
    :class:`gonio.formats.streams.StreamFile` offers for a file (one code path for both)."""

    def __init__(self, stream: Stream):
        self.st = stream
        self.metadata = stream.metadata
        self.path = stream.path
        self.has_table = stream.table_deg is not None

    def __len__(self) -> int:
        return int(self.st.time_s.size)

    def chunks(self):
        st = self.st
        yield StreamChunk(st.time_s, st.gyro_counts, st.table_deg, st.temperature_c, 0)

    @property
    def t_first(self) -> float:
        return float(self.st.time_s[0])

    @property
    def t_last(self) -> float:
        return float(self.st.time_s[-1])

    def time_at(self, i: int) -> float:
        return float(self.st.time_s[int(i)])

    def counts_at(self, i: int):
        return self.st.gyro_counts[int(i)]

    def search(self, t: float, side: str = "left") -> int:
        return int(np.searchsorted(self.st.time_s, t, side=side))

    def window(self, a: int, b: int) -> StreamChunk:
        n = len(self)
        a, b = max(0, int(a)), min(n, int(b))
        st = self.st
        tab = None if st.table_deg is None else st.table_deg[a:b]
        return StreamChunk(st.time_s[a:b], st.gyro_counts[a:b], tab, None, a)


class _Signal:
    """The signal rests are found on: the table angle (despiked by a median of three) or,
    without a table column, the gyro angle (counts − first count)/K; fetched by index."""

    def __init__(self, src, on_table: bool, k_sf: float | None):
        self.src, self.on_table, self.k = src, on_table, k_sf
        self.n = len(src)
        self.c0 = None if on_table else src.counts_at(0)

    def raw(self, ch: StreamChunk) -> np.ndarray:
        if self.on_table:
            return np.asarray(ch.table_deg, dtype=np.float64)
        return (ch.gyro_counts - self.c0).astype(np.float64) / self.k

    def get(self, a: int, b: int) -> tuple[np.ndarray, np.ndarray]:
        """(t, y) of samples a … b − 1 (clipped), y despiked on the table."""
        a, b = max(0, a), min(self.n, b)
        if not self.on_table:
            ch = self.src.window(a, b)
            return ch.time_s, self.raw(ch)
        lo, hi = max(0, a - 1), min(self.n, b + 1)
        ch = self.src.window(lo, hi)
        x = self.raw(ch)
        y = x.copy()
        if x.size >= 3:
            y[1:-1] = _median3(x)
        # the first/last fetched samples are despiked only at the stream's own ends
        return ch.time_s[a - lo: a - lo + (b - a)], y[a - lo: a - lo + (b - a)]


def _signal(time_s, table_deg, counts, scale_factor_counts_per_deg):
    if table_deg is not None:
        return True
    if counts is None:
        raise GonioError("find_rests needs table_deg or gyro counts")
    check_scale_factor(scale_factor_counts_per_deg)
    return False


def check_scale_factor(k):
    if not k or not math.isfinite(k) or k <= 0:
        raise GonioError("a stream without table_deg needs the metadata "
                         "nominal_scale_factor_counts_per_deg to find rests from the gyro rate",
                         key="nominal_scale_factor_counts_per_deg")


def find_rests(time_s: np.ndarray, table_deg: np.ndarray | None = None,
               counts: np.ndarray | None = None, *,
               scale_factor_counts_per_deg: float | None = None,
               rate_threshold_dps: float | None = None, window_s: float | None = None,
               min_rest_s: float = 0.5, refine: bool = True) -> list[Rest]:
    """Rests (dwells) of the table, from ``table_deg`` or, without it, from the gyro rate.

    Parameters
    ----------
    time_s : ndarray
        Sample times.
    table_deg : ndarray, optional
        Table encoder angle; despiked by a 3-sample median.
    counts : ndarray, optional
        Unwrapped counter, used when ``table_deg`` is None (then
        ``scale_factor_counts_per_deg`` is required).
    rate_threshold_dps : float, optional
        Rest when the rate is below this; default 0.01 °/s on the table, 0.05 °/s
        on the gyro (above the Earth rate, 15.04 °/h ≈ 0.0042 °/s at most).
    window_s : float, optional
        Rate taken over this span; default one sample (table), 0.5 s (gyro).
    min_rest_s : float
        Shorter rests are dropped.
    refine : bool
        Median levels and sub-sample arrival/departure times (see module notes).

    Returns
    -------
    list of Rest

    Examples
    --------
    >>> t = np.arange(0, 20, 0.01)
    >>> x = np.clip((t - 5.0) * 60.0, 0, 90.0)          # 5 s rest, move to 90°
    >>> x[1200] += 3.0                                   # a one-sample encoder glitch
    >>> r = find_rests(t, x)
    >>> [(round(q.level_deg, 6), q.i_start, q.i_end) for q in r]
    [(0.0, 0, 500), (90.0, 650, 1999)]
    >>> round(r[0].t_depart_s, 9), round(r[1].t_arrive_s, 9)
    (5.0, 6.5)
    """
    time_s = np.asarray(time_s, dtype=np.float64)
    on_table = _signal(time_s, table_deg, counts, scale_factor_counts_per_deg)
    st = Stream(time_s, np.zeros(time_s.size, dtype=np.int64) if counts is None else
                np.asarray(counts), None if table_deg is None else
                np.asarray(table_deg, dtype=np.float64))
    return rests_of(MemorySamples(st), on_table=on_table,
                    scale_factor_counts_per_deg=scale_factor_counts_per_deg,
                    rate_threshold_dps=rate_threshold_dps, window_s=window_s,
                    min_rest_s=min_rest_s, refine=refine)[0]


def rests_of(src, *, on_table: bool, scale_factor_counts_per_deg: float | None = None,
             rate_threshold_dps: float | None = None, window_s: float | None = None,
             min_rest_s: float = 0.5, refine: bool = True) -> tuple[list[Rest], float]:
    """:func:`find_rests` on a sample source (a :class:`gonio.formats.streams.StreamFile` or a stream
    in memory), reading it once chunk by chunk; returns the rests and the median sample
    interval of the first 100 000 samples.

    Memory: the rest finder's carry, the list of rests, and for the refinement a
    window around each edge and at most :data:`LEVEL_MAX_SAMPLES` samples of a rest.
    """
    k = scale_factor_counts_per_deg
    if not on_table:
        check_scale_factor(k)
    finder = None
    head_t: list[np.ndarray] = []
    head_x: list[np.ndarray] = []
    n_head = 0
    dt = 1.0
    sig = None
    c0 = None
    for ch in src.chunks():
        if not on_table and c0 is None:
            c0 = ch.gyro_counts[0]
        x = np.asarray(ch.table_deg, dtype=np.float64) if on_table else \
            (ch.gyro_counts - c0).astype(np.float64) / k
        if finder is None:
            head_t.append(ch.time_s)
            head_x.append(x)
            n_head += ch.time_s.size
            if n_head < 100_000:
                continue
            finder, dt = _start_finder(head_t, head_x, on_table, rate_threshold_dps, window_s,
                                       min_rest_s)
            continue
        finder.feed(ch.time_s, x)
    if finder is None:
        if not head_t:
            return [], dt
        finder, dt = _start_finder(head_t, head_x, on_table, rate_threshold_dps, window_s,
                                   min_rest_s)
    rests = finder.finish()
    if refine and rests:
        sig = _Signal(src, on_table, k)
        floor = 1e-9 if on_table else 1.5 / float(k)
        _refine(sig, rests, finder.w, floor, trend=not on_table)
    return rests, dt


def _start_finder(head_t, head_x, on_table, rate_threshold_dps, window_s, min_rest_s):
    t = np.concatenate(head_t)
    x = np.concatenate(head_x)
    dt = _dt(t)
    thr = rate_threshold_dps if rate_threshold_dps is not None else (
        TABLE_RATE_THRESHOLD_DPS if on_table else GYRO_RATE_THRESHOLD_DPS)
    ws = window_s if window_s is not None else (0.0 if on_table else GYRO_WINDOW_S)
    w = max(1, int(round(ws / dt)))
    f = RestFinder(rate_threshold_dps=thr, window=w, despike=on_table, min_rest_s=min_rest_s)
    f.feed(t, x)
    return f, dt


def _root_sqrt(t1, d1, t2, d2) -> float:
    """Time where √d reaches 0 on the line through (t1, √d1), (t2, √d2); NaN if none."""
    s1, s2 = math.sqrt(d1), math.sqrt(d2)
    if s1 == s2:
        return math.nan
    return t1 - s1 * (t2 - t1) / (s2 - s1)


def _edge_fit(t: np.ndarray, y: np.ndarray, lo: int, hi: int, t_ref: float, trend: bool):
    """Level (and slope when ``trend``) of the rest over samples lo…hi−1, and its noise."""
    tt, yy = t[lo:hi] - t_ref, y[lo:hi]
    if trend and yy.size >= 3:
        b, a = np.polyfit(tt, yy, 1)
    else:
        a, b = float(np.median(yy)), 0.0
    res = yy - (a + b * tt)
    return float(a), float(b), float(np.median(np.abs(res - np.median(res)))) * 1.4826


def _level(sig: _Signal, s: int, e: int) -> float:
    """Median of the signal over the rest s … e (evenly strided beyond LEVEL_MAX_SAMPLES)."""
    n = e + 1 - s
    if n <= _LEVEL_PIECE:
        return float(np.median(sig.get(s, e + 1)[1]))
    stride = -(-n // LEVEL_MAX_SAMPLES)
    if stride > _LEVEL_PIECE:         # pragma: no cover - a rest of > 5×10¹¹ samples
        stride = _LEVEL_PIECE
    piece = _LEVEL_PIECE - _LEVEL_PIECE % stride      # a multiple of the stride
    parts = []
    for a in range(s, e + 1, piece):
        parts.append(sig.get(a, min(e + 1, a + piece))[1][::stride])
    return float(np.median(np.concatenate(parts)))


def _refine(sig: _Signal, rests: list[Rest], w: int, floor: float, trend: bool = False) -> None:
    """Median levels, and sub-sample departure/arrival from the √-law of a start from rest.

    On the gyro angle (``trend``) the rest is a line (the Earth rate), not a level.
    Each edge is refined on a window of samples around it (fetched from the source).
    """
    n = sig.n
    for r in rests:
        s, e = r.i_start, r.i_end
        r.level_deg = _level(sig, s, e)
        inner = max(1, w) if trend else 0     # samples near the edges the window may blur
        # departure
        r.t_depart_s = sig.src.time_at(e)
        if e < n - 1:
            hi = max(s + 2, e - inner + 1)
            lo = max(s, hi - max(3 * w, 20))
            j0, j1 = max(s + 1, hi - 1), min(n, e + w + 6)
            A = lo
            t, y = sig.get(A, j1)
            a, b, noise = _edge_fit(t, y, lo - A, hi - A, float(t[e - A]), trend)
            tol = max(5.0 * noise, floor)
            d = np.abs(y[j0 - A:j1 - A] - (a + b * (t[j0 - A:j1 - A] - t[e - A])))
            off = d > tol
            if off.any():
                k = int(np.argmax(off))
                j = j0 + k
                r.t_depart_s = float(t[j - 1 - A])
                if k + 1 < d.size:
                    td = _root_sqrt(t[j - A], d[k], t[j + 1 - A], d[k + 1])
                    if math.isfinite(td):
                        r.t_depart_s = float(min(max(td, t[j - 1 - A]), t[j - A]))
        # arrival
        r.t_arrive_s = sig.src.time_at(s)
        if s > 0:
            lo = min(e - 1, s + inner)
            hi = min(e + 1, lo + max(3 * w, 20))
            j0, j1 = max(0, s - w - 6), min(e, lo + 1)
            A = j0
            t, y = sig.get(A, max(hi, j1) + 1)
            a, b, noise = _edge_fit(t, y, lo - A, hi - A, float(t[s - A]), trend)
            tol = max(5.0 * noise, floor)
            d = np.abs(y[j0 - A:j1 - A] - (a + b * (t[j0 - A:j1 - A] - t[s - A])))
            off = d > tol
            if off.any():
                k = int(np.flatnonzero(off)[-1])
                j = j0 + k
                r.t_arrive_s = float(t[j + 1 - A])
                if k >= 1:
                    ta = _root_sqrt(t[j - A], d[k], t[j - 1 - A], d[k - 1])
                    if math.isfinite(ta):
                        r.t_arrive_s = float(min(max(ta, t[j - A]), t[j + 1 - A]))
