"""The virtual bench's readings keep their mark through what a laboratory's tools do to a
file without changing a value: a metadata line indented or quoted (as the readers still take
it), columns put in another order, a column added (a note), every time shifted by an odd
number of nanoseconds (times re-zeroed at a marked reading); for all four specifications and
the optical stream, and end to end on the certificate. Readings not written by the bench,
in the bench's columns rearranged, are flagged at most at the stated level
(scipy.stats.binomtest). gonio.formats.watermark, docs/formats.md#watermark."""

from __future__ import annotations

import csv
import io
import json
import subprocess
import sys
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import binomtest

from gonio.cli import main
from gonio.formats.watermark import BENCH_HEADERS, bench_order, detect, detect_text

from tests.test_watermark import PINS, RUNS


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """{spec: folder} of one simulation per specification (seed 6), the optical one with
    its CSV stream."""
    out = {}
    for spec, proto in RUNS:
        d = tmp_path_factory.mktemp(spec)
        p = [] if proto is None else ["--protocol", str(PINS / proto)]
        extra = ["--stream", "--stream-format", "csv"] if spec == "ogam-draft" else []
        r = subprocess.run([sys.executable, "-m", "gonio", "simulate", "--spec", spec, *p,
                            "--seed", "6", *extra, "--out", str(d / "sim")],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        out[spec] = d / "sim"
    return out


def laundered(text: str) -> str:
    """The readings with every metadata line that names the virtual bench deleted (its
    bench, seed, noise and generator, and every line saying "virtual"): only the mark in the
    values is left to tell."""
    keep = []
    for line in text.splitlines(keepends=True):
        key = line.lstrip("# ").split(":", 1)[0].strip().lower()
        if line.startswith("#") and (key in ("bench", "seed", "noise", "generator")
                                     or "virtual" in line.lower()):
            continue
        keep.append(line)
    return "".join(keep)


def _table(text: str) -> tuple[list[str], list[list[str]]]:
    """(metadata lines, rows with the header first) of a CSV text."""
    lines = text.splitlines()
    meta = [x for x in lines if x.startswith("#")]
    rows = list(csv.reader(io.StringIO("\n".join(x for x in lines if not x.startswith("#")))))
    return meta, [r for r in rows if r]


def _text(meta: list[str], rows: list[list[str]]) -> str:
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerows(rows)
    return "".join(m + "\n" for m in meta) + out.getvalue()


def rearranged(text: str, how: str) -> str:
    """The same readings as a laboratory's tool might leave them (``how``)."""
    meta, rows = _table(text)
    if how == "indented":       # the first metadata line indented, the rest as written
        return _text([" " + meta[0]] + meta[1:], rows)
    if how == "quoted":         # every metadata line quoted as one cell (a spreadsheet)
        return _text(['"' + m.replace('"', '""') + '"' for m in meta], rows)
    if how == "first_last":     # the first column moved to the end
        return _text(meta, [r[1:] + r[:1] for r in rows])
    if how == "reversed":
        return _text(meta, [r[::-1] for r in rows])
    if how == "note":           # a note column added after the second
        return _text(meta, [r[:2] + (["note"] if i == 0 else ["checked"]) + r[2:]
                            for i, r in enumerate(rows)])
    if how == "odd_ns":         # every time 1 ns later (re-zeroed at an odd nanosecond)
        j = rows[0].index("time_s")
        return _text(meta, [rows[0]] + [r[:j] + [str(Decimal(r[j]) + Decimal("1e-9"))]
                                        + r[j + 1:] if r[j] else r for r in rows[1:]])
    raise ValueError(how)


HOW = ("indented", "quoted", "first_last", "reversed", "note", "odd_ns")


def _files(sim: Path) -> list[Path]:
    return sorted(sim.glob("*.csv"))


def test_every_simulated_file_is_written_in_a_bench_order(simulated):
    """BENCH_HEADERS holds every header the bench writes (the detection reads a rearranged
    file in it): each simulated file's header is one, read in its own order."""
    for spec, sim in simulated.items():
        for f in _files(sim):
            _, rows = _table(f.read_text(encoding="utf-8"))
            assert tuple(rows[0]) in BENCH_HEADERS, (spec, f.name, rows[0])
            assert bench_order(rows[0]) is None


@pytest.mark.parametrize("how", HOW)
def test_rearranged_bench_readings_keep_their_mark(simulated, how):
    for spec, sim in simulated.items():
        for f in _files(sim):
            text = laundered(f.read_text(encoding="utf-8"))    # no bench lines to go by
            got = detect_text(rearranged(text, how))
            assert got["virtual"], (spec, f.name, how, got)


def test_a_mark_half_turned_over_is_no_mark(simulated):
    """Half the times 1 ns later (every other row): the parities of half the cells turned
    over, k ≈ n/2, no mark; the two-sided test flags only a shift of every time."""
    text = laundered((simulated["jjf1535-2015"] / "readings.csv").read_text(encoding="utf-8"))
    meta, rows = _table(text)
    j = rows[0].index("time_s")
    half = [rows[0]] + [r[:j] + [str(Decimal(r[j]) + Decimal("1e-9"))] + r[j + 1:]
                        if i % 2 and r[j] else r for i, r in enumerate(rows[1:])]
    got = detect_text(_text(meta, half))
    assert not got["virtual"] and got["cells"] > 100, got


def test_real_looking_readings_rearranged_are_not_flagged():
    """400 real-looking optical files (times on a millisecond clock, counts of a real
    counter) with a note column and their columns reversed: none flagged; each test's p is
    scipy's two-sided binomial p, and the file's the smallest × the number of tests."""
    rng = np.random.default_rng(2031)
    small = 0
    header = ["test", "series", "round", "rate_dps", "orientation", "time_s", "table_deg",
              "gyro_counts", "gyro_deg"]
    for _ in range(400):
        n = int(rng.integers(30, 300))
        times = np.cumsum(rng.integers(500, 20000, n)) / 1000.0
        rows = [header + ["note"]] + [
            ["angle_deviation", "1", str(i + 1), "60.0", "up", repr(float(times[i])),
             str(i * 30.0), str(int(rng.integers(0, 10**8))), "", "ok"] for i in range(n)]
        got = detect_text(_text([], [r[::-1] for r in rows]))
        assert not got["virtual"], got
        assert [t["order"] for t in got["tests"]] == ["file", "bench"]
        refs = [binomtest(t["matching"], t["cells"], 0.5).pvalue for t in got["tests"]]
        for t, ref in zip(got["tests"], refs):
            assert t["p_value"] == pytest.approx(ref, rel=1e-9)
        assert got["p_value"] == pytest.approx(min(1.0, 2 * min(refs)), rel=1e-9)
        small += got["p_value"] <= 0.05
    ci = binomtest(small, 400, 0.05).proportion_ci(0.999)
    assert ci.low <= 0.05 <= ci.high or small / 400 < 0.05, small


@pytest.mark.parametrize("spec,how", [("jjf1535-2015", "indented"),
                                      ("ogam-draft", "first_last"),
                                      ("iec62047-20", "odd_ns"),
                                      ("triad-alignment", "quoted")])
def test_calibrate_marks_rearranged_readings_virtual(simulated, tmp_path, spec, how):
    """End to end: the rearranged readings, their bench lines deleted, calibrate VIRTUAL
    (results.json's provenance by the watermark, summary.txt's banner)."""
    sim = simulated[spec]
    text = laundered((sim / "readings.csv").read_text(encoding="utf-8"))
    src = tmp_path / "readings.csv"
    src.write_text(rearranged(text, how), encoding="utf-8")
    for extra in ("thermal.csv",):
        if (sim / extra).is_file():
            (tmp_path / extra).write_text(laundered((sim / extra).read_text(encoding="utf-8")),
                                          encoding="utf-8")
    proto = dict(RUNS)[spec]
    argv = ["calibrate", str(src), "--spec", spec, "--out", str(tmp_path / "out")]
    if proto is not None:
        argv += ["--protocol", str(PINS / proto)]
    assert main(argv) == 0
    res = json.loads((tmp_path / "out" / "results.json").read_text(encoding="utf-8"))
    assert res["provenance"]["virtual"] and "watermark" in res["provenance"]["evidence"], \
        res["provenance"]
    summary = (tmp_path / "out" / "summary.txt").read_text(encoding="utf-8")
    assert "VIRTUAL BENCH EXAMPLE - NOT A CALIBRATION CERTIFICATE" in summary


def test_detect_reads_a_rearranged_stream(simulated, tmp_path):
    """The optical CSV stream, its columns reversed and a column added: still the bench's."""
    stream = simulated["ogam-draft"] / "stream.csv"
    text = laundered(stream.read_text(encoding="utf-8"))
    out = tmp_path / "s.csv"
    out.write_text(rearranged(rearranged(text, "reversed"), "note"), encoding="utf-8")
    assert detect(out)["virtual"]
