"""A computed coverage probability a hair above a round one (a whole per cent, which
:func:`p_text` prints bare for a p that is exactly one, or a chosen 95 / 95.45 / 99.73) never
prints as that round text: it keeps its zeros ("99.000"), and is never overstated."""
from decimal import Decimal

import pytest

from gonio.result.statement import CHOSEN_P_TEXTS, p_relation, p_text

ROUND = [Decimal(x) for x in range(1, 100)] + [Decimal(t) for t in CHOSEN_P_TEXTS]


@pytest.mark.parametrize("excess", [1e-11, 1e-9, 3e-7, 9e-6])
def test_hair_above_a_round_p_is_not_printed_round(excess):
    for pct in ROUND:
        p = float(pct / 100) + excess                  # a computed p just above the round one
        assert p > float(pct / 100)
        t = p_text(p)
        assert t != f"{pct.normalize():f}", (p, t)     # never the round p's own text
        assert Decimal(t) <= Decimal(repr(p)) * 100, (p, t)   # never overstated
        assert p_relation(t) == "≈", (p, t)


def test_a_round_p_prints_round():
    for pct in ROUND:
        assert p_text(float(pct / 100)) == f"{pct.normalize():f}"


def test_the_brief_case():
    assert p_text(0.990000001) == "99.000"
    assert p_text(0.99) == "99"
