"""``gonio bench serve`` stops on SIGINT or SIGTERM at any point: while Python starts and gonio
imports, once serving, during an acquisition, during a long integration step, and where it
was started with SIGINT ignored (a non-interactive shell's ``gonio bench serve &``: the
cause of servers seen running on after their SIGINT). Exit 130 (SIGINT) or 143 (SIGTERM);
a signal that arrives before Python has installed its handlers ends the process by the
signal itself (returncode −2 / −15, the shell's 130 / 143); a SIGINT while Python imports
its ``site`` module is fatal to Python itself (exit 1, "init_import_site").

The start-up points are wall-clock delays after the start, so where each lands depends on
the machine; what is asserted holds wherever it lands. Every server started here is waited
for; one that has not ended within :data:`PROMPT_S` is killed and the test fails.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gonio.instruments.child import dies_with_parent
from gonio.specs.ogam_draft.readings import read_readings
from tests.served import start_served

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "data" / "small-protocol.toml"
#: Wall seconds a stopped server may take to end (its own stop takes about 1 s on a loaded
#: 2-core machine: the servers' loops, Python's exit).
PROMPT_S = 15.0
ENV = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}


def _serve(*extra: str, sigint=signal.SIG_DFL, speed: str = "200"):
    """``python -m gonio bench serve`` started with SIGINT's disposition ``sigint`` (SIG_DFL:
    Python installs its own handler as it starts; SIG_IGN: a shell's background job), set
    in the child before it runs Python, whatever this test process inherited."""
    ends_with_us = dies_with_parent()

    def preexec():
        ends_with_us()
        signal.signal(signal.SIGINT, sigint)
    return start_served("--bench", "rlg", "--table-port", "0", "--gyro-port", "0", "--speed",
                        speed, *extra, stderr=subprocess.PIPE, preexec_fn=preexec)


def _rows(path: Path) -> int:
    """Readings written so far (the file is written as they come)."""
    if not path.exists():
        return 0
    return max(sum(1 for ln in path.read_text(encoding="utf-8").splitlines()
                   if ln and not ln.startswith("#")) - 1, 0)


def _resources(proc) -> dict:
    return dict(proc.stdout.readline().strip().split(": ", 1) for _ in range(2))


def _stopped_by(proc, sig) -> tuple[int, float, str]:
    """Send ``sig``; the exit code, the seconds it took to end and its stderr. A process not
    ended within :data:`PROMPT_S` is killed, never left running, and the test fails."""
    t0 = time.monotonic()
    proc.send_signal(sig)
    try:
        _, err = proc.communicate(timeout=PROMPT_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        pytest.fail(f"gonio bench serve still running {PROMPT_S} s after signal {sig}")
    return proc.returncode, time.monotonic() - t0, err


def _ended_by(rc: int, err: str, sig) -> None:
    """The exit of a process stopped by ``sig`` while it started: gonio's (130 / 143, one
    line), the signal's own (before Python's handlers), or Python's own while it imports
    ``site`` (a KeyboardInterrupt there is fatal to Python: exit 1, its traceback)."""
    if rc == 1 and "init_import_site" in err:
        return
    assert rc in ({signal.SIGINT: 130, signal.SIGTERM: 143}[sig], -sig), (rc, err)
    assert "Traceback" not in err, err


@pytest.mark.parametrize("delay_s", [0.0, 0.1, 0.4, 1.0])
def test_sigint_while_starting_stops_it(delay_s):
    proc = _serve()
    time.sleep(delay_s)
    rc, took, err = _stopped_by(proc, signal.SIGINT)
    _ended_by(rc, err, signal.SIGINT)


def test_sigterm_while_starting_stops_it():
    proc = _serve()
    time.sleep(0.4)
    rc, took, err = _stopped_by(proc, signal.SIGTERM)
    _ended_by(rc, err, signal.SIGTERM)


@pytest.mark.parametrize("sigint", [signal.SIG_DFL, signal.SIG_IGN], ids=["default", "ignored"])
def test_sigint_once_serving_stops_it_even_when_started_ignoring_it(sigint):
    """Started with SIGINT ignored (as ``cmd &`` in a script starts it), the served bench
    still takes SIGINT: without that it served on, a test's stop waited it out."""
    proc = _serve(sigint=sigint)
    res = _resources(proc)
    assert res["table"].startswith("TCPIP0::127.0.0.1::")
    rc, took, err = _stopped_by(proc, signal.SIGINT)
    assert rc == 130, (rc, err)
    assert err.strip().splitlines()[-1] == "gonio: interrupted"


def test_sigint_mid_acquisition_stops_it(tmp_path):
    """SIGINT to the server while ``gonio acquire`` runs against it. At --speed 20 the small
    programme (1 200 s of bench time) cannot end in less than a minute of wall time,
    whatever the load: the acquisition is mid-programme when the server is stopped."""
    proc = _serve(speed="20")
    acq = None
    try:
        res = _resources(proc)
        out = tmp_path / "acq"
        acq = subprocess.Popen([sys.executable, "-m", "gonio", "acquire", "--protocol",
                                str(SMALL), "--table", res["table"], "--gyro", res["gyro"],
                                "--out", str(out), "--meta", "latitude_deg=40.2"],
                               env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        deadline = time.monotonic() + 300
        while _rows(out / "readings.csv") < 2:
            assert acq.poll() is None and time.monotonic() < deadline, acq.stderr.read()
            time.sleep(0.1)
        rc, took, err = _stopped_by(proc, signal.SIGINT)
        assert rc == 130, (rc, err)
        # the acquisition sees its links lost, stops and keeps its readings
        _, aerr = acq.communicate(timeout=60)
        assert acq.returncode == 2, aerr
        assert read_readings(out / "readings.csv").metadata["acquisition"] == "incomplete"
    finally:
        for p in (acq, proc):
            if p is not None and p.poll() is None:
                p.kill()
                p.wait()


def test_sigint_during_a_long_integration_stops_it():
    """At --speed 100000 the bench cannot keep up (about 10⁸ samples to integrate per
    second of wall time): the background integration never rests and a ``ZERO`` integrates
    for as long as it is let, holding the bench's lock. SIGINT still ends it."""
    proc = _serve(speed="100000")
    try:
        port = int(_resources(proc)["gyro"].split("::")[2])
        with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
            s.sendall(b"ZERO\n")
            time.sleep(1.0)
            rc, took, err = _stopped_by(proc, signal.SIGINT)
        assert rc == 130, (rc, err)
        assert "Traceback" not in err, err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def _ended(pid: int) -> bool:
    """Whether process ``pid`` has ended (gone, or a zombie its new parent has not reaped)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return True
    return stat.rsplit(")", 1)[1].split()[0] in ("Z", "X")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
def test_a_served_bench_ends_with_the_process_that_started_it():
    """The starter (a script, a test run) killed with SIGKILL — no clean-up of its own runs —
    still takes its ``gonio bench serve`` with it (:func:`gonio.instruments.child.
    dies_with_parent`, used by tests/served.py and benchmarks/acquire_resume_draft.py). The
    starter has read both resource lines first: the server writes nothing more, so no broken
    pipe ends it instead."""
    starter = subprocess.Popen(
        [sys.executable, "-c",
         "import sys, time; from tests.served import start_served; "
         "p = start_served('--bench', 'rlg', '--table-port', '0', '--gyro-port', '0'); "
         "p.stdout.readline(); p.stdout.readline(); print(p.pid, flush=True); time.sleep(600)"],
        cwd=ROOT, env=ENV, stdout=subprocess.PIPE, text=True)
    served = None
    try:
        served = int(starter.stdout.readline())
        assert not _ended(served)
        starter.kill()
        starter.wait()
        deadline = time.monotonic() + PROMPT_S
        while not _ended(served):
            assert time.monotonic() < deadline, f"gonio bench serve {served} outlived its starter"
            time.sleep(0.1)
    finally:
        if starter.poll() is None:
            starter.kill()
            starter.wait()
        if served is not None and not _ended(served):       # never left running
            os.kill(served, signal.SIGKILL)
