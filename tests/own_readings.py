"""A laboratory's own readings made from the virtual bench's, for tests of the virtual-bench
mark (docs/formats.md#provenance): every metadata line the bench writes that says where the
readings come from (bench, seed, generator, noise) deleted, and its names of the instrument,
manufacturer, table and operator ("… (virtual)", "gonio virtual bench") replaced by a
laboratory's."""

from __future__ import annotations

import re

#: the metadata keys only the virtual bench writes
BENCH_KEYS = ("bench", "seed", "generator", "noise")
#: the keys whose value names the virtual bench, and the laboratory's name put in its place
NAME_KEYS = ("instrument", "manufacturer", "model", "table", "operator")
OWN_NAME = "Laboratory unit 7"


def own_metadata(md: dict) -> dict:
    """``md`` (a results.json's metadata) as a laboratory's own readings would state it."""
    return {k: (OWN_NAME if k in NAME_KEYS and re.search(r"(?i)\bvirtual\b", str(v)) else v)
            for k, v in md.items() if k not in BENCH_KEYS}


def own_text(text: str, unmark: bool = True) -> str:
    """A readings file's text as a laboratory's own file (the metadata lines above the
    header only); ``unmark``: its measured values also without the bench's watermark
    (:func:`unmarked`), as a laboratory's own instrument would have recorded them."""
    out, head = [], True
    for line in text.splitlines(keepends=True):
        m = re.match(r"#\s*([A-Za-z_]\w*)\s*:", line) if head else None
        head = head and line.startswith("#")
        if m and m.group(1).lower() in BENCH_KEYS:
            continue
        if m and m.group(1).lower() in NAME_KEYS and re.search(r"(?i)\bvirtual\b", line):
            line = f"# {m.group(1)}: {OWN_NAME}\n"
        out.append(line)
    return unmarked("".join(out)) if unmark else "".join(out)


def unmarked(text: str) -> str:
    """``text`` as a laboratory's own recording of the same values, without the bench's
    watermark (gonio.formats.watermark): every time written at the millisecond (a
    laboratory's clock; at the microsecond in a file sampled faster, where two successive
    times would read alike at the millisecond: a rate specification's angular-vibration run
    at about 1 kHz), the measured values as they are; in a file marked in its measured
    columns (no times) the last written digit of every other measured cell (by an unkeyed
    CRC of its line) moved by one (9 → 8, else up), readings of the same values at the same
    resolution with parities of their own."""
    import zlib

    from gonio.formats.watermark import TIME_COLUMN, marked_columns
    out, header, cols = [], None, {}
    digits = _clock_decimals(text)
    for line in text.splitlines(keepends=True):
        if line.startswith("#") or not line.strip() or '"' in line:
            out.append(line)
            continue
        body = line.rstrip("\r\n")
        cells = body.split(",")
        if header is None:
            header = cells
            cols = marked_columns(header)
            out.append(line)
            continue
        for j, name in cols.items():
            if j >= len(cells) or not re.fullmatch(r"-?\d+(\.\d+)?", cells[j]):
                continue
            if name == TIME_COLUMN:
                cells[j] = f"{float(cells[j]):.{digits}f}"
            elif zlib.crc32(f"{j}{body}".encode()) & 1:
                d = int(cells[j][-1])
                cells[j] = cells[j][:-1] + str(8 if d == 9 else d + 1)
        out.append(",".join(cells) + line[len(body):])
    return "".join(out)


def _clock_decimals(text: str) -> int:
    """3 (the millisecond) unless two successive distinct times of ``text``'s ``time_s``
    column would read alike at it; then 6 (the microsecond)."""
    from gonio.formats.watermark import TIME_COLUMN
    j, last = None, None
    for line in text.splitlines():
        if line.startswith("#") or not line.strip() or '"' in line:
            continue
        cells = line.split(",")
        if j is None:
            if TIME_COLUMN not in cells:
                return 3
            j = cells.index(TIME_COLUMN)
            continue
        if j >= len(cells) or not re.fullmatch(r"-?\d+(\.\d+)?", cells[j]):
            continue
        t = float(cells[j])
        if last is not None and t != last and round(t, 3) == round(last, 3):
            return 6
        last = t
    return 3


def resaved(text: str) -> str:
    """``text`` as a spreadsheet re-saves it in its General format: every numeric cell of a
    data row (not the ``#`` lines, not the header) written as ``'%.15g' % float(cell)``
    (``60.0`` → ``60``, ``2501.70`` → ``2501.7``, 17 significant digits → 15)."""
    num = re.compile(r"^[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?$")
    out, header = [], False
    for line in text.splitlines(keepends=True):
        if line.startswith("#") or not line.strip():
            out.append(line)
            continue
        body = line.rstrip("\r\n")
        if not header:
            header = True
            out.append(line)
            continue
        cells = [("%.15g" % float(c)) if num.match(c) else c for c in body.split(",")]
        out.append(",".join(cells) + line[len(body):])
    return "".join(out)
