"""Rate-gyro arithmetic shared by JJF 1535-2015 and IEC 62047-20:2014: what both
specifications use (the least-squares line, the Earth-rate projection, the frequency
response, the 50 % rule under noise, the drift term of a bias). The formulas of one document
alone are in its package: :mod:`gonio.specs.jjf1535.formulas` (``*_jjf`` and the JJF
readings), :mod:`gonio.specs.iec62047_20.formulas` (``*_iec`` and the IEC readings).

Every function is one formula (or one documented reading of an ambiguous
formula); the specification packages choose which to call and in what order. Nothing here
reads files or knows the bench.

Conventions: Ω (``rate_dps``) in °/s; F (``output``) in the gyro's own output
unit (mV, LSB, counts/s); K in output per °/s; temperatures in °C. The clause
readings are documented in ``docs/jjf1535-readings.md`` and
``docs/iec62047-20-readings.md``.

Contents
========
==============================  ==================================================
:func:`least_squares_line`      y = a x + b, JJF (5) / IEC (1), (2), (5), (6)
:func:`r5_rates`                the R5 rate series of JJF 7.2.1.1 c)
:func:`block_mean_stability`    JJF (18): std of P-sample block means / K
:func:`earth_rate_projection_dps`  Ω_E on a gyro axis, any orientation
:func:`sine_fit`                amplitude and phase at a known frequency (IEC 5.5 reading)
:func:`minus3db_frequency`      −3 dB crossing (JJF 7.2.15.2, IEC 5.5.3)
:func:`phase90_frequency`       90° lag crossing (IEC 5.5.3)
:func:`second_order_response`   |H|, ∠H of a second-order sensor (bench truth, checks)
==============================  ==================================================

Unit note: seconds per hour come from :mod:`gonio.units` (``S_PER_H``).
"""

from __future__ import annotations

import math

import numpy as np

from gonio.analysis.noise.stream import Record
from gonio.physics.earth import OMEGA_E_RAD_S, earth_rate_enu
from gonio.errors import GonioError
from gonio.protocol.rate import r5_rates  # noqa: F401  (JJF 7.2.1.1 c) series, re-exported)
from gonio.units import S_PER_H  # noqa: F401  (the doctests' unit)

#: Earth rate, °/s (IERS value; 4.178074×10⁻³ °/s).
OMEGA_E_DPS = math.degrees(OMEGA_E_RAD_S)
#: −3 dB as an amplitude ratio, 10^(−3/20) (JJF 7.2.15.2 reading; IEC 5.5.3).
MINUS_3DB_RATIO = 10.0 ** (-3.0 / 20.0)
#: √(2 ln 2 / π): Allan-deviation floor per unit bias instability (IEC 5.4.5.3 c)).
FLICKER_FLOOR_EXACT = math.sqrt(2.0 * math.log(2.0) / math.pi)
#: Standard gravity, m/s² (the "g" of JJF 7.2.12 and IEC 5.3.3.8).
G_STANDARD = 9.80665


def as_array(x, name: str) -> np.ndarray:
    """``x`` as a flat float64 array; a non-finite value is a GonioError naming ``name``. A
    long record (:class:`~gonio.analysis.noise.stream.Record`) is returned as it is, checked
    piece by piece: the functions given one read it by slices."""
    if isinstance(x, Record):               # a long record, read in pieces
        x.check_finite(name)
        return x
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
    x, y = as_array(x, "x"), as_array(y, "y")
    if x.size != y.size or x.size < 2:
        raise GonioError(f"a line needs ≥ 2 points of equal count, got {x.size} and {y.size}")
    xm, ym = x.mean(), y.mean()
    sxx = float(((x - xm) ** 2).sum())
    if sxx == 0:
        raise GonioError("a line needs at least two different input values")
    a = float(((x - xm) * (y - ym)).sum() / sxx)
    return a, float(ym - a * xm)


# --------------------------------------------------------------------------- bias
def block_mean_stability(samples, K: float, block: int) -> float:
    """JJF 1535 7.2.10 eq (18): B_s = (1/K)·s(block means of P samples), Bessel s over the
    N/P non-overlapping blocks (an incomplete last block dropped; reading taken).

    Digest check 9 (K = 10 mV/(°/s), P = 2): 1.2247×10⁻³ °/s.

    >>> round(block_mean_stability([.10, .12, .08, .11, .09, .13, .07, .10], 10.0, 2), 8)
    0.00122474
    """
    x = as_array(samples, "output")
    P = int(block)
    n = x.size // P
    if P < 1 or n < 2:
        raise GonioError(f"bias stability needs ≥ 2 blocks of {P} samples, got {x.size} samples")
    means = x.block_means(P) if isinstance(x, Record) else x[: n * P].reshape(n, P).mean(axis=1)
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


def last_exceedance_time(time_s, stat, level: float) -> float:
    """The time (from the first sample) of the point after the last one whose ``stat``
    exceeds ``level``: 0 when none does, NaN when the last point still does. The detection
    rule of JJF 1535 7.2.9 (stat: window stability) and IEC 62047-20 5.3.3.9 (stat:
    |smoothed output − settled bias|).

    >>> last_exceedance_time([0, 10, 20, 30], [5, 3, 1, 0.5], 2.0)
    20.0
    """
    t, x = as_array(time_s, "time_s"), as_array(stat, "stat")
    over = np.flatnonzero(x > level)
    if over.size == 0:
        return 0.0
    return math.nan if over[-1] + 1 >= t.size else float(t[over[-1] + 1] - t[0])


# --------------------------------------------------------------------------- frequency response


def sine_fit(time_s, y, freq_hz: float) -> tuple[float, float, float]:
    """Least-squares y ≈ c + A sin(2πft + φ) at a known frequency (IEC 5.5 reading taken):
    returns (A, φ in degrees, c).

    >>> t = np.arange(0, 1, 0.001)
    >>> A, p, c = sine_fit(t, 2 + 3 * np.sin(2 * np.pi * 5 * t - 0.5), 5.0)
    >>> round(A, 9), round(math.radians(p), 9), round(c, 9)
    (3.0, -0.5, 2.0)
    """
    t, v = as_array(time_s, "time_s"), as_array(y, "output")
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
    f, g = as_array(freq_hz, "freq_hz"), as_array(gain_ratio, "gain")
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
    f, p = as_array(freq_hz, "freq_hz"), as_array(phase_deg, "phase_deg")
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
    t, s = as_array(tau_s, "tau_s"), as_array(adev_high, "adev")
    def ok(x):
        return x if math.isfinite(x) else 0.0
    k2 = ok(K) ** 2 + ok(u_K) ** 2
    i = int(np.argmax(t))
    k2 = max(k2, (s[i] * math.sqrt(3.0 / t[i])) ** 2 / 3.0)
    b2 = ok(B) ** 2 + ok(u_B) ** 2
    return math.sqrt(k2 * abs(separation_s) + 2 * FLICKER_FLOOR_EXACT ** 2 * b2)
