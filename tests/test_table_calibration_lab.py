"""The rotary table's calibration as the laboratory's equipment knowledge: the laboratory
file's ``[table_calibration]`` (gonio/pipeline/equipment.py; docs/formats.md, "Laboratory
file") names the file relative to itself with its SHA-256, id and dates; ``gonio calibrate
--lab`` uses it, refuses a changed file, an expired calibration and a different explicit
``--table-calibration`` in one line (exit 2), nothing written.

Checked against truths outside gonio: the file's SHA-256 by hashlib; the results with the
laboratory's file are byte-identical to those with the same file given by
``--table-calibration`` (the documented, already tested path), and differ from a run without."""

from __future__ import annotations

import hashlib
import json
from dataclasses import replace

import numpy as np
import pytest

from gonio.cli import main
from gonio.formats.toml import read_toml
from gonio.resources import resolve
from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.specs.ogam_draft.readings import write_readings
from gonio.specs.ogam_draft.study import table_positions_deg

LAB = """[laboratory]
name = "L"
address = "A"

[certificate]
number = "C-1"
date_of_calibration = "{day}"

[customer]
name = "K"

[signatory]
approved_by = "P"
"""


def table_section(file: str, sha: str, due: str = "2027-06-01",
                  done: str = "2026-06-01") -> str:
    return (f'\n[table_calibration]\nfile = "{file}"\nsha256 = "{sha}"\nid = "TC-117"\n'
            f'calibrated_on = "{done}"\ndue_on = "{due}"\n')


@pytest.fixture(scope="module")
def bench_files(tmp_path_factory):
    """A short built-in session's readings (5 Hz) and a table calibration at every position
    the protocol uses (a 0.03″ first harmonic), in one folder: (folder, readings, csv, sha)."""
    d = tmp_path_factory.mktemp("tablab")
    p = parse_protocol(read_toml(resolve("ogam-draft", "protocol")),
                       resolve("ogam-draft", "protocol"))
    res = run_session(p, replace(load_bench("rlg"), sample_rate_hz=5.0), seed=4)
    rd = d / "readings.csv"
    write_readings(res.readings, rd, dict(res.metadata))
    x = table_positions_deg(p)
    f = d / "tc.csv"
    f.write_text("# table certificate TC-117\ntable_deg,error_arcsec,u_arcsec\n" + "".join(
        f"{a:g},{0.03 * np.cos(np.radians(a)):.6f},0.02\n" for a in x), encoding="utf-8")
    return d, rd, f, hashlib.sha256(f.read_bytes()).hexdigest()


def _lab(d, text, name="lab.toml"):
    p = d / name
    p.write_text(text, encoding="utf-8")
    return p


def _one_line_exit_2(capsys, argv, out, *words):
    rc = main(argv)
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.count("\n") == 1, err
    for w in words:
        assert w in err, err
    assert not out.exists()           # refused before the work: nothing written
    return err


def test_lab_file_table_calibration_used(bench_files, tmp_path, capsys):
    """The laboratory's file (named relative to the laboratory file, from another working
    folder) gives results.json byte-identical to the same file given explicitly, with the
    hashlib SHA-256 recorded and the manifest listing it; both given with the same content
    is the same again; without it K is another number (the correction is real)."""
    d, rd, f, sha = bench_files
    sub = tmp_path / "lab"
    sub.mkdir()
    (sub / "tables").mkdir()
    (sub / "tables" / "tc.csv").write_bytes(f.read_bytes())
    lab = _lab(sub, LAB.format(day="2026-11-16") + table_section("tables/tc.csv", sha))
    plain = _lab(tmp_path, LAB.format(day="2026-11-16"), "plain.toml")
    outs = {}
    for name, extra in (("lab", ["--lab", str(lab)]),
                        ("explicit", ["--lab", str(plain), "--table-calibration", str(f)]),
                        ("both", ["--lab", str(lab), "--table-calibration", str(f)]),
                        ("none", ["--lab", str(plain)])):
        out = tmp_path / name
        assert main(["calibrate", str(rd), "--out", str(out), *extra]) == 0
        capsys.readouterr()
        outs[name] = (out / "results.json").read_bytes()
    assert outs["lab"] == outs["explicit"] == outs["both"]
    assert outs["lab"] != outs["none"]
    d_lab = json.loads(outs["lab"])
    assert d_lab["items"]["scale_factor"]["details"]["table_calibration"]["sha256"] == sha
    assert "table_calibration" not in json.loads(outs["none"])["items"]["scale_factor"][
        "details"]
    man = json.loads((tmp_path / "lab" / "gonio-manifest.json").read_text(encoding="utf-8"))
    assert man["option_files"]["table_calibration"] == {"file": "tc.csv", "sha256": sha}


def test_changed_file_refused(bench_files, tmp_path, capsys):
    """One byte of the calibration file changed after the laboratory recorded its SHA-256:
    one line naming the laboratory file, the key and both digests, exit 2."""
    d, rd, f, sha = bench_files
    (tmp_path / "tc.csv").write_bytes(f.read_bytes().replace(b"0.02\n", b"0.03\n", 1))
    lab = _lab(tmp_path, LAB.format(day="2026-11-16") + table_section("tc.csv", sha))
    now = hashlib.sha256((tmp_path / "tc.csv").read_bytes()).hexdigest()
    _one_line_exit_2(capsys, ["calibrate", str(rd), "--lab", str(lab), "--out",
                              str(tmp_path / "o")], tmp_path / "o",
                     str(lab), "table_calibration.sha256", sha, now)


@pytest.mark.parametrize("day, due, done, key", [
    ("2027-06-02", "2027-06-01", "2026-06-01", "table_calibration.due_on"),    # a day late
    ("2026-05-31", "2027-06-01", "2026-06-01", "table_calibration.calibrated_on"),  # before
])
def test_outside_its_validity_refused(bench_files, tmp_path, capsys, day, due, done, key):
    """The calibration's date after the table calibration's due date (or before it was made):
    one line, exit 2; the due date itself is still valid (next test)."""
    d, rd, f, sha = bench_files
    (tmp_path / "tc.csv").write_bytes(f.read_bytes())
    lab = _lab(tmp_path, LAB.format(day=day) + table_section("tc.csv", sha, due, done))
    _one_line_exit_2(capsys, ["calibrate", str(rd), "--lab", str(lab), "--out",
                              str(tmp_path / "o")], tmp_path / "o", key, day, "TC-117")


def test_due_date_checked_against_the_readings_date(bench_files, tmp_path):
    """The readings' own # date: is checked too (a laboratory date within the validity does
    not hide a measurement after it); on the due day itself the calibration is valid."""
    from gonio.errors import GonioError
    from gonio.formats.lab import load_lab
    from gonio.pipeline.equipment import lab_table_calibration

    d, rd, f, sha = bench_files
    (tmp_path / "tc.csv").write_bytes(f.read_bytes())
    lab = _lab(tmp_path, LAB.format(day="2027-06-01") + table_section("tc.csv", sha))
    lab_d = load_lab(lab)
    assert lab_table_calibration(lab_d, lab, {"date": "2027-06-01"}) == str(tmp_path / "tc.csv")
    with pytest.raises(GonioError, match=r"expired on the calibration's date 2027-06-02 "
                                         r"\(the readings \(# date:\)\)"):
        lab_table_calibration(lab_d, lab, {"date": "2027-06-02T09:00:00"})
    lab_d["certificate"]["date_of_calibration"] = ""
    with pytest.raises(GonioError, match="cannot be checked"):
        lab_table_calibration(lab_d, lab, {})


def test_both_given_different_refused(bench_files, tmp_path, capsys):
    """--table-calibration naming another content than the laboratory file's: refused in one
    line naming both, never one silently in place of the other."""
    d, rd, f, sha = bench_files
    (tmp_path / "tc.csv").write_bytes(f.read_bytes())
    other = tmp_path / "other.csv"
    other.write_bytes(f.read_bytes() + b"15,0.0,0.02\n")
    lab = _lab(tmp_path, LAB.format(day="2026-11-16") + table_section("tc.csv", sha))
    _one_line_exit_2(capsys, ["calibrate", str(rd), "--lab", str(lab), "--table-calibration",
                              str(other), "--out", str(tmp_path / "o")], tmp_path / "o",
                     "other.csv", "tc.csv", "give one of them")


@pytest.mark.parametrize("line, words", [
    ('sha256 = "ABC"', "table_calibration.sha256"),
    ('due_on = "soon"', "table_calibration.due_on"),
    ('colour = "red"', "table_calibration.colour"),
])
def test_bad_section_refused(tmp_path, line, words):
    """The section is validated with the file (a short or upper-case digest, a due date that
    is no date, an unknown key): one GonioError naming the key."""
    from gonio.errors import GonioError
    from gonio.formats.lab import load_lab

    base = {"sha256": '"' + "0" * 64 + '"', "due_on": '"2027-01-01"'}
    key = line.split(" = ")[0]
    body = {**base, key: line.split(" = ")[1]}
    text = LAB.format(day="2026-01-01") + '\n[table_calibration]\nfile = "t.csv"\n' + "".join(
        f"{k} = {v}\n" for k, v in body.items())
    with pytest.raises(GonioError, match=words.replace(".", r"\.")):
        load_lab(_lab(tmp_path, text))


def test_dcc_zh_table_notes_valid(bench_files, tmp_path, capsys, dcc_schema):
    """A zh DCC of a calibration with the laboratory's table calibration: schema-valid (the
    carried DCC 3.3.0 XSD), and K's and E's descriptions (and K_l's, C_v's, C_g's where the
    table corrected them) each have a lang="zh" content written
    in Chinese (no English words of the English note left in it) that names the file and its
    SHA-256 (hashlib), beside the English one."""
    import re

    from lxml import etree

    d, rd, f, sha = bench_files
    (tmp_path / "tc.csv").write_bytes(f.read_bytes())
    lab = _lab(tmp_path, LAB.format(day="2026-11-16") + table_section("tc.csv", sha))
    out = tmp_path / "o"
    assert main(["calibrate", str(rd), "--lab", str(lab), "--out", str(out), "--dcc",
                 "--lang", "zh"]) == 0
    capsys.readouterr()
    doc = (out / "certificate.dcc.xml").read_bytes()
    errors = list(dcc_schema.iter_errors(doc.decode("utf-8")))
    assert not errors, errors[:3]
    ns = "{https://ptb.de/dcc}"
    found = {}
    for desc in etree.fromstring(doc).iter(f"{ns}description"):
        texts = {c.get("lang"): c.text for c in desc.iter(f"{ns}content")}
        en = texts.get("en") or ""
        if "table calibration tc.csv" in en:
            found[en.split(" ", 1)[0]] = texts
    assert {"K", "E"} <= set(found), list(found)     # and K_l, C_v, C_g where corrected
    for texts in found.values():
        zh = texts["zh"]
        assert sha in texts["en"] and sha in zh and "tc.csv" in zh and "转台校准" in zh
        words = set(re.findall(r"[A-Za-z]{4,}", zh)) - {"SHA"}
        assert not words & {"corrected", "table", "calibration", "beyond", "draft", "read",
                            "carries", "uncertainty", "place"}, words
