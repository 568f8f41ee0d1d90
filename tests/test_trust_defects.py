"""Issue 12, defects 1–5, from the outside: a damaged readings file, the command, the result.

Every file here is written by hand (a small protocol, readings whose deviations are
known), so each expected number is computed independently of gonio.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from gonio.specs.ogam_draft.calibration import analyse, calibrate
from gonio.specs.ogam_draft.outputs import warnings
from gonio.cli import main
from gonio.errors import GonioError

ROOT = Path(__file__).resolve().parents[1]

PROTO = """[protocol]
name = "{name}"
[scale_factor]
rounds = [{{stop_deg = 120.0}}, {{stop_deg = 240.0}}, {{stop_deg = 360.0}}]
[angle_deviation]
series = {series}
max_time_to_reading_s = 30.0
on_bad_reading = "{policy}"
rounds = [{{stop_deg = 90.0}}, {{stop_deg = 180.0}}, {{stop_deg = 270.0}}, {{stop_deg = 360.0}}]
[annex_a]
{annex}
"""

#: Deviations E_ij (″), series × round, of the hand-made files.
E = np.array([[0.30, -0.20, 0.10, 0.40],
              [0.10, -0.40, 0.30, 0.20],
              [0.20, -0.30, 0.50, 0.30],
              [0.40, -0.10, 0.20, 0.10],
              [0.00, -0.30, 0.40, 0.30]])
POS = [90.0, 180.0, 270.0, 360.0]
HEADER = "test,series,round,rate_dps,orientation,time_s,table_deg,gyro_counts,gyro_deg\n"


def write_case(tmp: Path, *, series=5, policy="exclude", annex="", meta=None, name="hand",
               rows=None, scale_factor=True, counts=False):
    """A protocol and a readings file; returns (readings path, protocol path, data lines)."""
    (tmp / "p.toml").write_text(PROTO.format(name=name, series=series, policy=policy,
                                             annex=annex))
    meta = {"latitude_deg": "40.0", **(meta or {})}
    lines = [f"# {k}: {v}\n" for k, v in meta.items()] + [HEADER]
    if scale_factor:
        for i, th in enumerate((120.0, 240.0, 360.0), 1):
            lines.append(f"scale_factor,1,{i},60,up,{5 + i},{th},{int(th * 36000)},\n")
    for j in range(series):
        for i, th in enumerate(POS):
            if rows is not None:
                th_file, t = rows.get((j + 1, i + 1), (th, 10.0 + i))
            else:
                th_file, t = th, 10.0 + i
            if counts:
                lines.append(f"angle_deviation,{j + 1},{i + 1},60,up,{t},{th_file},"
                             f"{int(round((th + E[j, i] / 3600) * 36000))},\n")
            else:
                lines.append(f"angle_deviation,{j + 1},{i + 1},60,up,{t},{th_file},,"
                             f"{float(th + E[j, i] / 3600)!r}\n")
    f = tmp / "readings.csv"
    f.write_text("".join(lines))
    return f, tmp / "p.toml", lines


def line_of(lines, series, rnd):
    """1-based file line of an angle_deviation reading."""
    for n, ln in enumerate(lines, 1):
        if ln.startswith(f"angle_deviation,{series},{rnd},"):
            return n
    raise KeyError((series, rnd))


def api(f, p=None, **kw):
    """The Python API: results.json content and the stderr warnings, without writing."""
    result = calibrate(f, p, **kw)
    return result.to_json(), "\n".join(warnings(result))


def cli_json(argv, capsys):
    capsys.readouterr()
    code = main(argv + ["--json"])
    out = capsys.readouterr()
    return code, (json.loads(out.out) if code == 0 else None), out.err


# --------------------------------------------------------------------------- defect 1

def test_defect1_inconsistent_round_is_excluded_and_said(tmp_path, capsys):
    f, p, lines = write_case(tmp_path, rows={(2, 1): (91.0, 10.0)})
    res, err = api(f, p)
    ad = res["items"]["angle_deviation"]["details"]
    pts = {round(r["position_deg"], 6): r for r in ad["table"]}
    assert sorted(pts) == POS                       # no "position 90.5°"
    # E at 90° is the mean of the four series that fit, not five
    assert pts[90.0]["E_arcsec"] == pytest.approx(np.mean(np.delete(E[:, 0], 1)), abs=1e-6)
    assert pts[90.0]["n_series"] == 4
    bad = line_of(lines, 2, 1)
    un = {u["line"]: u["reason"] for u in res["unused_readings"]}
    assert bad in un and "differs from the protocol's 90°" in un[bad]
    assert ad["excluded_readings"] == 1 and "fewer readings" in ad["excluded_note"]
    assert "excluded" in err and str(bad) in err


def test_defect1_swapped_positions_are_not_two_points(tmp_path, capsys):
    f, p, lines = write_case(tmp_path, rows={(2, 2): (270.0, 11.0), (2, 3): (180.0, 12.0)})
    res, _ = api(f, p)
    table = res["items"]["angle_deviation"]["details"]["table"]
    assert [r["position_deg"] for r in table] == POS
    lines_bad = {line_of(lines, 2, 2), line_of(lines, 2, 3)}
    assert lines_bad <= {u["line"] for u in res["unused_readings"]}


def test_defect1_error_policy_names_the_line(tmp_path):
    f, p, lines = write_case(tmp_path, policy="error", rows={(2, 1): (31.0, 10.0)})
    r = subprocess.run([sys.executable, "-m", "gonio", "calibrate", str(f), "--protocol", str(p),
                        "--out", str(tmp_path / "o")], capture_output=True, text=True,
                       env={"PYTHONPATH": str(ROOT), "PATH": ""})
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert r.stderr.count("\n") == 1
    assert f"readings.csv:{line_of(lines, 2, 1)}" in r.stderr and "table_deg" in r.stderr
    assert not (tmp_path / "o").exists()


def test_defect1_a_round_with_no_reading_left_is_an_error(tmp_path, capsys):
    f, p, lines = write_case(tmp_path, series=2, rows={(1, 4): (330.0, 13.0),
                                                       (2, 4): (330.0, 13.0)})
    with pytest.raises(GonioError, match="cannot stand") as exc:
        calibrate(f, p)
    assert exc.value.line == line_of(lines, 1, 4)


# --------------------------------------------------------------------------- defect 2

def test_defect2_no_E_no_U(tmp_path, capsys):
    """An equal-division-only file: nothing of clause 7 measured, so no U anywhere."""
    ed = ROOT / "tests" / "data" / "full.csv"
    text = [ln for ln in ed.read_text().splitlines(keepends=True)
            if ln.startswith(("#", "test,", "equal_division,"))]
    f = tmp_path / "eda_only.csv"
    f.write_text("".join(text))
    code, res, _ = cli_json(["calibrate", str(f), "--out", str(tmp_path / "o")], capsys)
    assert code == 0
    u = res["extra"]["uncertainty"]
    assert u["U_arcsec"] is None and u["measured"] is False
    for item in ("scale_factor", "angle_deviation", "repeatability", "zero_stability"):
        assert res["items"][item]["measured"] is False and res["items"][item]["uncertainty"] is None
    page = (tmp_path / "o" / "certificate.html").read_text()
    assert "U = " not in page and "no uncertainty" in page


def test_defect2_counts_without_scale_factor(tmp_path, capsys):
    f, p, _ = write_case(tmp_path, scale_factor=False, counts=True)
    rep = calibrate(f, p)
    res = rep.to_json()
    assert not res["items"]["angle_deviation"]["measured"]
    assert res["extra"]["uncertainty"]["U_arcsec"] is None
    assert all(res["items"][k]["uncertainty"] is None
               for k in ("angle_deviation", "repeatability"))
    from gonio.specs.ogam_draft.outputs import summary

    assert "U = " not in summary(rep) and "no uncertainty stated" in summary(rep)


# --------------------------------------------------------------------------- defect 3

def test_defect3_one_series_u_r_from_protocol_said_so(tmp_path, capsys):
    f, p, _ = write_case(tmp_path, series=1)
    code, res, _ = cli_json(["calibrate", str(f), "--protocol", str(p), "--out",
                             str(tmp_path / "o"), "--budget", "draft"], capsys)
    assert code == 0 and not res["items"]["repeatability"]["measured"]
    u = res["extra"]["uncertainty"]
    r = u["components"][3]
    assert r["symbol"] == "r" and r["type"] == "B" and r["u_arcsec"] == 0.096
    assert "protocol" in u["repeatability_source"] and "protocol" in r["source"]
    assert not any("largest Bessel" in t for t in res["readings_taken"])
    page = (tmp_path / "o" / "certificate.html").read_text()
    assert "largest Bessel standard deviation over the points of this calibration" not in page
    assert "annex_a.repeatability_arcsec" in page


def test_defect3_five_series_k_from_welch_satterthwaite(tmp_path, capsys):
    f, p, _ = write_case(tmp_path, series=5)
    res, _ = api(f, p, budget="draft")
    u = res["extra"]["uncertainty"]
    R = max(np.std(E, axis=0, ddof=1))
    comp = {c["symbol"]: c["u_arcsec"] for c in u["components"]}
    assert comp["r"] == pytest.approx(R) and u["components"][3]["dof"] == 4
    # by hand: u_c from the four lines, ν_eff = u_c⁴/(u_r⁴/4), k = t_0.975(ν_eff)
    u_c = math.sqrt(sum(v * v for v in comp.values()))
    nu = u_c ** 4 / (R ** 4 / 4)
    assert u["nu_eff"] == pytest.approx(nu, rel=1e-9)
    assert u["k"] == pytest.approx(stats.t.ppf(0.975, math.floor(nu)), rel=1e-9) and u["k"] > 2.05
    assert u["k_source"] == "welch-satterthwaite"
    # E itself is stated by the interval of max|E_i| (no k); the draft's max|E_i| ± U beside
    # carries this k
    assert res["items"]["angle_deviation"]["uncertainty"]["k"] is None
    assert u["draft_reading"]["k"] == pytest.approx(u["k"])


def test_defect3_laboratory_fixes_k(tmp_path, capsys):
    f, p, _ = write_case(tmp_path, annex="coverage_factor = 2.0")
    code, res, _ = cli_json(["calibrate", str(f), "--protocol", str(p), "--out",
                             str(tmp_path / "o")], capsys)
    assert code == 0 and res["extra"]["uncertainty"]["k"] == 2.0
    assert res["extra"]["uncertainty"]["k_source"] == "fixed by laboratory"
    assert "fixed by laboratory" in (tmp_path / "o" / "certificate.html").read_text()


# --------------------------------------------------------------------------- defect 4

def test_defect4_late_reading_excluded_and_u_BE_from_actual_time(tmp_path, capsys):
    f, p, lines = write_case(tmp_path, rows={(3, 2): (180.0, 3600.0), (1, 4): (360.0, 24.0)})
    res, _ = api(f, p, budget="draft")
    late = line_of(lines, 3, 2)
    un = {u["line"]: u["reason"] for u in res["unused_readings"]}
    assert "max_time_to_reading_s = 30" in un[late]
    # u(B_E) = 0.005 °/h × 60 ″/min/(°/h) × (24 s / 60) / √3, the longest time actually used
    b_e = [c for c in res["extra"]["uncertainty"]["components"] if c["symbol"] == "B_E"][0]
    assert b_e["u_arcsec"] == pytest.approx(0.005 * 60 * 24 / 60 / math.sqrt(3), rel=1e-9)


def test_defect4_late_reading_error_policy(tmp_path, capsys):
    f, p, lines = write_case(tmp_path, policy="error", rows={(3, 2): (180.0, 3600.0)})
    code, _, err = cli_json(["calibrate", str(f), "--protocol", str(p), "--out",
                             str(tmp_path / "o")], capsys)
    assert code == 2 and f"readings.csv:{line_of(lines, 3, 2)}" in err and "time_s" in err


# --------------------------------------------------------------------------- defect 5

def test_defect5_metadata_table_mpe_conflict_reported(tmp_path, capsys):
    f, p, _ = write_case(tmp_path, meta={"table_mpe_arcsec": "0.2"})
    res, err = api(f, p, budget="draft")
    assert res["extra"]["conflicts"] == [{"setting": "table_mpe_arcsec", "file_value": 0.2,
                                 "protocol_value": 0.1, "used": 0.2,
                                 "rule": "readings-file metadata over protocol annex_a"}]
    assert res["extra"]["uncertainty"]["components"][0]["u_arcsec"] == \
        pytest.approx(0.2 / math.sqrt(3))
    assert err.count("warning: table_mpe_arcsec") == 1


def test_defect5_protocol_named_in_file_is_used_or_refused(tmp_path, capsys):
    f, p, _ = write_case(tmp_path, meta={"protocol": "lab-24x15"})
    code, _, err = cli_json(["calibrate", str(f), "--out", str(tmp_path / "o")], capsys)
    assert code == 2 and "lab-24x15" in err and "--protocol" in err
    # the same name as a file next to the readings: used, and recorded
    (tmp_path / "lab-24x15.toml").write_text(p.read_text().replace('"hand"', '"lab-24x15"'))
    res, _ = api(f)
    assert res["settings"]["protocol"] == "lab-24x15" and res["extra"]["conflicts"] == []
    # --protocol overrides: the conflict is reported
    res, err = api(f, p)
    assert res["settings"]["protocol"] == "hand"
    c = res["extra"]["conflicts"][0]
    assert c["setting"] == "protocol" and c["used"] == "hand"
    assert "warning: protocol" in err


def test_precedence_rule_documented():
    doc = (ROOT / "docs" / "formats.md").read_text()
    assert "## Precedence of settings" in doc


def test_python_api_same_as_cli(tmp_path):
    f, p, _ = write_case(tmp_path, rows={(2, 1): (91.0, 10.0)})
    rep = analyse(f, p)                  # the analysis objects behind the sealed result
    assert rep.results.angle_deviation.details["excluded_readings"] == 1
    res = calibrate(f, p).to_json()
    assert res["items"]["angle_deviation"]["details"]["excluded_readings"] == 1
    assert {k for k, it in res["items"].items() if it["uncertainty"]} == set(rep.item_uncertainty)
    assert set(rep.item_uncertainty) == {"scale_factor", "scale_factor_nonlinearity",
                                         "angle_deviation", "repeatability"}


# --------------------------------------------------------------------------- budgets

def test_draft_budget_has_the_annex_four_lines_physical_more(tmp_path):
    f, p, _ = write_case(tmp_path)
    draft, _ = api(f, p, budget="draft")
    phys, _ = api(f, p)
    assert [c["symbol"] for c in draft["extra"]["uncertainty"]["components"]] == \
        ["P", "phi_e", "B_E", "r"]
    assert draft["extra"]["uncertainty"]["budget_kind"] == "draft"
    extra = [c for c in phys["extra"]["uncertainty"]["components"] if c["beyond_draft"]]
    assert {c["symbol"] for c in extra} == {"tilt_E"}    # angles in degrees: no K in E
    (tmp_path / "c").mkdir()
    fc, pc, _ = write_case(tmp_path / "c", counts=True)   # angles from counts through K
    physc, _ = api(fc, pc)
    e_i = E.mean(axis=0)                                   # 0.2, −0.26, 0.3, 0.26
    ad = physc["items"]["angle_deviation"]
    assert ad["details"]["signed_extreme_arcsec"] == pytest.approx(
        e_i[np.argmax(np.abs(e_i))], abs=1e-9)
    assert ad["value"] == pytest.approx(np.max(np.abs(e_i)), abs=1e-9)   # max|E_i| certified
    extra = [c for c in physc["extra"]["uncertainty"]["components"] if c["beyond_draft"]]
    # the table's errors at the stops (K_P) are in P, one line with the point's and the zero's
    assert {c["symbol"] for c in extra} == {"K_r", "tilt_E"}
    assert all(c["clause"] for c in extra)
    p_line = [c for c in physc["extra"]["uncertainty"]["components"] if c["symbol"] == "P"]
    assert "7.1 stops" in p_line[0]["source"]
    assert phys["extra"]["uncertainty"]["U_arcsec"] > draft["extra"]["uncertainty"]["U_arcsec"]


def test_measured_tilt_scales_the_coupling_line(tmp_path):
    """--tilt FILE: the coupling line uses ψ + U95 of the estimate instead of the 0.1°
    bound; the line is proportional to sin ψ (closed form), so it shrinks by
    sin 0.015°/sin 0.1° = 0.15."""
    f, p, _ = write_case(tmp_path)
    t = tmp_path / "tilt.json"
    t.write_text(json.dumps({"tilt_deg": 0.01, "U95_tilt_deg": 0.005}))
    a, _ = api(f, p)
    b, _ = api(f, p, tilt=t)
    ua = {c["symbol"]: c["u_arcsec"] for c in a["extra"]["uncertainty"]["components"]}
    ub = {c["symbol"]: c["u_arcsec"] for c in b["extra"]["uncertainty"]["components"]}
    ratio = math.sin(math.radians(0.015)) / math.sin(math.radians(0.1))
    assert ub["tilt_E"] / ua["tilt_E"] == pytest.approx(ratio, rel=1e-6)
    assert any("measured tilt" in n for n in b["extra"]["uncertainty"]["notes"])
    t.write_text("{}")
    with pytest.raises(GonioError, match="tilt_deg"):
        calibrate(f, p, tilt=t)


def test_every_measured_item_has_the_results_json_shape(tmp_path):
    f, p, _ = write_case(tmp_path)
    res, _ = api(f, p)
    keys = {"components", "u_c", "U", "k", "nu_eff", "coverage_probability", "k_source"}
    ckeys = {"name", "symbol", "u", "c", "contribution", "unit", "type", "distribution", "dof",
             "source", "beyond_standard", "clause"}
    for item in ("scale_factor", "scale_factor_nonlinearity", "angle_deviation",
                 "repeatability"):
        u = res["items"][item]["uncertainty"]
        assert keys <= set(u) and u["coverage_probability"] == 0.95, item
        assert all(ckeys == set(c) for c in u["components"]), item
        if u["k"] is None:       # stated by its χ² interval: U reaches its upper end
            assert u["U"] == pytest.approx(u["interval"][1] - res["items"][item]["value"])
        else:
            assert u["U"] == pytest.approx(u["k"] * u["u_c"])
    rep_ = res["items"]["repeatability"]
    assert rep_["uncertainty"]["interval"][0] == 0.0 < rep_["value"]
    for item in ("zero_stability", "rate_consistency", "pointing_consistency"):
        assert res["items"][item]["uncertainty"] is None


def test_cli_budget_draft_and_tilt_file(tmp_path, capsys):
    f, p, _ = write_case(tmp_path)
    t = tmp_path / "tilt.json"        # a tilt result shows the readings it came from
    from gonio.formats.provenance import result_source
    t.write_text(json.dumps(result_source(f, {"tilt_deg": 0.02, "U95_tilt_deg": 0.01})))
    code, res, _ = cli_json(["calibrate", str(f), "--protocol", str(p), "--out",
                             str(tmp_path / "o"), "--budget", "draft", "--tilt", str(t)],
                            capsys)
    assert code == 0 and res["extra"]["uncertainty"]["budget_kind"] == "draft"
    assert len(res["extra"]["uncertainty"]["components"]) == 4
    # the measured tilt bounds φ_e too: elliptic extreme at 0.03° instead of 0.1° (A.4.2)
    from gonio.specs.ogam_draft.tilt import elliptic_extreme
    phi = res["extra"]["uncertainty"]["components"][1]
    assert phi["half_width_arcsec"] == pytest.approx(elliptic_extreme(0.03).extreme_arcsec)
    from gonio.report.i18n import labels
    from gonio.specs.ogam_draft.phrases import LABELS

    import html

    page = html.unescape((tmp_path / "o" / "certificate.html").read_text())
    assert labels("en", LABELS)["budget_kind_draft"] in page


def test_one_series_physical_r_source_says_what_it_takes(tmp_path, capsys):
    """With one series the physical budget's r is the protocol's u(r) over √n, not the 7.4
    series' noise model: its source says so in English, and the Chinese certificate's source
    is the u(r)/√n sentence, not the noise-model one; the A.4.4 note names both forms."""
    from gonio.specs.ogam_draft.phrases import BUDGET_SOURCES_PHYSICAL_ZH
    from gonio.specs.ogam_draft.stated import budget_source

    f, p, _ = write_case(tmp_path, series=1)
    code, res, _ = cli_json(["calibrate", str(f), "--protocol", str(p), "--out",
                             str(tmp_path / "o")], capsys)
    assert code == 0
    comps = {c["symbol"]: c for c in res["extra"]["uncertainty"]["components"]}
    src = comps["r"]["source"]
    assert "[physical budget: u(r)/sqrt(n)]" in src and "reading noise" not in src
    zh = budget_source("r", src, "zh")
    assert zh == BUDGET_SOURCES_PHYSICAL_ZH["r/sqrt(n)"] != BUDGET_SOURCES_PHYSICAL_ZH["r"]
    noise_src = ("reading noise at this point's time from zeroing to reading, 17 s: ... "
                 "[physical budget; the draft's A.4.4 takes the largest s]")
    assert budget_source("r", noise_src, "zh") == BUDGET_SOURCES_PHYSICAL_ZH["r"]


def test_negative_time_to_reading_is_refused_naming_the_line(tmp_path, capsys):
    """A 7.4 reading whose time_s is negative (the time from zeroing to reading cannot be):
    the physical budget refuses it in one line naming file, line and column, exit 2, where it
    reached the square root of the reading noise (a math-domain error) before."""
    f, p, lines = write_case(tmp_path, rows={(2, 3): (POS[2], -5.0)}, counts=True)
    before = f.read_bytes()
    code, res, err = cli_json(["calibrate", str(f), "--protocol", str(p), "--out",
                               str(tmp_path / "o")], capsys)
    assert code == 2, err
    n = line_of(lines, 2, 3)
    assert f"{f.name}:{n}" in err and "time_s" in err and "negative" in err, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert f.read_bytes() == before
