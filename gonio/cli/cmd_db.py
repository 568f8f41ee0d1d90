"""``gonio db``: the records database from the command line (init, create-user, import,
backup, restore), and the ``--record`` option of ``gonio calibrate`` (added here: the
calibrate command runs as without it, and its finished output set is imported from the
staging folder before it is moved into ``--out``, so a set the records refuse is never
written)."""

from __future__ import annotations

import getpass
import os
import sys

from gonio.cli.cmd_serve import add_store_options, database_errors
from gonio.errors import GonioError


def register(sub) -> None:
    p = sub.add_parser("db", help="the records database: init, users, import, attach, backup, restore",
                       description="Manage the laboratory's records database.")
    dsub = p.add_subparsers(dest="db_command", metavar="ACTION")
    dsub.required = True
    q = dsub.add_parser("init", help="create or upgrade the database")
    add_store_options(q)
    for k in ("lab_name", "lab_address", "lab_accreditation", "lab_contact"):
        q.add_argument("--" + k.replace("_", "-"), dest=k, default=None)
    q.add_argument("--timezone", default=None,
                   help="the laboratory's time zone, an IANA name (e.g. Asia/Shanghai): the "
                        "records' calendar dates and 'today' are its dates (default: this "
                        "machine's IANA zone, UTC where it cannot be determined; written once "
                        "into the store, which every process then reads)")
    add_admin_option(q)
    q.set_defaults(func=run_init)
    add_user_commands(dsub)
    add_import(dsub)
    q = dsub.add_parser("attach", help="attach the registered standards used and the "
                                       "environment to a calibration not yet reviewed")
    add_store_options(q)
    q.add_argument("calibration", type=int, help="the calibration's number (its id)")
    q.add_argument("--user", default=None, metavar="NAME",
                   help="the records user attaching them (technician or reviewer; default "
                        "$GONIO_USER), with their password in $GONIO_PASSWORD or asked")
    add_attach_options(q)
    q.set_defaults(func=run_attach)
    q = dsub.add_parser("add-standard",
                        help="register a reference standard or piece of bench equipment "
                             "(technician); one past its due date only --out-of-service")
    add_store_options(q)
    q.add_argument("identifier", help="its identifier (unique)")
    q.add_argument("--name", required=True)
    q.add_argument("--due-on", required=True, metavar="YYYY-MM-DD")
    q.add_argument("--calibrated-on", default=None, metavar="YYYY-MM-DD")
    q.add_argument("--accuracy", default="")
    q.add_argument("--certificate", default="", help="its own calibration certificate")
    q.add_argument("--traceability", default="")
    q.add_argument("--out-of-service", default="", metavar="REASON",
                   help="one already past its due date: registered out of service (no "
                        "calibration can use it until its recalibration is recorded), the "
                        "reason in its record")
    q.add_argument("--user", default=None, metavar="NAME",
                   help="the records user registering it (technician; default $GONIO_USER)")
    q.set_defaults(func=run_add_standard)
    q = dsub.add_parser("register-table-calibration",
                        help="put a rotary table's calibration file into the laboratory's "
                             "register (technician)")
    add_store_options(q)
    q.add_argument("file", help="the table calibration file (CSV as gonio calibrate "
                                "--table-calibration)")
    q.add_argument("--table", required=True, metavar="IDENTIFIER",
                   help="the rotary table, registered as a standard (its identifier)")
    q.add_argument("--valid-from", required=True, metavar="YYYY-MM-DD",
                   help="the table's calibration date: valid from then")
    q.add_argument("--due-on", required=True, metavar="YYYY-MM-DD")
    q.add_argument("--certificate", default="", help="the table certificate's identifier")
    q.add_argument("--user", default=None, metavar="NAME",
                   help="the records user registering it (technician; default $GONIO_USER)")
    q.set_defaults(func=run_register_table_calibration)
    q = dsub.add_parser("table-calibrations",
                        help="list the register of the rotary tables' calibrations")
    add_store_options(q)
    q.add_argument("--date", default=None, metavar="YYYY-MM-DD",
                   help="say which is in force on this date (default today)")
    q.set_defaults(func=run_table_calibrations)
    q = dsub.add_parser("withdraw-table-calibration",
                        help="ask for a register entry to be withdrawn (technician or "
                             "reviewer, --reason), or approve (another reviewer) or decline "
                             "the withdrawal asked for")
    add_store_options(q)
    q.add_argument("entry", help="the register entry's number (gonio db table-calibrations)")
    how = q.add_mutually_exclusive_group(required=True)
    how.add_argument("--reason", default=None, help="ask for its withdrawal, saying why")
    how.add_argument("--approve", action="store_true",
                     help="approve the withdrawal asked for (not by its asker)")
    how.add_argument("--decline", action="store_true",
                     help="decline the withdrawal asked for")
    q.add_argument("--user", default=None, metavar="NAME",
                   help="the records user (default $GONIO_USER), with their password in "
                        "$GONIO_PASSWORD or asked")
    q.set_defaults(func=run_withdraw_table_calibration)
    for name, helptext in (("backup", "write every record and stored file to a ZIP archive"),
                           ("restore", "restore an archive into an empty database (or, "
                                       "with --replace, over the live records)")):
        q = dsub.add_parser(name, help=helptext)
        add_store_options(q)
        q.add_argument("archive")
        q.set_defaults(func=run_backup if name == "backup" else run_restore)
    add_replace_options(q)
    q = dsub.add_parser("verify", help="check every stored file, result and signed seal of "
                                       "the live records (or find a certificate file's record)")
    add_store_options(q)
    q.add_argument("--certificate", default=None, metavar="FILE",
                   help="a certificate file (PDF, HTML, DCC or results.json): find its "
                        "record by SHA-256 and check its result against the seal it was "
                        "issued from")
    q.set_defaults(func=run_verify)
    for action in dsub.choices.values():
        action.set_defaults(func=database_errors(action.get_default("func")))
    hook_calibrate(sub)


def add_user_commands(dsub) -> None:
    """``gonio db create-user`` and ``gonio db set-user``: their options."""
    q = dsub.add_parser("create-user", help="add a user (an administrator's login, --user; "
                                            "the new password from $GONIO_NEW_PASSWORD or "
                                            "asked)")
    add_store_options(q)
    q.add_argument("username")
    q.add_argument("--roles", default="technician",
                   help="space- or comma-separated: technician, reviewer, admin")
    q.add_argument("--full-name", default="")
    add_admin_option(q)
    q.set_defaults(func=run_create_user)
    q = dsub.add_parser("set-user", help="deactivate or reactivate a user, change the roles, "
                                         "reset the password (an administrator's login, "
                                         "--user; the new password from $GONIO_NEW_PASSWORD "
                                         "or asked)")
    add_store_options(q)
    q.add_argument("username")
    add_admin_option(q)
    g = q.add_mutually_exclusive_group()
    g.add_argument("--deactivate", dest="active", action="store_const", const=False)
    g.add_argument("--activate", dest="active", action="store_const", const=True)
    q.add_argument("--roles", default=None,
                   help="the new roles, space- or comma-separated")
    q.add_argument("--reset-password", action="store_true")
    q.set_defaults(func=run_set_user, active=None)


def add_import(dsub) -> None:
    """``gonio db import``: its options."""
    q = dsub.add_parser("import", help="import gonio output folders as computed calibrations")
    add_store_options(q)
    q.add_argument("folders", nargs="+")
    q.add_argument("--customer", default="(imported)")
    q.add_argument("--protocol", default=None,
                   help="the protocol file (or built-in name) the folders were computed with, "
                        "when it is not the one results.json names")
    q.add_argument("--lab", default=None, metavar="FILE",
                   help="the laboratory file the folders were computed with: its decision "
                        "rule and limits decide them at issue too")
    q.add_argument("--readings", default=None, metavar="FILE",
                   help="the readings file results.json was computed from, when it is not "
                        "in the folder (gonio calibrate's output holds none); one folder only")
    q.add_argument("--table-calibration", default=None, metavar="FILE",
                   help="the rotary table's calibration file the folder was computed with "
                        "(gonio calibrate --table-calibration FILE): kept with the "
                        "calibration, its SHA-256 checked against results.json's; one folder "
                        "only. A folder whose results.json records a table calibration is "
                        "refused without it (or the --lab file naming it)")
    q.add_argument("--option-file", action="append", default=[], metavar="OPTION=FILE",
                   help="a file the folder was computed with by a specification's option "
                        "(tilt=FILE for gonio calibrate --tilt FILE, thermal=FILE for "
                        "--thermal FILE), when it is not in the folder or beside the "
                        "readings: kept with the calibration, its SHA-256 checked against "
                        "the manifest's; repeat for several; one folder only")
    q.add_argument("--user", default=None, metavar="NAME",
                   help="the records user importing (recorded as the calibrations' creator, "
                        "who may then neither review nor approve them; default $GONIO_USER), "
                        "with their password in $GONIO_PASSWORD or asked on the terminal. "
                        "A calibration imported without one cannot be reviewed")
    add_attach_options(q)
    q.set_defaults(func=run_import)


def hook_calibrate(sub) -> None:
    """Add ``--record`` (with ``--database``/``--data``) to ``gonio calibrate``."""
    import argparse

    p = sub.choices.get("calibrate")
    if p is None:
        return
    try:
        p.add_argument("--record", action="store_true",
                       help="also put the calibration into the records database, computed "
                            "and awaiting review (see gonio serve)")
        p.add_argument("--record-user", default=None, metavar="NAME",
                       help="with --record: the records user recording it (its creator; "
                            "default $GONIO_USER), with their password in $GONIO_PASSWORD "
                            "or asked on the terminal")
        add_store_options(p)
        add_attach_options(p, prefix="with --record: ")
    except argparse.ArgumentError:           # calibrate has grown its own --record
        return
    inner = p.get_default("func")

    def run_recorded(args) -> int:
        if attach_of(args) and not args.record:
            raise GonioError("--standard, --temperature, --humidity and "
                             "--environment-from-readings go with --record", key="--record")
        if not args.record:
            return inner(args)
        from gonio.records import services
        from gonio.records.importer import (attach_recorded, check_attach_actor,
                                            import_output_folder)
        actor = None
        args.registered_gyro_type = registered_gyro_type(args)   # for K's bound
        if args.record_user or os.environ.get("GONIO_USER"):   # logged in before the run
            store = _store(args)
            try:
                actor = importing_user(store, args.record_user, "calibrate --record")
            finally:
                store.close()
        check_attach_actor(actor, **attach_of(args))               # refused before the work
        check_readings_unrecorded(args)
        recorded = []

        def record(stage) -> None:
            """The finished set, recorded before it is moved into --out: a set the records
            refuse is never written (the GonioError is the command's one line, exit 2)."""
            store = _store(args)
            try:
                recorded.append(import_output_folder(
                    store, stage, shown=args.out, readings=args.readings, spec_key=args.spec,
                    protocol=getattr(args, "protocol", None), lab=getattr(args, "lab", None),
                    table_calibration=getattr(args, "table_calibration", None), actor=actor,
                    registered_gyro_type=getattr(args, "registered_gyro_type", None),
                    option_files={d: getattr(args, d) for d in args.spec_inputs
                                  if d != "table_calibration" and getattr(args, d, None)}))
            finally:
                store.close()

        args.before_swap = record
        rc = inner(args)
        if rc == 0 and recorded:
            store = _store(args)
            try:
                cid = recorded[0]
                attach_recorded(store, cid, actor, **attach_of(args))
                line = attach_line(store, services.calibration(store, cid))
            finally:
                store.close()
            sys.stderr.write(f"gonio: recorded as {line}"
                             + (f" (gonio db attach {cid} --standard ID --temperature T "
                                "--humidity H)" if "needs" in line else "") + "\n")
        return rc

    p.set_defaults(func=run_recorded)


def _records_exist(args) -> bool:
    """Whether ``calibrate --record``'s records may hold anything yet: a database URL is
    given, or the SQLite records file exists (nothing is created before the run)."""
    from pathlib import Path

    from gonio.records.db import DEFAULT_DATA

    if args.database:
        return True
    folder = Path(os.path.expanduser(str(args.data or os.environ.get("GONIO_DATA")
                                          or DEFAULT_DATA)))
    return (folder / "records.sqlite3").is_file()


def check_readings_unrecorded(args) -> None:
    """``calibrate --record``: readings another calibration that stands already holds are
    refused before the work (:func:`gonio.records.services.check_readings_unused`, one line
    naming that calibration; the import checks it again when it records). Nothing when the
    records do not exist yet or the readings are no file (the calibration says why)."""
    from pathlib import Path

    from gonio.atomic import sha256_file
    from gonio.records import services

    if not _records_exist(args) or not Path(args.readings).is_file():
        return
    sha = sha256_file(args.readings)
    store = _store(args)
    try:
        with store.session() as s:
            try:
                services.check_readings_unused(s, sha, path=args.readings)
            except GonioError as exc:
                raise GonioError(exc.message, file=args.readings, key=exc.key) from None
    finally:
        store.close()


def registered_gyro_type(args) -> str | None:
    """``calibrate --record``: the optical-gyro type of the instrument registered in the
    records under the identity the readings state (manufacturer, model, serial), which the
    calibration takes for K's temperature-coefficient bound when neither the readings nor the
    laboratory file state a type; None when none is registered or it states none, when the
    readings cannot be read (the calibration says why), or when the SQLite records do not
    exist yet (nothing is created before the run)."""
    from pathlib import Path

    from gonio.formats.provenance import readings_metadata
    from gonio.records.importer import registered_instrument

    if not _records_exist(args):
        return None
    try:
        if not Path(args.readings).is_file():
            return None
        meta = readings_metadata(args.readings)
    except (GonioError, OSError):
        return None
    store = _store(args)
    try:
        with store.session() as s:
            inst = registered_instrument(s, meta)
            return (inst.gyro_type or None) if inst is not None else None
    finally:
        store.close()


def add_attach_options(q, prefix: str = "") -> None:
    """The options naming what a calibration is attached (``db import``, ``db attach``,
    ``calibrate --record``; ``prefix`` starts each help text)."""
    q.add_argument("--standard", action="append", default=[], metavar="IDENTIFIER",
                   help=prefix + "a registered standard used (its identifier), valid on the "
                        "calibration date; repeat for several")
    q.add_argument("--temperature", default=None, metavar="DEG_C",
                   help=prefix + "the room temperature of the calibration (°C; with "
                                 "--humidity, instead of the laboratory file's)")
    q.add_argument("--humidity", default=None, metavar="PCT",
                   help=prefix + "the relative humidity of the calibration (%%)")
    q.add_argument("--environment-from-readings", action="store_true",
                   help=prefix + "take the temperature and humidity from the readings' "
                                 "metadata (stated so on the certificate)")


def attach_of(args) -> dict:
    """The attach options given, as :func:`gonio.records.services.attach_conditions`'s
    keyword arguments ({} when none)."""
    out = {}
    if args.standard:
        out["standard_identifiers"] = list(args.standard)
    if args.temperature is not None or args.humidity is not None:
        out.update(temperature_c=args.temperature, humidity_pct=args.humidity)
    if args.environment_from_readings:
        out["environment_from_readings"] = True
    return out


def _registering_user(store, args):
    """The records user registering an entry (``--user`` or $GONIO_USER, password checked by
    :func:`importing_user`); none given is refused in one line."""
    actor = importing_user(store, args.user)
    if actor is None:
        raise GonioError("give the records user registering it (--user or $GONIO_USER)",
                         key="--user")
    return actor


def run_add_standard(args) -> int:
    from gonio.records import services

    store = _store(args)
    try:
        actor = _registering_user(store, args)
        st = services.add_standard(
            store, actor, name=args.name, identifier=args.identifier, due_on=args.due_on,
            calibrated_on=args.calibrated_on, accuracy=args.accuracy,
            certificate=args.certificate, traceability=args.traceability,
            out_of_service=args.out_of_service)
        print(f"standard {st.id}: {st.identifier} {st.name}, due on {st.due_on}"
              + (f"; registered out of service (past its due date): {st.out_of_service}"
                 if st.out_of_service else ""))
    finally:
        store.close()
    return 0


def run_register_table_calibration(args) -> int:
    from gonio.records import services

    store = _store(args)
    try:
        actor = _registering_user(store, args)
        tc = services.register_table_calibration_file(
            store, actor, args.file, table=args.table, valid_from=args.valid_from,
            due_on=args.due_on, certificate=args.certificate)
        print(f"table calibration {tc.id}: {args.table} {tc.certificate} {tc.name} "
              f"(SHA-256 {tc.sha256}), valid from {tc.valid_from}, due on {tc.due_on}")
    finally:
        store.close()
    return 0


def run_table_calibrations(args) -> int:
    from gonio.records import services

    store = _store(args)
    try:
        day = services.date_value(args.date, "--date")
        for r in services.table_calibrations(store, day):
            e, w = r["entry"], r["withdrawal"]
            note = ""
            if w is not None:
                note = (f"\twithdrawn by {_who(w.withdrawn_by)} (asked by {_who(w.asked_by)}): "
                        f"{' '.join(w.reason.split())}; affected: "
                        + (", ".join(f"calibration {i}" for i in r["affected"]) or "none"))
            elif r["asked"] is not None:
                note = f"\twithdrawal asked for by {r['asked']['asked_by']}"
            print(f"{e.id}\t{e.standard.identifier}\t{e.certificate}\t{e.name}\t{e.sha256}\t"
                  f"{e.valid_from}\t{e.due_on}\t{r['state'] or 'in force'}\t"
                  f"used by {r['used']}\t"
                  f"{e.registered_by.username if e.registered_by else ''}{note}")
    finally:
        store.close()
    return 0


def _who(user) -> str:
    return user.username if user is not None else "(unknown)"


def run_withdraw_table_calibration(args) -> int:
    from gonio.records import services

    store = _store(args)
    try:
        name = args.user or os.environ.get("GONIO_USER") or ""
        if not name:
            raise GonioError("give the records user (--user or $GONIO_USER)", key="--user")
        actor = logged_in(store, name, "db withdraw-table-calibration")
        if not args.entry.isdigit():
            raise GonioError("the register entry's number (a whole number)", key="entry")
        if args.approve:
            w = services.approve_withdrawal(store, actor, int(args.entry))
            print(f"table calibration {args.entry} withdrawn at "
                  f"{w.withdrawn_at:%Y-%m-%d %H:%M:%S}Z")
        elif args.decline:
            services.decline_withdrawal(store, actor, int(args.entry))
            print(f"table calibration {args.entry}: withdrawal declined")
        else:
            services.ask_withdrawal(store, actor, int(args.entry), args.reason)
            print(f"table calibration {args.entry}: withdrawal asked for; another person "
                  "approves it")
    finally:
        store.close()
    return 0


def run_attach(args) -> int:
    from gonio.records import services

    store = _store(args)
    try:
        name = args.user or os.environ.get("GONIO_USER") or ""
        if not name:
            raise GonioError("give the active records user attaching them (--user or "
                             "$GONIO_USER)", key="--user")
        actor = logged_in(store, name, "db attach")
        services.attach_by_identifiers(store, actor, args.calibration, **attach_of(args))
        from gonio.records.worker import run_now
        run_now(store, args.calibration)        # its draft rendered with them, at once
        print(attach_line(store, services.calibration(store, args.calibration)))
    finally:
        store.close()
    return 0


def attach_line(store, cal) -> str:
    """One line: what a calibration names now, and what it still lacks for its review."""
    from gonio.records import services

    with store.session() as s:
        missing = services.missing_for_review(s, cal)
        names = services.standard_names(s, cal.id)
    temp, hum = services.environment_shown(cal)     # as entered, as the certificate
    env = ("not entered" if temp is None else f"{temp.text} °C, {hum.text} %"
           + {"readings": " (from the readings)", "lab file": " (from the laboratory file)"}
           .get(cal.environment_from, ""))
    return (f"calibration {cal.id}: standards {', '.join(names) or 'none'}; environment "
            f"{env}" + (f"; before its review it needs {' and '.join(missing)}"
                        if missing else ""))


def importing_user(store, name: str | None, command: str = "db import"):
    """The records user named by ``--user`` (else ``$GONIO_USER``), logged in with their
    password (:func:`logged_in`), active and a technician; None when neither names one."""
    from gonio.records import services

    name = name or os.environ.get("GONIO_USER") or None
    if name is None:
        return None
    return services.require(logged_in(store, name, command), "technician")


def os_user() -> str:
    """The operating-system account running this command ("(unknown)" where none is
    found)."""
    try:
        return getpass.getuser()
    except (KeyError, OSError):           # no name for the uid (a container's bare uid)
        return f"(uid {os.getuid()})" if hasattr(os, "getuid") else "(unknown)"


def logged_in(store, name: str, command: str):
    """The records user ``name`` acting on the command line, proven as ``gonio serve``'s login
    proves it: their password (from ``$GONIO_PASSWORD``, else asked on the terminal; never an
    option, which other users could read in the process list) checked against the stored
    Argon2id hash (:func:`gonio.records.auth.authenticate`: the same message for an unknown
    name and a wrong password, failures counted and throttled as the browser's). The login is
    an audit event naming the operating-system account that ran ``command``. A GonioError
    (one line) otherwise."""
    from gonio.records import auth, services

    who = os_user()
    password = os.environ.get("GONIO_PASSWORD")
    if password is None:
        if not sys.stdin.isatty():
            raise GonioError(f"give the password of records user {name[:64]!r} in "
                             "$GONIO_PASSWORD (no terminal to ask on)", key="--user")
        password = getpass.getpass(f"password of records user {name}: ")
    try:
        u = auth.authenticate(store, name, password, address=f"command line ({who})"[:64])
    except GonioError as exc:
        raise GonioError(f"--user {name[:64]!r}: {exc.message}", key="--user") from None
    with store.writing() as s:
        services.audit(s, u, "command-line login", "user", u.id, None,
                       {"command": command, "os_user": who})
        s.commit()
    return u


def _store(args):
    from gonio.records.db import open_store
    return open_store(args.database, args.data)


def run_init(args) -> int:
    from gonio.records import services

    store = _store(args)
    try:
        values = {k: getattr(args, k) for k in ("lab_name", "lab_address", "lab_accreditation",
                                                "lab_contact", "timezone")
                  if getattr(args, k) is not None}
        if values:    # the laboratory's settings: an admin's, as on the settings page
            services.set_settings(store, managing_admin(store, args.user, "db init"),
                                  **values)
        print(f"records ready: {store.engine.url.render_as_string(hide_password=True)}")
    finally:
        store.close()
    return 0


def add_admin_option(q) -> None:
    """``--user ADMIN`` of the commands that manage users or the laboratory's settings
    (:func:`managing_admin`)."""
    q.add_argument("--user", default=None, metavar="ADMIN",
                   help="the active administrator doing it (default $GONIO_USER), with "
                        "their password in $GONIO_PASSWORD or asked; needed once the records "
                        "have an active administrator")


def managing_admin(store, name: str | None, command: str):
    """The administrator managing users or settings on the command line: the records user
    ``name`` (else ``$GONIO_USER``) logged in with their password (:func:`logged_in`) and
    holding the admin role.

    None while the records hold no user at all (a new database being set up: no one to log
    in as, a name given is not asked for; ``actor=None`` in the audit trail): its first user
    is then its administrator (:func:`check_first_user`). Records that hold users but no
    active administrator (made before this rule, or restored so) are refused too: an
    account on the machine cannot make itself their administrator; whoever administers the
    database itself makes one (``gonio.records.services.update_user`` with ``actor=None``).
    Once there are users, a GonioError (one line) asks for the login, so that an account on
    the machine cannot create, promote or take over records users, nor change the
    laboratory's name, accreditation or time zone."""
    from gonio.records import queries, services

    if not queries.users(store):
        return None
    name = name or os.environ.get("GONIO_USER") or None
    if name is None:
        if not queries.active_admins(store):
            raise GonioError(f"{command}: the records have users but no active "
                             "administrator; none can be made from the command line "
                             "without one (whoever administers the database makes one: "
                             "docs/records.md, 'Users')", key="--user")
        raise GonioError(f"{command}: the records have an active administrator, who does "
                         "this: give --user ADMIN (or $GONIO_USER), with their password in "
                         "$GONIO_PASSWORD or asked", key="--user")
    return services.require(logged_in(store, name, command), "admin")


def check_first_user(roles: str) -> None:
    """The first user of a new database, created without a login, is its administrator: a
    GonioError (one line) where ``roles`` lacks admin."""
    from gonio.records.auth import check_roles

    if "admin" not in check_roles(roles.replace(",", " ")).split():
        raise GonioError("the records hold no user yet: the first is their administrator "
                         "(give --roles admin, with technician or reviewer as well if the "
                         "same person does those); the administrator then creates the "
                         "others with --user ADMIN", key="--roles")


def run_create_user(args) -> int:
    from gonio.records import services

    store = _store(args)
    try:
        admin = managing_admin(store, args.user, "db create-user")
        if admin is None:
            check_first_user(args.roles)
        password = new_password(args.username, admin is None)
        u = services.create_user(store, admin, args.username, password,
                                 args.roles.replace(",", " "), args.full_name)
        print(f"user {u.username} ({u.roles})")
    finally:
        store.close()
    return 0


def new_password(username: str, setting_up: bool) -> str:
    """The new password of ``username``: ``$GONIO_NEW_PASSWORD``, else (``setting_up``: no
    administrator logged in with ``$GONIO_PASSWORD``) ``$GONIO_PASSWORD``, else asked on the
    terminal; a GonioError (one line) where none is given and no terminal can ask."""
    password = os.environ.get("GONIO_NEW_PASSWORD")
    if password is None and setting_up:
        password = os.environ.get("GONIO_PASSWORD")
    if password is None:
        if not sys.stdin.isatty():
            raise GonioError("give the new password in $GONIO_NEW_PASSWORD (no terminal to "
                             "ask on)", key="password")
        password = getpass.getpass(f"new password for {username}: ")
    return password


def run_set_user(args) -> int:
    from gonio.records import services

    store = _store(args)
    try:
        admin = managing_admin(store, args.user, "db set-user")
        password = new_password(args.username, admin is None) if args.reset_password else None
        u = services.update_user(store, admin, args.username, active=args.active,
                                 roles=None if args.roles is None
                                 else args.roles.replace(",", " "), password=password)
        print(f"user {u.username} ({u.roles}; {'active' if u.active else 'deactivated'})"
              + ("; password reset" if password else ""))
    finally:
        store.close()
    return 0


def run_import(args) -> int:
    from gonio.records import services
    from gonio.records.importer import record_output_folder

    store = _store(args)
    try:
        actor = importing_user(store, args.user)
        if args.readings and len(args.folders) > 1:
            raise GonioError("give --readings with one folder only", key="--readings")
        if args.table_calibration and len(args.folders) > 1:
            raise GonioError("give --table-calibration with one folder only",
                             key="--table-calibration")
        if args.option_file and len(args.folders) > 1:
            raise GonioError("give --option-file with one folder only", key="--option-file")
        for folder in args.folders:
            cid = record_output_folder(store, folder, customer=args.customer,
                                       protocol=args.protocol, lab=args.lab, actor=actor,
                                       readings=args.readings,
                                       table_calibration=args.table_calibration,
                                       option_files=option_files_of(args.option_file),
                                       **attach_of(args))
            print(f"{folder}: {attach_line(store, services.calibration(store, cid))}")
    finally:
        store.close()
    return 0


def option_files_of(given: list[str]) -> dict:
    """``--option-file OPTION=FILE`` values as {option: FILE} (``tilt-estimate`` and
    ``tilt_estimate`` alike); a value without ``=``, or an option given twice, is refused in
    one line."""
    out: dict = {}
    for v in given:
        option, sep, path = str(v).partition("=")
        option = option.strip().lstrip("-").replace("-", "_")
        if not sep or not option or not path:
            raise GonioError(f"expected OPTION=FILE (e.g. tilt=tilt.json), got {v[:80]!r}",
                             key="--option-file")
        if option in out:
            raise GonioError(f"{option} given twice", key="--option-file")
        out[option] = path
    return out


def run_backup(args) -> int:
    from gonio.records.backup import backup

    store = _store(args)
    try:
        counts = backup(store, args.archive)
    finally:
        store.close()
    print(f"{args.archive}: " + ", ".join(f"{k} {v}" for k, v in counts.items() if v))
    return 0


def run_verify(args) -> int:
    from gonio.records import services
    from gonio.records.backup import verify

    store = _store(args)
    try:
        if args.certificate:
            try:
                with open(args.certificate, "rb") as fh:
                    data = fh.read()
            except OSError as exc:
                raise GonioError(f"cannot read: {exc.strerror}", file=args.certificate) from None
            found = services.verify_certificate(store, data)
            print(f"{args.certificate}: {found['file']} of certificate {found['number']}"
                  + (f" (replaces {found['replaces']})" if found["replaces"] else "")
                  + f", issued {found['issued_at']:%Y-%m-%d %H:%M} UTC; SHA-256 "
                  f"{found['sha256']}; sealed result {found['seal_now']} as issued")
            return 0
        counts, problems = verify(store)
    finally:
        store.close()
    for p in problems:
        print(p)
    if problems:
        raise GonioError(f"{len(problems)} problem(s) in the records (listed above)",
                         key="verify")
    print("records verified: " + ", ".join(f"{k} {v}" for k, v in counts.items()))
    return 0


def add_replace_options(q) -> None:
    """``gonio db restore``'s ``--replace`` with the administrator and the confirmation."""
    q.add_argument("--replace", action="store_true",
                   help="replace the live records with the archive's (what the browser's "
                        "restore does; stop gonio serve first); needs --user ADMIN and "
                        "--sha256 DIGEST")
    q.add_argument("--user", default=None, metavar="NAME",
                   help="with --replace: the active administrator restoring (default "
                        "$GONIO_USER), with their password in $GONIO_PASSWORD or asked")
    q.add_argument("--sha256", default=None, metavar="DIGEST",
                   help="with --replace: the archive's SHA-256, confirming the archive that "
                        "replaces the records (without it the refusal names the digest)")


def _replacing_admin(store, args):
    """The active administrator ``--user`` (else ``$GONIO_USER``) names, for --replace."""
    from gonio.records import services

    name = args.user or os.environ.get("GONIO_USER") or ""
    if not name:
        raise GonioError("--replace needs the active administrator restoring (--user NAME or "
                         "$GONIO_USER)", key="--user")
    return services.require(logged_in(store, name, "db restore --replace"), "admin")


def run_restore(args) -> int:
    from gonio.records.backup import archive_sha256, restore

    if not args.replace and (args.user or args.sha256):
        raise GonioError("--user and --sha256 go with --replace", key="--replace")
    store = _store(args)
    try:
        if not args.replace:
            counts = restore(store, args.archive)
        else:
            actor = _replacing_admin(store, args)
            want = (args.sha256 or "").strip().lower()
            if not want:
                raise GonioError("--replace replaces the live records: confirm this archive "
                                 f"with --sha256 {archive_sha256(args.archive)} (its SHA-256); "
                                 "nothing restored", key="--sha256")
            counts = restore(store, args.archive, replace=True, actor=actor,
                             expect_sha256=want)
    finally:
        store.close()
    print("restored: " + ", ".join(f"{k} {v}" for k, v in counts.items() if v))
    return 0
