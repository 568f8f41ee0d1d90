"""Benchmark: coverage of EVERY certified item of the gyro triad (issue 24).

For ``--trials`` fresh seeds the built-in programme (protocol ``triad-alignment``, bench
``mems-triad``: the alignment session and the chamber programme) is simulated with
``SPEC.simulate`` and calibrated as ``gonio calibrate`` does (``SPEC.screen`` then
``SPEC.calibrate``, BIC orders, sensor temperature, no Monte Carlo); every item of the
result that has a true value — the system matrix M_ij, the biases b_i (long-term), the
cross-axis sensitivities S_ij, the residual leakage L_ij (against what this trial's
alignment leaves, :func:`realised_leakage`) and the thermal coefficients K/b/ARW — is
compared with ``SPEC.truth`` (the bench's physical parameters; closed form,
no estimator). Prints per item the coverage of U with its 95 % Clopper–Pearson interval,
the mean and sd of z = (value − truth)/u_c, flags (< 90 %, sd z < 0.3) and the time per
trial; the items without a truth are named. Figures: README (triad section),
docs/alignment.md §Coverage, docs/thermal-model.md §7.

The trial is the one of ``gonio validate --spec triad-alignment`` (its ``typeb`` case draws the
table the same way; :mod:`gonio.specs.triad_alignment.study`, which also has the worst case).

Run: ``python benchmarks/bench_triad_coverage.py [--trials 100] [--seed 2500000]``
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout

from gonio.pipeline.coverage import coverage_table_from, format_coverage  # noqa: E402
from gonio.specs.triad_alignment.study import triad_trial  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--trials", type=int, default=100)
    ap.add_argument("--seed", type=int, default=2_500_000, help="first seed (fresh: no test uses it)")
    ap.add_argument("--jsonl", help="append each trial's records to this file as it ends "
                                    "(a long study can be summarised before it finishes)")
    ap.add_argument("--fixed-equipment", action="store_true",
                    help="the bench file's exact table in every trial (no Type B draw)")
    ap.add_argument("--summarise", nargs="+", metavar="JSONL",
                    help="print the table from trial files written by --jsonl; no new trials")
    a = ap.parse_args()
    if a.summarise:
        rows = [json.loads(line) for f in a.summarise
                for line in Path(f).read_text(encoding="utf-8").splitlines() if line.strip()]
        rows.sort(key=lambda r: r["seed"])
        seeds = [r["seed"] for r in rows]
        report([r["items"] for r in rows], {k for r in rows for k in r["no_truth"]},
               f"seeds {min(seeds)}…{max(seeds)} ({len(seeds)} trials)",
               sum(r["s"] for r in rows) / len(rows))
        return
    t0 = time.perf_counter()
    trials, no_truth = [], set()
    for k, s in enumerate(range(a.seed, a.seed + a.trials)):
        t1 = time.perf_counter()
        rec, nt = triad_trial(s, draw=not a.fixed_equipment)
        trials.append(rec)
        no_truth.update(nt)
        if a.jsonl:
            with open(a.jsonl, "a", encoding="utf-8") as f:
                f.write(json.dumps({"seed": s, "items": rec, "no_truth": nt,
                                    "s": time.perf_counter() - t1}) + "\n")
        if sys.stderr.isatty():
            print(f"\r{k + 1}/{a.trials}", end="", file=sys.stderr, flush=True)
    report(trials, no_truth, f"seeds {a.seed}…{a.seed + a.trials - 1} ({a.trials} trials)",
           (time.perf_counter() - t0) / a.trials)


def report(trials: list, no_truth: set, seeds: str, per_trial_s: float) -> None:
    df = coverage_table_from(trials)
    print(format_coverage(df, f"triad items: {seeds}, protocol triad-alignment, bench "
                              f"mems-triad (built-in programme), gonio calibrate defaults"), end="")
    print(f"items without a truth (not studied): {', '.join(sorted(no_truth)) or 'none'}")
    print(f"items measured in fewer trials were chosen by the order selection only then "
          f"(n column); {per_trial_s:.2f} s per trial")


if __name__ == "__main__":
    main()
