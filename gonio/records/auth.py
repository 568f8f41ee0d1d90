"""Users, passwords, login throttling and browser sessions (docs/records.md#security).

* Passwords are stored as Argon2id hashes (argon2-cffi, its default parameters: RFC 9106's
  low-memory choice); a hash made with older parameters is rehashed at the next login.
* Login throttling: after :data:`MAX_FAILURES` failed logins for one user name, or
  :data:`MAX_FAILURES_PER_ADDRESS` from one address, within :data:`WINDOW`, further attempts
  are refused without checking the password until the window has passed.
* A session is a random 256-bit token in an HttpOnly cookie; the database keeps only its
  SHA-256 (a stolen database holds no usable session), with a per-session CSRF token that
  every POST must carry, and an expiry.
"""

from __future__ import annotations

import datetime as _dt
import functools
import hashlib
import hmac
import secrets

from argon2 import PasswordHasher
from argon2.exceptions import InvalidHashError, VerificationError, VerifyMismatchError
from sqlalchemy import delete, func, select
from sqlalchemy.orm import joinedload

from gonio.errors import GonioError, TooManyAttemptsError
from gonio.records.models import ROLES, LoginFailure, User, WebSession, utcnow

MAX_FAILURES = 5
MAX_FAILURES_PER_ADDRESS = 20
WINDOW = _dt.timedelta(minutes=15)
SESSION_LIFETIME = _dt.timedelta(hours=12)
MIN_PASSWORD = 8

_HASHER = PasswordHasher()


@functools.cache
def _dummy_hash() -> str:
    """A hash verified when the user does not exist, so both cases take the same time; made
    at the first such login, not at import (every worker process imports this module, and
    one Argon2id hash is half a second)."""
    return _HASHER.hash("not a password of anyone")


def hash_password(password: str) -> str:
    """An Argon2id hash of ``password`` (at least :data:`MIN_PASSWORD` characters)."""
    if not isinstance(password, str) or len(password) < MIN_PASSWORD:
        raise GonioError(f"a password needs at least {MIN_PASSWORD} characters", key="password")
    if len(password) > 1024:
        raise GonioError("password longer than 1024 characters", key="password")
    return _HASHER.hash(password)


def check_roles(roles) -> str:
    """``roles`` (a list or a space-separated string) checked against :data:`ROLES`."""
    names = roles.split() if isinstance(roles, str) else list(roles)
    bad = [r for r in names if r not in ROLES]
    if bad or not names:
        raise GonioError(f"roles must be some of {', '.join(ROLES)}", key="roles")
    return " ".join(r for r in ROLES if r in names)


def throttled(s, username: str, address: str) -> bool:
    """True when this user name or address has failed too often within :data:`WINDOW`."""
    since = utcnow() - WINDOW
    by_name = s.scalar(select(func.count()).select_from(LoginFailure).where(
        LoginFailure.username == username, LoginFailure.at >= since))
    by_addr = s.scalar(select(func.count()).select_from(LoginFailure).where(
        LoginFailure.address == address, LoginFailure.at >= since))
    return by_name >= MAX_FAILURES or by_addr >= MAX_FAILURES_PER_ADDRESS


def authenticate(store, username: str, password: str, address: str = "") -> User:
    """The active user with this name and password; a GonioError (the same message whether
    the name or the password was wrong) otherwise, or when throttled."""
    username = (username or "")[:64]
    address = (address or "")[:64]
    with store.writing() as s:
        if throttled(s, username, address):
            raise TooManyAttemptsError("too many failed logins; try again later", key="login")
        user = s.scalar(select(User).where(User.username == username))
        ok = False
        try:
            ok = _HASHER.verify(user.password_hash if user else _dummy_hash(), password or "")
        except (VerifyMismatchError, VerificationError, InvalidHashError):
            ok = False
        if not ok or user is None or not user.active:
            s.add(LoginFailure(username=username, address=address))
            s.commit()
            raise GonioError("wrong user name or password", key="login")
        if _HASHER.check_needs_rehash(user.password_hash):
            user.password_hash = _HASHER.hash(password)
        s.execute(delete(LoginFailure).where(LoginFailure.username == username))
        s.commit()
        s.refresh(user)
        s.expunge(user)
        return user


def _digest(token: str) -> str:
    return hashlib.sha256(token.encode()).hexdigest()


def open_session(store, user: User) -> tuple[str, str]:
    """A new browser session for ``user``: (cookie token, CSRF token)."""
    token, csrf = secrets.token_urlsafe(32), secrets.token_urlsafe(32)
    with store.writing() as s:
        s.execute(delete(WebSession).where(WebSession.expires_at < utcnow()))
        s.add(WebSession(id=_digest(token), user_id=user.id, csrf_token=csrf,
                         expires_at=utcnow() + SESSION_LIFETIME))
        s.commit()
    return token, csrf


def session_user(store, token: str | None) -> tuple[User, str] | None:
    """(user, CSRF token) of a live session, or None."""
    if not token or len(token) > 200:
        return None
    with store.session() as s:          # the session and its user in one query
        ws = s.get(WebSession, _digest(token), options=[joinedload(WebSession.user)])
        if ws is None or ws.expires_at < utcnow() or not ws.user.active:
            return None
        user = ws.user
        s.expunge(user)
        return user, ws.csrf_token


def close_session(store, token: str | None) -> None:
    """Log out: the session's row is deleted."""
    if token:
        with store.writing() as s:
            s.execute(delete(WebSession).where(WebSession.id == _digest(token)))
            s.commit()


def same_token(a: str | None, b: str | None) -> bool:
    """Constant-time comparison of two tokens (False if either is missing)."""
    return bool(a) and bool(b) and hmac.compare_digest(str(a).encode(), str(b).encode())
