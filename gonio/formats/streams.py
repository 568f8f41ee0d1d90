"""Stream files: the instrument sampled continuously (``docs/formats.md#stream-file``).

Contents
========
=========================  ===================================================
:data:`STREAM_COLUMNS`     the written column order
:class:`Stream`            a validated stream held in memory
:class:`StreamChunk`       one chunk of :func:`iter_stream`
:func:`read_stream`        read, validate and unwrap a whole stream
:func:`iter_stream`        the same chunk by chunk, in bounded memory
:func:`unwrap_counts`      undo counter wrap-around (16, 24, 32, 64 bit)
:func:`write_stream`       write a stream file (atomic)
:class:`StreamWriter`      chunked writer (``gonio simulate --stream``)
:func:`sniff_kind`         ``"readings"`` or ``"stream"``, from the header row
=========================  ===================================================

A stream is CSV (UTF-8, BOM and CRLF tolerated): ``# key: value`` metadata lines,
one header row, then ``time_s,gyro_counts[,table_deg][,temperature_c]``. Metadata
``counter_bits`` (16, 24, 32, 64; default 64) and ``counter_signed`` (default true)
describe the pulse counter; ``counts_quantised: false`` allows fractional counts
(a virtual instrument with quantisation off; no wrap-around then).

Wrap-around (the one assumption): between two consecutive samples the counter
moves by less than half its range, ``|Δcount| < 2^(bits−1)``. Each difference is
then taken modulo ``2^bits`` into ``[−2^(bits−1), 2^(bits−1))`` and summed; the
unwrapped counter starts at the first value read.

Parsing is pandas' C reader (fast path); when a chunk fails to parse, the same
rows are re-read cell by cell to name the file, line and column of the first bad
value. Time must increase strictly; a step longer than ``max_gap_s`` (default
10× the median sample interval of the first chunk) is an error naming the line.
The input file is only read, never modified.
"""

from __future__ import annotations

import csv
import io as _io
import math
import os
import re
import tempfile
import contextlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator, Mapping

import numpy as np
import pandas as pd

from gonio.errors import GonioError, check_header
from gonio.formats.metadata import NUMERIC_METADATA, metadata_bool, metadata_float

#: Column order of a written stream file.
STREAM_COLUMNS: tuple[str, ...] = ("time_s", "gyro_counts", "table_deg", "temperature_c")
#: Columns a stream must have.
REQUIRED_STREAM_COLUMNS: tuple[str, ...] = ("time_s", "gyro_counts")
#: Counter widths the contract allows.
COUNTER_BITS: tuple[int, ...] = (16, 24, 32, 64)
_INT = re.compile(r"^\s*[+-]?\d+\s*$")
_FLOAT = re.compile(r"^\s*[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?\s*$")


@dataclass
class Stream:
    """A validated, unwrapped stream.

    Attributes
    ----------
    time_s : ndarray of float64
        Sample times, strictly increasing.
    gyro_counts : ndarray of int64 (float64 when ``counts_quantised: false``)
        The pulse counter, unwrapped.
    table_deg, temperature_c : ndarray of float64 or None
        Optional columns.
    metadata : dict of str to str
    path : Path or None
    """

    time_s: np.ndarray
    gyro_counts: np.ndarray
    table_deg: np.ndarray | None = None
    temperature_c: np.ndarray | None = None
    metadata: dict[str, str] = field(default_factory=dict)
    path: Path | None = None

    def __len__(self) -> int:
        return int(self.time_s.size)


@dataclass
class StreamChunk:
    """Rows ``first_row``… of a stream (0-based data-row index), already unwrapped."""

    time_s: np.ndarray
    gyro_counts: np.ndarray
    table_deg: np.ndarray | None
    temperature_c: np.ndarray | None
    first_row: int


@dataclass
class _Header:
    metadata: dict[str, str]
    columns: list[str]
    header_line: int      # 1-based line of the header row
    data_offset: int      # byte offset of the first data line
    bits: int
    signed: bool
    quantised: bool


def _parse_header(path: Path) -> _Header:
    """Metadata lines and header row, read line by line (never the whole file)."""
    fname = str(path)
    metadata: dict[str, str] = {}
    try:
        fh = open(path, "rb")
    except OSError as exc:
        raise GonioError(f"cannot read stream file: {exc.strerror}", file=path) from None
    with fh:
        lineno, offset = 0, 0
        while True:
            raw = fh.readline(1 << 20)
            if not raw:
                raise GonioError("no data: the file has no header row", file=fname,
                                 line=max(1, lineno))
            lineno += 1
            offset += len(raw)
            if lineno == 1 and raw.startswith(b"\xef\xbb\xbf"):
                raw = raw[3:]
            try:
                line = raw.decode("utf-8").rstrip("\r\n")
            except UnicodeDecodeError:
                raise GonioError("not UTF-8 text", file=fname, line=lineno) from None
            if "\x00" in line:
                raise GonioError("not UTF-8 text (NUL bytes; UTF-16?)", file=fname, line=lineno)
            if not line.strip():
                continue
            if line.lstrip().startswith("#"):
                key, sep, value = line.lstrip()[1:].partition(":")
                key = key.strip()
                if not sep or not key:
                    raise GonioError(f"bad metadata line, expected '# key: value', got {line!r}",
                                     file=fname, line=lineno)
                if key in metadata:
                    raise GonioError(f"metadata key {key!r} given twice", file=fname,
                                     line=lineno, key=key)
                metadata[key] = value.strip()
                continue
            columns = [h.strip() for h in next(csv.reader([line]))]
            break
    return _header_from(fname, metadata, columns, lineno, offset)


def _header_from(fname, metadata, columns, lineno, offset) -> _Header:
    seen = check_header(columns, REQUIRED_STREAM_COLUMNS, file=fname, line=lineno)
    for key in metadata:
        if key in NUMERIC_METADATA:
            metadata_float(metadata, key, file=fname)
    bits_text = metadata.get("counter_bits", "64").strip()
    if bits_text not in {str(b) for b in COUNTER_BITS}:
        raise GonioError(f"expected one of 16, 24, 32, 64, got {bits_text!r}", file=fname,
                         key="counter_bits")
    bits = int(bits_text)
    signed = metadata_bool(metadata, "counter_signed", True, file=fname)
    quantised = metadata_bool(metadata, "counts_quantised", True, file=fname)
    if not quantised and bits != 64:
        raise GonioError("fractional counts (counts_quantised: false) cannot wrap around; "
                         "counter_bits must be 64", file=fname, key="counter_bits")
    return _Header(metadata, columns, lineno, offset, bits, signed, quantised)


def counter_range(bits: int, signed: bool) -> tuple[int, int]:
    """Smallest and largest value a ``bits``-wide counter shows.

    >>> counter_range(16, True), counter_range(16, False)
    ((-32768, 32767), (0, 65535))
    """
    if signed:
        return -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    return 0, (1 << bits) - 1


def unwrap_counts(raw: np.ndarray, bits: int, previous: int | None = None) -> np.ndarray:
    """Unwrap a wrapped counter: differences modulo 2^bits into the signed half-range.

    Assumes ``|Δcount| < 2^(bits−1)`` between consecutive samples. ``previous``
    is the last *raw* value of the preceding chunk (its unwrapped value is
    carried by the caller); without it the first value is kept as read.
    Arithmetic is int64 (modulo 2^64, which is the 64-bit case).

    >>> unwrap_counts(np.array([32766, 32767, -32768, -32767]), 16).tolist()
    [32766, 32767, 32768, 32769]
    >>> unwrap_counts(np.array([1, 0, 65535, 65534]), 16).tolist()
    [1, 0, -1, -2]
    """
    c = np.asarray(raw).astype(np.int64, copy=False)
    if c.size == 0:
        return c.copy()
    d = np.empty_like(c)
    with np.errstate(over="ignore"):
        if previous is None:
            d[0] = c[0]
        else:
            d[0] = c[0] - np.int64(previous)
        d[1:] = c[1:] - c[:-1]
        if bits < 64:
            half = np.int64(1) << np.int64(bits - 1)
            mask = (np.int64(1) << np.int64(bits)) - np.int64(1)
            if previous is None:
                first = d[0]
                d = ((d + half) & mask) - half
                d[0] = first
            else:
                d = ((d + half) & mask) - half
        return np.cumsum(d)


def _data_lines(path: Path, header: _Header):
    """Yield (data row index, 1-based file line, raw bytes) of the non-blank data lines."""
    with open(path, "rb") as fh:
        fh.seek(header.data_offset)
        line = header.header_line
        n = -1
        for raw in fh:
            line += 1
            if raw.strip():
                n += 1
                yield n, line, raw


def _line_of_row(path: Path, header: _Header, row: int) -> int:
    """1-based file line of data row ``row`` (0-based, blank lines skipped); used on errors."""
    line = header.header_line
    for n, line, _ in _data_lines(path, header):
        if n == row:
            break
    return line


def _check_cell(text: str, col: str, header: _Header, where: dict):
    """Validate one cell the way the fast path does; raise naming the place."""
    t = text.strip()
    if col == "gyro_counts":
        if header.quantised:
            if not _INT.match(t):
                raise GonioError(f"expected an integer pulse count, got {text!r}",
                                 column=col, **where)
            lo, hi = counter_range(header.bits, header.signed)
            if header.bits == 64:
                lo, hi = -(1 << 63), (1 << 64) - 1 if not header.signed else (1 << 63) - 1
            if not lo <= int(t) <= hi:
                raise GonioError(f"count {t} outside the {header.bits}-bit "
                                 f"{'signed' if header.signed else 'unsigned'} counter range",
                                 column=col, **where)
            return
    if col == "temperature_c" and t == "":
        return
    if not _FLOAT.match(t):
        raise GonioError(f"expected a finite number, got {text!r}", column=col, **where)
    if not math.isfinite(float(t)):
        raise GonioError(f"expected a finite number, got {text!r}", column=col, **where)


def _locate_bad(path: Path, header: _Header, first_row: int, nrows: int, reason: str):
    """Re-read rows ``first_row``… cell by cell and raise for the first bad one."""
    fname = str(path)
    used = [c for c in header.columns if c in STREAM_COLUMNS]
    for n, line, raw in _data_lines(path, header):
        if n < first_row:
            continue
        if n >= first_row + nrows:
            break
        where = dict(file=fname, line=line)
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            raise GonioError("not UTF-8 text", **where) from None
        if text.lstrip().startswith("#"):
            raise GonioError("metadata line after the header; '#' lines belong at the top",
                             **where)
        try:
            cells = next(csv.reader([text.rstrip("\r\n")]))
        except (csv.Error, StopIteration):
            raise GonioError("unreadable CSV row", **where) from None
        if len(cells) != len(header.columns):
            raise GonioError(f"expected {len(header.columns)} fields as in the header, "
                             f"got {len(cells)}", **where)
        row = dict(zip(header.columns, cells))
        for col in used:
            _check_cell(row[col], col, header, where)
    raise GonioError(f"rows {first_row + 1}–{first_row + nrows} of the data do not parse "
                     f"({reason})", file=fname, line=header.header_line + first_row + 1)


def _dtypes(header: _Header) -> dict:
    dt: dict = {c: str for c in header.columns if c not in STREAM_COLUMNS}
    dt.update({"time_s": np.float64, "table_deg": np.float64, "temperature_c": np.float64})
    if not header.quantised:
        dt["gyro_counts"] = np.float64
    elif header.bits == 64 and not header.signed:
        dt["gyro_counts"] = np.uint64
    else:
        dt["gyro_counts"] = np.int64
    return {c: v for c, v in dt.items() if c in header.columns}


def iter_stream(path: str | Path, chunk_rows: int = 1_000_000, *,
                max_gap_s: float | None = None,
                _header: _Header | None = None) -> Iterator[StreamChunk]:
    """Read a stream chunk by chunk; unwrapping and time checks carry across chunks.

    Memory is bounded by ``chunk_rows`` whatever the file's length.

    Parameters
    ----------
    path : str or Path
    chunk_rows : int
        Rows per chunk (≥ 2).
    max_gap_s : float, optional
        Largest allowed step between samples; default 10× the median step of
        the first chunk.

    Yields
    ------
    StreamChunk

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.csv"
    >>> _ = p.write_text("# counter_bits: 16\\ntime_s,gyro_counts\\n"
    ...                  "0.0,32766\\n0.1,-32768\\n0.2,-32766\\n")
    >>> [c.gyro_counts.tolist() for c in iter_stream(p, chunk_rows=2)]
    [[32766, 32768], [32770]]
    """
    path = Path(path)
    header = _header or _parse_header(path)
    if chunk_rows < 2:
        raise GonioError(f"chunk_rows must be ≥ 2, got {chunk_rows}")
    fname = str(path)
    dtypes = _dtypes(header)
    lo, hi = counter_range(header.bits, header.signed)
    prev_raw: int | None = None
    prev_unwrapped = 0
    prev_t: float | None = None
    row0 = 0
    gap = max_gap_s
    fh = open(path, "rb")
    try:
        fh.seek(header.data_offset)
        reader = pd.read_csv(fh, header=None, names=header.columns, dtype=dtypes,
                             chunksize=chunk_rows, engine="c", skip_blank_lines=True,
                             keep_default_na=False, na_values=[""], comment=None,
                             encoding="utf-8", on_bad_lines="error", index_col=False)
        while True:
            try:
                df = next(reader)
            except StopIteration:
                break
            except (ValueError, OverflowError, TypeError, UnicodeDecodeError,
                    pd.errors.ParserError) as exc:
                _locate_bad(path, header, row0, chunk_rows, str(exc).splitlines()[0][:80])
            n = len(df)
            if n == 0:
                continue
            t = df["time_s"].to_numpy(np.float64)
            cols = {"table_deg": None, "temperature_c": None}
            bad = ~np.isfinite(t)
            if "table_deg" in df:
                cols["table_deg"] = df["table_deg"].to_numpy(np.float64)
                bad |= ~np.isfinite(cols["table_deg"])
            if "temperature_c" in df:
                cols["temperature_c"] = df["temperature_c"].to_numpy(np.float64)
                bad |= np.isinf(cols["temperature_c"])
            raw = df["gyro_counts"].to_numpy()
            if not header.quantised:
                raw = raw.astype(np.float64)
                bad |= ~np.isfinite(raw)
            elif header.bits < 64:
                bad |= (raw < lo) | (raw > hi)
            if bad.any():
                i = int(np.argmax(bad))
                _locate_bad(path, header, row0 + i, 1, "non-finite or out-of-range value")
            # time strictly increasing, gaps bounded
            dtt = np.diff(t) if prev_t is None else np.diff(np.concatenate(([prev_t], t)))
            if dtt.size and not np.all(dtt > 0):
                i = int(np.argmax(~(dtt > 0))) + (1 if prev_t is None else 0)
                raise GonioError("time_s must increase strictly", file=fname,
                                 line=_line_of_row(path, header, row0 + i), column="time_s")
            if gap is None and dtt.size:
                gap = 10.0 * float(np.median(dtt))
            if gap is not None and dtt.size and np.any(dtt > gap):
                i = int(np.argmax(dtt > gap)) + (1 if prev_t is None else 0)
                raise GonioError(f"gap of {float(dtt[np.argmax(dtt > gap)]):.6g} s in time_s "
                                 f"exceeds max_gap_s = {gap:.6g} s", file=fname,
                                 line=_line_of_row(path, header, row0 + i), column="time_s")
            if not header.quantised:
                counts = raw
            else:
                if raw.dtype == np.uint64:
                    raw = raw.view(np.int64)
                counts = unwrap_counts(raw, header.bits, prev_raw)
                if prev_raw is not None:
                    with np.errstate(over="ignore"):
                        counts = counts + np.int64(prev_unwrapped)
                prev_raw = int(raw[-1])
                prev_unwrapped = int(counts[-1])
            prev_t = float(t[-1])
            yield StreamChunk(t, counts, cols["table_deg"], cols["temperature_c"], row0)
            row0 += n
    finally:
        fh.close()
    if row0 == 0:
        raise GonioError("no data: header only", file=fname, line=header.header_line)


def read_stream(path: str | Path, *, chunk_rows: int = 1_000_000,
                max_gap_s: float | None = None) -> Stream:
    """Read, validate and unwrap a stream file (``docs/formats.md#stream-file``).

    Parameters
    ----------
    path : str or Path
        CSV stream (or ``.parquet`` when pyarrow is installed).
    chunk_rows : int
        Rows parsed at a time.
    max_gap_s : float, optional
        Largest allowed time step (default 10× the median step).

    Returns
    -------
    Stream

    Raises
    ------
    GonioError
        Naming file, line and column (or key) for any departure from the contract.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.csv"
    >>> _ = p.write_text("# counter_bits: 16\\n# counter_signed: false\\n"
    ...                  "time_s,gyro_counts,table_deg\\n0.00,65534,0.0\\n0.01,1,0.0\\n")
    >>> s = read_stream(p)
    >>> s.gyro_counts.tolist(), s.metadata["counter_bits"]
    ([65534, 65537], '16')
    """
    path = Path(path)
    if path.suffix.lower() == ".parquet":
        return _read_parquet(path, max_gap_s)
    header = _parse_header(path)
    parts = list(iter_stream(path, chunk_rows, max_gap_s=max_gap_s, _header=header))
    cat = (lambda name: np.concatenate([getattr(p, name) for p in parts])
           if getattr(parts[0], name) is not None else None)
    return Stream(cat("time_s"), cat("gyro_counts"), cat("table_deg"), cat("temperature_c"),
                  dict(header.metadata), path)


def _read_parquet(path: Path, max_gap_s: float | None) -> Stream:  # pragma: no cover - optional
    try:
        import pyarrow.parquet as pq
    except ImportError:
        raise GonioError("reading Parquet needs pyarrow (not installed)", file=path) from None
    try:
        tab = pq.read_table(path)
    except Exception as exc:  # noqa: BLE001 - any pyarrow failure is a bad file
        raise GonioError(f"cannot read Parquet: {exc}", file=path) from None
    md = {k.decode(): v.decode() for k, v in (tab.schema.metadata or {}).items()
          if not k.startswith(b"pandas")}
    header = _header_from(str(path), md, list(tab.column_names), 1, 0)
    df = tab.to_pandas()
    t = df["time_s"].to_numpy(np.float64)
    if not np.all(np.isfinite(t)) or not np.all(np.diff(t) > 0):
        raise GonioError("time_s must be finite and increase strictly", file=path,
                         column="time_s")
    raw = df["gyro_counts"].to_numpy()
    counts = raw.astype(np.float64) if not header.quantised else unwrap_counts(
        raw.astype(np.int64), header.bits)
    get = (lambda c: df[c].to_numpy(np.float64) if c in df else None)
    return Stream(t, counts, get("table_deg"), get("temperature_c"), md, path)


def _fmt_metadata(metadata: Mapping[str, str]) -> str:
    out = []
    for key, value in metadata.items():
        key, value = str(key), str(value)
        if not key.strip() or ":" in key or any(c in key + value for c in "\r\n"):
            raise GonioError("metadata key must be non-empty without ':' or line breaks, "
                             "value without line breaks", key=key)
        out.append(f"# {key.strip()}: {value.strip()}\n")
    return "".join(out)


class StreamWriter:
    """Write a stream chunk by chunk; the file appears (atomically) only at :meth:`close`.

    Counts are given unwrapped and written wrapped to the counter width in
    ``metadata`` (``counter_bits``, ``counter_signed``). Use as a context manager:
    an exception inside the ``with`` leaves no file behind.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.csv"
    >>> with StreamWriter(p, {"counter_bits": "16"}, table=True) as w:
    ...     w.write(np.array([0.0, 0.5]), np.array([32767.0, 32768.0]), np.array([0.0, 1.5]))
    >>> print(p.read_text(), end="")
    # counter_bits: 16
    time_s,gyro_counts,table_deg
    0.0,32767,0.0
    0.5,-32768,1.5
    """

    def __init__(self, path: str | Path, metadata: Mapping[str, str] | None = None, *,
                 table: bool = True, temperature: bool = False):
        self.path = Path(path)
        md = {str(k): str(v) for k, v in (metadata or {}).items()}
        self._header = _header_from(str(self.path), md, ["time_s", "gyro_counts"], 1, 0)
        self.table, self.temperature = table, temperature
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd, self._tmp = tempfile.mkstemp(prefix=f".{self.path.name}.", suffix=".tmp",
                                         dir=self.path.parent)
        umask = os.umask(0)             # mkstemp makes 0600; every output is 0666 & ~umask
        os.umask(umask)
        os.fchmod(fd, 0o666 & ~umask)
        self._fh = os.fdopen(fd, "wb")
        cols = ["time_s", "gyro_counts"] + (["table_deg"] if table else []) \
            + (["temperature_c"] if temperature else [])
        self._ncol = len(cols)
        self._fh.write((_fmt_metadata(md) + ",".join(cols) + "\n").encode())
        self._last_t = -math.inf
        self.rows = 0

    def write(self, time_s, counts, table_deg=None, temperature_c=None) -> None:
        """Append rows; ``counts`` unwrapped (integers unless ``counts_quantised: false``)."""
        t = np.asarray(time_s, dtype=np.float64)
        if t.size == 0:
            return
        if not np.all(np.isfinite(t)) or not (t[0] > self._last_t and np.all(np.diff(t) > 0)):
            raise GonioError("stream times must be finite and increase strictly")
        c = np.asarray(counts)
        h = self._header
        if h.quantised:
            cf = np.asarray(c, dtype=np.float64)
            if not np.all(np.isfinite(cf)) or np.any(cf != np.round(cf)):
                raise GonioError("counts must be integers (or metadata counts_quantised: false)")
            from gonio.formats.counters import wrap_counter
            ctext = wrap_counter(c, h.bits, h.signed).astype(str)
        else:
            ctext = np.array([repr(float(x)) for x in c], dtype=object)
        cols = [np.array([repr(float(x)) for x in t], dtype=object), ctext]
        for flag, arr, name in ((self.table, table_deg, "table_deg"),
                                (self.temperature, temperature_c, "temperature_c")):
            if flag:
                a = np.asarray(arr, dtype=np.float64)
                if a.shape != t.shape or not np.all(np.isfinite(a)):
                    raise GonioError(f"{name} must be finite, one value per sample")
                cols.append(np.array([repr(float(x)) for x in a], dtype=object))
        lines = cols[0].astype(object)
        for col in cols[1:]:
            lines = lines + "," + col.astype(object)
        self._fh.write(("\n".join(lines.tolist()) + "\n").encode())
        self._last_t = float(t[-1])
        self.rows += int(t.size)

    def close(self) -> Path:
        """Flush, fsync and move the file into place."""
        if self._fh.closed:
            return self.path
        self._fh.flush()
        os.fsync(self._fh.fileno())
        self._fh.close()
        os.replace(self._tmp, self.path)
        return self.path

    def abort(self) -> None:
        """Drop the partial file."""
        if not self._fh.closed:
            self._fh.close()
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self._tmp)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            self.close()
        else:
            self.abort()
        return False


def write_stream(path: str | Path, time_s, counts, table_deg=None,
                 metadata: Mapping[str, str] | None = None, temperature_c=None) -> Path:
    """Write a whole stream file atomically (counts given unwrapped, written wrapped).

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.csv"
    >>> _ = write_stream(p, [0.0, 0.01], [65535, 65536], [0.0, 0.0],
    ...                  {"counter_bits": "16", "counter_signed": "false"})
    >>> read_stream(p).gyro_counts.tolist()
    [65535, 65536]
    """
    with StreamWriter(path, metadata, table=table_deg is not None,
                      temperature=temperature_c is not None) as w:
        w.write(time_s, counts, table_deg, temperature_c)
    return Path(path)


def sniff_kind(path: str | Path) -> str:
    """``"readings"`` or ``"stream"``, told from the header row.

    A header with ``test`` is a readings file (section 1); one with ``time_s``
    and ``gyro_counts`` but no ``test`` is a stream (section 2).

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "x.csv"
    >>> _ = p.write_text("# a: b\\ntime_s,gyro_counts\\n0,1\\n")
    >>> sniff_kind(p)
    'stream'
    """
    path = Path(path)
    if path.suffix.lower() == ".parquet":
        return "stream"
    try:
        h = _parse_header(path)
    except GonioError as exc:
        if "missing required column" not in exc.message:
            # let the readings reader report what is wrong with this file
            return "readings"
        cols = _first_header(path)
        return "readings" if "test" in cols or "time_s" not in cols else "stream"
    return "readings" if "test" in h.columns else "stream"


def _first_header(path: Path) -> list[str]:
    with open(path, "rb") as fh:
        for raw in fh:
            line = raw.decode("utf-8", "replace").lstrip("\ufeff").strip()
            if line and not line.startswith("#"):
                return [c.strip() for c in next(csv.reader([line]))]
    return []
