"""Conformity of items stated by their 95 % interval alone, decided on what is stated
(ILAC-G8:09/2019 4.2, JCGM 106:2012 8): every expected outcome below is worked by hand from
the stated interval, the limit and r (closed forms in the docstrings), never read back from
gonio."""

from __future__ import annotations

import pytest

from gonio.analysis.conformity import NON_NORMAL_K_SOURCES, decide_items, normal_cdf
from gonio.errors import GonioError
from gonio.result.model import Item, Result, Uncertainty
from gonio.result.statement import K_SOURCE_MAX_MAGNITUDE
from gonio.specs import get

#: The rate gyros' items stated as a largest magnitude max_i |x_i| (the review's list).
MAGNITUDES = [("jjf1535-2015", "g_sensitivity"), ("jjf1535-2015", "sf_temperature_sensitivity"),
              ("jjf1535-2015", "bias_temperature_sensitivity"), ("iec62047-20", "cross_axis"),
              ("iec62047-20", "ratiometric_error"), ("iec62047-20", "bias_ratiometric_error"),
              ("iec62047-20", "g_sensitivity")]


def magnitude_result(spec: str, key: str, value=0.45, lo=0.30, hi=0.55) -> Result:
    unc = Uncertainty([], 0.05, hi - value, None, None, None, 0.95, K_SOURCE_MAX_MAGNITUDE,
                      (lo, hi))
    return Result(spec, spec, {key: Item(key, key, "c", "u", value, uncertainty=unc,
                                         nonnegative=True)}, {}, {})


def interval_result(value, lo, hi, source="neyman-belt", nu=None) -> Result:
    unc = Uncertainty([], (hi - lo) / 4, hi - value, None, nu, None, 0.95, source, (lo, hi))
    return Result("s", "S", {"C": Item("C", "C", "7.7", "%", value, uncertainty=unc,
                                       nonnegative=True)}, {}, {})


@pytest.mark.parametrize("spec, key", MAGNITUDES)
def test_rate_magnitudes_are_declared_and_refuse_an_asymmetric_limit(spec, key):
    """An asymmetric limit [−0.4, 0.6] of a magnitude 0.45 gave "pass" before: refused now by
    the statement's marker alone (no declaration passed), and declared by the specification
    so that the laboratory file's check refuses it before any work."""
    assert key in get(spec).magnitude_extremes
    for lim in ({"lower": -0.4, "upper": 0.6}, {"upper": 0.6}, {"lower": -0.4}):
        with pytest.raises(GonioError, match="extreme of magnitudes"):
            decide_items(magnitude_result(spec, key), [{"item": key, **lim}],
                         {"rule": "guarded"})


@pytest.mark.parametrize("spec, key", MAGNITUDES)
@pytest.mark.parametrize("mpe, simple, guarded", [
    # stated 0.45, interval [0.30, 0.55]: simple decides 0.45 against ±mpe; guarded (r = 1)
    # the upper end 0.55 ≤ mpe; the lower end never (a magnitude's interval lies above 0)
    (0.44, "fail", "fail"), (0.45, "pass", "fail"), (0.54, "pass", "fail"),
    (0.55, "pass", "pass"),
])
def test_a_magnitude_is_accepted_on_its_upper_end_only(spec, key, mpe, simple, guarded):
    for rule, want in (("simple", simple), ("guarded", guarded)):
        (c,) = decide_items(magnitude_result(spec, key), [{"item": key, "mpe": mpe}],
                            {"rule": rule})
        assert c.outcome == want, (rule, mpe)
        if rule == "guarded":
            assert c.acceptance_lower is None and c.acceptance_upper == mpe


def test_the_lab_file_check_refuses_a_rate_magnitude_s_asymmetric_limit(tmp_path, monkeypatch,
                                                                        capsys):
    """`gonio calibrate --lab` with lower −0.4, upper 0.6 for JJF B_g: exit 2, one line naming
    the file and the entry, before any calibration."""
    import gonio.pipeline.dispatch as dispatch
    from gonio.cli import main
    from gonio.resources import protocols_dir

    def never(*args, **kwargs):
        raise AssertionError("calibrated before the lab file's check")
    monkeypatch.setattr(dispatch, "calibrate", never)
    example = (protocols_dir() / "lab-example.toml").read_text(encoding="utf-8")
    given = 'item = "angle_deviation"\nmpe = 0.5\n'
    assert given in example
    lab = tmp_path / "lab.toml"
    head = example[:example.index("\n[[specification_limits]]")]
    lab.write_text(head + '\n[[specification_limits]]\nitem = "g_sensitivity"\nlower = -0.4\n'
                   'upper = 0.6\n', encoding="utf-8")
    readings = tmp_path / "readings.csv"
    readings.write_text("# spec: jjf1535-2015\n", encoding="utf-8")
    rc = main(["calibrate", str(readings), "--spec", "jjf1535-2015", "--lab", str(lab),
               "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert rc == 2, err
    assert len(err.splitlines()) == 1 and "specification_limits[0]" in err and str(lab) in err
    assert "g_sensitivity is an extreme of magnitudes" in err


@pytest.mark.parametrize("spec", ["jjf1535-2015", "iec62047-20"])
def test_the_declared_magnitudes_are_the_items_stated_so(tmp_path, spec):
    """The declaration (checked before any work) names exactly the items a calibration states
    by the interval of max_i |x_i| (the statement's kind, K_SOURCE_MAX_MAGNITUDE): an item
    restated as a magnitude without its declaration fails here.

    On the pin test's small programme (tests/data/pins/SPEC-small.toml: the built-in
    programme, every test and item, with the coverage study's reduced sizes): which items are
    stated by that interval is the item's kind, not the programme's size (every declared
    item is measured there; the full programme took about twice the CPU)."""
    from pathlib import Path

    from gonio.cli import main
    proto = ["--protocol", str(Path(__file__).parent / "data" / "pins" / f"{spec}-small.toml")]
    assert main(["simulate", "--spec", spec, *proto, "--seed", "0", "--out",
                 str(tmp_path / "s")]) == 0
    import contextlib
    import io
    import json
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["calibrate", str(tmp_path / "s" / "readings.csv"), "--spec", spec,
                     *proto, "--out", str(tmp_path / "c")]) == 0
    items = json.loads((tmp_path / "c" / "results.json").read_text(encoding="utf-8"))["items"]
    assert all(items[k]["measured"] for k in get(spec).magnitude_extremes)
    stated = {k for k, it in items.items()
              if (it.get("uncertainty") or {}).get("k_source") == K_SOURCE_MAX_MAGNITUDE}
    assert stated and stated == set(get(spec).magnitude_extremes)


@pytest.mark.parametrize("value", [2e-6, -1.58e-5, 9e-6])
@pytest.mark.parametrize("r, T_U, want", [
    # stated [0, 1.0×10⁻⁵], U = half-width 0.5e-5 whatever the (unprinted) estimate:
    # guarded passes where 1.0e-5 ≤ T_U − (r − 1)·0.5e-5
    (1.0, 1.0e-5, "pass"), (1.0, 0.99e-5, "fail"),
    (1.5, 1.25e-5, "pass"), (1.5, 1.24e-5, "fail"),
    (2.0, 1.5e-5, "pass"), (2.0, 1.49e-5, "fail"),
])
def test_the_same_printed_interval_gets_the_same_verdict(value, r, T_U, want):
    """The review's C_g: [0, 1.0e-5] with the estimate 2e-6 passed and with −1.58e-5 failed
    at r = 1.5 (U was "upper end − value"). U is the stated interval's half-width now."""
    (c,) = decide_items(interval_result(value, 0.0, 1.0e-5), [{"item": "C", "upper": T_U}],
                        {"rule": "guarded", "guard_band_factor": r})
    assert c.outcome == want
    assert c.U == pytest.approx(0.5e-5) and c.guard_band == pytest.approx(r * 0.5e-5)
    assert c.stated_interval[1] in ("0.000010", "1.00×10⁻⁵")     # as the statement prints


@pytest.mark.parametrize("rule", ["simple", "guarded", "non-binary"])
def test_simple_acceptance_decides_what_is_stated(rule):
    """C_g −1.58e-5 below its interval [0, 1.4e-5], mpe 1.5e-5: stated by the interval
    alone (the estimate fell below zero), so its stated value is 0, within ±1.5e-5: "pass" by
    every rule (the interval lies inside the tolerance); before, simple said "fail"."""
    (c,) = decide_items(interval_result(-1.58e-5, 0.0, 1.4e-5), [{"item": "C", "mpe": 1.5e-5}],
                        {"rule": rule})
    assert c.outcome == "pass"
    # and at the other limit: a stated value of 0 against a lower limit above it fails
    (c,) = decide_items(interval_result(-1.58e-5, 0.0, 1.4e-5), [{"item": "C",
                                                                    "lower": 1e-7}],
                        {"rule": rule})
    assert c.outcome in ("fail", "conditional fail")


def test_the_false_accept_bound_of_an_accepted_interval_item():
    """Accepted under a guard band (r ≥ 1) on a 95 % interval: the measurand lies above the
    interval's upper end with at most 1 − p = 5 % (a one-sided 95 % bound reaches it): stated
    "≤ 5.0 %" where no probability is computable. A χ² item keeps its exact probability
    (P(σ > T) = χ²_ν cdf(ν s²/T²) ≤ 5 % at T = its one-sided bound); simple acceptance states
    no bound."""
    from scipy.stats import chi2

    from gonio.report.i18n import labels
    from gonio.report.stated import conformity_texts
    (c,) = decide_items(interval_result(0.2, 0.0, 0.4), [{"item": "C", "upper": 0.5}],
                        {"rule": "guarded"})
    assert c.outcome == "pass" and c.false_accept_bound == pytest.approx(0.05)
    assert conformity_texts(c, None, labels("en"))["pfa"] == "≤ 5.0 %"
    (c,) = decide_items(interval_result(0.2, 0.0, 0.4), [{"item": "C", "upper": 0.5}],
                        {"rule": "simple"})
    assert c.false_accept_bound is None and conformity_texts(c, None, labels("en"))["pfa"] == "—"
    s, nu = 0.11278, 9.0
    hi = s * (nu / chi2.ppf(0.05, nu)) ** 0.5          # the one-sided 95 % bound, 0.18554
    (c,) = decide_items(interval_result(s, 0.0, hi, "chi-square", nu),
                        [{"item": "C", "upper": 0.19}], {"rule": "guarded"})
    assert c.outcome == "pass" and c.false_accept_bound is None
    assert c.false_accept_probability == pytest.approx(chi2.cdf(nu * s * s / 0.19 ** 2, nu),
                                                       rel=1e-9)
    assert c.false_accept_probability < 0.05


def test_k_from_a_non_normal_distribution_gives_no_normal_probability():
    """The review's K: U = 0.02336, k = 1.7275 from the JCGM 101 convolution of K's budget;
    N(y, U/k) gave p_c = 95.8 % at y = T_U − U, a probability of a distribution whose 95 %
    half-width is not U. No probability now, with the reason; a Welch–Satterthwaite k keeps
    the normal one (Φ(k) at y = T_U − U, by hand)."""
    from gonio.specs.ogam_draft.item_uncertainty import K_SOURCE_COMBINED
    assert K_SOURCE_COMBINED in NON_NORMAL_K_SOURCES
    U, k, T = 0.02336447992379669, 1.7275045253287247, 76434.87
    for source, want in ((K_SOURCE_COMBINED, None), ("welch-satterthwaite", normal_cdf(k))):
        unc = Uncertainty([], U / k, U, k, 50.0, None, 0.95, source)
        res = Result("ogam-draft", "d", {"scale_factor": Item(
            "scale_factor", "K", "7.1", "1", T - U, uncertainty=unc)}, {}, {})
        (c,) = decide_items(res, [{"item": "scale_factor", "lower": 76434.80, "upper": T}],
                            {"rule": "guarded"})
        assert c.outcome == "pass"
        if want is None:
            assert c.conformance_probability is None and c.false_accept_probability is None
            assert c.probability_model.startswith("not given") and "1.73" in \
                c.probability_model
            from gonio.report.i18n import translator    # the zh DCC states the reason too
            zh = translator()(f"— ({c.probability_model})")
            assert zh and "1.73" in zh and "不给出" in zh
        else:
            # on the value and U as printed (76434.847 ± 0.023: decided on what is stated,
            # tests/test_conformity_printed_value.py): T − y = U exactly, Φ(k) at T
            y_p, U_p = 76434.847, 0.023
            assert c.value == y_p and c.U == U_p
            assert c.conformance_probability == pytest.approx(want - normal_cdf(
                (76434.80 - y_p) / (U_p / k)), rel=1e-9)


@pytest.mark.parametrize("r", ["0.0", "0.5", "0.99"])
def test_a_lab_file_with_a_guard_factor_below_one_is_refused(tmp_path, r):
    """guarded, guard_band_factor 0.5 put the acceptance limit at 0.81 against ±0.5: the
    laboratory file is refused, one line naming the file and the key (exit 2 on the
    command line, as every GonioError); r = 1 is accepted, r = 0 under "simple" too."""
    from gonio.formats.lab import load_lab
    from gonio.resources import protocols_dir
    example = (protocols_dir() / "lab-example.toml").read_text(encoding="utf-8")
    given = 'rule = "non-binary"\nguard_band_factor = 1.0\n'
    assert given in example
    lab = tmp_path / "lab.toml"
    for rule in ("guarded", "non-binary"):
        lab.write_text(example.replace(given, f'rule = "{rule}"\nguard_band_factor = {r}\n'),
                       encoding="utf-8")
        with pytest.raises(GonioError) as e:
            load_lab(lab)
        msg = str(e.value)
        assert msg.startswith(f"{lab}: key decision_rule.guard_band_factor: ") and "\n" not in msg
        assert "r ≥ 1" in msg
    lab.write_text(example.replace(given, 'rule = "simple"\nguard_band_factor = 0.0\n'),
                   encoding="utf-8")
    load_lab(lab)


def test_the_cli_refuses_a_guard_factor_below_one(tmp_path, capsys):
    from gonio.cli import main
    from gonio.resources import protocols_dir
    example = (protocols_dir() / "lab-example.toml").read_text(encoding="utf-8")
    lab = tmp_path / "lab.toml"
    lab.write_text(example.replace('rule = "non-binary"\nguard_band_factor = 1.0\n',
                                   'rule = "guarded"\nguard_band_factor = 0.5\n'),
                   encoding="utf-8")
    readings = tmp_path / "readings.csv"
    readings.write_text("# spec: ogam-draft\n", encoding="utf-8")
    rc = main(["calibrate", str(readings), "--spec", "ogam-draft", "--lab", str(lab),
               "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1 and "guard_band_factor" in err, err


@pytest.mark.parametrize("r, T_U, want", [
    # stated 1.808, ≤ 1.833: U = the limit's reach above the estimate, 0.025 (a + R), as a χ²
    # bound's; guarded passes where 1.833 ≤ T_U − (r − 1)·0.025
    (1.0, 1.833, "pass"), (1.0, 1.832, "fail"),
    (2.0, 1.858, "pass"), (2.0, 1.857, "fail"),
])
def test_a_dispersions_one_sided_bound_condition_is_guarded_by_its_reach(r, T_U, want):
    """A noise item stated by its one-sided bound condition [0, (s + R)/(1 − g)]
    (gonio.result.statement.K_SOURCE_BOUND_CHI2): the guard band's U is the printed limit's
    reach above the printed estimate (not the interval's half-width, 0.92, which would make
    any guarded decision fail), and no probability of a normal or χ² model is claimed."""
    from gonio.result.statement import K_SOURCE_BOUND_CHI2

    (c,) = decide_items(interval_result(1.808, 0.0, 1.8326, K_SOURCE_BOUND_CHI2, 18264.2),
                        [{"item": "C", "upper": T_U}],
                        {"rule": "guarded", "guard_band_factor": r})
    assert c.outcome == want, c
    assert c.U == pytest.approx(0.025) and c.guard_band == pytest.approx(r * 0.025)
    assert c.false_accept_probability is None


@pytest.mark.parametrize("lower, upper, rule, want", [
    # warm-up 23 s, U 31 s (k 2.18): stated "≤ 54 s (interval [0, 54])"; worked by hand on
    # that interval (U = 54/2 = 27 for r > 1): [-5, 60] holds [0, 54] → pass; ≤ 50 does not
    # hold 54 but holds 23 → conditional pass (non-binary); r = 1.1 moves the ends in by 2.7
    (-5.0, 60.0, "non-binary", "pass"), (None, 50.0, "non-binary", "conditional pass"),
    (None, 56.0, "guarded", "fail"), (None, 56.8, "guarded", "pass"),
])
def test_an_item_stated_by_its_upper_bound_is_decided_on_that_interval(lower, upper, rule, want):
    """A non-negative item whose U reaches below zero is stated "≤ b (interval [0, b])" and
    shows no U and no k: it is decided on that interval, as every item stated by an interval
    is, never on a value ± U with a normal model the certificate does not print (JJF
    warm-up 23 s: [−5, 60] gave "conditional pass, probability of conformance 88 %" while
    the stated [0, 54] lies within the limits)."""
    unc = Uncertainty([], 31.0 / 2.18, 31.0, 2.18, 12.0, None, 0.95, "welch-satterthwaite")
    res = Result("s", "S", {"W": Item("W", "W", "7.2.9", "s", 23.0, uncertainty=unc,
                                      nonnegative=True)}, {}, {})
    lim = {"item": "W", **({"lower": lower} if lower is not None else {}), "upper": upper}
    guard = {"guard_band_factor": 1.1} if rule == "guarded" else {}
    (c,) = decide_items(res, [lim], {"rule": rule, **guard})
    assert c.outcome == want, (lower, upper, rule, c)
    assert c.conformance_probability is None
