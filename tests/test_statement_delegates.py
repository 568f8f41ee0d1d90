"""Every display of a number delegates to the one statement rule (gonio.result.statement):
the certificate's display rules (report/i18n.py), the stated items (report/stated.py) and a
budget's carried-on rounded number agree with ``state`` for all inputs (hypothesis), and
``state`` agrees with an independent decimal computation, carries included."""

from __future__ import annotations

import math
from decimal import ROUND_HALF_UP, Decimal, localcontext

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from gonio.report.i18n import (coverage_text, display, display_number, display_uncertainty,
                               parse_display)
from gonio.report.stated import item_nums
from gonio.specs.ogam_draft.stated import stated_item
from gonio.result.statement import item_statement, k_text, p_relation, p_text, rounded, state

finite = st.floats(min_value=-1e20, max_value=1e20, allow_nan=False, allow_infinity=False)
positive = st.floats(min_value=1e-12, max_value=1e12, allow_nan=False, allow_infinity=False)


def _sig_round(x: float, sig: int) -> Decimal:
    """Independent: ``x`` to ``sig`` significant digits half up, via scientific formatting."""
    with localcontext(prec=sig, rounding=ROUND_HALF_UP):
        return +Decimal(repr(x))


def _value(text: str) -> Decimal:
    """A stated text ("1.00×10⁻⁴", "-0.12") back to an exact Decimal."""
    mant, _, e = text.partition("×10")
    d = Decimal(mant)
    if e:
        d = d.scaleb(int(e.translate(str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789"))))
    return d


def _mantissa_ok(text: str) -> bool:
    """A power-of-ten form has a mantissa in [1, 10) (no "10.0×10⁻⁵")."""
    if "×10" not in text:
        return True
    m = abs(Decimal(text.partition("×10")[0]))
    return Decimal(1) <= m < Decimal(10)


@settings(max_examples=400, deadline=None)
@given(finite, st.integers(min_value=1, max_value=9))
@example(9.996e-5, 3).via("issue: 10.0×10⁻⁵")
@example(0.99996, 3).via("carry to 1.00")
@example(999.96, 3).via("carry to 1000")
@example(-9.996e-5, 3).via("negative carry")
@example(9.9996e-4, 3).via("carry out of the power-of-ten range")
@example(0.0, 3).via("zero")
def test_display_number_is_state_without_U(x, sig):
    text = display_number(x, sig)
    assert text == state(x, sig=sig).value_text
    assert _mantissa_ok(text), text
    if x != 0:
        want = _sig_round(x, sig)
        if "×10" not in text and want.adjusted() >= sig - 1:
            # without U, digits left of the point are kept (1296000.003 → "1296000")
            with localcontext(prec=200):
                want = Decimal(repr(x)).quantize(Decimal(1), rounding=ROUND_HALF_UP)
        assert _value(text) == want, (x, sig, text, want)
        assert parse_display(text) == pytest.approx(float(want), rel=1e-12)
    else:
        assert text == "0"


@settings(max_examples=400, deadline=None)
@given(finite, positive)
@example(9.996e-5, 1.0e-8).via("carry with a common power of ten")
@example(0.99996, 0.0001).via("carry at U's place")
@example(999.96, 0.1).via("carry into a new digit")
@example(-999.96, 0.1).via("negative")
@example(5.0, 0.0996).via("U carries to 0.10")
def test_state_with_U_against_independent_rounding(value, U):
    s = state(value, U)
    # U: two significant digits; the value at U's (absolute) decimal place
    Ud = _sig_round(U, 2)
    place = Ud.adjusted() - 1
    with localcontext(prec=200):
        vd = Decimal(repr(value)).quantize(Decimal(1).scaleb(place), rounding=ROUND_HALF_UP)
    assert _value(s.U_text) == Ud
    assert _value(s.value_text) == vd
    if s.exponent:
        assert _mantissa_ok(s.value_text) or abs(vd) < abs(Ud), s.text()
        assert s.exponent == max(vd.adjusted() if vd else Ud.adjusted(), Ud.adjusted())
    # the delegates: the certificate's rules give the same texts where no power of ten is used
    if not s.exponent:
        assert display_uncertainty(U) == s.U
        assert display(f"dec{s.decimals}", value) == s.value
        assert display("atU", value, U=U) == s.value
    assert rounded(U, 2) == float(Ud)


@settings(max_examples=300, deadline=None)
@given(finite, st.one_of(positive, st.just(0.0), st.none()),
       st.floats(min_value=1.0, max_value=60.0), st.floats(min_value=0.5, max_value=0.999))
@example(9.996e-5, 0.0, 2.0, 0.95).via("zero U")
@example(-0.11879399, 0.35896, 2.0, 0.9545).via("negative, p 95.45 %")
def test_item_displays_agree(value, U, k, p):
    """item_nums (rate and triad certificates, DCC) and stated_item (optical) state an item
    as item_statement does; k and p through every route the same."""
    unc = {"U": U, "k": k, "coverage_probability": p} if U is not None else None
    item = {"value": value, "unit": "°/h", "measured": True, "clause": "x", "uncertainty": unc}
    st_ = item_statement(item)
    n = item_nums(item, "items.x")
    assert str(n["value"]) == st_.value_text
    s = stated_item({"items": {"x": item}}, "x")      # a results.json
    assert str(s["value"]) == st_.value_text
    if st_.U is not None:
        assert str(n["U"]) == st_.U_text == str(s["U"])
        assert str(n["k"]) == k_text(k) == display("k", k) == str(s["k"])
        assert n["p"] == p_text(p) == s["p"]
        assert coverage_text(p) == (f"{p_text(p)} %" if p_relation(p_text(p)) == "="
                                    else f"approximately {p_text(p)} %")


@pytest.mark.parametrize("x,sig,text", [
    (9.996e-5, 3, "1.00×10⁻⁴"), (0.99996, 3, "1.00"), (999.96, 3, "1000"),
    (-9.996e-5, 3, "-1.00×10⁻⁴"), (-0.99996, 3, "-1.00"), (0.0, 3, "0"),
    (2.1805064433995786e-05, 3, "2.18×10⁻⁵"), (76434.8425925926, 8, "76434.843"),
])
def test_hand_cases_without_U(x, sig, text):
    assert display_number(x, sig) == state(x, sig=sig).value_text == text


@pytest.mark.parametrize("value,U,text", [
    (9.99996e-5, 1.0e-8, "1.00000×10⁻⁴ ± 0.00010×10⁻⁴"),
    (9.996e-5, 1.0e-8, "9.9960×10⁻⁵ ± 0.0010×10⁻⁵"),
    (0.99996, 0.001, "1.0000 ± 0.0010"),
    (999.96, 0.1, "999.96 ± 0.10"),
    (999.96, 2.0, "1000.0 ± 2.0"),
    (-9.99996e-5, 1.0e-8, "-1.00000×10⁻⁴ ± 0.00010×10⁻⁴"),
    (9.996e-5, 0.0, "1.00×10⁻⁴"),          # zero U: the value to 3 significant digits
    (-5.0, None, "-5.00"),
])
def test_hand_cases_with_U(value, U, text):
    assert state(value, U).text() == text


def test_p_is_stated_the_same_everywhere():
    """A p the procedure chose is stated as chosen, so the text says what results.json and
    the DCC's si:coverageProbability carry: 0.9545 (the triad's, k = t for 95.45 %,
    EA-4/02 Annex E) is "95.45", never "95" beside a k computed for 95.45 %; a p computed
    from a distribution keeps two significant digits."""
    from decimal import Decimal
    assert p_text(0.9545) == "95.45" and Decimal(p_text(0.9545)) / 100 == Decimal("0.9545")
    assert coverage_text(0.9545) == "95.45 %" and coverage_text(0.95) == "95 %" and coverage_text(0.98) == "approximately 98 %"
    assert coverage_text(0.9545, "zh") == "95.45 %"
    assert p_text(0.95) == "95" and p_text(0.99) == "99" and p_text(0.9973) == "99.73"
    assert p_text(0.9946477675623514) == "99" and p_text(0.981526203417951) == "98"


@pytest.mark.parametrize("k, text", [
    (2.0, "2"), (2.5, "2.5"), (1.96, "1.96"),
    (1.9954689314298435, "2.00"),      # t_95(68), the IEC ARW's k: never "2"
    (1.9989715170333788, "2.00"),      # t_95(62), the JJF B_t's k
    (2.0000024438996027, "2.00"),      # t_0.9545(∞)-like factor of the triad
    (1.959963984540054, "1.96"), (2.0452, "2.05"), (12.706, "12.7"),
])
def test_k_is_never_stated_as_a_chosen_whole_number(k, text):
    """A t-factor is stated to 3 significant digits; "2" (a chosen k) only for k = 2
    exactly: the stated k, read back, is k to within half a unit of its last digit, and
    a stated whole number means k is that number."""
    from decimal import Decimal
    t = k_text(k)
    assert t == text
    last = Decimal(1).scaleb(Decimal(t).as_tuple().exponent)
    assert abs(Decimal(t) - Decimal(repr(k))) <= last / 2
    if "." not in t:
        assert float(t) == k
