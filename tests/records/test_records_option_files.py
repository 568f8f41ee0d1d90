"""A calibration computed with a file named by an option (``gonio calibrate --tilt FILE``; the
triad's ``--thermal FILE`` takes the same path) goes into the records with that file: stored
content-addressed with the calibration (``option/tilt/NAME``, its SHA-256 the manifest's
``option_files``), read by the import's recomputation under the name the run read it by, so the
recomputed result is the folder's; a missing or changed file is refused naming it, nothing
recorded (docs/records.md, *Every file the calibration reads is stored*). Before, every such
run was refused at import ("an input the records do not keep").

Through the command line (``gonio db import``, ``gonio calibrate --record``), on SQLite and
PostgreSQL. The truths: the tilt file's bytes and their hashlib digest, written here; the
tilt it states (ψ + U95) named in results.json's budget as the run read it."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest

from gonio.cli import main
from gonio.records import services
from gonio.records.models import CalibrationFile

from .conftest import SMALL_PROTOCOL
from .test_records_record_refused import _where
from .test_web_lab_file import n_calibrations

#: a tilt result states the instrument it was measured on (a file of the instrument's data
#: that states no serial is refused: docs/formats.md, "Identity not stated")
#: and shows the readings it was computed from, under its check (docs/formats.md, "Derived
#: results"): here a laboratory's readings of one line, written only to be shown
def _tilt_bytes() -> bytes:
    import tempfile

    from gonio.formats.provenance import result_source
    with tempfile.TemporaryDirectory() as d:
        readings = Path(d) / "readings.csv"
        readings.write_text("# serial: RLG-0001\ntest,time_s\n")
        return json.dumps(result_source(readings, {"tilt_deg": 0.02, "U95_tilt_deg": 0.01,
                                                   "metadata": {"serial": "RLG-0001"}})).encode()


TILT = _tilt_bytes()
NAME = "tilt estimate.json"                     # the user's name, with a space
KEPT = f"option/tilt/{NAME}"
SHA = hashlib.sha256(TILT).hexdigest()


@pytest.fixture(scope="module")
def tilt_run(bench_readings, tmp_path_factory):
    """``gonio calibrate READINGS --tilt 'tilt estimate.json'`` into a folder (the tilt file
    kept elsewhere): (folder, readings, tilt file). Only read by the tests."""
    root = tmp_path_factory.mktemp("tiltrun")
    (root / "elsewhere").mkdir()
    tilt = root / "elsewhere" / NAME
    tilt.write_bytes(TILT)
    out = root / "run"
    assert main(["calibrate", str(bench_readings[0]), "--protocol", str(SMALL_PROTOCOL),
                 "--tilt", str(tilt), "--out", str(out)]) == 0
    return out, Path(bench_readings[0]), tilt


def _one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("gonio: error: ") and err.count("\n") == 1, err
    return err


def test_the_run_read_the_tilt_file(tilt_run):
    """The premise, from outside: the manifest records the file by name and hashlib digest,
    and the budget names the tilt it states (0.02° + 0.01°) from that file."""
    out, _, _ = tilt_run
    man = json.loads((out / "gonio-manifest.json").read_text(encoding="utf-8"))
    assert man["option_files"]["tilt"] == {"file": NAME, "sha256": SHA}
    text = (out / "results.json").read_text(encoding="utf-8")
    assert f"U95 0.01°, {NAME})" in text


def test_import_keeps_the_tilt_file(store, tilt_run, tmp_path, capsys):
    """Without the file (not in the folder, not beside the readings), then with other bytes:
    exit 2, one line naming it, nothing recorded. With it: recorded, the file kept under its
    name with the hashlib digest, the seal holds, and the worker's copy for a run again is
    the same bytes under the same name."""
    out, readings, tilt = tilt_run
    args = ["db", "import", str(out), "--readings", str(readings), "--protocol",
            str(SMALL_PROTOCOL), *_where(store)]
    other = tmp_path / NAME
    other.write_bytes(TILT.replace(b"0.02", b"0.03"))
    capsys.readouterr()
    for extra, expect in (([], f"results.json was computed with --tilt {NAME} (SHA-256 "
                                f"{SHA[:16]}…), which is not here"),
                          (["--option-file", f"tilt={other}"],
                           f"not the {SHA[:16]}… the run read as --tilt {NAME}")):
        assert main(args + extra) == 2
        err = _one_line(capsys)
        assert expect in err, err
    assert n_calibrations(store) == 0
    assert main(args + ["--option-file", f"tilt={tilt}"]) == 0
    with store.session() as s:
        kept = s.get(CalibrationFile, (1, KEPT))
    assert kept is not None and kept.sha256 == SHA
    assert services.file_bytes(store, SHA) == TILT
    assert services.seal(store, 1)
    again = services.write_option_files(store, 1, tmp_path / "work")
    assert again == {"tilt": tmp_path / "work" / "option" / "tilt" / NAME}
    assert again["tilt"].read_bytes() == TILT


def test_calibrate_record_keeps_the_tilt_file(bench_readings, tmp_path, monkeypatch):
    """``gonio calibrate --tilt FILE --record``: recorded (before: refused, the certificate
    left behind), the file kept with its digest."""
    from gonio.records.db import open_store

    monkeypatch.delenv("GONIO_USER", raising=False)
    tilt = tmp_path / NAME
    tilt.write_bytes(TILT)
    data = tmp_path / "data"
    assert main(["calibrate", str(bench_readings[1]), "--protocol", str(SMALL_PROTOCOL),
                 "--tilt", str(tilt), "--out", str(tmp_path / "cal"), "--record",
                 "--data", str(data)]) == 0
    st = open_store(None, data)
    try:
        with st.session() as s:
            assert s.get(CalibrationFile, (1, KEPT)).sha256 == SHA
        assert services.seal(st, 1)
    finally:
        st.close()


@pytest.mark.parametrize("record", [{"protocol": {"file": "p.toml", "sha256": "0"}},
                                    {"tilt": {"file": "../t.json", "sha256": "0"}},
                                    {"thermal": {"file": "t.csv", "sha256": "0"}},
                                    {"tilt": "t.json"}],
                         ids=["protocol", "outside", "other-spec", "not-an-object"])
def test_a_manifest_naming_no_option_file_to_keep_refused(record, tmp_path):
    """A manifest whose option_files names what no run of the specification reads by an option
    (the protocol, a path outside the folder, another specification's option, no file) is
    refused in one line naming the manifest, before anything is read or computed."""
    from gonio.errors import GonioError
    from gonio.records.importer import option_inputs
    from gonio.specs import get

    with pytest.raises(GonioError) as exc:
        option_inputs(get("ogam-draft"), {"option_files": record}, tmp_path / "results.json",
                      tmp_path / "readings.csv")
    assert exc.value.file == str(tmp_path / "gonio-manifest.json")
    assert "cannot be computed again with" in exc.value.message and "\n" not in str(exc.value)
