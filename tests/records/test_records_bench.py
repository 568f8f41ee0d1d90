"""A calibration started in ``gonio serve`` from a connected bench: the web form queues it,
the worker runs the acquisition engine of ``gonio acquire`` on ``gonio bench serve`` (started
here, a real process on real sockets, through pyvisa-py), stores the readings and the raw I/O
log with the calibration, then calibrates them."""

from __future__ import annotations

import datetime as dt
import html as html_module
import re
from pathlib import Path

import pytest
from sqlalchemy import select

from gonio.errors import GonioError
from gonio.records import bench, services, worker
from gonio.records.models import AuditEvent, CalibrationFile, ResultItem
from tests.served import start_served, stop_served

from .test_web_security import app, csrf_of, login  # noqa: F401  (the app fixture)

REPO = Path(__file__).resolve().parents[2]
SMALL_PROTOCOL = REPO / "tests" / "data" / "small-protocol.toml"


@pytest.fixture
def served_bench():
    """``gonio bench serve --bench rlg`` as a process: its two VISA resource strings."""
    proc = start_served("--bench", "rlg", "--table-port", "0", "--gyro-port", "0", "--speed",
                        "200", "--seed", "3")
    try:
        yield dict(proc.stdout.readline().strip().split(": ", 1) for _ in range(2))
    finally:
        stop_served(proc)


def _file(store, cal_id: int, name: str) -> bytes:
    with store.session() as s:
        f = s.get(CalibrationFile, (cal_id, name))
    assert f is not None, name
    return services.file_bytes(store, f.sha256)


def _registered(store, actor, serial: str):
    """An instrument of the optical draft with ``serial`` and a standard due in 300 days."""
    cust = services.add_customer(store, actor, "C")
    return (services.register_instrument(store, actor, customer_id=cust.id, serial=serial,
                                         spec_key="ogam-draft"),
            services.add_standard(store, actor, name="rotary table", identifier="RT-07",
                                  due_on=dt.date.today() + dt.timedelta(days=300)))


def test_calibration_from_a_connected_bench(app, sqlite_store, served_bench):  # noqa: F811
    store = sqlite_store
    tech = login(app, "tech")
    inst, std = _registered(store, services.user(store, "tech"), "RLG-0001")
    form = {"csrf": csrf_of(tech), "performed_on": str(dt.date.today()),
            "standards": str(std.id), "temperature_c": "20.0", "humidity_pct": "45",
            "table": served_bench["table"], "gyro": served_bench["gyro"],
            "metadata": "latitude_deg=40.2\noperator=A. Tester"}
    files = {"protocol_file": ("small.toml", SMALL_PROTOCOL.read_bytes())}
    bad = tech.post(f"/instruments/{inst.id}/acquire", files=files,
                    data={**form, "gyro": "not a resource"})
    assert bad.status_code == 400
    assert "not a VISA resource string" in html_module.unescape(bad.text)
    bad = tech.post(f"/instruments/{inst.id}/acquire", files=files,
                    data={k: v for k, v in form.items() if k != "standards"})
    assert bad.status_code == 400 and "tick the reference standard" in bad.text
    r = tech.post(f"/instruments/{inst.id}/acquire", files=files, data=form)
    assert r.status_code == 303, r.text[:2000]
    cal_id = int(r.headers["location"].rsplit("/", 1)[1])
    queued = services.calibration(store, cal_id)
    assert queued.status == "queued" and queued.readings_name == bench.PENDING_NAME

    cal = services.claim_next(store)
    assert cal.id == cal_id and worker.execute(store, cal_id), \
        services.calibration(store, cal_id).error
    done = services.calibration(store, cal_id)
    assert done.status == "computed" and done.readings_name == "readings.csv"
    readings = services.file_bytes(store, done.readings_sha256).decode("utf-8")
    assert readings.startswith("# acquisition: complete\n")
    assert "# operator: A. Tester\n" in readings and "# latitude_deg: 40.2\n" in readings
    rows = [ln for ln in readings.splitlines() if ln and not ln.startswith("#")]
    assert len(rows) == 1 + 27                          # header + the small programme
    log = _file(store, cal_id, "io.log").decode("utf-8").splitlines()
    assert re.search(r"Z table > \*CLS$", log[0]) and log[-1].endswith("table > STOP")
    assert any(re.search(r"Z gyro < gonio virtual bench,RLG goniometer", ln) for ln in log)
    request = _file(store, cal_id, "bench-request.json").decode("utf-8")
    assert served_bench["table"] in request
    with store.session() as s:
        measured = dict(s.execute(select(ResultItem.key, ResultItem.measured).where(
            ResultItem.calibration_id == cal_id)).all())
    assert measured.get("angle_deviation") is True and len(measured) >= 5
    assert len(services.seal(store, cal_id)) == 64      # io.log is under the seal, verified
    with store.session() as s:
        actions = [a for (a,) in s.execute(select(AuditEvent.action).where(
            AuditEvent.entity == "calibration", AuditEvent.entity_id == str(cal_id)))]
    assert "acquired" in actions
    page = tech.get(f"/calibrations/{cal_id}").text
    assert "io.log" in page
    assert tech.get(f"/calibrations/{cal_id}/files/io.log").status_code == 200


def test_readings_of_another_instrument_fail_the_run_and_keep_the_log(sqlite_store,
                                                                       served_bench):
    """The readings taken are checked as an upload is: the bench's gyro (serial RLG-0001)
    is not the instrument registered, so the run fails with the reason; the I/O log is
    stored, the request stays the readings (run again, it acquires again)."""
    store = sqlite_store
    actor = services.create_user(store, None, "tech", "correct horse battery", "technician")
    inst, std = _registered(store, actor, "RLG-9999")
    psha, _ = services.store_file(store, open(SMALL_PROTOCOL, "rb"))
    cal = bench.create_bench_calibration(
        store, actor, instrument_id=inst.id, resources=served_bench,
        metadata={"latitude_deg": "40.2"}, protocol_sha256=psha, standard_ids=[std.id],
        temperature_c=20.0, humidity_pct=45)
    assert services.claim_next(store).id == cal.id and not worker.execute(store, cal.id)
    failed = services.calibration(store, cal.id)
    assert failed.status == "failed" and "RLG-0001" in failed.error, failed.error
    assert failed.readings_name == bench.PENDING_NAME
    assert b"gyro > ZERO" in _file(store, cal.id, "io.log")


def test_a_request_is_checked_before_anything_is_queued():
    with pytest.raises(GonioError, match="give the table's VISA resource"):
        bench.check_request({"gyro": "TCPIP0::h::1::SOCKET"}, {})
    with pytest.raises(GonioError, match="metadata key"):
        bench.check_request({"table": "GPIB0::12::INSTR", "gyro": "ASRL/dev/ttyUSB0::INSTR"},
                            {"bad key": "1"})
    with pytest.raises(GonioError, match="metadata line 2"):
        bench.parse_metadata_lines("a=1\nno equals sign")
    ok = bench.check_request({"table": "GPIB0::12::INSTR", "gyro": "ASRL/dev/ttyUSB0::INSTR",
                              "chamber": ""}, {"k": "v"})
    assert ok["resources"] == {"table": "GPIB0::12::INSTR", "gyro": "ASRL/dev/ttyUSB0::INSTR"}


def test_bench_form_has_place_and_performed_at(app, sqlite_store):  # noqa: F811
    """The form that starts a calibration from a connected bench offers the place and
    "Performed at" with the very choices of the upload form, and the choice is recorded
    (before: the bench form had neither; the route passed them)."""
    store = sqlite_store
    tech = login(app, "tech")
    inst, std = _registered(store, services.user(store, "tech"), "RLG-0002")
    page = tech.get(f"/instruments/{inst.id}/calibrate").text
    upload, acquire = page.split('action="/instruments/%d/acquire"' % inst.id)

    def choices(html: str) -> list[tuple[str, str]]:
        select = re.search(r'<select name="location">(.*?)</select>', html, re.S)
        assert select is not None
        return re.findall(r'<option value="([^"]+)"[^>]*>([^<]+)</option>', select.group(1))

    assert choices(acquire) == choices(upload)
    assert [k for k, _ in choices(acquire)] == ["laboratory", "customer", "laboratoryBranch",
                                               "customerBranch", "other"]
    assert 'name="place"' in acquire
    form = {"csrf": csrf_of(tech), "performed_on": str(dt.date.today()),
            "standards": str(std.id), "temperature_c": "20.0", "humidity_pct": "45",
            "table": "TCPIP0::127.0.0.1::5025::SOCKET",
            "gyro": "TCPIP0::127.0.0.1::5026::SOCKET", "location": "customer",
            "place": "Hangar 4, Example Field"}
    bad = tech.post(f"/instruments/{inst.id}/acquire", data={**form, "standards": ""})
    assert bad.status_code == 400            # the form comes back with the choice kept
    kept = bad.text.split('action="/instruments/%d/acquire"' % inst.id)[1]
    assert '<option value="customer" selected>' in kept
    r = tech.post(f"/instruments/{inst.id}/acquire", data=form)
    assert r.status_code == 303, r.text[:2000]
    cal = services.calibration(store, int(r.headers["location"].rsplit("/", 1)[1]))
    assert (cal.location, cal.place) == ("customer", "Hangar 4, Example Field")


def test_bench_form_has_the_date_of_receipt(app, sqlite_store):  # noqa: F811
    """The bench form offers the date of receipt as the upload form does; the date given is
    recorded on the calibration (and so on its certificate), kept when the form comes back
    with an error, and a date after the calibration's is refused as on the upload form."""
    store = sqlite_store
    tech = login(app, "tech")
    inst, std = _registered(store, services.user(store, "tech"), "RLG-0003")
    page = tech.get(f"/instruments/{inst.id}/calibrate").text
    upload, acquire = page.split('action="/instruments/%d/acquire"' % inst.id)
    field = re.compile(r'<label>Date of receipt <input name="received_on" type="date"[^>]*>')
    assert field.search(upload) and field.search(acquire)
    day = dt.date.today()
    form = {"csrf": csrf_of(tech), "performed_on": str(day), "standards": str(std.id),
            "temperature_c": "20.0", "humidity_pct": "45",
            "table": "TCPIP0::127.0.0.1::5025::SOCKET",
            "gyro": "TCPIP0::127.0.0.1::5026::SOCKET",
            "received_on": str(day - dt.timedelta(days=3))}
    bad = tech.post(f"/instruments/{inst.id}/acquire", data={**form, "standards": ""})
    assert bad.status_code == 400
    kept = bad.text.split('action="/instruments/%d/acquire"' % inst.id)[1]
    assert f'name="received_on" type="date" value="{day - dt.timedelta(days=3)}"' in kept
    late = tech.post(f"/instruments/{inst.id}/acquire", data={
        **form, "performed_on": str(day - dt.timedelta(days=5))})
    assert late.status_code == 400
    r = tech.post(f"/instruments/{inst.id}/acquire", data=form)
    assert r.status_code == 303, r.text[:2000]
    cal = services.calibration(store, int(r.headers["location"].rsplit("/", 1)[1]))
    assert cal.received_on == day - dt.timedelta(days=3)
    details = services.lab_details(store, cal.id, final=False)
    assert details["certificate"]["date_of_receipt"] == str(day - dt.timedelta(days=3))
