"""Coverage of the rate-gyro budgets over many seeds (issue 17): per item, how often the
bench's true value lies within the reported U, with the binomial uncertainty.

    PYTHONPATH=$PWD python benchmarks/bench_rate_coverage.py [--spec iec62047-20] [--seeds 200]

The programme is the built-in protocol reduced to the sizes of
SPEC.coverage.reduced (stated there); the bench is SPEC.coverage.study_bench(). The seeds
are first … first + seeds − 1 (serial, in this process). The same study in parallel, with
SeedSequence seeds, is ``gonio validate --spec <spec> --trials 200`` (docs/jjf1535-readings.md).
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
    from gonio.pipeline.coverage import coverage_study, format_coverage, reduced_protocol

    with tempfile.TemporaryDirectory() as d:
        proto = reduced_protocol(a.spec, Path(d) / "reduced.toml")
        t0 = time.perf_counter()
        df = coverage_study(a.spec, range(a.first, a.first + a.seeds), protocol=str(proto))
        wall = time.perf_counter() - t0
    print(format_coverage(df, f"{a.spec}: {a.seeds} seeds, reduced protocol, {wall:.0f} s"),
          end="")
    return 0 if (df["coverage"] >= 0.9).all() else 1

if __name__ == "__main__":
    sys.exit(main())
