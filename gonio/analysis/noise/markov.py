"""The noise model with a bias instability of realistic shape: the five terms of
:mod:`.fit` with the flat flicker floor replaced by a *band-limited* flicker — a dense sum of
first-order Gauss–Markov (exponentially correlated) rate terms from a lower correlation
time T_lo up — with T_lo fitted: the angle random walk read without the flat floor's bias.

Why
---
The five-term model (IEEE 952-1997 Annex C; JJF 1535 formula (25)) makes the bias
instability's Allan variance the constant (2 ln 2/π) B² at every τ: flicker rate noise over
an unbounded band. A gyro's bias instability is band-limited: below the correlation time of
its fastest component its Allan variance falls (as τ, like a rate random walk). Fitted with
a flat B, the missing short-τ variance is traded against N (and a spurious Q > 0): on the
virtual bench's ADXRS610 (a sum of 11 Gauss–Markov processes, 0.5 s … 29 525 s) the fit of
the exact expected Allan variance of the JJF built-in static record gives N 0.28 % low,
0.9 of u(N) on a 2-h record.

Model
-----
σ²(τ) = 3Q²/τ² + N²/τ + B²·b(τ; T_lo) + K²τ/3 + R²τ²/2, where B²·b is the Allan variance of
Gauss–Markov terms of variance s² = B² ln r/π at T_j = T_lo·r^j (r = 10^{1/4}) up to 10⁴
record lengths: their one-sided density sums to ≈ B²/(π f) (flicker, IEEE 952 C.3) between
1/(2π T_hi) and 1/(2π T_lo), so b → 2 ln 2/π (the flat floor) for T_lo ≪ τ ≪ T_hi and falls
as τ below T_lo. Each Gauss–Markov term of variance s² and correlation time T has the Allan
variance (IEEE 952-1997 Annex C, exponentially correlated noise, q² = 2s²/T)

    (q²T²/τ)·[1 − (T/2τ)(3 − 4e^{−τ/T} + e^{−2τ/T})]                (:func:`markov_avar`).

T_lo is profiled on a grid (τ0·10^{j/4} up to a tenth of the record, and T_lo = 0, the
flat floor: the five-term model is one candidate), each candidate fitted by the weighted
non-negative least squares of :func:`.fit.fit_noise_model` (same weights and iteration),
and the candidate of least weighted residual sum is taken; a T_lo > 0 is then refined
between its grid neighbours (bounded Brent search in ln T_lo, :data:`REFINE_XATOL`): N moves
with T_lo where the bias instability dominates the short τ, and a grid-bound T_lo read N
0.43 % low on the bench's exact curve with 4.5 times its bias instability (refined:
+0.05 %). One amplitude and one band edge:
a free amplitude per correlation time would be degenerate with N (a Gauss–Markov term much
shorter than τ is white) and, held ≥ 0, bias N low on noisy records.

u(N) (and u_Q, u_B, u_K, u_R) is the sandwich covariance of :func:`.fit.fit_noise_model`
with the covariance Σ of the Allan estimates under the fitted model
(:func:`.covariance.variance_covariance` with its Gauss–Markov terms; Σ computed on the lag
grid can be slightly indefinite and is replaced by its nearest positive semi-definite
matrix), scaled by max(1, χ²_red), with the band edge as one more parameter of the
linearised fit (the model's derivative in ln T_lo as a column of the design): N and T_lo
trade against each other, and u(N) carries it.

The discrete choice of T_lo is also stated, not added: ``u_N_selection`` is the spread of N
over the grid's candidates weighted by exp(−Δχ²/2) of their generalised residual sums
under Σ (a model average, :func:`_selection_spread`). Added to u(N) it made the intervals
over-wide on simulated bench records (the docs' coverage study of N): the linearised
T_lo column already carries the band edge's uncertainty.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from gonio.analysis.noise.allan import AllanResult
from gonio.analysis.noise.covariance import variance_covariance
from gonio.analysis.noise.fit import (
    FLICKER_COEFF, TERMS, covariance_rows, edf_memo, sandwich_covariance, TERM_ALPHA, wnnls,
    design_matrix,
)
from gonio.errors import GonioError

__all__ = ["markov_avar", "band_flicker_avar", "band_correlation_times", "t_lo_grid",
           "MarkovFit", "fit_markov_model"]


def markov_avar(tau_s, s2: float, tc_s: float) -> np.ndarray:
    """Allan variance of a first-order Gauss–Markov rate of variance ``s2`` and
    correlation time ``tc_s`` (IEEE 952-1997 Annex C, exponentially correlated noise):
    (q²T²/τ)[1 − (T/2τ)(3 − 4e^{−τ/T} + e^{−2τ/T})], q² = 2s²/T.

    >>> round(float(markov_avar(1e6, 1.0, 1.0)) * 1e6, 4)   # τ ≫ T: white, 2s²T/τ
    2.0
    >>> round(float(markov_avar(1e-4, 1.0, 1.0)) / (2 * 1e-4 / 3), 4)   # τ ≪ T: q²τ/3
    0.9999
    """
    t = np.asarray(tau_s, dtype=np.float64)
    x = t / float(tc_s)
    # the bracket is x²/3 − x³/4 + … for small x: its series avoids the cancellation
    big = 1.0 - (3.0 - 4.0 * np.exp(-x) + np.exp(-2.0 * x)) / (2.0 * np.maximum(x, 1e-300))
    small = x * x / 3.0 - x ** 3 / 4.0 + 7.0 * x ** 4 / 60.0
    bracket = np.where(x < 1e-3, small, big)
    return 2.0 * float(s2) * float(tc_s) / t * bracket


#: Ratio of neighbouring correlation times of the band-limited flicker (fine: no ripple).
BAND_RATIO = 10.0 ** 0.25
#: The band's upper correlation time, in record lengths (beyond: flat over any record).
BAND_TOP_RECORDS = 1.0e4


def band_correlation_times(t_lo_s: float, record_s: float) -> np.ndarray:
    """T_j = T_lo·r^j, r = :data:`BAND_RATIO`, up to :data:`BAND_TOP_RECORDS` record lengths."""
    n = int(math.ceil(math.log(BAND_TOP_RECORDS * record_s / t_lo_s) / math.log(BAND_RATIO))) + 1
    return float(t_lo_s) * BAND_RATIO ** np.arange(max(n, 1))


def band_flicker_avar(tau_s, t_lo_s: float, record_s: float) -> np.ndarray:
    """b(τ; T_lo): Allan variance per B² of the band-limited flicker (module docstring);
    T_lo = 0 is the flat floor 2 ln 2/π.

    >>> round(float(band_flicker_avar(100.0, 0.1, 7200.0)) / FLICKER_COEFF, 2)  # in band
    1.0
    >>> float(band_flicker_avar(0.01, 10.0, 7200.0)) < 0.01 * FLICKER_COEFF  # below T_lo
    True
    """
    t = np.asarray(tau_s, dtype=np.float64)
    if t_lo_s <= 0:
        return np.full_like(t, FLICKER_COEFF)
    s2 = math.log(BAND_RATIO) / math.pi
    return sum(markov_avar(t, s2, tc) for tc in band_correlation_times(t_lo_s, record_s))


def t_lo_grid(tau0_s: float, record_s: float) -> np.ndarray:
    """Candidate T_lo: 0 (flat floor) and τ0·10^{j/4} up to a tenth of the record."""
    n = int(math.floor(4.0 * math.log10(max(record_s / (10.0 * tau0_s), 1.0)) + 1e-9)) + 1
    return np.r_[0.0, float(tau0_s) * 10.0 ** (np.arange(n) / 4.0)]


#: Tolerance of the refinement of T_lo between its grid neighbours, in ln T_lo.
REFINE_XATOL = 1e-3


@dataclass
class MarkovFit:
    """The fitted model of this module: values [Q, N, B, K, R] (rate unit u, τ in s, as
    :class:`.fit.NoiseFit`; B the band-limited flicker's amplitude), ``u_N`` the standard
    uncertainty of N (``u_N_fit``, the same), ``u_Q``, ``u_B``, ``u_K``, ``u_R`` those of
    the other amplitudes (0 for a term held at zero), ``u_N_selection`` the spread of N
    over the T_lo candidates the data do not tell apart (stated, not in ``u_N``: module
    docstring), ``t_lo_s`` the band's lower correlation time (0: the flat floor)."""

    Q: float
    N: float
    B: float
    K: float
    R: float
    u_N: float
    t_lo_s: float
    chi2_red: float
    rate_unit: str
    tau_s: np.ndarray
    residuals: np.ndarray

    record_s: float = math.inf
    u_N_fit: float = 0.0
    u_N_selection: float = 0.0
    u_Q: float = 0.0
    u_B: float = 0.0
    u_K: float = 0.0
    u_R: float = 0.0

    def adev(self, tau_s) -> np.ndarray:
        """The fitted model's Allan deviation at ``tau_s``."""
        t = np.atleast_1d(np.asarray(tau_s, dtype=np.float64))
        a = design_matrix(t, "adev")
        a[:, 2] = band_flicker_avar(t, self.t_lo_s, self.record_s)
        coef = np.nan_to_num(np.array([self.Q, self.N, self.B, self.K, self.R])) ** 2
        return np.sqrt(a @ coef).reshape(np.shape(tau_s))

    def bias_instability_adev(self, tau_s) -> np.ndarray:
        """The bias instability's share of the model's Allan deviation at ``tau_s``:
        B·√b(τ; T_lo) (module docstring; √(2 ln 2/π)·B in the band, less below T_lo). With
        ``B``/``u_B`` and ``K``/``u_K`` it is what a drift budget or the Allan
        floor reading takes from this model in place of the five-term fit's flat floor."""
        t = np.asarray(tau_s, dtype=np.float64)
        return float(np.nan_to_num(self.B)) * np.sqrt(band_flicker_avar(t, self.t_lo_s,
                                                                        self.record_s))

    def to_dict(self) -> dict:
        """Plain dict (lists for the arrays)."""
        return {"model": "five terms, flicker band-limited below T_lo (Gauss-Markov sum)",
                "rate_unit": self.rate_unit, "Q": self.Q, "N": self.N, "u_N": self.u_N,
                "u_N_fit": self.u_N_fit, "u_N_selection": self.u_N_selection,
                "B": self.B, "u_B": self.u_B, "K": self.K, "u_K": self.u_K, "R": self.R,
                "t_lo_s": self.t_lo_s,
                "chi2_red": self.chi2_red, "tau_s": [float(v) for v in self.tau_s],
                "residuals": [float(v) for v in self.residuals]}


def _fit(var, a, m, n_phase, iterations):
    """IRLS non-negative fit (as :func:`.fit._fit_core`): coefficients, model, sd."""
    model = var.copy()
    edf = edf_memo("adev", n_phase, m, np.zeros(m.size, dtype=np.int64))
    p = np.zeros(a.shape[1])
    for _ in range(max(1, iterations)):
        sd = np.maximum(model, np.finfo(float).tiny) * np.sqrt(2.0 / edf)
        p = wnnls(a, var, sd)
        model = np.maximum(a @ p, np.finfo(float).tiny)
        edf = edf_memo("adev", n_phase, m, TERM_ALPHA[np.argmax(a * p[None, :], axis=1)])
    sd = model * np.sqrt(2.0 / edf)
    return p, model, sd


def fit_markov_model(allan: AllanResult, *, iterations: int = 4) -> MarkovFit:
    """Fit the model of this module to an overlapping (or total) Allan deviation (T_lo
    profiled and refined, module docstring) and give its amplitudes with their sandwich
    uncertainties (``u_N`` the ARW's).

    An exact white-noise curve returns its N:

    >>> tau = 0.1 * 2.0 ** np.arange(12)
    >>> r = AllanResult(tau, 0.5 / np.sqrt(tau), (tau / 0.1).astype(int),
    ...                 40000 - 2 * (tau / 0.1).astype(int), np.full(12, 100.0),
    ...                 np.zeros(12, int), tau, tau, "rate", "overlapping", 0.1, 40000, 0.683)
    >>> round(float(fit_markov_model(r).N), 6)
    0.5
    """
    if allan.kind not in ("adev", "totdev"):
        raise GonioError(f"the band-limited flicker model is fitted to an Allan variance, "
                         f"not {allan.kind!r}", key="kind")
    sel = np.isfinite(allan.adev) & (allan.adev > 0)
    tau = np.asarray(allan.tau_s[sel], dtype=np.float64)
    var = np.asarray(allan.adev[sel], dtype=np.float64) ** 2
    m = np.asarray(allan.m[sel], dtype=np.int64)
    if tau.size < len(TERMS):
        raise GonioError(f"{tau.size} usable τ values cannot determine {len(TERMS)} terms",
                         key="taus")
    tau0 = float(allan.tau0_s)
    record = allan.n_samples * tau0
    n_phase = allan.n_phase or (allan.n_samples + (0 if allan.input_type == "angle" else 1))
    base = design_matrix(tau, "adev")

    def candidate(t_lo):
        a = base.copy()
        a[:, 2] = band_flicker_avar(tau, t_lo, record)
        p, model, sd = _fit(var, a, m, n_phase, iterations)
        return float(np.sum(((var - model) / sd) ** 2)), float(t_lo), a, p, model, sd

    grid = [candidate(t_lo) for t_lo in t_lo_grid(tau0, record)]
    best = min(grid, key=lambda c: c[0])
    h = math.log(BAND_RATIO)
    if best[1] > 0:
        # the grid's step (a factor 10^{1/4}) is refined: a grid-bound T_lo biases N where
        # the bias instability dominates the short τ (the model's own N moves with T_lo)
        x0 = math.log(best[1])
        res = optimize.minimize_scalar(lambda x: candidate(math.exp(x))[0],
                                       bounds=(x0 - h, x0 + h), method="bounded",
                                       options={"xatol": REFINE_XATOL})
        refined = candidate(math.exp(float(res.x)))
        if refined[0] < best[0]:
            best = refined
    rss, t_lo, a, p, model, sd = best
    active = np.flatnonzero(p > 0)
    chi2_red = rss / max(tau.size - active.size - 1, 1)
    v = np.sqrt(p)
    u_fit, u_sel = np.zeros(len(TERMS)), np.zeros(len(TERMS))
    if active.size:
        rows = covariance_rows(tau)
        coef, markov = p.copy(), []
        if t_lo > 0:
            coef[2] = 0.0
            s2 = p[2] * math.log(BAND_RATIO) / math.pi
            markov = [(s2, tc) for tc in band_correlation_times(t_lo, record)]
        sigma = variance_covariance("adev", m[rows], np.asarray(allan.n_pairs[sel])[rows],
                                    tau0, coef, markov=markov)
        jac = a[:, active]
        if t_lo > 0 and p[2] > 0:
            # the band edge's own uncertainty: the model's derivative in ln T_lo, a column
            # of the linearised (Gauss–Newton) design
            d = (band_flicker_avar(tau, t_lo * BAND_RATIO, record)
                 - band_flicker_avar(tau, t_lo / BAND_RATIO, record)) / (2.0 * h)
            jac = np.column_stack([jac, p[2] * d])
        # Σ as computed on the lag grid can be slightly indefinite (a negative eigenvalue
        # gave a negative variance of N, read as u = 0): its nearest positive
        # semi-definite matrix (negative eigenvalues set to 0; Higham 1988) is used
        lam, vec = np.linalg.eigh(sigma)
        sigma = (vec * np.clip(lam, 0.0, None)) @ vec.T
        infl = max(1.0, chi2_red)
        cov = sandwich_covariance(jac[rows], sd[rows], sigma) * infl
        u_fit[active] = np.sqrt(np.clip(np.diag(cov)[:active.size], 0.0, None)) / (2.0 * v[active])
        u_sel = _selection_spread(grid, var, rows, sigma * infl, v)
    u = u_fit
    n_col = TERMS.index("N")
    return MarkovFit(*v, u_N=float(u[n_col]), t_lo_s=float(t_lo), chi2_red=chi2_red,
                     rate_unit=allan.unit, tau_s=tau, residuals=np.sqrt(var / model) - 1.0,
                     record_s=record, u_N_fit=float(u_fit[n_col]),
                     u_N_selection=float(u_sel[n_col]), u_Q=float(u[0]), u_B=float(u[2]),
                     u_K=float(u[3]), u_R=float(u[4]))


def _selection_spread(grid, var, rows, sigma, values) -> np.ndarray:
    """The spread of each amplitude over the T_lo candidates the data cannot tell apart:
    a model average (Buckland, Burnham & Augustin 1997, Biometrics 53, 603) with weights
    exp(−Δχ²/2) (equal prior weight per grid point: uniform in ln T_lo, and T_lo = 0),
    χ² the generalised residual sum rᵀΣ⁻¹r of each candidate's fit under the estimates'
    covariance Σ (every candidate weighed with the chosen model's Σ), taken about the
    chosen values: √(Σ w_i (v_i − v)² / Σ w_i)."""
    w_eig, v_eig = np.linalg.eigh(sigma)
    keep = w_eig > w_eig.max() * 1e-9
    proj = v_eig[:, keep] / np.sqrt(w_eig[keep])
    chi2 = np.array([float(np.sum(((var[rows] - c[4][rows]) @ proj) ** 2)) for c in grid])
    w = np.exp(-(chi2 - chi2.min()) / 2.0)
    v_i = np.sqrt(np.array([c[3] for c in grid]))
    return np.sqrt(w @ (v_i - values[None, :]) ** 2 / np.sum(w))
