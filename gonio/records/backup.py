"""Backup and restore of the whole records: every table and every stored file in one ZIP
archive that restores into an empty database of either kind (SQLite or PostgreSQL).

Archive layout: ``records.json`` (format version, gonio version, per table its columns and
rows, values as JSON: dates and times ISO 8601) and ``blobs/<sha256>`` for every stored file.
:func:`restore` checks every file against its digest before anything is written, refuses
a database that holds records already, inserts the rows in dependency order in one
transaction (so a failed restore leaves the database empty), and moves the ids' sequences
past the restored rows on PostgreSQL.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
import tempfile
import zipfile
from pathlib import Path

from sqlalchemy import Date, DateTime, func, select, text

from gonio.errors import GonioError
from gonio.records import blobs
from gonio.records.models import Base, Blob, User

FORMAT = "gonio-records-backup/1"


def _tables():
    return list(Base.metadata.sorted_tables)      # parents before children


def _json(v):
    if isinstance(v, (_dt.date, _dt.datetime)):
        return v.isoformat()
    return v


def backup(store, path: str | os.PathLike) -> dict:
    """Write the archive to ``path`` (atomically: a temporary file renamed into place);
    returns the counts of rows per table and of files."""
    from gonio import __version__

    path = Path(path)
    counts: dict[str, int] = {}
    doc = {"format": FORMAT, "gonio_version": __version__, "tables": {}}
    with store.session() as s:
        # one snapshot of every table (a repeatable read on PostgreSQL, a WAL snapshot on SQLite)
        if store.engine.dialect.name == "postgresql":
            s.execute(text("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ"))
        for table in _tables():
            cols = [c.name for c in table.columns]
            rows = [[_json(v) for v in r] for r in s.execute(select(*table.columns)
                                                             .order_by(*table.primary_key))]
            doc["tables"][table.name] = {"columns": cols, "rows": rows}
            counts[table.name] = len(rows)
        shas = [r[0] for r in s.execute(select(Blob.sha256))]
    fd, tmp = tempfile.mkstemp(prefix=".backup-", suffix=".zip", dir=path.parent or ".")
    os.close(fd)
    try:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
            zf.writestr("records.json", json.dumps(doc, ensure_ascii=False))
            for sha in shas:
                zf.write(blobs.blob_path(store.blob_root, sha), f"blobs/{sha}")
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    counts["files"] = len(shas)
    return counts


def _convert(table, cols: list[str], row: list):
    out = {}
    for name, v in zip(cols, row):
        col = table.columns[name]
        if v is not None and isinstance(col.type, DateTime):
            v = _dt.datetime.fromisoformat(v)
        elif v is not None and isinstance(col.type, Date):
            v = _dt.date.fromisoformat(v)
        out[name] = v
    return out


def restore(store, path: str | os.PathLike) -> dict:
    """Restore the archive at ``path`` into the (empty) database of ``store``; returns the
    counts restored."""
    path = Path(path)
    try:
        zf = zipfile.ZipFile(path)
    except (OSError, zipfile.BadZipFile) as exc:
        raise GonioError(f"not a gonio backup archive ({exc})", file=path) from None
    with zf:
        try:
            doc = json.loads(zf.read("records.json"))
        except (KeyError, ValueError, RecursionError) as exc:   # RecursionError: too deep
            raise GonioError(f"no readable records.json ({str(exc)[:120] or 'nested too deeply'})",
                             file=path) from None
        if doc.get("format") != FORMAT:
            raise GonioError(f"unknown backup format {doc.get('format')!r}", file=path)
        names = {n[len("blobs/"):] for n in zf.namelist() if n.startswith("blobs/")}
        for sha in names:                                 # every file checked first
            data = zf.read(f"blobs/{sha}")
            if hashlib.sha256(data).hexdigest() != sha:
                raise GonioError(f"stored file {sha[:12]}… does not match its SHA-256",
                                 file=path)
        with store.session() as s:
            if s.scalar(select(func.count()).select_from(User)):
                raise GonioError("the database holds records already; restore into an "
                                 "empty one (gonio db init on a new data folder or database)",
                                 file=path)
        for sha in names:
            blobs.put_bytes(store.blob_root, zf.read(f"blobs/{sha}"))
    counts = {}
    with store.writing() as s:
        for table in _tables():
            t = doc["tables"].get(table.name)
            if not t or not t["rows"]:
                continue
            unknown = set(t["columns"]) - set(table.columns.keys())
            if unknown:
                raise GonioError(f"table {table.name} has unknown columns {sorted(unknown)}",
                                 file=path)
            s.execute(table.insert(), [_convert(table, t["columns"], r) for r in t["rows"]])
            counts[table.name] = len(t["rows"])
        if store.engine.dialect.name == "postgresql":
            for table in _tables():
                pk = list(table.primary_key.columns)
                if [c.name for c in pk] == ["id"]:
                    s.execute(text(f"SELECT setval(pg_get_serial_sequence('{table.name}', "
                                   f"'{pk[0].name}'), COALESCE((SELECT MAX({pk[0].name}) "
                                   f"FROM {table.name}), 0) + 1, false)"))
        s.commit()
    counts["files"] = len(names)
    return counts
