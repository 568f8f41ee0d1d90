"""Every file a calibration reads carries its identity and its provenance, not only the main
readings (docs/formats.md#identity-and-conditions, #provenance): a triad's readings name their
thermal programme (``# thermal_readings: thermal.csv``), and the calibration reads both.

- A thermal.csv of another instrument (its ``# serial:`` differs from the readings') is refused
  with one line naming thermal.csv (exit 2, no certificate), also without a laboratory file;
  with ``[identity] on_mismatch = "proceed"`` it is a flagged identity finding in results.json.
- Readings stripped of the virtual bench's lines, beside a thermal.csv that still names the
  bench, are marked virtual (results.json's provenance, the certificate's text); both files
  stripped give no mark (the check can fail).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from gonio.pipeline.identity import MISMATCH_CODE
from tests.own_readings import own_text
from tests.test_provenance import LAB_SERIAL, lab_file

ROOT = Path(__file__).resolve().parent.parent


def gonio(*args, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "gonio", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=900)


@pytest.fixture(scope="module")
def triad(shared_simulation) -> Path:
    """What ``gonio simulate --spec triad-alignment --seed 3`` writes (the session's shared
    set: read only, :func:`copy_of` before any change)."""
    return shared_simulation("triad-alignment", None, 3)


def copy_of(src: Path, dst: Path, *, readings=None, thermal=None) -> Path:
    """The simulated set in ``dst``, readings.csv / thermal.csv text passed through the given
    functions."""
    dst.mkdir()
    for name, change in (("readings.csv", readings), ("thermal.csv", thermal)):
        text = (src / name).read_text(encoding="utf-8")
        (dst / name).write_text(change(text) if change else text, encoding="utf-8")
    return dst / "readings.csv"


def other_serial(text: str) -> str:
    assert "# serial: TRIAD-0001\n" in text
    return text.replace("# serial: TRIAD-0001\n", "# serial: TRIAD-0999\n", 1)


def test_a_thermal_file_of_another_instrument_is_refused(triad, tmp_path):
    rd = copy_of(triad, tmp_path / "in", thermal=other_serial)
    r = gonio("calibrate", rd, "--out", tmp_path / "out", cwd=tmp_path)
    assert r.returncode == 2, r.stdout + r.stderr
    assert "Traceback" not in r.stderr
    line = r.stderr.strip().splitlines()[-1]
    assert "thermal.csv" in line and "TRIAD-0999" in line and "TRIAD-0001" in line, line
    assert not (tmp_path / "out" / "certificate.pdf").exists()


def test_proceeding_states_the_thermal_files_contradiction(triad, tmp_path):
    rd = copy_of(triad, tmp_path / "in", thermal=other_serial)
    lab = lab_file(tmp_path, identity='on_mismatch = "proceed"')
    lab.write_text(lab.read_text(encoding="utf-8").replace(LAB_SERIAL, "TRIAD-0001"),
                   encoding="utf-8")
    r = gonio("calibrate", rd, "--out", tmp_path / "out", "--lab", lab, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    res = json.loads((tmp_path / "out" / "results.json").read_text(encoding="utf-8"))
    found = [f["message"] for f in res["findings"] if f["code"] == MISMATCH_CODE]
    # thermal.csv against the readings (the laboratory file says what the readings say)
    assert len(found) == 1 and "thermal.csv says 'TRIAD-0999'" in found[0], found
    assert "TRIAD-0999" in (tmp_path / "out" / "summary.txt").read_text(encoding="utf-8")


@pytest.mark.parametrize("strip_thermal", [False, True])
def test_a_virtual_thermal_file_marks_the_calibration_virtual(triad, tmp_path, strip_thermal):
    rd = copy_of(triad, tmp_path / "in", readings=own_text,
                 thermal=own_text if strip_thermal else None)
    r = gonio("calibrate", rd, "--out", tmp_path / "out", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    res = json.loads((tmp_path / "out" / "results.json").read_text(encoding="utf-8"))
    prov = res["provenance"]
    summary = (tmp_path / "out" / "summary.txt").read_text(encoding="utf-8")
    if strip_thermal:
        assert prov["virtual"] is False and prov["evidence"] == [], prov
        assert "virtual" not in summary.lower()
    else:
        assert prov["virtual"] is True, prov
        assert "thermal.csv:bench" in prov["evidence"] and prov["seed"] == "3", prov
        assert "virtual" in summary.lower()
        if shutil.which("pdftotext"):
            text = subprocess.run(["pdftotext", str(tmp_path / "out" / "certificate.pdf"), "-"],
                                  capture_output=True, text=True).stdout
            assert "virtual" in text.lower()
