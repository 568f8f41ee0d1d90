"""A month of a laboratory in Chromium, run by its quality manager (Playwright, Debian's
Chromium, a real ``gonio serve`` with its worker processes), on SQLite and on PostgreSQL:
register and retire master data, calibrate, review, approve and issue, see and export what is
due, take last night's backup, amend with a reason of two lines, attach the standards and
environment a command-line import lacks (its review refused until then), deactivate a user,
verify the records and last night's backup in the browser, restore it there (confirmed
with the password; the records replaced, every session ended) and find last night's records.
Screenshots go to $GONIO_SCREENSHOTS/month-<database> (default /tmp/gonio-web-shots)."""

from __future__ import annotations

import csv
import datetime as dt
import io
import os
import shutil
import time

import pytest

from gonio.cli import main
from gonio.records import services
from gonio.records.db import open_store

from .conftest import new_pg_database
from .test_web_browser import (PASSWORD, PROTOCOL, SHOTS, Shots, browser,  # noqa: F401
                               log_in, log_out, upload, wait_status)


@pytest.fixture(params=["sqlite", "postgresql"])
def month(request, tmp_path, serve):
    """A running gonio serve on a new database (SQLite in the data folder, or PostgreSQL)
    with its people: qm (the quality manager: admin, technician, reviewer), tech, rev,
    rev2; yields (base URL, data folder, database URL or None, the database's kind)."""
    url = (new_pg_database(request.getfixturevalue("pg_server"))
           if request.param == "postgresql" else None)
    data = tmp_path / "data"
    st = open_store(url, data)
    for name, roles in (("qm", "admin technician reviewer"), ("tech", "technician"),
                        ("rev", "reviewer"), ("rev2", "reviewer")):
        services.create_user(st, None, name, PASSWORD, roles, name.upper() + " Person")
    services.set_settings(st, None, lab_name="Example Angle Laboratory",
                          lab_address="1 Example Road\nXi'an")
    st.close()
    proc, base = serve.start(data, database=url, memo=True)
    yield base, data, url, request.param
    serve.stop(proc)


def edit_row(page, row_text: str, **fields) -> None:
    """Open the edit form of the table row holding ``row_text``, set ``fields`` (name →
    value; ``state`` a select), save."""
    row = page.locator("tr", has_text=row_text).first
    row.locator("summary").click()
    for name, value in fields.items():
        if name == "state":
            row.locator("select[name=state]").select_option(value)
        else:
            row.locator(f"[name={name}]").fill(value)
    with page.expect_navigation():
        row.locator("button:has-text('Save')").click()


def act(page, base: str, who: str, cal_url: str, button: str, want: str) -> None:
    """``who`` logs in, presses ``button`` on the calibration's page and waits for ``want``."""
    log_in(page, base, who)
    page.goto(cal_url)
    with page.expect_navigation():
        page.click(button)
    wait_status(page, want)


def test_a_month_of_the_laboratory_in_chromium(month, browser, bench_readings,  # noqa: F811
                                               computed_folder, serve, tmp_path):
    base, data, url, kind = month
    shot = Shots(SHOTS / f"month-{kind}")
    today = dt.date.today()
    page = browser.new_page(viewport={"width": 1280, "height": 900}, accept_downloads=True)

    # master data: registered, one customer and one standard retired
    log_in(page, base, "qm")
    page.goto(base + "/customers")
    for name in ("Alpha Navigation Co.", "Closed Customer Ltd"):
        page.fill("form[action='/customers'] input[name=name]", name)
        page.fill("form[action='/customers'] textarea[name=address]", "2 Sample Street\nXi'an")
        with page.expect_navigation():
            page.click("text=Add customer")
    edit_row(page, "Closed Customer Ltd", state="retired")
    assert f"retired {today}" in page.locator("tr", has_text="Closed Customer Ltd").inner_text()
    page.goto(base + "/standards")
    for name, ident in (("Precision rotary table", "RT-07"), ("Old autocollimator", "AC-1")):
        new = page.locator("form[action='/standards']")
        new.locator("input[name=name]").fill(name)
        new.locator("input[name=identifier]").fill(ident)
        new.locator("input[name=due_on]").fill((today + dt.timedelta(days=200)).isoformat())
        with page.expect_navigation():
            page.click("text=Add standard")
    edit_row(page, "AC-1", state="retired")
    assert "(retired" in page.locator("tr", has_text="AC-1").inner_text()
    shot(page, "standards")
    page.goto(base + "/instruments")
    page.select_option("select[name=customer_id]", label="Alpha Navigation Co.")
    assert "Closed Customer Ltd" not in page.locator("select[name=customer_id]").inner_text()
    page.fill("input[name=kind]", "RLG goniometer")
    page.fill("input[name=manufacturer]", "gonio virtual bench")
    page.fill("input[name=model]", "RLG-GM-1")
    page.fill("input[name=serial]", "RLG-0001")
    page.select_option("select[name=spec_key]", "ogam-draft")
    with page.expect_navigation():
        page.click("button:has-text('Register')")
    inst_url = page.url
    page.click("summary:has-text('Edit, transfer or retire')")
    page.fill("input[name=interval_months]", "12")
    with page.expect_navigation():
        page.click("form[action$='/edit'] button:has-text('Save')")
    assert "12 months" in page.content()
    log_out(page)

    # a calibration made 350 days ago (12-month interval: due in 15 days), reviewed, issued
    log_in(page, base, "tech")
    day = today - dt.timedelta(days=350)
    page.goto(inst_url)
    page.click("text=New calibration")
    assert page.locator("label", has_text="AC-1").first.locator("input").is_disabled()
    # the second bench run: the first is imported below, and one measurement is never
    # calibrated twice
    cal_url = upload(page, base, inst_url, bench_readings[1], day.isoformat())
    wait_status(page, "computed")
    log_out(page)
    act(page, base, "rev", cal_url, "button[value=accept]", "reviewed")
    log_out(page)
    act(page, base, "qm", cal_url, "button:has-text('Approve and issue')", "issued")
    number = f"GC-{time.gmtime().tm_year}-0001"
    assert number in page.content()

    # what is due: the instrument, on the page and in the export
    page.goto(base + "/due")
    row = page.locator("tr", has_text="RLG-0001")
    due_on = (day.replace(year=day.year + 1)).isoformat()
    assert row.count() == 1 and due_on in row.inner_text()
    shot(page, "due")
    with page.expect_download() as dl:
        page.click("text=export CSV")
    got = list(csv.reader(io.StringIO(dl.value.path().read_text(encoding="utf-8"))))
    assert any("RLG-0001" in r and due_on in r for r in got[1:]), got

    # last night's backup (the page's download; a nightly job runs gonio db backup)
    page.goto(base + "/backup")
    with page.expect_download() as dl:
        page.click("text=Download a backup now")
    nightly = tmp_path / "nightly.zip"
    dl.value.save_as(nightly)
    log_out(page)

    # an amendment, asked for by rev2 with a reason of two lines, approved by rev
    log_in(page, base, "rev2")
    page.goto(cal_url)
    page.click(f"text={number}")
    page.fill("textarea[name=reason]", "customer's address corrected\nserial confirmed")
    with page.expect_navigation():
        page.click("text=Issue an amended certificate")
    log_out(page)
    log_in(page, base, "rev")
    page.goto(cal_url)
    assert "customer's address corrected\nserial confirmed" in page.locator(
        "p.pre").inner_text()
    log_out(page)
    act(page, base, "rev", cal_url, "button:has-text('Approve and issue')", "issued")
    amended = f"GC-{time.gmtime().tm_year}-0002"
    page.click(f"text={amended}")
    assert number in page.locator("dd.pre").inner_text()
    html = page.request.get(page.url + "/certificate.html").text()
    assert "Reason for the amendment: customer&#x27;s address corrected<br>serial confirmed" \
        in html
    shot(page, "amended-certificate")
    log_out(page)

    # command-line work put in without standards nor environment (gonio db import): its
    # review is refused, naming what is missing, until they are attached on its page
    folder = tmp_path / "run"
    shutil.copytree(computed_folder, folder)
    shutil.copy(bench_readings[0], folder / "readings.csv")
    db = ["--data", str(data)] + (["--database", url] if url else [])
    os.environ["GONIO_PASSWORD"] = PASSWORD        # tech's, checked as the login checks it
    try:
        assert main(["db", "import", str(folder), "--protocol", str(PROTOCOL), "--user",
                     "tech", *db]) == 0
    finally:
        del os.environ["GONIO_PASSWORD"]
    log_in(page, base, "rev")
    page.goto(base + "/calibrations?status=computed")
    with page.expect_navigation():
        page.locator("table a[href^='/calibrations/']").first.click()
    imported = page.url
    assert page.locator("#missing").inner_text().startswith(
        "Before its review and approval this calibration needs: registered standard valid on")
    with page.expect_navigation():
        page.click("button[value=accept]")
    assert "it names no registered standard valid on" in page.locator(
        "p.error[role=alert]").inner_text()
    attach = page.locator("form#attach")
    attach.locator("label", has_text="RT-07").locator("input").check()
    attach.locator("input[name=temperature_c]").fill("20.1")
    attach.locator("input[name=humidity_pct]").fill("45")
    shot(page, "attach")
    with page.expect_navigation():
        attach.locator("button:has-text('Attach')").click()
    assert page.locator("#missing").count() == 0 and "20.1 °C, 45 %" in page.content()
    # its draft is rendered from the stored result with them, by the server's worker
    wait_status(page, "computed")
    draft = page.request.get(imported + "/files/certificate.html").text()
    assert "<td>20.1 °C</td>" in draft and '<span class="nb">RT-07</span>' in draft
    with page.expect_navigation():
        page.click("button[value=accept]")
    wait_status(page, "reviewed")
    assert page.url.startswith(imported)
    log_out(page)

    # a user deactivated: tech can no longer log in
    log_in(page, base, "qm")
    page.goto(base + "/users")
    form = page.locator("form[action='/users/tech']")
    form.locator("input[name=active]").uncheck()
    with page.expect_navigation():
        form.locator("button:has-text('Save')").click()
    assert page.locator("tr", has_text="TECH Person").locator("td").nth(3).inner_text() == "no"
    log_out(page)
    page.goto(base + "/login")
    page.fill("input[name=username]", "tech")
    page.fill("input[name=password]", PASSWORD)
    page.click("button[type=submit]")
    page.wait_for_load_state()
    assert page.url.startswith(base + "/login")

    # the records verified, last night's backup verified, then restored and served
    log_in(page, base, "qm")
    page.goto(base + "/backup")
    with page.expect_navigation():
        page.click("text=Verify the records now")
    assert page.locator("#verified").inner_text().startswith("Records verified: ")
    page.set_input_files("input[name=archive]", str(nightly))
    with page.expect_navigation():
        page.click("text=Verify the archive")
    assert page.locator("#archive-ok").inner_text().startswith(
        "nightly.zip: complete and intact — 1 calibrations, 1 certificates")
    shot(page, "backup-verified")
    # restored in the browser: what is replaced shown, confirmed with the word and the password
    form = page.locator("form#restore-form")
    assert "<td>Certificates</td><td>2</td><td>1</td>" in form.inner_html()
    form.locator("input[name=confirm]").fill("RESTORE")
    form.locator("input[name=password]").fill("not the password")
    with page.expect_navigation():
        form.locator("button:has-text('Restore this archive')").click()
    assert page.locator("#restore-error").inner_text() == "wrong password: nothing restored"
    form = page.locator("form#restore-form")
    form.locator("input[name=confirm]").fill("RESTORE")
    form.locator("input[name=password]").fill(PASSWORD)
    shot(page, "restore-confirm")
    with page.expect_navigation():
        form.locator("button:has-text('Restore this archive')").click()
    assert page.locator("#restored").inner_text().startswith(
        "Restored from nightly.zip: 1 calibrations, 1 certificates")
    shot(page, "restored")
    page.goto(base + "/certificates")            # the session ended with the restore
    assert page.url.startswith(base + "/login")
    log_in(page, base, "tech")                   # deactivated after last night: active again
    log_out(page)
    log_in(page, base, "qm")
    page.goto(base + "/certificates")
    assert number in page.content() and amended not in page.content()
    shot(page, "restored-certificates")
    page.goto(base + "/backup")
    with page.expect_navigation():
        page.click("text=Verify the records now")
    assert page.locator("#verified").inner_text().startswith("Records verified: ")
    page.goto(base + "/audit?entity=records")
    assert "restore" in page.locator("table").inner_text()
    assert main(["db", "verify", *db]) == 0
