"""Coverage-study throughput, before and after, in one run.

1. Per-trial cost: one virtual calibration of the validation (the RLG bench at 100 Hz,
   7.1 + 7.4 with its 10 series), N trials in one process, with
     a. the code of ``--before REV`` (a git worktree of it on PYTHONPATH, in a subprocess),
     b. this tree,
   alternated (a, b, a, b) so both see the same machine load; trials per second (CPU time
   and wall) and the ratio b/a (target ≥ 2). The comparison needs REV to hold what the
   timing imports (:data:`BEFORE_NEEDS`); a revision without it (the default, the start
   commit, predates the package layout) is not checked out: this tree is timed alone and
   the reason printed.
2. The execution engine (this tree): trials per second of ``validate`` on 1 and 2 local
   joblib workers and on a 2-worker ``distributed.LocalCluster`` (started here; the study
   connects to it by its tcp:// address, with the Dask settings the engine gives the
   LocalCluster it starts itself; the engine keeps its client and warmed workers between
   studies), the same trials and seeds; and once, untimed in the efficiency, the whole
   ``local:N`` path (cluster start, warm-up, close). Every worker is
   warmed first (it has imported gonio and run a trial), the three studies are
   interleaved for ``--rounds`` rounds and the best of each is kept; scaling efficiency
   1 → n workers (target ≥ 85 %, ≥ 90 % at 16); whether all ``validation.json`` texts are
   byte-identical. The thread pools each worker runs with are printed (one BLAS/OpenMP
   thread per worker: ``gonio.pipeline.validate.WORKER_THREADS``).

3. Start-up (this tree): a fresh process imports the study code and runs its first trial;
   the start-up is the import plus the first trial's excess over a warm trial (what every
   new worker pays once), best of ``--startup-runs``; and whether SymPy was imported (the
   trial path must not need it). Then the fixed cost of a whole ``gonio validate`` as a user
   runs it, for every specification with a coverage study (the optical draft's default
   study at 5 Hz; the rate specifications' item studies with their defaults), one worker:
   the command with 2 and with 4 trials, CPU (the command and its worker processes) and
   wall, and the fixed cost 2·T(2) − T(4) (the study's cost extrapolated to no trials;
   target < 3 s): the median over ``--startup-runs`` paired runs, the pairs' range beside it.
   That difference doubles the scatter of the trials' own cost (trials of different seeds
   differ in cost), so the fixed cost is also measured directly, inside one command
   (:data:`DIRECT`): the command runs in a process whose batch function
   (``run_batch`` of :mod:`gonio.pipeline.validate` and :mod:`gonio.pipeline.coverage`) is
   timed; the fixed cost is the process's CPU outside its batches (interpreter start,
   imports, bench and protocol set-up, the report) plus the first batch's excess over the
   same batch run again warm (imports and caches its first trial pulls in); printed with
   the CPU to the first trial. ``--startup-only`` prints item 3 alone (no checkout, no
   engine study). gonio's modules are byte-compiled first (``compileall``, as ``pip install``
   does; ``--from-source`` times them as found): with no cached bytecode and
   ``PYTHONDONTWRITEBYTECODE`` set, every fresh process would compile every module it imports.

The worker counts are 1, 2, 4, 8, 16 up to the machine's cores (on 2 cores: 1 and 2); the
efficiency of n workers is rate(n) / (n · rate(1)). The Dask LocalCluster has the largest
count. On a 16-core machine: ``--trials 3200`` (the issue's figure).

Usage: python benchmarks/bench_validate.py [--trials-per-cost 8] [--trials 48] [--batch N]
       [--rounds 2] [--skip-cost] [--before REV] [--startup-runs 3] [--startup-only]
       [--specs KEY,KEY] [--from-source]
The load average is printed beside every figure: on a shared machine (load above the
number of cores) the second worker shares a core with other processes and the scaling
figure measures that, not gonio.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
START_COMMIT = "477f910"       # main before issue 16
# what the per-trial timing (COST) imports from the "before" tree, besides the study code
BEFORE_NEEDS = ("gonio/specs/ogam_draft/bench",)

COST = r"""
import sys, time
from dataclasses import replace
try:
    from gonio.specs.ogam_draft.study import validation_protocol, run_trial
except ImportError:
    try:
        from gonio.pipeline.validate import validation_protocol, run_trial
    except ImportError:
        from gonio.validate import validation_protocol, run_trial
from gonio.specs.ogam_draft.bench import load_bench
p = validation_protocol(); b = replace(load_bench("rlg"), sample_rate_hz=100.0)
run_trial(p, b, 12345)                         # warm-up (imports, caches)
n = int(sys.argv[1])
c0, w0 = time.process_time(), time.perf_counter()
for s in range(n):
    run_trial(p, b, s)
print(n / (time.process_time() - c0), n / (time.perf_counter() - w0))
"""


def before_missing(rev: str) -> str | None:
    """Why ``rev`` cannot be timed against this tree (None when it can): an unknown
    revision, or one without a path of :data:`BEFORE_NEEDS` (a module or a package)."""
    def has(path: str) -> bool:
        return any(subprocess.run(["git", "-C", str(ROOT), "cat-file", "-e", f"{rev}:{p}"],
                                  capture_output=True).returncode == 0
                   for p in (path, path + ".py"))
    if subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--verify", "--quiet",
                       f"{rev}^{{commit}}"], capture_output=True).returncode:
        return f"{rev} is not a commit of this repository"
    missing = [p for p in BEFORE_NEEDS if not has(p)]
    return f"{rev} has no {', '.join(missing)}" if missing else None


def per_trial_cost(before: str, n: int) -> None:
    """Item 1 of the module docstring: ``before`` against this tree, or this tree alone
    (with the reason) when ``before`` lacks what the timing imports."""
    why = before_missing(before)
    if why is not None:
        cpu, wall = max(cost(ROOT, n) for _ in range(2))
        print(f"one trial (this tree): {cpu:.2f} trials/s CPU, {wall:.2f} trials/s wall (best "
              f"of 2 x {n}; load {os.getloadavg()[0]:.1f}); no before/after ratio: {why} "
              "(--before REV: a revision that has it)", flush=True)
        return
    with tempfile.TemporaryDirectory(prefix="gonio-bench-validate-") as tmp:
        wt = Path(tmp) / "before"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(wt),
                        before], check=True, capture_output=True)
        try:
            runs = {"before": [], "after": []}
            for _ in range(2):
                runs["before"].append(cost(wt, n))
                runs["after"].append(cost(ROOT, n))
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(wt)],
                           capture_output=True)
    best = {k: (max(x[0] for x in v), max(x[1] for x in v)) for k, v in runs.items()}
    for k in ("before", "after"):
        print(f"one trial ({k:<6}, {before if k == 'before' else 'this tree'}"
              f"): {best[k][0]:.2f} trials/s CPU, {best[k][1]:.2f} trials/s wall "
              f"(best of 2 x {n})", flush=True)
    r_cpu = best["after"][0] / best["before"][0]
    r_wall = best["after"][1] / best["before"][1]
    print(f"per-trial speed-up: {r_cpu:.2f}x CPU, {r_wall:.2f}x wall (target >= 2x): "
          f"{'OK' if min(r_cpu, r_wall) >= 2 else 'MISSED'} (load {os.getloadavg()[0]:.1f})",
          flush=True)


def cost(pythonpath: Path, n: int) -> tuple[float, float]:
    env = dict(os.environ, PYTHONPATH=str(pythonpath))
    r = subprocess.run([sys.executable, "-c", COST, str(n)], env=env, cwd="/tmp",
                       capture_output=True, text=True)
    if r.returncode:
        raise SystemExit(r.stderr)
    cpu, wall = r.stdout.split()
    return float(cpu), float(wall)


STARTUP = r"""
import sys, time
t0, c0 = time.perf_counter(), time.process_time()
from dataclasses import replace
from gonio.specs.ogam_draft.bench import load_bench
from gonio.specs.ogam_draft.study import run_trial, validation_protocol
t1, c1 = time.perf_counter(), time.process_time()
p = validation_protocol(); b = replace(load_bench("rlg"), sample_rate_hz=100.0)
run_trial(p, b, 1)
t2, c2 = time.perf_counter(), time.process_time()
run_trial(p, b, 2)
t3, c3 = time.perf_counter(), time.process_time()
print(t1 - t0, t2 - t1, t3 - t2, int("sympy" in sys.modules),
      (c1 - c0) + max((c2 - c1) - (c3 - c2), 0.0))
"""


def startup(runs: int) -> None:
    """Start-up of a fresh worker process (item 3 of the module docstring)."""
    best = None
    for _ in range(runs):
        w0 = time.perf_counter()
        r = subprocess.run([sys.executable, "-c", STARTUP], cwd=ROOT, capture_output=True,
                           text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)))
        wall = time.perf_counter() - w0
        if r.returncode:
            raise SystemExit(r.stderr)
        imp, first, warm, sym, cpu = (float(v) for v in r.stdout.split())
        start = imp + max(first - warm, 0.0)
        if best is None or start < best[0]:
            best = (start, imp, first, warm, wall, sym, cpu)
    start, imp, first, warm, wall, sym, cpu = best
    print(f"start-up of a fresh process (best of {runs}): {start:.2f} s (target < 3 s) = "
          f"import {imp:.2f} s + first trial {first:.2f} s − warm trial {warm:.2f} s; "
          f"in CPU time {cpu:.2f} s; interpreter and all {wall:.2f} s; SymPy imported: "
          f"{'yes' if sym else 'no'} (load {os.getloadavg()[0]:.1f})", flush=True)


def study_specs() -> list[str]:
    """Keys of the specifications with a coverage study (``gonio validate --spec KEY``)."""
    r = subprocess.run([sys.executable, "-c", "from gonio.specs import available; print(' '.join("
                        "k for k, s in available().items() if s.coverage is not None))"],
                       cwd=ROOT, capture_output=True, text=True, check=True,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)))
    return r.stdout.split()


# ``gonio validate`` in this process with its batch function timed (item 3 of the module
# docstring): argv[1:] are the command's arguments; prints a JSON line of CPU seconds.
DIRECT = r"""
import json, resource, runpy, sys, time

def cpu():
    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime

import gonio.pipeline.coverage as cov
import gonio.pipeline.validate as val
t_import = cpu()               # the interpreter and the two study modules (the command's own)
calls = []

def timed(mod):
    fn = mod.run_batch
    def run_batch(*a):
        c0 = cpu()
        out = fn(*a)
        calls.append((fn, a, c0, cpu()))
        return out
    mod.run_batch = run_batch

timed(cov); timed(val)
sys.argv = ["gonio", *sys.argv[1:]]
try:
    runpy.run_module("gonio", run_name="__main__", alter_sys=True)
except SystemExit as e:
    if e.code:
        raise
total = cpu()
fn, a, c0, c1 = calls[0]
w0 = cpu(); fn(*a); warm = cpu() - w0
in_batches = sum(e[3] - e[2] for e in calls)
print(json.dumps({"total": total, "batches": len(calls), "in_batches": in_batches,
                  "to_first": c0, "first": c1 - c0, "first_warm": warm,
                  "outside": total - in_batches, "fixed": total - in_batches
                  + max(c1 - c0 - warm, 0.0), "modules_at_start": t_import}))
"""


def _median(xs):
    xs = sorted(xs)
    return 0.5 * (xs[(len(xs) - 1) // 2] + xs[len(xs) // 2])


def study_fixed_cost(runs: int, spec: str) -> None:
    """The fixed cost of ``gonio validate --spec spec`` (item 3 of the module docstring):
    ``runs`` pairs (2 and 4 trials, alternated), the difference estimate per pair and its
    median; and the direct measurement in each 2-trial run, median."""
    extra = ["--sample-rate-hz", "5"] if spec == "ogam-draft" else []
    load0 = os.getloadavg()[0]
    runs_by = {2: [], 4: []}
    direct = []
    for _ in range(runs):
        for trials in (2, 4):
            with tempfile.TemporaryDirectory(prefix="gonio-bench-study-") as tmp:
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                w0 = time.perf_counter()
                args = ["validate", "--spec", spec, "--trials", str(trials), "--workers", "1",
                        *extra, "--out", str(Path(tmp) / "out")]
                if trials == 2:
                    r = subprocess.run([sys.executable, "-c", DIRECT, *args], cwd=tmp,
                                       capture_output=True, text=True,
                                       env=dict(os.environ, PYTHONPATH=str(ROOT)))
                    if r.returncode:
                        raise SystemExit(r.stderr)
                    d = json.loads(r.stdout.strip().splitlines()[-1])
                    direct.append(d)
                else:
                    subprocess.run([sys.executable, "-m", "gonio", *args], check=True, cwd=tmp,
                                   capture_output=True, env=dict(os.environ,
                                                                 PYTHONPATH=str(ROOT)))
                wall = time.perf_counter() - w0
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
            if trials == 2:     # the direct run also ran its first batch again, warm
                cpu -= d["first_warm"]
            runs_by[trials].append((cpu, wall))
    diffs = [2 * a[0] - b[0] for a, b in zip(runs_by[2], runs_by[4])]
    fixed = _median(diffs)
    c2, c4 = _median([x[0] for x in runs_by[2]]), _median([x[0] for x in runs_by[4]])
    w2, w4 = _median([x[1] for x in runs_by[2]]), _median([x[1] for x in runs_by[4]])
    fd = _median([d["fixed"] for d in direct])
    print(f"gonio validate --spec {spec}{' ' + ' '.join(extra) if extra else ''}, 1 worker "
          f"(median of {runs} pairs): 2 trials {c2:.2f} s CPU / {w2:.2f} s wall, 4 trials "
          f"{c4:.2f} s CPU / {w4:.2f} s wall; fixed cost 2*T(2) - T(4): {fixed:.2f} s CPU "
          f"(pairs {min(diffs):.2f} .. {max(diffs):.2f}); measured directly (2 trials): "
          f"{fd:.2f} s CPU (runs {min(d['fixed'] for d in direct):.2f} .. "
          f"{max(d['fixed'] for d in direct):.2f}) = outside the batches "
          f"{_median([d['outside'] for d in direct]):.2f} s + first batch's excess "
          f"{_median([max(d['first'] - d['first_warm'], 0.0) for d in direct]):.2f} s; "
          f"CPU to the first trial {_median([d['to_first'] for d in direct]):.2f} s "
          f"(target < 3 s of CPU: {'OK' if fd < 3 else 'MISSED'}; "
          f"load {load0:.1f} -> {os.getloadavg()[0]:.1f})", flush=True)


def tree_cpu_s() -> float:
    """CPU seconds (user + system) used so far by this process and every live process
    descended from it (the joblib pool, the Dask cluster's nannies and workers): a study's
    CPU cost, whatever else the machine runs at the time."""
    tick = os.sysconf("SC_CLK_TCK")
    parent, cpu = {}, {}
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/stat") as fh:
                f = fh.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        parent[int(d)] = int(f[1])
        cpu[int(d)] = (int(f[11]) + int(f[12])) / tick
    me, total = os.getpid(), 0.0
    for pid in cpu:
        p = pid
        while p > 1 and p != me:
            p = parent.get(p, 0)
        if p == me:
            total += cpu[pid]
    return total


def bytecode(compile_first: bool) -> str:
    """Byte-compile this tree's gonio (``compile_first``; what ``pip install`` does) and say
    how its modules are loaded: where no bytecode is cached and Python may not write it
    (``PYTHONDONTWRITEBYTECODE``), every fresh process compiles every gonio module it
    imports, a few tenths of a second of CPU that an installed gonio does not pay."""
    import compileall

    if compile_first:
        compileall.compile_dir(str(ROOT / "gonio"), quiet=2)
        return "gonio's modules: byte-compiled first (compileall), as an installed gonio's are"
    cached = any((ROOT / "gonio" / "__pycache__").glob("__init__.*.pyc"))
    return (f"gonio's modules: as found (bytecode cached: {'yes' if cached else 'no'}; "
            f"PYTHONDONTWRITEBYTECODE={os.environ.get('PYTHONDONTWRITEBYTECODE', 'unset')})")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials-per-cost", type=int, default=8)
    ap.add_argument("--trials", type=int, default=48)
    ap.add_argument("--batch", type=int, default=None,
                    help="trials per task (default: the study's own choice)")
    ap.add_argument("--rounds", type=int, default=2,
                    help="interleaved rounds of the three studies (the best of each is kept)")
    ap.add_argument("--skip-cost", action="store_true")
    ap.add_argument("--before", default=START_COMMIT,
                    help="revision the per-trial cost is compared with (item 1; only when it "
                         f"has {', '.join(BEFORE_NEEDS)}; default {START_COMMIT})")
    ap.add_argument("--startup-runs", type=int, default=3)
    ap.add_argument("--startup-only", action="store_true",
                    help="item 3 only: the start-up of a fresh worker process and the "
                         "fixed cost of gonio validate per specification")
    ap.add_argument("--specs", default=None,
                    help="comma-separated specification keys for the fixed cost (default: "
                         "every one with a coverage study)")
    ap.add_argument("--from-source", action="store_true",
                    help="time gonio as found (by default its modules are byte-compiled "
                         "first, as an installed gonio's are)")
    a = ap.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores", flush=True)
    print(bytecode(compile_first=not a.from_source), flush=True)
    if not (a.skip_cost or a.startup_only):
        per_trial_cost(a.before, a.trials_per_cost)
    startup(a.startup_runs)
    for spec in a.specs.split(",") if a.specs else study_specs():
        study_fixed_cost(a.startup_runs, spec)
    if a.startup_only:
        return 0
    sys.path.insert(0, str(ROOT))
    from joblib import Parallel, delayed

    from gonio.pipeline.validate import validate, worker_threads
    kw = dict(seed=0, bench="rlg", sample_rate_hz=100.0, show_progress=False,
              batch_size=a.batch)
    texts, rates, cpus = {}, {}, {}

    def study(label, **extra):
        load0 = os.getloadavg()[0]
        c0 = tree_cpu_s()
        t0 = time.perf_counter()
        rep = validate(a.trials, **kw, **extra)
        wall = time.perf_counter() - t0
        cpu = tree_cpu_s() - c0
        cpus.setdefault(label, []).append(cpu / a.trials)
        text = json.dumps(rep.to_dict(), indent=2, ensure_ascii=False, allow_nan=False)
        if texts.setdefault(label, text) != text:
            texts[label + " (repeat)"] = text
        rate = a.trials / wall
        rates.setdefault(label, []).append((rate, load0, os.getloadavg()[0]))
        print(f"{label:<28} {a.trials} trials in {wall:6.1f} s: {rate:.2f} trials/s, "
              f"{cpu / a.trials:.3f} CPU s/trial, {cpu / wall:.2f} cores obtained "
              f"(load {load0:.1f} -> {os.getloadavg()[0]:.1f})", flush=True)

    def warm(n=4, **extra):
        # every worker imports gonio and runs a trial before anything is timed: at least
        # four one-trial tasks and one per worker, so that no worker's start-up lands in a
        # timed study
        validate(max(4, n), **{**kw, "batch_size": 1}, **extra)

    print(f"threads per worker (threadpoolctl, while a batch runs): {worker_threads()}; "
          f"pool workers: " + "; ".join(Parallel(n_jobs=2)(delayed(worker_threads)()
                                                        for _ in range(2))), flush=True)
    print(f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}, "
          f"OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', 'unset')} in this process "
          "(joblib sets both to cores // workers in its pool; Dask's nanny sets them to 1)",
          flush=True)
    import logging

    from distributed import Client, LocalCluster
    counts = [n for n in (1, 2, 4, 8, 16) if n <= (os.cpu_count() or 1)]
    top = counts[-1]
    for n in counts:
        warm(n, workers=n)
    dask_label = f"Dask LocalCluster, {top} workers"
    import dask

    from gonio.pipeline.engine import LOCAL_CLUSTER_CONFIG, close_clients
    t0 = time.perf_counter()
    validate(max(4, top), **{**kw, "batch_size": 1}, scheduler=f"local:{top}")
    print(f"--scheduler local:{top} (cluster started, workers warmed, {max(4, top)} one-trial "
          f"tasks, closed): {time.perf_counter() - t0:.1f} s (load {os.getloadavg()[0]:.1f})",
          flush=True)
    # the cluster the engine starts for local:N (its Dask settings), here started once and
    # reached by address, so that the timed studies measure the trials, not the start-up
    with dask.config.set(LOCAL_CLUSTER_CONFIG), \
            LocalCluster(n_workers=top, threads_per_worker=1, processes=True,
                         dashboard_address=None, silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as client:
        addr = cluster.scheduler_address
        print("Dask workers: " + "; ".join(f"{v}" for v in client.run(worker_threads).values()),
              flush=True)
        warm(top, scheduler=addr)
        for r in range(a.rounds):       # interleaved, so that all see the same load
            for n in counts:
                study(f"joblib, {n} worker{'s' if n > 1 else ''}", workers=n)
            study(dask_label, scheduler=addr)
        close_clients()                 # the engine's kept client, before the cluster goes
    best = {k: max(v) for k, v in rates.items()}
    for k, (rate, l0, l1) in best.items():
        print(f"best of {a.rounds}: {k:<28} {rate:.2f} trials/s (load {l0:.1f} -> {l1:.1f})")
    one = best["joblib, 1 worker"]
    for n in counts[1:]:
        rn = best[f"joblib, {n} workers"]
        eff = rn[0] / one[0] / n
        target = 0.90 if n == 16 else 0.85
        print(f"scaling efficiency 1 -> {n} workers (joblib): {100 * eff:.0f} % (target >= "
              f"{100 * target:.0f} %): {'OK' if eff >= target else 'MISSED'} (load {one[1]:.1f} "
              f"and {rn[1]:.1f} on {os.cpu_count()} cores; above the core count the workers "
              "share their cores with other processes)")
    eff_d = best[dask_label][0] / one[0] / top
    print(f"scaling efficiency 1 -> {top} workers (Dask): {100 * eff_d:.0f} %")
    # the engine's own cost, which load does not hide: CPU seconds per trial (all processes
    # of the study), lowest of the rounds. With no other load the 1 -> n worker efficiency
    # can be no better than this ratio (the extra CPU is the parallel overhead).
    c1 = min(cpus["joblib, 1 worker"])
    for k, v in cpus.items():
        print(f"CPU per trial, {k:<28} {min(v):.3f} s (1-worker cost / this: {c1 / min(v):.0%};"
              " the bound on scaling efficiency without other load)")
    same = len(set(texts.values())) == 1
    print(f"validation.json identical for every worker count and the Dask cluster: "
          f"{'yes' if same else 'NO'}")
    print(f"load average at end: {os.getloadavg()[0]:.1f}")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
