"""The backup page (admin): verify the live records, download a backup, verify an archive
before restoring it (the checks of ``gonio db restore``, nothing written); the restore
itself is the command line's."""

from __future__ import annotations

import io
import re
import zipfile

from gonio.records import services
from gonio.records.backup import backup, check_archive, restore
from gonio.records.db import open_store

from .test_records_backup import (_records_made_once, damage, first_pdf,  # noqa: F401
                                  records)  # noqa: F401  (the fixtures)
from .test_web_security import PASSWORD, csrf_of, login


def test_backup_page_verifies_downloads_and_checks_an_archive(records, tmp_path):  # noqa: F811
    from gonio.web.app import create_app

    services.create_user(records, None, "boss", PASSWORD, "admin")
    app = create_app(records)
    tech = login(app, "tech")
    assert tech.get("/backup").status_code == 403
    assert tech.post("/backup/download", data={"csrf": csrf_of(tech)}).status_code == 403
    web = login(app, "boss")
    assert 'href="/backup"' in web.get("/").text
    page = web.post("/backup/verify", data={"csrf": csrf_of(web)}).text
    assert re.search(r'<p id="verified" class="ok">Records verified: \d+ stored files, '
                     r'2 calibrations, 1 certificates.</p>', page), page
    r = web.post("/backup/download", data={"csrf": csrf_of(web)})
    assert r.status_code == 200 and r.headers["content-type"] == "application/zip"
    assert re.fullmatch(r'attachment; filename="gonio-records-\d{4}-\d\d-\d\d-\d{4}\.zip"',
                        r.headers["content-disposition"])
    archive = tmp_path / "nightly.zip"
    archive.write_bytes(r.content)
    want = check_archive(archive)
    assert (want["calibrations"], want["certificates"]) == (2, 1)
    page = web.post("/backup/check", data={"csrf": csrf_of(web)},
                    files={"archive": ("nightly.zip", r.content, "application/zip")}).text
    assert (f"nightly.zip: complete and intact — 2 calibrations, 1 certificates, "
            f"{want['files']} stored files; last recorded change {want['newest']} UTC") in page
    # an archive missing one stored file (the first certificate's PDF): named, refused
    sha = first_pdf(records)
    buf = io.BytesIO()
    with zipfile.ZipFile(archive) as zin, zipfile.ZipFile(buf, "w") as zout:
        for item in zin.infolist():
            if item.filename != f"blobs/{sha}":
                zout.writestr(item, zin.read(item.filename))
    r = web.post("/backup/check", data={"csrf": csrf_of(web)},
                 files={"archive": ("short.zip", buf.getvalue(), "application/zip")})
    assert r.status_code == 400
    assert (f"incomplete: 1 stored file(s) of the records are not in the archive, first "
            f"{sha}: nothing restored") in r.text
    # the archive verified restores (on the command line) into an empty database
    other = open_store(None, tmp_path / "restored")
    try:
        assert restore(other, archive)["calibrations"] == 2
    finally:
        other.close()
    # a stored file damaged on disk: the live check names it, and no backup is made
    damage(records, sha)
    page = web.post("/backup/verify", data={"csrf": csrf_of(web)}).text
    assert f"<li>stored file {sha} (damaged)</li>" in page
    r = web.post("/backup/download", data={"csrf": csrf_of(web)})
    assert r.status_code == 409 and "1 stored file(s) missing or damaged" in r.text


def test_an_archive_with_web_sessions_restores_into_postgresql(pg_server, tmp_path):
    """A backup taken while people are logged in holds web sessions (a text id, no
    sequence): its restore into PostgreSQL moved every id sequence, that table's too, and
    failed ("COALESCE types text and integer cannot be matched")."""
    from gonio.records import auth

    from .conftest import new_pg_database

    src = open_store(new_pg_database(pg_server), tmp_path / "a")
    dst = open_store(new_pg_database(pg_server), tmp_path / "b")
    try:
        qm = services.create_user(src, None, "qm", PASSWORD, "admin")
        auth.open_session(src, qm)
        backup(src, tmp_path / "b.zip")
        counts = restore(dst, tmp_path / "b.zip")
        assert counts["users"] == 1 and "web_sessions" not in counts  # everyone logs in again
        # the ids go on after the restored ones
        assert services.create_user(dst, None, "next", PASSWORD, "technician").id == qm.id + 1
    finally:
        src.close()
        dst.close()


def _confirm(page: str) -> dict:
    """The restore form's hidden fields on a checked archive's page."""
    form = page[page.index('id="restore-form"'):]
    return {k: re.search(rf'name="{k}" value="([^"]*)"', form).group(1)
            for k in ("archive", "name", "sha256")}


def test_restore_in_the_browser(records, tmp_path, monkeypatch):  # noqa: F811
    """An archive from the backup folder verified, then restored over the live records:
    a technician is refused, a wrong password and a missing confirmation write nothing, the
    restore replaces the records and ends every session; while it runs other requests get
    503."""
    import hashlib

    from gonio.records.backup import summary
    from gonio.web.app import create_app

    services.create_user(records, None, "boss", PASSWORD, "admin")
    folder = tmp_path / "nightly-backups"
    folder.mkdir()
    monkeypatch.setenv("GONIO_BACKUP_FOLDER", str(folder))
    backup(records, folder / "2026-11-28.zip")
    services.add_customer(records, services.user(records, "tech"), "After the backup Ltd")
    app = create_app(records)
    tech, web = login(app, "tech"), login(app, "boss")
    page = web.get("/backup").text
    assert '<option value="2026-11-28.zip">2026-11-28.zip' in page
    page = web.post("/backup/check", data={"csrf": csrf_of(web), "choose": "2026-11-28.zip"}).text
    assert "2026-11-28.zip: complete and intact — 2 calibrations, 1 certificates" in page
    fields = _confirm(page)
    sha = hashlib.sha256((folder / "2026-11-28.zip").read_bytes()).hexdigest()
    assert fields == {"archive": "folder:2026-11-28.zip", "name": "2026-11-28.zip",
                      "sha256": sha} and f'<code id="archive-sha">{sha}</code>' in page
    customers = summary(records)["rows"]["customers"]
    assert customers == 2 and "<td>Calibrations</td><td>2</td><td>2</td>" in page
    send = dict(fields, confirm="RESTORE", password=PASSWORD)
    # a technician (with a CSRF token of their own), a wrong password, no confirmation
    assert tech.post("/backup/restore", data=dict(send, csrf=csrf_of(tech))).status_code == 403
    r = web.post("/backup/restore", data=dict(send, csrf=csrf_of(web), password="wrong"))
    assert r.status_code == 400 and "wrong password: nothing restored" in r.text
    r = web.post("/backup/restore", data=dict(send, csrf=csrf_of(web), confirm="yes"))
    assert r.status_code == 400 and "type RESTORE to confirm" in r.text
    r = web.post("/backup/restore", data=dict(send, csrf=csrf_of(web), archive="folder:../x.zip"))
    assert r.status_code == 400 and "verify it again" in r.text
    # no CSRF token: refused before anything
    assert web.post("/backup/restore", data=send).status_code == 403
    assert summary(records)["rows"]["customers"] == 2
    # the archive changed after it was verified: refused
    r = web.post("/backup/restore", data=dict(send, csrf=csrf_of(web), sha256="0" * 64))
    assert r.status_code == 409 and "not the one verified and confirmed" in r.text
    # the maintenance state: every other request answered 503 while it is closed
    assert app.state.gate.close("the records are being restored from a backup", 1)
    r = tech.get("/")
    assert r.status_code == 503 and "restored from a backup" in r.text
    app.state.gate.open()
    r = web.post("/backup/restore", data=dict(send, csrf=csrf_of(web)))
    assert r.status_code == 200, r.text
    assert "Restored from 2026-11-28.zip: 2 calibrations, 1 certificates" in r.text
    assert summary(records)["rows"]["customers"] == 1
    # every session ended: both people are sent to the login page
    for c in (web, tech):
        assert c.get("/").status_code == 303
    again = login(app, "boss")
    audit = again.get("/audit").text
    assert "restore" in audit and sha in audit


def test_the_gate_waits_for_requests_in_flight_and_answers_the_rest():
    """gonio.web.common.Gate: closing waits until the closing request is the only one in
    flight; meanwhile and afterwards every new request is turned away with the reason."""
    import threading
    import time

    from gonio.web.common import Gate

    gate = Gate()
    assert gate.enter() == ""                      # a page being answered
    assert gate.enter() == ""                      # the restore's own request
    closed = []
    t = threading.Thread(target=lambda: closed.append(gate.close("restoring", 10)))
    t.start()
    time.sleep(0.3)
    assert not closed and gate.enter() == "restoring"   # waiting, new requests refused
    gate.leave()                                   # the page ends: the restore may run
    t.join(5)
    assert closed == [True] and gate.close("again", 0.1) is False
    gate.open()
    gate.leave()
    assert gate.enter() == "" and gate.busy == 1
    # others that do not end in time: the gate opens again and says so
    gate.enter()
    assert gate.enter() == "" and gate.close("restoring", 0.2) is False
    assert gate.enter() == ""


def test_no_restore_while_a_worker_runs(records, tmp_path):  # noqa: F811
    """A calibration being computed: the restore is refused and nothing replaced; the
    dispatcher claims again afterwards."""
    import subprocess
    import sys

    from gonio.records.backup import summary
    from gonio.records.worker import Dispatcher
    from gonio.web.app import create_app

    services.create_user(records, None, "boss", PASSWORD, "admin")
    backup(records, tmp_path / "nightly.zip")
    services.add_customer(records, services.user(records, "tech"), "After the backup Ltd")
    dispatcher = Dispatcher(records)
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    dispatcher.children[99] = child
    try:
        app = create_app(records, dispatcher)
        web = login(app, "boss")
        page = web.post("/backup/check", data={"csrf": csrf_of(web)}, files={
            "archive": ("nightly.zip", (tmp_path / "nightly.zip").read_bytes(),
                        "application/zip")}).text
        r = web.post("/backup/restore", data=dict(_confirm(page), csrf=csrf_of(web),
                                                  confirm="RESTORE", password=PASSWORD))
        assert r.status_code == 409
        assert "1 calibration(s) are being computed or issued now" in r.text
        assert summary(records)["rows"]["customers"] == 2 and not dispatcher._paused
        assert web.get("/backup").status_code == 200        # the server is open again
    finally:
        child.kill()
        child.wait()
