"""E (7.4) is stated by the 95 % interval of its extreme max|E_i| in every output.

The draft states E = ± max|E_i| with U; that statement does not hold the largest true |E_i|
with 95 % for every pattern of the true E_i (all zero: about 0.95^12). The interval
[max(0, max_i(|E_i| − c_L u_i)), max_i(|E_i| + c_H u_i)] does (uncertainty/extreme.py). These
tests check, from outside (the command line), that results.json, summary.txt, the DCC and the
certificate (HTML) state that one interval for E, recomputed here by hand from the per-point
E_i and u_i in results.json with factors computed here (Šidák's closed form for c_L, a
bisection of the worst-pattern miss for c_H); that the conformity decision never says "pass"
where the interval reaches over the limit (true E_i all zero); and that the old ± U form is
caught.
"""

from __future__ import annotations

import copy
import json
import math
import re
from decimal import ROUND_CEILING, Decimal
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import norm
from scipy.stats import t as student

ROOT = Path(__file__).resolve().parents[1]
P = 0.95


def _factors(m: int) -> tuple[float, float]:
    """(c_H, c_L) for m points, computed here: c_L from Šidák (all E_i zero misses 5 %),
    c_H by bisection so that the worst pattern "one point at θ, the others δ·u below" misses
    5 % with both tails together."""
    c_lo = float(norm.ppf((1.0 + P ** (1.0 / m)) / 2.0))
    delta = np.linspace(0.0, 10.0, 4001)

    def miss(c):
        return float(np.max(norm.cdf(-c) * norm.cdf(delta - c) ** (m - 1)
                            + 1.0 - norm.cdf(c_lo) * norm.cdf(c_lo + delta) ** (m - 1)))
    a, b = 0.5, 6.0
    for _ in range(200):
        mid = 0.5 * (a + b)
        a, b = (mid, b) if miss(mid) > 1.0 - P else (a, mid)
    return 0.5 * (a + b), c_lo


def hand_interval(res: dict) -> tuple[float, float, float]:
    """(lower, upper, max|E_i|) by hand from results.json's per-point E_i, u_i and ν_i (as
    stated: the integer part, ∞ above 1000)."""
    table = res["items"]["angle_deviation"]["details"]["table"]
    points = {round(p["position_deg"], 9): p for p in res["extra"]["uncertainty"]["points"]}
    x = np.array([abs(r["E_arcsec"]) for r in table])
    pt = [points[round(r["position_deg"], 9)] for r in table]
    # where the table's bound b_i is stated, u and ν are the point's without its table line
    # and b_i widens each point's reach (every table within the MPE; 0 elsewhere)
    bounded = "table_bound_arcsec" in pt[0]
    u = np.array([p["u_without_table_arcsec" if bounded else "u_c_arcsec"] for p in pt])
    nu = [p["nu_without_table" if bounded else "nu_eff"] for p in pt]
    b = np.array([p.get("table_bound_arcsec", 0.0) for p in pt])
    c_hi, c_lo = _factors(len(x))

    def f(c):       # each ν as stated (GUM G.6.4): its integer part, the normal above 1000
        return np.array([c if n is None or n > 1000 else
                         float(student.ppf(norm.cdf(c), max(1, math.floor(n)))) for n in nu])
    return max(0.0, float(np.max(x - f(c_lo) * u - b))), float(np.max(x + f(c_hi) * u + b)), \
        float(np.max(x))


def upper_text(hi: float, m: float) -> str:
    """The upper end as a one-sided interval states it: U = hi − m to two significant
    digits gives the decimal place, the end rounded up (never narrower)."""
    dec = 1 - math.floor(math.log10(hi - m))
    return str(Decimal(repr(hi)).quantize(Decimal(1).scaleb(-dec), rounding=ROUND_CEILING))


@pytest.fixture(scope="module")
def demo(shared_demo):
    """What ``gonio demo --spec ogam-draft --seed 3`` writes (the session's shared folder,
    made through the command line once for every file that reads it; read only)."""
    return shared_demo("ogam-draft", seed=3)


def e_row(summary: str) -> str:
    return next(line for line in summary.splitlines() if "angle-position deviation E" in line
                and "7.4" in line)


def states_interval(summary: str, hi: str) -> bool:
    """summary.txt's E row states the interval alone: "≤ hi (p = 95 %)", no U, no k."""
    row = e_row(summary)
    cols = re.split(r"\s{2,}", row.strip())
    return f"≤ {hi} (p = 95 %)" in row and "k =" not in row and cols[-2] == "—"


def test_every_output_states_the_hand_interval(demo):
    res = json.loads((demo / "results.json").read_text(encoding="utf-8"))
    lo, hi, m = hand_interval(res)
    unc = res["items"]["angle_deviation"]["uncertainty"]
    assert unc["k"] is None and unc["coverage_probability"] == P
    assert unc["interval"] == pytest.approx([lo, hi], rel=1e-9, abs=1e-12)
    assert lo <= m <= hi
    assert res["items"]["angle_deviation"]["details"]["max_abs_arcsec"] == pytest.approx(m)
    assert unc["U"] == pytest.approx(hi - m, rel=1e-9)
    hi_t = upper_text(hi, m)
    assert lo == 0.0          # the demo's E_i are small beside u: the interval starts at 0
    summary = (demo / "summary.txt").read_text(encoding="utf-8")
    assert states_interval(summary, hi_t)
    dcc = (demo / "certificate.dcc.xml").read_text(encoding="utf-8")
    if res["extra"]["uncertainty"].get("u_c_certified", True) is False:
        # U = k·u + b: no u of E certified, the ends as a list, no valueStandardMU
        block = dcc.split('id="result-angle_deviation"')[1].split("</dcc:result>")[0]
        assert re.search(rf"<si:valueXMLList>[\d.]+ {re.escape(hi_t)}</si:valueXMLList>",
                         block)
        assert "valueStandardMU>" not in block
    else:
        block = dcc.split('id="result-angle_deviation"')[1].split("</dcc:quantity>")[0]
        assert f"<si:intervalMax>{hi_t}</si:intervalMax>" in block
    assert "expandedMU" not in block and "coverageFactor" not in block
    html = (demo / "certificate.html").read_text(encoding="utf-8")
    row = html.split("Angle-position deviation E")[1].split("</tr>")[0]
    assert f"≤\u00a0{hi_t}" in row or f"≤ {hi_t}" in row or f"≤&nbsp;{hi_t}" in row
    assert "k = " not in row


def test_the_old_plus_minus_u_statement_is_caught(demo):
    """Mutation: E's uncertainty put back to the draft's ± U (the largest point's U, k):
    summary.txt then states "± U (k = …)" and the check above fails."""
    from gonio.specs.ogam_draft.stated import summary_text

    res = json.loads((demo / "results.json").read_text(encoding="utf-8"))
    lo, hi, m = hand_interval(res)
    old = copy.deepcopy(res)
    e = old["extra"]["uncertainty"]
    old["items"]["angle_deviation"]["uncertainty"].update(
        U=e["U_arcsec"], k=e["k"], nu_eff=e.get("nu_eff"), k_source="welch-satterthwaite")
    old["items"]["angle_deviation"]["uncertainty"].pop("interval")
    assert states_interval(summary_text(res), upper_text(hi, m))
    assert not states_interval(summary_text(old), upper_text(hi, m))


def test_decision_with_all_true_e_zero_never_passes_over_the_limit():
    """True E_i all zero, twelve points, u = 0.1″, limit ±0.25″: "pass" only where the
    interval's upper end lies within the limit (guard band r = 1); the interval holds the
    truth 0, the draft's max|E_i| ± U misses it about half the time."""
    from gonio.analysis.conformity import decide_items
    from gonio.result.model import Item, Result, Uncertainty
    from gonio.specs.ogam_draft.calibration import e_stated_uncertainty
    from uncertainty.extreme import max_abs_interval

    rng = np.random.default_rng(20261201)
    u, mpe = np.full(12, 0.1), 0.25
    passes = over = covered = old_covered = 0
    for _ in range(400):
        x = rng.normal(0.0, u)
        r = max_abs_interval(x, u)
        signed = float(x[np.argmax(np.abs(x))])
        base = {"u_c": 0.1, "U": 1.96 * 0.1, "k": 1.96, "nu_eff": None,
                "k_source": "welch-satterthwaite", "coverage_probability": P}
        unc = e_stated_uncertainty(base, {"lower_arcsec": r.lower, "upper_arcsec": r.upper,
                                          "max_abs_arcsec": r.estimate, "p": r.p})
        item = Item("angle_deviation", "E", "7.4", "arcsec", signed, uncertainty=Uncertainty(
            [], unc["u_c"], unc["U"], unc["k"], unc["nu_eff"], None,
            unc["coverage_probability"], unc["k_source"], tuple(unc["interval"])))
        res = Result("ogam-draft", "draft", {"angle_deviation": item}, {}, {})
        over += r.upper > mpe
        for rule in ("guarded", "non-binary"):   # guard band r = 1: the interval's reach
            c = decide_items(res, [{"item": "angle_deviation", "mpe": mpe}],
                             {"rule": rule, "guard_band_factor": 1.0})[0]
            # max|E_i| as stated (rounded), not the signed extreme
            assert c.value == pytest.approx(r.estimate, abs=0.01)
            # no single normal model describes the extreme of twelve points: no probability
            assert c.conformance_probability is None and c.false_accept_probability is None
            assert c.probability_model.startswith("not given")
            if rule == "non-binary" and c.outcome in ("fail", "conditional fail"):
                # outside the limit: conditional where the interval reaches back in
                # (its stated lower end, rounded down: the interval as printed)
                assert (c.outcome == "conditional fail") == (
                    float(c.stated_interval[0]) <= mpe)
            if c.outcome == "pass":
                passes += 1
                assert r.upper <= mpe + 1e-12
        # simple acceptance (shared risk, ILAC-G8 4.2.1) decides max|E_i| itself
        c = decide_items(res, [{"item": "angle_deviation", "mpe": mpe}], {"rule": "simple"})[0]
        # on the printed max|E_i| and, never less strict, on the measured one before rounding
        assert (c.outcome == "pass") == (c.value <= mpe and r.estimate <= mpe)
        assert (c.decided_on_measured is not None) == (c.value <= mpe < r.estimate)
        covered += r.lower <= 0.0 <= r.upper            # the truth max|E_i,true| = 0
        old_covered += r.estimate - 0.196 <= 0.0        # the draft's max|E_i| ± U
    assert passes > 0 and over > 0
    # the interval holds the all-zero truth (Clopper-Pearson upper limit reaches 95 %),
    # the ± U statement does not (about 0.95^12 = 54 %)
    from scipy.stats import beta
    assert beta.ppf(0.975, covered + 1, 400 - covered) >= P
    assert old_covered / 400 < 0.7
