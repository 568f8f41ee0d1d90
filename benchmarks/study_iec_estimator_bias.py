"""Monte Carlo of the two IEC 62047-20 estimator biases corrected (docs/iec62047-20-readings.md,
5.1.3.7 and 5.3.3.9): the largest of several sample spreads, and the start-up time count
where the transient flattens. Prints, per case, the reading's and the estimate's mean error
and the coverage of the stated interval (5.1.3.7), or the count's and the corrected value's
mean error against the closed-form truth (5.3.3.9).

    PYTHONPATH=$PWD python benchmarks/study_iec_estimator_bias.py [--records 1500] [--seed 7] [--only unequal]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def spreads(seed: int, n_rec: int) -> None:
    from gonio.specs.iec62047_20.formulas import max_spread_estimate

    rng = np.random.default_rng(seed)
    print("5.1.3.7  true σ_i        s    reading   estimate  cover   z mean  z sd   (reading's χ² interval: cover)")
    from scipy import stats
    for sig, n in (((1.0, 1.0), 300), ((1.0, 1.0), 50), ((1.0, 0.8), 50), ((1.0, 0.95), 300),
                   ((1.0, 1.0, 1.0), 50)):
        truth = max(sig) * math.sqrt((n - 1) / n)       # √E[population variance]
        raw, est, cov, z, cov_raw = [], [], [], [], []
        for _ in range(n_rec):
            d = [float(np.std(s * rng.standard_normal(n))) for s in sig]
            r = max_spread_estimate(d, [n - 1] * len(d))
            raw.append(r["reading"] / truth - 1)
            est.append(r["value"] / truth - 1)
            cov.append(r["interval"][0] <= truth <= r["interval"][1])
            z.append((r["value"] - truth) / r["u_c"])
            top = max(d)
            cov_raw.append(top * math.sqrt((n - 1) / stats.chi2.ppf(0.975, n - 1)) <= truth
                           <= top * math.sqrt((n - 1) / stats.chi2.ppf(0.025, n - 1)))
        print(f"         {str(sig):15s} {n:4d}  {100 * np.mean(raw):+6.2f} %  {100 * np.mean(est):+6.2f} %"
              f"  {np.mean(cov):.3f}  {np.mean(z):+.2f}   {np.std(z, ddof=1):.2f}   ({np.mean(cov_raw):.3f})")


def unequal_lengths(seed: int, n_rec: int) -> None:
    """The interval of max σ_i where the records' ν differ (each δ_i = σ_i·√(χ²_ν_i/ν_i)):
    coverage, each side's misses, and the width against one record's exact χ² interval."""
    from scipy import stats

    from gonio.specs.iec62047_20.formulas import max_spread_estimate

    rng = np.random.default_rng(seed)
    print("5.1.3.7  true σ_i        ν_i          cover   below   above   width/σ  (one record's χ² width/σ at ν_top)")
    for sig, nu in (((1.0, 2.0), (299, 4)), ((1.0, 1.5), (299, 9)), ((1.0, 1.0), (4, 299)),
                    ((1.0, 1.0), (299, 299)), ((1.0, 1.0, 1.0), (49, 49, 49))):
        s, v = np.array(sig), np.array(nu, dtype=float)
        truth, j = float(s.max()), int(np.argmax(s))
        lo_m = hi_m = 0
        w = []
        for _ in range(n_rec):
            lo, hi = max_spread_estimate(s * np.sqrt(rng.chisquare(v) / v), v)["interval"]
            lo_m += truth < lo
            hi_m += truth > hi
            w.append((hi - lo) / truth)
        one = (math.sqrt(v[j] / stats.chi2.ppf(0.025, v[j]))
               - math.sqrt(v[j] / stats.chi2.ppf(0.975, v[j])))
        print(f"         {str(sig):15s} {str(nu):12s} {1 - (lo_m + hi_m) / n_rec:.3f}  "
              f"{lo_m / n_rec:.3f}   {hi_m / n_rec:.3f}   {np.mean(w):.3f}    ({one:.3f})")


def startup(seed: int, n_rec: int) -> None:
    from gonio.specs._rate_family import formulas as rg
    from gonio.specs.iec62047_20.items import startup_time_record
    from tests.test_iec_estimator_bias import (A_DPS, BAND_DPS, TAU_S, _closed_form_truth,
                                               _white_records)
    from tests.test_iec_startup_tc_ratio import _bench_noise_records

    truth = _closed_form_truth()
    grid = TAU_S * math.log(A_DPS / BAND_DPS) - truth
    print(f"5.3.3.9  closed-form truth {truth:.1f} s; smoothing-grid offset {grid:+.2f} s")
    print("         noise                       records  count − truth   corrected − truth   se    mean correction")
    cases = [("white 0.03 °/s per sample", lambda r: (_white_records(r, n_rec, 0.03), None)),
             ("white 0.05 °/s per sample", lambda r: (_white_records(r, n_rec, 0.05), None)),
             ("bench generator, walk × 1", lambda r: _bench_noise_records(r, n_rec, 1.0)),
             ("bench generator, walk × 2", lambda r: _bench_noise_records(r, n_rec, 2.0))]
    for i, (name, make) in enumerate(cases):
        recs, kb = make(np.random.default_rng(seed + i))
        du = (lambda a, b: 0.0) if kb is None else \
            (lambda a, b, k2=kb[0], b2=kb[1]: rg.record_difference_u_coef(k2, b2, a, b))
        raw, cor, c = [], [], []
        for tt, ys, y in recs:
            r = startup_time_record(tt, ys, y, BAND_DPS, du)
            raw.append(r["count_s"] - truth)
            cor.append(r["corrected_s"] - truth)
            c.append(r["curvature_bias_s"])
        raw = np.array(raw)
        print(f"         {name:27s} {raw.size:7d}  {raw.mean():+8.2f} s     {np.mean(cor):+8.2f} s"
              f"        {raw.std(ddof=1) / math.sqrt(raw.size):5.2f}  {np.mean(c):6.2f} s")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--records", type=int, default=1500)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--only", choices=("spreads", "unequal", "startup"), default=None)
    a = ap.parse_args(argv)
    if a.only == "unequal":
        unequal_lengths(a.seed, a.records)
        return 0
    spreads(a.seed, a.records)
    unequal_lengths(a.seed, a.records)
    startup(a.seed, max(a.records // 3, 100))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
