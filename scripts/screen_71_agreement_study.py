"""7.1 without a repeated reference (7.4 in fewer than 5 series): clean sessions and planted typos.

Small programmes of the optical draft (7.1 and 7.4 at the same six stops, 60°…360°, 7.4 in S
series; 7.3, 7.6 and 7.7 as in ``small_protocol``), simulated on the built-in ``rlg`` and
``fog`` benches (``run_session``, seed = base seed + trial). For each session the whole
screening (``screen.screen``) runs on the clean readings and on copies with 1, 2 or 3 of the
six 7.1 readings moved by a typo of each size (positions drawn without replacement, signs
drawn; whole counts). Printed per bench, S, typo count and size: the sessions where a 7.1
reading was set aside or refused (the planted ones found), and for the clean readings the
sessions with any 7.1 finding (a false alarm) with their 95 % Clopper–Pearson interval.

    python scripts/screen_71_agreement_study.py --seed 20261206 --trials 40 [--series 2,3,4]
        [--benches rlg,fog] [--sizes 0.5,1,2]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.stats import beta

from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.specs.ogam_draft.readings import Readings
from gonio.specs.ogam_draft.screen import screen
from gonio.units import ARCSEC_PER_DEG

STOPS = [{"stop_deg": float(a)} for a in (60, 120, 180, 240, 300, 360)]


def small(series: int):
    """The small programme: 7.1 and 7.4 at the six 60° stops, 7.4 in ``series`` series."""
    raw = {"protocol": {"name": f"small-{series}x6"}, "session": {"static_s": 30.0},
           "scale_factor": {"rest_s": 15.0, "rounds": STOPS},
           "zero_stability": {"readings": 4, "interval_s": 20.0},
           "angle_deviation": {"series": series, "rest_s": 15.0, "rounds": STOPS},
           "rate_consistency": {"rates_dps": [30.0, 60.0], "rest_s": 15.0},
           "pointing_consistency": {"orientations": ["up", "north"], "rest_s": 15.0}}
    return parse_protocol(raw, None)


def clopper_pearson(k: int, n: int) -> tuple[float, float]:
    lo = float(beta.ppf(0.025, k, n - k + 1)) if k else 0.0
    hi = float(beta.ppf(0.975, k + 1, n - k)) if k < n else 1.0
    return lo, hi


def found_71(df, md, protocol) -> set:
    """The 7.1 lines set aside or refused, and 'refused' where the 7.1 readings are refused
    together."""
    out = set()
    for f in screen(Readings(df, md, None), protocol):
        if f.test == "scale_factor" and f.action != "flagged":
            out.add("refused" if f.code == "readings-disagree-with-reference" else f.line)
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=20261206)
    ap.add_argument("--trials", type=int, default=40)
    ap.add_argument("--series", default="2,3,4")
    ap.add_argument("--benches", default="rlg,fog")
    ap.add_argument("--sizes", default="0.5,1,2")
    a = ap.parse_args(argv)
    sizes = [float(x) for x in a.sizes.split(",")]
    t0 = time.time()
    for bench_name in a.benches.split(","):
        bench = load_bench(bench_name)
        for series in (int(x) for x in a.series.split(",")):
            protocol = small(series)
            false, caught = 0, {}
            for i in range(a.trials):
                res = run_session(protocol, bench, seed=a.seed + i)
                df = res.readings.copy()
                df["line"] = np.arange(2, len(df) + 2)
                md = dict(res.metadata)
                k = float(md["nominal_scale_factor_counts_per_deg"])
                false += bool(found_71(df, md, protocol))
                rows = np.flatnonzero((df["test"] == "scale_factor").to_numpy())
                rng = np.random.default_rng([a.seed, i, series])
                for n_typo in (1, 2, 3):
                    for size in sizes:
                        d2 = df.copy()
                        for r in rng.choice(rows, n_typo, replace=False):
                            d2.at[r, "gyro_counts"] += int(rng.choice([-1, 1])) * round(
                                size / ARCSEC_PER_DEG * k)
                        caught[(n_typo, size)] = caught.get((n_typo, size), 0) + bool(
                            found_71(d2, md, protocol))
            lo, hi = clopper_pearson(false, a.trials)
            print(f"{bench_name} 7.4 in {series} series: clean {false}/{a.trials} with a 7.1 "
                  f"finding (95 % CP [{lo:.3f}, {hi:.3f}]); typos found: " + "; ".join(
                      f"{n}×{s:g}″ {caught[(n, s)]}/{a.trials}" for n in (1, 2, 3) for s in sizes),
                  flush=True)
    print(f"seed {a.seed}, trials {a.trials}, {time.time() - t0:.0f} s")


if __name__ == "__main__":
    main()
