"""A standard deviation decided on its printed estimate s under simple acceptance can pass with
a probability of conformance under 50 %: σ's χ² distribution about s is skewed (its median lies
above s). The certificate says so beside the table (before: "pass" beside "p_c 49 %",
unexplained); an item whose p_c agrees with its outcome gets no such note."""
from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from scipy.stats import chi2

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("lang", ["en", "zh"])
def test_a_chi2_pass_under_half_is_explained(tmp_path, capsys, lang):
    from gonio.cli import main
    from gonio.report.i18n import labels

    assert main(["demo", "--spec", "jjf1535-2015", "--out", str(tmp_path / "a")]) == 0
    it = json.loads((tmp_path / "a" / "results.json").read_text())["items"]["bias_stability"]
    s, nu = it["value"], math.floor(it["uncertainty"]["nu_eff"])
    T = round(s * 1.001, 6)         # just above s: decided pass on s as printed
    # independently: P(σ ≤ T) with σ = s·√(ν/χ²_ν) is P(χ²_ν ≥ ν s²/T²), under one half
    p_c = chi2.sf(nu * s * s / (T * T), nu)
    assert p_c < 0.5
    head = (ROOT / "protocols" / "lab-example.toml").read_text(encoding="utf-8").split(
        "[decision_rule]")[0]
    (tmp_path / "lab.toml").write_text(
        head + '[decision_rule]\nrule = "simple"\nagreed = "test"\n\n'
        f'[[specification_limits]]\nitem = "bias_stability"\nupper = {T}\n\n'
        '[[specification_limits]]\nitem = "warmup_time"\nupper = 1000\n', encoding="utf-8")
    capsys.readouterr()
    assert main(["demo", "--spec", "jjf1535-2015", "--lang", lang, "--lab",
                 str(tmp_path / "lab.toml"), "--out", str(tmp_path / "b")]) == 0
    items = json.loads((tmp_path / "b" / "results.json").read_text())["items"]
    c = items["bias_stability"]["conformity"]
    assert c["outcome"] == "pass" and c["conformance_probability"] == pytest.approx(p_c,
                                                                                     rel=1e-3)
    html = (tmp_path / "b" / "certificate.html").read_text(encoding="utf-8")
    note = labels(lang)["c_skewed_note"].split("{items}")[1][:40]
    at = html.find(note)
    assert at > 0, "no note on the pass under 50 %"
    named = html[max(0, at - 200):at]
    assert ("bias stability" in named) if lang == "en" else ("零偏稳定性" in named), named
    assert items["warmup_time"]["conformity"]["outcome"] == "pass"
    assert html.count(note) == 1          # the warm-up's pass is not named
