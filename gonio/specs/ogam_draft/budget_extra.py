"""Budget components beyond a specification's own lines: one implementation each.

The draft's Annex A budget has four lines (table, tilt projection, zero drift,
repeatability). The validation on the virtual bench (``gonio validate``) showed
three effects it lacks; each is built here once, and both the calibration
pipeline and the validation use these functions:

:class:`ExtraComponent`            an additive Type B line (symbol, source, half-width, distribution)
:func:`compensation_component`     the residual of the clause-7 Earth-rate compensation
:func:`session_coupling`           tilt × Earth-rate coupling of every planned reading
:func:`coupling_budget_component`  its worst case as an arcsine line (``C_te``)
:func:`tilt_coupling_coefficients` the coupling integrals of a reading at constant rate
:func:`budget_extra_components`    ``K_P``, ``K_r`` (scale-factor error carried from 7.1
                                   into E) and ``tilt_E`` from a calibration's own readings
:func:`angle_tilt_correction`      E's coupling at a *measured* tilt (the correction and its u)

The physics is in :mod:`gonio.specs.ogam_draft.coupling` and
:mod:`gonio.specs.ogam_draft.compensation`; see ``docs/draft-readings.md#what-the-draft-leaves-out``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from gonio.errors import GonioError
from gonio.specs.ogam_draft.compensation import CompensationResidual
from gonio.specs.ogam_draft.coupling import coupling_terms
from gonio.physics.earth import earth_rate_split
from gonio.physics.kinematics import Timeline
from gonio.specs.ogam_draft.protocol import Protocol
from gonio.specs.ogam_draft.table_calibration import position_key
from gonio.specs.ogam_draft.table_periodic import periodic_response, worst_order
from gonio.units import ARCSEC_PER_DEG, dps_to_arcsec_s

__all__ = ["ExtraComponent", "compensation_component", "SessionCoupling", "session_coupling",
           "coupling_budget_component", "tilt_coupling_coefficients", "budget_extra_components",
           "scale_factor_tilt_bias", "scale_factor_round_coupling",
           "nonlinearity_tilt_bias", "TiltCorrection", "scale_factor_tilt_correction",
           "MeasuredRoundTilt", "measured_round_tilt", "AngleTiltCorrection",
           "angle_tilt_correction", "EXTRA_SYMBOLS"]

#: Symbols of :func:`budget_extra_components`.
EXTRA_SYMBOLS: tuple[str, ...] = ("K_P", "K_r", "tilt_E")


@dataclass(frozen=True)
class ExtraComponent:
    """An additional additive Type B component of the Annex A model (c = +1).

    >>> ExtraComponent("E_r", "Earth-rate residual", 0.02).distribution
    'rectangular'
    """

    symbol: str
    source: str
    half_width_arcsec: float
    distribution: str = "rectangular"


def compensation_component(residual: CompensationResidual, symbol: str = "E_c") -> ExtraComponent:
    """An additive component for an Earth-rate compensation residual: normal, half-width = u(angle).

    >>> from gonio.specs.ogam_draft.compensation import measured_compensation
    >>> c = compensation_component(measured_compensation(60.0, arw_dpsh=0.001))
    >>> c.symbol, c.distribution, round(c.half_width_arcsec, 4)
    ('E_c', 'normal', 0.2324)
    """
    return ExtraComponent(symbol, f"Earth-rate compensation residual ({residual.method}, "
                          f"t = {residual.measuring_time_s:g} s)", residual.u_angle_arcsec, "normal")


@dataclass
class SessionCoupling:
    """Coupling error per planned reading of a session (see :func:`session_coupling`)."""

    test: list
    orientation: list
    round: list
    table_deg: np.ndarray
    time_s: np.ndarray
    error_arcsec: np.ndarray          # at the given α (NaN if no α given)
    worst_case_arcsec: np.ndarray     # over α


def session_coupling(protocol, bench, tilt_deg: float | None = None,
                     tilt_azimuth_table_deg: float | None = None) -> SessionCoupling:
    """Coupling error of every reading the bench would take for ``protocol``.

    The motion and the zeroing/reading instants come from
    :func:`gonio.specs.ogam_draft.bench.session.plan_session` (no random table scatter); the
    compensation is the protocol's (measured in the static phase at the start of
    each block, or computed). ψ and α default to the bench instrument's.

    Examples
    --------
    One round 0° → 180° at 60 °/s, 60 °/s² (1 s ramps, 2 s cruise), read 10 s after
    arrival (Δt = 14 s); axis up at 40° N, ψ = 0.1°. By hand: P = ∫cos θ − Δt =
    (0 over the symmetric move − 10 s at 180°) − 14 s = −24 s; Q = ∫sin θ =
    (cos 30° − cos 150°)/(π/3 rad/s) + 2∫₀¹ sin(π t²/6) dt = 1.654 + 0.342 = 1.996 s;
    worst case = Ω_⊥ tan ψ · hypot(P, Q) = 0.020110″/s × 24.083 s = 0.484″.

    >>> from gonio.specs.ogam_draft.protocol import parse_protocol
    >>> from gonio.specs.ogam_draft.bench.config import Bench, InstrumentConfig, TableConfig
    >>> p = parse_protocol({"protocol": {"name": "x"}, "angle_deviation": {
    ...     "rest_s": 15.0, "rounds": [{"stop_deg": 180.0}]}})
    >>> b = Bench("b", InstrumentConfig(tilt_deg=0.1), TableConfig(), latitude_deg=40.0,
    ...           sample_rate_hz=100.0)
    >>> round(float(session_coupling(p, b).worst_case_arcsec[0]), 3)
    0.484
    """
    psi = bench.instrument.tilt_deg if tilt_deg is None else tilt_deg
    az = bench.instrument.tilt_azimuth_deg if tilt_azimuth_table_deg is None \
        else tilt_azimuth_table_deg
    from gonio.specs.ogam_draft.bench.session import plan_session      # only for this optional component

    blocks = plan_session(protocol, bench, None)
    dt = 1.0 / bench.sample_rate_hz
    comp = protocol.session.earth_compensation
    lat = bench.latitude_deg if bench.earth_rate else None
    out = {k: [] for k in ("test", "orientation", "round", "table_deg", "time_s", "e", "w")}
    for blk in blocks:
        if lat is None:
            par = perp = beta = 0.0
        else:
            sp = earth_rate_split(lat, blk.orientation)
            par, perp, beta = sp.parallel_dps, sp.perpendicular_dps, sp.perpendicular_direction_deg
        c = comp if blk.compensate else "none"
        thc = None
        if c == "measured" and blk.k_static:
            thc = float(blk.timeline.angle_deg(np.array([blk.k_static[0] * dt]))[0])
        for r in blk.readings:
            terms = coupling_terms(blk.timeline, r.k_zero * dt, r.k_read * dt, psi, perp,
                                   compensation=c, theta_comp_deg=thc, parallel_dps=par)
            out["test"].append(r.test)
            out["orientation"].append(r.orientation)
            out["round"].append(r.round)
            out["table_deg"].append(r.table_deg)
            out["time_s"].append((r.k_read - r.k_zero) * dt)
            out["e"].append(float(terms.error_arcsec(az - beta)))
            out["w"].append(terms.worst_case_arcsec())
    return SessionCoupling(out["test"], out["orientation"], out["round"],
                           np.array(out["table_deg"]), np.array(out["time_s"]),
                           np.array(out["e"]), np.array(out["w"]))


def coupling_budget_component(protocol, latitude_deg: float, tilt_deg: float, *,
                              accel_dps2: float = 60.0, symbol: str = "C_te",
                              test: str = "angle_deviation"):
    """An optional Annex A component for the tilt × Earth-rate coupling (off by default).

    Half-width: the worst case over α and over the ``test`` readings of the
    protocol (at the protocol's orientation, rates and timing); arcsine
    distribution, because the error is a sinusoid of an unknown, uniformly
    distributed tilt azimuth α (JCGM 101 6.4.6: u = a/√2). Pass the result to
    a specification's budget in ``extra_components``. The draft's
    budget has no such line (``docs/draft-readings.md#tilt-and-earth-rate-coupling``).

    Examples
    --------
    The draft's 7.4 at 40° N with the 0.1° bound of Annex A.1 (largest at the
    180° point, as in :func:`session_coupling`'s example; the draft's budget, 0.30″
    expanded, has no line for it):

    >>> from gonio.specs.ogam_draft.protocol import load_protocol
    >>> from gonio.specs import DEFAULT_KEY, get
    >>> c = coupling_budget_component(load_protocol(get(DEFAULT_KEY).default_protocol), 40.0, 0.1)
    >>> c.symbol, c.distribution, round(c.half_width_arcsec, 2)
    ('C_te', 'arcsine', 0.48)
    """
    from gonio.specs.ogam_draft.bench.config import Bench, InstrumentConfig, TableConfig

    bench = Bench("coupling", InstrumentConfig(tilt_deg=tilt_deg),
                  TableConfig(accel_dps2=accel_dps2), latitude_deg=latitude_deg,
                  sample_rate_hz=1000.0)
    sc = session_coupling(protocol, bench)
    sel = np.array([t == test for t in sc.test])
    if not sel.any():
        raise GonioError(f"the protocol has no {test} readings", key=test)
    return ExtraComponent(symbol, f"tilt × Earth-rate coupling (ψ = {tilt_deg:g}°, "
                          f"φ = {latitude_deg:g}°)", float(sc.worst_case_arcsec[sel].max()),
                          "arcsine")


def tilt_coupling_coefficients(theta_deg, time_s, rate_dps: float, read_delay_s: float,
                               accel_dps2: float = 60.0):
    """(C, S) with ∫₀ᵗ [cos(θ(t′)+α) − cos α] dt′ = C cos α − S sin α, seconds, per reading.

    The residual rate of the tilt × Earth-rate coupling after the compensation
    measured at the zero position is Ω_⊥ sin ψ [cos(θ+α) − cos α]
    (:mod:`gonio.specs.ogam_draft.coupling`); integrated from the zeroing to the reading it
    is Ω_⊥ sin ψ (C cos α − S sin α). Each reading is modelled as a trapezoidal
    move from 0 to θ at ``rate_dps`` and ``accel_dps2`` followed by a rest until
    ``time_s`` after zeroing (``read_delay_s`` is kept for the call signature of
    the readings model: the rest is whatever the time to reading leaves). The
    integrals are :func:`gonio.specs.ogam_draft.coupling.coupling_terms`' (one implementation).

    A half turn at 60 °/s with a near-instant start, read 13 s after zeroing:
    C = sin θ/ω − T_r + (cos θ − 1)(t − T_r) = −23 s, S = (1 − cos θ)/ω + sin θ (t − T_r) = 1.91 s.

    >>> c, s = tilt_coupling_coefficients([180.0], [13.0], 60.0, 10.0, accel_dps2=1e9)
    >>> round(float(c[0]), 3), round(float(s[0]), 3)
    (-23.0, 1.91)
    """
    th = np.atleast_1d(np.asarray(theta_deg, dtype=float))
    t = np.atleast_1d(np.asarray(time_s, dtype=float))
    th, t = np.broadcast_arrays(th, t)
    # one integration per distinct (θ, t) pair: a large file repeats the same few moves
    pairs, inverse = np.unique(np.stack([th.ravel(), t.ravel()], axis=1), axis=0,
                               return_inverse=True)
    c = np.empty(len(pairs))
    s = np.empty(len(pairs))
    for i, (theta, t_read) in enumerate(pairs.tolist()):
        # keyed by the exact bits (hex): −0.0 and 0.0 are kept apart
        c[i], s[i] = _move_coupling(float(theta).hex(), float(t_read).hex(),
                                    float(rate_dps).hex(), float(accel_dps2).hex())
    inverse = inverse.reshape(-1)
    return c[inverse].reshape(th.shape), s[inverse].reshape(th.shape)


@functools.lru_cache(maxsize=1024)
def _move_coupling(theta_deg: str, t_read_s: str, rate_dps: str,
                   accel_dps2: str) -> tuple[float, float]:
    """(C, S) of :func:`tilt_coupling_coefficients` for one move from 0 to θ and a rest to
    the reading, the four numbers given as ``float.hex`` strings: a pure function of them,
    kept for the budgets that ask for the same few moves again (the K, E, C and
    nonlinearity budgets)."""
    theta_deg, t_read_s, rate_dps, accel_dps2 = (
        float.fromhex(v) for v in (theta_deg, t_read_s, rate_dps, accel_dps2))
    tl = Timeline()
    arrive = tl.move(theta_deg, rate_dps, accel_dps2)
    tl.dwell(max(t_read_s - arrive, 0.0))
    terms = coupling_terms(tl, 0.0, t_read_s, 0.0, 0.0, compensation="measured",
                           theta_comp_deg=0.0)
    return float(terms.p_s), float(terms.q_s)


def scale_factor_tilt_bias(scale_factor_rows: pd.DataFrame, protocol: Protocol,
                           latitude_deg: float, tilt_deg: float,
                           accel_dps2: float = 60.0) -> float:
    """Worst case over the tilt azimuth of the bias the tilt × Earth-rate coupling of the
    7.1 rounds gives K, as the error it makes in an angle: A_K (arcsec per degree), so an
    angle θ read with that K is off by up to A_K·θ (arcsine in the unknown azimuth).

    K = mean C_k/θ_k; round k's coupling e_k(α) = Ω_⊥ sin ψ (C_k cos α − S_k sin α)
    (:func:`tilt_coupling_coefficients`) moves it by mean_k e_k/θ_k, whose amplitude over α
    is Ω_⊥ sin ψ · |(mean C_k/θ_k, mean S_k/θ_k)|. This is the part of
    :func:`budget_extra_components`'s ``tilt_E`` that enters through K; a difference of
    two angles θ_a, θ_b read with the same K carries A_K·|θ_a − θ_b|.

    >>> from gonio.specs.ogam_draft.protocol import load_protocol
    >>> from gonio.specs import DEFAULT_KEY, get
    >>> p = load_protocol(get(DEFAULT_KEY).default_protocol)
    >>> sf = pd.DataFrame({"table_deg": [60.0, 120.0, 180.0, 240.0, 300.0, 360.0],
    ...                    "time_s": [11.0, 12.0, 13.0, 14.0, 15.0, 16.0]})
    >>> a = scale_factor_tilt_bias(sf, p, 40.0, 0.1)
    >>> 0 < a * 360 / 1296000 < 1e-6, scale_factor_tilt_bias(sf, p, 40.0, 0.0)
    (True, 0.0)
    """
    a_k, b_k = scale_factor_round_coupling(scale_factor_rows, protocol, latitude_deg, tilt_deg,
                                           accel_dps2)
    if a_k.size == 0:
        return 0.0
    return float(math.hypot(float(np.mean(a_k)), float(np.mean(b_k))))


def scale_factor_round_coupling(scale_factor_rows: pd.DataFrame, protocol: Protocol,
                                latitude_deg: float, tilt_deg: float,
                                accel_dps2: float = 60.0) -> tuple[np.ndarray, np.ndarray]:
    """Per 7.1 round k, (a_k, b_k), arcsec per degree: the tilt × Earth-rate coupling moves
    round k's reading by e_k(α) = Ω_⊥ sin ψ (C_k cos α − S_k sin α)
    (:func:`tilt_coupling_coefficients`), so its K_i = C_i/θ_i by the relative error
    e_k/(3600 θ_k) = (a_k cos α − b_k sin α)/3600 with a_k = Ω_⊥ sin ψ C_k/θ_k,
    b_k = Ω_⊥ sin ψ S_k/θ_k. Empty arrays when the protocol has no 7.1.

    >>> from gonio.specs.ogam_draft.protocol import load_protocol
    >>> from gonio.specs import DEFAULT_KEY, get
    >>> p = load_protocol(get(DEFAULT_KEY).default_protocol)
    >>> sf = pd.DataFrame({"table_deg": [60.0, 360.0], "time_s": [11.0, 16.0]})
    >>> a, b = scale_factor_round_coupling(sf, p, 40.0, 0.1)
    >>> a.shape, bool(abs(a[1]) < abs(a[0]))
    ((2,), True)
    """
    th_k = np.abs(scale_factor_rows["table_deg"].to_numpy(dtype=float))
    t_k = scale_factor_rows["time_s"].to_numpy(dtype=float)
    sfi = protocol.scale_factor
    if sfi is None or th_k.size == 0:
        return np.zeros(0), np.zeros(0)
    omega = dps_to_arcsec_s(earth_rate_split(latitude_deg, sfi.orientation).perpendicular_dps) \
        * math.sin(math.radians(tilt_deg))
    ck, sk = tilt_coupling_coefficients(th_k, t_k, sfi.rate_dps, sfi.read_delay_s, accel_dps2)
    return omega * ck / th_k, omega * sk / th_k


@dataclass(frozen=True)
class TiltCorrection:
    """The tilt × Earth-rate coupling of the 7.1 rounds at a *measured* tilt (the in-situ
    tilt estimate, :mod:`gonio.specs.ogam_draft.tilt_estimate`): K's relative bias δ and its
    standard uncertainty, with the estimate it comes from (see
    :func:`scale_factor_tilt_correction`)."""

    delta_rel: float            # δ: K(7.1) = K·(1 + δ)
    u_delta_rel: float          # u(δ), from the fit's covariance (ν = dof)
    dof: int                    # ν of the tilt estimate's fit (N/2 − 2 in pairs, else N − 3)
    tilt_deg: float             # ψ
    u_tilt_deg: float
    azimuth_deg: float          # α, the tilt's azimuth in the table frame
    u_azimuth_deg: float
    r_tilt_azimuth: float       # correlation coefficient r(ψ, α)
    k95: float                  # Student-t factor for 95 % with ν = dof
    n_positions: int
    orientation: str            # the tilt estimate's table axis
    basis: str                  # how the fit's u was found (tilt_estimate.fit_first_harmonic)
    left_out_deg: tuple         # rests left out of the fit (outside a complete opposite pair)

    def to_dict(self) -> dict:
        """Plain dict (results.json); the 95 % expanded uncertainties of ψ and α beside u."""
        d = dict(self.__dict__)
        d["left_out_deg"] = list(self.left_out_deg)
        d.update(U95_tilt_deg=self.k95 * self.u_tilt_deg,
                 U95_azimuth_deg=self.k95 * self.u_azimuth_deg)
        return d


def scale_factor_tilt_correction(scale_factor_rows: pd.DataFrame, protocol: Protocol,
                                 latitude_deg: float, estimate,
                                 accel_dps2: float = 60.0) -> TiltCorrection:
    """K's relative bias δ from the tilt × Earth-rate coupling of the 7.1 rounds at the
    tilt ψ and azimuth α the in-situ estimate measured, and u(δ) (beyond the draft).

    Round k's K_i is off by (a_k cos γ − b_k sin γ)/3600 (:func:`scale_factor_round_coupling`,
    a_k, b_k ∝ sin ψ; γ = α − β the azimuth from Ω_⊥'s direction β of 7.1's orientation), so
    K = mean K_i is off by δ(ψ, γ) = sin ψ·D(γ), D(γ) = mean(a¹_k cos γ − b¹_k sin γ)/3600
    (a¹, b¹ at sin ψ = 1). The estimate's fit c0 + a cos θ + b sin θ
    (:func:`gonio.specs.ogam_draft.tilt_estimate.fit_first_harmonic`, covariance Σ_ab) gives
    ψ = asin(hypot(a, b)/Ω_⊥) and α = atan2(−b, a) + β_te; their covariance J Σ_ab Jᵀ and
    δ's gradient (cos ψ·D, sin ψ·D′) give u²(δ) by the law of propagation with the
    correlation of ψ and α (JCGM 100 5.2). With the estimate taken in 7.1's orientation δ is
    linear in (a, b) (sin ψ cos γ = a/Ω_⊥, sin ψ sin γ = −b/Ω_⊥), so the first-order u is
    exact; ν the fit's (N/2 − 2 for rests in opposite pairs, else N − 3).

    Examples
    --------
    A noise-free estimate in 7.1's orientation: δ equals the coupling of the rounds at the
    estimate's ψ and phase (the worst-case amplitude of :func:`scale_factor_tilt_bias` at
    the phase where it is largest), u(δ) = 0:

    >>> from gonio.specs.ogam_draft.protocol import load_protocol
    >>> from gonio.specs.ogam_draft.tilt_estimate import estimate_tilt
    >>> from gonio.specs import DEFAULT_KEY, get
    >>> p = load_protocol(get(DEFAULT_KEY).default_protocol)
    >>> sf = pd.DataFrame({"table_deg": [60.0, 120.0, 180.0, 240.0, 300.0, 360.0],
    ...                    "time_s": [11.0, 12.0, 13.0, 14.0, 15.0, 16.0]})
    >>> a, b = scale_factor_round_coupling(sf, p, 40.0, 0.1)
    >>> g = math.atan2(-b.mean(), a.mean())               # the phase of the largest bias
    >>> th = np.arange(12) * 30.0
    >>> amp = 11.522126 * math.sin(math.radians(0.1))
    >>> e = estimate_tilt(th, 9.7 + amp * np.cos(np.radians(th) + g), 40.0, "up")
    >>> c = scale_factor_tilt_correction(sf, p, 40.0, e)
    >>> A = scale_factor_tilt_bias(sf, p, 40.0, e.tilt_deg)
    >>> bool(abs(c.delta_rel - A / 3600) < 1e-12 * A), c.u_delta_rel < 1e-15, c.dof
    (True, True, 9)
    """
    sfi = protocol.scale_factor
    if sfi is None or len(scale_factor_rows) == 0:
        raise GonioError("the tilt correction of K needs the 7.1 rounds")
    fit = estimate.fit                      # the fit ψ and α come from, its covariance
    _, fa, fb = fit.coef
    amp = math.hypot(fa, fb)
    if not amp > 0:
        raise GonioError("the tilt estimate's first harmonic is zero: no azimuth to correct at")
    perp = estimate.perpendicular_arcsec_s
    psi = math.radians(estimate.tilt_deg)
    # J: (ψ, α) by (a, b): ψ = asin(A/Ω_⊥), α = atan2(−b, a) + β
    jac = np.array([[fa, fb], [fb, -fa]]) / np.array([[amp * perp * math.cos(psi)], [amp ** 2]])
    cov = jac @ fit.cov[1:, 1:] @ jac.T
    a1, b1 = scale_factor_round_coupling(scale_factor_rows, protocol, latitude_deg, 90.0,
                                         accel_dps2)
    beta = math.radians(earth_rate_split(latitude_deg, sfi.orientation)
                        .perpendicular_direction_deg)
    gam = math.radians(estimate.tilt_azimuth_table_deg) - beta
    d_g = float(np.mean(a1 * math.cos(gam) - b1 * math.sin(gam))) / ARCSEC_PER_DEG
    dd_g = -float(np.mean(a1 * math.sin(gam) + b1 * math.cos(gam))) / ARCSEC_PER_DEG
    grad = np.array([math.cos(psi) * d_g, math.sin(psi) * dd_g])
    u_psi, u_al = (math.sqrt(max(float(cov[i, i]), 0.0)) for i in (0, 1))
    r = float(cov[0, 1] / (u_psi * u_al)) if u_psi > 0 and u_al > 0 else 0.0
    return TiltCorrection(
        delta_rel=math.sin(psi) * d_g, u_delta_rel=math.sqrt(max(float(grad @ cov @ grad), 0.0)),
        dof=int(fit.dof), tilt_deg=float(estimate.tilt_deg), u_tilt_deg=math.degrees(u_psi),
        azimuth_deg=float(estimate.tilt_azimuth_table_deg), u_azimuth_deg=math.degrees(u_al),
        r_tilt_azimuth=r, k95=float(estimate.k95), n_positions=int(estimate.n_positions),
        orientation=str(estimate.orientation), basis=fit.basis,
        left_out_deg=tuple(float(estimate.table["table_deg"].iloc[i]) for i in fit.left_out))


@dataclass(frozen=True)
class MeasuredRoundTilt:
    """The tilt × Earth-rate coupling of each 7.1 round at the tilt the in-situ estimate
    measured (see :func:`measured_round_tilt`): per round the relative error of K_i is
    sin ψ·(a¹_k cos γ − b¹_k sin γ)/3600 (a¹, b¹ of :func:`scale_factor_round_coupling` at
    sin ψ = 1, ″/°; γ = α − β), with the estimate's (ψ, γ), their covariance (rad²) and ν."""

    a1: np.ndarray
    b1: np.ndarray
    psi_rad: float
    gamma_rad: float
    cov_rad2: np.ndarray        # 2×2 covariance of (ψ, γ)
    dof: int

    def rel_error(self, psi_rad=None, gamma_rad=None) -> np.ndarray:
        """Relative error of each round's K_i at (ψ, γ) (default the estimate's); arrays of
        shape (draws, 1) give (draws, n)."""
        psi = self.psi_rad if psi_rad is None else psi_rad
        gam = self.gamma_rad if gamma_rad is None else gamma_rad
        return np.sin(psi) * (self.a1 * np.cos(gam) - self.b1 * np.sin(gam)) / ARCSEC_PER_DEG


def measured_round_tilt(scale_factor_rows: pd.DataFrame, protocol: Protocol,
                        latitude_deg: float, correction: TiltCorrection,
                        accel_dps2: float = 60.0) -> MeasuredRoundTilt:
    """Each 7.1 round's coupling at the measured tilt (a :class:`TiltCorrection`): what K_l
    corrects round by round instead of allowing for the A.1 bound at an unknown azimuth
    (beyond the draft; JCGM 100 3.2.4: a known systematic effect is corrected). Rows in the
    order of the K_i they go with. The mean of the rounds' errors is K's δ
    (:func:`scale_factor_tilt_correction`); four rounds, a tilt of 0.08° at 40° N:

    >>> from gonio.specs import DEFAULT_KEY, get
    >>> from gonio.specs.ogam_draft.protocol import load_protocol
    >>> from gonio.specs.ogam_draft.tilt_estimate import estimate_tilt
    >>> p = load_protocol(get(DEFAULT_KEY).default_protocol)
    >>> sf = pd.DataFrame({"table_deg": [90.0, 180.0, 270.0, 360.0],
    ...                    "time_s": [12.0, 13.5, 15.0, 16.5]})
    >>> th = np.arange(12) * 30.0
    >>> amp = 11.522126 * math.sin(math.radians(0.08))
    >>> y = 9.7 + amp * np.cos(np.radians(th + 40.0)) + 1e-4 * np.cos(np.radians(3 * th))
    >>> c = scale_factor_tilt_correction(sf, p, 40.0, estimate_tilt(th, y, 40.0, "up"))
    >>> m = measured_round_tilt(sf, p, 40.0, c)
    >>> bool(abs(m.rel_error().mean() - c.delta_rel) < 1e-12 * abs(c.delta_rel)), m.dof
    (True, 9)
    """
    a1, b1 = scale_factor_round_coupling(scale_factor_rows, protocol, latitude_deg, 90.0,
                                         accel_dps2)
    beta = earth_rate_split(latitude_deg, protocol.scale_factor.orientation) \
        .perpendicular_direction_deg
    u = np.radians([correction.u_tilt_deg, correction.u_azimuth_deg])
    r = correction.r_tilt_azimuth
    cov = np.array([[u[0] ** 2, r * u[0] * u[1]], [r * u[0] * u[1], u[1] ** 2]])
    return MeasuredRoundTilt(a1, b1, math.radians(correction.tilt_deg),
                             math.radians(correction.azimuth_deg - beta), cov,
                             int(correction.dof))


@dataclass(frozen=True)
class AngleTiltCorrection:
    """The tilt × Earth-rate coupling of each 7.4 reading at the tilt the in-situ estimate
    measured (see :func:`angle_tilt_correction`): its error in E_ij (″, to subtract) and the
    standard uncertainty of that error from the estimate's covariance of (ψ, α), ν = dof."""

    error_arcsec: np.ndarray    # per 7.4 reading, in the order of the rows given
    u_arcsec: np.ndarray        # u of each error (first order in (ψ, γ); exact, see below)
    dof: int
    tilt_deg: float
    azimuth_deg: float
    U95_tilt_deg: float         # the estimate's U95 of ψ and α (k95 · u), as K's correction
    U95_azimuth_deg: float


def angle_tilt_correction(scale_factor_rows: pd.DataFrame, angle_rows: pd.DataFrame,
                          protocol: Protocol, latitude_deg: float, correction: TiltCorrection,
                          accel_dps2: float = 60.0) -> AngleTiltCorrection:
    """E_ij's error from the tilt × Earth-rate coupling at the measured tilt (beyond the draft;
    JCGM 100 3.2.4: a known systematic effect is corrected), and its u.

    Reading i (7.4, angle θ_i, read t_i after zeroing) carries the coupling
    e_i = Ω_⊥ sin ψ (C_i cos γ − S_i sin γ) (:func:`tilt_coupling_coefficients`, γ = α − β);
    it is converted with the 7.1 K, which the rounds' coupling moves by δ = mean_k(e_k/θ_k)/3600
    (:func:`scale_factor_tilt_correction`), so an angle θ reads θ(1 − δ). E_ij is off by
    Ω_⊥ sin ψ [(C_i − θ_i m_C) cos γ − (S_i − θ_i m_S) sin γ], m_C = mean C_k/θ_k,
    m_S = mean S_k/θ_k: the line ``tilt_E`` of :func:`budget_extra_components` (``intrinsic``)
    at the measured (ψ, γ) instead of its worst case at the A.1 bound. u by the law of
    propagation (JCGM 100 5.2) with the covariance of (ψ, α) of ``correction``; the error is
    linear in (sin ψ cos γ, sin ψ sin γ), which the estimate's fit gives linearly when it is
    taken in 7.4's orientation, so the first-order u is exact there. 7.1 and 7.4 must share
    their orientation (the estimate's azimuth is in that frame).

    Examples
    --------
    At the A.1 bound, the error's largest amplitude over the azimuth is ``tilt_E``'s
    half-width; at the estimate's γ it is that sinusoid's value (here u = 0: a noise-free
    estimate):

    >>> from gonio.specs.ogam_draft.protocol import load_protocol
    >>> from gonio.specs.ogam_draft.tilt_estimate import estimate_tilt
    >>> from gonio.specs import DEFAULT_KEY, get
    >>> p = load_protocol(get(DEFAULT_KEY).default_protocol)
    >>> sf = pd.DataFrame({"table_deg": [60.0, 120.0, 180.0, 240.0, 300.0, 360.0],
    ...                    "time_s": [11.0, 12.0, 13.0, 14.0, 15.0, 16.0]})
    >>> ad = pd.DataFrame({"table_deg": [180.0, 360.0], "time_s": [13.0, 16.0]})
    >>> th = np.arange(12) * 30.0
    >>> amp = 11.522126 * math.sin(math.radians(0.1))
    >>> e = estimate_tilt(th, 9.7 + amp * np.cos(np.radians(th + 70.0)), 40.0, "up")
    >>> c = angle_tilt_correction(sf, ad, p, 40.0, scale_factor_tilt_correction(sf, p, 40.0, e))
    >>> top = budget_extra_components(pd.concat([sf.assign(test="scale_factor"),
    ...     ad.assign(test="angle_deviation")]), p, 40.0, 0.1, truth="intrinsic")[2]
    >>> bool(np.abs(c.error_arcsec).max() <= top.half_width_arcsec * (1 + 1e-9)), c.dof
    (True, 9)
    >>> bool(c.u_arcsec.max() < 1e-9)
    True
    """
    sfi, adi = protocol.scale_factor, protocol.angle_deviation
    if sfi is None or adi is None or len(scale_factor_rows) == 0:
        raise GonioError("E's tilt correction needs the 7.1 rounds and the 7.4 readings")
    if adi.orientation != sfi.orientation:
        raise GonioError(f"E's tilt correction needs 7.4 in 7.1's orientation "
                         f"({adi.orientation} vs {sfi.orientation})", key="orientation")
    th_k = np.abs(scale_factor_rows["table_deg"].to_numpy(dtype=float))
    ck, sk = tilt_coupling_coefficients(th_k, scale_factor_rows["time_s"].to_numpy(dtype=float),
                                        sfi.rate_dps, sfi.read_delay_s, accel_dps2)
    th_i = np.abs(angle_rows["table_deg"].to_numpy(dtype=float))
    ci, si = tilt_coupling_coefficients(th_i, angle_rows["time_s"].to_numpy(dtype=float),
                                        adi.rate_dps, adi.read_delay_s, accel_dps2)
    p_i = ci - th_i * float(np.mean(ck / th_k))
    q_i = si - th_i * float(np.mean(sk / th_k))
    split = earth_rate_split(latitude_deg, adi.orientation)
    om = dps_to_arcsec_s(split.perpendicular_dps)
    psi = math.radians(correction.tilt_deg)
    gam = math.radians(correction.azimuth_deg - split.perpendicular_direction_deg)
    err = om * math.sin(psi) * (p_i * math.cos(gam) - q_i * math.sin(gam))
    g_psi = om * math.cos(psi) * (p_i * math.cos(gam) - q_i * math.sin(gam))
    g_gam = -om * math.sin(psi) * (p_i * math.sin(gam) + q_i * math.cos(gam))
    u_psi, u_gam = math.radians(correction.u_tilt_deg), math.radians(correction.u_azimuth_deg)
    cov = correction.r_tilt_azimuth * u_psi * u_gam
    var = g_psi ** 2 * u_psi ** 2 + 2.0 * g_psi * g_gam * cov + g_gam ** 2 * u_gam ** 2
    return AngleTiltCorrection(err, np.sqrt(np.maximum(var, 0.0)), int(correction.dof),
                               float(correction.tilt_deg), float(correction.azimuth_deg),
                               float(correction.k95 * correction.u_tilt_deg),
                               float(correction.k95 * correction.u_azimuth_deg))


def nonlinearity_tilt_bias(scale_factor_rows: pd.DataFrame, protocol: Protocol,
                           latitude_deg: float, tilt_deg: float, i_max: int, i_min: int,
                           accel_dps2: float = 60.0) -> float:
    """Worst case over the tilt azimuth of the error the tilt × Earth-rate coupling gives the
    spread K_i(max) − K_i(min) of the 7.1 rounds (draft 7.2), arcsec per degree: rounds
    ``i_max`` and ``i_min`` (positions in ``scale_factor_rows``) are off by
    (a_k cos α − b_k sin α)/3600 relative (:func:`scale_factor_round_coupling`), their
    difference by (Δa cos α − Δb sin α)/3600, whose amplitude over α is |(Δa, Δb)|. The
    coupling differs between rounds (it grows with the time from zeroing to reading, not
    with the angle), so unlike the common factor cos ψ it does not cancel in K_l.

    >>> from gonio.specs.ogam_draft.protocol import load_protocol
    >>> from gonio.specs import DEFAULT_KEY, get
    >>> p = load_protocol(get(DEFAULT_KEY).default_protocol)
    >>> sf = pd.DataFrame({"table_deg": [60.0, 360.0], "time_s": [11.0, 16.0]})
    >>> a, b = scale_factor_round_coupling(sf, p, 40.0, 0.1)
    >>> nonlinearity_tilt_bias(sf, p, 40.0, 0.1, 0, 1) == math.hypot(a[0] - a[1], b[0] - b[1])
    True
    >>> nonlinearity_tilt_bias(sf, p, 40.0, 0.1, 1, 1)
    0.0
    """
    a_k, b_k = scale_factor_round_coupling(scale_factor_rows, protocol, latitude_deg, tilt_deg,
                                           accel_dps2)
    if a_k.size == 0:
        return 0.0
    return float(math.hypot(float(a_k[i_max] - a_k[i_min]), float(b_k[i_max] - b_k[i_min])))


def table_error_coefficients(theta_deg: float, stops_deg) -> dict:
    """Sensitivities of E_i at the 7.4 point ``theta_deg`` to the table's positioning error
    at each distinct table position (° mod 360, rounded to 1e-6°): {position: c}.

    The table turns from its zero to θ with error P(θ) − P(0) (A.4.1); the 7.1 K is the mean
    of C_k/θ_k over the stops θ_k (n of them), so K/K_true − 1 ≈ (1/n) Σ (P(θ_k) − P(0))/θ_k
    (7.1), and E_i = C_i/K − θ_i ≈ (P(θ_i) − P(0)) − (θ_i/n) Σ (P(θ_k) − P(0))/θ_k. A position
    the table reaches twice (a stop that is also the point, 360° that is 0°) has one error,
    so its coefficients add (at 360° the point's own term cancels: P(360°) = P(0)). Angles
    keep their sign (a counter-clockwise point or stop is negative): the table's position is
    θ mod 360 (−60° is the position 300°), and θ_i/θ_k keeps its sign.

    >>> c = table_error_coefficients(360.0, [60.0, 120.0, 180.0, 240.0, 300.0, 360.0])
    >>> [round(float(c[p]), 4) for p in (0.0, 60.0, 300.0)], 360.0 in c
    ([2.2833, -1.0, -0.2], False)

    A counter-clockwise point at −60° with clockwise stops: its position is 300°, a stop's
    position, so the two coefficients add there (1 − (−60)/(6·300)); 60° is only a stop:

    >>> c = table_error_coefficients(-60.0, [60.0, 120.0, 180.0, 240.0, 300.0, 360.0])
    >>> [round(float(c[p]), 4) for p in (60.0, 300.0)]
    [0.1667, 1.0333]
    """
    theta = float(theta_deg)
    stops = np.asarray(stops_deg, dtype=float)
    n = stops.size
    out: dict = {}

    def add(pos: float, c: float) -> None:
        key = position_key(pos)
        out[key] = out.get(key, 0.0) + c

    add(theta, 1.0)
    add(0.0, -1.0)
    for th_k in stops:
        add(th_k, -theta / (n * th_k))
        add(0.0, theta / (n * th_k))
    return out


def table_line_u(theta_deg: float, stops_deg, u_position_arcsec: float) -> float:
    """u of E_i from the table's positioning errors at the point, the common zero and the 7.1
    stops together (:func:`table_error_coefficients`), each position's error independent of
    the others' with u = ``u_position_arcsec`` (A.4.1: MPE/√3): u·√(Σ c²). One line in place
    of Annex A's P (at every point the same) and the stops' ``K_P``, which treat P(0) in the
    point and in K as unrelated and P(360°) as another position than P(0).

    >>> round(table_line_u(360.0, [60.0, 120.0, 180.0, 240.0, 300.0, 360.0], 1.0), 4)
    2.584
    >>> round(table_line_u(30.0, [60.0, 120.0, 180.0, 240.0, 300.0, 360.0], 1.0), 4)
    1.2907
    """
    c = np.array(list(table_error_coefficients(theta_deg, stops_deg).values()))
    return float(u_position_arcsec * math.sqrt(float(np.sum(c * c))))


def table_harmonic_line_u(theta_deg: float, stops_deg, mpe_arcsec: float,
                          max_order: int = 360) -> dict:
    """Beside the standard's reading (:func:`table_line_u`, each position independent, u =
    MPE/√3, A.4.1): u of E_i at the 7.4 point ``theta_deg`` for a table whose error curve is
    one periodic error P(x) = a·sin(h·x + φ) of unknown order h (1 … ``max_order``), phase
    φ uniform and size a uniform in [0, MPE] (A.4.1 bounds |P| ≤ MPE; the laboratory knows
    the bound, not the shape). The curve is one function: a point's error, the zero's and
    the 7.1 stops' are correlated (P(360°) = P(0)). With the coefficients c_p of
    :func:`table_error_coefficients`, E_i's table error is a·Im(e^{iφ} Σ c_p e^{ihp}), so
    u² = (MPE²/3)·|Σ c_p e^{ihp}|²/2 at the worst order h (the largest). Returned:
    ``u_arcsec``, ``order`` (that h) and ``half_width_at_bound_arcsec`` (a = MPE: the
    error is arcsine with that half-width, MPE·|Σ c_p e^{ihp}|). The search over orders is
    :mod:`gonio.specs.ogam_draft.table_periodic`'s (shared with K and K_l).

    At 360° with the built-in 7.1 stops the worst order is 3 (u 0.125″ for MPE 0.1″, the
    standard's reading 0.149″); at 30° it is 6 (0.082″ against 0.075″): the harmonic
    model is not narrower than the standard's at every point.

    >>> s = [60.0, 120.0, 180.0, 240.0, 300.0, 360.0]
    >>> [(round(d["u_arcsec"], 4), d["order"]) for d in
    ...  (table_harmonic_line_u(t, s, 0.1) for t in (30.0, 360.0))]
    [(0.0816, 6), (0.1252, 3)]
    """
    c = table_error_coefficients(theta_deg, stops_deg)
    pos_deg = np.array(list(c.keys()), dtype=float)
    cv = np.array(list(c.values()), dtype=float)
    g = np.abs(periodic_response(pos_deg, max_order) @ cv)   # |Σ c_p e^{ihp}| per order
    order = worst_order(g)
    return {"u_arcsec": float(mpe_arcsec * g[order - 1] / math.sqrt(6.0)), "order": order,
            "half_width_at_bound_arcsec": float(mpe_arcsec * g[order - 1])}


def budget_extra_components(readings: pd.DataFrame, protocol: Protocol, latitude_deg: float,
                            repeatability_arcsec: float, *,
                            truth: str = "systematic",
                            accel_dps2: float = 60.0, theta_deg: float | None = None,
                            sf_reading_u_arcsec=None) -> list[ExtraComponent]:
    """Budget lines the Annex A budget lacks, from the calibration's data and the annex's bounds.

    E_i uses the K of 7.1; an error δK of that K gives −θ·δK/K at point θ, the same in
    every series (so u(r) does not see it). With 7.1 rounds θ_k (n of them) and the
    7.4 points up to θ_max, an error e_k of round k moves E at θ by
    −θ/n · e_k/θ_k (draft 7.1: K = mean C_k/θ_k). Three terms, at θ_max:

    ``K_P`` (normal, u)
        the table error at the 7.1 stops and at the common zero, independent,
        u(P) = MPE/√3 (A.4.1): u = θ_max/n · u(P) · √(Σ 1/θ_k² + (Σ 1/θ_k)²).
    ``K_r`` (normal, u)
        the scatter of each single 7.1 reading, taken as u(r) (A.4.4):
        u = θ_max/n · u(r) · √(Σ 1/θ_k²).
    ``tilt_E`` (arcsine, amplitude A)
        the tilt × Earth-rate coupling, ψ = the A.1 tilt bound, azimuth α unknown
        (uniform, so the error, a sinusoid in α, is arcsine distributed):
        e_i(α) = Ω_⊥ sin ψ (C_i cos α − S_i sin α) (:func:`tilt_coupling_coefficients`),
        through K: −θ_i mean_k(e_k/θ_k). With ``truth="systematic"`` (deviation as
        mounted, e_i is in the truth) only the K part counts; with ``"intrinsic"``
        both. A = max_i of the amplitude over α.

    Examples
    --------
    >>> from gonio.specs.ogam_draft.protocol import load_protocol
    >>> from gonio.specs import DEFAULT_KEY, get
    >>> p = load_protocol(get(DEFAULT_KEY).default_protocol)
    >>> df = pd.DataFrame({"test": ["scale_factor"] * 6 + ["angle_deviation"] * 2,
    ...     "table_deg": [60.0, 120.0, 180.0, 240.0, 300.0, 360.0, 180.0, 360.0],
    ...     "time_s": [11.0, 12.0, 13.0, 14.0, 15.0, 16.0, 13.0, 16.0]})
    >>> [(c.symbol, round(c.half_width_arcsec, 4))
    ...  for c in budget_extra_components(df, p, 40.0, 0.1, truth="intrinsic")]
    [('K_P', 0.158), ('K_r', 0.1221), ('tilt_E', 0.4915)]

    ``theta_deg``: the point θ at which ``K_P`` and ``K_r`` are given (θ/n in place of
    θ_max/n: an error δK shared by the points moves E_i by θ_i·δK/K, so the lines grow
    with the point's angle); None: θ_max, the largest point. ``sf_reading_u_arcsec``: u of
    each single 7.1 reading (an array in the rows' order, or one number) for ``K_r``; None:
    u(r) for every reading. At θ = 90° the two lines are a quarter of θ_max's:

    >>> [round(c.half_width_arcsec, 4) for c in
    ...  budget_extra_components(df, p, 40.0, 0.1, theta_deg=90.0)[:2]]
    [0.0395, 0.0305]

    With instant starts and stops (the constant-rate model) tilt_E is 5 % larger:

    >>> round(budget_extra_components(df, p, 40.0, 0.1, truth="intrinsic",
    ...                               accel_dps2=1e9)[2].half_width_arcsec, 4)
    0.5169
    """
    sf = readings[readings["test"] == "scale_factor"]
    ad = readings[readings["test"] == "angle_deviation"]
    th_k = np.abs(sf["table_deg"].to_numpy(dtype=float))
    t_k = sf["time_s"].to_numpy(dtype=float)
    n = th_k.size
    th_i = np.abs(ad["table_deg"].to_numpy(dtype=float))
    t_i = ad["time_s"].to_numpy(dtype=float)
    theta_max = float(np.max(th_i))
    u_p = protocol.annex_a.table_mpe_arcsec / math.sqrt(3.0)
    amp = (theta_max if theta_deg is None else abs(float(theta_deg))) / n
    u_kp = amp * u_p * math.sqrt(np.sum(1.0 / th_k ** 2) + np.sum(1.0 / th_k) ** 2)
    u_read = np.broadcast_to(np.asarray(repeatability_arcsec if sf_reading_u_arcsec is None
                                        else sf_reading_u_arcsec, dtype=float), th_k.shape)
    u_kr = amp * math.sqrt(np.sum((u_read / th_k) ** 2))
    omega = dps_to_arcsec_s(earth_rate_split(latitude_deg, protocol.angle_deviation.orientation)
                            .perpendicular_dps) * math.sin(math.radians(protocol.annex_a.tilt_bound_deg))
    sfi, adi = protocol.scale_factor, protocol.angle_deviation
    ck, sk = tilt_coupling_coefficients(th_k, t_k, sfi.rate_dps, sfi.read_delay_s, accel_dps2)
    ci, si = tilt_coupling_coefficients(th_i, t_i, adi.rate_dps, adi.read_delay_s, accel_dps2)
    mc, ms = float(np.mean(ck / th_k)), float(np.mean(sk / th_k))
    keep = 0.0 if truth == "systematic" else 1.0
    a_tilt = omega * float(np.max(np.hypot(keep * ci - th_i * mc, keep * si - th_i * ms)))
    return [
        ExtraComponent("K_P", "table error at the 7.1 stops -> dK*theta (validation)",
                       float(u_kp), "normal"),
        ExtraComponent("K_r", "scatter of the 7.1 readings -> dK*theta (validation)",
                       float(u_kr), "normal"),
        ExtraComponent("tilt_E", "tilt x Earth-rate coupling to the reading (validation)",
                       float(a_tilt), "arcsine"),
    ]
