"""A VISA link with a raw I/O log, and the base of every driver: a table of commands.

:class:`Link` opens a VISA resource (``TCPIP0::host::5025::SOCKET``, ``ASRL/dev/ttyUSB0::INSTR``,
``GPIB0::12::INSTR``, ``USB0::…::INSTR``) through PyVISA with its pure-Python ``@py`` backend
(pyvisa-py; pyserial for serial links), line-terminated, and writes every command and every
answer to an :class:`IOLog` with its UTC time. Its failures are :class:`LinkLost` (the
connection closed or timed out) and :class:`InstrumentError` (the instrument reported an
error): both :class:`~gonio.errors.GonioError`, so the command line prints one line.

:class:`Driver` is what every instrument interface (:mod:`gonio.instruments.table`,
:mod:`gonio.instruments.rate`, a specification's own, such as the goniometer's acquisition
module) shares: ``COMMANDS``, a table of command templates by
operation (``None``: the instrument has no such command), formatted with Python's
``str.format`` and sent as a query when the template ends in ``?``; ``after_command``
checks the instrument's error queue (IEEE 488.2 / SCPI ``SYSTem:ERRor?``, drained until
``0,"No error"``) or, for a vendor dialect, the reply code. A laboratory's controller is a
subclass that replaces the table and, where its replies differ, the parsing methods
(docs/instruments.md).
"""

from __future__ import annotations

import datetime as _dt
import re
import threading
from pathlib import Path

from gonio.errors import GonioError


class LinkLost(GonioError):
    """The connection to an instrument closed, failed or timed out."""


class InstrumentError(GonioError):
    """The instrument reported an error (its error queue or its reply code)."""


class IOLog:
    """Every command and answer on every link, one line each, flushed as written:
    ``2026-11-29T02:10:00.123456Z table > MOVE:ABS 90,60`` (``<`` for an answer, ``!`` for
    a failure). ``path`` None keeps the lines in memory only (``lines``)."""

    def __init__(self, path: str | Path | None = None):
        self.path = Path(path) if path is not None else None
        self.lines: list[str] = []
        self._lock = threading.Lock()
        self._fh = open(self.path, "a", encoding="utf-8") if self.path is not None else None

    def write(self, name: str, direction: str, text: str) -> None:
        stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%S.%fZ")
        line = f"{stamp} {name} {direction} {text}"
        with self._lock:
            self.lines.append(line)
            if self._fh is not None:
                self._fh.write(line + "\n")
                self._fh.flush()

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None


def resource_manager():
    """PyVISA's resource manager on the pure-Python backend (no vendor VISA needed)."""
    import pyvisa

    return pyvisa.ResourceManager("@py")


class Link:
    """One instrument's VISA session: ``write``, ``query``, ``close``, all logged.

    ``timeout_s`` bounds every read; an expired read, a closed socket or any VISA failure
    raises :class:`LinkLost` naming the instrument and the command.
    """

    def __init__(self, resource: str, *, name: str, log: IOLog | None = None,
                 timeout_s: float = 10.0, rm=None):
        self.resource, self.name = resource, name
        self.log = log or IOLog()
        self._rm = rm or resource_manager()
        try:
            self._inst = self._rm.open_resource(resource, read_termination="\n",
                                                write_termination="\n",
                                                timeout=int(timeout_s * 1000))
        except Exception as exc:                 # pyvisa raises many kinds here
            self.log.write(name, "!", f"open {resource}: {exc}")
            raise LinkLost(f"{name}: cannot open {resource}: {_one_line(exc)}") from None

    def _fail(self, cmd: str, exc: Exception):
        self.log.write(self.name, "!", f"{cmd}: {_one_line(exc)}")
        raise LinkLost(f"{self.name} ({self.resource}): connection lost at {cmd!r}: "
                       f"{_one_line(exc)}") from None

    def write(self, cmd: str) -> None:
        self.log.write(self.name, ">", cmd)
        try:
            self._inst.write(cmd)
        except Exception as exc:
            self._fail(cmd, exc)

    def query(self, cmd: str) -> str:
        self.log.write(self.name, ">", cmd)
        try:
            self._inst.write(cmd)
            answer = self._inst.read()
        except Exception as exc:
            self._fail(cmd, exc)
        answer = answer.strip()
        self.log.write(self.name, "<", answer)
        return answer

    def close(self) -> None:
        try:
            self._inst.close()
        except Exception:        # closing a lost link: nothing more to do
            pass


def _one_line(exc: Exception) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


#: SCPI's ``0,"No error"`` (and ``+0,...``).
NO_ERROR = re.compile(r"^\s*[+]?0\s*(,|$)")


class Driver:
    """The base of a driver: a command table over a :class:`Link`.

    ``COMMANDS`` maps an operation to a template (``"MOVE:ABS {angle_deg:.6f},{rate_dps:.6f}"``)
    or to None where the instrument lacks it. ``ERROR_QUERY`` drains the error queue after
    each command (None: the dialect has no queue; override :meth:`after_command`).
    """

    COMMANDS: dict[str, str | None] = {"identify": "*IDN?", "clear": "*CLS", "reset": "*RST",
                                       "complete": "*OPC?"}
    ERROR_QUERY: str | None = "SYST:ERR?"
    COMPOUND = True
    KIND = "instrument"

    def __init__(self, link: Link):
        self.link = link

    def has(self, op: str) -> bool:
        """Whether the instrument has the operation ``op``."""
        return self.COMMANDS.get(op) is not None

    def command(self, op: str, **values) -> str:
        """The text of operation ``op`` with ``values`` filled in."""
        tpl = self.COMMANDS.get(op)
        if tpl is None:
            raise GonioError(f"{self.KIND} {self.link.name}: the driver {type(self).__name__} "
                             f"has no command for {op!r}")
        return tpl.format(**values)

    def send(self, op: str, *, check: bool = True, **values) -> str | None:
        """Send operation ``op``: a query returns its answer; then the error check.

        A command that has no answer goes out on one line with the error query
        (``ZERO;:SYST:ERR?``, SCPI's compound form when ``COMPOUND`` is true): one round
        trip, and no wait on the peer's delayed acknowledgement of a lone small write."""
        cmd = self.command(op, **values)
        if cmd.rstrip().endswith("?"):
            answer = self.link.query(cmd)
            if check:
                self.after_command(cmd)
            return answer
        if check and self.ERROR_QUERY is not None and self.COMPOUND:
            self.after_command(cmd, self.link.query(f"{cmd};:{self.ERROR_QUERY.lstrip(':')}"))
            return None
        self.link.write(cmd)
        if check:
            self.after_command(cmd)
        return None

    def after_command(self, cmd: str, first: str | None = None) -> None:
        """Drain the SCPI error queue (``first``: its first entry, already read); any entry
        is an :class:`InstrumentError`."""
        if self.ERROR_QUERY is None:
            return
        errors = []
        for _ in range(32):                     # a queue is finite; guard a stuck one
            e = first if first is not None else self.link.query(self.ERROR_QUERY)
            first = None
            if NO_ERROR.match(e):
                break
            errors.append(e)
        if errors:
            raise InstrumentError(f"{self.KIND} {self.link.name}: {cmd!r} → "
                                  + "; ".join(errors))

    def identify(self) -> str:
        """``*IDN?``: maker, model, serial, firmware."""
        return self.send("identify")

    def wait_complete(self) -> None:
        """``*OPC?``: returns once the operations in progress are complete (a move: arrived)."""
        self.send("complete")

    def clear(self) -> None:
        """``*CLS``: empty the error queue and status."""
        self.send("clear", check=False)

    def clock_s(self) -> float:
        """The instrument's clock (operation ``clock``), s; no error check: it is polled
        while waiting."""
        ans = self.send("clock", check=False)
        try:
            return float(ans)
        except ValueError:
            raise InstrumentError(f"{self.KIND} {self.link.name}: clock: expected a number, "
                                  f"got {ans!r}") from None

    def number(self, op: str, **values) -> float:
        """A query whose answer is one number."""
        answer = self.send(op, **values)
        try:
            return float(answer.split(",")[0])
        except (ValueError, AttributeError):
            raise InstrumentError(f"{self.KIND} {self.link.name}: {op}: expected a number, "
                                  f"got {answer!r}") from None
