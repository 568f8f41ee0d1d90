"""The optical draft's coverage study: its Annex A budget against the truth of many virtual
calibrations (``gonio validate --spec ogam-draft``; ``SPEC.coverage.study``).

This module describes the study (its trial, budget, truths, estimators and bench cases) and
summarises it; the generic engine of :mod:`gonio.pipeline.validate` runs it (batches, joblib
or Dask, partial results and resume, seeding by trial index). The protocol it follows is
:func:`plan_study` → :class:`OpticalStudy` (``settings``, ``jobs``, ``unpack``, ``report``),
documented in docs/writing-a-specification.md.

Contents
--------
:func:`validation_protocol`   the draft's protocol restricted to what E and U need (7.1, 7.4/7.5)
:data:`CASES`, :func:`case_bench`   the default bench and the named stress cases
:func:`run_trial`             one virtual calibration: E_ij, E_i, truth, U (Annex A)
:func:`gonio.specs.ogam_draft.budget_extra.budget_extra_components` (used here) extra budget lines the annex lacks (off by default)
:func:`plan_study`            the study's settings and jobs; :class:`ValidationReport` its report
:func:`gonio.analysis.coverage.coverage`, :func:`~gonio.analysis.coverage.binomial_u` coverage
                              fraction and its uncertainty

The question asked: a calibration on the virtual bench states, at each
calibration point i, E_i (mean over the 10 series of 7.4/7.5, as
:mod:`gonio.specs.ogam_draft.items` computes it) with the expanded uncertainty U of Annex A
(k = 2, u(r) from the calibration's own 7.5 data). How often is |E_i − truth_i| ≤ U?
Also for each single series E_ij, which is what the Annex A budget (u(r) of a single
reading) actually describes. A budget that holds covers ≈ 95 % or more.

Truth definitions (all from the bench's noise-free rerun, :func:`gonio.specs.ogam_draft.bench.run_session`):

``systematic`` (default)
    ``systematic_deviation_arcsec``: noise-free indicated angle through the mount's true
    scale factor minus the true table angle; the instrument's real deviation *as mounted*
    (the tilt × Earth-rate coupling and any warm-up drift are part of it).
``calibrated``
    ``systematic_deviation_calibrated_arcsec``: the same with the K the noise-free 7.1
    gives (table and tilt errors of 7.1 included in the truth).
``intrinsic``
    the deviation the same instrument shows on an ideal set-up (no tilt, no Earth rate,
    no bias or drift, error-free table): what a certificate is about; everything the
    set-up adds is an error of the calibration.

Sample rate: the validation runs the bench at 100 Hz by default instead of the
bench file's 1 kHz. The RLG counter integrates the table term in closed form and the
smooth terms by the trapezoid rule, so the counts at the readings do not depend on the
rate (the noise is drawn per sample with the right variance at any rate); 100 Hz keeps
200 trials under two minutes on two cores. The rate is the simulation's, not the
instrument's: a FOG, which integrates its rate by rectangles at its own rate (the bench
file's), keeps that integration (:func:`study_bench`; at a study rate below it, its
accumulated angle is integrated exactly, leaving out the rectangle residual at its own rate,
≤ a·h²/4 = 0.054″ at 60 °/s² and 1 kHz).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

from gonio import __version__
from gonio.analysis.coverage import coverage, spawn_seed
from gonio.specs.ogam_draft.bench import Bench, TableConfig, load_bench, run_session
from gonio.specs.ogam_draft.bench.config import Harmonic
from gonio.specs.ogam_draft.bench.session import session_metadata
from gonio.specs.ogam_draft.budget_extra import EXTRA_SYMBOLS, budget_extra_components
from gonio.errors import GonioError
from gonio.specs.ogam_draft.readings import Readings
from gonio.formats.toml import read_toml
from gonio.limits import check
from gonio.specs.ogam_draft.protocol import Protocol, parse_protocol
from gonio.resources import resolve
from gonio.specs.ogam_draft.budget import annex_a_budget
from gonio.specs.ogam_draft.calibration import analyse, temperature_coeff_bound
from gonio.specs.ogam_draft.item_coverage import item_coverage, trial_items
from gonio.units import PPM, deg_to_arcsec

__all__ = ["CASES", "TRUTHS", "validation_protocol", "case_bench", "ideal_bench", "run_trial",
           "TrialResult", "budget_extra_components", "plan_study", "OpticalStudy",
           "ValidationReport", "trial_seeds", "trial_seed", "TrialJob", "trial_bench",
           "pack_trials", "unpack_trials", "EXTRA_SYMBOLS", "draw_type_b", "worst_azimuth",
           "worst_condition",
           "coupling_bias", "tilted", "TABLE_RATE_ERROR_BOUND", "TABLE_CALIBRATION_U_ARCSEC",
           "table_positions_deg", "drawn_table_calibration", "case_table_calibration",
           "drawn_table_curve", "corner_table", "worst_harmonic_table", "TABLE_CURVE_MAX_ORDER",
           "TABLE_GRADUATION_ARCSEC"]

#: Stress cases: name → what is changed (see :func:`case_bench`).
CASES = {
    "default": "the bench as loaded (inside the budget's assumptions)",
    "tilt": "sensing plane tilted at the Annex A.1 bound (tilt_deg = annex_a.tilt_bound_deg)",
    "drift": "Gauss-Markov bias instability sigma = 0.005/sqrt(2) deg/h, tau = 300 s: the "
             "bias change since the Earth-rate compensation has an RMS of 0.005 deg/h (A.4.3 bound)",
    "table": "table positioning harmonics scaled so that sum |a_h| = table MPE (A.4.1 bound), "
             "random scatter off",
    "ideal": "no noise, no tilt, no bias, no harmonics, error-free table (sanity check)",
    "mounted": "each trial's tilt drawn uniformly over the disc psi <= annex_a.tilt_bound_deg "
               "(azimuth uniform): a tilt the laboratory bounds but does not know, so the "
               "budget's tilt terms are exercised, not held at one value",
    "typeb": "every Type B effect of the set-up drawn per trial from what the laboratory "
             "knows of it: the tilt over the A.1 disc (azimuth uniform), the table's "
             "positioning error a random smooth curve (harmonics of orders 1-"
             "6, amplitudes uniform/order, phases uniform, scaled so "
             "that its max |e| over the circle is uniform within the MPE less the scatter's 3 "
             "sigma and the graduation part) plus a small graduation part independent at every "
             "30 deg position (uniform within TABLE_GRADUATION_ARCSEC), its wobble "
             "phase and axis set-up azimuth uniform, its rate error "
             "uniform within Table 1's 1e-5, the chamber's deviation from the reference "
             "temperature uniform within Table 2's tolerance, the gyro's scale-factor "
             "temperature coefficient uniform within the bound K's chamber line takes, its "
             "bias instability uniform within the A.4.3 bound (RMS change <= 0.005 deg/h)",
    "worst": "the worst condition the draft allows for K: tilt at the A.1 bound, at the "
             "azimuth where the tilt x Earth-rate coupling biases the 7.1 K most "
             "(worst_azimuth, from noise-free sessions of the bench); the other Type B "
             "effects (table errors, table rate error, chamber temperature, alpha_K) drawn "
             "per trial as in typeb",
    "worsttable": "the table at its A.4.1 bound, the corner for K: the error at the 7.1 "
                  "rounds' zero at -(MPE less the scatter's 3 sigma) and at every other "
                  "30 deg position at +(that), or the reverse (sign drawn): every round's "
                  "angle off by twice the bound the same way; every other Type B effect "
                  "drawn per trial as in typeb",
    "worstharmonic": "the table's one periodic error at the A.4.1 bound (amplitude the MPE "
                     "less the scatter's 3 sigma) of the order and phase that move the 7.1 K "
                     "most (sign drawn); every other Type B effect drawn per trial as in typeb",
    "worstshape": "the bench's table shape at its A.4.1 bound (amplitudes' sum = the MPE less "
                  "the scatter's 3 sigma, phases drawn; worsttable until 2026-12-01), every "
                  "other Type B effect drawn per trial as in typeb",
    "tablecal": "the draws of typeb with a calibrated table: per trial a table calibration "
                "(table_calibration.py) drawn from the trial bench's true periodic table "
                "error at every position the protocol uses plus normal noise of "
                "u = TABLE_CALIBRATION_U_ARCSEC, as a laboratory's table certificate states "
                "it; K is corrected by it and its table line is the calibration's",
    "tablecalpart": "the draws of typeb with a partial calibration of few degrees of freedom: "
                    "per trial a table calibration drawn as tablecal's at every position the "
                    "protocol uses but TABLE_CALIBRATION_PART_OMIT_DEG (so E keeps its MPE "
                    "line there and C_v, C_g keep theirs), its u a Type A estimate of "
                    "TABLE_CALIBRATION_PART_DOF degrees of freedom (per position u = "
                    "sigma*sqrt(chi2_nu/nu), stated with dof = nu, the error's noise of "
                    "sd sigma = TABLE_CALIBRATION_U_ARCSEC)",
    "tablecaldof": "the draws of typeb with a full calibration of few degrees of freedom: "
                   "per trial tablecalpart's calibration at every position the protocol uses "
                   "(so K_l, C_v and C_g all draw its errors as t of "
                   "TABLE_CALIBRATION_PART_DOF degrees of freedom)",
    "worstcorner": "the worst condition for K at once: the tilt at the A.1 bound at the "
                   "worst azimuth (as worst) and the table at the corner (as worsttable, "
                   "sign drawn); every other Type B effect drawn per trial as in typeb",
}

#: The standard uncertainty of the table calibration the ``tablecal`` case draws, arcsec
#: (a good table certificate, or an equal-division comparison, IEC 62047-20 A.3).
TABLE_CALIBRATION_U_ARCSEC = 0.02
#: The ``tablecalpart`` case's calibration: the position it leaves out (a 7.4/7.6/7.7 point,
#: none of K's 7.1 stops or zeros) and the degrees of freedom of its u (a table certificate
#: from four repeats per position).
TABLE_CALIBRATION_PART_OMIT_DEG = (330.0,)
TABLE_CALIBRATION_PART_DOF = 3.0

#: Cases at one fixed condition chosen as the worst: coverage is their test, not z's spread
#: (a Type B line is one fixed offset there; :func:`item_coverage`'s ``judge_spread``).
FIXED_CONDITION_CASES = ("worst", "worsttable", "worstharmonic", "worstshape", "worstcorner")

#: Table 1's bound on the rate table's relative rate error (the ``typeb`` case draws within it).
TABLE_RATE_ERROR_BOUND = 1e-5


#: Truth definitions (see the module docstring).
TRUTHS = ("systematic", "calibrated", "intrinsic")

_TRUTH_DOC = {
    "systematic": "systematic_deviation_arcsec of the bench truth: noise-free indicated angle "
                  "through the mount's true scale factor minus the true table angle",
    "calibrated": "systematic_deviation_calibrated_arcsec: the same with the K of the "
                  "noise-free rerun's own 7.1 rounds",
    "intrinsic": "systematic_deviation_arcsec of a noise-free session of the same instrument "
                 "on an ideal set-up (no tilt, Earth rate, bias or drift; error-free table)",
}


def validation_protocol(protocol: str = "ogam-draft", all_items: bool = False) -> Protocol:
    """The protocol restricted to what E and U need: 7.1 and 7.4 (10 series, 7.5).

    7.3, 7.6 and 7.7 are dropped (they do not enter E_i or its Annex A budget) unless
    ``all_items`` (then every item's coverage is measured); timings, rests and the
    Earth-rate compensation of the draft are kept. k is the draft's A.7 k = 2 when the
    protocol does not fix it (the criterion of the study).

    >>> p = validation_protocol()
    >>> p.zero_stability is None, p.rate_consistency, p.angle_deviation.series
    (True, (), 10)
    """
    raw = read_toml(resolve(protocol, "protocol"))
    for key in ("zero_stability", "rate_consistency", "pointing_consistency"):
        if not all_items:
            raw.pop(key, None)
    raw.setdefault("annex_a", {}).setdefault("coverage_factor", 2.0)
    if "angle_deviation" not in raw or "scale_factor" not in raw:
        raise GonioError("validation needs scale_factor (7.1) and angle_deviation (7.4) sections",
                         file=str(protocol), key="angle_deviation")
    return parse_protocol(raw, resolve(protocol, "protocol"))


def ideal_bench(bench: Bench) -> Bench:
    """The same instrument (K, nonlinearity, position harmonics) on an ideal set-up.

    No tilt, no Earth rate, no bias or warm-up drift, no noise or quantisation,
    error-free table (same acceleration, so the timings are the same).

    >>> b = ideal_bench(load_bench("rlg"))
    >>> b.instrument.tilt_deg, b.earth_rate, b.table.error_bound_arcsec()
    (0.0, False, 0.0)
    """
    inst = replace(bench.random_off().instrument, tilt_deg=0.0, bias_dph=0.0,
                   warmup_drift_dph=0.0)
    table = TableConfig(accel_dps2=bench.table.accel_dps2, mpe_arcsec=bench.table.mpe_arcsec)
    return replace(bench, instrument=inst, table=table, earth_rate=False)


def case_bench(case: str, bench: Bench, protocol: Protocol) -> Bench:
    """The bench of a named case (see :data:`CASES`).

    >>> p = validation_protocol(); b = load_bench("rlg")
    >>> case_bench("tilt", b, p).instrument.tilt_deg
    0.1
    >>> round(sum(abs(h.amplitude_arcsec)
    ...           for h in case_bench("table", b, p).table.positioning_harmonics), 12)
    0.1
    """
    if case == "default":
        return bench
    if case == "tilt":
        return replace(bench, instrument=replace(bench.instrument,
                                                 tilt_deg=protocol.annex_a.tilt_bound_deg))
    if case == "drift":
        return replace(bench, instrument=replace(bench.instrument,
                                                 bias_instability_dph=0.005 / math.sqrt(2.0),
                                                 bias_instability_tau_s=300.0))
    if case == "table":
        hs = bench.table.positioning_harmonics or (Harmonic(1, 1.0, 0.0),)
        total = sum(abs(h.amplitude_arcsec) for h in hs)
        scale = bench.table.mpe_arcsec / total
        hs = tuple(replace(h, amplitude_arcsec=h.amplitude_arcsec * scale) for h in hs)
        return replace(bench, table=replace(bench.table, positioning_harmonics=hs,
                                            positioning_random_arcsec=0.0))
    if case == "ideal":
        b = ideal_bench(bench)
        return replace(b, instrument=replace(b.instrument, position_harmonics=()),
                       earth_rate=True)
    if case in ("mounted", "typeb", "worsttable", "worstharmonic", "worstshape", "tablecal",
                "tablecalpart", "tablecaldof"):
        return bench                      # drawn per trial (:func:`trial_bench`)
    if case in ("worst", "worstcorner"):  # the other Type B effects drawn per trial
        psi = float(protocol.annex_a.tilt_bound_deg)
        return tilted(bench, psi, worst_azimuth(bench, protocol, psi))
    raise GonioError(f"unknown case {case!r} (known: {', '.join(CASES)})", key="cases")


def tilted(bench: Bench, tilt_deg: float, azimuth_deg: float) -> Bench:
    """``bench`` with its sensing plane tilted by ``tilt_deg`` at ``azimuth_deg``."""
    return replace(bench, instrument=replace(bench.instrument, tilt_deg=float(tilt_deg),
                                             tilt_azimuth_deg=float(azimuth_deg)))


def coupling_bias(bench: Bench, protocol: Protocol) -> float:
    """K of the noise-free rerun's own 7.1 rounds minus K through the mount (counts/°): what
    the set-up (tilt × Earth-rate coupling, angle-position error) does to the 7.1 K without
    noise, from the bench's simulation alone (no budget formula)."""
    tr = run_session(protocol, bench, seed=0).truth
    return float(tr["scale_factor_noise_free_calibrated_counts_per_deg"]
                 - tr["scale_factor_through_mount_at_chamber_counts_per_deg"])


def worst_azimuth(bench: Bench, protocol: Protocol, tilt_deg: float) -> float:
    """The tilt azimuth α (°) at which the coupling biases the 7.1 K most
    (:func:`worst_condition`)."""
    return worst_condition(bench, protocol, tilt_deg)[0]


def worst_condition(bench: Bench, protocol: Protocol, tilt_deg: float) -> tuple[float, float]:
    """(α, sign): the tilt azimuth α (°) at which the coupling biases the 7.1 K most, and
    the sign (±1) of that bias. The noise-free bias is c₀ + a cos α + b sin α (c₀ the part
    that does not depend on the tilt's direction,
    :func:`gonio.specs.ogam_draft.budget_extra.scale_factor_tilt_bias` for the sinusoid), so
    the biases at α = 0°, 90° and 180° give c₀ = (B₀ + B₁₈₀)/2, a = (B₀ − B₁₈₀)/2,
    b = B₉₀ − c₀; |c₀ + R cos(α − φ)| with R = |(a, b)|, φ = atan2(b, a) is largest at
    α = φ where c₀ ≥ 0 (bias c₀ + R > 0) and at φ + 180° where c₀ < 0 (bias c₀ − R < 0)."""
    b0, b90, b180 = (coupling_bias(tilted(bench, tilt_deg, a), protocol) for a in (0, 90, 180))
    c0 = (b0 + b180) / 2.0
    phi = math.degrees(math.atan2(b90 - c0, (b0 - b180) / 2.0))
    return (phi + (180.0 if c0 < 0 else 0.0)) % 360.0, (-1.0 if c0 < 0 else 1.0)


def k_tilt_trial(bench: Bench, protocol: Protocol, seed: int,
                 work: Path) -> tuple[float, float, float]:
    """(K − K_true, u_c(K), U(K)) of one simulated calibration on ``bench`` (a tilted mount,
    :func:`tilted`), the readings written into the folder ``work`` and read back from the
    CSV as ``gonio calibrate`` reads them; K_true is the instrument's own K at the 7.1
    rounds through the mount (:func:`gonio.specs.ogam_draft.item_coverage.scale_factor_truth`),
    never gonio's calibration. The trial of ``scripts/k_tilt_coverage.py``."""
    from gonio.specs.ogam_draft.bench import write_session
    from gonio.specs.ogam_draft.readings import read_readings
    from gonio.specs.ogam_draft.item_coverage import scale_factor_truth

    session = run_session(protocol, bench, seed=seed)
    d = Path(work) / f"s{seed}"
    write_session(session, d)
    rep = analyse(read_readings(d / "readings.csv"), protocol,
                  static_record=session.static_record)
    iu = rep.item_uncertainty["scale_factor"]
    kt = scale_factor_truth(session.truth)[0]
    return float(iu.value) - kt, float(iu.u_c), float(iu.k * iu.u_c)   # K as stated


def draw_type_b(bench: Bench, protocol: Protocol, seed: int, table_errors: str = "curve"
                ) -> Bench:
    """``bench`` with its set-up's Type B effects drawn from the trial's seed, each from what
    a laboratory knows of it (a bound, not the value): the tilt uniform over the disc ψ ≤
    the A.1 bound (ψ = bound·√u, azimuth uniform); the table's positioning error as real
    tables err (``table_errors="curve"``, :func:`drawn_table_curve`): one smooth random
    curve of low orders whose max |e| over the circle is drawn within what the MPE leaves
    beside the scatter's 3σ and a small graduation part, plus that graduation part,
    independent at every position the programme visits (every :data:`TABLE_GRID_DEG`) — a
    table the laboratory knows by its MPE alone, drawn from physics, not from a budget's
    model; or (``table_errors="positions"``, :func:`drawn_position_errors`) every position
    independent uniform within that room (the per-position model, kept for comparison); or
    (``table_errors="shape"``) the bench's periodic errors at uniform phases with their sizes
    drawn as below; the wobble's phase and the axis set-up error's azimuth uniform; the
    table's relative rate error uniform within Table 1's ±1e-5
    (:data:`TABLE_RATE_ERROR_BOUND`); the chamber's deviation from the reference temperature
    uniform within Table 2's tolerance (``conditions.temperature_tolerance_c``, ±1 °C), which
    moves the instrument's K and bias by its temperature coefficients (drawn after the table,
    so the other draws are those of a bench without it); the scale factor's temperature
    coefficient α_K uniform within ± the bound K's chamber line ``K_T`` takes for the
    instrument (:func:`~gonio.specs.ogam_draft.calibration.temperature_coeff_bound` of the
    readings the trial's session writes: 0.1 ppm/°C for an RLG, 1.0 for a FOG by default;
    drawn after the others, so every other draw keeps its value); then the sizes of the
    table's periodic errors, their sum uniform within what the MPE leaves beside the
    scatter's 3σ (:func:`_harmonic_sizes`, A.4.1), and the gyro's bias instability (the
    Gauss–Markov σ, correlation time kept) uniform in [0, B/√2] with B the protocol's
    ``annex_a.zero_stability_dph`` (A.4.3: the bias change since the compensation has an
    RMS of σ√2 ≤ B; the ``drift`` case puts it at the bound). The instrument's own parameters (its
    K at the reference temperature, its angle-position error, its noise, its bias
    temperature coefficient) are the measurands' and are kept; the truth is K at the
    reference, from the trial bench's drawn α_K and chamber deviation.

    >>> p = validation_protocol(); b = load_bench("rlg")
    >>> d = draw_type_b(b, p, 4)
    >>> d == draw_type_b(b, p, 4), d.instrument.tilt_deg <= 0.1, d.table.mpe_arcsec
    (True, True, 0.1)
    >>> abs(d.table.rate_error_rel) <= TABLE_RATE_ERROR_BOUND
    True
    >>> abs(d.chamber_deviation_c) <= p.conditions.temperature_tolerance_c
    True
    >>> abs(d.instrument.sf_temperature_coeff_ppm_per_c) <= 0.1      # the RLG's bound
    True
    >>> from gonio.specs.ogam_draft.bench.instrument import harmonic_sum_arcsec
    >>> e = harmonic_sum_arcsec(np.arange(0.0, 360.0, 30.0), d.table.positioning_harmonics)
    >>> bool(np.ptp(e) <= 2 * (0.1 - 3 * 0.01)), len(d.table.positioning_harmonics)
    (True, 6)
    >>> s = draw_type_b(b, p, 4, table_errors="shape").table.positioning_harmonics
    >>> sum(abs(h.amplitude_arcsec) for h in s) <= 0.1 - 3 * 0.01, len(s)
    (True, 5)
    >>> 0.0 <= d.instrument.bias_instability_dph <= 0.005 / math.sqrt(2)
    True
    """
    rng = np.random.default_rng([int(seed), 0x7B])
    psi = float(protocol.annex_a.tilt_bound_deg) * math.sqrt(float(rng.uniform()))
    az = float(rng.uniform(0.0, 360.0))
    t = bench.table
    hs = tuple(replace(h, phase_deg=float(rng.uniform(0.0, 360.0)))
               for h in t.positioning_harmonics)
    table = replace(t, positioning_harmonics=hs,
                    wobble_phase_deg=float(rng.uniform(0.0, 360.0)),
                    axis_setup_azimuth_deg=float(rng.uniform(0.0, 360.0)),
                    rate_error_rel=float(rng.uniform(-TABLE_RATE_ERROR_BOUND,
                                                     TABLE_RATE_ERROR_BOUND)))
    tol = float(protocol.conditions.temperature_tolerance_c)
    dev_c = float(rng.uniform(-tol, tol))
    bound = sf_temperature_coeff_bound_ppm_per_c(bench, protocol)
    out = tilted(bench, psi, az)
    inst = replace(out.instrument, sf_temperature_coeff_ppm_per_c=float(rng.uniform(-bound, bound)))
    # drawn after every draw above, which keep their values: the sizes a laboratory bounds
    table = replace(table, positioning_harmonics=_harmonic_sizes(table, float(rng.uniform())))
    sigma_dph = float(rng.uniform()) * float(protocol.annex_a.zero_stability_dph) / math.sqrt(2.0)
    inst = replace(inst, bias_instability_dph=sigma_dph)
    if table_errors == "curve":          # its own stream: every draw above keeps its value
        table = replace(table, positioning_harmonics=drawn_table_curve(table, seed))
    elif table_errors == "positions":
        table = replace(table, positioning_harmonics=drawn_position_errors(table, seed))
    elif table_errors != "shape":
        raise ValueError(f"table_errors must be 'curve', 'positions' or 'shape', not "
                         f"{table_errors!r}")
    return replace(out, instrument=inst, table=table, chamber_deviation_c=dev_c)


#: The step of the table positions the study draws errors at: the built-in programme's
#: positions (7.1's stops, 7.4's points, the tilt estimate's rests) are all multiples of 30°.
TABLE_GRID_DEG = 30.0


#: The highest order of the smooth part of the table error the ``typeb`` study draws
#: (:func:`drawn_table_curve`): a worm-gear or encoder table's error is dominated by its
#: low orders (eccentricity 1, ellipticity 2, the encoder's and mount's few-lobe terms).
TABLE_CURVE_MAX_ORDER = 6
#: The bound of the graduation part of the drawn table error, independent at every
#: :data:`TABLE_GRID_DEG` position, arcsec (a tenth of the draft's MPE, A.4.1).
TABLE_GRADUATION_ARCSEC = 0.01


def _room_arcsec(table) -> float:
    """What the MPE leaves for the table's systematic error beside its scatter's 3σ
    (A.4.1: |error| ≤ MPE)."""
    return max(float(table.mpe_arcsec) - 3.0 * float(table.positioning_random_arcsec), 0.0)


def _grid_harmonics(v: np.ndarray) -> dict:
    """{order: complex amplitude c} of the trigonometric polynomial through the values ``v``
    at the :data:`TABLE_GRID_DEG` grid, less their mean (a constant error cancels in every
    angle turned), e(x) = Σ Im(c e^{ihx})."""
    n = v.size
    spec = np.fft.rfft(v)
    # a_k cos(kx + φ) = Im(a_k e^{i(kx + φ + 90°)})
    return {k: complex(spec[k] * (1.0 if 2 * k == n else 2.0) / n * 1j)
            for k in range(1, n // 2 + 1)}


def _as_harmonics(c: dict) -> tuple:
    return tuple(Harmonic(k, float(abs(v)), float(math.degrees(np.angle(v)) % 360.0))
                 for k, v in sorted(c.items()))


def drawn_table_curve(table, seed: int) -> tuple:
    """A table's positioning error drawn as real tables err and as a laboratory knows them
    (by the MPE alone, A.4.1), the ``typeb`` study's table: a smooth curve
    Σ_{h=1}^{N} a_h sin(h x + φ_h), N = :data:`TABLE_CURVE_MAX_ORDER`, with a_h uniform in
    [0, 1/h) (a smooth curve's spectrum falls with the order) and φ_h uniform, scaled so that
    its max |e| over the circle (0.1° steps) is uniform within the room the MPE leaves beside
    the scatter's 3σ and the graduation part; plus the graduation part, uniform within
    ±:data:`TABLE_GRADUATION_ARCSEC` independently at every :data:`TABLE_GRID_DEG` position
    (as the harmonics of the trigonometric polynomial through those values, less their mean).
    Between the grid's positions the graduation part is that polynomial (no item of the
    built-in programme stops there). The truth is the bench's physics, never a budget's
    model: the curve's errors at the 7.1 positions are correlated as one table's are.

    >>> from gonio.specs.ogam_draft.bench.instrument import harmonic_sum_arcsec
    >>> t = load_bench("rlg").table
    >>> hs = drawn_table_curve(t, 3)
    >>> x = np.arange(0.0, 360.0, 30.0)
    >>> bool(np.ptp(harmonic_sum_arcsec(x, hs)) <= 2 * (0.1 - 3 * 0.01))   # a constant cancels
    True
    >>> [h.order for h in hs], drawn_table_curve(t, 3) == hs, drawn_table_curve(t, 4) != hs
    ([1, 2, 3, 4, 5, 6], True, True)
    """
    rng = np.random.default_rng([int(seed), 0xC0A7E])
    grad = min(TABLE_GRADUATION_ARCSEC, _room_arcsec(table))
    room = _room_arcsec(table) - grad
    orders = np.arange(1, TABLE_CURVE_MAX_ORDER + 1)
    amp = rng.uniform(0.0, 1.0, orders.size) / orders
    phase = rng.uniform(0.0, 2.0 * math.pi, orders.size)
    x = np.radians(np.arange(0.0, 360.0, 0.1))
    e = np.sin(np.outer(x, orders) + phase) @ amp
    scale = float(rng.uniform()) * room / float(np.max(np.abs(e)))
    n = int(round(360.0 / TABLE_GRID_DEG))
    c = _grid_harmonics(rng.uniform(-grad, grad, n))
    for h, a, ph in zip(orders, amp, phase):
        c[int(h)] = c.get(int(h), 0j) + scale * a * complex(math.cos(ph), math.sin(ph))
    return _as_harmonics(c)


def _k_coefficients(protocol: Protocol) -> dict:
    """K's coefficients at the 7.1 rounds' positions of ``protocol``
    (:func:`~gonio.specs.ogam_draft.item_uncertainty.scale_factor_table_coefficients`)."""
    from gonio.specs.ogam_draft.item_uncertainty import scale_factor_table_coefficients

    item = next(it for it in protocol.items() if it.test == "scale_factor")
    stop = np.array([r.stop_deg for r in item.rounds], dtype=float)
    zero = np.array([(r.start_deg if item.rezero else item.rounds[0].start_deg)
                     for r in item.rounds], dtype=float)
    return scale_factor_table_coefficients(stop - zero, stop, zero)


def corner_table(table, protocol: Protocol, sign: float) -> tuple:
    """The ``worsttable`` study's table: the error at the 7.1 rounds' zero at −sign·room and at
    every other :data:`TABLE_GRID_DEG` position at +sign·room (room: the MPE less the
    scatter's 3σ, A.4.1), as the harmonics through those values: every round's angle off by
    2·room the same way, K moved by room·Σ|c_p| (the 7.1 zero is the only position with a
    negative coefficient where the rounds share it, :func:`_k_coefficients`).

    >>> from gonio.specs.ogam_draft.bench.instrument import harmonic_sum_arcsec
    >>> p = validation_protocol(); t = load_bench("rlg").table
    >>> e = harmonic_sum_arcsec(np.array([0.0, 60.0, 330.0]), corner_table(t, p, 1.0))
    >>> bool(np.allclose(e - e[0], [0.0, 0.14, 0.14]))
    True
    """
    room = _room_arcsec(table)
    zeros = {p for p, c in _k_coefficients(protocol).items() if c < 0}
    x = np.arange(0.0, 360.0, TABLE_GRID_DEG)
    v = np.where([round(float(p), 6) in zeros for p in x], -sign * room, sign * room)
    return _as_harmonics(_grid_harmonics(v))


def worst_harmonic_table(table, protocol: Protocol, sign: float, max_order: int = 12) -> tuple:
    """The ``worstharmonic`` study's table: one periodic error room·sin(h x + φ) (room: the MPE
    less the scatter's 3σ, A.4.1) of the order h ≤ ``max_order`` and phase φ that move the 7.1
    K most, δK/K = room·Im(e^{iφ} Σ_p c_p e^{ihp}), in the direction ``sign``.

    >>> p = validation_protocol(); t = load_bench("rlg").table
    >>> h = worst_harmonic_table(t, p, 1.0)[0]
    >>> h.order, round(h.amplitude_arcsec, 3)
    (3, 0.07)
    """
    c = _k_coefficients(protocol)
    pos = np.radians(np.array(list(c), dtype=float))
    cp = np.array(list(c.values()))
    g = [complex(np.sum(cp * np.exp(1j * h * pos))) for h in range(1, max_order + 1)]
    h = int(np.argmax(np.abs(g))) + 1
    phi = math.pi / 2.0 - float(np.angle(g[h - 1])) + (0.0 if sign > 0 else math.pi)
    return (Harmonic(h, _room_arcsec(table), math.degrees(phi) % 360.0),)


def drawn_position_errors(table, seed: int) -> tuple:
    """The table's positioning error at every multiple of :data:`TABLE_GRID_DEG` drawn
    uniform within ± what the MPE leaves beside the scatter's 3σ (A.4.1: |error| ≤ MPE),
    each position independent of the others — the state of knowledge of a laboratory that
    knows its table by the MPE alone (JCGM 100 4.3.7), the distribution K's table lines
    (one per position, the zero shared) and E's (``budget_extra.table_line_u``) take —
    given as the harmonics (orders 1 … N/2, N positions) of the trigonometric polynomial
    through the drawn values less their mean (a constant error cancels in every angle
    turned, e(stop) − e(zero)). Between the grid's positions the table's error is that
    polynomial (no item of the built-in programme stops there).

    >>> from gonio.specs.ogam_draft.bench.instrument import harmonic_sum_arcsec
    >>> t = load_bench("rlg").table
    >>> hs = drawn_position_errors(t, 3)
    >>> x = np.arange(0.0, 360.0, 30.0)
    >>> v = np.random.default_rng([3, 0x7AB1E]).uniform(-0.07, 0.07, 12)
    >>> bool(np.allclose(harmonic_sum_arcsec(x, hs), v - v.mean(), atol=1e-15))
    True
    >>> [h.order for h in hs], drawn_position_errors(t, 3) == hs
    ([1, 2, 3, 4, 5, 6], True)
    """
    room = max(float(table.mpe_arcsec) - 3.0 * float(table.positioning_random_arcsec), 0.0)
    n = int(round(360.0 / TABLE_GRID_DEG))
    v = np.random.default_rng([int(seed), 0x7AB1E]).uniform(-room, room, n)
    spec = np.fft.rfft(v)
    out = []
    for k in range(1, n // 2 + 1):
        amp = abs(spec[k]) * (1.0 if 2 * k == n else 2.0) / n
        # a_k cos(kx + φ) = a_k sin(kx + φ + 90°)
        out.append(Harmonic(k, float(amp), float((math.degrees(np.angle(spec[k])) + 90.0) % 360.0)))
    return tuple(out)


def _harmonic_sizes(table, u: float) -> tuple:
    """The table's positioning harmonics with their amplitudes scaled together so that their
    sum is ``u`` (uniform in [0, 1)) times what the MPE leaves beside the scatter's 3σ
    (A.4.1: |error| ≤ MPE; Σ|a_h| + 3σ ≤ MPE): a size the laboratory only bounds, each size
    inside the bound equally likely. The ratios of the amplitudes (the table's error shape)
    and the phases drawn before are kept.

    >>> t = load_bench("rlg").table
    >>> round(sum(abs(h.amplitude_arcsec) for h in _harmonic_sizes(t, 1.0)), 12)
    0.07
    >>> [h.phase_deg for h in _harmonic_sizes(t, 0.5)] == [h.phase_deg for h in t.positioning_harmonics]
    True
    """
    hs = table.positioning_harmonics
    total = sum(abs(h.amplitude_arcsec) for h in hs)
    room = max(float(table.mpe_arcsec) - 3.0 * float(table.positioning_random_arcsec), 0.0)
    if total <= 0.0:
        return hs
    return tuple(replace(h, amplitude_arcsec=h.amplitude_arcsec * u * room / total) for h in hs)


def sf_temperature_coeff_bound_ppm_per_c(bench: Bench, protocol: Protocol) -> float:
    """The bound |α_K|max (ppm/°C) the calibration of a session of ``bench`` takes for K's
    chamber line: :func:`~gonio.specs.ogam_draft.calibration.temperature_coeff_bound` of the
    metadata that session writes (its ``gyro_type``), so the study draws within the bound
    the certificate states.

    >>> p = validation_protocol()
    >>> [sf_temperature_coeff_bound_ppm_per_c(load_bench(b), p) for b in ("rlg", "fog")]
    [0.1, 1.0]
    """
    md = session_metadata(protocol, bench, 0)
    return float(temperature_coeff_bound(Readings(pd.DataFrame(), md), protocol)[
        "bound_ppm_per_c"])


def trial_bench(case: str, bench: Bench, protocol: Protocol, seed: int) -> Bench:
    """The bench of one trial of ``case``: ``bench`` itself, except in the ``mounted`` case,
    whose tilt is drawn from the trial's seed uniformly over the disc ψ ≤ the Annex A.1
    bound (ψ = bound·√u, azimuth uniform): the distribution of a tilt that is only known to
    lie within the bound, so the budget's tilt terms (u(φ_e), and the physical budget's
    tilt × Earth-rate line) meet tilts of every size they allow.

    >>> p = validation_protocol(); b = load_bench("rlg")
    >>> t = [trial_bench("mounted", b, p, s).instrument for s in range(200)]
    >>> max(i.tilt_deg for i in t) <= p.annex_a.tilt_bound_deg, len({i.tilt_deg for i in t})
    (True, 200)
    >>> trial_bench("default", b, p, 3) is b
    True

    In the ``typeb`` case every Type B effect of the set-up is drawn (:func:`draw_type_b`);
    in the ``worst`` case too, except the tilt, which stays where :func:`case_bench` put it
    (the A.1 bound at the worst azimuth). Why the chamber is drawn there and not put at its
    bound: the budget adds the Type B lines as rectangular (and arcsine) distributions by
    the sum of their variances (JCGM 100 4.3.7, 5.1.2); it promises coverage over the
    bounds' distributions, not at the corner where every bound holds at once, which no
    laboratory meets and which the RSS of bounded effects does not cover (docs/draft-readings.md).

    >>> w = case_bench("worst", b, p)
    >>> t = trial_bench("worst", w, p, 3)
    >>> (t.instrument.tilt_deg, t.instrument.tilt_azimuth_deg) == (0.1, w.instrument.tilt_azimuth_deg)
    True
    >>> t.chamber_deviation_c == draw_type_b(w, p, 3).chamber_deviation_c != 0.0
    True

    ``worsttable``, ``worstharmonic``: the draws of ``typeb`` with the table at the corner
    (:func:`corner_table`) or its worst periodic error (:func:`worst_harmonic_table`), the
    sign drawn; ``worstshape``: the bench's table shape with its harmonics at the A.4.1 bound
    (their sum plus the scatter's 3σ = the MPE):

    >>> t = trial_bench("worstshape", b, p, 3)
    >>> h = t.table.positioning_harmonics
    >>> round(sum(abs(x.amplitude_arcsec) for x in h) + 3 * t.table.positioning_random_arcsec, 12)
    0.1
    >>> t.chamber_deviation_c == draw_type_b(b, p, 3).chamber_deviation_c
    True
    >>> trial_bench("worstharmonic", b, p, 3).table.positioning_harmonics[0].order
    3

    ``worstcorner``: ``worst``'s tilt (the bench of :func:`case_bench`) with
    ``worsttable``'s corner table and draws:

    >>> w = case_bench("worstcorner", b, p)
    >>> t = trial_bench("worstcorner", w, p, 3)
    >>> (t.instrument.tilt_deg, t.instrument.tilt_azimuth_deg) == (0.1, w.instrument.tilt_azimuth_deg)
    True
    >>> t.table == trial_bench("worsttable", w, p, 3).table
    True
    """
    if case in ("typeb", "tablecal", "tablecalpart", "tablecaldof"):
        return draw_type_b(bench, protocol, seed)
    if case == "worstshape":
        d = draw_type_b(bench, protocol, seed, table_errors="shape")
        return replace(d, table=replace(d.table,
                                        positioning_harmonics=_harmonic_sizes(d.table, 1.0)))
    if case in ("worsttable", "worstharmonic"):
        d = draw_type_b(bench, protocol, seed)
        sign = 1.0 if np.random.default_rng([int(seed), 0x5161]).uniform() < 0.5 else -1.0
        f = corner_table if case == "worsttable" else worst_harmonic_table
        return replace(d, table=replace(d.table,
                                        positioning_harmonics=f(d.table, protocol, sign)))
    if case == "worst":
        i = bench.instrument
        return tilted(draw_type_b(bench, protocol, seed), i.tilt_deg, i.tilt_azimuth_deg)
    if case == "worstcorner":             # worst's tilt, worsttable's table
        i = bench.instrument
        return tilted(trial_bench("worsttable", bench, protocol, seed), i.tilt_deg,
                      i.tilt_azimuth_deg)
    if case != "mounted":
        return bench
    rng = np.random.default_rng([int(seed), 0x7117])
    psi = float(protocol.annex_a.tilt_bound_deg) * math.sqrt(float(rng.uniform()))
    return replace(bench, instrument=replace(bench.instrument, tilt_deg=psi,
                                             tilt_azimuth_deg=float(rng.uniform(0.0, 360.0))))


def table_positions_deg(protocol: Protocol) -> np.ndarray:
    """Every table position the protocol's session uses (stops and zeroing positions of the
    rotation items, the tilt estimate's rests), modulo 360°, sorted.

    >>> table_positions_deg(validation_protocol()).tolist()[:4]
    [0.0, 30.0, 60.0, 90.0]
    """
    pos = []
    for item in protocol.items():
        x0 = item.rounds[0].start_deg
        for r in item.rounds:
            pos += [r.stop_deg, r.start_deg if item.rezero else x0]
    te = protocol.tilt_estimate
    if te is not None:
        pos += list(te.order_deg)
    w = np.mod(np.round(np.asarray(pos, dtype=float), 9), 360.0)
    return np.unique(w)


def drawn_table_calibration(bench: Bench, protocol: Protocol, seed: int,
                            u_arcsec: float = TABLE_CALIBRATION_U_ARCSEC, *,
                            dof: float | None = None, omit_deg=()):
    """A laboratory's table calibration for one trial: at every position the protocol uses
    (:func:`table_positions_deg`) but ``omit_deg``, the trial bench's TRUE periodic
    positioning error (indicated − true, the bench's harmonics; the per-visit scatter is no
    property a calibration can state) plus normal noise of standard deviation ``u_arcsec``.
    Stated with u = ``u_arcsec`` (``dof`` None: known, ν = ∞), or, with ``dof`` = ν, as a
    Type A estimate of ν degrees of freedom would state it: per position u_p =
    u_arcsec·√(χ²_ν/ν), independent of the error's noise (a normal sample's mean and
    variance), with ``dof`` ν — so (stated − true)/u_p is Student's t_ν, as the laboratory's
    certificate and JCGM 101 6.4.9 take it. The truth comes from the bench's parameters,
    never from an estimator; the same seed gives the same errors with or without ``dof``.

    >>> b = draw_type_b(load_bench("rlg"), validation_protocol(), 3)
    >>> c = drawn_table_calibration(b, validation_protocol(), 3)
    >>> c.table_deg.size == table_positions_deg(validation_protocol()).size, float(c.u_arcsec[0])
    (True, 0.02)
    >>> f = drawn_table_calibration(b, validation_protocol(), 3, dof=3.0, omit_deg=(330.0,))
    >>> 330.0 in f.table_deg, f.table_deg.size, set(f.dof.tolist()), len(set(f.u_arcsec.tolist()))
    (False, 11, {3.0}, 11)
    >>> bool(np.all(f.error_arcsec == c.error_arcsec[:11]))
    True
    """
    from gonio.specs.ogam_draft.bench.instrument import harmonic_sum_arcsec
    from gonio.specs.ogam_draft.table_calibration import TableCalibration

    x = table_positions_deg(protocol)
    true = np.asarray(harmonic_sum_arcsec(x, bench.table.positioning_harmonics), dtype=float) \
        + 0.0 * x
    rng = np.random.default_rng([int(seed), 0x7ab1ec])
    err = true + u_arcsec * rng.standard_normal(x.size)
    u = np.full(x.size, float(u_arcsec))
    if dof is not None:
        u = u * np.sqrt(rng.chisquare(float(dof), x.size) / float(dof))
    keep = np.ones(x.size, dtype=bool)
    for o in omit_deg:
        keep &= ~np.isclose(x, float(o) % 360.0, atol=1e-9)
    what = f"u {u_arcsec:g}″" + (f", nu {dof:g}" if dof is not None else "") \
        + (f", without {', '.join(f'{o:g}' for o in omit_deg)} deg" if omit_deg else "")
    return TableCalibration(x[keep], err[keep], u[keep], f"drawn table calibration ({what})",
                            dof=None if dof is None else np.full(int(keep.sum()), float(dof)))


def case_table_calibration(case: str, bench: Bench, protocol: Protocol, seed: int):
    """The laboratory's table calibration of one trial of ``case``: ``tablecal``'s (every
    position, u known), ``tablecalpart``'s (without TABLE_CALIBRATION_PART_OMIT_DEG, u of
    TABLE_CALIBRATION_PART_DOF degrees of freedom), ``tablecaldof``'s (every position, ν as
    tablecalpart's), None for the other cases."""
    if case == "tablecal":
        return drawn_table_calibration(bench, protocol, seed)
    if case == "tablecalpart":
        return drawn_table_calibration(bench, protocol, seed, dof=TABLE_CALIBRATION_PART_DOF,
                                       omit_deg=TABLE_CALIBRATION_PART_OMIT_DEG)
    if case == "tablecaldof":
        return drawn_table_calibration(bench, protocol, seed, dof=TABLE_CALIBRATION_PART_DOF)
    return None


@dataclass
class TrialResult:
    """One virtual calibration; arrays are (series, points), arcsec."""

    seed: int
    position_deg: np.ndarray
    E_ij: np.ndarray
    truth_systematic: np.ndarray
    truth_calibrated: np.ndarray
    U_arcsec: float
    U_extended_arcsec: float
    u_r_arcsec: float
    k_cal: float
    k_mount: float
    extras: list
    items: dict = field(default_factory=dict)     # item_coverage.trial_items of this trial


def _matrix(df, col: str) -> np.ndarray:
    """(series, round) matrix of ``col``, rows and columns in ascending order, NaN where a
    (series, round) is absent (what ``DataFrame.pivot`` gives, without its cost).

    >>> _matrix({"series": [2, 1, 1], "round": [1, 2, 1], "v": [5.0, 4.0, 3.0]}, "v").tolist()
    [[3.0, 4.0], [5.0, nan]]
    """
    s_idx = np.asarray(df["series"])
    r_idx = np.asarray(df["round"])
    us, si = np.unique(s_idx, return_inverse=True)
    ur, ri = np.unique(r_idx, return_inverse=True)
    if np.unique(si * ur.size + ri).size != si.size:
        raise ValueError("a (series, round) pair is given twice")
    out = np.full((us.size, ur.size), np.nan)
    out[si, ri] = np.asarray(df[col], dtype=float)
    return out


def run_trial(protocol: Protocol, bench: Bench, seed: int, u_scale: float = 1.0,
              truth: str = "systematic", extras_used: Sequence[str] = EXTRA_SYMBOLS,
              table_calibration=None) -> TrialResult:
    """One virtual calibration on ``bench``: session, calibration, Annex A U, truth.

    U is the calibration's own Annex A U (k = 2, u(r) from its 7.5 data), times
    ``u_scale`` (1 except to test the validation's power); ``U_extended_arcsec``
    adds the :func:`budget_extra_components` named in ``extras_used``.
    ``table_calibration``: the laboratory's table calibration (``tablecal``), or None.
    """
    res = run_session(protocol, bench, seed=seed)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    # the continuous record of the 7.3 rest, as a stream calibration has it (B_s's model)
    rep = analyse(Readings(df, dict(res.metadata)), protocol, budget="draft",
                  static_record=res.static_record, table_calibration=table_calibration)
    ad = rep.results.angle_deviation.tables["readings"]
    e = _matrix(ad, "E_arcsec")
    pos = ad.groupby("round")["table_deg"].mean().sort_index().to_numpy(dtype=float)
    rows = [r for r in res.truth["readings"] if r["test"] == "angle_deviation"]
    tr = {k: [r[k] for r in rows] for k in ("series", "round", "systematic_deviation_arcsec",
                                             "systematic_deviation_calibrated_arcsec")}
    u_r = float(rep.uncertainty.parameters["repeatability_arcsec"])
    extras = [e for e in budget_extra_components(res.readings, protocol, bench.latitude_deg, u_r,
                                                 truth=truth, accel_dps2=bench.table.accel_dps2)
              if e.symbol in extras_used]
    par = rep.uncertainty.parameters
    ext = annex_a_budget(table_mpe_arcsec=par["table_mpe_arcsec"], tilt_deg=par["tilt_deg"],
                         zero_stability_dph=par["zero_stability_dph"],
                         duration_min=par["duration_min"], repeatability_arcsec=u_r, k=par["k"],
                         extra_components=extras)
    return TrialResult(seed=seed, position_deg=pos, E_ij=e,
                       truth_systematic=_matrix(tr, "systematic_deviation_arcsec"),
                       truth_calibrated=_matrix(tr, "systematic_deviation_calibrated_arcsec"),
                       U_arcsec=float(rep.uncertainty.U_arcsec) * u_scale,
                       U_extended_arcsec=float(ext.U_arcsec) * u_scale, u_r_arcsec=u_r,
                       k_cal=float(rep.results.scale_factor.value),
                       k_mount=float(res.truth[
                           "scale_factor_through_mount_at_chamber_counts_per_deg"]),
                       extras=[(c.symbol, c.half_width_arcsec, c.distribution) for c in extras],
                       items=trial_items(rep, res.truth))


def trial_seed(seed: int, case: str, index: int) -> int:
    """Seed of trial ``index`` of ``case``: numpy SeedSequence(seed, spawn_key=(case, index)).

    The same number as the ``index``-th child of ``SeedSequence(seed,
    spawn_key=(case,)).spawn(...)``, computed from the index alone: a trial's
    random stream does not depend on which other trials run, in which batch, on
    which worker, or in which order.

    >>> trial_seed(0, "default", 4) == trial_seeds(0, "default", 5)[4]
    True
    """
    return spawn_seed(seed, list(CASES).index(case), index)


def trial_seeds(seed: int, case: str, trials: int) -> list[int]:
    """Seeds of the first ``trials`` trials of one case (:func:`trial_seed` by index).

    A case's seeds do not depend on which other cases run, and the first n seeds
    do not depend on the number of trials.

    >>> trial_seeds(0, "default", 3) == trial_seeds(0, "default", 5)[:3]
    True
    """
    return [trial_seed(seed, case, i) for i in range(trials)]


@dataclass(frozen=True)
class TrialJob:
    """What a worker needs to run trials of one case (picklable)."""

    protocol: Protocol
    bench: Bench
    case: str
    seed: int
    u_scale: float
    truth: str
    extras_used: tuple

    def run(self, start: int, stop: int) -> dict:
        """Trials ``start`` … ``stop − 1`` of this case, packed (:func:`pack_trials`); the
        engine (:func:`gonio.pipeline.validate.run_batch`) calls it in a worker."""
        idx = range(start, stop)
        seeds = [trial_seed(self.seed, self.case, i) for i in idx]
        res = []
        for sd in seeds:
            b = trial_bench(self.case, self.bench, self.protocol, sd)
            cal = case_table_calibration(self.case, b, self.protocol, sd)
            res.append(run_trial(self.protocol, b, sd, self.u_scale, self.truth,
                                 self.extras_used, table_calibration=cal))
        return pack_trials(self.case, list(idx), res)


def pack_trials(case: str, indices: Sequence[int], trials: Sequence[TrialResult]) -> dict:
    """Trials as a dict of numpy arrays (lossless: float64 bits are kept)."""
    ex = trials[0].extras
    return {
        "case": np.array(case), "index": np.asarray(indices, dtype=np.int64),
        "seed": np.array([t.seed for t in trials], dtype=np.int64),
        "position_deg": np.stack([t.position_deg for t in trials]),
        "E_ij": np.stack([t.E_ij for t in trials]),
        "truth_systematic": np.stack([t.truth_systematic for t in trials]),
        "truth_calibrated": np.stack([t.truth_calibrated for t in trials]),
        "U_arcsec": np.array([t.U_arcsec for t in trials]),
        "U_extended_arcsec": np.array([t.U_extended_arcsec for t in trials]),
        "u_r_arcsec": np.array([t.u_r_arcsec for t in trials]),
        "k_cal": np.array([t.k_cal for t in trials]),
        "k_mount": np.array([t.k_mount for t in trials]),
        "extras_symbol": np.array([e[0] for e in ex], dtype=str),
        "extras_distribution": np.array([e[2] for e in ex], dtype=str),
        "extras_half_width": np.array([[e[1] for e in t.extras] for t in trials],
                                      dtype=np.float64).reshape(len(trials), len(ex)),
        # per-item records (nested dicts of floats): JSON text, lossless (repr of each float)
        "items_json": np.array([json.dumps(t.items, sort_keys=True) for t in trials], dtype=str),
    }


def unpack_trials(packed: Mapping) -> dict[int, TrialResult]:
    """Trial index → :class:`TrialResult` from :func:`pack_trials`."""
    sym = [str(x) for x in packed["extras_symbol"]]
    dist = [str(x) for x in packed["extras_distribution"]]
    out = {}
    for j, i in enumerate(packed["index"].tolist()):
        out[int(i)] = TrialResult(
            seed=int(packed["seed"][j]), position_deg=packed["position_deg"][j],
            E_ij=packed["E_ij"][j], truth_systematic=packed["truth_systematic"][j],
            truth_calibrated=packed["truth_calibrated"][j],
            U_arcsec=float(packed["U_arcsec"][j]),
            U_extended_arcsec=float(packed["U_extended_arcsec"][j]),
            u_r_arcsec=float(packed["u_r_arcsec"][j]), k_cal=float(packed["k_cal"][j]),
            k_mount=float(packed["k_mount"][j]),
            extras=[(s, float(packed["extras_half_width"][j, m]), d)
                    for m, (s, d) in enumerate(zip(sym, dist))],
            items=json.loads(str(packed["items_json"][j])) if "items_json" in packed else {})
    return out



@dataclass
class CaseResult:
    """Every trial of one case, and its summary (``summary``: plain dict)."""

    name: str
    description: str
    trials: list[TrialResult]
    truth_intrinsic: np.ndarray
    summary: dict = field(default_factory=dict)


def _summarise(case: CaseResult, truth: str, extended: bool) -> dict:
    tr = case.trials
    pos = tr[0].position_deg
    E = np.stack([t.E_ij for t in tr])                     # (trials, series, points)
    truths = {"systematic": np.stack([t.truth_systematic for t in tr]),
              "calibrated": np.stack([t.truth_calibrated for t in tr]),
              "intrinsic": np.broadcast_to(case.truth_intrinsic, E.shape)}
    U = np.array([t.U_arcsec for t in tr])
    Ux = np.array([t.U_extended_arcsec for t in tr])
    # a reading the calibration's screening set aside is NaN in E: E_i is the mean of the
    # series it used (the calibration's own E_i), its truth the mean over the same series;
    # the errors' means and the coverages are over the readings used (coverage's set_aside)
    used = np.isfinite(E)
    n_used = used.sum(axis=1)
    Ei = np.where(n_used > 0, np.where(used, E, 0.0).sum(axis=1) / np.maximum(n_used, 1),
                  np.nan)

    def mean_over_used(x, axis=None):
        ok = np.isfinite(x)
        return np.where(ok, x, 0.0).sum(axis=axis) / ok.sum(axis=axis)

    def block(Uv):
        out = {}
        for name, T in truths.items():
            Ti = np.where(used, T, 0.0).sum(axis=1) / np.maximum(n_used, 1)
            d_i, d_ij = Ei - Ti, E - T
            ok_i = np.isfinite(d_i)
            out[name] = {
                "coverage_E_i": coverage(np.abs(d_i), Uv),
                "coverage_E_ij": coverage(np.abs(d_ij), Uv),
                "mean_abs_error_E_i_arcsec": float(mean_over_used(np.abs(d_i))),
                "mean_abs_error_E_ij_arcsec": float(mean_over_used(np.abs(d_ij))),
                "bias_E_i_per_point_arcsec": [float(x) for x in mean_over_used(d_i, 0)],
                "std_E_i_per_point_arcsec": [
                    float(np.std(d_i[ok_i[:, j], j], ddof=1)) if ok_i[:, j].sum() > 1
                    else math.nan for j in range(d_i.shape[1])]
                if len(tr) > 1 else None,
            }
        return out

    k_term = deg_to_arcsec(np.array([(t.k_mount / t.k_cal - 1.0) for t in tr])[:, None] * pos[None, :])
    diag = {
        "scale_factor_term_rms_per_point_arcsec": [float(x) for x in
                                                   np.sqrt((k_term ** 2).mean(axis=0))],
        "scale_factor_rel_error_rms_ppm": float(np.sqrt(np.mean(
            [(t.k_cal / t.k_mount - 1.0) ** 2 for t in tr])) / PPM),
        "setup_minus_intrinsic_per_point_arcsec": [float(x) for x in
                                                   (truths["systematic"].mean(axis=(0, 1))
                                                    - case.truth_intrinsic.mean(axis=0))],
        "residual_after_scale_factor_term_rms_E_i_arcsec": float(np.sqrt(np.mean(
            (Ei - k_term - truths["systematic"].mean(axis=1)) ** 2))),
    }
    s = {
        "name": case.name, "description": case.description,
        "positions_deg": [float(x) for x in pos], "points": int(pos.size),
        "series": int(E.shape[1]), "trials": len(tr),
        "seeds_first": [t.seed for t in tr[:3]],
        "mean_U_arcsec": float(U.mean()), "min_U_arcsec": float(U.min()),
        "mean_u_r_arcsec": float(np.mean([t.u_r_arcsec for t in tr])),
        "annex_a": block(U),
        "items": item_coverage([t.items for t in tr],
                               np.asarray(case.truth_intrinsic).mean(axis=0),
                               judge_spread=case.name not in FIXED_CONDITION_CASES),
        "diagnosis": diag,
        "primary": {"truth": truth},
    }
    if extended:
        s["extra_components"] = [
            {"symbol": sym, "distribution": dist,
             "mean_half_width_arcsec": float(np.mean([dict((e[0], e[1]) for e in t.extras)[sym]
                                                      for t in tr]))}
            for sym, _, dist in tr[0].extras]
        s["mean_U_extended_arcsec"] = float(Ux.mean())
        s["extended"] = block(Ux)
        s["extended_for_truth"] = truth
    return s


def fixed_condition(bench: Bench, protocol: Protocol) -> dict:
    """The set-up of a fixed-condition case (validation.json ``condition``): the tilt and
    its azimuth, and what is drawn per trial around them (:func:`trial_bench`): the
    chamber's deviation within ± ``chamber_tolerance_c``, the table's errors."""
    return {"tilt_deg": bench.instrument.tilt_deg,
            "tilt_azimuth_deg": bench.instrument.tilt_azimuth_deg,
            "chamber_tolerance_c": float(protocol.conditions.temperature_tolerance_c),
            "drawn_per_trial": "as in typeb: table errors, table rate error, chamber "
                               "deviation, alpha_K within its bound"}


def condition_text(c: dict) -> str:
    """One line for :func:`fixed_condition`.

    >>> condition_text({"tilt_deg": 0.1, "tilt_azimuth_deg": 123.45, "chamber_tolerance_c": 1.0})
    'tilt 0.1 deg at azimuth 123.5 deg; chamber drawn within +-1 degC and table errors drawn, as in typeb'
    """
    return (f"tilt {c['tilt_deg']:g} deg at azimuth {c['tilt_azimuth_deg']:.1f} deg; "
            f"chamber drawn within +-{c['chamber_tolerance_c']:g} degC and table errors "
            "drawn, as in typeb")


def item_coverage_lines(cases) -> list[str]:
    """Per case, the coverage of every measured item (|result − truth| ≤ U; interval)."""
    out = ["", "coverage per item (|result - truth| <= U as stated; for B_s and R also the "
               "95 % interval holding the truth)"]
    for c in cases:
        for name, it in c.summary.get("items", {}).items():
            w = it["within_U"]
            txt = (f"{c.name:<10}{name:<28}{it['trials']:>5} trials  within U "
                   f"{100 * w['fraction']:5.1f} ± {100 * w['u_binomial']:4.1f}%")
            if "interval_holds_truth" in it:
                ih = it["interval_holds_truth"]
                txt += f"   interval {100 * ih['fraction']:5.1f}%"
                if "clopper_pearson" in ih:
                    txt += (f" (CP {100 * ih['clopper_pearson'][0]:.1f}-"
                            f"{100 * ih['clopper_pearson'][1]:.1f}%, "
                            f"mean width {ih['mean_width']:.3g})")
            if "z_chi2" in it:
                txt += (f"   chi2 z mean {it['z_chi2']['mean']:+.2f} "
                        f"sd {it['z_chi2']['sd']:.2f}"
                        + (f" rms {it['z_chi2']['rms']:.2f}" if "rms" in it["z_chi2"] else ""))
                if "predicted" in it:     # R: its exact distribution at the σ_i found
                    pr = it["predicted"]
                    txt += (f" (exact at the ensemble sigma_i: {pr['z_chi2_mean']:+.2f} sd "
                            f"{pr['z_chi2_sd']:.2f}, interval "
                            f"{100 * pr['interval_coverage']:.1f}%)")
            if "within_U_intrinsic" in it:
                txt += (f"   vs intrinsic truth "
                        f"{100 * it['within_U_intrinsic']['fraction']:5.1f}%")
            if "two_sided" in it:
                txt += "   " + two_sided_text(it["two_sided"])
            if "max_interval" in it:      # E's certified statement first
                mi = it["max_interval"]
                txt += (f"   {MAX_INTERVAL_LINE}: " + two_sided_text(mi)
                        + f", mean width {mi['mean_width']:.3g}")
                if "miss_above" in mi:
                    txt += (f", missed above {mi['miss_above']['n']}, below "
                            f"{mi['miss_below']['n']}")
                if "z_level" in mi:       # the statement's own z (its family's level)
                    zl = mi["z_level"]
                    txt += (f", level z mean {zl['mean']:+.2f} sd {zl['sd']:.2f} "
                            f"rms {zl['rms']:.2f}")
            if "max_statement" in it:     # the draft's form beside, labelled
                txt += f"   {MAX_STATEMENT_LINE}: " + two_sided_text(it["max_statement"])
            out.append(txt)
    return out


#: ``gonio validate``'s label of the coverage of E's certified statement, the 95 % interval of
#: max|E_i| (item_coverage ``max_interval``), printed first.
MAX_INTERVAL_LINE = ("E certified: max|E_i|'s 95 % interval (every pattern) holds the "
                     "truth's max|E_i|")
#: ... and of the draft's max|E_i| ± U beside it (item_coverage ``max_statement``; Annex A's
#: form with the budget's largest U), which no certificate states.
MAX_STATEMENT_LINE = ("the draft's Annex A reading max|E_i| +- U (not certified) vs the "
                      "truth's max|E_i|")


def two_sided_text(t: dict) -> str:
    """``CP [lo, hi] %, z mean/sd, flags`` of :func:`gonio.analysis.coverage.two_sided`."""
    z = ("z —" if t["z_sd"] is None else
         f"z mean {t['z_mean']:+.2f} sd {t['z_sd']:.2f}")
    if t.get("spread_judged") is False:
        z += " (fixed condition: spread not judged)"
    flags = f"  FLAG: {', '.join(t['flags'])}" if t["flags"] else ""
    return f"CP95 [{100 * t['cp_low']:.0f}, {100 * t['cp_high']:.0f}] %, {z}{flags}"


@dataclass
class ValidationReport:
    """The validation study: settings and, per case, coverage and diagnosis."""

    settings: dict
    cases: list[CaseResult]

    def to_dict(self) -> dict:
        """Plain dict for ``validation.json`` (deterministic)."""
        return {"gonio_version": __version__, "settings": self.settings,
                "truth_definitions": dict(_TRUTH_DOC),
                "estimators": {"E_i": "mean over the series at point i (gonio.specs.ogam_draft.items)",
                               "E_ij": "single series j at point i (what u(r) describes)"},
                "criterion": "|E - truth| <= U, U = the calibration's own Annex A U (k = 2)",
                "cases": [c.summary for c in self.cases]}

    def table(self) -> str:
        """case, points, trials, coverage of E_i and E_ij, mean |E − truth|, mean U."""
        truth = self.settings["truth"]
        lines = [f"truth: {truth}   criterion |E - truth| <= U (k = 2)",
                 f"{'case':<10}{'budget':<10}{'points':>7}{'trials':>7}{'cov E_i':>16}"
                 f"{'cov E_ij':>16}{'|E_i-T|':>9}{'|E_ij-T|':>9}{'mean U':>8}"]
        for c in self.cases:
            s = c.summary
            rows = [("annex", s["annex_a"][truth], s["mean_U_arcsec"])]
            if "extended" in s:
                rows.append(("+extra", s["extended"][truth], s["mean_U_extended_arcsec"]))
            for label, b, mu in rows:
                ci, cij = b["coverage_E_i"], b["coverage_E_ij"]
                lines.append(
                    f"{c.name:<10}{label:<10}{s['points']:>7}{s['trials']:>7}"
                    f"{100 * ci['fraction']:>8.1f} ± {100 * ci['u_trials']:>4.1f}%"
                    f"{100 * cij['fraction']:>8.1f} ± {100 * cij['u_trials']:>4.1f}%"
                    f"{b['mean_abs_error_E_i_arcsec']:>9.3f}{b['mean_abs_error_E_ij_arcsec']:>9.3f}"
                    f"{mu:>8.3f}")
        lines.append("± : standard error over trials (u_trials); binomial u in the JSON")
        lines += set_aside_lines(self.cases, truth)
        lines += [f"{c.name}: {condition_text(c.summary['condition'])}" for c in self.cases
                  if "condition" in c.summary]
        lines += item_coverage_lines(self.cases)
        lines += monte_carlo_lines(self.cases)
        return "\n".join(lines) + "\n"



def set_aside_lines(cases, truth: str) -> list[str]:
    """One line per case whose calibrations set readings aside: how many of the E_ij
    comparisons (per point), and the coverage of E_ij with each set-aside counted as a miss
    and as a hit (:func:`gonio.analysis.coverage.coverage`), so that a false set-aside, which
    the coverage over the readings used cannot see, is visible."""
    out = []
    for c in cases:
        cij = c.summary["annex_a"][truth]["coverage_E_ij"]
        if not cij.get("set_aside"):
            continue
        out.append(f"{c.name}: E_ij set aside {cij['set_aside']} of "
                   f"{cij['set_aside'] + cij['n']} (per point {cij['set_aside_per_point']}); "
                   f"coverage without them {100 * cij['fraction']:.1f} %, counting them as "
                   f"misses {100 * cij['fraction_set_aside_as_miss']:.1f} %, as hits "
                   f"{100 * cij['fraction_set_aside_as_hit']:.1f} %")
    return out


#: The ``gonio validate`` options this study takes beyond the engine's (``SPEC.coverage.options``).
STUDY_OPTIONS = frozenset({"cases", "truth", "extra_components", "u_scale", "sample_rate_hz",
                           "all_items", "monte_carlo"})


def study_cases(cases: str | Sequence[str]) -> list[str]:
    """The cases asked for: a sequence of names from :data:`CASES`, or the command line's text
    (comma-separated, or ``all``); an unknown one is a GonioError listing them.

    >>> study_cases("default, tilt"), len(study_cases("all")) == len(CASES)
    (['default', 'tilt'], True)
    """
    if isinstance(cases, str):
        cases = list(CASES) if cases.strip() == "all" else \
            [c.strip() for c in cases.split(",") if c.strip()]
    cases = list(cases)
    if not cases:
        raise GonioError("no cases given", key="cases")
    for c in cases:
        if c not in CASES:
            raise GonioError(f"unknown case {c!r} (known: {', '.join(CASES)})", key="cases")
    return cases


def extras_used(extra_components: bool | str | Sequence[str]) -> tuple[str, ...]:
    """The extra budget components to evaluate: True or ``"all"`` every one of
    :data:`EXTRA_SYMBOLS`, False/None none, else the symbols (a sequence or comma-separated).

    >>> extras_used(False), extras_used("all") == EXTRA_SYMBOLS
    ((), True)
    """
    if isinstance(extra_components, str):
        extra_components = True if extra_components.strip() == "all" else \
            [e.strip() for e in extra_components.split(",") if e.strip()]
    if extra_components is True:
        return EXTRA_SYMBOLS
    if not extra_components:
        return ()
    used = tuple(extra_components)
    for e in used:
        if e not in EXTRA_SYMBOLS:
            raise GonioError(f"unknown extra component {e!r} (known: "
                             f"{', '.join(EXTRA_SYMBOLS)})", key="extra_components")
    return used


def _check_options(truth: str, u_scale: float, sample_rate_hz: float, monte_carlo: int) -> None:
    if truth not in TRUTHS:
        raise GonioError(f"unknown truth {truth!r} (known: {', '.join(TRUTHS)})", key="truth")
    if not (math.isfinite(u_scale) and u_scale > 0):
        raise GonioError(f"u_scale must be > 0, got {u_scale}", key="u_scale")
    if not (1.0 <= sample_rate_hz <= 100_000.0):
        raise GonioError(f"--sample-rate-hz must be within 1–100000, got {sample_rate_hz}",
                         key="sample_rate_hz")
    if int(monte_carlo) != monte_carlo or monte_carlo < 0 or monte_carlo == 1:
        raise GonioError(f"--monte-carlo must be 0 or an integer >= 2, got {monte_carlo}",
                         key="monte_carlo")
    check("GONIO_MAX_MONTE_CARLO", monte_carlo, "--monte-carlo", unit="trials")


def study_protocol(protocol: str | Protocol, all_items: bool) -> Protocol:
    """The study's protocol: a Protocol as given, else :func:`validation_protocol`; k = 2
    (the draft's A.7) where it fixes none; 7.1 and 7.4 with at least 2 series required."""
    proto = protocol if isinstance(protocol, Protocol) else \
        validation_protocol(protocol, all_items=all_items)
    if proto.annex_a.coverage_factor is None:        # the study's criterion: the draft's k = 2
        proto = replace(proto, annex_a=replace(proto.annex_a, coverage_factor=2.0))
    if proto.scale_factor is None or proto.angle_deviation is None \
            or proto.angle_deviation.series < 2:
        raise GonioError("validation needs 7.1 and 7.4 with at least 2 series", key="protocol")
    return proto


def study_bench(bench: Bench, sample_rate_hz: float) -> Bench:
    """The bench simulated at the study's ``sample_rate_hz``: the simulation's grid changes,
    the instrument does not. A FOG integrates its rate at the bench file's rate, its own;
    a coarser study grid samples the record more coarsely and leaves the instrument's
    accumulated angle as it is (``integration_rate_hz``, the bench's own rate), instead
    of integrating its rate by rectangles 10× wider (a deterministic angle error up to
    a·dt²/4 = 5.4″ at 60 °/s² and 100 Hz that no real instrument of the bench has).

    >>> b = study_bench(load_bench("fog"), 100.0)
    >>> b.sample_rate_hz, b.instrument.integration_rate_hz
    (100.0, 1000.0)
    """
    inst = bench.instrument
    if inst.integration == "rectangle" and not inst.integration_rate_hz:
        inst = replace(inst, integration_rate_hz=float(bench.sample_rate_hz))
    return replace(bench, instrument=inst, sample_rate_hz=float(sample_rate_hz))


def plan_study(trials: int, *, seed: int = 0, bench: str | Bench = "rlg",
               protocol: str | Protocol = "ogam-draft",
               cases: str | Sequence[str] = ("default",), sample_rate_hz: float = 100.0,
               extra_components: bool | str | Sequence[str] = False,
               truth: str = "systematic", u_scale: float = 1.0, all_items: bool = False,
               monte_carlo: int = 0) -> "OpticalStudy":
    """``SPEC.coverage.study``: the study of ``trials`` independent virtual calibrations per
    case (run by :func:`gonio.pipeline.validate.validate`).

    Parameters
    ----------
    trials, seed : int
        Calibrations per case; master seed (trial seeds from :func:`trial_seeds`).
    bench : str or Bench
        Bench file / built-in name, or a :class:`~gonio.specs.ogam_draft.bench.Bench`.
    protocol : str or Protocol
        A protocol name/path (restricted by :func:`validation_protocol`) or a Protocol
        used as given.
    cases : str or sequence of str
        Names from :data:`CASES` (:func:`study_cases`).
    sample_rate_hz : float
        Simulation rate (default 100 Hz, see the module docstring).
    extra_components : bool, str or sequence of str
        Also evaluate the budget with :func:`budget_extra_components` (:func:`extras_used`).
    truth : str
        The truth of the printed table (all of :data:`TRUTHS` are in the JSON).
    u_scale : float
        Multiplies U (1; < 1 deliberately breaks the budget, to test the study).
    all_items : bool
        Keep 7.3, 7.6 and 7.7 in the protocol, so that every item's coverage is measured
        (summary ``items``, :func:`gonio.specs.ogam_draft.item_coverage.item_coverage`).
    monte_carlo : int
        When > 0, the JCGM 101 Monte Carlo (this many trials, fixed M) of every item
        budget of each case's first calibration, compared with its GUM result (JCGM 101
        8.2; summary ``monte_carlo``, :func:`gonio.specs.ogam_draft.item_coverage.item_monte_carlo`).

    Examples
    --------
    >>> from gonio.pipeline.validate import validate
    >>> from gonio.specs.ogam_draft.bench import Bench, InstrumentConfig, TableConfig
    >>> from gonio.specs.ogam_draft.protocol import parse_protocol
    >>> p = parse_protocol({"protocol": {"name": "tiny"},
    ...     "scale_factor": {"rounds": [{"stop_deg": 90.0}, {"stop_deg": 180.0}], "rest_s": 1.0},
    ...     "angle_deviation": {"series": 2, "rest_s": 1.0,
    ...                         "rounds": [{"stop_deg": 90.0}, {"stop_deg": 180.0}]}})
    >>> b = Bench("ideal", InstrumentConfig(), TableConfig(), sample_rate_hz=20.0)
    >>> r = validate(2, bench=b, protocol=p, cases=["ideal"], sample_rate_hz=20.0, workers=1)
    >>> r.cases[0].summary["annex_a"]["systematic"]["coverage_E_ij"]["fraction"]
    1.0
    """
    _check_options(truth, u_scale, sample_rate_hz, monte_carlo)
    cases = study_cases(cases)
    used = extras_used(extra_components)
    proto = study_protocol(protocol, all_items)
    base = study_bench(bench if isinstance(bench, Bench) else load_bench(bench),
                       sample_rate_hz)
    settings = {"trials": trials, "seed": seed,
                "bench": base.name if isinstance(bench, Bench) else str(bench),
                "cases": cases, "sample_rate_hz": float(sample_rate_hz),
                "protocol": proto.name,
                "protocol_items": ["7.1", f"7.4 x {proto.angle_deviation.series} series (7.5)"]
                + (["7.3", "7.6", "7.7"] if all_items else []),
                "extra_components": list(used), "truth": truth,
                "u_scale": float(u_scale), "monte_carlo_trials": int(monte_carlo),
                "seeding": "numpy SeedSequence(seed, spawn_key=(case index, trial index))"}
    jobs = {name: TrialJob(proto, case_bench(name, base, proto), name, seed, float(u_scale),
                           truth, tuple(used)) for name in cases}
    return OpticalStudy(settings, jobs, proto)


@dataclass
class OpticalStudy:
    """The planned study (:func:`plan_study`), in the form the engine runs: ``settings``
    (validation.json's, and the partial store's identity), ``jobs`` (case → picklable
    :class:`TrialJob`; ``job.run(start, stop)`` → packed arrays), :meth:`unpack` and
    :meth:`report`."""

    settings: dict
    jobs: dict
    protocol: Protocol

    @staticmethod
    def unpack(packed: Mapping) -> dict[int, TrialResult]:
        """Trial index → trial, from one packed batch (:func:`unpack_trials`)."""
        return unpack_trials(packed)

    def report(self, done: dict[str, list]) -> ValidationReport:
        """The report of the finished study: ``done`` case → its trials in trial order."""
        s = self.settings
        out = []
        for name, res in done.items():
            b = self.jobs[name].bench
            intr = pd.DataFrame(run_session(self.protocol, ideal_bench(b), seed=0)
                                .truth["readings"])
            t_int = _matrix(intr[intr["test"] == "angle_deviation"], "systematic_deviation_arcsec")
            cr = CaseResult(name, CASES[name], list(res), t_int)
            cr.summary = _summarise(cr, s["truth"], bool(s["extra_components"]))
            if name in ("worst", "worstcorner"):
                cr.summary["condition"] = fixed_condition(b, self.protocol)
            if s["monte_carlo_trials"]:
                t0 = trial_seed(s["seed"], name, 0)
                cr.summary["monte_carlo"] = _monte_carlo_case(
                    self.protocol, trial_bench(name, b, self.protocol, t0), trial_seed(s["seed"], name, 0), s["monte_carlo_trials"],
                    s["seed"])
            out.append(cr)
        return ValidationReport(s, out)


def _monte_carlo_case(proto: Protocol, bench: Bench, trial_seed_: int, trials: int,
                      seed: int) -> dict:
    """JCGM 101 check of every item budget of the case's first calibration (trial 0)."""
    from gonio.specs.ogam_draft.item_coverage import item_monte_carlo

    res = run_session(proto, bench, seed=trial_seed_)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    rep = analyse(Readings(df, dict(res.metadata)), proto, budget="draft",
                  static_record=res.static_record)
    return {"trials": trials, "trial": 0, "seed": trial_seed_,
            "criterion": "JCGM 101 8.2: d_low, d_high <= delta (u_c to 2 significant digits)",
            "items": item_monte_carlo(rep, trials, seed)}


def monte_carlo_lines(cases) -> list[str]:
    """Per case and item: the JCGM 101 validation of the GUM result (pass/fail, d_low, d_high)."""
    out = []
    for c in cases:
        mc = c.summary.get("monte_carlo")
        if not mc:
            continue
        out += ["", f"JCGM 101 Monte Carlo per item (M = {mc['trials']}, trial 0; GUM interval "
                    "validated when d_low, d_high <= delta)"]
        for name, r in mc["items"].items():
            out.append(f"{c.name:<10}{name:<28}{r['model']:<10}"
                       f"{'pass' if r['passed'] else 'FAIL':<6}d_low {r['d_low']:.3g}  "
                       f"d_high {r['d_high']:.3g}  delta {r['delta']:.2g}"
                       + ("" if r["passed"] else "  (GUM interval contains MC's)"
                          if r["gum_contains_mc"] else "  (GUM interval too short)"))
    return out

