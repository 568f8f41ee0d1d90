"""Benchmark: ``gonio demo`` (the draft's whole calibration, bench simulated at 1 kHz).

Target: under 10 s of CPU time and under 1 GB peak memory. Runs the demo in a child
process per seed (as a user would) and prints that child's CPU time (user + system), wall
time, peak resident memory, the load average (1 min, before and after) and the machine's
cores. Not part of the test run.

``--runs K`` runs each seed K times and prints every run's CPU time and their median: on a
shared virtual machine the same seed's CPU time varies by ±15 % between runs at the same
load (the host's other guests), so one run is not a figure.

The children run gonio as ``pip install .`` leaves it: its modules byte-compiled before
the timed runs (``compileall`` into the tree's own ``__pycache__`` folders, which git
ignores), so that no run pays the ≈ 0.4–1 s of compiling gonio's modules that a checkout
run with ``PYTHONDONTWRITEBYTECODE=1`` (this development environment) and no cached
bytecode pays every time. (A ``PYTHONPYCACHEPREFIX`` would not do: Python then ignores the
libraries' installed bytecode too, and the first run compiles NumPy, SciPy, pandas and
Matplotlib.)

``--peer DIR`` runs the same seeds with ``PYTHONPATH=DIR`` (another checkout of gonio, such
as main before a change; its modules are byte-compiled in place too), alternated run by run
with this tree, and checks that both write the same bytes (every file of :data:`COMPARED`):
a speed change must not change an output.

    python benchmarks/bench_demo.py [--repeat 3] [--runs 1] [--peer DIR]
"""

from __future__ import annotations

import argparse
import hashlib
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: The outputs whose bytes the alternated trees must agree on (same seed, same bytes).
COMPARED = ("results.json", "summary.txt", "certificate.dcc.xml", "certificate.pdf",
            "certificate.html", "readings.csv", "truth.json")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3, help="seeds 0 … repeat − 1")
    ap.add_argument("--runs", type=int, default=1, help="runs of each seed")
    ap.add_argument("--peer", default=None, help="another gonio checkout, run alternated")
    args = ap.parse_args()
    trees = [("this tree", ROOT)] + ([("peer", Path(args.peer).resolve())] if args.peer else [])
    with tempfile.TemporaryDirectory(prefix="bench-demo-") as work:
        env = {name: dict(os.environ, PYTHONPATH=str(tree)) for name, tree in trees}
        for name, tree in trees:
            for pkg in ("gonio", "uncertainty"):
                subprocess.run([sys.executable, "-m", "compileall", "-q", str(tree / pkg)],
                               check=True, stdout=subprocess.DEVNULL)
        print(f"python {sys.version.split()[0]}, {os.cpu_count()} cores, gonio's modules "
              "byte-compiled before the runs (compileall), as an installed gonio's are",
              flush=True)
        for i in range(args.repeat):
            res = {name: ([], [], 0.0) for name, _ in trees}
            load0 = os.getloadavg()[0]
            digests = {}
            for _ in range(max(1, args.runs)):
                for name, _tree in trees:
                    cpu, wall, peak, dig = _one(i, env[name], work)
                    cpus, walls, rss = res[name]
                    cpus.append(cpu)
                    walls.append(wall)
                    res[name] = (cpus, walls, max(rss, peak))
                    digests.setdefault(name, dig)
                    if dig != digests[name]:
                        raise SystemExit(f"{name}: seed {i} wrote other bytes in a second run")
            if args.peer and digests["this tree"] != digests["peer"]:
                raise SystemExit(f"seed {i}: this tree and the peer wrote different bytes: "
                                 + ", ".join(f for f in COMPARED
                                             if digests["this tree"].get(f)
                                             != digests["peer"].get(f)))
            for name, _tree in trees:
                cpus, walls, rss = res[name]
                runs = "" if len(cpus) == 1 else (
                    f" (median of {len(cpus)} runs: " + ", ".join(f"{c:.1f}" for c in cpus)
                    + " s)")
                who = f"[{name}] " if args.peer else ""
                print(f"{who}gonio demo --seed {i} (1 kHz, whole draft protocol): CPU "
                      f"{statistics.median(cpus):.1f} s{runs}, wall "
                      f"{statistics.median(walls):.1f} s, peak RSS {rss:.0f} MB, load "
                      f"{load0:.1f} to {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores "
                      "(targets: < 10 s CPU, < 1024 MB)", flush=True)
            if args.peer:
                print(f"seed {i}: this tree and the peer wrote the same bytes "
                      f"({', '.join(COMPARED)})", flush=True)


def _one(seed: int, env: dict, work: str) -> tuple[float, float, float, dict]:
    """(CPU s, wall s, peak RSS MB, {output: sha256}) of one ``gonio demo --seed SEED``
    child process, run in a folder that is not a gonio checkout (PYTHONPATH decides)."""
    with tempfile.TemporaryDirectory(dir=work) as d:
        out = Path(d) / "out"
        t0 = time.perf_counter()
        p = subprocess.Popen([sys.executable, "-m", "gonio", "demo", "--out", str(out),
                              "--seed", str(seed)], stdout=subprocess.DEVNULL, env=env, cwd=d)
        _, status, ru = os.wait4(p.pid, 0)
        wall = time.perf_counter() - t0
        if os.waitstatus_to_exitcode(status):
            raise SystemExit(f"gonio demo --seed {seed} failed")
        dig = {f: hashlib.sha256((out / f).read_bytes()).hexdigest() for f in COMPARED
               if (out / f).is_file()}
    return ru.ru_utime + ru.ru_stime, wall, ru.ru_maxrss / 1024.0, dig


if __name__ == "__main__":
    main()
