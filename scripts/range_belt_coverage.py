"""Coverage of the stated interval of a corrected range (K_l, C_v, C_g: the range's confidence
belt, ``uncertainty.stdev.range_belt_interval``) over the pattern of the true values.

    python scripts/range_belt_coverage.py [--repeats 200] [--seed 2] [--draws 4000]
        [--patterns 3/3,2/4,1/5,spaced,random] [--d 0,1,2.5,4,6,10] [--belt robust]

Six true values of range d (σ = 1 the errors' standard deviation, independent normal):
``3/3`` three high, three low, alternating (a third-order table error); ``2/4`` and ``1/5``
two and one high, the rest low (``1/5`` one outlier); ``spaced`` evenly spaced from 0 to d
(one value at each extreme, as the measured pattern usually looks); ``random`` one value at
each extreme, the rest uniform between, drawn per repeat. Each repeat measures x = t + e,
e ~ N(0, 1) (seeded ``--seed``, the same for every case), and states the interval from the
same ``--draws`` error draws as the budgets (seed 7); it prints, per case, the share of
repeats whose interval holds d with its Clopper–Pearson 95 % interval, the mean width, and
z = (value − d)/u of the corrected value (which takes the measured pattern). The truth d is
the simulation's own, never gonio's. ``--belt measured`` states the belt along the measured
pattern alone (the construction before the pattern-robust one).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy import stats

from uncertainty.stdev import corrected_range, range_belt_interval

N = 6


def true_values(name: str, d: float, rng: np.random.Generator) -> np.ndarray:
    """The six true values of the pattern ``name`` at range d."""
    fixed = {"3/3": [1, 0, 1, 0, 1, 0], "2/4": [1, 0, 0, 1, 0, 0], "1/5": [0, 0, 1, 0, 0, 0],
             "spaced": [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]}
    if name in fixed:
        return d * np.asarray(fixed[name], dtype=float)
    if name == "random":
        t = rng.uniform(0.0, 1.0, N)
        t[rng.choice(N, 2, replace=False)] = [0.0, 1.0]
        return d * t
    raise SystemExit(f"range_belt_coverage: unknown pattern {name!r} (--patterns)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=200)
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("--draws", type=int, default=4000)
    ap.add_argument("--patterns", default="3/3,2/4,1/5,spaced,random")
    ap.add_argument("--d", default="0,1,2.5,4,6,10")
    ap.add_argument("--belt", choices=("robust", "measured"), default="robust")
    a = ap.parse_args()
    draws = np.random.default_rng(7).normal(0.0, 1.0, (a.draws, N))
    print("pattern  d/σ  covered  CP95            width  z mean  z sd  ms/repeat")
    for name in a.patterns.split(","):
        for d in (float(v) for v in a.d.split(",")):
            rng = np.random.default_rng(a.seed)
            hit, width, z = 0, [], []
            t0 = time.process_time()
            for _ in range(a.repeats):
                x = true_values(name, d, rng) + rng.normal(0.0, 1.0, N)
                c = corrected_range(x, draws)
                lo, hi = (c.interval if a.belt == "robust"
                          else range_belt_interval(x, draws, patterns="measured"))
                hit += lo <= d <= hi
                width.append(hi - lo)
                z.append((c.value - d) / c.u)
            k, n = hit, a.repeats
            ci_lo = stats.beta.ppf(0.025, k, n - k + 1) if k > 0 else 0.0
            ci_hi = stats.beta.ppf(0.975, k + 1, n - k) if k < n else 1.0
            ms = (time.process_time() - t0) / n * 1e3
            print(f"{name:7s} {d:4.1f}  {100 * k / n:5.1f} %  [{100 * ci_lo:4.1f}, "
                  f"{100 * ci_hi:5.1f}] %  {np.mean(width):5.2f}  {np.mean(z):+5.2f}  "
                  f"{np.std(z, ddof=1):4.2f}  {ms:5.0f}", flush=True)


if __name__ == "__main__":
    main()
