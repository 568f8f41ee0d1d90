"""The rate-gyro laboratory's equipment on the virtual bench (JJF 1535 Table 2).

* :class:`RateTable` — a single-axis rate table (vertical axis) with a relative rate
  error and a once-per-revolution rate ripple ("rate accuracy and smoothness 0.05 %
  for rates ≥ 10 °/s"), optionally a tilt of its axis;
* :class:`PositionTable` — a two-axis position table (positioning error, arc-seconds)
  that sets any body axis up or down (±1 g on each axis, JJF 7.2.12);
* :class:`VibrationTable` — an angular vibration table: sinusoidal rate at a set
  frequency and amplitude, waveform distortion (second harmonic, ≤ 2 %), a reference
  rate sensor with its own noise (JJF 7.2.15, IEC 62047-20 5.5);
* :class:`Chamber` — a temperature chamber: set points reached at a ramp rate, soak
  times, a temperature deviation, fluctuation and uniformity (JJF Table 2: ±2 °C,
  ±1 °C, 2 °C);
* :class:`Acquisition` — the voltmeter / counter: a relative gain error (6½ digits,
  Annex A u₂) and a resolution.

The Earth rate is applied on every axis orientation by the session runner
(:mod:`gonio.bench.rate_session`) from the site latitude.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

from gonio.errors import GonioError
from gonio.formats.toml import Field, non_negative, validate_table


@dataclass(frozen=True)
class RateTable:
    """Rate table: actual rate = set·(1 + rate_error_rel) + ripple·|set|·sin(θ + φ)."""

    rate_error_rel: float = 0.0
    ripple_rel: float = 0.0
    ripple_phase_deg: float = 0.0
    tilt_deg: float = 0.0


@dataclass(frozen=True)
class PositionTable:
    """Two-axis position table: each position is off by a random error (1 σ, arc-seconds)."""

    position_error_arcsec: float = 0.0


@dataclass(frozen=True)
class VibrationTable:
    """Angular vibration table with a reference sensor."""

    distortion_rel: float = 0.0          # second-harmonic amplitude / fundamental
    amplitude_error_rel: float = 0.0     # actual amplitude / set − 1 (cancels in the ratio)
    reference_noise_dps: float = 0.0     # white noise of the reference rate sensor (1 σ)


@dataclass(frozen=True)
class Chamber:
    """Temperature chamber (JJF Table 2)."""

    deviation_c: float = 0.0             # constant offset of the chamber from the set point
    fluctuation_c: float = 0.0           # amplitude of the periodic fluctuation
    fluctuation_period_s: float = 600.0
    uniformity_c: float = 0.0            # gyro position offset within the volume (±half)
    max_ramp_c_per_min: float = 5.0


@dataclass(frozen=True)
class Acquisition:
    """Voltmeter / frequency counter: relative gain error and resolution (output units)."""

    gain_error_rel: float = 0.0
    resolution: float = 0.0


@dataclass(frozen=True)
class Equipment:
    """All the equipment of a rate-gyro bench."""

    rate_table: RateTable = RateTable()
    position_table: PositionTable = PositionTable()
    vibration_table: VibrationTable = VibrationTable()
    chamber: Chamber = Chamber()
    acquisition: Acquisition = Acquisition()
    rate_table_u_rel: float = 2.5e-4     # standard uncertainty of the table rate (its certificate)
    acquisition_u_rel: float = 3.0e-5    # standard uncertainty of the voltmeter gain

    def ideal(self) -> "Equipment":
        """Error-free equipment (same stated uncertainties)."""
        return replace(self, rate_table=RateTable(), position_table=PositionTable(),
                       vibration_table=VibrationTable(),
                       chamber=Chamber(max_ramp_c_per_min=self.chamber.max_ramp_c_per_min),
                       acquisition=Acquisition())

    def to_dict(self) -> dict:
        return asdict(self)


_F = Field("float", default=0.0)
_NN = Field("float", default=0.0, check=non_negative, expect="≥ 0")
_SCHEMAS = {
    "rate_table": (RateTable, {"rate_error_rel": _F, "ripple_rel": _NN, "ripple_phase_deg": _F,
                               "tilt_deg": _NN}),
    "position_table": (PositionTable, {"position_error_arcsec": _NN}),
    "vibration_table": (VibrationTable, {"distortion_rel": _NN, "amplitude_error_rel": _F,
                                         "reference_noise_dps": _NN}),
    "chamber": (Chamber, {"deviation_c": _F, "fluctuation_c": _NN,
                          "fluctuation_period_s": Field("float", default=600.0,
                                                        check=lambda x: x > 0, expect="> 0"),
                          "uniformity_c": _NN,
                          "max_ramp_c_per_min": Field("float", default=5.0,
                                                      check=lambda x: x > 0, expect="> 0")}),
    "acquisition": (Acquisition, {"gain_error_rel": _F, "resolution": _NN}),
}


def equipment_from_dict(d: dict, file=None) -> Equipment:
    """Build :class:`Equipment` from a bench file's ``[equipment]`` table (every key checked)."""
    if not isinstance(d, dict):
        raise GonioError("expected a table", file=file, key="equipment")
    top = {k: v for k, v in d.items() if k not in _SCHEMAS}
    topv = validate_table(top, {"rate_table_u_rel": Field("float", default=2.5e-4, check=non_negative,
                                                          expect="≥ 0"),
                                "acquisition_u_rel": Field("float", default=3.0e-5,
                                                           check=non_negative, expect="≥ 0")},
                          "equipment", file)
    parts = {}
    for key, (cls, schema) in _SCHEMAS.items():
        parts[key] = cls(**validate_table(d.get(key, {}), schema, f"equipment.{key}", file))
    return Equipment(**parts, **topv)
