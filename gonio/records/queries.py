"""Reading the records for lists and pages (what ``gonio serve`` shows), paginated so a
page costs the same with ten or ten thousand calibrations (indexed columns only).

Each function returns plain dicts or detached records and the total count.
"""

from __future__ import annotations

from sqlalchemy import func, or_, select
from sqlalchemy.orm import selectinload

from gonio.records.models import (AuditEvent, Calibration, CalibrationFile, CalibrationStandard,
                                  Certificate, Customer, Instrument, ResultItem, Standard, User)


def _page(s, stmt, page: int, size: int):
    total = s.scalar(select(func.count()).select_from(stmt.order_by(None).subquery()))
    rows = s.scalars(stmt.limit(size).offset((page - 1) * size)).all()
    return rows, total


def customers(store) -> list[Customer]:
    """Every customer, by name."""
    with store.session() as s:
        return s.scalars(select(Customer).order_by(Customer.name)).all()


def instruments(store, page: int = 1, size: int = 50, search: str = ""):
    """(instruments of the page with their customer, total); ``search`` matches serial,
    model or manufacturer (substring)."""
    stmt = select(Instrument).options(selectinload(Instrument.customer)).order_by(
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
        inst = s.scalar(select(Instrument).options(selectinload(Instrument.customer))
                        .where(Instrument.id == inst_id))
        if inst is None:
            return None, []
        cals = s.scalars(select(Calibration).options(selectinload(Calibration.created_by))
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
    stmt = select(Calibration).options(
        selectinload(Calibration.instrument).selectinload(Instrument.customer),
        selectinload(Calibration.created_by)).order_by(Calibration.id.desc())
    if status:
        stmt = stmt.where(Calibration.status == status)
    with store.session() as s:
        return _page(s, stmt, page, size)


def calibration_page(store, cal_id: int) -> dict | None:
    """Everything the calibration page shows."""
    from gonio.errors import GonioError
    from gonio.records.services import calibration, seal

    try:
        cal = calibration(store, cal_id)
    except Exception:
        return None
    with store.session() as s:
        items = s.scalars(select(ResultItem).where(ResultItem.calibration_id == cal_id)
                          .order_by(ResultItem.id)).all()
        files = [f.name for f in s.scalars(select(CalibrationFile).where(
            CalibrationFile.calibration_id == cal_id).order_by(CalibrationFile.name))]
        stds = s.execute(select(Standard, CalibrationStandard.due_on_at_use)
                         .join(CalibrationStandard,
                               CalibrationStandard.standard_id == Standard.id)
                         .where(CalibrationStandard.calibration_id == cal_id)).all()
        certs = s.scalars(select(Certificate).where(Certificate.calibration_id == cal_id)
                          .order_by(Certificate.id)).all()
    try:
        sealed, broken = seal(store, cal_id), ""
    except GonioError as exc:                 # no result yet, or one that no longer matches
        sealed, broken = "", str(exc) if cal.results_sha256 else ""
    return {"cal": cal, "items": items, "files": files, "standards": stds, "certs": certs,
            "seal": sealed, "seal_error": broken}


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


def standards(store):
    """Every standard, soonest due first."""
    with store.session() as s:
        return s.scalars(select(Standard).order_by(Standard.due_on)).all()


def users(store):
    with store.session() as s:
        return s.scalars(select(User).order_by(User.username)).all()


def audit_events(store, page: int = 1, size: int = 100):
    """(audit events newest first, total)."""
    with store.session() as s:
        return _page(s, select(AuditEvent).order_by(AuditEvent.id.desc()), page, size)


def counts_by_status(store) -> dict:
    """How many calibrations are in each state."""
    with store.session() as s:
        return dict(s.execute(select(Calibration.status, func.count())
                              .group_by(Calibration.status)).all())
