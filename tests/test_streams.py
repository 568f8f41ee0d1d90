"""Stream files: unwrap against an independent big-integer model, chunk independence,
located errors, atomic writing, the simulate → stream → reduce round trip."""

from __future__ import annotations

import hashlib
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gonio.formats.counters import wrap_counter
from gonio.errors import GonioError
from gonio.formats.streams import (StreamWriter, iter_stream, read_stream, sniff_kind, unwrap_counts,
                           write_stream)

ROOT = Path(__file__).resolve().parents[1]


def _py_wrap(values, bits, signed):
    """Independent model: Python big integers, modulo arithmetic by hand."""
    m = 1 << bits
    out = []
    for v in values:
        w = v % m
        if signed and w >= m // 2:
            w -= m
        out.append(w)
    return out


@pytest.mark.parametrize("bits", [16, 24, 32, 64])
@pytest.mark.parametrize("signed", [True, False])
def test_unwrap_recovers_counter_through_file(tmp_path, bits, signed, monkeypatch):
    import gonio.formats.streams as S
    monkeypatch.setattr(S, "CHECK_PIECE_ROWS", 64)     # unwrapped across 47 pieces too
    rng = np.random.default_rng(bits + signed)
    limit = min(2 ** (bits - 1) - 1, 2 ** 40)
    steps = rng.integers(-limit // 2, limit // 2, size=3000)
    start = int(rng.integers(-2**20, 2**20))
    true = start + np.cumsum(steps)                 # crosses the counter range many times
    wrapped = _py_wrap([int(v) for v in true], bits, signed)
    if bits < 64:
        assert wrapped == wrap_counter(true, bits, signed).tolist()
    t = np.arange(true.size) * 0.001
    p = tmp_path / "s.csv"
    lines = [f"# counter_bits: {bits}", f"# counter_signed: {str(signed).lower()}",
             "time_s,gyro_counts"] + [f"{a!r},{b}" for a, b in zip(t.tolist(), wrapped)]
    p.write_text("\n".join(lines) + "\n")
    s = read_stream(p, chunk_rows=517)
    first = wrapped[0]
    assert (s.gyro_counts - s.gyro_counts[0]).tolist() == (true - true[0]).tolist()
    assert int(s.gyro_counts[0]) == first
    np.testing.assert_array_equal(s.time_s, t)


def test_unwrap_uint64_near_top(tmp_path):
    vals = [2**64 - 3, 2**64 - 1, 1, 4]
    p = tmp_path / "s.csv"
    p.write_text("# counter_signed: false\ntime_s,gyro_counts\n" +
                 "".join(f"{i},{v}\n" for i, v in enumerate(vals)))
    s = read_stream(p)
    assert np.diff(s.gyro_counts).tolist() == [2, 2, 3]


def test_chunking_does_not_change_result(tmp_path):
    rng = np.random.default_rng(5)
    true = np.cumsum(rng.integers(-30000, 30000, 2000))
    p = write_stream(tmp_path / "s.csv", np.arange(2000) * 0.01, true,
                     rng.normal(size=2000), {"counter_bits": "16"})
    ref = read_stream(p, chunk_rows=2000)
    for cr in (2, 3, 999):
        parts = list(iter_stream(p, cr))
        assert np.concatenate([c.gyro_counts for c in parts]).tolist() == ref.gyro_counts.tolist()
        assert sum(c.time_s.size for c in parts) == 2000
    assert (ref.gyro_counts - ref.gyro_counts[0]).tolist() == (true - true[0]).tolist()


def test_write_read_round_trip_bit_exact(tmp_path):
    rng = np.random.default_rng(7)
    t = np.cumsum(rng.uniform(0.001, 0.002, 500))
    table = rng.normal(0, 100, 500)
    temp = rng.normal(20, 1, 500)
    c = np.cumsum(rng.integers(-5, 5, 500))
    p = write_stream(tmp_path / "s.csv", t, c, table, {"serial": "7"}, temperature_c=temp)
    s = read_stream(p)
    np.testing.assert_array_equal(s.time_s, t)
    np.testing.assert_array_equal(s.table_deg, table)
    np.testing.assert_array_equal(s.temperature_c, temp)
    assert s.gyro_counts.tolist() == c.tolist() and s.metadata == {"serial": "7"}


def test_writer_is_atomic(tmp_path):
    p = tmp_path / "s.csv"
    with pytest.raises(RuntimeError):
        with StreamWriter(p, {}) as w:
            w.write([0.0, 1.0], [1, 2], [0.0, 0.0])
            raise RuntimeError("session failed")
    assert not p.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("body,line,column", [
    ("time_s,gyro_counts\n0,1\n0.1,1.5\n", 3, "gyro_counts"),
    ("time_s,gyro_counts,table_deg\n0,1,0\n0.1,2,nan\n", 3, "table_deg"),
    ("time_s,gyro_counts\n0,1\n,2\n", 3, "time_s"),
    ("# a: b\ntime_s,gyro_counts\n0,1\n0.1,2\n\n0.1,3\n", 6, "time_s"),
    ("time_s,gyro_counts\n0,1\n0.1,2\n0.2,3\n9,4\n", 5, "time_s"),
    ("# counter_bits: 16\ntime_s,gyro_counts\n0,1\n0.1,70000\n", 4, "gyro_counts"),
    ("time_s,table_deg\n0,1\n", 1, "gyro_counts"),
])
def test_errors_name_file_line_column(tmp_path, body, line, column):
    p = tmp_path / "bad.csv"
    p.write_text(body)
    with pytest.raises(GonioError) as e:
        read_stream(p)
    assert e.value.file == str(p) and e.value.line == line and e.value.column == column
    assert f"bad.csv:{line}: column {column}" in str(e.value)


def test_bad_metadata_names_key(tmp_path):
    p = tmp_path / "m.csv"
    p.write_text("# counter_bits: 12\ntime_s,gyro_counts\n0,1\n")
    with pytest.raises(GonioError, match="key counter_bits"):
        read_stream(p)


def test_sniff_kind(tmp_path):
    a = tmp_path / "a.csv"
    a.write_text("test,series,round,time_s,table_deg,gyro_counts\n")
    b = tmp_path / "b.csv"
    b.write_text("\ufeff# x: y\r\ntime_s,gyro_counts\r\n0,1\r\n")
    assert sniff_kind(a) == "readings" and sniff_kind(b) == "stream"
    assert read_stream(b).gyro_counts.tolist() == [1]


def test_cli_simulate_stream_reduce_equals_session_readings(tmp_path):
    """gonio simulate --stream → gonio reduce gives the bench's own readings (24-bit counter
    wraps several times; quantised counts): same rows, same counts."""
    proto = tmp_path / "mini.toml"
    proto.write_text("""
[protocol]
name = "mini"
[session]
warm_up_s = 0.0
static_s = 5.0
settle_s = 1.0
[scale_factor]
rest_s = 3.0
read_delay_s = 1.505
rounds = [{stop_deg = 60.0}, {stop_deg = 360.0}]
[angle_deviation]
rest_s = 3.0
read_delay_s = 1.005
rounds = [{stop_deg = 30.0}, {stop_deg = 180.0}]
""")
    bench = tmp_path / "fog100.toml"
    text = (ROOT / "protocols/benches/fog.toml").read_text()
    bench.write_text(text.replace("sample_rate_hz = 1000.0", "sample_rate_hz = 100.0")
                     .replace("counter_bits = 32", "counter_bits = 24"))
    (tmp_path / "table-precision.toml").write_text(
        (ROOT / "protocols/benches/table-precision.toml").read_text())
    env = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"}
    run = lambda *a: subprocess.run([sys.executable, "-m", "gonio", *a], cwd=tmp_path, env=env,
                                    capture_output=True, text=True)
    r = run("simulate", "--protocol", str(proto), "--bench", str(bench), "--out", "out",
            "--stream")
    assert r.returncode == 0, r.stderr
    s = read_stream(tmp_path / "out/stream.parquet")          # Parquet by default
    assert s.metadata["counter_bits"] == "24"
    assert np.ptp(s.gyro_counts) > 2**24                    # really wrapped and unwrapped
    digest = hashlib.sha256((tmp_path / "out/stream.parquet").read_bytes()).hexdigest()
    r = run("reduce", "out/stream.parquet", "--protocol", str(proto), "--out", "red.csv", "--json")
    assert r.returncode == 0, r.stderr
    assert hashlib.sha256((tmp_path / "out/stream.parquet").read_bytes()).hexdigest() == digest
    body = lambda p: [ln.split(",") for ln in p.read_text().splitlines()
                      if not ln.startswith("#")]
    red, ses = body(tmp_path / "red.csv"), body(tmp_path / "out/readings.csv")
    # the same rows; the session's readings.csv and the stream carry the bench's watermark
    # in their times' 1 ns digit only (gonio.formats.watermark): every count, angle and set
    # point equal, every time within 3 ns
    assert len(red) == len(ses) and red[0] == ses[0]
    col = red[0].index("time_s")
    for a, b in zip(red[1:], ses[1:]):
        assert a[:col] + a[col + 1:] == b[:col] + b[col + 1:], (a, b)
        assert abs(float(a[col]) - float(b[col])) <= 3e-9, (a, b)
    r = run("calibrate", "out/stream.parquet", "--protocol", str(proto), "--out", "cal", "--json")
    assert r.returncode == 0, r.stderr
    r2 = run("calibrate", "out/readings.csv", "--protocol", str(proto), "--out", "cal2", "--json")
    import json
    a, b = json.loads(r.stdout), json.loads(r2.stdout)
    def strip(d):      # file name, hash, metadata and file line numbers differ by design
        if isinstance(d, dict):
            return {k: strip(v) for k, v in d.items()
                    if k not in ("source", "metadata", "line")}
        return [strip(v) for v in d] if isinstance(d, list) else d
    # the same items from the stream and from the readings: the counts are equal, the
    # watermark's nanoseconds move K by less than 10⁻⁹ of itself
    assert strip(a).keys() == strip(b).keys() and a["items"].keys() == b["items"].keys()
    ka, kb = a["items"]["scale_factor"]["value"], b["items"]["scale_factor"]["value"]
    assert abs(ka - kb) <= 1e-9 * abs(kb), (ka, kb)


def test_residual_step_bound_is_an_upper_bound_rounding_included():
    # The counter-against-table check forms count/K − table only where this bound exceeds
    # the tolerance; it must bound the float64 steps of that residual as numpy forms them,
    # also in the worst case for rounding: the table still (or moving with the counter)
    # while huge counts step by their largest amount.
    import gonio.formats.streams as S
    rng = np.random.default_rng(11)
    worst = 0.0
    for case in range(3000):
        n = int(rng.integers(2, 60))
        k = float(rng.choice([1.0 / 3.0, 3597.1223021582737, 72000.0, 1e6 / 7.0]))
        base = int(rng.integers(-2**52, 2**52)) if case % 2 else int(rng.integers(-10**6, 10**6))
        counts = base + np.cumsum(rng.integers(-2**20, 2**20, n))
        if case % 3 == 0:
            table = np.full(n, float(rng.uniform(-1e5, 1e5)))
        elif case % 3 == 1:
            table = counts / k + rng.normal(0, 1e-3, n)
        else:
            table = rng.uniform(-360, 360, n)
        top = float(np.abs(np.diff(counts)).max())
        resid = np.divide(counts, k)
        resid -= table
        actual = float(np.abs(np.diff(resid)).max())
        bound = S._residual_step_bound(counts, table, top, k)
        assert bound >= actual, (case, bound, actual)
        worst = max(worst, actual / bound)
    assert worst > 0.999           # and not loose where the residual's step is the count's
