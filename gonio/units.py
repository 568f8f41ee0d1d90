"""Unit constants and conversions used by the noise analysis (one place for each factor).

Only the helpers that lived privately in the noise module are here; the project's
full table of units joins this module when the layout restructure lands.

Angle random walk (ARW) is quoted in several customary units (IEEE Std 952-1997,
Annex C.2): °/√h, (°/h)/√Hz, ″/√s and rad/s/√Hz. 1 °/√h = 1 (°/h)·√h = 60 (°/h)·√s,
and (°/h)·√s = (°/h)/√Hz, so the factor between the first two is √(3600 s/h) = 60.
"""

from __future__ import annotations

import math

#: Seconds per hour.
S_PER_H = 3600.0
#: √(seconds per hour) = 60 √s/√h: the factor between °/√h and (°/h)/√Hz.
SQRT_S_PER_SQRT_H = 60.0
#: Arc-seconds per degree.
ARCSEC_PER_DEG = 3600.0
#: Radians per degree.
RAD_PER_DEG = math.pi / 180.0

__all__ = [
    "S_PER_H", "SQRT_S_PER_SQRT_H", "ARCSEC_PER_DEG", "RAD_PER_DEG",
    "arw_deg_sqrt_h_to_dph_sqrt_hz", "arw_dph_sqrt_hz_to_deg_sqrt_h",
    "arw_deg_sqrt_h_to_arcsec_sqrt_s", "arw_arcsec_sqrt_s_to_deg_sqrt_h",
    "arw_deg_sqrt_h_to_rad_s_sqrt_hz", "arw_rad_s_sqrt_hz_to_deg_sqrt_h",
    "dph_to_rad_s", "rad_s_to_dph",
    "rrw_dph_sqrt_s_to_dph_sqrt_h", "ramp_dph_per_s_to_dph_per_h",
]


def arw_deg_sqrt_h_to_dph_sqrt_hz(arw_deg_sqrt_h):
    """Angle random walk °/√h -> (°/h)/√Hz (× 60, IEEE 952 C.2).

    >>> arw_deg_sqrt_h_to_dph_sqrt_hz(0.01)
    0.6
    """
    return arw_deg_sqrt_h * SQRT_S_PER_SQRT_H


def arw_dph_sqrt_hz_to_deg_sqrt_h(arw_dph_sqrt_hz):
    """Angle random walk (°/h)/√Hz = (°/h)·√s -> °/√h (÷ 60, IEEE 952 C.2).

    >>> arw_dph_sqrt_hz_to_deg_sqrt_h(0.6)
    0.01
    """
    return arw_dph_sqrt_hz / SQRT_S_PER_SQRT_H


def arw_deg_sqrt_h_to_arcsec_sqrt_s(arw_deg_sqrt_h):
    """Angle random walk °/√h -> ″/√s: 3600″ / 60 √s = 60 ″/√s per °/√h.

    >>> round(arw_deg_sqrt_h_to_arcsec_sqrt_s(0.002), 12)
    0.12
    """
    return arw_deg_sqrt_h * ARCSEC_PER_DEG / SQRT_S_PER_SQRT_H


def arw_arcsec_sqrt_s_to_deg_sqrt_h(arw_arcsec_sqrt_s):
    """Angle random walk ″/√s -> °/√h (÷ 60).

    >>> round(arw_arcsec_sqrt_s_to_deg_sqrt_h(0.12), 12)
    0.002
    """
    return arw_arcsec_sqrt_s * SQRT_S_PER_SQRT_H / ARCSEC_PER_DEG


def arw_deg_sqrt_h_to_rad_s_sqrt_hz(arw_deg_sqrt_h):
    """Angle random walk °/√h -> rad/s/√Hz = rad/√s: (π/180)/60.

    >>> round(arw_deg_sqrt_h_to_rad_s_sqrt_hz(1.0), 10)
    0.0002908882
    """
    return arw_deg_sqrt_h * RAD_PER_DEG / SQRT_S_PER_SQRT_H


def arw_rad_s_sqrt_hz_to_deg_sqrt_h(arw_rad_s_sqrt_hz):
    """Angle random walk rad/s/√Hz -> °/√h: 60·180/π.

    >>> round(arw_rad_s_sqrt_hz_to_deg_sqrt_h(2.908882086657216e-4), 9)
    1.0
    """
    return arw_rad_s_sqrt_hz * SQRT_S_PER_SQRT_H / RAD_PER_DEG


def dph_to_rad_s(rate_dph):
    """Rate °/h -> rad/s (π/180/3600).

    >>> f"{dph_to_rad_s(15.041067):.5e}"  # Earth rate
    '7.29212e-05'
    """
    return rate_dph * RAD_PER_DEG / S_PER_H


def rad_s_to_dph(rate_rad_s):
    """Rate rad/s -> °/h (180·3600/π).

    >>> round(rad_s_to_dph(7.2921150e-5), 4)  # Earth rate
    15.0411
    """
    return rate_rad_s * S_PER_H / RAD_PER_DEG


def rrw_dph_sqrt_s_to_dph_sqrt_h(rrw_dph_per_sqrt_s):
    """Rate random walk (°/h)/√s -> (°/h)/√h (× 60, IEEE 952 C.5).

    >>> rrw_dph_sqrt_s_to_dph_sqrt_h(0.001)
    0.06
    """
    return rrw_dph_per_sqrt_s * SQRT_S_PER_SQRT_H


def ramp_dph_per_s_to_dph_per_h(ramp_dph_per_s):
    """Rate ramp (°/h)/s -> (°/h)/h (× 3600, IEEE 952 C.6).

    >>> ramp_dph_per_s_to_dph_per_h(0.001)
    3.6
    """
    return ramp_dph_per_s * S_PER_H
