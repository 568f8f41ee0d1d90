"""gonio serve's security, tested through HTTP (Starlette's TestClient, no browser): sessions
on every page, CSRF on every POST, roles on the server, login throttling, hostile input in
every field (HTML, SQL, path traversal, 10 MB strings, control characters)."""

from __future__ import annotations

import datetime as dt
import io
import re

import pytest
from sqlalchemy import func, select

from gonio.records import services
from gonio.records.models import Calibration, Customer, Instrument, Standard, User

PASSWORD = "correct horse battery"
HOSTILE = {
    "html": "<script>alert('x')</script><img src=x onerror=alert(1)>",
    "sql": "x'); DROP TABLE users; --",
    "traversal": "../../../../etc/passwd",
    "control": "bad\x00name\x1b[31m",
    "huge": "A" * (10 * 2**20),
}


@pytest.fixture
def app(sqlite_store):
    from gonio.web.app import create_app

    for name, roles in (("tech", "technician"), ("rev", "reviewer"),
                        ("admin", "admin technician reviewer")):
        services.create_user(sqlite_store, None, name, PASSWORD, roles)
    return create_app(sqlite_store)


def client(app):
    from fastapi.testclient import TestClient
    return TestClient(app, follow_redirects=False)


def login(app, name: str):
    c = client(app)
    token = c.cookies.get("gonio_login") or _login_token(c)
    r = c.post("/login", data={"username": name, "password": PASSWORD, "csrf": token})
    assert r.status_code == 303, r.text
    return c


def _login_token(c) -> str:
    r = c.get("/login")
    return re.search(r'name="csrf" value="([^"]+)"', r.text).group(1)


def csrf_of(c) -> str:
    return re.search(r'name="csrf" value="([^"]+)"', c.get("/").text).group(1)


def get_routes(app):
    from fastapi.routing import APIRoute

    from gonio.web.pages import router

    for r in router.routes:
        if isinstance(r, APIRoute):
            path = re.sub(r"\{[^}]+\}", "1", r.path)
            for m in r.methods:
                yield m, path, r.path


def test_every_page_but_login_needs_a_session(app):
    c = client(app)
    checked = 0
    for method, path, template in get_routes(app):
        if template == "/login":
            continue
        r = c.request(method, path, data={"csrf": "x"})
        assert r.status_code in (303, 403), (method, path, r.status_code)
        if r.status_code == 303:
            assert r.headers["location"] == "/login", (method, path)
        checked += 1
    assert checked >= 25
    assert c.get("/login").status_code == 200
    assert c.get("/static/style.css").status_code == 200


def test_every_post_needs_the_csrf_token(app, sqlite_store):
    c = login(app, "admin")
    for method, path, template in get_routes(app):
        if method != "POST" or template == "/login":
            continue
        for data in ({}, {"csrf": "forged"}):
            r = c.post(path, data=dict(data, name="x", reason="x", username="evil"))
            assert r.status_code == 403, (path, data, r.status_code)
    with sqlite_store.session() as s:
        assert s.scalar(select(func.count()).select_from(Customer)) == 0
        assert s.scalar(select(func.count()).select_from(User)) == 3
    # the login form: its own cookie token
    c2 = client(app)
    _login_token(c2)
    r = c2.post("/login", data={"username": "admin", "password": PASSWORD, "csrf": "forged"})
    assert r.status_code == 403


def test_login_throttled_after_repeated_failures(app):
    c = client(app)
    for _ in range(5):
        r = c.post("/login", data={"username": "tech", "password": "wrong password",
                                   "csrf": _login_token(c)})
        assert r.status_code == 401 and "wrong user name or password" in r.text
    r = c.post("/login", data={"username": "tech", "password": PASSWORD,
                               "csrf": _login_token(c)})
    assert r.status_code == 429 and "too many failed logins" in r.text
    assert "gonio_session" not in r.cookies
    login(app, "rev")                       # another user is not locked out


def test_roles_enforced_on_the_server(app, sqlite_store):
    rev = login(app, "rev")
    r = rev.post("/customers", data={"csrf": csrf_of(rev), "name": "ACME"})
    assert r.status_code == 400 and "technician role" in r.text
    r = rev.post("/users", data={"csrf": csrf_of(rev), "username": "mallory",
                                 "password": "password123", "roles": "admin"})
    assert r.status_code == 400 and "admin role" in r.text
    tech = login(app, "tech")
    tech.post("/customers", data={"csrf": csrf_of(tech), "name": "ACME"})
    cust = services.add_customer(sqlite_store, services.user(sqlite_store, "tech"), "B")
    r = tech.post("/instruments", data={"csrf": csrf_of(tech), "customer_id": cust.id,
                                        "serial": "S1", "spec_key": "ogam-draft"})
    assert r.status_code == 303
    inst_id = int(r.headers["location"].rsplit("/", 1)[1])
    std = services.add_standard(sqlite_store, services.user(sqlite_store, "tech"), name="T",
                                identifier="T-1", due_on="2099-01-01")
    r = tech.post(f"/instruments/{inst_id}/calibrate",
                  data={"csrf": csrf_of(tech), "standards": [str(std.id)],
                        "temperature_c": "20", "humidity_pct": "40"},
                  files={"readings": ("r.csv", b"x,y\n")})
    assert r.status_code == 303
    cal_id = int(r.headers["location"].rsplit("/", 1)[1])
    with sqlite_store.writing() as s:               # as if the worker had computed it
        s.get(Calibration, cal_id).status = "computed"
        s.commit()
    for url in (f"/calibrations/{cal_id}/review", f"/calibrations/{cal_id}/approve"):
        r = tech.post(url, data={"csrf": csrf_of(tech), "decision": "accept"})
        assert r.status_code == 303 and "reviewer%20role" in r.headers["location"]
    assert services.calibration(sqlite_store, cal_id).status == "computed"


#: a table calibration file the register takes (docs/formats.md, "Table calibration")
TABLE_FILE = b"table_deg,error_arcsec,u_arcsec\n0,0.0,0.02\n120,0.01,0.02\n"


def _fields_posts(inst_id, cust_id, table_id, entry_id):
    """Every form of the application with its text fields (the register of table
    calibrations' form: ``table_id`` a rotary table registered as a standard; the withdrawal
    form of its entry ``entry_id``)."""
    return [
        ("/customers", ["name", "address"], {}),
        ("/instruments", ["kind", "manufacturer", "model", "serial", "limit_item_0",
                          "limit_source_0"],
         {"customer_id": str(cust_id), "serial": "S-OK", "spec_key": "ogam-draft"}),
        ("/standards", ["name", "identifier", "accuracy", "certificate", "traceability"],
         {"name": "n", "identifier": "id-ok", "due_on": "2099-01-01"}),
        (f"/instruments/{inst_id}/calibrate", ["place", "location", "protocol",
                                               "temperature_c"], {}),
        ("/users", ["username", "full_name"], {"username": "u-ok", "password": "password123",
                                               "roles": "technician"}),
        ("/settings", ["lab_name", "lab_address", "table_calibration_max_months"], {}),
        ("/table-calibrations", ["certificate", "valid_from", "due_on", "standard_id"],
         {"standard_id": str(table_id), "valid_from": "2025-02-01", "due_on": "2026-02-01"}),
        (f"/table-calibrations/{entry_id}/withdraw", ["reason", "decision"],
         {"decision": "ask"}),
    ]


def hostile_conformity(value: str):
    """A stand-in for :func:`gonio.records.results.conformity_of` whose every text (rule,
    row, note) is ``value``: what a calibration page prints of its stored decisions is
    escaped like the rest, whatever the stored result says."""
    fields = ("key", "title", "limits", "acceptance", "guard_band", "outcome", "pc", "pfa")

    def conformity_of(doc, lang="en", titles=None):
        return {"rules": [value], "rows": [dict.fromkeys(fields, value)], "notes": [value]}
    return conformity_of


@pytest.mark.parametrize("kind", sorted(HOSTILE))
def test_hostile_input_in_every_field_refused_or_escaped(app, sqlite_store, kind,
                                                         monkeypatch):
    from gonio.records import queries

    admin = login(app, "admin")
    monkeypatch.setattr(queries, "conformity_of", hostile_conformity(HOSTILE[kind]))
    actor = services.user(sqlite_store, "admin")
    cust = services.add_customer(sqlite_store, actor, "Base customer")
    inst = services.register_instrument(sqlite_store, actor, customer_id=cust.id,
                                        serial="BASE", spec_key="ogam-draft")
    table = services.add_standard(sqlite_store, actor, name="rotary table", identifier="RT-1",
                                  due_on="2099-01-01")
    sha, _ = services.store_file(sqlite_store, io.BytesIO(TABLE_FILE + b"240,0.0,0.02\n"))
    entry = services.register_table_calibration(sqlite_store, actor, standard_id=table.id,
                                                sha256=sha, name="tc.csv",
                                                valid_from="2025-01-01", due_on="2026-01-01")
    value = HOSTILE[kind]
    for url, fields, base in _fields_posts(inst.id, cust.id, table.id, entry.id):
        for field in fields:
            data = dict(base, csrf=csrf_of(admin))
            data[field] = value
            files = {"readings": ("r.csv", b"a\n")} if "calibrate" in url else \
                {"file": ("tc.csv", io.BytesIO(TABLE_FILE))} if url == "/table-calibrations" \
                else None
            r = admin.post(url, data=data, files=files)
            assert r.status_code in (303, 400, 413), (url, field, r.status_code)
            if kind in ("control", "huge"):
                assert r.status_code in (400, 413), (url, field)
            if r.status_code == 400:
                assert "Traceback" not in r.text
    # stored hostile text comes back escaped on every page, and the tables are intact
    pages = ["/", "/customers", "/instruments", "/standards", "/calibrations", "/users",
             "/audit", f"/instruments/{inst.id}", "/table-calibrations",
             f"/standards/{table.id}"]
    with sqlite_store.session() as s:
        pages += [f"/calibrations/{c}" for c in s.scalars(select(Calibration.id))]
        pages += [f"/instruments/{i}" for i in s.scalars(select(Instrument.id))]
        assert s.scalar(select(func.count()).select_from(User)) >= 3
    for page in pages:
        r = admin.get(page)
        assert r.status_code == 200, page
        assert "<script>alert" not in r.text and "<img src=x" not in r.text, page
    if kind == "html":
        assert "&lt;script&gt;alert(" in admin.get("/customers").text
        std = services.add_standard(sqlite_store, actor, name="reference", identifier="REF-1",
                                    due_on="2099-01-01")
        r = admin.post(f"/instruments/{inst.id}/calibrate", data={
            "csrf": csrf_of(admin), "standards": [str(std.id)], "temperature_c": "20",
            "humidity_pct": "40"}, files={"readings": ("r.csv", io.BytesIO(
                b"# spec: ogam-draft\ntest,series,round,time_s,table_deg\n"))})
        assert r.status_code == 303, r.text
        page = admin.get(r.headers["location"]).text   # its statement of conformity escaped
        conformity = re.search(r'<table id="conformity">(.*?)</table>', page, re.S).group(1)
        assert "<script>alert" not in page and conformity.count("&lt;script&gt;alert(") >= 7
        register = admin.get("/table-calibrations").text      # the certificate and reason
        assert register.count("&lt;script&gt;alert(") >= 2, register
    exported = admin.get("/export/table_calibrations.csv")    # text, not a page
    assert exported.status_code == 200 and exported.headers["content-type"].startswith(
        "text/csv")
    for r in services.table_calibrations(sqlite_store):   # only plain text was registered
        assert r["entry"].certificate in ("", value), r["entry"].certificate[:40]
        assert r["entry"].valid_from == dt.date(2025, 2, 1) or r["entry"].id == entry.id


def test_uploaded_file_name_never_becomes_a_path(app, sqlite_store):
    tech = login(app, "tech")
    actor = services.user(sqlite_store, "tech")
    cust = services.add_customer(sqlite_store, actor, "C")
    inst = services.register_instrument(sqlite_store, actor, customer_id=cust.id, serial="S",
                                        spec_key="ogam-draft")
    std = services.add_standard(sqlite_store, actor, name="T", identifier="T-1",
                                due_on="2099-01-01")
    body = b"# spec: ogam-draft\ntest,series,round,time_s,table_deg\n"
    r = tech.post(f"/instruments/{inst.id}/calibrate", data={
        "csrf": csrf_of(tech), "standards": [str(std.id)], "temperature_c": "20",
        "humidity_pct": "40"},
                  files={"readings": ("../../../../tmp/evil\x00.csv", io.BytesIO(body))})
    assert r.status_code == 303
    cal = services.calibration(sqlite_store, int(r.headers["location"].rsplit("/", 1)[1]))
    assert "/" not in cal.readings_name and cal.readings_name.startswith("evil")
    stored = list(sqlite_store.blob_root.rglob("*"))
    assert all(p.name == cal.readings_sha256 or p.is_dir() or p.name.startswith(".")
               for p in stored if p.is_file()) and any(p.name == cal.readings_sha256
                                                      for p in stored)
    with sqlite_store.session() as s:
        assert s.scalar(select(func.count()).select_from(Standard)) == 1


def test_security_headers_and_cookie_flags(app):
    c = client(app)
    r = c.get("/login")
    assert "frame-ancestors 'none'" in r.headers["content-security-policy"]
    assert r.headers["x-content-type-options"] == "nosniff"
    token = _login_token(c)
    r = c.post("/login", data={"username": "tech", "password": PASSWORD, "csrf": token})
    cookie = r.headers["set-cookie"]
    assert "HttpOnly" in cookie and "SameSite=strict" in cookie.replace("Strict", "strict")
