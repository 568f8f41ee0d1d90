"""The virtual bench's true value of every JJF 1535 item (truth.json, recovery tests).

Each value comes from the gyro model's parameters (:class:`gonio.bench.rate_gyro.RateGyroConfig`)
and the protocol, by closed forms where they exist (g-sensitivity, ARW, temperature
sensitivities, bandwidth) and otherwise by applying the clause's formula to the model's
*exact, noise-free* outputs at the protocol's points (scale factor with its nonlinearity and
asymmetry, threshold, resolution, warm-up time) — labelled ``"how"`` in the result. The
noise statistics (bias stability, bias repeatability) use the exact covariance of the
noise model (white, Gauss–Markov sum, random walk), independent of the generator.
"""

from __future__ import annotations

import math

import numpy as np

from gonio.specs._rate_family import formulas as rg
from gonio.bench.rate_gyro import NoiseState, RateBench, difference_noise_sigma
from gonio.physics.alignment import mount_matrix
from gonio.physics.earth import earth_rate_enu
from gonio.units import S_PER_H


def _earth_body(lat: float, up: str, north: str) -> np.ndarray:
    """Earth rate in body axes, °/s."""
    R = mount_matrix(up, north)
    return R.T @ np.degrees(earth_rate_enu(lat))


def block_mean_covariance(bench: RateBench, dt: float, n_blocks: int, P: int,
                          t_start_s: float) -> np.ndarray:
    """Covariance (°/s)² of the n_blocks means of P samples of the rate noise, the record
    starting t_start_s after power-on: white (N²/dt per sample), each Gauss–Markov term of
    the bias-instability sum (σ² a^|k|), the rate random walk (q²·min(t_i, t_j), from
    power-on)."""
    g = bench.gyro
    ns = NoiseState(g, np.random.default_rng(0), enabled=True)   # only for taus and sigmas
    n = n_blocks
    C = np.zeros((n, n))
    N = g.arw_deg_sqrt_h / math.sqrt(S_PER_H)
    C += np.eye(n) * (N ** 2 / dt) / P
    u = np.arange(P)
    d = np.arange(n)
    lag = d[None, :] - d[:, None]
    for tau, s in zip(ns.taus, ns.sig):
        a = math.exp(-dt / tau)
        same = float(np.sum(a ** np.abs(u[:, None] - u[None, :]))) / P ** 2
        cross = float(np.sum(a ** u) * np.sum(a ** (-u.astype(float)))) / P ** 2
        Cg = np.where(lag == 0, same, cross * a ** (P * np.abs(lag).astype(float)))
        C += s ** 2 * Cg
    q2 = (g.rrw_dph_sqrt_h / S_PER_H / math.sqrt(S_PER_H)) ** 2
    if q2 > 0:
        k0 = t_start_s / dt
        # sample i (0-based in the record) carries i + 1 steps after the start value
        mean_idx = (d * P + (P - 1) / 2.0 + 1.0)
        same_min = float(np.mean(np.minimum(u[:, None], u[None, :]))) + 1.0
        Cr = np.where(lag == 0, d * P + same_min, np.minimum(mean_idx[:, None], mean_idx[None, :]))
        C += q2 * dt * (Cr + k0)
    return C


def expected_block_std(bench: RateBench, dt: float, n_samples: int, P: int,
                       t_start_s: float) -> float:
    """√E[s²] of the block means of one record (the population value B_s estimates), °/s."""
    n = n_samples // P
    C = block_mean_covariance(bench, dt, n, P, t_start_s)
    es2 = (np.trace(C) - C.sum() / n) / (n - 1)
    return math.sqrt(max(es2, 0.0))


def record_mean_variance(bench: RateBench, dt: float, n_samples: int, t_start_s: float) -> float:
    """Variance (°/s)² of the mean of one record of the rate noise (from power-on)."""
    P = 10 if n_samples % 10 == 0 else 1
    C = block_mean_covariance(bench, dt, n_samples // P, P, t_start_s)
    return float(C.sum()) / (n_samples // P) ** 2


def truth(bench: RateBench, proto) -> dict:
    """True values of the fifteen items (keys as in :data:`gonio.specs.jjf1535.items.ITEMS`)."""
    from gonio.specs.jjf1535.protocol import bandwidth_frequencies, sf_rates

    g = bench.gyro
    P = proto.sections
    room = P["protocol"]["room_temperature_c"]
    lat = bench.latitude_deg
    eb = _earth_body(lat, "+z", "+x")
    ez = float(eb[2])
    K0 = float(g.scale_factor_at(room, g.supply_nominal_v))
    rates = np.array(sf_rates(proto))
    om = np.concatenate([rates, -rates])
    F = K0 * (g.response(om + ez) - g.response(np.array([ez]))[0])
    fit = rg.fit_scale_factor(om, F)
    asym = rg.asymmetry_jjf(om, fit.means)
    out = {}
    out["scale_factor"] = {"value": fit.K, "how": "least squares on the exact model outputs"}
    out["nonlinearity"] = {"value": rg.nonlinearity_jjf(fit), "how": "eq (6) on exact outputs"}
    out["asymmetry"] = {"value": asym.value, "how": "eq (8) on exact outputs"}
    out["sf_repeatability"] = {"value": g.sf_scatter_rel, "how": "power-cycle scatter σ of K"}
    temps = [room] + list(P["temperature"]["points_c"])
    Ks = [float(g.scale_factor_at(t, g.supply_nominal_v)) for t in temps]
    out["sf_temperature_sensitivity"] = {
        "value": rg.temperature_sensitivity(Ks, temps, 0, relative=True)[0],
        "how": "K(T) of the model at the set points"}
    # threshold and resolution: the 50 % rule on exact outputs, K = the true K above
    th = P["threshold"]["rates_dps"]
    dt0 = P["protocol"]["sample_interval_s"]
    settle = P["scale_factor"]["settle_s"]
    tp = P["threshold"]
    sig_th = K0 * difference_noise_sigma(g, dt0, tp["samples"], tp["rest_samples"],
                                         0.5 * (tp["samples"] + tp["rest_samples"]) * dt0 + settle,
                                         both_sides=True, temp_c=room)
    cands, pmfs = [], []
    for s in (1.0, -1.0):
        r = s * np.array(th)
        meas = K0 * (g.response(r + ez) - g.response(np.array([ez]))[0])
        cands.append(rg.fifty_percent_candidate(r, meas, fit.K * r)[0])
        pmfs.append(rg.fifty_percent_outcome_pmf(
            r, rg.fifty_percent_pass_probability(meas, sig_th, fit.K * r)))
    out["threshold"] = {"value": rg.outcome_quantile(rg.max_outcome_pmf(*pmfs), 0.5),
                        "noise_free_dps": None if None in cands else max(cands),
                        "noise_sigma_output": sig_th,
                        "continuous_dps": 2 * g.dead_band_dps,
                        "how": "median outcome of the 50 % rule at the protocol's rates: exact "
                               "model responses, the model's noise of each rest-referred mean "
                               "(equals the noise-free result when the noise is off)"}
    rs = P["resolution"]
    sig_rs = K0 * difference_noise_sigma(g, dt0, rs["samples"], rs["samples"],
                                         rs["samples"] * dt0 + settle, both_sides=False,
                                         temp_c=room)
    cands, pmfs = [], []
    for s in (1.0, -1.0):
        b = s * rs["base_rate_dps"]
        inc = s * np.array(rs["increments_dps"])
        meas = K0 * (g.response(b + inc + ez) - g.response(np.array([b + ez]))[0])
        cands.append(rg.fifty_percent_candidate(inc, meas, fit.K * inc)[0])
        pmfs.append(rg.fifty_percent_outcome_pmf(
            inc, rg.fifty_percent_pass_probability(meas, sig_rs, fit.K * inc)))
    out["resolution"] = {"value": rg.outcome_quantile(rg.max_outcome_pmf(*pmfs), 0.5),
                         "noise_free_dps": None if None in cands else max(cands),
                         "noise_sigma_output": sig_rs,
                         "how": "median outcome of the 50 % rule (exact responses, the model's "
                                "noise of each base-referred mean)"}
    # bias at room temperature, input axis up, Earth rate removed: b + g·f + cross·ω_E
    gz = np.asarray(g.g_sensitivity_dps_per_g)
    f_b = mount_matrix("+z", "+x").T @ np.array([0.0, 0.0, 1.0])
    kr = K0 / fit.K          # the measured rate unit is output / K_LS, not output / K₀
    b0 = float(g.bias_at(room, g.supply_nominal_v)) + float(gz @ f_b) \
        + g.cross_axis_x * float(eb[0]) + g.cross_axis_y * float(eb[1])
    f_ez = float(g.response(np.array([ez]))[0])
    out["bias"] = {"value": ((b0 + f_ez) * kr - ez) * S_PER_H,
                   "model_bias_dph": b0 * S_PER_H,
                   "how": "[b(T_rt) + g·f + k·ω_E⊥ + f(Ω_E,z)]·K₀/K_LS − Ω_E,z (°/h)"}
    b = P["bias"]
    dt = P["protocol"]["sample_interval_s"]
    warm = P["protocol"]["warmup_s"]
    bs = expected_block_std(bench, dt, b["samples"], b["stability_block_samples"], warm)
    out["bias_stability"] = {"value": bs * S_PER_H, "how": "√E[s²] from the noise covariance"}
    vm = record_mean_variance(bench, dt, b["samples"], warm)
    out["bias_repeatability"] = {"value": math.sqrt(g.bias_scatter_dps ** 2 + vm) * S_PER_H,
                                 "how": "√(σ_b,run² + var(record mean)) from the noise model"}
    # warm-up time on the exact transient
    w = P["warmup"]
    t = np.arange(w["samples"]) * dt
    tau = g.warmup_tau_s
    x = g.warmup_bias_dps * tau / dt * (np.exp(-t / tau) - np.exp(-(t + dt) / tau))
    out["warmup_time"] = {"value": rg.warmup_time_s(t, x, window=w["window_samples"],
                                                    block=w["block_samples"],
                                                    nominal=w["nominal_stability_dph"] / S_PER_H),
                          "how": "7.2.9 reading on the noise-free transient"}
    s_noise = expected_block_std(bench, dt, w["window_samples"], w["block_samples"], 0.0)
    nom = w["nominal_stability_dph"] / S_PER_H
    out["warmup_time"]["value_with_noise"] = (
        rg.warmup_time_s(t, x, window=w["window_samples"], block=w["block_samples"],
                         nominal=math.sqrt(nom ** 2 - s_noise ** 2)) if nom > s_noise else math.nan)
    out["warmup_time"]["noise_block_std_dph"] = s_noise * S_PER_H
    # g-sensitivity per axis: g_axis + cross-axis coupling of the Earth rate, Earth removed
    per = {}
    for ax, (up, dn, north) in {"x": ("+x", "-x", "+y"), "y": ("+y", "-y", "+z"),
                               "z": ("+z", "-z", "+x")}.items():
        vals = []
        for u in (up, dn):
            e = _earth_body(lat, u, north)
            fb = mount_matrix(u, north).T @ np.array([0.0, 0.0, 1.0])
            vals.append((float(gz @ fb) + g.cross_axis_x * e[0] + g.cross_axis_y * e[1]
                         + float(g.response(np.array([e[2]]))[0])) * kr - e[2])
        per[ax] = (vals[0] - vals[1]) / 2.0 * S_PER_H
    ax = max(per, key=lambda a: abs(per[a]))
    out["g_sensitivity"] = {"value": abs(per[ax]), "per_axis_dph_per_g": per, "axis": ax,
                            "how": "g-sensitivity parameters (+ cross-axis × Earth rate)"}
    out["angle_random_walk"] = {"value": g.arw_deg_sqrt_h * (1 + g.arw_tc1_per_c * (room - g.reference_temperature_c)),
                                "how": "ARW parameter at room temperature"}
    Bs = [float(g.bias_at(tc, g.supply_nominal_v)) * kr * S_PER_H for tc in temps]
    out["bias_temperature_sensitivity"] = {
        "value": rg.temperature_sensitivity(Bs, temps, 0, relative=False)[0],
        "how": "b(T) of the model at the set points"}
    f = np.array(bandwidth_frequencies(proto, bench))
    h = np.abs(g.dynamics(f))
    target = rg.MINUS_3DB_RATIO * abs(g.dynamics(f[0]))
    lo, hi = f[0], f[-1] * 10
    if abs(g.dynamics(hi)) < target:
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if abs(g.dynamics(mid)) > target else (lo, mid)
        bw = 0.5 * (lo + hi)
    else:
        bw = math.nan
    out["bandwidth"] = {"value": bw, "grid_interpolated_hz": rg.minus3db_frequency(f, h),
                        "phase90_hz": g.natural_frequency_hz,
                        "how": "|H(f)|/|H(f_lowest)| = 10^(-3/20) of the second-order model"}
    return out
