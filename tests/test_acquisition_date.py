"""The readings' ``# date:`` an acquisition writes is the laboratory's calendar date: in the
laboratory's zone where it is given (``gonio acquire --timezone``, the records' setting), else
in the bench computer's local time zone (docs/instruments.md); never UTC's.
Checked in two zones 26 h apart (UTC+14 and UTC−12), where at every instant at least one local
date differs from UTC's, against the date computed from the zone's fixed offset."""

from __future__ import annotations

import datetime as dt
import time
from pathlib import Path

import pytest

from gonio.instruments.run import laboratory_date_text

ROOT = Path(__file__).resolve().parents[1]
#: (TZ, its fixed offset from UTC in hours: POSIX's Etc/GMT signs are inverted)
ZONES = (("Etc/GMT-14", 14), ("Etc/GMT+12", -12))


@pytest.fixture
def zone(monkeypatch):
    def set_zone(tz):
        monkeypatch.setenv("TZ", tz)
        time.tzset()
    yield set_zone
    monkeypatch.undo()
    time.tzset()


@pytest.mark.parametrize("tz,hours", ZONES)
def test_date_is_the_local_calendar_date(zone, tz, hours):
    zone(tz)
    for at in (dt.datetime(2026, 12, 1, 23, 30, tzinfo=dt.timezone.utc),
               dt.datetime(2026, 12, 2, 3, 30, tzinfo=dt.timezone.utc)):
        assert laboratory_date_text(at) == (at + dt.timedelta(hours=hours)).date().isoformat()
    before = dt.datetime.now(dt.timezone.utc)
    now = laboratory_date_text()
    after = dt.datetime.now(dt.timezone.utc)
    assert now in {(t + dt.timedelta(hours=hours)).date().isoformat() for t in (before, after)}


def test_the_asia_shanghai_morning(zone):
    """At 07:30 in Beijing (23:30 UTC the day before) the date is Beijing's."""
    zone("Asia/Shanghai")
    assert laboratory_date_text(dt.datetime(2026, 12, 1, 23, 30,
                                            tzinfo=dt.timezone.utc)) == "2026-12-02"


@pytest.mark.parametrize("module", ["gonio/instruments/rate_acquire.py",
                                    "gonio/specs/ogam_draft/acquisition.py"])
def test_every_acquisition_writes_that_date(module):
    """Both acquisitions (the rate programmes' and the optical draft's) take their ``# date:``
    from it, in the readings' ``timezone`` where given, none from a UTC clock."""
    text = (ROOT / module).read_text(encoding="utf-8")
    assert "laboratory_date_text(zone=" in text
    assert "timezone.utc" not in text


@pytest.mark.parametrize("tz", ["UTC", "America/Los_Angeles"])
def test_the_laboratory_zone_decides_near_midnight(zone, tz):
    """A bench computer in another zone (UTC, Los Angeles) and the laboratory in Beijing
    (UTC+8, no daylight saving): one second either side of Beijing's midnight the date is
    Beijing's, worked out from the fixed offset; without the zone, the computer's."""
    zone(tz)
    for at in (dt.datetime(2026, 12, 1, 15, 59, 59, tzinfo=dt.timezone.utc),   # 23:59:59
               dt.datetime(2026, 12, 1, 16, 0, 0, tzinfo=dt.timezone.utc),     # 00:00:00
               dt.datetime(2026, 12, 1, 23, 30, tzinfo=dt.timezone.utc)):      # 07:30
        lab = (at + dt.timedelta(hours=8)).date().isoformat()
        assert laboratory_date_text(at, "Asia/Shanghai") == lab
        assert laboratory_date_text(at) == at.astimezone().date().isoformat()
    assert laboratory_date_text(dt.datetime(2026, 12, 1, 16, 0, tzinfo=dt.timezone.utc),
                                "Asia/Shanghai") != laboratory_date_text(
        dt.datetime(2026, 12, 1, 16, 0, tzinfo=dt.timezone.utc))


def test_an_unknown_zone_is_refused(tmp_path, capsys):
    from gonio.cli import main
    from gonio.errors import GonioError

    with pytest.raises(GonioError, match="timezone"):
        laboratory_date_text(zone="Mars/Olympus")
    rc = main(["acquire", "--protocol", "x", "--table", "TCPIP0::h::1::SOCKET", "--gyro",
               "ASRL1::INSTR", "--out", str(tmp_path / "o"), "--timezone", "Mars/Olympus"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "'Mars/Olympus'" in err, err
    assert not (tmp_path / "o").exists()
