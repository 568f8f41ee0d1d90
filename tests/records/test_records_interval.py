"""The recalibration-interval methods (docs/records.md#intervals) against closed forms and a
second algorithm (numpy.polyfit)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.records.interval import (DAYS_PER_MONTH, MIN_MONTHS, DriftFit, fit_drift, propose,
                                    staircase, time_to_limit)


def closed_form_time(fit: DriftFit, limit: float, sign: float, k: float) -> float:
    """Smallest t ≥ 0 with sign·(limit − a − b t) = k·u(t): the quadratic
    (c − β t)² = k² (Vaa + 2 Vab t + Vbb t²), c = sign·(limit − a), β = sign·b,
    restricted to c − β t ≥ 0."""
    c, beta = sign * (limit - fit.a), sign * fit.b
    k2 = k * k
    A = beta**2 - k2 * fit.var_b
    B = -2 * c * beta - 2 * k2 * sign * sign * fit.cov_ab
    C = c * c - k2 * fit.var_a
    roots = np.roots([A, B, C])
    good = [r.real for r in roots if abs(r.imag) < 1e-9 and r.real >= 0
            and c - beta * r.real >= 0]
    return min(good) if good else math.inf


def test_exact_line_reaches_limit_at_closed_form_time():
    fit = DriftFit(a=0.10, b=0.002, var_a=0.0, var_b=0.0, cov_ab=0.0, birge=1.0)
    assert time_to_limit(fit, None, 0.5) == pytest.approx((0.5 - 0.10) / 0.002, rel=1e-9)
    assert time_to_limit(DriftFit(0.1, -0.002, 0, 0, 0, 1), -0.5, None) == pytest.approx(300)


@pytest.mark.parametrize("seed", range(5))
def test_band_edge_reaches_limit_at_quadratic_root(seed):
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 1500, 4))
    u = rng.uniform(0.02, 0.06, 4)
    y = 0.05 + 2e-4 * t + rng.normal(0, u)
    fit = fit_drift(t, y, u)
    for lower, upper, sign, limit in ((None, 0.8, 1.0, 0.8), (-0.3, None, -1.0, -0.3)):
        if fit.b * sign <= 0:
            continue
        got = time_to_limit(fit, lower, upper, k=2.0, horizon_days=1e6)
        assert got == pytest.approx(closed_form_time(fit, limit, sign, 2.0), rel=1e-6)


def test_fit_matches_numpy_polyfit():
    t = np.array([0.0, 365.0, 730.0, 1100.0, 1460.0])
    u = np.array([0.05, 0.04, 0.05, 0.03, 0.04])
    y = np.array([0.10, 0.19, 0.33, 0.38, 0.52])
    fit = fit_drift(t, y, u)
    # numpy's weighted fit (w = 1/σ) about the last point, covariance unscaled then Birge
    p, cov = np.polyfit(t - t.max(), y, 1, w=1 / u, cov="unscaled")
    resid = y - np.polyval(p, t - t.max())
    birge2 = np.sum((resid / u) ** 2) / (len(t) - 2)
    cov = cov * max(1.0, birge2)
    assert (fit.b, fit.a) == pytest.approx(tuple(p), rel=1e-10)
    assert fit.var_a == pytest.approx(cov[1, 1], rel=1e-9)
    assert fit.var_b == pytest.approx(cov[0, 0], rel=1e-9)
    assert fit.cov_ab == pytest.approx(cov[0, 1], rel=1e-9)
    assert fit.birge**2 == pytest.approx(birge2, rel=1e-10)


def test_already_at_the_limit_and_never_reaching_it():
    assert time_to_limit(DriftFit(0.49, 0.0, 0.01**2, 0, 0, 1), None, 0.5) == 0.0
    assert time_to_limit(DriftFit(0.0, 0.0, 0.01**2, 0, 0, 1), None, 0.5) == math.inf


def test_staircase_method():
    assert staircase(12, [True, True, False], max_months=24) == pytest.approx(12 * 1.25 * 1.25 / 2)
    assert staircase(12, [True] * 10, max_months=24) == 24
    assert staircase(2, [False] * 5, max_months=24) == 1


def test_propose_uses_drift_with_three_points_else_staircase_else_default():
    rows = [(0, 0.10, 0.04, 2.0, -0.5, 0.5), (365, 0.20, 0.04, 2.0, -0.5, 0.5),
            (730, 0.30, 0.04, 2.0, -0.5, 0.5)]
    p = propose({"angle_deviation": rows}, 12)
    fit = fit_drift([r[0] for r in rows], [r[1] for r in rows], [0.02] * 3)
    days = closed_form_time(fit, 0.5, 1.0, 2.0)
    assert p.method.startswith("drift") and p.months == math.floor(days / DAYS_PER_MONTH)
    assert 0 < p.months < 24
    assert propose({"angle_deviation": rows[:2]}, 12).method.startswith("simple response")
    nolim = [(r[0], r[1], r[2], r[3], None, None) for r in rows]
    assert propose({"angle_deviation": nolim}, 12).months == 12


def lim_rows(days, values, U=0.04, lim=0.5):
    return [(t, v, U, 2.0, -lim, lim) for t, v in zip(days, values)]


def test_calibrations_days_apart_do_not_lengthen_the_interval():
    """Two calibrations three days apart, both within the limits, are no evidence for a
    longer interval (before: 12 × 1.25 × 1.25 → 18 months)."""
    p = propose({"angle_deviation": lim_rows([0, 3], [0.1, 0.1])}, 12)
    assert p.months == 12 and "1 found within the limits" in p.detail
    # a year apart the second one counts once: 12 × 1.25, by the method's own rule
    p = propose({"angle_deviation": lim_rows([0, 366], [0.1, 0.1])}, 12)
    assert p.months == math.floor(staircase(12, [True], max_months=24))
    # one found outside always shortens, however soon it came
    assert propose({"angle_deviation": lim_rows([0, 3], [0.1, 0.7])}, 12).months == 6


def test_drift_needs_the_history_to_span_an_interval():
    """Three calibrations within a month cannot be extrapolated over a year: the staircase
    decides, and the detail says why the drift was not used."""
    p = propose({"angle_deviation": lim_rows([0, 10, 20], [0.1, 0.2, 0.3])}, 12)
    assert p.method.startswith("simple response")
    assert "drift not extrapolated: the history spans less than 12 months" in p.detail


def test_never_zero_months_and_saying_why():
    """An item whose fitted band is at its limit already: the drift gives 0 months; the
    proposal is the stated minimum, with the reason (before: "0 months")."""
    rows = lim_rows([0, 365, 730], [0.30, 0.40, 0.49], U=0.02)
    fit = fit_drift([r[0] for r in rows], [r[1] for r in rows], [0.01] * 3)
    assert time_to_limit(fit, -0.5, 0.5) < DAYS_PER_MONTH     # the drift says < 1 month
    p = propose({"angle_deviation": rows}, 12)
    assert p.months == MIN_MONTHS == 1
    assert "less than the shortest interval proposed" in p.detail and "angle_deviation" in \
        p.detail


def test_no_history_with_limits_is_not_called_no_limits():
    """An instrument with limits but no issued calibration yet: the default, and the
    detail names the limited items (before: "no specification limits")."""
    p = propose({}, 12, limited_items=("angle_deviation",))
    assert p.months == 12 and "no specification limits" not in p.detail
    assert "angle_deviation" in p.detail
    assert "no specification limits" in propose({}, 12).detail


def test_an_item_stated_by_its_interval_is_judged_not_dropped():
    """E stated by the interval of max|E_i| has U (the reach to the interval's upper end)
    and no k: its calibrations count against the limits (the staircase, as with k), and no
    drift is extrapolated from them (no u = U/k). Before, every such row was dropped and the
    proposal fell back to the specification default."""
    out = [(0, -1.3, 0.4, None, -1.0, 1.0), (365, -1.35, 0.4, None, -1.0, 1.0)]
    with_k = [(t, v, U, 2.0, lo, hi) for t, v, U, _, lo, hi in out]
    p, q = propose({"angle_deviation": out}, 12), propose({"angle_deviation": with_k}, 12)
    assert p.method.startswith("simple response") and p.months == q.months == 3
    three = [(0, 0.10, 0.2, None, -0.5, 0.5), (365, 0.20, 0.2, None, -0.5, 0.5),
             (730, 0.30, 0.2, None, -0.5, 0.5)]
    p = propose({"angle_deviation": three}, 12)
    assert p.method.startswith("simple response") and p.per_item == {}


def test_history_figure_draws_the_extreme_at_its_magnitude():
    """A row stated by the interval of max|E_i| (``max_abs``, from its result's k_source)
    whose value is the signed extreme is drawn at |value|, inside its own bar; every other row
    at its value, a non-negative range's bias-corrected estimate below zero beside its
    interval [0, …] too (C_g: −1.58×10⁻⁵, not mirrored to +1.58×10⁻⁵ inside its bar)."""
    from gonio.report.history_figure import bar_ends, drawn_value

    e = {"value": -0.83, "U": 0.17, "interval": (0.54, 1.0), "max_abs": True}
    lo, hi = bar_ends(e)
    assert drawn_value(e) == 0.83 and lo <= drawn_value(e) <= hi
    assert drawn_value({"value": -0.2, "U": 0.1, "interval": None}) == -0.2
    assert drawn_value({"value": 0.12, "U": 0.1, "interval": (0.08, 0.22)}) == 0.12
    c_g = {"value": -1.5776e-05, "U": 5.478e-05, "interval": (0.0, 3.9e-05), "max_abs": False}
    assert drawn_value(c_g) == -1.5776e-05
    assert drawn_value({**c_g, "max_abs": None}) == -1.5776e-05      # a row without the key


@pytest.mark.parametrize("order", ["K first", "E first"])
def test_an_item_out_of_tolerance_caps_another_items_drift(order):
    """One item with a drift fit far from its limit, another (stated by its interval: no k,
    no drift) found outside its limits: the proposal is the shorter of the items' rules —
    the staircase's reduction, as E alone gives (before: the drift's 24 months, "no item
    reaches its limit", whatever E's finding)."""
    K = [(t, 1.0, 1e-4, 2.0, 0.9, 1.1) for t in (0, 267, 534, 801)]
    E = [(0, 0.2, 0.1, None, -0.5, 0.5), (400, 0.3, 0.1, None, -0.5, 0.5),
         (801, 0.9, 0.1, None, -0.5, 0.5)]
    alone = propose({"E": E}, 12)
    # E alone, by the staircase's own rule: in force 12, lengthened once, shortened once
    assert alone.months == math.floor(staircase(12, [True, False], max_months=24)) == 7
    assert propose({"K": K}, 12).months == 24           # the drift alone: the cap
    history = {"K": K, "E": E} if order == "K first" else {"E": E, "K": K}
    p = propose(history, 12)
    assert p.months == alone.months and p.method.startswith("simple response")
    assert "24 month(s)" in p.detail and math.isinf(p.per_item["K"])
    # E in tolerance and K drifting towards its limit: the drift is the shorter
    near = [(t, 1.0 + 0.03 * i, 0.004, 2.0, 0.9, 1.1) for i, t in enumerate((0, 267, 534, 801))]
    ok = [(t, 0.1, 0.1, None, -0.5, 0.5) for t in (0, 400, 801)]
    q = propose({"K": near, "E": ok} if order == "K first" else {"E": ok, "K": near}, 12)
    assert q.method.startswith("drift") and q.months == propose({"K": near}, 12).months
    assert q.months < propose({"E": ok}, 12).months


def test_history_rows_know_the_extreme_of_magnitudes_from_the_stored_result(tmp_path):
    """``max_abs`` comes from the stored result's k_source, read only where it matters (a
    value below zero beside an interval starting at or above zero): E (max-abs-interval)
    yes, C_g (neyman-belt) with the same signs no."""
    import json
    from types import SimpleNamespace

    from gonio.records import services
    from gonio.records.blobs import put_bytes
    from gonio.result.statement import K_SOURCE_MAX_ABS

    doc = {"items": {
        "angle_deviation": {"value": -0.45, "uncertainty": {"k_source": K_SOURCE_MAX_ABS}},
        "pointing_consistency": {"value": -1.58e-05,
                                 "uncertainty": {"k_source": "neyman-belt"}}}}
    store = SimpleNamespace(blob_root=tmp_path)
    sha = put_bytes(tmp_path, json.dumps(doc).encode())
    assert services._max_abs(store, "angle_deviation", -0.45, (0.30, 0.55), sha)
    assert not services._max_abs(store, "pointing_consistency", -1.58e-05, (0.0, 3.9e-05), sha)
    assert not services._max_abs(store, "angle_deviation", 0.45, (0.30, 0.55), sha)
    assert not services._max_abs(store, "angle_deviation", -0.45, None, sha)
    assert not services._max_abs(store, "angle_deviation", -0.45, (0.30, 0.55), "0" * 64)


def test_an_unreadable_stored_result_is_read_again(tmp_path):
    """A stored result that cannot be read (here: not yet stored) gives no keys and no
    intervals, and that answer is not kept for the process: once readable, E is known as
    the extreme of magnitudes and its interval is found (was cached empty until restart,
    the history figure drawing E at its signed value)."""
    import hashlib
    import json
    from types import SimpleNamespace

    from gonio.records.blobs import put_bytes
    from gonio.records.results import max_abs_keys, stated_intervals
    from gonio.result.statement import K_SOURCE_MAX_ABS

    data = json.dumps({"items": {"angle_deviation": {
        "value": -0.45, "uncertainty": {"k_source": K_SOURCE_MAX_ABS}}}}).encode()
    sha = hashlib.sha256(data).hexdigest()
    store = SimpleNamespace(blob_root=tmp_path)
    assert max_abs_keys(store, sha) == frozenset()
    assert stated_intervals(store, sha) == {}
    assert put_bytes(tmp_path, data) == sha
    assert max_abs_keys(store, sha) == frozenset({"angle_deviation"})
