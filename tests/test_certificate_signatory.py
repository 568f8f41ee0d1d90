"""What a signatory stopped at, checked on the rendered certificates of the per-item
specifications (JJF 1535, IEC 62047-20, the triad), in English and Chinese: HTML text, PDF
text (pdftotext) and the DCC. No recalibration interval unless the laboratory file says one
was agreed (ISO/IEC 17025 7.8.4.3); figures numbered; the signature block kept on one page;
table cells broken only between words; every limit with its unit; no "1e-05"; the IEC
certificate a calibration certificate; a specification's procedure cited as a document, not
a file of gonio's repository (the laboratory's own procedure where its file names it);
every demo writes its DCC; and a certificate rendered again from the stored results.json is
byte-identical to the one the calibration wrote."""

from __future__ import annotations

import html
import json
import re
import subprocess

import pytest

from gonio.formats.lab import load_lab

LAB = """
[laboratory]
name = "Lab Seventeen"
address = "17 Calibration Row"
[certificate]
number = "C17-0002"
procedure = "LP-17 rev. 4"
[customer]
name = "Customer Nine"
[signatory]
calibrated_by = "A. Calibrator"
approved_by = "Q. Approver"
[decision_rule]
rule = "simple"
[[specification_limits]]
item = "{item}"
mpe = {mpe}
"""
RECAL = '[recalibration]\ninterval_months = 18\nagreed = "contract review C-17"\n'
ITEM = {"jjf1535-2015": ("bias", "1.0e-5"), "iec62047-20": ("bias", "1.0e6"),
        "triad-alignment": ("S_xy", "1.0")}


@pytest.fixture(scope="module", params=tuple(ITEM))
def calibrated(request, tmp_path_factory):
    from tests.test_zh_certificates import small_calibration
    d, result = small_calibration(request.param, tmp_path_factory)
    item, mpe = ITEM[request.param]
    text = LAB.replace("{item}", item).replace("{mpe}", mpe)
    (d / "lab.toml").write_text(text, encoding="utf-8")
    (d / "lab-recal.toml").write_text(text + RECAL, encoding="utf-8")
    return {"key": request.param, "result": result, "dir": d}


def _render(c, lang, lab="lab.toml", name=None):
    from gonio.pipeline.dispatch import decide_conformity
    from gonio.specs import get
    out = c["dir"] / (name or f"{lang}-{lab}")
    if not out.exists():
        decide_conformity(c["result"], load_lab(c["dir"] / lab))   # the pipeline's decision
        get(c["key"]).renderer().write(c["result"], out, lab=load_lab(c["dir"] / lab),
                                       lang=lang, dcc=True)
    page = (out / "certificate.html").read_text(encoding="utf-8")
    body = re.sub(r"<svg.*?</svg>", " ", page.split("<body>")[1], flags=re.S)
    text = re.sub(r"\s+", " ", html.unescape(re.sub(r"<[^>]+>", " ", body)))
    pages = subprocess.run(["pdftotext", "-layout", str(out / "certificate.pdf"), "-"],
                           capture_output=True, text=True, check=True).stdout.split("\f")
    return out, page, text, pages


@pytest.mark.parametrize("lang", ("en", "zh"))
def test_recalibration_interval_only_where_agreed(calibrated, lang):
    word = {"en": "Recalibration", "zh": "复校"}[lang]
    _, page, text, pages = _render(calibrated, lang)
    assert word not in text and word not in "".join(pages), calibrated["key"]
    assert "recommended" not in text and "建议" not in text
    _, page, text, pages = _render(calibrated, lang, "lab-recal.toml")
    want = {"en": "18 months, as agreed with the customer (contract review C-17)",
            "zh": "18 个月（与委托方约定：contract review C-17）"}[lang]
    assert want in text and want.split(",")[0] in re.sub(r"\s+", " ", "".join(pages))


@pytest.mark.parametrize("lang", ("en", "zh"))
def test_layout_of_every_certificate(calibrated, lang):
    out, page, text, pages = _render(calibrated, lang)
    # figures numbered in order, each once
    caps = re.findall(r"<figcaption>([^<]*)</figcaption>", page)
    assert caps, calibrated["key"]
    fig = {"en": "Fig. {n} ", "zh": "图{n}"}[lang]
    for n, cap in enumerate(caps, 1):
        assert html.unescape(cap).startswith(fig.format(n=n)), (n, cap)
    # the signature block on one page: in the browser's print (a kept block) and in the PDF
    sig = {"en": ("Calibrated by", "Approved by"), "zh": ("校准员", "批准人")}[lang]
    kept = re.search(r'<div class="keep">\s*<h2>[^<]*</h2>\s*<table class="kv">(.*?)</div>',
                     page, re.S)
    assert kept and all(s in kept.group(1) for s in sig)
    assert any(all(s in p for s in sig) for p in pages)
    # cells break between words: every word of the tables' heads whole in the PDF
    pdf = " ".join(pages)
    if lang == "en":
        for word in ("Probability", "conformance", "false-accept"):
            assert word in pdf, word
    # no e-notation on the page (the readings file's SHA-256 prefix is hex, not a number);
    # every specification limit with its unit
    plain = re.sub(r"SHA-256 [0-9a-f]+", "SHA-256", text)
    assert not re.search(r"\d[eE][-+]?\d", plain), re.search(r".{20}\d[eE][-+]?\d.{10}", plain)
    table = re.search(r'<table id="conformity">(.*?)</table>', page, re.S).group(1)
    limits = [html.unescape(re.sub(r"<[^>]+>", "", r[1]))
              for r in re.findall(r"<tr>(<td>.*?</td>)(<td>.*?</td>)", table)]
    assert limits
    for lim in limits:
        assert re.search(r"[\]\d]\s+\S", lim), lim       # "[-1, 1] (dimensionless)", "≤ 2 °/h"
    if lang == "zh":          # Chinese punctuation, one term per concept, symbols not words
        # (a formula keeps its ASCII brackets: "(max − min)/2")
        assert not re.search(r"[\u3400-\u9fff][:;,!?]|合格 \(|[\u3400-\u9fff] \(\d", text), \
            re.search(r".{15}([\u3400-\u9fff][:;,!?]|合格 \(|[\u3400-\u9fff] \(\d).{15}", text)
        assert "滞回" not in text
        for word in ("noise", "grid", "drift"):
            assert not re.search(rf"(?<![A-Za-z_]){word}(?![A-Za-z_])", text), word
    # the laboratory's procedure is named; no file of gonio's repository is cited
    assert "LP-17 rev. 4" in text and "docs/" not in text and ".md" not in text


def test_the_iec_certificate_is_a_calibration_certificate(calibrated):
    if calibrated["key"] != "iec62047-20":
        pytest.skip("IEC 62047-20 only")
    for lang, title, wrong in (("en", "Calibration Certificate", "test results"),
                               ("zh", "校准证书", "测试结果")):
        _, page, text, _ = _render(calibrated, lang)
        assert f"<h1>{title}</h1>" in page and wrong not in text.lower()


def test_rendered_again_from_the_stored_results_is_byte_identical(calibrated):
    """Certificate (HTML, PDF), DCC, results.json and tables: a pure function of the stored
    results.json and the laboratory file."""
    from gonio.result.model import Result
    from gonio.specs import get
    for lang in ("en", "zh"):
        out, *_ = _render(calibrated, lang, "lab-recal.toml")
        stored = Result.from_json(json.loads((out / "results.json").read_text(encoding="utf-8")))
        again = calibrated["dir"] / f"again-{lang}"
        get(calibrated["key"]).renderer().write(stored, again, lab=load_lab(
            calibrated["dir"] / "lab-recal.toml"), lang=lang, dcc=True)
        names = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
        assert "certificate.dcc.xml" in names and "certificate.pdf" in names
        for name in names:
            assert (again / name).read_bytes() == (out / name).read_bytes(), (lang, name)


def test_the_triad_demo_writes_its_dcc(tmp_path):
    from gonio.specs.triad_alignment.outputs import demo
    _, paths = demo(tmp_path / "d", seed=3, dcc=True, monte_carlo_trials=50)
    doc = (tmp_path / "d" / "certificate.dcc.xml").read_bytes()
    assert doc.startswith(b"<?xml") and b"digitalCalibrationCertificate" in doc
    assert "certificate.dcc.xml" in {p.name for p in paths.values()}


@pytest.mark.parametrize("lang", ("en", "zh"))
def test_a_printed_certificate_never_ends_on_a_page_of_its_closing_alone(calibrated, lang,
                                                                          tmp_path):
    """Printed from the browser, the end mark, footer and banner stay with the last block:
    the last page holds more than "end of certificate" and the page furniture."""
    from tests.test_certificate_statement import chromium_print, pdf_pages
    out, page, *_ = _render(calibrated, lang)
    assert re.search(r'<div class="closing">\s*<p class="end"', page)
    pages = pdf_pages(chromium_print(out / "certificate.html", tmp_path / "p.pdf", tmp_path))
    furniture = (r"End of certificate|证书结束|Certificate No\.|证书编号|Page \d+ of|第 \d+ 页|"
                 r"shall not be reproduced|不得|VIRTUAL|虚拟|NOT A CALIBRATION|Lab Seventeen|"
                 r"EXAMPLE|示例|^\W*$")
    rest = [li for li in pages[-1].splitlines() if li.strip() and not re.search(furniture, li)]
    assert rest, (calibrated["key"], lang, pages[-1])
