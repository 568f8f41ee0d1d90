"""Rate-gyro readings files: read, validate and write (docs/formats.md#rate-gyro-readings-file).

Same family as the optical-gyro readings file: UTF-8 text, ``# key: value`` metadata
lines at the top, one CSV header row, then one row per *sample* (the rate-gyro
standards work on sample means, Allan records and sinusoids, so every sample is kept).

Columns (order of :data:`COLUMNS`; ``test``, ``run``, ``step``, ``role``, ``time_s``,
``output`` required, the others optional with the defaults of :data:`DEFAULTS`):

=================  ==========================================================
``test``           the programme part: one of :data:`TESTS`
``run``            calibration / power-cycle / temperature-point index (int ≥ 0)
``step``           index within the run (rate point, position, frequency; int ≥ 0)
``role``           ``rest``, ``rate``, ``base``, ``increment``, ``record``,
                   ``position``, ``vibration`` (:data:`ROLES`)
``time_s``         time since the gyro's power-on, s
``rate_dps``       set table rate (vibration: rate amplitude), °/s
``freq_hz``        vibration frequency, Hz (0 otherwise)
``temperature_c``  chamber set point (room temperature when the chamber is off), °C
``supply_v``       supply voltage at the gyro terminals, V
``up_axis``        body axis pointing up (``+z`` etc.); the input axis is body +z
``north_axis``     body axis pointing north
``reference_dps``  reference rate sensor of the vibration table (empty otherwise)
``output``         gyro output in the unit of metadata ``output_unit``
``stand_deg``      tilting-stand angle γ about ``stand_axis`` (IEC 5.3.3.8), ° (0)
``stand_axis``     body axis the tilting stand turns about (``+x``)
``supply_set_v``   set supply voltage; ``supply_v`` is then the actual one and the
                   outputs of a ratiometric gyro are corrected by IEC eq (18) (empty:
                   no correction)
=================  ==========================================================

Metadata the package reads: ``spec`` (the specification key), ``output_unit``,
``nominal_scale_factor``, ``null_output``, ``latitude_deg``, ``room_temperature_c``,
``supply_nominal_v``; others are kept. Every error is a :class:`GonioError` naming
file, line and column. The input file is never modified; writing is atomic and
byte-deterministic.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from gonio.atomic import write_text
from gonio.errors import GonioError, check_header, check_near_miss, read_utf8
from gonio.formats.metadata import (IDENTITY_METADATA, check_identity_synonyms, comment_body,
                                    is_comment, logged_median, parse_number)

COLUMNS: tuple[str, ...] = ("test", "run", "step", "role", "time_s", "rate_dps", "freq_hz",
                            "temperature_c", "supply_v", "up_axis", "north_axis",
                            "reference_dps", "output", "stand_deg", "stand_axis", "supply_set_v")
REQUIRED: tuple[str, ...] = ("test", "run", "step", "role", "time_s", "output")
TESTS: tuple[str, ...] = ("scale_factor", "sf_temperature", "threshold", "resolution", "bias",
                          "warmup", "g_sensitivity", "static", "bias_temperature", "vibration",
                          "cross_axis", "ratiometric")
ROLES: tuple[str, ...] = ("rest", "rate", "base", "increment", "record", "position", "vibration")
DEFAULTS = {"rate_dps": 0.0, "freq_hz": 0.0, "temperature_c": math.nan, "supply_v": math.nan,
            "up_axis": "+z", "north_axis": "+x", "reference_dps": math.nan, "stand_deg": 0.0,
            "stand_axis": "+x", "supply_set_v": math.nan}
AXES = ("+x", "-x", "+y", "-y", "+z", "-z")
#: Numeric metadata: key -> (lowest, highest, expected) — physically plausible ranges
#: (docs/formats.md "Rate-gyro metadata"); a value outside is refused naming the key,
#: before any arithmetic could overflow or a budget lose its meaning.
META_RANGES: dict[str, tuple[float, float, str]] = {
    "nominal_scale_factor": (-1e12, 1e12, "a non-zero number in [-1e12, 1e12]"),
    "null_output": (-1e12, 1e12, "a number in [-1e12, 1e12]"),
    "latitude_deg": (-90.0, 90.0, "a number in [-90, 90]"),
    "room_temperature_c": (-100.0, 200.0, "a temperature in [-100, 200] °C"),
    # the environment stated on the certificate (identity compares it with the lab file)
    "temperature_c": (-100.0, 200.0, "a temperature in [-100, 200] °C"),
    "humidity_pct": (0.0, 100.0, "a relative humidity in [0, 100] %"),
    "supply_nominal_v": (1e-3, 1e3, "a voltage in [0.001, 1000] V"),
    "rate_table_u_rel": (0.0, 0.5, "a relative standard uncertainty in [0, 0.5]"),
    "rate_table_ripple_rel": (0.0, 0.5, "a relative ripple amplitude in [0, 0.5]"),
    "acquisition_u_rel": (0.0, 0.5, "a relative standard uncertainty in [0, 0.5]"),
    "chamber_deviation_bound_c": (0.0, 50.0, "a temperature bound in [0, 50] °C"),
    "chamber_fluctuation_c": (0.0, 50.0, "a temperature amplitude in [0, 50] °C"),
    "chamber_uniformity_c": (0.0, 50.0, "a temperature uniformity in [0, 50] °C"),
    "chamber_fluctuation_period_s": (0.0, 1e7, "a period in [0, 1e7] s (0: not stated)"),
}
NUMERIC_METADATA = {k: v[2] for k, v in META_RANGES.items()}
#: Plausible range of each numeric column: (lowest, highest, expected). A value outside is
#: a unit or transcription error (1e308 mV, 300 °C in a gyro chamber, a supply of 0 V).
COLUMN_RANGES: dict[str, tuple[float, float, str]] = {
    "time_s": (-1e9, 1e9, "a time in [-1e9, 1e9] s"),
    "rate_dps": (-1e5, 1e5, "a rate in [-1e5, 1e5] °/s"),
    "freq_hz": (0.0, 1e5, "a frequency in [0, 1e5] Hz"),
    "temperature_c": (-100.0, 200.0, "a temperature in [-100, 200] °C"),
    "supply_v": (1e-3, 1e3, "a voltage in [0.001, 1000] V"),
    "supply_set_v": (1e-3, 1e3, "a voltage in [0.001, 1000] V"),
    "reference_dps": (-1e5, 1e5, "a rate in [-1e5, 1e5] °/s"),
    "output": (-1e12, 1e12, "a number in [-1e12, 1e12]"),
    "stand_deg": (-1e4, 1e4, "an angle in [-1e4, 1e4]°"),
}
#: Tests whose rows are records (one segment sampled in time): a constant output there is
#: a stuck gyro or a filled column, never a measurement of zero noise.
RECORD_TESTS: tuple[str, ...] = ("bias", "warmup", "static", "bias_temperature")
#: A run of this many consecutive samples at the file's largest (or smallest) output is a
#: clipped, saturated gyro: its scale factor and noise would be certified from a flat top.
SATURATION_RUN = 5


@dataclass
class RateReadings:
    """A validated rate readings file: ``data`` (DataFrame, :data:`COLUMNS` + ``line``),
    ``metadata`` (file order) and ``path``."""

    data: pd.DataFrame
    metadata: dict = field(default_factory=dict)
    path: Path | None = None

def _meta_number(key: str, v: str, path) -> float:
    """A numeric metadata value: a plain number of ASCII digits only (the optical reader's
    :func:`gonio.formats.metadata.parse_number`: Python's ``float`` also takes "４５", "٤٥"
    and "4_5", which a certificate would print as written and a DCC cannot state), within
    its range; else one line naming the key."""
    x = parse_number(v.strip())
    if x is None:
        raise GonioError(f"expected {NUMERIC_METADATA.get(key, 'a number')}, got {v!r}",
                         file=path, key=key)
    lo, hi, _ = META_RANGES.get(key, (-math.inf, math.inf, ""))
    bad = not math.isfinite(x) or not lo <= x <= hi or (key == "nominal_scale_factor" and x == 0)
    if bad:
        raise GonioError(f"expected {NUMERIC_METADATA.get(key, 'a number')}, got {v!r}",
                         file=path, key=key)
    return x


def read_columns() -> tuple[str, ...]:
    """The columns a rate readings file is read by (:data:`COLUMNS`); another column of a
    file is stated as unread (docs/formats.md#rate-gyro-columns)."""
    return COLUMNS


def read_rate_readings(path: str | Path) -> RateReadings:
    """Read and validate a rate readings file.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "r.csv"
    >>> _ = p.write_text("# spec: a-rate-spec\\ntest,run,step,role,time_s,output\\n"
    ...                  "bias,0,0,record,1800,2500.06\\n")
    >>> r = read_rate_readings(p)
    >>> r.metadata["spec"], float(r.data["output"][0]), r.data["up_axis"][0]
    ('a-rate-spec', 2500.06, '+z')
    """
    global _LAST_READ
    path = Path(path)
    text = read_utf8(path, "readings file")
    last = _LAST_READ
    if last is not None and last[0] == str(path) and last[1] == text:
        return _copy(last[2])       # the same file with the same text: the same readings
    rd = parse_rate_readings(text, path=path)
    _LAST_READ = (str(path), text, _copy(rd)) if len(text) <= _MEMO_CHARS else None
    return rd


#: Text size up to which the last file read is kept (path, text, its readings): a
#: specification's screening and its calibration read the same file one after the other.
_MEMO_CHARS = 1 << 25
_LAST_READ: tuple[str, str, RateReadings] | None = None


def _copy(rd: RateReadings) -> RateReadings:
    """A copy the caller may change without changing the kept readings."""
    return RateReadings(rd.data.copy(), dict(rd.metadata), rd.path)


def parse_rate_readings(text: str, *, path: str | Path | None = None) -> RateReadings:
    """Validate rate readings given as text (see :func:`read_rate_readings`)."""
    fname = "<text>" if path is None else str(path)
    if text.startswith("\ufeff"):
        text = text[1:]
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    lines = text.split("\n")
    md: dict[str, str] = {}
    i = 0
    while i < len(lines) and (not lines[i].strip() or is_comment(lines[i])):
        s = lines[i].strip()
        i += 1
        if not s:
            continue
        key, sep, value = comment_body(s).partition(":")
        key = key.strip()
        if not sep or not key:
            raise GonioError(f"bad metadata line, expected '# key: value', got {s!r}",
                             file=fname, line=i)
        if key in md:
            raise GonioError(f"metadata key {key!r} given twice", file=fname, line=i, key=key)
        md[key] = value.strip()
    for key in md:
        if key in NUMERIC_METADATA:
            _meta_number(key, md[key], fname)
    if i >= len(lines):
        raise GonioError("no readings: the file has no header row", file=fname, line=max(i, 1))
    header_line = i + 1
    header = [h.strip() for h in lines[i].split(",")]
    check_header(header, REQUIRED, file=fname, line=header_line)   # another format: named
    check_identity_synonyms(md, fname)
    check_near_miss(md, (*NUMERIC_METADATA, *IDENTITY_METADATA), what="metadata key",
                    file=fname)
    check_near_miss(header, COLUMNS, what="column", file=fname, line=header_line)
    body = "\n".join(lines[i:])
    for j in range(i + 1, len(lines)):
        if is_comment(lines[j]):
            raise GonioError("metadata line after the header; '#' lines belong at the top",
                             file=fname, line=j + 1)
    try:
        df = pd.read_csv(io.StringIO(body), dtype=str, keep_default_na=False,
                         skip_blank_lines=True)
    except pd.errors.ParserError as exc:
        _field_counts(lines, i, len(header), fname)
        raise GonioError(f"CSV: {exc}".replace("\n", " "), file=fname) from None
    # line numbers of the data rows (blank lines skipped)
    line_no = np.array([j + 1 for j in range(i + 1, len(lines)) if lines[j].strip()], dtype=np.int64)
    if len(df) == 0:
        raise GonioError("no readings: header only", file=fname, line=header_line)
    if len(line_no) != len(df):
        _field_counts(lines, i, len(header), fname)
        raise GonioError("a row has more fields than the header", file=fname)
    if '"' not in body:
        # a short row (a file cut in its last line: '2501.29' read as '25') is refused; the
        # CSV reader would fill the missing cells as blanks
        _field_counts(lines, i, len(header), fname)
    out = pd.DataFrame({"line": line_no})
    for col in COLUMNS:
        cells = df[col].str.strip() if col in df else None
        if col in ("test", "role", "up_axis", "north_axis", "stand_axis"):
            if cells is None:
                out[col] = DEFAULTS[col]
                continue
            vals = cells.where(cells != "", DEFAULTS.get(col, ""))
            allowed = {"test": TESTS, "role": ROLES}.get(col, AXES)
            bad = ~vals.isin(allowed)
            if bad.any():
                k = int(np.flatnonzero(bad.to_numpy())[0])
                raise GonioError(f"expected one of {', '.join(allowed)}, got {vals.iloc[k]!r}",
                                 file=fname, line=int(line_no[k]), column=col)
            out[col] = vals.to_numpy(dtype=object)
            continue
        if cells is None:
            out[col] = DEFAULTS[col]
            continue
        empty = cells == ""
        if empty.any() and col in REQUIRED:
            k = int(np.flatnonzero(empty.to_numpy())[0])
            raise GonioError("empty cell in a required column", file=fname,
                             line=int(line_no[k]), column=col)
        num = pd.to_numeric(cells.where(~empty, "nan"), errors="coerce")
        bad = num.isna() & ~empty | (np.isinf(num.to_numpy(dtype=float)))
        if bad.any():
            k = int(np.flatnonzero(bad.to_numpy())[0])
            raise GonioError(f"expected a finite number, got {cells.iloc[k]!r}", file=fname,
                             line=int(line_no[k]), column=col)
        arr = num.to_numpy(dtype=np.float64)
        if col in ("run", "step"):
            if np.any(arr < 0) or np.any(arr != np.round(arr)):
                k = int(np.flatnonzero((arr < 0) | (arr != np.round(arr)))[0])
                raise GonioError(f"expected an integer ≥ 0, got {cells.iloc[k]!r}", file=fname,
                                 line=int(line_no[k]), column=col)
            out[col] = arr.astype(np.int64)
        else:
            out[col] = np.where(empty.to_numpy(), DEFAULTS.get(col, math.nan), arr)
    out = out[list(COLUMNS) + ["line"]]
    check_rate_rows(out, fname, ratiometric=md.get("ratiometric", "").strip().lower()
                    in ("true", "yes", "1"),
                    noise_free=md.get("noise", "").strip().lower() in ("off", "false", "no"))
    return RateReadings(out, md, None if path is None else Path(path))


def _field_counts(lines: list[str], i: int, n: int, fname) -> None:
    """GonioError naming the first data line (file numbering) whose field count differs
    from the header's ``n`` (pandas numbers the lines of the part it was given)."""
    for j in range(i + 1, len(lines)):
        if lines[j].strip() and lines[j].count(",") + 1 != n:
            raise GonioError(f"expected {n} fields as in the header (line {i + 1}), got "
                             f"{lines[j].count(',') + 1}", file=fname, line=j + 1)


def _first(mask: np.ndarray) -> int:
    return int(np.flatnonzero(mask)[0])


def check_rate_rows(df: pd.DataFrame, fname, *, ratiometric: bool = False,
                    noise_free: bool = False) -> None:
    """Whole-file checks after every cell is read, each a GonioError naming the line:

    * every number within :data:`COLUMN_RANGES` (and, for a ratiometric gyro, a supply on
      every row of the ``ratiometric`` test: eq (18) divides by it);
    * within each (``test``, ``run``), ``time_s`` strictly increasing from row to row — a
      duplicated sample, shuffled rows or a column of equal times is refused (each would
      weigh a sample twice, reorder a record, or make a warm-up or a frequency response
      from no time at all);
    * a record test (:data:`RECORD_TESTS`) is one segment per run (one ``step``);
    * no record test whose output is one value in every sample (a stuck gyro, or a
      column filled with zeros: the noise would be certified as 0);
    * no run of :data:`SATURATION_RUN` consecutive samples at the file's largest or
      smallest output (a clipped, saturated gyro).

    The last two do not apply to a noise-free virtual bench (metadata ``noise: off``),
    whose records are constant by construction.
    """
    line = df["line"].to_numpy()
    for col, (lo, hi, expect) in COLUMN_RANGES.items():
        v = df[col].to_numpy(dtype=float)
        bad = ~np.isnan(v) & ((v < lo) | (v > hi))
        if bad.any():
            k = _first(bad)
            raise GonioError(f"expected {expect}, got {v[k]:.6g}", file=fname,
                             line=int(line[k]), column=col)
    if ratiometric:
        rows = (df["test"] == "ratiometric").to_numpy() & np.isnan(df["supply_v"].to_numpy(float))
        if rows.any():
            k = _first(rows)
            raise GonioError("a ratiometric row needs the actual supply voltage (IEC eq (18) "
                             "divides by it)", file=fname, line=int(line[k]), column="supply_v")
    t = df["time_s"].to_numpy(dtype=float)
    key = df["test"].astype(str).to_numpy() + "/" + df["run"].astype(str).to_numpy()
    same = np.r_[False, key[1:] == key[:-1]]
    back = same & np.r_[False, t[1:] <= t[:-1]]
    if back.any():
        k = _first(back)
        raise GonioError(f"time_s must increase from sample to sample within test "
                         f"{df['test'].iat[k]} run {df['run'].iat[k]}; {t[k]:.6g} s does not "
                         f"follow {t[k - 1]:.6g} s on line {int(line[k - 1])} (a duplicated "
                         "sample, reordered rows or one time for all)", file=fname,
                         line=int(line[k]), column="time_s")
    y = df["output"].to_numpy(dtype=float)
    step = df["step"].to_numpy()
    rec = df["test"].isin(RECORD_TESTS).to_numpy()
    moved = rec & same & np.r_[False, step[1:] != step[:-1]]
    if moved.any():
        k = _first(moved)
        raise GonioError(f"test {df['test'].iat[k]} run {df['run'].iat[k]} is one record: its "
                         f"rows share one step (step {step[k]} follows step {step[k - 1]})",
                         file=fname, line=int(line[k]), column="step")
    if noise_free:
        return
    for test in RECORD_TESTS:
        for run in np.unique(df["run"].to_numpy()[(df["test"] == test).to_numpy()]):
            m = ((df["test"] == test) & (df["run"] == run)).to_numpy()
            v = y[m]
            if v.size >= 2 and np.all(v == v[0]):
                raise GonioError(f"the output is {v[0]:.6g} in every sample of test {test} run "
                                 f"{run}: a stuck gyro or a filled column, not a record (its "
                                 "noise would be certified as 0)", file=fname,
                                 line=int(line[m][0]), column="output")
    for ext, word in ((y.max(), "largest"), (y.min(), "smallest")):
        need = _saturation_run(y, ext)
        at = (y == ext).astype(np.int64)
        if at.sum() < need:
            continue
        run = np.convolve(at, np.ones(need, dtype=np.int64), "valid")
        hit = np.flatnonzero(run == need)
        if hit.size:
            k = int(hit[0])
            raise GonioError(f"{need} or more consecutive samples at the file's "
                             f"{word} output {ext:.6g}: the gyro saturated (clipped); a scale "
                             "factor or noise from a flat top would be wrong", file=fname,
                             line=int(line[k]), column="output")


def _saturation_run(y: np.ndarray, ext: float) -> int:
    """The run of equal samples at the extreme ``ext`` that is a clipped top:
    :data:`SATURATION_RUN`, or longer where the output is so coarsely quantised that equal
    neighbours are common away from that level too (share p of the other samples): the
    length a chance run reaches with probability ≤ 1 % over the file,
    1 + log(0.01/N)/log p (a bias record logged to 1 mV with 0.2 mV noise
    was refused as 'saturated')."""
    other = (y[1:] != ext) & (y[:-1] != ext)
    p = float(np.mean(y[1:][other] == y[:-1][other])) if other.any() else 0.0
    if p >= 1.0:
        return y.size + 1
    if p <= 0.0:
        return SATURATION_RUN
    return max(SATURATION_RUN, math.ceil(1 + math.log(0.01 / y.size) / math.log(p)))


def write_rate_readings(data: pd.DataFrame, metadata: dict, path: str | Path) -> Path:
    """Write the exact format (metadata lines, header, rows): deterministic bytes, atomic.

    Floats are written with 12 significant digits (``%.12g``); NaN cells are empty.
    """
    return write_text(path, rate_readings_text(data, metadata))


def rate_readings_text(data: pd.DataFrame, metadata: dict) -> str:
    """The text :func:`write_rate_readings` writes."""
    missing = [c for c in COLUMNS if c not in data]
    if missing:
        raise GonioError(f"cannot write rate readings without column(s) {', '.join(missing)}")
    head = "".join(f"# {k}: {str(v).replace(chr(10), ' ')}\n" for k, v in metadata.items())
    frame = data[list(COLUMNS)]
    cells = pd.DataFrame({c: _float_cells(frame[c], "%.12g") if frame[c].dtype.kind == "f"
                          else frame[c] for c in COLUMNS}, index=frame.index)
    body = cells.to_csv(index=False, float_format="%.12g", lineterminator="\n", na_rep="")
    return head + body


def _float_cells(col: pd.Series, fmt: str) -> np.ndarray:
    """A float column's CSV cells: ``fmt % value``, NaN empty — what ``to_csv`` writes with
    ``float_format=fmt, na_rep=""``, formed in one list comprehension instead of pandas'
    formatter call per value (most of the time a readings file took to write)."""
    vals = col.to_numpy()
    out = np.array([fmt % v for v in vals.tolist()], dtype=object)
    out[np.isnan(vals)] = ""
    return out


#: The rate readings' tests run in a temperature chamber away from the room: their
#: ``temperature_c`` is the set point's, not the laboratory's (:func:`room_temperature_measured`).
CHAMBER_TESTS: tuple[str, ...] = ("sf_temperature", "bias_temperature")


def room_temperature_measured(path) -> dict:
    r"""The room temperature a rate readings file measured: the median of the logged
    ``temperature_c`` of the rows of the tests run in the room (every test but
    :data:`CHAMBER_TESTS`), as ``{"temperature_c": (text, where)}`` for the identity check
    (:func:`gonio.pipeline.identity.check_identity` ``measured``); ``{}`` where the file has
    no such column or no finite value in those rows (a blank between a slow logger's rows is
    no value). Read row by row; a row the screening will set aside can move a median of
    thousands of rows by nothing that matters against the check's 1 °C.

    >>> import tempfile, os
    >>> d = tempfile.mkdtemp(); f = os.path.join(d, "r.csv")
    >>> _ = open(f, "w").write("# serial: A-1\ntest,run,step,role,time_s,output,"
    ...     "temperature_c\nbias,0,0,record,0,1,20.0\nbias,0,0,record,1,1,\n"
    ...     "bias_temperature,0,0,record,2,1,85\nbias,0,0,record,3,1,20.4\n")
    >>> room_temperature_measured(f)["temperature_c"][0]
    '20.2'
    """
    def chamber_row(header: list[str], row: list[str]) -> bool:
        it = header.index("test") if "test" in header else None
        return it is None or len(row) <= it or row[it].strip() in CHAMBER_TESTS

    found = logged_median(path, "temperature_c", chamber_row)
    if found is None:
        return {}
    med, n = found
    return {"temperature_c": (f"{med:.6g}", f"the temperature_c column: median of {n} "
                              "rows of the tests run in the room")}

