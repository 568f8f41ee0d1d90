"""Benchmark: ``gonio demo`` (the draft's whole calibration, bench simulated at 1 kHz).

Target: under 10 s of CPU time and under 1 GB peak memory. Runs the demo in a child
process per seed (as a user would) and prints that child's CPU time (user + system), wall
time, peak resident memory, the load average (1 min, before and after) and the machine's
cores. Not part of the test run.

    python benchmarks/bench_demo.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    for i in range(args.repeat):
        with tempfile.TemporaryDirectory() as d:
            load = os.getloadavg()[0]
            t0 = time.perf_counter()
            p = subprocess.Popen([sys.executable, "-m", "gonio", "demo", "--out", d,
                                  "--seed", str(i)], stdout=subprocess.DEVNULL)
            _, status, ru = os.wait4(p.pid, 0)
            wall = time.perf_counter() - t0
            if os.waitstatus_to_exitcode(status):
                raise SystemExit(f"gonio demo --seed {i} failed")
        print(f"gonio demo --seed {i} (1 kHz, whole draft protocol): CPU "
              f"{ru.ru_utime + ru.ru_stime:.1f} s, wall {wall:.1f} s, peak RSS "
              f"{ru.ru_maxrss / 1024.0:.0f} MB, load {load:.1f} to {os.getloadavg()[0]:.1f} "
              f"on {os.cpu_count()} cores (targets: < 10 s CPU, < 1024 MB)", flush=True)


if __name__ == "__main__":
    main()
