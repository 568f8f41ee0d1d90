"""Instruments served on TCP sockets with line-terminated SCPI, for a virtual bench served as a
laboratory's instruments (``gonio bench serve``): header matching in SCPI's short and long
forms (:func:`scpi_match`), one instrument's command table and error queue
(:class:`Instrument`, :class:`ScpiError`), the socket server (:class:`ScpiServer`,
:func:`scpi_handler`), the injected faults of the safety tests (:class:`Faults`,
:class:`DropLink`) and the bench clock a test can hold at a known point (:class:`HeldClock`).
The served rate bench (:mod:`gonio.instruments.served_rate`) and a
specification's own served bench (its ``serve`` hook) are built on these.
"""

from __future__ import annotations

import math
import socket
import socketserver
import threading
import time
from collections import deque
from dataclasses import dataclass, field

from gonio.errors import GonioError


def scpi_match(header: str, mnemonic: str) -> bool:
    """Whether a received header matches a mnemonic in SCPI's short/long forms
    (``SYST:ERR?`` and ``:system:error?`` both match ``SYSTem:ERRor?``).

    >>> scpi_match(":syst:err?", "SYSTem:ERRor?"), scpi_match("SYSTEM:ERROR?", "SYSTem:ERRor?")
    (True, True)
    >>> scpi_match("SYSTE:ERR?", "SYSTem:ERRor?"), scpi_match("SYST:ERR", "SYSTem:ERRor?")
    (False, False)
    """
    h, m = header.lstrip(":"), mnemonic
    if h.endswith("?") != m.endswith("?"):
        return False
    hp, mp = h.rstrip("?").split(":"), m.rstrip("?").split(":")
    if len(hp) != len(mp):
        return False
    for tok, mn in zip(hp, mp):
        short = "".join(c for c in mn if not c.islower())
        if tok.upper() not in (short.upper(), mn.upper()):
            return False
    return True


class ScpiError(Exception):
    """An error the served instrument puts in its queue: ``code,"message"``."""

    def __init__(self, code: int, message: str):
        super().__init__(f'{code},"{message}"')
        self.code = code


class HeldClock:
    """A served bench's wall clock (``time.monotonic`` by default) that can be held: while
    held it stands still, so the bench's simulated time stops and every wait an acquisition
    times on the bench's clock waits on; released, it runs on from where it stood (the time
    held is taken out: the bench sees no gap)."""

    def __init__(self, wall=time.monotonic):
        self.wall = wall
        self._lock = threading.Lock()
        self._held_at: float | None = None
        self._offset = 0.0

    def __call__(self) -> float:
        with self._lock:
            now = self._held_at if self._held_at is not None else self.wall()
            return now - self._offset

    @property
    def held(self) -> bool:
        return self._held_at is not None

    def hold(self) -> None:
        with self._lock:
            if self._held_at is None:
                self._held_at = self.wall()

    def release(self) -> None:
        with self._lock:
            if self._held_at is not None:
                self._offset += self.wall() - self._held_at
                self._held_at = None


@dataclass
class Faults:
    """Injected faults, for tests of an acquisition's safety and interruption:
    ``table-error:N`` (the N-th move of the table answers an axis fault and is not made),
    ``gyro-drop:N`` (the instrument that reads the gyro closes its connection at its N-th
    reading request), ``hold:N`` (once the N-th reading has been answered, the bench's clock
    stops, a :class:`HeldClock`, until the next connection to the instrument that reads the
    gyro: an acquisition held at a known point, never finished before a test interrupts
    it). ``held`` is set and ``on_hold(N)`` called when the clock stops."""

    table_error_at_move: int | None = None
    gyro_drop_at_read: int | None = None
    hold_at_reading: int | None = None
    moves: int = 0
    reads: int = 0
    readings: int = 0
    held: threading.Event = field(default_factory=threading.Event)
    on_hold: object = None

    @classmethod
    def parse(cls, specs: list[str] | None) -> "Faults":
        f = cls()
        for spec in specs or []:
            name, _, n = spec.partition(":")
            if not n.isdigit() or int(n) < 1 or name not in ("table-error", "gyro-drop", "hold"):
                raise GonioError(f"--fault {spec!r}: expected table-error:N, gyro-drop:N or "
                                 "hold:N (N ≥ 1)")
            if name == "table-error":
                f.table_error_at_move = int(n)
            elif name == "gyro-drop":
                f.gyro_drop_at_read = int(n)
            else:
                f.hold_at_reading = int(n)
        return f

    def clock(self, wall):
        """The served bench's wall clock: ``wall`` itself, or a :class:`HeldClock` on it where
        a hold is asked for."""
        if self.hold_at_reading is None or isinstance(wall, HeldClock):
            return wall
        return HeldClock(wall)

    def reading_answered(self, clock) -> None:
        """Count a reading answered (its answer already computed); hold ``clock`` at the
        ``hold:N`` one."""
        self.readings += 1
        if self.readings == self.hold_at_reading and isinstance(clock, HeldClock):
            clock.hold()
            self.held.set()
            if self.on_hold is not None:
                self.on_hold(self.readings)

    @staticmethod
    def connected(clock) -> None:
        """A new connection to the instrument that reads the gyro: a held clock runs on."""
        if isinstance(clock, HeldClock):
            clock.release()


def parse_float(arg: str) -> float:
    try:
        v = float(arg)
    except ValueError:
        raise ScpiError(-104, f"Data type error; {arg!r}") from None
    if not math.isfinite(v):
        raise ScpiError(-224, f"Illegal parameter value; {arg!r}")
    return v


@dataclass
class Instrument:
    """One served instrument: its command table (mnemonic → handler) and error queue."""

    name: str
    idn: str
    commands: list = field(default_factory=list)
    errors: deque = field(default_factory=lambda: deque(maxlen=16))
    #: called when a client connects (None: nothing)
    on_connect: object = None

    def execute(self, line: str) -> str | None:
        """Run one line: commands separated by ``;`` (SCPI's compound form); the answers
        of its queries joined by ``;`` (None when it has none)."""
        answers = [a for a in (self.execute_one(c) for c in line.split(";") if c.strip())
                   if a is not None]
        return ";".join(answers) if answers else None

    def execute_one(self, command: str) -> str | None:
        """Run one command; the answer of a query (None for a command)."""
        header, _, arg = command.strip().partition(" ")
        for mnemonic, handler in self.commands:
            if scpi_match(header, mnemonic):
                try:
                    return handler(arg.strip())
                except ScpiError as exc:
                    self.errors.append(str(exc))
                except (ArithmeticError, ValueError, GonioError) as exc:
                    self.errors.append(f'-300,"Device-specific error; {type(exc).__name__}"')
                return "9.91E+37" if header.endswith("?") else None
        self.errors.append(f'-113,"Undefined header; {header}"')
        return "9.91E+37" if header.endswith("?") else None

    def next_error(self, _arg: str = "") -> str:
        return self.errors.popleft() if self.errors else '0,"No error"'


class DropLink(Exception):
    """Close the connection (an injected fault)."""


def scpi_handler(inst: Instrument):
    class Handler(socketserver.StreamRequestHandler):
        def setup(self):
            super().setup()
            if inst.on_connect is not None:
                inst.on_connect()

        def handle(self):
            try:
                self.serve_lines()
            except ConnectionError:     # the client went away (reset): nothing to answer
                pass

        def serve_lines(self):
            for raw in self.rfile:
                line = raw.decode("ascii", "replace").strip()
                if not line:
                    continue
                try:
                    answer = inst.execute(line)
                except DropLink:
                    return
                if answer is not None:
                    self.wfile.write((answer + "\n").encode("ascii", "replace"))
                    self.wfile.flush()
    return Handler


#: How often a server's loop looks for a request to stop, s (``close`` waits at most this).
POLL_S = 0.05


class ScpiServer(socketserver.ThreadingTCPServer):
    """Every connection in its own daemon thread (an open connection never keeps the process
    from ending); :meth:`serve` is the loop a server thread runs."""

    allow_reuse_address = True
    daemon_threads = True

    def serve(self) -> None:
        self.serve_forever(poll_interval=POLL_S)

    def get_request(self):
        conn, addr = super().get_request()
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return conn, addr
