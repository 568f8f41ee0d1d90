"""The submission checks of a new calibration (gonio.records.submission), on the service and
through the web form (Starlette's TestClient): a registered standard and the environment
required, the readings checked against the instrument at upload (their specification, serial,
temperature; a JSON file), the same readings file used twice refused without a reason, which
is audited; the form coming back with what was entered and the files uploaded; an upload over
the size limit refused with the limit, before it is read."""

from __future__ import annotations

import html as html_module
import io
import json
import re

import pytest
from sqlalchemy import func, select

from gonio.errors import GonioError
from gonio.records import services, submission
from gonio.records.models import AuditEvent, Calibration

from .conftest import make_people
from .test_web_security import app, csrf_of, login  # noqa: F401  (the app fixture)

#: the head of a rate-gyro (JJF 1535) readings file, as the virtual bench writes it
RATE_HEAD = (b"# spec: jjf1535-2015\n# model: ADXRS610-class\n# serial: MEMS-0610-001\n"
             b"test,run,step,role,time_s,rate_dps,output\nsf,1,1,ref,0.0,10.0,2560.1\n")


def setup(store, serial="RLG-0001"):
    people = make_people(store)
    tech = people["tech"]
    cust = services.add_customer(store, tech, "C", "1 Road")
    inst = services.register_instrument(store, tech, customer_id=cust.id, serial=serial,
                                        spec_key="ogam-draft", model="")
    std = services.add_standard(store, tech, name="rotary table", identifier="RT-07",
                                due_on="2099-01-01")
    return people, inst, std


def submit(store, actor, inst, sha, std_ids, **kw):
    args = dict(temperature_c=20.1, humidity_pct=45, performed_on="2025-11-20")
    args.update(kw)
    return submission.submit_calibration(store, actor, instrument_id=inst.id,
                                         readings_sha256=sha, standard_ids=std_ids, **args)


def n_calibrations(store) -> int:
    with store.session() as s:
        return s.scalar(select(func.count()).select_from(Calibration))


def test_standard_and_environment_required(store, bench_readings):
    """Finding: a certificate issued with no registered standard and no environment."""
    sqlite_store = store                               # on SQLite and PostgreSQL
    people, inst, std = setup(sqlite_store)
    sha, _ = services.store_file(sqlite_store, open(bench_readings[0], "rb"))
    tech = people["tech"]
    with pytest.raises(GonioError, match="key standards: tick the reference standard"):
        submit(sqlite_store, tech, inst, sha, [])
    with pytest.raises(GonioError, match="enter the room temperature"):
        submit(sqlite_store, tech, inst, sha, [std.id], temperature_c="")
    with pytest.raises(GonioError, match="enter the relative humidity"):
        submit(sqlite_store, tech, inst, sha, [std.id], humidity_pct=None)
    old = services.add_standard(sqlite_store, tech, name="autocollimator", identifier="AC-1",
                                due_on="2025-11-19", out_of_service="awaiting recalibration")
    with pytest.raises(GonioError, match="AC-1 was due on 2025-11-19"):
        submit(sqlite_store, tech, inst, sha, [std.id, old.id])
    assert n_calibrations(sqlite_store) == 0
    cal = submit(sqlite_store, tech, inst, sha, [std.id])
    assert (cal.status, cal.temperature_c, cal.humidity_pct) == ("queued", 20.1, 45)


def test_dates_refused_before_anything_else(sqlite_store):
    people, inst, std = setup(sqlite_store)
    sha, _ = services.store_file(sqlite_store, io.BytesIO(b"not readings"))
    with pytest.raises(GonioError, match="2099-03-01 is in the future"):
        submit(sqlite_store, people["tech"], inst, sha, [std.id], performed_on="2099-03-01")
    with pytest.raises(GonioError, match="received on 2025-11-21, after the calibration"):
        submit(sqlite_store, people["tech"], inst, sha, [std.id], received_on="2025-11-21")


@pytest.mark.parametrize("body, expect", [
    (b'{"spec": "ogam-draft", "items": {}}', "the readings file is JSON"),
    (b"\n  [1, 2, 3]\n", "the readings file is JSON"),
    (b"<?xml version='1.0'?><dcc/>", "XML or HTML"),
    (b"PK\x03\x04 a spreadsheet", "binary document"),
    (b"\xff\xfe\x00\x01" * 40, "not UTF-8 text"),
    (b"# spec: ogam-draft\n# serial: RLG-0001\n", "holds no readings"),
    (b"# serial: RLG-0001\njust some words\n", "('just some words') is no CSV header"),
    (RATE_HEAD, "the readings are jjf1535-2015 readings (# spec: jjf1535-2015); this "
                "calibration is per ogam-draft"),
], ids=["json", "json-list", "xml", "xlsx", "binary", "metadata-only", "not-csv",
        "rate-gyro"])
def test_readings_that_cannot_be_of_this_instrument_refused(sqlite_store, body, expect):
    """Finding: a rate-gyro file for an optical instrument, or a JSON file, was queued and
    failed later in the command line's words."""
    people, inst, std = setup(sqlite_store)
    sha, _ = services.store_file(sqlite_store, io.BytesIO(body))
    with pytest.raises(GonioError, match=re.escape(expect)) as got:
        submit(sqlite_store, people["tech"], inst, sha, [std.id])
    assert got.value.key == "readings" and "\n" not in str(got.value)
    assert n_calibrations(sqlite_store) == 0


def test_readings_of_another_instrument_or_conditions_refused(sqlite_store, bench_readings):
    """The readings' own # serial and # temperature_c (read here from the file) against the
    instrument's record and the entered temperature, at the pipeline's tolerance (1 °C)."""
    from gonio.formats.provenance import readings_metadata
    from gonio.pipeline.identity import TEMPERATURE_TOLERANCE_C

    md = readings_metadata(bench_readings[0])
    people, inst, std = setup(sqlite_store, serial="RLG-0002")
    sha, _ = services.store_file(sqlite_store, open(bench_readings[0], "rb"))
    with pytest.raises(GonioError, match=f"serial: the readings say '{md['serial']}' "
                                         r"\(# serial\), the instrument's record 'RLG-0002'"):
        submit(sqlite_store, people["tech"], inst, sha, [std.id])
    ok = services.update_instrument(sqlite_store, people["tech"], inst.id,
                                    serial=md["serial"])
    hot = float(md["temperature_c"]) + TEMPERATURE_TOLERANCE_C + 0.5
    with pytest.raises(GonioError, match=rf"temperature: .* what was entered {hot:g} °C "
                                         r"\(more than 1 °C apart\)"):
        submit(sqlite_store, people["tech"], ok, sha, [std.id], temperature_c=hot)
    near = float(md["temperature_c"]) + TEMPERATURE_TOLERANCE_C - 0.5
    assert submit(sqlite_store, people["tech"], ok, sha, [std.id], temperature_c=near)


def test_same_readings_twice_needs_a_reason_which_is_audited(store, bench_readings):
    sqlite_store = store                               # on SQLite and PostgreSQL
    people, inst, std = setup(sqlite_store)
    tech = people["tech"]
    sha, _ = services.store_file(sqlite_store, open(bench_readings[0], "rb"))
    first = submit(sqlite_store, tech, inst, sha, [std.id])
    with pytest.raises(GonioError, match=f"already those of calibration {first.id} "
                                         r"\(RLG-0001, 2025-11-20, queued\)") as got:
        submit(sqlite_store, tech, inst, sha, [std.id])
    assert got.value.key == submission.REUSE_KEY
    assert n_calibrations(sqlite_store) == 1
    # another file (the second seed's readings) is not the same measurement
    other, _ = services.store_file(sqlite_store, open(bench_readings[1], "rb"))
    assert submit(sqlite_store, tech, inst, other, [std.id])
    again = submit(sqlite_store, tech, inst, sha, [std.id],
                   reuse_reason="recomputed with the corrected protocol")
    with sqlite_store.session() as s:
        ev = s.scalar(select(AuditEvent).where(AuditEvent.action == "reuse-readings"))
    assert (ev.entity_id, ev.username) == (str(again.id), "tech")
    assert json.loads(ev.after_json) == {"readings_sha256": sha, "used_by": [first.id],
                                         "reason": "recomputed with the corrected protocol"}
    # readings of a rejected or void calibration may be used again without a reason
    with sqlite_store.writing() as s:
        for c in s.scalars(select(Calibration).where(Calibration.readings_sha256 == sha)):
            c.status = "void"
        s.commit()
    assert submit(sqlite_store, tech, inst, sha, [std.id]).status == "queued"


# --------------------------------------------------------------------------- the web form


def alert(text: str) -> str:
    m = re.search(r'<p class="error" role="alert">(.*?)</p>', text, re.S)
    assert m, text[:2000]
    return html_module.unescape(m.group(1))


def post_form(web, inst, data, files=None):
    return web.post(f"/instruments/{inst.id}/calibrate", data=dict(data, csrf=csrf_of(web)),
                    files=files or {})


def test_form_refuses_in_its_words_and_keeps_input_and_files(app, sqlite_store,  # noqa: F811
                                                               bench_readings):
    tech = services.user(sqlite_store, "tech")
    cust = services.add_customer(sqlite_store, tech, "C")
    inst = services.register_instrument(sqlite_store, tech, customer_id=cust.id,
                                        serial="RLG-0001", spec_key="ogam-draft")
    std = services.add_standard(sqlite_store, tech, name="table", identifier="T-1",
                                due_on="2099-01-01")
    web = login(app, "tech")
    entered = {"performed_on": "2025-11-20", "received_on": "2025-11-18", "place": "Room 2",
               "temperature_c": "20.1", "humidity_pct": "45", "standards": [str(std.id)]}
    r = post_form(web, inst, entered, {"readings": ("results.json", b'{"items": {}}')})
    assert r.status_code == 400 and alert(r.text).startswith(
        "key readings: the readings file is JSON")
    r = post_form(web, inst, entered, {"readings": ("r.csv", RATE_HEAD)})
    assert "jjf1535-2015 readings" in alert(r.text) and "Traceback" not in r.text
    # the environment forgotten: the form comes back with the readings file kept
    r = post_form(web, inst, dict(entered, humidity_pct=""),
                  {"readings": ("run1.csv", open(bench_readings[0], "rb").read())})
    assert "enter the relative humidity" in alert(r.text)
    for kept in ('value="2025-11-20"', 'value="2025-11-18"', 'value="Room 2"',
                 'value="20.1"', f'value="{std.id}"  checked', '<b class="kept">run1.csv</b>'):
        assert kept in r.text, kept
    token = re.search(r'name="kept_readings" value="([^"]+)"', r.text).group(1)
    assert n_calibrations(sqlite_store) == 0
    # sent again without choosing the file: the kept one is used
    r = post_form(web, inst, dict(entered, kept_readings=token,
                                  kept_readings_name="run1.csv"))
    assert r.status_code == 303, alert(r.text)
    cal = services.calibration(sqlite_store, int(r.headers["location"].rsplit("/", 1)[1]))
    assert cal.readings_name == "run1.csv" and cal.place == "Room 2"
    # a token not made for this session (or this name) names no file
    for forged in (token.split(".")[0] + "." + "0" * 64, token):
        r = post_form(web, inst, dict(entered, kept_readings=forged,
                                      kept_readings_name="other.csv"))
        assert "choose a readings file" in alert(r.text)
    # the same file again: the form asks why, and takes the reason
    r = post_form(web, inst, dict(entered, kept_readings=token, kept_readings_name="run1.csv"))
    assert f"already those of calibration {cal.id}" in alert(r.text)
    assert 'name="reuse_reason"' in r.text
    r = post_form(web, inst, dict(entered, kept_readings=token, kept_readings_name="run1.csv",
                                  reuse_reason="the protocol file was wrong"))
    assert r.status_code == 303


def test_upload_over_the_limit_says_so(app, sqlite_store, monkeypatch):  # noqa: F811
    """Finding: a file over the limit got a generic "not found or not allowed" page. The
    declared size is refused before the body is read (413), one line with the limit; an
    undeclared one is stopped by the store while it reads."""
    tech = services.user(sqlite_store, "tech")
    cust = services.add_customer(sqlite_store, tech, "C")
    inst = services.register_instrument(sqlite_store, tech, customer_id=cust.id, serial="S",
                                        spec_key="ogam-draft")
    monkeypatch.setattr(services, "MAX_UPLOAD", 2**20)
    web = login(app, "tech")
    big = b"a,b\n" * (5 * 2**20 // 4)                 # 5 MiB > 1 MiB + 3 MiB of form
    r = post_form(web, inst, {}, {"readings": ("big.csv", big)})
    assert r.status_code == 413
    text = html_module.unescape(re.sub(r"<[^>]+>", "", r.text))
    assert "key upload: the upload, 5 MiB (5,2" in text
    assert "is larger than the limit of 1 MiB (1,048,576 bytes) for a readings file" in text
    with pytest.raises(GonioError, match=r"larger than the limit of 1 MiB \(1,048,576 bytes\)"):
        services.store_file(sqlite_store, io.BytesIO(b"x" * (2**20 + 1)), limit_bytes=2**20)
    assert n_calibrations(sqlite_store) == 0


def test_a_form_the_parser_refuses_says_why(app):  # noqa: F811
    """A text field over the parser's 2 MB: the 400 page names the reason (before: "not
    found or not allowed")."""
    web = login(app, "tech")
    r = web.post("/customers", data={"csrf": csrf_of(web), "name": "x" * (3 * 2**20)})
    assert r.status_code == 400
    assert "400: Field exceeded maximum size of 2048KB. <a" in r.text
    assert "not found or not allowed" not in r.text
