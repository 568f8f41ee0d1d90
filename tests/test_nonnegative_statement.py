"""A non-negative quantity is never stated with a negative bound: the statement rule refuses
an interval wholly at or below zero, bounds the others at or above zero, and an acceptance
interval of such a quantity that ends below zero is said to be empty."""

from __future__ import annotations

from decimal import Decimal
from types import SimpleNamespace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gonio.errors import GonioError
from gonio.report.i18n import labels
from gonio.report.stated import conformity_texts
from gonio.result.model import Item, Uncertainty
from gonio.result.statement import state
from gonio.specs._rate_family.rate_records import calibrate_items

vals = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)
Us = st.floats(min_value=1e-9, max_value=1e6, allow_nan=False)


def test_interval_below_zero_is_refused():
    with pytest.raises(GonioError, match="non-negative"):
        state(-5.0, 1.0, nonnegative=True, unit="s")
    with pytest.raises(GonioError):
        state(-1.0, 1.0, nonnegative=True)          # [−2, 0]: only 0, refused too
    # a quantity that may be negative is stated as ever
    assert state(-5.0, 1.0, unit="s").text() == "-5.0 ± 1.0 s"


@settings(max_examples=400, deadline=None)
@given(vals, Us)
def test_bound_is_never_negative_and_covers_value_plus_U(value, U):
    if value + U <= 0:
        with pytest.raises(GonioError):
            state(value, U, nonnegative=True)
        return
    s = state(value, U, nonnegative=True)
    if U > value:
        b = Decimal(s.upper).scaleb(s.exponent)
        assert b >= 0 and "-" not in s.upper
        assert b >= Decimal(repr(value)) + Decimal(repr(U))        # never understated
        assert f"[0, {s.upper_text}]" in s.text()
    else:
        assert s.upper is None


def test_empty_acceptance_interval_of_a_non_negative_quantity_in_words():
    L = labels("en")
    c = {"item": "startup_time", "U": 100.0, "lower": None, "upper": 60.0,
         "acceptance_lower": None, "acceptance_upper": -40.0, "outcome": "fail"}
    res = {"startup_time": {"nonnegative": True}}
    assert conformity_texts(c, res, L)["acceptance"] == L["c_acc_empty"]
    assert conformity_texts(c, None, L, nonnegative=True)["acceptance"] == L["c_acc_empty"]
    # a signed quantity keeps its one-sided acceptance interval
    assert conformity_texts(c, None, L, nonnegative=False)["acceptance"] == "≤ -40"


def test_rate_item_below_zero_is_not_measured():
    """calibrate_items reports a non-negative item that the rule refuses as not measured."""
    def bad(ctx):
        return Item("noise", "noise", "5.6", "°/s", -5.0, uncertainty=Uncertainty(
            [], 0.5, 1.0, 2.0, None, coverage_probability=0.95))

    def good(ctx):
        return Item("ok", "ok", "5.7", "°/s", 5.0, uncertainty=Uncertainty(
            [], 0.5, 1.0, 2.0, None, coverage_probability=0.95))
    mod = SimpleNamespace(ITEMS=[("noise", "noise", "5.6", bad), ("ok", "ok", "5.7", good)],
                          NEEDS={}, NONNEGATIVE=frozenset({"noise", "ok"}),
                          with_needs=lambda ctx, done: ctx)
    items = calibrate_items(None, mod)
    assert not items["noise"].measured and "non-negative" in items["noise"].reason
    assert items["noise"].to_json()["value"] is None
    assert items["ok"].measured and items["ok"].value == 5.0
