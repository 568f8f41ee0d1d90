"""Memory and time of the provenance check (gonio.formats.provenance.file_provenance: the
metadata, then the virtual bench's watermark, gonio.formats.watermark.detect) on a large,
real-looking CSV stream that carries no mark: the check runs on every laboratory file before
its calibration, so its cost must not grow with the file.

    python benchmarks/watermark_memory.py [--rows 4000000] [--seed 1] [--keep] [--file F]

Writes ``real_stream.csv`` (``# serial: REAL-001``, ``time_s,gyro_counts,table_deg`` at
1 kHz, counts of a counter at 76434.87 counts/° with white noise; --rows 4000000 is about
100 MB) into a temporary folder, then runs ``file_provenance`` on it in a fresh Python
process and prints that process's maximum resident set size (``ru_maxrss``), the same for a
process that only imports the modules (the baseline), and the wall time. Run it with
``PYTHONPATH`` naming the tree to measure (the figures of docs/formats.md#watermark were
printed this way for the code before and after the lazy read).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

CHILD = r"""
import resource, sys, time
import gonio
from gonio.formats.provenance import file_provenance
import gonio.formats.watermark, scipy.stats
t = time.perf_counter()
out = None if sys.argv[1] == "-" else file_provenance(sys.argv[1])
dt = time.perf_counter() - t
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, f"{dt:.3f}", gonio.__file__,
      None if out is None else (out["virtual"], out.get("watermark")))
"""


def write_stream(path: Path, rows: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    k = 76434.87
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("# serial: REAL-001\n# counter_bits: 32\n# counter_signed: true\n"
                 "# sample_rate_hz: 1000\ntime_s,gyro_counts,table_deg\n")
        step = 500_000
        for a in range(0, rows, step):
            i = np.arange(a, min(rows, a + step))
            t = i / 1000.0
            ang = (t * 0.5) % 360.0
            counts = np.rint(k * (t * 0.5) + rng.normal(0.0, 2.0, i.size)).astype(np.int64)
            fh.write("".join(f"{x:.3f},{c},{g:.6f}\n" for x, c, g in zip(t, counts, ang)))


def write_apart(path: Path, rows: int, seed: int) -> None:
    """:func:`write_stream` in a process of its own, so that this one stays small: a child
    starts with its parent's resident size as its maximum (Linux keeps ``ru_maxrss`` across
    ``fork`` and ``exec``), which would hide the measured process's own peak."""
    subprocess.run([sys.executable, str(Path(__file__).resolve()), "--write", str(path),
                    "--rows", str(rows), "--seed", str(seed)], check=True)


def measure(path, child: str = CHILD) -> tuple[int, float, object]:
    """(max RSS in kB, seconds, what it returned) of ``child`` run on ``path`` ("-": the
    imports only) in a fresh process; the child prints them and gonio's place."""
    # run outside the repository: ``python -c`` puts the working folder first on sys.path
    arg = "-" if str(path) == "-" else str(Path(path).resolve())
    r = subprocess.run([sys.executable, "-c", child, arg],
                       capture_output=True, text=True, check=True, env=os.environ,
                       cwd=tempfile.gettempdir())
    rss, dt, where, out = r.stdout.strip().split(" ", 3)
    print(f"  (gonio from {Path(where).parent})")
    return int(rss), float(dt), out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=4_000_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--keep", action="store_true", help="keep the temporary folder")
    ap.add_argument("--file", type=Path, help="measure this file (one --keep left) instead")
    ap.add_argument("--write", type=Path, help=argparse.SUPPRESS)   # write_apart's child
    a = ap.parse_args(argv)
    if a.write:
        write_stream(a.write, a.rows, a.seed)
        return
    if a.file:
        d, p = None, a.file
        print(f"measuring {p} ({p.stat().st_size / 1e6:.1f} MB)")
    else:
        d = Path(tempfile.mkdtemp(prefix="wm-mem-"))
        p = d / "real_stream.csv"
        t0 = time.perf_counter()
        write_apart(p, a.rows, a.seed)
        print(f"wrote {p} ({p.stat().st_size / 1e6:.1f} MB, {a.rows} rows, seed {a.seed}) "
              f"in {time.perf_counter() - t0:.1f} s")
    base, _, _ = measure("-")
    rss, dt, out = measure(p)
    print(f"imports only: max RSS {base / 1024:.0f} MB")
    print(f"file_provenance: max RSS {rss / 1024:.0f} MB (+{(rss - base) / 1024:.0f} MB over "
          f"the imports), {dt:.2f} s; virtual, watermark = {out}")
    if a.keep or d is None:
        print(f"kept {p}")
    else:
        p.unlink()
        d.rmdir()


if __name__ == "__main__":
    main()
