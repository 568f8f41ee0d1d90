"""Benchmark: ``gonio calibrate`` on large readings files (issue 14: 10⁶ rows in seconds).

Builds readings files of 10⁵ and 10⁶ rows by hand (numpy, no simulation): the draft's
whole calibration repeated as many times as it takes — angle-deviation series of 12
rounds, zero-stability series of 15 readings, scale-factor rounds, rate- and
pointing-consistency rounds — each value the nominal one plus noise.

Runs ``gonio calibrate`` (built-in protocol) in a child process, as a user would, and
prints wall time, CPU time, the child's peak resident memory and the size of the
outputs. Not part of the test run. Target: 10⁶ rows under ~20 s and 1 GB on a 2-core
machine; results.json and the certificate of bounded size (tables/*.csv keep every row).

    python benchmarks/bench_large_readings.py [--rows 100000 1000000] [--keep DIR]
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

#: nominal scale factor of the hand-made instrument, counts per degree
K_NOMINAL = 76434.87
AD_STOPS_DEG = np.arange(1, 13) * 30.0          # the draft's 12 rounds of 7.4
SF_STOPS_DEG = np.arange(1, 7) * 60.0           # the draft's 6 rounds of 7.1
RC_RATES_DPS = (1.0, 10.0, 30.0, 100.0, 200.0, 300.0)
PC_ORIENTATIONS = ("north", "south", "east", "west")
#: rows of one "block": 10 angle-deviation series, one zero-stability series, one 7.1
#: series, the 7.6 rates and the 7.7 orientations (the draft's own calibration)
BLOCK = 10 * 12 + 15 + 6 + len(RC_RATES_DPS) * 12 + len(PC_ORIENTATIONS) * 6


def blocks_for(rows: int) -> int:
    """Blocks (whole calibrations) in a file of about ``rows`` rows."""
    return max(1, int(round(rows / BLOCK)))


def make_readings(path: Path, rows: int, seed: int = 0) -> int:
    """Write a readings file of about ``rows`` rows; returns the number of blocks."""
    rng = np.random.default_rng(seed)
    nb = blocks_for(rows)
    parts = []

    def emit(test, series, rnd, rate, orient, time_s, table, counts, gyro_deg):
        n = len(series)
        parts.append({"test": np.full(n, test, dtype=object), "series": series, "round": rnd,
                      "rate": rate, "orient": np.full(n, orient, dtype=object) if
                      isinstance(orient, str) else orient, "time": time_s, "table": table,
                      "counts": counts, "gyro_deg": gyro_deg})

    b = np.arange(nb)
    # 7.4: 10 series per block of 12 rounds, the gyro's reading in degrees
    s = (b[:, None] * 10 + np.arange(1, 11)[None, :]).ravel()
    ser = np.repeat(s, 12)
    rnd = np.tile(np.arange(1, 13), s.size)
    stop = AD_STOPS_DEG[rnd - 1]
    dev_deg = (2e-4 * np.sin(np.deg2rad(stop)) + rng.normal(0, 3e-5, stop.size))
    emit("angle_deviation", ser, rnd, np.full(ser.size, 60.0), "up",
         10.0 + 0.5 * rnd, stop, np.full(ser.size, np.nan), stop + dev_deg)
    # 7.3: one series of 15 readings 300 s apart per block, counts (a drifting zero)
    ser = np.repeat(b + 1, 15)
    rnd = np.tile(np.arange(1, 16), nb)
    emit("zero_stability", ser, rnd, np.full(ser.size, np.nan), "up", (rnd - 1) * 300.0,
         np.full(ser.size, np.nan), np.round(rng.normal(0, 8, ser.size)),
         np.full(ser.size, np.nan))
    # 7.1: one series of 6 rounds per block, pulse counts
    ser = np.repeat(b + 1, 6)
    rnd = np.tile(np.arange(1, 7), nb)
    stop = SF_STOPS_DEG[rnd - 1]
    emit("scale_factor", ser, rnd, np.full(ser.size, 60.0), "up", 5.0 + stop / 60.0, stop,
         np.round(K_NOMINAL * stop * (1 + 2e-6 * rng.normal(size=stop.size))),
         np.full(ser.size, np.nan))
    # 7.6: the 12 rounds at each rate; 7.7: 6 rounds in each orientation
    for rate in RC_RATES_DPS:
        ser = np.repeat(b + 1, 12)
        rnd = np.tile(np.arange(1, 13), nb)
        stop = AD_STOPS_DEG[rnd - 1]
        emit("rate_consistency", ser, rnd, np.full(ser.size, rate), "up",
             10.0 + stop / rate, stop,
             np.round(K_NOMINAL * (stop + rng.normal(0, 3e-5, stop.size))),
             np.full(ser.size, np.nan))
    for orient in PC_ORIENTATIONS:
        ser = np.repeat(b + 1, 6)
        rnd = np.tile(np.arange(1, 7), nb)
        stop = AD_STOPS_DEG[rnd - 1]
        emit("pointing_consistency", ser, rnd, np.full(ser.size, 60.0), orient,
             10.0 + stop / 60.0, stop,
             np.round(K_NOMINAL * (stop + rng.normal(0, 3e-5, stop.size))),
             np.full(ser.size, np.nan))

    def col(name):
        return np.concatenate([p[name] for p in parts])

    def fmt(values, how):
        out = np.empty(values.size, dtype=object)
        nan = np.isnan(values)
        out[nan] = ""
        out[~nan] = [how(v) for v in values[~nan].tolist()]
        return out

    cells = [col("test"), col("series").astype(str).astype(object),
             col("round").astype(str).astype(object), fmt(col("rate"), repr), col("orient"),
             fmt(col("time"), repr), fmt(col("table"), repr),
             fmt(col("counts"), lambda v: str(int(v))), fmt(col("gyro_deg"), repr)]
    head = ("# instrument: hand-made large readings file (benchmarks/bench_large_readings.py)\n"
            "# serial: BIG-0001\n"
            f"# nominal_scale_factor_counts_per_deg: {K_NOMINAL!r}\n"
            "# latitude_deg: 40.2\n"
            "test,series,round,rate_dps,orientation,time_s,table_deg,gyro_counts,gyro_deg\n")
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(head)
        fh.writelines(",".join(r) + "\n" for r in zip(*cells))
    return nb


def run_calibrate(readings: Path, out: Path) -> tuple[float, float, float]:
    """Wall time, CPU time (user + system) and peak RSS (MB) of one ``gonio calibrate``
    child process."""
    argv = [sys.executable, "-m", "gonio", "calibrate", str(readings), "--out", str(out),
            "--force"]
    t0 = time.perf_counter()
    p = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    err = p.stderr.read()
    p.stderr.close()
    _, status, ru = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise SystemExit(f"gonio calibrate {readings} failed: {err.decode()[-300:]}")
    return wall, ru.ru_utime + ru.ru_stime, ru.ru_maxrss / 1024.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rows", type=int, nargs="+", default=[100_000, 1_000_000])
    ap.add_argument("--keep", default=None, help="keep the files and outputs in this folder")
    args = ap.parse_args()
    base = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="gonio-bench-"))
    base.mkdir(parents=True, exist_ok=True)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores "
          "(wall time grows with the load; CPU time is what one free core would take)")
    for rows in args.rows:
        readings = base / f"readings-{rows}.csv"
        make_readings(readings, rows)
        n = sum(1 for _ in open(readings, encoding="utf-8")) - 5
        out = base / f"out-{rows}"
        wall, cpu, rss = run_calibrate(readings, out)
        sizes = {p.relative_to(out).as_posix(): p.stat().st_size
                 for p in sorted(out.rglob("*")) if p.is_file()}
        tables = sum(v for k, v in sizes.items() if k.startswith("tables/"))
        main_files = ", ".join(f"{k} {v / 1e3:.0f} kB" for k, v in sizes.items()
                               if not k.startswith("tables/") and k != "gonio-manifest.json")
        print(f"{n:>8d} rows ({readings.stat().st_size / 1e6:.0f} MB): wall {wall:5.1f} s, "
              f"CPU {cpu:5.1f} s, peak RSS {rss:4.0f} MB; {main_files}; "
              f"tables/*.csv {tables / 1e6:.1f} MB", flush=True)
    if not args.keep:
        import shutil
        shutil.rmtree(base, ignore_errors=True)


if __name__ == "__main__":
    main()
