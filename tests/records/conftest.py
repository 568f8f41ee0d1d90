"""Fixtures of the records and web tests: a throwaway PostgreSQL cluster (Debian's server
binaries, started in a temporary folder), stores on SQLite and PostgreSQL, users, readings
from the virtual bench and one real pipeline run shared by the service tests."""

from __future__ import annotations

import contextlib
import glob
import os
import pwd
import shutil
import socket
import subprocess
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SMALL_PROTOCOL = REPO / "tests" / "data" / "small-protocol.toml"
PASSWORD = "correct horse battery"


def pg_bindir() -> Path | None:
    """The PostgreSQL server binaries (initdb, pg_ctl), or None when not installed."""
    found = sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"))
    if found:
        return Path(found[-1]).parent
    w = shutil.which("initdb")
    return Path(w).parent if w else None


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _as_pg_user(cmd: list[str]) -> list[str]:
    # initdb and postgres refuse to run as root: run them as the 'postgres' account
    if os.geteuid() == 0:
        pwd.getpwnam("postgres")
        return ["runuser", "-u", "postgres", "--"] + cmd
    return cmd


@contextlib.contextmanager
def throwaway_postgresql():
    """A PostgreSQL server on 127.0.0.1 (trust authentication) in a temporary folder; yields
    its URL without a database name and removes it afterwards (also used by
    benchmarks/bench_records.py --postgresql)."""
    import tempfile

    bindir = pg_bindir()
    if bindir is None:
        raise RuntimeError("PostgreSQL server binaries not installed "
                           "(bash scripts/install-test-system-deps.sh)")
    # not under pytest's base folder: that is private to root, and the server runs as postgres
    root = Path(tempfile.mkdtemp(prefix="gonio-pg-"))
    data = root / "cluster"
    if os.geteuid() == 0:
        os.chmod(root, 0o755)
        os.makedirs(data, mode=0o700)
        shutil.chown(data, "postgres", "postgres")
    subprocess.run(_as_pg_user([str(bindir / "initdb"), "-D", str(data), "-U", "postgres",
                                "--auth=trust", "-E", "UTF8", "--no-sync"]),
                   check=True, capture_output=True)
    log = data / "server.log"
    for attempt in range(5):
        # a free port may be taken between free_port() and the server's bind (by another
        # pytest-xdist worker's server or any client's ephemeral port): start on another
        port = free_port()
        started = subprocess.run(
            _as_pg_user([str(bindir / "pg_ctl"), "-D", str(data), "-l", str(log), "-w",
                         "-o", f"-p {port} -k {data} -c listen_addresses=127.0.0.1 "
                               "-c fsync=off -c max_connections=200", "start"]),
            capture_output=True, text=True)
        if started.returncode == 0:
            break
    else:
        shutil.rmtree(root, ignore_errors=True)
        raise RuntimeError(f"PostgreSQL did not start in 5 attempts: {started.stderr.strip()}")
    try:
        yield f"postgresql://postgres@127.0.0.1:{port}"
    finally:
        subprocess.run(_as_pg_user([str(bindir / "pg_ctl"), "-D", str(data), "-m", "immediate",
                                    "stop"]), capture_output=True)
        shutil.rmtree(root, ignore_errors=True)


@pytest.fixture(scope="session")
def pg_server():
    """A throwaway PostgreSQL server (:func:`throwaway_postgresql`) for this test session;
    its URL without a database name. Skipped only when the server binaries are absent
    (scripts/install-test-system-deps.sh installs them)."""
    if pg_bindir() is None:
        pytest.skip("PostgreSQL server binaries not installed "
                    "(bash scripts/install-test-system-deps.sh)")
    with throwaway_postgresql() as url:
        yield url


_counter = iter(range(10**6))


def new_pg_database(server: str) -> str:
    import psycopg

    name = f"gonio_test_{os.getpid()}_{next(_counter)}"
    with psycopg.connect(server.replace("postgresql://", "postgresql://", 1) + "/postgres",
                         autocommit=True) as conn:
        conn.execute(f'CREATE DATABASE "{name}"')
    return f"{server}/{name}"


def both_back_ends(tmp_path: Path, server: str) -> list[tuple[str | None, Path]]:
    """(url, data folder) of new records on SQLite (url None, ``tmp_path/sqlite``) and on a
    new database of the throwaway PostgreSQL ``server`` (``tmp_path/pg``), for the
    migration tests that run once on each."""
    return [(None, tmp_path / "sqlite"), (new_pg_database(server), tmp_path / "pg")]


def records_at(url: str | None, data: Path, revision: str):
    """A store opened without upgrading and migrated up to ``revision`` only: the records
    as that revision wrote them, for a migration test to write its rows into."""
    from gonio.records.db import migrate, open_store

    st = open_store(url, data, upgrade=False)
    migrate(st.engine, revision)
    return st


def insert_instrument(conn, sha256: str = "a" * 64, size: int = 1,
                      created_at: str = "2025-01-01") -> None:
    """Rows every schema since 0001 has, written by hand as an old revision holds them: a
    stored file ``sha256`` of ``size`` bytes, customer 1 ('C') and its instrument 1 (serial
    'S', ogam-draft), all created at ``created_at``."""
    from sqlalchemy import text

    conn.execute(text("INSERT INTO blobs (sha256, size, created_at) VALUES (:s, :n, :t)"),
                 {"s": sha256, "n": size, "t": created_at})
    conn.execute(text("INSERT INTO customers (id, name, address, created_at) VALUES "
                      "(1, 'C', '', :t)"), {"t": created_at})
    conn.execute(text(
        "INSERT INTO instruments (id, customer_id, kind, manufacturer, model, serial, "
        "spec_key, limits_json, created_at) VALUES (1, 1, '', '', '', 'S', 'ogam-draft', "
        "'[]', :t)"), {"t": created_at})


@pytest.fixture(params=["sqlite", "postgresql"])
def store(request, tmp_path):
    """An open, migrated records store on SQLite or on PostgreSQL (a new database)."""
    from gonio.records.db import open_store

    url = None
    if request.param == "postgresql":
        url = new_pg_database(request.getfixturevalue("pg_server"))
    st = open_store(url, tmp_path / "data")
    yield st
    st.close()


@pytest.fixture
def sqlite_store(tmp_path):
    from gonio.records.db import open_store

    st = open_store(None, tmp_path / "data")
    yield st
    st.close()


def make_people(store):
    """tech (technician), rev (reviewer), admin — with :data:`PASSWORD`."""
    from gonio.records import services

    return {name: services.create_user(store, None, name, PASSWORD, roles)
            for name, roles in (("tech", "technician"), ("rev", "reviewer"),
                                ("rev2", "reviewer"), ("admin", "admin technician reviewer"))}


@pytest.fixture
def people(store):
    return make_people(store)


@pytest.fixture(autouse=True)
def pipeline_memo(request, monkeypatch):
    """The records' pipeline call and the certificate's rendering behind in-process memos
    keyed by the SHA-256 of every input (tests/records/pipeline_memo.py): an import computes
    its folder's result again, an issue renders the stored result again, and these tests
    import the same folders and issue the same result with the same details many times (the
    worker's calls too: its draft's pipeline, its issue's and redraft's rendering), shared by
    the session's xdist workers (``session_memo``).
    ``@pytest.mark.real_pipeline``: without."""
    if request.node.get_closest_marker("real_pipeline"):
        return
    from gonio.records import compute, worker

    from .pipeline_memo import _MEMO, _RENDER_MEMO, memoised, memoised_render

    session_memo = request.getfixturevalue("session_memo")

    real = getattr(compute.calibrate_folder, "__wrapped__", compute.calibrate_folder)
    memo = session_memo("pipeline", _MEMO)
    monkeypatch.setattr(compute, "calibrate_folder", memoised(real, memo))
    monkeypatch.setattr(worker, "calibrate_folder", memoised(real, memo))
    render = getattr(worker.render_folder, "__wrapped__", worker.render_folder)
    monkeypatch.setattr(worker, "render_folder",
                        memoised_render(render, session_memo("render", _RENDER_MEMO)))


@pytest.fixture(scope="session")
def session_memo(tmp_path_factory):
    """``session_memo(name, local)``: the memo of tests/records/pipeline_memo.py shared by
    every xdist worker of this session (:class:`SessionMemo`, files under the session's
    shared temporary root), with this process's dict ``local`` in front."""
    from .pipeline_memo import SessionMemo

    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent                       # shared by the session's workers
    made = {}

    def get(name: str, local: dict) -> SessionMemo:
        if name not in made:
            made[name] = SessionMemo(root / "records-memo" / name, local)
        return made[name]
    return get


@pytest.fixture(scope="session")
def bench_readings(shared_run):
    """Two readings files of the small optical protocol (seeds 1 and 2) from the virtual
    bench, made once per test session for every xdist worker (``shared_run``: read them,
    never write beside them)."""
    import hashlib

    def make(root: Path) -> None:
        from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
        from gonio.specs.ogam_draft.protocol import load_protocol

        for seed in (1, 2):
            session = run_session(load_protocol(SMALL_PROTOCOL), load_bench("rlg"), seed=seed)
            write_session(session, root / f"run{seed}")

    tag = hashlib.sha256(SMALL_PROTOCOL.read_bytes()).hexdigest()[:16]
    root = shared_run(f"records-bench-rlg-small-protocol-{tag}-seeds-1-2", make)
    return [root / f"run{seed}" / "readings.csv" for seed in (1, 2)]


@pytest.fixture(scope="session")
def computed_folder(bench_readings, shared_run):
    """One real pipeline run (readings of seed 1, small protocol, certificate and DCC):
    what the worker stores, reused by the service tests so they need not recompute; made
    once per test session for every xdist worker (``shared_run``: copy it into ``tmp_path``
    before changing a file)."""
    import hashlib

    def make(root: Path) -> None:
        from gonio.records.compute import calibrate_folder

        real = getattr(calibrate_folder, "__wrapped__", calibrate_folder)
        real(bench_readings[0], root / "out", spec_key="ogam-draft",
             protocol=str(SMALL_PROTOCOL))

    tag = hashlib.sha256(bench_readings[0].read_bytes() + b"\0"
                         + SMALL_PROTOCOL.read_bytes()).hexdigest()[:16]
    return shared_run(f"records-computed-ogam-draft-small-protocol-{tag}", make) / "out"


@pytest.fixture(scope="session")
def server_memo(tmp_path_factory) -> Path:
    """The folder of the pipeline's and the rendering's memos shared by the session's servers
    (``serve.start(..., memo=True)``) and xdist workers: :func:`session_memo`'s."""
    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent                       # shared by the session's workers
    return root / "records-memo"


class Server:
    """Start and stop ``gonio serve`` processes (each in its own process group, so that a
    test can kill the server together with its worker processes). ``memo``: the folder of
    the memo its workers' pipeline and rendering share (the browser tests' calibrations made
    again with the same inputs: the same bytes); None: every run computes."""

    def __init__(self, memo: Path | None = None):
        self.procs = []
        self.memo = memo

    def start(self, data: Path, workers: int = 2, database: str | None = None,
              memo: bool = False):
        """A ``gonio serve`` on ``data``; ``memo``: its workers behind the session's memo
        (:func:`server_memo`)."""
        import sys
        import urllib.request

        from .pipeline_memo import server_environment

        url = ["--database", database] if database else []
        env = server_environment(self.memo) if memo and self.memo is not None else None
        for attempt in range(5):
            # a free port may be taken before the server binds it (another pytest-xdist
            # worker, any client's ephemeral port): a server that could not bind it is
            # started again on another port; any other early end fails the test
            port = free_port()
            proc = subprocess.Popen([sys.executable, "-m", "gonio", "serve", "--data",
                                     str(data), "--port", str(port), "--workers", str(workers),
                                     *url], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                    start_new_session=True, env=env)
            self.procs.append(proc)
            answer = self._wait(proc, port)
            if answer is not None:
                return proc, answer
        raise AssertionError("gonio serve could not bind a free port in 5 attempts")

    @staticmethod
    def _wait(proc, port: int) -> str | None:
        """The server's URL once it answers; None where it ended because its port was taken."""
        import urllib.request

        end = time.monotonic() + 240
        while time.monotonic() < end:
            if proc.poll() is not None:
                err = proc.stderr.read().decode()
                if "address already in use" in err.lower() or "errno 98" in err.lower():
                    return None
                raise AssertionError(f"gonio serve ended: {err}")
            try:
                urllib.request.urlopen(f"http://127.0.0.1:{port}/login", timeout=2)
                return f"http://127.0.0.1:{port}"
            except OSError:
                time.sleep(0.5)
        raise AssertionError("gonio serve did not answer within 240 s")

    def stop(self, proc, sig=None) -> None:
        import signal

        if proc.poll() is None:
            os.killpg(proc.pid, sig or signal.SIGTERM)
            try:
                proc.wait(30)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()


@pytest.fixture
def serve(server_memo):
    """A :class:`Server`; every server it started is stopped after the test."""
    srv = Server(server_memo)
    yield srv
    for p in srv.procs:
        srv.stop(p)


def conditions(store, actor) -> dict:
    """What every new calibration names (the submission checks of
    :func:`gonio.records.services.create_calibration`): one registered standard in date
    (registered on the first call) and the environment, as keyword arguments."""
    import datetime as dt

    from sqlalchemy import select

    from gonio.records import services
    from gonio.records.models import Standard

    with store.session() as s:
        sid = s.scalar(select(Standard.id).where(Standard.identifier == "ENV-STD-1"))
    if sid is None:
        sid = services.add_standard(store, actor, name="reference rotary table",
                                    identifier="ENV-STD-1",
                                    due_on=dt.date.today() + dt.timedelta(days=400)).id
    return {"standard_ids": [sid], "temperature_c": 20.0, "humidity_pct": 45.0}
