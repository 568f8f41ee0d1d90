"""In-situ estimate of the sensing-axis tilt from a static multi-position test.

Contents
--------
:class:`~gonio.specs.ogam_draft.protocol.TiltEstimatePlan` the ``[tilt_estimate]`` protocol section (defined in the protocol layer)
:func:`fit_first_harmonic`         LS fit c0 + a cos θ + b sin θ with its residual-based covariance
:func:`estimate_tilt`              ψ, α and their standard uncertainties from rates at positions
:func:`tilt_estimate_from_readings` the same from ``tilt_estimate`` rows of a readings file

Physics (``docs/draft-readings.md#tilt-and-earth-rate-coupling``; :mod:`gonio.physics.kinematics`).
A rate gyro whose sensing axis n is tilted by ψ from the table axis a senses, with
the table at rest at angle θ,

    ω_s(θ) = b + cos ψ (Ω·a) + sin ψ · Ω_⊥ cos(θ + α − β)

(b the bias, Ω_⊥ the Earth rate across the table axis, β its direction and α the
tilt's azimuth in the table frame). Resting at N ≥ 4 equally spaced positions and
averaging the rate at each shows that first harmonic: its amplitude is Ω_⊥ sin ψ,
its phase α − β. A least-squares fit of c0 + a cos θ + b sin θ (design matrix
``X = [1, cos θ, sin θ]``) with the residual-based covariance s²(XᵀX)⁻¹,
s² = RSS/(N − 3) (JCGM 100 H.3; any LS textbook), gives

    ψ = asin(hypot(a, b) / Ω_⊥),       α − β = atan2(−b, a)

and their standard uncertainties by the law of propagation (JCGM 100 5.1.2), with
ν = N − 3 degrees of freedom (use the Student-t factor ``k95`` for a 95 %
interval). The laboratory can then replace the draft's assumed tilt bound of 0.1°
(Annex A.1, A.4.2) with a measured ψ and u(ψ), and the coupling analysis of
:mod:`gonio.specs.ogam_draft.coupling` with a measured α.

Caveats: the estimate sees the tilt of the sensing axis relative to the axis about
which the table actually turns; a table-axis wobble with the same period adds a
first harmonic of the same form (amplitude w·Ω_⊥) and is included in the
estimate. Near Ω_⊥ = 0 (table axis parallel to the Earth's axis) the test has no
signal. Counts are converted with the scale factor given (7.1's or the nominal
one); a 7.1 scale factor already holds cos ψ (rigid-body reading of A.4.2), which
changes the amplitude by the factor 1/cos ψ (1.5×10⁻⁶ at 0.1°, ignored).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from gonio.physics.earth import earth_rate_split
from gonio.errors import GonioError
from gonio.units import ARCSEC_PER_DEG





#: How a fit's uncertainty was found (:func:`fit_first_harmonic`).
BASIS_PAIRS = "opposite pairs"
BASIS_RESIDUALS = "residuals"
#: Two positions are opposite when they differ by 180° within this, degrees.
OPPOSITE_TOL_DEG = 1e-6


@dataclass(frozen=True)
class HarmonicFit:
    """c0 + a cos θ + b sin θ: coefficients (input unit), covariance, residuals."""

    coef: np.ndarray            # (c0, a, b)
    cov: np.ndarray             # 3×3 (see fit_first_harmonic for its basis)
    residual_sd: float          # s, the scale the covariance of (a, b) is drawn from
    dof: int                    # its degrees of freedom: N/2 − 2 (pairs) or N − 3
    fitted: np.ndarray
    residuals: np.ndarray
    basis: str = BASIS_RESIDUALS
    #: indices (in the order taken) of rests left out of the fit: in the pairs' basis, the
    #: rests outside a complete opposite pair (their partner set aside by screening)
    left_out: tuple[int, ...] = ()


def opposite_pair_split(theta_deg) -> tuple[list[tuple[int, int]], list[int]]:
    """The complete opposite pairs among rests taken in the order ``theta_deg`` and the rests
    outside one: read in order, a rest and the next one 180° away (``OPPOSITE_TOL_DEG``)
    form a pair; a rest whose next one is not opposite stands alone (its partner missing,
    as where screening set one aside, or another order).

    >>> opposite_pair_split([0, 180, 30, 210, 60, 240, 270, 120, 300])
    ([(0, 1), (2, 3), (4, 5), (7, 8)], [6])
    >>> opposite_pair_split(np.arange(4) * 90.0)
    ([], [0, 1, 2, 3])
    """
    th = np.asarray(theta_deg, dtype=float)
    pairs, lone, i = [], [], 0
    while i < th.size:
        if i + 1 < th.size and abs((th[i + 1] - th[i]) % 360.0 - 180.0) <= OPPOSITE_TOL_DEG:
            pairs.append((i, i + 1))
            i += 2
        else:
            lone.append(i)
            i += 1
    return pairs, lone


def fit_first_harmonic(theta_deg, y) -> HarmonicFit:
    """Least-squares fit of y = c0 + a cos θ + b sin θ and the covariance of (a, b), the
    positions ``theta_deg`` and the rates ``y`` in the order the rests were taken.

    The coefficients are the least-squares ones. Their uncertainty is the one documented
    choice of this estimate (the draft has no such test):

    * **opposite pairs** (at least three complete pairs in the order taken,
      :func:`opposite_pair_split`; the order the programme takes): the
      difference within pair m, d_m = y(θ_m) − y(θ_m + 180°) = 2(a cos θ_m + b sin θ_m)
      + e_m, holds the first harmonic twice and, the two rests being one dwell apart, the
      bias's slow wander (drift, Gauss–Markov instability, rate random walk) hardly at all;
      the pair sums hold c0 and that wander. The least-squares (a, b) are those of the d_m
      alone (the sums and differences are an orthogonal split of the data), so
      s² = Σ r_m² / (2(M − 2)) over the M pairs' residuals r_m gives Σ_ab = s²[(XᵀX)⁻¹]_ab
      with ν = M − 2; c0's variance is drawn from the sums' scatter (M − 1 degrees of
      freedom), which holds the wander. A rest outside a complete pair (its partner set
      aside by screening) is left out of the fit (``left_out``): in it the wander is not
      cancelled, and the pairs' covariance would not describe a fit that holds it.
    * **residuals** (any other order): s² = RSS/(N − 3), ν = N − 3 (JCGM 100 H.3 for the
      straight-line analogue), which assumes the rests' errors uncorrelated. Rests taken in
      order of θ under a bias correlated over several dwells put the wander into the first
      harmonic while the residuals see its average: on the virtual RLG bench (Gauss–Markov
      instability, τ = 300 s, rests 125 s apart) the 95 % intervals held the truth in 91 %
      of 300 draws (``docs/draft-readings.md``, in-situ tilt estimate).

    Needs N ≥ 4 positions spread over the circle (N = 3 leaves no degree of freedom).

    Examples
    --------
    >>> th = np.arange(4) * 90.0
    >>> f = fit_first_harmonic(th, [3.1, 2.0, 0.9, 2.0])   # 2 + 1.1 cos θ, plus nothing
    >>> (f.coef.round(12) + 0.0).tolist(), f.dof, round(f.residual_sd, 12), f.basis
    ([2.0, 1.1, 0.0], 1, 0.0, 'residuals')
    >>> th = [0, 180, 60, 240, 120, 300]                    # three opposite pairs
    >>> y = 2 + 1.1 * np.cos(np.radians(th)) + np.array([0.3, 0.3, 0.0, 0.0, -0.3, -0.3])
    >>> f = fit_first_harmonic(th, y)                      # a wander the pairs cancel
    >>> (f.coef.round(12) + 0.0).tolist(), f.dof, round(f.residual_sd, 12), f.basis
    ([2.0, 1.1, 0.0], 1, 0.0, 'opposite pairs')
    >>> th = [0, 180, 60, 240, 120, 300, 90]                # and one rest without its partner
    >>> f = fit_first_harmonic(th, 2 + 1.1 * np.cos(np.radians(th)) + np.r_[0.3, 0.3, 0, 0, -0.3, -0.3, 5.0])
    >>> (f.coef.round(12) + 0.0).tolist(), f.dof, f.basis, f.left_out
    ([2.0, 1.1, 0.0], 1, 'opposite pairs', (6,))
    """
    th = np.radians(np.asarray(theta_deg, dtype=float))
    y = np.asarray(y, dtype=float)
    if th.shape != y.shape or th.ndim != 1:
        raise GonioError("positions and rates must be 1-D arrays of the same length")
    if th.size < 4:
        raise GonioError(f"the tilt estimate needs at least 4 positions, got {th.size}")
    if not (np.all(np.isfinite(th)) and np.all(np.isfinite(y))):
        raise GonioError("positions and rates must be finite numbers")
    x = np.column_stack([np.ones_like(th), np.cos(th), np.sin(th)])
    pairs, lone = opposite_pair_split(np.degrees(th))
    paired = len(pairs) >= 3
    used = np.array(sorted(i for p in pairs for i in p)) if paired else np.arange(th.size)
    xtx = x[used].T @ x[used]
    if np.linalg.cond(xtx) > 1e10:
        raise GonioError("positions do not determine a first harmonic (spread them over 360°)")
    coef = np.linalg.solve(xtx, x[used].T @ y[used])
    fitted = x @ coef
    res = y - fitted
    inv = np.linalg.inv(xtx)
    if not paired:
        dof = th.size - 3
        s2 = float(res @ res) / dof
        return HarmonicFit(coef, s2 * inv, math.sqrt(s2), dof, fitted, res)
    first, second = (np.array([p[k] for p in pairs]) for k in (0, 1))
    m = len(pairs)
    r_d = res[first] - res[second]              # residuals of the pair differences
    dof = m - 2
    s2 = float(r_d @ r_d) / (2.0 * dof)
    r_s = res[first] + res[second]              # of the pair sums (mean zero: c0 fitted)
    cov = s2 * inv
    cov[0, :] = cov[:, 0] = 0.0
    cov[0, 0] = float(r_s @ r_s) / (2.0 * (m - 1)) / (2 * m)
    return HarmonicFit(coef, cov, math.sqrt(s2), dof, fitted, res, BASIS_PAIRS, tuple(lone))


@dataclass
class TiltEstimate:
    """Result of the in-situ tilt estimate (see :func:`estimate_tilt`)."""

    orientation: str
    latitude_deg: float
    n_positions: int
    perpendicular_arcsec_s: float       # Ω_⊥
    offset_arcsec_s: float              # c0 = bias + cos ψ Ω·a
    amplitude_arcsec_s: float           # Ω_⊥ sin ψ
    u_amplitude_arcsec_s: float
    tilt_deg: float                     # ψ
    u_tilt_deg: float
    phase_deg: float                    # α − β: tilt azimuth relative to Ω_⊥, at table 0°
    u_phase_deg: float
    tilt_azimuth_table_deg: float       # α in the table frame e₁, e₂ of gonio.physics.kinematics
    dof: int
    k95: float                          # Student-t factor for 95 % with ν = dof
    residual_sd_arcsec_s: float
    table: pd.DataFrame = field(repr=False, default_factory=pd.DataFrame)   # in the order taken
    basis: str = BASIS_RESIDUALS        # how u was found (fit_first_harmonic)
    #: table positions of the rests left out of the fit (outside a complete opposite pair)
    left_out_deg: tuple[float, ...] = ()
    #: the first-harmonic fit ψ and α come from (its covariance: K's correction takes it)
    fit: HarmonicFit | None = field(repr=False, default=None)

    def to_dict(self) -> dict:
        """Plain dict (for ``--json``)."""
        d = {k: v for k, v in self.__dict__.items() if k not in ("table", "fit")}
        d["U95_tilt_deg"] = self.k95 * self.u_tilt_deg
        d["positions"] = [{k: (bool(v) if isinstance(v, (bool, np.bool_)) else
                               float(v) if isinstance(v, (float, np.floating)) else int(v))
                           for k, v in r.items()} for r in self.table.to_dict("records")]
        return d


def estimate_tilt(theta_deg, rate_arcsec_s, latitude_deg: float, orientation: str = "up",
                  u_latitude_deg: float = 0.0, rounds=None) -> TiltEstimate:
    """ψ and α with standard uncertainties from mean rates at rest positions.

    Parameters
    ----------
    theta_deg : array
        Table positions in the order the rests were taken, degrees (N ≥ 4, best equally
        spaced over 360° and taken in opposite pairs: :func:`fit_first_harmonic`).
    rate_arcsec_s : array
        Mean sensed rate at each position, ″/s (uncompensated: the Earth rate is the signal).
    latitude_deg, orientation : float, str
        Site latitude and table-axis direction; they give Ω_⊥ and its direction β.
    u_latitude_deg : float
        Standard uncertainty of the latitude (enters through Ω_⊥).
    rounds : array, optional
        The rests' round numbers as the readings give them (the table's ``round``; default
        1…N): a rest set aside keeps its neighbours' numbers.

    Returns
    -------
    TiltEstimate
        ψ = asin(A/Ω_⊥), A = hypot(a, b); α − β = atan2(−b, a) (module docstring);
        u by the law of propagation on the fit covariance (JCGM 100 5.1.2), ν and the
        covariance's basis those of :func:`fit_first_harmonic`.

    Examples
    --------
    Axis up at 40° N: Ω_⊥ = 11.5221″/s. A tilt of 0.1° at α − β = 30° gives the
    harmonic 0.020110 cos(θ + 30°) ″/s on top of the 9.668″/s offset:

    >>> th = np.arange(8) * 45.0
    >>> amp = 11.522126 * math.sin(math.radians(0.1))
    >>> y = 9.668 + amp * np.cos(np.radians(th + 30.0))
    >>> e = estimate_tilt(th, y, 40.0, "up")
    >>> round(e.amplitude_arcsec_s, 6), round(e.tilt_deg, 6), round(e.phase_deg, 6)
    (0.02011, 0.1, 30.0)
    """
    th = np.asarray(theta_deg, dtype=float)
    fit = fit_first_harmonic(th, rate_arcsec_s)
    perp = earth_rate_split(latitude_deg, orientation).perpendicular_dps * ARCSEC_PER_DEG
    if perp < 1e-3:
        raise GonioError(f"the table axis ({orientation}) is parallel to the Earth's axis at "
                         f"latitude {latitude_deg}°: no Earth rate across it, no tilt signal")
    c0, a, b = fit.coef
    amp = math.hypot(a, b)
    if amp >= perp:
        raise GonioError(f"first-harmonic amplitude {amp:.4g}″/s exceeds Ω_⊥ = {perp:.4g}″/s: "
                         "not a tilt (check scale factor, latitude and orientation)")
    cab = fit.cov[1:, 1:]
    if amp > 0:
        j_amp = np.array([a, b]) / amp
        j_ph = np.array([b, -a]) / amp ** 2
        u_amp = math.sqrt(float(j_amp @ cab @ j_amp))
        u_ph = math.sqrt(float(j_ph @ cab @ j_ph))
    else:
        u_amp, u_ph = math.sqrt(float(np.trace(cab)) / 2.0), math.pi
    psi = math.asin(amp / perp)
    # Ω_⊥ through the latitude: numerical derivative (central difference, 1e-4°).
    h = 1e-4
    lo, hi = max(-90.0, latitude_deg - h), min(90.0, latitude_deg + h)
    dperp = ((earth_rate_split(hi, orientation).perpendicular_dps
              - earth_rate_split(lo, orientation).perpendicular_dps) * ARCSEC_PER_DEG
             / math.radians(hi - lo))
    u_perp = abs(dperp) * math.radians(u_latitude_deg)
    cpsi = math.cos(psi)
    u_psi = math.hypot(u_amp / (perp * cpsi), amp / (perp ** 2 * cpsi) * u_perp)
    gamma = math.atan2(-b, a)
    beta = _perp_direction_rad(latitude_deg, orientation)
    from scipy.stats import t as student_t

    in_fit = np.ones(th.size, dtype=bool)
    in_fit[list(fit.left_out)] = False
    table = pd.DataFrame({"round": (np.arange(1, th.size + 1) if rounds is None
                                    else np.asarray(rounds, dtype=int)), "table_deg": th,
                          "rate_arcsec_s": np.asarray(rate_arcsec_s, dtype=float),
                          "fitted_arcsec_s": fit.fitted, "residual_arcsec_s": fit.residuals,
                          "in_fit": in_fit})
    return TiltEstimate(
        orientation=orientation, latitude_deg=float(latitude_deg), n_positions=int(th.size),
        perpendicular_arcsec_s=perp, offset_arcsec_s=float(c0), amplitude_arcsec_s=amp,
        u_amplitude_arcsec_s=u_amp, tilt_deg=math.degrees(psi), u_tilt_deg=math.degrees(u_psi),
        phase_deg=math.degrees(gamma), u_phase_deg=math.degrees(u_ph),
        tilt_azimuth_table_deg=(math.degrees(gamma + beta) + 180.0) % 360.0 - 180.0,
        dof=fit.dof, k95=float(student_t.ppf(0.975, fit.dof)),
        residual_sd_arcsec_s=fit.residual_sd, table=table, basis=fit.basis,
        left_out_deg=tuple(float(th[i]) for i in fit.left_out), fit=fit)


def _perp_direction_rad(latitude_deg: float, orientation: str) -> float:
    """β: direction of Ω_⊥ in the table frame (e₁, e₂ of :func:`gonio.physics.kinematics.sensing_axis_basis`)."""
    return math.radians(earth_rate_split(latitude_deg, orientation).perpendicular_direction_deg)


def tilt_estimate_from_readings(readings, scale_factor_counts_per_deg: float | None = None,
                                latitude_deg: float | None = None,
                                u_latitude_deg: float = 0.0) -> TiltEstimate:
    """The tilt estimate from the ``tilt_estimate`` rows of a readings file.

    Rate at each position = gyro_counts / (K · time_s) (or gyro_deg / time_s), ″/s;
    K from the argument, else the file's ``nominal_scale_factor_counts_per_deg``;
    latitude from the argument, else the file's ``latitude_deg``. Rows must share
    one orientation and one series; they are taken in the order of ``round`` (the order the
    rests were taken, whatever the file's row order), each round once.

    Parameters
    ----------
    readings : gonio.specs.ogam_draft.readings.Readings or pandas.DataFrame
    scale_factor_counts_per_deg, latitude_deg, u_latitude_deg : float, optional

    Examples
    --------
    >>> df = pd.DataFrame({"test": ["tilt_estimate"] * 4, "series": [1] * 4,
    ...     "round": [1, 2, 3, 4], "orientation": ["up"] * 4, "time_s": [10.0] * 4,
    ...     "table_deg": [0.0, 90.0, 180.0, 270.0],
    ...     "gyro_counts": [1004.0, 1000.0, 996.0, 1000.0]})
    >>> e = tilt_estimate_from_readings(df, 3600.0, 40.0)   # 1 count = 1″: 0.4″/s amplitude
    >>> round(e.amplitude_arcsec_s, 9), round(e.tilt_deg, 4)
    (0.4, 1.9895)
    """
    from gonio.specs.ogam_draft.readings import Readings, metadata_float

    if isinstance(readings, Readings):
        df, md, file = readings.data, readings.metadata, readings.path
    else:
        df, md, file = readings, {}, None
    rows = df[df["test"] == "tilt_estimate"]
    if rows.empty:
        raise GonioError("no tilt_estimate rows in the readings", file=file)
    orients = rows["orientation"].unique() if "orientation" in rows else np.array(["up"])
    if len(orients) != 1 or rows["series"].nunique() != 1:
        raise GonioError("tilt_estimate rows must share one orientation and one series "
                         f"(found orientations {sorted(map(str, orients))}, series "
                         f"{sorted(rows['series'].unique().tolist())})", file=file)
    if rows["round"].duplicated().any():
        dup = sorted(int(r) for r in rows.loc[rows["round"].duplicated(), "round"].unique())
        raise GonioError(f"tilt_estimate rounds {dup} appear more than once (one rest per "
                         "round)", file=file, key="round")
    rows = rows.sort_values("round", kind="stable")
    if latitude_deg is None:
        latitude_deg = metadata_float(md, "latitude_deg", file=file)
        if latitude_deg is None:
            raise GonioError("no latitude: give it or put latitude_deg in the file's metadata",
                             file=file, key="latitude_deg")
    t = rows["time_s"].to_numpy(dtype=float)
    if np.any(~(t > 0)):
        raise GonioError("tilt_estimate rows need time_s > 0 (the dwell time)", file=file,
                         key="time_s")
    gdeg = rows["gyro_deg"].to_numpy(dtype=float) if "gyro_deg" in rows else np.full(t.size, np.nan)
    counts = rows["gyro_counts"].to_numpy(dtype=float) if "gyro_counts" in rows \
        else np.full(t.size, np.nan)
    if np.any(np.isnan(gdeg)):
        k = scale_factor_counts_per_deg
        if k is None:
            k = metadata_float(md, "nominal_scale_factor_counts_per_deg", file=file)
        if k is None:
            raise GonioError("counts need a scale factor: give it or put "
                             "nominal_scale_factor_counts_per_deg in the metadata", file=file)
        gdeg = np.where(np.isnan(gdeg), counts / k, gdeg)
    rate = gdeg / t * ARCSEC_PER_DEG
    return estimate_tilt(rows["table_deg"].to_numpy(dtype=float), rate, float(latitude_deg),
                         str(orients[0]), u_latitude_deg, rows["round"].to_numpy(dtype=int))
