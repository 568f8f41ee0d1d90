"""The virtual bench's true value of every JJF 1535 item (truth.json, recovery tests).

Each value comes from the gyro model's parameters (:class:`gonio.bench.rate_gyro.RateGyroConfig`)
and the protocol, by closed forms (:mod:`gonio.bench.rate_truth`: scale factor, asymmetry,
temperature sensitivities, bias, g-sensitivity, ARW, warm-up time, bandwidth) and otherwise by
the clause's definition written out here on the model's *exact, noise-free* outputs
(nonlinearity's residuals, the 50 % rules' walk) — labelled ``"how"`` in the result. None of
it calls the estimators of :mod:`gonio.specs._rate_family.formulas`, so a formula mutated there
changes the estimate and not the truth (tests/test_rate_truth_independent.py). The noise
statistics (bias stability, bias repeatability) use the exact covariance of the noise model
(white, Gauss–Markov sum, random walk), independent of the generator.
"""

from __future__ import annotations

import math

import numpy as np

from gonio.bench import rate_truth as rt
from gonio.specs._rate_family import formulas as rg
from gonio.bench.rate_gyro import NoiseState, RateBench, difference_noise_sigma
from gonio.physics.alignment import mount_matrix
from gonio.physics.earth import earth_rate_enu
from gonio.units import S_PER_H


def _earth_body(lat: float, up: str, north: str) -> np.ndarray:
    """Earth rate in body axes, °/s."""
    R = mount_matrix(up, north)
    return R.T @ np.degrees(earth_rate_enu(lat))


def _lag_sum(f0: float, f: np.ndarray) -> float:
    """Σ_ij of an n×n matrix whose entries depend on |i − j| only: f0 on the diagonal and
    ``f[k − 1]`` at lag k = 1 … n − 1 (n = f.size + 1), without forming the matrix."""
    n = f.size + 1
    return n * f0 + 2.0 * float(np.sum((n - np.arange(1, n)) * f))


def block_mean_moments(bench: RateBench, dt: float, n_blocks: int, P: int,
                       t_start_s: float) -> tuple[float, float]:
    """(trace, sum of all entries) of the covariance (°/s)² of the ``n_blocks`` means of
    ``P`` samples of the rate noise, the record starting ``t_start_s`` after power-on: white
    (N²/dt per sample), each Gauss–Markov term of the bias-instability sum (σ² a^|k|), the
    rate random walk (q²·min(t_i, t_j), from power-on).

    The only moments the truths need, in O(n_blocks + P) time and memory (the
    n×n matrix and its P×P inner sums took 3 GB and more for ``stability_block_samples =
    100000`` or a long record). Each GM term's matrix depends on the lag only, the random
    walk's off-diagonal entries on the earlier block only, so both sums are written by lag;
    the GM cross-block sums are formed as a^((k−1)P)·Σa^j·Σa^(P−i) (no a^(−P) overflow)."""
    g = bench.gyro
    ns = NoiseState(g, np.random.default_rng(0), enabled=True)   # only for taus and sigmas
    n = int(n_blocks)
    if n < 1 or P < 1:
        raise ValueError(f"need at least one block of at least one sample, got {n} × {P}")
    N = g.arw_deg_sqrt_h / math.sqrt(S_PER_H)
    white = (N ** 2 / dt) / P
    trace, total = n * white, n * white
    u = np.arange(P, dtype=float)
    k = np.arange(1, n, dtype=float)
    for tau, s in zip(ns.taus, ns.sig):
        a = math.exp(-dt / tau)
        # (1/P²) Σ_{i,j<P} a^|i−j| by lag
        same = (P + 2.0 * float(np.sum((P - u[1:]) * a ** u[1:]))) / P ** 2
        s0 = float(np.sum(a ** u))                      # Σ_{j<P} a^j
        s1 = float(np.sum(a ** (u + 1.0)))              # Σ_{m=1..P} a^m
        cross = s0 * s1 * a ** ((k - 1.0) * P) / P ** 2  # lag k ≥ 1
        trace += s ** 2 * n * same
        total += s ** 2 * _lag_sum(same, cross)
    q2 = (g.rrw_dph_sqrt_h / S_PER_H / math.sqrt(S_PER_H)) ** 2
    if q2 > 0:
        k0 = t_start_s / dt
        d = np.arange(n, dtype=float)
        # sample i (0-based in the record) carries i + 1 steps after the start value
        mean_idx = d * P + (P - 1) / 2.0 + 1.0
        # mean of min(u_i, u_j) over the P×P pairs: min = v for 2(P − v) − 1 pairs
        same_min = float(np.sum(u * (2.0 * (P - u) - 1.0))) / P ** 2 + 1.0
        diag = float(np.sum(d * P + same_min))
        # off-diagonal: min(mean_idx_i, mean_idx_j) = the earlier block's, counted for each
        # later block j (n − 1 − i of them, both triangles)
        off = 2.0 * float(np.sum(mean_idx * (n - 1.0 - d)))
        trace += q2 * dt * (diag + n * k0)
        total += q2 * dt * (diag + off + n * n * k0)
    return trace, total


def expected_block_std(bench: RateBench, dt: float, n_samples: int, P: int,
                       t_start_s: float) -> float:
    """√E[s²] of the block means of one record (the population value B_s estimates), °/s."""
    n = n_samples // P
    trace, total = block_mean_moments(bench, dt, n, P, t_start_s)
    es2 = (trace - total / n) / (n - 1)
    return math.sqrt(max(es2, 0.0))


def record_mean_variance(bench: RateBench, dt: float, n_samples: int, t_start_s: float) -> float:
    """Variance (°/s)² of the mean of one record of the rate noise (from power-on)."""
    P = 10 if n_samples % 10 == 0 else 1
    _, total = block_mean_moments(bench, dt, n_samples // P, P, t_start_s)
    return total / (n_samples // P) ** 2


def sample_noise_covariance(bench: RateBench, t_s: np.ndarray, dt_s: np.ndarray,
                            temp_c: float) -> np.ndarray:
    """Covariance (°/s)² of the rate-noise samples taken at ``t_s`` (each sample's start,
    s after power-on, one power-up) with intervals ``dt_s``: white N²/dt on the diagonal
    (interval means), each Gauss–Markov term of the bias-instability sum s²·e^(−|t_i − t_j|/τ),
    the rate random walk q²·min(t_i + dt_i, t_j + dt_j) (its steps up to the end of each
    interval, from zero at power-on) and the output quantisation LSB²/12 per sample — the
    noise model's parameters as :func:`block_mean_moments` takes them, for samples with gaps."""
    g = bench.gyro
    ns = NoiseState(g, np.random.default_rng(0), enabled=True)   # only for taus and sigmas
    t, d = np.asarray(t_s, float), np.asarray(dt_s, float)
    N = g.arw_deg_sqrt_h / math.sqrt(S_PER_H) * (1 + g.arw_tc1_per_c * float(g.delta_t(temp_c)))
    lsb = max(g.output_lsb, bench.equipment.acquisition.resolution) / abs(g.scale_factor)
    C = np.diag(N ** 2 / d + lsb ** 2 / 12.0)
    lag = np.abs(t[:, None] - t[None, :])
    for tau, s in zip(ns.taus, ns.sig):
        C += s ** 2 * np.exp(-lag / tau)
    q2 = (g.rrw_dph_sqrt_h / S_PER_H / math.sqrt(S_PER_H)) ** 2
    if q2 > 0:
        C += q2 * np.minimum((t + d)[:, None], (t + d)[None, :])
    return C


def sf_fit_noise_rel(bench: RateBench, proto) -> float:
    """Standard deviation of the relative error that the gyro's rate noise gives one
    calibration's least-squares K_m (7.2.1.2 eqs (4), (5)): with c_j = (Ω_j − Ω̄)/Σ(Ω − Ω̄)²
    over the rate points, K_m/K − 1 = Σ_j c_j r̄_j, r̄_j the noise mean of point j (the rest
    level F_r is common to every point and Σ c_j = 0, so it drops out); its variance is
    wᵀCw, w = c_j/N_j on point j's samples, C their covariance
    (:func:`sample_noise_covariance`) along the first calibration's segments of the plan
    (times from its power-on; 7.2.4 powers the gyro off between calibrations)."""
    from gonio.specs.jjf1535.protocol import plan

    segs = [s for s in plan(proto, bench) if s.test == "scale_factor"]
    if not segs:
        return 0.0
    t, times, dts, rates, idx = 0.0, [], [], [], []
    for s in (s for s in segs if s.run == segs[0].run):
        t += s.delay_s
        if s.role == "rate":
            times.append(t + s.interval_s * np.arange(s.samples))
            dts.append(np.full(s.samples, float(s.interval_s)))
            rates.append(float(s.rate_dps))
            idx.append(np.full(s.samples, len(rates) - 1))
        t += s.samples * s.interval_s
    if len(rates) < 2:
        return 0.0
    om = np.array(rates)
    c = (om - om.mean()) / float(np.sum((om - om.mean()) ** 2))
    j = np.concatenate(idx)
    w = c[j] / np.bincount(j)[j]
    C = sample_noise_covariance(bench, np.concatenate(times), np.concatenate(dts),
                                proto["protocol"]["room_temperature_c"])
    return math.sqrt(max(float(w @ C @ w), 0.0))


def _scale_factor_truths(g, K0: float, rates: np.ndarray, ez: float) -> dict:
    """7.2.1–7.2.3 from the model's closed forms (:mod:`gonio.bench.rate_truth`): K, the
    residuals of eq (5) written out, K± of each direction."""
    k, how = rt.slope_both_directions(g, rates, ez)
    K = K0 * k
    om = np.concatenate([rates, -rates])
    F = K0 * (rt.response_at(g, om + ez) - rt.response_at(g, np.array([ez]))[0])
    v = F - K * om - (F.mean() - K * om.mean())          # eq (5) residuals, F_0 = F̄ − KΩ̄
    kp, kn, how_d = rt.slopes_per_direction(g, rates, ez)
    return {"scale_factor": {"value": K, "how": f"K₀·LS slope of f(Ω + Ω_E,z), {how}"},
            "nonlinearity": {"value": float(np.abs(v).max() / abs(K * (om.max() - om.min()))),
                             "how": "eq (6) on the model's exact outputs, residuals from the "
                                    "closed-form K"},
            "asymmetry": {"value": abs(kp - kn) / (0.5 * (kp + kn)),
                          "how": f"|K+ − K−|/((K+ + K−)/2), {how_d}"}}


def _rule_truth(g, K0: float, K: float, steps, base: float, ez: float, sigma: float,
                two_sided: bool, field: str) -> dict:
    """The 50 % rule of 7.2.6 / 7.2.7 on the model's exact responses to ``steps`` (above a
    ``base`` rate), both directions: the noise-free outcome by the rule's walk
    (:func:`gonio.bench.rate_truth.rule_walk`), and the median outcome under the model's noise
    of each referred mean (σ in output units) — the two agree when the noise is off."""
    cands, pmfs = [], []
    for s in (1.0, -1.0):
        b = s * base
        inc = s * np.asarray(steps, float)
        meas = K0 * (rt.response_at(g, b + inc + ez) - rt.response_at(g, np.array([b + ez]))[0])
        exp = K * inc
        ok = np.abs(meas - exp) <= 0.5 * np.abs(exp) * (1 + 1e-12)
        cands.append(rt.rule_walk(inc, ok))
        pmfs.append(rg.fifty_percent_outcome_pmf(
            inc, rg.fifty_percent_pass_probability(meas, sigma, exp)))
    free = None if None in cands else max(cands)
    pmf = rg.max_outcome_pmf(*pmfs)
    value = free if sigma == 0 else rg.outcome_quantile(pmf, 0.5)
    top = float(np.max(np.abs(steps)))
    x = np.array([top if k is None else abs(k) for k in pmf], float)
    w = np.array(list(pmf.values()), float)
    w = w / w.sum()
    mean = float(w @ x)
    sd = math.sqrt(max(float(w @ (x - mean) ** 2), 0.0))
    return {"value": value, "noise_free_dps": free, "noise_sigma_output": sigma,
            "outcome_mean_dps": mean, "outcome_sd_dps": sd,
            "outcome_skew_z": (mean - value) / sd if sd > 0 and value is not None else 0.0,
            "how": f"the {field} rule's walk on exact model responses (noise off); the median "
                   "outcome under the model's noise of each referred mean (noise on); "
                   "outcome_skew_z = (mean − median)/sd of that outcome: the mean of "
                   "z = (value − median)/u_c that an honest u_c gives (the outcome is "
                   "discrete and skewed)"}


def _warmup_truth(g, w: dict, dt: float, nominal: float, kr: float) -> float:
    """7.2.9 on the exact transient A·e^(−t/τ) (interval means): the block-mean standard
    deviation of a window starting at t is e^(−t/τ) times that of the first window, so the
    earliest compliant start is the first block boundary ≥ τ·ln(s₀/nominal)."""
    W, P = w["window_samples"], w["block_samples"]
    tau, A = g.warmup_tau_s, g.warmup_bias_dps * kr
    blocks = [rt.exponential_interval_mean(A, tau, j * P * dt, (j + 1) * P * dt)
              for j in range(W // P)]
    s0 = float(np.std(blocks, ddof=1))
    if s0 <= nominal:
        return 0.0
    t_min = tau * math.log(s0 / nominal)
    t = math.ceil(t_min / (P * dt) * (1 - 1e-12)) * P * dt
    return t if t <= (w["samples"] - W) * dt else math.nan


def _bandwidth_truth(g, f: np.ndarray) -> dict:
    """7.2.15: the model's −3 dB frequency relative to its gain at the lowest test frequency,
    by bisection of |H(f)| (and its log-f interpolation on the test grid, the noise-off
    value the item reads)."""
    target = 10.0 ** (-3.0 / 20.0) * abs(g.dynamics(f[0]))
    lo, hi = f[0], f[-1] * 10
    if abs(g.dynamics(hi)) < target:
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if abs(g.dynamics(mid)) > target else (lo, mid)
        bw = 0.5 * (lo + hi)
    else:
        bw = math.nan
    return {"value": bw, "grid_interpolated_hz": rt.log_grid_crossing(
        f, np.abs(g.dynamics(f)), 10.0 ** (-3.0 / 20.0)),
        "phase90_hz": g.natural_frequency_hz,
        "how": "|H(f)|/|H(f_lowest)| = 10^(-3/20) of the second-order model"}


def truth(bench: RateBench, proto) -> dict:
    """True values of the fifteen items (keys as in :data:`gonio.specs.jjf1535.items.ITEMS`),
    from the model's parameters: closed forms (:mod:`gonio.bench.rate_truth`) and the
    clauses' definitions written out here, never the estimators' functions (only the
    outcome distribution of the noisy 50 % rule comes from :mod:`gonio.specs._rate_family.formulas`)."""
    from gonio.specs.jjf1535.protocol import bandwidth_frequencies, sf_rates

    g = bench.gyro
    P = proto.sections
    room = P["protocol"]["room_temperature_c"]
    lat = bench.latitude_deg
    eb = _earth_body(lat, "+z", "+x")
    ez = float(eb[2])
    K0 = float(g.scale_factor_at(room, g.supply_nominal_v))
    rates = np.array(sf_rates(proto), float)
    out = _scale_factor_truths(g, K0, rates, ez)
    K = out["scale_factor"]["value"]
    fit_rel = sf_fit_noise_rel(bench, proto)
    out["sf_repeatability"] = {
        "value": math.sqrt(g.sf_scatter_rel ** 2 + fit_rel ** 2),
        "power_cycle_scatter_rel": g.sf_scatter_rel, "fit_noise_rel": fit_rel,
        "how": "√(σ_K,run² + var(K_m from the rate noise)/K²): each K_m of eq (10) is one "
               "calibration's least-squares fit, so it carries the noise of its rate points "
               "(sf_fit_noise_rel) beside the power-cycle scatter, as B_r's records carry "
               "their means' noise"}
    temps = [room] + list(P["temperature"]["points_c"])
    dT = np.array([g.delta_t(t) for t in temps], float)
    poly = 1 + g.sf_tc1_per_c * dT + g.sf_tc2_per_c2 * dT ** 2      # K(T)/K(T_ref)
    out["sf_temperature_sensitivity"] = {
        "value": float(np.max(np.abs((poly[1:] / poly[0] - 1) / (dT[1:] - dT[0])))),
        "how": "eq (11) on K(T) = K₀(1 + k₁ΔT + k₂ΔT²) of the model (the response factor cancels)"}
    dt0 = P["protocol"]["sample_interval_s"]
    settle = P["scale_factor"]["settle_s"]
    tp, rs = P["threshold"], P["resolution"]
    sig_th = K0 * difference_noise_sigma(g, dt0, tp["samples"], tp["rest_samples"],
                                         0.5 * (tp["samples"] + tp["rest_samples"]) * dt0 + settle,
                                         both_sides=True, temp_c=room)
    out["threshold"] = {**_rule_truth(g, K0, K, tp["rates_dps"], 0.0, ez, sig_th, True,
                                      "threshold"), "continuous_dps": 2 * g.dead_band_dps}
    sig_rs = K0 * difference_noise_sigma(g, dt0, rs["samples"], rs["samples"],
                                         rs["samples"] * dt0 + settle, both_sides=False,
                                         temp_c=room)
    out["resolution"] = _rule_truth(g, K0, K, rs["increments_dps"], rs["base_rate_dps"], ez,
                                    sig_rs, True, "resolution")
    # bias at room temperature, input axis up, Earth rate removed: b + g·f + cross·ω_E
    gz = np.asarray(g.g_sensitivity_dps_per_g)
    f_b = mount_matrix("+z", "+x").T @ np.array([0.0, 0.0, 1.0])
    kr = K0 / K          # the measured rate unit is output / K_LS, not output / K₀
    b0 = float(g.bias_at(room, g.supply_nominal_v)) + float(gz @ f_b) \
        + g.cross_axis_x * float(eb[0]) + g.cross_axis_y * float(eb[1])
    f_ez = float(rt.response_at(g, np.array([ez]))[0])
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
    w = P["warmup"]
    nom = w["nominal_stability_dph"] / S_PER_H
    s_noise = expected_block_std(bench, dt, w["window_samples"], w["block_samples"], 0.0)
    with_noise = _warmup_truth(g, w, dt, math.sqrt(nom ** 2 - s_noise ** 2), kr) \
        if nom > s_noise else math.nan
    out["warmup_time"] = {
        "value": with_noise, "value_with_noise": with_noise,
        "noise_free_s": _warmup_truth(g, w, dt, nom, kr),
        "noise_block_std_dph": s_noise * S_PER_H,
        "how": "7.2.9: the first block boundary where the expected window stability, "
               "√(s_transient² + E[s²_noise]), meets the nominal — the gyro's own noise is "
               "part of the stability its specification states; closed form "
               "τ·ln(s₀/√(nominal² − E[s²_noise])) (the noise-free transient's time, "
               "noise_free_s, when the noise is off)"}
    out["g_sensitivity"] = _g_truth(g, lat, kr)
    out["angle_random_walk"] = {"value": g.arw_deg_sqrt_h * (1 + g.arw_tc1_per_c * (room - g.reference_temperature_c)),
                                "how": "ARW parameter at room temperature"}
    slopes = kr * (g.bias_tc1_dps_per_c + g.bias_tc2_dps_per_c2 * (dT[1:] + dT[0])) * S_PER_H
    out["bias_temperature_sensitivity"] = {
        "value": float(np.max(np.abs(slopes))),
        "how": "eq (27) on b(T) = b₀ + b₁ΔT + b₂ΔT²: (B_i − B_rt)/(T_i − T_rt) = "
               "[b₁ + b₂(ΔT_i + ΔT_rt)]·K₀/K_LS"}
    out["bandwidth"] = _bandwidth_truth(g, np.array(bandwidth_frequencies(proto, bench)))
    return out


def _g_truth(g, lat: float, kr: float) -> dict:
    """7.2.12: per axis half the difference of the ±axis-up rates (g-sensitivity parameters
    plus the cross-axis coupling of the Earth rate, Earth projection removed)."""
    gz = np.asarray(g.g_sensitivity_dps_per_g)
    per = {}
    for ax, (up, dn, north) in {"x": ("+x", "-x", "+y"), "y": ("+y", "-y", "+z"),
                               "z": ("+z", "-z", "+x")}.items():
        vals = []
        for u in (up, dn):
            e = _earth_body(lat, u, north)
            fb = mount_matrix(u, north).T @ np.array([0.0, 0.0, 1.0])
            vals.append((float(gz @ fb) + g.cross_axis_x * e[0] + g.cross_axis_y * e[1]
                         + float(rt.response_at(g, np.array([e[2]]))[0])) * kr - e[2])
        per[ax] = (vals[0] - vals[1]) / 2.0 * S_PER_H
    ax = max(per, key=lambda a: abs(per[a]))
    return {"value": abs(per[ax]), "per_axis_dph_per_g": per, "axis": ax,
            "how": "g-sensitivity parameters (+ cross-axis × Earth rate)"}
