"""IEC 62047-20 5.3.3.5: how the power-on records were fitted (one transient for all, or one
per power-on, and why) is recorded in the item's details and stated under the results table
(en, zh), in summary.txt and as the item's dcc:description (one sentence,
:func:`gonio.report.rate_content.item_conditions`). The recorded decision is checked against
the fit the budget actually used (its budget row names "one transient for all records" only
then) and against the test's p recomputed here from the replicates' statistics."""
from __future__ import annotations

import numpy as np
import pytest

from gonio.report.rate_content import item_conditions, spec_content
from gonio.specs.iec62047_20 import items as I

from tests.test_iec_power_on_drift import _unequal_records


def _fit(recs, nr=100):
    val, vals, u, m, fit = I.power_on_drift_budget(recs, nr, lambda s: 0.0, (0.0, 0.0))
    pooled_row = "one transient for all records" in u.components[0]["source"]
    return fit, pooled_row


def _p_here(recs, nr=100):
    """The test's p as its definition reads, (1 + #{T* ≥ T}) / (1 + n), computed here."""
    rep = I._power_on_replicates(recs, nr, lambda s: 0.0, (0.0, 0.0), test=True)
    t_star = np.asarray(rep["lr_star"], float)
    return (1 + int(np.sum(t_star >= rep["lr"]))) / (1 + t_star.size)


def test_unequal_power_ons_recorded_as_refuted():
    recs, _ = _unequal_records(np.random.default_rng(57), (0.2, 0.05, 0.05))
    fit, pooled_row = _fit(recs)
    assert fit["transient_basis"] == "refuted" and fit["transient_one"] is False
    assert not pooled_row                               # the fit used: one per power-on
    assert fit["transient_test_p"] == pytest.approx(_p_here(recs), abs=1e-12)
    assert fit["transient_test_p"] < fit["transient_test_level"] == 0.05
    assert fit["power_on_records"] == 3


def test_equal_power_ons_recorded_as_pooled():
    recs, _ = _unequal_records(np.random.default_rng(3), (0.1, 0.1))
    fit, pooled_row = _fit(recs)
    assert fit["transient_basis"] == "not_refuted" and fit["transient_one"] is True
    assert pooled_row
    assert fit["transient_test_p"] == pytest.approx(_p_here(recs), abs=1e-12)
    assert fit["transient_test_p"] >= 0.05


def test_records_of_different_timing_recorded():
    a, _ = _unequal_records(np.random.default_rng(4), (0.1,), n=2000)
    b, _ = _unequal_records(np.random.default_rng(5), (0.1,), n=1000)
    fit, pooled_row = _fit([*a, *b])
    assert fit == {"power_on_records": 2, "transient_test_level": 0.05,
                   "transient_test_p": None, "transient_one": False,
                   "transient_basis": "timing_differs"}
    assert not pooled_row


@pytest.mark.parametrize("basis", I.POWER_ON_FIT_BASES)
def test_stated_in_both_languages(basis):
    det = {"power_on_records": 3, "transient_test_level": 0.05, "transient_basis": basis,
           "transient_one": basis == "not_refuted",
           "transient_test_p": {"refuted": 0.01, "not_refuted": 0.42}.get(basis)}
    res = {"items": {"bias_drift_after_power_on": {"measured": True, "details": det}}}
    content = spec_content("iec62047-20")
    (k, en), = item_conditions(res, content, "en")
    (_, zh), = item_conditions(res, content, "zh")
    assert k == "bias_drift_after_power_on" and "5.3.3.5" in en and "5.3.3.5" in zh
    if det["transient_test_p"] is not None:
        assert f"p-value {det['transient_test_p']:#.2g}" in en and \
            f"p 值 {det['transient_test_p']:#.2g}" in zh
    assert ("one transient fitted to all 3 records" in en) == (basis == "not_refuted")
    assert ("each of the 3 power-ons" in en) == (basis == "refuted")
    # a result stored before the details held it states nothing
    res["items"]["bias_drift_after_power_on"]["details"] = {}
    assert item_conditions(res, content, "en") == []


@pytest.mark.parametrize("p, basis", [(0.0496, "refuted"), (0.0499999, "refuted"),
                                      (0.05, "not_refuted"), (0.0504, "not_refuted")])
def test_the_printed_p_value_holds_its_relation(p, basis):
    """The p-value is printed so that the relation the sentence states holds at the digits
    printed: 0.0496 is refuted at 0.05 and must not read "0.05 < 0.05" (en and zh)."""
    import re

    det = {"power_on_records": 3, "transient_test_level": 0.05, "transient_basis": basis,
           "transient_one": basis == "not_refuted", "transient_test_p": p}
    res = {"items": {"bias_drift_after_power_on": {"measured": True, "details": det}}}
    content = spec_content("iec62047-20")
    for lang, word in (("en", r"p-value "), ("zh", r"p 值 ")):
        (_, text), = item_conditions(res, content, lang)
        m = re.search(word + r"([0-9.e-]+) (<|≥) ([0-9.]+)", text)
        assert m, text
        printed, rel, lvl = float(m.group(1)), m.group(2), float(m.group(3))
        assert rel == ("<" if basis == "refuted" else "≥"), text
        assert (printed < lvl) == (rel == "<"), text
        assert abs(printed - p) <= 1e-3 * p + 1e-12 or abs(printed - p) < 0.0006, text
