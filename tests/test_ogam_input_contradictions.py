"""Optical draft: inputs that contradict themselves are refused, and a limitation the
calibration knows reaches the certificate, all through ``gonio calibrate``.

- a 7.3 reading at a negative time, or at a time not after its series' previous round's:
  one line naming the line and ``time_s``, exit 2 (before, it was used, flagged
  off-schedule, and B_s moved);
- a row whose ``gyro_deg`` contradicts its ``gyro_counts`` through K: refused naming the line
  and both columns, also where the screen would have set the row aside as an outlier;
- a laboratory file whose certificate is issued before the calibration, or whose item was
  received after it, and an upper limit below zero for an item that cannot be negative;
- no 7.1 readings: E, C_v and C_g are read with the metadata's nominal K, and the
  certificate (en, zh) says so beside them, not only results.json and summary.txt.
"""

from __future__ import annotations

import contextlib
import io
import re
import shutil
from pathlib import Path

import pytest

from gonio.cli import main

ROOT = Path(__file__).resolve().parents[1]
LAB = (ROOT / "protocols" / "lab-example.toml").read_text(encoding="utf-8")


def _gonio(argv: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(argv)
    return rc, err.getvalue()


@pytest.fixture
def readings(shared_simulation, tmp_path):
    """(path, lines) of a copy of the simulated optical readings, to edit."""
    sim = tmp_path / "sim"
    shutil.copytree(shared_simulation("ogam-draft"), sim)
    path = sim / "readings.csv"
    return path, path.read_text(encoding="utf-8").split("\n")


def _edit(lines: list[str], prefix: str, col: int, value: str) -> tuple[list[str], int]:
    """The lines with cell ``col`` of the first line starting with ``prefix`` set to
    ``value``, and that line's number (1-based)."""
    i = next(n for n, x in enumerate(lines) if x.startswith(prefix))
    cells = lines[i].split(",")
    cells[col] = value
    return lines[:i] + [",".join(cells)] + lines[i + 1:], i + 1


def _refused(path: Path, tmp_path: Path, *more: str) -> str:
    rc, err = _gonio(["calibrate", str(path), "--out", str(tmp_path / "out"), *more])
    assert rc == 2, err
    lines = [x for x in err.splitlines() if x.strip()]
    assert len(lines) == 1 and lines[0].startswith("gonio: error: "), err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize("time_s, words", [("-300", "before the zeroing"),
                                            ("200", "must increase with the round")])
def test_zero_stability_time_negative_or_out_of_order_refused(readings, tmp_path, time_s,
                                                               words):
    path, lines = readings
    edited, line = _edit(lines, "zero_stability,1,4,", 5, time_s)
    path.write_text("\n".join(edited), encoding="utf-8")
    msg = _refused(path, tmp_path)
    assert f"readings.csv:{line}: column time_s:" in msg and words in msg, msg


def test_gyro_deg_contradicting_gyro_counts_refused(readings, tmp_path):
    path, lines = readings
    edited, line = _edit(lines, "angle_deviation,1,4,", 8, "12.5")
    path.write_text("\n".join(edited), encoding="utf-8")
    msg = _refused(path, tmp_path)
    assert f"readings.csv:{line}: column gyro_deg:" in msg and "gyro_counts" in msg, msg


@pytest.mark.parametrize("old, new, words", [
    ('date_of_issue = "2026-11-20"', 'date_of_issue = "2026-11-10"',
     "date_of_issue 2026-11-10 is before date_of_calibration 2026-11-16"),
    ('date_of_receipt = "2026-11-02"', 'date_of_receipt = "2026-11-30"',
     "date_of_calibration 2026-11-16 is before date_of_receipt 2026-11-30")])
def test_lab_dates_out_of_order_refused(readings, tmp_path, old, new, words):
    assert old in LAB
    lab = tmp_path / "lab.toml"
    lab.write_text(LAB.replace(old, new), encoding="utf-8")
    msg = _refused(readings[0], tmp_path, "--lab", str(lab))
    assert "lab.toml: key certificate.date_of_" in msg and words in msg, msg


def test_upper_limit_below_zero_of_a_nonnegative_item_refused(readings, tmp_path):
    lab = tmp_path / "lab.toml"
    lab.write_text(LAB + '\n[[specification_limits]]\nitem = "zero_stability"\n'
                   'upper = -0.01\n', encoding="utf-8")
    msg = _refused(readings[0], tmp_path, "--lab", str(lab))
    assert "lab.toml: key specification_limits[" in msg and "].upper:" in msg, msg
    assert "zero_stability cannot be negative" in msg, msg


@pytest.mark.parametrize("lang, words", [
    ("en", "nominal scale factor of the readings"), ("zh", "标称标度因数")])
def test_nominal_k_stated_on_the_certificate(readings, tmp_path, lang, words):
    path, lines = readings
    path.write_text("\n".join(x for x in lines if not x.startswith("scale_factor,")),
                    encoding="utf-8")
    out = tmp_path / "out"
    rc, err = _gonio(["calibrate", str(path), "--out", str(out), "--lang", lang])
    assert rc == 0, err
    html = (out / "certificate.html").read_text(encoding="utf-8")
    assert len(re.findall(re.escape(words), html)) >= 3, "E, C_v and C_g"
    import json
    items = json.loads((out / "results.json").read_text(encoding="utf-8"))["items"]
    for name in ("angle_deviation", "rate_consistency", "pointing_consistency"):
        assert items[name]["details"]["scale_factor_for_angles_source"] == "metadata"
