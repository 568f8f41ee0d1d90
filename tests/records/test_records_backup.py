"""Backups that restore: ``gonio db backup`` refuses (exit 2, naming it) a stored file that
is missing or damaged; ``gonio db restore`` checks completeness, integrity and every row and
reference of the archive before writing anything; ``gonio db verify`` checks the live
records (files, result rows, signed seals) and finds a certificate file's record."""

from __future__ import annotations

import json
import os
import shutil
import zipfile

import pytest
from sqlalchemy import func, select, text

from gonio.cli import main
from gonio.errors import GonioError
from gonio.records import blobs, services
from gonio.records.backup import backup, restore
from gonio.records.db import open_store
from gonio.records.models import AuditEvent, Certificate, User

from .conftest import PASSWORD, make_people
from .test_records_services import new_calibration, run_worker, setup_instrument


@pytest.fixture(scope="module")
def _records_made_once(tmp_path_factory, computed_folder, bench_readings):
    """The data folder of :func:`records`, made once for the module (people, an issue and a
    computation each test would otherwise make again: some 5 s a test)."""
    data = tmp_path_factory.mktemp("records-once") / "data"
    st = open_store(None, data)
    try:
        with pytest.MonkeyPatch.context() as mp:
            people = make_people(st)
            inst, std = one_issued(st, people, computed_folder, bench_readings, mp)
            new_calibration(st, people, inst, std, bench_readings[1])
            run_worker(st, mp, computed_folder)
    finally:
        st.close()
    return data


@pytest.fixture
def records(_records_made_once, tmp_path):
    """A SQLite records store with one issued certificate and one computed calibration: a
    copy of the module's folder (database and stored files, modes kept) in
    ``tmp_path / "data"``, the test's own to change."""
    shutil.copytree(_records_made_once, tmp_path / "data")
    st = open_store(None, tmp_path / "data")
    yield st
    st.close()


def one_issued(store, people, computed_folder, bench_readings, monkeypatch):
    """One calibration computed, reviewed, approved and issued in ``store``: (instrument,
    standard)."""
    inst, std = setup_instrument(store, people)
    cal = new_calibration(store, people, inst, std, bench_readings[0])
    run_worker(store, monkeypatch, computed_folder)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev2"], cal.id)
    run_worker(store, monkeypatch, computed_folder)
    return inst, std


def cli(argv, capsys, rc):
    assert main([str(a) for a in argv]) == rc
    out = capsys.readouterr()
    if rc == 2:
        assert out.err.startswith("gonio: error: ") and out.err.count("\n") == 1, out.err
    return out


def damage(store, sha):
    path = blobs.blob_path(store.blob_root, sha)
    path.chmod(0o644)
    path.write_bytes(path.read_bytes() + b"\n")


def first_pdf(store):
    with store.session() as s:
        return s.scalar(select(Certificate.pdf_sha256))


def test_backup_refuses_a_damaged_stored_file(records, tmp_path, capsys):
    sha = first_pdf(records)
    damage(records, sha)
    archive = tmp_path / "b.zip"
    out = cli(["db", "backup", archive, "--data", records.data], capsys, 2)
    assert sha in out.err and "damaged" in out.err
    assert not archive.exists() and not list(tmp_path.glob(".backup-*"))
    out = cli(["db", "verify", "--data", records.data], capsys, 2)
    assert f"stored file {sha} (damaged)" in out.out


def test_verify_live_records_and_a_certificate_file(records, tmp_path, capsys):
    out = cli(["db", "verify", "--data", records.data], capsys, 0)
    assert "records verified: files" in out.out and "certificates 1" in out.out
    pdf = tmp_path / "c.pdf"
    pdf.write_bytes(services.file_bytes(records, first_pdf(records)))
    out = cli(["db", "verify", "--certificate", pdf, "--data", records.data], capsys, 0)
    with records.session() as s:
        cert = s.scalar(select(Certificate))
    assert cert.number in out.out and cert.seal_sha256 in out.out
    with records.writing() as s:
        s.execute(text("UPDATE result_items SET value = value*1.5 WHERE key='scale_factor'"))
        s.commit()
    out = cli(["db", "verify", "--data", records.data], capsys, 2)
    assert "calibration 1: the stored result row scale_factor differs" in out.out
    assert "calibration 2: the stored result row scale_factor differs" in out.out
    out = cli(["db", "verify", "--certificate", pdf, "--data", records.data], capsys, 2)
    assert "scale_factor differs" in out.err


def archive_without(src, dst, drop=None, records_json=None):
    with zipfile.ZipFile(src) as a, zipfile.ZipFile(dst, "w") as b:
        for n in a.namelist():
            if n == drop:
                continue
            data = a.read(n)
            if n == "records.json" and records_json is not None:
                data = json.dumps(records_json(json.loads(data))).encode()
            b.writestr(n, data)
    return dst


def empty_target(tmp_path):
    return open_store(None, tmp_path / "target")


def assert_empty(store):
    with store.session() as s:
        assert s.scalar(select(func.count()).select_from(User)) == 0
    assert not list(store.blob_root.rglob("*")) or not any(
        p.is_file() and not p.name.startswith(".") for p in store.blob_root.rglob("*"))


def test_restore_refuses_an_incomplete_archive(records, tmp_path):
    full = tmp_path / "full.zip"
    backup(records, full)
    part = archive_without(full, tmp_path / "part.zip", drop=f"blobs/{first_pdf(records)}")
    target = empty_target(tmp_path)
    try:
        with pytest.raises(GonioError, match="incomplete: 1 stored file"):
            restore(target, part)
        assert_empty(target)
        assert restore(target, full)["certificates"] == 1
    finally:
        target.close()


def _set(table, col, value, row=0):
    def edit(doc):
        t = doc["tables"][table]
        t["rows"][row][t["columns"].index(col)] = value
        return doc
    return edit


HOSTILE = {
    "a list": (lambda doc: [doc], "unknown backup format 'list'"),
    "not a date": (_set("calibrations", "performed_on", "not a date"),
                   "calibrations row 1: performed_on is not a date: 'not a date'"),
    "instrument 999999": (_set("calibrations", "instrument_id", 999999),
                          "calibrations row 1: instrument_id 999999 is not among the "
                          "archive's instruments"),
    "tables a list": (lambda doc: dict(doc, tables=[]), "records.json has no tables"),
    "rows a string": (lambda doc: (doc["tables"]["users"].update(rows="x"), doc)[1],
                      "table users is not"),
    "short row": (lambda doc: (doc["tables"]["users"]["rows"][0].pop(), doc)[1],
                  "users row 1: a row is a list of"),
    "unknown table": (lambda doc: (doc["tables"].update(extra={"columns": [], "rows": []}),
                                   doc)[1], "tables this gonio does not know"),
}


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_restore_refuses_a_hostile_archive_with_one_line(records, tmp_path, capsys, name):
    full = tmp_path / "full.zip"
    backup(records, full)
    edit, message = HOSTILE[name]
    bad = archive_without(full, tmp_path / "bad.zip", records_json=edit)
    out = cli(["db", "restore", bad, "--data", tmp_path / "target"], capsys, 2)
    assert message in out.err, out.err
    target = empty_target(tmp_path)
    try:
        assert_empty(target)
    finally:
        target.close()





def test_db_restore_replace_on_the_command_line(records, tmp_path, capsys, monkeypatch):
    """``gonio db restore --replace`` replaces a populated SQLite database with the archive's
    records through the browser's function (an active admin named, the archive confirmed by
    its SHA-256, the replaced file kept); without the confirmation, by a non-admin, or with an
    archive that fails its checks, one line and the live records as they were."""
    import hashlib

    from gonio.records.backup import summary

    people = {u: services.user(records, u) for u in ("tech", "admin")}
    archive = tmp_path / "nightly.zip"
    backup(records, archive)
    digest = hashlib.sha256(archive.read_bytes()).hexdigest()     # independently of gonio
    services.add_customer(records, people["tech"], "After the backup Ltd")
    live = summary(records)["rows"]
    records.engine.dispose()          # the command line opens the database itself
    data = ["--data", records.data]
    monkeypatch.setenv("GONIO_PASSWORD", PASSWORD)     # the named user's, as at the login

    err = cli(["db", "restore", archive, "--replace", "--user", "admin", *data], capsys, 2).err
    assert f"--sha256 {digest}" in err and "nothing restored" in err
    cli(["db", "restore", archive, "--replace", "--user", "tech", "--sha256", digest, *data],
        capsys, 2)
    cli(["db", "restore", archive, "--replace", "--sha256", digest, *data], capsys, 2)
    cli(["db", "restore", archive, "--user", "admin", *data], capsys, 2)   # no --replace
    err = cli(["db", "restore", archive, "--replace", "--user", "admin", "--sha256", "0" * 64,
               *data], capsys, 2).err
    assert "not the one verified and confirmed" in err
    part = archive_without(archive, tmp_path / "part.zip", drop=f"blobs/{first_pdf(records)}")
    err = cli(["db", "restore", part, "--replace", "--user", "admin", "--sha256",
               hashlib.sha256(part.read_bytes()).hexdigest(), *data], capsys, 2).err
    assert "incomplete: 1 stored file" in err
    now = summary(records)["rows"]    # the admin's two refusals audited, and each login
    with records.session() as s:      # of a named user (admin three times, tech once)
        logins = s.scalar(select(func.count()).select_from(AuditEvent).where(
            AuditEvent.action == "command-line login"))
    assert logins == 4
    assert now.pop("audit_events") == live["audit_events"] + 2 + logins
    assert now == {k: v for k, v in live.items() if k != "audit_events"}
    assert not list(records.data.glob("records.sqlite3.replaced-*"))
    records.engine.dispose()

    out = cli(["db", "restore", archive, "--replace", "--user", "admin", "--sha256",
               digest.upper(), *data], capsys, 0).out
    assert out.startswith("restored: ")
    after = open_store(None, records.data)
    try:
        with zipfile.ZipFile(archive) as zf:
            doc = json.loads(zf.read("records.json"))
        rows = summary(after)["rows"]
        assert rows["customers"] == len(doc["tables"]["customers"]["rows"]) == \
            live["customers"] - 1
        with after.session() as s:
            event = s.scalar(select(AuditEvent).order_by(
                AuditEvent.id.desc()).limit(1))
        assert (event.action, event.username) == ("restore", "admin")
        assert json.loads(event.after_json)["sha256"] == digest
    finally:
        after.close()
    assert len(list(records.data.glob("records.sqlite3.replaced-*"))) == 1


def test_a_restore_keeps_the_newest_replaced_files(records, tmp_path, monkeypatch):
    """After a successful restore over SQLite the replaced files beyond the newest
    ``GONIO_KEEP_REPLACED`` (default 3) are removed, newest by their names' stamps (not the
    files' times); other files are left. A bad value refuses the restore before any work,
    the live records and every replaced file as they were."""
    from gonio.limits import KEEP_REPLACED
    from gonio.records.backup import archive_sha256, summary

    admin = services.user(records, "admin")
    archive = tmp_path / "nightly.zip"
    backup(records, archive)
    folder = records.data
    names = ["records.sqlite3.replaced-20240101T000000", "records.sqlite3.replaced-20240101T"
             "000000-2", "records.sqlite3.replaced-20230505T101010",
             "records.sqlite3.replaced-20250101T000000"]
    for i, n in enumerate(names):                # file times the reverse of the stamps
        (folder / n).write_bytes(b"old")
        os.utime(folder / n, (2e9 - i * 1e6, 2e9 - i * 1e6))
    others = ["records.sqlite3.replaced-notes.txt", "other.sqlite3.replaced-20200101T000000"]
    for n in others:
        (folder / n).write_bytes(b"keep")
    live = summary(records)["rows"]
    for bad in ("0", "x", "-1"):
        monkeypatch.setenv("GONIO_KEEP_REPLACED", bad)
        with pytest.raises(GonioError, match="GONIO_KEEP_REPLACED must be a whole number"):
            restore(records, archive, replace=True, actor=admin,
                    expect_sha256=archive_sha256(archive))
    now = summary(records)["rows"]
    assert now.pop("audit_events") == live.pop("audit_events") + 3 and now == live
    assert all((folder / n).exists() for n in names + others)

    monkeypatch.setenv("GONIO_KEEP_REPLACED", "2")
    restore(records, archive, replace=True, actor=admin, expect_sha256=archive_sha256(archive))
    left = sorted(p.name for p in folder.glob("records.sqlite3.replaced-2*"))
    assert len(left) == 2 and "records.sqlite3.replaced-20250101T000000" in left
    assert left[-1] > "records.sqlite3.replaced-2025"        # the one this restore kept
    assert all((folder / n).exists() for n in others)

    monkeypatch.delenv("GONIO_KEEP_REPLACED")
    assert KEEP_REPLACED == 3
    for _ in range(3):
        restore(records, archive, replace=True, actor=admin,
                expect_sha256=archive_sha256(archive))
    left = sorted(p.name for p in folder.glob("records.sqlite3.replaced-2*"))
    assert len(left) == 3 and "records.sqlite3.replaced-20250101T000000" not in left


def test_backup_refuses_rows_restore_would_refuse(records, tmp_path, capsys):
    """A row SQLite kept with a value its column's type does not take (U = 'abc'): the backup
    is refused with one line naming the row, and no archive or temporary file is left
    (before: exit 0, an archive that restore then refused). SQLite only: PostgreSQL never
    stores such a row. The records' verification names it first (the row is not its stored
    results.json's); the archive's own check would name "result_items row 2: U is not a
    number"."""
    with records.writing() as s:
        rid, was = s.execute(text("SELECT id, U FROM result_items ORDER BY id LIMIT 1 "
                                  "OFFSET 1")).one()
        s.execute(text("UPDATE result_items SET U = 'abc' WHERE id = :i"), {"i": rid})
        s.commit()
    archive = tmp_path / "b.zip"
    out = cli(["db", "backup", archive, "--data", records.data], capsys, 2)
    assert "the records do not verify" in out.err and "differs from the stored results.json" \
        in out.err and "nothing written" in out.err and "\n" not in out.err.strip()
    assert not archive.exists() and not list(tmp_path.glob(".backup-*"))
    with records.writing() as s:            # the row mended, the backup restores
        s.execute(text("UPDATE result_items SET U = :u WHERE id = :i"), {"u": was, "i": rid})
        s.commit()
    cli(["db", "backup", archive, "--data", records.data], capsys, 0)
    cli(["db", "restore", archive, "--data", tmp_path / "other"], capsys, 0)


def test_a_restore_takes_the_archive_s_time_zone(sqlite_store, tmp_path, monkeypatch):
    """A fresh store holds its machine's zone (migration 0013): a restore into it takes the
    archive's zone instead of colliding with that row; an archive without a zone, or with an
    empty one (written before stores held one), keeps the target's zone, and a replacing
    restore gives it the machine's zone, as the migration gives an older store."""
    from gonio.records.models import records_zone

    monkeypatch.setenv("TZ", "America/Los_Angeles")       # the machine's zone, not the lab's
    people = make_people(sqlite_store)
    services.set_settings(sqlite_store, people["admin"], timezone="Asia/Shanghai")
    archive = tmp_path / "b.zip"
    backup(sqlite_store, archive)
    target = open_store(None, tmp_path / "t1")
    assert records_zone(target) == "America/Los_Angeles"
    restore(target, archive)
    assert records_zone(target) == "Asia/Shanghai"
    target.close()

    def zone_rows(doc, value):
        rows = doc["tables"]["settings"]["rows"]
        key = doc["tables"]["settings"]["columns"].index("key")
        kept = [r for r in rows if r[key] != "timezone"]
        if value is not None:
            kept.append([value if c == "value" else "timezone"
                         for c in doc["tables"]["settings"]["columns"]])
        doc["tables"]["settings"]["rows"] = kept
        return doc

    for i, value in enumerate((None, "")):
        old = archive_without(archive, tmp_path / f"old{i}.zip",
                              records_json=lambda d, v=value: zone_rows(d, v))
        monkeypatch.setenv("TZ", "Europe/Berlin")         # the target's zone by its migration
        target = open_store(None, tmp_path / f"o{i}")
        monkeypatch.setenv("TZ", "America/Los_Angeles")
        assert records_zone(target) == "Europe/Berlin"
        restore(target, old)
        assert records_zone(target) == "Europe/Berlin"
        with target.session() as s:
            assert s.scalar(text("SELECT count(*) FROM settings WHERE key = 'timezone'")) == 1
        restore(target, old, replace=True, actor=services.user(target, "admin"))
        assert records_zone(target) == "America/Los_Angeles"
        target.close()


def test_a_restore_refuses_an_archive_with_an_unknown_time_zone(sqlite_store, tmp_path,
                                                                 capsys, monkeypatch):
    """An archive whose setting ``timezone`` is no IANA zone is refused at restore (and at
    verify) in one line naming records.json's setting, exit 2, nothing restored: the store
    keeps its own zone and every dated command still works."""
    from gonio.records.models import records_zone

    monkeypatch.setenv("TZ", "Europe/Berlin")
    people = make_people(sqlite_store)
    services.set_settings(sqlite_store, people["admin"], timezone="Asia/Shanghai")
    archive = tmp_path / "a.zip"
    backup(sqlite_store, archive)

    def mars(doc):
        t = doc["tables"]["settings"]
        key, val = t["columns"].index("key"), t["columns"].index("value")
        for r in t["rows"]:
            if r[key] == "timezone":
                r[val] = "Mars/Olympus"
        return doc

    bad = archive_without(archive, tmp_path / "b.zip", records_json=mars)
    cli(["db", "init", "--data", tmp_path / "target"], capsys, 0)
    out = cli(["db", "restore", bad, "--data", tmp_path / "target"], capsys, 2)
    err = out.err.strip()
    assert "\n" not in err and "Traceback" not in err, err
    assert "settings" in err and "timezone" in err and "'Mars/Olympus'" in err, err
    assert "nothing restored" in err, err
    from gonio.records.backup import check_archive
    with pytest.raises(GonioError, match="Mars/Olympus"):     # the web page's check too
        check_archive(bad)
    target = open_store(None, tmp_path / "target")
    try:
        assert records_zone(target) == "Europe/Berlin"         # db init's, not the archive's
        assert_empty(target)
    finally:
        target.close()
    cli(["db", "restore", archive, "--data", tmp_path / "target"], capsys, 0)
    target = open_store(None, tmp_path / "target")
    try:
        assert records_zone(target) == "Asia/Shanghai"
    finally:
        target.close()


def _trail(st) -> list[dict]:
    """The audit trail's rows in id order, every value as records.json writes it."""
    with st.session() as s:
        return [{k: v.isoformat() if hasattr(v, "isoformat") else v
                 for k, v in r.items()}
                for r in s.execute(select(AuditEvent.__table__)
                                   .order_by(AuditEvent.id)).mappings()]


def test_a_restore_into_an_initialised_store_keeps_both_trails(store, tmp_path, capsys,
                                                               request):
    """``gonio db init`` with every option writes settings and their audit events; a
    ``gonio db restore`` into that store collided with them (audit_events.id, settings'
    key). Now the archive's trail comes back row for row under its own ids (compared with
    the archive's records.json, read here independently), the store's own events follow it
    unchanged but for their ids, the restore's event is the newest and names both, the
    archive's settings replace the store's (the zone too), the store's laboratory details
    the archive lacks are removed with it (named in the event), the trail still refuses DELETE and UPDATE, and the next event follows the
    restore's. On SQLite and PostgreSQL, from the command line."""
    from sqlalchemy.exc import DBAPIError

    from gonio.records.models import records_zone

    people = make_people(store)
    services.set_settings(store, people["admin"], timezone="Asia/Shanghai", lab_name="Lab A",
                          lab_address="1 A Street")
    archive = tmp_path / "a.zip"
    backup(store, archive)
    with zipfile.ZipFile(archive) as zf:
        doc = json.loads(zf.read("records.json"))["tables"]
    theirs = [dict(zip(doc["audit_events"]["columns"], r)) for r in doc["audit_events"]["rows"]]
    assert len(theirs) >= 6

    url = None
    if store.engine.dialect.name == "postgresql":
        from .conftest import new_pg_database
        url = new_pg_database(request.getfixturevalue("pg_server"))
    where = (["--database", url] if url else []) + ["--data", tmp_path / "t"]
    init = {"--timezone": "Europe/Berlin", "--lab-name": "Lab B", "--lab-address": "2 B Road",
            "--lab-accreditation": "CNAS L0000", "--lab-contact": "b@example.org"}
    cli(["db", "init", *where, *[x for kv in init.items() for x in kv]], capsys, 0)
    target = open_store(url, tmp_path / "t")
    try:
        own = _trail(target)
        assert len(own) == 5 and {e["entity_id"] for e in own} == {
            "timezone", "lab_name", "lab_address", "lab_accreditation", "lab_contact"}
        target.engine.dispose()
        cli(["db", "restore", *where, archive], capsys, 0)
        trail = _trail(target)
        assert trail[:len(theirs)] == theirs                   # the archive's, row for row
        after = trail[len(theirs):-1]
        first = max(e["id"] for e in theirs) + 1
        assert [e["id"] for e in after] == list(range(first, first + len(own)))
        assert [dict(e, id=None) for e in after] == [dict(e, id=None) for e in own]
        last = trail[-1]
        assert last["action"] == "restore" and last["id"] == first + len(own)
        said = json.loads(last["after_json"])
        assert said["store_events"] == {"were": [e["id"] for e in own],
                                        "now": [e["id"] for e in after]}
        assert said["settings_replaced"] == {"timezone": ["Europe/Berlin", "Asia/Shanghai"],
                                             "lab_name": ["Lab B", "Lab A"],
                                             "lab_address": ["2 B Road", "1 A Street"]}
        # the laboratory's identity travels as one group: Lab B's accreditation and contact
        # are not left beside Lab A's name, and the restore's event names them
        assert said["settings_removed"] == {"lab_accreditation": "CNAS L0000",
                                            "lab_contact": "b@example.org"}
        assert records_zone(target) == "Asia/Shanghai"
        got = services.settings(target)
        assert (got["lab_name"], got["lab_address"]) == ("Lab A", "1 A Street")
        assert not got.get("lab_accreditation") and not got.get("lab_contact")
        with target.session() as s:
            keys = set(s.scalars(text("SELECT key FROM settings")))
        assert {k for k in keys if k.startswith("lab_")} == {"lab_name", "lab_address"}
        for sql in ("DELETE FROM audit_events WHERE id = 1",
                    "UPDATE audit_events SET action = 'x' WHERE id = 1"):
            with pytest.raises(DBAPIError, match="append-only"):
                with target.engine.begin() as c:
                    c.execute(text(sql))
        services.set_settings(target, services.user(target, "admin"), lab_name="Lab C")
        assert _trail(target)[-1]["id"] == last["id"] + 1
        target.engine.dispose()
        cli(["db", "verify", *where], capsys, 0)
    finally:
        target.close()


def test_a_restore_refuses_a_user_added_after_its_first_check(sqlite_store, tmp_path,
                                                                 capsys, monkeypatch):
    """A user added to the target between the restore's first "no user" check and the
    transaction that sets its own events aside (here: while the archive's rows are filled,
    the step between them) is seen by the check repeated in that transaction: refused,
    exit 2, the store's trail and user as they were."""
    from gonio.records import backup as backup_mod

    make_people(sqlite_store)
    archive = tmp_path / "a.zip"
    backup(sqlite_store, archive)
    cli(["db", "init", "--data", tmp_path / "t", "--lab-name", "Lab B"], capsys, 0)
    target = open_store(None, tmp_path / "t")
    try:
        before = _trail(target)
        fill = backup_mod._fill_stated

        def fill_and_add_user(store, rows):
            fill(store, rows)
            other = open_store(None, tmp_path / "t")
            try:
                services.create_user(other, None, "late", PASSWORD, "admin")
                with other.engine.begin() as c:                # an id no archive user has,
                    c.execute(text("UPDATE users SET id = 1000"))   # so only the check sees it
            finally:
                other.close()

        monkeypatch.setattr(backup_mod, "_fill_stated", fill_and_add_user)
        target.engine.dispose()
        out = cli(["db", "restore", "--data", tmp_path / "t", archive], capsys, 2)
        assert "user was added" in out.err and "nothing restored" in out.err
        trail = _trail(target)
        assert trail[:len(before)] == before
        assert len(trail) == len(before) + 1                   # the late user's own event
        with target.session() as s:
            assert list(s.scalars(text("SELECT username FROM users"))) == ["late"]
    finally:
        target.close()


def test_a_refused_restore_leaves_an_initialised_store_s_trail(sqlite_store, tmp_path,
                                                                capsys):
    """A restore the database refuses part-way (two users with one id) after the store's own
    events were set aside leaves them where they were, and the trail still append-only."""
    from sqlalchemy.exc import DBAPIError

    make_people(sqlite_store)
    archive = tmp_path / "a.zip"
    backup(sqlite_store, archive)

    def twice(doc):
        users = doc["tables"]["users"]["rows"]
        users.append(list(users[0]))
        return doc

    bad = archive_without(archive, tmp_path / "bad.zip", records_json=twice)
    cli(["db", "init", "--data", tmp_path / "t", "--lab-name", "Lab B"], capsys, 0)
    target = open_store(None, tmp_path / "t")
    try:
        before = _trail(target)
        target.engine.dispose()
        out = cli(["db", "restore", "--data", tmp_path / "t", bad], capsys, 2)
        assert "nothing restored" in out.err
        assert _trail(target) == before and len(before) == 1
        with pytest.raises(DBAPIError, match="append-only"):
            with target.engine.begin() as c:
                c.execute(text("DELETE FROM audit_events"))
    finally:
        target.close()
