"""Benchmark: what the recomputation on ``gonio db import`` adds, and that it is deterministic.

For each specification, ``gonio demo --spec KEY --seed SEED`` is written into a temporary
folder and imported into a new SQLite records store
(:func:`gonio.records.importer.import_output_folder`); the time of the import and of its
recomputation (:func:`gonio.records.importer.recomputed`, timed around the call) are printed
(wall seconds, this process), with the load average. The recomputation is then run a second
time into another folder and the two results.json (and summary.txt) are compared byte for
byte, and both with the demo's own: same seed, same bytes. Not part of the test run.

    python benchmarks/bench_import_recompute.py [--seed 0] [--spec KEY ...]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

SPECS = ("ogam-draft", "jjf1535-2015", "iec62047-20", "triad-alignment")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--spec", nargs="*", default=list(SPECS))
    args = ap.parse_args()
    from gonio.cli import main as gonio
    from gonio.records import importer
    from gonio.records.db import open_store

    timed: list[float] = []
    real = importer.recomputed

    def recomputed(*a, **kw):
        t = time.perf_counter()
        try:
            return real(*a, **kw)
        finally:
            timed.append(time.perf_counter() - t)

    importer.recomputed = recomputed
    print(f"seed {args.seed}, {os.cpu_count()} cores, load before "
          f"{os.getloadavg()[0]:.1f}", flush=True)
    for key in args.spec:
        with tempfile.TemporaryDirectory(prefix="bench-import-") as tmp:
            tmp = Path(tmp)
            demo = tmp / "demo"
            t = time.perf_counter()
            assert gonio(["demo", "--spec", key, "--seed", str(args.seed), "--out",
                          str(demo)]) == 0
            t_demo = time.perf_counter() - t
            store = open_store(None, tmp / "data")
            try:
                timed.clear()
                t = time.perf_counter()
                importer.import_output_folder(store, demo)
                t_import = time.perf_counter() - t
                t_recompute = timed[0]
                again = []
                for i in range(2):        # the recomputation twice: byte-identical outputs
                    work = tmp / f"again{i}"
                    work.mkdir()
                    out = real(store, key, "readings.csv", *_stored(store), None,
                               work, *_inputs_options(store, demo, key))
                    again.append({n: (out / n).read_bytes()
                                  for n in ("results.json", "summary.txt")})
            finally:
                store.close()
            same = again[0] == again[1]
            as_demo = all(again[0][n] == (demo / n).read_bytes()
                          for n in ("results.json", "summary.txt"))
            print(f"{key:16s} demo {t_demo:5.1f} s  import {t_import:5.1f} s, of which "
                  f"recomputation {t_recompute:5.1f} s  ({100 * t_recompute / t_import:.0f} %)"
                  f"  twice byte-identical: {same}  = the demo's files: {as_demo}  "
                  f"load {os.getloadavg()[0]:.1f}", flush=True)
    return 0


def _stored(store):
    """(readings sha, protocol name, protocol sha, lab, table sha, table name) of the one
    imported calibration."""
    from gonio.atomic import sha256_file
    from gonio.records import services
    from gonio.resources import resolve
    cal = services.calibration(store, 1)
    proto = cal.protocol or None
    if proto:         # a built-in protocol by its path, as the import gives it
        path = resolve(Path(proto).stem)
        proto = path if sha256_file(path) == cal.protocol_sha256 else proto
    return (cal.readings_sha256, proto, cal.protocol_sha256, None, None, "")


def _inputs_options(store, demo: Path, key: str):
    """(inputs [(name, sha)], options) the import stored and read for calibration 1."""
    from gonio.atomic import read_manifest
    from gonio.records import services
    from gonio.records.importer import recorded_options
    from gonio.specs import get
    with store.session() as s:
        from gonio.records.models import CalibrationFile
        rows = s.query(CalibrationFile).filter_by(calibration_id=1).all()
        inputs = [(f.name[len(services.INPUT_PREFIX):], f.sha256) for f in rows
                  if f.name.startswith(services.INPUT_PREFIX)]
    return inputs, recorded_options(read_manifest(demo) or {}, get(key),
                                    demo / "results.json")


if __name__ == "__main__":
    raise SystemExit(main())
