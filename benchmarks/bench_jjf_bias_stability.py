"""Coverage of the JJF 1535 7.2.10 bias stability statement on the study bench: how often
the stated one-sided 95 % limit [0, B_s + U] holds the bench's B_s (√E[s²] from the noise
covariance), with the Clopper–Pearson 95 % interval, and z = (B_s − truth)/u_c.

    PYTHONPATH=$PWD python benchmarks/bench_jjf_bias_stability.py [--first 5000] [--seeds 200]

Seeds first … first + seeds − 1, each a full virtual calibration on the reduced programme
(SPEC.coverage.reduced) and the study bench (as benchmarks/bench_rate_coverage.py). Figures
in docs/jjf1535-readings.md#7210-bias-stability.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--first", type=int, default=5000)
    ap.add_argument("--seeds", type=int, default=200)
    a = ap.parse_args(argv)
    import numpy as np
    from scipy.stats import binomtest

    from gonio.pipeline.coverage import reduced_protocol, study_bench, trial_records
    from gonio.specs import get

    spec = "jjf1535-2015"
    rows = []
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as d:
        proto = str(reduced_protocol(spec, Path(d) / "reduced.toml"))
        bench = study_bench(get(spec))
        for seed in range(a.first, a.first + a.seeds):
            r = trial_records(spec, bench, proto, seed)["bias_stability"]
            if r["value"] is not None:
                rows.append((r["value"], r["truth"], r["U"], r["u_c"]))
    v, t, U, u = (np.array(c) for c in zip(*rows))
    hits = int(np.sum(t <= v + U))
    ci = binomtest(hits, len(rows)).proportion_ci(method="exact")
    z = (v - t) / u
    print(f"JJF 1535 7.2.10 bias stability, seeds {a.first}-{a.first + a.seeds - 1}, "
          f"{time.perf_counter() - t0:.0f} s")
    print(f"stated limit holds the truth: {hits}/{len(rows)} = {hits / len(rows):.3f} "
          f"(Clopper-Pearson 95 % [{ci.low:.3f}, {ci.high:.3f}])")
    print(f"z = (B_s - truth)/u_c: mean {z.mean():+.2f}, sd {z.std(ddof=1):.2f}; "
          f"mean limit {np.mean((v + U) / v):.3f}·B_s; truth {t.mean():.2f} °/h; "
          f"nu = (B_s/u_c)²/2: median {np.median(0.5 * (v / u) ** 2):.0f}; "
          f"|value - truth| <= U (the generic study's count): {int(np.sum(abs(v - t) <= U))}")
    return 0 if ci.high >= 0.95 and 0.7 <= z.std(ddof=1) <= 1.3 else 1


if __name__ == "__main__":
    sys.exit(main())
