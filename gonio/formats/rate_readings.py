"""Rate-gyro readings files: read, validate and write (docs/formats-rate-gyro.md).

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
from gonio.errors import GonioError, check_header, read_utf8

COLUMNS: tuple[str, ...] = ("test", "run", "step", "role", "time_s", "rate_dps", "freq_hz",
                            "temperature_c", "supply_v", "up_axis", "north_axis",
                            "reference_dps", "output")
REQUIRED: tuple[str, ...] = ("test", "run", "step", "role", "time_s", "output")
TESTS: tuple[str, ...] = ("scale_factor", "sf_temperature", "threshold", "resolution", "bias",
                          "warmup", "g_sensitivity", "static", "bias_temperature", "vibration",
                          "cross_axis", "ratiometric")
ROLES: tuple[str, ...] = ("rest", "rate", "base", "increment", "record", "position", "vibration")
DEFAULTS = {"rate_dps": 0.0, "freq_hz": 0.0, "temperature_c": math.nan, "supply_v": math.nan,
            "up_axis": "+z", "north_axis": "+x", "reference_dps": math.nan}
AXES = ("+x", "-x", "+y", "-y", "+z", "-z")
NUMERIC_METADATA = {"nominal_scale_factor": "a non-zero number", "null_output": "a number",
                    "latitude_deg": "a number in [-90, 90]", "room_temperature_c": "a number",
                    "supply_nominal_v": "a number > 0"}


@dataclass
class RateReadings:
    """A validated rate readings file: ``data`` (DataFrame, :data:`COLUMNS` + ``line``),
    ``metadata`` (file order) and ``path``."""

    data: pd.DataFrame
    metadata: dict = field(default_factory=dict)
    path: Path | None = None

    def meta_float(self, key: str, default: float | None = None) -> float:
        """A numeric metadata value; missing without default → GonioError naming the key."""
        v = self.metadata.get(key)
        if v is None or v == "":
            if default is None:
                raise GonioError("required metadata key is missing", file=self.path, key=key)
            return float(default)
        return _meta_number(key, v, self.path)


def _meta_number(key: str, v: str, path) -> float:
    try:
        x = float(v)
    except ValueError:
        raise GonioError(f"expected {NUMERIC_METADATA.get(key, 'a number')}, got {v!r}",
                         file=path, key=key) from None
    bad = not math.isfinite(x) or (key == "latitude_deg" and abs(x) > 90) or \
        (key == "supply_nominal_v" and x <= 0) or (key == "nominal_scale_factor" and x == 0)
    if bad:
        raise GonioError(f"expected {NUMERIC_METADATA.get(key, 'a number')}, got {v!r}",
                         file=path, key=key)
    return x


def read_rate_readings(path: str | Path) -> RateReadings:
    """Read and validate a rate readings file.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "r.csv"
    >>> _ = p.write_text("# spec: jjf1535-2015\\ntest,run,step,role,time_s,output\\n"
    ...                  "bias,0,0,record,1800,2500.06\\n")
    >>> r = read_rate_readings(p)
    >>> r.metadata["spec"], float(r.data["output"][0]), r.data["up_axis"][0]
    ('jjf1535-2015', 2500.06, '+z')
    """
    path = Path(path)
    return parse_rate_readings(read_utf8(path, "readings file"), path=path)


def parse_rate_readings(text: str, *, path: str | Path | None = None) -> RateReadings:
    """Validate rate readings given as text (see :func:`read_rate_readings`)."""
    fname = "<text>" if path is None else str(path)
    if text.startswith("\ufeff"):
        text = text[1:]
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    lines = text.split("\n")
    md: dict[str, str] = {}
    i = 0
    while i < len(lines) and (not lines[i].strip() or lines[i].lstrip().startswith("#")):
        s = lines[i].strip()
        i += 1
        if not s:
            continue
        key, sep, value = s[1:].partition(":")
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
    check_header(header, REQUIRED, file=fname, line=header_line)
    body = "\n".join(lines[i:])
    for j in range(i + 1, len(lines)):
        if lines[j].lstrip().startswith("#"):
            raise GonioError("metadata line after the header; '#' lines belong at the top",
                             file=fname, line=j + 1)
    try:
        df = pd.read_csv(io.StringIO(body), dtype=str, keep_default_na=False,
                         skip_blank_lines=True)
    except pd.errors.ParserError as exc:
        raise GonioError(f"CSV: {exc}".replace("\n", " "), file=fname) from None
    # line numbers of the data rows (blank lines skipped)
    line_no = np.array([j + 1 for j in range(i + 1, len(lines)) if lines[j].strip()], dtype=np.int64)
    if len(df) == 0:
        raise GonioError("no readings: header only", file=fname, line=header_line)
    if len(line_no) != len(df):
        raise GonioError("a row has more fields than the header", file=fname)
    out = pd.DataFrame({"line": line_no})
    for col in COLUMNS:
        cells = df[col].str.strip() if col in df else None
        if col in ("test", "role", "up_axis", "north_axis"):
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
    return RateReadings(out, md, None if path is None else Path(path))


def write_rate_readings(data: pd.DataFrame, metadata: dict, path: str | Path) -> Path:
    """Write the exact format (metadata lines, header, rows): deterministic bytes, atomic.

    Floats are written with 12 significant digits (``%.12g``); NaN cells are empty.
    """
    missing = [c for c in COLUMNS if c not in data]
    if missing:
        raise GonioError(f"cannot write rate readings without column(s) {', '.join(missing)}")
    head = "".join(f"# {k}: {str(v).replace(chr(10), ' ')}\n" for k, v in metadata.items())
    body = data[list(COLUMNS)].to_csv(index=False, float_format="%.12g", lineterminator="\n",
                                      na_rep="")
    return write_text(path, head + body)
