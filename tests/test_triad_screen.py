"""Issue 24: screening of triad readings from the outside — damaged copies of a simulated
session (duplicated row, sign-flipped dwell, a thermal programme at one temperature) are
refused with their line, on the API and the command line."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from gonio.cli import main
from gonio.errors import GonioError
from gonio.specs.triad_alignment.readings import read_triad_readings
from gonio.specs import get
from gonio.specs.triad_alignment.screen import screen


@pytest.fixture(scope="session")
def triad_files(tmp_path_factory):
    out = tmp_path_factory.mktemp("triad_screen") / "sim"
    assert main(["simulate", "--spec", "triad-alignment", "--seed", "2414", "--out",
                 str(out)]) == 0
    return out


def copy_with(src: Path, dst: Path, edit) -> Path:
    """The session's folder copied to ``dst`` with readings.csv's lines edited."""
    shutil.copytree(src, dst)
    f = dst / "readings.csv"
    f.write_text("".join(edit(f.read_text().splitlines(keepends=True))))
    return f


def first_line(lines, prefix) -> int:
    return next(i for i, ln in enumerate(lines) if ln.startswith(prefix))


def test_clean_session_has_no_finding(triad_files):
    for name in ("readings.csv", "thermal.csv"):
        assert screen(read_triad_readings(triad_files / name)) == []


def test_duplicated_row_is_refused_with_its_line(triad_files, tmp_path, capsys):
    box = {}

    def dup(ls):
        i = first_line(ls, "alignment,3,")
        box["line"] = i + 2                               # the copy, 1-based
        return ls[:i + 1] + [ls[i]] + ls[i + 1:]
    f = copy_with(triad_files, tmp_path / "d", dup)
    with pytest.raises(GonioError, match="repeats line") as exc:
        get("triad-alignment").calibrate(f)
    assert exc.value.line == box["line"]
    capsys.readouterr()
    assert main(["calibrate", str(f), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert f"readings.csv:{box['line']}" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_sign_flipped_dwell_is_set_aside_with_its_line(triad_files, tmp_path):
    """A rate-sign typo in one dwell: the screen flags it; the calibration sets that dwell
    aside (named by its line) and fits M and b from the other dwells, exactly as from the
    same file with the line deleted (docs/formats-triad.md, the screening)."""
    box = {}

    def flip(ls):
        i = first_line(ls, "alignment,4,")
        p = ls[i].split(",")
        p[6] = str(-float(p[6]))
        box["line"] = i + 1
        return ls[:i] + [",".join(p)] + ls[i + 1:]
    f = copy_with(triad_files, tmp_path / "s", flip)
    found = screen(read_triad_readings(f))
    assert [(x.code, x.line, x.column, x.action) for x in found] == [
        ("rate-sign", box["line"], "rate_dps", "flagged")]
    r = get("triad-alignment").calibrate(f)
    js = r.to_json()
    assert (box["line"], "set_aside") in [(x["line"], x["action"]) for x in js["findings"]]
    assert {x["line"] for x in js["findings"]} == {box["line"]}
    cut = copy_with(triad_files, tmp_path / "d",
                    lambda ls: ls[:box["line"] - 1] + ls[box["line"]:])
    ref = get("triad-alignment").calibrate(cut)
    for key in ("b_x", "M_xy"):
        assert r.items[key].measured and r.items[key].value == ref.items[key].value, key


def test_thermal_programme_at_one_temperature_is_refused(triad_files, tmp_path):
    dst = tmp_path / "t"
    shutil.copytree(triad_files, dst)
    th = dst / "thermal.csv"
    keep = []
    for ln in th.read_text().splitlines(keepends=True):
        p = ln.split(",")
        if ln.startswith("thermal,") and not (p[2] == "soak" and float(p[10]) == 25.0):
            continue
        keep.append(ln)
    th.write_text("".join(keep))
    with pytest.raises(GonioError, match="a temperature model needs") as exc:
        get("triad-alignment").calibrate(dst / "readings.csv")
    assert exc.value.line is not None and "thermal.csv" in str(exc.value.file)


def test_findings_reach_results_json(triad_files, tmp_path):
    from gonio.pipeline.dispatch import calibrate
    res, paths = calibrate(triad_files / "readings.csv", tmp_path / "o",
                           spec_key="triad-alignment")
    assert json.loads(paths["results"].read_text())["findings"] == []
