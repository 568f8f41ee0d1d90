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
:func:`block_mean_variogram`    E[(ȳ_(i+k) − ȳ_i)²] of block means, pooled over records
:func:`block_variogram_fit`     that variogram fitted by white + flicker + random walk
:func:`block_variogram_model`   the fitted variogram at every lag
:func:`block_std_dof`           effective ν of a standard deviation of correlated means
:func:`bias_stability_dof`      effective ν of JJF (19)'s B_s from its own records
:func:`bias_stability_dofs`     the same, stated and estimated, from one fit
:func:`earth_rate_projection_dps`  Ω_E on a gyro axis, any orientation
:func:`max_abs_normal_mean`     c_n = E[max |Z_i|] of n normal values
:func:`selection_excess`        midpoint and half-width of a noisy maximum's excess
:func:`sine_fit`                amplitude and phase at a known frequency (IEC 5.5 reading)
:func:`minus3db_frequency`      −3 dB crossing (JJF 7.2.15.2, IEC 5.5.3)
:func:`phase90_frequency`       90° lag crossing (IEC 5.5.3)
:func:`second_order_response`   |H|, ∠H of a second-order sensor (bench truth, checks)
:func:`bias_drift_u`            drift of a bias difference, Allan floor + K√Δt
:func:`record_difference_u`     the same for two records' means, exact for their spans
:func:`record_difference_u_coef` the same with K² and B² given
:func:`window_combination_u_coef` any zero-sum combination of window means (a slope)
==============================  ==================================================

Unit note: seconds per hour come from :mod:`gonio.units` (``S_PER_H``).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtri

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
#: rms of the largest excursion of a standard Wiener process over [0, 1],
#: √E[max_t |W(t)|²] = √E[1/τ₁] = √(2G) ≈ 1.3535 (τ₁ the exit time of [−1, 1], whose
#: Laplace transform is sech √(2s), so E[1/τ₁] = ∫₀^∞ v·sech v dv = 2G, G Catalan's constant).
WALK_MAX_RMS = math.sqrt(2.0 * 0.915965594177219015)


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


def block_mean_variogram(records) -> tuple[np.ndarray, np.ndarray]:
    """The empirical variogram of block means pooled over records: D̂(k) = mean of
    (ȳ_(i+k) − ȳ_i)² over every pair k blocks apart in every record (k = 0 … n_max − 1,
    D̂(0) = 0), and the number of pairs behind each lag. It needs no mean, so a drift (a
    rate random walk) does not bias it (Cressie, Statistics for Spatial Data, 2.4.1). The
    lag products come from an FFT (O(n log n) per record), of each record less its mean (the
    variogram does not change; the FFT's rounding, about 10⁻¹⁶·n times the values' square,
    would otherwise scale with the output's level: a record at 10⁸ with block means of
    σ ≈ 0.3 moved the stated ν of :func:`bias_stability_dofs` from 126 to 49).

    >>> d, m = block_mean_variogram([[0.0, 1.0, 0.0, 1.0]])
    >>> d.tolist(), m.tolist()
    ([0.0, 1.0, 0.0, 1.0], [0, 3, 2, 1])
    """
    xs = [as_array(r, "block means") for r in records]
    n_max = max(x.size for x in xs)
    num, pairs = np.zeros(n_max), np.zeros(n_max, dtype=int)
    for x in xs:
        n = x.size
        x = x - x.mean() if n else x
        f = np.fft.rfft(x, 2 * n)
        cross = np.fft.irfft(f * np.conj(f), 2 * n)[:n]       # Σ_i x_i x_(i+k)
        c2 = np.concatenate([[0.0], np.cumsum(x * x)])
        k = np.arange(n)
        # Σ_(i<n−k) x_(i+k)² + x_i²  =  (Σ_(j≥k) x_j²) + (Σ_(i<n−k) x_i²)
        num[:n] += (c2[n] - c2[k]) + c2[n - k] - 2.0 * cross
        pairs[:n] += n - k
    out = np.zeros(n_max)
    ok = pairs > 0
    out[ok] = np.maximum(num[ok], 0.0) / pairs[ok]
    out[0] = 0.0
    pairs[0] = 0
    return out, pairs


def _h_log(x: np.ndarray) -> np.ndarray:
    """x²·ln|x|/2 − 3x²/4 (0 at x = 0): the second antiderivative of ln|x|."""
    x = np.asarray(x, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = 0.5 * x * x * np.log(np.abs(x)) - 0.75 * x * x
    return np.where(x == 0.0, 0.0, v)


def block_variogram_basis(lags) -> np.ndarray:
    """Columns of the block-mean variogram of the three rate-noise types of IEEE 952 C.1
    that matter beyond one block, per unit of each (lag k ≥ 1 in blocks; 0 at k = 0):
    white rate noise, a constant (2σ²/P); flicker (bias instability), whose structure
    function is logarithmic, ∫(1 − |w|)ln|k + w|dw over w ∈ [−1, 1] less its k = 0 value,
    = H(k + 1) − 2H(k) + H(k − 1) + 3/2 with H(x) = x²ln|x|/2 − 3x²/4; rate random walk,
    k − 1/3 (q²·P·t₀ per unit; at k = 1, 2/3, twice the Allan variance q²τ/3).

    >>> [round(float(v), 4) for v in block_variogram_basis([1, 2])[:, 1]]
    [1.3863, 2.1712]
    """
    k = np.asarray(lags, float)
    flick = _h_log(k + 1.0) - 2.0 * _h_log(k) + _h_log(k - 1.0) + 1.5
    cols = np.column_stack([np.ones_like(k), flick, k - 1.0 / 3.0])
    cols[k == 0] = 0.0
    return cols


def block_variogram_fit(variogram, pairs, iterations: int = 4
                        ) -> tuple[np.ndarray, np.ndarray]:
    """The coefficients (white, flicker, random walk) of the block-mean variogram fitted to
    the empirical one (:func:`block_mean_variogram`) by non-negative least squares on the
    columns of :func:`block_variogram_basis`, each lag weighted by its pairs over the
    model's variance (iteratively reweighted, starting from the empirical values; a squared
    difference has variance ∝ D(k)²), and their covariance: the weighted fit's
    (X'WX)⁻¹ scaled by its residual variance (the lags' weights are relative, and lags of one
    variogram are correlated: the scatter of the residuals, not the weights, sets the scale).
    Zero coefficients and covariance where no lag has a positive value.

    >>> k = np.arange(40)
    >>> d = block_variogram_basis(k) @ np.array([2.0, 0.0, 0.5])
    >>> c, cov = block_variogram_fit(d, 40 - k)
    >>> [round(float(v), 6) for v in c], float(np.abs(cov).max()) < 1e-12
    ([2.0, 0.0, 0.5], True)
    """
    from scipy.optimize import nnls

    d = np.asarray(variogram, float)
    m = np.asarray(pairs, float)
    lag = np.arange(d.size)
    use = (lag > 0) & (m > 0)
    if not np.any(use) or not np.any(d[use] > 0):
        return np.zeros(3), np.zeros((3, 3))
    X = block_variogram_basis(lag[use])
    y = d[use]
    scale = np.where(y > 0, y, np.max(y))
    for _ in range(iterations):
        w = np.sqrt(m[use]) / scale
        coef, _ = nnls(X * w[:, None], y * w)
        fit = X @ coef
        if not np.all(fit > 0):
            break
        scale = fit
    xw = X * w[:, None]
    r = (y - X @ coef) * w
    dof = max(1, y.size - X.shape[1])
    return coef, float(r @ r) / dof * np.linalg.pinv(xw.T @ xw)


def block_variogram_model(variogram, pairs, iterations: int = 4) -> np.ndarray:
    """The block-mean variogram D(k) fitted to the empirical one
    (:func:`block_mean_variogram`; the fit :func:`block_variogram_fit`). The raw variogram's
    long lags rest on a few pairs; their noise would enter ν as extra spread. Returns D at
    every lag (D(0) = 0)."""
    coef, _ = block_variogram_fit(variogram, pairs, iterations)
    return block_variogram_basis(np.arange(np.asarray(variogram).size)) @ coef


def block_std_dof(variogram, n: int) -> float:
    """Effective degrees of freedom of the sample variance s² of n block means whose
    variogram is D(k) (k = 0 … n − 1): s² = x'Mx/(n − 1), M the centring matrix, and
    M·Σ·M = −½·M·D·M for any covariance with that variogram (stationary or with stationary
    increments, a random walk included), so s² is Σλ_i·χ²₁ over the eigenvalues λ of
    A = −½MDM/(n − 1) and its Satterthwaite ν = (tr A)²/tr(A²) (Satterthwaite 1946; for
    independent means, D constant, ν = n − 1 exactly). O(n): tr(MDM) = −(1/n)·1'D1 and
    ‖MDM‖² = ‖D‖² − 2‖D1‖²/n + (1'D1)²/n², D Toeplitz.

    >>> block_std_dof([0.0, 2.0, 2.0, 2.0, 2.0], 5)
    4.0
    """
    d = np.asarray(variogram, float)[:n]
    if n < 2 or d.size < n:
        raise GonioError(f"the effective ν of a standard deviation needs ≥ 2 means and a "
                         f"variogram to lag {n - 1}")
    k = np.arange(n)
    total = 2.0 * float(np.sum((n - k[1:]) * d[1:]))            # 1'D1
    frob = 2.0 * float(np.sum((n - k[1:]) * d[1:] ** 2))        # ‖D‖²
    c = np.concatenate([[0.0], np.cumsum(d[1:])])               # C(m) = Σ_(1..m) D(j)
    rows = c[k] + c[n - 1 - k]                                  # (D1)_i
    tr = total / (2.0 * n)
    tr2 = 0.25 * (frob - 2.0 * float(rows @ rows) / n + total ** 2 / n ** 2)
    if not tr2 > 0:
        return math.inf
    return tr * tr / tr2


def bias_stability_dof(records, block: int, correlated_upper_p: float | None = None) -> float:
    """Effective degrees of freedom of JJF 1535 7.2.10's B_s, the mean over the Q records of
    s(block means) (eq (19)), from the records themselves: the block means' variogram pooled
    over the records (:func:`block_mean_variogram`), fitted by the noise types of
    IEEE 952 (:func:`block_variogram_fit`), gives each record's ν_m
    (:func:`block_std_dof`); a mean of Q standard deviations of relative variance 1/(2ν_m)
    has ν = Q²/Σ(1/ν_m). Correlated block means (bias instability, rate random walk) give
    ν well below Q(n − 1); independent ones give Q(n − 1). Blocks of ``block`` samples,
    an incomplete last block dropped, as eq (18) forms them.

    ``correlated_upper_p``: ν with the flicker and random-walk coefficients raised to their
    one-sided ``correlated_upper_p`` upper confidence limits (the fit's covariance,
    :func:`block_variogram_fit`), the ν the statement takes. The estimate's ν is negatively
    correlated with s²: where the correlated noise happens to wander little, B_s reads low
    and the variogram looks whiter, so ν̂ is large exactly where the limit must reach
    (corr(s², ν̂) ≈ −0.5 on the JJF study bench), and it reads high for strongly correlated
    noise. On sets of three records drawn from exact covariances (docs/jjf1535-readings.md,
    7.2.10) the estimate's χ² limit held σ in 91–94 %; with p = 0.95 here 94.6–97.8 %
    (Clopper–Pearson reaching 95 % on each of five noise mixes).

    >>> rng = np.random.default_rng(1)
    >>> x = [rng.normal(size=600) for _ in range(3)]
    >>> round(bias_stability_dof(x, 10)), round(bias_stability_dof(x, 10, 0.95))
    (177, 126)
    """
    return bias_stability_dofs(records, block, correlated_upper_p)[0]


def bias_stability_dofs(records, block: int, correlated_upper_p: float | None = None
                        ) -> tuple[float, float]:
    """(ν stated, ν estimated) of :func:`bias_stability_dof` from one fit of the records'
    variogram: the ν with the flicker and random-walk coefficients at their one-sided
    ``correlated_upper_p`` upper limits (the estimate's where None) and the estimate's.

    >>> rng = np.random.default_rng(1)
    >>> [round(v) for v in bias_stability_dofs([rng.normal(size=600) for _ in range(3)],
    ...                                        10, 0.95)]
    [126, 177]
    """
    P = int(block)
    means = []
    for r in records:
        x = as_array(r, "bias record")
        n = x.size // P
        if P < 1 or n < 2:
            raise GonioError(f"bias stability needs ≥ 2 blocks of {P} samples, got {x.size}")
        means.append(x[: n * P].reshape(n, P).mean(axis=1))
    d, pairs = block_mean_variogram(means)
    coef, cov = block_variogram_fit(d, pairs)
    basis = block_variogram_basis(np.arange(d.size))

    def nu_of(c) -> float:
        inv = sum(1.0 / block_std_dof(basis @ c, m.size) for m in means)
        return math.inf if inv == 0 else len(means) ** 2 / inv

    estimate = nu_of(coef)
    if correlated_upper_p is None:
        return estimate, estimate
    # flicker and random walk at their one-sided upper confidence limits, white as fitted
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    return nu_of(coef + float(ndtri(correlated_upper_p)) * sd * np.array([0.0, 1.0, 1.0])), \
        estimate


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


def max_abs_normal_mean(n: int) -> float:
    """c_n = E[max_i |Z_i|] of ``n`` independent standard normal values: the mean excess of
    the largest of n noisy values (or differences) whose true values are all equal, read as
    magnitudes (IEC 5.3.3.7's maximum over the temperatures visited twice, 5.3.3.5's largest
    smoothed value, JJF 7.2.2's largest residual): ∫₀^∞ 1 − (2Φ(x) − 1)ⁿ dx.

    >>> round(max_abs_normal_mean(1), 6), round(math.sqrt(2 / math.pi), 6)   # E|Z| = √(2/π)
    (0.797885, 0.797885)
    """
    from scipy import integrate, special

    if n < 1:
        raise GonioError(f"max_abs_normal_mean: n must be ≥ 1, got {n!r}")
    f = lambda x: 1.0 - special.erf(x / math.sqrt(2.0)) ** n  # noqa: E731   (2Φ − 1 = erf(x/√2))
    return float(integrate.quad(f, 0.0, 12.0, limit=200)[0])


def selection_excess(values, sds) -> tuple[float, int]:
    """The selection excess of the largest of noisy non-negative ``values`` (magnitudes, each
    with the standard deviation ``sds`` of its noise), as a midpoint and half-width
    (JCGM 100 4.3.7): (c_m·σ/2, m), σ the largest value's, m the contenders — the values
    within 2√2·σ_j of the largest (closer than twice the σ of a difference of two, so
    either could hold the largest true value). Noise raises a maximum by between 0 (one
    value stands clear of the others) and c_m·σ (m values share the largest true value,
    c_m = :func:`max_abs_normal_mean`); which holds is not known, so the reading less the
    midpoint c_m·σ/2 is the estimate and ± c_m·σ/2 its rectangular term. One contender
    (m = 1): no excess. The midpoint never exceeds the largest value.

    >>> half, m = selection_excess([5.0, 5.0], [1.0, 1.0])   # two equal: c_2·σ/2
    >>> m, round(half, 4), round(max_abs_normal_mean(2) / 2, 4)
    (2, 0.5642, 0.5642)
    >>> selection_excess([5.0, 1.0], [1.0, 1.0])              # one clear of the other
    (0.0, 1)
    """
    v, s = as_array(values, "values"), as_array(sds, "sds")
    if v.shape != s.shape or v.size == 0:
        raise GonioError(f"selection_excess: {v.size} values and {s.size} standard deviations")
    i = int(np.argmax(v))
    m = int(np.sum(v >= v[i] - 2 * math.sqrt(2) * s))
    half = min(max_abs_normal_mean(m) * float(s[i]) / 2, float(v[i])) if m > 1 else 0.0
    return half, m


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
                                   two_sided: bool = True, dof=None) -> np.ndarray:
    """Probability that a step passes the 50 % rule when its measured response is normal with
    ``mean`` and standard deviation ``sigma``: two-sided (JJF 1535 eqs (13), (14) reading)
    P(|X − e| ≤ limit·|e|), one-sided (IEC 62047-20 5.6.3) P(X/e ≥ limit). σ = 0 gives 0 or 1.
    With ``dof`` (per step) X is the scaled and shifted t of a mean whose σ was estimated
    with those degrees of freedom (JCGM 101 6.4.9), not normal.

    >>> [round(float(v), 6) for v in fifty_percent_pass_probability([1.0, 1.0], [0.0, 0.5], [1.0, 1.0])]
    [1.0, 0.682689]
    >>> round(float(fifty_percent_pass_probability([1.0], [0.5], [1.0], dof=[4])[0]), 6)  # t₄(1)
    0.626099
    """
    from scipy import stats

    m, s, e = (np.asarray(v, float) for v in (mean, sigma, expected))
    m, s, e = np.broadcast_arrays(m, s, e)
    ae = np.abs(e)
    sg = np.sign(e)
    out = np.empty(m.shape)
    z = s == 0
    nz = ~z
    if dof is None:
        cdf = _phi
    else:
        nu = np.broadcast_to(np.asarray(dof, float), m.shape)[nz]
        def cdf(x):                                        # noqa: E306
            return stats.t.cdf(x, nu)
    if two_sided:
        out[z] = (np.abs(m[z] - e[z]) <= limit * ae[z] * (1 + 1e-12)).astype(float)
        out[nz] = cdf((e[nz] + limit * ae[nz] - m[nz]) / s[nz]) - cdf((e[nz] - limit * ae[nz] - m[nz]) / s[nz])
    else:
        out[z] = (sg[z] * m[z] >= limit * ae[z] * (1 - 1e-12)).astype(float)
        out[nz] = 1.0 - cdf((limit * ae[nz] - sg[nz] * m[nz]) / s[nz])
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


def rule_outcome_uncertainty(pmfs: list[dict], value: float):
    """The uncertainty of a 50 % rule's outcome on a tested grid (IEC 62047-20 5.6
    Out,resolution; the same reading as JJF 1535 7.2.6/7.2.7, docs/jjf1535-readings.md):
    the measurand is the tested value at which the rule stops, its true value the median
    outcome under the instrument's noise. A grid value is a grid value (the grid belongs to
    the measurand's definition), so no rectangular step term.

    ``pmfs``: each direction's outcome distribution under the data's noise
    (:func:`fifty_percent_outcome_pmf`), combined by :func:`max_outcome_pmf`. u_c is its
    standard deviation (None, "above the grid", counted as the largest tested step); the
    statement is the central 95 % range of the outcome, widened to hold the value (where
    that range is one outcome, to the neighbouring outcomes that can occur) — a discrete,
    skewed distribution, stated by its interval (JCGM 101 7.7), no k (U: the distance to the
    upper end). Its coverage probability is the interval's own probability under the outcome
    distribution (whole grid steps: at least 95 %, often more), the one p every output
    states. One possible outcome (noise-free readings): u_c = U = 0 and no interval.
    Returns (Uncertainty, the combined pmf).

    >>> u, _ = rule_outcome_uncertainty([{0.1: 0.01, 0.05: 0.98, 0.02: 0.01}], 0.05)
    >>> u.interval, u.coverage_probability
    ((0.02, 0.1), 1.0)
    >>> u, _ = rule_outcome_uncertainty([{0.1: 0.02, 0.05: 0.96, 0.02: 0.01, 0.01: 0.01}], 0.05)
    >>> u.interval, round(u.coverage_probability, 4)
    ((0.02, 0.1), 0.99)

    >>> u, _ = rule_outcome_uncertainty([{0.1: 0.25, 0.05: 0.5, 0.02: 0.25}], 0.05)   # mean 0.055
    >>> round(u.u_c, 6), u.interval, round(u.U, 6), u.k
    (0.028723, (0.02, 0.1), 0.05, None)
    """
    from gonio.result.model import Uncertainty

    pmf = max_outcome_pmf(*pmfs)
    top = max(k for p in pmfs for k in p if k is not None)
    x = np.array([top if k is None else k for k in pmf], float)
    w = np.array(list(pmf.values()), float)
    w = w / w.sum()
    u_c = math.sqrt(max(float(w @ (x - w @ x) ** 2), 0.0))
    lo, hi = (outcome_quantile(pmf, q) for q in (0.025, 0.975))
    lo, hi = min(top if lo is None else lo, value), max(top if hi is None else hi, value)
    if hi == lo:             # ≥ 95 % on one outcome: reach the neighbouring possible outcomes
        lo = max((float(k) for k, p in zip(x, w) if k < lo and p > 1e-9), default=lo)
        hi = min((float(k) for k, p in zip(x, w) if k > hi and p > 1e-9), default=hi)
    row = {"symbol": "rule_outcome", "source": "spread of the 50 % rule's outcome under the "
           "data's noise (the interval: whole grid steps holding at least 95 % of it)",
           "type": "A", "u": u_c, "c": 1.0, "contribution": u_c, "dof": None}
    if hi == lo:             # one possible outcome (noise-free readings)
        return Uncertainty([row], u_c, 0.0, None, None, None, 0.95, "outcome distribution"), pmf
    # the interval's own probability under the outcome distribution: whole grid steps, so at
    # least 95 % and mostly more; stated as p in every output (certificate, summary, DCC)
    p_iv = float(w[(x >= lo - 1e-12 * abs(lo)) & (x <= hi + 1e-12 * abs(hi))].sum())
    return Uncertainty([row], u_c, hi - value, None, None, None, min(p_iv, 1.0),
                       "outcome distribution", interval=(lo, hi)), pmf


def bias_drift_u(K: float, u_K: float, B: float, u_B: float, tau_s, adev_high,
                 separation_s: float) -> float:
    """Standard uncertainty of the difference of two bias records ``separation_s`` apart, from
    the static record's noise analysis (same rate unit as ``adev_high``): rate random walk
    K√Δt and bias instability √2·0.664·B, each coefficient's square increased by its fit
    uncertainty (E[K²] = K² + u_K²).

    The Allan deviation bounds the rate random walk at every τ, σ_RRW(τ)² = K²τ/3 ≤ σ(τ)², so
    K ≤ min over τ of σ_hi(τ)·√(3/τ), σ_hi the upper confidence limit (the longest τ alone,
    with its one or two degrees of freedom, gave bounds 1–5× the tighter one on a 2-h record).
    A rate random walk the fit resolves (K > u_K: its interval does not reach 0) counts as
    K² + u_K², at most that bound squared (a fit coefficient whose uncertainty runs past the
    bound says no more than the bound); one it does not resolve (K = 0, or u_K ≥ K) is taken
    as rectangular on [0, bound] (K² = bound²/3, JCGM 100 4.3.7).

    >>> round(bias_drift_u(0.0, 0.0, 0.0, 0.0, [10.0, 300.0], [50.0, 10.0], 3600.0), 6)   # √(1/3·3600)
    34.641016
    >>> round(bias_drift_u(0.0, 0.0, 0.0, 0.0, [10.0, 300.0], [1.0, 10.0], 3600.0), 6)   # τ = 10 s
    18.973666
    >>> round(bias_drift_u(0.5, 0.1, 0.0, 0.0, [10.0, 300.0], [50.0, 10.0], 3600.0), 6)   # √(0.26·3600)
    30.594117
    >>> round(bias_drift_u(1.0, 0.5, 0.0, 0.0, [10.0, 300.0], [50.0, 10.0], 3600.0), 6)   # bound 1
    60.0
    >>> round(bias_drift_u(5.0, 9.0, 0.0, 0.0, [10.0, 300.0], [50.0, 10.0], 3600.0), 6)   # unresolved
    34.641016
    """
    k2, b2 = drift_coefficients(K, u_K, B, u_B, tau_s, adev_high)
    return math.sqrt(k2 * abs(separation_s) + 2 * FLICKER_FLOOR_EXACT ** 2 * b2)


def drift_coefficients(K: float, u_K: float, B: float, u_B: float, tau_s,
                       adev_high) -> tuple[float, float]:
    """(E[K²], E[B²]) of the rate random walk and the bias instability for a drift term, by
    the rules of :func:`bias_drift_u` (K bounded by min over τ of σ_hi(τ)·√(3/τ); a K the
    fit resolves as K² + u_K² up to that bound, one it does not as rectangular on [0,
    bound]; B² + u_B²).

    >>> [round(x, 6) for x in drift_coefficients(0.0, 0.0, 2.0, 1.0, [10.0, 300.0], [50.0, 10.0])]
    [0.333333, 5.0]
    """
    t, s = as_array(tau_s, "tau_s"), as_array(adev_high, "adev")
    def ok(x):
        return x if math.isfinite(x) else 0.0
    bound2 = float(np.min(s ** 2 * 3.0 / t))
    k, u_k = abs(ok(K)), ok(u_K)
    k2 = min(k ** 2 + u_k ** 2, bound2) if k > u_k else bound2 / 3.0
    return k2, ok(B) ** 2 + ok(u_B) ** 2


def record_difference_u(K: float, u_K: float, B: float, u_B: float, tau_s, adev_high,
                        first: tuple[float, float], second: tuple[float, float]) -> float:
    """Standard uncertainty that the rate random walk and the bias instability give the
    difference of the means of two records, ``first`` and ``second`` = (start, duration) in
    s on one time line (the white noise is in each mean's own u), with E[K²] and E[B²] of
    :func:`drift_coefficients`.

    Each record's mean is (θ(t + d) − θ(t))/d of the angle θ, so the difference is a
    combination of four angle values whose coefficients sum to zero and have zero first
    moment; its variance is Σ c_a c_b G(t_a − t_b) with the five-term model's generalised
    covariance G (:func:`gonio.analysis.noise.covariance.generalised_covariance`: flicker
    B²t² ln|t|/(2π), rate random walk K²|t|³/12). For adjacent records of length τ this is
    twice the Allan variance, 2·(2 ln 2/π)B² + 2K²τ/3 (the flicker floor :func:`bias_drift_u`
    takes at every separation); further apart the flicker part grows as ln of the separation
    (IEEE 952 C.1: a 1/f spectrum) and the walk's as K²·(separation − d/3).

    >>> round(record_difference_u(0.0, 0.0, 1.0, 0.0, [1e3], [0.0], (0.0, 60.0), (60.0, 60.0)), 6)
    0.939437
    >>> round(math.sqrt(2) * FLICKER_FLOOR_EXACT, 6)                      # adjacent: the floor
    0.939437
    """
    return record_difference_u_coef(*drift_coefficients(K, u_K, B, u_B, tau_s, adev_high),
                                    first, second)


def record_difference_u_coef(k2: float, b2: float, first: tuple[float, float],
                             second: tuple[float, float]) -> float:
    """:func:`record_difference_u` with the rate random walk's K² and the flicker's B²
    given (a specification's own rule for them, e.g. IEC 62047-20's
    :func:`gonio.specs.iec62047_20.formulas.walk_coefficient_bound`): the combination
    m₂ − m₁ of :func:`window_combination_u_coef`.

    >>> round(record_difference_u_coef(0.0, 1.0, (0.0, 60.0), (60.0, 60.0)), 6)
    0.939437
    """
    return window_combination_u_coef(k2, b2, [first, second], [-1.0, 1.0])


def window_combination_u_coef(k2: float, b2: float, windows, weights) -> float:
    """Standard uncertainty that the rate random walk (K², (unit)²/s) and the bias
    instability's flicker (B², (unit)²) give the combination Σ w_i·m_i of the bias drift's
    means m_i over the ``windows`` (start s, duration s) on one time line, e.g. a
    least-squares slope's row of (AᵀA)⁻¹Aᵀ over records whose means are regressed (the
    white noise is in each mean's own u).

    Each m_i = (θ(t_i + d_i) − θ(t_i))/d_i of the angle θ, so the combination is one of
    2n angle values whose coefficients sum to zero and whose first moment is Σ w_i; with
    Σ w_i = 0 (a combination blind to a constant bias: a difference, or a slope fitted
    with an intercept) its variance is Σ c_a c_b G(t_a − t_b) with the five-term model's
    generalised covariance G (:func:`gonio.analysis.noise.covariance.generalised_covariance`:
    flicker B²t² ln|t|/(2π), rate random walk K²|t|³/12), exact for the model. A
    combination with Σ w_i ≠ 0 sees the drift's unbounded level: refused.

    >>> round(window_combination_u_coef(1.0, 0.0, [(0.0, 1.0), (10.0, 1.0)], [-1, 1]) ** 2, 6)
    9.666667
    """
    from gonio.analysis.noise.covariance import generalised_covariance

    w = np.asarray(weights, dtype=np.float64)
    win = np.asarray(windows, dtype=np.float64).reshape(-1, 2)
    if w.size != win.shape[0]:
        raise GonioError(f"{w.size} weights for {win.shape[0]} windows")
    if np.any(win[:, 1] <= 0):
        raise GonioError(f"window durations {', '.join(f'{d:g}' for d in win[:, 1])} s: "
                         f"each must be positive")
    if abs(float(w.sum())) > 1e-9 * max(1.0, float(np.abs(w).sum())):
        raise GonioError(f"weights summing to {float(w.sum()):g}, not 0: the combination "
                         f"would see the drift's level, which no record bounds")
    pts = np.column_stack([win[:, 0], win[:, 0] + win[:, 1]]).ravel()
    c = np.column_stack([-w / win[:, 1], w / win[:, 1]]).ravel()
    lag = np.abs(pts[:, None] - pts[None, :])
    var = float(c @ generalised_covariance(lag, [0.0, 0.0, b2, k2], 1.0) @ c)
    return math.sqrt(max(var, 0.0))


#: The source text of the budgets' line for the gyro's temperature error at a chamber set point.
TEMPERATURE_BOUND_SOURCE = ("the gyro's temperature error at the set point: the chamber's "
                            "deviation (± bound) and the gyro's place in its volume (± half "
                            "the uniformity, JJF Table 2), both bounded and allowed at once, "
                            "their bounds added linearly")


def gyro_temperature_bound_c(deviation_bound_c: float, uniformity_c: float) -> float:
    """Half-width (°C) of the gyro's temperature error at a chamber set point: the chamber's
    deviation bound plus half its uniformity (JJF 1535 Table 2: ±2 °C and 2 °C; IEC 62047-20
    5.1.4.1 refers to the chamber's stated conditions). Both are bounded effects the
    procedure allows at once (the chamber at its deviation, the gyro at the volume's warm
    end), so their bounds add linearly into one rectangular line: u = (δ + U/2)/√3, not the
    quadrature √(δ² + (U/2)²)/√3 of two independent lines, which a condition with both at
    their bounds exceeds (the rate studies' worst case: IEC a_BASE covered 0.000, JJF K_t
    0.625 with the uniformity missing).

    >>> gyro_temperature_bound_c(2.0, 2.0), gyro_temperature_bound_c(2.0, 0.0)
    (3.0, 2.0)
    """
    return float(deviation_bound_c) + 0.5 * float(uniformity_c)
