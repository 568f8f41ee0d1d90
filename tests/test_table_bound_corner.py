"""The table's bound on K_l (draft 7.2) and on E's extreme (7.4) against a brute-force search
over every corner of the box the MPE allows (A.4.1: each table position's error within ±MPE).

The closed forms (:func:`range_table_bound`: MPE·max_ij Σ_p |w_ip − w_jp|; the physical
budget's b_i = MPE·Σ_p |c_p| of :func:`table_error_coefficients`) are checked against a second
algorithm that knows nothing of coefficients: the 7.1 chain and the 7.4 readings computed from
the turned angles θ + e(stop) − e(zero) of a table at every vertex of the box (2^P tables),
K = mean C_k/θ_k, E_i = C_i/K − θ_i, K_l the range of the K_i over their mean. A linear
function on a box is largest at a vertex, so the search finds the exact worst shift, and the
corner (the zero at −MPE, every stop at +MPE) is one of the vertices searched.

Then the statements that use them: the interval of max|E_i| widened by b_i holds the truth
at the corner table ≥ 95 % where the per-point table lines at MPE/√3 do not."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy import stats

from gonio.specs.ogam_draft.budget_extra import table_error_coefficients, table_line_u
from gonio.specs.ogam_draft.item_uncertainty import range_table_bound
from gonio.units import ARCSEC_PER_DEG
from uncertainty.extreme import max_abs_interval

MPE = 0.1                                                       # ″, A.4.1
STOPS = np.array([60.0, 120.0, 180.0, 240.0, 300.0, 360.0])     # the draft's 7.1 stops
POINTS = np.arange(30.0, 361.0, 30.0)                           # the built-in 7.4 points
K_TRUE = 76434.8                                                # counts/°, the rlg bench's order


def _vertices(n):
    return np.array(list(itertools.product((-MPE, MPE), repeat=n)))


def _pos(x):
    k = round(float(x) % 360.0, 6)
    return 0.0 if k == 360.0 else k


def _k_i(e_at: dict, theta, stop, zero):
    """The rounds' K_i on a table with error e_at[position] (″): turned θ + e(s) − e(z)."""
    turned = np.array([t * ARCSEC_PER_DEG + e_at[_pos(s)] - e_at[_pos(z)]
                       for t, s, z in zip(theta, stop, zero)])
    return K_TRUE * turned / ARCSEC_PER_DEG / np.asarray(theta, dtype=float)


def _brute_range(theta, stop, zero, truth_k=None):
    """Over every vertex of the box: the largest |range(K_true,i(1 + δ_i)) − range(K_true,i)|
    in % of the mean (truth_k: the true K_i; None: equal)."""
    theta = np.asarray(theta, dtype=float)
    pos = sorted({_pos(x) for x in np.concatenate([stop, zero])})
    base = np.full(theta.size, K_TRUE) if truth_k is None else np.asarray(truth_k, dtype=float)
    r0 = (base.max() - base.min()) / base.mean() * 100.0
    worst = 0.0
    for v in _vertices(len(pos)):
        k = _k_i(dict(zip(pos, v)), theta, stop, zero) / K_TRUE * base
        worst = max(worst, abs((k.max() - k.min()) / k.mean() * 100.0 - r0))
    return worst


CASES = {
    "draft": (STOPS, STOPS, np.zeros(6)),
    "zeroed at 30°": (STOPS, STOPS + 30.0, np.full(6, 30.0)),
    "a counter-clockwise round": (np.array([60.0, 120.0, -180.0, 240.0, 300.0, 360.0]),
                                  np.array([60.0, 120.0, -180.0, 240.0, 300.0, 360.0]),
                                  np.zeros(6)),
    "three stops": (np.array([90.0, 180.0, 270.0]), np.array([90.0, 180.0, 270.0]), np.zeros(3)),
}


@pytest.mark.parametrize("case", list(CASES))
def test_range_bound_is_the_worst_vertex(case):
    """K_l's table half-width equals the largest range any vertex table gives equal true K_i
    (the bound is reached), to the chain's second order (1e-6 relative)."""
    theta, stop, zero = CASES[case]
    d = range_table_bound(np.full(theta.size, K_TRUE), theta, MPE, stop, zero)
    assert d == pytest.approx(_brute_range(theta, stop, zero), rel=1e-6)


def test_range_bound_of_the_draft_stops_is_twice_the_mpe_over_60_degrees():
    """The draft's stops: the 60° round against the 360° one (its stop is its zero),
    2·MPE/60° = 9.26·10⁻⁵ % — the periodic reading's "up to" figure."""
    d = range_table_bound(np.full(6, K_TRUE), STOPS, MPE)
    assert d == pytest.approx(2.0 * MPE / (60.0 * ARCSEC_PER_DEG) * 100.0, rel=1e-12)


def test_range_bound_holds_for_unequal_true_values():
    """Every vertex table moves the range of spread true K_i by no more than the bound."""
    rng = np.random.default_rng(7)
    d = range_table_bound(np.full(6, K_TRUE), STOPS, MPE)
    for _ in range(5):
        truth = K_TRUE * (1.0 + rng.normal(0.0, 5e-7, 6))
        assert _brute_range(STOPS, STOPS, np.zeros(6), truth) <= d * (1.0 + 1e-6)


def _e_shift(e_at: dict, theta_i: float) -> float:
    """E_i's error (″) from the table e_at through the 7.1 K (the chain, no coefficients)."""
    k = float(np.mean(_k_i(e_at, STOPS, STOPS, np.zeros(6))))
    c_i = K_TRUE * (theta_i * ARCSEC_PER_DEG + e_at[_pos(theta_i)] - e_at[0.0]) / ARCSEC_PER_DEG
    return (c_i / k - theta_i) * ARCSEC_PER_DEG


def _e_bound(theta_i: float) -> float:
    return MPE * float(np.sum(np.abs(list(table_error_coefficients(theta_i, STOPS).values()))))


def test_point_bound_is_the_worst_vertex_at_every_point():
    """b_i = MPE·Σ|c_p| equals max over the 2^12 vertex tables of |E_i's shift| at every
    built-in 7.4 point; at 360° it is 0.457″, 3.1 times the point's line u at MPE/√3 —
    the corner moves every point at once."""
    pos = [float(p) for p in np.arange(0.0, 360.0, 30.0)]
    verts = _vertices(len(pos))
    for theta in POINTS:
        worst = max(abs(_e_shift(dict(zip(pos, v)), float(theta))) for v in verts)
        assert _e_bound(float(theta)) == pytest.approx(worst, rel=1e-6), theta
    assert _e_bound(360.0) == pytest.approx(0.45667, abs=1e-5)
    assert _e_bound(360.0) > 3.0 * table_line_u(360.0, STOPS, MPE / math.sqrt(3.0))


def _corner():
    """The corner table: the zero at −MPE, every other 30° position at +MPE."""
    return {float(p): (-MPE if p == 0.0 else MPE) for p in np.arange(0.0, 360.0, 30.0)}


def test_extreme_interval_with_the_bound_covers_the_corner():
    """True E_i = 0 at every point (the hardest pattern for the lower end), the corner table,
    each point's other errors normal with u = 0.05″: max|E_i| read from the shifted points.
    The interval with b_i covers ≥ 95 % (Clopper–Pearson); with the per-point table line at
    MPE/√3 in u instead (the former statement) it misses below in most trials."""
    shift = np.array([_e_shift(_corner(), float(t)) for t in POINTS])
    b = np.array([_e_bound(float(t)) for t in POINTS])
    assert np.all(np.abs(shift) <= b * (1.0 + 1e-6))
    u_rest = np.full(POINTS.size, 0.05)
    u_tab = np.array([table_line_u(float(t), STOPS, MPE / math.sqrt(3.0)) for t in POINTS])
    u_old = np.hypot(u_rest, u_tab)
    rng = np.random.default_rng(20261201)
    n, hit_new, hit_old = 400, 0, 0
    for _ in range(n):
        x = shift + rng.normal(0.0, u_rest)
        r = max_abs_interval(x, u_rest, bound=b)
        hit_new += r.lower <= 0.0 <= r.upper
        r0 = max_abs_interval(x, u_old)
        hit_old += r0.lower <= 0.0 <= r0.upper
    cp_new = float(stats.beta.ppf(0.975, hit_new + 1, n - hit_new)) if hit_new < n else 1.0
    cp_old = float(stats.beta.ppf(0.975, hit_old + 1, n - hit_old)) if hit_old < n else 1.0
    assert cp_new >= 0.95, hit_new
    assert cp_old < 0.95, hit_old
