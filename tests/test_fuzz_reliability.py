"""Hostile inputs, values and places (issue 14): every case ends in one clear line.

Generated classes: special files as every input, huge cells, extreme floats in every
numeric field (readings, metadata, protocol, bench), deep and long TOML, every
output-place failure (including a full disk on a small tmpfs), signals at random
instants, sizes beyond the stated limits, data-integrity cases (outputs over
inputs, mixed or stale sets, concurrent runs, a stray reading), contradictions and
determinism. Each case checks: a GonioError naming the place (API) or exit 2 with
at most three lines and no traceback (CLI); inputs unchanged; the previous output
set intact or none; no temporary or staging file left. The Python API is used
except where the CLI layer itself is under test.
"""

from __future__ import annotations

import contextlib
import copy
import hashlib
import json
import math
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from gonio.atomic import MANIFEST, output_set, read_manifest, sha256_file, write_text
from gonio.specs.ogam_draft.bench import load_bench
from gonio.cli import main
from gonio.errors import GonioError
from gonio.specs.ogam_draft.readings import read_readings
from gonio.specs.ogam_draft.protocol import load_protocol
from gonio.report.i18n import display_number, round_half_up
from gonio.formats.toml import read_toml

ROOT = Path(__file__).resolve().parents[1]
FULL = ROOT / "tests/data/full.csv"
FULL_PROTOCOL = ROOT / "tests/data/full.toml"     # the protocol the file was taken with
FULL_TEXT = FULL.read_text()
PROTO_TEXT = (ROOT / "protocols/ogam-draft.toml").read_text()
BENCH_TEXT = (ROOT / "protocols/benches/rlg.toml").read_text()
LAB_TEXT = (ROOT / "protocols/lab-example.toml").read_text()
ENV = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "HOME": "/tmp"}

MINI_PROTO = """
[protocol]
name = "mini"
[session]
warm_up_s = 0.0
static_s = 3.0
settle_s = 1.0
[scale_factor]
rest_s = 3.0
read_delay_s = 1.05
rounds = [{ stop_deg = 30.0 }, { stop_deg = 60.0 }]
"""


# ----------------------------------------------------------------------------- helpers

@contextlib.contextmanager
def deadline(seconds: int = 60):
    """Fail a case that runs longer than ``seconds`` (SIGALRM)."""
    def boom(signum, frame):
        raise TimeoutError(f"case ran longer than {seconds} s")
    old = signal.signal(signal.SIGALRM, boom)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def tree_hash(d: Path) -> dict:
    """Every file under ``d`` (hidden ones too) with its SHA-256."""
    if not d.exists():
        return {}
    return {p.relative_to(d).as_posix(): sha256_file(p)
            for p in sorted(d.rglob("*")) if p.is_file() and not p.is_symlink()}


def no_debris(parent: Path) -> None:
    """No staging folder or temporary file left anywhere under ``parent``."""
    left = [p for p in parent.rglob("*") if p.name.startswith(".gonio-")]
    assert not left, left


def set_is_complete(d: Path) -> None:
    """``d`` holds exactly one run: the manifest lists every file, every hash matches."""
    man = read_manifest(d)
    assert man is not None, f"{d} has no manifest"
    files = {k: v for k, v in tree_hash(d).items() if k != MANIFEST}
    assert files == man["files"], (sorted(files), sorted(man["files"]))


def api_error(fn, *args, **kw) -> GonioError:
    with deadline(60):
        with pytest.raises(GonioError) as ei:
            fn(*args, **kw)
    msg = str(ei.value)
    assert "\n" not in msg and len(msg) < 800, msg
    return ei.value


def cli(argv, capsys, expect: int = 2) -> str:
    """Run the CLI in-process; exit code, one to three lines, no traceback."""
    with deadline(60):
        rc = main([str(a) for a in argv])
    err = capsys.readouterr().err
    assert rc == expect, (argv, rc, err)
    if expect == 2:
        lines = err.strip().splitlines()
        assert 1 <= len(lines) <= 3, err
        assert "Traceback" not in err and "error:" in lines[-1], err
    return err


def run_proc(argv, cwd=None, timeout=120):
    """The CLI as a separate process with a 3 GB address-space cap."""
    import resource

    def cap():
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
    return subprocess.run([sys.executable, "-m", "gonio", *map(str, argv)], capture_output=True,
                          text=True, cwd=cwd or ROOT, env=ENV, timeout=timeout, preexec_fn=cap)


def proc_ok_error(r) -> None:
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert 1 <= len(lines) <= 3 and "Traceback" not in r.stderr, r.stderr


CASES: list[str] = []          # names of every generated case (their number is reported)


def count(name: str) -> None:
    CASES.append(name)


@pytest.fixture(scope="module")
def _full_report_once():
    from gonio.specs.ogam_draft.calibration import calibrate
    return calibrate(FULL, FULL_PROTOCOL)


@pytest.fixture
def full_report(_full_report_once):
    """``calibrate(FULL, FULL_PROTOCOL)``: computed once for the module (a deterministic
    function of the two files; four tests write it), each test given its own deep copy, as
    ``write_outputs`` changes the report it writes."""
    return copy.deepcopy(_full_report_once)


# ----------------------------------------------------------------------------- special files

def _specials(tmp: Path) -> dict[str, Path]:
    fifo = tmp / "fifo"
    os.mkfifo(fifo)
    sock = tmp / "sock"
    s = socket.socket(socket.AF_UNIX)
    s.bind(str(sock))
    (tmp / "dir").mkdir()
    (tmp / "link-zero").symlink_to("/dev/zero")
    return {"dev-zero": Path("/dev/zero"), "dev-urandom": Path("/dev/urandom"),
            "dev-null": Path("/dev/null"), "fifo": fifo, "socket": sock,
            "folder": tmp / "dir", "symlink-to-device": tmp / "link-zero",
            "missing": tmp / "missing.csv"}


READERS = {
    "readings": read_readings,
    "protocol": load_protocol,
    "bench": load_bench,
    "lab": lambda p: __import__("gonio.formats.lab", fromlist=["load_lab"]).load_lab(p),
    "calibrate": lambda p: __import__("gonio.specs.ogam_draft.calibration", fromlist=["calibrate"]).calibrate(p),
    "toml": read_toml,
}


@pytest.mark.parametrize("reader", sorted(READERS))
def test_special_files_refused_before_reading(tmp_path, reader):
    for kind, path in _specials(tmp_path).items():
        e = api_error(READERS[reader], path)
        assert path.name in str(e), str(e)
        count(f"special:{reader}:{kind}")


def test_special_files_cli(tmp_path, capsys):
    sp = _specials(tmp_path)
    for kind in ("dev-zero", "fifo", "folder"):
        p = sp[kind]
        for argv in (["calibrate", p, "--out", tmp_path / "o"], ["reduce", p, "--out",
                     tmp_path / "r.csv"], ["noise", p], ["eda", p, "--starts", "2"],
                     ["calibrate", FULL, "--protocol", p, "--out", tmp_path / "o"]):
            cli(argv, capsys)
            count(f"special-cli:{argv[0]}:{kind}")
    assert not (tmp_path / "o").exists() and not (tmp_path / "r.csv").exists()


def test_size_limit_before_reading(tmp_path, monkeypatch):
    big = tmp_path / "big.csv"
    big.write_text(FULL_TEXT + "\n" * 2000)
    monkeypatch.setenv("GONIO_MAX_INPUT_BYTES", "1000")
    e = api_error(read_readings, big)
    assert "GONIO_MAX_INPUT_BYTES" in str(e)
    monkeypatch.setenv("GONIO_MAX_TOML_BYTES", "100")
    p = tmp_path / "p.toml"
    p.write_text(PROTO_TEXT)
    api_error(load_protocol, p)
    count("size:readings")
    count("size:toml")


# ----------------------------------------------------------------------------- huge cells

def _rows():
    lines = FULL_TEXT.splitlines()
    head = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    return lines, head


@pytest.mark.parametrize("size", [4097, 131_073, 1_000_000])
def test_huge_cells(tmp_path, size):
    lines, head = _rows()
    ncol = len(lines[head].split(","))
    for col in range(ncol):
        ls = list(lines)
        cells = ls[head + 1].split(",")
        cells[col] = "7" * size
        ls[head + 1] = ",".join(cells)
        p = tmp_path / "r.csv"
        p.write_text("\n".join(ls) + "\n")
        h = sha256_file(p)
        e = api_error(read_readings, p)
        assert e.line == head + 2, str(e)
        assert sha256_file(p) == h
        count(f"huge-cell:{size}:{col}")
    ls = ["# operator: " + "x" * size] + lines
    p = tmp_path / "m.csv"
    p.write_text("\n".join(ls) + "\n")
    assert api_error(read_readings, p).line == 1
    count(f"huge-metadata:{size}")


def test_csv_edge_cases(tmp_path):
    lines, head = _rows()
    cases = {
        "bare-cr": "\r".join(lines) + "\r",
        "line-column": "\n".join(ln + (",line" if i == head else ",1") if i >= head else ln
                                 for i, ln in enumerate(lines)) + "\n",
        "bad-quote": "\n".join(lines[:head + 1] + ['"scale_factor,1,1,60,up,3.0,60.0,216030,']
                               + lines[head + 2:]) + "\n",
    }
    r = None
    for name, text in cases.items():
        p = tmp_path / f"{name}.csv"
        p.write_text(text)
        try:
            r = read_readings(p)
        except GonioError as e:
            assert e.line is not None or e.column is not None, str(e)
            assert name != "bare-cr", str(e)
        else:
            assert name == "bare-cr" and len(r.data) == len(lines) - head - 1
        count(f"csv:{name}")


# ----------------------------------------------------------------------------- extreme floats

EXTREMES = ["1e308", "-1e308", "5e-324", "-2.2e-310", "1e400", "9" * 5000, "1e99999",
            "１２３", "١٢٣", "1_000", "0x10", "nan", "-inf", "1e-9", "-1e9", "4e18"]
READING_COLUMNS = ["series", "round", "rate_dps", "time_s", "table_deg", "gyro_counts",
                   "gyro_deg"]
NUMERIC_METADATA = ["nominal_scale_factor_counts_per_deg", "latitude_deg", "temperature_c",
                    "humidity_pct", "table_mpe_arcsec", "tilt_bound_deg"]


def _read_then_calibrate(p: Path) -> None:
    """Only GonioError, located; if the file is accepted, calibration and display hold."""
    from gonio.specs.ogam_draft.calibration import calibrate

    h = sha256_file(p)
    with deadline(60):
        try:
            rep = calibrate(p)
        except GonioError as e:
            assert e.file is not None and "\n" not in str(e) and len(str(e)) < 800, str(e)
        else:
            d = rep.to_json()
            json.dumps(d, allow_nan=False)
            for v in _floats(d):
                assert isinstance(display_number(v), str)
    assert sha256_file(p) == h


def _floats(x):
    if isinstance(x, dict):
        for v in x.values():
            yield from _floats(v)
    elif isinstance(x, list):
        for v in x:
            yield from _floats(v)
    elif isinstance(x, float):
        yield x


@pytest.mark.parametrize("column", READING_COLUMNS)
def test_extreme_values_in_every_column(tmp_path, column):
    lines, head = _rows()
    cols = lines[head].split(",")
    j = cols.index(column)
    rng = random.Random(column)
    targets = [i for i in range(head + 1, len(lines)) if lines[i].split(",")[0] in
               ("scale_factor", "angle_deviation", "rate_consistency")]
    for value in EXTREMES:
        ls = list(lines)
        i = rng.choice(targets)
        cells = ls[i].split(",")
        cells[j] = value
        ls[i] = ",".join(cells)
        p = tmp_path / "x.csv"
        p.write_text("\n".join(ls) + "\n")
        _read_then_calibrate(p)
        count(f"extreme:{column}:{value[:12]}")


@pytest.mark.parametrize("key", NUMERIC_METADATA)
def test_extreme_values_in_numeric_metadata(tmp_path, key):
    lines, head = _rows()
    for value in EXTREMES:
        ls = [f"# {key}: {value}"] + [ln for ln in lines if not ln.startswith(f"# {key}:")]
        p = tmp_path / "m.csv"
        p.write_text("\n".join(ls) + "\n")
        try:
            read_readings(p)
        except GonioError as e:
            assert e.key == key, str(e)
        else:
            # harmless where accepted; a K of 4e18 counts/° is representable (bounds from
            # physics and representability, issue 26), and calibration must hold with it
            assert value in ("1e-9", "5e-324", "-2.2e-310") or (
                key == "nominal_scale_factor_counts_per_deg" and value == "4e18"), value
        _read_then_calibrate(p)
        count(f"extreme-metadata:{key}:{value[:12]}")


def _toml_numeric_keys(text: str) -> list[tuple[int, str]]:
    out = []
    for i, ln in enumerate(text.splitlines()):
        s = ln.split("#")[0].strip()
        if "=" in s and not s.startswith("[") and "{" not in s:
            k, v = (x.strip() for x in s.split("=", 1))
            try:
                float(v)
            except ValueError:
                continue
            out.append((i, k))
    return out


TOML_EXTREMES = ["1e308", "-1e308", "5e-324", "1e-310", "1e12", "1e13", "-1e9", "999999999999",
                 "1e-20"]


@pytest.mark.parametrize("which", ["protocol", "bench"])
def test_extreme_values_in_every_toml_number(tmp_path, which):
    text = PROTO_TEXT if which == "protocol" else BENCH_TEXT
    loader = load_protocol if which == "protocol" else load_bench
    lines = text.splitlines()
    if which == "bench":
        shutil.copy(ROOT / "protocols/benches/table-precision.toml", tmp_path)
    for i, key in _toml_numeric_keys(text):
        for value in TOML_EXTREMES:
            ls = list(lines)
            ls[i] = f"{key} = {value}"
            p = tmp_path / f"{which}.toml"
            p.write_text("\n".join(ls) + "\n")
            with deadline(60):
                try:
                    obj = loader(p)
                except GonioError as e:
                    assert e.file is not None and e.key is not None, str(e)
                else:
                    if which == "bench":
                        json.dumps(obj.to_dict(), allow_nan=False)
            count(f"extreme-toml:{which}:{key}:{value}")


def test_number_display_is_total():
    rng = np.random.default_rng(1)
    vals = [0.0, -0.0, 5e-324, -5e-324, 1e308, -1.7976931348623157e308, math.inf, math.nan,
            1e15, 9.999999e14, 1e-3, 9.9996e-5, 123456789.123456789]
    vals += list(rng.standard_normal(200) * 10.0 ** rng.integers(-320, 308, 200))
    for v in vals:
        for sig in (1, 2, 3, 8):
            s = display_number(v, sig)
            assert isinstance(s, str) and s
        if math.isfinite(v):
            for dec in (-3, 0, 2, 12):
                assert isinstance(round_half_up(v, dec), str)
    count("display:total")


# ----------------------------------------------------------------------------- deep TOML

@pytest.mark.parametrize("loader", ["protocol", "bench", "lab"])
@pytest.mark.parametrize("shape", ["array-40", "array-100000", "table-100000", "dotted-1000",
                                   "dotted-100000"])
def test_deep_and_long_toml(tmp_path, loader, shape):
    kind, n = shape.rsplit("-", 1)
    n = int(n)
    if kind == "array":
        text = "x = " + "[" * n + "]" * n + "\n"
    elif kind == "table":
        text = "x = " + "{a = " * n + "1" + "}" * n + "\n"
    else:
        text = "a" + ".b" * n + " = 1\n"
    p = tmp_path / "deep.toml"
    p.write_text(text)
    fn = {"protocol": load_protocol, "bench": load_bench,
          "lab": READERS["lab"]}[loader]
    e = api_error(fn, p)
    assert e.file is not None
    count(f"deep-toml:{loader}:{shape}")


# ----------------------------------------------------------------------------- output places

def _previous_set(d: Path) -> dict:
    """A previous run's set in ``d`` (written with the output-set machinery)."""
    with output_set(d, source_sha256="0" * 64) as st:
        write_text(st / "results.json", '{"previous": true}\n')
        write_text(st / "tables" / "x.csv", "a\n1\n")
    return tree_hash(d)


def test_files_gonio_did_not_write_are_kept_and_never_replaced(tmp_path, capsys):
    """A folder holding the user's files (a log redirected there, notes): the run's set is
    swapped in around them, byte for byte unchanged; a run that would write one of their
    names is refused and the folder left as it was."""
    d = tmp_path / "mine"
    d.mkdir()
    (d / ".log").write_text("started\n")
    (d / "notes").mkdir()
    (d / "notes" / "mine.txt").write_text("mine")
    cli(["calibrate", FULL, "--protocol", FULL_PROTOCOL, "--out", d], capsys, expect=0)
    assert (d / ".log").read_text() == "started\n"
    assert (d / "notes" / "mine.txt").read_text() == "mine"
    assert (d / "results.json").is_file()
    man = json.loads((d / "gonio-manifest.json").read_text())
    assert ".log" not in man["files"] and man["foreign_files_kept"] == [".log", "notes/mine.txt"]
    clash = tmp_path / "clash"
    clash.mkdir()
    (clash / "summary.txt").write_text("my own summary")
    before = tree_hash(clash)
    err = cli(["calibrate", FULL, "--protocol", FULL_PROTOCOL, "--out", clash], capsys)
    assert "summary.txt" in err and tree_hash(clash) == before
    no_debris(tmp_path)
    count("out-place:foreign-files-kept")


def test_output_place_failures_cli(tmp_path, capsys):
    (tmp_path / "afile").write_text("keep")
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    (tmp_path / "dirlink").symlink_to(tmp_path)
    (tmp_path / "notgonio").mkdir()
    (tmp_path / "notgonio" / "mine.txt").write_text("mine")
    places = {
        "existing-file": tmp_path / "afile", "parent-is-file": tmp_path / "afile" / "x",
        "fifo": tmp_path / "fifo", "char-device": "/dev/null", "symlink-loop": tmp_path / "loop",
        "symlink-to-folder": tmp_path / "dirlink", "name-too-long": tmp_path / ("n" * 300),
        "empty": "", "blank": "   ",
    }
    before = tree_hash(tmp_path)
    for name, place in places.items():
        for argv in (["calibrate", FULL, "--out", place], ["simulate", "--protocol",
                     tmp_path / "none.toml", "--out", place], ["demo", "--out", place],
                     ["validate", "--trials", "2", "--out", place]):
            cli(argv, capsys)
            count(f"out-place:{argv[0]}:{name}")
    for name in ("existing-file-is-input", "fifo", "char-device", "folder"):
        place = {"existing-file-is-input": FULL, "fifo": tmp_path / "fifo",
                 "char-device": "/dev/null", "folder": tmp_path}[name]
        cli(["eda", FULL, "--starts", "2", "--plot", place], capsys)
        cli(["reduce", FULL, "--out", place], capsys)
        count(f"plot-place:{name}")
        count(f"reduce-place:{name}")
    assert os.path.exists("/dev/null") and Path("/dev/null").is_char_device()
    assert tree_hash(tmp_path) == before
    no_debris(tmp_path)


def test_read_only_folder(tmp_path, full_report):
    ro = tmp_path / "ro"
    ro.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=64k", "tmpfs", str(ro)],
                      capture_output=True).returncode != 0:
        pytest.skip("cannot mount a read-only tmpfs here (needs root and mount rights)")
    try:
        from gonio.specs.ogam_draft.outputs import write_outputs
        rep = full_report
        e = api_error(write_outputs, rep, ro / "out")
        assert "Read-only" in str(e) or "read-only" in str(e).lower(), str(e)
        count("out-place:read-only")
    finally:
        subprocess.run(["umount", str(ro)])


def test_full_disk_leaves_previous_set_and_no_debris(tmp_path, full_report):
    mnt = tmp_path / "small"
    mnt.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=300k", "tmpfs", str(mnt)],
                      capture_output=True).returncode != 0:
        pytest.skip("cannot mount a 300 KB tmpfs here (needs root and mount rights)")
    try:
        from gonio.specs.ogam_draft.outputs import write_outputs
        rep = full_report
        out = mnt / "out"
        prev = _previous_set(out)
        for fill_kb in (0, 100, 200, 400):
            filler = mnt / "filler"
            with open(filler, "wb", buffering=0) as fh:          # as much as fits, up to fill_kb
                for _ in range(fill_kb // 4):
                    try:
                        fh.write(b"\0" * 4096)
                    except OSError:
                        break
            e = api_error(write_outputs, rep, out)
            assert "No space left" in str(e), str(e)
            assert tree_hash(out) == prev
            no_debris(mnt)
            filler.unlink(missing_ok=True)
            count(f"full-disk:{fill_kb}KB-prefilled")
        e = api_error(write_text, mnt / "single.txt", "x" * 400_000)
        assert not (mnt / "single.txt").exists()
        no_debris(mnt)
        count("full-disk:single-file")
    finally:
        subprocess.run(["umount", str(mnt)])


def test_failed_rerun_leaves_previous_set(tmp_path, monkeypatch, full_report):
    from gonio.specs.ogam_draft.outputs import write_outputs
    import gonio.specs.ogam_draft.outputs as cert       # the writer the outputs call

    rep = full_report
    out = tmp_path / "D"
    write_outputs(rep, out)
    set_is_complete(out)
    prev = tree_hash(out)

    def broken(*a, **k):
        raise GonioError("certificate failed mid-way")
    monkeypatch.setattr(cert, "write_certificate", broken)
    api_error(write_outputs, rep, out)
    assert tree_hash(out) == prev
    no_debris(tmp_path)
    fresh = tmp_path / "fresh"
    api_error(write_outputs, rep, fresh)
    assert not fresh.exists()
    count("failed-rerun:previous")
    count("failed-rerun:fresh")


# ----------------------------------------------------------------------------- data integrity

def test_outputs_never_replace_inputs(tmp_path, capsys):
    raw = tmp_path / "raw.csv"
    raw.write_text(FULL_TEXT)
    h = sha256_file(raw)
    cli(["reduce", raw, "--out", raw], capsys)
    D = tmp_path / "D"
    cli(["calibrate", FULL, "--protocol", FULL_PROTOCOL, "--out", D], capsys, expect=0)
    capsys.readouterr()
    prev = tree_hash(D)
    cli(["calibrate", D / "results.json", "--out", D], capsys)
    cli(["calibrate", FULL, "--out", D, "--lab", D / "summary.txt"], capsys)
    lab = tmp_path / "lab"
    lab.mkdir()
    (lab / "readings.csv").write_text("a laboratory's real data\n")
    for argv in (["simulate", "--protocol", tmp_path / "m.toml", "--out", lab],
                 ["demo", "--out", lab], ["calibrate", lab / "readings.csv", "--out", lab]):
        (tmp_path / "m.toml").write_text(MINI_PROTO)
        cli(argv, capsys)
    lab2 = tmp_path / "lab2"                      # an input inside --out is kept, unchanged
    lab2.mkdir()
    shutil.copy(FULL, lab2 / "readings.csv")
    for _ in range(2):
        cli(["calibrate", lab2 / "readings.csv", "--protocol", FULL_PROTOCOL, "--out", lab2], capsys, expect=0)
        capsys.readouterr()
        assert (lab2 / "readings.csv").read_bytes() == FULL.read_bytes()
        set_is_complete(lab2)
        assert (lab2 / "certificate.html").exists()
    count("integrity:input-inside-out-kept")
    out_csv = tmp_path / "red.csv"
    out_csv.write_text("existing readings\n")
    cli(["reduce", raw, "--out", out_csv], capsys)
    assert out_csv.read_text() == "existing readings\n"
    assert sha256_file(raw) == h and tree_hash(D) == prev
    assert (lab / "readings.csv").read_text() == "a laboratory's real data\n"
    for c in ("reduce-over-input", "calibrate-over-own-input", "lab-inside-out",
              "simulate-over-readings", "demo-over-readings", "calibrate-input-in-out",
              "reduce-over-readings"):
        count(f"integrity:{c}")


def test_simulate_readings_need_force(tmp_path, capsys):
    (tmp_path / "m.toml").write_text(MINI_PROTO)
    out = tmp_path / "S"
    cli(["simulate", "--protocol", tmp_path / "m.toml", "--out", out, "--stream"], capsys, 0)
    set_is_complete(out)
    first = tree_hash(out)
    cli(["simulate", "--protocol", tmp_path / "m.toml", "--out", out, "--seed", "3"], capsys)
    assert tree_hash(out) == first
    cli(["simulate", "--protocol", tmp_path / "m.toml", "--out", out, "--seed", "3", "--force"],
        capsys, 0)
    set_is_complete(out)
    assert "stream.csv" not in tree_hash(out)          # no stale part of the earlier run
    count("integrity:simulate-needs-force")
    count("integrity:rerun-no-stale-files")


def test_rerun_replaces_the_whole_set_and_stale_staging_is_cleaned(tmp_path):
    from gonio.atomic import _tag
    out = tmp_path / "D"
    _previous_set(out)
    stale = tmp_path / f"{_tag(out)}-stage-999999-abc"
    stale.mkdir()
    (stale / "results.json").write_text("half")
    with output_set(out) as st:
        write_text(st / "new.txt", "new\n")
    assert sorted(tree_hash(out)) == [MANIFEST, "new.txt"]
    assert not stale.exists()
    no_debris(tmp_path)
    count("integrity:stale-staging-cleaned")


def test_concurrent_runs_cannot_mix(tmp_path):
    (tmp_path / "m.toml").write_text(MINI_PROTO)
    out = tmp_path / "C"
    procs = []
    for seed in (1, 2):
        procs.append(subprocess.Popen(
            [sys.executable, "-m", "gonio", "simulate", "--protocol", str(tmp_path / "m.toml"),
             "--seed", str(seed), "--out", str(out), "--stream"], cwd=ROOT, env=ENV,
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True))
        time.sleep(0.3)
    res = [(p.wait(timeout=120), p.stderr.read()) for p in procs]
    assert all(rc in (0, 2) for rc, _ in res), res
    assert any(rc == 0 for rc, _ in res), res
    for rc, err in res:
        if rc == 2:
            assert "another gonio run" in err or "--force" in err, err
    set_is_complete(out)
    seeds = {ln for ln in (out / "readings.csv").read_text().splitlines() if "# seed" in ln}
    truth = json.loads((out / "truth.json").read_text())
    assert seeds == {f"# seed: {truth['seed']}"}       # readings and truth of one run
    no_debris(tmp_path)
    count("integrity:concurrent")


def test_signals_at_random_instants(tmp_path):
    (tmp_path / "m.toml").write_text(MINI_PROTO)
    rng = random.Random(14)
    out = tmp_path / "R"
    r = run_proc(["simulate", "--protocol", tmp_path / "m.toml", "--out", out, "--stream"])
    assert r.returncode == 0, r.stderr
    for i in range(4):
        sig = (signal.SIGINT, signal.SIGTERM)[i % 2]
        before = tree_hash(out)
        p = subprocess.Popen([sys.executable, "-m", "gonio", "simulate", "--protocol",
                              str(tmp_path / "m.toml"), "--out", str(out), "--stream",
                              "--force", "--seed", str(i + 10)], cwd=ROOT, env=ENV,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(rng.uniform(0.05, 2.5))
        p.send_signal(sig)
        rc = p.wait(timeout=60)
        err = p.stderr.read()
        assert "Traceback" not in err and len(err.strip().splitlines()) <= 3, err
        assert rc in (0, 130, 143, -sig), (rc, err)
        after = tree_hash(out)
        assert after == before or rc == 0 or read_manifest(out) is not None, err
        set_is_complete(out)
        no_debris(tmp_path)
        count(f"signal:{sig.name}:{i}")
    # SIGKILL leaves a staging folder; the next run removes it and says so
    p = subprocess.Popen([sys.executable, "-m", "gonio", "simulate", "--protocol",
                          str(tmp_path / "m.toml"), "--out", str(out), "--force", "--stream"],
                         cwd=ROOT, env=ENV, stderr=subprocess.PIPE, text=True)
    for _ in range(200):
        if any(q.name.startswith(".gonio-") for q in tmp_path.iterdir()):
            break
        time.sleep(0.05)
    p.kill()
    p.wait()
    set_is_complete(out)
    r = run_proc(["simulate", "--protocol", tmp_path / "m.toml", "--out", out, "--force"])
    assert r.returncode == 0, r.stderr
    no_debris(tmp_path)
    set_is_complete(out)
    count("signal:SIGKILL-then-rerun")


def test_stray_reading_is_set_aside_alone():
    """One rate_consistency reading at an unplanned rate, given to the items without the
    protocol (the calibration sets a rate outside the programme aside before them): it is a
    condition lacking the other conditions' positions, so 7.6 is not stated, naming it
    (items.consistency_incomplete: never a C_v over fewer positions), nothing else changes."""
    from gonio.specs.ogam_draft.items import compute_characteristics

    r = read_readings(FULL)
    base = compute_characteristics(r)
    df = r.data
    rc = df[df["test"] == "rate_consistency"].iloc[[0]].copy()
    rc["rate_dps"] = 7.77
    rc["series"] = 1
    rc["line"] = 10_000
    r.data = __import__("pandas").concat([df, rc], ignore_index=True)
    res = compute_characteristics(r)
    assert base.rate_consistency.measured and not res.rate_consistency.measured
    assert "7.77" in res.rate_consistency.reason and "lacks" in res.rate_consistency.reason
    for name in ("scale_factor", "angle_deviation", "pointing_consistency"):
        assert getattr(res, name).value == getattr(base, name).value, name
    count("integrity:stray-reading")


# ----------------------------------------------------------------------------- contradictions

def test_contradictions_refused(tmp_path, capsys):
    from gonio.specs.ogam_draft.calibration import calibrate

    lines, head = _rows()
    cols = lines[head].split(",")
    # gyro_deg contradicting gyro_counts through K by 29.5°
    i = next(k for k in range(head + 1, len(lines)) if lines[k].startswith("scale_factor"))
    cells = lines[i].split(",")
    cells[cols.index("gyro_deg")] = repr(float(cells[cols.index("table_deg")]) + 29.5)
    ls = list(lines)
    ls[i] = ",".join(cells)
    p = tmp_path / "c.csv"
    p.write_text("\n".join(ls) + "\n")
    e = api_error(calibrate, p, FULL_PROTOCOL)
    assert e.line == i + 1 and e.column == "gyro_deg", str(e)
    count("contradiction:gyro_deg-vs-counts")
    # Unicode digits
    for digits in ("６０", "٦٠", "६०", "60\u00a0"):
        ls = list(lines)
        cells = ls[head + 1].split(",")
        cells[cols.index("table_deg")] = digits
        ls[head + 1] = ",".join(cells)
        p.write_text("\n".join(ls) + "\n")
        if digits.strip() != "60":
            api_error(read_readings, p)
        count(f"contradiction:unicode-digits:{digits!r}")
    # equal division: 7 starts on 12 points
    rows = ["test,series,round,table_deg,gyro_deg"]
    for rnd in range(1, 8):
        for j in range(1, 13):
            rows.append(f"equal_division,1,{rnd},{30.0 * j},{30.0 * j + 1e-5}")
    p.write_text("\n".join(rows) + "\n")
    cli(["eda", p, "--starts", "7"], capsys)
    count("contradiction:eda-n-not-dividing-m")
    # sagnac --json never prints Infinity / NaN
    with deadline(60):
        rc = main(["sagnac", "--rlg", "--area-m2", "1e-6", "--perimeter-m", "100", "--json"])
    out = capsys.readouterr().out
    assert rc == 0 and "Infinity" not in out and "NaN" not in out
    json.loads(out)
    count("contradiction:sagnac-json")


# ----------------------------------------------------------------------------- sizes and CLI values

BIG_PROTOCOLS = {
    "series-1e9": __import__("re").sub(r"(?m)^series = 10 ", "series = 1000000000 ", PROTO_TEXT),
    "zs-readings-1e9": __import__("re").sub(r"(?m)^readings = 15", "readings = 1000000000",
                                            PROTO_TEXT),
    "rest-1e12": __import__("re").sub(r"(?m)^rest_s = ", "rest_s = 1e12 #", PROTO_TEXT, count=1),
    "rate-1e-9": __import__("re").sub(r"(?m)^rate_dps = 60.0", "rate_dps = 1e-9", PROTO_TEXT,
                                      count=1),
    "stop-1e9": PROTO_TEXT.replace("stop_deg = 60.0", "stop_deg = 1e9", 1),
    "rates-1e6": __import__("re").sub(r"(?m)^rates_dps = .*$", "rates_dps = ["
                                      + ", ".join(f"{1 + i * 1e-4:.4f}" for i in range(60_000))
                                      + "]", PROTO_TEXT, count=1),
    "rates-1000": __import__("re").sub(r"(?m)^rates_dps = .*$", "rates_dps = ["
                                       + ", ".join(f"{1 + i * 1e-3:.3f}" for i in range(1000))
                                       + ", 60.0]", PROTO_TEXT, count=1),
    "rounds-2e5": PROTO_TEXT + "\n[pointing_consistency]\norientations = ['up','north']\nrounds = ["
                  + ",".join("{stop_deg = 30.0}" for _ in range(200_000)) + "]\n",
}


@pytest.mark.parametrize("name", sorted(BIG_PROTOCOLS))
def test_protocol_sizes_beyond_limits(tmp_path, name):
    text = BIG_PROTOCOLS[name]
    assert text != PROTO_TEXT
    p = tmp_path / "big.toml"
    p.write_text(text)
    e = api_error(load_protocol, p)
    assert e.file is not None and (e.key is not None or "bytes" in str(e)), str(e)
    count(f"size:protocol:{name}")


def test_empty_protocol_names_the_protocol(tmp_path, capsys):
    p = tmp_path / "empty.toml"
    p.write_text('[protocol]\nname = "empty"\n')
    err = cli(["simulate", "--protocol", p, "--out", tmp_path / "o"], capsys)
    assert "empty.toml" in err and "no reading" in err and not (tmp_path / "o").exists()
    count("message:empty-protocol")


def test_bench_sizes_beyond_limits(tmp_path):
    from gonio.specs.ogam_draft.bench import run_session

    shutil.copy(ROOT / "protocols/benches/table-precision.toml", tmp_path)
    p = tmp_path / "b.toml"
    p.write_text(BENCH_TEXT.replace("sample_rate_hz = 1000.0", "sample_rate_hz = 100000.0"))
    e = api_error(run_session, load_protocol("ogam-draft"), load_bench(p))
    assert "GONIO_MAX_SAMPLES" in str(e) or "GONIO_MAX_SESSION_S" in str(e), str(e)
    count("size:bench-100kHz-session")
    p.write_text(BENCH_TEXT.replace("sample_rate_hz = 1000.0", "sample_rate_hz = 100.0")
                 .replace("counter_bits = 32", "counter_bits = 16"))
    e = api_error(load_bench, p)
    assert e.key == "instrument.counter_bits", str(e)
    count("size:bench-counter-overflow")
    fast = PROTO_TEXT.replace("rates_dps = [", "rates_dps = [400.0, ", 1)
    q = tmp_path / "fast.toml"
    q.write_text(fast)
    e = api_error(run_session, load_protocol(q), load_bench("rlg"))
    assert "max_rate_dps" in str(e), str(e)
    count("size:protocol-rate-over-table")


def test_session_time_and_reading_rows_beyond_limits(tmp_path, monkeypatch, capsys):
    """The estimated simulation time (GONIO_MAX_RUN_S) and the readings row limit
    (GONIO_MAX_READING_ROWS), each set low: exit 2 naming the variable, nothing written."""
    from gonio.specs.ogam_draft.bench import run_session

    (tmp_path / "m.toml").write_text(MINI_PROTO)
    for lim in ("0.01", "0.2"):
        monkeypatch.setenv("GONIO_MAX_RUN_S", lim)
        e = api_error(run_session, load_protocol(tmp_path / "m.toml"), load_bench("rlg"))
        assert "GONIO_MAX_RUN_S" in str(e) and "sample_rate_hz" in str(e) and e.key, str(e)
        err = cli(["simulate", "--protocol", tmp_path / "m.toml", "--out", tmp_path / "o"],
                  capsys)
        assert "GONIO_MAX_RUN_S" in err and not (tmp_path / "o").exists()
        count(f"size:run-time:{lim}")
    monkeypatch.delenv("GONIO_MAX_RUN_S")
    big = tmp_path / "big.csv"
    big.write_text(FULL.read_text() + "".join(f"zero_stability,3,{i},,up,{300.0 * i},,,0.0\n"
                                              for i in range(1, 400)))
    before = big.read_bytes()
    for lim in ("5", "150"):
        monkeypatch.setenv("GONIO_MAX_READING_ROWS", lim)
        err = cli(["calibrate", big, "--out", tmp_path / "c"], capsys)
        assert "GONIO_MAX_READING_ROWS" in err and not (tmp_path / "c").exists()
        assert big.read_bytes() == before
        count(f"size:reading-rows:{lim}")


def test_signals_during_rate_demo(tmp_path):
    """SIGINT/SIGTERM at random instants of `gonio demo --spec jjf1535-2015` (a staged set):
    no output folder or a complete one, no staging debris, at most three lines."""
    rng = random.Random(1535)
    for i, sig in enumerate((signal.SIGINT, signal.SIGTERM)):
        out = tmp_path / f"D{i}"
        p = subprocess.Popen([sys.executable, "-m", "gonio", "demo", "--spec", "jjf1535-2015",
                              "--out", str(out)], cwd=ROOT, env=ENV,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(rng.uniform(0.5, 4.0))
        p.send_signal(sig)
        rc = p.wait(timeout=120)
        err = p.stderr.read()
        assert "Traceback" not in err and len(err.strip().splitlines()) <= 3, err
        assert rc in (0, 130, 143, -sig), (rc, err)
        if out.exists():
            set_is_complete(out)
        no_debris(tmp_path)
        count(f"signal:rate-demo:{sig.name}")


CLI_VALUES = [
    ["simulate", "--seed", "-1", "--out", "{t}/o"], ["demo", "--seed", "-5", "--out", "{t}/o"],
    ["validate", "--trials", "2", "--seed", "1e3"],
    ["budget", "--tilt-deg", "89.9999999"], ["budget", "--monte-carlo", "1000000000"],
    ["budget", "--monte-carlo", "1000000000000"], ["budget", "--k", "0"],
    ["budget", "--table-mpe-arcsec", "1e308"], ["budget", "--duration-min", "nan"],
    ["calibrate", str(FULL), "--out", "{t}/o", "--monte-carlo", "1000000000"],
    ["validate", "--trials", "1000000000"], ["validate", "--trials", "2", "--workers", "1000000"],
    ["validate", "--trials", "2", "--workers", "0"], ["noise", str(FULL), "--taus", "decade:1e9"],
    ["noise", str(FULL), "--taus", "decade:1000000"], ["noise", str(FULL), "--scale-factor", "0"],
    ["noise", str(FULL), "--confidence", "1"], ["reduce", str(FULL), "--out", "{t}/r.csv",
                                                "--max-gap", "-1"],
    ["earth", "--latitude-deg", "91"], ["sagnac", "--rlg", "--area-m2", "1e-300",
                                        "--perimeter-m", "1"],
    ["sagnac", "--fog", "--length-m", "1e308", "--diameter-m", "1"], ["eda", str(FULL),
                                                                      "--starts", "0"],
    ["tilt", "--tilt-deg", "１"], ["simulate", "--seed", "9" * 5000, "--out", "{t}/o"],
    ["calibrate", str(FULL), "--out", ""],
]


@pytest.mark.parametrize("argv", CLI_VALUES, ids=lambda a: "-".join(a[:3])[:40])
def test_cli_values(tmp_path, capsys, argv):
    argv = [a.replace("{t}", str(tmp_path)) for a in argv]
    err = cli(argv, capsys)
    assert len(err) < 900
    assert not (tmp_path / "o").exists() and not (tmp_path / "r.csv").exists()
    count(f"cli:{' '.join(argv)[:60]}")


def test_cli_process_level_one_line(tmp_path):
    """The same, as separate processes (startup, warnings and exit paths included)."""
    for argv in (["budget", "--monte-carlo", "1000000000000"], ["calibrate", "/dev/zero",
                 "--out", tmp_path / "o"], ["calibrate", FULL, "--out", "/dev/null"]):
        proc_ok_error(run_proc(argv))
        count(f"cli-process:{argv[0]}")
    assert Path("/dev/null").is_char_device()


# ----------------------------------------------------------------------------- certificate text

def test_user_text_rendered_literally(tmp_path, full_report):
    """Markup, TeX and bidirectional controls in lab text are rendered literally; control
    characters and over-long fields are refused by the lab reader naming the key (issue 26;
    before, they were stripped or clipped on the page)."""
    from gonio.specs.ogam_draft.outputs import write_outputs
    from gonio.formats.lab import load_lab

    hostile = [("$\\foo$ \u202eevil\u202c <script>alert(1)</script>", "a b $x^2$ \\textbf{b}", None),
               ("x" * 2000, "名" * 300, None),
               ("ok", "a\x00b\x1bc", "instrument.serial"), ("x" * 20_000, "s", "laboratory.name")]
    rep = full_report
    for i, (name, serial, refused_key) in enumerate(hostile):
        lab = LAB_TEXT
        for key, val in (("name", name), ("serial", serial)):
            lab = "\n".join((f'{key} = {json.dumps(val)}' if ln.startswith(f"{key} =") else ln)
                            for ln in lab.splitlines())
        lp = tmp_path / f"lab{i}.toml"
        lp.write_text(lab)
        if refused_key is not None:
            assert f"key {refused_key}" in str(api_error(load_lab, lp))
            count(f"cert-text:{i}:refused")
            continue
        with deadline(60):
            paths = write_outputs(rep, tmp_path / f"o{i}", lab=load_lab(lp))
        page = paths["certificate.html"].read_text()
        assert "<script>" not in page and "\u202e" not in page
        if name.startswith("$"):
            assert "$\\foo$" in page and "&lt;script&gt;" in page
        else:
            assert "x" * 2000 in page
        count(f"cert-text:{i}:name")
        count(f"cert-text:{i}:serial")


# ----------------------------------------------------------------------------- determinism

def test_plots_and_truth_are_byte_stable(tmp_path):
    from gonio.specs.ogam_draft.bench import run_session, write_session
    from gonio.specs.ogam_draft.pages import equal_division_figure
    from gonio.report.figure_files import save_figure

    def plot_eda(res, path):
        return save_figure(equal_division_figure(res), path)
    from gonio.specs.ogam_draft.equal_division import equal_division_analysis, simulate_eda_matrix

    sim = simulate_eda_matrix({1: 1.0}, {2: 0.2}, 8, 8, 1, 0.05, 0)
    res = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg)
    for fmt in ("svg", "pdf", "png"):
        a = plot_eda(res, tmp_path / f"a.{fmt}").read_bytes()
        time.sleep(1.05 if fmt == "pdf" else 0)
        b = plot_eda(res, tmp_path / f"b.{fmt}").read_bytes()
        assert a == b, fmt
        count(f"determinism:eda-plot:{fmt}")
    proto = load_protocol(ROOT / "protocols/ogam-draft.toml").__class__
    mini = tmp_path / "m.toml"
    mini.write_text(MINI_PROTO)
    p = load_protocol(mini)
    bench_rel = os.path.relpath(ROOT / "protocols/benches/rlg.toml")
    s1 = run_session(p, load_bench(bench_rel), seed=1)
    s2 = run_session(p, load_bench(ROOT / "protocols/benches/../benches/rlg.toml"), seed=1)
    write_session(s1, tmp_path / "t1")
    write_session(s2, tmp_path / "t2")
    assert (tmp_path / "t1/truth.json").read_bytes() == (tmp_path / "t2/truth.json").read_bytes()
    assert str(ROOT) not in (tmp_path / "t1/truth.json").read_text()
    assert proto is not None
    count("determinism:truth-path")


def test_case_count_reported():
    """Kept last: the number of generated cases run in this module (README figure)."""
    assert len(CASES) > 300, len(CASES)
    print(f"\nreliability fuzz cases: {len(CASES)}")
