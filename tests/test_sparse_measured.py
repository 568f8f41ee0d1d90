"""A chamber temperature logged on every 10th row of the JJF temperature tests (blank between,
as a slow logger writes, the logged rows not at the segments' starts) gives K_t and B_t
measured, equal to those of the same file logged on every row (the check that does not come
from the filling itself), with one ``measured-sparse`` finding per test instead of one per
row and no planned set point named missing (a segment's set point is the value most of its
logged rows give, not the blank between them) (docs/formats.md#rate-gyro-columns)."""

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


def test_no_planned_set_point_is_missing_from_a_sparse_log(runs):
    """The blanks between a slow logger's rows are no value: every planned temperature is in
    the sparse readings, as in the full ones."""
    for name in ("full", "sparse"):
        miss = [f for f in runs[name]["findings"] if f["code"] == "programme-point-missing"]
        assert not miss, (name, miss)


def test_a_set_point_really_missing_from_a_sparse_log_is_named(tmp_path):
    """The same rule still names a planned set point the logged rows do not give: the logged
    rows of one segment say 65 °C where 70 °C is planned (the blanks around them do not
    hide it), and a segment with no logged row gives no set point at all."""
    from gonio.specs._rate_family.screening import missing_points

    nan = float("nan")
    rows = []
    for step, logged in ((0, 20.0), (1, 65.0), (2, nan)):
        for i in range(20):
            rows.append({"test": "sf_temperature", "run": 0, "step": step,
                         "temperature_c": logged if i % 10 == 5 else nan})
    import pandas as pd

    df = pd.DataFrame(rows)
    expected = {("sf_temperature", 0): [("temperature_c", 20.0), ("temperature_c", 70.0)]}
    found = missing_points(df, expected)
    assert [f.code for f in found] == ["programme-point-missing"], found
    assert "70" in found[0].message, found[0].message
    expected = {("sf_temperature", 0): [("temperature_c", 20.0), ("temperature_c", 65.0)]}
    assert missing_points(df, expected) == []
