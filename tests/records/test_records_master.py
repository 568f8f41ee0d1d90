"""Master data: customers, instruments and standards edited, transferred, retired and
brought back, with the audit trail keeping every earlier state (a standard's certificates
and due dates over time); retired ones are not used by new calibrations."""

from __future__ import annotations

import datetime as dt
import io
import json

import pytest
from sqlalchemy import select

from gonio.errors import GonioError
from gonio.records import services
from gonio.records.models import AuditEvent

from .conftest import conditions, make_people
from .test_records_services import setup_instrument
from .test_web_security import app, csrf_of, login  # noqa: F401  (the app fixture)


def trail(store, entity, entity_id):
    with store.session() as s:
        return [(json.loads(e.before_json), json.loads(e.after_json)) for e in s.scalars(
            select(AuditEvent).where(AuditEvent.entity == entity, AuditEvent.action ==
                                     "update", AuditEvent.entity_id == str(entity_id))
            .order_by(AuditEvent.id))]


def test_standard_recalibrated_and_retired(store):
    people = make_people(store)
    tech = people["tech"]
    inst, std = setup_instrument(store, people)
    # the recalibrated standard: its identifier is not refused as a duplicate any more,
    # the new due date is recorded on it, the earlier one kept in the trail
    with pytest.raises(GonioError, match="record its recalibration by editing it"):
        services.add_standard(store, tech, name="rotary table", identifier="RT-07",
                              due_on="2030-01-01")
    old_due = std.due_on
    new_due = old_due + dt.timedelta(days=365)
    services.update_standard(store, tech, std.id, certificate="NIM-2026-1",
                             calibrated_on=dt.date.today(), due_on=new_due)
    (before, after), = trail(store, "standard", std.id)
    assert (before["due_on"], after["due_on"]) == (old_due.isoformat(), new_due.isoformat())
    assert after["certificate"] == "NIM-2026-1"
    with pytest.raises(GonioError, match="due date is before the calibration date"):
        services.update_standard(store, tech, std.id, calibrated_on="2026-01-02",
                                 due_on="2026-01-01")
    services.update_standard(store, tech, std.id, retire=True)
    sha, _ = services.store_file(store, io.BytesIO(b"x"))
    with pytest.raises(GonioError, match="RT-07 was retired on"):
        services.create_calibration(store, tech, instrument_id=inst.id, readings_sha256=sha,
                                    **dict(conditions(store, tech), standard_ids=[std.id]))
    services.update_standard(store, tech, std.id, retire=False)
    assert services.create_calibration(store, tech, instrument_id=inst.id,
                                       readings_sha256=sha,
                                       **dict(conditions(store, tech), standard_ids=[std.id]))


def test_instrument_transferred_edited_and_retired(store):
    people = make_people(store)
    tech = people["tech"]
    inst, _ = setup_instrument(store, people)
    other = services.add_customer(store, tech, "New Owner Ltd", "3 Road")
    with pytest.raises(GonioError, match="technician role"):
        services.update_instrument(store, people["rev"], inst.id, customer_id=other.id)
    got = services.update_instrument(store, tech, inst.id, customer_id=other.id,
                                     interval_months="6", kind="RLG")
    assert (got.customer_id, got.interval_months, got.kind) == (other.id, 6, "RLG")
    assert services.update_instrument(store, tech, inst.id,
                                      interval_months=None).interval_months is None
    services.register_instrument(store, tech, customer_id=other.id, serial="RLG-0002",
                                 spec_key="ogam-draft", manufacturer="Example Gyro Works",
                                 model="RLG-GM-1")
    with pytest.raises(GonioError, match="is registered"):
        services.update_instrument(store, tech, inst.id, serial="RLG-0002")
    services.update_instrument(store, tech, inst.id, retire=True)
    sha, _ = services.store_file(store, io.BytesIO(b"x"))
    with pytest.raises(GonioError, match="the instrument was retired on"):
        services.create_calibration(store, tech, instrument_id=inst.id, readings_sha256=sha,
                                    **conditions(store, tech))
    assert [a["customer_id"] for _, a in trail(store, "instrument", inst.id)][0] == other.id


def test_customer_edited_on_the_web(app, sqlite_store):  # noqa: F811
    tech = login(app, "tech")
    actor = services.user(sqlite_store, "tech")
    cust = services.add_customer(sqlite_store, actor, "Old Name", "1 Road")
    services.add_customer(sqlite_store, actor, "Taken")
    r = tech.post(f"/customers/{cust.id}/edit", data={
        "csrf": csrf_of(tech), "name": "New Name", "address": "1 Road\r\nTown",
        "state": "retired"})
    assert r.status_code == 303
    with sqlite_store.session() as s:
        from gonio.records.models import Customer
        c = s.get(Customer, cust.id)
        assert (c.name, c.address, c.retired_on) == ("New Name", "1 Road\nTown",
                                                    dt.date.today())
    r = tech.post(f"/customers/{cust.id}/edit", data={"csrf": csrf_of(tech), "name": "Taken"})
    assert "a%20customer%20with%20this%20name%20exists" in r.headers["location"]
    assert "a customer with this name exists" in tech.get(r.headers["location"]).text
    rev = login(app, "rev")
    r = rev.post(f"/customers/{cust.id}/edit", data={"csrf": csrf_of(rev), "name": "X"})
    assert "technician%20role" in r.headers["location"]
    std = services.add_standard(sqlite_store, actor, name="table", identifier="T-1",
                                due_on="2027-01-01")
    r = tech.post(f"/standards/{std.id}/edit", data={"csrf": csrf_of(tech),
                                                    "due_on": "2028-01-01"})
    assert r.status_code == 303 and "2028-01-01" in tech.get("/standards").text


def test_no_instrument_registered_for_a_retired_customer(sqlite_store):
    people = make_people(sqlite_store)
    tech = people["tech"]
    cust = services.add_customer(sqlite_store, tech, "Closed Ltd")
    services.update_customer(sqlite_store, tech, cust.id, retire=True)
    with pytest.raises(GonioError, match=f"customer Closed Ltd was retired on {dt.date.today()}"):
        services.register_instrument(sqlite_store, tech, customer_id=cust.id, serial="S-1",
                                     spec_key="ogam-draft")
