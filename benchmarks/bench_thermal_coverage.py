"""Benchmark: coverage of the triad's certified thermal values.

For ``--trials`` fresh seeds the built-in programme (protocol ``triad-alignment``, bench
``mems-triad``: the chamber programme, and the alignment session for its static record) is
simulated on the bench with the rate table's errors drawn from the seed
(``simulate.for_trial``; ``--fixed-equipment``: the bench file's table) and identified as
``gonio calibrate`` does (sensor temperature, BIC orders, the K values with the table's Type B
line); every
certified value — K and b at each set point and supply level (``K_z_t1_v2``, ``b_z_t3_v1``
…), ARW at each set point — is compared with ``SPEC.truth`` (the bench's polynomials in
closed form at the soaked set point, :func:`gonio.specs.triad_alignment.bench.true_thermal_coefficients`;
no estimator). Prints per item the coverage of U with its 95 % Clopper–Pearson interval, the
mean and sd of z = (value − truth)/u_c, and the time per trial; with ``--jsonl`` each trial's
records are appended as it ends and ``--summarise`` prints the table from such files.
Figures: docs/thermal-model.md §7.

Run: ``python benchmarks/bench_thermal_coverage.py [--trials 200] [--seed 2400000]``
"""

from __future__ import annotations

import argparse
import json
import math
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
    ap.add_argument("--fixed-equipment", action="store_true",
                    help="the bench file's rate table in every trial (default: its errors "
                         "drawn per trial, simulate.for_trial)")
    ap.add_argument("--jsonl", help="append each trial's records to this file as it ends")
    ap.add_argument("--summarise", nargs="+", metavar="JSONL",
                    help="print the table from trial files written by --jsonl; no new trials")
    a = ap.parse_args()
    if a.summarise:
        rows = sorted((json.loads(line) for f in a.summarise
                       for line in Path(f).read_text(encoding="utf-8").splitlines()
                       if line.strip()), key=lambda r: r["seed"])
        seeds = [r["seed"] for r in rows]
        report([r["items"] for r in rows], f"{len(rows)} trials, seeds {min(seeds)}…"
               f"{max(seeds)}", a.criterion, sum(r.get("s", math.nan) for r in rows) / len(rows))
        return
    t0 = time.perf_counter()
    trials = []
    for s in range(a.seed, a.seed + a.trials):
        t1 = time.perf_counter()
        trials.append(thermal_trial(s, criterion=a.criterion, draw=not a.fixed_equipment))
        if a.jsonl:
            with open(a.jsonl, "a", encoding="utf-8") as f:
                f.write(json.dumps({"seed": s, "items": trials[-1],
                                    "s": time.perf_counter() - t1}) + "\n")
    report(trials, f"{a.trials} trials, seeds {a.seed}…{a.seed + a.trials - 1}", a.criterion,
           (time.perf_counter() - t0) / a.trials)


def report(trials: list, seeds: str, criterion: str, per_trial_s: float) -> None:
    df = coverage_table_from(trials)
    print(format_coverage(df, f"triad thermal values at the set points: {seeds}, protocol "
                              f"triad-alignment, bench mems-triad, sensor temperature, "
                              f"criterion {criterion}"), end="")
    print(f"{per_trial_s:.2f} s per trial")

if __name__ == "__main__":
    main()
