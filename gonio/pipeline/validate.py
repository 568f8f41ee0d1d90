"""The engine of ``gonio validate``: any specification's coverage study, run in batches of
trials on joblib or Dask, kept as it finishes, resumed where it stopped. Nothing here names a
specification: it finds the study through the registry (``SPEC.coverage``).

Contents
--------
:func:`validate`              N trials per part of a specification's study → its report
                              (``to_dict`` → validation.json, ``table`` → the printed table)
:func:`run_batch`, :func:`run_parallel`, :func:`study_workers`, :func:`batches`
                              the execution: batches of trials through joblib or Dask
:class:`PartialStore`         finished batches kept atomically; ``resume`` reuses them
:func:`spawn_seed`            trial i of part k seeded by SeedSequence(seed, spawn_key=(k, i))
:func:`coverage`, :func:`binomial_u`    coverage fraction and its uncertainty
                              (:mod:`gonio.analysis.coverage`, the statistics every study uses)

Two kinds of study (``SPEC.coverage.engine``):

``"items"``
    the generic item study of :mod:`gonio.pipeline.coverage`: ``SPEC.run_trial`` simulates,
    ``SPEC.calibrate`` calibrates, each item's U is checked against ``SPEC.truth``.
``"cases"``
    a study the specification describes itself (``SPEC.coverage.study``, e.g. the optical
    draft's Annex A budget over bench cases): ``study(trials, seed=…, bench=…,
    protocol=…, **options)`` returns an object with ``settings`` (a dict), ``jobs`` (part
    name → a picklable job whose ``run(start, stop)`` returns the trials packed as arrays,
    ``case`` and ``index`` among them), ``unpack(packed)`` → {trial index: trial} and
    ``report(done)`` → the report (``done``: part → its trials in trial order).
    docs/writing-a-specification.md has the whole protocol.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import re
import shutil
from pathlib import Path
from typing import Callable, Mapping

import numpy as np

from gonio import __version__
from gonio.analysis.coverage import binomial_u, coverage, spawn_seed
from gonio.atomic import write_bytes, write_text
from gonio.errors import GonioError
from gonio.pipeline.engine import (MAX_BATCH, TASKS_PER_WORKER, WORKER_THREADS,  # noqa: F401
                                   available_cores, batches, execution_backend, run_parallel,
                                   study_workers, worker_threads)
from gonio.progress import Progress
from gonio.specs import DEFAULT_KEY, Specification, get

__all__ = ["validate", "run_study", "coverage", "binomial_u", "spawn_seed", "run_batch",
           "study_workers", "run_parallel", "batches", "execution_backend", "PartialStore",
           "batch_digest", "worker_threads", "PARTIAL_DIR", "MAX_BATCH", "WORKER_THREADS"]

# ----------------------------------------------------------------------------- execution
#
# Trials run in batches (:func:`run_batch`, hundreds of trials per task) through
# joblib (:mod:`gonio.pipeline.engine`): its local process pool by default, or its Dask backend on a
# distributed cluster. Every batch returns its trials packed as arrays (the
# specification's job packs them); the parent stores each finished batch atomically in the
# output folder (``.validate-partial/``), so an interrupted study keeps what it
# finished and ``resume`` runs only the trials still missing. Results are put
# back in trial order before anything is summarised: the JSON does not depend on
# the number of workers, the backend, the batching or the order of completion.

#: Folder (inside ``--out``) holding the finished batches of a study in progress.
PARTIAL_DIR = ".validate-partial"


def run_batch(job, start: int, stop: int) -> dict:
    """Run trials ``start`` … ``stop − 1`` of one part of a study (``job.run(start, stop)``,
    the specification's trial code), returned packed as arrays (a dict holding at least the
    part's name ``case`` and the trials' ``index``).

    The numerical libraries' thread pools are held to :data:`WORKER_THREADS` while the
    batch runs (``threadpoolctl``), in this process as in a pool or Dask worker.
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=WORKER_THREADS):
        return job.run(start, stop)


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

    def __init__(self, folder: Path, fingerprint: str, describe: dict,
                 unpack: Callable[[Mapping], dict]):
        self.folder = Path(folder)
        self.fingerprint = fingerprint
        self.describe = describe
        self.unpack = unpack                  # packed batch → {trial index: trial}
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
        except RecursionError:                  # '[' nested 10⁵ deep: not a study record
            raise GonioError("unreadable partial study: nested too deeply", file=head) from None
        if not isinstance(info, dict) or not isinstance(info.get("fingerprint"), str) or \
                not isinstance(info.get("batches", {}), dict):
            raise GonioError("not a partial-study record (expected an object with the study's "
                             f"fingerprint and batches); remove {self.folder}", file=head)
        return info

    def open(self, resume: bool) -> dict[str, dict[int, object]]:
        """Create the store, or (``resume``) load what it holds: case → {index: trial}."""
        head = self.folder / "study.json"
        done: dict[str, dict[int, object]] = {}
        if os.path.lexists(head) and not resume and self._holds_nothing(head):
            self._write_head()          # a study that finished no batch: nothing to keep
            return done
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

    def _holds_nothing(self, head: Path) -> bool:
        """Whether the unfinished study here finished no batch (its record lists none and no
        other file is in the folder): a study stopped before its first batch (a cluster
        that never answered, a Ctrl-C during start-up) then does not block the rerun
        without ``--resume``. A record that cannot be read is not judged
        empty: the refusal stands."""
        try:
            info = self._head(head)
        except GonioError:
            return False
        others = [f for f in self.folder.iterdir()
                  if f.name != "study.json" and not f.name.startswith(".gonio-")]
        return not info.get("batches") and not others

    def load_batch(self, f: Path) -> tuple[str, dict[int, object]]:
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
            got = self.unpack(packed)
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


# ----------------------------------------------------------------------------- the study
def _check_run(trials: int, seed: int) -> None:
    if not isinstance(trials, int) or trials < 2:
        raise GonioError(f"--trials must be an integer >= 2, got {trials}", key="trials")
    if seed < 0:
        raise GonioError(f"--seed must be >= 0, got {seed}", key="seed")


def validate(trials: int, *, spec: str | Specification = DEFAULT_KEY, seed: int = 0,
             bench=None, protocol=None, workers: int | None = None,
             scheduler: str | None = None, batch_size: int | None = None,
             partial_dir: str | Path | None = None, resume: bool = False,
             show_progress: bool = True, **options):
    """Run a specification's coverage study (``SPEC.coverage``) over ``trials`` virtual
    calibrations (per part of the study) and return its report (``to_dict()`` →
    validation.json, ``table()`` → the printed table).

    Parameters
    ----------
    trials : int
        Calibrations (per case of a study with cases; ≥ 2).
    spec : str or Specification
        The specification (default :data:`gonio.specs.DEFAULT_KEY`).
    seed : int
        Master seed; trial i of part k is seeded by SeedSequence(seed, spawn_key=(k, i))
        (:func:`spawn_seed`): same seed → same JSON.
    bench, protocol
        Bench and protocol (names, files, or loaded; default the specification's, as the
        study makes them).
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
        (the CLI uses ``OUT/.validate-partial``); removed by the caller once the study is
        complete. An interrupted study keeps what it finished there.
    resume : bool
        Load the finished trials from ``partial_dir`` (same settings required) and
        run only the missing ones.
    **options
        The study's own options (``SPEC.coverage.options``: for the optical draft's study
        cases, truth, sample_rate_hz, …), passed to ``SPEC.coverage.study``.

    An example, the optical draft's study of two trials on an ideal bench, is in
    ``SPEC.coverage.study``'s docstring.
    """
    s = get(spec) if isinstance(spec, str) else spec
    if s.coverage is None:
        raise GonioError(f"{s.key} has no coverage study (SPEC.coverage is None)", key="--spec")
    if s.coverage.engine == "items":
        from gonio.pipeline.coverage import coverage_validate

        cases = options.pop("cases", None)
        if options or partial_dir is not None or resume:
            bad = sorted(options) + (["resume"] if resume else [])
            raise GonioError(f"{', '.join(bad) or 'partial results'} do not apply to the item "
                             f"study of {s.key}", key="--spec")
        return coverage_validate(s.key, trials, seed=seed, bench=bench, protocol=protocol,
                                 workers=workers, scheduler=scheduler, batch_size=batch_size,
                                 show_progress=show_progress, cases=cases)
    if s.coverage.study is None:
        raise GonioError(f"{s.key} has no coverage study (SPEC.coverage.study is None)",
                         key="--spec")
    _check_run(trials, seed)
    study = s.coverage.study(trials, seed=seed, bench=bench or s.default_bench,
                             protocol=protocol or s.default_protocol, **options)
    return run_study(study, trials, workers=workers, scheduler=scheduler,
                     batch_size=batch_size, partial_dir=partial_dir, resume=resume,
                     show_progress=show_progress)


def _open_store(study, trials: int, partial_dir, resume: bool, done: dict):
    """The partial store of ``study`` in ``partial_dir`` (None without one); what it holds
    from an interrupted run (``resume``) goes into ``done``."""
    if partial_dir is None:
        if resume:
            raise GonioError("--resume needs --out (the folder of the interrupted study)",
                             key="resume")
        return None
    describe = {k: v for k, v in study.settings.items() if k != "trials"}
    ident = {**describe, "gonio": __version__, "jobs": [repr(j) for j in study.jobs.values()]}
    store = PartialStore(Path(partial_dir), _fingerprint(ident), describe, study.unpack)
    for name, got in store.open(resume).items():
        if name in done:
            done[name].update({i: t for i, t in got.items() if i < trials})
    return store


def run_study(study, trials: int, *, workers: int | None = None, scheduler: str | None = None,
              batch_size: int | None = None, partial_dir: str | Path | None = None,
              resume: bool = False, show_progress: bool = True):
    """Run every trial of a planned study (``SPEC.coverage.study``'s object: ``settings``,
    ``jobs``, ``unpack``, ``report``) in batches (:func:`run_batch` through
    :func:`run_parallel`), keeping each finished batch in ``partial_dir`` and reusing them
    on ``resume``; the report comes from the trials put back in trial order."""
    names = list(study.jobs)
    default_batch = batch_size is None
    workers, batch_size = study_workers(trials, workers, scheduler, batch_size, len(names))
    done: dict[str, dict] = {name: {} for name in names}
    store = _open_store(study, trials, partial_dir, resume, done)
    def tasks(n_workers: int) -> list[tuple]:
        size = batch_size
        if default_batch and scheduler is not None:     # the cluster's own worker count
            size = study_workers(trials, workers, scheduler, None, len(names), n_workers)[1]
        return [(study.jobs[name], a, b) for name in names
                for a, b in batches([i for i in range(trials) if i not in done[name]], size)]
    already = sum(len(d) for d in done.values())
    prog = Progress(trials * len(names), label="validate: trials", done=already,
                    force=False) if show_progress else None
    try:
        for packed in run_parallel(run_batch, tasks, workers, scheduler):
            if store is not None:
                store.save(packed)
            got = study.unpack(packed)
            done[str(packed["case"])].update(got)
            if prog is not None:
                prog.update(len(got))
    finally:
        if prog is not None:
            prog.close()
    return study.report({name: [done[name][i] for i in range(trials)] for name in names})
