"""A calibration's row against its own audit trail: a creator rewritten in the database (so
that they may approve their own calibration) and a seal recomputed over a forged result and
written into the signed columns are refused on every path — approval and issue — and listed
by ``gonio db verify``; before, both were approved and issued and verify exited 0."""
from __future__ import annotations

import pytest
from sqlalchemy import text

from gonio.errors import GonioError
from gonio.records import backup, services, worker

from .test_records_sealed import certificates, computed
from .test_records_services import fake_pipeline


def _sql(store, statement: str, **params):
    with store.writing() as s:
        s.execute(text(statement), params)
        s.commit()


def test_a_creator_rewritten_in_the_database_cannot_approve(store, people, computed_folder,
                                                            bench_readings, monkeypatch):
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    creator = services.calibration(store, cal.id).created_by_id
    assert creator == people["tech"].id
    # the creator takes the reviewer role, and the row is made to name rev2 as the creator
    services.update_user(store, None, "tech", roles="technician reviewer")
    _sql(store, "UPDATE calibrations SET created_by_id = :u WHERE id = :c",
         u=people["rev2"].id, c=cal.id)
    with pytest.raises(GonioError, match="recorded creator is not the one its audit trail"):
        services.approve(store, services.user(store, "tech"), cal.id)
    assert services.calibration(store, cal.id).status == "reviewed"
    _, problems = backup.verify(store)
    assert any(f"calibration {cal.id}: its recorded creator" in p for p in problems), problems


def test_a_seal_recomputed_over_a_forged_result_is_not_issued(store, people, computed_folder,
                                                              bench_readings, monkeypatch):
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev2"], cal.id)
    # forge a row and recompute the seal over it, written into both signed columns
    _sql(store, "UPDATE result_items SET value = value * 1.5 WHERE key = 'scale_factor' "
                "AND calibration_id = :c", c=cal.id)
    forged = "f" * 64
    _sql(store, "UPDATE calibrations SET reviewed_seal = :f, approved_seal = :f WHERE id = :c",
         f=forged, c=cal.id)
    monkeypatch.setattr(services, "seal", lambda store, cal_id: forged)   # a consistent forgery
    monkeypatch.setattr(worker, "calibrate_folder", fake_pipeline(computed_folder))
    services.claim_next(store)
    assert not worker.execute(store, cal.id)
    cal = services.calibration(store, cal.id)
    assert cal.status == "failed" and "seal is not the one its audit trail's" in cal.error, \
        cal.error
    assert certificates(store) == []
    monkeypatch.undo()
    _, problems = backup.verify(store)
    assert any("approved seal is not the one its audit trail's approve event" in p
               for p in problems), problems


def test_stored_readings_damaged_after_approval_are_not_issued(store, people, computed_folder,
                                                               bench_readings, monkeypatch):
    """The raw data the result was computed from is part of what is sealed: readings whose
    stored file was changed on disk after approval (a serial edited) stop the issue; before,
    it went ahead and only a later ``gonio db verify`` named the file."""
    from gonio.records import blobs

    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev2"], cal.id)
    path = blobs.blob_path(store.blob_root, cal.readings_sha256)
    path.chmod(0o644)
    path.write_bytes(path.read_bytes().replace(b"# serial:", b"# serial: X", 1) + b"\n")
    monkeypatch.setattr(worker, "calibrate_folder", fake_pipeline(computed_folder))
    services.claim_next(store)
    assert not worker.execute(store, cal.id)
    cal = services.calibration(store, cal.id)
    assert cal.status == "failed" and "stored readings are missing or do not match" in cal.error
    assert certificates(store) == []


def test_a_swapped_stored_file_is_named_where_the_seal_breaks(store, people, computed_folder,
                                                              bench_readings, monkeypatch):
    """A stored file of a reviewed calibration pointed at another file in the database (the
    laboratory file swapped) is refused at approval, and the refusal and ``gonio db verify``
    name the file and both digests, not only the two seals."""
    import io

    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    with store.session() as s:
        names = set(s.scalars(text("SELECT name FROM calibration_files WHERE "
                                   "calibration_id = :c"), {"c": cal.id}))
        signed = s.scalar(text("SELECT sha256 FROM calibration_files WHERE calibration_id = "
                               ":c AND name = 'lab.toml'"), {"c": cal.id})
    assert "lab.toml" in names and signed
    other, _ = services.store_file(store, io.BytesIO(b"[laboratory]\nname = 'Another'\n"))
    _sql(store, "UPDATE calibration_files SET sha256 = :h WHERE calibration_id = :c AND "
                "name = 'lab.toml'", h=other, c=cal.id)
    with pytest.raises(GonioError) as got:
        services.approve(store, people["rev2"], cal.id)
    msg = got.value.message
    assert "no longer matches the one reviewed" in msg and "nothing approved" in msg, msg
    assert f"lab.toml is not the file signed (SHA-256 {other[:8]}… now, {signed[:8]}… " \
           "signed)" in msg, msg
    assert "results.json is not" not in msg, msg         # only what differs is named
    _, problems = backup.verify(store)
    assert any(f"calibration {cal.id}: its stored result no longer matches the seal of its "
               "review — lab.toml is not the file signed" in p for p in problems), problems


def test_a_file_swapped_after_approval_stays_listed_once_the_issue_failed(
        store, people, computed_folder, bench_readings, monkeypatch):
    """The issue refuses a stored file swapped after approval; the calibration is then failed
    with its number reserved and the seal approved, and ``gonio db verify`` still names the
    file (before: it listed nothing once the issue had failed)."""
    import io

    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev2"], cal.id)
    other, _ = services.store_file(store, io.BytesIO(b"another summary\n"))
    _sql(store, "UPDATE calibration_files SET sha256 = :h WHERE calibration_id = :c AND "
                "name = 'summary.txt'", h=other, c=cal.id)
    monkeypatch.setattr(worker, "calibrate_folder", fake_pipeline(computed_folder))
    services.claim_next(store)
    assert not worker.execute(store, cal.id)
    failed = services.calibration(store, cal.id)
    assert failed.status == "failed" and failed.pending_number, failed.status
    assert "summary.txt is not the file signed" in failed.error, failed.error
    assert certificates(store) == []
    _, problems = backup.verify(store)
    assert any(f"calibration {cal.id}: its stored result no longer matches the seal of its "
               "approval — summary.txt is not the file signed" in p for p in problems), problems


def _delete_events(store, where: str, **params) -> None:
    """Delete audit events as someone with the database would: the append-only trigger
    dropped, the events deleted and the trigger made again, as it was."""
    with store.writing() as s:
        if s.get_bind().dialect.name == "postgresql":
            s.execute(text("ALTER TABLE audit_events DISABLE TRIGGER audit_events_no_delete"))
            s.execute(text(f"DELETE FROM audit_events WHERE {where}"), params)
            s.execute(text("ALTER TABLE audit_events ENABLE TRIGGER audit_events_no_delete"))
        else:
            sql = s.scalar(text("SELECT sql FROM sqlite_master WHERE name = "
                                "'audit_events_no_delete'"))
            s.execute(text("DROP TRIGGER audit_events_no_delete"))
            s.execute(text(f"DELETE FROM audit_events WHERE {where}"), params)
            s.execute(text(sql))
        s.commit()


def test_a_deleted_creation_event_is_a_problem_not_nothing_to_compare(
        store, people, computed_folder, bench_readings, monkeypatch):
    """The creation event deleted and the creator column rewritten: the creator (given the
    reviewer role) does not approve their own calibration and verify names the missing
    event (before: a missing event was "nothing to compare", the approval went through and
    verify exited 0)."""
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    services.update_user(store, None, "tech", roles="technician reviewer")
    _delete_events(store, "entity = 'calibration' AND action IN ('create', 'import') AND "
                          "entity_id = :c", c=str(cal.id))
    _sql(store, "UPDATE calibrations SET created_by_id = :u WHERE id = :c",
         u=people["rev2"].id, c=cal.id)
    with pytest.raises(GonioError, match=f"calibration {cal.id}: its audit trail has no "
                                         r"creation event \(create or import\)"):
        services.approve(store, services.user(store, "tech"), cal.id)
    assert services.calibration(store, cal.id).status == "reviewed"
    assert (f"calibration {cal.id}: its audit trail has no creation event (create or "
            "import): events were removed outside gonio") in backup.verify(store)[1]


def test_an_issued_certificate_whose_trail_is_wiped_does_not_verify(
        store, people, computed_folder, bench_readings, monkeypatch, tmp_path):
    """Every audit event of an issued calibration and its certificate deleted: verify names
    each missing event, and no backup of it is written (before: verify found nothing)."""
    from .test_records_issue import approved, run_issue

    cal = approved(store, people, computed_folder, bench_readings, monkeypatch)
    cert = run_issue(store, monkeypatch)
    assert backup.verify(store)[1] == []
    _delete_events(store, "entity IN ('calibration', 'certificate')")
    problems = backup.verify(store)[1]
    for missing in ("no creation event", "no review event", "no approve event",
                    f"certificate {cert.number}: its audit trail has no issue event"):
        assert any(p.startswith(f"calibration {cal.id}: ") and missing in p
                   for p in problems), (missing, problems)
    with pytest.raises(GonioError, match="the records do not verify"):
        backup.backup(store, tmp_path / "wiped.zip")


def test_a_missing_trigger_is_a_problem(sqlite_store, tmp_path):
    """The audit trail's append-only trigger dropped: verify names it (before: nothing was
    said, and the trail could be deleted without an error)."""
    assert backup.verify(sqlite_store)[1] == []
    _sql(sqlite_store, "DROP TRIGGER audit_events_no_delete")
    assert backup.verify(sqlite_store)[1] == [
        "table audit_events: its trigger audit_events_no_delete is missing (its rows can be "
        "deleted without an error)"]
