"""Gyro-triad readings files: read, validate, write (docs/formats-triad.md).

A triad readings file is CSV (UTF-8, BOM allowed, ``\\n`` or ``\\r\\n``): ``# key: value``
metadata lines, one header row, one row per record. Every error a file can cause is a
:class:`gonio.errors.GonioError` naming file, line (1-based, counting metadata lines)
and column. The input file is only read.

Row kinds (column ``test``):

* ``alignment`` — one dwell on the rate table: the fixture's reference axis ``up`` on the
  (vertical) table axis, ``north0`` the reference axis pointing north at table angle 0,
  ``table_deg`` the table angle at the start, ``rate_dps`` the table rate (right-handed
  about up; 0 for a static position), ``duration_s``; ``out_x/y/z`` the mean outputs over
  the dwell, ``sd_x/y/z`` their sample standard deviations over ``n_samples`` samples.
* ``static`` — one sample of a record at rest (``n_samples`` = 1, ``sd_*`` empty), for the
  Allan deviation that sets the averaging time.
* ``thermal`` — one dwell of a temperature-chamber / supply programme, as ``alignment``
  plus the chamber temperature, the gyro's internal temperature-sensor reading and the
  supply voltage; ``phase`` is ``soak`` (temperature settled) or ``ramp``.

Normalised columns of :attr:`TriadReadings.data`: the :data:`COLUMNS`, numbers as float
(NaN when empty), ``step`` and ``n_samples`` int64, text columns str, plus ``line``.
"""

from __future__ import annotations

import copy
import csv
import io
import math
import threading
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from gonio.errors import GonioError, check_header, check_near_miss, read_utf8
from gonio.formats.metadata import (IDENTITY_METADATA, check_identity_synonyms,
                                    metadata_block, named_files, parse_number)

FORMAT = "gonio-triad-readings/1"
TESTS = ("alignment", "static", "thermal")
SIGNED = ("+x", "-x", "+y", "-y", "+z", "-z")
OUT = ("out_x", "out_y", "out_z")
SD = ("sd_x", "sd_y", "sd_z")
PHASES = ("", "soak", "ramp")
COLUMNS = ("test", "step", "phase", "up", "north0", "table_deg", "rate_dps", "time_s",
           "duration_s", "n_samples", "chamber_c", "sensor_c", "supply_v") + OUT + SD
REQUIRED = ("test", "step", "up", "north0", "table_deg", "rate_dps", "time_s", "duration_s",
            "n_samples") + OUT
_FLOATS = ("table_deg", "rate_dps", "time_s", "duration_s", "chamber_c", "sensor_c",
           "supply_v") + OUT + SD
_OPTIONAL_FLOATS = ("chamber_c", "sensor_c", "supply_v") + SD
#: metadata keys that must be numbers, with their check
NUMERIC_METADATA = {"latitude_deg": (lambda v: -90 <= v <= 90, "a number in [-90, 90]"),
                    "sample_rate_hz": (lambda v: v > 0, "a number > 0")}
#: the environment the certificate states, where the readings give it (checked when present)
ENVIRONMENT_METADATA = {
    "temperature_c": (lambda v: -100 <= v <= 200, "a temperature in [-100, 200] °C"),
    "room_temperature_c": (lambda v: -100 <= v <= 200, "a temperature in [-100, 200] °C"),
    "humidity_pct": (lambda v: 0 <= v <= 100, "a relative humidity in [0, 100] %")}
#: optional metadata: the rate table's certificate and the fixture's bound (the alignment's
#: Type B terms, :func:`gonio.specs.triad_alignment.analysis.table_type_b_cov`), with the
#: value taken when a file does not state it — the rate-gyro specifications' table
#: (JJF 1535 Table 2: rate accuracy 0.05 %, read as a standard uncertainty of 2.5×10⁻⁴)
#: and the fixture bound the virtual bench states for a gyro in its fixture (±0.05°)
TABLE_METADATA = {"rate_table_u_rel": (2.5e-4, lambda v: 0 <= v <= 0.5,
                                       "a relative standard uncertainty in [0, 0.5]"),
                  "orientation_bound_deg": (0.05, lambda v: 0 <= v <= 10,
                                            "a bound in [0, 10] degrees")}
REQUIRED_METADATA = ("format", "latitude_deg", "sample_rate_hz", "output_unit")
#: Plausible range of each numeric column (docs/formats-triad.md): a value outside is a
#: unit or transcription error, refused with its line before any arithmetic can overflow.
RANGES: dict[str, tuple[float, float, str]] = {
    "table_deg": (-1e6, 1e6, "a number in [-1e6, 1e6]"),
    "rate_dps": (-1e5, 1e5, "a number in [-1e5, 1e5] °/s"),
    "time_s": (-1e9, 1e9, "a number in [-1e9, 1e9] s"),
    "duration_s": (0.0, 1e7, "a number in (0, 1e7] s"),
    "chamber_c": (-100.0, 200.0, "a temperature in [-100, 200] °C"),
    "sensor_c": (-100.0, 200.0, "a temperature in [-100, 200] °C"),
    "supply_v": (1e-3, 1e3, "a supply voltage in [0.001, 1000] V"),
    **{c: (-1e12, 1e12, "a number in [-1e12, 1e12]") for c in OUT},
    **{c: (0.0, 1e12, "a number in [0, 1e12]") for c in SD},
}


@dataclass
class TriadReadings:
    """A validated triad readings file."""

    data: pd.DataFrame
    metadata: dict = field(default_factory=dict)
    path: str | None = None
    #: lines of the file set aside by the screening (their rows are not in ``data``): the
    #: static record's time-step check joins the samples either side of them
    aside: frozenset = frozenset()

    def rows(self, test: str) -> pd.DataFrame:
        """The rows of one kind (``alignment``, ``static``, ``thermal``), in file order."""
        return self.data[self.data["test"] == test].reset_index(drop=True)

    def table_metadata(self, key: str) -> float:
        """A :data:`TABLE_METADATA` value: the file's (checked when read), or the default."""
        v = str(self.metadata.get(key, "")).strip()
        return float(v) if v else float(TABLE_METADATA[key][0])

    @property
    def latitude_deg(self) -> float:
        return float(self.metadata["latitude_deg"])

    @property
    def sample_rate_hz(self) -> float:
        return float(self.metadata["sample_rate_hz"])


def _num(text: str, *, file, line, column, allow_empty: bool) -> float:
    t = text.strip()
    if t == "":
        if allow_empty:
            return math.nan
        raise GonioError("empty cell where a number is required", file=file, line=line, column=column)
    try:
        v = float(t)
    except ValueError:
        raise GonioError(f"expected a number, got {t!r}", file=file, line=line, column=column) from None
    if not math.isfinite(v):
        raise GonioError(f"expected a finite number, got {t!r}", file=file, line=line, column=column)
    return v


def _check_number(meta: dict, key: str, ok, expect: str, file) -> None:
    """A numeric metadata value: a plain number of ASCII digits (``parse_number``; "４５" or
    "4_5", which ``float`` takes, a certificate and a DCC cannot state), finite and accepted
    by ``ok``, else a one-line error."""
    v = parse_number(str(meta[key]).strip())
    if v is None or not (math.isfinite(v) and ok(v)):
        raise GonioError(f"expected {expect}, got {meta[key]!r}", file=file, key=key)


#: The last few files parsed, {file: (text, TriadReadings)}: a calibration reads its
#: readings and thermal programme once to screen them and again to calibrate them.
_PARSED: OrderedDict[str, tuple[str, TriadReadings]] = OrderedDict()
_PARSED_MAX = 4
_PARSED_LOCK = threading.Lock()


def _copy(r: TriadReadings) -> TriadReadings:
    return TriadReadings(r.data.copy(deep=True), copy.deepcopy(r.metadata), r.path, r.aside)


def parse_triad_readings(text: str, path: str | Path = "<text>") -> TriadReadings:
    """Parse and validate the text of a triad readings file (see the module docstring).
    The same text of the same file parsed again is the last parse's copy (the same
    values; a text that differs by one character is parsed afresh); each caller gets its
    own copy to change."""
    file = str(path)
    with _PARSED_LOCK:
        hit = _PARSED.get(file)
    if hit is not None and hit[0] == text:
        return _copy(hit[1])
    r = _parse_triad_readings(text, file)
    with _PARSED_LOCK:
        _PARSED[file] = (text, r)
        _PARSED.move_to_end(file)
        while len(_PARSED) > _PARSED_MAX:
            _PARSED.popitem(last=False)
    return _copy(r)


def _parse_triad_readings(text: str, file: str) -> TriadReadings:
    lines = text.splitlines()
    meta, i = metadata_block(lines, file)
    if i >= len(lines):
        raise GonioError("no header row", file=file, line=i + 1)
    for k in REQUIRED_METADATA:
        if k not in meta:
            raise GonioError(f"missing metadata '# {k}: ...'", file=file, key=k)
    if meta["format"] != FORMAT:
        raise GonioError(f"format must be {FORMAT!r}, got {meta['format']!r}", file=file, key="format")
    check_identity_synonyms(meta, file)
    check_near_miss(meta, (*REQUIRED_METADATA, *NUMERIC_METADATA, *TABLE_METADATA,
                           *ENVIRONMENT_METADATA, *IDENTITY_METADATA),
                    what="metadata key", file=file)
    for k, (ok, expect) in NUMERIC_METADATA.items():
        _check_number(meta, k, ok, expect, file)
    for k, (_, ok, expect) in TABLE_METADATA.items():
        if str(meta.get(k, "")).strip():
            _check_number(meta, k, ok, expect, file)
    for k, (ok, expect) in ENVIRONMENT_METADATA.items():
        if str(meta.get(k, "")).strip():
            _check_number(meta, k, ok, expect, file)
    header_line = i + 1
    reader = csv.reader(lines[i:])
    header = [h.strip() for h in next(reader)]
    check_header(header, REQUIRED, file=file, line=header_line)
    check_last_row_ended(text, lines, header_line, header, file)
    unknown = [h for h in header if h not in COLUMNS]
    if unknown:
        raise GonioError(f"unknown column (known: {', '.join(COLUMNS)})", file=file,
                         line=header_line, column=unknown[0])
    cols: dict[str, list] = {c: [] for c in COLUMNS}
    cols["line"] = []
    for j, row in enumerate(reader):
        ln = header_line + 1 + j
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) != len(header):
            raise GonioError(f"expected {len(header)} cells, got {len(row)}", file=file, line=ln)
        rec = dict(zip(header, row))
        test = rec["test"].strip()
        if test not in TESTS:
            raise GonioError(f"test must be one of {', '.join(TESTS)}, got {test!r}",
                             file=file, line=ln, column="test")
        for c in ("up", "north0"):
            v = rec[c].strip().lower()
            if v not in SIGNED:
                raise GonioError(f"expected one of {', '.join(SIGNED)}, got {rec[c]!r}",
                                 file=file, line=ln, column=c)
            rec[c] = v
        if rec["up"][1] == rec["north0"][1]:
            raise GonioError("north0 must be a different axis from up", file=file, line=ln,
                             column="north0")
        for c in ("step", "n_samples"):
            t = rec[c].strip()
            if not t.isdigit():
                raise GonioError(f"expected a whole number ≥ 0, got {t!r}", file=file, line=ln, column=c)
            rec[c] = int(t)
        if rec["n_samples"] < 1:
            raise GonioError("n_samples must be ≥ 1", file=file, line=ln, column="n_samples")
        for c in _FLOATS:
            if c in rec:
                rec[c] = _num(rec[c], file=file, line=ln, column=c, allow_empty=c in _OPTIONAL_FLOATS)
            else:
                rec[c] = math.nan
        if rec["duration_s"] <= 0:
            raise GonioError("duration_s must be > 0", file=file, line=ln, column="duration_s")
        if test == "thermal":
            for c in ("sensor_c", "supply_v"):
                if math.isnan(rec[c]):
                    raise GonioError("a thermal row needs this value", file=file, line=ln, column=c)
        rec["test"] = test
        rec["phase"] = rec.get("phase", "").strip()
        if rec["phase"] not in PHASES:
            raise GonioError(f"phase must be empty, soak or ramp, got {rec['phase']!r}",
                             file=file, line=ln, column="phase")
        for c in COLUMNS:
            cols[c].append(rec[c])
        cols["line"].append(ln)
    df = pd.DataFrame(cols)
    if df.empty:
        raise GonioError("no data rows", file=file, line=header_line + 1)
    for c in ("step", "n_samples", "line"):
        df[c] = df[c].astype(np.int64)
    for c in _FLOATS:
        df[c] = df[c].astype(float)
    check_triad_rows(df, file)
    check_sample_counts(df, float(meta["sample_rate_hz"]), file)
    check_sd_cells(df, header, file)
    return TriadReadings(df, meta, file)


#: Largest difference between a row's ``n_samples`` and ``duration_s`` × ``sample_rate_hz``:
#: one sample (a record starts and ends on a sample) or this share of the count, whichever
#: is larger (a logger that drops a few samples states the count it averaged).
SAMPLE_COUNT_TOL, SAMPLE_COUNT_TOL_REL = 1.0, 0.01


def check_sample_counts(df: pd.DataFrame, rate_hz: float, file) -> None:
    """Refuse a row whose ``n_samples`` contradicts ``duration_s`` × ``sample_rate_hz`` by
    more than :data:`SAMPLE_COUNT_TOL` samples and :data:`SAMPLE_COUNT_TOL_REL` of the
    count. The duration and the file's sample rate are the record's settings; ``n_samples``
    is the count they give, less any samples the logger dropped, and it weighs the dwell in
    the alignment fit and divides its sd: a count further from them than a few dropped
    samples is a typo in one of the two columns, which cannot be told, so the row is
    refused (naming ``n_samples``) rather than fitted with a wrong weight."""
    n = df["n_samples"].to_numpy(float)
    want = df["duration_s"].to_numpy(float) * rate_hz
    tol = np.maximum(SAMPLE_COUNT_TOL, SAMPLE_COUNT_TOL_REL * np.abs(want))
    bad = np.flatnonzero(np.abs(n - want) > tol)
    if bad.size:
        k = int(bad[0])
        raise GonioError(f"n_samples {int(n[k])} contradicts duration_s "
                         f"{df['duration_s'].iloc[k]:.6g} s × sample_rate_hz {rate_hz:.6g} Hz = "
                         f"{want[k]:.6g} samples (more than {tol[k]:.3g} apart): a typo in "
                         "one of them", file=file, line=int(df["line"].iloc[k]), column="n_samples")


def check_sd_cells(df: pd.DataFrame, header: list[str], file) -> None:
    """Refuse an empty ``sd_*`` cell on a row of two samples or more of a test whose other
    rows of two samples or more log that column: a lost cell, not a record without one (the
    static soak rows' sd gives the angle random walk, the alignment dwells' the consistency
    check's noise scale; read as "no sd" the row would drop out of both unsaid). A row of
    one sample has no sd (its cell is empty); a column absent from the header, or empty on
    every such row of a test, is a file that does not log it."""
    many = df["n_samples"].to_numpy() >= 2
    for c in SD:
        if c not in header:
            continue
        v = df[c].to_numpy(float)
        for test in TESTS:
            rows = many & (df["test"] == test).to_numpy()
            empty = rows & np.isnan(v)
            if empty.any() and (rows & ~np.isnan(v)).any():
                k = int(np.flatnonzero(empty)[0])
                raise GonioError(f"empty {c} on this {test} row of {int(df['n_samples'].iloc[k])} "
                                 f"samples, where the other {test} rows give one: a lost cell",
                                 file=file, line=int(df["line"].iloc[k]), column=c)


def check_last_row_ended(text: str, lines: list[str], header_line: int, header: list[str],
                         file) -> None:
    """Refuse a file whose last data row has no final newline: the file may be cut inside
    that row's last number ('0.7732' kept as '0.77' or '0'), which has as many cells as a
    complete row and would be read as a plausible, wrong value. The writer
    (:func:`format_triad_readings`) ends every row with a newline; a complete row typed by
    hand without one is refused with the remedy named."""
    if not text or text.endswith(("\n", "\r")):
        return
    last = len(lines)
    if last <= header_line or not lines[-1].strip():
        return
    cell = lines[-1].rsplit(",", 1)[-1].strip()
    raise GonioError(f"the file ends inside its last row, without a final newline: it may "
                     f"be cut short ({cell!r} may be part of a number); if the row is "
                     "complete, end the file with a newline", file=file, line=last,
                     column=header[-1] if header else None)


def check_triad_rows(df: pd.DataFrame, file) -> None:
    """Whole-file checks after every cell is read, each a GonioError naming the line:

    * every number within :data:`RANGES` (1e308 °/s or a temperature of 1e300 °C is a
      transcription error, not a measurement);
    * within each test, ``step`` unique and ``time_s`` strictly increasing from row to
      row (a duplicated, repeated or shuffled row, or a file whose times were all set to
      one value, is refused: each would weigh a dwell twice or order a ramp wrongly);
    * no output channel with one value in every row of a test (a gyro that did not
      respond, or a column filled with zeros: no scale factor can come from it).
    """
    line = df["line"].to_numpy()
    for c, (lo, hi, expect) in RANGES.items():
        v = df[c].to_numpy(dtype=float)
        bad = ~np.isnan(v) & ((v < lo) | (v > hi) | ((v == lo) & (c == "duration_s")))
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise GonioError(f"expected {expect}, got {v[k]:.6g}", file=file, line=int(line[k]),
                             column=c)
    for test, g in df.groupby("test", sort=False):
        ln = g["line"].to_numpy()
        dup = g["step"].duplicated().to_numpy()
        if dup.any():
            k = int(np.flatnonzero(dup)[0])
            first = int(ln[np.flatnonzero(g["step"].to_numpy() == g["step"].iloc[k])[0]])
            raise GonioError(f"step {int(g['step'].iloc[k])} of test {test} repeats line {first} "
                             "(a duplicated row)", file=file, line=int(ln[k]), column="step")
        t = g["time_s"].to_numpy(dtype=float)
        back = np.flatnonzero(np.diff(t) <= 0)
        if back.size:
            k = int(back[0]) + 1
            raise GonioError(f"time_s must increase from row to row within test {test}; "
                             f"{t[k]:.6g} s does not follow {t[k - 1]:.6g} s on line "
                             f"{int(ln[k - 1])} (a repeated, reordered or constant time)",
                             file=file, line=int(ln[k]), column="time_s")
        if len(g) < 2 or test == "static":
            continue
        for c in OUT:
            v = g[c].to_numpy(dtype=float)
            if np.all(v == v[0]):
                raise GonioError(f"{c} is {v[0]:.6g} in every {test} row: the gyro did not "
                                 "respond (or the column was filled with one value)",
                                 file=file, line=int(ln[0]), column=c)


def named_inputs(path: str | Path) -> list[Path]:
    """The files a triad readings file names as part of its data (``# thermal_readings:``,
    relative to its folder): inputs no output may replace (:func:`gonio.formats.metadata.named_files`)."""
    return named_files(path, "thermal_readings")


def read_triad_readings(path: str | Path) -> TriadReadings:
    """Read and validate a triad readings file."""
    return parse_triad_readings(read_utf8(path, "triad readings file"), path)


def _cell(v) -> str:
    if isinstance(v, str):
        return v
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    f = float(v)
    return "" if math.isnan(f) else repr(f)


def format_triad_readings(data: pd.DataFrame, metadata: dict) -> str:
    """The exact text of a triad readings file (deterministic: shortest round-trip floats)."""
    meta = {"format": FORMAT, **{k: v for k, v in metadata.items() if k != "format"}}
    out = io.StringIO()
    for k, v in meta.items():
        out.write(f"# {k}: {v}\n")
    w = csv.writer(out, lineterminator="\n")
    w.writerow(COLUMNS)
    w.writerows(zip(*[_column_cells(data[c]) if c in data else [""] * len(data)
                      for c in COLUMNS]))
    return out.getvalue()


def _column_cells(col: pd.Series) -> list[str]:
    """:func:`_cell` of every value of a column, a float or integer column's at once (the
    same texts: its values are Python floats or ints)."""
    vals = col.tolist()
    if col.dtype.kind == "f":
        return ["" if v != v else repr(v) for v in vals]
    if col.dtype.kind in "iu":
        return [str(v) for v in vals]
    return [_cell(v) for v in vals]

