"""Screening of triad readings: the triad specification's rules.

:func:`screen` returns one :class:`gonio.result.Finding` per reading a rule fired on. A
rule on the alignment dwells refuses (a triad fit has no way to carry a dwell it does not
trust: one wrong dwell moves M and b for every gyro), and :func:`check` raises the first
refused finding as a GonioError naming the line; a thermal soak row or a static sample that
departs is set aside instead (the calibration drops its line and states the finding). The rules (docs/alignment.md, "Screening"):

- **duplicated row** — two rows of the same test with the same ``step`` (the dwell's index)
  or with identical data: a copied dwell would count twice in the fit.
- **rate sign** — a rotating alignment dwell about axis a (``up`` = ±a) must show the sign
  of rate × sign(up) × sign(nominal scale) on gyro a's output, when that output is far
  from the bias (|out − median static out| > :data:`SIGN_MIN_RATIO` × the dwell's
  sample deviation): a sign-flipped dwell otherwise enters the fit as a wrong column of M.
- **step gap** (flagged) — a jump in the rows' ``step`` numbers: a dwell or samples
  missing from the file, named.
- **no static record** (flagged) — alignment dwells without a ``static`` record: the
  biases b_i are then the in-run bias over this record, without the bias-instability term
  (their U holds the fit alone, about 6× smaller on the bench), and the averaging time is not
  measured; said on the certificate, not left to a detail.
- **one-sample dwell** (flagged) — static soak dwells of ``n_samples`` = 1: no standard
  deviation, so no ARW from them (the ARW values rest on the other dwells, or are not
  measured).
- **one temperature** — a thermal programme whose soak rows span less than
  :data:`MIN_TEMPERATURE_SPAN_C` (chamber) cannot identify a temperature model; it was
  certified as a model before.
- **set point departs** (set aside) — a thermal soak row whose supply, table rate or
  chamber temperature departs from the programme the majority of the soaks hold
  (:func:`_thermal_settings`); the calibration fits without it.
- **static spike** (set aside) — a sample of the static record beyond the Hampel limit
  (:func:`_static_outliers`); the record refused when more than 5 % are, or when many
  moderate spikes lie between 5 robust σ and the limit.
- **dwell sd departs** (set aside) — an alignment or thermal row whose ``sd_*`` stands far
  above the others of its test (:func:`_sd_outliers`): a record disturbed inside.
- **ramp block departs** (set aside) — a thermal ramp block off the line of its
  neighbouring blocks in an output, a temperature or the supply (:func:`_ramp_outliers`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from gonio.errors import GonioError
from gonio.specs.triad_alignment.readings import OUT
from gonio.result.findings import Finding

#: A rotating dwell's output must stand this many sample deviations from the static median
#: before its sign is judged (at 50 °/s the bench's gyro shows ~1000 sd).
SIGN_MIN_RATIO: float = 20.0
#: Smallest chamber-temperature span of the soak rows a thermal model needs, °C.
MIN_TEMPERATURE_SPAN_C: float = 1.0

_AXES = "xyz"


def _duplicates(df: pd.DataFrame, file) -> list[Finding]:
    out, seen = [], set()
    data_cols = [c for c in df.columns if c not in ("line", "step")]
    for key, what in ((["test", "step"], "the same test and step"),
                      (data_cols, "identical data")):
        cand = df[df.duplicated(subset=key, keep=False)]
        for _, g in cand.groupby(key, sort=False, dropna=False):
            if len(g) < 2:
                continue
            first = int(g["line"].iloc[0])
            for line, test in zip(g["line"].iloc[1:], g["test"].iloc[1:]):
                if int(line) in seen:
                    continue
                seen.add(int(line))
                out.append(Finding("duplicated-row", f"{test} row repeats line {first} "
                                   f"({what}): a copied dwell would count twice", "refused",
                                   file=file, line=int(line), column="step", test=str(test),
                                   clause="triad screening", rule=f"no two rows with {what}"))
    return sorted(out, key=lambda f: f.line)


def _scale_signs(metadata: dict) -> np.ndarray:
    raw = str(metadata.get("nominal_scale_per_dps", "")).split()
    try:
        v = np.array([float(x) for x in raw])
    except ValueError:
        v = np.array([])
    return np.sign(v) if v.size == 3 and np.all(v != 0) else np.ones(3)


def _rate_signs(df: pd.DataFrame, metadata: dict, file) -> list[Finding]:
    rows = df[df["test"] == "alignment"]
    static = rows[rows["rate_dps"] == 0]
    rot = rows[rows["rate_dps"] != 0]
    if not len(rot):
        return []
    base = np.array([float(np.median(static[c])) if len(static) else 0.0 for c in OUT])
    sgn = _scale_signs(metadata)
    out = []
    for _, row in rot.iterrows():
        up = str(row["up"]).strip()
        if len(up) != 2 or up[1] not in _AXES or up[0] not in "+-":
            continue
        a = _AXES.index(up[1])
        dev = float(row[OUT[a]]) - base[a]
        sd = float(row.get(f"sd_{up[1]}", np.nan))
        if not np.isfinite(sd) or sd <= 0 or abs(dev) < SIGN_MIN_RATIO * sd:
            continue
        want = np.sign(row["rate_dps"]) * (1 if up[0] == "+" else -1) * sgn[a]
        if np.sign(dev) != want:
            out.append(Finding(
                "rate-sign", f"alignment dwell about {up} at {float(row['rate_dps']):g} °/s: "
                f"gyro {up[1]}'s output moved {dev:+.4g} from the static median, the opposite "
                "sign of the rate (a sign-flipped rate_dps or up?)", "flagged", file=file,
                line=int(row["line"]), column="rate_dps", test="alignment",
                clause="triad screening",
                rule=f"sign(out − static median) = sign(rate·up·K) when |out − median| > "
                     f"{SIGN_MIN_RATIO:g} sd"))
    return out


def _one_temperature(df: pd.DataFrame, file) -> list[Finding]:
    th = df[df["test"] == "thermal"]
    if not len(th):
        return []
    soak = th[th["phase"].astype(str) != "ramp"] if "phase" in th else th
    soak = soak if len(soak) else th
    t = soak["chamber_c"].to_numpy(float)
    t = t[np.isfinite(t)]
    if not t.size:
        t = soak["sensor_c"].to_numpy(float)
        t = t[np.isfinite(t)]
    if t.size and float(t.max() - t.min()) < MIN_TEMPERATURE_SPAN_C:
        return [Finding("one-temperature",
                        f"the thermal programme's soak rows span {t.max() - t.min():.3g} °C "
                        f"(around {np.median(t):.4g} °C): a temperature model needs at least "
                        f"{MIN_TEMPERATURE_SPAN_C:g} °C between set points", "refused", file=file,
                        line=int(soak["line"].iloc[0]), column="chamber_c", test="thermal",
                        clause="thesis eq. 6.14",
                        rule=f"max − min chamber_c of the soak rows ≥ {MIN_TEMPERATURE_SPAN_C:g} °C")]
    return []


def _step_gaps(df: pd.DataFrame, file) -> list[Finding]:
    """``programme-point-missing`` (flagged): the rows' ``step`` numbers the programme's rows
    in file order; a jump of more than one is a dwell (or samples) missing from the file —
    a row lost or deleted — named once per gap (one alignment dwell
    removed changed every U with no word)."""
    if "step" not in df or len(df) < 2:
        return []
    step = pd.to_numeric(df["step"], errors="coerce").to_numpy(float)
    jump = np.diff(step)
    out = []
    for k in np.flatnonzero(jump > 1) + 1:
        row = df.iloc[k]
        a, b = int(step[k - 1]) + 1, int(step[k]) - 1
        steps = f"step {a}" if a == b else f"steps {a}–{b}"
        out.append(Finding("programme-point-missing",
                           f"{steps} missing before {row['test']} step {int(step[k])}: the "
                           "results rest on the rows present", "flagged", file=file,
                           line=int(row["line"]), column="step", test=str(row["test"]),
                           rule="steps numbered without gaps in file order"))
    return out


def _no_static_record(df: pd.DataFrame, file) -> list[Finding]:
    """``static-record-missing`` (flagged): alignment rows and no ``static`` row (without the
    static record the bias U falls silently by a factor of about six, the change only in a
    detail, so the absence is stated)."""
    tests = set(df["test"].astype(str))
    if "alignment" not in tests or "static" in tests:
        return []
    first = df[df["test"].astype(str) == "alignment"]
    return [Finding("static-record-missing", "no static record: the biases b_i are the "
                    "in-run bias over this record, without the bias-instability term, and "
                    "the averaging time is not measured", "flagged", file=file,
                    line=int(first["line"].iloc[0]), column="test", test="static",
                    rule="a static record beside the alignment dwells")]


def _one_sample_dwells(df: pd.DataFrame, file) -> list[Finding]:
    """``one-sample-dwell`` (flagged): static soak dwells (thermal, soak, rate 0) of one
    sample: one sample gives no standard deviation, so no angle random walk from them (the
    ARW values rest on the other dwells, or are not measured); named once, by their lines."""
    if not {"phase", "rate_dps", "n_samples"} <= set(df.columns):
        return []
    rate = pd.to_numeric(df["rate_dps"], errors="coerce")
    n = pd.to_numeric(df["n_samples"], errors="coerce")
    hit = df[(df["test"].astype(str) == "thermal") & (df["phase"].astype(str) == "soak")
             & (rate == 0) & (n < 2)]
    if not len(hit):
        return []
    lines = [int(x) for x in hit["line"]]
    return [Finding("one-sample-dwell",
                    f"{len(lines)} static soak dwells of one sample (lines "
                    f"{', '.join(map(str, lines))}): one sample gives no standard deviation, "
                    "so no angle random walk from them", "flagged", file=file, line=lines[0],
                    column="n_samples", test="thermal", clause="thesis eq. 6.20",
                    rule="a static soak dwell's standard deviation needs n_samples ≥ 2")]


#: Tolerances of the thermal programme's set points (``setting-departs``, as the rate
#: specifications' screening): supply 0.01 V + 0.2 %, table rate 10⁻⁶ relative + 10⁻⁹ °/s,
#: chamber temperature 1 °C from its soak's median.
SUPPLY_TOL_V, SUPPLY_TOL_REL, RATE_TOL_REL, RATE_TOL_DPS, CHAMBER_TOL_C = \
    0.01, 2e-3, 1e-6, 1e-9, 1.0


def _soaks(df: pd.DataFrame) -> tuple[pd.DataFrame, np.ndarray]:
    """The thermal soak rows and, per row, its soak (a run of consecutive soak rows: a ramp
    or another up axis ends it, as :func:`thermal_model.soak_points` pairs them)."""
    th = df[df["test"].astype(str) == "thermal"]
    block = ((th["phase"] != th["phase"].shift()) | (th["up"] != th["up"].shift())).cumsum()
    soak = (th["phase"].astype(str) == "soak").to_numpy()
    return th[soak], block.to_numpy()[soak]


def _thermal_settings(df: pd.DataFrame, file) -> list[Finding]:
    """``setting-departs`` (set aside): a soak row whose set point departs from the
    programme. The programme is what the majority of the soaks hold: every soak runs the
    same supply voltages and table rates, so a ``supply_v`` or ``rate_dps`` that fewer than
    half of the soaks hold (within the tolerance) is a typo (supply 50 for 5 V: fitted, it
    would move the soak point's K and b); a ``chamber_c`` more than 1 °C from its soak's median
    too. Needs three soaks or more (a majority)."""
    th, blk = _soaks(df)
    n_soaks = len(set(blk.tolist()))
    if n_soaks < 3:
        return []
    out: dict[int, Finding] = {}
    for col, rel, ab, unit in (("supply_v", SUPPLY_TOL_REL, SUPPLY_TOL_V, "V"),
                               ("rate_dps", RATE_TOL_REL, RATE_TOL_DPS, "°/s")):
        v = th[col].to_numpy(float)
        tol = ab + rel * np.abs(v)
        near = np.abs(v[:, None] - v[None, :]) <= tol[:, None]
        held = np.array([len(set(blk[near[i]].tolist())) for i in range(v.size)])
        for i in np.flatnonzero(2 * held <= n_soaks):
            row = th.iloc[i]
            out.setdefault(int(row["line"]), Finding(
                "setting-departs", f"thermal soak step {int(row['step'])}: {col} {v[i]:.10g} "
                f"{unit} is held by {held[i]} of the programme's {n_soaks} soaks — set aside "
                "(the soak point it belongs to goes with it); the thermal model rests on the "
                "other points", "set_aside", file=file,
                line=int(row["line"]), column=col, test="thermal", clause="triad screening",
                rule=f"a set point held by more than half of the soaks (±{ab:g} {unit} + "
                     f"{rel:g}·|x|)"))
    c = th["chamber_c"].to_numpy(float)
    med = pd.Series(c).groupby(blk).transform("median").to_numpy()
    for i in np.flatnonzero(np.abs(c - med) > CHAMBER_TOL_C):
        row = th.iloc[i]
        out.setdefault(int(row["line"]), Finding(
            "setting-departs", f"thermal soak step {int(row['step'])}: chamber_c {c[i]:.10g} °C "
            f"departs from its soak's {med[i]:.10g} °C — set aside (the soak point it belongs "
            "to goes with it); the thermal model rests on the other points", "set_aside", file=file, line=int(row["line"]),
            column="chamber_c", test="thermal", clause="triad screening",
            rule=f"|chamber_c − soak median| ≤ {CHAMBER_TOL_C:g} °C"))
    found = [out[k] for k in sorted(out)]
    if len(found) > max(DEPART_MAX_ROWS, DEPART_SHARE * len(th)):
        f = found[0]
        return [Finding(**{**f.to_json(), "action": "refused", "message":
                           f"{len(found)} of the {len(th)} thermal soak rows depart from the "
                           f"set points the soaks share (the first here: {f.message}): not "
                           "typos to set aside — the programme or its columns are not as "
                           "the soaks state"})]
    return found


#: More thermal soak rows departing from the programme than this (and than this share of
#: the soak rows) refuse the file: a column logged differently, not typos to set aside.
DEPART_MAX_ROWS, DEPART_SHARE = 2, 0.1


def _static_outliers(df: pd.DataFrame, file) -> list[Finding]:
    """``output-outlier`` (set aside): a sample of the static record against its running
    median, the Hampel rule every record is screened with
    (:func:`gonio.analysis.outliers.hampel_residuals`: one spike of 1000 among values near 11
    dominates the Allan deviation the averaging time is read from). The Allan deviation then
    joins the samples either side of it. The record is refused (``record-damaged``), as a
    rate specification's record is, when more than 5 % (and ≥ 3) of its samples are beyond
    the limit (:func:`~gonio.analysis.outliers.too_many_outliers`) or when many lie between
    5 robust σ and the limit (:func:`~gonio.analysis.outliers.moderate_tail`): dense
    moderate spikes, each below the limit, raise the Allan deviation's floor and the bias
    instability with it, and what is left of such a record is not a sample of the gyro."""
    from gonio.analysis.outliers import (DENSE_SHARE, HAMPEL_MIN_ROWS, K_TAIL, TAIL_P,
                                         hampel_residuals, moderate_tail, too_many_outliers)

    st = df[df["test"].astype(str) == "static"]
    if len(st) < HAMPEL_MIN_ROWS:
        return []
    out: dict[int, Finding] = {}
    rule = "|y_i − running median (21)| > 8·1.4826·local median |y − running median|"
    for c in OUT:
        y = st[c].to_numpy(float)
        d, lim = hampel_residuals(y)
        bad = np.flatnonzero(np.abs(d) > lim)
        tail = None if too_many_outliers(bad.size, y.size) else moderate_tail(d, lim)
        if too_many_outliers(bad.size, y.size) or tail is not None:
            i = int(bad[0] if tail is None else np.flatnonzero(tail)[0])
            what = (f"{bad.size} of its {y.size} samples are outliers (more than "
                    f"{DENSE_SHARE:.0%})" if tail is None else
                    f"{int(tail.sum())} of its {y.size} samples lie beyond {K_TAIL:g} robust σ "
                    f"of the running median (a normal record of this length has "
                    f"{y.size * TAIL_P:.2g})")
            ln = int(st["line"].iloc[i])
            return [Finding("record-damaged", f"static record: {c}: {what}, the first here "
                            f"({y[i]:.10g}): the record is damaged, not a sample of the gyro",
                            "refused", file=file, line=ln, column=c, test="static",
                            clause="triad screening",
                            rule=rule if tail is None else
                            f"count of |y − running median| > {K_TAIL:g}·1.4826·local MAD "
                            "≥ max(5, 0.001·n)")]
        for i in bad:
            ln = int(st["line"].iloc[i])
            out.setdefault(ln, Finding(
                "output-outlier", f"static record: {c} {y[i]:.10g} departs from its running "
                f"median by {d[i]:+.4g} (limit {lim[i]:.3g}) — set aside; the Allan deviation "
                "joins the samples either side", "set_aside", file=file, line=ln, column=c,
                test="static", clause="triad screening", rule=rule))
    return [out[k] for k in sorted(out)]


#: Robust threshold of the sd rule, in units of 1.4826·MAD (the rate specifications'
#: K_ROBUST for a setting that departs from its segment), and its floor as a ratio to the
#: median sd (a sample sd of tens of samples or more is never twice its kind's by chance).
SD_K_ROBUST, SD_MIN_RATIO = 10.0, 2.0


def _sd_kinds(g: pd.DataFrame, axis: str) -> np.ndarray:
    """Per row, its kind for gyro ``axis``'s sd: 0 at rest, 1 rotating about that gyro's own
    axis, 2 rotating about another (the table's rotation modulates the other gyros' outputs
    by the Earth rate and the cross-coupling over each revolution, not its own)."""
    rot = g["rate_dps"].to_numpy(float) != 0
    own = g["up"].astype(str).str[-1].to_numpy() == axis
    return np.where(~rot, 0, np.where(own, 1, 2))


def _sd_outliers(df: pd.DataFrame, file) -> list[Finding]:
    """``sd-departs`` (set aside): a row whose ``sd_*`` stands far above the others of its
    kind — the rows of two samples or more of its test (alignment; thermal) at rest, or
    rotating about that gyro's axis, or about another (:func:`_sd_kinds`) — above their
    median sd by more than 10·1.4826·MAD, and above twice that median (and 10⁻⁹ of the
    output's size). A record's sd is its noise; one far above its kind's is a record
    disturbed inside (a spike or a step among its samples, which moves its mean too): the
    row is set aside as the rate specifications set aside an output that departs from its
    segment, and the results rest on the other rows (those of the file with the row
    deleted). Kinds of fewer than 4 rows are not judged. Only the upper side: a low sd (0
    from a filled column) moves no mean and weighs nothing (the fit weighs dwells by
    n_samples). More than 2 (and 10 %) of a test's rows: refused, the column is not what
    the rows state."""
    out: list[Finding] = []
    for test in ("alignment", "thermal"):
        g = df[(df["test"].astype(str) == test) & (df["n_samples"] >= 2)]
        found: dict[int, Finding] = {}
        for a in _AXES:
            c = f"sd_{a}"
            v = g[c].to_numpy(float)
            kind = _sd_kinds(g, a)
            size = 1e-9 * (1.0 + float(np.nanmax(np.abs(g[f"out_{a}"].to_numpy(float)),
                                                 initial=0.0)))
            for k in range(3):
                ok = np.isfinite(v) & (kind == k)
                if ok.sum() < 4:
                    continue
                med = float(np.median(v[ok]))
                lim = max(med + SD_K_ROBUST * 1.4826 * float(np.median(np.abs(v[ok] - med))),
                          SD_MIN_RATIO * med, size)
                for i in np.flatnonzero(ok & (v > lim)):
                    row = g.iloc[i]
                    found.setdefault(int(row["line"]), Finding(
                        "sd-departs", f"{test} step {int(row['step'])}: {c} {v[i]:.10g} stands "
                        f"far above the median {med:.4g} of its kind (limit {lim:.4g}): a "
                        "record disturbed inside — set aside; the results rest on the other "
                        "rows", "set_aside", file=file, line=int(row["line"]), column=c,
                        test=test, clause="triad screening",
                        rule=f"sd ≤ max(median + {SD_K_ROBUST:g}·1.4826·MAD, "
                             f"{SD_MIN_RATIO:g}·median) of the rows of its kind"))
        rows = [found[k] for k in sorted(found)]
        if len(rows) > max(DEPART_MAX_ROWS, DEPART_SHARE * len(g)):
            f = rows[0]
            rows = [Finding(**{**f.to_json(), "action": "refused", "message":
                               f"{len(rows)} of the {len(g)} {test} rows have an sd far above "
                               f"the others (the first here: {f.message}): not disturbed "
                               "records to set aside — the sd columns are not as stated"})]
        out += rows
    return out


#: The ramp rule: half-width (rows) of the local line each ramp block is judged against,
#: its threshold in robust σ of the run (the rate specifications' K_SPIKE for a record
#: that follows a smooth trend), and the shortest ramp run it judges.
RAMP_HALF_WINDOW, RAMP_K, RAMP_MIN_ROWS = 3, 15.0, 5
#: Floors of the ramp rule per column: a temperature 1 °C (the soak rows' chamber
#: tolerance), a supply 0.01 V + 0.2 % (theirs); an output none (its scale is its noise).
RAMP_FLOOR = {"chamber_c": (CHAMBER_TOL_C, 0.0), "sensor_c": (CHAMBER_TOL_C, 0.0),
              "supply_v": (SUPPLY_TOL_V, SUPPLY_TOL_REL)}


def ramp_departures(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """d_i = y_i − the local line of its neighbours (the rows within
    :data:`RAMP_HALF_WINDOW` of i, i left out): slope the median of their pairwise slopes,
    level the median of their values carried to t_i along it (Theil–Sen: a spike among the
    neighbours moves neither). A ramp block follows the chamber smoothly, so a block off
    that line by many times the run's own scatter is a typo, not the gyro.

    >>> t = np.arange(10.0)
    >>> y = 2.0 * t; y[4] = 80.0
    >>> [int(i) for i in np.flatnonzero(np.abs(ramp_departures(t, y)) > 1)]
    [4]
    """
    d = np.empty(y.size)
    for i in range(y.size):
        j = [k for k in range(max(0, i - RAMP_HALF_WINDOW), min(y.size, i + RAMP_HALF_WINDOW + 1))
             if k != i]
        tj, yj = t[j], y[j]
        dt = tj[:, None] - tj[None, :]
        pair = np.triu(np.ones(dt.shape, bool), 1) & (dt != 0)
        slope = float(np.median((yj[:, None] - yj[None, :])[pair] / dt[pair])) if pair.any() else 0.0
        d[i] = y[i] - float(np.median(yj + slope * (t[i] - tj)))
    return d


def _ramp_worst(t: np.ndarray, y: np.ndarray, floor: tuple[float, float]
                ) -> list[tuple[int, float, float]]:
    """(index, d, limit) of each block of one ramp run beyond the ramp rule's limit, worst
    first: the worst block is taken out and the rest judged again, so that a typo does not
    tilt the line its neighbours are judged against."""
    keep = np.arange(y.size)
    out = []
    while keep.size >= RAMP_MIN_ROWS and len(out) < y.size // 2:
        d = ramp_departures(t[keep], y[keep])
        lim = np.maximum(RAMP_K * 1.4826 * float(np.median(np.abs(d))),
                         floor[0] + floor[1] * np.abs(y[keep]))
        k = int(np.argmax(np.abs(d) / np.where(lim > 0, lim, np.inf)))
        if not abs(d[k]) > lim[k]:
            break
        out.append((int(keep[k]), float(d[k]), float(lim[k])))
        keep = np.delete(keep, k)
    return out


def _ramp_outliers(df: pd.DataFrame, file) -> list[Finding]:
    """``ramp-departs`` (set aside): a ramp row (thermal, ``phase`` ramp) whose output,
    chamber or sensor temperature or supply stands off the local line of its run's
    neighbouring blocks (:func:`ramp_departures`) by more than 15·1.4826·the run's median
    |d| (at least :data:`RAMP_FLOOR`). The ramp blocks feed the ramp analysis the
    certificate states (the soak model's error on the ramps, the lag τ, the hysteresis,
    the compensation before and after): screened as the soak rows are, set aside and named,
    the analysis then that of the file with the row deleted. Runs of fewer than
    :data:`RAMP_MIN_ROWS` rows are not judged. More than 2 (and 10 %) of the ramp rows:
    refused."""
    th = df[df["test"].astype(str) == "thermal"]
    if not len(th):
        return []
    run = ((th["phase"] != th["phase"].shift()) | (th["up"] != th["up"].shift())).cumsum()
    ramp = (th["phase"].astype(str) == "ramp").to_numpy()
    found: dict[int, Finding] = {}
    for _, g in th[ramp].groupby(run[ramp], sort=False):
        if len(g) < RAMP_MIN_ROWS:
            continue
        t = g["time_s"].to_numpy(float)
        for c in OUT + ("chamber_c", "sensor_c", "supply_v"):
            y = g[c].to_numpy(float)
            if not np.all(np.isfinite(y)):
                continue
            for i, dev, lim in _ramp_worst(t, y, RAMP_FLOOR.get(c, (0.0, 0.0))):
                row = g.iloc[i]
                found.setdefault(int(row["line"]), Finding(
                    "ramp-departs", f"thermal ramp step {int(row['step'])}: {c} {y[i]:.10g} "
                    f"departs from the line of its neighbouring ramp blocks by {dev:+.4g} "
                    f"(limit {lim:.3g}) — set aside; the ramp analysis rests on the other "
                    "blocks", "set_aside", file=file, line=int(row["line"]), column=c,
                    test="thermal", clause="triad screening",
                    rule=f"|y − local line of ±{RAMP_HALF_WINDOW} blocks| ≤ max({RAMP_K:g}·1.4826·"
                         "median |d| of the run, floor)"))
    rows = [found[k] for k in sorted(found)]
    if len(rows) > max(DEPART_MAX_ROWS, DEPART_SHARE * int(ramp.sum())):
        f = rows[0]
        return [Finding(**{**f.to_json(), "action": "refused", "message":
                           f"{len(rows)} of the {int(ramp.sum())} thermal ramp rows depart "
                           f"from the line of their neighbours (the first here: {f.message}): "
                           "not typos to set aside — the ramp rows are not as stated"})]
    return rows


def screen(readings, protocol=None) -> list[Finding]:
    """Every finding on a triad readings file (:class:`gonio.specs.triad_alignment.readings.TriadReadings`)."""
    df = readings.data
    file = None if readings.path is None else str(readings.path)
    return (_duplicates(df, file) + _rate_signs(df, readings.metadata, file)
            + _one_temperature(df, file) + _step_gaps(df, file)
            + _no_static_record(df, file) + _one_sample_dwells(df, file)
            + _thermal_settings(df, file) + _static_outliers(df, file)
            + _sd_outliers(df, file) + _ramp_outliers(df, file))


def check(readings, protocol=None) -> list[Finding]:
    """:func:`screen`, raising the first refused finding as a GonioError naming its line."""
    found = screen(readings, protocol)
    for f in found:
        if f.action == "refused":
            raise GonioError(f.message, file=readings.path, line=f.line, column=f.column)
    return found
