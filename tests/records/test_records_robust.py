"""A robust service: one line (exit 2) for a corrupt, locked or read-only database; 404 for
what does not exist; implausible dates refused; --workers bounded; gonio db import of a
calibrate folder says what to give; a malformed results.json is a GonioError; a killed
worker's folder removed."""

from __future__ import annotations

import datetime as dt
import io
import os
import sqlite3

import pytest

from gonio.cli import main
from gonio.errors import GonioError
from gonio.records import services

from .conftest import SMALL_PROTOCOL, conditions, make_people
from .test_records_services import setup_instrument
from .test_web_security import app, login  # noqa: F401  (the app fixture)


def cli(argv, capsys, rc=2):
    assert main([str(a) for a in argv]) == rc
    out = capsys.readouterr()
    if rc == 2:
        assert out.err.startswith("gonio: error: ") and out.err.count("\n") == 1, out.err
    return out.err


def test_a_file_of_random_bytes_is_no_database(tmp_path, capsys):
    data = tmp_path / "data"
    data.mkdir()
    (data / "records.sqlite3").write_bytes(os.urandom(4096))
    err = cli(["db", "init", "--data", data], capsys)
    assert "not a readable records database" in err and "restore it from a backup" in err


def test_a_locked_database_is_one_line(tmp_path, capsys, monkeypatch):
    from gonio.records import db

    data = tmp_path / "data"
    cli(["db", "init", "--data", data], capsys, 0)
    monkeypatch.setattr(db, "BUSY_TIMEOUT_S", 0.3)
    monkeypatch.setenv("GONIO_PASSWORD", "long enough password")
    other = sqlite3.connect(data / "records.sqlite3", isolation_level=None)
    other.execute("BEGIN EXCLUSIVE")
    try:
        err = cli(["db", "create-user", "alice", "--roles", "admin", "--data", data], capsys)
    finally:
        other.execute("ROLLBACK")
        other.close()
    assert "locked by another process (waited 0.3 s)" in err


def test_a_read_only_database_is_one_line(tmp_path, capsys, monkeypatch):
    data = tmp_path / "data"
    cli(["db", "init", "--data", data], capsys, 0)
    monkeypatch.setenv("GONIO_PASSWORD", "long enough password")
    url = f"sqlite:///file:{data / 'records.sqlite3'}?mode=ro&uri=true"
    err = cli(["db", "create-user", "alice", "--roles", "admin", "--database", url,
               "--data", data], capsys)
    assert "the database is read-only" in err


def test_implausible_dates_refused(sqlite_store):
    people = make_people(sqlite_store)
    inst, _ = setup_instrument(sqlite_store, people)
    sha, _ = services.store_file(sqlite_store, io.BytesIO(b"x"))
    for kw, msg in (({"performed_on": "9999-12-31"}, "key performed_on: 9999-12-31 is in "
                     "the future"),
                    ({"performed_on": dt.date.today() + dt.timedelta(days=1)}, "in the future"),
                    ({"performed_on": "2025-03-01", "received_on": "2025-03-02"},
                     "received on 2025-03-02, after the calibration date 2025-03-01")):
        with pytest.raises(GonioError, match=msg):
            services.create_calibration(sqlite_store, people["tech"], instrument_id=inst.id,
                                        readings_sha256=sha, **kw,
                                        **conditions(sqlite_store, people["tech"]))
    ok = services.create_calibration(sqlite_store, people["tech"], instrument_id=inst.id,
                                     readings_sha256=sha, performed_on="2025-03-02",
                                     received_on="2025-03-01",
                                     **conditions(sqlite_store, people["tech"]))
    assert ok.status == "queued"


def test_what_does_not_exist_is_404(app):  # noqa: F811
    tech = login(app, "tech")
    for url in ("/calibrations/999999/progress", "/calibrations/999999",
                "/certificates/999999", "/instruments/999999/calibrate"):
        assert tech.get(url).status_code == 404, url


@pytest.mark.parametrize("workers,limit,msg", [
    ("1000", "4", "must be within 1 … 4"), ("-3", "4", "got -3"), ("0", "", "got 0"),
    ("2", "x", "GONIO_MAX_WORKERS must be a number")])
def test_workers_bounded(tmp_path, capsys, monkeypatch, workers, limit, msg):
    monkeypatch.setenv("GONIO_MAX_WORKERS", limit)
    err = cli(["serve", "--workers", workers, "--data", tmp_path / "data"], capsys)
    assert msg in err
    assert not (tmp_path / "data").exists()            # refused before anything was opened


def test_import_of_a_calibrate_folder_takes_its_readings(tmp_path, capsys, computed_folder,
                                                         bench_readings):
    data = tmp_path / "data"
    err = cli(["db", "import", computed_folder, "--data", data, "--protocol", SMALL_PROTOCOL],
              capsys)
    assert "give it with --readings" in err
    out = cli(["db", "import", computed_folder, "--data", data, "--protocol", SMALL_PROTOCOL,
               "--readings", bench_readings[0]], capsys, 0)
    assert out == ""


@pytest.mark.parametrize("doc", [{"spec": "x"}, {"spec": "x", "items": []},
                                 {"spec": "x", "items": {"K": [1]}},
                                 {"spec": "x", "items": {"K": {"uncertainty": {
                                     "interval": [1]}}}}])
def test_result_from_malformed_json_is_a_gonio_error(doc):
    from gonio.result.model import RESULTS_VERSION, Result

    with pytest.raises(GonioError, match="malformed results.json"):
        Result.from_json(dict(doc, version=RESULTS_VERSION))


def test_killed_workers_folder_removed(sqlite_store):
    people = make_people(sqlite_store)
    inst, std = setup_instrument(sqlite_store, people)
    sha, _ = services.store_file(sqlite_store, io.BytesIO(b"readings"))
    cal = services.create_calibration(sqlite_store, people["tech"], instrument_id=inst.id,
                                      readings_sha256=sha,
                                      **conditions(sqlite_store, people["tech"]))
    services.claim_next(sqlite_store)
    services.attach(sqlite_store, cal.id, 999_999_999)
    work = sqlite_store.data / "work" / f"cal-{cal.id}-0123456789ab"
    work.mkdir(parents=True)
    (work / "readings.csv").write_bytes(b"readings")
    keep = sqlite_store.data / "work" / f"cal-{cal.id + 1}-0123456789ab"
    keep.mkdir()
    assert services.recover(sqlite_store) == [cal.id]
    assert not work.exists() and keep.exists()


def test_a_failed_run_is_voided_with_a_reason(app, sqlite_store):  # noqa: F811
    tech = services.user(sqlite_store, "tech")
    cust = services.add_customer(sqlite_store, tech, "C")
    inst = services.register_instrument(sqlite_store, tech, customer_id=cust.id, serial="S",
                                        spec_key="ogam-draft")
    sha, _ = services.store_file(sqlite_store, io.BytesIO(b"not readings"))
    cal = services.create_calibration(sqlite_store, tech, instrument_id=inst.id,
                                      readings_sha256=sha, **conditions(sqlite_store, tech))
    with pytest.raises(GonioError, match="cannot void a calibration that is queued"):
        services.void(sqlite_store, tech, cal.id, "wrong file")
    services.claim_next(sqlite_store)
    services.fail(sqlite_store, cal.id, "not a readings file")
    with pytest.raises(GonioError, match="key reason: must not be empty"):
        services.void(sqlite_store, tech, cal.id, " ")
    web = login(app, "tech")
    page = web.get(f"/calibrations/{cal.id}").text
    assert f'action="/calibrations/{cal.id}/void"' in page
    from .test_web_security import csrf_of
    r = web.post(f"/calibrations/{cal.id}/void", data={"csrf": csrf_of(web),
                                                       "reason": "a rate-gyro file"})
    assert r.status_code == 303 and "error" not in r.headers["location"]
    got = services.calibration(sqlite_store, cal.id)
    assert got.status == "void" and got.error == "void: a rate-gyro file"
    assert web.get("/calibrations?status=void").text.count(f"/calibrations/{cal.id}\"") == 1


def test_a_form_with_an_error_keeps_what_was_entered(app, sqlite_store):  # noqa: F811
    from .test_web_security import csrf_of

    tech = services.user(sqlite_store, "tech")
    cust = services.add_customer(sqlite_store, tech, "C")
    inst = services.register_instrument(sqlite_store, tech, customer_id=cust.id, serial="S",
                                        spec_key="ogam-draft")
    std = services.add_standard(sqlite_store, tech, name="table", identifier="T-1",
                                due_on="2099-01-01")
    web = login(app, "tech")
    r = web.post(f"/instruments/{inst.id}/calibrate", data={
        "csrf": csrf_of(web), "performed_on": "9999-12-31", "received_on": "2025-01-02",
        "temperature_c": "20.5", "humidity_pct": "41", "place": "Room 2",
        "location": "customer", "standards": [str(std.id)]},
        files={"readings": ("r.csv", b"x\n")})
    assert r.status_code == 400 and "9999-12-31 is in the future" in r.text
    for kept in ('value="9999-12-31"', 'value="2025-01-02"', 'value="20.5"', 'value="41"',
                 'value="Room 2"', f'value="{std.id}"  checked',
                 '<option value="customer" selected>'):
        assert kept in r.text, kept


def test_import_of_a_result_dated_in_the_future_refused(tmp_path, capsys, computed_folder,
                                                        bench_readings):
    import hashlib
    import json
    import shutil

    folder = tmp_path / "run"
    shutil.copytree(computed_folder, folder)
    res = json.loads((folder / "results.json").read_text())
    res.setdefault("metadata", {})["date"] = "9999-12-31"
    (folder / "results.json").write_text(json.dumps(res))
    # written so by gonio (a workstation whose clock is wrong): its manifest lists these bytes
    # (an edited results.json beside an untouched manifest is refused before the date)
    man = json.loads((folder / "gonio-manifest.json").read_text())
    man["files"]["results.json"] = hashlib.sha256((folder / "results.json").read_bytes()
                                                  ).hexdigest()
    (folder / "gonio-manifest.json").write_text(json.dumps(man))
    err = cli(["db", "import", folder, "--data", tmp_path / "data", "--protocol",
               SMALL_PROTOCOL, "--readings", bench_readings[0]], capsys)
    assert "key metadata.date: 9999-12-31 is in the future" in err


def test_import_without_a_manifest_refused(tmp_path, capsys, computed_folder, bench_readings):
    """gonio-manifest.json deleted and results.json edited (K by 2 ppm): refused by the
    recomputation on import, one line, exit 2, nothing recorded; the same folder with its
    manifest back and results.json as gonio wrote it imports (so the refusal is the edit's)."""
    import json
    import shutil

    folder = tmp_path / "run"
    shutil.copytree(computed_folder, folder)
    man = (folder / "gonio-manifest.json").read_bytes()
    original = (folder / "results.json").read_bytes()
    (folder / "gonio-manifest.json").unlink()
    doc = json.loads(original)
    doc["items"]["scale_factor"]["value"] *= 1 + 2e-6
    (folder / "results.json").write_text(json.dumps(doc, indent=2), encoding="utf-8")
    data = tmp_path / "data"
    args = ["db", "import", folder, "--data", data, "--protocol", SMALL_PROTOCOL,
            "--readings", bench_readings[0]]
    err = cli(args, capsys)
    assert "scale_factor" in err and "recomputed" in err      # the recomputation refuses it
    (folder / "results.json").write_bytes(original)
    (folder / "gonio-manifest.json").write_bytes(man)
    assert cli(args, capsys, 0) == ""
    from gonio.records.db import open_store
    from gonio.records.models import Calibration
    st = open_store(None, data)
    try:
        with st.session() as s:                 # the refused import recorded nothing
            assert s.query(Calibration).count() == 1
    finally:
        st.close()


def test_a_far_future_record_leaves_the_pages_answering(app, sqlite_store):  # noqa: F811
    """A calibration dated 9999-12-31 (refused at entry, but possible in an old database) no
    longer makes the overview, the due lists and the history plot answer 500: its due date
    is the last date there is, so the instrument is simply not due."""
    from .test_web_lists import issued

    tech = services.user(sqlite_store, "tech")
    cust = services.add_customer(sqlite_store, tech, "Far Ltd", "1 Road")
    inst = services.register_instrument(sqlite_store, tech, customer_id=cust.id, serial="F-1",
                                        spec_key="ogam-draft", model="M", interval_months=12)
    issued(sqlite_store, inst.id, dt.date(9999, 12, 31), "GC-9999-0001")
    web = login(app, "tech")
    for url in ("/", "/due", "/due?within_days=100000", "/export/due.csv", "/due/recall",
                f"/instruments/{inst.id}", f"/instruments/{inst.id}/history.svg"):
        assert web.get(url).status_code == 200, url
    assert services.due_instruments(sqlite_store, within_days=10**7) == [
        {"instrument_id": inst.id, "serial": "F-1", "model": "M", "customer": "Far Ltd",
         "last": dt.date(9999, 12, 31), "due": dt.date.max, "overdue": False}]


@pytest.mark.parametrize("name", ["GONIO_MAX_UPLOAD_BYTES", "GONIO_MAX_BACKUP_BYTES",
                                  "GONIO_MAX_RECORDS_JSON_BYTES"])
@pytest.mark.parametrize("value,msg", [("8 GiB", "must be a number"), ("0", "must be > 0"),
                                       ("-1", "must be > 0"), ("nan", "must be > 0")])
def test_backup_limits_checked_when_serve_starts(tmp_path, capsys, monkeypatch, name, value,
                                                 msg):
    """A backup limit that is no positive number stops ``gonio serve`` at start with one
    line naming the variable (exit 2), before the data folder is made or a port is bound;
    not at the first upload."""
    monkeypatch.setenv(name, value)
    # port 0 is refused too, later: the server never starts in this test
    err = cli(["serve", "--data", tmp_path / "data", "--port", "0"], capsys)
    assert f"environment variable {name} {msg}" in err, err
    assert not (tmp_path / "data").exists()


def test_upload_limit_read_through_limits_by_every_db_command(tmp_path):
    """``GONIO_MAX_UPLOAD_BYTES`` is read with the other limits (:func:`gonio.limits.limit`):
    a value that is no number stops a ``gonio db`` command (which imports the records'
    services) with one line naming the variable, exit 2, no traceback, nothing made."""
    import subprocess
    import sys

    env = dict(os.environ, GONIO_MAX_UPLOAD_BYTES="256 MiB")
    out = subprocess.run([sys.executable, "-m", "gonio", "db", "verify", "--data",
                          str(tmp_path / "data")], capture_output=True, text=True, env=env,
                         timeout=300)
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "GONIO_MAX_UPLOAD_BYTES must be a number" in lines[0], lines
    assert not (tmp_path / "data").exists()


def test_history_reads_the_stored_results_only_for_the_plot(sqlite_store, monkeypatch):
    """The instrument page asks the history without intervals (it shows counts and the
    interval proposal, not bars): no stored results.json is read for it, so the page's time
    does not grow with the stored results' size; the plot's history reads them for a row
    that keeps no statement (``stated`` None: written before rows kept it)."""
    from gonio.records import results
    from gonio.records.models import ResultItem

    from .test_web_lists import issued

    tech = make_people(sqlite_store)["tech"]
    cust = services.add_customer(sqlite_store, tech, "Near Ltd", "1 Road")
    inst = services.register_instrument(sqlite_store, tech, customer_id=cust.id, serial="H-1",
                                        spec_key="ogam-draft", model="M")
    cal_id = issued(sqlite_store, inst.id, dt.date(2025, 1, 2), "GC-2025-0001")
    with sqlite_store.writing() as s:
        s.add(ResultItem(calibration_id=cal_id, key="zero_stability", title="B_s",
                         clause="7.3", unit="deg/h", value=1e-3, U=None, k=None))
        s.commit()
    reads = []
    monkeypatch.setattr(results, "stated_intervals",
                        lambda store, sha: reads.append(sha) or {"zero_stability": (0, 2e-3)})
    quiet = services.history(sqlite_store, inst.id, intervals=False)
    assert reads == [] and quiet["zero_stability"][0]["interval"] is None
    drawn = services.history(sqlite_store, inst.id)
    assert len(reads) == 1 and drawn["zero_stability"][0]["interval"] == (0, 2e-3)
