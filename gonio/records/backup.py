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

from sqlalchemy import Date, DateTime, Integer, func, select, text

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
    bad = damaged_files(store, shas)
    if bad:
        raise GonioError(f"{len(bad)} stored file(s) missing or damaged, first {bad[0]}: "
                         "nothing written (gonio db verify lists them)", file=path)
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


def damaged_files(store, shas) -> list[str]:
    """The stored files among ``shas`` that are missing or do not match their SHA-256, each
    as "<sha256> (missing|damaged)"."""
    out = []
    for sha in shas:
        path = blobs.blob_path(store.blob_root, sha)
        if not path.is_file():
            out.append(f"{sha} (missing)")
        elif not blobs.verify(store.blob_root, sha):
            out.append(f"{sha} (damaged)")
    return out


def _convert(table, cols: list[str], row: list, where: str):
    if not isinstance(row, list) or len(row) != len(cols):
        raise GonioError(f"{where}: a row is a list of {len(cols)} values", key=table.name)
    out = {}
    for name, v in zip(cols, row):
        col = table.columns[name]
        try:
            if v is not None and isinstance(col.type, DateTime):
                v = _dt.datetime.fromisoformat(v)
            elif v is not None and isinstance(col.type, Date):
                v = _dt.date.fromisoformat(v)
        except (TypeError, ValueError):
            raise GonioError(f"{where}: {name} is not a date: {str(v)[:40]!r}",
                             key=table.name) from None
        if v is not None and not isinstance(v, (str, int, float, bool, _dt.date)):
            raise GonioError(f"{where}: {name} is not a plain value", key=table.name)
        out[name] = v
    return out


def _rows(doc, path) -> dict:
    """records.json's tables as {table name: [row dicts]}, every row converted and checked:
    known tables and columns only, dates that are dates, every reference to another row
    (a calibration's instrument, a certificate's files) present in the archive."""
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        got = doc.get("format") if isinstance(doc, dict) else type(doc).__name__
        raise GonioError(f"unknown backup format {got!r}", file=path)
    tables = doc.get("tables")
    if not isinstance(tables, dict):
        raise GonioError("records.json has no tables", file=path)
    known = {t.name: t for t in _tables()}
    unknown = sorted(set(tables) - set(known))
    if unknown:       # a table this gonio does not know would be lost: refused
        raise GonioError(f"records.json has tables this gonio does not know {unknown}: "
                         "restore with the gonio version that wrote it", file=path)
    out = {}
    for name, table in known.items():
        t = tables.get(name) or {"columns": [], "rows": []}
        if not isinstance(t, dict) or not isinstance(t.get("columns"), list) \
                or not isinstance(t.get("rows"), list) \
                or not all(isinstance(c, str) for c in t["columns"]):
            raise GonioError(f"table {name} is not {{columns: [...], rows: [...]}}", file=path)
        extra = set(t["columns"]) - set(table.columns.keys())
        if extra:
            raise GonioError(f"table {name} has unknown columns {sorted(extra)}", file=path)
        out[name] = [_convert(table, t["columns"], r, f"{name} row {i + 1}")
                     for i, r in enumerate(t["rows"])]
    for name, table in known.items():              # every reference resolved in the archive
        for fk in table.foreign_keys:
            target = fk.column
            have = {r.get(target.name) for r in out[target.table.name]}
            for i, r in enumerate(out[name]):
                v = r.get(fk.parent.name)
                if v is not None and v not in have:
                    raise GonioError(f"{name} row {i + 1}: {fk.parent.name} {str(v)[:64]} is "
                                     f"not among the archive's {target.table.name}", file=path)
    return out


def _open(source, path: Path) -> zipfile.ZipFile:
    try:
        return zipfile.ZipFile(source)
    except (OSError, zipfile.BadZipFile) as exc:
        raise GonioError(f"not a gonio backup archive ({exc})", file=path) from None


def _checked(zf: zipfile.ZipFile, path: Path) -> tuple[dict, set, dict]:
    """An open archive checked whole, nothing written: (rows per table, the stored files'
    digests, records.json). records.json's tables, rows and references
    (:func:`_rows`); every file listed in ``blobs`` present in the archive (complete) and
    matching its SHA-256 (intact); no file the records do not list."""
    try:
        doc = json.loads(zf.read("records.json"))
    except (KeyError, ValueError, RecursionError) as exc:   # RecursionError: too deep
        raise GonioError(f"no readable records.json ({str(exc)[:120] or 'nested too deeply'})",
                         file=path) from None
    rows = _rows(doc, path)
    names = {n[len("blobs/"):] for n in zf.namelist() if n.startswith("blobs/")}
    listed = {r["sha256"] for r in rows["blobs"]}
    missing, unlisted = sorted(listed - names), sorted(names - listed)
    if missing:
        raise GonioError(f"incomplete: {len(missing)} stored file(s) of the records are "
                         f"not in the archive, first {str(missing[0])[:64]}: nothing "
                         "restored", file=path)
    if unlisted:
        raise GonioError(f"{len(unlisted)} file(s) in the archive are not in its records, "
                         f"first {unlisted[0][:64]}: nothing restored", file=path)
    for sha in sorted(names):                         # every file checked first
        try:
            data = zf.read(f"blobs/{sha}")
        except (zipfile.BadZipFile, OSError) as exc:
            raise GonioError(f"stored file {sha[:12]}… unreadable ({exc})",
                             file=path) from None
        if hashlib.sha256(data).hexdigest() != sha:
            raise GonioError(f"stored file {sha[:12]}… does not match its SHA-256",
                             file=path)
    return rows, names, doc


def check_archive(path: str | os.PathLike, stream=None) -> dict:
    """Check a backup archive as :func:`restore` does before it writes anything, and write
    nothing (``stream``: the archive as an open binary file, ``path`` then only its name):
    a GonioError names the first problem; else ``{"gonio_version", "rows": {table:
    count}, "files": count, "calibrations", "certificates", "newest": the latest time
    recorded in it (the audit trail's last event, UTC, "YYYY-MM-DD HH:MM") or ""}``."""
    path = Path(path)
    with _open(path if stream is None else stream, path) as zf:
        rows, names, doc = _checked(zf, path)
    stamps = [r["at"] for r in rows.get("audit_events", []) if r.get("at") is not None]
    return {"gonio_version": str(doc.get("gonio_version", ""))[:40],
            "rows": {k: len(v) for k, v in rows.items()}, "files": len(names),
            "calibrations": len(rows.get("calibrations", [])),
            "certificates": len(rows.get("certificates", [])),
            "newest": max(stamps).isoformat(sep=" ", timespec="minutes") if stamps else ""}


def restore(store, path: str | os.PathLike) -> dict:
    """Restore the archive at ``path`` into the (empty) database of ``store``; returns the
    counts restored. Everything is checked before anything is written (:func:`_checked`:
    records.json's tables, rows and references, every file listed in ``blobs`` present in
    the archive (complete) and matching its SHA-256 (intact), no file the records do not
    list)."""
    path = Path(path)
    with _open(path, path) as zf:
        rows, names, _ = _checked(zf, path)
        with store.session() as s:
            if s.scalar(select(func.count()).select_from(User)):
                raise GonioError("the database holds records already; restore into an "
                                 "empty one (gonio db init on a new data folder or database)",
                                 file=path)
        for sha in names:
            blobs.put_bytes(store.blob_root, zf.read(f"blobs/{sha}"))
    counts = {}
    from sqlalchemy.exc import SQLAlchemyError

    with store.writing() as s:
        try:
            for table in _tables():
                if rows[table.name]:
                    s.execute(table.insert(), rows[table.name])
                    counts[table.name] = len(rows[table.name])
        except SQLAlchemyError as exc:
            s.rollback()
            msg = str(getattr(exc, "orig", exc)).strip().splitlines()[0][:200]
            raise GonioError(f"records.json refused by the database ({msg}): nothing "
                             "restored", file=path) from None
        if store.engine.dialect.name == "postgresql":
            for table in _tables():
                pk = list(table.primary_key.columns)
                # an integer id has a sequence (a web session's text id has none)
                if [c.name for c in pk] == ["id"] and isinstance(pk[0].type, Integer):
                    s.execute(text(f"SELECT setval(pg_get_serial_sequence('{table.name}', "
                                   f"'{pk[0].name}'), COALESCE((SELECT MAX({pk[0].name}) "
                                   f"FROM {table.name}), 0) + 1, false)"))
        s.commit()
    counts["files"] = len(names)
    return counts


def verify(store) -> tuple[dict, list[str]]:
    """Check a live database as a backup and a restore check an archive: every stored file
    present and matching its SHA-256, every computed calibration's result rows matching its
    stored results.json and, where it was signed, its seal the one signed (at review, at
    approval, on its newest certificate). Returns (counts, problems: one line each)."""
    from gonio.records import services
    from gonio.records.models import Calibration, Certificate

    problems = []
    with store.session() as s:
        shas = [r[0] for r in s.execute(select(Blob.sha256))]
        cals = s.execute(select(Calibration.id, Calibration.status, Calibration.reviewed_seal,
                                Calibration.approved_seal).where(
            Calibration.results_sha256.is_not(None)).order_by(Calibration.id)).all()
        certs = s.execute(select(Certificate.calibration_id, Certificate.number,
                                 Certificate.seal_sha256).order_by(Certificate.id)).all()
    problems += [f"stored file {b}" for b in damaged_files(store, shas)]
    newest = {cid: (number, sealed) for cid, number, sealed in certs}
    for cid, status, reviewed, approved in cals:
        try:
            now = services.seal(store, cid)
        except GonioError as exc:
            problems.append(f"calibration {cid}: {exc.message}")
            continue
        signed = [("its review", reviewed if status in ("reviewed",) else ""),
                  ("its approval", approved if status in ("issuing", "amending") else ""),
                  (f"certificate {newest.get(cid, ('', ''))[0]}",
                   newest.get(cid, ("", ""))[1] or "")]
        for what, sealed in signed:
            if sealed and sealed != now:
                problems.append(f"calibration {cid}: its stored result no longer matches the "
                                f"seal of {what}")
    return {"files": len(shas), "calibrations": len(cals), "certificates": len(certs)}, problems
