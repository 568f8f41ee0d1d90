"""Drivers of a rate specification's bench: rate table, gyro output reader, chamber, supply.

Each is a :class:`~gonio.instruments.link.Driver` with its command table (SCPI-style by
default; what ``gonio bench serve`` serves for a rate bench,
:mod:`gonio.instruments.served_rate`), so a laboratory's instrument with another dialect is
a subclass with its own table (docs/instruments.md):

- :class:`RateTable` — the rotary table's rate mode (``ROT``, ``STOP``) with the two
  operations a rate specification adds: ``oscillate`` (a sine of the table's rate, the
  angular vibration table of JJF 7.2.15 / IEC 5.1.3.8) and ``mount`` (the two-axis position
  fixture that points a body axis up and one north, JJF 7.2.12); None: an operator does it;
- :class:`GyroOutput` — a data logger on the gyro's output: configure a record of ``n``
  samples at an interval (each the mean over its interval, or instantaneous on a sine),
  start it at a time of its own clock, fetch the samples (time, output, reference rate);
- :class:`Chamber` — set point, ramp, on/off, air temperature;
- :class:`Supply` — voltage, output on/off, the voltage measured at the terminals.
"""

from __future__ import annotations

import numpy as np

from gonio.errors import GonioError
from gonio.instruments.link import Driver, InstrumentError
from gonio.instruments.table import RotaryTable


class RateTable(RotaryTable):
    """A rate table: rate mode, its sine mode and the position fixture on it."""

    KIND = "rate table"
    COMMANDS = {
        **RotaryTable.COMMANDS,
        "move": None, "set_axis": None, "axis": None,
        "rate": "RATE?",
        "oscillate": "OSC {freq_hz:.10g},{amplitude_dps:.10g}",
        "max_freq": "LIM:FREQ?",
        "mount": "MOUNT {up},{north}",
        "mounting": "MOUNT?",
    }
    STATES = {**RotaryTable.STATES, "OSC": "oscillating"}

    def oscillate(self, freq_hz: float, amplitude_dps: float) -> None:
        """Turn the table's rate as a sine of ``freq_hz`` and ``amplitude_dps``."""
        top = self.number("max_freq") if self.has("max_freq") else float("inf")
        if not 0.0 < freq_hz <= top or not 0.0 < amplitude_dps <= self.limits().max_rate_dps:
            raise GonioError(f"rate table {self.link.name}: a sine of {freq_hz:g} Hz, "
                             f"{amplitude_dps:g} °/s is beyond its {top:g} Hz, "
                             f"{self.limits().max_rate_dps:g} °/s; not sent")
        self.send("oscillate", freq_hz=freq_hz, amplitude_dps=amplitude_dps)

    @property
    def can_mount(self) -> bool:
        return self.has("mount")

    def mount(self, up: str, north: str) -> None:
        """Point the gyro's body axis ``up`` (``+z``) up and ``north`` north."""
        self.send("mount", up=up, north=north)


class GyroOutput(Driver):
    """A data logger on the gyro's output (and the vibration table's reference rate)."""

    KIND = "gyro output"
    COMMANDS = {
        **Driver.COMMANDS,
        "clock": "SYST:TIME?",
        "configure": "ACQ:CONF {samples},{interval_s:.10g}",
        "start": "ACQ:STAR {at_s:.10g}",
        "ready": "ACQ:COUN?",
        "data": "ACQ:DATA? {first},{count}",
        "temperature": "MEAS:TEMP?",
        "unit": "CONF:UNIT?",
        "scale_factor": "CONF:SCAL?",
        "null_output": "CONF:NULL?",
    }
    #: Samples asked per ``data`` query.
    CHUNK = 2000

    def start_record(self, samples: int, interval_s: float, at_s: float) -> None:
        """Record ``samples`` at ``interval_s`` from the logger's time ``at_s``."""
        self.send("configure", samples=int(samples), interval_s=float(interval_s))
        self.send("start", at_s=float(at_s))

    def ready(self) -> int:
        return int(self.number("ready"))

    def fetch(self, samples: int) -> np.ndarray:
        """The record's samples as rows (time on its clock, output, reference rate)."""
        parts = []
        for first in range(0, samples, self.CHUNK):
            n = min(self.CHUNK, samples - first)
            cmd = self.command("data", first=first, count=n)
            ans = self.link.query(cmd)          # a query with parameters
            self.after_command(cmd)
            try:
                a = np.array([float(x) for x in ans.split(",")], dtype=float).reshape(n, 3)
            except ValueError:
                raise InstrumentError(f"gyro output {self.link.name}: data: expected {n} "
                                      f"triples 'time,output,reference'") from None
            parts.append(a)
        return np.vstack(parts)

    def stated(self, op: str) -> str | None:
        """What the gyro states of itself (``unit``, ``scale_factor``, ``null_output``)."""
        return self.send(op) if self.has(op) else None


class Chamber(Driver):
    """A temperature chamber: set point (turns it on), ramp, off, air temperature."""

    KIND = "chamber"
    COMMANDS = {
        **Driver.COMMANDS,
        "set_point": "TEMP {temperature_c:.10g}",
        "ramp": "RAMP {c_per_min:.10g}",
        "off": "OUTP OFF",
        "set_point?": "TEMP?",
        "ramp?": "RAMP?",
        "on?": "OUTP?",
        "air": "MEAS:TEMP?",
        "range": "LIM:TEMP?",
        "max_ramp": "LIM:RAMP?",
    }

    def set_point(self, temperature_c: float, ramp_c_per_min: float) -> None:
        """Ramp to ``temperature_c`` (refused beyond the chamber's stated range, unsent)."""
        if self.has("range"):
            lo, hi = (float(x) for x in self.send("range").split(",")[:2])
            if not lo <= temperature_c <= hi:
                raise GonioError(f"chamber {self.link.name}: {temperature_c:g} °C is outside "
                                 f"its range [{lo:g}, {hi:g}] °C; not sent")
        self.send("ramp", c_per_min=ramp_c_per_min)
        self.send("set_point", temperature_c=temperature_c)

    def air_c(self) -> float:
        """The air temperature the chamber measures, °C."""
        return self.number("air")

    def off(self) -> None:
        self.send("off")


class Supply(Driver):
    """The gyro's power supply (a DMM at its terminals where ``measure`` is another's)."""

    KIND = "supply"
    COMMANDS = {
        **Driver.COMMANDS,
        "voltage": "VOLT {volts:.10g}",
        "voltage?": "VOLT?",
        "on?": "OUTP?",
        "on": "OUTP ON",
        "off": "OUTP OFF",
        "measure": "MEAS:VOLT?",
    }

    def set_voltage(self, volts: float) -> None:
        self.send("voltage", volts=volts)

    def on(self) -> None:
        self.send("on")

    def off(self, *, check: bool = True) -> None:
        self.send("off", check=check)

    def measured_v(self) -> float:
        return self.number("measure")
