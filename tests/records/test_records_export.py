"""Every list exported as CSV (formula cells neutralised), the audit trail filtered by record
and person and exported (reviewers and admins only)."""

from __future__ import annotations

import csv
import io

from gonio.records import queries, services

from .test_web_security import app, login  # noqa: F401  (the app fixture)


def rows_of(r):
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/csv")
    return list(csv.reader(io.StringIO(r.text)))


def test_lists_exported_as_csv(app, sqlite_store):  # noqa: F811
    tech = services.user(sqlite_store, "tech")
    services.add_customer(sqlite_store, tech, "=HYPERLINK(\"http://x\")", "1 Road\nTown")
    c2 = services.add_customer(sqlite_store, tech, "Plain Co")
    services.register_instrument(sqlite_store, tech, customer_id=c2.id, serial="S-1",
                                 spec_key="ogam-draft")
    services.register_instrument(sqlite_store, tech, customer_id=c2.id, serial="S-2",
                                 spec_key="ogam-draft", gyro_type="fog")
    services.add_standard(sqlite_store, tech, name="table", identifier="T-1",
                          due_on="2030-01-01")
    web = login(app, "tech")
    got = rows_of(web.get("/export/customers.csv"))
    assert got[0] == ["id", "name", "address", "retired_on"]
    assert ["'=HYPERLINK(\"http://x\")", "1 Road\nTown"] == got[1][1:3]
    inst = rows_of(web.get("/export/instruments.csv"))
    assert inst[0][-1] == "gyro_type"                # appended: earlier columns keep their place
    assert {r[5]: r[-1] for r in inst[1:]} == {"S-1": "", "S-2": "fog"}
    services.add_standard(sqlite_store, tech, name="old level", identifier="L-1",
                          due_on="2020-01-01", out_of_service="overdue, kept for its history")
    std = rows_of(web.get("/export/standards.csv"))
    assert {r[2]: r[7] for r in std[1:]}["T-1"] == "2030-01-01"
    # a standard registered out of service exports with its reason (appended column)
    assert std[0][-1] == "out_of_service"
    assert {r[2]: r[-1] for r in std[1:]} == {"T-1": "", "L-1": "overdue, kept for its history"}
    for name in ("calibrations", "certificates", "due"):
        assert len(rows_of(web.get(f"/export/{name}.csv"))) == 1, name    # the header
    assert web.get("/export/nothing.csv").status_code == 404
    assert web.get("/export/audit.csv").status_code == 403               # a technician
    assert 'filename="gonio-customers-' in web.get("/export/customers.csv").headers[
        "content-disposition"]


def test_audit_filtered_and_exported(app, sqlite_store):  # noqa: F811
    tech = services.user(sqlite_store, "tech")
    admin = services.user(sqlite_store, "admin")
    a = services.add_customer(sqlite_store, tech, "A")
    services.add_customer(sqlite_store, admin, "B")
    services.update_customer(sqlite_store, tech, a.id, address="2 Road")
    web = login(app, "rev")
    got = rows_of(web.get(f"/export/audit.csv?entity=customer&entity_id={a.id}"))
    assert [(r[2], r[3]) for r in got[1:]] == [("tech", "update"), ("tech", "create")]
    got = rows_of(web.get("/export/audit.csv?username=admin&entity=customer"))
    assert [r[5] for r in got[1:]] == ["2"]
    page = web.get("/audit?username=tech&entity=customer").text
    assert page.count("<td>tech</td>") == 2 and "<td>admin</td>" not in page
    assert 'href="/export/audit.csv?entity=customer&amp;username=tech"' in page
    # readable: the field the update changed, from what to what (not only the raw JSON)
    assert '<div class="change"><b>address</b>: — → 2 Road</div>' in page
    assert queries.audit_changes('{"a": 1, "b": "x", "d": null}',
                                 '{"a": 1, "b": "y", "c": [2], "d": ""}') == [
        ("b", "x", "y"), ("c", "", "[2]")]
    assert queries.audit_changes("[1]", "{}") == [("(state)", "[1]", "{}")]
