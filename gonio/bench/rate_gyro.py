"""The virtual rate gyro: a MEMS (or optical) gyro seen as a rate sensor.

Model: the extended MEMS gyro model of [Vagner2015] (docs/references.md#vagner2015) with the
terms of JJF 1535-2015 and IEC 62047-20:

    F = F_null(V) + K(T, V)·(1 + ε_K,run)·[ f(ω_dyn) + b(T, V) + b_run + b_warm(t)
        + g·a + k_x ω_x + k_y ω_y + n(t) ],     then quantised to ``output_lsb``

* ω_dyn: the input rate about the input axis through the second-order dynamics
  H(s) = ω_n²/(s² + 2ζω_n s + ω_n²) (steady state; bandwidth and phase);
* f(ω): threshold d (|ω| < d gives 0 — the sensing element does not respond — else ω;
  the 50 % rule then finds d), then asymmetry (K·(1 ± α/2) for ω ≷ 0), cubic nonlinearity c₃ω³ and
  saturation at ±range;
* K(T, V) = K₀(1 + k₁ΔT + k₂ΔT²)·(V/V₀)^r·(1 + ε_r (V − V₀)/V₀) with r = 1 for a
  ratiometric gyro (IEC 62047-20 5.1.3.5), 0 otherwise; ΔT = T − T_ref;
* b(T, V) = b₀ + b₁ΔT + b₂ΔT² + b_V (V − V₀) (°/s); b_warm(t) = A_w e^(−t/τ_w) after
  power-on (warm-up, JJF 7.2.9);
* g = (g_x, g_y, g_z) (°/s)/g on the specific force in body axes (JJF 7.2.12), k_x, k_y
  cross-axis sensitivities (IEC 5.2);
* ε_K,run, b_run: power-cycle to power-cycle scatter (JJF 7.2.4, 7.2.11), one draw per
  power-on;
* n(t): angle random walk N(T) = N₀(1 + n₁ΔT) (white rate noise), bias instability
  (a sum of first-order Gauss–Markov processes with log-spaced correlation times whose
  sum has a 1/f spectrum S(f) = B²/(π f) one-sided over the covered band, so its Allan
  deviation has the floor 0.664 B), rate random walk K_rrw, rate ramp R, and the output
  quantisation (ADC / counter LSB).

The bench file (``protocols/benches/mems-adxrs610.toml``) sets every parameter;
:func:`load_rate_bench` also accepts an optical bench (``rlg``, ``fog``) and reads its
instrument as a rate sensor with pulse-rate output (counts/s per °/s).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
from scipy import signal

from gonio.errors import GonioError
from gonio.resources import resolve
from gonio.units import S_PER_H
from gonio.formats.toml import Field, non_negative, positive, read_toml, validate_table


@dataclass(frozen=True)
class RateGyroConfig:
    """Every parameter of the rate-gyro model (units in the names; see module docstring)."""

    name: str = "rate gyro"
    model: str = ""
    manufacturer: str = ""
    serial: str = ""
    kind: str = "mems"                       # mems, rlg, fog
    output_unit: str = "mV"
    scale_factor: float = 6.0                # K₀, output per °/s at T_ref, V₀
    null_output: float = 0.0                 # F_null at V₀ (e.g. 2500 mV for an analog MEMS)
    ratiometric: bool = False
    supply_nominal_v: float = 5.0
    ratiometric_error_rel: float = 0.0       # ε_r
    range_dps: float = 300.0
    reference_temperature_c: float = 20.0
    sf_tc1_per_c: float = 0.0
    sf_tc2_per_c2: float = 0.0
    sf_asymmetry: float = 0.0                # α: K+ = K(1 + α/2), K− = K(1 − α/2)
    sf_cubic_per_dps2: float = 0.0           # c₃
    dead_band_dps: float = 0.0
    bias_dps: float = 0.0
    bias_tc1_dps_per_c: float = 0.0
    bias_tc2_dps_per_c2: float = 0.0
    bias_supply_dps_per_v: float = 0.0
    g_sensitivity_dps_per_g: tuple[float, float, float] = (0.0, 0.0, 0.0)
    cross_axis_x: float = 0.0
    cross_axis_y: float = 0.0
    natural_frequency_hz: float = 1.0e9      # second-order dynamics
    damping: float = 0.7
    datasheet_bandwidth_hz: float = 0.0      # the estimate a laboratory starts from
    warmup_bias_dps: float = 0.0
    warmup_tau_s: float = 300.0
    thermal_tau_s: float = 600.0             # gyro temperature lag behind its surroundings
    sf_scatter_rel: float = 0.0              # power-cycle scatter of K (1 σ, relative)
    bias_scatter_dps: float = 0.0            # power-cycle scatter of b (1 σ)
    arw_deg_sqrt_h: float = 0.0
    arw_tc1_per_c: float = 0.0
    bias_instability_dph: float = 0.0
    bias_instability_tau_min_s: float = 0.5
    bias_instability_tau_max_s: float = 2.0e4
    rrw_dph_sqrt_h: float = 0.0
    rate_ramp_dph_per_h: float = 0.0
    output_lsb: float = 0.0                  # quantisation step of the output (0: none)

    # ------------------------------------------------------------------ deterministic parts
    def delta_t(self, temp_c):
        return np.asarray(temp_c, float) - self.reference_temperature_c

    def scale_factor_at(self, temp_c, supply_v) -> np.ndarray:
        """K(T, V), output per °/s (before the power-cycle scatter)."""
        dt = self.delta_t(temp_c)
        v = np.asarray(supply_v, float)
        k = self.scale_factor * (1 + self.sf_tc1_per_c * dt + self.sf_tc2_per_c2 * dt ** 2)
        if self.ratiometric:
            k = k * (v / self.supply_nominal_v)
        return k * (1 + self.ratiometric_error_rel * (v - self.supply_nominal_v)
                    / self.supply_nominal_v)

    def null_at(self, supply_v) -> np.ndarray:
        """F_null(V): proportional to the supply for a ratiometric gyro."""
        v = np.asarray(supply_v, float)
        return self.null_output * (v / self.supply_nominal_v if self.ratiometric else 1.0 + 0 * v)

    def bias_at(self, temp_c, supply_v) -> np.ndarray:
        """b(T, V), °/s (before the power-cycle scatter and the warm-up transient)."""
        dt = self.delta_t(temp_c)
        return (self.bias_dps + self.bias_tc1_dps_per_c * dt + self.bias_tc2_dps_per_c2 * dt ** 2
                + self.bias_supply_dps_per_v * (np.asarray(supply_v, float) - self.supply_nominal_v))

    def response(self, rate_dps) -> np.ndarray:
        """f(ω): threshold (no response below ``dead_band_dps``), asymmetry, cubic
        nonlinearity, saturation (°/s equivalent)."""
        w = np.asarray(rate_dps, float)
        d = self.dead_band_dps
        wd = np.where(np.abs(w) < d, 0.0, w) if d > 0 else w
        out = wd * (1 + 0.5 * self.sf_asymmetry * np.sign(wd)) + self.sf_cubic_per_dps2 * wd ** 3
        return np.clip(out, -self.range_dps * 1.5, self.range_dps * 1.5) \
            if self.range_dps > 0 else out

    def dynamics(self, freq_hz) -> np.ndarray:
        """H(j2πf) of the second-order dynamics (complex)."""
        u = np.asarray(freq_hz, float) / self.natural_frequency_hz
        return 1.0 / (1.0 - u ** 2 + 2j * self.damping * u)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["g_sensitivity_dps_per_g"] = list(self.g_sensitivity_dps_per_g)
        return d


# --------------------------------------------------------------------------- noise
class NoiseState:
    """Stateful generator of the gyro's random rate error, °/s, at sample interval ``dt``.

    Each call of :meth:`samples` continues the processes (bias instability, rate random walk,
    rate ramp) from where the last call (or :meth:`skip`) left them; a new power-on is a new
    :class:`NoiseState`. ``samples`` returns the *mean* rate error over each interval for
    white noise (variance N²/dt) and the sampled value of the slow processes.
    """

    def __init__(self, gyro: RateGyroConfig, rng: np.random.Generator, enabled: bool = True):
        self.g, self.rng, self.enabled = gyro, rng, enabled
        b = gyro.bias_instability_dph / S_PER_H          # °/s
        self.taus = np.array([])
        self.sig = np.array([])
        if enabled and b > 0:
            ratio = 3.0
            n = max(1, int(math.ceil(math.log(gyro.bias_instability_tau_max_s
                                              / gyro.bias_instability_tau_min_s) / math.log(ratio))) + 1)
            self.taus = gyro.bias_instability_tau_min_s * ratio ** np.arange(n)
            # GM(σ², T) has the one-sided PSD 4σ²T/(1 + (2πfT)²); summed over T_i log-spaced by
            # r it is ≈ σ²/(f ln r) in the covered band; = B²/(π f) (IEEE 952) for
            # σ² = B² ln r / π, whose Allan floor is √(2 ln 2/π)·B
            self.sig = np.full(n, math.sqrt(math.log(ratio) / math.pi) * b)
        self.gm = self.sig * rng.standard_normal(self.taus.size) if self.taus.size else np.zeros(0)
        self.rw = 0.0
        self.t = 0.0

    def skip(self, duration_s: float) -> None:
        """Advance the slow processes over an unrecorded interval."""
        if not self.enabled or duration_s <= 0:
            self.t += max(duration_s, 0.0)
            return
        if self.taus.size:
            a = np.exp(-duration_s / self.taus)
            self.gm = a * self.gm + np.sqrt(1 - a ** 2) * self.sig * self.rng.standard_normal(self.taus.size)
        k = self.g.rrw_dph_sqrt_h / S_PER_H / math.sqrt(S_PER_H)   # °/s/√s
        if k > 0:
            self.rw += k * math.sqrt(duration_s) * float(self.rng.standard_normal())
        self.t += duration_s

    def samples(self, n: int, dt: float, temp_c) -> np.ndarray:
        """n samples of the rate error at interval dt (temperature per sample or scalar)."""
        t_rel = self.t + dt * np.arange(n)
        self.t += n * dt
        if not self.enabled:
            return np.zeros(n)
        g = self.g
        out = np.zeros(n)
        if g.arw_deg_sqrt_h > 0:
            arw = g.arw_deg_sqrt_h / math.sqrt(S_PER_H) * (1 + g.arw_tc1_per_c * g.delta_t(temp_c))
            out += arw / math.sqrt(dt) * self.rng.standard_normal(n)
        if self.taus.size:
            for i, (tau, s) in enumerate(zip(self.taus, self.sig)):
                a = math.exp(-dt / tau)
                w = math.sqrt(1 - a * a) * s * self.rng.standard_normal(n)
                y, _ = signal.lfilter([1.0], [1.0, -a], w, zi=[a * self.gm[i]])
                out += y
                self.gm[i] = y[-1]
        k = g.rrw_dph_sqrt_h / S_PER_H / math.sqrt(S_PER_H)
        if k > 0:
            steps = k * math.sqrt(dt) * self.rng.standard_normal(n)
            walk = self.rw + np.cumsum(steps)
            out += walk
            self.rw = float(walk[-1])
        if g.rate_ramp_dph_per_h:
            out += g.rate_ramp_dph_per_h / S_PER_H / S_PER_H * t_rel
        return out


def noise_psd_one_sided(g, freq_hz, dt: float, temp_c: float) -> np.ndarray:
    """One-sided density ((°/s)²/Hz) of the bench's sampled rate noise at interval ``dt``: the
    white term 2N² (interval means), each Gauss–Markov term of the bias-instability sum as a
    sampled AR(1) process, the rate random walk as a sampled random walk, and the output
    quantisation (LSB²/12 per sample) — the model's own closed forms, used for truths."""
    f = np.asarray(freq_hz, float)
    z = np.exp(-2j * math.pi * f * dt)
    n_s = g.arw_deg_sqrt_h / math.sqrt(S_PER_H) * (1 + g.arw_tc1_per_c * (temp_c - g.reference_temperature_c))
    psd = np.full(f.size, 2.0 * n_s ** 2)
    ns = NoiseState(g, np.random.default_rng(0), enabled=True)
    for tau, s in zip(ns.taus, ns.sig):
        a = math.exp(-dt / tau)
        psd = psd + 2 * dt * s ** 2 * (1 - a * a) / np.abs(1 - a * z) ** 2
    q = g.rrw_dph_sqrt_h / S_PER_H / math.sqrt(S_PER_H)
    with np.errstate(divide="ignore"):
        if q > 0:
            psd = psd + 2 * dt * q ** 2 * dt / np.abs(1 - z) ** 2
    if g.output_lsb:
        psd = psd + 2 * dt * (g.output_lsb / g.scale_factor) ** 2 / 12
    return psd


def difference_noise_sigma(gyro: RateGyroConfig, dt: float, n: int, n_ref: int,
                           separation_s: float, *, both_sides: bool, temp_c: float) -> float:
    """Standard deviation (°/s) of the noise of a step response measured as the mean of ``n``
    samples minus a reference mean of ``n_ref`` samples whose centre is ``separation_s`` away
    (``both_sides``: the average of two such references, before and after). From the model's
    one-sided density (:func:`noise_psd_one_sided`) through the exact discrete filter
    (Dirichlet kernels of the means): H = D_n − D_r cos ωΔ (both sides) or
    |H|² = D_n² + D_r² − 2 D_n D_r cos ωΔ. The truth of the noise-limited 50 % rule items.
    """
    f = np.linspace(0.0, 0.5 / dt, 400001)[1:]

    def dirichlet(m):
        return np.sin(math.pi * f * m * dt) / (m * np.sin(math.pi * f * dt))

    dn, dr = dirichlet(n), dirichlet(n_ref)
    c = np.cos(2 * math.pi * f * separation_s)
    h2 = (dn - dr * c) ** 2 if both_sides else dn ** 2 + dr ** 2 - 2 * dn * dr * c
    return math.sqrt(float(np.trapezoid(noise_psd_one_sided(gyro, f, dt, temp_c) * h2, f)))


# --------------------------------------------------------------------------- loading
_GYRO_SCHEMA = {
    "name": Field("str", default="rate gyro"),
    "model": Field("str", default=""),
    "manufacturer": Field("str", default=""),
    "serial": Field("str", default=""),
    "kind": Field("str", default="mems", choices=("mems", "rlg", "fog")),
    "output_unit": Field("str", default="mV"),
    "scale_factor": Field("float", check=lambda x: x != 0, expect="a non-zero number"),
    "null_output": Field("float", default=0.0),
    "ratiometric": Field("bool", default=False),
    "supply_nominal_v": Field("float", default=5.0, check=positive, expect="> 0"),
    "ratiometric_error_rel": Field("float", default=0.0),
    "range_dps": Field("float", default=300.0, check=positive, expect="> 0"),
    "reference_temperature_c": Field("float", default=20.0),
    "sf_tc1_per_c": Field("float", default=0.0),
    "sf_tc2_per_c2": Field("float", default=0.0),
    "sf_asymmetry": Field("float", default=0.0, check=lambda x: abs(x) < 1, expect="|α| < 1"),
    "sf_cubic_per_dps2": Field("float", default=0.0),
    "dead_band_dps": Field("float", default=0.0, check=non_negative, expect="≥ 0"),
    "bias_dps": Field("float", default=0.0),
    "bias_tc1_dps_per_c": Field("float", default=0.0),
    "bias_tc2_dps_per_c2": Field("float", default=0.0),
    "bias_supply_dps_per_v": Field("float", default=0.0),
    "g_sensitivity_dps_per_g": Field("float_list", default=[0.0, 0.0, 0.0]),
    "cross_axis_x": Field("float", default=0.0),
    "cross_axis_y": Field("float", default=0.0),
    "natural_frequency_hz": Field("float", default=1.0e9, check=positive, expect="> 0"),
    "damping": Field("float", default=0.7, check=positive, expect="> 0"),
    "datasheet_bandwidth_hz": Field("float", default=0.0, check=non_negative, expect="≥ 0"),
    "warmup_bias_dps": Field("float", default=0.0),
    "warmup_tau_s": Field("float", default=300.0, check=positive, expect="> 0"),
    "thermal_tau_s": Field("float", default=600.0, check=positive, expect="> 0"),
    "sf_scatter_rel": Field("float", default=0.0, check=non_negative, expect="≥ 0"),
    "bias_scatter_dps": Field("float", default=0.0, check=non_negative, expect="≥ 0"),
    "arw_deg_sqrt_h": Field("float", default=0.0, check=non_negative, expect="≥ 0"),
    "arw_tc1_per_c": Field("float", default=0.0),
    "bias_instability_dph": Field("float", default=0.0, check=non_negative, expect="≥ 0"),
    "bias_instability_tau_min_s": Field("float", default=0.5, check=positive, expect="> 0"),
    "bias_instability_tau_max_s": Field("float", default=2.0e4, check=positive, expect="> 0"),
    "rrw_dph_sqrt_h": Field("float", default=0.0, check=non_negative, expect="≥ 0"),
    "rate_ramp_dph_per_h": Field("float", default=0.0),
    "output_lsb": Field("float", default=0.0, check=non_negative, expect="≥ 0"),
}


@dataclass(frozen=True)
class RateBench:
    """A rate-gyro bench: the gyro, the equipment (:mod:`gonio.bench.equipment`) and the site."""

    name: str
    gyro: RateGyroConfig
    equipment: "object"
    latitude_deg: float
    north_azimuth_deg: float = 0.0     # azimuth of the gyro's body +x when the mount says "north"
    path: Path | None = None
    #: The coverage studies' bench: each trial draws the equipment's type-B errors from its
    #: seed (gonio.bench.equipment.draw_equipment) before it runs.
    draw_equipment: bool = False
    #: With ``draw_equipment``: ``"typeb"`` draws the type-B errors per trial, ``"worst"``
    #: puts them at their bounds (gonio.bench.equipment.worst_equipment), ``"cold"`` as
    #: ``"worst"`` with the gyro cold at every set point (gonio.bench.equipment.cold_equipment).
    equipment_case: str = "typeb"

    def for_trial(self, seed: int) -> "RateBench":
        """The bench one trial of seed ``seed`` runs on: with ``draw_equipment``, the
        equipment's errors drawn from the seed (:func:`gonio.bench.equipment.draw_equipment`),
        or, ``equipment_case == "worst"``, put at their bounds
        (:func:`gonio.bench.equipment.worst_equipment`: the chamber's deviation split at the
        gyro's reference temperature, the fixture's signs from its cross-axis
        sensitivities), ``"cold"`` the same with the gyro cold at every set point
        (:func:`gonio.bench.equipment.cold_equipment`); else this bench."""
        if not self.draw_equipment:
            return self
        from gonio.bench.equipment import cold_equipment, draw_equipment, worst_equipment
        if self.equipment_case == "worst":
            eq = worst_equipment(self.equipment, seed,
                                 temperature_split_c=self.gyro.reference_temperature_c,
                                 cross_axis=(self.gyro.cross_axis_x, self.gyro.cross_axis_y))
        elif self.equipment_case == "cold":
            eq = cold_equipment(self.equipment, seed,
                                cross_axis=(self.gyro.cross_axis_x, self.gyro.cross_axis_y))
        elif self.equipment_case == "typeb":
            eq = draw_equipment(self.equipment, seed)
        else:
            raise GonioError(f"unknown equipment case {self.equipment_case!r} (typeb, worst, cold)")
        return replace(self, equipment=eq, draw_equipment=False)

    def without_noise(self) -> "RateBench":
        """The same bench with every random and equipment error off (truth-recovery checks)."""
        g = replace(self.gyro, arw_deg_sqrt_h=0.0, bias_instability_dph=0.0, rrw_dph_sqrt_h=0.0,
                    rate_ramp_dph_per_h=0.0, output_lsb=0.0, sf_scatter_rel=0.0,
                    bias_scatter_dps=0.0)
        return replace(self, gyro=g, equipment=self.equipment.ideal())


def gyro_from_optical(inst: dict) -> RateGyroConfig:
    """An optical bench's ``[instrument]`` read as a rate sensor: output in counts/s,
    K = the true counts per degree, bias and noise terms converted, wide bandwidth."""
    k0 = inst["nominal_scale_factor_counts_per_deg"] * (1 + inst.get("scale_factor_error_ppm", 0.0) * 1e-6)
    kind = inst.get("type", "rlg")
    fn = 2000.0 if kind == "rlg" else 1500.0
    return RateGyroConfig(
        name=f"{inst.get('name', kind)} (as rate sensor)", model=kind.upper(),
        manufacturer=inst.get("manufacturer", ""), serial=inst.get("serial", ""), kind=kind,
        output_unit="counts/s", scale_factor=k0, range_dps=400.0,
        sf_cubic_per_dps2=inst.get("sf_rate_quadratic_ppm", 0.0) * 1e-6 / 300.0 ** 2,
        bias_dps=inst.get("bias_dph", 0.0) / S_PER_H,
        warmup_bias_dps=inst.get("warmup_drift_dph", 0.0) / S_PER_H,
        warmup_tau_s=inst.get("warmup_tau_s", 1200.0),
        arw_deg_sqrt_h=inst.get("arw_dpsh", 0.0),
        bias_instability_dph=inst.get("bias_instability_dph", 0.0),
        rrw_dph_sqrt_h=inst.get("rrw_dphsh", 0.0),
        natural_frequency_hz=fn, damping=0.7, datasheet_bandwidth_hz=round(fn * 1.45, -1),
        sf_tc1_per_c=2e-7, bias_tc1_dps_per_c=0.0005 / S_PER_H,
        sf_scatter_rel=2e-7, bias_scatter_dps=0.0005 / S_PER_H,
        output_lsb=1.0 if inst.get("quantisation", True) else 0.0)


def load_rate_bench(path: str | Path = "mems-adxrs610") -> RateBench:
    """Load a rate-gyro bench (``[bench]``, ``[site]``, ``[gyro]``, ``[equipment]``) or an
    optical bench (``[instrument]``, read by :func:`gyro_from_optical`)."""
    from gonio.bench.equipment import Equipment, equipment_from_dict

    p = resolve(path, kind="bench")
    raw = read_toml(p)
    site = raw.get("site", {})
    lat = site.get("latitude_deg")
    if not isinstance(lat, (int, float)) or isinstance(lat, bool) or abs(lat) > 90:
        raise GonioError("expected a latitude in [-90, 90]", file=p, key="site.latitude_deg")
    name = str(raw.get("bench", {}).get("name", p.stem))
    if "gyro" in raw:
        g = validate_table(raw["gyro"], _GYRO_SCHEMA, "gyro", p)
        if len(g["g_sensitivity_dps_per_g"]) != 3:
            raise GonioError("expected 3 values (x, y, z)", file=p, key="gyro.g_sensitivity_dps_per_g")
        g["g_sensitivity_dps_per_g"] = tuple(g["g_sensitivity_dps_per_g"])
        gyro = RateGyroConfig(**g)
    elif "instrument" in raw:
        gyro = gyro_from_optical(raw["instrument"])
    else:
        raise GonioError("a rate bench needs a [gyro] section (or an optical [instrument])", file=p)
    eq = equipment_from_dict(raw.get("equipment", {}), p) if "equipment" in raw else Equipment()
    return RateBench(name=name, gyro=gyro, equipment=eq, latitude_deg=float(lat),
                     north_azimuth_deg=float(site.get("north_azimuth_deg", 0.0)), path=p)
