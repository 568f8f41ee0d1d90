"""One statement per result cell, one p and one set of measurand conditions in every output,
checked from the outside: the CLI's demo is run and every output it writes is parsed
(certificate HTML, en and zh; summary.txt; results.json; tables/items.csv; the DCC XML).

* The optical certificate's result cells hold the item's statement alone: no reading of the
  draft, no range/T, no spread, no correction beside it; every such reading is in the one
  labelled table beside the results (``id="beside"``), each number equal to results.json.
  The line under the table names U as what it is (each point's U), not "Certified".
* A computed coverage probability (JJF 7.2.6/7.2.7) is the same p in the certificate,
  summary.txt, the DCC, items.csv and results.json (``p_stated``, ``u_c_of``), rounded down.
* JJF 7.2.9's window W, block P and nominal stability are in the certificate, summary.txt
  and the DCC, with the numbers results.json stores.
"""

from __future__ import annotations

import csv
import html
import json
import math
import re

import pytest
from lxml import etree

from gonio.report.dcc import DCC_NS, SI_NS

NS = {"dcc": DCC_NS, "si": SI_NS}

SUP = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻", "0123456789-")


def _number(text: str) -> float:
    """A printed number ("4.36×10⁻⁵", "−0.18", "76434.844") as a float."""
    t = html.unescape(text).replace("−", "-").replace("\u2009", "").replace("±", "")
    mant, _, exp = t.partition("×10")
    return float(mant) * (10.0 ** int(exp.translate(SUP)) if exp else 1.0)


def _last_digit(text: str) -> float:
    """Half a unit of the last digit printed (the rounding a printed number may carry)."""
    t = html.unescape(text).replace("−", "-")
    mant, _, exp = t.partition("×10")
    dec = len(mant.partition(".")[2])
    return 0.5 * 10.0 ** (-dec) * (10.0 ** int(exp.translate(SUP)) if exp else 1.0)


def _get(res: dict, src: str):
    node = res
    for part in src.split("."):
        node = node[int(part)] if isinstance(node, list) else node[part]
    return node


def _table(page: str, ident: str) -> str:
    m = re.search(rf'<table id="{ident}">(.*?)</table>', page, re.S)
    assert m, ident
    return m.group(1)


def _spans(fragment: str) -> list[tuple[str, str]]:
    return re.findall(r'<span class="num" data-src="([^"]+)"[^>]*>([^<]*)</span>', fragment)


def _text(fragment: str) -> str:
    text = html.unescape(re.sub(r"<[^>]+>", "", fragment))
    return re.sub(r"[\u00a0\u2009\u202f]", " ", text)


#: The demos read here are the session's shared ones (``gonio demo --spec X --seed 3 [--lang
#: zh]``, made once for every file that reads them; read only): seed 3 as the other files'.
SEED = 3


@pytest.fixture(scope="module")
def optical(shared_demo):
    out = {}
    for lang in ("en", "zh"):
        d = shared_demo("ogam-draft", lang=lang, seed=SEED)
        out[lang] = {"html": (d / "certificate.html").read_text(encoding="utf-8"),
                     "res": json.loads((d / "results.json").read_text(encoding="utf-8"))}
    return out


@pytest.fixture(scope="module")
def jjf(shared_demo):
    d = shared_demo("jjf1535-2015", seed=SEED)
    with open(d / "tables" / "items.csv", encoding="utf-8", newline="") as f:
        rows = {r["item"]: r for r in csv.DictReader(f)}
    return {"res": json.loads((d / "results.json").read_text(encoding="utf-8")),
            "summary": (d / "summary.txt").read_text(encoding="utf-8"),
            "html": (d / "certificate.html").read_text(encoding="utf-8"),
            "dcc": etree.parse(str(d / "certificate.dcc.xml")).getroot(), "items": rows}


#: The fields of an item a result cell may show: its statement (value, max|E_i| and its
#: sign, the interval's ends or bound, U, k) and the point it is at.
CELL_FIELDS = re.compile(r"^items\.[a-z_]+\.(value|upper_bound|uncertainty\.[A-Za-z_.0-9]+|"
                         r"details\.(max_abs_arcsec|signed_extreme_arcsec|position_deg))$")
#: What only the table beside the results may show.
BESIDE = re.compile(r"estimates\.|range_deg_per_h|spread_arcsec|tilt_correction|"
                    r"table_calibration|draft_reading")


@pytest.mark.parametrize("lang", ["en", "zh"])
def test_optical_result_cells_hold_the_statement_alone(optical, lang):
    page, res = optical[lang]["html"], optical[lang]["res"]
    cells = _table(page, "results")
    for src, _ in _spans(cells):
        assert CELL_FIELDS.match(src), src
    words = ("beside", "not stated", "draft", "range/T", "uncorrected", "spread",
             "并列", "草案", "极差", "未修正")
    for word in words:
        assert word not in _text(cells), word
    # every reading that was beside a statement is in the one table beside the results,
    # and nowhere else on the page; each number is results.json's, rounded
    beside = _table(page, "beside")
    shown = {src: text for src, text in _spans(beside)}
    for src, text in shown.items():
        raw = _get(res, src)
        raw = abs(raw) if "±" in text else raw       # max|E_i| ± U: the magnitude
        assert abs(_number(text) - raw) <= _last_digit(text) * 1.000001, (src, text, raw)
    rest = page.replace(beside, "")
    assert not [s for s, _ in _spans(rest) if BESIDE.search(s)]
    items = res["items"]
    want = {f"items.{k}.details.estimates.draft.value"
            for k in ("scale_factor_nonlinearity", "rate_consistency", "pointing_consistency")
            if items[k]["measured"] and (items[k]["details"].get("estimates") or {}).get("draft")}
    if items["zero_stability"]["measured"]:
        want.add("items.zero_stability.details.range_deg_per_h")
    if (res["extra"]["uncertainty"].get("draft_reading") or {}).get("U_arcsec") is not None:
        want.add("extra.uncertainty.draft_reading.U_arcsec")
    assert want and want <= set(shown), want - set(shown)
    title = ("The draft's readings and the notes on the results, given beside and not "
             "certified" if lang == "en" else "草案的读数及结果的说明（并列给出，不作为校准结果）")
    assert _text(page).count(title) == 1
    # the line under the results names U for what it is: no "Certified:" on the page
    assert "Certified:" not in _text(page)


def _floor_p(p: float) -> str:
    """A computed coverage probability as stated, worked out here: per cent, two
    significant digits, rounded down (more decimals only where it rounds to 100)."""
    for dec in range(0, 6):
        v = math.floor(p * 100 * 10 ** dec) / 10 ** dec
        if v < 100:
            return f"{v:.{dec}f}"
    raise AssertionError(p)


@pytest.mark.parametrize("key", ["threshold", "resolution"])
def test_a_computed_p_is_stated_the_same_everywhere(jjf, key):
    u = jjf["res"]["items"][key]["uncertainty"]
    p = u["coverage_probability"]
    assert not math.isclose(p * 100, round(p * 100))     # a computed p, not a chosen one
    text = _floor_p(p)
    stated = f"p ≈ {text} %"
    assert u["p_stated"] == stated
    assert stated in u["u_c_of"] and "95 %" not in u["u_c_of"]
    assert float(jjf["items"][key]["p"]) == pytest.approx(float(text) / 100, abs=1e-12)
    line = next(ln for ln in jjf["summary"].splitlines()
                if ln.strip().startswith(jjf["res"]["items"][key]["clause"]))
    assert f"(p ≈ {text} %)" in line
    assert f"(p ≈ {text} %)" in _text(_table(jjf["html"], "results"))
    res_el = jjf["dcc"].find(f".//dcc:result[@id='result-{key}']", NS)
    cp = res_el.find(".//si:coverageProbability", NS)
    assert float(cp.text) == pytest.approx(float(text) / 100, abs=1e-12)


def test_a_chosen_p_is_unchanged(jjf):
    for key, it in jjf["res"]["items"].items():
        u = it.get("uncertainty") or {}
        if it["measured"] and u.get("coverage_probability") == 0.95:
            assert u["p_stated"] == "p = 95 %", key
            assert float(jjf["items"][key]["p"]) == 0.95, key


def test_warmup_conditions_in_every_output(jjf):
    d = jjf["res"]["items"]["warmup_time"]["details"]
    w, p, nominal = d["window_samples"], d["block_samples"], d["nominal_stability_dph"]
    want = (f"W = {w} samples", f"P = {p} samples", f"nominal {nominal:g} °/h")
    dcc_el = jjf["dcc"].find(".//dcc:result[@id='result-warmup_time']/dcc:description",
                             NS)
    assert dcc_el is not None
    dcc_text = "".join(dcc_el.itertext())
    summary = [ln for ln in jjf["summary"].splitlines() if "7.2.9" in ln and "W = " in ln]
    assert len(summary) == 1
    for text in (_text(jjf["html"]), dcc_text, summary[0]):
        for part in want:
            assert part in text, (part, text[:200])


def test_warmup_conditions_in_the_zh_dcc(shared_demo):
    """A zh DCC gives the sentence in Chinese beside the English, as the zh certificate."""
    d = shared_demo("jjf1535-2015", lang="zh", seed=SEED)
    res = json.loads((d / "results.json").read_text(encoding="utf-8"))
    det = res["items"]["warmup_time"]["details"]
    desc = etree.parse(str(d / "certificate.dcc.xml")).getroot().find(
        ".//dcc:result[@id='result-warmup_time']/dcc:description", NS)
    zh = [c.text for c in desc.findall("dcc:content", NS) if c.get("lang") == "zh"]
    assert len(zh) == 1
    for part in (f"W = {det['window_samples']} 个采样", f"P = {det['block_samples']} 个采样",
                 f"标称值 {det['nominal_stability_dph']:g} °/h"):
        assert part in zh[0], part
        assert part in _text((d / "certificate.html").read_text(encoding="utf-8"))


def test_warmup_records_spread_is_its_type_a_and_k_from_nu_eff(jjf):
    """JJF 7.2.9: the N records' times enter u as the Type A line s/√N on ν = N − 1 (not
    u = 0 beside records that differ), and k is t₉₅ at the Welch–Satterthwaite ν_eff the
    uncertainty states (rounded down, as printed) — each recomputed here from the stored times and rows."""
    from scipy import stats

    it = jjf["res"]["items"]["warmup_time"]
    t = [float(x) for x in it["details"]["t_n_s"]]
    n = len(t)
    mean = sum(t) / n
    s = math.sqrt(sum((x - mean) ** 2 for x in t) / (n - 1))
    u = it["uncertainty"]
    rows = {r["symbol"]: r for r in u["components"]}
    assert rows["t_w"]["type"] == "A"
    assert rows["t_w"]["u"] == pytest.approx(s / math.sqrt(n), rel=1e-12)
    uc = math.sqrt(sum(r["contribution"] ** 2 for r in u["components"]))
    assert u["u_c"] == pytest.approx(uc, rel=1e-9)
    if s > 0:
        assert rows["t_w"]["dof"] == n - 1
        nu = uc ** 4 / ((s / math.sqrt(n)) ** 4 / (n - 1))       # the others: ν = ∞
        assert u["nu_eff"] == pytest.approx(nu, rel=1e-9)
        # k from ν_eff rounded down, the ν printed (the statement rule)
        assert u["k"] == pytest.approx(float(stats.t.ppf(0.975, math.floor(nu))), rel=1e-9)
        assert u["U"] == pytest.approx(u["k"] * uc, rel=1e-9)
        line = next(ln for ln in jjf["summary"].splitlines() if ln.strip().startswith("7.2.9"))
        if "±" in line:                                   # k printed: its ν_eff beside it
            assert f"ν_eff = {int(nu)}" in line, line
