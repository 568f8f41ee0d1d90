"""The calibration date of an imported run (docs/records.md, importing an output folder): the
readings' ``date`` (which results.json carries and the recomputation checks), else the day of
the import (the laboratory's date) — never results.json's file time, which ``touch -d`` sets and which would
choose the standards and the table calibration in force on that day. On SQLite and on the
throwaway PostgreSQL, through the Python function and ``gonio db import``.

Truths from outside the code under test: the date written into the readings' text by the
test, the UTC date from the standard library's clock, a file time set by ``os.utime``."""

from __future__ import annotations

import datetime as dt
import json
import os
import shutil

from sqlalchemy import select

from gonio.records import services
from gonio.records.models import AuditEvent

from .conftest import PASSWORD, SMALL_PROTOCOL

#: 2025-01-15 00:00 UTC as a file time: what ``touch -d 2025-01-15`` gives results.json
BACKDATED = dt.datetime(2025, 1, 15, tzinfo=dt.timezone.utc).timestamp()


def utc_today() -> dt.date:
    """The laboratory's date now in the zone a new store holds (this machine's zone, written
    when the store is made)."""
    from gonio.records import models
    return models.laboratory_date(models.utcnow(), models.machine_zone())


def backdated_copy(computed_folder, bench_readings, tmp_path):
    folder = tmp_path / "run"
    shutil.copytree(computed_folder, folder)
    shutil.copy(bench_readings[0], folder / "readings.csv")
    os.utime(folder / "results.json", (BACKDATED, BACKDATED))
    assert dt.date.fromtimestamp((folder / "results.json").stat().st_mtime) <= \
        dt.date(2025, 1, 15)
    assert "# date:" not in (folder / "readings.csv").read_text()     # undated readings
    return folder


def date_from(store, cal_id) -> str:
    with store.session() as s:
        ev = s.scalar(select(AuditEvent).where(AuditEvent.action == "import",
                                               AuditEvent.entity_id == str(cal_id)))
        return json.loads(ev.after_json)["date_from"]


def test_undated_import_is_dated_the_import_day_not_the_file_time(store, people,
                                                                  computed_folder,
                                                                  bench_readings, tmp_path):
    """Readings without a date, results.json's file time set to 2025-01-15: the calibration
    is dated today (UTC), and the audit trail says where the date came from."""
    from gonio.records.importer import import_output_folder

    folder = backdated_copy(computed_folder, bench_readings, tmp_path)
    before = utc_today()
    cid = import_output_folder(store, folder, protocol=SMALL_PROTOCOL, actor=people["tech"])
    cal = services.calibration(store, cid)
    assert cal.performed_on in (before, utc_today()) and cal.performed_on != dt.date(2025, 1,
                                                                                       15)
    assert date_from(store, cid) == "the import day (the readings give no date)"


def test_undated_import_on_the_command_line(store, people, computed_folder, bench_readings,
                                            tmp_path, capsys, monkeypatch):
    """``gonio db import`` of the backdated folder: exit 0, dated today (UTC)."""
    from gonio.cli import main

    monkeypatch.setenv("GONIO_PASSWORD", PASSWORD)
    folder = backdated_copy(computed_folder, bench_readings, tmp_path)
    where = ["--database", store.url] if not store.url.startswith("sqlite") else \
        ["--data", str(store.blob_root.parent)]
    before = utc_today()
    assert main(["db", "import", str(folder), "--protocol", str(SMALL_PROTOCOL), "--user",
                 "tech", *where]) == 0, capsys.readouterr().err
    cal = services.calibration(store, 1)
    assert cal.performed_on in (before, utc_today())


def test_dated_readings_give_the_date_whatever_the_file_time(store, people, bench_readings,
                                                             tmp_path):
    """Readings that say ``# date: 2026-11-20`` (computed into results.json, checked by the
    recomputation), results.json's file time 2025-01-15: dated 2026-11-20."""
    from gonio.records.compute import calibrate_folder
    from gonio.records.importer import import_output_folder

    text = bench_readings[0].read_text()
    dated = tmp_path / "dated.csv"
    dated.write_text("# date: 2026-11-20\n" + text)
    out = tmp_path / "out"
    calibrate_folder(dated, out, spec_key="ogam-draft", protocol=str(SMALL_PROTOCOL))
    os.utime(out / "results.json", (BACKDATED, BACKDATED))
    cid = import_output_folder(store, out, readings=dated, protocol=SMALL_PROTOCOL,
                               actor=people["tech"])
    assert services.calibration(store, cid).performed_on == dt.date(2026, 11, 20)
    assert date_from(store, cid) == "the readings' date"
