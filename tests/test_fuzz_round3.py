"""Hostile round 3 (issue 26): what was added since rounds 1 and 2, through what a user does.

Folders are made with ``gonio simulate`` (one per file family, once per module) and damaged
copies written into the test's own temporary folder. Each case checks what a user gets: an
exit code 0 or 2 with one line naming file, line, column or key; inputs byte-unchanged; and
what reaches the result — a reading that is missing, mislabelled or misspelt is refused or
stated (a finding), never silently absorbed into a number that looks right.
"""

from __future__ import annotations

import hashlib
import json
import warnings
from pathlib import Path

import pytest

from gonio.cli import main
from gonio.errors import GonioError
from gonio.formats.rate_readings import parse_rate_readings
from gonio.specs.ogam_draft.readings import read_readings
from gonio.specs.ogam_draft.protocol import load_protocol
from gonio.resources import builtin_names, protocols_dir, resolve
from gonio.specs.ogam_draft.screen import screen

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "data" / "small-protocol.toml"
CASES: list[str] = []


def count(name: str) -> None:
    CASES.append(name)


def sha(p: Path) -> str:
    return hashlib.sha256(p.read_bytes()).hexdigest()


def cli(argv, capsys, expect: int) -> str:
    rc = main([str(a) for a in argv])
    cap = capsys.readouterr()
    assert rc == expect, (argv, rc, cap.err[-2000:])
    if expect == 2:
        lines = cap.err.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in cap.err, cap.err
        return lines[0]
    return cap.err


# ------------------------------------------------------------------ the folders, once

@pytest.fixture(scope="module")
def sims(tmp_path_factory):
    """A small optical session (the small protocol) and a JJF folder, seed 1."""
    base = tmp_path_factory.mktemp("round3")
    assert main(["simulate", "--protocol", str(SMALL), "--seed", "1", "--out",
                 str(base / "OG")]) == 0
    assert main(["simulate", "--spec", "jjf1535-2015", "--seed", "1", "--out",
                 str(base / "JS")]) == 0
    return {"OG": base / "OG" / "readings.csv", "JS": base / "JS" / "readings.csv"}


@pytest.fixture(scope="module")
def og_lines(sims):
    return sims["OG"].read_text(encoding="utf-8").splitlines(keepends=True)


@pytest.fixture(scope="module")
def js_bias(sims):
    """The JJF readings cut to the bias test (metadata, header and its rows)."""
    out = []
    for ln in sims["JS"].read_text(encoding="utf-8").splitlines(keepends=True):
        if ln.startswith("#") or ln.startswith("test,") or ln.startswith("bias,"):
            out.append(ln)
    return out


COLS = ("test", "series", "round", "rate_dps", "orientation", "time_s", "table_deg",
        "gyro_counts", "gyro_deg")


def og_index(lines, test: str, series: int, rnd: int) -> int:
    for i, ln in enumerate(lines):
        c = ln.split(",")
        if c[0] == test and c[1] == str(series) and c[2] == str(rnd):
            return i
    raise AssertionError((test, series, rnd))


def og_set(lines, i: int, col: str, value) -> list[str]:
    out = list(lines)
    c = out[i].rstrip("\n").split(",")
    k = COLS.index(col)
    c[k] = value(c[k]) if callable(value) else value
    out[i] = ",".join(c) + "\n"
    return out


def og_screen(tmp_path, lines, name="r.csv"):
    p = tmp_path / name
    p.write_text("".join(lines), encoding="utf-8")
    before = sha(p)
    found = screen(read_readings(p), load_protocol(SMALL))
    assert sha(p) == before
    # less the statements of what the median rule could not see in the small programme's
    # three 7.1 readings and four of 7.6 and 7.7 (on every file of it:
    # tests/test_ogam_71_median_rule.py, tests/test_ogam_consistency_median_rule.py)
    return [f for f in found if not (f.code == "readings-not-judged"
                                     and f.clause in ("7.1", "7.6", "7.7"))]


# ------------------------------------------------ a folder named like a built-in protocol

@pytest.mark.parametrize("name", builtin_names())
def test_a_folder_named_like_a_builtin_is_not_the_protocol(tmp_path, monkeypatch, name):
    """``gonio simulate --spec X --out X`` makes a folder X in the working folder; every later
    command there that meant the built-in X (the default protocol, ``# protocol: X``) was
    refused: 'X: protocol file is a folder, not a regular file' — for every specification."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / name).mkdir()
    assert resolve(name) == protocols_dir() / f"{name}.toml"
    count(f"folder-named:{name}")


def test_simulate_into_a_folder_named_like_the_spec(tmp_path, monkeypatch, capsys):
    """The README workflow with the natural folder name: exit 0, readings written."""
    monkeypatch.chdir(tmp_path)
    cli(["simulate", "--spec", "ogam-draft", "--seed", "1", "--out", "ogam-draft"], capsys, 0)
    assert (tmp_path / "ogam-draft" / "readings.csv").is_file()
    count("folder-named:simulate-cli")


def test_a_fifo_or_other_folder_is_still_named(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mylab").mkdir()
    with pytest.raises(GonioError, match="is a folder"):
        resolve("mylab")
    with pytest.raises(GonioError, match="is a folder"):
        resolve(tmp_path / "mylab")
    count("folder-named:not-builtin")


# -------------------------------------------------------------- optical: series and gaps

def test_clean_session_has_no_finding(tmp_path, og_lines):
    assert og_screen(tmp_path, og_lines) == []
    count("ogam:clean")


def test_a_reading_missing_from_one_series_is_flagged(tmp_path, og_lines):
    """One 7.4 reading absent (the other series have its round): before, nothing said so —
    E's round mean was over the other series and the certificate was silent."""
    i = og_index(og_lines, "angle_deviation", 2, 3)
    found = og_screen(tmp_path, og_lines[:i] + og_lines[i + 1:])
    assert [(f.code, f.action) for f in found] == [("incomplete-programme", "flagged")], found
    assert "series 2 has no reading of round 3" in found[0].message
    count("ogam:missing-reading")


def test_a_series_typo_is_set_aside_and_the_gap_flagged(tmp_path, og_lines):
    """series 1 → 9 on one reading (the protocol has 3 series): before, accepted as a new
    series and series 1 short of a round, with no finding."""
    i = og_index(og_lines, "angle_deviation", 1, 4)
    found = og_screen(tmp_path, og_set(og_lines, i, "series", "9"))
    codes = sorted((f.code, f.action) for f in found)
    assert codes == [("incomplete-programme", "flagged"),
                     ("series-not-in-programme", "set_aside")], found
    bad = next(f for f in found if f.code == "series-not-in-programme")
    assert bad.line == i + 1 and bad.column == "series" and "3 series" in bad.message
    count("ogam:series-typo")


def test_a_late_reading_is_not_also_a_gap(tmp_path, og_lines):
    """A reading set aside (late) has its own finding; it is not reported twice."""
    i = og_index(og_lines, "angle_deviation", 1, 4)
    found = og_screen(tmp_path, og_set(og_lines, i, "time_s", lambda v: str(float(v) + 100)))
    assert [f.code for f in found] == ["late-reading"], found
    count("ogam:late")


@pytest.mark.parametrize("test", ["scale_factor", "angle_deviation"])
@pytest.mark.parametrize("how", ["+1deg", "-1deg", "sign"])
def test_a_one_degree_typo_in_the_counts_is_never_certified(tmp_path, og_lines, test, how):
    """A 1° slip (± K counts) or a sign typo in one optical reading's counts: set aside by
    line, or refused by line where its round would be lost — never in a certified value."""
    i = og_index(og_lines, test, 1, 2)
    k = 76435
    f = {"+1deg": lambda v: str(int(v) + k), "-1deg": lambda v: str(int(v) - k),
         "sign": lambda v: str(-int(v))}[how]
    try:
        found = og_screen(tmp_path, og_set(og_lines, i, "gyro_counts", f))
    except GonioError as e:
        assert f"r.csv:{i + 1}:" in str(e) and "gyro_counts" in str(e), e
    else:
        assert any(x.line == i + 1 and x.action in ("set_aside", "refused") for x in found), found
    count(f"ogam:counts-{how}:{test}")


# ----------------------------------------------------- misspelt keys and columns, every family

def test_ogam_misspelt_metadata_key_is_refused(tmp_path, og_lines, capsys):
    """``# latitude_dge:`` was kept as an extra key and the latitude taken as not stated
    (the coupling line at the equator's worst case): refused, naming the key."""
    lines = [ln.replace("# latitude_deg:", "# latitude_dge:") for ln in og_lines]
    assert lines != og_lines
    p = tmp_path / "r.csv"
    p.write_text("".join(lines), encoding="utf-8")
    msg = cli(["calibrate", p, "--protocol", SMALL, "--out", tmp_path / "o"], capsys, 2)
    assert "key latitude_dge" in msg and "'latitude_deg'" in msg and str(p) in msg, msg
    assert not (tmp_path / "o").exists()
    count("ogam:meta-key-typo")


@pytest.mark.parametrize("old,new,frag", [
    ("# rate_table_u_rel:", "# rate_table_urel:", "key rate_table_urel"),
    ("# acquisition_u_rel:", "# acquisiton_u_rel:", "key acquisiton_u_rel"),
    ("# chamber_deviation_bound_c:", "# chamber_deviation_bound:", "key chamber_deviation_bound"),
])
def test_rate_misspelt_metadata_key_is_refused(js_bias, old, new, frag):
    """A misspelt numeric key: before, the default replaced the value silently (2.5e-4 for the
    rate table; the budget changed with no word)."""
    lines = [ln.replace(old, new) for ln in js_bias]
    assert lines != js_bias
    with pytest.raises(GonioError) as ei:
        parse_rate_readings("".join(lines), path="r.csv")
    assert frag in str(ei.value) and "did you mean" in str(ei.value), ei.value
    count(f"jjf:meta-typo:{new}")


@pytest.mark.parametrize("old,new", [("temperature_c", "temperature"), ("supply_v", "suply_v"),
                                     ("rate_dps", "rate_dsp")])
def test_rate_misspelt_column_is_refused(js_bias, old, new):
    """A header typo made the column an ignored extra and every row took the default (rate 0,
    no temperature): refused, naming the column and the header line."""
    i = next(k for k, ln in enumerate(js_bias) if ln.startswith("test,"))
    lines = list(js_bias)
    lines[i] = lines[i].replace(old, new)
    with pytest.raises(GonioError) as ei:
        parse_rate_readings("".join(lines), path="r.csv")
    msg = str(ei.value)
    assert msg.startswith(f"r.csv:{i + 1}: column {new}:") and repr(old) in msg, msg
    count(f"jjf:column-typo:{new}")


def test_known_extra_columns_and_keys_still_read(js_bias):
    """Names far from every known one (a lab's own note column or key) are kept as before."""
    i = next(k for k, ln in enumerate(js_bias) if ln.startswith("test,"))
    lines = ["# operator_badge: 42\n"] + [
        ln.rstrip("\n") + (",note\n" if k == i else ",x\n") if k >= i else ln
        for k, ln in enumerate(js_bias)]
    rd = parse_rate_readings("".join(lines), path="r.csv")
    assert len(rd.data) == len(js_bias) - i - 1
    count("jjf:extras-kept")


@pytest.mark.parametrize("cut", [12, 9, 4])
def test_rate_file_cut_in_its_last_line_is_refused(js_bias, cut):
    """A file cut inside its last row ('2501.29' → '25'): before, read with the output 25
    (the missing cells blank); now refused naming the line and the field count."""
    text = "".join(js_bias[:-1])
    last = js_bias[-1].rstrip("\n")
    with pytest.raises(GonioError) as ei:
        parse_rate_readings(text + last[:-cut], path="r.csv")
    assert str(ei.value).startswith(f"r.csv:{len(js_bias)}: expected 16 fields"), ei.value
    parse_rate_readings(text + last, path="r.csv")         # no final newline: complete
    count(f"jjf:truncated-last-line:{cut}")


def _screen_rate(tmp_path, lines):
    from gonio.specs import get

    p = tmp_path / "r.csv"
    p.write_text("".join(lines), encoding="utf-8")
    spec = get("jjf1535-2015")
    return spec.screen(p, None)


def test_coarse_quantisation_of_a_record_is_stated(tmp_path, js_bias):
    """The bias record logged to 1 mV (noise ≈ 0.2 mV): before, a file of such records was
    refused as 'saturated' (5 samples in a row at the largest output, 2502 — two levels
    only), and with a scale-factor test beside it accepted with no word, its noise items
    (IEC in-band noise 0.0483 for 0.0434, JJF ARW 2.02 ± 0.04 for 1.79) certified as the
    gyro's; now read, with one flagged finding per test naming the resolution. The intact
    record has none."""
    assert not [f for f in _screen_rate(tmp_path, js_bias) if f.code == "coarse-quantisation"]
    k = js_bias[next(i for i, ln in enumerate(js_bias) if ln.startswith("test,"))].split(",")
    k = k.index("output")

    def rounded(ln):
        if not ln.startswith("bias,"):
            return ln
        c = ln.rstrip("\n").split(",")
        c[k] = str(round(float(c[k])))
        return ",".join(c) + "\n"

    found = [f for f in _screen_rate(tmp_path, [rounded(ln) for ln in js_bias])
             if f.code == "coarse-quantisation"]
    assert len(found) == 1 and found[0].action == "flagged" and found[0].test == "bias", found
    assert "resolution 1 " in found[0].message and "q/√12" in found[0].message
    count("jjf:coarse-quantisation")


@pytest.mark.parametrize("address", ["tcp://", "tcp://host", "tcp://host:port"])
def test_a_malformed_scheduler_address_is_refused_before_the_study(tmp_path, capsys, address):
    """``validate --scheduler tcp://``: 40 s, then the error and a Client.__del__ traceback
    on stderr, and a partial study left in --out that refused the corrected rerun. Now one
    line at once, nothing written."""
    msg = cli(["validate", "--trials", "2", "--scheduler", address, "--out", tmp_path / "v"],
              capsys, 2)
    assert "key scheduler" in msg and "not a scheduler address" in msg, msg
    assert not (tmp_path / "v").exists()
    count(f"validate:scheduler:{address}")


# ----------------------------------------------------- --spec of another family's file

def test_optical_spec_on_rate_or_triad_readings_names_the_mismatch(tmp_path, js_bias, tri,
                                                                    capsys):
    """``calibrate --spec ogam-draft`` on JJF or triad readings: the optical protocol reader
    got the file's own protocol and said 'jjf1535-2015.toml: key temperature: unknown
    section'; now the protocol's specification and how to give it."""
    r = tmp_path / "r.csv"
    r.write_text("".join(js_bias), encoding="utf-8")
    for readings, other in ((r, "jjf1535-2015"), (tri, "triad-alignment")):
        msg = cli(["calibrate", readings, "--spec", "ogam-draft", "--out", tmp_path / "o"],
                  capsys, 2)
        assert f"{other}.toml: key protocol.spec: this protocol is for '{other}'" in msg, msg
        assert f"--spec {other}" in msg and not (tmp_path / "o").exists()
    count("spec-mismatch:ogam-on-rate-and-triad")


def test_rate_spec_on_optical_readings_names_the_header(tmp_path, sims, capsys):
    """The misspelt-key rule does not hide a file of another format: the header is judged
    first ('column run: missing required column'), not '# temperature_c' taken for a typo."""
    msg = cli(["calibrate", sims["OG"], "--spec", "jjf1535-2015", "--out", tmp_path / "o"],
              capsys, 2)
    assert "column run: missing required column" in msg, msg
    count("spec-mismatch:jjf-on-ogam")


# ------------------------------------------ a page or figure into another command's set

def _fake_set(d: Path) -> Path:
    """An output set as calibrate leaves it: files listed in its manifest."""
    from gonio.atomic import MANIFEST

    d.mkdir()
    files = {}
    for name in ("certificate.html", "allan.png"):
        (d / name).write_bytes(b"<html>" + name.encode())
        files[name] = sha(d / name)
    (d / MANIFEST).write_text(json.dumps({"command": "calibrate", "files": files}),
                              encoding="utf-8")
    return d


@pytest.mark.parametrize("argv", [
    ["align", "{R}", "--report", "{C}/certificate.html"],
    ["thermal-model", "{R}", "--report", "{C}/certificate.html"],
    ["align", "{R}", "--plot", "{C}/allan.png"],
    ["noise", "{R}", "--plot", "{C}/allan.png"],
    ["eda", "{R}", "--plot", "{C}/allan.png"],
], ids=lambda a: f"{a[0]}-{a[2]}")
def test_a_page_or_figure_never_replaces_a_file_of_another_set(tmp_path, capsys, argv):
    """``gonio align R --report CAL/certificate.html`` replaced a calibration's certificate
    (exit 0), leaving its folder with two runs' files; ``eda --plot`` did not even check for
    a data file before the work. Now refused at once, naming the set; the set unchanged."""
    c = _fake_set(tmp_path / "CAL")
    before = {p.name: sha(p) for p in c.iterdir()}
    r = tmp_path / "r.csv"
    r.write_text("# x: y\n", encoding="utf-8")
    msg = cli([a.format(R=r, C=c) for a in argv], capsys, 2)
    assert "a file of the output set in" in msg and str(c.resolve()) in msg, msg
    assert {p.name: sha(p) for p in c.iterdir()} == before
    count(f"other-set:{argv[0]}{argv[2]}")


def test_rewriting_ones_own_page_is_still_allowed(tmp_path, capsys):
    """A page outside any set (or rewritten by a rerun) is not refused by this rule."""
    from gonio.atomic import check_output_files

    (tmp_path / "r.html").write_text("old", encoding="utf-8")
    assert check_output_files({"--report": tmp_path / "r.html"})
    count("other-set:own-page")


# ------------------------------------------ JSON inputs nested too deeply or too long

DEEP = "[" * 100_000 + "]" * 100_000 + "\n"
BIGNUM = "1" * 5000 + "\n"


@pytest.mark.parametrize("body", [DEEP, BIGNUM], ids=["deep", "5000-digits"])
def test_tilt_file_not_json_enough_names_the_file(tmp_path, sims, capsys, body):
    """``calibrate --tilt F``: a JSON nested 10⁵ deep said 'input nested too deeply' naming
    no file; a 5000-digit number escaped the JSON error handling. Now one line naming F."""
    t = tmp_path / "tilt.json"
    t.write_text(body, encoding="utf-8")
    msg = cli(["calibrate", sims["OG"], "--protocol", SMALL, "--tilt", t, "--out",
               tmp_path / "o"], capsys, 2)
    assert f"{t}: not a tilt result" in msg, msg
    assert not (tmp_path / "o").exists()
    count(f"json:tilt:{len(body)}")


def test_db_import_of_a_deep_results_json_names_the_folder(tmp_path, capsys):
    d = tmp_path / "c"
    d.mkdir()
    (d / "results.json").write_text(DEEP, encoding="utf-8")
    msg = cli(["db", "import", d, "--data", tmp_path / "data"], capsys, 2)
    assert f"{d}: no readable results.json" in msg, msg
    count("json:db-import")


def test_db_restore_of_a_deep_records_json_names_the_archive(tmp_path, capsys):
    import zipfile

    z = tmp_path / "b.zip"
    with zipfile.ZipFile(z, "w") as zf:
        zf.writestr("records.json", DEEP)
    msg = cli(["db", "restore", z, "--data", tmp_path / "data"], capsys, 2)
    assert f"{z}: no readable records.json" in msg, msg
    count("json:db-restore")


def test_resume_with_a_deep_study_json_names_it(tmp_path):
    """``validate --resume`` over a study.json nested 10⁵ deep: a RecursionError (exit 1 in
    Python, a one-line message naming no file on the CLI); now a GonioError naming it."""
    import importlib.util

    import gonio.pipeline.validate as V

    spec = importlib.util.spec_from_file_location(
        "_validate_engine", Path(__file__).with_name("test_validate_engine.py"))
    eng = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(eng)
    part = tmp_path / "s" / V.PARTIAL_DIR
    part.mkdir(parents=True)
    (part / "study.json").write_text(DEEP, encoding="utf-8")
    with pytest.raises(GonioError) as ei:
        V.validate(6, seed=3, bench=eng.bench(), protocol=eng.tiny_protocol(),
                   sample_rate_hz=10.0, show_progress=False, workers=1, batch_size=2,
                   partial_dir=part, resume=True)
    assert str(ei.value).startswith(f"{part / 'study.json'}: unreadable partial study"), ei.value
    count("json:resume-study")


# ------------------------------------------------------------------------------ triad

@pytest.fixture(scope="module")
def tri(tmp_path_factory):
    d = tmp_path_factory.mktemp("tri")
    assert main(["simulate", "--spec", "triad-alignment", "--seed", "1", "--out",
                 str(d / "TRI")]) == 0
    return d / "TRI" / "readings.csv"


def test_triad_missing_dwell_is_named(tri):
    """One alignment dwell deleted: before, every U changed (M_xx 0.0027 → 0.0035) with no
    finding; now a flagged programme-point-missing naming the gap's line."""
    from gonio.pipeline.dispatch import screen_and_calibrate
    from gonio.specs import get

    lines = tri.read_text(encoding="utf-8").splitlines(keepends=True)
    i = next(k for k, ln in enumerate(lines) if ln.startswith("alignment,3,"))
    p = tri.parent / "missing.csv"
    p.write_text("".join(lines[:i] + lines[i + 1:]), encoding="utf-8")
    res = screen_and_calibrate(get("triad-alignment"), p, None).to_json()
    f = [x for x in res["findings"] if x["code"] == "programme-point-missing"]
    assert len(f) == 1 and f[0]["action"] == "flagged" and f[0]["line"] == i + 1, f
    assert "step 3 missing" in f[0]["message"]
    assert res["items"]["M_xx"]["measured"]
    count("triad:missing-dwell")


def test_triad_dwell_with_sd_zero_gives_no_warning(tri):
    """A dwell whose sd_x is 0 (a filled column) was divided by in the consistency check: a
    RuntimeWarning on stderr of a run that exits 0. The values are those of the intact file."""
    from gonio.pipeline.dispatch import screen_and_calibrate
    from gonio.specs import get

    src = tri
    d = tri.parent.parent
    lines = src.read_text(encoding="utf-8").splitlines(keepends=True)
    i = next(k for k, ln in enumerate(lines) if ln.startswith("test,"))
    cols = lines[i].strip().split(",")
    c = lines[i + 3].rstrip("\n").split(",")
    c[cols.index("sd_x")] = "0"
    lines[i + 3] = ",".join(c) + "\n"
    p = d / "TRI" / "r.csv"
    p.write_text("".join(lines), encoding="utf-8")
    spec = get("triad-alignment")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = screen_and_calibrate(spec, p, None)
    ref = screen_and_calibrate(spec, src, None)
    a, b = res.to_json()["items"], ref.to_json()["items"]
    assert a["M_xx"]["value"] == b["M_xx"]["value"] and a["M_xx"]["measured"]
    count("triad:sd-zero")


# ------------------------------------------- protocols that plan what the reader refuses

PROTOCOL_TEMPERATURES = {
    # case: (spec, old text, new text, key the message names)
    "iec-operating-min-below-absolute-zero": ("iec62047-20", "operating_min_c = -40.0",
                                              "operating_min_c = -300.0",
                                              "protocol.operating_min_c"),
    "jjf-room-300": ("jjf1535-2015", "room_temperature_c = 20.0", "room_temperature_c = 300.0",
                     "protocol.room_temperature_c"),
    "jjf-point-300": ("jjf1535-2015", "points_c = [70.0, -40.0]", "points_c = [300.0, -40.0]",
                      "temperature.points_c"),
    "triad-setpoint-minus-400": ("triad-alignment", "setpoints_c = [-40.0,",
                                 "setpoints_c = [-400.0,", "thermal.setpoints_c"),
    "triad-start-1e6": ("triad-alignment", "start_c = 25.0", "start_c = 1e6",
                        "thermal.start_c"),
}


@pytest.mark.parametrize("name", sorted(PROTOCOL_TEMPERATURES))
def test_protocol_temperatures_the_reader_would_refuse(tmp_path, capsys, name):
    """A protocol temperature outside what the readings reader takes: before, IEC
    operating_min_c = -300 °C (below absolute zero) and JJF room 300 °C were simulated (exit 0)
    into a file the reader then refused; triad start_c = 1e6 blamed thermal.ramp_block_s.
    Now refused when the protocol is read, naming the key; nothing written."""
    spec, old, new, key = PROTOCOL_TEMPERATURES[name]
    text = (protocols_dir() / f"{spec}.toml").read_text(encoding="utf-8")
    assert old in text
    p = tmp_path / "p.toml"
    p.write_text(text.replace(old, new, 1), encoding="utf-8")
    before = sha(p)
    msg = cli(["simulate", "--spec", spec, "--protocol", p, "--seed", "1", "--out",
               tmp_path / "o"], capsys, 2)
    assert msg.startswith(f"gonio: error: {p}: key {key}:") and "[-100, 200]" in msg, msg
    assert not (tmp_path / "o").exists() and sha(p) == before
    count(f"protocol-temperature:{name}")


def test_case_count_reported():
    assert len(CASES) >= 1


def test_triad_without_static_record_is_said(tri, tmp_path):
    """Hostile round 3 (left by the round, done by the lead): the static rows deleted, the
    bias U fell about 6× (the bias-instability term needs the static record) with exit 0 and
    the change only in a detail; now a flagged static-record-missing that reaches
    results.json and the certificate, and the bias's details say what it is."""
    lines = tri.read_text(encoding="utf-8").splitlines(keepends=True)
    keep = [ln for ln in lines if not ln.startswith("static,")]
    assert len(keep) < len(lines)
    p = tri.parent / "nostatic.csv"           # beside the thermal file it names
    p.write_text("".join(keep), encoding="utf-8")
    out = tmp_path / "cal"
    assert main(["calibrate", str(p), "--spec", "triad-alignment", "--out", str(out)]) == 0
    res = json.loads((out / "results.json").read_text(encoding="utf-8"))
    f = [x for x in res["findings"] if x["code"] == "static-record-missing"]
    assert len(f) == 1 and f[0]["action"] == "flagged", res["findings"]
    assert "no bias-instability term" in res["items"]["b_x"]["details"]["stated"]
    assert "no static record" in (out / "certificate.html").read_text(encoding="utf-8")
    zh = tmp_path / "zh"
    assert main(["calibrate", str(p), "--spec", "triad-alignment", "--lang", "zh", "--out",
                 str(zh)]) == 0
    html = (zh / "certificate.html").read_text(encoding="utf-8")
    assert "无静态记录" in html and "no static record" not in html
    # the intact file gives no such finding
    from gonio.pipeline.dispatch import screen_and_calibrate
    from gonio.specs import get
    assert not [x for x in screen_and_calibrate(get("triad-alignment"), tri, None)
                .to_json()["findings"] if x["code"] == "static-record-missing"]
    count("triad:no-static-record")


@pytest.mark.parametrize("every", [2, 3])
def test_rate_blank_on_half_a_segment_is_refused(sims, tmp_path, capsys, every):
    """rate_dps blank on every other row (a blank reads as the default 0 °/s): before, every
    item 'not measured' with 100 missing-point findings and no word on the cause; now
    refused by line, naming the segment and its split. Blank on every third row leaves a
    majority: those rows are set aside by line, as before, and the file is calibrated."""
    lines = sims["JS"].read_text(encoding="utf-8").splitlines(keepends=True)
    hdr = next(i for i, ln in enumerate(lines) if ln.startswith("test,"))
    ri = lines[hdr].strip().split(",").index("rate_dps")
    out, k = lines[:hdr + 1], 0
    for ln in lines[hdr + 1:]:
        f = ln.rstrip("\n").split(",")
        if f[0] == "scale_factor" and f[ri] not in ("0", ""):
            if k % every == 0:
                f[ri] = ""
            k += 1
        out.append(",".join(f) + "\n")
    p = tmp_path / "half.csv"
    p.write_text("".join(out), encoding="utf-8")
    before = p.read_bytes()
    rc = main(["calibrate", str(p), "--out", str(tmp_path / "cal")])
    err = capsys.readouterr().err.strip().splitlines()
    assert p.read_bytes() == before
    if every == 2:
        assert rc == 2 and len(err) == 1, err
        assert "rate_dps has no majority value" in err[0] and "scale_factor run" in err[0]
        assert not (tmp_path / "cal").exists()
    else:
        assert rc == 0
        res = json.loads((tmp_path / "cal" / "results.json").read_text(encoding="utf-8"))
        assert res["items"]["scale_factor"]["measured"]
        assert any(f["code"] == "setting-departs" and f["action"] == "set_aside"
                   for f in res["findings"])
    count(f"jjf:rate-blank-every-{every}")
