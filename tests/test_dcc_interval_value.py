"""An item stated only by its coverage interval: the DCC writes the interval and, as its
si:value, the value the certificate's statement rounds (sign and digits). A non-negative
quantity whose bias-corrected estimate fell below zero is stated on the certificate by its
upper bound alone ("≤ upper (interval [0, upper])"): every DCC (the optical draft's, the rate
and per-item DCCs) writes its interval [0, upper] alone, with no si:value — neither the bound
nor the negative estimate is a measured value — and the statement with its note as the
description. Checked through the writer every DCC uses
(:func:`gonio.report.dcc.below_zero_quantity`, from :func:`gonio.report.stated.item_nums`),
on numbers written here, with the interval's ends worked out independently of the
statement rule."""

from __future__ import annotations

import math
from decimal import ROUND_CEILING, Decimal

import pytest
from lxml import etree

from gonio.report.dcc import DCC_NS, SI_NS, below_zero_quantity, element, quantity
from gonio.report.stated import item_nums

NS = {"dcc": DCC_NS, "si": SI_NS}


def _item(value, U, interval=None):
    unc = {"U": U, "u_c": U / 2, "k": None if interval else 2.0, "nu_eff": None,
           "coverage_probability": 0.95, "k_source": "neyman-belt" if interval else "x"}
    if interval:
        unc["interval"] = list(interval)
    return {"value": value, "unit": "%", "measured": True, "nonnegative": True,
            "clause": "7.7", "uncertainty": unc}


@pytest.mark.parametrize("value, U, interval", [
    (-1.5776118482164668e-05, 5.477989761853442e-05, (0.0, 3.900377913636975e-05)),  # C_g
    (-0.5, 2.54, (0.0, 2.04)),
    (-3.0, 4.0, None),          # a ± U item below zero: [0, value + U] by the rule
])
def test_dcc_of_an_estimate_below_zero_is_its_interval_alone(value, U, interval):
    it = _item(value, U, interval)
    n = item_nums(it, "items.x")
    st = n["statement"]
    assert st.below_zero and n["interval"] is not None
    root = element(etree.Element("root", nsmap={"dcc": DCC_NS, "si": SI_NS}), "dcc:data")
    below_zero_quantity(root, "x", n["interval"]["ends"], "\\percent", 0.95,
                        description=st.text())
    # no value at all: neither the bound nor the negative estimate is one
    assert root.find(".//si:real", NS) is None and root.find(".//si:value", NS) is None
    labels = root.find(".//si:realListXMLList/si:labelXMLList", NS).text
    lo, hi = (float(x) for x in
              root.find(".//si:realListXMLList/si:valueXMLList", NS).text.split())
    assert labels == "intervalMin intervalMax"
    # the interval as the certificate states it: [0, upper], upper = the interval's end
    # rounded up at two significant digits of its distance from 0
    end = interval[1] if interval else value + U
    q = Decimal(1).scaleb(-(2 - 1 - Decimal(repr(end)).adjusted()))
    assert lo == 0.0 and hi == float(Decimal(repr(end)).quantize(q, rounding=ROUND_CEILING))
    assert math.isclose(hi, float(st.upper_text), rel_tol=1e-12)
    name = root.find(".//dcc:quantity/dcc:name/dcc:content", NS).text
    assert "upper bound alone" in name and name.endswith("p = 95 %")
    desc = root.find(".//dcc:description/dcc:content", NS).text
    assert "below zero" in desc and st.upper_text in desc


@pytest.mark.parametrize("spec", ["jjf1535-2015", "iec62047-20"])
def test_rate_dcc_states_a_below_zero_item_by_its_interval_alone(spec, shared_demo):
    """Through the rate DCC writer, on a demo's results.json with one non-negative item
    stated by its interval moved below zero (as a bias correction can take it): that item's
    dcc:result has no si:value and its interval [0, upper] as the certificate states it."""
    import json

    from gonio.report.rate_dcc import rate_dcc_tree
    from gonio.result.model import Result

    d = json.loads((shared_demo(spec) / "results.json").read_text(encoding="utf-8"))
    key = next(k for k, it in sorted(d["items"].items())
               if it["measured"] and it.get("nonnegative") and it["uncertainty"]
               and it["uncertainty"].get("k") is None
               and (it["uncertainty"].get("interval") or [None])[0] == 0.0)
    it = d["items"][key]
    hi = it["uncertainty"]["interval"][1]
    it["value"] = -0.2 * hi
    st = item_nums(it, f"items.{key}")["statement"]
    assert st.below_zero
    root = rate_dcc_tree(Result.from_json(d), cert_id="T-1")
    res = root.find(f".//dcc:result[@id='result-{key}']", NS)
    # no value of the item itself; the one si:real is the ν its interval was computed with
    # (its own gonio_degreesOfFreedom quantity, as the certificate's ν column prints it)
    reals = [q for q in res.iterfind(".//dcc:quantity", NS) if q.find("si:real", NS) is not None]
    assert [q.get("refType") for q in reals] == ["gonio_degreesOfFreedom"], key
    nu = item_nums(it, f"items.{key}")["interval_nu"]
    assert reals[0].find("si:real/si:value", NS).text == str(nu), key
    lo, up = res.find(".//si:realListXMLList/si:valueXMLList", NS).text.split()
    assert float(lo) == 0.0 and float(up) >= hi and up == st.upper_text
    assert "upper bound alone" in res.find(".//dcc:quantity/dcc:name/dcc:content", NS).text
    # every other measured item keeps its value
    assert len(root.findall(".//si:real/si:value", NS)) >= 10


def test_a_value_inside_its_interval_is_written_as_stated():
    it = _item(0.112, 0.092, (0.066, 0.204))
    it["nonnegative"] = False
    n = item_nums(it, "items.x")
    root = element(etree.Element("root", nsmap={"dcc": DCC_NS, "si": SI_NS}), "dcc:data")
    quantity(root, "x", n["value"], "%", interval=n["interval"]["ends"],
             u_std=n["interval"]["u"], p=0.95)
    assert root.find(".//si:real/si:value", NS).text == "0.112"


@pytest.mark.parametrize("value, U, interval", [
    (0.0607, None, (0.0496, 0.0692)), (0.01, 0.088, None), (-3.0, 4.0, None),
])
def test_a_zh_dcc_states_an_interval_statement_in_chinese(value, U, interval):
    """A DCC description that carries an item's interval statement (a per-g item's, a
    below-zero item's) reads in a zh DCC as the zh certificate states it."""
    from gonio.report.i18n import translator
    from gonio.result.statement import state, state_interval
    st = (state_interval(value, interval, p=0.95, unit="(°/s)/g") if interval else
          state(value, U, k=2.0, p=0.95, unit="s", nonnegative=True))
    assert translator()(st.text()) == st.text("zh")
