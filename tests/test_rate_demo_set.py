"""``gonio demo --spec jjf1535-2015`` writes one staged output set, like the optical demo.

From the outside: the CLI into a folder, then a rerun refused without ``--force``
(the protected readings.csv), a failure injected after results.json is written
(the previous set stays, byte for byte; a fresh folder is not created), and a
``--force`` rerun that swaps in a complete new set.
"""

from __future__ import annotations

import pytest

import gonio.pipeline.dispatch as rate
from gonio.atomic import MANIFEST, read_manifest, sha256_file
from gonio.cli import main
from gonio.errors import GonioError


def tree(d):
    return {p.relative_to(d).as_posix(): sha256_file(p)
            for p in sorted(d.rglob("*")) if p.is_file()}


def complete(d):
    man = read_manifest(d)
    assert man is not None
    files = {k: v for k, v in tree(d).items() if k != MANIFEST}
    assert files == man["files"]
    assert {"readings.csv", "truth.json", "results.json", "summary.txt",
            "certificate.html", "certificate.pdf"} <= set(files)


def no_debris(parent):
    assert not [p for p in parent.rglob("*") if p.name.startswith(".gonio-")]


@pytest.fixture(scope="module")
def first_set(tmp_path_factory):
    d = tmp_path_factory.mktemp("rate") / "D"
    assert main(["demo", "--spec", "jjf1535-2015", "--out", str(d), "--seed", "3"]) == 0
    return d


def test_demo_writes_one_complete_set(first_set):
    complete(first_set)
    no_debris(first_set.parent)


def test_rerun_without_force_is_refused_like_the_optical_demo(first_set, capsys):
    prev = tree(first_set)
    capsys.readouterr()
    assert main(["demo", "--spec", "jjf1535-2015", "--out", str(first_set)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "readings.csv" in err[0] and "--force" in err[0], err
    assert tree(first_set) == prev
    # the optical demo refuses the same folder for the same reason
    assert main(["demo", "--out", str(first_set)]) == 2
    err2 = capsys.readouterr().err
    assert "readings.csv" in err2 and "--force" in err2 and "Traceback" not in err2


def test_calibrate_into_the_demo_folder_is_refused_and_deletes_nothing(first_set, capsys):
    """``gonio calibrate D/readings.csv --out D`` on a folder ``gonio demo`` wrote: refused
    before any work (the demo's truth.json and results are another command's outputs), with
    or without --force (before: exit 0, truth.json deleted)."""
    prev = tree(first_set)
    for extra in ([], ["--force"]):
        capsys.readouterr()
        assert main(["calibrate", str(first_set / "readings.csv"), "--out", str(first_set),
                     *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "gonio demo" in err[0] and "Traceback" not in err[0], err
        assert tree(first_set) == prev
    no_debris(first_set.parent)


def test_failure_after_results_leaves_previous_set(first_set, tmp_path, monkeypatch, capsys):
    prev = tree(first_set)
    import gonio.report.item_outputs as rc        # the per-item renderer (ITEM_RENDERER)
    seen = {}

    def broken(result, out, **kw):
        from gonio.atomic import active_stage
        stage = active_stage(out)
        seen["results"] = (stage / "results.json").is_file()   # results already written
        raise GonioError("certificate failed mid-way (injected)")
    monkeypatch.setattr(rc, "write_rate_certificate", broken)
    capsys.readouterr()
    assert main(["demo", "--spec", "jjf1535-2015", "--out", str(first_set), "--force",
                 "--seed", "4"]) == 2
    err = capsys.readouterr().err
    assert "injected" in err and "Traceback" not in err
    assert seen == {"results": True}
    assert tree(first_set) == prev                  # nothing of the failed run mixed in
    no_debris(first_set.parent)
    fresh = tmp_path / "fresh"            # a failure early in a fresh folder: no folder left

    def sim_fails(*a, **k):
        raise GonioError("simulation failed (injected)")
    monkeypatch.setattr(rate, "simulate", sim_fails)
    assert main(["demo", "--spec", "iec62047-20", "--out", str(fresh)]) == 2
    assert not fresh.exists()
    no_debris(tmp_path)


def test_force_rerun_swaps_in_a_new_complete_set(first_set, monkeypatch):
    before = tree(first_set)
    (first_set / "notes.txt").write_text("the operator's notes\n")
    rate.demo("jjf1535-2015", first_set, seed=5, force=True)
    after = tree(first_set)
    man = read_manifest(first_set)
    assert man["foreign_files_kept"] == ["notes.txt"]
    assert after["readings.csv"] != before["readings.csv"]        # seed 5, not 3
    assert (first_set / "notes.txt").read_text() == "the operator's notes\n"
    files = {k: v for k, v in after.items() if k not in (MANIFEST, "notes.txt")}
    assert files == man["files"]
    no_debris(first_set.parent)
