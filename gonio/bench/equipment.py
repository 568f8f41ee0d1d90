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
    #: Set (the coverage studies' worst-condition case): the deviation is + ``point_deviation_c``
    #: at every set point above this temperature and − ``point_deviation_c`` at or below it
    deviation_split_c: float | None = None
    #: Set (the worst-condition case): the gyro's place in the volume follows the set point —
    #: + |position_offset()| at every set point above this temperature, − at or below it
    #: (JJF Table 2 bounds the uniformity at each set point; wall losses make the volume's
    #: gradient grow with T − ambient, so the far corner is warmer when hot, cooler when cold)
    position_split_c: float | None = None

    def position_offset(self) -> float:
        """The gyro's temperature offset from the chamber's (°C): ``position_offset_c``,
        or + ``uniformity_c``/2 (the far corner of the volume) when it is not set.

        >>> Chamber(uniformity_c=0.4).position_offset(), Chamber(0.0, position_offset_c=-0.1).position_offset()
        (0.2, -0.1)
        """
        return 0.5 * self.uniformity_c if self.position_offset_c is None \
            else float(self.position_offset_c)

    def position_at(self, set_point_c: float) -> float:
        """The gyro's temperature offset from the chamber's (°C) at ``set_point_c``: the one
        place :meth:`position_offset`, or — with ``position_split_c`` set — its magnitude
        with the sign of the set point's side of the split (the place's effect then moves
        a slope over the set points, as a constant offset does not).

        >>> Chamber(uniformity_c=2.0).position_at(-40.0)
        1.0
        >>> c = Chamber(uniformity_c=2.0, position_split_c=20.0)
        >>> c.position_at(85.0), c.position_at(20.0), c.position_at(-40.0)
        (1.0, -1.0, -1.0)
        """
        p = self.position_offset()
        if self.position_split_c is None:
            return p
        return abs(p) if float(set_point_c) > self.position_split_c else -abs(p)

    def deviation_at(self, set_point_c: float) -> float:
        """The chamber's deviation from the set point ``set_point_c`` (°C).

        >>> Chamber(deviation_c=0.5).deviation_at(60.0)
        0.5
        >>> c = Chamber(point_deviation_c=2.0, deviation_seed=7)
        >>> c.deviation_at(60.0) == c.deviation_at(60.0) != c.deviation_at(-40.0)
        True
        >>> w = Chamber(point_deviation_c=2.0, deviation_split_c=20.0)
        >>> w.deviation_at(70.0), w.deviation_at(20.0), w.deviation_at(-40.0)
        (2.0, -2.0, -2.0)
        """
        if self.point_deviation_c <= 0:
            return self.deviation_c
        if self.deviation_split_c is not None:
            return self.point_deviation_c if float(set_point_c) > self.deviation_split_c \
                else -self.point_deviation_c
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
    #: standard uncertainty of the table rate (its certificate); None: none stated — the
    #: laboratory knows only JJF 1535 Table 2's 0.05 % bound (the readings then state no
    #: ``rate_table_u_rel``, and the budgets read it as that bound, rectangular)
    rate_table_u_rel: float | None = 2.5e-4
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

    - the rate table's relative rate error: normal, σ = ``rate_table_u_rel``; where none
      is stated (None), uniform within JJF 1535 Table 2's ±0.05 % (the bound the budget
      then carries: the rate specifications' table line, docs/formats.md);
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
    rate_err = float(rng.normal(0.0, eq.rate_table_u_rel)) if eq.rate_table_u_rel is not None \
        else float(rng.uniform(-TABLE2_RATE_ACCURACY_REL, TABLE2_RATE_ACCURACY_REL))
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


#: JJF 1535-2015 Table 2's bounds of the equipment that the worst-condition case puts the
#: bench at where the bench file states a smaller value: the rate table's rate smoothness
#: (0.05 %, its once-per-revolution ripple), the chamber's fluctuation (±1 °C) and
#: uniformity (2 °C).
TABLE2_RATE_SMOOTHNESS_REL = 5.0e-4
#: JJF 1535-2015 Table 2's rate accuracy (the same row's 0.05 %): the bound of the table's
#: rate error where the bench states no certificate u (``rate_table_u_rel`` None).
TABLE2_RATE_ACCURACY_REL = 5.0e-4
TABLE2_CHAMBER_FLUCTUATION_C = 1.0
TABLE2_CHAMBER_UNIFORMITY_C = 2.0
#: The worst-condition rule (one rule for every study of the rate family, and the optical
#: draft's: its tilt at the bound with the worst azimuth, the others drawn): an effect the
#: procedure BOUNDS (a rectangular line: the chamber's deviation at each set point, the gyro's
#: place in the volume, its misalignment in the fixture; the amplitudes the readings state,
#: Table 2's fluctuation, uniformity and smoothness) sits at its bound with the sign that moves
#: the items most, all at once (the procedure allows them at once); an effect known by a
#: NORMAL certificate (the rate table's rate, the voltmeter's gain: u stated, k = 2) has no
#: bound — its certificate's U is a 95 % value of a state of knowledge, not a limit — and is
#: drawn from that certificate per trial, as in ``typeb``.
WORST_RULE = ("bounded effects (rectangular lines and the readings' stated amplitudes) at "
              "their bounds with the worst sign, all at once, the gyro's place in the volume "
              "following the set point; the rate table's rate at Table 2's 0.05 % where no "
              "certificate u is stated; normal-certificate effects (rate table's rate where "
              "its u is stated, voltmeter's gain) drawn from their certificates; phases drawn")


def worst_equipment(eq: Equipment, seed: int, *, temperature_split_c: float,
                    cross_axis: tuple[float, float] = (0.0, 0.0)) -> Equipment:
    """``eq`` with every BOUNDED error :func:`draw_equipment` draws put at the bound the
    procedure allows, at the sign that moves the items most, and the normal-certificate
    errors drawn (the coverage studies' ``worst`` case, the rule :data:`WORST_RULE`):

    - the rate table's relative rate error and the voltmeter's gain error: drawn from their
      certificates (normal, σ = ``rate_table_u_rel``, ``acquisition_u_rel``) exactly as
      :func:`draw_equipment` draws them from ``seed`` — a normal certificate's 2u is not a
      bound, and a k = 2 budget whose line is that certificate's u cannot cover a condition
      that fixes the line at 2u where it dominates (JJF K and B_0 covered 0.60–0.75 so);
      but where the bench states NO certificate u (``rate_table_u_rel`` None: the laboratory
      knows only Table 2's 0.05 %, a bound), the table's error sits AT that bound,
      + :data:`TABLE2_RATE_ACCURACY_REL` (raising the indicated K);
    - the chamber's deviation at ± ``chamber_deviation_bound_c`` at every set point:
      + above ``temperature_split_c`` and − at or below it
      (:attr:`Chamber.deviation_split_c`), which stretches every temperature span that
      crosses the split by twice the bound, so a temperature coefficient (a slope over the
      set points, or over a point and the reference point at the split) reads high in
      magnitude; a set point visited twice keeps its deviation (hysteresis unaffected);
    - the chamber's fluctuation amplitude and uniformity at Table 2's ±1 °C and 2 °C where
      the bench states less (:data:`TABLE2_CHAMBER_FLUCTUATION_C`,
      :data:`TABLE2_CHAMBER_UNIFORMITY_C`), the gyro's place in the volume at half the
      uniformity with the deviation's sign at each set point (+ above the split, − at or
      below: :attr:`Chamber.position_split_c`), so it stretches the spans as the deviation
      does — Table 2 bounds the uniformity at each set point, and a place that follows the
      set point moves a slope, which one constant offset cannot;
    - the table's once-per-revolution ripple at Table 2's 0.05 % where the bench states less
      (:data:`TABLE2_RATE_SMOOTHNESS_REL`);
    - the gyro's misalignment in its fixture at ± ``axis_alignment_bound_deg`` about body x
      and y, the sign that adds to the gyro's own cross-axis sensitivity on each axis
      (``cross_axis`` = (k_x, k_y); a rotation a_y about y adds sin a_y to the apparent k_x,
      one a_x about x adds −sin a_x to the apparent k_y; + where k is 0), so the measured
      cross-axis sensitivity's magnitude reads high.

    Not held at a worst value: the phases of the chamber's fluctuation and of the table's
    ripple, drawn from ``seed`` exactly as :func:`draw_equipment` draws them. A phase's worst
    value is a function of each item's point timing (it differs from item to item), and the
    case is one trial set for every item. The amplitudes the readings state are the bench's,
    so each budget sees the bound it is given. Same seed → same equipment.

    >>> w = worst_equipment(Equipment(), 3, temperature_split_c=20.0, cross_axis=(0.01, -0.008))
    >>> d = draw_equipment(Equipment(), 3)
    >>> (w.rate_table.rate_error_rel, w.acquisition.gain_error_rel) == (d.rate_table.rate_error_rel, d.acquisition.gain_error_rel)
    True
    >>> w.chamber.deviation_at(70.0), w.chamber.deviation_at(-40.0), w.fixture
    (2.0, -2.0, Fixture(misalignment_x_deg=0.05, misalignment_y_deg=0.05))
    >>> w.chamber.fluctuation_phase_deg == draw_equipment(Equipment(), 3).chamber.fluctuation_phase_deg
    True
    """
    drawn = draw_equipment(eq, seed)                  # the phases, as the typeb case has them
    a = eq.axis_alignment_bound_deg
    kx, ky = (float(v) for v in cross_axis)
    uni = max(eq.chamber.uniformity_c, TABLE2_CHAMBER_UNIFORMITY_C)
    return replace(
        eq, rate_table=replace(eq.rate_table,
                               rate_error_rel=drawn.rate_table.rate_error_rel
                               if eq.rate_table_u_rel is not None else TABLE2_RATE_ACCURACY_REL,
                               ripple_rel=max(eq.rate_table.ripple_rel,
                                              TABLE2_RATE_SMOOTHNESS_REL),
                               ripple_phase_deg=drawn.rate_table.ripple_phase_deg),
        acquisition=replace(eq.acquisition, gain_error_rel=drawn.acquisition.gain_error_rel),
        chamber=replace(eq.chamber, point_deviation_c=eq.chamber_deviation_bound_c,
                        deviation_split_c=float(temperature_split_c),
                        fluctuation_c=max(eq.chamber.fluctuation_c,
                                          TABLE2_CHAMBER_FLUCTUATION_C),
                        uniformity_c=uni, position_offset_c=0.5 * uni,
                        position_split_c=float(temperature_split_c),
                        fluctuation_phase_deg=drawn.chamber.fluctuation_phase_deg),
        fixture=Fixture(-a if ky > 0 else a, -a if kx < 0 else a))


def cold_equipment(eq: Equipment, seed: int, *,
                   cross_axis: tuple[float, float] = (0.0, 0.0)) -> Equipment:
    """:func:`worst_equipment` with the gyro COLD at every set point (the coverage studies'
    ``cold`` case): the chamber's deviation at − ``chamber_deviation_bound_c`` and the gyro's
    place at − half Table 2's uniformity at every set point, the static record's included,
    and the chamber's fluctuation at the bench's own amplitude (Table 2's ±1 °C would add
    output noise, the other way). The sign `worst` does not reach for the items read at one
    temperature whose reading falls with it: the noise items' white level (IEC 62047-20
    5.4.5), which a gyro cold during the static record reads low. Every other error as
    :func:`worst_equipment` puts it (the table at Table 2's bound where no certificate u is
    stated, the fixture, the ripple; the phases drawn). Same seed → same equipment.

    >>> c = cold_equipment(Equipment(), 3)
    >>> c.chamber.deviation_at(85.0), c.chamber.deviation_at(-40.0), c.chamber.position_at(25.0)
    (-2.0, -2.0, -1.0)
    >>> c.chamber.fluctuation_c == Equipment().chamber.fluctuation_c
    True
    """
    w = worst_equipment(eq, seed, temperature_split_c=0.0, cross_axis=cross_axis)
    half = 0.5 * w.chamber.uniformity_c
    return replace(w, chamber=replace(
        w.chamber, point_deviation_c=0.0, deviation_c=-float(eq.chamber_deviation_bound_c),
        deviation_split_c=None, position_offset_c=-half, position_split_c=None,
        fluctuation_c=eq.chamber.fluctuation_c))


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
