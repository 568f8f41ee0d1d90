"""Many-record check of IEC 62047-20 5.4.5.2 (ARW) and 5.1.3.7 (scale-factor stability) on
the built-in programme's own records: per seed the bench of
``bench_rate_coverage_builtin.py`` (equipment drawn per trial) runs only the segments
these two items read — the scale-factor run that gives FullScale and a_BASE, the
stability rates and the static record (72 000 samples at 0.1 s) — gonio calibrates them,
and z = (value − truth)/u_c against the truth the specification computes from the bench's
physical parameters (``gonio.specs.iec62047_20.truth``: the ARW parameter at T_BASE; the
square root of the expected population variance at each constant rate over the noise-free
FullScale), never from the estimator.

    nice python benchmarks/study_iec_arw_stability_records.py FIRST COUNT OUT.jsonl
    python benchmarks/study_iec_arw_stability_records.py --table 'OUT*.jsonl'

The first form appends one JSON line per seed (both items' value, truth, U, u_c); the
second prints, per item, n, the coverage of U with its Clopper–Pearson 95 % interval, z
mean (with its standard error), sd z with its χ² 95 % interval (normal z) and a bootstrap
95 % interval, the share of |z| ≤ 1 and ≤ 2, and how often 40 records drawn from these
would show an sd z below 0.70 (the built-in programme's 40-trial tables).
"""
from __future__ import annotations

import glob
import json
import sys
from pathlib import Path

import numpy as np

ITEMS = ("arw", "sf_stability")


def run(first: int, count: int, out: str) -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import gonio.specs.iec62047_20.simulate as sim
    from bench_rate_coverage_builtin import bench_for
    from gonio.pipeline.coverage import trial_records

    full = sim.plan
    sim.plan = lambda proto, b: [s for s in full(proto, b) if s.test in ("scale_factor", "static")]
    bench = bench_for("iec62047-20", True)
    with open(out, "a", encoding="utf-8") as f:
        for s in range(first, first + count):
            r = trial_records("iec62047-20", bench, "iec62047-20", s)
            f.write(json.dumps({"seed": s, **{k: r[k] for k in ITEMS}}) + "\n")
            f.flush()


def table(pattern: str) -> str:
    from scipy import stats

    from gonio.analysis.coverage import clopper_pearson

    recs = [json.loads(x) for p in sorted(glob.glob(pattern)) for x in open(p, encoding="utf-8")]
    lines = []
    for k in ITEMS:
        r = [x[k] for x in recs if x[k]["value"] is not None]
        v, t, U, u = (np.array([y[q] for y in r]) for q in ("value", "truth", "U", "u_c"))
        z = (v - t) / u
        n, sd = z.size, float(z.std(ddof=1))
        lo = sd * np.sqrt((n - 1) / stats.chi2.ppf(0.975, n - 1))
        hi = sd * np.sqrt((n - 1) / stats.chi2.ppf(0.025, n - 1))
        rng = np.random.default_rng(0)
        boot = np.array([rng.choice(z, n).std(ddof=1) for _ in range(4000)])
        sd40 = np.array([rng.choice(z, 40).std(ddof=1) for _ in range(4000)])
        h = int((np.abs(v - t) <= U).sum())
        cp = clopper_pearson(h, n)
        lines.append(
            f"{k} ({r[0]['clause']}): n {n}, cover {h / n:.3f} [{cp[0]:.3f}, {cp[1]:.3f}], "
            f"z mean {z.mean():+.2f} (se {sd / np.sqrt(n):.2f}), sd z {sd:.2f} "
            f"(χ² 95 % [{lo:.2f}, {hi:.2f}], bootstrap [{np.quantile(boot, 0.025):.2f}, "
            f"{np.quantile(boot, 0.975):.2f}]), |z| ≤ 1 {np.mean(np.abs(z) <= 1):.3f}, "
            f"|z| ≤ 2 {np.mean(np.abs(z) <= 2):.3f}, max|z| {np.abs(z).max():.2f}; "
            f"value/truth mean {np.mean(v / t):.4f}; P(sd z of 40 < 0.70) {np.mean(sd40 < 0.70):.2f}")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    if sys.argv[1] == "--table":
        print(table(sys.argv[2]), end="")
    else:
        run(int(sys.argv[1]), int(sys.argv[2]), sys.argv[3])
