"""A result row keeps how its stored results.json states the item (``stated``, the interval's
rounded ends), written with the row when the result is stored, filled by the migration that
added it and by a restore of an older backup, and checked against the stored result wherever
the rows are (the seal, ``gonio db verify``): the instrument's history plot then draws from
the rows alone, the same bars the stored results give."""

from __future__ import annotations

import json

import pytest
from sqlalchemy import select, text

from gonio.errors import GonioError
from gonio.records import results, services
from gonio.records.backup import backup, restore
from gonio.records.db import MIGRATIONS, migrate, open_store
from gonio.records.models import ResultItem
from tests.statement_numbers import expected_cell, measured

from .conftest import make_people
from .test_records_backup import archive_without
from .test_records_services import new_calibration, run_worker, setup_instrument
from .test_web_security import app, login  # noqa: F401  (the app fixture)

STATEMENT = ("stated", "interval_low", "interval_high")


def computed(store, computed_folder, bench_readings, monkeypatch):
    people = make_people(store)
    inst, std = setup_instrument(store, people)
    new_calibration(store, people, inst, std, bench_readings[0])
    return run_worker(store, monkeypatch, computed_folder)


def kept(store, cal_id) -> dict:
    """Item key → its row's statement columns."""
    with store.session() as s:
        return {r.key: tuple(getattr(r, c) for c in STATEMENT)
                for r in s.scalars(select(ResultItem).where(
                    ResultItem.calibration_id == cal_id).order_by(ResultItem.id))}


def from_the_page(doc: dict) -> dict:
    """Item key → the statement columns its certificate's statement gives (worked out from the
    item's numbers by tests.statement_numbers, not by the records' code)."""
    from gonio.report.dcc import dsi_decimal

    out = {}
    for key, it in measured(doc).items():
        ends = expected_cell(it).get("interval")
        out[key] = ("value", None, None) if ends is None else (
            "interval", *(float(dsi_decimal(x.replace("\u2212", "-"))) for x in ends))
    return out


def test_rows_keep_the_stored_statement_and_the_plot_reads_no_result(
        store, computed_folder, bench_readings, monkeypatch):
    cal = computed(store, computed_folder, bench_readings, monkeypatch)
    doc = json.loads((computed_folder / "results.json").read_text())
    rows, want = kept(store, cal.id), from_the_page(doc)
    assert sum(v[0] == "interval" for v in want.values()) >= 2        # the check can fail
    for key, cols in want.items():
        assert rows[key][0] == cols[0], key
        if cols[1] is None:                   # stated by its value: no interval ends
            assert rows[key][1:] == (None, None), key
        else:
            assert rows[key][1:] == pytest.approx(cols[1:], rel=1e-12), key
    assert all(v[0] in ("value", "none") for k, v in rows.items() if k not in want)
    # the plot's history: no stored result read (every reader of one refuses)
    monkeypatch.setattr(results, "stored_columns", lambda *a: pytest.fail("read a result"))
    hist = services.history(store, cal.instrument_id)
    for key, cols in rows.items():
        (row,) = hist[key]
        assert row["interval"] == (cols[1:] if cols[0] == "interval" else None), key


def test_a_changed_statement_is_detected_and_an_unkept_one_read(
        store, computed_folder, bench_readings, monkeypatch):
    cal = computed(store, computed_folder, bench_readings, monkeypatch)
    signed = services.seal(store, cal.id)
    hist = services.history(store, cal.instrument_id)
    key = next(k for k, v in kept(store, cal.id).items() if v[0] == "interval")
    with store.writing() as s:
        s.execute(text("UPDATE result_items SET interval_high = interval_high * 2 "
                       "WHERE key = :k AND calibration_id = :c"), {"k": key, "c": cal.id})
        s.commit()
    with pytest.raises(GonioError, match=f"row {key} differs from the stored results"):
        services.seal(store, cal.id)
    # a row keeping no statement (written before rows kept it) is read from its stored
    # result: the same bars, the same seal (the statement is checked, not hashed)
    with store.writing() as s:
        s.execute(text("UPDATE result_items SET stated = NULL, interval_low = NULL, "
                       "interval_high = NULL WHERE calibration_id = :c"), {"c": cal.id})
        s.commit()
    results._INTERVALS.clear()
    assert services.seal(store, cal.id) == signed
    assert services.history(store, cal.instrument_id) == hist


def _downgrade(engine, revision: str) -> None:
    from alembic import command
    from alembic.config import Config

    cfg = Config()
    cfg.set_main_option("script_location", str(MIGRATIONS))
    sqlite = engine.dialect.name == "sqlite"
    with engine.connect() as conn:
        raw = conn.connection.dbapi_connection   # autocommit: no BEGIN before the PRAGMA
        if sqlite:      # SQLite's table rebuild (a referenced table dropped and copied back)
            raw.execute("PRAGMA foreign_keys=OFF")           # outside the transaction
        with conn.begin():
            cfg.attributes["connection"] = conn
            command.downgrade(cfg, revision)
        if sqlite:
            assert raw.execute("PRAGMA foreign_key_check").fetchall() == []
            raw.execute("PRAGMA foreign_keys=ON")


def test_the_migration_fills_the_rows_of_older_records(store, computed_folder, bench_readings,
                                                       monkeypatch):
    """Records written before rows kept their statement (schema 0007) open at the head with
    every row filled from its stored results.json, as a newly stored result writes it; the
    seals signed before stay the seals."""
    cal = computed(store, computed_folder, bench_readings, monkeypatch)
    rows, signed = kept(store, cal.id), services.seal(store, cal.id)
    _downgrade(store.engine, "0007")
    with store.engine.connect() as c:
        assert "stated" not in [col for col in c.execute(text(
            "SELECT * FROM result_items")).keys()]
    url, data = store.url, store.data
    store.close()
    again = open_store(None if url.startswith("sqlite") else url, data)
    try:
        assert kept(again, cal.id) == rows
        assert services.seal(again, cal.id) == signed
        # without the blob store the rows are left None (the history then reads them)
        _downgrade(again.engine, "0007")
        migrate(again.engine)
        assert set(kept(again, cal.id).values()) == {(None, None, None)}
    finally:
        again.close()


def test_backup_carries_the_statement_and_an_older_backup_is_filled(
        sqlite_store, computed_folder, bench_readings, monkeypatch, tmp_path):
    cal = computed(sqlite_store, computed_folder, bench_readings, monkeypatch)
    rows = kept(sqlite_store, cal.id)
    full = tmp_path / "full.zip"
    backup(sqlite_store, full)
    doc = json.loads(__import__("zipfile").ZipFile(full).read("records.json"))
    table = doc["tables"]["result_items"]
    assert set(STATEMENT) <= set(table["columns"])

    def older(d):                      # the archive an older gonio wrote: no such columns
        t = d["tables"]["result_items"]
        keep = [i for i, c in enumerate(t["columns"]) if c not in STATEMENT]
        t["columns"] = [t["columns"][i] for i in keep]
        t["rows"] = [[r[i] for i in keep] for r in t["rows"]]
        return d

    old = archive_without(full, tmp_path / "old.zip", records_json=older)
    for i, archive in enumerate((full, old)):
        target = open_store(None, tmp_path / f"target{i}")
        try:
            restore(target, archive)
            assert kept(target, cal.id) == rows, archive.name
        finally:
            target.close()


def test_fill_stated_reads_each_result_once_and_keeps_what_it_cannot_read(tmp_path,
                                                                          computed_folder):
    from gonio.records import blobs

    body = (computed_folder / "results.json").read_bytes()
    sha = blobs.put_bytes(tmp_path, body)
    want = results.stated_columns(json.loads(body))
    rows = [{"key": k} for k in want] + [{"key": "no such item"}, {"key": "x", "stated": "value"},
                                         {"key": next(iter(want)), "gone": True}]
    n = results.fill_stated(tmp_path, rows, lambda r: "f" * 64 if r.get("gone") else sha)
    assert n == len(want) + 1
    assert [{c: r[c] for c in STATEMENT} for r in rows[:len(want)]] == list(want.values())
    assert rows[-3]["stated"] == "none" and rows[-2]["stated"] == "value"
    assert {c: rows[-1][c] for c in STATEMENT} == dict.fromkeys(STATEMENT)


def test_the_figure_is_drawn_again_when_a_kept_statement_changes(
        app, sqlite_store, computed_folder, bench_readings, monkeypatch):  # noqa: F811
    """The web figure is kept per content of the history (its cache key): a changed row's
    bar is drawn, the old figure is served again for the old content."""
    people = {n: services.user(sqlite_store, n) for n in ("tech", "rev", "admin")}
    inst, std = setup_instrument(sqlite_store, people)
    new_calibration(sqlite_store, people, inst, std, bench_readings[0])
    cal = run_worker(sqlite_store, monkeypatch, computed_folder)
    key = next(k for k, v in kept(sqlite_store, cal.id).items() if v[0] == "interval")
    web, url = login(app, "tech"), f"/instruments/{inst.id}/history.svg"

    def scale(f):
        with sqlite_store.writing() as s:
            s.execute(text(f"UPDATE result_items SET interval_high = interval_high * {f} "
                           "WHERE key = :k"), {"k": key})
            s.commit()

    before = web.get(url).text
    scale(4)
    after = web.get(url).text
    scale(0.25)
    assert after != before and web.get(url).text == before
