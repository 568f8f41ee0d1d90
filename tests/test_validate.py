"""gonio.pipeline.validate: determinism, the ideal bench, a broken budget, binomial u, the coupling
closed form against numerical integration, and the CLI."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import integrate, stats

from gonio.specs.ogam_draft.bench import Bench, InstrumentConfig, TableConfig, run_session
from gonio.specs.ogam_draft.bench.instrument import geometry
from gonio.cli import main
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.specs.ogam_draft.budget_extra import tilt_coupling_coefficients
from gonio.physics.earth import earth_rate_split
from gonio.pipeline.validate import binomial_u, coverage, validate
from gonio.specs.ogam_draft.study import trial_seeds
from gonio.units import dps_to_arcsec_s


def earth_rate_perpendicular_arcsec_s(latitude_deg, orientation="up"):
    return dps_to_arcsec_s(earth_rate_split(latitude_deg, orientation).perpendicular_dps)

K_NOM = 76434.87


def tiny_protocol(series=3):
    """7.1 and 7.4 reduced: 3 scale-factor rounds, 3 points, short rests."""
    return parse_protocol({
        "protocol": {"name": "tiny"},
        "session": {"static_s": 20.0},
        "scale_factor": {"rounds": [{"stop_deg": 120.0 * i} for i in range(1, 4)],
                         "read_delay_s": 5.0, "rest_s": 6.0},
        "angle_deviation": {"series": series, "rest_s": 11.0, "read_delay_s": 10.0,
                            "rounds": [{"stop_deg": 120.0 * i} for i in range(1, 4)]},
    })


def noisy_bench(arw=0.002, sample_rate_hz=20.0):
    inst = InstrumentConfig(nominal_scale_factor_counts_per_deg=K_NOM, arw_dpsh=arw,
                            quantisation=True, tilt_deg=0.0)
    return Bench("noisy", inst, TableConfig(), latitude_deg=40.0, sample_rate_hz=sample_rate_hz)


def test_same_seed_same_json_and_workers_do_not_matter():
    p, b = tiny_protocol(), noisy_bench()
    a = validate(4, seed=7, bench=b, protocol=p, sample_rate_hz=20.0, workers=1,
                 show_progress=False).to_dict()
    c = validate(4, seed=7, bench=b, protocol=p, sample_rate_hz=20.0, workers=2,
                 show_progress=False).to_dict()
    d = validate(4, seed=8, bench=b, protocol=p, sample_rate_hz=20.0, workers=1,
                 show_progress=False).to_dict()
    dump = lambda x: json.dumps(x, indent=2, allow_nan=False)
    assert dump(a) == dump(c)
    assert dump(a) != dump(d)
    # SeedSequence derivation: independent of the trial count, distinct across cases.
    assert trial_seeds(7, "default", 2) == trial_seeds(7, "default", 4)[:2]
    assert set(trial_seeds(7, "default", 4)).isdisjoint(trial_seeds(7, "tilt", 4))


def test_ideal_noise_free_bench_every_error_vanishes():
    # No noise, no tilt, no harmonics, error-free table: E equals the truth exactly.
    inst = InstrumentConfig(nominal_scale_factor_counts_per_deg=K_NOM, quantisation=False,
                            scale_factor_error_ppm=3.0)
    b = Bench("ideal", inst, TableConfig(), latitude_deg=40.0, sample_rate_hz=20.0)
    r = validate(3, bench=b, protocol=tiny_protocol(), sample_rate_hz=20.0, workers=1,
                 show_progress=False)
    s = r.cases[0].summary["annex_a"]
    for truth in ("systematic", "calibrated", "intrinsic"):
        assert s[truth]["mean_abs_error_E_ij_arcsec"] < 1e-6
        assert s[truth]["coverage_E_i"]["fraction"] == 1.0
        assert s[truth]["coverage_E_ij"]["fraction"] == 1.0
    # U is then the annex's Type B part alone: 2·√(0.1²/3 + 0.0785²/3 + b²/3) (A.4.1–A.4.3),
    # b = 0.005 °/h × 60 ″/min × the longest time to reading actually used (issue 12, defect 4).
    from gonio.specs.ogam_draft.bench import run_session
    ses = run_session(tiny_protocol(), b, seed=0)
    t_max = ses.readings.loc[ses.readings["test"] == "angle_deviation", "time_s"].max()
    expected = 2 * math.sqrt((0.1 ** 2 + 0.078539 ** 2 + (0.005 * t_max) ** 2) / 3)
    assert r.cases[0].summary["mean_U_arcsec"] == pytest.approx(expected, rel=1e-3)


def test_broken_budget_coverage_falls_and_matches_normal_prediction():
    # ARW dominates; with U ×0.5 the coverage falls to ≈ 2Φ(x) − 1, x = U_t/σ per trial
    # (E_ij − T roughly normal with σ from the mean |error|). 80 trials × 12 readings:
    # the bound is 3 standard errors between trials (readings of one trial share the
    # 7.1 scale-factor error, so the binomial u is too small); at x ≈ 1 a U 20 % off
    # moves the coverage by ≈ 0.09, more than the bound (checked below), so it fails.
    p, b = tiny_protocol(series=4), noisy_bench(arw=0.004)
    r = validate(80, seed=1, bench=b, protocol=p, sample_rate_hz=20.0, u_scale=0.5, workers=2,
                 show_progress=False)
    case = r.cases[0]
    s = case.summary
    cov = s["annex_a"]["systematic"]["coverage_E_ij"]
    assert cov["fraction"] < 0.8
    sigma = s["annex_a"]["systematic"]["mean_abs_error_E_ij_arcsec"] * math.sqrt(math.pi / 2)
    U_t = np.array([t.U_arcsec for t in case.trials])

    def predicted(scale):
        return float(np.mean(2 * stats.norm.cdf(scale * U_t / sigma) - 1))

    bound = 3 * max(cov["u_trials"], cov["u_binomial"])
    assert abs(cov["fraction"] - predicted(1.0)) < bound
    assert abs(predicted(1.2) - predicted(1.0)) > bound       # the test has the power
    assert abs(predicted(1 / 1.2) - predicted(1.0)) > bound
    # Unbroken, the annex still misses the scale-factor term δK·θ of the noisy 7.1 rounds
    # (the same in every series, so u(r) cannot see it) when the noise dominates; the
    # extra components (K_r: θ_max/n·u(r)·√Σ1/θ_k²) restore the coverage.
    r = validate(8, seed=1, bench=b, protocol=p, sample_rate_hz=20.0, workers=2,
                 extra_components=True, show_progress=False).cases[0].summary
    assert r["annex_a"]["systematic"]["coverage_E_ij"]["fraction"] < 0.9
    assert r["extended"]["systematic"]["coverage_E_ij"]["fraction"] >= 0.95
    # The δK·θ term seen in the truth grows linearly with θ (ratio 3 between 120° and 360°).
    k_rms = r["diagnosis"]["scale_factor_term_rms_per_point_arcsec"]
    assert k_rms[2] / k_rms[0] == pytest.approx(3.0, rel=1e-6)


def test_binomial_uncertainty_reported_and_correct():
    # √(p(1−p)/n) against scipy's binomial standard deviation divided by n.
    for p, n in [(0.95, 200), (0.5, 37), (0.99, 2400)]:
        assert binomial_u(p, n) == pytest.approx(stats.binom(n, p).std() / n, rel=1e-12)
    rng = np.random.default_rng(0)
    err = np.abs(rng.standard_normal((50, 4, 3)))
    c = coverage(err, np.full(50, 1.0))
    hit = err <= 1.0
    assert c["fraction"] == pytest.approx(hit.mean())
    assert c["n"] == 600
    assert c["u_binomial"] == pytest.approx(math.sqrt(hit.mean() * (1 - hit.mean()) / 600))
    per_trial = hit.reshape(50, -1).mean(axis=1)
    assert c["u_trials"] == pytest.approx(per_trial.std(ddof=1) / math.sqrt(50))
    assert c["per_point"] == pytest.approx(hit.mean(axis=(0, 1)).tolist())
    # ±1σ of a normal covers 68.27 %: the estimate agrees within 4 binomial u.
    assert abs(c["fraction"] - 0.6827) < 4 * c["u_binomial"]


def test_tilt_coupling_closed_form_against_quadrature():
    # ∫₀ᵗ [cos(θ(t′)+α) − cos α] dt′ for a turn at constant rate then rest, by quad.
    rate, delay = 60.0, 10.0
    for theta, t in [(30.0, 10.5), (180.0, 13.0), (270.0, 14.5), (360.0, 16.0)]:
        c, s = tilt_coupling_coefficients([theta], [t], rate, delay, accel_dps2=1e12)
        t_rot = t - delay
        for alpha in (0.3, 2.0, 4.5):
            def f(x):
                th = math.radians(min(rate * x, theta))
                return math.cos(th + alpha) - math.cos(alpha)
            num = integrate.quad(f, 0.0, t_rot)[0] + f(t_rot + 1.0) * delay
            assert c[0] * math.cos(alpha) - s[0] * math.sin(alpha) == pytest.approx(num, abs=1e-9)
    # Ω_⊥ = Ω_E cos φ for the axis up (ogam-draft.md "Physics": 11.5″/s at 40°).
    assert earth_rate_perpendicular_arcsec_s(40.0) == pytest.approx(
        7.292115e-5 * 180 / math.pi * 3600 * math.cos(math.radians(40.0)), rel=1e-12)


def test_tilt_coupling_predicts_the_bench_truth():
    # The bench's noise-free truth (as mounted) minus the same instrument untilted equals
    # Ω_⊥ sin ψ (C cos α − S sin α) from the closed form (rates and rests are the protocol's).
    p = tiny_protocol(series=1)
    psi, alpha = 0.1, 30.0
    base = Bench("b", InstrumentConfig(nominal_scale_factor_counts_per_deg=K_NOM,
                                       quantisation=False),
                 TableConfig(accel_dps2=1e6), latitude_deg=40.0, sample_rate_hz=50.0)
    tilted = replace(base, instrument=replace(base.instrument, tilt_deg=psi,
                                              tilt_azimuth_deg=alpha))
    t0 = [r for r in run_session(p, base).truth["readings"] if r["test"] == "angle_deviation"]
    t1 = [r for r in run_session(p, tilted).truth["readings"] if r["test"] == "angle_deviation"]
    th = np.array([r["table_deg"] for r in t1])
    ts = np.array([r["time_s"] for r in t1])
    c, s = tilt_coupling_coefficients(th, ts, 60.0, 10.0, accel_dps2=1e6)
    w = earth_rate_perpendicular_arcsec_s(40.0) * math.sin(math.radians(psi))
    diff = np.array([a["systematic_deviation_arcsec"] - b["systematic_deviation_arcsec"]
                     for a, b in zip(t1, t0)])
    # α in the closed form is the tilt azimuth relative to the direction β of Ω_⊥ in the
    # table frame (gonio.specs.ogam_draft.bench.instrument.Geometry).
    g = geometry(tilted, "up")
    a = math.radians(alpha) - math.atan2(g.omega_e2_dps, g.omega_e1_dps)
    assert np.max(np.abs(diff)) > 0.05
    assert diff == pytest.approx(w * (c * math.cos(a) - s * math.sin(a)), abs=2e-3)


def test_cli_in_process(tmp_path, capsys):
    rc = main(["validate", "--trials", "2", "--bench", "rlg", "--cases", "ideal",
               "--sample-rate-hz", "5", "--workers", "1", "--out", str(tmp_path)])
    assert rc == 0
    out = capsys.readouterr().out
    assert "ideal" in out and "cov E_i" in out
    data = json.loads((tmp_path / "validation.json").read_text())
    assert data["settings"]["trials"] == 2
    assert data["cases"][0]["annex_a"]["systematic"]["coverage_E_ij"]["fraction"] == 1.0
    rc = main(["validate", "--trials", "2", "--cases", "ideal", "--sample-rate-hz", "5",
               "--workers", "1", "--json"])
    assert rc == 0
    assert json.loads(capsys.readouterr().out) == data


def test_cli_errors_exit_2(capsys):
    assert main(["validate", "--trials", "0"]) == 2
    assert "--trials" in capsys.readouterr().err
    assert main(["validate", "--trials", "2", "--cases", "nope"]) == 2
    assert "unknown case" in capsys.readouterr().err
