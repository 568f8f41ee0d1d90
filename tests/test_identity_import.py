"""The records' import path compares identity and conditions as ``gonio calibrate`` does
(docs/formats.md#identity-and-conditions): ``gonio db import FOLDER --lab FILE`` with a
laboratory file whose serial contradicts the readings is refused with one line (exit 2,
nothing recorded), for every specification; a laboratory file that proceeds is accepted only
for a folder whose results.json states the contradiction (computed with that file)."""

from __future__ import annotations

import re
import sqlite3

import pytest

from tests.test_provenance import LAB_SERIAL, PINS, RUNS, gonio, lab_file


def _calibrations(data) -> int:
    with sqlite3.connect(data / "records.sqlite3") as db:
        return db.execute("select count(*) from calibrations").fetchone()[0]


@pytest.mark.parametrize("spec, protocol, seed", RUNS, ids=[r[0] for r in RUNS])
def test_import_refuses_a_contradicting_laboratory_file(spec, protocol, seed, tmp_path):
    proto = [] if protocol is None else ["--protocol", PINS / protocol]
    sim, data = tmp_path / "sim", tmp_path / "data"
    gonio("simulate", "--spec", spec, *proto, "--seed", seed, "--out", sim, cwd=tmp_path)
    readings = sim / "readings.csv"
    gonio("calibrate", readings, "--spec", spec, *proto, "--out", tmp_path / "plain",
          cwd=tmp_path)
    gonio("db", "init", "--data", data, cwd=tmp_path)
    strict = lab_file(tmp_path, name="strict.toml")
    proceed = lab_file(tmp_path, 'on_mismatch = "proceed"', name="proceed.toml")
    for lab in (strict, proceed):      # no standards: the store has none registered
        lab.write_text(re.sub(r"(?ms)^\[\[standards\]\]\n.*?\n\n", "", lab.read_text("utf-8")),
                       encoding="utf-8")
        assert "[[standards]]" not in lab.read_text("utf-8")
    imp = ("db", "import", "--data", data, "--readings", readings, *proto)
    for lab in (strict, proceed):        # the folder was computed without the laboratory file
        r = gonio(*imp, "--lab", lab, tmp_path / "plain", cwd=tmp_path, rc=2)
        line = r.stderr.strip()
        assert "\n" not in line and "Traceback" not in line, line
        assert "serial" in line and LAB_SERIAL in line, line
    assert _calibrations(data) == 0
    gonio("calibrate", readings, "--spec", spec, *proto, "--lab", proceed, "--out",
          tmp_path / "flagged", cwd=tmp_path)
    gonio(*imp, "--lab", proceed, tmp_path / "flagged", cwd=tmp_path)
    assert _calibrations(data) == 1
