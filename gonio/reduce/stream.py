"""Stream → readings: find the table's rests and take the readings the protocol asks for.

Contents
========
=========================  ===================================================
:class:`Rest`              one dwell of the table (indices, level, edges)
:class:`RestFinder`        rest detection fed chunk by chunk (bounded memory)
:func:`find_rests`         rests of a whole stream, with sub-sample edges
:class:`Reduction`         readings, what could not be matched and why, a log
:func:`reduce_stream`      match rests to the protocol's rounds → readings
:func:`read_override`      an operator's explicit (t_zero, t_read) per round
=========================  ===================================================

What an acquisition does on its external trigger (docs/formats.md#from-a-stream-to-readings, draft clause 7
preamble), reproduced from the continuous counter:

1. **Rests.** With ``table_deg``: the encoder angle, despiked by a 3-sample
   median (single-sample glitches vanish), is at rest where its rate over
   ``window_s`` is below ``rate_threshold_dps``. Without it: the same on the
   gyro angle ``counts / K`` (``K`` nominal scale factor) smoothed over a longer
   window; the threshold sits above the Earth-rate level (≤ 0.0042 °/s).
   Rests shorter than ``min_rest_s`` are dropped.
2. **Edges.** Departure (zeroing) and arrival times are refined below one sample
   from the first/last two moving samples: in the constant-acceleration part of
   a move the angle off the rest level is ``a(t − t₀)²/2``, so ``√|Δθ|`` is linear
   in ``t`` and its root is ``t₀``. The zeroing is the sample nearest the
   departure; the reading is the first sample at or after arrival +
   ``read_delay_s``.
3. **Compensation.** ``measured``: the rate of the counter over the last
   ``static_s`` of rest before a series' first departure (draft clause 7
   preamble); ``computed``: K·Ω·axis from the metadata latitude; ``none``: 0.
4. **Readings.** ``counts(read) − counts(zero) − comp·(t_read − t_zero)``, rounded
   to whole counts when the counter is quantised (what the virtual bench and
   an acquisition module write).

Matching is by order and relative angle: each round needs a rest at its start
level followed (extra rests allowed in between) by a rest whose level differs by
``stop − start`` (``pos_tol_deg``). A round is skipped as missing when the next
expected round's pair is found before its own; every skipped round and every
rest no round used is reported with the reason. An operator can override the
matching round by round (:func:`read_override`).

The static multi-position test (``[tilt_estimate]``, after zero stability as the bench runs
it) is matched by position: N rests 360°/N apart, each at least ``settle_s + dwell_s`` long;
zeroing ``settle_s`` after arrival, reading ``dwell_s`` later, no compensation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np
import pandas as pd

from gonio.errors import GonioError
from gonio.protocol import Protocol, RotationItem
from gonio.formats.streams import Stream, StreamChunk, StreamFile

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


class _MemorySamples:
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
    _check_k(scale_factor_counts_per_deg)
    return False


def _check_k(k):
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
    return rests_of(_MemorySamples(st), on_table=on_table,
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
        _check_k(k)
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


# ----------------------------------------------------------------------------- matching


@dataclass
class Reduction:
    """The result of :func:`reduce_stream`.

    Attributes
    ----------
    readings : pandas.DataFrame
        Readings-file columns (docs/formats.md#columns), plus ``t_zero_s`` and ``t_read_s``
        (stream times of the zeroing and reading samples; not written by
        :func:`gonio.formats.readings.write_readings` unless kept as extra columns).
    unmatched : list of dict
        Rounds that could not be read and rests no round used, each with ``reason``.
    log : list of str
    rests : list of Rest
    compensation_counts_per_s : list of float
        Per series, in protocol order.
    metadata : dict
        For the readings file (the stream's, without the counter keys).
    """

    readings: pd.DataFrame
    unmatched: list[dict] = field(default_factory=list)
    log: list[str] = field(default_factory=list)
    rests: list[Rest] = field(default_factory=list)
    compensation_counts_per_s: list[float] = field(default_factory=list)
    metadata: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """Plain-JSON summary (``gonio reduce --json``)."""
        return {"readings": int(len(self.readings)), "rests": len(self.rests),
                "unmatched": self.unmatched, "log": self.log,
                "compensation_counts_per_s": [float(c) for c in self.compensation_counts_per_s]}


@dataclass
class _Ctx:
    st: object               # the sample source (_MemorySamples or StreamFile)
    proto: Protocol
    rests: list[Rest]
    pos_tol: float
    quantised: bool
    eps: float
    used: set = field(default_factory=set)
    rows: list = field(default_factory=list)
    unmatched: list = field(default_factory=list)
    log: list = field(default_factory=list)
    comps: list = field(default_factory=list)
    cursor: int = 0

    def sample_at_or_after(self, t: float) -> int:
        return self.st.search(t - self.eps, side="left")

    def nearest(self, t: float) -> int:
        st = self.st
        i = st.search(t)
        n = len(st)
        if i >= n:
            return n - 1
        if i > 0 and (t - st.time_at(i - 1)) <= (st.time_at(i) - t):
            return i - 1
        return i

    def t(self, i: int) -> float:
        return self.st.time_at(i)

    def c(self, i: int):
        return self.st.counts_at(i)

    def counts(self, kz: int, kr: int, comp: float) -> float:
        d = self.c(kr) - self.c(kz)
        raw = float(d) - comp * float(self.t(kr) - self.t(kz))
        return float(np.rint(raw)) if self.quantised else raw


def _computed_comp(st: Stream, orientation: str) -> float:
    from gonio.physics.earth import earth_rate_on_axis_dps
    from gonio.formats.readings import metadata_float
    k = metadata_float(st.metadata, "nominal_scale_factor_counts_per_deg", file=st.path)
    lat = metadata_float(st.metadata, "latitude_deg", file=st.path)
    if k is None or lat is None:
        raise GonioError("earth_compensation = 'computed' needs the stream metadata "
                         "nominal_scale_factor_counts_per_deg and latitude_deg", file=st.path,
                         key="latitude_deg" if lat is None else
                         "nominal_scale_factor_counts_per_deg")
    return k * earth_rate_on_axis_dps(lat, orientation)


def _static_comp(ctx: _Ctx, rest_idx: int, kz: int) -> float | None:
    """Counter rate over the last static_s before the zeroing sample ``kz`` (inside the rest)."""
    s = ctx.proto.session
    if s.earth_compensation == "none":
        return 0.0
    if s.earth_compensation == "computed":
        return None  # filled by caller
    k0 = ctx.nearest(ctx.t(kz) - s.static_s)
    if k0 < ctx.rests[rest_idx].i_start or k0 >= kz:
        return math.nan
    return float(ctx.c(kz) - ctx.c(k0)) / float(ctx.t(kz) - ctx.t(k0))


def _find_pair(ctx: _Ctx, start: int, zero_level: float | None, delta: float,
               read_need_s: float, zero_fixed: int | None) -> tuple[int, int] | None:
    """First (zero rest, read rest) from ``start``: read level − zero level ≈ delta."""
    R = ctx.rests
    tol = ctx.pos_tol
    for r in range(start + 1 if zero_fixed is None else max(start, zero_fixed) + 1, len(R)):
        if R[r].t_end_s + 1e-9 < R[r].t_arrive_s + read_need_s:
            continue
        if zero_fixed is not None:
            if abs(R[r].level_deg - R[zero_fixed].level_deg - delta) < tol:
                return zero_fixed, r
            continue
        for z in range(r - 1, start - 1, -1):
            if zero_level is not None and abs(R[z].level_deg - zero_level) >= tol:
                continue
            if abs(R[r].level_deg - R[z].level_deg - delta) < tol:
                return z, r
            break   # the zero is the last rest at the start level before the move
    return None


def _series_rounds(item: RotationItem) -> list[tuple[int, float, float]]:
    return [(i, r.start_deg, r.stop_deg) for i, r in enumerate(item.rounds, 1)]


def _row(test, series, rnd, rate, orient, ctx: _Ctx, kz, kr, table_deg, comp):
    tz, tr = ctx.t(kz), ctx.t(kr)
    return {"test": test, "series": series, "round": rnd, "rate_dps": rate,
            "orientation": orient, "time_s": round(float(tr - tz), 9),
            "table_deg": table_deg, "gyro_counts": ctx.counts(kz, kr, comp),
            "gyro_deg": math.nan, "t_zero_s": float(tz), "t_read_s": float(tr)}


def _zero_stability(ctx: _Ctx) -> None:
    z = ctx.proto.zero_stability
    s = ctx.proto.session
    static = s.static_s if s.earth_compensation == "measured" else 0.0
    need = static + (z.readings - 1) * z.interval_s
    for q in range(ctx.cursor, len(ctx.rests)):
        r = ctx.rests[q]
        if r.t_end_s + 1e-9 >= r.t_arrive_s + need:
            break
    else:
        ctx.unmatched.append({"kind": "round", "test": "zero_stability", "series": 1,
                              "round": None, "reason": f"no rest of {need:g} s (static phase + "
                              f"{z.readings} readings {z.interval_s:g} s apart) in the stream"})
        return
    kz = ctx.sample_at_or_after(r.t_arrive_s + static)
    if s.earth_compensation == "measured":
        k0 = ctx.nearest(ctx.t(kz) - static)
        comp = float(ctx.c(kz) - ctx.c(k0)) / float(ctx.t(kz) - ctx.t(k0))
    elif s.earth_compensation == "computed":
        comp = _computed_comp(ctx.st, z.orientation)
    else:
        comp = 0.0
    ctx.comps.append(comp)
    t_zero = ctx.t(kz)
    for n in range(z.readings):
        kr = ctx.sample_at_or_after(t_zero + n * z.interval_s)
        ctx.rows.append(_row("zero_stability", 1, n + 1, math.nan, z.orientation, ctx, kz, kr,
                             math.nan, comp))
    ctx.used.add(q)
    ctx.cursor = q
    ctx.log.append(f"zero_stability: rest {q} from {r.t_start_s:.3f} s, zero at {t_zero:.3f} s")


def _wrap_deg(x: float) -> float:
    """``x`` folded into [−180, 180)."""
    return (x + 180.0) % 360.0 - 180.0


def _tilt_estimate(ctx: _Ctx) -> None:
    """The static multi-position test (``[tilt_estimate]``): N rests 360°/N apart.

    As the bench takes it (gonio.bench.session ``tilt_estimate``): at each position the
    zeroing sample ``settle_s`` after arrival, the reading ``dwell_s`` later; the counts are
    not Earth-rate compensated (the Earth rate is the signal); ``table_deg`` is the nominal
    position 360°·(i−1)/N. The first position is the first rest long enough from the cursor;
    the others are looked for at its level + 360°·(i−1)/N (modulo a turn), in order.
    """
    plan = ctx.proto.tilt_estimate
    need = plan.settle_s + plan.dwell_s
    ref = None
    q = ctx.cursor
    found = 0
    for i in range(plan.positions):
        x = 360.0 * i / plan.positions
        while q < len(ctx.rests):
            r = ctx.rests[q]
            long_enough = r.t_end_s + 1e-9 >= r.t_arrive_s + need
            if long_enough and (ref is None or
                                abs(_wrap_deg(r.level_deg - ref - x)) < ctx.pos_tol):
                break
            q += 1
        else:
            ctx.unmatched.append({"kind": "round", "test": "tilt_estimate", "series": 1,
                                  "round": i + 1, "rate_dps": plan.rate_dps,
                                  "orientation": plan.orientation,
                                  "reason": f"no rest of {need:g} s (settle + dwell) at "
                                            f"position {x:g}° in the stream"})
            continue
        if ref is None:
            ref = r.level_deg
        kz = ctx.sample_at_or_after(r.t_arrive_s + plan.settle_s)
        kr = ctx.sample_at_or_after(ctx.t(kz) + plan.dwell_s)
        ctx.rows.append(_row("tilt_estimate", 1, i + 1, plan.rate_dps, plan.orientation, ctx,
                             kz, kr, x, 0.0))
        ctx.used.add(q)
        ctx.cursor = q
        found += 1
        q += 1
    ctx.log.append(f"tilt_estimate: {found} of {plan.positions} positions")


def _rotation_series(ctx: _Ctx, item: RotationItem, series: int, nxt) -> None:
    """Match one series; ``nxt`` = (item, first round) of the next series, for look-ahead."""
    s = ctx.proto.session
    rounds = _series_rounds(item)
    z_rest = None          # rest of the current zero
    kz = None
    zero_x = None
    ref_level = None       # level of the series' first zero rest (position start_1)
    start1 = rounds[0][1]
    comp = None
    for idx, (i, start, stop) in enumerate(rounds):
        rezero = z_rest is None or item.rezero
        zl = None if ref_level is None else ref_level + (start - start1)
        delta = (stop - start) if rezero else (stop - zero_x)
        found = _find_pair(ctx, ctx.cursor, zl, delta, item.read_delay_s,
                           None if rezero else z_rest)
        # look-ahead: is the next expected round's pair found earlier?
        if found is not None:
            if idx + 1 < len(rounds):
                _, s2, p2 = rounds[idx + 1]
                nz = None if ref_level is None else ref_level + (s2 - start1)
                d2 = (p2 - s2) if item.rezero else (p2 - (zero_x if zero_x is not None
                                                         else start))
                alt = _find_pair(ctx, ctx.cursor, nz, d2, item.read_delay_s,
                                 None if item.rezero or z_rest is None else z_rest)
            elif nxt is not None:
                it2, (_, s2, p2) = nxt
                alt = _find_pair(ctx, ctx.cursor, None, p2 - s2, it2.read_delay_s, None)
            else:
                alt = None
            if alt is not None and alt[1] < found[1] and (delta != (alt and 0) or True) \
                    and abs(ctx.rests[alt[1]].level_deg - ctx.rests[found[1]].level_deg) \
                    >= ctx.pos_tol:
                found = None
        if found is None:
            ctx.unmatched.append({"kind": "round", "test": item.test, "series": series,
                                  "round": i, "rate_dps": item.rate_dps,
                                  "orientation": item.orientation,
                                  "reason": f"no rest at {stop:g}° (Δ {delta:g}°) after a rest "
                                            f"at the start position with {item.read_delay_s:g} s"
                                            " to the reading, before the next round's"})
            continue
        zq, rq = found
        if rezero or kz is None:
            r = ctx.rests[zq]
            kz = ctx.nearest(r.t_depart_s)
            z_rest, zero_x = zq, start
            if ref_level is None:
                ref_level = r.level_deg
        if comp is None:
            if s.earth_compensation == "computed":
                comp = _computed_comp(ctx.st, item.orientation)
            else:
                comp = _static_comp(ctx, zq, kz)
            if comp is None or not math.isfinite(comp):
                ctx.unmatched.append({"kind": "round", "test": item.test, "series": series,
                                      "round": i, "rate_dps": item.rate_dps,
                                      "orientation": item.orientation,
                                      "reason": f"the rest before the series is shorter than "
                                                f"the static phase ({s.static_s:g} s): no "
                                                "Earth-rate compensation"})
                comp, z_rest, kz, ref_level = None, None, None, None
                ctx.used.add(zq)
                ctx.cursor = rq
                continue
            ctx.comps.append(comp)
        rr = ctx.rests[rq]
        kr = ctx.sample_at_or_after(rr.t_arrive_s + item.read_delay_s)
        ctx.rows.append(_row(item.test, series, i, item.rate_dps, item.orientation, ctx, kz,
                             kr, stop - zero_x, comp))
        ctx.used.update((zq, rq))
        ctx.cursor = rq


def _apply_override(ctx: _Ctx, override: Sequence[dict], plan: dict) -> None:
    st, s = ctx.st, ctx.proto.session
    for o in override:
        key = (o["test"], int(o["series"]), int(o["round"]))
        cands = [k for k in plan if k[:3] == key and
                 ("rate_dps" not in o or k[3] == float(o["rate_dps"])) and
                 ("orientation" not in o or k[4] == o["orientation"])]
        if len(cands) != 1:
            raise GonioError(f"override {key} does not name exactly one round of the protocol "
                             f"({len(cands)} match; give rate_dps/orientation)", key=str(key))
        k = cands[0]
        table_deg, orient = plan[k]
        t0, t1 = float(o["t_zero_s"]), float(o["t_read_s"])
        if not (st.t_first <= t0 < t1 <= st.t_last):
            raise GonioError(f"override {key}: times outside the stream "
                             f"[{st.t_first:g}, {st.t_last:g}] s", key=str(key))
        kz, kr = ctx.nearest(t0), ctx.nearest(t1)
        if s.earth_compensation == "computed":
            comp = _computed_comp(st, orient)
        elif s.earth_compensation == "none":
            comp = 0.0
        else:
            k0 = ctx.nearest(t0 - s.static_s)
            comp = float(ctx.c(kz) - ctx.c(k0)) / \
                float(ctx.t(kz) - ctx.t(k0)) if kz > k0 else 0.0
            prev = [r for r in ctx.rows if (r["test"], r["series"], r["rate_dps"],
                                            r["orientation"]) == (k[0], k[1], k[3], k[4])]
            if prev:   # the series' own static phase when the matching found it
                p = prev[0]
                kz0, kr0 = ctx.nearest(p["t_zero_s"]), ctx.nearest(p["t_read_s"])
                comp = (float(ctx.c(kr0) - ctx.c(kz0)) - p["gyro_counts"]) / \
                    float(ctx.t(kr0) - ctx.t(kz0))
        ctx.rows = [r for r in ctx.rows if (r["test"], r["series"], r["round"], r["rate_dps"],
                                            r["orientation"]) != k]
        ctx.unmatched = [u for u in ctx.unmatched
                         if not (u.get("kind") == "round" and (u.get("test"), u.get("series"),
                                 u.get("round")) == key)]
        ctx.rows.append(_row(k[0], k[1], k[2], k[3], orient, ctx, kz, kr, table_deg, comp))
        ctx.log.append(f"override {k[0]} series {k[1]} round {k[2]}: zero {ctx.t(kz):.6f} s,"
                       f" read {ctx.t(kr):.6f} s")


def _plan_keys(proto: Protocol) -> dict:
    plan = {}
    if proto.zero_stability is not None:
        for n in range(proto.zero_stability.readings):
            plan[("zero_stability", 1, n + 1, math.nan, proto.zero_stability.orientation)] = \
                (math.nan, proto.zero_stability.orientation)
    te = proto.tilt_estimate
    if te is not None:
        for i in range(te.positions):
            plan[("tilt_estimate", 1, i + 1, te.rate_dps, te.orientation)] = \
                (360.0 * i / te.positions, te.orientation)
    for item in proto.items():
        for series in range(1, item.series + 1):
            x0 = item.rounds[0].start_deg
            for i, r in enumerate(item.rounds, 1):
                zero_x = r.start_deg if item.rezero else x0
                plan[(item.test, series, i, item.rate_dps, item.orientation)] = \
                    (r.stop_deg - zero_x, item.orientation)
    return plan


def reduce_stream(stream: "Stream | StreamFile | str | Path", protocol: Protocol, *, override: Iterable[dict] | None = None,
                  pos_tol_deg: float | None = None, min_rest_s: float = 0.5,
                  rate_threshold_dps: float | None = None,
                  window_s: float | None = None) -> Reduction:
    """Reduce a stream to readings as the protocol's acquisition would take them.

    Parameters
    ----------
    stream : Stream, StreamFile or path
        A stream in memory (:func:`gonio.formats.streams.read_stream`, or built), or a
        stream file (CSV or Parquet) read in bounded memory: one pass to find the
        rests (validating and indexing the file), then only the blocks around the
        rests' edges and the readings are read again.
    protocol : Protocol
        The planned sequence: zero stability (one long rest), then per item and
        series a static phase and rounds (see the module notes).
    override : iterable of dict, optional
        ``{test, series, round, t_zero_s, t_read_s}`` (+ ``rate_dps``,
        ``orientation`` to disambiguate): the operator's own zeroing and reading
        times for these rounds; they replace whatever the matching found.
    pos_tol_deg : float, optional
        Level tolerance of the matching; default 0.05° on the table encoder,
        1° on the gyro angle (Earth rate drifts it between rests).
    min_rest_s, rate_threshold_dps, window_s
        Passed to :func:`find_rests`.

    Returns
    -------
    Reduction

    Examples
    --------
    A 30° round at 10 Hz: 5 s static, 1 s move, reading 2 s after arrival.

    >>> from gonio.protocol import parse_protocol
    >>> p = parse_protocol({"protocol": {"name": "x"}, "session": {"static_s": 5.0},
    ...     "scale_factor": {"rest_s": 3.0, "read_delay_s": 2.0, "return_to_zero": False,
    ...                      "rounds": [{"stop_deg": 30.0}]}})
    >>> t = np.arange(0, 10, 0.1)
    >>> table = np.clip((t - 5.0) * 30.0, 0.0, 30.0)
    >>> counts = np.round(table * 3600 + 2.0 * t).astype(np.int64)   # 2 counts/s Earth rate
    >>> red = reduce_stream(Stream(t, counts, table), p)
    >>> red.readings[["test", "round", "time_s", "table_deg", "gyro_counts"]].to_dict("records")
    [{'test': 'scale_factor', 'round': 1, 'time_s': 3.0, 'table_deg': 30.0, 'gyro_counts': 108000.0}]
    """
    if isinstance(stream, (str, Path)):
        stream = StreamFile(stream)
    if isinstance(stream, Stream):
        st = _MemorySamples(stream)
        has_table = stream.table_deg is not None
        if len(st) < 3:
            raise GonioError("the stream has fewer than 3 samples", file=st.path)
        int_counts = np.issubdtype(np.asarray(stream.gyro_counts).dtype, np.integer)
    else:
        st = stream
        has_table = "table_deg" in st.columns
        int_counts = st.header.quantised
    k_sf = None
    if not has_table:
        from gonio.formats.readings import metadata_float
        k_sf = metadata_float(st.metadata, "nominal_scale_factor_counts_per_deg", file=st.path)
        _check_k(k_sf)
    rests, dt = rests_of(st, on_table=has_table, scale_factor_counts_per_deg=k_sf,
                         rate_threshold_dps=rate_threshold_dps, window_s=window_s,
                         min_rest_s=min_rest_s)
    n = len(st)
    if n < 3:
        raise GonioError("the stream has fewer than 3 samples", file=st.path)
    from gonio.formats.readings import metadata_bool
    quantised = metadata_bool(st.metadata, "counts_quantised", True, file=st.path) and int_counts
    tol = pos_tol_deg if pos_tol_deg is not None else (0.05 if has_table else 1.0)
    ctx = _Ctx(st, protocol, rests, tol, quantised, eps=1e-6 * dt)
    ctx.log.append(f"{n} samples, {len(rests)} rests "
                   f"({'table encoder' if has_table else 'gyro rate'})")
    if protocol.zero_stability is not None:
        _zero_stability(ctx)
    if protocol.tilt_estimate is not None:      # the bench's order: after zero stability
        _tilt_estimate(ctx)
    series_list = [(item, s) for item in protocol.items() for s in range(1, item.series + 1)]
    for j, (item, s) in enumerate(series_list):
        nxt = None
        if j + 1 < len(series_list):
            it2 = series_list[j + 1][0]
            r0 = it2.rounds[0]
            nxt = (it2, (1, r0.start_deg, r0.stop_deg))
        _rotation_series(ctx, item, s, nxt)
    plan = _plan_keys(protocol)
    if override:
        _apply_override(ctx, list(override), plan)
    for q, r in enumerate(rests):
        if q not in ctx.used:
            ctx.unmatched.append({"kind": "rest", "index": q, "t_start_s": r.t_start_s,
                                  "t_end_s": r.t_end_s, "level_deg": r.level_deg,
                                  "reason": "no round used this rest (a return/settle rest or "
                                            "an extra stop)"})
    order = {k[:3] + (None if isinstance(k[3], float) and math.isnan(k[3]) else k[3], k[4]): i
             for i, k in enumerate(plan)}
    cols = ["test", "series", "round", "rate_dps", "orientation", "time_s", "table_deg",
            "gyro_counts", "gyro_deg", "t_zero_s", "t_read_s"]
    df = pd.DataFrame(ctx.rows, columns=cols)
    if len(df):
        key = [order.get((r["test"], r["series"], r["round"],
                          None if math.isnan(r["rate_dps"]) else r["rate_dps"],
                          r["orientation"]), 10**9) for r in ctx.rows]
        df = df.iloc[np.argsort(key, kind="stable")].reset_index(drop=True)
        df["series"] = df["series"].astype(np.int64)
        df["round"] = df["round"].astype(np.int64)
    md = {k: v for k, v in st.metadata.items() if k not in ("counter_bits", "counter_signed")}
    if st.path is not None:
        md["source_stream"] = Path(st.path).name
    return Reduction(df, ctx.unmatched, ctx.log, rests, ctx.comps, md)
