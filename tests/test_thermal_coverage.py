"""The triad's certified thermal values (K, b at the programme's set points and supply
levels, ARW at the set points) cover the bench's truth, on both sides, on the built-in
chamber programme.

Truth: ``SPEC.truth`` (:func:`gonio.specs.triad_alignment.bench.true_thermal_coefficients`, the bench's
polynomials in closed form, evaluated at the soaked set points), never an estimate. The
uncertainty terms are checked against independent computations: the soak-components
covariance against the ordinary fit of the soak means (the split-plot identity of a
balanced design), a point's variance against xᵀCx, the model-order term against its closed
form for two candidates and, at a point, against every candidate refitted by numpy. The full
study (200 trials) is benchmarks/bench_thermal_coverage.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.specs.triad_alignment.bench import load_triad_bench, true_thermal_coefficients
from gonio.pipeline.coverage import coverage_table_from
from gonio.specs.triad_alignment.thermal_model import (design, order_uncertainty,
                                                       soak_covariance)


def test_true_coefficients_re_expand_the_bench_polynomials():
    b = load_triad_bench("mems-triad")
    t = true_thermal_coefficients(b, "z")
    th = b.thermal
    m = float((b.axes + b.cross_coupling)[2, 2])
    for die in (-60.0, -3.0, 0.0, 41.0):          # ϑ of the die; the sensor reads +offset
        s = die + th.sensor_offset_c
        bias = sum(t["b"][f"theta{j}"] * s ** j for j in range(1, 4)) + t["b"]["c0"]
        assert bias * m == pytest.approx(th.bias_dps(2, die + th.reference_c, th.reference_v,
                                                     b.bias_dps[2]), rel=1e-12)
        k = sum(t["K"][f"theta{j}"] * s ** j for j in range(1, 3)) + t["K"]["c0"]
        assert k / m == pytest.approx(th.scale_factor(2, die + th.reference_c, th.reference_v,
                                                      b.scale_per_dps[2]), rel=1e-12)
    assert t["b"]["u1"] * m == pytest.approx(th.bias_supply_dps[2][0])
    assert "theta4" not in t["b"]


def test_soak_covariance_is_the_fit_of_the_soak_means_on_a_balanced_design():
    rng = np.random.default_rng(11)
    theta = np.repeat(np.array([-60.0, -40, -20, 0, 20, 40, 60, 5]), 3)
    u = np.tile([0.0, 0.25, -0.25], 8)
    soak = np.repeat(np.arange(8), 3)
    y = 0.1 + 1e-3 * theta + 0.4 * u + rng.normal(0, 2e-3, 8)[soak] + rng.normal(0, 5e-4, 24)
    x = design(theta / 60, u / 0.25, 2, 1)
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    cov, nu, method = soak_covariance(x, y - x @ coef, soak)
    assert method == "soak components"
    # independent: ordinary least squares on the 8 soak means (U cancels in each mean)
    xg = design(theta[::3] / 60, np.zeros(8), 2, 0)
    yg = y.reshape(8, 3).mean(1)
    cg, *_ = np.linalg.lstsq(xg, yg, rcond=None)
    rg = yg - xg @ cg
    cov_g = float(rg @ rg) / (8 - 3) * np.linalg.inv(xg.T @ xg) / 1.0
    assert cg == pytest.approx(coef[:3], rel=1e-10)
    assert cov[:3, :3] == pytest.approx(cov_g, rel=1e-9)
    assert nu[:3] == pytest.approx([8 - 3] * 3, rel=1e-6)      # the soak means' ν
    # without replicated soaks it is the ordinary s²(XᵀX)⁻¹ with ν = n − p
    y2 = 0.1 + 1e-3 * theta + rng.normal(0, 5e-4, 24)
    c2, *_ = np.linalg.lstsq(x, y2, rcond=None)
    r2 = y2 - x @ c2
    cov2, nu2, m2 = soak_covariance(x, r2, np.arange(24))      # no replication
    assert m2 == "ols" and list(nu2) == [20.0] * 4
    assert cov2 == pytest.approx(float(r2 @ r2) / 20 * np.linalg.inv(x.T @ x))


def test_order_term_closed_form_for_two_candidates():
    # two candidates: cubic (selected) and quartic, criterion values 0 and Δ
    fits = {(3, 0): (np.array([1.0, 2.0, 3.0, 4.0]),), (4, 0): (np.array([1.1, 2.0, 2.5, 4.0, 0.7]),)}
    for delta in (0.5, 3.0):
        table = [{"order_temperature": 3, "order_supply": 0, "bic": 0.0},
                 {"order_temperature": 4, "order_supply": 0, "bic": delta}]
        w4 = math.exp(-delta / 2) / (1 + math.exp(-delta / 2))
        uo = order_uncertainty(fits, table, (3, 0), "bic")
        assert uo == pytest.approx(math.sqrt(w4) * np.array([0.1, 0.0, 0.5, 0.0]), rel=1e-12)
        # selected quartic: its ϑ⁴ term counts as 0 in the cubic, so u_order(ϑ⁴) = √w₃·0.7
        t2 = [dict(table[0], bic=delta), dict(table[1], bic=0.0)]
        uo4 = order_uncertainty(fits, t2, (4, 0), "bic")
        assert uo4[4] == pytest.approx(math.sqrt(w4) * 0.7, rel=1e-12)
    # supply terms sit after the ϑ terms, whose number differs between the candidates:
    # selected (2, 1) = [c0, ϑ, ϑ², U]; candidate (1, 1) = [c0, ϑ, U] aligns as [c0, ϑ, 0, U]
    fits = {(2, 1): (np.array([1.0, 2.0, 0.3, 5.0]),), (1, 1): (np.array([1.2, 2.1, 4.0]),),
            (2, 2): (np.array([1.0, 2.0, 0.3, 5.5, 0.9]),)}
    table = [{"order_temperature": 2, "order_supply": 1, "aic": 0.0},
             {"order_temperature": 1, "order_supply": 1, "aic": 1.0},
             {"order_temperature": 2, "order_supply": 2, "aic": 2.0}]
    w = np.exp(-np.array([0.0, 1.0, 2.0]) / 2)
    w /= w.sum()
    expect = np.sqrt(w[1] * np.array([0.2, 0.1, 0.3, 1.0]) ** 2
                     + w[2] * np.array([0.0, 0.0, 0.0, 0.5]) ** 2)
    assert order_uncertainty(fits, table, (2, 1), "aic") == pytest.approx(expect, rel=1e-12)


@pytest.mark.slow
def test_thermal_values_cover_on_the_built_in_programme():
    """The certified K, b, ARW at the set points against the bench's truth on fresh seeds:
    no item significantly under 90 %, pooled not significantly under 95 %, z spread pooled
    within 0.6–1.4 — and both sides can fail (U ÷ 4 under-covers, U × 20 is over-wide).
    The full study (200 trials) is benchmarks/bench_thermal_coverage.py."""
    from scipy.stats import binomtest

    from gonio.specs.triad_alignment.simulate import thermal_trial

    trials = [thermal_trial(s) for s in range(24_900, 24_908)]
    df = coverage_table_from(trials).set_index("key")
    msg = df[["n", "coverage", "cp_low", "cp_high", "z_mean", "z_sd"]].to_string()
    assert len(df) == 8 * 3 * 2 + 8 and (df["n"] == len(trials)).all(), msg
    assert (df["cp_high"] >= 0.90).all(), msg
    hits, n = int(df["hits"].sum()), int(df["n"].sum())
    assert binomtest(hits, n).proportion_ci(0.95, method="exact").high >= 0.95, msg
    z = np.array([(r["value"] - r["truth"]) / r["u_c"] for t in trials for r in t.values()])
    assert 0.6 <= float(np.std(z, ddof=1)) <= 1.4, float(np.std(z, ddof=1))
    for f, col, bad in ((0.25, "cp_high", lambda v: v < 0.90), (20.0, "z_sd", lambda v: v < 0.3)):
        scaled = [{k: dict(r, U=r["U"] * f, u_c=r["u_c"] * f) for k, r in t.items()}
                  for t in trials]
        sdf = coverage_table_from(scaled).set_index("key")
        assert bad(sdf.loc["b_z_t2_v2", col]), (f, sdf.loc["b_z_t2_v2"].to_dict())


def test_point_variance_is_the_covariance_form_and_the_order_term_its_closed_form():
    """A certified point value x(ϑ, U)ᵀĉ: its variance from the soak components
    (:func:`linear_variance`) equals xᵀ C x with the covariance of :func:`soak_covariance`, a
    unit vector gives back a coefficient's variance and ν; its order term is
    √(Σ_m w_m (ŷ_m − ŷ)²) with every candidate refitted here by numpy in physical units."""
    from gonio.specs.triad_alignment.thermal_model import (criterion_weights, fit_polynomial,
                                                           linear_variance)
    rng = np.random.default_rng(17)
    theta = np.repeat(np.array([-65.0, -45, -25, -5, 0, 15, 35, 60]), 3)
    u = np.tile([-0.25, 0.0, 0.25], 8)
    soak = np.repeat(np.arange(8), 3)
    y = (0.1 + 1e-3 * theta - 4e-5 * theta ** 2 + 5e-7 * theta ** 3 + 0.4 * u
         + rng.normal(0, 2e-3, 8)[soak] + rng.normal(0, 5e-4, 24))
    f = fit_polynomial("b", theta, u, y, soak=soak)
    assert f.cov_method.startswith("soak components")
    for j in range(f.coef.size):
        e = np.zeros(f.coef.size)
        e[j] = 1.0
        var, nu = linear_variance(f.parts, e)
        assert var == pytest.approx(f.cov[j, j], rel=1e-9) and nu == pytest.approx(f.dof_coef[j])
    w = criterion_weights(f.table, f.criterion)
    for t0, u0 in ((-65.0, -0.25), (0.0, 0.0), (35.0, 0.25)):
        pt = f.point(t0, u0)
        g = design(np.array([t0]) / f.scale_t, np.array([u0]) / f.scale_u, f.n_t, f.n_u)[0]
        assert pt["u_fit"] ** 2 == pytest.approx(g @ f.cov @ g, rel=1e-9)
        assert pt["value"] == pytest.approx(float(f.predict(t0, u0)[0]), rel=1e-12)
        spread = []
        for row in f.table:
            x = design(theta, u, row["order_temperature"], row["order_supply"])
            c = np.linalg.lstsq(x, y, rcond=None)[0]
            xp = design(np.array([t0]), np.array([u0]), row["order_temperature"],
                        row["order_supply"])[0]
            spread.append((xp @ c - pt["value"]) ** 2)
        assert pt["u_order"] == pytest.approx(math.sqrt(float(np.dot(w, spread))), rel=1e-6)
    assert f.point(60.0, 0.25)["u_order"] > 0


@pytest.mark.parametrize("n_soaks, per_soak, n_t, expect", [
    (3, 3, 2, "ols"),                  # ν_b = 0: the temperature terms take every soak mean
    (5, 3, 3, "soak components"),      # ν_b = 1: the smallest between-soak ν still used
    (8, 1, 2, "ols"),                  # ν_w = 0: no replicated soak
])
def test_soak_covariance_degrees_of_freedom_boundaries(n_soaks, per_soak, n_t, expect):
    rng = np.random.default_rng(5)
    theta = np.repeat(np.linspace(-60.0, 60.0, n_soaks), per_soak)
    soak = np.repeat(np.arange(n_soaks), per_soak)
    y = 1e-3 * theta + rng.normal(0, 1e-2, n_soaks)[soak] + rng.normal(0, 1e-5, theta.size)
    x = design(theta / 60, np.zeros(theta.size), n_t, 0)
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    cov, nu, method = soak_covariance(x, y - x @ coef, soak)
    assert method == expect
    if expect == "soak components":
        assert nu[0] == pytest.approx(1.0, rel=1e-6)
        assert np.all(np.isfinite(np.diag(cov))) and np.all(np.diag(cov) > 0)


def test_soak_covariance_one_within_degree_of_freedom():
    # ν_w = 1: one soak measured twice, the others once; the soak means scatter far more
    rng = np.random.default_rng(9)
    theta = np.r_[np.linspace(-60.0, 60.0, 8), 60.0]
    soak = np.r_[np.arange(8), 7]
    y = 1e-3 * theta + rng.normal(0, 1e-2, 8)[soak] + rng.normal(0, 1e-5, 9)
    x = design(theta / 60, np.zeros(9), 1, 0)
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    cov, nu, method = soak_covariance(x, y - x @ coef, soak)
    assert method == "soak components"
    # the slope rests on the soak means: ≈ the fit of the 8 means (one counted with its pair)
    assert nu[1] == pytest.approx(6.0, rel=0.05)


def test_soak_covariance_never_pools_when_the_soak_means_hide_their_error():
    """Issue 24: when the soak means scatter no more than the points within a soak
    (σ̂_b² ≤ 0), MS_b is floored at MS_w and keeps its ν_b: covariance MS_w (XᵀX)⁻¹, and a
    temperature coefficient (which rests on the soak means) keeps ν ≈ ν_b, not the n − p of
    the pooled s²(XᵀX)⁻¹ that gave the study's heavy tails (|z| 6–7 at k ≈ 2.1)."""
    theta = np.repeat(np.linspace(-60.0, 60.0, 8), 3)
    u = np.tile([0.0, 0.25, -0.25], 8)
    soak = np.repeat(np.arange(8), 3)
    x = design(theta / 60, u / 0.25, 3, 1)
    rng = np.random.default_rng(3)
    for _ in range(50):                      # a draw whose soak means scatter little
        y = 1e-3 * theta + rng.normal(0, 1e-3, 24)
        coef, *_ = np.linalg.lstsq(x, y, rcond=None)
        r = y - x @ coef
        cov, nu, method = soak_covariance(x, r, soak)
        if method != "soak components":
            break
    assert method == "soak components, MS_b floored at MS_w"
    # independent: MS_w from the residuals of the fit with one mean per soak
    zx = np.column_stack([np.eye(8)[soak], u / 0.25])
    cw, *_ = np.linalg.lstsq(zx, y, rcond=None)
    rw = y - zx @ cw
    ms_w = float(rw @ rw) / (24 - 9)
    assert cov == pytest.approx(ms_w * np.linalg.inv(x.T @ x), rel=1e-9)
    nu_b = 8 - 4                              # soak means less the c0…ϑ³ terms
    assert nu[1] < nu_b + 1.5 and nu[1] < 0.5 * (24 - 5), nu
    assert nu[4] > 10                         # the supply term rests on within-soak differences


def test_certified_points_of_a_set_point_measured_once():
    """A set point with one soak point has no Type A spread of its (sensor − chamber): its
    temperature-reading term is 0 with ν 0 (no NaN, no budget line), the values stay finite;
    the others keep u_theta_c from their three points, (sd/√n of sensor − chamber)."""
    from gonio.specs.triad_alignment.bench import load_triad_bench, load_triad_protocol, run_thermal_session
    from gonio.specs.triad_alignment.readings import TriadReadings
    from gonio.specs.triad_alignment.calibration import thermal_items
    from gonio.specs.triad_alignment.thermal_model import identify_thermal_model

    p = load_triad_protocol("triad-alignment", "triad-alignment")
    s = run_thermal_session(p, load_triad_bench("mems-triad"), 31)
    r = TriadReadings(s.readings.assign(line=np.arange(len(s.readings)) + 1), s.metadata, None)
    th = identify_thermal_model(r, ramps=False)
    m = th.channels["z"]
    low = np.round(m.points["chamber_c"], 1) == -40.0
    assert low.sum() == 3
    m.points = m.points.drop(index=m.points.index[low][1:])
    pts = {(q["model"], q["t"], q["v"]): q for q in m.certified_points(th.reference_c,
                                                                         th.reference_v)}
    one, three = pts[("K", 1, 1)], pts[("K", 2, 1)]
    assert one["u_theta_c"] == 0.0 and one["nu_theta"] == 0.0
    g = m.points[np.round(m.points["chamber_c"], 1) == -20.0]
    o = g["theta_c"] - (g["chamber_c"] - th.reference_c)
    assert three["u_theta_c"] == pytest.approx(float(o.std(ddof=1)) / math.sqrt(3), rel=1e-12)
    items = thermal_items(th, "lsb")
    it = items["K_z_t1_v1"]
    assert math.isfinite(it.uncertainty.U) and math.isfinite(it.value)
    assert [c["symbol"] for c in it.uncertainty.components] == ["K_z_t1_v1_fit",
                                                                 "K_z_t1_v1_order"]
    assert "K_z_t2_v1_T" in [c["symbol"] for c in items["K_z_t2_v1"].uncertainty.components]
    # the stated point is the programme's: −40 °C, the lowest supply (4.75 V)
    assert (it.details["setpoint_c"], it.details["supply_v"]) == (-40.0, 4.75)
    assert items["b_z_t8_v3"].details["supply_v"] == 5.25
    # the slope the temperature term uses is the polynomial's derivative (closed form)
    for key, fit in (("K", m.scale), ("b", m.bias)):
        c = fit.coefficients()
        q = pts[(key, 2, 1)]
        d = sum(j * c[f"theta{j}"] * q["theta_c"] ** (j - 1) for j in range(1, fit.n_t + 1))
        assert q["slope"] == pytest.approx(d, rel=1e-6), key


def test_arw_chi2_spread_is_that_of_refitted_chi2_draws():
    """The χ² spread of a fitted ARW(ϑ) (:meth:`ChannelModel.arw_chi2`): each dwell's ARW a
    sample standard deviation of n samples, s²(n − 1)/σ² ~ χ²_(n−1). Checked by drawing
    those χ² directly (numpy) and refitting the same-order polynomial with numpy.polyfit
    at every draw: the spread of the fitted value at a point matches u within 3 %, and ν is
    ½(ARW/u)²."""
    import pandas as pd

    from gonio.specs.triad_alignment.thermal_model import ChannelModel, fit_polynomial

    rng = np.random.default_rng(20261202)
    theta = np.repeat(np.array([-63.5, -43.5, -23.5, -3.5, 1.5, 16.5, 36.5, 61.5]), 3)
    sigma = 0.3 * (1 + 5e-3 * theta + 2e-5 * theta ** 2)
    n = np.full(theta.size, 600)
    n[::3] = 300                                   # unequal dwells: ν_i differ
    y = sigma * np.sqrt(rng.chisquare(n - 1) / (n - 1))
    fit = fit_polynomial("ARW_z", theta, np.zeros(theta.size), y, orders=(2, 0))
    pts = pd.DataFrame({"theta_c": theta, "arw_deg_sqrt_h": y, "arw_n": n,
                        "arw_fs_hz": 10.0})
    m = ChannelModel("z", fit, fit, fit, None, pts, "sensor", (-63.5, 61.5), (0.0, 0.0))
    for at in (-40.0, 0.0, 60.0):
        u, nu = m.arw_chi2(at)
        fitted = np.polyval(np.polyfit(theta, y, 2), theta)
        draws = fitted[None, :] * np.sqrt(rng.chisquare(n - 1, (20000, theta.size)) / (n - 1))
        vals = np.polyval(np.polyfit(theta, draws.T, 2), at)     # every draw refitted
        assert u == pytest.approx(float(np.std(vals, ddof=1)), rel=0.03), at
        assert nu == pytest.approx(0.5 * (float(fit.predict(at)[0]) / u) ** 2, rel=1e-12)


def test_flicker_lift_is_the_mean_sample_variance_of_synthesised_flicker():
    """:func:`flicker_lift_var` against records of flicker noise synthesised here by FFT
    (one-sided PSD h/f, h = B²/π, from fs/N to fs/2): the mean sample variance of
    600-sample records at 10 Hz is the function's value within 6 %; twice B gives four times
    the lift, and a record of one sample none."""
    from gonio.specs.triad_alignment.thermal_model import flicker_lift_var

    rng = np.random.default_rng(7)
    fs, n, b = 10.0, 600, 2e-3
    big = 2 ** 20
    f = np.fft.rfftfreq(big, 1.0 / fs)
    s = np.zeros_like(f)
    s[1:] = b * b / math.pi / f[1:]
    means = []
    for _ in range(4):
        c = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) \
            * np.sqrt(s * fs / big)                 # E|c|² = 2 S Δf, Δf = fs/N
        x = np.fft.irfft(c * big / 2.0, n=big)
        rec = x[: (big // n) * n].reshape(-1, n)
        means.append(float(np.mean(np.var(rec, axis=1, ddof=1))))
    assert float(np.mean(means)) == pytest.approx(flicker_lift_var(b, n, fs), rel=0.06)
    assert flicker_lift_var(2 * b, n, fs) == pytest.approx(4 * flicker_lift_var(b, n, fs))
    assert flicker_lift_var(b, 1, fs) == 0.0
