"""Readings the virtual bench marked before the mark moved to ``time_s`` (gonio 230195c0 and
earlier marked rate and triad files in their measured columns) are still recognised as the
bench's once every metadata line naming it is deleted (gonio.formats.watermark.detect reads
both marks, each at ALPHA/2), and ``gonio calibrate`` marks such a file's results VIRTUAL.
The files (tests/data/old_marks, README there) were written by that commit's bench, not by
the code under test."""

from __future__ import annotations

import json
from decimal import Decimal
from pathlib import Path

import pytest
from scipy.stats import binom

from gonio.cli import main
from gonio.formats.provenance import file_provenance
from gonio.formats.watermark import (ALPHA, COLUMNS, detect_text, legacy_columns,
                                     marked_columns)

HERE = Path(__file__).resolve().parent
OLD = HERE / "data" / "old_marks"
FILES = ("jjf-230195c0.csv", "iec-230195c0.csv", "triad-230195c0.csv")


def _split(text: str):
    lines = text.splitlines(keepends=True)
    head = [x for x in lines if x.startswith("#")]
    data = [x for x in lines if not x.startswith("#")]
    return head, data[0], data[1:]


def _shifted(text: str, rows: int | None = None, every: int = 1) -> str:
    """The file with every measured value (the old mark's columns) moved by one unit of its
    last written decimal: each old mark's parity flipped; ``rows``: only the first rows;
    ``every``: only every ``every``-th row's values (the others as written)."""
    head, header, data = _split(text)
    names = [c.strip() for c in header.split(",")]
    cols = [j for j, n in enumerate(names) if n in COLUMNS]
    out = []
    for i, line in enumerate(data[:rows]):
        cells = line.rstrip("\n").split(",")
        for j in (j for j in cols if cells[j].strip() and i % every == 0):
            v = Decimal(cells[j])
            cells[j] = str(v + Decimal(1).scaleb(v.as_tuple().exponent))
        out.append(",".join(cells) + "\n")
    return "".join(head) + header + "".join(out)


@pytest.mark.parametrize("name", FILES)
def test_old_mark_recognised_without_metadata(name):
    text = (OLD / name).read_text(encoding="utf-8")
    assert "virtual" not in text.lower() and "# seed" not in text and "# bench" not in text
    head, header, data = _split(text)
    names = header.strip().split(",")
    assert "time_s" in names and legacy_columns(names)
    assert list(marked_columns(names).values()) == ["time_s"]      # the current mark's column
    got = detect_text(text)
    n = got["cells"]                       # every distinct measured cell matches its bit
    assert got["virtual"] and got["matching"] == n >= len(data), got
    # the reported p: the tests' level shared (Bonferroni), scipy's two-sided p × the tests
    m = len(got["tests"])
    assert got["p_value"] == pytest.approx(min(1.0, m * 2 * binom.sf(n - 1, n, 0.5)), rel=1e-9)
    assert file_provenance(OLD / name)["evidence"] == ["watermark"]
    # every value one unit off in its last digit turns every parity over: the bench's
    # values, offset (the two-sided test); every other value off carries no mark
    assert detect_text(_shifted(text))["virtual"]
    assert not detect_text(_shifted(text, every=2))["virtual"]


def test_two_marks_share_the_level():
    """21 matching cells of the old mark alone (two-sided 2·2⁻²¹ ≈ 9.5·10⁻⁷ ≤ ALPHA) do
    not decide a file that is tested in two places (the level halved); 22 (2·2⁻²² ≤
    ALPHA/2) do."""
    text = (OLD / "jjf-230195c0.csv").read_text(encoding="utf-8")
    head, header, data = _split(text)
    assert 2 * 0.5 ** 21 <= ALPHA < 4 * 0.5 ** 21 and 2 * 0.5 ** 22 <= ALPHA / 2
    cut = lambda k: "".join(head) + header + "".join(data[:k])    # noqa: E731
    assert len(detect_text(cut(21))["tests"]) == 2
    assert not detect_text(cut(21))["virtual"]
    assert detect_text(cut(22))["virtual"]


def test_calibrate_marks_an_old_marked_file_virtual(tmp_path, capsys):
    out = tmp_path / "out"
    rc = main(["calibrate", str(OLD / "jjf-230195c0.csv"), "--protocol",
               str(HERE / "data" / "pins" / "jjf1535-2015-small.toml"), "--out", str(out)])
    assert rc == 0, capsys.readouterr().err
    res = json.loads((out / "results.json").read_text(encoding="utf-8"))
    assert res["provenance"]["virtual"] and "watermark" in res["provenance"]["evidence"]
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    assert "VIRTUAL BENCH EXAMPLE - NOT A CALIBRATION CERTIFICATE" in summary
