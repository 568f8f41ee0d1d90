"""Equipment past its due date (ISO/IEC 17025 6.4.7, 6.4.13): registering a standard whose
due date has already passed is refused with one line naming it and the date (exit 2 on the
command line, nothing registered) unless it is registered out of service with the reason,
which its record keeps; such a standard is refused by a calibration dated after its due
date (the submission, the attach), until its recalibration is recorded. The dates are
relative to the day the test runs, so the rule is checked on either side of today."""

from __future__ import annotations

import datetime as dt
import io
import os
import subprocess
import sys

import pytest
from sqlalchemy import select

from gonio.errors import GonioError
from gonio.records import services
from gonio.records.db import open_store
from gonio.records.models import AuditEvent, Standard

from .conftest import PASSWORD, make_people

TODAY: dt.date        # the service's today (the laboratory's date), read as each test starts


def lab_today() -> dt.date:
    """The records' today of a new store: the date in the zone it was given when it was made
    (this machine's, :func:`gonio.records.models.machine_zone`)."""
    from gonio.records import models
    return models.laboratory_date(models.utcnow(), models.machine_zone())


@pytest.fixture(autouse=True)
def _today_at_each_test():
    """TODAY read as each test starts, never at import: a suite started before midnight runs
    these after it (a module constant was the day before's)."""
    global TODAY
    TODAY = lab_today()


def gonio(*args, data, rc=0):
    env = dict(os.environ, GONIO_PASSWORD=PASSWORD)
    r = subprocess.run([sys.executable, "-m", "gonio", *map(str, args), "--data", str(data)],
                       capture_output=True, text=True, env=env)
    assert r.returncode == rc, (r.returncode, r.stdout, r.stderr)
    return r


def standards(data) -> dict:
    st = open_store(None, data)
    try:
        with st.session() as s:
            return {x.identifier: (x.due_on, x.out_of_service, x.retired_on)
                    for x in s.scalars(select(Standard))}
    finally:
        st.close()


def test_add_standard_past_due_on_the_command_line(tmp_path):
    data = tmp_path / "data"
    gonio("db", "create-user", "alice", "--roles", "admin technician", data=data)
    late = TODAY - dt.timedelta(days=1)
    r = gonio("db", "add-standard", "AC-1", "--name", "autocollimator", "--due-on", late,
              "--user", "alice", data=data, rc=2)
    line = r.stderr.strip()
    assert "\n" not in line and "Traceback" not in line, line
    assert f"standard AC-1 was due on {late}, before today ({TODAY})" in line, line
    assert "--out-of-service" in line
    assert standards(data) == {}                                  # nothing registered
    # due today is in time; tomorrow too
    gonio("db", "add-standard", "RT-07", "--name", "rotary table", "--due-on", TODAY,
          "--user", "alice", data=data)
    r = gonio("db", "add-standard", "AC-1", "--name", "autocollimator", "--due-on", late,
              "--out-of-service", "sent for recalibration on 2026-11-20", "--user", "alice",
              data=data)
    assert "registered out of service" in r.stdout and "sent for recalibration" in r.stdout
    assert standards(data) == {"RT-07": (TODAY, "", None),
                               "AC-1": (late, "sent for recalibration on 2026-11-20", None)}
    # a blank reason is no reason
    gonio("db", "add-standard", "AC-2", "--name", "autocollimator", "--due-on", late,
          "--out-of-service", "   ", "--user", "alice", data=data, rc=2)
    assert "AC-2" not in standards(data)


def test_add_standard_past_due_in_python(sqlite_store):
    store = sqlite_store
    people = make_people(store)
    tech = people["tech"]
    late = TODAY - dt.timedelta(days=30)
    with pytest.raises(GonioError, match=f"standard LV-3 was due on {late}, before today"):
        services.add_standard(store, tech, name="level", identifier="LV-3", due_on=late)
    st = services.add_standard(store, tech, name="level", identifier="LV-3", due_on=late,
                               out_of_service="  broken bubble, kept for its history ")
    assert st.out_of_service == "broken bubble, kept for its history"
    with store.session() as s:                     # the reason is in the audit trail too
        ev = s.scalars(select(AuditEvent).where(AuditEvent.entity == "standard",
                                                AuditEvent.entity_id == str(st.id))).one()
        assert "broken bubble" in ev.after_json
    # used by a calibration dated after its due date: refused, naming it and the reason
    cust = services.add_customer(store, tech, "C")
    inst = services.register_instrument(store, tech, customer_id=cust.id, serial="RLG-1",
                                        spec_key="ogam-draft")
    good = services.add_standard(store, tech, name="table", identifier="RT-07",
                                 due_on=TODAY + dt.timedelta(days=300))
    n = iter(range(1, 10))

    def readings():                 # the same measurement is not calibrated twice
        return services.store_file(store, io.BytesIO(f"x,y\n{next(n)},2\n".encode()))[0]
    base = dict(instrument_id=inst.id, performed_on=TODAY, temperature_c=20, humidity_pct=45)
    with pytest.raises(GonioError, match=f"LV-3 was due on {late}.*out of service: broken"):
        services.create_calibration(store, tech, standard_ids=[good.id, st.id], **base,
                                    readings_sha256=readings())
    # a calibration dated before its due date may use it (it was valid then)
    cal = services.create_calibration(store, tech, standard_ids=[good.id, st.id],
                                      **{**base, "performed_on": late - dt.timedelta(days=1)},
                                      readings_sha256=readings())
    assert cal.id
    # its recalibration recorded: in use again
    services.update_standard(store, tech, st.id, calibrated_on=TODAY,
                             due_on=TODAY + dt.timedelta(days=365))
    assert services.create_calibration(store, tech, standard_ids=[st.id], **base,
                                       readings_sha256=readings()).id


def test_update_standard_past_due_follows_the_add_rule(sqlite_store):
    """Editing a standard's due date into the past is refused, as registering one past due
    is, unless the reason is stated: then it is out of service with it and refused by a
    calibration after its due date; a later due date in time puts it back in use."""
    store = sqlite_store
    tech = make_people(store)["tech"]
    st = services.add_standard(store, tech, name="table", identifier="RT-09",
                               due_on=TODAY + dt.timedelta(days=100))
    late = TODAY - dt.timedelta(days=2)
    with pytest.raises(GonioError, match=f"standard RT-09 was due on {late}, before today "
                                         rf"\({TODAY}\).*'Out of service'"):
        services.update_standard(store, tech, st.id, due_on=late)
    assert standards_of(store)["RT-09"] == (TODAY + dt.timedelta(days=100), "", None)
    # a blank reason is no reason
    with pytest.raises(GonioError, match="RT-09 was due on"):
        services.update_standard(store, tech, st.id, due_on=late, out_of_service="  ")
    services.update_standard(store, tech, st.id, due_on=late, out_of_service=" lost seal ")
    assert standards_of(store)["RT-09"] == (late, "lost seal", None)
    with store.session() as s:
        assert services.unusable_standard(s.get(Standard, st.id), TODAY).endswith(
            "(registered out of service: lost seal)")
    # other details edited, the due date unchanged: no new reason asked
    services.update_standard(store, tech, st.id, accuracy="1 arcsec", due_on=late)
    # recalibrated: in time again, the reason cleared (the audit trail keeps it)
    services.update_standard(store, tech, st.id, due_on=TODAY)
    assert standards_of(store)["RT-09"] == (TODAY, "", None)


def standards_of(store) -> dict:
    with store.session() as s:
        return {x.identifier: (x.due_on, x.out_of_service, x.retired_on)
                for x in s.scalars(select(Standard))}


@pytest.mark.parametrize("zone, shown", [("Asia/Shanghai", dt.date(2026, 12, 1)),
                                         ("America/Los_Angeles", dt.date(2026, 11, 30))])
def test_one_today_for_services_and_pages(sqlite_store, monkeypatch, zone, shown):
    """The records' "today" is one day for the services and the web pages, the laboratory's
    date in its zone (the setting ``timezone``), whatever the machine's zone (TZ set to the
    other one): at 23:30 UTC on 2026-11-30 it is 07:30 on 2026-12-01 in Beijing (a standard
    due on 2026-11-30 past due for add_standard, update_standard and the lists' overdue mark
    alike) and 15:30 on 2026-11-30 in Los Angeles (in time)."""
    from gonio.records import models
    from gonio.web import front
    monkeypatch.setattr(models, "utcnow", lambda: dt.datetime(2026, 11, 30, 23, 30))
    other = "America/Los_Angeles" if zone == "Asia/Shanghai" else "Asia/Shanghai"
    monkeypatch.setenv("TZ", other)
    import time
    if hasattr(time, "tzset"):
        time.tzset()
    try:
        store = sqlite_store
        tech = make_people(store)["tech"]
        services.set_settings(store, None, timezone=zone)
        due = dt.date(2026, 11, 30)
        today = models.records_today(store)
        assert today == shown
        late = today > due                      # Beijing: one day past due
        if late:
            with pytest.raises(GonioError, match=r"was due on 2026-11-30, before today "
                                                 r"\(2026-12-01\)"):
                services.add_standard(store, tech, name="level", identifier="LV-9", due_on=due)
        st = services.add_standard(store, tech, name="level", identifier="LV-9", due_on=due,
                                   out_of_service="sent away" if late else "")
        assert (st.out_of_service != "") == late
        assert front.past_due(due, models.records_today(store)) == late
    finally:
        monkeypatch.delenv("TZ")
        if hasattr(time, "tzset"):
            time.tzset()


def test_no_other_today_in_the_records_and_pages():
    """No module of the records or the web pages takes "today" from the local clock
    (date.today(), a naive now()): every one is models.records_today(store)."""
    import re
    from pathlib import Path

    import gonio
    root = Path(gonio.__file__).parent
    bad = []
    for f in sorted([*root.glob("records/**/*.py"), *root.glob("web/**/*.py")]):
        for i, line in enumerate(f.read_text(encoding="utf-8").splitlines(), 1):
            if re.search(r"date\.today\(\)|datetime\.now\(\)", line):
                bad.append(f"{f.relative_to(root)}:{i}: {line.strip()}")
    assert not bad, "\n".join(bad)
