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

from fastapi import FastAPI, Request
from fastapi.responses import HTMLResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles
from starlette.exceptions import HTTPException as StarletteHTTPException

from gonio.web import pages
from gonio.web.common import Forbidden, Gate, Redirect
from gonio.web.front import HEADERS, HERE, templates

def warm_up():
    """Import, in a background thread, what the first dashboard draws with — SciPy for the due
    list's interval proposals — so that the first person to open it after ``gonio serve``
    starts does not wait for the import (about 0.5 s on a loaded 2-core machine; the history
    plot is written as SVG text and needs no plotting library). Returns the thread (a
    daemon: it never holds the server up)."""
    import threading

    def run():
        try:
            import gonio.records.interval  # noqa: F401  (SciPy)
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
    app.state.templates = templates()
    app.mount("/static", StaticFiles(directory=str(HERE / "static")), name="static")

    gate = app.state.gate = Gate()

    @app.middleware("http")
    async def headers(request: Request, call_next):
        counted = not request.url.path.startswith("/static/")
        reason = gate.enter() if counted else ""
        if reason:
            response = HTMLResponse("<!doctype html><title>503 Restoring</title><p>503: "
                                    f"{html.escape(reason)}. Every session ends with it: "
                                    "log in again in a minute. <a href='/login'>Log in</a>"
                                    "</p>", status_code=503, headers={"Retry-After": "30"})
        else:
            try:
                response = await call_next(request)
            finally:
                if counted:
                    gate.leave()
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
