"""Rate-gyro arithmetic shared by JJF 1535-2015 and IEC 62047-20:2014.

Every function is one formula (or one documented reading of an ambiguous
formula) of one of the two documents; the specification packages
(:mod:`gonio.specs.jjf1535`, :mod:`gonio.specs.iec62047_20`) choose which to call
and in what order. Nothing here reads files or knows the bench.

Conventions: Ω (``rate_dps``) in °/s; F (``output``) in the gyro's own output
unit (mV, LSB, counts/s); K in output per °/s; temperatures in °C. The clause
readings are documented in ``docs/jjf1535-readings.md`` and
``docs/iec62047-20-readings.md``.

Contents
========
==============================  ==================================================
:func:`least_squares_line`      y = a x + b, JJF (5) / IEC (1), (2), (5), (6)
:func:`r5_rates`                the R5 rate series of JJF 7.2.1.1 c)
:func:`fit_scale_factor`        JJF (4), (5): rest-removed means, K, F_0, residuals
:func:`nonlinearity_jjf`        JJF (6): max |residual| / fitted span
:func:`asymmetry_jjf`           JJF (8): |K+ − K−| / mean
:func:`relative_std`            JJF (10): s(K_m)/K̄
:func:`temperature_sensitivity` JJF (11) and (27): largest slope to room temperature
:func:`fifty_percent_candidate` JJF (13), (14), IEC 5.6.3: the 50 % rule
:func:`block_mean_stability`    JJF (18): std of P-sample block means / K
:func:`sample_std`              JJF (20): Bessel standard deviation
:func:`g_sensitivity_axis`      JJF 7.2.12.2, Earth rate removed per position
:func:`earth_rate_projection_dps`  Ω_E on a gyro axis, any orientation
:func:`allan_variance_printed_jjf`  JJF (22)–(24) as printed (not an Allan variance)
:func:`allan_variance_overlapping`  the reading taken: IEEE 952 overlapping AVAR
:func:`arw_from_coefficient`    JJF (26), unit handling of 7.2.13
:func:`bandwidth_grid`          JJF 7.2.15.1 b) frequency grid
:func:`sine_fit`                amplitude and phase at a known frequency (IEC 5.5 reading)
:func:`minus3db_frequency`      −3 dB crossing (JJF 7.2.15.2, IEC 5.5.3)
:func:`phase90_frequency`       90° lag crossing (IEC 5.5.3)
:func:`second_order_response`   |H|, ∠H of a second-order sensor (bench truth, checks)
:func:`warmup_time_s`           JJF 7.2.9 reading: sliding-window stability
:func:`linearity_errors_iec`    IEC (8), (9)
:func:`symmetry_iec`            IEC (13)–(17)
:func:`ratiometric_error_iec`   IEC (7), (26)
:func:`cross_axis_iec`          IEC (20)–(23), read as a division by SF
:func:`arw_minus_half_line`     IEC 5.4.5.2 e): slope −½ line read at 1 h
:func:`bias_instability_floor`  IEC 5.4.5.3 c): floor / 0.664
==============================  ==================================================

Unit note: seconds per hour come from :mod:`gonio.units` (``S_PER_H``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gonio.physics.earth import OMEGA_E_RAD_S, earth_rate_enu
from gonio.errors import GonioError
from gonio.protocol.rate import r5_rates  # noqa: F401  (JJF 7.2.1.1 c) series, re-exported)
from gonio.units import S_PER_H

#: Earth rate, °/s (IERS value; 4.178074×10⁻³ °/s).
OMEGA_E_DPS = math.degrees(OMEGA_E_RAD_S)
#: −3 dB as an amplitude ratio, 10^(−3/20) (JJF 7.2.15.2 reading; IEC 5.5.3).
MINUS_3DB_RATIO = 10.0 ** (-3.0 / 20.0)
#: √(2 ln 2 / π): Allan-deviation floor per unit bias instability (IEC 5.4.5.3 c)).
FLICKER_FLOOR_EXACT = math.sqrt(2.0 * math.log(2.0) / math.pi)
#: Standard gravity, m/s² (the "g" of JJF 7.2.12 and IEC 5.3.3.8).
G_STANDARD = 9.80665


def _arr(x, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=np.float64).ravel()
    if not np.all(np.isfinite(a)):
        raise GonioError(f"{name} holds a non-finite value", key=name)
    return a


# --------------------------------------------------------------------------- lines
def least_squares_line(x, y) -> tuple[float, float]:
    """Slope and intercept of the least-squares line y = a·x + b.

    JJF 1535 7.2.1.2 eq (5) (K and F_0); IEC 62047-20 5.1.3.1 eqs (1), (2),
    5.1.3.4 eqs (5), (6), 5.1.3.8 eqs (13)–(16): a = [NΣxy − ΣxΣy]/[NΣx² − (Σx)²],
    b = [Σx²Σy − ΣxΣxy]/[NΣx² − (Σx)²]. Computed about the means (same algebra,
    better conditioned).

    >>> least_squares_line([1, 2, 3], [2, 4, 6.5])
    (2.25, -0.33333333333333304)
    """
    x, y = _arr(x, "x"), _arr(y, "y")
    if x.size != y.size or x.size < 2:
        raise GonioError(f"a line needs ≥ 2 points of equal count, got {x.size} and {y.size}")
    xm, ym = x.mean(), y.mean()
    sxx = float(((x - xm) ** 2).sum())
    if sxx == 0:
        raise GonioError("a line needs at least two different input values")
    a = float(((x - xm) * (y - ym)).sum() / sxx)
    return a, float(ym - a * xm)


# --------------------------------------------------------------------------- scale factor
@dataclass(frozen=True)
class ScaleFactorFit:
    """One calibration's least-squares scale factor (JJF 1535 7.2.1.2).

    ``rates_dps`` Ω_j, ``means`` F̄_j (rest removed, eq (4)), ``K`` and ``F0`` of eq (5),
    ``fitted`` F̂_j, ``residuals`` v_j, ``rest`` the subtracted F_r.
    """

    rates_dps: np.ndarray
    means: np.ndarray
    K: float
    F0: float
    fitted: np.ndarray
    residuals: np.ndarray
    rest: float


def rest_level(rest_before: float, rest_after: float) -> float:
    """F_r of JJF 1535 7.2.1.1 d), reading taken: the mean of the rest before and after.

    >>> rest_level(2.0, 4.0)
    3.0
    """
    return 0.5 * (float(rest_before) + float(rest_after))


def fit_scale_factor(rates_dps, raw_means, rest: float = 0.0) -> ScaleFactorFit:
    """JJF 1535 7.2.1.2 eqs (4), (5): F̄_j = mean − F_r, then K, F_0 by least squares over
    the rate points of both directions (rests are not fit points).

    >>> f = fit_scale_factor([-2, -1, 1, 2], [-19.0, -9.0, 11.0, 21.0], rest=1.0)
    >>> f.K, f.F0
    (10.0, 0.0)
    """
    rates = _arr(rates_dps, "rate_dps")
    means = _arr(raw_means, "output") - float(rest)
    if np.any(rates == 0):
        raise GonioError("JJF 1535 7.2.1.2: a rest point (0 °/s) is not a fit point")
    K, F0 = least_squares_line(rates, means)
    fitted = K * rates + F0
    return ScaleFactorFit(rates, means, K, F0, fitted, means - fitted, float(rest))


def nonlinearity_jjf(fit: ScaleFactorFit) -> float:
    """JJF 1535 7.2.2 eq (6): K_n = max_j |F̄_j − F̂_j| / [K (Ω_max+ − Ω_max−)].

    Reading taken: Ω_max− signed (negative), so the denominator is the fitted output span
    over the full range; a one-sided rate range is refused.
    """
    hi, lo = float(fit.rates_dps.max()), float(fit.rates_dps.min())
    if not (hi > 0 > lo):
        raise GonioError("JJF 1535 7.2.2 needs forward and reverse rates")
    return float(np.max(np.abs(fit.residuals)) / abs(fit.K * (hi - lo)))


@dataclass(frozen=True)
class Asymmetry:
    """JJF 1535 7.2.3: K+, K− (own intercepts), signed and absolute K_a."""

    K_pos: float
    F0_pos: float
    K_neg: float
    F0_neg: float
    signed: float
    value: float


def asymmetry_jjf(rates_dps, means, *, mean_of: str = "directions",
                  K_all: float | None = None) -> Asymmetry:
    """JJF 1535 7.2.3 eq (8): K_a = |K+ − K−| / K̄ from separate fits of each direction.

    Reading taken: K̄ = (K+ + K−)/2 (``mean_of="directions"``); the alternative
    ``mean_of="all"`` divides by the two-direction K of 7.2.1 (``K_all``).
    """
    r, y = _arr(rates_dps, "rate_dps"), _arr(means, "output")
    pos, neg = r > 0, r < 0
    if pos.sum() < 2 or neg.sum() < 2:
        raise GonioError("JJF 1535 7.2.3 needs ≥ 2 rates in each direction")
    kp, bp = least_squares_line(r[pos], y[pos])
    kn, bn = least_squares_line(r[neg], y[neg])
    if mean_of == "directions":
        kbar = 0.5 * (kp + kn)
    elif mean_of == "all":
        if K_all is None:
            raise GonioError("mean_of='all' needs K_all")
        kbar = float(K_all)
    else:
        raise GonioError(f"mean_of must be 'directions' or 'all', got {mean_of!r}")
    s = (kp - kn) / kbar
    return Asymmetry(kp, bp, kn, bn, float(s), float(abs(s)))


def relative_std(values) -> tuple[float, float, float]:
    """JJF 1535 7.2.4 eq (10): (mean, s, s/|mean|) with the Bessel s.

    >>> m, s, r = relative_std([10.0000, 10.0012, 9.9991])
    >>> round(m, 4), round(s, 7), round(r, 8)
    (10.0001, 0.0010536, 0.00010536)
    """
    v = _arr(values, "values")
    if v.size < 2:
        raise GonioError(f"a repeatability needs ≥ 2 values, got {v.size}")
    m = float(v.mean())
    s = float(v.std(ddof=1))
    return m, s, s / abs(m)


def sample_std(values) -> float:
    """JJF 1535 7.2.11 eq (20): B_r = Bessel standard deviation of the Q biases.

    >>> round(sample_std([1.0, 2.0, 3.0]), 12)
    1.0
    """
    v = _arr(values, "values")
    if v.size < 2:
        raise GonioError(f"a repeatability needs ≥ 2 values, got {v.size}")
    return float(v.std(ddof=1))


def temperature_sensitivity(values, temps_c, rt_index: int, *, relative: bool) -> tuple[float, list[float]]:
    """JJF 1535 7.2.5 eq (11) (``relative=True``) and 7.2.14 eq (27) (``relative=False``):
    the largest |(X_i − X_rt)/((T_i − T_rt)·(X_rt if relative))| over i ≠ rt.

    Returns the maximum and the per-point slopes (signed, in the order given, NaN at rt).

    >>> round(temperature_sensitivity([10.0, 10.03, 9.97], [20, 70, -40], 0, relative=True)[0], 10)
    6e-05
    >>> temperature_sensitivity([36.0, 61.0, -12.0], [20, 70, -40], 0, relative=False)[0]
    0.8
    """
    x, t = _arr(values, "values"), _arr(temps_c, "temperature_c")
    if x.size != t.size or x.size < 2:
        raise GonioError("temperature sensitivity needs ≥ 2 points (room temperature and one more)")
    xr, tr = x[rt_index], t[rt_index]
    slopes = []
    for i in range(x.size):
        if i == rt_index:
            slopes.append(math.nan)
            continue
        if t[i] == tr:
            raise GonioError(f"temperature point {i} equals the room temperature {tr} °C")
        d = (x[i] - xr) / (t[i] - tr)
        slopes.append(float(d / xr) if relative else float(d))
    return float(np.nanmax(np.abs(slopes))), slopes


# --------------------------------------------------------------------------- 50 % rule
def fifty_percent_candidate(step_dps, measured, expected, *, limit: float = 0.5) -> tuple[float | None, list[float]]:
    """JJF 1535 eqs (13)/(14) (two-sided reading) and IEC 62047-20 5.6.3: walk the steps
    in the order given (decreasing magnitude); the candidate is the last step meeting
    |measured − expected|/|expected| ≤ ``limit`` before the first failure.

    Returns (candidate magnitude or None if the first step already fails, deviations).

    >>> c, d = fifty_percent_candidate([0.05, 0.02, 0.01, 0.005], [0.49, 0.21, 0.06, 0.01],
    ...                                [0.5, 0.2, 0.1, 0.05])
    >>> c, [round(v, 2) for v in d]
    (0.01, [0.02, 0.05, 0.4, 0.8])
    """
    s, m, e = _arr(step_dps, "step"), _arr(measured, "measured"), _arr(expected, "expected")
    if not (s.size == m.size == e.size) or s.size == 0:
        raise GonioError("50 % rule: steps, measured and expected must have equal, non-zero length")
    dev = np.abs(m - e) / np.abs(e)
    cand = None
    for i in range(s.size):
        if dev[i] <= limit:
            cand = float(abs(s[i]))
        else:
            break
    return cand, [float(v) for v in dev]


# --------------------------------------------------------------------------- bias
def block_mean_stability(samples, K: float, block: int) -> float:
    """JJF 1535 7.2.10 eq (18): B_s = (1/K)·s(block means of P samples), Bessel s over the
    N/P non-overlapping blocks (an incomplete last block dropped; reading taken).

    Digest check 9 (K = 10 mV/(°/s), P = 2): 1.2247×10⁻³ °/s.

    >>> round(block_mean_stability([.10, .12, .08, .11, .09, .13, .07, .10], 10.0, 2), 8)
    0.00122474
    """
    x = _arr(samples, "output")
    P = int(block)
    n = x.size // P
    if P < 1 or n < 2:
        raise GonioError(f"bias stability needs ≥ 2 blocks of {P} samples, got {x.size} samples")
    means = x[: n * P].reshape(n, P).mean(axis=1)
    return float(means.std(ddof=1) / abs(K))


def earth_rate_projection_dps(latitude_deg: float, axis_enu) -> float:
    """Earth-rate component on a gyro axis (unit vector in ENU), °/s.

    Physics behind JJF 1535 7.2.8/7.2.12 (not removed there; reading taken: remove it) and
    IEC 62047-20 5.3.3.1 (whose printed sin/cos are swapped, erratum): up Ω_E sin λ,
    down −Ω_E sin λ, horizontal at azimuth φ from north Ω_E cos λ cos φ.

    >>> round(earth_rate_projection_dps(40.0, [0, 0, 1]) * S_PER_H, 3)
    9.668
    >>> round(earth_rate_projection_dps(35.0, [0, 0, 1]), 7)
    0.0023964
    """
    a = np.asarray(axis_enu, dtype=float)
    n = float(np.linalg.norm(a))
    if a.shape != (3,) or not n > 0:
        raise GonioError("an axis must be a non-zero 3-vector in ENU")
    return float(math.degrees(earth_rate_enu(latitude_deg) @ (a / n)))


def g_sensitivity_axis(rate_plus_dps: float, rate_minus_dps: float,
                       earth_plus_dps: float = 0.0, earth_minus_dps: float = 0.0) -> float:
    """JJF 1535 7.2.12.2: B_g,axis = [ω̄(+axis up) − ω̄(−axis up)]/(2 g), per g.

    Reading taken: the Earth-rate projection on the input axis is subtracted in each
    position first (digest check 10: 49.668/20.332 °/h → 5.000, literal 14.668).

    >>> round(g_sensitivity_axis(49.668, 20.332), 3), round(g_sensitivity_axis(49.668, 20.332, 9.668, -9.668), 3)
    (14.668, 5.0)
    """
    return ((rate_plus_dps - earth_plus_dps) - (rate_minus_dps - earth_minus_dps)) / 2.0


def last_exceedance_time(time_s, stat, level: float) -> float:
    """The time (from the first sample) of the point after the last one whose ``stat``
    exceeds ``level``: 0 when none does, NaN when the last point still does. The detection
    rule of JJF 1535 7.2.9 (stat: window stability) and IEC 62047-20 5.3.3.9 (stat:
    |smoothed output − settled bias|).

    >>> last_exceedance_time([0, 10, 20, 30], [5, 3, 1, 0.5], 2.0)
    20.0
    """
    t, x = _arr(time_s, "time_s"), _arr(stat, "stat")
    over = np.flatnonzero(x > level)
    if over.size == 0:
        return 0.0
    return math.nan if over[-1] + 1 >= t.size else float(t[over[-1] + 1] - t[0])


def detection_interval(time_s, stat, level: float, sd: float, z: float) -> tuple[float, float]:
    """Where the noise-free crossing of ``level`` can lie, from the data: the last exceedance
    of level + z·sd (earlier: an excursion that large is not noise alone, with the
    confidence z gives) and of level − z·sd (later). ``sd`` is the standard deviation of the
    statistic's noise; z the two-sided 95 % point for the number of independent looks.
    The detection term of the warm-up (JJF 7.2.9) and start-up (IEC 5.3.3.9) budgets.

    >>> detection_interval([0, 10, 20, 30, 40], [5, 3, 2.2, 1.6, 0.5], 2.0, 0.25, 2.0)
    (20.0, 40.0)
    """
    return (last_exceedance_time(time_s, stat, level + z * sd),
            last_exceedance_time(time_s, stat, level - z * sd))


def window_stabilities(time_s, rate, *, window: int, block: int) -> tuple[np.ndarray, np.ndarray]:
    """JJF 1535 7.2.9 reading: the block-mean stability (eq (18), P = ``block``) of every
    window of ``window`` samples starting at a block boundary: (start times, stabilities)."""
    t, x = _arr(time_s, "time_s"), _arr(rate, "rate")
    if x.size < window or window < 2 * block:
        raise GonioError(f"warm-up needs a record ≥ window ({window}) ≥ 2 blocks ({block})")
    starts = np.arange(0, x.size - window + 1, block)
    return t[starts], np.array([block_mean_stability(x[s:s + window], 1.0, block)
                                for s in starts])


def warmup_time_s(time_s, rate, *, window: int, block: int, nominal: float) -> float:
    """JJF 1535 7.2.9, reading taken: the earliest start t such that the block-mean stability
    (eq (18), P = ``block``) of every later window of ``window`` samples is ≤ ``nominal``.

    ``rate`` is the output already divided by K (so ``nominal`` is a rate). Windows start
    at every block boundary; returns the time of the first sample of the first window of
    the compliant tail (NaN when even the last window fails).

    >>> t = np.arange(100.0)
    >>> r = np.where(t < 30, 1.0 * (t % 2), 0.0)
    >>> warmup_time_s(t, r, window=20, block=2, nominal=1e-9)
    30.0
    """
    ts, st = window_stabilities(time_s, rate, window=window, block=block)
    return last_exceedance_time(ts, st, nominal)


# --------------------------------------------------------------------------- Allan
def allan_variance_printed_jjf(rate, k: int) -> float:
    """JJF 1535 7.2.13 eqs (22)–(24) **as printed** (the standard's reading, labelled):
    overlapping k-sample means Ω̄_p, differences of means *one sample apart*, then
    σ² = Σ (Ω̄_{p+2} − 2Ω̄_{p+1} + Ω̄_p)² / (2(n − k − 1)).

    This is not an Allan variance: for white noise of unit variance it gives 3 at k = 1
    and 2/k² for k ≥ 2 (digest check 14), so the ARW cannot be read from it.
    """
    x = _arr(rate, "rate")
    k = int(k)
    if k < 1 or x.size < k + 3:
        raise GonioError(f"printed eq (24) needs n ≥ k + 3, got n = {x.size}, k = {k}")
    c = _cumsum0(x)
    # overlapping means Ω̄_p = (c[p+k] − c[p])/k, p = 0 … n − k; terms p = 0 … n − k − 2
    total = 0.0
    for a, b in _pieces(x.size - k - 1):
        m = (c[a + k: b + k + 2] - c[a: b + 2]) / k
        d2 = m[2:] - 2 * m[1:-1] + m[:-2]
        total += float((d2 ** 2).sum())
    return total / (2.0 * (x.size - k - 1))


#: Terms formed at a time by the direct Allan forms (bounded temporaries on long records).
_PIECE = 1 << 16


def _pieces(n: int):
    """(start, end) of consecutive pieces of range(n)."""
    return ((a, min(n, a + _PIECE)) for a in range(0, n, _PIECE))


def _cumsum0(x: np.ndarray) -> np.ndarray:
    """[0, cumsum(x)] in one array (no concatenated copy)."""
    c = np.empty(x.size + 1)
    c[0] = 0.0
    np.cumsum(x, out=c[1:])
    return c


def allan_variance_overlapping(rate, k: int) -> float:
    """Reading taken for JJF 1535 7.2.13: the overlapping Allan variance (IEEE 952/1431),
    σ²(kτ0) = Σ_{p=1}^{n−2k+1} (Ω̄_{p+k} − Ω̄_p)² / (2(n − 2k + 1)).

    (The package's general estimator is :func:`gonio.analysis.noise.allan_deviation`; this direct
    form documents the formula and is checked against it.)

    >>> allan_variance_overlapping([1.0, -1.0] * 8, 1)
    2.0
    """
    x = _arr(rate, "rate")
    k = int(k)
    if k < 1 or x.size < 2 * k + 1:
        raise GonioError(f"overlapping AVAR needs n ≥ 2k + 1, got n = {x.size}, k = {k}")
    c = _cumsum0(x)
    # d_p = Ω̄_{p+k} − Ω̄_p, p = 0 … n − 2k, summed in pieces
    total, n_d = 0.0, x.size - 2 * k + 1
    for a, b in _pieces(n_d):
        d = (c[a + 2 * k: b + 2 * k] - c[a + k: b + k]) / k - (c[a + k: b + k] - c[a: b]) / k
        total += float((d ** 2).sum())
    return total / (2.0 * n_d)


def arw_from_coefficient(a_minus1: float, *, rate_unit: str, tau_unit: str) -> float:
    """JJF 1535 7.2.13 eq (26): ARW = √A_−1, returned in °/√h.

    With σ in °/h and τ in h √A_−1 is °/√h; with τ in s it is (°/h)·√s, divide by 60
    (digest check 13: 0.0064 (h) → 0.08; 23.04 (s) → 4.8/60 = 0.08).

    >>> arw_from_coefficient(0.0064, rate_unit="deg/h", tau_unit="h")
    0.08
    >>> round(arw_from_coefficient(23.04, rate_unit="deg/h", tau_unit="s"), 12)
    0.08
    """
    if a_minus1 < 0:
        raise GonioError(f"A_-1 must be ≥ 0, got {a_minus1}")
    n = math.sqrt(a_minus1)
    scale = {("deg/h", "h"): 1.0, ("deg/h", "s"): 1.0 / math.sqrt(S_PER_H),
             ("deg/s", "s"): math.sqrt(S_PER_H), ("deg/s", "h"): S_PER_H}
    try:
        return n * scale[(rate_unit, tau_unit)]
    except KeyError:
        raise GonioError(f"unsupported units {rate_unit}, τ in {tau_unit}") from None


def arw_minus_half_line(tau_s, adev_dph, *, slope_tol: float = 0.05) -> tuple[float, np.ndarray]:
    """IEC 62047-20 5.4.5.2 e), reading taken: a line of slope −½ through the short-τ part of
    the Allan curve — the τ from the shortest one up to the first whose local slope leaves
    −½ ± ``slope_tol`` — its value at τ = 1 h in °/h is the ARW in °/√h. Returns
    (ARW °/√h, mask of the τ used).

    >>> tau = np.array([1.0, 2, 4, 8, 16])
    >>> round(arw_minus_half_line(tau, 4.8 / np.sqrt(tau))[0], 6)
    0.08
    """
    t, s = _arr(tau_s, "tau_s"), _arr(adev_dph, "adev")
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
    s = _arr(adev_dph, "adev")
    ok = np.ones(s.size, bool) if n_clusters is None else np.asarray(n_clusters) >= min_clusters
    if not ok.any():
        raise GonioError("no τ has enough clusters for the bias-instability floor")
    idx = np.flatnonzero(ok)[int(np.argmin(s[ok]))]
    return float(s[idx] / FLICKER_FLOOR_EXACT), int(idx)


# --------------------------------------------------------------------------- frequency response
def bandwidth_grid(f_est_hz: float) -> list[float]:
    """JJF 1535 7.2.15.1 b), reading taken: f_u = f_est + 10 Hz, f_i = i·f_u/8 (i = 1…8),
    plus f_est and the midpoints between f_est and its grid neighbours (duplicates removed).

    >>> bandwidth_grid(70.0)
    [10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 65.0, 70.0, 75.0, 80.0]
    >>> bandwidth_grid(100.0)
    [13.75, 27.5, 41.25, 55.0, 68.75, 82.5, 96.25, 98.125, 100.0, 105.0, 110.0]
    """
    if not f_est_hz > 0:
        raise GonioError(f"estimated bandwidth must be > 0, got {f_est_hz}")
    fu = f_est_hz + 10.0
    grid = [i * fu / 8.0 for i in range(1, 9)]
    below = max([f for f in grid if f < f_est_hz - 1e-9], default=None)
    above = min([f for f in grid if f > f_est_hz + 1e-9], default=None)
    extra = [f_est_hz] + ([0.5 * (below + f_est_hz)] if below is not None else []) \
        + ([0.5 * (above + f_est_hz)] if above is not None else [])
    out: list[float] = []
    for f in sorted(grid + extra):
        if not out or abs(f - out[-1]) > 1e-9 * f:
            out.append(round(f, 9))
    return out


def sine_fit(time_s, y, freq_hz: float) -> tuple[float, float, float]:
    """Least-squares y ≈ c + A sin(2πft + φ) at a known frequency (IEC 5.5 reading taken):
    returns (A, φ in degrees, c).

    >>> t = np.arange(0, 1, 0.001)
    >>> A, p, c = sine_fit(t, 2 + 3 * np.sin(2 * np.pi * 5 * t - 0.5), 5.0)
    >>> round(A, 9), round(math.radians(p), 9), round(c, 9)
    (3.0, -0.5, 2.0)
    """
    t, v = _arr(time_s, "time_s"), _arr(y, "output")
    w = 2 * math.pi * float(freq_hz)
    A = np.column_stack([np.ones_like(t), np.sin(w * t), np.cos(w * t)])
    (c, s, co), *_ = np.linalg.lstsq(A, v, rcond=None)
    return float(math.hypot(s, co)), float(math.degrees(math.atan2(co, s))), float(c)


def _log_crossing(f, v, target) -> float:
    f, v = np.asarray(f, float), np.asarray(v, float)
    for i in range(1, f.size):
        if (v[i - 1] - target) * (v[i] - target) <= 0 and v[i] != v[i - 1]:
            lf = np.log(f[i - 1]) + (target - v[i - 1]) * (np.log(f[i]) - np.log(f[i - 1])) / (v[i] - v[i - 1])
            return float(np.exp(lf))
    return math.nan


def minus3db_frequency(freq_hz, gain_ratio, *, reference: float | None = None) -> float:
    """JJF 1535 7.2.15.2 / IEC 62047-20 5.5.3, reading taken: gain in dB relative to
    ``reference`` (default: the lowest frequency's), crossing of −3 dB found by linear
    interpolation of dB against log f; NaN when not reached.

    >>> round(minus3db_frequency([10, 100], [1.0, 10 ** (-6 / 20)]), 9)   # 10^1.5
    31.622776602
    """
    f, g = _arr(freq_hz, "freq_hz"), _arr(gain_ratio, "gain")
    order = np.argsort(f)
    f, g = f[order], g[order]
    ref = g[0] if reference is None else float(reference)
    db = 20 * np.log10(g / ref)
    return _log_crossing(f, db, -3.0)


def phase90_frequency(freq_hz, phase_deg) -> float:
    """IEC 62047-20 5.5.3: frequency of 90° lag (phase = −90°), interpolated in log f;
    NaN when not reached.

    >>> round(phase90_frequency([50, 200], [-45.0, -135.0]), 9)
    100.0
    """
    f, p = _arr(freq_hz, "freq_hz"), _arr(phase_deg, "phase_deg")
    order = np.argsort(f)
    return _log_crossing(f[order], p[order], -90.0)


def second_order_response(freq_hz, fn_hz: float, zeta: float) -> tuple[np.ndarray, np.ndarray]:
    """|H| and ∠H (degrees) of H(s) = ω_n²/(s² + 2ζω_n s + ω_n²).

    Digest checks (JJF 12, IEC 15): f_n = 100 Hz, ζ = 0.5 lags 90° at 100 Hz with |H| = 1.

    >>> g, p = second_order_response([100.0], 100.0, 0.5)
    >>> round(float(g[0]), 12), round(float(p[0]), 9)
    (1.0, -90.0)
    """
    f = np.asarray(freq_hz, float)
    u = f / fn_hz
    h = 1.0 / (1.0 - u ** 2 + 2j * zeta * u)
    return np.abs(h), np.degrees(np.angle(h))


# --------------------------------------------------------------------------- IEC specifics
def linearity_errors_iec(rates_dps, outputs) -> tuple[np.ndarray, float, float, float]:
    """IEC 62047-20 5.1.3.6 eqs (8), (9): L_i = [y_i − (a x_i + b)]/FullScale, the line of
    5.1.3.1 (rest point included), FullScale = y(CW max) − y(CCW max) (measured, magnitude).

    Returns (L_i array, a_BASE, b_BASE, FullScale).
    """
    x, y = _arr(rates_dps, "rate_dps"), _arr(outputs, "output")
    a, b = least_squares_line(x, y)
    fs = abs(float(y[np.argmax(x)] - y[np.argmin(x)]))
    if fs == 0:
        raise GonioError("IEC 62047-20 (9): full-scale span is zero")
    return (y - (a * x + b)) / fs, a, b, fs


def symmetry_iec(rates_dps, outputs, a_typ: float) -> tuple[float, float, float, float, float]:
    """IEC 62047-20 5.1.3.8 eqs (13)–(17): separate CW (x > 0) and CCW (x < 0) fits without
    the rest point; S = (a_CW − a_CCW)/a_TYP (signed). Returns (S, a_CW, b_CW, a_CCW, b_CCW).
    """
    x, y = _arr(rates_dps, "rate_dps"), _arr(outputs, "output")
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


# --------------------------------------------------------------------------- IEC additions
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
    t, b = _arr(temps_c, "temperature_c"), _arr(values, "bias")
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
    s, r = _arr(steps_dps, "step"), _arr(response_dps, "response")
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
    f, p = _arr(freq_hz, "freq_hz"), _arr(psd_one_sided, "psd")
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
    f, p = _arr(freq_hz, "freq_hz"), _arr(psd_one_sided, "psd")
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
    a = _arr(accel_g, "acceleration")
    w = _arr(rate_dps, "rate_dps") - (0.0 if earth_dps is None else _arr(earth_dps, "earth"))
    cols = [np.ones_like(a), a] + ([] if transverse_g is None else [_arr(transverse_g, "accel")])
    A = np.column_stack(cols)
    if a.size < A.shape[1] + 1 or np.linalg.matrix_rank(A) < A.shape[1]:
        raise GonioError("5.3.3.8: the stand angles do not determine the slope")
    coef, *_ = np.linalg.lstsq(A, w, rcond=None)
    return float(coef[1]), (float(coef[2]) if transverse_g is not None else math.nan)


# --------------------------------------------------------------------------- 50 % rule under noise
def _phi(x):
    from scipy.special import ndtr
    return ndtr(np.asarray(x, float))


def fifty_percent_pass_probability(mean, sigma, expected, *, limit: float = 0.5,
                                   two_sided: bool = True) -> np.ndarray:
    """Probability that a step passes the 50 % rule when its measured response is normal with
    ``mean`` and standard deviation ``sigma``: two-sided (JJF 1535 eqs (13), (14) reading)
    P(|X − e| ≤ limit·|e|), one-sided (IEC 62047-20 5.6.3) P(X/e ≥ limit). σ = 0 gives 0 or 1.

    >>> [round(float(v), 6) for v in fifty_percent_pass_probability([1.0, 1.0], [0.0, 0.5], [1.0, 1.0])]
    [1.0, 0.682689]
    """
    m, s, e = (np.asarray(v, float) for v in (mean, sigma, expected))
    m, s, e = np.broadcast_arrays(m, s, e)
    ae = np.abs(e)
    sg = np.sign(e)
    out = np.empty(m.shape)
    z = s == 0
    if two_sided:
        out[z] = (np.abs(m[z] - e[z]) <= limit * ae[z] * (1 + 1e-12)).astype(float)
        nz = ~z
        out[nz] = _phi((e[nz] + limit * ae[nz] - m[nz]) / s[nz]) - _phi((e[nz] - limit * ae[nz] - m[nz]) / s[nz])
    else:
        out[z] = (sg[z] * m[z] >= limit * ae[z] * (1 - 1e-12)).astype(float)
        nz = ~z
        out[nz] = 1.0 - _phi((limit * ae[nz] - sg[nz] * m[nz]) / s[nz])
    return out


def fifty_percent_outcome_pmf(steps, pass_prob) -> dict:
    """Distribution of the 50 % rule's outcome when the steps (in walking order) pass
    independently with ``pass_prob``: the result is step k with probability
    p_1···p_k·(1 − p_{k+1}) (the last step: p_1···p_n), and None ("the first step already
    fails") with 1 − p_1.

    >>> {k: round(v, 6) for k, v in fifty_percent_outcome_pmf([0.1, 0.05, 0.02], [1.0, 0.8, 0.5]).items()}
    {None: 0.0, 0.1: 0.2, 0.05: 0.4, 0.02: 0.4}
    """
    s, p = list(map(float, steps)), [float(v) for v in pass_prob]
    pmf = {None: 1.0 - p[0]}
    run = 1.0
    for i, (st, pi) in enumerate(zip(s, p)):
        run *= pi
        nxt = p[i + 1] if i + 1 < len(p) else 0.0
        pmf[abs(st)] = pmf.get(abs(st), 0.0) + run * (1.0 - nxt)
    return pmf


def max_outcome_pmf(*pmfs) -> dict:
    """Distribution of the larger of independent 50 % rule outcomes (the item takes the larger
    direction); None (above the grid) ranks highest.

    >>> max_outcome_pmf({0.1: 0.5, 0.05: 0.5}, {0.1: 0.5, 0.05: 0.5})
    {0.05: 0.25, 0.1: 0.75}
    """
    keys = sorted({k for p in pmfs for k in p if k is not None}) + [None]

    def cdf(p, k):
        idx = keys.index(k)
        return sum(v for kk, v in p.items() if keys.index(kk) <= idx)

    out, prev = {}, 0.0
    for k in keys:
        c = float(np.prod([cdf(p, k) for p in pmfs]))
        if c - prev > 0:
            out[k] = c - prev
        prev = c
    return out


def outcome_quantile(pmf: dict, q: float):
    """The q-quantile of an outcome distribution (None ranks highest).

    >>> outcome_quantile({0.05: 0.25, 0.1: 0.75}, 0.5)
    0.1
    """
    keys = sorted(k for k in pmf if k is not None) + ([None] if None in pmf else [])
    c = 0.0
    for k in keys:
        c += pmf[k]
        if c >= q - 1e-12:
            return k
    return keys[-1]


def bias_drift_u(K: float, u_K: float, B: float, u_B: float, tau_s, adev_high,
                 separation_s: float) -> float:
    """Standard uncertainty of the difference of two bias records ``separation_s`` apart, from
    the static record's noise analysis (same rate unit as ``adev_high``): rate random walk
    K√Δt and bias instability √2·0.664·B, each coefficient's square increased by its fit
    uncertainty. A rate random walk the record is too short to resolve (fit at K = 0) is
    bounded by the upper confidence limit of the Allan deviation at the longest τ,
    K ≤ σ_hi(τ_max)·√(3/τ_max), taken as rectangular on [0, bound] (K² ≥ bound²/3).

    >>> round(bias_drift_u(0.0, 0.0, 0.0, 0.0, [10.0, 300.0], [50.0, 10.0], 3600.0), 6)   # √(1/3·3600)
    34.641016
    """
    t, s = _arr(tau_s, "tau_s"), _arr(adev_high, "adev")
    def ok(x):
        return x if math.isfinite(x) else 0.0
    k2 = ok(K) ** 2 + ok(u_K) ** 2
    i = int(np.argmax(t))
    k2 = max(k2, (s[i] * math.sqrt(3.0 / t[i])) ** 2 / 3.0)
    b2 = ok(B) ** 2 + ok(u_B) ** 2
    return math.sqrt(k2 * abs(separation_s) + 2 * FLICKER_FLOOR_EXACT ** 2 * b2)
