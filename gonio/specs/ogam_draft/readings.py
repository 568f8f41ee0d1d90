"""Readings files: read, validate and write (``docs/formats.md#readings-file``).

Contents
========
=========================  ===================================================
:data:`TEST_NAMES`         the ``test`` values a readings file may carry
:data:`ORIENTATIONS`       the ``orientation`` values (table-axis direction)
:data:`COLUMNS`            the written column order
:class:`Readings`          a validated file: ``data``, ``metadata``, ``path``
:func:`read_readings`      parse and validate a readings CSV
:func:`parse_readings`     the same from text already in memory
:func:`write_readings`     write the exact format, deterministic bytes, atomic
=========================  ===================================================

A readings file is CSV (UTF-8, with or without BOM, ``\\n`` or ``\\r\\n``):
``# key: value`` metadata lines at the top, one header row, one row per
triggered reading. Every error a file can cause is a
:class:`gonio.errors.GonioError` naming file, line (1-based, counting the
metadata lines) and column. Blank lines are skipped. The input file is only
read, never modified.

Normalised columns of :attr:`Readings.data`: ``test`` (str), ``series`` and
``round`` (int64), ``rate_dps`` (float, 60 when absent or empty),
``orientation`` (str, ``up`` when absent or empty), ``time_s`` (float),
``table_deg`` (float, NaN only for ``zero_stability``), ``gyro_counts``
(float64 holding integers, NaN when empty), ``gyro_deg`` (float, NaN when
empty), ``line`` (int64: the row's line number in the file). Extra columns are
kept as text (empty string when empty).
"""

from __future__ import annotations

import csv
import math
import re
from bisect import bisect_left
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import numpy as np
import pandas as pd

from gonio.atomic import write_text
from gonio.errors import (GonioError, MissingColumnError, check_header, check_near_miss,
                          read_utf8)
from gonio.formats.metadata import (IDENTITY_METADATA, KNOWN_METADATA,  # noqa: F401
                                    NUMERIC_METADATA, metadata_bool,
                                    check_identity_synonyms, comment_body, is_comment,
                                    metadata_float, metadata_gyro_type, parse_number)
from gonio.formats.metadata import show_value as _show

#: The ``test`` names of the draft's clause 7 (the first five) and of later features.
TEST_NAMES: tuple[str, ...] = (
    "scale_factor", "zero_stability", "angle_deviation", "rate_consistency",
    "pointing_consistency", "equal_division", "tilt_estimate",
)
#: Table-axis directions of draft 7.7 (Fig. 3).
ORIENTATIONS: tuple[str, ...] = ("up", "north", "south", "east", "west")
#: Column order of a written readings file (extra columns follow).
COLUMNS: tuple[str, ...] = (
    "test", "series", "round", "rate_dps", "orientation", "time_s",
    "table_deg", "gyro_counts", "gyro_deg",
)
#: Extra columns with a meaning (docs/formats.md#columns): the table's position at the zeroing
#: of an equal-division row, the chamber's logged temperature.
MEANINGFUL_EXTRAS: tuple[str, ...] = ("start_deg", "temperature_c")


def read_columns() -> tuple[str, ...]:
    """The columns a readings file is read by; another is carried as text and stated as unread
    (docs/formats.md#columns)."""
    return COLUMNS + MEANINGFUL_EXTRAS


#: Columns a file must have in its header.
REQUIRED_COLUMNS: tuple[str, ...] = ("test", "series", "round", "time_s", "table_deg")
#: Default table rate, °/s (docs/formats.md#columns; draft 7.1 and 7.4 run at 60 °/s).
DEFAULT_RATE_DPS: float = 60.0
#: Default table-axis direction.
DEFAULT_ORIENTATION: str = "up"
#: The key that identifies one reading.
KEY_COLUMNS: tuple[str, ...] = ("test", "series", "round", "rate_dps", "orientation")

#: Plausible ranges of the numeric columns (docs/formats.md, "Plausible ranges"):
#: column -> (lowest, highest); values outside are refused with the line.
COLUMN_RANGES: dict[str, tuple[float, float]] = {
    "time_s": (-1e10, 1e10),
    "table_deg": (-1e4, 1e4),
    "gyro_counts": (-2.0 ** 63, 2.0 ** 63 - 1024),
    "gyro_deg": (-1e6, 1e6),
    "rate_dps": (1e-6, 1e4),
}
#: Longest cell and metadata value accepted, characters.
MAX_CELL_CHARS: int = 4096


@dataclass
class Readings:
    """A validated readings file.

    Attributes
    ----------
    data : pandas.DataFrame
        One row per reading, normalised columns (see module docstring).
    metadata : dict of str to str
        The ``# key: value`` lines, in file order.
    path : pathlib.Path or None
        Where the readings came from (None when built in memory).
    """

    data: pd.DataFrame
    metadata: dict[str, str] = field(default_factory=dict)
    path: Path | None = None

    def counts_quantised(self) -> bool:
        """Whether ``gyro_counts`` must be integers (metadata ``counts_quantised``, default true)."""
        return metadata_bool(self.metadata, "counts_quantised", True, file=self.path)



def read_readings(path: str | Path) -> Readings:
    """Read and validate a readings file (``docs/formats.md#readings-file``).

    Parameters
    ----------
    path : str or Path
        The CSV file. UTF-8 with or without BOM; LF or CRLF line ends.

    Returns
    -------
    Readings
        Normalised data, metadata in file order, and the path.

    Raises
    ------
    GonioError
        Naming file, line and column, for any departure from the contract.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "r.csv"
    >>> _ = p.write_text("# serial: 0042\\n"
    ...     "test,series,round,time_s,table_deg,gyro_counts\\n"
    ...     "scale_factor,1,1,3.0,60.0,216000\\n")
    >>> r = read_readings(p)
    >>> r.metadata
    {'serial': '0042'}
    >>> r.data[["test", "rate_dps", "orientation", "gyro_counts", "line"]].to_dict("records")
    [{'test': 'scale_factor', 'rate_dps': 60.0, 'orientation': 'up', 'gyro_counts': 216000.0, 'line': 3}]
    """
    path = Path(path)
    return parse_readings(read_utf8(path, "readings file"), path=path)


def parse_readings(text: str, *, path: str | Path | None = None) -> Readings:
    """Validate readings given as text (what :func:`read_readings` does after reading).

    >>> r = parse_readings("test,series,round,time_s,table_deg,gyro_deg\\n"
    ...                    "zero_stability,1,1,0,,0.0\\n", path="mem.csv")
    >>> bool(r.data["table_deg"].isna().all())
    True
    """
    fname = "<text>" if path is None else str(path)
    if text.startswith("\ufeff"):
        text = text[1:]
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    n_lines = text.count("\n") + 1
    _check_rows(n_lines, fname)
    metadata: dict[str, str] = {}
    idx = 0
    pos = 0                       # offset of the next line (the file is not split whole)
    header: list[str] | None = None
    header_line = 0
    while pos <= len(text):
        end = text.find("\n", pos)
        end = len(text) if end < 0 else end
        line = text[pos:end]
        pos = end + 1
        idx += 1
        if not line.strip():
            continue
        if is_comment(line):
            if header is not None:
                raise GonioError("metadata line after the header; '#' lines belong at the top",
                                 file=fname, line=idx)
            body = comment_body(line)
            key, sep, value = body.partition(":")
            key = key.strip()
            if not sep or not key:
                raise GonioError(f"bad metadata line, expected '# key: value', got {line!r}",
                                 file=fname, line=idx)
            if key in metadata:
                raise GonioError(f"metadata key {key!r} given twice", file=fname, line=idx,
                                 key=key)
            if len(value) > MAX_CELL_CHARS or len(key) > 200:
                raise GonioError(f"metadata value of {len(value)} characters, over the limit "
                                 f"of {MAX_CELL_CHARS}", file=fname, line=idx, key=key[:40])
            metadata[key] = value.strip()
            continue
        header = [h.strip() for h in _cells(line, fname, idx)]
        header_line = idx
        break
    if header is None:
        raise GonioError("no readings: the file has no header row", file=fname,
                         line=max(1, n_lines - text.endswith("\n")))
    for key in metadata:
        if key in NUMERIC_METADATA:
            metadata_float(metadata, key, file=fname)
    check_identity_synonyms(metadata, fname)
    check_near_miss(metadata, (*KNOWN_METADATA, *IDENTITY_METADATA), what="metadata key",
                    file=fname)
    metadata_gyro_type(metadata, file=fname)
    quantised = metadata_bool(metadata, "counts_quantised", True, file=fname)

    seen = check_header(header, REQUIRED_COLUMNS, file=fname, line=header_line)
    check_near_miss(header, read_columns(), what="column", file=fname, line=header_line)
    if "line" in seen:
        raise GonioError("column name 'line' is reserved (it holds each row's line number)",
                         file=fname, line=header_line, column="line")
    if "gyro_counts" not in seen and "gyro_deg" not in seen:
        raise GonioError("missing column: need gyro_counts or gyro_deg (or both)",
                         file=fname, line=header_line, column="gyro_counts")

    extras = [h for h in header if h not in COLUMNS]
    cols = _parse_body(text, pos, idx, header, extras, fname, quantised)
    del text
    if not len(cols["line"]):
        raise GonioError("no readings: header only", file=fname, line=header_line)
    data = _frame(cols, extras)
    return Readings(data=data, metadata=metadata, path=None if path is None else Path(path))


def _split_fast(text: str, pos: int, first: int, header: list[str]):
    """The data rows as Arrow string columns, read by Arrow's CSV reader, and their line
    numbers — or None when the body needs the line-by-line reading (a blank line, a
    quote, a ``#``, a long line, a wrong field count: whatever it must report exactly).
    The body is ``text`` from offset ``pos`` on, its first line is line ``first`` + 1;
    it is encoded once and read in place (no copies of a large file's text)."""
    import pyarrow as pa
    import pyarrow.csv as pcsv

    raw = text.encode("utf-8")
    start = len(text[:pos].encode("utf-8")) if not text[:pos].isascii() else pos
    end = len(raw)
    while end > start and raw[end - 1] == 10:           # the final line end(s)
        end -= 1
    if end <= start or raw[start] == 10 or raw.find(b'"', start, end) >= 0 or \
            raw.find(b"#", start, end) >= 0 or raw.find(b"\n\n", start, end) >= 0 or \
            _LONG_LINE.search(raw, start, end):
        return None
    n = raw.count(b"\n", start, end) + 1
    names = [f"c{i}" for i in range(len(header))]
    try:
        tab = pcsv.read_csv(
            pa.BufferReader(pa.py_buffer(raw).slice(start, end - start)),
            read_options=pcsv.ReadOptions(column_names=names, block_size=1 << 24),
            parse_options=pcsv.ParseOptions(quote_char=False, double_quote=False,
                                            newlines_in_values=False, ignore_empty_lines=False),
            convert_options=pcsv.ConvertOptions(
                column_types={c: pa.string() for c in names},
                strings_can_be_null=False, quoted_strings_can_be_null=False))
    except (pa.ArrowInvalid, ValueError):
        return None
    del raw
    if tab.num_rows != n:
        return None
    cols = {h: tab.column(i).combine_chunks() for i, h in enumerate(header)}
    return cols, np.arange(first + 1, first + 1 + n), None


#: A line longer than the longest cell allowed (it goes to the line-by-line reading).
_LONG_LINE = re.compile(rb"[^\n]{%d}" % (MAX_CELL_CHARS + 1))


def _split_lines(body: str, first: int, header: list[str], fname: str):
    """The data rows read line by line (the general reading): Arrow string columns, their
    line numbers and the first structural error (which ends the reading), if any."""
    import pyarrow as pa

    ncol = len(header)
    rows: list[list[str]] = []
    line_no: list[int] = []
    structural: GonioError | None = None
    for off, raw in enumerate(body.split("\n")):
        if not raw or raw.isspace():
            continue
        ln = first + off + 1
        if is_comment(raw):
            structural = GonioError("metadata line after the header; '#' lines belong at the "
                                    "top", file=fname, line=ln)
            break
        if '"' in raw or len(raw) > MAX_CELL_CHARS:
            try:
                cells = _cells(raw, fname, ln)
            except GonioError as exc:
                structural = exc
                break
        else:
            cells = raw.split(",")
        if len(cells) != ncol:
            structural = GonioError(f"expected {ncol} fields as in the header, got "
                                    f"{len(cells)}", file=fname, line=ln)
            break
        rows.append(cells)
        line_no.append(ln)
    columns = list(zip(*rows)) if rows else [()] * ncol
    cols = {h: pa.array(list(c), type=pa.string()) for h, c in zip(header, columns)}
    return cols, line_no, structural


def _parse_body(text: str, pos: int, idx: int, header: list[str], extras: list[str],
                fname: str, quantised: bool) -> dict[str, list | np.ndarray]:
    """The data rows after the header, validated: columns of :data:`COLUMNS`, the
    extras and ``line``.

    Vectorised: the rows are split by Arrow's CSV reader when the body is plain
    (:func:`_split_fast`, else line by line), and the cells of every column are checked
    and converted at once (:func:`_fast_numbers`); a row that any fast check does not
    accept outright (a blank to strip, a value out of range, a missing cell...) is
    parsed alone by :func:`_parse_row`, the one rule book, which accepts it or raises
    the error. The error raised is the one of the first bad line, as a row-by-row
    reading raises it: a structural error (a ``#`` line, bad CSV, a wrong field
    count), a value error or a duplicated reading, whichever comes first.
    """
    import pyarrow as pa
    import pyarrow.compute as pc

    got = _split_fast(text, pos, idx, header)
    if got is None:
        got = _split_lines(text[pos:], idx, header, fname)
    del text
    text, line_no, structural = got
    n = len(line_no)
    blank = pa.array([""] * n, type=pa.string()) if any(
        c not in text for c in COLUMNS) else None

    def col(name):
        return text[name] if name in text else blank

    def words(name, allowed, default=None):
        a = col(name)
        if default is not None:
            a = pc.if_else(pc.equal(a, ""), default, a)
        enc = a.dictionary_encode()
        values = np.asarray(enc.dictionary.to_pylist() or [""], dtype=object)
        ok = np.isin(values, list(allowed))
        idx_ = enc.indices.to_numpy(zero_copy_only=False)
        return values[idx_], ok[idx_]

    test, ok = words("test", TEST_NAMES)
    num: dict[str, np.ndarray] = {}
    for name in ("series", "round", "rate_dps", "time_s", "table_deg", "gyro_counts",
                 "gyro_deg"):
        v, good = _fast_numbers(col(name))
        num[name] = v
        ok &= good
    with np.errstate(invalid="ignore"):
        for name in ("series", "round"):
            v = num[name]
            ok &= (v >= 1) & (v <= 1_000_000) & (v == np.floor(v))
        for name, (lo, hi) in COLUMN_RANGES.items():
            v = num[name]
            ok &= np.isnan(v) | ((v >= lo) & (v <= hi))
        rate = np.where(np.isnan(num["rate_dps"]), DEFAULT_RATE_DPS, num["rate_dps"])
        orient, good = words("orientation", ORIENTATIONS, DEFAULT_ORIENTATION)
        ok &= good
        ok &= ~np.isnan(num["time_s"]) & (num["time_s"] >= 0)
        ok &= (test == "zero_stability") | ~np.isnan(num["table_deg"])
        counts, gdeg = num["gyro_counts"], num["gyro_deg"]
        ok &= ~(np.isnan(counts) & np.isnan(gdeg))
        ok &= ~((test == "scale_factor") & np.isnan(counts))
        if quantised:
            ok &= np.isnan(counts) | (counts == np.round(counts))
    first_error: tuple[int, GonioError] | None = None
    out = {"test": test, "series": num["series"], "round": num["round"], "rate_dps": rate,
           "orientation": orient, "time_s": num["time_s"], "table_deg": num["table_deg"],
           "gyro_counts": counts, "gyro_deg": gdeg}
    for i in np.flatnonzero(~ok):       # the rule book, row by row, for the rest
        i = int(i)
        row = {h: text[h][i].as_py().strip() for h in header}
        try:
            rec = _parse_row(row, dict(file=fname, line=int(line_no[i])), quantised)
        except GonioError as exc:
            first_error = (int(line_no[i]), exc)
            break
        for name in COLUMNS:
            out[name][i] = rec[name]
    upto = n if first_error is None else bisect_left(line_no, first_error[0])
    dup = _first_duplicate(out, upto, line_no, fname)
    order = _first_out_of_order(out, upto, line_no, fname)
    events = [e for e in (first_error, dup, order,
                          None if structural is None else (structural.line, structural))
              if e is not None]
    if events:
        raise min(events, key=lambda e: e[0])[1]
    cols: dict[str, list | np.ndarray] = dict(out)
    for name in ("series", "round"):
        cols[name] = out[name].astype(np.int64)
    for name in extras:
        cols[name] = np.asarray(pc.utf8_trim_whitespace(text[name]).to_pylist(), dtype=object)
    cols["line"] = line_no
    return cols


#: A plain decimal number (gonio.formats.metadata.parse_number's grammar), for Arrow.
_NUMBER_RE2 = r"^[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?$"


def _fast_numbers(cells) -> tuple[np.ndarray, np.ndarray]:
    """float64 values of an Arrow string column (NaN for an empty cell) and where the
    fast path accepted them (a plain ASCII decimal number as
    :func:`gonio.formats.metadata.parse_number` reads it, or empty); the rest is left
    to :func:`_parse_row`."""
    import pyarrow as pa
    import pyarrow.compute as pc

    n = len(cells)
    if not n:
        return np.empty(0), np.ones(0, dtype=bool)
    empty = pc.equal(cells, "")
    plain = pc.match_substring_regex(cells, _NUMBER_RE2)
    good = pc.or_(empty, plain).to_numpy(zero_copy_only=False)
    take = pc.if_else(plain, cells, "0")
    try:
        v = pc.cast(take, pa.float64()).to_numpy(zero_copy_only=False).copy()
    except (pa.ArrowInvalid, ValueError):          # e.g. out of double range: Python's float
        v = np.array([float(x) for x in take.to_pylist()])
    v[~plain.to_numpy(zero_copy_only=False)] = np.nan
    return v, good


def _first_duplicate(out: dict, upto: int, line_no: list[int],
                     fname: str) -> tuple[int, GonioError] | None:
    """The first duplicated reading among the first ``upto`` rows (key of
    :data:`KEY_COLUMNS`; an equal_division step adds its table angle), as the error."""
    if upto < 2:
        return None
    key = pd.DataFrame({k: out[k][:upto] for k in KEY_COLUMNS})
    eda = key["test"].to_numpy() == "equal_division"
    key["step"] = np.where(eda, out["table_deg"][:upto], 0.0)
    dups = np.flatnonzero(key.duplicated(keep="first").to_numpy())
    if not dups.size:
        return None
    i = int(dups[0])
    same = (key.iloc[:i] == key.iloc[i]).all(axis=1).to_numpy()
    j = int(np.flatnonzero(same)[0])
    t, se, r, rate, o = (key.iat[i, c] for c in range(5))
    step = f", table_deg {float(key.iat[i, 5])!r}" if eda[i] else ""
    return int(line_no[i]), GonioError(
        f"duplicated reading: test {t}, series {int(se)}, round {int(r)}, "
        f"rate {float(rate)} deg/s, orientation {o}{step} already on line {int(line_no[j])}",
        column="round", file=fname, line=int(line_no[i]))


def _first_out_of_order(out: dict, upto: int, line_no: list[int],
                        fname: str) -> tuple[int, GonioError] | None:
    """The first 7.3 reading (``zero_stability``), in file order among the first ``upto``
    rows, whose ``time_s`` is not after that of an earlier line's lower round of its series,
    or not before that of an earlier line's higher round (all the times of a series count
    from the one zeroing of the rest, so they increase with the round), as the error naming
    it and the first such earlier line: the line a row-by-row reading stops at. Prefix
    maxima and suffix minima over each series' rounds (Fenwick trees), O(n log n)."""
    test = np.asarray(out["test"][:upto], dtype=object)
    at = np.flatnonzero(test == "zero_stability")
    if at.size < 2:
        return None
    se = np.asarray(out["series"][:upto], dtype=float)[at]
    rd = np.asarray(out["round"][:upto], dtype=float)[at]
    t = np.asarray(out["time_s"][:upto], dtype=float)[at]
    ranks = {s_: {r: i + 1 for i, r in enumerate(sorted(set(rd[se == s_].tolist())))}
             for s_ in set(se.tolist())}
    lo = {s_: [-np.inf] * (len(m) + 1) for s_, m in ranks.items()}   # max t, rounds ≤ k
    hi = {s_: [np.inf] * (len(m) + 1) for s_, m in ranks.items()}    # min t, rounds ≥ k
    for j in range(at.size):
        m, k = ranks[se[j]], ranks[se[j]][rd[j]]
        n, best_lo, best_hi, x = len(m), -np.inf, np.inf, k - 1
        while x > 0:
            best_lo, x = max(best_lo, lo[se[j]][x]), x - (x & -x)
        x = n - k                       # rounds above k: the reversed index n - k
        while x > 0:
            best_hi, x = min(best_hi, hi[se[j]][x]), x - (x & -x)
        if best_lo >= t[j] or best_hi <= t[j]:
            return _out_of_order_error(j, se, rd, t, at, line_no, fname)
        x = k
        while x <= n:
            lo[se[j]][x], x = max(lo[se[j]][x], t[j]), x + (x & -x)
        x = n - k + 1
        while x <= n:
            hi[se[j]][x], x = min(hi[se[j]][x], t[j]), x + (x & -x)
    return None


def _out_of_order_error(j, se, rd, t, at, line_no, fname) -> tuple[int, GonioError]:
    """The error of :func:`_first_out_of_order` for row ``j``, naming the first earlier
    line of its series that its time contradicts."""
    i = next(i for i in range(j) if se[i] == se[j] and (
        (rd[i] < rd[j] and t[i] >= t[j]) or (rd[i] > rd[j] and t[i] <= t[j])))
    line = int(line_no[at[j]])
    return line, GonioError(
        f"zero_stability series {int(se[j])}: round {int(rd[j])} read at time_s {t[j]:g} s, "
        f"round {int(rd[i])} (line {int(line_no[at[i]])}) at {t[i]:g} s; the rounds of a 7.3 "
        "series count from its one zeroing, so their times must increase with the round",
        column="time_s", file=fname, line=line)


#: Rows above which a note says how long the run will take.
NOTE_ROWS: int = 200_000
#: CPU seconds per row of ``gonio calibrate`` on a large file (measured with
#: benchmarks/bench_large_readings.py: about 17 s for 10⁶ rows, certificate included).
SECONDS_PER_ROW: float = 1.7e-5


def _check_rows(n_lines: int, fname: str) -> None:
    """Refuse a file over ``GONIO_MAX_READING_ROWS`` lines; say how long a large one takes.

    The limit bounds memory, not time: a calibration holds the readings and their
    per-reading tables in memory, about 0.9 GB at 10⁶ rows (docs/formats.md,
    "Limits on work")."""
    import sys

    from gonio.limits import limit

    lim = limit("GONIO_MAX_READING_ROWS")
    if n_lines > lim + 200:          # metadata and blank lines allowed beyond the rows
        raise GonioError(f"{n_lines} lines, over the limit of {lim:.0f} readings "
                         "(GONIO_MAX_READING_ROWS): refused before parsing — a calibration "
                         "holds every reading and its tables in memory, about 0.9 GB a "
                         "million rows", file=fname)
    if n_lines > NOTE_ROWS:
        sys.stderr.write(f"gonio: note: {fname}: {n_lines} lines; expect about "
                         f"{max(1.0, n_lines * SECONDS_PER_ROW):.0f} s of computing\n")


def _cells(line: str, fname: str, idx: int) -> list[str]:
    """The CSV cells of one line; a cell over :data:`MAX_CELL_CHARS` or bad quoting → GonioError."""
    if len(line) > MAX_CELL_CHARS:
        longest = max((len(c) for c in line.split(",")), default=0)
        if longest > MAX_CELL_CHARS:
            raise GonioError(f"a cell of {longest} characters, over the limit of "
                             f"{MAX_CELL_CHARS}", file=fname, line=idx)
    try:
        return next(csv.reader([line], strict=True))
    except csv.Error as exc:
        raise GonioError(f"bad CSV: {exc}", file=fname, line=idx) from None


def _frame(cols: dict[str, list], extras: list[str]) -> pd.DataFrame:
    data = pd.DataFrame({
        "test": pd.Series(cols["test"], dtype=object),
        "series": np.asarray(cols["series"], dtype=np.int64),
        "round": np.asarray(cols["round"], dtype=np.int64),
        "rate_dps": np.asarray(cols["rate_dps"], dtype=np.float64),
        "orientation": pd.Series(cols["orientation"], dtype=object),
        "time_s": np.asarray(cols["time_s"], dtype=np.float64),
        "table_deg": np.asarray(cols["table_deg"], dtype=np.float64),
        "gyro_counts": np.asarray(cols["gyro_counts"], dtype=np.float64),
        "gyro_deg": np.asarray(cols["gyro_deg"], dtype=np.float64),
    })
    for name in extras:
        data[name] = pd.Series(cols[name], dtype=object)
    data["line"] = np.asarray(cols["line"], dtype=np.int64)
    return data


def _number(row: dict, name: str, where: dict, *, required: bool) -> float:
    text = row.get(name, "")
    if text == "":
        if required:
            raise GonioError("empty cell, expected a number", column=name, **where)
        return math.nan
    value = parse_number(text)
    if value is None:
        raise GonioError(f"expected a number, got {_show(text)}", column=name, **where)
    if not math.isfinite(value):
        raise GonioError(f"expected a finite number, got {_show(text)}", column=name, **where)
    lo, hi = COLUMN_RANGES.get(name, (-math.inf, math.inf))
    if not lo <= value <= hi and not (name == "rate_dps" and value <= 0):
        raise GonioError(f"{_show(text)} is outside the plausible range [{lo:g}, {hi:g}] "
                         "(docs/formats.md)", column=name, **where)
    return value


def _positive_int(row: dict, name: str, where: dict) -> int:
    text = row.get(name, "")
    value = _number(row, name, where, required=True)
    if value != int(value) or value < 1 or value > 1_000_000:
        raise GonioError(f"expected an integer >= 1 (at most 1000000), got {_show(text)}",
                         column=name, **where)
    return int(value)


def _parse_row(row: dict, where: dict, quantised: bool) -> dict:
    test = row["test"]
    if test not in TEST_NAMES:
        raise GonioError(f"unknown test {_show(test)}, expected one of {', '.join(TEST_NAMES)}",
                         column="test", **where)
    series = _positive_int(row, "series", where)
    rnd = _positive_int(row, "round", where)
    rate = _number(row, "rate_dps", where, required=False)
    if math.isnan(rate):
        rate = DEFAULT_RATE_DPS
    elif rate <= 0:
        raise GonioError(f"expected a rate > 0 deg/s, got {_show(row['rate_dps'])}",
                         column="rate_dps", **where)
    orientation = row.get("orientation", "") or DEFAULT_ORIENTATION
    if orientation not in ORIENTATIONS:
        raise GonioError(f"unknown orientation {_show(orientation)}, expected one of "
                         f"{', '.join(ORIENTATIONS)}", column="orientation", **where)
    time_s = _number(row, "time_s", where, required=True)
    if time_s < 0:
        raise GonioError(f"time_s {_show(row['time_s'])} is before the zeroing it counts "
                         "from; expected a time >= 0 s", column="time_s", **where)
    table_deg = _number(row, "table_deg", where, required=test != "zero_stability")
    counts = _number(row, "gyro_counts", where, required=False)
    gyro_deg = _number(row, "gyro_deg", where, required=False)
    if math.isnan(counts) and math.isnan(gyro_deg):
        raise GonioError("neither gyro_counts nor gyro_deg given; expected one of them",
                         column="gyro_counts" if "gyro_counts" in row else "gyro_deg",
                         **where)
    if test == "scale_factor" and math.isnan(counts):
        raise GonioError("scale_factor readings need gyro_counts (draft 7.1 counts pulses)",
                         column="gyro_counts", **where)
    if not math.isnan(counts):
        text = row["gyro_counts"]
        if re.match(r"^[+-]?[0-9]+$", text):
            counts = float(int(text))
        elif quantised and counts != int(counts):
            raise GonioError(f"expected an integer pulse count, got {_show(text)} (metadata "
                             "counts_quantised: false allows fractions)",
                             column="gyro_counts", **where)
    return {"test": test, "series": series, "round": rnd, "rate_dps": rate,
            "orientation": orientation, "time_s": time_s, "table_deg": table_deg,
            "gyro_counts": counts, "gyro_deg": gyro_deg}


def _fmt_float(x) -> str:
    x = float(x)
    if math.isnan(x):
        return ""
    if not math.isfinite(x):
        raise GonioError(f"cannot write a non-finite value {x!r} to a readings file")
    return repr(x)


def _fmt_counts(x) -> str:
    x = float(x)
    if math.isnan(x):
        return ""
    if not math.isfinite(x):
        raise GonioError(f"cannot write a non-finite count {x!r} to a readings file")
    if x == int(x) and abs(x) < 2.0 ** 63:
        return str(int(x))
    return repr(x)


def _fmt_text(x) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return ""
    if isinstance(x, (float, np.floating)):
        return repr(float(x))
    return str(x)


def write_readings(readings_or_df: Readings | pd.DataFrame, path: str | Path,
                   metadata: Mapping[str, str] | None = None) -> Path:
    """Write a readings file in exactly the contract's format, atomically.

    The text is :func:`format_readings`'s.

    Column order ``test,series,round,rate_dps,orientation,time_s,table_deg,
    gyro_counts,gyro_deg`` then extra columns (the ``line`` column is not
    written). Floats are written with ``repr`` (they read back bit for bit),
    integer counts without ``.0``, NaN as an empty cell, ``\\n`` line ends.
    The same input always gives the same bytes.

    Parameters
    ----------
    readings_or_df : Readings or pandas.DataFrame
        The readings; a DataFrame needs the required columns (``rate_dps``
        and ``orientation`` default to 60 and ``up``).
    path : str or Path
        Target file (written via :func:`gonio.atomic.write_text`).
    metadata : mapping of str to str, optional
        ``# key: value`` lines; defaults to the Readings' own metadata.
        Fractional ``gyro_counts`` need ``counts_quantised: false``.

    Returns
    -------
    Path

    Examples
    --------
    >>> import tempfile, pathlib
    >>> df = pd.DataFrame({"test": ["scale_factor"], "series": [1], "round": [1],
    ...                    "time_s": [3.0], "table_deg": [60.0],
    ...                    "gyro_counts": [216000.0], "gyro_deg": [float("nan")]})
    >>> p = write_readings(df, pathlib.Path(tempfile.mkdtemp()) / "r.csv", {"serial": "42"})
    >>> print(p.read_text(), end="")
    # serial: 42
    test,series,round,rate_dps,orientation,time_s,table_deg,gyro_counts,gyro_deg
    scale_factor,1,1,60.0,up,3.0,60.0,216000,
    """
    return write_text(path, format_readings(readings_or_df, metadata))


def format_readings(readings_or_df: Readings | pd.DataFrame,
                    metadata: Mapping[str, str] | None = None) -> str:
    """The text of a readings file (what :func:`write_readings` writes), in memory.

    ``parse_readings(format_readings(df, md))`` validates readings built in memory
    (a reduced stream) exactly as the file reader would, without a file.

    >>> df = pd.DataFrame({"test": ["scale_factor"], "series": [1], "round": [1],
    ...                    "time_s": [3.0], "table_deg": [60.0], "gyro_counts": [216000.0]})
    >>> parse_readings(format_readings(df)).data["gyro_counts"].tolist()
    [216000.0]
    """
    if isinstance(readings_or_df, Readings):
        df = readings_or_df.data
        if metadata is None:
            metadata = readings_or_df.metadata
    else:
        df = readings_or_df
    metadata = dict(metadata or {})
    out = []
    for key, value in metadata.items():
        key, value = str(key), str(value)
        if not key.strip() or ":" in key or "\n" in key or "\r" in key \
                or "\n" in value or "\r" in value:
            raise GonioError("metadata key must be non-empty without ':' or line breaks, "
                             "value without line breaks", key=key)
        out.append(f"# {key.strip()}: {value.strip()}")
    quantised = metadata_bool(metadata, "counts_quantised", True)
    for name in REQUIRED_COLUMNS:
        if name not in df.columns:
            raise MissingColumnError("missing required column", column=name)
    n = len(df)
    if n == 0:
        raise GonioError("no readings to write (the protocol or the reduction produced none)")
    get = (lambda name, default: df[name] if name in df.columns
           else pd.Series([default] * n, index=df.index))
    counts = get("gyro_counts", math.nan).astype(float).to_numpy()
    if quantised:
        finite = counts[~np.isnan(counts)]
        if np.any(finite != np.round(finite)):
            raise GonioError("fractional gyro_counts need metadata 'counts_quantised: false'",
                             column="gyro_counts")
    # A missing rate stays an empty cell (the reader's default, 60 °/s, applies), so
    # zero-stability rows — the table at rest — carry no rate, as in docs/formats.md#which-cells-may-be-empty.
    rate = get("rate_dps", DEFAULT_RATE_DPS).astype(float)
    orient = get("orientation", DEFAULT_ORIENTATION).fillna(DEFAULT_ORIENTATION)
    extras = [c for c in df.columns if c not in COLUMNS and c != "line"]
    columns_text = [
        [_fmt_text(x) for x in df["test"]],
        [str(int(x)) for x in df["series"]],
        [str(int(x)) for x in df["round"]],
        [_fmt_float(x) for x in rate],
        [_fmt_text(x) or DEFAULT_ORIENTATION for x in orient],
        [_fmt_float(x) for x in df["time_s"]],
        [_fmt_float(x) for x in df["table_deg"]],
        [_fmt_counts(x) for x in counts],
        [_fmt_float(x) for x in get("gyro_deg", math.nan)],
    ] + [[_fmt_text(x) for x in df[c]] for c in extras]
    names = list(COLUMNS) + [str(c) for c in extras]
    out.append(_csv_line(names))
    for row in zip(*columns_text):
        out.append(_csv_line(row))
    return "\n".join(out) + "\n"


def _csv_line(cells) -> str:
    parts = []
    for c in cells:
        if any(ch in c for ch in ',"\n\r'):
            c = '"' + c.replace('"', '""') + '"'
        parts.append(c)
    return ",".join(parts)


def temperature_measured(path) -> dict:
    r"""The temperature an optical readings file (or a stream, CSV or Parquet) logged in its
    ``temperature_c`` column: the median of its finite values, as
    ``{"temperature_c": (text, where)}`` for the identity check (the specification's
    ``measured_conditions``, :func:`gonio.pipeline.identity.check_identity` ``measured``):
    the draft's room is the chamber the column logs (Table 2's (20 ± 1) °C), so a laboratory
    file stating 20.1 °C for readings that logged 35 °C is a contradiction, as the metadata
    line's would be. ``{}`` where there is no such column or no finite value in it (a blank
    between a slow logger's rows is no value).

    >>> import tempfile, os
    >>> d = tempfile.mkdtemp(); f = os.path.join(d, "r.csv")
    >>> _ = open(f, "w").write("# serial: A-1\ntest,temperature_c\nscale_factor,20.0\n"
    ...                        "scale_factor,\nscale_factor,20.4\n")
    >>> temperature_measured(f)["temperature_c"][0]
    '20.2'
    """
    from gonio.formats.metadata import logged_median

    found = logged_median(path)
    if found is None:
        return {}
    med, n = found
    return {"temperature_c": (f"{med:.6g}", f"the temperature_c column: median of {n} rows")}
