"""The virtual bench served as instruments: a rotary table and an acquisition module on TCP.

``gonio bench serve`` (the optical draft's ``serve`` hook, :func:`serve`; :func:`serve_bench`) serves, on 127.0.0.1 only, the simulated table and
the goniometer's acquisition module of a bench file over line-terminated SCPI sockets, in
exactly the command sets of the default drivers (:class:`~gonio.instruments.table.RotaryTable`,
:class:`~gonio.specs.ogam_draft.acquisition_module.AcquisitionModule`), with their errors in
the SCPI
error queue (``SYST:ERR?``): a move beyond the range or the top rate (−222), a move while
moving or a read before zeroing (−221), an unknown header (−113), a bad parameter (−224).

The physics is the virtual bench's own, not a copy: the table's motion is a
:class:`gonio.physics.kinematics.Timeline` built as the commands arrive (a stop mid-move
replays it with the move cut to its stopping distance, so the motion already integrated is
unchanged), its positioning error the bench's harmonics and scatter; the instrument is the
bench's :class:`gonio.specs.ogam_draft.bench.instrument.Integrator` on its sample grid, its counter
:func:`gonio.specs.ogam_draft.bench.instrument.counts_from_angle` with the same dither and the
angle-position error of the angle since the zeroing (draft 4.2), its random streams seeded
as :func:`gonio.specs.ogam_draft.bench.session.run_session` seeds them. Simulated time runs ``speed`` times
faster than the wall clock; the instrument is integrated lazily up to the instant of each
query. The readings therefore agree with ``gonio simulate`` on the same bench within the
noise (not bit for bit: the timing of a served session is the host's).

Fault injection for tests of the acquisition's safety (``faults``): ``table-error:N`` (the
N-th move answers an axis fault, −310, and is not made), ``gyro-drop:N`` (the module closes
its connection at its N-th reading request, ``READ?`` or ``FETC?``).
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field

import numpy as np

from gonio import __version__
from gonio.specs.ogam_draft.bench.config import Bench
from gonio.specs.ogam_draft.bench.instrument import Integrator, counts_from_angle, geometry, harmonic_sum_arcsec
from gonio.errors import GonioError
from gonio.instruments.scpi import (DropLink, Faults, Instrument, ScpiError, ScpiServer, parse_float,
                                   scpi_handler)
from gonio.formats.counters import wrap_counter
from gonio.physics.earth import NAMED_AXES
from gonio.physics.kinematics import Timeline
from gonio.units import S_PER_H, arcsec_to_deg

#: Samples integrated per call of the instrument model (bounded memory for long waits).
CHUNK = 1 << 18
#: The draft's Table 2 reference room, °C: the module reports it plus the bench's chamber
#: deviation (``[chamber] deviation_c``), at which the instrument's K and bias are taken.
ROOM_C = 20.0
#: Samples the background integration takes per hold of the lock.
KEEP_UP_SAMPLES = 1 << 14
#: Wall seconds a ``FETC?`` waits for its trigger before answering −230 (the host asks again).
FETCH_WAIT_S = 1.0


@dataclass
class _Zero:
    k: int
    phi_deg: float
    counts: float


@dataclass
class _Trigger:
    """The module's trigger: ``EXT`` is the table's in-position signal (the end of a move),
    the reading taken ``delay_s`` after it on the sample grid; ``k`` its sample once known,
    ``reading`` (counts since zeroing, time since zeroing) once taken."""

    source: str = "BUS"
    delay_s: float = 0.0
    armed: bool = False
    k: int | None = None
    reading: tuple | None = None


class ServedBench:
    """The shared simulated state behind both served instruments (one lock for all).

    ``range_deg``: the table's stated range, [−range_deg, +range_deg]. ``warm_up_s``: how
    long the instrument has been on when serving starts (its warm-up transient and its
    clock, ``SYST:TIME?``, count from power-on).
    """

    def __init__(self, bench: Bench, *, seed: int = 0, speed: float = 1.0,
                 warm_up_s: float = S_PER_H, range_deg: float = 360.0, clock=time.monotonic,
                 faults: Faults | None = None):
        if not (speed > 0 and math.isfinite(speed)):
            raise GonioError(f"--speed must be a positive number, got {speed}")
        bench = bench.at_chamber_temperature()        # the instrument in the chamber
        self.bench, self.speed, self.warm_up_s, self.range_deg = bench, speed, warm_up_s, range_deg
        self.faults = faults or Faults()
        self.clock = self.faults.clock(clock)
        ss = np.random.SeedSequence(seed)
        self.rng_table, rng_inst = (np.random.default_rng(s) for s in ss.spawn(2))
        self.dither_key = int(ss.generate_state(1, np.uint64)[0])
        self.dt = 1.0 / bench.sample_rate_hz
        self.integ = Integrator(bench.instrument, bench.sample_rate_hz, warm_up_s, rng_inst)
        self.lock = threading.RLock()
        self.start_true_deg = self.true_position(0.0)
        self.ops: list[tuple] = []
        self.timeline = Timeline(start_angle_deg=self.start_true_deg)
        self.indicated_deg = 0.0
        self.rotating = False
        self.orientation = "up"
        self.geom = geometry(bench, "up")
        self.k_done, self.phi_deg = -1, 0.0
        self.zero: _Zero | None = None
        self.trigger = _Trigger()
        self.wall0 = clock()

    # ------------------------------------------------------------------ time, table
    def now_s(self) -> float:
        """Simulated time since serving started, s."""
        return (self.clock() - self.wall0) * self.speed

    def true_position(self, x_deg: float) -> float:
        """The true angle of the table when it indicates ``x_deg`` (the bench's positioning
        harmonics plus its random scatter, as the virtual bench's planner draws them)."""
        tab = self.bench.table
        err = float(harmonic_sum_arcsec(np.array([x_deg]), tab.positioning_harmonics)[0])
        if tab.positioning_random_arcsec:
            err += tab.positioning_random_arcsec * float(self.rng_table.standard_normal())
        return x_deg - arcsec_to_deg(err)

    def moving(self, t: float) -> bool:
        return t < self.timeline.end_s

    def _extend_to(self, t: float) -> None:
        if self.timeline.end_s < t:
            d = t - self.timeline.end_s
            self.timeline.dwell(d)
            self.ops.append(("dwell", d))

    def move(self, x_deg: float, rate_dps: float) -> None:
        """Start a move to the indicated angle ``x_deg`` now (checked: range, rate, at rest)."""
        t = self.now_s()
        tab = self.bench.table
        if self.moving(t):
            raise ScpiError(-221, "Settings conflict; table moving")
        if not -self.range_deg <= x_deg <= self.range_deg:
            raise ScpiError(-222, f"Data out of range; angle {x_deg:g} beyond +/-{self.range_deg:g}")
        if not 0.0 < rate_dps <= tab.max_rate_dps:
            raise ScpiError(-222, f"Data out of range; rate {rate_dps:g} beyond {tab.max_rate_dps:g}")
        self._advance(t)
        self._extend_to(t)
        to = self.true_position(x_deg)
        rate = rate_dps * (1.0 + tab.rate_error_rel)
        self.timeline.move(to, rate, tab.accel_dps2)
        self.ops.append(("move", to, rate, tab.accel_dps2))
        self.indicated_deg, self.rotating = x_deg, False
        self._schedule_trigger()

    def _schedule_trigger(self, moving: bool = True) -> None:
        """An armed external trigger fires at the end of the move just commanded (or in
        progress when armed: ``moving``)."""
        tr = self.trigger
        if tr.armed and tr.k is None and moving:
            tr.k = max(int(math.ceil((self.timeline.end_s + tr.delay_s) / self.dt - 1e-9)),
                       self.k_done + 1)

    def arm(self) -> None:
        """``INIT``: take the next reading on the trigger (EXT: the next arrival + delay)."""
        if self.trigger.source != "EXT":
            raise ScpiError(-221, "Settings conflict; INIT needs TRIG:SOUR EXT")
        self.trigger.armed, self.trigger.k, self.trigger.reading = True, None, None
        self._schedule_trigger(self.moving(self.now_s()))

    def fetch(self, wait_s: float) -> tuple[float, float] | None:
        """``FETC?``: the triggered reading (wrapped counts, time since zeroing), waiting up
        to ``wait_s`` of wall time for it; None while it is still to come."""
        tr = self.trigger
        if not tr.armed:
            raise ScpiError(-221, "Settings conflict; FETC? before INIT")
        if self.zero is None:
            raise ScpiError(-221, "Settings conflict; read before zeroing")
        deadline = time.monotonic() + wait_s
        while True:
            with self.lock:
                if tr.k is not None:
                    t_k = tr.k * self.dt
                    if self.now_s() >= t_k:
                        self._advance(t_k + 0.5 * self.dt)
                        if tr.reading is not None:
                            return tr.reading
                left = (tr.k * self.dt - self.now_s()) / self.speed if tr.k is not None else 0.05
            if time.monotonic() >= deadline:
                return None
            time.sleep(min(max(left, 1e-4), 0.05, max(deadline - time.monotonic(), 0.0)))

    def rotate(self, rate_dps: float) -> None:
        """Rate mode: turn at the signed ``rate_dps`` until stopped (a move far away)."""
        t = self.now_s()
        tab = self.bench.table
        if self.moving(t):
            raise ScpiError(-221, "Settings conflict; table moving")
        if not 0.0 < abs(rate_dps) <= tab.max_rate_dps:
            raise ScpiError(-222, f"Data out of range; rate {rate_dps:g}")
        self._advance(t)
        self._extend_to(t)
        rate = abs(rate_dps) * (1.0 + tab.rate_error_rel)
        to = self.timeline.end_angle_deg + math.copysign(rate * 1e6, rate_dps)
        self.timeline.move(to, rate, tab.accel_dps2)
        self.ops.append(("move", to, rate, tab.accel_dps2))
        self.rotating = True

    def stop(self) -> None:
        """Stop now: the move in progress is cut to its stopping distance at the table's
        acceleration; the motion up to now is unchanged (same trapezoid so far)."""
        t = self.now_s()
        if not self.moving(t):
            return
        self._advance(t)
        theta = float(self.timeline.angle_deg(np.array([t]))[0])
        v = float(self.timeline.rate_dps(np.array([t]))[0])
        _, to, rate, acc = self.ops[-1]
        stop_at = theta + math.copysign(v * v / (2.0 * acc), v) if v else theta
        if abs(to - theta) > abs(stop_at - theta) + 1e-12:      # not yet decelerating
            self.ops[-1] = ("move", stop_at, rate, acc)
            tl = Timeline(start_angle_deg=self.start_true_deg)
            for op in self.ops:
                tl.dwell(op[1]) if op[0] == "dwell" else tl.move(*op[1:])
            self.timeline = tl
            x = self.ops[-1][1]
            self.indicated_deg = x + arcsec_to_deg(float(harmonic_sum_arcsec(
                np.array([x]), self.bench.table.positioning_harmonics)[0]))
        self.rotating = False

    def position_deg(self) -> float:
        """The encoder's indicated angle (the commanded angle at rest)."""
        t = self.now_s()
        if not self.moving(t):
            return self.indicated_deg
        th = float(self.timeline.angle_deg(np.array([t]))[0])
        return th + arcsec_to_deg(float(harmonic_sum_arcsec(
            np.array([th]), self.bench.table.positioning_harmonics)[0]))

    def state(self) -> str:
        t = self.now_s()
        if not self.moving(t):
            return "IDLE"
        return "ROT" if self.rotating else "MOV"

    def set_axis(self, orientation: str) -> None:
        if orientation not in NAMED_AXES:
            raise ScpiError(-224, f"Illegal parameter value; axis {orientation}")
        t = self.now_s()
        if self.moving(t):
            raise ScpiError(-221, "Settings conflict; table moving")
        self._advance(t)
        self.orientation, self.geom = orientation, geometry(self.bench, orientation)
        self.integ.start_block()

    # ------------------------------------------------------------------ instrument
    def _motion_runs(self, ts: np.ndarray):
        """Table angle and rate on runs of samples (:meth:`Integrator.rates`' form): a sample
        inside a move is its own run, the samples of a rest one run (one angle)."""
        segs = self.timeline.segments()
        spans = np.array([(g.t0_s, g.t0_s + g.duration_s) for g in segs if g.distance_deg],
                         dtype=np.float64).reshape(-1, 2)
        spans = spans[(spans[:, 1] >= ts[0]) & (spans[:, 0] <= ts[-1])]
        edge = np.zeros(ts.size + 1, dtype=np.int64)
        np.add.at(edge, np.searchsorted(ts, spans[:, 0], side="left"), 1)
        np.add.at(edge, np.searchsorted(ts, spans[:, 1], side="right"), -1)
        moving = np.cumsum(edge[:-1]) > 0
        first = np.ones(ts.size, dtype=bool)
        first[1:] = moving[1:] | moving[:-1]
        idx = np.flatnonzero(first)
        te = ts[idx]
        return self.timeline.angle_deg(te), self.timeline.rate_dps(te), np.diff(np.append(idx, ts.size))

    def _advance(self, t: float) -> int:
        """Integrate the instrument up to the last grid sample at or before ``t``."""
        k_end = int(math.floor(t / self.dt + 1e-9))
        while self.k_done < k_end:
            a = self.k_done + 1
            b = min(k_end, a + CHUNK - 1)
            ts = np.arange(a, b + 1) * self.dt
            theta_u, rate_u, rep = self._motion_runs(ts)
            det = self.integ.rates(ts, theta_u, rate_u, rep, self.geom)
            phi = self.integ.integrate(det, np.repeat(theta_u, rep))
            self.k_done, self.phi_deg = b, float(phi[-1])
            tr = self.trigger
            if (tr.armed and tr.k is not None and a <= tr.k <= b and tr.reading is None
                    and self.zero is not None):
                tr.reading = self._since_zero(tr.k, float(phi[tr.k - a]), wrap=True)
        return k_end

    def keep_up(self, stop: threading.Event, period_s: float = 0.005) -> None:
        """Integrate in the background up to now every ``period_s`` of wall time, so that a
        query finds the instrument integrated but for its last few samples (its answer's
        latency does not grow with the time since the previous query)."""
        while not stop.wait(period_s):
            behind = True
            while behind and not stop.is_set():
                with self.lock:             # a short hold at a time: queries get in between
                    t = self.now_s()
                    step = min(t, (self.k_done + KEEP_UP_SAMPLES) * self.dt)
                    self._advance(step)
                    behind = step < t

    def _counts(self, k: int, phi: float) -> float:
        """The counter at sample k: angle plus the angle-position error of the angle since
        the zeroing, g(φ−φ₀) − g(0) (draft 4.2), times K, dithered and floored."""
        inst = self.bench.instrument
        g = 0.0
        if self.zero is not None and inst.position_harmonics:
            g = float(harmonic_sum_arcsec(np.array([phi - self.zero.phi_deg]),
                                          inst.position_harmonics)[0]
                      - harmonic_sum_arcsec(np.zeros(1), inst.position_harmonics)[0])
        return float(counts_from_angle(np.array([phi + arcsec_to_deg(g)]), inst,
                                       np.array([k]), self.dither_key)[0])

    def do_zero(self) -> None:
        k = self._advance(self.now_s())
        self.zero = _Zero(k, self.phi_deg, 0.0)
        self.zero.counts = self._counts(k, self.phi_deg)

    def read(self, wrap: bool = True) -> tuple[float, float]:
        """Counts since the zeroing (as the register shows them with ``wrap``) and the time
        since it, now."""
        if self.zero is None:
            raise ScpiError(-221, "Settings conflict; read before zeroing")
        k = self._advance(self.now_s())
        return self._since_zero(k, self.phi_deg, wrap)

    def _since_zero(self, k: int, phi: float, wrap: bool) -> tuple[float, float]:
        inst = self.bench.instrument
        c = self._counts(k, phi) - self.zero.counts
        if inst.quantisation and wrap:
            c = float(wrap_counter(np.array([int(c)]), inst.counter_bits, inst.counter_signed)[0])
        return c, (k - self.zero.k) * self.dt

    def rate_dps(self) -> float:
        """The sensed rate now: the table's rate on the tilted axis plus the Earth rate."""
        t = self.now_s()
        th = self.timeline.angle_deg(np.array([t]))
        w = self.timeline.rate_dps(np.array([t])) * self.geom.cos_psi + self.geom.earth_dps(th)
        return float(w[0])


def table_instrument(sb: ServedBench) -> Instrument:
    """The served rotary table: :class:`~gonio.instruments.table.RotaryTable`'s commands."""
    b = sb.bench

    def locked(f):
        def g(arg):
            with sb.lock:
                return f(arg)
        return g

    def move(arg):
        parts = arg.split(",")
        if len(parts) != 2:
            raise ScpiError(-109, "Missing parameter; MOVE:ABS angle,rate")
        sb.faults.moves += 1
        if sb.faults.table_error_at_move == sb.faults.moves:
            raise ScpiError(-310, "System error; axis fault (injected)")
        sb.move(parse_float(parts[0]), parse_float(parts[1]))

    def opc(_):
        while True:
            with sb.lock:
                left = sb.timeline.end_s - sb.now_s()
                if left <= 0 or sb.rotating:
                    return "1"
            time.sleep(min(left / sb.speed, 0.05))

    inst = Instrument("table", f"gonio,virtual rotary table ({b.table.name}),"
                                f"{b.name}-table,gonio {__version__}")
    inst.commands = [
        ("*IDN?", lambda a: inst.idn), ("*RST", locked(lambda a: sb.stop())),
        ("*CLS", lambda a: inst.errors.clear()), ("*OPC?", opc),
        ("SYSTem:ERRor?", inst.next_error),
        ("MOVE:ABSolute", locked(move)),
        ("ROTate", locked(lambda a: sb.rotate(parse_float(a)))),
        ("STOP", locked(lambda a: sb.stop())),
        ("POSition?", locked(lambda a: repr(sb.position_deg()))),
        ("STATe?", locked(lambda a: sb.state())),
        ("AXIS", locked(lambda a: sb.set_axis(a.strip().lower()))),
        ("AXIS?", lambda a: sb.orientation),
        ("LIMit:POSition?", lambda a: f"{-sb.range_deg!r},{sb.range_deg!r}"),
        ("LIMit:RATE?", lambda a: repr(b.table.max_rate_dps)),
        ("LIMit:ACCeleration?", lambda a: repr(b.table.accel_dps2)),
    ]
    return inst


def gyro_instrument(sb: ServedBench) -> Instrument:
    """The served acquisition module: the command set of
    :class:`~gonio.specs.ogam_draft.acquisition_module.AcquisitionModule`."""
    b, inst_cfg = sb.bench, sb.bench.instrument

    def count_read():
        with sb.lock:
            sb.faults.reads += 1
            if sb.faults.gyro_drop_at_read == sb.faults.reads:
                raise DropLink()

    def read(_):
        count_read()
        with sb.lock:
            c, t = sb.read()
            sb.faults.reading_answered(sb.clock)
        return f"{c:.0f},{t!r}" if inst_cfg.quantisation else f"{c!r},{t!r}"

    def read_angle(_):
        with sb.lock:
            c, t = sb.read(wrap=False)
        return f"{c / inst_cfg.nominal_scale_factor_counts_per_deg!r},{t!r}"

    def trig(arg):
        if arg.upper() not in ("BUS", "EXT", "EXTERNAL"):
            raise ScpiError(-224, f"Illegal parameter value; {arg}")
        sb.trigger.source = arg.upper()[:3]

    def delay(arg):
        d = parse_float(arg)
        if d < 0:
            raise ScpiError(-222, f"Data out of range; delay {d:g}")
        sb.trigger.delay_s = d

    def fetch(_):
        count_read()
        got = sb.fetch(FETCH_WAIT_S)
        if got is None:
            raise ScpiError(-230, "Data stale; trigger pending")
        with sb.lock:
            sb.faults.reading_answered(sb.clock)
        c, t = got
        return f"{c:.0f},{t!r}" if inst_cfg.quantisation else f"{c!r},{t!r}"

    def locked(f):
        def g(arg):
            with sb.lock:
                return f(arg)
        return g

    inst = Instrument("gyro", f"{inst_cfg.manufacturer or 'gonio'},{inst_cfg.name},"
                               f"{inst_cfg.serial or b.name},gonio {__version__}")
    inst.commands = [
        ("*IDN?", lambda a: inst.idn), ("*RST", lambda a: None),
        ("*CLS", lambda a: inst.errors.clear()), ("*OPC?", lambda a: "1"),
        ("SYSTem:ERRor?", inst.next_error),
        ("SYSTem:TIME?", lambda a: repr(sb.warm_up_s + sb.now_s())),
        ("ZERO", locked(lambda a: sb.do_zero())),
        ("READ?", read), ("READ:ANGle?", read_angle),
        ("MEASure:RATE?", locked(lambda a: repr(sb.rate_dps()))),
        ("MEASure:TEMPerature?", lambda a: repr(ROOM_C + b.chamber_deviation_c)),
        ("CONFigure:COUNter:BITS?", lambda a: str(inst_cfg.counter_bits)),
        ("CONFigure:COUNter:SIGN?", lambda a: "1" if inst_cfg.counter_signed else "0"),
        ("CONFigure:SCALe?", lambda a: repr(inst_cfg.nominal_scale_factor_counts_per_deg)),
        ("TRIGger:SOURce", locked(trig)), ("TRIGger:DELay", locked(delay)),
        ("INITiate", locked(lambda a: sb.arm())), ("FETCh?", fetch),
    ]
    inst.on_connect = lambda: Faults.connected(sb.clock)
    return inst


@dataclass
class Served:
    """The running servers: their ports, VISA resource strings and ``close``."""

    bench: ServedBench
    servers: list
    threads: list
    stop: threading.Event = field(default_factory=threading.Event)

    @property
    def table_port(self) -> int:
        return self.servers[0].server_address[1]

    @property
    def gyro_port(self) -> int:
        return self.servers[1].server_address[1]

    @property
    def table_resource(self) -> str:
        return f"TCPIP0::127.0.0.1::{self.table_port}::SOCKET"

    @property
    def gyro_resource(self) -> str:
        return f"TCPIP0::127.0.0.1::{self.gyro_port}::SOCKET"

    @property
    def resources(self) -> dict[str, str]:
        """The VISA resource strings by role (``table``, ``gyro``)."""
        return {"table": self.table_resource, "gyro": self.gyro_resource}

    def close(self) -> None:
        self.stop.set()
        for s in self.servers:
            s.shutdown()
            s.server_close()


def serve_bench(bench: Bench, table_port: int = 0, gyro_port: int = 0, *, speed: float = 1.0,
                seed: int = 0, range_deg: float = 360.0, warm_up_s: float = S_PER_H,
                faults: Faults | None = None) -> Served:
    """Serve ``bench``'s table and acquisition module on 127.0.0.1 (port 0: a free one) in
    background threads; returns the :class:`Served` (``close()`` stops them)."""
    sb = ServedBench(bench, seed=seed, speed=speed, range_deg=range_deg, warm_up_s=warm_up_s,
                     faults=faults)
    servers, threads = [], []
    for port, inst in ((table_port, table_instrument(sb)), (gyro_port, gyro_instrument(sb))):
        try:
            srv = ScpiServer(("127.0.0.1", port), scpi_handler(inst))
        except OSError as exc:
            for s in servers:
                s.server_close()
            raise GonioError(f"cannot serve the {inst.name} on 127.0.0.1:{port}: "
                             f"{exc.strerror or exc}") from None
        th = threading.Thread(target=srv.serve, name=f"serve-{inst.name}", daemon=True)
        th.start()
        servers.append(srv)
        threads.append(th)
    served = Served(sb, servers, threads)
    th = threading.Thread(target=sb.keep_up, args=(served.stop,), name="serve-integrate",
                          daemon=True)
    th.start()
    threads.append(th)
    return served


def serve(bench: str, ports: dict, *, speed: float = 1.0, seed: int = 0,
          faults: Faults | None = None, range_deg: float = 360.0,
          warm_up_s: float = S_PER_H) -> Served:
    """The ``serve`` hook (``gonio bench serve``): the bench file or built-in name ``bench``
    served by :func:`serve_bench` on the TCP ports of ``ports`` (by role, ``table`` and
    ``gyro``; 0 or absent: a free one)."""
    from gonio.specs.ogam_draft.bench import load_bench

    return serve_bench(load_bench(bench), ports.get("table") or 0, ports.get("gyro") or 0,
                       speed=speed, seed=seed, range_deg=range_deg, warm_up_s=warm_up_s,
                       faults=faults)
