"""Every file read for a calibration, named in the readings or given by an option
(``--thermal FILE``, ``--tilt FILE``), goes through the same identity and provenance checks;
a file of the instrument's data that states no serial is not accepted silently. From the
outside: the CLI's exit code, results.json and the certificate.
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import pytest

from gonio.cli import main
from gonio.pipeline.dispatch import INSTRUMENT_FILE_OPTIONS
from gonio.specs import get

ROOT = Path(__file__).resolve().parents[1]


def proceed_lab(path: Path, serial: str) -> Path:
    """The example laboratory file naming ``serial``, no limits, proceeding on a
    contradiction."""
    text = (ROOT / "protocols" / "lab-example.toml").read_text().split("[decision_rule]")[0]
    path.write_text(text.replace('serial = "RLG-0001"', f'serial = "{serial}"')
                    + '\n[identity]\non_mismatch = "proceed"\n')
    return path


def run(*args) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main([str(a) for a in args])
    return rc, err.getvalue()


def without(path: Path, dst: Path, *prefixes, replace: dict | None = None,
            unmark: bool = False) -> Path:
    """``path`` less its lines starting with ``prefixes``; ``unmark``: its values also without
    the bench's watermark (a laboratory's own recording, tests/own_readings.unmarked)."""
    from tests.own_readings import unmarked

    lines = [ln for ln in path.read_text().splitlines(keepends=True)
             if not ln.startswith(prefixes)]
    for k, v in (replace or {}).items():
        lines = [v if ln.startswith(k) else ln for ln in lines]
    dst.parent.mkdir(parents=True, exist_ok=True)
    dst.write_text(unmarked("".join(lines)) if unmark else "".join(lines))
    return dst


@pytest.fixture(scope="module")
def triad(tmp_path_factory):
    out = tmp_path_factory.mktemp("triad")
    assert main(["simulate", "--spec", "triad-alignment", "--seed", "3", "--out",
                 str(out / "T")]) == 0
    return out / "T"


@pytest.fixture(scope="module")
def optical(tmp_path_factory):
    out = tmp_path_factory.mktemp("optical")
    assert main(["simulate", "--spec", "ogam-draft", "--seed", "7", "--out",
                 str(out / "S")]) == 0
    tilt = out / "tilt.json"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["tilt-estimate", str(out / "S" / "readings.csv"), "--json"]) == 0
    tilt.write_text(buf.getvalue())
    return out / "S" / "readings.csv", tilt


def test_thermal_option_of_another_serial_is_refused(triad, tmp_path):
    rd = without(triad / "readings.csv", tmp_path / "t" / "readings.csv", "# thermal_readings:")
    other = without(triad / "thermal.csv", tmp_path / "other_thermal.csv",
                    replace={"# serial:": "# serial: TRIAD-0002\n"})
    rc, err = run("calibrate", rd, "--thermal", other, "--out", tmp_path / "o")
    assert rc == 2 and "TRIAD-0002" in err and "other_thermal.csv" in err
    assert not (tmp_path / "o").exists()
    # the laboratory proceeds: the contradiction is on the certificate
    lab = proceed_lab(tmp_path / "lab.toml", "TRIAD-0001")
    rc, err = run("calibrate", rd, "--thermal", other, "--lab", lab, "--out", tmp_path / "p")
    assert rc == 0, err
    res = json.loads((tmp_path / "p" / "results.json").read_text())
    found = [f["message"] for f in res["findings"] if f["code"] == "identity-mismatch"]
    assert found and "other_thermal.csv says" in found[0] and "TRIAD-0002" in found[0]
    assert "TRIAD-0002" in (tmp_path / "p" / "certificate.html").read_text()


def test_thermal_option_from_the_bench_marks_virtual(triad, tmp_path):
    rd = without(triad / "readings.csv", tmp_path / "t" / "readings.csv", "# thermal_readings:",
                 "# bench:", "# seed:", "# generator:", "# instrument:", unmark=True)
    assert main(["calibrate", str(rd), "--out", str(tmp_path / "plain")]) == 0
    plain = json.loads((tmp_path / "plain" / "results.json").read_text())
    assert plain["provenance"]["virtual"] is False       # nothing says bench: not virtual
    assert main(["calibrate", str(rd), "--thermal", str(triad / "thermal.csv"), "--out",
                 str(tmp_path / "o")]) == 0
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    assert res["provenance"]["virtual"] is True
    assert any(e.startswith("thermal.csv:") for e in res["provenance"]["evidence"])


def test_thermal_that_states_no_serial(triad, tmp_path):
    rd = without(triad / "readings.csv", tmp_path / "t" / "readings.csv", "# thermal_readings:")
    anon = without(triad / "thermal.csv", tmp_path / "anon.csv", "# serial:")
    rc, err = run("calibrate", rd, "--thermal", anon, "--out", tmp_path / "o")
    assert rc == 2 and "identity not stated in anon.csv" in err
    # named in the readings instead of given by the option: the same rule
    named = tmp_path / "n"
    named.mkdir()
    (named / "thermal.csv").write_text(anon.read_text())
    (named / "readings.csv").write_text((triad / "readings.csv").read_text())
    rc, err = run("calibrate", named / "readings.csv", "--out", tmp_path / "o2")
    assert rc == 2 and "identity not stated in thermal.csv" in err
    lab = proceed_lab(tmp_path / "lab.toml", "TRIAD-0001")
    rc, err = run("calibrate", rd, "--thermal", anon, "--lab", lab, "--out", tmp_path / "p")
    assert rc == 0, err
    res = json.loads((tmp_path / "p" / "results.json").read_text())
    assert [f for f in res["findings"] if "identity not stated in anon.csv" in f["message"]]


def test_tilt_option_identity(optical, tmp_path):
    readings, tilt = optical
    md = json.loads(tilt.read_text())["metadata"]
    assert md["serial"] == "RLG-0001" and md["bench"]
    assert main(["calibrate", str(readings), "--tilt", str(tilt), "--out",
                 str(tmp_path / "ok")]) == 0
    d = json.loads(tilt.read_text())
    other = tmp_path / "other.json"
    other.write_text(json.dumps({**d, "metadata": {**md, "serial": "RLG-0002"}}))
    rc, err = run("calibrate", readings, "--tilt", other, "--out", tmp_path / "o")
    assert rc == 2 and "RLG-0002" in err and "other.json" in err
    bare = tmp_path / "bare.json"
    bare.write_text(json.dumps({k: v for k, v in d.items() if k != "metadata"}))
    rc, err = run("calibrate", readings, "--tilt", bare, "--out", tmp_path / "o2")
    assert rc == 2 and "identity not stated in bare.json" in err
    # readings that do not say virtual, a tilt result from the bench: virtual
    plain = without(readings, tmp_path / "r" / "readings.csv", "# bench:", "# seed:",
                    "# generator:", "# instrument:", "# manufacturer:", "# table:",
                    "# operator:", unmark=True)
    assert main(["calibrate", str(plain), "--tilt", str(tilt), "--out",
                 str(tmp_path / "v")]) == 0
    res = json.loads((tmp_path / "v" / "results.json").read_text())
    assert res["provenance"]["virtual"] is True
    assert any(e.startswith("tilt.json:") for e in res["provenance"]["evidence"])


VIRTUAL_KEYS = ("bench", "seed", "noise", "generator", "instrument", "manufacturer",
                "model", "table", "operator")


def test_tilt_result_of_virtual_readings_stays_virtual(optical, tmp_path):
    """A tilt result whose metadata no longer say virtual (every such key deleted) still
    shows its source readings, the bench's: the calibration of plain readings with it is
    virtual. One that does not show its source, or whose source was edited to say
    non-virtual, is refused in one line naming it, exit 2, nothing written. A tilt result
    of readings stripped of their bench lines is virtual by their watermark."""
    readings, tilt = optical
    d = json.loads(tilt.read_text())
    assert d["source"]["virtual"] is True and d["source"]["file"] == "readings.csv"
    clean = {**d, "metadata": {k: v for k, v in d["metadata"].items()
                               if k not in VIRTUAL_KEYS}}
    assert clean["metadata"] == {"serial": "RLG-0001", "gyro_type": "rlg"}
    plain = without(readings, tmp_path / "r" / "readings.csv", "# bench:", "# seed:",
                    "# generator:", "# instrument:", "# manufacturer:", "# table:",
                    "# operator:", unmark=True)
    (tmp_path / "clean.json").write_text(json.dumps(clean))
    assert main(["calibrate", str(plain), "--tilt", str(tmp_path / "clean.json"), "--out",
                 str(tmp_path / "v")]) == 0
    res = json.loads((tmp_path / "v" / "results.json").read_text())
    assert res["provenance"]["virtual"] is True
    assert res["provenance"]["evidence"] == ["clean.json:source"]
    first = (tmp_path / "v" / "summary.txt").read_text().splitlines()[0]
    assert first.startswith("VIRTUAL BENCH") and "clean.json was computed from the virtual " \
        "bench's readings" in first and "metadata" not in first, first
    page = (tmp_path / "v" / "certificate.html").read_text(encoding="utf-8")
    assert "clean.json, used with the readings, was computed from the virtual bench" in page
    forged = {"nosource.json": {k: v for k, v in clean.items() if k != "source"},
              "edited.json": {**clean, "source": {**clean["source"], "virtual": False,
                                                  "evidence": []}},
              "moved.json": {**clean, "tilt_deg": clean["tilt_deg"] / 2}}
    for name, doc in forged.items():
        (tmp_path / name).write_text(json.dumps(doc))
        before = (tmp_path / name).read_bytes()
        rc, err = run("calibrate", plain, "--tilt", tmp_path / name, "--out", tmp_path / "o")
        assert rc == 2 and err.count("\n") == 1 and name in err, (name, err)
        assert "Traceback" not in err and not (tmp_path / "o").exists()
        assert (tmp_path / name).read_bytes() == before
    # the bench's readings without their header's marks: the source is virtual by its values
    marked = without(readings, tmp_path / "m" / "readings.csv", "# bench:", "# seed:",
                     "# generator:", "# instrument:", "# manufacturer:", "# table:",
                     "# operator:")
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["tilt-estimate", str(marked), "--json"]) == 0
    src = json.loads(buf.getvalue())["source"]
    assert src["virtual"] is True and src["evidence"] == ["watermark"]
    # and the laboratory's own readings give a non-virtual source
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["tilt-estimate", str(plain), "--json"]) == 0
    assert json.loads(buf.getvalue())["source"]["virtual"] is False


def test_the_demo_static_record_states_the_serial(shared_demo, tmp_path):
    """The optical demo's static record (named in its readings) carries the readings'
    identity, so the demo's folder calibrates again under the unstated-identity rule
    (``gonio demo --spec ogam-draft``'s folder, shared: calibrate writes elsewhere)."""
    d = shared_demo("ogam-draft")
    head = (d / "static_record.csv").read_text().splitlines()[:12]
    assert "# serial: RLG-0001" in head
    assert main(["calibrate", str(d / "readings.csv"), "--out",
                 str(tmp_path / "again")]) == 0


@pytest.mark.parametrize("key", ["jjf1535-2015", "iec62047-20"])
def test_rate_specs_read_no_instrument_files(key):
    """The rate-gyro specifications name no files in their readings and take no option
    that gives one: nothing reaches the identity check but the readings themselves."""
    spec = get(key)
    assert spec.named_inputs is None
    assert not set(INSTRUMENT_FILE_OPTIONS) & set(spec.calibrate_options)
