"""The rotary table's calibration in the records and ``gonio serve`` (docs/records.md#table-calibration):
uploaded with the calibration form, kept as the calibration's file ``table_calibration.csv``
(an input, sealed with the run), used by the worker's real pipeline run, shown on the
calibration page; a changed stored file is detected by the seal; a backup restores it and the
certificate renders again to the same bytes; a laboratory file's ``[table_calibration]`` is
checked against the upload (SHA-256, due date) on the form.

Truths from outside the records: the file's SHA-256 by hashlib; the K the run states against
the 7.1 mean recomputed here from the readings with the file's errors (the draft's K_i =
N_i/θ_i with θ_i corrected by the table's error, e(stop) − e(zero), in arcsec/3600)."""

from __future__ import annotations

import datetime as dt
import hashlib
import io
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from sqlalchemy import update

from gonio.errors import GonioError
from gonio.records import blobs, services, worker
from gonio.records.models import CalibrationFile

from .test_web_lab_file import HEAD, alert, n_calibrations
from .test_web_lab_file import instrument as bare_instrument
from .test_web_security import app, csrf_of, login  # noqa: F401  (the app fixture)

REPO = Path(__file__).resolve().parents[2]
SMALL_PROTOCOL = REPO / "tests" / "data" / "small-protocol.toml"
#: the small protocol's positions (K: 0 → 120, 240, 360; E: 90 … 360) and a table error
POSITIONS = (0.0, 90.0, 120.0, 180.0, 240.0, 270.0)


def error_arcsec(a_deg):
    return 0.04 * np.cos(np.radians(a_deg)) + 0.02 * np.sin(np.radians(3 * a_deg))


TABLE = ("# table certificate TC-9\ntable_deg,error_arcsec,u_arcsec\n" + "".join(
    f"{a:g},{error_arcsec(a):.6f},0.02\n" for a in POSITIONS)).encode()
SHA = hashlib.sha256(TABLE).hexdigest()


def register_table(store, content: bytes = TABLE, name: str = "RT-07 cal.csv"):
    """``content`` registered as the calibration of the table RT-07 (the records' standard the
    forms tick), in force from 30 days before today: a table calibration that corrects a
    result must be a registered entry in force."""
    from sqlalchemy import select

    from gonio.records.models import Standard

    with store.session() as s:
        sid = s.scalar(select(Standard.id).where(Standard.identifier == "RT-07"))
    sha, _ = services.store_file(store, io.BytesIO(content))
    today = dt.date.today()
    return services.register_table_calibration(
        store, services.user(store, "tech"), standard_id=sid, sha256=sha, name=name,
        valid_from=today - dt.timedelta(days=30), due_on=today + dt.timedelta(days=300),
        certificate="TC-9")


def instrument(store, spec_key="ogam-draft"):
    """The forms' instrument and table RT-07, TABLE registered as the table's calibration."""
    inst = bare_instrument(store, spec_key)
    register_table(store)
    return inst


def post(client, inst, readings: bytes, table: bytes | None, lab: str | None = None,
         performed_on: str | None = None, table_name: str = "RT-07 cal.csv"):
    files = {"readings": ("readings.csv", io.BytesIO(readings)),
             "protocol_file": ("protocol.toml", io.BytesIO(SMALL_PROTOCOL.read_bytes()))}
    if table is not None:
        files["table_calibration_file"] = (table_name, io.BytesIO(table))
    if lab is not None:
        files["lab_file"] = ("my-lab.toml", io.BytesIO(lab.encode()))
    return client.post(f"/instruments/{inst.id}/calibrate", files=files,
                       data={"csrf": csrf_of(client),
                             "performed_on": performed_on or str(dt.date.today()),
                             "standards": ["1"], "temperature_c": "20.1",
                             "humidity_pct": "45"})


def k_corrected_here(readings: Path) -> float:
    """The 7.1 K from the readings with the table file's errors (arcsec → degrees by
    /3600): mean of N_i/(θ_i − (e(stop) − e(zero))/3600), the stops read from the file."""
    df = pd.read_csv(readings, comment="#")
    k = df[df["test"] == "scale_factor"]
    stop = k["table_deg"].to_numpy(float)
    theta = stop - (error_arcsec(np.mod(stop, 360.0)) - error_arcsec(0.0)) / 3600.0
    return float(np.mean(k["gyro_counts"].to_numpy(float) / theta))


@pytest.fixture
def computed(app, sqlite_store, bench_readings):  # noqa: F811
    """A calibration made through the web form with the table calibration uploaded, computed
    by the worker's real pipeline: (the technician's client, calibration id)."""
    tech = login(app, "tech")
    inst = instrument(sqlite_store)
    r = post(tech, inst, Path(bench_readings[0]).read_bytes(), TABLE)
    assert r.status_code == 303, alert(r.text)
    cal_id = int(r.headers["location"].rsplit("/", 1)[1])
    assert services.claim_next(sqlite_store).id == cal_id
    assert worker.execute(sqlite_store, cal_id), services.calibration(sqlite_store, cal_id).error
    return tech, cal_id


def results_of(store, cal_id) -> dict:
    return json.loads(services.file_bytes(store, services.calibration(store, cal_id)
                                          .results_sha256))


def test_uploaded_table_calibration_used_kept_and_shown(computed, sqlite_store,
                                                         bench_readings):
    """The upload is the calibration's table_calibration.csv (hashlib digest), the run's K is
    the 7.1 mean corrected by the file's errors as recomputed here (and not the uncorrected
    mean), results.json records the digest, and the page shows the file with its digest and
    the items it corrected; the stored bytes are the upload's."""
    tech, cal_id = computed
    with sqlite_store.session() as s:
        assert s.get(CalibrationFile, (cal_id, "table_calibration.csv")).sha256 == SHA
    assert services.file_bytes(sqlite_store, SHA) == TABLE
    res = results_of(sqlite_store, cal_id)
    k = res["items"]["scale_factor"]
    assert k["details"]["table_calibration"]["sha256"] == SHA
    want = k_corrected_here(Path(bench_readings[0]))
    assert abs(k["value"] / want - 1.0) < 1e-9, (k["value"], want)
    assert abs(k["details"]["table_calibration"]["uncorrected_value"] / want - 1.0) > 1e-8
    page = tech.get(f"/calibrations/{cal_id}").text
    assert 'id="table-calibration"' in page and SHA in page
    assert "the result was computed with it" in page
    got = tech.get(f"/calibrations/{cal_id}/files/table_calibration.csv")
    assert got.status_code == 200 and got.content == TABLE


def test_changed_stored_file_breaks_the_seal(computed, sqlite_store):
    """The stored file's bytes changed on disk, or the calibration's file pointed at another
    stored file: the seal (what review, approval and issue check) refuses, naming it."""
    _, cal_id = computed
    sealed = services.seal(sqlite_store, cal_id)
    other = TABLE.replace(b"0.02\n", b"0.03\n", 1)
    sha2, _ = services.store_file(sqlite_store, io.BytesIO(other))
    with sqlite_store.writing() as s:
        s.execute(update(CalibrationFile).where(
            CalibrationFile.calibration_id == cal_id,
            CalibrationFile.name == "table_calibration.csv").values(sha256=sha2))
        s.commit()
    with pytest.raises(GonioError, match="not the table calibration the stored results.json "
                                         "was computed with"):
        services.seal(sqlite_store, cal_id)
    with sqlite_store.writing() as s:
        s.execute(update(CalibrationFile).where(
            CalibrationFile.calibration_id == cal_id,
            CalibrationFile.name == "table_calibration.csv").values(sha256=SHA))
        s.commit()
    assert services.seal(sqlite_store, cal_id) == sealed
    path = blobs.blob_path(sqlite_store.blob_root, SHA)
    path.chmod(0o644)
    path.write_bytes(TABLE + b"\n")
    with pytest.raises(GonioError, match="stored table_calibration.csv is missing or does not "
                                         "match its SHA-256"):
        services.seal(sqlite_store, cal_id)


def test_backup_restore_renders_the_same_bytes(computed, sqlite_store, tmp_path):
    """A backup restored into empty records holds the calibration's table calibration (same
    bytes, same digest), the same seal, and its draft certificate rendered again from the
    stored result is byte-identical to the one rendered from the original records."""
    from gonio.records.backup import backup, restore
    from gonio.records.compute import render_folder, write_lab_toml
    from gonio.records.db import open_store

    _, cal_id = computed
    archive = tmp_path / "b.zip"
    backup(sqlite_store, archive)
    target = open_store(None, tmp_path / "target")
    try:
        restore(target, archive)
        with target.session() as s:
            assert s.get(CalibrationFile, (cal_id, "table_calibration.csv")).sha256 == SHA
        assert services.file_bytes(target, SHA) == TABLE
        assert services.seal(target, cal_id) == services.seal(sqlite_store, cal_id)
        outs = []
        for i, store in enumerate((sqlite_store, target)):
            lab = write_lab_toml(services.lab_details(store, cal_id, final=False, redraft=True),
                                 tmp_path / f"lab{i}.toml")
            out = tmp_path / f"render{i}"
            render_folder(services.file_bytes(store, services.calibration(store, cal_id)
                                              .results_sha256), out, spec_key="ogam-draft",
                          lab=lab)
            outs.append({n: (out / n).read_bytes() for n in ("certificate.html",
                                                             "certificate.dcc.xml",
                                                             "certificate.pdf")})
        assert outs[0] == outs[1]
        assert SHA.encode() in outs[0]["certificate.dcc.xml"]
    finally:
        target.close()


def lab_with_table(sha: str, due: str = "2099-01-01") -> str:
    return (HEAD + f'\n[table_calibration]\nfile = "RT-07 cal.csv"\nsha256 = "{sha}"\n'
            f'id = "TC-9"\ndue_on = "{due}"\n')


OTHER_SHA = hashlib.sha256(TABLE + b"15,0.0,0.02\n").hexdigest()


@pytest.mark.parametrize("table, lab, spec_key, registered, expect", [
    (None, lab_with_table(SHA), "ogam-draft", False,
     "my-lab.toml: key table_calibration: the laboratory file names the table calibration"),
    (TABLE, lab_with_table(OTHER_SHA), "ogam-draft", True,
     "my-lab.toml: key table_calibration.sha256: the table calibration uploaded has SHA-256"),
    (TABLE, lab_with_table(SHA, "2020-01-01"), "ogam-draft", True,
     "my-lab.toml: key table_calibration.due_on: the table calibration TC-9 was due on "
     "2020-01-01: expired"),
    (TABLE, None, "jjf1535-2015", False, "key table_calibration: jjf1535-2015 takes no table "
                                         "calibration"),
    (TABLE + b"\n", None, "ogam-draft", False,
     "key table_calibration: the table calibration uploaded (SHA-256"),
    (TABLE + b"\n", None, "ogam-draft", True,
     "key table_calibration: the register holds the calibrations of the table RT-07"),
], ids=["lab-names-one-none-uploaded", "another-content", "expired", "spec-takes-none",
        "unregistered-upload", "registered-plus-one-byte"])
def test_refused_on_the_form(app, sqlite_store, bench_readings, table, lab,  # noqa: F811
                             spec_key, registered, expect):
    """The form comes back (400) with one line; nothing is queued. An upload the register
    does not hold is refused, naming the register command (a table calibration that corrects
    a result is a registered entry in force)."""
    tech = login(app, "tech")
    inst = (instrument if registered else bare_instrument)(sqlite_store, spec_key)
    readings = (Path(bench_readings[0]).read_bytes() if spec_key == "ogam-draft"
                else f"# spec: {spec_key}\n".encode())
    r = post(tech, inst, readings, table, lab)
    assert r.status_code == 400
    msg = alert(r.text)
    assert msg.startswith(expect) and "\n" not in msg, msg
    if "(SHA-256" in expect:
        assert "gonio db register-table-calibration" in msg, msg
    assert n_calibrations(sqlite_store) == 0


def test_lab_file_naming_the_upload_accepted(app, sqlite_store, bench_readings):  # noqa: F811
    """A laboratory file naming only its table calibration (no limits) with the matching
    upload is accepted; the instrument's own limits stay in force."""
    tech = login(app, "tech")
    inst = instrument(sqlite_store)
    r = post(tech, inst, Path(bench_readings[0]).read_bytes(), TABLE, lab_with_table(SHA))
    assert r.status_code == 303, alert(r.text)
    cal_id = int(r.headers["location"].rsplit("/", 1)[1])
    d = services.lab_details(sqlite_store, cal_id, final=False)
    assert [(x["item"], x["mpe"]) for x in d["specification_limits"]] == [("repeatability", 9.0)]
    assert "table_calibration" not in d


IMPORT_LAB = """[laboratory]
name = "L"
address = "A"

[certificate]
number = "C-1"
date_of_calibration = "2026-11-16"

[customer]
name = "K"

[signatory]
approved_by = "P"

[[standards]]
name = "rotary table"
identifier = "RT-07"

[table_calibration]
file = "tc.csv"
sha256 = "{sha}"
due_on = "2099-01-01"
"""


def test_import_keeps_the_laboratory_table_calibration(app, sqlite_store,  # noqa: F811
                                                        bench_readings, tmp_path, capsys):
    """``gonio db import FOLDER --lab FILE`` of a command-line run made with the laboratory
    file's [table_calibration]: the calibration keeps that file (hashlib digest) and its seal
    holds; a laboratory file naming another calibration than the run used is refused."""
    from gonio.cli import main
    from gonio.records.importer import import_output_folder

    bare_instrument(sqlite_store)
    (tmp_path / "tc.csv").write_bytes(TABLE)
    lab = tmp_path / "lab.toml"
    lab.write_text(IMPORT_LAB.format(sha=SHA), encoding="utf-8")
    out = tmp_path / "run"
    assert main(["calibrate", str(bench_readings[0]), "--protocol", str(SMALL_PROTOCOL),
                 "--lab", str(lab), "--out", str(out)]) == 0
    capsys.readouterr()
    # another table calibration named by a laboratory file: not the one the run used
    other = TABLE.replace(b"0.02\n", b"0.03\n", 1)
    (tmp_path / "o").mkdir()
    (tmp_path / "o" / "tc.csv").write_bytes(other)
    lab2 = tmp_path / "o" / "lab.toml"
    lab2.write_text(IMPORT_LAB.format(sha=hashlib.sha256(other).hexdigest()), encoding="utf-8")
    with pytest.raises(GonioError, match="is not the one results.json was computed with"):
        import_output_folder(sqlite_store, out, lab=lab2, readings=bench_readings[0],
                             protocol=SMALL_PROTOCOL)
    assert n_calibrations(sqlite_store) == 0
    # the run's table calibration not in the register: refused, naming the register command
    with pytest.raises(GonioError, match="not in the register.*gonio db "
                                         "register-table-calibration"):
        import_output_folder(sqlite_store, out, lab=lab, readings=bench_readings[0],
                             protocol=SMALL_PROTOCOL)
    assert n_calibrations(sqlite_store) == 0
    register_table(sqlite_store, TABLE, "tc.csv")
    cal_id = import_output_folder(sqlite_store, out, lab=lab, readings=bench_readings[0],
                                  protocol=SMALL_PROTOCOL)
    with sqlite_store.session() as s:
        assert s.get(CalibrationFile, (cal_id, "table_calibration.csv")).sha256 == SHA
    assert services.file_bytes(sqlite_store, SHA) == TABLE
    assert services.seal(sqlite_store, cal_id)


def test_the_run_names_the_uploaded_file(computed, sqlite_store, tmp_path):
    """The worker's run reads the upload under the name it was uploaded by ("RT-07 cal.csv",
    given by this test's form): results.json's table calibration source, the summary and the
    draft certificate name it, as ``gonio calibrate --table-calibration "RT-07 cal.csv"``
    would, and not the name the records keep the bytes under; the certificate rendered again
    from the stored result names it too, byte-identical to a second rendering."""
    from sqlalchemy import select

    from gonio.records.compute import render_folder, write_lab_toml

    _, cal_id = computed
    res = results_of(sqlite_store, cal_id)
    assert res["items"]["scale_factor"]["details"]["table_calibration"]["source"] == \
        "RT-07 cal.csv"
    with sqlite_store.session() as s:
        files = dict(s.execute(select(CalibrationFile.name, CalibrationFile.sha256).where(
            CalibrationFile.calibration_id == cal_id)).all())
    for name in ("summary.txt", "certificate.html"):
        text = services.file_bytes(sqlite_store, files[name]).decode("utf-8")
        assert "RT-07 cal.csv" in text and "table_calibration.csv" not in text, name
    lab = write_lab_toml(services.lab_details(sqlite_store, cal_id, final=False, redraft=True),
                         tmp_path / "lab.toml")
    outs = []
    for i in range(2):
        render_folder(services.file_bytes(sqlite_store, files["results.json"]),
                      tmp_path / f"r{i}", spec_key="ogam-draft", lab=lab)
        outs.append((tmp_path / f"r{i}" / "certificate.html").read_bytes())
    assert outs[0] == outs[1] and b"RT-07 cal.csv" in outs[0]


#: a file name a browser may send: markup, a quote and an ampersand (no path separator; the
#: test client percent-encodes a double quote in a multipart file name)
HOSTILE = "<img src=x onerror=alert(1)>&'RT-07.csv"


def test_page_shows_the_uploaded_name_escaped(app, sqlite_store, bench_readings):  # noqa: F811
    """The calibration page names the table calibration by the name it was uploaded under
    (services.table_calibration_name), HTML-escaped — a hostile name appears only escaped,
    never as markup — in its facts and in its list of files; the link serves the stored bytes
    (hashlib digest), offering the uploaded name only percent-encoded in the header."""
    import html as html_module
    from urllib.parse import quote

    tech = login(app, "tech")
    inst = bare_instrument(sqlite_store)
    register_table(sqlite_store, TABLE, HOSTILE)
    r = post(tech, inst, Path(bench_readings[0]).read_bytes(), TABLE, table_name=HOSTILE)
    assert r.status_code == 303, alert(r.text)
    cal_id = int(r.headers["location"].rsplit("/", 1)[1])
    with sqlite_store.session() as s:
        assert services.table_calibration_name(s, cal_id) == HOSTILE
    page = tech.get(f"/calibrations/{cal_id}").text
    assert "<img src=x" not in page
    fact = page[page.index('id="table-calibration"'):]
    fact = fact[:fact.index("</dd>")]
    assert "/files/table_calibration.csv" in fact
    shown = fact[fact.index('id="table-calibration-file">') + 28:fact.index("</a>")]
    assert html_module.unescape(shown) == HOSTILE and "<" not in shown, shown
    assert ">table_calibration.csv<" not in page          # not the storage name, anywhere
    listed = page[page.index("<h2>Files of the run</h2>"):]
    listed = listed[:listed.index("</p>")]
    assert "&lt;img src=x onerror=alert(1)&gt;&amp;" in listed and "RT-07.csv" in listed
    got = tech.get(f"/calibrations/{cal_id}/files/table_calibration.csv")
    assert got.status_code == 200 and hashlib.sha256(got.content).hexdigest() == SHA
    disp = got.headers["content-disposition"]
    assert f"filename*=UTF-8''DRAFT-{cal_id}-" + quote(HOSTILE, safe="") in disp
    assert "<" not in disp and "\n" not in disp


#: names that look like another when shown: a right-to-left override ("calib‮vsc.exe" is shown
#: as "calibexe.csv"), an isolate, a mark, a zero-width space, a C1 control
LOOKALIKE = ["calib\u202evsc.exe", "RT\u206607.csv", "RT-07\u200f.csv", "RT\u200b-07.csv",
             "RT-07\x85.csv"]


@pytest.mark.parametrize("name", LOOKALIKE, ids=["rlo", "isolate", "rlm", "zwsp", "c1"])
def test_lookalike_upload_name_refused(app, sqlite_store, bench_readings, name):  # noqa: F811
    """A table calibration named with an invisible or direction-changing character: its
    registration is refused with one line naming the code point, and its upload (so not in
    the register) comes back (400); nothing is queued."""
    tech = login(app, "tech")
    inst = bare_instrument(sqlite_store)
    bad = next(c for c in name if not (c.isascii() and c.isprintable()))
    with pytest.raises(GonioError) as e:
        register_table(sqlite_store, TABLE, name)
    assert f"U+{ord(bad):04X}" in str(e.value) and "\n" not in str(e.value), str(e.value)
    r = post(tech, inst, Path(bench_readings[0]).read_bytes(), TABLE, table_name=name)
    assert r.status_code == 400
    msg = alert(r.text)
    assert ("U+" in msg or "not in the register" in msg) and "\n" not in msg, msg
    assert n_calibrations(sqlite_store) == 0


@pytest.mark.parametrize("name", ["RT-07 cal.csv", "转台-07.csv"])
def test_download_names_agree(app, sqlite_store, bench_readings, name):  # noqa: F811
    """The draft's table calibration downloads as DRAFT-n-<uploaded name> in both
    ``filename=`` (outside ASCII letters, digits and ._-()+, and space: '_') and
    ``filename*=`` (the name whole, percent-encoded): the two agree."""
    from urllib.parse import quote, unquote

    tech = login(app, "tech")
    inst = bare_instrument(sqlite_store)
    register_table(sqlite_store, TABLE, name)
    r = post(tech, inst, Path(bench_readings[0]).read_bytes(), TABLE, table_name=name)
    assert r.status_code == 303, alert(r.text)
    cal_id = int(r.headers["location"].rsplit("/", 1)[1])
    disp = tech.get(f"/calibrations/{cal_id}/files/table_calibration.csv") \
        .headers["content-disposition"]
    plain = disp.split('filename="')[1].split('"')[0]
    whole = unquote(disp.split("filename*=UTF-8''")[1])
    assert whole == f"DRAFT-{cal_id}-{name}"
    assert plain == "".join(c if c.isascii() and (c.isalnum() or c in "._-()+, ") else "_"
                            for c in whole)
    assert disp.endswith(quote(whole, safe=""))
