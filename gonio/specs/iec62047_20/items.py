"""IEC 62047-20:2014 measured characteristics, one function each (clause in the docstring).

Shared formulas are in :mod:`gonio.analysis.rate_gyro` (the least-squares line, the
Earth-rate projection, sine fits and crossings are the same as for JJF 1535); the
readings taken are in ``docs/iec62047-20-readings.md``. Uncertainties come from the
calibration's own data (GUM, k = t₉₅(ν_eff)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import signal

from gonio.analysis import rate_gyro as rg
from gonio.analysis.noise import allan_deviation, fit_noise_model
from gonio.analysis.rate_records import (Item, gum, not_measured, segment_means,
                                         segment_samples)
from gonio.units import S_PER_H
from uncertainty import from_u, type_b


@dataclass
class Context:
    df: pd.DataFrame
    output_unit: str
    null_output: float
    latitude_deg: float
    a_typ: float
    t_base_c: float
    v_base: float
    protocol: dict
    rate_table_u_rel: float = 2.5e-4
    acquisition_u_rel: float = 3.0e-5
    chamber_deviation_c: float = 2.0
    a_base: float | None = None
    cache: dict = field(default_factory=dict)

    def has(self, test: str) -> bool:
        return bool((self.df["test"] == test).any())


def _miss(ctx, test, key, title, clause, unit, need_a=True):
    if not ctx.has(test):
        return not_measured(key, title, clause, unit, f"no '{test}' records in the readings")
    if need_a and ctx.a_base is None:
        return not_measured(key, title, clause, unit, "needs the scale factor of 5.1.3.1")
    return None


def _sf_runs(ctx: Context, test: str) -> list[dict]:
    """Each 2n + 1-point calibration of ``test`` (5.1.3.1): rates (rest included), means, fit."""
    if ("sf", test) in ctx.cache:
        return ctx.cache[("sf", test)]
    means = segment_means(ctx.df, test)
    out = []
    for run in sorted({m.run for m in means}):
        seg = [m for m in means if m.run == run]
        pts = [m for m in seg if m.role == "rate"]
        if test == "scale_factor" and run != 0:
            continue
        x = np.array([m.rate_dps for m in pts])
        y = np.array([m.mean for m in pts])
        a, b = rg.least_squares_line(x, y)
        r = y - (a * x + b)
        se = math.sqrt(float(r @ r) / (x.size - 2) / float(((x - x.mean()) ** 2).sum())) \
            if x.size > 2 else math.nan
        u_y = []
        for m in pts:
            yy = segment_samples(ctx.df, test, m.run, m.step)["output"].to_numpy()
            nb = yy.size // 5
            u_y.append(float(yy[: nb * 5].reshape(nb, 5).mean(1).std(ddof=1) / math.sqrt(nb))
                       if nb >= 2 else m.std / math.sqrt(m.n))
        out.append({"run": run, "x": x, "y": y, "a": a, "b": b, "se": se,
                    "T": pts[0].temperature_c, "V": pts[0].supply_v, "u_y": np.array(u_y)})
    ctx.cache[("sf", test)] = out
    return out


def _u_rel_sf(ctx: Context, c: dict) -> list:
    return [from_u("a", c["a"], c["se"], dof=c["x"].size - 2, source="least-squares slope"),
            from_u("e_table", 0.0, ctx.rate_table_u_rel, type="B", source="rate table, relative"),
            from_u("e_acq", 0.0, ctx.acquisition_u_rel, type="B", source="acquisition, relative")]


def scale_factor(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.1 eqs (1), (2): a_BASE, least squares over the 2n + 1 points (rest
    included) at T_BASE, V_BASE."""
    t, cl, un = "scale factor a_BASE", "5.1.3.1", f"{ctx.output_unit}/(°/s)"
    m = _miss(ctx, "scale_factor", "scale_factor", t, cl, un, need_a=False)
    if m:
        return m
    c = _sf_runs(ctx, "scale_factor")[0]
    ctx.a_base = c["a"]
    u = gum(lambda a, et, ea: a * (1 + ea) / (1 + et), _u_rel_sf(ctx, c))
    return Item("scale_factor", t, cl, un, c["a"], uncertainty=u,
                details={"b_BASE": c["b"], "x_dps": c["x"], "y": c["y"]})


def initial_sf_variation(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.2 eq (3): (a_BASE − a_TYP)/a_TYP, in %."""
    t, cl, un = "initial scale-factor variation", "5.1.3.2", "%"
    m = _miss(ctx, "scale_factor", "initial_sf_variation", t, cl, un)
    if m:
        return m
    c = _sf_runs(ctx, "scale_factor")[0]
    ins = _u_rel_sf(ctx, c)
    u = gum(lambda a, et, ea: 100 * (a * (1 + ea) / (1 + et) - ctx.a_typ) / ctx.a_typ, ins)
    return Item("initial_sf_variation", t, cl, un, 100 * (c["a"] - ctx.a_typ) / ctx.a_typ,
                uncertainty=u, details={"a_TYP": ctx.a_typ})


def linearity(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.6 eqs (8), (9): L_i = [y_i − (a x_i + b)]/FullScale per point,
    FullScale = y(CW max) − y(CCW max) measured; the characteristic max |L_i|, in %."""
    t, cl, un = "linearity (max |L_i|)", "5.1.3.6", "%"
    m = _miss(ctx, "scale_factor", "linearity", t, cl, un)
    if m:
        return m
    c = _sf_runs(ctx, "scale_factor")[0]
    L, a, b, fs = rg.linearity_errors_iec(c["x"], c["y"])
    i = int(np.argmax(np.abs(L)))
    u_noise = float(np.sqrt(np.mean(c["u_y"] ** 2))) * math.sqrt(2.0) / fs * 100
    u = gum(lambda v, n: v + n, [from_u("L", 100 * abs(L[i]), 0.0),
                                 from_u("noise", 0.0, u_noise, dof=50,
                                        source="noise of the point means / FullScale")])
    return Item("linearity", t, cl, un, 100 * abs(float(L[i])), uncertainty=u, details={
        "L_i_pct": 100 * L, "x_dps": c["x"], "full_scale": fs, "at_dps": float(c["x"][i])})


def symmetry(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.8 eqs (13)–(17): (a_CW − a_CCW)/a_TYP from separate fits without the
    rest point, signed, in %."""
    t, cl, un = "scale-factor symmetry", "5.1.3.8", "%"
    m = _miss(ctx, "scale_factor", "symmetry", t, cl, un)
    if m:
        return m
    c = _sf_runs(ctx, "scale_factor")[0]
    s, aw, bw, ac, bc = rg.symmetry_iec(c["x"], c["y"], ctx.a_typ)
    u_dir = c["se"] * math.sqrt(2.0) * 2.0      # each direction's slope: ~2× the full fit's se
    u = gum(lambda d: 100 * d / ctx.a_typ, [from_u("a_CW-a_CCW", aw - ac, u_dir, dof=2 * len(c["x"]) // 2 - 4,
                                                   source="slope standard errors of the two fits")])
    return Item("symmetry", t, cl, un, 100 * s, uncertainty=u, details={
        "a_CW": aw, "b_CW": bw, "a_CCW": ac, "b_CCW": bc})


def sf_stability(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.7 eqs (10)–(12): δ_i = population std of s samples at a constant
    rate / FullScale; the largest δ_i is reported (rest skipped)."""
    t, cl, un = "scale-factor stability (max δ_i)", "5.1.3.7", "1"
    m = _miss(ctx, "scale_factor", "sf_stability", t, cl, un)
    if m:
        return m
    fs = rg.linearity_errors_iec(*(_sf_runs(ctx, "scale_factor")[0][k] for k in ("x", "y")))[3]
    d = ctx.df[(ctx.df["test"] == "scale_factor") & (ctx.df["run"] == 1)]
    if d.empty:
        return not_measured("sf_stability", t, cl, un, "no constant-rate records (run 1)")
    deltas = {}
    for step, g in d.groupby("step"):
        y = g["output"].to_numpy()
        deltas[float(g["rate_dps"].iloc[0])] = float(np.std(y, ddof=0) / fs)
    r = max(deltas, key=deltas.get)
    n = int((d["rate_dps"] == r).sum())
    u = gum(lambda v: v, [from_u("delta", deltas[r], deltas[r] / math.sqrt(2 * (n - 1)),
                                 dof=n - 1, source="sampling of a standard deviation")])
    return Item("sf_stability", t, cl, un, deltas[r], uncertainty=u,
                details={"delta_by_rate": deltas, "full_scale": fs})


def sf_temperature(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.3 eq (4) and 5.1.3.4 eqs (5), (6): a(T_i) at the m + 1 temperatures,
    S_F,VAR,Ti = (a_Ti − a_BASE)/a_BASE, and the temperature coefficient T_c,SF = least-squares
    slope of a against T; reported as 100·T_c,SF/a_BASE in %/°C (reading taken), the slope
    and the per-point variations in the details."""
    t, cl, un = "scale-factor temperature coefficient", "5.1.3.4", "%/°C"
    m = _miss(ctx, "sf_temperature", "sf_temperature_coefficient", t, cl, un)
    if m:
        return m
    runs = _sf_runs(ctx, "sf_temperature")
    T = np.array([c["T"] for c in runs])
    a = np.array([c["a"] for c in runs])
    ib = int(np.argmin(np.abs(T - ctx.t_base_c)))
    slope, icpt = rg.least_squares_line(T, a)
    var = 100 * (a - a[ib]) / a[ib]
    sxx = float(((T - T.mean()) ** 2).sum())
    u_slope = math.sqrt(sum((c["se"] ** 2) * ((Ti - T.mean()) / sxx) ** 2 for c, Ti in zip(runs, T)))
    u_T = ctx.chamber_deviation_c / math.sqrt(3) * abs(slope) / math.sqrt(sxx / T.size) / math.sqrt(T.size)
    u = gum(lambda s, e, ab: 100 * (s + e) / ab,
            [from_u("T_c", slope, u_slope, dof=50, source="slope from the K_i standard errors"),
             from_u("dT", 0.0, u_T, type="B", source="chamber deviation (independent per point)"),
             from_u("a_BASE", a[ib], runs[ib]["se"], dof=50)])
    return Item("sf_temperature_coefficient", t, cl, un, 100 * slope / a[ib], uncertainty=u,
                details={"T_c_SF": slope, "c": icpt, "temperatures_c": T, "K_i": a,
                         "S_F_VAR_pct": var})


def ratiometric(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.5 eq (7): R_Vi = [a_Vi − a_BASE·V_i/V_BASE]/a_BASE with a_BASE the
    fit at V_BASE of the supply runs; the largest |R_Vi| in % (the plain supply sensitivity
    (a_Vi − a_BASE)/a_BASE kept in the details, for a regulated gyro)."""
    t, cl, un = "scale-factor ratiometric error (max |R|)", "5.1.3.5", "%"
    m = _miss(ctx, "ratiometric", "ratiometric_error", t, cl, un)
    if m:
        return m
    runs = _sf_runs(ctx, "ratiometric")
    V = np.array([c["V"] for c in runs])
    a = np.array([c["a"] for c in runs])
    ib = int(np.argmin(np.abs(V - ctx.v_base)))
    R = np.array([rg.ratiometric_error_iec(a[i], a[ib], V[i], V[ib]) for i in range(V.size)])
    i = int(np.argmax(np.abs(R)))
    u = gum(lambda ai, ab: 100 * abs(rg.ratiometric_error_iec(ai, ab, V[i], V[ib])),
            [from_u("a_Vi", a[i], runs[i]["se"], dof=50), from_u("a_Vb", a[ib], runs[ib]["se"], dof=50)])
    return Item("ratiometric_error", t, cl, un, 100 * abs(float(R[i])), uncertainty=u,
                details={"V": V, "a_V": a, "R_pct": 100 * R,
                         "supply_sensitivity_pct": 100 * (a - a[ib]) / a[ib]})


def cross_axis(ctx: Context) -> Item:
    """IEC 62047-20 5.2.3 eqs (20)–(23), reading taken: ω_x = (Out,x − Out,rest)/SF over whole
    revolutions (the printed ×SF is dimensionally wrong), K = ω_x/ω; with +ω and −ω applied,
    half their difference (bias-free refinement, flagged). Largest of X, Y in %."""
    t, cl, un = "cross-axis sensitivity (max of X, Y)", "5.2", "%"
    m = _miss(ctx, "cross_axis", "cross_axis", t, cl, un)
    if m:
        return m
    per, us = {}, {}
    for run, name in ((0, "X"), (1, "Y")):
        seg = [s for s in segment_means(ctx.df, "cross_axis") if s.run == run]
        if not seg:
            continue
        rest = np.mean([s.mean for s in seg if s.role == "rest"])
        pos = [s for s in seg if s.role == "rate" and s.rate_dps > 0]
        neg = [s for s in seg if s.role == "rate" and s.rate_dps < 0]
        w = pos[0].rate_dps
        kp = rg.cross_axis_iec(pos[0].mean, rest, ctx.a_base, w)
        kd = (pos[0].mean - neg[0].mean) / 2.0 / ctx.a_base / w if neg else kp
        per[name] = {"rest_corrected": kp, "plus_minus": kd}
        us[name] = math.hypot(pos[0].std / math.sqrt(pos[0].n),
                              neg[0].std / math.sqrt(neg[0].n) if neg else 0.0) / 2 / ctx.a_base / w
    if not per:
        return not_measured("cross_axis", t, cl, un, "no rotation about X or Y")
    ax = max(per, key=lambda k: abs(per[k]["plus_minus"]))
    u = gum(lambda k: 100 * abs(k), [from_u("K_" + ax, per[ax]["plus_minus"], us[ax], dof=50,
                                            source="noise of the rotating means")])
    return Item("cross_axis", t, cl, un, 100 * abs(per[ax]["plus_minus"]), uncertainty=u,
                details={"per_axis": per, "axis": ax})


def _axis_enu(up, north):
    from gonio.bench.rate_session import mount_matrix
    return mount_matrix(up, north) @ np.array([0.0, 0.0, 1.0])


def bias(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.1 eq (24): N_bias = Out,ave − Earth-rate component (°/s), computed in
    output units then divided by a_BASE (reading taken). The Earth component uses the
    physics (axis up Ω_E sin λ, horizontal Ω_E cos λ cos φ); the printed sin/cos are swapped
    (erratum). Mean over the records."""
    t, cl, un = "bias N_bias", "5.3.3.1", "°/s"
    m = _miss(ctx, "bias", "bias", t, cl, un)
    if m:
        return m
    vals, earth = [], None
    for s in segment_means(ctx.df, "bias"):
        earth = rg.earth_rate_projection_dps(ctx.latitude_deg, _axis_enu(s.up_axis, s.north_axis))
        vals.append((s.mean - ctx.null_output - ctx.a_base * earth) / ctx.a_base)
    v = np.array(vals)
    u = gum(lambda b: b, [from_u("N_bias", float(v.mean()),
                                 float(v.std(ddof=1) / math.sqrt(v.size)) if v.size > 1 else 0.0,
                                 dof=max(v.size - 1, 1), source="spread of the records")])
    return Item("bias", t, cl, un, float(v.mean()), uncertainty=u, details={
        "records_dps": v, "earth_component_dps": earth,
        "printed_formula_earth_dps": rg.OMEGA_E_DPS * math.cos(math.radians(ctx.latitude_deg)),
        "erratum": "5.3.3.1 prints Ω cos λ for a vertical axis and Ω sin λ cos φ for a "
                   "horizontal one; physically they are Ω sin λ and Ω cos λ cos φ"})


def bias_repeatability(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.4, reading taken: the records' deviations from their mean as
    +max/−min and the half range (max − min)/2 (°/s) as the single ± value."""
    t, cl, un = "bias repeatability (half range)", "5.3.3.4", "°/s"
    m = _miss(ctx, "bias", "bias_repeatability", t, cl, un)
    if m:
        return m
    v = np.array([(s.mean - ctx.null_output) / ctx.a_base for s in segment_means(ctx.df, "bias")])
    if v.size < 2:
        return not_measured("bias_repeatability", t, cl, un, "needs ≥ 2 records")
    hr = float((v.max() - v.min()) / 2)
    u = gum(lambda x: x, [from_u("hr", hr, hr / math.sqrt(2 * (v.size - 1)), dof=v.size - 1)])
    return Item("bias_repeatability", t, cl, un, hr, uncertainty=u, details={
        "plus_dps": float(v.max() - v.mean()), "minus_dps": float(v.min() - v.mean())})


def bias_temperature(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.6 b): bias temperature coefficient, the least-squares slope of bias
    against temperature through every visit (up and down passes), (°/s)/°C; a) the largest
    departures from the base-temperature bias and 5.3.3.7 the hysteresis (largest
    |B_up(T) − B_down(T)|) in the details. Input axis horizontal east: zero Earth input."""
    t, cl, un = "bias temperature coefficient", "5.3.3.6", "(°/s)/°C"
    m = _miss(ctx, "bias_temperature", "bias_temperature_coefficient", t, cl, un)
    if m:
        return m
    kmap = {round(c["T"], 6): c["a"] for c in _sf_runs(ctx, "sf_temperature")} \
        if ctx.has("sf_temperature") else {}
    T, B, us = [], [], []
    for s in segment_means(ctx.df, "bias_temperature"):
        a = kmap.get(round(s.temperature_c, 6), ctx.a_base)
        earth = rg.earth_rate_projection_dps(ctx.latitude_deg, _axis_enu(s.up_axis, s.north_axis))
        T.append(s.temperature_c)
        B.append((s.mean - ctx.null_output) / a - earth)
        us.append(s.std / math.sqrt(s.n) / abs(a))
    T, B = np.array(T), np.array(B)
    slope, c0 = rg.least_squares_line(T, B)
    r = B - (slope * T + c0)
    se = math.sqrt(float(r @ r) / (T.size - 2) / float(((T - T.mean()) ** 2).sum())) if T.size > 2 else 0.0
    base = B[np.abs(T - ctx.t_base_c) < 1e-9]
    # hysteresis: same temperature on the rising and the falling pass
    hyst = 0.0
    for Tv in np.unique(T):
        b = B[T == Tv]
        if b.size >= 2:
            hyst = max(hyst, float(b.max() - b.min()))
    u = gum(lambda s: s, [from_u("slope", slope, se, dof=max(T.size - 2, 1),
                                 source="least-squares slope (residual scatter)")])
    return Item("bias_temperature_coefficient", t, cl, un, slope, uncertainty=u, details={
        "temperatures_c": T, "bias_dps": B, "bias_dph": B * S_PER_H,
        "variation_max_dps": float((B - base.mean()).max()),
        "variation_min_dps": float((B - base.mean()).min()), "hysteresis_dps": hyst})


def _static(ctx: Context):
    if "allan" in ctx.cache:
        return ctx.cache["allan"]
    g = segment_samples(ctx.df, "static", 0, 0)
    t = g["time_s"].to_numpy()
    dt = float((t[-1] - t[0]) / (t.size - 1))
    rate_dph = (g["output"].to_numpy() - ctx.null_output) / ctx.a_base * S_PER_H
    allan = allan_deviation(rate_dph, dt, "rate", "decade:10", unit="deg/h")
    ctx.cache["allan"] = (allan, rate_dph, dt)
    return ctx.cache["allan"]


def _quiet(ctx: Context, key: str, title: str, clause: str, unit: str) -> Item | None:
    """A static record without any variation (noise-free bench): the noise terms are 0."""
    y = segment_samples(ctx.df, "static", 0, 0)["output"].to_numpy()
    if y.size and np.ptp(y) == 0:
        return Item(key, title, clause, unit, 0.0, uncertainty=gum(lambda v: v, [from_u(key, 0.0, 0.0)]),
                    details={"note": "the static record does not vary: no noise to analyse"})
    return None


def arw(ctx: Context) -> Item:
    """IEC 62047-20 5.4.5.2: the −½ line through the short-τ part of the Allan deviation read
    at τ = 1 h (°/√h); (29): 1 °/√h = 60 (°/h)/√Hz. Uncertainty from the χ² intervals of the
    points used."""
    t, cl, un = "angular random walk", "5.4.5.2", "°/√h"
    m = _miss(ctx, "static", "arw", t, cl, un) or _quiet(ctx, "arw", t, cl, un)
    if m:
        return m
    allan, _, _ = _static(ctx)
    val, mask = rg.arw_minus_half_line(allan.tau_s, allan.adev)
    rel = np.abs(np.log(allan.ci_high[mask] / allan.adev[mask]))
    u_rel = float(np.sqrt(np.mean(rel ** 2)) / math.sqrt(mask.sum())) * 2.0   # correlated τ
    u = gum(lambda n: n, [from_u("N", val, val * u_rel, dof=50, source="χ² intervals of the fit points")])
    return Item("arw", t, cl, un, val, uncertainty=u, details={
        "dph_per_sqrt_hz": val * math.sqrt(S_PER_H), "tau_used_s": allan.tau_s[mask]})


def bias_instability(ctx: Context) -> Item:
    """IEC 62047-20 5.4.5.3 c): Allan-deviation floor / 0.664 (°/h), over τ with ≥ 10
    independent clusters (reading taken); the five-term fit's B in the details."""
    t, cl, un = "bias instability", "5.4.5.3", "°/h"
    m = _miss(ctx, "static", "bias_instability", t, cl, un) or _quiet(ctx, "bias_instability", t, cl, un)
    if m:
        return m
    allan, rate, dt = _static(ctx)
    n_cl = allan.n_samples / allan.m
    val, i = rg.bias_instability_floor(allan.adev, n_clusters=n_cl)
    rel = math.log(allan.ci_high[i] / allan.adev[i])
    fit = fit_noise_model(allan)
    u = gum(lambda b: b, [from_u("floor", val, val * rel, dof=float(allan.edf[i]),
                                 source="χ² interval at the floor")])
    return Item("bias_instability", t, cl, un, val, uncertainty=u, details={
        "tau_floor_s": float(allan.tau_s[i]), "fit": fit.to_dict(),
        "allan": {"tau_s": allan.tau_s, "adev_dph": allan.adev, "ci_low": allan.ci_low,
                  "ci_high": allan.ci_high}})


def inband_noise(ctx: Context) -> Item:
    """IEC 62047-20 5.4.5.1 b), reading taken: the rms output noise below ``band_hz`` (°/s) from
    the Welch one-sided density, and the amplitude density ((°/s)/√Hz) at stated frequencies
    in the details. The broadband "20 dB/dec" figure of c) is not implemented (see docs)."""
    t, cl, un = "in-band noise (rms)", "5.4.5.1 b)", "°/s"
    m = _miss(ctx, "static", "inband_noise", t, cl, un) or _quiet(ctx, "inband_noise", t, cl, un)
    if m:
        return m
    _, rate_dph, dt = _static(ctx)
    x = rate_dph / S_PER_H
    f, p = signal.welch(x - x.mean(), fs=1.0 / dt, nperseg=min(4096, x.size))
    band = ctx.protocol["noise"]["band_hz"]
    sel = (f > 0) & (f <= band)
    rms = math.sqrt(float(np.trapezoid(p[sel], f[sel])))
    dens = {str(fq): float(np.sqrt(np.interp(fq, f, p))) for fq in ctx.protocol["noise"]["density_at_hz"]}
    nseg = max(1, x.size // 2048)
    u = gum(lambda r: r, [from_u("rms", rms, rms / math.sqrt(2 * nseg * max(sel.sum(), 1)) * 2,
                                 dof=50, source="Welch estimate")])
    return Item("inband_noise", t, cl, un, rms, uncertainty=u,
                details={"density_dps_per_sqrt_hz": dens, "band_hz": band})


def frequency_band(ctx: Context) -> Item:
    """IEC 62047-20 5.5.3, 5.5.5: gain and phase by sine fits against the reference; the band
    is the lower of the −3 dB frequency and the 90° ± 5° lag frequency (reading taken: both
    reported); gain peak (dB, frequency) in the details."""
    t, cl, un = "frequency band", "5.5", "Hz"
    if not ctx.has("vibration"):
        return not_measured("frequency_band", t, cl, un, "no 'vibration' records in the readings")
    f, K, ph, uph = [], [], [], []
    for s in segment_means(ctx.df, "vibration"):
        g = segment_samples(ctx.df, "vibration", s.run, s.step)
        tt = g["time_s"].to_numpy()
        yo = g["output"].to_numpy()
        ao, po, co = rg.sine_fit(tt, yo, s.freq_hz)
        ar, pr, _ = rg.sine_fit(tt, g["reference_dps"].to_numpy(), s.freq_hz)
        res = yo - co - ao * np.sin(2 * math.pi * s.freq_hz * tt + math.radians(po))
        uph.append(math.degrees(float(np.std(res)) * math.sqrt(2.0 / tt.size) / ao))
        f.append(s.freq_hz)
        K.append(ao / ar)
        ph.append(((po - pr + 180.0) % 360.0) - 180.0)
    f, K = np.array(f), np.array(K)
    ph = np.degrees(np.unwrap(np.radians(ph)))
    f3 = rg.minus3db_frequency(f, K)
    f90 = rg.phase90_frequency(f, ph)
    cands = [v for v in (f3, f90) if math.isfinite(v)]
    if not cands:
        return not_measured("frequency_band", t, cl, un, "neither −3 dB nor 90° lag reached")
    band = min(cands)
    db = 20 * np.log10(K / K[0])
    ip = int(np.argmax(db))
    grid = float(np.min(np.diff(np.log(f)))) if f.size > 1 else 0.0
    j = min(max(int(np.searchsorted(f, band)), 1), f.size - 1)
    if band == f90:
        slope = abs((ph[j] - ph[j - 1]) / (f[j] - f[j - 1]))            # ° per Hz
        u_f = math.hypot(uph[j], uph[j - 1]) / slope if slope > 0 else 0.0
    else:
        slope = abs((db[j] - db[j - 1]) / (f[j] - f[j - 1]))
        u_f = 20 / math.log(10) * math.hypot(uph[j], uph[j - 1]) * math.pi / 180 / slope \
            if slope > 0 else 0.0
    u = gum(lambda b, n, i: b + n + i,
            [from_u("f", band, 0.0), from_u("noise", 0.0, u_f, dof=50,
                                            source="phase/gain noise of the bracketing points"),
             type_b("interp", 0.0, band * grid * 0.05, "rectangular",
                    source="interpolation between grid points")])
    return Item("frequency_band", t, cl, un, band, uncertainty=u, details={
        "freq_hz": f, "gain_db": db, "phase_deg": ph, "minus3db_hz": f3, "phase90_hz": f90,
        "phase90_hz_iec": f90, "criterion": "-3 dB" if band == f3 else "90 deg lag",
        "gain_peak_db": float(db[ip]), "gain_peak_hz": float(f[ip])})


def _power_on_records(ctx: Context):
    po = ctx.protocol["power_on"]
    for s in segment_means(ctx.df, "warmup"):
        g = segment_samples(ctx.df, "warmup", s.run, s.step)
        y = (g["output"].to_numpy() - ctx.null_output) / ctx.a_base      # °/s (Earth included)
        P = po["smoothing_samples"]
        n = y.size // P
        t = g["time_s"].to_numpy()[: n * P].reshape(n, P).mean(1)
        ys = y[: n * P].reshape(n, P).mean(1)
        yield s.run, t, ys, y


def initial_bias_variation(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.2 eq (25): bias (Earth rate removed, 5.3.3.1) minus the nominal bias
    Out,typ, in °/s (reading taken: divided by a_BASE when the output is in V or bit)."""
    t, cl, un = "initial bias variation", "5.3.3.2", "°/s"
    m = _miss(ctx, "bias", "initial_bias_variation", t, cl, un)
    if m:
        return m
    b = bias(ctx)
    typ = ctx.protocol["power_on"]["nominal_bias_dps"]
    u = gum(lambda x: x - typ, [from_u("N_bias", b.value, b.uncertainty.u_c,
                                       dof=b.uncertainty.nu_eff, source="bias of 5.3.3.1")])
    return Item("initial_bias_variation", t, cl, un, b.value - typ, uncertainty=u,
                details={"nominal_bias_dps": typ})


def bias_drift_after_power_on(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.5 eq (27), reading taken: Out,ave = mean over the reference part just
    after power-on; the drift is max_t |Out(t) − Out,ave| over the record, Out(t) averaged over
    ``smoothing_samples`` (the literal max|Out| − Out,ave misbehaves for negative outputs);
    the largest over the records, °/s."""
    t, cl, un = "bias drift after power on", "5.3.3.5", "°/s"
    m = _miss(ctx, "warmup", "bias_drift_after_power_on", t, cl, un)
    if m:
        return m
    po = ctx.protocol["power_on"]
    vals, noise = [], []
    for run, tt, ys, y in _power_on_records(ctx):
        ref = float(y[: po["reference_samples"]].mean())
        vals.append(float(np.max(np.abs(ys - ref))))
        noise.append(float(np.std(np.diff(ys)) / math.sqrt(2)))
    i = int(np.argmax(vals))
    u = gum(lambda v: v, [from_u("drift", vals[i], noise[i], dof=50,
                                 source="noise of the smoothed output")])
    return Item("bias_drift_after_power_on", t, cl, un, vals[i], uncertainty=u,
                details={"per_record_dps": vals})


def startup_time(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.9, reading taken: the first time after power-on after which the
    smoothed output stays within ± ``startup_band_dps`` of the reference output (the settled
    bias: mean of the last fifth of the record); the mean over the records, s."""
    t, cl, un = "start-up time", "5.3.3.9", "s"
    m = _miss(ctx, "warmup", "startup_time", t, cl, un)
    if m:
        return m
    band = ctx.protocol["power_on"]["startup_band_dps"]
    times = []
    for run, tt, ys, y in _power_on_records(ctx):
        ref = float(y[-max(y.size // 5, 1):].mean())
        out = np.abs(ys - ref) > band
        last = np.flatnonzero(out)
        times.append(0.0 if last.size == 0 else
                     (float(tt[last[-1] + 1] - tt[0]) if last[-1] + 1 < tt.size else math.nan))
    v = np.array(times)
    if np.any(~np.isfinite(v)):
        return not_measured("startup_time", t, cl, un, "the output never settled within the band")
    step = float(np.median(np.diff(tt))) if tt.size > 1 else 0.0
    u = gum(lambda a, b, c: a + b + c,
            [from_u("t", float(v.mean()), 0.0),
             from_u("s_t", 0.0, float(v.std(ddof=1) / math.sqrt(v.size)) if v.size > 1 else 0.0,
                    dof=max(v.size - 1, 1), source="spread over the power-ups"),
             type_b("step", 0.0, step / 2, "rectangular", source="smoothing step")])
    return Item("startup_time", t, cl, un, float(v.mean()), uncertainty=u,
                details={"per_record_s": v, "band_dps": band})


#: The characteristics in the order of Table 4: (key, title, clause, function).
ITEMS = (
    ("scale_factor", "scale factor a_BASE", "5.1.3.1", scale_factor),
    ("initial_sf_variation", "initial scale-factor variation", "5.1.3.2", initial_sf_variation),
    ("sf_temperature_coefficient", "scale-factor temperature coefficient", "5.1.3.4", sf_temperature),
    ("ratiometric_error", "scale-factor ratiometric error", "5.1.3.5", ratiometric),
    ("linearity", "linearity", "5.1.3.6", linearity),
    ("sf_stability", "scale-factor stability", "5.1.3.7", sf_stability),
    ("symmetry", "scale-factor symmetry", "5.1.3.8", symmetry),
    ("cross_axis", "cross-axis sensitivity", "5.2", cross_axis),
    ("bias", "bias N_bias", "5.3.3.1", bias),
    ("initial_bias_variation", "initial bias variation", "5.3.3.2", initial_bias_variation),
    ("bias_repeatability", "bias repeatability", "5.3.3.4", bias_repeatability),
    ("bias_drift_after_power_on", "bias drift after power on", "5.3.3.5", bias_drift_after_power_on),
    ("bias_temperature_coefficient", "bias temperature coefficient", "5.3.3.6", bias_temperature),
    ("startup_time", "start-up time", "5.3.3.9", startup_time),
    ("inband_noise", "in-band noise", "5.4.5.1 b)", inband_noise),
    ("arw", "angular random walk", "5.4.5.2", arw),
    ("bias_instability", "bias instability", "5.4.5.3", bias_instability),
    ("frequency_band", "frequency band", "5.5", frequency_band),
)
