"""The instrument layer against the virtual bench served as instruments, through pyvisa-py.

Every path runs on real sockets (127.0.0.1) with PyVISA's ``@py`` backend; nothing of VISA
is mocked. The whole small draft programme taken with ``acquire`` must calibrate to the same
items as ``gonio simulate`` on the same bench and seed, within their U; an interrupted
acquisition keeps its readings and completes with ``--resume``; a lost link, an instrument
error and a move beyond the range stop the table (or never move it).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from gonio.specs.ogam_draft.bench import load_bench
from gonio.errors import GonioError
from gonio.formats.counters import wrap_counter
from gonio.specs.ogam_draft.readings import read_readings
from gonio.specs.ogam_draft.acquisition_module import AcquisitionModule, unwrap_near
from gonio.instruments.link import InstrumentError, IOLog, Link, LinkLost
from gonio.instruments.scpi import Faults, scpi_match
from gonio.instruments.table import RotaryTable
from gonio.specs.ogam_draft.protocol import load_protocol
from gonio.specs.ogam_draft.acquisition import (Block, Step, acquire, plan_programme,
                                                read_previous, resume_plan)
from gonio.specs.ogam_draft.served import ServedBench, gyro_instrument, serve_bench, table_instrument
from gonio.units import deg_to_arcsec
from tests.served import start_served

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "data" / "small-protocol.toml"
SEED = 3
SPEED = 200.0          # simulated seconds per real second: the small programme in ~6 s
META = {"latitude_deg": "40.2"}


@pytest.fixture(scope="module")
def rlg():
    return load_bench("rlg")


@pytest.fixture()
def served(rlg):
    s = serve_bench(rlg, speed=SPEED, seed=SEED)
    yield s
    s.close()


@pytest.fixture(scope="module")
def simulated(tmp_path_factory, simulate_calibrate):
    """``gonio simulate`` + ``gonio calibrate`` of the small programme on the same bench
    (tests/conftest.py)."""
    return simulate_calibrate(tmp_path_factory.mktemp("sim"), SMALL, "rlg", SEED)


@pytest.fixture()
def calibrate(calibrate_readings):
    """``gonio calibrate`` of a readings file with :data:`SMALL` (tests/conftest.py)."""
    return lambda readings, out: calibrate_readings(readings, SMALL, out)


#: E_n limit of the acquired-against-simulated comparison: |Δ| ≤ E_N_LIMIT·√(U_a² + U_b²).
#: E_n ≤ 1 (ISO 13528) fails about 5 % of the time per item for two correct results with
#: k ≈ 2, so over seven items a correct acquisition would fail a run in several; 1.5 (about
#: 3σ of the difference, 0.3 % per item) keeps the check of agreement without that.
E_N_LIMIT = 1.5


def _agree_within_u(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for key in a:
        va, vb = a[key]["value"], b[key]["value"]
        ua, ub = a[key]["uncertainty"]["U"], b[key]["uncertainty"]["U"]
        assert va is not None and vb is not None, key
        assert abs(va - vb) <= E_N_LIMIT * np.hypot(ua, ub), (key, va, vb, ua, ub)


def _drivers(s, log=None):
    log = log or IOLog()
    return (RotaryTable(Link(s.table_resource, name="table", log=log)),
            AcquisitionModule(Link(s.gyro_resource, name="gyro", log=log)), log)


def _keys(path: Path) -> list:
    df = read_readings(path).data
    return sorted(zip(df["test"], df["series"], df["round"], df["rate_dps"].fillna(0.0),
                      df["orientation"]))


# ------------------------------------------------------------------ command sets
def test_served_instruments_speak_exactly_the_drivers_command_sets(rlg):
    """Every driver command is a served mnemonic, and every served mnemonic is one the
    drivers send: neither side has a command the other lacks."""
    sb = ServedBench(rlg, speed=1.0)
    for driver, inst in ((RotaryTable, table_instrument(sb)), (AcquisitionModule, gyro_instrument(sb))):
        sent = [tpl.split(" ")[0] for tpl in driver.COMMANDS.values() if tpl]
        sent.append(driver.ERROR_QUERY)
        served = [m for m, _ in inst.commands]
        assert [h for h in sent if not any(scpi_match(h, m) for m in served)] == []
        assert [m for m in served if not any(scpi_match(h, m) for h in sent)] == []
    assert scpi_match("SYSTEM:ERROR?", "SYSTem:ERRor?") and not scpi_match("SY:ERR?", "SYSTem:ERRor?")


def test_unwrap_near_undoes_any_number_of_roll_overs():
    """A count wrapped by gonio.formats.counters comes back from the expected count, for
    signed and unsigned 24- and 32-bit registers and several roll-overs."""
    rng = np.random.default_rng(1)
    for bits in (24, 32):
        for signed in (True, False):
            counts = rng.integers(-5 * 2**bits, 5 * 2**bits, 200)
            shown = wrap_counter(counts, bits, signed)
            noise = rng.uniform(-0.4, 0.4, 200) * 2**(bits - 1)
            back = [unwrap_near(int(s), float(c + e), bits) for s, c, e in zip(shown, counts, noise)]
            assert back == counts.tolist()


def test_stop_mid_move_keeps_the_motion_so_far(rlg):
    """A stop cuts the move to its stopping distance at the table's acceleration; the angles
    already passed are unchanged (the trapezoid so far is the same)."""
    now = [0.0]
    sb = ServedBench(rlg, speed=1.0, clock=lambda: now[0])
    sb.move(300.0, 60.0)
    now[0] = 3.0                                  # cruising at 60 °/s since t = 1 s
    past = np.linspace(0.0, 3.0, 31)
    before = sb.timeline.angle_deg(past)
    theta = float(sb.timeline.angle_deg(np.array([3.0]))[0])
    v = float(sb.timeline.rate_dps(np.array([3.0]))[0])
    assert v == pytest.approx(60.0, rel=1e-4)
    sb.stop()
    assert np.array_equal(sb.timeline.angle_deg(past), before)
    a = rlg.table.accel_dps2
    assert sb.timeline.end_angle_deg == pytest.approx(theta + v * v / (2 * a), abs=1e-9)
    assert sb.timeline.end_s == pytest.approx(3.0 + v / a, abs=1e-9)


def test_run_length_integration_equals_per_sample_integration(rlg):
    """The served instrument integrates rests as runs (Integrator.rates' form); a per-sample
    pass of the bench's Integrator over the same motion gives the same angle."""
    bench = rlg.random_off()
    now = [0.0]
    a = ServedBench(bench, clock=lambda: now[0])
    for i in range(4):
        now[0] += 1.0
        a.do_zero()
        a.move(30.0 * (i + 1), 60.0)
        now[0] += 15.0
        a.read()
        a.move(0.0, 60.0)
        now[0] += 10.0
    k = a._advance(now[0])
    b = ServedBench(bench, clock=lambda: 0.0)
    ts = np.arange(k + 1) * a.dt
    phi = b.integ.advance(ts, a.timeline.angle_deg(ts), a.timeline.rate_dps(ts), a.geom)
    assert a.phi_deg == pytest.approx(float(phi[-1]), abs=1e-12)


# ------------------------------------------------------------------ drivers on sockets
def test_driver_errors_come_from_the_served_error_queue(served):
    table, gyro, log = _drivers(served)
    assert table.identify().startswith("gonio,virtual rotary table")
    with pytest.raises(InstrumentError, match="-221.*read before zeroing"):
        gyro.read()
    with pytest.raises(InstrumentError, match="-222"):          # sent raw: the table refuses
        table.send("move", angle_deg=400.0, rate_dps=60.0)
    assert served.bench.faults.moves == 1
    with pytest.raises(GonioError, match="outside the table's range"):   # checked: never sent
        table.move(400.0, 60.0)
    assert served.bench.faults.moves == 1
    assert not any("MOVE:ABS 400" in ln for ln in log.lines[-4:])
    gyro.zero()
    table.move(90.0, 60.0)
    while table.state() != "idle":
        time.sleep(0.002)
    r = gyro.read(90.0 * 76434.87)
    assert r.counts / 76434.87 == pytest.approx(90.0, abs=2.0)  # plus the Earth rate since zero
    assert table.position_deg() == 90.0


# ------------------------------------------------------------------ what --meta may add
@pytest.mark.parametrize("given, said", [
    ({"serial": "RLG-0999"}, "key serial: the instruments state 'RLG-0001', given 'RLG-0999'"),
    ({"manufacturer": "ACME"}, "key manufacturer: the instruments state 'gonio virtual bench'"),
    ({"gyro_idn": "ACME,G1,RLG-0001,2"}, "key gyro_idn: the instruments state 'gonio virtual "
                                         "bench,RLG goniometer (virtual)"),
    ({"chamber_idn": "ACME,CH"}, "key chamber_idn: no instrument answered as it"),
    ({"date": "1999-01-01"}, "key date: the instruments state '20"),
])
def test_given_metadata_never_replaces_what_the_instruments_report(served, tmp_path, given,
                                                                  said):
    """A laboratory's ``--meta`` adds lines; the serial, maker or ``*IDN?`` answer the
    instruments gave stay theirs (the virtual bench's identification keeps its readings
    virtual, and a certificate names the instrument that answered)."""
    with pytest.raises(GonioError, match=re.escape(said)):
        acquire(load_protocol(SMALL), served.table_resource, served.gyro_resource,
                tmp_path / "acq", metadata={**META, **given})
    assert not (tmp_path / "acq" / "readings.csv").exists()


# ------------------------------------------------------------------ whole programme
def test_small_programme_calibrates_like_simulate(served, simulated, calibrate, tmp_path):
    sim_readings, sim_items = simulated
    res = acquire(load_protocol(SMALL), served.table_resource, served.gyro_resource,
                  tmp_path / "acq", metadata=META)
    assert res.complete and res.taken == res.total == 27
    r = read_readings(res.readings)
    assert r.metadata["acquisition"] == "complete"
    assert r.metadata["instrument"] == "RLG goniometer (virtual)"
    assert _keys(res.readings) == _keys(sim_readings)
    # Row by row, the angle indicated agrees with the table's to within arc seconds (the
    # instrument's errors), as the simulated file's does.
    for data in (r.data, read_readings(sim_readings).data):
        rot = data[data["test"] != "zero_stability"]
        dev = deg_to_arcsec(rot["gyro_counts"] / 76434.87 - rot["table_deg"])
        assert float(np.abs(dev).max()) < 2.0      # tilt, scale-factor error, harmonics, noise
    _agree_within_u(calibrate(res.readings, tmp_path / "cal"), sim_items)
    log = res.io_log.read_text(encoding="utf-8")
    assert "table > *IDN?" in log and "gyro < gonio virtual bench,RLG goniometer" in log
    assert log.rstrip().splitlines()[-1].endswith("table > STOP")


class HandSetTable(RotaryTable):
    """A controller without an axis fixture: an operator points the axis."""

    COMMANDS = {**RotaryTable.COMMANDS, "set_axis": None, "axis": None}


class HostTimedModule(AcquisitionModule):
    """A module without an external trigger: read when the host's wait ends."""

    COMMANDS = {**AcquisitionModule.COMMANDS, "arm": None, "fetch": None, "trigger_delay": None}


def test_operator_prompt_and_host_timed_reads(served, tmp_path):
    """A table that cannot set its axis asks the operator (once per change of orientation);
    a module without an external trigger is read on the host's wait; both complete."""
    asked = []
    res = acquire(load_protocol(SMALL), served.table_resource, served.gyro_resource,
                  tmp_path / "acq", metadata=META, table_cls=HandSetTable,
                  gyro_cls=HostTimedModule, prompt=asked.append)
    assert res.complete and res.taken == 27
    assert asked == ["Set the table axis to UP and press Enter: ",
                     "Set the table axis to NORTH and press Enter: "]
    log = res.io_log.read_text(encoding="utf-8")
    assert "AXIS" not in log and "INIT" not in log and "READ?" in log


# ------------------------------------------------------------------ safety
#: Readings the bench answers before its clock stops (``hold:N``) in the interruption tests:
#: 34 readings in all on the small programme (27 rows, 7 static phases); the 17th is the
#: 13th row, the 6th the 5th (fewer where a late reading was taken again).
HOLD_SIGINT, HOLD_SIGTERM = 17, 6


def _interrupted_acquire(rlg, out: Path, hold_at: int, sig):
    """``gonio acquire`` of the small programme in a subprocess, on a served bench whose clock
    stops once its ``hold_at``-th reading is answered (``hold:N``: the acquisition cannot go on,
    let alone finish, before the signal, whatever the machine's load), sent ``sig`` once the
    bench is held; its exit code and stderr, and the bench (serving on: ``close`` it). The
    resume's new connection lets the clock run on."""
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    s = serve_bench(rlg, speed=SPEED, seed=SEED, faults=Faults.parse([f"hold:{hold_at}"]))
    cmd = [sys.executable, "-m", "gonio", "acquire", "--protocol", str(SMALL), "--table",
           s.table_resource, "--gyro", s.gyro_resource, "--out", str(out),
           "--meta", "latitude_deg=40.2"]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        while not s.bench.faults.held.wait(0.1):
            if proc.poll() is not None:         # ended before the hold: a fault of the run
                s.close()
                raise AssertionError(f"acquire ended ({proc.returncode}) before reading "
                                     f"{hold_at}: {proc.stderr.read()!r}")
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
        proc.wait()
    return proc.returncode, err, s


def test_sigint_keeps_the_readings_and_resume_completes(rlg, simulated, calibrate, tmp_path):
    out = tmp_path / "acq"
    rc, err, served = _interrupted_acquire(rlg, out, HOLD_SIGINT, signal.SIGINT)
    try:
        assert rc == 130, err
        assert b"continue with --resume" in err
        kept = read_readings(out / "readings.csv")
        assert kept.metadata["acquisition"] == "incomplete"
        assert "SIGINT" in kept.metadata["acquisition_stopped"]
        n_kept = len(kept.data)
        assert 10 <= n_kept < 27
        log = (out / "io.log").read_text(encoding="utf-8").splitlines()
        assert log[-1].endswith("table > STOP")
        assert served.bench.state() == "IDLE"
        res = acquire(load_protocol(SMALL), served.table_resource, served.gyro_resource, out,
                      resume=True, metadata=META)
    finally:
        served.close()
    assert res.complete and res.taken <= 27 - n_kept + 4     # at most 7.3's block again
    assert _keys(out / "readings.csv") == _keys(simulated[0])   # every reading once
    _agree_within_u(calibrate(out / "readings.csv", tmp_path / "cal"), simulated[1])


def test_sigterm_stops_the_table_and_keeps_the_readings(rlg, tmp_path):
    out = tmp_path / "acq"
    rc, err, served = _interrupted_acquire(rlg, out, HOLD_SIGTERM, signal.SIGTERM)
    served.close()
    assert rc == 143, err
    kept = read_readings(out / "readings.csv")
    assert kept.metadata["acquisition"] == "incomplete" and 3 <= len(kept.data) < 27
    assert "SIGTERM" in kept.metadata["acquisition_stopped"]
    log = (out / "io.log").read_text(encoding="utf-8").splitlines()
    assert log[-1].endswith("table > STOP")


def _failing_run(rlg, tmp_path, faults: str):
    s = serve_bench(rlg, speed=SPEED, seed=SEED, faults=Faults.parse([faults]))
    try:
        with pytest.raises(GonioError) as info:
            acquire(load_protocol(SMALL), s.table_resource, s.gyro_resource, tmp_path / "acq",
                    metadata=META, timeout_s=3.0)      # a dropped socket shows as a timeout
        # the table was stopped: at rest now, and STOP was the last thing it was sent
        deadline = time.monotonic() + 5.0
        while s.bench.state() != "IDLE" and time.monotonic() < deadline:
            time.sleep(0.01)
        assert s.bench.state() == "IDLE"
    finally:
        s.close()
    log = (tmp_path / "acq" / "io.log").read_text(encoding="utf-8").splitlines()
    assert [ln for ln in log if " table > " in ln][-1].endswith("table > STOP")
    kept = read_readings(tmp_path / "acq" / "readings.csv")
    assert kept.metadata["acquisition"] == "incomplete"
    return info.value, kept


def test_lost_connection_stops_the_table_and_keeps_the_readings(rlg, tmp_path):
    err, kept = _failing_run(rlg, tmp_path, "gyro-drop:12")
    assert isinstance(err, LinkLost) and "gyro" in str(err)
    assert 4 <= len(kept.data) < 12
    assert "connection lost" in kept.metadata["acquisition_stopped"]


def test_instrument_error_stops_the_table_and_keeps_the_readings(rlg, tmp_path):
    err, kept = _failing_run(rlg, tmp_path, "table-error:9")
    assert isinstance(err, InstrumentError) and "-310" in str(err) and "axis fault" in str(err)
    assert len(kept.data) >= 4
    assert "axis fault" in kept.metadata["acquisition_stopped"]


def test_move_beyond_the_range_is_refused_before_anything_moves(rlg, tmp_path):
    s = serve_bench(rlg, speed=SPEED, seed=SEED, range_deg=200.0)
    try:
        with pytest.raises(GonioError, match=r"scale_factor series 1 round 2: a move to 240° is "
                                             r"outside the table's range \[-200°, 200°\]"):
            acquire(load_protocol(SMALL), s.table_resource, s.gyro_resource, tmp_path / "acq")
        assert s.bench.faults.moves == 0
    finally:
        s.close()
    log = (tmp_path / "acq" / "io.log").read_text(encoding="utf-8")
    assert "MOVE" not in log and "LIM:POS?" in log


# ------------------------------------------------------------------ resume and the CLI
def test_resume_keeps_complete_rounds_and_retakes_shared_zeroings(tmp_path):
    rest = Block("zero_stability", "up", [Step("zero_stability", 1, n, None, "up")
                                          for n in (1, 2, 3)], at_rest=True, rezero=False)
    rot = Block("angle_deviation", "up", [Step("angle_deviation", 1, n, 60.0, "up", 0.0, 90.0 * n)
                                          for n in (1, 2, 3)])
    rows = ["zero_stability,1,1,,up,0.0,,0,\n", "zero_stability,1,2,,up,20.0,,1,\n",
            "angle_deviation,1,1,60.0,up,12.0,90.0,6879138,\n"]
    keys = {("zero_stability", 1, 1, None, "up"), ("zero_stability", 1, 2, None, "up"),
            ("angle_deviation", 1, 1, 60.0, "up")}
    kept, done = resume_plan([rest, rot], rows, keys)
    assert kept == rows[2:] and done == {("angle_deviation", 1, 1, 60.0, "up")}
    f = tmp_path / "readings.csv"
    f.write_text("# acquisition: incomplete\n# protocol: small\ntest,series,round,rate_dps,"
                 "orientation,time_s,table_deg,gyro_counts,gyro_deg\n" + "".join(rows)
                 + "angle_deviation,1,2,60.0,up,1", encoding="utf-8")     # a row cut short
    assert read_previous(f, load_protocol(SMALL)) == (rows, keys)
    with pytest.raises(GonioError, match="protocol 'small', not"):
        read_previous(f, load_protocol(ROOT / "tests" / "data" / "full.toml"))
    # 7.3, 7.1, 7.4 × 3 series, 7.6 at 30 °/s, 7.7 north (60 °/s and up reuse 7.4)
    assert len(plan_programme(load_protocol(SMALL))) == 1 + 1 + 3 + 1 + 1


def test_bench_serve_command_serves_on_loopback(tmp_path):
    proc = start_served("--bench", "fog", "--table-port", "0", "--gyro-port", "0", "--speed", "50",
                        stderr=subprocess.PIPE)
    try:
        lines = [proc.stdout.readline().strip() for _ in range(2)]
        assert lines[0].startswith("table: TCPIP0::127.0.0.1::") and lines[0].endswith("::SOCKET")
        gyro = AcquisitionModule(Link(lines[1].split(" ", 1)[1], name="gyro"))
        assert gyro.identify().split(",")[1] == "FOG goniometer (virtual)"
        assert gyro.counter_bits() == 32
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=20) == 143
    finally:
        proc.kill()
