"""The formulas of IEC 62047-20:2014 alone (the ``*_iec`` functions and the IEC readings
taken); what IEC 62047-20 and JJF 1535 share is :mod:`gonio.specs._rate_family.formulas`.

Conventions as there: Ω (``rate_dps``) in °/s; y the gyro's output; temperatures in °C. The
clause readings are documented in ``docs/iec62047-20-readings.md``.

Contents
========
==============================  ==================================================
:func:`linearity_errors_iec`    IEC (8), (9)
:func:`symmetry_iec`            IEC (13)–(17)
:func:`ratiometric_error_iec`   IEC (7), (26)
:func:`cross_axis_iec`          IEC (20)–(23), read as a division by SF
:func:`arw_minus_half_line`     IEC 5.4.5.2 e): slope −½ line read at 1 h
:func:`bias_instability_floor`  IEC 5.4.5.3 c): floor / 0.664
:func:`voltage_corrected`       IEC (18): each run referred to its own set voltage
:func:`hysteresis_iec`          IEC 5.3.3.7 reading: up/down visits of each temperature
:func:`resolution_iec`          IEC 5.6.3: the one-sided 50 % walk
:func:`boxcar_noise_rms`        IEC 5.6.3 reading: noise of a T-second mean from S(f)
:func:`broadband_noise_iec`     IEC 5.4.5.1 c) reading: rms and the 20 dB/dec value
:func:`g_slope_iec`             IEC 5.3.3.8 reading: slope against g cos γ, Earth rate removed
:func:`normal_range_cdf`        P(R/σ ≤ w), range of n normal values (Tippett)
:func:`normal_range_mean`       d_n = E[R/σ] of n normal values
:func:`half_range_upper`        IEC 5.3.3.4: one-sided upper limit of the expected half range
:func:`max_abs_normal_mean`     c_n = E[max |Z_i|] (5.3.3.7's selection excess; shared, re-exported)
:func:`hysteresis_level_iec`    IEC 5.3.3.7: the reading's least-favourable distribution G(M; h)
:func:`hysteresis_upper_iec`    IEC 5.3.3.7: one-sided upper limit of the largest true |B_up − B_down|
:func:`hysteresis_level_grid`   IEC 5.3.3.7: the statement's level z on a grid (for a study)
:func:`walk_coefficient_bound`  IEC 5.1.3, 5.3.3: the largest K² the static record allows
:func:`walk_k2_iec`             IEC 5.1.3, 5.3.3: E[K²] of every item's bias drift (posterior mean)
:func:`max_spread_moments`      IEC 5.1.3.7: E and sd of max δ_i, δ_i independent scaled χ
:func:`max_spread_estimate`     IEC 5.1.3.7: max σ_i from max δ_i, the maximum's bias removed
:func:`max_spread_bounds`       IEC 5.1.3.7: bounds of max σ_i, any record lengths
:func:`max_spread_level_z`      IEC 5.1.3.7: the level z of those bounds at a given max σ_i
:func:`max_spread_level_grid`   IEC 5.1.3.7: that level z on a grid (for a study)
==============================  ==================================================
"""

from __future__ import annotations

import math

import numpy as np

from gonio.errors import GonioError
from gonio.specs._rate_family.formulas import (FLICKER_FLOOR_EXACT, as_array,  # noqa: F401
                                               least_squares_line, max_abs_normal_mean)
from gonio.units import S_PER_H




def arw_minus_half_line(tau_s, adev_dph, *, slope_tol: float = 0.05) -> tuple[float, np.ndarray]:
    """IEC 62047-20 5.4.5.2 e), reading taken: a line of slope −½ through the short-τ part of
    the Allan curve — the τ from the shortest one up to the first whose local slope leaves
    −½ ± ``slope_tol`` — its value at τ = 1 h in °/h is the ARW in °/√h. Returns
    (ARW °/√h, mask of the τ used).

    >>> tau = np.array([1.0, 2, 4, 8, 16])
    >>> round(arw_minus_half_line(tau, 4.8 / np.sqrt(tau))[0], 6)
    0.08
    """
    t, s = as_array(tau_s, "tau_s"), as_array(adev_dph, "adev")
    lt, ls = np.log(t), np.log(s)
    slope = np.gradient(ls, lt)
    ok = np.abs(slope + 0.5) <= slope_tol
    first_bad = np.flatnonzero(~ok)
    first_bad = first_bad[first_bad > int(np.argmax(ok))] if ok.any() else first_bad
    end = int(first_bad[0]) if first_bad.size else ok.size
    mask = ok & (np.arange(ok.size) < end)
    if not mask.any():
        raise GonioError("IEC 62047-20 5.4.5.2: no part of the Allan curve has slope −½")
    n_sqrt_s = math.exp(float(np.mean(ls[mask] + 0.5 * lt[mask])))   # (°/h)·√s
    return n_sqrt_s / math.sqrt(S_PER_H), mask


def bias_instability_floor(adev_dph, *, n_clusters=None, min_clusters: int = 10) -> tuple[float, int]:
    """IEC 62047-20 5.4.5.3 c): the floor (minimum) of the Allan deviation divided by
    √(2 ln 2/π) = 0.664282; reading taken: only τ with ≥ ``min_clusters`` independent
    clusters (``n_clusters``) count. Returns (B, index of the floor).

    >>> round(bias_instability_floor([1.0, 0.4, 0.5])[0], 3)
    0.602
    """
    s = as_array(adev_dph, "adev")
    ok = np.ones(s.size, bool) if n_clusters is None else np.asarray(n_clusters) >= min_clusters
    if not ok.any():
        raise GonioError("no τ has enough clusters for the bias-instability floor")
    idx = np.flatnonzero(ok)[int(np.argmin(s[ok]))]
    return float(s[idx] / FLICKER_FLOOR_EXACT), int(idx)


def linearity_errors_iec(rates_dps, outputs) -> tuple[np.ndarray, float, float, float]:
    """IEC 62047-20 5.1.3.6 eqs (8), (9): L_i = [y_i − (a x_i + b)]/FullScale, the line of
    5.1.3.1 (rest point included), FullScale = y(CW max) − y(CCW max) (measured, magnitude).

    Returns (L_i array, a_BASE, b_BASE, FullScale).
    """
    x, y = as_array(rates_dps, "rate_dps"), as_array(outputs, "output")
    a, b = least_squares_line(x, y)
    fs = abs(float(y[np.argmax(x)] - y[np.argmin(x)]))
    if fs == 0:
        raise GonioError("IEC 62047-20 (9): full-scale span is zero")
    return (y - (a * x + b)) / fs, a, b, fs


def symmetry_iec(rates_dps, outputs, a_typ: float) -> tuple[float, float, float, float, float]:
    """IEC 62047-20 5.1.3.8 eqs (13)–(17): separate CW (x > 0) and CCW (x < 0) fits without
    the rest point; S = (a_CW − a_CCW)/a_TYP (signed). Returns (S, a_CW, b_CW, a_CCW, b_CCW).
    """
    x, y = as_array(rates_dps, "rate_dps"), as_array(outputs, "output")
    aw, bw = least_squares_line(x[x > 0], y[x > 0])
    ac, bc = least_squares_line(x[x < 0], y[x < 0])
    return (aw - ac) / a_typ, aw, bw, ac, bc


def ratiometric_error_iec(a_v: float, a_base: float, v: float, v_base: float) -> float:
    """IEC 62047-20 5.1.3.5 eq (7) and 5.3.3.3 eq (26), reading taken (ratio V_i/V_BASE):
    R = [a_V − a_BASE·V/V_BASE]/a_BASE.

    >>> round(ratiometric_error_iec(5.403, 6.0, 4.5, 5.0), 6)
    0.0005
    """
    return (a_v - a_base * v / v_base) / a_base


def cross_axis_iec(out_rotating: float, out_rest: float, sf: float, applied_dps: float) -> float:
    """IEC 62047-20 5.2.3 eqs (20)–(23), reading taken: ω_x = (Out,x − Out,rest)/SF (the
    printed ×SF is dimensionally wrong), K_x = ω_x/ω.

    >>> cross_axis_iec(3.0, 0.0, 6.0, 100.0)
    0.005
    """
    return (out_rotating - out_rest) / sf / applied_dps


def voltage_corrected(y_raw, v_set: float, v_actual: float):
    """IEC 62047-20 5.1.4.1 e) eq (18): y = y_RAW·V_set/V_actual, each run referred to its own
    set voltage (reading taken).

    >>> round(voltage_corrected(1000.0, 5.0, 4.9998), 2)
    1000.04
    """
    return np.asarray(y_raw, float) * (v_set / v_actual) if np.ndim(y_raw) else \
        float(y_raw) * v_set / v_actual


def hysteresis_iec(temps_c, values) -> tuple[float, dict]:
    """IEC 62047-20 5.3.3.7, reading taken: each visit of the programme base → max → base →
    min → base (5.3.4.4 e)) is "up" when reached from a lower temperature and "down" when
    reached from a higher one (the first visit has neither); the hysteresis is
    max over temperatures of |B_up(T) − B_down(T)|. Returns (value, {T: B_up − B_down}).

    >>> T = [25, 50, 85, 50, 25, 0, -40, 0, 25]
    >>> B = [1.0, 2.0, 3.0, 2.5, 1.2, 0.5, 0.1, 0.4, 0.9]
    >>> h, d = hysteresis_iec(T, B)
    >>> round(h, 12), {k: round(v, 12) for k, v in d.items()}
    (0.5, {0.0: -0.1, 25.0: -0.3, 50.0: -0.5})
    """
    t, b = as_array(temps_c, "temperature_c"), as_array(values, "bias")
    if t.size != b.size:
        raise GonioError("hysteresis: temperatures and biases must have equal length")
    up: dict[float, float] = {}
    down: dict[float, float] = {}
    for i in range(1, t.size):
        if t[i] > t[i - 1]:
            up[float(t[i])] = float(b[i])
        elif t[i] < t[i - 1]:
            down[float(t[i])] = float(b[i])
    both = sorted(set(up) & set(down))
    if not both:
        raise GonioError("IEC 62047-20 5.3.3.7: no temperature visited both rising and falling")
    d = {T: up[T] - down[T] for T in both}
    return float(max(abs(v) for v in d.values())), d


def resolution_iec(steps_dps, response_dps, *, limit: float = 0.5) -> tuple[float | None, list[float]]:
    """IEC 62047-20 5.6.3: the smallest input-rate change whose output change (as a rate,
    output change / scale factor) is at least ``limit`` = 50 % of it, walking the steps in
    the order given (decreasing) and stopping at the first that fails (one-sided: "at least
    50 %"). Returns (resolution or None when the first step fails, ratios response/step).

    Digest number 6: a 0.01 °/s step answered by 0.005 °/s is exactly 50 %.

    >>> resolution_iec([0.02, 0.01, 0.005], [0.019, 0.005, 0.002])
    (0.01, [0.95, 0.5, 0.4])
    """
    s, r = as_array(steps_dps, "step"), as_array(response_dps, "response")
    if s.size != r.size or s.size == 0:
        raise GonioError("5.6.3: steps and responses must have equal, non-zero length")
    ratio = r / s
    out = None
    for i in range(s.size):
        if ratio[i] >= limit - 1e-12:
            out = float(abs(s[i]))
        else:
            break
    return out, [round(float(v), 12) for v in ratio]


def boxcar_noise_rms(freq_hz, psd_one_sided, averaging_s: float) -> float:
    """IEC 62047-20 5.6.3 reading taken: Noise,RMS of a rate averaged over ``averaging_s``
    (the filter of the resolution test) from a one-sided density S(f):
    √∫ S(f)·sinc²(π f T) df (trapezoid over the given f). For white S = 2N² this is
    N/√T, the standard deviation of a T-second mean.

    >>> f = np.linspace(0, 500, 200001)
    >>> round(boxcar_noise_rms(f, np.full(f.size, 2.0 * 0.03 ** 2), 5.0) / (0.03 / 5 ** 0.5), 3)
    1.0
    """
    f, p = as_array(freq_hz, "freq_hz"), as_array(psd_one_sided, "psd")
    if not averaging_s > 0:
        raise GonioError(f"averaging time must be > 0, got {averaging_s}")
    h2 = np.sinc(f * averaging_s) ** 2          # numpy sinc(x) = sin(πx)/(πx)
    return math.sqrt(float(np.trapezoid(p * h2, f)))


def broadband_noise_iec(freq_hz, psd_one_sided, f_low_hz: float, f_high_hz: float) -> dict:
    """IEC 62047-20 5.4.5.1 c), reading taken: over the broadband region [f_low, f_high]
    (above the in-band limit), (i) the rms noise √∫S df (°/s, Table 4's unit) and (ii) the
    "20 dB/dec value": the coefficient c of an amplitude density c/f fitted with the slope
    fixed at −1 (log c = mean of log(√S·f)), in °/s^1.5, with the free log–log slope beside it
    so a reader sees whether the region really falls at 20 dB/dec.

    >>> f = np.linspace(0.5, 50, 9901)                 # ∫₁⁵⁰ 0.04/f² df = 0.04·(1 − 1/50)
    >>> d = broadband_noise_iec(f, (0.2 / f) ** 2, 1.0, 50.0)
    >>> round(d["c_dps_1p5"], 9), round(d["slope_db_per_decade"], 6), round(d["rms_dps"] ** 2, 4)
    (0.2, -20.0, 0.0392)
    """
    f, p = as_array(freq_hz, "freq_hz"), as_array(psd_one_sided, "psd")
    if not 0 < f_low_hz < f_high_hz:
        raise GonioError(f"broadband region needs 0 < f_low < f_high, got {f_low_hz}, {f_high_hz}")
    sel = (f >= f_low_hz) & (f <= f_high_hz) & (p > 0)
    if sel.sum() < 3:
        raise GonioError("5.4.5.1 c): fewer than 3 spectral lines in the broadband region")
    fs, ps = f[sel], p[sel]
    la = 0.5 * np.log10(ps)
    lf = np.log10(fs)
    c = 10.0 ** float(np.mean(la + lf))
    slope = least_squares_line(lf, la)[0]
    return {"rms_dps": math.sqrt(float(np.trapezoid(ps, fs))), "c_dps_1p5": c,
            "slope_db_per_decade": 20.0 * slope, "lines": int(sel.sum())}


def g_slope_iec(accel_g, rate_dps, earth_dps=None, transverse_g=None) -> tuple[float, float]:
    """IEC 62047-20 5.3.3.8, reading taken: the first-order fit of the gyro rate against the
    applied acceleration a = g cos γ (γ = 0 with the input axis up), the Earth-rate
    projection at each angle subtracted first; with ``transverse_g`` (the second transverse
    component, g sin γ) both slopes are fitted jointly, ω = c + s₁a₁ + s₂a₂. Returns
    (slope along ``accel_g``, slope along ``transverse_g`` or NaN), (°/s)/g.

    >>> g = np.cos(np.radians(np.arange(0, 360, 45)))
    >>> round(g_slope_iec(g, 0.1 + 0.02 * g + 0.003 * g, 0.003 * g)[0], 12)
    0.02
    """
    a = as_array(accel_g, "acceleration")
    w = as_array(rate_dps, "rate_dps") - (0.0 if earth_dps is None else as_array(earth_dps, "earth"))
    cols = [np.ones_like(a), a] + ([] if transverse_g is None else [as_array(transverse_g, "accel")])
    A = np.column_stack(cols)
    if a.size < A.shape[1] + 1 or np.linalg.matrix_rank(A) < A.shape[1]:
        raise GonioError("5.3.3.8: the stand angles do not determine the slope")
    coef, *_ = np.linalg.lstsq(A, w, rcond=None)
    return float(coef[1]), (float(coef[2]) if transverse_g is not None else math.nan)


# --------------------------------------------------------------------------- range of n normals

def normal_range_cdf(w: float, n: int) -> float:
    """P(R/σ ≤ w) for the range R of ``n`` independent normal values of standard deviation σ
    (Tippett 1925): n ∫ φ(x) [Φ(x + w) − Φ(x)]^(n−1) dx.

    >>> round(normal_range_cdf(3.314, 3), 3)     # Pearson–Hartley table: w_0.95(3) = 3.314
    0.95
    """
    from scipy import integrate
    from scipy.special import ndtr

    if w <= 0:
        return 0.0
    f = lambda x: _phi(x) * (ndtr(x + w) - ndtr(x)) ** (n - 1)  # noqa: E731
    return float(min(1.0, n * integrate.quad(f, -12.0, 12.0, limit=200)[0]))


def _phi(x):
    """φ(x) as ``scipy.stats.norm.pdf`` evaluates it (exp(−x²/2)/√(2π)), bit for bit, without
    its argument checks: the integrands here are called thousands of times inside a root
    search; Φ is ``scipy.special.ndtr`` (norm.cdf's own evaluation)."""
    return np.exp(-np.asarray(x, dtype=float) ** 2 / 2.0) / _SQRT_2PI


_SQRT_2PI = np.sqrt(2 * np.pi)


def normal_range_mean(n: int) -> float:
    """d_n = E[R/σ], the mean range of ``n`` normal values: ∫ 1 − Φ(x)ⁿ − (1 − Φ(x))ⁿ dx.

    >>> round(normal_range_mean(2), 4), round(normal_range_mean(3), 4)   # 2/√π, d₃ = 1.693
    (1.1284, 1.6926)
    """
    from scipy import integrate
    from scipy.special import ndtr

    f = lambda x: 1.0 - ndtr(x) ** n - ndtr(-x) ** n  # noqa: E731
    return float(integrate.quad(f, -12.0, 12.0, limit=200)[0])


def half_range_upper(half_range: float, n: int, p: float = 0.95) -> float:
    """IEC 62047-20 5.3.3.4, reading taken: the one-sided ``p`` upper limit of the expected
    half range θ = d_n σ/2 of ``n`` records, from the observed half range h = R/2:
    P(θ ≤ h·d_n/w_(1−p)) = P(R/σ ≥ w_(1−p)) = p, w_q the q-quantile of the normal range.

    >>> round(half_range_upper(1.0, 3), 3)       # d₃/w_0.05(3) = 1.6926/0.4315 (Harter)
    3.923
    """
    from scipy import optimize

    if not (n >= 2 and 0.0 < p < 1.0 and half_range >= 0.0):
        raise GonioError(f"half range {half_range!r} of {n} records at p = {p!r}: needs n ≥ 2")
    q = 1.0 - p
    w = optimize.brentq(lambda x: normal_range_cdf(x, n) - q, 1e-9, 40.0, xtol=1e-12)
    return float(half_range * normal_range_mean(n) / w)


# --------------------------------------------------------------------------- 5.3.3.6, 5.3.3.7

def hysteresis_level_iec(reading: float, sds, h) -> np.ndarray:
    """IEC 62047-20 5.3.3.7, the reading's distribution the statement is inverted from:
    G(M; h) = the largest probability P(max_T |D_T| ≤ M) any set of true differences
    whose largest |δ_T| is h gives, with D_T ~ N(δ_T, σ_T²) independent (``sds`` the σ_T):
    P(max_T |D_T| ≤ M) = Π_T F(M; δ_T, σ_T), F the folded normal
    Φ((M − δ)/σ) − Φ((−M − δ)/σ), each factor largest at δ_T = 0, so the least favourable
    set puts h on one temperature j and 0 on the others:
    G(M; h) = max_j F(M; h, σ_j)·Π_(T≠j) F(M; 0, σ_T). With every true difference 0 (h = 0,
    the study bench's chamber without lag) it is the exact distribution function of the
    reading, so G(M; H) of the truth H is uniform: its Φ⁻¹ is the statement's own level z
    (the probability integral transform). A σ of 0: that difference is exact (its factor
    the indicator |δ| ≤ M). ``h``: one value or an array; returns G at each. Φ is
    ``scipy.special.ndtr`` (what ``scipy.stats.norm.cdf`` evaluates, bit for bit, without its
    argument checks: this runs inside the root search of :func:`hysteresis_upper_iec`).

    >>> from scipy.stats import norm
    >>> g = hysteresis_level_iec(1.0, [1.0, 2.0], [0.0, 0.5])
    >>> F = lambda m, d, s: norm.cdf((m - d) / s) - norm.cdf((-m - d) / s)
    >>> round(float(g[0]), 12) == round(float(F(1, 0, 1) * F(1, 0, 2)), 12)
    True
    >>> round(float(g[1]), 12) == round(float(max(F(1, .5, 1) * F(1, 0, 2),
    ...                                            F(1, .5, 2) * F(1, 0, 1))), 12)
    True
    """
    from scipy.special import ndtr

    m, s = float(reading), as_array(sds, "sds")
    hh = np.atleast_1d(np.asarray(h, dtype=float))
    if not (m >= 0.0 and np.all(s >= 0.0) and s.size and np.all(hh >= 0.0)):
        raise GonioError(f"5.3.3.7: reading {reading!r}: needs reading ≥ 0, standard "
                         "deviations ≥ 0 and h ≥ 0")

    def fold(d, sj):
        if sj == 0.0:
            return (np.abs(d) <= m).astype(float)
        return ndtr((m - d) / sj) - ndtr((-m - d) / sj)

    f0 = np.array([float(fold(np.zeros(1), float(sj))[0]) for sj in s])
    out = np.zeros_like(hh)
    for j, sj in enumerate(s):
        rest = float(np.prod(np.delete(f0, j)))
        out = np.maximum(out, fold(hh, float(sj)) * rest)
    return out


def hysteresis_upper_iec(reading: float, sds, p: float = 0.95) -> float:
    """IEC 62047-20 5.3.3.7, the statement: the one-sided ``p`` upper confidence limit of the
    true hysteresis H = max_T |δ_T| (δ_T the true B_up − B_down at temperature T) from the
    reading M = max_T |D_T| (:func:`hysteresis_iec`), each difference D_T ~ N(δ_T, σ_T²)
    with ``sds`` the σ_T, by inverting the test of H = h on the reading's distribution
    (:func:`hysteresis_level_iec`): h_p = sup{h ≥ 0 : G(M; h) ≥ 1 − p}, G the largest
    P(max |D_T| ≤ M) a set of true differences with max |δ_T| = h gives (h on one
    temperature, 0 on the others: the product over the other temperatures' folded normals
    at 0 is part of it). It holds H with probability ≥ p for any true differences, exactly
    p where every true difference is 0 (independent differences). Where even h = 0 makes
    the reading improbably small (G(M; 0) < 1 − p: the exact test's empty set, a sign that
    the differences, which share the session's drift, are not independent), the limit is
    the one that holds whatever their correlation: each temperature's folded normal alone,
    P(M ≤ m) ≤ P(|D_j| ≤ m), inverted and the largest taken (the rule before 1 Dec 2026
    for every reading). Never below the reading M. The level z of the study is G's.
    The rule before left the other temperatures' factors out for every reading (a bound
    ≤ 1 on each), which made the interval over-wide at H = 0 (study z sd 0.55).

    >>> from scipy.stats import norm
    >>> h = hysteresis_upper_iec(1.0, [1.0])
    >>> round(h, 4), round(float(norm.cdf(1.0 - h) - norm.cdf(-1.0 - h)), 9)   # F(M; h, σ) = 5 %
    (2.6436, 0.05)
    >>> h = hysteresis_upper_iec(2.0, [1.0, 1.0])           # two temperatures: × F(M; 0, σ)
    >>> f0 = norm.cdf(2.0) - norm.cdf(-2.0)
    >>> round(float((norm.cdf(2.0 - h) - norm.cdf(-2.0 - h)) * f0), 9)
    0.05
    >>> hysteresis_upper_iec(0.0, [0.0, 0.0])        # noise-free: the reading itself
    0.0
    >>> G0 = float(hysteresis_level_iec(0.45, [1.0, 1.0, 1.0], 0.0)[0])  # < 5 %: no h left
    >>> h = hysteresis_upper_iec(0.45, [1.0, 1.0, 1.0])                   # one alone
    >>> round(G0, 4), round(float(norm.cdf(0.45 - h) - norm.cdf(-0.45 - h)), 9)
    (0.0419, 0.05)
    """
    from scipy import optimize

    m, s = float(reading), as_array(sds, "sds")
    if not (m >= 0.0 and 0.0 < p < 1.0 and np.all(s >= 0.0)):
        raise GonioError(f"5.3.3.7: reading {reading!r}, p {p!r}: needs reading ≥ 0, 0 < p < 1 "
                         "and standard deviations ≥ 0")
    q, hi = 1.0 - p, m
    if not np.any(s > 0.0):
        return float(hi)

    def f(h):
        return float(hysteresis_level_iec(m, s, h)[0]) - q
    top, tol = m + 12.0 * float(s.max()), 1e-14 * (m + float(s.max()))
    if f(0.0) > 0.0:
        return float(max(hi, optimize.brentq(f, 0.0, top, xtol=tol)))
    # the product leaves no h (the differences read smaller together than independent
    # differences of these σ make likely at 1 − p: the visits share the session's drift, so
    # they need not be independent): the limit that holds whatever the other differences
    # and their correlation, P(M ≤ m) ≤ P(|D_j| ≤ m), inverted on each j alone
    for sj in s[s > 0.0]:
        def g(h, sj=float(sj)):
            return float(hysteresis_level_iec(m, [sj], h)[0]) - q
        if g(0.0) > 0.0:
            hi = max(hi, optimize.brentq(g, 0.0, top, xtol=tol))
    return float(hi)


def hysteresis_level_grid(reading: float, sds, upper: float, n: int = 81) -> dict:
    """IEC 62047-20 5.3.3.7, the statement's level as a table for a coverage study (which
    knows the truth, the item does not): ``{"value": h_i, "z": Φ⁻¹(G(M; h_i))}`` on n
    points from 0 to twice the upper limit ``upper`` (:func:`hysteresis_level_iec`; z held
    within ±8). A study reads z at the truth by linear interpolation
    (:func:`gonio.analysis.coverage.level_z_at`).

    >>> g = hysteresis_level_grid(1.0, [1.0], hysteresis_upper_iec(1.0, [1.0]))
    >>> round(float(np.interp(hysteresis_upper_iec(1.0, [1.0]), g["value"], g["z"])), 2)
    -1.64
    """
    from scipy.stats import norm

    hs = np.linspace(0.0, 2.0 * max(float(upper), float(reading), 1e-300), int(n))
    z = np.clip(norm.ppf(hysteresis_level_iec(reading, sds, hs)), -8.0, 8.0)
    return {"value": [float(v) for v in hs], "z": [float(v) for v in z]}


def walk_coefficient_bound(tau_s, adev, edf, p: float = 0.95) -> float:
    """IEC 62047-20 5.3.3.5, the cap of the bootstrap's fitted walk: the largest rate random
    walk K² (adev's unit squared per s) the static record (5.4) allows: the walk's Allan
    variance K²τ/3 cannot exceed the whole σ(τ)² (IEEE 952 C.1), so K² ≤ min over τ of
    σ_hi(τ)²·3/τ, σ_hi(τ)² = σ̂(τ)²·ν/χ²_(1−p)(ν) the one-sided ``p`` upper limit at each τ
    (ν the edf there). The minimum picks the luckiest of several τ, so it holds K² less
    often than p: on 2-h records of white noise and a walk (the bench's K), in 83–86 % of
    80 records at p = 0.95, where the 68 % limits used before held it in 56–65 %
    (tests/test_iec_hysteresis_interval.py). Not a stated 95 % bound; the drift terms'
    E[K²] is :func:`walk_k2_iec` (a posterior mean, no level). τ with a non-finite value or
    edf are left out; none left: NaN.

    >>> from scipy.stats import chi2
    >>> b = walk_coefficient_bound([100.0, 1000.0], [1.0, 1.0], [10.0, 4.0])
    >>> round(b, 6), round(float(3e-3 * 4 / chi2.ppf(0.05, 4)), 6)    # the long τ sets it
    (0.016884, 0.016884)
    """
    from scipy.stats import chi2

    t, s, nu = as_array(tau_s, "tau_s"), as_array(adev, "adev"), as_array(edf, "edf")
    if not (t.shape == s.shape == nu.shape and 0.0 < p < 1.0):
        raise GonioError(f"walk_coefficient_bound: {t.size} τ, {s.size} deviations, {nu.size} "
                         f"edf at p = {p!r}")
    ok = np.isfinite(t) & np.isfinite(s) & np.isfinite(nu) & (t > 0) & (nu > 0)
    if not ok.any():
        return math.nan
    v = s[ok] ** 2 * nu[ok] / chi2.ppf(1.0 - p, nu[ok]) * 3.0 / t[ok]
    return float(np.min(v))


def walk_k2_iec(avar, edf, other_avar, k_column, *, k2_fit: float = 0.0, cov=None,
                p_cap: float = 0.9999) -> float:
    """IEC 62047-20 5.1.3 and 5.3.3, reading taken (the standard states no drift term): E[K²]
    of the rate random walk for the bias drift of every item's budget (scale-factor slope
    and linearity, 5.3.3.3, 5.3.3.6–5.3.3.9; one rule on one certificate) — the POSTERIOR
    MEAN of K² given the static record's (5.4) Allan variances, K uniform on [0, √cap].

    Likelihood (IEEE 952 C.1, NIST SP 1065 §5.3): at each τ_i the estimate ``avar``_i is
    σ_i²(K²)·χ²(ν_i)/ν_i with σ_i²(K²) = ``other_avar``_i + ``k_column``_i·K² — the other
    terms of the five-term fit (quantisation, white noise, bias instability, ramp) held at
    their fitted values, ``k_column`` the walk's response (τ/3 for AVAR) and ν_i = ``edf``
    (the caller gives the edf of the walk's own noise type, α = −2, the smallest at long τ).
    The τ's share most of their data, so the product of the per-τ likelihoods overstates
    the information: it is raised to the power s = min(1, H/J) (magnitude-adjusted
    composite likelihood, Chandler & Bate 2007, Biometrika 94(1)), H = Σ ν_i c_i²/(2σ_i⁴)
    its Fisher information for K² and J = gᵀ Σ g the variance of its score, g_i = ν_i
    c_i/(2σ_i⁴), Σ = ``cov`` the covariance of the Allan variance estimates across τ under
    the fitted model (σ_i² at ``k2_fit``); ``cov`` None: independent τ, s = 1. The prior is
    flat in K up to ``cap``, the smallest per-τ one-sided ``p_cap`` χ² limit of avar_i/c_i
    (a K no τ of the record allows); the mean is the integral over a grid of K.

    What it is for: about the walk's K² on average where the record resolves it, and large
    where the record cannot exclude a large K (the likelihood is flat there: the mean takes
    its width, never a fitted K̂ = 0). Entries with a non-finite or non-positive value, edf
    or response are left out; none left: NaN.

    One τ, no other term, independent (s = 1): the posterior of X = K² is inverse gamma,
    shape (ν − 1)/2, scale ν·avar/2 (c = 1), truncated at the cap; ν = 12, avar = 2:

    >>> from scipy.stats import invgamma
    >>> cap = 2 * 12 / __import__("scipy").stats.chi2.ppf(1e-4, 12)
    >>> a, b = 5.5, 12.0
    >>> exact = b / (a - 1) * invgamma.cdf(cap, a - 1, scale=b) / invgamma.cdf(cap, a, scale=b)
    >>> got = walk_k2_iec([2.0], [12.0], [0.0], [1.0])
    >>> round(got, 3), round(float(exact), 3)
    (2.661, 2.661)
    """
    from scipy.stats import chi2

    y, nu = as_array(avar, "avar"), as_array(edf, "edf")
    a, c = as_array(other_avar, "other_avar"), as_array(k_column, "k_column")
    if not (y.shape == nu.shape == a.shape == c.shape and 0.0 < p_cap < 1.0):
        raise GonioError(f"walk_k2_iec: {y.size} variances, {nu.size} edf, {a.size} other "
                         f"terms, {c.size} responses at p_cap = {p_cap!r}")
    ok = np.isfinite(y) & np.isfinite(nu) & np.isfinite(a) & np.isfinite(c) \
        & (y > 0) & (nu > 0) & (c > 0) & (a >= 0)
    if not ok.any():
        return math.nan
    k2f = float(k2_fit) if math.isfinite(k2_fit) and k2_fit > 0 else 0.0
    v_fit = np.maximum(a + c * k2f, np.finfo(float).tiny)
    s = 1.0
    if cov is not None:
        sig = np.asarray(cov, dtype=np.float64)
        if sig.shape != (y.size, y.size):
            raise GonioError(f"walk_k2_iec: covariance {sig.shape} for {y.size} variances")
        g = np.where(ok, nu * c / (2.0 * v_fit ** 2), 0.0)
        h = float(np.sum(g * c))
        j = float(g @ np.where(np.isfinite(sig), sig, 0.0) @ g)
        if h > 0 and j > 0:
            s = min(1.0, h / j)
    y, nu, a, c = y[ok], nu[ok], a[ok], c[ok]
    cap = float(np.min(y * nu / chi2.ppf(1.0 - p_cap, nu) / c))
    k = np.concatenate([[0.0], np.geomspace(math.sqrt(cap) * 1e-6, math.sqrt(cap), 4000)])
    v = np.maximum(a[None, :] + c[None, :] * (k * k)[:, None], np.finfo(float).tiny)
    with np.errstate(over="ignore"):        # K = 0 with no other term: likelihood 0
        ll = -0.5 * s * np.sum(nu[None, :] * (y[None, :] / v + np.log(v)), axis=1)
    w = np.exp(ll - np.max(ll))
    return float(np.trapezoid(w * k * k, k) / np.trapezoid(w, k))


def _max_spread_grid(spreads, dofs, n_grid: int = 4001):
    """The grid x and the CDF G(x) = Π_i F_χ²(ν_i x²/σ_i²; ν_i) of max_i δ_i for independent
    δ_i = σ_i·√(χ²_ν_i/ν_i) (the population standard deviation of a constant-rate record
    whose E[δ_i²] is σ_i²)."""
    from scipy import stats

    s, nu = as_array(spreads, "spreads"), as_array(dofs, "dofs")
    if s.shape != nu.shape or s.size == 0 or np.any(~(s >= 0)) or np.any(~(nu >= 1)):
        raise GonioError(f"max spread: {s.size} spreads ≥ 0 and {nu.size} dofs ≥ 1 expected")
    top = float(s.max())
    w = 12.0 / math.sqrt(2.0 * float(nu[int(np.argmax(s))]))   # G ≈ 0 below the top's tail
    hi = top * (1.0 + 12.0 / math.sqrt(2.0 * float(nu.min()))) if top > 0 else 1.0
    x = np.linspace(max(top * (1.0 - w), 0.0), hi, n_grid)
    G = np.ones_like(x)
    for si, ni in zip(s, nu):
        G *= stats.chi2.cdf(ni * (x / si) ** 2, ni) if si > 0 else 1.0
    return x, G


def max_spread_moments(spreads, dofs) -> tuple[float, float]:
    """(E, sd) of max_i δ_i, the δ_i independent σ_i·√(χ²_ν_i/ν_i) (``spreads`` σ_i,
    ``dofs`` ν_i): E = ∫₀^∞ (1 − G) dx, E[max²] = ∫₀^∞ 2x(1 − G) dx with G the product of
    the χ CDFs (the expectation of a non-negative variable from its CDF, JCGM 101 as a
    closed form: no draws; G is 0 to double precision below 12 standard deviations under
    the largest σ_i, where the grid starts). IEC 62047-20 5.1.3.7's reading max δ_i has
    this distribution.

    >>> e, sd = max_spread_moments([1.0], [1e6])        # one spread of many samples: σ
    >>> round(e, 4), round(sd * math.sqrt(2e6), 3)
    (1.0, 1.0)
    """
    x, G = _max_spread_grid(spreads, dofs)
    tail = 1.0 - G
    e = float(x[0]) + float(np.trapezoid(tail, x))
    e2 = float(x[0]) ** 2 + float(np.trapezoid(2.0 * x * tail, x))
    return e, math.sqrt(max(e2 - e * e, 0.0))


def max_spread_estimate(spreads, dofs, p: float = 0.95, noise: bool = True) -> dict:
    """IEC 62047-20 5.1.3.7, the physically right estimate beside the reading: the largest
    true spread max_i σ_i from the measured population spreads δ_i (``spreads``, each of a
    record of ν_i + 1 samples, ``dofs`` ν_i), with the bias of the maximum removed.

    The reading max δ_i reads high: the largest of several noisy spreads is more often one
    that noise raised (E[max δ_i] ≥ max σ_i; +2.3 % on the built-in programme's two rates),
    and each δ_i reads low by Jensen's E[δ] < σ. The bias B = E[max δ_i] − max σ_i, with
    δ_i = σ_i·√(χ²_ν_i/ν_i) (:func:`max_spread_moments`, the expectation of the maximum of
    scaled χ variables as a closed form, JCGM 101's propagation of the δ_i's distributions
    without draws), depends on which true spreads share the largest, which is not known: it
    lies between B_min = E[δ_top] − σ_top (one rate's spread stands clear: Jensen only) and
    B_max = E[max of the m contenders] − σ_top (the m spreads within 2√2 of their standard
    deviation σ_j/√(2ν_j) of the largest share it: the full selection excess), both at
    σ_top = max δ_i. As for every maximum of IEC 62047-20 (JCGM 100 4.3.7, the rule of
    :func:`gonio.specs._rate_family.formulas.selection_excess`), the estimate is the reading
    less the midpoint of [B_min, B_max] and the correction's own uncertainty is that range,
    rectangular: u_B = (B_max − B_min)/√12. (The plug-in bootstrap bias E_δ̂[max δ*] − max δ̂
    removes only about 40 % of the excess when the true spreads are equal — the measured
    gap makes the excess look smaller —, the midpoint half; where one spread stands clear
    the plug-in over-corrects and the midpoint does not.)

    Returns ``value`` = max δ_i − B_mid; ``u_c`` = √(sd(δ_top)² + u_B²) (sd of the largest
    spread's own scaled χ: where the true spreads differ, the maximum's distribution at the
    measured spreads, narrower where they look alike, would understate); the 95 %
    ``interval`` of max σ_i, the test inversion of the spreads' own distribution,
    :func:`max_spread_bounds` (each end at its least favourable true spreads: the lower at
    every spread equal to max σ_i, the upper at one spread alone; at least p for any true
    spreads and record lengths; the value held inside it). Until 1 Dec 2026 the lower end
    was the lower of that and the χ² interval of every δ_top − S united over the selection
    excess S in [0, S_max]: 0.955–0.98 on Monte Carlo records, but over-wide in the study
    (its level z sd 0.56–0.61 on 40 trials), the union counting the excess twice;
    ``reading`` (max δ_i, the standard's), ``bias`` B_mid, ``bias_bounds``, ``contenders``
    and ``sd_max``. ``noise`` False (a bench without noise: the spreads are exact): no
    correction.

    >>> r = max_spread_estimate([1.0, 1.0], [299, 299])
    >>> r["contenders"], round(r["bias_bounds"][1] / (1 / math.sqrt(2 * 299 * math.pi)), 1)
    (2, 1.0)
    >>> r["interval"][0] < r["value"] < r["reading"] < r["interval"][1]
    True
    >>> max_spread_estimate([1.0, 0.5], [299, 299])["contenders"]
    1
    """
    s, nu = as_array(spreads, "spreads"), as_array(dofs, "dofs")
    if s.shape != nu.shape or s.size == 0:
        raise GonioError(f"max spread: {s.size} spreads and {nu.size} dofs")
    i = int(np.argmax(s))
    top = float(s[i])
    m = int(np.sum(s >= top - 2.0 * math.sqrt(2.0) * s / np.sqrt(2.0 * nu)))
    if noise and top > 0:
        b_lo = max_spread_moments([top], [nu[i]])[0] - top
        b_hi = max_spread_moments(np.full(m, top), np.full(m, nu[i]))[0] - top
    else:
        b_lo = b_hi = 0.0
    b_mid = 0.5 * (b_lo + b_hi)
    half = 0.5 * (b_hi - b_lo)
    value = top - b_mid
    u_b = half / math.sqrt(3.0)
    # the interval: δ_top − S = σ_top·√(χ²_ν/ν) for a selection excess S (beyond Jensen's)
    # in [0, S_max], S_max = B_max − B_min; the χ² interval of σ_top (exact for a scaled χ)
    # of every δ_top − S, united: [(δ_top − S_max)·√(ν/χ²_(1+p)/2), δ_top·√(ν/χ²_(1−p)/2)]
    from scipy import stats

    e, sd = max_spread_moments([top], [nu[i]])
    lo, hi = max_spread_bounds(s, nu, p)
    return {"value": min(max(value, lo), hi), "u_c": math.sqrt(sd * sd + u_b * u_b),
            "sd_max": sd, "u_bias": u_b, "interval": (max(lo, 0.0), hi), "reading": top,
            "bias": b_mid, "bias_bounds": (b_lo, b_hi), "contenders": m}


def max_spread_bounds(spreads, dofs, p: float = 0.95) -> tuple[float, float]:
    """IEC 62047-20 5.1.3.7, the bounds of the largest TRUE spread max σ_i that hold for
    any true spreads and any record lengths (the reading of the standard's silence on how a
    maximum of spreads of unequal records is bounded; the one function for it): each record
    alone gives the exact χ² interval of its σ_i (JCGM 101 7.7 for a scaled χ,
    δ_i = σ_i·√(χ²_ν_i/ν_i), at its OWN ν_i), and

    - upper end: max_i δ_i·√(ν_i/χ²_{ν_i,(1−p)/2}), the largest of the records' own upper
      bounds, each at one-sided level (1 − p)/2. It misses max σ_i only when the record j
      holding the largest true spread misses its own σ_j (max_i U_i < σ_j ⇒ U_j < σ_j), so
      P(miss) ≤ (1 − p)/2 with no multiplicity correction (a Bonferroni or Šidák split
      would only widen it). The top record's bound alone is not this: with unequal ν a
      short record's δ can fall below a long record's, and the long record's bound then
      stands for the short one's σ (true σ (1, 2), ν (299, 4): 0.876 coverage).
    - lower end: max_i δ_i·√(ν_i/χ²_{ν_i,1−a}), a = 1 − (1 − (1 − p)/2)^(1/n) (Šidák,
      the n records independent): all n lower bounds hold together with probability
      1 − (1 − p)/2, and then their maximum is below max σ_i.

    Coverage ≥ p for every σ and ν (proved above; checked by Monte Carlo in
    tests/test_iec_estimator_bias.py). :func:`max_spread_estimate` states this interval;
    :func:`max_spread_level_z` is its level at a given max σ_i.

    >>> lo, hi = max_spread_bounds([1.0, 1.9], [299, 4])
    >>> round(hi, 3) == round(1.9 * math.sqrt(4 / __import__("scipy").stats.chi2.ppf(0.025, 4)), 3)
    True
    >>> max_spread_bounds([1.0, 0.5], [299, 4])[1] > max_spread_bounds([1.0], [299])[1]
    True
    """
    from scipy import stats

    s, nu = as_array(spreads, "spreads"), as_array(dofs, "dofs")
    if s.shape != nu.shape or s.size == 0:
        raise GonioError(f"max spread bounds: {s.size} spreads and {nu.size} dofs")
    a = 1.0 - (1.0 - (1.0 - p) / 2) ** (1.0 / s.size)
    lo = float(np.max(s * np.sqrt(nu / stats.chi2.ppf(1.0 - a, nu))))
    hi = float(np.max(s * np.sqrt(nu / stats.chi2.ppf((1.0 - p) / 2, nu))))
    return lo, hi


def max_spread_level_z(spreads, dofs, sigma) -> np.ndarray:
    """IEC 62047-20 5.1.3.7, the level of :func:`max_spread_bounds`' interval at a true
    largest spread ``sigma`` (one value or an array): with Q = max_i F_ν_i(ν_i δ_i²/σ²)
    (F the χ² distribution function), σ lies above the level-p lower end iff
    Q^n < (1 + p)/2 and below the upper end iff Q ≥ (1 − p)/2, so the smallest interval of
    the family holding σ has p* = max(2Q^n − 1, 1 − 2Q, 0) and the signed level z is
    Φ⁻¹(Q^n) where Q^n > ½ (the reading high), Φ⁻¹(Q) where Q < ½ (low), 0 between (σ
    inside every level's interval). Where every true spread equals σ, Q^n is uniform: z
    above 0 is then N(0, 1) exactly; below 0 it is Φ⁻¹ of Q, whose tail the upper end's
    one-spread-alone case makes conservative. Held within ±8.

    >>> from scipy.stats import norm
    >>> lo, hi = max_spread_bounds([1.0, 0.9], [99, 99])
    >>> [round(float(v), 3) for v in max_spread_level_z([1.0, 0.9], [99, 99], [lo, hi])]
    [1.96, -1.96]
    >>> q = [0.6 ** 0.5, 0.45]                     # two equal spreads: Q between ½ and ½^(1/2)
    >>> sg = [(99 / __import__("scipy").stats.chi2.ppf(v, 99)) ** 0.5 for v in q]
    >>> [round(float(v), 6) for v in max_spread_level_z([1.0, 1.0], [99, 99], sg)]
    [0.253347, -0.125661]
    >>> round(float(norm.ppf(0.6)), 6), round(float(norm.ppf(0.45)), 6)
    (0.253347, -0.125661)
    """
    from scipy import stats

    s, nu = as_array(spreads, "spreads"), as_array(dofs, "dofs")
    sg = np.atleast_1d(np.asarray(sigma, dtype=float))
    if s.shape != nu.shape or s.size == 0 or not np.all(sg > 0.0):
        raise GonioError(f"max spread level: {s.size} spreads, {nu.size} dofs, σ > 0 needed")
    q = np.max(stats.chi2.cdf(nu[None, :] * s[None, :] ** 2 / sg[:, None] ** 2, nu[None, :]),
               axis=1)
    qn = q ** s.size
    z = np.where(qn > 0.5, stats.norm.ppf(qn), np.where(q < 0.5, stats.norm.ppf(q), 0.0))
    return np.clip(z, -8.0, 8.0)


def max_spread_level_grid(spreads, dofs, interval, n: int = 81) -> dict:
    """IEC 62047-20 5.1.3.7, :func:`max_spread_level_z` as a table for a coverage study:
    ``{"value": σ_i, "z": z_i}`` on n points from half the interval's lower end to twice
    its upper end (a study reads z at the truth by linear interpolation,
    :func:`gonio.analysis.coverage.level_z_at`).

    >>> g = max_spread_level_grid([1.0], [99], max_spread_bounds([1.0], [99]))
    >>> len(g["value"]), g["z"][0] > 1.96 > -1.96 > g["z"][-1]
    (81, True)
    """
    lo, hi = float(interval[0]), float(interval[1])
    vs = np.linspace(max(0.5 * lo, 1e-12 * hi), 2.0 * hi, int(n))
    z = max_spread_level_z(spreads, dofs, vs)
    return {"value": [float(v) for v in vs], "z": [float(v) for v in z]}
