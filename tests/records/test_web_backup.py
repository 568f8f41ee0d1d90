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

from .test_records_backup import damage, first_pdf, records  # noqa: F401  (the fixture)
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
        assert restore(dst, tmp_path / "b.zip")["web_sessions"] == 1
        # the ids go on after the restored ones
        assert services.create_user(dst, None, "next", PASSWORD, "technician").id == qm.id + 1
    finally:
        src.close()
        dst.close()
