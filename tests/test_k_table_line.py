"""K's table line at the 7.1 stops against a Monte Carlo of the 7.1 chain with the table's
error at its A.4.1 bound: one periodic error P(x) = MPE·sin(h·x + φ) of each order h, the
phase drawn. The chain is simulated from its physics (the table turns θ_k + P(θ_k) − P(0),
the gyro counts the angle turned, K = mean C_k/θ_k), not from the line's formula."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.specs.ogam_draft.item_uncertainty import scale_factor_budget, scale_factor_table_line

K_TRUE = 3600.0                      # counts/°
MPE = 0.1                            # ″, Table 1 / A.4.1
STOPS = np.array([60.0, 120.0, 180.0, 240.0, 300.0, 360.0])    # the draft's 7.1 stops
ORDERS = range(1, 37)
DRAWS = 4000


def _table_error_arcsec(x_deg, sizes, orders, phases):
    """A table's error curve Σ a_h sin(h x + φ_h) at x (° ), arcseconds."""
    x = np.radians(np.asarray(x_deg, dtype=float))
    return sum(a * np.sin(h * x + p) for a, h, p in zip(sizes, orders, phases))


def _chain_k(stops_deg, err_fn):
    """The 7.1 chain: the table turns θ_k plus its error P(θ_k) − P(0); the gyro counts the
    angle turned at K_TRUE; K = mean over the rounds of C_k/θ_k (θ_k the commanded stop)."""
    turned = stops_deg + (err_fn(stops_deg) - err_fn(0.0)) / 3600.0
    k_i = K_TRUE * turned / stops_deg
    return k_i, float(np.mean(k_i))


def _errors_at_order(h, stops, rng):
    phases = rng.uniform(0.0, 2.0 * math.pi, DRAWS)
    return np.array([_chain_k(stops, lambda x, p=p: _table_error_arcsec(x, [MPE], [h], [p]))[1]
                     for p in phases]) / K_TRUE - 1.0


@pytest.mark.parametrize("stops", [STOPS, np.array([45.0, 90.0, 135.0, 180.0]),
                                   np.array([-60.0, -180.0, 100.0, 300.0])])
def test_line_bounds_the_chain_at_every_order(stops):
    line = scale_factor_table_line(stops, MPE)
    rng = np.random.default_rng(20261130)
    worst_sd, worst_max = 0.0, 0.0
    for h in ORDERS:
        d = _errors_at_order(h, stops, rng)
        assert np.max(np.abs(d)) <= line.half_width_rel_harmonic * (1 + 1e-9), h
        worst_sd = max(worst_sd, float(np.std(d)))
        worst_max = max(worst_max, float(np.max(np.abs(d))))
    # the line's half-width is reached at the worst order (not a loose bound) and its u is
    # the chain's spread there (arcsine, u = A/√2)
    assert worst_max == pytest.approx(line.half_width_rel_harmonic, rel=2e-3)
    assert worst_sd == pytest.approx(line.u_rel_harmonic, rel=0.04)


def test_standard_line_fails_at_the_worst_order_and_the_certified_one_covers():
    line = scale_factor_table_line(STOPS, MPE)
    assert line.certified == "harmonic" and line.order == 3
    d = _errors_at_order(line.order, STOPS, np.random.default_rng(7))
    cover_std = float(np.mean(np.abs(d) <= 2.0 * line.u_rel_standard))
    cover_cert = float(np.mean(np.abs(d) <= 2.0 * line.u_rel))
    assert cover_std < 0.5                     # independent stops: far too narrow here
    assert cover_cert == 1.0


def _chain_k_at(k_true, stops_deg, err_fn):
    k_i, _ = _chain_k(stops_deg, err_fn)
    return k_i * (k_true / K_TRUE)


# A fine counter (1000 counts per arcsecond), so that the count quantisation does not hide
# the table line; the gyro's noise per round of the size of the table's worst-order error.
K_FINE = 3.6e6


def _coverage(line_u_rel, h, rng, draws=2000):
    """Coverage and z sd of K ± 2·u_c over drawn phases at order h, u_c from K's budget
    with its P_K line replaced by ``line_u_rel`` (None: the certified budget as is)."""
    ref = scale_factor_table_line(STOPS, MPE)
    sig = ref.half_width_rel_harmonic * K_FINE
    z = []
    for _ in range(draws):
        p = rng.uniform(0.0, 2.0 * math.pi)
        k_i = _chain_k_at(K_FINE, STOPS, lambda x: _table_error_arcsec(x, [MPE], [h], [p]))
        k_i = k_i + rng.normal(0.0, sig, k_i.size)
        b = scale_factor_budget(k_i, STOPS, MPE, k=2.0)
        u2 = b.u_c ** 2
        if line_u_rel is not None:
            u2 += (line_u_rel * b.value) ** 2 - sum(c.u ** 2 for c in b.components
                                                    if c.symbol == "P_K")
        z.append((b.value - K_FINE) / math.sqrt(u2))
    z = np.array(z)
    return float(np.mean(np.abs(z) <= 2.0)), float(np.std(z))


@pytest.mark.parametrize("h", [1, 3])
def test_budget_covers_a_table_at_its_bound_and_the_standard_line_does_not(h):
    line = scale_factor_table_line(STOPS, MPE)
    cov, sd = _coverage(None, h, np.random.default_rng(20261130 + h))
    assert cov >= 0.95 and 0.7 <= sd <= 1.3, (cov, sd)
    cov_s, sd_s = _coverage(line.u_rel_standard, h, np.random.default_rng(20261130 + h))
    assert cov_s < 0.93 and sd_s > 1.3, (cov_s, sd_s)


def test_budget_bounds_a_table_of_any_shape_within_its_mpe():
    """Several harmonics with Σ|a_h| = MPE (sizes and phases drawn), no noise: the table's
    error of K never exceeds the certified line's half-width, the line is arcsine."""
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(400):
        m = int(rng.integers(1, 6))
        orders = rng.choice(np.arange(1, 25), size=m, replace=False)
        w = rng.dirichlet(np.ones(m)) * MPE
        ph = rng.uniform(0.0, 2.0 * math.pi, m)
        k_i = _chain_k_at(K_FINE, STOPS, lambda x: _table_error_arcsec(x, w, orders, ph))
        b = scale_factor_budget(k_i, STOPS, MPE, k=2.0)
        p_k = next(c for c in b.components if c.symbol == "P_K")
        assert p_k.distribution == "arcsine"
        worst = max(worst, abs(b.value - K_FINE) / (p_k.u * math.sqrt(2.0)))
    assert 0.8 < worst <= 1.0 + 1e-9
