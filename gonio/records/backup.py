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
import lzma
import os
import re
import shutil
import stat
import tempfile
import zipfile
import zlib
from pathlib import Path

from sqlalchemy import Date, DateTime, Integer, func, select, text

from gonio import limits
from gonio.errors import GonioError, first_of
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
    returns the counts of rows per table and of files. The written archive is checked as
    :func:`restore` checks it (:func:`check_archive`: every row, reference and file) before
    it is moved into place: an archive restore would refuse (a row SQLite kept with a value
    its column's type does not take) is a GonioError naming the row, and nothing is left."""
    from gonio import __version__

    path = Path(path)
    _not_the_store(store, path)
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
    _, problems = verify(store, files=False)
    if problems:      # an archive of them would be refused by restore: said now, not then
        raise GonioError(f"the records do not verify: {first_of(problems)}; nothing written "
                         "(gonio db verify lists them)", file=path)
    fd, tmp = tempfile.mkstemp(prefix=".backup-", suffix=".zip", dir=path.parent or ".")
    os.close(fd)
    try:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
            zf.writestr("records.json", json.dumps(doc, ensure_ascii=False))
            for sha in shas:
                zf.write(blobs.blob_path(store.blob_root, sha), f"blobs/{sha}")
        try:
            check_archive(tmp)
        except GonioError as exc:
            raise GonioError(f"the archive would not restore ({exc.message}): nothing "
                             "written (gonio db verify checks the records)", file=path) from None
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    counts["files"] = len(shas)
    return counts


def _not_the_store(store, path: Path) -> None:
    """A backup's target is none of the records' own files: the SQLite database file (and its
    journal files, and the files a restore set aside beside it) or anything in the blob
    store; a GonioError naming the target otherwise (the rename would put the archive in
    their place)."""
    target = Path(os.path.abspath(path.expanduser()))
    real = Path(os.path.realpath(target))
    own = []
    if store.engine.dialect.name == "sqlite" and store.engine.url.database:
        db = Path(os.path.realpath(store.engine.url.database))
        own = [db.parent / (db.name + suffix) for suffix in ("", "-wal", "-shm", "-journal")]
        if real.parent == db.parent and real.name.startswith(db.name + ".replaced-"):
            own.append(real)
    blob_root = Path(os.path.realpath(store.blob_root))
    if real in own or real == blob_root or blob_root in real.parents:
        raise GonioError("the archive would replace the records' own file: write the backup "
                         "elsewhere (e.g. the backups folder)", file=path)


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


#: what a value of records.json may be for each column type (a string where a number or a
#: true/false belongs would be stored by SQLite as it is and break every later read)
#: (text columns take numbers too: SQLite keeps a number written there as a number, and a
#: backup of such a database restores)
_KINDS = {"Boolean": (bool,), "Integer": (int,), "BigInteger": (int,), "Float": (int, float),
          "String": (str, int, float), "Text": (str, int, float), "Date": (_dt.date,),
          "DateTime": (_dt.datetime,)}
_KIND_NAMES = {"Boolean": "true or false", "Integer": "a whole number",
               "BigInteger": "a whole number", "Float": "a number", "String": "text",
               "Text": "text", "Date": "a date", "DateTime": "a date and time"}
_PLAIN = (str, int, float, bool, _dt.date)


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
        kind = type(col.type).__name__
        if v is not None and (not isinstance(v, _KINDS.get(kind, _PLAIN))
                              or (isinstance(v, bool) and kind != "Boolean")):
            raise GonioError(f"{where}: {name} is not {_KIND_NAMES.get(kind, 'a plain value')}"
                             f": {str(v)[:40]!r}", key=table.name)
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
    _check_zone(out["settings"], path)
    return out


def _check_zone(settings: list[dict], path) -> None:
    """GonioError unless the archive's setting ``timezone`` is empty (an archive written
    before stores held a zone, :func:`_settings_kept`) or a zone of the IANA database
    (:func:`gonio.records.models.laboratory_zone`, as ``gonio db set`` checks it): a store
    restored with an unknown zone would refuse every command that needs the laboratory's
    date, so the archive is refused before anything is written."""
    from gonio.records.models import laboratory_zone

    for i, r in enumerate(settings):
        if r.get("key") == "timezone" and r.get("value"):
            try:
                laboratory_zone(str(r["value"]))
            except GonioError as exc:
                raise GonioError(f"records.json settings row {i + 1} (timezone): "
                                 f"{exc.message}: nothing restored", file=path) from None


def open_archive(path: str | os.PathLike, follow_links: bool = True):
    """The archive file at ``path`` opened for reading (binary): a regular file, else a
    GonioError (a FIFO, a device or a folder is refused before a byte is read: it is
    opened non-blocking); ``follow_links=False``: a symbolic link is refused too."""
    flags = os.O_RDONLY | os.O_NONBLOCK | (0 if follow_links else os.O_NOFOLLOW)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        raise GonioError(f"cannot open the archive: {exc.strerror}", file=path) from None
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise GonioError("the archive is not a regular file", file=path)
    os.set_blocking(fd, True)
    return os.fdopen(fd, "rb")


def _open(source, path: Path) -> zipfile.ZipFile:
    try:
        return zipfile.ZipFile(source)
    except (OSError, zipfile.BadZipFile, ValueError) as exc:
        raise GonioError(f"not a gonio backup archive ({exc})", file=path) from None


#: the members of a backup archive: records.json and one blobs/<sha256> per stored file
_MEMBER = re.compile(r"records\.json|blobs/[0-9a-f]{64}")
#: what zipfile expands (an archive of another method is refused before it is read)
_METHODS = (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED, zipfile.ZIP_BZIP2, zipfile.ZIP_LZMA)
#: what reading a damaged member raises
_READ_ERRORS = (zipfile.BadZipFile, zlib.error, lzma.LZMAError, EOFError, OSError,
                RuntimeError, NotImplementedError, ValueError)


def _members(zf: zipfile.ZipFile, path: Path) -> dict[str, zipfile.ZipInfo]:
    """The archive's members by name, checked before a byte of any is expanded: records.json
    and ``blobs/<sha256>`` only (no other name: no folder, no ``..``, no absolute path),
    each once, none a symbolic link or encrypted, each of a method zipfile reads; their
    expanded sizes as the archive declares them (zipfile never expands a member past its
    declared size, and a member that expands to other bytes fails its CRC) within
    ``GONIO_MAX_BACKUP_BYTES`` together and records.json (read into memory) within
    ``GONIO_MAX_RECORDS_JSON_BYTES``: an archive that would expand past them (a zip bomb)
    is refused before it is read."""
    out: dict[str, zipfile.ZipInfo] = {}
    for info in zf.infolist():
        name, why = info.filename, ""
        if not _MEMBER.fullmatch(name):
            why = "is neither records.json nor blobs/<sha256>"
        elif name in out:
            why = "is in it twice"
        elif stat.S_ISLNK(info.external_attr >> 16):
            why = "is a symbolic link"
        elif info.flag_bits & 0x1:
            why = "is encrypted"
        elif info.compress_type not in _METHODS:
            why = f"is compressed by method {info.compress_type}, which gonio does not read"
        if why:
            raise GonioError(f"the archive's member {name[:80]!r} {why}: not a gonio backup; "
                             "nothing restored", file=path)
        out[name] = info
    total, most = sum(i.file_size for i in out.values()), limits.limit("GONIO_MAX_BACKUP_BYTES")
    if total > most:
        raise GonioError(f"the archive expands to {blobs.size_text(total)}, more than the limit "
                         f"of {blobs.size_text(most)} (GONIO_MAX_BACKUP_BYTES): nothing "
                         "restored", file=path)
    doc, most = out.get("records.json"), limits.limit("GONIO_MAX_RECORDS_JSON_BYTES")
    if doc is not None and doc.file_size > most:
        raise GonioError(f"records.json expands to {blobs.size_text(doc.file_size)}, more "
                         f"than the limit of {blobs.size_text(most)} "
                         "(GONIO_MAX_RECORDS_JSON_BYTES): nothing restored", file=path)
    return out


def _digest(zf: zipfile.ZipFile, info: zipfile.ZipInfo, path: Path) -> str:
    """The SHA-256 of a member's bytes, read piece by piece."""
    h = hashlib.sha256()
    try:
        with zf.open(info) as fh:
            for piece in iter(lambda: fh.read(1 << 20), b""):
                h.update(piece)
    except _READ_ERRORS as exc:
        raise GonioError(f"stored file {info.filename[6:18]}… unreadable ({str(exc)[:120]})",
                         file=path) from None
    return h.hexdigest()


def _checked(zf: zipfile.ZipFile, path: Path) -> tuple[dict, set, dict]:
    """An open archive checked whole, nothing written: (rows per table, the stored files'
    digests, records.json). Its members (:func:`_members`: names, links, sizes);
    records.json's tables, rows and references (:func:`_rows`); every file listed in
    ``blobs`` present in the archive (complete) and matching its SHA-256 (intact); no file
    the records do not list."""
    members = _members(zf, path)
    try:
        doc = json.loads(zf.read(members["records.json"]))
    except (KeyError, RecursionError, *_READ_ERRORS) as exc:   # RecursionError: too deep
        raise GonioError(f"no readable records.json ({str(exc)[:120] or 'nested too deeply'})",
                         file=path) from None
    rows = _rows(doc, path)
    names = {n[len("blobs/"):] for n in members if n.startswith("blobs/")}
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
        if _digest(zf, members[f"blobs/{sha}"], path) != sha:
            raise GonioError(f"stored file {sha[:12]}… does not match its SHA-256",
                             file=path)
    return rows, names, doc


def check_archive(path: str | os.PathLike, stream=None) -> dict:
    """Check a backup archive as :func:`restore` does before it writes anything, and write
    nothing (``stream``: the archive as an open binary file, ``path`` then only its name):
    a GonioError names the first problem; else ``{"gonio_version", "sha256": the SHA-256
    of the bytes checked, "rows": {table: count}, "files": count, "calibrations",
    "certificates", "newest": the latest time recorded in it (the audit trail's last
    event, UTC, "YYYY-MM-DD HH:MM") or ""}``."""
    path = Path(path)
    with (open_archive(path) if stream is None else _kept_open(stream)) as fh:
        sha = archive_sha256(fh)
        with _open(fh, path) as zf:
            rows, names, doc = _checked(zf, path)
    return {"gonio_version": str(doc.get("gonio_version", ""))[:40], "files": len(names),
            "sha256": sha, **check_summary(rows)}


def _kept_open(stream):
    """A caller's open file as a context that leaves it open."""
    import contextlib

    return contextlib.nullcontext(stream)


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


def archive_sha256(source) -> str:
    """The SHA-256 of the archive (what a confirmation names): the file at a path, or an
    open binary file read from its start (and left at its start: what is checked and
    restored afterwards are the bytes hashed, whatever the path names by then)."""
    if not hasattr(source, "read"):
        with open_archive(source) as fh:
            return archive_sha256(fh)
    h = hashlib.sha256()
    try:
        source.seek(0)
        for piece in iter(lambda: source.read(1 << 20), b""):
            h.update(piece)
        source.seek(0)
    except OSError as exc:
        raise GonioError(f"cannot read the archive: {exc.strerror}") from None
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
            expect_sha256: str | None = None, stream=None, name: str | None = None) -> dict:
    """Restore the archive at ``path`` into the records of ``store``; returns the counts of
    rows restored per table and of files.

    Everything is checked before anything is written (:func:`_checked`: records.json's
    tables, rows and references, every file listed in ``blobs`` present in the archive
    (complete) and matching its SHA-256 (intact), no file the records do not list): an
    archive a restore would lose anything of is refused whole. ``expect_sha256``: the digest
    of the archive that was verified and confirmed; a different file is refused (the file is
    opened once: the bytes hashed are the bytes restored). ``stream``: the archive as an
    open binary file (``path`` then only names it); ``name``: the archive's name for the
    audit event (an upload's own name), else the file's.

    Without ``replace`` the database must hold no user (``gonio db restore``): the settings
    ``gonio db init`` wrote are replaced by the archive's of the same key and their audit
    events appended after the archive's, which keep their ids (:func:`_set_aside`,
    :func:`_settings_kept`). With ``replace``
    (an admin ``actor``, the browser's restore) the live records are replaced atomically:
    SQLite — the archive is written into a new database file next to the live one, which is
    swapped in by one rename once complete (the replaced file is kept beside it as
    ``records.sqlite3.replaced-YYYYmmddTHHMMSS``) and the engine's connections are renewed;
    PostgreSQL — every table emptied and refilled in one transaction. A failure at any step
    leaves the live records as they were (their audit trail then records the refusal:
    action ``restore-refused``, the archive's name and the reason). The caller keeps other requests and the workers
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
    try:
        if replace and store.engine.dialect.name == "sqlite":
            limits.keep_replaced()             # a bad GONIO_KEEP_REPLACED: before any work
        with (open_archive(path) if stream is None else _kept_open(stream)) as fh:
            return _restore_open(store, fh, path, replace=replace, actor=actor,
                                 expect_sha256=expect_sha256, label=name or path.name)
    except GonioError as exc:
        if replace:
            _audit_refusal(store, actor, name or path.name, expect_sha256, exc)
        raise


def _audit_refusal(store, actor, label: str, sha256: str | None, exc: GonioError) -> None:
    """A restore over the live records that was refused or failed, appended to their audit
    trail, which it left as it was (action ``restore-refused``: the archive's name and the
    reason). A database that cannot take the event now (the failure's own cause, say) is
    left alone: the caller reports the failure either way."""
    from sqlalchemy.exc import SQLAlchemyError

    from gonio.records.services import audit

    try:
        with store.writing() as s:
            if store.engine.dialect.name == "postgresql":
                s.execute(text(f"SET LOCAL lock_timeout = '{int(LOCK_TIMEOUT_S)}s'"))
            audit(s, actor, "restore-refused", "records", (sha256 or "")[:64],
                  after={"archive": label[:200], "reason": exc.message[:500]})
            s.commit()
    except SQLAlchemyError:
        pass


def _restore_open(store, fh, path: Path, *, replace: bool, actor, expect_sha256,
                  label: str) -> dict:
    """:func:`restore` from the archive open as ``fh``."""
    sha = archive_sha256(fh)
    if expect_sha256 is not None and sha != expect_sha256:
        raise GonioError("the archive is not the one verified and confirmed (its SHA-256 "
                         "changed): verify it again; nothing restored", file=path)
    with _open(fh, path) as zf:
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
        event = {"archive": label[:200], "sha256": sha, "newest": check_summary(rows)["newest"],
                 "gonio_version": str(doc.get("gonio_version", ""))[:40],
                 "rows": {k: len(v) for k, v in rows.items() if v}, "files": len(names)}
        if replace:
            event["replaced"] = summary(store)["rows"]
            kept = _counters_kept(store, rows)
            if kept:
                event["counters_kept"] = kept
        _check_space(store, zf, names, path)
        for sha_file in sorted(names):
            _put_blob(store.blob_root, sha_file, zf, path)
    _fill_stated(store, rows)
    _fill_content(store, rows)
    who = actor.username if actor is not None else "(command line)"
    _restored_records_verify(store, rows, path, dict(event), who)
    if not replace:
        with store.writing() as s:
            _still_no_user(s, path)
            _write(s, rows, path, event, who, own=_set_aside(s))
            s.commit()
    elif store.engine.dialect.name == "sqlite":
        _swap_sqlite(store, rows, path, event, who)
    else:
        _replace_postgresql(store, rows, path, event, who)
    counts = {k: len(v) for k, v in rows.items() if v}
    counts["files"] = len(names)
    return counts


def _restored_records_verify(store, rows: dict, path: Path, event: dict, who: str) -> None:
    """The archive's records as they would be restored verify (:func:`verify`: every seal
    signed, every result row against its results.json, the rows' consistency): they are
    written first into a scratch SQLite store in a temporary folder whose blob store is this
    store's (the archive's files are in it already), and checked there. A problem is a
    GonioError naming it and the number of others: nothing restored (an archive whose result
    row was changed, or whose certificate or audit rows were taken out, restored with exit 0
    before and only a later verify saw it, or nothing did)."""
    import sqlite3

    from sqlalchemy.exc import SQLAlchemyError

    from gonio.records.db import open_store

    with tempfile.TemporaryDirectory(prefix="gonio-restore-check-") as tmp:
        data = Path(tmp) / "data"
        data.mkdir()
        os.symlink(os.path.realpath(store.blob_root), data / "blobs")
        try:
            scratch = open_store(None, data)
            try:
                with scratch.writing() as s:
                    _write(s, rows, path, event, who, own=_set_aside(s))
                    s.commit()
                _, problems = verify(scratch)
            finally:
                scratch.close()
        except (SQLAlchemyError, sqlite3.Error, OSError) as exc:   # a disk full, say
            msg = str(getattr(exc, "orig", exc)).strip().splitlines()[0][:200]
            raise GonioError(f"the restored records could not be written ({msg}): the live "
                             "records are unchanged; nothing restored", file=path) from None
    if problems:
        raise GonioError(f"the archive's records do not verify: {first_of(problems)}; nothing "
                         "restored", file=path)


def _still_no_user(s, path: Path) -> None:
    """The no-user check again, in the writing transaction that sets the store's own events
    aside (:func:`_set_aside`), so a user added since the first check (another command or a
    web process on the same store) is seen: SQLite's transaction holds the write lock from
    its first statement (BEGIN IMMEDIATE), PostgreSQL's locks both tables first. GonioError
    (nothing restored) if the store holds a user now."""
    if s.get_bind().dialect.name == "postgresql":
        s.execute(text(f"SET LOCAL lock_timeout = '{int(LOCK_TIMEOUT_S)}s'"))
        s.execute(text("LOCK TABLE users, audit_events IN EXCLUSIVE MODE"))
    if s.scalar(select(func.count()).select_from(User)):
        s.rollback()
        raise GonioError("the database holds records already (a user was added while the "
                         "archive was read); restore into an empty one (gonio db init on "
                         "a new data folder or database): nothing restored", file=path)


def _fill_stated(store, rows: dict) -> None:
    """The result rows of an archive written before rows kept their statement (no
    ``stated`` column, or None) get it from their calibration's stored results.json (in the
    blob store by now), as the migration fills a database's
    (:func:`gonio.records.results.fill_stated`)."""
    from gonio.records.results import fill_stated

    sha = {c.get("id"): c.get("results_sha256") for c in rows["calibrations"]}
    fill_stated(store.blob_root, rows["result_items"], lambda r: sha.get(r.get("calibration_id")))


def _counters_kept(store, rows: dict) -> dict:
    """A restore over live records never sets a year's certificate counter back: where the
    live counter is ahead of the archive's (certificates numbered after the backup was made),
    the restored counter keeps the live one, so that no number issued before is given again
    to another certificate (the numbers in between stay unused: the certificates they name
    are not in the archive). Changes ``rows`` in place; returns ``{year: {"archive": n,
    "kept": m}}`` for the audit event."""
    from gonio.records.models import CertificateCounter

    with store.session() as s:
        live = dict(s.execute(select(CertificateCounter.year, CertificateCounter.last)).all())
    archive = {r["year"]: r for r in rows["certificate_counters"]}
    kept = {}
    for year, last in sorted(live.items()):
        row = archive.get(year)
        if row is None:
            rows["certificate_counters"].append({"year": year, "last": last})
            kept[str(year)] = {"archive": 0, "kept": last}
        elif (row.get("last") or 0) < last:
            kept[str(year)] = {"archive": row.get("last") or 0, "kept": last}
            row["last"] = last
    return kept


def _fill_content(store, rows: dict) -> None:
    """The readings' content digests and source streams as the restored files give them,
    never as the archive states them (an archive's digest could hide readings calibrated
    twice): every calibration's readings file digested
    (:func:`gonio.records.blobs.content_rows`)."""
    stored = {b.get("sha256") for b in rows["blobs"]}
    shas = sorted({c.get("readings_sha256") for c in rows["calibrations"]} & stored)
    rows["readings_contents"] = blobs.content_rows(store.blob_root, shas)


def check_summary(rows: dict) -> dict:
    """An archive's checked rows counted (see :func:`check_archive`)."""
    stamps = [r["at"] for r in rows.get("audit_events", []) if r.get("at") is not None]
    return {"rows": {k: len(v) for k, v in rows.items()},
            "calibrations": len(rows.get("calibrations", [])),
            "certificates": len(rows.get("certificates", [])),
            "newest": max(stamps).isoformat(sep=" ", timespec="minutes") if stamps else ""}


#: room a restore leaves free on the data folder's disk beyond what it writes (bytes)
SPARE_BYTES = 64 * 2**20


def _check_space(store, zf: zipfile.ZipFile, names, path: Path) -> None:
    """GonioError unless the data folder's disk has room for what the restore writes there:
    the stored files the store lacks (their expanded sizes) and, on SQLite, the new records
    file (taken as twice records.json) — checked before a byte is written."""
    need = sum(zf.getinfo(f"blobs/{sha}").file_size for sha in names
               if not blobs.blob_path(store.blob_root, sha).is_file())
    if store.engine.dialect.name == "sqlite":
        need += 2 * zf.getinfo("records.json").file_size
    store.blob_root.mkdir(parents=True, exist_ok=True)
    free = shutil.disk_usage(store.blob_root).free
    if need + SPARE_BYTES > free:
        raise GonioError(f"the restore needs {blobs.size_text(need)} on the data folder's disk "
                         f"and {blobs.size_text(free)} is free: nothing restored", file=path)


def _put_blob(root: Path, sha: str, zf: zipfile.ZipFile, path: Path) -> None:
    """A stored file from the archive (checked against ``sha`` already) into the store,
    read piece by piece; a missing or damaged copy there is replaced."""
    target = blobs.blob_path(root, sha)
    if target.is_file() and blobs.verify(root, sha):
        return
    try:
        if target.exists():
            target.unlink()
        with zf.open(f"blobs/{sha}") as fh:
            blobs.put_stream(root, fh)
    except OSError as exc:
        raise GonioError(f"cannot write the stored file {sha[:12]}… ({exc.strerror}): the "
                         "records are unchanged; nothing restored", file=root) from None


def _write(s, rows: dict, path: Path, event: dict, who: str, own: list | None = None) -> None:
    """Insert the checked ``rows`` in dependency order in the session's transaction, move
    PostgreSQL's id sequences past them, and append the restore's audit event (its user the
    restored account of ``who``, if there is one). ``own``: the target store's own audit
    events, set aside by :func:`_set_aside` (a restore into a store that holds no user):
    appended after the archive's, unchanged but for their ids, the restore's event naming
    their ids before and after and the store's settings the archive's replaced. A row the
    database refuses is a GonioError (the transaction rolled back)."""
    from sqlalchemy.exc import SQLAlchemyError

    from gonio.records.models import AuditEvent

    try:
        for table in _tables():
            todo, replaced, removed = (_settings_kept(s, rows[table.name])
                                       if table.name == "settings"
                                       else (rows[table.name], {}, {}))
            if own is not None and replaced:
                event["settings_replaced"] = replaced
            if removed:
                event["settings_removed"] = removed
            if todo:
                s.execute(table.insert(), todo)
        if own:
            start = max((r["id"] for r in rows["audit_events"]), default=0) + 1
            moved = [dict(r, id=start + i) for i, r in enumerate(own)]
            s.execute(AuditEvent.__table__.insert(), moved)
            event["store_events"] = {"were": [r["id"] for r in own],
                                     "now": [r["id"] for r in moved]}
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


def _settings_kept(s, settings: list[dict]) -> tuple[list[dict], dict, dict]:
    """The archive's ``settings`` rows to insert into the session's database, the
    database's values they replace (``{key: [its value, the archive's]}``, where they
    differ) and the database's rows removed without a replacement (``{key: its value}``).
    The archive's setting of a key replaces the database's (that row deleted first:
    ``gonio db init``'s laboratory details, the ``timezone`` its migration wrote); a key the
    archive lacks keeps the database's row, but for the laboratory's identity (every
    ``lab_*`` key), which travels as one group: where the archive holds any of them, the
    database's ``lab_*`` keys the archive lacks are removed, so that no certificate states
    one laboratory's name beside another's accreditation or contact. An archive without a zone or with an
    empty one (written before stores held one) keeps the database's, else gets this
    machine's (:func:`gonio.records.models.machine_zone`), as the migration gives an older
    store."""
    from sqlalchemy import delete

    from gonio.records.models import Setting, machine_zone

    live = dict(s.execute(select(Setting.key, Setting.value)).all())
    todo = [r for r in settings if r.get("key") != "timezone" or r.get("value")]
    if not any(r.get("key") == "timezone" for r in todo) and not live.get("timezone"):
        todo.append({"key": "timezone", "value": machine_zone()})
    keys = [r.get("key") for r in todo]
    replaced = {r["key"]: [live[r["key"]], r.get("value")] for r in todo
                if r.get("key") in live and live[r["key"]] != r.get("value")}
    removed = {}
    if any(str(k).startswith("lab_") for k in keys):
        removed = {k: v for k, v in sorted(live.items())
                   if k.startswith("lab_") and k not in keys}
    if keys or removed:
        s.execute(delete(Setting).where(Setting.key.in_([*keys, *removed])))
    return todo, replaced, removed


def _set_aside(s) -> list[dict]:
    """The audit events a store that holds no user has already (``gonio db init``'s
    settings), as rows in id order, removed from ``audit_events`` in the session's
    transaction, so that the archive's trail keeps its own ids; :func:`_write` appends them
    after the archive's. The table refuses ``DELETE`` (its triggers): PostgreSQL empties it
    by ``TRUNCATE`` (no row trigger fires), SQLite drops its trigger, deletes and makes the
    trigger again from its own stored text — one transaction, rolled back on any failure."""
    from gonio.records.models import AuditEvent

    table = AuditEvent.__table__
    own = [dict(r) for r in s.execute(select(table).order_by(table.c.id)).mappings()]
    if not own:
        return own
    if s.get_bind().dialect.name == "postgresql":
        s.execute(text("TRUNCATE audit_events"))
        return own
    trigger = s.scalar(text("SELECT sql FROM sqlite_master WHERE type = 'trigger' "
                            "AND name = 'audit_events_no_delete'"))
    if trigger:
        s.execute(text("DROP TRIGGER audit_events_no_delete"))
    s.execute(table.delete())
    if trigger:
        s.execute(text(trigger))
    return own


def _swap_sqlite(store, rows: dict, path: Path, event: dict, who: str) -> None:
    """SQLite: the restored records written into a new file beside the live one (migrated,
    filled, checkpointed), then swapped in by one rename; the live engine's connections are
    closed first and renewed by its next use."""
    import sqlite3

    from sqlalchemy.exc import SQLAlchemyError
    from sqlalchemy.orm import Session as OrmSession

    from gonio.records.db import make_engine, migrate

    live = Path(store.engine.url.database)
    try:
        fd, new = tempfile.mkstemp(prefix=f".{live.name}.restoring-", dir=live.parent)
    except OSError as exc:
        raise GonioError(f"cannot write beside the records database ({exc.strerror}): "
                         "nothing restored", file=live) from None
    os.close(fd)
    engine = make_engine(f"sqlite:///{new}")
    try:
        try:
            migrate(engine)
            with OrmSession(engine.execution_options(gonio_write=True)) as s:
                _write(s, rows, path, event, who)
                s.commit()
        except (SQLAlchemyError, sqlite3.Error, OSError) as exc:   # a disk full, say
            msg = str(getattr(exc, "orig", exc)).strip().splitlines()[0][:200]
            raise GonioError(f"the restored records could not be written ({msg}): the live "
                             "records are unchanged; nothing restored", file=new) from None
        engine.dispose()
        store.engine.dispose()
        if _one_file(new) != "delete":
            raise GonioError("the restored database could not be written as one file: "
                             "nothing restored", file=new)
        _swap_in(live, Path(new))
    finally:
        engine.dispose()
        for leftover in (new, f"{new}-wal", f"{new}-shm", f"{new}-journal"):
            Path(leftover).unlink(missing_ok=True)
    store.engine.dispose()
    prune_replaced(live, limits.keep_replaced())


def prune_replaced(live: Path, keep: int) -> list[Path]:
    """Remove all but the newest ``keep`` replaced files of the SQLite database ``live``
    (``NAME.replaced-YYYYmmddTHHMMSS``, ``-N`` for a later one within the same second; newest
    by that stamp, never by the file's times, which are those of the replaced records' last
    write); returns the files removed. Only regular files of that exact form are touched;
    one that cannot be removed is left (the restore has succeeded)."""
    form = re.compile(re.escape(live.name)
                      + r"\.replaced-([0-9]{8}T[0-9]{6})(?:-([0-9]{1,3}))?")
    found = []
    for p in live.parent.iterdir():
        m = form.fullmatch(p.name)
        if m and p.is_file() and not p.is_symlink():
            found.append(((m[1], int(m[2] or 1)), p))
    gone = []
    for _, p in sorted(found, reverse=True)[keep:]:
        try:
            p.unlink()
        except OSError:
            continue
        gone.append(p)
    return gone


def _swap_in(live: Path, new: Path) -> None:
    """The new SQLite file renamed over the live one, the live one kept beside it as
    ``records.sqlite3.replaced-STAMP``; refused while another connection has the live file
    open (nobody else writes). A failing rename is a GonioError, the live file unchanged."""
    import sqlite3

    raw = sqlite3.connect(live, timeout=5, isolation_level=None)
    kept = None
    try:
        if _one_file(live, raw) != "delete":
            raise GonioError("another process has the records database open (a worker, "
                             "a gonio command): nothing restored", file=live)
        for extra in ("-wal", "-shm"):
            Path(f"{live}{extra}").unlink(missing_ok=True)
        stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y%m%dT%H%M%S")
        for n in range(1, 100):                     # two restores within one second
            kept = live.with_name(f"{live.name}.replaced-{stamp}" + (f"-{n}" if n > 1 else ""))
            if not kept.exists():
                break
        os.link(live, kept)
        os.replace(new, live)
    except OSError as exc:
        if kept is not None and kept.exists() and os.path.samefile(kept, live):
            kept.unlink()                           # the live file stays the only name
        raise GonioError(f"the restored records could not be swapped in ({exc.strerror}): "
                         "the live records are unchanged; nothing restored", file=live) from None
    finally:
        raw.close()


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


#: how long a PostgreSQL restore waits for another connection's hold on a table
LOCK_TIMEOUT_S = 30


def _replace_postgresql(store, rows: dict, path: Path, event: dict, who: str) -> None:
    """PostgreSQL: every table emptied (TRUNCATE: no row triggers, its identity resets
    transactional) and refilled in one transaction; a failure rolls all of it back."""
    from sqlalchemy.exc import SQLAlchemyError

    names = ", ".join(t.name for t in _tables())
    with store.writing() as s:
        try:
            s.execute(text(f"SET LOCAL lock_timeout = '{int(LOCK_TIMEOUT_S)}s'"))
            s.execute(text(f"TRUNCATE {names} RESTART IDENTITY"))
        except SQLAlchemyError as exc:   # another connection holds a table past the timeout
            s.rollback()
            msg = str(getattr(exc, "orig", exc)).strip().splitlines()[0][:200]
            raise GonioError(f"the live records could not be emptied for the restore ({msg}): "
                             "they are unchanged; nothing restored", file=path) from None
        _write(s, rows, path, event, who)
        s.commit()
    store.engine.dispose()


def verify(store, files: bool = True) -> tuple[dict, list[str]]:
    """Check a live database as a backup and a restore check an archive: every stored file
    present and matching its SHA-256, every computed calibration's result rows matching its
    stored results.json and, where it was signed, its seal the one signed (at review, at
    approval, on its newest certificate), and a reviewed or approved calibration's details
    the ones its reviewed draft states (:func:`gonio.records.services.details_changed`; an
    amendment waiting for its issue: what its approval fixed,
    :func:`gonio.records.services.amendment_problems`), each row against the audit events
    its state implies (:func:`gonio.records.services.trail_problems`,
    :func:`gonio.records.services.register_problems`: customers, instruments, standards), the
    protective triggers
    (:func:`trigger_problems`) and the rows' consistency (:func:`consistency_problems`);
    ``files`` False leaves out the
    stored files' digests (checked by the caller). Returns (counts, problems: one line
    each)."""
    from gonio.records import services
    from gonio.records.models import Calibration, Certificate

    problems = []
    with store.session() as s:
        shas = [r[0] for r in s.execute(select(Blob.sha256))]
        cals = s.execute(select(Calibration.id, Calibration.status, Calibration.reviewed_seal,
                                Calibration.approved_seal, Calibration.pending_number,
                                Calibration.pending_replaces_id).where(
            Calibration.results_sha256.is_not(None)).order_by(Calibration.id)).all()
        certs = s.execute(select(Certificate.calibration_id, Certificate.number,
                                 Certificate.seal_sha256).order_by(Certificate.id)).all()
    if files:          # (``files`` False: the caller checked every stored file already)
        problems += [f"stored file {b}" for b in damaged_files(store, shas)]
    newest = {cid: (number, sealed) for cid, number, sealed in certs}
    for cid, status, reviewed, approved, pending, replaces in cals:
        # an approved issue that failed keeps its number and the seal approved: checked too
        waiting = status in ("issuing", "amending") or (status == "failed" and bool(pending))
        try:
            now = services.seal(store, cid)
        except GonioError as exc:
            problems.append(f"calibration {cid}: {exc.message}")
            continue
        signed = [("its review", reviewed if status in ("reviewed",) else ""),
                  ("its approval", approved if waiting else ""),
                  (f"certificate {newest.get(cid, ('', ''))[0]}",
                   newest.get(cid, ("", ""))[1] or "")]
        for (what, sealed), action in zip(signed, ("review", "approve", "approve")):
            if sealed and sealed != now:
                problems.append(f"calibration {cid}: its stored result no longer matches the "
                                f"seal of {what}"
                                f"{services.seal_differences(store, cid, action)}")
        # what was reviewed is what is approved; an amendment waiting for its issue states
        # what its approval fixed (services.amendment_problems, with the trail below)
        if status == "reviewed" or (status == "issuing" and not replaces):
            problems += [f"calibration {cid}: {line}"
                         for line in services.details_changed(store, cid)]
    with store.session() as s:                    # each row against its own audit trail
        for cal in s.scalars(select(Calibration).order_by(Calibration.id)):
            problems += [f"calibration {cal.id}: {line}"
                         for line in services.trail_problems(s, cal)]
        for entity in services.REGISTER_TRAIL:
            problems += services.register_problems(s, entity)
    problems += trigger_problems(store) + consistency_problems(store)
    return {"files": len(shas), "calibrations": len(cals), "certificates": len(certs)}, problems


#: The tables whose rows are inserted and never updated or deleted, each kept so by two
#: triggers, ``TABLE_no_update`` and ``TABLE_no_delete`` (migrations 0001, 0009, 0010, 0014).
FROZEN_TABLES = ("audit_events", "certificates", "blobs", "table_calibrations",
                 "table_calibration_withdrawals", "readings_contents")


def trigger_problems(store) -> list[str]:
    """The protective triggers missing from the database (one line each): every table of
    :data:`FROZEN_TABLES` has its ``TABLE_no_update`` and ``TABLE_no_delete`` (on
    PostgreSQL: enabled). Without them
    the audit trail, an issued certificate or a stored file can be rewritten or deleted
    with no error, so their absence is a finding, not a detail of the set-up."""
    from sqlalchemy import text

    with store.session() as s:
        if s.get_bind().dialect.name == "postgresql":
            have = set(s.scalars(text("SELECT tgname FROM pg_trigger WHERE NOT tgisinternal "
                                          "AND tgenabled <> 'D'")))
        else:
            have = set(s.scalars(text("SELECT name FROM sqlite_master WHERE type = 'trigger'")))
    return [f"table {table}: its trigger {table}_no_{verb} is missing (its rows can be "
            f"{verb}d without an error)" for table in FROZEN_TABLES
            for verb in ("update", "delete") if f"{table}_no_{verb}" not in have]


def consistency_problems(store) -> list[str]:
    """What the records' rows say of each other that cannot be (one line each): an issued
    calibration without a certificate; a year's certificate counter behind a number issued
    or reserved in that year (the next approval would use it again); a certificate whose
    approver created the calibration it first certifies, or a calibration reviewed by its
    creator (ISO/IEC 17025 7.8.1.1: refused on every path, so such a row was written around
    the records)."""
    from gonio.records.models import Calibration, Certificate, CertificateCounter
    from gonio.records.services import NUMBER_PREFIX

    out = []
    with store.session() as s:
        issued = set(s.scalars(select(Certificate.calibration_id)))
        for cid in s.scalars(select(Calibration.id).where(Calibration.status == "issued")
                             .order_by(Calibration.id)):
            if cid not in issued:
                out.append(f"calibration {cid}: issued, and no certificate of it is recorded")
        last = dict(s.execute(select(CertificateCounter.year, CertificateCounter.last)).all())
        numbers = list(s.scalars(select(Certificate.number))) + [
            n for n in s.scalars(select(Calibration.pending_number)) if n]
        for number in sorted(numbers):
            m = re.fullmatch(rf"{re.escape(NUMBER_PREFIX)}-(\d{{4}})-(\d+)", number)
            if m and int(m.group(2)) > last.get(int(m.group(1)), 0):
                out.append(f"certificate {number}: beyond the {m.group(1)} counter "
                           f"({last.get(int(m.group(1)), 0)}): the next approval would "
                           "number another certificate the same")
        for number, approver, creator in s.execute(
                select(Certificate.number, Certificate.issued_by_id, Calibration.created_by_id)
                .join(Calibration, Calibration.id == Certificate.calibration_id)
                .where(Certificate.replaces_id.is_(None)).order_by(Certificate.id)):
            if approver is not None and approver == creator:
                out.append(f"certificate {number}: approved by the person who created its "
                           "calibration")
        for cid, reviewer in s.execute(
                select(Calibration.id, Calibration.reviewed_by_id)
                .where(Calibration.reviewed_by_id.is_not(None),
                       Calibration.reviewed_by_id == Calibration.created_by_id)
                .order_by(Calibration.id)):
            out.append(f"calibration {cid}: reviewed by the person who created it")
    return out
