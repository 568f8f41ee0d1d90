"""``gonio serve``: the laboratory's records in a browser (FastAPI, server-rendered Jinja2
templates, no JavaScript build; docs/records.md).

The web layer is thin: every page reads through and every form calls a documented function
of :mod:`gonio.records.services`, which checks roles and inputs. This module adds what only
a browser needs:

* a session (cookie ``gonio_session``: random token, HttpOnly, SameSite=Strict) for every
  page but the login page and the static files;
* a CSRF token on every POST (the session's token; the login form's own cookie token);
* security headers (a Content-Security-Policy without inline scripts, no framing,
  no MIME sniffing); certificates served as files with a sandboxing CSP;
* uploaded files streamed into the content-addressed store: their names are shown, never
  used as paths.
"""

from __future__ import annotations

import html
from pathlib import Path

from fastapi import FastAPI, Request
from fastapi.responses import HTMLResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles
from fastapi.templating import Jinja2Templates
from starlette.exceptions import HTTPException as StarletteHTTPException

from gonio.web import pages
from gonio.web.common import Forbidden, Redirect, fmt

HERE = Path(__file__).resolve().parent
HEADERS = {"Content-Security-Policy": "default-src 'self'; img-src 'self' data:; "
                                      "style-src 'self'; script-src 'self'; frame-ancestors 'none'; "
                                      "form-action 'self'; base-uri 'none'",
           "X-Frame-Options": "DENY", "X-Content-Type-Options": "nosniff",
           "Referrer-Policy": "no-referrer", "Cache-Control": "no-store"}


def warm_up():
    """Import, in a background thread, what the first pages draw with — SciPy for the due
    list's interval proposals on the dashboard, Matplotlib and its font for an instrument's
    history plot — so that the first person to open them after ``gonio serve`` starts does
    not wait for the imports (about 0.8 s and 1.1 s on a loaded 2-core machine). Returns the
    thread (a daemon: it never holds the server up)."""
    import threading

    def run():
        try:
            import datetime as dt

            import gonio.records.interval  # noqa: F401  (SciPy)
            from gonio.report.history_figure import history_svg
            history_svg({"K": [{"date": dt.date(2020 + i, 1, 1), "value": 1.0, "U": 0.1,
                                "k": 2.0, "unit": "", "title": "K", "status": "issued",
                                "certificate": ""} for i in range(2)]})   # fonts, backend
        except Exception:  # pragma: no cover - a page imports it again and says what failed
            pass
    t = threading.Thread(target=run, name="gonio-warm-up", daemon=True)
    t.start()
    return t


def create_app(store, dispatcher=None) -> FastAPI:
    """The application over an open :class:`~gonio.records.db.Store`; ``dispatcher`` (a
    :class:`~gonio.records.worker.Dispatcher`) is woken when work is queued."""
    app = FastAPI(title="gonio records", docs_url=None, redoc_url=None, openapi_url=None)
    app.state.store, app.state.dispatcher = store, dispatcher
    templates = Jinja2Templates(directory=str(HERE / "templates"))
    templates.env.globals.update(fmt=fmt, STATES=("queued", "running", "failed", "computed",
                                                   "reviewed", "rejected", "amending", "issuing",
                                                   "issued", "void"))
    app.state.templates = templates
    app.mount("/static", StaticFiles(directory=str(HERE / "static")), name="static")

    @app.middleware("http")
    async def headers(request: Request, call_next):
        response = await call_next(request)
        for k, v in HEADERS.items():
            response.headers.setdefault(k, v)
        return response

    @app.exception_handler(Redirect)
    async def _redirect(request: Request, exc: Redirect):
        return RedirectResponse(exc.url, status_code=303)

    @app.exception_handler(Forbidden)
    async def _forbidden(request: Request, exc: Forbidden):
        return HTMLResponse("<!doctype html><title>Forbidden</title><p>Forbidden: the form "
                            "expired or was not sent from this application. "
                            "<a href='/'>Back</a></p>", status_code=403)

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException):
        # a form the parser refused (a part too large, too many fields) says what it was
        said = html.escape(str(exc.detail).rstrip(".")) if exc.status_code in (400, 413) \
            and exc.detail else "not found or not allowed"
        return HTMLResponse(f"<!doctype html><title>{exc.status_code}</title>"
                            f"<p>{exc.status_code}: {said}. "
                            "<a href='/'>Back</a></p>", status_code=exc.status_code)

    pages.register(app)
    return app
