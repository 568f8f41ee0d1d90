"""Study: coverage of the optical draft's zero-stability noise model (the expected B_s given
beside the draft's B_s, item ``zero_stability_model`` of ``gonio validate --all-items``)
with the fit's uncertainties by parametric bootstrap (20 records) and by the fit's
covariance, on the same sessions.

Each trial simulates the whole draft protocol on the study bench (``gonio validate``'s
``default`` case and trial seeds) at ``--sample-rate-hz``, calibrates the readings, fits
the five-term model to the continuous 7.3 record once and states the model's expected B_s
with each uncertainty method (:func:`gonio.specs.ogam_draft.zero_stability_noise.expected_zero_stability`,
:func:`gonio.specs.ogam_draft.item_uncertainty.zero_stability_model_budget`, k as the
protocol fixes it, else t_95(ν_eff)); the truth is the population value from the bench's
noise parameters (:func:`gonio.specs.ogam_draft.item_coverage.zero_stability_truth`).
Prints, per method, coverage of |B − truth| ≤ U with its Clopper–Pearson interval and the
spread of z = (B − truth)/u_c (:func:`gonio.analysis.coverage.two_sided`: both sides), and
the CPU time of each method's fit. Not part of the test run.

    PYTHONPATH=$PWD python benchmarks/zero_stability_model_coverage.py --trials 40 \
        [--sample-rate-hz 1000] [--workers 2] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

from gonio.specs.ogam_draft.calibration import ZERO_STABILITY_NOISE_SAMPLES

#: name: (bootstrap records, most samples analysed or None for the whole record).
METHODS = {"bounded bootstrap-20": (20, ZERO_STABILITY_NOISE_SAMPLES),
           "bounded covariance": (0, ZERO_STABILITY_NOISE_SAMPLES),
           "whole covariance": (0, None),
           "whole bootstrap-20": (20, None)}


def trial(index: int, seed: int, rate_hz: float, methods: tuple) -> dict:
    """One session; the model's B_s, U, u_c by each method and the population truth."""
    import numpy as np

    from gonio.analysis.noise import analyse_static
    from gonio.specs.ogam_draft.zero_stability_noise import expected_zero_stability
    from gonio.specs.ogam_draft.bench import load_bench, run_session
    from gonio.specs.ogam_draft.readings import Readings
    from gonio.specs.ogam_draft.protocol import load_protocol
    from gonio.specs.ogam_draft.calibration import analyse
    from gonio.specs.ogam_draft.item_coverage import zero_stability_truth
    from gonio.specs.ogam_draft.item_uncertainty import zero_stability_model_budget
    from gonio.specs.ogam_draft.study import trial_bench, trial_seed

    proto = load_protocol("ogam-draft")
    bench = load_bench("rlg")
    bench = replace(bench, sample_rate_hz=float(rate_hz))
    sd = trial_seed(seed, "default", index)
    res = run_session(proto, trial_bench("default", bench, proto, sd), seed=sd)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    rep = analyse(Readings(df, dict(res.metadata)), proto)
    zs = rep.results.zero_stability
    rd = zs.tables["readings"]
    t = rd.loc[rd["series"] == zs.details["series"], "time_s"].to_numpy(dtype=float)
    truth = zero_stability_truth(res.truth, proto.session.static_s)
    rec = res.static_record
    out = {"index": index, "seed": sd, "truth": truth}
    for name in methods:
        boot, most = METHODS[name]
        d = 1 if most is None else max(1, -(-rec.time_s.size // most))
        c0 = time.process_time()
        noise = analyse_static(rec.time_s[::d], rec.angle_deg[::d], bootstrap=boot)
        cpu = time.process_time() - c0
        b = zero_stability_model_budget(expected_zero_stability(noise.fit, t,
                                                                proto.session.static_s),
                                        k=proto.annex_a.coverage_factor)
        out[name] = {"value": float(b.value), "U": float(b.U), "u_c": float(b.u_c),
                     "k": float(b.k), "cpu_s": cpu, "active": list(noise.fit.active)}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--trials", type=int, default=40)
    ap.add_argument("--seed", type=int, default=20261129)
    ap.add_argument("--sample-rate-hz", type=float, default=1000.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", default=None)
    ap.add_argument("--methods", default=",".join(METHODS),
                    help="comma-separated, of: " + ", ".join(METHODS))
    a = ap.parse_args(argv)
    methods = tuple(m.strip() for m in a.methods.split(","))
    from gonio.analysis.coverage import two_sided

    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(a.workers) as ex:
        rows = list(ex.map(trial, range(a.trials), [a.seed] * a.trials,
                           [a.sample_rate_hz] * a.trials, [methods] * a.trials))
    print(f"zero-stability model coverage: {a.trials} sessions of the whole draft on the rlg "
          f"study bench (default case, seed {a.seed}) at {a.sample_rate_hz:g} Hz, "
          f"{time.perf_counter() - t0:.0f} s wall, load {load:.1f} to {os.getloadavg()[0]:.1f}")
    summary = {}
    for name in methods:
        e = [r[name]["value"] - r["truth"] for r in rows]
        ts = two_sided(e, [r[name]["U"] for r in rows], [r[name]["u_c"] for r in rows])
        cpu = sum(r[name]["cpu_s"] for r in rows) / len(rows)
        k = sum(r[name]["k"] for r in rows) / len(rows)
        summary[name] = dict(ts, mean_fit_cpu_s=cpu, mean_k=k)
        print(f"  {name:21s} coverage {ts['coverage']:.1%} ({ts['hits']}/{ts['n']}, "
              f"Clopper-Pearson [{ts['cp_low']:.1%}, {ts['cp_high']:.1%}]), z mean "
              f"{ts['z_mean']:+.2f}, sd z {ts['z_sd']:.2f}, mean k {k:.2f}, flags "
              f"{ts['flags'] or 'none'}; fit CPU {cpu:.2f} s per session")
    if a.json:
        with open(a.json, "w", encoding="utf-8") as fh:
            json.dump({"trials": rows, "summary": summary}, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
