"""Coverage of U(K) on the study's trials with the chamber's temperature logged and not
logged: the two readings of K's chamber line ``K_T``
(``gonio.specs.ogam_draft.item_uncertainty.chamber_temperature_line``).

    python scripts/k_chamber_coverage.py [--bench fog] [--trials 40] [--sample-rate-hz 100]
                                         [--seed 20261129] [--cases typeb,worst]

Each trial is the one ``gonio validate --bench B --cases typeb,worst --trials N --seed S
--sample-rate-hz R`` runs (the same trial seeds, benches and protocol: 7.1 and 7.4, every
Type B effect drawn, α_K within the bound ``K_T`` takes). Its readings are calibrated twice:
as written (the bench logs the chamber's temperature in the metadata ``temperature_c``: ``K_T``
rectangular at the logged deviation; the study's own numbers) and with ``temperature_c``
removed (``K_T`` the product of two uniforms, u = |α_K|max·ΔT_max/3). The truth is the
instrument's own K at the reference temperature from the bench's parameters
(``item_coverage.scale_factor_truth``). Prints, per case and reading, the coverage
|K − K_true| ≤ U, its Clopper–Pearson 95 % interval and z = (K − K_true)/u_c's mean and sd.
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from gonio.analysis.coverage import clopper_pearson
from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.calibration import analyse
from gonio.specs.ogam_draft.item_coverage import scale_factor_truth
from gonio.specs.ogam_draft.readings import Readings
from gonio.specs.ogam_draft.study import case_bench, study_protocol, trial_bench, trial_seed


def errors(case: str, bench: str, trials: int, rate_hz: float, seed: int) -> dict:
    """{reading: [(K − K_true, U, u_c), …]} over the case's trials."""
    proto = study_protocol("ogam-draft", False)
    cb = case_bench(case, replace(load_bench(bench), sample_rate_hz=rate_hz), proto)
    out = {"logged": [], "not logged": []}
    for i in range(trials):
        sd = trial_seed(seed, case, i)
        res = run_session(proto, trial_bench(case, cb, proto, sd), seed=sd)
        df = res.readings.copy()
        df["line"] = np.arange(2, len(df) + 2)
        k_true = scale_factor_truth(res.truth)[0]
        for key, md in (("logged", dict(res.metadata)),
                        ("not logged", {k: v for k, v in res.metadata.items()
                                        if k != "temperature_c"})):
            b = analyse(Readings(df, md), proto, budget="draft").item_uncertainty["scale_factor"]
            out[key].append((b.value - k_true, b.U, b.u_c))
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bench", default="fog")
    ap.add_argument("--trials", type=int, default=40)
    ap.add_argument("--sample-rate-hz", type=float, default=100.0)
    ap.add_argument("--seed", type=int, default=20261129)
    ap.add_argument("--cases", default="typeb,worst")
    a = ap.parse_args(argv)
    for case in a.cases.split(","):
        for key, v in errors(case, a.bench, a.trials, a.sample_rate_hz, a.seed).items():
            d, U, u = np.array(v).T
            hits = int(np.sum(np.abs(d) <= U))
            lo, hi = clopper_pearson(hits, a.trials)
            z = d / u
            print(f"{a.bench} {case:6s} {key:11s} {hits}/{a.trials} = {100 * hits / a.trials:.1f} % "
                  f"CP95 [{100 * lo:.0f}, {100 * hi:.0f}] %, z mean {z.mean():+.2f} "
                  f"sd {z.std(ddof=1):.2f}", flush=True)


if __name__ == "__main__":
    main()
