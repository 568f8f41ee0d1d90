"""What every page of gonio serve needs: the session, the CSRF check, rendering, files."""

from __future__ import annotations

import re
import threading
from typing import Annotated

from fastapi import Depends, Request
from fastapi.responses import HTMLResponse, Response

from gonio.records import auth, services
from gonio.records.models import User
from gonio.web.front import (COOKIE, LOGIN_COOKIE, LOGIN_COOKIE_AGE_S,  # noqa: F401  (the pages')
                             fmt, fresh_token)

PAGE = 50
#: calibration files a browser may download, with their media types
FILE_TYPES = {"certificate.pdf": "application/pdf", "certificate.html": "text/html",
              "certificate.dcc.xml": "application/xml", "results.json": "application/json",
              "summary.txt": "text/plain", "io.log": "text/plain", "lab.toml": "text/plain",
              "bench-request.json": "application/json", "table_calibration.csv": "text/csv"}


class Redirect(Exception):
    def __init__(self, url: str):
        self.url = url


class Forbidden(Exception):
    pass


def current(request: Request) -> tuple[User, str]:
    """(user, CSRF token) of the request's session; a redirect to the login page without."""
    got = auth.session_user(request.app.state.store, request.cookies.get(COOKIE))
    if got is None:
        raise Redirect("/login")
    return got


#: A page's ``session: Session`` parameter: (user, CSRF token) of the request's session, resolved
#: by FastAPI before the page's code runs (:func:`current`; without a session: the login page).
Session = Annotated[tuple[User, str], Depends(current)]


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
                  number: str = "", own_name: str = "") -> Response:
    """A stored file; its download name carries the certificate ``number`` (``GC-2026-0001.pdf``,
    ``GC-2026-0001.dcc.xml``, ``GC-2026-0001-results.json``) when one is given. ``own_name``:
    the name the file was uploaded under (a table calibration's), offered as the download
    name too, percent-encoded (RFC 6266 ``filename*``), so no character of it reaches the
    header as it is. Both names carry the ``number``: ``filename=`` the name with every
    character outside ASCII letters, digits and ``._-()+, `` as ``_``, ``filename*=`` the
    same name whole (``DRAFT-7-RT-07 cal.csv``); a name holding an invisible or
    direction-changing character (:func:`gonio.records.services.unshowable`) is not offered."""
    from urllib.parse import quote

    media = FILE_TYPES.get(name, "application/octet-stream")
    own = own_name if own_name and own_name != name \
        and not services.unshowable(own_name) else ""
    base = own or name
    shown = base
    if number and re.fullmatch(r"[A-Za-z0-9-]+", number):
        shown = number + (base[len("certificate"):] if base.startswith("certificate.")
                          else "-" + base)
    plain = re.sub(r"[^A-Za-z0-9._()+, -]", "_", shown)
    disp = f'{disposition}; filename="{plain}"'
    if own:
        disp += f"; filename*=UTF-8''{quote(shown, safe='')}"
    headers = {"Content-Disposition": disp}
    if media == "text/html":
        headers["Content-Security-Policy"] = "sandbox; default-src 'none'; img-src data:; " \
                                             "style-src 'unsafe-inline'"
    return Response(services.file_bytes(store, sha), media_type=media, headers=headers)



class Gate:
    """The server's maintenance state. Every request but the static files passes it
    (:meth:`enter` … :meth:`leave`, counted); while it is closed (a restore replacing the
    records) every other request is answered 503 with the reason, and the request that
    closed it waits for those in flight to end first, so nobody sees the records half
    replaced."""

    def __init__(self):
        self._cond = threading.Condition()
        self.busy = 0
        self.reason = ""

    def enter(self) -> str:
        """Count a request in; the reason when the gate is closed (the request is not
        counted then)."""
        with self._cond:
            if self.reason:
                return self.reason
            self.busy += 1
            return ""

    def leave(self) -> None:
        with self._cond:
            self.busy -= 1
            self._cond.notify_all()

    def close(self, reason: str, timeout_s: float = 30) -> bool:
        """Close the gate from inside a request (itself counted): wait until it is the only
        one in flight. False (and the gate open again) when it was closed already or the
        others did not end within ``timeout_s``."""
        with self._cond:
            if self.reason:
                return False
            self.reason = reason
            if self._cond.wait_for(lambda: self.busy <= 1, timeout_s):
                return True
            self.reason = ""
            return False

    def open(self) -> None:
        with self._cond:
            self.reason = ""
