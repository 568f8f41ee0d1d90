"""The virtual bench's keyed watermark in the readings themselves (docs/formats.md#watermark).

Every readings file and stream the virtual bench writes (``gonio simulate``, ``gonio demo``,
``gonio simulate --stream`` as CSV or Parquet: the optical draft's readings and streams, the
rate specifications' readings, the triad's readings and thermal readings) carries, besides its
``# bench:``/``# seed:``/``# generator:`` lines, a mark in its values, so that readings keep
their provenance when those lines (or a Parquet file's key-value metadata) are deleted or
edited, rows are deleted or reordered, the file is renamed, or a spreadsheet re-saves it.

What it is
    For each marked cell of a data row, a keyed bit ``b = BLAKE2b(key, column ␟ the row's
    other cells)`` (:func:`cell_bit`), the other cells taken in their canonical form
    (:func:`canonical`: a number as ``'%.15g'`` of its value, so ``60.0``, ``60`` and
    ``6E1`` key alike): a pseudo-random bit of the row itself (its test, step, counts, set
    points …), not of its position nor of how its numbers are spelt. The virtual bench
    writes every marked value ``v`` so that the integer ``q = v·10ᵈ`` (``d`` the column's
    marked decimal) has the parity ``b``: where the bench's value does not, ``q`` is moved by
    one (in an optical file up or down by a second keyed bit, in a rate or triad file up;
    up from zero). The parity is a property of the value, not of
    its text: a re-save that keeps the value (``12.050`` → ``12.05``) keeps the mark.
Which cells
    ``time_s`` only, at :data:`TIME_DECIMALS` = 9 (one nanosecond), in every file that has a
    ``time_s`` column: the optical draft's readings and streams (a ``gyro_counts`` or
    ``gyro_deg`` column), the rate specifications' readings and the triad's readings and
    thermal readings. No measured value moves: the counts, angles, outputs and standard
    deviations are written as the bench made them (tests/test_virtual_mark_numbers.py; a
    Monte Carlo whose numerical error exceeds its printed digit can still print another
    digit, docs/formats.md#watermark); a reading's time moves by at most 1 ns (a 60 °/s
    rotation turns 0.2 µ″ in it; the Earth rate 4·10⁻⁹ ″; 10⁻⁹ s of a rate programme's
    one-second clock), far below the bench's own timing. A rate or triad time moves only
    later, so that no reading leaves the time window a procedure selects it by from below.
    A file without a ``time_s`` column is marked in its measured columns :data:`COLUMNS`
    (the rate specifications' ``output``, the triad's ``out_*``/``sd_*``) at the column's
    decimals ``d`` (the most decimals a value of the column is written with, at most
    ``15 −`` the digits of its largest whole part), each value written with ``d``
    decimals, moved by at most one unit of the ``d``-th; a column whose values have no
    decimals at all is not marked. Until 2026-12-02 the bench marked its rate and triad
    files so, which moved the rate outputs by one step of their resolution and the certified
    numbers by up to one printed digit; :func:`detect` still reads that mark
    (:func:`legacy_columns`) beside the time mark, so such a file is recognised when its
    metadata are deleted.
How it is detected
    :func:`detect` reads a CSV file line by line, or a Parquet stream batch by batch, up to
    :data:`MAX_ROWS` rows. The metadata lines (as the readers take them: ``#`` after
    blanks, or quoted as one cell) and Parquet metadata are not used. It takes each marked
    cell once per distinct row context and, block by block of :data:`MAX_CELLS` consecutive
    cells, counts the cells whose ``q`` has the parity of their bit (``k`` of ``n``) and
    computes the two-sided binomial p-value for ``K ~ Binomial(n, 1/2)``
    (:func:`two_sided_p`: times shifted by an odd number of nanoseconds turn every parity
    over, ``k = 0``). The readings are the virtual bench's when a block of ``n ≥``
    :data:`MIN_CELLS` cells has a p-value at most its level (:func:`block_level`: the first
    block at nearly :data:`ALPHA`, the later ones sharing a thousandth of it), so simulated
    rows appended to (or put among) real ones are found wherever a block is mostly theirs.
    Each test is made with the row's other cells in the file's column order; a file whose
    columns are a bench header's (:data:`BENCH_HEADERS`) in another order, or with columns
    more (a spreadsheet's rearrangement, a note column), is tested in the bench's order as
    well (:func:`bench_order`). A rate or triad file with times is tested in ``time_s`` and
    in the measured columns the bench marked until 2026-12-02. The tests of one file share
    :data:`ALPHA` (Bonferroni: each at :data:`ALPHA` divided by their number, so the file's
    level stays :data:`ALPHA`).
False positives
    On readings not written by the bench, the bit of each distinct row context is a keyed
    pseudo-random function of cells the marked value is not part of, so each cell matches
    with probability 1/2 independently of what the values are (constant, even only,
    quantised, times on a millisecond grid): a file is flagged with probability at most
    :data:`ALPHA` = 10⁻⁶ (the binomial test's own level; exactly ``2·2⁻ⁿ`` at ``k = n``),
    whatever its size. A marked file of ``n`` cells has ``k = n``: 27 cells (the smallest
    built-in protocol) give ``2·2⁻²⁷ ≈ 1.5·10⁻⁸``.
What it does not do
    It is not a security seal: the key is in this module, so anyone who means to can strip
    it. Readings perturbed in their marked digit (re-rounded, noise added, times re-written
    at fewer decimals) lose it. A time of 10⁶ s or more is not marked at 1 ns by a 15-digit
    re-save (such rows count as unmarked, never as marked). Readings acquired through
    ``gonio acquire`` from the virtual bench's instruments are marked by their instruments'
    identification and by this watermark (the acquisition's writer marks them, from that
    identification: ``gonio.instruments.run.ReadingsFile``). Files the bench wrote before the mark moved to
    the optical times and to canonical keys are recognised by their metadata only.
"""

from __future__ import annotations

import csv
import hashlib
import math
import re
from decimal import Decimal, InvalidOperation
from pathlib import Path

import numpy as np

from gonio.formats.metadata import is_comment

#: The key (a constant of gonio: the watermark marks provenance, it does not seal it).
KEY = b"gonio virtual bench readings watermark v2"
#: The measured columns the watermark is written into and read from in a rate or triad file
#: without a ``time_s`` column (the rate specifications' output, the triad's outputs and
#: their standard deviations); a file with times is marked in them alone.
COLUMNS: tuple[str, ...] = ("output", "out_x", "out_y", "out_z", "sd_x", "sd_y", "sd_z")
#: The optical draft's measured columns: a file holding one has its times marked up or down.
OPTICAL_COLUMNS: tuple[str, ...] = ("gyro_counts", "gyro_deg")
#: The optical readings' and streams' marked column and its decimal (1 ns).
TIME_COLUMN = "time_s"
TIME_DECIMALS = 9
#: The level of the detection's binomial test: a file not written by the bench is flagged
#: with probability at most this.
ALPHA = 1e-6
#: The fewest cells the detection decides on (two-sided, 2·2⁻²¹ ≈ 9.5·10⁻⁷ ≤ ALPHA at k = n).
MIN_CELLS = 21
#: The distinct cells of one block of the detection: a file is tested block by block, each
#: block of this many consecutive cells on its own (:func:`block_level`), so that marked rows
#: after unmarked ones (or among them) are not diluted by the whole file.
MAX_CELLS = 20000
#: The most data rows the detection reads (rows whose contexts repeat add no cell).
MAX_ROWS = 400000
#: The share of :data:`ALPHA` the blocks after the first spend (:func:`block_level`).
LATER_BLOCKS_SHARE = 1e-3
#: The most significant digits a marked value is written with (a spreadsheet keeps 15).
SIGNIFICANT = 15

_NUMBER = re.compile(r"^[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?$")

_STREAM = ("time_s", "gyro_counts")
#: The column orders the virtual bench writes (the optical readings, streams and static
#: records, the rate readings, the triad's readings and thermal readings): a row's bits are
#: keyed on its other cells in the order they were written, so a file whose columns were
#: put in another order, or given a column more, is read in its bench order as well
#: (:func:`bench_order`; tests/test_watermark_rearranged.py checks that every simulated
#: file's header is one of these).
BENCH_HEADERS: tuple[tuple[str, ...], ...] = (
    ("test", "series", "round", "rate_dps", "orientation", "time_s", "table_deg",
     "gyro_counts", "gyro_deg"),
    _STREAM, _STREAM + ("table_deg",), _STREAM + ("temperature_c",),
    _STREAM + ("table_deg", "temperature_c"),
    ("test", "run", "step", "role", "time_s", "rate_dps", "freq_hz", "temperature_c",
     "supply_v", "up_axis", "north_axis", "reference_dps", "output", "stand_deg",
     "stand_axis", "supply_set_v"),
    ("test", "step", "phase", "up", "north0", "table_deg", "rate_dps", "time_s",
     "duration_s", "n_samples", "chamber_c", "sensor_c", "supply_v", "out_x", "out_y",
     "out_z", "sd_x", "sd_y", "sd_z"),
)


def bench_order(header) -> tuple[str, ...] | None:
    """The bench's order (:data:`BENCH_HEADERS`) a header's columns were written in, where
    the header is not that order itself: the longest bench header all of whose columns the
    header has, with a marked column among them; None where the header is a bench header as
    it stands, or holds none.

    >>> bench_order(["time_s", "gyro_counts", "table_deg"]) is None
    True
    >>> bench_order(["table_deg", "note", "time_s", "gyro_counts"])
    ('time_s', 'gyro_counts', 'table_deg')
    """
    names = tuple(str(h).strip().lstrip("\ufeff") for h in header)
    if names in BENCH_HEADERS:
        return None
    have = set(names)
    fits = [h for h in BENCH_HEADERS if have.issuperset(h) and TIME_COLUMN in h]
    return max(fits, key=len) if fits else None


def cell_bit(column: str, context: str) -> tuple[int, int]:
    """The keyed parity bit of a marked cell and the direction bit the writer moves by."""
    h = hashlib.blake2b(f"{column}\x1f{context}".encode(), key=KEY, digest_size=2).digest()
    return h[0] & 1, h[1] & 1


def canonical(cell) -> str:
    """A cell as the watermark keys it: a number as ``'%.15g'`` of its value (−0 as 0), so
    that a spreadsheet's re-save (``60.0`` → ``60``) keys alike; any other text stripped.

    >>> canonical("60.0"), canonical("60"), canonical(" 6E1"), canonical("-0"), canonical("+x")
    ('60', '60', '60', '0', '+x')
    """
    if type(cell) is str:               # a CSV cell: the same steps as below, sooner
        c = cell.strip()
        return "%.15g" % (float(c) + 0.0) if _NUMBER.match(c) else c
    if isinstance(cell, (int, float, np.integer, np.floating)):
        return "%.15g" % (float(cell) + 0.0)
    c = str(cell).strip()
    if _NUMBER.match(c):
        return "%.15g" % (float(c) + 0.0)
    return c


def _value(cell) -> Decimal | None:
    """A marked cell's value at 15 significant digits (None: not a finite number)."""
    if isinstance(cell, (int, float, np.integer, np.floating)):
        f = float(cell)
    else:
        c = str(cell).strip()
        if not _NUMBER.match(c):
            return None
        f = float(c)
    if not np.isfinite(f):
        return None
    return Decimal("%.15g" % f)


def _decimals(v: Decimal) -> int:
    return max(0, -v.normalize().as_tuple().exponent) if v != 0 else 0


def _whole_digits(v: Decimal) -> int:
    a = abs(v)
    return len(str(int(a))) if a >= 1 else 1


def _q(v: Decimal, d: int) -> int:
    return int(v.scaleb(d).to_integral_value())


def marked_columns(header) -> dict[int, str]:
    """{index: name} of the marked columns of a header (module docstring, Which cells)."""
    names = [str(h).strip().lstrip("\ufeff") for h in header]
    if TIME_COLUMN in names:            # every file with times: the mark moves no value
        return {j: n for j, n in enumerate(names) if n == TIME_COLUMN}
    return {j: n for j, n in enumerate(names) if n in COLUMNS}


def legacy_columns(header) -> dict[int, str]:
    """{index: name} of the columns a rate or triad file with times was marked in before the
    mark moved to ``time_s`` (its measured columns :data:`COLUMNS`; module docstring,
    Which cells): read by :func:`detect` beside the time mark, so that such a file is still
    recognised once its metadata are deleted. {} for an optical file or a file without
    times (whose marked columns have not changed)."""
    names = [str(h).strip().lstrip("\ufeff") for h in header]
    if TIME_COLUMN not in names or any(n in OPTICAL_COLUMNS for n in names):
        return {}
    return {j: n for j, n in enumerate(names) if n in COLUMNS}


def column_decimals(name: str, values) -> int:
    """The decimal a column is marked at (module docstring): :data:`TIME_DECIMALS` for the
    optical time; else the most decimals of its values, at most 15 − the digits of its
    largest whole part; 0 (not marked) where no value has a decimal.

    >>> column_decimals("output", [Decimal("2501.7"), Decimal("2501.73")])
    2
    >>> column_decimals("sd_x", [Decimal("0"), Decimal("2")])
    0
    """
    if name == TIME_COLUMN:
        return TIME_DECIMALS
    vals = [v for v in values if v is not None]
    if not vals:
        return 0
    d = max(_decimals(v) for v in vals)
    return max(0, min(d, SIGNIFICANT - max(_whole_digits(v) for v in vals)))


def _iter_rows(lines):
    """(line index, cells) of a CSV text's lines, the header first: metadata lines (as the
    readers take them, :func:`gonio.formats.metadata.is_comment`: ``#`` after blanks, or
    quoted as one cell) and blank lines skipped. ``lines`` may be any iterable (a file read
    lazily)."""
    for i, line in enumerate(lines):
        s = line.rstrip("\r\n")
        if not s.strip() or is_comment(s):
            continue
        yield i, (next(csv.reader([s])) if '"' in s else s.split(","))


#: The most texts a :func:`_context` memo holds before it starts afresh (bounded memory).
_MEMO_MAX = 200_000


def _context(cells, marked, memo: dict | None = None) -> str:
    """The row's other cells (not in ``marked``), :func:`canonical` and joined by ␟.
    ``memo``: {text: canonical text} kept across the rows of one file (its set points,
    steps and empty cells repeat), the same texts as :func:`canonical`'s."""
    if memo is None:
        return "\x1f".join(canonical(c) for j, c in enumerate(cells) if j not in marked)
    if len(memo) > _MEMO_MAX:
        memo.clear()

    def miss(c):
        k = memo[c] = canonical(c)
        return k
    return "\x1f".join([memo[c] if c in memo else miss(c)
                        for j, c in enumerate(cells) if j not in marked])


def _fixed(q: int, d: int) -> str:
    return f"{Decimal(q).scaleb(-d):.{d}f}"


#: A plain decimal text: its sign, whole digits and decimals (ASCII digits, no exponent).
_PLAIN = re.compile(r"([+-]?)([0-9]*)\.?([0-9]*)")
_TIME_SCALE = 10 ** TIME_DECIMALS
#: 10**k for the digits of a time in ns held in an int64 (below 10**18).
_POW10 = np.array([10 ** k for k in range(19)], dtype=np.int64)
#: The longest time text the column path reads (sign, 15 digits, point).
_SHORT = 17


def _plain_q(s: str) -> int | None:
    """``s`` (a plain decimal text with at most :data:`TIME_DECIMALS` decimals and fewer
    than 16 whole digits) as the integer of its value in ns, exactly; None for any other
    text (an exponent, more decimals, other digits), which the caller takes through
    :class:`~decimal.Decimal`."""
    m = _PLAIN.fullmatch(s)
    if m is None:
        return None
    sign, whole, frac = m.groups()
    if len(frac) > TIME_DECIMALS or len(whole) > 15 or not (whole or frac):
        return None
    q = int(whole or "0") * _TIME_SCALE + int(frac.ljust(TIME_DECIMALS, "0"))
    return -q if sign == "-" else q


def _time_q(t: str) -> int | None:
    """``_q(_value(t), 9)`` of a stripped time text (None: not a finite number): plain
    ``'%.15g'`` texts by integer arithmetic, any other through :class:`~decimal.Decimal`."""
    if not _NUMBER.match(t):
        return None
    f = float(t)
    if not math.isfinite(f):
        return None
    s = "%.15g" % f
    q = _plain_q(s)
    return _q(Decimal(s), TIME_DECIMALS) if q is None else q


def _same_time(q: int, t: str) -> bool:
    """Whether ``q`` ns is the value of the time text ``t``:
    ``Decimal(q).scaleb(-9) == Decimal(t)``, by integers where ``t`` is plain."""
    qt = _plain_q(t)
    if qt is None:
        return Decimal(q).scaleb(-TIME_DECIMALS) == Decimal(t)
    return q == qt


def _fixed_time(q: int) -> str:
    """:func:`_fixed` of ``q`` at :data:`TIME_DECIMALS` (the same text)."""
    if abs(q) >= 10 ** 27:              # beyond the decimal context's 28 digits
        return _fixed(q, TIME_DECIMALS)
    a = abs(q)
    return f"{'-' if q < 0 else ''}{a // _TIME_SCALE}.{a % _TIME_SCALE:0{TIME_DECIMALS}d}"


def _short_times_q(texts: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """``(short, q)`` of a time column at once: ``short`` where a text is a plain decimal
    (an optional sign, ASCII digits, at most one point; no space) of at most 9 whole digits,
    9 decimals and 15 digits in all, ``q`` its exact value in ns there. Such a text's value
    is its ``'%.15g'`` value (a decimal of at most 15 significant digits survives the
    double and ``'%.15g'``: C's ``DBL_DIG``), so ``q`` is ``_q(_value(t), 9)``; the others
    go cell by cell (:func:`_time_q`)."""
    n = len(texts)
    length = np.fromiter(map(len, texts), dtype=np.int64, count=n)
    if n and int(length.max()) > _SHORT:
        texts = [t if len(t) <= _SHORT else "" for t in texts]
        length = np.where(length > _SHORT, 0, length)
    c = np.array(texts, dtype=str)
    c = c.view(np.uint32).reshape(n, -1).astype(np.int64) if c.itemsize else np.zeros((n, 1), np.int64)
    pos = np.arange(c.shape[1])[None, :]
    signed = (c[:, 0] == 43) | (c[:, 0] == 45)          # '+', '-'
    body = (pos < length[:, None]) & (pos >= signed[:, None])
    digit = body & (c >= 48) & (c <= 57)
    dot = body & (c == 46)
    n_dot, n_digit = dot.sum(1), digit.sum(1)
    point = np.where(n_dot == 1, dot.argmax(1), length)[:, None]
    n_whole = (digit & (pos < point)).sum(1)
    short = ((digit | dot) == body).all(1) & (n_dot <= 1) & (n_digit >= 1) & (n_digit <= 15) \
        & (n_whole <= TIME_DECIMALS) & (n_digit - n_whole <= TIME_DECIMALS)
    use = digit & short[:, None]
    power = np.where(use, np.where(pos < point, point - 1 - pos, point - pos) + TIME_DECIMALS, 0)
    q = np.where(use, (c - 48) * _POW10[power], 0).sum(1)
    return short, np.where(c[:, 0] == 45, -q, q)


def _data_columns(lines: list[str], start: int, width: int) -> tuple[list[int], list[str]]:
    """The line indices of the data rows after the header (line ``start``) that
    :func:`mark_text` marks ('#' and blank lines skipped as :func:`_iter_rows` does; lines
    with a quote or another number of cells than ``width`` left out) and their cells, row
    after row in one list (cell ``j`` of row ``r`` at ``r·width + j``)."""
    idx = [i for i in range(start + 1, len(lines))
           if (s := lines[i].rstrip("\r\n")).count(",") == width - 1 and '"' not in s
           and s.strip() and not is_comment(s)]
    return idx, ",".join([lines[i].rstrip("\r\n") for i in idx]).split(",")


def _contexts(columns: list[list[str]], marked) -> list[str]:
    """:func:`_context` of every row at once, from the file's columns: each distinct text
    made :func:`canonical` once."""
    others = [c for j, c in enumerate(columns) if j not in marked]
    if not others:
        return [""] * len(columns[0])
    memo = {t: canonical(t) for t in set().union(*others)}
    get = memo.__getitem__
    return list(map("\x1f".join, zip(*[list(map(get, col)) for col in others])))


def _bits(name: str, contexts: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """:func:`cell_bit` of ``name`` and each context, as two arrays (the parity bits and
    the direction bits): one keyed hasher, copied per row."""
    keyed = hashlib.blake2b(key=KEY, digest_size=2)
    keyed.update(f"{name}\x1f".encode())

    def digest(ctx: str) -> bytes:
        x = keyed.copy()
        x.update(ctx.encode())
        return x.digest()
    h = np.frombuffer(b"".join(map(digest, contexts)), dtype=np.uint8).reshape(-1, 2) & 1
    return h[:, 0].astype(np.int64), h[:, 1].astype(bool)


def _mark_time(name: str, texts: list[str], bit, up, optical: bool) -> dict[int, str]:
    """{row: new text} of a ``time_s`` column's cells whose value the mark moves (the
    others keep their text)."""
    short, q = _short_times_q(texts)
    step = np.where(up | (q == 0) | (not optical), 1, -1)
    move = short & (q % 2 != bit)
    out = {r: _fixed_time(v) for r, v in zip(np.flatnonzero(move).tolist(),
                                             (q + step)[move].tolist())}
    for r in np.flatnonzero(~short).tolist():
        t = texts[r].strip()
        v = _time_q(t)
        if v is None:
            continue
        if v % 2 != bit[r]:
            v += 1 if up[r] or v == 0 or not optical else -1
        if not _same_time(v, t):
            out[r] = _fixed_time(v)
    return out


def _mark_column(name: str, texts: list[str], bit, up, optical: bool) -> dict[int, str]:
    """{row: new text} of a measured column: every finite value written with the column's
    decimals (none where they are 0)."""
    values = [_value(c) for c in texts]
    d = column_decimals(name, values)
    if d <= 0:
        return {}
    out = {}
    for r, (v, b, u) in enumerate(zip(values, bit.tolist(), up.tolist())):
        if v is None:
            continue
        q = _q(v, d)
        if q % 2 != b:
            q += 1 if u or q == 0 or not optical else -1
        out[r] = _fixed(q, d)
    return out


def mark_text(text: str) -> str:
    """``text`` (a readings file's CSV text, the virtual bench's) with every marked cell
    carrying the watermark (module docstring). Deterministic: the same text gives the same
    bytes; marking marked text changes nothing. Lines with quoted cells are left as they
    are. A measured value is written with its column's decimals; a time whose value does
    not change keeps its text (``12.05`` stays ``12.05``), one that does is written with
    nine decimals. The work goes column by column over the whole file: the rows' contexts
    at once, one keyed hash per marked cell, the times' values in integer arrays."""
    lines = text.splitlines(keepends=True)
    first = next(_iter_rows(lines), None)
    if first is None:
        return text
    header = [c.strip().lstrip("\ufeff") for c in first[1]]
    cols = marked_columns(header)
    if not cols:
        return text
    optical = any(n in OPTICAL_COLUMNS for n in header)
    w = len(header)
    idx, flat = _data_columns(lines, first[0], w)
    if not idx:
        return text
    columns = [flat[j::w] for j in range(w)]
    contexts = _contexts(columns, cols)
    changed: set[int] = set()
    for j, name in cols.items():
        mark = _mark_time if name == TIME_COLUMN else _mark_column
        for r, new in mark(name, columns[j], *_bits(name, contexts), optical).items():
            flat[r * w + j] = new
            changed.add(r)
    for r in sorted(changed):
        i = idx[r]
        lines[i] = ",".join(flat[r * w:(r + 1) * w]) + lines[i][len(lines[i].rstrip("\r\n")):]
    return "".join(lines)


def mark_stream_times(time_s, columns) -> np.ndarray:
    """A stream chunk's times carrying the watermark: each time at 1 ns
    (:data:`TIME_DECIMALS`) with the parity of its row's bit, keyed on the row's other cells
    as written (``columns``: the counter's wrapped values, the table angle, the temperature,
    in the file's column order). Each time moves by at most 1.5 ns.

    >>> t = mark_stream_times(np.array([0.0, 0.05, 0.1]), [np.array([0, 11, 23])])
    >>> bool(np.all(np.abs(t - [0.0, 0.05, 0.1]) <= 1.5e-9)), bool(np.all(np.diff(t) > 0))
    (True, True)
    """
    t = np.asarray(time_s, dtype=np.float64)
    scale = 10 ** TIME_DECIMALS
    q = np.rint(t * scale).astype(np.int64)
    texts = [_canonical_column(np.asarray(c)) for c in columns]
    rows = map("\x1f".join, zip(*texts)) if texts else [""] * t.size
    keyed = hashlib.blake2b(key=KEY, digest_size=2)     # cell_bit's hash, its key set once
    keyed.update(f"{TIME_COLUMN}\x1f".encode())

    def digest(row: str) -> bytes:
        x = keyed.copy()
        x.update(row.encode())
        return x.digest()
    h = [digest(r) for r in rows]
    d = np.frombuffer(b"".join(h), dtype=np.uint8).reshape(-1, 2) & 1
    bit, up = d[:, 0].astype(np.int64), d[:, 1].astype(bool)
    move = (q % 2) != bit
    q = q + np.where(move, np.where(up | (q == 0), 1, -1), 0)
    return q / scale


def _canonical_column(a: np.ndarray) -> list[str]:
    """:func:`canonical` of every value of a stream column, at once (the same texts)."""
    if a.dtype.kind in "iu" and (a.size == 0 or int(np.max(np.abs(a.astype(np.float64)))) < 10**15):
        return a.astype(str).tolist()
    seen: dict[float, str] = {}         # a table at rest repeats its angle
    out = []
    for x in np.asarray(a, dtype=np.float64).tolist():
        c = seen.get(x)
        if c is None:
            c = seen[x] = "%.15g" % (x + 0.0)
        out.append(c)
    return out


def block_level(j: int, alpha: float = ALPHA) -> float:
    """The level block ``j`` (1, 2, …) of a file is tested at: the first at
    ``alpha·(1 − δ)``, block ``j ≥ 2`` at ``alpha·δ·2^−(j−1)`` (δ =
    :data:`LATER_BLOCKS_SHARE`), so that the levels of all blocks sum to at most ``alpha``
    (a union bound, as Bonferroni: a file not written by the bench is flagged with
    probability at most ``alpha`` however long it is), and a file of one block is decided
    almost as before (its 21 cells at k = n, two-sided 2⁻²⁰, still flagged at :data:`ALPHA`).

    >>> block_level(1) > 2.0 ** -20, sum(block_level(j) for j in range(1, 60)) <= ALPHA
    (True, True)
    """
    if j <= 1:
        return alpha * (1.0 - LATER_BLOCKS_SHARE)
    return alpha * LATER_BLOCKS_SHARE * 2.0 ** -(j - 1)


class _Tally:
    """The detection's count over distinct (column, context) cells, block by block of
    :data:`MAX_CELLS` cells, up to :data:`MAX_ROWS` rows. ``order``: the indices of the
    cells a row's context is made of, in their order (None: every cell but the marked ones,
    in the file's order)."""

    def __init__(self, cols: dict[int, str], order: list[int] | None = None):
        self.cols = cols
        self.order = order
        self.seen: set[int] = set()       # hash((column, context)) of every cell taken
        self.cells: list[tuple[str, str, Decimal]] = []
        self.blocks: list[tuple[int, int]] = []     # (n, k) of each block closed
        self.rows = 0
        self.memo: dict[str, str] = {}

    def add(self, cells) -> bool:
        """Take one row's cells; False once enough are read."""
        self.rows += 1
        if self.order is None:
            ctx = _context(cells, self.cols, self.memo)
        else:
            ctx = _context([cells[j] for j in self.order], (), self.memo)
        for j, name in self.cols.items():
            v = _value(cells[j])
            key = hash((name, ctx))
            if v is None or key in self.seen:
                continue
            self.seen.add(key)
            self.cells.append((name, ctx, v))
        if len(self.cells) >= MAX_CELLS:
            self._close()
        return self.rows < MAX_ROWS

    def _close(self) -> None:
        """Count the open block's cells (n, k) and start the next one."""
        cells, self.cells = self.cells[:MAX_CELLS], self.cells[MAX_CELLS:]
        dec = {name: column_decimals(name, [v for n, _, v in cells if n == name])
               for name in set(self.cols.values())}
        n = k = 0
        for name, ctx, v in cells:
            d = dec[name]
            if d <= 0:
                continue
            n += 1
            k += _q(v, d) % 2 == cell_bit(name, ctx)[0]
        self.blocks.append((n, k))

    def result(self, alpha: float = ALPHA) -> dict:
        """The binomial test of each block at its :func:`block_level` of ``alpha``
        (:data:`ALPHA` shared among the tests of one file, :func:`_combined`); the file is
        the bench's where any block's tail is at most its level. Reported: the block whose
        tail is the smallest share of its level (its cells, matching cells and tail),
        ``blocks`` the number of blocks tested."""
        if self.cells or not self.blocks:
            self._close()
        best = None
        for j, (n, k) in enumerate(self.blocks, start=1):
            if n < MIN_CELLS and best is not None:
                continue
            p = two_sided_p(k, n) if n >= MIN_CELLS else None
            level = block_level(j, alpha)
            score = math.inf if p is None else p / level
            if best is None or score < best[0]:
                best = (score, {"virtual": p is not None and p <= level, "cells": n,
                                "matching": k, "p_value": p})
        return {**best[1], "blocks": len(self.blocks)}


def _tallies(header) -> list[_Tally]:
    """The tests of a file with this header: its marked columns (:func:`marked_columns`)
    with each row's other cells in the file's order and, where its columns are a bench
    header's in another order or with more (:func:`bench_order`), in that bench order; for
    a rate or triad file with times, the columns the bench marked before
    (:func:`legacy_columns`)."""
    out = [t for t in (_Tally(marked_columns(header)), _Tally(legacy_columns(header)))
           if t.cols]
    order = bench_order(header)
    if order is not None:
        names = [str(h).strip().lstrip("\ufeff") for h in header]
        cols = {names.index(TIME_COLUMN): TIME_COLUMN}
        out.append(_Tally(cols, [names.index(n) for n in order if n != TIME_COLUMN]))
    return out


def _combined(tallies: list[_Tally]) -> dict:
    """One decision over a file's tests: each at :data:`ALPHA` divided by their number
    (Bonferroni), so that a file not written by the bench is still flagged with probability
    at most :data:`ALPHA`; the test with the smallest tail reported, its ``p_value``
    multiplied by the number of tests (at most 1); ``tests``: each test's own count and
    tail, with the columns it read."""
    if not tallies:
        return dict(_NONE)
    m = len(tallies)
    res = [t.result(ALPHA / m) for t in tallies]
    best = min(res, key=lambda r: (r["p_value"] is None, r["p_value"] or 0.0))
    p = best["p_value"]
    return {**best, "virtual": any(r["virtual"] for r in res),
            "p_value": None if p is None else min(1.0, m * p),
            "tests": [{**r, "columns": sorted(set(t.cols.values())),
                       "order": "file" if t.order is None else "bench"}
                      for t, r in zip(tallies, res)]}


def _detect_lines(lines) -> dict:
    rows = _iter_rows(lines)
    first = next(rows, None)
    header = [] if first is None else [c.strip().lstrip("\ufeff") for c in first[1]]
    open_ = tallies = _tallies(header)
    for _, cells in rows:
        if len(cells) == len(header):
            open_ = [t for t in open_ if t.add(cells)]
            if not open_:
                break
    return _combined(tallies)


def detect_text(text: str) -> dict:
    """The watermark's test on a CSV text: ``{"virtual", "cells", "matching", "p_value"}``
    (module docstring); ``p_value`` None where fewer than :data:`MIN_CELLS` cells."""
    return _detect_lines(iter(text.splitlines()))


def tail_probability(k: int, n: int) -> float:
    """P(K ≥ k) for K ~ Binomial(n, 1/2): the chance that readings not written by the bench
    match the watermark in ``k`` or more of ``n`` cells."""
    from scipy.stats import binom
    return float(binom.sf(k - 1, n, 0.5))


def two_sided_p(k: int, n: int) -> float:
    """The two-sided binomial p-value of ``k`` matching cells of ``n``:
    ``min(1, 2·min(P(K ≥ k), P(K ≤ k)))``, K ~ Binomial(n, 1/2) (scipy's ``binomtest``
    two-sided, for p = 1/2). Two-sided because every time shifted by an odd number of
    nanoseconds (times re-zeroed at a marked reading) turns each parity over: ``k = 0`` is
    as far from chance as ``k = n``.

    >>> two_sided_p(21, 21) == two_sided_p(0, 21) == 2.0 ** -20
    True
    """
    from scipy.stats import binom
    return float(min(1.0, 2.0 * min(binom.sf(k - 1, n, 0.5), binom.cdf(k, n, 0.5))))


_NONE = {"virtual": False, "cells": 0, "matching": 0, "p_value": None}


def _detect_parquet(path: Path) -> dict:
    import pyarrow.parquet as pq
    pf = pq.ParquetFile(path)
    names = pf.schema_arrow.names
    open_ = tallies = _tallies(names)
    if not tallies:
        return dict(_NONE)
    for batch in pf.iter_batches(batch_size=1 << 14):
        cols = [batch.column(j).to_pylist() for j in range(len(names))]
        for i in range(batch.num_rows):
            row = [c[i] for c in cols]
            open_ = [t for t in open_ if t.add(row)]
            if not open_:
                return _combined(tallies)
    return _combined(tallies)


def detect(path) -> dict:
    """:func:`detect_text` of a readings file or CSV stream, read line by line up to
    :data:`MAX_ROWS` rows, block by block of :data:`MAX_CELLS` cells; a Parquet stream's columns, batch by batch; a JSON file, or a
    file that cannot be read, gives ``virtual`` False and no cells."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".json":
        return dict(_NONE)
    try:
        if suffix == ".parquet":
            return _detect_parquet(p)
        with open(p, encoding="utf-8", errors="replace", newline="") as fh:
            return _detect_lines(fh)
    except OSError:
        return dict(_NONE)
    except Exception as e:          # a damaged Parquet file: its reader refuses it in words
        if suffix == ".parquet" and type(e).__module__.startswith("pyarrow"):
            return dict(_NONE)
        raise
