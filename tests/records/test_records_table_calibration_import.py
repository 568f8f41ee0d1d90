"""A command-line run made with ``gonio calibrate --table-calibration FILE`` (no laboratory
file) put into the records (docs/records.md#table-calibration): ``gonio db import`` keeps the
table calibration the run used or records nothing, and the seal refuses a result whose table
calibration the records do not keep. A table calibration that corrects a result is a
registered entry in force of a table among the calibration's standards: the imports that keep
the file tick the table RT-07 (a laboratory file's ``[[standards]]``) and are refused, nothing
recorded, until the file is registered.

Truths from outside the records: the file's SHA-256 by hashlib, the bytes written here, the
file name given to ``gonio calibrate``."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import pytest
from sqlalchemy import delete

from gonio.errors import GonioError
from gonio.records import services
from gonio.records.db import open_store
from gonio.records.models import CalibrationFile

from .conftest import make_people
from .test_records_table_calibration import IMPORT_LAB, SMALL_PROTOCOL, TABLE, register_table
from .test_web_lab_file import instrument as bare_instrument
from .test_web_lab_file import n_calibrations

SHA = hashlib.sha256(TABLE).hexdigest()
NAME = "RT-07 table cal.csv"          # the user's own file name, with a space
#: the laboratory file ticking the table RT-07 (its ``[[standards]]``) and naming no table
#: calibration: the run's file is the one given with --table-calibration or found in the folder
LAB_TICKS_TABLE = IMPORT_LAB.split("[table_calibration]")[0]
assert 'identifier = "RT-07"' in LAB_TICKS_TABLE and "sha256" not in LAB_TICKS_TABLE
REGISTER = "gonio db register-table-calibration"


@pytest.fixture(scope="module")
def cli_run(bench_readings, tmp_path_factory):
    """``gonio calibrate READINGS --table-calibration NAME`` into a folder: (folder, readings,
    the table calibration file)."""
    from gonio.cli import main

    root = tmp_path_factory.mktemp("tcrun")
    tc = root / NAME
    tc.write_bytes(TABLE)
    out = root / "run"
    assert main(["calibrate", str(bench_readings[0]), "--protocol", str(SMALL_PROTOCOL),
                 "--table-calibration", str(tc), "--out", str(out)]) == 0
    return out, Path(bench_readings[0]), tc


def _import(data: Path, folder: Path, readings: Path, *extra: str) -> int:
    from gonio.cli import main

    return main(["db", "import", str(folder), "--data", str(data), "--readings", str(readings),
                 "--protocol", str(SMALL_PROTOCOL), *extra])


def _with_table(st) -> None:
    """The records' people, the bench's instrument and the table RT-07 (a registered
    standard), whose register holds no calibration yet."""
    make_people(st)
    bare_instrument(st)


def _store_with_table(data: Path) -> None:
    """:func:`_with_table` in the records at ``data``."""
    st = open_store(None, data)
    try:
        _with_table(st)
    finally:
        st.close()


def _register(data: Path) -> int:
    """TABLE registered as RT-07's calibration in force (under another name than the user's
    file: the name kept is the one the run read it under); the entry's id."""
    st = open_store(None, data)
    try:
        return register_table(st, TABLE, "RT-07 cal.csv").id
    finally:
        st.close()


def _lab(where: Path) -> Path:
    """:data:`LAB_TICKS_TABLE` written into ``where``."""
    lab = where / "ticks-table.toml"
    lab.write_text(LAB_TICKS_TABLE, encoding="utf-8")
    return lab


def _one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("gonio: error: ") and err.count("\n") == 1, err
    return err


@pytest.fixture
def refused_until_registered(capsys):
    """``check(attempt, data)``: ``attempt()`` (a command line's exit code, or an API call)
    while the register at ``data`` does not hold the run's table calibration is refused —
    exit 2 with one line, or one GonioError line — naming the register command and the
    file's digest, and nothing is recorded; then the file is registered (:func:`_register`)
    and the entry's id returned."""
    def check(attempt, data: Path) -> int:
        capsys.readouterr()
        try:
            assert attempt() == 2
            msg = _one_line(capsys)
        except GonioError as exc:
            msg = str(exc)
            assert "\n" not in msg, msg
        assert "not in the register" in msg and REGISTER in msg and SHA[:16] in msg, msg
        st = open_store(None, data)
        try:
            assert n_calibrations(st) == 0
        finally:
            st.close()
        return _register(data)
    return check


def test_the_run_records_the_file_it_used(cli_run):
    """The premise, checked from outside: the run's results.json records the file's hashlib
    digest and the name it was given under; the output folder holds no copy of it."""
    out, _, _ = cli_run
    res = json.loads((out / "results.json").read_text(encoding="utf-8"))
    d = res["items"]["scale_factor"]["details"]["table_calibration"]
    assert d["sha256"] == SHA and d["source"] == NAME
    assert not any(p.read_bytes() == TABLE for p in out.rglob("*") if p.is_file())


def test_import_without_the_file_refused(cli_run, tmp_path, capsys):
    """No --table-calibration, no laboratory file naming it, no copy in the folder: exit 2,
    one line naming the file the run used and the option that supplies it; nothing
    recorded."""
    out, readings, _ = cli_run
    data = tmp_path / "data"
    capsys.readouterr()
    assert _import(data, out, readings) == 2
    err = _one_line(capsys)
    assert NAME in err and SHA[:16] in err and "--table-calibration" in err, err
    st = open_store(None, data)
    try:
        assert n_calibrations(st) == 0
    finally:
        st.close()


def test_import_with_another_file_refused(cli_run, tmp_path, capsys):
    """--table-calibration with other bytes than the run used: exit 2, one line naming both
    digests' heads; nothing recorded."""
    out, readings, _ = cli_run
    other = TABLE.replace(b"0.02\n", b"0.03\n", 1)
    f = tmp_path / NAME
    f.write_bytes(other)
    data = tmp_path / "data"
    capsys.readouterr()
    assert _import(data, out, readings, "--table-calibration", str(f)) == 2
    err = _one_line(capsys)
    assert hashlib.sha256(other).hexdigest()[:16] in err and SHA[:16] in err, err
    assert "results.json was computed with" in err
    st = open_store(None, data)
    try:
        assert n_calibrations(st) == 0
    finally:
        st.close()


def test_import_with_the_file_keeps_it_and_seals(cli_run, tmp_path, capsys,
                                                 refused_until_registered):
    """--table-calibration FILE (the run's bytes), the table ticked (--lab's [[standards]]):
    while the register does not hold the file, exit 2, one line naming the register command,
    nothing recorded; once it is registered, exit 0, the calibration keeps the file (hashlib
    digest, the same bytes) under the user's file name, which the certificate rendered from
    the record names as the run's did; the seal holds; the seal then refuses once the kept
    file is taken away, one line naming the calibration and the missing file."""
    from gonio.records.compute import render_folder, write_lab_toml

    out, readings, tc = cli_run
    data = tmp_path / "data"
    _store_with_table(data)
    lab = _lab(tmp_path)
    entry = refused_until_registered(lambda: _import(
        data, out, readings, "--table-calibration", str(tc), "--lab", str(lab)), data)
    assert _import(data, out, readings, "--table-calibration", str(tc), "--lab", str(lab)) == 0
    capsys.readouterr()
    st = open_store(None, data)
    try:
        assert n_calibrations(st) == 1
        (cal,) = [services.calibration(st, 1)]
        assert cal.table_calibration_id == entry     # the registered entry in force is used
        with st.session() as s:
            assert s.get(CalibrationFile, (cal.id, "table_calibration.csv")).sha256 == SHA
        assert services.file_bytes(st, SHA) == TABLE
        assert services.seal(st, cal.id)
        # the name kept is the file's own, and a record's certificate names it as the run did
        with st.session() as s:
            assert services.table_calibration_name(s, cal.id) == NAME
        lab = write_lab_toml(services.lab_details(st, cal.id, final=False, redraft=True),
                             tmp_path / "lab.toml")
        render_folder(services.file_bytes(st, cal.results_sha256), tmp_path / "r",
                      spec_key="ogam-draft", lab=lab)
        html = (tmp_path / "r" / "certificate.html").read_text(encoding="utf-8")
        assert NAME in html and "table_calibration.csv" not in html
        # a recorded name that is not a plain file name is never used as one
        for bad in ("../evil.csv", "lab.toml [table_calibration]", "a\nb.csv", ""):
            with st.writing() as s:
                services.audit(s, None, "table-calibration", "calibration", cal.id, None,
                               {"sha256": SHA, "name": bad})
                s.commit()
            with st.session() as s:
                assert services.table_calibration_name(s, cal.id) == "table_calibration.csv"
        with st.writing() as s:
            s.execute(delete(CalibrationFile).where(
                CalibrationFile.calibration_id == cal.id,
                CalibrationFile.name == "table_calibration.csv"))
            s.commit()
        with pytest.raises(GonioError) as exc:
            services.seal(st, cal.id)
        msg = str(exc.value)
        assert "\n" not in msg and f"calibration {cal.id}" in msg, msg
        assert "table_calibration.csv" in msg and SHA[:16] in msg, msg
    finally:
        st.close()


def test_import_takes_a_copy_in_the_folder(cli_run, tmp_path, refused_until_registered):
    """A copy of the file under the name the run used, put in the output folder, the table
    ticked (the laboratory file's [[standards]]): while the register does not hold the file
    the import is refused, one line naming the register command, nothing recorded; once it
    is registered, the copy is taken (its digest checked) under the user's name, with the
    registered entry; a copy with other bytes under that name is not, and the import is
    refused."""
    from gonio.records.importer import import_output_folder

    out, readings, _ = cli_run
    folder = tmp_path / "run"
    shutil.copytree(out, folder)
    (folder / NAME).write_bytes(TABLE)
    lab = _lab(tmp_path)
    st = open_store(None, tmp_path / "data")
    try:
        _with_table(st)                                     # the table RT-07, nothing registered
        entry = refused_until_registered(lambda: import_output_folder(
            st, folder, readings=readings, protocol=SMALL_PROTOCOL, lab=lab), tmp_path / "data")
        (folder / NAME).write_bytes(TABLE + b"\n")
        with pytest.raises(GonioError, match="not in the folder: give it with "
                                             "--table-calibration"):
            import_output_folder(st, folder, readings=readings, protocol=SMALL_PROTOCOL,
                                 lab=lab)
        assert n_calibrations(st) == 0
        (folder / NAME).write_bytes(TABLE)
        cid = import_output_folder(st, folder, readings=readings, protocol=SMALL_PROTOCOL,
                                   lab=lab)
        with st.session() as s:
            assert s.get(CalibrationFile, (cid, "table_calibration.csv")).sha256 == SHA
            assert services.table_calibration_name(s, cid) == NAME
        assert services.calibration(st, cid).table_calibration_id == entry
        assert services.seal(st, cid)
    finally:
        st.close()


def test_table_calibration_for_a_run_that_used_none_refused(cli_run, bench_readings, tmp_path):
    """--table-calibration for a folder whose results.json records none: refused, one line."""
    from gonio.cli import main
    from gonio.records.importer import import_output_folder

    _, _, tc = cli_run
    out = tmp_path / "plain"
    assert main(["calibrate", str(bench_readings[1]), "--protocol", str(SMALL_PROTOCOL),
                 "--out", str(out)]) == 0
    st = open_store(None, tmp_path / "data")
    try:
        with pytest.raises(GonioError, match="records no table calibration"):
            import_output_folder(st, out, readings=bench_readings[1], protocol=SMALL_PROTOCOL,
                                 table_calibration=tc)
        assert n_calibrations(st) == 0
    finally:
        st.close()


def test_calibrate_record_keeps_the_file(bench_readings, tmp_path, monkeypatch, capsys,
                                        refused_until_registered):
    """``gonio calibrate --table-calibration FILE --lab LAB --record``, the table ticked (the
    laboratory file's [[standards]]): while the register does not hold the file, exit 2, one
    line naming the register command, nothing recorded and no output folder written (no
    certificate of a refused calibration); once registered, the calibration
    recorded keeps the file the run used (hashlib digest) under the user's name, the
    registered entry, and seals."""
    from gonio.cli import main

    monkeypatch.delenv("GONIO_USER", raising=False)
    tc = tmp_path / NAME
    tc.write_bytes(TABLE)
    data = tmp_path / "data"
    _store_with_table(data)
    lab = _lab(tmp_path)

    def record(out: str) -> int:
        return main(["calibrate", str(bench_readings[1]), "--protocol", str(SMALL_PROTOCOL),
                     "--table-calibration", str(tc), "--lab", str(lab),
                     "--out", str(tmp_path / out), "--record", "--data", str(data)])

    entry = refused_until_registered(lambda: record("run0"), data)
    assert not (tmp_path / "run0").exists()      # refused by the records: no certificate left
    assert record("run") == 0
    st = open_store(None, data)
    try:
        assert n_calibrations(st) == 1
        with st.session() as s:
            assert s.get(CalibrationFile, (1, "table_calibration.csv")).sha256 == SHA
            assert services.table_calibration_name(s, 1) == NAME
        assert services.calibration(st, 1).table_calibration_id == entry
        assert services.seal(st, 1)
    finally:
        st.close()
