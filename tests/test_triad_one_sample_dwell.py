"""Thermal programmes whose static soak dwells hold one sample (n_samples = 1), from the
outside: one sample gives no standard deviation, so the ARW values are not measured (with
the reason, and a flagged finding naming the dwells' lines) while every other item is
certified as from the same file with its full dwells; n_samples = 2 (ν = 1 per dwell) is
still an ARW with its χ² line. A one-sample file stopped ``gonio calibrate`` with an
internal error before."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pytest

from gonio.cli import main
from gonio.specs import get


@pytest.fixture(scope="module")
def triad_files(tmp_path_factory):
    out = tmp_path_factory.mktemp("triad_one_sample") / "sim"
    assert main(["simulate", "--spec", "triad-alignment", "--seed", "5", "--out",
                 str(out)]) == 0
    return out


def with_static_n(src: Path, dst: Path, n: int) -> tuple[Path, list[int], list[int]]:
    """The session copied to ``dst`` with n_samples = ``n`` on every static soak dwell of
    thermal.csv (rate 0, sd kept; duration_s n/sample_rate_hz, as the count says); returns (thermal file, the dwells' 1-based lines, their
    original n_samples)."""
    shutil.copytree(src, dst)
    f = dst / "thermal.csv"
    lines = f.read_text().splitlines(keepends=True)
    head = next(i for i, ln in enumerate(lines) if ln.startswith("test,"))
    cols = lines[head].strip().split(",")
    rate_hz = float(next(ln for ln in lines if ln.startswith("# sample_rate_hz:")).split(":")[1])
    hit, was = [], []
    for i in range(head + 1, len(lines)):
        p = lines[i].rstrip("\n").split(",")
        if p[cols.index("phase")] == "soak" and float(p[cols.index("rate_dps")]) == 0.0:
            was.append(int(p[cols.index("n_samples")]))
            p[cols.index("n_samples")] = str(n)
            p[cols.index("duration_s")] = repr(n / rate_hz)
            lines[i] = ",".join(p) + "\n"
            hit.append(i + 1)
    f.write_text("".join(lines))
    return f, hit, was


def cli(folder: Path, out: Path, capsys) -> tuple[int, str, dict]:
    capsys.readouterr()
    rc = main(["calibrate", str(folder / "readings.csv"), "--thermal",
               str(folder / "thermal.csv"), "--out", str(out)])
    err = capsys.readouterr().err
    res = json.loads((out / "results.json").read_text()) if rc == 0 else {}
    return rc, err, res


def test_one_sample_dwells_leave_arw_not_measured_and_the_rest_as_before(
        triad_files, tmp_path, capsys):
    f, hit, _ = with_static_n(triad_files, tmp_path / "n1", 1)
    assert len(hit) >= 3
    rc, err, res = cli(tmp_path / "n1", tmp_path / "o1", capsys)
    assert rc == 0 and "Traceback" not in err and "internal error" not in err, err
    items = res["items"]
    arw = {k: v for k, v in items.items() if k.startswith("ARW_")}
    assert arw
    for v in arw.values():
        assert v["measured"] is False and v["value"] is None
        assert "one sample gives no standard deviation" in v["reason"]
    found = [x for x in res["findings"] if x["code"] == "one-sample-dwell"]
    assert len(found) == 1 and found[0]["action"] == "flagged"
    assert found[0]["line"] == hit[0] and found[0]["column"] == "n_samples"
    assert ", ".join(map(str, hit)) in found[0]["message"]
    # every other item as from the untouched file (same programme, full dwells)
    base = get("triad-alignment").calibrate(triad_files / "readings.csv",
                                            thermal=triad_files / "thermal.csv").to_json()
    assert base["items"].keys() == items.keys()
    for k, v in base["items"].items():
        if k.startswith("ARW_"):
            assert v["measured"] is True
            continue
        assert items[k]["measured"] == v["measured"], k
        if v["measured"]:
            assert items[k]["value"] == v["value"], k
            ua, ub = items[k].get("uncertainty"), v.get("uncertainty")
            assert (ua is None) == (ub is None), k
            if ub is not None:
                assert ua["u_c"] == ub["u_c"], k


def test_two_sample_dwells_still_give_arw_with_nu_one(triad_files, tmp_path, capsys):
    """n_samples = 2: each dwell's χ² has ν = 1, so the χ² line is the full dwells' times
    √((n₀ − 1)/1) (u(ARW_i) = ARW_i/√(2ν_i), JCGM 100 E.4.3; the same sd, the same fit)."""
    _, hit, was = with_static_n(triad_files, tmp_path / "n2", 2)
    assert len(set(was)) == 1 and was[0] > 2
    rc, err, res = cli(tmp_path / "n2", tmp_path / "o2", capsys)
    assert rc == 0 and "Traceback" not in err, err
    assert not [x for x in res["findings"] if x["code"] == "one-sample-dwell"]
    base = get("triad-alignment").calibrate(triad_files / "readings.csv",
                                            thermal=triad_files / "thermal.csv").to_json()
    arw = sorted(k for k in res["items"] if k.startswith("ARW_"))
    assert arw
    for k in arw:
        it = res["items"][k]
        assert it["measured"] is True and it["value"] > 0
        line = {c["symbol"]: c for c in it["uncertainty"]["components"]}[f"{k}_chi2"]
        ref = {c["symbol"]: c for c in base["items"][k]["uncertainty"]["components"]}[f"{k}_chi2"]
        assert line["u"] == pytest.approx(ref["u"] * math.sqrt(was[0] - 1.0), rel=1e-9)
        assert line["dof"] == pytest.approx(ref["dof"] / (was[0] - 1.0), rel=1e-9)
