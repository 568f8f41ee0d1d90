"""What every page of gonio serve needs: the session, the CSRF check, rendering, files."""

from __future__ import annotations

import datetime as _dt
import math
import re
import secrets

from fastapi import Request
from fastapi.responses import HTMLResponse, Response

from gonio.records import auth, services
from gonio.records.models import User
from gonio.units import S_PER_H

COOKIE, LOGIN_COOKIE = "gonio_session", "gonio_login"
#: lifetime of the login form's CSRF cookie
LOGIN_COOKIE_AGE_S = int(S_PER_H)
PAGE = 50
#: calibration files a browser may download, with their media types
FILE_TYPES = {"certificate.pdf": "application/pdf", "certificate.html": "text/html",
              "certificate.dcc.xml": "application/xml", "results.json": "application/json",
              "summary.txt": "text/plain", "io.log": "text/plain", "lab.toml": "text/plain",
              "bench-request.json": "application/json"}


class Redirect(Exception):
    def __init__(self, url: str):
        self.url = url


class Forbidden(Exception):
    pass


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



def current(request: Request) -> tuple[User, str]:
    """(user, CSRF token) of the request's session; a redirect to the login page without."""
    got = auth.session_user(request.app.state.store, request.cookies.get(COOKIE))
    if got is None:
        raise Redirect("/login")
    return got


async def form(request: Request, csrf: str) -> dict:
    """The POSTed form, its CSRF token checked against the session's."""
    data = await request.form(max_files=4, max_fields=200, max_part_size=2 * 2**20)
    if not auth.same_token(data.get("csrf"), csrf):
        raise Forbidden()
    return data


def render(request: Request, name: str, user: User | None, csrf: str | None,
           status_code: int = 200, **ctx) -> HTMLResponse:
    ctx.update(request=request, user=user, csrf=csrf)
    return request.app.state.templates.TemplateResponse(request, name, ctx,
                                                        status_code=status_code)


def page_of(request: Request) -> int:
    try:
        return max(1, min(int(request.query_params.get("page", "1")), 10**6))
    except ValueError:
        return 1


def wake(request: Request) -> None:
    d = request.app.state.dispatcher
    if d is not None:
        d.wake()


def file_response(store, sha: str, name: str, disposition: str = "inline",
                  number: str = "") -> Response:
    """A stored file; its download name carries the certificate ``number`` (``GC-2026-0001.pdf``,
    ``GC-2026-0001.dcc.xml``, ``GC-2026-0001-results.json``) when one is given."""
    media = FILE_TYPES.get(name, "application/octet-stream")
    shown = name
    if number and re.fullmatch(r"[A-Za-z0-9-]+", number):
        shown = number + (name[len("certificate"):] if name.startswith("certificate.")
                          else "-" + name)
    headers = {"Content-Disposition": f'{disposition}; filename="{shown}"'}
    if media == "text/html":
        headers["Content-Security-Policy"] = "sandbox; default-src 'none'; img-src data:; " \
                                             "style-src 'unsafe-inline'"
    return Response(services.file_bytes(store, sha), media_type=media, headers=headers)


def fresh_token() -> str:
    return secrets.token_urlsafe(32)

