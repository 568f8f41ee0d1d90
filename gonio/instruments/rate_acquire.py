"""Run a rate specification's programme on a rate table, a gyro output reader, a chamber and
a supply (``gonio acquire`` with a rate specification's protocol).

The programme is the specification's own list of
:class:`~gonio.protocol.programme.Segment` (its acquisition hook,
``Specification.acquisition``, looked up through the registry: this module names no
specification), the same list ``gonio simulate`` runs
on the virtual bench. :func:`acquire_rate` takes it segment by segment:

1. a segment that starts a power cycle (``power_on``, and the first one run): the supply
   off (a gyro left on is restarted), the time off
   (``off_time_s``, counted from the end of the last record) waited out, then the bench
   set (below) and the supply on — last, so that nothing changes after the power-on;
2. the bench set to the segment's conditions, only what changes: the chamber (set point
   and ramp; off where the segment has none), the mounting (the position fixture, or an
   operator prompt), the table (its rate, its sine, or a stop), the supply's voltage;
3. the record started at ``delay_s`` after the end of the last record (after the power-on
   in a new cycle), on the reader's own clock, so the host's latency does not move it;
4. once its time has passed, its samples fetched and written to ``readings.csv`` at once
   (appended, flushed, synced): ``time_s`` since the power-on, the output, the reference
   rate, the set rate/frequency, the temperature (below), the voltage the supply measures.
   ``temperature_c``: a chamber test's rows the chamber's set point (the specification's
   test temperature); a test run with the chamber off logs what was measured, never the
   protocol's nominal room — the chamber's air (``MEAS:TEMP?``) read as the record starts
   and after it ends, on its first and last rows (blank between, as a slow logger's
   column), and blank on every row where no chamber is connected.

Every wait is timed on the reader's clock (:class:`gonio.instruments.run.ModuleClock`),
so a bench served N× faster runs N× faster. Every exit path stops the table and switches
the chamber and the supply off (``finally``, signals held off); the rows taken stay, marked
``acquisition: incomplete``; ``resume`` keeps every power cycle complete in the file and
runs the programme again from the first one incomplete (a record's meaning depends on the
time since its power-on, so a cycle is never continued in the middle).
"""

from __future__ import annotations

import math
import signal
import sys
import time
from pathlib import Path

import numpy as np

from gonio import __version__
from gonio.errors import GonioError
from gonio.formats.rate_readings import COLUMNS as RATE_COLUMNS
from gonio.instruments.run import (ModuleClock, ReadingsFile, laboratory_date_text, raise_stop,
                                  with_given_metadata,
                                  stop_reason)
from gonio.instruments.link import IOLog, Link
from gonio.instruments.rate import Chamber, GyroOutput, RateTable, Supply
from gonio.progress import format_duration, status
from gonio.protocol.programme import Segment

#: The instruments, their drivers by default, and whether a programme may go without them.
ROLES = {"table": RateTable, "gyro": GyroOutput, "chamber": Chamber, "supply": Supply}


def needs(segments: list[Segment]) -> set[str]:
    """The instruments a programme needs (a chamber only for set points)."""
    need = {"table", "gyro", "supply"}
    if any(s.temperature_c is not None for s in segments):
        need.add("chamber")
    return need


def check_rate_programme(segments: list[Segment], table: RateTable) -> None:
    """Refuse, before anything moves, a segment the table cannot run or gonio cannot set."""
    lim = table.limits()
    for i, s in enumerate(segments):
        where = f"segment {i + 1} ({s.test}/{s.run}/{s.step})"
        if s.stand_deg:
            raise GonioError(f"{where}: a tilted stand ({s.stand_deg:g}° about {s.stand_axis}) "
                             "is not driven yet")
        top = max(abs(s.rate_dps), s.vib_amplitude_dps)
        if top > lim.max_rate_dps:
            raise GonioError(f"{where}: {top:g} °/s is beyond the table's top rate "
                             f"{lim.max_rate_dps:g} °/s; nothing was sent")


def _cell(v) -> str:
    if isinstance(v, str):
        return v
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return "" if math.isnan(v) else f"{float(v):.12g}"


def format_rows(seg: Segment, time_s: np.ndarray, output: np.ndarray, reference: np.ndarray,
                supply_v: float, air_c: tuple[float, float] = (math.nan, math.nan)) -> str:
    """A record's rows, as :func:`gonio.formats.rate_readings.write_rate_readings` writes
    them (12 significant digits, NaN empty). ``temperature_c``: the segment's chamber set
    point; for a segment with the chamber off, ``air_c`` (the air temperature measured as
    the record started and after it ended) on its first and last rows, blank between (NaN:
    none measured).

    >>> s = Segment("bias", 1, 0, "record", 3, 1.0)
    >>> rows = format_rows(s, np.arange(3.0), np.ones(3), np.zeros(3), 5.0, (20.4, 20.6))
    >>> [r.split(",")[RATE_COLUMNS.index("temperature_c")] for r in rows.splitlines()]
    ['20.4', '', '20.6']
    """
    fixed = {"test": seg.test, "run": seg.run, "step": seg.step, "role": seg.role,
             "rate_dps": seg.vib_amplitude_dps if seg.vib_amplitude_dps > 0 else seg.rate_dps,
             "freq_hz": seg.freq_hz, "supply_v": supply_v, "up_axis": seg.up_axis,
             "north_axis": seg.north_axis, "stand_deg": seg.stand_deg,
             "stand_axis": seg.stand_axis, "supply_set_v": math.nan}
    n = len(time_s)
    if seg.temperature_c is not None:
        temps = [seg.temperature_c] * n
    else:
        temps = [math.nan] * n
        if n:
            temps[0], temps[-1] = air_c[0], air_c[1]
    lines = []
    for t, o, r, c in zip(time_s.tolist(), output.tolist(), reference.tolist(), temps):
        row = {**fixed, "time_s": t, "output": o, "reference_dps": r, "temperature_c": c}
        lines.append(",".join(_cell(row[c]) for c in RATE_COLUMNS))
    return "\n".join(lines) + "\n"


def _previous(path: Path, segments: list[Segment], protocol_name: str) -> list[str]:
    """The rows of the complete power cycles of an interrupted readings.csv."""
    text = path.read_text(encoding="utf-8")
    lines = text[:text.rfind("\n") + 1].splitlines(keepends=True)
    md = dict((ln[1:].partition(":")[0].strip(), ln[1:].partition(":")[2].strip())
              for ln in lines if ln.startswith("#"))
    if md.get("protocol") != protocol_name:
        raise GonioError(f"--resume: {path} was taken with protocol {md.get('protocol')!r}, "
                         f"not {protocol_name!r}", file=str(path))
    if md.get("acquisition") == "complete":
        raise GonioError(f"--resume: {path} is complete already", file=str(path))
    body = [ln for ln in lines if not ln.startswith("#") and ln.strip()]
    if not body or body[0].rstrip("\n").split(",") != list(RATE_COLUMNS):
        raise GonioError(f"--resume: {path} has no readings header", file=str(path))
    return body[1:]


def resume_point(segments: list[Segment], rows: list[str]) -> tuple[int, list[str]]:
    """(index of the segment to run first, the rows kept): every row of the power cycles
    complete in ``rows``; the cycle in which the first incomplete segment lies runs again."""
    count: dict[tuple, int] = {}
    for r in rows:
        f = r.split(",", 3)
        count[(f[0], int(f[1]), int(f[2]))] = count.get((f[0], int(f[1]), int(f[2])), 0) + 1
    first = next((i for i, s in enumerate(segments)
                  if count.get((s.test, s.run, s.step), 0) != s.samples), len(segments))
    start = first
    while 0 < start < len(segments) and not segments[start].power_on:
        start -= 1
    keep_keys = {(s.test, s.run, s.step) for s in segments[:start]}
    kept = [r for r in rows if (lambda f: (f[0], int(f[1]), int(f[2])))(r.split(",", 3))
            in keep_keys]
    return start, kept


class RateAcquisition:
    """The engine: the bench's state as set so far, and one segment at a time."""

    def __init__(self, drivers: dict, writer: ReadingsFile, prompt=input,
                 nominal_v: float | None = None):
        self.d, self.writer, self.prompt = drivers, writer, prompt
        self.nominal_v = nominal_v
        self.clock = ModuleClock(drivers["gyro"])
        self.state: dict = {}
        self.powered = False
        self.t_end: float | None = None
        self.t_on: float | None = None
        self.taken = 0

    def _set(self, key: str, value, apply) -> None:
        if self.state.get(key, object()) != value:
            apply(value)
            self.state[key] = value

    def set_conditions(self, seg: Segment) -> None:
        d = self.d
        if seg.temperature_c is None:
            if "chamber" in d:
                self._set("chamber", None, lambda v: d["chamber"].off())
        else:
            self._set("chamber", (seg.temperature_c, seg.ramp_c_per_min),
                      lambda v: d["chamber"].set_point(*v))
        self._set("mount", (seg.up_axis, seg.north_axis), self._mount)
        motion = ("osc", seg.freq_hz, seg.vib_amplitude_dps) if seg.vib_amplitude_dps > 0 \
            else ("rate", seg.rate_dps)
        self._set("motion", motion, self._move)
        v = seg.supply_v if seg.supply_v is not None else self.nominal_v
        if v is not None:
            self._set("supply_v", v, d["supply"].set_voltage)

    def _mount(self, m) -> None:
        t = self.d["table"]
        if t.can_mount:
            t.mount(*m)
        else:
            self.prompt(f"Mount the gyro with its {m[0]} axis up and {m[1]} north, and press "
                        "Enter ")

    def _move(self, motion) -> None:
        t = self.d["table"]
        if motion[0] == "osc":
            t.oscillate(motion[1], motion[2])
        elif motion[1]:
            t.rotate(motion[1])
        else:
            t.stop()

    def run_segment(self, seg: Segment) -> None:
        d, clock = self.d, self.clock
        if seg.power_on or not self.powered:
            d["supply"].off()            # also the first time: a gyro left on is restarted
            self.powered = False
            if self.t_end is not None:
                clock.wait_until(self.t_end + seg.off_time_s)
            self.set_conditions(seg)
            t_before = clock.now()
            d["supply"].on()
            self.powered = True
            origin, fresh = t_before, True
        else:
            self.set_conditions(seg)
            origin, fresh = self.t_end, False
        at = origin + seg.delay_s
        d["gyro"].start_record(seg.samples, seg.interval_s, at)
        air_first = self._air(seg)
        clock.wait_until(at + seg.samples * seg.interval_s)
        while d["gyro"].ready() < seg.samples:
            clock.wait_until(clock.now() + seg.interval_s)
        data = d["gyro"].fetch(seg.samples)
        if fresh:           # the record starts at the power-on, or delay_s after it
            self.t_on = max(t_before, float(data[0, 0]) - seg.delay_s)
        self.t_end = float(data[-1, 0]) + seg.interval_s
        v = d["supply"].measured_v()
        self.writer.append(format_rows(seg, data[:, 0] - self.t_on, data[:, 1], data[:, 2], v,
                                       (air_first, self._air(seg))))
        self.taken += seg.samples

    def _air(self, seg: Segment) -> float:
        """The chamber's measured air temperature for a segment run with the chamber off
        (NaN where no chamber is connected, or the segment has a set point of its own)."""
        if seg.temperature_c is not None or "chamber" not in self.d:
            return math.nan
        return self.d["chamber"].air_c()


def _open(resources: dict, drivers: dict, log: IOLog, timeout_s: float, need: set) -> dict:
    missing = sorted(need - {k for k, v in resources.items() if v})
    if missing:
        raise GonioError(f"the programme needs the {', '.join(missing)}: give "
                         + " ".join(f"--{m} RESOURCE" for m in missing))
    out = {}
    for role in ROLES:
        if resources.get(role) and role in need:
            out[role] = drivers.get(role, ROLES[role])(
                Link(resources[role], name=role, log=log, timeout_s=timeout_s))
    return out


def acquire_rate(segments: list[Segment], metadata: dict, resources: dict[str, str | None],
                 out: str | Path, *, resume: bool = False,
                 drivers: dict | None = None, prompt=input, timeout_s: float = 10.0):
    """Run ``segments`` on the instruments at ``resources`` (``table``, ``gyro``,
    ``chamber``, ``supply``: VISA resource strings); write ``out``/``readings.csv`` (the
    rate readings format, record by record) and ``out``/``io.log``. ``metadata``: the
    readings' ``# key: value`` lines the specification's hook gave (``protocol`` among
    them); the instruments' identities are added. ``drivers``: a laboratory's driver
    classes by role. Returns an :class:`~gonio.instruments.run.AcquisitionResult`."""
    from gonio.instruments.run import AcquisitionResult

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "readings.csv"
    first, rows = 0, []
    if resume:
        if not path.exists():
            raise GonioError(f"--resume: no {path} to continue", file=str(path))
        first, rows = resume_point(segments, _previous(path, segments, metadata["protocol"]))
    elif path.exists():
        raise GonioError(f"{path} exists: continue it with --resume, or choose another --out",
                         file=str(path))
    log = IOLog(out / "io.log")
    old_term = None
    if signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, None):
        try:
            old_term = signal.signal(signal.SIGTERM, raise_stop)
        except ValueError:
            pass
    t0 = time.monotonic()
    d, writer = {}, None
    try:
        d = _open(resources, drivers or {}, log, timeout_s, needs(segments))
        md = {}
        for role, drv in d.items():
            drv.clear()                  # first: an error left by an earlier session
            md[f"{role}_idn"] = drv.identify()
        check_rate_programme(segments, d["table"])
        written = {"date": laboratory_date_text(zone=str(metadata.get("timezone") or "")),
                   "generator": f"gonio {__version__} acquire"}
        # an *_idn, date or generator given must be the instruments' answer or the run's own
        theirs = {k: v for k, v in metadata.items() if k.endswith("_idn") or k in written}
        md = with_given_metadata(
            {**md, **_stated(d["gyro"], {k: v for k, v in metadata.items() if k not in theirs}),
             **written}, theirs)
        writer = ReadingsFile(path, md, rows, columns=RATE_COLUMNS)
        nominal = md.get("supply_nominal_v")
        eng = RateAcquisition(d, writer, prompt,
                              float(nominal) if nominal not in (None, "") else None)
        total = sum(s.samples for s in segments)
        for i, seg in enumerate(segments[first:], first):
            eng.run_segment(seg)
            left = sum(s.delay_s + s.off_time_s + s.samples * s.interval_s for s in segments[i + 1:])
            status(f"acquire: segment {i + 1}/{len(segments)}  {seg.test} {seg.run}/{seg.step}  "
                   f"about {format_duration(left / (eng.clock.speed() or 1.0))} left")
        writer.finish(True)
        status("")
        return AcquisitionResult(path, out / "io.log", eng.taken, total, True, time.monotonic() - t0)
    except BaseException as exc:
        reason = stop_reason(exc)
        status("")
        if writer is not None:
            writer.finish(False, reason)
            sys.stderr.write(f"gonio acquire: stopped ({reason}); the table was sent a stop; "
                             f"{len(writer.rows)} records kept in {path} (incomplete: continue "
                             "with --resume)\n")
        else:
            sys.stderr.write(f"gonio acquire: stopped before the programme began ({reason})\n")
        raise
    finally:
        _safe_off(d, log)
        for drv in d.values():
            drv.link.close()
        log.close()
        if old_term is not None:
            signal.signal(signal.SIGTERM, old_term)


def _stated(gyro: GyroOutput, metadata: dict) -> dict:
    """The metadata: the gyro's identity and what it states of itself, under the hook's."""
    maker, model, serial = (gyro.identify().split(",") + ["", "", ""])[:3]
    md = {"instrument": model.strip(), "model": model.strip(), "serial": serial.strip(),
          "manufacturer": maker.strip()}
    for op, key in (("unit", "output_unit"), ("scale_factor", "nominal_scale_factor"),
                    ("null_output", "null_output")):
        v = gyro.stated(op)
        if v is not None:
            md[key] = v
    # the hook's lines add to what the instruments reported (their *IDN? answers, written
    # before), never replace it
    return with_given_metadata(md, {k: str(v) for k, v in metadata.items() if v is not None})


def _safe_off(d: dict, log: IOLog) -> None:
    """Stop the table and switch the chamber and the supply off, signals held off; a lost
    link is logged, not raised."""
    held = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            held[sig] = signal.signal(sig, signal.SIG_IGN)
        except ValueError:
            pass
    try:
        for role, op in (("table", "stop"), ("supply", "off"), ("chamber", "off")):
            if role in d:
                try:
                    d[role].link.write(d[role].command(op))
                except GonioError as exc:
                    log.write(role, "!", f"{op} not delivered: {exc}")
    finally:
        for sig, h in held.items():
            signal.signal(sig, h)
