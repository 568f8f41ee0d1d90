"""Run a protocol on a virtual bench: readings file, truth, optional stream.

:func:`plan_session` turns a :class:`~gonio.specs.ogam_draft.protocol.Protocol` into blocks of
table motion (one block per series and condition; the zero-stability test is
one block), with the zeroing and reading instants of each round. :func:`run_session`
simulates the instrument through every block on a uniform grid
(``bench.sample_rate_hz``), chunk by chunk, and takes the readings exactly as
an operator's acquisition would: pulse counts since zeroing, Earth-rate
compensated by the instrument (measured in a static phase before each series,
draft clause 7 preamble, or computed from latitude and axis). It then reruns the
same session with every random term off to give, for each reading, the
instrument's noise-free systematic deviation (``truth.json``).

Order of the items: 7.3 (right after the warm-up, as 7.3 asks), the optional
in-situ tilt estimate (``[tilt_estimate]``, uncompensated rests), 7.1, 7.4/7.5,
7.6, 7.7. The table is re-pointed between blocks instantly (no time passes).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from gonio import __version__
from gonio.atomic import active_stage, check_output_dir, output_dir, write_text
from gonio.specs.ogam_draft.bench.config import Bench
from gonio.specs.ogam_draft.bench.instrument import (Integrator, counts_from_angle, deterministic_signature,
                                    geometry, harmonic_sum_arcsec, rate_nonlinearity)
from gonio.specs.ogam_draft.static_record import StaticRecord
from gonio.physics.earth import NAMED_AXES, axis_enu, earth_rate_enu
from gonio.specs.ogam_draft.bench.config import check_counter
from gonio.errors import GonioError
from gonio.units import arcsec_to_deg, deg_to_arcsec
from gonio.physics.kinematics import Timeline
from gonio.specs.ogam_draft.protocol import Protocol, RotationItem

CHUNK = 1 << 20
#: Most samples kept of a captured record (the 7.3 rest for the Allan analysis): longer
#: records are decimated — the counter is cumulative, so every d-th sample is an exact
#: angle record at f_s/d (Allan deviation from τ = d/f_s up) — bounding memory for any
#: session length (16 bytes a sample: 64 MiB).
MAX_RECORD_SAMPLES = 1 << 22


@dataclass
class PlannedReading:
    """One reading the acquisition will take."""

    test: str
    series: int
    round: int
    rate_dps: float
    orientation: str
    k_read: int            # grid index of the reading
    k_zero: int            # grid index of the zeroing it refers to
    table_deg: float       # the standard's (indicated) angle since zeroing; NaN for 7.3
    start_deg: float = math.nan   # absolute table position at zeroing (equal-division only)


@dataclass
class Block:
    """A stretch of the session in one table orientation, with its own zeroings."""

    label: str
    orientation: str
    timeline: Timeline
    k_start: int
    k_end: int             # exclusive
    k_static: tuple[int, int] | None
    readings: list[PlannedReading] = field(default_factory=list)
    compensate: bool = True    # False: readings are raw counts (the tilt estimate's rests)
    moves: list = field(default_factory=list)   # (t_start, t_end) of every move, s


def _grid(t: float, dt: float) -> int:
    """The first grid index at or after time t (robust to rounding)."""
    return int(math.ceil(t / dt - 1e-9))


class _Planner:
    def __init__(self, protocol: Protocol, bench: Bench, rng: np.random.Generator | None):
        self.p, self.b, self.rng = protocol, bench, rng
        self.dt = 1.0 / bench.sample_rate_hz
        self.k = 0
        self.blocks: list[Block] = []
        self._periodic: dict[float, float] = {}

    def true_position(self, x_deg: float) -> float:
        """True angle of the table when it indicates ``x_deg`` (indicated − true = error)."""
        tab = self.b.table
        err = self._periodic.get(x_deg)
        if err is None:     # the periodic error of each stop is computed once per session
            err = self._periodic[x_deg] = float(
                harmonic_sum_arcsec(np.array([x_deg]), tab.positioning_harmonics)[0])
        if tab.positioning_random_arcsec and self.rng is not None:
            err += tab.positioning_random_arcsec * float(self.rng.standard_normal())
        return x_deg - arcsec_to_deg(err)

    @staticmethod
    def _move(blk: Block, tl: Timeline, to_deg: float, rate_dps: float, accel_dps2: float) -> float:
        """``tl.move``, recording the move's time span in the block (for :func:`_motion`)."""
        t_a = tl.end_s
        arrive = tl.move(to_deg, rate_dps, accel_dps2)
        if arrive > t_a:
            blk.moves.append((t_a, arrive))
        return arrive

    def _dwell_to_grid(self, tl: Timeline) -> int:
        k = _grid(tl.end_s, self.dt)
        tl.dwell(max(0.0, k * self.dt - tl.end_s))
        return k

    def _new_block(self, label: str, orientation: str, start_x: float) -> tuple[Block, Timeline]:
        tl = Timeline(start_angle_deg=self.true_position(start_x), t0_s=self.k * self.dt)
        s = self.p.session
        k_static = None
        if s.earth_compensation == "measured":
            tl.dwell(s.static_s)
            k_static = (self.k, self._dwell_to_grid(tl))
        blk = Block(label, orientation, tl, self.k, self.k, k_static)
        return blk, tl

    def _close(self, blk: Block, tl: Timeline) -> None:
        blk.k_end = self._dwell_to_grid(tl) + 1
        self.k = blk.k_end
        self.blocks.append(blk)

    def zero_stability(self) -> None:
        z = self.p.zero_stability
        blk, tl = self._new_block("zero_stability", z.orientation, 0.0)
        k_zero = self._dwell_to_grid(tl)
        for n in range(z.readings):
            tl.dwell(z.interval_s if n else 0.0)
            kr = self._dwell_to_grid(tl)
            blk.readings.append(PlannedReading("zero_stability", 1, n + 1, 60.0, z.orientation,
                                               kr, k_zero, math.nan))
        self._close(blk, tl)

    def tilt_estimate(self, plan) -> None:
        """Static multi-position block (``[tilt_estimate]``): rest at N equally spaced
        positions, in the plan's order (``plan.order_deg``); each reading is the
        uncompensated count over one dwell."""
        tab = self.b.table
        tl = Timeline(start_angle_deg=self.true_position(0.0), t0_s=self.k * self.dt)
        blk = Block(f"tilt_estimate {plan.orientation}", plan.orientation, tl, self.k, self.k,
                    None, compensate=False)
        rate = plan.rate_dps * (1.0 + tab.rate_error_rel)
        for i, x in enumerate(plan.order_deg):
            if i:
                self._move(blk, tl, self.true_position(x), rate, tab.accel_dps2)
            tl.dwell(plan.settle_s)
            k0 = self._dwell_to_grid(tl)
            tl.dwell(plan.dwell_s)
            k1 = self._dwell_to_grid(tl)
            blk.readings.append(PlannedReading("tilt_estimate", 1, i + 1, plan.rate_dps,
                                               plan.orientation, k1, k0, x))
        self._close(blk, tl)

    def rotation(self, item: RotationItem, series: int) -> None:
        s, tab = self.p.session, self.b.table
        rate = item.rate_dps * (1.0 + tab.rate_error_rel)
        back = s.return_rate_dps * (1.0 + tab.rate_error_rel)
        first = item.rounds[0].start_deg
        blk, tl = self._new_block(f"{item.test} {item.orientation} {item.rate_dps:g} dps "
                                  f"series {series}", item.orientation, first)
        pos, k_zero, zero_x = first, None, first
        for i, r in enumerate(item.rounds, 1):
            if r.start_deg != pos:
                self._move(blk, tl, self.true_position(r.start_deg), back, tab.accel_dps2)
                tl.dwell(s.settle_s)
                pos = r.start_deg
            if k_zero is None or item.rezero:
                k_zero, zero_x = self._dwell_to_grid(tl), pos
            depart = tl.end_s
            arrive = self._move(blk, tl, self.true_position(r.stop_deg), rate, tab.accel_dps2)
            pos = r.stop_deg
            if r.max_rotation_s is not None and arrive - depart > r.max_rotation_s + 1e-9:
                raise GonioError(
                    f"the bench table needs {arrive - depart:.2f} s for round {i} of {item.test} "
                    f"(limit {r.max_rotation_s} s): raise its accel_dps2", key=f"{item.test}.rounds")
            k_read = _grid(arrive + item.read_delay_s, self.dt)
            limit = item.max_time_to_reading_s
            if limit is not None and (k_read - k_zero) * self.dt > limit + 1e-9:
                raise GonioError(f"round {i} of {item.test}: reading {(k_read - k_zero) * self.dt:.1f} s "
                                 f"after zeroing exceeds {limit} s (Annex A.1)",
                                 key=f"{item.test}.read_delay_s")
            tl.dwell(max(item.rest_s, k_read * self.dt - arrive + self.dt))
            blk.readings.append(PlannedReading(item.test, series, i, item.rate_dps,
                                               item.orientation, k_read, k_zero,
                                               r.stop_deg - zero_x))
            if item.return_to_zero:
                self._move(blk, tl, self.true_position(r.start_deg), back, tab.accel_dps2)
                tl.dwell(s.settle_s)
                pos = r.start_deg
        self._close(blk, tl)

    def equal_division(self, p, series: int) -> None:
        """IEC 62047-20 Annex A.3: from each start x_k = k·360°/n, zero both, step m times by Δ.

        Between starts the table is re-pointed instantly (like between blocks); each
        start has its own static phase when the compensation is measured.
        """
        tab = self.b.table
        rate = p.rate_dps * (1.0 + tab.rate_error_rel)
        for k, x0 in enumerate(p.start_deg.tolist()):
            blk, tl = self._new_block(f"equal_division start {x0:g} series {series}", p.orientation, x0)
            k_zero = self._dwell_to_grid(tl)
            for j in range(1, p.points + 1):
                arrive = self._move(blk, tl, self.true_position(x0 + j * p.step_deg), rate,
                                    tab.accel_dps2)
                k_read = _grid(arrive + p.read_delay_s, self.dt)
                tl.dwell(max(p.rest_s, k_read * self.dt - arrive + self.dt))
                blk.readings.append(PlannedReading("equal_division", series, k + 1, p.rate_dps,
                                                   p.orientation, k_read, k_zero, j * p.step_deg,
                                                   start_deg=x0))
            self._close(blk, tl)


def plan_session(protocol: Protocol, bench: Bench, rng: np.random.Generator | None) -> list[Block]:
    """Blocks of motion with zeroing and reading instants, in the order the items run."""
    pl = _Planner(protocol, bench, rng)
    if protocol.zero_stability is not None:
        pl.zero_stability()
    if protocol.tilt_estimate is not None:
        pl.tilt_estimate(protocol.tilt_estimate)
    for item in protocol.items():
        for series in range(1, item.series + 1):
            pl.rotation(item, series)
    eda = protocol.equal_division
    if eda is not None:
        for series in range(1, eda.repeats + 1):
            pl.equal_division(eda, series)
    return pl.blocks


@dataclass
class _Run:
    counts: np.ndarray       # compensated counts since zeroing, per reading
    true_deg: np.ndarray     # true table angle turned since zeroing, per reading
    comp_counts_s: list      # per block
    records: dict = field(default_factory=dict)   # label -> (time_s, counts) of captured blocks


def _motion(blk: Block, t: np.ndarray):
    """Table angle and rate at the grid times ``t`` of ``blk``, on runs of samples.

    Returns ``(theta_u, rate_u, rep)``: value j holds for ``rep[j]`` consecutive
    samples. A sample inside a move (the planner's recorded spans, ends
    included) is its own run; the samples between two moves are one run, since
    the table rests there at one angle (every rest segment starts at the angle
    the previous segment ended at, and its angle is that start plus 0·sign).
    The closed-form timeline is evaluated at one time per run, so the values are
    those of a per-sample evaluation, bit for bit, at a fraction of the cost.
    """
    n = t.size
    moving = np.zeros(n, dtype=bool)
    if blk.moves:
        span = np.asarray(blk.moves, dtype=np.float64)
        i0 = np.searchsorted(t, span[:, 0], side="left")
        i1 = np.searchsorted(t, span[:, 1], side="right")
        for a, b in zip(i0.tolist(), i1.tolist()):
            if b > a:
                moving[a:b] = True
    start = np.ones(n, dtype=bool)
    start[1:] = moving[1:] | moving[:-1]
    idx = np.flatnonzero(start)
    rep = np.diff(np.append(idx, n))
    te = t[idx]
    return (*blk.timeline.angle_rate(te), rep)


@dataclass
class _Variant:
    """One instrument run through the session (the noisy one, the noise-free rerun)."""

    bench: Bench
    rng: np.random.Generator | None
    stream: object = None
    capture: frozenset = frozenset()
    dither_key: int = 0


def _counter(k, phi, inst, zeros, phi_at, comp, dt, dither_key):
    """Pulse counter at grid indices k: angle plus the angle-position error
    g(φ) − g(0) of the compensated angle φ since the last zeroing (draft 4.2;
    nil at the zeroing itself), times K, floored."""
    g = np.zeros(k.size)
    g0 = float(harmonic_sum_arcsec(np.zeros(1), inst.position_harmonics)[0])
    if inst.position_harmonics and zeros.size:
        iz = np.searchsorted(zeros, k, side="right") - 1
        ok = iz >= 0
        if ok.any():
            kz = zeros[iz[ok]]
            phz = np.array([phi_at.get(z, np.nan) for z in zeros.tolist()])[iz[ok]]
            since = (phi[ok] - phz
                     - comp / inst.nominal_scale_factor_counts_per_deg * (k[ok] - kz) * dt)
            g[ok] = harmonic_sum_arcsec(since, inst.position_harmonics) - g0
    return counts_from_angle(phi + arcsec_to_deg(g), inst, k, dither_key)


def _simulate(blocks: list[Block], bench: Bench, protocol: Protocol,
              rng: np.random.Generator | None, stream=None,
              capture: frozenset = frozenset(), dither_key: int = 0) -> _Run:
    return _simulate_many(blocks, protocol, [_Variant(bench, rng, stream, capture,
                                                      dither_key)])[0]


def _simulate_many(blocks: list[Block], protocol: Protocol, variants: list[_Variant]) -> list[_Run]:
    """Run the instruments of ``variants`` through the session in one pass.

    The variants share the bench set-up (table, site, geometry) and differ at most
    in the instrument's random terms (``Bench.random_off``): the table motion and
    the deterministic rate terms are computed once per chunk and shared; each
    variant integrates them with its own noise, counter and compensation.
    """
    bench0 = variants[0].bench
    dt = 1.0 / bench0.sample_rate_hz
    integs = [Integrator(v.bench.instrument, v.bench.sample_rate_hz, protocol.session.warm_up_s,
                         v.rng) for v in variants]
    readings = [r for b in blocks for r in b.readings]
    nv = len(variants)
    out_counts = [np.empty(len(readings)) for _ in range(nv)]
    out_true = np.empty(len(readings))
    comps: list[list] = [[] for _ in range(nv)]
    captured: list[dict] = [{} for _ in range(nv)]
    measured = protocol.session.earth_compensation == "measured"
    j = 0
    geoms: dict = {}
    for blk in blocks:
        if blk.orientation not in geoms:
            geoms[blk.orientation] = geometry(bench0, blk.orientation)
            for v in variants[1:]:
                if geometry(v.bench, blk.orientation) != geoms[blk.orientation]:
                    raise ValueError("variants of a session must share the set-up")
        geom = geoms[blk.orientation]
        for integ in integs:
            integ.start_block()
        need = set()
        if blk.k_static:
            need.update(blk.k_static)
        for r in blk.readings:
            need.update((r.k_read, r.k_zero))
        zeros = np.array(sorted({r.k_zero for r in blk.readings}), dtype=np.int64)
        theta_at: dict = {}
        phi_at: list[dict] = [{} for _ in range(nv)]
        comp = [0.0] * nv
        if protocol.session.earth_compensation == "computed" and blk.compensate:
            # The operator's computed compensation, possibly with a wrong latitude or
            # azimuth (protocol session.compensation_*; :mod:`gonio.specs.ogam_draft.compensation`).
            ss = protocol.session
            lat = (bench0.latitude_deg if ss.compensation_latitude_deg is None
                   else ss.compensation_latitude_deg)
            az, el = NAMED_AXES[blk.orientation]
            w = np.degrees(earth_rate_enu(lat)) @ axis_enu(
                (az + ss.compensation_azimuth_error_deg, el))
            comp = [v.bench.instrument.nominal_scale_factor_counts_per_deg * float(w)
                    for v in variants]
        need_arr = np.array(sorted(need), dtype=np.int64)
        for a in range(blk.k_start, blk.k_end, CHUNK):
            b = min(a + CHUNK, blk.k_end)
            k = np.arange(a, b)
            t = k * dt
            theta_u, rate_u, rep = _motion(blk, t)
            theta = np.repeat(theta_u, rep)
            dets: dict = {}
            sel = need_arr[(need_arr >= a) & (need_arr < b)]
            for kk, th in zip(sel.tolist(), theta[sel - a].tolist()):
                theta_at[kk] = th
            table_out = None
            for m, (v, integ) in enumerate(zip(variants, integs)):
                sig = deterministic_signature(v.bench.instrument)
                if sig not in dets:
                    dets[sig] = integ.rates(t, theta_u, rate_u, rep, geom)
                # every sample's angle only where a record or stream takes them all
                whole = v.stream is not None or blk.label in v.capture
                phi = integ.integrate(dets[sig], theta, at=None if whole else sel - a)
                inst = v.bench.instrument
                for kk, ph in zip(sel.tolist(), (phi[sel - a] if whole else phi).tolist()):
                    phi_at[m][kk] = ph
                if blk.k_static and a <= blk.k_static[1] < b and measured:
                    k0, k1 = blk.k_static
                    comp[m] = (_counter(np.array(blk.k_static),
                                        np.array([phi_at[m][k0], phi_at[m][k1]]), inst, zeros,
                                        phi_at[m], comp[m], dt, v.dither_key)
                               @ np.array([-1.0, 1.0])) / ((k1 - k0) * dt)
                if v.stream is not None or blk.label in v.capture:
                    keep = None
                    if blk.label in v.capture:
                        dec = -(-(blk.k_end - blk.k_start) // MAX_RECORD_SAMPLES)
                        keep = slice((blk.k_start - a) % dec, None, dec)
                    # the counter is element-wise in (k, φ): without a stream only the
                    # kept samples are counted (the same values, a fraction of the work)
                    at = keep if v.stream is None and keep is not None else slice(None)
                    c = _counter(k[at], phi[at], inst, zeros, phi_at[m], comp[m], dt,
                                 v.dither_key)
                    if keep is not None:
                        captured[m].setdefault(blk.label, []).append(
                            (t[keep], c if at is keep else c[keep]))
                    if v.stream is not None:
                        if table_out is None:
                            table_out = np.repeat(theta_u + arcsec_to_deg(harmonic_sum_arcsec(
                                theta_u, bench0.table.positioning_harmonics)), rep)
                        v.stream(t, c, table_out)
        kk = np.array(sorted(need), dtype=np.int64)
        for m, v in enumerate(variants):
            inst = v.bench.instrument
            comps[m].append(comp[m])
            cc = _counter(kk, np.array([phi_at[m][x] for x in kk.tolist()]), inst, zeros,
                          phi_at[m], comp[m], dt, v.dither_key)
            count_at = dict(zip(kk.tolist(), cc.tolist()))
            for i, r in enumerate(blk.readings):
                raw = count_at[r.k_read] - count_at[r.k_zero] - comp[m] * (r.k_read - r.k_zero) * dt
                out_counts[m][j + i] = float(np.rint(raw)) if inst.quantisation else raw
        for i, r in enumerate(blk.readings):
            out_true[j + i] = theta_at[r.k_read] - theta_at[r.k_zero]
        j += len(blk.readings)
    runs = []
    for m in range(nv):
        records = {lab: (np.concatenate([x[0] for x in v]), np.concatenate([x[1] for x in v]))
                   for lab, v in captured[m].items()}
        runs.append(_Run(out_counts[m], out_true, comps[m], records))
    return runs


def mount_scale_factor_counts_per_deg(bench: Bench, rate_dps: float) -> float:
    """The true scale factor as seen through the mount at a table rate: K (1+ε(ω cos ψ)) cos ψ.

    The scale-factor calibration (7.1) measures this product; the tilt's cos ψ is
    absorbed by it (the rigid-body reading of Annex A.4.2).
    """
    inst = bench.instrument
    c = math.cos(math.radians(inst.tilt_deg))
    eps = float(rate_nonlinearity(np.array([rate_dps * c]), inst)[0])
    return inst.true_scale_factor_counts_per_deg * (1.0 + eps) * c


@dataclass
class SessionResult:
    """What a virtual session produced: the readings (as a laboratory records them) and the truth."""

    readings: pd.DataFrame
    metadata: dict
    truth: dict
    static_record: "StaticRecord | None" = None


def session_metadata(protocol: Protocol, bench: Bench, seed: int) -> dict:
    """The metadata lines a bench run writes (instrument, site, protocol, seed; docs/formats.md#metadata)."""
    inst = bench.instrument
    md = {
        "instrument": inst.name,
        "serial": inst.serial,
        "manufacturer": inst.manufacturer,
        # the instrument's type (identity, docs/formats.md#metadata-keys); never its
        # temperature coefficients, which are the bench's truth
        "gyro_type": inst.type,
        "nominal_scale_factor_counts_per_deg": repr(inst.nominal_scale_factor_counts_per_deg),
        "latitude_deg": repr(bench.latitude_deg),
        # the chamber's temperature as logged: the reference plus the bench's deviation
        "temperature_c": repr(protocol.conditions.temperature_c + bench.chamber_deviation_c),
        "table": bench.table.name,
        "table_mpe_arcsec": repr(bench.table.mpe_arcsec),
        "table_accel_dps2": repr(bench.table.accel_dps2),
        "tilt_bound_deg": repr(protocol.annex_a.tilt_bound_deg),
        "operator": "virtual bench",
        "protocol": protocol.name,
        "bench": bench.name,
        "seed": str(seed),
        "generator": f"gonio {__version__}",
    }
    if not inst.quantisation:
        md["counts_quantised"] = "false"
    return md


@dataclass(frozen=True)
class SessionEstimate:
    """What a session will cost before it is simulated."""

    samples: int            # samples of one pass (the noise-free rerun doubles the work)
    duration_s: float
    memory_bytes: float     # peak, roughly: the chunk buffers plus the captured record
    seconds: float          # rough run time at ~10 million samples a second


#: Samples simulated a second of CPU time (the noisy run and its noise-free rerun
#: together), one core of the 2-core development machine: the draft's protocol took
#: 3.7 s (RLG) and 2.1 s (FOG) for 2.4·10⁷ samples, a 6 h zero-stability variant 5.4 s
#: and 3.9 s for 4.2·10⁷ (benchmarks/bench_long_session.py measures more).
SIMULATED_SAMPLES_PER_S: float = 8e6
#: Fixed cost of a simulation (planning, tables), s.
SIMULATE_OVERHEAD_S: float = 0.5


def estimate_session(blocks: list[Block], bench: Bench, protocol: Protocol) -> SessionEstimate:
    """Estimate a planned session's size and refuse it beyond the stated limits.

    Limits (:mod:`gonio.limits`): ``GONIO_MAX_SAMPLES`` samples per pass,
    ``GONIO_MAX_SESSION_S`` seconds of session, ``GONIO_MAX_RUN_S`` seconds of
    estimated computing (``samples / SIMULATED_SAMPLES_PER_S`` plus a fixed
    overhead, CPU time of one core; within a factor 2 of the measured time, see
    :data:`SIMULATED_SAMPLES_PER_S`; the message names the protocol section that
    contributes most samples and the bench's ``sample_rate_hz``); protocol rates above the table's
    ``max_rate_dps`` are refused too. Memory does not grow with the session (chunks of
    :data:`CHUNK` samples, captured records decimated to :data:`MAX_RECORD_SAMPLES`).
    """
    from gonio.limits import check, limit

    if not any(b.readings for b in blocks):
        raise GonioError("the protocol plans no reading (no test section): nothing to simulate",
                         file=protocol.path or None, key="protocol")
    n = int(sum(b.k_end - b.k_start for b in blocks))
    dur = n / bench.sample_rate_hz
    for it in protocol.items():
        if it.rate_dps > bench.table.max_rate_dps:
            raise GonioError(f"{it.test} at {it.rate_dps:g} °/s is faster than the table's "
                             f"max_rate_dps {bench.table.max_rate_dps:g} °/s",
                             file=protocol.path or None, key=f"{it.test}.rate_dps")
    est = SessionEstimate(n, dur, CHUNK * 8.0 * 24 + MAX_RECORD_SAMPLES * 16.0,
                          SIMULATE_OVERHEAD_S + n / SIMULATED_SAMPLES_PER_S)
    where = f"protocol {protocol.name} on bench {bench.name}"
    check("GONIO_MAX_SESSION_S", dur, f"{where}: the session lasts", unit="s")
    check("GONIO_MAX_SAMPLES", n, f"{where} at {bench.sample_rate_hz:g} Hz: the session needs",
          unit="samples")
    lim = limit("GONIO_MAX_RUN_S")
    if est.seconds > lim:
        per: dict[str, int] = {}
        for b in blocks:
            section = b.label.split()[0] if b.label else "session"
            per[section] = per.get(section, 0) + int(b.k_end - b.k_start)
        top = max(per, key=per.get)
        raise GonioError(
            f"{where}: simulating {n:.4g} samples takes about {est.seconds:.4g} s, over the "
            f"limit of {lim:.4g} s (set GONIO_MAX_RUN_S to raise it); most samples come from "
            f"[{top}] ({per[top] / n:.0%}) at the bench's sample_rate_hz "
            f"{bench.sample_rate_hz:g}", file=protocol.path or None, key=top)
    return est


def run_session(protocol: Protocol, bench: Bench, seed: int = 0, stream=None) -> SessionResult:
    """Execute ``protocol`` on ``bench``; same seed, same readings (bit for bit).

    ``stream``, if given, is called per chunk as ``stream(time_s, counts, table_deg)``
    with the unwrapped pulse counter (float64 holding integers) of the noisy run.
    """
    ss = np.random.SeedSequence(seed)
    rng_table, rng_inst = (np.random.default_rng(s) for s in ss.spawn(2))
    check_counter(bench)
    blocks = plan_session(protocol, bench, rng_table)
    estimate_session(blocks, bench, protocol)      # refuse what exceeds the stated limits
    # The instrument at the chamber's temperature (the bench itself at the reference).
    bench_t = bench.at_chamber_temperature()
    # The noisy run and its noise-free rerun (truth) in one pass over the session.
    run, nf = _simulate_many(blocks, protocol, [
        _Variant(bench_t, rng_inst, stream, frozenset({"zero_stability"}),
                 int(ss.generate_state(1, np.uint64)[0])),
        _Variant(bench_t.random_off(), None)])
    rows = [r for b in blocks for r in b.readings]
    dt = 1.0 / bench.sample_rate_hz
    df = pd.DataFrame({
        "test": [r.test for r in rows],
        "series": [r.series for r in rows],
        "round": [r.round for r in rows],
        "rate_dps": [r.rate_dps for r in rows],
        "orientation": [r.orientation for r in rows],
        "time_s": [round((r.k_read - r.k_zero) * dt, 9) for r in rows],
        "table_deg": [r.table_deg for r in rows],
        "gyro_counts": run.counts,
        "gyro_deg": np.nan,
    })
    df.loc[df["test"] == "zero_stability", "rate_dps"] = np.nan
    eda_rows = (df["test"] == "equal_division").to_numpy()
    if eda_rows.any():
        # Equal division: the instrument's own indicated angle (its nominal K), as the
        # eda reader expects; the scale-factor error then shows in the goniometer curve.
        df["start_deg"] = [r.start_deg for r in rows]
        df.loc[eda_rows, "gyro_deg"] = run.counts[eda_rows] / bench.instrument.nominal_scale_factor_counts_per_deg
        df.loc[eda_rows, "gyro_counts"] = np.nan
    sf_rate = protocol.scale_factor.rate_dps if protocol.scale_factor else 60.0
    k_mount = mount_scale_factor_counts_per_deg(bench, sf_rate)        # at the reference
    k_mount_t = mount_scale_factor_counts_per_deg(bench_t, sf_rate)    # in the chamber
    sf = df["test"].to_numpy() == "scale_factor"
    k_cal_nf = float(np.mean(nf.counts[sf] / df["table_deg"].to_numpy()[sf])) if sf.any() \
        else k_mount_t
    # E's angles come from counts through a K taken in the same chamber: its temperature
    # factor divides out, so the deviation as mounted uses the chamber's K.
    sys_mount = deg_to_arcsec(nf.counts / k_mount_t - run.true_deg)
    sys_cal = deg_to_arcsec(nf.counts / k_cal_nf - run.true_deg)
    per = []
    for i, r in enumerate(rows):
        per.append({
            "test": r.test, "series": r.series, "round": r.round,
            "rate_dps": r.rate_dps, "orientation": r.orientation,
            "time_s": df["time_s"].iat[i],
            "table_deg": None if math.isnan(r.table_deg) else r.table_deg,
            "true_table_deg": float(run.true_deg[i]),
            # tilt_estimate rows: table_deg is the rest position, true_table_deg the angle
            # turned during the dwell (0): no table error to report.
            "table_error_arcsec": None if math.isnan(r.table_deg) or r.test == "tilt_estimate"
            else float(deg_to_arcsec(r.table_deg - run.true_deg[i])),
            "noise_free_counts": float(nf.counts[i]),
            "systematic_deviation_arcsec": float(sys_mount[i]),
            "systematic_deviation_calibrated_arcsec": float(sys_cal[i]),
        })
    truth = {
        "generator": f"gonio {__version__}",
        "seed": seed,
        "protocol": protocol.name,
        "bench": bench.to_dict(),
        "scale_factor_through_mount_counts_per_deg": k_mount,
        "scale_factor_through_mount_at_chamber_counts_per_deg": k_mount_t,
        "scale_factor_noise_free_calibrated_counts_per_deg": k_cal_nf,
        "definitions": {
            "scale_factor_through_mount_counts_per_deg": "K(1+eps(w cos psi)) cos psi of the "
            "instrument at the protocol's reference temperature (the measurand)",
            "scale_factor_through_mount_at_chamber_counts_per_deg": "the same at the chamber's "
            "temperature: K(1 + alpha_K dT), dT = bench.chamber_deviation_c",
            "systematic_deviation_arcsec": "noise-free indicated angle (compensated counts of a rerun "
            "with every random term off, divided by the scale factor through the mount at the "
            "chamber's temperature) minus the true table angle turned since zeroing",
            "systematic_deviation_calibrated_arcsec": "the same with the scale factor the noise-free "
            "rerun's own 7.1 rounds give (what the draft's procedure finds without noise)",
        },
        "earth_compensation_counts_per_s": [float(c) for c in run.comp_counts_s],
        "readings": per,
    }
    static = None
    if "zero_stability" in run.records:
        t, c = run.records["zero_stability"]
        k = bench.instrument.nominal_scale_factor_counts_per_deg
        static = StaticRecord(t, c / k, counts=c, nominal_scale_factor_counts_per_deg=k)
    return SessionResult(df, session_metadata(protocol, bench, seed), truth, static)


def json_plain(x):
    """JSON-safe copy: non-finite floats become None (truth values are finite in practice)."""
    if isinstance(x, dict):
        return {k: json_plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_plain(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def write_session(result: SessionResult, out: str | Path, *,
                  force: bool = False) -> dict[str, Path]:
    """Write ``readings.csv`` and ``truth.json`` into ``out`` atomically.

    As ``gonio simulate --out`` does, an existing ``readings.csv`` or ``truth.json`` in
    ``out`` (a laboratory's data, or an earlier run) is refused unless ``force``: a
    GonioError naming the file, nothing written. Inside an output set being staged for
    ``out`` (:func:`gonio.atomic.output_set`, which made its own checks) the files go into
    that set.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "readings.csv").write_text("a laboratory's readings")
    >>> try:
    ...     write_session(None, d)
    ... except GonioError as e:
    ...     print(e.message)
    readings.csv exists in the output folder; give force=True to replace it
    """
    from gonio.formats.watermark import mark_text
    from gonio.specs.ogam_draft.readings import format_readings

    out = Path(out)
    if active_stage(out) is None:
        check_output_dir(out, force=force, what="output folder")
        for name in ("readings.csv", "truth.json"):
            if (out / name).exists() or (out / name).is_symlink():
                if not force:
                    raise GonioError(f"{name} exists in the output folder; give force=True to "
                                     "replace it", file=out / name)
    with output_dir(out) as stage:
        # the bench's watermark in its measured values (gonio.formats.watermark)
        write_text(stage / "readings.csv",
                   mark_text(format_readings(result.readings, result.metadata)))
        write_text(stage / "truth.json", json.dumps(json_plain(result.truth), indent=2,
                                                    allow_nan=False) + "\n")
    return {"readings": out / "readings.csv", "truth": out / "truth.json"}
