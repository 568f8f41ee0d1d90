"""A restore verifies the records it would write, as ``gonio db verify`` verifies live ones, and
a backup verifies the records it archives: an archive whose result row was changed, whose
certificate rows were taken out, whose counter was set back or whose certificate names the
calibration's creator as its approver restored with exit 0 before (a later verify saw the
first, nothing saw the others), and a backup of records that do not verify was written."""

from __future__ import annotations

import json
import zipfile

import pytest
from sqlalchemy import text

from gonio.errors import GonioError
from gonio.records import backup as backup_mod
from gonio.records.db import open_store

from .conftest import make_people
from .test_records_issue import approved, run_issue


@pytest.fixture
def issued_archive(sqlite_store, computed_folder, bench_readings, monkeypatch, tmp_path):
    """A backup of a store holding one issued certificate (and the store)."""
    people = make_people(sqlite_store)
    approved(sqlite_store, people, computed_folder, bench_readings, monkeypatch)
    run_issue(sqlite_store, monkeypatch)
    path = tmp_path / "issued.zip"
    backup_mod.backup(sqlite_store, path)
    return sqlite_store, path


def tampered(src, dst, change) -> None:
    """``src`` with its records.json changed by ``change(tables)``, as ``dst``."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            data = zin.read(info.filename)
            if info.filename == "records.json":
                doc = json.loads(data)
                change(doc["tables"])
                data = json.dumps(doc).encode("utf-8")
            zout.writestr(info.filename, data)


def col(table, name):
    return table["columns"].index(name)


def scaled_value(t):
    rows = t["result_items"]
    rows["rows"][0][col(rows, "value")] *= 1.001


def no_certificates(t):
    t["certificates"]["rows"] = []


def counter_back(t):
    t["certificate_counters"]["rows"] = []


def creator_approves(t):
    cal, cert = t["calibrations"], t["certificates"]
    cal["rows"][0][col(cal, "created_by_id")] = cert["rows"][0][col(cert, "issued_by_id")]


def creator_reviews(t):
    cal = t["calibrations"]
    cal["rows"][0][col(cal, "reviewed_by_id")] = cal["rows"][0][col(cal, "created_by_id")]


def events_removed(t):
    ae = t["audit_events"]
    ae["rows"] = [r for r in ae["rows"]
                  if r[col(ae, "entity")] not in ("calibration", "certificate")]


@pytest.mark.parametrize("change,said", [
    (scaled_value, "differs from the stored results.json"),
    (no_certificates, "issued, and no certificate of it is recorded"),
    (counter_back, "beyond the 20"),
    # the creator column rewritten: first against its own audit trail (the trail names the
    # calibration's real creator), then the approver check behind it
    (creator_approves, "its recorded creator is not the one its audit trail"),
    # the reviewer column rewritten: against the review event, which names the real reviewer
    (creator_reviews, "its reviewer is not the user its audit trail's review event names"),
    # the calibration's and certificate's events left out of the archive
    (events_removed, r"its audit trail has no creation event \(create or import\)")])
def test_a_tampered_archive_is_not_restored(issued_archive, tmp_path, change, said):
    _, good = issued_archive
    bad = tmp_path / "bad.zip"
    tampered(good, bad, change)
    backup_mod.check_archive(bad)          # its form is sound: only its records are not
    target = open_store(None, tmp_path / "target")
    try:
        with pytest.raises(GonioError, match=f"do not verify: .*{said}") as exc:
            backup_mod.restore(target, bad)
        assert "nothing restored" in str(exc.value) and "\n" not in str(exc.value)
        with target.session() as s:
            assert s.scalar(text("SELECT count(*) FROM users")) == 0
        assert backup_mod.restore(target, good)["certificates"] == 1   # the good one restores
        assert backup_mod.verify(target)[1] == []
    finally:
        target.close()


def test_a_backup_of_records_that_do_not_verify_is_not_written(issued_archive, tmp_path):
    store, _ = issued_archive
    with store.writing() as s:
        s.execute(text("UPDATE result_items SET value = value * 1.001 WHERE id = "
                       "(SELECT min(id) FROM result_items)"))
        s.commit()
    with pytest.raises(GonioError, match="the records do not verify: .*nothing written"):
        backup_mod.backup(store, tmp_path / "late.zip")
    assert not (tmp_path / "late.zip").exists()
    assert not list(tmp_path.glob(".backup-*"))
