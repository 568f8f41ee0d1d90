"""The formulas of JJF 1535-2015 alone (the ``*_jjf`` functions and the JJF readings taken);
what JJF 1535 and IEC 62047-20 share is :mod:`gonio.specs._rate_family.formulas`.

Conventions as there: Ω (``rate_dps``) in °/s; F (``output``) in the gyro's own output unit;
K in output per °/s; temperatures in °C. The clause readings are documented in
``docs/jjf1535-readings.md``.

Contents
========
==============================  ==================================================
:func:`fit_scale_factor`        JJF (4), (5): rest-removed means, K, F_0, residuals
:func:`nonlinearity_jjf`        JJF (6): max |residual| / fitted span
:func:`ripple_residual_sd`      JJF (6): table ripple in each residual of the line (5)
:func:`asymmetry_jjf`           JJF (8): |K+ − K−| / mean
:func:`asymmetry_slope_u`       JJF (8): noise and table ripple through K+ and K−
:func:`relative_std`            JJF (10): s(K_m)/K̄
:func:`temperature_sensitivity` JJF (11) and (27): largest slope to room temperature
:func:`fifty_percent_candidate` JJF (13), (14), IEC 5.6.3: the 50 % rule
:func:`sample_std`              JJF (20): Bessel standard deviation
:func:`g_sensitivity_axis`      JJF 7.2.12.2, Earth rate removed per position
:func:`allan_variance_printed_jjf`  JJF (22)–(24) as printed (not an Allan variance)
:func:`allan_variance_overlapping`  the reading taken: IEEE 952 overlapping AVAR
:func:`allan_variances_jjf`   both of the above for several k in one pass
:func:`arw_from_coefficient`    JJF (26), unit handling of 7.2.13
:func:`bandwidth_grid`          JJF 7.2.15.1 b) frequency grid
:func:`warmup_time_s`           JJF 7.2.9 reading: sliding-window stability
==============================  ==================================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gonio.analysis.noise.stream import CumulativeSum, Record
from gonio.errors import GonioError
from gonio.specs._rate_family.formulas import (as_array, block_mean_stability,
                                               last_exceedance_time, least_squares_line)
from gonio.units import S_PER_H


def rest_level(rest_before: float, rest_after: float) -> float:
    """F_r of JJF 1535 7.2.1.1 d), reading taken: the mean of the rest before and after.

    >>> rest_level(2.0, 4.0)
    3.0
    """
    return 0.5 * (float(rest_before) + float(rest_after))


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


def fit_scale_factor(rates_dps, raw_means, rest: float = 0.0) -> ScaleFactorFit:
    """JJF 1535 7.2.1.2 eqs (4), (5): F̄_j = mean − F_r, then K, F_0 by least squares over
    the rate points of both directions (rests are not fit points).

    >>> f = fit_scale_factor([-2, -1, 1, 2], [-19.0, -9.0, 11.0, 21.0], rest=1.0)
    >>> f.K, f.F0
    (10.0, 0.0)
    """
    rates = as_array(rates_dps, "rate_dps")
    means = as_array(raw_means, "output") - float(rest)
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


def ripple_mean_sd(rates_dps, spans_s, ripple_rel: float) -> np.ndarray:
    """Standard deviation (°/s) of the error that the rate table's once-per-revolution ripple
    gives each rate point's mean: amplitude ``ripple_rel``·|Ω_j|, averaged over the turn
    Δ_j = Ω_j·T_j the point's samples cover (``spans_s``), so the mean's error is
    ripple_rel·|Ω_j|·sinc(Δ_j/2)·sin(ψ_j) with ψ_j a phase the table's angle history sets
    (uniform, an arcsine variable of variance ½): ripple_rel·|Ω_j|·|sinc(Δ_j/2)|/√2.

    >>> [round(float(v), 9) for v in ripple_mean_sd([10, 1], [36, 1e-9], 1e-3)]   # a full turn
    [0.0, 0.000707107]
    """
    r, T = as_array(rates_dps, "rate_dps"), as_array(spans_s, "span_s")
    if r.shape != T.shape:
        raise GonioError(f"ripple_mean_sd: {r.size} rates and {T.size} spans")
    sinc = np.sinc(0.5 * np.radians(np.abs(r) * T) / math.pi)     # sin(Δ/2)/(Δ/2)
    return ripple_rel * np.abs(r * sinc) / math.sqrt(2.0)


def ripple_residual_sd(rates_dps, spans_s, ripple_rel: float,
                       scale_factor: float) -> np.ndarray:
    """Standard deviation (output units) of the rate-table ripple's share of each residual
    v_j of the two-direction line (JJF 1535 7.2.1.2 eq (5)), the residuals whose largest
    |v_j| eq (6) of 7.2.2 takes: the points' means carry K·e_k (e_k the ripple's error of
    point k, :func:`ripple_mean_sd`, phases independent between points), and the residuals
    are (I − H)·K·e, H the hat matrix of the least-squares line over the rate points, so
    Var(v_j) = K²·Σ_k (I − H)_jk²·sd(e_k)².

    To first order the largest |residual| moves by the ripple of its own residual, so this
    sd at its index is the ripple's standard uncertainty of eq (6)'s numerator.

    With no turn averaging, two points ±1 °/s: the line fits them exactly (no residual):

    >>> [round(float(v), 12) for v in ripple_residual_sd([1, -1], [1e-9, 1e-9], 1e-3, 2.0)]
    [0.0, 0.0]

    Rates (1, 2, −1, −2): H = 11ᵀ/4 + ΩΩᵀ/10, so row 1 of I − H is (0.65, −0.45, −0.15,
    −0.05) and row 2 (−0.45, 0.35, −0.05, 0.15); with sd(e) = 10⁻³·|Ω|/√2:

    >>> v = ripple_residual_sd([1, 2, -1, -2], [1e-9] * 4, 1e-3, 1.0)
    >>> [round(float(x), 9) for x in v[:2]], round(1e-3 * math.sqrt(1.265 / 2), 9)
    ([0.000795299, 0.000626498], 0.000795299)
    """
    r = as_array(rates_dps, "rate_dps")
    sd = ripple_mean_sd(r, spans_s, ripple_rel)
    X = np.column_stack([r, np.ones_like(r)])
    M = np.eye(r.size) - X @ np.linalg.pinv(X)                      # I − H
    return abs(float(scale_factor)) * np.sqrt((M ** 2) @ sd ** 2)


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
    r, y = as_array(rates_dps, "rate_dps"), as_array(means, "output")
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


def asymmetry_slope_u(rates_dps, u_noise, spans_s, ripple_rel: float,
                      scale_factor: float) -> tuple[float, float]:
    """Standard uncertainties of one calibration's signed K_a = (K+ − K−)/K̄ (JJF 1535
    7.2.3 eq (8)) from the rate points' means, through each direction's least-squares
    slope K± = Σ c_j·F_j, c_j = (Ω_j − Ω̄±)/S±, S± = Σ(Ω_j − Ω̄±)²:

    - noise: σ·√(1/S+ + 1/S−)/|K|, σ = ``u_noise`` the rate-point means' pooled standard
      error (output units);
    - table ripple: the table's once-per-revolution ripple, amplitude ``ripple_rel``·|Ω|,
      averaged over the point's sampled span T_j (``spans_s``): its mean is
      ripple_rel·|Ω_j|·sinc(Δ_j/2)·sin(ψ_j), Δ_j = Ω_j·T_j the turn sampled, ψ_j a phase
      the table's angle history sets (not in the readings: uniform, independent between
      points, an arcsine variable of variance ½); its share of K± is
      Σ c_j·Ω_j·e_j, so u² = ½·ripple_rel²·Σ_j (c_j·Ω_j·sinc(Δ_j/2))² over both directions.

    Returns (u_noise_rel, u_ripple_rel), relative (dimensionless, as K_a).

    A full revolution averages the ripple out (Δ = 360°: sinc(π) = 0):

    >>> un, ur = asymmetry_slope_u([1, 2, -1, -2], 0.0, [360, 180, 360, 180], 1e-3, 1.0)
    >>> un, round(ur, 12)
    (0.0, 0.0)
    >>> un, ur = asymmetry_slope_u([1, 2, -1, -2], 0.1, [1e-9] * 4, 1e-3, 2.0)
    >>> round(un, 6), round(ur, 8)   # σ·√(2 + 2)/2; c·Ω = (−1, 2) each way: √(½·1e-6·10)
    (0.1, 0.00223607)
    """
    r = as_array(rates_dps, "rate_dps")
    T = as_array(spans_s, "span_s")
    u_n2, u_r2 = 0.0, 0.0
    for sel in (r > 0, r < 0):
        x = r[sel]
        dx = x - x.mean()
        S = float((dx ** 2).sum())
        if x.size < 2 or S <= 0:
            raise GonioError("JJF 1535 7.2.3 needs ≥ 2 different rates in each direction")
        half_turn = 0.5 * np.radians(np.abs(x) * T[sel])
        sinc = np.sinc(half_turn / math.pi)                      # sin(Δ/2)/(Δ/2)
        u_n2 += u_noise ** 2 / S
        u_r2 += 0.5 * ripple_rel ** 2 * float(((dx / S * x * sinc) ** 2).sum())
    k = abs(float(scale_factor))
    return math.sqrt(u_n2) / k, math.sqrt(u_r2)


def relative_std(values) -> tuple[float, float, float]:
    """JJF 1535 7.2.4 eq (10): (mean, s, s/|mean|) with the Bessel s.

    >>> m, s, r = relative_std([10.0000, 10.0012, 9.9991])
    >>> round(m, 4), round(s, 7), round(r, 8)
    (10.0001, 0.0010536, 0.00010536)
    """
    v = as_array(values, "values")
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
    v = as_array(values, "values")
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
    x, t = as_array(values, "values"), as_array(temps_c, "temperature_c")
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
    s, m, e = as_array(step_dps, "step"), as_array(measured, "measured"), as_array(expected, "expected")
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


def g_sensitivity_axis(rate_plus_dps: float, rate_minus_dps: float,
                       earth_plus_dps: float = 0.0, earth_minus_dps: float = 0.0) -> float:
    """JJF 1535 7.2.12.2: B_g,axis = [ω̄(+axis up) − ω̄(−axis up)]/(2 g), per g.

    Reading taken: the Earth-rate projection on the input axis is subtracted in each
    position first (digest check 10: 49.668/20.332 °/h → 5.000, literal 14.668).

    >>> round(g_sensitivity_axis(49.668, 20.332), 3), round(g_sensitivity_axis(49.668, 20.332, 9.668, -9.668), 3)
    (14.668, 5.0)
    """
    return ((rate_plus_dps - earth_plus_dps) - (rate_minus_dps - earth_minus_dps)) / 2.0


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
    t, x = as_array(time_s, "time_s"), as_array(rate, "rate")
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


def allan_variance_printed_jjf(rate, k: int) -> float:
    """JJF 1535 7.2.13 eqs (22)–(24) **as printed** (the standard's reading, labelled):
    overlapping k-sample means Ω̄_p, differences of means *one sample apart*, then
    σ² = Σ (Ω̄_{p+2} − 2Ω̄_{p+1} + Ω̄_p)² / (2(n − k − 1)).

    This is not an Allan variance: for white noise of unit variance it gives 3 at k = 1
    and 2/k² for k ≥ 2 (digest check 14), so the ARW cannot be read from it.
    """
    x = as_array(rate, "rate")
    k = int(k)
    if k < 1 or x.size < k + 3:
        raise GonioError(f"printed eq (24) needs n ≥ k + 3, got n = {x.size}, k = {k}")
    c = _cumsum0(x)
    total = sum(_printed_terms(c, a, b, k) for a, b in _pieces(x.size - k - 1))
    return total / (2.0 * (x.size - k - 1))


def _printed_terms(c, a: int, b: int, k: int) -> float:
    """Σ of the printed eq (24) terms p = a … b − 1 from c = [0, cumsum(rate)]: overlapping
    means Ω̄_p = (c[p+k] − c[p])/k, p = 0 … n − k; terms p = 0 … n − k − 2."""
    m = (c[a + k: b + k + 2] - c[a: b + 2]) / k
    d2 = m[2:] - 2 * m[1:-1] + m[:-2]
    return float((d2 ** 2).sum())


def _overlapping_terms(c, a: int, b: int, k: int) -> float:
    """Σ of the overlapping AVAR terms p = a … b − 1 from c = [0, cumsum(rate)]:
    d_p = Ω̄_{p+k} − Ω̄_p, p = 0 … n − 2k."""
    d = (c[a + 2 * k: b + 2 * k] - c[a + k: b + k]) / k - (c[a + k: b + k] - c[a: b]) / k
    return float((d ** 2).sum())


def allan_variances_jjf(rate, ks) -> dict[int, tuple[float, float]]:
    """{k: (:func:`allan_variance_printed_jjf`, :func:`allan_variance_overlapping`)} for
    every k of ``ks`` at once, equal to the two functions bit for bit (the same terms in the
    same pieces) but from one cumulative sum read in one pass (each piece of it sliced once
    for every k): a long record's sum is rebuilt once, not twice per k.

    >>> allan_variances_jjf([1.0, -1.0] * 8, [1, 2])[1][1]
    2.0
    """
    x = as_array(rate, "rate")
    ks = sorted({int(k) for k in ks})
    if not ks or ks[0] < 1 or x.size < 2 * ks[-1] + 3:
        raise GonioError(f"the eq (22)–(24) statistics need n ≥ 2k + 3, got n = {x.size}, "
                         f"k = {ks[-1] if ks else None}")
    c = _cumsum0(x)
    n = x.size
    tot = {k: [0.0, 0.0] for k in ks}
    for a in range(0, n - ks[0] - 1, _PIECE):
        cs = c[a: a + _PIECE + 2 * ks[-1] + 2]        # c[a + i] = cs[i]: one slice for all k
        for k in ks:
            for j, n_terms, terms in ((0, n - k - 1, _printed_terms),
                                      (1, n - 2 * k + 1, _overlapping_terms)):
                if a < n_terms:
                    tot[k][j] += terms(cs, 0, min(n_terms, a + _PIECE) - a, k)
    return {k: (p / (2.0 * (n - k - 1)), o / (2.0 * (n - 2 * k + 1))) for k, (p, o) in tot.items()}


#: Terms formed at a time by the direct Allan forms (bounded temporaries on long records).
_PIECE = 1 << 16


def _pieces(n: int):
    """(start, end) of consecutive pieces of range(n)."""
    return ((a, min(n, a + _PIECE)) for a in range(0, n, _PIECE))


def _cumsum0(x: np.ndarray) -> np.ndarray:
    """[0, cumsum(x)] in one array (no concatenated copy); of a long record read in pieces,
    the same numbers rebuilt block by block (never held whole)."""
    if isinstance(x, Record):
        return CumulativeSum(x)
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
    x = as_array(rate, "rate")
    k = int(k)
    if k < 1 or x.size < 2 * k + 1:
        raise GonioError(f"overlapping AVAR needs n ≥ 2k + 1, got n = {x.size}, k = {k}")
    c = _cumsum0(x)
    n_d = x.size - 2 * k + 1              # summed in pieces
    return sum(_overlapping_terms(c, a, b, k) for a, b in _pieces(n_d)) / (2.0 * n_d)


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


def interpolation_remainder(lnf: np.ndarray, p: np.ndarray, j: int) -> float:
    """JJF 1535 7.2.15.2 (log-f interpolation of the −3 dB point): the bound of linear
    interpolation's error between points j − 1 and j of p(ln f), h²/8·|p''| (the remainder
    of linear interpolation, h = ln f_j − ln f_{j−1}), p'' the second divided difference
    over j − 1, j and a third point at least h/2 away in ln f (the nearest such above j,
    else below j − 1; the adjacent point where none is): 7.2.15.1 b)'s grid packs points 1 %
    apart near f_est, and a second difference over those is the gains' noise over the
    spacing squared, not the curve's curvature. 0 with fewer than three points.

    >>> x = np.log([1.0, 2.0, 4.0]); round(interpolation_remainder(x, x ** 2, 1), 6)   # p'' = 2
    0.120113
    """
    lnf, p = np.asarray(lnf, float), np.asarray(p, float)
    if lnf.size < 3:
        return 0.0
    h = float(lnf[j] - lnf[j - 1])
    a, b, c = curvature_points(lnf, j)
    d2 = 2 * ((p[c] - p[b]) / (lnf[c] - lnf[b]) - (p[b] - p[a]) / (lnf[b] - lnf[a])) \
        / (lnf[c] - lnf[a])
    return h * h / 8 * abs(float(d2))


def curvature_points(lnf: np.ndarray, j: int) -> tuple[int, int, int]:
    """The three grid indices, ascending, of :func:`interpolation_remainder`'s second
    difference around the interval (j − 1, j): those two and a third point at least h/2
    away in ln f (the nearest above j, else below j − 1; the adjacent point where none is)."""
    lnf = np.asarray(lnf, float)
    h = float(lnf[j] - lnf[j - 1])
    above = [m for m in range(j + 1, lnf.size) if lnf[m] - lnf[j] >= h / 2]
    below = [m for m in range(j - 2, -1, -1) if lnf[j - 1] - lnf[m] >= h / 2]
    third = above[0] if above else below[0] if below else (j + 1 if j + 1 < lnf.size else j - 2)
    return tuple(sorted((j - 1, j, third)))
