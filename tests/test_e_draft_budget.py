"""E (7.4) under the draft's own Annex A budget (``gonio calibrate --budget draft``) is
stated by the same kind of one interval as under the physical budget.

The draft's U is a statement about one point; max|E_i| ± U for the extreme of twelve points
holds the largest true |E_i| only about 0.95^12 of the time where every true E_i is 0. These
tests run the command line on simulated readings (seed 8) and check from outside:

- results.json states the interval of max|E_i| recomputed here by hand from the per-point
  E_i, the one budget's u_c at every point and its ν_eff (Welch–Satterthwaite over the
  budget's lines, computed here), with factors computed here (Šidák's closed form, a
  bisection of the worst-pattern miss); the draft's max|E_i| ± U (U = t95(ν_eff)·u_c, by
  hand) is kept beside, labelled not certified;
- summary.txt, the certificate (HTML and PDF, en and zh), the DCC (en and zh) and the
  conformity decision state that interval and nothing else as E's statement; the DCC says
  what its si:valueStandardMU is (the certificate's u_c, rounded to two digits by hand) and
  its zh DCC gives E's description in Chinese;
- ``gonio validate``'s lines print the certified interval's coverage first and label the
  draft's ± U as its Annex A reading, not certified.
"""

from __future__ import annotations

import json
import math
import re
import shutil
import subprocess
from decimal import ROUND_HALF_UP, Decimal
from pathlib import Path

import numpy as np
import pytest
from lxml import etree
from scipy.stats import norm
from scipy.stats import t as student

from gonio.cli import main
from tests.test_e_extreme_statement import _factors, states_interval, upper_text

P = 0.95
#: The repository's example laboratory file (its limit for E: ±0.5″, non-binary rule with
#: the guard band r = 1).
LAB_EXAMPLE = Path(__file__).resolve().parents[1] / "protocols" / "lab-example.toml"


@pytest.fixture(scope="module")
def draft(tmp_path_factory):
    """Simulated readings (seed 8) calibrated with ``--budget draft``: en with a laboratory
    file (limits for E) and the DCC, zh the same; the folder of each and results.json."""
    base = tmp_path_factory.mktemp("e_draft")
    assert main(["simulate", "--spec", "ogam-draft", "--seed", "8", "--out",
                 str(base / "sim")]) == 0
    out = {}
    for lang in ("en", "zh"):
        lab = LAB_EXAMPLE
        d = base / lang
        assert main(["calibrate", str(base / "sim" / "readings.csv"), "--budget", "draft",
                     "--lab", str(lab), "--dcc", "--lang", lang, "--out", str(d)]) == 0
        out[lang] = d
    out["res"] = json.loads((out["en"] / "results.json").read_text(encoding="utf-8"))
    out["base"] = base
    return out


def welch_nu(components) -> float:
    """ν_eff of the budget's lines (JCGM 100 G.2b), from results.json's u, c and dof."""
    num = sum((c["c"] * c["u_arcsec"]) ** 2 for c in components) ** 2
    den = sum((c["c"] * c["u_arcsec"]) ** 4 / c["dof"] for c in components
              if c["dof"] is not None and c["u_arcsec"])
    return math.inf if den == 0 else num / den


def hand_draft_interval(res: dict) -> tuple[float, float, float]:
    """(lower, upper, max|E_i|) by hand: the per-point E_i of results.json, u_i = the one
    budget's u_c (recomputed from its lines) and ν_i its ν_eff at every point, as stated
    (the integer part, as its k; ∞ above 1000)."""
    e = res["extra"]["uncertainty"]
    comps = e["components"]
    u = math.sqrt(sum((c["c"] * c["u_arcsec"]) ** 2 for c in comps))
    assert u == pytest.approx(e["u_c_arcsec"], rel=1e-12)
    nu = welch_nu(comps)
    x = np.array([abs(r["E_arcsec"]) for r in res["items"]["angle_deviation"]["details"]
                  ["table"]])
    c_hi, c_lo = _factors(len(x))

    def f(c):       # ν as stated (GUM G.6.4): its integer part, the normal above 1000
        return c if nu > 1000 else float(student.ppf(norm.cdf(c), max(1, math.floor(nu))))
    return max(0.0, float(np.max(x)) - f(c_lo) * u), float(np.max(x)) + f(c_hi) * u, \
        float(np.max(x))


def two_digits(x: float) -> str:
    """x to two significant digits, half up (the certificate's U and u rule)."""
    q = Decimal(1).scaleb(math.floor(math.log10(x)) - 1)
    return str(Decimal(repr(x)).quantize(q, rounding=ROUND_HALF_UP))


def test_results_json_states_the_interval_from_the_one_budget(draft):
    res = draft["res"]
    assert res["settings"]["budget_kind"] == "draft"
    lo, hi, m = hand_draft_interval(res)
    unc = res["items"]["angle_deviation"]["uncertainty"]
    assert unc["k"] is None and unc["nu_eff"] is None and unc["coverage_probability"] == P
    assert unc["k_source"] == "max-abs-interval"
    assert unc["interval"] == pytest.approx([lo, hi], rel=1e-9, abs=1e-12)
    assert unc["U"] == pytest.approx(hi - m, rel=1e-9)
    assert res["items"]["angle_deviation"]["details"]["max_abs_arcsec"] == pytest.approx(m)
    mi = res["extra"]["uncertainty"]["max_abs_interval"]
    assert mi["nu_eff"] == pytest.approx(welch_nu(res["extra"]["uncertainty"]["components"]))
    assert mi["u_c_arcsec"] == pytest.approx(res["extra"]["uncertainty"]["u_c_arcsec"])
    # the draft's reading beside: U = t95(ν_eff)·u_c of the one budget, not certified
    dr = res["extra"]["uncertainty"]["draft_reading"]
    k = float(student.ppf(0.975, math.floor(mi["nu_eff"])))   # ν stated: its integer part
    assert dr["k"] == pytest.approx(k, rel=1e-9)
    assert dr["U_arcsec"] == pytest.approx(k * mi["u_c_arcsec"], rel=1e-9)
    assert "not certified" in dr["label"] and "one point" in dr["label"]
    # it is not the statement: the interval differs from max|E_i| ± U
    assert hi != pytest.approx(m + dr["U_arcsec"])


def test_summary_and_certificate_state_the_interval(draft):
    res = draft["res"]
    lo, hi, m = hand_draft_interval(res)
    hi_t = upper_text(hi, m)
    assert lo == 0.0
    summary = (draft["en"] / "summary.txt").read_text(encoding="utf-8")
    assert states_interval(summary, hi_t)
    assert "each point's E_i (the same at every point) (draft budget)" in summary
    assert "largest of the points'" not in summary
    dr = res["extra"]["uncertainty"]["draft_reading"]
    beside = f"±{m:.{_dec(dr)}f} ± {two_digits(dr['U_arcsec'])}″ (k = {dr['k']:.3g})"
    assert beside in summary and "given beside and not certified" in summary
    html = (draft["en"] / "certificate.html").read_text(encoding="utf-8")
    row = html.split("Angle-position deviation E")[1].split("</tr>")[0]
    assert re.search(rf"≤(\xa0| |&nbsp;){re.escape(hi_t)}", row) and "k = " not in row
    text = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", html)).replace("\xa0", " ")
    assert "the same at every point" in text and "Certified for E: the interval above" in text
    assert "Certified: U of the draft's Annex A budget" not in text
    if shutil.which("pdftotext") is None:
        pytest.fail("pdftotext not found: run scripts/install-test-system-deps.sh")
    pdf = subprocess.run(["pdftotext", str(draft["en"] / "certificate.pdf"), "-"],
                         capture_output=True, text=True, check=True).stdout
    pdf = re.sub(r"\s+", " ", pdf)
    assert f"[0, {hi_t}]″" in pdf and "Certified for E: the interval above" in pdf
    zh = re.sub(r"\s+", " ", subprocess.run(
        ["pdftotext", str(draft["zh"] / "certificate.pdf"), "-"], capture_output=True,
        text=True, check=True).stdout)
    assert f"[0, {hi_t}]″" in zh and "各点相同" in zh and "E 的校准结果为上述" in zh


def _dec(dr: dict) -> int:
    """Decimal places of U to two significant digits (max|E_i| beside it at the same)."""
    return max(0, 1 - math.floor(math.log10(dr["U_arcsec"])))


def test_dcc_states_the_interval_and_says_what_its_standard_u_is(draft):
    res = draft["res"]
    lo, hi, m = hand_draft_interval(res)
    for lang in ("en", "zh"):
        doc = (draft[lang] / "certificate.dcc.xml").read_text(encoding="utf-8")
        block = doc.split('id="result-angle_deviation"')[1].split("</dcc:quantity>")[0]
        assert f"<si:intervalMax>{upper_text(hi, m)}</si:intervalMax>" in block
        assert "expandedMU" not in block and "coverageFactor" not in block
        # valueStandardMU: the one budget's u_c, the certificate's u_c line, two digits
        u = two_digits(res["extra"]["uncertainty"]["u_c_arcsec"])
        assert f"<si:valueStandardMU>{u}</si:valueStandardMU>" in block
        # the standard uncertainty of max|E_i| (law of propagation at the estimates): the one
        # budget's u_c, the same at every point, so at the largest |E_i| too
        assert "valueStandardMU is the standard uncertainty of max|E_i|" in block
        assert "u_c of the draft's one Annex A budget, the same at every point" in block
        assert f"{res['extra']['uncertainty']['max_abs_interval']['position_at_max']:g}°" \
            in block
    html = (draft["en"] / "certificate.html").read_text(encoding="utf-8")
    assert re.search(rf"u_c = <span[^>]*>{re.escape(u)}</span>", html)
    # the zh DCC: E's description in Chinese beside the English, no English words left
    from tests.test_zh_certificates import WHITELIST, WORD
    from gonio.report.dcc import DCC_NS
    root = etree.fromstring((draft["zh"] / "certificate.dcc.xml").read_bytes())
    e = next(r for r in root.iter(f"{{{DCC_NS}}}result") if r.get("id") ==
             "result-angle_deviation")
    desc = next(e.iter(f"{{{DCC_NS}}}description"))
    texts = {c.get("lang"): c.text for c in desc.iter(f"{{{DCC_NS}}}content")}
    assert set(texts) == {"en", "zh"}
    assert "max|E_i| 在估计值处按传播律" in texts["zh"] and "才是校准结果" in texts["zh"]
    assert not {w for w in WORD.findall(texts["zh"]) if w not in WHITELIST}, texts["zh"]


def test_conformity_decided_on_the_interval(draft):
    """The example laboratory's ±0.5″, non-binary rule, guard band r = 1: "pass" exactly where
    the interval's upper end lies within +MPE (hand interval); no probability of conformance
    of a normal model."""
    res = draft["res"]
    lo, hi, m = hand_draft_interval(res)
    c = res["items"]["angle_deviation"]["conformity"]
    # decided on the value as the statement prints it (m to the statement's digits)
    assert c["value"] == pytest.approx(m, abs=0.005) and c["value"] == round(c["value"], 2)
    assert c["rule"] == "non-binary" and c["upper"] == 0.5
    # stated on the interval's ends: at r = 1 its upper end within +MPE itself, the same
    # decision as max|E_i| ≤ 0.5 − (hi − m)
    assert c["acceptance_of"] == "interval" and c["acceptance_upper"] == 0.5
    assert (c["outcome"] == "pass") == (hi <= 0.5)
    dr = res["extra"]["uncertainty"]["draft_reading"]
    # the seed's case separates the two: the interval passes where max|E_i| ± U would not
    # (seed 8: upper end 0.474″, max|E_i| + U 0.522″; seeds 1–12 separate in 2, 5, 8, 9)
    assert hi <= 0.5 < m + dr["U_arcsec"] and c["outcome"] == "pass"
    assert c["conformance_probability"] is None and c["false_accept_probability"] is None
    summary = (draft["en"] / "summary.txt").read_text(encoding="utf-8")
    assert "conformity angle_deviation: pass" in summary


def test_the_old_plus_minus_u_is_caught(draft):
    """Mutation: E under the draft's budget put back to max|E_i| ± U (e_stated_uncertainty
    given no interval, as before): the statement checks above fail."""
    from gonio.specs.ogam_draft.calibration import e_stated_uncertainty
    from gonio.specs.ogam_draft.stated import summary_text

    res = draft["res"]
    lo, hi, m = hand_draft_interval(res)
    e = res["extra"]["uncertainty"]
    base = {"u_c": e["u_c_arcsec"], "U": e["U_arcsec"], "k": e["k"], "nu_eff": e["nu_eff"],
            "k_source": "welch-satterthwaite", "coverage_probability": P}
    assert e_stated_uncertainty(base, None) == base
    old = json.loads(json.dumps(res))
    old["items"]["angle_deviation"]["uncertainty"] = {
        **old["items"]["angle_deviation"]["uncertainty"], **base}
    old["items"]["angle_deviation"]["uncertainty"].pop("interval")
    assert states_interval(summary_text(res), upper_text(hi, m))
    assert not states_interval(summary_text(old), upper_text(hi, m))


def test_validate_prints_the_certified_interval_first():
    """``gonio validate``'s E line: the certified interval's coverage first, the draft's
    max|E_i| ± U after it, labelled its Annex A reading, not certified."""
    from types import SimpleNamespace

    from gonio.specs.ogam_draft.study import item_coverage_lines

    ts = {"cp_low": 0.9, "cp_high": 1.0, "z_mean": 0.1, "z_sd": 0.5, "flags": []}
    it = {"trials": 20, "within_U": {"fraction": 1.0, "u_binomial": 0.0},
          "max_statement": dict(ts), "max_interval": dict(ts, mean_width=0.3)}
    line = next(x for x in item_coverage_lines(
        [SimpleNamespace(name="typeb", summary={"items": {"angle_deviation_draft": it}})])
        if "angle_deviation_draft" in x)
    a = line.index("E certified: max|E_i|'s 95 % interval")
    b = line.index("the draft's Annex A reading max|E_i| +- U (not certified)")
    assert a < b


def test_validate_records_the_draft_budget_interval():
    """A study trial (analysed with the draft's budget, as the study analyses) records the
    interval E states under that budget, recomputed here from the trial's analysis, and the
    physical budget's beside: ``gonio validate`` reports the coverage of both."""
    from dataclasses import replace

    from gonio.specs.ogam_draft.bench import load_bench
    from gonio.specs.ogam_draft.study import run_trial, validation_protocol
    from uncertainty.extreme import max_abs_interval

    t = run_trial(validation_protocol(), replace(load_bench("rlg"), sample_rate_hz=100.0), 3)
    rec = t.items
    d, e = rec["angle_deviation_draft"], rec["angle_deviation"]
    u_c = d["u_c"]          # the draft's one budget: its u_c at every point
    assert "U_points" not in d and "U_points" in e
    lo, hi = d["max_interval"]
    assert hi > lo >= 0.0
    assert "max_interval" in e
    # the draft budget's interval from its points and its one u_c (ν ≥ that of any line: the
    # t-factor lies between the normal one and the one at the smallest ν, here bracketed)
    r_inf = max_abs_interval(d["points"], [u_c] * len(d["points"]))
    assert hi >= r_inf.upper - 1e-12 and d["U"] >= 1.959 * u_c
