"""Running calibrations for the records, each in its own process.

:func:`execute` runs one claimed calibration to its end. A draft: the stored readings (and
protocol) are copied into a private work folder under names gonio chooses (``readings.csv``
or ``readings.parquet`` by content), the laboratory details are written as a TOML file, the
pipeline runs (:func:`gonio.records.compute.calibrate_folder`), and the outputs go into the
content-addressed store and the database in one transaction. An issue: the stored
results.json that was reviewed and approved is checked against its seal and rendered with
the final details (:func:`gonio.records.compute.render_folder`); nothing is computed again.
A draft rendered again after standards or the environment were attached (drafting): the
stored result, checked against its seal, rendered the same way with the draft details
recorded now (:func:`run_now`: the same in the calling process, for the command line). Any
failure marks the calibration failed with the one-line reason; a killed process leaves it
running with a dead worker, which :func:`gonio.records.services.recover` marks failed.

:class:`Dispatcher` is the server's side: a thread that claims queued work and starts
``python -m gonio.records.worker ID`` processes (at most ``workers`` at a time; the
database URL travels in the environment, never on the command line).
"""

from __future__ import annotations

import argparse
import os
import secrets
import shutil
import subprocess
import sys
import threading

from gonio.errors import GonioError
from gonio.records import bench, services
from gonio.records.compute import (calibrate_folder, readings_suffix, render_folder,
                                   write_lab_toml)


def execute(store, cal_id: int) -> bool:
    """Run calibration ``cal_id`` (claimed: running or issuing). True when it succeeded."""
    cal = services.calibration(store, cal_id)
    work = store.data / "work" / f"cal-{cal_id}-{secrets.token_hex(6)}"
    try:
        work.mkdir(parents=True, mode=0o700)
        if cal.status == "issuing":
            _issue(store, cal, work)
        elif cal.status == services.DRAFTING:
            _redraft(store, cal, work)
        else:
            _compute(store, cal, work)
        return True
    except GonioError as exc:
        services.fail(store, cal_id, str(exc))
    except Exception as exc:  # a bug: recorded on the calibration, the server keeps running
        services.fail(store, cal_id, f"internal error: {type(exc).__name__}: {exc}")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return False


def _compute(store, cal, work) -> None:
    """The draft: the stored readings (and protocol) through the pipeline, its outputs
    stored (computed, ready for review)."""
    services.set_progress(store, cal.id, "preparing the readings")
    data = services.file_bytes(store, cal.readings_sha256)
    readings = work / ("readings" + readings_suffix(data[:4]))
    if services.write_inputs(store, cal.id, work / "in"):   # the files the readings name
        readings = work / "in" / readings.name
    readings.write_bytes(data)
    del data
    protocol = cal.protocol or None
    if cal.protocol_sha256:
        protocol = str(work / "protocol.toml")
        (work / "protocol.toml").write_bytes(services.file_bytes(store, cal.protocol_sha256))
    request = bench.pending_request(store, cal)
    if request is not None:              # started from a connected bench: acquire first
        readings = bench.acquire_for(store, cal, request, work, protocol)
    lab = write_lab_toml(services.lab_details(store, cal.id, final=False), work / "lab.toml")
    table = services.table_calibration_file(store, cal.id, work)
    by_option = services.write_option_files(store, cal.id, work)   # --tilt FILE, … kept
    services.set_progress(store, cal.id, "computing the items and their uncertainties, "
                                         "rendering the draft certificate")
    try:
        calibrate_folder(readings, work / "out", spec_key=cal.spec_key, protocol=protocol,
                         lab=lab, **({"table_calibration": table} if table else {}),
                         **({"options": {k: str(v) for k, v in by_option.items()}}
                            if by_option else {}))
    except GonioError as exc:          # the stored table calibration named as the records do
        if table is None or exc.file != str(table):
            raise
        raise GonioError(exc.message, file=services.TABLE_CALIBRATION, line=exc.line,
                         column=exc.column, key=exc.key) from None
    # the details the result was decided with, sealed with it: the issue's decision basis
    shutil.copyfile(lab, work / "out" / "lab.toml")
    services.set_progress(store, cal.id, "storing the files")
    services.store_run(store, cal.id, work / "out")


def _issue(store, cal, work) -> None:
    """The issue: the stored results.json that was reviewed and approved (its seal checked
    first), rendered with the final details; nothing is computed again."""
    services.set_progress(store, cal.id, "checking the sealed result")
    results = services.sealed_result(store, cal.id)
    details = services.lab_details(store, cal.id, final=True)
    lab = write_lab_toml(details, work / "lab.toml")
    services.set_progress(store, cal.id, "rendering the certificate from the sealed result")
    render_folder(results, work / "out", spec_key=cal.spec_key, lab=lab)
    services.set_progress(store, cal.id, "storing the files")
    services.store_issue(store, cal.id, work / "out",
                         stated_standards=details.get("standards") or [])


def _redraft(store, cal, work) -> None:
    """The draft certificate again, after an attach: the stored result (its stored files and
    rows checked against it first) rendered with the details recorded now; nothing is
    computed again."""
    services.set_progress(store, cal.id, "checking the stored result")
    signed = services.seal(store, cal.id)
    results = services.file_bytes(store, cal.results_sha256)
    lab = write_lab_toml(services.lab_details(store, cal.id, final=False, redraft=True),
                         work / "lab.toml")
    services.set_progress(store, cal.id, "rendering the draft certificate with what was "
                                         "attached")
    render_folder(results, work / "out", spec_key=cal.spec_key, lab=lab)
    shutil.copyfile(lab, work / "out" / "lab.toml")
    services.set_progress(store, cal.id, "storing the files")
    services.store_draft(store, cal.id, work / "out", signed)


def run_now(store, cal_id: int) -> None:
    """Claim calibration ``cal_id`` and run it in this process, the command line's way
    without a server (``gonio db attach`` renders the draft at once); nothing when it waits
    for no worker or another worker has it. A failed run is a GonioError naming the
    calibration and why (it is marked failed, as by a worker)."""
    if services.claim_next(store, cal_id=cal_id) is None:
        return
    services.attach(store, cal_id, os.getpid())
    if not execute(store, cal_id):
        raise GonioError(f"calibration {cal_id} failed: "
                         f"{services.calibration(store, cal_id).error}", key="worker")


class Dispatcher:
    """Claims queued calibrations and runs each in a worker process, ``workers`` at a time.

    ``start()`` first marks calibrations whose worker died (on this host) failed."""

    def __init__(self, store, workers: int = 2, poll_s: float = 0.5):
        self.store, self.workers, self.poll_s = store, max(1, int(workers)), poll_s
        self.children: dict[int, subprocess.Popen] = {}
        self._stop = threading.Event()
        self._wake = threading.Event()
        self._thread: threading.Thread | None = None
        self._claiming = threading.Lock()     # held while the loop touches the records
        self._paused = 0                      # pauses not yet resumed (two restores at once)

    def start(self) -> "Dispatcher":
        services.recover(self.store)
        self._thread = threading.Thread(target=self._loop, name="gonio-dispatcher",
                                        daemon=True)
        self._thread.start()
        return self

    def wake(self) -> None:
        """New work was queued: look now instead of at the next poll."""
        self._wake.set()

    def pause(self) -> int:
        """Stop claiming and reaping (the records are about to be replaced); returns how
        many worker processes are still running (a restore waits for none). Workers that
        ended are forgotten when none runs: each recorded its own end in the records that
        are replaced. Pauses nest: the dispatcher claims again once each has been
        resumed."""
        with self._claiming:
            self._paused += 1
            running = sum(p.poll() is None for p in self.children.values())
            if not running:
                self.children.clear()
            return running

    def resume(self) -> None:
        """Claim again after :meth:`pause`; calibrations left running by a worker that is
        gone (as a restored archive may hold them) are marked failed first. While another
        pause holds (a second restore that was turned away ends first) it only counts down."""
        with self._claiming:
            self._paused = max(0, self._paused - 1)
            if self._paused:
                return
            services.recover(self.store)
        self.wake()

    def stop(self, wait: bool = True, timeout_s: float = 600) -> None:
        """Stop claiming; with ``wait`` let the running workers finish."""
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
        if wait:
            for p in list(self.children.values()):
                p.wait(timeout_s)
            self._reap()

    def _reap(self) -> None:
        for cid, p in list(self.children.items()):
            rc = p.poll()
            if rc is None:
                continue
            del self.children[cid]
            cal = services.calibration(self.store, cid)
            if cal.status in services.WORKING and cal.worker_pid == p.pid:
                services.fail(self.store, cid, f"the worker process ended with code {rc}")
            services.remove_work(self.store, cid)

    def _spawn(self, cal_id: int) -> None:
        env = dict(os.environ, GONIO_RECORDS_DATABASE=self.store.url,
                   GONIO_RECORDS_DATA=str(self.store.data))
        p = subprocess.Popen([sys.executable, "-m", "gonio.records.worker", str(cal_id)],
                             env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
        self.children[cal_id] = p
        services.attach(self.store, cal_id, p.pid)

    def _claim(self) -> None:
        self._reap()
        while len(self.children) < self.workers and not self._stop.is_set():
            cal = services.claim_next(self.store)
            if cal is None:
                break
            self._spawn(cal.id)

    def _loop(self) -> None:
        while not self._stop.is_set():
            try:
                with self._claiming:
                    if not self._paused:
                        self._claim()
            except Exception as exc:  # the database went away a moment: try again later
                sys.stderr.write(f"gonio: dispatcher: {type(exc).__name__}: {exc}\n")
            self._wake.wait(self.poll_s)
            self._wake.clear()


def main(argv=None) -> int:
    """``python -m gonio.records.worker ID``: run one claimed calibration (the database URL
    and data folder from ``GONIO_RECORDS_DATABASE`` / ``GONIO_RECORDS_DATA``)."""
    from gonio.records.db import open_store

    ap = argparse.ArgumentParser(prog="gonio.records.worker")
    ap.add_argument("calibration", type=int)
    args = ap.parse_args(argv)
    store = open_store(os.environ.get("GONIO_RECORDS_DATABASE"),
                       os.environ.get("GONIO_RECORDS_DATA"), upgrade=False)
    try:
        return 0 if execute(store, args.calibration) else 1
    finally:
        store.close()


if __name__ == "__main__":  # pragma: no cover - run as a process by the Dispatcher
    raise SystemExit(main())
