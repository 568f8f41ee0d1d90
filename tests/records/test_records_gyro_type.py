"""The registered instrument's optical-gyro type reaches the calibration: the laboratory
details the records write name it (``[instrument] gyro_type``), so readings that state no
type take the protocol's default bound of K's temperature coefficient for that type, not
the larger of the two (docs/formats.md#the-temperature-coefficient-bound)."""

from __future__ import annotations

import datetime as dt
import html
import json
import re
from pathlib import Path

import pytest

from gonio.errors import GonioError
from gonio.records import services, worker
from gonio.records.models import CalibrationFile, Instrument
from gonio.specs.ogam_draft.protocol import load_protocol

from .conftest import SMALL_PROTOCOL, make_people
from .test_web_security import app  # noqa: F401  (the app fixture)


def _without_gyro_type(src, dst):
    lines = src.read_text(encoding="utf-8").splitlines(keepends=True)
    kept = [ln for ln in lines if not ln.lstrip("# ").lower().startswith("gyro_type")]
    assert len(kept) == len(lines) - 1          # the bench states its type: taken out here
    dst.write_text("".join(kept), encoding="utf-8")
    return dst


def _calibrate(store, people, readings, gyro_type):
    tech = people["tech"]
    cust = services.add_customer(store, tech, f"Owner {gyro_type or 'none'}")
    inst = services.register_instrument(store, tech, customer_id=cust.id,
                                        serial="RLG-0001",
                                        spec_key="ogam-draft", gyro_type=gyro_type)
    std = services.add_standard(store, tech, name="rotary table",
                                identifier=f"RT-{gyro_type or 'none'}",
                                due_on=dt.date.today() + dt.timedelta(days=300))
    sha, _ = services.store_file(store, open(readings, "rb"))
    psha, _ = services.store_file(store, open(SMALL_PROTOCOL, "rb"))
    cal = services.create_calibration(store, tech, instrument_id=inst.id, readings_sha256=sha,
                                      readings_name="readings.csv", protocol_sha256=psha,
                                      standard_ids=[std.id], temperature_c=20.1,
                                      humidity_pct=45)
    assert services.claim_next(store).id == cal.id
    ok = worker.execute(store, cal.id)
    return cal.id, ok, std.id


def _stored(store, cal_id, name) -> bytes:
    with store.session() as s:
        return services.file_bytes(store, s.get(CalibrationFile, (cal_id, name)).sha256)


def test_a_registered_rlg_gets_the_rlg_bound(sqlite_store, bench_readings, tmp_path):
    people = make_people(sqlite_store)
    readings = _without_gyro_type(bench_readings[0], tmp_path / "readings.csv")
    cid, ok, _ = _calibrate(sqlite_store, people, readings, "RLG")
    assert ok, services.calibration(sqlite_store, cid).error
    with sqlite_store.session() as s:
        assert s.get(Instrument, services.calibration(
            sqlite_store, cid).instrument_id).gyro_type == "rlg"
    res = json.loads(_stored(sqlite_store, cid, "results.json"))
    tb = res["items"]["scale_factor"]["details"]["temperature_coeff_bound"]
    annex = load_protocol(SMALL_PROTOCOL).annex_a
    assert annex.sf_temperature_coeff_bound_rlg_ppm_per_c < \
        annex.sf_temperature_coeff_bound_fog_ppm_per_c      # the larger would be the FOG's
    assert tb["bound_ppm_per_c"] == annex.sf_temperature_coeff_bound_rlg_ppm_per_c
    assert (tb["source"], tb["gyro_type"]) == ("protocol-rlg", "rlg")
    assert "laboratory file's [instrument] gyro_type" in tb["how"]
    assert b"[instrument]" in _stored(sqlite_store, cid, "lab.toml") and \
        b'gyro_type = "rlg"' in _stored(sqlite_store, cid, "lab.toml")
    page = html.unescape(_stored(sqlite_store, cid, "certificate.html").decode())
    assert "|α_K| ≤ 0.1 ppm/°C: the protocol's default for an RLG." in page


def test_a_registered_type_the_readings_contradict_is_refused(sqlite_store, bench_readings):
    people = make_people(sqlite_store)
    cid, ok, std_id = _calibrate(sqlite_store, people, bench_readings[0], "fog")   # an RLG's readings
    assert not ok
    err = services.calibration(sqlite_store, cid).error
    assert "gyro type" in err and "instrument.gyro_type" in err, err
    # the web form's submission refuses them at upload, naming the instrument's record
    from gonio.records.submission import submit_calibration
    cal = services.calibration(sqlite_store, cid)
    with pytest.raises(GonioError, match="gyro type: the readings say 'rlg' .*the "
                                         "instrument's record 'fog'"):
        submit_calibration(sqlite_store, people["tech"], instrument_id=cal.instrument_id,
                           readings_sha256=cal.readings_sha256,
                           standard_ids=[std_id],
                           temperature_c=20.1, humidity_pct=45)


def test_the_type_is_checked_and_edited(sqlite_store):
    people = make_people(sqlite_store)
    tech = people["tech"]
    cust = services.add_customer(sqlite_store, tech, "C")
    with pytest.raises(GonioError, match="gyro_type: 'mems' is not one of rlg, fog"):
        services.register_instrument(sqlite_store, tech, customer_id=cust.id, serial="S",
                                     spec_key="ogam-draft", gyro_type="MEMS")
    inst = services.register_instrument(sqlite_store, tech, customer_id=cust.id, serial="S",
                                        spec_key="ogam-draft")
    assert inst.gyro_type == ""
    assert services.update_instrument(sqlite_store, tech, inst.id,
                                      gyro_type="FOG").gyro_type == "fog"
    assert services.update_instrument(sqlite_store, tech, inst.id, gyro_type="").gyro_type == ""


def test_calibrate_record_takes_the_registered_type(tmp_path, bench_readings, capsys):
    """``gonio calibrate --record``: the instrument registered under the readings' identity
    states RLG, the readings and the command line state no type: the run takes the RLG bound
    (the same readings without --record take the larger default)."""
    from gonio.cli import main

    readings = _without_gyro_type(bench_readings[0], tmp_path / "readings.csv")
    data = _registered(tmp_path, "rlg")
    run = ["calibrate", str(readings), "--protocol", str(SMALL_PROTOCOL)]

    def bound(out):
        res = json.loads((out / "results.json").read_text())
        return res["items"]["scale_factor"]["details"]["temperature_coeff_bound"]

    assert main(run + ["--out", str(tmp_path / "plain")]) == 0
    assert bound(tmp_path / "plain")["source"] == "protocol-larger"
    assert main(run + ["--out", str(tmp_path / "rec"), "--record", "--data", str(data)]) == 0
    assert "recorded as calibration 1" in capsys.readouterr().err
    tb = bound(tmp_path / "rec")
    assert (tb["source"], tb["bound_ppm_per_c"]) == (
        "protocol-rlg",
        load_protocol(SMALL_PROTOCOL).annex_a.sf_temperature_coeff_bound_rlg_ppm_per_c)


def test_the_web_forms_register_and_edit_the_type(app, sqlite_store):  # noqa: F811
    """The register form and the instrument's edit form offer the optical-gyro type; what is
    chosen is recorded, shown on the instrument's page, and a type that is neither is said
    on the form (400), nothing registered."""
    from .test_web_security import csrf_of, login

    tech = login(app, "tech")
    cust = services.add_customer(sqlite_store, services.user(sqlite_store, "tech"), "C")
    page = tech.get("/instruments").text
    assert re.search(r'<select name="gyro_type"><option value="">not stated</option>'
                     r'<option value="rlg">RLG</option><option value="fog">FOG</option>', page)
    form = {"csrf": csrf_of(tech), "customer_id": str(cust.id), "serial": "W-1",
            "spec_key": "ogam-draft"}
    bad = tech.post("/instruments", data={**form, "gyro_type": "mems"})
    assert bad.status_code == 400 and "is not one of rlg, fog" in html.unescape(bad.text)
    r = tech.post("/instruments", data={**form, "gyro_type": "rlg"})
    assert r.status_code == 303, r.text[:500]
    inst_id = int(r.headers["location"].rsplit("/", 1)[1])
    with sqlite_store.session() as s:
        assert s.get(Instrument, inst_id).gyro_type == "rlg"
    page = tech.get(f"/instruments/{inst_id}").text
    assert "<dt>Optical gyro type</dt><dd>RLG</dd>" in page
    assert '<option value="rlg" selected>RLG</option>' in page
    r = tech.post(f"/instruments/{inst_id}/edit", data={
        "csrf": csrf_of(tech), "customer_id": str(cust.id), "serial": "W-1",
        "gyro_type": "fog", "interval_months": ""})
    assert r.status_code == 303 and "error" not in r.headers["location"], r.headers
    with sqlite_store.session() as s:
        assert s.get(Instrument, inst_id).gyro_type == "fog"


def _registered(tmp_path, gyro_type):
    """SQLite records under tmp_path/data with the bench's RLG-0001 registered as
    ``gyro_type``."""
    from gonio.records.db import open_store

    data = tmp_path / "data"
    st = open_store(None, data)
    try:
        people = make_people(st)
        cust = services.add_customer(st, people["tech"], "Owner")
        services.register_instrument(st, people["tech"], customer_id=cust.id,
                                     serial="RLG-0001", spec_key="ogam-draft",
                                     manufacturer="gonio virtual bench",
                                     model="RLG goniometer (virtual)", gyro_type=gyro_type)
        services.add_standard(st, people["tech"], name="rotary table", identifier="RT-07",
                              due_on=dt.date.today() + dt.timedelta(days=300))
    finally:
        st.close()
    return data


def _calibrations(data) -> int:
    from gonio.records.db import open_store
    from gonio.records.models import Calibration

    st = open_store(None, data)
    try:
        with st.session() as s:
            return len(s.query(Calibration).all())
    finally:
        st.close()


def _lab(tmp_path, gyro_type="", proceed=False):
    """The example laboratory file naming the bench's instrument as its readings do, with
    ``[instrument] gyro_type`` and ``[identity] on_mismatch = "proceed"`` as asked."""
    src = (Path(__file__).parents[2] / "protocols" / "lab-example.toml").read_text("utf-8")
    src = src.replace('model = "RLG-GM-1"', 'model = "RLG goniometer (virtual)"', 1)
    if gyro_type:
        src = src.replace("[instrument]\n", f'[instrument]\ngyro_type = "{gyro_type}"\n', 1)
    if proceed:
        src += '\n[identity]\non_mismatch = "proceed"\n'
    f = tmp_path / f"lab-{gyro_type or 'none'}-{proceed}.toml"
    f.write_text(src, encoding="utf-8")
    return f


@pytest.mark.parametrize("case", ["readings", "lab file"])
def test_calibrate_record_refuses_a_type_the_record_contradicts(tmp_path, bench_readings,
                                                                 capsys, case):
    """``gonio calibrate --record``: the readings (the bench states ``gyro_type: rlg``) or the
    laboratory file (readings silent) say another type than the instrument registered under
    the readings' identity: one line naming both values and the record, exit 2, nothing
    written nor recorded; without --record the same run calibrates (the record is what
    contradicts)."""
    from gonio.cli import main

    if case == "readings":
        readings, lab, said = bench_readings[0], _lab(tmp_path), "the readings say 'rlg'"
    else:
        readings = _without_gyro_type(bench_readings[0], tmp_path / "readings.csv")
        lab, said = _lab(tmp_path, "rlg"), "the laboratory file says 'rlg'"
    data = _registered(tmp_path, "fog")
    run = ["calibrate", str(readings), "--protocol", str(SMALL_PROTOCOL), "--lab", str(lab)]
    out = tmp_path / "rec"
    capsys.readouterr()
    assert main(run + ["--out", str(out), "--record", "--data", str(data)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert f"gyro type: {said}" in err and "the instrument's record 'fog' " \
        "(instruments.gyro_type)" in err, err
    assert not out.exists() and _calibrations(data) == 0
    assert main(run + ["--out", str(tmp_path / "plain")]) == 0


def test_calibrate_record_flags_the_contradiction_when_the_lab_proceeds(tmp_path,
                                                                       bench_readings):
    """With ``[identity] on_mismatch = "proceed"`` the contradiction with the record is a
    flagged identity finding: in results.json, on the certificate and on the recorded
    calibration's page (the documented rule, docs/formats.md#identity-and-conditions)."""
    from gonio.cli import main
    from gonio.records.db import open_store
    from gonio.records.queries import calibration_page

    data = _registered(tmp_path, "fog")
    out = tmp_path / "rec"
    assert main(["calibrate", str(bench_readings[0]), "--protocol", str(SMALL_PROTOCOL),
                 "--lab", str(_lab(tmp_path, proceed=True)), "--out", str(out),
                 "--record", "--data", str(data)]) == 0
    res = json.loads((out / "results.json").read_text("utf-8"))
    (f,) = [f for f in res["findings"] if f["code"] == "identity-mismatch"]
    assert f["message"].startswith("gyro type: the readings say 'rlg' (# gyro_type), the "
                                   "instrument's record 'fog' (instruments.gyro_type)"), f
    page = html.unescape((out / "certificate.html").read_text("utf-8"))
    assert "the instrument's record 'fog'" in page
    st = open_store(None, data)
    try:
        got = calibration_page(st, 1)
        assert any("the instrument's record 'fog'" in m for m in got["identity"])
    finally:
        st.close()
