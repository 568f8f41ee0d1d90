"""The records' calendar dates are the laboratory's (docs/records.md, "Dates and settings"):
the times stay UTC, but "today" of every date rule (a calibration date not in the future, the
form's default and maximum, a standard past its due date, the due list) is the laboratory's
date in its time zone, the setting ``timezone`` (an IANA name the store holds, written once at ``gonio db init`` or
at the migration of an older store: never each process's own local zone).
The clock is patched: at 23:30 UTC on 2026-12-01 it is 07:30 on 2026-12-02 in Beijing
(UTC+8, no daylight saving) and 15:30 on 2026-12-01 in Los Angeles (UTC-8 in December), the
expected dates worked out by hand from those offsets. Nothing reads the date at import: the
clock is patched after every module is loaded and each test's "today" follows it."""

from __future__ import annotations

import datetime as dt
import re

import pytest

from gonio.errors import GonioError
from gonio.records import models, services

from .conftest import make_people
from .test_web_lists import issued
from .test_web_security import app, login  # noqa: F401  (the app fixture)

AT = dt.datetime(2026, 12, 1, 23, 30)          # naive UTC, as the records hold times
BEIJING, LOS_ANGELES = "Asia/Shanghai", "America/Los_Angeles"


@pytest.fixture
def clock(monkeypatch):
    """The records' clock at ``AT`` (what models.records_today reads, at each call)."""
    monkeypatch.setattr(models, "utcnow", lambda: AT)
    return AT


@pytest.mark.parametrize("zone, today", [(BEIJING, dt.date(2026, 12, 2)),
                                         (LOS_ANGELES, dt.date(2026, 12, 1)),
                                         ("UTC", dt.date(2026, 12, 1))])
def test_today_is_the_laboratorys_date(sqlite_store, clock, zone, today):
    services.set_settings(sqlite_store, None, timezone=zone)
    assert models.records_today(sqlite_store) == today
    with sqlite_store.session() as s:          # an open session reads the same setting
        assert models.records_today(s) == today


def test_beijing_morning_calibration_date_accepted_and_yesterdays_due_past(sqlite_store,
                                                                             clock):
    """07:30 in Beijing on 2026-12-02: the laboratory's own date is accepted as the calibration
    date (it was refused "in the future (today 2026-12-01)" with the UTC date), tomorrow is
    not; a standard due on 2026-12-01 is one day past due: refused at registration without a
    reason, refused by a calibration dated today."""
    store = sqlite_store
    services.set_settings(store, None, timezone=BEIJING)
    today = models.records_today(store)
    services.plausible_dates(dt.date(2026, 12, 2), None, today)
    with pytest.raises(GonioError, match=r"2026-12-03 is in the future \(today 2026-12-02\)"):
        services.plausible_dates(dt.date(2026, 12, 3), None, today)
    day, *_ = services.submission_fields("", "", [1], 20, 45, today)
    assert day == dt.date(2026, 12, 2)                  # the default calibration date
    assert models.is_past_due(dt.date(2026, 12, 1), today)
    tech = make_people(store)["tech"]
    with pytest.raises(GonioError, match=r"standard RT-07 was due on 2026-12-01, before today "
                                         r"\(2026-12-02\)"):
        services.add_standard(store, tech, name="rotary table", identifier="RT-07",
                              due_on="2026-12-01")
    st = services.add_standard(store, tech, name="rotary table", identifier="RT-07",
                               due_on="2026-12-01", out_of_service="sent for recalibration")
    with store.session() as s:
        why = services.unusable_standard(s.get(models.Standard, st.id), today)
    assert why and "2026-12-01" in why, why


def test_west_of_utc_tomorrow_refused_and_todays_due_in_time(sqlite_store, clock):
    """15:30 in Los Angeles on 2026-12-01: 2026-12-02 (Beijing's date at that moment) is
    refused as the calibration date; a standard due on 2026-12-01 is in time (due today)."""
    store = sqlite_store
    services.set_settings(store, None, timezone=LOS_ANGELES)
    today = models.records_today(store)
    with pytest.raises(GonioError, match=r"2026-12-02 is in the future \(today 2026-12-01\)"):
        services.plausible_dates(dt.date(2026, 12, 2), None, today)
    services.plausible_dates(dt.date(2026, 12, 1), None, today)
    assert not models.is_past_due(dt.date(2026, 12, 1), today)
    tech = make_people(store)["tech"]
    st = services.add_standard(store, tech, name="rotary table", identifier="RT-07",
                               due_on="2026-12-01")
    assert st.out_of_service == ""


def test_west_of_utc_after_utc_midnight(sqlite_store, monkeypatch):
    """03:30 UTC on 2026-12-02 is 19:30 on 2026-12-01 in Los Angeles: the laboratory's date
    is still the 1st, so a calibration dated 2026-12-02 (the UTC date) is in the future and a
    standard due on 2026-12-01 is in time."""
    monkeypatch.setattr(models, "utcnow", lambda: dt.datetime(2026, 12, 2, 3, 30))
    services.set_settings(sqlite_store, None, timezone=LOS_ANGELES)
    today = models.records_today(sqlite_store)
    assert today == dt.date(2026, 12, 1)
    with pytest.raises(GonioError, match="in the future"):
        services.plausible_dates(dt.date(2026, 12, 2), None, today)
    assert not models.is_past_due(dt.date(2026, 12, 1), today)


def _in_process(tz: str, data, code: str) -> str:
    """``code`` run by a new Python process with TZ=``tz`` (its local zone) on the store in
    ``data``; its stdout."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "TZ": tz}
    pre = ("import datetime as dt; from gonio.records.db import open_store; "
           "from gonio.records import models; "
           f"st = open_store(None, {str(data)!r}); ")
    r = subprocess.run([sys.executable, "-c", pre + code], env=env, capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    return r.stdout.strip()


def test_one_zone_for_every_process_on_the_store(tmp_path):
    """The store made by a process in Beijing holds Asia/Shanghai; processes in Los Angeles
    and UTC read that zone and the same laboratory date at 23:30 UTC (2026-12-02, by hand:
    UTC+8), not their own (2026-12-01)."""
    data = tmp_path / "data"
    assert _in_process(BEIJING, data, "print(models.records_zone(st))") == BEIJING
    ask = ("z = models.records_zone(st); "
           "print(z, models.laboratory_date(dt.datetime(2026, 12, 1, 23, 30), z))")
    for tz in (LOS_ANGELES, "UTC", BEIJING):
        assert _in_process(tz, data, ask) == f"{BEIJING} 2026-12-02", tz


def test_a_store_without_the_setting_gets_one_zone(tmp_path, monkeypatch):
    """A store from before the setting was written (at migration 0012, no ``timezone`` row)
    gets this machine's zone once, at its migration; a later process elsewhere keeps it."""
    from gonio.records.db import data_folder, database_url, make_engine, migrate

    data = tmp_path / "data"
    folder = data_folder(data)
    engine = make_engine(database_url(None, folder))
    migrate(engine, "0012")
    with engine.begin() as conn:
        conn.exec_driver_sql("DELETE FROM settings WHERE key = 'timezone'")
    engine.dispose()
    assert _in_process("Europe/Berlin", data, "print(models.records_zone(st))") == "Europe/Berlin"
    assert _in_process(BEIJING, data, "print(models.records_zone(st))") == "Europe/Berlin"


def test_an_empty_zone_is_utc_in_every_process(monkeypatch):
    """No per-process fallback: "" reads as UTC whatever the process's TZ."""
    time = pytest.importorskip("time")
    if not hasattr(time, "tzset"):
        pytest.skip("no time.tzset on this platform")
    try:
        for tz in (BEIJING, LOS_ANGELES):
            monkeypatch.setenv("TZ", tz)
            time.tzset()
            assert models.laboratory_date(AT, "") == dt.date(2026, 12, 1), tz
    finally:
        monkeypatch.delenv("TZ")
        time.tzset()


def test_machine_zone_is_tz_or_utc(monkeypatch):
    monkeypatch.setenv("TZ", BEIJING)
    assert models.machine_zone() == BEIJING
    monkeypatch.setenv("TZ", "Mars/Olympus")
    assert models.laboratory_zone(models.machine_zone()) is not None   # some IANA zone or UTC


def test_an_empty_zone_is_refused(sqlite_store):
    before = services.settings(sqlite_store)["timezone"]
    with pytest.raises(GonioError, match=r"^key timezone: must not be empty"):
        services.set_settings(sqlite_store, None, timezone="")
    assert services.settings(sqlite_store)["timezone"] == before != ""


@pytest.mark.parametrize("bad", ["Mars/Olympus", "Asia/../etc/passwd", "+08:00"])
def test_unknown_zone_refused_nothing_stored(sqlite_store, bad):
    with pytest.raises(GonioError, match=r"^key timezone: .* is not a time zone of the IANA "
                                         r"database") as e:
        services.set_settings(sqlite_store, None, timezone=bad)
    assert "\n" not in str(e.value)
    assert services.settings(sqlite_store)["timezone"] == models.records_zone(sqlite_store) != ""


def test_form_and_lists_take_the_laboratorys_date(app, clock):  # noqa: F811
    """The calibration form's default and maximum date, the standards list's overdue mark,
    the due list and the recall at 07:30 in Beijing: today 2026-12-02, a standard due
    2026-12-01 overdue, an instrument due 2026-12-01 overdue (with the UTC date, 2026-12-01,
    neither was)."""
    store = app.state.store
    services.set_settings(store, None, timezone=BEIJING)
    tech = services.user(store, "tech")
    cust = services.add_customer(store, tech, "C")
    services.add_standard(store, tech, name="rotary table", identifier="RT-07",
                          due_on="2026-12-01", out_of_service="sent for recalibration")
    inst = services.register_instrument(store, tech, customer_id=cust.id, serial="RLG-0001",
                                        spec_key="ogam-draft", interval_months=12)
    issued(store, inst.id, dt.date(2025, 12, 1), "GC-2025-0001")     # due 2026-12-01
    c = login(app, "tech")
    form = c.get(f"/instruments/{inst.id}/calibrate").text
    assert re.search(r'name="performed_on" type="date" value="2026-12-02" max="2026-12-02"',
                     form), form
    assert "overdue, cannot be used" in form
    standards = c.get("/standards").text
    assert "(overdue)" in standards
    assert [r["overdue"] for r in services.due_instruments(store)] == [True]
    assert "<p>2026-12-02 — the instruments below" in c.get("/due/recall?customer=C").text
