"""Stream → readings: match the table's rests to the optical draft's rounds and take the
readings its acquisition would take.

Contents
========
=========================  ===================================================
:class:`Reduction`         readings, what could not be matched and why, a log
:func:`reduce_stream`      match rests to the protocol's rounds → readings
=========================  ===================================================

What an acquisition does on its external trigger (docs/formats.md#from-a-stream-to-readings, draft clause 7
preamble), reproduced from the continuous counter, on the rests and their refined edges
(:mod:`gonio.reduce.rests`):

1. **Zeroing and reading.** The zeroing is the sample nearest the departure; the reading is
   the first sample at or after arrival + ``read_delay_s``.
2. **Compensation.** ``measured``: the rate of the counter over the last
   ``static_s`` of rest before a series' first departure (draft clause 7
   preamble); ``computed``: K·Ω·axis from the metadata latitude; ``none``: 0.
3. **Readings.** ``counts(read) − counts(zero) − comp·(t_read − t_zero)``, rounded
   to whole counts when the counter is quantised (what the virtual bench and
   an acquisition module write).

Matching is by order and relative angle: each round needs a rest at its start
level followed (extra rests allowed in between) by a rest whose level differs by
``stop − start`` (``pos_tol_deg``). A round is skipped as missing when the next
expected round's pair is found before its own; every skipped round and every
rest no round used is reported with the reason. An operator can override the
matching round by round (:func:`gonio.specs.ogam_draft.override.read_override`).

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

from gonio.atomic import sha256_file
from gonio.errors import GonioError
from gonio.formats.metadata import metadata_bool, metadata_float
from gonio.formats.streams import Stream, StreamFile
from gonio.specs.ogam_draft.chamber import stream_temperature_at
from gonio.specs.ogam_draft.protocol import Protocol, RotationItem
from gonio.reduce.rests import MemorySamples, Rest, check_scale_factor, rests_of


@dataclass
class Reduction:
    """The result of :func:`reduce_stream`.

    Attributes
    ----------
    readings : pandas.DataFrame
        Readings-file columns (docs/formats.md#columns), plus ``t_zero_s`` and ``t_read_s``
        (stream times of the zeroing and reading samples; not written by
        :func:`gonio.specs.ogam_draft.readings.write_readings` unless kept as extra columns).
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


#: Times within this fraction of the sample interval are the same sample's: the stream's
#: samples lie on a grid of dt, and the virtual bench's mark moves a time by 1 ns
#: (gonio.formats.watermark), so a rest 1 ns short of its dwell, or a zeroing time 1 ns past
#: its sample, must still take that sample (at 1 kHz: 10 µs).
TIME_TOLERANCE_OF_DT = 0.01


@dataclass
class _Ctx:
    st: object               # the sample source (MemorySamples or StreamFile)
    proto: Protocol
    rests: list[Rest]
    pos_tol: float
    quantised: bool
    eps: float               # one sample's time tolerance (TIME_TOLERANCE_OF_DT of dt)
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
        if R[r].t_end_s + ctx.eps < R[r].t_arrive_s + read_need_s:
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
        if r.t_end_s + ctx.eps >= r.t_arrive_s + need:
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

    As the bench takes it (gonio.specs.ogam_draft.bench.session ``tilt_estimate``): at each position the
    zeroing sample ``settle_s`` after arrival, the reading ``dwell_s`` later; the counts are
    not Earth-rate compensated (the Earth rate is the signal); ``table_deg`` is the nominal
    position, the plan's i-th (``plan.order_deg``: opposite pairs). The first position is
    the first rest long enough from the cursor; the others are looked for at its level +
    their position (modulo a turn), in order.
    """
    plan = ctx.proto.tilt_estimate
    need = plan.settle_s + plan.dwell_s
    ref = None
    q = ctx.cursor
    found = 0
    for i, x in enumerate(plan.order_deg):
        while q < len(ctx.rests):
            r = ctx.rests[q]
            long_enough = r.t_end_s + ctx.eps >= r.t_arrive_s + need
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
        for i, x in enumerate(te.order_deg):
            plan[("tilt_estimate", 1, i + 1, te.rate_dps, te.orientation)] = (x, te.orientation)
    for item in proto.items():
        for series in range(1, item.series + 1):
            x0 = item.rounds[0].start_deg
            for i, r in enumerate(item.rounds, 1):
                zero_x = r.start_deg if item.rezero else x0
                plan[(item.test, series, i, item.rate_dps, item.orientation)] = \
                    (r.stop_deg - zero_x, item.orientation)
    return plan


def _chamber_column(st, df: pd.DataFrame) -> None:
    """A stream that logs the chamber's temperature (its ``temperature_c`` column, blank
    cells allowed) gives each reduced reading the logged temperature at its ``time_s``
    (:func:`gonio.specs.ogam_draft.chamber.stream_temperature_at`) as the mean of the
    logged temperature at its zeroing and at its reading (the stream's clock; the round's
    trapezoid mean): the readings' ``temperature_c`` column K's chamber line reads; nothing
    where it logs none."""
    has = (st.st.temperature_c is not None) if isinstance(st, MemorySamples) else \
        "temperature_c" in st.columns
    if not has or not len(df):
        return
    t = np.concatenate([df["t_zero_s"].to_numpy(dtype=float),
                        df["t_read_s"].to_numpy(dtype=float)])
    if not np.isfinite(t).any():
        return
    at = stream_temperature_at(st, np.where(np.isfinite(t), t, np.nanmax(t)))
    if at is not None:
        df["temperature_c"] = np.round(0.5 * (at[:len(df)] + at[len(df):]), 9)


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
        Passed to :func:`gonio.reduce.rests.find_rests`.

    Returns
    -------
    Reduction

    Examples
    --------
    A 30° round at 10 Hz: 5 s static, 1 s move, reading 2 s after arrival.

    >>> from gonio.specs.ogam_draft.protocol import parse_protocol
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
        st = MemorySamples(stream)
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
        k_sf = metadata_float(st.metadata, "nominal_scale_factor_counts_per_deg", file=st.path)
        check_scale_factor(k_sf)
    rests, dt = rests_of(st, on_table=has_table, scale_factor_counts_per_deg=k_sf,
                         rate_threshold_dps=rate_threshold_dps, window_s=window_s,
                         min_rest_s=min_rest_s)
    n = len(st)
    if n < 3:
        raise GonioError("the stream has fewer than 3 samples", file=st.path)
    quantised = metadata_bool(st.metadata, "counts_quantised", True, file=st.path) and int_counts
    tol = pos_tol_deg if pos_tol_deg is not None else (0.05 if has_table else 1.0)
    ctx = _Ctx(st, protocol, rests, tol, quantised, eps=TIME_TOLERANCE_OF_DT * dt)
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
    _chamber_column(st, df)
    md = {k: v for k, v in st.metadata.items() if k not in ("counter_bits", "counter_signed")}
    if st.path is not None:
        md["source_stream"] = Path(st.path).name
        # the stream by its bytes: the records know a stream and its readings as one
        # measurement (gonio.records.services.readings_used_by)
        md["source_stream_sha256"] = sha256_file(st.path)
    return Reduction(df, ctx.unmatched, ctx.log, rests, ctx.comps, md)
