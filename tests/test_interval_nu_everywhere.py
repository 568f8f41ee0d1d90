"""An item stated by an interval that is not a χ² one, but whose coverage factor came from a
ν_eff, states that ν_eff wherever the certificate prints it in its ν_eff column: JJF 7.2.9's
warm-up time (its U = k·u_c with k = t_p(ν_eff) reaches below zero, so it is stated by its
upper bound value + U; ν_eff = 7 in the demo) and the triad's bound-condition intervals
value ± (a + k·u_rest) (M_xy, S_xy: k = t_p(ν_eff) of u_rest; S and L show it in their
cross-axis table's cells). summary.txt ends the line with
"; ν_eff = N", the DCC writes a gonio_degreesOfFreedom quantity (rule "nu") after the item's,
and N is the certificate's span. N is worked out here from results.json (the integer part of
its ν_eff, GUM G.6.4) and checked to be the ν the coverage factor came from with scipy's t
quantile, never read from gonio's statement.
"""
from __future__ import annotations

import json
import math
import re

import pytest
from lxml import etree
from scipy.stats import t as student_t

from gonio.report.dcc import DCC_NS, SI_NS
from tests.statement_numbers import certificate_spans, nu_eff_interval_items

NS = {"dcc": DCC_NS, "si": SI_NS}

#: (specification, seed of its shared demo, the items that must be found)
CASES = [("jjf1535-2015", 1, {"warmup_time"}), ("iec62047-20", 3, {"scale_factor", "bias"}),
         ("triad-alignment", 5, {"M_xy", "M_xx", "S_xy"})]


def k_of(it: dict) -> float:
    """The coverage factor the item's interval was built with: its own k, or a bound
    condition's k of u_rest."""
    unc = it["uncertainty"]
    if unc.get("k") is not None:
        return unc["k"]
    return it["details"]["bound_condition"]["k_rest"]


@pytest.mark.parametrize("spec, seed, must", CASES)
def test_interval_nu_eff_in_summary_dcc_and_certificate(shared_demo, spec, seed, must):
    out = shared_demo(spec, seed=seed)
    res = json.loads((out / "results.json").read_text(encoding="utf-8"))
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    html = (out / "certificate.html").read_text(encoding="utf-8")
    spans = certificate_spans(html)
    root = etree.fromstring((out / "certificate.dcc.xml").read_bytes())
    items = nu_eff_interval_items(res)
    assert must <= set(items), sorted(items)
    for key, nu in items.items():
        it = res["items"][key]
        p = it["uncertainty"]["coverage_probability"]
        # the ν stated is the one the coverage factor came from (scipy, not gonio)
        dof = math.inf if nu == "∞" else float(nu)
        assert k_of(it) == pytest.approx(student_t.ppf(0.5 + p / 2, dof), rel=2e-3), key
        # the certificate's ν_eff column (the triad's: its bound-condition table's ν)
        shown = spans.get((key, "uncertainty.nu_eff")) or set(re.findall(
            rf'data-src="items\.{key}\.details\.bound_condition\.nu_rest"[^>]*>([^<]*)<',
            html))
        # (the triad's S and L, ratios of M's entries, have no row in that table: their
        # cells in the cross-axis table carry it)
        assert shown == {str(nu)}, (key, shown)
        # summary.txt: the item's line ends with it
        line = next(ln for ln in summary.splitlines() if f"{it['title']}:" in ln
                    and ln.strip().startswith(it["clause"] or it["title"]))
        assert line.endswith(f"; ν_eff = {nu}"), (key, line)
        # the DCC: one degrees-of-freedom quantity, rule "nu", the same number
        result = root.find(f".//dcc:result[@id='result-{key}']", NS)
        qs = [q for q in result.iterfind(".//dcc:quantity", NS)
              if q.get("refType") == "gonio_degreesOfFreedom"]
        if nu == "∞":                  # no si:real holds ∞: the normal k, as for value ± U
            assert qs == [], key
            continue
        assert len(qs) == 1, (key, len(qs))
        real = qs[0].find("si:real", NS)
        comment = real.getprevious()
        assert isinstance(comment, etree._Comment) and re.match(
            rf" src=items\.{key}\.uncertainty\.nu_eff rule=nu ", comment.text), key
        assert real.find("si:value", NS).text == str(nu), key
        assert real.find("si:unit", NS).text == r"\one"
        assert "effective degrees of freedom ν_eff" in "".join(
            qs[0].find("dcc:name", NS).itertext())


def test_jjf_warm_up_nu_is_seven(shared_demo):
    """The brief's case: the JJF demo's warm-up time, ν_eff = 7, on the certificate, in
    summary.txt, in the DCC."""
    out = shared_demo("jjf1535-2015", seed=0)
    res = json.loads((out / "results.json").read_text(encoding="utf-8"))
    assert nu_eff_interval_items(res)["warmup_time"] == "7"
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    assert re.search(r"warm-up time: .*; upper bound: ≤ .*; ν_eff = 7\n", summary), summary


def test_the_nu_eff_quantity_is_named_in_chinese():
    from gonio.report.dcc import INTERVAL_NU_EFF
    from gonio.report.i18n import translator

    zh = translator({"warm-up time": "预热时间"})(f"warm-up time: {INTERVAL_NU_EFF}")
    assert zh == "预热时间：其区间的包含因子计算所用的有效自由度 ν_eff", zh


def test_an_item_stated_by_its_upper_bound_alone_keeps_its_nu(shared_demo):
    """An estimate fallen below zero (the warm-up time's, set to −5 s here: stated "≤ 28 s"
    alone) keeps the ν_eff its bound's k came from in summary.txt and the DCC, as the
    certificate's ν_eff column prints it."""
    from gonio.report.item_outputs import summary
    from gonio.report.rate_certificate import results_table
    from gonio.report.rate_content import spec_content
    from gonio.report.rate_dcc import rate_dcc_bytes
    from gonio.report.i18n import labels
    from gonio.result.model import Result

    out = shared_demo("jjf1535-2015", seed=0)
    doc = json.loads((out / "results.json").read_text(encoding="utf-8"))
    it = doc["items"]["warmup_time"]
    it["value"] = -5.0
    nu = str(math.floor(it["uncertainty"]["nu_eff"]))
    assert nu == "7"
    result = Result.from_json(doc)
    line = next(ln for ln in summary(result).splitlines() if "warm-up time:" in ln)
    assert "the estimate fell below zero" in line and line.endswith(f"; ν_eff = {nu}"), line
    _, rows = results_table(result.to_json(), spec_content("jjf1535-2015"), labels("en"), "en")
    row = next(r for r in rows if r[2] == "7.2.9")
    assert str(row[6]) == nu, row
    root = etree.fromstring(rate_dcc_bytes(result, cert_id="T"))
    r = root.find(".//dcc:result[@id='result-warmup_time']", NS)
    qs = [q for q in r.iterfind(".//dcc:quantity", NS)
          if q.get("refType") == "gonio_degreesOfFreedom"]
    assert [q.find("si:real/si:value", NS).text for q in qs] == [nu]
