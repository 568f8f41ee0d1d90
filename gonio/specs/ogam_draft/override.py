"""The override file: hand-fixed matching of a stream's rounds.

``test,series,round,t_zero_s,t_read_s`` (+ optional ``rate_dps``,
``orientation``): the stream times of the zeroing and the reading of each
listed round (``docs/formats.md#override-file``). Read by
:func:`gonio.specs.ogam_draft.reduce.reduce_stream`'s caller and passed in as records.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

from gonio.errors import GonioError, check_header, read_utf8
from gonio.formats.metadata import parse_number


def read_override(path: str | Path) -> list[dict]:
    """Read an override CSV: ``test,series,round,t_zero_s,t_read_s`` (+ optional ``rate_dps``,
    ``orientation``), stream times of the zeroing and reading of each listed round.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "o.csv"
    >>> _ = p.write_text("test,series,round,t_zero_s,t_read_s\\nscale_factor,1,2,70.0,85.5\\n")
    >>> read_override(p)
    [{'test': 'scale_factor', 'series': 1, 'round': 2, 't_zero_s': 70.0, 't_read_s': 85.5}]
    """
    path = Path(path)
    text = read_utf8(path, "override file")
    rows = list(csv.reader(text.splitlines()))
    if not rows:
        raise GonioError("empty override file", file=path, line=1)
    head = [h.strip() for h in rows[0]]
    check_header(head, ("test", "series", "round", "t_zero_s", "t_read_s"), file=path, line=1)
    out = []
    for ln, cells in enumerate(rows[1:], 2):
        if not any(c.strip() for c in cells):
            continue
        if len(cells) != len(head):
            raise GonioError(f"expected {len(head)} fields, got {len(cells)}", file=path,
                             line=ln)
        d = dict(zip(head, (c.strip() for c in cells)))
        rec: dict = {"test": d["test"]}
        for col in ("series", "round"):
            v = parse_number(d[col])
            if v is None or not math.isfinite(v) or v != int(v) or v < 1:
                raise GonioError(f"expected an integer ≥ 1, got {d[col]!r}", file=path,
                                 line=ln, column=col)
            rec[col] = int(v)
        for col in ("t_zero_s", "t_read_s") + tuple(c for c in ("rate_dps",) if c in d):
            v = parse_number(d[col])
            if v is None or not math.isfinite(v):
                raise GonioError(f"expected a finite number, got {d[col]!r}", file=path,
                                 line=ln, column=col)
            rec[col] = v
        if "orientation" in d and d["orientation"]:
            rec["orientation"] = d["orientation"]
        if rec["t_read_s"] <= rec["t_zero_s"]:
            raise GonioError("t_read_s must be after t_zero_s", file=path, line=ln,
                             column="t_read_s")
        out.append(rec)
    return out
