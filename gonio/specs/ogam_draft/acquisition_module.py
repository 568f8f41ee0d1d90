"""The goniometer's data-acquisition module (draft clause 4, Fig. 2): zero, trigger, read.

:class:`AcquisitionModule` speaks the SCPI-style command set of
:data:`AcquisitionModule.COMMANDS` (what ``gonio bench serve`` serves): ``ZERO`` starts a
measurement (the pulse counter's reference), ``READ?`` triggers a reading and answers
``<counts>,<time_s>`` — the counter since the zeroing as its register shows it (rolling
over at its width) and the module's time since the zeroing. The counter's roll-over is
undone with the expected count (:func:`unwrap_near`, on :mod:`gonio.formats.counters`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from gonio.formats.counters import wrap_counter
from gonio.instruments.link import Driver, InstrumentError


def unwrap_near(shown: int, expected: float, bits: int) -> int:
    """The count nearest ``expected`` that a ``bits``-wide counter shows as ``shown``.

    Between a zeroing and a reading the counter may roll over any number of times (a turn
    of an RLG is ~2.75·10⁷ counts, a 24-bit counter rolls over at 1.7·10⁷); the count is
    ``shown`` plus the multiple of 2^bits that brings it nearest the count expected from the
    table's angle, exact while the instrument's error is below half the counter's range.

    >>> unwrap_near(3, 2**24 + 5.0, 24)              # one roll-over
    16777219
    >>> unwrap_near(-2, -1.0, 16), unwrap_near(65534, -1.0, 16)    # signed or unsigned
    (-2, -2)
    """
    if bits >= 64:
        return int(shown)
    base = int(round(expected))
    resid = wrap_counter(np.array([int(shown) - base]), bits, True)[0]
    return base + int(resid)


@dataclass(frozen=True)
class Reading:
    """One triggered reading: counts since the zeroing and the module's time since it."""

    counts: int
    time_s: float


class AcquisitionModule(Driver):
    """An angle/rate acquisition module, or a counter in totalize mode used as one.

    Operations: ``zero``, ``read`` (``<counts>,<time_s>``), ``read_angle``
    (``<deg>,<time_s>``), ``rate`` (°/s), ``temperature`` (°C), ``clock`` (the module's
    time, s: the acquisition times every wait on it), ``counter_bits``/``counter_signed``
    (the register's width and sign), ``scale_factor`` (its nominal counts per degree),
    ``trigger_source`` (``BUS`` or ``EXT``).
    """

    KIND = "acquisition module"
    COMMANDS = {
        **Driver.COMMANDS,
        "zero": "ZERO",
        "read": "READ?",
        "read_angle": "READ:ANG?",
        "rate": "MEAS:RATE?",
        "temperature": "MEAS:TEMP?",
        "clock": "SYST:TIME?",
        "counter_bits": "CONF:COUN:BITS?",
        "counter_signed": "CONF:COUN:SIGN?",
        "scale_factor": "CONF:SCAL?",
        "trigger_source": "TRIG:SOUR {source}",
        "trigger_delay": "TRIG:DEL {delay_s:.10g}",
        "arm": "INIT",
        "fetch": "FETC?",
    }
    #: The error a ``FETC?`` answers while its trigger is still to come (SCPI −230).
    PENDING = re.compile(r"^\s*-230\s*,")

    _bits: int | None = None

    def counter_bits(self) -> int:
        """The counter register's width (64 when the module does not say)."""
        if self._bits is None:
            self._bits = int(self.number("counter_bits")) if self.has("counter_bits") else 64
        return self._bits

    def zero(self) -> None:
        """Zero: the counter's reference and the time origin of the next readings."""
        self.send("zero")

    def _pair(self, op: str) -> tuple[float, float]:
        return self._parse_pair(op, self.send(op))

    def _parse_pair(self, op: str, ans: str) -> tuple[float, float]:
        try:
            a, t = (float(x) for x in ans.split(",")[:2])
        except ValueError:
            raise InstrumentError(f"acquisition module {self.link.name}: {op}: expected "
                                  f"'value,time_s', got {ans!r}") from None
        return a, t

    def read(self, expected_counts: float = 0.0) -> Reading:
        """Trigger and read: counts since the zeroing (roll-over undone near
        ``expected_counts``) and the module's time since the zeroing."""
        shown, t = self._pair("read")
        return Reading(unwrap_near(int(shown), expected_counts, self.counter_bits()), t)

    @property
    def can_trigger_on_table(self) -> bool:
        """Whether the module reads on an external trigger (the table's in-position signal)."""
        return self.has("arm") and self.has("fetch") and self.has("trigger_delay")

    def arm(self, delay_s: float) -> None:
        """Take the next reading ``delay_s`` after the table's next in-position signal."""
        self.send("trigger_delay", delay_s=delay_s)
        self.send("arm")

    def fetch(self, expected_counts: float = 0.0, wait=None) -> Reading:
        """The armed reading; while it is still to come (−230) ``wait()`` and ask again."""
        while True:
            ans = self.send("fetch", check=False)
            first = self.link.query(self.ERROR_QUERY) if self.ERROR_QUERY else None
            if first is not None and self.PENDING.match(first):
                self.after_command("FETC?")          # nothing else may be queued
                if wait is not None:
                    wait()
                continue
            self.after_command("FETC?", first)
            shown, t = self._parse_pair("fetch", ans)
            return Reading(unwrap_near(int(shown), expected_counts, self.counter_bits()), t)

    def read_angle_deg(self) -> tuple[float, float]:
        """Trigger and read the indicated angle since the zeroing, ° (and its time, s)."""
        return self._pair("read_angle")

    def rate_dps(self) -> float:
        """The sensed rate, °/s."""
        return self.number("rate")

    def temperature_c(self) -> float:
        """The module's temperature, °C."""
        return self.number("temperature")

    def scale_factor_counts_per_deg(self) -> float | None:
        """Its nominal scale factor, when it states one."""
        return self.number("scale_factor") if self.has("scale_factor") else None
