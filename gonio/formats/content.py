"""What a readings file measured, apart from how it is written (docs/formats.md#content-digest).

Two files hold the same measurement when their data are the same, whatever their bytes:
a trailing newline added, CRLF line ends, a byte-order mark, ``#`` metadata lines edited or
deleted, blank lines, spaces around cells, numbers re-spelt by a spreadsheet (``60.0`` →
``60``), columns or rows put in another order, a column with no value in any row added or
deleted. :func:`content_sha256` is a digest of the data alone: the names of the columns that
hold a value (stripped, case-folded) and the multiset of data rows, each row the set of its
non-empty cells tagged with their column's name, each cell in the form :func:`cell_text`
gives. The records compare it, beside the file's SHA-256, where they refuse the same
measurement calibrated twice.

It is not a seal: a changed value, a row added or deleted gives another digest, as it gives
another measurement; and the row multiset is summed (128-bit keyed row digests added
modulo 2¹²⁸), which an adversary with many rows to choose can collide.
"""

from __future__ import annotations

import csv
import hashlib
import io
import re
from pathlib import Path

import numpy as np

from gonio.errors import GonioError
from gonio.formats.metadata import header_lines, is_comment
from gonio.formats.watermark import canonical

#: The first bytes of a Parquet file.
PARQUET_MAGIC = b"PAR1"
#: The digest's version (part of what is hashed: a changed cell form changes every digest;
#: the records' migration 0015 digests the stored files again under a new one).
VERSION = b"gonio readings content v2"
_MOD = 1 << 128
#: A decimal number as a readings cell writes it (the watermark's pattern).
_NUMBER = re.compile(r"^[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?$")


def cell_text(cell) -> str:
    """A cell as the digest keys it. A number: ``'%.15g'`` of its value (a spreadsheet's
    15-digit re-save keys alike: ``60.0``, ``60``, ``6E1``), except an integral value, which
    is written whole — exactly where the cell is an integer (a 64-bit counter's
    ``18446744073709550709`` is not ``1.84467440737096e+19``), else where a double holds it
    exactly (below 2⁵³: ``1e15`` is ``1000000000000000``); −0 as 0. Other text stripped.

    >>> cell_text("60.0"), cell_text(" 6E1"), cell_text("-0"), cell_text("2.50"), cell_text("x ")
    ('60', '60', '0', '2.5', 'x')
    >>> cell_text("18446744073709550709"), cell_text(18446744073709550615), cell_text("1e15")
    ('18446744073709550709', '18446744073709550615', '1000000000000000')
    """
    if isinstance(cell, str):
        c = cell.strip()
        m = _NUMBER.match(c)
        if m is None:
            return c
        if m.group(3) is None and "." not in c:          # an integer, kept whole
            return str(int(c))
        value = float(c) + 0.0
    elif isinstance(cell, (int, np.integer)) and not isinstance(cell, bool):
        return str(int(cell))
    elif isinstance(cell, (float, np.floating)):
        value = float(cell) + 0.0
    else:
        return canonical(cell)
    if value.is_integer() and abs(value) < 2.0 ** 53:
        return str(int(value))
    return "%.15g" % value


def _row_sum(rows, names: list[str], filled: set[int]) -> tuple[int, int]:
    """(count, Σ row digest mod 2¹²⁸) of the rows, each row its non-empty cells tagged with
    their column's name in ``names`` (sorted by name: the columns' order does not count; an
    empty cell is no part of its row); ``filled`` gathers the columns that hold a value."""
    total = count = 0
    order = sorted(range(len(names)), key=lambda i: names[i])
    tags = [names[i] + "\x1d" for i in range(len(names))]
    width = len(names)
    for row in rows:
        cells = [(i, c) for i in order if i < len(row) and (c := cell_text(row[i]))]
        if not cells:
            continue
        if len(filled) < width:
            filled.update(i for i, _ in cells)
        text = "\x1f".join([tags[i] + c for i, c in cells])
        h = hashlib.blake2b(text.encode(), digest_size=16, key=VERSION)
        total = (total + int.from_bytes(h.digest(), "big")) % _MOD
        count += 1
    return count, total


def _finish(names: list[str], filled: set[int], count: int, total: int) -> str:
    h = hashlib.sha256(VERSION)
    h.update("\x1f".join(sorted(names[i] for i in filled)).encode())
    h.update(f"\x1e{count}\x1e{total:032x}".encode())
    return h.hexdigest()


def _csv(path: Path) -> str | None:
    """The digest of a CSV file, read line by line (memory bounded by the longest line)."""
    def data_lines(fh):
        # lines end at "\n" only, as the readers split them (str.splitlines also splits at
        # a form feed or U+2028 inside a cell, which the readers strip as space); metadata
        # lines as the readers take them (indented, or quoted by a spreadsheet)
        for line in fh:
            line = line.rstrip("\n").rstrip("\r")
            if line.strip() and not is_comment(line):
                yield line

    try:
        with open(path, encoding="utf-8-sig", newline="\n") as fh:
            reader = csv.reader(data_lines(fh))
            header = next(reader, None)
            names = [c.strip().casefold() for c in header or []]
            if not any(names):
                return None
            filled: set[int] = set()
            count, total = _row_sum(reader, names, filled)
    except (UnicodeDecodeError, csv.Error):   # not text; a cell past csv's field limit
        return None
    return _finish(names, filled, count, total)


def _parquet(path: Path) -> str | None:
    import pyarrow.parquet as pq

    try:
        pf = pq.ParquetFile(path)
    except Exception:                       # noqa: BLE001 - not a readable Parquet file
        return None
    names = [str(n).strip().casefold() for n in pf.schema_arrow.names]
    count = total = 0
    filled: set[int] = set()
    for batch in pf.iter_batches(batch_size=65536):
        cols = [batch.column(i).to_pylist() for i in range(batch.num_columns)]
        rows = zip(*[["" if v is None else v for v in c] for c in cols])
        n, t = _row_sum(rows, names, filled)
        count, total = count + n, (total + t) % _MOD
    return _finish(names, filled, count, total)


def content_sha256(path: str | Path) -> str | None:
    """The digest of what a readings file (CSV or Parquet stream) measured, the same for
    every writing of the same data (module docstring); None for a file that holds no
    readable table (then only its bytes' SHA-256 identify it).

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> a = d / "a.csv"; _ = a.write_text("# serial: X\\nt,output\\n1,2.50\\n2,3\\n")
    >>> b = d / "b.csv"; _ = b.write_bytes(b"\\xef\\xbb\\xbfOutput, t\\r\\n3.0,2\\r\\n2.5,1\\r\\n\\r\\n")
    >>> content_sha256(a) == content_sha256(b)
    True
    >>> c = d / "c.csv"; _ = c.write_text("t,output\\n1,2.51\\n2,3\\n")
    >>> content_sha256(a) == content_sha256(c)
    False
    """
    path = Path(path)
    with open(path, "rb") as fh:
        if fh.read(4) == PARQUET_MAGIC:
            return _parquet(path)
    return _csv(path)


#: The metadata key with which readings name the stream they were reduced from by its bytes.
SOURCE_KEY = "source_stream_sha256"
_SHA256 = re.compile(r"^[0-9a-f]{64}$")


def source_sha256(path: str | Path) -> str | None:
    """The SHA-256 of the stream a readings file was reduced from, as its leading metadata
    name it (``# source_stream_sha256:``, written by ``gonio reduce``), lower-case; None where
    they name none, or the file is a Parquet stream or no text. The same measurement as its
    stream: the records refuse one where the other is a standing calibration's readings.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> a = d / "a.csv"; _ = a.write_text("# source_stream_sha256: " + "AB" * 32 + "\\nt,v\\n")
    >>> b = d / "b.csv"; _ = b.write_text("# source_stream: s.csv\\nt,v\\n")
    >>> source_sha256(a) == "ab" * 32, source_sha256(b) is None
    (True, True)
    """
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            if fh.read(4) == PARQUET_MAGIC:
                return None
        for key, value in header_lines(path):
            if key.strip().lower() == SOURCE_KEY:
                v = value.strip().lower()
                return v if _SHA256.match(v) else None
    except (OSError, GonioError):
        return None
    return None
