"""A demo or a simulation into a folder holding a laboratory's own readings.csv is refused
before the virtual bench runs (it was refused only at the swap, after the whole simulation
and calibration), with the swap's message, exit 2, and the file unchanged — for every
specification (``Specification.simulated_files``)."""

from __future__ import annotations

import importlib

import pytest

from gonio.cli import main
from gonio.specs import available

#: where each specification's virtual bench starts (replaced by a function that fails)
BENCH_ENTRY = {
    "ogam-draft": ("gonio.specs.ogam_draft.outputs", "run_session"),
    "triad-alignment": ("gonio.specs.triad_alignment.simulate", "simulate"),
    "jjf1535-2015": ("gonio.specs._rate_family.simulate", "load_rate_bench"),
    "iec62047-20": ("gonio.specs._rate_family.simulate", "load_rate_bench"),
}
SIMULATE_ENTRY = {**BENCH_ENTRY,
                  "ogam-draft": ("gonio.specs.ogam_draft.simulate", "load_protocol")}


def test_every_built_in_specification_names_what_it_simulates():
    assert set(BENCH_ENTRY) == set(available())
    for key, spec in available().items():
        assert "readings.csv" in spec.simulated_files, key


def _lab_folder(tmp_path):
    lab = tmp_path / "lab"
    lab.mkdir()
    (lab / "readings.csv").write_text("a laboratory's real data\n", encoding="utf-8")
    return lab


def _refused(lab, argv, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "would replace a file gonio did not write, readings.csv" in err
    assert (lab / "readings.csv").read_text(encoding="utf-8") == "a laboratory's real data\n"
    assert sorted(p.name for p in lab.iterdir()) == ["readings.csv"]


def _never(*_a, **_k):
    raise AssertionError("the bench ran before the refusal")


@pytest.mark.parametrize("command,spec", [(c, s) for c in ("demo", "simulate")
                                          for s in sorted(BENCH_ENTRY)])
def test_refused_before_the_bench_runs(command, spec, tmp_path, monkeypatch, capsys):
    module, name = (BENCH_ENTRY if command == "demo" else SIMULATE_ENTRY)[spec]
    monkeypatch.setattr(importlib.import_module(module), name, _never)
    lab = _lab_folder(tmp_path)
    _refused(lab, [command, "--spec", spec, "--out", str(lab)], capsys)
