"""Coverage-study throughput, before and after, in one run.

1. Per-trial cost: one virtual calibration of the validation (the RLG bench at 100 Hz,
   7.1 + 7.4 with its 10 series), N trials in one process, with
     a. the code of the start commit (a git worktree of it on PYTHONPATH, in a subprocess),
     b. this tree,
   alternated (a, b, a, b) so both see the same machine load; trials per second (CPU time
   and wall) and the ratio b/a (target ≥ 2).
2. The execution engine (this tree): trials per second of ``validate`` on 1 and 2 local
   joblib workers and on a 2-worker ``distributed.LocalCluster`` (started here; the study
   connects to it by its tcp:// address), each after a warm-up, the same trials and
   seeds; scaling efficiency 1 → 2 workers (target ≥ 85 %); and whether the three
   ``validation.json`` texts are byte-identical.

Usage: python benchmarks/bench_validate.py [--trials-per-cost 8] [--trials 48] [--batch 6]
The machine's load average is printed: on a shared machine the figures are noisy.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
START_COMMIT = "477f910"       # main before issue 16

COST = r"""
import sys, time
from dataclasses import replace
try:
    from gonio.pipeline.validate import validation_protocol, run_trial
except ImportError:
    from gonio.validate import validation_protocol, run_trial
from gonio.bench import load_bench
p = validation_protocol(); b = replace(load_bench("rlg"), sample_rate_hz=100.0)
run_trial(p, b, 12345)                         # warm-up (imports, caches)
n = int(sys.argv[1])
c0, w0 = time.process_time(), time.perf_counter()
for s in range(n):
    run_trial(p, b, s)
print(n / (time.process_time() - c0), n / (time.perf_counter() - w0))
"""


def cost(pythonpath: Path, n: int) -> tuple[float, float]:
    env = dict(os.environ, PYTHONPATH=str(pythonpath))
    r = subprocess.run([sys.executable, "-c", COST, str(n)], env=env, cwd="/tmp",
                       capture_output=True, text=True)
    if r.returncode:
        raise SystemExit(r.stderr)
    cpu, wall = r.stdout.split()
    return float(cpu), float(wall)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials-per-cost", type=int, default=8)
    ap.add_argument("--trials", type=int, default=48)
    ap.add_argument("--batch", type=int, default=6)
    ap.add_argument("--skip-cost", action="store_true")
    a = ap.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores", flush=True)
    if not a.skip_cost:
        with tempfile.TemporaryDirectory(prefix="gonio-bench-validate-") as tmp:
            wt = Path(tmp) / "before"
            subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(wt),
                            START_COMMIT], check=True, capture_output=True)
            try:
                runs = {"before": [], "after": []}
                for _ in range(2):
                    runs["before"].append(cost(wt, a.trials_per_cost))
                    runs["after"].append(cost(ROOT, a.trials_per_cost))
            finally:
                subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(wt)],
                               capture_output=True)
        best = {k: (max(x[0] for x in v), max(x[1] for x in v)) for k, v in runs.items()}
        for k in ("before", "after"):
            print(f"one trial ({k:<6}, {'start commit ' + START_COMMIT if k == 'before' else 'this tree'}"
                  f"): {best[k][0]:.2f} trials/s CPU, {best[k][1]:.2f} trials/s wall "
                  f"(best of 2 x {a.trials_per_cost})", flush=True)
        r_cpu = best["after"][0] / best["before"][0]
        r_wall = best["after"][1] / best["before"][1]
        print(f"per-trial speed-up: {r_cpu:.2f}x CPU, {r_wall:.2f}x wall (target >= 2x): "
              f"{'OK' if min(r_cpu, r_wall) >= 2 else 'MISSED'}", flush=True)

    sys.path.insert(0, str(ROOT))
    from gonio.pipeline.validate import validate
    kw = dict(seed=0, bench="rlg", sample_rate_hz=100.0, show_progress=False,
              batch_size=a.batch)
    texts, rates = {}, {}

    def study(label, **extra):
        t0 = time.perf_counter()
        rep = validate(a.trials, **kw, **extra)
        wall = time.perf_counter() - t0
        texts[label] = json.dumps(rep.to_dict(), indent=2, ensure_ascii=False, allow_nan=False)
        rates[label] = a.trials / wall
        print(f"{label:<28} {a.trials} trials in {wall:6.1f} s: {rates[label]:.2f} trials/s "
              f"(load {os.getloadavg()[0]:.1f})", flush=True)

    validate(2, workers=1, **{k: v for k, v in kw.items() if k != "batch_size"})
    study("joblib, 1 worker", workers=1)
    validate(4, workers=2, **kw)                   # warm-up: the process pool starts
    study("joblib, 2 workers", workers=2)
    import logging

    from distributed import Client, LocalCluster
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None, silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as client:
        client.run(lambda: __import__("gonio.pipeline.validate"))
        validate(4, scheduler=cluster.scheduler_address, **kw)     # warm-up
        study("Dask LocalCluster, 2 workers", scheduler=cluster.scheduler_address)
    eff = rates["joblib, 2 workers"] / rates["joblib, 1 worker"] / 2
    print(f"scaling efficiency 1 -> 2 workers (joblib): {100 * eff:.0f} % (target >= 85 %): "
          f"{'OK' if eff >= 0.85 else 'MISSED'}")
    eff_d = rates["Dask LocalCluster, 2 workers"] / rates["joblib, 1 worker"] / 2
    print(f"scaling efficiency 1 -> 2 workers (Dask): {100 * eff_d:.0f} %")
    same = len(set(texts.values())) == 1
    print(f"validation.json identical for 1 worker, 2 workers and the Dask cluster: "
          f"{'yes' if same else 'NO'}")
    print(f"load average at end: {os.getloadavg()[0]:.1f}")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
