"""Allan deviation and the five-term gyro noise model.

Contents
--------
=============================  ==============================================
:func:`angle_series`           rate / increment / angle input -> angle series
:func:`averaging_factors`      the τ sets "octave", "decade:N", "all"
:func:`allan_deviation`        overlapping (or modified) ADEV with χ² CIs
:func:`edf_simple`             equivalent degrees of freedom (SP 1065 Tab. 5)
:func:`design_matrix`          the five-term AVAR model, one column per term
:func:`fit_noise_model`        weighted non-negative LS fit -> :class:`NoiseFit`
:func:`detect_sinusoid`        Allan signature of a sinusoidal disturbance
:func:`analyse_static`         draft 7.3 static record: ADEV + fit + sinusoid
:func:`analyse_record`         the same for any input type (used by the CLI)
:func:`plot_fit`               ADEV, model and residuals (matplotlib, Agg)
unit helpers                   °/√h, (°/h)/√Hz, ″/√s, rad/s/√Hz, °/h, rad/s
=============================  ==============================================

The input type is always an explicit argument (never guessed):

* ``"rate"``      -- rate samples (e.g. °/h), each the mean rate over one interval τ0;
* ``"increment"`` -- angle increments per sample (e.g. counts per sample), divided by
  ``scale`` (e.g. counts/°) to give an angle;
* ``"angle"``     -- the integrated angle (e.g. cumulative counts or degrees), divided by
  ``scale``.

Everything is computed from the angle (phase) series ``x`` (IEEE 952-1997 Annex C,
IEEE 1554-2005 Annex; NIST SP 1065 eq. 11): with ``m`` samples per cluster,
``σ²(mτ0) = Σ (x[n+2m] − 2x[n+m] + x[n])² / (2 (mτ0)² (N−2m))``. For a rate input
the Allan deviation is in the input's rate unit; for increment and angle inputs it
is in (angle unit)/s.

References
----------
.. [IEEE952] IEEE Std 952-1997, Annex C (Allan variance, noise terms).
.. [IEEE1554] IEEE Std 1554-2005, Annex (overlapping estimator).
.. [SP1065] W. J. Riley, NIST SP 1065 (2008), eq. 11, eq. 14, Table 5.
.. [IEC62047] IEC 62047-20:2014, 5.4 (bias instability = floor / 0.664).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, asdict
from pathlib import Path
from typing import Sequence

import numpy as np
import pandas as pd
from scipy import fft as sfft
from scipy import optimize, stats

from gonio.errors import GonioError
from gonio.units import deg_sqrt_h_from_dph_sqrt_hz, dph_per_sqrt_h_from_dph_sqrt_hz_per_s, dph_to_dps, h_to_s

__all__ = [
    "INPUT_TYPES", "AllanResult", "NoiseFit", "SinusoidDetection", "StaticNoiseResult",
    "angle_series", "averaging_factors", "allan_deviation", "edf_simple",
    "design_matrix", "fit_noise_model", "model_adev", "detect_sinusoid",
    "sinusoid_adev", "analyse_static", "analyse_record", "plot_fit",
]

#: The accepted input types (see module docstring).
INPUT_TYPES = ("rate", "increment", "angle")

#: 2 ln 2 / π, the flicker (bias-instability) coefficient of AVAR (IEEE 952 C.3).
FLICKER_COEFF = 2.0 * math.log(2.0) / math.pi
#: sqrt(2 ln 2 / π) = 0.664: ADEV floor of flicker rate noise per unit B (IEC 62047-20 5.4).
FLICKER_FLOOR = math.sqrt(FLICKER_COEFF)
#: τ of the ADEV peak of a sinusoid, per period T (IEEE 952 C.7; [Vagner2015], docs/references.md#vagner2015).
SINE_TAU_PER_PERIOD = 0.371
#: ADEV peak of a sinusoid, per amplitude Ω (IEEE 952 C.7; [Vagner2015], docs/references.md#vagner2015).
SINE_PEAK_PER_AMPLITUDE = 0.725

_BLOCK = 1 << 16  # samples per chunk of the direct O(N) sums (keeps temporaries small)
_BLOCK_SHARED = 1 << 13  # chunk of the chunk-outside loop (:func:`_sums_direct_shared`)


# --------------------------------------------------------------------- dataclasses
@dataclass
class AllanResult:
    """Allan deviation versus averaging time, with χ² confidence intervals.

    ``adev`` is in ``unit`` (the rate unit of the input, or angle unit per second),
    ``tau_s`` in seconds; ``edf`` the equivalent degrees of freedom used for the
    interval ``[ci_low, ci_high]`` at level ``confidence``; ``alpha`` the noise type
    (power-law exponent of the rate PSD) assumed for the edf at each τ.
    """

    tau_s: np.ndarray
    adev: np.ndarray
    m: np.ndarray
    n_pairs: np.ndarray
    edf: np.ndarray
    alpha: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray
    input_type: str
    method: str
    tau0_s: float
    n_samples: int
    confidence: float
    unit: str = ""

    def to_frame(self) -> pd.DataFrame:
        """One row per τ: tau_s, m, adev, n_pairs, edf, alpha, ci_low, ci_high."""
        return pd.DataFrame({"tau_s": self.tau_s, "m": self.m, "adev": self.adev,
                             "n_pairs": self.n_pairs, "edf": self.edf, "alpha": self.alpha,
                             "ci_low": self.ci_low, "ci_high": self.ci_high})

    def to_dict(self) -> dict:
        """Plain, JSON-ready dict (lists of floats)."""
        return {"input_type": self.input_type, "method": self.method,
                "tau0_s": float(self.tau0_s), "n_samples": int(self.n_samples),
                "confidence": float(self.confidence), "unit": self.unit,
                "tau_s": [float(v) for v in self.tau_s],
                "adev": [float(v) for v in self.adev],
                "m": [int(v) for v in self.m],
                "n_pairs": [int(v) for v in self.n_pairs],
                "edf": [float(v) for v in self.edf],
                "alpha": [int(v) for v in self.alpha],
                "ci_low": [float(v) for v in self.ci_low],
                "ci_high": [float(v) for v in self.ci_high]}


@dataclass
class NoiseFit:
    """Five-term AVAR model fitted to an :class:`AllanResult` (IEEE 952 Annex C).

    With rate unit ``u`` (``rate_unit``) and τ in s: ``Q`` quantisation [u·s],
    ``N`` angle random walk [u·√s], ``B`` bias instability [u], ``K`` rate random
    walk [u/√s], ``R`` rate ramp [u/s]; ``u_*`` their standard uncertainties (0 for
    a term held at zero by the non-negativity bound, NaN if not estimable).
    ``B_floor`` is the ADEV minimum / 0.664 (IEC 62047-20 5.4).
    """

    Q: float
    N: float
    B: float
    K: float
    R: float
    u_Q: float
    u_N: float
    u_B: float
    u_K: float
    u_R: float
    B_floor: float
    tau_floor_s: float
    rate_unit: str
    tau_s: np.ndarray
    residuals: np.ndarray  # (adev_obs − adev_model) / adev_model
    chi2_red: float
    active: tuple = ()

    def coefficients(self) -> np.ndarray:
        """The fitted variance coefficients [Q², N², B², K², R²]."""
        return np.array([self.Q, self.N, self.B, self.K, self.R]) ** 2

    def adev(self, tau_s) -> np.ndarray:
        """Model Allan deviation at ``tau_s`` (IEEE 952 C.1-C.6)."""
        return model_adev(tau_s, self.Q, self.N, self.B, self.K, self.R)

    def to_dict(self) -> dict:
        """Plain dict; when ``rate_unit`` is ``deg/h`` also the customary units."""
        u = self.rate_unit or "u"
        out = {"rate_unit": self.rate_unit,
               "Q": self.Q, "u_Q": self.u_Q, "Q_unit": f"{u}*s",
               "N": self.N, "u_N": self.u_N, "N_unit": f"{u}*sqrt(s)",
               "B": self.B, "u_B": self.u_B, "B_unit": u,
               "K": self.K, "u_K": self.u_K, "K_unit": f"{u}/sqrt(s)",
               "R": self.R, "u_R": self.u_R, "R_unit": f"{u}/s",
               "B_floor": self.B_floor, "tau_floor_s": self.tau_floor_s,
               "chi2_red": self.chi2_red, "active": list(self.active),
               "tau_s": [float(v) for v in self.tau_s],
               "residuals": [float(v) for v in self.residuals]}
        if self.rate_unit == "deg/h":
            out.update({
                "quantisation_arcsec": self.Q,  # 1 (°/h)·s = 1″
                "arw_deg_sqrt_h": deg_sqrt_h_from_dph_sqrt_hz(self.N),
                "u_arw_deg_sqrt_h": deg_sqrt_h_from_dph_sqrt_hz(self.u_N),
                "bias_instability_dph": self.B, "u_bias_instability_dph": self.u_B,
                "bias_instability_floor_dph": self.B_floor,
                "rrw_dph_sqrt_h": dph_per_sqrt_h_from_dph_sqrt_hz_per_s(self.K),
                "u_rrw_dph_sqrt_h": dph_per_sqrt_h_from_dph_sqrt_hz_per_s(self.u_K),
                "rate_ramp_dph_per_h": h_to_s(self.R),
                "u_rate_ramp_dph_per_h": h_to_s(self.u_R)})
        return {k: (float(v) if isinstance(v, (float, np.floating)) else v)
                for k, v in out.items()}

    def to_frame(self) -> pd.DataFrame:
        """One row per term: term, symbol, value, u, unit."""
        u = self.rate_unit or "u"
        rows = [("quantisation", "Q", self.Q, self.u_Q, f"{u}*s"),
                ("angle random walk", "N", self.N, self.u_N, f"{u}*sqrt(s)"),
                ("bias instability", "B", self.B, self.u_B, u),
                ("rate random walk", "K", self.K, self.u_K, f"{u}/sqrt(s)"),
                ("rate ramp", "R", self.R, self.u_R, f"{u}/s")]
        return pd.DataFrame(rows, columns=["term", "symbol", "value", "u", "unit"])


@dataclass
class SinusoidDetection:
    """A bump of the ADEV not explained by the noise model (IEEE 952 C.7)."""

    detected: bool
    period_s: float = math.nan
    amplitude: float = math.nan  # in the rate unit of the ADEV
    tau_peak_s: float = math.nan
    excess_sigma: float = 0.0  # largest excess of the bump over the model, in CI half-widths

    def to_dict(self) -> dict:
        """Plain dict."""
        return {k: (bool(v) if isinstance(v, (bool, np.bool_)) else float(v))
                for k, v in asdict(self).items()}


@dataclass
class StaticNoiseResult:
    """Result of :func:`analyse_static` (draft 7.3 static record)."""

    allan: AllanResult
    fit: NoiseFit
    sinusoid: SinusoidDetection
    tau0_s: float
    duration_s: float

    def to_dict(self) -> dict:
        """Plain, JSON-ready dict."""
        return {"tau0_s": float(self.tau0_s), "duration_s": float(self.duration_s),
                "allan": self.allan.to_dict(), "fit": self.fit.to_dict(),
                "sinusoid": self.sinusoid.to_dict()}


# ------------------------------------------------------------------- angle series
def angle_series(data, input_type: str, tau0_s: float, scale: float = 1.0) -> np.ndarray:
    """The angle (phase) series ``x`` from which every Allan statistic is computed.

    ``rate``: ``x = [0, cumsum(y − ȳ)]·τ0`` (N+1 points, unit rate·s);
    ``increment``: ``x = [0, cumsum(d/scale − mean)]`` (N+1 points);
    ``angle``: ``x = a/scale`` minus the straight line through its end points
    (N points). Removing the mean rate (equivalently a linear ramp of ``x``) is exact
    for the Allan and modified Allan variances, whose second differences cancel a
    ramp (IEEE 952 C.1; SP 1065 eq. 11), and keeps the cumulative sums small so that
    long records lose no precision.

    >>> angle_series([1.0, 3.0, 2.0], "rate", 0.5)
    array([ 0. , -0.5,  0. ,  0. ])
    >>> angle_series([0, 10, 30, 30], "angle", 1.0, scale=10.0)
    array([0., 0., 1., 0.])
    """
    if input_type not in INPUT_TYPES:
        raise GonioError(f"input type must be one of {', '.join(INPUT_TYPES)}, "
                         f"not {input_type!r}", key="input_type")
    tau0_s = float(tau0_s)
    if not (math.isfinite(tau0_s) and tau0_s > 0):
        raise GonioError(f"sample interval tau0_s must be > 0, not {tau0_s}", key="tau0_s")
    scale = float(scale)
    if not (math.isfinite(scale) and scale != 0):
        raise GonioError(f"scale must be finite and non-zero, not {scale}", key="scale")
    arr = np.asarray(data)
    if arr.ndim != 1:
        raise GonioError(f"data must be one-dimensional, got shape {arr.shape}", key="data")
    if arr.size < 3:
        raise GonioError(f"need at least 3 samples, got {arr.size}", key="data")
    try:
        arr = arr.astype(np.float64, copy=False)
    except (TypeError, ValueError) as exc:
        raise GonioError(f"data must be numeric ({exc})", key="data") from None
    if not np.isfinite(arr).all():
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise GonioError(f"data contains a non-finite value at index {bad}", key="data")
    if input_type == "angle":
        a = arr / scale if scale != 1.0 else arr.copy()
        n = a.size
        a0, a1 = a[0], a[-1]
        ramp = np.arange(n, dtype=np.float64)
        ramp *= (a1 - a0) / (n - 1)
        ramp += a0
        a -= ramp
        return a
    y = arr / scale if (input_type == "increment" and scale != 1.0) else arr
    mean = float(np.mean(y, dtype=np.float64))
    x = np.empty(y.size + 1, dtype=np.float64)
    x[0] = 0.0
    np.subtract(y, mean, out=x[1:])
    np.cumsum(x[1:], out=x[1:])
    if input_type == "rate":
        x *= tau0_s
    return x


def _unscaled_rate_phase(data) -> np.ndarray | None:
    """[0, cumsum(y − ȳ)] for a float64 rate input (τ0 applied later), else None."""
    arr = np.asarray(data)
    if arr.dtype != np.float64 or arr.ndim != 1 or arr.size < 3:
        return None
    mean = float(np.mean(arr))
    if not math.isfinite(mean):
        return None  # let angle_series name the bad sample
    x = np.empty(arr.size + 1, dtype=np.float64)
    x[0] = 0.0
    np.subtract(arr, mean, out=x[1:])
    np.cumsum(x[1:], out=x[1:])
    return x


def averaging_factors(n_phase: int, taus="octave", *, modified: bool = False) -> np.ndarray:
    """Cluster sizes m (τ = m·τ0) for a phase series of ``n_phase`` points.

    ``"octave"``: m = 1, 2, 4, …; ``"decade:N"``: N log-spaced per decade, rounded
    to unique integers; ``"all"``: every m. The largest m leaves at least one
    second difference: m ≤ (n−1)/2 (ADEV, SP 1065 eq. 11) or (n−1)/3 (MDEV, eq. 14).
    An explicit sequence of integers is accepted as given (validated).

    >>> averaging_factors(100, "octave")
    array([ 1,  2,  4,  8, 16, 32])
    >>> averaging_factors(100, "decade:3")
    array([ 1,  2,  5, 10, 22, 46])
    >>> averaging_factors(10, "all", modified=True)
    array([1, 2, 3])
    """
    m_max = (n_phase - 1) // (3 if modified else 2)
    if m_max < 1:
        raise GonioError(f"record too short: {n_phase} angle samples", key="data")
    if isinstance(taus, str):
        spec = taus.strip().lower()
        if spec == "octave":
            ms = 2 ** np.arange(int(math.floor(math.log2(m_max))) + 1)
        elif spec == "all":
            ms = np.arange(1, m_max + 1)
        elif spec.startswith("decade:"):
            try:
                per = int(spec.split(":", 1)[1])
            except ValueError:
                per = 0
            if per < 1:
                raise GonioError(f"τ set {taus!r}: 'decade:N' needs an integer N >= 1",
                                 key="taus")
            k = np.arange(int(math.floor(per * math.log10(m_max) + 1e-9)) + 1)
            ms = np.unique(np.round(10.0 ** (k / per)).astype(np.int64))
        else:
            raise GonioError(f"τ set must be 'octave', 'decade:N' or 'all', not {taus!r}",
                             key="taus")
        return ms[(ms >= 1) & (ms <= m_max)].astype(np.int64)
    ms = np.asarray(taus)
    if ms.ndim != 1 or ms.size == 0 or not np.all(ms == np.round(ms)):
        raise GonioError("explicit averaging factors must be a 1-D sequence of integers",
                         key="taus")
    ms = np.unique(ms.astype(np.int64))
    if ms[0] < 1 or ms[-1] > m_max:
        raise GonioError(f"averaging factors must lie in 1..{m_max}", key="taus")
    return ms


# ----------------------------------------------------------------- core sums (O(N))
def _sum_sq_second_diff(x: np.ndarray, m: int, buf: np.ndarray) -> float:
    """Σ (x[n+2m] − 2x[n+m] + x[n])², n = 0 … N−2m−1, in chunks (SP 1065 eq. 11).

    For m up to the chunk length the lag-m first differences D[n] = x[n+m] − x[n]
    of a chunk (plus m) are formed once and the second difference is D[n+m] − D[n]
    (two passes); for larger m the three terms are combined directly (three).
    ``buf`` must hold at least 2·min(_BLOCK, N) values.
    """
    n = x.size
    length = n - 2 * m
    total = 0.0
    for s in range(0, length, _BLOCK):
        e = min(length, s + _BLOCK)
        k = e - s
        if m <= _BLOCK:
            d1 = buf[: k + m]
            np.subtract(x[s + m: e + 2 * m], x[s: e + m], out=d1)
            v = buf[k + m: 2 * k + m]
            np.subtract(d1[m:], d1[:k], out=v)
        else:
            v = buf[:k]
            np.subtract(x[s + 2 * m: e + 2 * m], x[s + m: e + m], out=v)
            np.subtract(v, x[s + m: e + m], out=v)
            np.add(v, x[s:e], out=v)
        total += float(np.dot(v, v))
    return total


def _sums_direct(x: np.ndarray, ms) -> np.ndarray:
    """:func:`_sum_sq_second_diff` for each m in ``ms`` (one shared chunk buffer)."""
    buf = np.empty(3 * min(_BLOCK, x.size))
    return np.array([_sum_sq_second_diff(x, int(m), buf) for m in ms], dtype=np.float64)


def _sums_direct_shared(x: np.ndarray, ms) -> np.ndarray:
    """The same sums with the loops swapped: chunks outside, m inside.

    For a set like the octaves the data a chunk needs for one m (x at n, n+m,
    n+2m) is largely what the next m needs, so each chunk of ``x`` comes from main
    memory about once for all m, instead of once per m (the sums are bound by memory
    bandwidth). Small chunks (_BLOCK_SHARED) keep the working set in cache.
    Per m the arithmetic, and therefore the result, is that of
    :func:`_sum_sq_second_diff` with chunks of _BLOCK_SHARED.
    """
    ms = [int(m) for m in ms]
    n = x.size
    bsz = min(_BLOCK_SHARED, n)
    buf = np.empty(3 * bsz)
    total = np.zeros(len(ms))
    lengths = [n - 2 * m for m in ms]
    order = sorted(range(len(ms)), key=lambda i: ms[i])
    sub, add, dot = np.subtract, np.add, np.dot
    for s in range(0, max(lengths), bsz):
        for i in order:
            m, length = ms[i], lengths[i]
            if s >= length:
                break
            e = min(length, s + bsz)
            k = e - s
            if m <= bsz:
                d1 = buf[: k + m]
                sub(x[s + m: e + 2 * m], x[s: e + m], out=d1)
                v = buf[k + m: 2 * k + m]
                sub(d1[m:], d1[:k], out=v)
            else:
                v = buf[:k]
                mid = x[s + m: e + m]
                sub(x[s + 2 * m: e + 2 * m], mid, out=v)
                sub(v, mid, out=v)
                add(v, x[s:e], out=v)
            total[i] += float(dot(v, v))
    return total


def _sum_sq_mod(x: np.ndarray, m: int) -> float:
    """Σ_j (Σ_{i=j}^{j+m−1} x[i+2m] − 2x[i+m] + x[i])², j = 0 … N−3m (SP 1065 eq. 14).

    The second differences are formed first (small numbers), then their moving sum
    of length m by a cumulative sum, so nothing large is ever subtracted.
    """
    n = x.size
    e = x[2 * m:] - x[m: n - m]
    e -= x[m: n - m]
    e += x[: n - 2 * m]
    c = np.empty(e.size + 1)
    c[0] = 0.0
    np.cumsum(e, out=c[1:])
    w = c[m:] - c[:-m]
    return float(np.dot(w, w))


def _triangular_corr(x: np.ndarray, m_max: int) -> np.ndarray:
    """G[m] = Σ_{k<m} x[k]·x[k+m] for m = 0 … m_max, in O(M log² M).

    Divide and conquer over the triangle k < m: on a block [a, a+w) the rectangle
    k ∈ [a, a+w/2), m ∈ [a+w/2, a+w) is a plain cross-correlation (FFT, batched over
    all blocks of one level); the two half triangles recurse. Blocks of 8 are summed
    directly.
    """
    w = 8
    while w < m_max + 1:
        w *= 2
    width = w
    xp = np.zeros(2 * width + 1)
    take = min(x.size, xp.size)
    xp[:take] = x[:take]
    out = np.zeros(width)
    while w > 8:
        h = w // 2
        nf = sfft.next_fast_len(3 * h, real=True)  # linear correlation, lags 0…h−1
        nb = width // w
        per = max(1, (width // 4) // nf)  # blocks per batch: temporaries ≲ width/4
        for b0 in range(0, nb, per):
            a = np.arange(b0, min(nb, b0 + per)) * w
            u = xp[a[:, None] + np.arange(h)[None, :]]
            spec = sfft.rfft(xp[(2 * a + h)[:, None] + np.arange(2 * h - 1)[None, :]],
                             nf, axis=1)
            uspec = sfft.rfft(u, nf, axis=1)
            del u
            spec *= np.conj(uspec, out=uspec)
            del uspec
            c = sfft.irfft(spec, nf, axis=1)
            del spec
            out[(a + h)[:, None] + np.arange(h)[None, :]] += c[:, :h]
            del c
        w = h
    # base triangles of width 8: k < m inside each block
    nb = width // 8
    kk, mm = np.triu_indices(8, 1)
    per = 1 << 12  # blocks per batch, bounded temporaries
    for b0 in range(0, nb, per):
        a = np.arange(b0, min(nb, b0 + per)) * 8
        prod = xp[a[:, None] + kk[None, :]] * xp[2 * a[:, None] + kk[None, :] + mm[None, :]]
        np.add.at(out, (a[:, None] + mm[None, :]).ravel(), prod.ravel())
    return out[: m_max + 1]


def _sum_sq_all(x: np.ndarray, ms: np.ndarray, rtol: float) -> np.ndarray:
    """Σ of squared second differences for every m in ``ms`` (ascending, all m).

    SP 1065 eq. 11 with the square expanded (our derivation, checked in the tests
    against the direct sums and allantools): with L = N−2m, P₀ = Σ_{n<L} x[n]²,
    P₁ = Σ_{m≤n<m+L} x[n]², P₂ = Σ_{2m≤n<N} x[n]² (prefix sums of x²), the full
    autocorrelation A[k] = Σ x[n]x[n+k] (one FFT) and the triangular partial
    correlations G[m] = Σ_{k<m} x[k]x[k+m] of ``x`` and of ``x`` reversed
    (:func:`_triangular_corr`, for the ends the lag-m products miss):
    Σd² = P₂ + 4P₁ + P₀ − 4(A[m] − G_rev[m]) − 4(A[m] − G[m]) + 2A[2m].
    This cancels large terms, so each m whose estimated rounding error
    (≈ 64·ε·log₂N·Σx²) exceeds ``rtol``·Σd² is recomputed directly (O(N) each);
    these are the small m and the m close to N/2 (few terms, short direct sums).
    """
    n = x.size
    m_max = int(ms[-1])
    nfft = sfft.next_fast_len(2 * n, real=True)
    spec = sfft.rfft(x, nfft)
    power = np.square(spec.real)
    power += np.square(spec.imag)
    del spec
    full = sfft.irfft(power, nfft)
    del power
    m = ms
    a_m, a_2m = full[m], full[2 * m]
    del full
    q = np.empty(n + 1)
    q[0] = 0.0
    np.cumsum(np.square(x), out=q[1:])
    length = n - 2 * m
    s = q[length] + 4 * (q[m + length] - q[m]) + (q[n] - q[2 * m])
    err = 64.0 * np.finfo(float).eps * math.log2(nfft) * q[n]
    del q
    s += 2 * a_2m - 8 * a_m
    s += 4 * _triangular_corr(x, m_max)[m]
    s += 4 * _triangular_corr(x[::-1], m_max)[m]
    # doubtful: the small m (large Σx² relative to Σd²) and the m near N/2 (few
    # terms, so the direct sum is short): both are cheap to recompute directly
    redo = np.flatnonzero(~(s > err / rtol))
    if redo.size:
        s[redo] = _sums_direct(x, m[redo])
    return s


# ---------------------------------------------------------------------- edf and CI
def edf_simple(n_phase: int, m, alpha) -> np.ndarray:
    """Equivalent degrees of freedom of the overlapping AVAR, noise-type aware.

    NIST SP 1065 (2008) Table 5 (Howe, Allan & Barnes 1981; the simple
    approximations, not the full Greenhall & Riley 2003 algorithm), with
    ``n_phase`` phase points, cluster size m and α the exponent of the rate
    (frequency) PSD: +2 white phase (quantisation), +1 flicker phase, 0 white rate
    (angle random walk), −1 flicker rate (bias instability), −2 random-walk rate.
    The result is limited below by 1.

    >>> float(np.round(edf_simple(1000, 10, 0), 3))
    146.029
    >>> float(np.round(edf_simple(1000, 10, -2), 3))
    97.232
    """
    n = float(n_phase)
    m = np.asarray(m, dtype=np.float64)
    alpha = np.broadcast_to(np.asarray(alpha), m.shape)
    edf = np.full(m.shape, np.nan)
    a2 = alpha == 2
    edf[a2] = (n + 1) * (n - 2 * m[a2]) / (2 * (n - m[a2]))
    a1 = alpha == 1
    with np.errstate(invalid="ignore", divide="ignore"):
        la = np.log((n - 1) / (2 * m[a1]))
        lb = np.log((2 * m[a1] + 1) * (n - 1) / 4)
        edf[a1] = np.exp(np.sqrt(np.clip(la * lb, 0, None)))
    a0 = alpha == 0
    edf[a0] = ((3 * (n - 1) / (2 * m[a0]) - 2 * (n - 2) / n)
               * 4 * m[a0] ** 2 / (4 * m[a0] ** 2 + 5))
    am1 = alpha == -1
    mm = m[am1]
    edf[am1] = np.where(mm == 1, 2 * (n - 2) ** 2 / (2.3 * n - 4.9),
                        5 * n ** 2 / (4 * mm * (n + 3 * mm)))
    am2 = alpha == -2
    mm = m[am2]
    edf[am2] = (n - 2) / mm * ((n - 1) ** 2 - 3 * mm * (n - 1) + 4 * mm ** 2) / (n - 3) ** 2
    if np.isnan(edf).any():
        raise GonioError("noise exponent alpha must be one of 2, 1, 0, -1, -2", key="alpha")
    return np.maximum(edf, 1.0)


def _alpha_from_slope(tau: np.ndarray, dev: np.ndarray) -> np.ndarray:
    """Power-law noise type α at each τ from the local log-log slope μ/2 of the
    deviation: α = −μ − 1, rounded and limited to [−2, 2] (SP 1065 5.2.2, Table 3)."""
    if tau.size < 2:
        return np.zeros(tau.size, dtype=np.int64)
    lt, ld = np.log(tau), np.log(np.maximum(dev, np.finfo(float).tiny))
    slope = np.gradient(ld, lt)
    if slope.size >= 3:  # light smoothing, the estimates are noisy at long τ
        slope = np.convolve(np.pad(slope, 1, mode="edge"), np.ones(3) / 3, mode="valid")
    alpha = np.clip(np.round(-2 * slope - 1), -2, 2)
    return alpha.astype(np.int64)


def _chi2_interval(var, edf, confidence):
    """χ² interval of a variance with ``edf`` degrees of freedom (SP 1065 5.3.4)."""
    lo_q = stats.chi2.ppf((1 + confidence) / 2, edf)
    hi_q = stats.chi2.ppf((1 - confidence) / 2, edf)
    return var * edf / lo_q, var * edf / hi_q


# -------------------------------------------------------------------- public ADEV
def allan_deviation(data, tau0_s: float, input_type: str, taus="octave", *,
                    scale: float = 1.0, modified: bool = False,
                    confidence: float = 0.683, alpha=None, unit: str = "",
                    rtol_all: float = 1e-6) -> AllanResult:
    """Overlapping (or modified) Allan deviation with χ² confidence intervals.

    Overlapping ADEV: ``σ²(mτ0) = Σ (x[n+2m] − 2x[n+m] + x[n])² / (2 m²τ0² (N−2m))``
    (IEEE 952-1997 Annex C, IEEE 1554-2005; SP 1065 eq. 11). Modified ADEV
    (``modified=True``, SP 1065 eq. 14) averages the second differences over m
    consecutive starts. ``x`` is :func:`angle_series` of the data; each τ costs O(N)
    in vectorised, chunked sums. ``taus="all"`` (ADEV) uses the correlation
    expansion of :func:`_sum_sq_all` — O(N log² N) for every m at once — with the
    small m recomputed directly until the estimated relative rounding error is below
    ``rtol_all``. The modified ADEV with ``"all"`` is O(N) per m (slow for long records).

    Confidence intervals: χ² with edf from :func:`edf_simple` (SP 1065 Table 5);
    ``alpha`` (noise type) is given, or estimated at each τ from the local slope.

    Parameters
    ----------
    data : array_like
        Samples; meaning set by ``input_type`` (``rate``, ``increment``, ``angle``).
    tau0_s : float
        Sample interval τ0, s.
    input_type : str
        ``"rate"``, ``"increment"`` or ``"angle"`` — never guessed.
    taus : str or sequence of int
        ``"octave"``, ``"decade:N"``, ``"all"`` or explicit cluster sizes m.
    scale : float
        Increment/angle units per angle unit (e.g. counts/°); ignored for rate.
    modified : bool
        Modified Allan deviation instead of the overlapping one.
    confidence : float
        Level of the χ² interval (default 0.683).
    alpha : int or array of int, optional
        Noise type for the edf; estimated from the slope when omitted.
    unit : str
        Label of the ADEV unit, e.g. ``"deg/h"``.

    Examples
    --------
    Alternating rate ±1 (°/h) at 1 s: at τ = 1 s the cluster means differ by 2,
    σ² = 2²/2 = 2; at τ = 2 s they are all 0.

    >>> r = allan_deviation([1.0, -1.0] * 8, 1.0, "rate", taus=[1, 2], alpha=0)
    >>> [round(float(v), 6) for v in r.adev]
    [1.414214, 0.0]
    """
    if not (0 < float(confidence) < 1):
        raise GonioError(f"confidence must be in (0, 1), not {confidence}", key="confidence")
    factor = 1.0
    x = None
    if input_type == "rate" and float(tau0_s) > 0:
        # one pass less: the phase is τ0·x, applied to the deviation at the end
        x = _unscaled_rate_phase(data)
        factor = float(tau0_s)
    if x is None:
        x = angle_series(data, input_type, tau0_s, scale)
        factor = 1.0
    n = x.size
    ms = averaging_factors(n, taus, modified=modified)
    all_requested = isinstance(taus, str) and taus.strip().lower() == "all"
    if modified:
        sums = np.array([_sum_sq_mod(x, int(m)) for m in ms])
        n_terms = n - 3 * ms + 1
    elif all_requested and ms.size > 64:
        sums = _sum_sq_all(x, ms, rtol_all)
        n_terms = n - 2 * ms
    else:
        sums = _sums_direct_shared(x, ms)
        n_terms = n - 2 * ms
    tau = ms * float(tau0_s)
    if modified:
        var = sums / (2.0 * ms.astype(float) ** 2 * tau ** 2 * n_terms)
    else:
        var = sums / (2.0 * tau ** 2 * n_terms)
    var = np.maximum(var, 0.0) * factor ** 2
    dev = np.sqrt(var)
    if alpha is None:
        alpha_arr = _alpha_from_slope(tau, dev)
    else:
        alpha_arr = np.broadcast_to(np.asarray(alpha, dtype=np.int64), ms.shape).copy()
    edf = edf_simple(n, ms, alpha_arr)
    lo, hi = _chi2_interval(var, edf, float(confidence))
    return AllanResult(tau_s=tau, adev=dev, m=ms, n_pairs=n_terms, edf=edf,
                       alpha=alpha_arr, ci_low=np.sqrt(lo), ci_high=np.sqrt(hi),
                       input_type=input_type,
                       method="modified" if modified else "overlapping",
                       tau0_s=float(tau0_s), n_samples=int(np.asarray(data).size),
                       confidence=float(confidence), unit=unit)


# ------------------------------------------------------------------ noise model
_TERMS = ("Q", "N", "B", "K", "R")


def design_matrix(tau_s) -> np.ndarray:
    """Columns of the five-term AVAR model, IEEE 952-1997 Annex C (C.1–C.6):

    ``σ²(τ) = 3Q²/τ² + N²/τ + (2 ln2/π) B² + K² τ/3 + R² τ²/2``, so
    ``σ² = A @ [Q², N², B², K², R²]``.

    >>> design_matrix([1.0, 2.0]).round(4)
    array([[3.    , 1.    , 0.4413, 0.3333, 0.5   ],
           [0.75  , 0.5   , 0.4413, 0.6667, 2.    ]])
    """
    t = np.asarray(tau_s, dtype=np.float64)
    return np.column_stack([3.0 / t ** 2,           # quantisation Q
                            1.0 / t,                # angle random walk N
                            np.full_like(t, FLICKER_COEFF),  # bias instability B
                            t / 3.0,                # rate random walk K
                            t ** 2 / 2.0])          # rate ramp R


def model_adev(tau_s, Q=0.0, N=0.0, B=0.0, K=0.0, R=0.0) -> np.ndarray:
    """Allan deviation of the five-term model (IEEE 952 Annex C).

    >>> float(model_adev(4.0, N=2.0))  # N/√τ
    1.0
    >>> float(np.round(model_adev(3.0, K=1.0), 12))  # K·sqrt(τ/3)
    1.0
    """
    coef = np.array([Q, N, B, K, R], dtype=np.float64) ** 2
    return np.sqrt(design_matrix(np.atleast_1d(tau_s)) @ coef).reshape(np.shape(tau_s))


def _dominant_alpha(tau: np.ndarray, coef: np.ndarray) -> np.ndarray:
    """Noise type α of the largest model term at each τ (Q→+2, N→0, B→−1, K,R→−2)."""
    parts = design_matrix(tau) * coef[None, :]
    return np.array([2, 0, -1, -2, -2])[np.argmax(parts, axis=1)]


#: Assumed correlation of overlapping ADEV estimates one octave apart (see below).
RHO_OCTAVE = 0.6


def _correlation_inflation(tau: np.ndarray) -> float:
    """Variance factor (1+ρ)/(1−ρ) for correlated neighbouring τ estimates.

    Overlapping Allan variances at neighbouring τ share data and are positively
    correlated; a least-squares covariance that treats them as independent is too
    small. We take an AR(1) correlation along log₂τ with ρ = RHO_OCTAVE^(Δlog₂τ)
    (Δ the median spacing; ρ ≈ 0.6 one octave apart — our empirical reading,
    checked by the fit-coverage tests over seeds) and inflate the covariance by the
    long-run variance factor (1+ρ)/(1−ρ): 4 for octave spacing, more for denser sets.
    """
    if tau.size < 2:
        return 1.0
    step = float(np.median(np.diff(np.log2(tau))))
    rho = RHO_OCTAVE ** max(step, 1e-6)
    return (1.0 + rho) / (1.0 - rho)


def fit_noise_model(allan: AllanResult, *, terms: Sequence[str] = _TERMS,
                    tau_max_s: float | None = None, iterations: int = 4) -> NoiseFit:
    """Weighted non-negative least-squares fit of the five-term AVAR model.

    Model and design matrix: :func:`design_matrix` (IEEE 952-1997 Annex C; thesis
    004 of related-standards). Unknowns p = [Q², N², B², K², R²] ≥ 0, solved with
    ``scipy.optimize.nnls`` on rows weighted by 1/sd(σ̂²), sd(σ̂²) = σ²·sqrt(2/edf)
    (χ² variance of a variance estimate, SP 1065 5.3.4). The weights use the model's
    σ² (iteratively re-weighted, starting from the observed one) and the edf is
    re-evaluated with the noise type of the model's dominant term at each τ.
    Uncertainties: covariance (AᵀWA)⁻¹ of the *active* (non-zero) parameters at the
    solution, scaled by max(1, χ²_red) and by :func:`_correlation_inflation` for
    the correlation of overlapping estimates at neighbouring τ; u(N) = u(N²)/(2N)
    etc. Only the
    ``terms`` named are fitted (others held at 0).

    Examples
    --------
    An exact white-rate-noise curve σ = 0.5/√τ recovers N = 0.5:

    >>> tau = 2.0 ** np.arange(8)
    >>> r = AllanResult(tau, 0.5 / np.sqrt(tau), tau.astype(int), 1000 - 2 * tau,
    ...                 np.full(8, 100.0), np.zeros(8, int), tau, tau, "rate",
    ...                 "overlapping", 1.0, 1000, 0.683)
    >>> f = fit_noise_model(r)
    >>> round(float(f.N), 6), round(float(f.B), 6), round(float(f.K), 6)
    (0.5, 0.0, 0.0)
    """
    unknown = [t for t in terms if t not in _TERMS]
    if unknown or not terms:
        raise GonioError(f"terms must be a non-empty subset of {_TERMS}, got {list(terms)}",
                         key="terms")
    sel = np.isfinite(allan.adev) & (allan.adev > 0)
    if tau_max_s is not None:
        sel &= allan.tau_s <= tau_max_s
    tau = allan.tau_s[sel]
    var = allan.adev[sel] ** 2
    edf = allan.edf[sel]
    cols = [_TERMS.index(t) for t in terms]
    if tau.size < len(cols):
        raise GonioError(f"{tau.size} usable τ values cannot determine {len(cols)} terms",
                         key="taus")
    a_full = design_matrix(tau)
    a = a_full[:, cols]
    n_phase = allan.n_samples + (0 if allan.input_type == "angle" else 1)
    model = var.copy()
    coef = np.zeros(5)
    for _ in range(max(1, iterations)):
        sd = model * np.sqrt(2.0 / edf)
        aw = a / sd[:, None]
        bw = var / sd
        # column scaling so that the solver sees O(1) columns
        cscale = np.linalg.norm(aw, axis=0)
        cscale[cscale == 0] = 1.0
        p, _ = optimize.nnls(aw / cscale, bw)
        p = p / cscale
        coef = np.zeros(5)
        coef[cols] = p
        model = np.maximum(a_full @ coef, np.finfo(float).tiny)
        edf = edf_simple(n_phase, allan.m[sel], _dominant_alpha(tau, coef))
    sd = model * np.sqrt(2.0 / edf)
    aw = a_full / sd[:, None]
    resid_w = (var - model) / sd
    active = [i for i in cols if coef[i] > 0]
    dof = max(tau.size - len(active), 1)
    chi2_red = float(resid_w @ resid_w / dof)
    u_coef = np.zeros(5)
    if active:
        sub = aw[:, active]
        try:
            cov = (np.linalg.inv(sub.T @ sub) * max(1.0, chi2_red)
                   * _correlation_inflation(tau))
            u_coef[active] = np.sqrt(np.clip(np.diag(cov), 0, None))
        except np.linalg.LinAlgError:
            u_coef[active] = np.nan
    values = np.sqrt(coef)
    with np.errstate(divide="ignore", invalid="ignore"):
        u_vals = np.where(coef > 0, u_coef / (2.0 * np.where(values > 0, values, 1.0)), 0.0)
    i_floor = int(np.argmin(allan.adev[sel]))
    return NoiseFit(*values, *u_vals,
                    B_floor=float(allan.adev[sel][i_floor] / FLICKER_FLOOR),
                    tau_floor_s=float(tau[i_floor]), rate_unit=allan.unit,
                    tau_s=tau, residuals=np.sqrt(var) / np.sqrt(model) - 1.0,
                    chi2_red=chi2_red, active=tuple(_TERMS[i] for i in active))


# --------------------------------------------------------------------- sinusoid
def sinusoid_adev(tau_s, period_s: float, amplitude: float) -> np.ndarray:
    """Allan deviation of a rate sinusoid Ω·sin(2πt/T) (IEEE 952-1997 C.7):

    ``σ(τ) = Ω · sin²(πτ/T) / (πτ/T)``; its maximum ≈ 0.725 Ω at τ ≈ 0.371 T.

    >>> t = np.linspace(0.01, 2, 20000)
    >>> s = sinusoid_adev(t, 1.0, 1.0)
    >>> round(float(t[np.argmax(s)]), 3), round(float(s.max()), 3)
    (0.371, 0.725)
    """
    u = math.pi * np.asarray(tau_s, dtype=np.float64) / period_s
    return amplitude * np.sin(u) ** 2 / u


def detect_sinusoid(allan: AllanResult, fit: NoiseFit | None = None, *,
                    threshold: float = 3.0) -> SinusoidDetection:
    """Find a bump of the ADEV not explained by the noise model (IEEE 952 C.7).

    A sinusoidal rate disturbance of amplitude Ω and period T adds
    ``Ω² sin⁴(πτ/T)/(πτ/T)²`` to the Allan variance (peak σ ≈ 0.725 Ω at
    τ ≈ 0.371 T, [Vagner2015]). Candidates are local maxima of σ_obs/σ_model whose
    excess variance exceeds ``threshold`` standard deviations of σ̂² (sd from the
    edf). The candidate is then refined: for trial periods around
    τ_peak/0.371, the model's five columns plus the sinusoid's column are fitted by
    weighted NNLS and the T with the smallest weighted residual is kept; Ω follows
    from its coefficient.

    Examples
    --------
    A pure sinusoid's exact ADEV (no noise) is found with its period and amplitude:

    >>> tau = np.geomspace(1, 1000, 61)
    >>> dev = np.sqrt(sinusoid_adev(tau, 200.0, 2.0) ** 2 + (0.1 / np.sqrt(tau)) ** 2)
    >>> r = AllanResult(tau, dev, np.arange(1, 62), np.full(61, 10**5), np.full(61, 1e3),
    ...                 np.zeros(61, int), dev, dev, "rate", "overlapping", 1.0, 10**5, 0.683)
    >>> d = detect_sinusoid(r, fit_noise_model(r, terms=("N",)))
    >>> d.detected, round(d.period_s), round(d.amplitude, 2)
    (True, 200, 2.0)
    """
    if fit is None:
        fit = fit_noise_model(allan)
    sel = np.isfinite(allan.adev) & (allan.adev > 0)
    tau, dev, edf = allan.tau_s[sel], allan.adev[sel], allan.edf[sel]
    model = np.maximum(fit.adev(tau), np.finfo(float).tiny)
    sd = np.maximum(model, dev) ** 2 * np.sqrt(2.0 / edf)
    excess = (dev ** 2 - model ** 2) / sd
    ratio = dev / model
    if tau.size < 3:
        return SinusoidDetection(False)
    inner = np.arange(1, tau.size - 1)
    peak = inner[(ratio[inner] >= ratio[inner - 1]) & (ratio[inner] >= ratio[inner + 1])]
    peak = peak[excess[peak] > threshold]
    if peak.size == 0:
        return SinusoidDetection(False, excess_sigma=float(max(excess.max(), 0.0)))
    i = int(peak[np.argmax(excess[peak])])
    t_guess = tau[i] / SINE_TAU_PER_PERIOD
    var = dev ** 2
    a_noise = design_matrix(tau)
    best = None
    for period in t_guess * np.geomspace(0.6, 1.6, 121):
        col = sinusoid_adev(tau, period, 1.0) ** 2
        a = np.column_stack([a_noise, col]) / sd[:, None]
        cs = np.linalg.norm(a, axis=0)
        cs[cs == 0] = 1.0
        p, rnorm = optimize.nnls(a / cs, var / sd)
        if best is None or rnorm < best[0]:
            best = (rnorm, period, math.sqrt(p[-1] / cs[-1]))
    _, period, amp = best
    return SinusoidDetection(True, period_s=float(period), amplitude=float(amp),
                             tau_peak_s=float(SINE_TAU_PER_PERIOD * period),
                             excess_sigma=float(excess[i]))


# ----------------------------------------------------------------- static record
def analyse_static(time_s, angle_deg, *, taus="octave", modified: bool = False,
                   confidence: float = 0.683, tau_max_s: float | None = None,
                   sinusoid_threshold: float = 3.0) -> StaticNoiseResult:
    """Noise analysis of a static (zero-stability) record, draft 7.3.

    The angle record (degrees, uniformly sampled, instrument at rest) is analysed as
    an ``angle`` input: overlapping ADEV in °/h (IEEE 952 Annex C), the five-term
    fit (:func:`fit_noise_model`) and the sinusoid check (:func:`detect_sinusoid`).
    The sample interval is the mean time step; a record whose steps differ from it
    by more than 1 % is rejected (the Allan estimators assume uniform sampling).

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> t = np.arange(20000) * 0.1
    >>> rate_dph = 0.05 * rng.standard_normal(t.size) / np.sqrt(0.1)  # N = 0.05 (°/h)√s
    >>> angle = np.cumsum(rate_dph) * 0.1 / 3600.0
    >>> r = analyse_static(t, angle)
    >>> r.allan.unit, bool(abs(r.fit.N - 0.05) < 0.005)
    ('deg/h', True)
    """
    t = np.asarray(time_s, dtype=np.float64)
    a = np.asarray(angle_deg, dtype=np.float64)
    if t.ndim != 1 or a.shape != t.shape:
        raise GonioError(f"time_s and angle_deg must be 1-D of equal length, got "
                         f"{t.shape} and {a.shape}", key="angle_deg")
    if t.size < 8:
        raise GonioError(f"need at least 8 samples, got {t.size}", key="time_s")
    dt = np.diff(t)
    if not np.all(np.isfinite(dt)) or np.any(dt <= 0):
        bad = int(np.flatnonzero(~(dt > 0))[0]) + 1
        raise GonioError(f"time must be strictly increasing (sample {bad})", key="time_s")
    tau0 = float((t[-1] - t[0]) / (t.size - 1))
    if np.max(np.abs(dt - tau0)) > 0.01 * tau0:
        raise GonioError("sampling is not uniform (a step differs from the mean by >1 %)",
                         key="time_s")
    # 1° = 3600 (°/h)·s, so with scale 1/3600 the ADEV comes out in °/h
    return analyse_record(a, tau0, "angle", scale=dph_to_dps(1.0), unit="deg/h", taus=taus,
                          modified=modified, confidence=confidence, tau_max_s=tau_max_s,
                          sinusoid_threshold=sinusoid_threshold)


def analyse_record(data, tau0_s: float, input_type: str, *, scale: float = 1.0,
                   unit: str = "", taus="octave", modified: bool = False,
                   confidence: float = 0.683, tau_max_s: float | None = None,
                   sinusoid_threshold: float = 3.0) -> StaticNoiseResult:
    """ADEV (:func:`allan_deviation`), five-term fit (:func:`fit_noise_model`) and
    sinusoid check (:func:`detect_sinusoid`) of a uniformly sampled record
    (IEEE 952-1997 Annex C). The building block of :func:`analyse_static` and of
    ``gonio noise``.

    >>> rng = np.random.default_rng(2)
    >>> r = analyse_record(0.3 * rng.standard_normal(50000), 1.0, "rate", unit="deg/h")
    >>> bool(abs(r.fit.N - 0.3) < 0.03), r.sinusoid.detected
    (True, False)
    """
    allan = allan_deviation(data, tau0_s, input_type, taus, scale=scale, modified=modified,
                            confidence=confidence, unit=unit)
    fit = fit_noise_model(allan, tau_max_s=tau_max_s)
    sine = detect_sinusoid(allan, fit, threshold=sinusoid_threshold)
    n = allan.n_samples
    return StaticNoiseResult(allan=allan, fit=fit, sinusoid=sine, tau0_s=float(tau0_s),
                             duration_s=float(tau0_s) * (n - 1 if input_type == "angle" else n))


def plot_fit(allan: AllanResult, fit: NoiseFit | None = None, path=None):
    """Log-log ADEV with CI bars, the fitted model and its terms, and residuals.

    Uses matplotlib's Agg backend (no display). Returns the figure; writes it to
    ``path`` (atomically, format from the suffix) when given.

    >>> tau = 2.0 ** np.arange(6)
    >>> r = AllanResult(tau, 1 / np.sqrt(tau), tau.astype(int), 100 - 2 * tau,
    ...                 np.full(6, 50.0), np.zeros(6, int), 0.9 / np.sqrt(tau),
    ...                 1.1 / np.sqrt(tau), "rate", "overlapping", 1.0, 100, 0.683)
    >>> len(plot_fit(r, fit_noise_model(r)).axes)
    2
    """
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 6))
    ax, axr = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    yerr = np.vstack([allan.adev - allan.ci_low, allan.ci_high - allan.adev])
    ax.errorbar(allan.tau_s, allan.adev, yerr=yerr, fmt="o", ms=3, label=allan.method)
    if fit is not None:
        tt = np.geomspace(allan.tau_s[0], allan.tau_s[-1], 200)
        ax.plot(tt, fit.adev(tt), "k-", label="model")
        names = ("Q", "N", "B", "K", "R")
        coef = fit.coefficients()
        for j, name in enumerate(names):
            if coef[j] > 0:
                ax.plot(tt, np.sqrt(design_matrix(tt)[:, j] * coef[j]), "--", lw=0.8,
                        label=name)
        axr.semilogx(fit.tau_s, 100 * fit.residuals, "o", ms=3)
        axr.axhline(0, color="k", lw=0.5)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylabel(f"σ(τ) [{allan.unit}]" if allan.unit else "σ(τ)")
    ax.legend(fontsize=7)
    axr.set_xlabel("τ [s]")
    axr.set_ylabel("residual [%]")
    fig.tight_layout()
    if path is not None:
        from gonio.atomic import save_figure
        save_figure(fig, path)
    return fig
