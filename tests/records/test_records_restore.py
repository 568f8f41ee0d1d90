"""Restoring over the live records (gonio.records.backup.restore with ``replace``, what the
browser's restore runs), on SQLite and PostgreSQL: the archive's rows and files replace the
records, web sessions do not come back, the restore is the restored audit trail's newest
event; an admin only, the archive confirmed by its SHA-256; a failure part-way (a row the
database refuses after others were written, a failing swap) leaves the live records as they
were."""

from __future__ import annotations

import json
import zipfile

import pytest
from sqlalchemy import func, select

from gonio.errors import GonioError
from gonio.records import auth, backup as backup_mod, blobs, services
from gonio.records.backup import archive_sha256, backup, restore, summary
from gonio.records.models import AuditEvent, Base, Certificate, WebSession

from .conftest import PASSWORD
from .test_records_backup import archive_without, damage, one_issued
from .test_records_services import new_calibration, run_worker


@pytest.fixture
def nightly(store, people, computed_folder, bench_readings, monkeypatch, tmp_path):
    """The live records (one issued certificate) and last night's backup of them, taken
    before a second calibration was computed and somebody logged in: (store, archive)."""
    inst, std = one_issued(store, people, computed_folder, bench_readings, monkeypatch)
    auth.open_session(store, people["admin"])
    archive = tmp_path / "nightly.zip"
    backup(store, archive)
    new_calibration(store, people, inst, std, bench_readings[1])
    run_worker(store, monkeypatch, computed_folder)
    auth.open_session(store, people["tech"])
    return store, archive


def snapshot(store) -> dict:
    """Every table's rows, as text (so that each database's types compare), less the audit
    events of refused restores (which a refusal appends)."""
    out = {}
    with store.session() as s:
        for table in Base.metadata.sorted_tables:
            q = select(table).order_by(*table.primary_key)
            if table.name == "audit_events":
                q = q.where(table.c.action != "restore-refused")
            out[table.name] = [tuple(map(str, r)) for r in s.execute(q)]
    return out


def refusals(store) -> list[str]:
    """The reasons of the refused restores in the audit trail, oldest first."""
    with store.session() as s:
        return [json.loads(e.after_json)["reason"] for e in s.scalars(
            select(AuditEvent).where(AuditEvent.action == "restore-refused")
            .order_by(AuditEvent.id))]


def test_restore_replaces_the_live_records(nightly, people, tmp_path):
    store, archive = nightly
    before = summary(store)
    assert before["calibrations"] == 2 and before["rows"]["web_sessions"] == 2
    # the archive's own rows, read independently of restore: records.json
    with zipfile.ZipFile(archive) as zf:
        doc = json.loads(zf.read("records.json"))
    counts = restore(store, archive, replace=True, actor=people["admin"],
                     expect_sha256=archive_sha256(archive))
    assert counts["calibrations"] == 1 and "web_sessions" not in counts
    after = summary(store)
    assert after["calibrations"] == 1 and after["certificates"] == 1
    for name, table in doc["tables"].items():
        want = len(table["rows"]) + (1 if name == "audit_events" else 0)
        assert after["rows"][name] == (0 if name == "web_sessions" else want), name
    with store.session() as s:
        assert s.scalar(select(func.count()).select_from(WebSession)) == 0
        event = s.scalar(select(AuditEvent).order_by(AuditEvent.id.desc()).limit(1))
    assert (event.action, event.username, event.user_id) == ("restore", "admin",
                                                             people["admin"].id)
    said = json.loads(event.after_json)
    assert said["sha256"] == archive_sha256(archive) and said["archive"] == "nightly.zip"
    assert said["replaced"]["calibrations"] == 2
    # the records work on: verified whole, the next id after the restored ones
    assert backup_mod.verify(store)[1] == []
    assert services.add_customer(store, people["tech"], "After the restore Ltd").id == 2
    assert auth.authenticate(store, "admin", PASSWORD).username == "admin"
    if store.engine.dialect.name == "sqlite":    # the replaced file kept, no file left over
        assert len(list(store.data.glob("records.sqlite3.replaced-*"))) == 1
        assert not list(store.data.glob(".records.sqlite3.restoring-*"))


def test_restore_repairs_a_damaged_stored_file(nightly, people):
    store, archive = nightly
    with store.session() as s:
        sha = s.scalar(select(Certificate.pdf_sha256))
    damage(store, sha)
    assert any(sha in p for p in backup_mod.verify(store)[1])
    restore(store, archive, replace=True, actor=people["admin"])
    assert blobs.verify(store.blob_root, sha) and backup_mod.verify(store)[1] == []


def test_only_an_admin_restores_the_confirmed_archive(nightly, people, tmp_path):
    store, archive = nightly
    before = snapshot(store)
    for who in ("tech", "rev"):
        with pytest.raises(GonioError, match="this needs the admin role"):
            restore(store, archive, replace=True, actor=people[who])
    with pytest.raises(GonioError, match="this needs the admin role"):
        restore(store, archive, replace=True, actor=None)
    with pytest.raises(GonioError, match="not the one verified and confirmed"):
        restore(store, archive, replace=True, actor=people["admin"], expect_sha256="0" * 64)
    with pytest.raises(GonioError, match="holds records already"):
        restore(store, archive)
    # an archive without an active administrator: nobody could manage what it restores
    def no_admin(doc):
        t = doc["tables"]["users"]
        for row in t["rows"]:
            row[t["columns"].index("roles")] = "technician"
        return doc
    bad = archive_without(archive, tmp_path / "no-admin.zip", records_json=no_admin)
    with pytest.raises(GonioError, match="no active administrator"):
        restore(store, bad, replace=True, actor=people["admin"])
    assert snapshot(store) == before
    # an admin's refused restores are in the audit trail (a non-admin's never started)
    said = refusals(store)
    assert len(said) == 2 and "not the one verified" in said[0] and "no active admin" in said[1]


def test_a_failure_part_way_leaves_the_live_records(nightly, people, tmp_path, monkeypatch):
    store, archive = nightly
    before = snapshot(store)

    # the last table's rows refused by the database after every other table was written
    def twice(doc):
        t = doc["tables"]["audit_events"]
        t["rows"].append(list(t["rows"][0]))
        return doc
    bad = archive_without(archive, tmp_path / "dup.zip", records_json=twice)
    with pytest.raises(GonioError, match="records.json refused by the database .*nothing "
                                         "restored"):
        restore(store, bad, replace=True, actor=people["admin"])
    assert snapshot(store) == before
    assert services.add_customer(store, people["tech"], "Next Ltd").id == 2
    before = snapshot(store)
    if store.engine.dialect.name == "sqlite":    # the swap itself fails
        def fail(*a, **k):
            raise OSError(28, "No space left on device")
        with monkeypatch.context() as m:
            m.setattr(backup_mod.os, "replace", fail)
            with pytest.raises(GonioError, match="could not be swapped in .No space left"):
                restore(store, archive, replace=True, actor=people["admin"])
        assert snapshot(store) == before
        assert not list(store.data.glob(".records.sqlite3.restoring-*"))


def test_a_replace_never_sets_the_certificate_counter_back(nightly, people, monkeypatch,
                                                           computed_folder, bench_readings):
    """Last night's archive numbered one certificate; the live records issued a second
    since. Restored over them, the counter keeps the live one: the next certificate is the
    third, never a second GC-YYYY-0002 naming another calibration."""
    from .test_records_sealed import issue

    store, archive = nightly
    with store.session() as s:
        second = s.scalar(select(services.Calibration).order_by(services.Calibration.id.desc())
                          .limit(1))
    issue(store, people, second, monkeypatch, computed_folder)
    with store.session() as s:
        numbers = sorted(s.scalars(select(Certificate.number)))
    assert [n[-4:] for n in numbers] == ["0001", "0002"]
    restore(store, archive, replace=True, actor=people["admin"])
    with store.session() as s:
        assert [c.number for c in s.scalars(select(Certificate))] == numbers[:1]
        event = s.scalar(select(AuditEvent).order_by(AuditEvent.id.desc()).limit(1))
    year = numbers[0].split("-")[1]
    assert json.loads(event.after_json)["counters_kept"] == {year: {"archive": 1, "kept": 2}}
    assert backup_mod.verify(store)[1] == []
    inst_id = second.instrument_id
    with store.session() as s:
        std = s.scalar(select(services.Standard).limit(1))
        inst = s.get(services.Instrument, inst_id)
    third = new_calibration(store, people, inst, std, bench_readings[1])
    run_worker(store, monkeypatch, computed_folder)
    issue(store, people, third, monkeypatch, computed_folder)
    with store.session() as s:
        got = sorted(s.scalars(select(Certificate.number)))
    assert got == [numbers[0], f"{numbers[0][:-4]}0003"]
