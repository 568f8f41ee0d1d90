"""The laboratory's workflow as Python functions (docs/records.md#workflow): what the web
interface and the ``gonio db`` / ``gonio calibrate --record`` commands call.

Every function takes the open :class:`~gonio.records.db.Store` and, where a person acts,
the acting :class:`~gonio.records.models.User`; roles are checked here, on the server, so
no interface can skip them. Every change writes an audit event (who, what, when, the
record's state before and after) in the same transaction as the change.

ISO/IEC 17025 7.8 as states of a calibration::

    queued → running → computed → reviewed → approved → issuing → issued
                 ↘ failed (run again)      ↘ rejected

* a technician creates a calibration (instrument, readings, standards, environment); the
  worker runs it; the draft certificate is marked DRAFT;
* a reviewer who did not create it reviews it (accept or reject, with a comment);
* a reviewer who did not create it approves it, and issuing starts: the certificate number
  is reserved (GC-YYYY-NNNN), the stored result is checked against the seal the reviewer
  and the approver signed and rendered with the final details (number, signatories, date
  of issue, the seal); nothing is computed again; then, in one transaction, the frozen
  certificate row is written;
* an issued certificate is amended by a new certificate (new number) that names the one it
  replaces and why; nothing issued is ever updated or deleted (database triggers refuse it).
"""

from __future__ import annotations

import datetime as _dt
import functools
import json
import os
import re
import socket
from pathlib import Path
from typing import Iterable

from sqlalchemy import func, select, update
from sqlalchemy.orm import Session

from gonio.errors import GonioError
from gonio.limits import limit
from gonio.records import blobs
from gonio.records.auth import check_roles, hash_password
from gonio.records.models import (AuditEvent, Blob, Calibration, CalibrationFile,
                                  CalibrationStandard, Certificate, CertificateCounter, Customer,
                                  Instrument, ReadingsContent, ResultItem, Setting, Standard,
                                  TableCalibration,
                                  TableCalibrationWithdrawal, User, is_past_due,
                                  laboratory_zone, records_today, utcnow)
from gonio.records.results import NOT_STATED, result_rows

#: The certificate numbering scheme: prefix, year, four-digit sequence per year.
NUMBER_PREFIX = "GC"
#: Longest one-line text field (names, serials) and multi-line field (addresses, comments).
MAX_LINE, MAX_TEXT = 200, 4000
#: Largest readings or protocol file accepted through the records (bytes).
MAX_UPLOAD = limit("GONIO_MAX_UPLOAD_BYTES")

_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f\u2028\u2029\ufeff]")
_CONTROL_LINE = re.compile(r"[\x00-\x1f\x7f\u2028\u2029\ufeff]")

#: Laboratory settings and their defaults.
SETTINGS = {"lab_name": "Calibration laboratory", "lab_address": "(address not set)",
            "lab_accreditation": "", "lab_contact": "", "lab_place": "",
            "decision_rule": "non-binary", "guard_band_factor": "1.0", "min_people": "3",
            "table_calibration_max_months": "24", "timezone": "UTC"}

#: The longest a rotary table's calibration may be registered for (months from its valid
#: from to its due date; the setting ``table_calibration_max_months`` is the laboratory's
#: own, 1 … this).
MAX_TABLE_INTERVAL_MONTHS = 120

#: What ``min_people`` may be: 3 (creator, reviewer and approver three different people) or
#: 2 for a small laboratory (the reviewer may approve; the creator never reviews or approves).
MIN_PEOPLE = ("2", "3")


# --------------------------------------------------------------------------- checks


def text(value, name: str, *, max_len: int = MAX_LINE, multiline: bool = False,
         required: bool = False) -> str:
    """A text field checked: a string, no control characters (newlines and tabs only in a
    multi-line field), at most ``max_len`` characters, stripped; GonioError naming the field.

    >>> text("  RLG-0001 ", "serial")
    'RLG-0001'
    >>> text("a\\x00b", "serial")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key serial: control characters are not allowed
    """
    if value is None:
        value = ""
    if not isinstance(value, str):
        raise GonioError("must be text", key=name)
    if len(value) > max_len:
        raise GonioError(f"longer than {max_len} characters ({len(value)})", key=name)
    if multiline:                      # line ends as laboratories type them: CR LF, CR
        value = value.replace("\r\n", "\n").replace("\r", "\n")
    if (_CONTROL if multiline else _CONTROL_LINE).search(value):
        raise GonioError("control characters are not allowed", key=name)
    value = value.strip()
    if required and not value:
        raise GonioError("must not be empty", key=name)
    return value


#: The Unicode categories no shown file name may hold: controls (C0 and C1), format
#: characters (bidirectional overrides and isolates U+202A–U+202E, U+2066–U+2069, the marks
#: U+200E/U+200F, zero-width characters: they make a displayed name look like another, e.g.
#: "calib\u202evsc.exe" shown as "calibexe.csv"), line and paragraph separators, surrogates.
UNSHOWABLE = ("Cc", "Cf", "Zl", "Zp", "Cs")


def file_name(value, name: str) -> str:
    """A file name to be shown (:func:`text`, at most 255 characters) holding no character of
    :data:`UNSHOWABLE`; else a GonioError naming the field and the first such code point.

    >>> file_name(" RT-07 cal.csv", "name")
    'RT-07 cal.csv'
    >>> hex(ord(unshowable("calib\u202evsc.exe")))
    '0x202e'
    """
    bad = unshowable(str(value or ""))
    if bad:
        raise GonioError(f"the name holds U+{ord(bad):04X} (an invisible or direction-changing "
                         "character that can make it look like another name): rename the "
                         "file", key=name)
    return text(value, name, max_len=255)


def unshowable(name: str) -> str:
    """The first character of ``name`` in a category of :data:`UNSHOWABLE`, or ''."""
    import unicodedata

    return next((c for c in name if unicodedata.category(c) in UNSHOWABLE), "")


def date_value(value, name: str, *, required: bool = False) -> _dt.date | None:
    """An ISO date (``YYYY-MM-DD``) or a date; None when empty and not required."""
    if isinstance(value, _dt.date):
        return value
    value = text(value, name, max_len=10)
    if not value:
        if required:
            raise GonioError("a date YYYY-MM-DD is required", key=name)
        return None
    try:
        return _dt.date.fromisoformat(value)
    except ValueError:
        raise GonioError("not a date YYYY-MM-DD", key=name) from None


def number_value(value, name: str, lo: float, hi: float) -> float | None:
    """A number within [lo, hi], or None when empty."""
    if value is None or (isinstance(value, str) and not value.strip()):
        return None
    try:
        x = float(text(value, name, max_len=40) if isinstance(value, str) else value)
    except (TypeError, ValueError):
        raise GonioError("not a number", key=name) from None
    if not lo <= x <= hi:
        raise GonioError(f"must be within {lo:g} … {hi:g}", key=name)
    return x


def condition_digits(value) -> str:
    """The text an environment condition (temperature, humidity) is recorded and printed
    with: its digits as entered, the resolution they state kept ("20" stays "20", "20.0"
    stays "20.0"; a laboratory file's number as written there, its
    :class:`~gonio.formats.lab.WrittenNumber` text), written as a plain decimal that TOML
    reads as the same number (leading zeros and underscores dropped, "20." is "20", ".5" is
    "0.5"). A text in exponent form or with a sign "+" is stated plainly, as
    :func:`gonio.report.header.condition_text` states it; a number given as a float (no
    text: the Python API) to 6 significant digits where that is the number, else in full.

    >>> [condition_digits(v) for v in ("20", "20.0", " 020.50 ", "20.", ".5", "2e1", "+21.5")]
    ['20', '20.0', '20.50', '20', '0.5', '20', '21.5']
    >>> condition_digits(20), condition_digits(20.0), condition_digits(20.1234567)
    ('20', '20', '20.1234567')
    """
    import decimal

    text = getattr(value, "text", None)
    if isinstance(text, str):
        value = text
    if isinstance(value, str):
        t = value.strip().replace("_", "")
        if re.fullmatch(r"-?(\d+\.?\d*|\.\d+)", t):
            return format(decimal.Decimal(t), "f")
        value = float(t)
    if isinstance(value, int) and not isinstance(value, bool):
        return str(value)
    x = float(value)
    short = f"{x:g}"
    return short if float(short) == x else repr(x)


def condition_value(value, name: str, lo: float, hi: float):
    """:func:`number_value` of an environment condition, as a
    :class:`~gonio.formats.lab.WrittenNumber` whose text is :func:`condition_digits`
    (None when empty)."""
    from gonio.formats.lab import WrittenNumber

    x = number_value(value, name, lo, hi)
    if x is None:
        return None
    digits = condition_digits(value)
    if len(digits) > CONDITION_TEXT_CHARS:       # the column's width (".5" gains a "0")
        raise GonioError(f"more than {CONDITION_TEXT_CHARS} characters as a plain decimal",
                         key=name)
    return WrittenNumber(x, digits)


#: the width of ``calibrations.temperature_text`` and ``humidity_text`` (migration 0012)
CONDITION_TEXT_CHARS = 40


def environment_columns(temperature, humidity) -> dict:
    """A calibration's environment columns for ``temperature`` and ``humidity`` (numbers,
    texts or :class:`~gonio.formats.lab.WrittenNumber`; None: not given): each number with
    the text it was entered with (:func:`condition_digits`)."""
    def num(v):
        return None if v is None else float(v)

    def txt(v):
        return None if v is None else condition_digits(v)
    return {"temperature_c": num(temperature), "humidity_pct": num(humidity),
            "temperature_text": txt(temperature), "humidity_text": txt(humidity)}


def environment_shown(cal) -> tuple:
    """(temperature, humidity) of calibration ``cal`` as recorded, each a
    :class:`~gonio.formats.lab.WrittenNumber` with the text it was entered with (a row
    without the text: the number to 6 significant digits, as it was printed), or None."""
    from gonio.formats.lab import WrittenNumber

    def one(x, t):
        return None if x is None else WrittenNumber(x, t or condition_digits(float(x)))
    return (one(cal.temperature_c, cal.temperature_text),
            one(cal.humidity_pct, cal.humidity_text))


def require(actor: User | None, role: str) -> User:
    """``actor`` holds ``role`` (and is active), else a GonioError."""
    if actor is None or not actor.active or not actor.has(role):
        raise GonioError(f"this needs the {role} role", key="role")
    return actor


# --------------------------------------------------------------------------- audit


def state(obj) -> dict:
    """A record's column values as JSON-able data (the audit trail's before/after)."""
    if obj is None:
        return {}
    out = {}
    for col in obj.__table__.columns:
        v = getattr(obj, col.key)
        if col.key == "password_hash":
            v = "(hidden)"
        elif isinstance(v, (_dt.date, _dt.datetime)):
            v = v.isoformat()
        out[col.key] = v
    return out


def audit(s: Session, actor: User | None, action: str, entity: str, entity_id,
          before: dict | None = None, after: dict | None = None) -> None:
    """Append one audit event to the session's transaction."""
    s.add(AuditEvent(user_id=actor.id if actor else None,
                     username=actor.username if actor else "(system)", action=action,
                     entity=entity, entity_id=str(entity_id),
                     before_json=json.dumps(before or {}, sort_keys=True, default=str),
                     after_json=json.dumps(after or {}, sort_keys=True, default=str)))


# --------------------------------------------------------------------------- settings, users


def settings(store) -> dict:
    """The laboratory settings (defaults for those never set)."""
    with store.session() as s:
        rows = {r.key: r.value for r in s.scalars(select(Setting))}
    return {k: rows.get(k, v) for k, v in SETTINGS.items()}


def set_settings(store, actor: User | None, **values) -> dict:
    """Change laboratory settings (admin; ``actor=None`` from the command line)."""
    if actor is not None:
        require(actor, "admin")
    values = {k: check_setting(k, v) for k, v in values.items()}
    if "decision_rule" in values or "guard_band_factor" in values:
        check_guard_setting(settings(store) | values, values)
    with store.writing() as s:
        if "min_people" in values and values["min_people"] != str(min_people(s)):
            waiting = s.scalars(select(Calibration.pending_number).where(
                Calibration.pending_number != "").order_by(Calibration.id)).all()
            if waiting:   # approved under the rule in force; their certificates state it
                raise GonioError(f"{len(waiting)} approved certificate(s) wait for their issue "
                                 f"({waiting[0]}…), approved under min_people "
                                 f"{min_people(s)}: change it once they are issued",
                                 key="min_people")
        for k, v in values.items():
            row = s.get(Setting, k)
            before = state(row)
            if row is None:
                row = Setting(key=k, value=v)
                s.add(row)
            row.value = v
            audit(s, actor, "setting", "settings", k, before, {"key": k, "value": v})
        s.commit()
    return settings(store)


def check_guard_setting(merged: dict, changed: dict) -> None:
    """The laboratory's decision rule and guard-band factor together (``merged``: the
    settings as they would be stored) by the rule a laboratory file's ``[decision_rule]`` is
    checked with (:func:`gonio.formats.lab.check_guard_factor`: a rule with a guard band,
    guarded or non-binary, needs r ≥ 1): refused in one line naming the field changed
    (``guard_band_factor`` where ``changed`` sets it, else ``decision_rule``), before
    anything is stored — not when a calibration is decided with it."""
    from gonio.formats.lab import check_guard_factor

    try:
        check_guard_factor(merged["decision_rule"], float(merged["guard_band_factor"]))
    except GonioError as exc:
        raise GonioError(exc.message, key="guard_band_factor" if "guard_band_factor" in changed
                         else "decision_rule") from None


def check_setting(key: str, value) -> str:
    """A laboratory setting checked by the laboratory file's own schema (``LAB_SCHEMA``:
    the decision rule's choices, a guard-band factor ≥ 0, printable text within the
    certificate's limits), ``min_people`` 2 or 3; the value as stored (text)."""
    from gonio.formats.toml import MAX_TEXT_FIELD, check_text_fields, validate_table
    from gonio.formats.lab import LAB_SCHEMA

    if key not in SETTINGS:
        raise GonioError(f"unknown setting (known: {', '.join(SETTINGS)})", key=key)
    multi = key == "lab_address"
    value = text(value, key, max_len=MAX_TEXT_FIELD if multi else MAX_LINE, multiline=multi)
    check_text_fields({key: value}, None)
    if key == "min_people" and value not in MIN_PEOPLE:
        raise GonioError("2 or 3 (distinct people: creator, reviewer, approver)", key=key)
    if key == "table_calibration_max_months" and not (
            re.fullmatch(r"[0-9]{1,3}", value)
            and 1 <= int(value) <= MAX_TABLE_INTERVAL_MONTHS):
        raise GonioError(f"a whole number of months, 1 … {MAX_TABLE_INTERVAL_MONTHS}", key=key)
    if key == "timezone":
        if not value:
            raise GonioError("must not be empty (an IANA zone such as Asia/Shanghai, or UTC): "
                             "every process on the records reads this one zone", key=key)
        laboratory_zone(value)      # an IANA name (zoneinfo)
    if key == "guard_band_factor":
        number_value(value, key, 0, 1e6)
        if not value:
            raise GonioError("must not be empty", key=key)
    if key == "decision_rule":
        validate_table({"rule": value}, LAB_SCHEMA["decision_rule"].schema, "decision_rule")
    if key == "guard_band_factor":
        validate_table({"rule": SETTINGS["decision_rule"], "guard_band_factor": float(value)},
                       LAB_SCHEMA["decision_rule"].schema, "decision_rule")
    return value


def create_user(store, actor: User | None, username: str, password: str, roles,
                full_name: str = "") -> User:
    """A new user (admin; ``actor=None`` from ``gonio db create-user``)."""
    if actor is not None:
        require(actor, "admin")
    username = text(username, "username", max_len=64, required=True)
    if not re.fullmatch(r"[A-Za-z0-9._-]+", username):
        raise GonioError("letters, digits, '.', '_' and '-' only", key="username")
    user = User(username=username, full_name=text(full_name, "full_name"),
                password_hash=hash_password(password), roles=check_roles(roles))
    with store.session() as s:
        _distinct_name(s, user)
    return _create(store, actor, user, "user", User.username == username,
                   "a user with this name exists", "username")


def _printed_name(name: str) -> str:
    """A person's name as compared for telling people apart (the user names and full names
    of :func:`_distinct_name`, the readings' operator against :func:`names_held`): the one
    identity normaliser, :func:`gonio.formats.metadata.identity_text` (case, Unicode
    compatibility forms and spacing folded), on both sides.

    >>> _printed_name("  Alice   SMITH ") == _printed_name("alice smith")
    True
    >>> _printed_name("ＡＬＩＣＥ ＳＭＩＴＨ") == _printed_name("Alice Smith")
    True
    """
    from gonio.formats.metadata import identity_text

    return identity_text(name)


def _distinct_name(s: Session, u: User) -> None:
    """The name a certificate prints for ``u`` (:func:`_name`: the full name, else the user
    name) is no other user's, now or before (:func:`names_held`: a name another user gave
    up still stands on the certificates they signed; active or not), folded as
    :func:`_printed_name` folds it: the calibrated, checked and approved by of a
    certificate tell their people apart (ISO/IEC 17025 7.8.2.1 k). A GonioError naming the
    field otherwise."""
    mine = _printed_name(_name(u))
    for other in s.scalars(select(User).where(User.username != u.username)):
        if _printed_name(_name(other)) == mine:
            raise GonioError(f"the user {other.username!r} is named {_name(other)!r} on "
                             "certificates already: give every person a name that tells them "
                             "apart", key="full_name" if u.full_name else "username")
        if other.id is not None and mine in names_held(s, other):
            raise GonioError(f"the user {other.username!r} was named {_name(u)!r} before "
                             "and may be so named on certificates: give every person a name "
                             "that tells them apart", key="full_name" if u.full_name
                             else "username")


def update_user(store, actor: User | None, username: str, *, active: bool | None = None,
                password: str | None = None, roles=None, full_name: str | None = None) -> User:
    """Deactivate or reactivate a user, reset the password, change the roles or name
    (admin; ``actor=None`` from ``gonio db set-user``), with its audit event. An admin cannot
    deactivate themself, and the last active admin keeps the admin role and stays active.
    A deactivated user's sessions end at their next request; nothing they did is removed."""
    if actor is not None:
        require(actor, "admin")
    with store.writing() as s:
        # every admin's row locked until commit: two admins changing each other at once
        # (PostgreSQL, READ COMMITTED) are counted one after the other, so the last active
        # admin stays (SQLite's writing transaction is exclusive already)
        s.execute(select(User.id).where(User.roles.like("%admin%")).with_for_update()).all()
        u = s.scalar(select(User).where(User.username == text(username, "username",
                                                               max_len=64)))
        if u is None:
            raise GonioError("no such user", key="username")
        before = state(u)
        if active is not None:
            if not active and actor is not None and actor.id == u.id:
                raise GonioError("you cannot deactivate yourself", key="active")
            u.active = bool(active)
        if roles is not None:
            u.roles = check_roles(roles)
        if full_name is not None:
            u.full_name = text(full_name, "full_name")
            with s.no_autoflush:
                _distinct_name(s, u)
        if password:
            u.password_hash = hash_password(password)
        s.flush()
        admins = s.scalar(select(func.count()).select_from(User).where(
            User.active.is_(True), User.roles.like("%admin%")))
        if before["active"] and "admin" in before["roles"].split() and not admins:
            raise GonioError("the last active admin cannot be deactivated nor lose the admin "
                             "role: make another admin first", key="username")
        after = state(u)
        if password:
            after["password_hash"] = "(reset)"
        audit(s, actor, "update", "user", u.id, before, after)
        s.commit()
        s.expunge(u)
    return u


def user(store, username: str) -> User | None:
    """The user with this name (detached), or None."""
    with store.session() as s:
        u = s.scalar(select(User).where(User.username == username))
        if u is not None:
            s.expunge(u)
        return u


# --------------------------------------------------------------------------- register


def add_customer(store, actor: User, name: str, address: str = "") -> Customer:
    """A new customer (technician)."""
    require(actor, "technician")
    c = Customer(name=text(name, "customer name", required=True),
                 address=text(address, "customer address", max_len=MAX_TEXT, multiline=True))
    return _create(store, actor, c, "customer", Customer.name == c.name,
                   "a customer with this name exists", "customer name")


def _create(store, actor: User | None, obj, entity: str, same, message: str, key: str):
    """Insert ``obj`` with its audit event, unless a row matching ``same`` exists."""
    with store.writing() as s:
        if s.scalar(select(type(obj)).where(same)):
            raise GonioError(message, key=key)
        s.add(obj)
        s.flush()
        audit(s, actor, "create", entity, obj.id, None, state(obj))
        s.commit()
    return obj


def check_limits(limits, spec_key: str | None = None) -> list[dict]:
    """Specification limits [{item, lower, upper, mpe, unit, source}] checked as the
    certificate checks them (``LAB_SCHEMA['specification_limits']``: a ``unit`` is a unit's
    text; whether it is the item's is decided once a calibration states the item's unit,
    :func:`gonio.formats.lab.check_limit_unit` at the conformity decision, as for the
    laboratory file's limits); with ``spec_key``, a limit that is
    not symmetric for an item that specification declares an extreme of magnitudes
    (``SPEC.magnitude_extremes``), or an upper limit below zero for an item it declares
    cannot be negative (``SPEC.nonnegative_items``), is refused when stored, as the
    laboratory file's check refuses it, not only when a calibration is decided later."""
    from gonio.formats.toml import validate_table
    from gonio.formats.lab import LAB_SCHEMA, check_magnitude_extremes, check_nonnegative_limits
    from gonio.specs import magnitude_extremes, nonnegative_items

    if isinstance(limits, str):
        try:
            limits = json.loads(limits or "[]")
        except json.JSONDecodeError as exc:
            raise GonioError(f"not JSON: {exc.msg}", key="limits") from None
    if not isinstance(limits, list) or len(limits) > 50:
        raise GonioError("a list of at most 50 limits", key="limits")
    schema = LAB_SCHEMA["specification_limits"].schema
    out = []
    for i, lim in enumerate(limits):
        if not isinstance(lim, dict):
            raise GonioError("each limit is an object", key=f"limits[{i}]")
        d = validate_table(lim, schema, f"limits[{i}]", "limits")
        if d["mpe"] is None and d["lower"] is None and d["upper"] is None:
            raise GonioError("give mpe or lower/upper", key=f"limits[{i}]")
        if d["mpe"] is not None and (d["lower"] is not None or d["upper"] is not None):
            raise GonioError("give mpe or lower/upper, not both", key=f"limits[{i}]")
        d["source"] = text(d["source"], f"limits[{i}].source")
        out.append(d)
    if spec_key:
        check_magnitude_extremes(out, magnitude_extremes(spec_key), where="limits")
        check_nonnegative_limits(out, nonnegative_items(spec_key), where="limits")
    return out


def _refuse_registered(s: Session, manufacturer: str, model: str, serial: str,
                       other_than: int | None = None) -> None:
    """Refuse a registration (or an edit of instrument ``other_than``) whose manufacturer,
    model and serial are another registered instrument's, compared as the readings are
    matched to a registered instrument (:func:`gonio.records.importer.registered_instrument`,
    the one identity normaliser :func:`gonio.formats.metadata.identity_text`: case, Unicode
    compatibility forms and spacing folded): ``rlg-0001`` or full-width ``ＲＬＧ-0001`` beside
    the registered RLG-0001 would be one instrument registered twice, its calibrations'
    history split between two records."""
    from gonio.formats.metadata import identity_text

    want = tuple(identity_text(x) for x in (manufacturer, model, serial))
    for other in s.scalars(select(Instrument).where(Instrument.id != (other_than or 0))
                           .order_by(Instrument.id)):
        if tuple(identity_text(x) for x in (other.manufacturer, other.model,
                                            other.serial)) == want:
            raise GonioError("this instrument (manufacturer, model, serial) is registered"
                             f" as {other.manufacturer} {other.model} {other.serial}"
                             " (compared without regard to case, character width and "
                             "spacing)", key="serial")


def register_instrument(store, actor: User, *, customer_id: int, serial: str, spec_key: str,
                        kind: str = "", manufacturer: str = "", model: str = "",
                        interval_months=None, limits=(), gyro_type: str = "") -> Instrument:
    """A new instrument of a customer in use (technician); ``gyro_type``: an optical gyro's
    type (:func:`gyro_type_value`), written into the laboratory file its calibrations are
    computed with."""
    from gonio.specs import get

    require(actor, "technician")
    get(text(spec_key, "spec", max_len=64, required=True))
    months = number_value(interval_months, "interval_months", 1, 120)
    inst = Instrument(customer_id=int(customer_id), serial=text(serial, "serial", required=True),
                      spec_key=spec_key.strip(), kind=text(kind, "type"),
                      gyro_type=gyro_type_value(gyro_type),
                      manufacturer=text(manufacturer, "manufacturer"),
                      model=text(model, "model"),
                      interval_months=None if months is None else int(months),
                      limits_json=json.dumps(check_limits(list(limits) if not isinstance(
                          limits, str) else limits, spec_key.strip())))
    with store.writing() as s:
        cust = s.get(Customer, inst.customer_id)
        if cust is None:
            raise GonioError("no such customer", key="customer")
        if cust.retired_on is not None:
            raise GonioError(f"customer {cust.name} was retired on {cust.retired_on}",
                             key="customer")
        _refuse_registered(s, inst.manufacturer, inst.model, inst.serial)
        s.add(inst)
        s.flush()
        audit(s, actor, "create", "instrument", inst.id, None, state(inst))
        s.commit()
    return inst


def past_due(what: str, due: _dt.date, today: _dt.date, reason: str, how: str) -> str:
    """Registering equipment whose due date ``due`` is before ``today`` (ISO/IEC 17025 6.4.7,
    6.4.13): refused with one line naming ``what`` and the date unless the person states
    ``reason`` (``how``: the option or field that states it); the reason, stripped, to be
    recorded with the entry ("" for equipment registered in time).

    >>> import datetime as dt
    >>> past_due("standard RT-07", dt.date(2026, 12, 1), dt.date(2026, 12, 1), "", "x")
    ''
    >>> past_due("standard RT-07", dt.date(2025, 1, 1), dt.date(2026, 12, 1), "", "--out-of-service")
    Traceback (most recent call last):
    gonio.errors.GonioError: key due_on: standard RT-07 was due on 2025-01-01, before today (2026-12-01): equipment past its due date is registered only with the reason stated (--out-of-service)
    """
    reason = text(reason, "reason", max_len=MAX_TEXT)
    if not is_past_due(due, today):
        return ""
    if not reason:
        raise GonioError(f"{what} was due on {due}, before today ({today}): equipment past its "
                         f"due date is registered only with the reason stated ({how})",
                         key="due_on")
    return reason


def add_standard(store, actor: User, *, name: str, identifier: str, due_on,
                 calibrated_on=None, accuracy: str = "", certificate: str = "",
                 traceability: str = "", out_of_service: str = "") -> Standard:
    """A reference standard or piece of bench equipment with its due date (technician). One
    already past its due date is refused (:func:`past_due`) unless ``out_of_service`` states
    why it is registered: then it is registered out of service, the reason in its record
    (``out_of_service``), and no calibration can use it while its due date is past
    (:func:`unusable_standard`); its recalibration recorded later (:func:`update_standard`,
    a new due date) puts it in use."""
    require(actor, "technician")
    st = Standard(name=text(name, "name", required=True),
                  identifier=text(identifier, "identifier", required=True),
                  accuracy=text(accuracy, "accuracy"), certificate=text(certificate, "certificate"),
                  traceability=text(traceability, "traceability"),
                  calibrated_on=date_value(calibrated_on, "calibrated_on"),
                  due_on=date_value(due_on, "due_on", required=True))
    today = records_today(store)
    st.out_of_service = past_due(f"standard {st.identifier}", st.due_on, today,
                                 out_of_service or "",
                                 "register it out of service with the reason: --out-of-service "
                                 "REASON, or the form's 'Out of service' field")
    return _create(store, actor, st, "standard", Standard.identifier == st.identifier,
                   "a standard with this identifier exists (record its recalibration by "
                   "editing it: new certificate and due date)", "identifier")


def _update(store, actor: User, model, obj_id, entity: str, values: dict, retire=None,
            unique=None, message: str = "") -> object:
    """Apply ``values`` (only the fields to change) to the row and, with ``retire`` True or
    False, retire it today or bring it back; its audit event (before, after) in the same
    transaction. ``unique(obj)``: a statement matching another row that would clash
    (refused with ``message``). A change of what a certificate states of a customer, an
    instrument or a standard reaches the calibrations naming it in the same transaction
    (:func:`_stated_change`)."""
    if retire is not None:
        values["retired_on"] = records_today(store) if retire else None
    with store.writing() as s:
        obj = s.get(model, int(obj_id))
        if obj is None:
            raise GonioError(f"no such {entity}", key=entity)
        before = state(obj)
        if retire and obj.retired_on is not None:
            values.pop("retired_on")                      # retired already: keep the date
        with s.no_autoflush:
            for k, v in values.items():
                setattr(obj, k, v)
            if unique is not None and s.scalar(unique(obj).where(model.id != obj.id)):
                raise GonioError(message, key=entity)
        after = state(obj)
        if after != before:
            audit(s, actor, "update", entity, obj.id, before, after)
            if entity in STATED_FIELDS:
                _stated_change(s, actor, entity, obj.id, before, after)
        s.commit()
        s.expunge(obj)
    return obj


#: The fields of a customer and an instrument that a certificate states. A standard's are
#: not among them: a certificate states each standard as the reviewed draft stated it, when
#: it was used (its recalibration, a new certificate and accuracy, reaches no calibration
#: made before; which standards were used changes by an attach only).
STATED_FIELDS = {"customer": ("name", "address"),
                 "instrument": ("customer_id", "kind", "manufacturer", "model", "serial",
                                "gyro_type")}


def _naming(s: Session, entity: str, obj_id: int) -> list:
    """The calibrations whose certificate names the customer or instrument ``obj_id`` and is
    not yet issued: those still open to a change of their details (:data:`ATTACHABLE`) and
    those approved and waiting for their issue (a reserved number)."""
    q = select(Calibration).where(Calibration.status.in_(ATTACHABLE)
                                  | (Calibration.pending_number != ""))
    if entity == "instrument":
        q = q.where(Calibration.instrument_id == obj_id)
    else:
        q = q.join(Instrument, Instrument.id == Calibration.instrument_id).where(
            Instrument.customer_id == obj_id)
    return list(s.scalars(q.order_by(Calibration.id).with_for_update()))


def _stated_change(s: Session, actor: User, entity: str, obj_id: int, before: dict,
                   after: dict) -> None:
    """A change of what certificates state of a customer or an instrument
    (:data:`STATED_FIELDS`) reaches every calibration naming it that is not yet issued, as an
    attach does (ISO/IEC 17025 7.8.1.1: what is issued is what was checked): a reviewed one
    goes back to its review, one with a stored result has its draft rendered again
    (:data:`DRAFTING`), an amendment records the change (``attach`` audit event on the
    calibration: :func:`amendment_changers`, one changes, another approves). A calibration
    approved and waiting for its issue refuses the change (GonioError: its certificate
    states what was approved; change it once issued, then amend)."""
    changed = {k: [before.get(k), after.get(k)] for k in STATED_FIELDS[entity]
               if before.get(k) != after.get(k)}
    if not changed:
        return
    for cal in _naming(s, entity, obj_id):
        if cal.pending_number:
            raise GonioError(f"calibration {cal.id} is approved ({cal.pending_number} "
                             f"reserved) and waits for its issue: its certificate states this "
                             f"{entity} as approved; change it once the certificate is issued, "
                             "then amend the certificate", key=entity)
        cal_before = state(cal)
        if cal.status == "reviewed":     # what was reviewed changed: reviewed again
            cal.status, cal.reviewed_by_id, cal.reviewed_at = "computed", None, None
            cal.reviewed_seal, cal.review_comment = "", ""
        if cal.status in REDRAFTED and cal.results_sha256:   # its draft shows the change
            cal.status, cal.progress = DRAFTING, (f"waiting for a worker to render the draft "
                                                  f"certificate with the {entity} changed")
            cal.worker_pid, cal.worker_host, cal.error = None, "", ""
        s.flush()
        audit(s, actor, "attach", "calibration", cal.id, cal_before,
              dict(state(cal), changed={entity: {"id": obj_id, **changed}}))


def _given(**fields) -> dict:
    """The fields that were given (not None)."""
    return {k: v for k, v in fields.items() if v is not None}


def update_customer(store, actor: User, customer_id: int, *, name=None, address=None,
                    retire: bool | None = None) -> Customer:
    """Edit a customer's name or address, retire it or bring it back (technician)."""
    require(actor, "technician")
    values = _given(name=None if name is None else text(name, "customer name", required=True),
                    address=None if address is None else text(
                        address, "customer address", max_len=MAX_TEXT, multiline=True))
    return _update(store, actor, Customer, customer_id, "customer", values, retire,
                   lambda o: select(Customer).where(Customer.name == o.name),
                   "a customer with this name exists")


def update_instrument(store, actor: User, instrument_id: int, *, customer_id=None, kind=None,
                      manufacturer=None, model=None, serial=None, interval_months="",
                      limits=None, retire: bool | None = None, gyro_type=None) -> Instrument:
    """Edit an instrument: transfer it to another customer, correct its description, set its
    interval (None or blank: the specification's default; ``""`` by default: unchanged) or
    limits, retire it or bring it back (technician)."""
    require(actor, "technician")
    values = _given(kind=kind, manufacturer=manufacturer, model=model, serial=serial)
    values = {k: text(v, k, required=k == "serial") for k, v in values.items()}
    if gyro_type is not None:
        values["gyro_type"] = gyro_type_value(gyro_type)
    if customer_id is not None:
        with store.session() as s:
            if s.get(Customer, int(customer_id)) is None:
                raise GonioError("no such customer", key="customer")
        values["customer_id"] = int(customer_id)
    if interval_months != "":
        months = number_value(interval_months, "interval_months", 1, 120)
        values["interval_months"] = None if months is None else int(months)
    if limits is not None:
        with store.session() as s:
            inst = s.get(Instrument, int(instrument_id))
            spec_key = inst.spec_key if inst is not None else None
        values["limits_json"] = json.dumps(check_limits(limits, spec_key))
    if {"manufacturer", "model", "serial"} & set(values):
        with store.session() as s:
            if (inst := s.get(Instrument, int(instrument_id))) is not None:
                _refuse_registered(s, *(values.get(k, getattr(inst, k)) for k in (
                    "manufacturer", "model", "serial")), other_than=inst.id)
    return _update(store, actor, Instrument, instrument_id, "instrument", values, retire,
                   lambda o: select(Instrument).where(
                       Instrument.manufacturer == o.manufacturer, Instrument.model == o.model,
                       Instrument.serial == o.serial),
                   "this instrument (manufacturer, model, serial) is registered")


def update_standard(store, actor: User, standard_id: int, *, name=None, accuracy=None,
                    certificate=None, traceability=None, calibrated_on=None, due_on=None,
                    retire: bool | None = None, out_of_service: str | None = None) -> Standard:
    """Record a standard's recalibration (its new certificate, calibration and due date: the
    audit trail keeps every earlier one), correct its details, retire it or bring it back
    (technician). A due date set already past (:func:`past_due`, on :func:`records_today`,
    the rule of :func:`add_standard`) is refused unless ``out_of_service`` states why: the
    standard is then out of service with that reason (no calibration can use it while its
    due date is past, :func:`unusable_standard`); a new due date not past puts it in use
    and clears the reason (the audit trail keeps it)."""
    require(actor, "technician")
    values = {k: text(v, k) for k, v in _given(accuracy=accuracy, certificate=certificate,
                                               traceability=traceability).items()}
    if name is not None:
        values["name"] = text(name, "name", required=True)
    for k, v in _given(calibrated_on=calibrated_on or None, due_on=due_on or None).items():
        values[k] = date_value(v, k)
    if values.get("calibrated_on") and values.get("due_on") and \
            values["due_on"] < values["calibrated_on"]:
        raise GonioError("the due date is before the calibration date", key="due_on")
    if values.get("due_on"):
        with store.session() as s:
            st = s.get(Standard, standard_id)
            ident = st.identifier if st is not None else str(standard_id)
            same = st is not None and st.due_on == values["due_on"]
        if not same:     # a new due date: out of service with its reason, or in time
            values["out_of_service"] = past_due(
                f"standard {ident}", values["due_on"], records_today(store), out_of_service or "",
                "state why it is out of service: the edit form's 'Out of service' field")
    return _update(store, actor, Standard, standard_id, "standard", values, retire)


# --------------------------------------------------------------------------- files


def store_file(store, stream, *, limit_bytes: float = MAX_UPLOAD) -> tuple[str, int]:
    """Put an uploaded file into the content-addressed store; (sha256, size). Its name is
    never used: only the digest names it."""
    digest, size = blobs.put_stream(store.blob_root, stream, limit_bytes=limit_bytes)
    with store.writing() as s:
        if s.get(Blob, digest) is None:
            s.add(Blob(sha256=digest, size=size))
            s.commit()
    return digest, size


#: what a calibration form may carry beside its readings file: a protocol, a laboratory
#: file and a table calibration (1 MiB each) and the form's fields
FORM_OVERHEAD_BYTES = 4 * 2**20


def check_upload_size(declared_bytes, limit_bytes: float = MAX_UPLOAD) -> None:
    """An upload whose declared size (the request's Content-Length) exceeds the readings
    limit (``GONIO_MAX_UPLOAD_BYTES``, default 256 MiB) plus :data:`FORM_OVERHEAD_BYTES` is
    refused before a byte of it is read: a GonioError with the limit, in one line."""
    try:
        n = int(declared_bytes)
    except (TypeError, ValueError):
        return                        # not declared: the store counts while it reads
    if n > limit_bytes + FORM_OVERHEAD_BYTES:
        raise GonioError(f"the upload, {blobs.size_text(n)}, is larger than the limit of "
                         f"{blobs.size_text(limit_bytes)} for a readings file; nothing was "
                         "stored", key="upload")


def file_bytes(store, sha256: str) -> bytes:
    """A stored file's bytes (checked against the digest)."""
    return blobs.get_bytes(store.blob_root, sha256)


# --------------------------------------------------------------------------- calibrations


#: Largest laboratory file accepted through the records (bytes; a TOML file of details).
MAX_LAB_BYTES = 2**20


def lab_file(store, sha256: str, name: str, spec_key: str) -> dict:
    """The decision rule and limits of a stored laboratory file (the ``--lab`` TOML of the
    command line): ``{"decision_rule": …, "specification_limits": [...]}``.

    The file is read and validated whole by the command line's own function,
    :func:`gonio.pipeline.dispatch.load_lab_file` with the specification ``spec_key`` (so a
    limit on an item the specification cannot have is refused before any work); a
    GonioError names the file by its uploaded ``name``, never by where it is kept. The
    records take only its ``[decision_rule]`` and ``[[specification_limits]]`` (for this
    calibration, in place of the instrument's): the laboratory, certificate, customer,
    instrument, standards and signatories are the records' own, which the workflow controls.
    A file without limits is refused (it would only take the instrument's away).
    """
    import tempfile

    from gonio.pipeline.dispatch import load_lab_file
    from gonio.specs import get

    spec = get(spec_key)
    shown = text(name, "laboratory file name", max_len=255) or "laboratory file"
    with tempfile.TemporaryDirectory(prefix="gonio-lab-") as tmp:
        path = Path(tmp) / "lab.toml"
        path.write_bytes(file_bytes(store, sha256))
        try:
            lab = load_lab_file(path, spec)
        except GonioError as exc:
            raise GonioError(exc.message.replace(str(path), shown), file=shown, line=exc.line,
                             column=exc.column, key=exc.key) from None
    if not lab.get("specification_limits") and not lab.get("table_calibration"):
        raise GonioError("no [[specification_limits]]: the records take a laboratory file for "
                         "its decision rule and limits (and its [table_calibration]) only",
                         file=shown)
    out = {"decision_rule": lab["decision_rule"],
           "specification_limits": lab["specification_limits"]}
    if lab.get("table_calibration"):      # checked against the upload (:func:`table_calibration_of`)
        out["table_calibration"] = lab["table_calibration"]
    return out


def submission_fields(performed_on, received_on, standard_ids, temperature_c, humidity_pct,
                      today: _dt.date):
    """The submission checks of a calibration's own fields, which every path that creates
    one passes (:func:`create_calibration`): the dates plausible on the laboratory's
    ``today`` (:func:`~gonio.records.models.records_today`; also the calibration date when
    none is given), at least one standard (ISO/IEC 17025 6.5: the result's traceability), the
    environment entered (7.8.4.1 a); returns (day, received, standard ids, temperature,
    humidity).

    >>> submission_fields("2026-01-05", "", [], 20, 45, _dt.date(2026, 1, 5))
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key standards: tick the reference standard(s) used: a calibration names at least one registered standard (its traceability)
    """
    day = date_value(performed_on, "performed_on") or today
    received = date_value(received_on, "received_on")
    plausible_dates(day, received, today)
    ids = sorted({int(i) for i in standard_ids})
    if not ids:
        raise GonioError("tick the reference standard(s) used: a calibration names at least "
                         "one registered standard (its traceability)", key="standards")
    temp = condition_value(temperature_c, "temperature_c", -50, 100)
    hum = condition_value(humidity_pct, "humidity_pct", 0, 100)
    for value, what in ((temp, "room temperature (°C)"), (hum, "relative humidity (%)")):
        if value is None:
            raise GonioError(f"enter the {what} of the calibration", key="environment")
    return day, received, ids, temp, hum


#: the states in which a calibration no longer stands for its readings (they may be used again).
#: A failed calibration stands: its run, redraft or issue stopped, and it can be run again
#: (:func:`retry`) on the same readings, so it would certify them; void it (:func:`void`) when
#: it will not be run again, and its readings are free (docs/records.md).
CLOSED = ("rejected", "void")
#: the GonioError key of readings already used by another calibration
REUSE_KEY = "readings used before"
#: what the refusal adds when the calibration that holds the readings failed
FAILED_HINT = (" (it failed and can be run again; void it if it will not be, and its readings "
               "are free)")


def _writes(s: Session) -> bool:
    """Whether ``s`` is a writing session (:meth:`gonio.records.db.Store.writing`)."""
    try:
        return bool(s.get_bind().get_execution_options().get("gonio_write"))
    except Exception:                       # noqa: BLE001 - an unbound session: no
        return False


def readings_content_of(s: Session, sha256: str, path=None) -> str | None:
    """The content digest of the stored file ``sha256`` (table ``readings_contents``,
    :func:`gonio.records.blobs.readings_content`), computed from the store's file where none
    is kept yet (the session's ``info["blob_root"]``, set by
    :func:`gonio.records.db.open_store`) and kept where ``s`` writes and the file is stored;
    None: no such file, no table in it, or no store known. ``path``: the file itself, where
    it is not stored yet."""
    return _content_row(s, sha256, path)[0]


def _content_row(s: Session, sha256: str, path=None) -> tuple[str | None, str | None]:
    """(content digest, the SHA-256 of the stream the file was reduced from, as it names it:
    ``# source_stream_sha256``, :func:`gonio.formats.content.source_sha256`) of the file
    ``sha256``: its row of ``readings_contents``, else computed from ``path`` or the store's
    file (:func:`gonio.records.blobs.readings_facts`) and kept where ``s`` writes and the
    file is stored (:func:`readings_content_of`)."""
    row = s.get(ReadingsContent, sha256)
    if row is not None:
        return row.content_sha256, row.source_sha256
    root = s.info.get("blob_root")
    if path is not None and Path(path).is_file():
        from gonio.formats.content import content_sha256, source_sha256
        try:
            digest = content_sha256(path)
        except (OSError, ValueError):
            digest = None
        source = source_sha256(path)
    elif root is None:
        digest = source = None
    else:
        digest, source = blobs.readings_facts(root, sha256)
    if digest is not None and _writes(s) and s.get(Blob, sha256) is not None:
        s.add(ReadingsContent(sha256=sha256, content_sha256=digest, source_sha256=source))
    return digest, source


def readings_used_by(s: Session, sha256: str, *, other_than: int | None = None,
                     path=None) -> list[dict]:
    """The calibrations that stand (any state but rejected or void) whose readings are the
    file ``sha256``, hold its data written otherwise (the same content digest,
    :func:`readings_content_of`: a newline, line ends, metadata lines, the order of rows or
    columns, a number's spelling), are the stream it was reduced from (``"stream"``: the
    file names that stream's SHA-256, :func:`_content_row`) or were reduced from it
    (``"reduced"``: the file is their stream), less ``other_than``: ``[{"id", "serial",
    "performed_on", "status", "same": "file" | "content" | "stream" | "reduced"}]``, oldest
    first. ``path``: the readings file itself, where it is not in the store yet."""
    def standing(q):
        q = (q.join(Instrument, Calibration.instrument_id == Instrument.id)
             .where(Calibration.status.not_in(CLOSED)))
        return q if other_than is None else q.where(Calibration.id != other_than)

    cols = (Calibration.id, Instrument.serial, Calibration.performed_on, Calibration.status,
            Calibration.readings_sha256)
    found, how = {}, {}

    def add(where, label: str) -> None:
        """The standing calibrations whose readings (their digest row joined) meet
        ``where``, as ``label`` says they are the same measurement."""
        for r in s.execute(standing(select(*cols))
                           .outerjoin(ReadingsContent,
                                      Calibration.readings_sha256 == ReadingsContent.sha256)
                           .where(where)).all():
            found.setdefault(r[0], r)
            how.setdefault(r[0], label)

    add(Calibration.readings_sha256 == sha256, "file")
    content, source = _content_row(s, sha256, path)
    if source is not None:          # readings reduced from a stream a calibration used
        add(Calibration.readings_sha256 == source, "stream")
    # a standing calibration's readings not yet digested (an older store, a restore):
    # digested now (and kept where ``s`` writes), compared by digest and by source
    fresh, reduced = set(), set()
    for (other,) in s.execute(
            standing(select(Calibration.readings_sha256))
            .outerjoin(ReadingsContent, Calibration.readings_sha256 == ReadingsContent.sha256)
            .where(ReadingsContent.sha256.is_(None)).distinct()).all():
        if other != sha256:
            digest, came_from = _content_row(s, other)
            if content is not None and digest == content:
                fresh.add(other)
            if came_from == sha256:
                reduced.add(other)
    if _writes(s):
        s.flush()
    if content is not None:
        add((ReadingsContent.content_sha256 == content)
            | Calibration.readings_sha256.in_(fresh), "content")
    # a stream whose reduced readings a calibration used
    add((ReadingsContent.source_sha256 == sha256)
        | Calibration.readings_sha256.in_(reduced), "reduced")
    return [{"id": r[0], "serial": r[1], "performed_on": r[2], "status": r[3],
             "same": "file" if r[4] == sha256 else how[r[0]]}
            for _, r in sorted(found.items())]


def check_readings_unused(s: Session, sha256: str, *, other_than: int | None = None,
                          reason: str = "", path=None) -> list[dict]:
    """The one check, on every path that records readings for a calibration (the web form
    and :func:`create_calibration`, ``gonio db import`` and ``gonio calibrate --record``,
    a bench's acquired readings), that one measurement is not certified as several: readings
    whose SHA-256 are already those of another calibration that stands, or whose data are
    (the same content digest: the same readings with a newline added, other line ends or
    metadata lines, rows or columns in another order), or that were reduced from another's
    stream or are the stream of another's reduced readings (:func:`readings_used_by`, ``path``
    the file where it is not stored yet) are refused, a one-line GonioError (key :data:`REUSE_KEY`)
    naming that calibration (id, instrument serial, date, state) — unless ``reason`` says
    why they are used again (the web form asks it; the caller audits it). The lineage of one
    calibration is one row: a review, a re-computation, a redraft or an amendment of it
    (:func:`amend`) never records its readings again, and a rejected or void calibration's
    readings may be used by a new one; a failed one's may not (:data:`CLOSED`: it can be
    run again), the refusal says to void it first. ``other_than``: the calibration the
    readings are being recorded for. Call it inside the writing session that records them, so nothing
    is recorded when it refuses. Returns the other calibrations (empty when none)."""
    before = readings_used_by(s, sha256, other_than=other_than, path=path)
    if before and not reason:
        first = before[0]
        how = {"file": "are already those of",
               "stream": "were reduced from the stream that is the readings of",
               "reduced": "are the stream reduced to the readings of"}.get(
            first["same"], "hold the same data, written otherwise, as the readings of")
        raise GonioError(f"these readings (SHA-256 {sha256[:12]}…) {how} "
                         f"calibration {first['id']} ({first['serial']}, "
                         f"{first['performed_on']}, {first['status']})"
                         + (f" and {len(before) - 1} more" if len(before) > 1 else "")
                         + ": the same measurement is not calibrated twice"
                         + (FAILED_HINT if first["status"] == "failed" else ""), key=REUSE_KEY)
    return before


#: The name a calibration's table calibration file is kept under among its files (an input,
#: stored at creation; sealed with the run's files).
TABLE_CALIBRATION = "table_calibration.csv"

#: The prefix of the names a calibration's other input files are kept under among its files:
#: each file its readings name as part of their data (a triad's thermal readings, the optical
#: static record), ``input/`` + the name the readings give it (stored at import; sealed with
#: the run's files): a result is computed again from what is stored.
INPUT_PREFIX = "input/"


#: The prefix of the names a calibration's option files are kept under among its files: each
#: file the run was given by an option of its specification (``--tilt FILE``, ``--thermal
#: FILE``), ``option/OPTION/`` + the file name the run read it under (stored at import; sealed
#: with the run's files; the manifest's ``option_files`` records its SHA-256): a result is
#: computed again from what is stored.
OPTION_PREFIX = "option/"


def option_file_name(option: str, name: str) -> str:
    """The name an option's file ``name`` is kept under among a calibration's files.

    >>> option_file_name("tilt", "tilt.json")
    'option/tilt/tilt.json'
    """
    return f"{OPTION_PREFIX}{option}/{name}"


def write_option_files(store, cal_id: int, folder: Path) -> dict:
    """The calibration's stored option files (:data:`OPTION_PREFIX`, each checked against its
    digest) written into ``folder``/option/OPTION/ under the names the run read them by:
    {option: path}, the options its run is given ({} where none)."""
    with store.session() as s:
        rows = s.execute(select(CalibrationFile.name, CalibrationFile.sha256).where(
            CalibrationFile.calibration_id == int(cal_id),
            CalibrationFile.name.startswith(OPTION_PREFIX))).all()
    out = {}
    for name, sha in sorted(rows):
        option, _, base = name[len(OPTION_PREFIX):].partition("/")
        if not option or not base or base != Path(base).name or base in (".", ".."):
            raise GonioError(f"the stored option file {name!r} is not option/OPTION/NAME",
                             key=f"calibration {cal_id}")
        target = Path(folder) / "option" / option / base
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(file_bytes(store, sha))
        out[option] = target
    return out


def write_inputs(store, cal_id: int, folder: Path) -> list[str]:
    """The calibration's stored input files (:data:`INPUT_PREFIX`, each checked against its
    digest) written into ``folder`` under the names its readings give them, for a run of the
    readings placed there; their names (none: [])."""
    with store.session() as s:
        rows = s.execute(select(CalibrationFile.name, CalibrationFile.sha256).where(
            CalibrationFile.calibration_id == int(cal_id),
            CalibrationFile.name.startswith(INPUT_PREFIX))).all()
    names = []
    for name, sha in sorted(rows):
        rel = name[len(INPUT_PREFIX):]
        target = Path(folder) / rel
        if ".." in Path(rel).parts or Path(rel).is_absolute():
            raise GonioError(f"the stored input {name!r} is not a name inside the readings' "
                             "folder", key=f"calibration {cal_id}")
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(file_bytes(store, sha))
        names.append(rel)
    return names


def table_calibration_of(spec, lab: dict, lab_name: str, sha256: str | None,
                         day: _dt.date) -> None:
    """The table calibration upload ``sha256`` checked for a calibration per ``spec`` on
    ``day``: only a specification that takes one (``"table_calibration"`` in its
    ``calibrate_options``); where the laboratory file ``lab`` (:func:`lab_file`) names one
    (``[table_calibration]``), the upload is required, its SHA-256 must be the one stated and
    the calibration's date within its validity
    (:func:`gonio.pipeline.equipment.check_validity`). Each refusal one GonioError line."""
    from gonio.pipeline.equipment import check_validity

    tc = (lab or {}).get("table_calibration")
    if sha256 is None and tc is None:
        return
    if "table_calibration" not in spec.calibrate_options:
        raise GonioError(f"{spec.key} takes no table calibration", key="table_calibration")
    shown = lab_name or "laboratory file"
    if tc is None:
        return
    if sha256 is None:
        raise GonioError(f"the laboratory file names the table calibration {tc['file']} "
                         f"(SHA-256 {tc['sha256'][:16]}…): upload it as the table calibration "
                         "file", file=shown, key="table_calibration")
    if sha256 != tc["sha256"]:
        raise GonioError(f"the table calibration uploaded has SHA-256 {sha256}, not the "
                         f"{tc['sha256']} the laboratory file states for {tc['file']}",
                         file=shown, key="table_calibration.sha256")
    check_validity(tc, [(day, "date of calibration")], shown)


def table_calibration_name(s: Session, cal_id: int) -> str:
    """The file name a calibration's table calibration was given (the name uploaded, or the
    one the imported run read it under): its ``table-calibration`` audit event's ``name``
    where that is a plain file name, else :data:`TABLE_CALIBRATION` (the name the records
    keep the bytes under). Older imports recorded the laboratory file's name followed by
    ``[table_calibration]``, not the file's: those fall back too."""
    row = s.scalar(select(AuditEvent.after_json).where(
        AuditEvent.action == "table-calibration", AuditEvent.entity == "calibration",
        AuditEvent.entity_id == str(int(cal_id))).order_by(AuditEvent.id.desc()).limit(1))
    try:
        name = str((json.loads(row) if row else {}).get("name") or "")
    except (ValueError, AttributeError):
        name = ""
    plain = (name == Path(name).name and name not in ("", ".", "..") and "\\" not in name
             and name == name.strip() and len(name) <= 255
             and not unshowable(name)
             and not name.endswith("[table_calibration]"))
    return name if plain else TABLE_CALIBRATION


def table_calibration_file(store, cal_id: int, work: Path) -> Path | None:
    """The calibration's stored table calibration (:data:`TABLE_CALIBRATION`, checked against
    its digest) written into the work folder ``work`` for its run, under the name it was given
    (:func:`table_calibration_name`, in its own subfolder: the run's certificate names the
    file the laboratory gave, as ``gonio calibrate --table-calibration FILE`` does), or None
    where it has none."""
    with store.session() as s:
        f = s.get(CalibrationFile, (int(cal_id), TABLE_CALIBRATION))
        name = table_calibration_name(s, cal_id) if f is not None else ""
    if f is None:
        return None
    folder = Path(work) / "table-calibration"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_bytes(file_bytes(store, f.sha256))
    return path


# --------------------------------------------------------------------------- the register of
#                                                                            table calibrations


def _readable_table_calibration(store, sha256: str, shown: str) -> str:
    """The stored file ``sha256`` read as a table calibration by the reader of every
    specification that reads one (``Specification.read_table_calibration``): a file no
    reader takes (not UTF-8, a NUL byte, a formula in a number's place, a missing column) is
    refused in one line naming the file by ``shown``, its line and column, before it is
    registered. Returns what the readers read (:func:`table_content`)."""
    from gonio import specs

    readers = [sp.read_table_calibration for sp in specs.available().values()
               if sp.read_table_calibration is not None]
    if not readers:
        raise GonioError("no specification reads a table calibration", key="sha256")
    path = blobs.blob_path(store.blob_root, sha256)
    read_as = []
    for read in readers:
        try:
            read_as.append(read(path))
        except GonioError as exc:
            raise GonioError(f"not a table calibration: {exc.message}",
                             file=shown or TABLE_CALIBRATION, line=exc.line,
                             column=exc.column) from None
    return table_content(read_as)


#: Fields of a read table calibration that say where it was read from, not what it states
#: (:func:`table_content` leaves them out).
TABLE_CONTENT_NOT_STATED = frozenset({"sha256", "lines", "source"})


def table_content(read_as) -> str:
    """The SHA-256 of what a table calibration file states, as its readers read it: every
    field of each reader's object (a dataclass: positions, errors, uncertainties,
    covariance, degrees of freedom…) but where it was read from
    (:data:`TABLE_CONTENT_NOT_STATED`), numbers as float64 bytes (−0.0 as 0.0), the rows in
    one order (:func:`_rows_in_order`). Two files that differ only in their bytes (a line
    ending, a trailing blank, a comment, "0.10" for "0.1", "-0.0" for "0.0", the same rows in
    another order) have one content: a withdrawn entry's content is not registered again
    under other bytes (:func:`_refuse_withdrawn_bytes`).

    >>> from dataclasses import dataclass
    >>> import numpy as np
    >>> @dataclass
    ... class T:
    ...     table_deg: np.ndarray
    ...     source: str
    >>> a = table_content([T(np.array([0.0, 90.0]), "a.csv")])
    >>> a == table_content([T(np.array([0.0, 90.00]), "b.csv")])
    True
    >>> a == table_content([T(np.array([0.0, 90.1]), "a.csv")])
    False
    """
    import dataclasses
    import hashlib

    import numpy as np

    h = hashlib.sha256()
    for obj in read_as:
        fs = dataclasses.fields(obj) if dataclasses.is_dataclass(obj) else ()
        values = {}
        for f in fs:
            if f.name in TABLE_CONTENT_NOT_STATED:
                continue
            v = getattr(obj, f.name)
            if v is not None and isinstance(v, (np.ndarray, list, tuple, int, float)) \
                    and not isinstance(v, bool):
                try:
                    v = np.asarray(v, dtype=float) + 0.0       # -0.0 → 0.0
                except (TypeError, ValueError):
                    pass
            values[f.name] = v
        for name, v in _rows_in_order(values).items():
            h.update(name.encode())
            if v is None:
                h.update(b"\0none")
            elif isinstance(v, np.ndarray) and v.dtype == float:
                h.update(v.tobytes())
            else:
                h.update(repr(v).encode())
    return h.hexdigest()


def _rows_in_order(values: dict) -> dict:
    """A read table calibration's fields with its rows in one order: the 1-D float arrays of
    the first such array's length are its columns (a position and what the file states
    there), sorted together by their values (the first column first); an n × n array (a
    covariance between the rows) is permuted on both axes. A reader keeps rows in file order
    and pairs each position with its own numbers, so two files that list the same rows in
    another order state the same thing (:func:`table_content`).

    >>> import numpy as np
    >>> r = _rows_in_order({"deg": np.array([120.0, 0.0]), "e": np.array([0.01, 0.0]),
    ...                     "cov": np.array([[1.0, 0.5], [0.5, 2.0]]), "n": 3})
    >>> r["deg"].tolist(), r["e"].tolist(), r["cov"].tolist(), r["n"]
    ([0.0, 120.0], [0.0, 0.01], [[2.0, 0.5], [0.5, 1.0]], 3)
    """
    import numpy as np

    cols = [k for k, v in values.items() if isinstance(v, np.ndarray) and v.dtype == float
            and v.ndim == 1 and v.size > 1]
    if not cols:
        return values
    n = values[cols[0]].size
    cols = [k for k in cols if values[k].size == n]
    order = np.lexsort(tuple(values[k] for k in reversed(cols)))
    out = dict(values)
    for k, v in values.items():
        if not (isinstance(v, np.ndarray) and v.dtype == float):
            continue
        if v.ndim == 1 and v.size == n:
            out[k] = v[order]
        elif v.ndim == 2 and v.shape == (n, n):
            out[k] = v[np.ix_(order, order)]
    return out


def add_months(day: _dt.date, months: int) -> _dt.date:
    """``day`` plus ``months`` calendar months, the day of the month kept where the month
    has it, else its last day (2025-01-31 + 1 → 2025-02-28).

    >>> add_months(_dt.date(2025, 1, 31), 1), add_months(_dt.date(2024, 2, 29), 12)
    (datetime.date(2025, 2, 28), datetime.date(2025, 2, 28))
    """
    import calendar

    y, m = divmod(day.month - 1 + months, 12)
    year, month = day.year + y, m + 1
    return day.replace(year=year, month=month,
                       day=min(day.day, calendar.monthrange(year, month)[1]))


def table_interval_months(s: Session) -> int:
    """The laboratory's longest interval of a table calibration (setting
    ``table_calibration_max_months``, default 24)."""
    row = s.get(Setting, "table_calibration_max_months")
    try:
        return int(check_setting("table_calibration_max_months", row.value)) \
            if row is not None else int(SETTINGS["table_calibration_max_months"])
    except GonioError:
        return int(SETTINGS["table_calibration_max_months"])


def check_table_dates(start: _dt.date, due: _dt.date, months: int, today: _dt.date) -> None:
    """The register's dates (docs/records.md, the register): valid from (the table's
    calibration date) not after ``today`` (the laboratory's date, :func:`records_today`: a calibration
    is registered once it has been made), the due date after it and at most ``months`` calendar months after it (the
    laboratory's maximum interval, :func:`add_months`). One-line GonioError otherwise.

    >>> check_table_dates(_dt.date(2025, 1, 1), _dt.date(2027, 1, 1), 24, _dt.date(2026, 1, 1))
    >>> check_table_dates(_dt.date(2025, 1, 1), _dt.date(2027, 1, 2), 24, _dt.date(2026, 1, 1))
    Traceback (most recent call last):
    gonio.errors.GonioError: key due_on: due_on 2027-01-02 is more than 24 months after valid_from 2025-01-01 (the laboratory's longest table calibration interval, setting table_calibration_max_months: due on 2027-01-01 at the latest)
    """
    if start > today:
        raise GonioError(f"valid_from {start} is in the future (today is {today}, the laboratory's date): "
                         "register a table calibration once it has been made",
                         key="valid_from")
    if due <= start:
        raise GonioError(f"due_on {due} is not after valid_from {start}", key="due_on")
    latest = add_months(start, months)
    if due > latest:
        raise GonioError(f"due_on {due} is more than {months} months after valid_from {start} "
                         "(the laboratory's longest table calibration interval, setting "
                         f"table_calibration_max_months: due on {latest} at the latest)",
                         key="due_on")


def withdrawals(s: Session, ids: Iterable[int] | None = None) -> dict:
    """The register's withdrawn entries: entry id → :class:`TableCalibrationWithdrawal`
    (of the entries ``ids``, or all), with who asked and who approved loaded."""
    from sqlalchemy.orm import selectinload

    q = select(TableCalibrationWithdrawal).options(
        selectinload(TableCalibrationWithdrawal.asked_by),
        selectinload(TableCalibrationWithdrawal.withdrawn_by))
    if ids is not None:
        q = q.where(TableCalibrationWithdrawal.table_calibration_id.in_(list(ids)))
    return {w.table_calibration_id: w for w in s.scalars(q)}


def _governed(s: Session, st: Standard, start: _dt.date, sha256: str,
              withdrawn: dict) -> Calibration | None:
    """The first calibration recorded with the table ``st`` (among its standards, or made
    with one of its register entries) dated on or after ``start`` that an entry valid from
    ``start`` would govern behind its back: one made with another entry not withdrawn, with
    an upload of another file, or with none. Void and rejected calibrations, those made with
    a withdrawn entry (listed as affected by it) and those made with these very bytes do not
    count."""
    tables = select(TableCalibration.id).where(TableCalibration.standard_id == st.id)
    named = select(CalibrationStandard.calibration_id).where(
        CalibrationStandard.standard_id == st.id)
    cals = s.scalars(select(Calibration).where(
        Calibration.performed_on >= start,
        Calibration.status.not_in(("void", "rejected")),
        Calibration.id.in_(named) | Calibration.table_calibration_id.in_(tables))
        .order_by(Calibration.performed_on, Calibration.id)).all()
    for cal in cals:
        if cal.table_calibration_id is not None and cal.table_calibration_id in withdrawn:
            continue
        kept = s.get(CalibrationFile, (cal.id, TABLE_CALIBRATION))
        if kept is not None and kept.sha256 == sha256:
            continue
        return cal
    return None


def _same_identifier(text: str | None) -> str:
    """A certificate identifier as compared with a withdrawn entry's
    (:func:`_refuse_withdrawn_bytes`): case, Unicode compatibility forms and runs of white
    space do not make another certificate ("tc-1 " and full-width "ＴＣ－１" are TC-1), by
    the one identity normaliser, :func:`gonio.formats.metadata.identity_text`.

    >>> _same_identifier(" tc-1  a") == _same_identifier("TC-1 A") == _same_identifier("ＴＣ－１ Ａ")
    True
    """
    from gonio.formats.metadata import identity_text

    return identity_text(text)


def _refuse_withdrawn_bytes(s: Session, store, sha256: str, content: str, *,
                            standard_id: int, valid_from: _dt.date, due_on: _dt.date,
                            certificate: str) -> None:
    """Refuse to register what the register holds as a withdrawn entry (of any table): a
    withdrawal is asked by one person and approved by another, so one person registering the
    same again would undo it alone. Refused: the same bytes (``sha256``), whatever else is
    stated; and a file that states the same numbers (``content``, :func:`table_content`: a
    line ending, a blank or a comment changed) registered for the same table, valid from the
    same day, due the same day under the same certificate identifier (case and white space
    aside, :func:`_same_identifier`), i.e. a registration that corrects nothing. A correction takes the withdrawn entry's place: other numbers, or
    the same numbers under corrected dates or identifier (docs/records.md, the register:
    withdrawn)."""
    entries = s.scalars(select(TableCalibration).order_by(TableCalibration.id)).all()
    gone = withdrawals(s, [e.id for e in entries])
    for e in entries:
        if e.id not in gone:
            continue
        if e.sha256 == sha256:
            what = "bytes are"
        elif ((e.standard_id, e.valid_from, e.due_on, _same_identifier(e.certificate))
              == (standard_id, valid_from, due_on, _same_identifier(certificate))):
            try:
                same = _readable_table_calibration(store, e.sha256, e.name) == content
            except GonioError:
                same = False            # a withdrawn file no reader takes now: not this one
            if not same:
                continue
            what = ("numbers (as read), table, dates and certificate are, with other bytes "
                    "only,")
        else:
            continue
        raise GonioError(f"this file (SHA-256 {sha256[:16]}…) is table calibration "
                         f"{e.id} ({e.certificate or e.name}), "
                         f"withdrawn on {gone[e.id].withdrawn_at:%Y-%m-%d %H:%M} UTC: "
                         f"a withdrawn entry's {what} not registered again "
                         "(register the corrected file)", key="sha256")


def register_table_calibration(store, actor: User, *, standard_id: int, sha256: str,
                               name: str = "", valid_from=None, due_on=None,
                               certificate: str = "") -> TableCalibration:
    """Put a rotary table's calibration into the laboratory's register (technician, who
    registers equipment: ISO/IEC 17025 6.4.13): the stored file ``sha256`` (kept once by its
    SHA-256; ``name`` its own file name, for display and the run's file name), the table it
    belongs to (``standard_id``: the table registered as a standard, not retired), valid from
    ``valid_from`` (the table's calibration date) until ``due_on``
    (:func:`check_table_dates`: not in the future, due after it, within the laboratory's
    longest interval), and the table certificate's identifier ``certificate``; audited as
    ``register`` of a ``table-calibration``. Among the table's entries not withdrawn, the
    same file twice or two valid from the same day (which would be in force?) are refused
    with one line. A later one of the same table supersedes the earlier from its own
    ``valid_from`` (:func:`table_calibration_state`), so an entry is refused where a
    calibration already recorded on or after that day was made otherwise (:func:`_governed`:
    it would be in force on a day whose calibration used another entry). Nothing
    registered is changed or removed; a wrong entry is withdrawn
    (:func:`ask_withdrawal`). The file must read as a table calibration
    (:func:`_readable_table_calibration`). An entry already past its due date is a record of
    the register's history (a table calibration, not equipment: :func:`add_standard` refuses
    equipment past due), in force on no calibration day after it
    (:func:`table_calibration_state`)."""
    require(actor, "technician")
    start = date_value(valid_from, "valid_from", required=True)
    due = date_value(due_on, "due_on", required=True)
    shown = file_name(name, "table calibration file name")
    cert = text(certificate, "certificate")
    with store.writing() as s:
        check_table_dates(start, due, table_interval_months(s), records_today(s))
        st = s.get(Standard, int(standard_id), with_for_update=True)
        if st is None:
            raise GonioError("no such standard (register the rotary table as a standard "
                             "first)", key="standard")
        if st.retired_on is not None:
            raise GonioError(f"standard {st.identifier} was retired on {st.retired_on}",
                             key="standard")
        if s.get(Blob, sha256) is None:
            raise GonioError("no such stored file", key="sha256")
        content = _readable_table_calibration(store, sha256, shown)
        others = s.scalars(select(TableCalibration).where(
            TableCalibration.standard_id == st.id)).all()
        withdrawn = withdrawals(s, [o.id for o in others])
        _refuse_withdrawn_bytes(s, store, sha256, content, standard_id=st.id,
                                valid_from=start, due_on=due, certificate=cert)
        for other in others:
            if other.id in withdrawn:
                continue
            if other.sha256 == sha256:
                raise GonioError(f"this file (SHA-256 {sha256[:16]}…) is registered for "
                                 f"{st.identifier} already: table calibration {other.id}",
                                 key="sha256")
            if other.valid_from == start:
                raise GonioError(f"table calibration {other.id} of {st.identifier} is valid "
                                 f"from {start} already: one a day", key="valid_from")
        cal = _governed(s, st, start, sha256, withdrawn)
        if cal is not None:
            used = (f"table calibration {cal.table_calibration_id}"
                    if cal.table_calibration_id is not None else "an uploaded file"
                    if s.get(CalibrationFile, (cal.id, TABLE_CALIBRATION))
                    else "no table calibration")
            raise GonioError(f"calibration {cal.id} of {cal.performed_on} was made with {used} "
                             f"of {st.identifier}: an entry valid from {start} would be in "
                             "force on its day behind its back (register it valid from "
                             f"{cal.performed_on + _dt.timedelta(days=1)} or later, or "
                             "withdraw the entry that calibration used first)",
                             key="valid_from")
        tc = TableCalibration(standard_id=st.id, sha256=sha256, name=shown, certificate=cert,
                              valid_from=start, due_on=due, registered_by_id=actor.id)
        s.add(tc)
        s.flush()
        audit(s, actor, "register", "table-calibration", tc.id, None,
              dict(state(tc), table=st.identifier))
        s.commit()
        s.refresh(tc)
        s.expunge(tc)
    return tc


def withdrawal_affected(s: Session, tc_id: int) -> list[Calibration]:
    """The calibrations made with the register's entry ``tc_id`` (their seal names it): those
    a withdrawal of it leaves as they are, lists as affected and stops from review, approval
    and issue (:func:`_not_withdrawn`; docs/records.md, the register: affected)."""
    return list(s.scalars(select(Calibration).where(
        Calibration.table_calibration_id == int(tc_id)).order_by(Calibration.id)))


def pending_withdrawal(s: Session, tc_id: int) -> dict | None:
    """The withdrawal asked for of the entry ``tc_id`` and not yet approved or declined
    (its ``ask-withdrawal`` audit event, newer than any ``withdraw`` or
    ``decline-withdrawal`` of it): ``{"reason", "asked_by_id", "asked_by", "asked_at"}``."""
    events = s.scalars(select(AuditEvent).where(
        AuditEvent.entity == "table-calibration", AuditEvent.entity_id == str(int(tc_id)),
        AuditEvent.action.in_(("ask-withdrawal", "withdraw", "decline-withdrawal")))
        .order_by(AuditEvent.id.desc()).limit(1)).all()
    if not events or events[0].action != "ask-withdrawal":
        return None
    ev = events[0]
    return {"reason": json.loads(ev.after_json).get("reason", ""), "asked_by_id": ev.user_id,
            "asked_by": ev.username, "asked_at": ev.at}


def _entry_for_withdrawal(s: Session, tc_id) -> TableCalibration:
    try:
        tc = s.get(TableCalibration, int(tc_id), with_for_update=True)
    except (TypeError, ValueError):
        tc = None
    if tc is None:
        raise GonioError("no such table calibration in the register", key="table_calibration")
    w = s.scalar(select(TableCalibrationWithdrawal).where(
        TableCalibrationWithdrawal.table_calibration_id == tc.id))
    if w is not None:
        raise GonioError(f"table calibration {tc.id} was withdrawn on "
                         f"{w.withdrawn_at:%Y-%m-%d %H:%M} UTC already",
                         key="table_calibration")
    return tc


def _pending_withdrawal_or_refused(s: Session, tc_id) -> tuple[TableCalibration, dict]:
    """The register's entry ``tc_id`` (locked, not withdrawn: :func:`_entry_for_withdrawal`)
    and the withdrawal asked for of it (:func:`pending_withdrawal`), which approving or
    declining needs: none asked for is refused in one line."""
    tc = _entry_for_withdrawal(s, tc_id)
    asked = pending_withdrawal(s, tc.id)
    if asked is None:
        raise GonioError(f"no withdrawal of table calibration {tc.id} is asked for",
                         key="table_calibration")
    return tc, asked


def ask_withdrawal(store, actor: User, tc_id: int, reason: str) -> None:
    """Ask for the register's entry ``tc_id`` to be withdrawn (technician or reviewer), with
    the reason; it takes effect when another person approves it (:func:`approve_withdrawal`:
    the two-person rule of an amendment, whatever ``min_people``). Audited as
    ``ask-withdrawal``; one request at a time."""
    if not (actor is not None and actor.active and (actor.has("technician")
                                                   or actor.has("reviewer"))):
        raise GonioError("this needs the technician or reviewer role", key="role")
    reason = text(reason, "reason", max_len=MAX_TEXT, multiline=True, required=True)
    with store.writing() as s:
        tc = _entry_for_withdrawal(s, tc_id)
        if pending_withdrawal(s, tc.id) is not None:
            raise GonioError(f"a withdrawal of table calibration {tc.id} is asked for already: "
                             "another person approves or declines it", key="table_calibration")
        audit(s, actor, "ask-withdrawal", "table-calibration", tc.id, None,
              {"reason": reason, "affected": [c.id for c in withdrawal_affected(s, tc.id)]})
        s.commit()


def approve_withdrawal(store, actor: User, tc_id: int) -> TableCalibrationWithdrawal:
    """Approve the withdrawal asked for of the entry ``tc_id`` (reviewer, not the person who
    asked: one asks, another approves, as for an amendment): its immutable row
    (:class:`TableCalibrationWithdrawal`: reason, who asked and when, who approved and when)
    is written and the entry is in force on no day from then on; the calibrations made
    with it keep it and are listed as affected (:func:`withdrawal_affected`, in the
    ``withdraw`` audit event)."""
    require(actor, "reviewer")
    with store.writing() as s:
        tc, asked = _pending_withdrawal_or_refused(s, tc_id)
        if asked["asked_by_id"] == actor.id:
            raise GonioError("the person who asked for the withdrawal may not approve it "
                             "(another person approves a withdrawal)", key="role")
        w = TableCalibrationWithdrawal(table_calibration_id=tc.id, reason=asked["reason"],
                                       asked_by_id=asked["asked_by_id"],
                                       asked_at=asked["asked_at"], withdrawn_by_id=actor.id,
                                       withdrawn_at=utcnow())
        s.add(w)
        s.flush()
        affected = [c.id for c in withdrawal_affected(s, tc.id)]
        audit(s, actor, "withdraw", "table-calibration", tc.id, None,
              dict(state(w), affected=affected))
        for cal_id in affected:      # the flag, on each calibration's own trail too
            audit(s, actor, "table-calibration-withdrawn", "calibration", cal_id, None,
                  {"register_id": tc.id, "reason": asked["reason"]})
        s.commit()
        s.refresh(w)
        s.expunge(w)
    return w


def decline_withdrawal(store, actor: User, tc_id: int, reason: str = "") -> None:
    """Decline the withdrawal asked for of the entry ``tc_id`` (a reviewer, or the person
    who asked, taking it back); audited as ``decline-withdrawal``, the entry stays."""
    if not (actor is not None and actor.active and (actor.has("technician")
                                                   or actor.has("reviewer"))):
        raise GonioError("this needs the technician or reviewer role", key="role")
    reason = text(reason, "reason", max_len=MAX_TEXT, multiline=True)
    with store.writing() as s:
        tc, asked = _pending_withdrawal_or_refused(s, tc_id)
        if asked["asked_by_id"] != actor.id and not actor.has("reviewer"):
            raise GonioError("this needs the reviewer role (or the person who asked)",
                             key="role")
        audit(s, actor, "decline-withdrawal", "table-calibration", tc.id, None,
              {"reason": reason})
        s.commit()


def register_table_calibration_file(store, actor: User, path, *, table: str, valid_from=None,
                                    due_on=None, certificate: str = "") -> TableCalibration:
    """:func:`register_table_calibration` of the file at ``path`` (stored in the records under
    its SHA-256, its own name kept) for the table registered as the standard whose
    identifier is ``table`` (``gonio db register-table-calibration``)."""
    require(actor, "technician")
    path = Path(path)
    with store.session() as s:
        sid = s.scalar(select(Standard.id).where(Standard.identifier == text(table, "table")))
    if sid is None:
        raise GonioError(f"{table!r} is not a registered standard (register the rotary table "
                         "as a standard first)", key="--table")
    try:
        with path.open("rb") as f:
            sha, _ = store_file(store, f, limit_bytes=2**20)
    except OSError as exc:
        raise GonioError(f"cannot read the table calibration: {exc.strerror}",
                         file=path) from None
    return register_table_calibration(store, actor, standard_id=sid, sha256=sha,
                                      name=path.name, valid_from=valid_from, due_on=due_on,
                                      certificate=certificate)


def table_calibration_state(tc: TableCalibration, others: Iterable[TableCalibration],
                            day: _dt.date, withdrawn: dict | None = None) -> str:
    """Whether the register's table calibration ``tc`` may be used by a calibration dated
    ``day`` (``others``: the register's calibrations of the same table; ``withdrawn``: entry
    id → its withdrawal, :func:`withdrawals`): ``""`` in force — not withdrawn, valid from on
    or before ``day``, due on or after it, and no later calibration of that table not
    withdrawn valid from on or before ``day`` —, else why not, in words: ``"withdrawn …"``,
    ``"not yet valid …"``, ``"expired …"``, ``"superseded …"``. The newest valid is the one
    in force: a table calibration is replaced, not merely added to (ISO/IEC 17025 6.4.11,
    correction factors updated). A withdrawn entry is in force on no day and supersedes
    nothing: the one it had superseded is in force again on the days it was.

    >>> import datetime as dt
    >>> a = TableCalibration(id=1, certificate="TC-1", valid_from=dt.date(2026, 1, 1),
    ...                      due_on=dt.date(2027, 1, 1))
    >>> b = TableCalibration(id=2, certificate="TC-2", valid_from=dt.date(2026, 6, 1),
    ...                      due_on=dt.date(2027, 6, 1))
    >>> table_calibration_state(a, [a, b], dt.date(2026, 5, 31))
    ''
    >>> table_calibration_state(a, [a, b], dt.date(2026, 6, 1))
    'superseded by table calibration 2 (TC-2) valid from 2026-06-01'
    >>> table_calibration_state(b, [a, b], dt.date(2027, 6, 2))
    'expired: it was due on 2027-06-01'
    >>> w = TableCalibrationWithdrawal(withdrawn_at=dt.datetime(2026, 7, 1, 9, 30))
    >>> table_calibration_state(a, [a, b], dt.date(2026, 6, 1), {2: w})
    ''
    >>> table_calibration_state(b, [a, b], dt.date(2026, 6, 1), {2: w})
    'withdrawn on 2026-07-01 09:30 UTC'
    """
    withdrawn = withdrawn or {}
    if tc.id in withdrawn:
        return f"withdrawn on {withdrawn[tc.id].withdrawn_at:%Y-%m-%d %H:%M} UTC"
    others = [o for o in others if o.id not in withdrawn]
    if day < tc.valid_from:
        return f"not yet valid: valid from {tc.valid_from}"
    if day > tc.due_on:
        return f"expired: it was due on {tc.due_on}"
    newer = [o for o in others if o.id != tc.id and tc.valid_from < o.valid_from <= day]
    if newer:
        o = max(newer, key=lambda x: x.valid_from)
        return (f"superseded by table calibration {o.id}"
                + (f" ({o.certificate})" if o.certificate else "") + f" valid from {o.valid_from}")
    return ""


def _table_label(tc: TableCalibration, st: Standard | None) -> str:
    return (f"table calibration {tc.id}" + (f" ({tc.certificate})" if tc.certificate else "")
            + (f" of {st.identifier}" if st is not None else ""))


def table_calibration_for(s: Session, spec, standard_ids: Iterable[int], day: _dt.date,
                          upload_sha256: str | None = None,
                          register_id=None) -> tuple[str | None, TableCalibration | None]:
    """Which table calibration a calibration per ``spec`` dated ``day`` with the standards
    ``standard_ids`` uses: ``(sha256, register entry)``.

    * ``register_id`` (the user's pick): that entry of the register, which must be in force
      on ``day`` (:func:`table_calibration_state`: an expired, superseded or not yet valid one
      is refused with one line) and of a table among the calibration's standards; an upload
      beside it must be its file.
    * an upload only: where the register holds that file (of any table) its entry, which
      must be of a table among the calibration's standards and in force on ``day`` (the
      same checks: a registered file is never used as a bare upload); a file the register
      does not hold is refused with one line naming the register command (a table
      calibration that corrects a result is a registered entry in force: a one-byte edit of
      a registered file is another file).
    * neither: the register's entry in force on ``day`` of the ticked table; several ticked
      tables each with one are refused (pick one); a ticked table whose register holds
      calibrations none of which is in force on ``day`` is refused (register its current
      calibration); no calibration of a ticked table registered: ``(None, None)``.

    A specification that takes no table calibration (``"table_calibration"`` not in its
    ``calibrate_options``) uses none: ``(None, None)``, unless one was given (refused
    by :func:`table_calibration_of`)."""
    ids = sorted({int(i) for i in standard_ids})
    takes = "table_calibration" in spec.calibrate_options
    if register_id in (None, ""):
        register_id = None
    if register_id is None and not takes:
        return upload_sha256, None
    if register_id is not None and not takes:
        raise GonioError(f"{spec.key} takes no table calibration", key="table_calibration")
    if ids:     # a registration of these tables waits (PostgreSQL: FOR SHARE against its
        s.execute(select(Standard.id).where(Standard.id.in_(ids))   # FOR UPDATE)
                  .with_for_update(read=True))
    entries = s.scalars(select(TableCalibration).where(
        TableCalibration.standard_id.in_(ids)).order_by(TableCalibration.valid_from)).all() \
        if ids else []
    withdrawn = withdrawals(s)
    by_table: dict[int, list] = {}
    for e in entries:
        by_table.setdefault(e.standard_id, []).append(e)

    def checked(tc: TableCalibration) -> TableCalibration:
        st = s.get(Standard, tc.standard_id)
        if tc.standard_id not in ids:
            raise GonioError(f"{_table_label(tc, st)} is of a table the calibration does not "
                             "name among its standards: tick the table", key="table_calibration")
        why = table_calibration_state(tc, by_table.get(tc.standard_id, []), day, withdrawn)
        if why:
            raise GonioError(f"{_table_label(tc, st)} cannot be used on {day}: {why}",
                             key="table_calibration")
        if upload_sha256 is not None and upload_sha256 != tc.sha256:
            raise GonioError(f"the table calibration uploaded (SHA-256 {upload_sha256[:16]}…) "
                             f"is not {_table_label(tc, st)} (SHA-256 {tc.sha256[:16]}…): "
                             "give one of them", key="table_calibration")
        return tc

    if register_id is None and upload_sha256 is not None:
        # the upload's file looked up in the whole register: a registered file is used
        # only as its entry (its table ticked, in force on ``day``), never as a bare upload
        known = s.scalars(select(TableCalibration).where(
            TableCalibration.sha256 == upload_sha256).order_by(TableCalibration.id)).all()
        if known:       # a withdrawn entry's bytes registered again: that entry first
            known = sorted(known, key=lambda e: (e.id in withdrawn, e.id))
            ticked = [e for e in known if e.standard_id in ids]
            return upload_sha256, checked((ticked or known)[0])
    if register_id is not None:
        try:
            tc = s.get(TableCalibration, int(register_id))
        except (TypeError, ValueError):
            tc = None
        if tc is None:
            raise GonioError("no such table calibration in the register",
                             key="table_calibration")
        return tc.sha256, checked(tc)
    if upload_sha256 is not None:
        same = sorted((e for e in entries if e.sha256 == upload_sha256),
                      key=lambda e: (e.id in withdrawn, e.id))
        if same:
            return upload_sha256, checked(same[0])
        if entries:
            st = s.get(Standard, entries[0].standard_id)
            raise GonioError(f"the register holds the calibrations of the table "
                             f"{st.identifier}, and the file uploaded (SHA-256 "
                             f"{upload_sha256[:16]}…) is none of them: choose the register's "
                             "or register the new file first", key="table_calibration")
        raise GonioError(f"the table calibration uploaded (SHA-256 {upload_sha256[:16]}…) is "
                         "not in the register: a table calibration that corrects a result "
                         "must be a registered entry in force (register it with `gonio db "
                         "register-table-calibration FILE --table IDENT --valid-from D`, tick "
                         "its table, and choose it)", key="table_calibration")
    in_force = []
    for sid, group in by_table.items():
        now = [e for e in group if not table_calibration_state(e, group, day, withdrawn)]
        if not now:
            st = s.get(Standard, sid)
            newest = group[-1]
            raise GonioError(f"no calibration of the table {st.identifier} in the register is "
                             f"in force on {day} (the newest, {_table_label(newest, None)}: "
                             f"{table_calibration_state(newest, group, day, withdrawn)}): "
                             "register its current calibration", key="table_calibration")
        in_force.extend(now)
    if len(in_force) > 1:
        raise GonioError("the register holds a calibration in force of each of the tables "
                         + ", ".join(s.get(Standard, e.standard_id).identifier for e in in_force)
                         + ": choose the one used", key="table_calibration")
    if in_force:
        return in_force[0].sha256, in_force[0]
    return None, None


def table_calibrations(store, day: _dt.date | None = None) -> list[dict]:
    """The laboratory's register of table calibrations, newest first per table: each
    ``{"entry": TableCalibration (with its standard and who registered it), "state": ""
    in force on ``day`` (today) or why not (:func:`table_calibration_state`), "used": how
    many calibrations used it, "withdrawal": its :class:`TableCalibrationWithdrawal` or None,
    "affected": the ids of the calibrations made with a withdrawn entry
    (:func:`withdrawal_affected`), "asked": a withdrawal asked for and not yet decided
    (:func:`pending_withdrawal`) or None}``; today is the laboratory's date (:func:`records_today`)."""
    from sqlalchemy.orm import selectinload

    day = day or records_today(store)
    with store.session() as s:
        rows = s.scalars(select(TableCalibration).options(
            selectinload(TableCalibration.standard), selectinload(TableCalibration.registered_by))
            .order_by(TableCalibration.standard_id, TableCalibration.valid_from.desc())).all()
        used = dict(s.execute(select(Calibration.table_calibration_id, func.count())
                              .where(Calibration.table_calibration_id.is_not(None))
                              .group_by(Calibration.table_calibration_id)).all())
        withdrawn = withdrawals(s)
        affected = {i: [c.id for c in withdrawal_affected(s, i)] for i in withdrawn}
        asked = {r.id: pending_withdrawal(s, r.id) for r in rows if r.id not in withdrawn}
    groups: dict[int, list] = {}
    for r in rows:
        groups.setdefault(r.standard_id, []).append(r)
    return [{"entry": r,
             "state": table_calibration_state(r, groups[r.standard_id], day, withdrawn),
             "used": used.get(r.id, 0), "withdrawal": withdrawn.get(r.id),
             "affected": affected.get(r.id, []), "asked": asked.get(r.id)} for r in rows]


def create_calibration(store, actor: User, *, instrument_id: int, readings_sha256: str,
                       readings_name: str = "", spec_key: str | None = None,
                       protocol: str | None = None, protocol_sha256: str | None = None,
                       lab_sha256: str | None = None, lab_name: str = "",
                       standard_ids: Iterable[int] = (), temperature_c=None,
                       humidity_pct=None, performed_on=None, received_on=None,
                       place: str = "", location: str | None = None,
                       reuse_note: dict | None = None,
                       check_reuse: bool = True,
                       table_calibration_sha256: str | None = None,
                       table_calibration_name: str = "",
                       table_calibration_id=None) -> Calibration:
    """A new calibration, queued for the worker (technician), after the submission checks
    of its fields (:func:`submission_fields`: plausible dates, at least one standard, the
    environment); standards past their due date on the day of the calibration are refused
    (ISO/IEC 17025 6.4.7). ``lab_sha256``: a stored laboratory file whose decision rule
    and limits decide this calibration, validated here (:func:`lab_file`) before anything
    is queued. The checks of the readings against the instrument and of readings used
    before are :func:`gonio.records.submission.submit_calibration`'s, which the web form
    calls; readings used by another calibration that stands are refused here on every path
    (:func:`check_readings_unused`) unless ``reuse_note`` (the form's record of readings used
    again: why, used by which calibrations) gives the reason, audited with the creation.
    ``check_reuse`` False: only for a bench's request, which stands in for readings still
    to be taken (they are checked when taken, :func:`gonio.records.bench.store_acquisition`).
    ``table_calibration_sha256``: a stored table calibration file (the rotary table's own
    calibration, for a specification that takes one), kept as the calibration's file
    :data:`TABLE_CALIBRATION` and used by its run (:func:`table_calibration_of` checks it
    against the laboratory file's ``[table_calibration]``). ``table_calibration_id``: the
    register's table calibration to use; without it the one in force on the calibration's
    date of a table among its standards is used (:func:`table_calibration_for`), and the
    calibration records which (``table_calibration_id``)."""
    from gonio.specs import get

    require(actor, "technician")
    day, received, ids, temp, hum = submission_fields(performed_on, received_on,
                                                      standard_ids, temperature_c,
                                                      humidity_pct, records_today(store))
    with store.writing() as s:
        inst = s.get(Instrument, int(instrument_id))
        if inst is None:
            raise GonioError("no such instrument", key="instrument")
        if inst.retired_on is not None:
            raise GonioError(f"the instrument was retired on {inst.retired_on}",
                             key="instrument")
        key = text(spec_key, "spec", max_len=64) or inst.spec_key
        get(key)
        for sha in (readings_sha256, protocol_sha256, lab_sha256, table_calibration_sha256):
            if sha is not None and s.get(Blob, sha) is None:
                raise GonioError("no such stored file", key="sha256")
        lab_d = lab_file(store, lab_sha256, lab_name, key) if lab_sha256 is not None else {}
        table_calibration_sha256, entry = table_calibration_for(
            s, get(key), ids, day, table_calibration_sha256, table_calibration_id)
        table_calibration_of(get(key), lab_d, lab_name, table_calibration_sha256, day)
        if check_reuse:
            check_readings_unused(s, readings_sha256,
                                  reason=(reuse_note or {}).get("reason", ""))
        cal = Calibration(instrument_id=inst.id, spec_key=key,
                          protocol=text(protocol, "protocol", max_len=64),
                          protocol_sha256=protocol_sha256, readings_sha256=readings_sha256,
                          readings_name=text(readings_name, "readings file name", max_len=255),
                          lab_sha256=lab_sha256,
                          lab_name=text(lab_name, "laboratory file name", max_len=255)
                          if lab_sha256 else "",
                          **environment_columns(temp, hum), environment_from="",
                          place=text(place, "place"), location=location_value(location),
                          performed_on=day,
                          received_on=received, status="queued", progress="waiting for a worker",
                          created_by_id=actor.id,
                          table_calibration_id=entry.id if entry is not None else None)
        s.add(cal)
        s.flush()
        use_standards(s, cal, ids)
        audit(s, actor, "create", "calibration", cal.id, None, state(cal))
        if table_calibration_sha256 is not None:     # an input kept and sealed with the run
            s.add(CalibrationFile(calibration_id=cal.id, name=TABLE_CALIBRATION,
                                  sha256=table_calibration_sha256))
            audit(s, actor, "table-calibration", "calibration", cal.id, None,
                  {"sha256": table_calibration_sha256,
                   "name": entry.name if entry is not None else
                   file_name(table_calibration_name, "table calibration file name")}
                  | ({"register_id": entry.id, "valid_from": str(entry.valid_from),
                      "due_on": str(entry.due_on),
                      "picked": "chosen" if table_calibration_id not in (None, "")
                      else f"in force on {day}"} if entry is not None else {}))
        if reuse_note:
            audit(s, actor, "reuse-readings", "calibration", cal.id, None, reuse_note)
        s.commit()
    return cal


def location_value(value) -> str:
    """Where a calibration was performed, as the DCC's category (``LOCATIONS``; empty or
    None: the laboratory); anything else is a GonioError listing them."""
    from gonio.formats.lab import LOCATIONS

    value = (value or "").strip() or "laboratory"
    if value not in LOCATIONS:
        raise GonioError(f"location: {value[:40]!r} is not one of {', '.join(LOCATIONS)}",
                         key="location")
    return value


def gyro_type_value(value) -> str:
    """An instrument's optical-gyro type: ``rlg``, ``fog`` (case ignored) or ``""`` (not
    stated; None or blank); anything else is a GonioError listing them.

    >>> gyro_type_value(" RLG"), gyro_type_value(None)
    ('rlg', '')
    """
    from gonio.formats.metadata import GYRO_TYPES

    value = text(value, "gyro_type").lower()
    if value and value not in GYRO_TYPES:
        raise GonioError(f"gyro_type: {value[:40]!r} is not one of {', '.join(GYRO_TYPES)} "
                         "(or empty: not stated)", key="gyro_type")
    return value


def unusable_standard(st: Standard, day: _dt.date) -> str:
    """Why the registered standard ``st`` cannot be used on a calibration dated ``day``
    (retired on or before it, or past its due date on it: ISO/IEC 17025 6.4.7), or ''."""
    if st.retired_on is not None and st.retired_on <= day:
        return f"standard {st.identifier} was retired on {st.retired_on} (the calibration " \
               f"date is {day})"
    if is_past_due(st.due_on, day):
        why = getattr(st, "out_of_service", "")
        return f"standard {st.identifier} was due on {st.due_on} (before the calibration " \
               f"date {day}): calibrate it first" + (
                   f" (registered out of service: {why})" if why else "")
    return ""


def use_standards(s: Session, cal: Calibration, ids: Iterable[int]) -> list[str]:
    """The standards ``ids`` as the ones used by ``cal`` (those it had are replaced); each
    registered, not retired on or before the calibration date and not past its due date on
    it (ISO/IEC 17025 6.4.7); returns their identifiers."""
    day = cal.performed_on
    s.query(CalibrationStandard).filter(CalibrationStandard.calibration_id == cal.id).delete()
    names = []
    for sid in sorted(set(int(i) for i in ids)):
        st = s.get(Standard, sid)
        if st is None:
            raise GonioError("no such standard", key="standards")
        why = unusable_standard(st, day)
        if why:
            raise GonioError(why, key="standards")
        s.add(CalibrationStandard(calibration_id=cal.id, standard_id=sid,
                                  due_on_at_use=st.due_on))
        names.append(st.identifier)
    return names


#: The states in which the standards and the environment of a calibration may still be
#: attached: not yet approved (a reviewed one goes back to its review), or an amendment not
#: yet approved.
#: Where an entered environment was written (``calibrations.environment_from``; "readings":
#: taken from the readings' metadata): on the page or the command line, or in the laboratory
#: file the calibration was computed with.
ENTERED_IN = ("", "lab file")
#: The state of a calibration whose draft certificate is being rendered again from its
#: stored result with what was attached (a worker claims it; then computed again).
DRAFTING = "drafting"
ATTACHABLE = ("queued", "computed", "failed", "reviewed", DRAFTING, "amending")
#: The states whose draft certificate is rendered again after an attach (:data:`DRAFTING`).
REDRAFTED = ("computed", "reviewed")


def attach_conditions(store, actor: User, cal_id: int, *, standard_ids=None,
                      temperature_c=None, humidity_pct=None,
                      environment_from_readings: bool = False,
                      entered_in: str = "") -> Calibration:
    """Attach the reference standards used and the environment to a calibration that is not
    yet approved (:data:`ATTACHABLE`; a reviewed one goes back to its review), or to an
    amendment not yet approved, e.g. one put in with ``gonio db import`` or ``gonio
    calibrate --record``, which carries neither; technician or reviewer, audited
    (``attach``, the record and its standards before and after).

    ``standard_ids``: the registered standards used (they replace those recorded), each
    valid on the calibration date (:func:`use_standards`); None or none leaves them. The
    environment: ``temperature_c`` and ``humidity_pct`` as entered (compared with what the
    readings state, as at upload), or ``environment_from_readings``: both taken from the
    readings file's metadata (``# temperature_c`` or ``# room_temperature_c``, and
    ``# humidity_pct``), stated so on the page and the certificate; neither leaves it.
    ``entered_in``: where the entered values were written, recorded with them
    (:data:`ENTERED_IN`: '' on the page or the command line, ``"lab file"`` the laboratory
    file's ``[environment]``).
    Review and approval require both (:func:`missing_for_review`).

    A calibration with a stored result (computed, or reviewed: it goes back to its review)
    becomes :data:`DRAFTING`: a worker renders its draft certificate again from the stored,
    sealed result with the details recorded now (:func:`gonio.records.worker.execute`),
    nothing computed again; ``gonio db attach`` renders it at once. A failed issue (approved,
    its number reserved) is attached nothing: what was approved is issued."""
    if not (actor is not None and actor.active and (actor.has("technician")
                                                   or actor.has("reviewer"))):
        raise GonioError("this needs the technician or reviewer role", key="role")
    entered = [v for v in (temperature_c, humidity_pct)
               if v is not None and not (isinstance(v, str) and not v.strip())]
    if entered_in not in ENTERED_IN:
        raise GonioError(f"unknown source of the environment {entered_in!r}", key="attach")
    if environment_from_readings and entered:
        raise GonioError("enter the environment or take it from the readings, not both",
                         key="environment")
    temp = condition_value(temperature_c, "temperature_c", -50, 100)
    hum = condition_value(humidity_pct, "humidity_pct", 0, 100)
    if entered and (temp is None or hum is None):
        raise GonioError("enter both the room temperature (°C) and the relative humidity "
                         "(%)", key="environment")
    if standard_ids is not None:
        standard_ids = list(standard_ids) or None      # none ticked: those named stay
    cal = calibration(store, cal_id)
    env = _environment_of(store, cal, temp, hum, environment_from_readings, entered_in)
    if standard_ids is None and env is None:
        raise GonioError("nothing to attach: name the standard(s) used or the environment",
                         key="attach")
    with store.writing() as s:
        cal = s.get(Calibration, int(cal_id), with_for_update=True)
        if cal.status not in ATTACHABLE or cal.pending_number:
            raise GonioError(f"cannot attach standards or the environment to a calibration "
                             f"that is {cal.status} (only before its approval, or to an "
                             "amendment before its approval)", key="status")
        before = state(cal)
        before["standards"] = standard_names(s, cal.id)
        if standard_ids is not None:
            use_standards(s, cal, standard_ids)
        if env is not None:
            for key, value in environment_columns(env[0], env[1]).items():
                setattr(cal, key, value)
            cal.environment_from = env[2]
        if cal.status == "reviewed":     # what was reviewed changed: reviewed again
            cal.status, cal.reviewed_by_id, cal.reviewed_at = "computed", None, None
            cal.reviewed_seal, cal.review_comment = "", ""
        if cal.status in REDRAFTED and cal.results_sha256:   # its draft shows what is attached
            cal.status, cal.progress = DRAFTING, "waiting for a worker to render the draft " \
                                                 "certificate with what was attached"
            cal.worker_pid, cal.worker_host, cal.error = None, "", ""
        s.flush()
        after = dict(state(cal), standards=standard_names(s, cal.id))
        audit(s, actor, "attach", "calibration", cal.id, before, after)
        s.commit()
    return calibration(store, cal_id)


def attach_by_identifiers(store, actor: User, cal_id: int, *,
                          standard_identifiers: Iterable[str] | None = None,
                          **environment) -> Calibration:
    """:func:`attach_conditions` with the standards named by their identifiers (the command
    line's ``--standard``); an identifier not registered is a GonioError naming it."""
    ids = None
    if standard_identifiers is not None:
        with store.session() as s:
            ids = []
            for ident in standard_identifiers:
                sid = s.scalar(select(Standard.id).where(Standard.identifier == str(ident)))
                if sid is None:
                    raise GonioError(f"no registered standard {str(ident)[:80]!r}",
                                     key="--standard")
                ids.append(sid)
    return attach_conditions(store, actor, cal_id, standard_ids=ids, **environment)


def standard_names(s: Session, cal_id: int) -> list[str]:
    """The identifiers of the standards a calibration names, sorted."""
    return list(s.scalars(select(Standard.identifier).join(
        CalibrationStandard, CalibrationStandard.standard_id == Standard.id)
        .where(CalibrationStandard.calibration_id == cal_id).order_by(Standard.identifier)))


def _environment_of(store, cal: Calibration, temp, hum, from_readings: bool,
                    entered_in: str = ""):
    """(temperature, humidity, environment_from) to record, or None: taken from the readings'
    metadata, or as entered; either compared with what the readings state and what they
    measured (the specification's ``measured_conditions``), as ``gonio calibrate`` compares."""
    from gonio.formats.provenance import readings_metadata
    from gonio.pipeline.identity import contradictions
    from gonio.records.compute import readings_file
    from gonio.specs import get

    if not from_readings and temp is None:
        return None
    spec = get(cal.spec_key)
    room_keys = spec.room_temperature_keys   # IEC's room_temperature_c is T_BASE
    src = blobs.blob_path(store.blob_root, cal.readings_sha256)
    if not src.is_file():
        raise GonioError("the calibration's readings are not in the store", key="readings")
    # a bench calibration's readings not acquired yet (its request): no metadata lines
    with readings_file(src) as path:
        md = readings_metadata(path)
        # what the readings measured (a logged room temperature) is compared as the
        # calibration pipeline compares it, whatever the metadata line says or where it is gone
        measured = spec.measured_conditions(path) if (
            spec.measured_conditions is not None and md) else None
    if from_readings:
        got = []
        for keys, what, lo, hi in ((room_keys, "temperature", -50, 100),
                                   (("humidity_pct",), "humidity", 0, 100)):
            v = next((md[k] for k in keys if str(md.get(k, "")).strip()), None)
            if v is None:
                raise GonioError(f"the readings state no {what} (# {keys[0]}): enter the "
                                 "environment", key="environment")
            got.append(condition_value(str(v), f"readings' # {keys[0]}", lo, hi))
        temp, hum = got
    found = contradictions(md, {"environment": {"temperature_c": temp, "humidity_pct": hum}},
                           measured, room_keys)
    if found:
        c = found[0]
        said = "their metadata say" if from_readings else "entered"
        raise GonioError(f"{c['what']}: the readings say {c['readings']} "
                         f"({c.get('where') or '# ' + c['key']}), {said} {c['lab']}: "
                         "enter the conditions of these readings", key="environment")
    return temp, hum, (entered_in if not from_readings else "readings")


def missing_for_review(s: Session, cal: Calibration) -> list[str]:
    """What a calibration lacks to be reviewed or approved (empty: nothing): a registered
    standard valid on its date (not retired on or before it, not past its due date on it;
    ISO/IEC 17025 6.4.7, 6.5) and the environment (7.8.4.1 a), each as the words of the
    one line that refuses it."""
    day = cal.performed_on
    rows = s.execute(select(Standard, CalibrationStandard.due_on_at_use).join(
        CalibrationStandard, CalibrationStandard.standard_id == Standard.id)
        .where(CalibrationStandard.calibration_id == cal.id)).all()
    valid = [st for st, due in rows if due >= day
             and (st.retired_on is None or st.retired_on > day)]
    out = []
    if not valid:
        out.append(f"registered standard valid on {day}" + (
            f" ({', '.join(st.identifier for st, _ in rows)} not)" if rows else ""))
    if cal.temperature_c is None or cal.humidity_pct is None:
        out.append("environment (temperature, humidity)")
    return out


def plausible_dates(performed: _dt.date, received: _dt.date | None, today: _dt.date) -> None:
    """Dates a certificate can carry: the calibration not after ``today``, the laboratory's
    date (:func:`~gonio.records.models.records_today`: its certificate is issued on or after
    it), and the item received on or before it; else a GonioError.

    >>> plausible_dates(_dt.date(9999, 12, 31), None, _dt.date(2026, 1, 1))
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key performed_on: 9999-12-31 is in the future (today 2026-01-01)
    """
    if performed > today:
        raise GonioError(f"{performed} is in the future (today {today})", key="performed_on")
    if received is not None and received > performed:
        raise GonioError(f"the item was received on {received}, after the calibration "
                         f"date {performed}", key="received_on")


def _check(s: Session, actor: User, cal_id: int, action: str,
           allowed: tuple[str, ...]) -> Calibration:
    # the row locked until commit (SELECT … FOR UPDATE on PostgreSQL; SQLite's writing
    # session holds the database's write lock already): two people acting at once on one
    # calibration are serialised, and the second sees the first one's state
    cal = s.get(Calibration, int(cal_id), with_for_update=True)
    if cal is None:
        raise GonioError("no such calibration", key="calibration")
    if cal.status not in allowed:
        raise GonioError(f"cannot {action} a calibration that is {cal.status}", key="status")
    if action in ("review", "approve", "amend"):
        check_duties(s, cal, actor, action)
    if action in ("review", "approve"):
        _complete(s, cal, action)
        _not_withdrawn(s, cal, action)
    return cal


def _not_withdrawn(s: Session, cal: Calibration, action: str) -> None:
    """Refuse to ``action`` (review, approve — a first issue or an amendment —, issue) a
    calibration made with a register entry that was withdrawn: its correction is one the
    laboratory took back, so the calibration is computed again with an entry in force (a new
    calibration, or the run imported again); one issued before stays issued and is listed as
    affected (docs/records.md, the register: withdrawn)."""
    if cal.table_calibration_id is None:
        return
    gone = withdrawals(s, [cal.table_calibration_id]).get(cal.table_calibration_id)
    if gone is None:
        return
    tc = s.get(TableCalibration, cal.table_calibration_id)
    raise GonioError(f"cannot {action} calibration {cal.id}: it was made with table "
                     f"calibration {tc.id} ({tc.certificate or tc.name}), withdrawn on "
                     f"{gone.withdrawn_at:%Y-%m-%d %H:%M} UTC (reason: "
                     f"{' '.join(gone.reason.split())}); make a new calibration (or import "
                     "the run again) with a table calibration in force", key="table_calibration")


def _complete(s: Session, cal: Calibration, action: str) -> None:
    """The submission checks at review and approval, on every path: a GonioError naming
    what is missing (:func:`missing_for_review`) and how to attach it."""
    missing = missing_for_review(s, cal)
    if missing:
        raise GonioError(f"cannot {action} calibration {cal.id}: it names no "
                         + " and no ".join(missing) + "; attach them first (the calibration "
                         "page, or gonio db attach)", key="submission")


def min_people(s: Session) -> int:
    """The laboratory's minimum number of distinct people on a certificate (setting
    ``min_people``: 3, or 2 for a small laboratory)."""
    row = s.get(Setting, "min_people")
    return int(row.value) if row is not None and row.value in MIN_PEOPLE else 3


def check_duties(s: Session, cal: Calibration, actor: User, action: str) -> None:
    """ISO/IEC 17025 6.2 / 7.8.1.1 / 7.8.8 on every path: the creator of a calibration never
    reviews it, approves its first issue or asks for its amendment (a calibration whose
    creator is not recorded cannot be reviewed); with ``min_people`` 3 the approver is not
    the reviewer either. An amendment (a change to an issued certificate) is approved by a
    person who neither asked for it nor changed anything of it (:func:`amendment_changers`:
    one changes, another approves), whatever ``min_people``; with ``min_people`` 2 that
    person may be the calibration's creator (the two-person laboratory: the reviewer asks
    and changes, the creator approves), with 3 never. The same for a first issue: who
    reviewed it and last changed its details (:func:`last_changer`) does not approve it.
    The person the readings name as their operator (:func:`readings_operator`, matched by
    user name or any full name they hold or held, :func:`names_held`, both sides folded by
    :func:`_printed_name`: case, Unicode compatibility forms and spacing) counts as the
    creator."""
    if cal.created_by_id is None:
        raise GonioError(f"cannot {action} a calibration whose creator is not recorded "
                         "(import it again with --user)", key="role")
    check_trail(s, cal, action)          # the row's creator and seals are the trail's
    amending = action == "approve" and cal.status == "amending"
    if amending:
        if cal.amend_requested_by_id == actor.id:
            raise GonioError("the person who asked for the amendment may not approve it "
                             "(another person approves an amendment)", key="role")
        if actor.id in amendment_changers(s, cal.id):
            raise GonioError("the person who changed the calibration during its amendment "
                             "may not approve the amendment (ISO/IEC 17025 7.8.8: one "
                             "changes, another approves)", key="role")
    if cal.created_by_id == actor.id and not (amending and min_people(s) == 2):
        raise GonioError(f"the person who created a calibration may not {action} it "
                         "(ISO/IEC 17025 7.8.1.1: a second person)", key="role")
    operator = readings_operator(s, cal)
    if operator and not (amending and min_people(s) == 2) \
            and _printed_name(operator) in names_held(s, actor):
        raise GonioError(f"the readings name {actor.username!r} ({operator!r}) as their "
                         f"operator: the person who measured may not {action} the "
                         "calibration (ISO/IEC 17025 7.8.1.1: a second person)", key="role")
    if action == "approve" and not amending and min_people(s) >= 3 \
            and cal.reviewed_by_id == actor.id:
        raise GonioError("the person who reviewed the calibration may not approve it (the "
                         "laboratory requires three different people)", key="role")
    if action == "approve" and not amending and cal.reviewed_by_id == actor.id \
            and last_changer(s, cal.id) == actor.id:
        raise GonioError("the person who last changed the calibration's details (standards, "
                         "environment, what its certificate states) and reviewed it may not "
                         "approve it too (one changes, another checks): another person "
                         "reviews or approves", key="role")


def _latest_event(s: Session, entity: str, entity_id, actions: tuple[str, ...],
                  first: bool = False) -> dict | None:
    """The latest (``first``: the earliest) audit event ``actions`` on a record, as
    ``{"user_id", "event_id", **after}`` (its recorded state after), None where the trail has
    none."""
    order = AuditEvent.id if first else AuditEvent.id.desc()
    ev = s.scalar(select(AuditEvent).where(
        AuditEvent.entity == entity, AuditEvent.entity_id == str(entity_id),
        AuditEvent.action.in_(actions)).order_by(order).limit(1))
    if ev is None:
        return None
    try:
        after = json.loads(ev.after_json or "{}")
    except ValueError:
        after = {}
    return {**(after if isinstance(after, dict) else {}), "user_id": ev.user_id,
            "event_id": ev.id}


def trail_problems(s: Session, cal: Calibration) -> list[str]:
    """What a calibration's row says against its own audit trail (one line each). Every state
    implies its events, each naming the user the row names: a calibration has its creation
    event (``create`` or ``import``, naming ``created_by_id``); a reviewed one
    (``reviewed_by_id`` set) its ``review`` by that reviewer, with the ``reviewed_seal`` the
    row holds; an approved one (``approved_by_id`` set) its ``approve`` by that approver,
    with the ``approved_seal``; each issued certificate its ``issue`` event recording that
    number and approver (:func:`issue_problems`); an amendment waiting for its issue the
    standards its approval fixed (:func:`amendment_problems`). The duties and the issue
    trust neither the columns nor a trail with events missing: a row rewritten in the
    database (a creator changed so that they may approve, a seal recomputed over a forged
    result) or a trail with events deleted (its append-only trigger dropped) is refused on
    every path and listed by ``gonio db verify`` (the trail is appended to and never
    rewritten by gonio, and every state it records is entered with its event)."""
    out = []
    made = _latest_event(s, "calibration", cal.id, ("create", "import"), first=True)
    if made is None:
        out.append("its audit trail has no creation event (create or import): events were "
                   "removed outside gonio")
    else:
        creator = made.get("created_by_id", made["user_id"])
        if creator is not None and creator != cal.created_by_id:
            out.append("its recorded creator is not the one its audit trail's creation event "
                       "names: the row was changed outside gonio")
    for action, noun, person, column in (
            ("review", "reviewer", "reviewed_by_id", "reviewed_seal"),
            ("approve", "approver", "approved_by_id", "approved_seal")):
        who, signed = getattr(cal, person), getattr(cal, column) or ""
        if who is None and not signed:
            continue
        ev = _latest_event(s, "calibration", cal.id, (action,))
        if ev is None:
            out.append(f"its audit trail has no {action} event, and the row names its "
                       f"{noun}: events were removed outside gonio")
            continue
        if who is not None and ev["user_id"] != who:
            out.append(f"its {noun} is not the user its audit trail's {action} event "
                       "names: the row was changed outside gonio")
        if signed and ev.get(column) not in (None, signed):
            out.append(f"its {column.replace('_', ' ')} is not the one its audit trail's "
                       f"{action} event recorded: the row was changed outside gonio")
    return out + issue_problems(s, cal) + amendment_problems(s, cal)


def issue_problems(s: Session, cal: Calibration) -> list[str]:
    """Each certificate of ``cal`` against its ``issue`` audit event (one line each): the
    event is there and records the certificate's number and approver. A certificate is
    entered only with its issue event (:func:`store_issue`), so one without it had its
    trail removed outside gonio."""
    out = []
    for cert in s.scalars(select(Certificate).where(Certificate.calibration_id == cal.id)
                          .order_by(Certificate.id)):
        ev = _latest_event(s, "certificate", cert.id, ("issue",))
        if ev is None:
            out.append(f"certificate {cert.number}: its audit trail has no issue event: "
                       "events were removed outside gonio")
            continue
        kept = ev.get("certificate") if isinstance(ev.get("certificate"), dict) else {}
        if (kept.get("number"), kept.get("issued_by_id")) != (cert.number, cert.issued_by_id):
            out.append(f"certificate {cert.number}: its number or approver is not the one its "
                       "audit trail's issue event recorded: the row was changed outside gonio")
    return out


def approved_statement(s: Session, cal: Calibration) -> list | None:
    """The standards an amendment's approval fixed (its ``approve`` audit event's
    ``stated_standards``, :func:`approve`): what its certificate states. None where the
    latest approval is not one of the latest amendment asked for, or it fixed none
    (approved before approvals kept it: the statement is then made at the issue,
    :func:`amended_standards`)."""
    asked = _event_id(s, "amend", "calibration", cal.id)
    ev = _latest_event(s, "calibration", cal.id, ("approve",))
    if asked is None or ev is None or ev["event_id"] < asked:
        return None
    got = ev.get("stated_standards")
    return got if isinstance(got, list) else None


def amendment_problems(s: Session, cal: Calibration) -> list[str]:
    """An amendment approved and waiting for its issue (a reserved number, a certificate it
    replaces) against what its approval fixed (:func:`approved_statement`), one line: the
    standards attached now are the ones it states. Attaching is refused once approved, so
    another set was written around the records; the issue refuses it rather than print
    what nobody approved. The register entries' own fields: :func:`register_problems`."""
    if not (cal.pending_number and cal.pending_replaces_id):
        return []
    kept = approved_statement(s, cal)
    if kept is None:
        return []
    fixed = sorted(str(e.get("identifier")) for e in kept if isinstance(e, dict))
    now = sorted(standard_names(s, cal.id))
    if fixed == now:
        return []
    return [f"standards: {fixed} when its amendment was approved, now {now}: changed outside "
            "gonio"]


def register_problems(s: Session, entity: str, ids: Iterable[int] | None = None) -> list[str]:
    """Each register entry of ``entity`` (``customer``, ``instrument`` or ``standard``; those
    ``ids``, None: every one) against its audit trail, one line each: the entry has its
    creation event, and the fields a certificate states of it and its dates
    (:data:`REGISTER_TRAIL`) are the ones its latest ``create`` or ``update`` event
    recorded. Every way gonio writes these rows — registering (:func:`add_customer`,
    :func:`register_instrument`, :func:`add_standard`, the import's registration of a new
    instrument and customer), editing, retiring and bringing back (:func:`_update`) — enters
    the row's state with that event, so a difference is an entry changed in the database,
    which no certificate may state (an amendment states its customer and instrument as the
    register holds them at its issue). A field an event did not record (a column added
    since) is not compared."""
    model, label, fields = REGISTER_TRAIL[entity]
    q = select(model).order_by(model.id)
    if ids is not None:
        q = q.where(model.id.in_([int(i) for i in ids]))
    out = []
    for obj in s.scalars(q):
        name = f"{entity} {getattr(obj, label)}"
        ev = _latest_event(s, entity, obj.id, ("create", "update"))
        if ev is None:
            out.append(f"{name}: its audit trail has no creation event: events were removed "
                       "outside gonio")
            continue
        row = state(obj)
        for k in fields:
            if k in ev and ev[k] != row.get(k):
                out.append(f"{name}: its {k} {row.get(k)!r} is not the {ev[k]!r} its audit "
                           "trail's latest event recorded: the row was changed outside gonio")
    return out


def stated_register_problems(s: Session, cal: Calibration) -> list[str]:
    """:func:`register_problems` of the entries a certificate of ``cal`` states: its
    instrument, that instrument's customer and the standards attached to it."""
    inst = s.get(Instrument, cal.instrument_id)
    return (register_problems(s, "customer", [inst.customer_id] if inst is not None else [])
            + register_problems(s, "instrument", [cal.instrument_id])
            + register_problems(s, "standard", s.scalars(
                select(CalibrationStandard.standard_id).where(
                    CalibrationStandard.calibration_id == cal.id)).all()))


def check_trail(s: Session, cal: Calibration, action: str) -> None:
    """Refuse ``action`` on a calibration whose row contradicts its audit trail
    (:func:`trail_problems`) or names a customer, instrument or standard whose register
    entry contradicts its own (:func:`stated_register_problems`: the certificate would
    state it), naming it and what no longer matches."""
    found = trail_problems(s, cal) + stated_register_problems(s, cal)
    if found:
        more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
        raise GonioError(f"calibration {cal.id}: {found[0]}{more}: nothing to {action} "
                         "(gonio db verify lists it; restore the records from a backup)",
                         key=f"calibration {cal.id}")


def names_held(s: Session, u: User) -> set[str]:
    """Every name ``u`` is or was known by, as :func:`_printed_name` folds it: the user name,
    the full name now and each full name the audit trail's user events recorded for them
    (a renamed person is still the operator their readings name).

    A name given up stays theirs here, so a later user given the same name is matched too:
    the check errs towards a second person."""
    names = {_printed_name(u.username), _printed_name(_name(u))}
    for ev in s.scalars(select(AuditEvent).where(AuditEvent.entity == "user",
                                                 AuditEvent.entity_id == str(u.id))):
        for blob in (ev.before_json, ev.after_json):
            try:
                full = (json.loads(blob or "{}") or {}).get("full_name")
            except (ValueError, AttributeError):
                continue
            if isinstance(full, str) and full.strip():
                names.add(_printed_name(full))
    return names


def readings_operator(s: Session, cal: Calibration) -> str:
    """Who measured a calibration's readings, as their ``# operator:`` line (or a stream's
    metadata) names them; "" where they name nobody or the file cannot be read (no store
    known: the session's ``info["blob_root"]``). :func:`check_duties` treats that person as
    the calibration's creator: they neither review nor approve it. The name is returned as
    written, spacing collapsed (for the message); it is compared folded
    (:func:`_printed_name`), never as written."""
    from gonio.formats.provenance import readings_metadata
    from gonio.records.compute import readings_file

    root = s.info.get("blob_root")
    if root is None or not cal.readings_sha256:
        return ""
    src = blobs.blob_path(root, cal.readings_sha256)
    if not src.is_file():
        return ""
    try:
        with readings_file(src) as path:
            md = readings_metadata(path)
    except (GonioError, OSError, ValueError):
        return ""
    md = {str(k).strip().casefold(): v for k, v in md.items()}
    return " ".join(str(md.get("operator") or "").split())


def last_changer(s: Session, cal_id: int) -> int | None:
    """The user of a calibration's latest ``attach`` audit event (its standards, environment
    or the details its certificate states changed: :func:`attach_conditions`,
    :func:`_stated_change`), None where nobody changed them."""
    return s.scalar(select(AuditEvent.user_id).where(
        AuditEvent.action == "attach", AuditEvent.entity == "calibration",
        AuditEvent.entity_id == str(int(cal_id))).order_by(AuditEvent.id.desc()).limit(1))


def amendment_changers(s: Session, cal_id: int) -> set[int]:
    """The users who changed a calibration (its ``attach`` audit events: standards,
    environment) since its latest amendment was asked for (its latest ``amend`` event), and
    those who changed one of its standards' details since (an ``update`` of the standard),
    or corrected one since the certificate it replaces was issued (a correction reaches the
    amendment, :func:`amended_standards`)."""
    asked = _event_id(s, "amend", "calibration", cal_id)
    if asked is None:
        return set()
    used = [str(i) for i in s.scalars(select(CalibrationStandard.standard_id).where(
        CalibrationStandard.calibration_id == int(cal_id)))]
    changed = set(s.scalars(select(AuditEvent.user_id).where(
        AuditEvent.action == "attach", AuditEvent.entity == "calibration",
        AuditEvent.entity_id == str(int(cal_id)), AuditEvent.id > asked,
        AuditEvent.user_id.is_not(None))))
    if used:
        changed |= set(s.scalars(select(AuditEvent.user_id).where(
            AuditEvent.action == "update", AuditEvent.entity == "standard",
            AuditEvent.entity_id.in_(used), AuditEvent.id > asked,
            AuditEvent.user_id.is_not(None))))
        cal = s.get(Calibration, int(cal_id))
        if cal is not None and cal.pending_replaces_id:   # corrections it states, made earlier
            since = _event_id(s, "issue", "certificate", cal.pending_replaces_id) or asked
            changed |= {uid for _e, uid, _s, _f in standard_corrections(s, used, since)
                        if uid is not None}
    return changed


def _transition(store, actor: User, cal_id: int, action: str, allowed: tuple[str, ...],
                number: bool = False, check=None, sealed_files: dict | None = None,
                recorded=None, **changes) -> Calibration:
    """Check the state (and the second person; ``check(s, cal)``: the caller's own check
    after those), apply ``changes``, audit — one transaction; with ``number`` a certificate
    number is reserved in it (none is used up by a refusal). ``sealed_files`` (the stored
    files' digests the signed seal covers, :func:`sealed_content`) go into the audit event
    beside the row's state, so that a later mismatch names the file
    (:func:`seal_differences`); ``recorded(s, cal)`` (after the checks, before the changes)
    gives what else the event records (an amendment's approval: the statement it fixes)."""
    with store.writing() as s:
        cal = _check(s, actor, cal_id, action, allowed)
        if check is not None:
            check(s, cal)
        fixed = recorded(s, cal) if recorded is not None else {}
        before = state(cal)
        if number and not cal.pending_number:
            changes["pending_number"] = _reserve_number(s, utcnow().year)
        for k, v in changes.items():
            setattr(cal, k, v)
        after = state(cal)
        if sealed_files is not None:
            after["sealed_files"] = dict(sealed_files)
        after.update(fixed)
        audit(s, actor, action, "calibration", cal.id, before, after)
        s.commit()
    return cal


def review(store, actor: User, cal_id: int, *, accept: bool, comment: str = "",
           shown_seal: str | None = None) -> Calibration:
    """Review a computed calibration (reviewer, not its creator): accepted → reviewed,
    else rejected (a rejected calibration is closed; create a new one). The reviewer signs
    the result's :func:`seal` (``shown_seal``: the one the page showed, which must still be
    the result's)."""
    require(actor, "reviewer")
    comment = text(comment, "comment", max_len=MAX_TEXT, multiline=True)
    if not accept and not comment:
        raise GonioError("say why the calibration is rejected", key="comment")
    content = sealed_content(store, cal_id)
    signed = seal_of(content)
    _signs(signed, shown_seal)
    return _transition(store, actor, cal_id, "review", ("computed",),
                       sealed_files=content["files"],
                       status="reviewed" if accept else "rejected", reviewed_by_id=actor.id,
                       reviewed_at=utcnow(), review_comment=comment, reviewed_seal=signed)


def _signs(signed: str, shown: str | None) -> None:
    """The seal a person saw (on the page) is the result's seal now."""
    if shown is not None and shown != signed:
        raise GonioError("the result changed since the page was shown: reload it and check "
                         "the result again", key="seal")


#: The columns of a result row its seal hashes (:func:`seal`).
_ROW_SEALED = ("key", "title", "clause", "unit", "measured", "value", "U", "k")


def seal(store, cal_id: int) -> str:
    """The seal of a calibration's stored result now: :func:`seal_of` its
    :func:`sealed_content`."""
    return seal_of(sealed_content(store, cal_id))


def seal_of(content: dict) -> str:
    """SHA-256 of the canonical JSON of :func:`sealed_content`."""
    import hashlib

    doc = json.dumps(content, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(doc.encode("utf-8")).hexdigest()


def sealed_content(store, cal_id: int) -> dict:
    """What the seal of a calibration's stored result covers (``files``: name → SHA-256;
    ``items``; the register entry used). The seal, the content hash of a calibration's
    stored result, which the reviewer and the approver sign and the issue checks: SHA-256 of the canonical JSON of the stored files'
    digests (results.json, summary, draft certificate) and every result row (key, title,
    clause, unit, measured, value, U, k), and where the calibration used an entry of the
    register of table calibrations that entry (id, standard, SHA-256, valid from, due on:
    ``table_calibration_id`` changed after signing breaks the seal; a calibration without
    an entry is sealed as before). Every stored file is checked against its digest
    and every row against the stored results.json first, its kept statement too (stated,
    interval ends: :func:`gonio.records.results.result_rows`; a row that keeps none, None,
    is drawn from the stored result itself), and results.json's readings against the
    calibration's (:func:`_same_readings`): a GonioError names what no longer matches (a
    row changed in the database, a file changed on disk, the link to the readings). The kept statement is not hashed:
    it follows from results.json, whose digest is, so a seal signed before rows kept it
    stays the seal."""
    with store.session() as s:
        cal = s.get(Calibration, int(cal_id))
        if cal is None:
            raise GonioError("no such calibration", key="calibration")
        if not cal.results_sha256:
            raise GonioError("the calibration has no stored result", key="calibration")
        files = dict(s.execute(select(CalibrationFile.name, CalibrationFile.sha256).where(
            CalibrationFile.calibration_id == cal.id)).all())
        files["results.json"] = cal.results_sha256
        entry = s.get(TableCalibration, cal.table_calibration_id) \
            if cal.table_calibration_id is not None else None
        kept = s.scalars(select(ResultItem).where(
            ResultItem.calibration_id == cal.id).order_by(ResultItem.id)).all()
    for name, sha in sorted(files.items()):
        if not blobs.verify(store.blob_root, sha):
            raise GonioError(f"the stored {name} is missing or does not match its SHA-256",
                             key=f"calibration {cal_id}")
    if cal.readings_sha256 and not blobs.verify(store.blob_root, cal.readings_sha256):
        # the raw data the result was computed from, as stored: damaged on disk → no seal
        raise GonioError("the stored readings are missing or do not match their SHA-256",
                         key=f"calibration {cal_id}")
    doc = json.loads(file_bytes(store, cal.results_sha256))
    _same_readings(doc, cal.readings_sha256, cal_id)
    _same_table_calibration(doc, files.get(TABLE_CALIBRATION), cal_id)
    if entry is not None and files.get(TABLE_CALIBRATION) != entry.sha256:
        raise GonioError(f"the stored {TABLE_CALIBRATION} is not the file of the register's "
                         f"table calibration {entry.id} the calibration used (SHA-256 "
                         f"{entry.sha256[:16]}…)", key=f"calibration {cal_id}")
    expect = result_rows(cal.id, doc)
    if len(expect) != len(kept):
        raise GonioError(f"{len(kept)} stored result rows, results.json has {len(expect)}",
                         key=f"calibration {cal_id}")
    rows = [(r.key, r.title, r.clause, r.unit, bool(r.measured), r.value, r.U, r.k)
            for r in kept]                                    # :data:`_ROW_SEALED`
    for r, want in zip(kept, expect):
        names = _ROW_SEALED + (tuple(NOT_STATED) if r.stated is not None else ())
        if any(getattr(r, name) != want[name] for name in names):
            raise GonioError(f"the stored result row {r.key} differs from the stored "
                             "results.json (changed in the database)", key=f"calibration {cal_id}")
    sealed: dict = {"files": files, "items": rows}
    if entry is not None:   # which register entry was used; a seal without one stays as it was
        sealed["table_calibration_entry"] = {
            "id": entry.id, "standard_id": entry.standard_id, "sha256": entry.sha256,
            "valid_from": entry.valid_from.isoformat(), "due_on": entry.due_on.isoformat()}
    return sealed


def seal_differences(store, cal_id: int, action: str) -> str:
    """The stored files of a calibration that are not the ones its latest ``action``
    ("review" or "approve") signed, as the audit event recorded them (``sealed_files``), in
    one phrase (" — lab.toml is not the file signed (SHA-256 1a2b3c4d… now, 5e6f7a8b…
    signed)"); "" where the event recorded none (signed before files were recorded) or every
    file is the one signed (a row, the register entry or the seal itself then differs)."""
    with store.session() as s:
        blob = s.scalar(select(AuditEvent.after_json).where(
            AuditEvent.entity == "calibration", AuditEvent.entity_id == str(int(cal_id)),
            AuditEvent.action == action).order_by(AuditEvent.id.desc()).limit(1))
    try:
        signed = (json.loads(blob or "{}") or {}).get("sealed_files")
    except (ValueError, AttributeError):
        signed = None
    if not isinstance(signed, dict):
        return ""
    try:
        now = sealed_content(store, cal_id)["files"]
    except GonioError:
        return ""
    lines = []
    for name in sorted(set(now) | set(signed)):
        a, b = now.get(name), signed.get(name)
        if a != b:
            lines.append(f"{name} is not the file signed (SHA-256 "
                         f"{(a or '(none)')[:8]}… now, {(b or '(none)')[:8]}… signed)")
    return (" — " + "; ".join(lines)) if lines else ""


def _same_readings(results: dict, stored: str | None, cal_id) -> None:
    """The readings a stored results.json was computed from (its ``source.sha256``) are the
    calibration's stored readings (``stored``, their digest): a GonioError naming both
    otherwise (the calibration's link to its raw data changed: its result is not theirs).
    A results.json without the digest is left to the other checks."""
    used = str(((results or {}).get("source") or {}).get("sha256") or "")
    if used and stored and used != stored:
        raise GonioError(f"the stored results.json was computed from the readings "
                         f"{used[:16]}…, not from the calibration's stored readings "
                         f"{stored[:16]}…: not sealed", key=f"calibration {cal_id}")


def recorded_table_calibrations(results: dict) -> set[str]:
    """The SHA-256 digests of the table calibrations a results.json records (any item's
    ``details.table_calibration.sha256``; items as a mapping or a list).

    >>> sorted(recorded_table_calibrations({"items": {"K": {"details": {
    ...     "table_calibration": {"sha256": "ab"}}}, "R": {"details": None}}}))
    ['ab']
    """
    items = (results or {}).get("items") or {}
    items = items.values() if isinstance(items, dict) else items
    return {str(d["sha256"]) for it in items if isinstance(it, dict)
            for d in [((it.get("details") or {}).get("table_calibration") or {})]
            if isinstance(d, dict) and d.get("sha256")}


def _same_table_calibration(results: dict, stored: str | None, cal_id) -> None:
    """The table calibration a stored results.json was computed with (the SHA-256 any item's
    ``details.table_calibration`` records) is the calibration's stored
    :data:`TABLE_CALIBRATION` (``stored``, its digest): a GonioError naming both otherwise
    (the file kept with the calibration is not the one its result used); a results.json that
    records one where the calibration keeps none is a GonioError too: a result is never sealed
    without the table calibration it was computed with."""
    used = sorted(recorded_table_calibrations(results))
    if not used:
        return
    if stored is None:
        raise GonioError(f"calibration {cal_id}: its results.json was computed with the table "
                         f"calibration {', '.join(u[:16] + '…' for u in used)} and no stored "
                         f"{TABLE_CALIBRATION} keeps it: not sealed",
                         key=f"calibration {cal_id}")
    if used != [stored]:
        raise GonioError(f"the stored {TABLE_CALIBRATION} (SHA-256 {stored[:16]}…) is not the "
                         f"table calibration the stored results.json was computed with "
                         f"({', '.join(u[:16] + '…' for u in used)})",
                         key=f"calibration {cal_id}")


def _reserve_number(s: Session, year: int) -> str:
    """The next certificate number of ``year`` (the counter row is locked until commit:
    numbers are unique and without gaps, also with several workstations)."""
    if s.get_bind().dialect.name == "postgresql":
        from sqlalchemy.dialects.postgresql import insert
    else:
        from sqlalchemy.dialects.sqlite import insert
    s.execute(insert(CertificateCounter).values(year=year, last=0)
              .on_conflict_do_nothing(index_elements=["year"]))
    row = s.scalar(select(CertificateCounter).where(CertificateCounter.year == year)
                   .with_for_update())
    row.last += 1
    return f"{NUMBER_PREFIX}-{year:04d}-{row.last:04d}"


def approve(store, actor: User, cal_id: int, shown_seal: str | None = None) -> Calibration:
    """Approve a reviewed calibration, or an amendment asked for (reviewer; not its creator,
    with ``min_people`` 3 not its reviewer; an amendment: not its asker nor who changed it,
    and with ``min_people`` 2 its creator may: :func:`check_duties`) and start issuing:
    the certificate number is reserved and the worker renders the final certificate. The
    approver signs the same :func:`seal` the reviewer signed (an amendment: the one its
    calibration was approved with); a result changed since is refused. An amendment's
    approval fixes the statement of its standards (:func:`amendment_standards`, kept in
    the ``approve`` audit event as ``stated_standards``): its certificate states them so
    (:func:`approved_statement`), whatever the register says after."""
    require(actor, "reviewer")
    cal = calibration(store, cal_id)
    if cal.status not in ("reviewed", "amending"):
        raise GonioError(f"cannot approve a calibration that is {cal.status}", key="status")
    content = sealed_content(store, cal_id)
    signed = seal_of(content)
    _signs(signed, shown_seal)
    before = cal.approved_seal if cal.status == "amending" else cal.reviewed_seal
    if signed != before:
        which = seal_differences(store, cal_id,
                                 "approve" if cal.status == "amending" else "review")
        raise GonioError("the stored result no longer matches the one reviewed (its seal "
                         f"{signed[:12]}… is not the signed {before[:12] or '(none)'}…"
                         f"{which}): nothing approved", key=f"calibration {cal_id}")
    changed = details_changed(store, cal_id) if cal.status == "reviewed" else []

    def as_reviewed(s, cal):        # after the state, duties and completeness checks
        if changed and cal.status == "reviewed":
            more = f" and {len(changed) - 1} more" if len(changed) > 1 else ""
            raise GonioError(f"the records state the calibration differently from the draft "
                             f"that was reviewed ({changed[0]}{more}): nothing approved "
                             "(gonio db verify lists it)", key=f"calibration {cal_id}")
    def fixed(s, cal):              # an amendment states its standards as approved now
        if cal.status != "amending":
            return {}
        return {"stated_standards": amendment_standards(store, s, cal, approved=False)}
    return _transition(store, actor, cal_id, "approve", ("reviewed", "amending"),
                       number=True, check=as_reviewed, recorded=fixed, status="issuing",
                       sealed_files=content["files"], approved_by_id=actor.id,
                       approved_at=utcnow(), approved_seal=signed,
                       progress="waiting for a worker", error="")


def failed_redraft(cal: Calibration) -> bool:
    """A failed calibration whose failure was the rendering of its draft again
    (:data:`DRAFTING`): it has its stored result and no reserved certificate number (a
    failed run has no result yet, a failed issue its number)."""
    return cal.status == "failed" and bool(cal.results_sha256) and not cal.pending_number


def retry(store, actor: User, cal_id: int) -> Calibration:
    """Run a failed calibration again (technician): a failed run is queued again, a failed
    issue (its number reserved) goes back to issuing, a failed redraft
    (:func:`failed_redraft`) back to :data:`DRAFTING` — its draft rendered again from the
    stored, sealed result, nothing computed again."""
    require(actor, "technician")
    cal = calibration(store, cal_id)
    status = ("issuing" if cal.pending_number else DRAFTING if failed_redraft(cal)
              else "queued")
    return _transition(store, actor, cal_id, "retry", ("failed",), status=status,
                       progress="waiting for a worker", error="", worker_pid=None,
                       worker_host="")


def void(store, actor: User, cal_id: int, reason: str) -> Calibration:
    """Void a failed run that will not be run again (technician or reviewer), with the
    reason; it stays in the records, out of the lists of work. A failed issue, which holds
    a reserved certificate number, is not voided: it is issued again (the number is used)."""
    if not (actor is not None and actor.active and (actor.has("technician")
                                                   or actor.has("reviewer"))):
        raise GonioError("this needs the technician or reviewer role", key="role")
    reason = text(reason, "reason", max_len=MAX_TEXT, multiline=True, required=True)
    if calibration(store, cal_id).pending_number:
        raise GonioError("a failed issue holds its reserved certificate number: run it "
                         "again", key="status")
    return _transition(store, actor, cal_id, "void", ("failed",), status="void",
                       progress="void", error=f"void: {reason}")


def amend(store, actor: User, certificate_id: int, reason: str) -> Calibration:
    """Ask for an amendment of an issued certificate (reviewer, not the calibration's
    creator): once another person approves it (:func:`approve`), a new certificate with a
    new number is issued for the same calibration, naming the one it replaces and why
    (ISO/IEC 17025 7.8.8); the replaced certificate keeps its own approvals."""
    require(actor, "reviewer")
    reason = text(reason, "reason", max_len=MAX_TEXT, multiline=True, required=True)
    with store.session() as s:
        cert = s.get(Certificate, int(certificate_id))
        if cert is None:
            raise GonioError("no such certificate", key="certificate")
        if s.scalar(select(Certificate).where(Certificate.replaces_id == cert.id)):
            raise GonioError(f"{cert.number} has been replaced already; amend the newest "
                             "certificate", key="certificate")
        cal_id = cert.calibration_id
    return _transition(store, actor, cal_id, "amend", ("issued",), status="amending",
                       pending_replaces_id=cert.id, pending_reason=reason,
                       amend_requested_by_id=actor.id,
                       progress="amendment asked for: awaiting approval by another person",
                       error="")


# --------------------------------------------------------------------------- the worker's side


#: The states in which a worker process runs a calibration.
WORKING = ("running", "issuing", DRAFTING)


def claim_next(store, host: str | None = None,
               cal_id: int | None = None) -> Calibration | None:
    """Claim the oldest queued calibration, or one waiting to be issued or to have its draft
    rendered again (:data:`DRAFTING`), for a worker on ``host`` (atomically: two dispatchers
    never claim the same one); with ``cal_id`` that one only (None when it waits for
    nothing or another worker has it). Queued → running; issuing and drafting stay so. The
    worker's process id is set by :func:`attach`."""
    host = host or socket.gethostname()
    with store.writing() as s:
        waiting = (Calibration.status == "queued") | (
            Calibration.status.in_(("issuing", DRAFTING)) & (Calibration.worker_host == ""))
        if cal_id is not None:
            waiting = waiting & (Calibration.id == int(cal_id))
        cal = s.scalar(select(Calibration).where(waiting)
                       .order_by(Calibration.id).limit(1).with_for_update(skip_locked=True))
        if cal is None:
            return None
        before = state(cal)
        if cal.status == "queued":
            cal.status = "running"
        cal.worker_host, cal.worker_pid = host, None
        cal.started_at, cal.progress = utcnow(), "starting a worker"
        audit(s, None, "claim", "calibration", cal.id, before, state(cal))
        s.commit()
    return cal


def attach(store, cal_id: int, pid: int) -> None:
    """Record the process id of the worker running a claimed calibration."""
    with store.writing() as s:
        s.execute(update(Calibration).where(Calibration.id == cal_id).values(worker_pid=pid))
        s.commit()


def set_progress(store, cal_id: int, message: str) -> None:
    """The worker's progress line for a calibration."""
    with store.writing() as s:
        s.execute(update(Calibration).where(Calibration.id == cal_id)
                  .values(progress=message[:200]))
        s.commit()


def fail(store, cal_id: int, error: str) -> None:
    """A run ended without a result: running, issuing or drafting → failed, with the error.
    Nothing was issued (the certificate row is written only by :func:`store_issue`); a
    failed issue keeps its reserved number for :func:`retry`; a failed redraft keeps its
    stored result, its error says so, and :func:`retry` renders the draft again. A calibration no longer running (another worker finished it) is
    left as it is."""
    with store.writing() as s:
        cal = s.get(Calibration, cal_id, with_for_update=True)
        if cal.status not in WORKING:                   # finished meanwhile (another worker)
            return
        before = state(cal)
        if cal.status == DRAFTING:
            error = (f"rendering the draft certificate again failed: {error} (run again: "
                     "rendered again from the stored result, nothing computed)")
        cal.progress = ("issuing failed" if cal.pending_number else "drafting failed"
                        if cal.status == DRAFTING else "failed")
        cal.status = "failed"
        cal.error = error[:MAX_TEXT]
        cal.worker_pid, cal.worker_host, cal.finished_at = None, "", utcnow()
        audit(s, None, "fail", "calibration", cal.id, before, state(cal))
        s.commit()


def recover(store, host: str | None = None, alive=None) -> list[int]:
    """Calibrations whose worker on this host died (server killed, power lost) are marked
    failed, so that they can be run again; returns their ids. ``alive(pid)`` decides
    whether a worker process still runs (default: ``os.kill(pid, 0)``)."""
    host = host or socket.gethostname()
    alive = alive or _pid_alive
    with store.session() as s:
        rows = s.scalars(select(Calibration).where(
            Calibration.status.in_(WORKING),
            Calibration.worker_host == host)).all()
    dead = [c.id for c in rows if c.worker_pid is None or not alive(c.worker_pid)]
    for cid in dead:
        fail(store, cid, "interrupted: the worker stopped before the run finished "
                         "(server stopped or killed); nothing was issued — run it again")
        remove_work(store, cid)
    return dead


def remove_work(store, cal_id: int) -> list[Path]:
    """Remove a calibration's work folders (``<data>/work/cal-<id>-*``, the copied readings
    of a worker that was killed before its own clean-up); returns those removed."""
    import shutil

    gone = []
    for path in (store.data / "work").glob(f"cal-{int(cal_id)}-*"):
        shutil.rmtree(path, ignore_errors=True)
        gone.append(path)
    return gone


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:                       # a zombie child of ours counts as dead
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split(") ")[-1][:1] != "Z"
    except OSError:
        return True


def lab_details(store, cal_id: int, *, final: bool, redraft: bool = False) -> dict:
    """The laboratory details file (``LAB_SCHEMA``) for a calibration's certificate: the
    draft (number DRAFT-<id>, not approved) or the final one (reserved number, signatories,
    date of issue). The decision rule and limits are the calibration's laboratory file's
    (:func:`lab_file`) if it has one, else the instrument's under the laboratory's rule; the
    final one, and a draft rendered again (``redraft``: after an attach), take them from the
    details the draft was computed with (stored as lab.toml with the run and sealed with
    it), so that a limit edited after the run never reaches the certificate."""
    cfg = settings(store)
    with store.session() as s:
        cal = s.get(Calibration, cal_id)
        inst, cust = cal.instrument, cal.instrument.customer
        stds = [cs.standard for cs in s.scalars(select(CalibrationStandard).where(
            CalibrationStandard.calibration_id == cal.id))]
        limits = json.loads(inst.limits_json or "[]")
        number = cal.pending_number if final else f"DRAFT-{cal.id}"
        who = {k: _name(getattr(cal, k)) for k in ("created_by", "reviewed_by", "approved_by")}
        record = {"status": "draft"}
        if final:
            record = {"status": "issued", "seal_sha256": cal.approved_seal,
                      "min_people": min_people(s)}
            if cal.pending_replaces_id:      # ISO/IEC 17025 7.8.8: what it replaces and why
                record.update(replaces=s.get(Certificate, cal.pending_replaces_id).number,
                              amendment_reason=cal.pending_reason,
                              amendment_asked_by=_name(s.get(User,
                                                             cal.amend_requested_by_id)))
        lab = {
            "laboratory": {"name": cfg["lab_name"], "address": _lines(cfg["lab_address"]),
                           "accreditation": cfg["lab_accreditation"],
                           "contact": cfg["lab_contact"]},
            "certificate": {"number": number,
                            "date_of_issue": records_today(store).isoformat() if final else "",
                            "date_of_receipt": cal.received_on.isoformat()
                            if cal.received_on else "",
                            "date_of_calibration": cal.performed_on.isoformat(),
                            "place": cal.place or cfg["lab_place"],
                            "location": cal.location or "laboratory"},
            "customer": {"name": cust.name, "address": _lines(cust.address)},
            "instrument": {"description": inst.kind, "model": inst.model,
                           "serial": inst.serial, "manufacturer": inst.manufacturer,
                           "gyro_type": inst.gyro_type or None},
            "standards": [{"name": st.name, "identifier": st.identifier,
                           "accuracy": st.accuracy, "certificate": st.certificate,
                           "traceability": st.traceability} for st in stds],
            # the numbers with the digits they were entered with (the file writes them)
            "environment": {"temperature_c": environment_shown(cal)[0],
                            "humidity_pct": environment_shown(cal)[1],
                            # one from the laboratory file was entered there
                            "source": "readings" if cal.environment_from == "readings"
                            else "entered"},
            "signatory": {"calibrated_by": who["created_by"], "checked_by": who["reviewed_by"],
                          "approved_by": who["approved_by"] if final
                          else "(not approved: draft for review)"},
            "record": record,
        }
        drafted = s.get(CalibrationFile, (cal.id, "lab.toml")) if final or redraft else None
        if drafted is not None:        # the basis the reviewed decisions were made on
            import tomllib
            basis = tomllib.loads(file_bytes(store, drafted.sha256).decode("utf-8"))
            lab.update({k: basis[k] for k in DECISION_BASIS if k in basis})
            if final and not cal.pending_replaces_id:   # a first issue: the details reviewed
                lab.update(_with_reviewed(lab, basis))
            elif final:                # an amendment: as its approval fixed them
                kept = approved_statement(s, cal)
                lab["standards"] = kept if kept is not None else amended_standards(
                    s, cal, stds, lab["standards"], basis)
        elif cal.lab_sha256 and (own := lab_file(store, cal.lab_sha256, cal.lab_name,
                                                 cal.spec_key)).get("specification_limits"):
            # the calibration's own laboratory file (one naming only its table calibration
            # leaves the instrument's limits in force)
            lab.update({k: own[k] for k in DECISION_BASIS})
        elif limits:
            lab["decision_rule"] = {"rule": cfg["decision_rule"],
                                    "guard_band_factor": float(cfg["guard_band_factor"]),
                                    "agreed": "laboratory's decision rule"}
            lab["specification_limits"] = limits
    return lab


#: The laboratory details' sections the reviewer signs with the draft (its stored lab.toml,
#: sealed with the result): whom and what the certificate names, and the conditions.
REVIEWED = ("customer", "instrument", "standards", "environment")
#: The ``certificate`` section's fields signed with the draft (the number and the date of
#: issue are the issue's own).
REVIEWED_CERTIFICATE = ("date_of_receipt", "date_of_calibration", "place", "location")


def reviewed_part(lab: dict) -> dict:
    """The part of laboratory details (:func:`lab_details`, or a stored lab.toml read back)
    that the reviewer signs with the draft: the :data:`REVIEWED` sections (None where
    absent) and the certificate's :data:`REVIEWED_CERTIFICATE` fields.

    >>> reviewed_part({"customer": {"name": "A"}, "laboratory": {"name": "L"},
    ...                "certificate": {"number": "DRAFT-1", "place": "P"}})
    {'customer': {'name': 'A'}, 'instrument': None, 'standards': None, 'environment': None, \
'certificate': {'place': 'P'}}
    """
    part = {k: lab.get(k) for k in REVIEWED}
    cert = lab.get("certificate") or {}
    part["certificate"] = {k: cert[k] for k in REVIEWED_CERTIFICATE if k in cert}
    return part


#: The fields of a standard's register entry that a certificate states.
STANDARD_STATED = ("name", "identifier", "accuracy", "certificate", "traceability")
#: The fields whose change in an edit records the standard's recalibration.
STANDARD_RECALIBRATED = ("calibrated_on", "due_on")

#: The register entries checked against their audit trail (:func:`register_problems`): each
#: entity's model, the column naming an entry in a finding, and the fields compared — what a
#: certificate states of it (:data:`STATED_FIELDS`, :data:`STANDARD_STATED`) and its dates
#: (:data:`STANDARD_RECALIBRATED`, ``retired_on``).
REGISTER_TRAIL = {
    "customer": (Customer, "name", STATED_FIELDS["customer"] + ("retired_on",)),
    "instrument": (Instrument, "serial", STATED_FIELDS["instrument"] + ("retired_on",)),
    "standard": (Standard, "identifier",
                 STANDARD_STATED + STANDARD_RECALIBRATED + ("retired_on",)),
}


def standard_corrections(s: Session, standard_ids, since: int, until: int | None = None
                         ) -> list[tuple[int, int | None, str, dict]]:
    """The corrections of standards' register entries in the audit trail between the events
    ``since`` and ``until`` (exclusive, inclusive; None: to now): (event id, user id, the
    standard's id, {stated field: value after}) for each ``update`` event that changed a
    field a certificate states (:data:`STANDARD_STATED`) without recording a recalibration
    (it changes none of :data:`STANDARD_RECALIBRATED`: an edit that records a new
    calibration date or due date is a recalibration, never a correction), oldest first."""
    ids = [str(int(i)) for i in standard_ids]
    if not ids:
        return []
    stmt = select(AuditEvent.id, AuditEvent.user_id, AuditEvent.entity_id,
                  AuditEvent.before_json, AuditEvent.after_json).where(
        AuditEvent.action == "update", AuditEvent.entity == "standard",
        AuditEvent.entity_id.in_(ids), AuditEvent.id > int(since))
    if until is not None:
        stmt = stmt.where(AuditEvent.id <= int(until))
    out = []
    for eid, uid, sid, before, after in s.execute(stmt.order_by(AuditEvent.id)):
        try:
            b, a = json.loads(before or "{}"), json.loads(after or "{}")
        except ValueError:
            continue
        if any(b.get(k) != a.get(k) for k in STANDARD_RECALIBRATED):
            continue
        fields = {k: a.get(k) for k in STANDARD_STATED if b.get(k) != a.get(k)}
        if fields:
            out.append((eid, uid, sid, fields))
    return out


def _event_id(s: Session, action: str, entity: str, entity_id, first: bool = False
              ) -> int | None:
    """The id of the latest (``first``: the earliest) audit event ``action`` on a record."""
    col = func.min(AuditEvent.id) if first else func.max(AuditEvent.id)
    return s.scalar(select(col).where(AuditEvent.action == action, AuditEvent.entity == entity,
                                      AuditEvent.entity_id == str(int(entity_id))))


def _replaced_statement(s: Session, cal: Calibration, drafted: dict) -> tuple[list, int]:
    """(the standards the certificate an amendment replaces stated, the id of the audit event
    from which register corrections reach the amendment): that certificate's own statement
    and issue event (:func:`stated_standards`); for one issued before statements were kept,
    the calibration's first certificate's — its reviewed draft's standards — and that first
    issue's event."""
    kept = stated_standards(s, cal.pending_replaces_id)
    if kept is not None:
        return kept, _event_id(s, "issue", "certificate", cal.pending_replaces_id) or 0
    first = s.scalar(select(func.min(Certificate.id)).where(
        Certificate.calibration_id == cal.id))
    since = _event_id(s, "issue", "certificate", first) if first is not None else None
    return reviewed_part(drafted)["standards"] or [], since or 0


def amended_standards(s: Session, cal: Calibration, stds: list, live: list,
                      drafted: dict, approved: bool = True) -> list:
    """The standards an amendment of ``cal`` states (``stds`` the standards it names, ``live``
    their register entries now, in that order; ``drafted`` its reviewed draft's details).

    Each standard the replaced certificate stated is stated as it stated it — as it was when
    used: a recalibration recorded in the register since does not reach the amendment — with
    the corrections of its register entry made since that certificate's issue and up to the
    amendment's approval applied field by field (:func:`standard_corrections`: a misread
    certificate number corrected, before the amendment is asked for or during it). An edit
    after the approval reaches nothing (what is issued is what was approved). A standard the
    replaced certificate did not state (attached during the amendment) is stated as the
    register holds it. The replaced certificate's statement: :func:`_replaced_statement`.
    ``approved`` False: the corrections up to now (the approval being made)."""
    base, since = _replaced_statement(s, cal, drafted)
    until = _event_id(s, "approve", "calibration", cal.id) if approved else None
    by_ident = {str(e.get("identifier")): dict(e) for e in base if isinstance(e, dict)}
    fixes: dict[str, dict] = {}
    for _eid, _uid, sid, fields in standard_corrections(s, [st.id for st in stds], since,
                                                       until):
        fixes.setdefault(sid, {}).update(fields)
    out = []
    for st, entry in zip(stds, live):
        stated = by_ident.get(st.identifier)
        out.append(entry if stated is None else dict(stated, **fixes.get(str(st.id), {})))
    return out


def amendment_standards(store, s: Session, cal: Calibration, approved: bool = True) -> list:
    """The standards an amendment of ``cal`` states (:func:`amended_standards`), from the
    standards attached to it, their register entries and its reviewed draft's details (its
    stored lab.toml); ``approved`` False: with the corrections up to now."""
    import tomllib

    stds = [cs.standard for cs in s.scalars(select(CalibrationStandard).where(
        CalibrationStandard.calibration_id == cal.id))]
    live = [{"name": st.name, "identifier": st.identifier, "accuracy": st.accuracy,
             "certificate": st.certificate, "traceability": st.traceability} for st in stds]
    drafted = s.get(CalibrationFile, (cal.id, "lab.toml"))
    basis = (tomllib.loads(file_bytes(store, drafted.sha256).decode("utf-8"))
             if drafted is not None else {})
    return amended_standards(s, cal, stds, live, basis, approved=approved)


def stated_standards(s: Session, cert_id: int) -> list | None:
    """The standards an issued certificate stated, as its issue's audit event kept them
    (:func:`store_issue`), or None where the event kept none (issued before they were
    kept)."""
    after = s.scalar(select(AuditEvent.after_json).where(
        AuditEvent.action == "issue", AuditEvent.entity == "certificate",
        AuditEvent.entity_id == str(int(cert_id))).order_by(AuditEvent.id.desc()).limit(1))
    got = json.loads(after or "{}").get("stated_standards")
    return got if isinstance(got, list) else None


def _with_reviewed(lab: dict, drafted: dict) -> dict:
    """``lab``'s sections with the reviewed part (:func:`reviewed_part`) taken from
    ``drafted``, the details the reviewed draft was rendered with."""
    part = reviewed_part(drafted)
    out = {k: part[k] if part[k] is not None else [] if k == "standards" else None
           for k in REVIEWED}      # a section the draft had not: stated none
    out["certificate"] = dict(lab["certificate"], **part["certificate"])
    return out


def details_changed(store, cal_id: int) -> list[str]:
    """What the records state now of a calibration (its customer, instrument, the standards
    used — by identifier: a standard's details are stated as when it was used —,
    environment, dates, place: :func:`reviewed_part`) differently from the draft last
    rendered for it (its stored lab.toml, sealed with the result): one line each, e.g.
    ``instrument serial: 'RLG-0001' in the draft, now 'FAKE-9999'``; [] where they agree or
    no draft is stored (an imported result before its first draft). A change through the
    records' own edits renders the draft again (:func:`_stated_change`), so a line here is a
    change made around them (the database edited)."""
    import tomllib

    from gonio.records.compute import lab_toml

    with store.session() as s:
        drafted = s.get(CalibrationFile, (int(cal_id), "lab.toml"))
        sha = drafted.sha256 if drafted is not None else None
    if sha is None:
        return []
    was = reviewed_part(tomllib.loads(file_bytes(store, sha).decode("utf-8")))
    now = reviewed_part(tomllib.loads(lab_toml(lab_details(store, cal_id, final=False,
                                                           redraft=True))))

    def ids(v):        # the standards by which were used (their details: as when used)
        return sorted(str(x.get("identifier")) for x in v or [])
    was["standards"], now["standards"] = ids(was["standards"]), ids(now["standards"])
    lines = []
    for section, before in was.items():
        after = now[section]
        if before == after:
            continue
        if isinstance(before, dict) and isinstance(after, dict):
            lines += [f"{section} {k}: {before.get(k)!r} in the draft, now {after.get(k)!r}"
                      for k in sorted(set(before) | set(after)) if before.get(k) != after.get(k)]
        else:
            lines.append(f"{section}: {before!r} in the draft, now {after!r}")
    return lines


def _name(u: User | None) -> str:
    """A person as the certificate names them: the full name, else the user name."""
    return (u.full_name or u.username) if u is not None else ""


def _lines(value: str) -> str:
    """Multi-line text with its line ends as LF (a value stored before CR was normalised)."""
    return (value or "").replace("\r\n", "\n").replace("\r", "\n")


#: The files of a run kept in the store (tables stay in the worker's folder only); lab.toml:
#: the laboratory details the draft was computed with (its decision rule and limits are the
#: issue's, whatever was edited since).
KEPT = ("results.json", "summary.txt", "certificate.html", "certificate.pdf",
        "certificate.dcc.xml", "lab.toml")
#: The sections of the laboratory details the result's conformity was decided with.
DECISION_BASIS = ("decision_rule", "specification_limits")


#: The files kept of an imported command-line folder: its certificate files carry the command
#: line's number and title and no DRAFT mark, so they are not kept as the records' draft (the
#: certificate is rendered at issue from the stored result).
KEPT_IMPORTED = ("results.json", "summary.txt")


def _put_files(s: Session, cal_id: int, files: dict) -> None:
    """The files ``{name: (sha256, size)}`` (in the blob store) as the calibration's."""
    for name, (sha, size) in files.items():
        if s.get(Blob, sha) is None:
            s.add(Blob(sha256=sha, size=size))
        s.flush()
        old = s.get(CalibrationFile, (cal_id, name))
        if old is None:
            s.add(CalibrationFile(calibration_id=cal_id, name=name, sha256=sha))
        else:
            old.sha256 = sha


def store_run(store, cal_id: int, out: Path, kept: tuple[str, ...] = KEPT) -> None:
    """Record a finished draft run: its files (``kept`` of them) into the blob store, its
    items, computed."""
    files = {n: blobs.put_file(store.blob_root, out / n) for n in kept if (out / n).is_file()}
    rows = result_rows(cal_id, json.loads((out / "results.json").read_text(encoding="utf-8")))
    with store.writing() as s:
        cal = s.get(Calibration, cal_id)
        before = state(cal)
        _put_files(s, cal_id, files)
        s.query(ResultItem).filter(ResultItem.calibration_id == cal_id).delete()
        for row in rows:
            s.add(ResultItem(**row))
        cal.results_sha256 = files["results.json"][0]
        cal.status, cal.progress, cal.error = "computed", "done", ""
        cal.worker_pid, cal.worker_host, cal.finished_at = None, "", utcnow()
        audit(s, None, "computed", "calibration", cal.id, before, state(cal))
        s.commit()


#: The files of a draft rendered again (:func:`store_draft`): the certificate and the
#: details it was rendered with; the result and its summary stay the stored ones.
REDRAWN = ("certificate.html", "certificate.pdf", "certificate.dcc.xml", "lab.toml")


def store_draft(store, cal_id: int, out: Path, signed: str) -> None:
    """Record a draft certificate rendered again from the stored result (:data:`REDRAWN`
    from ``out``): drafting → computed, once the result's seal is checked again against
    ``signed`` (the one it was rendered from). The seal changes with the draft's files:
    the review signs the draft rendered last."""
    files = {n: blobs.put_file(store.blob_root, out / n) for n in REDRAWN
             if (out / n).is_file()}
    if seal(store, cal_id) != signed:
        raise GonioError("the stored result changed while its draft was rendered: nothing "
                         "stored", key=f"calibration {cal_id}")
    from gonio.records.compute import lab_toml

    with store.writing() as s:
        cal = s.get(Calibration, cal_id, with_for_update=True)
        if cal.status != DRAFTING:
            raise GonioError(f"calibration {cal_id} is {cal.status}, no longer waiting for "
                             "its draft: nothing stored", key="status")
        before = dict(state(cal), files=_file_digests(s, cal_id))
        _put_files(s, cal_id, files)
        # attached again while it was rendered: stored, and rendered once more
        again = (out / "lab.toml").read_text(encoding="utf-8") != lab_toml(
            lab_details(store, cal_id, final=False, redraft=True))
        cal.status, cal.progress, cal.error = (
            (DRAFTING, "waiting for a worker to render the draft certificate with what was "
                       "attached since", "") if again else ("computed", "done", ""))
        cal.worker_pid, cal.worker_host, cal.finished_at = None, "", utcnow()
        s.flush()
        audit(s, None, "redraft", "calibration", cal.id, before,
              dict(state(cal), files=_file_digests(s, cal_id)))
        s.commit()


def _file_digests(s: Session, cal_id: int) -> dict:
    return dict(s.execute(select(CalibrationFile.name, CalibrationFile.sha256).where(
        CalibrationFile.calibration_id == cal_id)).all())


def _approved(signed: str, approved: str, what: str, which: str = "") -> None:
    """The seal of the stored result now is the one the approver signed (``which``: the
    files that differ, :func:`seal_differences`)."""
    if not approved or signed != approved:
        raise GonioError("the stored result no longer matches the one reviewed and approved "
                         f"(seal {signed[:12]}…, signed {approved[:12] or '(none)'}…{which}): "
                         f"nothing {what}", key="issue")


def sealed_result(store, cal_id: int) -> bytes:
    """The stored results.json of a calibration being issued, after checking every stored
    file and row against it (:func:`seal`) and the seal against the one approved: what the
    certificate is rendered from."""
    signed = seal(store, cal_id)
    cal = calibration(store, cal_id)
    _approved(signed, cal.approved_seal, "issued",
              seal_differences(store, cal_id, "approve") if signed != cal.approved_seal
              else "")
    with store.session() as s:
        check_trail(s, s.get(Calibration, cal_id), "issue")
        _not_withdrawn(s, cal, "issue")
    return file_bytes(store, cal.results_sha256)


#: The files of an issue kept with its certificate row (the results.json is the stored one).
ISSUED = ("certificate.html", "certificate.pdf", "certificate.dcc.xml")


def store_issue(store, cal_id: int, out: Path, stated_standards: list | None = None) -> Certificate:
    """Record an issued certificate: the files rendered from the sealed result and the
    frozen certificate row, in one transaction (the seal checked again in it).
    ``stated_standards``: the standards the certificate states (its laboratory details'
    ``standards``, :func:`lab_details`), kept in the issue's audit event, from which an
    amendment of it states them (:func:`stated_standards`)."""
    files = {n: blobs.put_file(store.blob_root, out / n) for n in ISSUED if (out / n).is_file()}
    signed = seal(store, cal_id)
    with store.writing() as s:
        # the row locked until commit: of two issues of one calibration at once (two workers,
        # two hosts), the second sees the first one's state and issues nothing
        cal = s.get(Calibration, cal_id, with_for_update=True)
        if cal.status != "issuing" or not cal.pending_number:
            raise GonioError(f"calibration {cal_id} is {cal.status}, not being issued: "
                             "nothing issued twice", key="issue")
        before = state(cal)
        _approved(signed, cal.approved_seal, "issued")
        check_trail(s, cal, "issue")
        _not_withdrawn(s, cal, "issue")
        for sha, size in files.values():
            if s.get(Blob, sha) is None:
                s.add(Blob(sha256=sha, size=size))
        s.flush()
        cert = Certificate(number=cal.pending_number, calibration_id=cal.id,
                           issued_by_id=cal.approved_by_id, replaces_id=cal.pending_replaces_id,
                           reason=cal.pending_reason, html_sha256=files["certificate.html"][0],
                           pdf_sha256=files["certificate.pdf"][0],
                           dcc_sha256=files.get("certificate.dcc.xml", (None,))[0],
                           results_sha256=cal.results_sha256, seal_sha256=signed,
                           reviewed_by_id=cal.amend_requested_by_id if cal.pending_replaces_id
                           else cal.reviewed_by_id, min_people=min_people(s))
        s.add(cert)
        cal.status, cal.progress, cal.error = "issued", "issued", ""
        cal.pending_number, cal.pending_replaces_id, cal.pending_reason = "", None, ""
        cal.amend_requested_by_id = None
        cal.worker_pid, cal.worker_host, cal.finished_at = None, "", utcnow()
        s.flush()
        after = {"certificate": state(cert), "calibration": state(cal)}
        if stated_standards is not None:
            after["stated_standards"] = list(stated_standards)
        audit(s, None, "issue", "certificate", cert.id, before, after)
        s.commit()
    return cert


def verify_certificate(store, data: bytes) -> dict:
    """The record of a certificate file (its PDF, HTML or DCC, or results.json): found by
    its SHA-256 among the issued certificates, with the seal it was issued from and the seal
    of its calibration's stored result now (which must be the same: a GonioError names what
    no longer matches). ``{"number", "file", "sha256", "seal", "seal_now", "issued_at",
    "replaces"}``; a file that is no issued certificate is a GonioError."""
    import hashlib

    digest = hashlib.sha256(data).hexdigest()
    cols = {"certificate.pdf": Certificate.pdf_sha256, "certificate.html":
            Certificate.html_sha256, "certificate.dcc.xml": Certificate.dcc_sha256,
            "results.json": Certificate.results_sha256}
    with store.session() as s:
        for name, col in cols.items():
            cert = s.scalar(select(Certificate).where(col == digest).order_by(Certificate.id))
            if cert is not None:
                break
        else:
            raise GonioError(f"no certificate issued in these records has this file "
                             f"(SHA-256 {digest})", key="certificate")
        replaces = cert.replaces.number if cert.replaces else ""
    out = {"number": cert.number, "file": name, "sha256": digest, "seal": cert.seal_sha256,
           "issued_at": cert.issued_at, "replaces": replaces}
    for col in ("html_sha256", "pdf_sha256", "dcc_sha256", "results_sha256"):
        sha = getattr(cert, col)
        if sha and not blobs.verify(store.blob_root, sha):
            raise GonioError(f"the stored file of {cert.number} ({col[:-7]}) is missing or "
                             "does not match its SHA-256", key="certificate")
    out["seal_now"] = seal(store, cert.calibration_id)
    if cert.seal_sha256 and out["seal_now"] != cert.seal_sha256:
        raise GonioError(f"{cert.number}: its calibration's stored result no longer matches "
                         "the seal it was issued from", key="certificate")
    return out


# --------------------------------------------------------------------------- reading


def calibration(store, cal_id: int) -> Calibration:
    """A calibration with its instrument, customer and people loaded (detached)."""
    from sqlalchemy.orm import selectinload

    with store.session() as s:
        cal = s.scalar(select(Calibration).where(Calibration.id == int(cal_id)).options(
            selectinload(Calibration.instrument).selectinload(Instrument.customer),
            selectinload(Calibration.created_by), selectinload(Calibration.reviewed_by),
            selectinload(Calibration.approved_by)))
        if cal is None:
            raise GonioError("no such calibration", key="calibration")
        return cal


#: the states of a calibration whose result the history shows
_HISTORY_DONE = ("computed", DRAFTING, "reviewed", "approved", "issuing", "issued", "amending")


def history(store, instrument_id: int, *, intervals: bool = True) -> dict:
    """An instrument's item history: key → list of dicts (calibration id, date, value, U,
    k, ``max_abs`` (:func:`_max_abs`: the row's value is the signed extreme beside the
    interval of max|E_i|), ``interval`` (the (low, high) of an item stated by one coverage interval, as its
    certificate states it: the row's kept statement, written with the row from the stored
    result; None for the other items, and for every item with ``intervals=False``), unit,
    title, status, certificate number, issued, amended), oldest first; failed,
    rejected and unfinished calibrations are left out (one whose draft is being rendered
    again, or whose amendment is asked for, has its result: it stays). ``issued``: it has a
    certificate, whatever its state now; ``amended``: issued, and a certificate of it has
    been replaced by an amendment or an amendment of it is under way (not 'issued' now)."""
    done = _HISTORY_DONE
    with store.session() as s:
        rows = s.execute(      # the columns, not the rows as objects (thousands of them)
            select(ResultItem.key, ResultItem.value, ResultItem.U, ResultItem.k,
                   ResultItem.unit, ResultItem.title, ResultItem.clause, ResultItem.stated,
                   ResultItem.interval_low, ResultItem.interval_high,
                   Calibration.performed_on, Calibration.status, Calibration.id,
                   Calibration.results_sha256)
            .join(Calibration, ResultItem.calibration_id == Calibration.id)
            .where(Calibration.instrument_id == int(instrument_id),
                   Calibration.status.in_(done))
            .order_by(Calibration.performed_on, Calibration.id)).all()
        certs = {cid: (number, n) for cid, number, n in s.execute(
            select(Certificate.calibration_id, func.max(Certificate.number),
                   func.count(Certificate.id))
            .join(Calibration, Certificate.calibration_id == Calibration.id)
            .where(Calibration.instrument_id == int(instrument_id))
            .group_by(Certificate.calibration_id)).all()}
    out: dict[str, list] = {}
    for key, value, U, k, unit, title, clause, *stated, day, status, cid, rsha in rows:
        number, n = certs.get(cid, ("", 0))
        iv = _interval(store, key, stated, rsha) if intervals else None
        out.setdefault(key, []).append(
            {"calibration_id": cid, "date": day, "value": value, "U": U, "k": k,
             "interval": iv, "max_abs": _max_abs(store, key, value, iv, rsha),
             "unit": unit, "title": title, "clause": clause, "status": status,
             "certificate": number, "issued": n > 0,
             "amended": n > 1 or (n > 0 and status != "issued")})
    return out


def _max_abs(store, key: str, value, interval, results_sha256: str | None) -> bool:
    """Whether a history row is stated by the interval of an extreme of magnitudes (the
    optical E: its value the signed extreme in a result written before 2026-12-02, its
    interval that of max|E_i|), where it
    matters: a value below zero beside an interval starting at or above zero; the stored
    result's ``k_source`` says (:func:`gonio.records.results.max_abs_keys`), never the
    numbers' signs alone (a range's bias-corrected estimate below zero, C_g, is not one)."""
    if interval is None or value is None or results_sha256 is None \
            or not float(value) < 0.0 <= float(interval[0]):
        return False
    from gonio.records.results import max_abs_keys

    return key in max_abs_keys(store, results_sha256)


def _interval(store, key: str, stated: list, results_sha256: str | None):
    """(low, high) of a result row stated by one coverage interval, else None: the row's
    kept statement ``stated`` (its stated, interval_low, interval_high), or for a row without
    one (stated None: not read when it was written) its stored result's
    (:func:`gonio.records.results.stated_intervals`)."""
    how, low, high = stated
    if how is None:
        from gonio.records.results import stated_intervals

        return stated_intervals(store, results_sha256).get(key) if results_sha256 else None
    return (low, high) if how == "interval" else None


def instrument_limits(inst: Instrument) -> dict:
    """Item key → (lower, upper) from the instrument's specification limits."""
    from gonio.analysis.conformity import limits_of

    out = {}
    for lim in json.loads(inst.limits_json or "[]"):
        lo_hi = limits_of(lim)
        out[lim["item"]] = (lo_hi.lower, lo_hi.upper)
    return out


@functools.lru_cache(maxsize=64)
def default_interval(spec_key: str) -> tuple[int, str]:
    """The specification's clause-9 default interval in months, and where it comes from:
    the specification's own ``recalibration_interval_months`` where it states one, else
    12 months (JJF 1535-2015 clause 9 recommends one year; the optical draft's clause 9
    leaves it to the user, normally ≤ 12 months)."""
    from gonio.records.interval import DEFAULT_MONTHS
    from gonio.specs import get

    months = get(spec_key).recalibration_interval_months
    if months:
        return int(months), "the specification's clause 9"
    return DEFAULT_MONTHS, "clause 9: normally ≤ 12 months"


def propose_interval(store, instrument_id: int, hist: dict | None = None):
    """The recalibration interval proposed from the instrument's issued calibrations
    (:func:`gonio.records.interval.propose`; ``hist``: its :func:`history` if at hand, of
    which only the issued ones count), with the specification's default beside it."""
    from gonio.records.interval import propose

    with store.session() as s:
        inst = s.get(Instrument, int(instrument_id))
        if inst is None:
            raise GonioError("no such instrument", key="instrument")
    limits = instrument_limits(inst)
    months, _ = default_interval(inst.spec_key)
    if hist is None:
        table, counts = _issued_table(store, instrument_id, limits)
        return propose(table, months, limited_items=tuple(limits), counts=counts)
    # only what was issued (a certificate, also while an amendment of it is asked for or
    # issued): a calibration not (yet) reviewed and approved is no evidence
    hist = {k: [r for r in rows if r["certificate"]] for k, rows in hist.items()}
    hist = {k: rows for k, rows in hist.items() if rows}
    dates = [r["date"] for rows in hist.values() for r in rows]
    t0 = min(dates) if dates else None
    table = {key: [((r["date"] - t0).days, r["value"], r["U"], r["k"],
                    *limits.get(key, (None, None))) for r in rows]
             for key, rows in hist.items()}
    return propose(table, months, limited_items=tuple(limits))


def _issued_history(instrument_id: int):
    """The result rows of an instrument's issued calibrations (those :func:`history` shows
    with a certificate number), as a WHERE clause over ResultItem joined to Calibration."""
    # correlated (EXISTS), so that each of the instrument's calibrations looks its
    # certificate up by ix_certificates_calibration_id: ``id IN (SELECT calibration_id FROM
    # certificates …)`` read the whole certificates table on every instrument page
    issued = select(Certificate.id).where(Certificate.calibration_id == Calibration.id,
                                          Certificate.number != "").exists()
    return (Calibration.instrument_id == int(instrument_id),
            Calibration.status.in_(_HISTORY_DONE), issued)


def _issued_table(store, instrument_id: int, limits: dict) -> tuple[dict, dict]:
    """What :func:`gonio.records.interval.propose` reads of the issued history, selected in
    the database: (the table of the items with limits: key → (days, value, U, k, lower,
    upper) oldest first; the issued calibrations counted per item, every item). The same
    table :func:`propose_interval` builds from :func:`history`, without the items' rows
    the proposal only counts (a triad's 81 items, 8 100 rows for 100 calibrations)."""
    where = _issued_history(instrument_id)
    join = (ResultItem.calibration_id == Calibration.id)
    with store.session() as s:
        conn = s.connection()        # plain rows: no ORM loading for a count and a few items
        counts = dict(conn.execute(select(ResultItem.key, func.count()).join(Calibration, join)
                                   .where(*where).group_by(ResultItem.key)).all())
        t0 = conn.execute(select(func.min(Calibration.performed_on))
                          .join(ResultItem, join).where(*where)).scalar()
        rows = conn.execute(
            select(ResultItem.key, Calibration.performed_on, ResultItem.value, ResultItem.U,
                   ResultItem.k).join(Calibration, join)
            .where(*where, ResultItem.key.in_(list(limits)))
            .order_by(Calibration.performed_on, Calibration.id)).all() if limits else []
    table: dict[str, list] = {}
    for key, day, value, U, k in rows:
        table.setdefault(key, []).append(((day - t0).days, value, U, k, *limits[key]))
    return table, counts


def history_points(store, instrument_id: int) -> int:
    """The calibrations the instrument's history plot shows: its longest item's history (the
    longest list of :func:`history`), counted in the database."""
    where = (Calibration.instrument_id == int(instrument_id),
             Calibration.status.in_(_HISTORY_DONE))
    with store.session() as s:
        return max(s.connection().execute(
            select(func.count()).select_from(ResultItem)
            .join(Calibration, ResultItem.calibration_id == Calibration.id)
            .where(*where).group_by(ResultItem.key)).scalars().all(), default=0)


def due_instruments(store, today: _dt.date | None = None, within_days: int = 30) -> list[dict]:
    """Instruments in use (not retired) due for recalibration within ``within_days`` or
    overdue: the last issued calibration's date plus the instrument's interval (else the
    specification's default)."""
    today = today or records_today(store)
    with store.session() as s:
        last = dict(s.execute(       # issued: it has a certificate (also while amended)
            select(Calibration.instrument_id, func.max(Calibration.performed_on))
            .where(Calibration.id.in_(select(Certificate.calibration_id)))
            .group_by(Calibration.instrument_id)).all())
        from sqlalchemy.orm import selectinload

        insts = s.scalars(select(Instrument).options(selectinload(Instrument.customer))
                          .where(Instrument.id.in_(list(last)),
                                 Instrument.retired_on.is_(None))).all()
        out = []
        for inst in insts:
            months = inst.interval_months or default_interval(inst.spec_key)[0]
            due = _add_months(last[inst.id], months)
            if (due - today).days <= within_days:
                out.append({"instrument_id": inst.id, "serial": inst.serial,
                            "model": inst.model, "customer": inst.customer.name,
                            "last": last[inst.id], "due": due,
                            "overdue": due < today})
    return sorted(out, key=lambda d: (d["due"], d["customer"], d["serial"]))


def _add_months(day: _dt.date, months: int) -> _dt.date:
    """``day`` plus ``months`` calendar months (the day clipped to the month's last); a date
    past the calendar's end (a record dated near 9999-12-31, refused at entry but possible in
    an old database) is the last date there is, so that lists built on it still answer."""
    import calendar

    y, m = divmod(day.month - 1 + int(months), 12)
    year, month = day.year + y, m + 1
    if year > _dt.MAXYEAR:
        return _dt.date.max
    return _dt.date(year, month, min(day.day, calendar.monthrange(year, month)[1]))
