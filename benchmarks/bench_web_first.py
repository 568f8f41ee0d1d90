"""Benchmark: the web's first answers after ``gonio serve`` starts.

A fresh SQLite database is filled with one instrument and ``--calibrations`` calibrations
(7 items each, half issued; each its own stored readings file, half of them the virtual
bench's, whose metadata the pages read as they mark virtual-bench calibrations — ``--one-blob``
points them all to one synthetic blob instead; :func:`bench_records.fill`), ``gonio serve``
is started, and the
wall seconds are printed of:

* "after start" measured two ways: from the process start (``Popen``) until the login page
  answers (with the server's CPU seconds spent by then, read from /proc: the figure a loaded
  machine hides least), and from the process start until the line "serving the records"
  (every page answers from then on); then the first page asked after that line;
* the login (one Argon2id verification, by design about half a second), the first
  dashboard, the instrument's page (which marks its virtual-bench calibrations: the first
  time it reads each stored readings file's header) and again, and its history plot at its
  first drawing and again.

With ``--results FILE`` (a ``results.json``, e.g. of ``gonio demo --spec triad-alignment``)
every calibration gets its own stored copy of it (one field changed, so each has its own
digest: the source file's name numbered) and its result rows as the records write them when a result is stored (its items,
each keeping how it is stated: the history plot draws from the rows alone); ``--unkept``
keeps the synthetic rows without their statement, as a database written before rows kept it
(the plot's first drawing then reads and states each stored result once); without
``--results`` every calibration points to one synthetic blob that is no results.json.

Targets: each page under 0.5 s. Prints the machine and its load: on a loaded machine the
wall time measures the queue. Not part of the test run.

    python benchmarks/bench_web_first.py [--calibrations 100] [--pause 3] [--results FILE [--unkept]]
                                           [--one-blob]

``gonio serve`` answers the login page before its application is built
(:mod:`gonio.web.front`), then imports SciPy in the background
(:func:`gonio.web.app.warm_up`); ``--pause`` (a person typing the password) lets it finish.
"""

from __future__ import annotations

import argparse
import os
import platform
import socket
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_records import PASSWORD, PROTOCOL, fill  # noqa: E402


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _cpu_s(pid: int) -> float:
    """CPU seconds (user + system, all threads) the process ``pid`` has used so far."""
    fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def timed(rows: list, name: str, call):
    t0 = time.perf_counter()
    r = call()
    rows.append((name, time.perf_counter() - t0, r.status_code))
    return r


def give_results(store, results: Path, rows: bool = True) -> None:
    """Every calibration its own stored copy of ``results`` (its source file's name numbered)
    and, with ``rows``, the result rows the records write when a result is stored
    (:func:`gonio.records.results.result_rows`: its items, each with its statement) in place
    of the synthetic ones; without, the synthetic rows keep no statement (a database
    written before rows kept it: the plot then reads every stored result)."""
    import json

    from sqlalchemy import delete, insert, select

    from gonio.records import blobs
    from gonio.records.models import Blob, Calibration, ResultItem
    from gonio.records.results import result_rows

    doc = json.loads(results.read_bytes())
    with store.writing() as s:
        for cal in s.scalars(select(Calibration)).all():
            source = doc.get("source") if isinstance(doc.get("source"), dict) else {}
            mine = dict(doc, source=dict(source, file=f"{source.get('file', '')} #{cal.id}"))
            body = json.dumps(mine).encode()
            sha = blobs.put_bytes(store.blob_root, body)
            s.add(Blob(sha256=sha, size=len(body)))
            cal.results_sha256 = sha
            if rows:
                s.execute(delete(ResultItem).where(ResultItem.calibration_id == cal.id))
                s.execute(insert(ResultItem), result_rows(cal.id, mine))
        s.commit()


def main(argv=None) -> int:
    import re
    import subprocess

    from gonio.records.db import open_store

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--calibrations", type=int, default=100)
    ap.add_argument("--pause", type=float, default=0.0,
                    help="seconds between the login page and the login (a person typing)")
    ap.add_argument("--results", type=Path, default=None,
                    help="a results.json stored (one copy each) for every calibration, with "
                         "its result rows as the records write them")
    ap.add_argument("--unkept", action="store_true",
                    help="with --results: the synthetic rows, keeping no statement (as "
                         "before the rows kept it: the plot reads every stored result)")
    ap.add_argument("--one-blob", action="store_true",
                    help="every calibration points to one synthetic blob (no readings file "
                         "for the lists' virtual-bench mark to read)")
    args = ap.parse_args(argv)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load "
          f"{' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    with tempfile.TemporaryDirectory(prefix="bench-web-") as tmp:
        data = Path(tmp) / "data"
        readings = None
        if not args.one_blob:
            from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
            from gonio.specs.ogam_draft.protocol import load_protocol
            write_session(run_session(load_protocol(PROTOCOL), load_bench("rlg"), seed=3),
                          Path(tmp) / "run")
            readings = Path(tmp) / "run" / "readings.csv"
        store = open_store(None, data)
        fill(store, 1, args.calibrations, readings)
        if args.results is not None:
            give_results(store, args.results, rows=not args.unkept)
            print(f"results: each calibration its own copy of {args.results} "
                  f"({args.results.stat().st_size // 1024} KB), "
                  + ("the synthetic rows (no statement kept)" if args.unkept
                     else "its result rows with their statements"))
        store.close()
        port = _port()
        base = f"http://127.0.0.1:{port}"
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "gonio", "serve", "--data", str(data),
                                 "--port", str(port), "--workers", "1"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        ready = []

        def read_stderr():
            for line in proc.stderr:
                if "serving the records" in line and not ready:
                    ready.append(time.perf_counter())
        threading.Thread(target=read_stderr, daemon=True).start()
        rows: list = []
        try:
            c = httpx.Client(base_url=base, timeout=120)
            while True:
                try:
                    page = c.get("/login")
                    rows.append(("process start → login page", time.perf_counter() - t0,
                                 page.status_code))
                    rows.append(("  server CPU by then", _cpu_s(proc.pid), page.status_code))
                    break
                except httpx.HTTPError:
                    time.sleep(0.01)
            while not ready:
                if proc.poll() is not None:
                    raise SystemExit("gonio serve ended")
                time.sleep(0.01)
            rows.append(("process start → ready line", ready[0] - t0, 0))
            rows.append(("  server CPU by then", _cpu_s(proc.pid), 0))
            t1 = time.perf_counter()
            page = c.get("/login")
            rows.append(("first page after ready line", time.perf_counter() - t1,
                         page.status_code))
            token = re.search(r'name="csrf" value="([^"]+)"', page.text).group(1)
            time.sleep(args.pause)
            timed(rows, "login (Argon2id)", lambda: c.post("/login", data={
                "username": "tech", "password": PASSWORD, "csrf": token}))
            timed(rows, "first dashboard /", lambda: c.get("/"))
            timed(rows, "instrument page", lambda: c.get("/instruments/1"))
            timed(rows, "instrument page, again", lambda: c.get("/instruments/1"))
            timed(rows, "history plot, first drawing",
                  lambda: c.get("/instruments/1/history.svg"))
            timed(rows, "history plot, again", lambda: c.get("/instruments/1/history.svg"))
        finally:
            proc.terminate()
            proc.wait(30)
    for name, wall, code in rows:
        print(f"{name:<32} {wall:7.3f} s" + (f"  (HTTP {code})" if code else ""))
    print(f"load after: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
