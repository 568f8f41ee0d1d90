"""IEC 62047-20 5.3.3.7 on the study programme: is the stated interval [0, upper] wider
than the scatter it is built on? Runs the trials of ``gonio validate --spec iec62047-20
--seed S`` (same bench, reduced protocol, trial i seeded by SeedSequence(S, spawn_key=
(stream, i))) and records, per trial, the differences D_T = B_up − B_down and the σ_T that
:func:`gonio.specs.iec62047_20.formulas.hysteresis_upper_iec` is given, then prints: D_T/σ_T
(mean, sd with its χ² 95 % interval, fraction within ±1.96; the truths δ_T are ≈ 0 on the
study bench, whose chamber has no lag), the PIT of the reading max|D_T| under δ_T = 0
(independent differences), z on u_c against the half-normal's √(1 − 2/π), and the upper
limit against the reading's spread.

    PYTHONPATH=$PWD nice python benchmarks/iec_hysteresis_sigma.py --seed 20261129 --trials 40
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
from pathlib import Path

import numpy as np


def trials(seed: int, n: int, records: str | None = None) -> list[dict]:
    from gonio.kit import get
    from gonio.pipeline import coverage as C
    from gonio.specs.iec62047_20 import formulas as ief

    spec = get("iec62047-20")
    bench = C.study_bench(spec, None)
    with tempfile.TemporaryDirectory() as d:
        proto = (spec.load_protocol or (lambda p: p))(
            str(C.reduced_protocol(spec.key, Path(d) / "reduced.toml")))
    calls, orig = [], ief.hysteresis_upper_iec

    def spy(reading, sds, p=0.95):
        calls.append((float(reading), [float(x) for x in sds]))
        return orig(reading, sds, p)

    ief.hysteresis_upper_iec = spy
    rows = []
    try:
        for i in range(n):
            sd = C.spawn_seed(seed, spec.coverage.stream, i)
            readings, truth = spec.run_trial(bench, proto, int(sd))
            calls.clear()
            it = C.screen_and_calibrate(spec, readings, proto).items["bias_hysteresis"]
            rows.append({"seed": int(sd), "diffs": [float(v) for v in
                                                    it.details["up_minus_down_dps"].values()],
                         "sds": calls[-1][1], "reading": calls[-1][0],
                         "value": float(it.value), "upper": float(it.uncertainty.interval[1]),
                         "u_c": float(it.uncertainty.u_c),
                         "truth": float(truth["items"]["bias_hysteresis"]["value"])})
            if records:
                with open(records, "a", encoding="utf-8") as f:
                    f.write(json.dumps(rows[-1]) + "\n")
    finally:
        ief.hysteresis_upper_iec = orig
    return rows


def report(rows: list[dict]) -> str:
    from scipy import stats

    z = np.array([v / s for r in rows for v, s in zip(r["diffs"], r["sds"])])
    n, sd = z.size, float(z.std(ddof=1))
    lo = sd * math.sqrt((n - 1) / stats.chi2.ppf(0.975, n - 1))
    hi = sd * math.sqrt((n - 1) / stats.chi2.ppf(0.025, n - 1))
    m = np.array([r["reading"] for r in rows])
    t = np.array([r["truth"] for r in rows])
    up = np.array([r["upper"] for r in rows])
    zc = (np.array([r["value"] for r in rows]) - t) / np.array([r["u_c"] for r in rows])
    pit = np.array([np.prod([2 * stats.norm.cdf(r["reading"] / s) - 1 for s in r["sds"]])
                    for r in rows])
    return "\n".join([
        f"{len(rows)} trials, {n} differences D_T/σ_T: mean {z.mean():+.3f}, sd {sd:.3f} "
        f"(χ² 95 % [{lo:.3f}, {hi:.3f}]), within ±1.96: {np.mean(np.abs(z) <= 1.96):.3f}",
        f"truth mean {t.mean():.4f} °/s (largest {t.max():.4f}); reading mean {m.mean():.4f}; "
        f"upper limit mean {up.mean():.4f}, median {np.median(up):.4f}; truth inside "
        f"{np.mean((t >= 0) & (t <= up)):.3f}",
        f"(upper − reading)/largest σ_T: mean "
        f"{np.mean([(r['upper'] - r['reading']) / max(r['sds']) for r in rows]):.2f}; "
        f"95 % quantile of reading − truth over the trials {np.quantile(m - t, 0.95):.4f}",
        f"PIT of the reading under δ_T = 0 (independent): mean {pit.mean():.3f} (uniform "
        f"0.5), sd {pit.std(ddof=1):.3f} (0.289), KS p {stats.kstest(pit, 'uniform').pvalue:.3f}",
        f"z on u_c: mean {zc.mean():+.2f}, sd {zc.std(ddof=1):.2f} (a half-normal's sd/σ "
        f"{math.sqrt(1 - 2 / math.pi):.3f})"])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=20261129)
    ap.add_argument("--trials", type=int, default=40)
    ap.add_argument("--records", help="append each trial's numbers (JSON lines) here")
    a = ap.parse_args(argv)
    print(report(trials(a.seed, a.trials, a.records)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
