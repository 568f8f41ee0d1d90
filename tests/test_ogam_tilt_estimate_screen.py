"""The optical draft's in-situ tilt estimate, from the outside: its rows are screened like
the other groups (a typo in one rest is set aside, ψ comes from the others), and a measured
tilt whose 95 % interval lies beyond the stated bound (Annex A.1's ``tilt_bound_deg``) is a
finding on the certificate, with the bound's lines taken at ψ + U95.

The numbers are checked against a first-harmonic fit made here with numpy (not gonio's
fit) and against the coupling line's proportionality to sin ψ.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from gonio.cli import main

#: Earth's rotation rate, ″/s (IERS: 7.292115e-5 rad/s).
EARTH_ARCSEC_S = 7.292115e-5 * 180.0 / math.pi * 3600.0


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    out = tmp_path_factory.mktemp("tilt_sim")
    assert main(["simulate", "--spec", "ogam-draft", "--seed", "7", "--out",
                 str(out / "S")]) == 0
    return out / "S" / "readings.csv"


def tilt_rows(path: Path) -> list[tuple[int, list[str]]]:
    """(1-based line, fields) of the tilt_estimate rows."""
    return [(i + 1, ln.split(",")) for i, ln in enumerate(path.read_text().splitlines())
            if ln.startswith("tilt_estimate,")]


def edited(src: Path, dst: Path, line: int | None = None, add: int = 0,
           header: tuple[str, str] | None = None) -> Path:
    lines = src.read_text().splitlines(keepends=True)
    if line is not None:
        p = lines[line - 1].rstrip("\n").split(",")
        p[7] = str(int(p[7]) + add)
        lines[line - 1] = ",".join(p) + "\n"
    if header is not None:
        lines = [header[1] if ln.startswith(header[0]) else ln for ln in lines]
    dst.mkdir(parents=True, exist_ok=True)
    (dst / "readings.csv").write_text("".join(lines))
    return dst / "readings.csv"


def calibrate(readings: Path, out: Path, *more) -> dict:
    assert main(["calibrate", str(readings), "--out", str(out), *more]) == 0
    return json.loads((out / "results.json").read_text())


def psi_numpy(path: Path, k: float, skip=()) -> float:
    """ψ from the tilt rows by a least-squares first harmonic made here (numpy)."""
    md = {ln[2:].split(":")[0]: ln.split(":", 1)[1].strip()
          for ln in path.read_text().splitlines() if ln.startswith("# ") and ":" in ln}
    rows = [p for line, p in tilt_rows(path) if line not in skip]
    th = np.radians([float(p[6]) for p in rows])
    rate = np.array([float(p[7]) / k / float(p[5]) * 3600.0 for p in rows])
    x = np.column_stack([np.ones_like(th), np.cos(th), np.sin(th)])
    c0, a, b = np.linalg.lstsq(x, rate, rcond=None)[0]
    perp = EARTH_ARCSEC_S * math.cos(math.radians(float(md["latitude_deg"])))   # axis up
    return math.degrees(math.asin(math.hypot(a, b) / perp))


def tilt_measured(res: dict) -> dict:
    return res["items"]["scale_factor"]["details"]["tilt_measured"]


def test_clean_tilt_rows_no_finding(sim, tmp_path):
    res = calibrate(sim, tmp_path / "o")
    assert not [f for f in res["findings"] if f["test"] == "tilt_estimate"]
    k = res["items"]["scale_factor"]["value"]
    assert tilt_measured(res)["tilt_deg"] == pytest.approx(psi_numpy(sim, k), rel=1e-4)


@pytest.mark.parametrize("add", [400, -400, 100])
def test_typo_in_a_tilt_row_is_set_aside(sim, tmp_path, add):
    line = tilt_rows(sim)[3][0]                 # the 90° rest (line 36 of seed 7's file)
    bad = edited(sim, tmp_path / "in", line, add)
    res = calibrate(bad, tmp_path / "o")
    found = [f for f in res["findings"] if f["test"] == "tilt_estimate"]
    assert [(f["line"], f["action"], f["column"]) for f in found] == \
        [(line, "set_aside", "gyro_counts")]
    k = res["items"]["scale_factor"]["value"]
    # ψ from the five complete opposite pairs left (numpy): not from the typo (which moved
    # it to ~0.17°), nor from its partner, whose wander the pair no longer cancels
    theta = float(tilt_rows(sim)[3][1][6])
    partner = [ln for ln, p in tilt_rows(sim)
               if abs((float(p[6]) - theta) % 360.0 - 180.0) < 1e-6]
    assert len(partner) == 1
    psi = tilt_measured(res)["tilt_deg"]
    assert psi == pytest.approx(psi_numpy(bad, k, skip={line, *partner}), rel=1e-4)
    assert abs(psi - psi_numpy(sim, k)) < tilt_measured(res)["U95_tilt_deg"]
    assert not [f for f in res["findings"] if f["code"] == "tilt-beyond-bound"]
    html = (tmp_path / "o" / "certificate.html").read_text()
    assert "departs from the fit the other positions draw" in html
    # its pair is incomplete: the partner left out, u from the five pairs (ν = 3), and the
    # calibration says so; the clean file's six pairs give ν = 4
    tc = res["items"]["scale_factor"]["details"]["tilt_correction"]
    assert (tc["basis"], tc["dof"]) == ("opposite pairs", 3)
    assert tc["left_out_deg"] == [(theta + 180.0) % 360.0]
    assert "is left out of the fit: its opposite partner was set aside" in json.dumps(res)
    clean = calibrate(sim, tmp_path / "c")["items"]["scale_factor"]["details"]["tilt_correction"]
    assert (clean["basis"], clean["dof"]) == ("opposite pairs", 4)


def bound_line_u(res: dict) -> float:
    """u of the draft's K_tilt line of K (the coupling at the bound)."""
    comps = res["items"]["scale_factor"]["details"]["estimates"]["draft"]["uncertainty"][
        "components"]
    return next(c["u"] for c in comps if c["symbol"] == "K_tilt")


def test_tilt_beyond_stated_bound_is_a_finding(sim, tmp_path):
    k = 76434.84
    psi = psi_numpy(sim, k)
    assert 0.04 < psi < 0.055                     # the bench's mounting 0.05° (estimate 0.048°)
    low = edited(sim, tmp_path / "low", header=("# tilt_bound_deg:", "# tilt_bound_deg: 0.02\n"))
    near = edited(sim, tmp_path / "near",
                  header=("# tilt_bound_deg:", "# tilt_bound_deg: 0.047\n"))
    far = edited(sim, tmp_path / "far", header=("# tilt_bound_deg:", "# tilt_bound_deg: 0.2\n"))
    r_low, r_near = calibrate(low, tmp_path / "ol"), calibrate(near, tmp_path / "on")
    r_far = calibrate(far, tmp_path / "of")
    beyond = [f for f in r_low["findings"] if f["code"] == "tilt-beyond-bound"]
    assert len(beyond) == 1 and beyond[0]["action"] == "flagged" and beyond[0]["clause"] == "A.1"
    assert "0.02°" in beyond[0]["message"]
    # 0.047° lies inside ψ's interval: the bound is not contradicted (no finding), but it no
    # longer bounds what was measured: its lines are taken at ψ + U95 as well, and noted
    assert not [f for f in r_near["findings"] if f["code"] == "tilt-beyond-bound"]
    tm = tilt_measured(r_low)
    top = tm["tilt_deg"] + tm["U95_tilt_deg"]
    assert tm["tilt_deg"] - tm["U95_tilt_deg"] > 0.02
    assert tm["tilt_deg"] - tm["U95_tilt_deg"] <= 0.047 < top
    assert bound_line_u(r_near) == pytest.approx(bound_line_u(r_low), rel=1e-9)
    assert f"upper 95 % limit psi + U95 = {top:.3g} deg" in json.dumps(r_near)
    # 0.2° bounds the whole interval: the line stays at the stated bound (the coupling is
    # proportional to the sine of the tilt), nothing noted
    assert top < 0.2 and "psi + U95 =" not in json.dumps(r_far)
    ratio = bound_line_u(r_low) / bound_line_u(r_far)
    assert ratio == pytest.approx(math.sin(math.radians(top)) / math.sin(math.radians(0.2)),
                                  rel=1e-3)
    html = (tmp_path / "ol" / "certificate.html").read_text()
    assert "beyond the stated tilt bound 0.02°" in html
    assert main(["calibrate", str(low), "--out", str(tmp_path / "oz"), "--lang", "zh"]) == 0
    assert "超出所声明的倾斜限值 0.02°" in (tmp_path / "oz" / "certificate.html").read_text()


def test_the_tilt_estimate_keeps_the_files_rounds_and_marks_the_lone_rest(sim, tmp_path, capsys):
    """``gonio tilt-estimate --json`` on a file with one rest removed: the positions keep the
    file's round numbers (the removed one missing, none renumbered), the removed rest's
    partner is marked out of the fit, and the text output names it."""
    rows = tilt_rows(sim)
    line, fields = rows[3]
    text = sim.read_text().splitlines(keepends=True)
    del text[line - 1]
    src = tmp_path / "cut.csv"
    src.write_text("".join(text))
    assert main(["tilt-estimate", str(src), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    gone, theta = int(fields[2]), float(fields[6])
    rounds = [p["round"] for p in d["positions"]]
    assert gone not in rounds and sorted(rounds) == sorted(int(p[2]) for _, p in rows
                                                           if int(p[2]) != gone)
    out = [p["table_deg"] for p in d["positions"] if not p["in_fit"]]
    assert out == d["left_out_deg"] == [(theta + 180.0) % 360.0]
    assert (d["basis"], d["dof"]) == ("opposite pairs", 3)
    assert main(["tilt-estimate", str(src)]) == 0
    assert "left out of the fit (opposite partner missing)" in capsys.readouterr().out
