"""The optical draft's whole programme taken through the instruments, interrupted and resumed.

``gonio bench serve --bench rlg`` and ``gonio acquire --protocol ogam-draft`` run as
processes; the served bench holds its clock once it has answered ``--stop-after`` readings
(``--fault hold:N``: the acquisition cannot go on, let alone finish, before it is
interrupted, whatever the machine's load), ``gonio acquire`` is then sent SIGINT and
continued with ``--resume`` (whose connection lets the bench's clock run on); the readings
calibrate (``gonio calibrate``) to items that are compared with an uninterrupted
``gonio simulate`` of the same bench and seed, each within the two results' U (root sum of
squares), and the in-situ tilt estimates of the two files within theirs. Prints the timings
and the tables.

    python benchmarks/acquire_resume_draft.py [--speed 200] [--seed 1] [--stop-after 140]
        [--protocol FILE]

``--protocol`` (default ``protocols/ogam-draft.toml``) takes another protocol of the draft
through the same path (tests/test_instruments_whole_draft.py: the draft with shorter rests).

``--stop-after`` counts the readings the module answers, the static phases' among them (the
rows kept are fewer: 140 answered readings are 129 rows where none was taken again). The draft's programme (with
the built-in tilt estimate's rests) is about 8.5 h of bench time: at ``--speed 200`` some
2–3 min per pass on a loaded 2-core machine, at ``--speed 1000`` about 15 s. The speed is
bounded by the host's latency: a reply that takes 30 ms of real time is 30 s of bench time at
``--speed 1000``, the whole of Annex A.1's 0.5 min. tests/test_instruments_whole_draft.py
runs this script at ``--speed 250`` (with ``--protocol``); tests/test_instruments.py runs the same path on the
small programme.

Every ``gonio`` process it starts dies with it: each is asked (Linux ``prctl``
``PR_SET_PDEATHSIG``, :func:`gonio.instruments.child.dies_with_parent`) to be sent SIGTERM
when this script ends, however it ends (a test's timeout kills it with SIGKILL), and on an
ordinary exit, SIGINT or SIGTERM the script stops them itself (SIGINT, then SIGKILL after
30 s).
"""

from __future__ import annotations

import argparse
import atexit
import json
import math
import os
import select
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from gonio.instruments.child import dies_with_parent  # noqa: E402

PROTOCOL = ROOT / "protocols" / "ogam-draft.toml"
#: the gonio processes started and not yet waited for
CHILDREN: list[subprocess.Popen] = []


def stop(p: subprocess.Popen, timeout_s: float = 30.0) -> None:
    """SIGINT (a gonio command's clean stop), then SIGKILL after ``timeout_s``."""
    if p.poll() is None:
        p.send_signal(signal.SIGINT)
        try:
            p.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
    if p in CHILDREN:
        CHILDREN.remove(p)


def _stop_children() -> None:
    for p in list(CHILDREN):
        stop(p)


def _terminated(signum, frame):
    raise SystemExit(128 + signum)       # the finally blocks and atexit run


def gonio(*args: str, **kw) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    p = subprocess.Popen([sys.executable, "-m", "gonio", *args], env=env,
                         preexec_fn=dies_with_parent(), **kw)    # no thread here: safe
    CHILDREN.append(p)
    return p


def run(*args: str) -> None:
    p = gonio(*args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    _, err = p.communicate()
    CHILDREN.remove(p)
    if p.returncode:
        sys.exit(f"gonio {' '.join(args[:1])} failed ({p.returncode}): {err.strip()}")


class Lines:
    """Lines of a child's unbuffered binary stdout, read without a thread (``select``)."""

    def __init__(self, stream):
        self.fd, self.buf = stream.fileno(), b""

    def next(self, wait_s: float) -> str | None:
        """The next line, or None when none came within ``wait_s`` (or the stream ended)."""
        end = time.monotonic() + wait_s
        while b"\n" not in self.buf:
            left = end - time.monotonic()
            if left <= 0 or not select.select([self.fd], [], [], left)[0]:
                return None
            chunk = os.read(self.fd, 4096)
            if not chunk:
                return None
            self.buf += chunk
        line, self.buf = self.buf.split(b"\n", 1)
        return line.decode().strip()


def rows(path: Path) -> int:
    if not path.exists():
        return 0
    lines = [ln for ln in path.read_text(encoding="utf-8").splitlines()
             if ln and not ln.startswith("#")]
    return max(len(lines) - 1, 0)


def items(folder: Path) -> dict:
    return json.loads((folder / "results.json").read_text(encoding="utf-8"))["items"]


def tilt_lines(d: Path) -> int:
    """Print the in-situ tilt estimate of both files (ψ, α with U95 = k95·u, ν = N − 3) and
    how K was stated; 1 when the two ψ or α differ by more than k95·√(u_a² + u_s²) or a
    calibration did not correct K by the measured tilt, else 0."""
    from gonio.specs.ogam_draft.readings import read_readings
    from gonio.specs.ogam_draft.tilt_estimate import tilt_estimate_from_readings

    est = {n: tilt_estimate_from_readings(read_readings(d / n / "readings.csv"))
           for n in ("acq", "sim")}
    for n, e in est.items():
        stated = items(d / f"cal-{n}")["scale_factor"]["details"].get("stated")
        print(f"tilt estimate ({n}): psi {e.tilt_deg:.4f} deg (U95 {e.k95 * e.u_tilt_deg:.4f}), "
              f"azimuth {e.tilt_azimuth_table_deg:.1f} deg (U95 {e.k95 * e.u_phase_deg:.1f}), "
              f"{e.n_positions} rests; K stated {stated}")
    a, s = est["acq"], est["sim"]
    k = max(a.k95, s.k95)
    d_az = (a.tilt_azimuth_table_deg - s.tilt_azimuth_table_deg + 180.0) % 360.0 - 180.0
    ok = (abs(a.tilt_deg - s.tilt_deg) <= k * math.hypot(a.u_tilt_deg, s.u_tilt_deg)
          and abs(d_az) <= k * math.hypot(a.u_phase_deg, s.u_phase_deg)
          and all(items(d / f"cal-{n}")["scale_factor"]["details"].get("stated")
                  == "tilt_corrected" for n in est))
    print(f"tilt estimates {'agree within U' if ok else 'DISAGREE'}")
    return 0 if ok else 1


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speed", type=float, default=200.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--stop-after", type=int, default=140)
    ap.add_argument("--latitude", default="40.2")
    ap.add_argument("--protocol", type=Path, default=PROTOCOL,
                    help="the protocol acquired, simulated and calibrated (default: the draft)")
    ap.add_argument("--dir", type=Path, default=None,
                    help="folder for the files (default: a new temporary folder)")
    a = ap.parse_args()
    d = a.dir if a.dir is not None else Path(tempfile.mkdtemp(prefix="acq-draft-"))
    atexit.register(_stop_children)
    signal.signal(signal.SIGTERM, _terminated)
    srv = gonio("bench", "serve", "--bench", "rlg", "--table-port", "0", "--gyro-port", "0",
                "--speed", str(a.speed), "--seed", str(a.seed), "--fault", f"hold:{a.stop_after}",
                stdout=subprocess.PIPE, bufsize=0)
    out = Lines(srv.stdout)
    try:
        said = [out.next(120.0) for _ in range(2)]
        if None in said:
            sys.exit(f"gonio bench serve did not start: {said}")
        res = dict(ln.split(": ", 1) for ln in said)
        args = ["acquire", "--protocol", str(a.protocol), "--table", res["table"], "--gyro",
                res["gyro"], "--out", str(d / "acq"), "--meta", f"latitude_deg={a.latitude}"]
        t0 = time.monotonic()
        p = gonio(*args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        held = None
        while held is None and p.poll() is None:
            held = out.next(0.2)
        if held != f"held: {a.stop_after}":
            print(f"the bench did not hold at reading {a.stop_after} (it said {held!r}; "
                  f"acquire exit {p.poll()})")
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=60)
        CHILDREN.remove(p)
        t1 = time.monotonic()
        head = (d / "acq" / "readings.csv").read_text(encoding="utf-8").splitlines()[0]
        kept = rows(d / "acq" / "readings.csv")
        print(f"first pass: exit {p.returncode} after {t1 - t0:.1f} s, {kept} readings kept, "
              f"header '{head}'")
        said = [ln for ln in err.splitlines() if "stopped" in ln]
        print(f"  it said: {said[-1] if said else err.strip()}")
        run(*args, "--resume")
        t2 = time.monotonic()
        print(f"resume: {t2 - t1:.1f} s, {rows(d / 'acq' / 'readings.csv')} readings in all, "
              f"header '{(d / 'acq' / 'readings.csv').read_text().splitlines()[0]}'")
    finally:
        stop(srv)
    run("simulate", "--protocol", str(a.protocol), "--bench", "rlg", "--seed", str(a.seed),
        "--out", str(d / "sim"))
    print(f"simulated: {rows(d / 'sim' / 'readings.csv')} readings")
    for name in ("acq", "sim"):
        run("calibrate", str(d / name / "readings.csv"), "--protocol", str(a.protocol), "--out",
            str(d / f"cal-{name}"))
    ia, isim = items(d / "cal-acq"), items(d / "cal-sim")
    bad = 0
    print(f"{'item':34s} {'acquired':>14s} {'simulated':>14s} {'|diff|':>10s} {'U (rss)':>10s}")
    for key in isim:
        va, vs = ia[key]["value"], isim[key]["value"]
        u = math.hypot(ia[key]["uncertainty"]["U"], isim[key]["uncertainty"]["U"])
        ok = va is not None and vs is not None and abs(va - vs) <= u
        bad += not ok
        print(f"{key:34s} {va:14.6g} {vs:14.6g} {abs(va - vs):10.3g} {u:10.3g} "
              f"{'ok' if ok else 'OUTSIDE U'}")
    print(f"{len(isim) - bad} of {len(isim)} items within U; files in {d}")
    bad += tilt_lines(d)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
