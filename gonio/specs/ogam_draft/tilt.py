"""Errors caused by a tilt ψ between the gyro's sensing plane and the table's plane.

Two models, side by side:

- **Elliptic projection** (draft Annex A.4.2), the draft's own model: the sensed
  path is the table circle projected on the tilted plane, and the scale factor is
  fixed over a full turn, so the reading is
  φ_e(θ) = 360°·F(θ)/F(2π) with F(θ) = ∫₀^θ dθ'/√(cos²ψ cos²θ' + sin²θ'),
  and the error Δ(θ; ψ) = φ_e(θ) − θ. Since cos²ψ cos²θ + sin²θ = 1 − sin²ψ cos²θ,
  F is an incomplete elliptic integral of the first kind with parameter m = sin²ψ.
  Three evaluations that must agree: quadrature, closed form, sympy series
  Δ = (ψ²/8)·sin 2θ + O(ψ⁴). Extreme ±ψ²/8 at 45°, 135°, 225°, 315° (signs
  alternating): 0.0785″ at ψ = 0.1° (the annex prints 0.08″).
- **Rigid body** (physics of a rate gyro): a gyro measures ω·n, so with its axis n
  tilted by ψ from the table axis it senses ω cos ψ at every θ — a pure scale
  factor. Uncalibrated, the error is θ(cos ψ − 1); after the scale-factor
  calibration over a full turn (which absorbs cos ψ) it is exactly 0.

Functions: :func:`elliptic_error_arcsec`, :func:`elliptic_series`,
:func:`elliptic_extreme`, :func:`rigid_error_arcsec`, :func:`rigid_extreme`.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy import integrate, special

from gonio.units import ARCSEC_PER_DEG, ARCSEC_PER_RAD

__all__ = ["TiltExtreme", "ARCSEC_PER_RAD", "elliptic_error_arcsec", "elliptic_series",
           "elliptic_extreme", "rigid_error_arcsec", "rigid_extreme"]



@dataclass(frozen=True)
class TiltExtreme:
    """Largest |error| over 0–360° and the table angles where it occurs.

    ``extreme_arcsec`` is the (non-negative) largest |Δ|; ``at_deg`` the angles.
    """

    extreme_arcsec: float
    at_deg: tuple[float, ...]
    model: str = "elliptic"
    tilt_deg: float = 0.0


def _check_tilt(tilt_deg: float) -> float:
    t = float(tilt_deg)
    if not (0.0 <= abs(t) < 90.0):
        raise ValueError(f"tilt must satisfy |tilt_deg| < 90, got {tilt_deg}")
    return t


# ----------------------------------------------------------------------- closed form
def _f_ours(theta: np.ndarray, m: float) -> np.ndarray:
    """F(θ) = ∫₀^θ dθ'/√(1 − m cos²θ') via F(φ|m) = ellipkinc(φ, m).

    Substituting t = π/2 − θ': F(θ) = K(m) − F(π/2 − θ | m). The argument is reduced
    with the quasi-periodicity F(φ + nπ | m) = F(φ | m) + 2nK(m), so ellipkinc only
    sees |φ| ≤ π/2.
    """
    k = special.ellipk(m)
    phi = np.pi / 2 - theta
    n = np.round(phi / np.pi)
    r = phi - n * np.pi
    return k - (special.ellipkinc(r, m) + 2.0 * n * k)


def _error_closed_rad(theta: np.ndarray, psi: float) -> np.ndarray:
    m = math.sin(psi) ** 2
    k = special.ellipk(m)
    return 2.0 * np.pi * _f_ours(theta, m) / (4.0 * k) - theta


# ----------------------------------------------------------------------- quadrature
def _error_quad_rad(theta: np.ndarray, psi: float) -> np.ndarray:
    """Quadrature of F(θ) − θ = ∫₀^θ (f − 1) (the −1 keeps the small part accurate)."""
    m = math.sin(psi) ** 2
    g = lambda t: 1.0 / math.sqrt(1.0 - m * math.cos(t) ** 2) - 1.0
    opts = dict(epsabs=1e-300, epsrel=1e-11, limit=200)
    total = integrate.quad(g, 0.0, 2.0 * np.pi, **opts)[0]
    out = np.empty_like(theta)
    for i, t in enumerate(theta.flat):  # one integral per requested angle
        part = integrate.quad(g, 0.0, float(t), **opts)[0] if t != 0.0 else 0.0
        # Δ = 2π(θ + G(θ))/(2π + G(2π)) − θ = (2π G(θ) − θ G(2π)) / (2π + G(2π))
        out.flat[i] = (2.0 * np.pi * part - float(t) * total) / (2.0 * np.pi + total)
    return out


# ----------------------------------------------------------------------- series
@functools.lru_cache(maxsize=8)
def elliptic_series(order: int = 4) -> "sympy.Expr":
    """Δ(θ; ψ) in radians as a sympy series in ψ through ψ^order (draft Annex A.4.2).

    Derived here: expand 1/√(1 − sin²ψ cos²θ) in ψ, integrate term by term from 0 to
    θ and to 2π, form 2π·F(θ)/F(2π) − θ and re-expand. The leading term is
    (ψ²/8)·sin 2θ.

    >>> import sympy
    >>> th, ps = sympy.symbols("theta psi", real=True)
    >>> sympy.simplify(elliptic_series(2) - ps**2 * sympy.sin(2 * th) / 8)
    0
    """
    import sympy                       # lazily: only the series needs it
    th, ps, t = sympy.symbols("theta psi t", real=True)
    n = order + 1
    f = sympy.series(1 / sympy.sqrt(1 - sympy.sin(ps) ** 2 * sympy.cos(t) ** 2), ps, 0, n).removeO()
    f = sympy.expand(f)
    coeffs = sympy.Poly(f, ps).all_coeffs()[::-1]
    big_f = 0
    big_f2pi = 0
    for j, cj in enumerate(coeffs):
        if cj == 0:
            continue
        big_f += ps ** j * sympy.integrate(cj, (t, 0, th))
        big_f2pi += ps ** j * sympy.integrate(cj, (t, 0, 2 * sympy.pi))
    delta = sympy.series(2 * sympy.pi * big_f / big_f2pi - th, ps, 0, n).removeO()
    return sympy.simplify(sympy.expand(sympy.expand_trig(delta).rewrite(sympy.sin)))


@functools.lru_cache(maxsize=8)
def _series_fn(order: int):
    import sympy
    th, ps = sympy.symbols("theta psi", real=True)
    return sympy.lambdify((th, ps), elliptic_series(order), "numpy")


# ----------------------------------------------------------------------- public
def elliptic_error_arcsec(theta_deg, tilt_deg: float, method: str = "closed",
                          order: int = 4):
    """Elliptic-projection error Δ(θ; ψ) in arc-seconds (draft Annex A.4.2).

    Δ(θ) = 360°·F(θ)/F(2π) − θ, F(θ) = ∫₀^θ dθ'/√(cos²ψ cos²θ' + sin²θ').

    Parameters
    ----------
    theta_deg : array_like
        Table angle(s) θ in degrees (vectorised).
    tilt_deg : float
        Tilt ψ between the sensing and table planes, |ψ| < 90°.
    method : {"closed", "quad", "series"}
        Incomplete elliptic integral (scipy.special.ellipkinc), adaptive quadrature
        (scipy.integrate.quad), or the sympy series through ψ^order.

    Examples
    --------
    >>> round(float(elliptic_error_arcsec(45.0, 0.1)), 4)
    0.0785
    >>> [round(float(v), 4) for v in elliptic_error_arcsec([135.0, 225.0], 0.1, method="quad")]
    [-0.0785, 0.0785]
    """
    psi = math.radians(_check_tilt(tilt_deg))
    theta = np.radians(np.asarray(theta_deg, dtype=float))
    scalar = theta.ndim == 0
    theta = np.atleast_1d(theta)
    if method == "closed":
        d = _error_closed_rad(theta, psi)
    elif method == "quad":
        d = _error_quad_rad(theta, psi)
    elif method == "series":
        d = np.asarray(_series_fn(order)(theta, psi), dtype=float) * np.ones_like(theta)
    else:
        raise ValueError(f"method must be 'closed', 'quad' or 'series', got {method!r}")
    d = d * ARCSEC_PER_RAD
    return float(d[0]) if scalar else d


def elliptic_extreme(tilt_deg: float) -> TiltExtreme:
    """Largest |Δ| over 0–360° of the elliptic-projection error and where (Annex A.4.2).

    At an extreme dΔ/dθ = 0, i.e. f(θ*) = F(2π)/(2π) = 2K/π, so
    cos²θ* = (1 − (π/(2K))²)/m with m = sin²ψ: θ* = 45° + O(ψ²), and the extremes
    are at θ*, 180° − θ*, 180° + θ*, 360° − θ* (signs +, −, +, −).

    >>> e = elliptic_extreme(0.1)
    >>> round(e.extreme_arcsec, 4), [round(a, 3) for a in e.at_deg]
    (0.0785, [45.0, 135.0, 225.0, 315.0])
    """
    t = _check_tilt(tilt_deg)
    psi = math.radians(abs(t))
    m = math.sin(psi) ** 2
    if m == 0.0:
        return TiltExtreme(0.0, (45.0, 135.0, 225.0, 315.0), "elliptic", t)
    k = special.ellipk(m)
    c2 = (1.0 - (math.pi / (2.0 * k)) ** 2) / m
    th = math.degrees(math.acos(math.sqrt(min(max(c2, 0.0), 1.0))))
    at = (th, 180.0 - th, 180.0 + th, 360.0 - th)
    val = float(np.max(np.abs(elliptic_error_arcsec(np.array(at), t))))
    return TiltExtreme(val, at, "elliptic", t)


def rigid_error_arcsec(theta_deg, tilt_deg: float, calibrated: bool = True):
    """Rigid-body tilt error in arc-seconds: a rate gyro senses ω·n = ω cos ψ.

    Uncalibrated: Δ = θ(cos ψ − 1). After the scale-factor calibration over a full
    turn (draft 7.x; it absorbs the constant cos ψ): Δ = 0 exactly. This is the
    alternative to the draft's elliptic model (Annex A.4.2), which assumes the
    scale factor is fixed but the sensed path is an ellipse.

    >>> round(float(rigid_error_arcsec(360.0, 0.1, calibrated=False)), 4)
    -1.9739
    >>> float(rigid_error_arcsec(45.0, 0.1))
    0.0
    """
    psi = math.radians(_check_tilt(tilt_deg))
    theta = np.asarray(theta_deg, dtype=float)
    if calibrated:
        d = np.zeros_like(theta)
    else:
        d = theta * ARCSEC_PER_DEG * (-2.0 * math.sin(psi / 2.0) ** 2)  # cos ψ − 1 without cancellation
    return float(d) if d.ndim == 0 else d


def rigid_extreme(tilt_deg: float, calibrated: bool = True) -> TiltExtreme:
    """Largest |Δ| of the rigid-body model over 0–360°.

    Calibrated: 0 (no angle singled out, ``at_deg`` empty). Uncalibrated:
    360°·(1 − cos ψ) at θ = 360°.

    >>> rigid_extreme(0.1).extreme_arcsec
    0.0
    >>> round(rigid_extreme(0.1, calibrated=False).extreme_arcsec, 4)
    1.9739
    """
    t = _check_tilt(tilt_deg)
    if calibrated:
        return TiltExtreme(0.0, (), "rigid", t)
    return TiltExtreme(abs(float(rigid_error_arcsec(360.0, t, calibrated=False))), (360.0,),
                       "rigid-uncalibrated", t)
