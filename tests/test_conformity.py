"""Decision rules and conformity (ILAC-G8:09/2019, JCGM 106) against closed forms.

The independent reference is scipy.stats.norm (a different Φ implementation) and the
closed-form values of the normal model: at a limit p_c = 1/2; at w = U = 2u inside one
limit the specific false-accept probability is Φ(−2); two-sided intervals give
Φ(a) − Φ(−b).
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import norm

from gonio.analysis.conformity import (DecisionRule, Limits, acceptance_interval,
                                       conformance_probability, decide, normal_cdf)
from gonio.errors import GonioError

LIM = Limits(-0.5, 0.5, "MPE")


def test_normal_cdf_matches_scipy():
    for z in (-6.0, -2.0, -1.0, -0.3, 0.0, 0.7, 1.96, 3.5):
        assert normal_cdf(z) == pytest.approx(norm.cdf(z), rel=1e-12, abs=1e-15)


def test_value_on_the_limit_conforms_with_probability_one_half():
    # JCGM 106 7.3: y = T_U and a one-sided interval → p_c = 1/2 exactly
    assert conformance_probability(0.5, 0.1, None, 0.5) == pytest.approx(0.5, abs=1e-15)
    d = decide("E", 0.5, 0.2, 2.0, Limits(None, 0.5), DecisionRule("simple"))
    assert d.outcome == "pass" and d.false_accept_probability == pytest.approx(0.5, abs=1e-12)


def test_guard_band_w_equals_U_bounds_false_accept_by_phi_minus_2():
    # y at the acceptance limit T_U − U, k = 2: (T_U − y)/u = 2 → 1 − p_c = Φ(−2) = 0.02275
    U = 0.1
    y = 0.5 - U
    d = decide("E", y, U, 2.0, LIM, DecisionRule("guarded", 1.0))
    assert d.outcome == "pass"
    assert d.acceptance_upper == pytest.approx(0.4) and d.guard_band == pytest.approx(0.1)
    assert d.false_accept_probability == pytest.approx(norm.cdf(-2.0), rel=1e-9)
    assert d.false_accept_probability == pytest.approx(0.0227501319, rel=1e-8)


def test_two_sided_closed_form():
    y, u = 0.1, 0.25
    expect = norm.cdf((0.5 - y) / u) - norm.cdf((-0.5 - y) / u)
    assert conformance_probability(y, u, -0.5, 0.5) == pytest.approx(expect, rel=1e-12)
    d = decide("E", y, 2 * u, 2.0, LIM, DecisionRule("simple"))
    assert d.false_accept_probability == pytest.approx(1 - expect, rel=1e-10)


@settings(max_examples=200, deadline=None)
@given(y=st.floats(-2, 2), u=st.floats(0.01, 1), lo=st.floats(-1.5, 0), width=st.floats(0.01, 2))
def test_conformance_probability_is_normal_mass(y, u, lo, width):
    hi = lo + width
    expect = norm.cdf(hi, loc=y, scale=u) - norm.cdf(lo, loc=y, scale=u)
    assert conformance_probability(y, u, lo, hi) == pytest.approx(expect, abs=1e-12)


def test_simple_acceptance_is_binary_on_the_tolerance():
    r = DecisionRule("simple")
    assert decide("E", 0.49, 0.3, 2.0, LIM, r).outcome == "pass"
    assert decide("E", -0.51, 0.3, 2.0, LIM, r).outcome == "fail"
    assert decide("E", 0.49, 0.3, 2.0, LIM, r).guard_band == 0.0
    f = decide("E", 0.6, 0.2, 2.0, LIM, r)
    # rejected: the specific false-reject probability is p_c = Φ((0.5 − 0.6)/0.1) = Φ(−1)
    assert f.false_accept_probability is None
    assert f.false_reject_probability == pytest.approx(norm.cdf(-1.0), rel=1e-10)


def test_non_binary_four_zones():
    # ILAC-G8 4.2.3, fig. 5, w = U = 0.1: pass ≤ 0.4 < conditional pass ≤ 0.5
    # < conditional fail ≤ 0.6 < fail
    r = DecisionRule("non-binary", 1.0)
    out = {y: decide("E", y, 0.1, 2.0, LIM, r).outcome for y in
           (0.0, 0.39, 0.45, 0.5, 0.55, 0.6, 0.61, -0.45, -0.55, -0.7)}
    assert out == {0.0: "pass", 0.39: "pass", 0.45: "conditional pass", 0.5: "conditional pass",
                   0.55: "conditional fail", 0.6: "conditional fail", 0.61: "fail",
                   -0.45: "conditional pass", -0.55: "conditional fail", -0.7: "fail"}


def test_guard_factor_r_scales_w():
    r = DecisionRule("guarded", 1.5)
    d = decide("R", 0.14, 0.1, 2.0, Limits(None, 0.3), r)
    assert d.guard_band == pytest.approx(0.15) and d.acceptance_upper == pytest.approx(0.15)
    assert d.outcome == "pass"
    assert decide("R", 0.16, 0.1, 2.0, Limits(None, 0.3), r).outcome == "fail"
    # (0.3 − 0.14)/0.05 = 3.2
    assert d.false_accept_probability == pytest.approx(norm.cdf(-3.2), rel=1e-9)


def test_guard_band_closing_the_interval_passes_nothing():
    d = decide("E", 0.0, 0.6, 2.0, LIM, DecisionRule("guarded"))
    assert acceptance_interval(LIM, 0.6) == (pytest.approx(0.1), pytest.approx(-0.1))
    assert d.outcome == "fail"


def test_bad_rules_and_limits_name_the_key():
    with pytest.raises(GonioError, match="decision_rule.rule"):
        DecisionRule("lenient")
    with pytest.raises(GonioError, match="guard_band_factor"):
        DecisionRule("guarded", -1.0)
    with pytest.raises(GonioError, match="lower, upper or mpe"):
        Limits(None, None)
    with pytest.raises(GonioError, match="not below"):
        Limits(1.0, 0.5)
    with pytest.raises(ValueError):
        decide("E", 0.0, 0.0, 2.0, LIM, DecisionRule())
    assert not math.isnan(normal_cdf(math.inf))


def test_chi2_model_of_a_standard_deviation_against_inverse_gamma():
    # σ² given s (ν dof) is scaled inverse-χ², i.e. Inv-Gamma(ν/2, ν s²/2): a second route
    from scipy.stats import invgamma
    from gonio.analysis.conformity import conformance_probability_chi2
    for s, nu, lo, hi in ((0.124, 9, None, 0.3), (1.0, 3, 0.5, 2.0), (0.02, 40, None, 0.021)):
        ref = invgamma.cdf(hi ** 2, nu / 2, scale=nu * s * s / 2) - (
            0.0 if lo is None else invgamma.cdf(lo ** 2, nu / 2, scale=nu * s * s / 2))
        assert conformance_probability_chi2(s, nu, lo, hi) == pytest.approx(ref, rel=1e-9)


def _result_with(value, U, k, nu, interval):
    from gonio.result.model import Item, Result, Uncertainty
    return Result("s", "S", {"R": Item("R", "repeatability", "7.5", "″", value,
                                       uncertainty=Uncertainty([], U / k, U, k, nu,
                                                               interval=interval))}, {}, {})


def test_a_standard_deviation_with_its_chi2_interval_is_decided_on_chi2():
    # review of stop 28: R = 0.124″ (ν = 9) against ≤ 0.3″ stated a false-accept risk of
    # 9×10⁻¹⁰ from the normal model; σ = s·√(ν/χ²_ν) gives 0.31 %
    from gonio.analysis.conformity import decide_items
    r = _result_with(0.124, 0.066, 2.26, 9.0, (0.085, 0.226))
    (c,) = decide_items(r, [{"item": "R", "upper": 0.3}], {"rule": "simple"})
    assert c.outcome == "pass" and c.probability_model.startswith("chi-square")
    assert c.false_accept_probability == pytest.approx(0.00314, abs=2e-5)
    # no χ² interval: the normal model, as before
    r = _result_with(0.124, 0.066, 2.26, 9.0, None)
    (c,) = decide_items(r, [{"item": "R", "upper": 0.3}], {"rule": "simple"})
    assert c.probability_model == "normal" and c.false_accept_probability < 1e-6


def test_a_second_limit_for_one_item_is_an_error_not_an_override(tmp_path):
    from gonio.analysis.conformity import decide_items
    from gonio.formats.lab import load_lab
    r = _result_with(0.124, 0.066, 2.26, 9.0, None)
    with pytest.raises(GonioError, match=r"'R' has a limit already") as exc:
        decide_items(r, [{"item": "R", "upper": 0.3}, {"item": "R", "upper": 0.5}], None)
    assert exc.value.key == "specification_limits[1].item"
    example = Path(__file__).resolve().parents[1] / "protocols" / "lab-example.toml"
    lab = tmp_path / "lab.toml"
    lab.write_text(example.read_text(encoding="utf-8") + '\n[[specification_limits]]\n'
                   'item = "angle_deviation"\nmpe = 0.7\n', encoding="utf-8")
    with pytest.raises(GonioError, match="limit already") as exc:
        load_lab(lab)
    assert exc.value.key.endswith("].item") and "angle_deviation" in str(exc.value)
    assert "lab.toml" in str(exc.value)


def test_an_item_stated_by_an_asymmetric_interval_is_guarded_by_its_own_reach():
    """An item stated by its interval alone (k None, U = distance to the upper end): the
    guard band at each limit is the interval's reach on that side, so with r = 1 "pass"
    is exactly "the stated interval lies inside the tolerance" at a lower limit too (the
    band at the lower limit was U, the upper reach, before)."""
    from gonio.analysis.conformity import decide_items
    from gonio.result.model import Item, Result, Uncertainty

    def res(value, lo, hi):
        unc = Uncertainty([], (hi - lo) / 4, hi - value, None, None, interval=(lo, hi),
                          k_source="neyman-belt")
        return Result("s", "S", {"C": Item("C", "range", "7.6", "ppm", value,
                                           uncertainty=unc)}, {}, {})
    rule = {"rule": "guarded", "guard_band_factor": 1.0}
    # interval [2.9, 6.0] about 3.0: lower limit 2.5 → lies inside, pass (w_L = 0.1);
    # with the upper reach 3.0 as the band the acceptance limit would be 5.5: fail
    # (the acceptance interval bounds the stated interval's ends: at r = 1 the tolerance)
    (c,) = decide_items(res(3.0, 2.9, 6.0), [{"item": "C", "lower": 2.5}], rule)
    assert c.outcome == "pass" and c.acceptance_lower == 2.5 and c.acceptance_of == "interval"
    (c,) = decide_items(res(3.0, 2.4, 6.0), [{"item": "C", "lower": 2.5}], rule)
    assert c.outcome == "fail"
    # the upper side keeps U: [2.9, 6.0] against ≤ 6.5 passes, against ≤ 5.9 does not
    (c,) = decide_items(res(3.0, 2.9, 6.0), [{"item": "C", "upper": 6.5}], rule)
    assert c.outcome == "pass" and c.acceptance_upper == 6.5
    (c,) = decide_items(res(3.0, 2.9, 6.0), [{"item": "C", "upper": 5.9}], rule)
    assert c.outcome == "fail"
    # non-binary: below the lower limit, "conditional fail" where the interval reaches back
    # above it (its upper reach), "fail" where the whole interval lies below it
    (c,) = decide_items(res(2.45, 2.4, 6.0), [{"item": "C", "lower": 2.5}],
                        {"rule": "non-binary"})
    assert c.outcome == "conditional fail"
    (c,) = decide_items(res(2.3, 2.25, 6.0), [{"item": "C", "lower": 2.5}],
                        {"rule": "non-binary"})
    assert c.outcome == "conditional fail"
    (c,) = decide_items(res(2.3, 2.0, 2.45), [{"item": "C", "lower": 2.5}],
                        {"rule": "non-binary"})
    assert c.outcome == "fail"


def test_non_binary_conditional_fail_reaches_back_from_the_right_side():
    """Outside the tolerance the outcome is "conditional fail" where the stated interval
    reaches back inside: above the upper limit by its reach below the value (U_lower),
    below the lower limit by its reach above it (U). Asymmetric intervals tell the two
    apart (before, the reaches were swapped)."""
    rule = DecisionRule("non-binary")
    lim = Limits(-1.0, 1.0)
    # above +1 by 0.2: the interval [0.914, 1.367] reaches back in below (0.286 ≥ 0.2)
    d = decide("E", 1.2, 0.1667, None, lim, rule, u=0.1, U_lower=0.2858)
    assert d.outcome == "conditional fail"
    # below −1 by 0.2: the interval [−1.3, −0.9] reaches back in above (0.3 ≥ 0.2)
    d = decide("x", -1.2, 0.3, None, lim, rule, u=0.1, U_lower=0.1)
    assert d.outcome == "conditional fail"
    d = decide("x", -1.2, 0.1, None, lim, rule, u=0.1, U_lower=0.3)   # [−1.5, −1.1]
    assert d.outcome == "fail"
    # a standard deviation 0.124 with its χ² interval [0.0853, 0.2264] (ν = 9) against an
    # upper limit 0.08: the whole interval lies above it
    d = decide("s", 0.124, 0.2264 - 0.124, None, Limits(None, 0.08), rule, chi2_nu=9,
               U_lower=0.124 - 0.0853)
    assert d.outcome == "fail"
