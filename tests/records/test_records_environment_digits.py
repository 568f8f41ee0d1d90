"""The environment as entered: the records keep the temperature and humidity with the digits
they were entered with ("20" is not "20.0": the digits state the reading's resolution), and
the records' page, the laboratory file the records write for a calibration, its draft and
issued certificate and its DCC all print that text; records written before keep printing
what they printed (migration 0012)."""

from __future__ import annotations

import re
import tomllib

import pytest
from lxml import etree
from sqlalchemy import text

from gonio.cli import main
from gonio.records import services, worker
from gonio.records.compute import lab_toml
from gonio.records.importer import import_output_folder

from .conftest import PASSWORD, SMALL_PROTOCOL
from .test_records_issue import kv_row, run_issue
from .test_records_services import run_worker, setup_instrument
from .test_web_security import app, csrf_of, login  # noqa: F401  (the app fixture)

NS = {"dcc": "https://ptb.de/dcc", "si": "https://ptb.de/si"}
#: (temperature, humidity) as a person types them, and the text every output must show
ENTERED = (("20", "45"), ("20.0", "45.50"), ("020.10", "45."))
SHOWN = (("20", "45"), ("20.0", "45.50"), ("20.10", "45"))


def dcc_conditions(dcc: bytes) -> list[str]:
    """The DCC's influence conditions' values (temperature, humidity), as written."""
    root = etree.fromstring(dcc)
    return [c.findtext(".//si:value", namespaces=NS).strip()
            for c in root.iterfind(".//dcc:influenceCondition", NS)][:2]


def lab_file_conditions(store, cal_id) -> tuple:
    """The [environment] numbers of the laboratory file the records write, as TOML text."""
    doc = lab_toml(services.lab_details(store, cal_id, final=False))
    env = tomllib.loads(doc, parse_float=str)["environment"]
    return str(env["temperature_c"]), str(env["humidity_pct"])


def test_entered_digits_on_the_page_the_draft_and_the_dcc(app, sqlite_store,  # noqa: F811
                                                          computed_folder, bench_readings):
    """Attached on the calibration page as typed: the page, the laboratory file written for
    the calibration, the draft certificate rendered from it and its DCC print the text typed
    ("20" → "20 °C", "20.0" → "20.0 °C"); the recorded number is the same."""
    tech = services.user(sqlite_store, "tech")
    inst, std = setup_instrument(sqlite_store, {"tech": tech})
    cid = import_output_folder(sqlite_store, computed_folder, readings=bench_readings[0],
                               protocol=SMALL_PROTOCOL, actor=tech)
    web = login(app, "tech")
    for (temp, hum), (t, h) in zip(ENTERED, SHOWN):
        r = web.post(f"/calibrations/{cid}/attach", data={
            "csrf": csrf_of(web), "standards": str(std.id), "temperature_c": temp,
            "humidity_pct": hum})
        assert r.status_code == 303 and "error" not in r.headers["location"], r.headers
        cal = services.calibration(sqlite_store, cid)
        assert (cal.temperature_c, cal.humidity_pct) == (float(temp), float(hum))
        assert lab_file_conditions(sqlite_store, cid) == (t, h)
        worker.run_now(sqlite_store, cid)
        page = web.get(f"/calibrations/{cid}").text
        assert f"<dd>{t} °C, {h} %" in page
        # the attach form offers the text as entered, not the float's repr
        assert f'name="temperature_c" inputmode="decimal" value="{t}"' in page
        draft = web.get(f"/calibrations/{cid}/files/certificate.html").text
        assert kv_row(draft, "Temperature") == f"{t} °C"
        assert kv_row(draft, "Relative humidity") == f"{h} %"
        dcc = web.get(f"/calibrations/{cid}/files/certificate.dcc.xml").content
        assert dcc_conditions(dcc) == [t, h]


def test_issued_certificate_states_the_environment_as_entered(store, people, computed_folder,
                                                              bench_readings, monkeypatch):
    """Entered at creation ("20", "45.0"), reviewed, approved and issued: the issued
    certificate and its DCC say "20 °C" and "45.0 %"; amended with "20.0": "20.0 °C"."""
    inst, std = setup_instrument(store, people)
    sha, _ = services.store_file(store, open(bench_readings[0], "rb"))
    psha, _ = services.store_file(store, open(SMALL_PROTOCOL, "rb"))
    cal = services.create_calibration(store, people["tech"], instrument_id=inst.id,
                                      readings_sha256=sha, readings_name="readings.csv",
                                      protocol_sha256=psha, standard_ids=[std.id],
                                      temperature_c="20", humidity_pct="45.0")
    cal = run_worker(store, monkeypatch, computed_folder)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev2"], cal.id)
    cert = run_issue(store, monkeypatch)
    page = services.file_bytes(store, cert.html_sha256).decode("utf-8")
    assert (kv_row(page, "Temperature"), kv_row(page, "Relative humidity")) == (
        "20 °C", "45.0 %")
    assert dcc_conditions(services.file_bytes(store, cert.dcc_sha256)) == ["20", "45.0"]
    services.amend(store, people["rev"], cert.id, "the temperature logger's digits")
    services.attach_conditions(store, people["rev"], cal.id, temperature_c="20.0",
                               humidity_pct="45.0")
    services.approve(store, people["rev2"], cal.id)
    again = run_issue(store, monkeypatch)
    page = services.file_bytes(store, again.html_sha256).decode("utf-8")
    assert kv_row(page, "Temperature") == "20.0 °C"


def test_command_line_attach_prints_the_digits(sqlite_store, computed_folder, bench_readings,
                                               capsys, monkeypatch):
    """``gonio db attach --temperature 20.0 --humidity 45``: the line says "20.0 °C, 45 %"
    and the laboratory file written for the calibration carries the same text."""
    from .conftest import make_people

    people = make_people(sqlite_store)
    inst, std = setup_instrument(sqlite_store, people)
    cid = import_output_folder(sqlite_store, computed_folder, readings=bench_readings[0],
                               protocol=SMALL_PROTOCOL, actor=people["tech"])
    data = sqlite_store.data
    sqlite_store.close()
    monkeypatch.setenv("GONIO_PASSWORD", PASSWORD)
    assert main(["db", "attach", str(cid), "--user", "tech", "--standard", std.identifier,
                 "--temperature", "20.0", "--humidity", "45", "--data", str(data)]) == 0
    assert capsys.readouterr().out.endswith("environment 20.0 °C, 45 %\n")


def _old_row(c, cid: int, temp, hum) -> None:
    """A calibration as the records at 0011 wrote it (the numbers only)."""
    c.execute(text(
        "INSERT INTO calibrations (id, instrument_id, spec_key, protocol, readings_sha256, "
        "readings_name, lab_name, temperature_c, humidity_pct, environment_from, place, "
        "location, performed_on, status, progress, error, worker_host, created_at, "
        "review_comment, pending_reason, pending_number, reviewed_seal, approved_seal) "
        "VALUES (:id, 1, 'ogam-draft', '', :s, '', '', :t, :h, '', '', 'laboratory', "
        "'2025-01-01', 'queued', '', '', '', '2025-01-01', '', '', '', '', '')"),
        {"id": cid, "s": "a" * 64, "t": temp, "h": hum})


def test_migration_0012_over_0011(tmp_path, pg_server):
    """Records at 0011 with calibrations whose environment is numbers only, upgraded: each
    row keeps printing what the page printed before (6 significant digits: 20.0 → "20"), on
    the page's text, in the laboratory file written for it; none entered stays none; down to
    0011 the numbers stay and the texts go — on SQLite and PostgreSQL."""
    from gonio.records.db import open_store
    from gonio.web.front import fmt

    from .conftest import both_back_ends, insert_instrument, records_at

    old = {1: (20.0, 45.5), 2: (20.25, 40.0), 3: (None, None)}
    for url, data in both_back_ends(tmp_path, pg_server):
        st = records_at(url, data, "0011")
        with st.engine.begin() as c:
            insert_instrument(c)
            for cid, (t, h) in old.items():
                _old_row(c, cid, t, h)
        st.close()
        st = open_store(url, data)
        try:
            for cid, (t, h) in old.items():
                cal = services.calibration(st, cid)
                if t is None:
                    assert (cal.temperature_text, cal.humidity_text) == (None, None)
                    continue
                # what the records' page printed before (its number format, fmt)
                before = (fmt(t), fmt(h))
                assert (cal.temperature_text, cal.humidity_text) == before
                assert (cal.temperature_c, cal.humidity_pct) == (t, h)
                assert lab_file_conditions(st, cid) == before
            assert services.calibration(st, 1).temperature_text == "20"
        finally:
            st.close()
        from .test_result_statement import _downgrade
        st = open_store(url, data)
        try:
            _downgrade(st.engine, "0011")
            with st.engine.connect() as c:
                cols = list(c.execute(text("SELECT * FROM calibrations")).keys())
                got = c.execute(text("SELECT temperature_c, humidity_pct FROM calibrations "
                                     "ORDER BY id")).all()
            assert "temperature_text" not in cols and "humidity_text" not in cols
            assert [tuple(r) for r in got] == list(old.values())
        finally:
            st.close()
        st = open_store(url, data)           # up again: filled again
        try:
            assert services.calibration(st, 2).temperature_text == "20.25"
        finally:
            st.close()


def test_condition_digits_are_the_same_number_in_toml():
    """Every text the records keep is a TOML number equal to what was entered, with as many
    decimals as were typed (a plain decimal); one wider than the column is refused in a line."""
    from gonio.errors import GonioError

    for typed in ("20", "20.0", "-3.25", "007.5", "20.", ".5", "-.5", "1_9.5", "2e1", "+21.5",
                  "2.05E1", "-0.0", "99.999999999999999"):
        got = services.condition_digits(typed)
        assert tomllib.loads(f"x = {got}")["x"] == float(typed.replace("_", "")), typed
        if re.fullmatch(r"[-\d_]*\.?\d*", typed):
            decimals = typed.split(".")[1] if "." in typed else ""
            assert (got.split(".")[1] if "." in got else "") == decimals, typed
    with pytest.raises(GonioError, match="temperature_c: more than 40 characters"):
        services.condition_value("-." + "0" * 38, "temperature_c", -50, 100)
