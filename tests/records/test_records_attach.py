"""Standards and environment attached to a calibration put in without them (``gonio db
import``, ``gonio calibrate --record``), and the submission checks enforced at review and
approval on every path: a calibration without a registered standard valid on its date, or
without its environment, is neither reviewed nor approved (one line naming what is missing)."""

from __future__ import annotations

import datetime as dt
import json
import shutil
from pathlib import Path

import pytest
from sqlalchemy import delete, select, update

from gonio.cli import main
from gonio.errors import GonioError
from gonio.records import queries, services, worker
from gonio.records.db import open_store
from gonio.records.importer import import_output_folder
from gonio.records.models import (AuditEvent, Calibration, CalibrationFile,
                                  CalibrationStandard)

from .conftest import REPO, SMALL_PROTOCOL, conditions, make_people
from .test_records_services import new_calibration, run_worker, setup_instrument
from .test_web_security import app, csrf_of, login  # noqa: F401  (the app fixture)


def void_all(data: Path) -> None:
    """Set every calibration of the records in ``data`` aside (void), so that their readings
    may be recorded again."""
    st = open_store(None, data)
    try:
        with st.writing() as s:
            s.execute(update(Calibration).values(status="void"))
            s.commit()
    finally:
        st.close()


def draft_html(store, cid) -> str:
    """The stored draft certificate (HTML) of a calibration."""
    with store.session() as s:
        sha = s.get(CalibrationFile, (cid, "certificate.html")).sha256
    return services.file_bytes(store, sha).decode("utf-8")


def imported(store, people, computed_folder, bench_readings):
    return import_output_folder(store, computed_folder, readings=bench_readings[0],
                                protocol=SMALL_PROTOCOL, actor=people["tech"])


def test_imported_calibration_is_reviewed_only_with_standards_and_environment(
        store, people, computed_folder, bench_readings):
    inst, std = setup_instrument(store, people)
    cid = imported(store, people, computed_folder, bench_readings)
    day = services.calibration(store, cid).performed_on
    # the command line's certificate (its number, "Calibration Certificate", no DRAFT mark)
    # is not kept as the records' draft
    assert queries.calibration_page(store, cid)["files"] == ["results.json", "summary.txt"]
    with pytest.raises(GonioError) as exc:
        services.review(store, people["rev"], cid, accept=True)
    assert str(exc.value) == (
        f"key submission: cannot review calibration {cid}: it names no registered standard "
        f"valid on {day} and no environment (temperature, humidity); attach them first (the "
        "calibration page, or gonio db attach)")
    # a standard past its due date on the calibration date, one retired: refused by name
    old = services.add_standard(store, people["tech"], name="autocollimator",
                                identifier="AC-OLD", due_on=day - dt.timedelta(days=1),
                                calibrated_on=day - dt.timedelta(days=400),
                                out_of_service="overdue, kept for its history")
    with pytest.raises(GonioError, match=f"AC-OLD was due on {day - dt.timedelta(days=1)}"):
        services.attach_conditions(store, people["tech"], cid, standard_ids=[old.id])
    # an environment the readings contradict (they say 20.0 °C)
    with pytest.raises(GonioError, match=r"temperature: the readings say 20.0 °C \(# "
                                         r"temperature_c\), entered 26.5 °C"):
        services.attach_conditions(store, people["tech"], cid, temperature_c="26.5",
                                   humidity_pct="40")
    # the readings state no humidity: it cannot be taken from them
    with pytest.raises(GonioError, match=r"the readings state no humidity \(# humidity_pct\)"):
        services.attach_conditions(store, people["tech"], cid, environment_from_readings=True)
    with pytest.raises(GonioError, match="technician or reviewer"):
        services.attach_conditions(store, None, cid, standard_ids=[std.id])
    got = services.attach_conditions(store, people["tech"], cid, standard_ids=[std.id])
    # its draft is rendered from the stored result with what is attached (a worker's turn;
    # review waits for it)
    assert got.status == "drafting"
    with pytest.raises(GonioError, match="cannot review a calibration that is drafting"):
        services.review(store, people["rev"], cid, accept=True)
    seal_before = services.seal(store, cid)
    results_before = services.calibration(store, cid).results_sha256
    worker.run_now(store, cid)
    assert services.calibration(store, cid).status == "computed"
    assert queries.calibration_page(store, cid)["files"] == [
        "certificate.dcc.xml", "certificate.html", "certificate.pdf", "lab.toml",
        "results.json", "summary.txt"]
    draft = draft_html(store, cid)
    assert "DRAFT-%d" % cid in draft and '<span class="nb">RT-07</span>' in draft
    assert "20.4 °C" not in draft
    with pytest.raises(GonioError, match="names no environment"):
        services.review(store, people["rev"], cid, accept=True)
    got = services.attach_conditions(store, people["tech"], cid, temperature_c="20.4",
                                     humidity_pct="41")
    assert (got.temperature_c, got.humidity_pct, got.environment_from) == (20.4, 41.0, "")
    worker.run_now(store, cid)
    draft = draft_html(store, cid)
    assert "<td>20.4 °C</td>" in draft and "<td>41 %</td>" in draft and "RT-07" in draft
    # the stored result itself is the one imported: nothing was computed again; the seal
    # changed with the draft's files (the review signs the draft rendered last)
    assert services.calibration(store, cid).results_sha256 == results_before
    assert services.seal(store, cid) != seal_before
    with store.session() as s:
        ev = s.scalars(select(AuditEvent).where(AuditEvent.action == "attach")
                       .order_by(AuditEvent.id)).all()
    (b1, a1), (b2, a2) = ((json.loads(e.before_json), json.loads(e.after_json)) for e in ev)
    assert (b1["standards"], a1["standards"]) == ([], ["RT-07"])
    assert (b2["temperature_c"], a2["temperature_c"]) == (None, 20.4)
    assert all(e.username == "tech" for e in ev)
    assert services.review(store, people["rev"], cid, accept=True).status == "reviewed"
    lab = services.lab_details(store, cid, final=True)
    assert lab["standards"][0]["identifier"] == "RT-07"
    assert lab["environment"] == {"temperature_c": 20.4, "humidity_pct": 41.0,
                                  "source": "entered"}
    # approved and issued: the certificate, rendered from the stored result at issue,
    # names the standard attached and the environment
    services.approve(store, people["rev2"], cid)
    assert worker.execute(store, services.claim_next(store).id), \
        services.calibration(store, cid).error
    with store.session() as s:
        from gonio.records.models import Certificate
        html_sha = s.scalar(select(Certificate.html_sha256).where(
            Certificate.calibration_id == cid))
    page = services.file_bytes(store, html_sha).decode("utf-8")
    assert '<span class="nb">RT-07</span>' in page and "<td>20.4 °C</td>" in page
    assert "<td>41 %</td>" in page


def test_approval_refused_without_them_and_attaching_sends_it_back_to_review(
        store, people, computed_folder, bench_readings, monkeypatch):
    inst, std = setup_instrument(store, people)
    cal = new_calibration(store, people, inst, std, bench_readings[0])
    run_worker(store, monkeypatch, computed_folder)
    services.review(store, people["rev"], cal.id, accept=True)
    with store.writing() as s:             # a record from before the checks: no standard
        s.execute(delete(CalibrationStandard).where(
            CalibrationStandard.calibration_id == cal.id))
        s.commit()
    with pytest.raises(GonioError, match=f"cannot approve calibration {cal.id}: it names no "
                                         "registered standard valid on"):
        services.approve(store, people["rev2"], cal.id)
    got = services.attach_conditions(store, people["tech"], cal.id, standard_ids=[std.id])
    assert (got.status, got.reviewed_by_id, got.reviewed_seal) == ("drafting", None, "")
    # while its draft is rendered again, what is attached meanwhile is rendered too
    services.attach_conditions(store, people["tech"], cal.id, temperature_c=20.0,
                               humidity_pct=47)
    assert services.claim_next(store).id == cal.id
    render = worker.render_folder

    def attached_while_rendering(*args, **kwargs):
        services.attach_conditions(store, people["tech"], cal.id, temperature_c=20.0,
                                   humidity_pct=48)
        return render(*args, **kwargs)
    monkeypatch.setattr(worker, "render_folder", attached_while_rendering)
    assert worker.execute(store, cal.id)
    monkeypatch.setattr(worker, "render_folder", render)
    got = services.calibration(store, cal.id)
    assert (got.status, got.worker_host) == ("drafting", "")   # once more: 48 % since
    worker.run_now(store, cal.id)
    assert services.calibration(store, cal.id).status == "computed"
    assert "<td>48 %</td>" in draft_html(store, cal.id)
    with store.session() as s:
        redrafts = s.scalars(select(AuditEvent).where(AuditEvent.action == "redraft")).all()
    assert len(redrafts) == 2 and all(e.username == "(system)" for e in redrafts)
    services.review(store, people["rev"], cal.id, accept=True)
    assert services.approve(store, people["rev2"], cal.id).status == "issuing"
    with pytest.raises(GonioError, match="cannot attach standards or the environment to a "
                                         "calibration that is issuing"):
        services.attach_conditions(store, people["tech"], cal.id, standard_ids=[std.id])


def test_an_amendment_is_approved_only_with_them(sqlite_store, computed_folder,
                                                 bench_readings, monkeypatch):
    people = make_people(sqlite_store)
    inst, std = setup_instrument(sqlite_store, people)
    cal = new_calibration(sqlite_store, people, inst, std, bench_readings[0])
    run_worker(sqlite_store, monkeypatch, computed_folder)
    services.review(sqlite_store, people["rev"], cal.id, accept=True)
    services.approve(sqlite_store, people["rev2"], cal.id)
    cert = services.store_issue(sqlite_store, cal.id, computed_folder)
    services.amend(sqlite_store, people["rev2"], cert.id, "environment corrected")
    with sqlite_store.writing() as s:       # issued before the checks: no environment
        from gonio.records.models import Calibration
        s.get(Calibration, cal.id).humidity_pct = None
        s.commit()
    with pytest.raises(GonioError, match=f"cannot approve calibration {cal.id}: it names no "
                                         r"environment \(temperature, humidity\)"):
        services.approve(sqlite_store, people["rev"], cal.id)
    got = services.attach_conditions(sqlite_store, people["tech"], cal.id,
                                     temperature_c=20.1, humidity_pct=46)
    assert got.status == "amending" and got.humidity_pct == 46.0
    assert services.approve(sqlite_store, people["rev"], cal.id).status == "issuing"


def test_environment_taken_from_the_readings_is_stated_so(sqlite_store, bench_readings,
                                                         tmp_path):
    from gonio.report.header import _environment_rows
    from gonio.report.i18n import labels

    people = make_people(sqlite_store)
    inst, std = setup_instrument(sqlite_store, people)
    text = bench_readings[0].read_text(encoding="utf-8")
    wet = tmp_path / "readings.csv"
    wet.write_text("# humidity_pct: 44\n" + text, encoding="utf-8")
    sha, _ = services.store_file(sqlite_store, open(wet, "rb"))
    cal = services.create_calibration(sqlite_store, people["tech"], instrument_id=inst.id,
                                      readings_sha256=sha, standard_ids=[std.id],
                                      temperature_c=20.2, humidity_pct=50)
    with pytest.raises(GonioError, match="not both"):
        services.attach_conditions(sqlite_store, people["tech"], cal.id, temperature_c=20,
                                   environment_from_readings=True)
    got = services.attach_conditions(sqlite_store, people["tech"], cal.id,
                                     environment_from_readings=True)
    assert (got.temperature_c, got.humidity_pct, got.environment_from) == (20.0, 44.0,
                                                                           "readings")
    lab = services.lab_details(sqlite_store, cal.id, final=False)
    assert lab["environment"]["source"] == "readings"
    # the readings' "# temperature_c: 20.0" with its digits, as the certificate of gonio
    # calibrate on these readings states it
    # (the readings are the optical draft's: its room-temperature keys, as its renderer looks
    # them up by the stored result's spec)
    assert _environment_rows({}, lab, labels("en"), "ogam-draft") == [
        ("Temperature", "20.0 °C (taken from the readings' metadata)"),
        ("Relative humidity", "44 % (taken from the readings' metadata)")]
    assert _environment_rows({}, lab, labels("zh"), "ogam-draft")[1] == ("相对湿度", "44 %（取自读数文件的元数据）")
    from gonio.report.rate_dcc import _conditions
    names = [c[0] for c in _conditions({"metadata": {}, "items": {}}, lab)]
    assert names == ["room temperature (taken from the readings' metadata)",
                     "relative humidity (taken from the readings' metadata)"]
    # entered values are stated plainly; with a lab file but none entered, the readings'
    # value is stated as taken from them
    plain = dict(lab, environment={"temperature_c": 21.0, "humidity_pct": 40.0})
    assert _environment_rows({}, plain, labels("en"), "ogam-draft")[0] == ("Temperature", "21 °C")
    assert _environment_rows({"temperature_c": "20.0"}, dict(lab, environment=None),
                             labels("en"), "ogam-draft")[0] == (
        "Temperature", "20.0 °C (taken from the readings' metadata)")


def test_every_new_calibration_names_a_standard_and_its_environment(sqlite_store,
                                                                   bench_readings):
    people = make_people(sqlite_store)
    inst, std = setup_instrument(sqlite_store, people)
    sha, _ = services.store_file(sqlite_store, open(bench_readings[0], "rb"))
    base = dict(instrument_id=inst.id, readings_sha256=sha)
    with pytest.raises(GonioError, match="tick the reference standard"):
        services.create_calibration(sqlite_store, people["tech"], **base)
    with pytest.raises(GonioError, match=r"enter the relative humidity \(%\)"):
        services.create_calibration(sqlite_store, people["tech"], **base,
                                    standard_ids=[std.id], temperature_c=20)
    assert services.create_calibration(sqlite_store, people["tech"], **base,
                                       **conditions(sqlite_store, people["tech"]))


def records_of_alice(tmp_path, monkeypatch):
    """A records data folder made on the command line: technician alice and the registered
    standard RT-07 (due in 300 days)."""
    data = tmp_path / "data"
    monkeypatch.setenv("GONIO_PASSWORD", "long enough password")
    assert main(["db", "create-user", "alice", "--roles", "admin technician", "--data",
                 str(data)]) == 0
    st = open_store(None, data)
    try:
        services.add_standard(st, services.user(st, "alice"), name="rotary table",
                              identifier="RT-07", due_on=dt.date.today() + dt.timedelta(300))
    finally:
        st.close()
    return data


def test_db_import_and_attach_on_the_command_line(tmp_path, computed_folder, bench_readings,
                                                  monkeypatch, capsys):
    data = records_of_alice(tmp_path, monkeypatch)
    folder = tmp_path / "run"
    shutil.copytree(computed_folder, folder)
    shutil.copy(bench_readings[0], folder / "readings.csv")
    capsys.readouterr()
    assert main(["db", "import", str(folder), "--data", str(data), "--protocol",
                 str(SMALL_PROTOCOL), "--user", "alice"]) == 0
    out = capsys.readouterr().out
    assert out.endswith("calibration 1: standards none; environment not entered; before "
                        "its review it needs registered standard valid on "
                        f"{dt.date.today()} and environment (temperature, humidity)\n"), out
    for argv, msg in ((["db", "attach", "1", "--standard", "RT-07"], "give the active records "
                                                                      "user"),
                      (["db", "attach", "1", "--user", "alice", "--standard", "NOPE"],
                       "no registered standard 'NOPE'"),
                      (["db", "attach", "1", "--user", "alice"], "nothing to attach"),
                      (["db", "attach", "1", "--user", "alice", "--temperature", "20"],
                       "enter both")):
        assert main(argv + ["--data", str(data)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("gonio: error: ") and err.count("\n") == 1 and msg in err, err
    monkeypatch.setenv("GONIO_USER", "alice")
    assert main(["db", "attach", "1", "--standard", "RT-07", "--temperature", "20.1",
                 "--humidity", "45", "--data", str(data)]) == 0
    assert capsys.readouterr().out == ("calibration 1: standards RT-07; environment "
                                       "20.1 °C, 45 %\n")
    # an import that attaches them at once (the same readings: the first one set aside,
    # as one readings file is one calibration that stands)
    void_all(data)
    assert main(["db", "import", str(folder), "--data", str(data), "--protocol",
                 str(SMALL_PROTOCOL), "--standard", "RT-07", "--temperature", "20",
                 "--humidity", "44"]) == 0
    assert capsys.readouterr().out.endswith("calibration 2: standards RT-07; environment "
                                            "20 °C, 44 %\n")


def test_attach_on_the_calibration_page(app, sqlite_store, computed_folder,  # noqa: F811
                                        bench_readings):
    tech = services.user(sqlite_store, "tech")
    people = {"tech": tech}
    inst, std = setup_instrument(sqlite_store, people)
    cid = imported(sqlite_store, people, computed_folder, bench_readings)
    web = login(app, "tech")
    page = web.get(f"/calibrations/{cid}").text
    assert "Before its review and approval this calibration needs: registered standard" in page
    assert 'action="/calibrations/%d/attach"' % cid in page
    assert "No draft certificate: this calibration was put in from the command line" in page
    r = web.post(f"/calibrations/{cid}/attach", data={
        "csrf": csrf_of(web), "standards": str(std.id), "temperature_c": "20.3",
        "humidity_pct": "47"})
    assert r.status_code == 303 and "error" not in r.headers["location"]
    page = web.get(f"/calibrations/{cid}").text
    assert "20.3 °C, 47 %" in page and "RT-07" in page and 'id="missing"' not in page
    assert "The draft certificate is being rendered again from the stored result" in page
    worker.run_now(sqlite_store, cid)           # the server's worker
    page = web.get(f"/calibrations/{cid}").text
    assert f"The certificate files above are the draft (number DRAFT-{cid})" in page
    draft = web.get(f"/calibrations/{cid}/files/certificate.html").text
    assert "<td>20.3 °C</td>" in draft and '<span class="nb">RT-07</span>' in draft
    r = web.post(f"/calibrations/{cid}/attach", data={
        "csrf": csrf_of(web), "environment_from_readings": "1"})
    assert "the%20readings%20state%20no%20humidity" in r.headers["location"]
    rev = login(app, "rev")
    r = rev.post(f"/calibrations/{cid}/review", data={"csrf": csrf_of(rev),
                                                     "decision": "accept"})
    assert r.status_code == 303 and "error" not in r.headers["location"]
    assert services.calibration(sqlite_store, cid).status == "reviewed"


def test_the_fixture_readings_have_no_humidity(bench_readings):
    """The tests above rely on the virtual bench writing a temperature and no humidity."""
    head = [ln for ln in Path(bench_readings[0]).read_text("utf-8").splitlines()
            if ln.startswith("#")]
    assert "# temperature_c: 20.0" in head and not any("humidity" in ln for ln in head)


def test_calibrate_record_attaches_and_carries_the_lab_environment(
        tmp_path, bench_readings, monkeypatch, capsys):
    """gonio calibrate --record: the laboratory file's [environment] is the record's (stated
    as from the laboratory file); --standard/--temperature/--humidity attach as with gonio
    db import and the draft is rendered with them; the options need --record."""
    data = records_of_alice(tmp_path, monkeypatch)
    lab = REPO / "protocols" / "lab-example.toml"
    run = ["calibrate", str(bench_readings[0]), "--protocol", str(SMALL_PROTOCOL), "--lab",
           str(lab), "--data", str(data), "--record-user", "alice"]
    capsys.readouterr()
    assert main(run + ["--out", str(tmp_path / "a"), "--record"]) == 0
    err = capsys.readouterr().err
    # the laboratory file's [[standards]] RT-07 is the registered RT-07 (before: none);
    # its humidity_pct = 45.0 keeps the digits written there, as the command line's
    # certificate states it (the draft below too)
    assert err.endswith("gonio: recorded as calibration 1: standards RT-07; environment "
                        "20.1 °C, 45.0 % (from the laboratory file)\n"), err
    assert "<td>45.0 %</td>" in (tmp_path / "a" / "certificate.html").read_text("utf-8")
    run[1] = str(bench_readings[1])         # another run: one readings file, one calibration
    assert main(run + ["--out", str(tmp_path / "b"), "--record", "--standard", "RT-07",
                       "--temperature", "20", "--humidity", "44"]) == 0
    assert capsys.readouterr().err.endswith(
        "gonio: recorded as calibration 2: standards RT-07; environment 20 °C, 44 %\n")
    assert main(run + ["--out", str(tmp_path / "c"), "--standard", "RT-07"]) == 2
    assert "go with --record" in capsys.readouterr().err
    # a laboratory file naming a standard not registered, for readings calibration 2 holds:
    # one line, nothing recorded, no --out; the readings held are refused first, before the
    # work (the standard alone: test_records_record_refused.py)
    other = tmp_path / "lab-other.toml"
    other.write_text(lab.read_text("utf-8").replace('identifier = "RT-07"',
                                                    'identifier = "AC-99"'), "utf-8")
    run[run.index(str(lab))] = str(other)
    assert main(run + ["--out", str(tmp_path / "d"), "--record"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gonio: error: ") and err.count("\n") == 1, err
    assert "already those of calibration 2 (RLG-0001, " in err, err
    assert not (tmp_path / "d").exists()
    st = open_store(None, data)
    try:
        one, two = services.calibration(st, 1), services.calibration(st, 2)
        assert (one.temperature_c, one.humidity_pct, one.environment_from) == (20.1, 45.0,
                                                                               "lab file")
        assert (two.temperature_c, two.humidity_pct, two.environment_from, two.status) == (
            20.0, 44.0, "", "computed")
        draft = draft_html(st, 2)          # rendered at once with what was attached
        assert "DRAFT-2" in draft and '<span class="nb">RT-07</span>' in draft
        assert "<td>20 °C</td>" in draft and "<td>44 %</td>" in draft
        assert services.lab_details(st, 1, final=False)["environment"]["source"] == "entered"
        assert queries.calibrations(st)[1] == 2                # the refused one: not recorded
        assert one.status == "computed"   # rendered at once with the lab file's standard
        assert '<span class="nb">RT-07</span>' in draft_html(st, 1)
        assert "<td>20.1 °C</td>" in draft_html(st, 1) and "<td>45.0 %</td>" in draft_html(st, 1)
    finally:
        st.close()


def lab_with_standards(tmp_path: Path, name: str, block: str) -> Path:
    """The example laboratory file with its [[standards]] replaced by ``block``, without
    its decision rule and limits (the computed folder was decided without them)."""
    text = (REPO / "protocols" / "lab-example.toml").read_text("utf-8")
    text = text[:text.index("\n# Statement of conformity") + 1]
    start = text.index("[[standards]]")
    end = text.index("\n[environment]") + 1
    path = tmp_path / name
    path.write_text(text[:start] + block + "\n" + text[end:], "utf-8")
    return path


def test_db_import_matches_the_lab_files_standards(tmp_path, computed_folder, bench_readings,
                                                   monkeypatch, capsys):
    """gonio db import --lab (gonio calibrate --record's function): each of the laboratory
    file's [[standards]] must be a registered standard, by identifier, valid on the
    calibration date; else one line, exit 2, and nothing is recorded (before: the file's
    standards were ignored, the calibration recorded with none)."""
    data = records_of_alice(tmp_path, monkeypatch)
    st = open_store(None, data)
    try:
        services.add_standard(st, services.user(st, "alice"), name="autocollimator",
                              identifier="AC-OLD", calibrated_on=dt.date(2019, 1, 1),
                              due_on=dt.date(2020, 1, 1), out_of_service="overdue since 2020")
    finally:
        st.close()
    folder = tmp_path / "run"
    shutil.copytree(computed_folder, folder)
    shutil.copy(bench_readings[0], folder / "readings.csv")
    rt07 = 'name = "rotary table"\nidentifier = "RT-07"\n'
    cases = (("unknown.toml", '[[standards]]\n' + rt07 + '[[standards]]\nname = "level"\n'
              'identifier = "LV-3"\n', "[[standards]] 2: 'LV-3' is not a registered standard"),
             ("blank.toml", '[[standards]]\nname = "level"\n',
              "[[standards]] 1 ('level') has no identifier to match a registered standard"),
             ("old.toml", '[[standards]]\n' + rt07 + '[[standards]]\nname = "ac"\n'
              'identifier = "AC-OLD"\n', "[[standards]] 2: standard AC-OLD was due on "
              f"2020-01-01 (before the calibration date {dt.date.today()})"))
    argv = ["db", "import", str(folder), "--data", str(data), "--protocol",
            str(SMALL_PROTOCOL), "--user", "alice"]
    capsys.readouterr()
    for name, block, msg in cases:
        assert main(argv + ["--lab", str(lab_with_standards(tmp_path, name, block))]) == 2
        err = capsys.readouterr().err
        assert err.startswith("gonio: error: ") and err.count("\n") == 1 and msg in err, err
    st = open_store(None, data)
    try:
        assert queries.calibrations(st)[1] == 0
        with st.session() as s:
            assert not s.scalars(select(AuditEvent).where(AuditEvent.action == "import")).all()
    finally:
        st.close()
    # both registered and valid: recorded with them and --standard's, its draft rendered
    good = lab_with_standards(tmp_path, "good.toml", '[[standards]]\n' + rt07)
    st = open_store(None, data)
    try:
        services.add_standard(st, services.user(st, "alice"), name="level", identifier="LV-3",
                              due_on=dt.date.today() + dt.timedelta(days=30))
    finally:
        st.close()
    assert main(argv + ["--lab", str(good), "--standard", "LV-3"]) == 0
    assert capsys.readouterr().out.endswith(
        "calibration 1: standards LV-3, RT-07; environment 20.1 °C, 45.0 % (from the "
        "laboratory file)\n")
    st = open_store(None, data)
    try:
        assert services.calibration(st, 1).status == "computed"
        draft = draft_html(st, 1)
        assert '<span class="nb">RT-07</span>' in draft and '<span class="nb">LV-3</span>' in draft
    finally:
        st.close()


def test_a_failed_redraft_is_rendered_again_not_computed_again(store, people, computed_folder,
                                                               bench_readings, monkeypatch):
    """A draft rendered again after an attach that fails: the calibration is failed with
    the reason (said to be the redraft's); run again, its draft is rendered again from the
    stored result — nothing computed (before: queued, computed again from the readings)."""
    inst, std = setup_instrument(store, people)
    cal = new_calibration(store, people, inst, std, bench_readings[0])
    run_worker(store, monkeypatch, computed_folder)
    results_before = services.calibration(store, cal.id).results_sha256
    services.attach_conditions(store, people["tech"], cal.id, temperature_c=20.0,
                               humidity_pct=47)

    render = worker.render_folder

    def broken(*args, **kwargs):
        raise GonioError("the renderer ran out of paper", key="render")
    monkeypatch.setattr(worker, "render_folder", broken)
    with pytest.raises(GonioError, match="ran out of paper"):
        worker.run_now(store, cal.id)
    got = services.calibration(store, cal.id)
    assert (got.status, got.progress) == ("failed", "drafting failed")
    assert got.error.startswith("rendering the draft certificate again failed: key render: "
                                "the renderer ran out of paper")
    assert queries.calibration_page(store, cal.id)["cal"].error == got.error

    def no_computing(*args, **kwargs):
        raise AssertionError("computed again")
    monkeypatch.setattr(worker, "render_folder", render)
    monkeypatch.setattr(worker, "calibrate_folder", no_computing)
    assert services.retry(store, people["tech"], cal.id).status == "drafting"
    worker.run_now(store, cal.id)
    got = services.calibration(store, cal.id)
    assert (got.status, got.error, got.results_sha256) == ("computed", "", results_before)
    assert "<td>47 %</td>" in draft_html(store, cal.id)
    with store.session() as s:
        actions = [a for (a,) in s.execute(select(AuditEvent.action).where(
            AuditEvent.entity == "calibration", AuditEvent.entity_id == str(cal.id)).order_by(AuditEvent.id))]
    assert actions[actions.index("attach"):] == ["attach", "claim", "fail", "retry", "claim",
                                                 "redraft"]
