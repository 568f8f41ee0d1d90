"""Benchmark: how long the records take to issue a reviewed, approved calibration.

The issue renders the stored, sealed results.json with the final details
(:func:`gonio.records.worker.execute` on an approved calibration: seal checked, then
:func:`gonio.records.compute.render_folder`, then the certificate row); before, it ran the
whole pipeline on the stored readings again (:func:`gonio.records.compute.calibrate_folder`
with the final details), which is timed here on the same calibration as "before". Each
specification's readings come from its virtual bench (``gonio simulate``, its default
protocol, seed 3); the draft runs once through the real worker, is reviewed and approved,
and then both are timed (median of ``--repeat``). Prints the machine and its load with the
figures: on a loaded machine the wall time measures the queue. Not part of the test run.

    python benchmarks/bench_issue.py [--spec ogam-draft --spec jjf1535-2015] [--repeat 3]
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import platform
import statistics
import tempfile
import time
from pathlib import Path

PASSWORD = "correct horse battery"


def approved_calibration(store, spec_key: str, readings: Path):
    """A calibration of ``readings`` computed by the real worker, reviewed and approved."""
    from gonio.records import services, worker

    from gonio.formats.metadata import header_lines

    md = dict(header_lines(readings))            # the instrument the readings name
    people = {n: services.create_user(store, None, n, PASSWORD, r) for n, r in (
        ("tech", "technician"), ("rev", "reviewer"), ("rev2", "reviewer"))}
    cust = services.add_customer(store, people["tech"], "Bench customer", "1 Road")
    inst = services.register_instrument(store, people["tech"], customer_id=cust.id,
                                        serial=md.get("serial") or "B-1", spec_key=spec_key,
                                        kind="gyro", manufacturer=md.get("manufacturer", ""),
                                        model=md.get("model", ""))
    std = services.add_standard(store, people["tech"], name="table", identifier="T-1",
                                due_on=dt.date.today() + dt.timedelta(days=300))
    sha, _ = services.store_file(store, open(readings, "rb"))
    cal = services.create_calibration(store, people["tech"], instrument_id=inst.id,
                                      readings_sha256=sha, readings_name=readings.name,
                                      standard_ids=[std.id],
                                      temperature_c=md.get("temperature_c")
                                      or md.get("room_temperature_c"),
                                      humidity_pct=md.get("humidity_pct"))
    services.claim_next(store)
    assert worker.execute(store, cal.id), services.calibration(store, cal.id).error
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev2"], cal.id)
    return services.calibration(store, cal.id), readings


def time_issue(root: Path, spec_key: str, repeat: int) -> tuple[list[float], list[float]]:
    """(before, after) wall seconds: the pipeline again vs the issue as it is now."""
    from gonio.pipeline.dispatch import simulate
    from gonio.records import services, worker
    from gonio.records.compute import calibrate_folder, write_lab_toml
    from gonio.records.db import open_store
    from gonio.records.models import Calibration

    sim = simulate(spec_key, root / "sim", seed=3)
    store = open_store(None, root / "data")
    try:
        cal, readings = approved_calibration(store, spec_key, Path(sim["readings"]))
        lab = write_lab_toml(services.lab_details(store, cal.id, final=True), root / "lab.toml")
        before, after = [], []
        for i in range(repeat):
            t0 = time.perf_counter()
            calibrate_folder(readings, root / f"again-{i}", spec_key=spec_key, lab=lab)
            before.append(time.perf_counter() - t0)
            with store.writing() as s:          # issuing again, as approved (bench only)
                c = s.get(Calibration, cal.id)
                c.status, c.worker_host = "issuing", ""
                c.pending_number = c.pending_number or f"GC-2099-{i + 1:04d}"
                s.commit()
            t0 = time.perf_counter()
            assert worker.execute(store, cal.id), services.calibration(store, cal.id).error
            after.append(time.perf_counter() - t0)
    finally:
        store.close()
    return before, after


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spec", action="append", help="specification (repeatable)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    specs = args.spec or ["ogam-draft", "jjf1535-2015"]
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load "
          f"{' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    print(f"{'specification':<16} {'before: pipeline again (s)':>28} {'now: render (s)':>16}")
    for key in specs:
        with tempfile.TemporaryDirectory(prefix="bench-issue-") as tmp:
            before, after = time_issue(Path(tmp), key, args.repeat)
        print(f"{key:<16} {statistics.median(before):>28.1f} {statistics.median(after):>16.1f}")
    print(f"load after: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
