"""The lists and the CSV exports mark a calibration as the virtual bench's by its stored
result too (its provenance holds the evidence of the files the readings name: a triad's
``thermal.csv`` with its ``# bench:`` lines), not by its readings alone — as the
calibration's own page does. Before, readings that showed no evidence left the row unmarked
while the page and the certificate said VIRTUAL."""
from __future__ import annotations

import json

from gonio.formats.provenance import result_provenance
from gonio.records import blobs
from gonio.records.queries import virtual_calibration, virtual_readings


def test_a_virtual_result_marks_a_row_whose_readings_show_nothing(store, tmp_path):
    plain = b"# serial: X-1\ntest,time_s,output\nbias,0,1.0\nbias,1,1.5\n"
    r_sha = blobs.put_bytes(store.blob_root, plain)
    assert not virtual_readings(store, r_sha)
    doc = {"spec": "triad-alignment", "metadata": {"serial": "X-1"}, "items": {},
           "extra": {}, "provenance": {"virtual": True,
                                       "evidence": ["thermal.csv: bench mems-triad"]}}
    if not result_provenance(doc)["virtual"]:       # the stored result's own reading of it
        doc["metadata"]["bench"] = "mems-triad"
    assert result_provenance(doc)["virtual"]
    res_sha = blobs.put_bytes(store.blob_root, json.dumps(doc).encode())
    assert virtual_calibration(store, r_sha, res_sha)
    clean = dict(doc, provenance={"virtual": False, "evidence": []},
                 metadata={"serial": "X-1"})
    assert not result_provenance(clean)["virtual"]
    clean_sha = blobs.put_bytes(store.blob_root, json.dumps(clean).encode())
    assert not virtual_calibration(store, r_sha, clean_sha)
