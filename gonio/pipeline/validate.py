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

import contextlib
import hashlib
import io
import json
import math
import os
import re
import shutil
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

from gonio import __version__
from gonio.atomic import write_bytes, write_text
from gonio.bench import Bench, TableConfig, load_bench, run_session
from gonio.bench.config import Harmonic
from gonio.budget.extra import EXTRA_SYMBOLS, budget_extra_components
from gonio.specs.ogam_draft.budget import annex_a_budget
from gonio.pipeline.calibrate import calibrate
from gonio.errors import GonioError
from gonio.units import PPM, deg_to_arcsec
from gonio.formats.readings import Readings
from gonio.limits import limit
from gonio.progress import Progress
from gonio.protocol import Protocol, parse_protocol
from gonio.resources import resolve
from gonio.formats.toml import read_toml
from gonio.pipeline.item_coverage import item_coverage, trial_items

__all__ = ["CASES", "TRUTHS", "validation_protocol", "case_bench", "ideal_bench", "run_trial",
           "TrialResult", "budget_extra_components", "coverage", "binomial_u", "validate",
           "ValidationReport", "trial_seeds", "trial_seed", "spawn_seed", "run_batch", "TrialJob",
           "study_workers", "run_parallel",
           "pack_trials", "unpack_trials", "execution_backend", "PartialStore", "EXTRA_SYMBOLS"]

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
    # the continuous record of the 7.3 rest, as a stream calibration has it (B_s's model)
    rep = calibrate(Readings(df, dict(res.metadata)), protocol, budget="draft",
                    static_record=res.static_record)
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
                       k_mount=float(res.truth["scale_factor_through_mount_counts_per_deg"]),
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


def spawn_seed(seed: int, key: int, index: int) -> int:
    """numpy SeedSequence(seed, spawn_key=(key, index)) as one 32-bit seed: the seed of
    trial ``index`` of study part ``key``, independent of every other trial.

    >>> spawn_seed(0, 0, 4) == trial_seed(0, list(CASES)[0], 4)
    True
    """
    ss = np.random.SeedSequence(seed, spawn_key=(int(key), int(index)))
    return int(ss.generate_state(1, np.uint32)[0])


def trial_seeds(seed: int, case: str, trials: int) -> list[int]:
    """Seeds of the first ``trials`` trials of one case (:func:`trial_seed` by index).

    A case's seeds do not depend on which other cases run, and the first n seeds
    do not depend on the number of trials.

    >>> trial_seeds(0, "default", 3) == trial_seeds(0, "default", 5)[:3]
    True
    """
    return [trial_seed(seed, case, i) for i in range(trials)]


# ----------------------------------------------------------------------------- execution
#
# Trials run in batches (:func:`run_batch`, hundreds of trials per task) through
# joblib: its local process pool by default, or its Dask backend on a
# distributed cluster. Every batch returns its trials packed as arrays
# (:func:`pack_trials`); the parent stores each finished batch atomically in the
# output folder (``.validate-partial/``), so an interrupted study keeps what it
# finished and ``resume`` runs only the trials still missing. Results are put
# back in trial order before anything is summarised: the JSON does not depend on
# the number of workers, the backend, the batching or the order of completion.

#: Largest batch (trials per task).
MAX_BATCH = 250
#: Tasks per worker a study is cut into by default (:func:`study_workers`).
TASKS_PER_WORKER = 4
#: Folder (inside ``--out``) holding the finished batches of a study in progress.
PARTIAL_DIR = ".validate-partial"


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


#: Threads each worker's numerical libraries (OpenBLAS, OpenMP) may use while it runs a
#: batch: one, so that N workers use N cores (a trial is single-threaded Python and numpy;
#: a library pool of its own would only compete with the other workers).
WORKER_THREADS = 1


def run_batch(job: TrialJob, start: int, stop: int) -> dict:
    """Run trials ``start`` … ``stop − 1`` of ``job.case``; returned packed (:func:`pack_trials`).

    The numerical libraries' thread pools are held to :data:`WORKER_THREADS` while the
    batch runs (``threadpoolctl``), in this process as in a pool or Dask worker.
    """
    from threadpoolctl import threadpool_limits

    idx = range(start, stop)
    with threadpool_limits(limits=WORKER_THREADS):
        res = [run_trial(job.protocol, job.bench, trial_seed(job.seed, job.case, i),
                         job.u_scale, job.truth, job.extras_used) for i in idx]
    return pack_trials(job.case, list(idx), res)


def worker_threads() -> str:
    """The thread pools a batch runs with, as ``library: threads`` (for benchmarks and logs)."""
    from threadpoolctl import threadpool_info, threadpool_limits

    with threadpool_limits(limits=WORKER_THREADS):
        pools = [f"{p['internal_api']}: {p['num_threads']}" for p in threadpool_info()]
    return ", ".join(pools) or "no BLAS/OpenMP thread pool loaded"


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


def batches(indices: Sequence[int], size: int) -> list[tuple[int, int]]:
    """Contiguous runs of the sorted ``indices`` cut into (start, stop) pieces of ≤ ``size``.

    >>> batches([0, 1, 2, 3, 4, 7, 8, 9], 3)
    [(0, 3), (3, 5), (7, 10)]
    """
    idx = sorted(int(i) for i in indices)
    out: list[tuple[int, int]] = []
    j = 0
    while j < len(idx):
        k = j
        while k + 1 < len(idx) and idx[k + 1] == idx[k] + 1 and k + 1 - j < size:
            k += 1
        out.append((idx[j], idx[k] + 1))
        j = k + 1
    return out


def available_cores() -> int:
    """CPU cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


@contextlib.contextmanager
def execution_backend(workers: int, scheduler: str | None):
    """joblib's configuration for the study: yields the ``n_jobs`` to give ``Parallel``.

    ``scheduler=None``: joblib's local process pool with ``workers`` processes
    (1: in this process). ``"local:N"``: a ``distributed.LocalCluster`` of N
    single-threaded worker processes started here; ``"tcp://host:port"`` (or any
    address ``distributed.Client`` accepts): an existing Dask cluster. Both use
    joblib's Dask backend, so the trials run through the same code either way.
    """
    if scheduler is None:
        yield workers
        return
    try:
        from distributed import Client, LocalCluster
        from joblib import parallel_config
    except ImportError:
        raise GonioError("a Dask scheduler needs the optional extra: pip install 'gonio[dask]'",
                         key="scheduler") from None
    import logging

    cluster = None
    if scheduler.startswith("local:"):
        n = scheduler[len("local:"):]
        if not n.isdigit() or int(n) < 1:
            raise GonioError(f"--scheduler local:N needs N >= 1 workers, got {scheduler!r}",
                             key="scheduler")
        cluster = LocalCluster(n_workers=int(n), threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.ERROR)
        address = cluster
    else:
        address = scheduler
    try:
        try:
            client = Client(address, timeout="20s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise GonioError(f"cannot connect to the Dask scheduler {scheduler!r}: {exc}",
                             key="scheduler") from None
        try:
            _warm_workers(client, scheduler)
            with parallel_config(backend="dask"):
                yield -1
        finally:
            client.close()
    finally:
        if cluster is not None:
            cluster.close()


def _warm_worker() -> str:
    """Import what a batch needs (in a Dask worker, once, before the first task)."""
    import gonio.pipeline.validate  # noqa: F401  (the trial code and its libraries)
    return worker_threads()


def _warm_workers(client, scheduler: str) -> None:
    """Every worker of the cluster imports the trial code once, all at the same time,
    before any task is sent (not each on its first task); a worker that cannot import
    gonio is one clear error, not a traceback per task."""
    try:
        client.run(_warm_worker)
    except Exception as exc:  # noqa: BLE001 - any worker-side failure, reported in one line
        raise GonioError(f"the Dask workers of {scheduler!r} cannot run gonio "
                         f"({type(exc).__name__}: {str(exc)[:200]}); install gonio there",
                         key="scheduler") from None


def study_workers(trials: int, workers: int | None, scheduler: str | None,
                  batch_size: int | None, cases: int = 1) -> tuple[int | None, int]:
    """(workers, batch size) of a study.

    ``workers`` default min(2, cores); local workers and a ``local:N`` cluster are capped
    at the machine's cores (``GONIO_MAX_WORKERS`` raises the cap), checked before anything
    starts (``local:100000`` once ran for minutes and ran out of memory). The batch size
    default comes from the trial count and the workers: all ``cases`` × ``trials`` trials
    in about :data:`TASKS_PER_WORKER` tasks per worker (so that the last tasks finish
    together and a slow worker holds little back), at most ``trials`` (batches are per
    case) and :data:`MAX_BATCH`. Bad values are GonioErrors. The results never depend on
    either.

    >>> study_workers(320, 1, None, None)           # one worker: 4 tasks of 80
    (1, 80)
    >>> study_workers(320, 1, None, None, cases=5)  # 1600 trials: batches capped at 250
    (1, 250)
    """
    if os.environ.get("GONIO_MAX_WORKERS", "").strip():
        cap = limit("GONIO_MAX_WORKERS")
        cap_note = f"GONIO_MAX_WORKERS = {cap:g}"
    else:
        cap = available_cores()
        cap_note = f"this machine's {cap} cores"
    if scheduler is None:
        if workers is None:
            workers = min(2, available_cores())
        if not isinstance(workers, int) or workers < 1:
            raise GonioError(f"--workers must be an integer >= 1, got {workers}", key="workers")
        if workers > cap:
            raise GonioError(f"--workers {workers} exceeds {cap_note} (set GONIO_MAX_WORKERS "
                             "to raise the cap, or give --scheduler tcp://... to run on a "
                             "cluster)", key="workers")
    elif scheduler.startswith("local:"):
        n = scheduler[len("local:"):]
        if not (n.isdigit() and len(n) <= 9) or int(n) < 1:
            raise GonioError(f"--scheduler local:N needs N >= 1 workers, got {scheduler!r}",
                             key="scheduler")
        if int(n) > cap:
            raise GonioError(f"--scheduler {scheduler}: {int(n)} worker processes exceed "
                             f"{cap_note} (set GONIO_MAX_WORKERS to raise the cap)",
                             key="scheduler")
    n_workers = workers if scheduler is None else _scheduler_workers(scheduler)
    if batch_size is None:
        per_task = -(-(trials * max(1, cases)) // (TASKS_PER_WORKER * max(1, n_workers)))
        batch_size = max(1, min(MAX_BATCH, trials, per_task))
    if not isinstance(batch_size, int) or batch_size < 1:
        raise GonioError(f"batch size must be an integer >= 1, got {batch_size}",
                         key="batch_size")
    return workers, batch_size


def run_parallel(fn, tasks: list[tuple], workers: int | None, scheduler: str | None):
    """``fn(*task)`` for every task through joblib (:func:`execution_backend`), yielded as
    they finish (unordered: the caller puts them back in trial order)."""
    if not tasks:
        return
    from joblib import Parallel, delayed

    with execution_backend(workers, scheduler) as n_jobs:
        run = Parallel(n_jobs=n_jobs, return_as="generator_unordered")
        yield from run(delayed(fn)(*t) for t in tasks)


def _fingerprint(job_settings: dict) -> str:
    return hashlib.sha256(repr(sorted(job_settings.items())).encode()).hexdigest()


#: What a batch file is named: ``<case>_<first trial>_<stop>.npz`` (10-digit indices).
BATCH_NAME = re.compile(r"^(?P<case>.+)_(?P<start>[0-9]{10})_(?P<stop>[0-9]{10})\.npz$")


def batch_digest(packed: Mapping) -> str:
    """SHA-256 over a batch's arrays (names, dtypes, shapes, bytes) in name order; stored in
    the batch (``digest``) so that an edited value is found even without ``study.json``."""
    h = hashlib.sha256()
    for k in sorted(packed):
        if k == "digest":
            continue
        a = np.ascontiguousarray(packed[k])
        h.update(f"{k}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


class PartialStore:
    """Finished batches of a study, one ``.npz`` file each, written atomically.

    ``study.json`` records the settings' fingerprint (seed included) and every batch
    written: its case, trial range and the SHA-256 of its bytes. Each batch also carries the
    fingerprint and a digest of its arrays. ``resume`` reuses a batch only when all agree
    (:meth:`load_batch`): a batch of another study, edited, reordered, truncated or empty,
    a FIFO or any non-regular file in its place, is refused with its name — never waited
    on, never silently mixed in.
    """

    def __init__(self, folder: Path, fingerprint: str, describe: dict):
        self.folder = Path(folder)
        self.fingerprint = fingerprint
        self.describe = describe
        self.batches: dict[str, dict] = {}

    def exists(self) -> bool:
        return (self.folder / "study.json").exists()

    def _write_head(self) -> None:
        write_text(self.folder / "study.json",
                   json.dumps({"fingerprint": self.fingerprint, "settings": self.describe,
                               "batches": self.batches}, indent=2, sort_keys=True) + "\n")

    def _head(self, head: Path) -> dict:
        from gonio.errors import check_input_file

        check_input_file(head, "partial study record")       # a FIFO is refused, not read
        try:
            info = json.loads(head.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise GonioError(f"unreadable partial study: {exc}", file=head) from None
        if not isinstance(info, dict) or not isinstance(info.get("fingerprint"), str) or \
                not isinstance(info.get("batches", {}), dict):
            raise GonioError("not a partial-study record (expected an object with the study's "
                             f"fingerprint and batches); remove {self.folder}", file=head)
        return info

    def open(self, resume: bool) -> dict[str, dict[int, TrialResult]]:
        """Create the store, or (``resume``) load what it holds: case → {index: trial}."""
        head = self.folder / "study.json"
        done: dict[str, dict[int, TrialResult]] = {}
        if os.path.lexists(head):
            if not resume:
                raise GonioError(f"{self.folder.parent} holds an unfinished study; give --resume "
                                 f"to continue it, or remove {self.folder}", key="resume")
            info = self._head(head)
            if info["fingerprint"] != self.fingerprint:
                raise GonioError("the unfinished study here was started with other settings "
                                 f"({info.get('settings')}); resume it with those, or remove "
                                 f"{self.folder}", file=head, key="resume")
            self.batches = {k: v for k, v in info.get("batches", {}).items()
                            if isinstance(v, dict)}
            for f in sorted(self.folder.iterdir()):
                if f.name == "study.json" or f.name.startswith(".gonio-"):
                    continue                         # the record; a killed write's temporary
                case, got = self.load_batch(f)
                for i, tr in got.items():
                    done.setdefault(case, {}).setdefault(i, tr)
            return done
        self._write_head()
        return done

    def load_batch(self, f: Path) -> tuple[str, dict[int, TrialResult]]:
        """(case, trials) of one batch file, every check of the class docstring made."""
        import stat
        import zipfile

        def bad(why: str) -> GonioError:
            return GonioError(f"partial batch refused: {why}; remove it (its trials are run "
                              "again) or the whole folder", file=f)

        st = os.lstat(f)
        if not stat.S_ISREG(st.st_mode):
            raise bad("not a regular file (a FIFO, link, device or folder)")
        m = BATCH_NAME.match(f.name)
        if m is None:
            raise bad("not a batch of this study (name <case>_<start>_<stop>.npz)")
        data = f.read_bytes()
        try:
            with np.load(io.BytesIO(data), allow_pickle=False) as z:
                packed = {k: z[k] for k in z.files}
        except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as exc:
            raise bad(f"unreadable (truncated or damaged: {str(exc)[:80]})") from None
        if str(packed.get("fingerprint", "")) != self.fingerprint:
            raise bad("written by another study (other settings, seed or gonio version)")
        rec = self.batches.get(f.name)
        if rec is not None and rec.get("sha256") != hashlib.sha256(data).hexdigest():
            raise bad("its bytes differ from the checksum study.json recorded (edited or "
                      "replaced)")
        if str(packed.get("digest", "")) != batch_digest(packed):
            raise bad("its values differ from its digest (edited)")
        start, stop = int(m["start"]), int(m["stop"])
        idx = packed.get("index")
        if stop <= start or str(packed.get("case")) != m["case"] or idx is None or \
                idx.shape != (stop - start,) or not np.array_equal(idx, np.arange(start, stop)):
            raise bad("its trials are not the range its name says (reordered, renamed, "
                      "truncated or empty)")
        try:
            got = unpack_trials(packed)
        except (KeyError, IndexError, ValueError, TypeError) as exc:
            raise bad(f"incomplete ({type(exc).__name__})") from None
        if rec is None:                       # written, then killed before study.json was
            self.batches[f.name] = {"sha256": hashlib.sha256(data).hexdigest(),
                                    "case": m["case"], "start": start, "stop": stop}
        return m["case"], got

    def save(self, packed: dict) -> None:
        """Store one finished batch (atomic: the file is complete or absent), then record it
        with its checksum in ``study.json``."""
        idx = packed["index"]
        name = f"{packed['case']}_{int(idx[0]):010d}_{int(idx[-1]) + 1:010d}.npz"
        packed = {**packed, "fingerprint": np.array(self.fingerprint)}
        packed["digest"] = np.array(batch_digest(packed))
        buf = io.BytesIO()
        np.savez(buf, **packed)
        data = buf.getvalue()
        write_bytes(self.folder / name, data)
        self.batches[name] = {"sha256": hashlib.sha256(data).hexdigest(),
                              "case": str(packed["case"]), "start": int(idx[0]),
                              "stop": int(idx[-1]) + 1}
        self._write_head()

    def remove(self) -> None:
        """Drop the store (the study is complete)."""
        shutil.rmtree(self.folder, ignore_errors=True)


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
        "items": item_coverage([t.items for t in tr],
                               np.asarray(case.truth_intrinsic).mean(axis=0)),
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
                txt += f"   interval {100 * it['interval_holds_truth']['fraction']:5.1f}%"
            if "within_U_intrinsic" in it:
                txt += (f"   vs intrinsic truth "
                        f"{100 * it['within_U_intrinsic']['fraction']:5.1f}%")
            if "two_sided" in it:
                txt += "   " + two_sided_text(it["two_sided"])
            out.append(txt)
    return out


def two_sided_text(t: dict) -> str:
    """``CP [lo, hi] %, z mean/sd, flags`` of :func:`gonio.pipeline.item_coverage.two_sided`."""
    z = ("z —" if t["z_sd"] is None else
         f"z mean {t['z_mean']:+.2f} sd {t['z_sd']:.2f}")
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
        lines += item_coverage_lines(self.cases)
        lines += monte_carlo_lines(self.cases)
        return "\n".join(lines) + "\n"


def validate(trials: int, *, seed: int = 0, bench: str | Bench = "rlg",
             cases: Sequence[str] = ("default",), sample_rate_hz: float = 100.0,
             protocol: str | Protocol = "ogam-draft",
             extra_components: bool | Sequence[str] = False,
             truth: str = "systematic", u_scale: float = 1.0, workers: int | None = None,
             scheduler: str | None = None, batch_size: int | None = None,
             partial_dir: str | Path | None = None, resume: bool = False,
             show_progress: bool = True, all_items: bool = False,
             monte_carlo: int = 0) -> ValidationReport:
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
    workers : int, optional
        Local processes (1: in this process; default min(2, cores); at most the
        machine's cores). Ignored with ``scheduler``. Results do not depend on it.
    scheduler : str, optional
        Run on a Dask cluster: ``"tcp://host:8786"`` (an existing scheduler; gonio
        must be installed on its workers) or ``"local:N"`` (start a
        ``distributed.LocalCluster`` of N processes). Needs ``gonio[dask]``.
        Results do not depend on it.
    batch_size : int, optional
        Trials per task (default: up to :data:`MAX_BATCH`, at least 4 tasks per
        worker). Results do not depend on it.
    partial_dir : path, optional
        Folder where every finished batch is stored atomically as it completes
        (the CLI uses ``OUT/.validate-partial``); removed once the study is
        complete. An interrupted study keeps what it finished there.
    resume : bool
        Load the finished trials from ``partial_dir`` (same settings required) and
        run only the missing ones.
    all_items : bool
        Keep 7.3, 7.6 and 7.7 in the protocol, so that every item's coverage is measured
        (summary ``items``, :func:`gonio.pipeline.item_coverage.item_coverage`).
    monte_carlo : int
        When > 0, the JCGM 101 Monte Carlo (this many trials, fixed M) of every item
        budget of each case's first calibration, compared with its GUM result (JCGM 101
        8.2; summary ``monte_carlo``, :func:`gonio.pipeline.item_coverage.item_monte_carlo`).

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
    if int(monte_carlo) != monte_carlo or monte_carlo < 0 or monte_carlo == 1:
        raise GonioError(f"--monte-carlo must be 0 or an integer >= 2, got {monte_carlo}",
                         key="monte_carlo")
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
    proto = protocol if isinstance(protocol, Protocol) else \
        validation_protocol(protocol, all_items=all_items)
    if proto.annex_a.coverage_factor is None:        # the study's criterion: the draft's k = 2
        proto = replace(proto, annex_a=replace(proto.annex_a, coverage_factor=2.0))
    if proto.scale_factor is None or proto.angle_deviation is None \
            or proto.angle_deviation.series < 2:
        raise GonioError("validation needs 7.1 and 7.4 with at least 2 series", key="protocol")
    base = bench if isinstance(bench, Bench) else load_bench(bench)
    base = replace(base, sample_rate_hz=float(sample_rate_hz))
    workers, batch_size = study_workers(trials, workers, scheduler, batch_size, len(cases))
    settings = {"trials": trials, "seed": seed,
                "bench": base.name if isinstance(bench, Bench) else str(bench),
                "cases": cases, "sample_rate_hz": float(sample_rate_hz),
                "protocol": proto.name,
                "protocol_items": ["7.1", f"7.4 x {proto.angle_deviation.series} series (7.5)"]
                + (["7.3", "7.6", "7.7"] if all_items else []),
                "extra_components": list(extras_used), "truth": truth,
                "u_scale": float(u_scale), "monte_carlo_trials": int(monte_carlo),
                "seeding": "numpy SeedSequence(seed, spawn_key=(case index, trial index))"}
    jobs = {name: TrialJob(proto, case_bench(name, base, proto), name, seed, float(u_scale),
                           truth, tuple(extras_used)) for name in cases}
    done: dict[str, dict[int, TrialResult]] = {name: {} for name in cases}
    store = None
    if partial_dir is not None:
        ident = {k: v for k, v in settings.items() if k != "trials"}
        ident.update(gonio=__version__, jobs=[repr(j) for j in jobs.values()])
        store = PartialStore(Path(partial_dir), _fingerprint(ident),
                             {k: v for k, v in settings.items() if k != "trials"})
        for name, got in store.open(resume).items():
            if name in done:
                done[name].update({i: t for i, t in got.items() if i < trials})
    elif resume:
        raise GonioError("--resume needs --out (the folder of the interrupted study)",
                         key="resume")
    tasks = [(jobs[name], a, b) for name in cases
             for a, b in batches([i for i in range(trials) if i not in done[name]], batch_size)]
    total = trials * len(cases)
    already = sum(len(d) for d in done.values())
    prog = Progress(total, label="validate: trials", done=already,
                    force=False) if show_progress else None
    try:
        for packed in run_parallel(run_batch, tasks, workers, scheduler):
            if store is not None:
                store.save(packed)
            got = unpack_trials(packed)
            done[str(packed["case"])].update(got)
            if prog is not None:
                prog.update(len(got))
    finally:
        if prog is not None:
            prog.close()
    out = []
    for name in cases:
        b = jobs[name].bench
        intr = run_session(proto, ideal_bench(b), seed=0).truth["readings"]
        intr = pd.DataFrame(intr)
        t_int = _matrix(intr[intr["test"] == "angle_deviation"], "systematic_deviation_arcsec")
        res = [done[name][i] for i in range(trials)]
        cr = CaseResult(name, CASES[name], res, t_int)
        cr.summary = _summarise(cr, truth, bool(extras_used))
        if monte_carlo:
            cr.summary["monte_carlo"] = _monte_carlo_case(proto, b, trial_seed(seed, name, 0),
                                                          int(monte_carlo), seed)
        out.append(cr)
    return ValidationReport(settings, out)


def _monte_carlo_case(proto: Protocol, bench: Bench, trial_seed_: int, trials: int,
                      seed: int) -> dict:
    """JCGM 101 check of every item budget of the case's first calibration (trial 0)."""
    from gonio.pipeline.item_coverage import item_monte_carlo

    res = run_session(proto, bench, seed=trial_seed_)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    rep = calibrate(Readings(df, dict(res.metadata)), proto, budget="draft",
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


def _scheduler_workers(scheduler: str) -> int:
    """Workers a scheduler string promises (for the default batch size; 2 if unknown)."""
    if scheduler.startswith("local:") and scheduler[6:].isdigit():
        return max(1, int(scheduler[6:]))
    return 2
