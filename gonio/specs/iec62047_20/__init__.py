"""IEC 62047-20:2014 (JIS C 5630-20:2015), MEMS gyroscopes — measuring methods.

:func:`calibrate` computes the characteristics of :data:`.items.ITEMS` from a rate readings
file; :mod:`.protocol` reads ``protocols/iec62047-20.toml`` and plans the programme;
:func:`truth` gives the bench's true values. The standard has no uncertainty annex of the
JJF kind (its Annex A is about the accuracy of the angle and rate references), so
``SPEC.budget`` is None.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from gonio.analysis.rate_gyro import hysteresis_iec as rg_hysteresis
from gonio.errors import GonioError
from gonio.bench.rate_gyro import noise_psd_one_sided
from gonio.specs import Specification
from gonio.specs.iec62047_20 import items as _items
from gonio.specs.iec62047_20.protocol import KEY, IECProtocol, load_protocol, t_base
from gonio.analysis.rate_records import (monte_carlo_validation, RateCalibrationResult, load_readings, not_measured,
                                     source_info)

TITLE_EN = "IEC 62047-20:2014 Semiconductor devices — MEMS — Part 20: Gyroscopes (measuring methods)"
TITLE_ZH = "IEC 62047-20:2014 半导体器件 微机电器件 第20部分：陀螺仪（测量方法）"

READINGS_TAKEN = (
    "5.1.3.1: the rest point is a fit point (2n + 1 points), unlike JJF 1535.",
    "5.1.3.4: the temperature coefficient is reported as 100·T_c,SF/a_BASE in %/°C; the slope too.",
    "5.1.3.5: R = [a_V − a_BASE·V/V_BASE]/a_BASE (ratio V/V_BASE, zero for an ideal "
    "ratiometric gyro).",
    "5.1.3.6: FullScale = measured y(CW max) − y(CCW max); linearity = max |L_i|.",
    "5.1.3.8: signed (a_CW − a_CCW)/a_TYP from separate fits without the rest point.",
    "5.2: ω = (Out − Out,rest)/SF (the printed × SF is dimensionally wrong); whole revolutions; "
    "±ω half-difference as a bias-free refinement.",
    "5.3.3.1: the Earth-rate components printed with sin and cos swapped (erratum); the physics "
    "is used: axis up Ω_E sin λ, horizontal Ω_E cos λ cos φ.",
    "5.3.3.4: bias repeatability as the half range (max − min)/2 of the records.",
    "5.3.3.6: least-squares slope through every visit of base → max → base → min → base.",
    "5.4.5.2: slope −½ line fitted where the local slope is −½ ± 0.1, read at 1 h.",
    "5.4.5.3: floor over τ with ≥ 10 clusters, divided by √(2 ln 2/π).",
    "5.5: band = the lower of the −3 dB and the 90° lag frequencies, both reported.",
    "5.1.4.1 e) eq (18): a ratiometric gyro's outputs are referred to each run's own set "
    "voltage, y = y_RAW·V_set/V_actual, when the readings record the set voltage.",
    "5.3.3.3: the bias of each supply run is its rest output (null included); R in %, the "
    "departure in output units (Table 4's V) in the details.",
    "5.3.3.7: a visit is 'up' when reached from below, 'down' from above; hysteresis = "
    "max |B_up − B_down|.",
    "5.3.3.8: a = g cos γ with γ = 0 at input axis up (eq (28)'s sin γ counts from the "
    "horizontal); the Earth rate removed at each angle; a whole turn in equal steps.",
    "5.4.5.1 c): broadband = rms over band_hz … broadband_high_hz of the one-sided density; the "
    "20 dB/dec value c of c/f (°/s^1.5) in the details.",
    "5.6: the filter is the mean over a step's samples; Noise,RMS = std of T-second means of "
    "the static record; resolution = max(Out,resolution, Noise,RMS).",
)


def _mf(md, key, fallback, path):
    v = md.get(key, "")
    if v in ("", None):
        if fallback in (None, "bench"):
            raise GonioError("required metadata key is missing", file=path, key=key)
        return float(fallback)
    try:
        return float(v)
    except ValueError:
        raise GonioError(f"expected a number, got {v!r}", file=path, key=key) from None


def calibrate(readings, protocol: str | Path | IECProtocol | None = None,
              monte_carlo_trials: int = 0, **options) -> RateCalibrationResult:
    """IEC 62047-20 characteristics from a rate readings file (path or RateReadings)."""
    rd = load_readings(readings)
    spec = rd.metadata.get("spec", KEY)
    if spec != KEY:
        raise GonioError(f"the readings are for specification {spec!r}, not {KEY!r}",
                         file=rd.path, key="spec")
    proto = protocol if isinstance(protocol, IECProtocol) else load_protocol(protocol or KEY)
    md, P = rd.metadata, proto.sections
    ratiometric = str(md.get("ratiometric", "")).strip().lower() in ("true", "yes", "1")
    df, n_corr = _items.supply_correction(rd.data, ratiometric)
    ctx = _items.Context(
        df=df, output_unit=md.get("output_unit", "output"),
        null_output=_mf(md, "null_output", P["protocol"]["null_output"], rd.path),
        latitude_deg=_mf(md, "latitude_deg", P["protocol"]["latitude_deg"], rd.path),
        a_typ=_mf(md, "nominal_scale_factor", P["protocol"]["nominal_scale_factor"], rd.path),
        t_base_c=t_base(proto), v_base=_mf(md, "supply_nominal_v", 5.0, rd.path), protocol=P,
        rate_table_u_rel=_mf(md, "rate_table_u_rel", 2.5e-4, rd.path),
        acquisition_u_rel=_mf(md, "acquisition_u_rel", 3.0e-5, rd.path))
    items = {}
    for key, title, clause, fn in _items.ITEMS:
        try:
            with monte_carlo_validation(monte_carlo_trials):
                items[key] = fn(ctx)
        except GonioError as exc:
            items[key] = not_measured(key, title, clause, "", f"the data were refused: {exc.message}")
    return RateCalibrationResult(KEY, TITLE_EN, items, dict(md), source_info(rd),
                                 list(READINGS_TAKEN),
                                 extra={"supply_correction_eq18": {
                                     "ratiometric": ratiometric, "rows_corrected": n_corr}})


def truth(bench, proto: IECProtocol) -> dict:
    """True values of the characteristics from the gyro model (noise-free outputs at the
    protocol's points where no closed form exists; labelled ``how``)."""
    from gonio.analysis import rate_gyro as rg
    from gonio.bench.rate_session import mount_matrix
    from gonio.physics.earth import earth_rate_enu
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
    from gonio.bench.rate_session import body_rotation
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
    from gonio.bench.rate_session import constant_rate_spread_dps
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
        from gonio.bench.rate_gyro import difference_noise_sigma
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


def simulate(bench, protocol=None, seed: int = 0, *, noise: bool = True):
    """Run the IEC programme on a rate bench: RateSessionResult with metadata and truth."""
    from gonio.bench.rate_session import run_rate_session
    from gonio.specs.iec62047_20.protocol import plan

    proto = protocol if isinstance(protocol, IECProtocol) else load_protocol(protocol or KEY)
    b = bench if noise else bench.without_noise()
    g, eq = b.gyro, b.equipment
    P = proto["protocol"]
    md = {"spec": KEY, "protocol": proto.path.stem if proto.path else KEY, "bench": b.name,
          "seed": seed, "noise": "on" if noise else "off", "instrument": g.name, "model": g.model,
          "serial": g.serial, "manufacturer": g.manufacturer, "output_unit": g.output_unit,
          "nominal_scale_factor": repr(g.scale_factor if P["nominal_scale_factor"] == "bench"
                                       else P["nominal_scale_factor"]),
          "null_output": repr(g.null_output if P["null_output"] == "bench" else P["null_output"]),
          "latitude_deg": repr(b.latitude_deg if P["latitude_deg"] == "bench" else P["latitude_deg"]),
          "room_temperature_c": repr(t_base(proto)), "supply_nominal_v": repr(g.supply_nominal_v),
          "rate_table_u_rel": repr(eq.rate_table_u_rel),
          "acquisition_u_rel": repr(eq.acquisition_u_rel),
          "ratiometric": "true" if g.ratiometric else "false"}
    res = run_rate_session(plan(proto, b), b, seed, room_temperature_c=20.0, metadata=md,
                           noise=noise)
    res.truth["items"] = truth(b, proto)
    # a single calibration measures K of its own power-up: the truth carries its scatter
    sf_seg = next((t for t in res.truth["segments"] if t["test"] == "scale_factor"), None)
    if sf_seg is not None and noise:
        eps = res.truth["power_cycles"][sf_seg["power_cycle"]]["scale_factor_scatter_rel"]
        items = res.truth["items"]
        items["scale_factor"]["value"] *= 1 + eps
        items["scale_factor"]["power_cycle_scatter_rel"] = eps
        items["initial_sf_variation"]["value"] = 100 * (items["scale_factor"]["value"]
                                                        - g.scale_factor) / g.scale_factor
    # 5.3.3.7: the true bias of every temperature visit (thermal lag included) from the session
    segs = [t for t in res.truth["segments"] if t["test"] == "bias_temperature"]
    if segs:
        kr = float(g.scale_factor_at(t_base(proto), g.supply_nominal_v)) / \
            res.truth["items"]["scale_factor"]["value"]
        try:
            h, d = rg_hysteresis([t["temperature_c"] for t in segs],
                                 [t["bias_dps"] * kr for t in segs])
        except GonioError:
            h, d = math.nan, {}
        res.truth["items"]["bias_hysteresis"] = {"value": h, "up_minus_down_dps": d,
                                                 "how": "5.3.3.7 on the session's true biases"}
    return res


SPEC = Specification(key=KEY, title_en=TITLE_EN, title_zh=TITLE_ZH,
                     clause_doc="docs/iec62047-20-readings.md", default_protocol=KEY,
                     default_bench="mems-adxrs610", calibrate=calibrate, budget=None)
