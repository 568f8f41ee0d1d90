"""Stream reading at scale: write an N-row stream CSV (default 10⁸, chunked, to /tmp), then
read + unwrap + find rests chunk by chunk; print wall time and peak memory; delete the file.

Usage: python benchmarks/bench_stream.py [ROWS] [--keep]
Targets (issue 5): < 1.5 GB peak RSS and < 2 min for 10⁸ rows (read + unwrap + rests).
"""

from __future__ import annotations

import os
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from gonio.reduce import RestFinder
from gonio.formats.streams import iter_stream

RATE_HZ = 1000
CHUNK = 2_000_000


def _digits(v: np.ndarray, width: int) -> np.ndarray:
    """Non-negative int64 → (n, width) ASCII digits, zero padded (vectorised)."""
    out = np.empty((v.size, width), dtype=np.uint8)
    x = v.copy()
    for j in range(width - 1, -1, -1):
        out[:, j] = 48 + (x % 10)
        x //= 10
    return out


def write_bench_stream(path: Path, rows: int) -> None:
    """Fixed-width rows 'SSSSSS.mmm,±CCCCCC,AAAAAA.AAAAAA' (16-bit wrapped counter, table
    moving 90° every 20 s and resting 10 s), written chunk by chunk."""
    with open(path, "wb") as fh:
        fh.write(b"# counter_bits: 16\n# counter_signed: true\ntime_s,gyro_counts,table_deg\n")
        for a in range(0, rows, CHUNK):
            k = np.arange(a, min(rows, a + CHUNK), dtype=np.int64)
            cyc = (k // (30 * RATE_HZ))
            ph = k % (30 * RATE_HZ)
            ang_u = cyc * 90_000_000 + np.clip((ph - 10 * RATE_HZ) * 4500, 0, 90_000_000)
            counts = (k * 7) // 3 + ang_u // 278             # ~3600 counts/°, Earth-rate drift
            wrapped = ((counts + 32768) % 65536) - 32768
            n = k.size
            line = np.empty((n, 33), dtype=np.uint8)
            line[:, 0:6] = _digits(k // RATE_HZ, 6)
            line[:, 6] = ord(".")
            line[:, 7:10] = _digits(k % RATE_HZ, 3)
            line[:, 10] = ord(",")
            line[:, 11] = np.where(wrapped < 0, ord("-"), ord("+"))
            line[:, 12:18] = _digits(np.abs(wrapped), 6)
            line[:, 18] = ord(",")
            line[:, 19:25] = _digits(ang_u // 1_000_000, 6)
            line[:, 25] = ord(".")
            line[:, 26:32] = _digits(ang_u % 1_000_000, 6)
            line[:, 32] = ord("\n")
            fh.write(line.tobytes())


def main() -> None:
    rows = int(float(sys.argv[1])) if len(sys.argv) > 1 and not sys.argv[1].startswith("-") \
        else 100_000_000
    keep = "--keep" in sys.argv
    tmp = Path(tempfile.mkdtemp(prefix="gonio-bench-", dir="/tmp"))
    path = tmp / "stream.csv"
    need = rows * 33 * 1.1
    free = shutil.disk_usage(tmp).free
    if free < need:
        print(f"disk space short: {free / 1e9:.1f} GB free, {need / 1e9:.1f} GB needed")
        return
    try:
        t0 = time.perf_counter()
        write_bench_stream(path, rows)
        t_write = time.perf_counter() - t0
        size = path.stat().st_size
        rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        t0 = time.perf_counter()
        finder = RestFinder(rate_threshold_dps=0.01, window=1, despike=True, min_rest_s=1.0)
        n = 0
        last = None
        for ch in iter_stream(path, CHUNK):
            finder.feed(ch.time_s, ch.table_deg)
            n += ch.time_s.size
            last = int(ch.gyro_counts[-1])
        rests = finder.finish()
        t_read = time.perf_counter() - t0
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        expect_rests = -(-rows // (30 * RATE_HZ))
        k = rows - 1
        cyc, ph = k // (30 * RATE_HZ), k % (30 * RATE_HZ)
        ang = cyc * 90_000_000 + min(max((ph - 10 * RATE_HZ) * 4500, 0), 90_000_000)
        expect_last = (k * 7) // 3 + ang // 278
        print(f"rows: {n:,} ({size / 1e9:.2f} GB CSV), chunk {CHUNK:,} rows")
        print(f"write (fixed-width, numpy): {t_write:.1f} s")
        print(f"read + unwrap + find rests: {t_read:.1f} s "
              f"({n / t_read / 1e6:.2f} M rows/s)")
        print(f"peak RSS: {rss:.0f} MB (before reading: {rss0:.0f} MB)")
        print(f"rests found: {len(rests)} (expected {expect_rests}); "
              f"last unwrapped count {last} (expected {expect_last}, first sample 0): "
              f"{'OK' if last == expect_last else 'MISMATCH'}")
        if rows < 100_000_000:
            f = 100_000_000 / rows
            print(f"extrapolated to 10^8 rows: read {t_read * f:.0f} s")
    finally:
        if not keep:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
