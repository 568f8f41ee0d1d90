"""What a readings file measured, apart from how it is written (docs/formats.md#content-digest).

Two files hold the same measurement when their data are the same, whatever their bytes:
a trailing newline added, CRLF line ends, a byte-order mark, ``#`` metadata lines edited or
deleted, blank lines, spaces around cells, numbers re-spelt by a spreadsheet (``60.0`` →
``60``), columns or rows put in another order. :func:`content_sha256` is a digest of the data
alone: the header's column names (stripped, case-folded) and the multiset of data rows, each
cell in the watermark's canonical form (:func:`gonio.formats.watermark.canonical`: a number
as ``'%.15g'`` of its value). The records compare it, beside the file's SHA-256, where they
refuse the same measurement calibrated twice.

It is not a seal: a changed value, a row added or deleted gives another digest, as it gives
another measurement; and the row multiset is summed (128-bit keyed row digests added
modulo 2¹²⁸), which an adversary with many rows to choose can collide.
"""

from __future__ import annotations

import csv
import hashlib
import io
from pathlib import Path

from gonio.formats.watermark import canonical

#: The first bytes of a Parquet file.
PARQUET_MAGIC = b"PAR1"
#: The digest's version (part of what is hashed: a changed canonical form changes every digest).
VERSION = b"gonio readings content v1"
_MOD = 1 << 128


def _row_sum(rows, order: list[int]) -> tuple[int, int]:
    """(count, Σ row digest mod 2¹²⁸) of the rows, each row's cells in ``order``."""
    total = count = 0
    for row in rows:
        cells = [canonical(row[i]) if i < len(row) else "" for i in order]
        if not any(cells):
            continue
        h = hashlib.blake2b("\x1f".join(cells).encode(), digest_size=16, key=VERSION)
        total = (total + int.from_bytes(h.digest(), "big")) % _MOD
        count += 1
    return count, total


def _finish(header: list[str], count: int, total: int) -> str:
    h = hashlib.sha256(VERSION)
    h.update("\x1f".join(header).encode())
    h.update(f"\x1e{count}\x1e{total:032x}".encode())
    return h.hexdigest()


def _csv(data: bytes) -> str | None:
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        return None
    reader = csv.reader(io.StringIO("\n".join(lines)))
    names = [c.strip().casefold() for c in next(reader)]
    while names and names[-1] == "":
        names.pop()
    if not names:
        return None
    order = sorted(range(len(names)), key=lambda i: names[i])
    count, total = _row_sum(reader, order)
    return _finish([names[i] for i in order], count, total)


def _parquet(path: Path) -> str | None:
    import pyarrow.parquet as pq

    try:
        pf = pq.ParquetFile(path)
    except Exception:                       # noqa: BLE001 - not a readable Parquet file
        return None
    names = [str(n).strip().casefold() for n in pf.schema_arrow.names]
    order = sorted(range(len(names)), key=lambda i: names[i])
    count = total = 0
    for batch in pf.iter_batches(batch_size=65536):
        cols = [batch.column(i).to_pylist() for i in range(batch.num_columns)]
        rows = zip(*[["" if v is None else v for v in c] for c in cols])
        n, t = _row_sum(rows, order)
        count, total = count + n, (total + t) % _MOD
    return _finish([names[i] for i in order], count, total)


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
        head = fh.read(4)
        if head == PARQUET_MAGIC:
            return _parquet(path)
        data = head + fh.read()
    return _csv(data)
