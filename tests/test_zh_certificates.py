"""Issue 25: no English word on a Chinese certificate. Each per-item specification's
certificate (JJF 1535, IEC 62047-20, the triad) is rendered in Chinese with a Chinese
laboratory file and without one; the HTML text, the figure text (matplotlib writes each
text as an SVG comment) and the PDF text (pdftotext) may hold Latin-letter words only from
a whitelist of symbols, units, model and software names and standard numbers, the budget's
component symbols, and what the readings file or the laboratory file itself says (data,
not certificate text: the readings' test and column names a finding points at, the
protocol's name). The optical draft's certificate is rendered too, from damaged readings (a
count typo set aside, a 7.4 round missing from every series, no pointing-consistency rows)
so that the screening's findings and an item not measured reach the page; the laboratory
file gives limits for three items of each specification (conformity statements). In the zh
DCC every text holding such a word is English (lang="en") with its Chinese beside it, and
the Chinese holds none."""

from __future__ import annotations

import html
import re
import shutil
import subprocess

import pytest

from lxml import etree

from gonio.formats.lab import load_lab
from gonio.report.dcc import DCC_NS

#: Symbols, units, names and standard numbers a Chinese certificate may print in Latin letters.
WHITELIST = set("""
JJF IEC GUM JCGM ILAC ISO CNAS IEEE MEMS Allan Welch Satterthwaite SHA VB gonio csv dB Hz mV lsb ppm
sin cos max min ln rms RMS ARW RRW BI BIC bic SF Out FullScale Noise CW CCW band_hz
broadband_high dec resolution rest cov WX PZ monte carlo ADXRS dt results json
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


#: Limits for three items of each specification (conformity statements on the page).
LIMITS = {"ogam-draft": ("angle_deviation", "repeatability", "zero_stability"),
          "jjf1535-2015": ("bias", "scale_factor", "angle_random_walk"),
          "iec62047-20": ("bias", "arw", "frequency_band"),
          "triad-alignment": ("M_xx", "b_x", "S_xy")}
SMALL = "tests/data/small-protocol.toml"


def _optical(d):
    """The small optical programme, damaged (module docstring)."""
    from gonio.cli import main
    from gonio.specs.ogam_draft.calibration import calibrate
    from tests.test_ogam_screen import data_line, nominal_k, set_col
    assert main(["simulate", "--protocol", SMALL, "--seed", "2411", "--out", str(d / "sim")]) == 0
    lines = (d / "sim" / "readings.csv").read_text().splitlines(keepends=True)
    i = data_line(lines, "angle_deviation", 2, 2)
    lines[i] = set_col(lines[i], 7, lambda c: str(int(c) + round(nominal_k(lines))))
    lines = [ln for ln in lines if not ln.startswith("pointing_consistency,") and not (
        ln.startswith("angle_deviation,") and ln.split(",")[2] == "3")]
    path = d / "readings.csv"
    path.write_text("".join(lines))
    return calibrate(path, SMALL), path


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


def small_result(key, d):
    """(result, readings path) of a small calibration of specification ``key`` in ``d``."""
    make = {"ogam-draft": _optical, "triad-alignment": _triad}.get(key, lambda d: _rate(key, d))
    return make(d)


def small_calibration(key, tmp_path_factory):
    """(folder, result) of a small calibration of ``key`` in a new temporary folder, for
    tests that read rendered PDFs (pdftotext must be installed)."""
    if shutil.which("pdftotext") is None:
        pytest.fail("pdftotext not found: run scripts/install-test-system-deps.sh")
    d = tmp_path_factory.mktemp(key)
    return d, small_result(key, d)[0]


@pytest.fixture(scope="module", params=("ogam-draft", "jjf1535-2015", "iec62047-20",
                                        "triad-alignment"))
def calibrated(request, tmp_path_factory):
    if shutil.which("pdftotext") is None:
        pytest.fail("pdftotext not found: run scripts/install-test-system-deps.sh")
    d = tmp_path_factory.mktemp(request.param)
    result, readings = small_result(request.param, d)
    lab = d / "lab-zh.toml"
    lab.write_text(LAB_ZH + '[decision_rule]\nrule = "non-binary"\nguard_band_factor = 1.0\n'
                   + "".join(f'[[specification_limits]]\nitem = "{k}"\nmpe = 1.0e6\n'
                             f'source = "制造商技术指标"\n' for k in LIMITS[request.param]),
                   encoding="utf-8")
    return {"key": request.param, "result": result, "dir": d, "lab": lab,
            "readings": readings}


def _write(c, out, lab):
    from gonio.pipeline.dispatch import decide_conformity
    from gonio.specs import get
    lab_d = load_lab(lab) if lab else None
    decide_conformity(c["result"], lab_d)          # the pipeline's one decision
    return get(c["key"]).renderer().write(c["result"], out, lab=lab_d, lang="zh", dcc=True)


def _json(c) -> dict:
    return c["result"].to_json()


def _allowed(c, lab) -> set:
    res = _json(c)
    ok = set(WHITELIST)
    for f in res.get("findings") or []:       # the readings' own test and column names
        ok |= set(WORD.findall(f"{f.get('test') or ''} {f.get('column') or ''}"))
    ok |= set(WORD.findall(str((res.get("settings") or {}).get("protocol") or "")))
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
    # the zh DCC carries Chinese beside every English text, and the Chinese is Chinese
    doc = (out / "certificate.dcc.xml").read_text(encoding="utf-8")
    assert doc.count('lang="zh"') >= 4 and "<dcc:usedLangCodeISO639_1>zh<" in doc
    root = etree.fromstring(doc.encode("utf-8"))
    for el in root.iter(f"{{{DCC_NS}}}content"):
        bad = sorted({w for w in WORD.findall(el.text or "") if w not in allowed})
        if el.get("lang") == "zh":
            assert not bad, f"{calibrated['key']} zh DCC: English words {bad} in {el.text!r}"
        elif bad:
            nxt = el.getnext()
            assert el.get("lang") == "en" and nxt is not None and nxt.get("lang") == "zh", \
                f"{calibrated['key']} zh DCC: no Chinese beside {el.text!r}"
    if calibrated["key"] == "ogam-draft":        # the findings and the item not measured
        assert "第 3 测回（270°）在各组中均缺失" in text and "[剔除]" in text and "未测" in text
        # "beyond the draft" once per budget row (was "…（超出草案） (超出草案)")
        assert not re.search(r"超出草案[）)]?\s*[（(]超出草案", re.sub(r"\s+", " ", text))


def test_the_check_can_fail(calibrated, tmp_path):
    """An English phrase slipped into a Chinese certificate is caught."""
    allowed = _allowed(calibrated, None)
    assert [w for w in WORD.findall("偏差 the scale factor") if w not in allowed]


def test_every_budget_source_and_reason_in_chinese(calibrated):
    """Every budget line's source of every rate item, those of u 0 included (the certificate's
    budget table leaves them out, so the page test above cannot see them: on the small
    programme JJF 7.2.9's t_w, "spread of the N records' times", is such a line), and every
    not-measured reason, as the zh certificate writes them: no English word."""
    from gonio.report.i18n import labels, reason_text
    from gonio.report.rate_certificate import component_source
    from gonio.specs import content_field, get

    if calibrated["key"] not in ("jjf1535-2015", "iec62047-20"):
        pytest.skip("the rate specifications' budget sources")
    L, res = labels("zh"), _json(calibrated)
    phrases = content_field(get(calibrated["key"]).content(), "PHRASES_ZH")
    allowed = _allowed(calibrated, None)
    seen = 0
    for key, it in res["items"].items():
        texts = [component_source(c, L, phrases)
                 for c in (it.get("uncertainty") or {}).get("components") or []]
        if not it["measured"]:
            texts.append(reason_text(it["reason"], L, phrases))
        for t in texts:
            seen += 1
            bad = sorted({w for w in WORD.findall(t) if w not in allowed})
            assert not bad, f"{calibrated['key']} {key}: English words {bad} in {t!r}"
    assert seen > 40


def test_the_test_names_reason_in_chinese():
    """An item not measured for want of its test's records (each rate specification's items)
    says so in Chinese, the test's name kept as the readings write it."""
    from gonio.report.i18n import labels, reason_text
    from gonio.specs import content_field, get

    for key in ("jjf1535-2015", "iec62047-20"):
        zh = reason_text("no 'sf_temperature' records in the readings", labels("zh"),
                         content_field(get(key).content(), "PHRASES_ZH"))
        assert "sf_temperature" in zh and "读数中无" in zh, zh
        assert not [w for w in WORD.findall(zh) if w not in WHITELIST | {"sf_temperature"}]
