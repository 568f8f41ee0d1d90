"""gonio serve's first answers (gonio.web.front): the login page before the application is
built — the same page, cookie and headers as the application's own — every other request
held until the application is there, a failed start answered 503 and raised as one line."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import threading
import time

from fastapi.testclient import TestClient

from gonio.web.app import create_app
from gonio.web.front import Front

from .conftest import free_port

TOKEN = re.compile(r"[A-Za-z0-9_-]{43}")


def _same_but_token(a: str, b: str) -> bool:
    return TOKEN.sub("T", a) == TOKEN.sub("T", b)


def test_front_login_page_is_the_applications(sqlite_store):
    full = TestClient(create_app(sqlite_store)).get("/login")
    early = TestClient(Front().prepare()).get("/login")
    assert full.status_code == early.status_code == 200
    assert _same_but_token(full.text, early.text)
    assert TOKEN.search(early.text).group(0) == early.cookies["gonio_login"]
    assert sorted(full.headers) == sorted(early.headers)
    for name in full.headers:
        assert _same_but_token(full.headers[name], early.headers[name]), name


def test_other_requests_wait_for_the_application(sqlite_store):
    front = Front()
    client = TestClient(front, follow_redirects=False)
    got = {}
    t = threading.Thread(target=lambda: got.update(r=client.get("/instruments")))
    t.start()
    time.sleep(0.3)
    assert "r" not in got                        # held: no application yet
    front.serve(create_app(sqlite_store))
    t.join(30)
    assert got["r"].status_code == 303 and got["r"].headers["location"] == "/login"
    assert client.get("/login").status_code == 200        # now the application's


def test_failed_start_answers_503():
    front = Front()
    front.fail("the database <is> locked")
    r = TestClient(front).get("/")
    assert r.status_code == 503 and "the database &lt;is&gt; locked" in r.text
    assert r.headers["x-frame-options"] == "DENY"


def _serve(data, port):
    return subprocess.Popen([sys.executable, "-m", "gonio", "serve", "--data", str(data),
                             "--port", str(port), "--workers", "1"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def test_serve_says_ready_once_every_page_answers(tmp_path):
    import httpx

    port = free_port()
    proc = _serve(tmp_path / "data", port)
    try:
        lines = []
        reader = threading.Thread(target=lambda: lines.extend(proc.stderr), daemon=True)
        reader.start()
        end = time.monotonic() + 240
        while not any("serving the records" in x for x in lines):
            assert proc.poll() is None and time.monotonic() < end, lines
            time.sleep(0.05)
        r = httpx.get(f"http://127.0.0.1:{port}/instruments", timeout=5, follow_redirects=True)
        assert r.status_code == 200 and "Log in" in r.text     # redirected by the application
    finally:
        proc.terminate()
        proc.wait(30)


def test_serve_on_a_broken_database_is_one_line(tmp_path):
    data = tmp_path / "data"
    data.mkdir()
    (data / "records.sqlite3").write_bytes(os.urandom(4096))
    proc = _serve(data, free_port())
    _, err = proc.communicate(timeout=240)
    assert proc.returncode == 2
    assert err.startswith("gonio: error: ") and err.count("\n") == 1, err
    assert "not a readable records database" in err
