"""tables/items.csv carries each item's one 95 % statement, as the certificate states it: the
cases the certificate states differently from value ± U (numbers of the seed-0 optical and
rate demos), each row checked against numbers worked out here (Student's t from scipy)."""

from __future__ import annotations

import math

import pytest
from scipy import stats

from gonio.result.model import Item, Uncertainty
from gonio.result.statement import item_statement
from gonio.result.tables import ITEM_COLUMNS, item_row


def _item(key, value, unc, nonnegative=False, unit="1"):
    it = Item(key, key, "x", unit, value, uncertainty=unc)
    it.nonnegative = nonnegative
    return it


def test_k_of_a_convolution_has_no_nu():
    """K: k = 1.753 from a JCGM 101 convolution, ν_eff None: "inf" beside it would read as
    k = t95(∞) = 1.96."""
    row = item_row("K", _item("K", 76434.84, Uncertainty([], 0.01363, 0.0239, 1.7531, None,
                                                       None, 0.95, "jcgm101-convolution")))
    assert row["k"] == 1.7531 and row["U"] == 0.0239 and row["nu"] is None
    assert not math.isclose(1.7531, stats.norm.ppf(0.975), rel_tol=1e-3)


def test_nu_is_the_stated_nu_k_was_computed_from():
    """IEC ARW: ν_eff 68.38 stated 68 with k = t95(68) = 1.9955; a ν above 1000 is ∞."""
    k = float(stats.t.ppf(0.975, 68))
    row = item_row("arw", _item("arw", 1.8039, Uncertainty([], 0.0258, k * 0.0258, k, 68.38,
                                                           None, 0.95, "welch-satterthwaite")))
    assert row["nu"] == 68.0 and row["k"] == pytest.approx(stats.t.ppf(0.975, row["nu"]))
    k = float(stats.norm.ppf(0.975))
    row = item_row("sf", _item("sf", 6.0, Uncertainty([], 0.0018, k * 0.0018, k, 18718496.9,
                                                      None, 0.95, "welch-satterthwaite")))
    assert row["nu"] == math.inf


def test_interval_item_has_its_ends_and_no_reach():
    """B_s: a χ² interval [0, 0.00452] with ν_eff 1.02, stated ν = 1; no U (a reach beside
    an empty k reads as value ± U) and no k."""
    unc = Uncertainty([], 0.000198, 0.004235, None, 1.0207912774156418, None, 0.95,
                      "chi-square", interval=(0.0, 0.004518326537744824))
    row = item_row("B_s", _item("B_s", 0.00028333, unc, nonnegative=True, unit="deg/h"))
    assert row["U"] is None and row["k"] is None and row["nu"] == 1.0
    assert (row["interval_low"], row["interval_high"]) == (0.0, 0.004518326537744824)
    assert item_statement(row | {"measured": True, "uncertainty": {
        "U": unc.U, "k": None, "interval": unc.interval, "nu_eff": unc.nu_eff,
        "coverage_probability": 0.95}, "nonnegative": True}).nu_eff == "1"


def test_below_zero_item_states_its_bound_alone():
    """C_g: estimate −1.58e-5 below its interval [0, 3.9e-5], stated on the certificate by
    its upper bound alone: the row carries the interval, no value ± U and no value outside
    the interval."""
    unc = Uncertainty([], 1.98e-05, 5.477989761853442e-05, None, None, None, 0.95,
                      "neyman-belt", interval=(0.0, 3.900377913636975e-05))
    row = item_row("C_g", _item("C_g", -1.5776118482164668e-05, unc, nonnegative=True,
                                unit="%"))
    assert row["U"] is None and row["k"] is None and row["nu"] is None
    assert (row["interval_low"], row["interval_high"]) == (0.0, 3.900377913636975e-05)
    assert row["value"] is None
    assert list(row) == ITEM_COLUMNS


def test_nonnegative_bound_from_value_plus_U():
    """A non-negative item whose U exceeds its value (k = 2): stated [0, value + U]."""
    row = item_row("t", _item("t", 0.01, Uncertainty([], 0.044, 0.088, 2.0, None, None, 0.95,
                                                     "x"), nonnegative=True))
    assert row["U"] is None and row["k"] is None
    assert (row["interval_low"], row["interval_high"]) == pytest.approx((0.0, 0.098))
