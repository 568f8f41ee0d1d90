"""Every list that shows a calibration marks the virtual bench's in the certificate banner's
words (the calibrations list, the dashboard's queues, the instrument's and the standard's
calibrations, the issued certificates, the calibrations CSV), and a laboratory's own readings
are not marked; each stored readings file is read once for it, not on every page."""

from __future__ import annotations

import csv
import datetime as dt
import io
import re

from gonio.records import queries, services, worker
from gonio.records.importer import record_output_folder
from gonio.report.i18n import labels
from tests.own_readings import own_text

from .conftest import SMALL_PROTOCOL, make_people
from .test_web_numbers import web_client

TAG = '<span class="virtual-tag">' + labels("en")["virtual"] + "</span>"


def _row(page: str, href: str) -> str:
    """The table row of ``page`` that links ``href`` first."""
    rows = [r for r in re.findall(r"<tr>.*?</tr>", page, re.S)
            if re.search(r'<td><a href="' + re.escape(href) + '"', r)]
    assert len(rows) == 1, (href, rows)
    return rows[0]


def test_lists_mark_the_virtual_bench(sqlite_store, bench_readings, computed_folder,
                                      monkeypatch):
    store = sqlite_store
    tech = make_people(store)["tech"]
    std = services.add_standard(store, tech, name="table", identifier="T-1",
                                due_on=dt.date.today() + dt.timedelta(days=300))
    virt = record_output_folder(store, computed_folder, actor=tech, readings=bench_readings[0],
                                protocol=str(SMALL_PROTOCOL), standard_identifiers=["T-1"],
                                temperature_c=20.1, humidity_pct=45)
    inst_id = services.calibration(store, virt).instrument_id
    # a laboratory's own file: the same readings without the bench's metadata lines
    text = bench_readings[1].read_text("utf-8")
    own = own_text(text)
    assert own != text
    sha, _ = services.store_file(store, io.BytesIO(own.encode("utf-8")))
    lab = services.create_calibration(store, tech, instrument_id=inst_id, readings_sha256=sha,
                                      readings_name="readings.csv", standard_ids=[std.id],
                                      protocol_sha256=services.store_file(
                                          store, open(SMALL_PROTOCOL, "rb"))[0],
                                      temperature_c=20.1, humidity_pct=45).id
    queries._VIRTUAL_READINGS.clear()
    reads = []
    import gonio.formats.provenance as prov        # virtual_readings imports it when called
    orig = prov.readings_provenance
    monkeypatch.setattr(prov, "readings_provenance", lambda p: reads.append(p) or orig(p))

    web = web_client(store)
    page = web.get("/calibrations").text
    assert TAG in _row(page, f"/calibrations/{virt}")
    assert "virtual-tag" not in _row(page, f"/calibrations/{lab}")
    assert len(reads) == 2                                  # one per stored readings file
    for url in ("/calibrations", f"/instruments/{inst_id}", f"/standards/{std.id}"):
        page = web.get(url).text
        assert TAG in _row(page, f"/calibrations/{virt}"), url
        assert "virtual-tag" not in _row(page, f"/calibrations/{lab}"), url
    assert len(reads) == 2                                  # kept: not read again
    assert TAG in _row(web.get("/").text, f"/calibrations/{virt}")   # awaiting review
    got = list(csv.reader(io.StringIO(web.get("/export/calibrations.csv").text)))
    assert got[0][-1] == "virtual_bench"
    assert {r[0]: r[-1] for r in got[1:]} == {str(virt): "yes", str(lab): ""}
    # issued: the certificates list marks it
    services.review(store, services.user(store, "rev"), virt, accept=True)
    services.approve(store, services.user(store, "rev2"), virt)
    assert worker.execute(store, services.claim_next(store).id), \
        services.calibration(store, virt).error
    assert services.calibration(store, virt).status == "issued"
    assert web.get("/certificates").text.count(TAG) == 1
    got = list(csv.reader(io.StringIO(web.get("/export/certificates.csv").text)))
    assert got[0][-1] == "virtual_bench" and [r[-1] for r in got[1:]] == ["yes"]
    assert len(reads) == 2


def test_virtual_readings_of_stored_csv_and_parquet_files(tmp_path):
    """The mark is read from a stored file under its SHA-256 (no suffix): a CSV file's
    header in place, a Parquet stream's key-value metadata told by its first bytes; each
    answer kept per blob folder; a missing file is not marked and not kept."""
    import hashlib
    import types

    from gonio.formats.streams import write_stream
    from gonio.records import blobs

    store = types.SimpleNamespace(blob_root=tmp_path / "blobs")
    queries._VIRTUAL_READINGS.clear()
    csv_lab = b"# serial: X-1\n# generator: LabVIEW 2021\ntest,series\nscale_factor,1\n"
    csv_virt = b"# serial: X-1\n# generator: gonio 0.1.0\ntest,series\nscale_factor,1\n"
    got = {}
    for name, body in (("csv lab", csv_lab), ("csv virtual", csv_virt)):
        got[name] = queries.virtual_readings(store, blobs.put_bytes(store.blob_root, body))
    for name, md in (("parquet lab", {"serial": "X-1"}),
                     ("parquet virtual", {"serial": "X-1", "bench": "rlg-typical"})):
        path = write_stream(tmp_path / f"{name.replace(' ', '-')}.parquet", [0.0, 0.01],
                            [0, 5], metadata=md)
        assert path.read_bytes()[:4] == b"PAR1"
        sha, _ = blobs.put_file(store.blob_root, path)
        got[name] = queries.virtual_readings(store, sha)
    missing = hashlib.sha256(csv_virt + b"x").hexdigest()          # never stored
    got["missing"] = queries.virtual_readings(store, missing)
    assert got == {"csv lab": False, "csv virtual": True, "parquet lab": False,
                   "parquet virtual": True, "missing": False}
    assert len(queries._VIRTUAL_READINGS) == 4                     # the missing one not kept
    assert queries.virtual_readings(store, None) is False
