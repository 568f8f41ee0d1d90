"""Recalibration intervals from an instrument's history (ILAC-G24:2007, OIML D 10).

Two of ILAC-G24's methods, both documented with their formulas in docs/records.md#intervals:

* :func:`drift_to_limit` — the drift of an item fitted over its calibrations (weighted least
  squares, weights 1/u², u = U/k) and extrapolated: the interval is the time after the last
  calibration at which the fitted value plus k times the standard uncertainty of the fit
  reaches the item's specification limit (ILAC-G24 clause 4, "control chart" / drift
  methods: the history predicts when the instrument leaves its tolerance);
* :func:`staircase` — ILAC-G24 method 1, the simple response ("staircase") method: after each
  calibration the interval is lengthened by :data:`EXTEND` when every item was found within
  its limits and shortened by :data:`REDUCE` otherwise.

:func:`propose` combines them with the specification's clause-9 default: the drift method
for each item with at least :data:`MIN_POINTS` calibrations and a limit, the staircase over
the findings of the other limited items, the shorter of the two where both apply (an item
found outside its limits shortens the interval whatever another item's drift says), else the
default; never longer than :data:`MAX_FACTOR` times the default, never shorter than
:data:`MIN_MONTHS` (a method that gives less is stated, with why, in the proposal's detail).
Each method's conditions are checked: the drift method needs its history to span
:data:`MIN_SPAN_FRACTION` of the default interval, and the staircase counts a recalibration
found within the limits only when it follows the previous calibration by at least
:data:`MIN_GAP_FRACTION` of the interval then in force (two calibrations days apart are no
evidence for a year's interval).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

#: days in a mean Gregorian month (time is measured in days, intervals shown in months)
DAYS_PER_MONTH = 365.25 / 12
#: the specification's default interval when it states none (clause 9: "normally ≤ 12 months")
DEFAULT_MONTHS = 12
#: staircase factors (ILAC-G24 method 1 leaves them to the laboratory)
EXTEND, REDUCE = 1.25, 0.5
#: the longest interval proposed, as a multiple of the specification's default
MAX_FACTOR = 2.0
#: the shortest interval proposed (months)
MIN_MONTHS = 1
#: a recalibration found within the limits lengthens the interval in force only when it
#: follows the previous calibration by at least this fraction of that interval (ILAC-G24
#: method 1 judges the interval that was actually run)
MIN_GAP_FRACTION = 0.5
#: the drift method needs calibrations spanning at least this fraction of the default interval
MIN_SPAN_FRACTION = 1.0
#: calibrations an item needs before its drift is extrapolated (two define a line, the
#: third is the first check of it)
MIN_POINTS = 3
#: coverage factor of the predicted value's uncertainty band
K_PREDICT = 2.0


@dataclass(frozen=True)
class DriftFit:
    """y(t) = a + b·t (t in days after the last calibration) and the covariance of (a, b)."""

    a: float
    b: float
    var_a: float
    var_b: float
    cov_ab: float
    birge: float            # sqrt(chi2/nu) of the fit; the covariance is scaled by max(1, birge²)

    def u(self, t):
        """Standard uncertainty of the fitted value at t days."""
        return np.sqrt(np.maximum(self.var_a + 2 * t * self.cov_ab + t * t * self.var_b, 0.0))


def fit_drift(t_days, values, u) -> DriftFit:
    """Weighted straight line through (t, value) with standard uncertainties u; t is shifted
    so that the last calibration is t = 0. With more points than two the covariance is
    scaled by the Birge ratio² when the scatter exceeds the stated uncertainties."""
    t = np.asarray(t_days, float) - float(np.max(t_days))
    y, u = np.asarray(values, float), np.asarray(u, float)
    w = 1.0 / u**2
    X = np.column_stack([np.ones_like(t), t])
    cov = np.linalg.inv(X.T @ (X * w[:, None]))
    a, b = cov @ (X.T @ (w * y))
    nu = len(t) - 2
    chi2 = float(np.sum(w * (y - a - b * t) ** 2))
    birge = math.sqrt(chi2 / nu) if nu > 0 else 1.0
    cov = cov * max(1.0, birge**2)
    return DriftFit(float(a), float(b), float(cov[0, 0]), float(cov[1, 1]), float(cov[0, 1]),
                    birge)


def time_to_limit(fit: DriftFit, lower: float | None, upper: float | None,
                  k: float = K_PREDICT, horizon_days: float = 3650.0) -> float:
    """Days after the last calibration until a + b·t ± k·u(t) first reaches a limit;
    0 when it is at or beyond a limit already, ``inf`` when not within ``horizon_days``."""
    best = math.inf
    for limit, sign in ((upper, 1.0), (lower, -1.0)):
        if limit is None:
            continue

        def margin(t, limit=limit, sign=sign):
            # distance from the band's edge to the limit, positive while inside
            return sign * (limit - (fit.a + fit.b * t)) - k * float(fit.u(t))

        if margin(0.0) <= 0:
            return 0.0
        if margin(horizon_days) > 0:
            continue
        best = min(best, brentq(margin, 0.0, horizon_days, xtol=1e-9))
    return best


def drift_to_limit(t_days, values, U, k, lower, upper) -> tuple[float, DriftFit]:
    """(days to the limit, the fit) for one item's history (U and k per calibration)."""
    u = np.asarray(U, float) / np.asarray(k, float)
    fit = fit_drift(t_days, values, u)
    return time_to_limit(fit, lower, upper), fit


def staircase(start_months: float, in_tolerance: list[bool], *,
              max_months: float) -> float:
    """ILAC-G24 method 1: the interval after each calibration's finding in turn."""
    months = float(start_months)
    for ok in in_tolerance:
        months = min(months * EXTEND, max_months) if ok else max(months * REDUCE, MIN_MONTHS)
    return months


def staircase_history(start_months: float, findings, *, max_months: float
                      ) -> tuple[float, int, int]:
    """ILAC-G24 method 1 over a dated history: ``findings`` (t_days, within the limits) in
    time order → (months, steps counted, recalibrations not counted). The first calibration
    starts the interval (it says nothing yet about how long the instrument stays within its
    limits); a later one within the limits lengthens the interval in force only when it
    follows the previous calibration by at least :data:`MIN_GAP_FRACTION` of it; one found
    outside the limits always shortens it.

    >>> staircase_history(12, [(0, True), (3, True)], max_months=24)
    (12.0, 0, 1)
    >>> staircase_history(12, [(0, True), (366, True)], max_months=24)
    (15.0, 1, 0)
    """
    months, last, counted, skipped = float(start_months), None, 0, 0
    for t, ok in findings:
        if not ok:
            months, counted = staircase(months, [False], max_months=max_months), counted + 1
        elif last is not None:
            if t - last >= MIN_GAP_FRACTION * months * DAYS_PER_MONTH:
                months, counted = staircase(months, [True], max_months=max_months), counted + 1
            else:
                skipped += 1
        last = t
    return months, counted, skipped


@dataclass(frozen=True)
class Proposal:
    """A proposed interval, the method that gave it, and the default beside it."""

    months: int
    method: str
    detail: str
    default_months: int
    per_item: dict            # key -> months to the limit (drift method), inf if none


def _within(value, U, lower, upper) -> bool:
    if value is None:
        return True
    return (upper is None or value <= upper) and (lower is None or value >= lower)


def propose(history: dict, default_months: int = DEFAULT_MONTHS,
            limited_items=(), counts: dict | None = None) -> Proposal:
    """The interval for an instrument from ``history``: item key → list of (t_days,
    value, U, k, lower, upper) in calibration order (limits may be None);
    ``limited_items``: the keys the instrument has limits for (what the detail says when no
    history can be judged against them); ``counts``: item key → its calibrations, of every
    item, where ``history`` holds only the items with limits (the others are only counted:
    whether any item has enough points for a drift); None: the lengths of ``history``'s
    lists."""
    cap = MAX_FACTOR * default_months
    per_item: dict[str, float] = {}
    findings: dict[float, bool] = {}
    spans = []
    for key, rows in history.items():
        # judged against the limits: every row with a value and U (an item stated by its
        # interval has no k: U is the reach to the interval's upper end); the drift is
        # extrapolated from rows with U and k only (value ± U, u = U/k)
        rows = [r for r in rows if r[1] is not None and r[2]]
        if not rows:
            continue
        lower, upper = rows[-1][4], rows[-1][5]
        if lower is None and upper is None:
            continue
        span = max(r[0] for r in rows) - min(r[0] for r in rows)
        spans.append(span)
        if len(rows) >= MIN_POINTS and all(r[3] for r in rows) and \
                span >= MIN_SPAN_FRACTION * default_months * DAYS_PER_MONTH:
            days, _ = drift_to_limit(*zip(*[(r[0], r[1], r[2], r[3]) for r in rows]),
                                     lower, upper)
            per_item[key] = days / DAYS_PER_MONTH
            continue
        for r in rows:        # an item without a drift fit: its findings, the staircase
            findings[r[0]] = findings.get(r[0], True) and _within(r[1], r[2], r[4], r[5])
    drift = _drift_proposal(per_item, cap, default_months) if per_item else None
    stair = _staircase_proposal(findings, spans, cap, default_months, per_item,
                                counts if counts is not None
                                else {k: len(v) for k, v in history.items()}) \
        if findings else None
    if drift is not None and stair is not None:
        return _shorter(drift, stair)
    if drift is not None or stair is not None:
        return drift or stair
    if limited_items:
        why = ("no issued calibration with a measured value and U of a limited item ("
               + ", ".join(sorted(limited_items)) + ") yet")
    else:
        why = "no specification limits: the history cannot be judged against a limit"
    return Proposal(default_months, "specification default (clause 9)", why,
                    default_months, per_item)


def _staircase_proposal(findings: dict, spans: list, cap: float, default_months: int,
                        per_item: dict, counts: dict) -> Proposal:
    """The staircase's proposal (ILAC-G24 method 1) from ``findings`` (t_days → every item
    without a drift fit found within its limits), with what it counted and why no drift was
    extrapolated where the history is too short."""
    months, counted, skipped = staircase_history(
        default_months, sorted(findings.items()), max_months=cap)
    detail = f"{len(findings)} calibration(s) against the limits, {counted} counted"
    if skipped:
        detail += (f"; {skipped} found within the limits less than "
                   f"{MIN_GAP_FRACTION:g} of the interval after the one before: not "
                   "counted")
    if max(spans, default=0) < MIN_SPAN_FRACTION * default_months * DAYS_PER_MONTH \
            and any(n >= MIN_POINTS for n in counts.values()):
        detail += (f"; drift not extrapolated: the history spans less than "
                   f"{MIN_SPAN_FRACTION * default_months:g} months")
    return Proposal(int(math.floor(months)), "simple response / staircase (ILAC-G24 "
                    "method 1)", detail, default_months, per_item)


def _shorter(drift: Proposal, stair: Proposal) -> Proposal:
    """The proposal where some items have a drift fit and others are judged by the
    staircase: the shorter of the two (each item's rule bounds the interval; ILAC-G24,
    OIML D 10: an item found outside its limits shortens the interval whatever another
    item's drift says), the other stated beside it."""
    first, other = (stair, drift) if stair.months < drift.months else (drift, stair)
    return Proposal(first.months, first.method,
                    f"{first.detail}; shorter than the {other.method.split(' (')[0]}'s "
                    f"{other.months} month(s) ({other.detail})", drift.default_months,
                    drift.per_item)


def _drift_proposal(per_item: dict, cap: float, default_months: int) -> Proposal:
    """The drift method's proposal: the item reaching its limit first, in whole months, at
    most ``cap``, at least :data:`MIN_MONTHS` (stated with why when the drift gives less)."""
    key = min(per_item, key=per_item.get)
    got = per_item[key]
    months = int(math.floor(min(got, cap)))
    if not math.isfinite(got):
        detail = f"no item reaches its limit within {cap:g} months"
    else:
        detail = (f"limited by {key}: fitted value + {K_PREDICT:g}·u reaches its limit "
                  f"after {got:.1f} months")
    if months < MIN_MONTHS:
        months = MIN_MONTHS
        detail += (f", less than the shortest interval proposed ({MIN_MONTHS} month): "
                   f"{key} is at or near its limit — adjust or repair the instrument before "
                   "it is used again")
    return Proposal(months, "drift-to-limit (ILAC-G24)", detail, default_months, per_item)
