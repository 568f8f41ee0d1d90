"""The whole workflow in a real browser: Playwright drives Debian's Chromium through a real
``gonio serve`` process (its own worker processes running gonio's pipeline): log in,
register, upload readings, watch the run, review, approve by a second person, download the
PDF and the DCC, calibrate again, see two calibrations in the history. Screenshots of every
page go to $GONIO_SCREENSHOTS (default /tmp/gonio-web-shots) for a person to look at."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import time
from pathlib import Path

import pytest

from gonio.records import services

PASSWORD = "correct horse battery"
CHROMIUM = "/usr/bin/chromium"
SHOTS = Path(os.environ.get("GONIO_SCREENSHOTS", "/tmp/gonio-web-shots"))
PROTOCOL = Path(__file__).resolve().parents[1] / "data" / "small-protocol.toml"


@pytest.fixture
def live(tmp_path, serve):
    """A running gonio serve with users tech (technician), rev and rev2 (reviewers)."""
    from gonio.records.db import open_store

    data = tmp_path / "data"
    st = open_store(None, data)
    for name, roles in (("tech", "technician"), ("rev", "reviewer"), ("rev2", "reviewer")):
        services.create_user(st, None, name, PASSWORD, roles, name.upper() + " Person")
    services.set_settings(st, None, lab_name="Example Angle Laboratory",
                          lab_address="1 Example Road")
    st.close()
    proc, base = serve.start(data, memo=True)
    yield base, data
    serve.stop(proc)


@pytest.fixture
def browser():
    sync = pytest.importorskip("playwright.sync_api", reason="pip install '.[test]'")
    if not Path(CHROMIUM).exists():
        pytest.skip("Debian's chromium not installed (bash scripts/install-test-system-deps.sh)")
    with sync.sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=[
            "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync"])
        yield b
        b.close()


class Shots:
    """Full-page screenshots, numbered, into ``root`` (its numbered screenshots of an earlier
    run removed first; its sub-folders, another test's, kept: the month test writes into
    ``SHOTS/month-*`` while this one, under pytest-xdist, may start on another worker)."""

    def __init__(self, root: Path = SHOTS):
        self.root = root
        root.mkdir(parents=True, exist_ok=True)
        for old in root.glob("[0-9][0-9]-*.png"):
            old.unlink(missing_ok=True)
        self.n = 0

    def __call__(self, page, name: str) -> None:
        self.n += 1
        page.screenshot(path=str(self.root / f"{self.n:02d}-{name}.png"), full_page=True)


def log_in(page, base: str, name: str) -> None:
    page.goto(base + "/login")
    page.fill("input[name=username]", name)
    page.fill("input[name=password]", PASSWORD)
    page.click("button[type=submit]")
    page.wait_for_url(base + "/")


def log_out(page) -> None:
    page.click("form.logout button")


def wait_status(page, want: str, timeout_s: float = 600) -> None:
    """Poll the calibration's state (its /progress, with the page's session) until it is
    ``want`` (fails on 'failed'), then load its page (the page refreshes itself meanwhile)."""
    page.wait_for_load_state()
    url = page.url.split("?")[0]
    end = time.monotonic() + timeout_s
    state = None
    while time.monotonic() < end:
        got = page.request.get(url + "/progress").json()
        state = got["status"]
        if state == "failed" and want != "failed":
            raise AssertionError(got["error"])
        if state == want:
            break
        time.sleep(0.2)
    else:
        raise AssertionError(f"calibration still {state} after {timeout_s} s")
    for attempt in range(5):          # a refresh the page had started may abort a goto
        try:
            page.goto(url)
            break
        except Exception:
            time.sleep(0.5)
    assert page.locator("h1 .status").inner_text() == want


def upload(page, base: str, inst_url: str, readings: Path, day: str) -> str:
    page.goto(inst_url)
    page.click("text=New calibration")
    page.set_input_files("input[name=readings]", str(readings))
    page.set_input_files("input[name=protocol_file]", str(PROTOCOL))
    page.check("input[name=standards]")
    page.fill("input[name=performed_on]", day)
    page.fill("input[name=temperature_c]", "20.1")
    page.fill("input[name=humidity_pct]", "45")
    page.click("text=Upload and run")
    page.wait_for_url(re.compile(r".*/calibrations/\d+$"))
    return page.url


def register(page, base: str, shot=None) -> str:
    """A customer, a standard and an instrument (with a limit), as the technician; the
    instrument's URL. The browser tests register the same ones: their first calibration
    (the same readings, date and details) is then the same pipeline run, computed once in a
    session (``serve.start(..., memo=True)``)."""
    shot = shot or (lambda page, name: None)
    page.goto(base + "/customers")
    page.fill("input[name=name]", "Example Navigation Instruments Co.")
    page.fill("textarea[name=address]", "2 Sample Street, Xi'an")
    page.click("text=Add customer")
    shot(page, "customers")
    page.goto(base + "/standards")
    page.fill("input[name=name]", "Precision rotary table")
    page.fill("input[name=identifier]", "RT-07")
    page.fill("input[name=accuracy]", "MPE ±0.1″")
    page.fill("input[name=due_on]", "2030-01-01")
    page.click("text=Add standard")
    shot(page, "standards")
    page.goto(base + "/instruments")
    page.fill("input[name=kind]", "RLG goniometer")
    page.fill("input[name=manufacturer]", "gonio virtual bench")
    page.fill("input[name=model]", "RLG-GM-1")
    page.fill("input[name=serial]", "RLG-0001")
    page.select_option("select[name=spec_key]", "ogam-draft")
    page.fill("input[name=limit_item_0]", "angle_deviation")
    page.fill("input[name=limit_mpe_0]", "0.5")
    page.fill("input[name=limit_source_0]", "manufacturer's specification")
    shot(page, "instrument-register")
    page.click("button:has-text('Register')")
    page.wait_for_url(re.compile(r".*/instruments/\d+$"))
    return page.url


def test_whole_workflow_in_chromium(live, browser, bench_readings, tmp_path):
    base, data = live
    shot = Shots()
    page = browser.new_page(viewport={"width": 1280, "height": 900}, accept_downloads=True)
    page.goto(base + "/instruments")                 # no session: the login page
    assert page.url == base + "/login"
    shot(page, "login")
    log_in(page, base, "tech")
    inst_url = register(page, base, shot)
    cal_url = upload(page, base, inst_url, bench_readings[0], "2025-11-20")
    shot(page, "calibration-running")
    assert page.locator("h1 .status").inner_text() in ("queued", "running", "computed")
    wait_status(page, "computed")
    assert "scale factor K" in page.content()
    shot(page, "calibration-computed")
    log_out(page)

    log_in(page, base, "rev")
    page.goto(cal_url)
    page.fill("textarea[name=comment]", "readings and environment checked")
    with page.expect_navigation():
        page.click("button[value=accept]")
    wait_status(page, "reviewed")
    shot(page, "calibration-reviewed")
    log_out(page)

    log_in(page, base, "rev2")
    shot(page, "dashboard")
    page.goto(cal_url)
    with page.expect_navigation():
        page.click("button:has-text('Approve and issue')")
    wait_status(page, "issued")
    shot(page, "calibration-issued")
    page.click("h2:has-text('Certificates') + p a")
    year = time.gmtime().tm_year
    assert f"GC-{year}-0001" in page.locator("h1").inner_text()
    shot(page, "certificate")
    with page.expect_download() as dl:
        page.click("text=certificate.pdf")
    pdf = tmp_path / "certificate.pdf"
    dl.value.save_as(pdf)
    assert pdf.read_bytes().startswith(b"%PDF")
    with page.expect_download() as dl:
        page.click("text=certificate.dcc.xml (DCC)")
    dcc = tmp_path / "certificate.dcc.xml"
    dl.value.save_as(dcc)
    from lxml import etree
    root = etree.parse(str(dcc)).getroot()
    assert root.tag.endswith("digitalCalibrationCertificate")
    assert f"GC-{year}-0001".encode() in dcc.read_bytes()
    text = subprocess.run(["pdftotext", str(pdf), "-"], capture_output=True,
                          text=True).stdout if shutil.which("pdftotext") else ""
    if text:
        assert f"GC-{year}-0001" in text and "RLG-0001" in text
    log_out(page)

    log_in(page, base, "tech")
    upload(page, base, inst_url, bench_readings[1], "2026-11-20")
    wait_status(page, "computed")
    page.goto(inst_url)
    assert "History (2 calibrations)" in page.content()
    img = page.locator("img.history")
    assert img.evaluate("i => i.complete && i.naturalWidth > 0")
    shot(page, "instrument-history")
    page.goto(base + "/calibrations")
    shot(page, "calibrations")
    page.goto(base + "/certificates")
    shot(page, "certificates")
    page.goto(base + "/audit")
    assert "reviewer or admin role" in page.content()     # not a technician's to read
    page.goto(base + "/")
    log_out(page)
    log_in(page, base, "rev")
    page.goto(base + "/audit")
    shot(page, "audit")
    from gonio.records.db import open_store
    st = open_store(None, data)
    try:
        inst_id = int(inst_url.rsplit("/", 1)[1])
        hist = services.history(st, inst_id)
        assert [r["date"].isoformat() for r in hist["scale_factor"]] == ["2025-11-20",
                                                                        "2026-11-20"]
        assert [r["status"] for r in hist["scale_factor"]] == ["issued", "computed"]
    finally:
        st.close()
