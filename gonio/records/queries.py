"""Reading the records for lists and pages (what ``gonio serve`` shows), paginated so a
page costs the same with ten or ten thousand calibrations (indexed columns only).

Each function returns plain dicts or detached records and the total count.
"""

from __future__ import annotations

from sqlalchemy import func, or_, select
from sqlalchemy.orm import joinedload, selectinload

from gonio.records.models import (AuditEvent, Calibration, CalibrationFile, CalibrationStandard,
                                  Certificate, Customer, Instrument, ResultItem, Standard,
                                  TableCalibration, User)
from gonio.records.results import conformity_of, items_of, statements_of, stored_result


def _page(s, stmt, page: int, size: int):
    """(the page's rows of ``stmt``, the total). The page is chosen on the ids alone (the
    same filter and order, LIMIT/OFFSET in a subquery) and only its rows are read whole with
    their joined rows: PostgreSQL, without fresh statistics (after a bulk load or a
    restore), otherwise joined and sorted every row of the table, wide rows spilling to
    disk (100 ms for a calibrations page at 10 000 calibrations)."""
    total = s.scalar(select(func.count()).select_from(stmt.order_by(None).subquery()))
    model = stmt.column_descriptions[0]["entity"]
    ids = stmt.with_only_columns(model.id).limit(size).offset((page - 1) * size)
    rows = s.scalars(stmt.where(model.id.in_(ids))).all()
    return rows, total


def customers(store) -> list[Customer]:
    """Every customer, by name."""
    with store.session() as s:
        return s.scalars(select(Customer).order_by(Customer.name)).all()


def instruments(store, page: int = 1, size: int = 50, search: str = ""):
    """(instruments of the page with their customer, total); ``search`` matches serial,
    model or manufacturer (substring)."""
    stmt = select(Instrument).options(joinedload(Instrument.customer)).order_by(
        Instrument.id.desc())
    if search:
        like = f"%{search.replace('%', '').replace('_', '')}%"
        stmt = stmt.where(or_(Instrument.serial.like(like), Instrument.model.like(like),
                              Instrument.manufacturer.like(like)))
    with store.session() as s:
        return _page(s, stmt, page, size)


def instrument(store, inst_id: int):
    """(instrument with customer, its calibrations newest first with certificates)."""
    with store.session() as s:
        inst = s.scalar(select(Instrument).options(joinedload(Instrument.customer))
                        .where(Instrument.id == inst_id))
        if inst is None:
            return None, []
        cals = s.scalars(select(Calibration).options(joinedload(Calibration.created_by))
                         .where(Calibration.instrument_id == inst_id)
                         .order_by(Calibration.performed_on.desc(), Calibration.id.desc())
                         .limit(200)).all()
        certs = s.execute(select(Certificate.calibration_id, Certificate.id, Certificate.number)
                          .where(Certificate.calibration_id.in_([c.id for c in cals]))
                          .order_by(Certificate.id)).all()
    by_cal: dict[int, list] = {}
    for cid, cert_id, number in certs:
        by_cal.setdefault(cid, []).append((cert_id, number))
    return inst, [(c, by_cal.get(c.id, [])) for c in cals]


def calibrations(store, page: int = 1, size: int = 50, status: str = ""):
    """(calibrations of the page, newest first, with instrument and customer, total)."""
    stmt = select(Calibration).options(                  # many-to-one: one query
        joinedload(Calibration.instrument).joinedload(Instrument.customer),
        joinedload(Calibration.created_by)).order_by(Calibration.id.desc())
    if status:
        stmt = stmt.where(Calibration.status == status)
    with store.session() as s:
        return _page(s, stmt, page, size)


def active_work(store, size: int = 20):
    """(the calibrations a worker is working on now, newest first, at most ``size``, total):
    being computed (``running``), issued (``issuing``) or having their draft rendered
    again (``drafting``) — :data:`gonio.records.services.WORKING`."""
    from gonio.records.services import WORKING

    stmt = select(Calibration).options(
        joinedload(Calibration.instrument).joinedload(Instrument.customer),
        joinedload(Calibration.created_by)).where(Calibration.status.in_(WORKING)
                                                  ).order_by(Calibration.id.desc())
    with store.session() as s:
        return _page(s, stmt, 1, size)


#: The languages of the web's calibration and certificate pages (the certificate's own).
PAGE_LANGS = ("en", "zh")


def page_lang(value) -> str:
    """The page language asked for (``?lang=``): "zh", else "en".

    >>> page_lang("zh"), page_lang("ZH "), page_lang(None), page_lang("fr")
    ('zh', 'zh', 'en', 'en')
    """
    v = str(value or "").strip().lower()
    return v if v in PAGE_LANGS else "en"


def result_texts(doc, lang: str, stated: dict | None = None) -> dict:
    """The stored result's items as a page in ``lang`` states them, with the certificate's own
    texts (no table of the web's own): ``L`` the report's labels
    (:func:`gonio.report.i18n.labels`), ``titles`` each item's name as the certificate in
    ``lang`` names it (the specification's ``item_titles``, else the stored title),
    ``shown`` each statement's one line (:meth:`gonio.result.statement.Statement.text` in
    ``lang``, each negative number with U+2212; an item stated by a χ² interval with the ν
    that interval was computed with, :func:`statement_line`)."""
    from gonio.report.i18n import labels, minus_sign
    from gonio.specs import get

    stated = statements_of(doc) if stated is None else stated
    items = items_of(doc)
    titles = {}
    if isinstance(doc, dict) and isinstance(doc.get("items"), dict):
        try:
            hook = get(str(doc.get("spec"))).output_hook("item_titles")
        except Exception:            # an unknown specification: its stored titles
            hook = None
        titles = hook(doc, lang) if hook else {
            k: it.get("title", k) for k, it in doc["items"].items()}
    return {"lang": lang, "L": labels(lang), "titles": titles,
            "shown": {k: minus_sign(statement_line(st, items.get(k), k, lang))
                      for k, st in stated.items()}}


def statement_line(st, item: dict | None, key: str, lang: str = "en") -> str:
    """An item's statement ``st`` on one line as the records' pages print it: its text in
    ``lang``, and for an item stated by its interval the ν the certificate's ν_eff column
    and summary.txt print beside it: "; ν = 94" for a χ² interval (a standard deviation's,
    a dispersion's bound-condition limit), "; ν_eff = 7" for another whose coverage factor
    came from a ν_eff (a bound-condition interval value ± (a + k·u), a non-negative item's
    upper bound): the one rule's (:func:`gonio.report.stated.item_nums`, ``interval_nu``;
    :func:`gonio.result.statement.interval_nu_symbol`), never computed here.

    >>> from gonio.result.statement import item_statement
    >>> it = {"value": 0.2288, "unit": "°/h", "measured": True, "nonnegative": True,
    ...       "uncertainty": {"k": None, "nu_eff": 94.7, "coverage_probability": 0.95,
    ...                       "k_source": "chi-square", "interval": [0.0, 0.2721]}}
    >>> statement_line(item_statement(it), it, "B_s")
    '0.229 °/h; upper bound: ≤ 0.273 °/h (interval [0, 0.273], p = 95 %); ν = 94'
    >>> statement_line(item_statement(it), it, "B_s", "zh")[-9:]
    '%）；ν = 94'
    >>> it = {"value": 20.0, "unit": "s", "measured": True, "nonnegative": True,
    ...       "uncertainty": {"U": 32.35, "k": 2.3646, "nu_eff": 7.005,
    ...                       "coverage_probability": 0.95, "k_source": "welch-satterthwaite"}}
    >>> statement_line(item_statement(it), it, "warmup_time")
    '20 s; upper bound: ≤ 53 s (interval [0, 53], p = 95 %); ν_eff = 7'
    """
    text = st.text(lang)
    if not isinstance(item, dict) or st.interval is None:
        return text
    from gonio.errors import GonioError
    from gonio.report.stated import item_nums
    from gonio.result.statement import interval_nu_symbol

    try:
        nu = item_nums(item, f"items.{key}")["interval_nu"]
    except (GonioError, TypeError, ValueError):
        return text
    if nu is None:
        return text
    symbol = interval_nu_symbol((item.get("uncertainty") or {}).get("k_source"))
    return f"{text}{'；' if lang == 'zh' else '; '}{symbol} = {nu}"


def calibration_page(store, cal_id: int, lang: str = "en") -> dict | None:
    """Everything the calibration page shows (``lang``: its results in the certificate's
    language, :func:`result_texts`: ``L``, ``titles``, ``shown``); ``stated``: each item's statement
    (:func:`gonio.records.results.stated_items`, from the sealed result only, which is read
    once for the page), ``shown``: its one line as the page prints it (each negative number
    with U+2212, as the certificate), ``conformity``: the stored decisions as the certificate
    states them (:func:`gonio.records.results.conformity_of`, from the same sealed result),
    ``virtual``: the virtual-bench mark
    (:func:`virtual_mark`) or "", ``identity``: the contradictions between the readings and
    the laboratory file the run proceeded with (:func:`identity_findings`); ``place`` is the
    place of calibration as the certificate states it (the one entered, else the laboratory's); ``missing``: what it
    lacks for its review (:func:`gonio.records.services.missing_for_review`) while
    ``attachable`` (standards and environment may still be attached; ``all_standards`` to
    choose from)."""
    from gonio.errors import GonioError
    from gonio.records.services import (INPUT_PREFIX, OPTION_PREFIX, TABLE_CALIBRATION,
                                        calibration, seal, settings, table_calibration_name)

    try:
        cal = calibration(store, cal_id)
    except Exception:
        return None
    with store.session() as s:
        items = s.scalars(select(ResultItem).where(ResultItem.calibration_id == cal_id)
                          .order_by(ResultItem.id)).all()
        rows = s.scalars(select(CalibrationFile).where(
            CalibrationFile.calibration_id == cal_id).order_by(CalibrationFile.name)).all()
        files = [f.name for f in rows            # the run's input files: not a page's
                 if not f.name.startswith((INPUT_PREFIX, OPTION_PREFIX))]
        table_sha = next((f.sha256 for f in rows if f.name == TABLE_CALIBRATION), None)
        table_name = table_calibration_name(s, cal_id) if table_sha else ""
        entry = s.scalar(select(TableCalibration).options(
            selectinload(TableCalibration.standard)).where(
            TableCalibration.id == cal.table_calibration_id)) \
            if cal.table_calibration_id is not None else None
        from gonio.records.services import withdrawals
        withdrawn = withdrawals(s, [entry.id]).get(entry.id) if entry is not None else None
        stds = s.execute(select(Standard, CalibrationStandard.due_on_at_use)
                         .join(CalibrationStandard,
                               CalibrationStandard.standard_id == Standard.id)
                         .where(CalibrationStandard.calibration_id == cal_id)).all()
        certs = s.scalars(select(Certificate).where(Certificate.calibration_id == cal_id)
                          .order_by(Certificate.id)).all()
    from gonio.records.services import ATTACHABLE, missing_for_review

    with store.session() as s:
        missing = missing_for_review(s, cal) if cal.status in ATTACHABLE else []
    try:
        sealed, broken = seal(store, cal_id), ""
    except GonioError as exc:                 # no result yet, or one that no longer matches
        sealed, broken = "", str(exc) if cal.results_sha256 else ""
    doc = stored_result(store, cal.results_sha256) if sealed else None   # read once
    stated = statements_of(doc) if sealed else {}
    texts = result_texts(doc, lang, stated)
    return {"cal": cal, "items": items, "files": files, "standards": stds, "certs": certs,
            "seal": sealed, "seal_error": broken,
            "place": cal.place or settings(store)["lab_place"], "missing": missing,
            "attachable": cal.status in ATTACHABLE,
            "all_standards": standards(store) if cal.status in ATTACHABLE else [],
            "stated": stated, **texts,
            "conformity": conformity_of(doc if sealed else None, lang, texts["titles"]),
            "virtual": virtual_mark(store, cal.results_sha256, cal.readings_sha256, doc=doc),
            "table_calibration": table_calibration_used(table_sha, doc, table_name),
            "file_names": {TABLE_CALIBRATION: table_name} if table_sha else {},
            "register_entry": entry,
            # the entry withdrawn after this calibration was made with it: kept (sealed),
            # flagged as affected (docs/records.md, the register)
            "register_withdrawal": withdrawn,
            "identity": identity_findings(store, cal.results_sha256, doc=doc) if sealed else []}


def identity_findings(store, results_sha256: str, doc: dict | None = None) -> list[str]:
    """The messages of the stored result's identity findings: a contradiction between the
    readings' metadata and the laboratory file (serial, model, temperature …) that the
    laboratory chose to proceed with (:func:`gonio.pipeline.identity.check_identity`), which
    its certificate states as a finding; ``doc``: the stored result already read."""
    from gonio.errors import GonioError
    from gonio.pipeline.identity import MISMATCH_CODE

    if doc is None:
        try:
            doc = stored_result(store, results_sha256)
        except (GonioError, ValueError, RecursionError):
            return []
    found = doc.get("findings") if isinstance(doc, dict) else None
    return [str(f.get("message", "")) for f in found or []
            if isinstance(f, dict) and f.get("code") == MISMATCH_CODE]


def virtual_mark(store, results_sha256: str | None, readings_sha256: str | None = None,
                 doc: dict | None = None) -> str:
    """The virtual-bench mark of a calibration's or a certificate's page, as the certificate
    words it (:func:`gonio.report.provenance.virtual_lines`: banner, notice, bench and seed),
    or "": from the provenance of the stored result
    (:func:`gonio.formats.provenance.result_provenance`), else, before there is one, of the
    readings' own metadata (``doc``: the stored result already read). Nothing switches it
    off."""
    from gonio.errors import GonioError
    from gonio.formats.provenance import result_provenance
    from gonio.report.i18n import labels
    from gonio.report.provenance import virtual_lines

    res = doc
    if res is None and results_sha256:
        try:
            res = stored_result(store, results_sha256)
        except (GonioError, ValueError, RecursionError):
            res = None
    if not isinstance(res, dict) and readings_sha256:
        from gonio.records.submission import readings_facts
        try:
            res = {"metadata": readings_facts(store, readings_sha256,
                                                  conditions=False)["metadata"]}
        except GonioError:
            return ""
    if not isinstance(res, dict) or not result_provenance(res)["virtual"]:
        return ""
    L = labels("en")
    return " ".join([L["virtual"] + "."] + virtual_lines(res, L))


#: readings SHA-256 → whether the readings are the virtual bench's, per blob folder: a stored
#: file never changes under its SHA-256, so its answer is read once (its metadata header, and
#: its values' watermark read block by block up to its first 400 000 rows)
_VIRTUAL_READINGS: dict[tuple[str, str], bool] = {}


def virtual_readings(store, readings_sha256: str | None) -> bool:
    """Whether a calibration's stored readings are the virtual bench's, from their own
    metadata (:func:`gonio.formats.provenance.provenance`: ``# bench:``, ``# seed:``,
    ``# generator: gonio``) or the watermark in their values
    (:func:`gonio.formats.provenance.file_provenance`: read line by line, or a Parquet
    stream batch by batch, up to its first 400 000 rows), as the lists mark each calibration; read
    once per stored file and kept (the answer of a content-addressed file cannot change). A
    file that is missing or unreadable is not marked (and not kept: its calibration's own
    page says why)."""
    from gonio.errors import GonioError
    from gonio.formats.provenance import readings_provenance
    from gonio.records.blobs import blob_path
    from gonio.records.compute import readings_file, readings_suffix

    if not readings_sha256:
        return False
    key = (str(store.blob_root), readings_sha256)
    got = _VIRTUAL_READINGS.get(key)
    if got is None:
        src = blob_path(store.blob_root, readings_sha256)
        try:
            with open(src, "rb") as fh:
                parquet = readings_suffix(fh.read(4)) == ".parquet"
            if parquet:                 # a stream is read by its name's suffix: a link
                with readings_file(src) as path:
                    got = bool(readings_provenance(path)["virtual"])
            else:                       # a CSV file's header, read in place (a temporary
                got = bool(readings_provenance(src)["virtual"])   # link costs ~10x more)
        except (GonioError, OSError, ValueError, UnicodeDecodeError):
            return False
        _VIRTUAL_READINGS[key] = got
    return got


#: results.json SHA-256 → whether the stored result's provenance is the virtual bench's
#: (content-addressed: read once per blob folder)
_VIRTUAL_RESULTS: dict[tuple[str, str], bool] = {}


def virtual_calibration(store, readings_sha256: str | None,
                        results_sha256: str | None = None) -> bool:
    """Whether a calibration is the virtual bench's, as the lists mark it: its stored readings
    (:func:`virtual_readings`), or the provenance of its stored result
    (:func:`gonio.formats.provenance.result_provenance`), which also holds the evidence of
    the files the readings name (a triad's ``thermal.csv`` with its ``# bench:`` lines beside
    readings that show none) — the calibration's own page marks it by the same result."""
    if virtual_readings(store, readings_sha256):
        return True
    if not results_sha256:
        return False
    from gonio.errors import GonioError
    from gonio.formats.provenance import result_provenance

    key = (str(store.blob_root), results_sha256)
    got = _VIRTUAL_RESULTS.get(key)
    if got is None:
        try:
            doc = stored_result(store, results_sha256)
        except (GonioError, OSError, ValueError, RecursionError):
            return False
        got = isinstance(doc, dict) and bool(result_provenance(doc)["virtual"])
        _VIRTUAL_RESULTS[key] = got
    return got


def certificates(store, page: int = 1, size: int = 50):
    """(issued certificates, newest first, total)."""
    stmt = select(Certificate).options(
        selectinload(Certificate.calibration).selectinload(Calibration.instrument)
        .selectinload(Instrument.customer), selectinload(Certificate.replaces)
    ).order_by(Certificate.id.desc())
    with store.session() as s:
        return _page(s, stmt, page, size)


def certificate(store, cert_id: int):
    """A certificate with its calibration, and the certificate that replaced it (or None)."""
    with store.session() as s:
        cert = s.scalar(select(Certificate).options(
            selectinload(Certificate.calibration).selectinload(Calibration.instrument)
            .selectinload(Instrument.customer), selectinload(Certificate.replaces),
            selectinload(Certificate.issued_by), selectinload(Certificate.reviewed_by))
            .where(Certificate.id == cert_id))
        newer = s.scalar(select(Certificate).where(Certificate.replaces_id == cert_id)) \
            if cert else None
    return cert, newer


def table_calibration_used(sha256: str | None, doc: dict | None,
                           name: str = "") -> dict | None:
    """The calibration's stored table calibration as its page shows it: ``{"sha256", "name",
    "items": [(item key, its title)…]}`` — ``name`` the file's own name as it was uploaded
    (:func:`gonio.records.services.table_calibration_name`; the records keep the bytes as
    ``table_calibration.csv``), the items whose results.json ``details`` record this file's
    SHA-256 (corrected by it; [] before the run or where none was) — or None.

    >>> table_calibration_used("ab", {"items": {"K": {"title": "Scale factor", "details":
    ...     {"table_calibration": {"sha256": "ab"}}}, "R": {"details": {}}}}, "RT-07.csv")
    {'sha256': 'ab', 'name': 'RT-07.csv', 'items': [('K', 'Scale factor')]}
    """
    if sha256 is None:
        return None
    raw = (doc or {}).get("items") or {}
    pairs = raw.items() if isinstance(raw, dict) else (
        (it.get("key"), it) for it in raw if isinstance(it, dict))
    items = [(k, it.get("title") or k) for k, it in pairs
             if isinstance(it, dict) and ((it.get("details") or {}).get("table_calibration")
                                          or {}).get("sha256") == sha256]
    return {"sha256": sha256, "name": name or "table_calibration.csv", "items": items}


def standards(store):
    """Every standard, soonest due first."""
    with store.session() as s:
        return s.scalars(select(Standard).order_by(Standard.due_on)).all()


def standard_history(store, std_id: int, page: int = 1, size: int = 50) -> dict | None:
    """A reference standard's history (None when there is no such standard): ``standard``;
    ``changes``, its recorded states over time from the audit trail, oldest first (each
    ``{"at", "username", "action", "certificate", "calibrated_on", "due_on", "retired_on"}``:
    its registration, each recalibration recorded with its certificate and due date, a
    retirement); ``uses``, the calibrations that used it, newest first, a page of them
    (``{"calibration_id", "performed_on", "status", "serial", "model", "customer",
    "due_on_at_use", "certificates"}``) and ``total`` of them."""
    import json

    with store.session() as s:
        std = s.get(Standard, int(std_id))
        if std is None:
            return None
        events = s.scalars(select(AuditEvent).where(AuditEvent.entity == "standard",
                                                    AuditEvent.entity_id == str(std.id))
                           .order_by(AuditEvent.id)).all()
        stmt = (select(CalibrationStandard.calibration_id, Calibration.performed_on,
                       Calibration.status, Instrument.serial, Instrument.model, Customer.name,
                       CalibrationStandard.due_on_at_use, Calibration.readings_sha256)
                .join(Calibration, CalibrationStandard.calibration_id == Calibration.id)
                .join(Instrument, Calibration.instrument_id == Instrument.id)
                .join(Customer, Instrument.customer_id == Customer.id)
                .where(CalibrationStandard.standard_id == std.id)
                .order_by(Calibration.performed_on.desc(), Calibration.id.desc()))
        total = s.scalar(select(func.count()).select_from(stmt.order_by(None).subquery()))
        rows = s.execute(stmt.limit(size).offset((page - 1) * size)).all()
        numbers: dict[int, list] = {}
        for cid, cert_id, number in s.execute(
                select(Certificate.calibration_id, Certificate.id, Certificate.number)
                .where(Certificate.calibration_id.in_([r[0] for r in rows]))
                .order_by(Certificate.id)):
            numbers.setdefault(cid, []).append((cert_id, number))
    keys = ("certificate", "calibrated_on", "due_on", "retired_on")
    changes = []
    for e in events:
        after = json.loads(e.after_json or "{}")
        changes.append({"at": e.at, "username": e.username, "action": e.action,
                        **{k: after.get(k) for k in keys}})
    uses = [{"calibration_id": r[0], "performed_on": r[1], "status": r[2], "serial": r[3],
             "model": r[4], "customer": r[5], "due_on_at_use": r[6], "readings_sha256": r[7],
             "certificates": numbers.get(r[0], [])} for r in rows]
    return {"standard": std, "changes": changes, "uses": uses, "total": total}


def due(store, page: int = 1, size: int = 50, search: str = "", within_days: int = 30,
        customer: str = "", today=None) -> tuple[list[dict], int]:
    """(a page of the instruments due for recalibration within ``within_days`` or overdue,
    soonest due first, their total) — :func:`gonio.records.services.due_instruments` —,
    ``search`` matching serial, model or customer (substring, any case), ``customer`` one
    customer's exactly (a recall list)."""
    from gonio.records.services import due_instruments

    rows = due_instruments(store, today, within_days)
    if customer:
        rows = [r for r in rows if r["customer"] == customer]
    if search:
        needle = search.casefold()
        rows = [r for r in rows if any(needle in str(r[k]).casefold()
                                       for k in ("serial", "model", "customer"))]
    return rows[(page - 1) * size: page * size], len(rows)


def recall(store, customer: str = "", within_days: int = 30, today=None) -> list[dict]:
    """Recall notices: per customer (one, or every customer with something due), the
    customer's name and address and its instruments due within ``within_days`` or overdue
    (:func:`due`), with the number of the last certificate issued for each."""
    rows, _ = due(store, 1, 10**7, "", within_days, customer, today)
    with store.session() as s:
        addresses = dict(s.execute(select(Customer.name, Customer.address)).all())
        last_cert = dict(s.execute(
            select(Calibration.instrument_id, func.max(Certificate.number))
            .join(Calibration, Certificate.calibration_id == Calibration.id)
            .where(Calibration.instrument_id.in_([r["instrument_id"] for r in rows]))
            .group_by(Calibration.instrument_id)).all())
    out: dict[str, dict] = {}
    for r in rows:
        notice = out.setdefault(r["customer"], {"customer": r["customer"], "address":
                                                addresses.get(r["customer"], ""), "rows": []})
        notice["rows"].append(dict(r, certificate=last_cert.get(r["instrument_id"], "")))
    return [out[k] for k in sorted(out)]


def users(store):
    with store.session() as s:
        return s.scalars(select(User).order_by(User.username)).all()


def active_admins(store) -> list[str]:
    """The user names of the active users holding the admin role, sorted."""
    return [u.username for u in users(store) if u.active and "admin" in u.roles.split()]


def audit_events(store, page: int = 1, size: int = 100, entity: str = "",
                 entity_id: str = "", username: str = ""):
    """(audit events newest first, total), filtered by record (``entity`` such as
    "calibration", and its id) and person (user name) where given."""
    stmt = select(AuditEvent).order_by(AuditEvent.id.desc())
    for col, v in ((AuditEvent.entity, entity), (AuditEvent.entity_id, entity_id),
                   (AuditEvent.username, username)):
        if v:
            stmt = stmt.where(col == v)
    with store.session() as s:
        return _page(s, stmt, page, size)


def audit_changes(before_json: str, after_json: str) -> list[tuple[str, str, str]]:
    """What an audit event changed, to be read: (field, before, after) for every field whose
    value, as written here, differs between the event's two recorded states, by field name;
    a field one state lacks (or has as null) is "" there, a value that is not text is written
    as JSON. A state that is not a
    JSON object is given whole as the one field "(state)"."""
    import json

    def load(doc: str):
        try:
            got = json.loads(doc or "{}")
        except ValueError:
            return None
        return got if isinstance(got, dict) else None

    def shown(v) -> str:
        return "" if v is None else v if isinstance(v, str) else json.dumps(v, sort_keys=True)

    before, after = load(before_json), load(after_json)
    if before is None or after is None:
        return [("(state)", before_json, after_json)]
    pairs = [(k, shown(before.get(k)), shown(after.get(k)))
             for k in sorted(set(before) | set(after))]
    return [(k, was, now) for k, was, now in pairs if was != now]


#: The lists ``gonio serve`` exports as CSV: name → (header, rows(store, params)).
def export_rows(store, name: str, params: dict) -> tuple[list[str], list[list]] | None:
    """A whole list as (header, rows) for its CSV export, or None for an unknown list;
    ``params``: the list's filters (audit: entity, entity_id, username; due: q,
    within_days, customer as :func:`due` takes them)."""
    big = 10**7
    if name == "customers":
        return (["id", "name", "address", "retired_on"],
                [[c.id, c.name, c.address, c.retired_on] for c in customers(store)])
    if name == "instruments":
        rows, _ = instruments(store, 1, big)
        return (["id", "customer", "type", "manufacturer", "model", "serial", "specification",
                 "interval_months", "retired_on", "gyro_type"],
                [[i.id, i.customer.name, i.kind, i.manufacturer, i.model, i.serial, i.spec_key,
                  i.interval_months, i.retired_on, i.gyro_type] for i in rows])
    if name == "standards":
        return (["id", "name", "identifier", "accuracy", "certificate", "traceability",
                 "calibrated_on", "due_on", "retired_on", "out_of_service"],
                [[x.id, x.name, x.identifier, x.accuracy, x.certificate, x.traceability,
                  x.calibrated_on, x.due_on, x.retired_on, x.out_of_service or ""]
                 for x in standards(store)])
    if name == "calibrations":
        rows, _ = calibrations(store, 1, big, params.get("status", ""))
        return (["id", "customer", "instrument_serial", "specification", "performed_on",
                 "status", "created_by", "error", "virtual_bench"],
                [[c.id, c.instrument.customer.name, c.instrument.serial, c.spec_key,
                  c.performed_on, c.status, c.created_by.username if c.created_by else "",
                  c.error, "yes" if virtual_calibration(store, c.readings_sha256,
                                                        c.results_sha256) else ""]
                 for c in rows])
    if name == "certificates":
        rows, _ = certificates(store, 1, big)
        return (["number", "issued_at", "calibration", "customer", "instrument_serial",
                 "replaces", "reason", "seal_sha256", "pdf_sha256", "virtual_bench"],
                [[c.number, c.issued_at, c.calibration_id, c.calibration.instrument.customer
                  .name, c.calibration.instrument.serial, c.replaces.number if c.replaces
                  else "", c.reason, c.seal_sha256, c.pdf_sha256,
                  "yes" if virtual_calibration(store, c.calibration.readings_sha256,
                                               c.calibration.results_sha256) else ""]
                 for c in rows])
    if name == "due":
        rows, _ = due(store, 1, big, params.get("q", ""), params.get("within_days", 30),
                      params.get("customer", ""))
        return (["customer", "instrument", "model", "serial", "last_calibration", "due",
                 "overdue"],
                [[r["customer"], r["instrument_id"], r["model"], r["serial"], r["last"],
                  r["due"], "yes" if r["overdue"] else "no"] for r in rows])
    if name == "table_calibrations":
        from gonio.records.services import table_calibrations

        rows = table_calibrations(store)

        def utc(at):                                                     # stored naive UTC
            return at.isoformat(timespec="seconds") + "Z" if at is not None else ""

        def name(u):
            return u.username if u is not None else ""

        return (["id", "table", "certificate", "file", "sha256", "valid_from", "due_on",
                 "state_today", "used_by", "registered_by", "registered_at", "withdrawn_at",
                 "withdrawn_by", "withdrawal_asked_by", "withdrawal_reason", "affected"],
                [[e.id, e.standard.identifier, e.certificate, e.name, e.sha256, e.valid_from,
                  e.due_on, r["state"] or "in force", r["used"], name(e.registered_by),
                  utc(e.registered_at), utc(w.withdrawn_at) if w else "",
                  name(w.withdrawn_by) if w else "", name(w.asked_by) if w else "",
                  w.reason if w else "", " ".join(str(i) for i in r["affected"])]
                 for r in rows for e, w in [(r["entry"], r["withdrawal"])]])
    if name == "audit":
        rows, _ = audit_events(store, 1, big, params.get("entity", ""),
                               params.get("entity_id", ""), params.get("username", ""))
        return (["id", "at", "user", "action", "entity", "entity_id", "before", "after"],
                [[e.id, e.at, e.username, e.action, e.entity, e.entity_id, e.before_json,
                  e.after_json] for e in rows])
    return None


def counts_by_status(store) -> dict:
    """How many calibrations are in each state."""
    with store.session() as s:
        return dict(s.execute(select(Calibration.status, func.count())
                              .group_by(Calibration.status)).all())
