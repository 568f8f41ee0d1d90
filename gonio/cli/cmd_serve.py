"""``gonio serve``: the laboratory's records in a browser (docs/records.md)."""

from __future__ import annotations

import secrets
import sys


def add_store_options(p) -> None:
    """``--database URL`` and ``--data DIR`` (shared by serve, db and calibrate --record)."""
    p.add_argument("--database", default=None, metavar="URL",
                   help="database URL (default: SQLite in the data folder; "
                        "postgresql://USER:PASSWORD@HOST/DB for several workstations)")
    p.add_argument("--data", default=None, metavar="DIR",
                   help="data folder: SQLite database and stored files (default: $GONIO_DATA "
                        "or ~/.local/share/gonio)")


def database_errors(run):
    """``run`` with a database error (a corrupt, locked or read-only database) turned into
    the one-line GonioError of :func:`gonio.records.db.database_problem`."""
    import functools

    @functools.wraps(run)
    def wrapped(args) -> int:
        try:
            return run(args)
        except Exception as exc:
            # imported here, not before the run: SQLAlchemy is most of a second of imports
            # that gonio serve's login page, answered before the records open, does not need
            from gonio.records.db import database_problem

            problem = database_problem(exc)
            if problem is None:
                raise
            from gonio.errors import GonioError
            raise GonioError(problem, key="--database") from None
    return wrapped


def register(sub) -> None:
    p = sub.add_parser("serve", help="the laboratory's records in a browser",
                       description="Serve the records (instruments, calibrations, "
                                   "certificates) to a browser on this machine.")
    add_store_options(p)
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1: this machine only)")
    p.add_argument("--port", type=int, default=8765, help="port (default 8765)")
    p.add_argument("--workers", type=int, default=None,
                   help="calibrations run at the same time (default 2; at most "
                        "$GONIO_MAX_WORKERS, else the machine's cores)")
    p.set_defaults(func=database_errors(run))


def first_admin(store) -> str | None:
    """On a database without users: create ``admin`` with a random password (returned)."""
    from gonio.records import queries, services

    if queries.users(store):
        return None
    password = secrets.token_urlsafe(12)
    services.create_user(store, None, "admin", password, "admin technician reviewer",
                         "Administrator")
    return password


def check_workers(workers: int | None) -> int:
    """``--workers`` within 1 … ``GONIO_MAX_WORKERS`` (:func:`gonio.limits.limit`; unset:
    the machine's cores, at least the default 2), else a GonioError; None: 2, or the cap if
    lower."""
    import os

    from gonio.errors import GonioError
    from gonio.limits import limit

    top = max(1, int(limit("GONIO_MAX_WORKERS")))
    if not os.environ.get("GONIO_MAX_WORKERS", "").strip():
        top = max(2, top)
    if workers is None:
        return min(2, top)
    if not 1 <= workers <= top:
        raise GonioError(f"must be within 1 … {top} (GONIO_MAX_WORKERS, else the machine's "
                         f"cores), got {workers}", key="--workers")
    return workers


def check_backup_limits() -> None:
    """``GONIO_MAX_UPLOAD_BYTES``, ``GONIO_MAX_BACKUP_BYTES`` and
    ``GONIO_MAX_RECORDS_JSON_BYTES`` read at start
    (:func:`gonio.limits.limit`), and ``GONIO_KEEP_REPLACED``
    (:func:`gonio.limits.keep_replaced`): a bad value is one line before anything is
    opened, not a surprise at the first backup upload or restore."""
    from gonio.limits import keep_replaced, limit

    for name in ("GONIO_MAX_UPLOAD_BYTES", "GONIO_MAX_BACKUP_BYTES",
                 "GONIO_MAX_RECORDS_JSON_BYTES"):
        limit(name)
    keep_replaced()                     # GONIO_KEEP_REPLACED, the restores' replaced files


def run(args) -> int:
    """Listen first, answer the login page at once (:class:`gonio.web.front.Front`), and
    build the application (imports, database, workers) in a background thread; the line
    "serving the records" says when every page answers."""
    import threading

    import uvicorn

    from gonio.errors import GonioError
    from gonio.web.front import Front

    check_backup_limits()
    if not 0 < args.port < 65536:
        raise GonioError("not a port number", key="--port")
    workers = check_workers(args.workers)
    front = Front().prepare()
    config = uvicorn.Config(front, host=args.host, port=args.port, log_level="warning",
                            lifespan="off")
    server = uvicorn.Server(config)
    sock = config.bind_socket()
    sock.listen(config.backlog)         # a browser's first request waits, never refused
    built: dict = {}
    builder = threading.Thread(target=_build, args=(args, workers, front, server, built),
                               name="gonio-start", daemon=True)
    builder.start()
    try:
        server.run(sockets=[sock])
    finally:
        builder.join()
        if "dispatcher" in built:
            built["dispatcher"].stop(wait=False)
        if "store" in built:
            built["store"].close()
    if "error" in built:
        raise built["error"]
    return 0


def _build(args, workers: int, front, server, built: dict) -> None:
    """The application behind ``front``: the records opened (and migrated), the first
    administrator, the workers, the pages; then the ready line once the server listens. A
    failure stops the server and is raised by :func:`run` (a database problem: exit 2)."""
    import time

    while not server.started and not server.should_exit:
        time.sleep(0.01)      # the login page answers first; then the imports take the CPU
    front.first_page.wait(front.FIRST_PAGE_GRACE_S)     # a browser already asking: its page
    try:
        from gonio.records.db import open_store
        from gonio.records.worker import Dispatcher
        from gonio.web.app import create_app, warm_up
        from gonio.web.front import warm

        store = built["store"] = open_store(args.database, args.data)
        password = first_admin(store)
        if password:
            sys.stderr.write(f"gonio: first start: user 'admin', password '{password}' "
                             "(change it: create your users and deactivate this one)\n")
        built["dispatcher"] = Dispatcher(store, workers=workers).start()
        warm_up()                 # the first dashboard without the SciPy import
        app = create_app(store, built["dispatcher"])
        warm(app)                 # its middleware, routes and templates, before a person
        front.serve(app)
    except BaseException as exc:  # noqa: BLE001 - handed to the main thread, raised there
        built["error"] = exc
        front.fail(str(exc).splitlines()[0] if str(exc) else type(exc).__name__)
        server.should_exit = True
        return
    sys.stderr.write(f"gonio: serving the records at http://{args.host}:{args.port}/ "
                     f"(database {store.engine.url.render_as_string(hide_password=True)})\n")
