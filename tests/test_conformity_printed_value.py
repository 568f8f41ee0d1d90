"""Items stated y ± U are decided on the value and U as printed, against the limit as given,
exactly (as the items stated by an interval are): a printed value above a printed limit never
passes; and never less strictly than on the measured value before rounding: a measured value
beyond a limit never passes because its printed value rounds back inside (the stricter of the
two outcomes is stated, with a note naming the measured value). The printed numbers are worked here independently of gonio's statement code (U to two
significant digits, the value half up at U's place); the expected outcomes are the rule's
closed forms (ILAC-G8:09/2019 4.2, JCGM 106 8.3.2) on those numbers."""

from __future__ import annotations

import json
import math
import re
from decimal import ROUND_HALF_UP, Decimal
from pathlib import Path

import numpy as np
import pytest

from gonio.analysis.conformity import decide_items
from gonio.result.model import Item, Result, Uncertainty

ROOT = Path(__file__).resolve().parents[1]
CONVOLUTION = "jcgm101-convolution"


def printed(y: float, U: float) -> tuple[Decimal, Decimal]:
    """y and U as a certificate prints them: U to 2 significant digits, y at U's place."""
    place = Decimal(1).scaleb(math.floor(math.log10(U)) - 1)
    return (Decimal(repr(y)).quantize(place, rounding=ROUND_HALF_UP),
            Decimal(repr(U)).quantize(place, rounding=ROUND_HALF_UP))


def k_result(y, U, k=2.06, source=CONVOLUTION) -> Result:
    unc = Uncertainty([], U / k, U, k, 50.0, None, 0.95, source)
    return Result("ogam-draft", "d", {"scale_factor": Item(
        "scale_factor", "K", "7.1", "counts/deg", y, uncertainty=unc)}, {}, {})


def test_the_reviewers_k_printed_above_the_limit_fails():
    """K 76434.84672484883 ± 0.02145 prints 76434.847; simple acceptance [76434.80,
    76434.8468]: the printed value lies above the printed upper limit, so "fail" (it was
    "pass" on the unrounded value)."""
    y, U = 76434.84672484883, 0.021454515495391444
    yp, Up = printed(y, U)
    assert str(yp) == "76434.847" and yp > Decimal("76434.8468") and y < 76434.8468
    (c,) = decide_items(k_result(y, U), [{"item": "scale_factor", "lower": 76434.80,
                                           "upper": 76434.8468}], {"rule": "simple"})
    assert c.outcome == "fail" and not c.accepted
    assert c.value == float(yp) and c.acceptance_upper_text == "76434.8468"
    assert "y alone" in c.probability_model and "y ± U" not in c.probability_model


def test_a_printed_value_below_a_lower_limit_fails():
    y, U = 76434.80045, 0.0105            # prints 76434.800 ± 0.011
    yp, _ = printed(y, U)
    assert yp < Decimal("76434.8004") < Decimal(repr(y))
    (c,) = decide_items(k_result(y, U), [{"item": "scale_factor", "lower": 76434.8004,
                                           "upper": 76434.9}], {"rule": "simple"})
    assert c.outcome == "fail"


def test_a_printed_value_on_the_limit_passes():
    """The limits are part of the acceptance interval (JCGM 106 3.3.9): printed 76434.847
    against an upper limit 76434.847 passes where the measured value is on or below it; and a
    guarded limit T_U − U at the printed U is met exactly (no float residue)."""
    y, U = 76434.84696, 0.0105
    (c,) = decide_items(k_result(y, U), [{"item": "scale_factor", "upper": 76434.847}],
                        {"rule": "simple"})
    assert c.outcome == "pass" and c.decided_on_measured is None
    # guarded r = 1: accepted when printed y ≤ T_U − printed U; T_U − U = 76434.847 exactly
    (c,) = decide_items(k_result(76434.84698, 0.02300001),
                        [{"item": "scale_factor", "upper": 76434.87}], {"rule": "guarded"})
    assert c.outcome == "pass", (c.value, c.U, c.acceptance_upper)
    (c,) = decide_items(k_result(76434.84751, 0.02300001),     # prints 76434.848
                        [{"item": "scale_factor", "upper": 76434.87}], {"rule": "guarded"})
    assert c.outcome == "fail"


def test_the_reviewers_measured_value_beyond_the_limit_fails():
    """K = 76434.8464, U = 0.0105 prints 76434.846 ± 0.011; simple acceptance with an upper
    limit 76434.8462: the printed value lies inside, the measured value beyond it. A value
    rounded towards the limit never turns a fail into a pass: "fail", and the measured value
    that decided it is kept for the certificate's note."""
    y, U = 76434.8464, 0.0105
    yp, _ = printed(y, U)
    assert str(yp) == "76434.846" and yp < Decimal("76434.8462") < Decimal(repr(y))
    (c,) = decide_items(k_result(y, U), [{"item": "scale_factor", "upper": 76434.8462}],
                        {"rule": "simple"})
    assert c.outcome == "fail" and not c.accepted
    assert c.decided_on_measured == "76434.8464" and c.value == float(yp)
    # guarded, r = 1: printed 76434.846 + 0.010 = 76434.856 ≤ 76434.8565 passes on the
    # printed numbers; the measured y + U = 76434.85698 lies beyond it
    assert printed(76434.84649, 0.01049) == (Decimal("76434.846"), Decimal("0.010"))
    (c,) = decide_items(k_result(76434.84649, 0.01049), [{"item": "scale_factor",
                                                          "upper": 76434.8565}],
                        {"rule": "guarded"})
    assert c.outcome == "fail" and c.decided_on_measured == "76434.84649"


def test_the_measured_value_prints_beyond_the_limit_it_lies_beyond():
    """A measured value 76434.85092592593 beyond a lower limit 76434.85093 prints with the
    digits that show it (10 significant digits would print the limit itself, and a value on a
    limit passes simple acceptance); the text lies on the value's side of every limit."""
    from gonio.analysis.conformity import measured_value_text
    y, lim = 76434.85092592593, 76434.85093
    assert f"{y:.10g}" == "76434.85093"            # the collision the rule avoids
    m = measured_value_text(y, (lim, None, None))
    assert float(m) < lim and Decimal(m) < Decimal(repr(lim))
    for y, lims in ((1.0 + 3e-16, (1.0,)), (-2.5e-7, (-2.5000000001e-7, 0.0)),
                    (123.456, (100.0, 200.0))):
        m = measured_value_text(y, lims)
        assert all((float(m) > L) == (y > L) and (float(m) < L) == (y < L) for L in lims), m


def closed_form(rule: str, y: Decimal, w: Decimal, w_lo: Decimal, L: Decimal, H: Decimal) -> str:
    """ILAC-G8:09/2019 4.2.1–4.2.3 on one value y with guard bands w (upper), w_lo (lower)."""
    in_tol = L <= y <= H
    in_acc = L + w_lo <= y <= H - w
    if rule == "non-binary":
        return ("pass" if in_acc else "conditional pass" if in_tol else
                "conditional fail" if (L - y <= w and y - H <= w) else "fail")
    return "pass" if in_acc else "fail"


STRICTNESS = ("pass", "conditional pass", "conditional fail", "fail")


@pytest.mark.parametrize("rule", ["simple", "guarded", "non-binary"])
def test_the_outcome_is_that_of_the_printed_numbers(rule):
    """Random K, U and limits near the printed value: the outcome equals the rule's closed
    form on the printed numbers, and a printed value outside a limit is never accepted."""
    rng = np.random.default_rng(11)
    for _ in range(400):
        U = float(10 ** rng.uniform(-3, -1))
        y = float(76434.8 + rng.uniform(-0.2, 0.2))
        yp, Up = printed(y, U)
        step = Decimal(1).scaleb(Up.as_tuple().exponent)
        lo = float(yp + step * int(rng.integers(-40, 3)))
        hi = float(yp + step * int(rng.integers(-2, 40)))
        if lo >= hi:
            continue
        (c,) = decide_items(k_result(y, U, source="welch-satterthwaite"),
                            [{"item": "scale_factor", "lower": lo, "upper": hi}],
                            {"rule": rule, "guard_band_factor": 1.0})
        L, H = Decimal(repr(lo)), Decimal(repr(hi))
        w = Decimal(0) if rule == "simple" else Up
        w_raw = Decimal(0) if rule == "simple" else Decimal(repr(U))
        on_printed = closed_form(rule, yp, w, w, L, H)
        on_measured = closed_form(rule, Decimal(repr(y)), w_raw, w_raw, L, H)
        want = max(on_printed, on_measured, key=STRICTNESS.index)
        assert c.outcome == want, (y, U, lo, hi, c)
        assert (c.decided_on_measured is not None) == (want != on_printed)
        if not (L <= yp <= H and L <= Decimal(repr(y)) <= H):
            assert not c.accepted


def test_the_no_probability_note_says_what_the_rule_decides_on():
    """K with a convolution k: under simple acceptance the outcome is y alone, under a guard
    band y ± U (y within the tolerance narrowed by r·U); both in Chinese too."""
    from gonio.report.i18n import translator

    zh = translator()
    notes = {}
    for rule in ("simple", "guarded", "non-binary"):
        (c,) = decide_items(k_result(76434.83, 0.0105),
                            [{"item": "scale_factor", "lower": 76434.80, "upper": 76434.87}],
                            {"rule": rule, "guard_band_factor": 1.0})
        notes[rule] = c.probability_model
        t = zh(f"— ({c.probability_model})")
        assert t and "不给出" in t and "decided" not in t, t
        assert ("仅依据 y" in t) == (rule == "simple"), t
    assert notes["simple"].endswith("decided on y alone (simple acceptance, no guard band)")
    assert notes["guarded"].endswith("decided on y ± U") and notes["non-binary"] == \
        notes["guarded"]


def _k_limit_run(tmp_path, capsys, far_side: bool, lang: str = "en"):
    """A simulated session calibrated twice: K read from the first results.json, then with a
    laboratory file whose simple-acceptance limit lies between the unrounded and the printed
    K (as the laboratory file's float reads it), on the printed value's side (the printed K
    beyond it) or, ``far_side``, on the measured value's (the printed K inside it). Returns
    (y, printed y, the limit, its side, conformity, the certificate's text)."""
    from gonio.cli import main

    proto = ROOT / "tests" / "data" / "small-protocol.toml"
    assert main(["simulate", "--protocol", str(proto), "--seed", "2414", "--out",
                 str(tmp_path / "sim")]) == 0
    rd = tmp_path / "sim" / "readings.csv"
    assert main(["calibrate", str(rd), "--protocol", str(proto), "--out",
                 str(tmp_path / "a")]) == 0
    k = json.loads((tmp_path / "a" / "results.json").read_text())["items"]["scale_factor"]
    y = k["value"]
    yp, _ = printed(y, k["uncertainty"]["U"])
    yd = Decimal(repr(y))
    assert yp != yd
    mid = Decimal(repr(float((yd + yp) / 2)))
    assert min(yd, yp) < mid < max(yd, yp)
    side = "upper" if (yd > yp if far_side else yp > yd) else "lower"
    other = ("lower", yp - 1) if side == "upper" else ("upper", yp + 1)
    lab = (ROOT / "protocols" / "lab-example.toml").read_text()
    lab = re.sub(r'\[decision_rule\]\nrule = "non-binary"\nguard_band_factor = 1.0',
                 '[decision_rule]\nrule = "simple"', lab)
    lab += (f'\n[[specification_limits]]\nitem = "scale_factor"\n{side} = {mid}\n'
            f'{other[0]} = {other[1]}\nsource = "test"\n')
    (tmp_path / "lab.toml").write_text(lab)
    capsys.readouterr()
    assert main(["calibrate", str(rd), "--protocol", str(proto), "--lab",
                 str(tmp_path / "lab.toml"), "--lang", lang, "--dcc", "--out",
                 str(tmp_path / "b")]) == 0
    capsys.readouterr()
    c = json.loads((tmp_path / "b" / "results.json").read_text())["items"]["scale_factor"][
        "conformity"]
    html = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ",
                                      (tmp_path / "b" / "certificate.html").read_text()))
    return y, yp, mid, side, c, html


def test_k_through_gonio_calibrate_with_a_simple_rule(tmp_path, capsys):
    """From the outside: a simulated session, K read from its results.json, a laboratory file
    with a simple-acceptance limit between the unrounded K and the printed K: the
    certificate says fail, prints the limit as given and the printed K beside it."""
    _, yp, mid, side, c, html = _k_limit_run(tmp_path, capsys, far_side=False)
    assert c["outcome"] == "fail" and c["value"] == float(yp)
    assert c[f"acceptance_{side}_text"] == str(mid)
    assert str(mid) in html and str(yp) in html


@pytest.mark.parametrize("lang", ["en", "zh"])
def test_k_measured_beyond_printed_inside_through_gonio_calibrate(tmp_path, capsys, lang):
    """From the outside: a limit between the printed K and the unrounded K on the measured
    value's side: the printed K lies inside, the measured K beyond: the certificate states
    fail and its note names the measured value; results.json keeps it."""
    y, yp, _, side, c, html = _k_limit_run(tmp_path, capsys, far_side=True, lang=lang)
    assert c["outcome"] == "fail" and c["value"] == float(yp)
    m = c["decided_on_measured"]
    # printed with the digits that put it beyond the limit, as the measured value lies
    lim = c.get("upper") if side == "upper" else c.get("lower")
    assert (float(m) > lim) == (y > lim) and float(m) != lim and len(m) >= len(f"{y:.10g}")
    assert m in html
    # the same measured value in summary.txt and the DCC's statement and data
    summary = (tmp_path / "b" / "summary.txt").read_text(encoding="utf-8")
    said = f"decided on the measurement result before rounding: its value {m} against its " \
           f"acceptance interval {c['decided_on_measured_acceptance']}"
    assert said in summary
    dcc = (tmp_path / "b" / "certificate.dcc.xml").read_text(encoding="utf-8")
    assert said in dcc
    assert "measured value before rounding (decided the outcome)" in dcc
    assert ("Decided on the measurement result before rounding" in html) == (lang == "en")
    assert ("按修约前的测量结果判定" in html) == (lang == "zh")
