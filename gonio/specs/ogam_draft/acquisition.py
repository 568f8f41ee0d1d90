"""Run a protocol's programme on a rotary table and an acquisition module (``gonio acquire``;
the optical draft's ``acquire`` hook, :func:`acquire_programme`).

:func:`plan_programme` turns a :class:`~gonio.specs.ogam_draft.protocol.Protocol` into blocks of readings in
the order the virtual bench runs them (:mod:`gonio.specs.ogam_draft.bench.session`): the zero-stability rest
(7.3), the in-situ tilt estimate's rests when the protocol has ``[tilt_estimate]`` (beyond the
draft), then every series of every rotation item (7.1, 7.4/7.5, 7.6, 7.7), each block in one
axis orientation and beginning with its static phase when the Earth-rate compensation is
measured (clause 7 preamble; the tilt estimate's rests are not compensated: the Earth rate
is their signal). :func:`check_programme` refuses, before the table moves at
all, any move outside the table's stated range or the protocol's Table 1 range, any rate
above the table's or the protocol's top rate, a rotation longer than the round's
``max_rotation_s`` at the table's acceleration, and a reading planned later than
``max_time_to_reading_s`` after its zeroing (Annex A.1's 0.5 min).

:class:`Acquisition` takes the readings: per round it zeroes the module at rest, arms it to read
``read_delay_s`` after the table's in-position signal (its external trigger, draft clause
4; a module without one is read when the host's wait on the module's clock ends), moves the
table at the round's rate, fetches the reading (counts since the zeroing, roll-over undone), subtracts the
compensation × time since zeroing, writes the row to ``readings.csv`` at once (append,
flush, fsync) and rests out ``rest_s``; a reading later than the Annex A.1 limit is
retaken. At each of the tilt estimate's positions it moves the table there at the section's
``rate_dps``, waits ``settle_s``, zeroes, and reads the raw counts ``dwell_s`` later (one
row per position, as ``gonio simulate`` writes it: ``table_deg`` the position, ``time_s`` the
dwell, ``gyro_counts`` uncompensated). Every wait is timed on the module's clock, so a served bench running N× faster
than real time is driven N× faster. Every exit path sends the table a stop; an interrupted
file stays marked ``acquisition: incomplete`` and ``resume`` continues it from the last
complete round (a block whose rounds share a zeroing — 7.3's rest, ``rezero = false`` —
is taken again whole; any block re-measures its compensation; each of the tilt estimate's
rests has its own zeroing, so an interrupted estimate continues at its next position).
"""

from __future__ import annotations

import csv
import math
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from gonio import __version__
from gonio.errors import GonioError
from gonio.specs.ogam_draft.acquisition_module import AcquisitionModule
from gonio.instruments.run import (AcquisitionResult, ModuleClock, ReadingsFile,
                                  with_given_metadata,
                                  laboratory_date_text, raise_stop, stop_reason)
from gonio.instruments.link import IOLog, Link
from gonio.instruments.table import RotaryTable, TableLimits
from gonio.physics.earth import NAMED_AXES, axis_enu, earth_rate_enu
from gonio.physics.kinematics import trapezoid_duration_s
from gonio.progress import format_duration, status
from gonio.specs.ogam_draft.protocol import Protocol
from gonio.units import S_PER_MIN

#: The readings file's columns, in the contract's order (docs/formats.md#readings-file).
COLUMNS = ("test", "series", "round", "rate_dps", "orientation", "time_s", "table_deg",
           "gyro_counts", "gyro_deg")
#: Retakes of a round whose reading came later than the Annex A.1 limit.
RETAKES = 2
#: The tests whose readings Annex A.1 bounds to its 0.5 min measuring time when the protocol
#: sets no ``max_time_to_reading_s`` (the calibration's screening applies the same bound and
#: sets later readings aside): 7.4 and 7.7, by their readings-file test names.
A1_TESTS = ("angle_deviation", "pointing_consistency")


@dataclass(frozen=True)
class Step:
    """One reading of the programme."""

    test: str
    series: int
    round: int
    rate_dps: float | None         # None: a reading at rest (7.3)
    orientation: str
    start_deg: float = 0.0
    stop_deg: float = 0.0
    read_delay_s: float = 0.0      # after arrival; for 7.3 and the tilt estimate's rests, the
                                   # reading's time after zeroing (the dwell)
    rest_s: float = 0.0            # after the reading; for the tilt estimate's rests, the
                                   # settling before the zeroing
    max_rotation_s: float | None = None
    max_time_to_reading_s: float | None = None

    @property
    def key(self) -> tuple:
        return (self.test, self.series, self.round, self.rate_dps, self.orientation)


@dataclass
class Block:
    """Readings taken in one orientation after one static phase."""

    label: str
    orientation: str
    steps: list[Step]
    at_rest: bool = False          # 7.3: one zeroing, readings at set times
    rezero: bool = True
    return_to_zero: bool = True
    positions: bool = False        # the tilt estimate: a rest at each step's stop_deg, each
                                   # with its own zeroing, counts not compensated


def plan_programme(protocol: Protocol) -> list[Block]:
    """The programme's blocks, in the virtual bench's order (zero stability, the in-situ
    tilt estimate's rests, then the rotation items' series); equal division's rests, which
    the acquisition does not run yet, are refused by name."""
    for name in ("equal_division",):
        if getattr(protocol, name, None) is not None:
            raise GonioError(f"gonio acquire does not run [{name}] yet: take it out of the "
                             "protocol, or record it as a stream", key=name,
                             file=protocol.path or None)
    blocks = []
    z = protocol.zero_stability
    if z is not None:
        blocks.append(Block("zero_stability", z.orientation, [
            Step("zero_stability", 1, n + 1, None, z.orientation, read_delay_s=n * z.interval_s)
            for n in range(z.readings)], at_rest=True, rezero=False, return_to_zero=False))
    if protocol.tilt_estimate is not None:
        blocks.append(tilt_estimate_block(protocol.tilt_estimate))
    for item in protocol.items():
        limit = item.max_time_to_reading_s
        if limit is None and item.test in A1_TESTS:
            limit = protocol.annex_a.duration_min * S_PER_MIN
        for series in range(1, item.series + 1):
            steps = [Step(item.test, series, i, item.rate_dps, item.orientation, r.start_deg,
                          r.stop_deg, item.read_delay_s, item.rest_s, r.max_rotation_s, limit)
                     for i, r in enumerate(item.rounds, 1)]
            blocks.append(Block(f"{item.test} {item.orientation} {item.rate_dps:g} dps series "
                                f"{series}", item.orientation, steps, rezero=item.rezero,
                                return_to_zero=item.return_to_zero))
    if not any(b.steps for b in blocks):
        raise GonioError("the protocol plans no reading (no test section)", key="protocol",
                         file=protocol.path or None)
    return blocks


def tilt_estimate_block(plan) -> Block:
    """The ``[tilt_estimate]`` rests (:class:`~gonio.specs.ogam_draft.protocol.TiltEstimatePlan`)
    as the virtual bench takes them: rest i (1…N) at the plan's i-th position
    (``plan.order_deg``: opposite pairs), reached from the one before at ``rate_dps``; after
    ``settle_s`` a zeroing and, ``dwell_s`` later, a reading of the counts (test
    ``tilt_estimate``, series 1, round i, ``rate_dps`` the section's)."""
    steps = []
    order = plan.order_deg
    for i, x in enumerate(order):
        steps.append(Step("tilt_estimate", 1, i + 1, plan.rate_dps, plan.orientation,
                          start_deg=order[i - 1] if i else 0.0, stop_deg=x,
                          read_delay_s=plan.dwell_s, rest_s=plan.settle_s))
    return Block(f"tilt_estimate {plan.orientation}", plan.orientation, steps,
                 return_to_zero=False, positions=True)


def check_programme(blocks: list[Block], protocol: Protocol, limits: TableLimits) -> None:
    """Refuse the programme before any move (see the module's docstring)."""
    cond, s = protocol.conditions, protocol.session
    top = min(limits.max_rate_dps, cond.table_rate_max_dps)
    lo = max(limits.min_deg, -cond.table_angle_range_deg)
    hi = min(limits.max_deg, cond.table_angle_range_deg)
    tab = TableLimits(lo, hi, top, limits.accel_dps2)
    tab.check(0.0, s.return_rate_dps, where="session.return_rate_dps")
    for b in blocks:
        if b.orientation not in cond.table_orientations:
            raise GonioError(f"{b.label}: the axis orientation {b.orientation!r} is not among the "
                             f"protocol's table_orientations {list(cond.table_orientations)}")
        for st in b.steps:
            if st.rate_dps is None:
                continue
            where = f"{st.test} series {st.series} round {st.round}"
            tab.check(st.start_deg, s.return_rate_dps, where=where)
            tab.check(st.stop_deg, st.rate_dps, where=where)
            turn = trapezoid_duration_s(st.stop_deg - st.start_deg, st.rate_dps, limits.accel_dps2)
            if st.max_rotation_s is not None and turn > st.max_rotation_s + 1e-9:
                raise GonioError(f"{where}: the table needs {turn:.2f} s at its acceleration "
                                 f"{limits.accel_dps2:g} °/s² (limit {st.max_rotation_s} s)")
            lim = st.max_time_to_reading_s
            if lim is not None and turn + st.read_delay_s > lim + 1e-9:
                raise GonioError(f"{where}: the reading comes {turn + st.read_delay_s:.1f} s after "
                                 f"zeroing, beyond {lim} s (Annex A.1)")


def programme_duration_s(blocks: list[Block], protocol: Protocol, accel_dps2: float) -> list[float]:
    """The planned duration of each step (s), its block's static phase and moves included."""
    s = protocol.session
    out = []
    for b in blocks:
        static = s.static_s if s.earth_compensation == "measured" else 0.0
        prev = 0.0
        for i, st in enumerate(b.steps):
            if st.rate_dps is None:
                out.append(st.read_delay_s - prev + (static if i == 0 else 0.0))
                prev = st.read_delay_s
                continue
            if b.positions:              # move there, settle, dwell (no static phase)
                out.append(trapezoid_duration_s(st.stop_deg - st.start_deg, st.rate_dps,
                                                accel_dps2) + st.rest_s + st.read_delay_s)
                continue
            d = trapezoid_duration_s(st.stop_deg - st.start_deg, st.rate_dps, accel_dps2)
            back = trapezoid_duration_s(st.stop_deg - st.start_deg, s.return_rate_dps, accel_dps2)
            out.append(d + max(st.rest_s, st.read_delay_s) + (back + s.settle_s if b.return_to_zero
                                                             else 0.0) + (static if i == 0 else 0.0))
    return out


# ---------------------------------------------------------------------- readings file
def _cell(v) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return ""
    return repr(float(v)) if isinstance(v, float) else str(v)


def format_row(step: Step, time_s: float, table_deg: float | None, counts: int) -> str:
    """One line of readings.csv, as :func:`gonio.specs.ogam_draft.readings.write_readings` writes it."""
    return ",".join([step.test, str(step.series), str(step.round), _cell(step.rate_dps),
                     step.orientation, _cell(round(time_s, 9)), _cell(table_deg), str(int(counts)),
                     ""]) + "\n"


def _row_key(row: dict) -> tuple:
    rate = float(row["rate_dps"]) if row.get("rate_dps") else None
    return (row["test"], int(row["series"]), int(row["round"]), rate, row.get("orientation") or "up")


def read_previous(path: Path, protocol: Protocol) -> tuple[list[str], set]:
    """The complete rows of an interrupted readings.csv (a last line cut short is dropped)
    and their keys; refuses a file of another protocol or an already complete one."""
    text = path.read_text(encoding="utf-8")
    if not text.endswith("\n"):
        text = text[:text.rfind("\n") + 1]
    lines = text.splitlines(keepends=True)
    md = {}
    body = []
    for ln in lines:
        if ln.startswith("#") and not body:
            k, _, v = ln[1:].partition(":")
            md[k.strip()] = v.strip()
        elif ln.strip():
            body.append(ln)
    if md.get("protocol") != protocol.name:
        raise GonioError(f"--resume: {path} was taken with protocol {md.get('protocol')!r}, "
                         f"not {protocol.name!r}", file=str(path))
    if md.get("acquisition") == "complete":
        raise GonioError(f"--resume: {path} is complete already", file=str(path))
    if not body or body[0].rstrip("\n").split(",") != list(COLUMNS):
        raise GonioError(f"--resume: {path} has no readings header", file=str(path))
    rows = body[1:]
    keys = {_row_key(r) for r in csv.DictReader([body[0]] + rows)}
    return rows, keys


# ---------------------------------------------------------------------- the run
@dataclass
class Acquisition:
    """The engine behind ``gonio acquire`` (see the module's docstring)."""

    protocol: Protocol
    table: RotaryTable
    gyro: AcquisitionModule
    writer: ReadingsFile | None = None
    prompt: object = input
    latitude_deg: float | None = None
    done: set = field(default_factory=set)
    taken: int = 0

    def __post_init__(self):
        self.s = self.protocol.session
        self.K = self.gyro.scale_factor_counts_per_deg() or 0.0
        self.clock = ModuleClock(self.gyro)
        self.position = None
        self.axis = None
        self.triggered = self.gyro.can_trigger_on_table
        if self.triggered:
            self.gyro.send("trigger_source", source="EXT")

    # -- table motion
    def move(self, angle_deg: float, rate_dps: float) -> float:
        """Move and wait for the arrival; returns the module's time at arrival."""
        if self.position is not None and abs(angle_deg - self.position) < 1e-12:
            return self.clock.now()
        lim = self.table.limits()
        dist = angle_deg - (self.position if self.position is not None
                            else self.table.position_deg())
        t0 = self.clock.now()
        self.table.move(angle_deg, rate_dps)
        expect = trapezoid_duration_s(dist, rate_dps, lim.accel_dps2)
        t = self.clock.wait_until(t0 + expect)
        # a move late by more than a fifth, 5 s and a second of the host's own delays (the
        # module's clock may run N× faster than the host's) is the table's fault
        deadline = t0 + expect * 1.2 + 5.0 + (self.clock.speed() or 1.0)
        while self.table.state() != "idle":
            if t > deadline:
                raise GonioError(f"table: still moving {t - t0:.1f} s after a move planned to "
                                 f"take {expect:.1f} s")
            t = self.clock.wait_until(t + 0.02)
        self.position = angle_deg
        return self.clock.now()

    def dwell(self, seconds: float) -> float:
        return self.clock.wait_until(self.clock.now() + seconds)

    def set_axis(self, orientation: str) -> None:
        if orientation == self.axis:
            return
        if self.table.can_set_axis:
            self.table.set_axis(orientation)
        else:
            status("")
            try:
                self.prompt(f"Set the table axis to {orientation.upper()} and press Enter: ")
            except EOFError:
                raise GonioError(f"the table cannot set its axis to {orientation!r} and no "
                                 "operator answered (stdin closed)") from None
        self.axis = orientation

    # -- compensation
    def compensation(self, orientation: str) -> float:
        """Counts per second to subtract: measured over a static phase, computed from the
        latitude and the axis, or none (clause 7 preamble; ``session.earth_compensation``)."""
        how = self.s.earth_compensation
        if how == "measured":
            self.gyro.zero()
            t0 = self.clock.now()
            self.clock.wait_until(t0 + self.s.static_s)
            r = self.gyro.read(0.0)
            return r.counts / r.time_s
        if how == "computed":
            lat = (self.s.compensation_latitude_deg if self.s.compensation_latitude_deg is not None
                   else self.latitude_deg)
            if lat is None or not self.K:
                raise GonioError("a computed Earth-rate compensation needs latitude_deg "
                                 "(--meta latitude_deg=…) and the module's scale factor")
            az, el = NAMED_AXES[orientation]
            w = earth_rate_enu(lat) @ axis_enu((az + self.s.compensation_azimuth_error_deg, el))
            return self.K * math.degrees(float(w))
        return 0.0

    # -- blocks
    def rest_block(self, b: Block, comp: float, on_row) -> None:
        self.gyro.zero()
        t_zero = self.clock.now()
        for st in b.steps:
            self.clock.wait_until(t_zero + st.read_delay_s)
            r = self.gyro.read(0.0)
            on_row(st, format_row(st, r.time_s, None, round(r.counts - comp * r.time_s)))

    def position_rest(self, st: Step, n_steps: int) -> str:
        """One of the tilt estimate's rests (see the module's docstring); returns its row.
        The counts are not compensated; their roll-over is undone near the Earth rate's
        count over the dwell when the latitude is known (else near 0)."""
        self.move(st.stop_deg, st.rate_dps)
        self.dwell(st.rest_s)
        status(f"acquire: tilt estimate rest {st.round}/{n_steps} at {st.stop_deg:g}°, "
               f"{format_duration(st.read_delay_s)} dwell")
        self.gyro.zero()
        self.clock.wait_until(self.clock.now() + st.read_delay_s)
        r = self.gyro.read(self.earth_counts_per_s(st.orientation) * st.read_delay_s)
        return format_row(st, r.time_s, st.stop_deg, r.counts)

    def earth_counts_per_s(self, orientation: str) -> float:
        """The Earth rate along the nominal axis, counts/s (0 without the latitude or K)."""
        if self.latitude_deg is None or not self.K:
            return 0.0
        return self.K * math.degrees(float(earth_rate_enu(self.latitude_deg)
                                           @ axis_enu(NAMED_AXES[orientation])))

    def rotation_step(self, b: Block, st: Step, comp: float, zero_x: list) -> str:
        """Take one round; returns its readings row."""
        for attempt in range(RETAKES + 1):
            if self.position != st.start_deg:
                self.move(st.start_deg, self.s.return_rate_dps)
                self.dwell(self.s.settle_s)
            if self.triggered:                  # armed first: the zeroing right before the move
                self.gyro.arm(st.read_delay_s)
            if zero_x[0] is None or b.rezero or attempt:
                self.gyro.zero()
                zero_x[0] = st.start_deg
            angle = st.stop_deg - zero_x[0]
            if self.triggered:                  # read by the module, on the table's signal
                arrive = self.move(st.stop_deg, st.rate_dps)
                r = self.gyro.fetch(self.K * angle, wait=lambda: self.dwell(0.1))
            else:                               # read when the host says, on its clock
                arrive = self.move(st.stop_deg, st.rate_dps)
                self.clock.wait_until(arrive + st.read_delay_s)
                r = self.gyro.read(self.K * angle)
            self.clock.wait_until(arrive + st.rest_s)
            lim = st.max_time_to_reading_s
            if lim is None or r.time_s <= lim + 1e-9 or not b.rezero:
                break
            if attempt == RETAKES:
                raise GonioError(f"{st.test} series {st.series} round {st.round}: the reading "
                                 f"came {r.time_s:.1f} s after zeroing, {RETAKES + 1} times "
                                 f"beyond {lim} s (Annex A.1)")
            self.table.link.log.write("acquire", "!", f"{st.test} series {st.series} round "
                                      f"{st.round}: read {r.time_s:.1f} s after zeroing, beyond "
                                      f"{lim} s (Annex A.1): taken again")
        row = format_row(st, r.time_s, angle, round(r.counts - comp * r.time_s))
        if b.return_to_zero:
            self.move(st.start_deg, self.s.return_rate_dps)
            self.dwell(self.s.settle_s)
        return row

    def run_block(self, b: Block, on_row) -> None:
        todo = [st for st in b.steps if st.key not in self.done]
        if not todo:
            return
        self.set_axis(b.orientation)
        if b.positions:
            for st in todo:
                on_row(st, self.position_rest(st, len(b.steps)))
            return
        first = 0.0 if b.at_rest else b.steps[0].start_deg
        self.move(first, self.s.return_rate_dps)
        comp = self.compensation(b.orientation)
        if b.at_rest:
            self.rest_block(b, comp, on_row)
            return
        zero_x = [None]
        for st in todo:
            on_row(st, self.rotation_step(b, st, comp, zero_x))


def _restartable(b: Block) -> bool:
    return b.rezero and not b.at_rest


def resume_plan(blocks: list[Block], rows: list[str], keys: set) -> tuple[list[str], set]:
    """Which rows of an interrupted run stand: every row of a complete block, and the rows of
    a partial block whose rounds each have their own zeroing; a partial block whose rounds
    share a zeroing (7.3, ``rezero = false``) is taken again whole."""
    drop = set()
    for b in blocks:
        ks = {st.key for st in b.steps}
        have = ks & keys
        if have and have != ks and not _restartable(b):
            drop |= have
    kept_rows = [r for r in rows if _row_key(next(csv.DictReader([",".join(COLUMNS), r])))
                 not in drop]
    return kept_rows, keys - drop


def _identity_metadata(table_idn: str, gyro_idn: str) -> dict:
    maker, model, serial = (gyro_idn.split(",") + ["", "", ""])[:3]
    tmaker, tmodel = (table_idn.split(",") + ["", ""])[:2]
    return {"instrument": model.strip(), "serial": serial.strip(), "manufacturer": maker.strip(),
            "table": f"{tmaker.strip()} {tmodel.strip()}".strip(),
            "gyro_idn": gyro_idn, "table_idn": table_idn}


def acquire(protocol: Protocol, table_resource: str, gyro_resource: str, out: str | Path, *,
            resume: bool = False, metadata: dict | None = None, table_cls=RotaryTable,
            gyro_cls=AcquisitionModule, prompt=input, timeout_s: float = 10.0) -> AcquisitionResult:
    """Run ``protocol`` on the table and module at the VISA resources; write ``out``/
    ``readings.csv`` (as the readings come) and ``out``/``io.log`` (every command and answer).

    ``metadata``: extra ``# key: value`` lines (``latitude_deg`` for the budgets and a computed
    compensation). ``table_cls``/``gyro_cls``: a laboratory's drivers. On any exit the table
    gets a stop; an unfinished file stays ``acquisition: incomplete`` (``resume`` continues it).
    """
    blocks = plan_programme(protocol)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "readings.csv"
    rows, keys = [], set()
    if resume:
        if not path.exists():
            raise GonioError(f"--resume: no {path} to continue", file=str(path))
        rows, keys = resume_plan(blocks, *read_previous(path, protocol))
    elif path.exists():
        raise GonioError(f"{path} exists: continue it with --resume, or choose another --out",
                         file=str(path))
    log = IOLog(out / "io.log")
    links, writer = [], None
    old_term = None
    if signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, None):
        try:
            old_term = signal.signal(signal.SIGTERM, raise_stop)
        except ValueError:               # not the main thread
            pass
    t_start = time.monotonic()
    table = gyro = None
    try:
        links.append(Link(table_resource, name="table", log=log, timeout_s=timeout_s))
        table = table_cls(links[-1])
        links.append(Link(gyro_resource, name="gyro", log=log, timeout_s=timeout_s))
        gyro = gyro_cls(links[-1])
        table.clear()                    # first: an error left by an earlier session
        gyro.clear()
        md = _identity_metadata(table.identify(), gyro.identify())
        lim = table.limits()
        check_programme(blocks, protocol, lim)
        md.update(_instrument_metadata(protocol, gyro, lim))
        zone = str((metadata or {}).get("timezone") or "")
        if zone:                                   # the date in the laboratory's zone
            md["date"] = laboratory_date_text(zone=zone)
        md = with_given_metadata(md, metadata)    # adds, never replaces what was reported
        writer = ReadingsFile(path, md, rows, COLUMNS)
        return _run(protocol, blocks, table, gyro, writer, keys, prompt, md, log, t_start)
    except BaseException as exc:
        reason = stop_reason(exc)
        if writer is not None:
            writer.finish(False, reason)
        status("")
        if writer is None:
            sys.stderr.write(f"gonio acquire: stopped before the programme began ({reason})\n")
        else:
            sys.stderr.write(f"gonio acquire: stopped ({reason}); the table was sent a stop; "
                             f"{len(writer.rows)} readings kept in {path} (incomplete: "
                             "continue with --resume)\n")
        raise
    finally:
        _safe_stop(table, log)
        for ln in links:
            ln.close()
        log.close()
        if old_term is not None:
            signal.signal(signal.SIGTERM, old_term)


def _instrument_metadata(protocol: Protocol, gyro: AcquisitionModule, lim: TableLimits) -> dict:
    md = {}
    k = gyro.scale_factor_counts_per_deg()
    if k:
        md["nominal_scale_factor_counts_per_deg"] = repr(k)
    if gyro.has("temperature"):
        md["temperature_c"] = repr(gyro.temperature_c())
    md.update({"table_accel_dps2": repr(lim.accel_dps2),
               "tilt_bound_deg": repr(protocol.annex_a.tilt_bound_deg),
               "protocol": protocol.name,
               "date": laboratory_date_text(),
               "generator": f"gonio {__version__} acquire"})
    return md


def _run(protocol, blocks, table, gyro, writer, keys, prompt, md, log, t_start):
    lat = md.get("latitude_deg")
    eng = Acquisition(protocol, table, gyro, writer, prompt,
                      float(lat) if lat not in (None, "") else None, set(keys))
    per = programme_duration_s(blocks, protocol, table.limits().accel_dps2)
    steps = [st for b in blocks for st in b.steps]
    left = {st.key: d for st, d in zip(steps, per) if st.key not in keys}
    total, n0 = len(steps), len(keys)

    def on_row(st, line):
        writer.append(line)
        eng.done.add(st.key)
        eng.taken += 1
        left.pop(st.key, None)
        sp = eng.clock.speed() or 1.0
        status(f"acquire: point {n0 + eng.taken}/{total}  {st.test} series {st.series} round "
               f"{st.round}  about {format_duration(sum(left.values()) / sp)} left")

    for b in blocks:
        eng.run_block(b, on_row)
    writer.finish(True)
    status("")
    return AcquisitionResult(writer.path, Path(log.path), eng.taken, total, True,
                             time.monotonic() - t_start)


def _safe_stop(table: RotaryTable | None, log: IOLog) -> None:
    """Send the table a stop, signals held off meanwhile; a lost link is logged, not raised."""
    if table is None:
        return
    held = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            held[sig] = signal.signal(sig, signal.SIG_IGN)
        except ValueError:              # not the main thread
            pass
    try:
        table.link.write(table.command("stop"))
    except GonioError as exc:
        log.write("table", "!", f"stop not delivered: {exc}")
    finally:
        for sig, h in held.items():
            signal.signal(sig, h)


def acquire_programme(protocol, resources: dict, out: str | Path, *, metadata: dict | None = None,
                      resume: bool = False, timeout_s: float = 10.0, prompt=input) -> AcquisitionResult:
    """The ``acquire`` hook (:func:`gonio.pipeline.acquire.acquire`): :func:`acquire` of the
    protocol (file or built-in name) on the table and the acquisition module of
    ``resources`` (VISA resource strings by role)."""
    from gonio.specs.ogam_draft.protocol import load_protocol

    for role in ("table", "gyro"):
        if not resources.get(role):
            raise GonioError(f"the programme needs the {role}: give its VISA resource")
    return acquire(load_protocol(protocol), resources["table"], resources["gyro"], out,
                   resume=resume, metadata=dict(metadata or {}), timeout_s=timeout_s,
                   prompt=prompt)
