"""Streams at scale, before and after, in one run.

1. Read speed on a 10⁸-row stream (fixed-width CSV, 16-bit wrapped counter, table moving 90°
   every 30 s; written with numpy to /tmp): read + unwrap + find rests chunk by chunk with
     a. the code of the start commit (pandas' C reader), run from a git worktree of that
        commit in a subprocess: "CSV via pandas (before)";
     b. this tree, CSV through pyarrow (gonio.formats.streams.StreamFile);
     c. this tree, the same stream as Parquet (converted once; conversion time printed).
   Each reader runs ``--repeat`` times (3) in fresh processes, its libraries imported before
   the clock; the fastest run of each is compared (all runs are printed). CPU seconds are
   those of the timed part, all threads of the process (imports excluded). Rows per second
   and CPU seconds for each; targets: b ≥ 3× a, c ≥ 10× a. Then the floor: pyarrow alone
   reading the same files' three columns into numpy, nothing else.
2. Peak memory (max RSS of the process) of ``gonio calibrate STREAM`` on a full draft session
   at 1 kHz (2×10⁷ rows, written by ``gonio simulate --stream``, Parquet) and on a 5× longer
   session (≈10⁸ rows: 7.4/7.5 with 95 series instead of 10). Target < 400 MB for both.

Usage: python benchmarks/bench_stream.py [--rows 1e8] [--repeat 3] [--skip-calibrate] [--keep]
The machine's load is printed: figures on a shared machine are noisy.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
START_COMMIT = "477f910"       # main before issue 16 (the "before" of every comparison)
RATE_HZ = 1000
CHUNK = 2_000_000
K_BENCH = 1e6 / 278            # counts per degree of the synthetic stream


def _digits(v: np.ndarray, width: int) -> np.ndarray:
    """Non-negative int64 → (n, width) ASCII digits, zero padded (vectorised)."""
    out = np.empty((v.size, width), dtype=np.uint8)
    x = v.copy()
    for j in range(width - 1, -1, -1):
        out[:, j] = 48 + (x % 10)
        x //= 10
    return out


def write_bench_stream(path: Path, rows: int) -> int:
    """Fixed-width rows 'SSSSSS.mmm,-CCCCCC,AAAAAA.AAAAAA' (a space where the count is not
    negative; pyarrow's integer parser takes a leading space but not a '+', which sends a
    block down a slower text path); returns the last unwrapped count."""
    with open(path, "wb") as fh:
        fh.write(b"# counter_bits: 16\n# counter_signed: true\n"
                 + f"# nominal_scale_factor_counts_per_deg: {K_BENCH!r}\n".encode()
                 + b"time_s,gyro_counts,table_deg\n")
        for a in range(0, rows, CHUNK):
            k = np.arange(a, min(rows, a + CHUNK), dtype=np.int64)
            cyc = (k // (30 * RATE_HZ))
            ph = k % (30 * RATE_HZ)
            ang_u = cyc * 90_000_000 + np.clip((ph - 10 * RATE_HZ) * 4500, 0, 90_000_000)
            counts = (k * 7) // 3 + ang_u // 278
            wrapped = ((counts + 32768) % 65536) - 32768
            line = np.empty((k.size, 33), dtype=np.uint8)
            line[:, 0:6] = _digits(k // RATE_HZ, 6)
            line[:, 6] = ord(".")
            line[:, 7:10] = _digits(k % RATE_HZ, 3)
            line[:, 10] = ord(",")
            line[:, 11] = np.where(wrapped < 0, ord("-"), ord(" "))
            line[:, 12:18] = _digits(np.abs(wrapped), 6)
            line[:, 18] = ord(",")
            line[:, 19:25] = _digits(ang_u // 1_000_000, 6)
            line[:, 25] = ord(".")
            line[:, 26:32] = _digits(ang_u % 1_000_000, 6)
            line[:, 32] = ord("\n")
            fh.write(line.tobytes())
    return int(counts[-1])


#: The libraries each version reads with are imported before the clock starts (the start
#: commit imports pandas with its module; this tree imports pyarrow when a file is opened).
READ_SCRIPT = r"""
import resource, sys, time
from gonio.{reduce_mod} import RestFinder
from gonio.{streams_mod} import iter_stream
import pandas, pyarrow, pyarrow.csv, pyarrow.parquet
t0, c0 = time.perf_counter(), time.process_time()
f = RestFinder(rate_threshold_dps=0.01, window=1, despike=True, min_rest_s=1.0)
n = 0
last = None
for ch in iter_stream(sys.argv[1], {chunk}):
    f.feed(ch.time_s, ch.table_deg)
    n += ch.time_s.size
    last = int(ch.gyro_counts[-1])
rests = f.finish()
hwm = [l for l in open("/proc/self/status") if l.startswith("VmHWM")][0].split()[1]
print(n, len(rests), last, time.perf_counter() - t0, int(hwm) / 1024,
      time.process_time() - c0)
"""

#: The floor: pyarrow alone reading the same file's three columns into numpy, nothing else:
#: CSV by its streaming reader (one core) and by read_csv on blocks as gonio reads (all
#: cores), Parquet row group by row group.
FLOOR_SCRIPT = r"""
import resource, sys, time
import pyarrow as pa, pyarrow.csv as pcsv, pyarrow.parquet as pq
path = sys.argv[1]
cols = ["time_s", "gyro_counts", "table_deg"]
t0, c0 = time.perf_counter(), time.process_time()
n = 0
if path.endswith(".parquet"):
    pf = pq.ParquetFile(path)
    for g in range(pf.num_row_groups):
        tab = pf.read_row_group(g, columns=cols)
        arrays = [c.to_numpy() for c in tab.columns]
        n += tab.num_rows
else:
    types = {"time_s": pa.float64(), "gyro_counts": pa.int64(), "table_deg": pa.float64()}
    if sys.argv[2] == "stream":
        # pyarrow's streaming reader: one core, the fewest CPU seconds
        r = pcsv.open_csv(path, read_options=pcsv.ReadOptions(skip_rows=4, column_names=cols,
                                                             block_size=1 << 24),
                          convert_options=pcsv.ConvertOptions(column_types=types))
        for b in r:
            arrays = [c.to_numpy() for c in b.columns]
            n += b.num_rows
    else:
        # as gonio parses: read_csv (all cores, 4 MB parse blocks) on 8 MB pieces cut at
        # a line end
        ropts = pcsv.ReadOptions(column_names=cols, block_size=1 << 22)
        copts = pcsv.ConvertOptions(column_types=types)
        with open(path, "rb") as fh:
            for _ in range(4):
                fh.readline()
            carry = b""
            while True:
                buf = bytearray(len(carry) + (1 << 23))
                buf[:len(carry)] = carry
                got = fh.readinto(memoryview(buf)[len(carry):])
                del buf[len(carry) + got:]
                if not buf:
                    break
                cut = buf.rfind(b"\n") + 1 if got else len(buf)
                block, carry = memoryview(buf)[:cut], bytes(buf[cut:])
                tab = pcsv.read_csv(pa.BufferReader(block), read_options=ropts,
                                    convert_options=copts)
                arrays = [c.to_numpy() for c in tab.columns]
                n += tab.num_rows
                del block, tab
                if not got:
                    break
print(n, time.perf_counter() - t0, time.process_time() - c0)
"""


def floor_read(path: Path, how: str = "blocks") -> tuple:
    out = subprocess.run([sys.executable, "-c", FLOOR_SCRIPT, str(path), how], cwd="/tmp",
                         capture_output=True, text=True)
    if out.returncode:
        raise SystemExit(out.stderr)
    n, secs, cpu = out.stdout.split()
    return int(n), float(secs), float(cpu)


#: The peak resident memory of this process, MB: VmHWM, which starts afresh at exec
#: (ru_maxrss does not: it keeps the forking parent's resident size, here the benchmark's).
PEAK_RSS_MB = ('int([l for l in open("/proc/self/status") if l.startswith("VmHWM")][0]'
               '.split()[1]) / 1024')


def timed_read(pythonpath: Path, path: Path, old: bool) -> tuple:
    script = READ_SCRIPT.format(reduce_mod="reduce" if old else "reduce",
                                streams_mod="streams" if old else "formats.streams",
                                chunk=CHUNK if old else "None")
    env = dict(os.environ, PYTHONPATH=str(pythonpath))
    out = subprocess.run([sys.executable, "-c", script, str(path)], env=env, cwd="/tmp",
                         capture_output=True, text=True)
    if out.returncode:
        raise SystemExit(out.stderr)
    n, nr, last, secs, rss, cpu = out.stdout.split()
    return int(n), int(nr), int(last), float(secs), float(rss), float(cpu)


def start_worktree(tmp: Path) -> Path:
    wt = tmp / "before"
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(wt), START_COMMIT],
                   check=True, capture_output=True)
    return wt


def long_protocol(tmp: Path) -> Path:
    """The draft's protocol with 95 series of 7.4/7.5 (≈ 10⁸ samples at 1 kHz)."""
    text = (ROOT / "protocols" / "ogam-draft.toml").read_text(encoding="utf-8")
    text = text.replace('name = "ogam-draft"', 'name = "ogam-draft-long"', 1)
    text = text.replace("series = 10                             # 7.5: repeat 7.4 ten times",
                        "series = 95")
    p = tmp / "ogam-draft-long.toml"
    p.write_text(text, encoding="utf-8")
    return p


def calibrate_peak(tmp: Path, protocol: str, label: str) -> None:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = tmp / f"sim-{label}"
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "gonio", "simulate", "--protocol", protocol,
                        "--out", str(out), "--stream"], env=env, cwd=tmp,
                       capture_output=True, text=True)
    if r.returncode:
        raise SystemExit(r.stderr)
    t_sim = time.perf_counter() - t0
    stream = out / "stream.parquet"
    import pyarrow.parquet as pq
    rows = pq.ParquetFile(stream).metadata.num_rows
    code = ("import resource, sys, time\n"
            "from gonio.cli import main\n"
            "t0 = time.perf_counter()\n"
            "rc = main(['calibrate', sys.argv[1], '--protocol', sys.argv[2], '--out', sys.argv[3]])\n"
            f"print(rc, time.perf_counter() - t0, {PEAK_RSS_MB}, file=sys.stderr)\n")
    r = subprocess.run([sys.executable, "-c", code, str(stream), protocol, str(tmp / f"cal-{label}")],
                       env=env, cwd=tmp, capture_output=True, text=True)
    rc, secs, rss = r.stderr.strip().splitlines()[-1].split()
    if rc != "0":
        raise SystemExit(r.stderr + r.stdout)
    print(f"load {os.getloadavg()[0]:.1f}: gonio calibrate STREAM, {rows:.3g} rows ({stream.stat().st_size / 1e6:.0f} MB "
          f"Parquet; simulated in {t_sim:.0f} s): {float(secs):.0f} s, peak RSS "
          f"{float(rss):.0f} MB (target < 400 MB): {'OK' if float(rss) < 400 else 'OVER'}",
          flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=float, default=1e8)
    ap.add_argument("--skip-calibrate", action="store_true")
    ap.add_argument("--skip-read", action="store_true")
    ap.add_argument("--keep", action="store_true")
    ap.add_argument("--repeat", type=int, default=3,
                    help="runs of each reader; the fastest is kept (default 3)")
    a = ap.parse_args()
    rows = int(a.rows)
    sys.path.insert(0, str(ROOT))
    tmp = Path(tempfile.mkdtemp(prefix="gonio-bench-stream-", dir="/tmp"))
    print(f"load average at start: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores", flush=True)
    try:
        if not a.skip_read:
            need = rows * 33 * 1.6
            if shutil.disk_usage(tmp).free < need:
                print(f"disk space short: {need / 1e9:.1f} GB needed")
                return 1
            csv = tmp / "stream.csv"
            t0 = time.perf_counter()
            expect_last = write_bench_stream(csv, rows)
            print(f"{rows:,} rows, {csv.stat().st_size / 1e9:.2f} GB CSV written in "
                  f"{time.perf_counter() - t0:.0f} s", flush=True)
            wt = start_worktree(tmp)
            res = {}
            runs: dict[str, list[float]] = {}

            def best_of(name, pythonpath, path, old):
                # each reader a.repeat times, interleaved with nothing else; the fastest
                # run is kept for every reader alike (the machine's noise only adds time)
                out = [timed_read(pythonpath, path, old=old) for _ in range(a.repeat)]
                runs[name] = [r[3] for r in out]
                res[name] = min(out, key=lambda r: r[3])

            best_of("CSV via pandas (before, start commit)", wt, csv, True)
            best_of("CSV via pyarrow (this tree)", ROOT, csv, False)
            from gonio.formats.streams import StreamFile, StreamWriter
            pqp = tmp / "stream.parquet"
            t0 = time.perf_counter()
            sf = StreamFile(csv)
            with StreamWriter(pqp, sf.metadata, table=True) as w:
                for ch in sf.chunks():
                    w.write(ch.time_s, ch.gyro_counts, ch.table_deg)
            print(f"converted to Parquet ({pqp.stat().st_size / 1e9:.2f} GB) in "
                  f"{time.perf_counter() - t0:.0f} s", flush=True)
            best_of("Parquet (this tree)", ROOT, pqp, False)
            floors = {"CSV, streaming reader (1 core)": floor_read(csv, "stream"),
                      "CSV, blocks as gonio reads": floor_read(csv, "blocks"),
                      "Parquet": floor_read(pqp)}
            base = None
            for name, (n, nr, last, secs, rss, cpu) in res.items():
                base = base or secs
                ok = "OK" if last == expect_last and n == rows else "MISMATCH"
                print(f"{name:<40} {secs:7.1f} s  {n / secs / 1e6:6.2f} M rows/s  "
                      f"{base / secs:5.1f}x  CPU {cpu:5.1f} s  peak RSS {rss:5.0f} MB  "
                      f"rests {nr}  last count {ok}  (runs: "
                      f"{', '.join(f'{r:.2f}' for r in runs[name])} s)", flush=True)
            for name, (n, secs, cpu) in floors.items():
                print(f"{'floor: pyarrow alone, ' + name:<40} {secs:7.1f} s  "
                      f"{n / secs / 1e6:6.2f} M rows/s  {base / secs:5.1f}x  CPU {cpu:5.1f} s "
                      "(pyarrow reading the three columns, nothing else)", flush=True)
            print(f"load average after the reads: {os.getloadavg()[0]:.1f} on "
                  f"{os.cpu_count()} cores (wall figures above ~{os.cpu_count()} are "
                  "shared with other processes; CPU seconds are not)", flush=True)
            t_old = res["CSV via pandas (before, start commit)"][3]
            cores = os.cpu_count() or 1
            parse_cpu = min(floors["CSV, streaming reader (1 core)"][2],
                            floors["CSV, blocks as gonio reads"][2])
            print(f"CSV: pyarrow's parse alone costs at least {parse_cpu:.1f} CPU s (the fewer "
                  f"of its two ways), so on {cores} cores "
                  f"no reader can take less than {parse_cpu / cores:.1f} s; the 3x target "
                  f"allows {t_old / 3:.1f} s", flush=True)
            print(f"targets: CSV via pyarrow >= 3x before: "
                  f"{'OK' if t_old / res['CSV via pyarrow (this tree)'][3] >= 3 else 'MISSED'}; "
                  f"Parquet >= 10x before: "
                  f"{'OK' if t_old / res['Parquet (this tree)'][3] >= 10 else 'MISSED'}",
                  flush=True)
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(wt)],
                           capture_output=True)
            csv.unlink()
            pqp.unlink()
        if not a.skip_calibrate:
            code = ("from gonio.cli import build_parser; build_parser(); "
                    f"print({PEAK_RSS_MB})")
            r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                               env=dict(os.environ, PYTHONPATH=str(ROOT)), cwd=tmp)
            print(f"of which the command line's module imports alone: {float(r.stdout):.0f} MB "
                  "peak RSS", flush=True)
            calibrate_peak(tmp, "ogam-draft", "2e7")
            calibrate_peak(tmp, str(long_protocol(tmp)), "1e8")
    finally:
        if not a.keep:
            shutil.rmtree(tmp, ignore_errors=True)
        subprocess.run(["git", "-C", str(ROOT), "worktree", "prune"], capture_output=True)
    print(f"load average at end: {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
