"""A demo into a folder holding a laboratory's own readings.csv is refused before the virtual
bench runs (it was refused only at the swap, after the whole simulation and calibration),
with the swap's message, exit 2, and the file unchanged."""

from __future__ import annotations

import pytest

from gonio.cli import main


@pytest.mark.parametrize("spec,module,name", [
    ("ogam-draft", "gonio.specs.ogam_draft.outputs", "run_session"),
    ("triad-alignment", "gonio.specs.triad_alignment.simulate", "simulate"),
])
def test_refused_before_the_bench_runs(spec, module, name, tmp_path, monkeypatch, capsys):
    import importlib

    def never(*_a, **_k):
        raise AssertionError("the bench ran before the refusal")

    monkeypatch.setattr(importlib.import_module(module), name, never)
    lab = tmp_path / "lab"
    lab.mkdir()
    (lab / "readings.csv").write_text("a laboratory's real data\n", encoding="utf-8")
    assert main(["demo", "--spec", spec, "--out", str(lab)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "would replace a file gonio did not write, readings.csv" in err
    assert (lab / "readings.csv").read_text(encoding="utf-8") == "a laboratory's real data\n"
    assert sorted(p.name for p in lab.iterdir()) == ["readings.csv"]
