"""Conformity of the items stated by a 95 % interval alone (k None), checked against hand
calculations of ILAC-G8:09/2019 4.2 and JCGM 106:2012 7.3 / 8.3:

* an extreme of magnitudes (the optical draft's E = ± max|E_i|, 7.4) takes a symmetric limit
  only: against [−0.4, 0.6] an E_i = −0.45″ beside max|E_i| = 0.45″ "passed" every rule;
* the acceptance interval of an item stated by its interval under a guard band bounds the
  interval's ends (at r = 1 the tolerance itself), never "value ≤ T_U − U", a negative
  limit of a non-negative quantity;
* a probability of conformance is given only where the interval's distribution is one gonio
  has (the χ² model of a standard deviation); a Neyman belt, a half range, a folded-normal
  maximum, a pivot or an outcome distribution gets none: N(y, u_c) with the belt's
  bias-corrected y contradicted the stated interval (C_g: 0.26 % false accept at a limit
  above the interval's upper end, K_l 6.1 %).
"""

from __future__ import annotations

import json
import re
import tomllib
from dataclasses import replace
from pathlib import Path

import pytest
from scipy.special import gammaincc

from gonio.analysis.conformity import decide_items
from gonio.errors import GonioError
from gonio.result.statement import given_text
from gonio.formats.lab import naming_lab_file
from gonio.result.model import Item, Result, Uncertainty
from gonio.result.statement import K_SOURCE_MAX_ABS
from gonio.resources import protocols_dir
from gonio.specs import get

RULES = ("simple", "guarded", "non-binary")


def e_result(signed: float, lo: float, hi: float, magnitude: float) -> Result:
    """E stated by the 95 % interval [lo, hi] of max|E_i| = ``magnitude`` (U = hi − max|E_i|),
    its value the signed extreme."""
    unc = Uncertainty([], 0.05, hi - magnitude, None, None, None, 0.95, K_SOURCE_MAX_ABS,
                      (lo, hi))
    return Result("ogam-draft", "draft", {"angle_deviation": Item(
        "angle_deviation", "E", "7.4", "arcsec", signed, uncertainty=unc,
        details={"max_abs_arcsec": magnitude})}, {}, {})


@pytest.mark.parametrize("rule", RULES)
@pytest.mark.parametrize("limit", [{"lower": -0.4, "upper": 0.6}, {"upper": 0.6},
                                   {"lower": -0.4}, {"lower": -0.05, "upper": 0.5}])
def test_an_extreme_of_magnitudes_refuses_an_asymmetric_limit(rule, limit):
    """E_i = −0.45″ is the extreme; max|E_i| = 0.45, interval [0.30, 0.55]: against
    [−0.4, 0.6] the instrument violates the lower limit, which neither max|E_i| nor its
    interval can show. Refused, naming the laboratory file's entry (exit 2 on the CLI)."""
    res = e_result(-0.45, 0.30, 0.55, 0.45)
    with pytest.raises(GonioError) as exc, naming_lab_file("lab.toml"):
        decide_items(res, [{"item": "angle_deviation", **limit}], {"rule": rule})
    assert str(exc.value).startswith("lab.toml: key specification_limits[0]: ")
    assert "symmetric" in str(exc.value) and "\n" not in str(exc.value)
    # the draft's own statement max|E_i| ± U (k given) carries no marker: the
    # specification's declaration (SPEC.magnitude_extremes) makes it an extreme of magnitudes,
    # never a detail key of the optical draft's output
    draft = Result("ogam-draft", "draft", {"angle_deviation": Item(
        "angle_deviation", "E", "7.4", "arcsec", 0.45,
        uncertainty=Uncertainty([], 0.05, 0.1, 2.0, None),
        details={"max_abs_arcsec": 0.45})}, {}, {})
    with pytest.raises(GonioError, match="symmetric"):
        decide_items(draft, [{"item": "angle_deviation", **limit}], {"rule": rule},
                     magnitude_extremes=get("ogam-draft").magnitude_extremes)
    # undeclared and unmarked, the detail key alone decides nothing about the limit's shape
    decide_items(draft, [{"item": "angle_deviation", **limit}], {"rule": rule})


@pytest.mark.parametrize("limit", [{"lower": -0.4, "upper": 0.6}, {"upper": 0.6},
                                   {"lower": -0.4}])
def test_an_asymmetric_limit_of_a_declared_extreme_is_refused_before_any_work(
        tmp_path, monkeypatch, limit):
    """The laboratory file's check (load_lab_file with the specification) refuses it in one
    line naming the file and the entry, before the calibration runs: the calibration hook
    is replaced by one that fails the test if called."""
    from gonio.pipeline.dispatch import load_lab_file

    ends = "\n".join(f"{k} = {v}" for k, v in limit.items())
    example = (protocols_dir() / "lab-example.toml").read_text(encoding="utf-8")
    given = 'item = "angle_deviation"\nmpe = 0.5\n'
    assert given in example
    lab = tmp_path / "lab.toml"
    lab.write_text(example.replace(given, f'item = "angle_deviation"\n{ends}\n'),
                   encoding="utf-8")
    with pytest.raises(GonioError) as exc:
        load_lab_file(lab, get("ogam-draft"))
    msg = str(exc.value)
    assert msg.startswith(f"{lab}: key specification_limits[0]: angle_deviation is an extreme")
    assert "symmetric" in msg and "\n" not in msg
    lab.write_text(example, encoding="utf-8")
    assert load_lab_file(lab, get("ogam-draft"))["specification_limits"][0]["mpe"] == 0.5
    lab.write_text(example.replace(given, given.replace("mpe = 0.5", "lower = -0.5\nupper = 0.5")),
                   encoding="utf-8")
    load_lab_file(lab, get("ogam-draft"))
    # a specification that declares nothing takes the same file's shape of limit as it is
    assert get("triad-alignment").magnitude_extremes == ()


def test_the_cli_refuses_before_calibrating(tmp_path, monkeypatch, capsys):
    """`gonio calibrate --lab` with an asymmetric E limit: exit 2, one line naming the file
    and the key, the calibration never called."""
    import gonio.pipeline.dispatch as dispatch
    from gonio.cli import main

    def never(*args, **kwargs):
        raise AssertionError("calibrated before the lab file's check")
    monkeypatch.setattr(dispatch, "calibrate", never)
    example = (protocols_dir() / "lab-example.toml").read_text(encoding="utf-8")
    lab = tmp_path / "lab.toml"
    lab.write_text(example.replace('item = "angle_deviation"\nmpe = 0.5\n',
                                   'item = "angle_deviation"\nlower = -0.4\nupper = 0.6\n'),
                   encoding="utf-8")
    readings = tmp_path / "readings.csv"
    readings.write_text("# spec: ogam-draft\n", encoding="utf-8")
    rc = main(["calibrate", str(readings), "--spec", "ogam-draft", "--lab", str(lab),
               "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert rc == 2, err
    assert len(err.splitlines()) == 1 and "specification_limits[0]" in err \
        and str(lab) in err and "symmetric" in err


@pytest.mark.parametrize("mpe, expected", [
    # hand: simple decides max|E_i| = 0.45 against ±MPE (ILAC-G8 4.2.1); guarded (r = 1)
    # passes where the interval's upper end 0.55 ≤ MPE (4.2.2); non-binary (4.2.3): inside
    # the tolerance but within w → conditional pass, outside with the interval reaching back
    # in (lower end 0.30 ≤ MPE) → conditional fail
    (0.4, {"simple": "fail", "guarded": "fail", "non-binary": "conditional fail"}),
    (0.5, {"simple": "pass", "guarded": "fail", "non-binary": "conditional pass"}),
    (0.6, {"simple": "pass", "guarded": "pass", "non-binary": "pass"}),
    (0.25, {"simple": "fail", "guarded": "fail", "non-binary": "fail"}),
])
def test_an_extreme_of_magnitudes_against_a_symmetric_limit(mpe, expected):
    for rule in RULES:
        for lim in ({"mpe": mpe}, {"lower": -mpe, "upper": mpe}):
            res = e_result(-0.45, 0.30, 0.55, 0.45)
            (c,) = decide_items(res, [{"item": "angle_deviation", **lim}], {"rule": rule})
            assert c.outcome == expected[rule], (mpe, rule, lim)
            assert c.value == pytest.approx(0.45)            # max|E_i|, not the signed −0.45
            assert c.conformance_probability is None and c.false_accept_probability is None
            if rule != "simple":        # the interval's upper end ≤ MPE (a magnitude's
                assert (c.acceptance_of, c.acceptance_lower, c.acceptance_upper) == \
                    ("interval", None, mpe)   # interval lies above 0: no lower end stated)


def belt_result(value: float, lo: float, hi: float, k_source: str = "neyman-belt",
                nu: float | None = None, nonnegative: bool = True) -> Result:
    unc = Uncertainty([], (hi - lo) / 4, hi - value, None, nu, None, 0.95, k_source, (lo, hi))
    return Result("s", "S", {"C": Item("C", "range", "7.7", "%", value, uncertainty=unc,
                                       nonnegative=nonnegative)}, {}, {})


@pytest.mark.parametrize("value, hi, T_U, r, outcome", [
    # the review's C_g: y = −1.58e−5 (bias-corrected, below zero), interval [0, 3.90e−5]
    # stated [0, 4.0×10⁻⁵] (2 digits of hi − y = 5.5e−5: 1e−6 places, the end rounded up);
    # U = half-width 2.0e−5. Against 3.95e−5 the printed end lies beyond the limit: fail
    (-1.5776e-5, 3.9004e-5, 3.95e-5, 1.0, "fail"),
    (-1.5776e-5, 3.9004e-5, 4.0e-5, 1.0, "pass"),
    # K_l: y = 5.05e−5, interval [0, 1.73e−4] stated [0, 1.8×10⁻⁴] (1e−5 places); U = 9e−5
    (5.0456e-5, 1.7323e-4, 1.0e-4, 1.0, "fail"),
    (5.0456e-5, 1.7323e-4, 1.8e-4, 1.0, "pass"),
    # r = 2: the upper end must lie at T_U − (r − 1)·U = T_U − 9e−5
    (5.0456e-5, 1.7323e-4, 2.6e-4, 2.0, "fail"),
    (5.0456e-5, 1.7323e-4, 2.7e-4, 2.0, "pass"),
])
def test_the_acceptance_of_an_interval_item_bounds_the_interval(value, hi, T_U, r, outcome):
    """Guarded, w = r·U with U the half-width of the interval as stated: the centre within
    T_U − r·U is the stated upper end ≤ T_U − (r − 1)·U (JCGM 106 8.3.2 rewritten on the
    interval's upper end): at r = 1 the tolerance limit itself."""
    hi_s = {3.9004e-5: 4.0e-5, 1.7323e-4: 1.8e-4}[hi]        # by hand, as stated
    U = hi_s / 2
    (c,) = decide_items(belt_result(value, 0.0, hi), [{"item": "C", "upper": T_U}],
                        {"rule": "guarded", "guard_band_factor": r})
    assert c.outcome == outcome
    assert c.acceptance_of == "interval"
    assert c.U == pytest.approx(U, rel=1e-12) and c.guard_band == pytest.approx(r * U)
    assert c.acceptance_upper == pytest.approx(T_U - (r - 1.0) * U, rel=1e-12, abs=1e-18)
    if r == 1.0:
        assert c.acceptance_upper == T_U                   # exactly the limit as given
    # simple acceptance decides the value as stated (0 for an estimate below zero)
    (s,) = decide_items(belt_result(value, 0.0, hi), [{"item": "C", "upper": T_U}],
                        {"rule": "simple"})
    assert s.acceptance_of == "value" and s.acceptance_upper == T_U
    assert s.outcome == "pass"


def test_a_guard_band_that_empties_the_acceptance_interval_is_said_in_words():
    """r = 3 with U = 1.2277e−4 > T_U/2: T_U − 2U < 0 ≤ the interval's upper end, nothing can
    pass: "none", never a negative limit of a non-negative quantity."""
    from gonio.report.i18n import labels
    from gonio.report.stated import conformity_texts

    (c,) = decide_items(belt_result(5.0456e-5, 0.0, 1.7323e-4), [{"item": "C",
                                                                     "upper": 1.75e-4}],
                        {"rule": "guarded", "guard_band_factor": 3.0})
    assert c.acceptance_empty and c.outcome == "fail"
    for lang in ("en", "zh"):
        L = labels(lang)
        assert conformity_texts(c, None, L)["acceptance"] == L["c_acc_empty"]
    (c,) = decide_items(belt_result(5.0456e-5, 0.0, 1.7323e-4), [{"item": "C",
                                                                     "upper": 1.75e-4}],
                        {"rule": "guarded"})
    t = conformity_texts(c, None, labels("en"))
    assert t["acceptance"] == "interval's upper end ≤ 0.000175" and not c.acceptance_empty
    assert labels("zh")["c_acc_iv_upper"].format(hi="x") == "区间上端 ≤ x"


#: The interval-stated items (k None) of the four specifications' seed-0 demos, each with
#: its k_source, as results.json holds them: (spec, item, value, interval, k_source, ν). The
#: triad's are its ARW values (χ², as JJF's bias stability; not repeated here) — its bound
#: conditions carry a k.
INTERVAL_ITEMS = [
    ("ogam-draft", "scale_factor_nonlinearity", 5.0456e-05, (0.0, 1.7323e-04), "neyman-belt",
     None),
    ("ogam-draft", "rate_consistency", 0.36938, (0.0, 4.7471), "neyman-belt", None),
    ("ogam-draft", "pointing_consistency", -1.5776e-05, (0.0, 3.9004e-05), "neyman-belt",
     None),
    ("ogam-draft", "zero_stability", 2.8333e-04, (0.0, 4.5183e-03), "chi-square", 1.02079),
    ("ogam-draft", "repeatability", 0.11278, (0.0, 0.18554), "chi-square", 9.0),
    ("jjf1535-2015", "sf_repeatability", 1.5250e-04, (0.0, 6.7333e-04), "chi-square", 2.0),
    ("jjf1535-2015", "bias_stability", 51.412, (0.0, 58.125), "chi-square", 103.03),
    ("jjf1535-2015", "threshold", 0.01, (0.01, 0.1), "outcome distribution", None),
    ("jjf1535-2015", "resolution", 0.05, (0.03, 0.1), "outcome distribution", None),
    ("iec62047-20", "bias_repeatability", 2.9527e-03, (0.0, 1.1585e-02), "normal range", 2.0),
    ("iec62047-20", "bias_hysteresis", 0.0, (0.0, 0.12229), "folded-normal maximum", None),
    ("iec62047-20", "bias_instability", 23.648, (18.264, 31.015),
     "floor rule's distribution (pivot)", None),
    ("iec62047-20", "resolution", 0.012234, (0.002, 0.05), "outcome distribution", None),
]


@pytest.mark.parametrize("spec, key, value, interval, source, nu", INTERVAL_ITEMS,
                         ids=[f"{s}:{k}" for s, k, *_ in INTERVAL_ITEMS])
def test_a_probability_only_from_the_interval_s_own_distribution(spec, key, value, interval,
                                                                 source, nu):
    """χ² items: p_c = P(σ ≤ T_U) with σ = s·√(ν/χ²_ν) (JCGM 106 7.3), by hand through the
    regularised incomplete gamma function Q(ν/2, ν s²/(2 T²)); at T_U = the interval's upper
    end it is the interval's own 95 %. Every other interval: no probability, the reason in
    ``probability_model``, the outcome from the interval alone."""
    lo, hi = interval
    unc = Uncertainty([], (hi - lo) / 4, hi - value, None, nu, None, 0.95, source, interval)
    for T_U in (hi * 1.2, hi * 0.8):         # clear of the stated end's outward rounding
        for rule in RULES:
            res = Result(spec, spec, {key: Item(key, key, "-", "u", value, uncertainty=unc,
                                                nonnegative=True)}, {}, {})
            (c,) = decide_items(res, [{"item": key, "upper": T_U}], {"rule": rule})
            if rule == "guarded":
                assert c.outcome == ("pass" if hi <= T_U else "fail")
            if source == "chi-square" and value > 0:
                nu_stated = float(int(nu))                  # ν as stated (integer part)
                p = gammaincc(nu_stated / 2.0, nu_stated * value ** 2 / (2.0 * T_U ** 2))
                assert c.conformance_probability == pytest.approx(p, rel=1e-9)
                assert c.probability_model.startswith("chi-square")
            else:
                assert c.conformance_probability is None
                assert c.false_accept_probability is None
                assert c.false_reject_probability is None
                assert c.probability_model.startswith("not given") and source in \
                    c.probability_model


def test_the_chi_square_probability_at_the_interval_s_end_is_its_coverage():
    """R, s = 0.11278″, ν = 9, χ² interval [0, 0.18554]: P(σ ≤ 0.18554) = 95 % (the interval
    is the one-sided 95 % bound s·√(ν/χ²_{0.05,ν}))."""
    res = belt_result(0.11278, 0.0, 0.18554, "chi-square", 9.0)
    (c,) = decide_items(res, [{"item": "C", "upper": 0.11278 * (9 / 3.3251128)
                               ** 0.5}], {"rule": "simple"})
    assert c.conformance_probability == pytest.approx(0.95, abs=1e-5)


# ------------------------------------------------------- the optical draft, end to end

SMALL = tomllib.loads((Path(__file__).parent / "data" / "small-protocol.toml")
                      .read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def optical(tmp_path_factory):
    """A short optical-draft session (20 Hz), calibrated: K_l and C_v stated by a Neyman belt
    with their bias-corrected estimates below zero, B_s and R by χ², E by max|E_i|."""
    from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
    from gonio.specs.ogam_draft.calibration import calibrate
    from gonio.specs.ogam_draft.protocol import parse_protocol

    d = tmp_path_factory.mktemp("conf_iv")
    proto = parse_protocol(SMALL)
    session = run_session(proto, replace(load_bench("rlg"), sample_rate_hz=20.0), seed=7)
    write_session(session, d)
    return d, calibrate(d / "readings.csv", proto, static_record=session.static_record)


def _lab(limits: list[dict], rule: str = "guarded") -> dict:
    from gonio.formats.lab import load_lab
    from gonio.resources import protocols_dir

    lab = load_lab(protocols_dir() / "lab-example.toml")
    return {**lab, "decision_rule": {"rule": rule, "guard_band_factor": 1.0, "agreed": "t"},
            "specification_limits": [{"source": "test", "lower": None, "upper": None,
                                      "mpe": None, **lim} for lim in limits]}


def test_optical_certificate_states_no_negative_acceptance_limit(optical, tmp_path):
    """The review's case on real items: guarded, r = 1, limits below the belt's reach. The
    certificate, summary.txt and results.json give "interval's upper end ≤ T_U", the
    outcome "pass" exactly where the stated interval's upper end is ≤ T_U, no probability
    for the belt items (the note says why) and the χ² one for R."""
    from gonio.pipeline.dispatch import decide_conformity
    from gonio.specs.ogam_draft.outputs import write

    _, result = optical
    items = result.items
    # each limit below its item's U (two significant digits of 0.9 U): the old acceptance
    # T_U − U lay below zero
    lims = {k: float(f"{0.9 * items[k].uncertainty.U:.2g}")
            for k in ("scale_factor_nonlinearity", "rate_consistency", "zero_stability",
                      "repeatability")}
    for key, T in lims.items():        # the old acceptance T_U − U lay below zero
        assert T - items[key].uncertainty.U < 0
    lab = _lab([{"item": k, "upper": T} for k, T in lims.items()]
               + [{"item": "angle_deviation", "mpe": 1.0}])
    decide_conformity(result, lab)
    write(result, tmp_path / "out", lab=lab, dcc=True)
    res = json.loads((tmp_path / "out" / "results.json").read_text(encoding="utf-8"))
    for key, T in lims.items():
        c = res["items"][key]["conformity"]
        hi = res["items"][key]["uncertainty"]["interval"][1]
        assert c["acceptance_of"] == "interval" and c["acceptance_upper"] == T
        # decided on the interval as stated (its ends rounded outward, at the digits the
        # belt's draws support) and as computed, the stricter of the two
        hi = max(hi, float(c["stated_interval"][1]))
        assert c["outcome"] == ("pass" if hi <= T else "fail"), key
        chi2 = res["items"][key]["uncertainty"]["k_source"] == "chi-square"
        assert (c["conformance_probability"] is not None) == chi2, key
    html = (tmp_path / "out" / "certificate.html").read_text(encoding="utf-8")
    table = html[html.index('id="conformity"'):]
    table = table[:table.index("</table>")]
    assert not re.search(r"≤\s*[−-]", table)
    assert table.count("interval&#x27;s upper end ≤") + table.count("interval's upper end ≤") \
        == 5            # the four above and E (an extreme of magnitudes: its upper end only)
    assert "no probability is stated for" in html
    summary = (tmp_path / "out" / "summary.txt").read_text(encoding="utf-8")
    assert "acceptance ≤ -" not in summary and "acceptance ≤ −" not in summary
    assert "interval's upper end ≤ " + given_text(lims["scale_factor_nonlinearity"]) in summary


def test_optical_asymmetric_e_limit_is_refused(optical):
    from gonio.pipeline.dispatch import decide_conformity

    _, result = optical
    with pytest.raises(GonioError, match=r"key specification_limits\[0\]: angle_deviation"):
        decide_conformity(result, _lab([{"item": "angle_deviation", "lower": -0.05,
                                         "upper": 0.5}]))


def test_rate_certificates_table_notes_the_items_without_a_probability():
    """The shared conformity table (JJF, IEC, the triad): "—" for an item whose interval is
    not normal or χ² (IEC bias instability's pivot), the note naming it; a χ² item (JJF bias
    stability) keeps its probability and is not named."""
    from gonio.report.i18n import labels
    from gonio.report.stated import conformity_blocks

    res = {}
    for spec, key, value, interval, source, nu in INTERVAL_ITEMS:
        if key not in ("bias_instability", "bias_stability"):
            continue
        lo, hi = interval
        unc = Uncertainty([], (hi - lo) / 4, hi - value, None, nu, None, 0.95, source, interval)
        r = Result(spec, spec, {key: Item(key, key, "-", "°/h", value, uncertainty=unc,
                                          nonnegative=True)}, {}, {})
        (c,) = decide_items(r, [{"item": key, "upper": hi * 1.1}], {"rule": "guarded"})
        res[key] = {"conformity": c.to_dict(), "nonnegative": True}
    for lang in ("en", "zh"):
        L = labels(lang)
        blocks = conformity_blocks(res, L, lambda k: f"<{k}>", lambda k: "°/h",
                                   lambda kind, data, extra: (kind, data, extra))
        rows = next(d for kind, d, _ in blocks if kind == "table")[1]
        pfa = {row[0]: row[-1] for row in rows}
        # accepted under a guard band on its interval: the bound the rule implies (1 − p)
        assert pfa["<bias_instability>"] == "≤ 5.0 %"
        assert pfa["<bias_stability>"].endswith("%") and "≤" not in pfa["<bias_stability>"]
        notes = [d[0] for kind, d, _ in blocks if kind == "p" and "<bias_instability>" in d[0]
                 and d[0].startswith("“—”")]
        assert len(notes) == 1 and "<bias_stability>" not in notes[0]
        assert all(not re.search(r"≤\s*[−-]", str(row[2])) for row in rows)


@pytest.mark.parametrize("rule,r", [("simple", 1.0), ("guarded", 1.0), ("guarded", 1.14),
                                    ("guarded", 1.15), ("guarded", 2.0),
                                    ("non-binary", 1.0), ("non-binary", 2.0)])
def test_a_value_below_its_own_interval_is_decided_on_the_interval(rule, r):
    """C_g non-negative, its bias-corrected y = −1.58e-5 below its 95 % interval [0, 1.4e-5],
    mpe 1.5e-5; stated "≤ 1.4×10⁻⁵ (interval [0, 1.4×10⁻⁵]); the estimate fell below zero".
    By hand (ILAC-G8 4.2.1/4.2.2 on what is stated): simple decides the stated value, 0
    (the least value the statement admits): pass. Guarded: U = half-width 0.7e-5, pass where
    1.4e-5 ≤ 1.5e-5 − (r − 1)·0.7e-5 ⇔ r ≤ 1 + 1/7 ≈ 1.143. Non-binary beyond that:
    conditional pass (the stated value 0 lies within the tolerance). Before, simple said
    "fail" (on the unprinted −1.58e-5) where guarded said "pass"."""
    y, lo, hi, mpe = -1.58e-5, 0.0, 1.4e-5, 1.5e-5
    U = hi - y
    unc = Uncertainty([], U / 2, U, None, None, None, 0.95, "belt", (lo, hi))
    res = Result("s", "S", {"C_g": Item("C_g", "C_g", "x", "", y, uncertainty=unc,
                                        nonnegative=True)}, {}, {})
    c = decide_items(res, [{"item": "C_g", "mpe": mpe}],
                     {"rule": rule, "guard_band_factor": r})[0]
    assert c.value == 0.0 and c.stated_interval == ("0", "0.000014")
    if rule == "simple":
        assert c.outcome == "pass" and c.acceptance_of == "value" and c.guard_band == 0
        return
    hand_pass = r <= 1 + 1 / 7
    assert c.acceptance_of == "interval"
    assert c.U == pytest.approx(0.7e-5) and c.guard_band == pytest.approx(r * 0.7e-5)
    assert c.acceptance_upper == pytest.approx(mpe - (r - 1.0) * 0.7e-5)
    assert c.acceptance_lower == pytest.approx(-mpe + (r - 1.0) * 0.7e-5)
    if hand_pass:
        assert c.outcome == "pass" and c.accepted
    else:
        assert c.outcome == ("fail" if rule == "guarded" else "conditional pass")
    assert c.false_accept_probability is None and c.conformance_probability is None
    assert c.false_accept_bound == (pytest.approx(0.05) if hand_pass else None)


@pytest.mark.parametrize("rule", ["guarded", "non-binary"])
@pytest.mark.parametrize("r", [0.0, 0.5, 0.99])
def test_a_guard_factor_below_one_is_refused(rule, r):
    """r < 1 under a guard band would accept a 95 % interval reaching past the limit (the
    review's "≤ 0.81" against ±0.5 at r = 0.5): refused, one line naming the key."""
    with pytest.raises(GonioError, match=r"key decision_rule.guard_band_factor: .*r ≥ 1") as e:
        decide_items(belt_result(0.1, 0.0, 0.2), [{"item": "C", "upper": 0.5}],
                     {"rule": rule, "guard_band_factor": r})
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("r", [1.0, 2.0])
def test_the_guard_band_of_e_is_stated_with_the_intervals_reach(r):
    """Under a guard band, the δ of w = r·δ (U's place in w = r·U) for E is the half-width of
    its stated interval [0.30, 0.55]: (0.55 − 0.30)/2 = 0.125, printed beside the decision rule in en and zh with
    w: never the draft's Annex A U (here 0.38, k = 2.13) that the certificate states beside
    E, and never the signed extreme (−0.45)."""
    from gonio.report.i18n import labels
    from gonio.report.stated import interval_band_note

    res = e_result(-0.45, 0.30, 0.55, 0.45)
    (c,) = decide_items(res, [{"item": "angle_deviation", "mpe": 0.8}],
                        {"rule": "guarded", "guard_band_factor": r},
                        magnitude_extremes=("angle_deviation",))
    assert c.acceptance_upper == pytest.approx(0.8 - (r - 1) * 0.125)
    for lang in ("en", "zh"):
        note = interval_band_note([("angle_deviation", c.to_dict())], labels(lang),
                                  lambda k: "E", lambda k: "″")
        w = "0.125" if r == 1.0 else "0.25"
        assert f"E: δ = (0.55 − 0.30)/2 ″ = 0.125 ″, w = {w} ″" in note.replace(
            "E：", "E: ").replace("，", ", "), note
        assert "0.38" not in note and "−0.45" not in note.replace("− 0.45", "")
    # simple acceptance has no guard band: no note
    (c,) = decide_items(e_result(-0.45, 0.30, 0.55, 0.45), [{"item": "angle_deviation",
                                                               "mpe": 0.8}], {"rule": "simple"})
    assert interval_band_note([("angle_deviation", c.to_dict())], labels("en"),
                              lambda k: "E", lambda k: "″") == ""


@pytest.mark.parametrize("r", [1.0, 2.0])
def test_printed_numbers_never_contradict_the_decision(r):
    """E = 0.40, interval [0.35, hi] for hi on a fine grid around the review's 0.4707,
    limits ±0.4709 … ±0.52: the interval's upper end as the item's statement prints it
    (rounded up) and the acceptance limit as the conformity table prints it (rounded down at
    the same place, or the limit as given) are in the order of the outcome, always: the
    review's "≤ 0.48 … acceptance ≤ 0.47: pass" cannot be printed."""
    from dataclasses import asdict

    from gonio.report import i18n
    from gonio.report.stated import conformity_texts
    from gonio.result.statement import item_statement
    seen = set()
    for i in range(60):
        hi = 0.4650 + i * 0.0002
        for mpe in (0.4709, 0.48, 0.5, 0.52, 0.53, 0.54):
            res = e_result(0.40, 0.35, hi, 0.40)
            c = decide_items(res, [{"item": "angle_deviation", "mpe": mpe}],
                             {"rule": "guarded", "guard_band_factor": r})[0]
            st_hi = item_statement(res.items["angle_deviation"]).interval[1]
            text = conformity_texts(asdict(c), None, i18n.labels("en"))["acceptance"]
            acc = re.search(r"≤ (\S+)", text).group(1)
            assert (c.outcome == "pass") == (float(st_hi) <= float(acc)), (hi, mpe, st_hi, text)
            seen.add(c.outcome)
    assert seen == {"pass", "fail"}


def outcome_item(value: float, lo: float, hi: float) -> Result:
    """JJF 7.2.6's threshold stated by its outcome distribution's interval [lo, hi], the
    value its grid's outcome (on the interval's upper end as often as not: U = hi − value
    may be 0)."""
    unc = Uncertainty([], 0.01, hi - value, None, None, None, 0.982, "rule-outcome",
                      (lo, hi))
    return Result("jjf1535-2015", "JJF", {"threshold": Item(
        "threshold", "threshold", "7.2.6", "°/s", value, uncertainty=unc,
        nonnegative=True)}, {}, {})


@pytest.mark.parametrize("rule", RULES)
@pytest.mark.parametrize("upper,outcome", [(0.04, "fail"), (0.1, "pass"), (0.05, "pass")])
def test_a_value_on_its_interval_s_upper_end_is_decided(rule, upper, outcome):
    """The value 0.050 on its interval [0.020, 0.050]'s upper end (U = 0): decided on the
    interval, by hand — ≤ 0.04 fails (the value above the limit; under the non-binary rule a
    conditional fail: the interval still reaches into the tolerance, ILAC-G8 4.2.3), ≤ 0.1
    passes every rule (r = 1: the interval within it), ≤ 0.05 passes (the interval's upper
    end on the limit). Before, U = 0 read as 'no expanded uncertainty to decide with' and no
    decision was made."""
    c, = decide_items(outcome_item(0.05, 0.02, 0.05), [{"item": "threshold", "upper": upper}],
                      {"rule": rule, "guard_band_factor": 1.0})
    if rule == "non-binary" and outcome == "fail":
        outcome = "conditional fail"
    assert c.outcome == outcome, c


def test_a_degenerate_interval_is_not_decided():
    """An interval of no width states nothing to decide with (no decision, said so)."""
    c, = decide_items(outcome_item(0.05, 0.05, 0.05), [{"item": "threshold", "upper": 0.1}],
                      {"rule": "simple"})
    assert c.outcome is None


def test_the_jjf_threshold_and_resolution_are_decided_end_to_end(tmp_path, capsys):
    """A JJF programme of the virtual bench with limits on the threshold and the resolution:
    both are decided in results.json and summary.txt, each as its stated interval says
    (computed here from the stated ends, not by gonio's rule)."""
    from gonio.cli import main
    from tests.test_rate_dcc import _simulate

    _, proto, path, _ = _simulate("jjf1535-2015", tmp_path, 5)
    assert main(["calibrate", str(path), "--protocol", str(proto), "--out",
                 str(tmp_path / "out")]) == 0
    items = json.loads((tmp_path / "out" / "results.json").read_text())["items"]
    limits = {}
    for key in ("threshold", "resolution"):
        lo, hi = items[key]["uncertainty"]["interval"]
        assert hi > lo
        limits[key] = (hi + (hi - lo), "pass") if key == "threshold" else (lo / 2, "fail")
    lab = tmp_path / "lab.toml"
    lab.write_text((protocols_dir() / "lab-example.toml").read_text(encoding="utf-8").split(
        "[decision_rule]")[0] + '[identity]\non_mismatch = "proceed"\n'
        '[decision_rule]\nrule = "simple"\nagreed = "test"\n' + "".join(
        f'[[specification_limits]]\nitem = "{k}"\nupper = {v[0]!r}\nsource = "test"\n'
        for k, v in limits.items()), encoding="utf-8")
    capsys.readouterr()
    code = main(["calibrate", str(path), "--protocol", str(proto), "--out",
                 str(tmp_path / "lab"), "--lab", str(lab)])
    if code != 0:
        pytest.fail(capsys.readouterr().err)
    items = json.loads((tmp_path / "lab" / "results.json").read_text())["items"]
    summary = (tmp_path / "lab" / "summary.txt").read_text()
    for key, (_, outcome) in limits.items():
        assert items[key]["conformity"]["outcome"] == outcome, items[key]["conformity"]
        assert re.search(rf"{key}: limits ≤ .*\(simple\): {outcome}\b", summary), summary
