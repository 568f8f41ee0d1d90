"""The due list (paged, searchable, per customer, CSV), the printable recall notices and a
reference standard's history page, through HTTP (Starlette's TestClient). The issued
calibrations are written as rows (a certificate row with a stored file), so that a long list
costs nothing to build; the due dates are checked against dates computed here with
``calendar`` (the last issued calibration plus the interval)."""

from __future__ import annotations

import calendar
import csv
import datetime as dt
import io
import re

from gonio.records import queries, services
from gonio.records.models import Calibration, CalibrationStandard, Certificate

from .test_web_security import app, login  # noqa: F401  (the app fixture)


def plus_months(day: dt.date, months: int) -> dt.date:
    y, m = divmod(day.month - 1 + months, 12)
    return dt.date(day.year + y, m + 1, min(day.day, calendar.monthrange(day.year + y,
                                                                           m + 1)[1]))


def issued(store, inst_id: int, day: dt.date, number: str, std_id: int | None = None) -> int:
    """An issued calibration of the instrument on ``day`` (rows only)."""
    sha, _ = services.store_file(store, io.BytesIO(number.encode()))
    with store.writing() as s:
        cal = Calibration(instrument_id=inst_id, spec_key="ogam-draft", readings_sha256=sha,
                          performed_on=day, status="issued", results_sha256=sha)
        s.add(cal)
        s.flush()
        s.add(Certificate(number=number, calibration_id=cal.id, html_sha256=sha,
                          pdf_sha256=sha, results_sha256=sha))
        if std_id is not None:
            s.add(CalibrationStandard(calibration_id=cal.id, standard_id=std_id,
                                      due_on_at_use=dt.date(2099, 1, 1)))
        s.commit()
        return cal.id


def fleet(store, n: int, today: dt.date):
    """``n`` instruments of two customers (even i: the first), each issued once, the i-th
    12 months before ``today`` + (i − 30) days: due about i − 30 days from today."""
    tech = services.user(store, "tech")
    custs = [services.add_customer(store, tech, name, f"{name} Road 1\nTown")
             for name in ("Alpha Gyro Ltd", "Beta Nav Co")]
    out = []
    for i in range(n):
        inst = services.register_instrument(store, tech, customer_id=custs[i % 2].id,
                                            serial=f"SN-{i:03d}", spec_key="ogam-draft",
                                            model="RLG-GM-1", interval_months=12)
        day = plus_months(today, -12) + dt.timedelta(days=i - 30)
        issued(store, inst.id, day, f"GC-2025-{i + 1:04d}")
        out.append((inst, day))
    return custs, out


def recalibrated_standard(store, name: str, first: tuple, second: tuple):
    """A standard registered with ``first`` (its certificate, calibrated on, due on) and
    recalibrated with ``second``. A ``first`` already past its due date is registered out of
    service with its reason (the records refuse it otherwise); a ``second`` already past is
    recorded with a reason too (an edit follows the same rule)."""
    from gonio.records.models import is_past_due, records_today

    tech = services.user(store, "tech")
    past = is_past_due(dt.date.fromisoformat(first[2]), records_today(store))
    std = services.add_standard(store, tech, name=name, identifier="RT-07",
                                **dict(zip(("certificate", "calibrated_on", "due_on"), first)),
                                out_of_service="registered with its history" if past else "")
    again = is_past_due(dt.date.fromisoformat(second[2]),
                        records_today(store))                # an edit follows the same rule
    services.update_standard(store, tech, std.id,
                             **dict(zip(("certificate", "calibrated_on", "due_on"), second)),
                             out_of_service="recorded with its history" if again else None)
    return std


def rows_of(html: str) -> list[str]:
    return re.findall(r'<a href="/instruments/\d+">RLG-GM-1 (SN-\d+)</a>', html)


def test_due_list_paged_searched_and_exported(app, sqlite_store):  # noqa: F811
    today = dt.date.today()
    custs, made = fleet(sqlite_store, 80, today)
    web = login(app, "tech")
    due = sorted(((plus_months(day, 12), inst.serial) for inst, day in made))
    want = [serial for d, serial in due if (d - today).days <= 30]
    assert 50 < len(want) < 80      # about 61: two pages, and some not due yet
    r = web.get("/due")
    assert r.status_code == 200 and f"{len(want)} in all · page 1 of 2" in r.text
    assert rows_of(r.text) == want[:50]
    assert rows_of(web.get("/due?page=2").text) == want[50:]
    r = web.get("/due?q=sn-00")                         # any case: serials SN-000 … SN-009
    assert sorted(rows_of(r.text)) == [f"SN-{i:03d}" for i in range(10)]
    r = web.get("/due?within_days=365")
    assert "80 in all" in r.text
    r = web.get("/due?customer=Beta+Nav+Co")
    assert rows_of(r.text) == [s for s in want if int(s[3:]) % 2 == 1]
    got = list(csv.reader(io.StringIO(web.get("/export/due.csv?customer=Beta+Nav+Co&q=SN-01")
                                      .text)))
    assert got[0][:3] == ["customer", "instrument", "model"]
    assert [row[3] for row in got[1:]] == [s for s in want if int(s[3:]) % 2 == 1
                                          and s.startswith("SN-01")]
    # a retired instrument is not recalled
    services.update_instrument(sqlite_store, services.user(sqlite_store, "tech"),
                               made[0][0].id, retire=True)
    assert "SN-000" not in rows_of(web.get("/due?q=SN-000").text)
    # the dashboard shows the first 20 and links to all
    assert f'all {len(want) - 1} due' in web.get("/").text


def test_recall_notices_one_per_customer(app, sqlite_store):  # noqa: F811
    today = dt.date.today()
    services.set_settings(sqlite_store, None, lab_name="Example Angle Laboratory",
                          lab_address="9 Lab Lane\nXi'an")
    custs, made = fleet(sqlite_store, 6, today)
    web = login(app, "tech")
    r = web.get("/due/recall")
    sections = r.text.split('<section class="recall">')[1:]
    assert len(sections) == 2                       # one notice per customer
    assert "Alpha Gyro Ltd" in sections[0] and "Beta Nav Co" in sections[1]
    assert "Example Angle Laboratory" in sections[0] and "Alpha Gyro Ltd Road 1\nTown" in \
        sections[0]
    for inst, day in made:
        sec = sections[0 if int(inst.serial[3:]) % 2 == 0 else 1]
        assert f"<td>{inst.serial}</td><td>GC-2025-{int(inst.serial[3:]) + 1:04d}</td>" \
               f"<td>{day}</td><td>{plus_months(day, 12)}" in sec
    one = web.get("/due/recall?customer=Beta+Nav+Co").text
    assert one.count('<section class="recall">') == 1 and "Alpha Gyro Ltd" not in one
    assert "Nothing is due for Nobody" in web.get("/due/recall?customer=Nobody").text
    css = web.get("/static/style.css").text
    assert "@media print" in css and "break-after: page" in css


def test_standard_history_page(app, sqlite_store):  # noqa: F811
    today = dt.date.today()
    std = recalibrated_standard(sqlite_store, "rotary table",
                                ("NIM-2024-1", "2024-01-05", "2025-01-05"),
                                ("NIM-2025-7", "2025-01-03", "2026-01-03"))
    custs, made = fleet(sqlite_store, 2, today)
    for inst, day in made:
        issued(sqlite_store, inst.id, day - dt.timedelta(days=400), f"GC-2024-{inst.id:04d}",
               std.id)
    web = login(app, "tech")
    assert f'<a href="/standards/{std.id}">rotary table</a>' in web.get("/standards").text
    r = web.get(f"/standards/{std.id}")
    assert r.status_code == 200
    text = re.sub(r"\s+", " ", r.text)
    text = text[text.index("due dates over time"):]
    # both certificates of the standard and their due dates, oldest first
    assert text.index("NIM-2024-1") < text.index("NIM-2025-7")
    assert "<td>2024-01-05</td><td>2025-01-05</td>" in text
    assert "<td>2025-01-03</td><td>2026-01-03</td>" in text
    assert "Used in 2 calibrations" in text
    for inst, _ in made:
        assert f"GC-2024-{inst.id:04d}" in text and inst.serial in text
    d = queries.standard_history(sqlite_store, std.id, 1, 1)
    assert d["total"] == 2 and len(d["uses"]) == 1
    assert web.get("/standards/999999").status_code == 404


def test_due_and_standard_history_queries(store):
    """The due list's and a standard's history queries on SQLite and PostgreSQL."""
    from .conftest import make_people

    make_people(store)
    today = dt.date.today()
    std = recalibrated_standard(store, "rotary table", ("A-1", "2024-01-05", "2025-01-05"),
                                ("A-2", "2025-01-03", "2026-01-03"))
    _, made = fleet(store, 40, today)
    for inst, day in made[:3]:
        issued(store, inst.id, day - dt.timedelta(days=400), f"GC-2024-{inst.id:04d}", std.id)
    want = sorted((plus_months(day, 12), inst.serial) for inst, day in made)
    due_serials = [serial for d, serial in want if (d - today).days <= 30]
    rows, total = queries.due(store, 2, 10, "sn-0")
    assert total == len([s for s in due_serials if s.startswith("SN-0")])
    assert [r["serial"] for r in rows] == [s for s in due_serials if s.startswith("SN-0")][10:20]
    notices = queries.recall(store, "Beta Nav Co")
    assert [n["customer"] for n in notices] == ["Beta Nav Co"]
    assert [r["serial"] for r in notices[0]["rows"]] == [s for s in due_serials
                                                        if int(s[3:]) % 2 == 1]
    d = queries.standard_history(store, std.id, 1, 2)
    assert [c["certificate"] for c in d["changes"]] == ["A-1", "A-2"]
    assert d["total"] == 3 and len(d["uses"]) == 2


def test_dashboard_links_every_waiting_and_lists_the_failed(app, sqlite_store):  # noqa: F811
    """More than 20 awaiting review: the overview shows 20 and links the whole list (paged
    by 50); failed calibrations are listed, not only counted (void ones are not)."""
    tech = services.user(sqlite_store, "tech")
    cust = services.add_customer(sqlite_store, tech, "Alpha Gyro Ltd", "Road 1\nTown")
    inst = services.register_instrument(sqlite_store, tech, customer_id=cust.id,
                                        serial="SN-1", spec_key="ogam-draft",
                                        model="RLG-GM-1", interval_months=12)
    sha, _ = services.store_file(sqlite_store, io.BytesIO(b"readings"))
    ids = {"computed": [], "failed": [], "void": []}
    with sqlite_store.writing() as s:
        for state, n in (("computed", 55), ("failed", 3), ("void", 2)):
            for _ in range(n):
                cal = Calibration(instrument_id=inst.id, spec_key="ogam-draft",
                                  readings_sha256=sha, performed_on=dt.date(2025, 3, 1),
                                  status=state, error="" if state == "computed" else "x")
                s.add(cal)
                s.flush()
                ids[state].append(cal.id)
        s.commit()
    web = login(app, "tech")
    page = web.get("/").text
    sections = dict(re.findall(r"<h2>([^<]+)</h2>(.*?)(?=<h2>|$)", page, re.S))

    def listed(html: str) -> set[int]:
        return {int(i) for i in re.findall(r'<td><a href="/calibrations/(\d+)">', html)}

    review = sections["Awaiting review"]
    assert '<a href="/calibrations?status=computed">all 55 awaiting review</a>' in review
    assert len(listed(review)) == 20 and listed(review) <= set(ids["computed"])
    failed = sections["Failed"]
    assert '<a href="/calibrations?status=failed">all 3 failed</a>' in failed
    assert listed(failed) == set(ids["failed"])
    whole = set()
    for p in (1, 2):
        whole |= listed(web.get(f"/calibrations?status=computed&page={p}").text)
    assert whole == set(ids["computed"])
    assert listed(web.get("/calibrations?status=failed").text) == set(ids["failed"])


def calibrations_in_states(store, states: dict) -> dict:
    """Calibration rows of one instrument in the given states (state → how many): state →
    their ids."""
    tech = services.user(store, "tech")
    cust = services.add_customer(store, tech, "Gamma Gyro Ltd", "Road 3")
    inst = services.register_instrument(store, tech, customer_id=cust.id, serial="SN-W",
                                        spec_key="ogam-draft", model="RLG-GM-1")
    sha, _ = services.store_file(store, io.BytesIO(b"readings"))
    ids: dict = {state: [] for state in states}
    with store.writing() as s:
        for state, n in states.items():
            for _ in range(n):
                cal = Calibration(instrument_id=inst.id, spec_key="ogam-draft",
                                  readings_sha256=sha, performed_on=dt.date(2025, 3, 1),
                                  status=state)
                s.add(cal)
                s.flush()
                ids[state].append(cal.id)
        s.commit()
    return ids


WORK = {"queued": 2, "running": 2, "issuing": 1, "drafting": 3, "computed": 1, "failed": 1}


def test_active_work_query(store):
    """The work under way: running, issuing and drafting, on SQLite and PostgreSQL (before:
    the overview listed only 'running')."""
    from .conftest import make_people

    make_people(store)
    ids = calibrations_in_states(store, WORK)
    want = sorted(ids["running"] + ids["issuing"] + ids["drafting"], reverse=True)
    rows, total = queries.active_work(store)
    assert [c.id for c in rows] == want and total == 6
    rows, total = queries.active_work(store, size=4)
    assert [c.id for c in rows] == want[:4] and total == 6


def test_dashboard_lists_every_calibration_being_worked_on(app, sqlite_store):  # noqa: F811
    """The overview's section of work under way lists those being computed, issued or having
    their draft rendered again, and none other."""
    ids = calibrations_in_states(sqlite_store, WORK)
    page = login(app, "tech").get("/").text
    sections = dict(re.findall(r"<h2>([^<]+)</h2>(.*?)(?=<h2>|$)", page, re.S))
    active = sections["Being worked on"]
    listed = {int(i) for i in re.findall(r'<td><a href="/calibrations/(\d+)">', active)}
    assert listed == set(ids["running"] + ids["issuing"] + ids["drafting"])
    assert "6 being computed, issued or having their draft rendered again" in active


def test_list_pages_sort_only_ids_beyond_the_page(store):
    """A list page is chosen on the ids (LIMIT/OFFSET over the ids alone) and only its own
    rows are read whole: every page equals the slice of all ids in the list's order (read
    here with a plain query), and on PostgreSQL no plan node sorts wide rows (whole
    calibrations joined to their instrument, customer and author) beyond the page's own —
    before, without fresh statistics, all of them were joined and sorted for every page."""
    import json

    from sqlalchemy import insert, select

    from gonio.records import blobs
    from gonio.records.models import Blob, Customer, Instrument
    from tests.records.conftest import make_people

    user = make_people(store)["tech"]
    sha = blobs.put_bytes(store.blob_root, b"page")
    with store.writing() as s:
        s.add(Blob(sha256=sha, size=4))
        s.add(Customer(id=1, name="C", address=""))
        s.add(Instrument(id=1, customer_id=1, kind="gyro", manufacturer="W", model="M",
                         serial="S", spec_key="ogam-draft", limits_json="[]"))
        s.flush()
        s.execute(insert(Calibration), [
            {"instrument_id": 1, "spec_key": "ogam-draft", "readings_sha256": sha,
             "readings_name": "r.csv", "status": ("issued", "computed")[c % 2],
             "review_comment": f"{c} " + "x" * 2000,                 # wide rows
             "performed_on": dt.date(2020, 1, 1) + dt.timedelta(days=c),
             "created_by_id": user.id, "results_sha256": sha} for c in range(120)])
        s.commit()
        every = s.scalars(select(Calibration.id).order_by(Calibration.id.desc())).all()
        computed = s.scalars(select(Calibration.id).where(Calibration.status == "computed")
                             .order_by(Calibration.id.desc())).all()
    for page in (1, 2, 5, 9):
        rows, total = queries.calibrations(store, page, 14)
        assert ([c.id for c in rows], total) == (every[(page - 1) * 14:page * 14], 120)
        assert all(c.instrument.customer.name == "C" for c in rows)
    rows, total = queries.calibrations(store, 3, 7, status="computed")
    assert ([c.id for c in rows], total) == (computed[14:21], 60)
    if store.engine.dialect.name != "postgresql":
        return
    from sqlalchemy import event
    sent = []

    def keep(conn, cursor, statement, params, context, many):
        if "LIMIT" in statement:
            sent.append((statement, params))
    event.listen(store.engine, "before_cursor_execute", keep)
    try:
        queries.calibrations(store, 6, 10)
    finally:
        event.remove(store.engine, "before_cursor_execute", keep)
    assert len(sent) == 1, sent

    def sorts(node):
        if node["Node Type"] in ("Sort", "Incremental Sort"):
            yield node
        for child in node.get("Plans", []):
            yield from sorts(child)
    with store.engine.connect() as conn:
        plan = conn.exec_driver_sql("EXPLAIN (ANALYZE, FORMAT JSON) " + sent[0][0],
                                    sent[0][1]).scalar()
    plan = plan if isinstance(plan, list) else json.loads(plan)
    wide = [(n["Plan Width"], n["Actual Rows"]) for n in sorts(plan[0]["Plan"])
            if n["Plan Width"] > 64]
    assert all(rows <= 10 for _, rows in wide), (wide, plan)
