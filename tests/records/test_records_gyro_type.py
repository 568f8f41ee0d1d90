"""The registered instrument's optical-gyro type reaches the calibration: the laboratory
details the records write name it (``[instrument] gyro_type``), so readings that state no
type take the protocol's default bound of K's temperature coefficient for that type, not
the larger of the two (docs/formats.md#the-temperature-coefficient-bound)."""

from __future__ import annotations

import datetime as dt
import html
import json
import re

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
    from gonio.records.db import open_store

    readings = _without_gyro_type(bench_readings[0], tmp_path / "readings.csv")
    data = tmp_path / "data"
    st = open_store(None, data)
    try:
        people = make_people(st)
        cust = services.add_customer(st, people["tech"], "Owner")
        services.register_instrument(st, people["tech"], customer_id=cust.id,
                                     serial="RLG-0001", spec_key="ogam-draft",
                                     manufacturer="gonio virtual bench",
                                     model="RLG goniometer (virtual)", gyro_type="rlg")
    finally:
        st.close()
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
