"""``gonio db import`` computes the result again from what the records store (docs/records.md,
*What is imported is what the readings give*): a folder whose results.json AND manifest were
rewritten consistently (a value edited, the manifest's SHA-256 updated) is refused, naming the
first difference, exit 2, nothing recorded; a genuine folder of every specification imports,
with every file its calibration read stored; a file the readings name that is missing is
refused in one line.

Truths from outside the importer: the values written into the doctored results.json here, the
folders' own bytes (hashlib), the number of calibrations in the database."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from gonio.errors import GonioError
from gonio.records import services
from gonio.records.db import open_store
from gonio.records.models import Calibration, CalibrationFile

from .conftest import SMALL_PROTOCOL, make_people

pytestmark = pytest.mark.real_pipeline      # the recomputation itself, each time

SPECS = ("ogam-draft", "jjf1535-2015", "iec62047-20", "triad-alignment")
#: the file each demo's readings name as part of their data (none for the rate specifications)
NAMED = {"ogam-draft": "static_record.csv", "triad-alignment": "thermal.csv"}


@pytest.fixture(scope="module", params=SPECS)
def demo(request, shared_demo):
    """``gonio demo --spec KEY`` (the session's shared folder, read only: a test copies it
    before changing a file; and its specification key)."""
    return shared_demo(request.param), request.param


def calibrations(store) -> int:
    with store.session() as s:
        return s.query(Calibration).count()


def doctor(folder: Path, edit) -> str:
    """results.json edited by ``edit(doc)`` (returns what it wrote) and the manifest rewritten
    with the edited file's hashlib SHA-256, as one who knows the format would."""
    res = folder / "results.json"
    doc = json.loads(res.read_text(encoding="utf-8"))
    what = edit(doc)
    res.write_text(json.dumps(doc, indent=2), encoding="utf-8")
    man_path = folder / "gonio-manifest.json"
    man = json.loads(man_path.read_text(encoding="utf-8"))
    man["files"]["results.json"] = hashlib.sha256(res.read_bytes()).hexdigest()
    man_path.write_text(json.dumps(man), encoding="utf-8")
    return what


def first_measured(doc: dict) -> str:
    return next(k for k, it in doc["items"].items()
                if it.get("measured") and isinstance(it.get("value"), float))


def rewrite_manifest(folder: Path, change) -> None:
    man_path = folder / "gonio-manifest.json"
    man = json.loads(man_path.read_text(encoding="utf-8"))
    change(man)
    man_path.write_text(json.dumps(man), encoding="utf-8")


def test_a_doctored_result_with_its_manifest_is_refused_and_the_genuine_folder_imports(
        demo, tmp_path):
    """Each specification's demo: a value changed by 1e-6 relative with the manifest updated is
    refused naming the item, its value here and the recomputed one (the folder's own), exit-2
    one line, nothing recorded; the genuine folder imports, the stored result byte for byte in
    its values the folder's, and every file its readings name kept with it (the bytes
    hashlib reads in the folder)."""
    from gonio.records.importer import import_output_folder

    src, key = demo
    folder = tmp_path / "doctored"
    shutil.copytree(src, folder)
    original = json.loads((src / "results.json").read_text(encoding="utf-8"))
    item = first_measured(original)
    true_value = original["items"][item]["value"]

    def edit(doc):
        doc["items"][item]["value"] = true_value * (1 + 1e-6)
        return doc["items"][item]["value"]

    edited = doctor(folder, edit)
    store = open_store(None, tmp_path / "data")
    try:
        with pytest.raises(GonioError) as e:
            import_output_folder(store, folder)
        msg = str(e.value)
        assert "\n" not in msg and f"items.{item}.value: " in msg, msg
        assert f"{edited!r} here" in msg and f"{true_value!r} recomputed" in msg, msg
        assert calibrations(store) == 0
        cid = import_output_folder(store, src)
        cal = services.calibration(store, cid)
        assert json.loads(services.file_bytes(store, cal.results_sha256)) == original
        with store.session() as s:
            files = {f.name: f.sha256 for f in s.query(CalibrationFile).filter_by(
                calibration_id=cid)}
        named = NAMED.get(key)
        want = {f"input/{named}": hashlib.sha256((src / named).read_bytes()).hexdigest()} \
            if named else {}
        assert {n: v for n, v in files.items() if n.startswith("input/")} == want
        services.seal(store, cid)                   # the stored inputs are sealed and verify
    finally:
        store.close()


@pytest.mark.parametrize("named", sorted(NAMED.values()))
def test_a_missing_named_file_is_refused_in_one_line(named, tmp_path, capsys):
    """A file the readings name as part of their data (the triad's thermal readings, the
    optical static record) missing beside them: one line naming it, exit 2, nothing recorded
    (the manifest of a ``gonio calibrate`` folder records its SHA-256 as ``named_inputs``).
    A missing readings file is refused in one line too."""
    from gonio.cli import main

    key = next(k for k, v in NAMED.items() if v == named)
    sim, folder = tmp_path / "sim", tmp_path / "run"
    simulated_with_named_file(key, sim)
    proto = ["--protocol", str(SMALL_PROTOCOL)] if key == "ogam-draft" else []
    assert main(["calibrate", str(sim / "readings.csv"), "--out", str(folder), *proto]) == 0
    capsys.readouterr()     # the calibration's own warnings (e.g. its findings): not the import's
    man = json.loads((folder / "gonio-manifest.json").read_text(encoding="utf-8"))
    assert man["named_inputs"] == {named: hashlib.sha256((sim / named).read_bytes()).hexdigest()}
    (sim / named).unlink()
    data = tmp_path / "data"
    assert main(["db", "import", str(folder), "--readings", str(sim / "readings.csv"),
                 "--data", str(data), *proto]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gonio: error: ") and err.count("\n") == 1, err
    assert f"{named}, which the readings name as part of their data, is missing" in err, err
    assert main(["db", "import", str(folder), "--data", str(data), *proto]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no readings file matching" in err, err
    store = open_store(None, data)
    try:
        assert calibrations(store) == 0
    finally:
        store.close()


def simulated_with_named_file(key: str, folder: Path) -> None:
    """Readings that name a file, without a demo's cost: the triad's bench (seed 1), or the
    small optical protocol with its static record file."""
    if key == "triad-alignment":
        from gonio.specs.triad_alignment.simulate import simulate
        simulate("triad-alignment", "mems-triad", 1, folder)
    else:
        small_optical_with_static_record(folder)


def small_optical_with_static_record(folder: Path) -> None:
    """The small protocol's readings (seed 1) with their static record file, as the optical
    demo writes them (:func:`gonio.specs.ogam_draft.outputs._with_static_record_file`)."""
    from gonio.atomic import output_set
    from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
    from gonio.specs.ogam_draft.outputs import _with_static_record_file
    from gonio.specs.ogam_draft.protocol import load_protocol

    session = run_session(load_protocol(SMALL_PROTOCOL), load_bench("rlg"), seed=1)
    assert session.static_record is not None
    with output_set(folder) as stage:
        write_session(_with_static_record_file(session, stage), folder)


def test_the_options_a_folder_was_computed_with_are_the_recomputations(tmp_path, capsys):
    """A triad folder computed with --monte-carlo 40 (the manifest records it) imports; its
    manifest rewritten to say 0 draws, or an option the records cannot give, or computed with
    --thermal FILE (an option file they do not keep), is refused in one line, nothing
    recorded."""
    from gonio.cli import main
    from gonio.specs.triad_alignment.simulate import simulate

    sim = tmp_path / "sim"
    simulate("triad-alignment", "mems-triad", 2, sim)
    folder = tmp_path / "run"
    assert main(["calibrate", str(sim / "readings.csv"), "--monte-carlo", "40",
                 "--out", str(folder)]) == 0
    man = json.loads((folder / "gonio-manifest.json").read_text(encoding="utf-8"))
    assert man["calibrate_options"] == {"monte_carlo_trials": 40}
    assert man["named_inputs"] == {
        "thermal.csv": hashlib.sha256((sim / "thermal.csv").read_bytes()).hexdigest()}
    data = tmp_path / "data"
    args = ["db", "import", str(folder), "--readings", str(sim / "readings.csv"),
            "--data", str(data)]
    for change, expect in (
            (lambda m: m["calibrate_options"].update(monte_carlo_trials=0),
             "results.json is not what its readings give (extra.alignment.u_monte_carlo"),
            (lambda m: m["calibrate_options"].update(seed=7),
             "the manifest records the option 'seed' = 7, which a calibration cannot be "
             "computed again with"),
            (lambda m: m.update(option_files={"thermal": {"file": "t.csv", "sha256": "0"}}),
             "results.json was computed with --thermal t.csv (SHA-256 0…), which is not "
             "here")):
        shutil.copy(folder / "gonio-manifest.json", tmp_path / "man.json")
        rewrite_manifest(folder, change)
        assert main(args) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and expect in err, err
        shutil.copy(tmp_path / "man.json", folder / "gonio-manifest.json")
    store = open_store(None, data)
    try:
        assert calibrations(store) == 0
    finally:
        store.close()
    assert main(args) == 0


def test_an_optical_run_with_a_lab_file_and_a_table_calibration(bench_readings, tmp_path):
    """``gonio calibrate --lab LAB --table-calibration TC`` (the small protocol): the folder
    imports with both (the recomputation reads the stored laboratory file and table
    calibration); the same folder with K edited and the manifest rewritten is refused naming
    K, nothing recorded."""
    from gonio.cli import main
    from gonio.records.importer import import_output_folder

    from .test_records_table_calibration import TABLE, register_table
    from .test_web_lab_file import limits_toml

    tc = tmp_path / "tc.csv"
    tc.write_bytes(TABLE)
    lab = tmp_path / "lab.toml"
    lab.write_text(limits_toml("scale_factor"), encoding="utf-8")
    folder = tmp_path / "run"
    assert main(["calibrate", str(bench_readings[0]), "--protocol", str(SMALL_PROTOCOL),
                 "--lab", str(lab), "--table-calibration", str(tc), "--out", str(folder)]) == 0
    good = tmp_path / "good"
    shutil.copytree(folder, good)
    k = json.loads((folder / "results.json").read_text())["items"]["scale_factor"]["value"]
    doctor(folder, lambda d: d["items"]["scale_factor"].update(value=k + 0.01))
    store = open_store(None, tmp_path / "data")
    try:
        tech = make_people(store)["tech"]
        services.add_standard(store, tech, name="rotary table", identifier="RT-07",
                              due_on="2099-01-01")          # the laboratory file's standard
        register_table(store, TABLE, "tc.csv")    # a correcting table calibration is registered
        kw = dict(readings=bench_readings[0], protocol=SMALL_PROTOCOL, lab=lab,
                  table_calibration=tc, actor=tech)
        with pytest.raises(GonioError, match=r"items\.scale_factor\.value: "):
            import_output_folder(store, folder, **kw)
        assert calibrations(store) == 0
        cid = import_output_folder(store, good, **kw)
        cal = services.calibration(store, cid)
        assert cal.lab_sha256 == hashlib.sha256(lab.read_bytes()).hexdigest()
        assert json.loads(services.file_bytes(store, cal.results_sha256))["items"][
            "scale_factor"]["value"] == k
    finally:
        store.close()


def test_a_static_record_file_reads_back_bit_for_bit(tmp_path):
    """The static record file (docs/formats.md#static-record-file) holds the counter and the
    nominal scale factor: read back, the angles are the division the bench made, bit for bit
    (checked with numpy on awkward floats), so a calibration from the file analyses the very
    samples it analysed from memory; a damaged file is one line naming its line."""
    from gonio.specs.ogam_draft.static_record import format_static_record, read_static_record

    rng = np.random.default_rng(11)
    t = np.cumsum(rng.uniform(1e-4, 3e-3, 500))
    c = np.round(np.cumsum(rng.normal(0, 40, 500)))
    c[::7] += rng.uniform(-0.5, 0.5, len(c[::7]))       # a counter that is not quantised too
    k = 76434.87 / 3
    p = tmp_path / "static_record.csv"
    p.write_text(format_static_record(t, c, nominal_scale_factor_counts_per_deg=k,
                                      source="test"), encoding="utf-8")
    rec = read_static_record(p)
    assert np.array_equal(rec.time_s, t) and np.array_equal(rec.angle_deg, c / k)
    assert rec.source == "static_record.csv: test"
    lines = p.read_text(encoding="utf-8").splitlines()
    lines[10] = "0.5,abc"
    p.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(GonioError, match=r"static_record\.csv:11: not one number pair"):
        read_static_record(p)


def test_the_static_record_file_gives_the_result_the_session_gave(tmp_path):
    """The small protocol calibrated with the session's static record in memory and from the
    file its readings name: every item's value and uncertainty the same (the noise analysis
    of the same samples), only the record's source text differs."""
    from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
    from gonio.specs.ogam_draft.calibration import calibrate
    from gonio.specs.ogam_draft.protocol import load_protocol

    folder = tmp_path / "run"
    small_optical_with_static_record(folder)
    from_file = calibrate(folder / "readings.csv", SMALL_PROTOCOL)
    session = run_session(load_protocol(SMALL_PROTOCOL), load_bench("rlg"), seed=1)
    plain = tmp_path / "plain"
    write_session(session, plain)
    in_memory = calibrate(plain / "readings.csv", SMALL_PROTOCOL,
                          static_record=session.static_record)
    a, b = from_file.to_json(), in_memory.to_json()
    assert a["items"].keys() == b["items"].keys()
    for key in a["items"]:
        assert a["items"][key]["value"] == b["items"][key]["value"], key
        assert a["items"][key]["uncertainty"] == b["items"][key]["uncertainty"], key
    noise = a["items"]["zero_stability"]["details"]
    assert "static_record.csv: virtual bench, 7.3 block" in json.dumps(noise)
