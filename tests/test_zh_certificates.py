"""Issue 25: no English word on a Chinese certificate. Each per-item specification's
certificate (JJF 1535, IEC 62047-20, the triad) is rendered in Chinese with a Chinese
laboratory file and without one; the HTML text, the figure text (matplotlib writes each
text as an SVG comment) and the PDF text (pdftotext) may hold Latin-letter words only from
a whitelist of symbols, units, model and software names and standard numbers, the budget's
component symbols, and what the readings file or the laboratory file itself says (data,
not certificate text)."""

from __future__ import annotations

import html
import re
import shutil
import subprocess

import pytest

from gonio.report.certificate import load_lab

#: Symbols, units, names and standard numbers a Chinese certificate may print in Latin letters.
WHITELIST = set("""
JJF IEC GUM JCGM ILAC ISO CNAS IEEE MEMS Allan Welch SHA VB gonio csv dB Hz mV lsb ppm
sin cos max min ln rms RMS ARW RRW BI BIC bic SF Out FullScale Noise CW CCW band_hz
broadband_high dec resolution rest cov WX monte carlo ADXRS dt
""".split())
WORD = re.compile(r"(?<![A-Za-z0-9_\\])[A-Za-z][A-Za-z]+(?:_[A-Za-z0-9,]+)?")

LAB_ZH = """
[laboratory]
name = "示例角度计量实验室"
address = "北京市示例路1号"
accreditation = "认可编号 0000"
contact = "电话 010-00000000"
[certificate]
number = "2026-0017"
date_of_receipt = "2026-11-02"
date_of_calibration = "2026-11-16"
date_of_issue = "2026-11-20"
place = "角度实验室 101 室"
[customer]
name = "示例导航仪器公司"
address = "西安市示例街2号"
[instrument]
description = "微机电陀螺仪"
model = "示例-1"
serial = "0001"
manufacturer = "示例陀螺厂"
[[standards]]
name = "速率转台"
identifier = "RT-07"
accuracy = "相对扩展不确定度 5×10⁻⁴（k = 2）"
certificate = "2026-A-0123"
traceability = "国家角速度基准"
[environment]
temperature_c = 20.1
humidity_pct = 45.0
[signatory]
calibrated_by = "张三"
checked_by = "李四"
approved_by = "王五"
approved_title = "技术负责人"
"""


def _rate(spec_key, d):
    from tests.test_rate_dcc import _simulate
    mod, proto, path, _ = _simulate(spec_key, d, 3)
    return mod.calibrate(path, str(proto)), path


def _triad(d):
    from gonio.cli import main
    from gonio.specs import get
    assert main(["simulate", "--spec", "triad-alignment", "--bench", "mems-triad",
                 "--out", str(d / "sim")]) == 0
    return get("triad-alignment").calibrate(d / "sim" / "readings.csv"), d / "sim" / "readings.csv"


@pytest.fixture(scope="module", params=("jjf1535-2015", "iec62047-20", "triad-alignment"))
def calibrated(request, tmp_path_factory):
    if shutil.which("pdftotext") is None:
        pytest.fail("pdftotext not found: run scripts/install-test-system-deps.sh")
    d = tmp_path_factory.mktemp(request.param)
    result, readings = _triad(d) if request.param == "triad-alignment" else \
        _rate(request.param, d)
    lab = d / "lab-zh.toml"
    lab.write_text(LAB_ZH, encoding="utf-8")
    return {"key": request.param, "result": result, "dir": d, "lab": lab,
            "readings": readings}


def _write(c, out, lab):
    if c["key"] == "triad-alignment":
        from gonio.specs.triad_alignment.certificate_pages import write_triad_certificate as w
    else:
        from gonio.report.rate_certificate import write_rate_certificate as w
    return w(c["result"], out, lab=lab, lang="zh", dcc=True)


def _allowed(c, lab) -> set:
    res = c["result"].to_json()
    ok = set(WHITELIST)
    for it in res["items"].values():
        for comp in (it.get("uncertainty") or {}).get("components") or []:
            ok |= set(WORD.findall(comp.get("symbol") or ""))
        ok |= set(WORD.findall(it.get("unit") or ""))
    data = " ".join(str(v) for v in res.get("metadata", {}).values())
    data += " " + str(res.get("source", {}).get("file", ""))
    if lab:
        data += " " + str(load_lab(lab))
    return ok | set(WORD.findall(data))


@pytest.mark.parametrize("with_lab", (True, False))
def test_no_english_word_on_a_chinese_certificate(calibrated, with_lab, tmp_path):
    lab = calibrated["lab"] if with_lab else None
    out = tmp_path / "zh"
    _write(calibrated, out, lab)
    page = (out / "certificate.html").read_text(encoding="utf-8")
    page = re.sub(r"<style.*?</style>", " ", page, flags=re.S)
    figures = " ".join(re.findall(r"<!-- (.*?) -->", page))
    text = html.unescape(re.sub(r"<[^>]+>", " ", re.sub(r"<svg.*?</svg>", " ", page,
                                                           flags=re.S)))
    pdf = subprocess.run(["pdftotext", str(out / "certificate.pdf"), "-"], capture_output=True,
                         text=True, check=True).stdout
    allowed = _allowed(calibrated, lab)
    for where, t in (("HTML", text), ("figures", figures), ("PDF", pdf)):
        bad = sorted({w for w in WORD.findall(t) if w not in allowed})
        assert not bad, f"{calibrated['key']} zh {where}: English words {bad}"
    # the zh DCC carries Chinese beside English
    doc = (out / "certificate.dcc.xml").read_text(encoding="utf-8")
    assert doc.count('lang="zh"') >= 4 and "<dcc:usedLangCodeISO639_1>zh<" in doc


def test_the_check_can_fail(calibrated, tmp_path):
    """An English phrase slipped into a Chinese certificate is caught."""
    allowed = _allowed(calibrated, None)
    assert [w for w in WORD.findall("偏差 the scale factor") if w not in allowed]
