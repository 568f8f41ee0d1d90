"""Opening the records database: SQLite (WAL) in a data folder by default, PostgreSQL
(psycopg 3) by URL; the schema is brought up to date by the shipped Alembic migrations
on every open (Alembic itself is imported only when the database is not at the newest
migration already: :func:`at_head`).

>>> import tempfile
>>> store = open_store(data=tempfile.mkdtemp())
>>> store.url.startswith("sqlite:///") and store.engine.dialect.name
'sqlite'
>>> store.close()
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

from sqlalchemy import create_engine, event
from sqlalchemy.engine import Engine, make_url
from sqlalchemy.exc import ArgumentError
from sqlalchemy.orm import Session, sessionmaker

from gonio.errors import GonioError

#: Default data folder (database, blob store, worker folders): ``$GONIO_DATA`` or
#: ``~/.local/share/gonio``.
DEFAULT_DATA = "~/.local/share/gonio"

MIGRATIONS = Path(__file__).resolve().parent / "migrations"


def data_folder(data: str | os.PathLike | None) -> Path:
    """The data folder to use (created, mode 0700 when new)."""
    path = Path(os.path.expanduser(str(data or os.environ.get("GONIO_DATA") or DEFAULT_DATA)))
    try:
        path.mkdir(parents=True, exist_ok=True, mode=0o700)
    except OSError as exc:
        raise GonioError(f"cannot create the data folder: {exc.strerror}", file=path) from None
    if not path.is_dir():
        raise GonioError("the data folder is not a folder", file=path)
    return path


def database_url(database: str | None, data: Path) -> str:
    """``database`` as a SQLAlchemy URL: None → SQLite ``records.sqlite3`` in ``data``;
    ``postgresql://…`` is read with the psycopg 3 driver."""
    if not database:
        return f"sqlite:///{data / 'records.sqlite3'}"
    try:
        url = make_url(database)
    except ArgumentError:
        raise GonioError("not a database URL (sqlite:///FILE or postgresql://USER@HOST/DB)",
                         key="--database") from None
    if url.drivername in ("postgresql", "postgres"):
        url = url.set(drivername="postgresql+psycopg")
    if url.get_backend_name() not in ("sqlite", "postgresql"):
        raise GonioError(f"unsupported database {url.get_backend_name()!r} "
                         "(sqlite or postgresql)", key="--database")
    return url.render_as_string(hide_password=False)


#: How long a SQLite connection waits for another process's lock before giving up (s).
BUSY_TIMEOUT_S = 30


def _sqlite_connect(dbapi_conn, _record) -> None:
    dbapi_conn.isolation_level = None          # transactions are begun by _sqlite_begin
    cur = dbapi_conn.cursor()
    cur.execute("PRAGMA journal_mode=WAL")
    cur.execute("PRAGMA synchronous=NORMAL")
    cur.execute("PRAGMA foreign_keys=ON")
    cur.execute(f"PRAGMA busy_timeout={int(BUSY_TIMEOUT_S * 1000)}")
    cur.close()


def _sqlite_begin(conn) -> None:
    # a writing session takes the write lock at BEGIN, so concurrent writers wait on the
    # busy timeout instead of failing when a read snapshot turns out stale at the write
    immediate = conn.get_execution_options().get("gonio_write", False)
    conn.exec_driver_sql("BEGIN IMMEDIATE" if immediate else "BEGIN")


def make_engine(url: str) -> Engine:
    """An engine for ``url``; SQLite gets WAL, foreign keys and a 30 s busy timeout."""
    if url.startswith("sqlite"):
        engine = create_engine(url, connect_args={"check_same_thread": False,
                                                  "timeout": BUSY_TIMEOUT_S})
        event.listen(engine, "connect", _sqlite_connect)
        event.listen(engine, "begin", _sqlite_begin)
        return engine
    return create_engine(url, pool_pre_ping=True, pool_size=10, max_overflow=20)


def migrate(engine: Engine, revision: str = "head", blob_root: Path | None = None) -> None:
    """Bring the schema to ``revision`` with the shipped Alembic migrations; ``blob_root``:
    the records' blob store, from which a migration that derives columns from the stored
    files fills the existing rows (without it they are left unfilled)."""
    from alembic import command
    from alembic.config import Config

    cfg = Config()
    cfg.set_main_option("script_location", str(MIGRATIONS))
    sqlite = engine.dialect.name == "sqlite"
    with engine.connect() as conn:
        # SQLite changes a table's constraints by making the table again (0010): with
        # foreign keys off, set outside the transaction (the driver runs without one until
        # the first statement), checked before the commit, and on again after — SQLite's
        # own procedure (lang_altertable.html, "other kinds of table schema changes")
        raw = conn.connection.dbapi_connection
        if sqlite:
            raw.execute("PRAGMA foreign_keys=OFF")
        try:
            with conn.begin():
                cfg.attributes["connection"] = conn
                cfg.attributes["blob_root"] = blob_root
                command.upgrade(cfg, revision)
                if sqlite:
                    bad = conn.exec_driver_sql("PRAGMA foreign_key_check").fetchall()
                    if bad:
                        raise GonioError(f"the migration left {len(bad)} row(s) whose "
                                         f"reference is missing (first: {tuple(bad[0])}): "
                                         "nothing changed", key="database")
        finally:
            if sqlite:
                raw.execute("PRAGMA foreign_keys=ON")


def head_revision() -> str | None:
    """The newest shipped migration: the revision no other migration revises, read from the
    ``revision`` and ``down_revision`` lines of the migration files; None unless they form
    one chain with a single head (then Alembic decides)."""
    revisions, revised = set(), set()
    for path in (MIGRATIONS / "versions").glob("*.py"):
        text = path.read_text(encoding="utf-8")
        rev = re.search(r"^revision\s*=\s*['\"]([^'\"]+)['\"]", text, re.M)
        down = re.search(r"^down_revision\s*=\s*(.+)$", text, re.M)
        if rev:
            revisions.add(rev.group(1))
        if down:
            revised.update(re.findall(r"['\"]([^'\"]+)['\"]", down.group(1)))
    heads = revisions - revised
    return heads.pop() if len(heads) == 1 else None


def at_head(engine: Engine) -> bool:
    """Whether the database's recorded revision (Alembic's ``alembic_version`` table) is the
    newest shipped one, read with one query; False when it cannot tell (no table yet, an
    unreadable database: :func:`migrate` then runs and says what is wrong)."""
    from sqlalchemy.exc import DBAPIError

    head = head_revision()
    if head is None:
        return False
    try:
        with engine.connect() as conn:
            rows = conn.exec_driver_sql("SELECT version_num FROM alembic_version").fetchall()
    except DBAPIError:
        return False
    return [r[0] for r in rows] == [head]


def database_problem(exc: BaseException) -> str | None:
    """The one line a database error deserves (a file that is no database, a database locked
    by another process, a read-only database, one that cannot be reached), or None when
    ``exc`` is no database error.

    >>> import sqlite3
    >>> from sqlalchemy.exc import OperationalError
    >>> database_problem(OperationalError("x", {}, sqlite3.OperationalError("database is locked")))
    'the database is locked by another process (waited 30 s): try again when it is done'
    """
    from sqlalchemy.exc import DBAPIError

    if not isinstance(exc, DBAPIError):
        return None
    msg = str(exc.orig).strip().splitlines()[0] if exc.orig is not None else str(exc)
    low = msg.lower()
    if "locked" in low:
        return (f"the database is locked by another process (waited {BUSY_TIMEOUT_S:g} s): "
                "try again when it is done")
    if "readonly" in low or "read-only" in low:
        return f"the database is read-only ({msg}): give a writable file or folder"
    if "not a database" in low or "malformed" in low or "corrupt" in low:
        return f"not a readable records database ({msg}): restore it from a backup"
    return f"cannot use the database: {msg[:200]}"


@dataclass
class Store:
    """An open records store: the database engine, a session factory, the data folder
    (its ``blobs/`` hold the content-addressed files)."""

    url: str
    engine: Engine
    sessions: sessionmaker
    data: Path

    def session(self) -> Session:
        """A session for reading (and small writes)."""
        return self.sessions()

    def writing(self) -> Session:
        """A session that writes: on SQLite it holds the write lock from its first
        statement (BEGIN IMMEDIATE), so concurrent writers queue instead of failing."""
        return self.sessions(bind=self.engine.execution_options(gonio_write=True))

    @property
    def blob_root(self) -> Path:
        return self.data / "blobs"

    def close(self) -> None:
        self.engine.dispose()


def open_store(database: str | None = None, data: str | os.PathLike | None = None, *,
               upgrade: bool = True) -> Store:
    """Open (and migrate) the records: SQLite in ``data`` unless ``database`` is a URL."""
    folder = data_folder(data)
    url = database_url(database, folder)
    engine = make_engine(url)
    if upgrade:
        try:
            if not at_head(engine):   # Alembic's import (~0.2 s) only when there is work
                migrate(engine, blob_root=folder / "blobs")
        except Exception as exc:
            engine.dispose()
            problem = database_problem(exc)
            if problem:
                raise GonioError(problem, key="--database") from None
            raise
    return Store(url=url, engine=engine,
                 sessions=sessionmaker(engine, expire_on_commit=False,
                                      info={"blob_root": folder / "blobs"}), data=folder)
