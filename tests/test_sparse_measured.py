"""A chamber temperature logged on every 10th row of the JJF temperature tests (blank between,
as a slow logger writes, the logged rows not at the segments' starts) gives K_t and B_t
measured, equal to those of the same file logged on every row (the check that does not come
from the filling itself), with one ``measured-sparse`` finding per test instead of one per
row (docs/formats.md#rate-gyro-columns)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

PINS = Path(__file__).resolve().parent / "data" / "pins"
TESTS = ("sf_temperature", "bias_temperature")
ITEMS = ("sf_temperature_sensitivity", "bias_temperature_sensitivity")


def gonio(*args, cwd: Path) -> None:
    r = subprocess.run([sys.executable, "-m", "gonio", *map(str, args)], cwd=cwd,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def sparse_copy(src: Path, dst: Path, every: int = 10, offset: int = 5) -> None:
    """``src`` with temperature_c blank except on every ``every``-th row of the temperature
    tests (counting from ``offset``)."""
    lines = src.read_text(encoding="utf-8").splitlines(keepends=True)
    out, cols, seen = [], None, {}
    for line in lines:
        if line.startswith("#") or cols is None:
            if not line.startswith("#"):
                cols = line.rstrip("\n").split(",")
            out.append(line)
            continue
        f = line.rstrip("\n").split(",")
        test = f[cols.index("test")]
        if test in TESTS:
            seen[test] = seen.get(test, -1) + 1
            if seen[test] % every != offset:
                f[cols.index("temperature_c")] = ""
        out.append(",".join(f) + "\n")
    dst.write_text("".join(out), encoding="utf-8")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    work = tmp_path_factory.mktemp("sparse")
    proto = PINS / "jjf1535-2015-small.toml"
    gonio("simulate", "--spec", "jjf1535-2015", "--protocol", proto, "--seed", 5,
          "--out", work / "sim", cwd=work)
    sparse_copy(work / "sim" / "readings.csv", work / "sparse.csv")
    out = {}
    for name, readings in (("full", work / "sim" / "readings.csv"),
                           ("sparse", work / "sparse.csv")):
        gonio("calibrate", readings, "--protocol", proto, "--out", work / name, cwd=work)
        out[name] = json.loads((work / name / "results.json").read_text(encoding="utf-8"))
    return out


def test_sparse_temperature_gives_the_items_measured(runs):
    for key in ITEMS:
        full, sparse = runs["full"]["items"][key], runs["sparse"]["items"][key]
        assert full["measured"] and sparse["measured"], sparse["reason"]
        assert sparse["value"] == pytest.approx(full["value"], rel=1e-12)
        assert sparse["uncertainty"]["U"] == pytest.approx(full["uncertainty"]["U"], rel=1e-12)


def test_one_finding_per_test_not_per_row(runs):
    found = [f for f in runs["sparse"]["findings"] if f["column"] == "temperature_c"]
    assert sorted(f["test"] for f in found) == sorted(TESTS), found
    assert all(f["code"] == "measured-sparse" and f["action"] == "flagged" for f in found)
    assert all("1 row in 10" in f["message"] for f in found)
    assert not [f for f in runs["full"]["findings"] if f["column"] == "temperature_c"]
