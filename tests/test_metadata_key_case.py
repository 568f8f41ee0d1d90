"""A metadata key that states the instrument's identity or the conditions, misspelt or in
another case, is refused by every readings format (one line naming it, exit 2): ``# SERIAL:
X-9`` beside the file's ``# serial:`` was kept aside and never compared with the laboratory
file, and the triad's reader kept ``# temprature_c: 30`` (its near misses were not checked)."""

from __future__ import annotations

import shutil

import pytest

from gonio.cli import main

SPECS = ("ogam-draft", "jjf1535-2015", "iec62047-20", "triad-alignment")
SMALL = "tests/data/small-protocol.toml"


@pytest.mark.parametrize("line,key", [("# SERIAL: X-9", "SERIAL"),
                                      ("# Model: X-9", "Model"),
                                      ("# humidty_pct: 90", "humidty_pct"),
                                      ("# temprature_c: 30", "temprature_c")])
@pytest.mark.parametrize("spec", SPECS)
def test_a_misspelt_identity_key_is_refused(spec, line, key, shared_simulation, tmp_path,
                                            capsys):
    sim = shared_simulation(spec, SMALL if spec == "ogam-draft" else None)
    folder = tmp_path / "sim"
    shutil.copytree(sim, folder)
    path = folder / "readings.csv"
    first, rest = path.read_text(encoding="utf-8").split("\n", 1)
    path.write_text(f"{first}\n{line}\n{rest}", encoding="utf-8")
    before = path.read_bytes()
    capsys.readouterr()
    code = main(["calibrate", str(path), "--out", str(tmp_path / "out")]
                + (["--protocol", SMALL] if spec == "ogam-draft" else []))
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "Traceback" not in err, err
    assert f"key {key}: unknown metadata key, did you mean" in err, err
    assert path.read_bytes() == before and not (tmp_path / "out" / "results.json").exists()
