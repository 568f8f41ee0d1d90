"""Targeted Monte Carlo of JJF 1535 7.2.11 B_r and 7.2.12 B_g on the coverage study's bench
(docs/validation-rate.md, "B_r and B_g on seed 20261214"): the item functions of
``gonio.specs.jjf1535.items`` on many virtual calibrations, against the truths of
``gonio.specs.jjf1535.truth``, without the other thirteen items.

Each trial runs the study's programme (``SPEC.coverage.reduced``, the study bench with its
equipment drawn per trial) and computes the scale factor (K for both items), B_r and B_g:

- ``--programme full``: the whole programme simulated (every segment, in order), so the
  trials of ``--validate-seed N`` are those of ``gonio validate --spec jjf1535-2015 --seed N``
  (trial i seeded by SeedSequence(N, spawn_key=(0, i))) — the items' values agree with the
  study's (screening aside); ``--programme segments``: only the segments the items read
  (B_r: bias, scale factor; B_g: g-sensitivity, static, scale factor; the bias records come
  first in the programme, so B_r's values are the full programme's), consecutive seeds from ``--first``.

Prints per item the coverage with its Clopper–Pearson 95 % interval, the z mean and sd (B_r:
the chi-square z, Φ⁻¹(F_χ²(ν s²/σ²; ν)); B_g: (value − truth)/u_c), for B_r the pooled
standard deviation of the records' biases against the truth (the truth's check: the
population value the estimator samples), for B_g the misses below and above the interval
and each axis's mean error.

    PYTHONPATH=$PWD python benchmarks/study_jjf_br_bg.py --trials 300 --programme segments --first 5000
    PYTHONPATH=$PWD python benchmarks/study_jjf_br_bg.py --trials 40 --programme full --validate-seed 20261214
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

#: the segments each item reads (with the scale factor's, for K)
SEGMENTS = {"B_r": ("bias", "scale_factor"), "B_g": ("g_sensitivity", "static", "scale_factor")}


def clopper_pearson(k: int, n: int) -> tuple[float, float]:
    from scipy.stats import beta
    lo = float(beta.ppf(0.025, k, n - k + 1)) if k > 0 else 0.0
    hi = float(beta.ppf(0.975, k + 1, n - k)) if k < n else 1.0
    return lo, hi


def trial(base, proto, seed: int, full: bool, items: set[str]) -> dict:
    from gonio.bench.rate_session import run_rate_session
    from gonio.formats.rate_readings import RateReadings
    from gonio.specs.jjf1535 import items as I
    from gonio.specs.jjf1535 import make_context
    from gonio.specs.jjf1535.protocol import null_output, plan
    from gonio.specs.jjf1535.truth import _g_truth, record_mean_variance
    from gonio.units import S_PER_H

    P = proto.sections
    b = base.for_trial(seed)
    need = {t for i in items for t in SEGMENTS[i]}
    segs = [s for s in plan(proto, b) if full or s.test in need]
    room = P["protocol"]["room_temperature_c"]
    md = {"spec": "jjf1535-2015", "null_output": repr(null_output(proto, b)),
          "latitude_deg": repr(b.latitude_deg), "output_unit": b.gyro.output_unit,
          "room_temperature_c": repr(room),
          "rate_table_u_rel": repr(b.equipment.rate_table_u_rel),
          "acquisition_u_rel": repr(b.equipment.acquisition_u_rel)}
    res = run_rate_session(segs, b, seed, room_temperature_c=room, metadata=md, noise=True)
    ctx = make_context(RateReadings(res.data, {k: str(v) for k, v in md.items()}), proto)
    sf = I.scale_factor(ctx)
    ctx = I.with_needs(ctx, {"scale_factor": sf})
    g = b.gyro
    out = {"seed": seed}
    if "B_r" in items:
        it = I.bias_repeatability(ctx)
        vm = record_mean_variance(b, P["protocol"]["sample_interval_s"], P["bias"]["samples"],
                                  P["protocol"]["warmup_s"])
        out["B_r"] = {"value": it.value, "upper": it.uncertainty.interval[1],
                      "truth": math.sqrt(g.bias_scatter_dps ** 2 + vm) * S_PER_H,
                      "B0": [r["B0_dph"] for r in I.bias_records(ctx)]}
    if "B_g" in items:
        it = I.g_sensitivity(ctx)
        kr = float(g.scale_factor_at(room, g.supply_nominal_v)) / sf.value
        tr = _g_truth(g, b.latitude_deg, kr)
        lo, hi = it.uncertainty.interval
        out["B_g"] = {"value": it.value, "truth": tr["value"], "lower": lo, "upper": hi,
                      "u_c": it.uncertainty.u_c,
                      "err": {a: it.details["per_axis_dph_per_g"][a] - tr["per_axis_dph_per_g"][a]
                              for a in "xyz"}}
    return out


def report(recs: list[dict]) -> None:
    from scipy.stats import chi2, norm

    n = len(recs)
    if "B_r" in recs[0]:
        r = [x["B_r"] for x in recs]
        hits = sum(x["truth"] <= x["upper"] for x in r)
        nu = len(r[0]["B0"]) - 1
        z = np.array([norm.ppf(chi2.cdf(nu * x["value"] ** 2 / x["truth"] ** 2, nu)) for x in r])
        b0 = np.array([x["B0"] for x in r])
        pooled = math.sqrt(float(np.sum((b0 - b0.mean(axis=1, keepdims=True)) ** 2)) / (n * nu))
        truth = math.sqrt(float(np.mean([x["truth"] ** 2 for x in r])))
        lo, hi = clopper_pearson(hits, n)
        print(f"7.2.11 B_r  n {n}  cover {hits / n:.3f} [{lo:.3f}, {hi:.3f}]  chi2 z mean "
              f"{z.mean():+.2f} sd {z.std(ddof=1):.2f}  pooled s of B_0 {pooled:.2f} °/h, "
              f"truth {truth:.2f} °/h (ratio {pooled / truth:.3f}, its sd "
              f"{1 / math.sqrt(2 * n * nu):.3f})")
    if "B_g" in recs[0]:
        r = [x["B_g"] for x in recs]
        below = sum(x["truth"] < x["lower"] for x in r)
        above = sum(x["truth"] > x["upper"] for x in r)
        hits = n - below - above
        z = np.array([(x["value"] - x["truth"]) / x["u_c"] for x in r])
        lo, hi = clopper_pearson(hits, n)
        print(f"7.2.12 B_g  n {n}  cover {hits / n:.3f} [{lo:.3f}, {hi:.3f}]  z mean "
              f"{z.mean():+.2f} sd {z.std(ddof=1):.2f}  truth above the interval {above}, "
              f"below {below}")
        for a in "xyz":
            e = np.array([x["err"][a] for x in r])
            print(f"    axis {a}: mean error {e.mean():+.2f} ± {e.std(ddof=1) / math.sqrt(n):.2f}"
                  f" (°/h)/g, sd {e.std(ddof=1):.2f}")


def main(argv=None) -> None:
    from gonio.analysis.coverage import spawn_seed
    from gonio.pipeline.coverage import reduced_protocol, study_bench
    from gonio.specs import get
    from gonio.specs.jjf1535.protocol import load_protocol

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=300)
    ap.add_argument("--programme", choices=("full", "segments"), default="segments")
    ap.add_argument("--first", type=int, default=5000, help="first seed (segments)")
    ap.add_argument("--validate-seed", type=int, default=None,
                    help="the trials of gonio validate --seed N (SeedSequence(N, (0, i)))")
    ap.add_argument("--items", default="B_r,B_g")
    a = ap.parse_args(argv)
    seeds = ([spawn_seed(a.validate_seed, 0, i) for i in range(a.trials)]
             if a.validate_seed is not None else list(range(a.first, a.first + a.trials)))
    with tempfile.TemporaryDirectory() as d:
        proto = load_protocol(str(reduced_protocol("jjf1535-2015", Path(d) / "reduced.toml")))
    base = study_bench(get("jjf1535-2015"))
    items = set(a.items.split(","))
    t0 = time.process_time()
    recs = [trial(base, proto, s, a.programme == "full", items) for s in seeds]
    print(f"JJF 1535 B_r/B_g targeted study: {a.trials} trials, programme {a.programme}, "
          + (f"validate seed {a.validate_seed}" if a.validate_seed is not None
             else f"seeds {a.first}–{a.first + a.trials - 1}")
          + f", {time.process_time() - t0:.0f} s CPU")
    report(recs)


if __name__ == "__main__":
    main()
