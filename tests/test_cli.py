"""The command line: outputs, JSON keys and units, partial files, one-line errors with exit code 2."""

from __future__ import annotations

import json
from pathlib import Path
import subprocess
import sys

import pytest

from gonio.cli import main

UNITS = {"scale_factor": "counts/deg", "scale_factor_nonlinearity": "%", "zero_stability": "deg/h",
         "angle_deviation": "arcsec", "repeatability": "arcsec", "rate_consistency": "ppm",
         "pointing_consistency": "%"}

SMALL = (Path(__file__).parent / "data" / "small-protocol.toml").read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("sim")
    (d / "small.toml").write_text(SMALL)
    bench = d / "bench.toml"
    from gonio.resources import resolve
    text = resolve("rlg", "bench").read_text().replace("sample_rate_hz = 1000.0", "sample_rate_hz = 100.0")
    text = text.replace('table = "table-precision"', f'table = "{resolve("table-precision", "bench")}"')
    bench.write_text(text)
    assert main(["simulate", "--protocol", str(d / "small.toml"), "--bench", str(bench),
                 "--seed", "5", "--out", str(d / "out")]) == 0
    return d


def test_simulate_then_calibrate(small_run, capsys):
    d = small_run
    assert (d / "out" / "readings.csv").is_file() and (d / "out" / "truth.json").is_file()
    capsys.readouterr()
    assert main(["calibrate", str(d / "out" / "readings.csv"), "--protocol", str(d / "small.toml"),
                 "--out", str(d / "cal"), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    written = json.loads((d / "cal" / "results.json").read_text())
    assert printed == written
    for key, unit in UNITS.items():
        it = written["items"][key]
        assert it["unit"] == unit and it["measured"] is True, key
        assert isinstance(it["value"], float)
    u = written["extra"]["uncertainty"]
    assert {"components", "u_c_arcsec", "U_arcsec", "k"} <= set(u)
    # the physical budget (default): the annex's four lines, then those beyond the draft
    assert [c["symbol"] for c in u["components"]][:4] == ["P", "phi_e", "B_E", "r"]
    assert u["budget_kind"] == "physical"
    # beyond the draft: K_r and the tilt line (the stops' table errors K_P are in P, per point)
    assert [c["beyond_draft"] for c in u["components"]] == [False] * 4 + [True] * 2
    assert u["U_arcsec"] == pytest.approx(u["k"] * u["u_c_arcsec"])
    # u(r) of the physical budget is E_i's, a mean over the series, at the extreme's point:
    # under this calibration's own repeatability (7.5, one reading, the largest point's)
    assert 0 < u["components"][3]["u_arcsec"] < written["items"]["repeatability"]["value"]
    assert "mean of" in u["components"][3]["source"]


def test_partial_file_reports_not_measured(small_run, tmp_path, capsys):
    src = (small_run / "out" / "readings.csv").read_text().splitlines(keepends=True)
    keep = [ln for ln in src if ln.startswith("#") or ln.startswith("test,")
            or ln.startswith("angle_deviation,")]
    f = tmp_path / "partial.csv"
    f.write_text("".join(keep))
    assert main(["calibrate", str(f), "--protocol", str(small_run / "small.toml"),
                 "--out", str(tmp_path / "o")]) == 0
    res = json.loads((tmp_path / "o" / "results.json").read_text())["items"]
    assert res["angle_deviation"]["measured"] and res["repeatability"]["measured"]
    for key in ("scale_factor", "zero_stability", "rate_consistency", "pointing_consistency"):
        assert res[key]["measured"] is False and res[key]["value"] is None and res[key]["reason"]


def test_input_file_unchanged_and_outputs_deterministic(small_run, tmp_path):
    f = small_run / "out" / "readings.csv"
    before = f.read_bytes()
    p = str(small_run / "small.toml")
    assert main(["calibrate", str(f), "--protocol", p, "--out", str(tmp_path / "a")]) == 0
    assert main(["calibrate", str(f), "--protocol", p, "--out", str(tmp_path / "b")]) == 0
    assert f.read_bytes() == before
    assert (tmp_path / "a" / "results.json").read_bytes() == (tmp_path / "b" / "results.json").read_bytes()


@pytest.mark.parametrize("argv, fragment", [
    (["calibrate", "nope.csv", "--out", "x"], "nope.csv"),
    (["simulate", "--bench", "nobench", "--out", "x"], "bench file not found"),
    (["simulate", "--seed", "-1", "--out", "x"], "--seed"),
])
def test_errors_are_one_line_exit_2(argv, fragment, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and fragment in err and "Traceback" not in err
    assert not (tmp_path / "x" / "results.json").exists()


def test_bad_readings_file_in_subprocess(tmp_path):
    f = tmp_path / "bad.csv"
    f.write_text("test,series,round,time_s,table_deg,gyro_deg\nangle_deviation,1,1,5.0,30.0,abc\n")
    r = subprocess.run([sys.executable, "-m", "gonio", "calibrate", str(f), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "bad.csv:2" in r.stderr and "gyro_deg" in r.stderr
    assert "Traceback" not in r.stderr
    assert not (tmp_path / "o" / "results.json").exists()


def test_incomplete_equal_division_rows_do_not_stop_the_calibration(tmp_path):
    """A stray equal_division row (tests/data/full.csv has one) is reported, not fatal."""
    from pathlib import Path

    full = Path(__file__).parent / "data" / "full.csv"
    assert main(["calibrate", str(full), "--protocol", str(full.with_suffix(".toml")),
                 "--out", str(tmp_path / "o")]) == 0
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    assert "equal_division" not in res["extra"]
    stray = [u for u in res["unused_readings"] if u["test"] == "equal_division"]
    assert stray and all("equal-division analysis not possible" in u["reason"] for u in stray)
    assert res["items"]["angle_deviation"]["measured"]
