"""An item stated only by its coverage interval: the DCC writes the interval and, as its
si:value, the value the certificate's statement rounds (sign and digits). A non-negative
quantity whose bias-corrected estimate fell below zero is stated on the certificate by its
upper bound alone ("≤ upper (interval [0, upper])"): the DCC writes that bound as its
si:value (the one number the certificate prints: never the negative estimate, which lies
outside its own interval and no page prints), and its description says that the statement
is the bound. Checked through the writers every DCC uses (the rate and per-item DCCs'
:func:`gonio.report.stated.item_nums` → :func:`gonio.report.dcc.quantity`), on numbers
written here, with the interval's ends worked out independently of the statement rule."""

from __future__ import annotations

import math
from decimal import ROUND_CEILING, Decimal

import pytest
from lxml import etree

from gonio.report.dcc import DCC_NS, SI_NS, element, quantity
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
def test_dcc_value_of_an_estimate_below_zero_is_its_printed_bound(value, U, interval):
    it = _item(value, U, interval)
    n = item_nums(it, "items.x")
    st = n["statement"]
    assert st.below_zero and n["interval"] is not None
    root = element(etree.Element("root", nsmap={"dcc": DCC_NS, "si": SI_NS}), "dcc:data")
    quantity(root, "x", n["stated_value"], "%", interval=n["interval"]["ends"],
             u_std=n["interval"]["u"], p=0.95, description=st.text())
    v = float(root.find(".//si:real/si:value", NS).text)
    lo = float(root.find(".//si:intervalMin", NS).text)
    hi = float(root.find(".//si:intervalMax", NS).text)
    # the interval as the certificate states it: [0, upper], upper = the interval's end
    # rounded up at two significant digits of its distance from 0
    end = interval[1] if interval else value + U
    q = Decimal(1).scaleb(-(2 - 1 - Decimal(repr(end)).adjusted()))
    assert lo == 0.0 and hi == float(Decimal(repr(end)).quantize(q, rounding=ROUND_CEILING))
    # si:value: that bound, as printed (never the negative estimate outside [0, upper])
    text = root.find(".//si:real/si:value", NS).text
    assert not text.startswith("-") and v == hi and v > value
    assert math.isclose(v, float(Decimal(repr(end)).quantize(q, rounding=ROUND_CEILING)),
                        rel_tol=1e-12)
    assert "below zero" in root.find(".//dcc:description/dcc:content", NS).text
    assert st.upper_text in root.find(".//dcc:description/dcc:content", NS).text


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
