"""The records' import path compares identity and conditions as ``gonio calibrate`` does
(docs/formats.md#identity-and-conditions): ``gonio db import FOLDER --lab FILE`` with a
laboratory file whose serial contradicts the readings is refused with one line (exit 2,
nothing recorded), for every specification; a laboratory file that proceeds is accepted only
for a folder whose results.json states the contradiction (computed with that file).

The commands run in this process (:func:`gonio.cli.main`, its exit code and stderr: what the
console script returns and prints) but the last import, which runs as its own process
(``python -m gonio db import``: the command line end to end, as a user runs it; simulate and
calibrate run so in tests/test_provenance.py). Each process started paid gonio's import
again (about 1.5 s of CPU each, seven per specification)."""

from __future__ import annotations

import re
import sqlite3

import pytest

from gonio.cli import main
from tests.test_provenance import LAB_SERIAL, PINS, RUNS, gonio, lab_file, simulated


def _calibrations(data) -> int:
    with sqlite3.connect(data / "records.sqlite3") as db:
        return db.execute("select count(*) from calibrations").fetchone()[0]


def run_in_process(capsys, *args, rc: int = 0) -> str:
    """``gonio ARGS`` through :func:`gonio.cli.main` in this process: asserts its exit code
    ``rc``; returns what it wrote to stderr."""
    capsys.readouterr()
    got = main([str(a) for a in args])
    err = capsys.readouterr().err
    assert got == rc, err
    return err


@pytest.mark.parametrize("spec, protocol, seed", RUNS, ids=[r[0] for r in RUNS])
def test_import_refuses_a_contradicting_laboratory_file(spec, protocol, seed, tmp_path,
                                                        monkeypatch, capsys, shared_simulation):
    monkeypatch.chdir(tmp_path)
    proto = [] if protocol is None else ["--protocol", PINS / protocol]
    sim, data = tmp_path / "sim", tmp_path / "data"
    simulated(shared_simulation, spec, protocol, seed, sim)      # gonio simulate's set
    readings = sim / "readings.csv"
    run_in_process(capsys, "calibrate", readings, "--spec", spec, *proto, "--out",
                   tmp_path / "plain")
    run_in_process(capsys, "db", "init", "--data", data)
    strict = lab_file(tmp_path, name="strict.toml")
    proceed = lab_file(tmp_path, 'on_mismatch = "proceed"', name="proceed.toml")
    for lab in (strict, proceed):      # no standards: the store has none registered
        lab.write_text(re.sub(r"(?ms)^\[\[standards\]\]\n.*?\n\n", "", lab.read_text("utf-8")),
                       encoding="utf-8")
        assert "[[standards]]" not in lab.read_text("utf-8")
    imp = ("db", "import", "--data", data, "--readings", readings, *proto)
    for lab in (strict, proceed):        # the folder was computed without the laboratory file
        line = run_in_process(capsys, *imp, "--lab", lab, tmp_path / "plain", rc=2).strip()
        assert line.startswith("gonio: "), line
        assert "\n" not in line and "Traceback" not in line, line
        assert "serial" in line and LAB_SERIAL in line, line
    assert _calibrations(data) == 0
    run_in_process(capsys, "calibrate", readings, "--spec", spec, *proto, "--lab", proceed,
                   "--out", tmp_path / "flagged")
    gonio(*imp, "--lab", proceed, tmp_path / "flagged", cwd=tmp_path)   # its own process
    assert _calibrations(data) == 1
    # recorded under the laboratory file's serial: the issued certificate names what the
    # command line's certificate and its finding name (not the readings' serial)
    with sqlite3.connect(data / "records.sqlite3") as db:
        assert [r[0] for r in db.execute("select serial from instruments")] == [LAB_SERIAL]


def test_readings_without_a_serial_are_recorded_under_the_laboratory_files(
        tmp_path, monkeypatch, capsys, shared_simulation):
    """Readings that state no serial, calibrated with a laboratory file that does: no
    contradiction, and the certificate names the laboratory file's serial; the records
    register the instrument under it too, not as "(unknown serial)"."""
    spec, protocol, seed = RUNS[0]
    monkeypatch.chdir(tmp_path)
    sim, data = tmp_path / "sim", tmp_path / "data"
    simulated(shared_simulation, spec, protocol, seed, sim)
    readings = sim / "readings.csv"
    text = readings.read_text(encoding="utf-8")
    assert "# serial:" in text
    readings.write_text("".join(ln for ln in text.splitlines(keepends=True)
                                if not ln.startswith("# serial:")), encoding="utf-8")
    lab = lab_file(tmp_path)
    lab.write_text(re.sub(r"(?ms)^\[\[standards\]\]\n.*?\n\n", "", lab.read_text("utf-8")),
                   encoding="utf-8")
    proto = ["--protocol", PINS / protocol]
    run_in_process(capsys, "calibrate", readings, "--spec", spec, *proto, "--lab", lab,
                   "--out", tmp_path / "out")
    assert LAB_SERIAL in (tmp_path / "out" / "certificate.html").read_text(encoding="utf-8")
    run_in_process(capsys, "db", "init", "--data", data)
    run_in_process(capsys, "db", "import", "--data", data, "--readings", readings, *proto,
                   "--lab", lab, tmp_path / "out")
    with sqlite3.connect(data / "records.sqlite3") as db:
        assert [r[0] for r in db.execute("select serial from instruments")] == [LAB_SERIAL]
