"""Damaged triad inputs, from the outside: a simulated readings.csv + thermal.csv is
damaged as a file would be (cut short, a typed set point, a spike in the static record),
then ``gonio calibrate`` runs on it. Each is refused with a one-line error (exit 2) or set
aside and stated as a finding; none changes a certified number silently."""

from __future__ import annotations

import json
import shutil

import pytest

from gonio.cli import main


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    d = tmp_path_factory.mktemp("tri") / "sim"
    assert main(["simulate", "--spec", "triad-alignment", "--out", str(d)]) == 0
    return d


def _copy(sim, tmp_path):
    d = tmp_path / "in"
    shutil.copytree(sim, d)
    return d


def _rows(text: str, test: str) -> list[int]:
    return [i for i, ln in enumerate(text.split("\n")) if ln.startswith(test + ",")]


def _edit(text: str, i: int, column: str, value: str) -> str:
    lines = text.split("\n")
    header = next(ln for ln in lines if ln.startswith("test,")).split(",")
    cells = lines[i].split(",")
    cells[header.index(column)] = value
    lines[i] = ",".join(cells)
    return "\n".join(lines)


def _calibrate(d, tmp_path, capsys):
    rc = main(["calibrate", str(d / "readings.csv"), "--out", str(tmp_path / "out")])
    return rc, capsys.readouterr()


@pytest.mark.parametrize("cut", [1, 6, 17])
def test_thermal_file_cut_inside_its_last_number_is_refused(sim, tmp_path, capsys, cut):
    """Before: the last row's sd_z cut to '0' (cells all present, no final newline) was
    read as 0 and moved the certified ARW_z at the last set point by −12 %."""
    d = _copy(sim, tmp_path)
    text = (d / "thermal.csv").read_text(encoding="utf-8")
    (d / "thermal.csv").write_text(text.rstrip("\n")[:-cut], encoding="utf-8")
    n = len(text.rstrip("\n").split("\n"))
    rc, cap = _calibrate(d, tmp_path, capsys)
    assert rc == 2
    err = cap.err.strip()
    assert "\n" not in err and "Traceback" not in err
    assert f"thermal.csv:{n}: column sd_z: the file ends inside its last row" in err, err


def test_readings_file_cut_inside_its_last_number_is_refused(sim, tmp_path, capsys):
    d = _copy(sim, tmp_path)
    text = (d / "readings.csv").read_text(encoding="utf-8")
    (d / "readings.csv").write_text(text.rstrip("\n")[:-3], encoding="utf-8")
    rc, cap = _calibrate(d, tmp_path, capsys)
    assert rc == 2 and "readings.csv:" in cap.err and "ends inside its last row" in cap.err


def test_complete_files_with_a_final_newline_still_calibrate(sim, tmp_path, capsys):
    d = _copy(sim, tmp_path)
    rc, _ = _calibrate(d, tmp_path, capsys)
    assert rc == 0
