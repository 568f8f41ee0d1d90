"""The records tests' in-process memo of the pipeline (tests/records/pipeline_memo.py): the
same inputs, wherever they lie, give the stored output files without running the pipeline;
one changed byte of any input (readings, a file beside them, protocol, laboratory file,
table calibration), another option, record, specification, ``GONIO_*`` variable runs it; an
output naming its folders is never kept; and the real pipeline gives the same bytes from
other folders, so a hit is what a run would have written.

Truths from outside the memo: a stub pipeline that counts its runs and writes the SHA-256 of
what it read (hashlib), and the real pipeline's own output files."""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import pytest

from .conftest import SMALL_PROTOCOL
from .pipeline_memo import memoised

pytestmark = pytest.mark.real_pipeline        # each test builds its own memo


def stub_pipeline(runs: list):
    """A pipeline that records each run and writes what it read, hashed."""
    def calibrate_folder(readings, out, *, spec_key, protocol=None, lab=None,
                         table_calibration=None, gyro_type=None, options=None, record=None):
        runs.append(Path(readings))
        h = hashlib.sha256(Path(readings).read_bytes())
        for f in (protocol, lab, table_calibration):
            h.update(Path(f).read_bytes() if f else b"-")
        h.update(repr((spec_key, gyro_type, options, record)).encode())
        out = Path(out)
        out.mkdir(parents=True)                  # a filled ``out`` is an error here
        (out / "tables").mkdir()
        (out / "results.json").write_text(h.hexdigest(), encoding="utf-8")
        (out / "tables" / "items.csv").write_text("a,b\n1,2\n", encoding="utf-8")
        return sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    return calibrate_folder


def inputs(root: Path) -> dict:
    """A readings folder (readings and a file they name), protocol, lab and table files."""
    root.mkdir(parents=True)
    (root / "in").mkdir()
    (root / "in" / "readings.csv").write_bytes(b"t_s,angle_deg\n0,1\n")
    (root / "in" / "static_record.csv").write_bytes(b"1\n2\n")
    for name in ("protocol.toml", "lab.toml", "table.csv"):
        (root / name).write_bytes(name.encode())
    return dict(readings=root / "in" / "readings.csv", spec_key="ogam-draft",
                protocol=str(root / "protocol.toml"), lab=root / "lab.toml",
                table_calibration=root / "table.csv", options={"a": 1},
                record={"gyro_type": "rlg"})


def call(memo_fn, kw: dict, out: Path):
    kw = dict(kw)
    return memo_fn(kw.pop("readings"), out, **kw)


def test_same_inputs_elsewhere_hit_and_give_the_same_files(tmp_path):
    runs, memo, stats = [], {}, {"hits": 0, "misses": 0}
    fn = memoised(stub_pipeline(runs), memo, stats)
    got1 = call(fn, inputs(tmp_path / "a"), tmp_path / "out1")
    got2 = call(fn, inputs(tmp_path / "b"), tmp_path / "out2")
    assert len(runs) == 1 and stats == {"hits": 1, "misses": 1}
    assert got1 == got2 == ["results.json", "tables/items.csv"]
    for name in got1:
        assert (tmp_path / "out1" / name).read_bytes() == (tmp_path / "out2" / name).read_bytes()


@pytest.mark.parametrize("change", ["readings", "beside", "protocol", "lab", "table", "options",
                                    "record", "spec", "env", "readings name"])
def test_a_changed_byte_or_argument_misses(tmp_path, monkeypatch, change):
    runs, memo = [], {}
    fn = memoised(stub_pipeline(runs), memo, {"hits": 0, "misses": 0})
    call(fn, inputs(tmp_path / "a"), tmp_path / "out1")
    kw = inputs(tmp_path / "b")
    if change == "readings":
        kw["readings"].write_bytes(kw["readings"].read_bytes().replace(b"1\n", b"2\n"))
    elif change == "beside":
        (kw["readings"].parent / "static_record.csv").write_bytes(b"1\n3\n")
    elif change in ("protocol", "lab", "table"):
        f = Path(kw["table_calibration" if change == "table" else change])
        f.write_bytes(f.read_bytes() + b" ")
    elif change == "options":
        kw["options"] = {"a": 2}
    elif change == "record":
        kw["record"] = {"gyro_type": "fog"}
    elif change == "spec":
        kw["spec_key"] = "jjf1535-2015"
    elif change == "env":
        monkeypatch.setenv("GONIO_MAX_WORKERS", "3")
    else:
        kw["readings"] = kw["readings"].rename(kw["readings"].with_name("r.csv"))
    call(fn, kw, tmp_path / "out2")
    assert len(runs) == 2, change


def test_an_output_naming_its_folder_is_not_kept_nor_a_filled_out(tmp_path):
    runs = []
    stub = stub_pipeline(runs)

    def naming(readings, out, **kw):
        got = stub(readings, out, **kw)
        (Path(out) / "summary.txt").write_text(f"read {readings}\n", encoding="utf-8")
        return got
    fn = memoised(naming, {}, {"hits": 0, "misses": 0})
    kw = inputs(tmp_path / "a")
    call(fn, kw, tmp_path / "out1")
    call(fn, kw, tmp_path / "out2")
    assert len(runs) == 2
    fn = memoised(stub, {}, {"hits": 0, "misses": 0})
    call(fn, kw, tmp_path / "out3")
    (tmp_path / "out4").mkdir()
    (tmp_path / "out4" / "old.txt").write_text("x", encoding="utf-8")
    with pytest.raises(FileExistsError):      # the stub's own answer: the memo stood aside
        call(fn, kw, tmp_path / "out4")


def test_the_real_pipeline_gives_the_same_bytes_from_other_folders(computed_folder,
                                                                   bench_readings, tmp_path):
    """computed_folder: the real pipeline on seed 1's readings (their simulation folder, the
    tests' protocol file); here the same readings and the file they name in another folder
    without the rest, the protocol copied elsewhere: through the memo the first run is real,
    the second (a third folder) a hit, and every file equals computed_folder's."""
    from gonio.records.compute import calibrate_folder

    real = getattr(calibrate_folder, "__wrapped__", calibrate_folder)
    stats = {"hits": 0, "misses": 0}
    fn = memoised(real, {}, stats)
    outs = []
    for name in ("b", "c"):
        (tmp_path / name / "in").mkdir(parents=True)
        for f in bench_readings[0].parent.iterdir():
            if f.name != "truth.json":
                shutil.copy(f, tmp_path / name / "in" / f.name)
        shutil.copy(SMALL_PROTOCOL, tmp_path / name / SMALL_PROTOCOL.name)
        outs.append(tmp_path / name / "out")
        fn(tmp_path / name / "in" / "readings.csv", outs[-1], spec_key="ogam-draft",
           protocol=str(tmp_path / name / SMALL_PROTOCOL.name))
    assert stats == {"hits": 1, "misses": 1}
    files = sorted(p.relative_to(computed_folder).as_posix()
                   for p in computed_folder.rglob("*") if p.is_file())
    assert len(files) > 5
    for out in outs:
        assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")
                      if p.is_file()) == files
        for name in files:
            assert (out / name).read_bytes() == (computed_folder / name).read_bytes(), name


@pytest.mark.parametrize("where", ["option file", "beside the lab file"])
def test_a_changed_file_an_option_or_the_lab_names_misses(tmp_path, where):
    """The same arguments, one byte changed in a file an option names (its path the same) or
    in a file beside the laboratory file (which may name it): the pipeline runs again."""
    runs = []
    fn = memoised(stub_pipeline(runs), {}, {"hits": 0, "misses": 0})
    kw = inputs(tmp_path / "a")
    named = tmp_path / "a" / ("t.csv" if where == "option file" else "named.csv")
    named.write_bytes(b"1\n")
    if where == "option file":
        kw["options"] = {"thermal": str(named)}
    call(fn, kw, tmp_path / "out1")
    call(fn, kw, tmp_path / "out2")
    assert len(runs) == 1                          # the same: a hit
    named.write_bytes(b"2\n")
    call(fn, kw, tmp_path / "out3")
    assert len(runs) == 2, where
