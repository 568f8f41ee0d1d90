"""Backup and restore of the whole records: every table and every stored file in one ZIP
archive that restores into a database of either kind (SQLite or PostgreSQL).

Archive layout: ``records.json`` (format version, gonio version, per table its columns and
rows, values as JSON: dates and times ISO 8601) and ``blobs/<sha256>`` for every stored file.
:func:`restore` checks every file against its digest and every row and reference before
anything is written, then either fills an empty database in one transaction (``gonio db
restore``) or replaces the live records atomically (the browser's restore: a new SQLite file
swapped in, or one PostgreSQL transaction), moving the ids' sequences past the restored rows
on PostgreSQL; a failure leaves the database as it was.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
import re
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
    return {"gonio_version": str(doc.get("gonio_version", ""))[:40], "files": len(names),
            **check_summary(rows)}


#: an archive name the backup folder may offer (never a path)
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,120}\.zip")


def backup_folder(store) -> Path:
    """Where the nightly backups lie (``gonio db backup`` run by a scheduled job):
    ``$GONIO_BACKUP_FOLDER``, else ``backups`` in the data folder."""
    return Path(os.path.expanduser(os.environ.get("GONIO_BACKUP_FOLDER", "").strip()
                                   or str(store.data / "backups")))


def archives_in(folder: Path, limit: int = 50) -> list[dict]:
    """The backup archives in ``folder`` (plain ``*.zip`` files with plain names), newest
    first: ``[{"name", "bytes", "modified": "YYYY-MM-DD HH:MM" UTC}]``; none when the folder
    does not exist."""
    try:
        found = [p for p in Path(folder).iterdir() if _NAME.fullmatch(p.name) and p.is_file()
                 and not p.is_symlink()]
    except OSError:
        return []
    found.sort(key=lambda p: p.stat().st_mtime, reverse=True)
    return [{"name": p.name, "bytes": p.stat().st_size,
             "modified": _dt.datetime.fromtimestamp(p.stat().st_mtime, _dt.timezone.utc)
             .strftime("%Y-%m-%d %H:%M")} for p in found[:limit]]


def archive_sha256(path: str | os.PathLike) -> str:
    """The SHA-256 of the archive file at ``path`` (what a confirmation names)."""
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for piece in iter(lambda: fh.read(1 << 20), b""):
                h.update(piece)
    except OSError as exc:
        raise GonioError(f"cannot read the archive: {exc.strerror}", file=path) from None
    return h.hexdigest()


def summary(store) -> dict:
    """The live records counted as :func:`check_archive` counts an archive: ``{"rows":
    {table: count}, "files", "calibrations", "certificates", "newest"}`` (what a restore
    would replace)."""
    from gonio.records.models import AuditEvent

    with store.session() as s:
        rows = {t.name: s.scalar(select(func.count()).select_from(t)) for t in _tables()}
        newest = s.scalar(select(func.max(AuditEvent.at)))
    return {"rows": rows, "files": rows["blobs"], "calibrations": rows["calibrations"],
            "certificates": rows["certificates"],
            "newest": newest.isoformat(sep=" ", timespec="minutes") if newest else ""}


#: rows a restore never writes: last night's browser sessions would be live again
NOT_RESTORED = ("web_sessions",)


def restore(store, path: str | os.PathLike, *, replace: bool = False, actor: User | None = None,
            expect_sha256: str | None = None) -> dict:
    """Restore the archive at ``path`` into the records of ``store``; returns the counts of
    rows restored per table and of files.

    Everything is checked before anything is written (:func:`_checked`: records.json's
    tables, rows and references, every file listed in ``blobs`` present in the archive
    (complete) and matching its SHA-256 (intact), no file the records do not list): an
    archive a restore would lose anything of is refused whole. ``expect_sha256``: the digest
    of the archive that was verified and confirmed; a different file is refused.

    Without ``replace`` the database must be empty (``gonio db restore``). With ``replace``
    (an admin ``actor``, the browser's restore) the live records are replaced atomically:
    SQLite — the archive is written into a new database file next to the live one, which is
    swapped in by one rename once complete (the replaced file is kept beside it as
    ``records.sqlite3.replaced-YYYYmmddTHHMMSS``) and the engine's connections are renewed;
    PostgreSQL — every table emptied and refilled in one transaction. A failure at any step
    leaves the live records as they were. The caller keeps other requests and the workers
    out meanwhile (gonio serve's maintenance state); on SQLite a database another process
    has open is refused. The archive must hold an active administrator (else nobody could
    manage the restored records).

    Either way the stored files are added to the blob store (a damaged copy there is
    replaced by the archive's), no browser session is restored (everyone logs in again), and
    the restore itself is the newest event of the restored audit trail (action ``restore``:
    the archive's name and SHA-256, its last recorded change, the counts, and with
    ``replace`` the counts replaced)."""
    path = Path(path)
    if replace:
        from gonio.records.services import require

        require(actor, "admin")
    sha = archive_sha256(path)
    if expect_sha256 is not None and sha != expect_sha256:
        raise GonioError("the archive is not the one verified and confirmed (its SHA-256 "
                         "changed): verify it again; nothing restored", file=path)
    with _open(path, path) as zf:
        rows, names, doc = _checked(zf, path)
        if replace and not any(r.get("active") and "admin" in str(r.get("roles", "")).split()
                               for r in rows["users"]):
            raise GonioError("the archive has no active administrator: nobody could manage "
                             "the restored records; nothing restored", file=path)
        if not replace:
            with store.session() as s:
                if s.scalar(select(func.count()).select_from(User)):
                    raise GonioError("the database holds records already; restore into an "
                                     "empty one (gonio db init on a new data folder or "
                                     "database)", file=path)
        for name in NOT_RESTORED:
            rows[name] = []
        event = {"archive": path.name, "sha256": sha, "newest": check_summary(rows)["newest"],
                 "gonio_version": str(doc.get("gonio_version", ""))[:40],
                 "rows": {k: len(v) for k, v in rows.items() if v}, "files": len(names)}
        if replace:
            event["replaced"] = summary(store)["rows"]
        for sha_file in names:
            _put_blob(store.blob_root, sha_file, zf.read(f"blobs/{sha_file}"))
    who = actor.username if actor is not None else "(command line)"
    if not replace:
        with store.writing() as s:
            _write(s, rows, path, event, who)
            s.commit()
    elif store.engine.dialect.name == "sqlite":
        _swap_sqlite(store, rows, path, event, who)
    else:
        _replace_postgresql(store, rows, path, event, who)
    counts = {k: len(v) for k, v in rows.items() if v}
    counts["files"] = len(names)
    return counts


def check_summary(rows: dict) -> dict:
    """An archive's checked rows counted (see :func:`check_archive`)."""
    stamps = [r["at"] for r in rows.get("audit_events", []) if r.get("at") is not None]
    return {"rows": {k: len(v) for k, v in rows.items()},
            "calibrations": len(rows.get("calibrations", [])),
            "certificates": len(rows.get("certificates", [])),
            "newest": max(stamps).isoformat(sep=" ", timespec="minutes") if stamps else ""}


def _put_blob(root: Path, sha: str, data: bytes) -> None:
    """A stored file from the archive (checked against ``sha`` already) into the store; a
    missing or damaged copy there is replaced."""
    path = blobs.blob_path(root, sha)
    if path.is_file() and blobs.verify(root, sha):
        return
    if path.exists():
        path.unlink()
    blobs.put_bytes(root, data)


def _write(s, rows: dict, path: Path, event: dict, who: str) -> None:
    """Insert the checked ``rows`` in dependency order in the session's transaction, move
    PostgreSQL's id sequences past them, and append the restore's audit event (its user the
    restored account of ``who``, if there is one). A row the database refuses is a
    GonioError (the transaction rolled back)."""
    from sqlalchemy.exc import SQLAlchemyError

    from gonio.records.models import AuditEvent

    try:
        for table in _tables():
            if rows[table.name]:
                s.execute(table.insert(), rows[table.name])
        if s.get_bind().dialect.name == "postgresql":
            for table in _tables():
                pk = list(table.primary_key.columns)
                # an integer id has a sequence (a web session's text id has none)
                if [c.name for c in pk] == ["id"] and isinstance(pk[0].type, Integer):
                    s.execute(text(f"SELECT setval(pg_get_serial_sequence('{table.name}', "
                                   f"'{pk[0].name}'), COALESCE((SELECT MAX({pk[0].name}) "
                                   f"FROM {table.name}), 0) + 1, false)"))
        uid = s.scalar(select(User.id).where(User.username == who))
        s.add(AuditEvent(user_id=uid, username=who[:64], action="restore", entity="records",
                         entity_id=event["sha256"][:64],
                         after_json=json.dumps(event, sort_keys=True, default=str)))
        s.flush()
    except SQLAlchemyError as exc:
        s.rollback()
        msg = str(getattr(exc, "orig", exc)).strip().splitlines()[0][:200]
        raise GonioError(f"records.json refused by the database ({msg}): nothing "
                         "restored", file=path) from None


def _swap_sqlite(store, rows: dict, path: Path, event: dict, who: str) -> None:
    """SQLite: the restored records written into a new file beside the live one (migrated,
    filled, checkpointed), then swapped in by one rename; the live engine's connections are
    closed first and renewed by its next use."""
    import sqlite3

    from sqlalchemy.orm import Session as OrmSession

    from gonio.records.db import make_engine, migrate

    live = Path(store.engine.url.database)
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y%m%dT%H%M%S")
    fd, new = tempfile.mkstemp(prefix=f".{live.name}.restoring-", dir=live.parent)
    os.close(fd)
    engine = make_engine(f"sqlite:///{new}")
    try:
        migrate(engine)
        with OrmSession(engine.execution_options(gonio_write=True)) as s:
            _write(s, rows, path, event, who)
            s.commit()
        engine.dispose()
        store.engine.dispose()
        if _one_file(new) != "delete":
            raise GonioError("the restored database could not be written as one file: "
                             "nothing restored", file=new)
        # refused while another connection has the live file open: nobody else writes
        raw = sqlite3.connect(live, timeout=5, isolation_level=None)
        try:
            if _one_file(live, raw) != "delete":
                raise GonioError("another process has the records database open (a worker, "
                                 "a gonio command): nothing restored", file=live)
            for extra in ("-wal", "-shm"):
                Path(f"{live}{extra}").unlink(missing_ok=True)
            os.link(live, live.with_name(f"{live.name}.replaced-{stamp}"))
            os.replace(new, live)
        finally:
            raw.close()
    finally:
        engine.dispose()
        for leftover in (new, f"{new}-wal", f"{new}-shm", f"{new}-journal"):
            Path(leftover).unlink(missing_ok=True)
    store.engine.dispose()


def _one_file(path, conn=None) -> str:
    """Switch the SQLite database at ``path`` out of WAL (its log folded in and removed):
    the journal mode it has then ("delete"; another mode or "" when another connection
    holds it open)."""
    import sqlite3

    own = conn is None
    conn = conn or sqlite3.connect(path, timeout=5, isolation_level=None)
    try:
        return str(conn.execute("PRAGMA journal_mode=DELETE").fetchone()[0]).lower()
    except sqlite3.OperationalError:
        return ""
    finally:
        if own:
            conn.close()


def _replace_postgresql(store, rows: dict, path: Path, event: dict, who: str) -> None:
    """PostgreSQL: every table emptied (TRUNCATE: no row triggers, its identity resets
    transactional) and refilled in one transaction; a failure rolls all of it back."""
    names = ", ".join(t.name for t in _tables())
    with store.writing() as s:
        s.execute(text("SET LOCAL lock_timeout = '30s'"))
        s.execute(text(f"TRUNCATE {names} RESTART IDENTITY"))
        _write(s, rows, path, event, who)
        s.commit()
    store.engine.dispose()


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
