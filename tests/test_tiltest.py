"""In-situ tilt estimate: exact recovery on a noise-free bench, coverage of ±2u over seeds
on a noisy bench, the LS covariance against scipy's curve_fit, protocol and CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats
from scipy.optimize import curve_fit

from gonio.specs.ogam_draft.bench import run_session, write_session
from gonio.specs.ogam_draft.bench.config import Bench, InstrumentConfig, TableConfig
from gonio.cli import main
from gonio.errors import GonioError
from gonio.specs.ogam_draft.protocol import load_protocol, parse_protocol
from gonio.specs.ogam_draft.protocol import TiltEstimatePlan
from gonio.specs.ogam_draft.tilt_estimate import (estimate_tilt, fit_first_harmonic,
                           tilt_estimate_from_readings)

K_NOM = 76434.87


def proto(positions=12, dwell=30.0, orientation="up"):
    return parse_protocol({"protocol": {"name": "te"}, "session": {"earth_compensation": "none"},
                           "tilt_estimate": {"positions": positions, "dwell_s": dwell,
                                             "settle_s": 2.0, "orientation": orientation}})


def bench(psi, alpha, lat, **kw):
    inst = dict(nominal_scale_factor_counts_per_deg=K_NOM, quantisation=False, tilt_deg=psi,
                tilt_azimuth_deg=alpha)
    inst.update(kw)
    return Bench("b", InstrumentConfig(**inst), TableConfig(), latitude_deg=lat,
                 sample_rate_hz=100.0)


@pytest.mark.parametrize("orientation,lat", [("up", 40.0), ("up", 0.0), ("north", 40.0),
                                             ("north", 80.0), ("east", 10.0), ("south", 60.0)])
def test_noise_free_bench_recovers_tilt_and_azimuth(orientation, lat):
    for psi, alpha in ((0.05, 10.0), (0.5, -120.0), (2.0, 200.0)):
        res = run_session(proto(8, 10.0, orientation), bench(psi, alpha, lat, bias_dph=0.02),
                          seed=0)
        e = tilt_estimate_from_readings(res.readings, K_NOM, lat)
        assert e.tilt_deg == pytest.approx(psi, rel=1e-6)
        d = (e.tilt_azimuth_table_deg - alpha + 180.0) % 360.0 - 180.0
        assert abs(d) < 1e-4
        assert e.n_positions == 8 and e.dof == 5


def test_coverage_over_seeds():
    """u(ψ) is right to better than 20 %: over 200 seeds the z-scores (ψ̂ − ψ)/u follow
    Student's t with ν = 21 (std √(ν/(ν − 2)) = 1.051), and ±2u covers 94 %.

    Bounds are 3 standard errors of the statistic for n = 200 seeds: the std of z within
    ±3·s/√(2(n − 1)) = ±0.16 (so u 20 % too small, std 1.26, or 20 % too large, 0.88,
    fails); the coverage count within ±3 binomial σ (3.4 counts).
    """
    from dataclasses import replace
    psi, alpha, lat = 0.15, 40.0, 40.0
    b = replace(bench(psi, alpha, lat, arw_dpsh=0.001, quantisation=True, bias_dph=0.01),
                sample_rate_hz=20.0)
    p = proto(24, 20.0)
    n, nu = 200, 21
    z, zp = [], []
    for seed in range(n):
        e = tilt_estimate_from_readings(run_session(p, b, seed=seed).readings, K_NOM, lat)
        assert e.dof == nu
        z.append((e.tilt_deg - psi) / e.u_tilt_deg)
        d = (e.tilt_azimuth_table_deg - alpha + 180.0) % 360.0 - 180.0
        zp.append(d / e.u_phase_deg)
    s_t = math.sqrt(nu / (nu - 2))
    tol = 3 * s_t / math.sqrt(2 * (n - 1))
    for zz in (np.array(z), np.array(zp)):
        assert abs(np.std(zz, ddof=1) - s_t) < tol
        p_cover = 2 * stats.t.cdf(2.0, nu) - 1            # 0.941
        hits = int(np.sum(np.abs(zz) <= 2.0))
        assert abs(hits - n * p_cover) <= 3 * math.sqrt(n * p_cover * (1 - p_cover))


def test_ls_covariance_against_curve_fit():
    rng = np.random.default_rng(5)
    th = np.arange(10) * 36.0
    y = 3.0 + 0.2 * np.cos(np.radians(th)) - 0.1 * np.sin(np.radians(th)) \
        + 0.01 * rng.standard_normal(th.size)
    f = fit_first_harmonic(th, y)
    model = lambda t, c0, a, b: c0 + a * np.cos(np.radians(t)) + b * np.sin(np.radians(t))
    popt, pcov = curve_fit(model, th, y, p0=[0, 0, 0], absolute_sigma=False)
    np.testing.assert_allclose(f.coef, popt, rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(f.cov, pcov, rtol=1e-6, atol=1e-14)


def test_propagation_against_monte_carlo():
    """u(ψ) by the law of propagation vs the scatter of ψ̂ under simulated fit noise."""
    th = np.arange(12) * 30.0
    perp = 11.522126                                  # up, 40° N
    amp = perp * math.sin(math.radians(0.2))
    rng = np.random.default_rng(1)
    y0 = 9.7 + amp * np.cos(np.radians(th + 25.0))
    psis, us = [], []
    for _ in range(400):
        e = estimate_tilt(th, y0 + 0.003 * rng.standard_normal(th.size), 40.0, "up")
        psis.append(e.tilt_deg)
        us.append(e.u_tilt_deg)
    # the mean of u (residual-based) agrees with the empirical scatter (σ√(2/N) / Ω_⊥ cos ψ).
    expected = math.degrees(0.003 * math.sqrt(2 / 12) / (perp * math.cos(math.radians(0.2))))
    assert np.std(psis) == pytest.approx(expected, rel=0.1)
    assert np.sqrt(np.mean(np.square(us))) == pytest.approx(expected, rel=0.1)


def test_no_signal_and_bad_inputs():
    th = np.arange(6) * 60.0
    with pytest.raises(GonioError, match="parallel to the Earth"):
        estimate_tilt(th, np.ones(6), 0.0, "north")
    with pytest.raises(GonioError, match="at least 4"):
        fit_first_harmonic([0.0, 120.0, 240.0], [1.0, 2.0, 3.0])
    with pytest.raises(GonioError, match="exceeds"):
        estimate_tilt(th, 20.0 * np.cos(np.radians(th)), 40.0, "up")
    with pytest.raises(GonioError, match="positions"):
        parse_protocol({"protocol": {"name": "x"}, "tilt_estimate": {"positions": 3}})


def test_protocol_file_and_cli(tmp_path, capsys):
    p = load_protocol("tilt-estimate")
    assert isinstance(p.extra["tilt_estimate"], TiltEstimatePlan)
    assert p.extra["tilt_estimate"].positions >= 4
    res = run_session(proto(8, 10.0), bench(0.3, 15.0, 40.0), seed=0)
    out = write_session(res, tmp_path / "s")
    assert main(["tilt-estimate", str(out["readings"]), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["tilt_deg"] == pytest.approx(0.3, rel=1e-6)
    assert len(d["positions"]) == 8
    assert main(["tilt-estimate", str(out["readings"])]) == 0
    assert "ψ = 0.3000°" in capsys.readouterr().out
