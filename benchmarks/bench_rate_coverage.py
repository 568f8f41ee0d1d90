"""Coverage of the rate-gyro budgets over many seeds (issue 17): per item, how often the
bench's true value lies within the reported U, with the binomial uncertainty.

    PYTHONPATH=$PWD python benchmarks/bench_rate_coverage.py [--spec iec62047-20] [--seeds 200]

The programme is the built-in protocol reduced to the sizes of
gonio.pipeline.rate_coverage.REDUCED (stated there); the bench is study_bench().
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--spec", default="jjf1535-2015")
    ap.add_argument("--seeds", type=int, default=200)
    ap.add_argument("--first", type=int, default=1000)
    a = ap.parse_args(argv)
    from gonio.pipeline.rate_coverage import coverage_study, reduced_protocol

    with tempfile.TemporaryDirectory() as d:
        proto = reduced_protocol(a.spec, Path(d) / "reduced.toml")
        t0 = time.perf_counter()
        df = coverage_study(a.spec, range(a.first, a.first + a.seeds), protocol=str(proto))
        wall = time.perf_counter() - t0
    print(f"{a.spec}: {a.seeds} seeds, reduced protocol, {wall:.0f} s")
    print(f"{'item':32s} {'clause':10s} {'n':>4s} {'cover':>6s} {'u':>6s} {'Wilson 95 %':>14s} "
          f"{'med|e|/u':>8s} {'max|e|/u':>8s}")
    bad = 0
    for r in df.itertuples():
        flag = "" if r.coverage >= 0.9 else "  < 90 %"
        bad += r.coverage < 0.9
        print(f"{r.key:32s} {r.clause:10s} {r.n:4d} {r.coverage:6.3f} {r.u_coverage:6.3f} "
              f"[{r.wilson_low:.3f}, {r.wilson_high:.3f}] {r.median_norm_error:8.2f} "
              f"{r.max_norm_error:8.2f}{flag}")
    return 0 if bad == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
