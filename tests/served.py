"""A ``gonio bench serve`` process a test started: starting it so that it ends with the test
process however that ends (:func:`start_served`), waiting for its ``held: N`` line
(``--fault hold:N``, :func:`wait_held`), and stopping it (:func:`stop_served`): SIGINT (its
clean stop), waited for 30 s; a server that has not stopped by then is killed, never left
running, and the test errs (a SIGINT lost under load is a fault to see, not to hide)."""

from __future__ import annotations

import os
import queue
import signal
import subprocess
import sys
import threading
from pathlib import Path

from gonio.instruments.child import dies_with_parent

ROOT = Path(__file__).resolve().parents[1]


def start_served(*args: str, **kw) -> subprocess.Popen:
    """``python -m gonio bench serve ARGS`` with this tree first on the path (text stdout by
    default), sent SIGTERM by the kernel should the test process end first (a killed run)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    kw.setdefault("stdout", subprocess.PIPE)
    kw.setdefault("text", True)
    return subprocess.Popen([sys.executable, "-m", "gonio", "bench", "serve", *args], env=env,
                            preexec_fn=kw.pop("preexec_fn", None) or dies_with_parent(), **kw)


def wait_held(srv: subprocess.Popen, proc: subprocess.Popen, n: int) -> None:
    """Wait for the served bench ``srv`` (text stdout) to say ``held: n``; fail, without
    waiting on, where the acquisition ``proc`` ends first."""
    lines: queue.Queue = queue.Queue()
    threading.Thread(target=lambda: lines.put(srv.stdout.readline().strip()),
                     daemon=True).start()
    while True:
        try:
            line = lines.get(timeout=0.1)
            break
        except queue.Empty:
            if proc.poll() is not None:
                raise AssertionError(f"the acquisition ended ({proc.returncode}) before the "
                                     f"bench held: {proc.stderr.read()!r}") from None
    assert line == f"held: {n}", line


def stop_served(proc: subprocess.Popen, timeout_s: float = 30.0) -> None:
    """Stop ``proc`` by SIGINT; kill it and re-raise ``subprocess.TimeoutExpired`` where it
    has not exited within ``timeout_s``."""
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout=timeout_s)
        raise
