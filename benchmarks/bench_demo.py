"""Benchmark: ``gonio demo`` (the draft's whole calibration, bench simulated at 1 kHz).

Target: under 10 s of CPU time and under 1 GB peak memory. Runs the demo in a child
process per seed (as a user would) and prints that child's CPU time (user + system), wall
time, peak resident memory, the load average (1 min, before and after) and the machine's
cores. Not part of the test run.

``--runs K`` runs each seed K times and prints every run's CPU time and their median: on a
shared virtual machine the same seed's CPU time varies by ±15 % between runs at the same
load (the host's other guests), so one run is not a figure.

    python benchmarks/bench_demo.py [--repeat 3] [--runs 1]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3, help="seeds 0 … repeat − 1")
    ap.add_argument("--runs", type=int, default=1, help="runs of each seed")
    args = ap.parse_args()
    for i in range(args.repeat):
        cpus, walls, rss, load0 = [], [], 0.0, os.getloadavg()[0]
        for _ in range(max(1, args.runs)):
            cpu, wall, peak = _one(i)
            cpus.append(cpu)
            walls.append(wall)
            rss = max(rss, peak)
        runs = "" if len(cpus) == 1 else (
            f" (median of {len(cpus)} runs: " + ", ".join(f"{c:.1f}" for c in cpus) + " s)")
        print(f"gonio demo --seed {i} (1 kHz, whole draft protocol): CPU "
              f"{statistics.median(cpus):.1f} s{runs}, wall {statistics.median(walls):.1f} s, "
              f"peak RSS {rss:.0f} MB, load {load0:.1f} to {os.getloadavg()[0]:.1f} "
              f"on {os.cpu_count()} cores (targets: < 10 s CPU, < 1024 MB)", flush=True)


def _one(seed: int) -> tuple[float, float, float]:
    """(CPU s, wall s, peak RSS MB) of one ``gonio demo --seed SEED`` child process."""
    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        p = subprocess.Popen([sys.executable, "-m", "gonio", "demo", "--out", d,
                              "--seed", str(seed)], stdout=subprocess.DEVNULL)
        _, status, ru = os.wait4(p.pid, 0)
        wall = time.perf_counter() - t0
        if os.waitstatus_to_exitcode(status):
            raise SystemExit(f"gonio demo --seed {seed} failed")
    return ru.ru_utime + ru.ru_stime, wall, ru.ru_maxrss / 1024.0

if __name__ == "__main__":
    main()
