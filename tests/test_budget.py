"""Draft Annex A budget: the annex's printed numbers, MC validation, the CLI."""

import json
import math
import statistics

import numpy as np
import pytest

from gonio.specs.ogam_draft.budget_extra import ExtraComponent
from gonio.specs.ogam_draft.budget import (annex_a5_rounding, annex_a_budget,
                          repeatability_from_deviations)
from gonio.cli import main
from gonio.errors import GonioError


def test_annex_a_numbers():
    b = annex_a_budget()
    u = {c.symbol: c.u_xi for c in b.gum.contributions}
    assert round(u["P"], 4) == 0.0577           # A.4.1: 0.1/sqrt(3)
    assert round(u["phi_e"], 4) == 0.0453       # A.4.2: 0.0785/sqrt(3)
    assert round(u["B_E"], 4) == 0.0866         # A.4.3: 0.3"/min x 0.5 min / sqrt(3)
    assert u["r"] == 0.096                      # A.4.4
    # A.6 root-sum-square of the printed unrounded components, computed independently
    rss = math.sqrt(0.1 ** 2 / 3 + (math.radians(0.1) ** 2 / 8 * 206264.806) ** 2 / 3
                    + 0.15 ** 2 / 3 + 0.096 ** 2)
    assert b.u_c_arcsec == pytest.approx(rss, rel=1e-6)
    assert round(b.u_c_arcsec, 4) == 0.1487 and round(b.U_arcsec, 3) == 0.297
    assert b.k == 2.0
    assert (b.stated_u_c_arcsec, b.stated_U_arcsec) == (0.15, 0.30)   # A.6, A.7
    # A.5 rounded path
    assert b.annex_rounded["components"] == {"P": 0.06, "phi_e": 0.05, "B_E": 0.09, "r": 0.09}
    assert round(b.annex_rounded["u_c_arcsec"], 4) == 0.1493
    # with u(r) = 0.09 exactly the result would be 0.145 / 0.29
    b09 = annex_a_budget(repeatability_arcsec=0.09)
    assert round(b09.u_c_arcsec, 3) == 0.145 and round(b09.U_arcsec, 2) == 0.29


def test_a5_rounding_reading():
    assert [annex_a5_rounding(x, "B") for x in (0.0577, 0.0453, 0.0866)] == [0.06, 0.05, 0.09]
    assert annex_a5_rounding(0.096, "A") == 0.09


def test_monte_carlo_validates_gum():
    b = annex_a_budget(monte_carlo_trials=10**6, seed=1)
    assert b.validation.passed                       # JCGM 101 clause 8, ndig = 2
    assert b.monte_carlo.u == pytest.approx(b.u_c_arcsec, rel=5e-3)
    assert b.validation.delta == 0.005
    d = b.to_dict()["monte_carlo"]
    assert d["gum_validation"]["passed"] is True and d["trials"] == 10**6


def test_repeatability_from_deviations_vs_statistics():
    rng = np.random.default_rng(0)
    e = rng.normal(0, 0.08, size=(10, 12))
    expect = max(statistics.stdev(e[:, j]) for j in range(12))
    assert repeatability_from_deviations(e) == pytest.approx(expect, rel=1e-12)
    with pytest.raises(GonioError):
        repeatability_from_deviations([1.0, 2.0])


def test_extra_components_enter_model():
    b = annex_a_budget(extra_components=[ExtraComponent("E_r", "Earth-rate residual", 0.1),
                                         ("T_x", "tilt x Earth rate", 0.05, "triangular")])
    base = annex_a_budget()
    assert [c.symbol for c in b.gum.contributions][-2:] == ["E_r", "T_x"]
    assert b.u_c_arcsec ** 2 == pytest.approx(
        base.u_c_arcsec ** 2 + 0.1 ** 2 / 3 + 0.05 ** 2 / 6, rel=1e-12)
    with pytest.raises(GonioError):
        annex_a_budget(extra_components=[("P", "dup", 0.1)])


@pytest.mark.parametrize("kwargs,key", [
    ({"table_mpe_arcsec": -0.1}, "table_mpe_arcsec"), ({"tilt_deg": 90.0}, "tilt_deg"),
    ({"k": 0.0}, "k"), ({"monte_carlo_trials": -5}, "monte_carlo_trials")])
def test_invalid_values(kwargs, key):
    with pytest.raises(GonioError) as ei:
        annex_a_budget(**kwargs)
    assert ei.value.key == key


def test_table_and_renderings():
    b = annex_a_budget()
    t = b.table()
    assert list(t.symbol) == ["P", "phi_e", "B_E", "r"]
    assert list(t.u_annex_A5) == [0.06, 0.05, 0.09, 0.09]
    assert "0.1487" in b.to_text() and b.to_markdown().startswith("| symbol")
    assert "<table" in b.to_html()


def test_cli_budget_json(capsys):
    assert main(["budget", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert set(d) == {"components", "u_c_arcsec", "U_arcsec", "k", "stated", "annex_rounded",
                      "monte_carlo"}
    assert set(d["components"][0]) == {"symbol", "source", "type", "distribution",
                                       "half_width_arcsec", "divisor", "u_arcsec", "c",
                                       "contribution_arcsec", "dof"}
    assert d["stated"] == {"u_c_arcsec": 0.15, "U_arcsec": 0.30}
    assert d["monte_carlo"] is None
    assert round(d["u_c_arcsec"], 4) == 0.1487


def test_cli_budget_text(capsys):
    assert main(["budget"]) == 0
    out = capsys.readouterr().out
    assert "0.1487" in out and "u_c = 0.15" in out and "U = 0.30" in out and "0.149" in out


@pytest.mark.parametrize("argv,opt", [
    (["budget", "--table-mpe-arcsec", "-1"], "--table-mpe-arcsec"),
    (["budget", "--tilt-deg", "95"], "--tilt-deg"),
    (["budget", "--k", "0"], "--k"),
    (["budget", "--monte-carlo", "-3"], "--monte-carlo"),
    (["tilt", "--tilt-deg", "90"], "--tilt-deg")])
def test_cli_bad_option_exit_2(capsys, argv, opt):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert opt in err and len(err.strip().splitlines()) == 1


def test_cli_tilt_json(capsys):
    assert main(["tilt", "--tilt-deg", "0.1", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert set(d) == {"extreme_arcsec", "at_deg", "model", "tilt_deg"}
    assert round(d["extreme_arcsec"], 4) == 0.0785 and len(d["at_deg"]) == 4
    assert main(["tilt", "--model", "rigid", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["extreme_arcsec"] == 0.0 and d["model"] == "rigid"
