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
