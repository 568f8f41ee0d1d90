"""The five-term gyro noise model, fitted to each Allan-family variance with its own
response, parameter uncertainties by parametric bootstrap or from the covariance of the
estimates across τ (:mod:`.covariance`), and the sinusoid check.

Contents
--------
=============================  ==============================================
:func:`design_matrix`          σ² = A @ [Q², N², B², K², R²] for adev/mdev/hdev
:func:`model_deviation`        the model's deviation of one kind
:func:`fit_noise_model`        weighted non-negative LS fit -> :class:`NoiseFit`
:func:`simulate_noise`         a record of the five-term model (bootstrap, tests)
:func:`bootstrap_uncertainty`  parametric bootstrap of the fitted coefficients
:func:`detect_sinusoid`        Allan signature of a sinusoidal disturbance
=============================  ==============================================

Responses of each term (rate unit u, τ = mτ0; IEEE Std 952-1997 Annex C for AVAR;
SP 1065 Tables for the ratios; the MVAR/HVAR integrals are ours, from the filters'
transfer functions |H_A|² = 2 sin⁴(πτf)/(πτf)², |H_mod|² = |H_A|²·sin²(πτf)/(πτf)²,
|H_H|² = (8/3) sin⁶(πτf)/(πτf)², checked numerically in the tests):

=====================  ==============  ========================  ================
term                   AVAR            MVAR                      HVAR
=====================  ==============  ========================  ================
Q quantisation (α=2)   3Q²/τ²          3Q²/(m τ²)                10Q²/(3τ²)
N angle RW (α=0)       N²/τ            N²(1 + 1/m²)/(2τ)         N²/τ
B bias inst. (α=−1)    (2 ln2/π) B²    (27 ln3 − 32 ln2)/(8π) B²  (24 ln2 − 9 ln3)/(6π) B²
K rate RW (α=−2)       K²τ/3           (11/40) K²τ               K²τ/6
R rate ramp            R²τ²/2          R²τ²/2                    0
=====================  ==============  ========================  ================

Q, N and R are exact for sampled data (white phase of variance Q² per sample; rate
samples that are means of white rate noise; a linear rate); B and K are the
continuous-time (large m) forms. The total variance estimates AVAR, so ``totdev``
uses the AVAR column. The Hadamard variance does not see a rate ramp: R is not
estimable from it and is reported as NaN.

References
----------
.. [IEEE952] IEEE Std 952-1997, Annex C (C.1–C.6).
.. [SP1065] W. J. Riley, NIST SP 1065 (2008), §5.2.5 (R(n)), Table 3, §5.2.8.
.. [IEC62047] IEC 62047-20:2014, 5.4 (bias instability = floor / 0.664).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from functools import lru_cache
from typing import Sequence

import numpy as np
import pandas as pd
from scipy import optimize
from scipy.fft import next_fast_len

from gonio.analysis.noise.allan import AllanResult, allan_deviation
from gonio.analysis.noise.covariance import variance_covariance
from gonio.analysis.noise.edf import edf_for
from gonio.errors import GonioError
from gonio.units import (
    S_PER_H, deg_sqrt_h_from_dph_sqrt_hz, dph_per_sqrt_h_from_dph_sqrt_hz_per_s,
)

__all__ = [
    "TERMS", "FLICKER_COEFF", "FLICKER_FLOOR", "MVAR_FLICKER_COEFF", "HVAR_FLICKER_COEFF",
    "MVAR_RRW_COEFF", "HVAR_RRW_COEFF", "SINE_TAU_PER_PERIOD", "SINE_PEAK_PER_AMPLITUDE",
    "NoiseFit", "SinusoidDetection", "design_matrix", "model_adev", "model_deviation",
    "fit_noise_model", "simulate_noise", "bootstrap_uncertainty", "sinusoid_adev",
    "detect_sinusoid",
]

TERMS = ("Q", "N", "B", "K", "R")

#: 2 ln 2 / π, the flicker (bias-instability) coefficient of AVAR (IEEE 952 C.3).
FLICKER_COEFF = 2.0 * math.log(2.0) / math.pi
#: √(2 ln 2 / π) = 0.6643: ADEV floor of flicker rate noise per unit B (IEEE 952 C.3;
#: IEC 62047-20 5.4 quotes it rounded as 0.664).
FLICKER_FLOOR = math.sqrt(FLICKER_COEFF)
#: MVAR of flicker rate noise per B²: (27 ln 3 − 32 ln 2)/(8π) (∫ 2 sin⁶u/u⁵ du / π).
MVAR_FLICKER_COEFF = (27.0 * math.log(3.0) - 32.0 * math.log(2.0)) / (8.0 * math.pi)
#: HVAR of flicker rate noise per B²: (24 ln 2 − 9 ln 3)/(6π) ((8/3)∫ sin⁶u/u³ du / π).
HVAR_FLICKER_COEFF = (24.0 * math.log(2.0) - 9.0 * math.log(3.0)) / (6.0 * math.pi)
#: MVAR of rate random walk per K²τ: 11/40 (2π·∫ sin⁶u/u⁶ du = 11π²/20, h = K²/2π²).
MVAR_RRW_COEFF = 11.0 / 40.0
#: HVAR of rate random walk per K²τ: 1/6 ((8/3)π·∫ sin⁶u/u⁴ du = π²/3, h = K²/2π²).
HVAR_RRW_COEFF = 1.0 / 6.0
#: τ of the ADEV peak of a sinusoid, per period T (IEEE 952 C.7; [Vagner2015], docs/references.md#vagner2015).
SINE_TAU_PER_PERIOD = 0.371
#: ADEV peak of a sinusoid, per amplitude Ω (IEEE 952 C.7; [Vagner2015], docs/references.md#vagner2015).
SINE_PEAK_PER_AMPLITUDE = 0.725

#: Noise type of each term (for the edf of model-based weights).
TERM_ALPHA = np.array([2, 0, -1, -2, -2])


# --------------------------------------------------------------------- dataclasses
@dataclass
class NoiseFit:
    """Five-term model fitted to an :class:`AllanResult` (IEEE 952 Annex C).

    With rate unit ``u`` (``rate_unit``) and τ in s: ``Q`` quantisation [u·s],
    ``N`` angle random walk [u·√s], ``B`` bias instability [u], ``K`` rate random
    walk [u/√s], ``R`` rate ramp [u/s]; ``u_*`` their standard uncertainties
    (``uncertainty_method``: ``"bootstrap"`` — the spread of the coefficients refitted
    to records simulated from the fitted model — or ``"covariance"``; 0 for a term
    held at zero by the non-negativity bound, NaN if not estimable, e.g. R from the
    Hadamard variance). ``B_floor`` is the deviation minimum / 0.6643 (IEC 62047-20 5.4;
    meaningful for ADEV).
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
    residuals: np.ndarray  # (dev_obs − dev_model) / dev_model
    chi2_red: float
    active: tuple = ()
    kind: str = "adev"
    uncertainty_method: str = "covariance"
    n_bootstrap: int = 0

    def coefficients(self) -> np.ndarray:
        """The fitted variance coefficients [Q², N², B², K², R²] (NaN → 0)."""
        return np.nan_to_num(np.array([self.Q, self.N, self.B, self.K, self.R])) ** 2

    def adev(self, tau_s, tau0_s: float | None = None) -> np.ndarray:
        """Model deviation of this fit's kind at ``tau_s`` (see the module table)."""
        return model_deviation(tau_s, *np.nan_to_num([self.Q, self.N, self.B, self.K,
                                                       self.R]),
                               kind=self.kind, tau0_s=tau0_s)

    def to_dict(self) -> dict:
        """Plain dict; when ``rate_unit`` is ``deg/h`` also the customary units."""
        u = self.rate_unit or "u"
        out = {"rate_unit": self.rate_unit, "kind": self.kind,
               "uncertainty_method": self.uncertainty_method,
               "n_bootstrap": int(self.n_bootstrap),
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
                # (°/h)/s × 3600 s/h = (°/h)/h
                "rate_ramp_dph_per_h": self.R * S_PER_H,
                "u_rate_ramp_dph_per_h": self.u_R * S_PER_H})
        return {k: (None if isinstance(v, (float, np.floating)) and not np.isfinite(v)
                    else float(v) if isinstance(v, (float, np.floating)) else v)
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
    excess_sigma: float = 0.0  # largest excess of the bump over the model, in sd

    def to_dict(self) -> dict:
        """Plain dict (NaN as None)."""
        out = {}
        for k, v in asdict(self).items():
            if isinstance(v, (bool, np.bool_)):
                out[k] = bool(v)
            else:
                out[k] = float(v) if np.isfinite(v) else None
        return out


# ------------------------------------------------------------------ the responses
def design_matrix(tau_s, kind: str = "adev", tau0_s: float | None = None) -> np.ndarray:
    """Columns of the five-term model for the variance ``kind`` (module table):
    σ² = A @ [Q², N², B², K², R²].

    ``tau0_s`` is needed for the exact MVAR terms of Q and N (their 1/m factors); for
    ``adev``, ``hdev`` and ``totdev`` it is not used. IEEE 952-1997 C.1–C.6 (AVAR).

    >>> design_matrix([1.0, 2.0]).round(4)
    array([[3.    , 1.    , 0.4413, 0.3333, 0.5   ],
           [0.75  , 0.5   , 0.4413, 0.6667, 2.    ]])
    >>> design_matrix([2.0], "mdev", tau0_s=1.0).round(4)
    array([[0.375 , 0.3125, 0.2977, 0.55  , 2.    ]])
    """
    t = np.asarray(tau_s, dtype=np.float64)
    if kind in ("adev", "totdev"):
        return np.column_stack([3.0 / t ** 2, 1.0 / t, np.full_like(t, FLICKER_COEFF),
                                t / 3.0, t ** 2 / 2.0])
    if kind == "mdev":
        if tau0_s is None:
            raise GonioError("the MVAR model needs the sample interval tau0_s", key="tau0_s")
        m = t / float(tau0_s)
        return np.column_stack([3.0 / (m * t ** 2), (1.0 + 1.0 / m ** 2) / (2.0 * t),
                                np.full_like(t, MVAR_FLICKER_COEFF), MVAR_RRW_COEFF * t,
                                t ** 2 / 2.0])
    if kind == "hdev":
        return np.column_stack([10.0 / (3.0 * t ** 2), 1.0 / t,
                                np.full_like(t, HVAR_FLICKER_COEFF), HVAR_RRW_COEFF * t,
                                np.zeros_like(t)])
    raise GonioError(f"kind must be adev, mdev, hdev or totdev, not {kind!r}", key="kind")


def model_deviation(tau_s, Q=0.0, N=0.0, B=0.0, K=0.0, R=0.0, *, kind: str = "adev",
                    tau0_s: float | None = None) -> np.ndarray:
    """Deviation of the five-term model for the variance ``kind``.

    >>> float(model_deviation(4.0, N=2.0))  # N/√τ
    1.0
    >>> float(np.round(model_deviation(3.0, K=1.0), 12))  # K·sqrt(τ/3)
    1.0
    """
    coef = np.array([Q, N, B, K, R], dtype=np.float64) ** 2
    a = design_matrix(np.atleast_1d(tau_s), kind, tau0_s)
    return np.sqrt(a @ coef).reshape(np.shape(tau_s))


def model_adev(tau_s, Q=0.0, N=0.0, B=0.0, K=0.0, R=0.0) -> np.ndarray:
    """Allan deviation of the five-term model (IEEE 952 Annex C).

    >>> float(model_adev(4.0, N=2.0))
    1.0
    """
    return model_deviation(tau_s, Q, N, B, K, R, kind="adev")


# ----------------------------------------------------------------------- the fit
def sandwich_covariance(a: np.ndarray, sd: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """Covariance of the weighted least-squares coefficients when the observations have
    the full covariance ``sigma`` but were weighted by 1/sd² as if independent:
    (AᵀWA)⁻¹ AᵀWΣWA (AᵀWA)⁻¹ (the "sandwich"; Seber & Wild, Nonlinear Regression, 2.1.4)."""
    aw = a / sd[:, None] ** 2
    bread = np.linalg.inv(a.T @ aw)
    return bread @ (aw.T @ sigma @ aw) @ bread


def _dominant_alpha(a: np.ndarray, coef: np.ndarray) -> np.ndarray:
    """Noise type α of the largest model term at each τ."""
    return TERM_ALPHA[np.argmax(a * coef[None, :], axis=1)]


def wnnls(a: np.ndarray, var: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """Non-negative least squares of ``var`` ≈ ``a``·p with rows weighted by 1/``sd``
    (columns scaled to unit norm for the solver)."""
    aw = a / sd[:, None]
    cs = np.linalg.norm(aw, axis=0)
    cs[cs == 0] = 1.0
    p, _ = optimize.nnls(aw / cs, var / sd)
    return p / cs


@lru_cache(maxsize=512)
def _edf_cached(kind: str, n_phase: int, m: tuple, alpha: tuple) -> np.ndarray:
    """:func:`edf_for`, memoised (the bootstrap refits at the same m many times)."""
    out = edf_for(kind, n_phase, np.array(m), np.array(alpha))
    out.setflags(write=False)
    return out


def edf_memo(kind, n_phase, m, alpha):
    """Greenhall's edf at averaging factors ``m`` for noise types ``alpha`` (memoised)."""
    return _edf_cached(kind, int(n_phase), tuple(int(v) for v in m),
                       tuple(int(v) for v in alpha))


def _fit_core(kind, tau, var, m, n_phase, tau0, cols, iterations):
    """IRLS non-negative fit; returns (coef[5], model variance, edf)."""
    a_full = design_matrix(tau, kind, tau0)
    a = a_full[:, cols]
    model = var.copy()
    edf = edf_memo(kind, n_phase, m, np.zeros(m.size, dtype=np.int64))
    coef = np.zeros(5)
    for _ in range(max(1, iterations)):
        sd = np.maximum(model, np.finfo(float).tiny) * np.sqrt(2.0 / edf)
        p = wnnls(a, var, sd)
        coef = np.zeros(5)
        coef[cols] = p
        model = np.maximum(a_full @ coef, np.finfo(float).tiny)
        edf = edf_memo(kind, n_phase, m, _dominant_alpha(a_full, coef))
    return coef, model, edf


def fit_noise_model(allan: AllanResult, *, terms: Sequence[str] = TERMS,
                    tau_max_s: float | None = None, iterations: int = 4,
                    bootstrap: int = 0, seed: int = 0, covariance: bool = True) -> NoiseFit:
    """Weighted non-negative least-squares fit of the five-term model to the variance
    of ``allan`` with that variance's own responses (:func:`design_matrix`:
    AVAR for overlapping and total, MVAR for modified, HVAR for Hadamard).

    Unknowns p = [Q², N², B², K², R²] ≥ 0, solved with ``scipy.optimize.nnls`` on rows
    weighted by 1/sd(σ̂²), sd = σ²_model·√(2/edf) (χ² variance of a variance estimate,
    SP 1065 §5.3.4), iteratively re-weighted with the model's σ² and the Greenhall
    edf at the noise type of the model's dominant term (IEEE 952-1997 Annex C).

    Uncertainties: with ``bootstrap`` = B > 0, a parametric bootstrap — B records of
    the fitted model (:func:`simulate_noise`, same τ0, length and input), each
    analysed and refitted the same way; u is the standard deviation of the refitted
    coefficients (it carries the correlation of the estimates across τ and the
    non-negativity bound). Otherwise the covariance of the weighted LS coefficients of
    the active terms with the full covariance Σ of the variance estimates across τ
    under the fitted model (:func:`gonio.analysis.noise.covariance.variance_covariance`:
    neighbouring τ share most of their data), (AᵀWA)⁻¹AᵀWΣWA(AᵀWA)⁻¹, scaled by
    max(1, χ²_red) for a model that does not fit; u of a coefficient is u(p)/(2√p)
    (``uncertainty_method`` says which was used; ``covariance=False`` skips it: u = 0,
    for refits that only need the values). Only the ``terms`` named are fitted.

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
    unknown = [t for t in terms if t not in TERMS]
    if unknown or not terms:
        raise GonioError(f"terms must be a non-empty subset of {TERMS}, got {list(terms)}",
                         key="terms")
    kind = allan.kind
    sel = np.isfinite(allan.adev) & (allan.adev > 0)
    if tau_max_s is not None:
        sel &= allan.tau_s <= tau_max_s
    tau = np.asarray(allan.tau_s[sel], dtype=np.float64)
    var = np.asarray(allan.adev[sel], dtype=np.float64) ** 2
    m = np.asarray(allan.m[sel], dtype=np.int64)
    cols = [TERMS.index(t) for t in terms]
    if kind == "hdev" and TERMS.index("R") in cols:
        cols.remove(TERMS.index("R"))  # the Hadamard variance does not see a ramp
    if tau.size < len(cols):
        raise GonioError(f"{tau.size} usable τ values cannot determine {len(cols)} terms",
                         key="taus")
    n_phase = allan.n_phase or (allan.n_samples + (0 if allan.input_type == "angle" else 1))
    tau0 = float(allan.tau0_s)
    coef, model, edf = _fit_core(kind, tau, var, m, n_phase, tau0, cols, iterations)
    a_full = design_matrix(tau, kind, tau0)
    sd = model * np.sqrt(2.0 / edf)
    resid_w = (var - model) / sd
    active = [i for i in cols if coef[i] > 0]
    dof = max(tau.size - len(active), 1)
    chi2_red = float(resid_w @ resid_w / dof)
    values = np.sqrt(coef)
    u_vals = np.zeros(5)
    method = "covariance"
    if bootstrap > 0:
        u_vals = bootstrap_uncertainty(allan, values, terms=terms, tau_max_s=tau_max_s,
                                       n_boot=bootstrap, seed=seed, iterations=iterations)
        method = "bootstrap"
    elif active and covariance:
        try:
            rows = covariance_rows(tau)
            sigma = _estimate_covariance(allan, np.flatnonzero(sel)[rows], kind, m[rows],
                                         tau0, coef, sd[rows])
            cov = (sandwich_covariance(a_full[np.ix_(rows, active)], sd[rows], sigma)
                   * max(1.0, chi2_red))
            u_coef = np.sqrt(np.clip(np.diag(cov), 0, None))
            u_vals[active] = u_coef / (2.0 * values[active])
        except np.linalg.LinAlgError:
            u_vals[active] = np.nan
    if kind == "hdev":
        values[4] = np.nan
        u_vals[4] = np.nan
    dev_sel = np.asarray(allan.adev[sel], dtype=np.float64)
    i_floor = int(np.argmin(dev_sel))
    return NoiseFit(*values, *u_vals,
                    B_floor=float(dev_sel[i_floor] / FLICKER_FLOOR),
                    tau_floor_s=float(tau[i_floor]), rate_unit=allan.unit,
                    tau_s=tau, residuals=np.sqrt(var) / np.sqrt(model) - 1.0,
                    chi2_red=chi2_red, active=tuple(TERMS[i] for i in active),
                    kind=kind, uncertainty_method=method, n_bootstrap=int(bootstrap))


#: At most this many τ enter the covariance of the fit's uncertainties (a log-spaced subset
#: of a denser set, e.g. every τ: neighbouring estimates then carry almost the same data).
_COV_MAX_TAUS = 64


def covariance_rows(tau: np.ndarray) -> np.ndarray:
    """Indices of the τ whose estimates enter the covariance (all, or a log-spaced subset
    of :data:`_COV_MAX_TAUS`)."""
    if tau.size <= _COV_MAX_TAUS:
        return np.arange(tau.size)
    grid = np.geomspace(tau[0], tau[-1], _COV_MAX_TAUS)
    return np.unique(np.clip(np.searchsorted(tau, grid), 0, tau.size - 1))


def _estimate_covariance(allan: AllanResult, sel, kind: str, m, tau0: float, coef,
                         sd: np.ndarray) -> np.ndarray:
    """Σ of the fitted variance estimates under the model ``coef`` (module
    :mod:`.covariance`); for the total and the modified variance the overlapping Allan
    variance's correlation (the modified variance's dense terms make its own cost grow as
    m²; its correlations are the smaller) scaled to the Greenhall variances ``sd``² of the
    fit's weights."""
    n_terms = np.asarray(allan.n_pairs[sel], dtype=np.int64)
    sigma = variance_covariance("hdev" if kind == "hdev" else "adev", m, n_terms, tau0, coef)
    if kind in ("totdev", "mdev"):
        d = np.sqrt(np.clip(np.diag(sigma), np.finfo(float).tiny, None))
        sigma = sigma / np.outer(d, d) * np.outer(sd, sd)
    return sigma


# ---------------------------------------------------------------- simulation
def _flicker_shape(nf: int, ntot: int, tau0_s: float, h: float) -> np.ndarray:
    """The flicker spectrum's amplitude √(h/f·ntot/(4τ0))·sinc(fτ0) at bins 1..nf−1 of an
    ``ntot``-point record (f = k/(ntot τ0), rfftfreq's), built piece by piece with the
    same operations per element as the whole-array form."""
    shape = np.empty(nf - 1)
    val = 1.0 / (ntot * tau0_s)               # rfftfreq's spacing
    for a in range(1, nf, _SYNTH_PIECE):
        e = min(nf, a + _SYNTH_PIECE)
        f = np.arange(a, e) * val
        shape[a - 1:e - 1] = np.sqrt(h / f * ntot / (4.0 * tau0_s)) * np.sinc(f * tau0_s)
    return shape


def _flicker_rate(rng, n: int, tau0_s: float, b: float, cache: dict | None = None,
                  add_to: np.ndarray | None = None) -> np.ndarray:
    """Rate samples (means over τ0) of flicker rate noise with AVAR (2 ln2/π)B²:
    one-sided PSD h/f, h = B²/π (IEEE 952 C.3), synthesised in the frequency domain
    on a record at least 4× longer than asked (the 1/f shape holds well below the
    record length; the length is the next 5-smooth one, ``scipy.fft.next_fast_len``:
    an FFT of a length with a large prime factor is 20× slower) and cut; each sample
    is the mean of the continuous process over τ0 (the sinc² of the averaging is
    applied). ``cache``: a dict that keeps the spectrum's shape for further records of
    the same length, τ0 and B (the draws differ, the shape does not). ``add_to``: an
    array of n rates the samples are added to (and returned) instead of a new one."""
    if b == 0:
        return np.zeros(n) if add_to is None else add_to
    ntot = next_fast_len(4 * n, real=True)
    nf = ntot // 2 + 1
    # Built piece by piece in place (the spectrum is 4× the record: whole-array
    # temporaries would dominate a long record's memory). The same draws in the same
    # order and the same operations per element as the whole-array form
    # ``(x + 1j·y)·√(h/f·ntot/(4τ0))·sinc(fτ0)``, f = numpy.fft.rfftfreq(ntot, τ0).
    spec = np.empty(nf, dtype=np.complex128)
    piece = np.empty(min(nf, _SYNTH_PIECE))
    for part in (spec.real, spec.imag):
        for a in range(0, nf, _SYNTH_PIECE):
            e = min(nf, a + _SYNTH_PIECE)
            rng.standard_normal(out=piece[: e - a])
            part[a:e] = piece[: e - a]
    del piece
    spec[0] = 0.0
    key = (nf, ntot, float(tau0_s), float(b))
    shape = None if cache is None else cache.get(key)
    if shape is None:
        shape = _flicker_shape(nf, ntot, tau0_s, b * b / math.pi)
        if cache is not None:             # a bootstrap's replicates share one shape
            cache.clear()
            cache[key] = shape
    spec[1:] *= shape
    del shape
    x = np.fft.irfft(spec, ntot)
    del spec
    if add_to is not None:
        add_to += x[:n]
        return add_to
    out = x[:n].copy()                        # not a view keeping the 4× record alive
    return out


#: Spectrum bins handled at a time by :func:`_flicker_rate`.
_SYNTH_PIECE = 1 << 18


def simulate_noise(n: int, tau0_s: float, Q=0.0, N=0.0, B=0.0, K=0.0, R=0.0, *,
                   rng=None, input_type: str = "rate", cache: dict | None = None
                   ) -> np.ndarray:
    """A record of the five-term model (rate unit u, τ0 in s), as rate samples
    (each the mean rate over its interval) or, with ``input_type="angle"``, the
    integrated angle (u·s, n + 1 points).

    White phase of sd Q on the angle; white rate of sd N/√τ0; flicker rate
    (:func:`_flicker_rate`); rate random walk with increments of sd K·√τ0; rate ramp
    R·t. These are the processes whose responses :func:`design_matrix` lists (IEEE
    952-1997 Annex C). ``cache``: see :func:`_flicker_rate` (the same numbers with or
    without it).
    """
    rng = np.random.default_rng(rng)
    # Each term is added piece by piece (a long record's memory is the record, not one
    # record per operation); the same draws in the same order and the same operations
    # per element as y = N/√τ0·z1 + flicker + K√τ0·cumsum(z2) + Rτ0·(k + ½) + diff(Q·z3)/τ0.
    # For an angle record the rates are built in place of the angles x[1:] (one array).
    x = np.zeros(n + 1) if input_type != "rate" else None
    y = np.zeros(n) if x is None else x[1:]
    step = _SYNTH_PIECE
    buf = np.empty(min(n, step) + 1)
    if N:
        c = N / math.sqrt(tau0_s)
        for a in range(0, n, step):
            z = buf[: min(n, a + step) - a]
            rng.standard_normal(out=z)
            z *= c
            y[a: a + z.size] += z
    if B:
        _flicker_rate(rng, n, tau0_s, B, cache, add_to=y)
    if K:
        c, carry = K * math.sqrt(tau0_s), 0.0
        for a in range(0, n, step):
            z = buf[: min(n, a + step) - a]
            rng.standard_normal(out=z)
            if a:
                z[0] += carry                 # the running sum continues across pieces
            np.cumsum(z, out=z)
            carry = float(z[-1])
            z *= c
            y[a: a + z.size] += z
    if R:
        c = R * tau0_s
        for a in range(0, n, step):
            z = np.arange(a, min(n, a + step), dtype=np.float64)
            z += 0.5
            z *= c
            y[a: a + z.size] += z
    if Q:
        rng.standard_normal(out=buf[:1])
        buf[0] *= Q
        for a in range(0, n, step):
            k = min(n, a + step) - a
            q = buf[: k + 1]
            rng.standard_normal(out=q[1:])
            q[1:] *= Q
            d = np.subtract(q[1:], q[:-1])
            d /= tau0_s
            y[a: a + k] += d
            buf[0] = q[k]
    del buf
    if input_type == "rate":
        return y
    y *= tau0_s
    np.cumsum(y, out=y)
    return x


def bootstrap_uncertainty(allan: AllanResult, values, *, terms: Sequence[str] = TERMS,
                          tau_max_s: float | None = None, n_boot: int = 40, seed: int = 0,
                          iterations: int = 4) -> np.ndarray:
    """Standard uncertainties of [Q, N, B, K, R] by parametric bootstrap: ``n_boot``
    rate records of the model ``values`` with the τ0 and length of ``allan``'s record
    (:func:`simulate_noise`), each analysed at the same m with the same estimator
    and refitted (:func:`fit_noise_model` without bootstrap); u = sample standard
    deviation of the refitted values (Efron & Tibshirani 1993, ch. 6). Seeded:
    the same inputs give the same u."""
    values = np.nan_to_num(np.asarray(values, dtype=np.float64))
    rng = np.random.default_rng(seed)
    n = int(allan.n_samples if allan.input_type != "angle" else allan.n_samples - 1)
    tau0 = float(allan.tau0_s)
    out = np.empty((n_boot, 5))
    shapes: dict = {}                       # the flicker spectrum's shape, built once
    for b in range(n_boot):
        # the record as angles (its rates integrated in place) analysed in place: one
        # record-length array in memory, not two (the mean rate removed by the rate path
        # and the end-to-end line removed here are the same detrending)
        x = None                            # the last record is freed before the next
        x = simulate_noise(n, tau0, *values, rng=rng, input_type="angle", cache=shapes)
        r = allan_deviation(x, tau0, "angle", allan.m.astype(np.int64), kind=allan.kind,
                            alpha=0, unit=allan.unit, overwrite_data=True)
        del x
        r.alpha = allan.alpha
        f = fit_noise_model(r, terms=terms, tau_max_s=tau_max_s, iterations=iterations,
                            covariance=False)
        out[b] = np.nan_to_num([f.Q, f.N, f.B, f.K, f.R])
    u = out.std(axis=0, ddof=1)
    return u


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
    τ ≈ 0.371 T). Candidates are local maxima of σ_obs/σ_model whose excess variance
    exceeds ``threshold`` standard deviations of σ̂² (sd from the Greenhall edf at
    the noise type of the model's dominant term: the null hypothesis). The candidate
    is refined: for trial periods around τ_peak/0.371, the model's columns plus the
    sinusoid's are fitted by weighted NNLS and the T with the smallest weighted
    residual is kept; Ω follows from its coefficient. Overlapping/total ADEV only
    (the sinusoid's response is the AVAR one); other kinds return "not detected".

    Examples
    --------
    >>> tau = np.geomspace(1, 1000, 61)
    >>> dev = np.sqrt(sinusoid_adev(tau, 200.0, 2.0) ** 2 + (0.1 / np.sqrt(tau)) ** 2)
    >>> r = AllanResult(tau, dev, np.arange(1, 62), np.full(61, 10**5), np.full(61, 1e3),
    ...                 np.zeros(61, int), dev, dev, "rate", "overlapping", 1.0, 10**5, 0.683)
    >>> d = detect_sinusoid(r, fit_noise_model(r, terms=("N",)))
    >>> d.detected, round(d.period_s), round(d.amplitude, 2)
    (True, 200, 2.0)
    """
    if allan.kind not in ("adev", "totdev"):
        return SinusoidDetection(False)
    if fit is None:
        fit = fit_noise_model(allan)
    sel = np.isfinite(allan.adev) & (allan.adev > 0)
    tau = np.asarray(allan.tau_s[sel], dtype=np.float64)
    dev = np.asarray(allan.adev[sel], dtype=np.float64)
    # under the null hypothesis (the noise model alone) the edf is the model's: noise
    # type of its dominant term at each τ (not the identification, which a sinusoid
    # itself disturbs)
    n_phase = allan.n_phase or (allan.n_samples + (0 if allan.input_type == "angle" else 1))
    edf = edf_memo(allan.kind, n_phase, np.asarray(allan.m[sel]),
               _dominant_alpha(design_matrix(tau, allan.kind, allan.tau0_s),
                               fit.coefficients()))
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
