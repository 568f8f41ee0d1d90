"""Benchmark: ``gonio demo`` (the draft's whole calibration, bench simulated at 1 kHz).

Target (issue 2): under 20 s wall time and under 1 GB peak memory on a 2-core machine.
Runs the demo in a child process (as a user would) and prints wall time and the
child's peak resident memory. Not part of the test run.

    python benchmarks/bench_demo.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    walls = []
    for i in range(args.repeat):
        with tempfile.TemporaryDirectory() as d:
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "gonio", "demo", "--out", d, "--seed", str(i)],
                           check=True, stdout=subprocess.DEVNULL)
            walls.append(time.perf_counter() - t0)
    peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
    print(f"gonio demo (1 kHz, whole draft protocol): wall best {min(walls):.2f} s, "
          f"worst {max(walls):.2f} s over {args.repeat} runs; peak RSS {peak_mb:.0f} MB "
          f"(targets: < 20 s, < 1024 MB)")


if __name__ == "__main__":
    main()
