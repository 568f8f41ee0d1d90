"""K_l's table reading against a Monte Carlo of the 7.1 chain, simulated from its physics (the
table turns θ_k + e(θ_k) − e(0), the gyro — the ``rlg`` bench's scale factor, angle-position
error and angle random walk — counts the angle turned, floored counter readings;
K_i = C_k/θ_k), not from the budget's formulas; the truth is the range of the gyro's own K_i
(draft 7.2), known from the bench's parameters.

The stated K_l takes the table's errors as K's table lines do: each position the rounds reach
rectangular ±MPE, independent, the common zero shared by every round (the laboratory knows its
table by the MPE, JCGM 100 4.3.7). Checked here: on tables drawn that way (its own state of
knowledge) it covers with z sd within 0.7–1.3; on a table at its bound — one periodic error at
the full MPE of each order 1–36, phase drawn — it still covers (Clopper–Pearson reaching 95 %);
its draws have the closed-form covariance and their mean K's table line. The standard's reading
per stop (``standard``, the zero inside each stop) under-covers at the worst order; the periodic
reading (``periodic``, the curve at the bound) corrects a good table's range by the bound's
errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from gonio.specs.ogam_draft.bench.config import load_bench
from gonio.specs.ogam_draft.item_uncertainty import (RoundNoise, nonlinearity_corrected_budget,
                                                    nonlinearity_table_order)
from gonio.units import ARCSEC_PER_DEG, S_PER_H

BENCH = load_bench("rlg")
K_NOM = BENCH.instrument.nominal_scale_factor_counts_per_deg
N_ARCSEC_PER_SQRT_S = BENCH.instrument.arw_dpsh * ARCSEC_PER_DEG / math.sqrt(S_PER_H)
MPE = 0.1                                                      # ″, Table 1 / A.4.1
STOPS = np.array([60.0, 120.0, 180.0, 240.0, 300.0, 360.0])    # the draft's 7.1 stops
TIMES_S = 10.0 + STOPS / 10.0          # zeroing to reading: 10 s at rest and 10 °/s turning
NOISE = RoundNoise(N_ARCSEC_PER_SQRT_S ** 2, None, 100)
DRAWS = 1000                           # the budget's Monte Carlo draws (speed)


def _sines(x_deg, terms):
    x = np.radians(np.asarray(x_deg, dtype=float))
    return sum(a * np.sin(h * x + p) for a, h, p in terms)


GYRO = [(c.amplitude_arcsec, c.order, math.radians(c.phase_deg))
        for c in BENCH.instrument.position_harmonics]
K_TRUE_I = K_NOM * (1.0 + (_sines(STOPS, GYRO) - _sines(0.0, GYRO)) / (STOPS * ARCSEC_PER_DEG))
KL_TRUE = float((K_TRUE_I.max() - K_TRUE_I.min()) / K_TRUE_I.mean() * 100.0)


def _chain_k_i(h, phase, rng, amplitude_arcsec=MPE):
    """One 7.1 session: the table's error one harmonic of order h at ``amplitude_arcsec``."""
    table = [(amplitude_arcsec, h, phase)]
    turned_arcsec = STOPS * ARCSEC_PER_DEG + _sines(STOPS, table) - _sines(0.0, table)
    gyro_arcsec = turned_arcsec + _sines(turned_arcsec / ARCSEC_PER_DEG, GYRO) - _sines(0.0, GYRO)
    gyro_arcsec = gyro_arcsec + rng.normal(0.0, N_ARCSEC_PER_SQRT_S * np.sqrt(TIMES_S))
    start = rng.uniform(0.0, 1.0, STOPS.size)                  # the counter's fraction at zero
    counts = np.floor(start + K_NOM * gyro_arcsec / ARCSEC_PER_DEG) - np.floor(start)
    return counts / STOPS


def _z(h, trials, seed, reading, amplitude_arcsec=MPE):
    """Hits of K_l's stated 95 % interval (the range's confidence belt; before, K_l ± U) over
    the truth and the z = (K_l − truth)/u_c of ``trials`` sessions."""
    rng = np.random.default_rng(seed)
    z, hits = [], 0
    for _ in range(trials):
        k_i = _chain_k_i(h, rng.uniform(0.0, 2.0 * math.pi), rng, amplitude_arcsec)
        b = nonlinearity_corrected_budget(k_i, STOPS, MPE, k=2.0, noise=NOISE, time_s=TIMES_S,
                                          draws=DRAWS, table_reading=reading)
        hits += b.interval[0] <= KL_TRUE <= b.interval[1]
        z.append((b.value - KL_TRUE) / b.u_c)
    return hits, np.array(z)


def _cp_upper(hits, n):
    """Clopper–Pearson 95 % interval's upper end."""
    return 1.0 if hits == n else float(stats.beta.ppf(0.975, hits + 1, n - hits))


def test_worst_order_of_the_range_is_the_largest_spread_of_the_rounds():
    """At the worst order the chain's table error alone (no noise) spreads the K_i by the
    order's bound, and no order 1…36 spreads them more."""
    w = nonlinearity_table_order(STOPS, MPE)
    spread = {}
    for h in range(1, 37):
        r = []
        for p in np.linspace(0.0, 2.0 * math.pi, 721):
            e = (_sines(STOPS, [(MPE, h, p)]) - _sines(0.0, [(MPE, h, p)])) / (STOPS * ARCSEC_PER_DEG)
            r.append(e.max() - e.min())
        spread[h] = max(r)
    assert max(spread.values()) <= 2.0 * w.half_range_rel * (1 + 1e-9)
    assert spread[w.order] == pytest.approx(2.0 * w.half_range_rel, rel=1e-4)


def _rms(z):
    return float(np.sqrt(np.mean(np.square(z))))


def test_stated_covers_at_the_worst_order_and_the_standards_reading_alone_does_not():
    """200 sessions at the worst order, one periodic error at the full MPE (the table at its
    bound, a corner of what the MPE allows). The stated K_l covers (Clopper–Pearson reaching
    95 %: 187/200, upper end 96.5 %), z mean +0.64, sd 1.06, root mean square 1.24 (asserted
    within 0.7–1.3: the corner biases the corrected value, about constantly over the
    sessions). The standard's reading per stop alone does not cover there."""
    w = nonlinearity_table_order(STOPS, MPE)
    n = 200
    hits, z = _z(w.order, n, 20261130, "stated")
    assert _cp_upper(hits, n) >= 0.95 and 0.7 <= _rms(z) <= 1.3, (hits, z.mean(), np.std(z))
    assert 0.5 <= np.std(z) <= 1.3, np.std(z)
    hits_s, z_s = _z(w.order, n, 20261130, "standard")
    assert _cp_upper(hits_s, n) < 0.95, (hits_s, np.std(z_s))


def _same_at_the_stops(h, g):
    """Orders h and g give the stops the same table errors (h ≡ ±g modulo 360/gcd of stops)."""
    x = np.radians(STOPS)
    return bool(np.allclose(np.exp(1j * h * x), np.exp(1j * g * x)))


@pytest.mark.parametrize("orders", [range(1, 13), range(13, 25), range(25, 37)])
def test_stated_covers_a_table_at_its_bound_at_every_order(orders):
    """Coverage of the stated K_l at every order 1–36 at the full MPE (40 sessions each,
    Clopper–Pearson reaching 95 %); z's spread at most 1.3 at every order; the orders that
    repeat the worst order's errors at the stops are judged together (their sessions are draws
    of one distribution) by z's root mean square within 0.7–1.3."""
    w = nonlinearity_table_order(STOPS, MPE)
    n, worst_z = 40, []
    for h in orders:
        hits, z = _z(h, n, 20261200 + h, "stated")
        assert _cp_upper(hits, n) >= 0.95, (h, hits)
        assert np.std(z) <= 1.3, (h, np.std(z))
        if _same_at_the_stops(h, w.order):
            worst_z.append(z)
    if worst_z:
        assert 0.7 <= _rms(np.concatenate(worst_z)) <= 1.3


def test_stated_value_is_the_standards_and_the_periodic_one_over_corrects_a_good_table():
    """An error-free table: the stated value is the standard's reading's, centred (|z mean| <
    0.5); the periodic reading's value subtracts the bound's range from the measured one and
    lands low (z mean < −0.4: why its value is not stated). The stated u holds a table
    anywhere within its MPE, so on this best of tables z's sd is below 1 (0.66)."""
    _, z_std = _z(3, 150, 5, "standard", amplitude_arcsec=0.0)
    _, z_st = _z(3, 150, 5, "stated", amplitude_arcsec=0.0)
    _, z_per = _z(3, 150, 5, "periodic", amplitude_arcsec=0.0)
    assert abs(z_st.mean()) < 0.5 and abs(z_std.mean()) < 0.5, (z_st.mean(), z_std.mean())
    assert np.std(z_st) <= 1.3
    assert z_per.mean() < -0.4, z_per.mean()


POSITIONS = np.arange(0.0, 360.0, 60.0)        # the positions the draft's 7.1 rounds reach


def _chain_k_i_positions(e_arcsec, rng):
    """One 7.1 session on a table whose error at each of POSITIONS is ``e_arcsec`` (the 360°
    stop is the 0° position): the table turns θ_k + e(θ_k) − e(0), the chain as
    :func:`_chain_k_i`."""
    e_at = dict(zip(POSITIONS, e_arcsec))
    e_stop = np.array([e_at[s % 360.0] for s in STOPS])
    turned_arcsec = STOPS * ARCSEC_PER_DEG + e_stop - e_at[0.0]
    gyro_arcsec = turned_arcsec + _sines(turned_arcsec / ARCSEC_PER_DEG, GYRO) - _sines(0.0, GYRO)
    gyro_arcsec = gyro_arcsec + rng.normal(0.0, N_ARCSEC_PER_SQRT_S * np.sqrt(TIMES_S))
    start = rng.uniform(0.0, 1.0, STOPS.size)
    counts = np.floor(start + K_NOM * gyro_arcsec / ARCSEC_PER_DEG) - np.floor(start)
    return counts / STOPS


def _z_positions(trials, seed, corner=False, reading="stated", amplitude_arcsec=MPE):
    """Hits of the stated interval and z = (K_l − truth)/u_c over ``trials`` sessions whose
    table errors are drawn per position uniform within ±MPE (what the laboratory knows of its
    table: the MPE), or (``corner``) at the corner no rectangular line holds: the zero at
    −MPE and every other position at +MPE."""
    rng = np.random.default_rng(seed)
    z, hits = [], 0
    for _ in range(trials):
        a = amplitude_arcsec
        e = (np.where(POSITIONS == 0.0, -a, a) if corner
             else rng.uniform(-a, a, POSITIONS.size))
        b = nonlinearity_corrected_budget(_chain_k_i_positions(e, rng), STOPS, MPE, k=2.0,
                                          noise=NOISE, time_s=TIMES_S, draws=DRAWS,
                                          table_reading=reading)
        hits += b.interval[0] <= KL_TRUE <= b.interval[1]
        z.append((b.value - KL_TRUE) / b.u_c)
    return hits, np.array(z)


def test_stated_on_tables_drawn_per_position_within_the_mpe():
    """The stated K_l on tables known only by their MPE (each position's error uniform within
    ±MPE, independent, the zero shared by every round): the interval covers (Clopper–Pearson
    reaching 95 %; 149/150 measured) and z = (K_l − truth)/u_c has sd within 0.7–1.3 (0.74).
    Its mean is +0.57: the value is not corrected for the table's spread of the K_i (its
    sign and size unknown within ±K_tab), so on such tables it reads high by part of it;
    asserted below +0.8 and above 0."""
    n = 150
    hits, z = _z_positions(n, 20261201)
    assert _cp_upper(hits, n) >= 0.95, hits
    assert 0.0 < z.mean() < 0.8 and 0.7 <= np.std(z) <= 1.3, (hits, z.mean(), np.std(z))


def test_stated_covers_the_corner_and_the_independent_reading_does_not():
    """The corner table (the zero at −MPE, every other position at +MPE: the same spread of
    the K_i in every session, which no rectangular line per position holds): the stated
    interval (the table's bound on the range added to the noise belt's ends) covers in every
    one of 40 sessions; the positions-independent reading (the stated one before) misses in
    some (38/40 here at the full MPE with this chain's noise; 35/40 in the study at 0.07″,
    docs/validation-optical.md)."""
    n = 40
    hits, _ = _z_positions(n, 20261202, corner=True)
    assert hits == n, hits
    hits_i, _ = _z_positions(n, 20261202, corner=True, reading="independent")
    assert hits_i < n, hits_i


def test_draws_of_the_independent_table_reading_have_the_closed_form_covariance():
    """The positions-independent reading's table draws (the stated one until the corner table;
    now kept beside it) (:func:`_range_table_errors`) against the closed form:
    round i's relative error (e(s_i) − e(z_i))/θ_i with each position's e rectangular ±MPE,
    independent, so cov_ij = (MPE²/3)·(1{s_i = s_j} − 1{s_i = z_j} − 1{z_i = s_j} +
    1{z_i = z_j})/(θ_i θ_j); their mean over the rounds has K's table line's u
    (:func:`scale_factor_table_u_rel`, an independent formula); the 360° round, zeroed and
    stopped at one position, has no table error. Rounds zeroed at 30° (one counter-clockwise)
    as well as the draft's."""
    from gonio.specs.ogam_draft.item_uncertainty import (_range_table_errors,
                                                        scale_factor_table_u_rel)

    cases = [(STOPS, None, None),
             (np.array([60.0, 120.0, 180.0, -60.0]), np.array([90.0, 150.0, 210.0, 330.0]),
              np.full(4, 30.0))]
    for th, stop, zero in cases:
        k_i = np.full(th.size, 3600.0)
        d, _ = _range_table_errors(k_i, th, MPE, None, np.random.default_rng(3), 400_000,
                                   "independent", stop, zero)
        rel = d / k_i
        s = th if stop is None else stop
        z0 = np.zeros_like(th) if zero is None else zero
        same = lambda a, b: np.isclose(np.mod(a[:, None] - b[None, :] + 180.0, 360.0), 180.0)
        ind = same(s, s).astype(float) - same(s, z0) - same(z0, s) + same(z0, z0)
        th_as = th * ARCSEC_PER_DEG
        cov = MPE ** 2 / 3.0 * ind / np.outer(th_as, th_as)
        scale = np.sqrt(np.outer(np.diag(cov), np.diag(cov))).max()
        assert np.allclose(np.cov(rel.T), cov, atol=0.01 * scale), (np.cov(rel.T), cov)
        u_k = scale_factor_table_u_rel(th, MPE, stop, zero)
        assert np.std(rel.mean(axis=1)) == pytest.approx(u_k, rel=0.01)
    d, _ = _range_table_errors(np.full(6, 3600.0), STOPS, MPE, None,
                               np.random.default_rng(4), 1000, "independent")
    assert np.all(d[:, -1] == 0.0) and np.all(d[:, 0] != 0.0)
