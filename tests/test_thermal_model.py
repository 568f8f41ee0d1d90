"""The extended MEMS-gyro model (issue 18, [Vagner2015]): exact identification without
noise, order selection against its own statistics, uncertainty coverage over seeds,
compensation by the expected factor, the ramp error of a static-soak model and its lag,
ARW(ϑ), and the thesis's ADXRS610 noise model.

Independent references: the bench's true coefficients, Student-t coverage, binomial
bounds, the closed-form Allan variance of white + flicker + random-walk noise (IEEE 952
Annex C), the steady-state lag of a first-order system on a ramp (T_c − τ·dT/dt).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from gonio.analysis.noise import allan_deviation, fit_noise_model
from gonio.specs.triad_alignment.thermal_model import (compensate_record, fit_polynomial,
                                                      identify_thermal_model)
from gonio.specs.triad_alignment.bench import (ThermalModel, TriadBench, TriadNoise, TriadProtocol,
                               _alternating, run_thermal_session)
from gonio.cli import main
from gonio.formats.jsonsafe import json_safe
from gonio.specs.triad_alignment.readings import TriadReadings, format_triad_readings
from gonio.units import deg_sqrt_s_from_deg_sqrt_h, dps_to_dph

K0, B0 = 49.7, 0.08
BT = (1.0e-3, -4.0e-5, 5.0e-7)         # bias, °/s per °C^j
KT = (1.2e-4, -1.0e-6)                 # scale, relative per °C^j
BU, KU = (0.4,), (-0.012,)
AT = (5.0e-3, 2.0e-5)                  # ARW relative per °C^j


def tbench(arw=0.3, tau=0.0, fs=10.0, offset=0.0) -> TriadBench:
    th = ThermalModel(25.0, 5.0, tau, ((0.0,), (0.0,), BT), ((0.0,), (0.0,), KT),
                      ((0.0,), (0.0,), BU), ((0.0,), (0.0,), KU), ((0.0,), (0.0,), AT), offset)
    return TriadBench("t", 49.2, fs, "i", "s", "lsb", (50.0, 50.0, K0), np.zeros((3, 3)),
                      (0.0, 0.0, 0.0), np.zeros((3, 3)), (0.0, 0.0, B0), (arw,) * 3, (0.0,) * 3,
                      (0.0,) * 3, thermal=th)


def tproto(setpoints=(-40.0, -20.0, 0.0, 20.0, 40.0, 60.0, 85.0), soak=60.0, ramp=5.0,
           dwell=7.2, static=30.0, volts=(4.75, 5.0, 5.25)) -> TriadProtocol:
    th = {"enabled": True, "up": ["+z"], "setpoints_c": list(setpoints), "start_c": 25.0,
          "supply_v": list(volts), "ramp_c_per_min": ramp, "soak_s": soak, "rate_dps": 100.0,
          "dwell_s": dwell, "static_dwell_s": static, "ramp_block_s": 60.0, "sample_rate_hz": 0.0}
    return TriadProtocol("t", "triad-alignment", (100.0,), 1, 0.0, False, 1.0,
                         {"x": "+y", "y": "+z", "z": "+x"}, 0.0, th)


def readings(s) -> TriadReadings:
    return TriadReadings(s.readings.assign(line=np.arange(len(s.readings))), s.metadata, "t.csv")


def true_bias(theta, u):
    return B0 + sum(c * theta ** (j + 1) for j, c in enumerate(BT)) + BU[0] * u


def true_scale(theta, u):
    return K0 * (1 + sum(c * theta ** (j + 1) for j, c in enumerate(KT)) + KU[0] * u)


FIXED = {"scale": (2, 1), "bias": (3, 1), "arw": (2, 0)}


def test_exact_identification_without_noise():
    r = readings(run_thermal_session(tproto(), tbench(arw=0.0), seed=0))
    m = identify_thermal_model(r, fixed_orders=FIXED).channels["z"]
    k = m.scale.coefficients()
    assert k["c0"] == pytest.approx(K0, rel=1e-10)
    assert k["theta1"] == pytest.approx(K0 * KT[0], rel=1e-7)
    assert k["theta2"] == pytest.approx(K0 * KT[1], rel=1e-7)
    assert k["u1"] == pytest.approx(K0 * KU[0], rel=1e-8)
    b = m.bias.coefficients()
    assert [b["c0"], b["theta1"], b["theta2"], b["theta3"], b["u1"]] == pytest.approx(
        [B0, *BT, BU[0]], rel=1e-6)
    # no lag, no noise: the only ramp "error" is the block mean of a curved b(ϑ) over the
    # 5 °C each 60 s block spans: mean − value at the mean = β2 Δ²/12 + β3 ϑ̄ Δ²/4
    th = np.asarray(m.ramp.theta_c)
    jensen = BT[1] * 25.0 / 12.0 + BT[2] * th * 25.0 / 4.0
    assert np.sqrt(np.mean(np.asarray(m.ramp.residual_dps) ** 2)) == pytest.approx(
        np.sqrt(np.mean(jensen ** 2)), rel=0.1)
    # a wrong Earth rate (latitude) leaves an error: the test can fail
    r.metadata["latitude_deg"] = "-49.2"
    b2 = identify_thermal_model(r, fixed_orders=FIXED).channels["z"].bias.coefficients()
    assert abs(b2["c0"] - B0) > 1e-3


def test_order_selection_rates_match_their_statistics():
    """Synthetic points, true orders (3 in ϑ, 1 in U): BIC keeps the truth with probability
    ≈ (1 − P(χ²₁ > ln n))² (two spurious candidates), the forward F-test with
    ≈ (1 − 0.05)²; neither underfits a strong cubic. Binomial 3.5σ bounds."""
    rng = np.random.default_rng(12)
    th = np.repeat(np.array([-65.0, -45.0, -25.0, -5.0, 15.0, 35.0, 60.0, 0.0]), 3)
    u = np.tile([-0.25, 0.0, 0.25], 8)
    n, trials = th.size, 300
    ok = {"bic": 0, "ftest": 0}
    under = 0
    for _ in range(trials):
        y = true_bias(th, u) + 0.002 * rng.standard_normal(n)
        for crit in ok:
            f = fit_polynomial("b", th, u, y, criterion=crit)
            ok[crit] += (f.n_t, f.n_u) == (3, 1)
            under += f.n_t < 3 or f.n_u < 1
    assert under == 0
    p_bic = (1 - stats.chi2.sf(math.log(n), 1)) ** 2
    p_f = (1 - 0.05) ** 2
    for crit, p in (("bic", p_bic), ("ftest", p_f)):
        sd = math.sqrt(p * (1 - p) / trials)
        assert abs(ok[crit] / trials - p) < 3.5 * sd + 0.02, (crit, ok[crit] / trials, p)


def test_parameter_and_prediction_uncertainty_coverage():
    """White noise, true orders: coefficient and prediction intervals with
    k = t_{0.9545,ν} cover at least 95.45 % (within 3.5 binomial sd; a u 20 % small is
    rejected) and at most 99 %: without a shared soak error about half the draws see soak
    means scattering less than the points within a soak, and the "never pool" rule of
    :func:`soak_covariance` (issue 24) keeps their ν_b, so the intervals are conservative
    there — the price of covering when a shared error is present and hidden."""
    b = tbench()
    p = tproto()
    n_seeds = 120
    hits, pred_hits = [], []
    nu = None
    grid = np.linspace(-60.0, 55.0, 6)
    for seed in range(n_seeds):
        m = identify_thermal_model(readings(run_thermal_session(p, b, seed=seed)),
                                   fixed_orders=FIXED, ramps=False).channels["z"]
        for fit, truth in ((m.scale, [K0, K0 * KT[0], K0 * KT[1], K0 * KU[0]]),
                           (m.bias, [B0, *BT, BU[0]])):
            c = fit.coefficients()
            est = [c[k] for k in c if not k.startswith("u_")]
            terms = [k for k in c if not k.startswith("u_")]
            unc = [c["u_" + k] for k in terms]
            kf = [stats.t.ppf(0.5 + 0.9545 / 2, fit.dof_of(k)) for k in terms]
            hits += [abs(e - t) <= kk * s for e, t, s, kk in zip(est, truth, unc, kf)]
            nu = fit.dof
        kb = stats.t.ppf(0.5 + 0.9545 / 2, m.bias.dof)
        pred_hits += list(np.abs(m.bias.predict(grid, 0.1) - true_bias(grid, 0.1))
                          <= kb * m.bias.u_predict(grid, 0.1))
    cov = float(np.mean(hits))
    n = len(hits)
    sd = math.sqrt(0.9545 * 0.0455 / n)
    lo, hi = 0.9545 - 3.5 * sd, 0.99
    k = stats.t.ppf(0.5 + 0.9545 / 2, nu)
    assert 2 * stats.t.cdf(k * 0.8, nu) - 1 < lo
    assert lo <= cov <= hi, (cov, lo, hi)
    # predictions at 6 temperatures share one fit: correlated, looser check; k is the
    # fit's smallest ν, ν_b where the floor applied, so no upper bound here (the
    # coefficients' ≤ 99 % above is the over-wide guard)
    assert 0.90 <= np.mean(pred_hits), np.mean(pred_hits)


def test_selected_model_predicts_within_uncertainty_and_arw():
    r = readings(run_thermal_session(tproto(), tbench(), seed=3))
    m = identify_thermal_model(r).channels["z"]
    assert m.bias.n_t >= 3 and m.bias.n_u >= 1 and m.scale.n_t >= 2 and m.scale.n_u >= 1
    g = np.linspace(-60, 55, 12)
    for u in (-0.25, 0.0, 0.25):
        kb = stats.t.ppf(0.99865, m.bias.dof)
        assert np.all(np.abs(m.bias.predict(g, u) - true_bias(g, u)) <= kb * m.bias.u_predict(g, u))
        kk = stats.t.ppf(0.99865, m.scale.dof)
        assert np.all(np.abs(m.scale.predict(g, u) - true_scale(g, u))
                      <= kk * m.scale.u_predict(g, u))
    a = m.arw.coefficients()
    assert abs(a["c0"] - 0.3) < 3 * a["u_c0"] + 0.003      # sample-sd estimate, n = 300
    # the thesis's ~0.5 %/°C ARW rise, recovered from the static dwells
    assert a["theta1"] / a["c0"] == pytest.approx(AT[0], abs=3 * a["u_theta1"] / a["c0"])


def test_compensation_reduces_residuals_by_the_expected_factor():
    b = tbench()
    model = identify_thermal_model(readings(run_thermal_session(tproto(), b, seed=1)),
                                   fixed_orders=FIXED).channels["z"]
    new = readings(run_thermal_session(
        tproto(setpoints=(-35.0, -25.0, -10.0, 5.0, 15.0, 30.0, 45.0, 55.0, 70.0, 80.0)), b, seed=2))
    c = compensate_record(model, new)
    pts = c.points
    before_truth = np.sqrt(np.mean((true_bias(pts.theta_c, pts.u_v) - B0) ** 2))
    assert c.rms_bias_before_dps == pytest.approx(before_truth, rel=0.02)
    expected_after = math.sqrt(model.bias.s ** 2
                               + np.mean(model.bias.u_predict(pts.theta_c, pts.u_v) ** 2))
    ratio = c.rms_bias_after_dps / expected_after
    assert 0.6 < ratio < 1.4, ratio
    factor = c.rms_bias_before_dps / c.rms_bias_after_dps
    assert factor == pytest.approx(before_truth / expected_after, rel=0.45)
    assert factor > 30
    k_before = np.sqrt(np.mean((true_scale(pts.theta_c, pts.u_v) / K0 - 1) ** 2))
    assert c.rms_scale_before_rel == pytest.approx(k_before, rel=0.02)
    assert c.rms_scale_after_rel < k_before / 50
    # on the ramps too
    assert c.rms_ramp_after_dps < c.rms_ramp_before_dps / 20


def test_ramp_error_of_a_static_soak_model_and_the_lag():
    """τ = 300 s between chamber and die. Modelled on the chamber temperature, the
    static-soak model errs on ramps by ≈ b(T_c − τ dT/dt) − b(T_c); the fitted lag recovers
    τ; on the internal sensor (which follows the die) there is no ramp error."""
    tau = 300.0
    b = tbench(tau=tau)
    p = tproto(soak=6 * tau, ramp=1.0)
    r = readings(run_thermal_session(p, b, seed=6))
    ch = identify_thermal_model(r, temperature="chamber", fixed_orders=FIXED).channels["z"]
    se = identify_thermal_model(r, temperature="sensor", fixed_orders=FIXED).channels["z"]
    ra = ch.ramp
    th = np.asarray(ra.theta_c)
    rate = np.asarray(ra.dtheta_dt)
    steady = np.abs(rate) > 0.5 * (1.0 / 60.0)               # on the ramp, not at its ends
    lag_err = true_bias(th - tau * rate, 0.0) - true_bias(th, 0.0)
    resid = np.asarray(ra.residual_dps)
    assert np.sqrt(np.mean(resid[steady] ** 2)) == pytest.approx(
        np.sqrt(np.mean(lag_err[steady] ** 2)), rel=0.25)
    assert ra.tau_s == pytest.approx(tau, rel=0.15)
    # its 95 % interval holds the bench's τ; on the sensor (no lag) no lag is resolved
    assert ra.tau_resolved and ra.lag_case == "fit"
    assert ra.tau_low_s <= tau <= ra.tau_high_s, (ra.tau_low_s, ra.tau_high_s)
    assert not se.ramp.tau_resolved and se.ramp.tau_low_s == 0.0
    assert se.ramp.lag_text().startswith("not resolved")
    assert ra.rms_with_lag_dps < 0.3 * ra.rms_static_model_dps
    assert ra.hysteresis_dps > 5 * se.ramp.rms_static_model_dps
    assert se.ramp.rms_static_model_dps < 0.2 * ra.rms_static_model_dps
    assert ra.rms_with_ramp_term_dps < ra.rms_static_model_dps


def test_thesis_adxrs610_noise_model():
    """[Vagner2015] §5.3: ADXRS610 approximated by ARW 1.8 °/√h, BI 22.3 °/h,
    RRW 36.7 °/h/√h. The bench's noise reproduces the IEEE 952 Allan deviation of those
    terms; the fitted ARW is 1.8 °/√h; the model's Allan minimum is at √3 N/K ≈ 306 s (the
    thesis reads ≈ 250 s off its measured curve, one of its tested averaging times)."""
    arw, bi, rrw = 1.8, 22.3, 36.7
    b = TriadBench("adxrs610", 49.2, 10.0, "i", "s", "lsb", (1.0,) * 3, np.zeros((3, 3)),
                   (0.0,) * 3, np.zeros((3, 3)), (0.0,) * 3, (arw,) * 3, (bi,) * 3, (rrw,) * 3)
    nz = TriadNoise(b, np.random.default_rng(2015))
    y = np.concatenate([nz.block(36_000) for _ in range(4)], axis=1)     # 4 × 1 h at 10 Hz
    n_dph_sqrt_s = dps_to_dph(deg_sqrt_s_from_deg_sqrt_h(arw))            # (°/h)·√s
    k_dph_per_sqrt_s = deg_sqrt_s_from_deg_sqrt_h(rrw)                      # (°/h)/√s
    for i in range(3):
        res = allan_deviation(dps_to_dph(y[i]), 0.1, "rate", taus="octave")
        sel = (res.tau_s >= 0.5) & (res.tau_s <= 60.0)
        model = np.sqrt(n_dph_sqrt_s ** 2 / res.tau_s + 2 * math.log(2) / math.pi * bi ** 2
                        + k_dph_per_sqrt_s ** 2 * res.tau_s / 3)
        assert np.all(np.abs(res.adev[sel] / model[sel] - 1) < 0.08)
        fit = fit_noise_model(res, terms=("N", "B", "K"))
        assert fit.N * deg_sqrt_s_from_deg_sqrt_h(1.0) == pytest.approx(arw, rel=0.03)
    tau_min = math.sqrt(3) * n_dph_sqrt_s / k_dph_per_sqrt_s
    assert tau_min == pytest.approx(305.8, abs=0.1)
    assert 250.0 <= tau_min <= 500.0          # between the thesis's tested 250 s and 500 s


def test_alternating_supply_order():
    assert _alternating([4.75, 5.0, 5.25]) == [5.0, 5.25, 4.75]


def test_cli_thermal_model(tmp_path, capsys):
    p = tproto(setpoints=(-20.0, 10.0, 40.0, 70.0), soak=30.0, ramp=10.0)
    for seed, name in ((1, "a.csv"), (2, "b.csv")):
        s = run_thermal_session(p, tbench(), seed=seed)
        (tmp_path / name).write_text(format_triad_readings(s.readings, s.metadata))
    png = tmp_path / "t.png"
    assert main(["thermal-model", str(tmp_path / "a.csv"), "--json", "--compensate",
                 str(tmp_path / "b.csv"), "--plot", str(png), "--criterion", "ftest"]) == 0
    out = json.loads(capsys.readouterr().out)
    z = out["channels"]["z"]
    assert z["bias"]["criterion"] == "ftest" and out["compensation"]["z"]["rms_bias_after_dps"] < 0.01
    assert png.stat().st_size > 1000
    assert main(["thermal-model", str(tmp_path / "a.csv"), "--report", str(tmp_path / "t.html"),
                 "--compensate", str(tmp_path / "b.csv")]) == 0
    assert "gyro z" in capsys.readouterr().out
    page = (tmp_path / "t.html").read_text()
    assert "Temperature and supply model" in page and "bias rms" in page and "<svg" in page
    assert main(["thermal-model", str(tmp_path / "a.csv"), "--plot", str(tmp_path / "x.bmp")]) == 2
    assert ".bmp" in capsys.readouterr().err


def test_cli_plot_needs_a_gyro_choice_when_several(tmp_path, capsys):
    p = tproto(setpoints=(0.0, 40.0), soak=10.0, ramp=20.0)
    p.thermal["up"] = ["+z", "+x"]
    s = run_thermal_session(p, tbench(), seed=1)
    f = tmp_path / "two.csv"
    f.write_text(format_triad_readings(s.readings, s.metadata))
    assert main(["thermal-model", str(f), "--plot", str(tmp_path / "p.png")]) == 2
    assert "--gyro" in capsys.readouterr().err
    assert main(["thermal-model", str(f), "--plot", str(tmp_path / "p.png"), "--gyro", "x"]) == 0
    assert (tmp_path / "p.png").stat().st_size > 1000


def test_lag_interval_on_the_built_in_programme_covers_and_never_states_a_bound():
    """Issue 24: on the built-in programme the chamber-to-die lag (bench τ = 300 s) lies in
    the fitted lag's 95 % interval (the first-order-hold discretisation: a zero-order hold
    biased τ̂ by +30 s, half a 60 s block, outside every interval); fed with the internal
    sensor (no lag on the bench) the lag is stated 'not resolved' with its upper bound,
    never as the search's bound τ̂ = 0 (seed 3 printed 'lag τ fit 0 s')."""
    from gonio.specs.triad_alignment.bench import load_triad_bench, load_triad_protocol
    from gonio.specs.triad_alignment.certificate import lag_phrase

    p, b = load_triad_protocol("triad-alignment"), load_triad_bench("mems-triad")
    taus = []
    for seed in (3, 5):
        r = readings(run_thermal_session(p, b, seed=seed))
        ch = identify_thermal_model(r, temperature="chamber").channels["z"].ramp
        se = identify_thermal_model(r, temperature="sensor").channels["z"].ramp
        assert ch.tau_resolved and ch.tau_low_s <= 300.0 <= ch.tau_high_s, ch.lag_text()
        taus.append(ch.tau_s)
        assert se.lag_case == "bound" and se.tau_high_s < 60.0, se.lag_text()
        for lang in ("en", "zh"):
            text = lag_phrase(json_safe(se.to_json()), lang)
            assert "τ ≤" in text and "τ = " not in text, text
        assert lag_phrase(json_safe(ch.to_json()), "en").startswith(f"τ = {ch.tau_s:.0f} s")
    assert abs(np.mean(taus) - 300.0) < 15.0, taus
