"""Validation of the draft's Annex A budget against the truth of many virtual calibrations.

Contents
--------
:func:`validation_protocol`   the draft's protocol restricted to what E and U need (7.1, 7.4/7.5)
:data:`CASES`, :func:`case_bench`   the default bench and the named stress cases
:func:`run_trial`             one virtual calibration: E_ij, E_i, truth, U (Annex A)
:func:`gonio.budget.extra.budget_extra_components` (used here) extra budget lines the annex lacks (off by default)
:func:`coverage`, :func:`binomial_u`    coverage fraction and its uncertainty
:func:`validate`              N trials per case → :class:`ValidationReport` (``to_dict`` → JSON)

The question asked (issue 3): a calibration on the virtual bench states, at each
calibration point i, E_i (mean over the 10 series of 7.4/7.5, as
:mod:`gonio.specs.ogam_draft.items` computes it) with the expanded uncertainty U of Annex A
(k = 2, u(r) from the calibration's own 7.5 data). How often is |E_i − truth_i| ≤ U?
Also for each single series E_ij, which is what the Annex A budget (u(r) of a single
reading) actually describes. A budget that holds covers ≈ 95 % or more.

Truth definitions (all from the bench's noise-free rerun, :func:`gonio.bench.run_session`):

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
200 trials under two minutes on two cores.
"""

from __future__ import annotations

import math
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from typing import Sequence

import numpy as np
import pandas as pd

from gonio import __version__
from gonio.bench import Bench, TableConfig, load_bench, run_session
from gonio.bench.config import Harmonic
from gonio.budget.extra import EXTRA_SYMBOLS, budget_extra_components
from gonio.specs.ogam_draft.budget import annex_a_budget
from gonio.pipeline.calibrate import calibrate
from gonio.errors import GonioError
from gonio.units import PPM, deg_to_arcsec
from gonio.formats.readings import Readings
from gonio.progress import progress
from gonio.protocol import Protocol, parse_protocol
from gonio.resources import resolve
from gonio.formats.toml import read_toml

__all__ = ["CASES", "TRUTHS", "validation_protocol", "case_bench", "ideal_bench", "run_trial",
           "TrialResult", "budget_extra_components", "coverage", "binomial_u", "validate",
           "ValidationReport", "trial_seeds", "EXTRA_SYMBOLS"]

#: Stress cases: name → what is changed (see :func:`case_bench`).
CASES = {
    "default": "the bench as loaded (inside the budget's assumptions)",
    "tilt": "sensing plane tilted at the Annex A.1 bound (tilt_deg = annex_a.tilt_bound_deg)",
    "drift": "Gauss-Markov bias instability sigma = 0.005/sqrt(2) deg/h, tau = 300 s: the "
             "bias change since the Earth-rate compensation has an RMS of 0.005 deg/h (A.4.3 bound)",
    "table": "table positioning harmonics scaled so that sum |a_h| = table MPE (A.4.1 bound), "
             "random scatter off",
    "ideal": "no noise, no tilt, no bias, no harmonics, error-free table (sanity check)",
}


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


def validation_protocol(protocol: str = "ogam-draft") -> Protocol:
    """The protocol restricted to what E and U need: 7.1 and 7.4 (10 series, 7.5).

    7.3, 7.6 and 7.7 are dropped (they do not enter E_i or its Annex A budget);
    timings, rests and the Earth-rate compensation of the draft are kept.

    >>> p = validation_protocol()
    >>> p.zero_stability is None, p.rate_consistency, p.angle_deviation.series
    (True, (), 10)
    """
    raw = read_toml(resolve(protocol, "protocol"))
    for key in ("zero_stability", "rate_consistency", "pointing_consistency"):
        raw.pop(key, None)
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
    raise GonioError(f"unknown case {case!r} (known: {', '.join(CASES)})", key="cases")


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


def _matrix(df: pd.DataFrame, col: str) -> np.ndarray:
    return df.pivot(index="series", columns="round", values=col).sort_index().sort_index(
        axis=1).to_numpy(dtype=float)


def run_trial(protocol: Protocol, bench: Bench, seed: int, u_scale: float = 1.0,
              truth: str = "systematic", extras_used: Sequence[str] = EXTRA_SYMBOLS
              ) -> TrialResult:
    """One virtual calibration on ``bench``: session, calibration, Annex A U, truth.

    U is the calibration's own Annex A U (k = 2, u(r) from its 7.5 data), times
    ``u_scale`` (1 except to test the validation's power); ``U_extended_arcsec``
    adds the :func:`budget_extra_components` named in ``extras_used``.
    """
    res = run_session(protocol, bench, seed=seed)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    rep = calibrate(Readings(df, dict(res.metadata)), protocol)
    ad = rep.results.angle_deviation.tables["readings"]
    e = _matrix(ad, "E_arcsec")
    pos = ad.groupby("round")["table_deg"].mean().sort_index().to_numpy(dtype=float)
    tr = pd.DataFrame(res.truth["readings"])
    tr = tr[tr["test"] == "angle_deviation"]
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
                       k_mount=float(res.truth["scale_factor_through_mount_counts_per_deg"]),
                       extras=[(c.symbol, c.half_width_arcsec, c.distribution) for c in extras])


def _run_trial_args(args):
    return run_trial(*args)


def trial_seeds(seed: int, case: str, trials: int) -> list[int]:
    """Seeds of the trials of one case: numpy SeedSequence(seed, spawn_key=(case index,)).

    A case's seeds do not depend on which other cases run, and the first n seeds
    do not depend on the number of trials.

    >>> trial_seeds(0, "default", 3) == trial_seeds(0, "default", 5)[:3]
    True
    """
    key = list(CASES).index(case)
    ss = np.random.SeedSequence(seed, spawn_key=(key,))
    return [int(c.generate_state(1, np.uint32)[0]) for c in ss.spawn(trials)]


def binomial_u(p: float, n: int) -> float:
    """Standard uncertainty of a coverage fraction p from n independent Bernoulli trials.

    u = √(p(1 − p)/n) (binomial distribution); for the clustered comparisons of a
    validation this is a lower bound (see ``u_trials`` in :func:`coverage`).

    >>> round(binomial_u(0.95, 200), 5)
    0.01541
    """
    return math.sqrt(p * (1.0 - p) / n) if n > 0 else math.nan


def coverage(abs_err: np.ndarray, U: np.ndarray) -> dict:
    """Coverage of |E − truth| ≤ U; axis 0 = trials, further axes pooled.

    Returns the overall fraction, its binomial u (:func:`binomial_u`, as if every
    comparison were independent), ``u_trials`` (standard error of the mean of the
    per-trial fractions: accounts for the correlation within a trial), the number
    of comparisons, and the fraction per point (last axis).

    >>> c = coverage(np.array([[0.1, 0.5], [0.2, 0.1]]), np.array([0.3, 0.3]))
    >>> c["fraction"], c["n"], c["per_point"]
    (0.75, 4, [1.0, 0.5])
    """
    a = np.asarray(abs_err, dtype=float)
    u = np.asarray(U, dtype=float).reshape((-1,) + (1,) * (a.ndim - 1))
    hit = a <= u
    p = float(hit.mean())
    per_trial = hit.reshape(hit.shape[0], -1).mean(axis=1)
    t = per_trial.size
    u_tr = float(per_trial.std(ddof=1) / math.sqrt(t)) if t > 1 else math.nan
    per_point = hit.reshape(-1, hit.shape[-1]).mean(axis=0)
    return {"fraction": p, "u_binomial": binomial_u(p, hit.size), "u_trials": u_tr,
            "n": int(hit.size), "per_point": [float(x) for x in per_point]}


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
    Ei = E.mean(axis=1)

    def block(Uv):
        out = {}
        for name, T in truths.items():
            Ti = T.mean(axis=1)
            d_i, d_ij = Ei - Ti, E - T
            out[name] = {
                "coverage_E_i": coverage(np.abs(d_i), Uv),
                "coverage_E_ij": coverage(np.abs(d_ij), Uv),
                "mean_abs_error_E_i_arcsec": float(np.abs(d_i).mean()),
                "mean_abs_error_E_ij_arcsec": float(np.abs(d_ij).mean()),
                "bias_E_i_per_point_arcsec": [float(x) for x in d_i.mean(axis=0)],
                "std_E_i_per_point_arcsec": [float(x) for x in d_i.std(axis=0, ddof=1)]
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
        return "\n".join(lines) + "\n"


def _quiet_worker() -> None:
    """A worker leaves SIGINT to the parent (which stops the pool and prints one line) and
    dies quietly on SIGTERM: no traceback from a worker on an interrupt."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def validate(trials: int, *, seed: int = 0, bench: str | Bench = "rlg",
             cases: Sequence[str] = ("default",), sample_rate_hz: float = 100.0,
             protocol: str | Protocol = "ogam-draft",
             extra_components: bool | Sequence[str] = False,
             truth: str = "systematic", u_scale: float = 1.0, workers: int = 2,
             show_progress: bool = True) -> ValidationReport:
    """Run ``trials`` independent virtual calibrations per case and measure coverage.

    Parameters
    ----------
    trials : int
        Calibrations per case (≥ 2).
    seed : int
        Master seed; trial seeds from :func:`trial_seeds` (same seed → same JSON).
    bench : str or Bench
        Bench file / built-in name, or a :class:`~gonio.bench.Bench`.
    cases : sequence of str
        Names from :data:`CASES`.
    sample_rate_hz : float
        Simulation rate (default 100 Hz, see the module docstring).
    protocol : str or Protocol
        A protocol name/path (restricted by :func:`validation_protocol`) or a Protocol
        used as given.
    extra_components : bool or sequence of str
        Also evaluate the budget with :func:`budget_extra_components` (True: all of
        :data:`EXTRA_SYMBOLS`; or the symbols to add).
    truth : str
        The truth of the printed table (all of :data:`TRUTHS` are in the JSON).
    u_scale : float
        Multiplies U (1; < 1 deliberately breaks the budget, to test the study).
    workers : int
        Processes (1: in this process). Results do not depend on it.

    Examples
    --------
    >>> from gonio.bench import Bench, InstrumentConfig
    >>> from gonio.protocol import parse_protocol
    >>> p = parse_protocol({"protocol": {"name": "tiny"},
    ...     "scale_factor": {"rounds": [{"stop_deg": 90.0}, {"stop_deg": 180.0}], "rest_s": 1.0},
    ...     "angle_deviation": {"series": 2, "rest_s": 1.0,
    ...                         "rounds": [{"stop_deg": 90.0}, {"stop_deg": 180.0}]}})
    >>> b = Bench("ideal", InstrumentConfig(), TableConfig(), sample_rate_hz=20.0)
    >>> r = validate(2, bench=b, protocol=p, cases=["ideal"], sample_rate_hz=20.0, workers=1)
    >>> r.cases[0].summary["annex_a"]["systematic"]["coverage_E_ij"]["fraction"]
    1.0
    """
    if not isinstance(trials, int) or trials < 2:
        raise GonioError(f"--trials must be an integer >= 2, got {trials}", key="trials")
    if seed < 0:
        raise GonioError(f"--seed must be >= 0, got {seed}", key="seed")
    if truth not in TRUTHS:
        raise GonioError(f"unknown truth {truth!r} (known: {', '.join(TRUTHS)})", key="truth")
    if not (math.isfinite(u_scale) and u_scale > 0):
        raise GonioError(f"u_scale must be > 0, got {u_scale}", key="u_scale")
    if not (1.0 <= sample_rate_hz <= 100_000.0):
        raise GonioError(f"--sample-rate-hz must be within 1–100000, got {sample_rate_hz}",
                         key="sample_rate_hz")
    cases = list(cases)
    if not cases:
        raise GonioError("no cases given", key="cases")
    for c in cases:
        if c not in CASES:
            raise GonioError(f"unknown case {c!r} (known: {', '.join(CASES)})", key="cases")
    if extra_components is True:
        extras_used = EXTRA_SYMBOLS
    elif not extra_components:
        extras_used = ()
    else:
        extras_used = tuple(extra_components)
        for e in extras_used:
            if e not in EXTRA_SYMBOLS:
                raise GonioError(f"unknown extra component {e!r} (known: "
                                 f"{', '.join(EXTRA_SYMBOLS)})", key="extra_components")
    proto = protocol if isinstance(protocol, Protocol) else validation_protocol(protocol)
    if proto.scale_factor is None or proto.angle_deviation is None \
            or proto.angle_deviation.series < 2:
        raise GonioError("validation needs 7.1 and 7.4 with at least 2 series", key="protocol")
    base = bench if isinstance(bench, Bench) else load_bench(bench)
    base = replace(base, sample_rate_hz=float(sample_rate_hz))
    out = []
    for name in cases:
        b = case_bench(name, base, proto)
        intr = run_session(proto, ideal_bench(b), seed=0).truth["readings"]
        intr = pd.DataFrame(intr)
        t_int = _matrix(intr[intr["test"] == "angle_deviation"], "systematic_deviation_arcsec")
        seeds = trial_seeds(seed, name, trials)
        tasks = [(proto, b, s, u_scale, truth, extras_used) for s in seeds]
        it_label = f"validate {name}"
        if workers > 1:
            ex = ProcessPoolExecutor(max_workers=workers, initializer=_quiet_worker)
            try:
                res = list(progress(ex.map(_run_trial_args, tasks, chunksize=4), total=trials,
                                    label=it_label) if show_progress else
                           ex.map(_run_trial_args, tasks, chunksize=4))
            except BaseException:          # an interrupt: drop the queued trials, stop soon
                ex.shutdown(wait=True, cancel_futures=True)
                raise
            ex.shutdown(wait=True)
        else:
            gen = (run_trial(*t) for t in tasks)
            res = list(progress(gen, total=trials, label=it_label) if show_progress else gen)
        cr = CaseResult(name, CASES[name], res, t_int)
        cr.summary = _summarise(cr, truth, bool(extras_used))
        out.append(cr)
    settings = {"trials": trials, "seed": seed,
                "bench": base.name if isinstance(bench, Bench) else str(bench),
                "cases": cases, "sample_rate_hz": float(sample_rate_hz),
                "protocol": proto.name,
                "protocol_items": ["7.1", f"7.4 x {proto.angle_deviation.series} series (7.5)"],
                "extra_components": list(extras_used), "truth": truth,
                "u_scale": float(u_scale),
                "seeding": "numpy SeedSequence(seed, spawn_key=(case index,)).spawn(trials)"}
    return ValidationReport(settings, out)
