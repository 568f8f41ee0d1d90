"""Sagnac scale factors of ring-laser and fibre-optic gyros, and the Earth rate's signal.

RLG: a ring of area A and perimeter P at wavelength λ gives 4A/(λP) pulses per
radian turned (Aronowitz 1971). FOG: a coil of length L and diameter D gives a
phase 2πLD/(λc) per rad/s (Lefèvre, *The Fiber-Optic Gyroscope*, 2.1). See
``docs/references.md`` for the full citations (``gonio sagnac``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gonio.errors import GonioError
from gonio.physics.earth import OMEGA_E_RAD_S, earth_rate_on_axis_dps
from gonio.units import rad_to_arcsec

# --- Sagnac scale factors ----------------------------------------------------

SPEED_OF_LIGHT_M_S = 299_792_458.0


def rlg_scale_factor_counts_per_rad(area_m2: float, perimeter_m: float,
                                    wavelength_m: float = 632.8e-9) -> float:
    """Ring-laser scale factor 4A/(λP), pulses (fringes) per radian (Sagnac).

    The beat frequency is Δf = 4A/(λP)·Ω; each fringe is one pulse.

    >>> k = rlg_scale_factor_counts_per_rad(0.15**2 * 3**0.5 / 4, 0.45)  # 15 cm triangle
    >>> round(k), round(k * math.pi / 180, 2)        # per rad, per degree
    (136856, 2388.59)
    """
    _check_positive(area_m2=area_m2, perimeter_m=perimeter_m, wavelength_m=wavelength_m)
    _check_optical(wavelength_m, perimeter_m=perimeter_m, area_m2=area_m2)
    # isoperimetric inequality: no closed path of perimeter P encloses more than P²/(4π)
    # (as A/P > P/4π, which cannot overflow)
    if area_m2 / perimeter_m > perimeter_m / (4.0 * math.pi) * (1.0 + 1e-12):
        raise GonioError(f"area_m2 = {area_m2:g} exceeds what a ring of perimeter_m = "
                         f"{perimeter_m:g} can enclose (P²/4π, a circle)")
    return _representable("scale factor 4A/(λP)", 4.0 * area_m2 / (wavelength_m * perimeter_m))


def _check_positive(**values: float) -> None:
    """Physical bounds of the Sagnac inputs: lengths, areas, wavelengths are finite and > 0.

    No upper bound from the instruments one has in mind (UG-2 encloses 834 m², fibre coils
    run to tens of km); what cannot be represented is refused by :func:`_representable`.
    """
    for name, v in values.items():
        if not (math.isfinite(v) and v > 0):
            raise GonioError(f"{name} must be a positive finite number, got {v}")


def _check_optical(wavelength_m: float, **sizes: float) -> None:
    """The Sagnac formulas treat light as rays along the ring or coil: every length must be
    at least one wavelength, an area at least a square wavelength (a "ring" smaller than
    its light has no Sagnac beat to count)."""
    for name, v in sizes.items():
        floor = wavelength_m ** 2 if name.startswith("area") else wavelength_m
        if v < floor:
            unit = "λ²" if name.startswith("area") else "λ"
            raise GonioError(f"{name} = {v:g} is below one wavelength ({unit} = {floor:g}): "
                             "the Sagnac formula assumes rays along the ring")


def _representable(what: str, value: float) -> float:
    """``value`` itself, refused when it over- or underflows a double (no inf, no 0)."""
    if not (math.isfinite(value) and value >= 2.2250738585072014e-308):
        raise GonioError(f"the {what} is not representable as a number ({value}): "
                         "the inputs are too far apart in scale")
    return value


def fog_phase_per_rate_s(length_m: float, diameter_m: float,
                         wavelength_m: float = 1550e-9) -> float:
    """Fibre-optic gyro Sagnac phase per unit rate, 2πLD/(λc), rad per (rad/s) = s.

    >>> round(fog_phase_per_rate_s(1000.0, 0.1), 3)      # 1 km coil, 10 cm diameter
    1.352
    """
    _check_positive(length_m=length_m, diameter_m=diameter_m, wavelength_m=wavelength_m)
    _check_optical(wavelength_m, length_m=length_m, diameter_m=diameter_m)
    return _representable("Sagnac phase per rate 2πLD/(λc)",
                          2.0 * math.pi * length_m * diameter_m
                          / (wavelength_m * SPEED_OF_LIGHT_M_S))


@dataclass(frozen=True)
class Sagnac:
    """Sagnac scale factor of a gyro and the signal the Earth rate gives it."""

    kind: str
    wavelength_m: float
    scale_factor_counts_per_rad: float | None       # RLG: pulses per radian, 4A/(λP)
    scale_factor_counts_per_deg: float | None
    resolution_arcsec: float | None                 # one pulse, ″
    phase_per_rate_s: float | None                  # FOG: rad of phase per rad/s, 2πLD/(λc)
    earth_rate_signal: float                        # RLG: Hz (pulses/s); FOG: rad of phase
    earth_rate_signal_unit: str
    latitude_deg: float | None = None               # where the axis points up (if given)
    earth_rate_up_signal: float | None = None       # the signal of Ω sin φ, same unit

    def to_dict(self) -> dict:
        """Plain dict (for ``--json``)."""
        return dict(self.__dict__)


def sagnac_rlg(area_m2: float, perimeter_m: float, wavelength_m: float = 632.8e-9,
               latitude_deg: float | None = None) -> Sagnac:
    """Ring-laser Sagnac scale factor and the full Earth rate's beat frequency.

    Δf = 4A/(λP)·Ω (docs/draft-readings.md#sagnac-effect; [Aronowitz1971]). One pulse is
    1/K rad. With ``latitude_deg``, also the beat of a horizontal ring (normal up), whose
    Sagnac frequency is 4A/(λP)·Ω_E·|sin φ| (the magnitude: the sign only says which beam
    is the faster).

    >>> s = sagnac_rlg(0.15**2 * 3**0.5 / 4, 0.45)          # 15 cm-side triangle, He-Ne
    >>> round(s.scale_factor_counts_per_deg, 2), round(s.resolution_arcsec, 4)
    (2388.59, 1.5072)
    >>> round(s.earth_rate_signal, 3)                       # Hz for the whole Ω_E
    9.98
    """
    k = rlg_scale_factor_counts_per_rad(area_m2, perimeter_m, wavelength_m)
    return Sagnac("rlg", wavelength_m, k, k * math.pi / 180.0, rad_to_arcsec(1.0 / k),
                  None, k * OMEGA_E_RAD_S, "Hz", latitude_deg, _up_signal(k, latitude_deg))


def _up_signal(per_rate: float, latitude_deg: float | None) -> float | None:
    """|signal| of the Earth rate's vertical component Ω sin φ (None without a latitude)."""
    if latitude_deg is None:
        return None
    return abs(per_rate * math.radians(earth_rate_on_axis_dps(latitude_deg, "up")))


def sagnac_fog(length_m: float, diameter_m: float, wavelength_m: float = 1550e-9,
               latitude_deg: float | None = None) -> Sagnac:
    """Fibre-optic Sagnac phase per rate 2πLD/(λc) and the full Earth rate's phase.

    Δφ = 2πLD/(λc)·Ω (docs/draft-readings.md#sagnac-effect; [Lefevre], 2.1).

    >>> s = sagnac_fog(1000.0, 0.1)                         # 1 km, 10 cm coil, 1550 nm
    >>> round(s.phase_per_rate_s, 4), f"{s.earth_rate_signal:.3e}"
    (1.3522, '9.860e-05')
    """
    f = fog_phase_per_rate_s(length_m, diameter_m, wavelength_m)
    return Sagnac("fog", wavelength_m, None, None, None, f, f * OMEGA_E_RAD_S, "rad",
                  latitude_deg, _up_signal(f, latitude_deg))
