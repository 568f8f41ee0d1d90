"""Stopping a ``gonio bench serve`` process a test started: SIGINT (its clean stop), waited
for 30 s; a server that has not stopped by then is killed, never left running, and the test
errs (a SIGINT lost under load is a fault to see, not to hide)."""

from __future__ import annotations

import signal
import subprocess


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
