"""One probability, one number: a rejected item's false-reject probability is printed with
the digits of its probability of conformance (the column beside it, summary.txt and the DCC's
value: 98.5 %, never "99 %" beside "98.5 %"), and the legend of the items stated by an
interval names the probability those items state (the triad's 95.45 %), en and zh."""
from __future__ import annotations

import pytest
from scipy.stats import chi2

from gonio.report.i18n import labels
from gonio.report.stated import conformity_texts, interval_legend


@pytest.mark.parametrize("lang, word", [("en", "false-reject probability"), ("zh", "误拒绝概率")])
@pytest.mark.parametrize("p, shown", [(0.98533, "98.5 %"), (0.9511, "95.1 %"),
                                      (0.99349, "99.3 %")])
def test_false_reject_probability_has_the_conformance_columns_digits(lang, word, p, shown):
    c = {"outcome": "fail", "lower": None, "upper": 54.0, "acceptance_upper": 7.0,
         "rule": "guarded", "conformance_probability": p, "false_reject_probability": p}
    t = conformity_texts(c, None, labels(lang))
    assert shown in t["pfr"] and word in t["pfr"], t["pfr"]
    # summary.txt's text of the same number (gonio.result.text: 3 significant digits)
    assert f"{100 * p:.3g} %" == shown


def _chi2_item(p: float) -> dict:
    s, nu = 0.2288, 2072
    upper = s * (nu / chi2.ppf(1 - p, nu)) ** 0.5
    return {"clause": "§4", "value": s, "nonnegative": True,
            "uncertainty": {"k": None, "k_source": "chi-square", "coverage_probability": p,
                            "nu_eff": float(nu), "interval": [0.0, upper]}}


@pytest.mark.parametrize("lang, at", [("en", "one-sided {p} % upper limit"),
                                      ("zh", "单侧 {p} % 上限")])
def test_the_interval_legend_names_the_items_probability(lang, at):
    L = labels(lang)
    assert at.format(p="95.45") in interval_legend({"ARW": _chi2_item(0.9545)}, L)
    assert at.format(p="95") in interval_legend({"ARW": _chi2_item(0.95)}, L)
    # items of one kind stating different probabilities: the text as written (no one p)
    mixed = interval_legend({"a": _chi2_item(0.95), "b": _chi2_item(0.9545)}, L)
    assert at.format(p="95") in mixed


def test_the_optical_summary_states_each_probability_of_conformance(shared_demo):
    """summary.txt's conformity line of an optical item carries the probability of
    conformance the certificate's column and the DCC state (as the rate specifications'
    summary does), never only the "—" of the false-accept probability."""
    import json

    from gonio.resources import protocols_dir

    out = shared_demo("ogam-draft", seed=1, lab=protocols_dir() / "lab-example.toml")
    res = json.loads((out / "results.json").read_text(encoding="utf-8"))
    lines = {ln.split(":")[0].split()[-1]: ln for ln in
             (out / "summary.txt").read_text(encoding="utf-8").splitlines()
             if ln.startswith("conformity ")}
    stated = [(k, it["conformity"]["conformance_probability"]) for k, it in res["items"].items()
              if (it.get("conformity") or {}).get("conformance_probability") is not None]
    assert stated, "the example laboratory file decides some item with a probability"
    from gonio.kit.render import display

    for key, pc in stated:           # the certificate's column's digits, trailing zeros kept
        assert f"probability of conformance {display('sig3', 100 * pc)} %" in lines[key], \
            lines[key]


def test_optical_chi2_items_print_the_nu_their_interval_was_computed_with(shared_demo):
    """B_s and R are stated by their one-sided χ² interval alone; the legend says "σ's χ²
    distribution with the ν_eff shown", so the results table (HTML) and summary.txt print
    that ν beside the interval — the integer part of results.json's ν_eff — and the upper
    end recomputed from the printed ν (JCGM 100 E.4.3, a closed form) is results.json's."""
    import json
    import math
    import re

    from gonio.resources import protocols_dir

    out = shared_demo("ogam-draft", seed=1, lab=protocols_dir() / "lab-example.toml")
    res = json.loads((out / "results.json").read_text(encoding="utf-8"))
    html = (out / "certificate.html").read_text(encoding="utf-8")
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    chi2_items = [k for k, it in res["items"].items() if it.get("measured")
                  and (it.get("uncertainty") or {}).get("k_source") == "chi-square"]
    assert {"zero_stability", "repeatability"} <= set(chi2_items)
    for key in chi2_items:
        it = res["items"][key]
        unc = it["uncertainty"]
        nu = math.floor(unc["nu_eff"])
        m = re.search(rf'data-src="items\.{key}\.uncertainty\.nu_eff"[^>]*>([^<]+)<', html)
        assert m and m.group(1) == str(nu), (key, m and m.group(1))
        row = next(ln for ln in summary.splitlines() if f"({it['clause']})" in ln
                   or f"  {it['clause']}  " in ln)
        assert f"ν_eff = {nu})" in row, row
        p = unc.get("coverage_probability") or 0.95
        upper = it["value"] * math.sqrt(nu / chi2.ppf(1 - p, nu))
        assert upper == pytest.approx(unc["interval"][1], rel=1e-6), key


@pytest.mark.parametrize("p, shown, q, h", [(0.9545, "95.45", "4.6", "2.3"),
                                            (0.95, "95", "5.0", "2.5")])
@pytest.mark.parametrize("lang", ["en", "zh"])
def test_the_guard_band_note_and_the_probability_model_name_the_items_p(p, shown, q, h, lang):
    """An item stated at p = 95.45 % (the triad) is decided "on its 95.45 % interval", and the
    guard-band note under the decision rule says 95.45 % and 1 − p = 4.6 % (rounded up, as
    the column's bound), never a fixed "95 %" and "5 %" beside a 95.45 % statement."""
    from gonio.analysis.conformity import decide_items
    from gonio.report.stated import interval_band_note
    from gonio.result.model import Item, Result, Uncertainty

    unc = Uncertainty([], 0.003, 0.0065, None, None, None, p, "U = a + k·u",
                      (0.8740, 0.8870))
    res = Result("s", "S", {"M": Item("M", "M", "c", "1", 0.8805, uncertainty=unc)}, {}, {})
    (c,) = decide_items(res, [{"item": "M", "lower": 0.8, "upper": 0.9}],
                        {"rule": "non-binary", "guard_band_factor": 1.0})
    assert f"its {shown} % interval" in c.probability_model and "95 %" not in \
        c.probability_model.replace(f"{shown} %", ""), c.probability_model
    note = interval_band_note([("M", c.to_json())], labels(lang), lambda k: k, lambda k: "",
                              lambda k: p)
    assert f"{shown} %" in note and f"1 − p = {q} %" in note and f"{h} %" in note, note


@pytest.mark.parametrize("spec", ["jjf1535-2015", "iec62047-20"])
def test_rate_summary_states_the_nu_of_each_chi2_interval(shared_demo, spec):
    """summary.txt gives an item stated by a χ² interval (a standard deviation, or a
    dispersion's bound-condition limit) with the ν its interval was computed with — the
    number the certificate's ν column prints (its span), never dropped."""
    import json
    import re

    from gonio.result.statement import chi2_nu, chi2_stated_nu

    out = shared_demo(spec, seed=1)
    res = json.loads((out / "results.json").read_text(encoding="utf-8"))
    html = (out / "certificate.html").read_text(encoding="utf-8")
    lines = (out / "summary.txt").read_text(encoding="utf-8").splitlines()
    seen = 0
    for key, it in res["items"].items():
        unc = it.get("uncertainty") or {}
        if not it.get("measured") or not chi2_stated_nu(unc.get("k_source")) \
                or unc.get("interval") is None:
            continue
        nu = f"{chi2_nu(unc['nu_eff']):g}"
        m = re.search(rf'data-src="items\.{key}\.uncertainty\.nu_eff"[^>]*>([^<]+)<', html)
        assert m and m.group(1) == nu, (key, m and m.group(1), nu)
        head = f"  {it['clause']} "
        row = [ln for ln in lines if ln.startswith(head) and "upper bound" in ln]
        assert any(ln.endswith(f"; ν = {nu}") for ln in row), (key, row)
        seen += 1
    assert seen >= 2
