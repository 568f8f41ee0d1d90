"""Benchmark: the whole JJF 1535-2015 programme (15 items, with its temperature points) on
the virtual MEMS bench — simulate, calibrate, certificate — against the issue's limits
(< 60 s CPU, < 1 GB). Prints CPU time (user + system of this process, imports included),
wall time, peak resident memory, the load average and the rows simulated. ``--spec
triad-alignment`` runs the triad demo the same way.

    PYTHONPATH=$PWD python benchmarks/bench_rate_demo.py [--spec iec62047-20] [--bench rlg]
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--spec", default="jjf1535-2015")
    ap.add_argument("--bench", default=None)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    load = os.getloadavg()[0]
    c0 = time.process_time()
    from gonio.pipeline.dispatch import demo

    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        result, paths = demo(a.spec, d, bench=a.bench, seed=a.seed)
        wall = time.perf_counter() - t0
        cpu = time.process_time() - c0
        rows = result.source.get("rows")
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    measured = sum(1 for it in result.items.values() if it.measured)
    print(f"{a.spec} demo ({a.bench or 'default bench'}, seed {a.seed}): CPU {cpu:.1f} s, "
          f"{wall:.1f} s wall, peak RSS {peak_mb:.0f} MB, load {load:.1f} to "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; {rows} readings rows, {measured}/{len(result.items)} "
          "items measured")
    # judged on CPU time: the wall time of a shared machine says more about its load
    ok = cpu < 60.0 and peak_mb < 1024.0
    print("within limits (< 60 s CPU, < 1 GB):", "yes" if ok else "NO")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
