"""The test suite's once-per-session runs (tests/conftest.py: shared_run): made once, found
again under the same key, a failed make leaves nothing behind, a different key is a
different run."""

from __future__ import annotations

import uuid

import pytest


def test_made_once_and_found_again(shared_run):
    key = f"selftest-{uuid.uuid4().hex}"
    calls = []

    def make(folder):
        calls.append(folder)
        (folder / "a.txt").write_text("one", encoding="utf-8")

    first = shared_run(key, make)
    assert shared_run(key, make) == first and len(calls) == 1
    assert (first / "a.txt").read_text(encoding="utf-8") == "one"
    assert shared_run(key + "-other", make) != first and len(calls) == 2


def test_a_failed_make_is_made_again(shared_run):
    key = f"selftest-{uuid.uuid4().hex}"

    def broken(folder):
        (folder / "half.txt").write_text("half", encoding="utf-8")
        raise RuntimeError("make failed")

    with pytest.raises(RuntimeError, match="make failed"):
        shared_run(key, broken)
    made = shared_run(key, lambda folder: (folder / "whole.txt").write_text("x"))
    assert sorted(p.name for p in made.iterdir()) == ["whole.txt"]


def test_shared_demo_is_what_gonio_demo_writes(shared_demo, tmp_path):
    """The shared demo folder holds the bytes `gonio demo` writes into a folder of its own."""
    from gonio.cli import main

    shared = shared_demo("triad-alignment", seed=5)
    assert main(["demo", "--spec", "triad-alignment", "--seed", "5",
                 "--out", str(tmp_path / "own")]) == 0
    names = sorted(p.name for p in shared.iterdir() if p.is_file())
    assert names == sorted(p.name for p in (tmp_path / "own").iterdir() if p.is_file())
    for name in ("results.json", "readings.csv", "certificate.html"):
        assert (shared / name).read_bytes() == (tmp_path / "own" / name).read_bytes(), name
