"""Run a rate-gyro programme on the virtual bench: readings (one row per sample) + truth.

A programme is a list of :class:`Segment` (one contiguous record under fixed conditions:
table rate, mounting, chamber set point, supply, vibration), produced from a protocol by
a specification package (its ``plan``). The runner
keeps the physical state between segments: time since power-on, the noise processes,
the gyro temperature lagging behind the chamber (ramps and soaks in the unrecorded
``delay_s``), the table angle, and the power-cycle draws of K and b.

Geometry: ENU frame at the site. A mounting names the body axis pointing up and the one
pointing north (``up_axis="+z"``, ``north_axis="+x"``); the gyro's input axis is body +z.
The rate table turns about the local vertical (positive: right-hand rule about up); the
Earth rate Ω_E(0, cos λ, sin λ) is projected on the input axis (and the cross axes) in
every orientation and at every table angle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import signal

from gonio.bench.rate_gyro import NoiseState, RateBench
from gonio.physics.alignment import body_rotation, mount_matrix  # noqa: F401  (re-exported)
from gonio.physics.earth import earth_rate_enu
from gonio.protocol.programme import Segment, check_rate_session_size
from gonio.units import ARCSEC_PER_DEG
from gonio.errors import GonioError

#: Column order of the rate readings (see docs/formats.md#rate-gyro-readings-file).
RATE_COLUMNS: tuple[str, ...] = ("test", "run", "step", "role", "time_s", "rate_dps", "freq_hz",
                                 "temperature_c", "supply_v", "up_axis", "north_axis",
                                 "reference_dps", "output", "stand_deg", "stand_axis",
                                 "supply_set_v")

#: Sub-samples per output interval on a turning table (the interval mean is their mean).
RATE_SUBSAMPLES = 16


def _rz(theta_rad) -> np.ndarray:
    c, s = np.cos(theta_rad), np.sin(theta_rad)
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)


def _small_rotation(rng, sigma_rad) -> np.ndarray:
    if sigma_rad <= 0:
        return np.eye(3)
    a = sigma_rad * rng.standard_normal(3)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + k + 0.5 * k @ k


@dataclass
class RateSessionResult:
    """Readings (one row per sample, :data:`RATE_COLUMNS`), metadata and truth."""

    data: pd.DataFrame
    metadata: dict
    truth: dict


class _State:
    def __init__(self, bench: RateBench, rng: np.random.Generator, room_c: float):
        self.bench, self.rng = bench, rng
        self.t = 0.0
        self.noise: NoiseState | None = None
        self.k_run = 1.0
        self.b_run = 0.0
        self.temp = room_c
        self.room = room_c
        self.chamber_set = room_c
        self.theta = 0.0
        self.run = -1


def _chamber_track(st: _State, target: float, ramp_c_per_min: float, duration_s: float,
                   eq) -> None:
    """Advance the gyro temperature over ``duration_s`` while the chamber ramps to ``target``
    (rate = min(protocol, chamber limit)) and holds (first-order lag, 1 s steps)."""
    if duration_s <= 0:
        return
    rate = min(ramp_c_per_min, eq.chamber.max_ramp_c_per_min) / 60.0
    n = int(math.ceil(duration_s))
    t = np.arange(1, n + 1, dtype=float) * (duration_s / n)
    start = st.chamber_set
    ramp_t = abs(target - start) / rate if rate > 0 else 0.0
    ch = np.where(t < ramp_t, start + np.sign(target - start) * rate * t, target)
    off = 0.0 if target == st.room else eq.chamber.deviation_at(target)
    ch = ch + np.where(t < ramp_t, 0.0, off)
    a = math.exp(-(duration_s / n) / st.bench.gyro.thermal_tau_s)
    y, _ = signal.lfilter([1 - a], [1, -a], ch, zi=[a * st.temp])
    st.temp = float(y[-1])
    st.chamber_set = target


class RateSession:
    """The virtual rate bench as a stateful recorder: :meth:`record` runs one segment after
    the other on the same physical state (power cycles, noise processes, the gyro's
    temperature, the table angle), as :func:`run_rate_session` does for a whole programme;
    the served bench (:mod:`gonio.instruments.served_rate`) records each segment when its
    instruments are told to, so that a live session and a batch one share every formula.
    """

    def __init__(self, bench: RateBench, seed: int = 0, *, room_temperature_c: float = 20.0,
                 noise: bool = True):
        self.bench, self.noise, self.room = bench, noise, room_temperature_c
        self.rng = np.random.default_rng(seed)
        self.st = _State(bench, self.rng, room_temperature_c)
        self.omega_enu = np.degrees(earth_rate_enu(bench.latitude_deg))      # °/s in ENU
        self.runs: dict = {}

    @property
    def time_since_power_on_s(self) -> float:
        return self.st.t

    def record(self, seg: Segment) -> tuple[dict, dict]:
        """Run ``seg`` (its power cycle, delay, then its samples): (its readings columns,
        :data:`RATE_COLUMNS` → lists, and its truth entry)."""
        st, rng, noise = self.st, self.rng, self.noise
        g, eq = self.bench.gyro, self.bench.equipment
        omega_enu = self.omega_enu
        if seg.samples < 1 or not seg.interval_s > 0:
            raise GonioError(f"segment {seg.test}/{seg.run}/{seg.step}: needs ≥ 1 sample and "
                             f"interval > 0")
        if seg.power_on or st.noise is None:
            if st.noise is not None:
                _chamber_track(st, st.chamber_set, seg.ramp_c_per_min, seg.off_time_s, eq)
            st.noise = NoiseState(g, rng, enabled=noise)
            st.k_run = 1.0 + (g.sf_scatter_rel * float(rng.standard_normal()) if noise else 0.0)
            st.b_run = g.bias_scatter_dps * float(rng.standard_normal()) if noise else 0.0
            st.t = 0.0
            st.run += 1
            self.runs[st.run] = {"scale_factor_scatter_rel": st.k_run - 1.0,
                                 "bias_scatter_dps": st.b_run,
                                 "first_segment": f"{seg.test}/{seg.run}/{seg.step}"}
        target = st.room if seg.temperature_c is None else float(seg.temperature_c)
        _chamber_track(st, target, seg.ramp_c_per_min, seg.delay_s, eq)
        st.noise.skip(seg.delay_s)
        if seg.rate_dps:
            st.theta += math.radians(seg.rate_dps) * seg.delay_s
        st.t += seg.delay_s
        n, dt = int(seg.samples), float(seg.interval_s)
        t = st.t + dt * np.arange(n)
        # gyro temperature along the record (chamber holding, with fluctuation)
        ch = target + (0.0 if seg.temperature_c is None else
                       eq.chamber.deviation_at(target) + eq.chamber.fluctuation_c
                       * np.sin(2 * math.pi * t / eq.chamber.fluctuation_period_s
                                + math.radians(eq.chamber.fluctuation_phase_deg)))
        a = math.exp(-dt / g.thermal_tau_s)
        temp, _ = signal.lfilter([1 - a], [1, -a], np.broadcast_to(ch, (n,)).astype(float),
                                 zi=[a * st.temp])
        st.temp = float(temp[-1])
        temp_g = temp + (0.0 if seg.temperature_c is None else eq.chamber.position_at(target))
        v_set = g.supply_nominal_v if seg.supply_v is None else float(seg.supply_v)
        v = v_set + eq.supply.error_v                       # actual terminal voltage
        K = g.scale_factor_at(temp_g, v) * st.k_run
        bias = g.bias_at(temp_g, v) + st.b_run
        R0 = _mounting(seg, eq, rng, noise)
        tilt = math.radians(eq.rate_table.tilt_deg)
        table_axis = np.array([math.sin(tilt), 0.0, math.cos(tilt)])
        if seg.vib_amplitude_dps > 0:
            det, ref, mean_in = _vibration_input(seg, g, eq, t, R0, table_axis, omega_enu,
                                                 rng, noise)
        else:
            ref = np.full(n, np.nan)
            det, mean_in = _table_input(seg, g, eq, t, st, R0, table_axis, omega_enu, dt)
        err = st.noise.samples(n, dt, temp_g)
        out = float(g.null_at(v)) + K * (det + bias + _warm_up(g, seg, t, dt) + err)
        out = out * (1 + eq.acquisition.gain_error_rel)
        lsb = max(g.output_lsb, eq.acquisition.resolution)
        if lsb > 0:
            out = np.round(out / lsb) * lsb
        st.t += n * dt
        cols: dict[str, list] = {c: [] for c in RATE_COLUMNS}
        _append_columns(cols, seg, t, v, v_set, ref, out, self.room, eq)
        truth = {"test": seg.test, "run": seg.run, "step": seg.step, "role": seg.role,
                 "temperature_c": target, "power_cycle": st.run,
                 "gyro_temperature_c": float(np.mean(temp_g)),
                 "scale_factor": float(np.mean(K)) * (1 + eq.acquisition.gain_error_rel),
                 "bias_dps": float(np.mean(bias)), "input_rate_dps": mean_in, "supply_v": v,
                 "earth_rate_on_input_dps": float(omega_enu @ (R0 @ np.array([0, 0, 1.0])))
                 if seg.rate_dps == 0 else None}
        return cols, truth

    def truth(self, seed: int, seg_truth: list) -> dict:
        """The session's truth: the bench, the power cycles drawn and every segment's."""
        b = self.bench
        return {"gyro": b.gyro.to_dict(), "equipment": b.equipment.to_dict(),
                "latitude_deg": b.latitude_deg, "seed": seed, "noise": self.noise,
                "power_cycles": self.runs, "segments": seg_truth}


def _warm_up(g, seg: Segment, t: np.ndarray, dt: float):
    """The warm-up transient: its mean over each interval (exact), or its instantaneous value
    for a vibration segment's instantaneous samples."""
    if not g.warmup_bias_dps:
        return 0.0
    tau = g.warmup_tau_s
    if seg.vib_amplitude_dps == 0:
        return g.warmup_bias_dps * tau / dt * (np.exp(-t / tau) - np.exp(-(t + dt) / tau))
    return g.warmup_bias_dps * np.exp(-t / tau)


def _mounting(seg: Segment, eq, rng, noise: bool) -> np.ndarray:
    """The gyro's attitude of a segment: its mounting, stand, fixture misalignment and, in a
    position other than the reference, the position table's random error."""
    R0 = mount_matrix(seg.up_axis, seg.north_axis)
    if seg.stand_deg:
        R0 = R0 @ body_rotation(seg.stand_axis, seg.stand_deg)
    R0 = R0 @ eq.fixture.matrix()                 # the gyro's misalignment in its fixture
    return _small_rotation(rng, math.radians(eq.position_table.position_error_arcsec / ARCSEC_PER_DEG)
                           if noise and seg.rate_dps == 0 and seg.vib_amplitude_dps == 0
                           and ((seg.up_axis, seg.north_axis) != ("+z", "+x") or seg.stand_deg)
                           else 0.0) @ R0


def run_rate_session(segments: list[Segment], bench: RateBench, seed: int = 0, *,
                     room_temperature_c: float = 20.0, metadata: dict | None = None,
                     noise: bool = True) -> RateSessionResult:
    """Execute ``segments`` in order on ``bench``; same seed → same numbers."""
    if not segments:
        raise GonioError("the programme has no segments")
    check_rate_session_size(segments, where=f"the programme on bench {bench.name}")
    session = RateSession(bench, seed, room_temperature_c=room_temperature_c, noise=noise)
    cols: dict[str, list] = {c: [] for c in RATE_COLUMNS}
    seg_truth = []
    for seg in segments:
        part, tr = session.record(seg)
        for c in RATE_COLUMNS:
            cols[c] += part[c]
        seg_truth.append(tr)
    df = pd.DataFrame(cols, columns=list(RATE_COLUMNS))
    return RateSessionResult(df, dict(metadata or {}), session.truth(seed, seg_truth))


def _vibration_input(seg: Segment, g, eq, t: np.ndarray, R0: np.ndarray,
                 table_axis: np.ndarray, omega_enu: np.ndarray, rng, noise: bool):
    """(detected rate, reference rate, mean input) of a vibration segment: the table's sine
    with its distortion through the gyro's dynamics, Earth rate, cross-axis and g terms."""
    n = t.size
    f = float(seg.freq_hz)
    vt = eq.vibration_table
    amp = seg.vib_amplitude_dps * (1 + vt.amplitude_error_rel)
    ph = 2 * math.pi * f * t
    h1, h2 = g.dynamics(f), g.dynamics(2 * f)
    true_in = amp * (np.sin(ph) + vt.distortion_rel * np.sin(2 * ph))
    dyn = amp * (abs(h1) * np.sin(ph + np.angle(h1))
                 + vt.distortion_rel * abs(h2) * np.sin(2 * ph + np.angle(h2)))
    zb = R0 @ np.array([0, 0, 1.0])
    w_in = dyn * float(table_axis @ zb) + float(omega_enu @ zb)
    det = g.response(w_in)
    xb, yb = R0 @ np.array([1.0, 0, 0]), R0 @ np.array([0, 1.0, 0])
    det = det + g.cross_axis_x * float(omega_enu @ xb) + g.cross_axis_y * float(omega_enu @ yb)
    fb = R0.T @ np.array([0, 0, 1.0])
    det = det + float(np.dot(g.g_sensitivity_dps_per_g, fb))
    ref = true_in + (vt.reference_noise_dps * rng.standard_normal(n) if noise else 0.0)
    mean_in = float(np.mean(true_in)) + float(omega_enu @ zb)
    return det, ref, mean_in


def _table_input(seg: Segment, g, eq, t: np.ndarray, st, R0: np.ndarray,
             table_axis: np.ndarray, omega_enu: np.ndarray, dt: float):
    """(detected rate, mean input) of a rate-table segment, averaged over sub-samples of
    each interval as the table turns (its rate error, ripple and tilt, Earth rate,
    cross-axis and g terms); the table's angle ``st.theta`` moves on."""
    w_set = float(seg.rate_dps)
    w_act = w_set * (1 + eq.rate_table.rate_error_rel)
    nsub = RATE_SUBSAMPLES if w_set != 0 else 1
    frac = (np.arange(nsub) + 0.5) / nsub
    ts = (t[:, None] + dt * frac[None, :]) - st.t                     # time in segment
    theta = st.theta + math.radians(w_act) * ts
    R = _rz(theta) @ R0                                                # (n, nsub, 3, 3)
    zb, xb, yb = R[..., :, 2], R[..., :, 0], R[..., :, 1]
    ripple = eq.rate_table.ripple_rel * abs(w_set) * np.sin(
        theta + math.radians(eq.rate_table.ripple_phase_deg))
    table_rate = (w_act + ripple)[..., None] * table_axis
    w_vec = table_rate + omega_enu                                      # ENU, °/s
    w_in = np.einsum("...i,...i", w_vec, zb)
    det = g.response(w_in) + g.cross_axis_x * np.einsum("...i,...i", w_vec, xb) \
        + g.cross_axis_y * np.einsum("...i,...i", w_vec, yb)
    fb = np.einsum("...ij,j->...i", np.swapaxes(R, -1, -2), np.array([0, 0, 1.0]))
    det = det + fb @ np.asarray(g.g_sensitivity_dps_per_g, float)
    det = det.mean(axis=1)
    mean_in = float(w_in.mean())
    st.theta = float(theta[-1, -1] + math.radians(w_act) * dt * 0.5 / nsub)
    return det, mean_in


def _append_columns(cols: dict, seg: Segment, t: np.ndarray, v: float, v_set: float,
                    ref: np.ndarray, out: np.ndarray, room_temperature_c: float, eq) -> None:
    """One segment's rows into the readings columns."""
    n = t.size
    cols["test"] += [seg.test] * n
    cols["run"] += [seg.run] * n
    cols["step"] += [seg.step] * n
    cols["role"] += [seg.role] * n
    cols["time_s"] += list(t)
    cols["rate_dps"] += [seg.vib_amplitude_dps if seg.vib_amplitude_dps > 0 else seg.rate_dps] * n
    cols["freq_hz"] += [seg.freq_hz] * n
    cols["temperature_c"] += [room_temperature_c if seg.temperature_c is None
                              else seg.temperature_c] * n
    cols["supply_v"] += [v] * n
    cols["up_axis"] += [seg.up_axis] * n
    cols["north_axis"] += [seg.north_axis] * n
    cols["reference_dps"] += list(ref)
    cols["output"] += list(out)
    cols["stand_deg"] += [seg.stand_deg] * n
    cols["stand_axis"] += [seg.stand_axis] * n
    cols["supply_set_v"] += [v_set if eq.supply.error_v else math.nan] * n


def constant_rate_spread_dps(bench: RateBench, rate_dps: float, interval_s: float,
                             samples: int, temp_c: float) -> dict:
    """Expected spread of ``samples`` output samples (interval means at ``interval_s``) on
    the rate table turning at a constant ``rate_dps``, gyro mounted input axis up
    (``+z``/``+x``), in °/s of input rate: the truth of IEC 62047-20 5.1.3.7.

    The population variance of the record (divisor ``samples``) has the expectation

    - noise: ∫ S(f)·(1 − D_s(f)²) df over [0, 1/(2·interval)], S the model's one-sided
      density (:func:`gonio.bench.rate_gyro.noise_psd_one_sided`), D_s the Dirichlet
      kernel of the mean of ``samples`` samples (variance of a sample minus variance of
      the record's mean);
    - the once-per-revolution terms of the turning table: the rate ripple (scaled by the
      slope of the response f′(ω)) and the cross-axis sensitivity times the horizontal
      rate (Earth rate north, table-axis tilt east), summed as phasors to an amplitude A,
      attenuated by the mean over :data:`RATE_SUBSAMPLES` sub-samples of each interval,
      D_16 = |sin(Δ/2)/(16 sin(Δ/32))|, Δ the table's turn per interval; its population
      variance averaged over the (history-dependent) start angle is A²/2·(1 − D_s(Δ)²),
      exact for any start angle when the record spans whole revolutions.

    Left out: the chamber's slow temperature fluctuation (history-dependent phase).
    Returns {"std_dps", "noise_dps", "periodic_amplitude_dps"} (std = √E[variance]).
    """
    from gonio.bench.rate_gyro import noise_psd_one_sided

    g, eq = bench.gyro, bench.equipment
    dt, n = float(interval_s), int(samples)
    if n < 2 or not dt > 0:
        raise GonioError("a spread needs ≥ 2 samples and an interval > 0", key="samples")
    f = np.linspace(0.0, 0.5 / dt, 200001)[1:]
    d_s = np.sin(math.pi * f * n * dt) / (n * np.sin(math.pi * f * dt))
    var_noise = float(np.trapezoid(noise_psd_one_sided(g, f, dt, temp_c) * (1 - d_s ** 2), f))
    tilt = math.radians(eq.rate_table.tilt_deg)
    w_act = float(rate_dps) * (1 + eq.rate_table.rate_error_rel)
    omega = np.degrees(earth_rate_enu(bench.latitude_deg))
    w_in = w_act * math.cos(tilt) + float(omega[2])
    h = 1e-6 * max(1.0, abs(w_in))
    slope = float((g.response(np.array([w_in + h])) - g.response(np.array([w_in - h])))[0]) / (2 * h)
    r = eq.rate_table.ripple_rel * abs(float(rate_dps)) * math.cos(tilt) * slope
    phi = math.radians(eq.rate_table.ripple_phase_deg)
    h_e, h_n = w_act * math.sin(tilt), float(omega[1])
    cx, cy = g.cross_axis_x, g.cross_axis_y
    # a·cos θ + b·sin θ (θ the table angle; body x = Rz(θ)·north, body y = Rz(θ)·west)
    a = r * math.sin(phi) + cx * h_n - cy * h_e
    b = r * math.cos(phi) - cx * h_e - cy * h_n
    amp = math.hypot(a, b)
    delta = math.radians(w_act) * dt
    m = RATE_SUBSAMPLES
    if amp and delta:
        amp *= abs(math.sin(delta / 2) / (m * math.sin(delta / (2 * m))))
        den = n * math.sin(delta / 2)
        d_rev = 1.0 if abs(den) < 1e-12 else math.sin(n * delta / 2) / den   # Δ = 2πk: constant
        var_per = 0.5 * amp ** 2 * (1 - d_rev ** 2)
    else:
        var_per = 0.0
    return {"std_dps": math.sqrt(var_noise + var_per), "noise_dps": math.sqrt(var_noise),
            "periodic_amplitude_dps": amp}
