"""Every certificate carries the same ISO/IEC 17025 7.8 content from the same laboratory
file: the optical draft's, JJF 1535's, IEC 62047-20's and the triad's, each rendered in
English and in Chinese with one laboratory file (limits for one item each, with their
source). Each page (HTML text and PDF text through pdftotext) must show the laboratory's
address, accreditation and contact, the customer's address, the approver with the title,
the decision rule as agreed, the source of the specification limits, "page x of y" and the
end-of-certificate mark; the laboratory file is read from formats/, not from a renderer."""

from __future__ import annotations

import html
import re
import subprocess

import pytest

from gonio.formats.lab import load_lab

LAB = """
[laboratory]
name = "Lab Seventeen"
address = "17 Calibration Row, Lanzhou"
accreditation = "CNAS L1717"
contact = "lab17@example.org"
[certificate]
number = "C17-0001"
[customer]
name = "Customer Nine"
address = "9 Buyer Street, Wuhan"
[signatory]
approved_by = "Q. Approver"
approved_title = "Quality manager"
[decision_rule]
rule = "simple"
agreed = "at contract review C-17"
[[specification_limits]]
item = "{item}"
mpe = 1.0e6
source = "purchase order PO-{item}"
"""

ITEM = {"ogam-draft": "angle_deviation", "jjf1535-2015": "bias", "iec62047-20": "bias",
        "triad-alignment": "M_xx"}


@pytest.fixture(scope="module", params=tuple(ITEM))
def calibrated(request, tmp_path_factory):
    from tests.test_zh_certificates import small_calibration
    d, result = small_calibration(request.param, tmp_path_factory)
    lab = d / "lab.toml"
    lab.write_text(LAB.replace("{item}", ITEM[request.param]), encoding="utf-8")
    return {"key": request.param, "result": result, "dir": d, "lab": load_lab(lab)}


def _texts(c, lang):
    from gonio.pipeline.dispatch import decide_conformity
    from gonio.specs import get
    out = c["dir"] / f"out-{lang}"
    decide_conformity(c["result"], c["lab"])          # the pipeline's one decision
    get(c["key"]).renderer().write(c["result"], out, lab=c["lab"], lang=lang)
    page = (out / "certificate.html").read_text(encoding="utf-8")
    text = html.unescape(re.sub(r"<[^>]+>", " ", page.split("<body>")[1]))
    pdf = subprocess.run(["pdftotext", "-layout", str(out / "certificate.pdf"), "-"],
                         capture_output=True, text=True, check=True).stdout
    return page, re.sub(r"\s+", " ", text), re.sub(r"\s+", " ", pdf)


@pytest.mark.parametrize("lang", ("en", "zh"))
def test_every_certificate_carries_the_17025_content(calibrated, lang):
    page, text, pdf = _texts(calibrated, lang)
    item = ITEM[calibrated["key"]]
    agreed = {"en": "Agreed: at contract review C-17", "zh": "约定：at contract review C-17"}
    source = {"en": "Source of the specification limits:", "zh": "规定限的来源："}
    end = {"en": "End of certificate", "zh": "证书结束"}
    for where, t in (("html", text), ("pdf", pdf)):
        for want in ("17 Calibration Row, Lanzhou", "CNAS L1717", "lab17@example.org",
                     "9 Buyer Street, Wuhan", "Q. Approver, Quality manager", agreed[lang],
                     source[lang], f"purchase order PO-{item}", end[lang]):
            assert want in t, (calibrated["key"], lang, where, want)
        # the end mark is the last thing of the certificate's body
        assert t.rindex(end[lang]) > t.rindex("Q. Approver"), (calibrated["key"], where)
    pages = len(re.findall("\f", subprocess.run(
        ["pdftotext", str(calibrated["dir"] / f"out-{lang}" / "certificate.pdf"), "-"],
        capture_output=True, text=True, check=True).stdout))
    of = {"en": f"Page 1 of {pages}", "zh": f"第 1 页 共 {pages} 页"}[lang]
    assert of in pdf, (calibrated["key"], lang, of)
    assert "counter(pages)" in page           # the printed HTML: page x of y on every page


def test_lab_file_is_read_by_formats_not_the_renderer():
    from gonio.formats import lab
    from gonio.report import rate_certificate
    from gonio.specs.ogam_draft import certificate_pages as certificate
    assert "LAB_SCHEMA" in vars(lab) and "def load_lab" in open(lab.__file__).read()
    for mod in (certificate, rate_certificate):
        src = open(mod.__file__).read()
        assert "def load_lab" not in src and "LAB_SCHEMA: dict" not in src
