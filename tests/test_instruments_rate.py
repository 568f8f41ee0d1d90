"""A rate specification's programme on the served rate bench, through pyvisa-py.

JJF 1535-2015's whole programme (the coverage study's reduced sample counts, every item
still measured) is taken by ``gonio acquire`` from ``gonio bench serve``'s rate table, gyro
output reader, chamber and supply, on real sockets with PyVISA's ``@py`` backend; its
readings must calibrate to the same fifteen items as ``gonio simulate`` on the same bench
and seed, each within the two results' U. An interruption by SIGINT keeps the records and
``--resume`` completes the file.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from gonio.bench.rate_gyro import load_rate_bench
from gonio.cli import main
from gonio.errors import GonioError
from gonio.formats.rate_readings import read_rate_readings
from gonio.instruments.rate import Chamber, GyroOutput, RateTable, Supply
from gonio.instruments.rate_acquire import acquire_rate, resume_point
from gonio.instruments.link import InstrumentError, LinkLost
from gonio.instruments.scpi import Faults, scpi_match
from gonio.instruments.served_rate import ServedRateBench, rate_instruments, serve_rate_bench
from gonio.protocol.programme import Segment
from gonio.specs.jjf1535.acquisition import programme
from tests.served import start_served, stop_served, wait_held

ROOT = Path(__file__).resolve().parents[1]
SEED = 3
SPEED = 2000.0       # the reduced programme's 9.8 h in about 18 s
BENCH = "mems-adxrs610"


@pytest.fixture(scope="module")
def bench():
    return load_rate_bench(BENCH)


@pytest.fixture(scope="module")
def proto(tmp_path_factory):
    from tests.test_rate_bench import small_protocol
    return small_protocol(tmp_path_factory.mktemp("proto"))


def _meta(b) -> list[str]:
    """What a laboratory states with --meta: the gyro's datasheet bandwidth and supply, the
    site's latitude, its equipment's certificates (the bench file's values here)."""
    eq = b.equipment
    return [f"datasheet_bandwidth_hz={b.gyro.datasheet_bandwidth_hz!r}",
            f"latitude_deg={b.latitude_deg!r}", f"supply_nominal_v={b.gyro.supply_nominal_v!r}",
            f"rate_table_u_rel={eq.rate_table_u_rel!r}",
            f"rate_table_ripple_rel={eq.rate_table.ripple_rel!r}",
            f"acquisition_u_rel={eq.acquisition_u_rel!r}"]


def _calibrate(readings: Path, proto: Path, out: Path) -> dict:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(["calibrate", str(readings), "--protocol", str(proto), "--out", str(out)])
    assert rc == 0, err.getvalue()
    return json.loads((out / "results.json").read_text(encoding="utf-8"))["items"]


@pytest.fixture(scope="module")
def simulated(proto, tmp_path_factory):
    d = tmp_path_factory.mktemp("sim")
    assert main(["simulate", "--spec", "jjf1535-2015", "--protocol", str(proto), "--bench", BENCH,
                 "--seed", str(SEED), "--out", str(d / "sim")]) == 0
    return d / "sim" / "readings.csv", _calibrate(d / "sim" / "readings.csv", proto, d / "cal")


def _agree_within_u(a: dict, b: dict) -> None:
    assert a.keys() == b.keys() and len(a) == 15
    for key in a:
        va, vb = a[key]["value"], b[key]["value"]
        assert va is not None and vb is not None, key
        u = np.hypot(a[key]["uncertainty"]["U"], b[key]["uncertainty"]["U"])
        assert abs(va - vb) <= u, (key, va, vb, u)


def _keys(path: Path) -> list:
    df = read_rate_readings(path).data
    return sorted(zip(df["test"], df["run"], df["step"], df["role"]))


def test_served_rate_instruments_speak_exactly_the_drivers_command_sets(bench):
    sb = ServedRateBench(bench)
    for driver, inst in zip((RateTable, GyroOutput, Chamber, Supply), rate_instruments(sb)):
        sent = [tpl.split(" ")[0] for tpl in driver.COMMANDS.values() if tpl]
        sent.append(driver.ERROR_QUERY)
        served = [m for m, _ in inst.commands]
        assert [h for h in sent if not any(scpi_match(h, m) for m in served)] == [], inst.name
        assert [m for m in served if not any(scpi_match(h, m) for h in sent)] == [], inst.name


def _cli_acquire(res: dict, out: Path, proto: Path, b, *extra) -> list[str]:
    return ["acquire", "--protocol", str(proto), "--table", res["table"], "--gyro", res["gyro"],
            "--chamber", res["chamber"], "--supply", res["supply"], "--out", str(out),
            *[x for m in _meta(b) for x in ("--meta", m)], *extra]


@pytest.mark.parametrize("given", ["serial=SN-7777", "gyro_idn=ACME,G-610,SN-7777,1.0",
                                   "supply_idn=ACME,PS", "date=1999-01-01"])
def test_given_metadata_never_replaces_the_rate_instruments_answers(bench, proto, tmp_path,
                                                                    capsys, given):
    """``--meta`` adds to what the rate instruments reported (their ``*IDN?`` answers, the
    gyro's serial), never replaces it: refused in one line before the programme, no readings."""
    served = serve_rate_bench(bench, speed=SPEED, seed=SEED)
    try:
        rc = main(_cli_acquire(served.resources, tmp_path / "acq", proto, bench,
                               "--meta", given))
    finally:
        served.close()
    err = capsys.readouterr().err
    key = given.split("=")[0]
    assert rc == 2 and f"key {key}: " in err and "never replace it" in err, err
    assert "Traceback" not in err
    assert not (tmp_path / "acq" / "readings.csv").exists()


def test_jjf_programme_through_the_instruments_calibrates_like_simulate(bench, proto, simulated,
                                                                        tmp_path):
    served = serve_rate_bench(bench, speed=SPEED, seed=SEED)
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            assert main(_cli_acquire(served.resources, tmp_path / "acq", proto, bench)) == 0
    finally:
        served.close()
    readings = tmp_path / "acq" / "readings.csv"
    r = read_rate_readings(readings)
    assert r.metadata["acquisition"] == "complete" and r.metadata["spec"] == "jjf1535-2015"
    # the served bench's readings stay virtual without every line that says so (its
    # instruments' *_idn, its manufacturer): the times carry the bench's watermark
    from gonio.formats.provenance import file_provenance
    bare = tmp_path / "bare" / "readings.csv"
    bare.parent.mkdir()
    bare.write_text("".join(ln for ln in readings.read_text().splitlines(keepends=True)
                            if not ln.startswith("# manufacturer:") and "_idn:" not in ln))
    assert "virtual" not in "".join(ln for ln in bare.read_text().splitlines() if ln[:1] == "#")
    prov = file_provenance(bare)
    assert prov["virtual"] and prov["evidence"] == ["watermark"], prov
    assert r.metadata["serial"] == bench.gyro.serial
    assert _keys(readings) == _keys(simulated[0])
    _agree_within_u(_calibrate(readings, proto, tmp_path / "cal"), simulated[1])
    log = (tmp_path / "acq" / "io.log").read_text(encoding="utf-8")
    for line in ("table > ROT -100", "table > OSC ", "table > MOUNT -x,+y", "chamber > TEMP 70",
                 "supply > OUTP OFF", "gyro > ACQ:STAR "):
        assert line in log, line
    assert log.rstrip().splitlines()[-3].endswith("table > STOP")
    # what was measured, never the protocol's nominal room: no "# room_temperature_c" line,
    # and each room test's record logs the chamber's air (MEAS:TEMP?) on its first and last
    # rows, blank between; the chamber tests' rows their set points
    assert "room_temperature_c" not in r.metadata
    assert "chamber > MEAS:TEMP?" in log
    df = r.data
    room = df[~df["test"].isin(("sf_temperature", "bias_temperature"))]
    for _, g in room.groupby(["test", "run", "step", "role"], sort=False):
        t = g["temperature_c"].to_numpy()
        assert np.isfinite(t[[0, -1]]).all() and (len(t) < 3 or np.isnan(t[1:-1]).all())
    served_room = 20.0                  # serve_rate_bench's room: the chamber off reads it
    assert np.nanmedian(room["temperature_c"]) == pytest.approx(served_room, abs=0.5)


#: The reader's answers before the served bench's clock stops (``hold:N``) in the SIGINT
#: test: the 6th ``ACQ:DATA?`` of 238 is a warm-up record's, after the bias records.
HOLD_AT = 6


def test_sigint_keeps_the_records_and_resume_completes(bench, proto, simulated, tmp_path):
    """``gonio bench serve`` and ``gonio acquire`` as processes: SIGINT mid-programme keeps
    the records (incomplete); ``--resume`` runs again from the power cycle cut short and
    the file calibrates like the uninterrupted simulation. The bench holds its clock once its
    :data:`HOLD_AT`-th reading is answered (``--fault hold:N``, it says ``held: N``), so the
    SIGINT comes mid-programme whatever the machine's load; the resume's connection lets
    the clock run on."""
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    srv = start_served("--bench", BENCH, "--table-port", "0", "--gyro-port", "0", "--speed",
                       str(SPEED), "--seed", str(SEED), "--fault", f"hold:{HOLD_AT}")
    try:
        res = dict(srv.stdout.readline().strip().split(": ", 1) for _ in range(4))
        out = tmp_path / "acq"
        proc = subprocess.Popen([sys.executable, "-m", "gonio",
                                 *_cli_acquire(res, out, proto, bench)],
                                env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        try:
            wait_held(srv, proc, HOLD_AT)
            proc.send_signal(signal.SIGINT)
            _, err = proc.communicate(timeout=60)
        finally:
            proc.kill()
            proc.wait()
        assert proc.returncode == 130, err
        kept = read_rate_readings(out / "readings.csv")
        assert kept.metadata["acquisition"] == "incomplete"
        assert "SIGINT" in kept.metadata["acquisition_stopped"]
        assert set(kept.data["test"]) >= {"bias", "warmup"} and len(kept.data) < len(
            read_rate_readings(simulated[0]).data)
        log = (out / "io.log").read_text(encoding="utf-8").splitlines()
        assert [ln.split(" ", 1)[1] for ln in log[-3:]] == [
            "table > STOP", "supply > OUTP OFF", "chamber > OUTP OFF"]
        with contextlib.redirect_stdout(io.StringIO()):
            assert main(_cli_acquire(res, out, proto, bench, "--resume")) == 0
    finally:
        stop_served(srv)
    assert _keys(out / "readings.csv") == _keys(simulated[0])        # every record once
    _agree_within_u(_calibrate(out / "readings.csv", proto, tmp_path / "cal"), simulated[1])


def test_resume_point_runs_the_cut_power_cycle_again():
    segs = [Segment("a", 0, 0, "r", 2, 1.0, power_on=True), Segment("a", 0, 1, "r", 2, 1.0),
            Segment("b", 0, 0, "r", 2, 1.0, power_on=True), Segment("b", 0, 1, "r", 2, 1.0)]
    rows = ["a,0,0,r,1\n", "a,0,0,r,2\n", "a,0,1,r,1\n", "a,0,1,r,2\n", "b,0,0,r,1\n",
            "b,0,0,r,2\n", "b,0,1,r,1\n"]
    assert resume_point(segs, rows) == (2, rows[:4])
    assert resume_point(segs, rows[:3]) == (0, [])
    assert resume_point(segs, rows + ["b,0,1,r,2\n"])[0] == 4


def test_programme_beyond_the_table_or_without_a_chamber_is_refused(bench, proto, tmp_path):
    prog = programme(str(proto), {"datasheet_bandwidth_hz": "40"})
    served = serve_rate_bench(bench, speed=SPEED, seed=SEED)
    try:
        no_chamber = {**served.resources, "chamber": None}
        with pytest.raises(GonioError, match="needs the chamber: give --chamber"):
            acquire_rate(prog.segments, prog.metadata, no_chamber, tmp_path / "a")
        fast = [Segment("scale_factor", 0, 0, "rate", 5, 1.0, rate_dps=5000.0, power_on=True)]
        with pytest.raises(GonioError, match="beyond the table's top rate"):
            acquire_rate(fast, prog.metadata, served.resources, tmp_path / "b")
        assert "ROT" not in (tmp_path / "b" / "io.log").read_text(encoding="utf-8")
        assert served.bench.cond.rate_dps == 0.0 and not served.bench.cond.supply_on
    finally:
        served.close()
    with pytest.raises(GonioError, match="datasheet_bandwidth_hz|estimated_bandwidth_hz"):
        programme(str(proto), {})


def _short_programme() -> list[Segment]:
    """A rest from power-on, ±10 °/s (the second at a chamber set point), a rest."""
    return [Segment("scale_factor", 0, 0, "rest", 5, 1.0, delay_s=5.0, power_on=True),
            Segment("scale_factor", 0, 1, "rate", 5, 1.0, 10.0, delay_s=2.0),
            Segment("scale_factor", 0, 2, "rate", 5, 1.0, -10.0, delay_s=2.0,
                    temperature_c=30.0),
            Segment("scale_factor", 0, 3, "rest", 5, 1.0, delay_s=2.0)]


@pytest.mark.parametrize("fault, error, words", [
    ("gyro-drop:3", LinkLost, "connection lost"),         # the third record's data
    ("table-error:2", InstrumentError, "axis fault"),     # the second rate: -310
])
def test_a_lost_link_or_an_instrument_error_stops_everything_and_keeps_the_records(
        bench, tmp_path, fault, error, words):
    served = serve_rate_bench(bench, speed=SPEED, seed=SEED, faults=Faults.parse([fault]))
    try:
        with pytest.raises(error, match=words):
            acquire_rate(_short_programme(), {"spec": "jjf1535-2015", "protocol": "short"},
                         served.resources, tmp_path / "a", timeout_s=3.0)
        c = served.bench.cond          # the stop and the switching off are written last
        deadline = time.monotonic() + 5.0
        while (c.rate_dps, c.supply_on, c.chamber_on) != (0.0, False, False) and \
                time.monotonic() < deadline:
            time.sleep(0.01)
        assert (c.rate_dps, c.freq_hz, c.supply_on, c.chamber_on) == (0.0, 0.0, False, False)
    finally:
        served.close()
    kept = read_rate_readings(tmp_path / "a" / "readings.csv")
    assert kept.metadata["acquisition"] == "incomplete" and words in \
        kept.metadata["acquisition_stopped"]
    assert _keys(tmp_path / "a" / "readings.csv") == sorted(
        [("scale_factor", 0, 0, "rest")] * 5 + [("scale_factor", 0, 1, "rate")] * 5)
    log = (tmp_path / "a" / "io.log").read_text(encoding="utf-8").splitlines()
    assert [ln.split(" ", 1)[1] for ln in log[-3:]] == [
        "table > STOP", "supply > OUTP OFF", "chamber > OUTP OFF"]


def test_a_laboratorys_acquisition_is_written_as_read(tmp_path):
    """Instruments that do not say virtual: the readings are written as read, no time moved;
    the virtual bench's (an ``*_idn`` that says so): the same rows with the bench's mark."""
    from gonio.formats.watermark import detect
    from gonio.instruments.run import ReadingsFile

    rows = [f"bias,0,0,record,{1800 + i},{2500 + i / 100:.2f}\n" for i in range(200)]
    cols = ("test", "run", "step", "role", "time_s", "output")
    for name, idn, virtual in (("lab", "ACME,G-610,SN-7,1.0", False),
                               ("virtual", "gonio,virtual rate table,x,1", True)):
        w = ReadingsFile(tmp_path / f"{name}.csv", {"gyro_idn": idn}, rows, cols)
        w.finish(True)
        text = (tmp_path / f"{name}.csv").read_text()
        assert (text.endswith("".join(rows))) is not virtual, name
        assert detect(tmp_path / f"{name}.csv")["virtual"] is virtual, name
