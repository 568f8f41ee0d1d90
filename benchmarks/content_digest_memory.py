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
import os
import subprocess
import sys
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


def _write_stream():
    """benchmarks/watermark_memory.py's ``write_stream`` (the same file, the same seed)."""
    spec = importlib.util.spec_from_file_location(
        "watermark_memory", Path(__file__).resolve().parent / "watermark_memory.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.write_stream


def measure(path) -> tuple[int, float, str]:
    # run outside the repository: ``python -c`` puts the working folder first on sys.path
    arg = "-" if str(path) == "-" else str(Path(path).resolve())
    r = subprocess.run([sys.executable, "-c", CHILD, arg], capture_output=True, text=True,
                       check=True, env=os.environ, cwd=tempfile.gettempdir())
    rss, dt, where, out = r.stdout.strip().split(" ", 3)
    print(f"  (gonio from {Path(where).parent})")
    return int(rss), float(dt), out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--file", type=Path, help="measure this file instead")
    a = ap.parse_args(argv)
    if a.file:
        d, p = None, a.file
        print(f"measuring {p} ({p.stat().st_size / 1e6:.1f} MB)")
    else:
        d = Path(tempfile.mkdtemp(prefix="content-mem-"))
        p = d / "real_stream.csv"
        t0 = time.perf_counter()
        _write_stream()(p, a.rows, a.seed)
        print(f"wrote {p} ({p.stat().st_size / 1e6:.1f} MB, {a.rows} rows, seed {a.seed}) "
              f"in {time.perf_counter() - t0:.1f} s")
    base, _, _ = measure("-")
    rss, dt, out = measure(p)
    print(f"imports only: max RSS {base / 1024:.0f} MB")
    print(f"content_sha256: max RSS {rss / 1024:.0f} MB (+{(rss - base) / 1024:.0f} MB over "
          f"the imports), {dt:.2f} s; digest {out[:16]}…")
    if d is not None:
        p.unlink()
        d.rmdir()


if __name__ == "__main__":
    main()
