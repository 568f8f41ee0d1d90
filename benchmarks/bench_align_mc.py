"""Time and peak memory of `gonio align --monte-carlo N` (issue 26).

The readings are `gonio simulate --spec triad-alignment --seed 1` (made in a temporary
folder unless ``--readings`` names a file). Each run is a fresh `python -m gonio align
READINGS --json --monte-carlo N` process, timed with its own peak resident set size
and CPU time (``os.wait4``: the CPU time means more than the wall time on a shared machine);
the process start-up (imports)
is in the time, so the start-up alone is printed first (``--monte-carlo 0``). Beside every
figure the load average (1, 5, 15 min) right after the run: the machine may be shared. ``--repo
DIR`` runs another checkout's gonio with the same interpreter (the "before" figures, e.g.
a ``git archive`` of the commit before the change).

The default seed (0) and the JSON's u_MC(M_xx) and u_MC(b_x) are printed under each run:
equal figures before and after a change show the same draws and trials.

Run: ``python benchmarks/bench_align_mc.py [--trials 10000 100000 10000000] [--repo DIR ...]``
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_noise_memory import ROOT, run_measured  # noqa: E402


def run_timed(argv: list[str], repo: Path, out: Path) -> tuple[float, float, float, int]:
    """(wall s, CPU s (user + system), peak RSS MB, exit status) of ``python -m gonio ARGV``
    with ``repo``'s gonio, its standard output written to ``out``."""
    t0 = time.perf_counter()
    with open(out, "wb") as fh:
        p = subprocess.Popen([sys.executable, "-m", "gonio", *argv], cwd=repo,
                             env={**os.environ, "PYTHONPATH": str(repo)},
                             stdout=fh, stderr=subprocess.PIPE)
        _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    rc = os.waitstatus_to_exitcode(status)
    if rc:
        print(f"   exit {rc}: {p.stderr.read().decode(errors='replace').strip()[-300:]}")
    return wall, ru.ru_utime + ru.ru_stime, ru.ru_maxrss / 1024.0, rc


def mc_figures(out: Path) -> str:
    """u_MC of M_xx and of the bias b_x as printed by ``align --json`` (the same seed must give
    the same figures before and after a change)."""
    try:
        d = json.loads(out.read_text(encoding="utf-8"))
        return (f"u_MC(M_xx) {d['u_monte_carlo_system_matrix'][0][0]:.12g}, "
                f"u_MC(b_x) {d['u_monte_carlo_bias_output'][0]:.12g}")
    except (ValueError, KeyError, TypeError, IndexError):
        return "no Monte Carlo figures"


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
        print(f"machine: {platform.node()}, {os.cpu_count()} CPUs, {platform.processor() or platform.machine()}")
        for repo in repos:
            print(f"gonio of {repo}:")
            for n in [0, *args.trials]:
                wall, cpu, rss, rc = run_timed(["align", str(readings), "--json",
                                                "--monte-carlo", str(n)], repo,
                                               Path(tmp) / "align.json")
                label = "start-up + fit (no Monte Carlo)" if n == 0 else f"{n:,} trials"
                load = " ".join(f"{v:.2f}" for v in os.getloadavg())
                print(f"  {label:34s} {wall:8.1f} s ({cpu:6.1f} s CPU)   peak RSS {rss:6.0f} MB"
                      f"   load {load}"
                      + ("" if rc == 0 else f"   (exit {rc})"), flush=True)
                if n:
                    print(f"  {'':34s} {mc_figures(Path(tmp) / 'align.json')}", flush=True)


if __name__ == "__main__":
    main()
