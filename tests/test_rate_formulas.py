"""Rate-gyro formulas against hand-computed values: every number of the JJF 1535 and
IEC 62047-20 digests' "Numbers to reproduce", Annex A to the printed digits, and the
Allan-variance finding checked against a peer library (allantools)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.specs._rate_family import formulas as rg
from gonio.specs.jjf1535 import formulas as jf
from gonio.specs.iec62047_20 import formulas as ief
from gonio.errors import GonioError
from gonio.specs.jjf1535.budget import annex_a
from gonio.units import S_PER_H

R5 = [1, 1.6, 2.5, 4, 6.3, 10, 16, 25, 40, 63, 100]


# ----------------------------------------------------------------- JJF 1535 numbers
def test_annex_a_printed_digits():
    a = annex_a()
    u = [c[2] for c in a.scale_factor.components]
    assert [f"{v:.2e}" for v in u] == ["2.50e-04", "3.00e-05", "4.65e-04"]
    assert round(a.scale_factor.u_c, 7) == pytest.approx(5.288e-4, abs=1e-7)
    assert f"{a.scale_factor.u_c_stated:.3g}" == "0.000529"
    assert a.scale_factor.U == pytest.approx(1.0576e-3, rel=1e-4)
    assert a.scale_factor.U_stated == pytest.approx(1.1e-3)
    assert a.bias.u_c == pytest.approx(5.2985e-4, rel=1e-4)
    assert a.bias.u_c_stated == pytest.approx(5.30e-4)
    assert a.bias.U == pytest.approx(1.06e-3, rel=1e-3) and a.bias.U_stated == pytest.approx(1.1e-3)
    # from the unrounded u_c(K) the bias would be 5.2965e-4 (digest) — a different number
    assert math.hypot(3.0e-5, 5.288e-4) == pytest.approx(5.2965e-4, rel=1e-4)
    assert any("A.2.2" in s and "u1" in s for s in a.slips)


def test_r5_rates_and_counts():
    assert rg.r5_rates(1, 100) == R5 and len(R5) == 11


def test_earth_rate_numbers():
    assert rg.OMEGA_E_DPS == pytest.approx(4.178074e-3, rel=1e-6)
    assert rg.OMEGA_E_DPS * S_PER_H == pytest.approx(15.0411, abs=1e-4)
    up, north = rg.earth_rate_projection_dps(40, [0, 0, 1]), rg.earth_rate_projection_dps(40, [0, 1, 0])
    assert up * S_PER_H == pytest.approx(9.668, abs=1e-3)
    assert north * S_PER_H == pytest.approx(11.522, abs=1e-3)
    assert rg.earth_rate_projection_dps(40, [0, 0, -1]) == pytest.approx(-up)


def _example5():
    om = np.array([-r for r in R5] + R5, float)
    F = np.where(om > 0, 10.02 * om, 9.98 * om) - 2.0e-6 * om ** 3
    return om, F


def test_scale_factor_nonlinearity_asymmetry_example():
    om, F = _example5()
    fit = jf.fit_scale_factor(om, F)
    assert fit.K == pytest.approx(9.985702, abs=1e-6)
    assert fit.F0 == pytest.approx(0.489818, abs=1e-6)
    i = int(np.argmax(np.abs(fit.residuals)))
    assert abs(fit.residuals[i]) == pytest.approx(2.080420, abs=1e-6) and om[i] == -100
    assert fit.K * 200 == pytest.approx(1997.1405, abs=1e-4)
    assert jf.nonlinearity_jjf(fit) == pytest.approx(1.0417e-3, abs=5e-8)
    measured_span = F[om == 100][0] - F[om == -100][0]
    assert measured_span == pytest.approx(1996.00, abs=1e-2)
    assert abs(fit.residuals[i]) / measured_span == pytest.approx(1.0423e-3, abs=5e-8)
    assert abs(fit.residuals[i]) / abs(F).max() == pytest.approx(2.0804e-3, abs=5e-8)
    a = jf.asymmetry_jjf(om, fit.means)
    assert (a.K_pos, a.F0_pos) == pytest.approx((10.002814, 0.178162), abs=1e-6)
    assert (a.K_neg, a.F0_neg) == pytest.approx((9.962814, -0.178162), abs=1e-6)
    assert a.value == pytest.approx(4.0069e-3, abs=5e-8)
    assert jf.asymmetry_jjf(om, fit.means, mean_of="all", K_all=fit.K).value == \
        pytest.approx(4.0057e-3, abs=5e-8)


def test_rest_points_refused_as_fit_points():
    with pytest.raises(GonioError, match="rest point"):
        jf.fit_scale_factor([0.0, 1.0, 2.0], [0.0, 1.0, 2.0])


def test_repeatability_and_temperature_sensitivities():
    m, s, r = jf.relative_std([10.0000, 10.0012, 9.9991])
    assert (round(m, 4), s, r) == (10.0001, pytest.approx(1.0536e-3, rel=1e-4),
                                   pytest.approx(1.0536e-4, rel=1e-4))
    kt, sl = jf.temperature_sensitivity([10.0, 10.03, 9.97], [20, 70, -40], 0, relative=True)
    assert kt == pytest.approx(6.0e-5) and sl[2] == pytest.approx(5.0e-5)
    bt, sl = jf.temperature_sensitivity([36, 61, -12], [20, 70, -40], 0, relative=False)
    assert (bt, sl[1]) == (pytest.approx(0.8), pytest.approx(0.5))


def test_bias_and_stability_example():
    F = np.array([0.10, 0.12, 0.08, 0.11, 0.09, 0.13, 0.07, 0.10])
    assert F.mean() / 10.0 == pytest.approx(0.01) and F.mean() / 10 * S_PER_H == pytest.approx(36.0)
    assert F.reshape(4, 2).mean(1) == pytest.approx([0.110, 0.095, 0.110, 0.085])
    bs = rg.block_mean_stability(F, 10.0, 2)
    assert bs == pytest.approx(1.2247e-3, abs=1e-7) and bs * S_PER_H == pytest.approx(4.409, abs=1e-3)


def test_g_sensitivity_earth_rate_example():
    e = rg.earth_rate_projection_dps(40, [0, 0, 1]) * S_PER_H
    up, down = 35 + 5 + e, 35 - 5 - e
    assert (up, down) == (pytest.approx(49.668, abs=1e-3), pytest.approx(20.332, abs=1e-3))
    assert jf.g_sensitivity_axis(up, down) == pytest.approx(14.668, abs=1e-3)
    assert jf.g_sensitivity_axis(up, down, e, -e) == pytest.approx(5.000, abs=1e-9)


def test_threshold_example():
    c, dev = jf.fifty_percent_candidate([0.05, 0.02, 0.01, 0.005], [0.49, 0.21, 0.06, 0.01],
                                        [0.5, 0.2, 0.1, 0.05])
    assert c == 0.01 and dev == pytest.approx([0.02, 0.05, 0.40, 0.80])
    # the first step failing gives no candidate
    assert jf.fifty_percent_candidate([0.1], [0.0], [1.0])[0] is None


def test_bandwidth_grid_and_second_order():
    assert jf.bandwidth_grid(70) == [10, 20, 30, 40, 50, 60, 65, 70, 75, 80]
    assert jf.bandwidth_grid(100) == [13.75, 27.5, 41.25, 55, 68.75, 82.5, 96.25, 98.125, 100,
                                      105, 110]
    assert rg.MINUS_3DB_RATIO == pytest.approx(0.70795, abs=1e-5)
    f = np.linspace(100, 150, 50001)
    g, p = rg.second_order_response(f, 100.0, 0.5)
    assert f[np.argmin(np.abs(20 * np.log10(g) + 3.0))] == pytest.approx(127.12, abs=0.01)
    assert f[np.argmin(np.abs(g - 1 / math.sqrt(2)))] == pytest.approx(127.20, abs=0.01)
    g, p = rg.second_order_response([100.0], 100.0, 0.5)
    assert p[0] == pytest.approx(-90.0) and 20 * math.log10(g[0]) == pytest.approx(0.0, abs=1e-12)
    # crossing by log-f interpolation on a dense grid reproduces the exact value
    ff = np.geomspace(10, 300, 400)
    gg, pp = rg.second_order_response(ff, 100.0, 0.5)
    assert rg.minus3db_frequency(ff, gg, reference=1.0) == pytest.approx(127.12, abs=0.02)
    assert rg.phase90_frequency(ff, pp) == pytest.approx(100.0, abs=0.01)


def test_arw_units_and_floor_factor():
    assert jf.arw_from_coefficient(0.0064, rate_unit="deg/h", tau_unit="h") == pytest.approx(0.08)
    assert math.sqrt(23.04) == pytest.approx(4.8)
    assert jf.arw_from_coefficient(23.04, rate_unit="deg/h", tau_unit="s") == pytest.approx(0.08)
    assert rg.FLICKER_FLOOR_EXACT == pytest.approx(0.664282, abs=1e-6)
    assert ief.bias_instability_floor([2.0, 0.4, 0.5])[0] == pytest.approx(0.6021, abs=1e-4)


def test_allan_estimator_guard_printed_vs_overlapping():
    """Digest check 14: unit white noise → AVAR 1/k; printed eq (24): 3 at k = 1, 2/k²."""
    x = np.random.default_rng(5).standard_normal(400_000)
    for k in (1, 2, 4, 8):
        assert jf.allan_variance_overlapping(x, k) == pytest.approx(1.0 / k, rel=0.03)
    assert jf.allan_variance_printed_jjf(x, 1) == pytest.approx(3.0, rel=0.03)
    for k, v in ((2, 0.5), (4, 0.125), (8, 0.03125)):
        assert jf.allan_variance_printed_jjf(x, k) == pytest.approx(v, rel=0.05)
    # non-overlapping Hadamard-with-½ reading gives 3/k
    k = 4
    m = x[: x.size // k * k].reshape(-1, k).mean(1)
    had = np.sum((m[2:] - 2 * m[1:-1] + m[:-2]) ** 2) / (2 * (m.size - 2))
    assert had == pytest.approx(3.0 / k, rel=0.05)


def test_overlapping_avar_matches_allantools():
    allantools = pytest.importorskip("allantools")
    x = np.random.default_rng(7).standard_normal(20000) + np.cumsum(
        0.01 * np.random.default_rng(8).standard_normal(20000))
    ms = [1, 3, 10, 30, 100]
    t, ad, _, _ = allantools.oadev(x, rate=1.0, data_type="freq", taus=np.array(ms, float))
    ours = [math.sqrt(jf.allan_variance_overlapping(x, m)) for m in ms]
    assert ours == pytest.approx(list(ad), rel=1e-9)


# ----------------------------------------------------------------- IEC 62047-20 numbers
IEC_Y = [704.50, 1062.82, 1421.66, 1780.89, 2140.38, 2500.00, 2860.34, 3220.55, 3580.50,
         3940.06, 4299.10]
IEC_X = [-300 + 60 * i for i in range(11)]


def test_iec_earth_components_and_erratum():
    up = rg.earth_rate_projection_dps(35, [0, 0, 1])
    north = rg.earth_rate_projection_dps(35, [0, 1, 0])
    az60 = rg.earth_rate_projection_dps(35, [math.sin(math.radians(60)), math.cos(math.radians(60)), 0])
    east = rg.earth_rate_projection_dps(35, [1, 0, 0])
    assert (up, north, az60) == (pytest.approx(2.3964e-3, abs=1e-7), pytest.approx(3.4224e-3, abs=1e-7),
                                 pytest.approx(1.7112e-3, abs=1e-7))
    assert abs(east) < 1e-18
    # the misprinted vertical component (Ω cos λ) is the horizontal-north one
    assert rg.OMEGA_E_DPS * math.cos(math.radians(35)) == pytest.approx(north)
    assert 0.012 - up == pytest.approx(0.009604, abs=1e-6)
    assert 0.012 - north == pytest.approx(0.008578, abs=1e-6)


def test_iec_noise_numbers():
    tau = np.geomspace(1, 3600, 30)
    arw, mask = ief.arw_minus_half_line(tau, 4.8 / np.sqrt(tau))
    assert arw == pytest.approx(0.08) and mask.all()
    assert 4.8 / math.sqrt(3600) == pytest.approx(0.08)
    assert 0.4 / 0.664 == pytest.approx(0.602, abs=1e-3)
    assert 2 * 0.5 / 200 == pytest.approx(0.005)                        # 5.2.4: 0.5 %
    assert ief.cross_axis_iec(3.0, 0.0, 6.0, 100.0) == pytest.approx(0.005)
    assert ief.voltage_corrected(1000.00, 5.0, 4.9998) == pytest.approx(1000.04, abs=5e-3)
    assert 5.0 / 4.9998 == pytest.approx(1.00004, abs=1e-8)
    c, _ = jf.fifty_percent_candidate([0.01], [0.005], [0.01])          # 5.6.3: exactly 50 %
    assert c == 0.01


def test_iec_scale_factor_linearity_symmetry():
    a, b = rg.least_squares_line(IEC_X, IEC_Y)
    assert (a, b) == (pytest.approx(5.993600, abs=1e-6), pytest.approx(2500.981818, abs=1e-6))
    L, a2, b2, fs = ief.linearity_errors_iec(IEC_X, IEC_Y)
    assert fs == pytest.approx(3594.60)
    assert 100 * L == pytest.approx([0.044461, 0.008407, -0.013181, -0.023920, -0.027425,
                                     -0.027314, -0.007172, 0.009352, 0.018644, 0.017086,
                                     0.001062], abs=2e-6)
    s, aw, bw, ac, bc = ief.symmetry_iec(IEC_X, IEC_Y, 6.0)
    assert (aw, ac) == (pytest.approx(5.995050, abs=1e-6), pytest.approx(5.983050, abs=1e-6))
    assert (bw, bc) == (pytest.approx(2501.001, abs=1e-3), pytest.approx(2498.999, abs=1e-3))
    assert 100 * s == pytest.approx(0.2000, abs=1e-4)
    assert 100 * (a - 6.0) / 6.0 == pytest.approx(-0.10667, abs=1e-5)
    assert 2 * 5 + 1 == 11 and 11 * 5 == 55 and 11 * 3 == 33


def test_iec_temperature_ratiometric_stability():
    lo, hi = -40.0, 85.0
    tb = (lo + hi) / 2
    T = [lo + i * (hi - lo) / 4 for i in range(5)]
    assert tb == 22.5 and T == [-40, -8.75, 22.5, 53.75, 85]
    aT = [5.970, 5.985, 6.000, 6.012, 6.030]
    assert [100 * (v - 6.0) / 6.0 for v in aT] == pytest.approx([-0.5, -0.25, 0, 0.2, 0.5])
    s, c = rg.least_squares_line(T, aT)
    assert (s, c) == (pytest.approx(4.704e-4, abs=1e-7), pytest.approx(5.988816, abs=1e-6))
    assert 100 * s / 6.0 == pytest.approx(0.00784, abs=1e-5)
    R = [ief.ratiometric_error_iec(av, 6.0, v, 5.0) for av, v in ((5.403, 4.5), (6.0, 5.0), (6.597, 5.5))]
    assert [100 * r for r in R] == pytest.approx([0.05, 0.0, -0.05], abs=1e-9)
    assert [100 * (av - 6) / 6 for av in (5.403, 6.597)] == pytest.approx([-9.95, 9.95])
    y = np.array([1801.0, 1801.2, 1800.8, 1801.1, 1800.9])
    assert np.std(y, ddof=0) / 3594.60 == pytest.approx(3.9343e-5, abs=1e-8)
    assert np.std(y, ddof=1) / 3594.60 == pytest.approx(4.3987e-5, abs=1e-8)


def test_eda_equal_division_numbers():
    """IEC Annex A.3 (digest check 16): averaging n equally spaced copies keeps only the
    harmonics whose order is a multiple of n."""
    th = np.linspace(0, 2 * np.pi, 720, endpoint=False)

    def e(t):
        return 2 * np.sin(t) + 1 * np.sin(2 * t + 0.3) + 0.5 * np.sin(8 * t)

    for n, expect in ((4, 0.5 * np.sin(8 * th)), (8, 0.5 * np.sin(8 * th)), (3, 0 * th)):
        avg = np.mean([e(th + 2 * np.pi * j / n) for j in range(n)], axis=0)
        assert avg == pytest.approx(expect, abs=1e-12)


def test_asymmetry_slope_u_against_monte_carlo():
    """JJF 7.2.3's two terms against the signed K_a of eq (8) computed by asymmetry_jjf on
    simulated means: white noise of the means, and a once-per-revolution table ripple of
    random phase averaged (numerically, on a fine grid) over each point's sampled turn."""
    rng = np.random.default_rng(11)
    om = np.array([1, 2.5, 6.3, 16, 40, 100, -1, -2.5, -6.3, -16, -40, -100], float)
    spans, K, r, sigma = np.full(om.size, 5.0), 2.0, 1e-3, 0.01
    u_n, u_r = jf.asymmetry_slope_u(om, sigma, spans, r, K)
    n = 4000
    noisy = [jf.asymmetry_jjf(om, K * om + sigma * rng.standard_normal(om.size)).signed
             for _ in range(n)]
    frac = (np.arange(2000) + 0.5) / 2000
    turn = np.radians(np.abs(om) * spans)[:, None] * frac[None, :]
    rippled = []
    for _ in range(n):
        psi = rng.uniform(0, 2 * np.pi, om.size)
        e = r * np.sin(psi[:, None] + turn).mean(axis=1)          # mean relative rate error
        rippled.append(jf.asymmetry_jjf(om, K * (om + np.abs(om) * e)).signed)
    assert np.std(noisy) == pytest.approx(u_n, rel=0.05)
    assert np.std(rippled) == pytest.approx(u_r, rel=0.05)
    assert u_r > 0.1 * r          # not attenuated to nothing: the low rates keep the ripple


def test_ripple_residual_sd_against_monte_carlo():
    """JJF 7.2.2: the table ripple's share of each residual of the line (5), and of eq (6)'s
    largest |residual|, against a Monte Carlo: a once-per-revolution ripple of random phase
    (independent per point) averaged numerically, on a fine grid, over each point's sampled
    turn, the line fitted by fit_scale_factor and eq (6)'s numerator taken as printed."""
    rng = np.random.default_rng(12)
    one = np.array([1, 1.6, 2.5, 4, 6.3, 10, 16, 25, 40, 63, 100], float)
    om = np.concatenate([one, -one])
    spans, K, r = np.full(om.size, 5.0), 6.0, 1e-3
    # asymmetry, quadratic and cubic terms: the largest residual (−100 °/s) stands 0.34 clear
    # of the next, 3.5 standard deviations of their ripple difference
    f_true = K * om * (1 + 1e-3 * np.sign(om)) + 1e-5 * K * om ** 2 + 1e-7 * K * om ** 3
    sd = jf.ripple_residual_sd(om, spans, r, K)
    frac = (np.arange(2000) + 0.5) / 2000
    turn = np.radians(np.abs(om) * spans)[:, None] * frac[None, :]
    v0 = jf.fit_scale_factor(om, f_true).residuals
    j = int(np.argmax(np.abs(v0)))
    res, top = [], []
    for _ in range(4000):
        psi = rng.uniform(0, 2 * np.pi, om.size)
        e = r * np.sin(psi[:, None] + turn).mean(axis=1)          # mean relative rate error
        v = jf.fit_scale_factor(om, f_true + K * np.abs(om) * e).residuals
        res.append(v - v0)
        top.append(np.max(np.abs(v)) - np.abs(v0[j]))
    assert np.std(res, axis=0) == pytest.approx(sd, rel=0.06)
    assert np.std(top) == pytest.approx(sd[j], rel=0.06)     # the maximum stays at j
    assert abs(np.mean(top)) < 0.1 * sd[j]
    # without turn averaging the largest rates carry r·|Ω|/√2 less the line's share
    flat = jf.ripple_residual_sd(om, np.full(om.size, 1e-9), r, K)
    assert flat[j] > sd[j] > 0.1 * flat[j]
