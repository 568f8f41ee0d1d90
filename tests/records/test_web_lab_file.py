"""A laboratory file (the command line's ``--lab`` TOML) chosen for a calibration in
``gonio serve``, through HTTP (Starlette's TestClient, no browser): validated on the form by
the command line's own function (``gonio.pipeline.dispatch.load_lab_file`` through
``gonio.records.services.lab_file``), refused with its one-line message naming the file by
its uploaded name before anything is stored as a calibration; a valid file's decision rule and
limits reach the worker's run (results.json) in place of the instrument's."""

from __future__ import annotations

import datetime as dt
import html as html_module
import io
import json
import re
from pathlib import Path

import pytest
from sqlalchemy import func, select

from gonio.records import services, worker
from gonio.records.models import Calibration

from .test_web_security import app, csrf_of, login  # noqa: F401  (the app fixture)

REPO = Path(__file__).resolve().parents[2]
SMALL_PROTOCOL = REPO / "tests" / "data" / "small-protocol.toml"
EXAMPLE = (REPO / "protocols" / "lab-example.toml").read_text(encoding="utf-8")
HEAD = EXAMPLE[:EXAMPLE.index("\n[[specification_limits]]")]


def limits_toml(*items) -> str:
    return HEAD + "".join(f'\n[[specification_limits]]\nitem = "{k}"\nmpe = 1.0\n'
                          for k in items)


def instrument(store, spec_key="ogam-draft"):
    actor = services.user(store, "tech")
    cust = services.add_customer(store, actor, "C")
    services.add_standard(store, actor, name="rotary table", identifier="RT-07",
                          due_on="2099-01-01")
    # the instrument's own limit: a lab file's replace it for the calibration
    return services.register_instrument(store, actor, customer_id=cust.id, serial="RLG-0001",
                                        spec_key=spec_key,
                                        limits=[{"item": "repeatability", "mpe": 9.0}])


def post(client, inst, readings: bytes, lab: str | bytes | None, name="my-lab.toml",
         protocol: bytes | None = None):
    files = {"readings": ("readings.csv", io.BytesIO(readings))}
    if lab is not None:
        files["lab_file"] = (name, io.BytesIO(lab.encode() if isinstance(lab, str) else lab))
    if protocol is not None:
        files["protocol_file"] = ("protocol.toml", io.BytesIO(protocol))
    return client.post(f"/instruments/{inst.id}/calibrate", files=files,
                       data={"csrf": csrf_of(client), "performed_on": str(dt.date.today()),
                             "standards": ["1"], "temperature_c": "20.1",
                             "humidity_pct": "45"})


def alert(html: str) -> str:
    m = re.search(r'<p class="error" role="alert">(.*?)</p>', html, re.S)
    assert m, html[:2000]
    return html_module.unescape(m.group(1))


def n_calibrations(store) -> int:
    with store.session() as s:
        return s.scalar(select(func.count()).select_from(Calibration))


@pytest.mark.parametrize("spec_key, lab, expect", [
    ("ogam-draft", limits_toml("angle_deviation", "no_such_item"),
     "my-lab.toml: key specification_limits[1].item: ogam-draft has no item 'no_such_item'"),
    ("triad-alignment", limits_toml("M_xx", "K_z_theta5"),
     "my-lab.toml: key specification_limits[1].item: triad-alignment has no item "
     "'K_z_theta5'"),
    ("ogam-draft", limits_toml("angle_deviation").replace("[customer]", "[customer]\nfax = 1"),
     "my-lab.toml: key customer.fax: unknown key"),
    ("ogam-draft", "[laboratory\nname = 1\n", "my-lab.toml"),
    ("ogam-draft", HEAD, "my-lab.toml: no [[specification_limits]]"),
    ("ogam-draft", limits_toml("angle_deviation") + '\n[[specification_limits]]\n'
     'item = "zero_stability"\nupper = -0.01\n',
     "my-lab.toml: key specification_limits[1].upper: zero_stability cannot be negative"),
], ids=["unknown-item", "triad-order-5", "unknown-key", "not-toml", "no-limits",
        "negative-upper-of-nonnegative"])
def test_bad_lab_file_refused_on_the_form(app, sqlite_store, spec_key, lab, expect):  # noqa: F811
    """The form comes back (400) with the one line the command line prints, naming the file
    as uploaded (never the server's temporary path); no calibration is queued."""
    tech = login(app, "tech")
    inst = instrument(sqlite_store, spec_key)
    r = post(tech, inst, f"# spec: {spec_key}\n".encode(), lab)
    assert r.status_code == 400
    msg = alert(r.text)
    assert msg.startswith(expect) and "\n" not in msg, msg
    assert "gonio-lab-" not in r.text and "/tmp" not in msg
    assert n_calibrations(sqlite_store) == 0


def test_lab_file_limits_decide_the_run(app, sqlite_store, bench_readings):  # noqa: F811
    """The example laboratory file's limits and non-binary rule (not the instrument's
    repeatability limit) are what the worker's real pipeline run decides with; the
    calibration page names the file."""
    tech = login(app, "tech")
    inst = instrument(sqlite_store)
    r = post(tech, inst, Path(bench_readings[0]).read_bytes(), EXAMPLE,
             protocol=SMALL_PROTOCOL.read_bytes())
    assert r.status_code == 303, alert(r.text)
    cal_id = int(r.headers["location"].rsplit("/", 1)[1])
    page = tech.get(f"/calibrations/{cal_id}").text
    assert "laboratory file my-lab.toml" in page
    details = services.lab_details(sqlite_store, cal_id, final=False)
    assert details["decision_rule"]["rule"] == "non-binary"
    assert details["laboratory"]["name"] == services.settings(sqlite_store)["lab_name"]

    cal = services.claim_next(sqlite_store)
    assert cal.id == cal_id and worker.execute(sqlite_store, cal_id), \
        services.calibration(sqlite_store, cal_id).error
    with sqlite_store.session() as s:
        from gonio.records.models import CalibrationFile
        sha = s.get(CalibrationFile, (cal_id, "results.json")).sha256
    res = json.loads(services.file_bytes(sqlite_store, sha))
    items = res["items"]
    items = {it["key"]: it for it in items} if isinstance(items, list) else items
    from gonio.formats.lab import load_lab
    lab = load_lab(REPO / "protocols" / "lab-example.toml")
    for lim in lab["specification_limits"]:
        c = items[lim["item"]]["conformity"]
        assert c["limits_from"] == "lab file" and c["rule"] == "non-binary"
        want = ((-lim["mpe"], lim["mpe"]) if lim["mpe"] is not None
                else (lim["lower"], lim["upper"]))
        assert (c["lower"], c["upper"]) == want, (lim, c)   # the file's, not the instrument's


@pytest.mark.parametrize("backend", ["sqlite", "postgresql"])
def test_existing_records_upgrade_keeping_their_calibrations(backend, request, tmp_path):
    """Records written before the laboratory file (schema 0001: a computed calibration with
    a result row) open at the new head: the rows are kept, untouched, with
    no laboratory file; the new reference to the stored files is enforced."""
    from sqlalchemy import text as sql
    from sqlalchemy.exc import IntegrityError

    from gonio.records.db import open_store

    from .conftest import insert_instrument, records_at

    url = None
    if backend == "postgresql":
        from .conftest import new_pg_database
        url = new_pg_database(request.getfixturevalue("pg_server"))
    old = records_at(url, tmp_path / "data", "0001")
    now = "2026-01-02 03:04:05"
    with old.engine.begin() as c:
        insert_instrument(c, size=3, created_at=now)
        c.execute(sql(f"INSERT INTO calibrations (id, instrument_id, spec_key, protocol, "
                      f"readings_sha256, readings_name, place, performed_on, status, progress, "
                      f"error, worker_host, created_at, review_comment, pending_reason, "
                      f"pending_number) VALUES (7, 1, 'ogam-draft', '', '{'a' * 64}', 'r.csv', "
                      f"'', '2026-01-02', 'computed', 'done', '', '', '{now}', '', '', '')"))
        c.execute(sql("INSERT INTO result_items (calibration_id, key, title, clause, unit, "
                      "measured, value) VALUES (7, 'R', 'R', '', '', true, 0.1)"))
    old.close()
    new = open_store(url, tmp_path / "data")
    try:
        cal = services.calibration(new, 7)
        assert (cal.status, cal.readings_name, cal.lab_sha256, cal.lab_name) == \
            ("computed", "r.csv", None, "")
        with pytest.raises(IntegrityError), new.engine.begin() as c:
            c.execute(sql(f"UPDATE calibrations SET lab_sha256 = '{'b' * 64}' WHERE id = 7"))
    finally:
        new.close()
