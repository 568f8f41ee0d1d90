"""The records tests' in-process memos of the pipeline and of the certificate's rendering
(tests/records/pipeline_memo.py). The pipeline's: the
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
from .pipeline_memo import SessionMemo, memoised, memoised_render

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


def same_outputs(tmp_path: Path, got1: list, got2: list) -> None:
    """Two calls wrote the stub's two files, out1's bytes the same as out2's."""
    assert got1 == got2 == ["results.json", "tables/items.csv"]
    for name in got1:
        assert (tmp_path / "out1" / name).read_bytes() == (tmp_path / "out2" / name).read_bytes()


def test_same_inputs_elsewhere_hit_and_give_the_same_files(tmp_path):
    runs, memo, stats = [], {}, {"hits": 0, "misses": 0}
    fn = memoised(stub_pipeline(runs), memo, stats)
    got1 = call(fn, inputs(tmp_path / "a"), tmp_path / "out1")
    got2 = call(fn, inputs(tmp_path / "b"), tmp_path / "out2")
    assert len(runs) == 1 and stats == {"hits": 1, "misses": 1}
    same_outputs(tmp_path, got1, got2)


def test_session_memo_shared_by_processes_and_a_changed_byte_misses(tmp_path):
    """Two processes of one session (each its own dict, one shared folder): what one ran the
    other reads without running (the same files, the same return value); another readings
    byte runs again in either; an unreadable entry is a miss, never an error."""
    runs, folder = [], tmp_path / "shared"
    first = memoised(stub_pipeline(runs), SessionMemo(folder, {}), {"hits": 0, "misses": 0})
    stats = {"hits": 0, "misses": 0}
    second = memoised(stub_pipeline(runs), SessionMemo(folder, {}), stats)
    got1 = call(first, inputs(tmp_path / "a"), tmp_path / "out1")
    got2 = call(second, inputs(tmp_path / "b"), tmp_path / "out2")
    assert len(runs) == 1 and stats == {"hits": 1, "misses": 0}
    same_outputs(tmp_path, got1, got2)
    kw = inputs(tmp_path / "c")
    kw["readings"].write_bytes(kw["readings"].read_bytes().replace(b"1\n", b"2\n"))
    call(second, kw, tmp_path / "out3")
    assert len(runs) == 2
    for p in folder.iterdir():
        p.write_bytes(b"not a pickle")
    call(memoised(stub_pipeline(runs), SessionMemo(folder, {}), {"hits": 0, "misses": 0}),
         inputs(tmp_path / "d"), tmp_path / "out4")
    assert len(runs) == 3


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


# --- the rendering's memo: the same stored result, laboratory file (and the files beside
# it), specification and language, wherever they lie, give the stored files; one changed
# byte or argument renders again; an output naming its folders is not kept; the real
# renderer gives the same bytes from other folders.

def stub_render(runs: list):
    """A renderer that records each run and writes what it read, hashed."""
    def render_folder(results, out, *, spec_key, lab, lang="en"):
        runs.append(Path(lab))
        h = hashlib.sha256(bytes(results) + Path(lab).read_bytes())
        h.update(repr((spec_key, lang)).encode())
        out = Path(out)
        out.mkdir(parents=True)                  # a filled ``out`` is an error here
        (out / "certificate.html").write_text(h.hexdigest(), encoding="utf-8")
        return ["certificate.html"]
    return render_folder


def render_inputs(root: Path) -> dict:
    root.mkdir(parents=True)
    (root / "lab.toml").write_bytes(b"[laboratory]\nname = 'L'\n")
    (root / "logo.svg").write_bytes(b"<svg/>")
    return dict(results=b'{"items": {}}', spec_key="ogam-draft", lab=root / "lab.toml",
                lang="en")


def render_call(fn, kw: dict, out: Path):
    kw = dict(kw)
    return fn(kw.pop("results"), out, **kw)


def test_render_same_inputs_elsewhere_hit_and_give_the_same_files(tmp_path):
    runs, stats = [], {"hits": 0, "misses": 0}
    fn = memoised_render(stub_render(runs), {}, stats)
    got1 = render_call(fn, render_inputs(tmp_path / "a"), tmp_path / "out1")
    got2 = render_call(fn, render_inputs(tmp_path / "b"), tmp_path / "out2")
    assert len(runs) == 1 and stats == {"hits": 1, "misses": 1}
    assert got1 == got2 == ["certificate.html"]
    assert (tmp_path / "out1" / "certificate.html").read_bytes() == \
        (tmp_path / "out2" / "certificate.html").read_bytes()


@pytest.mark.parametrize("change", ["results", "lab", "beside", "spec", "lang", "env"])
def test_render_a_changed_byte_or_argument_misses(tmp_path, monkeypatch, change):
    runs = []
    fn = memoised_render(stub_render(runs), {}, {"hits": 0, "misses": 0})
    render_call(fn, render_inputs(tmp_path / "a"), tmp_path / "out1")
    kw = render_inputs(tmp_path / "b")
    if change == "results":
        kw["results"] = b'{"items": {"K": 1}}'
    elif change == "lab":
        kw["lab"].write_bytes(kw["lab"].read_bytes() + b" ")
    elif change == "beside":
        (kw["lab"].parent / "logo.svg").write_bytes(b"<svg />")
    elif change == "spec":
        kw["spec_key"] = "jjf1535-2015"
    elif change == "lang":
        kw["lang"] = "zh"
    else:
        monkeypatch.setenv("GONIO_MAX_WORKERS", "3")
    render_call(fn, kw, tmp_path / "out2")
    assert len(runs) == 2, change


def test_render_output_naming_its_folder_is_not_kept_nor_a_filled_out(tmp_path):
    runs = []
    stub = stub_render(runs)

    def naming(results, out, **kw):
        got = stub(results, out, **kw)
        (Path(out) / "certificate.html").write_text(f"lab {kw['lab']}", encoding="utf-8")
        return got
    fn = memoised_render(naming, {}, {"hits": 0, "misses": 0})
    kw = render_inputs(tmp_path / "a")
    render_call(fn, kw, tmp_path / "out1")
    render_call(fn, kw, tmp_path / "out2")
    assert len(runs) == 2
    fn = memoised_render(stub, {}, {"hits": 0, "misses": 0})
    render_call(fn, kw, tmp_path / "out3")
    (tmp_path / "out4").mkdir()
    (tmp_path / "out4" / "old.txt").write_text("x", encoding="utf-8")
    with pytest.raises(FileExistsError):      # the stub's own answer: the memo stood aside
        render_call(fn, kw, tmp_path / "out4")


def test_the_real_renderer_gives_the_same_bytes_from_other_folders(computed_folder, tmp_path):
    """computed_folder's results.json rendered with the example laboratory file
    (protocols/lab-example.toml without its decision rule and limits: the computed folder was
    decided without them) in two other folders through the memo (the second a hit), and once
    more by the real renderer without it: every file of the three folders is byte for byte
    the same."""
    from gonio.records.compute import render_folder

    real = getattr(render_folder, "__wrapped__", render_folder)
    stats = {"hits": 0, "misses": 0}
    fn = memoised_render(real, {}, stats)
    results = (computed_folder / "results.json").read_bytes()
    example = (SMALL_PROTOCOL.parents[2] / "protocols" / "lab-example.toml").read_text("utf-8")
    example = example[:example.index("\n# Statement of conformity") + 1]
    outs = []
    for name in ("b", "c", "d"):
        (tmp_path / name).mkdir()
        lab = tmp_path / name / "lab.toml"
        lab.write_text(example, encoding="utf-8")
        outs.append(tmp_path / name / "out")
        (fn if name != "d" else real)(results, outs[-1], spec_key="ogam-draft", lab=lab)
    assert stats == {"hits": 1, "misses": 1}
    files = sorted(p.relative_to(outs[2]).as_posix() for p in outs[2].rglob("*")
                   if p.is_file())
    assert "certificate.pdf" in files and "certificate.html" in files
    for out in outs[:2]:
        assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")
                      if p.is_file()) == files
        for name in files:
            assert (out / name).read_bytes() == (outs[2] / name).read_bytes(), name
