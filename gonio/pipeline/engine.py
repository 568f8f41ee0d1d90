"""How the trials of a study run (``gonio validate``): batches of trials through joblib's
local process pool or its Dask backend, the numerical libraries held to one thread per worker,
the number of workers and the batch size checked before anything starts. Shared by every
study (:mod:`gonio.pipeline.validate`, :mod:`gonio.pipeline.coverage`); nothing here knows
what a trial is.
"""

from __future__ import annotations

import atexit
import contextlib
import os
from typing import Sequence

from gonio.errors import GonioError
from gonio.limits import limit

__all__ = ["MAX_BATCH", "TASKS_PER_WORKER", "WORKER_THREADS", "worker_threads", "batches",
           "available_cores", "execution_backend", "study_workers", "run_parallel",
           "close_clients"]

#: Largest batch (trials per task).
MAX_BATCH = 250
#: Tasks per worker a study is cut into by default (:func:`study_workers`).
TASKS_PER_WORKER = 4


#: Threads each worker's numerical libraries (OpenBLAS, OpenMP) may use while it runs a
#: batch: one, so that N workers use N cores (a trial is single-threaded Python and numpy;
#: a library pool of its own would only compete with the other workers).
WORKER_THREADS = 1

def worker_threads() -> str:
    """The thread pools a batch runs with, as ``library: threads`` (for benchmarks and logs)."""
    from threadpoolctl import threadpool_info, threadpool_limits

    with threadpool_limits(limits=WORKER_THREADS):
        pools = [f"{p['internal_api']}: {p['num_threads']}" for p in threadpool_info()]
    return ", ".join(pools) or "no BLAS/OpenMP thread pool loaded"


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


#: Dask settings of the LocalCluster a study starts (``--scheduler local:N``), given to the
#: scheduler, the nannies and (through the nannies) the worker processes. A trial is a few
#: hundred ms of NumPy and Python holding the GIL; what wakes a worker's event loop while a
#: task runs takes the GIL from it and, on a small machine, a core from another worker:
#:
#: * the statistical profiler (a thread sampling the running task every 10 ms): off, a
#:   trial needs no profile;
#: * the event-loop tick (every 20 ms, only to warn of a blocked loop): 1 s;
#: * the nanny's memory monitor (100 ms) and the system monitor (500 ms, the dashboard's
#:   CPU/memory plots; the dashboard is off): 1 s and 5 s;
#: * ``MALLOC_TRIM_THRESHOLD_=65536``, which Dask's nanny puts in each worker's environment
#:   to give memory back to the system at once: set at all, it also switches off glibc's
#:   dynamic mmap threshold, so every NumPy temporary above 128 KiB is a fresh mmap and its
#:   pages fault in again on every use — the workers spent 3× joblib's system time (2.2 s
#:   against 0.65 s per 16 trials). Not set (None unsets it); a trial's memory is small.
#:
#: Measured on 2 cores (A/B alternated on the same warm machine): the parent's CPU
#: per study (scheduler, nannies, client) fell about 3× with the first three, and the CPU per
#: trial of a 2-worker LocalCluster from 0.54–0.66 s to 0.44 s (joblib's 2 workers: 0.39 s).
#: A cluster given by its address keeps its own settings (its operator can set the same in
#: its Dask configuration).
LOCAL_CLUSTER_CONFIG = {"distributed.worker.profile.enabled": False,
                        "distributed.admin.tick.interval": "1s",
                        "distributed.worker.memory.monitor-interval": "1s",
                        "distributed.admin.system-monitor.interval": "5s",
                        "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}

#: Clients of the Dask schedulers this process has connected to, by address: a study on the
#: same cluster reuses its client and its warmed workers (the cluster warmed
#: once, not per study). Closed when the process exits.
_CLIENTS: dict[str, object] = {}
_WARMED: dict[str, set] = {}


@contextlib.contextmanager
def execution_backend(workers: int, scheduler: str | None):
    """joblib's configuration for the study: yields the ``n_jobs`` to give ``Parallel``.

    ``scheduler=None``: joblib's local process pool with ``workers`` processes
    (1: in this process). ``"local:N"``: a ``distributed.LocalCluster`` of N
    single-threaded worker processes started here; ``"tcp://host:port"`` (or any
    address ``distributed.Client`` accepts): an existing Dask cluster. Both use
    joblib's Dask backend, so the trials run through the same code either way.
    """
    with _backend(workers, scheduler) as (n_jobs, _):
        yield n_jobs


@contextlib.contextmanager
def _backend(workers: int, scheduler: str | None):
    """(n_jobs, worker count) of :func:`execution_backend`; the count is the cluster's
    own for a Dask scheduler (its threads), which sizes the default batch."""
    if scheduler is None:
        yield workers, workers
        return
    try:
        from distributed import Client, LocalCluster
        from joblib import parallel_config
    except ImportError:
        raise GonioError("a Dask scheduler needs the optional extra: pip install 'gonio[dask]'",
                         key="scheduler") from None
    import logging

    import dask

    cluster = None
    if scheduler.startswith("local:"):
        n = scheduler[len("local:"):]
        if not n.isdigit() or int(n) < 1:
            raise GonioError(f"--scheduler local:N needs N >= 1 workers, got {scheduler!r}",
                             key="scheduler")
        with dask.config.set(LOCAL_CLUSTER_CONFIG):
            cluster = LocalCluster(n_workers=int(n), threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.ERROR)
    try:
        client = _client(Client, cluster if cluster is not None else scheduler, scheduler,
                         keep=cluster is None)
        try:
            _warm_workers(client, scheduler)
            with parallel_config(backend="dask", client=client):
                yield -1, max(1, sum(client.nthreads().values()))
        finally:
            if cluster is not None:
                client.close()
    finally:
        if cluster is not None:
            cluster.close()


def check_address(scheduler: str) -> None:
    """A ``scheme://HOST:PORT`` scheduler address has its host and port (``tcp://`` waited
    40 s, then printed a Client.__del__ traceback) — checked before the
    study starts, so no partial study is left to block the corrected rerun."""
    if "://" not in scheduler:
        return
    from urllib.parse import urlsplit

    u = urlsplit(scheduler)
    try:
        port = u.port
    except ValueError:
        port = None
    if not u.hostname or port is None:
        raise GonioError(f"--scheduler {scheduler!r} is not a scheduler address: give "
                         "tcp://HOST:PORT or local:N", key="scheduler")


def _client(Client, address, scheduler: str, keep: bool):
    """A client of ``address``: for an existing cluster (``keep``) the one this process
    already holds when it still answers, else a new one (kept for the next study)."""
    old = _CLIENTS.get(scheduler) if keep else None
    if old is not None:
        try:
            if old.status == "running":
                old.scheduler_info()             # answers: the cluster is still there
                return old
        except Exception:  # noqa: BLE001 - a stale client: connect afresh
            pass
        _forget(scheduler)
    if isinstance(address, str):
        check_address(address)
    try:
        client = Client(address, timeout="20s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise GonioError(f"cannot connect to the Dask scheduler {scheduler!r}: {exc}",
                         key="scheduler") from None
    if keep:
        if not _CLIENTS:
            atexit.register(close_clients)
        _CLIENTS[scheduler] = client
    return client


def _forget(scheduler: str) -> None:
    client = _CLIENTS.pop(scheduler, None)
    _WARMED.pop(scheduler, None)
    if client is not None:
        with contextlib.suppress(Exception):
            client.close()


def close_clients() -> None:
    """Close the clients kept for clusters given by address (call before shutting such a
    cluster down in a process that goes on; done at exit)."""
    for scheduler in list(_CLIENTS):
        _forget(scheduler)


def _warm_worker() -> str:
    """Import what a batch needs (in a Dask worker, once, before the first task): the
    registered specifications (their calibration code and its libraries)."""
    from gonio.specs import available

    available()
    return worker_threads()


def _warm_workers(client, scheduler: str) -> None:
    """Every worker of the cluster imports the trial code once, all at the same time,
    before any task is sent (not each on its first task; a worker already warmed by an
    earlier study of this process is not asked again); a worker that cannot import
    gonio is one clear error, not a traceback per task."""
    workers = set(client.scheduler_info().get("workers", {}))
    warmed = _WARMED.setdefault(scheduler, set())
    if workers and workers <= warmed:
        return
    try:
        client.run(_warm_worker, workers=sorted(workers - warmed) or None)
        warmed |= workers
    except Exception as exc:  # noqa: BLE001 - any worker-side failure, reported in one line
        _WARMED.pop(scheduler, None)
        raise GonioError(f"the Dask workers of {scheduler!r} cannot run gonio "
                         f"({type(exc).__name__}: {str(exc)[:200]}); install gonio there",
                         key="scheduler") from None


def study_workers(trials: int, workers: int | None, scheduler: str | None,
                  batch_size: int | None, cases: int = 1,
                  cluster_workers: int | None = None) -> tuple[int | None, int]:
    """(workers, batch size) of a study.

    ``workers`` default min(2, cores); local workers and a ``local:N`` cluster are capped
    at the machine's cores (``GONIO_MAX_WORKERS`` raises the cap), checked before anything
    starts (``local:100000`` once ran for minutes and ran out of memory). The batch size
    default comes from the trial count and the workers: all ``cases`` × ``trials`` trials
    in about :data:`TASKS_PER_WORKER` tasks per worker (so that the last tasks finish
    together and a slow worker holds little back), at most ``trials`` (batches are per
    case) and :data:`MAX_BATCH`. On a Dask cluster the workers are ``cluster_workers``
    (its own count once connected, :func:`run_parallel`), else the N of ``local:N``
    (2 for an address before connecting). Bad values are GonioErrors. The results never
    depend on either.

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
    if scheduler is not None:
        check_address(scheduler)
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
    n_workers = workers if scheduler is None else (cluster_workers
                                                   or _scheduler_workers(scheduler))
    if batch_size is None:
        per_task = -(-(trials * max(1, cases)) // (TASKS_PER_WORKER * max(1, n_workers)))
        batch_size = max(1, min(MAX_BATCH, trials, per_task))
    if not isinstance(batch_size, int) or batch_size < 1:
        raise GonioError(f"batch size must be an integer >= 1, got {batch_size}",
                         key="batch_size")
    return workers, batch_size


def run_parallel(fn, tasks, workers: int | None, scheduler: str | None):
    """``fn(*task)`` for every task through joblib (:func:`execution_backend`), yielded as
    they finish (unordered: the caller puts them back in trial order). ``tasks``: a list,
    or a function of the number of workers the backend has (a Dask cluster's own count,
    known once connected) giving the list. One local worker (``workers`` 1, no scheduler)
    runs the tasks here, in order, as joblib's sequential backend would, without importing
    joblib (a tenth of a second of a study's fixed cost)."""
    if not callable(tasks) and not tasks:
        return
    if scheduler is None and workers == 1:
        for t in tasks(1) if callable(tasks) else tasks:
            yield fn(*t)
        return
    from joblib import Parallel, delayed

    with _backend(workers, scheduler) as (n_jobs, n_workers):
        if callable(tasks):
            tasks = tasks(n_workers)
            if not tasks:
                return
        run = Parallel(n_jobs=n_jobs, return_as="generator_unordered")
        yield from run(delayed(fn)(*t) for t in tasks)


def _scheduler_workers(scheduler: str) -> int:
    """Workers a scheduler string promises (for the default batch size; 2 if unknown)."""
    if scheduler.startswith("local:") and scheduler[6:].isdigit():
        return max(1, int(scheduler[6:]))
    return 2
