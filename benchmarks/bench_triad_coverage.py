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

Run: ``python benchmarks/bench_triad_coverage.py [--trials 100] [--seed 2500000]``
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout

import numpy as np  # noqa: E402

from gonio.pipeline.coverage import coverage_table_from, format_coverage  # noqa: E402
from gonio.pipeline.dispatch import screen_and_calibrate  # noqa: E402
from gonio.specs import get  # noqa: E402


def triad_trial(seed: int, protocol: str = "triad-alignment", bench: str = "mems-triad",
                draw: bool = True) -> tuple[dict[str, dict], list[str]]:
    """One simulated + calibrated triad programme: ({item: {clause, value, truth, U, u_c}},
    [items without a truth]). ``draw``: the bench's laboratory Type B effects drawn from
    the seed (``simulate.for_trial``: the table's rate error, its axis at each
    orientation); the truth is the drawn bench's (the triad's own parameters, which the
    draw leaves as they are)."""
    from gonio.specs.triad_alignment.bench import load_triad_bench, load_triad_protocol
    from gonio.specs.triad_alignment.simulate import for_trial

    spec = get("triad-alignment")
    b = for_trial(bench, int(seed)) if draw else load_triad_bench(bench)
    truth = spec.truth(b, load_triad_protocol(protocol))
    with tempfile.TemporaryDirectory() as d:
        files = spec.simulate(d, protocol=protocol, bench=b, seed=int(seed))
        res = screen_and_calibrate(spec, files["readings"], protocol)
    out, no_truth = {}, []
    leak = realised_leakage(res, truth)
    for key, it in res.items.items():
        if key not in truth:
            no_truth.append(key)
            continue
        if not it.measured or it.uncertainty is None:
            continue
        out[key] = {"clause": it.clause, "value": float(it.value),
                    "truth": float(leak.get(key, truth[key]["value"])),
                    "U": float(it.uncertainty.U), "u_c": float(it.uncertainty.u_c)}
    return out, no_truth


def realised_leakage(res, truth: dict) -> dict[str, float]:
    """The leakage this trial's alignment leaves: (M̂⁻¹M − I)_ij with the certified M̂ and the
    bench's true M. The item L_ij states 0 ± U (zero for the estimate by construction;
    ``SPEC.truth`` gives the expectation 0), so its U is checked against what the alignment
    actually leaves, not against a constant that every trial matches."""
    ax = "xyz"
    if not all(res.items[f"M_{a}{b}"].measured for a in ax for b in ax):
        return {}
    m_hat = np.array([[res.items[f"M_{a}{b}"].value for b in ax] for a in ax], float)
    m = np.array([[truth[f"M_{a}{b}"]["value"] for b in ax] for a in ax], float)
    left = np.linalg.solve(m_hat, m) - np.eye(3)
    return {f"L_{a}{b}": float(left[i, j]) for i, a in enumerate(ax)
            for j, b in enumerate(ax) if i != j}


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
