"""Earth-rate compensation (draft clause 7 preamble): its residual and that residual's uncertainty.

Contents
--------
:func:`computed_residual_dps`          residual rate of a compensation computed with wrong inputs
:func:`computed_compensation`          computed from latitude and axis direction: residual, u
:func:`measured_compensation`          measured in a static phase of averaging time T: residual, u
:class:`CompensationResidual`          rate (″/s), angle after a measuring time t (″), budget component
:func:`pointing_consistency_prediction` what 7.7 shows when the compensation is wrong

The draft asks that "before calibration the instrument completes warm-up and
Earth-rate compensation" (clause 7) and removes the Earth-rotation angle from the
Annex A.2 model on that ground; it says neither how nor how well. Two ways:

*computed*: subtract Ω_E·a, with a the table axis in ENU from the site latitude φ
and the axis's azimuth A and elevation E (:mod:`gonio.physics.earth`). Its residual is
Ω·a(φ, A, E) − Ω·a(φ_c, A_c, E_c) plus the instrument's bias b, which this way
leaves in. Standard uncertainty by the law of propagation (JCGM 100 5.1.2):

    u² = (∂(Ω·a)/∂φ · u_φ)² + (Ω·d_E · u_level)² + (Ω·d_X)²[(u_A cos E)² + (u_level sin E)²] + u_b²

with d_E = ∂a/∂E (the elevation direction) and d_X = a × d_E (horizontal, across
it): a rotation about the local vertical by δA moves a by δA cos E along d_X; a
levelling error moves it by u_level along d_E and, for a (near-)vertical axis, along
d_X as well. For a vertical axis the result is u² = (Ω cos φ u_φ)² + (Ω cos φ
u_level)² (levelling towards north) + u_b², for a horizontal axis pointing north
(Ω sin φ u_φ)² + (Ω sin φ u_level)² + u_b² (azimuth enters to second order only),
pointing east (Ω cos φ u_A)² + u_b².

*measured*: average the instrument's own rate over a static phase of length T
just before the series, at the zero position; this removes the Earth rate *and*
the bias. Residual 0 on average; standard uncertainty (IEEE 952 Annex C; the
noise terms as in :mod:`gonio.specs.ogam_draft.bench.instrument`)

    u² = (N/√T)² + B² + 2(q/√12)²/T²

N the angle random walk (°/√h → N/60 °/√s), B the bias instability taken as the
standard uncertainty of the bias change between the static phase and the
reading, q = 1/K the counter's quantum (two counter readings, each floored).

Either residual rate r becomes an angle error r·t at a reading taken t after
zeroing (Annex A.1: t ≤ 0.5 min). :func:`gonio.specs.ogam_draft.budget_extra.compensation_component`
turns its standard uncertainty into an :class:`~gonio.specs.ogam_draft.budget_extra.ExtraComponent`
(normal, half-width = u) for a specification's Annex A budget — off by
default, so the draft's budget stays reproducible. A tilted sensing axis adds a
further, position-dependent residual (:mod:`gonio.specs.ogam_draft.coupling`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from gonio.physics.earth import (OMEGA_E_ARCSEC_S, axis_az_el_deg, axis_enu, earth_rate_enu,
                                 earth_rate_on_axis_dps)
from gonio.errors import GonioError
from gonio.units import ARCSEC_PER_DEG, S_PER_H, arcsec_sqrt_s_from_deg_sqrt_h


@dataclass(frozen=True)
class CompensationResidual:
    """The residual of an Earth-rate compensation, as a rate and as an angle after ``measuring_time_s``."""

    method: str                     # "computed" or "measured"
    rate_arcsec_s: float            # signed systematic residual rate (for the stated errors)
    u_rate_arcsec_s: float          # its standard uncertainty
    components_arcsec_s: dict = field(default_factory=dict)   # contributions to u (″/s)
    measuring_time_s: float = 30.0

    @property
    def angle_arcsec(self) -> float:
        """Systematic angle error r·t at the measuring time, ″."""
        return self.rate_arcsec_s * self.measuring_time_s

    @property
    def u_angle_arcsec(self) -> float:
        """Standard uncertainty of the angle error, u(r)·t, ″."""
        return self.u_rate_arcsec_s * self.measuring_time_s

    def angle_error_arcsec(self, time_s) -> np.ndarray:
        """r·t for readings taken ``time_s`` after zeroing, ″."""
        return self.rate_arcsec_s * np.asarray(time_s, dtype=float)

    def to_dict(self) -> dict:
        """Plain dict."""
        return {"method": self.method, "rate_arcsec_s": self.rate_arcsec_s,
                "u_rate_arcsec_s": self.u_rate_arcsec_s,
                "components_arcsec_s": dict(self.components_arcsec_s),
                "measuring_time_s": self.measuring_time_s, "angle_arcsec": self.angle_arcsec,
                "u_angle_arcsec": self.u_angle_arcsec}


def _rate_arcsec_s(latitude_deg: float, az_deg: float, el_deg: float) -> float:
    return earth_rate_on_axis_dps(latitude_deg, (az_deg, el_deg)) * ARCSEC_PER_DEG


def computed_residual_dps(latitude_deg: float, axis="up", *,
                          compensation_latitude_deg: float | None = None,
                          azimuth_error_deg: float = 0.0,
                          elevation_error_deg: float = 0.0) -> float:
    """Residual rate of a computed compensation with wrong inputs, °/s (exact, not linearised).

    True Earth rate on the axis minus the one computed for latitude
    ``compensation_latitude_deg`` and the axis at azimuth A + δA, elevation E + δE
    (draft 7 preamble; Earth rate per :func:`gonio.physics.earth.earth_rate_on_axis_dps`).

    Examples
    --------
    Axis up at 40° N computed with 41°: Ω_E (sin 40° − sin 41°) = −0.1996″/s;
    axis east with a 1° azimuth error: −Ω_E cos 40° cos 91° = +0.2011″/s.

    >>> round(computed_residual_dps(40.0, "up", compensation_latitude_deg=41.0) * 3600, 4)
    -0.1996
    >>> round(computed_residual_dps(40.0, "east", azimuth_error_deg=1.0) * 3600, 4)
    0.2011
    """
    az, el = axis_az_el_deg(axis)
    lat_c = latitude_deg if compensation_latitude_deg is None else compensation_latitude_deg
    el_c = max(-90.0, min(90.0, el + elevation_error_deg))
    return (_rate_arcsec_s(latitude_deg, az, el)
            - _rate_arcsec_s(lat_c, az + azimuth_error_deg, el_c)) / ARCSEC_PER_DEG


def computed_compensation(latitude_deg: float, axis="up", *, measuring_time_s: float = 30.0,
                          u_latitude_deg: float = 0.0, u_azimuth_deg: float = 0.0,
                          u_level_deg: float = 0.0, bias_dph: float = 0.0,
                          u_bias_dph: float = 0.0,
                          compensation_latitude_deg: float | None = None,
                          azimuth_error_deg: float = 0.0,
                          elevation_error_deg: float = 0.0) -> CompensationResidual:
    """Earth-rate compensation computed from latitude and axis: residual and u (module docstring).

    Parameters
    ----------
    latitude_deg, axis
        Site latitude; table axis (name or AZ,EL).
    measuring_time_s : float
        Time from zeroing to the reading (Annex A.1, A.4.3: 0.5 min).
    u_latitude_deg, u_azimuth_deg, u_level_deg : float
        Standard uncertainties of the latitude, of the axis azimuth (true north) and of
        its levelling (local horizontal), degrees (draft 7.7: "set with reference to
        the local horizontal and true north").
    bias_dph, u_bias_dph : float
        Instrument bias, °/h, and its standard uncertainty: a computed compensation
        leaves the bias in the residual.
    compensation_latitude_deg, azimuth_error_deg, elevation_error_deg
        Known errors of the inputs actually used (give the signed residual).

    Examples
    --------
    Axis up at 40° N, latitude known to 0.01°, levelled to 0.01°, bias 0.005 °/h
    ± 0.002 °/h (1 °/h = 1″/s): u² = (11.5221″/s × 0.01° in rad)² × 2 + (0.002″/s)²
    = (0.002011² × 2 + 0.002²) (″/s)², u = 0.003477″/s; over 30 s 0.1043″:

    >>> r = computed_compensation(40.0, "up", u_latitude_deg=0.01, u_level_deg=0.01,
    ...                           bias_dph=0.005, u_bias_dph=0.002)
    >>> round(r.rate_arcsec_s, 4), round(r.u_rate_arcsec_s, 6), round(r.u_angle_arcsec, 4)
    (0.005, 0.003477, 0.1043)
    """
    if not (math.isfinite(measuring_time_s) and measuring_time_s >= 0):
        raise GonioError(f"measuring time must be ≥ 0 s, got {measuring_time_s}")
    for name, v in (("u_latitude_deg", u_latitude_deg), ("u_azimuth_deg", u_azimuth_deg),
                    ("u_level_deg", u_level_deg), ("u_bias_dph", u_bias_dph)):
        if not (math.isfinite(v) and v >= 0):
            raise GonioError(f"{name} must be ≥ 0, got {v}")
    az, el = axis_az_el_deg(axis)
    a = axis_enu((az, el))
    w = np.degrees(earth_rate_enu(latitude_deg)) * ARCSEC_PER_DEG        # ″/s, ENU
    phi = math.radians(latitude_deg)
    dw_dphi = OMEGA_E_ARCSEC_S * np.array([0.0, -math.sin(phi), math.cos(phi)])   # ∂Ω/∂φ
    azr, elr = math.radians(az), math.radians(el)
    d_e = np.array([-math.sin(elr) * math.sin(azr), -math.sin(elr) * math.cos(azr), math.cos(elr)])
    d_x = np.cross(a, d_e)
    c_lat = float(dw_dphi @ a) * math.radians(u_latitude_deg)
    c_lev = float(w @ d_e) * math.radians(u_level_deg)
    c_x = float(w @ d_x) * math.hypot(math.radians(u_azimuth_deg) * math.cos(elr),
                                      math.radians(u_level_deg) * math.sin(elr))
    c_b = u_bias_dph  # °/h → ″/s: 1 °/h = 1 ″/s
    comps = {"latitude": abs(c_lat), "levelling": abs(c_lev), "azimuth_cross": abs(c_x),
             "bias": abs(c_b)}
    u = math.sqrt(sum(v * v for v in comps.values()))
    r = computed_residual_dps(latitude_deg, (az, el),
                              compensation_latitude_deg=compensation_latitude_deg,
                              azimuth_error_deg=azimuth_error_deg,
                              elevation_error_deg=elevation_error_deg) * ARCSEC_PER_DEG + bias_dph
    return CompensationResidual("computed", r, u, comps, float(measuring_time_s))


def measured_compensation(averaging_time_s: float, *, arw_dpsh: float = 0.0,
                          bias_instability_dph: float = 0.0,
                          scale_factor_counts_per_deg: float | None = None,
                          measuring_time_s: float = 30.0) -> CompensationResidual:
    """Earth-rate compensation measured in a static phase of length T: residual and u.

    Parameters
    ----------
    averaging_time_s : float
        T, the static phase (protocol ``session.static_s``).
    arw_dpsh : float
        Angle random walk N, °/√h (IEEE 952 Annex C): the mean rate over T has
        u = (N/60)/√T °/s.
    bias_instability_dph : float
        Taken as the standard uncertainty of the bias change between the static
        phase and the reading, °/h (= ″/s).
    scale_factor_counts_per_deg : float, optional
        K; quantisation of the two counter readings over T gives u = (1/K)/√6/T °/s.
    measuring_time_s : float
        Time from zeroing to the reading, s.

    Examples
    --------
    N = 0.001 °/√h, T = 60 s: u = 0.001/60/√60 °/s = 0.007746″/s; over 30 s 0.2324″.

    >>> r = measured_compensation(60.0, arw_dpsh=0.001)
    >>> round(r.u_rate_arcsec_s, 6), round(r.u_angle_arcsec, 4), r.rate_arcsec_s
    (0.007746, 0.2324, 0.0)
    """
    if not (math.isfinite(averaging_time_s) and averaging_time_s > 0):
        raise GonioError(f"averaging time must be > 0 s, got {averaging_time_s}")
    if not (math.isfinite(measuring_time_s) and measuring_time_s >= 0):
        raise GonioError(f"measuring time must be ≥ 0 s, got {measuring_time_s}")
    for name, v in (("arw_dpsh", arw_dpsh), ("bias_instability_dph", bias_instability_dph)):
        if not (math.isfinite(v) and v >= 0):
            raise GonioError(f"{name} must be ≥ 0, got {v}")
    comps = {"angle_random_walk": arcsec_sqrt_s_from_deg_sqrt_h(arw_dpsh) / math.sqrt(averaging_time_s),
             "bias_instability": bias_instability_dph / S_PER_H * ARCSEC_PER_DEG}
    if scale_factor_counts_per_deg:
        comps["quantisation"] = (1.0 / scale_factor_counts_per_deg) / math.sqrt(6.0) \
            / averaging_time_s * ARCSEC_PER_DEG
    u = math.sqrt(sum(v * v for v in comps.values()))
    return CompensationResidual("measured", 0.0, u, comps, float(measuring_time_s))


@dataclass
class PointingPrediction:
    """What 7.7 shows from a constant compensation residual (see :func:`pointing_consistency_prediction`)."""

    residual_arcsec_s: dict          # orientation → r_g
    deviation_arcsec: dict           # orientation → E_g (signed extreme of r_g·t_i)
    points_arcsec: dict              # orientation → r_g·t_i per point
    spread_arcsec: float             # max E_g − min E_g


def pointing_consistency_prediction(latitude_deg: float, times_s,
                                    orientations=("up", "north", "east"), *,
                                    compensation_latitude_deg: float | None = None,
                                    azimuth_error_deg: float = 0.0,
                                    elevation_error_deg: float = 0.0,
                                    bias_dph: float = 0.0) -> PointingPrediction:
    """The deviations 7.7 finds when the computed compensation is wrong.

    With a constant residual r_g in orientation g (:func:`computed_residual_dps`
    plus an uncompensated bias), the reading at point i taken t_i after zeroing
    is off by r_g·t_i; E_g is the signed extreme over the points (draft 7.4
    "E = ± max |E_i|", the signed extreme of the specification's items), and
    C_g's spread is max E_g − min E_g (draft 7.7).

    Examples
    --------
    40° N computed with 41°, readings 14 s and 19 s after zeroing: up
    Ω_E (sin 40° − sin 41°) = −0.1996″/s, north Ω_E (cos 40° − cos 41°) = +0.1705″/s,
    east 0 → E = −3.793″, +3.239″, 0 (at 19 s); spread 7.03″.

    >>> p = pointing_consistency_prediction(40.0, [14.0, 19.0], compensation_latitude_deg=41.0)
    >>> {k: round(v, 3) for k, v in p.deviation_arcsec.items()}, round(p.spread_arcsec, 2)
    ({'up': -3.793, 'north': 3.239, 'east': 0.0}, 7.03)
    """
    t = np.asarray(times_s, dtype=float)
    res, dev, pts = {}, {}, {}
    for g in orientations:
        r = computed_residual_dps(latitude_deg, g, compensation_latitude_deg=compensation_latitude_deg,
                                  azimuth_error_deg=azimuth_error_deg,
                                  elevation_error_deg=elevation_error_deg) * ARCSEC_PER_DEG + bias_dph
        res[g] = r
        pts[g] = r * t
        dev[g] = float(pts[g][np.argmax(np.abs(pts[g]))]) if pts[g].size else float("nan")
    e = np.array(list(dev.values()))
    return PointingPrediction(res, dev, pts, float(e.max() - e.min()))
