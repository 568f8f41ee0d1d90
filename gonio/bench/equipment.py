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
  Annex A u₂) and a resolution;
* :class:`Fixture` — the gyro in its mounting fixture: a small misalignment of its body
  (rotations about body x and y), the same in every mounting.

:func:`draw_equipment` draws every one of these errors that a specification's budget carries
as type B from the distribution the equipment's certificate (or the laboratory's stated
bound) gives, from a seed: the coverage studies use it per trial, so the type-B
terms of the budgets are exercised instead of one fixed realisation.

The Earth rate is applied on every axis orientation by the session runner
(:mod:`gonio.bench.rate_session`) from the site latitude.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

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
    """Temperature chamber (JJF Table 2). The chamber holds a set point off by
    :meth:`deviation_at`: ``deviation_c`` at every set point, or — when
    ``point_deviation_c`` > 0 — a deviation of its own at each set point, uniform in
    ±``point_deviation_c`` and drawn from (``deviation_seed``, set point), so a set point
    visited twice has the same deviation."""

    deviation_c: float = 0.0             # constant offset of the chamber from the set point
    fluctuation_c: float = 0.0           # amplitude of the periodic fluctuation
    fluctuation_period_s: float = 600.0
    fluctuation_phase_deg: float = 0.0   # phase of the fluctuation at the session's t = 0
    uniformity_c: float = 0.0            # gyro position offset within the volume (±half)
    max_ramp_c_per_min: float = 5.0
    point_deviation_c: float = 0.0       # > 0: per-set-point deviation, uniform in ±this
    deviation_seed: int = 0
    position_offset_c: float | None = None   # the gyro's place in the volume; None: +half

    def position_offset(self) -> float:
        """The gyro's temperature offset from the chamber's (°C): ``position_offset_c``,
        or + ``uniformity_c``/2 (the far corner of the volume) when it is not set.

        >>> Chamber(uniformity_c=0.4).position_offset(), Chamber(0.0, position_offset_c=-0.1).position_offset()
        (0.2, -0.1)
        """
        return 0.5 * self.uniformity_c if self.position_offset_c is None \
            else float(self.position_offset_c)

    def deviation_at(self, set_point_c: float) -> float:
        """The chamber's deviation from the set point ``set_point_c`` (°C).

        >>> Chamber(deviation_c=0.5).deviation_at(60.0)
        0.5
        >>> c = Chamber(point_deviation_c=2.0, deviation_seed=7)
        >>> c.deviation_at(60.0) == c.deviation_at(60.0) != c.deviation_at(-40.0)
        True
        """
        if self.point_deviation_c <= 0:
            return self.deviation_c
        key = int(round((float(set_point_c) + 273.15) * 1000.0))
        rng = np.random.default_rng([int(self.deviation_seed), key])
        return float(rng.uniform(-self.point_deviation_c, self.point_deviation_c))


@dataclass(frozen=True)
class Acquisition:
    """Voltmeter / frequency counter: relative gain error and resolution (output units)."""

    gain_error_rel: float = 0.0
    resolution: float = 0.0


@dataclass(frozen=True)
class Supply:
    """The gyro's power supply: the actual terminal voltage differs from the set one by
    ``error_v`` (IEC 62047-20 5.1.4.1 c): "if it cannot be set exactly, record the actual
    value"); the readings record both, and eq (18) corrects a ratiometric gyro's output."""

    error_v: float = 0.0


@dataclass(frozen=True)
class Fixture:
    """The gyro in its fixture: its body is rotated by small angles about body x and y
    (degrees) from the fixture's axes, in every mounting; a rotation about y tilts the
    input axis (body z) towards body x, one about x towards −y."""

    misalignment_x_deg: float = 0.0
    misalignment_y_deg: float = 0.0

    def matrix(self) -> np.ndarray:
        """Body → fixture rotation R_x(a_x)·R_y(a_y) (identity when aligned)."""
        ax, ay = math.radians(self.misalignment_x_deg), math.radians(self.misalignment_y_deg)
        rx = np.array([[1, 0, 0], [0, math.cos(ax), -math.sin(ax)], [0, math.sin(ax), math.cos(ax)]])
        ry = np.array([[math.cos(ay), 0, math.sin(ay)], [0, 1, 0], [-math.sin(ay), 0, math.cos(ay)]])
        return rx @ ry


@dataclass(frozen=True)
class Equipment:
    """All the equipment of a rate-gyro bench, with what its certificates (and the
    laboratory) state: the table rate's and the voltmeter gain's relative standard
    uncertainties, the chamber's deviation bound (JJF Table 2: ±2 °C) and the bound of the
    input axis's alignment in its fixture (±0.05°)."""

    rate_table: RateTable = RateTable()
    position_table: PositionTable = PositionTable()
    vibration_table: VibrationTable = VibrationTable()
    chamber: Chamber = Chamber()
    acquisition: Acquisition = Acquisition()
    supply: Supply = Supply()
    fixture: Fixture = Fixture()
    rate_table_u_rel: float = 2.5e-4     # standard uncertainty of the table rate (its certificate)
    acquisition_u_rel: float = 3.0e-5    # standard uncertainty of the voltmeter gain
    chamber_deviation_bound_c: float = 2.0   # chamber deviation, rectangular half-width
    axis_alignment_bound_deg: float = 0.05   # input axis in its fixture, rectangular half-width

    def ideal(self) -> "Equipment":
        """Error-free equipment (same stated uncertainties)."""
        return replace(self, rate_table=RateTable(), position_table=PositionTable(),
                       vibration_table=VibrationTable(),
                       chamber=Chamber(max_ramp_c_per_min=self.chamber.max_ramp_c_per_min),
                       acquisition=Acquisition(), supply=Supply(), fixture=Fixture())

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
                          "fluctuation_phase_deg": _F,
                          "uniformity_c": _NN,
                          "max_ramp_c_per_min": Field("float", default=5.0,
                                                      check=lambda x: x > 0, expect="> 0")}),
    "acquisition": (Acquisition, {"gain_error_rel": _F, "resolution": _NN}),
    "supply": (Supply, {"error_v": _F}),
    "fixture": (Fixture, {"misalignment_x_deg": _F, "misalignment_y_deg": _F}),
}

#: Stream of the equipment draw (``default_rng([seed, EQUIPMENT_STREAM])``): the draw never
#: shares numbers with the session's own generator (``default_rng(seed)``).
EQUIPMENT_STREAM = 24


def draw_equipment(eq: Equipment, seed: int) -> Equipment:
    """``eq`` with every error that a budget carries as type B drawn, from ``seed``, from
    the distribution its certificate or stated bound gives:

    - the rate table's relative rate error: normal, σ = ``rate_table_u_rel``;
    - the voltmeter's relative gain error: normal, σ = ``acquisition_u_rel``;
    - the chamber's deviation, at each set point its own: uniform in
      ±``chamber_deviation_bound_c`` (Chamber.point_deviation_c, seeded per trial);
    - the gyro's misalignment in its fixture about body x and y: each uniform in
      ±``axis_alignment_bound_deg``;
    - the gyro's place in the chamber's volume: its temperature offset uniform in
      ±``uniformity_c``/2 (drawn after the above, so they are as before);
    - the phase of the chamber's periodic fluctuation: uniform in [0°, 360°) (drawn last;
      the IEC 62047-20 symmetry and ratiometric budgets carry the fluctuation with its
      phase unknown, so a phase held fixed would be a constant error in every trial);
    - the phase of the rate table's once-per-revolution ripple: uniform in [0°, 360°)
      (drawn after the chamber's phase, so every draw above is as before). JJF 1535 7.2.3
      carries the ripple at the amplitude the readings state (``rate_table_ripple_rel``,
      the bench's own ``ripple_rel``) with its phase unknown; the session starts the
      table at angle 0, so a phase held at the bench's value would put the same ripple
      error into every trial.

    What stays as the bench sets it: the ripple's amplitude (the readings state the
    bench's value, and the budget takes it as the amplitude, not as a bound) and the
    table's axis tilt, the position table's error (already drawn per position by the
    session), the vibration table, the chamber's fluctuation amplitude and period, the
    supply error — no budget carries them as a type-B term of the equipment drawn here.
    Same seed → same equipment.

    >>> e = draw_equipment(Equipment(), 3)
    >>> e == draw_equipment(Equipment(), 3) and e.rate_table.rate_error_rel != 0.0
    True
    >>> abs(e.fixture.misalignment_y_deg) <= 0.05 and e.chamber.point_deviation_c == 2.0
    True
    """
    rng = np.random.default_rng([int(seed), EQUIPMENT_STREAM])
    rate_err = float(rng.normal(0.0, eq.rate_table_u_rel))
    gain_err = float(rng.normal(0.0, eq.acquisition_u_rel))
    a = eq.axis_alignment_bound_deg
    mis_x, mis_y = (float(v) for v in rng.uniform(-a, a, 2)) if a > 0 else (0.0, 0.0)
    ch_seed = int(rng.integers(0, 2 ** 31))
    h = 0.5 * eq.chamber.uniformity_c
    pos = float(rng.uniform(-h, h)) if h > 0 else 0.0
    phase = float(rng.uniform(0.0, 360.0))
    ripple_phase = float(rng.uniform(0.0, 360.0))
    return replace(
        eq, rate_table=replace(eq.rate_table, rate_error_rel=rate_err,
                               ripple_phase_deg=ripple_phase),
        acquisition=replace(eq.acquisition, gain_error_rel=gain_err),
        chamber=replace(eq.chamber, point_deviation_c=eq.chamber_deviation_bound_c,
                        deviation_seed=ch_seed, position_offset_c=pos,
                        fluctuation_phase_deg=phase),
        fixture=Fixture(mis_x, mis_y))


def equipment_from_dict(d: dict, file=None) -> Equipment:
    """Build :class:`Equipment` from a bench file's ``[equipment]`` table (every key checked)."""
    if not isinstance(d, dict):
        raise GonioError("expected a table", file=file, key="equipment")
    top = {k: v for k, v in d.items() if k not in _SCHEMAS}
    topv = validate_table(top, {"rate_table_u_rel": Field("float", default=2.5e-4, check=non_negative,
                                                          expect="≥ 0"),
                                "acquisition_u_rel": Field("float", default=3.0e-5,
                                                           check=non_negative, expect="≥ 0"),
                                "chamber_deviation_bound_c": Field("float", default=2.0,
                                                                   check=non_negative, expect="≥ 0"),
                                "axis_alignment_bound_deg": Field("float", default=0.05,
                                                                  check=non_negative, expect="≥ 0")},
                          "equipment", file)
    parts = {}
    for key, (cls, schema) in _SCHEMAS.items():
        parts[key] = cls(**validate_table(d.get(key, {}), schema, f"equipment.{key}", file))
    return Equipment(**parts, **topv)
