"""The triad's laboratory Type B effects: the rate table's rate error and its spin axis in
the reference frame at each orientation.

Independent references: a Monte Carlo of the virtual bench (noise off, the table's errors
drawn per trial by ``simulate.for_trial``, every trial refitted by ``estimate_alignment``
with no Type B term) against the closed-form covariance ``table_type_b_cov``; and, through
``calibrate``, the Type B line of an item against the same first-order formula written out
for that entry.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from gonio.errors import GonioError
from gonio.specs.triad_alignment.analysis import estimate_alignment, table_type_b_cov
from gonio.specs.triad_alignment.bench import (TriadProtocol, load_triad_bench,
                                               run_alignment_session)
from gonio.specs.triad_alignment.calibration import calibrate
from gonio.specs.triad_alignment.simulate import for_trial
from gonio.specs.triad_alignment.readings import (format_triad_readings, parse_triad_readings)


def _quiet_bench(rate_u_rel: float, bound_deg: float):
    b = load_triad_bench("mems-triad")
    return dataclasses.replace(
        b, arw_deg_sqrt_h=(0.0,) * 3, bias_instability_dph=(0.0,) * 3,
        rate_table_u_rel=rate_u_rel, orientation_bound_deg=bound_deg)


def _protocol() -> TriadProtocol:
    return TriadProtocol("t", "triad-alignment", (50.0, 100.0), 1, 0.5, True, 5.0,
                         {"x": "+y", "y": "+z", "z": "+x"}, 0.0, {})


def _readings(session):
    return parse_triad_readings(format_triad_readings(session.readings, session.metadata), "r.csv")


def test_closed_form_covariance_matches_monte_carlo_of_the_bench():
    """The table's errors drawn per trial (rate error normal, axis components uniform),
    no noise: the spread of M̂ − M over the trials is the closed form's, entry by entry
    (the sd within sampling error of 300 trials, ≈ 4 %), and the correlations it predicts
    (the rate error common to every entry) are there too."""
    rate_u, bound = 1e-3, 0.05                # large enough to dominate the fit's rounding
    base = _quiet_bench(rate_u, bound)
    p = _protocol()
    errs = []
    for seed in range(300):
        b = for_trial(base, seed)
        res = estimate_alignment(_readings(run_alignment_session(p, b, seed=seed)))
        errs.append((res.system_matrix - base.system_matrix).ravel())
    errs = np.array(errs)
    cov = table_type_b_cov(base.system_matrix, rate_u, math.radians(bound) / math.sqrt(3.0))
    idx = [4 * i + j for i in range(3) for j in range(3)]
    c9 = cov[np.ix_(idx, idx)]
    sd_mc, sd_cf = errs.std(axis=0, ddof=1), np.sqrt(np.diag(c9))
    assert np.all(np.abs(sd_mc / sd_cf - 1.0) < 0.15), (sd_mc, sd_cf)
    assert np.all(np.abs(errs.mean(axis=0)) < 4 * sd_cf / math.sqrt(300))
    corr_mc = np.corrcoef(errs.T)
    corr_cf = c9 / np.outer(sd_cf, sd_cf)
    assert np.max(np.abs(corr_mc - corr_cf)) < 0.2
    assert corr_cf[0, 4] > 0.9 and corr_mc[0, 4] > 0.8      # M_xx, M_yy: the common ε
    # the alternative the closed form rules out: the axis errors ignored
    only_rate = np.sqrt(rate_u ** 2) * np.abs(base.system_matrix.ravel())
    assert np.max(sd_mc / np.maximum(only_rate, 1e-12)) > 5


def test_calibrate_carries_the_table_line_as_the_first_order_formula(tmp_path):
    """The Type B line of M_xy and M_xx through ``calibrate``: u² = (u_ε M_ij)² +
    u_δ² Σ_{k≠j} M_ik² (the fitted column j moves by Σ_k M_·k δ_jk), the rest of the
    budget (the fit) unchanged when the file states the table exact."""
    b = _quiet_bench(2.5e-4, 0.005)
    b = dataclasses.replace(b, arw_deg_sqrt_h=(0.3,) * 3)
    s = run_alignment_session(_protocol(), b, seed=4)
    text = format_triad_readings(s.readings, s.metadata)
    exact = text.replace("# rate_table_u_rel: 0.00025", "# rate_table_u_rel: 0.0") \
        .replace("# orientation_bound_deg: 0.005", "# orientation_bound_deg: 0.0")
    assert exact != text
    r1, r0 = parse_triad_readings(text, "a.csv"), parse_triad_readings(exact, "b.csv")
    c1, c0 = calibrate(r1).items, calibrate(r0).items
    m = c1["M_xx"].value, c1["M_xy"].value
    mm = np.array([[c1[f"M_{a}{c}"].value for c in "xyz"] for a in "xyz"])
    u_d = math.radians(0.005) / math.sqrt(3.0)
    for j, key in ((0, "M_xx"), (1, "M_xy")):
        line = [c for c in c1[key].uncertainty.components if c["symbol"] == f"{key}_table"][0]
        want = math.hypot(2.5e-4 * mm[0, j],
                          u_d * math.sqrt(sum(mm[0, k] ** 2 for k in range(3) if k != j)))
        assert line["u"] == pytest.approx(want, rel=1e-6)
        assert c1[key].uncertainty.u_c ** 2 == pytest.approx(
            c0[key].uncertainty.u_c ** 2 + want ** 2, rel=1e-6)
        assert not [c for c in c0[key].uncertainty.components if c["symbol"].endswith("_table")]
    assert m[0] == c0["M_xx"].value


@pytest.mark.parametrize("key, value", [("rate_table_u_rel", "-1e-4"),
                                        ("orientation_bound_deg", "abc")])
def test_a_bad_table_statement_is_refused_naming_it(key, value):
    b = _quiet_bench(2.5e-4, 0.005)
    s = run_alignment_session(_protocol(), b, seed=1)
    text = format_triad_readings(s.readings, {**s.metadata, key: value})
    with pytest.raises(GonioError, match=key):
        parse_triad_readings(text, "r.csv")


def _noisy_text(seed: int = 4) -> str:
    b = dataclasses.replace(_quiet_bench(2.5e-4, 0.005), arw_deg_sqrt_h=(0.3,) * 3)
    s = run_alignment_session(_protocol(), b, seed=seed)
    return format_triad_readings(s.readings, s.metadata)


def test_report_page_shows_the_certified_items_U():
    """``gonio align --report``'s page: every M_ij, S_ij and L_ij is printed as its certified
    statement, the bound-condition interval value [value − U, value + U] of the item, not
    the JCGM 100 U (kept in the details, not certified: smaller, so the check can fail) nor
    the fit's k times the total u."""
    from gonio.specs.triad_alignment.pages import (alignment_page, certified_cell,
                                                   value_with_u)

    cal = calibrate(parse_triad_readings(_noisy_text(), "r.csv"))
    al, items = cal.alignment, cal.items
    page = alignment_page(al)
    for key in [f"M_{a}{c}" for a in "xyz" for c in "xyz"]:
        it = items[key]
        assert it.uncertainty.k is None and certified_cell(it) in page, key
        gum = it.details["not_certified"]["gum"]
        assert gum["U"] < it.uncertainty.U
        assert value_with_u(it.value, gum["U"]) not in page, key
    for key in [k for k in items if k[:2] in ("S_", "L_")]:
        assert certified_cell(items[key], 1e3) in page, key
    k_fit = al.coverage_factor[0]
    assert value_with_u(items["M_xx"].value, k_fit * items["M_xx"].uncertainty.u_c) not in page


def test_align_command_includes_the_table_term(tmp_path, capsys):
    """``gonio align --json``: the same u(M) as ``calibrate``'s alignment (the table's
    Type B part in it), larger than the fit's alone."""
    from gonio.cli import main

    text = _noisy_text(seed=5)
    path = tmp_path / "r.csv"
    path.write_text(text, encoding="utf-8")
    assert main(["align", str(path), "--json", "--monte-carlo", "0"]) == 0
    import json
    got = json.loads(capsys.readouterr().out)
    r = parse_triad_readings(text, "r.csv")
    cal = calibrate(r).alignment
    assert got["type_b"] is not None
    um = np.array(got["u_system_matrix"])
    assert np.allclose(um, cal.u_system_matrix, rtol=1e-9)
    fit_only = estimate_alignment(r).u_system_matrix
    assert np.all(um > fit_only) and np.max(um / fit_only) > 2


def test_align_page_states_the_certified_b(tmp_path):
    """``gonio align --report`` on simulated readings with a static record: the page's b
    column is the certificate's b_i (the long-term bias: the in-run fit plus the bias
    instability), value, U and its own k as results.json and the certificate's HTML state
    them; the in-run statement (the fit's k times the fit's u) is not on the page (it is
    smaller, so the check can fail)."""
    import html as html_mod
    import json
    import re

    from scipy import stats

    from gonio.cli import main
    from gonio.specs.triad_alignment.pages import value_with_u

    sim, cal, page = tmp_path / "s", tmp_path / "c", tmp_path / "page.html"
    assert main(["simulate", "--spec", "triad-alignment", "--seed", "3", "--out", str(sim)]) == 0
    readings = sim / "readings.csv"
    assert main(["align", str(readings), "--report", str(page), "--monte-carlo", "0"]) == 0
    assert main(["calibrate", str(readings), "--out", str(cal), "--monte-carlo", "0"]) == 0
    res = json.loads((cal / "results.json").read_text(encoding="utf-8"))
    shown = html_mod.unescape(page.read_text(encoding="utf-8"))
    cert = (cal / "certificate.html").read_text(encoding="utf-8")
    al = res["extra"]["alignment"]
    for i, a in enumerate("xyz"):
        it = res["items"][f"b_{a}"]
        unc = it["uncertainty"]
        assert any(c["symbol"] == f"b_{a}_BI" for c in unc["components"])   # long-term
        text = f"{value_with_u(it['value'], unc['U'])} (k = {unc['k']:.2f})"
        row = re.search(rf"<td>gyro {a}</td>(.*?)</tr>", shown).group(1)
        assert row.endswith(f"<td>{text}</td>"), (a, row, text)
        for part in ("value", "uncertainty.U", "uncertainty.k"):      # the certificate's cell
            m = re.search(rf'data-src="items\.b_{a}\.{re.escape(part)}"[^>]*>([^<]*)<', cert)
            assert m.group(1).replace("\u2212", "-") in text, (a, part)
        fit = unc["components"][0]                       # the in-run fit's line, its ν
        k_fit = stats.t.ppf(0.5 + 0.9545 / 2, fit["dof"])
        assert math.isclose(fit["u"], al["u_bias_output"][i])
        assert value_with_u(it["value"], k_fit * fit["u"]) not in row
