"""The sealed review (the reviewer and the approver sign the stored result's content hash;
the issue refuses a result that no longer matches it) and the duties on every path: the
creator, the reviewer and the approver are different people (two for a small laboratory),
amendments included; certificates verified against their record."""

from __future__ import annotations

import hashlib
import math
import json

import pytest
from sqlalchemy import func, select, text

from gonio.errors import GonioError
from gonio.records import services, worker
from gonio.records.models import Calibration, Certificate, ResultItem

from .conftest import PASSWORD, conditions
from .test_web_security import app, csrf_of, login  # noqa: F401  (the app fixture)
from .test_records_services import fake_pipeline, new_calibration, run_worker, setup_instrument


def computed(store, people, computed_folder, bench_readings, monkeypatch):
    inst, std = setup_instrument(store, people)
    cal = new_calibration(store, people, inst, std, bench_readings[0])
    return run_worker(store, monkeypatch, computed_folder)


def tamper(store, cal_id):
    with store.writing() as s:
        s.execute(text("UPDATE result_items SET value = value*1.5 WHERE key='scale_factor' "
                       "AND calibration_id = :c"), {"c": cal_id})
        s.commit()


def certificates(store):
    with store.session() as s:
        return s.scalars(select(Certificate).order_by(Certificate.id)).all()


def test_seal_is_the_hash_of_the_stored_files_and_rows(store, people, computed_folder,
                                                       bench_readings, monkeypatch):
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    # recomputed here from the stored file digests and rows, independently of seal()
    with store.session() as s:
        rows = [[r.key, r.title, r.clause, r.unit, bool(r.measured), r.value, r.U, r.k]
                for r in s.scalars(select(ResultItem).where(
                    ResultItem.calibration_id == cal.id).order_by(ResultItem.id))]
        files = dict(s.execute(text("SELECT name, sha256 FROM calibration_files "
                                    "WHERE calibration_id = :c"), {"c": cal.id}).all())
    assert files["results.json"] == hashlib.sha256(
        (computed_folder / "results.json").read_bytes()).hexdigest()
    doc = json.dumps({"files": files, "items": rows}, sort_keys=True, separators=(",", ":"))
    assert services.seal(store, cal.id) == hashlib.sha256(doc.encode()).hexdigest()


def test_row_changed_after_review_refused_at_approval(store, people, computed_folder,
                                                      bench_readings, monkeypatch):
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    signed = services.seal(store, cal.id)
    assert services.review(store, people["rev"], cal.id, accept=True,
                           shown_seal=signed).reviewed_seal == signed
    tamper(store, cal.id)
    with pytest.raises(GonioError, match="row scale_factor differs from the stored results"):
        services.approve(store, people["rev2"], cal.id)
    assert services.calibration(store, cal.id).status == "reviewed"


def test_row_changed_after_approval_refused_at_issue(store, people, computed_folder,
                                                     bench_readings, monkeypatch):
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev2"], cal.id)
    tamper(store, cal.id)
    monkeypatch.setattr(worker, "calibrate_folder",
                        fake_pipeline(computed_folder))
    services.claim_next(store)
    assert not worker.execute(store, cal.id)
    cal = services.calibration(store, cal.id)
    assert cal.status == "failed" and "row scale_factor differs" in cal.error
    assert certificates(store) == []


def test_row_changed_before_review_refused_and_shown(store, people, computed_folder,
                                                     bench_readings, monkeypatch):
    from gonio.records import queries

    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    tamper(store, cal.id)
    page = queries.calibration_page(store, cal.id)
    assert page["seal"] == "" and "scale_factor differs" in page["seal_error"]
    with pytest.raises(GonioError, match="scale_factor differs"):
        services.review(store, people["rev"], cal.id, accept=True)


def test_stored_file_damaged_after_review_refused(store, people, computed_folder,
                                                  bench_readings, monkeypatch):
    from gonio.records import blobs

    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    path = blobs.blob_path(store.blob_root, cal.results_sha256)
    path.chmod(0o644)
    path.write_bytes(path.read_bytes().replace(b"scale_factor", b"scale_fact0r", 1))
    with pytest.raises(GonioError, match="results.json is missing or does not match"):
        services.approve(store, people["rev2"], cal.id)


def test_seal_shown_must_be_the_one_signed(store, people, computed_folder, bench_readings,
                                           monkeypatch):
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    with pytest.raises(GonioError, match="changed since the page was shown"):
        services.review(store, people["rev"], cal.id, accept=True, shown_seal="0" * 64)


def issue(store, people, cal, monkeypatch, computed_folder, reviewer="rev", approver="rev2"):
    services.review(store, people[reviewer], cal.id, accept=True)
    services.approve(store, people[approver], cal.id)
    return run_worker(store, monkeypatch, computed_folder)


def test_certificate_records_seal_people_and_verifies(store, people, computed_folder,
                                                      bench_readings, monkeypatch):
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    signed = services.seal(store, cal.id)
    issue(store, people, cal, monkeypatch, computed_folder)
    (cert,) = certificates(store)
    assert cert.seal_sha256 == signed and cert.min_people == 3
    assert cert.reviewed_by_id == people["rev"].id and cert.issued_by_id == people["rev2"].id
    pdf = services.file_bytes(store, cert.pdf_sha256)
    found = services.verify_certificate(store, pdf)
    assert found["number"] == cert.number and found["file"] == "certificate.pdf"
    assert found["seal"] == signed and found["seal_now"] == signed
    with pytest.raises(GonioError, match="no certificate"):
        services.verify_certificate(store, pdf + b" ")


def test_reviewer_may_not_approve_unless_two_people_suffice(store, people, computed_folder,
                                                            bench_readings, monkeypatch):
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    with pytest.raises(GonioError, match="reviewed the calibration may not approve"):
        services.approve(store, people["rev"], cal.id)
    with pytest.raises(GonioError, match="min_people"):
        services.set_settings(store, people["admin"], min_people="1")
    services.set_settings(store, people["admin"], min_people="2")
    services.approve(store, people["rev"], cal.id)
    run_worker(store, monkeypatch, computed_folder)
    assert certificates(store)[0].min_people == 2


def test_import_without_creator_cannot_be_reviewed(store, people, computed_folder,
                                                   bench_readings):
    from gonio.records.importer import import_output_folder
    from .test_records_services import SMALL_PROTOCOL

    cid = import_output_folder(store, computed_folder, readings=bench_readings[0],
                               protocol=SMALL_PROTOCOL)
    with pytest.raises(GonioError, match="creator is not recorded"):
        services.review(store, people["rev"], cid, accept=True)
    with store.writing() as s:       # set aside: one readings file, one standing calibration
        s.get(Calibration, cid).status = "void"
        s.commit()
    cid2 = import_output_folder(store, computed_folder, readings=bench_readings[0],
                                protocol=SMALL_PROTOCOL, actor=people["rev"])
    assert services.calibration(store, cid2).created_by_id == people["rev"].id
    with pytest.raises(GonioError, match="second person"):
        services.review(store, people["rev"], cid2, accept=True)
    services.attach_conditions(store, people["rev"], cid2, temperature_c=20, humidity_pct=45,
                               **{k: v for k, v in conditions(store, people["tech"]).items()
                                  if k == "standard_ids"})
    from gonio.records.worker import run_now
    run_now(store, cid2)                   # its draft rendered with them
    services.review(store, people["rev2"], cid2, accept=True)
    with pytest.raises(GonioError, match="may not approve"):
        services.approve(store, people["rev2"], cid2)


def test_amendment_needs_another_person_and_keeps_the_original(store, people, computed_folder,
                                                               bench_readings, monkeypatch):
    # created by admin, who holds the reviewer role too
    cal = computed(store, dict(people, tech=people["admin"]), computed_folder, bench_readings,
                   monkeypatch)
    issue(store, people, cal, monkeypatch, computed_folder)
    (first,) = certificates(store)
    # the creator cannot amend (before: re-issued it alone, "Approved by" the creator);
    # the one who asks cannot approve it alone
    with pytest.raises(GonioError, match="created a calibration may not amend"):
        services.amend(store, people["admin"], first.id, "typo")
    services.amend(store, people["rev2"], first.id, "customer address corrected")
    with pytest.raises(GonioError, match="asked for the amendment may not approve"):
        services.approve(store, people["rev2"], cal.id)
    services.approve(store, people["rev"], cal.id)
    run_worker(store, monkeypatch, computed_folder)
    old, new = certificates(store)
    assert (old.issued_by_id, old.reviewed_by_id) == (people["rev2"].id, people["rev"].id)
    assert (new.issued_by_id, new.reviewed_by_id) == (people["rev"].id, people["rev2"].id)
    assert new.replaces_id == old.id and new.reason == "customer address corrected"
    assert new.seal_sha256 == old.seal_sha256


def test_certificate_page_shows_seal_people_and_downloads_by_number(
        app, sqlite_store, computed_folder, bench_readings, monkeypatch):  # noqa: F811
    people = {n: services.user(sqlite_store, n) for n in ("tech", "rev", "admin")}
    people["rev2"] = services.create_user(sqlite_store, None, "rev2", PASSWORD, "reviewer")
    cal = computed(sqlite_store, people, computed_folder, bench_readings, monkeypatch)
    rev = login(app, "rev")
    page = rev.get(f"/calibrations/{cal.id}").text
    signed = services.seal(sqlite_store, cal.id)
    assert f'<code id="seal">{signed}</code>' in page
    r = rev.get(f"/calibrations/{cal.id}/files/certificate.pdf")
    assert f'filename="DRAFT-{cal.id}.pdf"' in r.headers["content-disposition"]
    # the page's seal travels with the decision; a changed result is refused
    r = rev.post(f"/calibrations/{cal.id}/review", data={
        "csrf": csrf_of(rev), "decision": "accept", "seal": "f" * 64})
    assert "changed%20since%20the%20page" in r.headers["location"]
    rev.post(f"/calibrations/{cal.id}/review", data={"csrf": csrf_of(rev),
                                                     "decision": "accept", "seal": signed})
    services.approve(sqlite_store, people["rev2"], cal.id)
    run_worker(sqlite_store, monkeypatch, computed_folder)
    (cert,) = certificates(sqlite_store)
    page = rev.get(f"/certificates/{cert.id}").text
    assert signed in page and "Reviewed by</dt><dd>rev<" in page
    assert "Approved by</dt><dd>rev2<" in page and "3 different people" in page
    for name, shown in (("certificate.pdf", ".pdf"), ("certificate.dcc.xml", ".dcc.xml"),
                        ("results.json", "-results.json")):
        r = rev.get(f"/certificates/{cert.id}/{name}")
        assert f'filename="{cert.number}{shown}"' in r.headers["content-disposition"], name


def test_page_states_every_item_by_the_statement_rule(store, people, computed_folder,
                                                      bench_readings, monkeypatch):
    """The calibration page states each item as the certificate does: the statement rule
    applied to the stored results.json (checked here against the rule's own texts, and
    against U to two significant digits computed independently)."""
    from gonio.records import queries
    from gonio.result.statement import item_statement

    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    page = queries.calibration_page(store, cal.id)
    res = json.loads((computed_folder / "results.json").read_text())
    items = res["items"]
    assert set(page["stated"]) == set(items)
    K = items["scale_factor"]
    assert page["stated"]["scale_factor"].text() == item_statement(K).text()
    U = K["uncertainty"]["U"]
    two = f"{U:.{max(0, 1 - math.floor(math.log10(abs(U))))}f}"
    assert page["stated"]["scale_factor"].U_text in (two, two.rstrip("0").rstrip("."))
