"""Stream files: the instrument sampled continuously (``docs/formats.md#stream-file``).

Contents
========
=========================  ===================================================
:data:`STREAM_COLUMNS`     the written column order
:class:`Stream`            a validated stream held in memory
:class:`StreamChunk`       one chunk of :func:`iter_stream`
:class:`StreamFile`        a stream file (CSV or Parquet) read in blocks, indexed
:func:`read_stream`        read, validate and unwrap a whole stream into memory
:func:`iter_stream`        the same chunk by chunk, in bounded memory
:func:`unwrap_counts`      undo counter wrap-around (16, 24, 32, 64 bit)
:func:`write_stream`       write a stream file (atomic)
:class:`StreamWriter`      chunked writer, CSV or Parquet (``gonio simulate --stream``)
:func:`sniff_kind`         ``"readings"`` or ``"stream"``, from the header row
=========================  ===================================================

A stream is CSV (UTF-8, BOM tolerated, lines ending in LF, CRLF or a lone CR):
``# key: value`` metadata lines, one header row, then
``time_s,gyro_counts[,table_deg][,temperature_c]``; or Parquet with the same
columns and the metadata as the file's key-value metadata. Metadata
``counter_bits`` (16, 24, 32, 64; default 64) and ``counter_signed`` (default true)
describe the pulse counter; ``counts_quantised: false`` allows fractional counts
(a virtual instrument with quantisation off; no wrap-around then).

Wrap-around (the one assumption): between two consecutive samples the counter
moves by less than half its range, ``|Δcount| < 2^(bits−1)``. Each difference is
then taken modulo ``2^bits`` into ``[−2^(bits−1), 2^(bits−1))`` and summed; the
unwrapped counter starts at the first value read.

Parsing is pyarrow's (CSV and Parquet), block by block; when a CSV block fails
to parse, its lines are re-read cell by cell to name the file, line and column
of the first bad value (Parquet: the data row). Time must increase strictly; a
step longer than ``max_gap_s`` (default 10× the median sample interval of the
first block) is an error naming the line; the unwrapped counter is checked
against a plausible rate and against ``table_deg`` (:class:`StreamFile`), so a
counter that overflowed between samples is caught, not unwrapped silently wrong.
The input file is only read, never modified.
"""

from __future__ import annotations

import csv
import math
import os
import re
import tempfile
import contextlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator, Mapping

import numpy as np

from gonio.errors import GonioError, MissingColumnError, check_header, check_not_binary
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
    header_line: int | None   # 1-based line of the header row (None: Parquet)
    data_offset: int      # byte offset of the first data line
    bits: int
    signed: bool
    quantised: bool


def _lines_with_ends(fh, piece: int = 1 << 16):
    """Lines of a binary file with their ends (LF, CRLF or a lone CR), read piece by piece."""
    buf = b""
    eof = False
    while True:
        i = 0
        while True:
            j = min((k for k in (buf.find(b"\n", i), buf.find(b"\r", i)) if k >= 0), default=-1)
            if j < 0:
                break
            if buf[j] == 13:
                if j + 1 >= len(buf) and not eof:
                    break                       # CR at the end of what was read: CRLF?
                if j + 1 < len(buf) and buf[j + 1] == 10:
                    j += 1
            yield buf[i:j + 1]
            i = j + 1
        buf = buf[i:]
        if eof:
            if buf:
                yield buf
            return
        more = fh.read(piece)
        if not more:
            eof = True
        buf += more


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
        lines = _lines_with_ends(fh)
        while True:
            raw = next(lines, None)
            if raw is None:
                raise GonioError("no data: the file has no header row", file=fname,
                                 line=max(1, lineno))
            lineno += 1
            offset += len(raw)
            if lineno == 1 and raw.startswith(b"\xef\xbb\xbf"):
                raw = raw[3:]
            if lineno == 1:
                check_not_binary(raw, fname)          # a Parquet file renamed .csv says so
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
    d = _unwrap_steps(c, bits, previous)
    with np.errstate(over="ignore"):
        return np.cumsum(d, out=d)


def _unwrap_steps(c: np.ndarray, bits: int, previous: int | None) -> np.ndarray:
    """The unwrapped counter's steps (int64, in one new array, formed in place): ``c[0]``
    as read (``previous`` None) or its wrapped step from ``previous``, then the wrapped
    steps ``c[i] − c[i−1]``; their cumulative sum is :func:`unwrap_counts`."""
    d = np.empty(c.size, dtype=np.int64)
    with np.errstate(over="ignore"):
        d[0] = c[0] if previous is None else c[0] - np.int64(previous)
        np.subtract(c[1:], c[:-1], out=d[1:])
        if bits < 64:
            half = np.int64(1) << np.int64(bits - 1)
            mask = (np.int64(1) << np.int64(bits)) - np.int64(1)
            w = d if previous is not None else d[1:]
            np.add(w, half, out=w)
            np.bitwise_and(w, mask, out=w)
            np.subtract(w, half, out=w)
    return d


def split_lines(data: bytes):
    """Yield ``(line_offset, text_bytes)`` for each line of ``data``; a line ends at LF,
    CRLF or a lone CR (the reader accepts all three), the end is not part of the text.

    >>> [x for _, x in split_lines(b"a\\r\\nb\\rc\\n\\nd")]
    [b'a', b'b', b'c', b'', b'd']
    """
    i, n = 0, len(data)
    while i < n:
        j = i
        while j < n and data[j] not in (10, 13):
            j += 1
        yield i, data[i:j]
        if j < n and data[j] == 13 and j + 1 < n and data[j + 1] == 10:
            j += 1
        i = j + 1


def count_lines(data: bytes) -> int:
    """Line ends in ``data`` (LF, CRLF and lone CR each count once).

    >>> count_lines(b"a\\r\\nb\\rc\\n")
    3
    """
    return data.count(b"\n") + data.count(b"\r") - data.count(b"\r\n")


def _check_cell(text: str, col: str, header: _Header, where: dict):
    """Validate one cell the way the fast path does; raise naming the place."""
    t = text.strip()
    if col == "gyro_counts":
        if header.quantised:
            if not _INT.match(t):
                raise GonioError(f"expected an integer pulse count, got {_clip(text)!r}",
                                 column=col, **where)
            lo, hi = counter_range(header.bits, header.signed)
            if not lo <= int(t) <= hi:
                raise GonioError(f"count {_clip(t)} outside the {header.bits}-bit "
                                 f"{'signed' if header.signed else 'unsigned'} counter range",
                                 column=col, **where)
            return
    if col == "temperature_c" and t == "":
        return
    if not _FLOAT.match(t):
        raise GonioError(f"expected a finite number, got {_clip(text)!r}", column=col, **where)
    if not math.isfinite(float(t)):
        raise GonioError(f"expected a finite number, got {_clip(text)!r}", column=col, **where)


def _clip(text: str, n: int = 40) -> str:
    return text if len(text) <= n else text[:n] + "…"


#: Bytes of CSV parsed at a time (a block ends at a line end).
CSV_BLOCK_BYTES = 1 << 23
#: Default plausible rate bound, °/s, for the unwrapped counter (metadata ``max_rate_dps``
#: overrides it): well above the draft's Table 1 table rates (0–300 °/s).
PLAUSIBLE_RATE_DPS = 1000.0


@dataclass
class _Block:
    """One block of a stream file as stored (CSV bytes range or a Parquet row group)."""

    first_row: int
    n_rows: int
    first_line: int          # CSV: 1-based line of the block's first line; Parquet: 0
    start: int               # CSV: byte offset; Parquet: row-group index
    stop: int                # CSV: byte offset after the block
    t_first: float
    t_last: float
    prev_raw: int | None     # raw counter value before the block (unwrap carry)
    prev_unwrapped: int


@dataclass
class _PassState:
    """What the checking pass carries from one row to the next (:meth:`StreamFile.chunks`)."""

    gap: float | None                   # max_gap_s (None until the first block sets it)
    prev_raw: int | None = None         # last raw counter value (unwrap carry)
    prev_unwrapped: int = 0             # … and its unwrapped value
    prev_t: float | None = None
    prev_c: object = None               # last unwrapped count (rate check)
    check_table: bool = False           # the counter is checked against table_deg
    table: dict = field(default_factory=lambda: {"resid": np.empty(0), "med": None})


#: Rows checked at a time: a piece's arrays (512 kB each) stay in the core's L2/L3 cache,
#: which makes the dozen passes of the checks several times faster than over a whole
#: block; smaller pieces cost more in per-call overhead (2¹⁶ measured best on 2¹⁵–2¹⁷).
CHECK_PIECE_ROWS = 1 << 16


def _read_ahead(blocks):
    """Iterate ``blocks`` (a generator) with the next item produced in a worker thread
    while the caller works on this one: pyarrow parses and decodes without holding the
    GIL, so reading overlaps checking. At most one item is made ahead (memory: two
    blocks). An exception in the generator is raised to the caller at the item where it
    happened; closing the iterator stops the thread and closes the generator."""
    import threading
    import queue
    ask = threading.Semaphore(1)            # permits to make one more item
    got: queue.Queue = queue.Queue()
    stop = threading.Event()

    def work():
        try:
            while True:
                ask.acquire()
                if stop.is_set():
                    return
                try:
                    item = next(blocks)
                except StopIteration:
                    got.put(("end", None))
                    return
                except BaseException as exc:        # handed to the caller, in order
                    got.put(("error", exc))
                    return
                got.put(("item", item))
        finally:
            blocks.close()

    th = threading.Thread(target=work, name="gonio-read-ahead", daemon=True)
    th.start()
    try:
        while True:
            kind, value = got.get()
            if kind == "end":
                return
            if kind == "error":
                raise value
            ask.release()                  # make the next one while this one is used
            yield value
            value = None
    finally:
        stop.set()
        ask.release()
        th.join()


class StreamFile:
    """A stream file (CSV or Parquet) read in blocks: validated, unwrapped, in bounded memory.

    :meth:`chunks` reads the file once from start to end (validating every value,
    unwrapping the counter across blocks); after that pass the file is indexed and
    :meth:`window`, :meth:`search`, :meth:`time_at` and :meth:`counts_at` give any
    samples by re-reading only the blocks that hold them (a few are cached).
    Memory is a few blocks, whatever the file's length.

    CSV is parsed with pyarrow; a block that fails to parse is re-read cell by cell
    to name the line and column of the first bad value. Parquet: the stream's
    metadata is the file's key-value metadata, one row group is a block, and an
    error names the data row (1-based) and column.

    Checks, beyond each value's type and range (docs/formats.md#stream-file): time strictly
    increasing, no gap above ``max_gap_s``; with the metadata
    ``nominal_scale_factor_counts_per_deg`` (K), the unwrapped counter must move
    at a plausible rate (|Δcount|/(K Δt) ≤ ``max_rate_dps``, metadata or
    :data:`PLAUSIBLE_RATE_DPS`), and, with ``table_deg`` and a counter narrower
    than 64 bits, agree with the table: the step of ``count/K − table_deg``
    (median of three, so one-sample encoder glitches pass) must stay below a
    quarter of the counter's range in degrees, 2^bits/(4K). A counter that
    overflowed between two samples (moved by more than half its range) is
    unwrapped by a whole range too little or too much, and that step shows it.
    """

    def __init__(self, path: str | Path, *, max_gap_s: float | None = None,
                 block_bytes: int = CSV_BLOCK_BYTES, cache_blocks: int = 3):
        self.path = Path(path)
        self.fname = str(self.path)
        self.kind = "parquet" if self.path.suffix.lower() == ".parquet" else "csv"
        self.max_gap_s = max_gap_s
        self.block_bytes = int(block_bytes)
        self._pq = None
        if self.kind == "parquet":
            self._pq, md, cols = _open_parquet(self.path)
            self.header = _header_from(self.fname, md, cols, None, 0)
        else:
            self.header = _parse_header(self.path)
        h = self.header
        self.metadata = dict(h.metadata)
        self.columns = [c for c in h.columns if c in STREAM_COLUMNS]
        self.k_nominal = metadata_float(h.metadata, "nominal_scale_factor_counts_per_deg",
                                        file=self.fname) if \
            "nominal_scale_factor_counts_per_deg" in h.metadata else None
        self.rate_bound_dps = metadata_float(h.metadata, "max_rate_dps", file=self.fname) \
            if "max_rate_dps" in h.metadata else PLAUSIBLE_RATE_DPS
        if not (self.rate_bound_dps is not None and math.isfinite(self.rate_bound_dps)
                and self.rate_bound_dps > 0):
            raise GonioError(f"expected a number > 0, got {h.metadata.get('max_rate_dps')!r}",
                             file=self.fname, key="max_rate_dps")
        self.blocks: list[_Block] | None = None
        self._cache: dict[int, StreamChunk] = {}
        self._cache_order: list[int] = []
        self._cache_max = max(1, cache_blocks)

    # ------------------------------------------------------------------ raw blocks
    def _raw_blocks(self):
        """Yield (start, stop, first_line, arrays dict) of the stored blocks, in order."""
        if self.kind == "parquet":
            for g in range(self._pq.num_row_groups):
                yield g, g + 1, 0, self._parquet_group(g)
            return
        h = self.header
        with open(self.path, "rb") as fh:
            fh.seek(h.data_offset)
            offset = h.data_offset
            carry = b""
            while True:
                # the block is read straight after the carried partial line (no copy
                # of the block to join them, none to cut it: a view is parsed)
                buf = bytearray(len(carry) + self.block_bytes)
                buf[:len(carry)] = carry
                got = fh.readinto(memoryview(buf)[len(carry):])
                data = got > 0
                del buf[len(carry) + got:]
                if not buf:
                    break
                if data:
                    cut = max(buf.rfind(b"\n"), buf.rfind(b"\r"))
                    if cut == len(buf) - 1 and buf[cut] == 13:
                        # a CR at the very end may be half of a CRLF: cut before it
                        cut = max(buf.rfind(b"\n", 0, cut), buf.rfind(b"\r", 0, cut))
                    if cut < 0:
                        carry = bytes(buf)
                        continue
                    block, carry = memoryview(buf)[:cut + 1], bytes(buf[cut + 1:])
                else:
                    block, carry = memoryview(buf), b""
                arrays = self._parse_csv(block, offset)
                yield offset, offset + len(block), 0, arrays
                offset += len(block)
                if not data:
                    break

    def _read_block(self, blk: _Block) -> dict:
        if self.kind == "parquet":
            return self._parquet_group(blk.start)
        with open(self.path, "rb") as fh:
            fh.seek(blk.start)
            data = fh.read(blk.stop - blk.start)
        return self._parse_csv(data, blk.start)

    def _line_at(self, offset: int) -> int:
        """1-based line number of the line starting at byte ``offset`` of a CSV stream
        (counted when an error is reported, so the fast path never counts lines)."""
        h = self.header
        line = h.header_line + 1
        with open(self.path, "rb") as fh:
            fh.seek(h.data_offset)
            pos, prev_cr = h.data_offset, False
            while pos < offset:
                piece = fh.read(min(1 << 24, offset - pos))
                if not piece:
                    break
                line += count_lines(piece)
                if prev_cr and piece.startswith(b"\n"):
                    line -= 1               # a CRLF split between two pieces
                prev_cr = piece.endswith(b"\r")
                pos += len(piece)
        return line

    def _csv_types(self) -> dict:
        import pyarrow as pa
        h = self.header
        types = {"time_s": pa.float64(), "table_deg": pa.float64(),
                 "temperature_c": pa.float64()}
        if not h.quantised:
            types["gyro_counts"] = pa.float64()
        elif h.bits == 64 and not h.signed:
            types["gyro_counts"] = pa.uint64()
        else:
            types["gyro_counts"] = pa.int64()
        return {c: t for c, t in types.items() if c in self.columns}

    def _parse_csv(self, data: bytes, offset: int) -> dict:
        import pyarrow as pa
        import pyarrow.csv as pcsv
        h = self.header
        def parse(types):
            return pcsv.read_csv(
                pa.BufferReader(data),
                read_options=pcsv.ReadOptions(column_names=h.columns, block_size=1 << 22),
                parse_options=pcsv.ParseOptions(newlines_in_values=False,
                                                ignore_empty_lines=True),
                convert_options=pcsv.ConvertOptions(column_types=types,
                                                    include_columns=self.columns,
                                                    null_values=[""],
                                                    strings_can_be_null=False,
                                                    quoted_strings_can_be_null=False))
        errors = (pa.ArrowInvalid, pa.ArrowNotImplementedError, pa.ArrowCapacityError,
                  UnicodeDecodeError)
        types = self._csv_types()
        try:
            tab = parse(types)
        except errors as exc:
            tab = None
            data = bytes(data)
            reason = str(exc).splitlines()[0][:80]
            if h.quantised and "gyro_counts" in types:
                # pyarrow's integer parser refuses a leading '+' ("+000123", which the
                # contract allows): read the counts as text, drop the sign, convert.
                import pyarrow.compute as pc
                try:
                    tab = parse(dict(types, gyro_counts=pa.string()))
                    txt = pc.replace_substring_regex(pc.utf8_trim_whitespace(
                        tab.column("gyro_counts")), pattern=r"^\+", replacement="")
                    tab = tab.set_column(tab.schema.get_field_index("gyro_counts"),
                                         "gyro_counts", pc.cast(txt, types["gyro_counts"]))
                except errors:
                    tab = None
            if tab is None:
                self._locate_bad(data, self._line_at(offset), reason)
        return _columns(tab, self.columns)

    def _parquet_group(self, g: int) -> dict:
        import pyarrow as pa
        try:
            # one thread: decoding a row group in parallel gains little on a few cores
            # and keeps a buffer per thread (tens of MB of resident memory)
            tab = self._pq.read_row_group(g, columns=self.columns, use_threads=False)
        except (OSError, pa.ArrowException) as exc:
            raise GonioError(f"cannot read Parquet row group {g}: {_clip(str(exc), 80)}",
                             file=self.fname) from None
        return _columns(tab, self.columns)

    # ------------------------------------------------------------------ locating errors
    def _locate_bad(self, data: bytes, first_line: int, reason: str):
        """Re-read a CSV block cell by cell and raise for the first bad one."""
        h = self.header
        line = first_line
        try:
            for _, raw in split_lines(data):
                where = dict(file=self.fname, line=line)
                line += 1
                if not raw:
                    continue
                try:
                    text = raw.decode("utf-8")
                except UnicodeDecodeError:
                    raise GonioError("not UTF-8 text", **where) from None
                if text.lstrip().startswith("#"):
                    raise GonioError("metadata line after the header; '#' lines belong at the "
                                     "top", **where)
                try:
                    cells = next(csv.reader([text]))
                except (csv.Error, StopIteration):
                    raise GonioError("unreadable CSV row", **where) from None
                if len(cells) != len(h.columns):
                    raise GonioError(f"expected {len(h.columns)} fields as in the header, "
                                     f"got {len(cells)}", **where)
                row = dict(zip(h.columns, cells))
                for col in self.columns:
                    _check_cell(row[col], col, h, where)
        except GonioError:
            raise
        raise GonioError(f"lines {first_line}–{line - 1} do not parse ({_clip(reason, 80)})",
                         file=self.fname, line=first_line)

    def _where(self, blk_first_line: int, blk_data_start: int, row_in_block: int,
               first_row: int) -> dict:
        """File location of a data row: CSV line (re-counted in its block) or Parquet row."""
        if self.kind == "parquet":
            return dict(file=self.fname, line=None, row=first_row + row_in_block + 1)
        with open(self.path, "rb") as fh:
            fh.seek(blk_data_start)
            data = fh.read(self.block_bytes + (1 << 20))
        line = self._line_at(blk_data_start)
        k = -1
        for _, raw in split_lines(data):
            if raw.strip():
                k += 1
                if k == row_in_block:
                    return dict(file=self.fname, line=line, row=None)
            line += 1
        return dict(file=self.fname, line=line, row=None)

    def _fail(self, message: str, column: str, loc: dict):
        if loc["row"] is not None:
            message = f"data row {loc['row']}: {message}"
        raise GonioError(message, file=loc["file"], line=loc["line"], column=column)

    # ------------------------------------------------------------------ the pass
    def chunks(self, chunk_rows: int | None = None) -> Iterator[StreamChunk]:
        """Validated, unwrapped chunks from the start (``chunk_rows`` rows each; default:
        one per stored block). Indexes the file on the way.

        The next block is parsed or decoded in a worker thread while this one is checked
        and used (:func:`_read_ahead`: pyarrow releases the GIL for the whole block; the
        checks stay in this thread, because many short numpy passes in two threads
        mostly wait for each other's GIL). The checks run :data:`CHECK_PIECE_ROWS` rows at
        a time, so each pass over a piece stays in the core's cache. Errors are raised in
        file order: the first bad row of the first piece that has one."""
        if chunk_rows is not None and chunk_rows < 2:
            raise GonioError(f"chunk_rows must be ≥ 2, got {chunk_rows}")
        blocks: list[_Block] = []
        ahead = _read_ahead(self._raw_blocks())
        try:
            for blk, arr, counts in self._checked_blocks(ahead):
                blocks.append(blk)
                n, row0 = blk.n_rows, blk.first_row
                t, tab, tmp = arr["time_s"], arr.get("table_deg"), arr.get("temperature_c")
                step_rows = n if chunk_rows is None else chunk_rows
                for a in range(0, n, step_rows):
                    b = min(n, a + step_rows)
                    yield StreamChunk(t[a:b], counts[a:b], None if tab is None else tab[a:b],
                                      None if tmp is None else tmp[a:b], row0 + a)
        finally:
            # stop the worker now, also when a check raised: the exception's traceback
            # keeps these frames (and so the reader) alive until it is collected
            ahead.close()
        if not blocks:
            raise GonioError("no data: header only", file=self.fname,
                             line=self.header.header_line)
        self.blocks = blocks
        release_arrow_memory()

    def _checked_blocks(self, raw_blocks):
        """Yield (block, arrays, unwrapped counts) of every non-empty block of ``raw_blocks``
        (:meth:`_raw_blocks`), checked."""
        h = self.header
        st = _PassState(gap=self.max_gap_s, check_table=self.k_nominal is not None
                        and "table_deg" in self.columns and h.bits < 64 and h.quantised)
        row0 = 0
        for start, stop, first_line, arr in raw_blocks:
            n = arr["time_s"].size
            if n == 0:
                continue

            def loc(i, _fl=first_line, _st=start, _r0=row0):
                return self._where(_fl, _st, i, _r0)

            t = arr["time_s"]
            if st.gap is None:
                # 10 × the median interval of the first block (when it is readable: a bad
                # value there stops the pass in this block anyway)
                dtt = _diff_after(st.prev_t, t)
                if dtt.size and np.isfinite(dtt).all() and dtt.min() > 0:
                    st.gap = 10.0 * float(np.median(dtt))
                del dtt
            blk = _Block(row0, n, first_line, start, stop, float(t[0]), float(t[-1]),
                         st.prev_raw, st.prev_unwrapped)
            counts = np.empty(n, dtype=np.float64 if not h.quantised else np.int64)
            for p in range(0, n, CHECK_PIECE_ROWS):
                q = min(n, p + CHECK_PIECE_ROWS)
                self._check_rows(arr, p, q, st, counts[p:q], row0 + p,
                                 lambda i, _p=p: loc(_p + i))
            yield blk, arr, counts
            row0 += n

    def _check_rows(self, arr: dict, p: int, q: int, st: "_PassState", out: np.ndarray,
                    first_row: int, loc) -> None:
        """Check rows ``p … q−1`` of a block and write their unwrapped counts to ``out``;
        ``loc(i)`` locates row ``p + i``; ``st`` carries the pass across rows.

        The checks, in this order for the piece: every value finite (and no empty cell),
        counts integer and inside the counter's range, time strictly increasing with no
        gap above ``max_gap_s``, the counter's rate, the counter against the table."""
        h = self.header
        k = self.k_nominal
        t = arr["time_s"][p:q]
        dtt = _diff_after(st.prev_t, t)
        off = 1 if st.prev_t is None else 0
        # strictly increasing between finite ends: then every time is finite (a NaN fails
        # the comparison), and the column needs no pass of its own
        dt_min = float(dtt.min()) if dtt.size else math.inf
        time_ok = math.isfinite(t[0]) and math.isfinite(t[-1]) and dt_min > 0 and \
            "time_s#null" not in arr
        for col in self.columns:
            if col == "time_s" and time_ok:
                continue
            a = arr[col][p:q]
            nulls = arr.get(col + "#null")
            if nulls is not None:
                nulls = nulls[p:q]
                if col != "temperature_c" and nulls.any():
                    i = int(np.argmax(nulls))
                    self._fail("expected a finite number, got an empty cell", col, loc(i))
            # the sum is finite when every value is (one pass, nothing allocated);
            # only rows whose sum is not are looked at value by value
            if a.dtype.kind == "f" and (nulls is not None or not _finite_sum(a)):
                bad = ~np.isfinite(a)
                if nulls is not None:         # empty temperature cells are allowed
                    bad &= ~nulls
                if bad.any():
                    i = int(np.argmax(bad))
                    self._fail(f"expected a finite number, got {a[i]!r}", col, loc(i))
        raw = arr["gyro_counts"][p:q]
        if h.quantised and raw.dtype.kind == "f":
            self._fail("expected integer pulse counts (or metadata counts_quantised: "
                       "false)", "gyro_counts", loc(0))
        lo, hi = counter_range(h.bits, h.signed)
        if h.quantised and h.bits < 64 and not lo <= int(raw.min()) <= int(raw.max()) <= hi:
            bad = (raw < lo) | (raw > hi)
            i = int(np.argmax(bad))
            self._fail(f"count {int(raw[i])} outside the {h.bits}-bit "
                       f"{'signed' if h.signed else 'unsigned'} counter range",
                       "gyro_counts", loc(i))
        elif h.quantised and raw.dtype == np.int64 and not h.signed:
            bad = raw < 0
            if bad.any():
                i = int(np.argmax(bad))
                self._fail(f"count {int(raw[i])} outside the 64-bit unsigned counter range",
                           "gyro_counts", loc(i))
        # time strictly increasing, gaps bounded
        if not time_ok and dtt.size and not dt_min > 0:
            i = int(np.argmax(~(dtt > 0))) + off
            self._fail("time_s must increase strictly", "time_s", loc(i))
        if st.gap is not None and dtt.size and dtt.max() > st.gap:
            j = int(np.argmax(dtt > st.gap))
            self._fail(f"gap of {float(dtt[j]):.6g} s in time_s exceeds max_gap_s = "
                       f"{st.gap:.6g} s", "time_s", loc(j + off))
        if not h.quantised:
            out[:] = raw
            dc = _diff_after(st.prev_c, out) if k is not None and k > 0 and dtt.size \
                else None
        else:
            if raw.dtype == np.uint64:
                raw = raw.view(np.int64)
            # unwrapped straight into ``out``; its steps are the rate check's steps
            d = _unwrap_steps(raw, h.bits, st.prev_raw)
            first = d[0]
            if st.prev_raw is not None:
                with np.errstate(over="ignore"):
                    d[0] = first + np.int64(st.prev_unwrapped)
            np.cumsum(d, out=out)
            d[0] = first
            dc = d if st.prev_raw is not None else d[1:]
        # plausibility of the unwrapped counter: |Δcount| ≤ bound·K·Δt
        top = None
        if k is not None and k > 0 and dtt.size:
            bound = self.rate_bound_dps * k
            # no step is too fast when the largest step is within the bound at the
            # shortest interval (monotone, so exact); else look step by step
            top = float(max(dc.max(), -dc.min())) if dc.dtype.kind == "f" else \
                float(max(int(dc.max()), -int(dc.min())))
            fast = None if top <= bound * dt_min else \
                np.abs(dc.astype(np.float64)) > bound * dtt
            if fast is not None and fast.any():
                j = int(np.argmax(fast))
                rate = abs(float(dc[j])) / (k * float(dtt[j]))
                self._fail(f"the counter moves at {rate:.4g} °/s here, above the "
                           f"plausible bound {self.rate_bound_dps:g} °/s (metadata "
                           "max_rate_dps)", "gyro_counts", loc(j + off))
        if st.check_table:
            table = arr["table_deg"][p:q]
            self._check_table(out, table, first_row, st.table, loc,
                              None if top is None else _residual_step_bound(out, table, top, k))
        if h.quantised:
            st.prev_raw = int(raw[-1])
            st.prev_unwrapped = int(out[-1])
        st.prev_t = float(t[-1])
        st.prev_c = out[-1]

    def release(self) -> None:
        """Drop the cached blocks and hand the memory Arrow keeps for reuse back to the
        system (call when done with random access; the index is kept)."""
        self._cache.clear()
        self._cache_order.clear()
        release_arrow_memory()

    def _check_table(self, counts, table, row0: int, state: dict, loc,
                     bound: float | None = None) -> None:
        """Step of the median-of-three residual count/K − table_deg (see the class notes).

        ``bound``: an upper bound, rounding included, on every step of the residual
        inside these rows (:func:`_residual_step_bound`); at or below the tolerance only
        the steps across the rows' edges are formed."""
        k, bits = self.k_nominal, self.header.bits
        carry = state["resid"]
        tol = float(1 << bits) / (4.0 * k)
        if bound is not None and bound <= tol and state["med"] is not None and counts.size:
            r_head = np.divide(counts[:1], k)
            r_head -= table[:1]
            head = np.diff(np.concatenate((carry, r_head)))
            if not (head.size and np.abs(head).max() > tol):
                r_tail = np.divide(counts[-3:], k)
                r_tail -= table[-3:]
                tail = np.concatenate((carry, r_tail))[-3:]
                if tail.size >= 3:
                    a3, b3, c3 = tail[-3], tail[-2], tail[-1]
                    state["med"] = float(max(min(a3, b3), min(max(a3, b3), c3)))
                state["resid"] = tail[-2:].copy()
                return
        resid = np.divide(counts, k)
        resid -= table
        # a step of the median of three needs a step of the raw residual: look closer
        # only where there is one (clean data never has one)
        step_seen = False
        if state["med"] is not None:
            d = np.diff(resid)
            head = np.diff(np.concatenate((carry, resid[:1])))
            step_seen = bool((d.size and max(d.max(), -d.min()) > tol)
                             or (head.size and np.abs(head).max() > tol))
            del d
        r_all = np.concatenate((carry, resid)) if step_seen or state["med"] is None \
            else None
        if r_all is not None and r_all.size >= 3 and (state["med"] is None or step_seen):
            a3, b3, c3 = r_all[:-2], r_all[1:-1], r_all[2:]
            med = np.maximum(np.minimum(a3, b3), np.minimum(np.maximum(a3, b3), c3))
            # med[i] is centred on global row row0 − len(carry) + i + 1
            had_prev = state["med"] is not None
            m_all = np.concatenate(([state["med"]], med)) if had_prev else med
            step = np.abs(np.diff(m_all))
            if step.size and np.any(step > tol):
                j = int(np.argmax(step > tol))
                centre = row0 - carry.size + j + 1 + (0 if had_prev else 1)
                self._fail(
                    f"the unwrapped counter disagrees with table_deg by {step[j]:.4g}° from "
                    f"one sample to the next (more than 2^{bits}/(4K) = {tol:.4g}°): the "
                    f"{bits}-bit counter overflowed between samples (moved by more than half "
                    "its range); record faster or with a wider counter", "gyro_counts",
                    loc(max(0, centre - row0)))
            state["med"] = float(med[-1])
        else:
            tail = r_all if r_all is not None else np.concatenate((carry, resid[-3:]))[-3:]
            if tail.size >= 3:
                a3, b3, c3 = tail[-3], tail[-2], tail[-1]
                state["med"] = float(max(min(a3, b3), min(max(a3, b3), c3)))
        state["resid"] = (r_all if r_all is not None
                          else np.concatenate((carry, resid[-2:])))[-2:].copy()

    # ------------------------------------------------------------------ random access
    def index(self) -> "StreamFile":
        """Read the file once (validating it) if it has not been; returns self."""
        if self.blocks is None:
            for _ in self.chunks():
                pass
        return self

    def __len__(self) -> int:
        self.index()
        b = self.blocks[-1]
        return b.first_row + b.n_rows

    @property
    def t_first(self) -> float:
        return self.index().blocks[0].t_first

    @property
    def t_last(self) -> float:
        return self.index().blocks[-1].t_last

    def _block(self, j: int) -> StreamChunk:
        if j in self._cache:
            return self._cache[j]
        blk = self.blocks[j]
        arr = self._read_block(blk)
        h = self.header
        raw = arr["gyro_counts"]
        if not h.quantised:
            counts = raw.astype(np.float64)
        else:
            if raw.dtype == np.uint64:
                raw = raw.view(np.int64)
            counts = unwrap_counts(raw, h.bits, blk.prev_raw)
            if blk.prev_raw is not None:
                with np.errstate(over="ignore"):
                    counts = counts + np.int64(blk.prev_unwrapped)
        ch = StreamChunk(arr["time_s"], counts, arr.get("table_deg"), arr.get("temperature_c"),
                         blk.first_row)
        self._cache[j] = ch
        self._cache_order.append(j)
        if len(self._cache_order) > self._cache_max:
            self._cache.pop(self._cache_order.pop(0), None)
        return ch

    def _block_of_row(self, i: int) -> int:
        firsts = [b.first_row for b in self.blocks]
        return int(np.searchsorted(firsts, i, side="right")) - 1

    def window(self, a: int, b: int, columns=None) -> StreamChunk:
        """Rows ``a`` … ``b − 1`` (clipped to the stream); ``columns``: only these of
        ``time_s, gyro_counts, table_deg, temperature_c`` (the others are None)."""
        self.index()
        n = len(self)
        a, b = max(0, int(a)), min(n, int(b))
        if b <= a:
            e = np.empty(0)
            return StreamChunk(e, e.astype(np.int64), None, None, a)
        out = None
        j = self._block_of_row(a)
        while j < len(self.blocks) and self.blocks[j].first_row < b:
            ch = self._block(j)
            lo = max(a, ch.first_row)
            hi = min(b, ch.first_row + ch.time_s.size)
            if out is None:          # the result is allocated once and filled block by block
                out = {name: None if getattr(ch, name) is None or
                       (columns is not None and name not in columns) else
                       np.empty(b - a, dtype=getattr(ch, name).dtype)
                       for name in ("time_s", "gyro_counts", "table_deg", "temperature_c")}
            for name, arr in out.items():
                if arr is not None:
                    arr[lo - a:hi - a] = getattr(ch, name)[lo - ch.first_row:hi - ch.first_row]
            j += 1
        return StreamChunk(out["time_s"], out["gyro_counts"], out["table_deg"],
                           out["temperature_c"], a)

    def time_at(self, i: int) -> float:
        """Time of row ``i``."""
        ch = self._block(self._block_of_row(int(i)))
        return float(ch.time_s[int(i) - ch.first_row])

    def counts_at(self, i: int):
        """Unwrapped counter at row ``i``."""
        ch = self._block(self._block_of_row(int(i)))
        return ch.gyro_counts[int(i) - ch.first_row]

    def search(self, t: float, side: str = "left") -> int:
        """``numpy.searchsorted`` of ``t`` in the whole time column."""
        self.index()
        lasts = np.array([b.t_last for b in self.blocks])
        j = int(np.searchsorted(lasts, t, side=side))
        if j >= len(self.blocks):
            return len(self)
        ch = self._block(j)
        return ch.first_row + int(np.searchsorted(ch.time_s, t, side=side))


def _finite_sum(a: np.ndarray) -> bool:
    """True when the sum of ``a`` is finite: then every value is (a NaN or an infinity
    makes the sum non-finite; a finite sum that overflows only sends the caller to the
    value-by-value check)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return bool(np.isfinite(np.sum(a)))


def _diff_after(prev, a: np.ndarray) -> np.ndarray:
    """``numpy.diff`` of ``a`` preceded by ``prev`` (None: of ``a`` alone), built without
    copying ``a`` first."""
    if prev is None:
        return np.diff(a)
    d = np.empty(a.size, dtype=np.result_type(a.dtype, np.asarray(prev).dtype))
    if a.size:
        with np.errstate(over="ignore"):      # int64 wraps, as numpy.diff does
            d[0] = a[0] - prev
        np.subtract(a[1:], a[:-1], out=d[1:])
    return d


def _residual_step_bound(counts: np.ndarray, table: np.ndarray, top: float, k: float) -> float:
    """An upper bound on every |Δ(count/K − table)| between consecutive rows, as computed in
    float64, from the largest count step ``top``: top/K + max|Δtable| plus the rounding of
    each operation (unit roundoff 2⁻⁵³ on values up to max|count/K| + max|table|, taken
    with a margin of ten). The values' size is itself bounded from the first row and the
    largest steps (|c_i| ≤ |c_0| + i·top), so the bound costs one difference and two
    reductions instead of the residual's own passes."""
    dt_ = np.diff(table)
    step = float(max(dt_.max(), -dt_.min())) if dt_.size else 0.0
    n = counts.size
    size = (abs(float(counts[0])) + top * n) / k + abs(float(table[0])) + step * n
    return (top / k + step + 1e-14 * size) * (1.0 + 1e-14)


def release_arrow_memory() -> None:
    """Hand the memory Arrow's pool keeps for reuse (tens of MB after a pass over a
    stream) back to the system, so that later stages do not carry it."""
    import pyarrow as pa
    pa.default_memory_pool().release_unused()


def _columns(tab, columns) -> dict:
    """pyarrow table → dict of numpy arrays (``col#null`` masks where a column has nulls)."""
    import pyarrow as pa
    import pyarrow.compute as pc
    out = {}
    for c in columns:
        col = tab.column(c)
        if col.null_count:
            out[c + "#null"] = col.is_null().to_numpy(zero_copy_only=False)
            if pa.types.is_floating(col.type):
                col = pc.fill_null(col, float("nan"))
            else:
                col = pc.fill_null(col, 0)
        a = col.to_numpy()
        if pa.types.is_floating(col.type):
            a = a.astype(np.float64, copy=False)
        out[c] = a
    return out


def _open_parquet(path: Path):
    """(ParquetFile, metadata, columns) with the checks a CSV header gets."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:  # pragma: no cover - pyarrow is a dependency
        raise GonioError("reading Parquet needs pyarrow (not installed)", file=path) from None
    try:
        # no pre-buffering: it caches the column chunks of what it reads (another
        # 30–40 MB resident with the compact encodings); row groups are read in order
        # and buffered reads of 1 MB cost nothing measurable
        pf = pq.ParquetFile(path, buffer_size=1 << 20, pre_buffer=False)
    except (OSError, pa.ArrowException) as exc:
        raise GonioError(f"cannot read Parquet: {_clip(str(exc), 80)}", file=path) from None
    schema = pf.schema_arrow
    md = {}
    for k, v in (schema.metadata or {}).items():
        if k.startswith(b"pandas") or k.startswith(b"ARROW:"):
            continue
        try:
            md[k.decode("utf-8")] = v.decode("utf-8")
        except UnicodeDecodeError:
            raise GonioError("metadata not UTF-8 text", file=path) from None
    cols = list(schema.names)
    check_header(cols, (), file=path, line=None)      # a column named twice: refused by name
    for c in cols:
        if c in STREAM_COLUMNS:
            t = schema.field(c).type
            ok = pa.types.is_integer(t) if c == "gyro_counts" and \
                md.get("counts_quantised", "true").strip().lower() not in ("false", "0", "no") \
                else (pa.types.is_floating(t) or pa.types.is_integer(t))
            if not ok:
                raise GonioError(f"column type {t} is not numeric (integer for quantised "
                                 "counts)", file=path, column=c)
    return pf, md, cols


def iter_stream(path: str | Path, chunk_rows: int = 1_000_000, *,
                max_gap_s: float | None = None) -> Iterator[StreamChunk]:
    """Read a stream (CSV or Parquet) chunk by chunk; unwrapping and checks carry across
    chunks. Memory is bounded by the block size whatever the file's length
    (:class:`StreamFile`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.csv"
    >>> _ = p.write_text("# counter_bits: 16\\ntime_s,gyro_counts\\n"
    ...                  "0.0,32766\\n0.1,-32768\\n0.2,-32766\\n")
    >>> [c.gyro_counts.tolist() for c in iter_stream(p, chunk_rows=2)]
    [[32766, 32768], [32770]]
    """
    return StreamFile(path, max_gap_s=max_gap_s).chunks(chunk_rows)


def read_stream(path: str | Path, *, chunk_rows: int = 1_000_000,
                max_gap_s: float | None = None) -> Stream:
    """Read, validate and unwrap a whole stream file (CSV or Parquet) into memory
    (``docs/formats.md#stream-file``).

    For long records use :class:`StreamFile` (bounded memory) instead.

    Raises
    ------
    GonioError
        Naming file, line (CSV) or data row (Parquet) and column (or key) for any
        departure from the contract.

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
    sf = StreamFile(path, max_gap_s=max_gap_s)
    parts = list(sf.chunks(chunk_rows))
    cat = (lambda name: np.concatenate([getattr(p, name) for p in parts])
           if getattr(parts[0], name) is not None else None)
    return Stream(cat("time_s"), cat("gyro_counts"), cat("table_deg"), cat("temperature_c"),
                  dict(sf.metadata), Path(path))


def _fmt_metadata(metadata: Mapping[str, str]) -> str:
    out = []
    for key, value in metadata.items():
        key, value = str(key), str(value)
        if not key.strip() or ":" in key or any(c in key + value for c in "\r\n"):
            raise GonioError("metadata key must be non-empty without ':' or line breaks, "
                             "value without line breaks", key=key)
        out.append(f"# {key.strip()}: {value.strip()}\n")
    return "".join(out)


#: Stream file formats the writer knows (by suffix: ``.parquet`` → Parquet, else CSV).
STREAM_FORMATS = ("parquet", "csv")
#: Rows per Parquet row group (one block of :class:`StreamFile`).
PARQUET_ROW_GROUP = 1 << 18
#: How streams are encoded in Parquet, column by column (no dictionary: 2¹⁸ distinct doubles
#: make it only overhead), then LZ4. Doubles BYTE_STREAM_SPLIT (the bytes of each rank side
#: by side: time and angle change slowly in their high bytes, which LZ4 then packs);
#: integer counts DELTA_BINARY_PACKED (sample-to-sample steps of a few bits). On a
#: simulated draft session this is 1.2 bytes a row against 8.0 for plain + LZ4 and 24
#: uncompressed, and decodes in 0.8 CPU s per 10⁸ rows against 1.2 (docs/formats.md#stream-file).
#: Any encoding is read.
PARQUET_OPTIONS = {"compression": "lz4", "use_dictionary": False}
#: Parquet encoding by column type (see :data:`PARQUET_OPTIONS`).
PARQUET_ENCODING = {"double": "BYTE_STREAM_SPLIT", "int64": "DELTA_BINARY_PACKED",
                    "uint64": "DELTA_BINARY_PACKED"}


def stream_format(path: str | Path) -> str:
    """``"parquet"`` for a ``.parquet`` file, else ``"csv"``."""
    return "parquet" if Path(path).suffix.lower() == ".parquet" else "csv"


class StreamWriter:
    """Write a stream chunk by chunk, as CSV or Parquet; the file appears (atomically) only
    at :meth:`close`.

    Counts are given unwrapped and written wrapped to the counter width in
    ``metadata`` (``counter_bits``, ``counter_signed``): the file holds what the
    counter shows. CSV: ``# key: value`` lines, the header, then rows (floats in
    their shortest form that reads back bit for bit). Parquet: the same metadata as
    the file's key-value metadata, columns ``time_s`` (double), ``gyro_counts``
    (int64; uint64 for an unsigned 64-bit counter; double when
    ``counts_quantised: false``), ``table_deg``, ``temperature_c`` (double), row
    groups of :data:`PARQUET_ROW_GROUP` rows. Use as a context manager: an
    exception inside the ``with`` leaves no file behind. ``watermark=True`` (the virtual
    bench's streams) writes each time with the bench's watermark in its 1 ns digit
    (:func:`gonio.formats.watermark.mark_stream_times`): in the data, so that it survives
    the metadata's deletion in CSV and in Parquet alike.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.csv"
    >>> with StreamWriter(p, {"counter_bits": "16"}, table=True) as w:
    ...     w.write(np.array([0.0, 0.5]), np.array([32767.0, 32768.0]), np.array([0.0, 1.5]))
    >>> print(p.read_text(), end="")
    # counter_bits: 16
    time_s,gyro_counts,table_deg
    0,32767,0
    0.5,-32768,1.5
    """

    def __init__(self, path: str | Path, metadata: Mapping[str, str] | None = None, *,
                 table: bool = True, temperature: bool = False, fmt: str | None = None,
                 watermark: bool = False):
        import pyarrow as pa
        self.path = Path(path)
        self.watermark = watermark
        self.fmt = fmt or stream_format(self.path)
        if self.fmt not in STREAM_FORMATS:
            raise GonioError(f"unknown stream format {self.fmt!r} (known: "
                             f"{', '.join(STREAM_FORMATS)})", key="stream_format")
        md = {str(k): str(v) for k, v in (metadata or {}).items()}
        text_md = _fmt_metadata(md)
        self._header = _header_from(str(self.path), md, ["time_s", "gyro_counts"], 1, 0)
        h = self._header
        self.table, self.temperature = table, temperature
        cols = ["time_s", "gyro_counts"] + (["table_deg"] if table else []) \
            + (["temperature_c"] if temperature else [])
        ctype = pa.float64() if not h.quantised else (
            pa.uint64() if h.bits == 64 and not h.signed else pa.int64())
        self._schema = pa.schema([pa.field(c, ctype if c == "gyro_counts" else pa.float64(),
                                           nullable=False) for c in cols])
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd, self._tmp = tempfile.mkstemp(prefix=f".{self.path.name}.", suffix=".tmp",
                                         dir=self.path.parent)
        umask = os.umask(0)             # mkstemp makes 0600; every output is 0666 & ~umask
        os.umask(umask)
        os.fchmod(fd, 0o666 & ~umask)
        self._fh = os.fdopen(fd, "wb")
        self._buffer: list = []
        self._buffered = 0
        if self.fmt == "parquet":
            import pyarrow.parquet as pq
            self._schema = self._schema.with_metadata({k.strip(): v.strip()
                                                       for k, v in md.items()})
            self._pq = pq.ParquetWriter(
                self._fh, self._schema, **PARQUET_OPTIONS,
                column_encoding={f.name: PARQUET_ENCODING[str(f.type)] for f in self._schema})
        else:
            import pyarrow.csv as pcsv
            self._fh.write((text_md + ",".join(cols) + "\n").encode())
            self._csv = pcsv.CSVWriter(self._fh, self._schema, write_options=pcsv.WriteOptions(
                include_header=False, quoting_style="none"))
        self._last_t = -math.inf
        self.rows = 0

    def write(self, time_s, counts, table_deg=None, temperature_c=None) -> None:
        """Append rows; ``counts`` unwrapped (integers unless ``counts_quantised: false``)."""
        import pyarrow as pa
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
            cw = wrap_counter(c, h.bits, h.signed)
            if h.bits == 64 and not h.signed:
                cw = cw.view(np.uint64)
        else:
            cw = np.asarray(c, dtype=np.float64)
            if not np.all(np.isfinite(cw)):
                raise GonioError("counts must be finite")
        arrays = [t, cw]
        for flag, arr, name in ((self.table, table_deg, "table_deg"),
                                (self.temperature, temperature_c, "temperature_c")):
            if flag:
                a = np.asarray(arr, dtype=np.float64)
                if a.shape != t.shape or not np.all(np.isfinite(a)):
                    raise GonioError(f"{name} must be finite, one value per sample")
                arrays.append(a)
        if self.watermark:
            from gonio.formats.watermark import mark_stream_times
            t = mark_stream_times(t, arrays[1:])
            if not (t[0] > self._last_t and np.all(np.diff(t) > 0)):
                raise GonioError("stream times closer than the watermark's 3 ns")
            arrays[0] = t
        tab = pa.Table.from_arrays([pa.array(a) for a in arrays], schema=self._schema)
        if self.fmt == "parquet":
            self._buffer.append(tab)
            self._buffered += tab.num_rows
            if self._buffered >= PARQUET_ROW_GROUP:
                self._flush()
        else:
            self._csv.write_table(tab)
        self._last_t = float(t[-1])
        self.rows += int(t.size)

    def _flush(self) -> None:
        if self._buffer:
            import pyarrow as pa
            tab = pa.concat_tables(self._buffer)
            self._pq.write_table(tab, row_group_size=PARQUET_ROW_GROUP)
            self._buffer, self._buffered = [], 0

    def close(self) -> Path:
        """Flush, fsync and move the file into place."""
        if self._fh.closed:
            return self.path
        if self.fmt == "parquet":
            self._flush()
            self._pq.close()
        else:
            self._csv.close()
        self._fh.flush()
        os.fsync(self._fh.fileno())
        self._fh.close()
        os.replace(self._tmp, self.path)
        return self.path

    def abort(self) -> None:
        """Drop the partial file (the Arrow writer is closed first, so that it has nothing
        left to flush into a closed file when it is collected at exit)."""
        for name in ("_pq", "_csv"):
            w = getattr(self, name, None)
            if w is not None:
                with contextlib.suppress(Exception):
                    w.close()
                setattr(self, name, None)
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
                 metadata: Mapping[str, str] | None = None, temperature_c=None,
                 fmt: str | None = None) -> Path:
    """Write a whole stream file atomically (counts given unwrapped, written wrapped);
    Parquet for a ``.parquet`` path (or ``fmt="parquet"``), else CSV.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "s.csv"
    >>> _ = write_stream(p, [0.0, 0.01], [65535, 65536], [0.0, 0.0],
    ...                  {"counter_bits": "16", "counter_signed": "false"})
    >>> read_stream(p).gyro_counts.tolist()
    [65535, 65536]
    """
    with StreamWriter(path, metadata, table=table_deg is not None,
                      temperature=temperature_c is not None, fmt=fmt) as w:
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
    except MissingColumnError:
        cols = first_header(path)
        return "readings" if "test" in cols or "time_s" not in cols else "stream"
    except GonioError:
        return "readings"         # let the readings reader report what is wrong with this file
    return "readings" if "test" in h.columns else "stream"


def first_header(path: str | Path) -> list[str]:
    """The column names of a CSV file's header row (the first line that is neither blank nor
    a ``#`` metadata line); [] when there is none."""
    with open(path, "rb") as fh:
        for raw in fh:
            line = raw.decode("utf-8", "replace").lstrip("\ufeff").strip()
            if line and not line.startswith("#"):
                return [c.strip() for c in next(csv.reader([line]))]
    return []
