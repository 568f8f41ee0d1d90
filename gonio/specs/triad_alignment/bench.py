"""A virtual MEMS gyro triad on a rate table and in a temperature chamber.

The triad (:class:`TriadBench`, from ``protocols/benches/<name>.toml``)
--------------------------------------------------------------------------
Output of gyro i at sample time t (alignment article [Looney-alignment] eq. 14; [Vagner2015]
eq. 6.7, 6.14–6.20)::

    y_i = K_i(ϑ, U) [ (A + X) ω(t) ]_i + K_i(ϑ, U) ( b_i(ϑ, U) + n_i(t) )

* ω(t): table rate about the vertical plus the Earth rate, in the fixture's reference
  frame (:func:`gonio.physics.alignment.ref_to_enu`, :func:`gonio.physics.earth.earth_rate_enu`);
* A = N Rᵀ the sensing axes (non-orthogonality N, mounting rotation R; exact forms of
  :mod:`gonio.physics.alignment`), X the electrical cross-coupling (zero diagonal);
* K_i(ϑ, U) = K0_i (1 + Σ_j κ_ϑj,i ϑ^j + Σ_j κ_Uj,i U^j),
  b_i(ϑ, U) = b0_i + Σ_j β_ϑj,i ϑ^j + Σ_j β_Uj,i U^j (°/s), with ϑ = T_die − T_ref and
  U = V − V_ref (thesis eq. 6.15–6.18: polynomials without a constant term in the
  deviations from the reference conditions);
* n_i(t): white noise with angle random walk ARW_i(ϑ) = ARW0_i (1 + Σ_j α_j,i ϑ^j)
  (thesis eq. 6.19–6.20), bias instability as a sum of first-order Gauss–Markov
  processes spread two per decade of correlation time (their summed spectrum ≈ 1/f
  between 1/(2π τ_max) and 1/(2π τ_min), Allan floor 0.664 B; thesis §3.4 uses one
  Gauss–Markov process), and a rate random walk.
* Temperatures: the die temperature follows the chamber through a first-order lag of
  time constant τ_th (thesis Fig. 5.7: fixture and table dominate); the internal
  temperature sensor reads the die temperature plus an offset, a supply sensitivity
  (thesis eq. 6.12) and white noise.

The sessions
------------
:func:`run_alignment_session` — each reference axis up on the table in turn, ± rates
about it (whole revolutions), six static positions, a static record for the Allan
deviation; :func:`run_thermal_session` — a chamber programme of set points (ramps at a
set gradient, soaks), at each soak ± rates and a static dwell at every supply voltage
(voltages in the alternating order the thesis recommends, Fig. 5.8), and static blocks
recorded all along the ramps. Both return a :class:`TriadSession` (readings table,
metadata, truth); :func:`write_triad_session` writes ``readings.csv`` (format
``docs/formats-triad.md``) and ``truth.json`` atomically. Same seed → same bytes.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import signal
from scipy.spatial.transform import Rotation

from gonio.atomic import output_dir
from gonio.physics.earth import earth_rate_enu
from gonio.errors import GonioError
from gonio.specs.triad_alignment.readings import COLUMNS, RANGES, format_triad_readings
from gonio.physics.alignment import (mean_earth_rate_ref, ref_to_enu, sensing_axis_matrix,
                                     system_matrix)
from gonio.resources import resolve
from gonio.units import deg_sqrt_s_from_deg_sqrt_h, dph_to_dps
from gonio.formats.toml import Field, non_negative, positive, read_toml, validate_table

# ----------------------------------------------------------------------------- config
_BENCH_SCHEMA = {
    "bench": Field("table", schema={
        "name": Field("str"),
        "latitude_deg": Field("float", check=lambda v: -90 <= v <= 90, expect="in [-90, 90]"),
        "sample_rate_hz": Field("float", check=positive, expect="> 0"),
    }),
    "triad": Field("table", schema={
        "name": Field("str", default="MEMS gyro triad (virtual)"),
        "serial": Field("str", default="TRIAD-0001"),
        "output_unit": Field("str", default="lsb"),
        "scale_per_dps": Field("float_list", check=lambda v: v != 0, expect="non-zero"),
        "nonorthogonality_mrad": Field("float_list", default=[0.0] * 6),
        "mounting_mrad": Field("float_list", default=[0.0] * 3),
        "cross_coupling": Field("float_list", default=[0.0] * 6),
        "bias_dps": Field("float_list", default=[0.0] * 3),
        "arw_deg_sqrt_h": Field("float_list", check=non_negative, expect=">= 0"),
        "bias_instability_dph": Field("float_list", default=[0.0] * 3, check=non_negative,
                                      expect=">= 0"),
        "rate_random_walk_dph_sqrt_h": Field("float_list", default=[0.0] * 3,
                                             check=non_negative, expect=">= 0"),
        "bi_tau_min_s": Field("float", default=1.0, check=positive, expect="> 0"),
        "bi_tau_max_s": Field("float", default=1.0e4, check=positive, expect="> 0"),
    }),
    "table": Field("table", default={}, schema={
        "rate_error_rel": Field("float", default=0.0, check=lambda v: abs(v) < 0.5,
                                expect="a relative error in (-0.5, 0.5)"),
        "rate_table_u_rel": Field("float", default=2.5e-4, check=lambda v: 0 <= v <= 0.5,
                                  expect="in [0, 0.5]"),
        "orientation_bound_deg": Field("float", default=0.05, check=lambda v: 0 <= v <= 10,
                                       expect="in [0, 10] degrees"),
    }),
    "thermal": Field("table", default={}, schema={
        "reference_c": Field("float", default=25.0),
        "reference_v": Field("float", default=5.0, check=positive, expect="> 0"),
        "time_constant_s": Field("float", default=0.0, check=non_negative, expect=">= 0"),
        # per gyro: coefficients of ϑ^1, ϑ^2, ... (one list per axis, x then y then z)
        "bias_temp_dps": Field("table", default={}, schema={a: Field("float_list", default=[0.0])
                                                             for a in "xyz"}),
        "scale_temp_rel": Field("table", default={}, schema={a: Field("float_list", default=[0.0])
                                                              for a in "xyz"}),
        "bias_supply_dps": Field("table", default={}, schema={a: Field("float_list", default=[0.0])
                                                               for a in "xyz"}),
        "scale_supply_rel": Field("table", default={}, schema={a: Field("float_list", default=[0.0])
                                                                for a in "xyz"}),
        "arw_temp_rel": Field("table", default={}, schema={a: Field("float_list", default=[0.0])
                                                            for a in "xyz"}),
        "sensor_offset_c": Field("float", default=0.0),
        "sensor_supply_c_per_v": Field("float", default=0.0),
        "sensor_noise_c": Field("float", default=0.0, check=non_negative, expect=">= 0"),
    }),
}


@dataclass(frozen=True)
class ThermalModel:
    """The bench's true temperature / supply dependence (thesis eq. 6.15–6.20)."""

    reference_c: float = 25.0
    reference_v: float = 5.0
    time_constant_s: float = 0.0
    bias_temp_dps: tuple = ((0.0,), (0.0,), (0.0,))
    scale_temp_rel: tuple = ((0.0,), (0.0,), (0.0,))
    bias_supply_dps: tuple = ((0.0,), (0.0,), (0.0,))
    scale_supply_rel: tuple = ((0.0,), (0.0,), (0.0,))
    arw_temp_rel: tuple = ((0.0,), (0.0,), (0.0,))
    sensor_offset_c: float = 0.0
    sensor_supply_c_per_v: float = 0.0
    sensor_noise_c: float = 0.0

    @staticmethod
    def _poly(coef, d) -> np.ndarray:
        """Σ_j c_j d^j, j from 1 (no constant term)."""
        d = np.asarray(d, dtype=float)
        out = np.zeros_like(d)
        for j, c in enumerate(coef, start=1):
            out = out + c * d ** j
        return out

    def scale_factor(self, axis: int, temp_c, supply_v, k0: float) -> np.ndarray:
        """K_i(ϑ, U) = K0 (1 + Σ κ_ϑj ϑ^j + Σ κ_Uj U^j)."""
        return k0 * (1.0 + self._poly(self.scale_temp_rel[axis], np.asarray(temp_c) - self.reference_c)
                     + self._poly(self.scale_supply_rel[axis], np.asarray(supply_v) - self.reference_v))

    def bias_dps(self, axis: int, temp_c, supply_v, b0: float) -> np.ndarray:
        """b_i(ϑ, U) = b0 + Σ β_ϑj ϑ^j + Σ β_Uj U^j, °/s."""
        return b0 + self._poly(self.bias_temp_dps[axis], np.asarray(temp_c) - self.reference_c) \
            + self._poly(self.bias_supply_dps[axis], np.asarray(supply_v) - self.reference_v)

    def arw_factor(self, axis: int, temp_c) -> np.ndarray:
        """ARW(ϑ)/ARW0 = 1 + Σ α_j ϑ^j (thesis eq. 6.20, normalised)."""
        return 1.0 + self._poly(self.arw_temp_rel[axis], np.asarray(temp_c) - self.reference_c)

    def to_dict(self) -> dict:
        return {k: (np.asarray(v, dtype=object).tolist() if isinstance(v, tuple) else v)
                for k, v in self.__dict__.items()}


@dataclass(frozen=True)
class TriadBench:
    """A virtual gyro triad on a rate table (see the module docstring)."""

    name: str
    latitude_deg: float
    sample_rate_hz: float
    instrument: str
    serial: str
    output_unit: str
    scale_per_dps: tuple
    nonorthogonality_rad: np.ndarray     # 3×3 lean angles, zero diagonal
    mounting_rad: tuple
    cross_coupling: np.ndarray           # 3×3, zero diagonal
    bias_dps: tuple
    arw_deg_sqrt_h: tuple
    bias_instability_dph: tuple
    rate_random_walk_dph_sqrt_h: tuple
    bi_tau_min_s: float = 1.0
    bi_tau_max_s: float = 1.0e4
    thermal: ThermalModel = field(default_factory=ThermalModel)
    #: the rate table (``[table]`` of the bench file): its relative rate error, and what the
    #: readings state of it — its certificate's relative standard uncertainty and the bound of
    #: its spin axis in the reference frame at each orientation (the fixture's face on the
    #: table top, the top's squareness), the same defaults as the rate benches' equipment
    #: (:class:`gonio.bench.equipment.Equipment`: 2.5×10⁻⁴, ±0.05°)
    rate_error_rel: float = 0.0
    rate_table_u_rel: float = 2.5e-4
    orientation_bound_deg: float = 0.05
    #: 3×3, row a: the table's spin axis in the reference frame when axis a is up, minus
    #: e_a (rad; [a, a] = 0): the fixture's face on the table top and the top's squareness
    orientation_error_rad: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))

    @property
    def axes(self) -> np.ndarray:
        """A = N Rᵀ (exact forms)."""
        return sensing_axis_matrix(self.nonorthogonality_rad, self.mounting_rad, exact=True)

    @property
    def system_matrix(self) -> np.ndarray:
        """M at the reference temperature and supply (output per °/s)."""
        return system_matrix(self.scale_per_dps, self.axes, self.cross_coupling)

    def table_axis(self, up: str) -> np.ndarray:
        """Rotation (3×3) from the ideal orientation's reference frame to the one the table
        really has with ``up`` up: the small rotation taking e_a to e_a + δ_a
        (δ_a = ``orientation_error_rad[a]``, normalised; Rodrigues' formula), identity
        without an error. The ± sign of ``up`` shares the axis's δ (the static positions
        see only the Earth rate, where δ is far below the noise)."""
        a = "xyz".index(up[-1])
        e = np.eye(3)[a]
        d = np.asarray(self.orientation_error_rad, dtype=float)[a]
        if not np.any(d):
            return np.eye(3)
        return Rotation.from_rotvec(np.cross(e, d)).as_matrix()

    @property
    def bias_output(self) -> np.ndarray:
        """Bias vector at reference conditions in output units: K_i b_i."""
        return np.asarray(self.scale_per_dps) * np.asarray(self.bias_dps)


def _offdiag(six, what: str, file) -> np.ndarray:
    """3×3 zero-diagonal matrix from [xy, xz, yx, yz, zx, zy]."""
    if len(six) != 6:
        raise GonioError(f"expected 6 values (xy, xz, yx, yz, zx, zy), got {len(six)}",
                         file=file, key=what)
    m = np.zeros((3, 3))
    for (i, j), v in zip(((0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)), six):
        m[i, j] = v
    return m


def load_triad_bench(name_or_path) -> TriadBench:
    """Read and validate a triad bench file (``protocols/benches/mems-triad.toml``, with an
    optional ``[table]``: the rate table's ``rate_error_rel``, ``rate_table_u_rel``,
    ``orientation_bound_deg``). A :class:`TriadBench` is returned as it is (a coverage
    trial's drawn bench, :func:`gonio.specs.triad_alignment.simulate.for_trial`)."""
    if isinstance(name_or_path, TriadBench):
        return name_or_path
    path = resolve(name_or_path, kind="bench")
    raw = read_toml(path)
    cfg = validate_table(raw, _BENCH_SCHEMA, file=path)
    t = cfg["triad"]
    for key in ("scale_per_dps", "bias_dps", "arw_deg_sqrt_h", "bias_instability_dph",
                "rate_random_walk_dph_sqrt_h", "mounting_mrad"):
        if len(t[key]) != 3:
            raise GonioError(f"expected 3 values (x, y, z), got {len(t[key])}", file=path,
                             key=f"triad.{key}")
    if t["bi_tau_max_s"] <= t["bi_tau_min_s"]:
        raise GonioError("bi_tau_max_s must exceed bi_tau_min_s", file=path, key="triad.bi_tau_max_s")
    th = cfg["thermal"] or validate_table({}, _BENCH_SCHEMA["thermal"].schema, "thermal", path)

    def per_axis(k):
        tab = th[k] or {a: [0.0] for a in "xyz"}
        return tuple(tuple(tab[a]) for a in "xyz")

    thermal = ThermalModel(th["reference_c"], th["reference_v"], th["time_constant_s"],
                           per_axis("bias_temp_dps"), per_axis("scale_temp_rel"),
                           per_axis("bias_supply_dps"), per_axis("scale_supply_rel"),
                           per_axis("arw_temp_rel"), th["sensor_offset_c"],
                           th["sensor_supply_c_per_v"], th["sensor_noise_c"])
    b = cfg["bench"]
    return TriadBench(
        name=b["name"], latitude_deg=b["latitude_deg"], sample_rate_hz=b["sample_rate_hz"],
        instrument=t["name"], serial=t["serial"], output_unit=t["output_unit"],
        scale_per_dps=tuple(t["scale_per_dps"]),
        nonorthogonality_rad=_offdiag(t["nonorthogonality_mrad"], "triad.nonorthogonality_mrad",
                                      path) * 1e-3,
        mounting_rad=tuple(v * 1e-3 for v in t["mounting_mrad"]),
        cross_coupling=_offdiag(t["cross_coupling"], "triad.cross_coupling", path),
        bias_dps=tuple(t["bias_dps"]), arw_deg_sqrt_h=tuple(t["arw_deg_sqrt_h"]),
        bias_instability_dph=tuple(t["bias_instability_dph"]),
        rate_random_walk_dph_sqrt_h=tuple(t["rate_random_walk_dph_sqrt_h"]),
        bi_tau_min_s=t["bi_tau_min_s"], bi_tau_max_s=t["bi_tau_max_s"], thermal=thermal,
        **(cfg["table"] or {}))


# ------------------------------------------------------------------------------ noise
class TriadNoise:
    """Continuous noise of the three gyros, °/s, generated block after block.

    White noise of density ARW (°/√h → (°/s)·√s is ÷ √(s per h)), bias instability as
    Gauss–Markov processes with correlation times τ_k spaced √10 apart in
    [τ_min, τ_max], each of variance B² ln(√10)/π (one-sided PSD h/f with h = B²/π gives
    the Allan floor σ² = 2 ln 2 h = (2 ln 2/π) B², IEEE 952 Annex C), rate random walk
    K·√dt per step. States carry across blocks, so the process is continuous in time.
    """

    def __init__(self, bench: TriadBench, rng: np.random.Generator):
        self.rng = rng
        self.dt = 1.0 / bench.sample_rate_hz
        self.white = deg_sqrt_s_from_deg_sqrt_h(np.array(bench.arw_deg_sqrt_h)) * math.sqrt(bench.sample_rate_hz)
        b_dps = dph_to_dps(np.array(bench.bias_instability_dph))
        ratio = math.sqrt(10.0)
        n_gm = max(1, int(round(math.log(bench.bi_tau_max_s / bench.bi_tau_min_s) / math.log(ratio))) + 1)
        self.taus = bench.bi_tau_min_s * ratio ** np.arange(n_gm)
        self.gm_sd = b_dps * math.sqrt(math.log(ratio) / math.pi)       # per process
        self.a = np.exp(-self.dt / self.taus)
        self.gm_state = self.gm_sd[:, None] * rng.standard_normal((3, n_gm))  # stationary start
        self.rrw = dph_to_dps(deg_sqrt_s_from_deg_sqrt_h(np.array(bench.rate_random_walk_dph_sqrt_h)))  # (°/s)/√s
        self.rw_state = np.zeros(3)

    def block(self, n: int, white_factor=None) -> np.ndarray:
        """(3, n) noise samples, °/s; ``white_factor`` (3, n) scales the white part."""
        w = self.rng.standard_normal((3, n)) * self.white[:, None]
        if white_factor is not None:
            w = w * white_factor
        out = w
        if np.any(self.gm_sd > 0):
            e = self.rng.standard_normal((3, self.taus.size, n))
            gm = np.zeros((3, n))
            for k, a in enumerate(self.a):
                drive = math.sqrt(1.0 - a * a) * self.gm_sd[:, None] * e[:, k, :]
                y, _ = signal.lfilter([1.0], [1.0, -a], drive, axis=1,
                                      zi=(a * self.gm_state[:, k])[:, None])
                self.gm_state[:, k] = y[:, -1]
                gm += y
            out = out + gm
        if np.any(self.rrw > 0):
            steps = self.rng.standard_normal((3, n)) * (self.rrw * math.sqrt(self.dt))[:, None]
            rw = self.rw_state[:, None] + np.cumsum(steps, axis=1)
            self.rw_state = rw[:, -1].copy()
            out = out + rw
        return out


# --------------------------------------------------------------------------- protocol
_CHAMBER_LO, _CHAMBER_HI, _CHAMBER_TXT = RANGES["chamber_c"]


def _chamber_c(x) -> bool:
    """A chamber temperature the triad reader accepts (a set point outside it was simulated
    and then refused by the reader, or grew the ramps past the row limit)."""
    return _CHAMBER_LO <= x <= _CHAMBER_HI


#: The one uncertainty statement of the items the rate table enters (M, S, L, K(ϑ, U)):
#: the bound condition (:func:`gonio.specs.triad_alignment.calibration.bound_condition`).
#: The JCGM 100 U covered 40–65 % at the table's bounds (docs/alignment.md), so "gum" is
#: refused, naming the key, rather than certified.
_BOUND_ONLY_TXT = ("'bound' (the statement that holds at every table error within its bounds; "
                   "the JCGM 100 U, 'gum', under-covers at the bounds and is not certified)")


def _bound_only(x) -> bool:
    return x == "bound"


_PROTOCOL_SCHEMA = {
    "protocol": Field("table", schema={
        "name": Field("str"),
        "spec": Field("str", default=""),     # "": the loader's spec_key
    }),
    "alignment": Field("table", schema={
        "rates_dps": Field("float_list", check=positive, expect="> 0"),
        "revolutions": Field("int", default=1, check=positive, expect="> 0"),
        "settle_s": Field("float", default=2.0, check=non_negative, expect=">= 0"),
        "static_positions": Field("bool", default=True),
        "static_dwell_s": Field("float", default=60.0, check=positive, expect="> 0"),
        # the statement of the table-dominated items: "bound" (the table's errors at their
        # bounds, worst combination, plus k·u of the rest), the one that holds at every
        # table error the procedure allows; the JCGM 100 U ("gum") under-covers at the
        # bounds and is no longer certified (docs/alignment.md, one statement per item)
        "uncertainty_statement": Field("str", default="bound", check=_bound_only,
                                       expect=_BOUND_ONLY_TXT),
        "north0": Field("table", default={}, schema={
            "x": Field("str", default="+y"), "y": Field("str", default="+z"),
            "z": Field("str", default="+x")}),
    }),
    "static": Field("table", default={}, schema={
        "duration_s": Field("float", default=300.0, check=non_negative, expect=">= 0"),
    }),
    "thermal": Field("table", default={}, schema={
        "enabled": Field("bool", default=False),
        "up": Field("str_list", default=["+z"]),
        "setpoints_c": Field("float_list", default=[25.0], check=_chamber_c, expect=_CHAMBER_TXT),
        "start_c": Field("float", default=25.0, check=_chamber_c, expect=_CHAMBER_TXT),
        "supply_v": Field("float_list", default=[5.0], check=positive, expect="> 0"),
        "ramp_c_per_min": Field("float", default=1.0, check=positive, expect="> 0"),
        "soak_s": Field("float", default=1800.0, check=non_negative, expect=">= 0"),
        "rate_dps": Field("float", default=100.0, check=positive, expect="> 0"),
        "dwell_s": Field("float", default=36.0, check=positive, expect="> 0"),
        "static_dwell_s": Field("float", default=60.0, check=positive, expect="> 0"),
        "ramp_block_s": Field("float", default=60.0, check=positive, expect="> 0"),
        "sample_rate_hz": Field("float", default=0.0, check=non_negative,
                                expect=">= 0 (0: the bench's)"),
    }),
}


@dataclass(frozen=True)
class TriadProtocol:
    """The triad session (a triad protocol file, ``protocols/<name>.toml``)."""

    name: str
    spec: str
    rates_dps: tuple
    revolutions: int
    settle_s: float
    static_positions: bool
    static_dwell_s: float
    north0: dict
    static_duration_s: float
    thermal: dict
    path: str = ""
    uncertainty_statement: str = "bound"


def load_triad_protocol(name_or_path, spec_key: str | None = None) -> TriadProtocol:
    """Read and validate a triad protocol file. Its ``[protocol] spec`` names the
    specification the readings are for; a file without one takes ``spec_key`` (the
    specification package that loads it passes its key), and with neither it is refused."""
    path = resolve(name_or_path, kind="protocol")
    cfg = validate_table(read_toml(path), _PROTOCOL_SCHEMA, file=path)
    if not (cfg["protocol"]["spec"] or spec_key):
        raise GonioError("the protocol names no specification", file=path, key="protocol.spec")
    al = cfg["alignment"]
    north0 = al["north0"] or {"x": "+y", "y": "+z", "z": "+x"}
    from gonio.physics.alignment import SIGNED_AXES
    for ax, code in north0.items():
        if code not in SIGNED_AXES or code[1] == ax:
            raise GonioError(f"expected a signed axis other than {ax}, got {code!r}", file=path,
                             key=f"alignment.north0.{ax}")
    th = cfg["thermal"] or validate_table({}, _PROTOCOL_SCHEMA["thermal"].schema, "thermal", path)
    for i, code in enumerate(th["up"]):
        if code not in SIGNED_AXES:
            raise GonioError(f"expected one of {', '.join(SIGNED_AXES)}, got {code!r}", file=path,
                             key=f"thermal.up[{i}]")
    st = cfg["static"] or {"duration_s": 600.0}
    return TriadProtocol(cfg["protocol"]["name"], cfg["protocol"]["spec"] or spec_key,
                         tuple(al["rates_dps"]),
                         al["revolutions"], al["settle_s"], al["static_positions"],
                         al["static_dwell_s"], dict(north0), st["duration_s"], dict(th), str(path),
                         al["uncertainty_statement"])


# ---------------------------------------------------------------------------- session
@dataclass
class TriadSession:
    """A simulated session: readings (columns of the format), metadata, truth."""

    readings: pd.DataFrame
    metadata: dict
    truth: dict


#: Largest piece of unrecorded time simulated at once (samples): bounds :meth:`_Runner.idle`'s
#: memory; the default programmes' soaks (18 000 samples) are one piece.
IDLE_PIECE = 1_000_000


class _Runner:
    """Advances time sample by sample-block: table motion, temperatures, outputs."""

    def __init__(self, bench: TriadBench, seed: int):
        self.bench = bench
        self.rng = np.random.default_rng(np.random.SeedSequence([int(seed), 18]))
        self.noise = TriadNoise(bench, self.rng)
        self.fs = bench.sample_rate_hz
        self.t = 0.0
        th = bench.thermal
        self.chamber_c = th.reference_c
        self.die_c = th.reference_c
        self.earth = np.degrees(earth_rate_enu(bench.latitude_deg))   # °/s in ENU
        self.mix = bench.axes + bench.cross_coupling
        self.rows: list[dict] = []
        self.step = 0
        self.samples = 0

    def _size(self, duration_s: float, key: str, *, recorded: bool) -> int:
        """Samples of a block, checked against the stated limits before any allocation
        (:mod:`gonio.limits`): a recorded block at most ``GONIO_MAX_READING_ROWS`` samples
        (it is held whole), the session at most ``GONIO_MAX_SAMPLES`` samples and
        ``GONIO_MAX_SESSION_S`` seconds; the message names the protocol key."""
        from gonio.limits import check, limit

        n = max(1, int(round(duration_s * self.fs)))
        where = f"triad bench {self.bench.name} at {self.fs:g} Hz, protocol key {key}"
        if recorded and n > limit("GONIO_MAX_READING_ROWS"):
            raise GonioError(f"{where}: one recorded block of {n:.4g} samples exceeds the limit "
                             f"of {limit('GONIO_MAX_READING_ROWS'):.4g} (set "
                             "GONIO_MAX_READING_ROWS to raise it)", key=key)
        self.samples += n
        check("GONIO_MAX_SAMPLES", self.samples, f"{where}: the session needs", unit="samples")
        check("GONIO_MAX_SESSION_S", self.t + n / self.fs, f"{where}: the session lasts",
              unit="s")
        return n

    def _temps(self, n: int, chamber_end: float) -> tuple[np.ndarray, np.ndarray]:
        """Chamber (linear from current to ``chamber_end``) and die temperature samples."""
        ch = self.chamber_c + (chamber_end - self.chamber_c) * (np.arange(1, n + 1) / n)
        tau = self.bench.thermal.time_constant_s
        if tau <= 0:
            die = ch.copy()
        else:
            a = math.exp(-1.0 / (self.fs * tau))
            die, _ = signal.lfilter([1.0 - a], [1.0, -a], ch, zi=[a * self.die_c])
        self.chamber_c, self.die_c = float(ch[-1]), float(die[-1])
        return ch, die

    def run(self, duration_s: float, *, up="+z", north0="+x", table_deg=0.0, rate_dps=0.0,
            supply_v=None, chamber_end=None, key: str = "protocol") -> dict:
        """Simulate one block; return its sample arrays (outputs (3, n), temps...)."""
        b = self.bench
        th = b.thermal
        n = self._size(duration_s, key, recorded=True)
        v = th.reference_v if supply_v is None else supply_v
        ch, die = self._temps(n, self.chamber_c if chamber_end is None else chamber_end)
        tk = np.arange(n) / self.fs
        rate_dps = rate_dps * (1.0 + b.rate_error_rel)        # the table's actual rate
        theta = np.radians(table_deg + rate_dps * tk)
        c0 = ref_to_enu(up, north0, 0.0)
        w = self.earth
        h, az = math.hypot(w[0], w[1]), math.atan2(w[0], w[1])
        earth_ref = c0.T @ np.vstack([h * np.sin(theta + az), h * np.cos(theta + az),
                                      np.full(n, w[2])])
        from gonio.physics.alignment import signed_axis
        omega = earth_ref + rate_dps * signed_axis(up)[:, None]
        if np.any(b.orientation_error_rad):
            omega = b.table_axis(up) @ omega
        sensed = self.mix @ omega
        wf = np.vstack([th.arw_factor(i, die) for i in range(3)])
        nz = self.noise.block(n, white_factor=wf)
        out = np.empty((3, n))
        for i in range(3):
            k = th.scale_factor(i, die, v, b.scale_per_dps[i])
            out[i] = k * (sensed[i] + th.bias_dps(i, die, v, b.bias_dps[i]) + nz[i])
        sensor = die + th.sensor_offset_c + th.sensor_supply_c_per_v * (v - th.reference_v)
        if th.sensor_noise_c > 0:
            sensor = sensor + th.sensor_noise_c * self.rng.standard_normal(n)
        blk = {"t0": self.t, "n": n, "out": out, "chamber": ch, "sensor": sensor, "v": v,
               "die": die}
        self.t += n / self.fs
        return blk

    def idle(self, duration_s: float, supply_v=None, chamber_end=None, key: str = "protocol",
             **kw) -> None:
        """Let time pass unrecorded: temperatures and the noise processes advance (in
        pieces of at most ``IDLE_PIECE`` samples, so memory stays bounded)."""
        if duration_s <= 0:
            return
        n = self._size(duration_s, key, recorded=False)
        end = self.chamber_c if chamber_end is None else chamber_end
        start, done = self.chamber_c, 0
        while done < n:
            m = min(IDLE_PIECE, n - done)
            done += m
            self._temps(m, end if done == n else start + (end - start) * done / n)
            if np.any(self.noise.gm_sd > 0) or np.any(self.noise.rrw > 0):
                self.noise.block(m)
            else:
                self.rng.standard_normal((3, m))  # the same draws a recorded block would use
        self.t += n / self.fs

    def record(self, test: str, blk: dict, *, up, north0, table_deg, rate_dps, phase="",
               thermal=False) -> None:
        out = blk["out"]
        row = {"test": test, "step": self.step, "phase": phase, "up": up, "north0": north0,
               "table_deg": float(table_deg), "rate_dps": float(rate_dps),
               "time_s": round(blk["t0"], 9), "duration_s": blk["n"] / self.fs,
               "n_samples": blk["n"],
               "chamber_c": float(np.mean(blk["chamber"])) if thermal else math.nan,
               "sensor_c": float(np.mean(blk["sensor"])) if thermal else math.nan,
               "supply_v": float(blk["v"]) if thermal else math.nan}
        for i, a in enumerate("xyz"):
            row[f"out_{a}"] = float(np.mean(out[i]))
            row[f"sd_{a}"] = float(np.std(out[i], ddof=1)) if blk["n"] > 1 else math.nan
        self.rows.append(row)
        self.step += 1


def _frame(rows) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=list(COLUMNS))


def _metadata(bench: TriadBench, protocol: TriadProtocol, seed: int, kind: str) -> dict:
    return {"format": "gonio-triad-readings/1", "spec": protocol.spec, "kind": kind,
            "instrument": bench.instrument,
            "serial": bench.serial, "output_unit": bench.output_unit,
            "latitude_deg": repr(float(bench.latitude_deg)),
            "sample_rate_hz": repr(float(bench.sample_rate_hz)),
            "nominal_scale_per_dps": " ".join(repr(float(k)) for k in bench.scale_per_dps),
            "reference_c": repr(float(bench.thermal.reference_c)),
            "reference_v": repr(float(bench.thermal.reference_v)),
            "rate_table_u_rel": repr(float(bench.rate_table_u_rel)),
            "orientation_bound_deg": repr(float(bench.orientation_bound_deg)),
            "bench": bench.name, "protocol": protocol.name, "seed": str(int(seed))}


def _shifted(coef, offset: float) -> list[float]:
    """c_k of Σ_j a_j (x − offset)^j = Σ_k c_k x^k (binomial expansion), ``coef`` = a_0 … a_n."""
    n = len(coef) - 1
    return [float(sum(coef[j] * math.comb(j, k) * (-offset) ** (j - k) for j in range(k, n + 1)))
            for k in range(n + 1)]


def true_thermal_coefficients(bench: TriadBench, channel: str, *, temperature: str = "sensor") -> dict[str, dict[str, float]]:
    """The bench's true K(ϑ, U), b(ϑ, U), ARW(ϑ) of gyro ``channel`` as the thermal model
    writes them (the triad specification's thermal model, thesis eq. 6.17–6.20), in
    closed form from the physical parameters — no estimator involved:

    * ϑ is the temperature the model is fed minus the reference: the gyro's sensor reads the
      die temperature + ``sensor_offset_c`` (+ supply term), so in sensor coordinates each
      polynomial in the die's ϑ is re-expanded about −offset (binomial); ``chamber`` keeps
      the die's coordinates (the chamber equals the die once soaked);
    * the rotation about the gyro's own reference axis (thermal ``up`` = ±channel) is sensed
      through m = (axes + cross coupling)[i, i], so K_meas = K·m, b_meas = b/m,
      ARW_meas = ARW/m (the other components of the Earth rate average out over whole
      revolutions, the vertical one is removed);
    * U terms as the bench states them (scale: K₀·m·κ_Uj; bias: β_Uj/m).

    Returns {"K": {...}, "b": {...}, "ARW": {...}} with keys c0, theta1 …, u1 … (every
    order the bench has; a term the bench lacks is 0)."""
    i = "xyz".index(channel)
    th = bench.thermal
    m = float((bench.axes + bench.cross_coupling)[i, i])
    if th.sensor_supply_c_per_v != 0.0 and temperature == "sensor":
        raise GonioError("true_thermal_coefficients: a supply-dependent sensor offset mixes "
                         "ϑ and U; not written out")
    off = th.sensor_offset_c if temperature == "sensor" else 0.0
    k0 = bench.scale_per_dps[i] * m
    arw0 = bench.arw_deg_sqrt_h[i] / m

    def poly(c0, temp, supply):
        t = _shifted([c0] + list(temp), off)
        d = {"c0": t[0], **{f"theta{j}": v for j, v in enumerate(t[1:], 1)}}
        d.update({f"u{j}": float(v) for j, v in enumerate(supply, 1)})
        return d

    return {"K": poly(k0, [k0 * c for c in th.scale_temp_rel[i]],
                      [k0 * c for c in th.scale_supply_rel[i]]),
            "b": poly(bench.bias_dps[i] / m, [c / m for c in th.bias_temp_dps[i]],
                      [c / m for c in th.bias_supply_dps[i]]),
            "ARW": poly(arw0, [arw0 * c for c in th.arw_temp_rel[i]], [])}


def _truth(bench: TriadBench) -> dict:
    m = bench.system_matrix
    return {"system_matrix": m.tolist(), "bias_output": bench.bias_output.tolist(),
            "bias_dps": list(bench.bias_dps), "scale_per_dps": list(bench.scale_per_dps),
            "sensing_axes": bench.axes.tolist(),
            "nonorthogonality_rad": bench.nonorthogonality_rad.tolist(),
            "mounting_rad": list(bench.mounting_rad),
            "cross_coupling": bench.cross_coupling.tolist(),
            "arw_deg_sqrt_h": list(bench.arw_deg_sqrt_h),
            "bias_instability_dph": list(bench.bias_instability_dph),
            "rate_random_walk_dph_sqrt_h": list(bench.rate_random_walk_dph_sqrt_h),
            "thermal": bench.thermal.to_dict(), "latitude_deg": bench.latitude_deg}


def run_alignment_session(protocol: TriadProtocol, bench: TriadBench, seed: int = 0) -> TriadSession:
    """Multi-position / multi-rate alignment session at reference temperature and supply.

    For each reference axis a (x, y, z): the axis up on the table, for each rate r of the
    protocol a +r and a −r dwell (alternating, each a whole number of revolutions, the
    table angle carried on), then — with ``static_positions`` — the six static positions
    (each axis up and down), then a static record (sample by sample) for the Allan
    deviation. The Earth rate is present in every orientation.
    """
    if seed < 0:
        raise GonioError(f"seed must be ≥ 0, got {seed}")
    r = _Runner(bench, seed)
    table = 0.0
    for ax in "xyz":
        up, north0 = f"+{ax}", protocol.north0[ax]
        for rate in protocol.rates_dps:
            for sgn in (1.0, -1.0):
                r.idle(protocol.settle_s, up=up, north0=north0, key="alignment.settle_s")
                dur = protocol.revolutions * 360.0 / rate
                blk = r.run(dur, up=up, north0=north0, table_deg=table, rate_dps=sgn * rate,
                            key="alignment.revolutions")
                r.record("alignment", blk, up=up, north0=north0, table_deg=table,
                         rate_dps=sgn * rate)
    if protocol.static_positions:
        for ax in "xyz":
            for s in "+-":
                up, north0 = f"{s}{ax}", protocol.north0[ax]
                r.idle(protocol.settle_s, up=up, north0=north0, key="alignment.settle_s")
                blk = r.run(protocol.static_dwell_s, up=up, north0=north0,
                            key="alignment.static_dwell_s")
                r.record("alignment", blk, up=up, north0=north0, table_deg=0.0, rate_dps=0.0)
    if protocol.static_duration_s > 0:
        up, north0 = "+z", protocol.north0["z"]
        blk = r.run(protocol.static_duration_s, up=up, north0=north0, key="static.duration_s")
        rows = {"test": "static", "phase": "", "up": up, "north0": north0, "table_deg": 0.0,
                "rate_dps": 0.0, "duration_s": 1.0 / r.fs, "n_samples": 1,
                "chamber_c": math.nan, "sensor_c": math.nan, "supply_v": math.nan}
        n = blk["n"]
        df = pd.DataFrame({**{k: [v] * n for k, v in rows.items()},
                           "step": np.arange(r.step, r.step + n),
                           "time_s": np.round(blk["t0"] + np.arange(n) / r.fs, 9),
                           "out_x": blk["out"][0], "out_y": blk["out"][1], "out_z": blk["out"][2],
                           "sd_x": math.nan, "sd_y": math.nan, "sd_z": math.nan})
        data = pd.concat([_frame(r.rows), df[list(COLUMNS)]], ignore_index=True)
    else:
        data = _frame(r.rows)
    return TriadSession(data, _metadata(bench, protocol, seed, "alignment"), _truth(bench))


def check_ramp_rows(th: dict) -> float:
    """The rows the thermal programme's ramps will record (every ``up``, every set point,
    ``ramp_block_s`` each), checked against ``GONIO_MAX_READING_ROWS`` before any block is
    simulated: a block of 0.01 s would otherwise grow the session without end. The error
    names the key."""
    from gonio.limits import check

    rows, at = 0.0, th["start_c"]
    for sp in th["setpoints_c"]:
        rows += math.ceil(abs(sp - at) / th["ramp_c_per_min"] * 60.0 / th["ramp_block_s"])
        at = sp
    rows *= len(th["up"])
    check("GONIO_MAX_READING_ROWS", rows, "thermal.ramp_block_s: the ramps would record",
          unit="rows")
    return rows


def run_thermal_session(protocol: TriadProtocol, bench: TriadBench, seed: int = 0) -> TriadSession:
    """Temperature-chamber and supply programme (thesis §5.2.3–5.2.4, §6.2).

    For each ``up`` axis of the protocol's [thermal] table: from ``start_c`` the chamber
    ramps at ``ramp_c_per_min`` to each set point in turn (static blocks of
    ``ramp_block_s`` recorded along the ramp, ``phase = ramp``), soaks ``soak_s``, then at
    every supply voltage (alternating order around the middle one) records +rate, −rate
    and a static dwell (``phase = soak``).
    """
    if seed < 0:
        raise GonioError(f"seed must be ≥ 0, got {seed}")
    th = protocol.thermal
    if th["sample_rate_hz"] > 0:
        import dataclasses
        bench = dataclasses.replace(bench, sample_rate_hz=th["sample_rate_hz"])
    r = _Runner(bench, seed)
    r.chamber_c = r.die_c = th["start_c"]
    volts = _alternating(th["supply_v"])
    rate = th["rate_dps"]
    check_ramp_rows(th)                       # sized before the first block is simulated
    for up in th["up"]:
        north0 = {"x": "+y", "y": "+z", "z": "+x"}[up[1]]
        for sp in th["setpoints_c"]:
            ramp_s = abs(sp - r.chamber_c) / th["ramp_c_per_min"] * 60.0
            nblk = int(math.ceil(ramp_s / th["ramp_block_s"])) if ramp_s > 0 else 0
            start = r.chamber_c
            for k in range(nblk):
                end = start + (sp - start) * (k + 1) / nblk
                blk = r.run(ramp_s / nblk, up=up, north0=north0, chamber_end=end,
                            key="thermal.ramp_block_s")
                r.record("thermal", blk, up=up, north0=north0, table_deg=0.0, rate_dps=0.0,
                         phase="ramp", thermal=True)
            r.idle(th["soak_s"], up=up, north0=north0, key="thermal.soak_s")
            for v in volts:
                for sgn in (1.0, -1.0):
                    dur = max(1, round(th["dwell_s"] * rate / 360.0)) * 360.0 / rate
                    blk = r.run(dur, up=up, north0=north0, rate_dps=sgn * rate, supply_v=v,
                                key="thermal.dwell_s")
                    r.record("thermal", blk, up=up, north0=north0, table_deg=0.0,
                             rate_dps=sgn * rate, phase="soak", thermal=True)
                blk = r.run(th["static_dwell_s"], up=up, north0=north0, supply_v=v,
                            key="thermal.static_dwell_s")
                r.record("thermal", blk, up=up, north0=north0, table_deg=0.0, rate_dps=0.0,
                         phase="soak", thermal=True)
    md = _metadata(bench, protocol, seed, "thermal")
    md["programme"] = ("set points " + " ".join(repr(float(v)) for v in th["setpoints_c"])
                       + f" °C from {th['start_c']!r} °C at {th['ramp_c_per_min']!r} °C/min, "
                       f"soak {th['soak_s']!r} s")
    return TriadSession(_frame(r.rows), md, _truth(bench))


def _alternating(volts) -> list[float]:
    """Supply voltages in alternating order around the middle (thesis Fig. 5.8):
    sorted values, middle first, then alternately above and below.

    >>> _alternating([4.75, 5.0, 5.25, 4.5, 5.5])
    [5.0, 5.25, 4.75, 5.5, 4.5]
    """
    v = sorted(float(x) for x in volts)
    mid = (len(v) - 1) // 2
    out = [v[mid]]
    for k in range(1, len(v)):
        for idx in (mid + k, mid - k):
            if 0 <= idx < len(v) and v[idx] not in out:
                out.append(v[idx])
    return out


def write_triad_session(session: TriadSession, out) -> dict:
    """Write ``readings.csv`` and ``truth.json`` into ``out`` atomically; return the paths."""
    text = format_triad_readings(session.readings, session.metadata)
    truth = json.dumps(session.truth, indent=2, sort_keys=True) + "\n"
    with output_dir(out) as stage:
        (stage / "readings.csv").write_text(text, encoding="utf-8")
        (stage / "truth.json").write_text(truth, encoding="utf-8")
    out = Path(out)
    return {"readings": out / "readings.csv", "truth": out / "truth.json"}
