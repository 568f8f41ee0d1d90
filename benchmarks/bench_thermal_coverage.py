"""Benchmark: coverage of the triad's certified thermal coefficients (issue 24).

For ``--trials`` fresh seeds the built-in chamber programme (protocol ``triad-alignment``,
bench ``mems-triad``, the gyro's sensor temperature, BIC orders) is simulated and
identified as ``gonio calibrate`` does; every certified coefficient (``K_z_theta1``,
``b_z_theta3``, ``ARW_z_c0`` …) is compared with the bench's closed-form truth
(:func:`gonio.bench.triad.true_thermal_coefficients`). Prints per coefficient the
coverage of U with its 95 % Clopper–Pearson interval, the mean and sd of
z = (value − truth)/u_c, and the time per trial. Figures: docs/thermal-model.md §7.

Run: ``python benchmarks/bench_thermal_coverage.py [--trials 200] [--seed 2400000]``
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout

from gonio.pipeline.coverage import coverage_table_from, format_coverage  # noqa: E402
from gonio.specs.triad_alignment.simulate import thermal_trial  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--seed", type=int, default=2_400_000, help="first seed (fresh: no test uses it)")
    ap.add_argument("--criterion", default="bic")
    a = ap.parse_args()
    t0 = time.perf_counter()
    trials = [thermal_trial(s, criterion=a.criterion) for s in range(a.seed, a.seed + a.trials)]
    dt = time.perf_counter() - t0
    df = coverage_table_from(trials)
    print(format_coverage(df, f"triad thermal coefficients: {a.trials} trials, seeds {a.seed}…"
                              f"{a.seed + a.trials - 1}, protocol triad-alignment, bench "
                              f"mems-triad, sensor temperature, criterion {a.criterion}"), end="")
    print(f"items measured in fewer trials were chosen by the order selection only then "
          f"(n column); {dt / a.trials:.2f} s per trial")


if __name__ == "__main__":
    main()
