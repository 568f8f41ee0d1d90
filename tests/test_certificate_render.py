"""The certificate as a person sees it: HTML rendered in headless Chromium, PDF rendered page by
page with poppler, and every number checked against results.json through the one rounding rule.

Needs the system packages of ``scripts/install-test-system-deps.sh`` (chromium, poppler-utils,
fonts-noto-cjk); without them these tests fail and say so — they are part of the test command.
"""

from __future__ import annotations

import html
import json
import tomllib
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from gonio.result.model import Result
from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
from gonio.specs.ogam_draft.calibration import calibrate
from gonio.pipeline.dispatch import decide_conformity
from gonio.specs.ogam_draft.outputs import write_calibration
from gonio.errors import GonioError
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.specs.ogam_draft import certificate_pages as cert
from gonio.specs.ogam_draft.figures import FIGURES
from gonio.report.i18n import display, labels, minus_sign
from gonio.specs.ogam_draft.phrases import LABELS as OWN_LABELS
from gonio.resources import protocols_dir
from tests.own_readings import own_text

HINT = "run scripts/install-test-system-deps.sh (chromium, poppler-utils, fonts-noto-cjk)"
ITEMS = ("scale_factor", "scale_factor_nonlinearity", "zero_stability", "angle_deviation",
         "repeatability", "rate_consistency", "pointing_consistency")

# the small protocol shared with other tests (tests/data/small-protocol.toml)
SMALL_TOML = (Path(__file__).parent / "data" / "small-protocol.toml").read_text(encoding="utf-8")
SMALL = tomllib.loads(SMALL_TOML)


def tool(name: str) -> str:
    path = shutil.which(name)
    if not path:
        pytest.skip(f"{name} is missing: {HINT}")
    return path


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    d = tmp_path_factory.mktemp("cert")
    from dataclasses import replace

    proto = parse_protocol(SMALL)
    session = run_session(proto, replace(load_bench("rlg"), sample_rate_hz=100.0), seed=4)
    write_session(session, d)
    result = calibrate(d / "readings.csv", proto, static_record=session.static_record)
    write_calibration(result, d)
    paths = cert.write_certificate(result.to_json(), d, truth=session.truth, dcc=True)
    lab_dir = d / "lab"
    lab = cert.load_lab(protocols_dir() / "lab-example.toml")
    # a laboratory's own readings: the bench's metadata lines out (else marked virtual)
    lab_readings = d / "lab-readings.csv"
    lab_readings.write_text(own_text((d / "readings.csv").read_text()))
    lab_result = calibrate(lab_readings, proto, static_record=session.static_record)
    decide_conformity(lab_result, lab)   # the pipeline decides; the certificate renders
    cert.write_certificate(lab_result.to_json(), lab_dir, lab=lab)
    return {"dir": d, "paths": paths, "lab_dir": lab_dir, "truth": session.truth,
            "results": json.loads((d / "results.json").read_text())}


def lookup(results: dict, src: str):
    x = results
    for part in src.split("."):
        x = x[int(part)] if isinstance(x, list) else x[part]
    return x


def shown_numbers(page: str):
    """(src, rule, text) of every number the HTML shows (they carry data-src/data-rule)."""
    pat = re.compile(r'<span class="num" data-src="([^"]+)" data-rule="([^"]+)"[^>]*>([^<]*)</span>')
    return [(s, r, html.unescape(t)) for s, r, t in pat.findall(page)]


def test_every_number_in_html_equals_results_json(run):
    page = run["paths"]["certificate.html"].read_text()
    nums = shown_numbers(page)
    assert len(nums) >= 20
    U = run["results"]["extra"]["uncertainty"]["U_arcsec"]
    srcs = {s for s, _, _ in nums}
    items = run["results"]["items"]
    for item in ITEMS:      # a range whose corrected estimate fell below zero: its bound
        shown = {f"items.{item}.value", f"items.{item}.upper_bound"}
        if item == "angle_deviation":   # E = ± max|E_i|: results.json's value is max|E_i|
            assert items[item]["value"] == items[item]["details"]["max_abs_arcsec"]
            shown.add(f"items.{item}.details.max_abs_arcsec")
        assert shown & srcs, item
    # the per-point U printed is k·u + b, the table's bound at the point included
    assert "extra.uncertainty.U_bound_arcsec" in srcs
    for src, rule, text in nums:     # the certificate's minus sign (U+2212), else the same
        assert text == minus_sign(display(rule, lookup(run["results"], src), U)), (src, rule, text)
    # The stated U obeys GUM 7.2.6: two significant digits.
    assert re.fullmatch(r"0\.\d\d|\d\.\d", display("U", U))


def chromium(html_path: Path, tmp: Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [tool("chromium"), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
         "--no-first-run", "--disable-background-networking", "--disable-component-update",
         "--disable-sync", f"--user-data-dir={tmp / 'profile'}", "--window-size=1200,4000",
         *extra, html_path.as_uri()],
        capture_output=True, text=True, timeout=120)


def test_html_in_chromium_items_u_and_figures_visible(run, tmp_path):
    src = run["paths"]["certificate.html"].read_text()
    # Self-contained: nothing is loaded from outside (namespace URIs are names, not loads).
    assert not re.search(r"""(?:src|href)\s*=\s*["'](?:https?:)?//|url\(\s*["']?(?:https?:)?//|@import""",
                         src), "the page loads something from the network"
    # Ask the browser itself what is visible: bounding boxes of every figure and item row.
    probe = """<script>
    window.addEventListener('load', function () {
      var figs = Array.from(document.querySelectorAll('figure svg')).map(function (s) {
        var r = s.getBoundingClientRect(); var st = getComputedStyle(s);
        return r.width > 50 && r.height > 50 && st.visibility !== 'hidden' && st.display !== 'none'; });
      document.body.setAttribute('data-figs', JSON.stringify(figs));
    });</script></body>"""
    probed = tmp_path / "probe.html"
    probed.write_text(src.replace("</body>", probe))
    dom = chromium(probed, tmp_path, "--dump-dom", "--virtual-time-budget=5000").stdout
    m = re.search(r'data-figs="([^"]*)"', dom)
    assert m, "the page did not load in chromium"
    figs = json.loads(html.unescape(m.group(1)))
    assert len(figs) == len(FIGURES) and all(figs), figs
    L = labels("en", OWN_LABELS)
    text = re.sub(r"\s+", " ", html.unescape(re.sub(r"<[^>]+>", " ", dom)))
    for item in ITEMS:
        assert L[item] in text, item
    U = display("U", run["results"]["extra"]["uncertainty"]["U_bound_arcsec"])
    k = display("k", run["results"]["extra"]["uncertainty"]["k_bound"])
    assert re.search(rf"U = {re.escape(U)} ?″, k = {re.escape(k)}", text), "U with its k is not shown"
    assert L["virtual"] in text
    shot = tmp_path / "certificate.png"
    chromium(run["paths"]["certificate.html"], tmp_path, f"--screenshot={shot}")
    import matplotlib.image as mpimg

    img = mpimg.imread(shot)
    assert img.shape[0] > 1000 and float(np.std(img[..., :3])) > 0.05     # not blank


def pdf_pages_text(pdf: Path, tmp: Path):
    out = subprocess.run([tool("pdftotext"), "-layout", str(pdf), "-"], capture_output=True,
                         text=True, check=True).stdout
    return out.split("\f")[:-1] if out.endswith("\f") else out.split("\f")


def test_pdf_pages_numbered_nonblank_and_numbers_match(run, tmp_path):
    pdf = run["paths"]["certificate.pdf"]
    pages = pdf_pages_text(pdf, tmp_path)
    n = len(pages)
    assert n >= 2
    subprocess.run([tool("pdftoppm"), "-r", "40", "-png", str(pdf), str(tmp_path / "p")],
                   check=True)
    import matplotlib.image as mpimg

    pngs = sorted(tmp_path.glob("p-*.png"))
    assert len(pngs) == n
    for i, (png, txt) in enumerate(zip(pngs, pages), 1):
        assert float(np.std(mpimg.imread(png)[..., :3])) > 0.02, f"page {i} is blank"
        assert f"Page {i} of {n}" in txt, f"page {i} lacks 'Page {i} of {n}'"
        assert labels("en")["virtual_short"] in txt, f"page {i} lacks the virtual-bench mark"
    ident = cert.certificate_id(run["results"])
    assert all(ident in t for t in pages)
    # Every number the HTML shows appears in the PDF text, formatted by the same rule.
    alltext = " ".join(pages)
    U = run["results"]["extra"]["uncertainty"]["U_arcsec"]
    for src, rule, text in shown_numbers(run["paths"]["certificate.html"].read_text()):
        expect = minus_sign(display(rule, lookup(run["results"], src), U))
        assert expect in alltext, (src, expect)


def test_lab_file_details_and_no_virtual_mark(run, tmp_path):
    pdf = run["lab_dir"] / "certificate.pdf"
    pages = pdf_pages_text(pdf, tmp_path)
    lab = cert.load_lab(protocols_dir() / "lab-example.toml")
    for i, t in enumerate(pages, 1):
        assert lab["certificate"]["number"] in t and f"Page {i} of {len(pages)}" in t
        assert labels("en")["virtual_short"] not in t
    page = (run["lab_dir"] / "certificate.html").read_text()
    for value in (lab["laboratory"]["name"], lab["customer"]["name"],
                  lab["signatory"]["approved_by"], lab["standards"][0]["traceability"]):
        assert html.escape(value) in page, value
    assert labels("en")["virtual"] not in page


def test_virtual_readings_with_a_lab_file_are_marked(run, tmp_path):
    """The simulated readings with the laboratory file: every page says virtual."""
    lab = cert.load_lab(protocols_dir() / "lab-example.toml")
    result = decide_conformity(Result.from_json(run["results"]), lab)   # the pipeline's step
    cert.write_certificate(result.to_json(), tmp_path, lab=lab)
    pages = pdf_pages_text(tmp_path / "certificate.pdf", tmp_path)
    assert all(labels("en")["virtual_short"] in t for t in pages)
    page = (tmp_path / "certificate.html").read_text()
    assert labels("en")["virtual"] in page and html.escape(lab["laboratory"]["name"]) in page


def test_bad_lab_file_names_the_key(tmp_path):
    f = tmp_path / "lab.toml"
    text = (protocols_dir() / "lab-example.toml").read_text()
    f.write_text(text.replace("[customer]\n", "[customer]\nphone = \"1\"\n"))
    with pytest.raises(GonioError, match=r"lab.toml: key customer.phone: unknown key"):
        cert.load_lab(f)
    f.write_text(text.replace('date_of_issue = "2026-11-20"', 'date_of_issue = "20.11.2026"'))
    with pytest.raises(GonioError, match="certificate.date_of_issue"):
        cert.load_lab(f)


def test_failure_leaves_no_half_written_certificate(run, tmp_path, monkeypatch):
    def boom(*a, **k):
        raise RuntimeError("PDF write failed")

    # the PDF's write fails after the HTML was written into the staged folder
    monkeypatch.setattr(cert, "write_bytes", boom)
    with pytest.raises(RuntimeError):
        cert.write_certificate(run["results"], tmp_path / "out")
    assert not list((tmp_path / "out").glob("certificate.*"))


def test_chinese_labels(run, tmp_path):
    from gonio.report.i18n import cjk_font

    if cjk_font() is None:
        pytest.skip(f"no CJK font: {HINT}")
    paths = cert.write_certificate(run["results"], tmp_path, lang="zh")
    page = paths["certificate.html"].read_text()
    for term in ("标度因数", "标度因数非线性度", "零位稳定性", "角位置偏差", "角位置重复性",
                 "速率一致性", "指向一致性"):
        assert term in page, term
    pages = pdf_pages_text(paths["certificate.pdf"], tmp_path)
    assert all(f"第 {i} 页 共 {len(pages)} 页" in re.sub(r"\s+", " ", t)
               for i, t in enumerate(pages, 1))


def test_cli_calibrate_writes_certificate_with_lab(run, tmp_path, capsys):
    from gonio.cli import main

    lab = protocols_dir() / "lab-example.toml"
    (tmp_path / "small.toml").write_text(SMALL_TOML)
    assert parse_protocol(SMALL) == parse_protocol(tomllib.loads(SMALL_TOML))
    assert main(["calibrate", str(run["dir"] / "readings.csv"), "--out", str(tmp_path / "o"),
                 "--protocol", str(tmp_path / "small.toml"), "--lab", str(lab)]) == 0
    assert (tmp_path / "o" / "certificate.html").is_file()
    assert (tmp_path / "o" / "certificate.pdf").is_file()
    bad = tmp_path / "bad.toml"
    bad.write_text("[laboratory]\nname = 1\n")
    assert main(["calibrate", str(run["dir"] / "readings.csv"), "--out", str(tmp_path / "p"),
                 "--protocol", str(tmp_path / "small.toml"), "--lab", str(bad)]) == 2
    assert "laboratory.name" in capsys.readouterr().err
    assert not (tmp_path / "p" / "results.json").exists()


def test_same_inputs_same_certificate_bytes(run, tmp_path):
    a = cert.write_certificate(run["results"], tmp_path / "a")
    b = cert.write_certificate(run["results"], tmp_path / "b")
    for name in ("certificate.html", "certificate.pdf"):
        assert a[name].read_bytes() == b[name].read_bytes(), name


def test_rendered_again_from_the_stored_results_json_alone(run, tmp_path):
    """The certificate (HTML, PDF), its figures and its DCC are a pure function of the stored
    results.json (and the virtual run's truth.json): rendered again from the file, read back
    through the one result model, they are the bytes the calibration wrote."""
    stored = Result.from_json(json.loads((run["dir"] / "results.json").read_text()))
    truth = json.loads((run["dir"] / "truth.json").read_text())
    again = cert.write_certificate(stored.to_json(), tmp_path, truth=truth, dcc=True)
    for name in ("certificate.html", "certificate.pdf", "certificate.dcc.xml"):
        assert again[name].read_bytes() == run["paths"][name].read_bytes(), name
    # the figures are drawn from the series results.json holds, not from analysis objects
    page = again["certificate.html"].read_text()
    assert page.count("<svg") >= len(FIGURES)
    assert set(stored.extra["figures"]) == {key for key, _, _ in FIGURES}
