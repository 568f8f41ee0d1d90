"""Items stated by a standard deviation's one-sided χ² upper bound (JJF 1535 7.2.13 and
IEC 62047-20 5.4.5.2 ARW, IEC 5.4.5.1 noise rms, every dispersion of
:func:`gonio.result.gum.dispersion_uncertainty`) and the bound-condition items, as every output
states them:

* the ν printed beside a χ² bound is the one the bound was computed with (its integer part,
  never ∞: the χ² limit still moves with ν above 1000), in the certificate, summary and
  ``tables/items.csv``; the bound is reproduced from it by scipy;
* the guard band of a χ² bound is its reach above the estimate, b − s, not half of [0, b]
  (with ν ≈ 10⁴, b/2 is ~50× that reach and a guarded rule r = 1.5 rejected ARW ≤ 1.826
  against a limit 1.9 with a probability of conformance of 100 %); its probability of
  conformance is σ's χ² distribution's, P(σ ≤ T) = χ²_ν.sf(ν s²/T²) (scipy);
* ``tables/items.csv`` gives u only where the certificate states u_c: not the quadrature
  u_c of a bound-condition item, which the certificate marks "not stated".
"""

from __future__ import annotations

import contextlib
import html
import io
import json
import math
import re
from decimal import Decimal
from pathlib import Path

import pytest
from scipy import stats

from gonio.analysis.conformity import decide_items
from gonio.result.gum import dispersion_uncertainty
from gonio.result.model import Item, Result, Uncertainty
from gonio.result.statement import item_statement
from gonio.result.tables import item_row

ROOT = Path(__file__).resolve().parents[1]


def _arw(s: float, nu: float) -> Result:
    """An ARW item s with the budget u_c = s/√(2ν), stated by dispersion_uncertainty."""
    u = dispersion_uncertainty(s, Uncertainty([], s / math.sqrt(2.0 * nu), 0.0, None, None,
                                              None, 0.95))
    return Result("s", "S", {"arw": Item("arw", "angle random walk ARW", "5.4.5.2", "°/√h", s,
                                         nonnegative=True, uncertainty=u)}, {}, {})


def _p_conform(s: float, nu: int, T: float) -> float:
    """P(σ ≤ T) for σ's χ² distribution about s with ν: ν s²/σ² ~ χ²_ν (scipy)."""
    return float(stats.chi2.sf(nu * s * s / (T * T), nu))


@pytest.mark.parametrize("s,nu,T,r", [(1.8081, 15590.4, 1.9, 1.5), (1.8081, 15590.4, 2.5, 2.0),
                                      (1.8011750, 49444.98, 1.9, 1.5), (0.5, 40.2, 0.8, 1.5)])
def test_guarded_chi2_bound_within_the_limit_passes(s, nu, T, r):
    """IEC seed 3's ARW (s 1.8081, ν 15 590, ≤ 1.826) against 1.9 under r = 1.5: pass (it
    was "fail, probability of conformance 100 %"), U = printed bound − printed value, the
    acceptance limit T − (r − 1)·U, and the probability of conformance from scipy's χ²."""
    res = _arw(s, nu)
    (c,) = decide_items(res, [{"item": "arw", "upper": T}],
                        {"rule": "guarded", "guard_band_factor": r})
    st = item_statement(res.items["arw"])
    reach = Decimal(st.interval[1]) - Decimal(st.value)
    assert c.outcome == "pass", c
    assert Decimal(repr(c.U)) == reach and c.guard_band == pytest.approx(r * float(reach))
    assert c.acceptance_upper == pytest.approx(T - (r - 1) * float(reach))
    n = math.floor(nu)
    assert c.probability_model == f"chi-square, nu = {n}"
    assert c.conformance_probability == pytest.approx(_p_conform(s, n, T), rel=1e-12)
    assert c.conformance_probability > 0.95


def test_guarded_chi2_bound_beyond_its_acceptance_fails():
    """The rule still rejects: a limit below bound + (r − 1)·(bound − value) fails, a limit
    just above it passes (the boundary is where b − s puts it, not b/2)."""
    res = _arw(1.8081, 15590.4)
    st = item_statement(res.items["arw"])
    b, v = Decimal(st.interval[1]), Decimal(st.value)
    edge = b + Decimal("0.5") * (b - v)
    for T, want in ((edge - Decimal("0.0005"), "fail"), (edge + Decimal("0.0005"), "pass")):
        (c,) = decide_items(res, [{"item": "arw", "upper": float(T)}],
                            {"rule": "guarded", "guard_band_factor": 1.5})
        assert c.outcome == want, (T, c)
        if want == "fail":
            assert c.false_reject_probability == pytest.approx(
                _p_conform(1.8081, 15590, float(T)), rel=1e-12)


def test_chi2_band_note_names_the_reach():
    """The certificate's guard-band note states the δ (U's place in w = r·U) it used:
    bound − value."""
    from gonio.report.i18n import labels
    from gonio.report.stated import interval_band_note

    res = _arw(1.8081, 15590.4)
    (c,) = decide_items(res, [{"item": "arw", "upper": 1.9}],
                        {"rule": "guarded", "guard_band_factor": 1.5})
    st = item_statement(res.items["arw"])
    reach = Decimal(st.interval[1]) - Decimal(st.value)
    for lang in ("en", "zh"):
        note = interval_band_note([("arw", c.to_dict())], labels(lang), lambda k: "ARW",
                                  lambda k: "°/√h")
        assert f"δ = {st.interval[1]} − {st.value} °/√h = {reach.normalize()} °/√h" in note
        assert f"w = {(Decimal('1.5') * reach).normalize()} °/√h" in note


@pytest.mark.parametrize("nu", [37.5, 999.9, 15590.4, 49444.98])
def test_chi2_nu_printed_is_the_nu_of_the_bound(nu):
    """Statement and items.csv give ν's integer part (never ∞) and the bound is
    s·√(ν/χ²_0.05,ν) with that ν (scipy)."""
    res = _arw(1.8011750, nu)
    it = res.items["arw"]
    st = item_statement(it)
    row = item_row("arw", it)
    n = math.floor(nu)
    assert st.nu_eff == str(n) and row["nu"] == n
    assert row["interval_high"] == pytest.approx(
        1.8011750 * math.sqrt(n / stats.chi2.ppf(0.05, n)), rel=1e-12)


def test_items_csv_states_no_u_for_a_bound_condition_item():
    """A bound-condition item (details.bound_condition, k_source "U = a + k·u"): u empty (its
    quadrature u_c is "not stated" on the certificate); a value ± U item keeps its u_c."""
    bc = Item("scale_factor", "scale factor K", "7.2.1", "mV/(°/s)", 5.99917,
              uncertainty=Uncertainty([], 0.0023, 0.0095, None, 2.06, None, 0.95,
                                      "U = a + k·u", interval=(5.9896, 6.0088)),
              details={"bound_condition": {"U": 0.0095, "u_rest": 0.00152, "nu_rest": 2.06}})
    plain = Item("bias", "bias", "7.2.8", "°/h", 0.4,
                 uncertainty=Uncertainty([], 0.05, 0.11, 2.2, 12.0, None, 0.95))
    assert item_row("scale_factor", bc)["u"] is None
    assert item_row("bias", plain)["u"] == 0.05


def _html_text(path: Path) -> str:
    text = html.unescape(re.sub(r"<[^>]+>", " ", path.read_text(encoding="utf-8")))
    return re.sub(r"\s+", " ", text.replace("\u00a0", " "))


def test_chi2_arw_through_gonio_calibrate(tmp_path):
    """From the outside (JJF 1535 small programme, seed 0: ARW ≈ 1.80, ν ≈ 4 000): a guarded
    rule r = 1.5 with ARW ≤ 1.9 (a few per cent above its bound): pass with scipy's χ²
    probability of conformance in results.json, summary.txt, the certificate and the DCC;
    the certificate's ν column and items.csv give the ν the bound is computed with."""
    from gonio.cli import main

    proto = ROOT / "tests" / "data" / "pins" / "jjf1535-2015-small.toml"
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["simulate", "--spec", "jjf1535-2015", "--protocol", str(proto), "--seed",
                     "0", "--out", str(tmp_path / "s")]) == 0
    lab = (ROOT / "protocols" / "lab-example.toml").read_text(encoding="utf-8")
    lab = lab[:lab.index("\n[[specification_limits]]\n")]
    lab = re.sub(r'\[decision_rule\]\nrule = "non-binary"\nguard_band_factor = 1.0',
                 '[decision_rule]\nrule = "guarded"\nguard_band_factor = 1.5', lab)
    assert 'rule = "guarded"' in lab
    lab += ('\n[[specification_limits]]\nitem = "angle_random_walk"\nupper = 1.9\n'
            'source = "test limit"\n\n[identity]\non_mismatch = "proceed"\n')
    (tmp_path / "lab.toml").write_text(lab, encoding="utf-8")
    out = tmp_path / "c"
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["calibrate", str(tmp_path / "s" / "readings.csv"), "--spec",
                     "jjf1535-2015", "--protocol", str(proto), "--lab", str(tmp_path / "lab.toml"),
                     "--dcc", "--out", str(out)]) == 0
    it = json.loads((out / "results.json").read_text(encoding="utf-8"))["items"][
        "angle_random_walk"]
    s, unc, c = it["value"], it["uncertainty"], it["conformity"]
    n = math.floor(unc["nu_eff"])
    assert n > 1000                                  # stated "∞" before
    b = unc["interval"][1]
    assert b == pytest.approx(s * math.sqrt(n / stats.chi2.ppf(0.05, n)), rel=1e-12)
    assert b < 1.9 / 1.02                            # the case: bound a few % under the limit
    p_c = _p_conform(s, n, 1.9)
    assert c["outcome"] == "pass" and c["conformance_probability"] == pytest.approx(p_c,
                                                                                   rel=1e-12)
    # U is the printed bound less the printed value
    assert Decimal(repr(c["U"])) == Decimal(c["stated_interval"][1]) - Decimal(c["stated_value"])
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    line = next(x for x in summary.splitlines() if x.strip().startswith("angle_random_walk:"))
    assert line.endswith("pass, probability of conformance 100 %"), line
    cert = _html_text(out / "certificate.html")
    assert re.search(r"angle random walk ARW ≤ 1\.9 °/√h interval's upper end ≤ "
                     + re.escape(c["acceptance_upper_text"]) + r" °/√h pass 100 %", cert)
    assert re.search(r"angle random walk ARW 7\.2\.13 [\d.]+ ; ≤ [\d.]+ \(p = 95 %\) — — "
                     + str(n) + " °/√h", cert)
    dcc = (out / "certificate.dcc.xml").read_text(encoding="utf-8")
    assert ("pass; rule guarded; limits ≤ 1.9; acceptance: interval's upper end ≤ "
            + c["acceptance_upper_text"]) in dcc
    rows = (out / "tables" / "items.csv").read_text(encoding="utf-8").splitlines()
    head = rows[0].split(",")
    row = dict(zip(head, next(r for r in rows if r.startswith("angle_random_walk,")).split(",")))
    assert float(row["nu"]) == n
