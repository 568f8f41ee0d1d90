"""The issue renders the stored result that was reviewed and sealed, computing nothing again:
the certificate (HTML, PDF) and the DCC carry the seal, the number of people required and
who did which step; an amendment states the certificate it replaces and why, names its own
approver and leaves the original's approval as it was; a draft is watermarked DRAFT on every
page, an issued certificate never."""

from __future__ import annotations

import json
import re
import subprocess

import pytest
from lxml import etree

from gonio.errors import GonioError
from gonio.records import services, worker
from gonio.records.compute import render_folder, write_lab_toml

from .conftest import PASSWORD
from .test_records_sealed import certificates, computed
from .test_web_security import app, login  # noqa: F401  (the app fixture)

NS = {"dcc": "https://ptb.de/dcc"}


def pdf_pages(data: bytes, tmp_path) -> list[str]:
    pdf = tmp_path / "c.pdf"
    pdf.write_bytes(data)
    text = subprocess.run(["pdftotext", "-layout", str(pdf), "-"], capture_output=True,
                          text=True, check=True).stdout
    return [p for p in text.split("\f") if p.strip()]


def kv_row(page: str, label: str) -> str:
    """The value of a key–value row of a certificate's HTML."""
    return re.search(rf"<tr><td>{re.escape(label)}</td><td>(.*?)</td></tr>", page).group(1)


def no_pipeline(*args, **kwargs):
    raise AssertionError("the issue ran the calibration pipeline")


def run_issue(store, monkeypatch):
    """Issue what is approved with the pipeline taken away: the issue must not compute."""
    monkeypatch.setattr(worker, "calibrate_folder", no_pipeline)
    cal = services.claim_next(store)
    assert worker.execute(store, cal.id), services.calibration(store, cal.id).error
    return certificates(store)[-1]


def approved(store, people, computed_folder, bench_readings, monkeypatch):
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev2"], cal.id)
    return cal


def measurement_results(dcc: bytes) -> bytes:
    """The DCC's results (the influence conditions aside: they are the laboratory's)."""
    return etree.tostring(etree.fromstring(dcc).find(".//dcc:measurementResult/dcc:results",
                                                     NS))


def validate(dcc_schema, data: bytes, tmp_path):
    path = tmp_path / "c.dcc.xml"
    path.write_bytes(data)
    dcc_schema.validate(str(path))


def test_issue_renders_the_sealed_result_without_computing(store, people, computed_folder,
                                                           bench_readings, monkeypatch,
                                                           dcc_schema, tmp_path):
    cal = approved(store, people, computed_folder, bench_readings, monkeypatch)
    signed = services.seal(store, cal.id)
    cert = run_issue(store, monkeypatch)
    assert cert.results_sha256 == cal.results_sha256 and cert.seal_sha256 == signed
    dcc = services.file_bytes(store, cert.dcc_sha256)
    validate(dcc_schema, dcc, tmp_path)
    # the results the pipeline wrote at the draft (the real run of the session fixture),
    # element for element: the stored result rendered, not another computation
    assert measurement_results(dcc) == measurement_results(
        (computed_folder / "certificate.dcc.xml").read_bytes())
    root = etree.fromstring(dcc)
    assert root.findtext(".//dcc:coreData/dcc:uniqueIdentifier", namespaces=NS) == cert.number
    seal_text = root.find(".//dcc:statement[@id='record-seal']", NS)
    assert signed in "".join(seal_text.itertext())
    people_text = "".join(root.find(".//dcc:statement[@id='record-people']", NS).itertext())
    assert "3: calibration, review and approval each by a different person" in people_text
    roles = {"".join(rp.find("dcc:person", NS).itertext()).strip(): rp.findtext("dcc:role", "",
                                                                               NS)
             for rp in root.iterfind(".//dcc:respPerson", NS)}
    assert roles == {"tech": "calibrated by", "rev": "checked by", "rev2": "approved by"}
    assert root.find(".//dcc:statement[@id='record-draft']", NS) is None
    page = services.file_bytes(store, cert.html_sha256).decode("utf-8")
    assert (kv_row(page, "Calibrated by"), kv_row(page, "Checked by"),
            kv_row(page, "Approved by")) == ("tech", "rev", "rev2")
    assert kv_row(page, "Seal of the result (SHA-256)").startswith(signed[:16] + "…")
    assert signed[:17] not in page                      # the short form only
    assert kv_row(page, "People required").startswith("3: ")
    assert "draft-watermark" not in page and "DRAFT" not in page
    pages = pdf_pages(services.file_bytes(store, cert.pdf_sha256), tmp_path)
    assert not any("DRAFT" in p for p in pages)
    assert any(signed[:16] + "…" in p for p in pages)


def test_results_file_changed_after_approval_refused_at_issue(store, people, computed_folder,
                                                              bench_readings, monkeypatch):
    from gonio.records import blobs

    cal = approved(store, people, computed_folder, bench_readings, monkeypatch)
    path = blobs.blob_path(store.blob_root, cal.results_sha256)
    path.chmod(0o644)
    path.write_bytes(path.read_bytes().replace(b"scale_factor", b"scale_fact0r", 1))
    monkeypatch.setattr(worker, "calibrate_folder", no_pipeline)
    services.claim_next(store)
    assert not worker.execute(store, cal.id)
    cal = services.calibration(store, cal.id)
    assert cal.status == "failed" and "results.json is missing or does not match" in cal.error
    assert certificates(store) == []


def test_two_people_stated_where_the_laboratory_needs_two(store, people, computed_folder,
                                                          bench_readings, monkeypatch):
    services.set_settings(store, people["admin"], min_people="2")
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev"], cal.id)
    cert = run_issue(store, monkeypatch)
    page = services.file_bytes(store, cert.html_sha256).decode("utf-8")
    assert kv_row(page, "People required") == ("2: the calibration by one person, its review "
                                               "and approval by another")
    assert (kv_row(page, "Checked by"), kv_row(page, "Approved by")) == ("rev", "rev")


def test_two_people_amendment_approved_by_another_than_its_asker(store, people,
                                                                  computed_folder,
                                                                  bench_readings, monkeypatch):
    """With ``min_people = 2`` the reviewer may approve what they reviewed, but an amendment
    is still approved by another person than the one who asked for it (before: the asker
    asked, attached and approved alone)."""
    services.set_settings(store, people["admin"], min_people="2")
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev"], cal.id)
    first = run_issue(store, monkeypatch)
    services.amend(store, people["rev"], first.id, "typo in the environment")
    services.attach_conditions(store, people["rev"], cal.id, temperature_c=20.6,
                               humidity_pct=60)
    assert services.calibration(store, cal.id).status == "amending"
    with pytest.raises(GonioError, match="asked for the amendment may not approve"):
        services.approve(store, people["rev"], cal.id)
    assert services.calibration(store, cal.id).status == "amending"
    services.approve(store, people["rev2"], cal.id)
    second = run_issue(store, monkeypatch)
    assert second.replaces_id == first.id and second.issued_by_id == people["rev2"].id


def test_two_person_laboratory_amends_end_to_end(store, people, computed_folder,
                                                 bench_readings, monkeypatch):
    """A laboratory of two (``min_people = 2``: T created, R reviewed and approved): R asks
    for an amendment and makes the change, T — who neither asked nor changed — approves it,
    and it is issued (before: the creator was refused and nobody was left to approve)."""
    services.set_settings(store, people["admin"], min_people="2")
    t = services.update_user(store, None, "tech", roles="technician reviewer")
    r = people["rev"]
    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    with pytest.raises(GonioError, match="created a calibration may not review"):
        services.review(store, t, cal.id, accept=True)
    services.review(store, r, cal.id, accept=True)
    with pytest.raises(GonioError, match="created a calibration may not approve"):
        services.approve(store, t, cal.id)                 # its first issue: never the creator
    services.approve(store, r, cal.id)
    first = run_issue(store, monkeypatch)
    with pytest.raises(GonioError, match="created a calibration may not amend"):
        services.amend(store, t, first.id, "typo")
    services.amend(store, r, first.id, "environment corrected")                  # ask
    services.attach_conditions(store, r, cal.id, temperature_c=20.6, humidity_pct=60)  # change
    with pytest.raises(GonioError, match="asked for the amendment may not approve"):
        services.approve(store, r, cal.id)
    assert services.approve(store, t, cal.id).status == "issuing"               # approve
    second = run_issue(store, monkeypatch)                                      # issue
    assert (second.replaces_id, second.issued_by_id, second.reviewed_by_id,
            second.min_people) == (first.id, t.id, r.id, 2)
    assert services.calibration(store, cal.id).temperature_c == 20.6
    page = services.file_bytes(store, second.html_sha256).decode("utf-8")
    assert (kv_row(page, "Checked by"), kv_row(page, "Approved by")) == ("rev", "tech")
    assert kv_row(page, "People required") == (
        "2: the calibration by one person, its review by another; this amendment asked for "
        "and made by one person, approved by another")
    root = etree.fromstring(services.file_bytes(store, second.dcc_sha256))
    assert "this amendment asked for and made by one person" in "".join(
        root.find(".//dcc:statement[@id='record-people']", NS).itertext())


def test_one_person_alone_cannot_amend_and_approve(store, people, computed_folder,
                                                   bench_readings, monkeypatch):
    """Whoever changed an amendment does not approve it, the creator included (one changes,
    another approves); with ``min_people = 3`` the creator never approves an amendment."""
    t = services.update_user(store, None, "tech", roles="technician reviewer")
    cal = approved(store, people, computed_folder, bench_readings, monkeypatch)
    first = run_issue(store, monkeypatch)
    services.amend(store, people["rev"], first.id, "environment corrected")
    with pytest.raises(GonioError, match="created a calibration may not approve"):
        services.approve(store, t, cal.id)               # three people: never the creator
    services.set_settings(store, people["admin"], min_people="2")
    services.attach_conditions(store, t, cal.id, temperature_c=20.6, humidity_pct=60)
    with pytest.raises(GonioError, match="changed the calibration during its amendment"):
        services.approve(store, t, cal.id)               # the creator changed it: not T
    services.attach_conditions(store, people["rev2"], cal.id, temperature_c=20.7,
                               humidity_pct=60)
    with pytest.raises(GonioError, match="changed the calibration during its amendment"):
        services.approve(store, people["rev2"], cal.id)
    assert services.calibration(store, cal.id).status == "amending"
    services.approve(store, people["admin"], cal.id)
    second = run_issue(store, monkeypatch)
    assert second.replaces_id == first.id and second.issued_by_id == people["admin"].id
    # a later amendment looks only at its own changes: rev2 changed the first one, not this
    services.amend(store, people["rev"], second.id, "address")
    assert services.approve(store, people["rev2"], cal.id).status == "issuing"


def test_amendment_states_what_it_replaces_and_why(store, people, computed_folder,
                                                   bench_readings, monkeypatch, dcc_schema,
                                                   tmp_path):
    approved(store, people, computed_folder, bench_readings, monkeypatch)
    first = run_issue(store, monkeypatch)
    first_html = services.file_bytes(store, first.html_sha256)
    reason = "customer's address corrected\n(second line)"
    cust = services.calibration(store, first.calibration_id).instrument.customer
    services.update_customer(store, people["tech"], cust.id, address="3 Sample Street\nTown")
    services.amend(store, people["admin"], first.id, reason)
    services.approve(store, people["rev"], first.calibration_id)
    second = run_issue(store, monkeypatch)
    assert second.replaces_id == first.id and second.number != first.number
    # the original keeps its own approval, its files untouched
    assert services.file_bytes(store, first.html_sha256) == first_html
    assert kv_row(first_html.decode("utf-8"), "Approved by") == "rev2"
    page = services.file_bytes(store, second.html_sha256).decode("utf-8")
    assert (kv_row(page, "Amendment asked for by"), kv_row(page, "Approved by")) == (
        "admin", "rev")
    # what the amendment corrects reaches it; the original keeps what it said
    assert "3 Sample Street" in kv_row(page, "Customer address")
    assert kv_row(first_html.decode("utf-8"), "Customer address") == "2 Sample Street"
    notice = (f"This certificate amends and replaces certificate {first.number}, which is "
              "withdrawn. Reason for the amendment: customer&#x27;s address corrected<br>"
              "(second line)")       # its line break kept (escaped text, then <br>)
    assert notice in page, re.findall(r"<p class=\"notice\">.*?</p>", page, re.S)
    pages = pdf_pages(services.file_bytes(store, second.pdf_sha256), tmp_path)
    assert f"replaces certificate {first.number}" in pages[0]
    dcc = services.file_bytes(store, second.dcc_sha256)
    validate(dcc_schema, dcc, tmp_path)
    root = etree.fromstring(dcc)
    assert root.findtext(".//dcc:reportAmendedSubstituted/dcc:replacedUniqueIdentifier",
                         namespaces=NS) == first.number
    assert root.findtext(".//dcc:reportAmendedSubstituted/dcc:typeOfChange",
                         namespaces=NS) == "amended"
    said = "".join(root.find(".//dcc:statement[@id='record-amendment']", NS).itertext())
    assert "customer's address corrected" in said and first.number in said
    roles = [rp.findtext("dcc:role", "", NS) for rp in root.iterfind(".//dcc:respPerson", NS)]
    assert roles == ["calibrated by", "checked by", "amendment asked for by", "approved by"]


def test_draft_watermarked_on_every_page(sqlite_store, computed_folder, bench_readings,
                                         monkeypatch, dcc_schema, tmp_path):
    """The draft's details say so; its certificate (HTML, every PDF page) and DCC say DRAFT,
    in English and in Chinese."""
    from .conftest import make_people

    people = make_people(sqlite_store)
    cal = computed(sqlite_store, people, computed_folder, bench_readings, monkeypatch)
    details = services.lab_details(sqlite_store, cal.id, final=False)
    assert details["record"] == {"status": "draft"}
    lab = write_lab_toml(details, tmp_path / "lab.toml")
    stored = services.file_bytes(sqlite_store, cal.results_sha256)
    for lang, mark, title, not_title in (
            ("en", "DRAFT", "Draft — not a calibration certificate", "Calibration Certificate"),
            ("zh", "草稿", "草稿 — 非校准证书", "<h1>校准证书")):
        out = tmp_path / lang
        render_folder(stored, out, spec_key=cal.spec_key, lab=lab, lang=lang)
        page = (out / "certificate.html").read_text(encoding="utf-8")
        assert re.search(rf'<div class="watermark draft" id="draft-watermark"[^>]*>{mark}</div>',
                         page)
        # the draft is not titled as a certificate (page title, heading, PDF title)
        assert f"<h1>{title}</h1>" in page and f"<title>{title} DRAFT-{cal.id}</title>" in page
        assert not_title not in page
        pages = pdf_pages((out / "certificate.pdf").read_bytes(), tmp_path)
        # a rotated mark: pdftotext gives its characters apart (and 稿 is on no other page)
        assert len(pages) > 3 and all(all(ch in p for ch in mark) for p in pages), lang
        assert title in pages[0] and "Calibration Certificate" not in pages[0], lang
    dcc = (tmp_path / "en" / "certificate.dcc.xml").read_bytes()
    validate(dcc_schema, dcc, tmp_path)
    said = etree.fromstring(dcc).find(".//dcc:statement[@id='record-draft']", NS)
    assert said.findtext("dcc:name/dcc:content", None, NS) == \
        "Draft — not a calibration certificate"


@pytest.mark.parametrize("lang", ["en", "zh"])
def test_multi_line_addresses_keep_their_lines(sqlite_store, computed_folder, bench_readings,
                                               monkeypatch, tmp_path, lang):
    """The laboratory's and the customer's addresses of several lines (as the records keep
    them) are printed with their line breaks on the optical certificate: the HTML (escaped,
    each line break a <br>), the PDF (line under line), the DCC (its text as entered)."""
    from .conftest import make_people

    people = make_people(sqlite_store)
    cal = computed(sqlite_store, people, computed_folder, bench_readings, monkeypatch)
    services.set_settings(sqlite_store, people["admin"], lab_address="1 Example Road\r\n"
                                                                     "Beijing <100000>")
    cust = services.calibration(sqlite_store, cal.id).instrument.customer
    services.update_customer(sqlite_store, people["tech"], cust.id,
                             address="2 Sample Street\nXi'an 710000")
    details = services.lab_details(sqlite_store, cal.id, final=False)
    out = tmp_path / lang
    render_folder(services.file_bytes(sqlite_store, cal.results_sha256), out, lang=lang,
                  spec_key=cal.spec_key, lab=write_lab_toml(details, tmp_path / "lab.toml"))
    page = (out / "certificate.html").read_text(encoding="utf-8")
    label = {"en": ("Address", "Customer address"), "zh": ("地址", "委托方地址")}[lang]
    assert kv_row(page, label[0]) == "1 Example Road<br>Beijing &lt;100000&gt;"
    assert kv_row(page, label[1]) == "2 Sample Street<br>Xi&#x27;an 710000"
    # the lines of page 1, without the rotated watermark's letters (one or two a line)
    lines = [ln.strip() for ln in pdf_pages((out / "certificate.pdf").read_bytes(),
                                            tmp_path)[0].splitlines() if len(ln.strip()) > 2]
    for first, second in (("1 Example Road", "Beijing <100000>"),
                          ("2 Sample Street", "Xi'an 710000")):
        at = next(i for i, ln in enumerate(lines) if ln.endswith(first))
        assert lines[at + 1] == second, lines[at - 1:at + 3]
    if lang == "en":
        root = etree.fromstring((out / "certificate.dcc.xml").read_bytes())
        further = [" ".join(e.itertext()).strip() for e in root.iterfind(
            ".//dcc:location/dcc:further", NS)]
        assert "1 Example Road\nBeijing <100000>" in further, further


def test_multi_line_amendment_reason_keeps_its_lines(sqlite_store, computed_folder,
                                                     bench_readings, monkeypatch, tmp_path):
    """An amendment's reason of several lines is printed with its line breaks: the HTML
    (escaped, each line break a <br>), every PDF line, the DCC's declaration."""
    from .conftest import make_people

    people = make_people(sqlite_store)
    cal = computed(sqlite_store, people, computed_folder, bench_readings, monkeypatch)
    details = services.lab_details(sqlite_store, cal.id, final=False)
    details["record"] = {"status": "issued", "seal_sha256": services.seal(sqlite_store, cal.id),
                         "min_people": 3, "replaces": "GC-2026-0001",
                         "amendment_reason": "customer's address corrected\n"
                                             "serial <RLG-0001> confirmed",
                         "amendment_asked_by": "REV2"}
    details["environment"] = {"temperature_c": 20.0, "humidity_pct": 44.0, "source": "readings"}
    out = tmp_path / "en"
    render_folder(services.file_bytes(sqlite_store, cal.results_sha256), out,
                  spec_key=cal.spec_key, lab=write_lab_toml(details, tmp_path / "lab.toml"))
    page = (out / "certificate.html").read_text(encoding="utf-8")
    assert ("Reason for the amendment: customer&#x27;s address corrected<br>"
            "serial &lt;RLG-0001&gt; confirmed</p>") in page
    first = pdf_pages((out / "certificate.pdf").read_bytes(), tmp_path)[0]
    lines = [ln.strip() for ln in first.splitlines()]
    at = next(i for i, ln in enumerate(lines) if ln.endswith("customer's address corrected"))
    assert lines[at + 1] == "serial <RLG-0001> confirmed"
    root = etree.fromstring((out / "certificate.dcc.xml").read_bytes())
    said = "".join(root.find(".//dcc:statement[@id='record-amendment']/dcc:declaration",
                            NS).itertext())
    assert said.strip().endswith("customer's address corrected\nserial <RLG-0001> confirmed")
    # an environment taken from the readings is stated so, on the page and in the DCC
    # (the laboratory file written from the records says temperature_c = 20.0: its digits)
    assert kv_row(page, "Temperature") == "20.0 °C (taken from the readings&#x27; metadata)"
    names = [n.strip() for n in root.xpath(".//dcc:influenceCondition/dcc:name/dcc:content/"
                                           "text()", namespaces=NS)]
    assert names[:2] == ["temperature (taken from the readings' metadata)",
                         "relative humidity (taken from the readings' metadata)"]


def test_issued_record_in_chinese(sqlite_store, computed_folder, bench_readings, monkeypatch,
                                  tmp_path):
    """The seal, the people required, the amendment and its reason on the Chinese page."""
    from .conftest import make_people

    people = make_people(sqlite_store)
    cal = computed(sqlite_store, people, computed_folder, bench_readings, monkeypatch)
    details = services.lab_details(sqlite_store, cal.id, final=False)
    seal = services.seal(sqlite_store, cal.id)
    details["record"] = {"status": "issued", "seal_sha256": seal, "min_people": 3,
                         "replaces": "GC-2026-0001", "amendment_reason": "地址更正",
                         "amendment_asked_by": "王五"}
    lab = write_lab_toml(details, tmp_path / "lab.toml")
    out = tmp_path / "zh"
    render_folder(services.file_bytes(sqlite_store, cal.results_sha256), out,
                  spec_key=cal.spec_key, lab=lab, lang="zh")
    page = (out / "certificate.html").read_text(encoding="utf-8")
    assert kv_row(page, "结果封印（SHA-256）").startswith(seal[:16] + "…（")
    assert kv_row(page, "所需人员") == "3 人：校准、核验、批准各由不同人员完成"
    assert kv_row(page, "修订申请人") == "王五"
    assert "本证书修订并取代证书 GC-2026-0001，原证书作废。修订原因：地址更正" in page
    assert "草稿" not in page
    pages = pdf_pages((out / "certificate.pdf").read_bytes(), tmp_path)
    assert "GC-2026-0001" in pages[0] and not any("稿" in p for p in pages)


def test_record_table_checked_like_the_rest_of_the_file(tmp_path):
    from gonio.formats.lab import load_lab

    base = ('[laboratory]\nname = "L"\naddress = "A"\n[certificate]\nnumber = "N"\n'
            '[customer]\nname = "C"\n[signatory]\napproved_by = "Q"\n')
    for bad, key in (('[record]\nstatus = "final"\n', "record.status"),
                     ('[record]\nseal_sha256 = "abc"\n', "record.seal_sha256"),
                     ('[record]\nmin_people = 1\n', "record.min_people")):
        (tmp_path / "lab.toml").write_text(base + bad, encoding="utf-8")
        with pytest.raises(GonioError, match=re.escape(key)):
            load_lab(tmp_path / "lab.toml")
    (tmp_path / "lab.toml").write_text(base, encoding="utf-8")
    assert load_lab(tmp_path / "lab.toml")["record"] is None


def test_two_concurrent_issues_give_one_certificate(store, people, computed_folder,
                                                    bench_readings, monkeypatch, tmp_path):
    """Two approvals of one calibration at once reserve one number; two workers storing its
    issue at once (two hosts, a retry raced) write one certificate: the row is locked
    (SELECT … FOR UPDATE on PostgreSQL) and the second sees the first one's state; the
    loser's failure does not undo the issue."""
    import threading

    from sqlalchemy import select

    from gonio.records.models import CertificateCounter

    cal = computed(store, people, computed_folder, bench_readings, monkeypatch)
    services.review(store, people["rev"], cal.id, accept=True)

    def race(calls):
        gate, out = threading.Barrier(len(calls)), []

        def run(call):
            gate.wait(timeout=60)
            try:
                out.append(call())
            except GonioError as exc:
                out.append(exc)
        threads = [threading.Thread(target=run, args=(c,)) for c in calls]
        for t in threads:
            t.start()
        for t in threads:
            t.join(120)
        return out

    got = race([lambda: services.approve(store, people["rev2"], cal.id),
                lambda: services.approve(store, people["admin"], cal.id)])
    refused = [g for g in got if isinstance(g, GonioError)]
    assert len(refused) == 1 and "that is issuing" in str(refused[0])
    number = services.calibration(store, cal.id).pending_number
    out = tmp_path / "out"
    render_folder(services.sealed_result(store, cal.id), out, spec_key=cal.spec_key,
                  lab=write_lab_toml(services.lab_details(store, cal.id, final=True),
                                     tmp_path / "lab.toml"))
    got = race([lambda: services.store_issue(store, cal.id, out)] * 2)
    refused = [g for g in got if isinstance(g, GonioError)]
    assert len(refused) == 1 and "nothing issued twice" in str(refused[0])
    services.fail(store, cal.id, str(refused[0]))        # the losing worker's ending
    assert [c.number for c in certificates(store)] == [number]
    assert services.calibration(store, cal.id).status == "issued"
    with store.session() as s:
        year = int(number.split("-")[1])
        assert s.scalar(select(CertificateCounter.last).where(
            CertificateCounter.year == year)) == 1


def test_place_and_receipt_on_the_certificate_dcc_and_issued_page(
        app, sqlite_store, computed_folder, bench_readings, monkeypatch, dcc_schema,
        tmp_path):  # noqa: F811
    """The place and receipt date entered reach the certificate and the DCC (the place as
    text, since dcc:performanceLocation is only a category), and the calibration page of an
    issued calibration no longer calls its files the draft awaiting approval."""
    from html import unescape

    from sqlalchemy import text

    people = {n: services.user(sqlite_store, n) for n in ("tech", "rev")}
    people["rev2"] = services.create_user(sqlite_store, None, "rev2", PASSWORD, "reviewer")
    cal = computed(sqlite_store, people, computed_folder, bench_readings, monkeypatch)
    place, received = "Room 2, customer's site at Wuxi", cal.performed_on
    with sqlite_store.writing() as s:
        s.execute(text("UPDATE calibrations SET place = :p, received_on = :r, "
                       "location = 'customer' WHERE id = :c"),
                  {"p": place, "r": received, "c": cal.id})
        s.commit()
    # entered around the records: the draft rendered again shows them (else the approval
    # refuses what the reviewed draft does not state)
    services.attach_conditions(sqlite_store, people["tech"], cal.id, temperature_c=20.1,
                               humidity_pct=45)
    assert worker.execute(sqlite_store, services.claim_next(sqlite_store).id)
    tech = login(app, "tech")
    page = tech.get(f"/calibrations/{cal.id}").text
    assert "until the calibration is approved" in page
    assert "Place</dt><dd>Room 2, customer&#39;s site at Wuxi (the customer&#39;s site)<" in page
    # its category, for the DCC's dcc:performanceLocation (tests/test_dcc.py: the DCC of
    # measured readings says it; these are the virtual bench's, whose DCC says "other")
    assert services.lab_details(sqlite_store, cal.id, final=False)["certificate"][
        "location"] == "customer"
    assert f"Received</dt><dd>{received.isoformat()}<" in page
    services.review(sqlite_store, people["rev"], cal.id, accept=True)
    services.approve(sqlite_store, people["rev2"], cal.id)
    cert = run_issue(sqlite_store, monkeypatch)
    html = services.file_bytes(sqlite_store, cert.html_sha256).decode("utf-8")
    assert unescape(kv_row(html, "Place of calibration")) == place
    assert kv_row(html, "Date of receipt") == received.isoformat()
    dcc = services.file_bytes(sqlite_store, cert.dcc_sha256)
    validate(dcc_schema, dcc, tmp_path)
    root = etree.fromstring(dcc)
    assert root.findtext(".//dcc:coreData/dcc:receiptDate", namespaces=NS) == received.isoformat()
    st = root.find(".//dcc:statement[@id='place']", NS)
    assert "".join(st.find("dcc:declaration", NS).itertext()).strip() == place
    page = tech.get(f"/calibrations/{cal.id}").text
    assert "until the calibration is approved" not in page
    assert "the issued certificate is listed below" in page
    assert f'href="/certificates/{cert.id}">{cert.number}<' in page
