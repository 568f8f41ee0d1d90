"""The records' workflow on SQLite and PostgreSQL: ISO/IEC 17025 7.8 states, roles on the
server, certificate numbers, frozen certificates and audit trail (database triggers),
amendments, failures and recovery, history, backup and restore, import."""

from __future__ import annotations

import datetime as dt
import io
import json
import shutil
import threading
from pathlib import Path

import pytest
from sqlalchemy import func, select, text

from gonio.errors import GonioError
from gonio.records import services, worker
from gonio.records.models import (AuditEvent, Base, Calibration, Certificate, ResultItem,
                                  CertificateCounter, Instrument)

SMALL_PROTOCOL = __import__("pathlib").Path(__file__).resolve().parents[1] / "data" / \
    "small-protocol.toml"


def fake_pipeline(folder):
    """The pipeline's real output of the session fixture copied into ``out`` (the
    computation itself is exercised by the browser and kill tests), its results.json naming
    the readings it was given (as the pipeline's does: the seal checks it)."""
    def run(readings, out, *, spec_key, protocol=None, lab=None):
        shutil.copytree(folder, out)
        of_readings(out, Path(readings))
        if lab is not None:
            decide_as_the_pipeline(out / "results.json", spec_key, lab)
        return sorted(p.name for p in out.iterdir())
    return run


def of_readings(out: Path, readings: Path) -> Path:
    """The copied result folder ``out`` made the result of ``readings``: results.json's
    ``source.sha256`` theirs (a run's result names the readings it was computed from)."""
    import hashlib

    doc = json.loads((out / "results.json").read_text(encoding="utf-8"))
    sha = hashlib.sha256(readings.read_bytes()).hexdigest()
    if doc["source"]["sha256"] != sha:          # the folder's own readings: as it is
        doc["source"]["sha256"] = sha
        (out / "results.json").write_text(json.dumps(doc), encoding="utf-8")
    return out


def store_run_as_computed(store, cal_id: int, folder: Path) -> None:
    """:func:`services.store_run` of the session's result ``folder`` for calibration
    ``cal_id``, whose stored readings may be others: a temporary copy made their result
    (:func:`of_readings`), as a run of them would name them."""
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "out"
        shutil.copytree(folder, out)
        sha = services.calibration(store, cal_id).readings_sha256
        doc = json.loads((out / "results.json").read_text(encoding="utf-8"))
        if doc["source"]["sha256"] != sha:
            doc["source"]["sha256"] = sha
            (out / "results.json").write_text(json.dumps(doc), encoding="utf-8")
        services.store_run(store, cal_id, out)


def decide_as_the_pipeline(path, spec_key, lab):
    """The conformity decisions the pipeline makes on the laboratory details ``lab`` (the
    pipeline's own function), written into the copied results.json."""
    from gonio.pipeline.dispatch import decide_conformity, load_lab_file
    from gonio.result.model import Result
    from gonio.specs import get

    spec = get(spec_key)
    lab_d = load_lab_file(lab, spec)
    if lab_d.get("specification_limits"):
        result = decide_conformity(Result.from_json(json.loads(path.read_text())), lab_d)
        path.write_text(json.dumps(spec.renderer().results_json(result, lab_d)))


def setup_instrument(store, people, limits=()):
    tech = people["tech"]
    cust = services.add_customer(store, tech, "Example Navigation Co.", "2 Sample Street")
    inst = services.register_instrument(store, tech, customer_id=cust.id, serial="RLG-0001",
                                        spec_key="ogam-draft", kind="RLG goniometer",
                                        manufacturer="Example Gyro Works", model="RLG-GM-1",
                                        limits=list(limits))
    std = services.add_standard(store, tech, name="rotary table", identifier="RT-07",
                                due_on=dt.date.today() + dt.timedelta(days=300))
    return inst, std


def new_calibration(store, people, inst, std, readings, day=None):
    """A queued calibration of ``readings``; given a ``day``, of that day's measurement (the
    file with a ``# note:`` line naming the day and its first count moved by the day: one
    measurement is one calibration, and a file differing in its metadata alone is the same
    measurement)."""
    data = Path(readings).read_bytes()
    if day is not None:
        lines = data.decode("utf-8").splitlines(keepends=True)
        head = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
        col = lines[head].strip().split(",").index("gyro_counts")
        cells = lines[head + 1].rstrip("\n").split(",")
        cells[col] = str(int(cells[col]) + dt.date.fromisoformat(str(day)).toordinal() % 997 + 1)
        lines[head + 1] = ",".join(cells) + "\n"
        data = f"# note: measured on {day}\n".encode("utf-8") + "".join(lines).encode("utf-8")
    sha, _ = services.store_file(store, io.BytesIO(data))
    psha, _ = services.store_file(store, open(SMALL_PROTOCOL, "rb"))
    return services.create_calibration(store, people["tech"], instrument_id=inst.id,
                                       readings_sha256=sha, readings_name="readings.csv",
                                       protocol_sha256=psha, standard_ids=[std.id],
                                       temperature_c=20.1, humidity_pct=45,
                                       performed_on=day)


def run_worker(store, monkeypatch, folder):
    monkeypatch.setattr(worker, "calibrate_folder", fake_pipeline(folder))
    cal = services.claim_next(store)
    assert cal is not None
    assert worker.execute(store, cal.id), services.calibration(store, cal.id).error
    return services.calibration(store, cal.id)


def test_workflow_roles_numbers_and_frozen_certificates(store, people, computed_folder,
                                                        bench_readings, monkeypatch):
    inst, std = setup_instrument(store, people)
    cal = new_calibration(store, people, inst, std, bench_readings[0])
    assert cal.status == "queued"
    cal = run_worker(store, monkeypatch, computed_folder)
    assert cal.status == "computed"
    # the items are results.json's, read independently here
    res = json.loads((computed_folder / "results.json").read_text())
    with store.session() as s:
        K = s.scalar(select(ResultItem).where(ResultItem.calibration_id == cal.id,
                                              ResultItem.key == "scale_factor"))
    assert K.value == res["items"]["scale_factor"]["value"]
    assert K.U == res["items"]["scale_factor"]["uncertainty"]["U"]
    # roles and the second person, on the server
    with pytest.raises(GonioError, match="reviewer role"):
        services.review(store, people["tech"], cal.id, accept=True)
    with pytest.raises(GonioError, match="that is computed"):
        services.approve(store, people["rev"], cal.id)           # not reviewed yet
    services.review(store, people["rev"], cal.id, accept=True, comment="checked")
    with pytest.raises(GonioError, match="reviewer role"):
        services.approve(store, people["tech"], cal.id)
    services.approve(store, people["rev2"], cal.id)
    year = dt.datetime.now(dt.timezone.utc).year
    assert services.calibration(store, cal.id).pending_number == f"GC-{year}-0001"
    cal = run_worker(store, monkeypatch, computed_folder)
    assert cal.status == "issued"
    with store.session() as s:
        cert = s.scalar(select(Certificate).where(Certificate.calibration_id == cal.id))
    assert cert.number == f"GC-{year}-0001" and cert.replaces_id is None
    assert services.file_bytes(store, cert.pdf_sha256).startswith(b"%PDF")
    # frozen: the database itself refuses to change or delete an issued certificate or
    # an audit event
    for sql in ("UPDATE certificates SET number = 'X'", "DELETE FROM certificates",
                "UPDATE audit_events SET action = 'x'", "DELETE FROM audit_events"):
        with store.writing() as s, pytest.raises(Exception, match="frozen|append-only"):
            s.execute(text(sql))
            s.commit()
    # an amendment is a new certificate naming the old one
    services.amend(store, people["rev"], cert.id, "customer address corrected")
    assert services.calibration(store, cal.id).status == "amending"
    services.approve(store, people["rev2"], cal.id)      # another person approves it
    cal = run_worker(store, monkeypatch, computed_folder)
    with store.session() as s:
        certs = s.scalars(select(Certificate).order_by(Certificate.id)).all()
    assert [c.number for c in certs] == [f"GC-{year}-0001", f"GC-{year}-0002"]
    assert certs[1].replaces_id == certs[0].id and "address" in certs[1].reason
    with pytest.raises(GonioError, match="replaced already"):
        services.amend(store, people["rev"], cert.id, "again")
    with store.session() as s:
        actions = [a for (a,) in s.execute(select(AuditEvent.action).order_by(AuditEvent.id))]
    for a in ("create", "claim", "computed", "review", "approve", "issue", "amend"):
        assert a in actions


def test_creator_may_not_review_own_calibration(store, people, computed_folder,
                                                bench_readings, monkeypatch):
    inst, std = setup_instrument(store, people)
    sha, _ = services.store_file(store, open(bench_readings[0], "rb"))
    cal = services.create_calibration(store, people["admin"], instrument_id=inst.id,
                                      readings_sha256=sha, standard_ids=[std.id],
                                      temperature_c=20, humidity_pct=45)
    run_worker(store, monkeypatch, computed_folder)
    with pytest.raises(GonioError, match="second person"):
        services.review(store, people["admin"], cal.id, accept=True)
    with pytest.raises(GonioError, match="why"):
        services.review(store, people["rev"], cal.id, accept=False)
    assert services.review(store, people["rev"], cal.id, accept=False,
                           comment="wrong protocol").status == "rejected"


def test_overdue_standard_refused(store, people, bench_readings):
    inst, _ = setup_instrument(store, people)
    old = services.add_standard(store, people["tech"], name="autocollimator", identifier="AC-1",
                                due_on="2020-01-01", out_of_service="sent for repair")
    sha, _ = services.store_file(store, open(bench_readings[0], "rb"))
    with pytest.raises(GonioError, match="AC-1 was due"):
        services.create_calibration(store, people["tech"], instrument_id=inst.id,
                                    readings_sha256=sha, standard_ids=[old.id],
                                    temperature_c=20, humidity_pct=45)
    with store.session() as s:
        assert s.scalar(select(func.count()).select_from(Calibration)) == 0


def test_numbers_unique_and_gapless_under_concurrency(store, people):
    year = 2031
    got, errors = [], []

    def reserve():
        try:
            with store.writing() as s:
                got.append(services._reserve_number(s, year))
                s.commit()
        except Exception as exc:     # pragma: no cover - reported below
            errors.append(exc)

    threads = [threading.Thread(target=reserve) for _ in range(12)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert sorted(got) == [f"GC-2031-{i:04d}" for i in range(1, 13)]
    with store.session() as s:
        assert s.get(CertificateCounter, year).last == 12


def test_dead_worker_marked_failed_then_retried(store, people, bench_readings,
                                                computed_folder, monkeypatch):
    inst, std = setup_instrument(store, people)
    cal = new_calibration(store, people, inst, std, bench_readings[0])
    services.claim_next(store)
    services.attach(store, cal.id, 999_999_999)         # a process that does not exist
    assert services.recover(store) == [cal.id]
    cal = services.calibration(store, cal.id)
    assert cal.status == "failed" and "interrupted" in cal.error
    with store.session() as s:
        assert s.scalar(select(func.count()).select_from(Certificate)) == 0
    services.retry(store, people["tech"], cal.id)
    assert run_worker(store, monkeypatch, computed_folder).status == "computed"


def test_limits_edited_after_review_reach_no_issued_certificate(store, people, computed_folder,
                                                                bench_readings, monkeypatch):
    """The issue renders the reviewed result with its own conformity decisions (none here):
    a limit set on the instrument after the review makes no decision nobody reviewed."""
    inst, std = setup_instrument(store, people)
    cal = new_calibration(store, people, inst, std, bench_readings[0])
    run_worker(store, monkeypatch, computed_folder)
    services.review(store, people["rev"], cal.id, accept=True)
    services.approve(store, people["rev2"], cal.id)
    services.update_instrument(store, people["tech"], inst.id,
                               limits=[{"item": "scale_factor", "mpe": 1e9}])

    def no_pipeline(*args, **kwargs):
        raise AssertionError("the issue ran the calibration pipeline")
    monkeypatch.setattr(worker, "calibrate_folder", no_pipeline)
    services.claim_next(store)
    assert worker.execute(store, cal.id), services.calibration(store, cal.id).error
    with store.session() as s:
        cert = s.scalars(select(Certificate)).one()
    page = services.file_bytes(store, cert.html_sha256).decode("utf-8")
    dcc = services.file_bytes(store, cert.dcc_sha256).decode("utf-8")
    assert "Statement of conformity" not in page and "decision-rule-" not in dcc
    assert cert.results_sha256 == services.calibration(store, cal.id).results_sha256


def test_history_and_interval_with_limits(store, people, computed_folder, bench_readings,
                                          monkeypatch):
    inst, std = setup_instrument(store, people, limits=[{"item": "angle_deviation",
                                                        "mpe": 0.5}])
    for day in ("2024-01-10", "2025-01-10"):
        cal = new_calibration(store, people, inst, std, bench_readings[0], day=day)
        run_worker(store, monkeypatch, computed_folder)
        services.review(store, people["rev"], cal.id, accept=True)
        services.approve(store, people["rev2"], cal.id)
        run_worker(store, monkeypatch, computed_folder)
    hist = services.history(store, inst.id)
    assert [r["date"].isoformat() for r in hist["angle_deviation"]] == ["2024-01-10",
                                                                       "2025-01-10"]
    p = services.propose_interval(store, inst.id)
    # two calibrations a year apart within ±0.5″: the first starts the 12 months, the second
    # (after more than half of them) lengthens them once (before: ×1.25 for each, 18 months)
    assert p.method.startswith("simple response") and p.months == 15
    assert p.detail.startswith("2 calibration(s)")
    # a third calibration computed but never issued is no evidence for the interval
    # (before: proposals came from calibrations that were never issued)
    new_calibration(store, people, inst, std, bench_readings[0], day="2025-06-10")
    run_worker(store, monkeypatch, computed_folder)
    assert len(services.history(store, inst.id)["angle_deviation"]) == 3
    assert services.propose_interval(store, inst.id).detail.startswith("2 calibration(s)")
    # an issued one whose amendment is asked for was issued all the same: it still counts
    with store.session() as s:
        newest = s.scalar(select(Certificate).order_by(Certificate.id.desc()).limit(1))
    assert services.amend(store, people["rev"], newest.id, "typo").status == "amending"
    assert len(services.history(store, inst.id)["angle_deviation"]) == 3
    assert services.propose_interval(store, inst.id).detail.startswith("2 calibration(s)")
    assert services.instrument_limits(services.calibration(store, 1).instrument) == {
        "angle_deviation": (-0.5, 0.5)}


def test_history_figure_draws_every_issued_calibration_as_issued(store, people, computed_folder,
                                                                 bench_readings, monkeypatch):
    """Every calibration with a certificate is drawn as issued, an amended one (its
    certificate replaced by an amendment, or an amendment asked for) marked as amended;
    the figure's classes are checked against the certificates table (before: only the
    state 'issued' was drawn as issued, an amendment asked for as 'not issued')."""
    import xml.etree.ElementTree as ET

    from gonio.report.history_figure import history_svg

    inst, std = setup_instrument(store, people)
    for day in ("2024-01-10", "2024-07-10", "2025-01-10", "2025-06-10"):
        cal = new_calibration(store, people, inst, std, bench_readings[0], day=day)
        run_worker(store, monkeypatch, computed_folder)
        if day != "2025-06-10":                  # the last is computed, never issued
            services.review(store, people["rev"], cal.id, accept=True)
            services.approve(store, people["rev2"], cal.id)
            run_worker(store, monkeypatch, computed_folder)
    with store.session() as s:
        first, _, third = s.scalars(select(Certificate).order_by(Certificate.id)).all()
    services.amend(store, people["rev"], first.id, "customer address corrected")
    services.approve(store, people["rev2"], first.calibration_id)
    run_worker(store, monkeypatch, computed_folder)         # its amendment issued
    services.amend(store, people["rev"], third.id, "typo")  # its amendment asked for
    with store.session() as s:
        certs = {cid: n for cid, n in s.execute(
            select(Certificate.calibration_id, func.count(Certificate.id))
            .group_by(Certificate.calibration_id))}
    assert certs == {1: 2, 2: 1, 3: 1}
    ns = {"s": "http://www.w3.org/2000/svg"}
    root = ET.fromstring(history_svg(services.history(store, inst.id)))
    panel = root.find("s:g[@class='panel']", ns)
    got = [c.get("class") for c in panel.findall("s:circle[@cx]", ns)
           if c.get("class") in ("issued", "amended", "other")]
    status = {c: services.calibration(store, c).status for c in (1, 2, 3, 4)}
    assert status == {1: "issued", 2: "issued", 3: "amending", 4: "computed"}
    want = ["amended" if certs.get(c, 0) > 1 or (c in certs and status[c] != "issued")
            else "issued" if c in certs else "other" for c in (1, 2, 3, 4)]
    assert got == want == ["amended", "issued", "amended", "other"]
    legend = [t.text for t in panel.findall("s:text[@class='legend']", ns)]
    assert sorted(legend) == ["amended", "issued", "not issued"]


def plain(v):
    """A value as text, so that each database's own return types compare."""
    if isinstance(v, bool):
        return str(int(v))
    if isinstance(v, dt.datetime):
        return v.isoformat(" ")
    return v if v is None else str(v)


def test_backup_restore_round_trip(store, people, computed_folder, bench_readings, monkeypatch,
                                   tmp_path):
    from gonio.records.backup import backup, restore
    from gonio.records.db import open_store

    inst, std = setup_instrument(store, people)
    new_calibration(store, people, inst, std, bench_readings[0])
    run_worker(store, monkeypatch, computed_folder)
    archive = tmp_path / "records.zip"
    counts = backup(store, archive)
    assert counts["calibrations"] == 1 and counts["files"] >= 6
    target = open_store(None, tmp_path / "restored")     # always restored into SQLite
    try:
        assert restore(target, archive) == {k: v for k, v in counts.items() if v}
        for table in Base.metadata.sorted_tables:
            with store.session() as a, target.session() as b:
                got = [[tuple(map(plain, r)) for r in x.execute(select(table).order_by(
                    *table.primary_key))] for x in (a, b)]
            if table.name == "audit_events":     # the restore is the restored trail's last
                assert got[1][-1][4:6] == ("restore", "records"), got[1][-1]
                got[1] = got[1][:-1]
            assert got[0] == got[1], table.name
        cal = services.calibration(target, 1)
        assert services.file_bytes(target, cal.readings_sha256) == bench_readings[0].read_bytes()
        with pytest.raises(GonioError, match="holds records already"):
            restore(target, archive)
    finally:
        target.close()


def test_import_output_folder(store, people, computed_folder, bench_readings, tmp_path):
    from gonio.records.importer import import_output_folder

    with pytest.raises(GonioError, match="no readings file matching"):
        import_output_folder(store, computed_folder, readings=bench_readings[1])
    # computed with a protocol file that is not built in: named, not silently the default
    with pytest.raises(GonioError, match="give the file with --protocol"):
        import_output_folder(store, computed_folder, readings=bench_readings[0])
    other = tmp_path / "other.toml"
    other.write_text(SMALL_PROTOCOL.read_text() + "\n# edited\n")
    with pytest.raises(GonioError, match="not the one results.json was computed with"):
        import_output_folder(store, computed_folder, readings=bench_readings[0],
                             protocol=other)
    cid = import_output_folder(store, computed_folder, readings=bench_readings[0],
                               protocol=SMALL_PROTOCOL)
    cal = services.calibration(store, cid)
    assert cal.status == "computed" and cal.instrument.serial == "RLG-0001"
    # the very protocol file is stored: the recomputation uses it
    assert services.file_bytes(store, cal.protocol_sha256) == SMALL_PROTOCOL.read_bytes()
    assert services.history(store, cal.instrument_id)["scale_factor"][0]["value"] == \
        json.loads((computed_folder / "results.json").read_text())["items"]["scale_factor"]["value"]


def test_import_refuses_a_results_file_changed_after_gonio_wrote_it(store, people,
                                                                    computed_folder,
                                                                    bench_readings, tmp_path):
    """A results.json edited after gonio wrote it (K changed by 2 ppm): refused, its SHA-256
    not the manifest's, nothing recorded; the untouched folder imports with K as computed.
    Before, any K typed into results.json was imported, reviewed and issued."""
    folder = tmp_path / "run"
    shutil.copytree(computed_folder, folder)
    res = folder / "results.json"
    original = res.read_bytes()
    doc = json.loads(original)
    k_true = doc["items"]["scale_factor"]["value"]
    doc["items"]["scale_factor"]["value"] = k_true * (1 + 2e-6)
    res.write_text(json.dumps(doc, indent=2), encoding="utf-8")
    with pytest.raises(GonioError, match="results.json was changed after gonio wrote it"):
        import_output_folder_of(store, folder, bench_readings, people)
    (folder / "gonio-manifest.json").unlink()
    (folder / "gonio-manifest.json").write_text("[]", encoding="utf-8")
    with pytest.raises(GonioError, match="unreadable manifest"):
        import_output_folder_of(store, folder, bench_readings, people)
    with store.session() as s:
        assert s.query(Calibration).count() == 0
    shutil.rmtree(folder)
    shutil.copytree(computed_folder, folder)
    cid = import_output_folder_of(store, folder, bench_readings, people)
    stored = json.loads(services.file_bytes(store, services.calibration(store, cid)
                                            .results_sha256))
    assert stored["items"]["scale_factor"]["value"] == k_true and stored == json.loads(original)


def import_output_folder_of(store, folder, bench_readings, people):
    from gonio.records.importer import import_output_folder
    return import_output_folder(store, folder, readings=bench_readings[0],
                                protocol=SMALL_PROTOCOL, actor=people["tech"])


def test_blob_store_checks_digest(sqlite_store):
    from gonio.records import blobs

    h, n = services.store_file(sqlite_store, io.BytesIO(b"readings"))
    assert services.store_file(sqlite_store, io.BytesIO(b"readings")) == (h, n)
    path = blobs.blob_path(sqlite_store.blob_root, h)
    path.chmod(0o644)
    path.write_bytes(b"changed")
    with pytest.raises(GonioError, match="does not match"):
        services.file_bytes(sqlite_store, h)
    with pytest.raises(GonioError, match="not a SHA-256"):
        blobs.blob_path(sqlite_store.blob_root, "../../etc/passwd")
    with pytest.raises(GonioError, match="larger than the limit"):
        services.store_file(sqlite_store, io.BytesIO(b"x" * 2000), limit_bytes=1000)



def _drawn_history(store, user_id: int, limits: list, n: int, step_days: int, seed: int) -> int:
    """One instrument with ``n`` calibrations of three items drawn at random (states drawn
    too: issued, computed, amending, failed; some issued rows without a value), written as
    rows; its id."""
    import random

    from sqlalchemy import insert

    from gonio.records import blobs
    from gonio.records.models import Blob, Customer, Instrument

    rng = random.Random(seed)
    sha = blobs.put_bytes(store.blob_root, b"drawn")
    with store.writing() as s:
        if s.get(Blob, sha) is None:
            s.add(Blob(sha256=sha, size=5))
        cust = Customer(name=f"C{seed}", address="")
        s.add(cust)
        s.flush()
        inst = Instrument(customer_id=cust.id, kind="gyro", manufacturer="W", model="M",
                          serial=f"S{seed}", spec_key="ogam-draft",
                          limits_json=json.dumps(limits))
        s.add(inst)
        s.flush()
        for c in range(n):
            status = rng.choice(["issued", "issued", "computed", "amending", "failed"])
            cal = Calibration(instrument_id=inst.id, spec_key="ogam-draft",
                              readings_sha256=sha, readings_name="r.csv", status=status,
                              performed_on=dt.date(2016, 1, 1) + dt.timedelta(
                                  days=step_days * c + rng.randrange(20)),
                              created_by_id=user_id, results_sha256=sha)
            s.add(cal)
            s.flush()
            s.execute(insert(ResultItem), [
                {"calibration_id": cal.id, "key": key, "title": key, "clause": "7",
                 "unit": "arcsec", "measured": True, "k": 2.0, "U": 0.05,
                 "value": None if rng.random() < 0.1 else rng.gauss(0.1 * c, 0.2)}
                for key in ("angle_deviation", "repeatability", "zero_stability")])
            if status in ("issued", "amending"):
                s.add(Certificate(number=f"N-{seed}-{c}", calibration_id=cal.id,
                                  issued_by_id=user_id, html_sha256=sha, pdf_sha256=sha,
                                  results_sha256=sha))
        s.commit()
        return inst.id


@pytest.mark.parametrize("limits, n, step_days", [
    ([{"item": "angle_deviation", "mpe": 3.0}, {"item": "repeatability", "upper": 2.5}], 12,
     200),                                                     # drift to the limit
    ([{"item": "angle_deviation", "mpe": 0.3}], 6, 20),        # staircase, short span
    ([{"item": "nothing_measured", "mpe": 1.0}], 5, 300),      # default: no limited item
    ([], 4, 300)])                                             # default: no limits
def test_instrument_page_proposal_selected_in_the_database(store, people, limits, n,
                                                           step_days):
    """The instrument page's proposal and count, selected in the database, equal those
    computed in Python from the whole history (:func:`services.history`) for the same rows."""
    inst_id = _drawn_history(store, people["tech"].id, limits, n, step_days, seed=n)
    hist = services.history(store, inst_id)
    got = services.propose_interval(store, inst_id)
    assert got == services.propose_interval(store, inst_id, hist)
    assert services.history_points(store, inst_id) == max(map(len, hist.values()))
    assert got.method.split()[0] == {12: "drift-to-limit", 6: "simple", 5: "specification",
                                     4: "specification"}[n]
    if n == 6:      # the unlimited items' counts reach the staircase's note
        assert "drift not extrapolated" in got.detail


def test_instrument_page_proposal_looks_certificates_up_by_index(sqlite_store):
    """The proposal's queries (every instrument page) find each calibration's certificate
    through ix_certificates_calibration_id: SQLite's own query plan (EXPLAIN QUERY PLAN) of
    every statement they send names no full scan of ``certificates``, whose size grows with
    the records (``id IN (SELECT calibration_id FROM certificates)`` scanned all of it),
    and each one that reads certificates searches it by that index."""
    from sqlalchemy import event

    from tests.records.conftest import make_people

    people = make_people(sqlite_store)
    for seed in (1, 2, 3):            # other instruments' certificates in the table too
        inst_id = _drawn_history(sqlite_store, people["tech"].id, [
            {"item": "angle_deviation", "mpe": 3.0}], 12, 200, seed=seed)
    sent = []

    def keep(conn, cursor, statement, params, context, many):
        if statement.lstrip().upper().startswith("SELECT"):
            sent.append((statement, params))
    event.listen(sqlite_store.engine, "before_cursor_execute", keep)
    try:
        services.propose_interval(sqlite_store, inst_id)
    finally:
        event.remove(sqlite_store.engine, "before_cursor_execute", keep)
    with_certs = [(q, p) for q, p in sent if "FROM certificates" in q]
    assert len(with_certs) >= 2, sent                # the count, the first date, the rows
    with sqlite_store.engine.connect() as conn:
        for statement, params in with_certs:
            plan = [row[-1] for row in conn.exec_driver_sql("EXPLAIN QUERY PLAN " + statement,
                                                            params).all()]
            assert not [d for d in plan if d.startswith("SCAN certificates")], plan
            assert any(d.startswith("SEARCH certificates USING")
                       and "ix_certificates_calibration_id" in d for d in plan), plan


@pytest.mark.parametrize("limit", [{"lower": -0.4, "upper": 0.6}, {"upper": 0.5}])
def test_stored_limits_of_an_extreme_of_magnitudes_are_symmetric(store, people, limit):
    """An instrument's stored limits refuse an asymmetric limit for an item its specification
    declares an extreme of magnitudes (the optical E, SPEC.magnitude_extremes), at
    registration and at an edit, in one line naming the entry; a symmetric one is stored."""
    inst, _ = setup_instrument(store, people, limits=[{"item": "angle_deviation", "mpe": 0.5}])
    with pytest.raises(GonioError) as exc:
        services.register_instrument(store, people["tech"], customer_id=inst.customer_id,
                                     serial="RLG-0002", spec_key="ogam-draft",
                                     limits=[{"item": "angle_deviation", **limit}])
    assert str(exc.value).startswith("key limits[0]: angle_deviation is an extreme")
    assert "symmetric" in str(exc.value) and "\n" not in str(exc.value)
    with pytest.raises(GonioError, match=r"key limits\[1\]: angle_deviation .* symmetric"):
        services.update_instrument(store, people["tech"], inst.id, limits=[
            {"item": "repeatability", "upper": 0.3}, {"item": "angle_deviation", **limit}])
    services.update_instrument(store, people["tech"], inst.id, limits=[
        {"item": "repeatability", "upper": 0.3},
        {"item": "angle_deviation", "lower": -0.5, "upper": 0.5}])
    with store.session() as s:
        stored = json.loads(s.get(Instrument, inst.id).limits_json)
    assert stored[1]["lower"] == -0.5 and stored[1]["upper"] == 0.5
