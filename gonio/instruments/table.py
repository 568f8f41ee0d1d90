"""The rotary-table controller: move to an angle at a rate, rotate at a rate, stop, query.

:class:`RotaryTable` speaks the SCPI-style command set of :data:`RotaryTable.COMMANDS`
(what ``gonio bench serve`` serves). A controller with another dialect is a subclass with
its own table (docs/instruments.md). Every move is checked against the table's stated
range, rate and acceleration (:meth:`RotaryTable.check_move`) *before* it is sent.
"""

from __future__ import annotations

from dataclasses import dataclass

from gonio.errors import GonioError
from gonio.instruments.link import Driver, InstrumentError


@dataclass(frozen=True)
class TableLimits:
    """What the table states it can do: its angle range, top rate and acceleration."""

    min_deg: float
    max_deg: float
    max_rate_dps: float
    accel_dps2: float

    def check(self, angle_deg: float, rate_dps: float, *, where: str = "") -> None:
        """Refuse a move to ``angle_deg`` at ``rate_dps`` beyond these limits."""
        at = f"{where}: " if where else ""
        if not self.min_deg <= angle_deg <= self.max_deg:
            raise GonioError(f"{at}a move to {angle_deg:g}° is outside the table's range "
                             f"[{self.min_deg:g}°, {self.max_deg:g}°]; not sent")
        if not 0.0 < abs(rate_dps) <= self.max_rate_dps:
            raise GonioError(f"{at}a rate of {rate_dps:g} °/s is outside the table's range "
                             f"(0, {self.max_rate_dps:g}] °/s; not sent")


class RotaryTable(Driver):
    """A rotary or rate table controller (position mode, rate mode, axis orientation).

    Operations of the command table: ``move`` (absolute angle at a rate), ``rotate`` (rate
    mode, signed rate), ``stop``, ``position``, ``state`` (one of :data:`STATES`' keys),
    ``set_axis``/``axis`` (the axis orientation, where a tilt fixture sets it; None: an
    operator sets it by hand), ``range``/``max_rate``/``accel`` (the stated limits).
    """

    KIND = "table"
    COMMANDS = {
        **Driver.COMMANDS,
        "move": "MOVE:ABS {angle_deg:.10g},{rate_dps:.10g}",
        "rotate": "ROT {rate_dps:.10g}",
        "stop": "STOP",
        "position": "POS?",
        "state": "STAT?",
        "set_axis": "AXIS {orientation}",
        "axis": "AXIS?",
        "range": "LIM:POS?",
        "max_rate": "LIM:RATE?",
        "accel": "LIM:ACC?",
    }
    #: The controller's state words and what they mean.
    STATES = {"IDLE": "idle", "MOV": "moving", "ROT": "rotating", "FAULT": "fault"}

    _limits: TableLimits | None = None

    def limits(self) -> TableLimits:
        """The stated range (``min,max``), top rate and acceleration, asked once."""
        if self._limits is None:
            ans = self.send("range")
            try:
                lo, hi = (float(x) for x in ans.split(","))
            except ValueError:
                raise InstrumentError(f"table {self.link.name}: range: expected 'min,max', "
                                      f"got {ans!r}") from None
            self._limits = TableLimits(lo, hi, self.number("max_rate"), self.number("accel"))
        return self._limits

    def check_move(self, angle_deg: float, rate_dps: float, *, where: str = "") -> None:
        """Refuse a move beyond the table's stated range or rate (nothing is sent)."""
        self.limits().check(angle_deg, rate_dps, where=where)

    def move(self, angle_deg: float, rate_dps: float) -> None:
        """Move to ``angle_deg`` at ``rate_dps`` (checked first; then the error queue)."""
        self.check_move(angle_deg, rate_dps)
        self.send("move", angle_deg=angle_deg, rate_dps=rate_dps)

    def rotate(self, rate_dps: float) -> None:
        """Turn continuously at the signed ``rate_dps`` (rate mode) until :meth:`stop`."""
        lim = self.limits()
        if not 0.0 < abs(rate_dps) <= lim.max_rate_dps:
            raise GonioError(f"table {self.link.name}: a rate of {rate_dps:g} °/s is beyond "
                             f"its {lim.max_rate_dps:g} °/s; not sent")
        self.send("rotate", rate_dps=rate_dps)

    def stop(self, *, check: bool = True) -> None:
        """Stop the table (decelerating at its acceleration)."""
        self.send("stop", check=check)

    def position_deg(self) -> float:
        """The table's indicated angle, °."""
        return self.number("position")

    def state(self) -> str:
        """``idle``, ``moving``, ``rotating`` or ``fault``."""
        word = self.send("state").strip().upper()
        if word not in self.STATES:
            raise InstrumentError(f"table {self.link.name}: unknown state {word!r}")
        return self.STATES[word]

    @property
    def can_set_axis(self) -> bool:
        """Whether the controller sets the axis orientation (else an operator does)."""
        return self.has("set_axis")

    def set_axis(self, orientation: str) -> None:
        """Point the table axis ``up``, ``north``, ``south``, ``east`` or ``west``."""
        self.send("set_axis", orientation=orientation)
