"""Time and peak memory of `gonio align --monte-carlo N` (issue 26).

The readings are `gonio simulate --spec triad-alignment --seed 1` (made in a temporary
folder unless ``--readings`` names a file). Each run is a fresh `python -m gonio align
READINGS --json --monte-carlo N` process, timed with its own peak resident set size
(:func:`bench_noise_memory.run_measured`, ``os.wait4``); the process start-up (imports)
is in the time, so the start-up alone is printed first (``--monte-carlo 0``). ``--repo
DIR`` runs another checkout's gonio with the same interpreter (the "before" figures, e.g.
a ``git archive`` of the commit before the change).

Run: ``python benchmarks/bench_align_mc.py [--trials 10000 100000 10000000] [--repo DIR ...]``
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_noise_memory import ROOT, run_measured  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--readings", type=Path, default=None)
    ap.add_argument("--trials", type=int, nargs="+", default=[10_000, 100_000, 10_000_000])
    ap.add_argument("--repo", type=Path, action="append", default=None,
                    help="checkout(s) whose gonio to run (default: this one)")
    args = ap.parse_args()
    repos = [r.resolve() for r in (args.repo or [ROOT])]
    with tempfile.TemporaryDirectory(prefix="bench-align-mc-") as tmp:
        readings = args.readings
        if readings is None:
            wall, rss, rc = run_measured(["simulate", "--spec", "triad-alignment", "--seed", "1",
                                          "--out", str(Path(tmp) / "T")], ROOT)
            readings = Path(tmp) / "T" / "readings.csv"
        readings = readings.resolve()
        print(f"readings: {readings}")
        for repo in repos:
            print(f"gonio of {repo}:")
            for n in [0, *args.trials]:
                wall, rss, rc = run_measured(["align", str(readings), "--json",
                                              "--monte-carlo", str(n)], repo)
                label = "start-up + fit (no Monte Carlo)" if n == 0 else f"{n:,} trials"
                print(f"  {label:34s} {wall:8.1f} s   peak RSS {rss:6.0f} MB"
                      + ("" if rc == 0 else f"   (exit {rc})"), flush=True)


if __name__ == "__main__":
    main()
