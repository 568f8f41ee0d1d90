"""The pages and forms of ``gonio serve`` (each a few lines over gonio.records)."""

from __future__ import annotations

import datetime as _dt
import hashlib
import hmac
import html
import re
from pathlib import Path

from fastapi import APIRouter, Request
from fastapi.responses import HTMLResponse, RedirectResponse, Response

from gonio.errors import GonioError, TooManyAttemptsError
from gonio.records import auth, blobs, queries, services, submission
from gonio.records.models import records_today
from gonio.web.common import (COOKIE, FILE_TYPES, LOGIN_COOKIE, PAGE, Forbidden, Session,
                              file_response, form, page_of, render, wake)
from gonio.web.front import STATES, login_response

router = APIRouter()


def register(app) -> None:
    app.include_router(router)


def _back(url: str) -> RedirectResponse:
    return RedirectResponse(url, status_code=303)


def _store(request: Request):
    return request.app.state.store


# --------------------------------------------------------------------------- login


@router.get("/login")
def login_page(request: Request):
    return login_response(request.app.state.templates, request)


@router.post("/login")
async def login(request: Request):
    data = await request.form(max_files=0, max_fields=10, max_part_size=4096)
    if not auth.same_token(data.get("csrf"), request.cookies.get(LOGIN_COOKIE)):
        raise Forbidden()
    address = request.client.host if request.client else ""
    try:
        user = auth.authenticate(_store(request), str(data.get("username", ""))[:200],
                                 str(data.get("password", ""))[:2000], address)
    except GonioError as exc:
        code = 429 if isinstance(exc, TooManyAttemptsError) else 401
        return login_response(request.app.state.templates, request, status_code=code,
                              error=str(exc).split(": ", 1)[-1])
    token, _ = auth.open_session(_store(request), user)
    r = _back("/")
    r.set_cookie(COOKIE, token, httponly=True, samesite="strict",
                 max_age=int(auth.SESSION_LIFETIME.total_seconds()))
    r.delete_cookie(LOGIN_COOKIE)
    return r


@router.post("/logout")
async def logout(request: Request, session: Session):
    user, csrf = session
    await form(request, csrf)
    auth.close_session(_store(request), request.cookies.get(COOKIE))
    r = _back("/login")
    r.delete_cookie(COOKIE)
    return r


# --------------------------------------------------------------------------- dashboard


@router.get("/")
def dashboard(request: Request, session: Session):
    user, csrf = session
    store = _store(request)
    review, _ = queries.calibrations(store, 1, 20, "computed")
    approve, _ = queries.calibrations(store, 1, 20, "reviewed")
    active, n_active = queries.active_work(store)
    failed, _ = queries.calibrations(store, 1, 20, "failed")
    due, n_due = queries.due(store, 1, 20)
    return render(request, "dashboard.html", user, csrf, counts=queries.counts_by_status(store),
                  due=due, n_due=n_due, review=review, approve=approve,
                  active=active, n_active=n_active, failed=failed,
                  today=records_today(_store(request)))


# --------------------------------------------------------------------------- customers


@router.get("/customers")
def customers_page(request: Request, session: Session):
    user, csrf = session
    return render(request, "customers.html", user, csrf,
                  customers=queries.customers(_store(request)),
                  error=request.query_params.get("error", "")[:300])


@router.post("/customers")
async def customers_add(request: Request, session: Session):
    user, csrf = session
    data = await form(request, csrf)
    try:
        services.add_customer(_store(request), user, data.get("name"), data.get("address"))
    except GonioError as exc:
        return render(request, "customers.html", user, csrf, status_code=400, error=str(exc),
                      customers=queries.customers(_store(request)))
    return _back("/customers")


def _retire_of(data) -> bool | None:
    """The edit forms' state: "retired" → True, "in use" → False, absent → unchanged."""
    v = data.get("state")
    return None if v is None else v == "retired"


async def _edit(request: Request, session: tuple, back: str, do) -> Response:
    """An edit form: ``do(user, data)``, then back to ``back`` (with the error if refused)."""
    from urllib.parse import quote

    user, csrf = session
    data = await form(request, csrf)
    try:
        do(user, data)
    except GonioError as exc:
        return _back(f"{back}?error={quote(str(exc)[:300])}")
    return _back(back)


@router.post("/customers/{cust_id}/edit")
async def customer_edit(request: Request, session: Session, cust_id: int):
    return await _edit(request, session, "/customers", lambda u, d: services.update_customer(
        _store(request), u, cust_id, name=d.get("name"), address=d.get("address"),
        retire=_retire_of(d)))


@router.post("/standards/{std_id}/edit")
async def standard_edit(request: Request, session: Session, std_id: int):
    return await _edit(request, session, "/standards", lambda u, d: services.update_standard(
        _store(request), u, std_id, **{k: d.get(k) for k in (
            "name", "accuracy", "certificate", "traceability", "calibrated_on", "due_on",
            "out_of_service")},
        retire=_retire_of(d)))


@router.post("/instruments/{inst_id}/edit")
async def instrument_edit(request: Request, session: Session, inst_id: int):
    def do(u, d):
        return services.update_instrument(
            _store(request), u, inst_id, customer_id=d.get("customer_id") and _int(
                d.get("customer_id"), "customer"),
            **{k: d.get(k) for k in ("kind", "manufacturer", "model", "serial", "gyro_type")},
            interval_months=d.get("interval_months", ""), retire=_retire_of(d))
    return await _edit(request, session, f"/instruments/{inst_id}", do)


# --------------------------------------------------------------------------- instruments


def _instruments(request, user, csrf, status_code=200, error=""):
    store = _store(request)
    page = page_of(request)
    search = request.query_params.get("q", "")[:100]
    rows, total = queries.instruments(store, page, PAGE, search)
    from gonio.specs import available
    return render(request, "instruments.html", user, csrf, status_code=status_code,
                  error=error, instruments=rows, total=total, page=page, size=PAGE, q=search,
                  customers=queries.customers(store), specs=list(available()))


@router.get("/instruments")
def instruments_page(request: Request, session: Session):
    user, csrf = session
    return _instruments(request, user, csrf)


@router.post("/instruments")
async def instruments_add(request: Request, session: Session):
    user, csrf = session
    data = await form(request, csrf)
    try:
        inst = services.register_instrument(
            _store(request), user, customer_id=_int(data.get("customer_id"), "customer"),
            serial=data.get("serial"), spec_key=data.get("spec_key"), kind=data.get("kind"),
            manufacturer=data.get("manufacturer"), model=data.get("model"),
            gyro_type=data.get("gyro_type"),
            interval_months=data.get("interval_months"), limits=_limits_from(data))
    except GonioError as exc:
        return _instruments(request, user, csrf, 400, str(exc))
    return _back(f"/instruments/{inst.id}")


def _int(v, name: str) -> int:
    try:
        return int(str(v))
    except (TypeError, ValueError):
        raise GonioError("not a number", key=name) from None


def _limits_from(data) -> list[dict]:
    """Up to three limit rows of the form: item, lower, upper, mpe, unit, source (a unit
    left empty is not given: the limit is in the item's unit; one given is checked as the
    laboratory file's, :func:`gonio.records.services.check_limits`)."""
    out = []
    for i in range(3):
        item = str(data.get(f"limit_item_{i}", "") or "").strip()
        if not item:
            if any(str(data.get(f"limit_{k}_{i}", "") or "").strip()
                   for k in ("lower", "upper", "mpe", "unit", "source")):
                raise GonioError("a limit needs its item key", key=f"limit {i + 1}")
            continue
        row = {"item": item, "source": str(data.get(f"limit_source_{i}", "") or "")}
        unit = str(data.get(f"limit_unit_{i}", "") or "").strip()
        if unit:
            row["unit"] = unit
        for k in ("lower", "upper", "mpe"):
            v = services.number_value(data.get(f"limit_{k}_{i}"), f"limit {k}", -1e12, 1e12)
            if v is not None:
                row[k] = v
        out.append(row)
    return out


@router.get("/instruments/{inst_id}")
def instrument_page(request: Request, session: Session, inst_id: int):
    user, csrf = session
    store = _store(request)
    inst, cals = queries.instrument(store, inst_id)
    if inst is None:
        return Response("no such instrument", status_code=404)
    # what the page shows of the history (the plot draws the rest): how many calibrations,
    # and the interval proposed from the issued ones, both selected in the database
    return render(request, "instrument.html", user, csrf, inst=inst, cals=cals,
                  customers=queries.customers(store),
                  error=request.query_params.get("error", "")[:300],
                  proposal=services.propose_interval(store, inst_id),
                  default=services.default_interval(inst.spec_key),
                  limits=services.instrument_limits(inst),
                  n_points=services.history_points(store, inst_id))


@router.get("/instruments/{inst_id}/history.svg")
def instrument_history(request: Request, session: Session, inst_id: int):
    import pickle

    from gonio.report.history_figure import history_svg

    store = _store(request)
    inst, _ = queries.instrument(store, inst_id)
    if inst is None:
        return Response("no such instrument", status_code=404)
    hist, limits = services.history(store, inst_id), services.instrument_limits(inst)
    # the key: the history's content (pickled: a third of repr's time for a triad's 8 100
    # rows; equal bytes only for equal content, so a stale figure is never served)
    key = hashlib.sha256(pickle.dumps((sorted(hist.items()), sorted(limits.items())),
                                      protocol=5)).hexdigest()
    svg = _SVG_CACHE.get(key)
    if svg is None:                  # drawn once per state of the history
        svg = _SVG_CACHE[key] = history_svg(hist, limits)
        while len(_SVG_CACHE) > 256:
            _SVG_CACHE.pop(next(iter(_SVG_CACHE)))
    return Response(svg, media_type="image/svg+xml")


_SVG_CACHE: dict[str, str] = {}


# --------------------------------------------------------------------------- due list, recall

#: how far ahead the due list may look (days)
DUE_WINDOWS = (30, 90, 180, 365)


def _due_filters(request: Request) -> dict:
    """The due list's filters from the query: ``q`` (search), ``within_days`` (one of
    :data:`DUE_WINDOWS`), ``customer`` (one customer, exactly)."""
    try:
        within = int(request.query_params.get("within_days", "30"))
    except ValueError:
        within = 30
    return {"q": request.query_params.get("q", "")[:100],
            "within_days": within if within in DUE_WINDOWS else 30,
            "customer": request.query_params.get("customer", "")[:200]}


@router.get("/due")
def due_page(request: Request, session: Session):
    user, csrf = session
    from urllib.parse import urlencode

    page, filters = page_of(request), _due_filters(request)
    rows, total = queries.due(_store(request), page, PAGE, filters["q"],
                              filters["within_days"], filters["customer"])
    query = urlencode({k: v for k, v in filters.items() if v})
    return render(request, "due.html", user, csrf, rows=rows, total=total, page=page,
                  size=PAGE, f=filters, windows=DUE_WINDOWS, query=query,
                  extra="&" + query if query else "", today=records_today(_store(request)))


@router.get("/due/recall")
def recall_page(request: Request, session: Session):
    """The recall notices, one printed page per customer (the print stylesheet)."""
    user, csrf = session
    filters = _due_filters(request)
    return render(request, "recall.html", user, csrf, today=records_today(_store(request)),
                  notices=queries.recall(_store(request), filters["customer"],
                                         filters["within_days"]),
                  f=filters, lab=services.settings(_store(request)))


# --------------------------------------------------------------------------- standards


@router.get("/standards/{std_id}")
def standard_page(request: Request, session: Session, std_id: int):
    user, csrf = session
    page = page_of(request)
    d = queries.standard_history(_store(request), std_id, page, PAGE)
    if d is None:
        return Response("no such standard", status_code=404)
    tables = [r for r in services.table_calibrations(_store(request))
              if r["entry"].standard_id == std_id]
    return render(request, "standard.html", user, csrf, **d, page=page, size=PAGE,
                  today=records_today(_store(request)), table_calibrations=tables)


@router.get("/standards")
def standards_page(request: Request, session: Session):
    user, csrf = session
    return render(request, "standards.html", user, csrf, standards=queries.standards(
        _store(request)), today=records_today(_store(request)),
        error=request.query_params.get("error", "")[:300])


@router.post("/standards")
async def standards_add(request: Request, session: Session):
    user, csrf = session
    data = await form(request, csrf)
    try:
        services.add_standard(_store(request), user, **{k: data.get(k) for k in (
            "name", "identifier", "due_on", "calibrated_on", "accuracy", "certificate",
            "traceability", "out_of_service")})
    except GonioError as exc:
        return render(request, "standards.html", user, csrf, status_code=400, error=str(exc),
                      standards=queries.standards(_store(request)),
                      today=records_today(_store(request)))
    return _back("/standards")


# --------------------------------------------------------------------------- table calibrations


def _register_page(request, user, csrf, status_code=200, error=""):
    """The register with each entry's state on ``?date=`` (default today)."""
    store = _store(request)
    try:
        day = services.date_value(request.query_params.get("date", "")[:20], "date")
    except GonioError as exc:
        day, error = None, error or str(exc)
    today = records_today(store)            # the laboratory's date (its time zone)
    day = day or today
    return render(request, "table_calibrations.html", user, csrf, status_code=status_code,
                  error=error, rows=services.table_calibrations(store, day),
                  standards=[s for s in queries.standards(store) if not s.retired_on],
                  today=today, day=day,
                  max_months=services.settings(store)["table_calibration_max_months"])


@router.get("/table-calibrations")
def table_calibrations_page(request: Request, session: Session):
    """The laboratory's register of its rotary tables' calibrations, and its form."""
    user, csrf = session
    return _register_page(request, user, csrf)


@router.post("/table-calibrations")
async def table_calibrations_add(request: Request, session: Session):
    user, csrf = session
    data = await form(request, csrf)
    store = _store(request)
    try:
        services.require(user, "technician")
        sha, name = _upload(store, data, "file", 2**20)
        if sha is None:
            raise GonioError("choose the table calibration file", key="file")
        services.register_table_calibration(
            store, user, standard_id=_int(data.get("standard_id"), "standard"), sha256=sha,
            name=name, valid_from=data.get("valid_from"), due_on=data.get("due_on"),
            certificate=data.get("certificate"))
    except GonioError as exc:
        return _register_page(request, user, csrf, 400, str(exc))
    return _back("/table-calibrations")


@router.post("/table-calibrations/{tc_id}/withdraw")
async def table_calibration_withdraw(request: Request, session: Session, tc_id: int):
    """Ask for a register entry's withdrawal (technician or reviewer, with the reason), or
    approve (``decision=approve``: a reviewer who did not ask) or decline
    (``decision=decline``) the withdrawal asked for."""
    user, csrf = session
    data = await form(request, csrf)
    store = _store(request)
    decision = str(data.get("decision") or "ask")
    try:
        if decision == "approve":
            services.approve_withdrawal(store, user, tc_id)
        elif decision == "decline":
            services.decline_withdrawal(store, user, tc_id, data.get("reason"))
        elif decision == "ask":
            services.ask_withdrawal(store, user, tc_id, data.get("reason"))
        else:
            raise GonioError("ask, approve or decline", key="decision")
    except GonioError as exc:
        return _register_page(request, user, csrf, 400, str(exc))
    return _back("/table-calibrations")


@router.get("/table-calibrations/{tc_id}/file")
def table_calibration_download(request: Request, session: Session, tc_id: int):
    from gonio.records.models import TableCalibration
    with _store(request).session() as s:
        tc = s.get(TableCalibration, tc_id)
    if tc is None:
        return Response("no such table calibration", status_code=404)
    return file_response(_store(request), tc.sha256, services.TABLE_CALIBRATION,
                         own_name=tc.name)


# --------------------------------------------------------------------------- calibrations


@router.get("/calibrations")
def calibrations_page(request: Request, session: Session):
    user, csrf = session
    page = page_of(request)
    status = request.query_params.get("status", "")
    status = status if status in STATES else ""
    rows, total = queries.calibrations(_store(request), page, PAGE, status)
    return render(request, "calibrations.html", user, csrf, cals=rows, total=total, page=page,
                  size=PAGE, status=status)


#: the calibration form's text fields, kept when the form comes back with an error
NEW_FIELDS = ("spec_key", "protocol", "performed_on", "received_on", "temperature_c",
              "humidity_pct", "place", "location", "reuse_reason", "table", "gyro", "chamber",
              "supply", "metadata", "table_calibration_id")
#: the calibration form's files: field, largest size (bytes)
NEW_FILES = (("readings", services.MAX_UPLOAD), ("protocol_file", 2**20),
             ("lab_file", services.MAX_LAB_BYTES), ("table_calibration_file", 2**20))


def _new_form(request, user, csrf, inst_id, status_code=200, error="", data=None,
              kept=None, reuse=False):
    """The calibration form; ``data``: what was entered, kept when it comes back with an
    error (text fields and ticked standards); ``kept``: field → (token, name) of the files
    already uploaded (:func:`kept_token`), sent again with the form so none is chosen twice;
    ``reuse``: the readings were used before (the form asks why they are used again)."""
    store = _store(request)
    inst, _ = queries.instrument(store, inst_id)
    if inst is None:
        return Response("no such instrument", status_code=404)
    from gonio.specs import available
    entered = {k: str(data.get(k) or "")[:2000] for k in NEW_FIELDS} if data else {}
    ticked = {str(v) for v in data.getlist("standards")} if data else set()
    return render(request, "calibration_new.html", user, csrf, status_code=status_code,
                  error=error, inst=inst, standards=[s for s in queries.standards(store)],
                  register=services.table_calibrations(store),
                  specs=list(available()), today=records_today(store), v=entered,
                  ticked=ticked,
                  kept=kept or {}, reuse=reuse or bool(entered.get("reuse_reason")),
                  limit=blobs.size_text(services.MAX_UPLOAD))


def kept_token(csrf: str, sha: str, name: str) -> str:
    """A stored upload handed back with a form that came back with an error: its digest and
    an HMAC over digest and shown name keyed by the session's CSRF token, so that a form can
    name only files this session uploaded."""
    mac = hmac.new(csrf.encode(), f"{sha}\0{name}".encode(), "sha256").hexdigest()
    return f"{sha}.{mac}"


def _kept(data, field: str, csrf: str) -> tuple[str | None, str]:
    """(sha256, name) of a file kept from the form's earlier sending, or (None, "")."""
    token = str(data.get("kept_" + field) or "")
    name = clean_name(data.get("kept_" + field + "_name"))
    sha = token.split(".", 1)[0]
    if token and hmac.compare_digest(token, kept_token(csrf, sha, name)):
        return sha, name
    return None, ""


@router.get("/instruments/{inst_id}/calibrate")
def calibration_new(request: Request, session: Session, inst_id: int):
    user, csrf = session
    return _new_form(request, user, csrf, inst_id)


def clean_name(name) -> str:
    """An uploaded file's name for display only: last path part, printable, ≤ 255.

    >>> clean_name("../../etc/passwd"), clean_name("C:\\\\x\\\\r.csv"), clean_name("a\\x00b")
    ('passwd', 'r.csv', 'ab')
    """
    name = re.split(r"[\\\\/]", str(name or ""))[-1]
    return re.sub(r"[\x00-\x1f\x7f]", "", name)[:255]


def _upload(store, data, field: str, limit_bytes: float) -> tuple[str | None, str]:
    """An optional uploaded file of the form into the store: (sha256, display name), or
    (None, "") when none was chosen."""
    f = data.get(field)
    if f is None or not hasattr(f, "read") or not f.filename:
        return None, ""
    sha, _ = services.store_file(store, f.file, limit_bytes=limit_bytes)
    return sha, clean_name(f.filename)


@router.post("/instruments/{inst_id}/calibrate")
async def calibration_create(request: Request, session: Session, inst_id: int):
    user, csrf = session
    try:
        services.check_upload_size(request.headers.get("content-length"),
                                   services.MAX_UPLOAD)
    except GonioError as exc:         # refused before the upload is read
        return HTMLResponse(f"<!doctype html><title>Upload too large</title><p role=alert>"
                            f"{html.escape(str(exc))}. <a href='/instruments/{inst_id}/"
                            "calibrate'>Back to the form</a></p>", status_code=413)
    data = await form(request, csrf)
    store = _store(request)
    files: dict[str, tuple] = {}
    try:
        services.require(user, "technician")
        for field, limit in NEW_FILES:
            files[field] = _upload(store, data, field, limit)
            if files[field][0] is None:
                files[field] = _kept(data, field, csrf)
        sha, name = files["readings"]
        if sha is None:
            raise GonioError("choose a readings file", key="readings")
        cal = submission.submit_calibration(
            store, user, instrument_id=inst_id, readings_sha256=sha, readings_name=name,
            spec_key=data.get("spec_key") or None, protocol=data.get("protocol") or None,
            protocol_sha256=files["protocol_file"][0], lab_sha256=files["lab_file"][0],
            lab_name=files["lab_file"][1],
            table_calibration_sha256=files["table_calibration_file"][0],
            table_calibration_name=files["table_calibration_file"][1],
            table_calibration_id=data.get("table_calibration_id") or None,
            standard_ids=[_int(v, "standards") for v in data.getlist("standards")],
            temperature_c=data.get("temperature_c"), humidity_pct=data.get("humidity_pct"),
            performed_on=data.get("performed_on"), received_on=data.get("received_on"),
            place=data.get("place"), location=data.get("location"),
            reuse_reason=data.get("reuse_reason"))
    except GonioError as exc:
        kept = {f: (kept_token(csrf, sha, name), name) for f, (sha, name) in files.items()
                if sha is not None}
        return _new_form(request, user, csrf, inst_id, 400, str(exc), data, kept,
                         reuse=exc.key == submission.REUSE_KEY)
    wake(request)
    return _back(f"/calibrations/{cal.id}")


@router.post("/instruments/{inst_id}/acquire")
async def calibration_acquire(request: Request, session: Session, inst_id: int):
    """A calibration started from a connected bench: the worker takes the readings through
    the instruments (:mod:`gonio.records.bench`), then calibrates them."""
    from gonio.records import bench

    user, csrf = session
    data = await form(request, csrf)
    store = _store(request)
    try:
        services.require(user, "technician")
        proto_sha, _ = _upload(store, data, "protocol_file", 2**20)
        cal = bench.create_bench_calibration(
            store, user, instrument_id=inst_id,
            resources={r: data.get(r) for r in bench.ROLES},
            metadata=bench.parse_metadata_lines(data.get("metadata")),
            spec_key=data.get("spec_key") or None, protocol=data.get("protocol") or None,
            protocol_sha256=proto_sha, place=data.get("place"),
            location=data.get("location"),
            standard_ids=[_int(v, "standards") for v in data.getlist("standards")],
            temperature_c=data.get("temperature_c"), humidity_pct=data.get("humidity_pct"),
            performed_on=data.get("performed_on"), received_on=data.get("received_on"))
    except GonioError as exc:
        return _new_form(request, user, csrf, inst_id, 400, str(exc), data)
    wake(request)
    return _back(f"/calibrations/{cal.id}")


@router.get("/calibrations/{cal_id}")
def calibration_page(request: Request, session: Session, cal_id: int):
    user, csrf = session
    d = queries.calibration_page(_store(request), cal_id,
                                 queries.page_lang(request.query_params.get("lang")))
    if d is None:
        return Response("no such calibration", status_code=404)
    return render(request, "calibration.html", user, csrf, **d,
                  refresh=d["cal"].status in ("queued",) + services.WORKING,
                  error=request.query_params.get("error", "")[:300])


@router.get("/calibrations/{cal_id}/progress")
def calibration_progress(request: Request, session: Session, cal_id: int):
    """The state as JSON, for a script or a test polling the run."""
    try:
        cal = services.calibration(_store(request), cal_id)
    except GonioError:
        return Response("no such calibration", status_code=404)
    return {"id": cal.id, "status": cal.status, "progress": cal.progress, "error": cal.error}


async def _act(request: Request, session: tuple, cal_id: int, do) -> Response:
    """A calibration's action (:func:`_edit` back to its page), and the dispatcher woken."""
    r = await _edit(request, session, f"/calibrations/{cal_id}", do)
    wake(request)
    return r


@router.post("/calibrations/{cal_id}/review")
async def calibration_review(request: Request, session: Session, cal_id: int):
    return await _act(request, session, cal_id, lambda u, d: services.review(
        _store(request), u, cal_id, accept=d.get("decision") == "accept",
        comment=d.get("comment"), shown_seal=d.get("seal") or None))


@router.post("/calibrations/{cal_id}/approve")
async def calibration_approve(request: Request, session: Session, cal_id: int):
    return await _act(request, session, cal_id, lambda u, d: services.approve(
        _store(request), u, cal_id, shown_seal=d.get("seal") or None))


@router.post("/calibrations/{cal_id}/attach")
async def calibration_attach(request: Request, session: Session, cal_id: int):
    def do(u, d):
        from_readings = bool(d.get("environment_from_readings"))
        services.attach_conditions(
            _store(request), u, cal_id,
            standard_ids=[_int(v, "standards") for v in d.getlist("standards")],
            temperature_c=None if from_readings else d.get("temperature_c"),
            humidity_pct=None if from_readings else d.get("humidity_pct"),
            environment_from_readings=from_readings)
    return await _act(request, session, cal_id, do)


@router.post("/calibrations/{cal_id}/void")
async def calibration_void(request: Request, session: Session, cal_id: int):
    return await _act(request, session, cal_id, lambda u, d: services.void(
        _store(request), u, cal_id, d.get("reason")))


@router.post("/calibrations/{cal_id}/retry")
async def calibration_retry(request: Request, session: Session, cal_id: int):
    return await _act(request, session, cal_id,
                      lambda u, d: services.retry(_store(request), u, cal_id))


@router.get("/calibrations/{cal_id}/files/{name}")
def calibration_file(request: Request, session: Session, cal_id: int, name: str):
    d = queries.calibration_page(_store(request), cal_id)
    if d is None or name not in FILE_TYPES or name not in d["files"]:
        return Response("no such file", status_code=404)
    from gonio.records.models import CalibrationFile
    with _store(request).session() as s:
        sha = s.get(CalibrationFile, (cal_id, name)).sha256
    return file_response(_store(request), sha, name, number=f"DRAFT-{cal_id}",
                         own_name=d["file_names"].get(name, ""))


# --------------------------------------------------------------------------- certificates


@router.get("/certificates")
def certificates_page(request: Request, session: Session):
    user, csrf = session
    page = page_of(request)
    rows, total = queries.certificates(_store(request), page, PAGE)
    return render(request, "certificates.html", user, csrf, certs=rows, total=total, page=page,
                  size=PAGE)


@router.get("/certificates/{cert_id}")
def certificate_page(request: Request, session: Session, cert_id: int):
    user, csrf = session
    cert, newer = queries.certificate(_store(request), cert_id)
    if cert is None:
        return Response("no such certificate", status_code=404)
    lang = queries.page_lang(request.query_params.get("lang"))
    try:                                         # the issued result's items, as stated
        doc = queries.stored_result(_store(request), cert.results_sha256)
    except (GonioError, ValueError, OSError):
        doc = None
    texts = queries.result_texts(doc, lang)
    return render(request, "certificate.html", user, csrf, cert=cert, newer=newer, **texts,
                  items=[(k, it) for k, it in ((doc or {}).get("items") or {}).items()
                         if isinstance(it, dict)],
                  virtual=queries.virtual_mark(_store(request), cert.results_sha256),
                  error=request.query_params.get("error", "")[:300])


@router.get("/certificates/{cert_id}/{name}")
def certificate_file(request: Request, session: Session, cert_id: int, name: str):
    cert, _ = queries.certificate(_store(request), cert_id)
    sha = None if cert is None else {"certificate.pdf": cert.pdf_sha256,
                                     "certificate.html": cert.html_sha256,
                                     "certificate.dcc.xml": cert.dcc_sha256,
                                     "results.json": cert.results_sha256}.get(name)
    if sha is None:
        return Response("no such file", status_code=404)
    return file_response(_store(request), sha, name, "attachment", number=cert.number)


@router.post("/certificates/{cert_id}/amend")
async def certificate_amend(request: Request, session: Session, cert_id: int):
    user, csrf = session
    data = await form(request, csrf)
    try:
        cal = services.amend(_store(request), user, cert_id, data.get("reason"))
    except GonioError as exc:
        from urllib.parse import quote
        return _back(f"/certificates/{cert_id}?error={quote(str(exc)[:300])}")
    wake(request)
    return _back(f"/calibrations/{cal.id}")


# --------------------------------------------------------------------------- admin


def _may_read(user, *roles) -> Response | None:
    """A 403 page unless ``user`` holds one of ``roles`` (technicians see what their work
    needs: not the users, not the whole audit trail)."""
    if any(user.has(r) for r in roles):
        return None
    return Response(f"this needs the {' or '.join(roles)} role", status_code=403)


AUDIT_FILTERS = ("entity", "entity_id", "username")


def _filters(request: Request, names) -> dict:
    return {k: request.query_params.get(k, "")[:64] for k in names}


@router.get("/audit")
def audit_page(request: Request, session: Session):
    user, csrf = session
    refused = _may_read(user, "reviewer", "admin")
    if refused:
        return refused
    from urllib.parse import urlencode

    page = page_of(request)
    filters = _filters(request, AUDIT_FILTERS)
    rows, total = queries.audit_events(_store(request), page, 100, **filters)
    query = urlencode({k: v for k, v in filters.items() if v})
    changes = {e.id: queries.audit_changes(e.before_json, e.after_json) for e in rows}
    return render(request, "audit.html", user, csrf, events=rows, total=total, page=page,
                  changes=changes, size=100, filters=filters, extra="&" + query if query else "", query=query)


def csv_text(header: list[str], rows: list[list]) -> str:
    """CSV (RFC 4180) of a list; a cell a spreadsheet would run as a formula (=, +, -, @,
    tab, CR first) is prefixed with an apostrophe (OWASP CSV injection).

    >>> csv_text(["a", "b"], [["=1+1", 2.5], [None, "x,y"]]).splitlines()
    ['a,b', "'=1+1,2.5", ',"x,y"']
    """
    import csv
    import io

    def cell(v):
        if v is None:
            return ""
        v = v.isoformat() if isinstance(v, (_dt.date, _dt.datetime)) else v
        if isinstance(v, str) and v[:1] in ("=", "+", "-", "@", "\t", "\r"):
            return "'" + v
        return v

    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(header)
    w.writerows([[cell(v) for v in r] for r in rows])
    return buf.getvalue()


@router.get("/export/{name}.csv")
def export_csv(request: Request, session: Session, name: str):
    """A whole list as CSV (the audit trail for reviewers and admins, filtered as its page)."""
    user, _ = session
    if name == "audit":
        refused = _may_read(user, "reviewer", "admin")
        if refused:
            return refused
    params = _filters(request, AUDIT_FILTERS + ("status",))
    params.update(_due_filters(request))
    got = queries.export_rows(_store(request), name, params)
    if got is None:
        return Response("no such list", status_code=404)
    stamp = records_today(_store(request)).isoformat()
    return Response(csv_text(*got), media_type="text/csv; charset=utf-8", headers={
        "Content-Disposition": f'attachment; filename="gonio-{name}-{stamp}.csv"'})


@router.get("/users")
def users_page(request: Request, session: Session):
    user, csrf = session
    refused = _may_read(user, "admin")
    if refused:
        return refused
    return render(request, "users.html", user, csrf, users=queries.users(_store(request)),
                  settings=services.settings(_store(request)))


@router.post("/users")
async def users_add(request: Request, session: Session):
    user, csrf = session
    data = await form(request, csrf)
    return _users_form(request, user, csrf, lambda: services.create_user(
        _store(request), user, data.get("username"), data.get("password"),
        data.getlist("roles"), data.get("full_name")))


@router.post("/users/{username}")
async def users_update(request: Request, session: Session, username: str):
    """Change a user: roles, active, a new password (admin)."""
    user, csrf = session
    data = await form(request, csrf)
    return _users_form(request, user, csrf, lambda: services.update_user(
        _store(request), user, username, active=data.get("active") == "yes",
        roles=data.getlist("roles"), password=data.get("password") or None))


def _users_form(request, user, csrf, do):
    """Run ``do`` and go back to the users page, or show it again with the error."""
    try:
        do()
    except GonioError as exc:
        return render(request, "users.html", user, csrf, status_code=400, error=str(exc),
                      users=queries.users(_store(request)),
                      settings=services.settings(_store(request)))
    return _back("/users")


@router.get("/backup")
def backup_page(request: Request, session: Session):
    """Backups (admin): verify the live records, download a backup, verify an archive
    (uploaded, or from the backup folder) and restore it (docs/records.md#backup)."""
    user, csrf = session
    refused = _may_read(user, "admin")
    if refused:
        return refused
    return _backup(request, user, csrf)


def _backup(request: Request, user, csrf, status_code: int = 200, **ctx):
    from gonio.records.backup import archives_in, backup_folder

    folder = backup_folder(_store(request))
    return render(request, "backup.html", user, csrf, status_code=status_code,
                  folder=folder, folder_archives=archives_in(folder), **ctx)


class _TooLarge(Exception):
    """A request body read past its limit."""


#: what a backup upload's form carries beside the archive (boundaries, the CSRF field), bytes
FORM_SLACK_BYTES = 64 * 2**10


def _backup_limit() -> float:
    """The largest backup archive (bytes): ``GONIO_MAX_BACKUP_BYTES`` (gonio.limits)."""
    from gonio.limits import limit

    return limit("GONIO_MAX_BACKUP_BYTES")


def _too_large(request: Request, user, csrf, size_bytes: float | None = None):
    """The backup page saying, in one line, that an upload is over the limit (HTTP 413)."""
    most = blobs.size_text(_backup_limit())
    said = f", {blobs.size_text(size_bytes)}," if size_bytes else ""
    return _backup(request, user, csrf, status_code=413, error=(
        f"the upload{said} is larger than the limit of {most} for a backup archive "
        "(GONIO_MAX_BACKUP_BYTES): nothing was stored"))


def _counted(request: Request, limit_bytes: float) -> Request:
    """``request`` whose body raises :class:`_TooLarge` once more than ``limit_bytes`` are
    read (a body sent without a Content-Length is counted as it arrives)."""
    receive, seen = request.receive, [0]

    async def counted():
        message = await receive()
        seen[0] += len(message.get("body", b""))
        if seen[0] > limit_bytes:
            raise _TooLarge()
        return message
    return Request(request.scope, counted)


async def _admin_post(request: Request, session: tuple, upload: bool = False):
    """An admin's form sent (the role checked before the body is read, then the CSRF
    token): (user, csrf, data), else the 403 Response. ``upload``: the form may carry a
    backup archive, refused (413, the backup page saying so) past ``GONIO_MAX_BACKUP_BYTES``
    as declared by the request's Content-Length or as read."""
    user, csrf = session
    refused = _may_read(user, "admin")
    if refused:
        return refused
    if not upload:
        return user, csrf, await form(request, csrf)
    try:
        most = _backup_limit() + FORM_SLACK_BYTES
    except GonioError as exc:            # GONIO_MAX_BACKUP_BYTES set to no number
        return _backup(request, user, csrf, status_code=500, error=exc.message)
    try:
        declared = int(request.headers.get("content-length") or 0)
    except ValueError:
        declared = 0
    if declared > most:
        return _too_large(request, user, csrf, declared)
    try:
        return user, csrf, await form(_counted(request, most), csrf)
    except _TooLarge:
        return _too_large(request, user, csrf)


def _admin_form(path: str, upload: bool = False):
    """An admin's POST form at ``path``: the decorated ``async def f(request, user, csrf,
    data)`` runs once the admin role and the CSRF token are checked (else 403);
    ``upload``: the form may carry a backup archive (:func:`_admin_post`)."""
    def wrap(fn):
        async def route(request: Request, session: Session):
            got = await _admin_post(request, session, upload)
            return got if isinstance(got, Response) else await fn(request, *got)
        route.__name__, route.__doc__ = fn.__name__, fn.__doc__
        router.post(path)(route)
        return fn
    return wrap


@_admin_form("/backup/verify")
async def backup_verify(request: Request, user, csrf, data):
    """The live records checked as ``gonio db verify`` checks them."""
    from gonio.records.backup import verify

    counts, problems = verify(_store(request))
    return _backup(request, user, csrf, live=counts, problems=problems)


@_admin_form("/backup/download")
async def backup_download(request: Request, user, csrf, data):
    """A backup archive of the records now (``gonio db backup``), as a download: written in
    a worker thread (the server answers others meanwhile) into a temporary folder of the
    data folder, sent from the file (never whole in memory) and removed once sent."""
    import shutil
    import tempfile

    from fastapi.responses import FileResponse
    from starlette.background import BackgroundTask
    from starlette.concurrency import run_in_threadpool

    from gonio.records.backup import backup

    tmp = Path(tempfile.mkdtemp(prefix="gonio-backup-", dir=_store(request).data))
    try:
        await run_in_threadpool(backup, _store(request), tmp / "records.zip")
    except BaseException as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        if not isinstance(exc, GonioError):
            raise
        return _backup(request, user, csrf, status_code=409, error=exc.message)
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d-%H%M")
    return FileResponse(tmp / "records.zip", media_type="application/zip",
                        filename=f"gonio-records-{stamp}.zip",
                        background=BackgroundTask(shutil.rmtree, tmp, ignore_errors=True))


def _staging(store) -> Path:
    """Where an uploaded archive waits between its check and its restore."""
    return store.data / "restore"


def _archive_path(store, token: str) -> Path | None:
    """The archive a form names: ``upload:<sha256>`` (staged by its check) or
    ``folder:<name>`` (one the backup folder lists); None for anything else."""
    from gonio.records.backup import archives_in, backup_folder

    kind, _, rest = str(token or "").partition(":")
    if kind == "upload" and re.fullmatch(r"[0-9a-f]{64}", rest):
        path = _staging(store) / f"{rest}.zip"
        return path if path.is_file() else None
    folder = backup_folder(store)
    if kind == "folder" and rest in {a["name"] for a in archives_in(folder)}:
        return folder / rest
    return None


#: uploaded archives kept waiting for their confirmation at most (the newest; older ones
#: and any older than a day are removed when another is uploaded)
STAGED_KEEP = 3


def _tidy_staging(root: Path, keep: int) -> None:
    """The staging folder pruned: archives older than a day or beyond the newest ``keep``,
    and uploads cut off part-way (``.upload-*``) older than an hour."""
    import time

    from gonio.units import S_PER_DAY

    def age_s(q: Path) -> float:        # one removed meanwhile (another upload): old
        try:
            return now - q.stat().st_mtime
        except FileNotFoundError:
            return float("inf")
    now = time.time()
    for part in root.glob(".upload-*"):
        if age_s(part) > S_PER_DAY / 24:
            part.unlink(missing_ok=True)
    staged = sorted(root.glob("*.zip"), key=age_s)
    for i, old in enumerate(staged):
        if i >= keep or age_s(old) > S_PER_DAY:
            old.unlink(missing_ok=True)


def _stage(store, upload) -> tuple[str, Path]:
    """An uploaded archive kept under its SHA-256 until it is restored: (token, path). Over
    ``GONIO_MAX_BACKUP_BYTES`` it is a GonioError and nothing is kept; the staging folder
    keeps the newest :data:`STAGED_KEEP` uploads at most, none older than a day."""
    import os
    import tempfile

    root = _staging(store)
    root.mkdir(mode=0o700, exist_ok=True)
    _tidy_staging(root, STAGED_KEEP - 1)
    h, size, most = hashlib.sha256(), 0, _backup_limit()
    fd, tmp = tempfile.mkstemp(prefix=".upload-", dir=root)
    try:
        with os.fdopen(fd, "wb") as fh:
            for piece in iter(lambda: upload.read(1 << 20), b""):
                size += len(piece)
                if size > most:
                    raise GonioError(f"the upload is larger than the limit of "
                                     f"{blobs.size_text(most)} for a backup archive "
                                     "(GONIO_MAX_BACKUP_BYTES): nothing was stored",
                                     key="upload")
                h.update(piece)
                fh.write(piece)
        path = root / f"{h.hexdigest()}.zip"
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return f"upload:{h.hexdigest()}", path


def _open_chosen(path: Path):
    """An archive the form names, opened without following a symbolic link (one put in
    its place after it was listed or staged is refused)."""
    from gonio.records.backup import open_archive

    return open_archive(path, follow_links=False)


def _restore_page(request: Request, user, csrf, token: str, path: Path, name: str,
                  status_code: int = 200, **ctx):
    """The archive checked (``gonio db restore``'s checks, nothing written) and, when it
    passes, what a restore of it would replace, with the confirmation form."""
    from gonio.records.backup import check_archive, summary

    try:
        with _open_chosen(path) as fh:
            checked = check_archive(path, fh)
    except GonioError as exc:
        if token.startswith("upload:"):
            path.unlink(missing_ok=True)
        return _backup(request, user, csrf, status_code=400, archive=name,
                       error=str(exc).replace(str(path), name))
    return _backup(request, user, csrf, status_code=status_code, archive=name,
                   checked=checked, token=token, sha256=checked["sha256"],
                   current=summary(_store(request)), **ctx)


@_admin_form("/backup/check", upload=True)
async def backup_check(request: Request, user, csrf, data):
    """A backup archive, uploaded or chosen from the backup folder, checked as ``gonio db
    restore`` checks it before it writes anything (complete, intact, every row and
    reference); nothing is written to the records. A passing archive is offered for
    restoring."""
    from starlette.concurrency import run_in_threadpool

    store = _store(request)
    f, chosen = data.get("archive"), str(data.get("choose") or "")
    if chosen:
        path = _archive_path(store, f"folder:{chosen}")
        if path is None:
            return _backup(request, user, csrf, status_code=400,
                           error="choose an archive the backup folder lists")
        token, name = f"folder:{chosen}", chosen
    elif f is not None and hasattr(f, "read") and f.filename:
        name = clean_name(f.filename)
        try:
            token, path = await run_in_threadpool(_stage, store, f.file)
        except GonioError as exc:
            if exc.key != "upload":
                raise
            return _too_large(request, user, csrf)
    else:
        return _backup(request, user, csrf, status_code=400,
                       error="choose a backup archive (.zip)")
    return await run_in_threadpool(_restore_page, request, user, csrf, token, path, name)


#: what the person restoring types to confirm
CONFIRM_WORD = "RESTORE"


@_admin_form("/backup/restore")
async def backup_restore(request: Request, user, csrf, data):
    """Restore a verified archive over the live records (admin; the word typed and the
    password given again): the server answers every other request 503 meanwhile and the
    workers claim nothing; :func:`gonio.records.backup.restore` replaces the records
    atomically; every session ends (everyone logs in again)."""
    from starlette.concurrency import run_in_threadpool

    store = _store(request)
    token, name = str(data.get("archive") or ""), clean_name(str(data.get("name") or ""))
    if token.startswith("folder:"):      # the folder's own name; an upload's as it was sent
        name = token[len("folder:"):]
    path = _archive_path(store, token)
    if path is None:
        return _backup(request, user, csrf, status_code=400,
                       error="that archive is no longer here: verify it again")
    again = dict(request=request, user=user, csrf=csrf, token=token, path=path, name=name,
                 status_code=400)
    if str(data.get("confirm") or "").strip() != CONFIRM_WORD:
        return _restore_page(**again, restore_error=f"type {CONFIRM_WORD} to confirm")
    try:
        auth.authenticate(store, user.username, str(data.get("password") or "")[:2000],
                          request.client.host if request.client else "")
    except GonioError as exc:
        return _restore_page(**again, restore_error="wrong password: nothing restored"
                             if not isinstance(exc, TooManyAttemptsError) else str(exc))
    try:
        counts = await run_in_threadpool(_restore_closed, request, user, path,
                                         str(data.get("sha256") or ""), name)
    except GonioError as exc:
        return _restore_page(**dict(again, status_code=409), restore_error=exc.message)
    if token.startswith("upload:"):
        path.unlink(missing_ok=True)
    r = render(request, "restored.html", None, None, archive=name, counts=counts,
               sha256=str(data.get("sha256") or ""))
    r.delete_cookie(COOKIE)
    return r


def _restore_closed(request: Request, user, path: Path, sha256: str, name: str) -> dict:
    """The restore run with the server closed (503 for every other request, no worker
    claiming); opened again whatever happens."""
    from gonio.records.backup import restore

    dispatcher, gate = request.app.state.dispatcher, request.app.state.gate
    running = dispatcher.pause() if dispatcher is not None else 0
    try:
        if running:
            raise GonioError(f"{running} calibration(s) are being computed or issued now: "
                             "restore when they are done; nothing restored", key="restore")
        stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%H:%M")
        if not gate.close(f"the records are being restored from a backup (by "
                          f"{user.username}, started {stamp} UTC)"):
            raise GonioError("other requests did not end within 30 s (or another restore "
                             "runs): try again; nothing restored", key="restore")
        try:
            with _open_chosen(path) as fh:
                return restore(_store(request), path, replace=True, actor=user,
                               expect_sha256=sha256, stream=fh, name=name)
        finally:
            gate.open()
    finally:
        if dispatcher is not None:
            dispatcher.resume()


@router.post("/settings")
async def settings_save(request: Request, session: Session):
    user, csrf = session
    data = await form(request, csrf)
    return _users_form(request, user, csrf, lambda: services.set_settings(
        _store(request), user, **{k: data.get(k) for k in services.SETTINGS
                                  if data.get(k) is not None}))

