"""Screening of optical-draft readings: every reading against the protocol and the other readings.

:func:`screen` returns one :class:`gonio.result.Finding` per reading a rule fired on, and one
per incomplete programme; :func:`apply_findings` refuses (GonioError naming the line) or sets
aside what the findings say. The rules, their thresholds and why (docs/draft-readings.md,
"Screening"):

- **round** — the reading's round must be one of its protocol item's rounds (7.1, 7.4, 7.6, 7.7),
  its series one of the item's series (a series 11 of a 10-series item is a label typo).
- **condition** — its rate and orientation must be a condition of the programme of its test
  (a 7.6 reading at 1 000 °/s is a typo, not an eighth rate).
- **angle** — ``table_deg`` must equal the round's stop − start within the item's
  ``position_tolerance_deg``.
- **time** — ``time_s`` (from zeroing to reading) within the item's ``max_time_to_reading_s``;
  for 7.4 and 7.7 a protocol that omits the key gets Annex A.1's 0.5 min
  (:data:`A1_MAX_TIME_S`); only an explicit key widens it.
- **indicated angle** — each reading's indicated angle (``gyro_deg``, else
  ``gyro_counts`` / K_ref with K_ref the median of counts / table angle over every rotation
  reading of the file, so the other rounds predict it) less the table angle, r, against the
  other readings of its condition (test, rate, orientation), with a threshold that follows
  the spread those readings show and a floor of ``ROUND_FLOOR_STEPS`` = ``SPREAD_FLOOR_STEPS``
  steps of the instrument's resolution (one count; the ``gyro_deg`` column's step):

  * rounds read in at least ``PER_ROUND_MIN`` series (7.4): against its round
    (:func:`round_threshold_arcsec`);
  * positions read once (7.1; 7.6, 7.7 once per rate or orientation), at least ``LINE_MIN``
    readings: d = r less the 7.4 reference round's median at the same angle (the position's
    own error), against the least-squares fit in the angle (a line; with cos θ, sin θ where
    12 positions allow) of the condition's other readings, leave one out, set aside when
    ``|d − fit| > max(c · s · √(1 + h), DRIFT_Z · drift, floor)``, s the others' residual
    standard deviation (never below the reference's pooled s), c the Bonferroni critical
    value of Student's t for the group's readings and s's degrees of freedom, so that a
    clean session sets aside a reading with probability ≤ ``SCREEN_ALPHA``
    (:func:`line_critical_value`), drift the draft's zero-stability bound times the
    reading's time from zeroing (:func:`line_departures`; for 7.6 and 7.7, where no single
    reading departs, two at a time, :func:`pair_departures`); where the condition is the
    7.4 reference's own rate and axis (7.1: the same stops at 60 °/s, axis up, which
    7.4/7.5 read ten times) s is pooled with the scatter of those ten repetitions
    (:func:`repeated_reference_scale`, ν ≈ 108): a position's repeated error
    (nonlinearity, table) cancels in d, a one-reading typo does not, and c falls from
    ≈ 19 to ≈ 3.8; such a 7.1 reading is set aside and K rests on the other rounds
    (``ROUND_MAY_GO``); where 7.4 is read in fewer than ``PER_ROUND_MIN`` series (no such
    prior) 7.1's readings, which then hide one another from the line rule when two or more
    depart, are judged together against 7.4's rounds at the same stops read in at least
    ``AGREEMENT_SERIES_MIN`` series (an F test; refused naming them), or named in a flagged
    ``readings-not-judged`` finding where no such rounds exist (:func:`reference_agreement`);
  * fewer readings: ``|r − median| > max(ROBUST_Z · 1.4826 · MAD, ANGLE_FLOOR_ARCSEC)``;
    a 7.1, 7.6 or 7.7 condition so judged gets a flagged ``readings-not-judged`` finding
    stating the largest typo in one reading the rule would not have seen and its effect on
    K and K_l (7.1) or on C_v / C_g (7.6, 7.7: :class:`ConsistencyEffect`, from the item's
    formula on the readings as read) (:func:`median_rule_limit`); one of fewer than 3
    readings, which no rule judges, one saying so with a typo's effect per ″
    (:func:`no_rule_statement`).
- **7.3 indicated angle** — a 7.3 reading (at rest) against its neighbours in time, not
  against the median of its series: the accumulated angle of a clean rest drifts (bias,
  warm-up, bias instability), so over the 70 min of 7.3 its readings spread beyond the
  floor around their median while each stays on the path its neighbours draw. The
  residual e_i is the reading less the line through its two neighbours (the two nearest,
  extrapolated, for the first and last, judged on the inner residuals' scale); set aside
  when ``|e − median(e)| > max(REST_Z · 1.4826 · MAD(e), SPREAD_FLOOR_STEPS steps)``, e
  and the threshold those of the other readings: the candidate is the reading without
  which the others' residuals are smallest (a typo moves its neighbours' residuals and
  their MAD too), e its departure from the line its neighbours among the others draw; the
  rule then runs again on the others. A series of fewer than four readings, or with
  repeated times, uses the median rule.

The z values were measured on clean sessions of the built-in programme, the false alarms
and the typos caught are in docs/draft-readings.md ("Screening").
- **tilt estimate** — each rest of the in-situ tilt estimate (``tilt_estimate`` rows, which
  support Annex A.1's tilt bound) against the fit in θ of the other positions, by the
  condition rule above with the A.4.3 drift over the dwell and the resolution as floors
  (:func:`tilt_estimate_rule`); a reading that breaks it is set aside (a finding) and ψ is
  estimated from the others.
- **7.3 schedule** — each series of 7.3 holds the protocol's ``readings`` rounds, round n
  at t_1 + (n − 1) · ``interval_s`` (t_1 the series' median of time_s − (n − 1) · interval_s) (within ``ZS_SCHEDULE_TOLERANCE``
  of the interval): a missing round and an off-schedule reading are flagged, saying what
  B_s rests on (the readings read, T from the first to the last).
- **incomplete programme** — a round of 7.1, 7.4, 7.6 or 7.7 missing from every series of a
  condition present in the file, a programme condition (rate, orientation) absent, or a
  round read in some series and not in another series present, is flagged (the item is
  computed on what is there, and says so).
- **both angles** — a row giving ``gyro_deg`` and ``gyro_counts`` must agree through K_ref
  (:func:`counts_agree_rule`): refused, every row judged, so the screening and the
  calibration refuse the same row.
- **nominal K** — the metadata's nominal K within ``NOMINAL_K_FACTOR`` of K_ref
  (:func:`nominal_k_rule`): refused without 7.1 readings, flagged with them.

A reading that breaks a rule is set aside (``on_bad_reading = "exclude"``, the default) or
refused (``"error"``); setting aside the last reading of a round refuses instead, because the
item would silently lose a point.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.stats import f as fisher_f
from scipy.stats import t as student_t

from gonio.errors import GonioError
from gonio.specs.ogam_draft.readings import Readings, metadata_float
from gonio.result.findings import Finding
from gonio.units import S_PER_MIN, deg_to_arcsec, dph_to_arcsec_s

#: Annex A.1: "the time from the start to each calibration position is within 0.5 min".
A1_MAX_TIME_S: float = 0.5 * S_PER_MIN
#: The tests Annex A.1 bounds (E is determined: 7.4, and each direction of 7.7).
A1_TESTS: tuple[str, ...] = ("angle_deviation", "pointing_consistency")
#: Robust z threshold of the indicated-angle rule (1.4826·MAD estimates σ for normal data:
#: 5 σ is a false alarm in ~6e-7 of healthy readings).
ROBUST_Z: float = 5.0
#: Floor of the median rule, ″, which judges only groups too small to show their own spread
#: (a condition of fewer than ``LINE_MIN`` readings read once per position, a 7.3 series of
#: fewer than ``ZS_NEIGHBOUR_MIN``): there a MAD of a few readings cannot stand alone, so the
#: floor stays above the spread of a healthy session (≤ 3″ at 1 °/s) and far below a
#: one-degree typo (3 600″). Every larger group has a rule that follows its own spread,
#: down to the instrument's resolution (:func:`round_threshold_arcsec`,
#: :func:`line_departures`, :func:`_rest_spread`).
ANGLE_FLOOR_ARCSEC: float = 5.0

#: Rounds read in at least this many series are screened round by round
#: (:func:`round_threshold_arcsec`); fewer, across the rounds of the condition.
PER_ROUND_MIN: int = 5
#: Robust z of the round-by-round rule. Its scale is never below the condition's pooled
#: one (:func:`round_threshold_arcsec`), so with Gaussian readings of 12 rounds × 10 series
#: a session false-alarms in ~0.5 % at 6 (2.4 % at 5; a MAD of one round's 10 readings
#: alone: 28 % at 6, 38 % at 5; numpy, 20 000 sessions, seed 1, quantised at one RLG count).
ROUND_Z: float = 6.0
#: Floor of the round-by-round rule, in steps of the column's resolution (one count of
#: ``gyro_counts``; for ``gyro_deg`` the smallest non-zero step between two readings of a
#: round). A round spread over a few steps has a lumpy MAD (five equal readings of ten
#: give MAD ≤ one step whatever the spread): on the RLG bench (0.047″ a count) a clean
#: ``typeb`` session had a reading 9 counts from its round's median, 6 · s_pooled being
#: 8.9 counts; 10 steps (0.47″ there) keeps such readings and still sets aside two
#: transposed digits (18 counts).
ROUND_FLOOR_STEPS: float = 10.0

CLAUSES = {"scale_factor": "7.1", "zero_stability": "7.3", "angle_deviation": "7.4",
           "rate_consistency": "7.6", "pointing_consistency": "7.7"}
ROTATION_TESTS = ("scale_factor", "angle_deviation", "rate_consistency", "pointing_consistency")
#: The tests whose item compares conditions over the same positions (7.6, 7.7): a round
#: missing from a condition leaves the item not measured (items.consistency_incomplete).
COMPARED = ("rate_consistency", "pointing_consistency")

_ANGLE_RULE = (f"|r − median(r of the condition)| > max({ROBUST_Z:g} · 1.4826 · MAD, "
               f"{ANGLE_FLOOR_ARCSEC:g}″), r = indicated − table angle, indicated = gyro_deg or "
               "gyro_counts / K_ref, K_ref = median(gyro_counts / table_deg) of all rotation "
               "readings")


def items_of(protocol, test: str) -> list:
    """The protocol's rotation items of ``test`` (7.6 and 7.7 may reuse 7.4's reference)."""
    if test == "scale_factor":
        its = [protocol.scale_factor]
    elif test == "angle_deviation":
        its = [protocol.angle_deviation]
    elif test == "rate_consistency":
        its = list(protocol.rate_consistency) + [protocol.angle_deviation]
    else:
        its = list(protocol.pointing_consistency) + [protocol.angle_deviation]
    return [it for it in its if it is not None]


def item_for(protocol, test: str, rate: float, orientation: str):
    """The protocol item of a reading's test, rate and orientation, or None."""
    for it in items_of(protocol, test):
        if math.isclose(it.rate_dps, rate, rel_tol=1e-9) and it.orientation == orientation:
            return it
    return None


def time_limit_s(item, test: str) -> tuple[float | None, str]:
    """The time-to-reading bound of a reading: the protocol's, else A.1's for 7.4/7.7."""
    if item.max_time_to_reading_s is not None:
        return float(item.max_time_to_reading_s), (
            f"the protocol's max_time_to_reading_s = {item.max_time_to_reading_s:g} s")
    if test in A1_TESTS:
        return A1_MAX_TIME_S, (f"Annex A.1's 0.5 min ({A1_MAX_TIME_S:g} s; the protocol sets "
                               "no max_time_to_reading_s, only an explicit one widens it)")
    return None, ""


def _action(item) -> str:
    return "refused" if item is not None and item.on_bad_reading == "error" else "set_aside"


def _complete_series(se: np.ndarray, rnd: np.ndarray, n: int) -> set:
    """The series numbers among ``se`` whose rounds, sorted, are exactly 1…n (each round
    read once), by one sort instead of a pass over the rows per series."""
    if not se.size:
        return set()
    order = np.lexsort((rnd, se))
    se, rnd = se[order], rnd[order]
    nums, first, count = np.unique(se, return_index=True, return_counts=True)
    place = np.arange(se.size) - np.repeat(first, count)     # position within its series
    wrong = np.unique(se[rnd != place + 1])
    return set(nums[(count == n) & ~np.isin(nums, wrong)].tolist())


def _series_outside(g: pd.DataFrame, it, test: str, clause, name: str, file,
                    aside_lines: set) -> tuple[list[Finding], set]:
    """Readings of a condition whose series number is outside 1…series, one finding per
    condition (the numbers, the count, its first line and the line range; its other lines
    in ``aside_lines``), and the set of those series that are kept:

    * a **complete** series beyond the programme (series > the protocol's count, every
      round read once) is data measured beyond the programme: kept and used, and
      ``series-beyond-programme`` flagged (a laboratory that ran 50 series);
    * any other (series < 1, or a series missing rounds — one reading numbered 11 of 10
      is a typo): ``series-not-in-programme``, set aside (or refused per the protocol).

    One finding per condition: a 12 000-row file of 20 series for a 10-series protocol
    wrote 9 900 findings, 3 MB of results.json."""
    se = g["series"].astype(int).to_numpy()
    rnd = g["round"].astype(int).to_numpy()
    n = len(it.rounds)
    kept = _complete_series(se[se > it.series], rnd[se > it.series], n)
    bad = ((se < 1) | (se > it.series)) & ~np.isin(se, list(kept))
    out = []
    for mask, code, action, what in (
            (np.isin(se, list(kept)), "series-beyond-programme", "flagged",
             "complete, measured beyond the programme: used"),
            (bad, "series-not-in-programme", _action(it), "all set aside")):
        if not mask.any():
            continue
        lines = np.sort(g["line"].to_numpy()[mask].astype(np.int64)).tolist()
        nums = sorted(set(se[mask].tolist()))
        which = (f"series {nums[0]}" if len(nums) == 1 else
                 f"series {', '.join(map(str, nums[:5]))}{', …' if len(nums) > 5 else ''}")
        verb = "is not one of" if len(nums) == 1 else "are not among"
        more = (f"; {len(lines)} readings, lines {lines[0]}–{lines[-1]}, {what}"
                if len(lines) > 1 else ("" if action != "flagged" else f"; {what}"))
        if action != "flagged":
            aside_lines.update(lines[1:])
        out.append(Finding(code, f"{test} {which} {verb} the protocol's {it.series} "
                           f"series ({name}){more}", action, file=file, line=lines[0],
                           column="series", test=test, clause=clause,
                           rule=f"1 ≤ series ≤ {it.series}, or a complete series beyond"))
    return out, kept


def _rows_to_check(cols, it, n: int, want: np.ndarray, limit, kept: set) -> np.ndarray:
    """Indices of the rows of a condition that break a round, angle or time rule (the
    rules of :func:`_protocol_rules`, element-wise), in file order: only those are looked
    at one by one."""
    _, se, rnd, tab, t = cols
    se, rnd = se.astype(np.int64), rnd.astype(np.int64)
    tab, t = tab.astype(np.float64), t.astype(np.float64)
    used = ((se >= 1) & (se <= it.series)) | np.isin(se, list(kept))
    round_bad = (rnd < 1) | (rnd > n)
    off = ~(np.abs(tab - want[np.clip(rnd - 1, 0, n - 1)]) <= it.position_tolerance_deg)
    late = (t > limit + 1e-9) if limit is not None else np.zeros(t.size, dtype=bool)
    return np.flatnonzero(used & (round_bad | off | late))


def _protocol_rules(df: pd.DataFrame, protocol, file, aside_lines: set) -> list[Finding]:
    """Round, condition, angle and time of every rotation reading against the protocol.

    A condition outside the programme is one finding (its first line, the count and the
    line range); its other lines go into ``aside_lines``."""
    out = []
    for test in ROTATION_TESTS:
        rows = df[df["test"] == test]
        if not len(rows) or not items_of(protocol, test):
            continue
        clause = CLAUSES[test]
        for (rate, orient), g in rows.groupby(["rate_dps", "orientation"], sort=False):
            it = item_for(protocol, test, float(rate), str(orient))
            if it is None:
                lines = sorted(int(x) for x in g["line"])
                more = (f"; {len(lines)} readings, lines {lines[0]}–{lines[-1]}, all set aside"
                        if len(lines) > 1 else "")
                out.append(Finding(
                    "condition-not-in-programme",
                    f"{test} at {float(rate):g} °/s, axis {orient}: not a condition of the "
                    f"protocol's programme ({protocol.name}){more}", "set_aside", file=file,
                    line=lines[0], column="rate_dps", test=test, clause=clause,
                    rule="rate and orientation must be a programme condition"))
                aside_lines.update(lines[1:])
                continue
            n = len(it.rounds)
            want = np.array([r.stop_deg - r.start_deg for r in it.rounds])
            limit, limit_txt = time_limit_s(it, test)
            found_s, kept = _series_outside(g, it, test, clause, protocol.name, file,
                                            aside_lines)
            out += found_s
            cols = [g[c].to_numpy() for c in ("line", "series", "round", "table_deg", "time_s")]
            for i in _rows_to_check(cols, it, n, want, limit, kept):
                line, se, rnd, tab, t = (c[i] for c in cols)
                rnd, tab, t = int(rnd), float(tab), float(t)
                f = dict(file=file, line=int(line), test=test, clause=clause)
                if not 1 <= int(se) <= it.series and int(se) not in kept:
                    continue                    # one finding per condition (_series_outside)
                elif not 1 <= rnd <= n:
                    out.append(Finding("round-not-in-programme",
                                       f"{test} round {rnd} is not one of the protocol's {n} "
                                       f"rounds ({protocol.name})", _action(it), column="round",
                                       rule=f"1 ≤ round ≤ {n}", **f))
                elif not abs(tab - want[rnd - 1]) <= it.position_tolerance_deg:
                    out.append(Finding("angle-off-nominal",
                                       f"{test} round {rnd}: table_deg {tab:g} differs from the "
                                       f"protocol's {want[rnd - 1]:g}° (tolerance "
                                       f"{it.position_tolerance_deg:g}°)", _action(it),
                                       column="table_deg",
                                       rule="|table_deg − (stop − start)| ≤ "
                                            "position_tolerance_deg", **f))
                elif limit is not None and t > limit + 1e-9:
                    out.append(Finding("late-reading",
                                       f"{test} round {rnd}: read {t:g} s after zeroing, beyond "
                                       f"{limit_txt} (Annex A.1)", _action(it), column="time_s",
                                       rule=f"time_s ≤ {limit:g} s", **f))
    return out


def reference_scale_factor(df: pd.DataFrame, metadata: dict, file=None) -> float | None:
    """K_ref: the median of gyro_counts / table_deg over every rotation reading, robust to
    a few typos (≥ 3 readings); else the metadata's nominal K; else None."""
    rot = df[df["test"].isin(ROTATION_TESTS)]
    c, a = rot["gyro_counts"].to_numpy(float), rot["table_deg"].to_numpy(float)
    ok = np.isfinite(c) & np.isfinite(a) & (np.abs(a) > 0)
    if ok.sum() >= 3:
        return float(np.median(c[ok] / a[ok]))
    return metadata_float(metadata, "nominal_scale_factor_counts_per_deg", file=file)


#: A row giving both gyro_deg and gyro_counts must agree through K within this relative
#: tolerance of the angle, or :data:`COUNTS_AGREE_ABS_DEG`, whichever is larger.
COUNTS_AGREE_REL: float = 1e-4
COUNTS_AGREE_ABS_DEG: float = 1e-3


def counts_agree_rule(df: pd.DataFrame, k_ref: float | None, file=None) -> list[Finding]:
    """``counts-contradict-angle``: refuse the first row whose ``gyro_deg`` contradicts its
    ``gyro_counts`` through K_ref (:func:`reference_scale_factor`), every row of the file
    judged, those another rule sets aside included; ``[]`` without K_ref or where they agree.

    Rule: |gyro_deg − gyro_counts/K_ref| ≤ max(:data:`COUNTS_AGREE_REL` · |gyro_deg|,
    :data:`COUNTS_AGREE_ABS_DEG`). Reason: a row stating its angle twice states one reading;
    when the two disagree the file cannot say which is the reading, so neither is set aside
    as an outlier in favour of the other. K_ref, not 7.1's K: the screening has it before
    the calibration, so the screening and the calibration refuse the same row; the two
    agree far inside the tolerance (10⁻⁴ of the angle)."""
    if not k_ref or not {"gyro_deg", "gyro_counts"} <= set(df.columns):
        return []
    deg = df["gyro_deg"].to_numpy(dtype=float)
    cnt = df["gyro_counts"].to_numpy(dtype=float)
    both = ~np.isnan(deg) & ~np.isnan(cnt)
    diff = np.abs(deg - cnt / k_ref)
    bad = both & (diff > np.maximum(COUNTS_AGREE_REL * np.abs(deg), COUNTS_AGREE_ABS_DEG))
    if not bad.any():
        return []
    i = int(np.argmax(bad))
    row = df.iloc[i]
    return [Finding("counts-contradict-angle",
                    f"gyro_deg {deg[i]:.9g} contradicts gyro_counts {cnt[i]:.0f} / K "
                    f"{k_ref:.9g} = {cnt[i] / k_ref:.9g} by {diff[i]:.3g}°", "refused",
                    file=file, line=int(row["line"]), column="gyro_deg",
                    test=str(row["test"]), clause=CLAUSES.get(str(row["test"])),
                    rule="gyro_deg = gyro_counts / K_ref within max(1e-4 · |angle|, 0.001°)")]


#: The factor by which the metadata's nominal K may depart from the K the readings
#: measure, either way (:func:`nominal_k_rule`).
NOMINAL_K_FACTOR: float = 10.0


def nominal_k_rule(df: pd.DataFrame, metadata: dict, file=None) -> list[Finding]:
    """``nominal-scale-factor-departs``: the metadata's ``nominal_scale_factor_counts_per_deg``
    against K_ref, the median of gyro_counts / table_deg over the rotation readings (at least
    3; :func:`reference_scale_factor`), where both exist.

    Rule: K_ref / nominal within 1/:data:`NOMINAL_K_FACTOR` … :data:`NOMINAL_K_FACTOR`.
    Reason: an instrument's K departs from its nominal by ppm; ten times is a nominal in
    another unit or scale (×1000, counts per arcsecond or radian). Where the file has no 7.1
    readings the nominal K reads every angle of E, R, C_v and C_g (certified numbers): the
    contradiction is refused. With 7.1 readings those angles use 7.1's K and the nominal
    enters no certified item: a flagged finding states it (certificate, results.json)."""
    nominal = metadata_float(metadata, "nominal_scale_factor_counts_per_deg", file=file)
    rot = df[df["test"].isin(ROTATION_TESTS)]
    c, a = rot["gyro_counts"].to_numpy(float), rot["table_deg"].to_numpy(float)
    ok = np.isfinite(c) & np.isfinite(a) & (np.abs(a) > 0)
    if not nominal or ok.sum() < 3:
        return []
    k_ref = float(np.median(c[ok] / a[ok]))
    ratio = k_ref / nominal
    if 1.0 / NOMINAL_K_FACTOR <= ratio <= NOMINAL_K_FACTOR:
        return []
    has_71 = bool((rot["test"] == "scale_factor").any())
    text = (f"nominal_scale_factor_counts_per_deg {nominal:.9g} departs from the K the "
            f"readings measure, {k_ref:.9g} counts/° (the median of gyro_counts / table_deg; "
            f"ratio {ratio:.3g}, beyond {NOMINAL_K_FACTOR:g}× either way: a nominal in "
            "another unit or scale?)")
    if not has_71:
        raise GonioError(f"{text}; without 7.1 readings it reads every angle of E, R, C_v "
                         "and C_g", file=file, key="nominal_scale_factor_counts_per_deg")
    return [Finding("nominal-scale-factor-departs", f"{text}; the angles are read with 7.1's "
                    "K, no certified item uses it", "flagged", file=file,
                    column="nominal_scale_factor_counts_per_deg",
                    rule=f"K_ref / nominal K within 1/{NOMINAL_K_FACTOR:g} … "
                         f"{NOMINAL_K_FACTOR:g}")]


def _outliers(r: np.ndarray) -> tuple[np.ndarray, float, float]:
    """The indices outside the rule, the median and the threshold (″)."""
    med = float(np.median(r))
    thr = max(ROBUST_Z * 1.4826 * float(np.median(np.abs(r - med))), ANGLE_FLOOR_ARCSEC)
    return np.flatnonzero(np.abs(r - med) > thr), med, thr


def round_threshold_arcsec(r_arcsec: np.ndarray, rounds: np.ndarray, step_arcsec: float
                           ) -> tuple[np.ndarray, np.ndarray]:
    """The round-by-round rule of a condition whose rounds are read in many series (7.4):
    each reading's round median and threshold, ″ (the reading is set aside when
    ``|r − median| > threshold``).

    threshold = max(``ROUND_Z`` · max(s_round, s_pooled), ``ROUND_FLOOR_STEPS`` · step),
    s_round = 1.4826 · MAD of the round's readings, s_pooled = 1.4826 · median of every
    reading's |r − its round's median| over the condition: the data's own spread, which a
    round's ten readings alone estimate too loosely (one round in a session would draw a
    small MAD), and never below a few steps of the instrument's resolution ``step_arcsec``.
    A digit transposed in one reading (18 counts, 0.85″, where a round spreads ~0.1″) is
    set aside; the former floor of ``ANGLE_FLOOR_ARCSEC`` let it through.

    >>> r = np.array([0.0, 0.1, -0.1, 0.05, -0.05, 0.9, 0.0, 0.1, -0.1, 0.05])
    >>> med, thr = round_threshold_arcsec(r, np.array([1] * 5 + [2] * 5), 0.047)
    >>> [round(float(x), 3) for x in (med[0], med[5], thr[0])]
    [0.0, 0.05, 0.47]
    >>> np.flatnonzero(np.abs(r - med) > thr).tolist()
    [5]
    """
    r = np.asarray(r_arcsec, float)
    rounds = np.asarray(rounds)
    med, s_round = np.empty_like(r), np.empty_like(r)
    for rd in np.unique(rounds):
        m = rounds == rd
        med[m] = np.median(r[m])
        s_round[m] = 1.4826 * np.median(np.abs(r[m] - med[m]))
    s_pooled = 1.4826 * float(np.median(np.abs(r - med)))
    return med, np.maximum(ROUND_Z * np.maximum(s_round, s_pooled),
                           ROUND_FLOOR_STEPS * step_arcsec)


def _resolution_arcsec(g: pd.DataFrame, k_ref, deg_step: float | None = None) -> float:
    """One step of the column the readings of ``g`` come from, ″: one count (1/K_ref) for
    ``gyro_counts``; for ``gyro_deg`` ``deg_step`` where given (:func:`_deg_step` of the
    file's rotation readings) and non-zero, else the smallest non-zero step between two
    readings of a round of ``g``, else (no round read twice) between any two of ``g``
    (0 where none)."""
    if (g["_col"] == "gyro_counts").all() and k_ref:
        return deg_to_arcsec(1.0 / float(k_ref))
    if deg_step:
        return float(deg_step)
    return _deg_step(g, ["round"]) or _deg_step(g, [])


def _deg_step(g: pd.DataFrame, keys=("test", "rate_dps", "orientation", "round")) -> float:
    """The smallest non-zero step between two values of ``_r`` in a group of ``g`` by
    ``keys`` (all of ``g`` for none), ″: a round read in ten series repeats values to the
    column's step (7.4); 0 where no two differ by a step."""
    groups = [g["_r"]] if not keys else [x for _, x in g.groupby(list(keys), dropna=False)["_r"]]
    steps = np.concatenate([np.diff(np.unique(x.to_numpy(float))) for x in groups]) \
        if groups else np.array([])
    steps = steps[steps > 1e-9]
    return float(steps.min()) if steps.size else 0.0


def _departures(g: pd.DataFrame, found, what: str, file, test: str, rule: str, k_ref
                ) -> list[Finding]:
    """One set-aside finding per reading of ``g`` in ``found``: (position in ``g``, what it
    departs from, the departure ″, the threshold ″ it broke, a note on the threshold). The
    round-by-round, condition and median rules all name a reading this way."""
    r = g["_r"].to_numpy(float)
    return [_outlier_finding(
        g.iloc[i], f"indicated − table angle {r[i]:.4g}″ departs from {against} by "
        f"{abs(dev):.4g}″ (> {thr:.3g}″{note})", what, file, test, rule, k_ref)
        for i, against, dev, thr, note in found]


def _round_outliers(g: pd.DataFrame, test: str, what: str, file, k_ref, step: float
                    ) -> list[Finding]:
    """The readings of a condition read in many series that break the round-by-round rule
    (:func:`round_threshold_arcsec`), one finding each."""
    r = g["_r"].to_numpy(float)
    med, thr = round_threshold_arcsec(r, g["round"].to_numpy(), step)
    return _departures(g, [(i, f"the round's median {med[i]:.3g}″", r[i] - med[i], thr[i], "")
                           for i in np.flatnonzero(np.abs(r - med) > thr)],
                       what, file, test, _ROUND_RULE, k_ref)


_ROUND_RULE = (f"|r − median(r of the round)| > max({ROUND_Z:g} · max(s_round, s_pooled), "
               f"{ROUND_FLOOR_STEPS:g} steps of resolution), s = 1.4826 · MAD (of the round; "
               "pooled over the condition's rounds), r = indicated − table angle, indicated = "
               "gyro_deg or gyro_counts / K_ref, K_ref = median(gyro_counts / table_deg) of all "
               "rotation readings")

#: A condition whose positions are read once (7.1; 7.6 and 7.7 read once per rate or
#: orientation) of at least this many readings is screened against the line its other
#: readings draw (:func:`line_departures`); a smaller one by the median rule
#: (:func:`_outliers`, ``ANGLE_FLOOR_ARCSEC``).
LINE_MIN: int = 5
#: With at least this many other readings the condition model adds cos θ and sin θ to the
#: line (:func:`line_departures`): 7.6 and 7.7's twelve positions, not 7.1's six.
HARMONIC_MIN: int = 9
#: Multiple of a reading's allowed drift (the draft's zero-stability bound, Annex A.4.3's
#: 0.005 °/h, times its time from zeroing) below which the condition rule keeps it: at 1 °/s
#: a clean reading 250–370 s after zeroing departed from the others' fit by up to 2.0 such
#: drifts (clean sessions, docs/draft-readings.md "Screening"), 10.9 times the others' s.
DRIFT_Z: float = 3.0
#: The probability that the condition rule (:func:`line_departures`) sets aside a reading of
#: a clean session (every reading normal about its condition's fit): the session's groups
#: judged by that rule share it (Bonferroni), each group's readings share its group's part
#: (:func:`line_critical_value`). A reading set aside in 7.1, 7.6 or 7.7 refuses the
#: calibration, so this is the chance that a good session is refused by this rule (for the
#: 7.6 and 7.7 groups at most twice it: the pair stage, :func:`pair_departures`, takes the
#: group's share again).
SCREEN_ALPHA: float = 0.02
#: Floor of the condition and 7.3 rules, in steps of the resolution (one count, or the
#: ``gyro_deg`` column's step): where the others agree to a few counts their MAD is
#: lumpy (see ``ROUND_FLOOR_STEPS``).
SPREAD_FLOOR_STEPS: float = 10.0


def _design(x_deg: np.ndarray, harmonic: bool) -> np.ndarray:
    """The columns of the condition model at the angles ``x_deg``: 1 and the angle (in
    turns), with cos θ and sin θ where ``harmonic``."""
    x = np.asarray(x_deg, float)
    cols = [np.ones_like(x), x / 360.0]
    if harmonic:
        cols += [np.cos(np.radians(x)), np.sin(np.radians(x))]
    return np.column_stack(cols)


def line_critical_value(n_readings: int, dof: int, alpha: float = SCREEN_ALPHA) -> float:
    """The small-sample factor c of the condition rule: the largest of ``n_readings``
    leave-one-out residuals, each divided by s · √(1 + h), exceeds c with probability
    ≤ ``alpha`` for normal readings, s having ``dof`` degrees of freedom.

    The rule. A reading's departure from the least-squares fit of the others, divided by
    the others' residual standard deviation s (ν = n_others − p) and √(1 + h), h its
    leverage, is the externally studentized (deleted) residual; for independent normal
    readings of equal variance it follows Student's t with ν degrees of freedom exactly
    (the prediction interval of a new observation; Cook & Weisberg, *Residuals and
    Influence in Regression*, 1982, §2.2.2; Beckman & Cook, Technometrics 25 (1983) 119,
    the Bonferroni outlier test). The largest of the group's n such residuals exceeds c
    with probability ≤ n · P(|t_ν| > c) (Bonferroni), so c = t_ν⁻¹(1 − α / (2n)); the
    session's groups take α = ``SCREEN_ALPHA`` / their number (:func:`_indicated_rule`).
    A fixed multiple of s (the former 7 · s) is exceeded far more often where s rests on
    few values: with ν = 3, |t_3| > 7 has probability 0.6 % per reading.

    >>> round(line_critical_value(6, 3, 0.01), 2), round(line_critical_value(12, 7, 0.01), 2)
    (10.87, 5.58)
    """
    if n_readings < 1 or dof < 1 or not 0.0 < alpha < 1.0:
        raise ValueError("line_critical_value needs n_readings ≥ 1, dof ≥ 1, 0 < alpha < 1")
    return float(student_t.isf(alpha / (2.0 * n_readings), dof))


def pair_departures(x: np.ndarray, d: np.ndarray, idx: np.ndarray, drift: np.ndarray,
                    floor_arcsec: float, scale_min_arcsec: float, alpha: float):
    """The condition rule's second stage (:func:`line_departures` with ``pairs``): two
    departing readings each widen the fit of the others and hide one another from the
    leave-one-out stage (7.6 at 10 °/s, two +10″ typos at 90° and 120° on the RLG: no
    finding, C_v 10.2 ppm [7.8, 12.3] certified where the clean file gives ≤ 4.9 ppm; two
    +100″: no finding either). Leave two out: the pair without which the others' residuals
    are smallest, each of the two against the others' least-squares model, set aside when
    |d_k − fit(θ_k)| > max(c₂ · s · √(1 + h_k), ``DRIFT_Z`` · drift_k, floor), s the others'
    residual standard deviation (ν = n − 2 − p, never below ``scale_min_arcsec``),
    c₂ = t_ν⁻¹(1 − α / (4 · P)) for the P = m(m − 1)/2 pairs of the m readings: each
    reading of each pair is Student's t under no typo, so the stage sets aside a reading of
    a clean group with probability ≤ α (Bonferroni over the 2P residuals). Returns
    ([(index, departure ″, threshold ″, s ″, c₂) of each set aside], the indices left)."""
    m = idx.size
    X = _design(x, m - 2 >= HARMONIC_MIN)
    dof = m - 2 - X.shape[1]
    if dof < 1:
        return [], idx
    best = None
    for a in range(m):
        for b in range(a + 1, m):
            rest = np.delete(idx, [a, b])
            coef, *_ = np.linalg.lstsq(X[rest], d[rest], rcond=None)
            e = d[rest] - X[rest] @ coef
            score = float(np.max(np.abs(e - np.median(e))))
            if best is None or score < best[0]:
                best = (score, (idx[a], idx[b]), rest, e, coef)
    _, pair, rest, e, coef = best
    s = max(math.sqrt(float(e @ e) / dof), float(scale_min_arcsec))
    c = float(student_t.isf(alpha / (4.0 * m * (m - 1) / 2.0), dof))
    inv = np.linalg.pinv(X[rest].T @ X[rest])
    out = []
    for k in pair:
        h = float(X[k] @ inv @ X[k])
        dev = float(d[k] - X[k] @ coef)
        thr = max(c * s * math.sqrt(1.0 + h), DRIFT_Z * float(drift[k]), float(floor_arcsec))
        if abs(dev) > thr:
            out.append((int(k), dev, thr, s, c))
    if not out:
        return [], idx
    return out, np.setdiff1d(idx, [k for k, *_ in out])


def line_departures(x_deg, d_arcsec, floor_arcsec: float, scale_min_arcsec: float = 0.0,
                    drift_arcsec=None, alpha: float = SCREEN_ALPHA, prior=None,
                    pairs: bool = False) -> list[tuple[int, float, float, float, float]]:
    """The condition rule of readings taken once per position (7.1, 7.6, 7.7): each
    reading against the least-squares model in the table angle θ that the condition's
    other readings draw (leave one out). The readings of one rate or orientation differ
    from the reference's by a scale-factor change and a drift over the turn's time, both
    in proportion to the angle (a line), and by the tilted sensing axis's Earth-rate
    coupling, which a slow turn integrates into a first harmonic of θ (``coupling.py``);
    the model is the line, and with ``HARMONIC_MIN`` others or more the line and cos θ,
    sin θ. The position's own error is taken out beforehand where a reference is read
    (``d`` = reading less the reference round's median at its angle,
    :func:`_line_outliers`).

    The candidate is the reading without which the others' residuals are smallest (a
    typo pulls the fit and widens the others' spread); it is set aside when
    |d_j − fit(θ_j)| > max(c · s · √(1 + h_j), ``DRIFT_Z`` · drift_j, ``floor_arcsec``),
    s = max(√(Σ others' residuals² / (n − p)), ``scale_min_arcsec``) over the n others and
    p terms, c = :func:`line_critical_value` (m, n − p, ``alpha``) for the m readings
    judged (the group's share of the session's false-alarm probability). The 7.4
    reference's scatter is not pooled into s even where the condition is the reference's
    (7.1): a clean FOG 7.1 reading departed 4.4 such pooled s from the others' line (the
    fit's misfit, which only the others' own residuals show);
    h_j = x_jᵀ(XᵀX)⁻¹x_j (the fit's own uncertainty at θ_j),
    drift_j the drift the instrument may accumulate from zeroing to reading j
    (``drift_arcsec``, :func:`_line_outliers`: the draft's zero-stability bound times
    time_s; 0 where not given): a slow turn's reading wanders with the bias over minutes
    (1 °/s: 6 min for 360°) beyond what the other readings' spread shows; the rule then
    runs again on the others while ``LINE_MIN`` − 1 remain. Returns (index, departure ″,
    threshold ″, s ″, c) of each reading set aside, in that order. With ``pairs`` (7.6 and
    7.7), where no single reading departs, the readings are judged two at a time
    (:func:`pair_departures`: two typos hide one another from the leave-one-out fit).

    ``prior`` = (s₀ ″, ν₀): an independent estimate of the scale of one ``d`` with ν₀
    degrees of freedom (7.1 against the repeated rounds of 7.4,
    :func:`repeated_reference_scale`). s is then pooled, s² = (ν₀ s₀² + ν s_others²) /
    (ν₀ + ν), with ν₀ + ν degrees of freedom in c, and ``scale_min_arcsec`` is not used
    (it was the lower bound a 3-degree-of-freedom s needed): the deleted residual is
    again Student's t, now with ~100 degrees of freedom, so c ≈ 3.8 instead of ≈ 19 and
    a single-reading typo of 0.75″ stands out of a scatter of 0.1″.

    >>> x = np.arange(30.0, 361.0, 30.0)
    >>> d = 0.002 * x + np.array([0.1, -0.1, 0.0, 0.05, -0.05, 0.1, 0.0, -0.1, 0.05, 0.0,
    ...                           -0.05, 0.1])
    >>> line_departures(x, d, 0.47)
    []
    >>> d[4] += 1.5
    >>> [(i, round(dev, 2)) for i, dev, *_ in line_departures(x, d, 0.47)]
    [(4, 1.42)]
    """
    x, d = np.asarray(x_deg, float), np.asarray(d_arcsec, float)
    drift = np.zeros(d.size) if drift_arcsec is None else np.asarray(drift_arcsec, float)
    idx = np.arange(d.size)
    out = []
    # with the prior, the scale needs no refit: the others are judged again down to a line
    # with one degree of freedom of its own (a set-aside never leaves readings unjudged)
    while idx.size >= (LINE_MIN if prior is None else 4):
        X = _design(x, idx.size - 1 >= HARMONIC_MIN)
        best = None
        for j in range(idx.size):
            rest = np.delete(idx, j)
            coef, *_ = np.linalg.lstsq(X[rest], d[rest], rcond=None)
            e = d[rest] - X[rest] @ coef
            score = float(np.max(np.abs(e - np.median(e))))
            if best is None or score < best[0]:
                best = (score, j, rest, e, coef)
        _, j, rest, e, coef = best
        n, p, k = rest.size, X.shape[1], idx[j]
        dof = n - p
        if prior is None:
            s = max(math.sqrt(float(e @ e) / dof), float(scale_min_arcsec))
        else:
            s0, nu0 = float(prior[0]), int(prior[1])
            s = math.sqrt((nu0 * s0 * s0 + float(e @ e)) / (nu0 + dof))
            dof += nu0
        h = float(X[k] @ np.linalg.pinv(X[rest].T @ X[rest]) @ X[k])
        dev = float(d[k] - X[k] @ coef)
        c = line_critical_value(idx.size, dof, alpha)
        thr = max(c * s * math.sqrt(1.0 + h), DRIFT_Z * float(drift[k]),
                  float(floor_arcsec))
        if not abs(dev) > thr:
            found, left = (pair_departures(x, d, idx, drift, floor_arcsec, scale_min_arcsec,
                                           alpha) if pairs and prior is None else ([], idx))
            if not found:
                break
            out += found
            idx = left
            continue
        out.append((int(k), dev, thr, s, c))
        idx = rest
    return out


def allowed_drift_arcsec_per_s(protocol) -> float:
    """The drift rate a reading may carry from zeroing to reading, ″/s: the draft's
    zero-stability bound (``[annex_a] zero_stability_dph``, A.4.3: 0.005 °/h), 0 where the
    protocol has none."""
    a = getattr(protocol, "annex_a", None)
    v = getattr(a, "zero_stability_dph", None) if a is not None else None
    return float(dph_to_arcsec_s(float(v))) if v else 0.0


def reference_rounds(work: pd.DataFrame, protocol, k_ref=None, deg_step: float = 0.0):
    """The reference condition's rounds (7.4 at its rate and orientation, every round read
    in at least ``PER_ROUND_MIN`` series): their table angles (median of ``table_deg``,
    °), the median of each round's r (″), the pooled scale s = 1.4826 · median of every
    reading's |r − its round's median| (″), the position tolerance and the scale of one
    reading from the rounds' repetition (:func:`repeated_reference_scale`, ``k_ref`` and
    ``deg_step`` giving the resolution); None where the file has no such reference."""
    it = getattr(protocol, "angle_deviation", None)
    if it is None:
        return None
    g = work[(work["test"] == "angle_deviation")
             & np.isclose(work["rate_dps"].to_numpy(float), it.rate_dps)
             & (work["orientation"] == it.orientation)]
    if not len(g):
        return None
    per = g.groupby("round", sort=True)
    if per.size().min() < PER_ROUND_MIN:
        return None
    med = per["_r"].transform("median").to_numpy(float)
    return (per["table_deg"].median().to_numpy(float), per["_r"].median().to_numpy(float),
            1.4826 * float(np.median(np.abs(g["_r"].to_numpy(float) - med))),
            float(it.position_tolerance_deg),
            repeated_reference_scale(g, _resolution_arcsec(g, k_ref, deg_step)
                                     if "_col" in g else 0.0))


def repeated_reference_scale(g: pd.DataFrame, step_arcsec: float = 0.0
                             ) -> tuple[float, int, int]:
    """The scale of one reading of the 7.4 reference condition, from its repetition (7.5:
    7.4 repeated ten times): (s ″, ν, n) with s² = Σ (r − its round's mean)² / ν over the
    rounds' readings, ν = N − R (N readings, R rounds), n the fewest readings of a round.
    Readings that break the round-by-round rule (:func:`round_threshold_arcsec` with the
    resolution ``step_arcsec``; a typo in 7.4, set aside by that rule) are left out, so one typo there does not widen it.

    Why it bounds 7.1. 7.1's rounds turn the same table, at the same rate and axis, to
    the same stops from the same zeroed start as 7.4's (both: 0° → 60°, …, 360° at
    60 °/s); what differs is the reading delay (5 s against 10 s) and the time of day.
    Everything a position repeats — the table's error at that stop (A.4.1, MPE 0.1″),
    the instrument's nonlinearity, the tilt's elliptic error (A.4.2) — is the same in a
    7.1 reading and in its 7.4 round; everything that changes from one turn to the next
    (noise, the table's random part, the drift of A.4.3) is what the ten repetitions of
    the round scatter by. So a 7.1 reading less its 7.4 round's median scatters by
    s · √(1 + π/(2n)) (the median of n normal readings has variance ≈ π σ² / (2n)), known
    from ν ≈ 100 degrees of freedom instead of the 3 of 7.1's own six positions
    (:func:`line_departures`' ``prior``). A real nonlinearity repeats in every round of
    7.4 and cancels; a typo lives in the one 7.1 reading and does not. Clean sessions
    (seed 20261202, 85 built-in sessions, RLG and FOG): the 7.1 readings' residuals from
    their line were at most 2.3 such s. The Bessel s, not the pooled 1.4826 · MAD, which
    on the FOG's 0.0375″ steps read 0.074″ where the Bessel s was 0.12–0.13″."""
    r = g["_r"].to_numpy(float)
    rounds = g["round"].to_numpy()
    med, thr = round_threshold_arcsec(r, rounds, step_arcsec)
    keep = np.abs(r - med) <= thr
    r, rounds = r[keep], rounds[keep]
    ss, n_min, nu = 0.0, None, 0
    for rd in np.unique(rounds):
        x = r[rounds == rd]
        ss += float(((x - x.mean()) ** 2).sum())
        nu += x.size - 1
        n_min = x.size if n_min is None else min(n_min, x.size)
    return (math.sqrt(ss / nu) if nu > 0 else 0.0), int(nu), int(n_min or 0)


def _line_outliers(g: pd.DataFrame, test: str, what: str, file, k_ref, step: float, ref,
                   drift_arcsec_per_s: float = 0.0, alpha: float = SCREEN_ALPHA,
                   reference_condition: bool = False) -> list[Finding]:
    """The readings of a condition read once per position that break the condition rule
    (:func:`line_departures`), one finding each. Where every reading's angle is a
    reference round's (``ref``, :func:`reference_rounds`), each is taken less that round's
    median (the position's own error, common to every rate and orientation) and the
    scale is never below the reference's pooled one; ``alpha`` is the group's share of the
    session's false-alarm probability. Where the condition is the reference's own rate and
    axis (``reference_condition``: 7.1) the scale is the one the reference's repeated
    rounds give (:func:`repeated_reference_scale`, pooled with the group's own)."""
    r = g["_r"].to_numpy(float)
    x = g["table_deg"].to_numpy(float)
    d, s_min, less, prior = r, 0.0, "", None
    if ref is not None:
        ang, med, s_ref, tol, (s_rep, nu_rep, n_rep) = ref
        j = np.abs(x[:, None] - ang[None, :]).argmin(axis=1)
        if np.all(np.abs(ang[j] - x) <= tol):
            d, s_min = r - med[j], s_ref
            less = ", each reading less the 7.4 reference round's median at its angle"
            if reference_condition and nu_rep > 0 and n_rep > 0:
                prior = (s_rep * math.sqrt(1.0 + math.pi / (2.0 * n_rep)), nu_rep)
                less += (f", s pooled with the 7.4 rounds' repetition ({s_rep:.3g}″ a "
                         f"reading, ν = {nu_rep})")
    drift = drift_arcsec_per_s * np.abs(g["time_s"].to_numpy(float))
    drift = np.where(np.isfinite(drift), drift, 0.0)
    found = [(i, f"the fit its condition's other readings draw{less}", dev, thr,
              f"; s = {s:.3g}″ of the others, drift allowed {drift[i]:.3g}″")
             for i, dev, thr, s, _ in line_departures(x, d, SPREAD_FLOOR_STEPS * step, s_min,
                                                      drift, alpha, prior,
                                                      pairs=test in COMPARED)]
    return _departures(g, found, what, file, test,
                       _LINE_RULE if prior is None else _REFERENCE_LINE_RULE, k_ref)


_LINE_RULE = (f"|d − line(others)| > max(c · s · √(1 + h), {DRIFT_Z:g} · drift, "
              f"{SPREAD_FLOOR_STEPS:g} steps of resolution), d = r less the 7.4 reference "
              "round's median at the same angle (r where none), line = least squares in the "
              "table angle through the condition's other readings, s = max(√(Σ their "
              "residuals² / ν), the reference's pooled s), ν = n − p, h its leverage, "
              "c = t_ν⁻¹(1 − α/(2m)) for the m readings judged, α = "
              f"{SCREEN_ALPHA:g} / the session's groups under this rule (Bonferroni); "
              "r = indicated − table angle, indicated = gyro_deg or gyro_counts / K_ref")


_REFERENCE_LINE_RULE = (
    _LINE_RULE + "; at the 7.4 reference's own rate and axis (7.1: the same stops, rate and "
    "axis as 7.4, repeated ten times by 7.5) s² = (ν₀ s₀² + Σ residuals²) / (ν₀ + ν) and "
    "c with ν₀ + ν, s₀ = s_rep · √(1 + π/(2n)), s_rep the Bessel standard deviation of the "
    "7.4 readings about their round's mean (ν₀ = N − rounds, n readings a round): what a "
    "position repeats (table error, nonlinearity) cancels in d, a typo in one reading does "
    "not")


def _group_rule(g: pd.DataFrame) -> str:
    """Which rule judges a condition's readings: "round" (every round read in at least
    ``PER_ROUND_MIN`` series), "line" (at least ``LINE_MIN`` readings), else "median"."""
    if g.groupby("round", sort=False).size().min() >= PER_ROUND_MIN:
        return "round"
    return "line" if len(g) >= LINE_MIN else "median"


def line_rule_groups(df: pd.DataFrame) -> int:
    """The number of conditions of the rotation readings ``df`` the condition rule judges."""
    rot = df[df["test"].isin(ROTATION_TESTS)]
    return sum(_group_rule(g) == "line"
               for _, g in rot.groupby(["test", "rate_dps", "orientation"], sort=False))


def _indicated_rule(df: pd.DataFrame, protocol, file, k_ref, skip: set,
                    line_groups: int | None = None) -> list[Finding]:
    """Each reading's indicated angle against what the other readings of its condition say.

    ``line_groups``: the number of the session's groups the condition rule judges, which
    share ``SCREEN_ALPHA``, where ``df`` is a part of the session (a study that screens one
    test and its reference); by default those of ``df``."""
    deg = df["gyro_deg"].to_numpy(float)
    cnt = df["gyro_counts"].to_numpy(float)
    ind = np.where(np.isfinite(deg), deg, cnt / k_ref if k_ref else np.nan)
    col = np.where(np.isfinite(deg), "gyro_deg", "gyro_counts")
    table = df["table_deg"].to_numpy(float)
    is_zs = (df["test"] == "zero_stability").to_numpy()
    r = deg_to_arcsec(ind - np.where(is_zs, 0.0, table))
    work = df.assign(_r=r, _col=col)
    work = work[np.isfinite(work["_r"]) & ~work["line"].isin(skip)]
    rot = work[work["test"].isin(ROTATION_TESTS)]
    drift_rate = allowed_drift_arcsec_per_s(protocol)
    deg_step = _deg_step(rot[rot["_col"] == "gyro_deg"]) if (rot["_col"] == "gyro_deg").any() \
        else 0.0
    ref = reference_rounds(rot, protocol, k_ref, deg_step)
    out = []
    keys = ["test", "rate_dps", "orientation"]
    groups = list(rot.groupby(keys, sort=False))
    rule = [_group_rule(g) for _, g in groups]
    # the session's false-alarm probability of the condition rule, shared by its groups
    alpha = SCREEN_ALPHA / max(line_groups or rule.count("line"), 1)
    for (key, g), how in zip(groups, rule):
        what = f"{key[0]} at {float(key[1]):g} °/s, axis {key[2]}"
        step = _resolution_arcsec(g, k_ref, deg_step)
        it = getattr(protocol, "angle_deviation", None)
        same = (it is not None and key[0] != "angle_deviation"
                and math.isclose(float(key[1]), float(it.rate_dps))
                and key[2] == it.orientation)
        if how == "round":
            # many series: each reading against the other series of its round (an error
            # proportional to the angle, e.g. of K, does not widen the small rounds' rule)
            found = _round_outliers(g, key[0], what, file, k_ref, step)
        elif how == "line":
            found = _line_outliers(g, key[0], what, file, k_ref, step, ref, drift_rate, alpha,
                                   same)
        else:
            found = _group_outliers(g, key[0], what, file, k_ref)
        out += found
        if key[0] in ROUND_MAY_GO and how == "line":
            ref74 = rot[(rot["test"] == "angle_deviation") & same
                        & np.isclose(rot["rate_dps"].to_numpy(float), float(key[1]))
                        & (rot["orientation"] == key[2])]
            out += reference_agreement(g, ref74, it, what, file, step, alpha,
                                       {f.line for f in found})
        elif key[0] in ROUND_MAY_GO + COMPARED and how == "median" and not found:
            out += _unjudged_statement(g, key[0], what, work, protocol, k_ref)
    for se, g in work[work["test"] == "zero_stability"].groupby("series", sort=False):
        what = f"zero_stability series {int(se)}"
        if len(g) < ZS_NEIGHBOUR_MIN:
            out += _group_outliers(g, "zero_stability", what, file, k_ref)
        else:
            out += _rest_outliers(g, what, file, k_ref, _resolution_arcsec(g, k_ref, deg_step),
                                  drift_rate)
    return out


def _unjudged_statement(g: pd.DataFrame, test: str, what: str, work: pd.DataFrame, protocol,
                        k_ref) -> list[Finding]:
    """The flagged statement of a 7.1, 7.6 or 7.7 condition the median rule alone judges
    (:func:`median_rule_limit`) or no rule (fewer than 3 readings, :func:`no_rule_statement`);
    none for a 7.6/7.7 condition whose item is not measured from the readings."""
    effect = None
    if test in COMPARED:
        effect = consistency_effect(work, protocol, test, k_ref)
        if effect is None:
            return []
    if len(g) >= 3:
        return [median_rule_limit(g, test, what, effect)]
    return [no_rule_statement(g, test, what, effect)]


def _passes_on_grid(r: np.ndarray, i: int, sign: float, grid: np.ndarray) -> np.ndarray:
    """Whether :func:`_outliers` finds nothing in ``r`` with ``sign · t`` added to reading
    ``i``, for every t of ``grid`` at once: row by row the same medians (np.median along the
    rows partitions each row as it does one array) and the same comparisons."""
    x = np.tile(r, (grid.size, 1))
    x[:, i] += sign * grid
    med = np.median(x, axis=1)
    dev = np.abs(x - med[:, None])
    thr = np.maximum(ROBUST_Z * 1.4826 * np.median(dev, axis=1), ANGLE_FLOOR_ARCSEC)
    return ~np.any(dev > thr[:, None], axis=1)


def median_rule_blind_arcsec(r_arcsec) -> np.ndarray:
    """For each reading of a group the median rule judges (:func:`_outliers`), the largest
    typo added to it alone, ″, with which the rule still finds nothing in the group: the
    supremum over both signs of the |t| for which ``r + t·e_i`` passes, searched over
    [0, hi] on a grid of 800 steps and refined by bisection at the last passing step. hi =
    2 · (spread + max(``ROBUST_Z`` · 1.4826 · spread, ``ANGLE_FLOOR_ARCSEC``)), spread the
    range of ``r``: beyond it the typo exceeds any threshold the others' spread allows.
    Where ``r`` itself breaks the rule, zeros (the rule found something). By hand for the
    example: +t on 0 leaves the median at 0.1 and the threshold at the 5″ floor, found when
    t − 0.1 > 5; −t on 0.1 leaves the median at −0.1, found when t − 0.2 > 5.

    >>> [round(float(x), 2) for x in median_rule_blind_arcsec([0.0, 0.1, -0.1])]
    [5.1, 5.2, 5.2]
    """
    r = np.asarray(r_arcsec, float)
    if r.size < 3 or _outliers(r)[0].size:
        return np.zeros(r.size)
    spread = float(r.max() - r.min())
    hi = 2.0 * (spread + max(ROBUST_Z * 1.4826 * spread, ANGLE_FLOOR_ARCSEC))
    grid = np.linspace(0.0, hi, 801)
    out = np.zeros(r.size)
    for i in range(r.size):
        for sign in (1.0, -1.0):
            def passes(t: float) -> bool:
                x = r.copy()
                x[i] += sign * t
                return _outliers(x)[0].size == 0
            k = int(np.flatnonzero(_passes_on_grid(r, i, sign, grid))[-1])
            if k == grid.size - 1:
                best = float(grid[-1])
            else:
                lo_t, hi_t = float(grid[k]), float(grid[k + 1])
                for _ in range(40):
                    mid = 0.5 * (lo_t + hi_t)
                    lo_t, hi_t = (mid, hi_t) if passes(mid) else (lo_t, mid)
                best = lo_t
            out[i] = max(out[i], best)
    return out


def ceil_sig(x: float, digits: int = 2) -> str:
    """``x`` > 0 to ``digits`` significant digits, rounded up (a stated bound never below
    what it bounds); "0" for x ≤ 0.

    >>> ceil_sig(4.07), ceil_sig(0.000398), ceil_sig(11.3), ceil_sig(5.351, 3)
    ('4.1', '0.00040', '12', '5.36')
    """
    if not x > 0:
        return "0"
    e = math.floor(math.log10(x)) - (digits - 1)
    v = math.ceil(round(x * 10.0 ** -e, 9)) * 10.0 ** e
    return f"{v:.{max(0, -e)}f}"


class ScaleFactorEffect:
    """What a typo in one 7.1 reading does (the default ``effect`` of :func:`median_rule_limit`
    and :func:`no_rule_statement`): it moves K_i = C_i/θ_i by t/θ_i, K (the mean of the m
    K_i) by t/(θ_i · m) and K_l (their range) by up to t/θ_i, and through K every item
    computed with it (E at 360° by 360° · ΔK/K)."""

    def bounded(self, g: pd.DataFrame, t_arcsec: np.ndarray) -> tuple[str, str]:
        """The effect of a typo of up to ``t_arcsec`` (one per reading of ``g``): (the
        sentence, the rule)."""
        theta = np.abs(g["table_deg"].to_numpy(float))
        rel = t_arcsec / np.where(theta > 0, deg_to_arcsec(theta), np.inf)
        return (f"it would move K by up to {float(np.max(rel)) / len(g) * 1e6:.2g} ppm and K_l "
                f"by up to {float(np.max(rel)) * 100.0:.2g} %, and E and every item computed "
                "with K with them", _MEDIAN_LIMIT_RULE)

    def per_arcsec(self, g: pd.DataFrame) -> tuple[int, str, str]:
        """The effect of each ″ of typo at the reading of ``g`` where it is largest (the
        smallest stop): (its position in ``g``, the sentence, the rule)."""
        theta = np.abs(g["table_deg"].to_numpy(float))
        rel = 1.0 / np.where(theta > 0, deg_to_arcsec(theta), np.nan)
        i = int(np.nanargmax(rel)) if np.isfinite(rel).any() else 0
        line = int(g["line"].iloc[i])
        return i, (f"each ″ of it moves K by up to {float(rel[i]) / len(g) * 1e6:.2g} ppm and "
                   f"K_l by up to {float(rel[i]) * 100.0:.2g} % (line {line}, {theta[i]:g}°), "
                   "and E and every item computed with K with them"), _NO_RULE


class ConsistencyEffect:
    """What a typo in one 7.6 or 7.7 reading does to C_v or C_g, from the item's own
    formula on the readings as read (:func:`consistency_effect`): the typo u moves the mean
    E of its position at its condition by u/n (n the series that read that round there),
    E_v (the signed extreme of the condition's points, 7.4) with it, and C = (max E_v −
    min E_v) / the reference angle (the reference's indicated angle at its largest
    position, moved too where the typo is there)."""

    def __init__(self, item, test: str):
        pts = item.tables["points"]
        self.col = "rate_dps" if test == "rate_consistency" else "orientation"
        self.symbol, self.unit = (("C_v", "ppm") if test == "rate_consistency" else ("C_g", "%"))
        self.scale = 1e6 if test == "rate_consistency" else 100.0
        self.clause = CLAUSES[test]
        self.conds = list(item.table[self.col])
        self.ref = int(np.flatnonzero(item.table["reference"].to_numpy(bool))[0])
        self.src = list(item.table["source_test"])
        key = pts["position_deg"].round(6)
        self.positions = sorted(set(key))
        shape = (len(self.conds), len(self.positions))
        self.e, self.n, self.cell = np.full(shape, np.nan), np.ones(shape), {}
        for row, x in zip(pts.itertuples(index=False), key):
            a, b = self.conds.index(getattr(row, self.col)), self.positions.index(x)
            self.e[a, b], self.n[a, b] = row.E_arcsec, row.n_series
            self.cell[(a, row.round)] = b
        self.angle = float(item.details["reference_angle_arcsec"])
        self.ref_pos = self.positions.index(max(self.positions))
        self.test = test

    def _cell(self, row) -> tuple[int, int] | None:
        """The (condition, position) of one reading of the screen's group, None where the
        item does not use it (another fixed condition, a position not compared)."""
        v = float(row["rate_dps"]) if self.col == "rate_dps" else row["orientation"]
        a = next((j for j, c in enumerate(self.conds) if (math.isclose(float(c), v)
                  if self.col == "rate_dps" else c == v) and self.src[j] == self.test), None)
        b = None if a is None else self.cell.get((a, row["round"]))
        return None if b is None or not np.isfinite(self.e[a, b]) else (a, b)

    def shift(self, a: int, b: int, u: np.ndarray) -> np.ndarray:
        """|ΔC| (in the item's unit) for typos ``u`` ″ on a reading of cell (a, b)."""
        e_v = np.array([float(x[np.nanargmax(np.abs(x))]) for x in self.e])
        row = np.where(np.isfinite(self.e[a]), self.e[a], 0.0)[None, :].repeat(u.size, 0)
        row[:, b] += u / self.n[a, b]
        ev = row[np.arange(u.size), np.argmax(np.abs(row), axis=1)]
        others = np.delete(e_v, a)
        spread = np.maximum(ev, others.max()) - np.minimum(ev, others.min())
        ang = self.angle + (u / self.n[a, b] if (a, b) == (self.ref, self.ref_pos) else 0.0)
        return np.abs(spread / ang - (e_v.max() - e_v.min()) / self.angle) * self.scale

    def bounded(self, g: pd.DataFrame, t_arcsec: np.ndarray) -> tuple[str, str]:
        """As :meth:`ScaleFactorEffect.bounded`: the largest |ΔC| over typos |u| ≤ t of each
        reading, on a grid of 2 000 steps plus the most a step can hide (slope 1/n)."""
        worst, e_pos = 0.0, 0.0
        for k in range(len(g)):
            cell = self._cell(g.iloc[k])
            if cell is None or not t_arcsec[k] > 0:
                continue
            u = np.linspace(-t_arcsec[k], t_arcsec[k], 2001)
            step = float(u[1] - u[0]) / self.n[cell] / self.angle * self.scale
            worst = max(worst, float(self.shift(*cell, u).max()) + step)
            e_pos = max(e_pos, float(t_arcsec[k]) / self.n[cell])
        return (f"it would move E at its position by up to {ceil_sig(e_pos, 3)}″ and "
                f"{self.symbol} ({self.clause}) by up to {ceil_sig(worst)} {self.unit}",
                _consistency_rule(self))

    def per_arcsec(self, g: pd.DataFrame) -> tuple[int, str, str]:
        """As :meth:`ScaleFactorEffect.per_arcsec`: 1/(n · reference angle) a ″, and at most
        the condition's own range more where the typo changes the sign of its extreme."""
        best = (0, 0.0, 0.0)
        for k in range(len(g)):
            cell = self._cell(g.iloc[k])
            if cell is not None:
                x = self.e[cell[0]]
                slope = self.scale / (self.n[cell] * self.angle)
                jump = float(np.nanmax(x) - np.nanmin(x)) / self.angle * self.scale
                best = max(best, (k, slope, jump), key=lambda b: (b[1], b[2]))
        k, slope, jump = best
        return k, (f"each ″ of it moves {self.symbol} ({self.clause}) by up to "
                   f"{ceil_sig(slope)} {self.unit} (line {int(g['line'].iloc[k])}), and by up "
                   f"to {ceil_sig(jump)} "
                   f"{self.unit} more where it changes the sign of the condition's extreme E"),\
            _consistency_rule(self, per_arcsec=True)


def _consistency_rule(eff: ConsistencyEffect, per_arcsec: bool = False) -> str:
    """The rule text of a 7.6/7.7 ``readings-not-judged`` finding."""
    head = (f"{eff.clause} condition of fewer than {LINE_MIN} readings: the median rule "
            f"(|r − median| > max({ROBUST_Z:g} · 1.4826 · MAD, {ANGLE_FLOOR_ARCSEC:g}″)); "
            "stated: the largest typo t in one reading with which that rule finds nothing "
            "(searched on the readings as read), and the largest change of ")
    if per_arcsec:
        head = (f"{eff.clause} condition of fewer than 3 readings: no rule judges them; "
                "stated: per ″ of typo, the change of ")
    return head + (f"{eff.symbol} = (max E − min E) / reference angle it makes, E of its "
                   "position moved by t / n (n series), each E the signed extreme of its "
                   "condition's points (7.4), K of 7.1")


def consistency_effect(df: pd.DataFrame, protocol, test: str, k_ref) -> ConsistencyEffect | None:
    """The 7.6 (``rate_consistency``) or 7.7 item computed on the readings ``df`` as read,
    as :mod:`items` computes it (K of 7.1, else ``k_ref``), for :class:`ConsistencyEffect`;
    None where the item is not measured from them (nothing to state an effect on)."""
    from gonio.specs.ogam_draft import items

    k = k_ref
    try:
        sf = items.scale_factor(df)
        k = sf.value if sf.measured else k_ref
    except GonioError:
        pass
    func = items.rate_consistency if test == "rate_consistency" else items.pointing_consistency
    try:
        item = func(df, k, reference_rate_dps=float(getattr(protocol, "rate_reference_dps", 60.0)),
                    reference_orientation=getattr(protocol, "pointing_reference", "up"))
    except GonioError:
        return None
    if not item.measured or not math.isfinite(item.value or math.nan):
        return None
    return ConsistencyEffect(item, test)


def median_rule_limit(g: pd.DataFrame, test: str, what: str, effect=None) -> Finding:
    """A flagged finding for readings judged only by the median rule (fewer than
    ``LINE_MIN`` readings, e.g. 7.1 at three stops, 7.6 or 7.7 at four positions): the size
    of a typo in one of them the rule could not have seen (:func:`median_rule_blind_arcsec`,
    the largest over the readings) and what it would do to the item: ``effect``
    (:class:`ScaleFactorEffect`, the default, for 7.1: K and K_l; :class:`ConsistencyEffect`
    for 7.6 and 7.7: C_v or C_g).

    Why. The median rule's floor (``ANGLE_FLOOR_ARCSEC``) sits far above a healthy
    reading's spread, so a typo below it passes, and in 7.1 a typo in one reading is
    indistinguishable from a nonlinearity at that stop: it moves K_i = C_i/θ_i by
    t/θ_i, K (the mean of the m K_i) by t/(θ_i · m) and K_l (their range) by up to
    t/θ_i, and through K every item computed with it (E at 360° by 360° · ΔK/K: a 3″
    typo at 120° of three stops moves E by 3″); in 7.6 and 7.7 it moves the E of its
    condition, so C_v or C_g (a 4″ typo at 90° of 30 °/s in the small programme: C_v
    0.39 → 3.5 ppm). Where 7.4 reads 7.1's stops at its rate and axis in several series,
    :func:`reference_agreement` judges them (the condition rule's groups); a median-rule
    group gets this statement instead (docs/draft-readings.md, "7.1 without a repeated
    reference", "7.6 and 7.7 judged by the median rule")."""
    effect = effect or ScaleFactorEffect()
    r = g["_r"].to_numpy(float)
    theta = np.abs(g["table_deg"].to_numpy(float))
    lines = g["line"].astype(int).tolist()
    t = median_rule_blind_arcsec(r)
    i = int(np.argmax(t))
    tail, rule = effect.bounded(g, t)
    return Finding(
        "readings-not-judged",
        f"{what}: readings at lines {', '.join(map(str, lines))} judged only by the median "
        f"rule (fewer than {LINE_MIN} readings; its floor {ANGLE_FLOOR_ARCSEC:g}″, widened "
        f"by the readings' own spread): a typo in one of them of up to "
        f"{math.ceil(float(t[i]) * 100.0) / 100.0:.2f}″ (line {lines[i]}, {theta[i]:g}°) "
        f"would not have been seen; {tail}", "flagged",
        # no path: a statement on every file of such a programme, so outputs stay the same
        # wherever the readings lie (results.json's inputs name the readings file)
        file=None, line=lines[i], column=str(g["_col"].iloc[i]), test=test,
        clause=CLAUSES[test], rule=rule)


_MEDIAN_LIMIT_RULE = (
    f"7.1 of fewer than {LINE_MIN} readings: the median rule (|r − median| > max("
    f"{ROBUST_Z:g} · 1.4826 · MAD, {ANGLE_FLOOR_ARCSEC:g}″)); stated: the largest typo t in one "
    "reading with which that rule finds nothing (searched on the readings as read), and "
    "t / θ / m (K) and t / θ (K_l) at its stop")


def no_rule_statement(g: pd.DataFrame, test: str, what: str, effect=None) -> Finding:
    """A flagged ``readings-not-judged`` finding for readings no screening rule judges:
    fewer than 3 (a programme of two stops, or three with one missing or set aside by
    another rule). It names them and states what a typo t″ in one of them does, per ″
    (``effect``, as :func:`median_rule_limit`): for 7.1 at the smallest stop K by
    t/(θ · m) (ppm), K_l by up to t/θ (%); for 7.6 and 7.7 C_v or C_g.

    Why. The median rule (:func:`_outliers`) cannot judge two readings: each departs from
    their median by half their difference, which the MAD (the same half) times
    ``ROBUST_Z`` · 1.4826 always exceeds, so it is not run (:func:`_group_outliers`), and
    no other rule sees such a reading; the size of a typo it would miss is unbounded, so
    the finding states the effect per ″ instead of a size (docs/draft-readings.md, "7.1
    judged by no rule")."""
    effect = effect or ScaleFactorEffect()
    lines = g["line"].astype(int).tolist()
    m = len(lines)
    i, tail, rule = effect.per_arcsec(g)
    word = "reading" if m == 1 else "readings"
    return Finding(
        "readings-not-judged",
        f"{what}: {word} at {'line' if m == 1 else 'lines'} {', '.join(map(str, lines))} "
        f"judged by no rule ({m} {word}; the median rule needs 3): a typo of any size in "
        f"one of them would not have been seen; {tail}", "flagged",
        # no path: a statement on every file of such a programme (median_rule_limit)
        file=None, line=lines[i], column=str(g["_col"].iloc[i]), test=test,
        clause=CLAUSES[test], rule=rule)


_NO_RULE = (
    "7.1 of fewer than 3 readings: no rule judges them (the median rule cannot: of two "
    "readings each departs from their median by their MAD); stated: the readings' lines and "
    "1 / (θ · m) (K) and 1 / θ (K_l) a ″ of typo at the smallest stop")


#: The fewest 7.4 series at 7.1's stops that :func:`reference_agreement` judges 7.1 against
#: (two readings of a stop give its repetition one degree of freedom).
AGREEMENT_SERIES_MIN: int = 2


def reference_agreement(g: pd.DataFrame, ref: pd.DataFrame, it, what: str, file,
                        step: float, alpha: float, gone: set) -> list[Finding]:
    """7.1 judged by the condition rule (at least ``LINE_MIN`` readings) where 7.4 is read in
    fewer than ``PER_ROUND_MIN`` series (no repeated-reference prior,
    :func:`repeated_reference_scale`): its readings all judged at once against the
    7.4 readings of the same stops, or a finding naming the readings judged only against
    one another.

    Why. Without the prior, 7.1's six readings are judged against each other's line
    (:func:`line_departures`, ν = 3, c ≈ 19): one departing reading is found, but two or
    more each widen the line of the others and hide one another (2″ at 60° and 180° on the
    RLG: no finding, K_l 0.00098 % and E 2.6″ certified where the clean file gives
    ≤ 0.00033 % and 0.2″), and once ``LINE_MIN`` − 1 are left the rest are not judged at all.

    The rule. ``ref`` holds the 7.4 readings at 7.1's rate and axis (empty where 7.4 is
    at another); every 7.1 stop must be a 7.4 round (within its position tolerance) read in
    at least ``AGREEMENT_SERIES_MIN`` series. Then d = r − the round's mean cancels what a
    position repeats (table error, nonlinearity; :func:`repeated_reference_scale`), and the
    7.1 readings the condition rule kept, less their least-squares line in θ (a K change or
    drift between the two tests), have residual variance s² = RSS / (m − 2); under no typo it
    estimates σ_d² = s_rep² (1 + 1/n) (n the fewest readings of a round, s_rep from 7.4's
    repetitions with ν₀ = N − R), so F = s² / σ_d² follows Fisher's F(m − 2, ν₀) (never
    below one step of resolution: σ_d² ≥ step² / 6, two readings' quantisation). F beyond
    its 1 − ``alpha`` quantile refuses the calibration naming the readings, largest
    departure first: several departing readings that the line rule cannot single out, and
    that do not hide one another here (each adds to s²). A typo pattern on a line in θ
    passes as a change of K between the tests. Where no such reference exists (7.4 in one
    series, at other stops, rate or axis), a flagged finding names the readings judged
    only against one another (docs/draft-readings.md, "7.1 without a repeated reference").
    """
    if it is None or not len(g):
        return []
    keep = g[~g["line"].isin(gone)]
    x = keep["table_deg"].to_numpy(float)
    per = ref.groupby("round", sort=True) if len(ref) else None
    ang = per["table_deg"].median().to_numpy(float) if per is not None else np.array([])
    cnt = per.size().to_numpy() if per is not None else np.array([], int)
    j = (np.abs(x[:, None] - ang[None, :]).argmin(axis=1) if ang.size
         else np.zeros(x.size, int))
    ok = (ang.size > 0 and x.size >= 3 and bool(np.all(np.abs(ang[j] - x)
                                                       <= it.position_tolerance_deg))
          and bool(np.all(cnt[j] >= AGREEMENT_SERIES_MIN)))
    if ok and int(cnt.min()) >= PER_ROUND_MIN:
        return []                 # the repeated-reference prior judged them (line_departures)
    lines = keep["line"].astype(int).tolist()
    if not ok:
        return [Finding(
            "readings-not-judged",
            f"{what}: readings at lines {', '.join(map(str, lines))} judged only against one "
            f"another: 7.4 does not read each of these stops at this rate and axis in "
            f"{AGREEMENT_SERIES_MIN} or more series, so no repeated reference says what each "
            f"position reads; the rule can single out one departing reading, two or more "
            f"hide one another and would be read as nonlinearity (K_l) and in E", "flagged",
            file=file, line=lines[0] if lines else None, column="gyro_counts",
            test="scale_factor", clause=CLAUSES["scale_factor"], rule=_AGREEMENT_RULE)]
    s_rep, nu0, n_min = repeated_reference_scale(ref, step)
    mean = per["_r"].mean().to_numpy(float)
    d = keep["_r"].to_numpy(float) - mean[j]
    X = _design(x, False)
    coef, *_ = np.linalg.lstsq(X, d, rcond=None)
    e = d - X @ coef
    dof = x.size - X.shape[1]
    var0 = max(s_rep * s_rep * (1.0 + 1.0 / max(n_min, 1)), step * step / 6.0)
    if nu0 < 1 or var0 <= 0.0:
        return []
    ratio = float(e @ e) / dof / var0
    crit = float(fisher_f.isf(alpha, dof, nu0))
    if not ratio > crit:
        return []
    # named by each reading's departure from 7.4 at its stop (the line's residuals spread a
    # typo over its clean neighbours; a median of d is a typo where half the readings are)
    dd = d
    order = np.argsort(-np.abs(dd), kind="stable")
    worst = ", ".join(f"{lines[i]} ({dd[i]:+.3g}″)" for i in order)
    # the lines first: a long refusal is cut on the command line's one line
    return [Finding(
        "readings-disagree-with-reference",
        f"{what}: the readings disagree with 7.4's repetitions of the same stops, more than "
        f"one departing (they hide one another from the condition rule): lines {worst} "
        f"(departure from 7.4's mean at the stop, largest first); the "
        f"calibration is refused (check these readings); scatter "
        f"{math.sqrt(float(e @ e) / dof):.3g}″ about their line where 7.4 allows "
        f"{math.sqrt(var0):.3g}″ (F = {ratio:.3g} > {crit:.3g}, ν = {dof}, {nu0})",
        "refused", file=file, line=lines[int(order[0])],
        column=str(keep["_col"].iloc[int(order[0])]), test="scale_factor",
        clause=CLAUSES["scale_factor"], rule=_AGREEMENT_RULE)]


_AGREEMENT_RULE = (
    "7.1 with 7.4 in fewer than 5 series: d = r − the 7.4 round's mean at the same stop "
    f"(7.4 read in at least {AGREEMENT_SERIES_MIN} series there), F = Σ (d − its least-squares "
    "line in θ)² / (m − 2) / (s_rep² (1 + 1/n)) against F(m − 2, N − R) at "
    "α (the group's share of the session's 2 %); without such a reference the readings are "
    "named as judged only against one another")


#: A 7.3 series of at least this many readings is screened against each reading's neighbours.
ZS_NEIGHBOUR_MIN: int = 4

#: Robust z of the 7.3 rule (:func:`_rest_spread`), whose threshold is also never below
#: ``DRIFT_Z`` times the residual the draft's zero-stability bound allows between
#: neighbours (0.005 °/h × 300 s / 2 = 0.75″): a clean rest's residuals reached 10.6 times
#: their MAD scale where the bias wandered (docs/draft-readings.md, "Screening").
REST_Z: float = 5.0

_REST_RULE = (f"|e − median(e)| > max({REST_Z:g} · 1.4826 · MAD(e), {DRIFT_Z:g} · the "
              "zero-stability bound × spacing / 2, "
              f"{SPREAD_FLOOR_STEPS:g} steps of resolution), "
              "e = indicated angle − the line through its two neighbours in time (the two "
              "nearest at the ends), the reading without which the others' e are smallest "
              "against the others' median and threshold; then again on the others")


def rest_residuals(t_s: np.ndarray, r_arcsec: np.ndarray) -> np.ndarray:
    """Each rest reading less the line through its neighbours in time (through the two
    nearest, extrapolated, for the first and last), ″. A drift, linear or slowly curving,
    leaves them near zero; a typo of d moves its own residual by d and its neighbours' by
    about d/2 (2d at an end extrapolated through it). Where the spacing is uneven (a
    reading set aside leaves a gap) and at the ends a residual is divided by √(its
    prediction's random-walk variance / an inner one's on an even grid of the median
    spacing): 1 inside an even grid, 2 at its ends (x0 − 2x1 + x2: four times the variance
    of an inner residual, for a random walk as for white noise).

    ``t_s`` strictly increasing, at least 3 readings.

    >>> e = rest_residuals(np.array([0., 300, 600, 900, 1200]), np.array([0., 1, 2, 8, 4]))
    >>> [round(float(x), 3) for x in e]
    [0.0, 0.0, -2.5, 5.0, -5.0]
    """
    t, x = np.asarray(t_s, float), np.asarray(r_arcsec, float)
    n = t.size
    e, f = np.empty(n), np.empty(n)
    a, b = t[1:-1] - t[:-2], t[2:] - t[1:-1]
    e[1:-1] = x[1:-1] - (x[:-2] * b + x[2:] * a) / (a + b)
    # an angle random walk's variance of the residual, per unit rate: ab/(a+b) inside,
    # a + a²/b at an end (a the gap to the nearest, b between the two used)
    h = float(np.median(np.diff(t)))
    f[1:-1] = (a * b / (a + b)) / (h / 2.0)
    for i, j, k in ((0, 1, 2), (n - 1, n - 2, n - 3)):
        e[i] = x[i] - (x[j] + (x[j] - x[k]) * (t[i] - t[j]) / (t[j] - t[k]))
        ga, gb = abs(t[i] - t[j]), abs(t[j] - t[k])
        f[i] = (ga + ga * ga / gb) / (h / 2.0)
    # relative to an inner residual on an even grid of the series' median spacing (1 there;
    # 4 at an end, whose extrapolation x0 − 2x1 + x2 has four times the variance for a random
    # walk and for white noise alike, so an end is judged on the inner readings' scale): a
    # gap a reading set aside leaves widens its neighbours' predictions
    return e / np.sqrt(f)


def _rest_spread(t: np.ndarray, x: np.ndarray, floor_arcsec: float
                 ) -> tuple[np.ndarray, float, float]:
    """The residuals (:func:`rest_residuals`), their median and the rule's threshold:
    ``REST_Z`` · 1.4826 · MAD of the residuals, never below ``floor_arcsec`` (steps of the
    resolution, or the drift the zero-stability bound allows: :func:`_rest_outliers`)."""
    e = rest_residuals(t, x)
    med = float(np.median(e))
    return e, med, max(REST_Z * 1.4826 * float(np.median(np.abs(e - med))),
                       float(floor_arcsec))


def _off_line(t: np.ndarray, x: np.ndarray, tj: float, xj: float
              ) -> tuple[float, float, float]:
    """A reading at ``tj`` less the line through its neighbours among ``t`` (the two
    nearest, extrapolated, beyond them), ″, the same scaled as :func:`rest_residuals`
    scales, and how much wider its gaps make the prediction than the even grid's (√ of the
    variance ratio: 1 on the grid; a reading beside one set aside, more)."""
    h = float(np.median(np.diff(t)))
    k = int(np.searchsorted(t, tj))
    if 0 < k < t.size:
        i, j = k - 1, k
        a, b = tj - t[i], t[j] - tj
        d = xj - (x[i] * b + x[j] * a) / (a + b)
        f = (a * b / (a + b)) / (h / 2.0)
        return d, d / math.sqrt(f), math.sqrt(max(f, 1.0))
    i, j = (0, 1) if k == 0 else (t.size - 1, t.size - 2)
    a, b = abs(tj - t[i]), abs(t[i] - t[j])
    d = xj - (x[i] + (x[i] - x[j]) * (tj - t[i]) / (t[i] - t[j]))
    f = (a + a * a / b) / (h / 2.0)
    return d, d / math.sqrt(f), math.sqrt(max(f / 4.0, 1.0))


def _rest_outliers(g: pd.DataFrame, what: str, file, k_ref, step: float,
                   drift_arcsec_per_s: float = 0.0) -> list[Finding]:
    """7.3 readings of one series off the path their neighbours draw (module docstring).

    The candidate is the reading without which the others' residuals are smallest (a typo
    also moves its neighbours' residuals and their MAD, and an end's extrapolation doubles
    its neighbour's typo); it is set aside when it departs from the line its neighbours
    among the others draw by more than the others' threshold, and the rule runs again on
    the others.
    """
    g = g.sort_values("time_s", kind="stable")
    t, x = g["time_s"].to_numpy(float), g["_r"].to_numpy(float)
    if np.any(np.diff(t) <= 0):              # repeated times: no neighbours to draw a line
        return _group_outliers(g, "zero_stability", what, file, k_ref)
    idx = np.arange(len(g))
    # the bias change the draft's A.4.3 bound allows moves an inner residual by about
    # Δb · h / 2 (h the spacing): DRIFT_Z such moves are the instrument's, not a typo
    drift = DRIFT_Z * drift_arcsec_per_s * float(np.median(np.diff(t))) / 2.0
    out = []
    while idx.size >= ZS_NEIGHBOUR_MIN:
        best = None
        for j in range(idx.size):
            rest = np.delete(idx, j)
            er, mr, tr = _rest_spread(t[rest], x[rest], max(SPREAD_FLOOR_STEPS * step, drift))
            score = float(np.max(np.abs(er - mr)))
            if best is None or score < best[0]:
                best = (score, j, rest, mr, tr)
        _, j, rest, med, thr = best
        raw, dev, wider = _off_line(t[rest], x[rest], t[idx[j]], x[idx[j]])
        # a bias change moves a residual across a gap (a reading set aside) more: the
        # allowed drift grows with the prediction's spread
        thr = max(thr, drift * wider)
        if not abs(dev - med) > thr:
            break
        row = g.iloc[idx[j]]
        idx = rest
        out.append(_outlier_finding(
            row, f"indicated angle {row['_r']:.4g}″ departs from the line through its "
            f"neighbours in time by {raw:.4g}″ ({dev:.4g}″ on an even grid's scale; the other "
            f"readings' residuals: median {med:.3g}″, threshold {thr:.3g}″)",
            what, file, "zero_stability", _REST_RULE, k_ref))
    return sorted(out, key=lambda f: f.line)


def _outlier_finding(row, message: str, what: str, file, test: str, rule: str,
                     k_ref) -> Finding:
    """One set-aside reading of ``what``'s round in ``row``: the finding names its file, line
    and column, and the reference K used where the column is the gyro's counts."""
    col = str(row["_col"])
    by = (f" (K_ref = {k_ref:.9g} counts/° from the other readings)"
          if col == "gyro_counts" else "")
    return Finding(
        "indicated-angle-outlier", f"{what} round {int(row['round'])}: {message}{by}",
        "set_aside", file=file, line=int(row["line"]), column=col, test=test,
        clause=CLAUSES[test], rule=rule)


def _group_outliers(g: pd.DataFrame, test: str, what: str, file, k_ref) -> list[Finding]:
    """The median rule of a group too small for its own spread (fewer than
    ``LINE_MIN`` readings of a condition read once per position; a 7.3 series of fewer than
    ``ZS_NEIGHBOUR_MIN``, or with repeated times)."""
    if len(g) < 3:
        return []
    r = g["_r"].to_numpy(float)
    idx, med, thr = _outliers(r)
    return _departures(g, [(i, f"the condition's median {med:.3g}″", r[i] - med, thr, "")
                           for i in idx], what, file, test, _ANGLE_RULE, k_ref)


def _incomplete(df: pd.DataFrame, protocol, file, present, df_all: pd.DataFrame
                ) -> list[Finding]:
    """Rounds missing from every series, conditions of the programme absent (flagged), for
    the tests ``present`` in the file; a round absent from one series of the file
    ``df_all`` (not one set aside: that has its own finding)."""
    out = []
    for test in ROTATION_TESTS:
        rows = df[df["test"] == test]
        if test not in present:
            continue
        own = items_of(protocol, test)
        if test in ("rate_consistency", "pointing_consistency"):
            own = own[:-1] if own and own[-1] is protocol.angle_deviation else own
        for it in own:
            g = rows[np.isclose(rows["rate_dps"].to_numpy(float), it.rate_dps)
                     & (rows["orientation"] == it.orientation)]
            cond = f"{it.rate_dps:g} °/s, axis {it.orientation}"
            if not len(g):
                gone = (f"; the item is not stated ({CLAUSES[test]} compares E at every "
                        "condition of the programme)" if test in COMPARED else "")
                out.append(Finding("incomplete-programme",
                                   f"{test} ({CLAUSES[test]}): the programme's condition {cond} "
                                   f"has no reading{gone}", "flagged", file=file, test=test,
                                   clause=CLAUSES[test], rule="every programme condition read"))
                continue
            have = set(g["round"].to_numpy().astype(np.int64).tolist())
            missing = [i for i in range(1, len(it.rounds) + 1) if i not in have]
            whole = df_all[(df_all["test"] == test)
                           & np.isclose(df_all["rate_dps"].to_numpy(float), it.rate_dps)
                           & (df_all["orientation"] == it.orientation)
                           & df_all["series"].between(1, it.series)]
            out += _missing_in_series(whole, test, cond, file)
            for i in missing:
                r = it.rounds[i - 1]
                rests = (f"the item rests on {len(it.rounds) - len(missing)} of the "
                         f"programme's {len(it.rounds)} rounds" if test not in COMPARED else
                         f"the item is not stated ({CLAUSES[test]} compares every condition "
                         "over the same positions)")
                if test == "scale_factor":     # K_l: items.nonlinearity_missing_rounds
                    rests = (f"K rests on {len(it.rounds) - len(missing)} of the programme's "
                             f"{len(it.rounds)} rounds (its table bound over all "
                             f"{len(it.rounds)}); K_l is not stated (7.2 is the range over "
                             "every round of the programme)")
                out.append(Finding(
                    "incomplete-programme",
                    f"{test} ({CLAUSES[test]}) at {cond}: round {i} ({r.stop_deg - r.start_deg:g}°)"
                    f" is missing from every series; {rests}",
                    "flagged", file=file, column="round", test=test, clause=CLAUSES[test],
                    rule="every programme round read in at least one series"))
    return out


#: A 7.3 reading more than this fraction of ``interval_s`` off the protocol's schedule
#: (round n at the first reading's time + (n − 1) · interval_s) is flagged: a reading taken
#: by hand a few seconds late is on schedule, one a minute late of 5 min is not.
ZS_SCHEDULE_TOLERANCE: float = 0.1


def zero_stability_schedule(df_all: pd.DataFrame, protocol, file) -> list[Finding]:
    """7.3 readings against the protocol's schedule (``readings`` readings ``interval_s``
    apart), per series of the file: a round missing (the count read of the programme's, B_s
    over the readings read and T from the first to the last) and a reading off its time
    (round n at t_1 + (n − 1) · interval_s within ``ZS_SCHEDULE_TOLERANCE`` · interval_s,
    t_1 the median over the series of time_s − (n − 1) · interval_s, so that one late
    reading, the first included, is the one flagged; used as read), flagged."""
    z = getattr(protocol, "zero_stability", None)
    rows = df_all[df_all["test"] == "zero_stability"]
    if z is None or not len(rows):
        return []
    out = []
    tol = ZS_SCHEDULE_TOLERANCE * z.interval_s
    for se, g in rows.groupby("series", sort=True):
        g = g.sort_values("time_s", kind="stable")
        rnd = g["round"].to_numpy().astype(np.int64)
        t = g["time_s"].to_numpy(float)
        missing = [i for i in range(1, z.readings + 1) if i not in set(rnd.tolist())]
        what = f"zero_stability (7.3) series {int(se)}"
        span = float(np.nanmax(t) - np.nanmin(t)) if t.size else 0.0
        if missing:
            out.append(Finding(
                "incomplete-programme",
                f"{what}: {len(set(rnd.tolist()) & set(range(1, z.readings + 1)))} of the "
                f"protocol's {z.readings} readings {z.interval_s:g} s apart; round(s) "
                f"{', '.join(map(str, missing))} missing; B_s rests on the {len(g)} readings "
                f"read, T = {span:g} s from the first to the last", "flagged", file=file,
                column="round", test="zero_stability", clause="7.3",
                rule=f"{z.readings} readings, rounds 1…{z.readings}"))
        if not t.size or not np.isfinite(t).all():
            continue
        start = float(np.median(t - (rnd - 1) * z.interval_s))   # the schedule's round 1
        want = start + (rnd - 1) * z.interval_s
        for i in np.flatnonzero(np.abs(t - want) > tol):
            out.append(Finding(
                "off-schedule-reading",
                f"{what} round {int(rnd[i])}: read at {t[i]:g} s, the schedule's {want[i]:g} s "
                f"(round 1 at {start:g} s, {z.interval_s:g} s apart); used as read, "
                f"T = {span:g} s from the first to the last reading", "flagged",
                file=file, line=int(g["line"].iloc[i]), column="time_s",
                test="zero_stability", clause="7.3",
                rule=f"|time_s − schedule| ≤ {ZS_SCHEDULE_TOLERANCE:g} · interval_s"))
    return out


def _missing_in_series(g: pd.DataFrame, test: str, cond: str, file) -> list[Finding]:
    """A round read in some series of a condition and not in another series that has
    readings (a reading lost or mislabelled): flagged, one finding per gap — the round's
    mean is over the series present, and the certificate says which one is short."""
    have = {(int(se), int(rd)) for se, rd in zip(g["series"], g["round"])}
    rounds = sorted({rd for _, rd in have})
    out = []
    for se in sorted({se for se, _ in have}):
        for rd in rounds:
            if (se, rd) not in have:
                out.append(Finding(
                    "incomplete-programme",
                    f"{test} ({CLAUSES[test]}) at {cond}: series {se} has no reading of round "
                    f"{rd} (the round's mean is over the other series)", "flagged", file=file,
                    column="round", test=test, clause=CLAUSES[test],
                    rule="every round read in every series present"))
    return out


#: The tilt estimate's clause as the findings name it (the test supports Annex A.1's bound).
TILT_ESTIMATE_CLAUSE = "A.1"


def tilt_estimate_rule(df: pd.DataFrame, protocol, file, k_ref, skip: set) -> list[Finding]:
    """The screening rule of the in-situ tilt estimate's rows (``tilt_estimate``, one rest
    per position; the estimate supports Annex A.1's tilt bound and A.4.2): each position's
    reading against what the other positions say, by the condition rule of readings taken
    once per position (:func:`line_departures`, its threshold and its small-sample factor
    where it has one; no second threshold rule).

    A rest at θ accumulates, over its dwell ``time_s``, the bias, the Earth rate along the
    table axis and the tilt's first harmonic Ω_⊥ sin ψ cos(θ + α − β)
    (:mod:`gonio.specs.ogam_draft.tilt_estimate`), plus a bias drift over the test (a line
    in θ where the positions are read in order of θ; taken in opposite pairs, as the
    programme takes them, the drift is a line within each half-turn, which the fit does not
    follow and the drift floor below allows for). So d_j = the reading's indicated angle
    (``gyro_deg``, else ``gyro_counts`` / K_ref), ″, scaled to the median dwell
    (d_j · median(time_s) / time_j), is judged against the least-squares fit of the others
    in θ (the line with cos θ, sin θ where ``HARMONIC_MIN`` others allow: the protocol's
    12 positions; fewer positions are judged against the line alone, a looser rule); its
    floors: ``DRIFT_Z`` times the drift Annex A.4.3's zero-stability bound allows over the
    dwell (``zero_stability_dph`` × time_s: a rest's mean rate may wander by the bound) and
    ``SPREAD_FLOOR_STEPS`` steps of the resolution (one count through K_ref, or the
    ``gyro_deg`` column's step). A reading that breaks it is set aside with a finding (the
    estimate is made from the others, :func:`apply_findings`); fewer than ``LINE_MIN``
    readings are not judged (the estimate itself needs 4).

    >>> th = np.arange(12) * 30.0
    >>> cnt = 24750 + 19 * np.cos(np.radians(th + 40)) + np.array(
    ...     [1, -2, 0, 2, -1, 1, 0, -2, 1, 2, -1, 0])
    >>> df = pd.DataFrame({"test": "tilt_estimate", "series": 1, "round": np.arange(1, 13),
    ...     "line": np.arange(33, 45), "orientation": "up", "time_s": 120.0,
    ...     "table_deg": th, "gyro_counts": cnt, "gyro_deg": np.nan})
    >>> tilt_estimate_rule(df, None, "r.csv", 76434.87, set())
    []
    >>> df.loc[3, "gyro_counts"] += 400
    >>> [(f.line, f.code, f.action) for f in tilt_estimate_rule(df, None, "r.csv", 76434.87,
    ...                                                          set())]
    [(36, 'indicated-angle-outlier', 'set_aside')]
    """
    rows = df[(df["test"] == "tilt_estimate") & ~df["line"].isin(skip)]
    if len(rows) < LINE_MIN:
        return []
    deg = rows["gyro_deg"].to_numpy(float) if "gyro_deg" in rows else np.full(len(rows), np.nan)
    cnt = rows["gyro_counts"].to_numpy(float)
    col = np.where(np.isfinite(deg), "gyro_deg", "gyro_counts")
    ind = np.where(np.isfinite(deg), deg, cnt / k_ref if k_ref else np.nan)
    t = rows["time_s"].to_numpy(float)
    ok = np.isfinite(ind) & np.isfinite(t) & (t > 0) & np.isfinite(
        rows["table_deg"].to_numpy(float))
    g = rows[ok].assign(_col=col[ok])
    if len(g) < LINE_MIN:
        return []
    t = t[ok]
    dwell = float(np.median(t))
    d = deg_to_arcsec(ind[ok]) * dwell / t
    g = g.assign(_r=d)
    step = _resolution_arcsec(g, k_ref, _deg_step(g, []) if (col[ok] == "gyro_deg").any()
                              else None)
    drift = allowed_drift_arcsec_per_s(protocol) * t
    what = (f"tilt_estimate (in-situ tilt estimate, supports {TILT_ESTIMATE_CLAUSE}) at "
            f"axis {g['orientation'].iloc[0]}")
    out = []
    for i, dev, thr, s, *_ in line_departures(g["table_deg"].to_numpy(float), d,
                                              SPREAD_FLOOR_STEPS * step, 0.0, drift):
        row = g.iloc[i]
        by = (f" (K_ref = {k_ref:.9g} counts/° from the rotation readings)"
              if row["_col"] == "gyro_counts" else "")
        out.append(Finding(
            "indicated-angle-outlier",
            f"{what} position {int(row['round'])} ({float(row['table_deg']):g}°): the angle "
            f"accumulated over its rest {d[i]:.6g}″ departs from the fit the other positions "
            f"draw by {abs(dev):.4g}″ (> {thr:.3g}″; s = {s:.3g}″ of the others, drift "
            f"allowed {drift[i]:.3g}″); set aside, ψ estimated from the other positions{by}",
            "set_aside", file=file, line=int(row["line"]), column=str(row["_col"]),
            test="tilt_estimate", clause=TILT_ESTIMATE_CLAUSE, rule=_TILT_RULE))
    return out


_TILT_RULE = ("the condition rule of readings taken once per position (|d − fit(others)| "
              f"beyond the others' spread, with floors of {DRIFT_Z:g} × the A.4.3 zero-stability "
              f"bound × the dwell and {SPREAD_FLOOR_STEPS:g} steps of resolution), d = the rest's indicated angle scaled to "
              "the median dwell, fit = least squares in θ (line, cos θ, sin θ) through the other "
              "positions")


def screen(readings: Readings, protocol) -> list[Finding]:
    """Every finding on the readings of an optical-draft calibration (module docstring).

    The indicated-angle rule runs on the readings the protocol rules leave; the incomplete
    programme is judged on what is left after everything set aside.
    """
    df, file = readings.data, readings.path
    name = None if file is None else str(file)
    aside_lines: set = set()
    found = _protocol_rules(df, protocol, name, aside_lines)
    out_lines = {f.line for f in found if f.action != "flagged"} | aside_lines
    kept = df[~df["line"].isin(out_lines)]
    found += nominal_k_rule(kept, readings.metadata, name)
    k_ref = reference_scale_factor(kept, readings.metadata, file)
    found += counts_agree_rule(df, k_ref, name)       # every row, those set aside included
    found += _indicated_rule(df, protocol, name, k_ref, out_lines)
    found += tilt_estimate_rule(df, protocol, name, k_ref, out_lines)
    gone = {f.line for f in found if f.action != "flagged"} | aside_lines
    found += _incomplete(df[~df["line"].isin(gone)], protocol, name, set(df["test"]), df)
    found += zero_stability_schedule(df, protocol, name)
    return found


#: The tests whose item stands on the rounds left when a round's only reading is set aside
#: by the repeated-reference rule (``_REFERENCE_LINE_RULE``: the reading disagrees with the
#: ten 7.4 readings of the same stop, rate and axis, so the position itself is known): 7.1's
#: K is the mean of the rounds' K_i (each an estimate of K by itself) and K_l their range,
#: so the item is computed on the other rounds, the ``incomplete-programme`` finding saying
#: on how many (certificate, results.json). A reading set aside by any other rule (no
#: repeated reference: the position is known from nothing else), and every round of 7.4
#: (E is the largest |E_i|: a point lost could be the largest), 7.6 and 7.7 (compared over
#: the same positions), refuse instead. At most :data:`ROUND_MAY_GO_MAX` such readings go.
ROUND_MAY_GO: tuple[str, ...] = ("scale_factor",)
#: The most readings of a ``ROUND_MAY_GO`` test the repeated-reference rule may set aside
#: before the calibration is refused: the rule judges the departing readings one at a time
#: while at least ``LINE_MIN`` remain, so with several departing the last ones are never
#: judged (three bad 7.1 readings: two set aside, the third kept, K_l and E certified from it
#: with tight intervals); and each reading gone leaves K_l a range over fewer positions. One
#: typo is set aside; more refuse, naming their lines.
ROUND_MAY_GO_MAX: int = 1


def _refuse_several_gone(df: pd.DataFrame, aside: dict, path) -> None:
    """Refuse a calibration where the repeated-reference rule sets aside more than
    :data:`ROUND_MAY_GO_MAX` readings of one ``ROUND_MAY_GO`` test (one line naming them)."""
    for test in ROUND_MAY_GO:
        lines = sorted(int(ln) for ln, f in aside.items() if f.rule == _REFERENCE_LINE_RULE
                       and (df.loc[df["line"] == ln, "test"] == test).any())
        if len(lines) > ROUND_MAY_GO_MAX:
            raise GonioError(
                f"{CLAUSES.get(test, test)} readings at lines {', '.join(map(str, lines))} "
                f"depart from the repeated readings of the same stops: one such reading is set "
                f"aside, {len(lines)} leave the others unjudged and the item on fewer "
                f"positions; the calibration is refused (check these readings)",
                file=path, line=lines[0], column=aside[lines[0]].column)


def apply_findings(readings: Readings, findings: list[Finding], protocol=None
                   ) -> tuple[Readings, pd.DataFrame]:
    """The readings kept and the DataFrame of those set aside (line, test, series, round,
    rate_dps, orientation, reason); a refused reading, or setting aside the last reading of
    a round (except in ``ROUND_MAY_GO``), raises a GonioError naming the line."""
    df = readings.data
    for f in findings:
        if f.action == "refused":
            raise GonioError(f.message, file=readings.path, line=f.line, column=f.column)
    aside = {}
    for f in findings:
        if f.action == "set_aside" and f.line is not None:
            aside.setdefault(f.line, f)
            if f.code == "condition-not-in-programme":      # one finding per condition
                row = df[df["line"] == f.line].iloc[0]
                same = df[(df["test"] == row["test"]) & (df["rate_dps"] == row["rate_dps"])
                          & (df["orientation"] == row["orientation"])]
                for line in same["line"]:
                    aside.setdefault(int(line), f)
    cols = ["line", "test", "series", "round", "rate_dps", "orientation"]
    if not aside:
        return readings, pd.DataFrame(columns=cols + ["reason"])
    mask = df["line"].isin(list(aside))
    left = df[~mask]
    for line, f in aside.items():
        if f.code in ("condition-not-in-programme", "round-not-in-programme"):
            continue
        row = df[df["line"] == line].iloc[0]
        same = left[(left["test"] == row["test"]) & (left["round"] == row["round"])
                    & (left["orientation"] == row["orientation"])
                    & ((left["rate_dps"] == row["rate_dps"])
                       | (left["rate_dps"].isna() & pd.isna(row["rate_dps"])))]
        may_go = row["test"] in ROUND_MAY_GO and f.rule == _REFERENCE_LINE_RULE
        if row["test"] in ROTATION_TESTS and not may_go and not len(same):
            # the why first: a long finding is cut on the command line's one line
            raise GonioError(f"{CLAUSES.get(row['test'], '')} reading set aside, and no other "
                             f"reading of its round is left: the item cannot stand without "
                             f"it; {f.message}", file=readings.path, line=line,
                             column=f.column)
    _refuse_several_gone(df, aside, readings.path)
    ex = df.loc[mask, cols].copy()
    ex["reason"] = [f"{aside[int(x)].message} [{aside[int(x)].code}]" for x in ex["line"]]
    kept = Readings(left.reset_index(drop=True), dict(readings.metadata), readings.path)
    return kept, ex.sort_values("line").reset_index(drop=True)
