"""`gonio noise` on streams with table motion (issue 12 item 7): only static windows
are analysed, a window with motion is refused, a readings file is refused."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from gonio.cli import main

K_COUNTS_PER_DEG = 3.6e6
ARW = 0.3  # white rate noise, (°/h)·√s
TAU0 = 0.1


def _stream(path, *, table=True):
    """Rest at 0° for 300 s, a 9 s move at 10 °/s to 90°, rest at 90° for 600 s."""
    rng = np.random.default_rng(8)
    t = np.arange(0.0, 909.0, TAU0)
    table_deg = np.clip((t - 300.0) * 10.0, 0.0, 90.0)
    rate_dph = ARW / math.sqrt(TAU0) * rng.standard_normal(t.size)
    gyro_deg = table_deg + np.cumsum(rate_dph) * TAU0 / 3600.0
    counts = np.round(gyro_deg * K_COUNTS_PER_DEG).astype(np.int64)
    lines = [f"# nominal_scale_factor_counts_per_deg: {K_COUNTS_PER_DEG:.0f}",
             "time_s,gyro_counts" + (",table_deg" if table else "")]
    for i in range(t.size):
        row = f"{t[i]:.1f},{counts[i]}"
        if table:
            row += f",{table_deg[i]:.6f}"
        lines.append(row)
    path.write_text("\n".join(lines) + "\n")
    return path


def test_noise_analyses_the_longest_rest_not_the_motion(tmp_path, capsys):
    s = _stream(tmp_path / "s.csv")
    assert main(["noise", str(s), "--json", "--bootstrap", "8"]) == 0
    out = json.loads(capsys.readouterr().out)
    w = out["window"]
    assert w["source"] == "rest" and out["windows_found"] == 2
    assert w["t_start_s"] >= 309.0 and w["t_end_s"] >= 908.0 and w["duration_s"] > 590
    # white rate noise only: N back (the whole record gave N = 0 and a huge K)
    assert out["fit"]["N"] == pytest.approx(ARW, rel=0.1)
    assert out["fit"]["chi2_red"] < 5


def test_noise_without_encoder_finds_rests_on_the_gyro(tmp_path, capsys):
    s = _stream(tmp_path / "g.csv", table=False)
    assert main(["noise", str(s), "--json", "--bootstrap", "0"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["window"]["t_start_s"] >= 300.0 and out["fit"]["N"] == pytest.approx(ARW, rel=0.1)


def test_window_option_and_motion_refused(tmp_path, capsys):
    s = _stream(tmp_path / "s.csv")
    assert main(["noise", str(s), "--window", "100:400", "--bootstrap", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "moves" in err and "s.csv" in err
    assert main(["noise", str(s), "--window", "320:800", "--json", "--bootstrap", "0"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["window"]["source"] == "option" and out["window"]["t_start_s"] == pytest.approx(320)
    assert main(["noise", str(s), "--window", "5:1e6"]) == 2
    assert "outside the record" in capsys.readouterr().err
    assert main(["noise", str(s), "--window", "abc"]) == 2
    assert "START:END" in capsys.readouterr().err


def test_each_window_reports_every_rest(tmp_path, capsys):
    s = _stream(tmp_path / "s.csv")
    assert main(["noise", str(s), "--each-window", "--json", "--bootstrap", "0",
                 "--kind", "hdev"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert len(out["windows"]) == 2
    assert [w["window"]["duration_s"] > 250 for w in out["windows"]] == [True, True]
    assert out["windows"][0]["allan"]["method"] == "hadamard"


def test_readings_file_is_refused(tmp_path, capsys):
    p = tmp_path / "r.csv"
    p.write_text("test,series,round,table_deg,gyro_counts\n"
                 "scale_factor,1,1,90,324000000\n")
    assert main(["noise", str(p)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "readings file" in err and "stream" in err


def test_default_uncertainties_are_the_bounded_covariance(tmp_path, capsys):
    """The defaults stay bounded: the fit's covariance, the bootstrap only on request (its
    records are synthesised at the window's length, B of them)."""
    s = _stream(tmp_path / "d.csv")
    assert main(["noise", str(s), "--json"]) == 0
    fit = json.loads(capsys.readouterr().out)["fit"]
    assert (fit["uncertainty_method"], fit["n_bootstrap"]) == ("covariance", 0)
    assert main(["noise", str(s), "--json", "--bootstrap", "3"]) == 0
    fit = json.loads(capsys.readouterr().out)["fit"]
    assert (fit["uncertainty_method"], fit["n_bootstrap"]) == ("bootstrap", 3)
