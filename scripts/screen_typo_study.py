"""The optical draft's screening on clean sessions and on sessions with one typo planted.

Sessions of the built-in programme with every item (``gonio validate --all-items``'
protocol, at the study's 100 Hz), on the study's benches and cases, with the validation's
trial seeds (``study.trial_seed(seed, case, i)``). For each session:

* **clean**: the whole screening (``screen.screen``); every reading set aside or refused is
  a false finding (the bench wrote no typo);
* **sweep** (the first ``--sweep-trials`` trials of each case): for each of 7.1, 7.3, 7.6 and
  7.7 and each size (0.3″, 0.5″, 0.75″, 1″, 2″, 5″) one reading drawn at random is moved by the size
  (sign drawn; a whole number of counts for ``gyro_counts``, the size itself for
  ``gyro_deg``) and the indicated-angle rule is run on that test's readings and 7.4's
  reference (K_ref of the clean file; the condition rule's false-alarm probability shared
  by the whole session's groups, as in the full screening): caught = the planted line is found; "other" = a
  reading of the same test found that the clean file did not.

    python scripts/screen_typo_study.py --seed 20261202 --trials 25 --sweep-trials 10 \\
        [--benches rlg,fog] [--cases default,typeb,worst,drift] [--programme 2x3] [--sizes 1,2,5]
        [--cache DIR]

``--programme SxP`` runs a small programme instead of the built-in one: 7.1, 7.4, 7.6 and
7.7 each read in S series at P positions (3: 120°, 240°, 360°; 6: every 60°; 12: the
built-in 30°), 7.3 as built in (:func:`small_protocol`). ``--cache DIR`` keeps each
simulated session (``DIR/programme_bench_case_i.pkl``) and reads it back on a second run.
Prints the counts, the clean sessions with a reading set aside or refused and their
Clopper–Pearson 95 % interval; docs/draft-readings.md ("Screening") quotes them.
"""

from __future__ import annotations

import argparse
import collections
import pickle
import time
import zlib
from pathlib import Path

import numpy as np

from scipy.stats import beta

from gonio.formats.toml import read_toml
from gonio.resources import resolve
from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.specs.ogam_draft.readings import Readings
from gonio.specs.ogam_draft.screen import (_indicated_rule, line_rule_groups,
                                           reference_scale_factor, screen)
from gonio.specs.ogam_draft.study import (case_bench, study_bench, study_protocol,
                                          trial_bench, trial_seed)
from gonio.units import ARCSEC_PER_DEG

SIZES = (0.3, 0.5, 0.75, 1.0, 2.0, 5.0)
TESTS = ("scale_factor", "zero_stability", "rate_consistency", "pointing_consistency")


def small_protocol(programme: str):
    """The built-in protocol with every item, its 7.1, 7.4, 7.6 and 7.7 read in S series at
    P equally spaced positions (``programme`` = "SxP", P dividing 12; 7.6 and 7.7 use 7.4's
    rounds); "default" is the built-in programme."""
    if programme == "default":
        return study_protocol("ogam-draft", all_items=True)
    series, positions = (int(x) for x in programme.split("x"))
    raw = read_toml(resolve("ogam-draft", "protocol"))
    for key in ("scale_factor", "angle_deviation"):
        rounds = raw[key]["rounds"]
        step = 360.0 / positions
        raw[key]["rounds"] = [r for r in rounds
                              if abs(r["stop_deg"] / step - round(r["stop_deg"] / step)) < 1e-9]
        if len(raw[key]["rounds"]) != positions:
            raise SystemExit(f"{key}: {positions} positions are not among the built-in rounds")
    for key in ("scale_factor", "angle_deviation", "rate_consistency", "pointing_consistency"):
        raw[key]["series"] = series
    raw.setdefault("annex_a", {}).setdefault("coverage_factor", 2.0)
    return study_protocol(parse_protocol(raw, resolve("ogam-draft", "protocol")), True)


def clopper_pearson(k: int, n: int) -> tuple[float, float]:
    """The two-sided 95 % Clopper–Pearson interval of a proportion k/n."""
    lo = float(beta.ppf(0.025, k, n - k + 1)) if k else 0.0
    hi = float(beta.ppf(0.975, k + 1, n - k)) if k < n else 1.0
    return lo, hi


def session(protocol, bench_name: str, case: str, seed: int, i: int, cache, tag="default"):
    f = Path(cache) / f"{tag}_{bench_name}_{case}_{i}.pkl" if cache else None
    if f is not None and f.exists():
        return pickle.loads(f.read_bytes())
    b0 = case_bench(case, study_bench(load_bench(bench_name), 100.0), protocol)
    s = trial_seed(seed, case, i)
    res = run_session(protocol, trial_bench(case, b0, protocol, s), seed=s)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    out = (df, dict(res.metadata))
    if f is not None:
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_bytes(pickle.dumps(out))
    return out


def sweep(df, md, protocol, name: str, caught, planted, other, sizes=SIZES) -> None:
    rng = np.random.default_rng([20261201, zlib.crc32(name.encode())])
    k = float(md["nominal_scale_factor_counts_per_deg"])
    k_ref = reference_scale_factor(df, md)
    bench = name.split("_")[0]
    groups = line_rule_groups(df)        # the whole session's, which share its alpha
    for test in TESTS:
        rows = np.flatnonzero((df["test"] == test).to_numpy())
        sub0 = df[df["test"].isin([test, "angle_deviation"])]
        before = {x.line for x in _indicated_rule(sub0, protocol, None, k_ref, set(), groups)
                  if x.test == test}
        for size in sizes:
            i, sgn = int(rng.choice(rows)), int(rng.choice([-1, 1]))
            d2 = df.copy()
            if np.isfinite(d2.at[i, "gyro_deg"]):
                d2.at[i, "gyro_deg"] += sgn * size / ARCSEC_PER_DEG
            else:
                d2.at[i, "gyro_counts"] += sgn * round(size / ARCSEC_PER_DEG * k)
            sub = d2[d2["test"].isin([test, "angle_deviation"])]
            lines = {x.line for x in _indicated_rule(sub, protocol, None, k_ref, set(), groups)
                     if x.test == test}
            key = (bench, test, size)
            planted[key] += 1
            caught[key] += int(df.at[i, "line"]) in lines
            other[key] += bool(lines - {int(df.at[i, "line"])} - before)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=20261202)
    ap.add_argument("--trials", type=int, default=25)
    ap.add_argument("--sweep-trials", type=int, default=10)
    ap.add_argument("--benches", default="rlg,fog")
    ap.add_argument("--cases", default="default,typeb,worst,drift")
    ap.add_argument("--programme", default="default")
    ap.add_argument("--sizes", default=",".join(f"{x:g}" for x in SIZES),
                    help="typo sizes of the sweep, arcsec")
    ap.add_argument("--cache", default=None)
    a = ap.parse_args(argv)
    protocol = small_protocol(a.programme)
    sizes = tuple(float(x) for x in a.sizes.split(","))
    n = collections.Counter()
    false = collections.Counter()
    hit = collections.Counter()
    named = []
    caught, planted, other = (collections.Counter() for _ in range(3))
    t0 = time.time()
    for bench in a.benches.split(","):
        for case in a.cases.split(","):
            for i in range(a.trials):
                df, md = session(protocol, bench, case, a.seed, i, a.cache, a.programme)
                n[bench] += 1
                fd = [x for x in screen(Readings(df, md, None), protocol)
                      if x.action != "flagged"]
                false[bench] += len(fd)
                hit[bench] += bool(fd)
                named += [f"  {bench} {case} trial {i}: line {x.line}: {x.message}" for x in fd]
                if i < a.sweep_trials:
                    sweep(df, md, protocol, f"{bench}_{case}_{i}", caught, planted, other,
                          sizes)
    print(f"programme {a.programme}, seed {a.seed}, cases {a.cases}, trials 0–{a.trials - 1} "
          f"(sweep: 0–{a.sweep_trials - 1}), {time.time() - t0:.0f} s")
    for bench in n:
        lo, hi = clopper_pearson(hit[bench], n[bench])
        print(f"clean {bench}: {n[bench]} sessions, {hit[bench]} with a reading set aside or "
              f"refused (95 % CP [{lo:.4f}, {hi:.4f}]), {false[bench]} readings")
    print("\n".join(named))
    for bench in n:
        for test in TESTS:
            cells = []
            for s in sizes:
                k = (bench, test, s)
                cells.append(f"{s:g}″ {caught[k]}/{planted[k]}"
                             + (f" (+{other[k]} other)" if other[k] else ""))
            print(f"{bench} {test}: " + ", ".join(cells))


if __name__ == "__main__":
    main()
