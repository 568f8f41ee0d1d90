"""The virtual bench's true value of every IEC 62047-20 characteristic (truth.json, recovery
tests), from the gyro model's parameters (:class:`gonio.bench.rate_gyro.RateGyroConfig`):
closed forms (:mod:`gonio.bench.rate_truth`: scale factor and symmetry, temperature and
supply coefficients, bias, power-on transient, g-sensitivity by the orthogonality of a
whole turn, noise densities) and the clauses' definitions written out here on the model's
exact outputs (linearity's residuals, the 50 % rule's walk). None of it calls an estimator
of :mod:`gonio.specs._rate_family.formulas` (only the outcome distribution of the noisy 50 % rule),
so a formula mutated there changes the estimate and not the truth
(tests/test_rate_truth_independent.py). Each entry says ``how``.
"""

from __future__ import annotations

import math

import numpy as np

from gonio.bench import rate_truth as rt
from gonio.bench.rate_gyro import difference_noise_sigma, noise_psd_one_sided
from gonio.bench.rate_session import constant_rate_spread_dps
from gonio.physics.alignment import body_rotation, mount_matrix
from gonio.physics.earth import earth_rate_enu
from gonio.specs.iec62047_20.protocol import (IECProtocol, g_stand_runs, sf_rates, stand_angles,
                                              t_base, temperatures)


def _S(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(((a - a.mean()) * (b - b.mean())).sum())


def _sf_truths(g, proto: IECProtocol, tb: float, vb: float, ez: float) -> dict:
    """5.1.3.1–5.1.3.8 at T_BASE, V_BASE: a_BASE, linearity (eq (8) residuals written out),
    symmetry (closed-form K± difference), temperature and supply coefficients."""
    r = np.array(sf_rates(proto), float)
    x = np.concatenate([-r[::-1], [0.0], r])
    KB = float(g.scale_factor_at(tb, vb))
    k, how = rt.slope_both_directions(g, r, ez)
    a = KB * k
    y = KB * rt.response_at(g, x + ez)
    resid = y - a * x - (y.mean() - a * x.mean())
    fs = abs(float(y[-1] - y[0]))
    kp, kn, how_d = rt.slopes_per_direction(g, r, ez)
    out = {"scale_factor": {"value": a, "how": f"K(T_BASE)·LS slope of f(x + Ω_E,z), {how}"},
           "initial_sf_variation": {"value": 100 * (a - g.scale_factor) / g.scale_factor,
                                    "how": "(a_BASE − K₀)/K₀"},
           "linearity": {"value": 100 * float(np.max(np.abs(resid))) / fs,
                         "how": "eq (8) on the model's exact outputs, closed-form a_BASE"},
           "symmetry": {"value": 100 * KB * (kp - kn) / g.scale_factor,
                        "how": f"K(T_BASE)·(K+ − K−)/a_TYP, {how_d}"}}
    T = np.array(temperatures(proto), float)
    dT = T - g.reference_temperature_c
    dTb = tb - g.reference_temperature_c
    out["sf_temperature_coefficient"] = {
        "value": 100 * rt.ls_slope_of_poly(dT, g.sf_tc1_per_c, g.sf_tc2_per_c2)
        / (1 + g.sf_tc1_per_c * dTb + g.sf_tc2_per_c2 * dTb ** 2),
        "how": "LS slope of K₀(1 + k₁ΔT + k₂ΔT²) over the grid / a_BASE (closed form)"}
    V = np.array(proto["supply"]["voltages_v"], float)
    ib = int(np.argmin(np.abs(V - vb)))
    R = [float(g.scale_factor_at(tb, v)) / float(g.scale_factor_at(tb, V[ib])) - v / V[ib]
         for v in V]
    out["ratiometric_error"] = {"value": 100 * float(np.max(np.abs(R))),
                                "how": "K(V)/K(V_BASE) − V/V_BASE of the model (the response "
                                       "factor cancels)"}
    out["cross_axis"] = {"value": 100 * max(abs(g.cross_axis_x), abs(g.cross_axis_y)) / k,
                         "how": "cross-axis parameter × K(T_BASE)/a_BASE (a_BASE carries the "
                                "nonlinearity of the fit)"}
    return out


def _power_on_truths(g, proto: IECProtocol, kr: float) -> dict:
    """5.3.3.5 and 5.3.3.9 on the transient A·e^(−t/τ) (interval means), closed forms of the
    two readings taken."""
    po, dt = proto["power_on"], proto["protocol"]["sample_interval_s"]
    A, tau = g.warmup_bias_dps * kr, g.warmup_tau_s
    P, n = po["smoothing_samples"], po["samples"]

    def mean_over(t0, t1):
        return rt.exponential_interval_mean(A, tau, t0, t1)

    ref = mean_over(0.0, po["reference_samples"] * dt)
    blocks = [mean_over(j * P * dt, (j + 1) * P * dt) for j in range(n // P)]
    settled = mean_over((n - max(n // 5, 1)) * dt, n * dt)
    outside = [j for j, b in enumerate(blocks) if abs(b - settled) > po["startup_band_dps"]]
    return {"bias_drift_after_power_on": {"value": max(abs(b - ref) for b in blocks),
                                          "how": "closed form on the transient"},
            "startup_time": {"value": 0.0 if not outside else (outside[-1] + 1) * P * dt,
                             "how": "closed form on the transient"}}


def _g_truth(g, proto: IECProtocol, E: np.ndarray, kr: float) -> dict:
    """5.3.3.8: the model's rate at every stand angle (g-sensitivity, cross-axis × Earth,
    response to the Earth component), Earth projection removed, regressed on the
    acceleration components; over a whole turn in equal steps cos γ, sin γ and 1 are
    orthogonal, so each slope is S(a, ω)/S(a, a)."""
    gv = np.asarray(g.g_sensitivity_dps_per_g)
    slopes = {}
    for run, (up, north, axis) in enumerate(g_stand_runs()):
        a1, a2, w = [], [], []
        for gam in stand_angles(proto):
            Rm = mount_matrix(up, north) @ body_rotation(axis, gam)
            f_b = Rm.T @ np.array([0.0, 0.0, 1.0])
            e_b = Rm.T @ E
            w.append((float(gv @ f_b) + g.cross_axis_x * e_b[0] + g.cross_axis_y * e_b[1]
                      + float(rt.response_at(g, np.array([e_b[2]]))[0])) * kr - float(e_b[2]))
            a1.append(f_b[2] if run == 0 else f_b[0])
            a2.append(f_b[1])
        s1, s2 = _S(a1, w) / _S(a1, a1), _S(a2, w) / _S(a2, a2)
        slopes["parallel" if run == 0 else "perpendicular"] = s1 if run == 0 else \
            (s1 if abs(s1) >= abs(s2) else s2)
    return {"value": max(abs(v) for v in slopes.values()), "slopes": slopes,
            "g_parameter_dps_per_g": list(g.g_sensitivity_dps_per_g),
            "how": "model rate at each stand angle, slopes by orthogonality over a whole turn"}


def _noise_truths(bench, proto: IECProtocol, tb: float) -> dict:
    """5.4.5.1 b), c) and 5.1.3.7: the model's one-sided noise density integrated over the
    clause's bands; the expected population spread at each constant rate."""
    g = bench.gyro
    nz = proto["noise"]
    dts = nz["sample_interval_s"]
    fgrid = np.linspace(0.0, 0.5 / dts, 200001)
    psd = noise_psd_one_sided(g, fgrid, dts, tb)
    hi = nz.get("broadband_high_hz", 0.0) or 0.5 / dts
    selb = (fgrid >= nz["band_hz"]) & (fgrid <= min(hi, 0.5 / dts))
    nper = min(4096, int(nz["samples"]))
    seli = (fgrid >= 1.0 / (nper * dts)) & (fgrid <= nz["band_hz"])
    out = {"broadband_noise": {"value": math.sqrt(float(np.trapezoid(psd[selb], fgrid[selb]))),
                               "how": "∫ of the model's one-sided density over the broadband "
                                      "region (white, Gauss-Markov sum, random walk, "
                                      "quantisation)"},
           "inband_noise": {"value": math.sqrt(float(np.trapezoid(psd[seli], fgrid[seli]))),
                            "how": "∫ of the model's one-sided density from the first Welch "
                                   "line (1/(4096·Δt)) to band_hz"}}
    return out, fgrid, psd


def _resolution_truth(bench, proto: IECProtocol, tb: float, ez: float, kr: float,
                      fgrid, psd) -> dict:
    """5.6: the one-sided 50 % rule's walk on exact responses (noise off), its median outcome
    under the model's noise (noise on), and the model's Noise,RMS of T-second means."""
    g, rs, nz = bench.gyro, proto["resolution"], proto["noise"]
    dt, dts = proto["protocol"]["sample_interval_s"], nz["sample_interval_s"]
    sig = difference_noise_sigma(g, dt, rs["samples"], rs["rest_samples"],
                                 0.5 * (rs["samples"] + rs["rest_samples"]) * dt
                                 + proto["scale_factor"]["settle_s"], both_sides=True,
                                 temp_c=tb) * kr
    from gonio.specs._rate_family import formulas as rg        # outcome distribution only
    st = np.array(rs["steps_dps"], float)
    cands, pmfs = [], []
    for sgn in (1.0, -1.0):
        resp = kr * (rt.response_at(g, sgn * st + ez) - rt.response_at(g, np.array([ez]))[0]) * sgn
        cands.append(rt.rule_walk(st, resp / st >= 0.5 - 1e-12))
        pmfs.append(rg.fifty_percent_outcome_pmf(st, rg.fifty_percent_pass_probability(
            resp, sig, st, two_sided=False)))
    T_f = rs["samples"] * dt
    L = nz["samples"] * dts
    nb = int(L // T_f)
    f1 = fgrid[1:]
    hp = 1.0 - np.sinc(f1 * L) ** 2
    noise_rms = math.sqrt(nb / (nb - 1) * float(np.trapezoid(
        psd[1:] * np.sinc(f1 * T_f) ** 2 * hp, f1))) if nb >= 2 else 0.0
    free = None if None in cands else max(cands)
    o_res = free if sig == 0 else rg.outcome_quantile(rg.max_outcome_pmf(*pmfs), 0.5)
    return {"value": None if o_res is None else max(o_res, noise_rms),
            "out_resolution_dps": o_res, "noise_rms_dps": noise_rms,
            "noise_free_out_resolution_dps": free,
            "how": "max(the 50 % rule's walk on exact responses — its median outcome under the "
                   "model's noise when on —, E of the std of T-means of the static record from "
                   "the model's density: ∫S·sinc²(πfT)·(1 − sinc²(πfL)) df · n/(n − 1))"}


def truth(bench, proto: IECProtocol) -> dict:
    """True values of the characteristics from the gyro model (see the module docstring)."""
    g = bench.gyro
    tb, vb = t_base(proto), g.supply_nominal_v
    E = np.degrees(earth_rate_enu(bench.latitude_deg))
    ez = float((mount_matrix("+z", "+x") @ np.array([0, 0, 1.0])) @ E)
    out = _sf_truths(g, proto, tb, vb, ez)
    a = out["scale_factor"]["value"]
    k_tb = float(g.scale_factor_at(tb, vb))
    kr = k_tb / a             # measured rates are output / a_BASE, not output / K
    fb = mount_matrix("+z", "+x").T @ np.array([0.0, 0.0, 1.0])
    eb = mount_matrix("+z", "+x").T @ E
    gv = np.asarray(g.g_sensitivity_dps_per_g)
    f_ez = float(rt.response_at(g, np.array([ez]))[0])
    b_in = float(g.bias_at(tb, vb)) + float(gv @ fb) + g.cross_axis_x * eb[0] \
        + g.cross_axis_y * eb[1]
    out["bias"] = {"value": (b_in + f_ez) * kr - ez,
                   "how": "[b(T_BASE) + g·f + k·ω_E + f(Ω_E,z)]·K/a_BASE − Ω_E,z"}
    T = np.array(temperatures(proto), float)
    out["bias_temperature_coefficient"] = {
        "value": kr * rt.ls_slope_of_poly(T - g.reference_temperature_c, g.bias_tc1_dps_per_c,
                                          g.bias_tc2_dps_per_c2),
        "how": "LS slope of b(T) = b₀ + b₁ΔT + b₂ΔT² over the grid (closed form; the visits "
               "weight it differently when b is not linear)"}
    out["initial_bias_variation"] = {"value": out["bias"]["value"]
                                     - proto["power_on"]["nominal_bias_dps"], "how": "bias − Out,typ"}
    out.update(_power_on_truths(g, proto, kr))
    V = np.array(proto["supply"]["voltages_v"], float)
    ib = int(np.argmin(np.abs(V - vb)))
    o = np.array([float(g.null_at(v)) + float(g.scale_factor_at(tb, v))
                  * (float(g.bias_at(tb, v)) + float(gv @ fb) + f_ez) for v in V])
    Rb = [o[i] / o[ib] - V[i] / V[ib] for i in range(V.size) if i != ib]
    out["bias_ratiometric_error"] = {"value": 100 * float(np.max(np.abs(Rb))) if Rb else math.nan,
                                     "rest_output": o, "how": "model rest output at each supply"}
    out["g_sensitivity"] = _g_truth(g, proto, E, kr)
    noise, fgrid, psd = _noise_truths(bench, proto, tb)
    out.update(noise)
    st = proto["stability"]
    dt = proto["protocol"]["sample_interval_s"]
    r = np.array(sf_rates(proto), float)
    fs_dps = abs(float(rt.response_at(g, r[-1] + ez) - rt.response_at(g, -r[-1] + ez)))
    by_rate = {str(float(w)): constant_rate_spread_dps(bench, w, dt, st["samples"], tb)["std_dps"]
               / fs_dps for w in st["rates_dps"] if w != 0}
    out["sf_stability"] = {"value": max(by_rate.values()) if by_rate else None,
                           "by_rate": by_rate,
                           "how": "√E[population variance] of the samples at each constant rate "
                                  "(model density, rate ripple, cross-axis × horizontal rate) / "
                                  "the noise-free FullScale; the largest"}
    if proto["resolution"]["steps_dps"]:
        out["resolution"] = _resolution_truth(bench, proto, tb, ez, kr, fgrid, psd)
    out["arw"] = {"value": g.arw_deg_sqrt_h * (1 + g.arw_tc1_per_c * (tb - g.reference_temperature_c)),
                  "how": "ARW parameter at T_BASE"}
    out["bias_instability"] = {"value": g.bias_instability_dph, "how": "bias-instability parameter"}
    f = np.array(proto["frequency"]["frequencies_hz"], float)
    grid = rt.log_grid_crossing(f, np.abs(g.dynamics(f)), 10.0 ** (-3.0 / 20.0))
    out["frequency_band"] = {"value": min(v for v in (grid, g.natural_frequency_hz)
                                          if math.isfinite(v)),
                             "phase90_hz": g.natural_frequency_hz, "minus3db_grid_hz": grid,
                             "how": "second-order model: 90° at f_n, −3 dB on the grid"}
    return out


def hysteresis_truth(temps_c, biases) -> tuple[float, dict]:
    """5.3.3.7 on the session's true biases of the visits: a visit reached from below is
    'up', from above 'down'; the largest |B_up(T) − B_down(T)| (NaN when no temperature
    was visited both ways)."""
    up, down = {}, {}
    for i in range(1, len(temps_c)):
        d = up if temps_c[i] > temps_c[i - 1] else down if temps_c[i] < temps_c[i - 1] else None
        if d is not None:
            d[float(temps_c[i])] = float(biases[i])
    diff = {T: up[T] - down[T] for T in sorted(set(up) & set(down))}
    return (max(abs(v) for v in diff.values()) if diff else math.nan), diff
