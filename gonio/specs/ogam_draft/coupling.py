"""Tilt × Earth-rate coupling: the angle error a tilted sensing axis picks up as the table turns.

Contents
--------
:func:`trig_integrals`            ∫cos θ(t) dt, ∫sin θ(t) dt over a :class:`~gonio.physics.kinematics.Timeline`
:func:`coupling_terms`            the two α-independent terms of one reading's error
:func:`coupling_error_arcsec`     the angle error of readings, for a tilt azimuth α
:func:`coupling_worst_case_arcsec` its largest magnitude over α

Per reading of a planned session, and as a budget line: :mod:`gonio.specs.ogam_draft.budget_extra`.

Physics (``docs/draft-readings.md#tilt-and-earth-rate-coupling``; :mod:`gonio.physics.kinematics`).
A rate gyro senses ω·n; with the sensing axis n tilted by ψ from the table axis a,
coning with the table angle θ,

    Ω_E·n(θ) = cos ψ (Ω·a) + sin ψ Ω_⊥ cos(θ + α)

with Ω_⊥ the Earth rate across the table axis and α the tilt's azimuth measured
from Ω_⊥'s direction in the table frame (α = α_table − β). A compensation
*measured* at rest at table angle θ_c (clause 7 preamble; usually the zero
position, θ_c = 0) removes cos ψ (Ω·a) + sin ψ Ω_⊥ cos(θ_c + α); what is left is

    r(t) = Ω_⊥ sin ψ [cos(θ(t) + α) − cos(θ_c + α)]

(up to 2 Ω_⊥ sin ψ). A *computed* compensation removes Ω·a from latitude and the
nominal axis, leaving r(t) = (cos ψ − 1) Ω·a + Ω_⊥ sin ψ cos(θ(t) + α). The angle
error of a reading taken at t_r after zeroing at t_z, in the instrument's
calibrated unit (the 7.1 scale factor holds cos ψ, so the counts are divided by
K cos ψ — the "mount" scale factor of the bench), is

    e = (1/cos ψ) ∫_{t_z}^{t_r} r(t) dt
      = (Ω_⊥ tan ψ) [cos α · (C − cos θ_c Δt) − sin α · (S − sin θ_c Δt)]   (measured)

with C = ∫cos θ dt, S = ∫sin θ dt, Δt = t_r − t_z. The error is a sinusoid in α,
so its worst case over α is (Ω_⊥ tan ψ)·hypot(C − cos θ_c Δt, S − sin θ_c Δt); with
α unknown and equally likely in [0, 2π) it is arcsine-distributed (JCGM 101 6.4.6).

C and S are closed form during rests and constant-rate cruise; during the
constant-acceleration phases of a trapezoidal move (θ quadratic in t; Fresnel
integrals) they use Gauss–Legendre quadrature on pieces of at most 0.25 rad,
exact to rounding (tested against adaptive quadrature to 1e-12).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gonio.errors import GonioError
from gonio.units import ARCSEC_PER_DEG
from gonio.physics.kinematics import Timeline

_GL_X, _GL_W = np.polynomial.legendre.leggauss(24)
_MAX_PIECE_RAD = 0.25


def _pieces(tl: Timeline, t_a: float, t_b: float):
    """Pieces of [t_a, t_b] on which θ is constant, linear or quadratic in t.

    Yields (t0, t1, kind) with kind 'const', 'linear' or 'quad'.
    """
    segs = tl.segments()
    t0s = np.array([g.t0_s for g in segs], dtype=float)
    dist = np.array([g.distance_deg for g in segs], dtype=float)
    tacc = np.array([g.accel_time_s for g in segs], dtype=float)
    dur = np.array([g.duration_s for g in segs], dtype=float)
    out = []
    if t0s.size == 0:
        return [(t_a, t_b, "const")]
    # Before the first and after the last segment: at rest.
    if t_a < t0s[0]:
        out.append((t_a, min(t_b, t0s[0]), "const"))
    end = tl.end_s
    for i in range(t0s.size):
        s0, s1 = t0s[i], t0s[i] + dur[i]
        if s1 <= t_a or s0 >= t_b:
            continue
        if dist[i] == 0.0:
            bounds, kinds = [s0, s1], ["const"]
        else:
            bounds = [s0, s0 + tacc[i], s1 - tacc[i], s1]
            kinds = ["quad", "linear", "quad"]
        for (u0, u1), kind in zip(zip(bounds[:-1], bounds[1:]), kinds):
            lo, hi = max(u0, t_a), min(u1, t_b)
            if hi > lo:
                out.append((lo, hi, kind))
    if t_b > end:
        out.append((max(t_a, end), t_b, "const"))
    return out


def trig_integrals(timeline: Timeline, t_a: float, t_b: float) -> tuple[float, float]:
    """(∫cos θ dt, ∫sin θ dt) over [t_a, t_b], θ = the timeline's angle in radians, s.

    Closed form at rest (θ constant) and in cruise (θ linear: [sin θ]/θ̇,
    [−cos θ]/θ̇); Gauss–Legendre (24 nodes, pieces ≤ 0.25 rad) while accelerating.

    Examples
    --------
    A quarter turn at 90 °/s after a 1 s rest (acceleration so high that the
    ramps last 10 µs): ∫cos θ = ∫sin θ over the turn = 1/(π/2 rad/s) = 0.6366 s.

    >>> tl = Timeline(); _ = tl.dwell(1.0); _ = tl.move(90.0, 90.0, 9e6)
    >>> c, s = trig_integrals(tl, 0.0, tl.end_s)
    >>> round(c - 1.0, 4), round(s, 4)         # minus the 1 s at θ = 0
    (0.6366, 0.6366)
    """
    if not (math.isfinite(t_a) and math.isfinite(t_b)) or t_b < t_a:
        raise GonioError(f"need t_a ≤ t_b, got {t_a}, {t_b}")
    c_sum = s_sum = 0.0
    for lo, hi, kind in _pieces(timeline, t_a, t_b):
        th = np.radians(timeline.angle_deg(np.array([lo, hi])))
        if kind == "const":
            c_sum += math.cos(th[0]) * (hi - lo)
            s_sum += math.sin(th[0]) * (hi - lo)
            continue
        if kind == "linear":
            w = (th[1] - th[0]) / (hi - lo)
            if w != 0.0:
                c_sum += (math.sin(th[1]) - math.sin(th[0])) / w
                s_sum += (math.cos(th[0]) - math.cos(th[1])) / w
            else:
                c_sum += math.cos(th[0]) * (hi - lo)
                s_sum += math.sin(th[0]) * (hi - lo)
            continue
        # quadratic θ: split so that each piece turns by at most _MAX_PIECE_RAD.
        n = max(1, int(math.ceil(abs(th[1] - th[0]) / _MAX_PIECE_RAD)))
        edges = np.linspace(lo, hi, n + 1)
        half = 0.5 * np.diff(edges)
        mid = 0.5 * (edges[1:] + edges[:-1])
        t = (mid[:, None] + half[:, None] * _GL_X[None, :]).ravel()
        w = (half[:, None] * _GL_W[None, :]).ravel()
        tt = np.radians(timeline.angle_deg(t))
        c_sum += float(w @ np.cos(tt))
        s_sum += float(w @ np.sin(tt))
    return float(c_sum), float(s_sum)


@dataclass(frozen=True)
class CouplingTerms:
    """α-independent terms of one reading: e(α) = scale·(P cos α − Q sin α) + offset, ″."""

    p_s: float                 # C − cos θ_c Δt (measured) or C (computed), s
    q_s: float                 # S − sin θ_c Δt (measured) or S (computed), s
    scale_arcsec_s: float      # Ω_⊥ tan ψ, ″/s
    offset_arcsec: float       # computed compensation: (cos ψ − 1) Ω·a Δt / cos ψ, ″
    duration_s: float

    def error_arcsec(self, alpha_deg) -> np.ndarray:
        """e(α), ″ (α relative to Ω_⊥'s direction, degrees)."""
        a = np.radians(np.asarray(alpha_deg, dtype=float))
        return self.scale_arcsec_s * (self.p_s * np.cos(a) - self.q_s * np.sin(a)) \
            + self.offset_arcsec

    def worst_case_arcsec(self) -> float:
        """max over α of |e(α)| = |offset| + scale·hypot(P, Q)."""
        return abs(self.offset_arcsec) + abs(self.scale_arcsec_s) * math.hypot(self.p_s, self.q_s)


def coupling_terms(timeline: Timeline, t_zero_s: float, t_read_s: float, tilt_deg: float,
                   perpendicular_dps: float, *, compensation: str = "measured",
                   theta_comp_deg: float | None = None,
                   parallel_dps: float = 0.0) -> CouplingTerms:
    """Terms of the coupling error of a reading (module docstring formula).

    Parameters
    ----------
    timeline : Timeline
        The table's motion (θ in the table frame in which α is given).
    t_zero_s, t_read_s : float
        Zeroing and reading instants.
    tilt_deg : float
        ψ.
    perpendicular_dps, parallel_dps : float
        Ω_⊥ and Ω·a, °/s (:func:`gonio.physics.earth.earth_rate_split`).
    compensation : {"measured", "computed", "none"}
        Measured at rest at ``theta_comp_deg`` (default: the angle at zeroing);
        computed from Ω·a; none.
    """
    if compensation not in ("measured", "computed", "none"):
        raise GonioError(f"compensation must be measured, computed or none, got {compensation!r}")
    psi = math.radians(tilt_deg)
    dt = t_read_s - t_zero_s
    c, s = trig_integrals(timeline, t_zero_s, t_read_s)
    scale = perpendicular_dps * ARCSEC_PER_DEG * math.tan(psi)
    offset = 0.0
    if compensation == "measured":
        thc = float(timeline.angle_deg(np.array([t_zero_s]))[0]) if theta_comp_deg is None \
            else theta_comp_deg
        c -= math.cos(math.radians(thc)) * dt
        s -= math.sin(math.radians(thc)) * dt
    elif compensation == "computed":
        offset = (math.cos(psi) - 1.0) / math.cos(psi) * parallel_dps * ARCSEC_PER_DEG * dt
    else:
        offset = parallel_dps * ARCSEC_PER_DEG * dt
    return CouplingTerms(c, s, scale, offset, dt)


def coupling_error_arcsec(timeline: Timeline, t_zero_s, t_read_s, tilt_deg: float,
                          alpha_deg: float, perpendicular_dps: float, **kw) -> np.ndarray:
    """Coupling angle error of readings (arrays of zeroing/reading times), ″.

    ``alpha_deg`` is the tilt azimuth relative to Ω_⊥'s direction in the table
    frame; other keywords as :func:`coupling_terms`.

    Examples
    --------
    Axis up at 40° N (Ω_⊥ = 11.5221″/s), ψ = 0.1°, α = 0, measured compensation at
    0°: a reading 10 s after arriving at 180° (instant move) has drifted by
    Ω_⊥ tan ψ (cos 180° − cos 0°)·10 s = −0.4022″.

    >>> tl = Timeline(); _ = tl.move(180.0, 1e6, 1e12); _ = tl.dwell(10.0)
    >>> perp = 11.522126 / 3600
    >>> round(float(coupling_error_arcsec(tl, 0.0, tl.end_s, 0.1, 0.0, perp)[0]), 4)
    -0.4022
    """
    tz = np.atleast_1d(np.asarray(t_zero_s, dtype=float))
    tr = np.atleast_1d(np.asarray(t_read_s, dtype=float))
    tz, tr = np.broadcast_arrays(tz, tr)
    return np.array([coupling_terms(timeline, a, b, tilt_deg, perpendicular_dps, **kw)
                     .error_arcsec(alpha_deg) for a, b in zip(tz, tr)], dtype=float)


def coupling_worst_case_arcsec(timeline: Timeline, t_zero_s, t_read_s, tilt_deg: float,
                               perpendicular_dps: float, **kw) -> np.ndarray:
    """max over α of |coupling error| for each reading, ″ (see :class:`CouplingTerms`).

    >>> tl = Timeline(); _ = tl.move(180.0, 1e6, 1e12); _ = tl.dwell(10.0)
    >>> round(float(coupling_worst_case_arcsec(tl, 0.0, tl.end_s, 0.1, 11.522126 / 3600)[0]), 4)
    0.4022
    """
    tz = np.atleast_1d(np.asarray(t_zero_s, dtype=float))
    tr = np.atleast_1d(np.asarray(t_read_s, dtype=float))
    tz, tr = np.broadcast_arrays(tz, tr)
    return np.array([coupling_terms(timeline, a, b, tilt_deg, perpendicular_dps, **kw)
                     .worst_case_arcsec() for a, b in zip(tz, tr)], dtype=float)



