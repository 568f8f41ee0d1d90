"""``gonio demo --lab FILE`` compares the laboratory file's instrument with the simulated
readings as calibrate does, and states a contradiction (never silently puts another
instrument's name on the bench's numbers): exit 0, flagged ``identity-mismatch`` findings in
results.json, summary.txt and the certificate. A laboratory file naming the bench's own
instrument gives none (docs/formats.md, identity)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gonio.cli import main

ROOT = Path(__file__).resolve().parents[1]


def lab_file(path: Path, serial: str, manufacturer: str, model: str | None = None) -> Path:
    """The example laboratory file without limits or decision rule, naming ``serial``."""
    out, skip = [], False
    for line in (ROOT / "protocols" / "lab-example.toml").read_text().splitlines():
        if line.startswith("["):
            skip = "specification_limits" in line or "decision_rule" in line
        if not skip:
            out.append(line)
    text = "\n".join(out) + "\n"
    text = text.replace('serial = "RLG-0001"', f'serial = "{serial}"')
    text = text.replace('manufacturer = "gonio virtual bench"', f'manufacturer = "{manufacturer}"')
    if model is None:
        text = text.replace('model = "RLG-GM-1"\n', "")
    path.write_text(text)
    return path


def mismatches(out: Path) -> list[str]:
    res = json.loads((out / "results.json").read_text(encoding="utf-8"))
    return [f["message"] for f in res["findings"] if f["code"] == "identity-mismatch"]


@pytest.mark.parametrize("spec", ["jjf1535-2015", "triad-alignment"])
def test_demo_states_the_laboratory_files_other_instrument(spec, tmp_path):
    lab = lab_file(tmp_path / "lab.toml", "REAL-4242", "ACME")
    out = tmp_path / "o"
    assert main(["demo", "--spec", spec, "--lab", str(lab), "--out", str(out)]) == 0
    found = mismatches(out)
    assert any("REAL-4242" in m for m in found), found
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    assert "serial: REAL-4242 [CONTRADICTED" in summary
    assert "REAL-4242" in (out / "certificate.html").read_text(encoding="utf-8")
    assert summary.startswith("VIRTUAL BENCH")


def test_demo_with_the_benchs_own_instrument_states_nothing(tmp_path):
    lab = lab_file(tmp_path / "lab.toml", "MEMS-0610-001", "gonio virtual bench")
    out = tmp_path / "o"
    assert main(["demo", "--spec", "jjf1535-2015", "--lab", str(lab), "--out", str(out)]) == 0
    assert mismatches(out) == []
