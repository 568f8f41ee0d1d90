"""What a noise model predicts for the draft's 7.3 readings: their covariance and the
expected zero stability B_s (the physically founded estimate beside the draft's s(M)/T).

The 7.3 readings of an integrating gyro are M_i = θ(t_i) − θ(0) − t_i·ĉ, angles since the
zeroing at 0 after an Earth-rate/bias compensation measured at rest over the T_c before
it, ĉ = (θ(0) − θ(−T_c))/T_c (the bench and the reducer both take the counter's rate over
the static phase). Each M_i is a linear combination Σ a_k θ(s_k) of the angle at the
instants s = (−T_c, 0, t_1 … t_n) whose weights sum to zero and whose first moment Σ a_k s_k
is zero too: the compensation removes any constant rate. Such combinations see a noise
process only through its *generalised covariance* G(h) (Matheron's intrinsic random
functions of order 1): Cov(Σ a θ, Σ b θ) = Σ_k Σ_l a_k b_l G(s_k − s_l). For the terms of
the five-term gyro model (IEEE Std 952-1997 Annex C; :mod:`gonio.analysis.noise.fit`),
angle in (rate unit)·s:

=========================  ==========================  ============================
term                       G(h)                        check: AVAR (4·(−2G(τ))…)/2τ²
=========================  ==========================  ============================
Q quantisation (white θ)   Q² if h = 0, else 0         3Q²/τ²
N angle random walk        −N²|h|/2                    N²/τ
B flicker rate             B² h² ln|h| / (2π)          (2 ln 2/π) B²
K rate random walk         K²|h|³/12                   K²τ/3
Gauss–Markov rate (σ, τ_c) −σ²τ_c²(|h|/τ_c − 1 + e^{−|h|/τ_c})   (bench truth only)
=========================  ==========================  ============================

(the AVAR column is the same combination with weights (1, −2, 1) at (0, τ, 2τ):
AVAR = Σ a_k a_l G(s_k − s_l)/(2τ²); it reproduces the fit module's table, which ties the
G's to the fitted coefficients). A rate ramp R is deterministic: θ = R s²/2 adds the
vector R·(A s²/2) to the readings. Then, with P the centring matrix and V = A G Aᵀ,

    E[s²(M)] = s²(deterministic part) + tr(P V)/(n − 1)             (1)

and the population value of the draft's statistic is B_s,pop = √E[s²(M)] / T, T = t_n − t_1:
the σ of the χ² reading of 7.3 (ν s²/σ² ≈ χ²_ν), the same quantity the draft's s(M)/T
estimates from one set of 15 readings.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["reading_weights", "generalised_covariance", "readings_covariance",
           "expected_sample_variance", "expected_zero_stability", "ExpectedZeroStability"]


def reading_weights(time_s, compensation_time_s: float | None):
    """Instants s and weights A (n × len(s)) of the 7.3 readings M = A θ(s).

    With a measured compensation over ``compensation_time_s`` T_c before the zeroing:
    s = (−T_c, 0, t_1 … t_n), M_i = θ(t_i) − (1 + t_i/T_c) θ(0) + (t_i/T_c) θ(−T_c);
    without: s = (0, t_1 … t_n), M_i = θ(t_i) − θ(0).

    >>> s, A = reading_weights([0.0, 300.0], 60.0)
    >>> s.tolist(); A.tolist()
    [-60.0, 0.0, 0.0, 300.0]
    [[0.0, -1.0, 1.0, 0.0], [5.0, -6.0, 0.0, 1.0]]
    """
    t = np.asarray(time_s, dtype=float)
    n = t.size
    if compensation_time_s:
        tc = float(compensation_time_s)
        s = np.concatenate([[-tc, 0.0], t])
        A = np.zeros((n, n + 2))
        A[:, 0] = t / tc
        A[:, 1] = -1.0 - t / tc
        A[np.arange(n), 2 + np.arange(n)] += 1.0
    else:
        s = np.concatenate([[0.0], t])
        A = np.zeros((n, n + 1))
        A[:, 0] = -1.0
        A[np.arange(n), 1 + np.arange(n)] += 1.0
    return s, A


def generalised_covariance(h, *, Q: float = 0.0, N: float = 0.0, B: float = 0.0,
                           K: float = 0.0, gm_sigma: float = 0.0,
                           gm_tau_s: float = 0.0) -> np.ndarray:
    """G(h) of the noise terms (module table), angle unit (rate unit)·s, h in s.

    Checked against the Allan variance it implies (AVAR(τ) of white rate noise = N²/τ):

    >>> tau = 10.0
    >>> a, s = np.array([1.0, -2.0, 1.0]), np.array([0.0, tau, 2 * tau])
    >>> G = generalised_covariance(np.subtract.outer(s, s), N=2.0)
    >>> float(a @ G @ a / (2 * tau ** 2))       # N²/τ = 0.4
    0.4
    """
    h = np.abs(np.asarray(h, dtype=float))
    g = np.where(h == 0.0, Q * Q, 0.0) - N * N * h / 2.0 + K * K * h ** 3 / 12.0
    if B:
        with np.errstate(divide="ignore", invalid="ignore"):
            g = g + np.where(h > 0, B * B * h * h * np.log(np.where(h > 0, h, 1.0))
                             / (2.0 * math.pi), 0.0)
    if gm_sigma and gm_tau_s:
        x = h / gm_tau_s
        g = g - gm_sigma ** 2 * gm_tau_s ** 2 * (x - 1.0 + np.exp(-x))
    return g


def readings_covariance(time_s, compensation_time_s: float | None, **terms) -> np.ndarray:
    """V = A G Aᵀ: covariance of the 7.3 readings' noise (angle unit² of the terms)."""
    s, A = reading_weights(time_s, compensation_time_s)
    return A @ generalised_covariance(np.subtract.outer(s, s), **terms) @ A.T


def expected_sample_variance(time_s, compensation_time_s: float | None, *,
                             deterministic=None, R: float = 0.0, **terms) -> float:
    """E[s²(M)] of equation (1): noise part tr(P V)/(n − 1) plus the sample variance of the
    deterministic readings (``deterministic``, same unit) and of a rate ramp R."""
    t = np.asarray(time_s, dtype=float)
    n = t.size
    V = readings_covariance(t, compensation_time_s, **terms)
    P = np.eye(n) - 1.0 / n
    out = float(np.trace(P @ V)) / (n - 1)
    det = np.zeros(n)
    if deterministic is not None:
        det = det + np.asarray(deterministic, dtype=float)
    if R:
        s, A = reading_weights(t, compensation_time_s)
        det = det + R * (A @ (s * s / 2.0))
    return out + float(np.var(det, ddof=1))


class ExpectedZeroStability:
    """B_s,pop from a fitted five-term model (value, u, ν) — see :func:`expected_zero_stability`."""

    def __init__(self, value: float, u: float, dof: float, parts: dict, source: str,
                 coefficients: dict | None = None, u_coefficients: dict | None = None,
                 responses: dict | None = None, duration_s: float = 1.0):
        self.value, self.u, self.dof, self.parts, self.source = value, u, dof, parts, source
        self.coefficients = coefficients or {}
        self.u_coefficients = u_coefficients or {}
        self.responses = responses or {}
        self.duration_s = duration_s

    def sample(self, rng: np.random.Generator, m: int) -> np.ndarray:
        """JCGM 101 draws of B_s,pop: each fitted coefficient normal with its u (JCGM 101
        6.4.7), then √(Σ c_j x_j²)/T — the model itself, not its linearisation."""
        S = np.zeros(int(m))
        for k, x in self.coefficients.items():
            draw = x + self.u_coefficients.get(k, 0.0) * rng.standard_normal(int(m))
            S += self.responses[k] * draw * draw
        return np.sqrt(S) / self.duration_s

    def to_dict(self) -> dict:
        return {"value": float(self.value), "u": float(self.u),
                "dof": None if not math.isfinite(self.dof) else float(self.dof),
                "variance_shares": {k: float(v) for k, v in self.parts.items()},
                "source": self.source}


def expected_zero_stability(fit, time_s, compensation_time_s: float | None
                            ) -> ExpectedZeroStability:
    """B_s,pop = √E[s²(M)]/T (equation (1)) from a :class:`gonio.analysis.noise.NoiseFit`
    in °/h, with its standard uncertainty.

    E[s²] is linear in the squared coefficients x = (Q², N², B², K², R²): E[s²] = Σ c_j x_j,
    so u²(E[s²]) = Σ (c_j · 2 x_j u_j)² from the fit's (bootstrap) u_j, taken
    independent (the fitted N, B, K are usually negatively correlated, so this is the
    larger of the two readings), and u(B_s,pop) = u(E[s²])/(2 E[s²]^{1/2} T) (JCGM 100
    5.1.2). ν from Welch–Satterthwaite with ν_j = n_bootstrap − 1 per term (∞ for the
    covariance method). Limits: a term the fit holds at zero has u = 0 (the bootstrap
    refits zero), and the five-term model has no Gauss–Markov term; a Gauss–Markov
    bias whose correlation time lies inside the record is then missed and this u is
    too small (docs/draft-readings.md, 7.3: why this estimate is given beside the
    draft's and not stated by default).
    """
    t = np.asarray(time_s, dtype=float)
    T = float(t.max() - t.min())
    coef = {k: float(np.nan_to_num(getattr(fit, k))) for k in ("Q", "N", "B", "K", "R")}
    us = {k: float(np.nan_to_num(getattr(fit, "u_" + k))) for k in coef}
    c = {}
    for k in coef:
        c[k] = expected_sample_variance(t, compensation_time_s, **{k: 1.0})
    S = sum(c[k] * coef[k] ** 2 for k in coef)
    terms = {k: c[k] * 2.0 * coef[k] * us[k] for k in coef}
    if S <= 0:
        return ExpectedZeroStability(0.0, 0.0, math.inf, {}, "five-term fit: no noise")
    uS = math.sqrt(sum(v * v for v in terms.values()))
    value = math.sqrt(S) / T
    u = uS / (2.0 * math.sqrt(S) * T)
    nb = int(getattr(fit, "n_bootstrap", 0) or 0)
    nu_j = (nb - 1) if nb >= 2 else math.inf
    den = sum(v ** 4 / nu_j for v in terms.values()) if math.isfinite(nu_j) else 0.0
    dof = (uS ** 4 / den) if den > 0 else math.inf
    parts = {k: c[k] * coef[k] ** 2 / S for k in coef}
    return ExpectedZeroStability(value, u, dof, parts,
                                 f"five-term Allan fit of the 7.3 record ({fit.kind}), "
                                 f"u by {fit.uncertainty_method}", coef, us, c, T)
