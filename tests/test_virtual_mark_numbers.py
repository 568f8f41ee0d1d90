"""The virtual marking changes no number: one simulated readings file calibrated as simulated
and with its ``# bench:``/``# seed:``/``# generator:`` lines deleted (the values' watermark
still marks it virtual, docs/formats.md#watermark) gives the same certified numbers, digit
for digit, for every specification; only the virtual notice's wording differs. (That the
mark moves no measured value, so no number differs from the bench's unmarked readings
either: tests/test_watermark.py::test_mark_moves_no_measured_value.)"""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import pytest

from gonio.cli import main

ROOT = Path(__file__).resolve().parents[1]
PINS = ROOT / "tests" / "data" / "pins"

#: specification → the extra ``gonio simulate``/``gonio calibrate`` arguments: the small
#: programmes of the pins (the built-in ones cost minutes each)
SPECS = {"ogam-draft": ["--protocol", str(PINS / "ogam-draft-small.toml")],
         "jjf1535-2015": ["--protocol", str(PINS / "jjf1535-2015-small.toml")],
         "iec62047-20": ["--protocol", str(PINS / "iec62047-20-small.toml")],
         "triad-alignment": []}
BENCH_LINES = re.compile(r"^# (bench|seed|generator):.*\n", re.M)


def _strip(src: Path, dst: Path) -> None:
    dst.mkdir(parents=True)
    for f in src.iterdir():
        if f.suffix == ".csv":
            (dst / f.name).write_text(BENCH_LINES.sub("", f.read_text()))


def _numbers(out: Path) -> dict:
    res = json.loads((out / "results.json").read_text())
    keep = ("value", "measured", "upper_bound")
    return {k: ({f: it.get(f) for f in keep},
                {f: (it.get("uncertainty") or {}).get(f)
                 for f in ("U", "k", "u_c", "nu_eff", "interval", "coverage_probability")})
            for k, it in res["items"].items()}


@pytest.mark.slow
@pytest.mark.parametrize("spec", list(SPECS))
def test_deleting_the_bench_lines_changes_no_number(spec, tmp_path, capsys):
    sim = tmp_path / "sim"
    assert main(["simulate", "--spec", spec, "--seed", "5", "--out", str(sim),
                 *SPECS[spec]]) == 0
    _strip(sim, tmp_path / "lab_in")
    assert "# seed:" in (sim / "readings.csv").read_text()
    assert "# seed:" not in (tmp_path / "lab_in" / "readings.csv").read_text()
    extra = SPECS[spec]
    for name, src in (("virt", sim), ("lab", tmp_path / "lab_in")):
        assert main(["calibrate", str(src / "readings.csv"), "--out", str(tmp_path / name),
                     *extra]) == 0
    capsys.readouterr()
    virt, lab = tmp_path / "virt", tmp_path / "lab"
    # both are marked virtual (the values' watermark), by other evidence
    pv = json.loads((virt / "results.json").read_text())["provenance"]
    pl = json.loads((lab / "results.json").read_text())["provenance"]
    assert pv["virtual"] and pl["virtual"] and pv["seed"] and not pl["seed"]
    # every item's numbers, at full precision
    a, b = _numbers(virt), _numbers(lab)
    assert a.keys() == b.keys() and len(a) > 3
    for k in a:
        assert a[k] == b[k], k
    # what is printed: tables/items.csv byte for byte, summary.txt but the notice
    assert (virt / "tables" / "items.csv").read_bytes() == \
        (lab / "tables" / "items.csv").read_bytes()
    # (a finding's file lines move up by the deleted lines: "line N" compared as such)
    sa, sb = ([re.sub(r"\blines? \d+(, \d+)*", "line N", x) for x in
               (d / "summary.txt").read_text().splitlines()] for d in (virt, lab))
    notice = [i for i, (x, y) in enumerate(zip(sa, sb)) if x != y]
    assert len(sa) == len(sb) and notice == [0] and "VIRTUAL" in sa[0] and "VIRTUAL" in sb[0], \
        [(sa[i], sb[i]) for i in notice]
    rows = list(csv.DictReader((virt / "tables" / "items.csv").open()))
    assert any(r["value"] for r in rows)
