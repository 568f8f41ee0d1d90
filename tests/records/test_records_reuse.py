"""One measurement, one calibration: readings whose SHA-256 are already those of another
calibration that stands are refused on every path that records them — ``gonio db import``,
``gonio calibrate --record``, the service layer the web form and a bench use — with one line
naming that calibration (exit 2, nothing recorded), while the lineage of one calibration (its
review, approval, issue and amendment) goes on with the same readings
(``gonio.records.services.check_readings_unused``, docs/records.md)."""

from __future__ import annotations

import hashlib
import shutil
import sqlite3
from pathlib import Path

import pytest

from gonio.cli import main
from gonio.errors import GonioError
from gonio.records import services
from gonio.records.db import open_store

from .conftest import SMALL_PROTOCOL, make_people
from .test_records_sealed import certificates, issue
from .test_records_services import new_calibration, run_worker, setup_instrument


def _rows(data: Path) -> dict:
    """Every table's row count: what "nothing recorded" is checked against."""
    with sqlite3.connect(data / "records.sqlite3") as db:
        names = [r[0] for r in db.execute("select name from sqlite_master where type='table'")]
        return {n: db.execute(f'select count(*) from "{n}"').fetchone()[0] for n in names}


def _refused(argv, capsys) -> str:
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("gonio: error: ") and err.count("\n") == 1, err
    return err


def test_the_same_folder_imported_twice_is_refused(tmp_path, computed_folder, bench_readings,
                                                   capsys):
    data, folder = tmp_path / "data", tmp_path / "run"
    shutil.copytree(computed_folder, folder)
    shutil.copy(bench_readings[0], folder / "readings.csv")
    assert main(["db", "init", "--data", str(data)]) == 0
    imp = ["db", "import", str(folder), "--data", str(data), "--protocol", str(SMALL_PROTOCOL)]
    assert main(imp) == 0
    before = _rows(data)
    assert before["calibrations"] == 1
    sha = hashlib.sha256(bench_readings[0].read_bytes()).hexdigest()   # independent digest
    err = _refused(imp, capsys)
    assert f"SHA-256 {sha[:12]}" in err and "already those of calibration 1 (RLG-0001, " in err
    assert _rows(data) == before                           # nothing recorded, not even audit


def test_calibrate_record_twice_with_the_same_readings_is_refused(tmp_path, bench_readings,
                                                                  capsys):
    data = tmp_path / "data"
    argv = ["calibrate", str(bench_readings[1]), "--protocol", str(SMALL_PROTOCOL),
            "--record", "--data", str(data)]
    assert main(argv + ["--out", str(tmp_path / "a")]) == 0
    before = _rows(data)
    err = _refused(argv + ["--out", str(tmp_path / "b")], capsys)
    assert "already those of calibration 1 (RLG-0001, " in err
    assert _rows(data) == before
    # other readings (another seed) are another measurement
    assert main(["calibrate", str(bench_readings[0]), "--protocol", str(SMALL_PROTOCOL),
                 "--record", "--data", str(data), "--out", str(tmp_path / "c")]) == 0
    assert _rows(data)["calibrations"] == 2


def test_an_amendment_of_the_same_calibration_goes_on(tmp_path, computed_folder,
                                                      bench_readings, monkeypatch):
    store = open_store(None, tmp_path / "data")
    try:
        people = make_people(store)
        inst, std = setup_instrument(store, people)
        cal = new_calibration(store, people, inst, std, bench_readings[0])
        run_worker(store, monkeypatch, computed_folder)
        issue(store, people, cal, monkeypatch, computed_folder)
        (first,) = certificates(store)
        services.amend(store, people["rev2"], first.id, "customer address corrected")
        services.approve(store, people["rev"], cal.id)
        run_worker(store, monkeypatch, computed_folder)            # issued again, same readings
        _, second = certificates(store)
        assert second.replaces_id == first.id and second.calibration_id == cal.id
        # the service layer every path calls: the calibration's own readings are not
        # "another's"; a new calibration with them is refused, naming this one
        with store.session() as s:
            assert services.check_readings_unused(s, cal.readings_sha256,
                                                  other_than=cal.id) == []
            with pytest.raises(GonioError, match=rf"already those of calibration {cal.id} "
                                                 rf"\({inst.serial}, .*, issued\)"):
                services.check_readings_unused(s, cal.readings_sha256)
        with pytest.raises(GonioError, match=f"already those of calibration {cal.id} "):
            new_calibration(store, people, inst, std, bench_readings[0])
        with store.session() as s:
            assert len(services.readings_used_by(s, cal.readings_sha256)) == 1
    finally:
        store.close()



def test_a_failed_calibration_holds_its_readings_until_voided(tmp_path, computed_folder,
                                                              bench_readings, monkeypatch):
    """A failed calibration stands for its readings (docs/records.md): it can be run again
    on them (``retry``), so a new calibration of the same readings is refused, naming it and
    saying to void it; its own retry goes on; once voided, the readings are free and a new
    calibration of them is recorded (a rejected one's too: the other closed state)."""
    store = open_store(None, tmp_path / "data")
    try:
        people = make_people(store)
        inst, std = setup_instrument(store, people)
        cal = new_calibration(store, people, inst, std, bench_readings[0])
        services.claim_next(store)
        services.fail(store, cal.id, "worker stopped")
        assert services.calibration(store, cal.id).status == "failed"
        with pytest.raises(GonioError, match=rf"already those of calibration {cal.id} "
                                             rf"\({inst.serial}, .*, failed\).*void it") as got:
            new_calibration(store, people, inst, std, bench_readings[0])
        assert got.value.key == services.REUSE_KEY
        with store.session() as s:                    # its own run again is not a re-use
            assert services.check_readings_unused(s, cal.readings_sha256,
                                                  other_than=cal.id) == []
        services.void(store, people["tech"], cal.id, "the chamber log was lost; run again")
        again = new_calibration(store, people, inst, std, bench_readings[0])
        assert again.status == "queued" and again.readings_sha256 == cal.readings_sha256
        with store.session() as s:                    # one standing calibration: the new one
            assert [r["id"] for r in services.readings_used_by(s, cal.readings_sha256)] == [
                again.id]
    finally:
        store.close()


def test_the_refusal_of_a_standing_calibration_has_no_void_hint(tmp_path, bench_readings):
    """The hint to void is said only of a failed calibration: a queued one (it will run)
    is refused with the plain message."""
    store = open_store(None, tmp_path / "data")
    try:
        people = make_people(store)
        inst, std = setup_instrument(store, people)
        cal = new_calibration(store, people, inst, std, bench_readings[0])
        with pytest.raises(GonioError, match=rf"calibration {cal.id} .*, queued\): the same "
                                             r"measurement is not calibrated twice$"):
            new_calibration(store, people, inst, std, bench_readings[0])
    finally:
        store.close()
