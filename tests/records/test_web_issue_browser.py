"""Review → approve → issue of a stored result in Chromium through a real ``gonio serve``: the
draft certificate is watermarked DRAFT; a result row changed in the database after the review
is refused at approval with the page's one line; the issued certificate (rendered from the
sealed result) carries the seal and the people, without the watermark; an amendment asked for
by one reviewer and approved by another is a new certificate that names the one it
replaces and why, the original keeping its approver."""

from __future__ import annotations

import re
import sqlite3

from lxml import etree

from .test_web_browser import (browser, live, log_in, log_out, register, upload,  # noqa: F401
                               wait_status)

NS = {"dcc": "https://ptb.de/dcc"}


def certificate_view(page, url: str) -> str:
    """A certificate's HTML (fetched with the page's session; an issued one downloads) as
    Chromium shows it: the text of its page."""
    got = page.request.get(url)
    assert got.ok, url
    page.set_content(got.text())
    return page.locator("body").inner_text()


def test_issue_of_the_sealed_result_and_its_amendment_in_chromium(live, browser,  # noqa: F811
                                                                  bench_readings, tmp_path):
    base, data = live
    page = browser.new_page(viewport={"width": 1280, "height": 900}, accept_downloads=True)
    log_in(page, base, "tech")
    cal_url = upload(page, base, register(page, base), bench_readings[0], "2025-11-20")
    wait_status(page, "computed")
    draft = certificate_view(page, cal_url + "/files/certificate.html")
    assert page.locator("#draft-watermark").is_visible() and "DRAFT FOR REVIEW" in draft
    page.goto(cal_url)
    log_out(page)

    log_in(page, base, "rev")
    page.goto(cal_url)
    seal = page.locator("#seal").inner_text()
    with page.expect_navigation():
        page.click("button[value=accept]")
    wait_status(page, "reviewed")
    log_out(page)

    # a result row changed in the database after the review
    cal_id = int(cal_url.rsplit("/", 1)[1])
    db = sqlite3.connect(data / "records.sqlite3")
    where = "WHERE key = 'scale_factor' AND calibration_id = ?"
    (value,) = db.execute(f"SELECT value FROM result_items {where}", (cal_id,)).fetchone()
    db.execute(f"UPDATE result_items SET value = ? {where}", (value * 1.5, cal_id))
    db.commit()
    log_in(page, base, "rev2")
    page.goto(cal_url)
    assert "scale_factor differs from the stored results.json" in page.content()
    with page.expect_navigation():
        page.click("button:has-text('Approve and issue')")
    assert "differs from the stored results.json" in page.locator("[role=alert]").inner_text()
    assert page.locator("h1 .status").inner_text() == "reviewed"
    db.execute(f"UPDATE result_items SET value = ? {where}", (value, cal_id))   # put back
    db.commit()
    db.close()
    page.goto(cal_url)
    with page.expect_navigation():
        page.click("button:has-text('Approve and issue')")
    wait_status(page, "issued")
    page.click("h2:has-text('Certificates') + p a")
    cert_url = page.url
    number = page.locator("h1").inner_text().split()[-1]
    issued = certificate_view(page, cert_url + "/certificate.html")
    assert page.locator("#draft-watermark").count() == 0 and "DRAFT" not in issued
    assert f"{seal[:16]}…" in issued and "3: calibration, review and approval" in issued
    for label, who in (("Calibrated by", "TECH Person"), ("Checked by", "REV Person"),
                       ("Approved by", "REV2 Person")):
        assert re.search(rf"{label}\s+{who}\n", issued), label
    page.goto(cert_url)
    with page.expect_download() as dl:
        page.click("text=certificate.dcc.xml (DCC)")
    dcc = tmp_path / "issued.dcc.xml"
    dl.value.save_as(dcc)
    said = "".join(etree.parse(str(dcc)).find(".//dcc:statement[@id='record-seal']",
                                              NS).itertext())
    assert seal in said
    log_out(page)

    # the amendment: asked for by rev2 (not the creator), approved by rev (not the asker)
    log_in(page, base, "rev2")
    page.goto(cert_url)
    page.fill("textarea[name=reason]", "customer's address corrected")
    with page.expect_navigation():
        page.click("text=Issue an amended certificate")
    log_out(page)
    log_in(page, base, "rev")
    page.goto(cal_url)
    with page.expect_navigation():
        page.click("button:has-text('Approve and issue')")
    wait_status(page, "issued")
    page.goto(cert_url)
    assert "Replaced by" in page.content()
    page.click("text=Replaced by >> a")
    new_url = page.url
    facts = page.locator("dl.facts").inner_text()
    assert "Replaces" in facts and number in facts
    amended = certificate_view(page, new_url + "/certificate.html")
    assert (f"This certificate amends and replaces certificate {number}, which is withdrawn. "
            "Reason for the amendment: customer's address corrected") in amended
    assert re.search(r"Amendment asked for by\s+REV2 Person\n", amended)
    assert re.search(r"Approved by\s+REV Person\n", amended)
    original = certificate_view(page, cert_url + "/certificate.html")
    assert re.search(r"Approved by\s+REV2 Person\n", original)
    assert "amends and replaces" not in original
