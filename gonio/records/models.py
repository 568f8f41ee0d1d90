"""The laboratory's records as SQLAlchemy 2 tables (docs/records.md#model).

Every table is created by the Alembic migrations shipped in
``gonio/records/migrations`` (never by ``create_all`` outside tests), so a database
made by one gonio version is upgraded in place by the next.

Tables that must never change once written are guarded in the database itself by
triggers (the migrations create them, for SQLite and PostgreSQL alike):

* ``audit_events``  append-only: no UPDATE, no DELETE;
* ``certificates``  an issued certificate is frozen: no UPDATE, no DELETE;
* ``blobs``         a stored file's record is never changed (the bytes live in the
                    content-addressed store, named by their SHA-256);
* ``table_calibrations``  a registered table calibration is never changed or removed
                    (migration 0009): a correction is a new registration;
* ``table_calibration_withdrawals``  a table calibration's withdrawal (migration 0010):
                    no UPDATE, no DELETE;
* ``readings_contents``  a stored readings file's content digest (migration 0014) and the
                    stream it was reduced from (0015): no UPDATE, no DELETE.

Times are naive UTC ``datetime`` values; dates (due dates, calibration dates) are
``date`` values, calendar dates of the laboratory in its time zone (the setting
``timezone``, :func:`records_today`).
"""

from __future__ import annotations

import datetime as _dt

from sqlalchemy import (BigInteger, Boolean, Date, DateTime, Float, ForeignKey, Integer, String, Text,
                        UniqueConstraint)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, relationship


def utcnow() -> _dt.datetime:
    """Now, UTC, without tzinfo (what every DateTime column holds)."""
    return _dt.datetime.now(_dt.timezone.utc).replace(tzinfo=None)


def laboratory_zone(name: str = "") -> _dt.tzinfo | None:
    """The laboratory's time zone: the IANA name ``name`` (the records' setting
    ``timezone``, e.g. ``Asia/Shanghai``) read by :mod:`zoneinfo`, or None for "" (read as
    UTC by :func:`laboratory_date`; a store holds an explicit zone, :func:`machine_zone`).
    An unknown name is a GonioError naming the setting.

    >>> laboratory_zone("Asia/Shanghai")
    zoneinfo.ZoneInfo(key='Asia/Shanghai')
    >>> laboratory_zone("Mars/Olympus")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key timezone: 'Mars/Olympus' is not a time zone of the IANA database (e.g. Asia/Shanghai, Europe/Berlin, UTC)
    """
    import zoneinfo

    from gonio.errors import GonioError

    if not name:
        return None
    try:
        return zoneinfo.ZoneInfo(name)
    except (zoneinfo.ZoneInfoNotFoundError, ValueError, TypeError):
        raise GonioError(f"{name!r} is not a time zone of the IANA database (e.g. "
                         "Asia/Shanghai, Europe/Berlin, UTC)",
                         key="timezone") from None


def laboratory_date(at_utc: _dt.datetime, zone: str = "") -> _dt.date:
    """The laboratory's calendar date at the naive UTC time ``at_utc`` (what the records'
    times hold), in its time zone ``zone`` (:func:`laboratory_zone`; "" UTC, the same in
    every process: never the process's local zone). The one conversion from the records'
    UTC times to the laboratory's calendar dates
    (calibration date, due dates, date of issue): 23:30 UTC on 2026-12-01 is 2026-12-02 in
    Beijing and still 2026-12-01 in Los Angeles.

    >>> import datetime as dt
    >>> laboratory_date(dt.datetime(2026, 12, 1, 23, 30), "Asia/Shanghai")
    datetime.date(2026, 12, 2)
    >>> laboratory_date(dt.datetime(2026, 12, 2, 3, 30), "America/Los_Angeles")
    datetime.date(2026, 12, 1)
    """
    aware = at_utc.replace(tzinfo=_dt.timezone.utc)
    tz = laboratory_zone(zone)
    return aware.astimezone(_dt.timezone.utc if tz is None else tz).date()


def machine_zone() -> str:
    """This machine's IANA time zone name, written once into a store's setting ``timezone``
    (by ``gonio db init`` and the migration that brings a store without it up to date), so
    that every process on the store reads that one zone, never its own: ``TZ`` where it names
    an IANA zone, else ``/etc/timezone``, else the ``zoneinfo/`` link of ``/etc/localtime``;
    "UTC" where none of them names one (the settings page then shows UTC, which an
    administrator changes to the laboratory's zone)."""
    import os
    from pathlib import Path

    cands = [os.environ.get("TZ", "").lstrip(":")]
    try:
        cands.append(Path("/etc/timezone").read_text(encoding="utf-8").strip())
    except OSError:
        pass
    try:
        link = os.path.realpath("/etc/localtime")
        if "zoneinfo/" in link:
            cands.append(link.split("zoneinfo/", 1)[1])
    except OSError:
        pass
    for name in cands:
        if name and "/" not in name[:1] and _is_zone(name):
            return name
    return "UTC"


def _is_zone(name: str) -> bool:
    import zoneinfo

    try:
        zoneinfo.ZoneInfo(name)
    except (zoneinfo.ZoneInfoNotFoundError, ValueError, TypeError):
        return False
    return True


def records_zone(store) -> str:
    """The laboratory's time zone as the records ``store`` (a store, or an open SQLAlchemy
    session of one) hold it: the setting ``timezone`` (written at ``gonio db init`` and by the
    migration of an older store, :func:`machine_zone`; "UTC" where a store holds none)."""
    get = getattr(store, "get", None)
    if get is not None and hasattr(store, "scalars"):          # an open session
        row = store.get(Setting, "timezone")
    else:
        with store.session() as s:
            row = s.get(Setting, "timezone")
    return row.value if row is not None and row.value else "UTC"


def records_today(store) -> _dt.date:
    """The records' "today": the laboratory's calendar date now (:func:`laboratory_date` of
    :func:`utcnow` in the time zone of the setting ``timezone``, :func:`records_zone`). The
    records keep their times in UTC, but the dates they compare are the laboratory's calendar
    dates, so "today" is the laboratory's date — the one day every rule and page of the
    records compares a date with: a standard's or table calibration's due date when it is
    registered or edited (:func:`is_past_due`), the overdue marks of the web lists, the due
    list and recall, a calibration date not in the future (and the form's default and
    maximum), the register's "today", the date of issue. At 07:30 in Beijing (23:30 UTC the
    day before) the laboratory's date is today's, not yesterday's. ``store``: the records
    (a store or an open session)."""
    return laboratory_date(utcnow(), records_zone(store))


def is_past_due(due: _dt.date, today: _dt.date) -> bool:
    """Whether equipment due on ``due`` is past its due date on ``today`` (the laboratory's
    date, :func:`records_today`): due strictly before it. A standard due today is in time
    (ISO/IEC 17025 6.4.7: it may be used on its due date); the one rule of registering,
    editing and the lists' "overdue".

    >>> import datetime as dt
    >>> is_past_due(dt.date(2026, 12, 1), dt.date(2026, 12, 1))
    False
    >>> is_past_due(dt.date(2026, 11, 30), dt.date(2026, 12, 1))
    True
    """
    return due < today


class Base(DeclarativeBase):
    pass


#: Roles a user may hold (space-separated in ``users.roles``).
ROLES = ("technician", "reviewer", "admin")

#: A calibration's states, in workflow order (docs/records.md#workflow).
STATES = ("queued", "running", "failed", "computed", "drafting", "reviewed", "rejected", "approved",
          "issuing", "issued", "amending", "void")


class User(Base):
    __tablename__ = "users"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    username: Mapped[str] = mapped_column(String(64), unique=True)
    full_name: Mapped[str] = mapped_column(String(200), default="")
    password_hash: Mapped[str] = mapped_column(String(255))
    roles: Mapped[str] = mapped_column(String(100), default="technician")
    active: Mapped[bool] = mapped_column(Boolean, default=True)
    created_at: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)

    def has(self, role: str) -> bool:
        return role in self.roles.split()


class WebSession(Base):
    """A browser session: the cookie holds a random token, the table its SHA-256."""
    __tablename__ = "web_sessions"
    id: Mapped[str] = mapped_column(String(64), primary_key=True)
    user_id: Mapped[int] = mapped_column(ForeignKey("users.id"))
    csrf_token: Mapped[str] = mapped_column(String(64))
    created_at: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)
    expires_at: Mapped[_dt.datetime] = mapped_column(DateTime)
    user: Mapped[User] = relationship()


class LoginFailure(Base):
    """One failed login (throttling counts them per user name and per address)."""
    __tablename__ = "login_failures"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    username: Mapped[str] = mapped_column(String(64), index=True)
    address: Mapped[str] = mapped_column(String(64), index=True)
    at: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow, index=True)


class Setting(Base):
    """Laboratory-wide settings (name, address, accreditation, contact, decision rule)."""
    __tablename__ = "settings"
    key: Mapped[str] = mapped_column(String(64), primary_key=True)
    value: Mapped[str] = mapped_column(Text, default="")


class Blob(Base):
    """A file in the content-addressed store (bytes on disk under their SHA-256)."""
    __tablename__ = "blobs"
    sha256: Mapped[str] = mapped_column(String(64), primary_key=True)
    size: Mapped[int] = mapped_column(BigInteger)
    created_at: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)


class ReadingsContent(Base):
    """A stored readings file's content digest (:func:`gonio.formats.content.content_sha256`:
    its data apart from how they are written), kept when first computed; insert-only, as the
    file's own record (migration 0014). A file with no row: not yet digested, or no table.
    ``source_sha256``: the SHA-256 of the stream the readings were reduced from, where they
    name it (``# source_stream_sha256``; migration 0015), else NULL."""
    __tablename__ = "readings_contents"
    sha256: Mapped[str] = mapped_column(ForeignKey("blobs.sha256"), primary_key=True)
    content_sha256: Mapped[str] = mapped_column(String(64), index=True)
    source_sha256: Mapped[str | None] = mapped_column(String(64), index=True, nullable=True)


class Customer(Base):
    __tablename__ = "customers"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200), unique=True)
    address: Mapped[str] = mapped_column(Text, default="")
    created_at: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)
    #: retired (no new calibration uses it; its history stays); None: in use
    retired_on: Mapped[_dt.date | None] = mapped_column(Date, nullable=True)


class Instrument(Base):
    """An instrument under calibration: type, manufacturer, model, serial, owner."""
    __tablename__ = "instruments"
    __table_args__ = (UniqueConstraint("manufacturer", "model", "serial"),)
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    customer_id: Mapped[int] = mapped_column(ForeignKey("customers.id"), index=True)
    kind: Mapped[str] = mapped_column(String(200), default="")
    #: an optical gyro's type, "rlg" or "fog" ("" not stated): the laboratory file's
    #: ``[instrument] gyro_type`` its calibrations are computed with (the bound of K's
    #: temperature coefficient, and the identity check against the readings)
    gyro_type: Mapped[str] = mapped_column(String(8), default="", server_default="")
    manufacturer: Mapped[str] = mapped_column(String(200), default="")
    model: Mapped[str] = mapped_column(String(200), default="")
    serial: Mapped[str] = mapped_column(String(200))
    spec_key: Mapped[str] = mapped_column(String(64))
    #: the interval set by the laboratory (months); None: the specification's default
    interval_months: Mapped[int | None] = mapped_column(Integer, nullable=True)
    #: specification limits: JSON list of {item, lower, upper, mpe, unit, source}
    limits_json: Mapped[str] = mapped_column(Text, default="[]")
    created_at: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)
    #: retired (no new calibration uses it; its history stays); None: in use
    retired_on: Mapped[_dt.date | None] = mapped_column(Date, nullable=True)
    customer: Mapped[Customer] = relationship()


class Standard(Base):
    """Bench equipment / reference standard with its own calibration and due date."""
    __tablename__ = "standards"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200))
    identifier: Mapped[str] = mapped_column(String(200), unique=True)
    accuracy: Mapped[str] = mapped_column(String(200), default="")
    certificate: Mapped[str] = mapped_column(String(200), default="")
    traceability: Mapped[str] = mapped_column(String(200), default="")
    calibrated_on: Mapped[_dt.date | None] = mapped_column(Date, nullable=True)
    due_on: Mapped[_dt.date] = mapped_column(Date)
    created_at: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)
    #: retired (no new calibration uses it; its history stays); None: in use
    retired_on: Mapped[_dt.date | None] = mapped_column(Date, nullable=True)
    #: registered, or given a due date by an edit, already past its due date: the reason
    #: stated (out of service: refused in use until its recalibration is recorded;
    #: :func:`gonio.records.services.add_standard`, :func:`~gonio.records.services.
    #: update_standard`); "" registered in time
    out_of_service: Mapped[str] = mapped_column(Text, default="", server_default="")


class TableCalibration(Base):
    """The laboratory's register of its rotary tables' calibrations (ISO/IEC 17025 6.4.13:
    equipment records): one table calibration file, kept once by its SHA-256, of the table
    it belongs to (a registered standard), valid from ``valid_from`` (the table's calibration
    date) until ``due_on``; a later one of the same table supersedes it from its own
    ``valid_from`` (:func:`gonio.records.services.table_calibration_state`)."""
    __tablename__ = "table_calibrations"
    # one file per table and one start per day hold among the entries not withdrawn
    # (:func:`gonio.records.services.register_table_calibration`; migration 0010 dropped the
    # database's constraints, so a withdrawn entry's file or day can be registered again)
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    #: the rotary table, registered as a standard (bench equipment)
    standard_id: Mapped[int] = mapped_column(ForeignKey("standards.id"), index=True)
    sha256: Mapped[str] = mapped_column(ForeignKey("blobs.sha256"))
    #: the file's own name as it was registered (display and the run's file name only)
    name: Mapped[str] = mapped_column(String(255), default="")
    #: the table certificate's identifier (named in the refusals and on the pages)
    certificate: Mapped[str] = mapped_column(String(200), default="")
    valid_from: Mapped[_dt.date] = mapped_column(Date)
    due_on: Mapped[_dt.date] = mapped_column(Date)
    registered_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"), nullable=True)
    registered_at: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)
    standard: Mapped[Standard] = relationship()
    registered_by: Mapped[User | None] = relationship()


class TableCalibrationWithdrawal(Base):
    """A register entry withdrawn (migration 0010; frozen by triggers): why, who asked and
    when, who approved it — another person — and when it took effect. From then on the entry
    is in force on no day (:func:`gonio.records.services.table_calibration_state`); the
    calibrations already made with it keep it (their seal names it) and are listed as
    affected (:func:`gonio.records.services.withdrawal_affected`)."""
    __tablename__ = "table_calibration_withdrawals"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    table_calibration_id: Mapped[int] = mapped_column(ForeignKey("table_calibrations.id"),
                                                      unique=True)
    reason: Mapped[str] = mapped_column(Text)
    asked_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"), nullable=True)
    asked_at: Mapped[_dt.datetime] = mapped_column(DateTime)
    withdrawn_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"),
                                                        nullable=True)
    withdrawn_at: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)
    entry: Mapped[TableCalibration] = relationship()
    asked_by: Mapped[User | None] = relationship(foreign_keys=[asked_by_id])
    withdrawn_by: Mapped[User | None] = relationship(foreign_keys=[withdrawn_by_id])


class Calibration(Base):
    """One calibration of one instrument: inputs, state, result, people."""
    __tablename__ = "calibrations"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    instrument_id: Mapped[int] = mapped_column(ForeignKey("instruments.id"), index=True)
    spec_key: Mapped[str] = mapped_column(String(64))
    protocol: Mapped[str] = mapped_column(String(200), default="")
    protocol_sha256: Mapped[str | None] = mapped_column(ForeignKey("blobs.sha256"),
                                                        nullable=True)
    readings_sha256: Mapped[str] = mapped_column(ForeignKey("blobs.sha256"))
    readings_name: Mapped[str] = mapped_column(String(255), default="")
    #: a laboratory file (``--lab`` TOML) whose decision rule and limits this calibration
    #: is decided with, in place of the instrument's (None: the instrument's)
    lab_sha256: Mapped[str | None] = mapped_column(ForeignKey("blobs.sha256"), nullable=True)
    lab_name: Mapped[str] = mapped_column(String(255), default="")
    temperature_c: Mapped[float | None] = mapped_column(Float, nullable=True)
    humidity_pct: Mapped[float | None] = mapped_column(Float, nullable=True)
    #: the temperature and humidity as entered ("20" or "20.0": their digits state the
    #: reading's resolution), which the page, the laboratory file written for the
    #: calibration, its certificate and DCC print (migration 0012; None: no environment)
    temperature_text: Mapped[str | None] = mapped_column(String(40), nullable=True)
    humidity_text: Mapped[str | None] = mapped_column(String(40), nullable=True)
    #: where the environment came from: "" entered by a person, "readings" taken from the
    #: readings file's metadata (and stated so on the page and the certificate), "lab file"
    #: the laboratory file's [environment] it was computed with
    environment_from: Mapped[str] = mapped_column(String(16), default="", server_default="")
    place: Mapped[str] = mapped_column(String(200), default="")
    #: where it was performed, as the DCC's category (``gonio.formats.lab.LOCATIONS``)
    location: Mapped[str] = mapped_column(String(16), default="laboratory",
                                          server_default="laboratory")
    received_on: Mapped[_dt.date | None] = mapped_column(Date, nullable=True)
    performed_on: Mapped[_dt.date] = mapped_column(Date, index=True)
    status: Mapped[str] = mapped_column(String(16), index=True, default="queued")
    progress: Mapped[str] = mapped_column(String(200), default="")
    error: Mapped[str] = mapped_column(Text, default="")
    worker_host: Mapped[str] = mapped_column(String(200), default="")
    worker_pid: Mapped[int | None] = mapped_column(Integer, nullable=True)
    results_sha256: Mapped[str | None] = mapped_column(ForeignKey("blobs.sha256"),
                                                       nullable=True)
    created_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"), nullable=True)
    created_at: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)
    started_at: Mapped[_dt.datetime | None] = mapped_column(DateTime, nullable=True)
    finished_at: Mapped[_dt.datetime | None] = mapped_column(DateTime, nullable=True)
    reviewed_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"), nullable=True)
    reviewed_at: Mapped[_dt.datetime | None] = mapped_column(DateTime, nullable=True)
    review_comment: Mapped[str] = mapped_column(Text, default="")
    approved_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"), nullable=True)
    approved_at: Mapped[_dt.datetime | None] = mapped_column(DateTime, nullable=True)
    #: an amendment being issued: the certificate it replaces and why
    pending_replaces_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    pending_reason: Mapped[str] = mapped_column(Text, default="")
    #: the certificate number reserved when issuing starts (kept if the run fails)
    pending_number: Mapped[str] = mapped_column(String(32), default="")
    #: the seal (:func:`gonio.records.services.seal`) the reviewer signed, and the approver
    reviewed_seal: Mapped[str] = mapped_column(String(64), default="")
    approved_seal: Mapped[str] = mapped_column(String(64), default="")
    #: who asked for the amendment being issued (it is approved by another person)
    amend_requested_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"),
                                                              nullable=True)
    #: the register's table calibration this calibration used (its file is the calibration's
    #: ``table_calibration.csv``, sealed with the result); None: none, or an upload kept
    #: with this calibration only
    table_calibration_id: Mapped[int | None] = mapped_column(
        ForeignKey("table_calibrations.id"), nullable=True)
    instrument: Mapped[Instrument] = relationship()
    created_by: Mapped[User | None] = relationship(foreign_keys=[created_by_id])
    reviewed_by: Mapped[User | None] = relationship(foreign_keys=[reviewed_by_id])
    approved_by: Mapped[User | None] = relationship(foreign_keys=[approved_by_id])


class CalibrationStandard(Base):
    """A standard used in a calibration, with its due date as it was when used."""
    __tablename__ = "calibration_standards"
    calibration_id: Mapped[int] = mapped_column(ForeignKey("calibrations.id"),
                                                primary_key=True)
    standard_id: Mapped[int] = mapped_column(ForeignKey("standards.id"), primary_key=True)
    due_on_at_use: Mapped[_dt.date] = mapped_column(Date)
    standard: Mapped[Standard] = relationship()


class ResultItem(Base):
    """One item of a calibration's result (value, U), for history plots and lists."""
    __tablename__ = "result_items"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    calibration_id: Mapped[int] = mapped_column(ForeignKey("calibrations.id"), index=True)
    key: Mapped[str] = mapped_column(String(64))
    title: Mapped[str] = mapped_column(String(200), default="")
    clause: Mapped[str] = mapped_column(String(64), default="")
    unit: Mapped[str] = mapped_column(String(32), default="")
    measured: Mapped[bool] = mapped_column(Boolean, default=True)
    value: Mapped[float | None] = mapped_column(Float, nullable=True)
    U: Mapped[float | None] = mapped_column(Float, nullable=True)
    k: Mapped[float | None] = mapped_column(Float, nullable=True)
    #: how the stored results.json states the item, kept when the row is written (the
    #: history figure's bars then need no stored result read):
    #: ``gonio.records.results.stated_columns`` — "interval" (one coverage interval, its
    #: rounded ends ``interval_low``/``interval_high``), "value" (value ± U) or "none" (not
    #: stated); None: not read (the history reads the stored result for it)
    stated: Mapped[str | None] = mapped_column(String(8), nullable=True)
    interval_low: Mapped[float | None] = mapped_column(Float, nullable=True)
    interval_high: Mapped[float | None] = mapped_column(Float, nullable=True)


class CalibrationFile(Base):
    """A file a calibration run produced (draft certificate, DCC, results, summary)."""
    __tablename__ = "calibration_files"
    calibration_id: Mapped[int] = mapped_column(ForeignKey("calibrations.id"),
                                                primary_key=True)
    name: Mapped[str] = mapped_column(String(64), primary_key=True)
    sha256: Mapped[str] = mapped_column(ForeignKey("blobs.sha256"))


class CertificateCounter(Base):
    """The last certificate sequence number used in a year (GC-YYYY-NNNN)."""
    __tablename__ = "certificate_counters"
    year: Mapped[int] = mapped_column(Integer, primary_key=True)
    last: Mapped[int] = mapped_column(Integer, default=0)


class Certificate(Base):
    """An issued certificate: frozen (database triggers refuse UPDATE and DELETE)."""
    __tablename__ = "certificates"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    number: Mapped[str] = mapped_column(String(32), unique=True)
    calibration_id: Mapped[int] = mapped_column(ForeignKey("calibrations.id"), index=True)
    issued_at: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)
    issued_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"), nullable=True)
    replaces_id: Mapped[int | None] = mapped_column(ForeignKey("certificates.id"),
                                                    nullable=True)
    reason: Mapped[str] = mapped_column(Text, default="")
    html_sha256: Mapped[str] = mapped_column(ForeignKey("blobs.sha256"))
    pdf_sha256: Mapped[str] = mapped_column(ForeignKey("blobs.sha256"))
    dcc_sha256: Mapped[str | None] = mapped_column(ForeignKey("blobs.sha256"), nullable=True)
    results_sha256: Mapped[str] = mapped_column(ForeignKey("blobs.sha256"))
    #: the sealed result it was issued from (signed by reviewer and approver), the person
    #: who reviewed it (for an amendment: who asked for it) and the laboratory's minimum
    #: number of distinct people (creator, reviewer, approver) it was issued under
    seal_sha256: Mapped[str | None] = mapped_column(String(64), nullable=True)
    reviewed_by_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"), nullable=True)
    min_people: Mapped[int | None] = mapped_column(Integer, nullable=True)
    calibration: Mapped[Calibration] = relationship()
    replaces: Mapped["Certificate | None"] = relationship(remote_side=[id])
    issued_by: Mapped[User | None] = relationship(foreign_keys=[issued_by_id])
    reviewed_by: Mapped[User | None] = relationship(foreign_keys=[reviewed_by_id])


class AuditEvent(Base):
    """Append-only trail: who did what, when, from which record state to which."""
    __tablename__ = "audit_events"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    at: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow, index=True)
    user_id: Mapped[int | None] = mapped_column(ForeignKey("users.id"), nullable=True)
    username: Mapped[str] = mapped_column(String(64), default="")
    action: Mapped[str] = mapped_column(String(64))
    entity: Mapped[str] = mapped_column(String(64))
    entity_id: Mapped[str] = mapped_column(String(64), default="")
    before_json: Mapped[str] = mapped_column(Text, default="")
    after_json: Mapped[str] = mapped_column(Text, default="")
