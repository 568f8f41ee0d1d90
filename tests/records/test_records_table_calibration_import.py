"""A command-line run made with ``gonio calibrate --table-calibration FILE`` (no laboratory
file) put into the records (docs/records.md#table-calibration): ``gonio db import`` keeps the
table calibration the run used or records nothing, and the seal refuses a result whose table
calibration the records do not keep.

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

from .test_records_table_calibration import SMALL_PROTOCOL, TABLE
from .test_web_lab_file import n_calibrations

SHA = hashlib.sha256(TABLE).hexdigest()
NAME = "RT-07 table cal.csv"          # the user's own file name, with a space


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


def _one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("gonio: error: ") and err.count("\n") == 1, err
    return err


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


def test_import_with_the_file_keeps_it_and_seals(cli_run, tmp_path, capsys):
    """--table-calibration FILE (the run's bytes): exit 0, the calibration keeps the file
    (hashlib digest, the same bytes) under the user's file name, which the certificate
    rendered from the record names as the run's did; the seal holds;
    the seal then refuses once the kept file is taken away, one line naming the calibration
    and the missing file."""
    from gonio.records.compute import render_folder, write_lab_toml

    out, readings, tc = cli_run
    data = tmp_path / "data"
    assert _import(data, out, readings, "--table-calibration", str(tc)) == 0
    capsys.readouterr()
    st = open_store(None, data)
    try:
        (cal,) = [services.calibration(st, 1)]
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


def test_import_takes_a_copy_in_the_folder(cli_run, tmp_path):
    """A copy of the file under the name the run used, put in the output folder, is taken
    (its digest checked); a copy with other bytes under that name is not, and the import is
    refused."""
    from gonio.records.importer import import_output_folder

    out, readings, _ = cli_run
    folder = tmp_path / "run"
    shutil.copytree(out, folder)
    (folder / NAME).write_bytes(TABLE + b"\n")
    st = open_store(None, tmp_path / "data")
    try:
        with pytest.raises(GonioError, match="not in the folder: give it with "
                                             "--table-calibration"):
            import_output_folder(st, folder, readings=readings, protocol=SMALL_PROTOCOL)
        assert n_calibrations(st) == 0
        (folder / NAME).write_bytes(TABLE)
        cid = import_output_folder(st, folder, readings=readings, protocol=SMALL_PROTOCOL)
        with st.session() as s:
            assert s.get(CalibrationFile, (cid, "table_calibration.csv")).sha256 == SHA
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


def test_calibrate_record_keeps_the_file(bench_readings, tmp_path, monkeypatch):
    """``gonio calibrate --table-calibration FILE --record``: the calibration recorded keeps
    the file the run used (hashlib digest) and seals."""
    from gonio.cli import main

    monkeypatch.delenv("GONIO_USER", raising=False)
    tc = tmp_path / NAME
    tc.write_bytes(TABLE)
    data = tmp_path / "data"
    assert main(["calibrate", str(bench_readings[1]), "--protocol", str(SMALL_PROTOCOL),
                 "--table-calibration", str(tc), "--out", str(tmp_path / "run"), "--record",
                 "--data", str(data)]) == 0
    st = open_store(None, data)
    try:
        with st.session() as s:
            assert s.get(CalibrationFile, (1, "table_calibration.csv")).sha256 == SHA
            assert services.table_calibration_name(s, 1) == NAME
        assert services.seal(st, 1)
    finally:
        st.close()
