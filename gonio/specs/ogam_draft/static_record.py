"""The optical draft's record of continuous instrument output over the 7.3 rest, cut from a
laboratory's stream or captured by the virtual bench.

A :class:`StaticRecord` is the instrument's output over a phase at rest (the 7.3
zero-stability phase), the input of the draft's noise analysis. It is plain data: the
calibration builds one from a laboratory's stream, the virtual bench from its own
simulation, and neither needs the other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class StaticRecord:
    """The instrument's record over the 7.3 zero-stability phase (at rest), for noise analysis.

    ``angle_deg`` is the pulse counter divided by the nominal scale factor (not
    compensated: the Allan deviation ignores a constant rate).
    """

    time_s: np.ndarray
    angle_deg: np.ndarray
    source: str = "virtual bench, 7.3 block"
    #: the counter the angles were divided from, where it is known (the virtual bench's), and
    #: the nominal scale factor it was divided by: what :func:`format_static_record` writes
    counts: np.ndarray | None = None
    nominal_scale_factor_counts_per_deg: float | None = None


#: The first line of a static record file (docs/formats.md#static-record-file).
FORMAT = "gonio-static-record/1"
#: The readings' metadata key naming the static record file beside them.
METADATA_KEY = "static_record"
#: The static record file's columns.
COLUMNS = ("time_s", "gyro_counts")


def _number(v: float) -> str:
    """A counter or time value as the shortest text that reads back to the same float (an
    integral value without a decimal point)."""
    f = float(v)
    return str(int(f)) if f.is_integer() and abs(f) < 2 ** 53 else repr(f)


def _numbers(values: np.ndarray) -> list[str]:
    """:func:`_number` of every value of a float array, the same texts (each float's
    ``repr``; an integral one below 2⁵³ as its integer), made at C speed."""
    out = list(map(repr, values.tolist()))
    whole = np.flatnonzero((values == np.floor(values)) & (np.abs(values) < 2.0 ** 53))
    for i, text in zip(whole.tolist(), map(str, values[whole].astype(np.int64).tolist())):
        out[i] = text
    return out


def format_static_record(time_s, counts, *, nominal_scale_factor_counts_per_deg: float,
                         source: str, identity: dict | None = None) -> str:
    """The exact text of a static record file: the counter ``counts`` at the times
    ``time_s`` over the 7.3 rest, with the nominal scale factor its angles are divided by
    (``angle_deg = gyro_counts / nominal``, as :class:`StaticRecord` holds them) and a
    description ``source``. Every number is written as the shortest text that reads back to
    the same float, so that the record read back (:func:`read_static_record`) is the record
    written, bit for bit: same record, same analysis (deterministic).

    >>> print(format_static_record([0.0, 0.5], [0, 3], nominal_scale_factor_counts_per_deg=2.5,
    ...                            source="test"), end="")
    # format: gonio-static-record/1
    # test: zero_stability
    # nominal_scale_factor_counts_per_deg: 2.5
    # source: test
    time_s,gyro_counts
    0,0
    0.5,3
    """
    t, c = np.asarray(time_s, dtype=float), np.asarray(counts, dtype=float)
    lines = [f"# format: {FORMAT}", "# test: zero_stability",
             f"# nominal_scale_factor_counts_per_deg: {float(nominal_scale_factor_counts_per_deg)!r}",
             f"# source: {' '.join(str(source).split())}"]
    # the instrument's identity and the readings' provenance (``identity``: the readings'
    # serial, bench, seed…): the record is checked against the readings as they are
    lines += [f"# {k}: {' '.join(str(v).split())}" for k, v in (identity or {}).items()
              if str(v).strip()]
    lines.append(",".join(COLUMNS))
    lines += map(",".join, zip(_numbers(t), _numbers(c)))
    return "\n".join(lines) + "\n"


def read_static_record(path) -> StaticRecord:
    """A static record file (:func:`format_static_record`) as the :class:`StaticRecord` it
    holds: angles ``gyro_counts / nominal_scale_factor_counts_per_deg``, its source named
    after the file. A file that is not one (its format line, the nominal scale factor, the
    header, a number, times not increasing, fewer than two samples) is a GonioError naming
    the file, line and column."""
    import math

    from gonio.errors import GonioError, check_input_file, read_utf8
    check_input_file(path, "static record file")
    text = read_utf8(path, "static record file")
    from gonio.formats.metadata import metadata_block
    lines = text.splitlines()
    meta, i = metadata_block(lines, path)
    if meta.get("format") != FORMAT:
        raise GonioError(f"not a static record file (its first line is not '# format: "
                         f"{FORMAT}')", file=path, line=1)
    try:
        k = float(meta.get("nominal_scale_factor_counts_per_deg", ""))
    except ValueError:
        k = math.nan
    if not (math.isfinite(k) and k > 0):
        raise GonioError("nominal_scale_factor_counts_per_deg is not a positive number",
                         file=path, key="nominal_scale_factor_counts_per_deg")
    if i >= len(lines) or tuple(lines[i].strip().split(",")) != COLUMNS:
        raise GonioError(f"the header is not '{','.join(COLUMNS)}'", file=path, line=i + 1)
    head = i + 1
    pairs = _number_pairs(lines[head:])
    vals = [] if pairs is not None else _checked_pairs(lines, head, path)
    arr = (pairs if pairs is not None else np.array(vals, dtype=float)).reshape(-1, 2)
    t, c = arr[:, 0], arr[:, 1]
    if len(t) < 2:
        raise GonioError("fewer than two samples", file=path, line=head + 1)
    back = np.diff(t) <= 0
    if back.any():
        raise GonioError("the time does not increase", file=path,
                         line=head + 2 + int(np.argmax(back)), column="time_s")
    from pathlib import Path
    return StaticRecord(t, c / k, source=f"{Path(path).name}: {meta.get('source') or '(none)'}")


def _number_pairs(body: list[str]) -> np.ndarray | None:
    """The rows ``body`` as an (n, 2) float array read by Python's float (what
    :func:`_checked_pairs` reads), or None where a row is not one pair of finite numbers
    (:func:`_checked_pairs` then names it)."""
    from itertools import repeat

    if any(n != 1 for n in map(str.count, body, repeat(","))):
        return None
    try:
        arr = np.array(list(map(float, ",".join(body).split(","))) if body else [],
                       dtype=float)
    except ValueError:
        return None
    return arr.reshape(-1, 2) if np.isfinite(arr).all() else None


def _checked_pairs(lines: list[str], head: int, path) -> list[tuple[float, float]]:
    """The number pairs of ``lines[head:]`` row by row; the first row that is not one pair
    of finite numbers is a GonioError naming the file, line and column."""
    import math

    from gonio.errors import GonioError
    vals = []
    for n, ln in enumerate(lines[head:], head + 1):   # Python's float: round-trip exact
        a, sep, b = ln.partition(",")
        try:
            pair = (float(a), float(b))
        except ValueError:
            pair = None
        if not sep or pair is None or "," in b:
            raise GonioError("not one number pair (time_s,gyro_counts)", file=path, line=n)
        for col, v in zip(COLUMNS, pair):
            if not math.isfinite(v):
                raise GonioError("not a finite number", file=path, line=n, column=col)
        vals.append(pair)
    return vals


def named_static_record(readings_path, metadata: dict) -> StaticRecord | None:
    """The static record the readings' ``# static_record:`` metadata names (a file relative
    to the readings' folder, :func:`read_static_record`), or None where they name none. A
    named file that is missing is a GonioError naming it: the record is part of the data."""
    from pathlib import Path

    from gonio.errors import GonioError
    name = str((metadata or {}).get(METADATA_KEY) or "").strip()
    if not name:
        return None
    p = Path(name)
    if not p.is_absolute() and readings_path:
        p = Path(readings_path).parent / p
    if not p.is_file():
        raise GonioError(f"the static record {name[:80]!r} the readings name "
                         f"('# {METADATA_KEY}:') is missing", file=readings_path,
                         key=METADATA_KEY)
    return read_static_record(p)


def named_inputs(path) -> list:
    """The files a readings file names as part of its data (``# static_record:``, relative to
    its folder): inputs no output may replace, and the records keep with the readings. Only
    the metadata lines at the top are read (:func:`gonio.formats.metadata.named_files`); an
    unreadable file, or a stream, names nothing."""
    from gonio.formats.metadata import named_files
    return named_files(path, METADATA_KEY)


#: The name the demo gives the static record file it writes beside its readings.
FILE_NAME = "static_record.csv"


#: The readings' metadata the demo's static record repeats (its identity and provenance).
IDENTITY_KEYS = ("serial", "model", "manufacturer", "gyro_type", "bench", "seed", "generator")


def static_record_text(record: StaticRecord, max_samples: int, identity: dict | None = None
                       ) -> str:
    """The static record file of a virtual bench's ``record`` (its counter and nominal scale
    factor known), every d-th sample kept, d the smallest that leaves at most ``max_samples``
    (the counter is cumulative: that is an exact record at d·τ0; the noise analysis decimates
    a longer record the same way, so it analyses the same samples from the file as from
    memory)."""
    if record.counts is None or not record.nominal_scale_factor_counts_per_deg:
        raise ValueError("the record's counter and nominal scale factor are not known")
    n = int(np.size(record.time_s))
    d = max(1, -(-n // int(max_samples)))
    source = record.source if d == 1 else \
        f"{record.source}; one sample in {d} kept (at most {int(max_samples)})"
    return format_static_record(
        record.time_s[::d], record.counts[::d], source=source,
        nominal_scale_factor_counts_per_deg=record.nominal_scale_factor_counts_per_deg,
        identity={k: identity[k] for k in IDENTITY_KEYS if (identity or {}).get(k)})
