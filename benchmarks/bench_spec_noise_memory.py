"""Time and peak memory of the specifications' own noise items on a long static record
(issue 26): JJF 1535 7.2.13 (ARW from the overlapping Allan fit, with the printed eq (22)–(24)
statistic) and IEC 62047-20 5.4.5.1 b), c), 5.4.5.2, 5.4.5.3.

A static record of ``--samples`` samples (white rate noise, 10 Hz) is built in a fresh
process as the readings frame the items read; each item's wall and CPU time are measured
(the CPU time means more than the wall time on a shared machine), then, in a second run of
the items (tracemalloc slows every allocation), its own peak allocation beyond the record
with ``tracemalloc`` (numpy reports its buffers to it); the process's peak RSS is printed.
Each checkout runs the streamed path (the one taken on such a record) and the whole-array
path (``STREAM_MIN_SAMPLES`` raised: what the streaming costs in CPU), each in its own
process, with the load average beside. ``--repo DIR`` runs another checkout's gonio with
the same interpreter (the "before" figures, e.g. a ``git archive`` of the commit before
the change).

Run: ``python benchmarks/bench_spec_noise_memory.py [--samples 4300000] [--repo DIR ...]
[--paths streamed array]``
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import sys, time, tracemalloc, resource
import numpy as np, pandas as pd
N = int(sys.argv[1])
if sys.argv[2] == "array":           # the whole-array path: nothing streamed
    from gonio.analysis.noise import stream
    stream.STREAM_MIN_SAMPLES = 1 << 62
dt = 0.1
rng = np.random.default_rng(0)
y = 2.5 + 0.006 * 0.05 * rng.standard_normal(N) / np.sqrt(dt) / 3600
df = pd.DataFrame({"test": pd.Categorical(["static"] * N), "run": np.zeros(N, np.int64),
                   "step": np.zeros(N, np.int64), "time_s": np.arange(N) * dt, "output": y})
del y
from gonio.specs.jjf1535 import items as J
from gonio.specs.jjf1535.protocol import load_protocol as LJ
from gonio.specs.iec62047_20 import items as I
from gonio.specs.iec62047_20.protocol import load_protocol as LI
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(f"  record of {N:,} samples ({N * 8 / 1e6:.0f} MB per column); RSS with it {base:.0f} MB")
def contexts():
    cj = J.Context(df=df, output_unit="V", null_output=2.5, latitude_deg=45.0,
                   protocol=LJ("jjf1535-2015").sections, room_temperature_c=20.0, K=0.006,
                   u_K_rel=1e-4)
    ci = I.Context(df=df, output_unit="V", null_output=2.5, latitude_deg=45.0,
                   protocol=LI("iec62047-20").sections, a_typ=0.006, t_base_c=25.0, v_base=5.0)
    ci.a_base = 0.006
    return cj, ci
ITEMS = [("JJF 7.2.13 angle random walk", lambda cj, ci: J.angle_random_walk(cj)),
         ("IEC 5.4.5.2 ARW", lambda cj, ci: I.arw(ci)),
         ("IEC 5.4.5.3 bias instability", lambda cj, ci: I.bias_instability(ci)),
         ("IEC 5.4.5.1 b) in-band noise", lambda cj, ci: I.inband_noise(ci)),
         ("IEC 5.4.5.1 c) broadband noise", lambda cj, ci: I.broadband_noise(ci))]
# the times without tracemalloc (it slows every allocation), then the same sequence again
# (fresh contexts: the same caching between items) for the peaks
times, ctx = [], contexts()
for name, fn in ITEMS:
    t0, c0 = time.perf_counter(), time.process_time()
    fn(*ctx)
    times.append((time.perf_counter() - t0, time.process_time() - c0))
ctx = contexts()
for (name, fn), (wall, cpu) in zip(ITEMS, times):
    tracemalloc.start()
    it = fn(*ctx)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    print(f"  {name:36s} {wall:7.2f} s ({cpu:6.2f} s CPU)   peak beyond the record "
          f"{peak / 1e6:6.0f} MB   value {float(it.value):.13g}", flush=True)
print(f"  peak RSS of the process {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=4_300_000)
    ap.add_argument("--repo", type=Path, action="append", default=None)
    ap.add_argument("--paths", nargs="+", choices=("streamed", "array"),
                    default=["streamed", "array"],
                    help="the streamed (bounded-memory) path, and the whole-array path "
                         "(the streaming threshold raised) to compare its CPU time with")
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores "
          f"({platform.node()}, {platform.machine()})")
    for repo in [r.resolve() for r in (args.repo or [ROOT])]:
        for mode in args.paths:
            print(f"gonio of {repo}, {mode} path "
                  f"(load {' '.join(f'{v:.2f}' for v in os.getloadavg())}):", flush=True)
            r = subprocess.run([sys.executable, "-c", CHILD, str(args.samples), mode],
                               cwd="/tmp", env={**os.environ, "PYTHONPATH": str(repo)},
                               text=True, stdout=sys.stdout, stderr=subprocess.PIPE)
            if r.returncode:
                print(f"  exit {r.returncode}: {r.stderr.strip()[-400:]}")


if __name__ == "__main__":
    main()
