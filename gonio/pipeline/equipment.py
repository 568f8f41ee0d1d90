"""The laboratory's equipment files a calibration reads: the rotary table's calibration named
by the laboratory file's ``[table_calibration]`` (docs/formats.md, "Laboratory file").

:func:`lab_table_calibration` resolves the file (relative to the laboratory file), checks its
content against the SHA-256 the laboratory file states and its validity on the calibration's
date, and reconciles it with a file given explicitly (``calibrate --table-calibration``): the
same content is used, another content is refused — never one silently in place of the other.
Every refusal is a :class:`~gonio.errors.GonioError` in one line (exit 2). The pipeline passes
the path on as the specification's ``table_calibration`` option; nothing here reads the file's
rows (the specification does).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
from pathlib import Path

from gonio.errors import GonioError

__all__ = ["lab_table_calibration", "calibration_dates", "check_validity"]

KEY = "table_calibration"


def _sha256(path: Path, lab_file, key: str) -> str:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError as exc:
        raise GonioError(f"cannot read the table calibration {path}: {exc.strerror}",
                         file=lab_file, key=key) from None


def calibration_dates(lab_d: dict | None, metadata: dict) -> list[tuple[_dt.date, str]]:
    """The dates the calibration is of: the readings' ``# date:`` (first 10 characters,
    YYYY-MM-DD) and the laboratory file's ``[certificate] date_of_calibration``, each with
    where it came from; a readings date that is not a date is a GonioError.

    >>> calibration_dates({"certificate": {"date_of_calibration": "2026-03-02"}},
    ...                   {"date": "2026-03-01T10:00"})
    [(datetime.date(2026, 3, 1), 'the readings (# date:)'), (datetime.date(2026, 3, 2), '[certificate] date_of_calibration')]
    """
    out = []
    raw = str(metadata.get("date") or "").strip()
    if raw:
        try:
            out.append((_dt.date.fromisoformat(raw[:10]), "the readings (# date:)"))
        except ValueError:
            raise GonioError(f"the readings' # date: {raw!r} is not a date YYYY-MM-DD",
                             key="date") from None
    lab_day = ((lab_d or {}).get("certificate") or {}).get("date_of_calibration") or ""
    if lab_day:
        out.append((_dt.date.fromisoformat(str(lab_day)[:10]),
                    "[certificate] date_of_calibration"))
    return out


def check_validity(tc: dict, days: list[tuple[_dt.date, str]], lab_file=None) -> None:
    """The laboratory file's ``[table_calibration]`` ``tc`` valid on every date of ``days``
    (``[(date, where it came from)]``, at least one): calibrated on or before it (where
    ``calibrated_on`` is given) and due on or after it; else a one-line GonioError naming
    ``lab_file`` and the key.

    >>> import datetime as dt
    >>> check_validity({"id": "T", "due_on": "2027-01-01"}, [(dt.date(2027, 1, 2), "d")])
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key table_calibration.due_on: the table calibration T was due on 2027-01-01: expired on the calibration's date 2027-01-02 (d)
    """
    ident = f" {tc['id']}" if tc.get("id") else ""
    if not days:
        raise GonioError(f"the table calibration{ident}'s due date {tc['due_on']} cannot be "
                         "checked: the readings state no # date: and [certificate] "
                         "date_of_calibration is empty (give the calibration's date)",
                         file=lab_file, key=f"{KEY}.due_on")
    due = _dt.date.fromisoformat(tc["due_on"])
    done = _dt.date.fromisoformat(tc["calibrated_on"]) if tc.get("calibrated_on") else None
    for day, where in days:
        if day > due:
            raise GonioError(f"the table calibration{ident} was due on {due}: expired on the "
                             f"calibration's date {day} ({where})", file=lab_file,
                             key=f"{KEY}.due_on")
        if done is not None and day < done:
            raise GonioError(f"the table calibration{ident} was made on {done}, after the "
                             f"calibration's date {day} ({where})", file=lab_file,
                             key=f"{KEY}.calibrated_on")


def lab_table_calibration(lab_d: dict | None, lab_file, metadata: dict,
                          given: str | Path | None = None) -> str | None:
    """The table calibration file to use: the laboratory file's ``[table_calibration]``
    checked (its SHA-256 the stated one; calibrated on or before, and due on or after, every
    date of :func:`calibration_dates`, of which there must be one), or ``given`` where the
    laboratory file names none. Both given: the same content (SHA-256) is the one used; a
    different content is refused. ``lab_file``: the laboratory file's path (relative names
    are taken from its folder; None: a laboratory dict, names relative to the current
    folder); ``metadata``: the readings' metadata. Returns a path (text) or None."""
    tc = (lab_d or {}).get(KEY)
    if not tc:
        return None if given is None else str(given)
    name = Path(tc["file"])
    path = name if name.is_absolute() else (
        Path(lab_file).parent if lab_file is not None else Path.cwd()) / name
    sha = _sha256(path, lab_file, f"{KEY}.file")
    if sha != tc["sha256"]:
        raise GonioError(f"the table calibration {path} has SHA-256 {sha}, not the {tc['sha256']} "
                         "stated: the file changed since the laboratory recorded it (record "
                         "the new calibration's SHA-256 and dates, or restore the file)",
                         file=lab_file, key=f"{KEY}.sha256")
    check_validity(tc, calibration_dates(lab_d, metadata), lab_file)
    if given is not None:
        other = _sha256(Path(given), None, "--table-calibration")
        if other != sha:
            raise GonioError(f"give one of them: --table-calibration {Path(given).name} "
                             f"(SHA-256 {other[:16]}…) is not the laboratory file's "
                             f"[table_calibration] {Path(path).name} (SHA-256 {sha[:16]}…)",
                             file=lab_file, key=KEY)
    return str(path)
