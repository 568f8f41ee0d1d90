"""The bias-drift term of the rate specifications' budgets (IEC 62047-20 5.3.3.3, 5.3.3.5,
5.3.3.6, 5.3.3.7, 5.3.3.8; JJF 1535 7.2.14): `formulas.bias_drift_u` against Monte Carlo
of the bench's own noise processes, and the largest excursion of a walk (5.3.3.5's wander)
against simulated paths."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from gonio.analysis.noise import allan_deviation, fit_noise_model
from gonio.bench.rate_gyro import NoiseState, load_rate_bench
from gonio.specs._rate_family import formulas as rg
from gonio.units import S_PER_H


def test_walk_max_rms_against_simulated_paths():
    # √E[max_t |W(t)|²] over [0, 1] = √(2G): Monte Carlo of fine random walks (the
    # discrete maximum reads low by ≈ 0.58/√n of σ, Asmussen–Glynn–Pitman 1995)
    rng = np.random.default_rng(11)
    n, sq = 4000, []
    for _ in range(8):
        w = np.cumsum(rng.standard_normal((1000, n)), axis=1) / math.sqrt(n)
        sq.append(np.abs(w).max(axis=1) ** 2)
    rms = math.sqrt(float(np.mean(np.concatenate(sq))))
    rms *= 1.0 + 0.5826 / math.sqrt(n)          # the discrete maximum's shortfall
    assert rms == pytest.approx(rg.WALK_MAX_RMS, rel=0.03)
    assert rg.WALK_MAX_RMS == pytest.approx(1.35348, abs=1e-5)


def test_bias_drift_u_matches_the_walk_it_bounds():
    # a resolved fit (u_K < K): u = √(K²Δt + 2·0.664²B²); for the rate random walk alone
    # the difference of two short means Δt apart has variance K²(Δt − T/3) (T ≪ Δt here)
    g = load_rate_bench("mems-adxrs610").gyro
    g = replace(g, arw_deg_sqrt_h=0.0, bias_instability_dph=0.0, output_lsb=0.0)
    K = g.rrw_dph_sqrt_h / math.sqrt(S_PER_H)                 # °/h/√s
    dt, T, gap = 1.0, 10, 3600.0
    d = []
    for s in range(400):
        ns = NoiseState(g, np.random.default_rng(s))
        a = ns.samples(T, dt, 20.0).mean()
        ns.skip(gap - T * dt)
        d.append((ns.samples(T, dt, 20.0).mean() - a) * S_PER_H)
    sd = float(np.std(d, ddof=1))
    u = rg.bias_drift_u(K, 0.1 * K, 0.0, 0.0, [10.0, 300.0], [1e6, 1e6], gap)
    assert u == pytest.approx(K * math.sqrt(1.01 * gap))
    assert sd == pytest.approx(K * math.sqrt(gap - T * dt / 3), rel=0.12)      # 400 draws
    # a fit that does not resolve K (u_K ≥ K) is the bound's rectangular, whatever K says
    hi = [50.0, 10.0]
    assert rg.bias_drift_u(3.0, 30.0, 0.0, 0.0, [10.0, 300.0], hi, gap) == \
        pytest.approx(math.sqrt(gap / 3.0))
    # a resolved K above the bound is held at the bound
    assert rg.bias_drift_u(3.0, 1.0, 0.0, 0.0, [10.0, 300.0], hi, gap) == \
        pytest.approx(math.sqrt(gap))


def test_bias_drift_u_on_the_protocols_static_record_is_neither_wide_nor_narrow():
    # the ADXRS610-class bench (RRW 36.7 °/h/√h, BI 22.3 °/h), 2-h records at 10 Hz as the
    # built-in IEC/JJF programmes take them: the term for Δt = 2 h against the model's own
    # drift variance K²Δt + 2(0.664 B)²; rms over 6 records within a factor 0.6–1.6
    g = load_rate_bench("mems-adxrs610").gyro
    gap = 7200.0
    true = math.hypot(g.rrw_dph_sqrt_h / 60.0 * math.sqrt(gap),
                      math.sqrt(2) * rg.FLICKER_FLOOR_EXACT * g.bias_instability_dph)
    us = []
    for s in range(6):
        y = NoiseState(g, np.random.default_rng(300 + s)).samples(72000, 0.1, 20.0) * S_PER_H
        a = allan_deviation(y, 0.1, "rate", "decade:10", unit="deg/h")
        f = fit_noise_model(a)
        us.append(rg.bias_drift_u(f.K, f.u_K, f.B, f.u_B, a.tau_s, a.ci_high, gap))
    ratio = math.sqrt(float(np.mean(np.square(us)))) / true
    assert 0.6 < ratio < 1.6, (ratio, us, true)


@pytest.mark.parametrize("first,second", [((18240.0, 60.0), (18305.0, 60.0)),     # 7.2.12 pair
                                          ((25008.0, 100.0), (28768.0, 100.0)),   # 7.2.14, 70 °C
                                          ((25008.0, 100.0), (34500.0, 100.0))])  # −40 °C
def test_record_difference_u_against_the_benchs_exact_covariance(first, second):
    """The difference of two record means under the fitted model's bias instability (flicker,
    generalised covariance) and rate random walk, against the exact covariance of the bench's
    own processes (a sum of Gauss–Markov terms for the bias instability, the walk from
    power-on: gonio.specs.jjf1535.truth.sample_noise_covariance) with the bench's B and K.
    The Allan floor √2·0.664·B that bias_drift_u holds at every separation reads the
    bias-instability part of the hour-apart 7.2.14 records low by about half."""
    from gonio.specs.jjf1535.truth import sample_noise_covariance

    b = load_rate_bench("mems-adxrs610")
    g = b.gyro
    K, B = g.rrw_dph_sqrt_h / math.sqrt(S_PER_H), g.bias_instability_dph   # °/h/√s, °/h

    def exact(gyro):
        n1, n2 = int(first[1]), int(second[1])
        t = np.concatenate([first[0] + np.arange(n1), second[0] + np.arange(n2)])
        C = sample_noise_covariance(replace(b, gyro=gyro), t, np.ones(t.size), 20.0)
        w = np.concatenate([-np.ones(n1) / n1, np.ones(n2) / n2])
        return math.sqrt(float(w @ C @ w)) * S_PER_H

    quiet = dict(arw_deg_sqrt_h=0.0, output_lsb=0.0)
    gm = exact(replace(g, rrw_dph_sqrt_h=0.0, **quiet))
    rw = exact(replace(g, bias_instability_dph=0.0, **quiet))
    big = [1e9]          # no bound on K from an Allan deviation here
    fl = rg.record_difference_u(0.0, 0.0, B, 0.0, [1.0], [0.0], first, second)
    walk = rg.record_difference_u(K, 0.0, 0.0, 0.0, [1.0], big, first, second)
    assert fl == pytest.approx(gm, rel=0.03)
    assert walk == pytest.approx(rw, rel=0.01)
    both = rg.record_difference_u(K, 0.0, B, 0.0, [1.0], big, first, second)
    assert both == pytest.approx(math.hypot(gm, rw), rel=0.03)
    if second[0] - first[0] > 1000:
        floor = math.sqrt(2) * rg.FLICKER_FLOOR_EXACT * B
        assert fl > 1.8 * floor
