"""Input that cannot break the package: >1,000 mutated and generated inputs through every
reader (readings, streams, protocols, benches) and the stages after them. The only exception
allowed is GonioError; the readers' errors name file and line/column/key; inputs are never
modified; the CLI prints one line (no traceback) and exits 2."""

from __future__ import annotations

import hashlib
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings, strategies as st

from gonio.specs.ogam_draft.bench import load_bench
from gonio.specs.ogam_draft.items import compute_characteristics
from gonio.errors import GonioError
from gonio.specs.ogam_draft.readings import read_readings
from gonio.physics.kinematics import Timeline
from gonio.specs.ogam_draft.protocol import load_protocol, parse_protocol
from gonio.specs.ogam_draft.reduce import reduce_stream
from gonio.formats.streams import read_stream, write_stream

ROOT = Path(__file__).resolve().parents[1]
WORK = Path(tempfile.mkdtemp(prefix="gonio-fuzz-"))
READINGS = (ROOT / "tests/data/full.csv").read_bytes()
PROTO_TEXT = (ROOT / "protocols/ogam-draft.toml").read_bytes()
BENCH_TEXT = (ROOT / "protocols/benches/fog.toml").read_bytes()
shutil.copy(ROOT / "protocols/benches/table-precision.toml", WORK / "table-precision.toml")
MINI = parse_protocol({
    "protocol": {"name": "mini"}, "session": {"warm_up_s": 0.0, "static_s": 3.0, "settle_s": 1.0},
    "scale_factor": {"rest_s": 3.0, "read_delay_s": 1.05,
                     "rounds": [{"stop_deg": 30.0}, {"stop_deg": 60.0}]}})


def _stream_bytes() -> bytes:
    tl = Timeline(0.0)
    tl.dwell(3.0)
    for stop in (30.0, 60.0):
        tl.move(stop, 60.0, 60.0)
        tl.dwell(3.0)
        tl.move(0.0, 60.0, 60.0)
        tl.dwell(1.0)
    t = np.arange(0.0, tl.end_s, 0.05)
    ang = tl.angle_deg(t)
    counts = np.floor(ang * 3600.0 + 0.7 * t).astype(np.int64)
    p = write_stream(WORK / "base_stream.csv", t, counts, ang,
                     {"counter_bits": "16", "nominal_scale_factor_counts_per_deg": "3600"})
    return p.read_bytes()


STREAM = _stream_bytes()
TOKENS = ["nan", "inf", "-inf", "1e400", "abc", "", "9" * 30, "-0", "1.5", " ", "-1", "0",
          "0x10", "1,2", '"', "true", "é", "北", "NaN", "1e-400", "-9e18", "18446744073709551616"]
TOML_VALUES = ['"x"', "-1", "0", "1e400", "nan", "inf", "true", "[]", '[1, "a"]', "{}", "-1e308",
               "99999999999999999999", "[[1]]", '""', "1979-05-27", "0.0", "[{stop_deg = 1}]"]


def _cells_mutation(lines: list[bytes], data: st.DataObject) -> list[bytes]:
    body = [i for i, ln in enumerate(lines) if ln and not ln.startswith(b"#")]
    if not body:
        return lines
    i = data.draw(st.sampled_from(body))
    cells = lines[i].split(b",")
    j = data.draw(st.integers(0, len(cells) - 1))
    cells[j] = data.draw(st.sampled_from(TOKENS)).encode("utf-8")
    lines[i] = b",".join(cells)
    return lines


def mutate(raw: bytes, data: st.DataObject, csv: bool = True) -> bytes:
    """One or two mutations of a valid file's bytes."""
    kinds = ["truncate", "cell", "drop_line", "dup_line", "shuffle", "latin1", "utf16", "bom",
             "crlf", "drop_col", "extra_col", "empty", "header_only", "swap_lines", "nul",
             "unknown_test", "round_jump", "huge"]
    out = raw
    for _ in range(data.draw(st.integers(1, 2))):
        kind = data.draw(st.sampled_from(kinds))
        lines = out.split(b"\n")
        head = next((i for i, ln in enumerate(lines) if ln and not ln.startswith(b"#")), 0)
        if kind == "truncate":
            out = out[:data.draw(st.integers(0, max(0, len(out) - 1)))]
        elif kind == "cell" and csv:
            out = b"\n".join(_cells_mutation(lines, data))
        elif kind == "drop_line" and len(lines) > 1:
            del lines[data.draw(st.integers(0, len(lines) - 1))]
            out = b"\n".join(lines)
        elif kind == "dup_line" and len(lines) > 1:
            i = data.draw(st.integers(0, len(lines) - 1))
            lines.insert(i, lines[i])
            out = b"\n".join(lines)
        elif kind == "shuffle":
            rest = lines[head + 1:]
            perm = data.draw(st.permutations(list(range(len(rest))))) if len(rest) < 60 else \
                list(np.random.default_rng(data.draw(st.integers(0, 99))).permutation(len(rest)))
            out = b"\n".join(lines[:head + 1] + [rest[k] for k in perm])
        elif kind == "swap_lines" and len(lines) > 3:
            i = data.draw(st.integers(0, len(lines) - 2))
            lines[i], lines[i + 1] = lines[i + 1], lines[i]
            out = b"\n".join(lines)
        elif kind == "latin1":
            i = data.draw(st.integers(0, len(out)))
            out = out[:i] + "é°".encode("latin-1") + out[i:]
        elif kind == "utf16":
            out = out.decode("utf-8", "replace").encode("utf-16")
        elif kind == "bom":
            out = b"\xef\xbb\xbf" + out
        elif kind == "crlf":
            out = out.replace(b"\n", b"\r\n")
        elif kind == "drop_col" and csv and head < len(lines):
            ncol = len(lines[head].split(b","))
            j = data.draw(st.integers(0, max(0, ncol - 1)))
            out = b"\n".join(b",".join(c for k, c in enumerate(ln.split(b",")) if k != j)
                             if ln and not ln.startswith(b"#") else ln for ln in lines)
        elif kind == "extra_col" and csv:
            out = b"\n".join((ln + (b",extra" if i == head else b",1"))
                             if ln and not ln.startswith(b"#") else ln
                             for i, ln in enumerate(lines))
        elif kind == "empty":
            out = b""
        elif kind == "header_only":
            out = b"\n".join(lines[:head + 1])
        elif kind == "nul":
            out = out.replace(b",", b"\x00", 1)
        elif kind == "unknown_test":
            out = out.replace(b"angle_deviation", b"angle_deviaton", 1)
        elif kind == "round_jump":
            out = out.replace(b",1,3,", b",1,7,", 1)
        elif kind == "huge":
            out = out.replace(b"60.0", b"1e308", 1)
    return out


def _located(e: GonioError, path: Path) -> None:
    assert e.file is not None and Path(e.file).name == path.name, str(e)
    assert path.name in str(e)
    assert (e.line is not None or e.column is not None or e.key is not None
            or "cannot read" in e.message), str(e)


def _write(name: str, raw: bytes) -> tuple[Path, str]:
    p = WORK / name
    p.write_bytes(raw)
    return p, hashlib.sha256(raw).hexdigest()


FUZZ = settings(max_examples=450, deadline=None, derandomize=True,
                suppress_health_check=list(HealthCheck))


def _read_and_compute(p, h):
    """Read a readings file and compute the seven items: only GonioError, located; input kept."""
    try:
        r = read_readings(p)
    except GonioError as e:
        _located(e, p)
    else:
        try:
            compute_characteristics(r)
        except GonioError:
            pass
    assert hashlib.sha256(p.read_bytes()).hexdigest() == h


@FUZZ
@given(st.data())
def test_fuzz_readings(data):
    p, h = _write("readings.csv", mutate(READINGS, data))
    _read_and_compute(p, h)


@settings(max_examples=300, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
@given(st.data())
def test_fuzz_streams(data):
    p, h = _write("stream.csv", mutate(STREAM, data))
    try:
        s = read_stream(p, chunk_rows=data.draw(st.sampled_from([7, 100, 10_000])))
    except GonioError as e:
        _located(e, p)
    else:
        try:
            reduce_stream(s, MINI)
        except GonioError:
            pass
    assert hashlib.sha256(p.read_bytes()).hexdigest() == h


def _toml_mutation(raw: bytes, data: st.DataObject) -> bytes:
    lines = raw.split(b"\n")
    kv = [i for i, ln in enumerate(lines) if b"=" in ln and not ln.lstrip().startswith(b"#")
          and not ln.startswith(b" ")]
    kind = data.draw(st.sampled_from(["value", "value", "drop", "unknown", "bytes"]))
    if kind == "value" and kv:
        i = data.draw(st.sampled_from(kv))
        key = lines[i].split(b"=")[0]
        lines[i] = key + b"= " + data.draw(st.sampled_from(TOML_VALUES)).encode()
    elif kind == "drop" and kv:
        del lines[data.draw(st.sampled_from(kv))]
    elif kind == "unknown":
        i = data.draw(st.integers(0, len(lines)))
        lines.insert(i, b"bogus_key = 1")
    else:
        return mutate(raw, data, csv=False)
    return b"\n".join(lines)


@FUZZ
@given(st.data())
def test_fuzz_protocols(data):
    raw = _toml_mutation(PROTO_TEXT, data)
    if data.draw(st.booleans()):
        raw = _toml_mutation(raw, data)
    p, h = _write("proto.toml", raw)
    try:
        load_protocol(p)
    except GonioError as e:
        _located(e, p)
    assert hashlib.sha256(p.read_bytes()).hexdigest() == h


@settings(max_examples=250, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
@given(st.data())
def test_fuzz_benches(data):
    p, h = _write("bench.toml", _toml_mutation(BENCH_TEXT, data))
    try:
        load_bench(p)
    except GonioError as e:
        _located(e, p)
    assert hashlib.sha256(p.read_bytes()).hexdigest() == h


ROW = st.fixed_dictionaries({
    "test": st.sampled_from(["scale_factor", "angle_deviation", "zero_stability",
                             "rate_consistency", "pointing_consistency", "equal_division",
                             "tilt_estimate", "bogus"]),
    "series": st.integers(-1, 12), "round": st.integers(-1, 14),
    "rate_dps": st.sampled_from(["", "60", "1", "300", "-5", "0"]),
    "orientation": st.sampled_from(["", "up", "north", "east", "sideways"]),
    "time_s": st.floats(allow_nan=True, allow_infinity=True, width=32),
    "table_deg": st.one_of(st.just(""), st.sampled_from(["30.0", "360.0", "0", "-30"]),
                           st.floats(width=32)),
    "gyro_counts": st.one_of(st.just(""), st.integers(-2**70, 2**70).map(str)),
    "gyro_deg": st.one_of(st.just(""), st.floats(width=32).map(repr)),
})


@settings(max_examples=150, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
@given(st.lists(ROW, min_size=0, max_size=40))
def test_generated_readings(rows):
    head = "test,series,round,rate_dps,orientation,time_s,table_deg,gyro_counts,gyro_deg"
    body = [",".join(str(r[k]) for k in head.split(",")) for r in rows]
    p, h = _write("gen.csv", ("# nominal_scale_factor_counts_per_deg: 3600\n" + head + "\n"
                              + "\n".join(body) + "\n").encode())
    _read_and_compute(p, h)


def test_cli_one_line_exit_2_no_traceback(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_bytes(b"time_s,gyro_counts\n0,1\n0.1,oops\n")
    badr = tmp_path / "badr.csv"
    badr.write_bytes(READINGS.replace(b"angle_deviation", b"angle_dev", 1))
    badp = tmp_path / "p.toml"
    badp.write_bytes(PROTO_TEXT.replace(b"static_s = 60.0", b"static_s = -1.0"))
    cases = [["reduce", str(bad), "--protocol", "ogam-draft", "--out", str(tmp_path / "o.csv")],
             ["calibrate", str(bad), "--out", str(tmp_path / "c")],
             ["calibrate", str(badr), "--out", str(tmp_path / "c")],
             ["calibrate", str(ROOT / "tests/data/full.csv"), "--protocol", str(badp),
              "--out", str(tmp_path / "c")],
             ["reduce", str(tmp_path / "missing.csv"), "--out", str(tmp_path / "o.csv")]]
    for argv in cases:
        r = subprocess.run([sys.executable, "-m", "gonio", *argv], capture_output=True, text=True,
                           cwd=ROOT, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
        assert r.returncode == 2, (argv, r.stderr)
        assert "Traceback" not in r.stderr and r.stderr.count("\n") == 1, r.stderr
        assert r.stderr.startswith("gonio: error: ")
    assert not (tmp_path / "o.csv").exists() and not (tmp_path / "c").exists() or \
        not any((tmp_path / "c").iterdir())
