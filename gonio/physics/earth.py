"""Earth rate, the local frame and axis directions.

Constants
---------
``OMEGA_E_RAD_S``          IERS nominal Earth rotation rate, rad/s.
``SIDEREAL_DAY_S``         the stellar day used by IEC 62047-20 5.3.3.1, s.
``OMEGA_E_STELLAR_RAD_S``  360°/stellar day, rad/s (IEC 62047-20 reading).

Frames
------
Local ENU (east, north, up). An axis direction is a unit vector in ENU, given by
name (``up``, ``north``, ``south``, ``east``, ``west``) or by azimuth (from
north, towards east) and elevation, both in degrees.

The Earth-rate vector in ENU at latitude φ is Ω_E (0, cos φ, sin φ): on an axis
pointing up its component is Ω_E sin φ, north Ω_E cos φ, east 0.

Ω_E: the IERS nominal value 7.292115×10⁻⁵ rad/s (Conventions 2010, Table 1.1) is
used throughout; 2π per stellar day (86164.0989 s, relative to the fixed stars,
the day IEC 62047-20 5.3.3.1 names) is 7.2921151×10⁻⁵ rad/s: they differ by
1.5×10⁻¹² rad/s (2×10⁻⁸ relative, 3×10⁻⁷ ″/s, 1×10⁻⁵ ″ over the 30 s of Annex A.1).
The often-quoted 7.2921158×10⁻⁵ rad/s is 2π per *sidereal* day (86164.0905 s,
relative to the precessing equinox), 1.2×10⁻⁷ relative above IERS (1.8×10⁻⁶ ″/s).
All are far below anything the draft resolves: the choice is a convention.
(The solar day's 2π/86400 s = 7.2722×10⁻⁵ rad/s is *wrong* here: 0.27 % low,
0.04″/s on the Earth rate.)

:func:`earth_rate` gives one axis's rate in °/h, ″/s and rad/s with its split
into parts along and across the axis (``gonio earth``). The Sagnac scale factors
are in :mod:`gonio.physics.sagnac`.

Note (IEC 62047-20 5.3.3.1 erratum): that text gives the vertical component as
Ω cos λ and the horizontal as Ω sin λ cos φ; physically vertical is Ω sin λ and
horizontal (azimuth φ from north) Ω cos λ cos φ, which is what this module uses.

References
----------
IERS Conventions (2010), Table 1.1 (ω = 7.292115×10⁻⁵ rad/s).
IEC 62047-20:2014 / JIS C 5630-20:2015, 5.3.3.1.
Draft JJF "光学陀螺测角仪校准规范", clauses 4.5, 7, 7.7.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gonio.errors import GonioError
from gonio.physics.kinematics import sensing_axis_basis
from gonio.units import S_PER_H, dph_from_rad_s, dps_to_dph, rad_to_arcsec
from gonio.units import dps_to_arcsec_s  # noqa: F401  (doctests)

#: IERS nominal mean angular velocity of the Earth, rad/s.
OMEGA_E_RAD_S = 7.292115e-5
#: Stellar day (one turn relative to the fixed stars), s; IEC 62047-20 5.3.3.1.
SIDEREAL_DAY_S = 86164.0989
#: 2π per stellar day, rad/s (= 7.2921151×10⁻⁵; differs from the IERS value by
#: 1.5×10⁻¹² rad/s, i.e. 2×10⁻⁸ relative: 3×10⁻⁷ ″/s, negligible here).
OMEGA_E_STELLAR_RAD_S = 2.0 * math.pi / SIDEREAL_DAY_S
#: Earth rate in °/h (IERS value): 15.0411 °/h.
OMEGA_E_DPH = dph_from_rad_s(OMEGA_E_RAD_S)
#: Earth rate in ″/s (IERS value): 15.0411 ″/s.
OMEGA_E_ARCSEC_S = rad_to_arcsec(OMEGA_E_RAD_S)

#: Named axis directions as (azimuth_deg, elevation_deg).
NAMED_AXES = {
    "up": (0.0, 90.0),
    "north": (0.0, 0.0),
    "south": (180.0, 0.0),
    "east": (90.0, 0.0),
    "west": (270.0, 0.0),
}


def axis_enu(axis) -> np.ndarray:
    """Unit vector in ENU of an axis given by name or as (azimuth_deg, elevation_deg).

    >>> axis_enu("north").round(12).tolist()
    [0.0, 1.0, 0.0]
    >>> axis_enu((90.0, 0.0)).round(12).tolist()
    [1.0, 0.0, 0.0]
    """
    if isinstance(axis, str):
        key = axis.strip().lower()
        if key in NAMED_AXES:
            az, el = NAMED_AXES[key]
        else:
            try:
                az, el = (float(v) for v in key.split(","))
            except ValueError:
                raise GonioError(f"unknown axis direction {axis!r}: expected one of "
                                 f"{', '.join(NAMED_AXES)} or AZ,EL in degrees") from None
    else:
        az, el = (float(v) for v in axis)
    if not (math.isfinite(az) and math.isfinite(el)) or abs(el) > 90.0:
        raise GonioError(f"axis elevation must be within ±90°, got {el}")
    a, e = math.radians(az), math.radians(el)
    return np.array([math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e)])


def earth_rate_enu(latitude_deg: float, omega_rad_s: float = OMEGA_E_RAD_S) -> np.ndarray:
    """Earth-rate vector in the local ENU frame, rad/s: Ω (0, cos φ, sin φ).

    >>> (earth_rate_enu(90.0) / OMEGA_E_RAD_S).round(12).tolist()
    [0.0, 0.0, 1.0]
    """
    if not math.isfinite(latitude_deg) or abs(latitude_deg) > 90.0:
        raise GonioError(f"latitude must be within ±90°, got {latitude_deg}")
    p = math.radians(latitude_deg)
    return omega_rad_s * np.array([0.0, math.cos(p), math.sin(p)])


def earth_rate_on_axis_dps(latitude_deg: float, axis="up",
                           omega_rad_s: float = OMEGA_E_RAD_S) -> float:
    """Earth-rate component on an axis, °/s (draft 4.5; IEC 62047-20 5.3.3.1, corrected).

    Up: Ω sin φ; north: Ω cos φ; east/west: 0; south: −Ω cos φ.

    >>> round(earth_rate_on_axis_dps(40.0, "up") * 3600, 3)   # ″/s at 40° N, axis up
    9.668
    >>> round(earth_rate_on_axis_dps(40.0, "north") * 3600, 3)
    11.522
    >>> abs(earth_rate_on_axis_dps(40.0, "east")) < 1e-18
    True
    """
    return float(math.degrees(earth_rate_enu(latitude_deg, omega_rad_s) @ axis_enu(axis)))


def earth_rate_table_frame_dps(latitude_deg: float, axis) -> tuple[float, float, float]:
    """The Earth rate in the frame (a, e₁, e₂) of a table axis a, °/s: (Ω·a, Ω·e₁, Ω·e₂).

    The one place where the Earth rate is resolved along and across a table axis
    (the bench, the coupling budget, the reports and the tilt estimate all use it).
    ``axis`` is a name, (azimuth, elevation) in degrees, or an ENU unit vector;
    e₁, e₂ complete a to a right-handed frame
    (:func:`gonio.physics.kinematics.sensing_axis_basis`).

    >>> [round(x * 3600, 4) for x in earth_rate_table_frame_dps(40.0, "up")]   # ″/s
    [9.6682, 0.0, 11.5221]
    """
    a = np.asarray(axis, dtype=float) if isinstance(axis, np.ndarray) else axis_enu(axis)
    e1, e2 = sensing_axis_basis(a)
    w = np.degrees(earth_rate_enu(latitude_deg))
    return float(w @ a), float(w @ e1), float(w @ e2)


@dataclass(frozen=True)
class EarthRateSplit:
    """Earth rate relative to a table axis: parallel and perpendicular parts, °/s, and the
    direction β of the perpendicular part in the table frame (e₁, e₂), degrees."""

    parallel_dps: float
    perpendicular_dps: float
    perpendicular_direction_deg: float = 0.0


def earth_rate_split(latitude_deg: float, axis="up") -> EarthRateSplit:
    """Split Ω_E into its components along and across a table axis, °/s.

    The perpendicular part Ω_⊥ drives the tilt × Earth-rate coupling
    (``docs/draft-readings.md#what-the-draft-leaves-out``); a tilt with azimuth
    α_table in the table frame has α = α_table − β relative to Ω_⊥.

    >>> s = earth_rate_split(40.0, "up")       # e₁ east, e₂ north: Ω_⊥ points north
    >>> round(dps_to_arcsec_s(s.perpendicular_dps), 2), round(s.perpendicular_direction_deg, 6)
    (11.52, 90.0)
    """
    par, p1, p2 = earth_rate_table_frame_dps(latitude_deg, axis)
    return EarthRateSplit(par, math.hypot(p1, p2), math.degrees(math.atan2(p2, p1)))


# --- reports for the CLI -------------------------------------------------------



@dataclass(frozen=True)
class EarthRate:
    """Earth rate on one axis at one latitude (see :func:`earth_rate`)."""

    latitude_deg: float
    axis_azimuth_deg: float
    axis_elevation_deg: float
    axis_enu: tuple[float, float, float]
    rate_dph: float
    rate_arcsec_s: float
    rate_rad_s: float
    parallel_dph: float
    perpendicular_dph: float
    perpendicular_arcsec_s: float
    omega_rad_s: float

    def to_dict(self) -> dict:
        """Plain dict (for ``--json``)."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}


def axis_az_el_deg(axis) -> tuple[float, float]:
    """(azimuth_deg, elevation_deg) of an axis given by name or AZ,EL.

    >>> axis_az_el_deg("east"), axis_az_el_deg("30,10")
    ((90.0, 0.0), (30.0, 10.0))
    """
    a = axis_enu(axis)
    el = math.degrees(math.asin(max(-1.0, min(1.0, float(a[2])))))
    if isinstance(axis, str) and axis.strip().lower() in NAMED_AXES:
        return NAMED_AXES[axis.strip().lower()]
    if isinstance(axis, str):
        az = float(axis.split(",")[0])
    else:
        az = float(axis[0])
    return az, el


def earth_rate(latitude_deg: float, axis="up", omega_rad_s: float = OMEGA_E_RAD_S) -> EarthRate:
    """The Earth rate on an axis (draft 4.5, 7.7; "Physics the draft relies on").

    Ω·a with Ω = Ω_E (0, cos φ, sin φ) in ENU; for an axis at azimuth A (from
    north towards east) and elevation E that is Ω_E (cos φ cos E cos A + sin φ sin E)
    (IEC 62047-20 5.3.3.1 with its cos/sin erratum corrected). The part across
    the axis, Ω_⊥ = Ω_E·sqrt(1 − (Ω̂·a)²), is what a tilted sensing axis picks up
    as the table turns (the tilt × Earth-rate coupling of a reading).

    Examples
    --------
    At 40° N, axis up: 15.0411 °/h × sin 40° = 9.6682 °/h = 9.6682 ″/s.

    >>> r = earth_rate(40.0, "up")
    >>> round(r.rate_dph, 4), round(r.rate_arcsec_s, 4), f"{r.rate_rad_s:.4e}"
    (9.6682, 9.6682, '4.6873e-05')
    >>> round(r.perpendicular_dph, 4)           # 15.0411 × cos 40°
    11.5221
    >>> round(earth_rate(40.0, "0,40").rate_dph, 4)   # pointing at the pole: all of Ω
    15.0411
    """
    az, el = axis_az_el_deg(axis)
    a = axis_enu((az, el))
    split = earth_rate_split(latitude_deg, (az, el))
    scale = omega_rad_s / OMEGA_E_RAD_S
    dph = dps_to_dph(split.parallel_dps) * scale
    perp_dph = dps_to_dph(split.perpendicular_dps) * scale
    return EarthRate(float(latitude_deg), az, el, tuple(float(x) for x in a.round(15)),
                     dph, dph, math.radians(dph / S_PER_H), dph, perp_dph, perp_dph, omega_rad_s)
