"""The new flows in a real browser on a phone's screen (390 × 844 CSS px): Playwright drives
Debian's Chromium through a real ``gonio serve`` (one worker running gonio's pipeline).

* the calibration form refuses a JSON file, a rate-gyro file, readings whose temperature
  contradicts the one entered, and an upload over the size limit, each in one line, keeping
  what was entered and the readings already uploaded; the kept file is sent without
  choosing it again; the same readings a second time need a reason;
* the due list searched and narrowed to a customer, the recall notices printed (one PDF page
  per customer, menus not printed), a standard's history page;
* no main page scrolls sideways at 390 px.

Screenshots and the printed recall PDF go to $GONIO_SCREENSHOTS_PHONE (default
/tmp/gonio-web-shots-phone) for a person to look at."""

from __future__ import annotations

import datetime as dt
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from gonio.records import services

from .test_web_browser import (PASSWORD, PROTOCOL, Shots, browser, log_in,  # noqa: F401
                               wait_status)
from .test_web_lists import fleet, issued, recalibrated_standard

SHOTS = Path(os.environ.get("GONIO_SCREENSHOTS_PHONE", "/tmp/gonio-web-shots-phone"))
PHONE = {"width": 390, "height": 844}
RATE = (b"# spec: jjf1535-2015\n# model: ADXRS610-class\n# serial: MEMS-0610-001\n"
        b"test,run,step,role,time_s,rate_dps,output\nsf,1,1,ref,0.0,10.0,2560.1\n")
#: the readings limit the server runs under here (small, so that a test can pass it)
LIMIT = 2**20


@pytest.fixture
def lab(tmp_path, serve, monkeypatch):
    """gonio serve (one worker, readings limit :data:`LIMIT`) with users, a standard with its
    recalibration recorded, an instrument of the virtual bench and 30 issued instruments of
    two customers (their due dates spread around today)."""
    from gonio.records.db import open_store

    data = tmp_path / "data"
    st = open_store(None, data)
    for name, roles in (("tech", "technician"), ("rev", "reviewer"),
                        ("admin", "admin technician reviewer")):
        services.create_user(st, None, name, PASSWORD, roles, name.upper() + " Person")
    services.set_settings(st, None, lab_name="Example Angle Laboratory",
                          lab_address="1 Example Road\nXi'an")
    tech = services.user(st, "tech")
    std = recalibrated_standard(st, "Precision rotary table",
                                ("NIM-2024-1", "2024-06-01", "2025-06-01"),
                                ("NIM-2025-3", "2025-05-20", "2030-05-20"))
    _, made = fleet(st, 30, dt.date.today())
    for inst, day in made[:3]:
        issued(st, inst.id, day - dt.timedelta(days=380), f"GC-2024-{inst.id:04d}", std.id)
    cust = services.add_customer(st, tech, "Example Navigation Instruments Co.",
                                 "2 Sample Street\nXi'an")
    inst = services.register_instrument(st, tech, customer_id=cust.id, serial="RLG-0001",
                                        spec_key="ogam-draft", kind="RLG goniometer",
                                        manufacturer="gonio virtual bench", model="RLG-GM-1")
    st.close()
    monkeypatch.setenv("GONIO_MAX_UPLOAD_BYTES", str(LIMIT))
    proc, base = serve.start(data, workers=1)
    yield base, inst.id, std.id
    serve.stop(proc)


def no_sideways(page) -> None:
    """The page is no wider than the screen (nothing to scroll sideways)."""
    page.wait_for_load_state()
    got = page.evaluate("() => [document.documentElement.scrollWidth, "
                        "document.body.scrollWidth, window.innerWidth]")
    assert got[0] <= got[2] and got[1] <= got[2], (page.url, got)


def alert(page) -> str:
    return page.locator("p.error[role=alert]").inner_text()


def fill_form(page, std_id: int, temperature: str) -> None:
    page.check(f"input[name=standards][value='{std_id}']")
    page.fill("input[name=performed_on]", "2025-11-20")
    page.fill("input[name=received_on]", "2025-11-18")
    page.fill("input[name=temperature_c]", temperature)
    page.fill("input[name=humidity_pct]", "45")
    page.fill("input[name=place]", "Room 2")


def send(page) -> None:
    with page.expect_navigation():
        page.click("text=Upload and run")


def test_new_flows_on_a_phone(lab, browser, bench_readings, tmp_path):  # noqa: F811
    base, inst_id, std_id = lab
    shot = Shots(SHOTS)
    page = browser.new_page(viewport=PHONE, accept_downloads=True)
    page.goto(base + "/login")
    no_sideways(page)
    shot(page, "login")
    log_in(page, base, "tech")
    form_url = f"{base}/instruments/{inst_id}/calibrate"

    # 1. the submission checks, in the form's words, what was entered kept
    page.goto(form_url)
    no_sideways(page)
    shot(page, "form")
    json_file = tmp_path / "results.json"
    json_file.write_text('{"items": {}}')
    fill_form(page, std_id, "20.1")
    page.set_input_files("input[name=readings]", str(json_file))
    send(page)
    assert "key readings: the readings file is JSON" in alert(page)
    no_sideways(page)
    shot(page, "form-json-refused")
    rate = tmp_path / "jjf-readings.csv"
    rate.write_bytes(RATE)
    page.set_input_files("input[name=readings]", str(rate))
    send(page)
    assert "the readings are jjf1535-2015 readings" in alert(page)
    assert page.input_value("input[name=place]") == "Room 2"
    assert page.is_checked(f"input[name=standards][value='{std_id}']")
    page.set_input_files("input[name=readings]", str(bench_readings[0]))
    page.set_input_files("input[name=protocol_file]", str(PROTOCOL))
    page.fill("input[name=temperature_c]", "25")
    send(page)
    assert re.search(r"temperature: the readings say 20.0 °C .* what was entered 25 °C", alert(page))
    assert page.locator("b.kept").first.inner_text() == "readings.csv"
    assert page.input_value("input[name=temperature_c]") == "25"
    no_sideways(page)
    shot(page, "form-temperature-refused-file-kept")
    page.fill("input[name=temperature_c]", "20.1")        # the files are not chosen again
    send(page)
    assert re.search(r"/calibrations/\d+$", page.url), alert(page)
    cal_url = page.url

    # the same readings again: refused until a reason is given
    page.goto(form_url)
    fill_form(page, std_id, "20.1")
    page.set_input_files("input[name=readings]", str(bench_readings[0]))
    send(page)
    assert "already those of calibration" in alert(page)
    shot(page, "form-reuse-asks-why")
    page.fill("textarea[name=reuse_reason]", "checking the second workstation")
    send(page)
    assert re.search(r"/calibrations/\d+$", page.url), alert(page)

    # an upload over the limit: one line with the limit, not a generic error page
    big = tmp_path / "big.csv"
    big.write_bytes(b"a,b\n" * (5 * LIMIT // 4))
    page.goto(form_url)
    fill_form(page, std_id, "20.1")
    page.set_input_files("input[name=readings]", str(big))
    send(page)
    body = page.locator("body").inner_text()
    assert "is larger than the limit of 1 MiB (1,048,576 bytes) for a readings file" in body
    shot(page, "upload-too-large")

    # 2. the run computed, its page at 390 px
    page.goto(cal_url)
    wait_status(page, "computed")
    no_sideways(page)
    shot(page, "calibration-computed")

    # 3. the due list, searched and per customer; recall notices printed
    page.goto(base + "/due")
    no_sideways(page)
    shot(page, "due")
    page.fill("input[name=q]", "sn-01")
    with page.expect_navigation():
        page.click("form.search button")
    serials = page.locator("table.due td:first-child a").all_inner_texts()
    assert serials and all("SN-01" in s for s in serials)
    page.goto(base + "/due")
    with page.expect_navigation():
        page.click("table.due td:nth-child(2) a >> nth=0")
    customer = page.locator("p.note").first.inner_text()
    assert customer.startswith("Customer ")
    page.goto(base + "/due/recall")
    no_sideways(page)
    shot(page, "recall-screen")
    page.emulate_media(media="print")
    assert not page.locator("header").is_visible()
    pdf = SHOTS / "recall.pdf"
    page.pdf(path=str(pdf), format="A4")
    page.emulate_media(media="screen")
    n_customers = page.locator("section.recall").count()
    assert n_customers == 2
    if shutil.which("pdfinfo"):
        info = subprocess.run(["pdfinfo", str(pdf)], capture_output=True, text=True).stdout
        assert re.search(r"Pages:\s+2\b", info), info           # one sheet per customer
        text = subprocess.run(["pdftotext", str(pdf), "-"], capture_output=True,
                              text=True).stdout
        assert "gonio records" not in text and "Log out" not in text     # no menus
        assert "Recalibration due" in text and "Example Angle Laboratory" in text

    # 4. a standard's history
    page.goto(base + "/standards")
    no_sideways(page)
    shot(page, "standards")
    with page.expect_navigation():
        page.click("text=Precision rotary table")
    text = page.locator("main").inner_text()
    assert "NIM-2024-1" in text and "NIM-2025-3" in text and "Used in 5 calibrations" in text  # 3 + 2 uploaded
    no_sideways(page)
    shot(page, "standard-history")

    # 5. every other main page fits the screen
    for path in ("/", "/instruments", f"/instruments/{inst_id}", "/calibrations",
                 "/certificates", "/customers"):
        page.goto(base + path)
        no_sideways(page)
        shot(page, path.strip("/").replace("/", "-") or "overview")
    page.click("form.logout button")
    log_in(page, base, "admin")
    for path in ("/users", "/audit", "/certificates/1", "/backup"):
        page.goto(base + path)
        assert page.locator("h1").count() == 1, path
        no_sideways(page)
        shot(page, path.strip("/").replace("/", "-"))
