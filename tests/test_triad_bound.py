"""The triad's bound-condition statement (docs/alignment.md §4): the rate table's errors at
their bounds in their worst combination, a = Σ_k |c_k| a_k, plus t(ν)·u of the fit.

Independent references: the worst sign combination found by enumerating every sign of the
seven table errors through the written-out first-order model (``study.table_bias``) and, for
S_ij, through the exact ratio of the perturbed matrix; the bench's true M for coverage at the
table's worst condition (``study.worst_table``); the protocol switch read back from a file.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import re
from pathlib import Path

import numpy as np
import pytest

from gonio.errors import GonioError
from gonio.specs.triad_alignment.analysis import _derived, table_bound, table_bound_vectors
from gonio.specs.triad_alignment.bench import (TriadProtocol, load_triad_bench,
                                               run_alignment_session)
from gonio.specs.triad_alignment.calibration import calibrate
from gonio.specs.triad_alignment.readings import format_triad_readings, parse_triad_readings
from gonio.specs.triad_alignment.study import table_bias, worst_table

ROOT = Path(__file__).resolve().parents[1]


def _protocol() -> TriadProtocol:
    return TriadProtocol("t", "triad-alignment", (50.0, 100.0), 1, 0.5, True, 5.0,
                         {"x": "+y", "y": "+z", "z": "+x"}, 0.0, {})


def _signed_errors(eps: float, bound: float):
    """Every combination of the seven table errors at ± their bounds: (ε, δ (3 × 3))."""
    off = [(a, j) for a in range(3) for j in range(3) if j != a]
    for signs in itertools.product((1.0, -1.0), repeat=7):
        d = np.zeros((3, 3))
        for (a, j), s in zip(off, signs[1:]):
            d[a, j] = s * bound
        yield signs[0] * eps, d


def test_bound_equals_the_worst_sign_combination():
    """a of every M_ij is the largest |bias| over the 2⁷ sign combinations of the errors at
    their bounds (the first-order model written out in ``table_bias``); a of S_ij the largest
    change of the exact ratio M_ij/M_ii of the perturbed matrix (first order: within 1 %)."""
    m = load_triad_bench("mems-triad").system_matrix
    eps, bound = 1e-3, math.radians(0.05)
    theta = np.column_stack([m, np.ones(3)]).ravel()
    vecs = table_bound_vectors(m, eps, bound)
    a_m = table_bound(lambda t: t, theta, vecs).reshape(3, 4)[:, :3]
    a_s = table_bound(_derived, theta, vecs)[21:27]
    worst_m = np.zeros((3, 3))
    worst_s = np.zeros(6)
    s0 = np.array([m[i, j] / m[i, i] for i in range(3) for j in range(3) if i != j])
    for e, d in _signed_errors(eps, bound):
        bias = table_bias(m, e, d)
        worst_m = np.maximum(worst_m, np.abs(bias))
        mm = m + bias
        s1 = np.array([mm[i, j] / mm[i, i] for i in range(3) for j in range(3) if i != j])
        worst_s = np.maximum(worst_s, np.abs(s1 - s0))
    assert np.allclose(a_m, worst_m, rtol=1e-6, atol=1e-12)
    assert np.allclose(a_s, worst_s, rtol=1e-2)
    # closed form of M_xx: ε M_xx plus column x's shifts M_xy δ_xy + M_xz δ_xz
    assert a_m[0, 0] == pytest.approx(eps * abs(m[0, 0])
                                      + bound * (abs(m[0, 1]) + abs(m[0, 2])), rel=1e-6)


def _noisy_bench():
    return dataclasses.replace(load_triad_bench("mems-triad"), arw_deg_sqrt_h=(0.3,) * 3,
                               bias_instability_dph=(0.0,) * 3)


def test_bound_statement_covers_at_the_tables_worst_condition():
    """The table at its bounds with the worst signs (``worst_table``), noise drawn: against
    the bench's true M the JCGM 100 U of M_xx (dominated by the rate error, k ≈ 2; kept in
    the details, not certified) covers about half the sessions, the certified statement —
    the bound condition — every one but a few (by construction at least 95.45 %: |offset|
    ≤ a)."""
    base = _noisy_bench()
    wb = worst_table(base)
    truth = base.system_matrix
    gum_in = bound_in = n = 0
    for seed in range(30):
        text = format_triad_readings(*(lambda s: (s.readings, s.metadata))(
            run_alignment_session(_protocol(), wb, seed=seed)))
        res = calibrate(parse_triad_readings(text, "r.csv"))
        for i, a in enumerate("xyz"):
            it = res.items[f"M_{a}{a}"]
            err = abs(it.value - truth[i, i])
            gum_in += err <= it.details["not_certified"]["gum"]["U"]
            bound_in += err <= it.uncertainty.U
            assert it.uncertainty.U == it.details["bound_condition"]["U"]
            n += 1
    assert bound_in / n >= 0.93, (bound_in, n)
    assert gum_in / n <= 0.85, (gum_in, n)


def _text(seed: int = 4) -> str:
    s = run_alignment_session(_protocol(), _noisy_bench(), seed=seed)
    return format_triad_readings(s.readings, s.metadata)


def test_one_statement_the_bound_condition(tmp_path):
    """Without a protocol and with the built-in one, the items the table enters (M, S, L)
    are stated by the bound-condition interval alone: U = a + t_0.9545(ν_rest)·u_rest (k
    from scipy here), the interval value ± U, no k of the whole; the JCGM 100 U and the Monte
    Carlo u are in ``details.not_certified``, labelled so, and nowhere in the uncertainty.
    b keeps its own k. ``uncertainty_statement = "gum"`` (or anything but "bound") is refused
    naming the key: the JCGM 100 U under-covers at the table's bounds."""
    from scipy import stats

    r = parse_triad_readings(_text(), "r.csv")
    src = (ROOT / "protocols" / "triad-alignment.toml").read_text(encoding="utf-8")
    for items in (calibrate(r).items, calibrate(r, "triad-alignment").items):
        for key in ("M_xx", "M_yz", "S_xy", "L_zx"):
            it = items[key]
            bc = it.details["bound_condition"]
            k_rest = stats.t.ppf(0.5 + 0.9545 / 2, math.floor(bc["nu_rest"] + 1e-9))
            assert it.uncertainty.k is None and it.uncertainty.monte_carlo is None
            assert bc["k_rest"] == pytest.approx(k_rest, rel=1e-9)
            assert it.uncertainty.U == pytest.approx(bc["a_table"] + k_rest * bc["u_rest"],
                                                     rel=1e-12)
            assert it.uncertainty.interval == pytest.approx(
                (it.value - it.uncertainty.U, it.value + it.uncertainty.U))
            gum = it.details["not_certified"]["gum"]
            assert gum["status"] == "not certified" and "gum" not in it.details
            assert gum["U"] < it.uncertainty.U
        assert items["b_x"].uncertainty.k is not None
        assert items["b_x"].uncertainty.interval is None
    for value in ("gum", "worst"):
        bad = tmp_path / f"{value}.toml"
        bad.write_text(src.replace("[alignment]\n",
                                   f"[alignment]\nuncertainty_statement = \"{value}\"\n"),
                       encoding="utf-8")
        with pytest.raises(GonioError, match="uncertainty_statement") as e:
            calibrate(r, str(bad))
        assert "\n" not in str(e.value)


def test_conformity_is_decided_on_the_certified_interval():
    """A guarded rule (r = 1) and an upper limit on M_xy between the JCGM 100 U's reach and
    the bound interval's: the certified interval reaches past the limit, so M_xy does not
    pass, though the JCGM 100 U alone would have; a limit beyond the interval passes."""
    from gonio.formats.lab import load_lab
    from gonio.pipeline.dispatch import decide_conformity
    from gonio.resources import protocols_dir

    def lab(upper):
        base = load_lab(protocols_dir() / "lab-example.toml")
        return {**base, "decision_rule": {"rule": "guarded", "guard_band_factor": 1.0,
                                          "agreed": "t"},
                "specification_limits": [{"source": "test", "item": "M_xy", "lower": None,
                                          "upper": upper, "mpe": None}]}
    r = parse_triad_readings(_text(), "r.csv")
    res = calibrate(r)
    it = res.items["M_xy"]
    u_gum, u_bound = it.details["not_certified"]["gum"]["U"], it.uncertainty.U
    assert u_bound > 1.1 * u_gum
    between = it.value + (u_gum + u_bound) / 2
    decide_conformity(res, lab(between))
    c = res.items["M_xy"].conformity
    assert c.outcome != "pass" and c.acceptance_of == "interval", c
    res = calibrate(r)
    decide_conformity(res, lab(it.value + 1.5 * u_bound))
    assert res.items["M_xy"].conformity.outcome == "pass"


def test_align_page_states_one_statement_per_cell():
    """``gonio align --report``: every cell of M, S and L is its certified bound-condition
    interval (no k of the whole), b its own k; no Monte Carlo or second statement column."""
    from gonio.specs.triad_alignment.pages import alignment_page, certified_cell

    cal = calibrate(parse_triad_readings(_text(), "r.csv"))
    page = alignment_page(cal.alignment)
    for key in [f"M_{a}{c}" for a in "xyz" for c in "xyz"]:
        cell = certified_cell(cal.items[key])
        assert "(k = " not in cell and "[" in cell and cell in page, key
    for key in [f"b_{a}" for a in "xyz"]:
        cell = certified_cell(cal.items[key])
        assert "(k = " in cell and cell in page, key
    for key in [k for k in cal.items if k[:2] in ("S_", "L_")]:
        cell = certified_cell(cal.items[key], 1e3)
        assert "(k = " not in cell and cell in page, key
    assert "Monte Carlo, the fit" not in page and "(bound)</th>" not in page
    assert "S (GUM)" not in page
