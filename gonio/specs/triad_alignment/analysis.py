"""Electrical alignment of a gyro triad: M, bias, M⁻¹, uncertainties, leakage.

Model ([Looney-alignment] eq. 14–18, docs/references.md): the mean outputs of a dwell are
G = M w + b, with w the mean rate vector in the fixture's reference frame — the table
rate about the axis that was up plus the Earth rate in that orientation, averaged
exactly over the dwell (:func:`gonio.physics.alignment.mean_earth_rate_ref`). The article
isolates one column of M per rotation axis (eq. 19–27) and cancels the bias with equal
and opposite rates (eq. 28–30a); a least-squares fit over all dwells does both at once
and also uses the static positions, and it reduces exactly to the article's difference
formula for a single ± pair (tested).

Estimators
----------
* weighted least squares per output channel, weights ∝ the dwell's sample count
  (white noise: the variance of a dwell mean is ∝ 1/T), unknowns (M_i1, M_i2, M_i3, b_i);
* GUM (JCGM 100 §5, Type A): covariance s² (XᵀWX)⁻¹ with s² from the weighted
  residuals, ν = n − 4 degrees of freedom, coverage factor k = t_{0.9545, ν};
  uncertainties of derived quantities (M⁻¹, scale factors, angles, cross-axis
  sensitivities, bias in °/s) by first-order propagation with a numerical Jacobian
  (JCGM 100 §5.1.2);
* Monte Carlo (JCGM 101 §7, parametric): the fit repeated on outputs redrawn from the
  fitted model with the estimated noise, every quantity recomputed;
* robust: iteratively reweighted least squares, Huber weights (c = 1.345) to convergence,
  then Tukey's bisquare (c = 4.685) from there, both on
  leverage-adjusted residuals r_i/√(1 − h_ii) (h the hat matrix of the non-robust weighted
  fit: a dwell that alone fixes a parameter has h ≈ 1 and a small raw residual), scaled by
  the median absolute residual / 0.6745; rows whose final weight is
  below 0.5 are reported as outliers (file line and channel), never silently dropped;
* averaging time: from the Allan deviation (:func:`gonio.analysis.noise.allan_deviation`) of the
  static record, the shortest τ whose deviation is below the article's noise limit
  ω_TR sin ψ_T / 10 (eq. 30b, :func:`gonio.physics.alignment.alignment_noise_limit_dps`);
* leakage after alignment: M̂⁻¹ M − I; on the bench (truth known) its actual value,
  otherwise its standard uncertainty (the estimate itself is I by construction).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import stats

from gonio.physics.earth import earth_rate_enu
from gonio.units import S_PER_DAY, dph_to_dps, dps_to_dph
from gonio.errors import GonioError
from gonio.specs.triad_alignment.keys import OFFDIAG  # noqa: F401  (the off-diagonal pairs)
from gonio.specs.triad_alignment.readings import OUT, TriadReadings
from gonio.analysis.noise import allan_deviation
from gonio.analysis.noise.stream import Record, frame_column, rows_where
from gonio.physics.alignment import (alignment_noise_limit_dps, decompose_system_matrices,
                                     mean_earth_rate_ref, signed_axis)

#: Huber tuning constant (95 % efficiency at the normal distribution).
HUBER_C = 1.345
#: Tukey bisquare tuning constant (95 % efficiency at the normal distribution).
BISQUARE_C = 4.685
#: MAD → σ for normal data.
MAD_TO_SIGMA = 1.0 / 0.6744897501960817
#: Coverage probability of the expanded uncertainties.
COVERAGE = 0.9545


def dwell_regressors(rows: pd.DataFrame, latitude_deg: float) -> np.ndarray:
    """(n, 3) mean rate vector of every dwell in the reference frame, °/s: the table rate
    along the ``up`` axis plus the Earth rate averaged over the dwell — the ω of
    [Looney-alignment] eq. 14 with the Earth rate of every orientation
    (:func:`gonio.physics.alignment.mean_earth_rate_ref`)."""
    w_enu = np.degrees(earth_rate_enu(latitude_deg))
    out = np.empty((len(rows), 3))
    for k, r in enumerate(rows.itertuples(index=False)):
        out[k] = (r.rate_dps * signed_axis(r.up)
                  + mean_earth_rate_ref(w_enu, r.up, r.north0, r.table_deg, r.rate_dps,
                                        r.duration_s))
    return out


def _wls(x: np.ndarray, y: np.ndarray, w: np.ndarray):
    sw = np.sqrt(w)
    theta, *_ = np.linalg.lstsq(x * sw[:, None], y * sw, rcond=None)
    return theta


def _fit_channel(x, y, w, robust: bool, max_iter: int = 100):
    """(θ, cov, s, robust weights, ν) of one channel's weighted least-squares fit
    (JCGM 100 §4.2 Type A: cov = s²(XᵀWX)⁻¹, s² = Σ w r²/ν), optionally robust (IRLS,
    Huber then Tukey bisquare; module docstring)."""
    n, p = x.shape
    rw = np.ones(n)
    theta = _wls(x, y, w)
    if robust:
        # Huber first (convex: a unique solution whatever the start), then Tukey's bisquare
        # from there (redescending: gross outliers get weight 0)
        h = np.einsum("ij,jk,ik->i", x, np.linalg.inv(x.T @ (x * w[:, None])), x) * w
        adj = np.sqrt(w) / np.sqrt(np.clip(1.0 - h, 1e-6, None))
        for kind in ("huber", "bisquare"):
            for _ in range(max_iter):
                r = (y - x @ theta) * adj
                scale = MAD_TO_SIGMA * np.median(np.abs(r))
                if scale <= 0:
                    break
                if kind == "huber":
                    a = np.abs(r) / (HUBER_C * scale)
                    new = np.where(a <= 1.0, 1.0, 1.0 / np.maximum(a, 1e-300))
                else:
                    u = r / (BISQUARE_C * scale)
                    new = np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 2, 0.0)
                if np.linalg.matrix_rank(x[new > 0]) < p or np.sum(new > 0) < p + 1:
                    raise GonioError("robust fit: the readings left after down-weighting the "
                                     "outliers no longer determine M and b")
                theta_new = _wls(x, y, w * new)
                done = np.allclose(theta_new, theta, rtol=0,
                                   atol=1e-12 * (1 + np.max(np.abs(theta))))
                theta, rw = theta_new, new
                if done:
                    break
    wt = w * rw
    r = y - x @ theta
    dof = float(np.sum(rw) - p) if robust else float(n - p)
    if dof <= 0:
        raise GonioError(f"alignment fit needs more than {p} dwells, got {n}")
    s2 = float(np.sum(wt * r * r) / dof)
    xtwx_inv = np.linalg.inv(x.T @ (x * wt[:, None]))
    return theta, s2 * xtwx_inv, math.sqrt(s2), rw, dof


def dwell_blocks(rows: pd.DataFrame) -> np.ndarray:
    """Block number of every dwell for the bias wander: the rotating dwells (rate ≠ 0) of
    one orientation (``up``) share a block — recorded one after the other, their ± pairs see
    the same slowly wandering bias — and every static dwell is a block of its own."""
    rot = rows["rate_dps"].to_numpy(float) != 0.0
    ups = rows["up"].astype(str).to_numpy()
    names = {u: k for k, u in enumerate(dict.fromkeys(ups[rot]))}
    out = np.empty(len(rows), dtype=int)
    nxt = len(names)
    for k in range(len(rows)):
        if rot[k]:
            out[k] = names[ups[k]]
        else:
            out[k], nxt = nxt, nxt + 1
    return out


def variance_components(x, y, w, theta, blocks, dof_full: float):
    """The noise of the dwell means in two parts (JCGM 100 4.2, a random-effects model): a
    white part σ_w²/w_k per dwell and a bias offset per block of σ_B² (the bias instability
    wanders between the orientations and the static positions, recorded minutes apart).

    σ_w² comes from the weighted fit with one bias per block (M plus the block biases): its
    residuals are the dwells' scatter about their own block's bias, ν_w = n − rank. σ_B² by
    the method of moments from the weighted residual sum of squares of the model's fit
    (one bias b): E[RSS] = σ_w²(n − p) + σ_B² tr(R W^½ Z Zᵀ W^½), R the residual maker,
    clipped at 0, ν_B = (n − p) − ν_w. The covariance of θ̂ = P y, P = (XᵀWX)⁻¹XᵀW, is
    σ_w²(XᵀWX)⁻¹ + σ_B² (PZ)(PZ)ᵀ; a parameter's ν by Welch–Satterthwaite (JCGM 100 G.4).
    The ± pairs of a block cancel its offset, so M sees σ_w; b sees both. Where the blocks
    leave fewer than 2 degrees of freedom (e.g. one rate per axis) the single s² of the fit
    is used (σ_B = 0, ν the fit's).

    Returns (cov (p, p), ν per parameter (p,), σ_w, σ_B, PZ (p, blocks))."""
    n, p = x.shape
    z = (blocks[:, None] == np.arange(int(blocks.max()) + 1)[None, :]).astype(float)
    sw = np.sqrt(w)
    xtwx_inv = np.linalg.inv(x.T @ (x * w[:, None]))
    pz = xtwx_inv @ (x * w[:, None]).T @ z
    r = y - x @ theta
    rss = float(np.sum(w * r * r))
    xb = np.column_stack([x[:, :p - 1], z]) * sw[:, None]
    rank = int(np.linalg.matrix_rank(xb))
    nu_w = float(np.sum(w > 0) - rank)
    if nu_w < 2 or dof_full - nu_w < 1:
        s2 = rss / dof_full
        return s2 * xtwx_inv, np.full(p, dof_full), math.sqrt(s2), 0.0, pz
    fit_b, *_ = np.linalg.lstsq(xb, y * sw, rcond=None)
    s2_w = float(np.sum((y * sw - xb @ fit_b) ** 2) / nu_w)
    xs = x * sw[:, None]
    resid_maker = np.eye(n) - xs @ xtwx_inv @ xs.T
    zs = z * sw[:, None]
    tr = float(np.trace(resid_maker @ zs @ zs.T))
    s2_b = max(0.0, (rss - s2_w * dof_full) / tr) if tr > 0 else 0.0
    a = s2_w * np.diag(xtwx_inv)
    c = s2_b * np.sum(pz * pz, axis=1)
    nu_b = dof_full - nu_w
    with np.errstate(divide="ignore", invalid="ignore"):
        nu = (a + c) ** 2 / (a * a / nu_w + c * c / nu_b)
    return s2_w * xtwx_inv + s2_b * pz @ pz.T, nu, math.sqrt(s2_w), math.sqrt(s2_b), pz


#: Off-diagonal (i, j) in the order of :data:`OFFDIAG`.
_OFF = ((0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1))


def _derived_batch(thetas: np.ndarray) -> np.ndarray:
    """Derived quantities of each row of ``thetas`` (shape (k, 12), θ = rows of [M | b]
    stacked), one row each: vec(M⁻¹) (9), scale factors (3), ψ (3), φ off-diagonal (6),
    cross-axis S (6), bias in °/s = M⁻¹ b (3)."""
    mb = np.asarray(thetas, dtype=float).reshape(-1, 3, 4)
    m, b = mb[:, :, :3], mb[:, :, 3]
    minv = np.linalg.inv(m)
    d = decompose_system_matrices(m)
    i, j = np.array(_OFF).T
    return np.concatenate([minv.reshape(-1, 9), d["scale"], d["psi_rad"],
                           d["phi_rad"][:, i, j], d["cross_axis"][:, i, j],
                           np.matmul(minv, b[:, :, None])[:, :, 0]], axis=1)


def _derived_trials(thetas: np.ndarray) -> np.ndarray:
    """:func:`_derived_batch` of a Monte Carlo piece (shape (k, 12)), written out element by
    element for speed (each quantity a few operations on arrays of k, no stacked 3 × 3
    LAPACK calls or full 3 × 3 temporaries): M⁻¹ = adj(M)/det M (Cramer's rule), K_i the
    row norms, ψ_i = acos|M_ii/K_i|, φ_ij = asin(M_ij/K_i), S_ij = M_ij/M_ii, M⁻¹b — the
    same formulas as :func:`gonio.physics.alignment.decompose_system_matrices` (equal to
    :func:`_derived_batch` to rounding, tested). A trial whose M has a zero row or is
    singular is a GonioError, as in :func:`_derived_batch`."""
    t = np.ascontiguousarray(np.asarray(thetas, dtype=float).T)      # (12, k): one row each
    m = [[t[4 * i + j] for j in range(3)] for i in range(3)]
    b = [t[4 * i + 3] for i in range(3)]
    out = np.empty((30, t.shape[1]))
    # cofactors C_ij; M⁻¹[j][i] = C_ij / det
    cof = [[m[(i + 1) % 3][(j + 1) % 3] * m[(i + 2) % 3][(j + 2) % 3]
            - m[(i + 1) % 3][(j + 2) % 3] * m[(i + 2) % 3][(j + 1) % 3] for j in range(3)]
           for i in range(3)]
    det = m[0][0] * cof[0][0] + m[0][1] * cof[0][1] + m[0][2] * cof[0][2]
    if not np.all(np.isfinite(det) & (det != 0)):
        raise GonioError("a Monte Carlo trial's system matrix is singular: the dwells "
                         "hardly determine M")
    for r in range(3):
        for c in range(3):
            np.divide(cof[c][r], det, out=out[3 * r + c])
    scale = out[9:12]
    for i in range(3):
        np.sqrt(m[i][0] * m[i][0] + m[i][1] * m[i][1] + m[i][2] * m[i][2], out=scale[i])
    if np.any(scale == 0):
        raise GonioError("system matrix has a zero row (a gyro with no output)")
    for i in range(3):
        np.arccos(np.clip(np.abs(m[i][i] / scale[i]), -1.0, 1.0), out=out[12 + i])
    for n, (i, j) in enumerate(_OFF):
        np.arcsin(np.clip(m[i][j] / scale[i], -1.0, 1.0), out=out[15 + n])
        np.divide(m[i][j], m[i][i], out=out[21 + n])
    for r in range(3):
        minv = out[3 * r: 3 * r + 3]
        np.add(minv[0] * b[0] + minv[1] * b[1], minv[2] * b[2], out=out[27 + r])
    return out.T


def _derived(theta12: np.ndarray) -> np.ndarray:
    """:func:`_derived_batch` of one θ."""
    return _derived_batch(np.asarray(theta12, dtype=float)[None, :])[0]


_DERIVED_SLICES = {"alignment_matrix": slice(0, 9), "scale": slice(9, 12), "psi_rad": slice(12, 15),
                   "phi_rad": slice(15, 21), "cross_axis": slice(21, 27), "bias_dps": slice(27, 30)}


def gum_propagate(f, x: np.ndarray, cov: np.ndarray, rel_step: float = 1e-6) -> np.ndarray:
    """Covariance of f(x) by first-order propagation (JCGM 100 §5.1.2, eq. 13), with a
    central-difference Jacobian.

    >>> c = gum_propagate(lambda v: np.array([v[0] * v[1]]), np.array([2.0, 3.0]), np.diag([0.01, 0.04]))
    >>> round(float(c[0, 0]), 6)   # 3² 0.01 + 2² 0.04
    0.25
    """
    x = np.asarray(x, dtype=float)
    f0 = np.asarray(f(x), dtype=float)
    jac = np.empty((f0.size, x.size))
    for j in range(x.size):
        h = rel_step * max(abs(x[j]), 1e-3)
        xp, xm = x.copy(), x.copy()
        xp[j] += h
        xm[j] -= h
        jac[:, j] = (np.asarray(f(xp)) - np.asarray(f(xm))) / (2 * h)
    return jac @ cov @ jac.T


@dataclass
class AveragingTime:
    """Averaging time chosen from the Allan deviation (article eq. 30b, Fig. 6)."""

    noise_limit_dps: float
    target_deg: float
    test_rate_dps: float
    tau_needed_s: list            # per channel, NaN if never reached
    tau_min_adev_s: list          # τ of the Allan minimum per channel
    min_adev_dph: list
    shortest_dwell_s: float
    sufficient: bool
    tau_s: list = field(default_factory=list)
    adev_dph: list = field(default_factory=list)   # per channel

    def to_json(self) -> dict:
        return dict(self.__dict__)


@dataclass
class AlignmentResult:
    """Electrical alignment of a triad (see the module docstring)."""

    system_matrix: np.ndarray          # M, output per °/s
    bias_output: np.ndarray            # b, output units
    cov_theta: np.ndarray              # 12×12, rows of [M | b] stacked
    sigma_output: np.ndarray           # residual noise of a unit-weight dwell, per channel
    dof: np.ndarray
    coverage_factor: np.ndarray        # k = t_{0.9545, ν} per channel
    derived: dict                      # name -> value array
    u_derived: dict                    # name -> GUM standard uncertainty array
    u_mc: dict | None                  # name -> Monte Carlo standard uncertainty array
    u_mc_theta: np.ndarray | None
    robust: bool
    outliers: list                     # {"line", "channel", "weight"}
    leakage_u: np.ndarray              # standard uncertainty of M̂⁻¹M − I
    averaging: AveragingTime | None
    n_dwells: int
    output_unit: str = ""
    lines: list = field(default_factory=list)
    residuals: np.ndarray | None = None
    dof_theta: np.ndarray | None = None   # (3, 4): ν of each M_ij and b_i (Welch–Satterthwaite)
    sigma_components: np.ndarray | None = None   # (3, 2): σ_w (white, unit weight), σ_B (block)
    #: the rate table's Type B part (:func:`table_type_b_cov`), included in ``cov_theta``,
    #: ``u_derived`` and ``leakage_u``: its inputs and its own u_theta (12,), u_derived,
    #: leakage_u; None when the table is taken as exact
    type_b: dict | None = None

    @property
    def coverage_factor_theta(self) -> np.ndarray:
        """k = t_{0.9545, ν} of each M_ij and b_i, (3, 4)."""
        nu = np.column_stack([np.repeat(self.dof[:, None], 3, 1), self.dof]) \
            if self.dof_theta is None else self.dof_theta
        return stats.t.ppf(0.5 + COVERAGE / 2, nu)

    @property
    def u_system_matrix(self) -> np.ndarray:
        return np.sqrt(np.diag(self.cov_theta)).reshape(3, 4)[:, :3]

    @property
    def u_bias_output(self) -> np.ndarray:
        return np.sqrt(np.diag(self.cov_theta)).reshape(3, 4)[:, 3]

    @property
    def alignment_matrix(self) -> np.ndarray:
        """M⁻¹ (article eq. 15): multiply bias-corrected outputs by it to get rates."""
        return np.asarray(self.derived["alignment_matrix"]).reshape(3, 3)

    def apply(self, outputs) -> np.ndarray:
        """Aligned rates ω̂ = M⁻¹ (G − b), °/s, for outputs of shape (n, 3) or (3,)."""
        g = np.asarray(outputs, dtype=float)
        return (g - self.bias_output) @ self.alignment_matrix.T

    def leakage_against(self, true_system_matrix) -> np.ndarray:
        """Residual cross-axis leakage M̂⁻¹ M_true − I (known truth, e.g. the bench)."""
        return self.alignment_matrix @ np.asarray(true_system_matrix) - np.eye(3)

    def to_json(self) -> dict:
        def mat(a):
            return np.asarray(a, dtype=float).round(15).tolist()
        out = {
            "kind": "triad-alignment", "output_unit": self.output_unit,
            "n_dwells": self.n_dwells, "robust": self.robust,
            "coverage_probability": COVERAGE,
            "system_matrix": mat(self.system_matrix),
            "u_system_matrix": mat(self.u_system_matrix),
            "bias_output": mat(self.bias_output), "u_bias_output": mat(self.u_bias_output),
            "dof": mat(self.dof), "coverage_factor": mat(self.coverage_factor),
            "sigma_output": mat(self.sigma_output),
            "dof_bias": None if self.dof_theta is None else mat(self.dof_theta[:, 3]),
            "sigma_white_block": None if self.sigma_components is None
            else mat(self.sigma_components),
            "derived": {k: mat(v) for k, v in self.derived.items()},
            "u_derived": {k: mat(v) for k, v in self.u_derived.items()},
            "u_monte_carlo": None if self.u_mc is None else {k: mat(v) for k, v in self.u_mc.items()},
            "u_monte_carlo_system_matrix": None if self.u_mc_theta is None
            else mat(self.u_mc_theta.reshape(3, 4)[:, :3]),
            "u_monte_carlo_bias_output": None if self.u_mc_theta is None
            else mat(self.u_mc_theta.reshape(3, 4)[:, 3]),
            "residual_leakage_u": mat(self.leakage_u),
            "outliers": self.outliers,
            "averaging_time": None if self.averaging is None else self.averaging.to_json(),
            "offdiagonal_order": list(OFFDIAG),
            "type_b": None if self.type_b is None else {
                "rate_u_rel": self.type_b["rate_u_rel"],
                "orientation_u_rad": self.type_b["orientation_u_rad"],
                "u_system_matrix": mat(self.type_b["u_theta"].reshape(3, 4)[:, :3]),
                "u_derived": {k: mat(v) for k, v in self.type_b["u_derived"].items()},
                "residual_leakage_u": mat(self.type_b["leakage_u"]),
                **({"rate_bound_rel": self.type_b["rate_bound_rel"],
                    "orientation_bound_rad": self.type_b["orientation_bound_rad"],
                    "a_system_matrix": mat(self.type_b["a_theta"].reshape(3, 4)[:, :3]),
                    "a_derived": {k: mat(v) for k, v in self.type_b["a_derived"].items()},
                    "residual_leakage_a": mat(self.type_b["a_leakage"])}
                   if "a_theta" in self.type_b else {})},
        }
        return out


#: How long the stated bias is meant to hold (s): one day of operation. The long-term term of
#: b integrates the bias instability's flicker spectrum from the shortest dwell to this.
BIAS_HORIZON_S: float = S_PER_DAY
#: Allan floor of flicker bias noise: σ_A = √(2 ln 2 / π) · B (IEEE 952 Annex C).
FLICKER_FLOOR: float = math.sqrt(2.0 * math.log(2.0) / math.pi)


def bias_instability_u_dps(averaging: "AveragingTime | None", static_s: float,
                           horizon_s: float = BIAS_HORIZON_S, tau_d_s: float | None = None
                           ) -> tuple[np.ndarray, np.ndarray]:
    """Long-term term of the bias b (°/s per gyro) and its degrees of freedom.

    The fit's u(b) is in-run: it holds for the mean bias over this record. The bias a
    certificate states is meant to hold beyond it, and a gyro's bias wanders (bias
    instability, flicker: one-sided PSD h/f with h = B²/π). Between time scales τ_d and
    τ_L that wander has variance ∫ h/f df = (B²/π) ln(τ_L/τ_d), so

        u_BI = B̂ √(ln(τ_L/τ_d)/π),   B̂ = min σ_A(τ) / √(2 ln 2/π),

    B̂ from the static record's Allan deviation, τ_d the shortest dwell (faster wander
    averages within a dwell and shows in the fit's residuals), τ_L = ``horizon_s``. Its
    degrees of freedom are those of the Allan deviation at its minimum, T/τ − 1 for a
    record of T = ``static_s`` (at least 1). Without a static record: zeros, ν = ∞.
    ``tau_d_s`` replaces the alignment's shortest dwell (the thermal programme's dwells).

    >>> av = AveragingTime(0.0, 0.1, 50.0, [1.0] * 3, [50.0] * 3, [3.0] * 3, 10.0, True)
    >>> u, nu = bias_instability_u_dps(av, 300.0)
    >>> round(float(u[0]) * 3600, 3), float(nu[0])
    (7.671, 5.0)
    """
    if averaging is None or not static_s:
        return np.zeros(3), np.full(3, math.inf)
    b = dph_to_dps(np.asarray(averaging.min_adev_dph, dtype=float)) / FLICKER_FLOOR
    tau_d = averaging.shortest_dwell_s if math.isfinite(averaging.shortest_dwell_s) else 1.0
    tau_d = tau_d if tau_d_s is None else tau_d_s
    u = b * math.sqrt(max(math.log(horizon_s / tau_d), 0.0) / math.pi)
    nu = np.maximum(static_s / np.asarray(averaging.tau_min_adev_s, dtype=float) - 1.0, 1.0)
    return u, nu


def table_type_b_cov(m: np.ndarray, rate_u_rel: float, orientation_u_rad: float) -> np.ndarray:
    """Covariance (12 × 12, θ = rows of [M | b] stacked) that the rate table's errors give
    the fitted θ (JCGM 100 5.1.2 with the sensitivities of the model below; JCGM 100
    4.3.7 for a rectangular bound). The fit takes the table's set rate r about reference
    axis a as the applied rate vector r e_a; the table turns at r(1 + ε) (ε its relative
    rate error, standard uncertainty ``rate_u_rel`` from its certificate) about an axis
    that, in the fixture's reference frame, is e_a + δ_a (δ_a ⊥ e_a: the fixture's face on
    the table top, the table top's squareness to its spin axis; each of δ_a's two
    components rectangular within the fixture's stated bound, standard uncertainty
    ``orientation_u_rad``, independent between the three orientations). The ± rate
    dwells then read M r(1 + ε)(e_a + δ_a), so to first order the fitted column a is

        M̂_·a = M_·a (1 + ε) + Σ_{j ≠ a} M_·j δ_aj,

    and the bias b (the ± pairs' mean and the static dwells, at the Earth rate only) is
    unchanged. ε is common to every entry: u² vec(M) vec(M)ᵀ; each δ_aj adds
    u_δ² v vᵀ with v the column M_·j placed in column a. The Earth rate's part of the
    same errors (≤ 7.3×10⁻⁵ rad/s × δ) is below the dwells' noise and left out.
    Checked against a Monte Carlo of the bench with drawn table errors
    (tests/test_triad_type_b.py).

    >>> c = table_type_b_cov(np.diag([50.0, 50.0, 50.0]), 1e-3, 0.0)
    >>> round(float(np.sqrt(c[0, 0])), 6), round(float(c[0, 5] / c[0, 0]), 6), float(c[3, 3])
    (0.05, 1.0, 0.0)
    >>> c = table_type_b_cov(np.diag([50.0, 50.0, 50.0]), 0.0, 1e-3)
    >>> round(float(np.sqrt(c[1, 1])), 6), float(c[0, 0])   # M_xy gets M_xx δ_yx
    (0.05, 0.0)
    """
    m = np.asarray(m, dtype=float)
    cov = np.zeros((12, 12))
    idx = np.array([[4 * i + j for j in range(3)] for i in range(3)])
    v = np.zeros(12)
    v[idx] = m
    cov += rate_u_rel ** 2 * np.outer(v, v)
    for a in range(3):
        for j in range(3):
            if j != a:
                v = np.zeros(12)
                v[idx[:, a]] = m[:, j]
                cov += orientation_u_rad ** 2 * np.outer(v, v)
    return cov


def _split(vec: np.ndarray) -> dict:
    return {k: vec[s] for k, s in _DERIVED_SLICES.items()}


def _check_static_steps(readings: TriadReadings, rows, tau0: float) -> None:
    """Every time step of the static record is 1/sample_rate_hz (±1 %), checked in pieces;
    the first one that is not is a GonioError naming its line."""
    t = frame_column(readings.data, "time_s", rows)
    for s in range(0, t.size, 1 << 16):
        base = s - 1 if s else 0                 # x[j] = t[base + j]
        x = t[base: s + (1 << 16)]
        steps = np.diff(x)
        bad = np.nonzero(np.abs(steps - tau0) > 0.01 * tau0)[0]
        for b in bad:
            k = base + int(b) + 1                # the sample after the step
            first, _, idx = rows
            pos = first + k if idx is None else int(idx[k])
            prev = first + k - 1 if idx is None else int(idx[k - 1])
            if _aside_gap(readings, prev, pos, float(steps[b]), tau0):
                continue
            raise GonioError(f"static record not sampled every 1/sample_rate_hz = {tau0:g} s "
                             f"(step {steps[b]:g} s)", file=readings.path,
                             line=int(readings.data["line"].iloc[pos]), column="time_s")


def _aside_gap(readings: TriadReadings, prev: int, pos: int, step: float, tau0: float) -> bool:
    """Whether a step of the static record between rows ``prev`` and ``pos`` is the samples
    the screening set aside there (every line between them set aside, the step one sample
    more than they are, ±1 %)."""
    if not readings.aside:
        return False
    line = readings.data["line"]
    a, b = int(line.iloc[prev]), int(line.iloc[pos])
    gone = range(a + 1, b)
    return bool(gone) and all(x in readings.aside for x in gone) \
        and abs(step - (len(gone) + 1) * tau0) <= 0.01 * tau0


def averaging_time(readings: TriadReadings, scale_per_dps, *, target_deg: float = 0.1,
                   fraction: float = 0.1, test_rate_dps: float | None = None,
                   shortest_dwell_s: float = math.nan) -> AveragingTime | None:
    """Averaging time from the Allan deviation of the ``static`` record (article eq. 30b).

    The outputs are turned into °/s with each channel's scale factor; the limit is
    ω_TR sin ψ_T · ``fraction``; the result is the shortest octave τ at which every
    channel's Allan deviation is below it. ``None`` when the file has no static record.
    """
    data = readings.data
    rows = rows_where(data, lambda d: d["test"] == "static")    # never a copy of the rows
    if rows[1] < 16:
        return None
    rates = readings.rows("alignment")["rate_dps"].abs()
    if test_rate_dps is None:
        test_rate_dps = float(rates[rates > 0].min()) if (rates > 0).any() else 0.0
    if test_rate_dps <= 0:
        return None
    limit = alignment_noise_limit_dps(test_rate_dps, math.radians(target_deg), fraction)
    tau0 = 1.0 / readings.sample_rate_hz
    _check_static_steps(readings, rows, tau0)
    need, tmin, amin, adevs = [], [], [], []
    tau = None
    for i, c in enumerate(OUT):
        y = frame_column(data, c, rows) / float(scale_per_dps[i])
        # a long record is read in pieces (bounded memory); the estimator removes its mean
        res = allan_deviation(y if isinstance(y, Record) else y - y.mean(), tau0, "rate",
                              taus="octave", alpha=0)
        tau = res.tau_s
        ok = np.nonzero(res.adev <= limit)[0]
        need.append(float(res.tau_s[ok[0]]) if ok.size else math.nan)
        j = int(np.argmin(res.adev))
        tmin.append(float(res.tau_s[j]))
        amin.append(float(dps_to_dph(res.adev[j])))
        adevs.append(dps_to_dph(res.adev).tolist())
    sufficient = bool(np.all(np.isfinite(need)) and shortest_dwell_s >= max(need))
    return AveragingTime(limit, target_deg, test_rate_dps, need, tmin, amin,
                         float(shortest_dwell_s), sufficient, list(map(float, tau)), adevs)


#: Monte Carlo trials held in memory at once; more are combined chunk by chunk.
MC_CHUNK = 100_000
#: Normal draws made at once inside a chunk (bounded temporaries of the vectorised trials).
MC_DRAWS = 1 << 20


def chunked_std(batch, n: int, chunk: int = MC_CHUNK) -> tuple[np.ndarray, np.ndarray]:
    """Sample standard deviations (ddof 1) of the two vectors per trial that ``batch(k)``
    returns for ``k`` trials at once (two fresh arrays of k rows, which this function may
    change), over ``n`` trials, in bounded
    memory: chunks of ``chunk`` trials combined by Chan et al.'s pairwise update (count,
    mean, sum of squared deviations). Up to one chunk the result is ``np.std`` of all
    trials, exactly.

    >>> it = iter(range(10))
    >>> def f(k):
    ...     v = np.array([float(next(it)) for _ in range(k)])[:, None]
    ...     return v, 2 * v
    >>> [round(float(a[0]), 6) for a in chunked_std(f, 10, chunk=3)]
    [3.02765, 6.055301]
    """
    acc = None
    done = 0
    while done < n:
        k = min(chunk, n - done)
        blocks = batch(k)
        if acc is None and k == n:
            return tuple(np.std(b, axis=0, ddof=1) for b in blocks)
        stats_ = []
        for b in blocks:
            mean = b.mean(axis=0)
            b -= mean                      # the block is this function's: deviations in place
            stats_.append((k, mean, np.einsum("ij,ij->j", b, b)))
        del blocks
        if acc is None:
            acc = stats_
        else:
            merged = []
            for (na, ma, sa), (nb, mb_, sb) in zip(acc, stats_):
                d = mb_ - ma
                nn = na + nb
                merged.append((nn, ma + d * nb / nn, sa + sb + d * d * na * nb / nn))
            acc = merged
        done += k
    return tuple(np.sqrt(sq / (cnt - 1)) for cnt, _, sq in acc)


def _mc_trials(x: np.ndarray, w: np.ndarray, fitted: np.ndarray, sd: np.ndarray, rng,
               zb: np.ndarray | None = None, sd_b: np.ndarray | None = None):
    """The Monte Carlo trials of :func:`estimate_alignment`, vectorised: ``trials(k)`` draws
    k synthetic outputs (fitted + sd·N(0, 1), the draws in the order of one trial after the
    other), refits each channel by weighted least squares and returns (θ, derived) with k
    rows each, in pieces of at most :data:`MC_DRAWS` normal draws.

    The weighted least-squares estimate is linear in the outputs, θ̂_i = P y_i with
    P = (XᵀWX)⁻¹XᵀW the same (4 × dwells) matrix for every trial (X has full column rank,
    checked before), so P is formed once (``lstsq`` of the weighted design against the
    weights, the solve the per-trial fit made) and a piece of trials is three small products,
    θ̂_i = θ_i + (P sd_i) z_i: the same estimates as refitting every trial, to rounding
    (tested against a per-trial ``lstsq`` loop), without a least-squares solve per piece.
    The normal draws go into one reused buffer (the same numbers as a fresh array).

    With block offsets (``zb`` the (rows, blocks) indicator, ``sd_b`` σ_B per channel, any
    > 0; :func:`variance_components`) each trial's outputs also get one N(0, σ_B²) offset
    per block, drawn after the trial's dwell draws (a trial draws (rows + blocks, 3))."""
    sw = np.sqrt(w)
    proj, *_ = np.linalg.lstsq(x * sw[:, None], np.diag(sw), rcond=None)   # P, (4, rows)
    # channel i's fit applied to its draws: P with sd[:, i] folded in, (3, 4, rows)
    proj_sd = np.ascontiguousarray(proj[None, :, :] * sd.T[:, None, :])
    if zb is not None and sd_b is not None and np.any(np.asarray(sd_b) > 0):
        pz = proj @ zb                                                      # (4, blocks)
        proj_sd = np.ascontiguousarray(np.concatenate(
            [proj_sd, pz[None, :, :] * np.asarray(sd_b, float)[:, None, None]], axis=2))
    rows_drawn = proj_sd.shape[2]
    theta0 = (proj @ fitted).T.reshape(12)         # the fit's θ (P X θ = θ)
    per = max(1, MC_DRAWS // (rows_drawn * 3))
    z_buf = np.empty((min(per, MC_CHUNK), rows_drawn, 3))

    def trials(k: int):
        th = np.empty((k, 12))
        der = np.empty((k, max(sl.stop for sl in _DERIVED_SLICES.values())))
        for a in range(0, k, per):
            kk = min(per, k - a)
            z = z_buf[:kk] if kk <= z_buf.shape[0] else np.empty((kk,) + z_buf.shape[1:])
            rng.standard_normal(out=z)                    # (kk, rows [+ blocks], 3)
            t = th[a:a + kk]
            for i in range(3):        # einsum: no BLAS threads spinning on a shared machine
                np.einsum("kr,pr->kp", z[:, :, i], proj_sd[i], out=t[:, 4 * i: 4 * i + 4])
            t += theta0
            der[a:a + kk] = _derived_trials(t)
        return th, der
    return trials


#: The rate error's bound in the bound-condition statement, in units of the table
#: certificate's standard uncertainty: its expanded uncertainty at k = 2 (a normal error has
#: no bound; the certificate's 95 % statement is taken as one, JCGM 100 4.3.4 read backwards).
RATE_ERROR_BOUND_K = 2.0


def table_bound_vectors(m: np.ndarray, rate_bound_rel: float, orientation_bound_rad: float
                        ) -> list[np.ndarray]:
    """The rate table's errors at their bounds as shifts of θ (12, rows of [M | b] stacked),
    one per independent error, in the first-order model of :func:`table_type_b_cov`: the rate
    error at ``rate_bound_rel`` shifts every M_ia by M_ia ε; each axis component δ_aj
    (j ≠ a) at ``orientation_bound_rad`` shifts column a by M_·j δ_aj. The worst combination
    of the errors within their bounds moves a linear function g(θ) by at most Σ_k |∇g · s_k|
    (each error takes the sign that adds; JCGM 100 5.1.2's sensitivities, summed in absolute
    value instead of in quadrature): :func:`table_bound`.

    >>> v = table_bound_vectors(np.diag([50.0, 50.0, 50.0]), 1e-3, 2e-3)
    >>> len(v), round(float(v[0][0]), 6), round(float(v[1][4]), 6)   # ε: M_xx; δ_xy: M_yx
    (7, 0.05, 0.1)
    """
    m = np.asarray(m, dtype=float)
    idx = np.array([[4 * i + j for j in range(3)] for i in range(3)])
    out = []
    v = np.zeros(12)
    v[idx] = m * rate_bound_rel
    out.append(v)
    for a in range(3):
        for j in range(3):
            if j != a:
                v = np.zeros(12)
                v[idx[:, a]] = m[:, j] * orientation_bound_rad
                out.append(v)
    return out


def table_bound(f, theta: np.ndarray, vectors: list[np.ndarray]) -> np.ndarray:
    """The largest first-order change of f(θ) that the table's errors within their bounds
    give (:func:`table_bound_vectors`): Σ_k |J s_k|, J the Jacobian of f at θ
    (:func:`gum_propagate` of the rank-one covariance s_k s_kᵀ gives (J s_k)²).

    >>> s = [np.array([1.0, 0.0]), np.array([0.0, 1.0])]
    >>> table_bound(lambda t: np.array([t[0] - 2.0 * t[1]]), np.array([1.0, 1.0]), s)
    array([3.])
    """
    total = 0.0
    for v in vectors:
        total = total + np.sqrt(np.clip(np.diag(gum_propagate(f, theta, np.outer(v, v))),
                                        0, None))
    return np.atleast_1d(total)


def estimate_alignment(readings: TriadReadings, *, robust: bool = False,
                       monte_carlo: int = 0, seed: int = 0, target_deg: float = 0.1,
                       rate_u_rel: float = 0.0, orientation_u_rad: float = 0.0,
                       ) -> AlignmentResult:
    """Estimate M and b from the ``alignment`` rows (see the module docstring).

    ``monte_carlo`` > 0 adds Monte Carlo uncertainties from that many trials (seeded,
    so the result is reproducible). ``rate_u_rel`` and ``orientation_u_rad`` (the rate
    table's relative rate uncertainty and the standard uncertainty of each component of
    its axis in the reference frame) add the table's Type B covariance
    (:func:`table_type_b_cov`) to the fit's; ``type_b`` keeps that part on its own (the
    Monte Carlo redraws the noise only).
    """
    rows = readings.rows("alignment")
    if len(rows) < 5:
        raise GonioError(f"{readings.path}: need at least 5 alignment dwells, got {len(rows)}")
    x = np.column_stack([dwell_regressors(rows, readings.latitude_deg), np.ones(len(rows))])
    if np.linalg.matrix_rank(x) < 4:
        raise GonioError(f"{readings.path}: the dwells do not determine M and b (rotations "
                         "about all three axes are needed)")
    w = rows["n_samples"].to_numpy(float)
    w = w / w.max()
    thetas, covs, sig, dof, outl, comps = [], [], [], [], [], []
    blocks = dwell_blocks(rows)
    resid = np.empty((len(rows), 3))
    for i, c in enumerate(OUT):
        y = rows[c].to_numpy(float)
        th, _, s, rw, nu = _fit_channel(x, y, w, robust)
        cv, nu_p, s_w, s_b, pz = variance_components(x, y, w * rw, th, blocks, nu)
        thetas.append(th)
        covs.append(cv)
        sig.append(s)
        dof.append(nu_p)
        comps.append((s_w, s_b, pz))
        resid[:, i] = y - x @ th
        if robust:
            for k in np.nonzero(rw < 0.5)[0]:
                outl.append({"line": int(rows["line"].iloc[k]), "channel": c,
                             "weight": float(rw[k])})
    theta = np.concatenate(thetas)
    cov = np.zeros((12, 12))
    for i, cv in enumerate(covs):
        cov[4 * i:4 * i + 4, 4 * i:4 * i + 4] = cv
    mb = theta.reshape(3, 4)
    m, b = mb[:, :3], mb[:, 3]
    der = _derived(theta)
    cov_b = table_type_b_cov(m, rate_u_rel, orientation_u_rad)
    cov = cov + cov_b
    u_der = np.sqrt(np.clip(np.diag(gum_propagate(_derived, theta, cov)), 0, None))
    # leakage after alignment: δL = −M⁻¹ δM (first order)
    minv = np.linalg.inv(m)

    def leak(t):
        mm = t.reshape(3, 4)[:, :3]
        return (minv @ mm - np.eye(3)).ravel()
    leak_u = np.sqrt(np.clip(np.diag(gum_propagate(leak, theta, cov)), 0, None)).reshape(3, 3)
    type_b = None
    if np.any(cov_b):
        type_b = {"rate_u_rel": float(rate_u_rel), "orientation_u_rad": float(orientation_u_rad),
                  "u_theta": np.sqrt(np.diag(cov_b)),
                  "u_derived": _split(np.sqrt(np.clip(np.diag(
                      gum_propagate(_derived, theta, cov_b)), 0, None))),
                  "leakage_u": np.sqrt(np.clip(np.diag(gum_propagate(leak, theta, cov_b)),
                                               0, None)).reshape(3, 3),
                  # the bound condition: each error at its bound, the worst combination
                  "rate_bound_rel": RATE_ERROR_BOUND_K * float(rate_u_rel),
                  "orientation_bound_rad": float(orientation_u_rad) * math.sqrt(3.0)}
        vecs = table_bound_vectors(m, type_b["rate_bound_rel"], type_b["orientation_bound_rad"])
        type_b["a_theta"] = table_bound(lambda t: t, theta, vecs)
        type_b["a_derived"] = _split(table_bound(_derived, theta, vecs))
        type_b["a_leakage"] = table_bound(leak, theta, vecs).reshape(3, 3)
    u_mc = u_mc_theta = None
    if monte_carlo > 0:
        rng = np.random.default_rng(np.random.SeedSequence([int(seed), 1801]))
        fitted = x @ mb.T
        sd = np.array([cp[0] for cp in comps])[None, :] / np.sqrt(w)[:, None]
        sd_b = np.array([cp[1] for cp in comps])
        zb = (blocks[:, None] == np.arange(int(blocks.max()) + 1)[None, :]).astype(float)
        u_mc_theta, u_der_mc = chunked_std(_mc_trials(x, w, fitted, sd, rng, zb, sd_b),
                                           int(monte_carlo))
        u_mc = _split(u_der_mc)
    dof_theta = np.array(dof)                        # (3, 4): ν of M_i1..M_i3, b_i
    dofa = dof_theta[:, :3].min(axis=1)
    k = stats.t.ppf(0.5 + COVERAGE / 2, dofa)
    rates = rows["rate_dps"].abs()
    shortest = float(rows.loc[rates > 0, "duration_s"].min()) if (rates > 0).any() else math.nan
    avg = averaging_time(readings, np.diag(m), target_deg=target_deg, shortest_dwell_s=shortest)
    return AlignmentResult(m, b, cov, np.array(sig), dofa, k, _split(der), _split(u_der),
                           u_mc, u_mc_theta, robust, outl, leak_u, avg, len(rows),
                           readings.metadata.get("output_unit", ""),
                           rows["line"].tolist(), resid, dof_theta,
                           np.array([[cp[0], cp[1]] for cp in comps]), type_b)


# ------------------------------------------------------------ IEC 62047-20 5.2
def cross_axis_sensitivity_iec(out_cross: float, out_rest: float, scale_factor: float,
                               rate_dps: float) -> float:
    """Cross-axis sensitivity of a single-axis gyro (IEC 62047-20 5.2.3, eq. 20–23, with
    the reading taken in the project's digest: ω_x = (Out_x − Out_rest)/SF, K_x = ω_x/ω;
    the printed Out × SF is dimensionally wrong).

    >>> round(cross_axis_sensitivity_iec(3.0, 0.0, 6.0, 100.0), 6)   # 3 mV, 6 mV/(°/s), 100 °/s
    0.005
    """
    if scale_factor == 0 or rate_dps == 0:
        raise GonioError("scale factor and applied rate must be non-zero")
    return (out_cross - out_rest) / scale_factor / rate_dps


def cross_axis_sensitivity_pm(out_plus: float, out_minus: float, scale_factor: float,
                              rate_dps: float) -> float:
    """Bias-free variant (not in IEC 62047-20; flagged as a refinement): rates +ω and −ω
    about the non-input axis, K = (Out₊ − Out₋) / (2 SF ω) (article eq. 28–30a applied to
    one gyro).

    >>> round(cross_axis_sensitivity_pm(1003.0, 997.0, 6.0, 100.0), 6)
    0.005
    """
    if scale_factor == 0 or rate_dps == 0:
        raise GonioError("scale factor and applied rate must be non-zero")
    return (out_plus - out_minus) / (2.0 * scale_factor * rate_dps)


def cross_axis_table(result: AlignmentResult) -> pd.DataFrame:
    """Cross-axis sensitivities S_ij = M_ij/M_ii of every gyro (IEC 62047-20 5.2 for each
    gyro of the triad: its output for a rate about a non-input axis, per unit scale factor
    and rate) with GUM and, when computed, Monte Carlo standard uncertainties."""
    rows = []
    for n, name in enumerate(OFFDIAG):
        rows.append({"gyro": name[0], "about": name[1],
                     "sensitivity": float(result.derived["cross_axis"][n]),
                     "u_gum": float(result.u_derived["cross_axis"][n]),
                     "u_mc": math.nan if result.u_mc is None else float(result.u_mc["cross_axis"][n])})
    return pd.DataFrame(rows)
