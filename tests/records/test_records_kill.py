"""Killing ``gonio serve`` (SIGKILL to the server and its worker processes) in the middle
of a calibration run and in the middle of issuing: the calibration is marked failed at the
next start, nothing is half issued, and running it again issues the certificate under the
number reserved before the kill."""

from __future__ import annotations

import datetime as dt
import signal
import time
from pathlib import Path

from sqlalchemy import func, select

from gonio.records import services
from gonio.records.db import open_store
from gonio.records.models import Certificate, CertificateCounter

from .conftest import conditions
from .test_records_services import store_run_as_computed

PASSWORD = "correct horse battery"


def prepare(data, readings, protocol):
    st = open_store(None, data)
    tech = services.create_user(st, None, "tech", PASSWORD, "technician")
    rev = services.create_user(st, None, "rev", PASSWORD, "reviewer")
    cust = services.add_customer(st, tech, "C")
    inst = services.register_instrument(st, tech, customer_id=cust.id, serial="RLG-0001",
                                        spec_key="ogam-draft")
    sha, _ = services.store_file(st, open(readings, "rb"))
    psha, _ = services.store_file(st, open(protocol, "rb"))
    args = dict(instrument_id=inst.id, readings_sha256=sha, protocol_sha256=psha,
                **conditions(st, tech))
    return st, tech, rev, args


def test_kill_during_run_and_during_issue(tmp_path, serve, bench_readings, computed_folder):
    protocol = Path(__file__).resolve().parents[1] / "data" / "small-protocol.toml"
    data = tmp_path / "data"
    st, tech, rev, args = prepare(data, bench_readings[0], protocol)
    try:
        # 1. killed while computing
        cal = services.create_calibration(st, tech, **args)
        proc, _ = serve.start(data, workers=1)
        _wait_for(lambda: services.calibration(st, cal.id).worker_pid, 240)
        serve.stop(proc, signal.SIGKILL)                 # server and worker, at once
        got = services.calibration(st, cal.id)
        assert got.status == "running" and not got.results_sha256
        proc, _ = serve.start(data, workers=1)           # the next start finds it dead
        got = _wait_for(lambda: (c := services.calibration(st, cal.id)).status == "failed"
                       and c, 120)
        assert "interrupted" in got.error
        # the killed worker's copy of the readings is removed with it
        assert not list((data / "work").glob(f"cal-{cal.id}-*"))
        serve.stop(proc)

        # 2. killed while issuing: the number is reserved, no certificate row exists
        other, _ = services.store_file(st, open(bench_readings[1], "rb"))  # another run
        cal2 = services.create_calibration(st, tech, **dict(args, readings_sha256=other))
        services.claim_next(st)
        store_run_as_computed(st, cal2.id, computed_folder)
        services.review(st, rev, cal2.id, accept=True)
        services.approve(st, services.create_user(st, None, "rev2", PASSWORD, "reviewer"),
                         cal2.id)                     # a third person approves
        number = services.calibration(st, cal2.id).pending_number
        proc, _ = serve.start(data, workers=1)
        _wait_for(lambda: (c := services.calibration(st, cal2.id)).worker_pid
                 and c.status == "issuing", 240)
        serve.stop(proc, signal.SIGKILL)
        with st.session() as s:
            assert s.scalar(select(func.count()).select_from(Certificate)) == 0
        proc, _ = serve.start(data, workers=1)
        got = _wait_for(lambda: (c := services.calibration(st, cal2.id)).status == "failed"
                       and c, 120)
        assert got.pending_number == number and got.progress == "issuing failed"
        # 3. issued on the second try, under the same number; no number used up
        services.retry(st, tech, cal2.id)
        got = _wait_for(lambda: (c := services.calibration(st, cal2.id)).status
                       in ("issued", "failed") and c, 600)
        assert got.status == "issued", got.error
        with st.session() as s:
            certs = s.scalars(select(Certificate)).all()
            year = dt.datetime.now(dt.timezone.utc).year
            assert [c.number for c in certs] == [number] == [f"GC-{year}-0001"]
            assert s.get(CertificateCounter, year).last == 1
        assert not list((data / "blobs").rglob(".incoming-*"))
    finally:
        st.close()


def _wait_for(predicate, timeout_s: float = 120, step_s: float = 0.3):
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        got = predicate()
        if got:
            return got
        time.sleep(step_s)
    raise AssertionError(f"timed out after {timeout_s} s")
