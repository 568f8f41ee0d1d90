"""What ``gonio serve`` answers before its application is built: the login page.

The full application (FastAPI, SQLAlchemy, the records, the pages) takes about a second of
imports to build. :class:`Front` is the ASGI application the server starts with: it
answers ``GET /login`` at once from the same template, cookie and headers as the full
application, holds every other request until the application is built (then hands it
over), and answers 503 if the build failed. It imports only Starlette's templating and
Jinja2, which the server imports anyway.

This module also holds what the login page shares with the full application: the cookie
names, the security headers, the template environment and the page itself.
"""

from __future__ import annotations

import asyncio
import datetime as _dt
import html
import math
import secrets
import threading
from pathlib import Path

from jinja2 import pass_context
from starlette.requests import Request
from starlette.responses import HTMLResponse
from starlette.templating import Jinja2Templates

from gonio.units import S_PER_H

HERE = Path(__file__).resolve().parent
HEADERS = {"Content-Security-Policy": "default-src 'self'; img-src 'self' data:; "
                                      "style-src 'self'; script-src 'self'; frame-ancestors 'none'; "
                                      "form-action 'self'; base-uri 'none'",
           "X-Frame-Options": "DENY", "X-Content-Type-Options": "nosniff",
           "Referrer-Policy": "no-referrer", "Cache-Control": "no-store"}
COOKIE, LOGIN_COOKIE = "gonio_session", "gonio_login"
#: lifetime of the login form's CSRF cookie
LOGIN_COOKIE_AGE_S = int(S_PER_H)
#: the states a calibration passes through, in the pages' order
STATES = ("queued", "running", "failed", "computed", "drafting", "reviewed", "rejected", "amending",
          "issuing", "issued", "void")


def fresh_token() -> str:
    return secrets.token_urlsafe(32)


def fmt(x, digits: int = 6) -> str:
    """A number for a table cell (6 significant digits), '—' for None."""
    if x is None:
        return "—"
    if isinstance(x, float):
        if not math.isfinite(x):
            return "—"
        return f"{x:.{digits}g}"
    if isinstance(x, _dt.datetime):
        return x.strftime("%Y-%m-%d %H:%M")
    return str(x)


@pass_context
def virtual_tag(ctx, readings_sha256: str | None, results_sha256: str | None = None) -> str:
    """A list's mark for a calibration that is the virtual bench's, by its readings or its
    stored result (:func:`gonio.records.queries.virtual_calibration`), in the certificate
    banner's words; "" otherwise."""
    from gonio.records.queries import virtual_calibration
    from gonio.report.i18n import labels

    request = ctx.get("request")
    store = getattr(getattr(getattr(request, "app", None), "state", None), "store", None)
    if store is None or not virtual_calibration(store, readings_sha256, results_sha256):
        return ""
    return labels("en")["virtual"]


def past_due(due: _dt.date, today: _dt.date) -> bool:
    """The lists' "overdue" mark: :func:`gonio.records.models.is_past_due`, the rule the
    services register and edit standards by, on the records' today (the laboratory's date,
    :func:`gonio.records.models.records_today`)."""
    from gonio.records.models import is_past_due

    return is_past_due(due, today)


def templates() -> Jinja2Templates:
    """The pages' template environment (autoescaped), with the globals every page uses."""
    t = Jinja2Templates(directory=str(HERE / "templates"))
    t.env.globals.update(fmt=fmt, STATES=STATES, virtual_tag=virtual_tag,
                         past_due=past_due)
    return t


def login_response(tpl: Jinja2Templates, request: Request, status_code: int = 200,
                   **ctx) -> HTMLResponse:
    """The login page with a fresh CSRF token, also set as the login form's cookie."""
    token = fresh_token()
    ctx.update(request=request, user=None, csrf=token)
    r = tpl.TemplateResponse(request, "login.html", ctx, status_code=status_code)
    r.set_cookie(LOGIN_COOKIE, token, httponly=True, samesite="strict",
                 max_age=LOGIN_COOKIE_AGE_S)
    return r


def warm(app, path: str = "/login") -> int:
    """One GET of ``path`` through ``app`` in this thread, its answer discarded: the first
    request builds the application's middleware stack and compiles its routes and templates,
    so that a person's first request does not. Returns the status code."""
    scope = {"type": "http", "asgi": {"version": "3.0"}, "http_version": "1.1",
             "method": "GET", "scheme": "http", "path": path, "raw_path": path.encode(),
             "root_path": "", "query_string": b"", "headers": [(b"host", b"localhost")],
             "client": ("127.0.0.1", 0), "server": ("127.0.0.1", 80)}
    status = []

    async def receive():
        return {"type": "http.request", "body": b"", "more_body": False}

    async def send(message):
        if message["type"] == "http.response.start":
            status.append(message["status"])

    asyncio.run(app(scope, receive, send))
    return status[0]


class Front:
    """The ASGI application ``gonio serve`` starts with (module docstring). The thread that
    builds the full application calls :meth:`serve` with it, or :meth:`fail`."""

    #: how often a held request looks whether the application is there (s)
    POLL_S = 0.02
    #: how long the build waits for the first login page to be answered (s): a browser's
    #: first request then does not share the CPU (and the GIL) with the build's imports
    FIRST_PAGE_GRACE_S = 0.3

    def __init__(self):
        self.app = None
        self.failed: str | None = None
        self._templates: Jinja2Templates | None = None
        self.first_page = threading.Event()     # set once a login page has been sent

    def prepare(self) -> Front:
        """Load and compile the login page's templates now (before the first request)."""
        self._templates = templates()
        self._templates.get_template("login.html")
        return self

    def serve(self, app) -> None:
        self.app = app

    def fail(self, reason: str) -> None:
        self.failed = reason

    async def __call__(self, scope, receive, send):
        if self.app is None and scope["type"] == "http" and self.failed is None \
                and scope["method"] in ("GET", "HEAD") and scope["path"] == "/login":
            if self._templates is None:
                self._templates = templates()
            r = login_response(self._templates, Request(scope, receive))
            for k, v in HEADERS.items():
                r.headers.setdefault(k, v)
            try:
                return await r(scope, receive, send)
            finally:
                self.first_page.set()
        self.first_page.set()           # any other request: the build goes ahead at once
        while self.app is None and self.failed is None:
            await asyncio.sleep(self.POLL_S)
        if self.app is None:
            if scope["type"] == "http":
                await HTMLResponse(f"<!doctype html><title>503</title><p>gonio serve could not "
                                   f"start: {html.escape(self.failed)}</p>", status_code=503,
                                   headers=HEADERS)(scope, receive, send)
            return None
        return await self.app(scope, receive, send)
