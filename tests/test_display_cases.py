"""The certificate's number display against a hand-written table (JCGM 100 7.2.6).

Each expected text was worked out by hand: U to two significant digits rounded half up
(away from zero on a tie), E and R to the decimal place of U, E with a sign only where
the rounded value has one, other items to their stated significant digits. None of
these expectations is produced by the code under test.
"""

import math

import pytest

from gonio.report.i18n import display_number, display_uncertainty
from gonio.specs.ogam_draft.stated import display_item

ITEM_CASES = [
    # (item, value, U, expected text)
    ("angle_deviation", -0.004, 0.36, "0.00"),       # rounds to zero: no sign
    ("angle_deviation", 0.004, 0.36, "0.00"),
    ("angle_deviation", -0.006, 0.36, "-0.01"),
    ("angle_deviation", -0.11879399, 0.35896, "-0.12"),
    ("angle_deviation", 0.873, 0.46, "+0.87"),
    ("angle_deviation", 0.125, 0.30, "+0.13"),      # half up
    ("angle_deviation", -0.125, 0.30, "-0.13"),     # half away from zero
    ("angle_deviation", 1.23456, 2.3, "+1.2"),      # U has 2 digits → one decimal
    ("angle_deviation", 0.0996, 0.0996, "+0.10"),   # U 0.0996 shows as 0.10: two decimals
    ("angle_deviation", 12.46, 13.0, "+12"),        # U 13: no decimals
    ("repeatability", 0.13901059, 0.35896, "0.14"),
    ("repeatability", 0.095, 0.30, "0.10"),
    ("angle_deviation", math.nan, 0.3, "—"),
    ("angle_deviation", None, 0.3, "—"),
]

U_CASES = [
    (0.297, "0.30"), (0.0996, "0.10"), (1.25, "1.3"), (0.35896, "0.36"), (12.5, "13"),
    (0.0014999, "0.0015"), (0.15, "0.15"), (0.995, "1.0"),
]

NUMBER_CASES = [
    (2.18e-5, 3, "2.18×10⁻⁵"), (9.996e-5, 3, "1.00×10⁻⁴"), (2.0533102, 3, "2.05"),
    (0.0, 3, "0"), (-0.0123456, 3, "-0.0123"),
]


@pytest.mark.parametrize("item,value,U,expected", ITEM_CASES)
def test_item_display(item, value, U, expected):
    assert display_item(item, value, U=U) == expected


@pytest.mark.parametrize("U,expected", U_CASES)
def test_expanded_uncertainty_two_significant_digits(U, expected):
    assert display_uncertainty(U) == expected


@pytest.mark.parametrize("x,sig,expected", NUMBER_CASES)
def test_number_display(x, sig, expected):
    assert display_number(x, sig) == expected
