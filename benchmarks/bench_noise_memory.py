"""Peak memory and CPU time of `gonio noise` on a full draft stream.

The stream is `gonio simulate --protocol ogam-draft --stream` (≈ 6.8 h at 1 kHz, 24.5 M
samples; its longest static window ≈ 4.3 M samples), simulated into a temporary folder
unless ``--stream`` names one. Each run is a fresh `python -m gonio noise` process; its
peak resident set size and CPU time (user + system) come from ``os.wait4`` (that child's
own rusage); the load average is printed beside them (the machine may be shared: CPU time
is the figure the load hides least). Cases: the defaults (the fit's covariance), and the
parametric bootstrap of 20 records on request (its cost: the difference). ``--repo DIR``
runs another checkout's gonio (e.g. the main branch before the change) with the same
interpreter: the "before" figures.

Run: ``python benchmarks/bench_noise_memory.py [--stream S] [--repo DIR ...]``
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run_measured(argv: list[str], repo: Path) -> tuple[float, float, int, float]:
    """(wall s, peak RSS MB, exit status, CPU s) of ``python -m gonio ARGV`` with ``repo``'s
    gonio."""
    env = {**os.environ, "PYTHONPATH": str(repo)}
    t0 = time.perf_counter()
    # cwd = the checkout: `python -m` puts the working directory first on sys.path
    p = subprocess.Popen([sys.executable, "-m", "gonio", *argv], env=env, cwd=repo,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    err = p.stderr.read().decode(errors="replace").strip()
    if p.returncode:
        print(f"   exit {p.returncode}: {err[-300:]}")
    cpu = ru.ru_utime + ru.ru_stime
    return wall, ru.ru_maxrss / 1024.0, p.returncode, cpu  # ru_maxrss in KiB on Linux


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stream", type=Path, default=None)
    ap.add_argument("--repo", type=Path, action="append", default=None,
                    help="checkout(s) whose gonio to run (default: this one)")
    args = ap.parse_args()
    repos = [r.resolve() for r in (args.repo or [ROOT])]
    with tempfile.TemporaryDirectory(prefix="bench-noise-mem-") as tmp:
        stream = None if args.stream is None else args.stream.resolve()
        if stream is None:
            out = Path(tmp) / "full"
            print("simulating the full draft stream (a few minutes) ...", flush=True)
            wall, rss, rc, _ = run_measured(["simulate", "--protocol", "ogam-draft",
                                             "--stream", "--out", str(out)], ROOT)
            print(f"  simulate: {wall:.1f} s, peak {rss:.0f} MB")
            stream = out / "stream.parquet"
        print(f"stream: {stream} ({stream.stat().st_size / 1e6:.1f} MB on disk)")
        cases = [["noise", str(stream)], ["noise", str(stream), "--bootstrap", "0"],
                 ["noise", str(stream), "--bootstrap", "20"]]
        print(f"{os.cpu_count()} CPUs, Python {sys.version.split()[0]}")
        for repo in repos:
            print(f"gonio of {repo}:")
            cpus = {}
            for argv in cases:
                load = os.getloadavg()[0]
                wall, rss, rc, cpu = run_measured(argv, repo)
                cpus[" ".join(argv[2:])] = cpu
                print(f"  {' '.join(argv[2:]) or '(defaults)':20s} CPU {cpu:6.1f} s   "
                      f"wall {wall:6.1f} s   peak RSS {rss:6.0f} MB   load {load:.1f}"
                      + ("" if rc == 0 else f"   (exit {rc})"))
            print(f"  the bootstrap of 20 costs {cpus['--bootstrap 20'] - cpus['--bootstrap 0']:.1f}"
                  " s of CPU beyond the analysis")


if __name__ == "__main__":
    main()
