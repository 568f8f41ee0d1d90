"""The one statement rule (gonio.result.statement): hand cases from the issue and GUM 7.2.6,
and properties checked on many random values against an independent decimal computation."""

from __future__ import annotations

import math
from decimal import Decimal

import numpy as np
import pytest

from gonio.result.statement import k_text, nu_text, p_text, state

HAND = [
    # value, U, expected value, expected U   (issue 25's cases and GUM 7.2.6)
    (5.99906, 0.00316, "5.9991", "0.0032"),
    (786.5, 160.0, "790", "160"),
    (0.01, 0.088, "0.010", "0.088"),
    (175.0, 1200.0, "200", "1200"),
    (10.05, 0.0996, "10.05", "0.10"),       # U rounds up into a new digit: 0.10, 2 places
    (-0.11879399, 0.35896, "-0.12", "0.36"),
    (100.02147, 0.00035, "100.02147", "0.00035"),
    (0.125, 0.25, "0.13", "0.25"),          # half up, not half even
    (-0.004, 0.25, "0.00", "0.25"),         # no "-0.00"
    (12345.6, 44.9, "12346", "45"),
]


@pytest.mark.parametrize("value,U,v_txt,U_txt", HAND)
def test_hand_cases(value, U, v_txt, U_txt):
    s = state(value, U)
    assert (s.value, s.U) == (v_txt, U_txt)


def test_factors_and_text():
    s = state(5.99906, 0.00316, k=1.97414, nu_eff=58.99, p=0.95, unit="mV/(°/s)")
    assert s.text() == "5.9991 ± 0.0032 mV/(°/s) (k = 1.97, ν_eff = 58, p = 95 %)"
    assert (k_text(2.0), k_text(2.2622), nu_text(math.inf), nu_text(9.9), p_text(0.9545)) == \
        ("2", "2.26", "∞", "9", "95.45")


def test_upper_bound_of_non_negative_quantity():
    s = state(0.01, 0.088, k=2.0, p=0.95, unit="°/s", nonnegative=True)
    assert s.upper == "0.098"
    assert "≤ 0.098 °/s" in s.text() and "[0, 0.098]" in s.text()
    assert "上限" in s.text("zh")
    # the bound is rounded up, never understated: 0.0104 + 0.0881 = 0.0985 → 0.099
    assert state(0.0104, 0.0881, nonnegative=True).upper == "0.099"
    # U below the value: no bound; a signed quantity: no bound
    assert state(0.2, 0.088, nonnegative=True).upper is None
    assert state(0.01, 0.088).upper is None


@pytest.mark.parametrize("value,U,upper", [(0.1, 0.2, "0.30"), (1.1, 2.2, "3.3"),
                                           (0.7, 1.4, "2.1"), (2.2e-7, 4.4e-7, "6.6")])
def test_upper_bound_not_raised_by_a_float_artefact(value, U, upper):
    # 0.1 + 0.2 = 0.30000000000000004 in binary: rounding *that* up would state ≤ 0.31
    assert state(value, U, nonnegative=True).upper == upper


def test_upper_bound_against_decimal_sum():
    rng = np.random.default_rng(25)
    for _ in range(2000):
        U = float(rng.uniform(0.1, 9.9)) * 10.0 ** int(rng.integers(-5, 4))
        value = U * float(rng.uniform(0, 1))
        s = state(value, U, nonnegative=True)
        q = Decimal(1).scaleb(-s.decimals)
        exact = (Decimal(repr(value)) + Decimal(repr(U))).quantize(q, rounding="ROUND_CEILING")
        if s.exponent:
            continue            # mantissa form: checked by the hand cases
        assert Decimal(s.upper) == exact, (value, U)


def test_small_numbers_share_U_exponent():
    s = state(2.1805064e-05, 1.3e-06, k=2)
    assert (s.value_text, s.U_text) == ("2.18×10⁻⁵", "0.13×10⁻⁵")
    s = state(0.0061124, 5.6e-06)
    assert (s.value_text, s.U_text) == ("6.1124×10⁻³", "0.0056×10⁻³")


def test_no_uncertainty_keeps_significant_digits():
    assert state(76434.8425925926, None, sig=8).value == "76434.843"
    assert state(5.99839, None, sig=4).value == "5.998"
    assert state(float("nan"), 0.1).value == "—"


def _independent(value: float, U: float) -> tuple[Decimal, Decimal, int]:
    """U to two significant digits and the value at its place, with Decimal's own formatting
    (an implementation that shares nothing with gonio.result.statement)."""
    dU = Decimal(repr(U))
    q = 1 - dU.adjusted()                  # two digits: 10^(1-q) <= U < 10^(2-q)
    r = dU.quantize(Decimal(f"1e{-q}"), rounding="ROUND_HALF_UP")
    if r >= Decimal(f"1e{2 - q}"):          # 0.0996 -> 0.100: one place fewer
        q -= 1
        r = dU.quantize(Decimal(f"1e{-q}"), rounding="ROUND_HALF_UP")
    place = Decimal(f"1e{-q}")
    return Decimal(repr(value)).quantize(place, rounding="ROUND_HALF_UP"), r, q


def test_random_values_against_independent_rounding():
    rng = np.random.default_rng(25)
    for _ in range(2000):
        U = float(10 ** rng.uniform(-4.9, 4))
        value = float(rng.normal() * 10 ** rng.uniform(-3, 5))
        s = state(value, U)
        v, r, q = _independent(value, U)
        assert Decimal(s.U) == r, (value, U, s)
        assert Decimal(s.value) == v, (value, U, s)
        # same decimal place for value and U
        dec = lambda t: len(t.split(".")[1]) if "." in t else 0  # noqa: E731
        assert dec(s.value) == dec(s.U) == max(q, 0)


def test_p_text_never_says_certainty_below_one():
    """A stated interval's probability below 1 is never printed as 100 %: it keeps the
    decimals that show it below 100 (rounded down at the last), and 1.0 is 100."""
    import math as _m
    for p in (0.99671, 0.99949, 0.99995, 0.99998, 0.9999999, 1 - 1e-12, 0.9999):
        t = p_text(p)
        assert float(t) < 100.0, (p, t)
        assert 0 <= 100.0 * p - float(t) < 0.1, (p, t)
    assert p_text(1.0) == "100" and p_text(0.95) == "95"
    assert _m.isclose(float(p_text(0.99671)), 99.6)


def test_a_computed_p_is_never_rounded_up():
    """A computed coverage probability is stated rounded down at the digits printed (never
    overstated): the text is at most 100 p and within one unit of its last digit below it,
    checked against the decimal expansion of 100 p (exact, from the float's repr)."""
    from decimal import Decimal

    import numpy as np

    for p in (0.98765, 0.94567, 0.9999, 0.959999, 0.99499999):
        t = p_text(p)
        exact = Decimal(repr(p)) * 100
        unit = Decimal(1).scaleb(Decimal(t).as_tuple().exponent)
        assert Decimal(t) <= exact < Decimal(t) + unit, (p, t)
    assert (p_text(0.98765), p_text(0.94567)) == ("98", "94")
    for p in np.random.default_rng(7).uniform(0.9, 0.99999, 2000):
        t = p_text(float(p))
        exact = Decimal(repr(float(p))) * 100
        unit = Decimal(1).scaleb(Decimal(t).as_tuple().exponent)
        assert Decimal(t) <= exact < Decimal(t) + unit, (p, t)
        assert len(t.replace(".", "").lstrip("0")) >= 2
