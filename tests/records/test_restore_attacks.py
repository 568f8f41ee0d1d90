"""The restore attacked (gonio.records.backup.restore and the /backup page): hostile archive
members (paths, links, duplicates, encryption), archives that expand past the limit (zip
bombs) or past the free disk, an upload over the limit, an archive swapped between its
check and its restore, a restore failing half-way (a disk full while the new SQLite file is
written, a rename refused, a PostgreSQL table held by another connection), two restores at
once, and the staging folder of uploads kept small. Each archive here is a backup of a small
store (users and a customer, a stored file or two): quick to build, read by the real
backup and restore."""

from __future__ import annotations

import io
import json
import os
import re
import stat
import time
import zipfile
from pathlib import Path

import pytest

from gonio.errors import GonioError
from gonio.records import backup as backup_mod
from gonio.records import services
from gonio.records.backup import archive_sha256, backup, check_archive, restore, summary
from gonio.records.db import open_store

from .conftest import PASSWORD
from .test_records_restore import refusals
from .test_web_backup import _confirm

ZEROS_BYTES = 3 * 2**20          # a stored file of zeros: deflates to a few KiB


def small_records(store, customer: str = "First Ltd", blob: bytes = b"") -> dict:
    """An admin "boss", a technician "tech", one customer and (``blob``) one stored file."""
    people = {"boss": services.create_user(store, None, "boss", PASSWORD, "admin"),
              "tech": services.create_user(store, None, "tech", PASSWORD, "technician")}
    services.add_customer(store, people["tech"], customer)
    if blob:
        services.store_file(store, io.BytesIO(blob))
    return people


def archive_of(tmp_path, name: str, **records) -> Path:
    """A backup of a new store holding :func:`small_records` (``records``: its arguments):
    ``tmp_path/<name>.zip``."""
    st = open_store(None, tmp_path / name)
    try:
        small_records(st, **records)
        backup(st, tmp_path / f"{name}.zip")
    finally:
        st.close()
    return tmp_path / f"{name}.zip"


@pytest.fixture
def small(tmp_path):
    """(store with :func:`small_records`, its backup archive)."""
    st = open_store(None, tmp_path / "live")
    small_records(st)
    backup(st, tmp_path / "small.zip")
    yield st, tmp_path / "small.zip"
    st.close()


def rewritten(src, dst, extra=(), skip=()):
    """``src``'s members copied into ``dst`` (less ``skip``) with ``extra`` (ZipInfo or name,
    bytes) appended."""
    with zipfile.ZipFile(src) as a, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as b:
        for info in a.infolist():
            if info.filename not in skip:
                b.writestr(info, a.read(info))
        for name, data in extra:
            b.writestr(name, data)
    return dst


def _patched(path, flags: int | None = None, method: int | None = None) -> None:
    """The first member's general-purpose flags or compression method set in its local
    header and in the central directory (what zipfile's writer would not write)."""
    raw = bytearray(path.read_bytes())
    for sig, at_flags in ((b"PK\x03\x04", 6), (b"PK\x01\x02", 8)):
        at = raw.index(sig) + at_flags
        if flags is not None:
            raw[at:at + 2] = flags.to_bytes(2, "little")
        if method is not None:
            raw[at + 2:at + 4] = method.to_bytes(2, "little")
    path.write_bytes(bytes(raw))


@pytest.mark.parametrize("member, said", [
    ("../x", "is neither records.json nor blobs/<sha256>"),
    ("/etc/cron.d/x", "is neither records.json nor blobs/<sha256>"),
    ("blobs/../../x", "is neither records.json nor blobs/<sha256>"),
    ("blobs/", "is neither records.json nor blobs/<sha256>"),
    ("records.json", "is in it twice"),
])
def test_a_member_outside_the_layout_or_twice_is_refused(small, tmp_path, member, said):
    """A member named outside the layout was ignored (a path trick never written, but the
    archive not what it claimed); records.json twice was read as the last one, which
    another tool would not."""
    _, archive = small
    bad = rewritten(archive, tmp_path / "bad.zip", extra=[(member, b"{}")])
    with pytest.raises(GonioError, match=f"member {member[:80]!r} {said}: not a gonio "
                                         "backup; nothing restored"):
        check_archive(bad)


def test_a_link_an_encrypted_member_or_an_unknown_method_is_refused(small, tmp_path):
    """A symbolic-link member, an encrypted member (zipfile raised RuntimeError: an internal
    error), a compression method zipfile cannot read (NotImplementedError)."""
    _, archive = small
    with zipfile.ZipFile(archive) as zf:
        doc = zf.read("records.json")
    link = zipfile.ZipInfo("records.json")
    link.external_attr = (stat.S_IFLNK | 0o777) << 16
    for patch, said in (({}, "is a symbolic link"), ({"flags": 0x1}, "is encrypted"),
                        ({"method": 97}, "is compressed by method 97, which gonio does not "
                                         "read")):
        bad = tmp_path / "bad.zip"
        with zipfile.ZipFile(bad, "w") as zf:
            zf.writestr(link if not patch else "records.json", doc)
        _patched(bad, **patch)
        with pytest.raises(GonioError, match=f"'records.json' {said}"):
            check_archive(bad)


def test_a_damaged_member_is_a_clear_refusal(small, tmp_path):
    """A member whose bytes fail their CRC: a GonioError (zipfile's BadZipFile escaped)."""
    _, archive = small
    raw = bytearray(archive.read_bytes())
    with zipfile.ZipFile(archive) as zf:
        info = zf.getinfo("records.json")
    start = info.header_offset + 30 + len(info.filename) + len(info.extra)
    raw[start + info.compress_size // 2] ^= 0xFF
    bad = tmp_path / "damaged.zip"
    bad.write_bytes(bytes(raw))
    with pytest.raises(GonioError, match="no readable records.json"):
        check_archive(bad)


def test_an_archive_expanding_past_the_limit_is_refused_unread(tmp_path, monkeypatch):
    """A zip bomb: a stored file of zeros deflates to a few KiB; with the limit below its
    expanded size the archive is refused from its declared sizes, no member opened."""
    archive_of(tmp_path, "bomb", blob=bytes(ZEROS_BYTES))
    assert (tmp_path / "bomb.zip").stat().st_size < ZEROS_BYTES / 100
    assert check_archive(tmp_path / "bomb.zip")["files"] == 1     # within the default
    opened = []
    real_open = zipfile.ZipFile.open
    monkeypatch.setattr(zipfile.ZipFile, "open",
                        lambda self, *a, **k: opened.append(a) or real_open(self, *a, **k))
    monkeypatch.setenv("GONIO_MAX_BACKUP_BYTES", str(2**20))
    with pytest.raises(GonioError, match=r"the archive expands to 3(\.\d+)? MiB "
                                         r"\(3,1\d\d,\d+ bytes\), more than the limit of "
                                         r"1 MiB .*GONIO_MAX_BACKUP_BYTES"):
        check_archive(tmp_path / "bomb.zip")
    monkeypatch.setenv("GONIO_MAX_BACKUP_BYTES", str(2**30))
    monkeypatch.setenv("GONIO_MAX_RECORDS_JSON_BYTES", "100")
    with pytest.raises(GonioError, match="records.json expands to .* more than the limit of "
                                         "100 bytes"):
        check_archive(tmp_path / "bomb.zip")
    assert opened == []


def test_a_restore_the_disk_cannot_hold_writes_nothing(tmp_path, monkeypatch):
    """The stored files the store lacks would not fit on the data folder's disk: refused
    before a byte is written (before, the blobs filled the disk first)."""
    archive_of(tmp_path, "a", blob=bytes(ZEROS_BYTES))
    target = open_store(None, tmp_path / "target")
    try:
        free = ZEROS_BYTES + backup_mod.SPARE_BYTES - 1
        monkeypatch.setattr(backup_mod.shutil, "disk_usage",
                            lambda p: type("U", (), {"free": free})())
        with pytest.raises(GonioError, match=r"the restore needs 3(\.\d+)? MiB .* on the data "
                                             r"folder's disk and .* is free: nothing "
                                             "restored"):
            restore(target, tmp_path / "a.zip")
        assert not [p for p in target.blob_root.rglob("*") if p.is_file()]
        assert summary(target)["rows"]["users"] == 0
    finally:
        target.close()


def test_the_bytes_restored_are_the_bytes_confirmed(tmp_path, monkeypatch):
    """The archive file replaced right after its SHA-256 was taken: the restore reads the
    file it hashed (one open file), not what the path names by then."""
    archives = {who: archive_of(tmp_path, who, customer=f"{who} Ltd")
                for who in ("alice", "mallory")}
    confirmed = archive_sha256(archives["alice"])
    real = backup_mod.archive_sha256

    def then_swap(source):
        digest = real(source)
        os.replace(archives["mallory"], archives["alice"])      # a new file at the path
        return digest
    monkeypatch.setattr(backup_mod, "archive_sha256", then_swap)
    target = open_store(None, tmp_path / "target")
    try:
        restore(target, archives["alice"], expect_sha256=confirmed)
        from gonio.records import queries
        names = [c.name for c in queries.customers(target)]
        assert names == ["alice Ltd"], names
    finally:
        target.close()


def test_a_sqlite_restore_failing_half_way_leaves_the_live_records(small, tmp_path,
                                                                   monkeypatch):
    """A disk full while the new file is migrated (an internal error before), a rename
    refused (an OSError before, and the replaced-* name of the live file left behind): one
    clear line, the live records and their files as they were, nothing left over; two
    restores within one second each keep the file they replaced."""
    import sqlite3

    from gonio.records import db as db_mod

    st, archive = small
    boss = services.user(st, "boss")
    services.add_customer(st, services.user(st, "tech"), "After the backup Ltd")
    before = summary(st)["rows"]

    def full(*a, **k):
        raise sqlite3.OperationalError("database or disk is full")
    with monkeypatch.context() as m:
        m.setattr(db_mod, "migrate", full)
        with pytest.raises(GonioError, match=r"could not be written \(database or disk is "
                                             r"full\): the live records are unchanged"):
            restore(st, archive, replace=True, actor=boss)

    def refused(*a, **k):
        raise OSError(13, "Permission denied")
    with monkeypatch.context() as m:
        m.setattr(backup_mod.os, "replace", refused)
        with pytest.raises(GonioError, match=r"could not be swapped in \(Permission denied\): "
                                             "the live records are unchanged"):
            restore(st, archive, replace=True, actor=boss)
    after = summary(st)["rows"]
    assert after == dict(before, audit_events=before["audit_events"] + 2)
    assert [r.split(" (")[0] for r in refusals(st)] == [
        "the restored records could not be written", "the restored records could not be "
        "swapped in"]
    left = [p.name for p in st.data.iterdir() if "restoring" in p.name or "replaced" in p.name]
    assert left == [], left
    # two restores in the same second: the second keeps its replaced file under another name
    monkeypatch.setattr(backup_mod, "_dt", _FrozenClock)
    for _ in range(2):
        restore(st, archive, replace=True, actor=services.user(st, "boss"))
    kept = sorted(p.name for p in st.data.glob("records.sqlite3.replaced-*"))
    assert kept == ["records.sqlite3.replaced-20261129T120000",
                    "records.sqlite3.replaced-20261129T120000-2"], kept
    assert summary(st)["rows"]["customers"] == 1


class _FrozenClock:
    """``datetime`` as the backup module uses it, its clock stopped at 12:00:00 UTC."""
    import datetime as _real

    date, timezone = _real.date, _real.timezone

    class datetime(_real.datetime):
        @classmethod
        def now(cls, tz=None):
            import datetime as d
            return d.datetime(2026, 11, 29, 12, 0, 0, tzinfo=tz)


def test_a_postgresql_table_held_by_another_connection(pg_server, tmp_path, monkeypatch):
    """Another connection holds a table past the lock timeout: the TRUNCATE fails (an
    internal error before), one clear line, the live records unchanged."""
    import psycopg

    from .conftest import new_pg_database

    url = new_pg_database(pg_server)
    st = open_store(url, tmp_path / "live")
    try:
        small_records(st)
        backup(st, tmp_path / "pg.zip")
        services.add_customer(st, services.user(st, "tech"), "After the backup Ltd")
        monkeypatch.setattr(backup_mod, "LOCK_TIMEOUT_S", 1, raising=False)
        with psycopg.connect(url) as other:
            other.execute("LOCK TABLE customers IN ACCESS SHARE MODE")
            with pytest.raises(GonioError, match=r"the live records could not be emptied for "
                                                 r"the restore \(.*lock timeout.*\): they are "
                                                 "unchanged; nothing restored"):
                restore(st, tmp_path / "pg.zip", replace=True, actor=services.user(st, "boss"))
        assert summary(st)["rows"]["customers"] == 2
        assert "could not be emptied for the restore" in refusals(st)[0]
    finally:
        st.close()


def test_pauses_of_the_dispatcher_nest(sqlite_store):
    """Two restores at once: the one turned away resumes the dispatcher; before, that
    resume let the workers claim (and ``recover`` write) while the other was replacing the
    records."""
    from gonio.records.worker import Dispatcher

    d = Dispatcher(sqlite_store)
    calls = []
    real = services.recover
    try:
        services.recover = lambda store: calls.append(store) or real(store)
        assert d.pause() == 0 and d.pause() == 0
        d.resume()
        assert d._paused and calls == []
        d.resume()
        assert not d._paused and len(calls) == 1
    finally:
        services.recover = real


# --------------------------------------------------------------------------- the page

def _page_app(store):
    from gonio.web.app import create_app

    return create_app(store)


def test_an_upload_over_the_limit_is_refused_in_one_line(small, monkeypatch):
    """Declared by its Content-Length or sent without one (chunked): HTTP 413, the backup
    page saying the limit once, nothing staged (before, any size was spooled and kept)."""
    from .test_web_security import csrf_of, login

    st, archive = small
    monkeypatch.setenv("GONIO_MAX_BACKUP_BYTES", str(256 * 2**10))
    web = login(_page_app(st), "boss")
    said = ("is larger than the limit of 256 KiB (262,144 bytes) for a backup archive "
            "(GONIO_MAX_BACKUP_BYTES): nothing was stored")
    # within the form's slack: counted as it is staged; far over: refused from its header
    for kib, before in ((300, "the upload "), (400, "the upload, 400.")):
        big = os.urandom(kib * 2**10)
        r = web.post("/backup/check", data={"csrf": csrf_of(web)},
                     files={"archive": ("huge.zip", big, "application/zip")})
        assert r.status_code == 413 and r.text.count(said) == 1, r.text[-600:]
        assert before in r.text
    boundary = "gonio-test-boundary"
    csrf = csrf_of(web)

    def chunks():
        yield (f"--{boundary}\r\nContent-Disposition: form-data; name=\"csrf\"\r\n\r\n{csrf}"
               f"\r\n--{boundary}\r\nContent-Disposition: form-data; name=\"archive\"; "
               f"filename=\"huge.zip\"\r\nContent-Type: application/zip\r\n\r\n").encode()
        for i in range(0, len(big) * 2, 2**16):
            yield (big + big)[i:i + 2**16]
        yield f"\r\n--{boundary}--\r\n".encode()
    r = web.post("/backup/check", content=chunks(),
                 headers={"content-type": f"multipart/form-data; boundary={boundary}"})
    assert r.status_code == 413 and r.text.count(said) == 1, r.text[-600:]
    staged = st.data / "restore"
    assert not staged.exists() or not list(staged.iterdir())
    # a technician is refused before the body is read
    tech = login(_page_app(st), "tech")
    r = tech.post("/backup/check", data={"csrf": csrf_of(tech)},
                  files={"archive": ("huge.zip", big, "application/zip")})
    assert r.status_code == 403
    # an admin's upload without the form's CSRF token: refused, nothing staged
    r = web.post("/backup/check", files={"archive": ("a.zip", archive.read_bytes(),
                                                     "application/zip")})
    assert r.status_code == 403 and (not staged.exists() or not list(staged.iterdir()))


def test_the_staging_folder_keeps_few_uploads(small, tmp_path):
    """Five archives verified and never restored: only the newest few are kept (before,
    every upload of the day stayed); an upload cut off part-way an hour ago is removed."""
    from gonio.web.pages import STAGED_KEEP

    from .test_web_security import csrf_of, login

    st, archive = small
    web = login(_page_app(st), "boss")
    staged = st.data / "restore"
    staged.mkdir(mode=0o700)
    cut = staged / ".upload-cut"
    cut.write_bytes(b"x" * 100)
    os.utime(cut, (time.time() - 7200,) * 2)
    for i in range(5):
        one = tmp_path / f"n{i}.zip"
        with zipfile.ZipFile(archive) as a, zipfile.ZipFile(one, "w") as b:
            for info in a.infolist():
                b.writestr(info, a.read(info))
            b.comment = f"copy {i}".encode()                    # another SHA-256
        r = web.post("/backup/check", data={"csrf": csrf_of(web)},
                     files={"archive": (one.name, one.read_bytes(), "application/zip")})
        assert r.status_code == 200 and "complete and intact" in r.text, r.text[-500:]
    assert len(list(staged.glob("*.zip"))) == STAGED_KEEP == 3 and not cut.exists()
    assert not list(staged.glob(".upload-*"))


def test_the_page_shows_an_error_once_and_no_server_path(small, tmp_path, monkeypatch):
    """The shared layout and the backup page both printed ``error`` (every refusal shown
    twice); a failed restore named the server's file; the audit names the upload's name."""
    from .test_web_security import csrf_of, login

    st, archive = small
    web = login(_page_app(st), "boss")
    r = web.post("/backup/check", data={"csrf": csrf_of(web)})
    assert r.status_code == 400 and r.text.count("choose a backup archive (.zip)") == 1
    page = web.post("/backup/check", data={"csrf": csrf_of(web)}, files={
        "archive": ("last-night.zip", archive.read_bytes(), "application/zip")}).text
    send = dict(_confirm(page), csrf=csrf_of(web), confirm="RESTORE", password=PASSWORD)

    def refused(*a, **k):
        raise OSError(28, "No space left on device")
    with monkeypatch.context() as m:
        m.setattr(backup_mod.os, "replace", refused)
        r = web.post("/backup/restore", data=send)
    assert r.status_code == 409 and r.text.count("No space left on device") == 1
    said = re.search(r'<p class="error" role="alert" id="restore-error">([^<]*)</p>', r.text)
    assert said and str(st.data) not in said.group(1) and said.group(1).startswith(
        "the restored records could not be swapped in (No space left on device): the live "
        "records are unchanged; nothing restored"), r.text[-1500:]
    assert web.get("/backup").status_code == 200                # open again
    assert refusals(st) == ["the restored records could not be swapped in (No space left on "
                            "device): the live records are unchanged; nothing restored"]
    r = web.post("/backup/restore", data=send)
    assert r.status_code == 200 and "Restored from last-night.zip" in r.text
    assert restored_event(st)["archive"] == "last-night.zip"


def test_a_folder_archive_by_a_path_trick_or_a_link_is_never_read(small, tmp_path,
                                                                  monkeypatch):
    """``choose`` names: ``../x.zip``, an absolute path, a link in the folder to an archive
    outside it: none listed, each refused as not listed; a staged upload replaced by a link
    after its check: refused when it is opened (not followed)."""
    from .test_web_security import csrf_of, login

    st, archive = small
    folder = tmp_path / "backups"
    folder.mkdir()
    monkeypatch.setenv("GONIO_BACKUP_FOLDER", str(folder))
    (folder / "link.zip").symlink_to(archive)
    web = login(_page_app(st), "boss")
    assert "link.zip" not in web.get("/backup").text
    for name in ("../small.zip", str(archive), "link.zip"):
        r = web.post("/backup/check", data={"csrf": csrf_of(web), "choose": name})
        assert r.status_code == 400 and "choose an archive the backup folder lists" in r.text
    page = web.post("/backup/check", data={"csrf": csrf_of(web)}, files={
        "archive": ("small.zip", archive.read_bytes(), "application/zip")}).text
    fields = _confirm(page)
    staged = st.data / "restore" / f"{fields['sha256']}.zip"
    staged.unlink()
    staged.symlink_to(archive)
    r = web.post("/backup/restore", data=dict(fields, csrf=csrf_of(web), confirm="RESTORE",
                                              password=PASSWORD))
    assert r.status_code == 400 and "cannot open the archive" in r.text, r.text[-800:]
    # the audit names a folder archive by the name the server chose, not the form's
    (folder / "2026-11-28.zip").write_bytes(archive.read_bytes())
    page = web.post("/backup/check", data={"csrf": csrf_of(web), "choose": "2026-11-28.zip"})
    fields = dict(_confirm(page.text), name="forged.zip")
    r = web.post("/backup/restore", data=dict(fields, csrf=csrf_of(web), confirm="RESTORE",
                                              password=PASSWORD))
    assert r.status_code == 200 and "Restored from 2026-11-28.zip" in r.text
    assert restored_event(st)["archive"] == "2026-11-28.zip"


def restored_event(store) -> dict:
    """What the newest ``restore`` audit event says."""
    from sqlalchemy import select

    from gonio.records.models import AuditEvent

    with store.session() as s:
        event = s.scalar(select(AuditEvent).where(AuditEvent.action == "restore")
                         .order_by(AuditEvent.id.desc()).limit(1))
    return json.loads(event.after_json)


def test_two_admins_restoring_at_once(small, tmp_path, monkeypatch):
    """A second admin's restore sent while the first runs is answered 503 (Retry-After) and
    restores nothing; the first's restore is the only one in the audit; the same form sent
    again afterwards meets the login page (every session ended)."""
    import threading

    from .test_web_security import csrf_of, login

    st, archive = small
    services.create_user(st, None, "boss2", PASSWORD, "admin")
    folder = tmp_path / "backups"
    folder.mkdir()
    (folder / "a.zip").write_bytes(archive.read_bytes())
    monkeypatch.setenv("GONIO_BACKUP_FOLDER", str(folder))
    app = _page_app(st)
    sends = []
    for who in ("boss", "boss2"):
        web = login(app, who)
        page = web.post("/backup/check", data={"csrf": csrf_of(web), "choose": "a.zip"}).text
        sends.append((web, dict(_confirm(page), csrf=csrf_of(web), confirm="RESTORE",
                                password=PASSWORD)))
    started, go_on = threading.Event(), threading.Event()
    real = backup_mod._check_space

    def held(*a, **k):                       # the first restore, the server closed
        started.set()
        go_on.wait(30)
        return real(*a, **k)
    monkeypatch.setattr(backup_mod, "_check_space", held)
    answers = {}
    first = threading.Thread(target=lambda: answers.setdefault(
        "boss", sends[0][0].post("/backup/restore", data=sends[0][1])))
    first.start()
    assert started.wait(30)
    second = sends[1][0].post("/backup/restore", data=sends[1][1])
    assert second.status_code == 503 and second.headers["retry-after"] == "30"
    assert "restored from a backup (by boss" in second.text
    go_on.set()
    first.join(30)
    assert answers["boss"].status_code == 200
    again = sends[0][0].post("/backup/restore", data=sends[0][1], follow_redirects=False)
    assert again.status_code == 303 and again.headers["location"] == "/login"
    from sqlalchemy import func, select

    from gonio.records.models import AuditEvent
    with st.session() as s:
        assert s.scalar(select(func.count()).where(AuditEvent.action == "restore")) == 1


@pytest.mark.parametrize("column, value, said", [
    ("active", "no", "true or false"), ("id", "1", "a whole number"),
    ("id", True, "a whole number"), ("username", True, "text"),
    ("username", ["x"], "text")])
def test_a_value_of_the_wrong_kind_is_refused(small, tmp_path, column, value, said):
    """records.json's users row with ``active: "no"``: SQLite stored the text as it was,
    the restore succeeded (the check took "no" for an active admin) and every later read
    of the users failed; each value is checked against its column's type."""
    from .test_records_backup import archive_without

    st, archive = small

    def wrong(doc):
        t = doc["tables"]["users"]
        t["rows"][0][t["columns"].index(column)] = value
        return doc
    bad = archive_without(archive, tmp_path / "wrong.zip", records_json=wrong)
    with pytest.raises(GonioError, match=f"users row 1: {column} is not {said}"):
        check_archive(bad)


def test_a_deactivated_admin_cannot_restore(small, tmp_path):
    """An admin deactivated after the archive was verified on their page: the confirmation
    sent afterwards meets the login page and nothing is restored."""
    from .test_web_security import csrf_of, login

    st, archive = small
    services.create_user(st, None, "boss2", PASSWORD, "admin")
    web = login(_page_app(st), "boss2")
    page = web.post("/backup/check", data={"csrf": csrf_of(web)}, files={
        "archive": ("a.zip", archive.read_bytes(), "application/zip")}).text
    send = dict(_confirm(page), csrf=csrf_of(web), confirm="RESTORE", password=PASSWORD)
    services.add_customer(st, services.user(st, "tech"), "After the backup Ltd")
    services.update_user(st, services.user(st, "boss"), "boss2", active=False, roles=["admin"])
    r = web.post("/backup/restore", data=send, follow_redirects=False)
    assert r.status_code == 303 and r.headers["location"] == "/login"
    assert summary(st)["rows"]["customers"] == 2


def test_a_stored_file_the_disk_refuses_is_one_line(tmp_path, monkeypatch):
    """The disk fills while the archive's stored files are written (an OSError before):
    one line, no records written."""
    from gonio.records import blobs

    archive = archive_of(tmp_path, "a", blob=b"readings " * 100)
    target = open_store(None, tmp_path / "target")
    try:
        def full(*a, **k):
            raise OSError(28, "No space left on device")
        monkeypatch.setattr(blobs, "put_stream", full)
        with pytest.raises(GonioError, match=r"cannot write the stored file [0-9a-f]{12}… \(No "
                                             r"space left on device\): the records are "
                                             "unchanged; nothing restored"):
            restore(target, archive)
        assert summary(target)["rows"]["users"] == 0
    finally:
        target.close()


def test_a_limit_that_is_no_number_is_said_on_the_page(small, monkeypatch):
    """GONIO_MAX_BACKUP_BYTES set to no number: the upload is refused with the variable
    named on the backup page (before, no limit applied at all)."""
    from .test_web_security import csrf_of, login

    st, archive = small
    web = login(_page_app(st), "boss")
    monkeypatch.setenv("GONIO_MAX_BACKUP_BYTES", "8 GB")
    r = web.post("/backup/check", data={"csrf": csrf_of(web)}, files={
        "archive": ("a.zip", archive.read_bytes(), "application/zip")})
    assert r.status_code == 500 and r.text.count(
        "environment variable GONIO_MAX_BACKUP_BYTES must be a number, got &#39;8 GB&#39;") == 1
