"""An instrument's stored limits take the laboratory file's ``unit`` key (register, the web
form): a unit's text is stored as given and decides nothing by itself (the item's unit is
checked once a calibration states it, tests/test_limit_units.py); text that is no unit is
refused in one line naming the entry, nothing registered."""

from __future__ import annotations

import html
import json
import re

from sqlalchemy import func, select

from gonio.records import services
from gonio.records.models import Instrument

from .test_web_security import app  # noqa: F401  (the app fixture)


def _count(store) -> int:
    with store.session() as s:
        return s.scalar(select(func.count()).select_from(Instrument))


def test_the_web_form_stores_a_unit_and_refuses_no_unit(app, sqlite_store):  # noqa: F811
    from .test_web_security import csrf_of, login

    tech = login(app, "tech")
    cust = services.add_customer(sqlite_store, services.user(sqlite_store, "tech"), "C")
    form = {"csrf": csrf_of(tech), "customer_id": str(cust.id), "serial": "W-1",
            "spec_key": "ogam-draft", "limit_item_0": "repeatability", "limit_upper_0": "0.3",
            "limit_item_1": "zero_stability", "limit_upper_1": "0.01",
            "limit_unit_1": "(deg/h"}
    r = tech.post("/instruments", data=form)
    assert r.status_code == 400
    m = re.search(r'<p class="error" role="alert">(.*?)</p>', r.text, re.S)
    assert m, r.text[:2000]
    msg = html.unescape(m.group(1))
    assert msg.startswith("limits: key limits[1].unit: "), msg
    assert "\n" not in msg
    assert _count(sqlite_store) == 0
    r = tech.post("/instruments", data={**form, "limit_unit_1": " deg/h "})
    assert r.status_code == 303, r.text[:500]
    with sqlite_store.session() as s:
        stored = json.loads(s.scalars(select(Instrument)).one().limits_json)
    assert [lim.get("unit") for lim in stored] == [None, "deg/h"]
