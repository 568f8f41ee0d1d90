"""One measurement, one calibration, whatever its bytes: readings that differ from another
standing calibration's only in how they are written (a newline added, CRLF line ends, a
metadata line edited, rows or columns in another order, a number re-spelt) are refused as the
same measurement on every path that records them; readings with one value changed are
another measurement (``gonio.formats.content``, ``services.check_readings_unused``,
docs/records.md)."""

from __future__ import annotations

import csv
import io
import json
import sqlite3
import zipfile
from pathlib import Path

import pytest

from gonio.cli import main
from gonio.errors import GonioError
from gonio.formats.content import content_sha256
from gonio.records import services
from gonio.records.db import open_store

from .conftest import SMALL_PROTOCOL, make_people
from .test_records_reuse import _refused, _rows
from .test_records_services import new_calibration, setup_instrument


def _split(text: str) -> tuple[list[str], list[str], list[str]]:
    lines = text.splitlines()
    head = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    return lines[:head], [lines[head]], [ln for ln in lines[head + 1:] if ln]


def rewritten(src: Path, how: str) -> bytes:
    """The same readings written otherwise (``how``), or with one count changed ("value")."""
    text = src.read_text(encoding="utf-8")
    meta, header, rows = _split(text)
    if how == "newline":
        return (text + "\n").encode()
    if how == "crlf":
        return text.replace("\n", "\r\n").encode()
    if how == "bom":
        return b"\xef\xbb\xbf" + text.encode()
    if how == "metadata":
        return "\n".join([m for m in meta if not m.startswith("# seed")]
                         + ["# note: copied from the lab PC"] + header + rows + [""]).encode()
    if how == "reversed":
        return "\n".join(meta + header + rows[::-1] + [""]).encode()
    if how == "columns":
        table = list(csv.reader(io.StringIO("\n".join(header + rows))))
        out = io.StringIO()
        csv.writer(out, lineterminator="\n").writerows([r[::-1] for r in table])
        return ("\n".join(meta) + "\n" + out.getvalue()).encode()
    if how == "respelt":            # a spreadsheet's re-save: 60.0 → 60, 120.0 → 1.2E2
        return "\n".join(meta + header + [r.replace(",60.0,", ",60,")
                                          .replace(",120.0,", ",1.2E2,") for r in rows]
                         + [""]).encode()
    if how == "empty_column":       # a column with no value in any row, added
        return "\n".join(meta + [header[0] + ",operator_note"] + [r + "," for r in rows]
                         + [""]).encode()
    if how == "quoted_metadata":    # a spreadsheet's re-save: each # line one quoted cell
        return "\n".join(['"' + m + '"' for m in meta] + header + rows + [""]).encode()
    if how == "form_feed":          # a stray form feed after a cell, stripped as space
        return "\n".join(meta + header + [rows[0].replace(",", "\x0c,", 1)] + rows[1:]
                         + [""]).encode()
    if how == "value":
        cells = rows[0].split(",")
        col = header[0].split(",").index("gyro_counts")
        cells[col] = str(int(cells[col]) + 1)
        return "\n".join(meta + header + [",".join(cells)] + rows[1:] + [""]).encode()
    raise ValueError(how)


WRITTEN_OTHERWISE = ("newline", "crlf", "bom", "metadata", "reversed", "columns", "respelt",
                     "empty_column", "form_feed", "quoted_metadata")


@pytest.mark.parametrize("how", WRITTEN_OTHERWISE)
def test_the_digest_is_the_same_for_the_same_data_written_otherwise(tmp_path, bench_readings,
                                                                    how):
    src = bench_readings[0]
    other = tmp_path / "r.csv"
    other.write_bytes(rewritten(src, how))
    assert other.read_bytes() != src.read_bytes()
    assert content_sha256(other) == content_sha256(src)


def test_one_value_or_one_row_is_another_measurement(tmp_path, bench_readings):
    src = bench_readings[0]
    changed, fewer = tmp_path / "v.csv", tmp_path / "f.csv"
    changed.write_bytes(rewritten(src, "value"))
    meta, header, rows = _split(src.read_text(encoding="utf-8"))
    fewer.write_text("\n".join(meta + header + rows[:-1] + [""]), encoding="utf-8")
    digests = {content_sha256(p) for p in (src, changed, fewer, bench_readings[1])}
    assert len(digests) == 4


def test_a_64_bit_counters_counts_are_kept_whole(tmp_path):
    """Counts of an unsigned 64-bit counter that counts down from zero differ in their low
    digits only: two such streams drifting at different rates are two measurements (a
    15-digit cell form made them one), while an integral value spelt as a decimal is the
    integer (``1e15``, ``60.0``)."""
    start = 2 ** 64 - 1000
    a, b, c, d = (tmp_path / f"{n}.csv" for n in "abcd")
    a.write_text("time_s,gyro_counts\n0.000,%d\n0.001,%d\n" % (start, start - 1))
    b.write_text("time_s,gyro_counts\n0.000,%d\n0.001,%d\n" % (start, start - 2))
    c.write_text("time_s,gyro_counts\n0,1000000000000000\n1.0,60\n")
    d.write_text("time_s,gyro_counts\n0.0,1e15\n1,60.0\n")
    assert content_sha256(a) != content_sha256(b)
    assert content_sha256(c) == content_sha256(d)


def test_a_column_with_a_value_is_part_of_the_data(tmp_path):
    a, b, c = (tmp_path / f"{n}.csv" for n in "abc")
    a.write_text("time_s,gyro_counts\n0,1\n1,2\n")
    b.write_text("time_s,gyro_counts,temperature_c\n0,1,\n1,2,\n")
    c.write_text("time_s,gyro_counts,temperature_c\n0,1,\n1,2,20.1\n")
    assert content_sha256(a) == content_sha256(b) != content_sha256(c)


def test_a_file_csv_cannot_read_has_no_digest_and_is_refused_by_the_reader(tmp_path,
                                                                         bench_readings,
                                                                         capsys):
    """A cell past csv's field limit: no content digest (only the SHA-256 identifies the
    file), and the calibration stops at the reader's one-line refusal, not a traceback."""
    big = tmp_path / "big.csv"
    meta, header, rows = _split(bench_readings[1].read_text(encoding="utf-8"))
    cells = rows[0].split(",")
    cells[-1] = "x" * 200_000
    big.write_text("\n".join(meta + header + [",".join(cells)] + rows[1:] + [""]),
                   encoding="utf-8")
    assert content_sha256(big) is None
    argv = ["calibrate", str(big), "--protocol", str(SMALL_PROTOCOL), "--record",
            "--data", str(tmp_path / "data"), "--out", str(tmp_path / "o")]
    err = _refused(argv, capsys)
    assert "characters, over the limit" in err and "Traceback" not in err


def test_a_parquet_stream_and_its_rows_reordered_digest_alike(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    t = pa.table({"time_s": [0.0, 0.5, 1.0], "gyro_counts": [1, 2, 3]})
    pq.write_table(t, tmp_path / "a.parquet", row_group_size=2)
    pq.write_table(t.take([2, 0, 1]).select(["gyro_counts", "time_s"]), tmp_path / "b.parquet")
    pq.write_table(t.set_column(1, "gyro_counts", pa.array([1, 2, 4])), tmp_path / "c.parquet")
    a, b, c = (content_sha256(tmp_path / f"{n}.parquet") for n in "abc")
    assert a == b and a != c


@pytest.fixture(scope="module")
def stream_and_reduced(tmp_path_factory):
    """A simulated stream of the small programme and the readings ``gonio reduce`` makes of
    it (which name the stream's SHA-256)."""
    d = tmp_path_factory.mktemp("stream")
    assert main(["simulate", "--protocol", str(SMALL_PROTOCOL), "--stream", "--seed", "5",
                 "--out", str(d / "sim")]) == 0
    stream = d / "sim" / "stream.parquet"
    reduced = d / "reduced.csv"
    assert main(["reduce", str(stream), "--protocol", str(SMALL_PROTOCOL), "--out",
                 str(reduced)]) == 0
    return stream, reduced


@pytest.mark.parametrize("first", ["stream", "reduced"])
def test_a_stream_and_its_reduced_readings_are_one_measurement(tmp_path, stream_and_reduced,
                                                              capsys, first):
    """A stream calibrated, then the readings reduced from it (or the other way round): the
    second is refused, naming the first calibration; the reduced readings name the stream by
    its SHA-256 (``# source_stream_sha256``)."""
    from gonio.atomic import sha256_file
    from gonio.formats.content import source_sha256

    stream, reduced = stream_and_reduced
    assert source_sha256(reduced) == sha256_file(stream)
    data = tmp_path / "data"
    one, other = (stream, reduced) if first == "stream" else (reduced, stream)
    argv = ["--protocol", str(SMALL_PROTOCOL), "--record", "--data", str(data)]
    assert main(["calibrate", str(one), *argv, "--out", str(tmp_path / "a")]) == 0
    before = _rows(data)
    err = _refused(["calibrate", str(other), *argv, "--out", str(tmp_path / "b")], capsys)
    how = ("were reduced from the stream that is the readings of calibration 1 "
           if first == "stream" else "are the stream reduced to the readings of calibration 1 ")
    assert how in err and "the same measurement is not calibrated twice" in err, err
    assert _rows(data) == before


@pytest.mark.parametrize("how", ["newline", "metadata", "reversed"])
def test_calibrate_record_refuses_the_same_data_written_otherwise(tmp_path, bench_readings,
                                                                  capsys, how):
    data = tmp_path / "data"
    argv = ["calibrate", "--protocol", str(SMALL_PROTOCOL), "--record", "--data", str(data)]
    assert main(argv[:1] + [str(bench_readings[1])] + argv[1:]
                + ["--out", str(tmp_path / "a")]) == 0
    before = _rows(data)
    copy = tmp_path / "copy.csv"
    copy.write_bytes(rewritten(bench_readings[1], how))
    err = _refused(argv[:1] + [str(copy)] + argv[1:] + ["--out", str(tmp_path / "b")], capsys)
    assert "hold the same data, written otherwise, as the readings of calibration 1 " \
           "(RLG-0001, " in err, err
    assert _rows(data) == before
    # one count changed is another measurement: recorded
    changed = tmp_path / "changed.csv"
    changed.write_bytes(rewritten(bench_readings[1], "value"))
    assert main(argv[:1] + [str(changed)] + argv[1:] + ["--out", str(tmp_path / "c")]) == 0
    assert _rows(data)["calibrations"] == 2


def _stored(store, data: bytes) -> str:
    sha, _ = services.store_file(store, io.BytesIO(data))
    return sha


def test_the_service_refuses_it_and_digests_an_older_stores_readings(tmp_path, bench_readings):
    """Every path's check (the web form's and a bench's service): a readings file whose
    content digest is not yet kept (a store from before the digest, a restore) is digested
    when first compared, and the digest is kept."""
    store = open_store(None, tmp_path / "data")
    try:
        people = make_people(store)
        inst, std = setup_instrument(store, people)
        cal = new_calibration(store, people, inst, std, bench_readings[0])
        with sqlite3.connect(tmp_path / "data" / "records.sqlite3") as db:
            assert db.execute("select count(*) from readings_contents").fetchone()[0] == 1
            db.execute("drop trigger readings_contents_no_delete")   # a store before 0014
            db.execute("delete from readings_contents")
        sha = _stored(store, rewritten(bench_readings[0], "crlf"))
        with store.writing() as s:
            with pytest.raises(GonioError, match=rf"written otherwise, as the readings of "
                                                 rf"calibration {cal.id} ") as got:
                services.check_readings_unused(s, sha)
            assert got.value.key == services.REUSE_KEY
            s.commit()
        with sqlite3.connect(tmp_path / "data" / "records.sqlite3") as db:
            kept = db.execute("select content_sha256 from readings_contents where sha256 = ?",
                              (cal.readings_sha256,)).fetchone()[0]
        assert kept == content_sha256(bench_readings[0])
        respelt = tmp_path / "x.csv"
        respelt.write_bytes(rewritten(bench_readings[0], "respelt"))
        with pytest.raises(GonioError, match="written otherwise"):
            new_calibration(store, people, inst, std, respelt)
        with store.session() as s:      # the reason given: recorded beside the other
            used = services.check_readings_unused(s, sha, reason="repeated for the customer")
        assert [(u["id"], u["same"]) for u in used] == [(cal.id, "content")]
    finally:
        store.close()


def test_a_restore_digests_the_files_never_the_archives_digest(tmp_path, bench_readings):
    store = open_store(None, tmp_path / "data")
    try:
        people = make_people(store)
        inst, std = setup_instrument(store, people)
        cal = new_calibration(store, people, inst, std, bench_readings[0])
    finally:
        store.close()
    archive = tmp_path / "b.zip"
    assert main(["db", "backup", str(archive), "--data", str(tmp_path / "data")]) == 0
    forged = tmp_path / "forged.zip"
    with zipfile.ZipFile(archive) as zin, zipfile.ZipFile(forged, "w") as zout:
        for info in zin.infolist():
            body = zin.read(info)
            if info.filename == "records.json":
                doc = json.loads(body)
                t = doc["tables"]["readings_contents"]
                i = t["columns"].index("content_sha256")
                assert t["rows"]
                for r in t["rows"]:
                    r[i] = "0" * 64
                body = json.dumps(doc).encode()
            zout.writestr(info, body)
    other = tmp_path / "other"
    assert main(["db", "init", "--data", str(other)]) == 0
    assert main(["db", "restore", str(forged), "--data", str(other)]) == 0
    with sqlite3.connect(other / "records.sqlite3") as db:
        (got,) = db.execute("select content_sha256 from readings_contents where sha256 = ?",
                            (cal.readings_sha256,)).fetchone()
    assert got == content_sha256(bench_readings[0])     # the file's own digest


def _migrated(store, bench_readings, revision: str, before=None, change: str = "") -> None:
    """One calibration recorded, the schema taken down to ``revision`` (``before(engine,
    calibration)`` then run on it), the store opened again at the head: its digests are the
    stored file's of the current form, and ``change`` (SQL) is refused by the triggers."""
    from sqlalchemy import text

    from .test_result_statement import _downgrade

    people = make_people(store)
    inst, std = setup_instrument(store, people)
    cal = new_calibration(store, people, inst, std, bench_readings[0])
    _downgrade(store.engine, revision)
    if before is not None:
        before(store.engine, cal)
    url, data = store.url, store.data
    store.close()
    again = open_store(None if url.startswith("sqlite") else url, data)
    try:
        with again.engine.connect() as c:
            got = c.execute(text("SELECT sha256, content_sha256 FROM readings_contents")).all()
        assert [tuple(r) for r in got] == [(cal.readings_sha256,
                                            content_sha256(bench_readings[0]))]
        with pytest.raises(Exception, match="never changed"):
            with again.engine.begin() as c:
                c.execute(text(change))
    finally:
        again.close()


def test_the_migration_digests_again_what_the_first_form_kept(store, bench_readings):
    """A store at 0014 keeps digests of the digest's first form, which no new file's digest
    matches: at the head they are the stored files' digests of the current form (SQLite and
    PostgreSQL)."""
    from sqlalchemy import text

    def first_form(engine, cal):            # as the first form kept it
        with engine.begin() as c:
            c.execute(text("INSERT INTO readings_contents (sha256, content_sha256) "
                           "VALUES (:s, :d)"), {"s": cal.readings_sha256, "d": "1" * 64})
    _migrated(store, bench_readings, "0014", first_form, "DELETE FROM readings_contents")


def test_the_migration_digests_an_older_stores_readings(store, bench_readings):
    """Records written before the digest (schema 0013) open at the head with every
    calibration's readings digested from the stored file (SQLite and PostgreSQL), and the
    digest cannot be changed in the database."""
    _migrated(store, bench_readings, "0013",
              change="UPDATE readings_contents SET content_sha256 = 'x'")
