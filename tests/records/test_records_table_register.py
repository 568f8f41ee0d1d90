"""The laboratory's register of its rotary tables' calibrations
(docs/records.md#the-register-of-table-calibrations), on SQLite and on the throwaway
PostgreSQL: registered once by a
technician (file by SHA-256, table, valid from / due on, who, audit event), frozen by the
database; a calibration picks the one in force on its date of the table among its standards, or
the one chosen; an expired, superseded or not yet valid one is refused in one line; the
calibration keeps which one it used (its file sealed as before); the web page, the form's
choice, ``gonio db register-table-calibration`` and ``gonio db table-calibrations``; migration
0009 over a database of 0008; backup and restore.

Truths from outside the code under test: the files' digests by hashlib, and which calibration
is in force on a day by a second rule written here (the newest valid from on or before the day,
in force only when that one is not past its due date), compared over every day of two years."""

from __future__ import annotations

import datetime as dt
import hashlib
import io
import json

import pytest
from sqlalchemy import select, text, update
from sqlalchemy.exc import DBAPIError, IntegrityError

from gonio.errors import GonioError
from gonio.records import models, services
from gonio.records.models import AuditEvent, Calibration, CalibrationFile, TableCalibration

from .conftest import PASSWORD, make_people
from .test_records_services import store_run_as_computed

FILES = {k: (f"# table certificate {k}\ntable_deg,error_arcsec,u_arcsec\n"
             f"0,0.0,0.02\n120,{0.01 * (i + 1):.3f},0.02\n").encode()
         for i, k in enumerate(("TC-1", "TC-2", "TC-3"))}
SHA = {k: hashlib.sha256(v).hexdigest() for k, v in FILES.items()}
#: TC-1 valid 2025-01-01 … 2026-01-01, TC-2 (same table) from 2025-06-01 … 2026-03-01
VALID = {"TC-1": ("2025-01-01", "2026-01-01"), "TC-2": ("2025-06-01", "2026-03-01")}


def setup_lab(store):
    """People, a customer, an optical instrument, the table RT-07 and another standard;
    returns (people, instrument id, table id, other standard id)."""
    people = make_people(store)
    tech = people["tech"]
    cust = services.add_customer(store, tech, "C")
    inst = services.register_instrument(store, tech, customer_id=cust.id, serial="RLG-1",
                                        spec_key="ogam-draft")
    table = services.add_standard(store, tech, name="rotary table", identifier="RT-07",
                                  due_on="2099-01-01")
    other = services.add_standard(store, tech, name="autocollimator", identifier="AC-1",
                                  due_on="2099-01-01")
    return people, inst.id, table.id, other.id


def register(store, actor, table_id, key, name=None):
    sha, _ = services.store_file(store, io.BytesIO(FILES[key]))
    start, due = VALID[key]
    return services.register_table_calibration(store, actor, standard_id=table_id, sha256=sha,
                                               name=name or f"{key}.csv", valid_from=start,
                                               due_on=due, certificate=key)


def create(store, actor, inst_id, day, standards, n=[0], **kw):  # noqa: B006 (a counter)
    n[0] += 1
    readings, _ = services.store_file(store, io.BytesIO(f"x,y\n{n[0]},{day}\n".encode()))
    return services.create_calibration(store, actor, instrument_id=inst_id,
                                       readings_sha256=readings, performed_on=day,
                                       standard_ids=standards, temperature_c=20,
                                       humidity_pct=45, **kw)


def in_force_here(entries: list[tuple[str, str, str]], day: dt.date) -> str | None:
    """The second rule: of (key, valid_from, due_on), the newest valid from on or before
    ``day``; in force when it is not past its due date on ``day``; else none."""
    started = [e for e in entries if dt.date.fromisoformat(e[1]) <= day]
    if not started:
        return None
    newest = max(started, key=lambda e: e[1])
    return newest[0] if day <= dt.date.fromisoformat(newest[2]) else None


def test_register_once_audited_and_frozen(store):
    """A technician registers (hashlib digest kept, the file's name, who, the audit event);
    the same file twice for the table, two valid from one day, a due date before the start
    and a retired table are refused in one line; UPDATE and DELETE of a registered row are
    refused by the database itself."""
    people, inst_id, table_id, _ = setup_lab(store)
    tc = register(store, people["tech"], table_id, "TC-1")
    assert (tc.sha256, tc.name, tc.certificate) == (SHA["TC-1"], "TC-1.csv", "TC-1")
    assert services.file_bytes(store, tc.sha256) == FILES["TC-1"]
    with store.session() as s:
        ev = s.scalar(select(AuditEvent).where(AuditEvent.action == "register",
                                               AuditEvent.entity == "table-calibration"))
        assert ev.username == "tech" and ev.entity_id == str(tc.id)
        after = json.loads(ev.after_json)
        assert (after["sha256"], after["table"], after["valid_from"], after["due_on"]) == \
            (SHA["TC-1"], "RT-07", "2025-01-01", "2026-01-01")
    for kw, expect in (
            ({"key": "TC-1"}, "is registered for RT-07 already"),
            ({"key": "TC-2", "valid_from": "2025-01-01"}, "is valid from 2025-01-01 already"),
            ({"key": "TC-3", "valid_from": "2025-05-01", "due_on": "2025-04-30"},
             "due_on 2025-04-30 is not after valid_from 2025-05-01")):
        sha, _ = services.store_file(store, io.BytesIO(FILES[kw["key"]]))
        with pytest.raises(GonioError, match=expect) as e:
            services.register_table_calibration(
                store, people["tech"], standard_id=table_id, sha256=sha, name="x.csv",
                valid_from=kw.get("valid_from", "2025-02-02"),
                due_on=kw.get("due_on", "2026-02-02"))
        assert "\n" not in str(e.value)
    services.update_standard(store, people["tech"], table_id, retire=True)
    sha, _ = services.store_file(store, io.BytesIO(FILES["TC-3"]))
    with pytest.raises(GonioError, match="standard RT-07 was retired on"):
        services.register_table_calibration(store, people["tech"], standard_id=table_id,
                                            sha256=sha, valid_from="2025-09-01",
                                            due_on="2026-09-01")
    for stmt in (update(TableCalibration).values(due_on=dt.date(2099, 1, 1)),
                 TableCalibration.__table__.delete()):
        with store.writing() as s:
            with pytest.raises((DBAPIError, IntegrityError), match="never changed or removed"):
                s.execute(stmt)
            s.rollback()
    assert len(services.table_calibrations(store)) == 1


def test_who_may_register(store):
    """Registering equipment is the technician's (docs/records.md, roles): a reviewer and an
    administrator without the technician role are refused, nothing registered; the
    technician registers alone, as a standard is registered (the project's rules ask no
    second person for equipment)."""
    people, _, table_id, _ = setup_lab(store)
    only_admin = services.create_user(store, people["admin"], "boss", PASSWORD, "admin")
    sha, _ = services.store_file(store, io.BytesIO(FILES["TC-1"]))
    for who in (people["rev"], only_admin):
        with pytest.raises(GonioError, match="technician role"):
            services.register_table_calibration(store, who, standard_id=table_id, sha256=sha,
                                                valid_from="2025-01-01", due_on="2026-01-01")
    assert services.table_calibrations(store) == []
    register(store, people["tech"], table_id, "TC-1")
    assert len(services.table_calibrations(store)) == 1


def test_state_against_a_second_rule_every_day():
    """table_calibration_state's "in force" agrees with the second rule on every day of two
    years, for TC-1 and TC-2 of one table (TC-2 supersedes TC-1 from 2025-06-01; TC-2 expires
    on 2026-03-02, TC-1 is then superseded still, not in force again)."""
    rows = [TableCalibration(id=i + 1, certificate=k, valid_from=dt.date.fromisoformat(a),
                             due_on=dt.date.fromisoformat(b))
            for i, (k, (a, b)) in enumerate(VALID.items())]
    entries = [(k, a, b) for k, (a, b) in VALID.items()]
    day, seen = dt.date(2024, 12, 1), set()
    while day < dt.date(2026, 12, 1):
        got = [r.certificate for r in rows if not services.table_calibration_state(r, rows, day)]
        want = in_force_here(entries, day)
        assert got == ([want] if want else []), day
        seen.add(want)
        day += dt.timedelta(days=1)
    assert seen == {None, "TC-1", "TC-2"}


def test_calibration_picks_the_one_in_force_and_keeps_it(store):
    """Without a choice a calibration takes the register's calibration in force on its date
    of the table among its standards (the second rule): its file is the calibration's
    table_calibration.csv (hashlib digest), the calibration records the entry, the audit
    event names it and its file's name; a calibration not naming the table takes none; the
    register lists how many used each."""
    people, inst_id, table_id, other_id = setup_lab(store)
    tech = people["tech"]
    ids = {k: register(store, tech, table_id, k).id for k in VALID}
    entries = [(k, a, b) for k, (a, b) in VALID.items()]
    count = {k: 0 for k in VALID}
    for day in ("2025-03-01", "2025-06-01", "2025-12-31", "2026-03-01"):
        want = in_force_here(entries, dt.date.fromisoformat(day))
        count[want] += 1
        cal = create(store, tech, inst_id, day, [table_id, other_id])
        assert cal.table_calibration_id == ids[want], day
        with store.session() as s:
            assert s.get(CalibrationFile, (cal.id, "table_calibration.csv")).sha256 == SHA[want]
            assert services.table_calibration_name(s, cal.id) == f"{want}.csv"
            ev = json.loads(s.scalar(select(AuditEvent.after_json).where(
                AuditEvent.action == "table-calibration",
                AuditEvent.entity_id == str(cal.id))))
        assert (ev["register_id"], ev["picked"]) == (ids[want], f"in force on {day}")
    cal = create(store, tech, inst_id, "2025-03-01", [other_id])
    assert cal.table_calibration_id is None
    with store.session() as s:
        assert s.get(CalibrationFile, (cal.id, "table_calibration.csv")) is None
    used = {r["entry"].certificate: r["used"] for r in services.table_calibrations(store)}
    assert used == count == {"TC-1": 1, "TC-2": 3}


@pytest.mark.parametrize("day, pick, upload, expect", [
    ("2025-07-01", "TC-1", None, "table calibration 1 (TC-1) of RT-07 cannot be used on "
                                 "2025-07-01: superseded by table calibration 2 (TC-2) valid "
                                 "from 2025-06-01"),
    ("2026-03-02", "TC-2", None, "table calibration 2 (TC-2) of RT-07 cannot be used on "
                                 "2026-03-02: expired: it was due on 2026-03-01"),
    ("2024-12-31", "TC-1", None, "cannot be used on 2024-12-31: not yet valid"),
    ("2026-03-02", None, None, "no calibration of the table RT-07 in the register is in force "
                               "on 2026-03-02"),
    ("2025-07-01", None, "TC-3", "the register holds the calibrations of the table RT-07, and "
                                 "the file uploaded"),
    ("2025-07-01", "TC-2", "TC-1", "the table calibration uploaded (SHA-256"),
], ids=["superseded", "expired", "not-yet-valid", "none-in-force", "unregistered-upload",
        "pick-and-other-upload"])
def test_refused_in_one_line(store, day, pick, upload, expect):
    """An expired, superseded or not yet valid choice, no calibration of the ticked table in
    force, an upload the register does not hold while it holds the table's: one line, nothing
    created."""
    people, inst_id, table_id, _ = setup_lab(store)
    ids = {k: register(store, people["tech"], table_id, k).id for k in VALID}
    kw = {}
    if pick:
        kw["table_calibration_id"] = ids[pick]
    if upload:
        kw["table_calibration_sha256"] = services.store_file(store, io.BytesIO(FILES[upload]))[0]
    with pytest.raises(GonioError) as e:
        create(store, people["tech"], inst_id, day, [table_id], **kw)
    msg = str(e.value)
    assert expect in msg and "\n" not in msg, msg
    with store.session() as s:
        assert s.scalar(select(Calibration.id)) is None


def test_choice_and_registered_upload_accepted(store):
    """The entry chosen (in force), or an upload whose bytes are the register's entry in
    force, is used and recorded as that entry."""
    people, inst_id, table_id, _ = setup_lab(store)
    ids = {k: register(store, people["tech"], table_id, k).id for k in VALID}
    cal = create(store, people["tech"], inst_id, "2025-03-01", [table_id],
                 table_calibration_id=str(ids["TC-1"]))
    assert cal.table_calibration_id == ids["TC-1"]
    sha = services.store_file(store, io.BytesIO(FILES["TC-2"]))[0]
    cal = create(store, people["tech"], inst_id, "2025-07-01", [table_id],
                 table_calibration_sha256=sha, table_calibration_name="copy.csv")
    assert cal.table_calibration_id == ids["TC-2"]
    with store.session() as s:
        assert services.table_calibration_name(s, cal.id) == "TC-2.csv"


def test_seal_checks_the_register_entry(store, computed_folder):
    """The calibration's stored table_calibration.csv pointed at another file after its run:
    the seal (review, approval, issue) refuses, naming the register's entry."""
    people, inst_id, table_id, _ = setup_lab(store)
    tc = register(store, people["tech"], table_id, "TC-1")
    cal = create(store, people["tech"], inst_id, "2025-03-01", [table_id])
    store_run_as_computed(store, cal.id, computed_folder)
    sealed = services.seal(store, cal.id)
    other = services.store_file(store, io.BytesIO(FILES["TC-3"]))[0]
    with store.writing() as s:
        s.execute(update(CalibrationFile).where(
            CalibrationFile.calibration_id == cal.id,
            CalibrationFile.name == "table_calibration.csv").values(sha256=other))
        s.commit()
    with pytest.raises(GonioError, match=f"register's table calibration {tc.id} the "
                                         "calibration used"):
        services.seal(store, cal.id)
    with store.writing() as s:
        s.execute(update(CalibrationFile).where(
            CalibrationFile.calibration_id == cal.id,
            CalibrationFile.name == "table_calibration.csv").values(sha256=SHA["TC-1"]))
        s.commit()
    assert services.seal(store, cal.id) == sealed


def test_backup_restore_keeps_the_register(store, tmp_path):
    """A backup restored into empty records holds the register (same rows, bytes by hashlib)
    and which entry each calibration used."""
    from gonio.records.backup import backup, restore
    from gonio.records.db import open_store

    people, inst_id, table_id, _ = setup_lab(store)
    for k in VALID:
        register(store, people["tech"], table_id, k)
    cal = create(store, people["tech"], inst_id, "2025-07-01", [table_id])
    backup(store, tmp_path / "b.zip")
    target = open_store(None, tmp_path / "target")
    try:
        restore(target, tmp_path / "b.zip")
        got = [(r["entry"].certificate, r["entry"].sha256, str(r["entry"].valid_from))
               for r in services.table_calibrations(target)]
        assert sorted(got) == [("TC-1", SHA["TC-1"], "2025-01-01"),
                               ("TC-2", SHA["TC-2"], "2025-06-01")]
        assert services.calibration(target, cal.id).table_calibration_id == \
            cal.table_calibration_id
        assert hashlib.sha256(services.file_bytes(target, SHA["TC-2"])).hexdigest() == SHA["TC-2"]
    finally:
        target.close()


def test_migration_0009_over_0008(tmp_path, pg_server):
    """A database made at 0008 with a calibration, upgraded: the register exists, empty, and
    the calibration used none — on SQLite and PostgreSQL."""
    from gonio.records.db import open_store

    from .conftest import both_back_ends, insert_instrument, records_at

    for url, data in both_back_ends(tmp_path, pg_server):
        st = records_at(url, data, "0008")
        with st.engine.begin() as c:
            insert_instrument(c)
            c.execute(text(
                "INSERT INTO calibrations (id, instrument_id, spec_key, protocol, "
                "readings_sha256, readings_name, lab_name, place, performed_on, status, "
                "progress, error, worker_host, created_at, review_comment, pending_reason, "
                "pending_number, reviewed_seal, approved_seal) VALUES (1, 1, 'ogam-draft', "
                "'', :s, '', '', '', '2025-01-01', 'queued', '', '', '', '2025-01-01', '', "
                "'', '', '', '')"), {"s": "a" * 64})
        st.close()
        st = open_store(url, data)
        try:
            assert services.calibration(st, 1).table_calibration_id is None
            assert services.table_calibrations(st) == []
        finally:
            st.close()


def test_command_line_registers_and_lists(store, tmp_path, capsys, monkeypatch):
    """``gonio db register-table-calibration`` (technician; a reviewer is refused, exit 2,
    one line) and ``gonio db table-calibrations`` (which is in force on --date) — on the
    back end of ``store``; ``--user`` logs in with the password in $GONIO_PASSWORD."""
    from gonio.cli import main

    from .conftest import PASSWORD

    monkeypatch.setenv("GONIO_PASSWORD", PASSWORD)

    people, _, table_id, _ = setup_lab(store)
    where = ["--database", store.url] if not store.url.startswith("sqlite") else \
        ["--data", str(store.blob_root.parent)]
    for k in VALID:
        (tmp_path / f"{k} file.csv").write_bytes(FILES[k])
    args = ["db", "register-table-calibration", str(tmp_path / "TC-1 file.csv"), "--table",
            "RT-07", "--valid-from", VALID["TC-1"][0], "--due-on", VALID["TC-1"][1],
            "--certificate", "TC-1", *where]
    assert main(args + ["--user", "rev"]) == 2
    err = capsys.readouterr().err
    assert "technician role" in err and err.count("\n") == 1, err
    assert main(args + ["--user", "tech"]) == 0
    assert SHA["TC-1"] in capsys.readouterr().out
    assert main(["db", "register-table-calibration", str(tmp_path / "TC-2 file.csv"), "--table",
                 "RT-07", "--valid-from", VALID["TC-2"][0], "--due-on", VALID["TC-2"][1],
                 "--certificate", "TC-2", "--user", "tech", *where]) == 0
    capsys.readouterr()
    for day, want in (("2025-03-01", {"TC-1": "in force", "TC-2": "not yet valid"}),
                      ("2025-07-01", {"TC-1": "superseded", "TC-2": "in force"})):
        assert main(["db", "table-calibrations", "--date", day, *where]) == 0
        lines = [ln.split("\t") for ln in capsys.readouterr().out.splitlines()]
        got = {ln[2]: ln[7] for ln in lines}
        assert set(got) == set(want) and all(got[k].startswith(v) for k, v in want.items()), got
        assert {ln[3] for ln in lines} == {"TC-1 file.csv", "TC-2 file.csv"}
        assert in_force_here([(k, a, b) for k, (a, b) in VALID.items()],
                             dt.date.fromisoformat(day)) == \
            next(k for k, v in want.items() if v == "in force")


def test_web_register_page_and_form(tmp_path, bench_readings):
    """The register's page: a technician registers (a hostile file name shown escaped, the
    file served by its link), a reviewer's registration is refused on the server; the
    calibration form offers the register and a superseded choice comes back in one line."""
    import html as html_module
    import re

    from gonio.records.db import open_store
    from gonio.web.app import create_app

    from .test_web_lab_file import alert, instrument
    from .test_web_security import csrf_of, login

    st = open_store(None, tmp_path / "data")
    try:
        for name, roles in (("tech", "technician"), ("rev", "reviewer"),
                            ("admin", "admin technician reviewer")):
            services.create_user(st, None, name, PASSWORD, roles)
        app = create_app(st)
        inst = instrument(st)                     # registers the table RT-07 too
        with st.session() as s:
            from gonio.records.models import Standard
            table_id = s.scalar(select(Standard.id).where(Standard.identifier == "RT-07"))
        hostile = "<img src=x onerror=alert(1)>&TC-1.csv"

        def post(c, key, name):
            return c.post("/table-calibrations", data={
                "csrf": csrf_of(c), "standard_id": str(table_id), "certificate": key,
                "valid_from": VALID[key][0], "due_on": VALID[key][1]},
                files={"file": (name, io.BytesIO(FILES[key]))})

        rev = login(app, "rev")
        r = post(rev, "TC-1", "a.csv")
        assert r.status_code == 400 and "technician role" in alert(r.text)
        assert services.table_calibrations(st) == []
        tech = login(app, "tech")
        assert post(tech, "TC-1", hostile).status_code == 303
        assert post(tech, "TC-2", "TC-2.csv").status_code == 303
        page = tech.get("/table-calibrations").text
        assert "<img src=x" not in page
        assert "&lt;img src=x onerror=alert(1)&gt;&amp;TC-1.csv" in page
        assert SHA["TC-1"] in page and "expired: it was due on 2026-01-01" in page
        page = tech.get("/table-calibrations?date=2025-07-01").text
        assert "superseded by table calibration 2 (TC-2) valid from 2025-06-01" in page
        assert "<td>in force</td>" in page
        exported = tech.get("/export/table_calibrations.csv")
        assert exported.status_code == 200
        import csv
        rows = list(csv.DictReader(io.StringIO(exported.text)))
        assert [(r["certificate"], r["sha256"], r["valid_from"], r["file"]) for r in rows] == \
            [("TC-2", SHA["TC-2"], "2025-06-01", "TC-2.csv"),
             ("TC-1", SHA["TC-1"], "2025-01-01", hostile)]
        now = dt.datetime.now(dt.timezone.utc)
        for r in rows:      # UTC, marked: within a few minutes of the clock's UTC now
            at = dt.datetime.fromisoformat(r["registered_at"].replace("Z", "+00:00"))
            assert r["registered_at"].endswith("Z") and abs(now - at) < dt.timedelta(minutes=10)
        std_page = tech.get(f"/standards/{table_id}").text
        assert 'id="table-calibrations"' in std_page and SHA["TC-2"] in std_page
        assert "<img src=x" not in std_page
        got = tech.get("/table-calibrations/1/file")
        assert got.status_code == 200 and hashlib.sha256(got.content).hexdigest() == SHA["TC-1"]
        assert tech.get("/table-calibrations/99/file").status_code == 404
        form = tech.get(f"/instruments/{inst.id}/calibrate").text
        assert 'name="table_calibration_id"' in form and "<img src=x" not in form
        from pathlib import Path

        from .test_records_table_calibration import SMALL_PROTOCOL
        r = tech.post(f"/instruments/{inst.id}/calibrate", files={
            "readings": ("readings.csv", io.BytesIO(Path(bench_readings[0]).read_bytes())),
            "protocol_file": ("protocol.toml", io.BytesIO(SMALL_PROTOCOL.read_bytes()))},
            data={"csrf": csrf_of(tech), "performed_on": "2025-07-01",
                  "standards": [str(table_id)], "temperature_c": "20.1", "humidity_pct": "45",
                  "table_calibration_id": "1"})
        assert r.status_code == 400
        msg = alert(r.text)
        assert "cannot be used on 2025-07-01: superseded by table calibration 2" in msg
        assert "\n" not in msg
        assert re.search(r'<option value="1" selected', r.text)   # the choice kept
        r = tech.post(f"/instruments/{inst.id}/calibrate", files={
            "readings": ("readings.csv", io.BytesIO(Path(bench_readings[0]).read_bytes())),
            "protocol_file": ("protocol.toml", io.BytesIO(SMALL_PROTOCOL.read_bytes()))},
            data={"csrf": csrf_of(tech), "performed_on": "2025-07-01",
                  "standards": [str(table_id)], "temperature_c": "20.1", "humidity_pct": "45"})
        assert r.status_code == 303, alert(r.text)
        cal_id = int(r.headers["location"].rsplit("/", 1)[1])
        assert services.calibration(st, cal_id).table_calibration_id == 2
        page = tech.get(f"/calibrations/{cal_id}").text
        fact = page[page.index('id="table-calibration"'):]
        fact = html_module.unescape(fact[:fact.index("</dd>")])
        assert "TC-2.csv" in fact and "table calibration 2" in fact and "RT-07" in fact
    finally:
        st.close()


def test_import_records_the_register_entry(tmp_path, bench_readings, capsys):
    """``gonio db import --lab FILE`` of a run made with the laboratory file's
    [table_calibration], whose [[standards]] name the table: the register's entry of that
    file (hashlib digest) is recorded as the one used; in records where a later calibration
    of the table, valid from the calibration's date, supersedes it, the import is refused in
    one line and nothing is recorded."""
    from gonio.cli import main
    from gonio.records.db import open_store
    from gonio.records.importer import import_output_folder

    from .test_records_table_calibration import IMPORT_LAB, SHA as TSHA, SMALL_PROTOCOL, TABLE

    (tmp_path / "tc.csv").write_bytes(TABLE)
    lab = tmp_path / "lab.toml"
    lab.write_text(IMPORT_LAB.format(sha=TSHA) + '\n[[standards]]\nname = "rotary table"\n'
                   'identifier = "RT-07"\n', encoding="utf-8")
    out = tmp_path / "run"
    assert main(["calibrate", str(bench_readings[0]), "--protocol", str(SMALL_PROTOCOL),
                 "--lab", str(lab), "--out", str(out)]) == 0
    capsys.readouterr()
    day = None
    for i, supersede in enumerate((False, True)):
        st = open_store(None, tmp_path / f"data{i}")
        try:
            people, _, table_id, _ = setup_lab(st)
            sha, _ = services.store_file(st, io.BytesIO(TABLE))
            entry = services.register_table_calibration(
                st, people["tech"], standard_id=table_id, sha256=sha, name="tc.csv",
                valid_from="2025-12-01", due_on="2027-12-01", certificate="TC-9")
            if supersede:
                other = services.store_file(st, io.BytesIO(FILES["TC-3"]))[0]
                services.register_table_calibration(
                    st, people["tech"], standard_id=table_id, sha256=other, valid_from=day,
                    due_on=services.add_months(day, 12), certificate="TC-10")
                with pytest.raises(GonioError, match=f"cannot be used on {day}: superseded by "
                                                     "table calibration 2 \\(TC-10\\)"):
                    import_output_folder(st, out, lab=lab, readings=bench_readings[0],
                                         protocol=SMALL_PROTOCOL)
                with st.session() as s:
                    assert s.scalar(select(Calibration.id)) is None
                continue
            cal_id = import_output_folder(st, out, lab=lab, readings=bench_readings[0],
                                          protocol=SMALL_PROTOCOL)
            cal = services.calibration(st, cal_id)
            assert cal.table_calibration_id == entry.id and entry.sha256 == TSHA
            with st.session() as s:
                assert s.get(CalibrationFile, (cal_id, "table_calibration.csv")).sha256 == TSHA
            assert services.seal(st, cal_id)
            day = cal.performed_on
        finally:
            st.close()


def test_lookalike_names_refused_and_not_shown(store):
    """A table calibration's name with an invisible or direction-changing character (Unicode
    Cf, a C1 control) is refused in one line naming the code point, at registration and at a
    calibration's upload; one recorded before (its audit event) is shown as the storage
    name."""
    people, inst_id, table_id, other_id = setup_lab(store)
    for bad in ("\u202e", "\u2069", "\u200e", "\ufeff", "\x9b"):
        with pytest.raises(GonioError, match=f"U\\+{ord(bad):04X}") as e:
            register(store, people["tech"], table_id, "TC-1", name=f"calib{bad}vsc.exe")
        assert "\n" not in str(e.value)
    sha, _ = services.store_file(store, io.BytesIO(FILES["TC-3"]))
    with pytest.raises(GonioError, match="U\\+202E|not in the register"):
        create(store, people["tech"], inst_id, "2025-02-01", [table_id, other_id],
               table_calibration_sha256=sha, table_calibration_name="calib\u202evsc.exe")
    services.register_table_calibration(store, people["tech"], standard_id=table_id,
                                        sha256=sha, name="RT-07.csv", valid_from="2025-01-01",
                                        due_on="2026-01-01", certificate="TC-3")
    cal = create(store, people["tech"], inst_id, "2025-02-01", [table_id, other_id],
                 table_calibration_sha256=sha, table_calibration_name="RT-07.csv")
    with store.session() as s:
        assert services.table_calibration_name(s, cal.id) == "RT-07.csv"
    with store.writing() as s:      # as an older release recorded it
        services.audit(s, people["tech"], "table-calibration", "calibration", cal.id, None,
                       {"sha256": sha, "name": "calib\u202evsc.exe"})
        s.commit()
    with store.session() as s:
        assert services.table_calibration_name(s, cal.id) == services.TABLE_CALIBRATION


@pytest.mark.parametrize("standards, day, expect", [
    ("other", "2026-02-01", "table calibration 1 (TC-1) of RT-07 is of a table the calibration "
                            "does not name among its standards: tick the table"),
    ("both", "2026-02-01", "table calibration 1 (TC-1) of RT-07 cannot be used on 2026-02-01: "
                           "expired: it was due on 2026-01-01"),
    ("other", "2025-03-01", "table calibration 1 (TC-1) of RT-07 is of a table the calibration "
                            "does not name among its standards"),
], ids=["expired-table-not-ticked", "expired-table-ticked", "in-force-table-not-ticked"])
def test_registered_upload_looked_up_in_the_whole_register(store, standards, day, expect):
    """An upload of a registered file is that entry, whichever standards are ticked: its table
    must be among them and the entry in force (an expired TC-1 uploaded with only the
    autocollimator ticked is not used as a bare upload): one line, nothing created."""
    people, inst_id, table_id, other_id = setup_lab(store)
    register(store, people["tech"], table_id, "TC-1")
    sha = services.store_file(store, io.BytesIO(FILES["TC-1"]))[0]
    ids = [other_id] if standards == "other" else [table_id, other_id]
    with pytest.raises(GonioError) as e:
        create(store, people["tech"], inst_id, day, ids, table_calibration_sha256=sha)
    msg = str(e.value)
    assert expect in msg and "\n" not in msg, msg
    with store.session() as s:
        assert s.scalar(select(Calibration.id)) is None


def test_seal_binds_the_register_entry(store, computed_folder):
    """The calibration's table_calibration_id emptied, or pointed at another table's entry
    holding the same file, after signing: the seal no longer matches; put back, it does."""
    people, inst_id, table_id, _ = setup_lab(store)
    tech = people["tech"]
    tc = register(store, tech, table_id, "TC-1")
    rt8 = services.add_standard(store, tech, name="rotary table", identifier="RT-08",
                                due_on="2099-01-01")
    twin = register(store, tech, rt8.id, "TC-1")
    assert twin.sha256 == tc.sha256 and twin.id != tc.id
    cal = create(store, tech, inst_id, "2025-03-01", [table_id])
    assert cal.table_calibration_id == tc.id
    store_run_as_computed(store, cal.id, computed_folder)
    sealed = services.seal(store, cal.id)
    for tampered in (None, twin.id):
        with store.writing() as s:
            s.execute(update(Calibration).where(Calibration.id == cal.id)
                      .values(table_calibration_id=tampered))
            s.commit()
        assert services.seal(store, cal.id) != sealed, tampered
    with store.writing() as s:
        s.execute(update(Calibration).where(Calibration.id == cal.id)
                  .values(table_calibration_id=tc.id))
        s.commit()
    assert services.seal(store, cal.id) == sealed


@pytest.mark.parametrize("data, expect", [
    (b"table_deg,error_arcsec,u_arcsec\n0,0.0,0.02\n120,0.01\x00,0.02\n",
     "bad.csv:3: column error_arcsec: not a table calibration: expected a number"),
    (b"table_deg,error_arcsec,u_arcsec\n0,0.0,0.02\n120,=1+1,0.02\n",
     "bad.csv:3: column error_arcsec: not a table calibration: expected a number, got '=1+1'"),
    (b"\x00\x01\x02\xff binary", "bad.csv"),
], ids=["nul", "formula", "binary"])
def test_register_reads_the_file_first(store, data, expect):
    """A file the table calibration reader does not take (a NUL byte, a spreadsheet
    formula, binary bytes) is refused in one line naming it, and nothing is registered."""
    people, _, table_id, _ = setup_lab(store)
    sha, _ = services.store_file(store, io.BytesIO(data))
    with pytest.raises(GonioError) as e:
        services.register_table_calibration(store, people["tech"], standard_id=table_id,
                                            sha256=sha, name="bad.csv", valid_from="2025-01-01",
                                            due_on="2026-01-01")
    msg = str(e.value)
    assert expect in msg and "not a table calibration" in msg and "\n" not in msg, msg
    with store.session() as s:
        assert s.scalar(select(TableCalibration.id)) is None


def test_register_today_is_the_laboratorys_date(store, monkeypatch):
    """The register's state "today" is the laboratory's date in its zone (setting
    ``timezone`` Asia/Shanghai, UTC+8): TC-1 (due 2026-01-01) at 15:30 UTC on its due date
    (23:30 in Beijing) is in force, at 16:30 UTC (00:30 on 2026-01-02 in Beijing) expired,
    whatever the machine's zone."""
    people, _, table_id, _ = setup_lab(store)
    register(store, people["tech"], table_id, "TC-1")
    services.set_settings(store, None, timezone="Asia/Shanghai")
    for at, want in ((dt.datetime(2026, 1, 1, 15, 30), ""),
                     (dt.datetime(2026, 1, 1, 16, 30), "expired: it was due on 2026-01-01")):
        monkeypatch.setattr(services, "utcnow", lambda at=at: at)
        monkeypatch.setattr(models, "utcnow", lambda at=at: at)    # models.records_today
        assert [r["state"] for r in services.table_calibrations(store)] == [want], at


@pytest.mark.parametrize("content, standards", [
    (lambda b: b + b"\n", "other"),                              # one byte more, table not ticked
    (lambda b: b.replace(b"0.010", b"0.500"), "other"),          # its 120 deg error edited
    (lambda b: b.replace(b"0.010", b"0.500"), "table"),          # edited, the table ticked
], ids=["newline-table-not-ticked", "edited-table-not-ticked",
        "edited-table-ticked"])
def test_unregistered_upload_refused(store, content, standards):
    """A table calibration that corrects a result is a registered entry: an upload the register
    does not hold (a registered file plus one byte, or with an error edited) is refused in one
    line naming the register command, whatever is ticked (was: accepted as a bare upload,
    table_calibration_id None, when no rotary table was ticked); nothing created."""
    people, inst_id, table_id, other_id = setup_lab(store)
    register(store, people["tech"], table_id, "TC-1")
    sha = services.store_file(store, io.BytesIO(content(FILES["TC-1"])))[0]
    assert sha != hashlib.sha256(FILES["TC-1"]).hexdigest()
    ids = {"other": [other_id], "table": [table_id, other_id]}[standards]
    with pytest.raises(GonioError) as e:
        create(store, people["tech"], inst_id, "2025-03-01", ids, table_calibration_sha256=sha,
               table_calibration_name="TC-1.csv")
    msg = str(e.value)
    assert "\n" not in msg and ("gonio db register-table-calibration" in msg
                                or "register the new file" in msg), msg
    with store.session() as s:
        assert s.scalar(select(Calibration.id)) is None
