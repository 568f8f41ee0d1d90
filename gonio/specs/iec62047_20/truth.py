"""IEC 62047-20: the bench's true value of every characteristic, from the gyro model's
physical parameters (noise-free outputs at the protocol's points where no closed form
exists; each value labelled ``how``). Part of the simulation side: it imports the bench.
"""

from __future__ import annotations

import math

import numpy as np

from gonio.bench.rate_gyro import difference_noise_sigma, noise_psd_one_sided
from gonio.bench.rate_session import constant_rate_spread_dps
from gonio.physics.alignment import body_rotation, mount_matrix
from gonio.physics.earth import earth_rate_enu
from gonio.specs._rate_family import formulas as rg
from gonio.specs.iec62047_20.protocol import IECProtocol, t_base


def truth(bench, proto: IECProtocol) -> dict:
    """True values of the characteristics from the gyro model (noise-free outputs at the
    protocol's points where no closed form exists; labelled ``how``)."""
    from gonio.specs.iec62047_20.protocol import sf_rates, temperatures

    g = bench.gyro
    tb, vb = t_base(proto), g.supply_nominal_v
    lat = bench.latitude_deg
    E = np.degrees(earth_rate_enu(lat))
    ez = float((mount_matrix("+z", "+x") @ np.array([0, 0, 1.0])) @ E)
    r = np.array(sf_rates(proto))
    x = np.concatenate([-r[::-1], [0.0], r])

    def outputs(T, V):
        K = float(g.scale_factor_at(T, V))
        return K * g.response(x + ez)

    y = outputs(tb, vb)
    a, b = rg.least_squares_line(x, y)
    L, _, _, fs = rg.linearity_errors_iec(x, y)
    s = rg.symmetry_iec(x, y, g.scale_factor)[0]
    out = {"scale_factor": {"value": a, "how": "fit on exact outputs at T_BASE"},
           "initial_sf_variation": {"value": 100 * (a - g.scale_factor) / g.scale_factor,
                                    "how": "exact"},
           "linearity": {"value": 100 * float(np.max(np.abs(L))), "how": "exact outputs"},
           "symmetry": {"value": 100 * s, "how": "exact outputs"}}
    T = np.array(temperatures(proto))
    aT = np.array([rg.least_squares_line(x, outputs(t, vb))[0] for t in T])
    out["sf_temperature_coefficient"] = {"value": 100 * rg.least_squares_line(T, aT)[0] / a,
                                         "how": "slope of the model's a(T) at the grid"}
    V = np.array(proto["supply"]["voltages_v"])
    aV = np.array([rg.least_squares_line(x, outputs(tb, v))[0] for v in V])
    ib = int(np.argmin(np.abs(V - vb)))
    R = [rg.ratiometric_error_iec(aV[i], aV[ib], V[i], V[ib]) for i in range(V.size)]
    out["ratiometric_error"] = {"value": 100 * float(np.max(np.abs(R))), "how": "model a(V)"}
    k_tb = float(g.scale_factor_at(tb, vb))
    out["cross_axis"] = {"value": 100 * max(abs(g.cross_axis_x), abs(g.cross_axis_y)) * k_tb / a,
                         "how": "cross-axis parameter × K(T_BASE)/a_BASE (a_BASE carries the "
                                "nonlinearity of the fit)"}
    fb = mount_matrix("+z", "+x").T @ np.array([0.0, 0.0, 1.0])
    eb = mount_matrix("+z", "+x").T @ E
    kr = k_tb / a             # measured rates are output / a_BASE, not output / K
    b_in = float(g.bias_at(tb, vb)) + float(np.asarray(g.g_sensitivity_dps_per_g) @ fb) \
        + g.cross_axis_x * eb[0] + g.cross_axis_y * eb[1]
    out["bias"] = {"value": (b_in + float(g.response(np.array([ez]))[0])) * kr - ez,
                   "how": "[b(T_BASE) + g·f + k·ω_E + f(Ω_E,z)]·K/a_BASE − Ω_E,z"}
    Ts = np.array(T)
    out["bias_temperature_coefficient"] = {
        "value": rg.least_squares_line(Ts, np.array([float(g.bias_at(t, vb)) for t in Ts]))[0] * kr,
        "how": "least-squares slope of the model's b(T) over the grid (visits weight it "
               "differently when b is not linear)"}
    out["initial_bias_variation"] = {"value": out["bias"]["value"]
                                     - proto["power_on"]["nominal_bias_dps"], "how": "bias − Out,typ"}
    # power-on transient A·e^(−t/τ) (interval means), closed forms of the two readings taken
    po, dt = proto["power_on"], proto["protocol"]["sample_interval_s"]
    A, tau = g.warmup_bias_dps * kr, g.warmup_tau_s
    P, n = po["smoothing_samples"], po["samples"]

    def mean_over(t0, t1):                       # mean of A e^(−t/τ) over [t0, t1]
        return A * tau / (t1 - t0) * (math.exp(-t0 / tau) - math.exp(-t1 / tau))

    ref = mean_over(0.0, po["reference_samples"] * dt)
    nb = n // P
    blocks = [mean_over(j * P * dt, (j + 1) * P * dt) for j in range(nb)]
    out["bias_drift_after_power_on"] = {"value": max(abs(b - ref) for b in blocks),
                                        "how": "closed form on the transient"}
    settled = mean_over((n - max(n // 5, 1)) * dt, n * dt)
    outside = [j for j, b in enumerate(blocks) if abs(b - settled) > po["startup_band_dps"]]
    out["startup_time"] = {"value": 0.0 if not outside else (outside[-1] + 1) * P * dt,
                           "how": "closed form on the transient"}
    # 5.3.3.3: the rest output (bias in output units, null included) at each supply
    def rest_out(Vv):
        Kv = float(g.scale_factor_at(tb, Vv))
        bv = float(g.bias_at(tb, Vv)) + float(np.asarray(g.g_sensitivity_dps_per_g) @ fb)
        return float(g.null_at(Vv)) + Kv * (bv + float(g.response(np.array([ez]))[0]))

    o = np.array([rest_out(v) for v in V])
    Rb = [rg.ratiometric_error_iec(o[i], o[ib], V[i], V[ib]) for i in range(V.size) if i != ib]
    out["bias_ratiometric_error"] = {"value": 100 * float(np.max(np.abs(Rb))) if Rb else math.nan,
                                     "rest_output": o, "how": "model rest output at each supply"}
    # 5.3.3.8: exact model rate at every stand angle, then the clause's fit
    from gonio.specs.iec62047_20.protocol import g_stand_runs, stand_angles
    slopes = {}
    for run, (up, north, axis) in enumerate(g_stand_runs()):
        a1, a2, w, e = [], [], [], []
        for gam in stand_angles(proto):
            Rm = mount_matrix(up, north) @ body_rotation(axis, gam)
            f_b = Rm.T @ np.array([0.0, 0.0, 1.0])
            e_b = Rm.T @ E
            w.append((float(np.asarray(g.g_sensitivity_dps_per_g) @ f_b) + g.cross_axis_x * e_b[0]
                      + g.cross_axis_y * e_b[1] + float(g.response(np.array([e_b[2]]))[0])) * kr)
            e.append(float(e_b[2]))
            a1.append(f_b[2] if run == 0 else f_b[0])
            a2.append(f_b[1])
        s1, s2 = rg.g_slope_iec(a1, w, e, a2)
        slopes["parallel" if run == 0 else "perpendicular"] = s1 if run == 0 else \
            (s1 if abs(s1) >= abs(s2) else s2)
    out["g_sensitivity"] = {"value": max(abs(v) for v in slopes.values()), "slopes": slopes,
                            "g_parameter_dps_per_g": list(g.g_sensitivity_dps_per_g),
                            "how": "exact model rate at each stand angle, fitted as 5.3.3.8"}
    # 5.4.5.1 c) and 5.6: the model's one-sided noise density of the static record
    nz = proto["noise"]
    dts = nz["sample_interval_s"]
    fgrid = np.linspace(0.0, 0.5 / dts, 200001)
    psd = noise_psd_one_sided(g, fgrid, dts, tb)
    hi = nz.get("broadband_high_hz", 0.0) or 0.5 / dts
    selb = (fgrid >= nz["band_hz"]) & (fgrid <= min(hi, 0.5 / dts))
    out["broadband_noise"] = {"value": math.sqrt(float(np.trapezoid(psd[selb], fgrid[selb]))),
                              "how": "∫ of the model's one-sided density over the broadband region "
                                     "(white, Gauss-Markov sum, random walk, quantisation)"}
    # 5.4.5.1 b): the model's density over the Welch lines the item integrates (first line
    # 1/(segment length) … band_hz; the per-segment mean is removed by the estimator)
    nper = min(4096, int(nz["samples"]))
    seli = (fgrid >= 1.0 / (nper * dts)) & (fgrid <= nz["band_hz"])
    out["inband_noise"] = {"value": math.sqrt(float(np.trapezoid(psd[seli], fgrid[seli]))),
                           "how": "∫ of the model's one-sided density from the first Welch line "
                                  "(1/(4096·Δt)) to band_hz"}
    # 5.1.3.7: expected population spread at each constant rate / the noise-free FullScale
    st = proto["stability"]
    fs_dps = abs(float(np.ptp(g.response(np.array([x.min(), x.max()]) + ez))))
    by_rate = {str(float(w)): constant_rate_spread_dps(bench, w, dt, st["samples"], tb)["std_dps"]
               / fs_dps for w in st["rates_dps"] if w != 0}
    out["sf_stability"] = {"value": max(by_rate.values()) if by_rate else None,
                           "by_rate": by_rate,
                           "how": "√E[population variance] of the samples at each constant rate "
                                  "(model density, rate ripple, cross-axis × horizontal rate) / "
                                  "the noise-free FullScale; the largest"}
    rs = proto["resolution"]
    if rs["steps_dps"]:
        sig = difference_noise_sigma(g, dt, rs["samples"], rs["rest_samples"],
                                     0.5 * (rs["samples"] + rs["rest_samples"]) * dt
                                     + proto["scale_factor"]["settle_s"], both_sides=True,
                                     temp_c=tb) * k_tb / a
        cands, pmfs = [], []
        for sgn in (1.0, -1.0):
            st = np.array(rs["steps_dps"])
            resp = k_tb / a * (g.response(sgn * st + ez) - g.response(np.array([ez]))[0]) * sgn
            cands.append(rg.resolution_iec(st, resp)[0])
            pmfs.append(rg.fifty_percent_outcome_pmf(st, rg.fifty_percent_pass_probability(
                resp, sig, st, two_sided=False)))
        T_f = rs["samples"] * dt
        L = nz["samples"] * dts
        nb = int(L // T_f)
        f1 = fgrid[1:]
        hp = 1.0 - np.sinc(f1 * L) ** 2
        noise_rms = math.sqrt(nb / (nb - 1) * float(np.trapezoid(
            psd[1:] * np.sinc(f1 * T_f) ** 2 * hp, f1))) if nb >= 2 else 0.0
        o_res = rg.outcome_quantile(rg.max_outcome_pmf(*pmfs), 0.5)
        out["resolution"] = {"value": None if o_res is None else max(o_res, noise_rms),
                             "out_resolution_dps": o_res, "noise_rms_dps": noise_rms,
                             "noise_free_out_resolution_dps": None if None in cands else max(cands),
                             "how": "max(median outcome of the 50 % rule under the model's noise, "
                                    "E of the std of T-means of the static record from the model's "
                                    "density: ∫S·sinc²(πfT)·(1 − sinc²(πfL)) df · n/(n − 1))"}
    out["arw"] = {"value": g.arw_deg_sqrt_h * (1 + g.arw_tc1_per_c * (tb - g.reference_temperature_c)),
                  "how": "ARW parameter at T_BASE"}
    out["bias_instability"] = {"value": g.bias_instability_dph, "how": "bias-instability parameter"}
    f = np.array(proto["frequency"]["frequencies_hz"])
    h = g.dynamics(f)
    out["frequency_band"] = {"value": min(v for v in (rg.minus3db_frequency(f, np.abs(h)),
                                                      g.natural_frequency_hz) if math.isfinite(v)),
                             "phase90_hz": g.natural_frequency_hz,
                             "minus3db_grid_hz": rg.minus3db_frequency(f, np.abs(h)),
                             "how": "second-order model: 90° at f_n"}
    return out
