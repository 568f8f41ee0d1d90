"""The seven characteristics of the draft's clause 7, one function each.

Contents
========
===================================  =============================================
:func:`scale_factor`                 7.1  K = mean of K_i = C_i / θ_i, counts/°
:func:`scale_factor_nonlinearity`    7.2  K_l = (max K_i − min K_i) / K, %
:func:`zero_stability`               7.3  B_s = s(M) / T (and 3.3: range / T), °/h
:func:`indicated_angle_deg`          the instrument's angle M from gyro_deg or counts / K
:func:`angle_deviation`              7.4  E = ± max |E_i|, E_i = M_i − S_i, ″
:func:`repeatability`                7.5  R = max_i s_j(E_ij), ″
:func:`rate_consistency`             7.6  C_v = (max E_v − min E_v) / reference, ppm
:func:`pointing_consistency`         7.7  C_g = (max E_g − min E_g) / reference, %
:func:`signed_extreme`               the reading of "E = ± max |E_i|"
:func:`consistency_reference_angle`  the reading of the garbled 7.6/7.7 denominator
:func:`compute_characteristics`      all seven from one readings file
:func:`summary_table`                fixed-width text table (Annex B order)
===================================  =============================================

Each function takes the normalised readings DataFrame of :mod:`gonio.specs.ogam_draft.readings` and
returns a :class:`Characteristic` (value, unit, clause, measured, reason, detail
tables, and which input lines it used). A characteristic whose readings are
absent is *not measured* (value None, with the reason), never invented.
Clause numbers refer to the draft as read in ``docs/draft-readings.md``; where
the draft is ambiguous, the reading taken is a named function or is stated in
the function's docstring, with the alternative.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from gonio.errors import GonioError
from gonio.units import ARCSEC_PER_DEG, S_PER_H  # noqa: F401
from gonio.specs.ogam_draft.readings import Readings, metadata_float
from gonio.specs.ogam_draft.keys import ITEM_KEYS  # noqa: F401  (the seven, in Annex B order)

#: Positions of different conditions (7.6, 7.7) are matched on table_deg rounded to this many decimals.
POSITION_DECIMALS: int = 2

#: The keys of the validation records: the seven, with the draft's and the model's readings
#: of the zero stability and the angle deviation beside them, and K's U under the
#: distribution of the tilt coupling over the allowed mountings (``scale_factor_disc``), and,
#: when the in-situ tilt estimate corrects K, the uncorrected K with the bound's U (``scale_factor_bound``).
RECORD_KEYS: tuple[str, ...] = ("scale_factor", "scale_factor_disc", "scale_factor_bound",
                                "scale_factor_nonlinearity", "scale_factor_nonlinearity_draft",
                                "zero_stability",
                                "zero_stability_draft", "zero_stability_model", "angle_deviation",
                                "angle_deviation_draft", "repeatability", "rate_consistency",
                                "rate_consistency_draft", "pointing_consistency",
                                "pointing_consistency_draft")
_TITLES = {
    "scale_factor": "scale factor K",
    "scale_factor_nonlinearity": "scale-factor nonlinearity K_l",
    "zero_stability": "zero stability B_s",
    "angle_deviation": "angle-position deviation E",
    "repeatability": "angle-position repeatability R",
    "rate_consistency": "rate consistency C_v",
    "pointing_consistency": "pointing consistency C_g",
}
_UNITS = {"scale_factor": "counts/deg", "scale_factor_nonlinearity": "%",
          "zero_stability": "deg/h", "angle_deviation": "arcsec", "repeatability": "arcsec",
          "rate_consistency": "ppm", "pointing_consistency": "%"}
_CLAUSES = {"scale_factor": "7.1", "scale_factor_nonlinearity": "7.2",
            "zero_stability": "7.3 (3.3)", "angle_deviation": "7.4", "repeatability": "7.5",
            "rate_consistency": "7.6", "pointing_consistency": "7.7"}


@dataclass
class Characteristic:
    """One calibrated item: its result and how it was obtained.

    Attributes
    ----------
    name : str
        Key, e.g. ``"scale_factor"``.
    value : float or None
        The result in ``unit``; None when not measured.
    unit, clause : str
        E.g. ``"counts/deg"``, ``"7.1"``.
    measured : bool
        False when the file lacks what the clause needs; ``reason`` says why.
    reason : str
        Why not measured (empty when measured).
    details : dict
        Further scalar results (e.g. ``max_abs_arcsec``, ``spread_arcsec``).
    table : pandas.DataFrame
        The main detail table (per round, per point, per condition...).
    tables : dict of str to DataFrame
        Other detail tables (e.g. the full E_ij matrix).
    used_lines : frozenset of int
        File lines of the readings this result used.
    unused : dict of int to str
        Lines this function looked at but did not use, with the reason.
    """

    name: str
    value: float | None = None
    measured: bool = False
    reason: str = ""
    details: dict[str, Any] = field(default_factory=dict)
    table: pd.DataFrame = field(default_factory=pd.DataFrame)
    tables: dict[str, pd.DataFrame] = field(default_factory=dict)
    used_lines: frozenset = frozenset()
    unused: dict[int, str] = field(default_factory=dict)

    @property
    def unit(self) -> str:
        return _UNITS[self.name]

    @property
    def clause(self) -> str:
        return _CLAUSES[self.name]

    @property
    def title(self) -> str:
        return _TITLES[self.name]

    def to_dict(self) -> dict:
        """JSON-able dict: plain floats, NaN as None, tables as lists of row dicts."""
        out: dict[str, Any] = {"item": self.title, "value": _plain(self.value),
                               "unit": self.unit, "clause": self.clause,
                               "measured": self.measured, "reason": self.reason}
        for k, v in self.details.items():
            out[k] = _plain(v)
        for k, t in [("table", self.table), *self.tables.items()]:
            out[k], summary = listing(t)
            if summary is not None:
                out[f"{k}_summary"] = summary
        return out


def _plain(x):
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        x = float(x)
        return None if not math.isfinite(x) else x
    if x is None or isinstance(x, str):
        return x
    return str(x)


#: Rows of a detail table listed in results.json (and on the certificate). A longer table
#: (a large readings file) is summarised: its row count, statistics of the column that
#: matters and the rows farthest from its median; the whole table is in tables/*.csv.
LISTED_ROWS: int = 200
#: Series columns of the 7.4 matrix listed in results.json (the worst ones beyond this).
LISTED_SERIES: int = 50
#: The column a long table is ranked by (the first present), farthest from the median first.
RANK_COLUMNS: tuple[str, ...] = ("E_arcsec", "deviation_pct", "K_i_counts_per_deg",
                                 "B_s_deg_per_h", "angle_deg", "R_arcsec")


def listing(df: pd.DataFrame, *, cap: int = LISTED_ROWS) -> tuple[list[dict], dict | None]:
    """The rows of ``df`` to list in results.json and a summary of the rest (None when the
    whole table is listed).

    A table of more than ``cap`` rows lists the ``cap`` rows farthest from the median of
    its rank column (:data:`RANK_COLUMNS`; the first rows when it has none), in table
    order; the summary gives the row count and that column's statistics. A table with
    more than :data:`LISTED_SERIES` ``series_*`` columns (the 7.4 matrix) keeps the
    series of largest ``|E_ij|``.

    >>> df = pd.DataFrame({"round": range(1, 6), "E_arcsec": [0.1, -0.2, 3.0, 0.0, 0.2]})
    >>> rows, summary = listing(df, cap=2)
    >>> [r["round"] for r in rows], summary["rows"], summary["max"]
    ([2, 3], 5, 3.0)
    """
    summary: dict[str, Any] = {}
    series = [c for c in df.columns if str(c).startswith("series_")]
    if len(series) > LISTED_SERIES:
        worst = df[series].abs().max(axis=0).to_numpy(dtype=float)
        keep = sorted(np.argsort(-np.nan_to_num(worst, nan=-1.0), kind="stable")[:LISTED_SERIES])
        summary.update({"series": len(series), "series_listed": LISTED_SERIES,
                        "series_listed_are": f"the {LISTED_SERIES} series of largest |E_ij|"})
        named = set(series)
        df = df[[c for c in df.columns if c not in named] + [series[i] for i in keep]]
    if len(df) > cap:
        col = next((c for c in RANK_COLUMNS if c in df.columns), None)
        summary.update({"rows": int(len(df)), "listed": cap})
        if col is None:
            df = df.iloc[:cap]
            summary["listed_are"] = f"the first {cap} rows"
        else:
            v = df[col].to_numpy(dtype=float)
            med = float(np.nanmedian(v)) if np.isfinite(v).any() else math.nan
            far = np.nan_to_num(np.abs(v - med), nan=-1.0)
            thr = np.partition(far, len(far) - cap)[len(far) - cap]     # O(n), not a sort
            above = np.flatnonzero(far > thr)
            keep = np.sort(np.concatenate([above,
                                           np.flatnonzero(far == thr)[:cap - above.size]]))
            fin = v[np.isfinite(v)]
            summary.update({"listed_are": f"the {cap} rows farthest from the median of {col}",
                            "column": col, "median": _plain(med),
                            "mean": _plain(fin.mean() if fin.size else math.nan),
                            "std": _plain(fin.std(ddof=1) if fin.size > 1 else math.nan),
                            "min": _plain(fin.min() if fin.size else math.nan),
                            "max": _plain(fin.max() if fin.size else math.nan)})
            df = df.iloc[keep]
    return _records(df), (summary or None)


def _records(df: pd.DataFrame) -> list[dict]:
    return [{str(k): _plain(v) for k, v in zip(df.columns, row)}
            for row in df.itertuples(index=False, name=None)]


def _not_measured(name: str, reason: str, rows: pd.DataFrame | None = None) -> Characteristic:
    unused = {} if rows is None else {int(l): reason for l in rows["line"]}
    return Characteristic(name=name, reason=reason, unused=unused)


def _rows(df: pd.DataFrame, test: str) -> pd.DataFrame:
    return df[df["test"] == test]


def _lines(rows: pd.DataFrame) -> frozenset:
    return frozenset(rows["line"].to_numpy().astype(np.int64).tolist())


# --------------------------------------------------------------------------- 7.1, 7.2

def scale_factor(df: pd.DataFrame) -> Characteristic:
    """Scale factor K, draft 7.1: K_i = C_i / θ_i per round, K = mean K_i.

    θ_i is the round's standard angle (``table_deg`` of its reading) and C_i
    its pulse count (``gyro_counts``). The draft runs one series of six rounds
    (60°…360°); with several series every round of every series is a K_i and
    K is the mean over all of them.

    Parameters
    ----------
    df : pandas.DataFrame
        Normalised readings (:mod:`gonio.specs.ogam_draft.readings`); rows of other tests are ignored.

    Returns
    -------
    Characteristic
        ``value`` in counts/°; ``table`` per round (series, round,
        table_deg, gyro_counts, K_i_counts_per_deg, line).

    Examples
    --------
    Three rounds, 60°, 120°, 180°: K_i = 3600.5, 3600.0, 3601.0, K = 3600.5.

    >>> df = pd.DataFrame({"test": ["scale_factor"] * 3, "series": [1, 1, 1],
    ...     "round": [1, 2, 3], "table_deg": [60.0, 120.0, 180.0],
    ...     "gyro_counts": [216030.0, 432000.0, 648180.0], "line": [2, 3, 4]})
    >>> sf = scale_factor(df)
    >>> sf.value
    3600.5
    >>> sf.table["K_i_counts_per_deg"].tolist()
    [3600.5, 3600.0, 3601.0]
    >>> round(scale_factor_nonlinearity(sf).value, 6)   # (3601 − 3600) / 3600.5 in %
    0.027774
    """
    rows = _rows(df, "scale_factor")
    if rows.empty:
        return _not_measured("scale_factor", "no scale_factor rows in file")
    rows = rows.sort_values(["series", "round"], kind="stable")
    theta = rows["table_deg"].to_numpy(dtype=float)
    counts = rows["gyro_counts"].to_numpy(dtype=float)
    bad = (theta == 0) | np.isnan(theta)
    if bad.any():
        line = int(rows["line"].to_numpy()[np.argmax(bad)])
        raise GonioError("scale_factor reading at table angle 0: K_i = C_i / θ_i needs θ_i ≠ 0",
                         line=line, column="table_deg")
    if np.isnan(counts).any():
        line = int(rows["line"].to_numpy()[np.argmax(np.isnan(counts))])
        raise GonioError("scale_factor readings need gyro_counts", line=line,
                         column="gyro_counts")
    k_i = counts / theta
    table = pd.DataFrame({"series": rows["series"].to_numpy(), "round": rows["round"].to_numpy(),
                          "table_deg": theta, "gyro_counts": counts,
                          "K_i_counts_per_deg": k_i, "line": rows["line"].to_numpy()})
    value = float(np.mean(k_i))
    return Characteristic(name="scale_factor", value=value, measured=True,
                          details={"n_rounds": int(len(k_i)),
                                   "n_series": int(rows["series"].nunique())},
                          table=table, used_lines=_lines(rows))


def nonlinearity_missing_rounds(theta_read_deg, programme_deg) -> str | None:
    """*Ambiguity* (7.2): K_l with a round of the programme not read or set aside.

    7.2: K_l = (max K_i − min K_i)/K over "the" rounds of 7.1, the programme's stops. The
    range over fewer rounds is at most the range over all of them for every instrument (a
    different, smaller quantity), and the table bound of the rounds left is smaller too (the
    60° round carries the largest table term): a 7.1 reading set aside left K_l at
    0.000027; ≤ 0.000121 % where the whole programme gave ≤ 0.00022 %. **Reading taken**:
    K_l is the range over every round of the programme (the protocol's 7.1 angles); a round
    of them with no reading left makes K_l not measured, the reason naming each missing
    angle (K and E rest on the rounds read, their table bounds over the programme's stops);
    a round is read where a reading's table angle is within 0.001° of it (the protocol's
    position tolerance). ``programme_deg`` None (the items called without a programme): the
    rounds read are the programme.

    Returns the reason, or None when every round of the programme was read.

    >>> why = nonlinearity_missing_rounds([120.0, 180.0], (60.0, 120.0, 180.0))
    >>> why.split(": ")[1].split(";")[0]
    '60 deg has no reading (2 of 3 rounds read)'
    >>> nonlinearity_missing_rounds([60.0, 120.0], None) is None
    True
    """
    if programme_deg is None:
        return None
    read = np.asarray(theta_read_deg, dtype=float)
    missing = [float(t) for t in programme_deg
               if not np.any(np.isclose(read, float(t), rtol=0.0, atol=1e-3))]
    if not missing:
        return None
    n = len(programme_deg)
    return (f"7.2 is the range of K_i over every round of the programme: "
            f"{', '.join(f'{t:g}' for t in missing)} deg has no reading ({n - len(missing)} of "
            f"{n} rounds read); not stated from fewer rounds (read the missing round)")


def scale_factor_nonlinearity(sf: Characteristic, programme_deg=None) -> Characteristic:
    """Scale-factor nonlinearity K_l, draft 7.2 (and 3.2): (max K_i − min K_i) / K, in %.

    Uses the rounds of :func:`scale_factor`; needs at least two rounds (one
    round has no variation to speak of, so it is reported as not measured) and every round
    of the programme ``programme_deg`` (the 7.1 angles; :func:`nonlinearity_missing_rounds`).

    Examples
    --------
    >>> df = pd.DataFrame({"test": ["scale_factor"] * 2, "series": [1, 1],
    ...     "round": [1, 2], "table_deg": [100.0, 200.0],
    ...     "gyro_counts": [360000.0, 720036.0], "line": [2, 3]})
    >>> round(scale_factor_nonlinearity(scale_factor(df)).value, 9)  # 0.18 / 3600.09 · 100
    0.004999875
    """
    name = "scale_factor_nonlinearity"
    if not sf.measured:
        return _not_measured(name, f"scale factor not measured: {sf.reason}")
    k_i = sf.table["K_i_counts_per_deg"].to_numpy(dtype=float)
    if len(k_i) < 2:
        return _not_measured(name, "needs at least 2 scale_factor rounds, file has 1")
    why = nonlinearity_missing_rounds(sf.table["table_deg"], programme_deg)
    if why:
        return _not_measured(name, why)
    k = float(sf.value)
    table = sf.table[["series", "round", "table_deg", "K_i_counts_per_deg"]].copy()
    table["deviation_pct"] = (k_i - k) / k * 100.0
    value = float((k_i.max() - k_i.min()) / k * 100.0)
    return Characteristic(name=name, value=value, measured=True,
                          details={"K_max_counts_per_deg": float(k_i.max()),
                                   "K_min_counts_per_deg": float(k_i.min())},
                          table=table, used_lines=sf.used_lines)


# --------------------------------------------------------------------------- angles

def indicated_angle_deg(df: pd.DataFrame,
                        scale_factor_counts_per_deg: float | None) -> np.ndarray:
    """The instrument's indicated angle M of each row, in degrees (docs/draft-readings.md#counts-to-angle).

    ``gyro_deg`` where the row has it; otherwise ``gyro_counts / K``. The
    caller chooses K: the value calibrated by 7.1 in the same file when there
    is one, else the metadata ``nominal_scale_factor_counts_per_deg`` (see
    :func:`compute_characteristics`).

    Raises
    ------
    GonioError
        When a row has only counts and no K is given (names the line).

    Examples
    --------
    >>> df = pd.DataFrame({"gyro_deg": [30.0001, float("nan")],
    ...                    "gyro_counts": [float("nan"), 216036.0], "line": [5, 6]})
    >>> indicated_angle_deg(df, 3600.0).tolist()
    [30.0001, 60.01]
    """
    deg = df["gyro_deg"].to_numpy(dtype=float) if "gyro_deg" in df.columns \
        else np.full(len(df), np.nan)
    counts = df["gyro_counts"].to_numpy(dtype=float) if "gyro_counts" in df.columns \
        else np.full(len(df), np.nan)
    need = np.isnan(deg)
    if need.any() and scale_factor_counts_per_deg is None:
        line = int(df["line"].to_numpy()[np.argmax(need)])
        raise GonioError("reading given in counts only, but no scale factor to convert it: "
                         "no scale_factor rows in file and no metadata "
                         "nominal_scale_factor_counts_per_deg", line=line, column="gyro_counts")
    k = np.nan if scale_factor_counts_per_deg is None else float(scale_factor_counts_per_deg)
    return np.where(need, counts / k, deg)


def _needs_counts(rows: pd.DataFrame) -> bool:
    return bool(rows["gyro_deg"].isna().any()) if len(rows) else False


# --------------------------------------------------------------------------- 7.3

def zero_stability(df: pd.DataFrame,
                   scale_factor_counts_per_deg: float | None = None) -> Characteristic:
    """Zero stability B_s, draft 7.3 with the 3.3 reading beside it, in °/h.

    Angle readings M_n (:func:`indicated_angle_deg`) of one series, taken at
    rest, in time order; T = time between first and last reading.

    - 7.3 (the result, ``value``): B_s = s(M) / T, s the Bessel standard
      deviation (n − 1).
    - 3.3 (``range_deg_per_h``): B_s = (max M − min M) / T.
    - beside them, per series in the table, ``drift_deg_per_h``: the least-squares
      slope of M against time (a linear drift, which the certificate's 7.3 figure
      draws; not a result of the draft).

    *Ambiguity* (draft 7.3): "every 5 min for 1 h, giving 15 results" — 1 h at
    5 min gives 13 readings, 15 span 70 min — and 3.3 defines a range, 7.3 a
    standard deviation. Reading taken: use whatever readings the file holds
    (the protocol sets count and spacing, default 15 at 5 min) and report both
    formulas. With several series each is evaluated; ``value`` is the largest
    (the worst series), the table lists all. A series with one reading is not
    used.

    Examples
    --------
    Readings 0, 1e-4, 2e-4 ° at 0, 300, 600 s: s = 1e-4 °, T = 1/6 h, so
    B_s = 6e-4 °/h; range / T = 1.2e-3 °/h.

    >>> df = pd.DataFrame({"test": ["zero_stability"] * 3, "series": [1, 1, 1],
    ...     "round": [1, 2, 3], "time_s": [0.0, 300.0, 600.0],
    ...     "gyro_deg": [0.0, 1e-4, 2e-4], "gyro_counts": [float("nan")] * 3,
    ...     "line": [2, 3, 4]})
    >>> z = zero_stability(df)
    >>> round(z.value, 12), round(z.details["range_deg_per_h"], 12)
    (0.0006, 0.0012)
    """
    name = "zero_stability"
    rows = _rows(df, "zero_stability")
    if rows.empty:
        return _not_measured(name, "no zero_stability rows in file")
    rows = rows.sort_values(["series", "time_s", "round"], kind="stable").copy()
    rows["angle_deg"] = indicated_angle_deg(rows, scale_factor_counts_per_deg)
    per_series = []
    unused: dict[int, str] = {}
    used = []
    for series, g in rows.groupby("series", sort=True):
        if len(g) < 2:
            for l in g["line"]:
                unused[int(l)] = f"zero_stability series {series} has only one reading"
            continue
        t = g["time_s"].to_numpy(dtype=float)
        m = g["angle_deg"].to_numpy(dtype=float)
        duration_s = float(t.max() - t.min())
        if duration_s <= 0:
            raise GonioError(f"zero_stability series {series}: readings span no time "
                             "(T = 0), expected increasing time_s",
                             line=int(g["line"].iloc[-1]), column="time_s")
        t_h = duration_s / S_PER_H
        std = float(np.std(m, ddof=1))
        rng = float(m.max() - m.min())
        slope_deg_per_s, intercept_deg = np.polyfit(t - t.min(), m, 1)
        per_series.append({"series": int(series), "n_readings": int(len(g)),
                           "duration_s": duration_s, "std_deg": std, "range_deg": rng,
                           "B_s_deg_per_h": std / t_h, "B_s_range_deg_per_h": rng / t_h,
                           "drift_deg_per_h": float(slope_deg_per_s) * S_PER_H,
                           "drift_intercept_deg": float(intercept_deg)})
        used.extend(int(l) for l in g["line"])
    if not per_series:
        return Characteristic(name=name, reason="zero_stability needs at least 2 readings "
                              "in a series", unused=unused)
    table = pd.DataFrame(per_series)
    worst = int(np.argmax(table["B_s_deg_per_h"].to_numpy()))
    readings = rows.loc[rows["line"].isin(used),
                        ["series", "round", "time_s", "angle_deg", "line"]].reset_index(drop=True)
    return Characteristic(
        name=name, value=float(table["B_s_deg_per_h"].iloc[worst]), measured=True,
        details={"range_deg_per_h": float(table["B_s_range_deg_per_h"].max()),
                 "n_readings": int(table["n_readings"].iloc[worst]),
                 "duration_s": float(table["duration_s"].iloc[worst]),
                 "series": int(table["series"].iloc[worst])},
        table=table, tables={"readings": readings}, used_lines=frozenset(used), unused=unused)


# --------------------------------------------------------------------------- 7.4, 7.5

def signed_extreme(values) -> float:
    """The draft's "E = ± max |E_i|" (7.4) as one signed number.

    Reading taken: the E_i of largest magnitude with its own sign (the first
    one on a tie); the magnitude alone is ``abs`` of it. The alternative, an
    unsigned ± bound, loses the sign 7.6 and 7.7 need for max E − min E.

    >>> signed_extreme([0.1, -0.3, 0.2])
    -0.3
    """
    v = np.asarray(values, dtype=float)
    v = v[~np.isnan(v)]
    if v.size == 0:
        return math.nan
    return float(v[int(np.argmax(np.abs(v)))])


def _condition_mask(rows, rate_dps, orientation):
    return np.isclose(rows["rate_dps"].to_numpy(dtype=float), rate_dps, rtol=1e-9, atol=0) & \
        (rows["orientation"].to_numpy() == orientation)


def _deviation_tables(rows: pd.DataFrame, k: float | None):
    """Per reading E_ij (″) and per point (round) mean E_i, Bessel s, M, n_series."""
    m_deg = indicated_angle_deg(rows, k)
    s_deg = rows["table_deg"].to_numpy(dtype=float)
    long = pd.DataFrame({"series": rows["series"].to_numpy(), "round": rows["round"].to_numpy(),
                         "table_deg": s_deg, "M_deg": m_deg,
                         "E_arcsec": (m_deg - s_deg) * ARCSEC_PER_DEG,
                         "line": rows["line"].to_numpy()})
    long = long.sort_values(["round", "series"], kind="stable").reset_index(drop=True)
    g = long.groupby("round", sort=True)
    points = pd.DataFrame({
        "position_deg": g["table_deg"].mean(),
        "E_arcsec": g["E_arcsec"].mean(),
        "n_series": g["series"].count().astype(np.int64),
        "s_arcsec": g["E_arcsec"].std(ddof=1),
        "M_deg": g["M_deg"].mean(),
    }).reset_index()
    return long, points


def _condition_rows(df, test, rate_dps, orientation):
    rows = _rows(df, test)
    mask = _condition_mask(rows, rate_dps, orientation)
    return rows[mask], rows[~mask]


def _k_details(rows, k):
    return {"scale_factor_for_angles_counts_per_deg": k if _needs_counts(rows) else None}


def angle_deviation(df: pd.DataFrame, scale_factor_counts_per_deg: float | None = None, *,
                    reference_rate_dps: float = 60.0,
                    reference_orientation: str = "up") -> Characteristic:
    """Angle-position deviation E, draft 7.4 (and 3.6), in ″.

    For each calibration point (round i, position = its ``table_deg``) and
    series j: E_ij = (M_ij − S_ij) · 3600, M the indicated angle
    (:func:`indicated_angle_deg`), S = ``table_deg``. The draft's text is a
    single run. Reading taken: E_i = mean of E_ij over the series present at
    the point (with one series, that series), and E = :func:`signed_extreme`
    of the E_i; ``max_abs_arcsec`` = max |E_i|. Only ``angle_deviation`` rows
    at the 7.4 condition (60 °/s, axis up by default) are used.

    Returns
    -------
    Characteristic
        ``table``: per point (round, position_deg, E_arcsec, n_series,
        s_arcsec, M_deg); ``tables["readings"]``: every E_ij;
        ``tables["matrix"]``: E_ij wide, one column per series.

    Examples
    --------
    Two points, two series: E_1 = mean(0.36, 0.72) = 0.54″,
    E_2 = mean(−1.08, −0.72) = −0.9″, so E = −0.9″.

    >>> df = pd.DataFrame({"test": ["angle_deviation"] * 4, "series": [1, 2, 1, 2],
    ...     "round": [1, 1, 2, 2], "rate_dps": [60.0] * 4, "orientation": ["up"] * 4,
    ...     "table_deg": [30.0, 30.0, 60.0, 60.0],
    ...     "gyro_deg": [30.0001, 30.0002, 59.9997, 59.9998],
    ...     "gyro_counts": [float("nan")] * 4, "line": [2, 3, 4, 5]})
    >>> e = angle_deviation(df)
    >>> round(e.value, 9), round(e.details["max_abs_arcsec"], 9)
    (-0.9, 0.9)
    """
    name = "angle_deviation"
    rows, other = _condition_rows(df, "angle_deviation", reference_rate_dps,
                                  reference_orientation)
    cond = f"{reference_rate_dps:g} deg/s, axis {reference_orientation}"
    unused = {int(l): f"angle_deviation row not at the 7.4 condition ({cond})"
              for l in other["line"]}
    if rows.empty:
        reason = "no angle_deviation rows in file" if other.empty else \
            f"no angle_deviation rows at the 7.4 condition ({cond})"
        return Characteristic(name=name, reason=reason, unused=unused)
    long, points = _deviation_tables(rows, scale_factor_counts_per_deg)
    value = signed_extreme(points["E_arcsec"])
    at = int(np.argmax(np.abs(points["E_arcsec"].to_numpy()) == abs(value)))
    matrix = long.pivot(index="round", columns="series", values="E_arcsec")
    matrix.columns = [f"series_{c}" for c in matrix.columns]
    matrix.insert(0, "position_deg", points.set_index("round")["position_deg"])
    matrix = matrix.reset_index()
    details = {"max_abs_arcsec": abs(value), "position_deg": float(points["position_deg"][at]),
               "n_points": int(len(points)), "n_series": int(rows["series"].nunique())}
    details.update(_k_details(rows, scale_factor_counts_per_deg))
    return Characteristic(
        name=name, value=value, measured=True, details=details,
        table=points[["round", "position_deg", "E_arcsec", "n_series", "s_arcsec", "M_deg"]],
        tables={"readings": long, "matrix": matrix}, used_lines=_lines(rows), unused=unused)


def repeatability(df: pd.DataFrame, scale_factor_counts_per_deg: float | None = None, *,
                  reference_rate_dps: float = 60.0,
                  reference_orientation: str = "up") -> Characteristic:
    """Angle-position repeatability R, draft 7.5 (and 3.7), in ″.

    The series j = 1…10 of 7.4: R_i = Bessel standard deviation of E_ij over
    j at point i, R = max R_i. Needs at least two series; points with one
    series have no R_i (NaN in the table, readings not used).

    Examples
    --------
    Point 1: E = 0.36, 0.72″ → R_1 = 0.36/√2; point 2: −1.08, −0.36″ →
    R_2 = 0.72/√2 = 0.509…″ = R. Series that agree to the last digit at every point are no
    repeatability measurement (a copied or filled column): not measured, said why, never
    R = 0.

    >>> df = pd.DataFrame({"test": ["angle_deviation"] * 4, "series": [1, 2, 1, 2],
    ...     "round": [1, 1, 2, 2], "rate_dps": [60.0] * 4, "orientation": ["up"] * 4,
    ...     "table_deg": [30.0, 30.0, 60.0, 60.0],
    ...     "gyro_deg": [30.0001, 30.0002, 59.9997, 59.9999],
    ...     "gyro_counts": [float("nan")] * 4, "line": [2, 3, 4, 5]})
    >>> round(repeatability(df).value, 9)
    0.509116882
    """
    name = "repeatability"
    rows, other = _condition_rows(df, "angle_deviation", reference_rate_dps,
                                  reference_orientation)
    if rows.empty and other.empty:
        return _not_measured(name, "no angle_deviation rows in file")
    if rows.empty:
        return _not_measured(name, "no angle_deviation rows at the 7.4 condition "
                             f"({reference_rate_dps:g} deg/s, axis {reference_orientation})")
    n_series = int(rows["series"].nunique())
    if n_series < 2:
        return _not_measured(name, "repeatability needs at least 2 angle_deviation series, "
                             "file has 1")
    long, points = _deviation_tables(rows, scale_factor_counts_per_deg)
    table = points[["round", "position_deg", "n_series"]].copy()
    table["R_arcsec"] = points["s_arcsec"].to_numpy()
    ok = table.loc[table["n_series"] >= 2, "round"]
    used = long[long["round"].isin(ok)]
    alone = ~long["round"].isin(ok).to_numpy()
    unused = {int(l): f"angle_deviation round {r} has one series only, no repeatability"
              for l, r in zip(long["line"][alone], long["round"][alone])}
    r = table["R_arcsec"].to_numpy(dtype=float)
    if not np.nanmax(r) > 0:
        return _not_measured(name, "the series agree to the last digit at every point (a "
                             "copied or filled column, or readings rounded coarser than their "
                             "scatter): R would be certified as 0")
    at = int(np.nanargmax(r))
    details = {"position_deg": float(table["position_deg"][at]), "n_series": n_series}
    details.update(_k_details(rows, scale_factor_counts_per_deg))
    return Characteristic(name=name, value=float(r[at]), measured=True, details=details,
                          table=table, used_lines=_lines(used), unused=unused)


# --------------------------------------------------------------------------- 7.6, 7.7

def consistency_reference_angle(points: pd.DataFrame) -> tuple[float, float]:
    """The denominator of C_v (7.6) and C_g (7.7): the reference angle, in ″.

    *Ambiguity*: the draft's formula lost its fraction bar; it reads
    "(max E_v − min E_v) / … 60 °/s". Reading taken (from definitions 3.4 and
    3.5, "divided by the angle result in the reference state"): the angle the
    instrument measured in the reference condition on the full 360° round,
    i.e. the mean indicated angle M at the reference condition's point of
    largest position (360° in the draft's 12-round run). The alternative
    reading, dividing by E at 60 °/s, makes the ratio blow up when E is small.
    The spread max E − min E in ″ is reported beside it, unambiguously.

    Parameters
    ----------
    points : pandas.DataFrame
        Per-point table of the reference condition (``position_deg``, ``M_deg``).

    Returns
    -------
    (angle_arcsec, position_deg)

    Examples
    --------
    >>> angle, pos = consistency_reference_angle(pd.DataFrame(
    ...     {"position_deg": [30.0, 360.0], "M_deg": [30.0, 360.0001]}))
    >>> round(angle, 6), pos
    (1296000.36, 360.0)
    """
    i = int(np.argmax(points["position_deg"].to_numpy(dtype=float)))
    return (float(points["M_deg"].iloc[i]) * ARCSEC_PER_DEG,
            float(points["position_deg"].iloc[i]))


def consistency_incomplete(per_cond: list, fmt, clause: str) -> str | None:
    """*Ambiguity* (7.6, 7.7): a condition that lacks a calibration position the others have.

    7.6 "calibrate E at each rate (E_v)", 7.7 "calibrate E in each [direction] (E_g)": E at
    a condition is 7.4's result, ± max |E_i| over the programme's calibration points. A
    position read in no series of a condition leaves that condition without a 7.4 E (the
    extreme over fewer points is at most as large), and neither remedy gives the clause's C:
    setting the condition aside makes the range over fewer conditions (one missing 1 °/s
    reading took the most adverse rate away, C_v 1.5 → 0.26 ppm, stated over the programme),
    and comparing only the positions every condition shares changes every other condition's
    E. **Reading taken**: a position (rounded to ``POSITION_DECIMALS``) of the reference
    condition (7.4's points), or that at least two conditions of the item have, and that
    another condition has in none of its series makes the item not measured; the reason
    names each such condition and its missing positions. A position read at one condition
    only, not the reference, is not compared (listed unused). A position missing from
    some series of a condition only is not missing: its mean is over the series that read
    it, and the item's uncertainty takes the fewer series (its repeatability term).

    Returns the reason, or None when every condition has every position.

    >>> p = lambda *k: (None, None, None, None, pd.DataFrame({"key": list(k)}), False)
    >>> fmt = lambda v: "x"
    >>> r = consistency_incomplete([p(30.0, 60.0), p(30.0, 60.0), p(30.0)], fmt, "7.6")
    >>> r.split(": ", 1)[1].split(";")[0]
    'x lacks 60 deg (1 of 2 positions)'
    >>> consistency_incomplete([p(30.0, 60.0), p(60.0, 30.0, 90.0)], fmt, "7.6") is None
    True
    >>> ref = (None, None, None, None, pd.DataFrame({"key": [30.0, 60.0]}), True)
    >>> consistency_incomplete([ref, p(30.0)], fmt, "7.7") is None
    False
    """
    have = [set(p["key"]) for *_, p, _ in per_cond]
    seen = [x for h in have for x in h]
    target = {x for x in set(seen) if seen.count(x) >= 2}
    target |= set().union(*(h for h, (*_, ref) in zip(have, per_cond) if ref))
    short = [(v, sorted(target - h)) for (v, *_), h in zip(per_cond, have) if target - h]
    if not short:
        return None
    said = "; ".join(f"{fmt(v)} lacks {', '.join(f'{x:g}' for x in miss)} deg "
                     f"({len(target) - len(miss)} of {len(target)} positions)"
                     for v, miss in short)
    return (f"{clause} compares E over the same calibration positions at every condition: "
            f"{said}; not stated from fewer conditions or positions (read the missing "
            "position again)")


def consistency_missing_conditions(values, conditions, fmt, clause: str) -> str | None:
    """*Ambiguity* (7.6, 7.7): a condition of the programme with no reading at all.

    7.6 "calibrate E at each rate", 7.7 "in each [direction]": C is the range of E over
    the programme's conditions. A condition with no reading leaves that range unknown (the
    range over fewer conditions is at most as large: every 1 °/s reading deleted gave C_v
    0.50 ppm over 6 of 7 rates, 1.21 ppm over the seven). **Reading taken**: the
    programme's conditions (the protocol's rates or orientations with the reference; the
    draft's default programme when no protocol is named, ``ogam-draft``) define the item;
    a condition of them read in no row (its own test's rows, or 7.4's rows for the
    reference) makes the item not measured, the reason naming each missing condition, as
    a missing position does (:func:`consistency_incomplete`). ``conditions`` None (the
    items called without a programme): the conditions read are the programme.

    Returns the reason, or None when every condition of the programme was read.

    >>> fmt = lambda v: f"{v:g} deg/s"
    >>> consistency_missing_conditions([60.0, 10.0], (1.0, 10.0, 60.0), fmt, "7.6")[:60]
    '7.6 compares E at every condition of the programme: 1 deg/s '
    >>> consistency_missing_conditions([60.0, 10.0], (10.0, 60.0), fmt, "7.6") is None
    True
    """
    if conditions is None:
        return None
    missing = [c for c in conditions if not any(_same_condition(c, v) for v in values)]
    if not missing:
        return None
    n = len(conditions)
    return (f"{clause} compares E at every condition of the programme: "
            f"{', '.join(fmt(c) for c in missing)} has no reading ({n - len(missing)} of "
            f"{n} conditions read); not stated from fewer conditions (read the missing "
            "condition)")


def consistency_order(groups, conditions=None) -> list[int]:
    """The order 7.6 and 7.7 take their conditions in — the rows of the item's table, and
    the order in which its Monte Carlo lines draw for them: the programme's order
    (``conditions``, the protocol's rates or orientations), a condition it does not list
    after those in ascending order (rates) or by name (orientations), and the reference
    read from 7.4's rows last. ``groups``: (condition value, source test) in the order
    the file first holds them; the file's row order never enters (the same readings in
    another order gave C_v 0.364 and 0.324 ppm: the draws fell to other conditions).
    Returns the indices of ``groups`` in that order.

    >>> consistency_order([(100.0, "rate_consistency"), (1.0, "rate_consistency"),
    ...                    (60.0, "angle_deviation"), (10.0, "rate_consistency")],
    ...                   (1.0, 10.0, 60.0, 100.0))
    [1, 3, 0, 2]
    >>> consistency_order([("east", "pointing_consistency"), ("north", "pointing_consistency")])
    [0, 1]
    """
    def rank(v) -> float:
        return next((float(j) for j, c in enumerate(conditions or ())
                     if _same_condition(c, v)), math.inf)

    # one item's conditions are all rates or all orientations: v orders them among themselves
    return sorted(range(len(groups)), key=lambda i: (groups[i][1] == "angle_deviation",
                                                      rank(groups[i][0]), groups[i][0]))


def _same_condition(a, b) -> bool:
    """Two 7.6/7.7 conditions are the same: orientations by name, rates to 10⁻⁹."""
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=0.0)


def _consistency(df, k, *, name, test, cond_col, ref_value, fixed_col, fixed_value,
                 fmt, scale, conditions=None):
    """E per condition (7.6 rates, 7.7 orientations), spread and ratio."""
    rows = _rows(df, test)
    if rows.empty:
        return _not_measured(name, f"no {test} rows in file")
    if fixed_col == "orientation":
        fixed_ok = rows["orientation"].to_numpy() == fixed_value
        fixed_txt = f"axis {fixed_value}"
    else:
        fixed_ok = np.isclose(rows["rate_dps"].to_numpy(dtype=float), fixed_value,
                              rtol=1e-9, atol=0)
        fixed_txt = f"{fixed_value:g} deg/s"
    unused = {int(l): f"{test} row not at {fixed_txt}, the fixed condition of "
              f"{_CLAUSES[name]}" for l in rows.loc[~fixed_ok, "line"]}
    rows = rows[fixed_ok]
    if rows.empty:
        return Characteristic(name=name, reason=f"no {test} rows at {fixed_txt}", unused=unused)
    groups: list[tuple[Any, str, pd.DataFrame]] = [
        (v, test, g) for v, g in rows.groupby(cond_col, sort=False)]
    is_ref = [(np.isclose(v, ref_value, rtol=1e-9, atol=0) if cond_col == "rate_dps"
               else v == ref_value) for v, _, _ in groups]
    ref_txt = fmt(ref_value)
    if not any(is_ref):
        ref_rows, _ = _condition_rows(df, "angle_deviation",
                                      ref_value if cond_col == "rate_dps" else fixed_value,
                                      ref_value if cond_col == "orientation" else fixed_value)
        if ref_rows.empty:
            reason = (f"no reference condition ({ref_txt}): neither {test} nor "
                      f"angle_deviation rows there")
            for l in rows["line"]:
                unused.setdefault(int(l), reason)
            return Characteristic(name=name, reason=reason, unused=unused)
        groups.append((ref_value, "angle_deviation", ref_rows))
        is_ref.append(True)
    order = consistency_order([(v, src) for v, src, _ in groups], conditions)
    groups, is_ref = [groups[i] for i in order], [is_ref[i] for i in order]
    reason = consistency_missing_conditions([v for v, _, _ in groups], conditions, fmt,
                                            _CLAUSES[name])
    if reason is not None:
        for _, _, g in groups:
            for l in g["line"]:
                unused.setdefault(int(l), reason)
        return Characteristic(name=name, reason=reason, unused=unused)
    if len(groups) < 2:
        reason = f"{_CLAUSES[name]} needs at least 2 conditions, file has only {ref_txt}"
        for l in rows["line"]:
            unused.setdefault(int(l), reason)
        return Characteristic(name=name, reason=reason, unused=unused)
    per_cond = []
    for (v, src, g), ref in zip(groups, is_ref):
        long, points = _deviation_tables(g, k)
        points["key"] = points["position_deg"].round(POSITION_DECIMALS)
        per_cond.append((v, src, g, long, points, ref))
    reason = consistency_incomplete(per_cond, fmt, _CLAUSES[name])
    if reason is not None:
        for *_, g, _long, _points, _ref in per_cond:
            for l in g["line"]:
                unused.setdefault(int(l), reason)
        return Characteristic(name=name, reason=reason, unused=unused)
    common = set.intersection(*(set(p["key"]) for *_, p, _ in per_cond))
    if len(per_cond) < 2:
        reason = f"{_CLAUSES[name]} needs at least 2 complete conditions"
        for l in rows["line"]:
            unused.setdefault(int(l), reason)
        return Characteristic(name=name, reason=reason, unused=unused)
    if not common:
        reason = "no calibration position common to every condition"
        for l in rows["line"]:
            unused.setdefault(int(l), reason)
        return Characteristic(name=name, reason=reason, unused=unused)
    cond_table, point_tables, used = [], [], set()
    ref_angle = ref_pos = math.nan
    for v, src, g, long, points, ref in per_cond:
        keep = points["key"].isin(common)
        kept = points[keep]
        in_common = long["round"].isin(set(kept["round"])).to_numpy()
        used.update(long["line"][in_common].astype(int).tolist())
        alone = long[~in_common]
        for l, r, pos in zip(alone["line"], alone["round"], alone["round"].map(
                points.set_index("round")["position_deg"])):
            unused.setdefault(int(l), f"{src} round {r} at {pos:g} deg ({fmt(v)}) has no "
                              "counterpart in every other condition")
        e_v = signed_extreme(kept["E_arcsec"])
        cond_table.append({cond_col: v, "source_test": src, "reference": bool(ref),
                           "n_points": int(len(kept)), "n_series": int(g["series"].nunique()),
                           "E_arcsec": e_v, "max_abs_arcsec": abs(e_v)})
        pt = kept[["round", "position_deg", "E_arcsec", "n_series"]].copy()
        pt.insert(0, cond_col, v)
        point_tables.append(pt)
        if ref:
            ref_angle, ref_pos = consistency_reference_angle(points)
    table = pd.DataFrame(cond_table)
    e = table["E_arcsec"].to_numpy(dtype=float)
    spread = float(e.max() - e.min())
    value = spread / ref_angle * scale
    details = {"spread_arcsec": spread, "reference_angle_arcsec": ref_angle,
               "reference_position_deg": ref_pos, "n_conditions": int(len(table))}
    details.update(_k_details(pd.concat([g for _, _, g, *_ in per_cond]), k))
    return Characteristic(name=name, value=float(value), measured=True, details=details,
                          table=table,
                          tables={"points": pd.concat(point_tables, ignore_index=True)},
                          used_lines=frozenset(used), unused=unused)


def rate_consistency(df: pd.DataFrame, scale_factor_counts_per_deg: float | None = None, *,
                     reference_rate_dps: float = 60.0,
                     reference_orientation: str = "up",
                     conditions=None) -> Characteristic:
    """Rate consistency C_v, draft 7.6 (and 3.4), in ppm; spread in ″.

    For each table rate v of the ``rate_consistency`` rows (axis at
    ``reference_orientation``): E_v = :func:`signed_extreme` of the per-point
    means over series, as in :func:`angle_deviation`. If no
    ``rate_consistency`` row is at the reference rate, the ``angle_deviation``
    rows at that rate serve ("if 7.4 is done, 60 °/s need not be repeated").
    A condition missing a position the reference or two conditions have
    leaves C_v not measured (:func:`consistency_incomplete`), and so does a rate of
    ``conditions`` (the programme's rates, reference included; None: the rates read)
    with no reading (:func:`consistency_missing_conditions`); a position read
    at one condition only is not compared (reported unused). C_v = (max E_v − min E_v) / reference angle · 10⁶, the
    reference angle from :func:`consistency_reference_angle`;
    ``spread_arcsec`` = max E_v − min E_v.

    Examples
    --------
    E at 360°: +0.36″ at 60 °/s (reference, M = 360.0001°), −0.36″ at
    10 °/s: spread 0.72″, C_v = 0.72 / 1296000.36 · 10⁶ = 0.5556 ppm.

    >>> df = pd.DataFrame({"test": ["rate_consistency"] * 2, "series": [1, 1],
    ...     "round": [1, 1], "rate_dps": [60.0, 10.0], "orientation": ["up"] * 2,
    ...     "table_deg": [360.0, 360.0], "gyro_deg": [360.0001, 359.9999],
    ...     "gyro_counts": [float("nan")] * 2, "line": [2, 3]})
    >>> c = rate_consistency(df)
    >>> round(c.details["spread_arcsec"], 9), round(c.value, 4)
    (0.72, 0.5556)
    """
    return _consistency(df, scale_factor_counts_per_deg, name="rate_consistency",
                        test="rate_consistency", cond_col="rate_dps",
                        ref_value=float(reference_rate_dps), fixed_col="orientation",
                        fixed_value=reference_orientation, fmt=lambda v: f"{v:g} deg/s",
                        scale=1e6, conditions=conditions)


def pointing_consistency(df: pd.DataFrame, scale_factor_counts_per_deg: float | None = None, *,
                         reference_rate_dps: float = 60.0,
                         reference_orientation: str = "up",
                         conditions=None) -> Characteristic:
    """Pointing consistency C_g, draft 7.7 (and 3.5), in %; spread in ″.

    As :func:`rate_consistency`, over the table-axis directions of the
    ``pointing_consistency`` rows at ``reference_rate_dps`` (up, north/south,
    east/west); reference = axis up, from ``angle_deviation`` rows when there
    is no ``pointing_consistency`` row with the axis up. C_g = (max E_g −
    min E_g) / reference angle · 100. ``conditions``: the programme's orientations
    (reference included), each of which must be read (None: those read).

    Examples
    --------
    >>> df = pd.DataFrame({"test": ["pointing_consistency"] * 2, "series": [1, 1],
    ...     "round": [1, 1], "rate_dps": [60.0] * 2, "orientation": ["up", "east"],
    ...     "table_deg": [360.0, 360.0], "gyro_deg": [360.0, 360.001],
    ...     "gyro_counts": [float("nan")] * 2, "line": [2, 3]})
    >>> c = pointing_consistency(df)
    >>> round(c.details["spread_arcsec"], 9), round(c.value, 10)  # 3.6″ / 1296000″
    (3.6, 0.0002777778)
    """
    return _consistency(df, scale_factor_counts_per_deg, name="pointing_consistency",
                        test="pointing_consistency", cond_col="orientation",
                        ref_value=reference_orientation, fixed_col="rate_dps",
                        fixed_value=float(reference_rate_dps), fmt=lambda v: f"axis {v}",
                        scale=100.0, conditions=conditions)


# --------------------------------------------------------------------------- all seven

@dataclass
class CalibrationResults:
    """The seven characteristics of one readings file, in Annex B order.

    ``unused_readings`` lists every input row no characteristic used
    (columns line, test, series, round, rate_dps, orientation, reason).
    ``scale_factor_for_angles_counts_per_deg`` and its ``..._source`` say
    which K converted counts to angles (``"7.1"``, ``"argument"``,
    ``"metadata"`` or None).
    """

    scale_factor: Characteristic
    scale_factor_nonlinearity: Characteristic
    zero_stability: Characteristic
    angle_deviation: Characteristic
    repeatability: Characteristic
    rate_consistency: Characteristic
    pointing_consistency: Characteristic
    unused_readings: pd.DataFrame
    scale_factor_for_angles_counts_per_deg: float | None = None
    scale_factor_for_angles_source: str | None = None

    def items(self) -> list[Characteristic]:
        """The seven results in Annex B order."""
        return [getattr(self, n) for n in ITEM_KEYS]

    def to_dict(self) -> dict:
        """JSON-able dict: the seven keys plus ``unused_readings`` (list of row dicts)."""
        out = {c.name: c.to_dict() for c in self.items()}
        un = self.unused_readings
        out["unused_readings"] = _records(un.iloc[:LISTED_ROWS])
        if len(un) > LISTED_ROWS:
            out["unused_readings_summary"] = {
                "total": int(len(un)), "listed": LISTED_ROWS,
                "listed_are": f"the first {LISTED_ROWS} by line",
                "by_reason": {str(k): int(v) for k, v in
                              un["reason"].value_counts(sort=False).sort_index().items()}}
        return out


def _unused_reason_default(test: str) -> str:
    if test == "equal_division":
        return "equal_division is not one of the seven clause-7 items (see gonio.specs.ogam_draft.equal_division)"
    if test == "tilt_estimate":
        return "tilt_estimate is not one of the seven clause-7 items (see gonio.specs.ogam_draft.tilt)"
    return "not used by any characteristic"


def compute_characteristics(readings: Readings | pd.DataFrame, *,
                            reference_rate_dps: float = 60.0,
                            reference_orientation: str = "up",
                            nominal_scale_factor_counts_per_deg: float | None = None,
                            rates_dps=None, orientations=None,
                            scale_factor_deg=None) -> CalibrationResults:
    """All seven characteristics of draft clause 7 from one readings file.

    Counts are turned into angles with K from 7.1 when the file has
    ``scale_factor`` rows, else ``nominal_scale_factor_counts_per_deg`` (the
    argument, then the metadata key of that name). An item whose readings
    are absent, or whose counts cannot be converted, is not measured, with
    the reason; the others are still computed. ``rates_dps``, ``orientations``: the
    programme's 7.6 rates and 7.7 orientations, reference included (the calibration passes
    the protocol's, the draft's default programme when none is named); a condition of them
    without a reading makes the item not measured (:func:`consistency_missing_conditions`).
    None: the conditions read are the programme (the items without a protocol).
    ``scale_factor_deg``: the programme's 7.1 angles, K_l's rounds
    (:func:`nonlinearity_missing_rounds`); None: the rounds read.

    Examples
    --------
    >>> df = pd.DataFrame({"test": ["scale_factor", "scale_factor", "equal_division"],
    ...     "series": [1, 1, 1], "round": [1, 2, 1], "rate_dps": [60.0] * 3,
    ...     "orientation": ["up"] * 3, "time_s": [3.0, 65.0, 0.0],
    ...     "table_deg": [60.0, 120.0, 30.0], "gyro_counts": [216000.0, 432036.0, 108000.0],
    ...     "gyro_deg": [float("nan")] * 3, "line": [2, 3, 4]})
    >>> res = compute_characteristics(df)
    >>> res.scale_factor.value, res.angle_deviation.measured
    (3600.15, False)
    >>> res.angle_deviation.reason
    'no angle_deviation rows in file'
    >>> res.unused_readings["line"].tolist()
    [4]
    """
    if isinstance(readings, Readings):
        df, metadata, file = readings.data, readings.metadata, readings.path
    else:
        df, metadata, file = readings, {}, None
    df = df.copy()
    if "rate_dps" not in df.columns:
        df["rate_dps"] = 60.0
    if "orientation" not in df.columns:
        df["orientation"] = "up"
    for col in ("gyro_counts", "gyro_deg"):
        if col not in df.columns:
            df[col] = np.nan
    try:
        sf = scale_factor(df)
    except GonioError as exc:
        raise GonioError(exc.message, file=file, line=exc.line, column=exc.column) from None
    nl = scale_factor_nonlinearity(sf, scale_factor_deg)
    if sf.measured:
        k, k_src = sf.value, "7.1"
    elif nominal_scale_factor_counts_per_deg is not None:
        k, k_src = float(nominal_scale_factor_counts_per_deg), "argument"
    else:
        k = metadata_float(metadata, "nominal_scale_factor_counts_per_deg", file=file)
        k_src = None if k is None else "metadata"
    kw = dict(reference_rate_dps=reference_rate_dps, reference_orientation=reference_orientation)
    no_k = ("readings given in counts only, but no scale factor: no scale_factor rows in "
            "file and no nominal_scale_factor_counts_per_deg")

    def run(func, tests, *args, **kwargs):
        name = func.__name__
        rows = df[df["test"].isin(tests)]
        if k is None and _needs_counts(rows):
            return _not_measured(name, no_k, rows)
        try:
            return func(*args, **kwargs)
        except GonioError as exc:
            raise GonioError(exc.message, file=file, line=exc.line,
                             column=exc.column) from None

    zs = run(zero_stability, ["zero_stability"], df, k)
    ad = run(angle_deviation, ["angle_deviation"], df, k, **kw)
    rp = run(repeatability, ["angle_deviation"], df, k, **kw)
    rc = run(rate_consistency, ["rate_consistency", "angle_deviation"], df, k,
             conditions=rates_dps, **kw)
    pc = run(pointing_consistency, ["pointing_consistency", "angle_deviation"], df, k,
             conditions=orientations, **kw)
    results = [sf, nl, zs, ad, rp, rc, pc]
    used = frozenset().union(*(r.used_lines for r in results))
    reasons: dict[int, str] = {}
    for r in results:
        for line, why in r.unused.items():
            reasons.setdefault(line, why)
    unused = df[~df["line"].isin(used)].sort_values("line")
    table = unused[["line", "test", "series", "round", "rate_dps", "orientation"]].copy()
    table["reason"] = [reasons.get(int(l), _unused_reason_default(t))
                       for l, t in zip(unused["line"], unused["test"])]
    return CalibrationResults(sf, nl, zs, ad, rp, rc, pc,
                              unused_readings=table.reset_index(drop=True),
                              scale_factor_for_angles_counts_per_deg=k,
                              scale_factor_for_angles_source=k_src)


def _fmt_value(c: Characteristic) -> str:
    if not c.measured or c.value is None:
        return "not measured"
    if c.name == "scale_factor":
        return f"{c.value:.9g}"
    if c.name == "angle_deviation":
        return f"±{abs(c.value):.3g} (signed {c.value:+.3g})"
    return f"{c.value:.4g}"


def summary_table(results: CalibrationResults) -> str:
    """Fixed-width text table of the seven items: item, clause, result, unit (Annex B).

    Examples
    --------
    >>> df = pd.DataFrame({"test": ["scale_factor"] * 2, "series": [1, 1], "round": [1, 2],
    ...     "time_s": [3.0, 65.0], "table_deg": [60.0, 120.0],
    ...     "gyro_counts": [216000.0, 432036.0], "line": [2, 3]})
    >>> print(summary_table(compute_characteristics(df)).splitlines()[2])
    1  scale factor K                  7.1        3600.15        counts/deg
    """
    head = ["#", "item", "clause", "result", "unit"]
    rows = []
    for i, c in enumerate(results.items(), 1):
        result = _fmt_value(c)
        rows.append([str(i), c.title, c.clause, result, c.unit if c.measured else ""])
    widths = [max(len(r[j]) for r in rows + [head]) for j in range(5)]
    widths[3] = max(widths[3], 13)
    fmt_row = lambda r: "  ".join(s.ljust(w) for s, w in zip(r, widths)).rstrip()
    lines = [fmt_row(head), "  ".join("-" * w for w in widths)]
    lines += [fmt_row(r) for r in rows]
    notes = [f"{i}. {c.title}: {c.reason}" for i, c in enumerate(results.items(), 1)
             if not c.measured]
    if notes:
        lines += ["", "not measured:"] + ["  " + n for n in notes]
    return "\n".join(lines) + "\n"
