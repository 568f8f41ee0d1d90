"""Load benchmark of the records and gonio serve (issue 27).

1. Fills a fresh database with 1 000 instruments and 10 000 calibrations (7 result items
   each, half of them issued with a certificate) by bulk inserts; each calibration stores
   its own readings file (half of them the virtual bench's: the lists read each shown
   calibration's metadata to mark it), or with ``--one-blob`` all point to one synthetic blob.
2. Starts ``gonio serve`` on it and times pages over HTTP from one client: the instrument
   list, the calibration list (random pages), the instrument page (random instruments) and
   its history plot; prints p50 / p95 per page (target: p95 < 200 ms for lists and
   instrument pages).
3. Uploads 8 readings files at once (8 client threads, small optical protocol) and waits
   until all 8 are computed: prints the time and checks every one has its items.

    python benchmarks/bench_records.py [--database postgresql://… | --postgresql]
                                       [--requests 200] [--pages-only] [--one-blob]

``--postgresql`` starts a throwaway PostgreSQL server for the run (as the tests do, from
Debian's server binaries); ``--pages-only`` skips the uploads (3.).

Prints the machine (cores, load) with the figures: page times depend on it.
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import random
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx
from sqlalchemy import insert

REPO = Path(__file__).resolve().parents[1]
PROTOCOL = REPO / "tests" / "data" / "small-protocol.toml"
PASSWORD = "benchmark password"


def readings_copies(readings: Path, n_calibrations: int, n_instruments: int):
    """Each calibration its own stored readings file (a list of bytes, calibration 1 first),
    made from the virtual bench's ``readings``: its serial the instrument's and its operator
    line numbered (each file has its own SHA-256); every second file keeps the virtual
    bench's own lines (``# bench:``, ``# seed:``, ``# generator:``: the lists mark it
    virtual), the others have them removed and the instrument, manufacturer and table named
    as a laboratory's (a laboratory's file: not marked)."""
    lines = readings.read_text().splitlines(keepends=True)
    out = []
    for c in range(n_calibrations):
        virtual = c % 2 == 0
        mine = []
        for line in lines:
            key = line[2:].split(":", 1)[0] if line.startswith("# ") else None
            if key == "serial":
                line = f"# serial: S-{c % n_instruments + 1:05d}\n"
            elif key == "operator":
                line = f"# operator: technician {c + 1}\n"
            elif key in ("bench", "seed", "generator", "noise") and not virtual:
                continue
            elif key in ("instrument", "manufacturer", "table") and not virtual:
                line = f"# {key}: laboratory {key}\n"      # the bench's names say "virtual"
            mine.append(line)
        out.append("".join(mine).encode())
    return out


def fill(store, n_instruments: int, n_calibrations: int, readings: Path | None = None) -> None:
    """``n_calibrations`` calibrations of ``n_instruments`` instruments (7 result items each,
    every second one issued). With ``readings`` (a virtual bench's readings file) each
    calibration stores its own copy (:func:`readings_copies`: half of them virtual), so
    the lists read each one's metadata as they mark virtual-bench calibrations; without,
    every calibration points to one synthetic blob that is no readings file."""
    from gonio.records import blobs, services
    from gonio.records.models import (Blob, Calibration, Certificate, Customer, Instrument,
                                      ResultItem)

    services.create_user(store, None, "tech", PASSWORD, "technician reviewer admin")
    sha = blobs.put_bytes(store.blob_root, b"synthetic readings")
    own = []
    if readings is not None:
        for body in readings_copies(readings, n_calibrations, n_instruments):
            own.append((blobs.put_bytes(store.blob_root, body), len(body)))
    keys = [("scale_factor", "scale factor K", "7.1", "counts/deg", 76434.8, 0.025),
            ("scale_factor_nonlinearity", "scale-factor nonlinearity K_l", "7.2", "%", 3e-5,
             2e-5), ("zero_stability", "zero stability B_s", "7.3", "deg/h", 8e-4, 3e-3),
            ("angle_deviation", "angle-position deviation E", "7.4", "arcsec", 0.17, 0.9),
            ("repeatability", "angle-position repeatability R", "7.5", "arcsec", 0.18, 0.38),
            ("rate_consistency", "rate consistency C_v", "7.6", "ppm", 0.015, 0.39),
            ("pointing_consistency", "pointing consistency C_g", "7.7", "%", 7.6e-6, 4e-5)]
    rng = random.Random(0)
    t0 = time.perf_counter()
    with store.writing() as s:
        s.add(Blob(sha256=sha, size=18))
        if own:
            s.execute(insert(Blob), [{"sha256": h, "size": n} for h, n in own])
        s.execute(insert(Customer), [{"id": i + 1, "name": f"Customer {i + 1}", "address": ""}
                                     for i in range(50)])
        s.execute(insert(Instrument), [
            {"id": i + 1, "customer_id": i % 50 + 1, "kind": "RLG goniometer",
             "manufacturer": "Works", "model": f"M-{i % 7}", "serial": f"S-{i + 1:05d}",
             "spec_key": "ogam-draft", "limits_json": '[{"item": "angle_deviation", '
             '"mpe": 0.5, "lower": null, "upper": null, "source": ""}]'}
            for i in range(n_instruments)])
        cals, items, certs = [], [], []
        for c in range(n_calibrations):
            inst = c % n_instruments + 1
            day = dt.date(2016, 1, 1) + dt.timedelta(days=365 * (c // n_instruments)
                                                      + rng.randrange(60))
            issued = c % 2 == 0
            cals.append({"id": c + 1, "instrument_id": inst, "spec_key": "ogam-draft",
                         "readings_sha256": own[c][0] if own else sha,
                         "readings_name": "readings.csv",
                         "performed_on": day, "status": "issued" if issued else "computed",
                         "created_by_id": 1, "results_sha256": sha})
            for k, title, clause, unit, v, U in keys:
                items.append({"calibration_id": c + 1, "key": k, "title": title,
                              "clause": clause, "unit": unit, "measured": True,
                              "value": v * (1 + 0.05 * rng.gauss(0, 1)), "U": U, "k": 2.0})
            if issued:
                certs.append({"number": f"GC-{day.year}-{len(certs) + 1:05d}",
                              "calibration_id": c + 1, "issued_by_id": 1, "html_sha256": sha,
                              "pdf_sha256": sha, "results_sha256": sha})
        s.execute(insert(Calibration), cals)
        s.execute(insert(ResultItem), items)
        s.execute(insert(Certificate), certs)
        s.commit()
    if store.engine.dialect.name == "postgresql":
        from sqlalchemy import text
        with store.writing() as s:
            for t in ("customers", "instruments", "calibrations", "result_items",
                      "certificates"):
                s.execute(text(f"SELECT setval(pg_get_serial_sequence('{t}', 'id'), "
                               f"(SELECT MAX(id) FROM {t}))"))
            s.commit()
    print(f"filled: {n_instruments} instruments, {n_calibrations} calibrations, "
          f"{len(items)} result items, {len(certs)} certificates, "
          + (f"{len(own)} stored readings files (half virtual)" if own
             else "one synthetic readings blob") + " in "
          f"{time.perf_counter() - t0:.1f} s")


def start(data: Path, database: str | None, port: int) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "gonio", "serve", "--data", str(data), "--port", str(port)]
    if database:
        cmd += ["--database", database]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(600):
        try:
            httpx.get(f"http://127.0.0.1:{port}/login", timeout=2)
            return proc
        except httpx.HTTPError:
            time.sleep(0.5)
    raise SystemExit("gonio serve did not start")


def login(base: str) -> httpx.Client:
    c = httpx.Client(base_url=base, timeout=120)
    token = re.search(r'name="csrf" value="([^"]+)"', c.get("/login").text).group(1)
    r = c.post("/login", data={"username": "tech", "password": PASSWORD, "csrf": token})
    assert r.status_code == 303, r.text
    return c


def time_pages(c: httpx.Client, n: int, n_instruments: int, n_calibrations: int) -> None:
    rng = random.Random(1)
    pages = {
        "instrument list": lambda: f"/instruments?page={rng.randrange(1, n_instruments // 50)}",
        "calibration list": lambda: f"/calibrations?page={rng.randrange(1, n_calibrations // 50)}",
        "instrument page": lambda: f"/instruments/{rng.randrange(1, n_instruments + 1)}",
        "history plot (SVG)": lambda: f"/instruments/{rng.randrange(1, n_instruments + 1)}"
                                      "/history.svg",
    }
    page = c.get(f"/calibrations?page={n_calibrations // 50}").text
    marks, shown = page.count('class="virtual-tag"'), page.count('<tr><td><a href="/calibr')
    print(f"virtual-bench marks on a calibration list page: {marks} of {shown} rows")
    print(f"{'page':22s} {'n':>5s} {'p50 ms':>8s} {'p95 ms':>8s} {'max ms':>8s}")
    for name, url in pages.items():
        c.get(url())                                 # warm
        times = []
        for _ in range(n if "plot" not in name else 20):
            t = time.perf_counter()
            r = c.get(url())
            times.append(1000 * (time.perf_counter() - t))
            assert r.status_code == 200, (name, r.status_code)
        times.sort()
        p95 = times[min(len(times) - 1, int(0.95 * len(times)))]
        print(f"{name:22s} {len(times):5d} {statistics.median(times):8.1f} {p95:8.1f} "
              f"{times[-1]:8.1f}")


def uploads(base: str, readings: Path, n: int = 8, inst_id: int = 1) -> None:
    results: list = [None] * n

    def one(i):
        c = login(base)
        token = re.search(r'name="csrf" value="([^"]+)"', c.get("/").text).group(1)
        with open(readings, "rb") as fh, open(PROTOCOL, "rb") as ph:
            r = c.post(f"/instruments/{inst_id}/calibrate",
                       data={"csrf": token, "spec_key": "ogam-draft",
                             "performed_on": f"2027-01-{i + 1:02d}"},
                       files={"readings": (f"readings-{i}.csv", fh),
                              "protocol_file": ("p.toml", ph)})
        assert r.status_code == 303, r.text[:500]
        results[i] = int(r.headers["location"].rsplit("/", 1)[1])

    t0 = time.perf_counter()
    threads = [threading.Thread(target=one, args=(i,)) for i in range(n)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    t_up = time.perf_counter() - t0
    c = login(base)
    while True:
        states = [c.get(f"/calibrations/{cid}/progress").json() for cid in results]
        if all(s["status"] in ("computed", "failed") for s in states):
            break
        time.sleep(1)
    t_all = time.perf_counter() - t0
    ok = [s for s in states if s["status"] == "computed"]
    print(f"{n} concurrent uploads: accepted in {t_up:.1f} s, all finished in {t_all:.1f} s; "
          f"{len(ok)}/{n} computed" + "".join(f"; {s['id']}: {s['error']}" for s in states
                                               if s["status"] != "computed"))


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--database", default=None)
    ap.add_argument("--instruments", type=int, default=1000)
    ap.add_argument("--calibrations", type=int, default=10000)
    ap.add_argument("--requests", type=int, default=200)
    ap.add_argument("--port", type=int, default=8791)
    ap.add_argument("--postgresql", action="store_true",
                    help="a throwaway PostgreSQL server for this run")
    ap.add_argument("--pages-only", action="store_true", help="no uploads (step 3)")
    ap.add_argument("--one-blob", action="store_true",
                    help="every calibration points to one synthetic blob (no readings file "
                         "for the lists' virtual-bench mark to read)")
    args = ap.parse_args()
    if args.postgresql:
        sys.path.insert(0, str(REPO / "tests" / "records"))
        from conftest import new_pg_database, throwaway_postgresql

        with throwaway_postgresql() as server:
            args.database = new_pg_database(server)
            return run(args)
    return run(args)


def run(args) -> int:
    from gonio.records.db import open_store

    print(f"machine: {os.cpu_count()} cores, load average "
          f"{' '.join(f'{x:.1f}' for x in os.getloadavg())}; database "
          f"{'PostgreSQL' if args.database else 'SQLite'}")
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "data"
        from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
        from gonio.specs.ogam_draft.protocol import load_protocol
        write_session(run_session(load_protocol(PROTOCOL), load_bench("rlg"), seed=3),
                      Path(tmp) / "run")
        store = open_store(args.database, data)
        fill(store, args.instruments, args.calibrations,
             None if args.one_blob else Path(tmp) / "run" / "readings.csv")
        store.close()
        proc = start(data, args.database, args.port)
        try:
            base = f"http://127.0.0.1:{args.port}"
            time_pages(login(base), args.requests, args.instruments, args.calibrations)
            print(f"load average after the pages: "
                  f"{' '.join(f'{x:.1f}' for x in os.getloadavg())}")
            if not args.pages_only:
                uploads(base, Path(tmp) / "run" / "readings.csv")
        finally:
            proc.terminate()
            try:
                proc.wait(30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
