"""A readings file opened and saved again by a spreadsheet (Excel's "CSV UTF-8"): a
byte-order mark, CRLF line ends, every row padded with empty cells to the widest row (so
each ``#`` line ends in commas), numbers in "General" format (15 significant digits,
trailing zeros dropped: ``60.0`` → ``60``). Such a file is the same measurement: it
calibrates, its metadata read as written before the re-save (no identity contradiction, no
unknown specification), and its numbers agree with the original file's
(:func:`gonio.formats.metadata.comment_body`; docs/formats.md#metadata)."""

from __future__ import annotations

import csv
import io
import json
import re

import pytest

from gonio.formats.metadata import comment_body, is_comment
from gonio.pipeline.coverage import reduced_protocol
from gonio.pipeline.dispatch import calibrate as calibrate_file
from gonio.pipeline.dispatch import simulate as simulate_files

SPECS = ("ogam-draft", "jjf1535-2015", "iec62047-20", "triad-alignment")
_NUM = re.compile(r"^-?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


def _general(cell: str) -> str:
    """A number cell as a spreadsheet's General format writes it."""
    if not _NUM.match(cell):
        return cell
    s = f"{float(cell):.15g}"
    if "e" in s:
        m, e = s.split("e")
        s = f"{m}E{'+' if int(e) >= 0 else '-'}{abs(int(e)):02d}"
    return s


def resave(src, dst) -> None:
    """``src`` as a spreadsheet writes it back: cells split at commas (a ``#`` line too),
    numbers re-written, rows padded to the widest, BOM and CRLF."""
    rows = [next(csv.reader([ln])) if ln else [] for ln in
            src.read_text(encoding="utf-8").splitlines()]
    width = max(len(r) for r in rows)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\r\n")
    for r in rows:
        w.writerow([_general(c) for c in r] + [""] * (width - len(r)))
    dst.write_bytes(b"\xef\xbb\xbf" + buf.getvalue().encode("utf-8"))


def test_a_padded_metadata_line_reads_as_written():
    assert comment_body("# serial: RLG-0001,,,,,") == "serial: RLG-0001"
    assert comment_body('"# table: a, b",,') == "table: a, b"
    assert comment_body("\ufeff# spec: jjf1535-2015,,,\r") == "spec: jjf1535-2015"
    assert is_comment('"# table: a, b",,') and not is_comment("time_s,#")


@pytest.fixture(scope="module", params=SPECS)
def original(request, tmp_path_factory):
    spec = request.param
    tmp = tmp_path_factory.mktemp(spec.replace("-", "_"))
    changes = {"arw" if spec.startswith("jjf") else "noise": {"samples": 3000}} \
        if spec in ("jjf1535-2015", "iec62047-20") else None
    try:
        proto = reduced_protocol(spec, tmp / "p.toml", changes)
    except Exception:                       # a specification without a study programme
        proto = None
    files = simulate_files(spec, tmp / "sim", protocol=str(proto) if proto else None, seed=5)
    calibrate_file(files["readings"], tmp / "cal", spec_key=spec,
                                protocol=str(proto) if proto else None)
    return spec, proto, files["readings"], tmp, json.loads((tmp / "cal" / "results.json")
                                                          .read_text("utf-8"))


def test_a_re_saved_file_calibrates_to_the_same_numbers(original):
    spec, proto, readings, tmp, before = original
    xl = tmp / "resaved" / readings.name
    xl.parent.mkdir()
    for f in readings.parent.iterdir():     # a readings file may name companion files
        if f.is_file() and f.name != readings.name:
            (xl.parent / f.name).write_bytes(f.read_bytes())
    resave(readings, xl)
    assert xl.read_bytes() != readings.read_bytes()
    assert xl.read_text("utf-8-sig").splitlines()[0].endswith(",")   # a padded # line
    calibrate_file(xl, tmp / "cal-resaved", spec_key=spec,
                   protocol=str(proto) if proto else None)
    after = json.loads((tmp / "cal-resaved" / "results.json").read_text("utf-8"))
    assert after["spec"] == before["spec"]
    assert after["provenance"]["virtual"] is True
    items_b = {k: v for k, v in before["items"].items()}
    items_a = {k: v for k, v in after["items"].items()}
    assert items_a.keys() == items_b.keys()
    for key, b in items_b.items():
        a = items_a[key]
        assert a.get("measured") == b.get("measured"), key
        if isinstance(b.get("value"), float) and isinstance(a.get("value"), float):
            assert a["value"] == pytest.approx(b["value"], rel=1e-6, abs=1e-9), key
