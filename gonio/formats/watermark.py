"""The virtual bench's keyed watermark in the readings themselves (docs/formats.md#watermark).

Every readings file the virtual bench writes (``gonio simulate``, ``gonio demo``: the optical
draft's readings, the rate specifications' readings, the triad's readings and thermal
readings) carries, besides its ``# bench:``/``# seed:``/``# generator:`` lines, a mark in its
measured values, so that readings keep their provenance when those lines are deleted or
edited, rows are deleted or reordered, or the file is renamed.

What it is
    For each cell of a measured column (:data:`COLUMNS`) of a data row, a keyed bit
    ``b = BLAKE2b(key, column ␟ the row's other cells)`` (:func:`cell_bit`): a pseudo-random
    bit of the row itself (its test, step, time, set points …), not of its position. The
    virtual bench writes every such value with the parity of its last written digit equal to
    ``b`` (:func:`mark_text`): where it is not, the last written digit is moved by one (9 → 8,
    0 → 1, else up or down by a second keyed bit), so no value moves by more than one unit of
    its last written digit: one count of the optical counter, one step of the rate bench's
    output resolution (the rate bench's values are first written with their column's
    decimals, e.g. ``2501.70``, so that the step is the resolution, not ten of it), one unit
    in the 15th–17th significant digit of the triad's full-precision values.
How it is detected
    :func:`detect` reads the data rows (the ``#`` lines are not used), takes each measured
    cell once per distinct row context (at most :data:`MAX_CELLS`), counts the cells whose
    last digit's parity equals their bit (``k`` of ``n``) and computes the one-sided binomial
    tail ``P(K ≥ k)`` for ``K ~ Binomial(n, 1/2)``. The readings are the virtual bench's when
    ``n ≥`` :data:`MIN_CELLS` and that tail is at most :data:`ALPHA`.
False positives
    On readings not written by the bench, the bit of each distinct row context is a keyed
    pseudo-random function of cells the parity is not part of, so each cell matches with
    probability 1/2 independently of what the values are (constant, even only, quantised):
    a file is flagged with probability at most :data:`ALPHA` = 10⁻⁶ (the binomial test's
    own level; exactly ``2⁻ⁿ`` at ``k = n``), whatever its size. A marked file of ``n`` cells
    has ``k = n``: 27 cells (the smallest built-in protocol) give ``2⁻²⁷ ≈ 7.5·10⁻⁹``.
What it does not do
    It is not a security seal: the key is in this module, so anyone who means to can strip
    it. Readings perturbed in their last digit (re-rounded, noise added) lose it. Readings
    acquired through ``gonio acquire`` from the virtual bench's instruments are marked by
    their instruments' identification, not by this watermark.
"""

from __future__ import annotations

import csv
import hashlib
import re
from pathlib import Path

#: The key (a constant of gonio: the watermark marks provenance, it does not seal it).
KEY = b"gonio virtual bench readings watermark v1"
#: The measured columns the watermark is written into and read from (the optical draft's
#: counter and angle output, the rate specifications' output, the triad's outputs and their
#: standard deviations).
COLUMNS: tuple[str, ...] = ("gyro_counts", "gyro_deg", "output",
                            "out_x", "out_y", "out_z", "sd_x", "sd_y", "sd_z")
#: The level of the detection's binomial test: a file not written by the bench is flagged
#: with probability at most this.
ALPHA = 1e-6
#: The fewest cells the detection decides on (2⁻²⁰ ≈ 9.5·10⁻⁷ ≤ ALPHA at k = n).
MIN_CELLS = 20
#: The most distinct cells the detection reads (a large file is decided on its first rows).
MAX_CELLS = 20000
#: A column whose values have at most this many decimals is written with its column's
#: decimals (a quantised output: the last digit is then the resolution's step).
PAD_DECIMALS = 6

_NUMBER = re.compile(r"^[+-]?\d+(\.\d+)?([eE][+-]?\d+)?$")


def cell_bit(column: str, context: str) -> tuple[int, int]:
    """The keyed parity bit of a measured cell and the direction bit the writer moves by."""
    h = hashlib.blake2b(f"{column}\x1f{context}".encode(), key=KEY, digest_size=2).digest()
    return h[0] & 1, h[1] & 1


def _mantissa_digit(token: str) -> int | None:
    if not _NUMBER.match(token):
        return None
    m = re.split(r"[eE]", token)[0]
    return int(m[-1])


def _iter_rows(lines):
    """(line index, cells) of a CSV text's lines, the header first: '#' lines and blank
    lines skipped."""
    for i, line in enumerate(lines):
        s = line.rstrip("\r\n")
        if not s.strip() or s.lstrip("\ufeff").startswith("#"):
            continue
        yield i, (next(csv.reader([s])) if '"' in s else s.split(","))


def _rows(lines):
    """(header, [(line index, cells)]) of a CSV text's lines (:func:`_iter_rows`)."""
    it = _iter_rows(lines)
    first = next(it, None)
    header = None if first is None else [c.strip().lstrip("\ufeff") for c in first[1]]
    return header, list(it)


def _context(cells, marked: set[int]) -> str:
    return "\x1f".join(c for j, c in enumerate(cells) if j not in marked)


def _pad(token: str, decimals: int) -> str:
    if "e" in token.lower() or decimals <= 0:
        return token
    whole, _, frac = token.partition(".")
    return f"{whole}.{frac.ljust(decimals, '0')}"


def mark_text(text: str) -> str:
    """``text`` (a readings file's CSV text, the virtual bench's) with every measured cell
    carrying the watermark (module docstring). Deterministic: the same text gives the same
    bytes. Lines with quoted cells are left as they are."""
    lines = text.splitlines(keepends=True)
    header, rows = _rows(lines)
    if header is None:
        return text
    cols = {j: name for j, name in enumerate(header) if name in COLUMNS}
    if not cols:
        return text
    decimals = {}
    for j in cols:
        tokens = [c[j] for _, c in rows if len(c) == len(header) and _NUMBER.match(c[j])
                  and "e" not in c[j].lower()]
        d = max((len(t.partition(".")[2]) for t in tokens), default=0)
        decimals[j] = d if d <= PAD_DECIMALS else 0
    marked = set(cols)
    for i, cells in rows:
        if len(cells) != len(header) or '"' in lines[i]:
            continue
        ctx = _context(cells, marked)
        for j, name in cols.items():
            tok = _pad(cells[j], decimals[j])
            digit = _mantissa_digit(tok)
            if digit is None:
                continue
            bit, up = cell_bit(name, ctx)
            if digit % 2 != bit:
                new = 8 if digit == 9 else 1 if digit == 0 else digit + (1 if up else -1)
                mant, sep, exp = _split_exp(tok)
                tok = mant[:-1] + str(new) + sep + exp
            cells[j] = tok
        end = lines[i][len(lines[i].rstrip("\r\n")):]
        lines[i] = ",".join(cells) + end
    return "".join(lines)


def _split_exp(token: str) -> tuple[str, str, str]:
    for sep in ("e", "E"):
        if sep in token:
            mant, exp = token.split(sep, 1)
            return mant, sep, exp
    return token, "", ""


def detect_text(text: str) -> dict:
    """The watermark's test on a CSV text: ``{"virtual", "cells", "matching", "p_value"}``
    (module docstring); ``p_value`` None where fewer than :data:`MIN_CELLS` cells."""
    rows = _iter_rows(text.splitlines())
    first = next(rows, None)
    header = [] if first is None else [c.strip().lstrip("\ufeff") for c in first[1]]
    cols = {j: n for j, n in enumerate(header) if n in COLUMNS}
    seen: set[tuple[str, str]] = set()
    n = k = 0
    for _, cells in rows:
        if len(cells) != len(header):
            continue
        ctx = _context(cells, set(cols))
        for j, name in cols.items():
            digit = _mantissa_digit(cells[j].strip())
            if digit is None or (name, ctx) in seen:
                continue
            seen.add((name, ctx))
            n += 1
            k += digit % 2 == cell_bit(name, ctx)[0]
        if n >= MAX_CELLS:
            break
    p = tail_probability(k, n) if n >= MIN_CELLS else None
    return {"virtual": p is not None and p <= ALPHA, "cells": n, "matching": k, "p_value": p}


def tail_probability(k: int, n: int) -> float:
    """P(K ≥ k) for K ~ Binomial(n, 1/2): the chance that readings not written by the bench
    match the watermark in ``k`` or more of ``n`` cells."""
    from scipy.stats import binom
    return float(binom.sf(k - 1, n, 0.5))


def detect(path) -> dict:
    """:func:`detect_text` of a readings file (a CSV text file; any other file, or one that
    cannot be read as text, gives ``virtual`` False and no cells)."""
    p = Path(path)
    if p.suffix.lower() in (".parquet", ".json"):
        return {"virtual": False, "cells": 0, "matching": 0, "p_value": None}
    try:
        text = p.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return {"virtual": False, "cells": 0, "matching": 0, "p_value": None}
    return detect_text(text)
