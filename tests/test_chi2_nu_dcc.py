"""The DCC states an item stated by a χ² interval with the ν that interval was computed with:
the optical draft's zero stability B_s and repeatability R, the rate specifications' bias
stability, K_r, B_r, ARW. Its ν is the certificate's (the number its ν column prints, the
integer part of results.json's ν_eff), in a quantity of its own after the item's
(gonio.report.dcc.nu_quantity), and the interval's upper end computed again from that ν
(JCGM 100 E.4.3: s·√(ν/χ²_{1−p}(ν))) is results.json's and within the DCC's
si:intervalMax. The DCC stays valid against the DCC 3.3.0 schema, and a zh DCC names the
quantity in Chinese."""
from __future__ import annotations

import json
import math
import re

import pytest
from lxml import etree
from scipy.stats import chi2

from gonio.report.dcc import DCC_NS, SI_NS
from gonio.resources import protocols_dir
from gonio.result.statement import K_SOURCE_CHI2, chi2_nu, chi2_stated_nu
from tests.statement_numbers import certificate_spans

NS = {"dcc": DCC_NS, "si": SI_NS}

#: (specification, laboratory file or None, the χ² items its demo must state)
CASES = [("ogam-draft", "lab-example.toml", {"zero_stability", "repeatability"}),
         ("jjf1535-2015", None, {"bias_stability", "sf_repeatability", "bias_repeatability"})]


def _demo(shared_demo, spec, lab):
    out = shared_demo(spec, seed=1, lab=None if lab is None else protocols_dir() / lab)
    return (out, json.loads((out / "results.json").read_text(encoding="utf-8")),
            etree.fromstring((out / "certificate.dcc.xml").read_bytes()),
            (out / "certificate.html").read_text(encoding="utf-8"))


def chi2_items(res: dict) -> dict:
    """The measured items of results.json ``res`` stated by a χ² interval."""
    return {k: it for k, it in res["items"].items() if it.get("measured")
            and (it.get("uncertainty") or {}).get("interval") is not None
            and (it.get("uncertainty") or {}).get("k") is None
            and chi2_stated_nu((it.get("uncertainty") or {}).get("k_source"))}


@pytest.mark.parametrize("spec, lab, must", CASES)
def test_dcc_states_the_nu_of_each_chi2_interval(shared_demo, dcc_schema, spec, lab, must):
    out, res, root, html = _demo(shared_demo, spec, lab)
    spans = certificate_spans(html)
    items = chi2_items(res)
    assert must <= set(items), sorted(items)
    for key, it in items.items():
        unc = it["uncertainty"]
        nu = chi2_nu(unc["nu_eff"])
        result = root.find(f".//dcc:result[@id='result-{key}']", NS)
        qs = [q for q in result.iterfind(".//dcc:quantity", NS)
              if q.get("refType") == "gonio_degreesOfFreedom"]
        assert len(qs) == 1, (key, len(qs))
        q = qs[0]
        real = q.find("si:real", NS)
        comment = real.getprevious()
        assert isinstance(comment, etree._Comment) and re.match(
            rf" src=items\.{key}\.uncertainty\.nu_eff rule=nuchi2 ", comment.text), key
        shown = real.find("si:value", NS).text
        assert real.find("si:unit", NS).text == r"\one"
        # the certificate's ν, results.json's ν_eff as stated (its integer part)
        assert shown == f"{nu:g}" == str(math.floor(unc["nu_eff"])), (key, shown)
        assert spans.get((key, "uncertainty.nu_eff")) == {shown}, (key, spans.get(
            (key, "uncertainty.nu_eff")))
        assert "degrees of freedom ν" in "".join(q.find("dcc:name", NS).itertext())
        # it follows the item's own quantity (and, for a bound condition, its ends' list)
        assert q.getprevious().tag == f"{{{DCC_NS}}}quantity", key
        if unc["k_source"] != K_SOURCE_CHI2:
            continue                  # a bound-condition limit: s + a + R, not s alone
        p = unc.get("coverage_probability") or 0.95
        upper = it["value"] * math.sqrt(float(shown) / chi2.ppf(1 - p, float(shown)))
        assert upper == pytest.approx(unc["interval"][1], rel=1e-6), key
        ci = result.find(".//si:coverageIntervalMU", NS)
        if ci is not None:
            assert float(ci.find("si:intervalMax", NS).text) >= upper * (1 - 1e-12), key
    errors = list(dcc_schema.iter_errors(etree.tostring(root).decode("utf-8")))
    assert not errors, str(errors[0])[:500]


def test_an_item_stated_otherwise_has_no_nu_quantity(shared_demo):
    """Only the ν printed beside an interval is written so: a χ² interval's ν, or the ν_eff
    of another interval's coverage factor (named so: tests/test_interval_nu_everywhere.py);
    an item stated by value ± U (its k in si:coverageFactor) or by an interval no ν defines
    has none."""
    from tests.statement_numbers import nu_eff_interval_items

    _, res, root, _ = _demo(shared_demo, "jjf1535-2015", None)
    chi = chi2_items(res)
    other = nu_eff_interval_items(res)
    for q in root.iter(f"{{{DCC_NS}}}quantity"):
        if q.get("refType") == "gonio_degreesOfFreedom":
            key = q.getparent().getparent().get("id").removeprefix("result-")
            name = "".join(q.find("dcc:name", NS).itertext())
            assert key in chi or key in other, key
            assert ("chi-square" in name) == (key in chi), (key, name)


def test_the_nu_quantity_is_named_in_chinese():
    from gonio.report.dcc import CHI2_NU
    from gonio.report.i18n import translator

    zh = translator({"bias stability B_s": "零偏稳定性 B_s"})(
        f"bias stability B_s: {CHI2_NU}")
    assert zh == "零偏稳定性 B_s：其 χ² 区间计算所用的自由度 ν", zh
