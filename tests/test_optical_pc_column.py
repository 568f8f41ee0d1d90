"""The optical certificate's conformity table has the probability-of-conformance column the
rate certificates have, in English and Chinese, with the number its DCC, summary.txt and the
records' page state (three significant digits, "99.4 %"), and "—" where no probability is
given, with the note naming the item. The χ² item's p_c (repeatability R, σ's χ²
distribution about s: P(σ ≤ T) = P(χ²_ν ≥ ν·s²/T²)) is worked out here with scipy from
results.json's s, ν and limit, never read from gonio.
"""
from __future__ import annotations

import html as html_lib
import json
import re

import pytest
from lxml import etree
from scipy.stats import chi2

from gonio.resources import protocols_dir

LAB = protocols_dir() / "lab-example.toml"


def table_rows(html: str) -> list[list[str]]:
    """The conformity table's header and rows as cell texts."""
    i = html.index('id="conformity"')
    table = html[i:html.index("</table>", i)]
    rows = []
    for tr in re.findall(r"<tr[^>]*>(.*?)</tr>", table, re.S):
        cells = re.findall(r"<t[hd][^>]*>(.*?)</t[hd]>", tr, re.S)
        rows.append([html_lib.unescape(re.sub(r"<[^>]+>", "", c)).replace("\xa0", " ").strip()
                     for c in cells])
    return rows


@pytest.fixture(scope="module")
def optical(shared_demo, tmp_path_factory):
    from gonio.records.compute import render_folder

    out = shared_demo("ogam-draft", seed=1, lab=LAB)
    zh = tmp_path_factory.mktemp("zh")
    render_folder((out / "results.json").read_bytes(), zh, spec_key="ogam-draft", lab=LAB,
                  lang="zh")
    return out, zh, json.loads((out / "results.json").read_text(encoding="utf-8"))


@pytest.mark.parametrize("lang", ["en", "zh"])
def test_optical_conformity_table_has_the_pc_column(optical, lang):
    from gonio.report.i18n import labels

    out, zh, res = optical
    d = out if lang == "en" else zh
    L = labels(lang)
    rows = table_rows((d / "certificate.html").read_text(encoding="utf-8"))
    head, body = rows[0], rows[1:]
    assert head[4] == L["c_pc"] and head[5] == L["c_pfa"] and len(head) == 6, head
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    dcc = etree.parse(str(d / "certificate.dcc.xml")).getroot()
    decided = {k: it for k, it in res["items"].items() if it.get("conformity")}
    assert len(body) == len(decided) and "repeatability" in decided
    for key, row in zip(decided, body):
        c = decided[key]["conformity"]
        assert len(row) == 6, row
        pc = c["conformance_probability"]
        if pc is None:
            assert row[4] == "—", row
            continue
        want = f"{100 * pc:#.3g}".rstrip(".") + " %"
        assert row[4] == want, (row, want)
        line = next(ln for ln in summary.splitlines() if ln.startswith(f"conformity {key}:"))
        assert f"probability of conformance {want}" in line, line
        # the DCC's p_c at the same digits (a fraction)
        texts = [etree.tostring(q, encoding="unicode") for q in dcc.iter(
            "{*}quantity") if "conformance" in "".join(q.itertext())]
        frac = f"{pc:#.3g}"
        assert any(f">{frac}<" in t for t in texts), (key, frac)
    # an item without a probability: "—" in the column and named by the note
    dash = [L["angle_deviation"] if "angle_deviation" in L else k
            for k, it in decided.items() if it["conformity"]["conformance_probability"] is None]
    if dash:
        text = html_lib.unescape(re.sub(r"<[^>]+>", "", (d / "certificate.html").read_text(
            encoding="utf-8")))
        note = L["c_no_p_note"].split("{items}")[0]
        assert note in text


def test_optical_repeatability_pc_is_the_chi2_probability(optical):
    """scipy: σ's χ² distribution about s with the stated ν; p_c = P(σ ≤ T)."""
    _, _, res = optical
    it = res["items"]["repeatability"]
    c = it["conformity"]
    nu = int(it["uncertainty"]["nu_eff"])
    s, T = it["value"], c["upper"]
    assert c["lower"] is None and c["probability_model"].startswith("chi-square")
    p = chi2.sf(nu * s * s / T ** 2, nu)
    assert c["conformance_probability"] == pytest.approx(p, abs=5e-4)
