"""Units: every constant and conversion gonio uses, in one place.

Names carry their unit (``_deg``, ``_arcsec``, ``_rad``, ``_s``, ``_h``, ``_dps``
for °/s, ``_dph`` for °/h); values are converted here and nowhere else. A test
(``tests/test_layers.py``) checks that no other module writes the bare literals
3600 or 206264.8.

Angle random walk (ARW) and rate random walk (RRW) units follow IEEE Std 952-1997
Annex C: N in °/√h equals 60·N in (°/h)/√Hz, since √h = 60 √s.

>>> ARCSEC_PER_DEG, S_PER_H, round(ARCSEC_PER_RAD, 3)
(3600.0, 3600.0, 206264.806)
>>> deg_to_arcsec(0.5), arcsec_to_deg(1800.0)
(1800.0, 0.5)
>>> dph_to_dps(36.0), dps_to_dph(0.01)
(0.01, 36.0)
"""

from __future__ import annotations

import math

__all__ = [
    "ARCSEC_PER_DEG", "ARCMIN_PER_DEG", "ARCSEC_PER_RAD", "DEG_PER_RAD", "S_PER_MIN",
    "MIN_PER_H", "S_PER_H", "S_PER_DAY", "PPM", "PERCENT", "STANDARD_GRAVITY_M_S2",
    "deg_to_arcsec", "arcsec_to_deg", "rad_to_arcsec", "arcsec_to_rad",
    "dph_to_dps", "dps_to_dph", "dps_to_arcsec_s", "arcsec_s_to_dph", "dph_to_arcsec_s",
    "rad_s_from_dph", "dph_from_rad_s", "s_to_h", "h_to_s", "min_to_s",
    "dph_sqrt_hz_from_deg_sqrt_h", "deg_sqrt_h_from_dph_sqrt_hz",
    "arcsec_sqrt_s_from_deg_sqrt_h", "deg_sqrt_h_from_arcsec_sqrt_s",
    "rad_s_sqrt_hz_from_deg_sqrt_h", "deg_sqrt_h_from_rad_s_sqrt_hz",
    "deg_sqrt_s_from_deg_sqrt_h", "dph_per_sqrt_h_from_dph_sqrt_hz_per_s",
]

#: Arcseconds per degree (″/°).
ARCSEC_PER_DEG: float = 3600.0
#: Arcminutes per degree.
ARCMIN_PER_DEG: float = 60.0
#: Degrees per radian.
DEG_PER_RAD: float = 180.0 / math.pi
#: Arcseconds per radian, 206264.806…″.
ARCSEC_PER_RAD: float = DEG_PER_RAD * ARCSEC_PER_DEG
#: Seconds per minute.
S_PER_MIN: float = 60.0
#: Minutes per hour.
MIN_PER_H: float = 60.0
#: Seconds per hour.
S_PER_H: float = S_PER_MIN * MIN_PER_H
#: Seconds per (solar) day.
S_PER_DAY: float = 24.0 * S_PER_H
#: One part per million, as a ratio.
PPM: float = 1e-6
#: One per cent, as a ratio.
PERCENT: float = 1e-2
#: Standard acceleration of gravity g_n (CGPM 1901), m/s².
STANDARD_GRAVITY_M_S2: float = 9.80665


def deg_to_arcsec(x_deg):
    """Degrees → arcseconds (works on floats and numpy arrays)."""
    return x_deg * ARCSEC_PER_DEG


def arcsec_to_deg(x_arcsec):
    """Arcseconds → degrees."""
    return x_arcsec / ARCSEC_PER_DEG


def rad_to_arcsec(x_rad):
    """Radians → arcseconds.

    >>> round(rad_to_arcsec(1e-6), 6)
    0.206265
    """
    return x_rad * ARCSEC_PER_RAD


def arcsec_to_rad(x_arcsec):
    """Arcseconds → radians."""
    return x_arcsec / ARCSEC_PER_RAD


def dph_to_dps(rate_dph):
    """°/h → °/s."""
    return rate_dph / S_PER_H


def dps_to_dph(rate_dps):
    """°/s → °/h."""
    return rate_dps * S_PER_H


def dps_to_arcsec_s(rate_dps):
    """°/s → ″/s."""
    return rate_dps * ARCSEC_PER_DEG


def dph_to_arcsec_s(rate_dph):
    """°/h → ″/s (numerically the same: 3600″/3600 s).

    >>> dph_to_arcsec_s(15.0)
    15.0
    """
    return rate_dph * ARCSEC_PER_DEG / S_PER_H


def arcsec_s_to_dph(rate_arcsec_s):
    """″/s → °/h."""
    return rate_arcsec_s * S_PER_H / ARCSEC_PER_DEG


def rad_s_from_dph(rate_dph):
    """Rate °/h → rad/s (π/180/3600).

    >>> f"{rad_s_from_dph(15.041):.4e}"
    '7.2921e-05'
    """
    return rate_dph / DEG_PER_RAD / S_PER_H


def dph_from_rad_s(rate_rad_s):
    """Rate rad/s → °/h (180·3600/π).

    >>> round(dph_from_rad_s(7.292115e-5), 4)
    15.0411
    """
    return rate_rad_s * DEG_PER_RAD * S_PER_H


def s_to_h(t_s):
    """Seconds → hours."""
    return t_s / S_PER_H


def h_to_s(t_h):
    """Hours → seconds."""
    return t_h * S_PER_H


def min_to_s(t_min):
    """Minutes → seconds."""
    return t_min * S_PER_MIN


# ----------------------------------------------------------------- noise coefficients
def dph_sqrt_hz_from_deg_sqrt_h(arw_deg_sqrt_h):
    """Angle random walk °/√h → (°/h)/√Hz: ×60 (IEEE 952 C.1).

    >>> dph_sqrt_hz_from_deg_sqrt_h(0.01)
    0.6
    """
    return arw_deg_sqrt_h * MIN_PER_H


def deg_sqrt_h_from_dph_sqrt_hz(arw_dph_sqrt_hz):
    """Angle random walk (°/h)/√Hz → °/√h: ÷60.

    >>> deg_sqrt_h_from_dph_sqrt_hz(0.6)
    0.01
    """
    return arw_dph_sqrt_hz / MIN_PER_H


def arcsec_sqrt_s_from_deg_sqrt_h(arw_deg_sqrt_h):
    """Angle random walk °/√h → ″/√s: 3600″ / 60 √s = 60 ″/√s per °/√h.

    >>> round(arcsec_sqrt_s_from_deg_sqrt_h(0.001), 12)
    0.06
    """
    return arw_deg_sqrt_h * ARCSEC_PER_DEG / math.sqrt(S_PER_H)


def deg_sqrt_h_from_arcsec_sqrt_s(arw_arcsec_sqrt_s):
    """Angle random walk ″/√s → °/√h.

    >>> round(deg_sqrt_h_from_arcsec_sqrt_s(0.06), 12)
    0.001
    """
    return arw_arcsec_sqrt_s * math.sqrt(S_PER_H) / ARCSEC_PER_DEG


def rad_s_sqrt_hz_from_deg_sqrt_h(arw_deg_sqrt_h):
    """Angle random walk °/√h → (rad/s)/√Hz = rad/√s.

    >>> f"{rad_s_sqrt_hz_from_deg_sqrt_h(1.0):.4e}"
    '2.9089e-04'
    """
    return arw_deg_sqrt_h / DEG_PER_RAD / math.sqrt(S_PER_H)


def deg_sqrt_h_from_rad_s_sqrt_hz(arw_rad_s_sqrt_hz):
    """Angle random walk (rad/s)/√Hz → °/√h.

    >>> round(deg_sqrt_h_from_rad_s_sqrt_hz(2.908882e-4), 6)
    1.0
    """
    return arw_rad_s_sqrt_hz * math.sqrt(S_PER_H) * DEG_PER_RAD


def deg_sqrt_s_from_deg_sqrt_h(arw_deg_sqrt_h):
    """Angle random walk °/√h → °/√s (the white rate density in (°/s)/√Hz): ÷60."""
    return arw_deg_sqrt_h / math.sqrt(S_PER_H)


def dph_per_sqrt_h_from_dph_sqrt_hz_per_s(k_dph_per_sqrt_s):
    """Rate random walk (°/h)/√s → (°/h)/√h: ×60."""
    return k_dph_per_sqrt_s * math.sqrt(S_PER_H)
