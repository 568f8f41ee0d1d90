"""The simulated goniometer: what an RLG or FOG senses on a turning, tilted table.

Sensed rate (draft clause 4 and Annex A; ``docs/draft-readings.md#a-tilted-axis-on-a-rotating-table``):

    ω_s(t) = θ̇(t) cos ψ + Ω_E · n(θ(t))

with n the sensing axis tilted by ψ from the (wobbling) table axis, coning as
the table turns (:mod:`gonio.physics.kinematics`). The instrument's angle, in degrees,
is the integral of ω_s·(1 + ε(|ω_s|)) plus its bias and noise:

* scale factor K = K_nom (1 + e_K) counts/°; rate-dependent nonlinearity
  ε(ω) = q (ω/300 °/s)² + L exp(−|ω|/s_L) (RLG lock-in residual);
* angle-position-dependent error g(φ) − g(0), g(φ) = Σ a_h sin(h φ + p_h), of
  the angle φ turned since zeroing (draft 4.2: "K differs between angle positions");
* bias, warm-up transient b_w exp(−t/τ_w), Gauss–Markov bias instability,
  angle random walk (white rate), rate random walk;
* RLG: the counter is the exact integral (trapezoid on the grid for the
  Earth-rate and nonlinearity terms, closed form for θ cos ψ); FOG: rate
  samples integrated by the rectangle rule at the sample rate (draft 4.4: a
  source of the rate dependence that 7.6 measures). A FOG simulated at a rate
  below its own integration rate (``integration_rate_hz``) outputs its
  accumulated angle as the RLG's exact integral: the simulation's grid is the
  record's sampling, not the instrument's integrator; the rectangle residual at
  the instrument's own rate, at most a·h²/4 (0.054″ at 60 °/s² and 1 kHz), is
  then left out (:func:`integration_mode`);
* integer pulse counting (floor), optionally wrapping at ``counter_bits``.

Everything is vectorised over samples; :class:`Integrator` carries the state
from one chunk of samples to the next so long sessions run in bounded memory.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gonio.units import S_PER_H, arcsec_to_deg, deg_sqrt_s_from_deg_sqrt_h, dph_to_dps
from gonio.specs.ogam_draft.bench.config import Bench, Harmonic, InstrumentConfig
from gonio.physics.earth import axis_enu, earth_rate_table_frame_dps
from gonio.physics.kinematics import sensing_axis_basis


def harmonic_sum_arcsec(x_deg, harmonics: tuple[Harmonic, ...]) -> np.ndarray:
    """Σ a_h sin(h·x + p_h), arcsec, vectorised over ``x_deg``.

    >>> float(harmonic_sum_arcsec(np.array([90.0]), (Harmonic(1, 0.5, 0.0),))[0])
    0.5
    """
    x = np.radians(np.asarray(x_deg, dtype=float))
    out = np.zeros_like(x)
    for h in harmonics:
        out += h.amplitude_arcsec * np.sin(h.order * x + math.radians(h.phase_deg))
    return out


def rate_nonlinearity(rate_dps, inst: InstrumentConfig) -> np.ndarray:
    """Relative scale-factor change ε(|ω|) (dimensionless).

    >>> i = InstrumentConfig(sf_rate_quadratic_ppm=1.0)
    >>> float(rate_nonlinearity(np.array([300.0]), i)[0])
    1e-06
    """
    w = np.abs(np.asarray(rate_dps, dtype=float))
    eps = 1e-6 * inst.sf_rate_quadratic_ppm * (w / 300.0) ** 2
    if inst.sf_lowrate_ppm:
        eps = eps + 1e-6 * inst.sf_lowrate_ppm * np.exp(-w / inst.sf_lowrate_scale_dps)
    return eps


def actual_axis_enu(orientation: str, bench: Bench) -> np.ndarray:
    """The table axis as set up: the named direction plus the table's setup error."""
    a = axis_enu(orientation)
    t = bench.table
    if t.axis_setup_error_deg:
        e1, e2 = sensing_axis_basis(a)
        d, az = math.radians(t.axis_setup_error_deg), math.radians(t.axis_setup_azimuth_deg)
        a = math.cos(d) * a + math.sin(d) * (math.cos(az) * e1 + math.sin(az) * e2)
    return a / np.linalg.norm(a)


@dataclass(frozen=True)
class Geometry:
    """Earth-rate projections for one table orientation, °/s (see :func:`geometry`)."""

    omega_axis_dps: float     # Ω·a
    omega_e1_dps: float       # Ω·e₁
    omega_e2_dps: float       # Ω·e₂
    cos_psi: float
    sin_psi: float
    alpha_rad: float          # tilt azimuth in the table frame
    wobble_rad: float
    wobble_phase_rad: float

    def earth_dps(self, theta_deg: np.ndarray) -> np.ndarray:
        """Ω_E · n(θ): the Earth rate on the coning sensing axis, °/s.

        Ω·n = cos ψ [Ω·a + w Ω_⊥ cos(θ + β_w − β)] + sin ψ Ω_⊥ cos(θ + α − β),
        with Ω_⊥ = |(Ω·e₁, Ω·e₂)| and β its direction in the table frame.
        """
        th = np.radians(theta_deg)
        perp = math.hypot(self.omega_e1_dps, self.omega_e2_dps)
        beta = math.atan2(self.omega_e2_dps, self.omega_e1_dps)
        out = self.sin_psi * perp * np.cos(th + (self.alpha_rad - beta))
        out += self.cos_psi * self.omega_axis_dps
        if self.wobble_rad:
            out += (self.cos_psi * self.wobble_rad * perp) * np.cos(th + (self.wobble_phase_rad - beta))
        return out


def geometry(bench: Bench, orientation: str) -> Geometry:
    """Earth rate in the frame of the table set up in ``orientation``."""
    a = actual_axis_enu(orientation, bench)
    par, w1, w2 = earth_rate_table_frame_dps(bench.latitude_deg, a) if bench.earth_rate \
        else (0.0, 0.0, 0.0)
    inst, tab = bench.instrument, bench.table
    psi = math.radians(inst.tilt_deg)
    return Geometry(par, w1, w2, math.cos(psi), math.sin(psi),
                    math.radians(inst.tilt_azimuth_deg), math.radians(arcsec_to_deg(tab.wobble_arcsec)),
                    math.radians(tab.wobble_phase_deg))


def integration_mode(inst: InstrumentConfig, sample_rate_hz: float) -> str:
    """How the simulation integrates the instrument's rate at ``sample_rate_hz``:
    ``"rectangle"`` (a FOG's left rectangle rule on the simulation's grid, when that grid
    is the instrument's own: ``integration_rate_hz`` 0 or not above it) or ``"exact"``.

    >>> fog = InstrumentConfig(integration="rectangle", integration_rate_hz=1000.0)
    >>> integration_mode(fog, 1000.0), integration_mode(fog, 100.0)
    ('rectangle', 'exact')
    """
    if inst.integration == "rectangle" and inst.integration_rate_hz \
            and sample_rate_hz < inst.integration_rate_hz * (1.0 - 1e-12):
        return "exact"
    return inst.integration


def deterministic_signature(inst: InstrumentConfig) -> tuple:
    """The parameters the deterministic rate terms depend on (not the random ones)."""
    return (inst.integration, inst.integration_rate_hz, inst.bias_dph, inst.warmup_drift_dph, inst.warmup_tau_s,
            inst.sf_rate_quadratic_ppm, inst.sf_lowrate_ppm, inst.sf_lowrate_scale_dps)


@dataclass
class DeterministicRates:
    """Deterministic rate terms on a chunk of samples (:meth:`Integrator.rates`), °/s.

    ``values``: RLG, Earth rate + nonlinearity + bias (the trapezoid's integrand);
    FOG, the sensed rate with its nonlinearity plus bias (the rectangle rule's).
    """

    integration: str
    values: np.ndarray
    signature: tuple
    cos_psi: float
    trapezoid: tuple | None = None    # (previous sample's value, dt), trapezoid increments


class Integrator:
    """Stateful integration of the instrument's angle over consecutive chunks of samples.

    ``advance`` takes the times (uniform grid, continuing the previous chunk),
    the true table angle and rate, and returns the instrument's accumulated
    angle in degrees (before quantisation) since the start of the session.
    """

    def __init__(self, inst: InstrumentConfig, sample_rate_hz: float, warm_up_s: float,
                 rng: np.random.Generator | None):
        self.inst = inst
        self.dt = 1.0 / sample_rate_hz
        self.integration = integration_mode(inst, sample_rate_hz)
        self.warm_up_s = warm_up_s
        self.rng = rng
        self.angle = 0.0          # accumulated angle, deg
        self.prev = None          # (t, theta, integrand) of the last sample
        self.gm = 0.0             # Gauss–Markov bias state, °/s
        self.rrw = 0.0            # rate-random-walk state, °/s
        self.new_block = True
        if rng is not None and inst.bias_instability_dph:
            self.gm = rng.standard_normal() * dph_to_dps(inst.bias_instability_dph)

    def _noise_rate(self, n: int) -> np.ndarray | None:
        """Random rate terms on the grid, °/s (ARW as white rate; GM; RRW); None if none.

        The terms are summed in the order ARW, GM, RRW (onto zero), so the values
        do not depend on which terms are on.
        """
        inst, dt, rng = self.inst, self.dt, self.rng
        if rng is None or not (inst.arw_dpsh or inst.bias_instability_dph or inst.rrw_dphsh):
            return None
        out = None
        if inst.arw_dpsh:
            # ARW N (°/√h) → white rate with σ = N/60 (°/√s) /√dt per sample.
            out = rng.standard_normal(n)
            out *= deg_sqrt_s_from_deg_sqrt_h(inst.arw_dpsh)
            out /= math.sqrt(dt)
        if inst.bias_instability_dph:
            from scipy.signal import lfilter
            phi = math.exp(-dt / inst.bias_instability_tau_s)
            s = dph_to_dps(inst.bias_instability_dph) * math.sqrt(1.0 - phi * phi)
            w = rng.standard_normal(n)
            w *= s
            gm, _ = lfilter([1.0], [1.0, -phi], w, zi=[phi * self.gm])
            self.gm = float(gm[-1])
            if out is None:
                out = gm + 0.0
            else:
                out += gm
        if inst.rrw_dphsh:
            # K (°/h/√h) → rate increments σ = K/3600/60 (°/s/√s)·√dt.
            steps = rng.standard_normal(n)
            steps *= dph_to_dps(inst.rrw_dphsh) / math.sqrt(S_PER_H)
            steps *= math.sqrt(dt)
            r = np.cumsum(steps, out=steps)    # in place: the same running sum
            r += self.rrw
            self.rrw = float(r[-1])
            if out is None:
                out = r + 0.0
            else:
                out += r
        return out

    def advance(self, t: np.ndarray, theta_deg: np.ndarray, rate_dps: np.ndarray,
                geom: Geometry) -> np.ndarray:
        """Instrument angle (deg, unquantised, uncompensated) at each time in ``t``."""
        rep = np.ones(t.size, dtype=np.int64)
        return self.integrate(self.rates(t, theta_deg, rate_dps, rep, geom), theta_deg)

    def rates(self, t: np.ndarray, theta_u: np.ndarray, rate_u: np.ndarray, rep: np.ndarray,
              geom: Geometry) -> "DeterministicRates":
        """The deterministic rate terms on the grid ``t``, °/s.

        ``theta_u``, ``rate_u`` are the table angle and rate on runs of samples:
        value j holds for ``rep[j]`` consecutive samples (a rest is one run, a move
        one run per sample), so the Earth-rate and nonlinearity terms, constant
        over a rest, are evaluated once per run and repeated. The values are those
        of a per-sample evaluation, bit for bit. Instruments that differ only in
        their random terms share the result (:meth:`integrate` adds the noise).
        """
        inst = self.inst
        earth = geom.earth_dps(theta_u)
        sensed = rate_u * geom.cos_psi + earth
        eps = rate_nonlinearity(sensed, inst)
        # bias + drift·exp(−t_on/τ), in place on one array: t_on/(−τ) is (−t_on)/τ bit for bit
        # (IEEE division is symmetric in sign), and each step is the same operation on the
        # same operands as the expression, so the values are those of the expression
        x = t + self.warm_up_s
        x /= -inst.warmup_tau_s
        np.exp(x, out=x)
        x *= inst.warmup_drift_dph
        x += inst.bias_dph
        bias = dph_to_dps(x)
        if self.integration == "rectangle":
            det = np.repeat(sensed * (1.0 + eps), rep)
        else:
            det = np.repeat(earth + sensed * eps, rep)
        det += bias
        return DeterministicRates(self.integration, det, deterministic_signature(inst), geom.cos_psi)

    def integrate(self, det: "DeterministicRates", theta_deg: np.ndarray,
                  at: np.ndarray | None = None) -> np.ndarray:
        """Instrument angle from :meth:`rates` (same instrument but for its random terms)
        and the table angle on every sample; adds this instrument's noise.

        ``at``: indices into the chunk; only the angles there are returned (the state, the
        noise drawn and the values are those of the whole chunk's angle at those indices,
        bit for bit: the running sum is taken over every sample either way)."""
        if det.signature != deterministic_signature(self.inst):
            raise ValueError("rates() of another instrument")
        n = theta_deg.size
        noise = self._noise_rate(n)
        if det.integration == "rectangle":
            # FOG: rate samples at the grid times, left rectangle rule:
            # φ(t_k) = φ(t_{k−1}) + r(t_{k−1})·dt.
            r = det.values if noise is None else det.values + noise
            first = self.angle + (0.0 if self.prev is None else self.prev[2] * self.dt)
            ang = first + np.concatenate(([0.0], np.cumsum(r[:-1] * self.dt)))
            self.angle = float(ang[-1])
            self.prev = (0.0, float(theta_deg[-1]), float(r[-1]))
            self.new_block = False
            return ang if at is None else ang[at]
        # RLG: exact θ cos ψ, trapezoid for the smooth rest; white noise enters as
        # angle increments (the exact integral of white rate over a sample).
        smooth = det.values
        if self.prev is None:
            sm_prev, th_prev = smooth[0], theta_deg[0]
        else:
            sm_prev = self.prev[2]
            th_prev = theta_deg[0] if self.new_block else self.prev[1]
        key = (float(sm_prev), self.dt)
        if det.trapezoid is None or det.trapezoid[0] != key:
            # 0.5·(s_k + s_{k−1})·dt with s_{−1} the previous chunk's last value
            trap = np.empty_like(smooth)
            trap[0] = smooth[0] + sm_prev
            np.add(smooth[1:], smooth[:-1], out=trap[1:])
            trap *= 0.5
            trap *= self.dt
            det.trapezoid = (key, trap)      # shared with instruments that differ in noise only
        if noise is None:
            inc = det.trapezoid[1] if self.prev is not None else det.trapezoid[1].copy()
        else:
            inc = noise                       # the noise drawn for this chunk alone
            inc *= self.dt
            inc += det.trapezoid[1]
        if self.prev is None:
            inc[0] = 0.0
        # the noise's own array (drawn for this chunk) takes its running sum in place; the
        # shared trapezoid increments are summed into a new one
        run = np.cumsum(inc, out=inc if noise is not None else None)
        if at is None:
            ang = self.angle + det.cos_psi * (theta_deg - th_prev) + run
            self.angle = float(ang[-1])
        else:
            # the same expression at the indices asked and the last sample only
            ix = np.append(np.asarray(at, dtype=np.int64), theta_deg.size - 1)
            ang = self.angle + det.cos_psi * (theta_deg[ix] - th_prev) + run[ix]
            self.angle = float(ang[-1])
            ang = ang[:-1]
        self.prev = (0.0, float(theta_deg[-1]), float(smooth[-1]))
        self.new_block = False
        return ang

    def start_block(self) -> None:
        """The table was re-pointed (a new block): the closed-form θ term restarts there."""
        self.new_block = True


def uniform_hash(k, key: int) -> np.ndarray:
    """A uniform number in [0, 1) for each integer sample index ``k`` (SplitMix64 of k and key).

    Counter-based: the value of sample k does not depend on which other samples
    are drawn, so the readings and the stream see the same dither.

    >>> u = uniform_hash(np.arange(100000), key=7)
    >>> bool(0.0 <= u.min() and u.max() < 1.0), round(float(u.mean()), 2)
    (True, 0.5)
    """
    offset = np.uint64((key * 0x9E3779B97F4A7C15 + 0x9E3779B97F4A7C15) % (1 << 64))
    with np.errstate(over="ignore"):
        z = np.asarray(k, dtype=np.int64).astype(np.uint64) + offset
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        z = z ^ (z >> np.uint64(31))
    return (z >> np.uint64(11)).astype(np.float64) * (1.0 / (1 << 53))


def counts_from_angle(angle_deg: np.ndarray, inst: InstrumentConfig, k=None,
                      dither_key: int = 0) -> np.ndarray:
    """Pulse counter from the instrument angle: K·φ, floored when quantised (float64).

    With ``quantisation_dither`` the count is floor(K·φ + u), u uniform on [0, 1)
    per sample (``k`` the sample indices): random dither of the readout (as an RLG's
    noise-injected body dither does) makes the quantisation error white with zero
    mean, where a bare floor of a near-constant rate gives a deterministic sawtooth.

    >>> counts_from_angle(np.array([1.0, -1e-9]), InstrumentConfig(nominal_scale_factor_counts_per_deg=10.0)).tolist()
    [10.0, -1.0]
    """
    c = inst.true_scale_factor_counts_per_deg * np.asarray(angle_deg, dtype=float)
    if not inst.quantisation:
        return c
    if inst.quantisation_dither and k is not None:
        return np.floor(c + uniform_hash(k, dither_key))
    return np.floor(c)
