"""Memory and time of the readings' content digest (gonio.formats.content.content_sha256,
which the records compute for every readings file they store and compare) on a large CSV
stream: its memory must not grow with the file.

    python benchmarks/content_digest_memory.py [--rows 1000000] [--seed 1] [--file F]

Writes the real-looking stream of benchmarks/watermark_memory.py (``time_s,gyro_counts,
table_deg`` at 1 kHz; --rows 1000000 is about 30 MB) into a temporary folder, then runs
``content_sha256`` on it in a fresh Python process and prints that process's maximum
resident set size (``ru_maxrss``), the same for a process that only imports the module (the
baseline), and the wall time. Run it with ``PYTHONPATH`` naming the tree to measure (a
checkout of another commit, for the figures before a change).
"""

from __future__ import annotations

import argparse
import importlib.util
import tempfile
import time
from pathlib import Path

CHILD = r"""
import resource, sys, time
import gonio
from gonio.formats.content import content_sha256
t = time.perf_counter()
out = None if sys.argv[1] == "-" else content_sha256(sys.argv[1])
dt = time.perf_counter() - t
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, f"{dt:.3f}", gonio.__file__, out)
"""


def _watermark_benchmark():
    """benchmarks/watermark_memory.py (its ``write_apart``, the same file for the same seed,
    and its ``measure``)."""
    spec = importlib.util.spec_from_file_location(
        "watermark_memory", Path(__file__).resolve().parent / "watermark_memory.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--file", type=Path, help="measure this file instead")
    a = ap.parse_args(argv)
    bench = _watermark_benchmark()
    if a.file:
        d, p = None, a.file
        print(f"measuring {p} ({p.stat().st_size / 1e6:.1f} MB)")
    else:
        d = Path(tempfile.mkdtemp(prefix="content-mem-"))
        p = d / "real_stream.csv"
        t0 = time.perf_counter()
        bench.write_apart(p, a.rows, a.seed)
        print(f"wrote {p} ({p.stat().st_size / 1e6:.1f} MB, {a.rows} rows, seed {a.seed}) "
              f"in {time.perf_counter() - t0:.1f} s")
    base, _, _ = bench.measure("-", CHILD)
    rss, dt, out = bench.measure(p, CHILD)
    print(f"imports only: max RSS {base / 1024:.0f} MB")
    print(f"content_sha256: max RSS {rss / 1024:.0f} MB (+{(rss - base) / 1024:.0f} MB over "
          f"the imports), {dt:.2f} s; digest {out[:16]}…")
    if d is not None:
        p.unlink()
        d.rmdir()


if __name__ == "__main__":
    main()
