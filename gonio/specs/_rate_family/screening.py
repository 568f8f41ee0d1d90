"""Screening of rate-gyro readings (JJF 1535, IEC 62047-20): every reading is
checked against what the rest of its segment predicts, in every column, and the programme
against the protocol. Each specification's ``screen(readings, protocol)`` calls these rules
with its own programme; the calibration sets the flagged rows aside, states every
finding in ``results.json`` (``findings``) and on the certificate, and lists every row set
aside in ``results.json``'s ``unused_readings`` (:func:`unused_readings`).

Rules (one segment = the rows of one test, run and step, in time order):

* ``output-outlier`` of a record of ≥ 200 rows (not vibration) — the Hampel rule
  (:func:`hampel_residuals`): y against its running median over 21 samples, set aside beyond
  8·1.4826·the local median departure (101 samples, at least the segment's); of a rate
  point (8–199 rows): |y − its median| > 10·1.4826·max(its MAD, the test's pooled MAD).
* ``record-damaged`` — more than 5 % (and ≥ 3) of the outputs of a segment of ≥ 20 rows, or in a
  record at least max(5, 0.1 %) of the rows between 5 and 8 robust σ: refused, naming the
  first (bias records full of ±1000 spikes passed with B_s 48 ± 9 for 19 °/h).
* ``label-departs`` — ≤ 2 rows whose (test, run, step) differs from that of the rows just
  before and after them: set aside (a typo moving a reading into a segment of its own).
* ``output-outlier`` of a vibration segment — the output against its two neighbours, r = y_i − (y_{i−1} + y_{i+1})/2:
  a row is set aside when |r| > 15·1.4826·(median |r| over the 21 rows around it, at least
  the segment's) and is the local maximum (a spike lifts its neighbours by half) — a robust
  15σ of the local scale, which a smooth trend raises with itself, so a warm-up transient
  or a vibration sine is not flagged; a slip of a digit above the noise is. A segment of
  fewer than 8 rows: |y − its median| > 10·1.4826·(median of |y − median| pooled over the
  test's short segments). Also the reference rate of a vibration segment.
* ``setting-departs`` — rate, frequency, temperature, supply voltage, axes, role and stand
  angle are settings of the segment (a value given where the segment's other rows have none,
  or the reverse, is set aside too): a row whose value differs from the segment's median by more
  than max(10·1.4826·MAD, tolerance) (rate 10⁻⁶ relative + 10⁻⁹ °/s, temperature 1 °C,
  supply 0.01 V, frequency 10⁻⁶ relative, stand angle 0.01°; axes: any difference) is set
  aside.
* ``time-departs`` — times of a segment lie on a grid t₀ + n·Δt (Δt the median step, t₀
  the grid's phase as the circular mean of the rows' fractional steps): a row more than
  Δt/4 off the grid is set aside.
* ``time-gap`` — whole samples missing from the grid (n jumps by more than one): flagged,
  not set aside — the rows around a gap are good; the certificate names the gap.
* ``run-sign-departs`` — a run of a scale-factor test (``scale_factor``,
  ``sf_temperature``) whose output-against-rate slope has the other sign than the
  majority of the test's runs is refused, naming its first line.
* ``coarse-quantisation`` — a record whose noise is below one step of the output's
  resolution: flagged once per test (its noise items hold the rounding's q/√12).
* ``setting-departs`` with no majority — a set column with no value on more than half of a
  segment's rows (a column blank on every other row) is refused: the typos cannot be told.
* ``sample-interval-departs`` — a record (bias, warm-up, static, temperature) whose median
  time step departs from the protocol's sample interval by more than 1 %: refused, naming
  the test, run and both intervals (its items are defined at the protocol's interval).
* ``off-programme`` — a whole step (not a rest) at a rate the protocol does not plan for its
  test and run (a rate mistyped on every row of the step): every row set aside and named;
  the planned point it stood for is then named missing.
* ``null_output`` — the null output (metadata, else protocol) leaving a zero-rate bias beyond
  the scale-factor test's largest rate: refused, naming the key and both values
  (:func:`null_output_rule`).
* ``nominal-scale-factor-departs`` — a nominal scale factor more than 10× from the measured
  K, or of the other sign: refused where an item reads it (IEC 62047-20's a_TYP), else
  flagged (:func:`nominal_scale_factor_rule`).
* ``programme-point-missing`` — a rate point, record, position or set point the protocol
  plans and the readings lack is named (flagged: the item is computed from what is there
  and the certificate says what is missing).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
from scipy.ndimage import median_filter

from gonio.analysis.outliers import (DENSE_SHARE, HAMPEL_MIN_ROWS, HAMPEL_WINDOW, K_TAIL,
                                     TAIL_MIN_ROWS, TAIL_P, TAIL_SHARE, hampel_residuals,
                                     moderate_tail, quantum, quantum_floor, too_many_outliers)
from gonio.errors import GonioError
from gonio.formats.rate_readings import RateReadings
from gonio.result.findings import Finding

#: The robust threshold, in units of 1.4826·MAD (a robust σ).
K_ROBUST = 10.0
#: The spike threshold of the output rule, in local robust σ of the second difference.
K_SPIKE = 15.0
#: Absolute tolerances of the setting columns (below them a difference is not a typo).
SETTING_TOL = {"rate_dps": (1e-6, 1e-9), "freq_hz": (1e-6, 0.0), "temperature_c": (0.0, 1.0),
               "supply_v": (0.0, 0.01), "supply_set_v": (0.0, 0.01), "stand_deg": (0.0, 0.01)}
AXES = ("up_axis", "north_axis", "stand_axis")
#: Columns compared as labels (any difference from the segment's most common value).
CATEGORICAL = AXES + ("role",)
#: Setting columns that are measured alongside the output rather than set (a blank or an
#: extra value there is flagged, never a reason to set the row's output aside).
MEASURED = ("temperature_c", "supply_v")


def _finding(code, message, row, column, file, clauses, rule) -> Finding:
    line = row.get("line")
    return Finding(code, message, "set_aside", file=file,
                   line=None if line is None else int(line), column=column,
                   test=str(row["test"]), clause=clauses.get(str(row["test"])), rule=rule)


def spike_residuals(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(r, limit) per sample: r_i = y_i − (y_{i−1} + y_{i+1})/2 (ends: against the one
    neighbour), limit_i = 15·1.4826·median |r| over the 21 samples around i (at least the
    segment's median |r|) — a local robust scale, so a smooth trend (a warm-up transient, a
    sine of the vibration table) raises its own limit — floored at 3 quanta of the output (its smallest non-zero step) and 10⁻⁹ of
    its size. A one-digit slip above the noise stands far above its neighbours' scale.

    >>> y = np.r_[np.zeros(30), 5.0, np.zeros(30)] + 0.01 * np.sin(np.arange(61))
    >>> r, lim = spike_residuals(y)
    >>> [int(i) for i in np.flatnonzero(np.abs(r) > lim)]
    [29, 30, 31]
    """
    n = y.size
    r = np.empty(n)
    r[1:-1] = y[1:-1] - 0.5 * (y[:-2] + y[2:])
    r[0], r[-1] = y[0] - y[1], y[-1] - y[-2]
    local = np.maximum(median_filter(np.abs(r), size=21, mode="nearest"),
                       float(np.median(np.abs(r))))
    return r, np.maximum(K_SPIKE * 1.4826 * local, quantum_floor(y))


#: Segments shorter than this are not refused as a whole (a rate point of a few samples:
#: its outliers are set aside one by one; a noise-free point has no scale to judge by).
DENSE_MIN_SEGMENT = 20


def _output_rule(df, idx: np.ndarray, col: str, file, clauses, pooled=None) -> list[Finding]:
    y = df[col].to_numpy(dtype=float)[idx]
    if y.size < 3 or not np.all(np.isfinite(y)):
        return []
    vib = str(df["test"].iloc[idx[0]]) == "vibration"
    hampel = y.size >= HAMPEL_MIN_ROWS and not vib
    if y.size < 8 or (y.size < HAMPEL_MIN_ROWS and not vib):
        # a short segment (a rate point): against its median, the larger of its own MAD
        # (8 rows or more) and the test's pooled MAD of its short segments
        r = y - np.median(y)
        own = float(np.median(np.abs(r))) if y.size >= 8 else 0.0
        lim = np.full(y.size, max(K_ROBUST * 1.4826 * max(float(pooled or 0.0), own),
                                  quantum_floor(y) if y.size >= 8 else 0.0,
                                  1e-9 * (1.0 + float(np.max(np.abs(y))))))
        rule = "|y − median| > 10·1.4826·max(MAD, pooled MAD of the test's segments < 8 rows)"
    elif hampel:                # a record or rate point: against its running median
        r, lim = hampel_residuals(y)
        rule = "|y_i − running median (21)| > 8·1.4826·local median |y − running median|"
    else:                       # a vibration sine: against its neighbours
        r, lim = spike_residuals(y)
        rule = "|y_i − (y_i−1 + y_i+1)/2| > 15·1.4826·local median"
    out = []
    for i in np.flatnonzero(np.abs(r) > lim):
        # a spike lifts its neighbours' r by half: only the local maximum is the reading
        if y.size < HAMPEL_MIN_ROWS or hampel or \
                abs(r[i]) >= max(abs(r[max(i - 1, 0)]), abs(r[min(i + 1, y.size - 1)])):
            out.append(_finding("output-outlier", f"{col} {y[i]:.10g} departs from its "
                                f"neighbours by {r[i]:+.4g} (limit {lim[i]:.3g})",
                                df.iloc[idx[i]], col, file, clauses, rule))
    if y.size >= DENSE_MIN_SEGMENT and too_many_outliers(len(out), y.size):
        return [_damaged(df, idx, np.abs(r) > lim, col, file, clauses,
                         f"{len(out)} of its {y.size} {col} values are outliers (more than "
                         f"{DENSE_SHARE:.0%}, the first here)",
                         f"outliers > {DENSE_SHARE:.0%} of a segment's rows")]
    if hampel:                  # many below the row limit: a tail no normal record has
        tail = moderate_tail(r, lim)
        if tail is not None:
            return [_damaged(df, idx, tail, col, file, clauses,
                             f"{int(tail.sum())} of its {y.size} {col} values lie beyond "
                             f"{K_TAIL:g} robust σ of the running median (a normal record of "
                             f"this length has {y.size * TAIL_P:.2g}; the first here)",
                             f"count of |y − running median| > {K_TAIL:g}·1.4826·local MAD "
                             f"≥ max({TAIL_MIN_ROWS}, {TAIL_SHARE:g}·n)")]
    return out


def _damaged(df, idx, mask, col, file, clauses, what: str, rule: str) -> Finding:
    """The refused finding of a damaged segment, on the line of its first bad row."""
    row = df.iloc[idx[int(np.flatnonzero(mask)[0])]]
    f = _finding("record-damaged", f"{row['test']} run {row['run']} step {row['step']}: "
                 f"{what}: the record is damaged, not a sample of the gyro", row, col, file,
                 clauses, rule)
    return Finding(**{**f.to_json(), "action": "refused"})


def _setting_rule(df: pd.DataFrame, key: pd.Series, col: str, file, clauses) -> list[Finding]:
    if col in CATEGORICAL:
        v = df[col].astype(str)
        vc = (pd.DataFrame({"k": key.to_numpy(), "v": v.to_numpy()}).groupby(["k", "v"]).size()
              .reset_index(name="n").sort_values(["k", "n"], ascending=[True, False])
              .drop_duplicates("k"))
        mode = key.map(dict(zip(vc["k"], vc["v"])))
        bad = np.flatnonzero((v != mode).to_numpy())
        return [_finding("setting-departs", f"{col} {v.iloc[i]!r} differs from the segment's "
                         f"{mode.iloc[i]!r}", df.iloc[i], col, file, clauses,
                         "axis differs from the segment's") for i in bad]
    v = pd.to_numeric(df[col], errors="coerce")
    # a value where the segment's other rows have none (or the reverse) is a typo too — of a
    # setting the items group by; a measured column (MEASURED: a slow sensor logs every n-th
    # row) is only flagged, its row's output kept; a tie (half and half) is no finding
    present = v.notna()
    share = present.groupby(key).transform("mean")
    absent_odd = ((present & (share < 0.5)) | (~present & (share > 0.5))).to_numpy()
    out = [_finding("setting-departs", f"{col} {'blank' if pd.isna(v.iloc[i]) else f'{v.iloc[i]:.10g}'}"
                    f" where the segment's other rows have "
                    f"{'a value' if pd.isna(v.iloc[i]) else 'none'}", df.iloc[i], col, file,
                    clauses, "a setting present in some rows of a segment only")
           for i in np.flatnonzero(absent_odd)]
    if col in MEASURED:
        sparse = _sparse_logged(df, present, col, file, clauses)
        tests = {f.test for f in sparse}
        out = sparse + [Finding(**{**f.to_json(), "action": "flagged"}) for f in out
                        if f.test not in tests]
    else:
        out += _setting_ties(df, key, v, col, file, clauses)
    med = v.groupby(key).transform("median")
    dev = (v - med).abs()
    mad = dev.groupby(key).transform("median") * 1.4826
    rel, ab = SETTING_TOL[col]
    lim = np.maximum(K_ROBUST * mad, rel * med.abs() + ab)
    bad = [i for i in np.flatnonzero((dev > lim).fillna(False).to_numpy())
           if not (col == "rate_dps" and df["test"].iloc[i] == "vibration")]
    return out + [_finding("setting-departs", f"{col} {v.iloc[i]:.10g} departs from the "
                           f"segment's {med.iloc[i]:.10g} (limit {lim.iloc[i]:.3g})",
                           df.iloc[i], col, file, clauses,
                           "|x − median| > max(10·1.4826·MAD, tolerance)") for i in bad]


#: A measured column logged on every n-th row of a test (n ≥ 2) on at least this share of the
#: gaps between its logged rows is a slow logger's cadence, not a typo.
SPARSE_REGULAR_SHARE = 0.9


def _sparse_logged(df, present: pd.Series, col: str, file, clauses) -> list[Finding]:
    """One flagged ``measured-sparse`` finding per test whose ``col`` (MEASURED) is logged on
    every n-th row (a slow chamber logger, blank between): the blank rows take the value
    interpolated in time within their segment
    (:func:`gonio.specs._rate_family.rate_records.fill_measured`), instead of one finding per
    row."""
    out = []
    for test, idx in df.groupby("test", sort=False).indices.items():
        p = present.to_numpy()[idx]
        logged = np.flatnonzero(p)
        if logged.size < 2 or 2 * logged.size >= idx.size:     # a tie or more: no cadence
            continue
        gaps = np.diff(logged)
        n = int(np.median(gaps))
        if n < 2 or np.mean(gaps == n) < SPARSE_REGULAR_SHARE:
            continue
        row = df.iloc[idx[logged[0]]]
        f = _finding("measured-sparse", f"{test}: {col} logged on 1 row in {n} ({logged.size} "
                     f"of {idx.size} rows); each blank row takes the value interpolated in time "
                     "between the logged rows of its segment", row, col, file, clauses,
                     f"a measured column logged on every n-th row (n ≥ 2, on ≥ "
                     f"{SPARSE_REGULAR_SHARE:.0%} of the gaps)")
        out.append(Finding(**{**f.to_json(), "action": "flagged"}))
    return out


def _setting_ties(df, key, v, col, file, clauses) -> list[Finding]:
    """A set column (not MEASURED) with no majority value in a segment (a blank cell reads
    as the column's default, so a column blank on every other row splits its segment half
    and half): which rows are the typos cannot be told, and the items would group them as
    other points (``rate_dps`` blank on every other row made every item
    'not measured', with 100 findings of missing points and no word on the cause). Refused,
    once per segment, on its first row off the segment's first value."""
    vals = v.fillna(np.inf).to_numpy()
    frame = pd.DataFrame({"k": key.to_numpy(), "v": vals})
    top = frame.groupby(["k", "v"]).size().groupby(level=0).max()
    size = frame.groupby("k").size()
    no_major = (2 * top <= size) & (size >= 2)
    if col == "rate_dps":
        vib = frame["k"][(df["test"] == "vibration").to_numpy()].unique()
        no_major[no_major.index.isin(vib)] = False
    out = []
    for k in no_major.index[no_major.to_numpy()]:
        idx = np.flatnonzero((frame["k"] == k).to_numpy())
        first = vals[idx[0]]
        i = next(j for j in idx if vals[j] != first)
        row = df.iloc[i]
        counts = frame["v"].iloc[idx].value_counts()
        what = ", ".join(f"{'blank' if not np.isfinite(x) else f'{x:.10g}'} on {n}"
                         for x, n in counts.head(3).items())
        f = _finding("setting-departs", f"{row['test']} run {row['run']} step {row['step']}: "
                     f"{col} has no majority value in its {len(idx)} rows ({what}): which "
                     "are the typos cannot be told", row, col, file, clauses,
                     "one value on more than half of a segment's rows")
        out.append(Finding(**{**f.to_json(), "action": "refused"}))
    return out


def _time_rule(df: pd.DataFrame, key: pd.Series, file, clauses) -> list[Finding]:
    t = pd.to_numeric(df["time_s"], errors="coerce")
    dt = t.groupby(key).diff().groupby(key).transform("median")
    u = (t - t.groupby(key).transform("first")) / dt          # grid steps from the first row
    # the grid's phase: circular mean of the fractional steps (a robust t₀ that a gap,
    # unlike a fit of t₀ + i·Δt by row index, does not move)
    z = np.exp(2j * np.pi * (u - np.round(u)))
    phase = np.angle(pd.Series(z, index=t.index).groupby(key).transform("mean")) / (2 * np.pi)
    n = np.round(u - phase)
    off = (u - phase - n) * dt
    ok = (dt > 0).fillna(False)
    bad_mask = ((off.abs() > dt / 4) & ok).fillna(False)
    out = [_finding("time-departs", f"time {t.iloc[k]:.10g} s is {off.iloc[k]:+.4g} s off the "
                    f"segment's sampling grid (step {dt.iloc[k]:.6g} s)", df.iloc[k], "time_s",
                    file, clauses, "|t − (t₀ + n·Δt)| > Δt/4")
           for k in np.flatnonzero(bad_mask.to_numpy())]
    # samples missing from the grid: kept (the rows there are good), named
    # (grid steps between neighbouring good rows) − (rows between them): a row set aside
    # above still occupies its place on the grid
    on_grid = ok & ~bad_mask
    row = pd.Series(np.arange(len(t)), index=t.index).groupby(key).cumcount()
    missing = (n[on_grid].groupby(key[on_grid]).diff()
               - row[on_grid].groupby(key[on_grid]).diff())
    for k in missing.index[(missing > 0).fillna(False).to_numpy()]:
        pos = df.index.get_loc(k)
        f = _finding("time-gap", f"{int(missing[k])} sample(s) missing before time "
                     f"{t.loc[k]:.10g} s (step {dt.loc[k]:.6g} s)", df.iloc[pos], "time_s",
                     file, clauses, "(n_i − n_j) − (i − j) > 0 between neighbouring rows on the grid t₀ + n·Δt")
        out.append(Finding(**{**f.to_json(), "action": "flagged"}))
    return out


#: Tests whose runs each measure the scale factor over ± rates: a run's K has the sign of
#: the others' (cross-axis runs, whose slope is near zero, are not among them).
SLOPE_TESTS = ("scale_factor", "sf_temperature")


def _run_slopes(df: pd.DataFrame, test: str) -> dict:
    """{run: (slope of the step-mean output against the rate, first row)} of one test's
    runs with at least two distinct rates."""
    rows = df[(df["test"] == test) & (df["role"].astype(str) == "rate")] if "role" in df \
        else df[df["test"] == test]
    out = {}
    for run, h in rows.groupby("run", sort=False):
        m = h.groupby("step").agg(r=("rate_dps", "mean"), y=("output", "mean"))
        if m["r"].nunique() >= 2:
            out[run] = (float(np.polyfit(m["r"].to_numpy(float), m["y"].to_numpy(float),
                                         1)[0]), h.iloc[0])
    return out


def sign_rule(df: pd.DataFrame, file=None, clauses: dict | None = None) -> list[Finding]:
    """``run-sign-departs``: a run of a scale-factor test whose output falls with the rate
    while the other runs' rises (or the reverse) — rates or outputs of a whole run entered
    with the wrong sign — is refused, naming the run's first line: averaged in, it gives
    a K of a third of the true one (K = 2.00 ± 17 for 6.00 on the bench). A tie
    (as many runs of each sign) names the first run of the sign the first run lacks."""
    clauses = clauses or {}
    out = []
    for test in SLOPE_TESTS:
        slopes = _run_slopes(df, test)
        signs = {run: np.sign(k) for run, (k, _) in slopes.items() if k != 0}
        if len(set(signs.values())) < 2:
            continue
        pos = sum(v > 0 for v in signs.values())
        major = 1.0 if pos > len(signs) - pos else -1.0 if pos < len(signs) - pos else \
            next(iter(signs.values()))
        for run, sg in signs.items():
            if sg != major:
                k, row = slopes[run]
                others = float(np.median([slopes[r][0] for r in signs if signs[r] == major]))
                f = _finding("run-sign-departs", f"{test} run {run}: output against rate has "
                             f"slope {k:.6g}, the other runs' {others:.6g} (sign differs: "
                             "rates or outputs of this run entered with the wrong sign?)",
                             row, "rate_dps", file, clauses,
                             "sign of a run's slope ≠ the majority of the test's runs")
                out.append(Finding(**{**f.to_json(), "action": "refused"}))
    return out


def quantisation_rule(df: pd.DataFrame, file=None, clauses: dict | None = None
                      ) -> list[Finding]:
    """``coarse-quantisation`` (flagged, one per test): a record (≥ 200 rows, not vibration)
    whose noise is below one step of the output's resolution — the same test as the
    screening's coarse branch of :func:`hampel_residuals`. Its noise and stability items
    then hold the rounding's q/√12 (the acquisition's, not the gyro's): stated, so a
    certificate never presents it as the gyro's noise (output logged to
    1 mV with 0.2 mV noise, IEC in-band noise 0.0483 for 0.0434 with no word)."""
    clauses = clauses or {}
    key = df.groupby(["test", "run", "step"], sort=False).ngroup()
    y_all = df["output"].to_numpy(dtype=float)
    out, seen = [], set()
    for idx in df.groupby(key, sort=False).indices.values():
        test = str(df["test"].iloc[idx[0]])
        if test in seen or test == "vibration" or idx.size < HAMPEL_MIN_ROWS:
            continue
        y = y_all[idx]
        q = quantum(y)
        if not (q > 0 and np.all(np.isfinite(y))):
            continue
        sigma = 1.4826 * float(np.median(np.abs(
            y - median_filter(y, size=HAMPEL_WINDOW, mode="nearest"))))
        if sigma < q:
            seen.add(test)
            f = _finding("coarse-quantisation", f"{test}: the output's resolution {q:.6g} is "
                         f"coarser than its noise (robust σ {sigma:.3g} about the running "
                         f"median): its noise and stability items include the rounding's "
                         f"q/√12 = {q / math.sqrt(12):.3g}, the acquisition's, not the gyro's",
                         df.iloc[idx[0]], "output", file, clauses,
                         "1.4826·median |y − running median (21)| < the output's smallest step")
            out.append(Finding(**{**f.to_json(), "action": "flagged"}))
    return out


#: The finding of a rate file that states no certificate u for its rate table.
RATE_TABLE_UNSTATED_CODE = "rate-table-u-unstated"


def rate_table_unstated(metadata: dict, file, assumed_by: str) -> list[Finding]:
    """A flagged finding where the readings state no ``rate_table_u_rel`` (the rate table's
    certificate u): the budgets then take the table to conform to JJF 1535 Table 2's rate
    accuracy 0.05 % (added linearly at that bound in the items stated by the bound
    condition, :func:`.rate_records.table_bound_statement`; one rectangular line in the
    others, :func:`.rate_records.rate_table_line`), an assumption the certificate states,
    naming whose it is (``assumed_by``: JJF 1535's
    requirement, or the laboratory's own where the specification states none); ``[]``
    where the readings state it.

    >>> [f.code for f in rate_table_unstated({"rate_table_u_rel": "2.5e-4"}, None, "x")]
    []
    >>> f, = rate_table_unstated({}, "r.csv", "JJF 1535 Table 2's requirement")
    >>> f.action, "0.05 %" in f.message, "0.000289" in f.message
    ('flagged', True, True)
    """
    from gonio.specs._rate_family.rate_records import TABLE2_RATE_ACCURACY_REL

    if str(metadata.get("rate_table_u_rel", "") or "").strip():
        return []
    half = TABLE2_RATE_ACCURACY_REL
    return [Finding(RATE_TABLE_UNSTATED_CODE,
                    f"the rate table's uncertainty is not stated (no # rate_table_u_rel): "
                    f"budgeted as a table within ±{100 * half:g} % of the set rate, "
                    f"{assumed_by}: the items stated by the bound condition add the table "
                    f"at ±{100 * half:g} % linearly (U = a + k·u), the others budget it as a "
                    f"rectangular line (u = {half / math.sqrt(3):.3g} relative); a table "
                    "outside it makes the stated U too small — state "
                    "rate_table_u_rel from the table's calibration certificate",
                    "flagged", file=file, column="rate_table_u_rel",
                    rule="the rate table's u stated from its certificate")]


#: The largest zero-rate bias a stated null output may leave in the readings, as a share of
#: the largest rate of the scale-factor test (:func:`null_output_rule`).
NULL_BIAS_SHARE = 1.0
#: The factor by which a stated nominal scale factor may depart from the one the
#: scale-factor test measures, either way (:func:`nominal_scale_factor_rule`).
NOMINAL_SCALE_FACTOR_FACTOR = 10.0


def zero_rate_line(df: pd.DataFrame) -> tuple[float, float, float] | None:
    """(K, F₀, Ω_max) the readings measure: the least-squares line y = F₀ + K·Ω through the
    median output at each rate of the scale-factor test (every run, its rests included), and
    the test's largest |Ω| (°/s); None where the test holds fewer than two rates or the line
    is flat. Medians, not means: a mistyped output moves nothing here.

    >>> df = pd.DataFrame({"test": ["scale_factor"] * 7,
    ...                    "rate_dps": [-10, -10, 0, 0, 0, 10, 10],
    ...                    "output": [2440.0, 2440.0, 2500.0, 9e9, 2500.0, 2560.0, 2560.0]})
    >>> [round(x, 6) for x in zero_rate_line(df)]
    [6.0, 2500.0, 10.0]
    """
    if not {"test", "rate_dps", "output"} <= set(df.columns):
        return None
    rows = df[df["test"].astype(str) == "scale_factor"]
    r = pd.to_numeric(rows["rate_dps"], errors="coerce")
    y = pd.to_numeric(rows["output"], errors="coerce")
    ok = np.isfinite(r.to_numpy(float)) & np.isfinite(y.to_numpy(float))
    med = y[ok].groupby(r[ok]).median()
    if med.size < 2:
        return None
    k, f0 = np.polyfit(med.index.to_numpy(float), med.to_numpy(float), 1)
    if not (np.isfinite(k) and np.isfinite(f0)) or k == 0:
        return None
    return float(k), float(f0), float(np.max(np.abs(med.index.to_numpy(float))))


def null_output_rule(df: pd.DataFrame, null_output: float | None, file=None,
                     unit: str = "", line=None) -> None:
    """Refuse a null output (``null_output``: the metadata's, else the protocol's number)
    that contradicts the zero-rate output the scale-factor test measures.

    Rule: with (K, F₀, Ω_max) of :func:`zero_rate_line`, the zero-rate bias the null output
    leaves in the readings, |F₀ − null_output|/|K|, must not exceed ``NULL_BIAS_SHARE`` ×
    Ω_max; beyond it the GonioError names the key and both values. Reason: every item that
    reads a rate at rest (bias, its repeatability and temperature coefficient, the static
    record) takes (output − null_output)/K; a gyro's bias is a small part of the rates it is
    calibrated over (0.15 °/s of 100 °/s on the bench), so a null output leaving a bias
    beyond the largest rate tested is not a bias but a value in another unit or scale
    (2.5 where 2500 mV is meant would leave a bias of 416 °/s). Nothing is checked where the test
    lacks two rates (then no item has a K either) or no null output is stated. ``line``:
    :func:`zero_rate_line` of ``df`` where the caller fitted it already."""
    line = zero_rate_line(df) if line is None else line
    if line is None or null_output is None:
        return
    k, f0, top = line
    bias, u = abs(f0 - null_output) / abs(k), f" {unit}" if unit else ""
    if bias > NULL_BIAS_SHARE * top:
        raise GonioError(
            f"null_output {null_output:.6g}{u} contradicts the zero-rate output the "
            f"scale-factor test measures, {f0:.6g}{u} (the line through its rates, K {k:.6g}): "
            f"it would leave a bias of {bias:.4g} °/s, beyond the test's largest rate "
            f"{top:g} °/s (a null output in another unit?)", file=file, key="null_output")


def nominal_scale_factor_rule(df: pd.DataFrame, nominal: float | None, file=None,
                              used_by: str | None = None, line=None) -> list[Finding]:
    """A nominal scale factor (``nominal_scale_factor``: the metadata's, else the protocol's
    number) that departs from the K the scale-factor test measures (:func:`zero_rate_line`)
    by more than ``NOMINAL_SCALE_FACTOR_FACTOR`` either way, or has the other sign.

    ``used_by``: the items the nominal enters (IEC 62047-20's a_TYP in the initial
    scale-factor variation and the symmetry): a wrong nominal changes certified numbers, so
    the contradiction is refused (GonioError naming the key and both values). None: no item
    reads it (JJF 1535 computes every item from the measured K): a flagged finding states it
    on the certificate and in results.json. Reason: a gyro's scale factor departs from its
    nominal by percent; a factor of ten or more is a nominal in another unit (V for mV,
    rad for degrees). ``[]`` where it agrees, where no nominal is stated, or where the test
    lacks two rates."""
    line = zero_rate_line(df) if line is None else line
    if line is None or nominal is None or nominal == 0:
        return []
    k = line[0]
    ratio = k / nominal
    if 1.0 / NOMINAL_SCALE_FACTOR_FACTOR <= ratio <= NOMINAL_SCALE_FACTOR_FACTOR:
        return []
    text = (f"nominal_scale_factor {nominal:.6g} departs from the scale factor the "
            f"scale-factor test measures, {k:.6g} (ratio {ratio:.3g}, beyond "
            f"{NOMINAL_SCALE_FACTOR_FACTOR:g}× either way: a nominal in another unit?)")
    if used_by is not None:
        raise GonioError(f"{text}; it enters {used_by}", file=file, key="nominal_scale_factor")
    return [Finding("nominal-scale-factor-departs", f"{text}; no item reads it (every item "
                    "uses the measured K)", "flagged", file=file, column="nominal_scale_factor",
                    rule=f"measured K / nominal within 1/{NOMINAL_SCALE_FACTOR_FACTOR:g} … "
                         f"{NOMINAL_SCALE_FACTOR_FACTOR:g}")]


def metadata_rules(readings, null_default, nominal_default, used_by: str | None = None
                   ) -> list[Finding]:
    """The stated null output and nominal scale factor against what the scale-factor test
    measures (:func:`null_output_rule`, :func:`nominal_scale_factor_rule`), each the
    metadata's value, else its ``*_default`` (the protocol's; None or ``"bench"``: not
    stated, not checked, as the calibration then asks for it)."""
    from gonio.specs._rate_family.rate_records import metadata_number

    md, path = readings.metadata, readings.path
    file = None if path is None else str(path)

    def stated(key, default):
        if not str(md.get(key, "") or "").strip() and default in (None, "bench"):
            return None
        return metadata_number(md, key, default, path)

    line = zero_rate_line(readings.data)         # one fit for both rules
    null_output_rule(readings.data, stated("null_output", null_default), file,
                     str(md.get("output_unit", "") or "").strip(), line=line)
    return nominal_scale_factor_rule(readings.data, stated("nominal_scale_factor",
                                                           nominal_default), file, used_by,
                                     line=line)


def screen(readings, segments, clauses: dict) -> list[Finding]:
    """Every rule on a RateReadings against the planned ``segments`` (the quantisation rule
    where the bench had noise: a noise-free virtual record has none to compare with)."""
    file = None if readings.path is None else str(readings.path)
    noisy = str(readings.metadata.get("noise", "on")).strip().lower() != "off"
    expected = expected_from_plan(segments)
    rows = screen_rows(readings.data, file, clauses)
    aside = {f.line for f in rows if f.action == "set_aside"}
    return interval_rule(readings.data, segments, file, clauses) + rows + sign_rule(
        readings.data, file, clauses) + off_programme_rule(
        readings.data, expected, file, clauses, aside) + missing_points(
        readings.data, expected, file=file, clauses=clauses) + (
        quantisation_rule(readings.data, file, clauses) if noisy else [])


#: Largest relative departure of a record's median time step from the protocol's sample
#: interval (a logger's clock; a record kept at every other sample departs by 100 %).
INTERVAL_TOL = 0.01


def interval_rule(df: pd.DataFrame, segments, file=None, clauses: dict | None = None
                  ) -> list[Finding]:
    """``sample-interval-departs``: a record (role ``record`` of the programme: the bias, warm-up,
    static and temperature records) whose median time step departs from the protocol's sample
    interval by more than 1 % is refused, naming the test, run and both intervals. The items
    of a record are defined at that interval (a bias-stability block of P samples, the Allan
    deviation's τ₀): computed at another, they are another quantity under the same name."""
    clauses = clauses or {}
    planned: dict = {}
    for s in segments:
        if s.role == "record" and s.test != "vibration":
            planned.setdefault(s.test, set()).add(float(s.interval_s))
    out = []
    t_all = pd.to_numeric(df["time_s"], errors="coerce").to_numpy(dtype=float)
    rec = (df["role"].astype(str) == "record").to_numpy()
    groups = df[rec].groupby(["test", "run", "step"], sort=False).indices
    where = np.flatnonzero(rec)
    for (test, run, step), idx in groups.items():
        want = planned.get(str(test))
        steps = np.diff(t_all[where[idx]])
        steps = steps[np.isfinite(steps)]
        if not want or steps.size < 2:
            continue
        m = float(np.median(steps))
        if all(abs(m - dt) > INTERVAL_TOL * dt for dt in want):
            row = df.iloc[where[idx[0]]]
            shown = " or ".join(f"{dt:g}" for dt in sorted(want))
            out.append(_finding("sample-interval-departs",
                                f"{test} run {run} step {step}: the record's median time step "
                                f"is {m:g} s, the protocol's sample interval {shown} s "
                                f"(±{INTERVAL_TOL:.0%})", row, "time_s", file, clauses,
                                "median time step of a record = the protocol's sample "
                                "interval ± 1 %"))
            out[-1] = _refused(out[-1])
    return out


def _refused(f: Finding) -> Finding:
    """The finding ``f`` with the action ``refused``."""
    return dataclasses.replace(f, action="refused")


#: The code of a whole segment set aside (its finding names the segment's first line).
OFF_PROGRAMME = "off-programme"


def off_programme_rule(df: pd.DataFrame, expected: dict, file=None,
                       clauses: dict | None = None, aside=frozenset()) -> list[Finding]:
    """``off-programme``: a whole segment (not a rest) whose rate (its setting: the value most
    of its rows give) is none of the rates the protocol plans for its test and run — a step
    logged at a mistyped rate throughout — is set aside, every row of it, and named; it is
    never fitted at a rate the programme does not have (the planned point it stood for is
    then named missing). One finding per segment, naming its first line: :func:`apply` sets
    the whole segment aside. A segment whose every row is already set aside (``aside``: its
    lines; a reading a label typo moved into a segment of its own) is the other rule's."""
    clauses = clauses or {}
    if "rate_dps" not in df:
        return []
    rates = {k: [v for w, v in wants if w == "rate_dps"] for k, wants in expected.items()}
    seg = segment_values(df, ["rate_dps", "role"])
    rel, ab = MATCH_TOL["rate_dps"]
    bad = {}
    for r in seg.itertuples(index=False):
        want = rates.get((r.test, r.run))
        if not want or str(r.role) == "rest" or not np.isfinite(float(r.rate_dps)):
            continue
        if not np.any(np.isclose(want, float(r.rate_dps), rtol=rel, atol=ab)):
            bad[(r.test, r.run, r.step)] = float(r.rate_dps)
    if not bad:
        return []
    out = []
    for key, idx in df.groupby(["test", "run", "step"], sort=False).indices.items():
        if key not in bad or ("line" in df and set(df["line"].to_numpy()[idx]) <= aside):
            continue
        row, lines = df.iloc[idx[0]], df["line"].to_numpy()[idx] if "line" in df else []
        span = f"; {len(idx)} readings, lines {min(lines)}–{max(lines)}" if len(lines) else ""
        out.append(_finding(OFF_PROGRAMME, f"{row['test']} run {row['run']} step {row['step']}: "
                            f"rate {bad[key]:g} °/s is not a rate of the "
                            f"protocol's programme{span}, all set aside", row, "rate_dps",
                            file, clauses,
                            "every step's rate is one the protocol plans"))
    return out


def screen_rows(df: pd.DataFrame, file=None, clauses: dict | None = None) -> list[Finding]:
    """The row rules over every segment of ``df`` (columns of the rate readings format,
    rows of a segment in time order as a readings file holds them)."""
    clauses = clauses or {}
    key = df.groupby(["test", "run", "step"], sort=False).ngroup()
    out: list[Finding] = []
    groups = list(df.groupby(key, sort=False).indices.values())
    y_all = df["output"].to_numpy(dtype=float)
    tests = df["test"].to_numpy()
    short: dict = {}
    for idx in groups:                   # pooled |y − median| of the short segments per test
        if 3 <= idx.size < 8:
            short.setdefault(tests[idx[0]], []).append(np.abs(y_all[idx] - np.median(y_all[idx])))
    pooled = {t: float(np.median(np.concatenate(v))) for t, v in short.items()}
    for idx in groups:
        out += _output_rule(df, idx, "output", file, clauses, pooled.get(tests[idx[0]]))
        if "reference_dps" in df and df["test"].iloc[idx[0]] == "vibration":
            out += _output_rule(df, idx, "reference_dps", file, clauses)
    for col in list(SETTING_TOL) + list(CATEGORICAL):
        if col in df:
            out += _setting_rule(df, key, col, file, clauses)
    out += _time_rule(df, key, file, clauses)
    return out + label_rule(df, file, clauses)


#: Longest block of rows the label rule treats as mislabelled (a typo touches a row or two).
LABEL_BLOCK = 2


def label_rule(df: pd.DataFrame, file=None, clauses: dict | None = None) -> list[Finding]:
    """``label-departs``: a block of at most 2 consecutive rows whose (test, run, step)
    differs from the rows just before and just after it, which share one — a typo in the
    test, run or step of a reading moves it into a segment of its own (or another), where
    it would be a rate point of one sample; each such row is set aside, naming the column
    that differs."""
    clauses = clauses or {}
    cols = ("test", "run", "step")
    k = df.groupby(list(cols), sort=False).ngroup().to_numpy()
    if k.size < 3:
        return []
    starts = np.flatnonzero(np.r_[True, k[1:] != k[:-1]])      # blocks of equal keys
    ends = np.r_[starts[1:], k.size]
    out = []
    for j in range(1, starts.size - 1):
        a, b = starts[j], ends[j]
        if b - a <= LABEL_BLOCK and k[a - 1] == k[b] != k[a]:
            before = df.iloc[a - 1]
            for i in range(a, b):
                row = df.iloc[i]
                col = next(c for c in cols if str(row[c]) != str(before[c]))
                out.append(_finding("label-departs", f"{col} {row[col]!s} between rows of "
                                    f"{before['test']} run {before['run']} step "
                                    f"{before['step']}", row, col, file, clauses,
                                    "(test, run, step) of ≤ 2 rows ≠ that of the rows "
                                    "before and after"))
    return out


#: Tolerances when matching a planned set point with the readings' (temperature: the
#: chamber deviation of JJF Table 2, ±2 °C, plus margin).
MATCH_TOL = {"rate_dps": (1e-6, 1e-9), "temperature_c": (0.0, 2.5), "supply_v": (0.0, 0.05),
             "stand_deg": (0.0, 0.01)}


def expected_from_plan(segments, skip=("vibration",)) -> dict:
    """{(test, run): [(column, value), …]} of a programme (``plan(protocol, …)`` segments):
    the rate of every non-rest segment, and where set the temperature, supply voltage,
    mounting (g-sensitivity, cross-axis) and stand angle."""
    out: dict = {}
    for s in segments:
        if s.test in skip:
            continue
        want = out.setdefault((s.test, s.run), [])
        items = [] if s.role == "rest" else [("rate_dps", float(s.rate_dps))]
        if s.temperature_c is not None:
            items.append(("temperature_c", float(s.temperature_c)))
        if s.supply_v is not None:
            items.append(("supply_v", float(s.supply_v)))
        if s.test in ("g_sensitivity", "cross_axis"):
            items.append(("up_axis", str(s.up_axis)))
        if s.test == "g_sensitivity" and getattr(s, "stand_deg", None) is not None:
            items.append(("stand_deg", float(s.stand_deg)))
        want += [w for w in items if w not in want]
    return out


def segment_values(df: pd.DataFrame, cols) -> pd.DataFrame:
    """One row per segment (``test``, ``run``, ``step``) with each of ``cols`` the segment's
    setting from its LOGGED rows (blanks are no value, a segment with none is NaN): for a set
    column (``rate_dps``, the axes) the value most of them give (the first of equally common
    ones), which a typo in one row does not change; for a measured column (MEASURED:
    ``temperature_c``, ``supply_v``, a noisy logger whose values all differ, so that no value
    is "most common") the median of the logged values, which one row still on the ramp into
    the segment does not move far. Neither is changed by a slow logger's blanks between its
    rows (a chamber logging every 10th row: its set point, not NaN, is the segment's).

    >>> d = pd.DataFrame({"test": ["sf"] * 4, "run": [0] * 4, "step": [0] * 4,
    ...                   "rate_dps": [10.0, 100.0, 100.0, 100.0]})
    >>> segment_values(d, ["rate_dps"])["rate_dps"].tolist()
    [100.0]
    >>> d = pd.DataFrame({"test": ["t"] * 5, "run": [0] * 5, "step": [0, 0, 0, 1, 1],
    ...                   "temperature_c": [float("nan"), float("nan"), 70.0] + [float("nan")] * 2})
    >>> segment_values(d, ["temperature_c"])["temperature_c"].tolist()
    [70.0, nan]
    >>> d = pd.DataFrame({"test": ["t"] * 5, "run": [0] * 5, "step": [0] * 5,
    ...                   "temperature_c": [45.0, 69.91, 70.04, 69.97, 70.02]})
    >>> segment_values(d, ["temperature_c"])["temperature_c"].tolist()
    [69.97]
    """
    keys = ["test", "run", "step"]
    if not cols:
        return df.groupby(keys, sort=False).first().reset_index()[keys]
    g = df.groupby(keys, sort=False)
    out = g.size().to_frame("_n")
    for c in cols:
        if c in MEASURED:           # the median of the logged numbers, group by group
            x = pd.to_numeric(df[c], errors="coerce")
            out[c] = x.groupby([df[k] for k in keys], sort=False).median().astype(float)
            continue
        # a set column: a segment whose logged cells all agree (the usual case) has that
        # value, with no count per segment; the others are counted as _most_common_logged
        col = g[c]
        one, first = col.nunique(dropna=True), col.first()
        val = first.astype(object).where(one == 1, np.nan)
        for key in one.index[one > 1]:
            val[key] = _most_common_logged(col.get_group(key))
        out[c] = val.infer_objects() if val.dtype == object else val
    return out.drop(columns="_n").reset_index()


def _median_logged(v: pd.Series):
    """The median of ``v``'s logged (not blank, numeric) cells; NaN where none is logged."""
    x = pd.to_numeric(v, errors="coerce").dropna()
    return float(x.median()) if len(x) else np.nan


def _most_common_logged(v: pd.Series):
    """The value most of ``v``'s logged (not blank) cells give, the first of equally common
    ones; NaN where none is logged."""
    counts = v.value_counts(sort=True, dropna=True)
    return counts.index[0] if len(counts) else np.nan


def missing_points(df: pd.DataFrame, expected: dict, *, file=None,
                   clauses: dict | None = None) -> list[Finding]:
    """``expected``: {(test, run): [(what, value), …]} with ``what`` a column (``rate_dps``,
    ``temperature_c``, ``supply_v``, ``up_axis``, ``stand_deg``) and the value each planned
    segment of that run has; a value absent from the readings' segments is named. A run
    absent altogether is named once. A segment's value is its setting
    (:func:`segment_values`: the value most of its rows give for a set column, the median of
    the logged values for a measured one): one row's typo in the set-point column, or a
    measured row still on the ramp, is that row's finding, not a planned point missing."""
    out = []
    clauses = clauses or {}
    cols = sorted({what for wants in expected.values() for what, _ in wants} & set(df.columns))
    seg = segment_values(df, cols)
    for (test, run), wants in expected.items():
        have = seg[(seg["test"] == test) & (seg["run"] == run)]
        cl = clauses.get(test)
        if have.empty:
            if (df["test"] == test).any():
                out.append(Finding("programme-point-missing", f"{test} run {run} (all of it) "
                                   "is missing from the readings", "flagged", file=file,
                                   test=test, clause=cl, rule="every planned run present"))
            continue
        for what, value in wants:
            col = have[what] if what in have else pd.Series([], dtype=object)
            if isinstance(value, str):
                found = (col.astype(str) == value).any()
            else:
                rel, ab = MATCH_TOL.get(what, (1e-9, 1e-9))
                found = bool(np.any(np.isclose(col.to_numpy(dtype=float), value,
                                               rtol=rel, atol=ab)))
            if not found:
                shown = value if isinstance(value, str) else f"{value:g}"
                out.append(Finding("programme-point-missing",
                                   f"{test} run {run}: the planned {what} = {shown} is "
                                   "missing from the readings", "flagged", file=file,
                                   test=test, clause=cl, rule="every planned point present"))
    return out


def set_aside_lines(df: pd.DataFrame, findings: list[Finding]) -> dict[int, Finding]:
    """Every line of ``df`` a ``set_aside`` finding takes out, with the first finding that
    does (in the findings' order): the finding's own line, and for an ``off-programme``
    finding every line of its segment (the rows of its line's test, run and step) — the one
    account :func:`apply` removes and :func:`unused_readings` lists, so the two cannot differ.
    A line the readings do not hold is kept with its finding (the list names it all the same)."""
    out: dict[int, Finding] = {}
    mine = [f for f in findings if f.action == "set_aside" and f.line is not None]
    if not mine or "line" not in df:
        return out
    lines = df["line"].to_numpy()
    key = df.groupby(["test", "run", "step"], sort=False).ngroup().to_numpy() \
        if any(f.code == OFF_PROGRAMME for f in mine) else None
    for f in mine:
        taken = [int(f.line)]
        if f.code == OFF_PROGRAMME and key is not None:   # every row of its segment
            at = np.flatnonzero(lines == f.line)
            if at.size:
                taken = [int(v) for v in lines[key == key[at[0]]]]
        for line in taken:
            out.setdefault(line, f)
    return out


def apply(df: pd.DataFrame, findings: list[Finding]) -> pd.DataFrame:
    """The readings without the rows set aside (by line, :func:`set_aside_lines`; the input
    is not modified)."""
    lines = set_aside_lines(df, findings)
    if not lines:
        return df
    return df[~df["line"].isin(lines)].reset_index(drop=True)


def unused_readings(readings, findings: list[Finding]) -> list[dict]:
    """results.json's ``unused_readings``: one row per line of the readings (as read, before
    the screening) a ``set_aside`` finding takes out (:func:`set_aside_lines`: every row of an
    off-programme step, each listed), in the file's order — ``file``, ``line``, the row's
    ``test``, ``run`` and ``step``, the ``column`` the rule judged (an off-programme step's
    rows: ``rate_dps``) and the finding's message as ``reason``, the shape of the triad's rows
    (docs/formats.md "Results file"). A row set aside is a finding and a reading no item
    used: results.json names it in both, so a reader sees which rows were left out without
    reading the findings."""
    df = readings.data
    file = None if readings.path is None else str(readings.path)
    rows = {}
    if "line" in df:
        for rec in df[["line", "test", "run", "step"]].itertuples(index=False):
            rows[int(rec.line)] = rec
    out = []
    for line, f in sorted(set_aside_lines(df, findings).items()):
        rec = rows.get(line)
        out.append({"file": f.file if f.file is not None else file, "line": line,
                    "test": f.test if rec is None else str(rec.test),
                    "run": None if rec is None else int(rec.run),
                    "step": None if rec is None else int(rec.step),
                    "column": f.column, "reason": f.message})
    return out


def summary(findings: list[Finding]) -> str:
    """One sentence for the certificate: how many rows set aside, points missing."""
    n_set = len({f.line for f in findings if f.action == "set_aside" and f.code != OFF_PROGRAMME})
    n_off = sum(f.code == OFF_PROGRAMME for f in findings)
    miss = [f for f in findings if f.code == "programme-point-missing"]
    parts = []
    if n_set:
        parts.append(f"{n_set} reading(s) set aside by the screening")
    if n_off:
        parts.append(f"{n_off} step(s) at a rate not in the programme set aside")
    if miss:
        parts.append(f"{len(miss)} planned point(s) missing")
    return "; ".join(parts) + ("" if not parts else " (see findings)")



def screened(readings, findings: list[Finding]):
    """(readings without the rows set aside, findings); a refused finding stops here with
    the one-line error naming the reading."""
    for f in findings:
        if f.action == "refused":
            raise GonioError(f"refused by the screening: {f.message}", file=f.file,
                             line=f.line, column=f.column)
    if not any(f.action == "set_aside" for f in findings):
        return readings, findings
    return RateReadings(apply(readings.data, findings), readings.metadata,
                        readings.path), findings


def screening_extra(findings: list[Finding]) -> dict:
    """The ``extra`` section of the screening: a one-sentence ``screening`` summary (empty
    when nothing was found); the findings themselves are the result's ``findings``."""
    return {"screening": summary(findings)}
