"""What every acquisition through the instruments shares: the readings file written as the
readings come (:class:`ReadingsFile`), waits timed on the instrument's own clock
(:class:`ModuleClock`), what a run left (:class:`AcquisitionResult`), how a stop is told
(:func:`raise_stop`, :func:`stop_reason`), the readings' ``# date:``
(:func:`laboratory_date_text`) and the metadata an acquisition's caller may add
(:func:`with_given_metadata`).

Used by :mod:`gonio.instruments.rate_acquire` (a rate specification's segment programme) and
by a specification that runs its own programme through its ``acquire`` hook (the goniometer's
table and acquisition module).
"""

from __future__ import annotations

import datetime as _dt
import os
import time
from dataclasses import dataclass
from pathlib import Path

from gonio.atomic import write_text
from gonio.errors import GonioError


#: Metadata keys that state what the instruments reported of themselves or what gonio measured
#: and wrote (the date it ran, in the laboratory's zone; besides every ``*_idn``, an
#: instrument's own ``*IDN?`` answer): a caller's metadata (``gonio acquire --meta``, the
#: records' bench form) may add them where the instruments are silent, never replace them —
#: a certificate names the instrument the bench answered as, and the virtual bench's
#: identification keeps its readings virtual.
REPORTED_KEYS = frozenset({"instrument", "model", "serial", "manufacturer", "table",
                           "generator", "temperature_c", "date"})


def with_given_metadata(md: dict, given: dict | None) -> dict:
    """``md`` (what the acquisition wrote from the instruments) with the caller's ``given``
    lines added; a given key of :data:`REPORTED_KEYS` or an ``*_idn`` that the instruments
    stated otherwise is a GonioError naming the key (``--meta``).

    >>> with_given_metadata({"serial": "A-1", "latitude_deg": "40"}, {"latitude_deg": "39.9",
    ...                                                              "serial": " A-1"})
    {'serial': 'A-1', 'latitude_deg': '39.9'}
    >>> with_given_metadata({"serial": ""}, {"serial": "A-1"})
    {'serial': 'A-1'}
    >>> with_given_metadata({"gyro_idn": "gonio virtual bench,RLG (virtual),RLG-0001"},
    ...                     {"gyro_idn": "ACME,RLG,7"})
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key gyro_idn: the instruments state 'gonio virtual bench,RLG (virtual),RLG-0001', given 'ACME,RLG,7': metadata given to an acquisition add to what the instruments report, never replace it
    """
    out = dict(md)
    for key, value in (given or {}).items():
        if value is None:
            continue
        ours = str(md.get(key) or "").strip()
        idn = key.endswith("_idn")        # only an instrument's own answer is its *IDN?
        if (key in REPORTED_KEYS and ours) or idn:
            if ours != str(value).strip():
                said = f"the instruments state {ours!r}" if ours else \
                    "no instrument answered as it"
                raise GonioError(f"{said}, given {str(value).strip()!r}: metadata given to an "
                                 "acquisition add to what the instruments report, never "
                                 "replace it", key=key)
            continue                      # the same: the instruments' text kept
        out[key] = value
    return out


def laboratory_date_text(at: _dt.datetime | None = None, zone: str = "") -> str:
    """The readings' ``# date:``: the laboratory's calendar date (YYYY-MM-DD) at ``at`` (an
    aware time; None: now). One rule: the laboratory's time zone where it is known, ``zone``
    (an IANA name: ``gonio acquire --timezone``, which writes it as the readings'
    ``# timezone:``; give the records' setting ``timezone``, the zone every date of the
    records is taken in, ``gonio.records.models.records_today``); else the bench computer's
    local zone (the ``TZ`` environment variable, else the system's), which is the
    laboratory's only where that computer is set to it. Never UTC's, which is the day
    before in Beijing until 08:00 (tests/test_acquisition_date.py). An unknown ``zone`` is a
    GonioError naming ``timezone``.

    >>> laboratory_date_text(_dt.datetime(2026, 12, 1, 23, 30, tzinfo=_dt.timezone.utc),
    ...                      "Asia/Shanghai")
    '2026-12-02'
    >>> len(laboratory_date_text()), laboratory_date_text()[4]
    (10, '-')
    """
    at = _dt.datetime.now(_dt.timezone.utc) if at is None else at
    if not zone:
        return at.astimezone().strftime("%Y-%m-%d")
    return at.astimezone(zone_info(zone)).strftime("%Y-%m-%d")


def zone_info(zone: str) -> _dt.tzinfo:
    """The IANA time zone ``zone`` (zoneinfo), else a GonioError naming ``timezone``."""
    import zoneinfo

    try:
        return zoneinfo.ZoneInfo(str(zone))
    except (zoneinfo.ZoneInfoNotFoundError, ValueError, TypeError):
        raise GonioError(f"{str(zone)[:60]!r} is not a time zone of the IANA database (e.g. "
                         "Asia/Shanghai, Europe/Berlin, UTC)", key="timezone") from None


class ReadingsFile:
    """readings.csv written as the readings come: metadata and header first, then one row per
    reading, appended, flushed and synced. ``acquisition: incomplete`` until :meth:`finish`
    rewrites the metadata (atomically) to ``complete``. Readings of the virtual bench's
    instruments (metadata that say virtual: their ``*_idn``) are written with the bench's
    watermark at each rewrite (the rows appended between are marked at the next one)."""

    def __init__(self, path: Path, metadata: dict, rows: list[str], columns):
        self.path, self.metadata, self.rows = path, dict(metadata), list(rows)
        self.columns = tuple(columns)
        self._rewrite("incomplete")
        self._fh = open(self.path, "a", encoding="utf-8", newline="\n")

    def _text(self, state: str, reason: str = "") -> str:
        md = {"acquisition": state, **self.metadata}
        if reason:
            md["acquisition_stopped"] = " ".join(reason.split())[:300]
        head = "".join(f"# {k}: {v}\n" for k, v in md.items())
        text = head + ",".join(self.columns) + "\n" + "".join(self.rows)
        from gonio.formats.provenance import provenance
        if provenance(self.metadata)["virtual"]:
            # the virtual bench's instruments (their *IDN? answers say so): their readings
            # carry its watermark in their times, as a simulation's do, so that they stay
            # virtual with their identification lines deleted (docs/formats.md#watermark)
            from gonio.formats.watermark import mark_text
            text = mark_text(text)
        return text

    def _rewrite(self, state: str, reason: str = "") -> None:
        write_text(self.path, self._text(state, reason))

    def append(self, line: str) -> None:
        """One row (or several: a record's rows at once)."""
        self.rows.append(line)          # first: a rewrite after an interrupt keeps it
        self._fh.write(line)
        self._fh.flush()
        os.fsync(self._fh.fileno())

    def finish(self, complete: bool, reason: str = "") -> None:
        self._fh.close()
        self._rewrite("complete" if complete else "incomplete", reason)


class ModuleClock:
    """Waits timed on the acquisition module's clock (``SYST:TIME?``): the wall-clock sleep
    is the time left divided by the module's measured speed against the wall clock (1 on a
    real bench; N on a bench served N× faster), then the clock is asked again."""

    def __init__(self, gyro, wall=time.monotonic, sleep=time.sleep):
        self.gyro, self.wall, self.sleep = gyro, wall, sleep
        self.first = (wall(), gyro.clock_s())
        self.last = self.first

    def now(self) -> float:
        t = self.gyro.clock_s()
        self.last = (self.wall(), t)
        return t

    def speed(self) -> float | None:
        dw, dm = self.last[0] - self.first[0], self.last[1] - self.first[1]
        return dm / dw if dw > 0.02 and dm > 0 else None

    def wait_until(self, t_s: float) -> float:
        """Return the module's time once it is at or past ``t_s``."""
        while True:
            now = self.now()
            if now >= t_s:
                return now
            sp = self.speed()
            self.sleep(0.005 if sp is None else min(max(0.9 * (t_s - now) / sp, 2e-4), 1.0))


@dataclass
class AcquisitionResult:
    """What an acquisition left: the files, the readings taken (this run) and in all."""

    readings: Path
    io_log: Path
    taken: int
    total: int
    complete: bool
    seconds: float = 0.0


class _StopRequested(BaseException):
    """SIGTERM during an acquisition run outside the command line (which has its own)."""


def raise_stop(signum, frame):
    raise _StopRequested()


def stop_reason(exc: BaseException) -> str:
    if isinstance(exc, KeyboardInterrupt):
        return "interrupted (SIGINT)"
    if isinstance(exc, GonioError):
        return str(exc)
    if type(exc).__name__ in ("Terminated", "_StopRequested"):
        return "terminated (SIGTERM)"
    return f"{type(exc).__name__}: {exc}"
