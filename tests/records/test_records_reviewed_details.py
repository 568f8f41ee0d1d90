"""What is issued is what was reviewed: the customer, instrument, standards and conditions a
certificate states are the ones of the draft its reviewer signed. An edit through the records
sends a reviewed calibration back to its review with its draft rendered again, is refused
while an approved one waits for its issue, and counts as a change of an amendment; a change
made around the records (the database edited) is refused at approval, listed by verify, and
never reaches the certificate. The people on a certificate are told apart by their names, the
number of people it states is the one it was approved under, and who last changed what a
reviewer checks does not approve it alone."""

from __future__ import annotations

import pytest
from sqlalchemy import text

from gonio.errors import GonioError
from gonio.records import backup, services, worker

from .test_records_issue import approved, run_issue
from .test_records_sealed import computed
from .test_web_security import app  # noqa: F401  (the app fixture, for the store fixtures)


def redraft(store, monkeypatch):
    """Render the draft again as a worker does (nothing computed)."""
    cal = services.claim_next(store)
    assert cal is not None and cal.status == services.DRAFTING
    assert worker.execute(store, cal.id), services.calibration(store, cal.id).error
    return services.calibration(store, cal.id)


def draft_page(store, cal_id) -> str:
    with store.session() as s:
        sha = s.get(services.CalibrationFile, (cal_id, "certificate.html")).sha256
    return services.file_bytes(store, sha).decode("utf-8")


def test_an_instrument_edit_after_review_is_reviewed_again(store, people, computed_folder,
                                                           bench_readings, monkeypatch):
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    services.update_instrument(store, people["tech"], cal.instrument_id, serial="RLG-0002")
    now = services.calibration(store, cal.id)
    assert (now.status, now.reviewed_by_id, now.reviewed_seal) == (services.DRAFTING, None, "")
    with pytest.raises(GonioError, match="cannot approve a calibration that is drafting"):
        services.approve(store, people["rev2"], cal.id)
    assert redraft(store, monkeypatch).status == "computed"
    assert "RLG-0002" in draft_page(store, cal.id) and "RLG-0001" not in draft_page(store, cal.id)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev2"], cal.id)
    page = services.file_bytes(store, run_issue(store, monkeypatch).html_sha256).decode()
    assert "RLG-0002" in page and "RLG-0001" not in page


@pytest.mark.parametrize("what", ["instrument", "customer", "standard"])
def test_an_edit_is_refused_while_an_approved_certificate_waits(what, store, people,
                                                                computed_folder,
                                                                bench_readings, monkeypatch):
    """An instrument or customer edit is refused while an approved certificate waits for its
    issue; a standard's (its recalibration: a new accuracy) goes through, and the certificate
    states the standard as the reviewed draft did, when it was used."""
    cal = approved(store, people, computed_folder, bench_readings, monkeypatch)
    tech = people["tech"]
    if what == "standard":
        with store.session() as s:
            sid = s.scalar(text("SELECT standard_id FROM calibration_standards WHERE "
                                "calibration_id = :c"), {"c": cal.id})
        services.update_standard(store, tech, sid, accuracy="±99″")
        assert services.details_changed(store, cal.id) == []
    with pytest.raises(GonioError, match="waits for its issue"):
        if what in ("instrument", "standard"):
            other = services.add_customer(store, tech, "Other Customer Ltd")
            services.update_instrument(store, tech, cal.instrument_id, serial="FAKE-9999",
                                       customer_id=other.id)
        else:
            with store.session() as s:
                cid = s.scalar(text("SELECT customer_id FROM instruments WHERE id = :i"),
                               {"i": cal.instrument_id})
            services.update_customer(store, tech, cid, name="Other Customer Ltd")
    # an edit that no certificate states goes through
    services.update_instrument(store, tech, cal.instrument_id, interval_months=6)
    page = services.file_bytes(store, run_issue(store, monkeypatch).html_sha256).decode()
    assert "RLG-0001" in page and "Example Navigation Co." in page
    assert "FAKE-9999" not in page and "Other Customer" not in page and "±99″" not in page
    # issued: the register may change again (an amendment would state it)
    services.update_instrument(store, tech, cal.instrument_id, serial="RLG-0001A")


def test_a_database_edit_is_refused_at_approval_and_never_issued(store, people,
                                                                 computed_folder,
                                                                 bench_readings, monkeypatch):
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)

    def serial(value):
        with store.writing() as s:
            s.execute(text("UPDATE instruments SET serial = :v WHERE id = :i"),
                      {"v": value, "i": cal.instrument_id})
            s.commit()
    serial("FAKE-9999")
    assert services.details_changed(store, cal.id) == [
        "instrument serial: 'RLG-0001' in the draft, now 'FAKE-9999'"]
    # the register entry against its trail is checked first (check_duties), in one line
    with pytest.raises(GonioError, match="instrument FAKE-9999: its serial 'FAKE-9999' is "
                                         "not the 'RLG-0001' its audit trail's latest event"):
        services.approve(store, people["rev2"], cal.id)
    assert any("instrument serial" in p for p in backup.verify(store)[1])
    serial("RLG-0001")
    assert services.details_changed(store, cal.id) == [] and backup.verify(store)[1] == []
    services.approve(store, people["rev2"], cal.id)
    serial("FAKE-9999")           # after the approval: the issue refuses the edited register
    from .test_records_issue import no_pipeline
    monkeypatch.setattr(worker, "calibrate_folder", no_pipeline)
    services.claim_next(store)
    assert not worker.execute(store, cal.id)
    assert "instrument FAKE-9999: its serial" in services.calibration(store, cal.id).error
    serial("RLG-0001")                          # restored: issued, stating the draft's
    services.retry(store, people["tech"], cal.id)
    page = services.file_bytes(store, run_issue(store, monkeypatch).html_sha256).decode()
    assert "RLG-0001" in page and "FAKE-9999" not in page


def amending(store, people, computed_folder, bench_readings, monkeypatch, reason: str,
             tech_roles: str):
    """A two-person laboratory's calibration issued (reviewed and approved by rev) and its
    amendment asked for by rev2 with ``reason``; tech given ``tech_roles``. Returns (the
    calibration, tech)."""
    services.set_settings(store, people["admin"], min_people="2")
    tr = services.update_user(store, None, "tech", roles=tech_roles)
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev"], cal.id)
    first = run_issue(store, monkeypatch)
    services.amend(store, people["rev2"], first.id, reason)
    return cal, tr


def test_an_instrument_edit_during_an_amendment_is_a_change(store, people, computed_folder,
                                                            bench_readings, monkeypatch):
    """One changes, another approves: the serial corrected in the register during an
    amendment counts as a change of it (before: only an attach did)."""
    cal, tr = amending(store, people, computed_folder, bench_readings, monkeypatch,
                       "serial misread", "technician reviewer")
    services.update_instrument(store, tr, cal.instrument_id, serial="RLG-0002")
    with pytest.raises(GonioError, match="changed the calibration during its amendment"):
        services.approve(store, tr, cal.id)
    services.approve(store, people["rev"], cal.id)
    page = services.file_bytes(store, run_issue(store, monkeypatch).html_sha256).decode()
    assert "RLG-0002" in page


def test_a_standard_edit_during_an_amendment_is_a_change(store, people, computed_folder,
                                                         bench_readings, monkeypatch):
    """One changes, another approves: a standard of the calibration edited in the register
    during its amendment (the amended certificate states it as edited) counts as a change by
    the editor, who then does not approve the amendment (before: the editor approved it)."""
    from gonio.records.models import CalibrationStandard
    from sqlalchemy import select

    cal, tr = amending(store, people, computed_folder, bench_readings, monkeypatch,
                       "standard's certificate misread", "technician reviewer admin")
    with store.session() as s:
        std_id = s.scalars(select(CalibrationStandard.standard_id).where(
            CalibrationStandard.calibration_id == cal.id)).first()
    services.update_standard(store, tr, std_id, certificate="NIM-2026-9999")
    with pytest.raises(GonioError, match="changed the calibration during its amendment"):
        services.approve(store, tr, cal.id)
    assert services.approve(store, people["rev"], cal.id).status == "issuing"
    # the amendment's own correction reaches its certificate
    page = services.file_bytes(store, run_issue(store, monkeypatch).html_sha256).decode()
    assert "NIM-2026-9999" in page


USED, USED_ACC, RECAL = "TC-2025-0007", "0.2 arcsec, k 2", "RECAL-2027-0042"


def issued_under(store, people, computed_folder, bench_readings, monkeypatch,
                 certificate=USED):
    """A two-person laboratory's calibration made with RT-07 under its certificate
    ``certificate`` (accuracy USED_ACC), issued: (the calibration, RT-07, the certificate)."""
    from .test_records_services import new_calibration, run_worker, setup_instrument

    services.set_settings(store, people["admin"], min_people="2")
    inst, std = setup_instrument(store, people)
    services.update_standard(store, people["tech"], std.id, certificate=certificate,
                             accuracy=USED_ACC)
    new_calibration(store, people, inst, std, bench_readings[0])
    cal = run_worker(store, monkeypatch, computed_folder)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev"], cal.id)
    first = run_issue(store, monkeypatch)
    page = services.file_bytes(store, first.html_sha256).decode()
    assert certificate in page and USED_ACC in page
    return cal, std, first


def recalibrate(store, people, std) -> None:
    """RT-07's recalibration recorded as the register's form records it: a new certificate
    and accuracy with the new calibration and due dates, in one edit."""
    import datetime as dt

    today = services.records_today(store)
    services.update_standard(store, people["tech"], std.id, certificate=RECAL,
                             accuracy="0.05 arcsec, recalibrated", calibrated_on=today,
                             due_on=today + dt.timedelta(days=365))


def amended_page(store, people, cal, monkeypatch) -> str:
    services.approve(store, people["rev"], cal.id)
    return services.file_bytes(store, run_issue(store, monkeypatch).html_sha256).decode()


def test_a_standard_recalibrated_after_the_issue_is_stated_as_used(store, people,
                                                                   computed_folder,
                                                                   bench_readings,
                                                                   monkeypatch):
    """A standard recalibrated after the first issue (a new certificate and accuracy in the
    register) is stated in an amendment as the replaced certificate stated it, as it was when
    used; before, the amendment stated the register's new certificate for a measurement made
    under the old one. An unrelated correction during the amendment (its traceability) reaches
    it field by field, without the recalibration."""
    cal, std, first = issued_under(store, people, computed_folder, bench_readings, monkeypatch)
    recalibrate(store, people, std)
    services.amend(store, people["rev2"], first.id, "customer's address misprinted")
    services.update_standard(store, people["admin"], std.id, traceability="NIM (typo fixed)")
    page = amended_page(store, people, cal, monkeypatch)
    assert USED in page and RECAL not in page
    assert "recalibrated" not in page and USED_ACC in page and "NIM (typo fixed)" in page
    # and an amendment of the amendment too (from its issue's record)
    amended = services.amend(store, people["rev2"], cal_certificate(store, cal), "once more")
    page = amended_page(store, people, amended, monkeypatch)
    assert USED in page and RECAL not in page and "NIM (typo fixed)" in page


def cal_certificate(store, cal) -> int:
    """The id of the calibration's newest certificate."""
    from .test_records_sealed import certificates

    return [c for c in certificates(store) if c.calibration_id == cal.id][-1].id


def test_a_correction_made_before_the_amendment_is_asked_for_reaches_it(
        store, people, computed_folder, bench_readings, monkeypatch):
    """The register corrected first (a misread certificate number), then the amendment asked
    for to carry it: the amendment states the correction; who corrected it does not approve
    the amendment (one changes, another approves)."""
    cal, std, first = issued_under(store, people, computed_folder, bench_readings,
                                   monkeypatch, certificate="TC-2025-0O07")
    tech2 = services.update_user(store, None, "tech", roles="technician reviewer")
    services.update_standard(store, tech2, std.id, certificate=USED)
    services.amend(store, people["rev2"], first.id, "standard's certificate number misread")
    with pytest.raises(GonioError, match="changed the calibration during its amendment"):
        services.approve(store, tech2, cal.id)
    page = amended_page(store, people, cal, monkeypatch)
    assert USED in page and "TC-2025-0O07" not in page


def test_an_edit_after_the_amendments_approval_reaches_nothing(
        store, people, computed_folder, bench_readings, monkeypatch):
    """What is issued is what was approved: a standard edited after the amendment's approval,
    before its issue, is not stated on it (before: it was, and gonio db verify said
    nothing)."""
    cal, std, first = issued_under(store, people, computed_folder, bench_readings, monkeypatch)
    services.amend(store, people["rev2"], first.id, "customer's address misprinted")
    services.approve(store, people["rev"], cal.id)
    services.update_standard(store, people["tech"], std.id, certificate="UNAPPROVED-1")
    page = services.file_bytes(store, run_issue(store, monkeypatch).html_sha256).decode()
    assert USED in page and "UNAPPROVED-1" not in page


def test_a_standard_attached_during_an_amendment(store, people, computed_folder,
                                                 bench_readings, monkeypatch):
    """A second standard attached during the amendment is stated as the register holds it;
    the one used before stays as the replaced certificate stated it."""
    import datetime as dt

    cal, std, first = issued_under(store, people, computed_folder, bench_readings, monkeypatch)
    recalibrate(store, people, std)
    services.amend(store, people["rev2"], first.id, "a level used was not named")
    lvl = services.add_standard(store, people["tech"], name="level", identifier="LV-3",
                                certificate="LV-CERT-9",
                                due_on=dt.date.today() + dt.timedelta(days=300))
    services.attach_conditions(store, people["tech"], cal.id, standard_ids=[std.id, lvl.id])
    page = amended_page(store, people, cal, monkeypatch)
    assert "LV-3" in page and "LV-CERT-9" in page
    assert USED in page and RECAL not in page


def test_an_amendment_of_one_issued_before_statements_were_kept(
        store, people, computed_folder, bench_readings, monkeypatch):
    """A chain whose amendment was issued before the issue kept its statement (its event has
    none): the next amendment states the first certificate's standards, with the corrections
    since, not the recalibration."""
    cal, std, first = issued_under(store, people, computed_folder, bench_readings, monkeypatch)
    services.amend(store, people["rev2"], first.id, "one")
    services.approve(store, people["rev"], cal.id)
    real = services.store_issue
    monkeypatch.setattr(services, "store_issue",
                        lambda st, cid, out, stated_standards=None: real(st, cid, out))
    second = run_issue(store, monkeypatch)
    monkeypatch.setattr(services, "store_issue", real)
    recalibrate(store, people, std)
    services.amend(store, people["rev2"], second.id, "two")
    page = amended_page(store, people, cal, monkeypatch)
    assert USED in page and RECAL not in page


def test_who_last_changed_and_reviewed_does_not_approve_alone(store, people, computed_folder,
                                                              bench_readings, monkeypatch):
    services.set_settings(store, people["admin"], min_people="2")
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    rev = people["rev"]
    services.attach_conditions(store, rev, cal.id, temperature_c="20.4", humidity_pct="55")
    redraft(store, monkeypatch)
    services.review(store, rev, cal.id, accept=True)
    with pytest.raises(GonioError, match="last changed the calibration's details"):
        services.approve(store, rev, cal.id)
    # the technician states the conditions again: another person changed them last
    services.attach_conditions(store, people["tech"], cal.id, temperature_c="20.4",
                               humidity_pct="55")
    redraft(store, monkeypatch)
    services.review(store, rev, cal.id, accept=True)
    assert services.approve(store, rev, cal.id).status == "issuing"


def test_the_number_of_people_is_the_one_approved_under(store, people, computed_folder,
                                                        bench_readings, monkeypatch):
    services.set_settings(store, people["admin"], min_people="2")
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev"], cal.id)
    with pytest.raises(GonioError, match="wait for their issue"):
        services.set_settings(store, people["admin"], min_people="3")
    services.set_settings(store, people["admin"], min_people="2")      # unchanged: fine
    assert run_issue(store, monkeypatch).min_people == 2
    services.set_settings(store, people["admin"], min_people="3")


def test_people_are_told_apart_by_their_names(store, people):
    services.update_user(store, None, "tech", full_name="Alice Smith")
    for name in ("Alice Smith", " alice   SMITH ", "rev2"):
        with pytest.raises(GonioError, match="on certificates already"):
            services.update_user(store, None, "rev", full_name=name)
    with pytest.raises(GonioError, match="'tech' is named 'Alice Smith'"):
        services.create_user(store, None, "alice2", "correct horse battery", "reviewer",
                             full_name="ALICE SMITH")
    with pytest.raises(GonioError, match="on certificates already"):
        services.create_user(store, None, "alice smith".replace(" ", "."), "x" * 12,
                             "reviewer", full_name="rev")
    services.update_user(store, None, "rev", full_name="Alice Smythe")


def test_a_name_given_up_is_not_given_to_another(store, people):
    """A certificate signed by "Tom Tech" keeps that name after its signatory is renamed: no
    other user may take it, in any case or Unicode form; the renamed person may take it
    back."""
    import unicodedata
    services.update_user(store, None, "tech", full_name="Tom Tech")
    services.update_user(store, None, "tech", full_name="Thomas Techson")
    for name in ("Tom Tech", "TOM  tech"):
        with pytest.raises(GonioError, match="'tech' was named"):
            services.update_user(store, None, "rev", full_name=name)
        with pytest.raises(GonioError, match="'tech' was named"):
            services.create_user(store, None, "tom2", "correct horse battery", "reviewer",
                                 full_name=name)
    services.update_user(store, None, "tech", full_name="Tom Tech")
    # a name in another Unicode form prints alike: the same name
    services.update_user(store, None, "rev", full_name=unicodedata.normalize("NFC", "José Núñez"))
    with pytest.raises(GonioError, match="on certificates already"):
        services.create_user(store, None, "jose2", "correct horse battery", "reviewer",
                             full_name=unicodedata.normalize("NFD", "José Núñez"))


def test_a_backup_never_replaces_the_records_own_files(sqlite_store, tmp_path):
    from .conftest import make_people

    make_people(sqlite_store)
    db = sqlite_store.engine.url.database
    before = open(db, "rb").read()[:100]
    for target in (db, db + "-wal", sqlite_store.blob_root / "ab"):
        with pytest.raises(GonioError, match="replace the records' own file"):
            backup.backup(sqlite_store, target)
    assert open(db, "rb").read()[:100] == before and backup.verify(sqlite_store)[1] == []
    assert backup.backup(sqlite_store, tmp_path / "b.zip")["users"] == 4


def test_the_link_to_the_readings_is_checked(store, people, computed_folder, bench_readings,
                                             monkeypatch):
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    other, _ = services.store_file(store, open(bench_readings[1], "rb"))
    with store.writing() as s:
        s.execute(text("UPDATE calibrations SET readings_sha256 = :v WHERE id = :i"),
                  {"v": other, "i": cal.id})
        s.commit()
    with pytest.raises(GonioError, match="computed from the readings .* not from the "
                                         "calibration's stored readings"):
        services.review(store, people["rev"], cal.id, accept=True)
    assert any("not from the calibration's stored readings" in p
               for p in backup.verify(store)[1])


def test_a_serial_in_another_case_is_the_registered_instrument(store, people):
    """Readings naming ``rlg-0001`` are of the registered RLG-0001 (case and spacing folded, as
    the laboratory file is compared): its gyro type and customer hold, never a second
    registration of one instrument."""
    from gonio.records.importer import registered_instrument

    from .test_records_services import setup_instrument

    inst, _ = setup_instrument(store, people)
    with store.session() as s:
        for meta in ({"serial": "rlg-0001", "manufacturer": "example gyro works",
                      "model": "RLG-GM-1"},
                     {"serial": " RLG-0001", "manufacturer": "Example  Gyro Works",
                      "model": "rlg-gm-1"}):
            assert registered_instrument(s, meta).id == inst.id, meta
        assert registered_instrument(s, {"serial": "RLG-0002", "manufacturer":
                                         "Example Gyro Works", "model": "RLG-GM-1"}) is None


def test_the_readings_operator_neither_reviews_nor_approves(store, people, computed_folder,
                                                            bench_readings, monkeypatch):
    """The person the readings name as their operator (``# operator: virtual bench``)
    counts as the calibration's creator, matched by full name (case and spacing folded):
    they neither review it nor approve its first issue; two others do."""
    from .conftest import PASSWORD

    measured = services.create_user(store, None, "vb", PASSWORD, "reviewer",
                                    full_name="Virtual  BENCH")
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    with store.session() as s:
        assert services.readings_operator(s, services.calibration(store, cal.id)) == \
            "virtual bench"
    with pytest.raises(GonioError, match=r"as their operator: the person who measured "
                                         r"may not review") as got:
        services.review(store, measured, cal.id, accept=True)
    assert got.value.key == "role"
    services.review(store, people["rev"], cal.id, accept=True)
    with pytest.raises(GonioError, match="may not approve"):
        services.approve(store, measured, cal.id)
    assert services.approve(store, people["rev2"], cal.id).status == "issuing"


def test_a_renamed_operator_still_does_not_review(store, people, computed_folder,
                                                  bench_readings, monkeypatch):
    """Renaming the operator (a new full name, by an admin) does not make the person the
    readings name a second person: every full name the trail recorded for them counts."""
    from .conftest import PASSWORD

    measured = services.create_user(store, None, "vb", PASSWORD, "reviewer",
                                    full_name="Virtual Bench")
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.update_user(store, people["admin"], "vb", full_name="Someone Else")
    measured = services.user(store, "vb")
    assert measured.full_name == "Someone Else"
    with pytest.raises(GonioError, match=r"as their operator: the person who measured "
                                         r"may not review"):
        services.review(store, measured, cal.id, accept=True)
    # a person never known by the operator's name reviews
    services.review(store, people["rev"], cal.id, accept=True)
    with store.session() as s:
        assert services.names_held(s, measured) == {"vb", "someone else", "virtual bench"}


def attached_and_approved(store, people, computed_folder, bench_readings, monkeypatch):
    """An issued calibration's amendment asked for, a level LV-3 (certificate LV-CERT-9,
    accuracy '0.1 arcsec') attached during it and the amendment approved (waiting for its
    issue): (the calibration, LV-3)."""
    import datetime as dt

    cal, std, first = issued_under(store, people, computed_folder, bench_readings, monkeypatch)
    services.amend(store, people["rev2"], first.id, "a level used was not named")
    lvl = services.add_standard(store, people["tech"], name="level", identifier="LV-3",
                                certificate="LV-CERT-9", accuracy="0.1 arcsec",
                                due_on=dt.date.today() + dt.timedelta(days=300))
    services.attach_conditions(store, people["tech"], cal.id, standard_ids=[std.id, lvl.id])
    assert services.approve(store, people["rev"], cal.id).status == "issuing"
    return cal, lvl


def test_a_standard_attached_during_an_amendment_is_stated_as_approved(
        store, people, computed_folder, bench_readings, monkeypatch, tmp_path):
    """The standard attached during an amendment is stated as the register held it when the
    amendment was approved: an edit through the register between the approval and the
    issue reaches nothing (before: the issued amendment printed a certificate number and
    accuracy nobody approved). While it waits for its issue the records verify and a
    backup is written (before: verify named the attached standard as a change from the
    draft and the backup refused)."""
    cal, lvl = attached_and_approved(store, people, computed_folder, bench_readings,
                                     monkeypatch)
    services.update_standard(store, people["tech"], lvl.id, certificate="FORGED-999",
                             accuracy="0.00001 arcsec")
    assert backup.verify(store)[1] == []
    assert backup.backup(store, tmp_path / "waiting.zip")["calibrations"] == 1
    page = services.file_bytes(store, run_issue(store, monkeypatch).html_sha256).decode()
    assert "LV-CERT-9" in page and "0.1 arcsec" in page
    assert "FORGED-999" not in page and "0.00001 arcsec" not in page
    assert backup.verify(store)[1] == []


def test_a_standard_edited_in_the_database_after_an_amendments_approval_is_not_issued(
        store, people, computed_folder, bench_readings, monkeypatch):
    """The register entry of a standard an approved amendment states, changed in the
    database (no audit event): verify names it and the issue refuses, nothing issued
    (before: the forged certificate number was printed and verify found nothing)."""
    from .test_records_issue import no_pipeline
    from .test_records_sealed import certificates

    cal, lvl = attached_and_approved(store, people, computed_folder, bench_readings,
                                     monkeypatch)
    issued = len(certificates(store))
    with store.writing() as s:
        s.execute(text("UPDATE standards SET certificate = 'FORGED-999' WHERE id = :i"),
                  {"i": lvl.id})
        s.commit()
    assert ("standard LV-3: its certificate 'FORGED-999' is not the 'LV-CERT-9' its audit "
            "trail's latest event recorded: the row was changed outside gonio"
            in backup.verify(store)[1])
    monkeypatch.setattr(worker, "calibrate_folder", no_pipeline)
    services.claim_next(store)
    assert not worker.execute(store, cal.id)
    now = services.calibration(store, cal.id)
    assert now.status == "failed" and "standard LV-3: its certificate" in now.error
    assert "\n" not in now.error and len(certificates(store)) == issued


REGISTER_EDITS = {        # (table, column, value): a row edited in the database, no event
    "instrument": ("instruments", "serial", "FAKE-9999"),
    "customer": ("customers", "name", "Forged Customer Ltd"),
}


@pytest.mark.parametrize("what", sorted(REGISTER_EDITS))
def test_an_instrument_or_customer_edited_in_the_database_after_an_amendments_approval(
        what, store, people, computed_folder, bench_readings, monkeypatch):
    """The instrument's serial or the customer's name an approved amendment states, changed
    in the database after its approval (no audit event): verify names it, and the issue
    refuses in one line, nothing issued (before: an amendment keeps no copy of them, so the
    edit was printed on the issued certificate and verify found nothing)."""
    from .test_records_issue import no_pipeline
    from .test_records_sealed import certificates

    cal, std, first = issued_under(store, people, computed_folder, bench_readings, monkeypatch)
    services.amend(store, people["rev2"], first.id, "customer's address misprinted")
    assert services.approve(store, people["rev"], cal.id).status == "issuing"
    assert backup.verify(store)[1] == []
    table, column, value = REGISTER_EDITS[what]
    was = {"instrument": "RLG-0001", "customer": "Example Navigation Co."}[what]
    issued = len(certificates(store))
    with store.writing() as s:
        s.execute(text(f"UPDATE {table} SET {column} = :v"), {"v": value})
        s.commit()
    line = (f"{what} {value}: its {column} {value!r} is not the {was!r} its audit trail's "
            "latest event recorded: the row was changed outside gonio")
    assert line in backup.verify(store)[1]
    monkeypatch.setattr(worker, "calibrate_folder", no_pipeline)
    services.claim_next(store)
    assert not worker.execute(store, cal.id)
    now = services.calibration(store, cal.id)
    assert now.status == "failed" and line in now.error, now.error
    assert "\n" not in now.error and len(certificates(store)) == issued


def test_register_edits_through_the_records_verify(store, people, computed_folder,
                                                    bench_readings, monkeypatch, tmp_path):
    """The instrument's serial and the customer's name corrected through the records before
    the amendment is asked for, the instrument retired and brought back, the customer
    retired and brought back: the records verify (a backup is written) while the amendment
    waits and once it is issued, and the amendment states the corrections."""
    cal, std, first = issued_under(store, people, computed_folder, bench_readings, monkeypatch)
    tech = people["tech"]
    inst = services.update_instrument(store, tech, cal.instrument_id, serial="RLG-0001B")
    services.update_customer(store, tech, inst.customer_id, name="Example Navigation Ltd")
    for retire in (True, False):
        services.update_instrument(store, tech, cal.instrument_id, retire=retire)
        services.update_customer(store, tech, inst.customer_id, retire=retire)
        assert backup.verify(store)[1] == []
    services.amend(store, people["rev2"], first.id, "serial and name corrected")
    services.approve(store, people["rev"], cal.id)
    assert backup.verify(store)[1] == []
    assert backup.backup(store, tmp_path / "waiting.zip")["calibrations"] == 1
    page = services.file_bytes(store, run_issue(store, monkeypatch).html_sha256).decode()
    assert "RLG-0001B" in page and "Example Navigation Ltd" in page
    assert backup.verify(store)[1] == []
