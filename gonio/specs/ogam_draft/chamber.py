"""The chamber temperature K's line ``K_T`` takes: read from the readings (a logged
``temperature_c`` column over the 7.1 rounds, else the metadata key) and, for a stream, the
logged column carried to each reduced reading by interpolation in time.

One reading for K (docs/draft-readings.md, "Table 2, environment"): K = mean K_i over the
7.1 rounds (draft 7.1) and every K_i moves by the same α_K·ΔT_i, so K moves by α_K times the
mean of the rounds' deviations; the temperature K's line takes is therefore the mean of
the logged temperature over the 7.1 rounds (each round's reading row weighing the same),
not its extreme (the rounds' spread about it is in the Type A scatter of K_i already). A
logger slower than the readings (a value on every Nth row, blank cells between) is
interpolated linearly between its values and held at the first/last value outside them:
in a stream by the stream's clock (each reduced reading takes the mean of the logged
temperature at its zeroing and at its reading, the round's trapezoid mean); in a readings
file, whose ``time_s`` counts from each round's own zeroing and so is no common clock, by
the row's place in the file (the session's order). A column without any value falls back
to the metadata.
"""

from __future__ import annotations

import numpy as np

from gonio.errors import GonioError
from gonio.formats.metadata import metadata_float, parse_number

__all__ = ["COLUMN", "logged_chamber_temperature", "temperature_at", "stream_temperature_at"]

#: The readings/stream column that logs the chamber's temperature, °C.
COLUMN = "temperature_c"


def _column_values(readings) -> np.ndarray:
    """The ``temperature_c`` column as floats, NaN where blank; a value that is not a finite
    number in (−273.15, 1000] °C is a GonioError naming the column and the row's line."""
    df = readings.data
    lines = df["line"].to_numpy() if "line" in df.columns else np.arange(2, len(df) + 2)
    out = np.full(len(df), np.nan)
    for i, v in enumerate(df[COLUMN].to_numpy()):
        text = "" if v is None or (isinstance(v, float) and np.isnan(v)) else str(v).strip()
        if text == "":
            continue
        x = parse_number(text)
        if x is None or not np.isfinite(x) or not -273.15 < x <= 1000.0:
            raise GonioError(f"expected a temperature in (-273.15, 1000] degC or an empty cell, "
                             f"got {text[:40]!r}", file=readings.path, line=int(lines[i]),
                             column=COLUMN)
        out[i] = x
    return out


def temperature_at(t_s, t_logged_s, temperature_c) -> np.ndarray:
    """The logged temperature at the times ``t_s``: linear in time between the logged
    values (NaN entries are gaps, not values), the first/last value outside them.

    >>> temperature_at([0.0, 1.5, 9.0], [1.0, 2.0, 3.0], [20.0, np.nan, 21.0]).tolist()
    [20.0, 20.25, 21.0]
    """
    t = np.asarray(t_logged_s, dtype=float)
    v = np.asarray(temperature_c, dtype=float)
    ok = np.isfinite(v)
    t, v = t[ok], v[ok]
    order = np.argsort(t, kind="stable")
    return np.interp(np.asarray(t_s, dtype=float), t[order], v[order])


def logged_chamber_temperature(readings) -> tuple[float | None, str | None]:
    """The chamber temperature K's line takes, °C, and where it comes from: ``column`` (the
    readings' ``temperature_c`` column: its mean over the 7.1 rounds' rows, a blank row's
    value interpolated between the logged rows by its place in the file), ``metadata`` (the
    key ``temperature_c``), or (None, None) when neither logs it.

    >>> import pandas as pd
    >>> from gonio.specs.ogam_draft.readings import Readings
    >>> df = pd.DataFrame({"test": ["scale_factor"] * 3 + ["angle_deviation"],
    ...                    "temperature_c": ["20.2", "", "20.6", "25"]})
    >>> logged_chamber_temperature(Readings(df, {"temperature_c": "20.0"}))
    (20.4, 'column')
    >>> logged_chamber_temperature(Readings(df.drop(columns="temperature_c"), {}))
    (None, None)
    """
    if COLUMN in readings.data.columns:
        vals = _column_values(readings)
        if np.isfinite(vals).any():
            sf = (readings.data["test"] == "scale_factor").to_numpy()
            row = np.arange(vals.size, dtype=float)
            at = temperature_at(row[sf] if sf.any() else row, row, vals)
            return round(float(np.mean(at)), 9), "column"
    logged = metadata_float(readings.metadata, COLUMN, file=readings.path)
    return (None, None) if logged is None else (logged, "metadata")


def stream_temperature_at(samples, t_s) -> np.ndarray | None:
    """A stream's logged ``temperature_c`` at the times ``t_s`` (on the stream's clock), as :func:`temperature_at` takes it (linear in time between the logged
    values, blank cells skipped, held outside them), in one pass over ``samples`` (a
    :class:`~gonio.formats.streams.StreamFile` or
    :class:`~gonio.reduce.rests.MemorySamples`) keeping only the logged values around each
    chunk's edge; None when the stream has no such column or no value in it."""
    q = np.asarray(t_s, dtype=float)
    order = np.argsort(q, kind="stable")
    qs = q[order]
    out = np.full(q.size, np.nan)
    first = last = None                   # (t, T) of the first and of the latest logged value
    for ch in samples.chunks():
        if ch.temperature_c is None:
            return None
        ok = np.isfinite(ch.temperature_c)
        t, v = ch.time_s[ok], ch.temperature_c[ok]
        if not t.size:
            continue
        if last is not None:
            t, v = np.concatenate(([last[0]], t)), np.concatenate(([last[1]], v))
        else:
            first = (float(t[0]), float(v[0]))
        lo = int(np.searchsorted(qs, t[0], side="left"))
        hi = int(np.searchsorted(qs, t[-1], side="right"))
        out[lo:hi] = np.interp(qs[lo:hi], t, v)
        last = (float(t[-1]), float(v[-1]))
    if first is None:
        return None
    out[qs < first[0]] = first[1]
    out[qs > last[0]] = last[1]
    res = np.empty_like(out)
    res[order] = out
    return res
