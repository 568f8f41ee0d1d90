"""Equal-division averaging: a rotary table and a goniometer calibrate each other.

A goniometer has no fixed zero on the circle; a rotary table does. Measuring
from ``n`` start positions of the table and stepping the table ``m`` equal steps
of ``Δ = 360°/m`` from each, both zeroed at each start, the observed deviation
(goniometer minus table) is

    D[r, k, j] = g(jΔ) − [t(x_k + jΔ) − t(x_k)] + e[r, k, j]

(``r`` repeat, ``k`` start, ``j = 1..m``, ``j = m`` the full turn), where
``t(x)`` is the table's positioning error at its absolute position ``x``
(indicated minus true) and ``g(φ)`` the goniometer's error after turning ``φ``
from its zero. Averaging over the starts cancels every table harmonic whose
order is not a multiple of ``n`` (IEC 62047-20:2014 Annex A.3, equal-division
averaging); averaging over the steps then separates the table's error from the
goniometer's. This module does the same thing as one least-squares fit, which
also handles ``n ≠ m``, repeats, and gives standard uncertainties.

Contents
========
:func:`equal_division_analysis`   the least-squares separation → :class:`EdaResult`
:func:`harmonic_transfer`         per harmonic order: observable, aliased, unobservable
:func:`blind_table_basis`         the table errors a set of starts cannot see
:func:`compare_tables`            two tables, same goniometer as transfer standard
:func:`simulate_eda_matrix`       a small synthetic generator (tests, examples)
:func:`eda_matrix_from_readings`  a readings file's ``equal_division`` rows → D
:func:`load_eda_protocol`         the ``[equal_division]`` protocol section (protocols/eda.toml)

Conventions
===========
* ``D`` is in arcseconds; positions and angles in degrees.
* Gauge: the model only sees differences of ``t``, so ``t`` is known up to a
  constant, and -- when the starts do not cover every position -- up to every
  table harmonic whose order is a multiple of ``n`` (these look exactly like a
  goniometer error). We report the table error *orthogonal* to that
  unobservable subspace: with ``gauge="closure"`` the table errors sum to zero
  over the ``m`` positions (the circle closes), with ``gauge="zero"`` the error
  at the first grid position (absolute 0°) is zero instead. The unobservable
  table harmonics are attributed to the goniometer curve, which therefore
  reads ``g(jΔ) − [τ(jΔ) − τ(0)]`` where ``τ`` is the table's part made of
  orders that are multiples of ``n`` (zero when ``n = m``).
* ``g`` is estimated at ``jΔ`` for ``j = 1..m``; ``g(360°)`` is the full-turn
  error, which a goniometer with a correct scale factor has zero (its zero
  closes). The table's part of the ``j = m`` column cancels identically, so the
  ``j = m`` column checks closure (:class:`ClosureCheck`).
* Restriction: every start position must lie on the step grid (a multiple of
  ``Δ`` modulo 360°); then all visited table positions are the ``m`` grid
  points and the step links every position to every other. Equally spaced
  starts ``x_k = k·360°/n`` satisfy this exactly when ``n`` divides ``m``.
  Other start sets raise :class:`~gonio.errors.GonioError`.
* Noise (:func:`noise_whitening`): by default ``random_walk`` — a gyro's angle
  random walk and any Earth-rate compensation residual accumulate from each
  zeroing, so the readings of one start form a random walk; the fit whitens each
  start by first differences (generalised least squares). ``white`` is the classic
  A.3 model of independent readings, which on a gyro understates the
  uncertainty (≈ 1.8× on the bench). Either way one common standard deviation is
  estimated from the whitened residuals, pooled over repeats.

References
==========
IEC 62047-20:2014 (JIS C 5630-20:2015) Annex A.3, equal-division averaging.
JCGM 100:2008 (GUM) 4.2 and H.3 (Type A evaluation, least-squares fits).
R. Probst et al., "The new PTB angle comparator", Meas. Sci. Technol. 9 (1998)
1059 (cross-calibration of circle divisions; closure).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import scipy.sparse as sp

from gonio.physics.kinematics import trapezoid_duration_s
from gonio.errors import GonioError
from gonio.specs.ogam_draft.readings import Readings
from gonio.units import ARCSEC_PER_DEG
from gonio.specs.ogam_draft.protocol import load_protocol
from gonio.specs.ogam_draft.protocol import EdaProtocol

#: Tolerance for "a start lies on the step grid", in units of the step (–).
GRID_TOL_STEPS = 1e-6
#: Tolerance for a table reading to be taken as step j, degrees.
STEP_TOL_DEG = 1e-3
#: Relative eigenvalue threshold below which a normal-matrix direction is null (–).
NULL_RTOL = 1e-9
#: |z| above which the full-turn closure is reported as not consistent with zero (–).
CLOSURE_Z_LIMIT = 3.0


# --------------------------------------------------------------------------- results
@dataclass(frozen=True)
class ClosureCheck:
    """Full-circle closure of an equal-division measurement.

    Attributes
    ----------
    table_sum_arcsec : float
        Sum of the reported table errors over the ``m`` positions (0 by
        construction with ``gauge="closure"``; ``m`` times the mean otherwise).
    full_turn_arcsec : float
        Estimated goniometer error after one full turn, ``g(360°)``: the mean
        of the ``j = m`` column, in which the table's part cancels exactly.
    u_full_turn_arcsec : float
        Its standard uncertainty.
    z : float
        ``full_turn_arcsec / u_full_turn_arcsec``.
    per_start_full_turn_arcsec : numpy.ndarray
        The ``j = m`` column averaged over repeats, one value per start.
    consistent : bool
        ``|z| <= CLOSURE_Z_LIMIT`` — the full turn closes within its noise.
    """

    table_sum_arcsec: float
    full_turn_arcsec: float
    u_full_turn_arcsec: float
    z: float
    per_start_full_turn_arcsec: np.ndarray
    consistent: bool


@dataclass(frozen=True)
class EdaResult:
    """Result of :func:`equal_division_analysis` (all errors in arcseconds).

    Attributes
    ----------
    table_position_deg : numpy.ndarray, shape (m,)
        Absolute table positions ``pΔ``, ``p = 0..m−1``.
    table_error_arcsec, table_u_arcsec : numpy.ndarray, shape (m,)
        Table positioning error (indicated − true) and standard uncertainty,
        in the stated ``gauge``, unobservable harmonics removed.
    table_cov_arcsec2 : numpy.ndarray, shape (m, m)
        Covariance of ``table_error_arcsec``.
    gonio_angle_deg : numpy.ndarray, shape (m,)
        Angles turned since zeroing, ``jΔ``, ``j = 1..m``.
    gonio_error_arcsec, gonio_u_arcsec : numpy.ndarray, shape (m,)
        Goniometer error at those angles and standard uncertainty.
    gonio_cov_arcsec2 : numpy.ndarray, shape (m, m)
        Covariance of ``gonio_error_arcsec``.
    residual_std_arcsec : float
        Standard deviation of one reading from the residuals, ``sqrt(RSS/dof)``.
    dof : int
        Residual degrees of freedom, readings minus identifiable parameters.
    residuals_arcsec : numpy.ndarray, shape (R, n, m)
        Residuals of the fit, whitened (for ``random_walk``: of the step increments).
    start_deg : numpy.ndarray, shape (n,)
        Table positions at zeroing.
    step_deg : float
        The step ``Δ``.
    repeats : int
        Number of repeated matrices ``R``.
    gauge : str
        ``"closure"`` or ``"zero"``.
    unobservable_dim : int
        Dimension of the table subspace the data cannot see beyond the constant
        (``m/n − 1`` for equally spaced starts).
    harmonics : pandas.DataFrame
        :func:`harmonic_transfer` for orders ``1..max_order``.
    closure : ClosureCheck
        Full-circle closure check.
    """

    table_position_deg: np.ndarray
    table_error_arcsec: np.ndarray
    table_u_arcsec: np.ndarray
    table_cov_arcsec2: np.ndarray
    gonio_angle_deg: np.ndarray
    gonio_error_arcsec: np.ndarray
    gonio_u_arcsec: np.ndarray
    gonio_cov_arcsec2: np.ndarray
    residual_std_arcsec: float
    dof: int
    residuals_arcsec: np.ndarray
    start_deg: np.ndarray
    step_deg: float
    repeats: int
    gauge: str
    unobservable_dim: int
    harmonics: pd.DataFrame = field(repr=False)
    closure: ClosureCheck = field(repr=False)
    noise: str = "random_walk"
    coupling: "CouplingFit | None" = None

    @property
    def n_starts(self) -> int:
        """Number of starts ``n``."""
        return int(self.start_deg.size)

    @property
    def m_points(self) -> int:
        """Points per revolution ``m``."""
        return int(self.table_position_deg.size)

    def table_frame(self) -> pd.DataFrame:
        """The table error as a DataFrame (position, error, uncertainty)."""
        return pd.DataFrame({"position_deg": self.table_position_deg,
                             "error_arcsec": self.table_error_arcsec,
                             "u_arcsec": self.table_u_arcsec})

    def to_dict(self) -> dict:
        """Plain, JSON-ready summary (floats rounded to 1e-6 arcsec for determinism)."""
        def r(a):
            return [round(float(v), 6) for v in np.ravel(a)]
        c = self.closure
        return {
            "n_starts": self.n_starts, "m_points": self.m_points, "repeats": self.repeats,
            "step_deg": round(float(self.step_deg), 9), "start_deg": r(self.start_deg),
            "gauge": self.gauge, "noise": self.noise, "unobservable_dim": self.unobservable_dim,
            "residual_std_arcsec": round(float(self.residual_std_arcsec), 6), "dof": self.dof,
            "table": {"position_deg": r(self.table_position_deg),
                      "error_arcsec": r(self.table_error_arcsec),
                      "u_arcsec": r(self.table_u_arcsec)},
            "goniometer": {"angle_deg": r(self.gonio_angle_deg),
                           "error_arcsec": r(self.gonio_error_arcsec),
                           "u_arcsec": r(self.gonio_u_arcsec)},
            "closure": {"table_sum_arcsec": round(float(c.table_sum_arcsec), 6),
                        "full_turn_arcsec": round(float(c.full_turn_arcsec), 6),
                        "u_full_turn_arcsec": round(float(c.u_full_turn_arcsec), 6),
                        "z": round(float(c.z), 6), "consistent": bool(c.consistent),
                        "per_start_full_turn_arcsec": r(c.per_start_full_turn_arcsec)},
            "coupling": None if self.coupling is None else self.coupling.to_dict(),
            "harmonics": [{k: (v.item() if hasattr(v, "item") else v) for k, v in row.items()}
                          for row in self.harmonics.round(9).to_dict(orient="records")],
        }


@dataclass(frozen=True)
class CouplingFit:
    """The tilt × Earth-rate coupling estimated as a nuisance parameter.

    Model: a sensing axis tilted by ψ on a table whose axis is not along the Earth's
    axis picks up Ω_⊥ sin ψ cos(θ + α) as the table turns (gonio.coupling); after
    the compensation measured at rest at the start x_k, the reading (k, j) taken t
    after zeroing is off by a·P_kj + b·Q_kj with P = ∫(cos θ − cos x_k) dt,
    Q = ∫(sin θ − sin x_k) dt over the time since zeroing, θ the absolute table angle
    (:func:`coupling_design`): a first harmonic of the absolute position growing with
    the time since zeroing. (a, b) = Ω_⊥ tan ψ (cos α, −sin α), in ″/s.

    Attributes
    ----------
    separable : bool
        Whether (a, b) could be estimated jointly with the table and goniometer
        errors (the design is well conditioned). If not, the table and goniometer
        errors are those of the plain fit and ``max_effect_arcsec`` is the size of
        the coupling at the stated ``bound_amplitude_arcsec_s`` (when known), which
        the result does *not* include.
    a_arcsec_s, b_arcsec_s, u_a_arcsec_s, u_b_arcsec_s : float
        Estimates and standard uncertainties (NaN when not separable).
    amplitude_arcsec_s, u_amplitude_arcsec_s : float
        hypot(a, b) = Ω_⊥ tan ψ and its uncertainty.
    max_effect_arcsec : float
        Largest |a P + b Q| over the readings (fitted), or at the bound.
    note : str
        What was done, in words (English; the certificate states it from ``reason`` and
        the numbers in the page's language).
    reason : str
        ``"estimated"`` (fitted and removed), ``"not_separable"`` (the joint design's
        ``condition_number`` is above :data:`COUPLING_COND_LIMIT`) or ``"no_times"``
        (the readings carry no ``time_s``).
    condition_number : float
        Of the scaled joint normal matrix where it made the coupling not separable.
    """

    separable: bool
    a_arcsec_s: float
    b_arcsec_s: float
    u_a_arcsec_s: float
    u_b_arcsec_s: float
    amplitude_arcsec_s: float
    u_amplitude_arcsec_s: float
    max_effect_arcsec: float
    note: str
    reason: str = "estimated"
    condition_number: float = math.nan

    def to_dict(self) -> dict:
        def f(x):
            x = float(x)
            return round(x, 9) if math.isfinite(x) else None
        return {"separable": bool(self.separable), "a_arcsec_s": f(self.a_arcsec_s),
                "b_arcsec_s": f(self.b_arcsec_s), "u_a_arcsec_s": f(self.u_a_arcsec_s),
                "u_b_arcsec_s": f(self.u_b_arcsec_s),
                "amplitude_arcsec_s": f(self.amplitude_arcsec_s),
                "u_amplitude_arcsec_s": f(self.u_amplitude_arcsec_s),
                "max_effect_arcsec": f(self.max_effect_arcsec), "note": self.note,
                "reason": self.reason, "condition_number": f(self.condition_number)}


#: Condition number of the joint normal matrix above which the coupling is reported
#: as not separable from the table and goniometer errors (–).
COUPLING_COND_LIMIT = 1e8


def coupling_design(time_s, start_deg, step_deg: float, read_delay_s: float,
                    rate_dps: float, accel_dps2: float | None = None) -> np.ndarray:
    """The coupling's design columns P, Q (seconds) of every reading, shape (n, m, 2).

    ``time_s``: time from zeroing to reading, shape (n, m) (or (R, n, m): the mean
    over repeats is used). The table rests at x_k + (i−1)Δ until move i, which ends
    ``read_delay_s`` before reading i and lasts Δ/rate at constant rate or, with the
    table's acceleration ``accel_dps2`` known, the rest-to-rest trapezoid's duration
    (:func:`gonio.physics.kinematics.trapezoid_duration_s`: a 30° step at 60 °/s and
    60 °/s² takes 1.41 s, not 0.5 s); each move's own ∫cos θ dt, ∫sin θ dt is integrated
    over its angle profile (:func:`_move_integrals`). P_kj = ∫₀^t_kj (cos θ − cos x_k) dt,
    Q likewise with sin (compensation measured at rest at the start, as the procedure
    of protocols/eda.toml and the virtual bench do; a constant residual rate is the
    same for every start and is absorbed by the goniometer curve).

    Examples
    --------
    One start at 0°, steps of 90° read at 10 s and 20 s, 2 s read delay, 90 °/s: the
    table rests at 0° until 7 s, turns to 90° by 8 s (a ramp: ∫cos = ∫sin = 2/π s),
    rests until 17 s, turns to 180° by 18 s (∫cos = −2/π, ∫sin = 2/π):
    P_1 = 7 + 2/π − 10 = −2.36338, Q_1 = 2/π + 2 = 2.63662;
    P_2 = 7 + 2/π + 0 − 2/π − 2 − 20 = −15, Q_2 = 2/π + 9 + 2/π = 10.27324.

    >>> coupling_design([[10.0, 20.0]], [0.0], 90.0, 2.0, 90.0)[0].round(5).tolist()
    [[-2.36338, 2.63662], [-15.0, 10.27324]]

    With 90 °/s² each move takes 2 s (6–8 s, 16–18 s), its angle ½·a·s² then
    symmetric: ∫cos = ∫sin = I = ∫₀¹ [cos(πu²/4) + sin(πu²/4)] du = 1.19054 (scipy's
    quad): P_1 = 6 + I − 10 = −2.80946, Q_1 = I + 2 = 3.19054, P_2 = 6 + I − I − 2 − 20
    = −16, Q_2 = I + 8 + I = 10.38108.

    >>> coupling_design([[10.0, 20.0]], [0.0], 90.0, 2.0, 90.0, 90.0)[0].round(5).tolist()
    [[-2.80946, 3.19054], [-16.0, 10.38108]]
    """
    t = np.asarray(time_s, dtype=float)
    if t.ndim == 3:
        t = t.mean(axis=0)
    n, m = t.shape
    x0 = np.radians(np.asarray(start_deg, dtype=float))
    d, A, B = _move_integrals(step_deg, rate_dps, accel_dps2)
    tau = t - read_delay_s - d / 2.0                       # middle of move j, (n, m)
    ends = t - read_delay_s                                # arrival of move j
    step = np.radians(step_deg)
    out = np.zeros((n, m, 2))
    for k in range(n):
        edges = np.concatenate([[0.0], tau[k]])            # position i from edges[i]
        pos = x0[k] + step * np.arange(m + 1)
        # the real motion minus the jump at the middle, per move (from its start angle)
        cp, sp_ = np.cos(pos[:-1]), np.sin(pos[:-1])
        half = d / 2.0
        corr_c = cp * A - sp_ * B - half * (cp + np.cos(pos[1:]))
        corr_s = sp_ * A + cp * B - half * (sp_ + np.sin(pos[1:]))
        for j in range(m):
            tj = t[k, j]
            lo = edges[: j + 2]
            hi = np.minimum(np.concatenate([edges[1: j + 2], [tj]]), tj)
            dur = np.clip(hi - lo, 0.0, None)
            p = pos[: j + 2]
            done = ends[k, : j + 1] <= tj                  # moves completed by reading j
            out[k, j, 0] = (float(np.cos(p) @ dur) + float(corr_c[: j + 1] @ done)
                            - math.cos(x0[k]) * tj)
            out[k, j, 1] = (float(np.sin(p) @ dur) + float(corr_s[: j + 1] @ done)
                            - math.sin(x0[k]) * tj)
    return out


def _move_integrals(step_deg: float, rate_dps: float,
                    accel_dps2: float | None) -> tuple[float, float, float]:
    """Duration T (s) of one step and ∫₀ᵀ cos φ(s) ds, ∫₀ᵀ sin φ(s) ds (s) of its angle
    profile φ (0 → Δ): constant rate, or with ``accel_dps2`` the rest-to-rest trapezoid
    (:func:`gonio.physics.kinematics.trapezoid_duration_s`); Gauss–Legendre on each
    smooth piece (exact to rounding for these profiles' smoothness).

    >>> T, A, B = _move_integrals(90.0, 90.0, None)     # linear ramp over 1 s: 2/π each
    >>> round(T, 9), round(A, 9), round(B, 9)
    (1.0, 0.636619772, 0.636619772)
    """
    D = math.radians(step_deg)
    v = math.radians(rate_dps)
    if accel_dps2 is None:
        pieces = [(0.0, D / v, lambda s: v * s)]
        T = D / v
    else:
        a = math.radians(accel_dps2)
        ta = v / a if D >= v * v / a else math.sqrt(D / a)
        vp = a * ta
        tc = max(D - a * ta * ta, 0.0) / vp
        T = trapezoid_duration_s(step_deg, rate_dps, accel_dps2)
        pieces = [(0.0, ta, lambda s: 0.5 * a * s * s),
                  (ta, ta + tc, lambda s: 0.5 * a * ta * ta + vp * (s - ta)),
                  (ta + tc, T, lambda s: D - 0.5 * a * (T - s) ** 2)]
    x, w = np.polynomial.legendre.leggauss(24)
    A = B = 0.0
    for lo, hi, phi in pieces:
        if hi <= lo:
            continue
        s_ = 0.5 * (hi - lo) * x + 0.5 * (hi + lo)
        f = phi(s_)
        A += 0.5 * (hi - lo) * float(w @ np.cos(f))
        B += 0.5 * (hi - lo) * float(w @ np.sin(f))
    return T, A, B

@dataclass(frozen=True)
class TableComparison:
    """Result of :func:`compare_tables` (arcseconds).

    Attributes
    ----------
    position_deg : numpy.ndarray
        Table positions common to both calibrations.
    difference_arcsec, u_difference_arcsec : numpy.ndarray
        ``t_a − t_b`` at those positions, re-centred to zero mean over them
        (the difference is defined only up to a constant), and its standard
        uncertainty.
    cov_arcsec2 : numpy.ndarray
        Covariance of ``difference_arcsec``.
    gonio_chi2 : float
        ``Σ (g_a − g_b)² / (u_a² + u_b²)`` over the common goniometer angles:
        the transfer standard should read the same in both runs.
    gonio_points : int
        Number of goniometer angles in ``gonio_chi2``.
    """

    position_deg: np.ndarray
    difference_arcsec: np.ndarray
    u_difference_arcsec: np.ndarray
    cov_arcsec2: np.ndarray
    gonio_chi2: float
    gonio_points: int


@dataclass(frozen=True)
class EdaSimulation:
    """Output of :func:`simulate_eda_matrix` (arcseconds, degrees).

    Attributes
    ----------
    D_arcsec : numpy.ndarray, shape (R, n, m)
        Simulated deviations, goniometer minus table.
    start_deg : numpy.ndarray, shape (n,)
        ``k·360°/n``.
    step_deg : float
        ``360°/m``.
    table_true_arcsec : numpy.ndarray, shape (m,)
        The true table error at positions ``pΔ``.
    gonio_true_arcsec : numpy.ndarray, shape (m,)
        The true goniometer error at ``jΔ``, ``j = 1..m``.
    """

    D_arcsec: np.ndarray
    start_deg: np.ndarray
    step_deg: float
    table_true_arcsec: np.ndarray
    gonio_true_arcsec: np.ndarray


# --------------------------------------------------------------------------- helpers
def _grid_indices(start_deg: np.ndarray, step_deg: float) -> np.ndarray:
    """Start positions as indices on the step grid; GonioError if off the grid."""
    m = int(round(360.0 / step_deg))
    q = np.mod(start_deg, 360.0) / step_deg
    idx = np.rint(q)
    bad = np.abs(q - idx) > GRID_TOL_STEPS * max(1.0, m)
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise GonioError(
            f"start {k + 1} at {start_deg[k]:.9g}° is not a multiple of the step "
            f"{step_deg:.9g}°: the table positions x_k + jΔ do not form one grid "
            f"(equally spaced starts need n to divide m)", key="start_deg")
    return idx.astype(int) % m


def _design(p: np.ndarray, m: int) -> sp.csr_matrix:
    """Design matrix of one D matrix (rows k-major, then j = 1..m).

    Columns ``0..m−1`` are ``g(jΔ)``, ``j = 1..m``; columns ``m..2m−1`` are
    ``t(pΔ)``, ``p = 0..m−1``. Row (k, j): ``+g_j − t_{(p_k+j) mod m} + t_{p_k}``.
    """
    n = p.size
    k, j = np.meshgrid(np.arange(n), np.arange(1, m + 1), indexing="ij")
    rows = np.arange(n * m)
    kf, jf = k.ravel(), j.ravel()
    end = (p[kf] + jf) % m
    r = np.concatenate([rows, rows, rows])
    c = np.concatenate([jf - 1, m + end, m + p[kf]])
    v = np.concatenate([np.ones(n * m), -np.ones(n * m), np.ones(n * m)])
    # for j = m the two table entries coincide and cancel (summed by coo→csr)
    A = sp.coo_matrix((v, (r, c)), shape=(n * m, 2 * m)).tocsr()
    A.eliminate_zeros()
    return A


def _table_null_basis(N: np.ndarray, m: int) -> np.ndarray:
    """Orthonormal basis (m × d) of the table parts of the normal matrix's null space."""
    w, V = np.linalg.eigh(N)
    null = w <= NULL_RTOL * max(w.max(), 1.0)
    T = V[m:, null]
    if T.shape[1] == 0:  # pragma: no cover - the constant is always null
        return np.zeros((m, 0))
    U, s, _ = np.linalg.svd(T, full_matrices=False)
    return U[:, s > 1e-8]


def _orth_complement(B: np.ndarray) -> np.ndarray:
    """Orthonormal basis of the complement of the column space of orthonormal ``B``."""
    m, d = B.shape
    U, _, _ = np.linalg.svd(B, full_matrices=True)
    return U[:, d:]


# --------------------------------------------------------------------------- harmonics
def harmonic_transfer(start_deg, step_deg: float, max_order: int) -> pd.DataFrame:
    """How each harmonic order of the table and goniometer errors reaches the result.

    For every order ``h = 1..max_order``:

    * ``eda_mean_transfer`` — the gain ``|(1/n) Σ_k exp(i h x_k)|`` of the plain
      average over the starts (IEC 62047-20 Annex A.3: for equally spaced
      starts it is 1 when ``n`` divides ``h`` and 0 otherwise; it is the part of
      the table's harmonic that survives into the start-average and so
      cannot be told apart from the goniometer).
    * ``table_status`` — ``"observable"`` (recovered at the grid positions),
      ``"aliased"`` (recovered at the grid positions, but indistinguishable
      there from order ``table_alias_order`` because ``h > m/2``),
      ``"unobservable"`` (lies in the null space of the fit: it is attributed
      to the goniometer curve), ``"invisible"`` (constant on the grid:
      ``m`` divides ``h``, part of the gauge constant) or ``"partial"``
      (irregular starts: only ``table_observed_fraction`` is seen).
    * ``table_observed_fraction`` — share of the harmonic's (zero-mean) energy
      on the grid outside the null space, computed from the fit's own normal
      matrix (1 observable, 0 unobservable).
    * ``gonio_status`` — ``"observable"``, ``"aliased"`` (sampled only at
      ``jΔ``) or ``"invisible"`` (zero at every ``jΔ``: ``m`` divides ``h``,
      with ``g(0) = 0``); ``gonio_absorbs_table`` is true when the table's
      harmonic of the same order is unobservable, so the goniometer curve at
      that order carries both.

    Parameters
    ----------
    start_deg : array_like, shape (n,)
        Table positions at zeroing, degrees (on the step grid).
    step_deg : float
        Step ``Δ = 360°/m``, degrees.
    max_order : int
        Highest order reported.

    Returns
    -------
    pandas.DataFrame
        One row per order, columns as above.

    Examples
    --------
    >>> df = harmonic_transfer([0, 45, 90, 135, 180, 225, 270, 315], 15.0, 24)
    >>> df.loc[df.order.isin([1, 8, 13, 24]), ["order", "table_status", "table_alias_order"]]
        order  table_status  table_alias_order
    0       1    observable                  1
    7       8  unobservable                  8
    12     13       aliased                 11
    23     24     invisible                  0
    """
    start_deg = np.atleast_1d(np.asarray(start_deg, dtype=float))
    m = _check_step(step_deg)
    p = _grid_indices(start_deg, step_deg)
    N = (_design(p, m).T @ _design(p, m)).toarray()
    B = _table_null_basis(N, m)
    return _harmonic_frame(start_deg, p, m, B, int(max_order))


def blind_table_basis(start_deg, step_deg: float) -> np.ndarray:
    """Orthonormal basis (m × d) of the zero-mean table errors at the m grid positions that
    a comparison with starts ``start_deg`` cannot see (the fit's null space less the gauge
    constant; IEC 62047-20 A.3: for n equally spaced starts the harmonics whose orders are
    multiples of n). d = ``EdaResult.unobservable_dim``; d = 0 where the starts cover every
    position.

    >>> blind_table_basis([0, 180], 30.0).shape, blind_table_basis(np.arange(12) * 30, 30.0).shape
    ((12, 5), (12, 0))
    """
    start_deg = np.atleast_1d(np.asarray(start_deg, dtype=float))
    m = _check_step(step_deg)
    p = _grid_indices(start_deg, step_deg)
    a = _design(p, m)
    b = _table_null_basis((a.T @ a).toarray(), m)
    b = b - b.mean(axis=0, keepdims=True)                # the constant is the gauge
    u, s, _ = np.linalg.svd(b, full_matrices=False)
    return u[:, s > 1e-8]


def _harmonic_frame(start_deg, p, m, B, max_order) -> pd.DataFrame:
    h = np.arange(1, max_order + 1)
    x = 2 * np.pi * np.arange(m) / m
    V = np.exp(1j * np.outer(x, h))                      # (m, H) table harmonics on the grid
    V = V - V.mean(axis=0)                               # the constant is the gauge
    energy = np.sum(np.abs(V) ** 2, axis=0)
    # the constant is in B; remove it so B_nc spans the non-constant null space
    P_const = np.ones((m, 1)) / math.sqrt(m)
    Bnc = B - P_const @ (P_const.T @ B)
    U, s, _ = np.linalg.svd(Bnc, full_matrices=False)
    Bnc = U[:, s > 1e-8]
    null_energy = np.sum(np.abs(Bnc.T @ V) ** 2, axis=0)
    invisible = (h % m) == 0
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = np.where(invisible, 0.0, 1.0 - null_energy / np.where(invisible, 1.0, energy))
    frac = np.clip(frac, 0.0, 1.0)
    alias = h % m
    alias = np.minimum(alias, m - alias)
    xk = np.deg2rad(start_deg)
    transfer = np.abs(np.exp(1j * np.outer(h, xk)).mean(axis=1))
    table_status = np.where(
        invisible, "invisible",
        np.where(frac < 1e-9, "unobservable",
                 np.where(frac < 1 - 1e-9, "partial",
                          np.where(alias != h, "aliased", "observable"))))
    gonio_status = np.where(invisible, "invisible",
                            np.where(alias != h, "aliased", "observable"))
    return pd.DataFrame({
        "order": h,
        "eda_mean_transfer": np.round(transfer, 12),
        "table_status": table_status,
        "table_observed_fraction": np.round(frac, 12),
        "table_alias_order": alias,
        "gonio_status": gonio_status,
        "gonio_alias_order": alias,
        "gonio_absorbs_table": (table_status == "unobservable") | (table_status == "partial"),
    })


def _check_step(step_deg: float) -> int:
    if not np.isfinite(step_deg) or step_deg <= 0:
        raise GonioError(f"step must be a positive angle, got {step_deg!r}", key="step_deg")
    m = int(round(360.0 / step_deg))
    if m < 2 or abs(m * step_deg - 360.0) > 1e-9 * 360.0 * m:
        raise GonioError(f"step {step_deg:.9g}° does not divide the full turn into "
                         f"an integer number m ≥ 2 of steps", key="step_deg")
    return m


# --------------------------------------------------------------------------- analysis
NOISE_MODELS = ("random_walk", "white")


def noise_whitening(m: int, noise: str, time_s=None,
                    compensation_time_s: float | None = None) -> np.ndarray:
    """The m×m matrix W that whitens one start's reading errors (generalised least squares).

    ``white``: readings independent, W = I (the classic IEC 62047-20 A.3 model).
    ``random_walk``: a gyro's angle random walk (and any drift of the compensation)
    accumulates from the zeroing, so the error of reading j is the sum of the
    increments before it and W is the first difference (e_1, e_2 − e_1, …): the
    increments between equally spaced steps are independent. Readings of one start
    are then correlated, and the white model understates the uncertainty.

    With the readings' times t_j since zeroing (``time_s``, shape (m,)) the random
    walk's covariance is min(t_i, t_j) (unequal steps); with ``compensation_time_s`` T
    the Earth-rate/bias compensation measured at rest for T before the start adds its
    own error, a rate common to the start's readings whose variance is the random
    walk's over T divided by T²: covariance min(t_i, t_j) + t_i t_j / T. W = L⁻¹ with
    V = L Lᵀ (Cholesky).

    >>> noise_whitening(3, "random_walk").tolist()
    [[1.0, 0.0, 0.0], [-1.0, 1.0, 0.0], [0.0, -1.0, 1.0]]
    >>> np.round(noise_whitening(2, "random_walk", [1.0, 2.0]), 9).tolist()
    [[1.0, 0.0], [-1.0, 1.0]]
    """
    if noise == "white":
        return np.eye(m)
    if noise == "random_walk" and time_s is not None:
        t = np.asarray(time_s, dtype=float)
        V = np.minimum.outer(t, t)
        if compensation_time_s:
            V = V + np.outer(t, t) / float(compensation_time_s)
        return np.linalg.inv(np.linalg.cholesky(V))
    if noise == "random_walk":
        return np.eye(m) - np.eye(m, k=-1)
    raise GonioError(f"unknown noise model {noise!r} (expected one of {', '.join(NOISE_MODELS)})",
                     key="noise")


def equal_division_analysis(D, start_deg, step_deg: float, *, repeats_axis: int | None = None,
                            gauge: str = "closure", max_order: int | None = None,
                            noise: str = "random_walk", coupling=None,
                            coupling_bound_arcsec_s: float | None = None,
                            noise_time_s=None,
                            compensation_time_s: float | None = None) -> EdaResult:
    """Separate the table's and the goniometer's errors by equal-division averaging.

    Least-squares fit of (IEC 62047-20 Annex A.3, generalised; GUM H.3)

        D[r, k, j] = g_j − t_{(p_k + j) mod m} + t_{p_k} + e[r, k, j],   j = 1..m

    with ``p_k = x_k / Δ`` the start's grid index, the gauge constraints of the
    module docstring (table orthogonal to its unobservable subspace, plus
    ``Σ t = 0`` or ``t_0 = 0``), and ``e`` independent with a common standard
    deviation ``s = sqrt(RSS / dof)``, ``dof = R·n·m − rank``. The parameter
    covariance is ``s² Z (Zᵀ AᵀA Z)⁻¹ Zᵀ`` with ``Z`` the basis of the gauge.
    For ``n = m`` the fit reduces to the classical averages: ``g_j`` is the
    mean of column ``j`` over the starts (Annex A.3: the table's differences
    cancel), and with ``E = D − g`` the table error at position ``q`` is the
    mean of the two closure sums ``(1/m) Σ_{j<m} E[q, j]`` (runs starting at
    ``q``) and ``−(1/m) Σ_{j<m} E[q−j, j]`` (runs arriving at ``q``).

    Parameters
    ----------
    D : array_like, shape (n, m) or (R, n, m) or a sequence of (n, m) arrays
        Deviations goniometer − table in arcseconds; row ``k`` is start ``k``,
        column ``j−1`` is step ``j`` (the last column the full turn).
    start_deg : array_like, shape (n,)
        Absolute table position at each start's zeroing, degrees; each must be
        a multiple of ``step_deg`` (mod 360).
    step_deg : float
        The step ``Δ = 360°/m``, degrees.
    repeats_axis : int, optional
        Axis of ``D`` that holds repeats when ``D`` is 3-D (default 0).
    gauge : {"closure", "zero"}
        ``"closure"``: table errors sum to zero over the ``m`` positions;
        ``"zero"``: the table error at position 0° is zero.
    max_order : int, optional
        Highest harmonic order in ``result.harmonics`` (default ``2m``).
    coupling : array_like, shape (n, m, 2), optional
        The tilt × Earth-rate coupling's design columns (:func:`coupling_design`): its
        two coefficients are then estimated jointly with the table and goniometer
        errors (a nuisance; :class:`CouplingFit`), and the uncertainties include it.
        When the design cannot separate them, the plain fit is returned and the
        result says so (``result.coupling.separable`` False) with the coupling's size
        at ``coupling_bound_arcsec_s`` (Ω_⊥ tan ψ at the tilt bound) when given.

    Returns
    -------
    EdaResult

    Raises
    ------
    GonioError
        Wrong shapes, non-finite values, starts off the step grid, or no
        residual degrees of freedom.

    Examples
    --------
    Eight starts, eight steps of 45°, a table with a 2″ first harmonic and a
    goniometer with 0.5″ of third harmonic, no noise:

    >>> sim = simulate_eda_matrix({1: 2.0}, {3: 0.5}, 8, 8, 1, 0.0, 0)
    >>> res = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg)
    >>> np.round(res.table_error_arcsec, 3) + 0.0   # 2 cos(x) at x = 0°, 45°, ...
    array([ 2.   ,  1.414,  0.   , -1.414, -2.   , -1.414,  0.   ,  1.414])
    >>> np.round(res.gonio_error_arcsec, 3) + 0.0   # 0.5 (cos 3φ − 1) at φ = 45°, ...
    array([-0.854, -0.5  , -0.146, -1.   , -0.146, -0.5  , -0.854,  0.   ])
    >>> res.dof, res.unobservable_dim
    (49, 0)
    """
    if gauge not in ("closure", "zero"):
        raise GonioError(f"gauge must be 'closure' or 'zero', got {gauge!r}", key="gauge")
    D, start_deg, m = _eda_input(D, start_deg, step_deg, repeats_axis)
    R, n, _ = D.shape
    p = _grid_indices(start_deg, float(step_deg))

    W, Wn, A = _whitened_design(p, n, m, noise, noise_time_s, compensation_time_s)
    D_raw = D
    D = D @ W.T          # whiten each start's row of readings (GLS)
    N1 = (A.T @ A).toarray()
    B = _table_null_basis(N1, m)
    Bc = _orth_complement(B)
    d = B.shape[1]
    # Z maps the free parameters to (g, t) with t orthogonal to the null table space
    Z = np.zeros((2 * m, m + m - d))
    Z[:m, :m] = np.eye(m)
    Z[m:, m:] = Bc
    y_sum = D.sum(axis=0).ravel()
    cfit = None
    if coupling is not None:
        A, Z, N1, cfit = _with_coupling(A, Z, N1, R, Wn, coupling, n, m,
                                        coupling_bound_arcsec_s)
    theta, cov, resid, dof, s2 = _gauged_least_squares(A, Z, N1, D, y_sum)

    g, t = theta[:m], theta[m:2 * m]
    cov_g, cov_t = cov[:m, :m], cov[m:2 * m, m:2 * m]
    if cfit == "fit":
        cfit = _coupling_estimate(theta[2 * m:2 * m + 2], cov[2 * m:2 * m + 2, 2 * m:2 * m + 2],
                                  coupling)
    if gauge == "zero":
        G = np.eye(m)
        G[:, 0] -= 1.0
        t = G @ t
        cov_t = G @ cov_t @ G.T
    harm = _harmonic_frame(start_deg, p, m, B, int(max_order or 2 * m))
    step = float(step_deg)
    return EdaResult(
        table_position_deg=np.arange(m) * step,
        table_error_arcsec=t, table_u_arcsec=np.sqrt(np.clip(np.diag(cov_t), 0, None)),
        table_cov_arcsec2=cov_t,
        gonio_angle_deg=np.arange(1, m + 1) * step,
        gonio_error_arcsec=g, gonio_u_arcsec=np.sqrt(np.clip(np.diag(cov_g), 0, None)),
        gonio_cov_arcsec2=cov_g,
        residual_std_arcsec=math.sqrt(s2), dof=int(dof), residuals_arcsec=resid,
        start_deg=start_deg, step_deg=step, repeats=R, gauge=gauge,
        unobservable_dim=int(d - 1), harmonics=harm,
        closure=_closure_check(g, cov_g, t, D_raw), noise=noise, coupling=cfit)


def _whitened_design(p: np.ndarray, n: int, m: int, noise: str, noise_time_s,
                     compensation_time_s):
    """The whitening W of one start's readings (its schedule the mean over starts), W for
    all n starts, and the whitened design matrix (GLS)."""
    tw = None
    if noise_time_s is not None:
        tw = np.asarray(noise_time_s, dtype=float).reshape(-1, m).mean(axis=0)
    W = noise_whitening(m, noise, tw, compensation_time_s)
    Wn = sp.kron(sp.eye(n), sp.csr_matrix(W))
    return W, Wn, sp.csr_matrix(Wn @ _design(p, m))


def _gauged_least_squares(A, Z, N1, D: np.ndarray, y_sum: np.ndarray):
    """θ = Z (Zᵀ R·AᵀA Z)⁻¹ Zᵀ Aᵀ Σ_r y_r, the whitened residuals, ν = R·n·m − rank,
    s² = RSS/ν and the covariance s² Z (Zᵀ R·AᵀA Z)⁻¹ Zᵀ (GUM H.3)."""
    R, n, m = D.shape
    M = Z.T @ (R * N1) @ Z
    Minv = np.linalg.inv(M)
    theta = Z @ (Minv @ (Z.T @ (A.T @ y_sum)))
    resid = D - (A @ theta).reshape(n, m)[None]  # whitened residuals: independent under the model
    rank = M.shape[0]
    dof = R * n * m - rank
    if dof <= 0:
        raise GonioError(f"no residual degrees of freedom ({R * n * m} readings, {rank} "
                         f"parameters): add starts or repeats", key="D")
    s2 = float(np.sum(resid ** 2)) / dof
    return theta, s2 * (Z @ Minv @ Z.T), resid, dof, s2


def _eda_input(D, start_deg, step_deg: float, repeats_axis: int | None):
    """D as (R, n, m) finite arcseconds, the starts as (n,), m from the step; GonioError
    naming the argument otherwise."""
    try:
        D = np.asarray(D, dtype=float)
    except (TypeError, ValueError) as exc:
        raise GonioError(f"D is not a numeric array: {exc}", key="D") from None
    if D.ndim == 2:
        D = D[None]
    elif D.ndim == 3:
        D = np.moveaxis(D, 0 if repeats_axis is None else repeats_axis, 0)
    else:
        raise GonioError(f"D must be 2-D (n, m) or 3-D (R, n, m), got shape {D.shape}", key="D")
    if not np.all(np.isfinite(D)):
        raise GonioError("D contains non-finite values (every reading is needed)", key="D")
    _, n, m_cols = D.shape
    m = _check_step(float(step_deg))
    if m_cols != m:
        raise GonioError(f"D has {m_cols} columns but the step {step_deg:.9g}° gives "
                         f"m = {m} points per revolution (columns are j = 1..m)", key="D")
    start_deg = np.atleast_1d(np.asarray(start_deg, dtype=float))
    if start_deg.shape != (n,):
        raise GonioError(f"{start_deg.size} start positions for {n} rows of D", key="start_deg")
    return D, start_deg, m


def _with_coupling(A, Z, N1, R: int, Wn, coupling, n: int, m: int, bound_arcsec_s):
    """The design extended by the tilt × Earth-rate coupling's two columns when they can be
    separated from the table and goniometer errors (then ``cfit`` is ``"fit"``); else the
    plain design and a :class:`CouplingFit` saying why, with the coupling's size at the
    tilt bound."""
    C = np.asarray(coupling, dtype=float)
    if C.shape != (n, m, 2) or not np.all(np.isfinite(C)):
        raise GonioError(f"coupling design must be finite with shape {(n, m, 2)}, got "
                         f"{C.shape}", key="coupling")
    cols = C.reshape(n * m, 2)
    q = cols.shape[1]
    Cw = np.asarray(Wn @ cols)
    A_ext = sp.hstack([A, sp.csr_matrix(Cw)]).tocsr()
    N_ext = (A_ext.T @ A_ext).toarray()
    Z_ext = np.zeros((2 * m + q, Z.shape[1] + q))
    Z_ext[:2 * m, :Z.shape[1]] = Z
    Z_ext[2 * m:, Z.shape[1]:] = np.eye(q)
    M_ext = Z_ext.T @ (R * N_ext) @ Z_ext
    scale = np.sqrt(np.clip(np.diag(M_ext), 1e-300, None))
    cond = np.linalg.cond(M_ext / np.outer(scale, scale))
    if cond < COUPLING_COND_LIMIT:
        return A_ext, Z_ext, N_ext / 1.0, "fit"
    size = math.nan
    if bound_arcsec_s is not None:
        size = float(bound_arcsec_s) * float(np.max(np.hypot(C[..., 0], C[..., 1])))
    return A, Z, N1, CouplingFit(
        False, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan, size,
        "the coupling cannot be separated from the table and goniometer errors (condition "
        f"number {cond:.2g}); it is not in the result"
        + (f": up to {size:.3g}″ at the tilt bound" if math.isfinite(size) else ""),
        reason="not_separable", condition_number=float(cond))


def _coupling_estimate(ab: np.ndarray, cab: np.ndarray, coupling) -> CouplingFit:
    """The coupling's two coefficients, their amplitude and its largest effect."""
    amp = float(np.hypot(*ab))
    grad = ab / amp if amp > 0 else np.array([1.0, 0.0])
    eff = np.asarray(coupling, dtype=float) @ ab
    return CouplingFit(True, float(ab[0]), float(ab[1]), math.sqrt(max(cab[0, 0], 0.0)),
                       math.sqrt(max(cab[1, 1], 0.0)), amp,
                       math.sqrt(max(float(grad @ cab @ grad), 0.0)),
                       float(np.max(np.abs(eff))),
                       "tilt × Earth-rate coupling estimated jointly with the table and "
                       "goniometer errors (nuisance, first harmonic of the absolute "
                       "position growing with the time since zeroing) and removed")


def _closure_check(g: np.ndarray, cov_g: np.ndarray, t: np.ndarray,
                   D_raw: np.ndarray) -> ClosureCheck:
    """The full-turn closure: column j = m involves g_m only."""
    full = float(g[-1])
    u_full = math.sqrt(max(cov_g[-1, -1], 0.0))
    z = full / u_full if u_full > 0 else (0.0 if full == 0 else math.inf)
    return ClosureCheck(
        table_sum_arcsec=float(t.sum()), full_turn_arcsec=full, u_full_turn_arcsec=u_full,
        z=float(z), per_start_full_turn_arcsec=D_raw[:, :, -1].mean(axis=0),
        consistent=bool(abs(z) <= CLOSURE_Z_LIMIT))


# --------------------------------------------------------------------------- comparison
def compare_tables(result_a: EdaResult, result_b: EdaResult) -> TableComparison:
    """Difference of two tables' error curves, one goniometer as transfer standard.

    Both tables are calibrated by :func:`equal_division_analysis` with the same
    goniometer; the goniometer's error cancels from each result, so the
    difference ``t_a − t_b`` at the positions common to both grids is
    independent of it (IEC 62047-20 Annex A.3; comparison by transfer
    standard). The difference is re-centred to zero mean over the common
    positions, ``d = H (S_a t_a − S_b t_b)``, ``H = I − 11ᵀ/c``, with covariance
    ``H (S_a C_a S_aᵀ + S_b C_b S_bᵀ) Hᵀ`` (the two runs independent; GUM 5.1).
    Table harmonics unobservable in either run (multiples of its ``n``) are
    missing from that run's curve and hence from the difference.

    The goniometer curves should agree: ``gonio_chi2`` sums the squared
    normalised differences at the common angles (expect about ``gonio_points``
    when both runs see the same table-harmonic content in their goniometer
    curves, i.e. when ``n = m`` in both).

    Parameters
    ----------
    result_a, result_b : EdaResult
        Calibrations of tables A and B.

    Returns
    -------
    TableComparison

    Raises
    ------
    GonioError
        Fewer than two common positions.

    Examples
    --------
    >>> a = equal_division_analysis(**_sim_kw(simulate_eda_matrix({2: 1.0}, {1: 0.3}, 8, 8, 1, 0.0, 0)))
    >>> b = equal_division_analysis(**_sim_kw(simulate_eda_matrix({2: 0.4}, {1: 0.3}, 8, 8, 1, 0.0, 0)))
    >>> np.round(compare_tables(a, b).difference_arcsec, 3) + 0.0   # 0.6 cos 2x
    array([ 0.6,  0. , -0.6,  0. ,  0.6,  0. , -0.6,  0. ])
    """
    pa = np.round(np.mod(result_a.table_position_deg, 360.0) * 1e6).astype(np.int64)
    pb = np.round(np.mod(result_b.table_position_deg, 360.0) * 1e6).astype(np.int64)
    common, ia, ib = np.intersect1d(pa, pb, return_indices=True)
    c = common.size
    if c < 2:
        raise GonioError("the two calibrations share fewer than two table positions",
                         key="table_position_deg")
    H = np.eye(c) - 1.0 / c
    diff = H @ (result_a.table_error_arcsec[ia] - result_b.table_error_arcsec[ib])
    cov = H @ (result_a.table_cov_arcsec2[np.ix_(ia, ia)]
               + result_b.table_cov_arcsec2[np.ix_(ib, ib)]) @ H.T
    ga = np.round(result_a.gonio_angle_deg * 1e6).astype(np.int64)
    gb = np.round(result_b.gonio_angle_deg * 1e6).astype(np.int64)
    _, ja, jb = np.intersect1d(ga, gb, return_indices=True)
    var = result_a.gonio_u_arcsec[ja] ** 2 + result_b.gonio_u_arcsec[jb] ** 2
    dg = result_a.gonio_error_arcsec[ja] - result_b.gonio_error_arcsec[jb]
    ok = var > 0
    chi2 = float(np.sum(dg[ok] ** 2 / var[ok]))
    return TableComparison(position_deg=common / 1e6, difference_arcsec=diff,
                           u_difference_arcsec=np.sqrt(np.clip(np.diag(cov), 0, None)),
                           cov_arcsec2=cov, gonio_chi2=chi2, gonio_points=int(ok.sum()))


# --------------------------------------------------------------------------- simulation
def _harmonic_table(spec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if spec is None:
        return np.zeros(0, int), np.zeros(0), np.zeros(0)
    if isinstance(spec, Mapping):
        items = list(spec.items())
    else:
        items = [(row[0], tuple(row[1:])) for row in spec]
    orders, amps, phases = [], [], []
    for order, val in items:
        if isinstance(val, (tuple, list, np.ndarray)):
            a, ph = (float(val[0]), float(val[1]) if len(val) > 1 else 0.0)
        else:
            a, ph = float(val), 0.0
        if int(order) != order or order < 1:
            raise GonioError(f"harmonic order must be an integer ≥ 1, got {order!r}",
                             key="harmonics")
        orders.append(int(order)); amps.append(a); phases.append(ph)
    return np.array(orders, int), np.array(amps), np.array(phases)


def table_error_arcsec(x_deg, table_harmonics) -> np.ndarray:
    """Table error ``t(x) = Σ_h A_h cos(h x + φ_h)`` in arcseconds.

    ``table_harmonics`` maps order ``h`` to ``A_h`` (arcsec) or ``(A_h, φ_h)``
    (φ in radians). A Fourier series of a periodic circle-division error
    (IEC 62047-20 Annex A.3).

    >>> np.round(table_error_arcsec([0, 45, 90], {1: 2.0, 2: (1.0, np.pi / 2)}), 6) + 0.0
    array([2.      , 0.414214, 0.      ])
    """
    h, a, ph = _harmonic_table(table_harmonics)
    x = np.deg2rad(np.asarray(x_deg, dtype=float))
    return np.cos(np.multiply.outer(x, h) + ph) @ a


def gonio_error_arcsec(phi_deg, gonio_harmonics) -> np.ndarray:
    """Goniometer error ``g(φ) = Σ_h B_h [cos(h φ + ψ_h) − cos ψ_h]``, arcseconds.

    The same Fourier series as :func:`table_error_arcsec`, less its value at
    ``φ = 0``: the goniometer reads zero where it was zeroed, so ``g(0) = 0``
    and, being periodic, ``g(360°) = 0``.

    >>> np.round(gonio_error_arcsec([0, 90, 180, 360], {1: 1.0}), 6)
    array([ 0., -1., -2.,  0.])
    """
    h, b, ps = _harmonic_table(gonio_harmonics)
    phi = np.deg2rad(np.asarray(phi_deg, dtype=float))
    return (np.cos(np.multiply.outer(phi, h) + ps) - np.cos(ps)) @ b


def simulate_eda_matrix(table_harmonics, gonio_harmonics, n: int, m: int, repeats: int,
                        noise_arcsec: float, rng) -> EdaSimulation:
    """Synthetic equal-division measurement with known harmonic errors.

    ``D[r, k, j] = g(jΔ) − [t(x_k + jΔ) − t(x_k)] + e``, ``x_k = k·360°/n``,
    ``Δ = 360°/m``, ``e ~ N(0, noise_arcsec²)`` independent (the model of
    IEC 62047-20 Annex A.3 with :func:`table_error_arcsec` and
    :func:`gonio_error_arcsec`). Independent of the virtual bench.

    Parameters
    ----------
    table_harmonics, gonio_harmonics : mapping or sequence or None
        ``{order: amplitude_arcsec}`` or ``{order: (amplitude_arcsec, phase_rad)}``
        or rows ``(order, amplitude_arcsec, phase_rad)``.
    n, m : int
        Starts and points per revolution.
    repeats : int
        Number of repeated matrices ``R``.
    noise_arcsec : float
        Reading noise standard deviation, arcseconds.
    rng : numpy.random.Generator or int
        Random generator or seed.

    Returns
    -------
    EdaSimulation

    Examples
    --------
    >>> sim = simulate_eda_matrix({1: 1.0}, None, 4, 4, 2, 0.0, 1)
    >>> sim.D_arcsec.shape, sim.start_deg, sim.step_deg
    ((2, 4, 4), array([  0.,  90., 180., 270.]), 90.0)
    >>> sim.D_arcsec[0, 0]
    array([1., 2., 1., 0.])
    """
    if int(n) < 1 or int(m) < 2 or int(repeats) < 1:
        raise GonioError(f"need n ≥ 1, m ≥ 2, repeats ≥ 1 (got {n}, {m}, {repeats})")
    n, m, repeats = int(n), int(m), int(repeats)
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    start = np.arange(n) * 360.0 / n
    step = 360.0 / m
    phi = np.arange(1, m + 1) * step
    t0 = table_error_arcsec(start, table_harmonics)                         # (n,)
    tj = table_error_arcsec(start[:, None] + phi[None, :], table_harmonics)  # (n, m)
    g = gonio_error_arcsec(phi, gonio_harmonics)                             # (m,)
    clean = g[None, :] - (tj - t0[:, None])
    D = clean[None] + float(noise_arcsec) * rng.standard_normal((repeats, n, m))
    return EdaSimulation(D_arcsec=D, start_deg=start, step_deg=step,
                         table_true_arcsec=table_error_arcsec(np.arange(m) * step,
                                                              table_harmonics),
                         gonio_true_arcsec=g)


def _sim_kw(sim: EdaSimulation) -> dict:
    """Keyword arguments of :func:`equal_division_analysis` from a simulation."""
    return {"D": sim.D_arcsec, "start_deg": sim.start_deg, "step_deg": sim.step_deg}


# --------------------------------------------------------------------------- readings
_EDA_COLUMNS = ("series", "round", "table_deg", "gyro_deg")


def _where(df: pd.DataFrame, label) -> dict:
    """``line=`` for GonioError: the DataFrame index label when it is an int (line number)."""
    try:
        return {"line": int(label)}
    except (TypeError, ValueError):  # pragma: no cover
        return {}


def eda_matrix_from_readings(df: pd.DataFrame, *, starts: int | None = None,
                             file=None, return_times: bool = False):
    """Build the deviation matrix D from a readings file's ``equal_division`` rows.

    Readings-file rows (``docs/formats.md#rows-of-each-test``): rows with
    ``test = equal_division``; ``series`` = repeat index; ``round`` = start
    index ``k+1``; ``start_deg`` = the table's absolute position at zeroing
    (same for every row of a round, and for a round in every series);
    ``table_deg`` = the table's indicated angle turned since the start,
    ``jΔ``, ``j = 1..m`` (a row at ``table_deg = 0``, a reading at the zero, is
    ignored); ``gyro_deg`` = the goniometer's indicated angle since zeroing.
    ``D = (gyro_deg − table_deg)·3600`` in arcseconds. Other tests' rows are
    ignored.

    The DataFrame's index labels are quoted as line numbers in errors (the CLI
    sets them to the file's line numbers).

    Parameters
    ----------
    df : pandas.DataFrame
        Readings.
    starts : int, optional
        Number of starts ``n``. Without a ``start_deg`` column the starts are
        taken as ``(round − 1)·360°/n`` and ``starts`` is required; with it,
        the number of rounds must equal ``starts``.
    file : str or Path, optional
        File name quoted in errors.

    Returns
    -------
    D_arcsec : numpy.ndarray, shape (R, n, m)
    start_deg : numpy.ndarray, shape (n,)
    step_deg : float
    time_s : numpy.ndarray, shape (R, n, m)
        Only with ``return_times``: each reading's ``time_s`` (time from zeroing to
        reading; None when the file has no such column), for :func:`coupling_design`.

    Raises
    ------
    GonioError
        Missing columns, unparsable values, an incomplete or duplicated grid,
        steps that are not ``j·360°/m``, inconsistent start positions.

    Examples
    --------
    >>> df = pd.DataFrame({"test": "equal_division", "series": 1,
    ...     "round": [1, 1, 2, 2], "start_deg": [0.0, 0.0, 180.0, 180.0],
    ...     "table_deg": [180.0, 360.0] * 2,
    ...     "gyro_deg": [180.0 + 1 / 3600, 360.0, 180.0 - 1 / 3600, 360.0]})
    >>> D, start, step = eda_matrix_from_readings(df)
    >>> np.round(D, 9), start, step
    (array([[[ 1.,  0.],
            [-1.,  0.]]]), array([  0., 180.]), 180.0)
    """
    rows, num, has_start = _eda_numbers(df, file)
    table_all = num["table_deg"].to_numpy()
    keep = np.abs(table_all) > STEP_TOL_DEG                   # drop readings at the zero
    labels = rows.index[keep]
    series = num["series"].to_numpy()[keep].astype(int)
    rnd = num["round"].to_numpy()[keep].astype(int)
    table = table_all[keep]
    dev = (num["gyro_deg"].to_numpy()[keep] - table) * ARCSEC_PER_DEG
    if table.size == 0:
        raise GonioError("equal_division rows have no reading away from the zero",
                         file=file, column="table_deg")
    j, m, step, R, n = _eda_grid(df, labels, series, rnd, table, file)
    D = np.empty((R, n, m))
    D[series - 1, rnd - 1, j - 1] = dev
    start = _eda_starts(df, num, keep, labels, rnd, n, m, starts, has_start, file)
    if not return_times:
        return D, start, step
    T = None
    if "time_s" in rows.columns:
        tv = pd.to_numeric(rows["time_s"], errors="coerce").to_numpy(dtype=float)[keep]
        if np.all(np.isfinite(tv)):
            T = np.empty((R, n, m))
            T[series - 1, rnd - 1, j - 1] = tv
    return D, start, step, T


def _eda_numbers(df: pd.DataFrame, file):
    """The ``equal_division`` rows and their numeric columns (series and round integers
    ≥ 1), GonioError naming the line otherwise; whether start positions are given."""
    if "test" not in df.columns:
        raise GonioError("missing required column", file=file, column="test")
    rows = df[df["test"].astype(str).str.strip() == "equal_division"]
    if rows.empty:
        raise GonioError("no rows with test = equal_division", file=file, column="test")
    cols = list(_EDA_COLUMNS)
    has_start = "start_deg" in rows.columns and rows["start_deg"].notna().any()
    if has_start:
        cols.append("start_deg")
    for c in cols:
        if c not in rows.columns:
            raise GonioError("missing required column for equal_division", file=file, column=c)
    num = {}
    for c in cols:
        v = pd.to_numeric(rows[c], errors="coerce")
        bad = v.isna() | ~np.isfinite(v.astype(float))
        if bad.any():
            i = int(np.argmax(bad.to_numpy()))
            raise GonioError(f"expected a number, got {rows[c].iloc[i]!r}", file=file,
                             column=c, **_where(df, rows.index[i]))
        num[c] = v.astype(float)
    for c in ("series", "round"):
        bad = (num[c] != np.round(num[c])) | (num[c] < 1)
        if bad.any():
            i = int(np.argmax(bad.to_numpy()))
            raise GonioError("expected an integer ≥ 1", file=file, column=c,
                             **_where(df, rows.index[i]))
    return rows, num, has_start


def _eda_grid(df: pd.DataFrame, labels, series, rnd, table, file):
    """Step index j of every reading, m points per revolution and the step, R series and
    n rounds: the grid complete, without duplicates, numbered from 1."""
    # points per revolution: the most common number of readings in a round
    _, counts = np.unique(np.stack([series, rnd]), axis=1, return_counts=True)
    vals, freq = np.unique(counts, return_counts=True)
    m = int(vals[freq == freq.max()].max())
    if m < 2:
        raise GonioError("each round needs at least two steps", file=file, column="table_deg")
    step = 360.0 / m
    j = np.rint(table / step)
    bad = (np.abs(table - j * step) > STEP_TOL_DEG) | (j < 1) | (j > m)
    if bad.any():
        i = int(np.argmax(bad))
        raise GonioError(f"table_deg {table[i]:.9g} is not a multiple j·{step:.9g}° "
                         f"(j = 1..{m}) of the step implied by {m} readings per round",
                         file=file, column="table_deg", **_where(df, labels[i]))
    j = j.astype(int)
    key = pd.DataFrame({"s": series, "r": rnd, "j": j})
    dup = key.duplicated().to_numpy()
    if dup.any():
        i = int(np.argmax(dup))
        raise GonioError(f"duplicate reading: series {series[i]}, round {rnd[i]}, "
                         f"step {j[i]} (table_deg {table[i]:.9g})", file=file,
                         **_where(df, labels[i]))
    s_vals = np.unique(series)
    r_vals = np.unique(rnd)
    R, n = s_vals.size, r_vals.size
    if not np.array_equal(s_vals, np.arange(1, R + 1)):
        raise GonioError(f"series must be numbered 1..{R}, found {s_vals.tolist()}",
                         file=file, column="series")
    if not np.array_equal(r_vals, np.arange(1, n + 1)):
        raise GonioError(f"rounds must be numbered 1..{n}, found {r_vals.tolist()}",
                         file=file, column="round")
    if R * n * m != len(key):
        full = pd.MultiIndex.from_product([s_vals, r_vals, np.arange(1, m + 1)])
        have = pd.MultiIndex.from_frame(key)
        missing = full.difference(have)[0]
        raise GonioError(f"incomplete grid: no reading for series {missing[0]}, round "
                         f"{missing[1]}, table_deg {missing[2] * step:.9g} ({len(full) - len(have)}"
                         f" of {len(full)} readings missing)", file=file, column="table_deg")
    return j, m, step, R, n


def _eda_starts(df: pd.DataFrame, num, keep, labels, rnd, n: int, m: int,
                starts: int | None, has_start: bool, file) -> np.ndarray:
    """Each round's start position: the file's ``start_deg`` (one per round), else
    (round − 1)·360°/n with n dividing m (IEC 62047-20 A.3)."""
    if has_start:
        st = num["start_deg"].to_numpy()[keep]
        start = np.full(n, np.nan)
        for idx_r in range(n):
            sel = np.flatnonzero(rnd == idx_r + 1)
            vals = np.mod(st[sel], 360.0)
            ref = vals[0]
            off = np.abs((vals - ref + 180.0) % 360.0 - 180.0) > STEP_TOL_DEG
            if off.any():
                i = sel[int(np.argmax(off))]
                raise GonioError(f"start_deg {st[i]:.9g} differs from {ref:.9g} given "
                                 f"elsewhere for round {idx_r + 1}", file=file,
                                 column="start_deg", **_where(df, labels[i]))
            start[idx_r] = ref
        if starts is not None and int(starts) != n:
            raise GonioError(f"--starts {starts} but the file has {n} rounds (starts)",
                             file=file, column="round")
    else:
        if starts is None:
            raise GonioError("no start_deg column: give the number of starts n "
                             "(starts are then (round − 1)·360°/n)", file=file,
                             column="start_deg")
        if int(starts) != n:
            raise GonioError(f"--starts {starts} but the file has {n} rounds (starts)",
                             file=file, column="round")
        if m % n:
            raise GonioError(f"{n} starts do not divide the {m} points per revolution: starts "
                             f"(round − 1)·360°/{n} fall between the table's steps (IEC 62047-20 "
                             "A.3 needs n to divide m, or a start_deg column)", file=file,
                             column="round")
        start = np.arange(n) * 360.0 / n
    return start


def coupling_bound_arcsec_s(latitude_deg: float | None, tilt_bound_deg: float | None,
                            orientation: str = "up") -> float | None:
    """Ω_⊥ tan ψ at the tilt bound, ″/s (the coupling's size when it cannot be fitted).

    >>> round(coupling_bound_arcsec_s(40.0, 0.1), 5)        # 11.5221″/s × tan 0.1°
    0.02011
    """
    if latitude_deg is None or tilt_bound_deg is None:
        return None
    from gonio.physics.earth import earth_rate_split

    perp_dps = earth_rate_split(float(latitude_deg), orientation).perpendicular_dps
    return perp_dps * ARCSEC_PER_DEG * math.tan(math.radians(float(tilt_bound_deg)))


def analyse_eda_readings(df: pd.DataFrame, protocol: "EdaProtocol | None" = None, *,
                         starts: int | None = None, file=None, gauge: str = "closure",
                         noise: str = "random_walk", coupling: bool = True,
                         latitude_deg: float | None = None,
                         tilt_bound_deg: float | None = None,
                         compensation_time_s: float | None = None,
                         table_accel_dps2: float | None = None) -> EdaResult:
    """A readings file's ``equal_division`` rows analysed, the coupling as a nuisance.

    With ``coupling`` (default) and the rows' ``time_s``, the tilt × Earth-rate coupling
    is estimated jointly (:func:`coupling_design` with the protocol's ``rate_dps`` and
    ``read_delay_s``; the built-in ``eda`` protocol when none is given). Without times
    it cannot be: the result then carries a :class:`CouplingFit` with
    ``separable=False`` and its size at the tilt bound (latitude and tilt bound known).
    ``compensation_time_s``: the static phase of a measured Earth-rate compensation
    before each start (the protocol's ``session.static_s``); its error, a rate common
    to the start's readings, enters the noise model (:func:`noise_whitening`).
    ``table_accel_dps2``: the table's acceleration (readings metadata of the same name),
    which sets how long each step takes in the coupling design; without it the moves
    are taken at constant rate (shorter: on the default example 0.5 s instead of 1.41 s,
    a first-harmonic error of about a fifth of the table's u).
    """
    D, start, step, T = eda_matrix_from_readings(df, starts=starts, file=file,
                                                 return_times=True)
    bound = coupling_bound_arcsec_s(latitude_deg, tilt_bound_deg,
                                    protocol.orientation if protocol else "up")
    if not coupling:
        return equal_division_analysis(D, start, step, gauge=gauge, noise=noise)
    if T is None:
        res = equal_division_analysis(D, start, step, gauge=gauge, noise=noise)
        size = math.nan
        if bound is not None:
            # without times, bound the effect by the longest plausible time: m rests
            size = bound * 2.0 * res.m_points * (protocol.rest_s if protocol else 10.0)
        note = ("the coupling cannot be estimated: the equal_division rows have no time_s; "
                "it is not in the result" + (f" (up to about {size:.3g}″ at the tilt bound)"
                                             if math.isfinite(size) else ""))
        from dataclasses import replace as _replace
        return _replace(res, coupling=CouplingFit(False, *([math.nan] * 6), size, note,
                                                  reason="no_times"))
    p = protocol or load_eda_protocol()
    C = coupling_design(T, start, step, p.read_delay_s, p.rate_dps, table_accel_dps2)
    return equal_division_analysis(D, start, step, gauge=gauge, noise=noise, coupling=C,
                                   coupling_bound_arcsec_s=bound, noise_time_s=T,
                                   compensation_time_s=compensation_time_s)


# --------------------------------------------------------------------------- protocol


def load_eda_protocol(path="eda") -> EdaProtocol:
    """Load the ``[equal_division]`` section of a protocol (default ``protocols/eda.toml``).

    Validated like every protocol section (unknown key, wrong type → GonioError
    naming file and key); additionally the starts must divide the points (the
    grid restriction of :func:`equal_division_analysis`) and the reading must
    fall within the rest.

    >>> p = load_eda_protocol()
    >>> p.starts, p.points, p.step_deg, p.rate_dps
    (12, 12, 30.0, 60.0)
    """
    proto = load_protocol(path)
    p = proto.equal_division
    if p is None:
        raise GonioError("no [equal_division] section", file=proto.path, key="equal_division")
    if p.points % p.starts:
        raise GonioError(f"starts ({p.starts}) must divide points ({p.points}): the starts "
                         f"must lie on the step grid", file=proto.path,
                         key="equal_division.starts")
    if p.read_delay_s > p.rest_s:
        raise GonioError("read_delay_s is longer than rest_s", file=proto.path,
                         key="equal_division.read_delay_s")
    return p


def equal_division_from_readings(readings: Readings, *, starts: int | None = None,
                                 gauge: str = "closure", noise: str = "random_walk",
                                 protocol: "EdaProtocol | None" = None, coupling: bool = True,
                                 compensation_time_s: float | None = None) -> EdaResult:
    """Equal-division analysis of a readings file's ``equal_division`` rows.

    The one path from a readings file to an :class:`EdaResult`, used by
    ``gonio eda`` and by the calibration pipeline: the file is read by
    :func:`gonio.specs.ogam_draft.readings.read_readings` (its checks apply), the rows
    indexed by their line numbers so that errors name the line. The tilt × Earth-rate
    coupling is estimated as a nuisance (:func:`analyse_eda_readings`; the file's
    ``table_accel_dps2`` times the moves, its ``latitude_deg`` and ``tilt_bound_deg``
    size the coupling when it cannot be estimated).
    """
    df = readings.data
    rows = df[df["test"] == "equal_division"]
    if not len(rows):
        raise GonioError("no equal_division rows", file=readings.path, column="test")
    from gonio.formats.metadata import metadata_float

    md, file = readings.metadata, readings.path
    return analyse_eda_readings(
        rows.set_index("line", drop=False) if "line" in rows else rows, protocol,
        starts=starts, file=file, gauge=gauge, noise=noise, coupling=coupling,
        latitude_deg=metadata_float(md, "latitude_deg", file=file),
        tilt_bound_deg=metadata_float(md, "tilt_bound_deg", file=file),
        compensation_time_s=compensation_time_s,
        table_accel_dps2=metadata_float(md, "table_accel_dps2", file=file))
