"""Instruments served on TCP sockets with line-terminated SCPI, for a virtual bench served as a
laboratory's instruments (``gonio bench serve``): header matching in SCPI's short and long
forms (:func:`scpi_match`), one instrument's command table and error queue
(:class:`Instrument`, :class:`ScpiError`), the socket server (:class:`ScpiServer`,
:func:`scpi_handler`) and the injected faults of the safety tests (:class:`Faults`,
:class:`DropLink`). The served rate bench (:mod:`gonio.instruments.served_rate`) and a
specification's own served bench (its ``serve`` hook) are built on these.
"""

from __future__ import annotations

import math
import socket
import socketserver
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


@dataclass
class Faults:
    """Injected faults, for tests of an acquisition's safety: ``table-error:N`` (the N-th move
    of the table answers an axis fault and is not made), ``gyro-drop:N`` (the instrument that
    reads the gyro closes its connection at its N-th reading request)."""

    table_error_at_move: int | None = None
    gyro_drop_at_read: int | None = None
    moves: int = 0
    reads: int = 0

    @classmethod
    def parse(cls, specs: list[str] | None) -> "Faults":
        f = cls()
        for spec in specs or []:
            name, _, n = spec.partition(":")
            if not n.isdigit() or int(n) < 1 or name not in ("table-error", "gyro-drop"):
                raise GonioError(f"--fault {spec!r}: expected table-error:N or gyro-drop:N "
                                 "(N ≥ 1)")
            if name == "table-error":
                f.table_error_at_move = int(n)
            else:
                f.gyro_drop_at_read = int(n)
        return f


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
        def handle(self):
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


class ScpiServer(socketserver.ThreadingTCPServer):
    allow_reuse_address = True
    daemon_threads = True

    def get_request(self):
        conn, addr = super().get_request()
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return conn, addr
