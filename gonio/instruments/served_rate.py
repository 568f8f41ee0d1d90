"""A rate-gyro bench served as instruments: rate table, gyro output reader, chamber, supply.

``gonio bench serve --bench <rate bench>`` (:func:`serve_rate_bench`) serves, on 127.0.0.1
only, the four instruments a rate specification's programme needs (JJF 1535-2015 Table 2,
IEC 62047-20 5.1.2), each in exactly the command set of its default driver in
:mod:`gonio.instruments.rate`:

- the **rate table** (``ROT``, ``STOP``, ``OSC`` — its sine mode, the angular vibration table —
  ``MOUNT`` — the two-axis position fixture on it — and the queries);
- the **gyro output reader** (a data logger on the gyro's output: ``ACQ:CONF n,interval``,
  ``ACQ:STAR t`` to record from the module time t, ``ACQ:COUN?``, ``ACQ:DATA?``, the gyro's
  temperature sensor, the module clock ``SYST:TIME?``);
- the **chamber** (``TEMP``, ``RAMP``, ``OUTP ON|OFF``, ``MEAS:TEMP?``);
- the **supply** (``VOLT``, ``OUTP ON|OFF``, ``MEAS:VOLT?``).

The physics is the virtual rate bench's own, not a copy: every record is one
:class:`gonio.protocol.programme.Segment` run by :class:`gonio.bench.rate_session.RateSession`
(the recorder ``gonio simulate`` runs the whole programme with), built from the
instruments' state when the record starts — the table's rate or sine, the mounting, the
chamber's set point and ramp, the supply's voltage, the time the supply has been on
(a power cycle when it was switched off and on since the last record) and the simulated
time since the last record (its ``delay_s``). Simulated time runs ``speed`` times faster
than the wall clock; a record's samples are released as their time passes.

``ACQ:STAR t`` with ``t`` already past starts from the reader's pre-trigger buffer, but no
earlier than the last change of the bench's conditions, the end of the last record or the
supply's switching on: a record asked to start at a power-on (``delay_s`` 0, JJF 7.2.9's
warm-up) starts exactly there whatever the host's latency.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field

import numpy as np

from gonio import __version__
from gonio.bench.rate_session import RateSession
from gonio.errors import GonioError
from gonio.instruments.scpi import (DropLink, Faults, Instrument, ScpiError, ScpiServer,
                                   parse_float, scpi_handler)
from gonio.protocol.programme import Segment

#: The served rate table's stated top rate (°/s), acceleration (°/s²) and sine frequency (Hz).
TOP_RATE_DPS = 1500.0
ACCEL_DPS2 = 200.0
TOP_FREQ_HZ = 1000.0
#: The served chamber's stated range (°C).
CHAMBER_RANGE_C = (-70.0, 180.0)
#: The four served instruments, in the order of their ports.
NAMES = ("table", "gyro", "chamber", "supply")
_AXES = ("+x", "-x", "+y", "-y", "+z", "-z")


@dataclass
class _Record:
    """A record in progress: its first sample's module time, interval and the samples
    (module time, output, reference)."""

    start_s: float
    interval_s: float
    t_s: np.ndarray
    output: np.ndarray
    reference: np.ndarray

    def ready(self, now_s: float) -> int:
        """Samples whose interval has passed by ``now_s``."""
        return int(np.clip(math.floor((now_s - self.start_s) / self.interval_s + 1e-9),
                           0, self.t_s.size))


@dataclass
class _Conditions:
    rate_dps: float = 0.0
    freq_hz: float = 0.0
    amplitude_dps: float = 0.0
    up_axis: str = "+z"
    north_axis: str = "+x"
    chamber_on: bool = False
    set_point_c: float = 20.0
    ramp_c_per_min: float = 1.0
    supply_v: float = 0.0
    supply_on: bool = False


@dataclass
class ServedRateBench:
    """The shared state behind the four served instruments (one lock for all)."""

    bench: object
    seed: int = 0
    speed: float = 1.0
    room_c: float = 20.0
    clock: object = time.monotonic
    lock: threading.RLock = field(default_factory=threading.RLock)
    #: injected faults: ``table-error:N`` (the N-th ``ROT`` or ``OSC`` answers an axis fault,
    #: −310, and is not made), ``gyro-drop:N`` (the reader closes its link at its N-th
    #: ``ACQ:DATA?``), ``hold:N`` (the clock stops once the N-th ``ACQ:DATA?`` is answered,
    #: until the next connection to the reader)
    faults: Faults = field(default_factory=Faults)

    def __post_init__(self):
        self.clock = self.faults.clock(self.clock)
        if not (self.speed > 0 and math.isfinite(self.speed)):
            raise GonioError(f"--speed must be a positive number, got {self.speed}")
        self.session = RateSession(self.bench, self.seed, room_temperature_c=self.room_c)
        self.cond = _Conditions(supply_v=float(self.bench.gyro.supply_nominal_v))
        self.config = (0, 0.0)
        self.record: _Record | None = None
        self.wall0 = self.clock()
        self.last_change = self.last_end = 0.0
        self.power_on_at: float | None = None      # a switching on not yet recorded
        self.angle = (0.0, 0.0)                    # (angle at, module time) of the table
        self.chamber_from = (self.room_c, 0.0)     # (temperature, time) the ramp began at

    def now_s(self) -> float:
        return (self.clock() - self.wall0) * self.speed

    # ---------------------------------------------------------------- conditions
    def change(self, *, abort: bool = False, **values) -> None:
        """Change conditions: refused while a record is pending or running, unless
        ``abort`` (a stop, switching the supply or the chamber off: always obeyed), which
        ends the record at the samples taken so far."""
        now = self.now_s()
        r = self.record
        if r is not None and r.ready(now) < r.t_s.size:
            if not abort:
                raise ScpiError(-221, "Settings conflict; a record is running")
            k = r.ready(now)
            self.record = _Record(r.start_s, r.interval_s, r.t_s[:k], r.output[:k],
                                  r.reference[:k])
            self.last_end = max(now, r.start_s)
        if all(getattr(self.cond, k) == v for k, v in values.items()):
            return
        if "rate_dps" in values or "freq_hz" in values:
            self.angle = (self.table_angle_deg(now), now)
        if "set_point_c" in values or "chamber_on" in values:
            self.chamber_from = (self.air_c(now), now)
        if values.get("supply_on") is True and not self.cond.supply_on:
            self.power_on_at = now
        for k, v in values.items():
            setattr(self.cond, k, v)
        self.last_change = now

    def table_angle_deg(self, now: float) -> float:
        a, t0 = self.angle
        return a + (self.cond.rate_dps * (now - t0) if not self.cond.freq_hz else 0.0)

    def table_state(self) -> str:
        c = self.cond
        return "OSC" if c.freq_hz else ("ROT" if c.rate_dps else "IDLE")

    def air_c(self, now: float) -> float:
        """The chamber's air temperature: ramping from where it was to its set point (room
        when off) at the slower of its set ramp and its top ramp."""
        c, ch = self.cond, self.bench.equipment.chamber
        target = c.set_point_c if c.chamber_on else self.room_c
        t0c, t0 = self.chamber_from
        rate = min(c.ramp_c_per_min, ch.max_ramp_c_per_min) / 60.0
        step = rate * max(now - t0, 0.0)
        return target if abs(target - t0c) <= step else t0c + math.copysign(step, target - t0c)

    def supply_measured_v(self) -> float:
        return self.cond.supply_v + self.bench.equipment.supply.error_v if self.cond.supply_on \
            else 0.0

    # ---------------------------------------------------------------- records
    def start(self, at_s: float) -> None:
        """``ACQ:STAR``: record the configured samples from module time ``at_s`` (no earlier
        than the last change, the last record's end or the power-on)."""
        n, dt = self.config
        if n < 1:
            raise ScpiError(-221, "Settings conflict; ACQ:CONF first")
        if not self.cond.supply_on:
            raise ScpiError(-221, "Settings conflict; the gyro is not powered")
        now = self.now_s()
        if self.record is not None and self.record.ready(now) < self.record.t_s.size:
            raise ScpiError(-221, "Settings conflict; a record is running")
        start = max(at_s, self.last_change, self.last_end)
        fresh = self.power_on_at is not None
        origin = self.power_on_at if fresh else self.last_end
        c = self.cond
        seg = Segment("served", 0, 0, "record", n, dt, rate_dps=c.rate_dps if not c.freq_hz else 0.0,
                      up_axis=c.up_axis, north_axis=c.north_axis,
                      temperature_c=c.set_point_c if c.chamber_on else None,
                      ramp_c_per_min=c.ramp_c_per_min, supply_v=c.supply_v, freq_hz=c.freq_hz,
                      vib_amplitude_dps=c.amplitude_dps if c.freq_hz else 0.0,
                      delay_s=max(start - origin, 0.0), power_on=fresh,
                      off_time_s=max(origin - self.last_end, 0.0) if fresh else 0.0)
        cols, _ = self.session.record(seg)
        t = start + dt * np.arange(n)
        self.record = _Record(start, dt, t, np.asarray(cols["output"], float),
                              np.asarray(cols["reference_dps"], float))
        self.power_on_at = None
        self.last_end = start + n * dt

    def data(self, first: int, count: int) -> str:
        r = self.record
        if r is None:
            raise ScpiError(-230, "Data stale; no record")
        ready = r.ready(self.now_s())
        if first < 0 or count < 1 or first + count > ready:
            raise ScpiError(-222, f"Data out of range; samples {first}..{first + count - 1} "
                                  f"of {ready} ready")
        sl = slice(first, first + count)
        return ",".join(f"{t!r},{o!r},{f!r}" for t, o, f in
                        zip(r.t_s[sl].tolist(), r.output[sl].tolist(), r.reference[sl].tolist()))


def _ints(arg: str, n: int) -> list[int]:
    parts = [p.strip() for p in arg.split(",")]
    if len(parts) != n:
        raise ScpiError(-109, f"Missing parameter; expected {n}")
    try:
        return [int(p) for p in parts]
    except ValueError:
        raise ScpiError(-104, f"Data type error; {arg!r}") from None


def _on_off(arg: str) -> bool:
    a = arg.strip().upper()
    if a not in ("ON", "OFF", "1", "0"):
        raise ScpiError(-224, f"Illegal parameter value; {arg}")
    return a in ("ON", "1")


def _common(inst: Instrument, reset) -> list:
    return [("*IDN?", lambda a: inst.idn), ("*RST", reset), ("*CLS", lambda a: inst.errors.clear()),
            ("*OPC?", lambda a: "1"), ("SYSTem:ERRor?", inst.next_error)]


def rate_instruments(sb: ServedRateBench) -> list[Instrument]:
    """The four served instruments (:data:`NAMES`), sharing ``sb``."""
    return [_table(sb), _gyro(sb), _chamber(sb), _supply(sb)]


def _locked(sb: ServedRateBench, f):
    def run(arg):
        with sb.lock:
            return f(arg)
    return run


def _table(sb: ServedRateBench) -> Instrument:
    """The rate table: :class:`gonio.instruments.rate.RateTable`'s commands."""
    b = sb.bench

    def locked(f):
        return _locked(sb, f)

    def motion_fault():
        sb.faults.moves += 1
        if sb.faults.table_error_at_move == sb.faults.moves:
            raise ScpiError(-310, "System error; axis fault (injected)")

    def rotate(arg):
        motion_fault()
        w = parse_float(arg)
        if abs(w) > TOP_RATE_DPS:
            raise ScpiError(-222, f"Data out of range; rate {w:g} beyond {TOP_RATE_DPS:g}")
        sb.change(rate_dps=w, freq_hz=0.0, amplitude_dps=0.0)

    def oscillate(arg):
        parts = arg.split(",")
        if len(parts) != 2:
            raise ScpiError(-109, "Missing parameter; OSC freq,amplitude")
        motion_fault()
        f, a = (parse_float(x) for x in parts)
        if not 0 < f <= TOP_FREQ_HZ or not 0 < a <= TOP_RATE_DPS:
            raise ScpiError(-222, f"Data out of range; OSC {f:g},{a:g}")
        sb.change(rate_dps=0.0, freq_hz=f, amplitude_dps=a)

    def mount(arg):
        parts = [p.strip().lower() for p in arg.split(",")]
        if len(parts) != 2 or any(p not in _AXES for p in parts) or parts[0][1] == parts[1][1]:
            raise ScpiError(-224, f"Illegal parameter value; MOUNT {arg}")
        sb.change(up_axis=parts[0], north_axis=parts[1])

    table = Instrument("table", f"gonio,virtual rate table,{b.name}-table,gonio {__version__}")
    stop = locked(lambda a: sb.change(abort=True, rate_dps=0.0, freq_hz=0.0, amplitude_dps=0.0))
    table.commands = _common(table, stop) + [
        ("ROTate", locked(rotate)), ("STOP", stop), ("OSCillate", locked(oscillate)),
        ("MOUNT", locked(mount)),
        ("MOUNT?", lambda a: f"{sb.cond.up_axis},{sb.cond.north_axis}"),
        ("RATE?", lambda a: repr(sb.cond.rate_dps)),
        ("POSition?", locked(lambda a: repr(sb.table_angle_deg(sb.now_s()) % 360.0))),
        ("STATe?", lambda a: sb.table_state()),
        ("LIMit:POSition?", lambda a: "-inf,inf"),
        ("LIMit:RATE?", lambda a: repr(TOP_RATE_DPS)), ("LIMit:ACCeleration?", lambda a: repr(ACCEL_DPS2)),
        ("LIMit:FREQuency?", lambda a: repr(TOP_FREQ_HZ)),
    ]
    return table


def _gyro(sb: ServedRateBench) -> Instrument:
    """The gyro output reader: :class:`gonio.instruments.rate.GyroOutput`'s commands."""
    b, g = sb.bench, sb.bench.gyro

    def locked(f):
        return _locked(sb, f)

    def data(arg):
        sb.faults.reads += 1
        if sb.faults.gyro_drop_at_read == sb.faults.reads:
            raise DropLink()
        answer = sb.data(*_ints(arg, 2))
        sb.faults.reading_answered(sb.clock)
        return answer

    def configure(arg):
        parts = arg.split(",")
        if len(parts) != 2:
            raise ScpiError(-109, "Missing parameter; ACQ:CONF samples,interval")
        n, dt = _ints(parts[0], 1)[0], parse_float(parts[1])
        if n < 1 or not dt > 0:
            raise ScpiError(-222, f"Data out of range; ACQ:CONF {arg}")
        sb.config = (n, dt)

    gyro = Instrument("gyro", f"{g.manufacturer or 'gonio'},{g.model or g.name},"
                               f"{g.serial or b.name},gonio {__version__}")
    gyro.commands = _common(gyro, lambda a: None) + [
        ("SYSTem:TIME?", lambda a: repr(sb.now_s())),
        ("ACQuire:CONFigure", locked(configure)),
        ("ACQuire:STARt", locked(lambda a: sb.start(parse_float(a)))),
        ("ACQuire:COUNt?", locked(lambda a: str(sb.record.ready(sb.now_s()) if sb.record else 0))),
        ("ACQuire:DATA?", locked(data)),
        ("MEASure:TEMPerature?", locked(lambda a: repr(sb.session.st.temp))),
        ("CONFigure:UNIT?", lambda a: g.output_unit),
        ("CONFigure:SCALe?", lambda a: repr(g.scale_factor)),
        ("CONFigure:NULL?", lambda a: repr(g.null_output)),
    ]
    gyro.on_connect = lambda: Faults.connected(sb.clock)
    return gyro


def _chamber(sb: ServedRateBench) -> Instrument:
    """The chamber: :class:`gonio.instruments.rate.Chamber`'s commands."""
    b = sb.bench

    def locked(f):
        return _locked(sb, f)

    def set_point(arg):
        c = parse_float(arg)
        if not CHAMBER_RANGE_C[0] <= c <= CHAMBER_RANGE_C[1]:
            raise ScpiError(-222, f"Data out of range; TEMP {c:g}")
        sb.change(set_point_c=c, chamber_on=True)

    def ramp(arg):
        r = parse_float(arg)
        if not r > 0:
            raise ScpiError(-222, f"Data out of range; RAMP {r:g}")
        sb.change(ramp_c_per_min=r)

    ch = b.equipment.chamber
    chamber = Instrument("chamber", f"gonio,virtual chamber,{b.name}-chamber,gonio {__version__}")
    chamber.commands = _common(chamber, locked(lambda a: sb.change(abort=True,
                                                                    chamber_on=False))) + [
        ("TEMPerature", locked(set_point)), ("TEMPerature?", lambda a: repr(sb.cond.set_point_c)),
        ("RAMP", locked(ramp)), ("RAMP?", lambda a: repr(sb.cond.ramp_c_per_min)),
        ("OUTPut", locked(lambda a: sb.change(abort=not _on_off(a), chamber_on=_on_off(a)))),
        ("OUTPut?", lambda a: "1" if sb.cond.chamber_on else "0"),
        ("MEASure:TEMPerature?", locked(lambda a: repr(sb.air_c(sb.now_s())))),
        ("LIMit:TEMPerature?", lambda a: f"{CHAMBER_RANGE_C[0]!r},{CHAMBER_RANGE_C[1]!r}"),
        ("LIMit:RAMP?", lambda a: repr(ch.max_ramp_c_per_min)),
    ]
    return chamber


def _supply(sb: ServedRateBench) -> Instrument:
    """The supply: :class:`gonio.instruments.rate.Supply`'s commands."""
    b = sb.bench

    def locked(f):
        return _locked(sb, f)

    def volt(arg):
        v = parse_float(arg)
        if not 0 <= v <= 60:
            raise ScpiError(-222, f"Data out of range; VOLT {v:g}")
        sb.change(supply_v=v)

    supply = Instrument("supply", f"gonio,virtual supply,{b.name}-supply,gonio {__version__}")
    supply.commands = _common(supply, locked(lambda a: sb.change(abort=True,
                                                                  supply_on=False))) + [
        ("VOLTage", locked(volt)), ("VOLTage?", lambda a: repr(sb.cond.supply_v)),
        ("OUTPut", locked(lambda a: sb.change(abort=not _on_off(a), supply_on=_on_off(a)))),
        ("OUTPut?", lambda a: "1" if sb.cond.supply_on else "0"),
        ("MEASure:VOLTage?", locked(lambda a: repr(sb.supply_measured_v()))),
    ]
    return supply


@dataclass
class ServedRate:
    """The running servers: ports and VISA resource strings by name, and ``close``."""

    bench: ServedRateBench
    servers: dict
    threads: list

    def port(self, name: str) -> int:
        return self.servers[name].server_address[1]

    def resource(self, name: str) -> str:
        return f"TCPIP0::127.0.0.1::{self.port(name)}::SOCKET"

    @property
    def resources(self) -> dict[str, str]:
        return {n: self.resource(n) for n in self.servers}

    def close(self) -> None:
        for s in self.servers.values():
            s.shutdown()
            s.server_close()


def serve_rate_bench(bench, ports: dict[str, int] | None = None, *, speed: float = 1.0,
                     seed: int = 0, room_temperature_c: float = 20.0,
                     faults: Faults | None = None) -> ServedRate:
    """Serve the rate ``bench``'s four instruments on 127.0.0.1 (``ports`` by name; 0 or
    absent: a free one) in background threads; ``close()`` stops them. ``faults``: see
    :class:`ServedRateBench`."""
    sb = ServedRateBench(bench, seed=seed, speed=speed, room_c=room_temperature_c,
                         faults=faults or Faults())
    servers, threads = {}, []
    for inst in rate_instruments(sb):
        port = int((ports or {}).get(inst.name) or 0)
        try:
            srv = ScpiServer(("127.0.0.1", port), scpi_handler(inst))
        except OSError as exc:
            for s in servers.values():
                s.server_close()
            raise GonioError(f"cannot serve the {inst.name} on 127.0.0.1:{port}: "
                             f"{exc.strerror or exc}") from None
        th = threading.Thread(target=srv.serve, name=f"serve-{inst.name}", daemon=True)
        th.start()
        servers[inst.name] = srv
        threads.append(th)
    return ServedRate(sb, servers, threads)
