"""Hostile inputs of issue 26, generated from simulated folders of every specification.

``JS``, ``IEC`` and ``TRI`` are the folders ``gonio simulate --spec jjf1535-2015 |
iec62047-20 | triad-alignment`` writes (made once per session); each case damages a copy in
the test's own folder and checks the outcome a user must get: exit 2 (or a GonioError) with
one line naming file, line or key; or, where the data allow a result, an honest one ("not
measured" with the reason, never 0 ± 0). Inputs are never written, moved or deleted; a
folder holds the outputs of one command; ``--resume`` reuses only verified batches.

To keep the run short, reader cases parse a copy cut to the tests a case needs; the cases
that need a whole calibration use those cut copies too.
"""

from __future__ import annotations

import json
import math
import os
import random
import shutil
from pathlib import Path

import numpy as np
import pytest

from gonio.atomic import MANIFEST, read_manifest, sha256_file
from gonio.cli import main
from gonio.errors import GonioError
from gonio.formats.rate_readings import parse_rate_readings
from gonio.specs.triad_alignment.readings import parse_triad_readings

CASES: list[str] = []          # every generated case, counted for the README


def count(name: str) -> None:
    CASES.append(name)


def cli(argv, capsys, expect: int = 2) -> str:
    """The CLI in-process: the exit code, and for an error one line without a traceback."""
    rc = main([str(a) for a in argv])
    cap = capsys.readouterr()
    assert rc == expect, (argv, rc, cap.err[-2000:])
    if expect == 2:
        lines = cap.err.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in cap.err and "error:" in lines[0], cap.err
        return lines[0]
    return cap.err


def tree(d: Path) -> dict:
    return {p.relative_to(d).as_posix(): sha256_file(p)
            for p in sorted(d.rglob("*")) if p.is_file()}


# ----------------------------------------------------------------------------- the folders

@pytest.fixture(scope="session")
def sims(tmp_path_factory):
    """Simulated folders of the three file families (seed 1), made once."""
    base = tmp_path_factory.mktemp("sims")
    out = {}
    for name, spec in (("JS", "jjf1535-2015"), ("IEC", "iec62047-20"),
                       ("TRI", "triad-alignment")):
        assert main(["simulate", "--spec", spec, "--seed", "1", "--out", str(base / name)]) == 0
        out[name] = base / name
    return out


class Text:
    """A readings file as metadata lines, header fields and data rows (lists of cells)."""

    def __init__(self, path: Path):
        lines = path.read_text(encoding="utf-8").splitlines()
        i = 0
        while lines[i].startswith("#"):
            i += 1
        self.meta = lines[:i]
        self.header = lines[i].split(",")
        self.rows = [ln.split(",") for ln in lines[i + 1:] if ln]

    def col(self, name: str) -> int:
        return self.header.index(name)

    def only(self, *tests: str) -> "Text":
        """A copy keeping the rows of ``tests`` (all rows when none is given)."""
        t = object.__new__(Text)
        t.meta, t.header = list(self.meta), list(self.header)
        t.rows = [list(r) for r in self.rows if not tests or r[0] in tests]
        return t

    def set_meta(self, key: str, value: str | None) -> "Text":
        self.meta = [m for m in self.meta if not m.startswith(f"# {key}:")]
        if value is not None:
            self.meta.append(f"# {key}: {value}")
        return self

    def set(self, column: str, value, test: str | None = None, first: bool = False) -> "Text":
        k = self.col(column)
        for r in self.rows:
            if test is None or r[0] == test:
                r[k] = value(r[k]) if callable(value) else value
                if first:
                    break
        return self

    def text(self) -> str:
        return "\n".join(self.meta + [",".join(self.header)] + [",".join(r) for r in self.rows]) \
            + "\n"

    def write(self, path: Path) -> Path:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(self.text(), encoding="utf-8")
        return path

    def line_of(self, index: int) -> int:
        """The file line (1-based) of data row ``index``."""
        return len(self.meta) + 2 + index


@pytest.fixture(scope="session")
def js(sims):
    return Text(sims["JS"] / "readings.csv")


@pytest.fixture(scope="session")
def iec(sims):
    return Text(sims["IEC"] / "readings.csv")


def refused(text: Text, *fragments: str, line: int | None = None,
            parse=parse_rate_readings, name: str = "r.csv") -> str:
    """``parse`` refuses the text; the one-line message holds every fragment (and the line)."""
    with pytest.raises(GonioError) as ei:
        parse(text.text(), path=name)
    msg = str(ei.value)
    assert "\n" not in msg and msg.startswith(name), msg
    for f in fragments:
        assert f in msg, msg
    if line is not None:
        assert msg.startswith(f"{name}:{line}:"), msg
    return msg


# ------------------------------------------------- degenerate, absurd, duplicated rate data

def _shuffle(t: Text) -> Text:
    random.Random(1).shuffle(t.rows)
    return t


def _dup(t: Text) -> Text:
    t.rows.insert(11, list(t.rows[10]))
    return t


def _own_steps(t: Text) -> Text:
    k = t.col("step")
    for n, r in enumerate(t.rows):
        r[k] = str(n)
    return t


def _clip(t: Text) -> Text:
    k = t.col("output")
    for r in t.rows:
        r[k] = repr(min(max(float(r[k]), 2050.0), 2950.0))
    return t


def _extra_field(t: Text) -> Text:
    t.rows[5].append("7")
    return t


RATE_CASES = {
    # name: (family, tests kept, mutation, message fragments, data row the error names)
    "jjf-time-all-zero": ("js", ("warmup",), lambda t: t.set("time_s", "0"),
                          ("time_s", "increase"), 1),
    "iec-time-all-equal": ("iec", ("warmup", "vibration"), lambda t: t.set("time_s", "100"),
                           ("time_s", "increase"), 1),
    "jjf-duplicated-sample": ("js", ("bias",), _dup, ("duplicated sample",), 11),
    "jjf-rows-shuffled": ("js", ("bias", "scale_factor"), _shuffle, ("time_s",), None),
    "jjf-static-own-steps": ("js", ("static",), _own_steps, ("one record", "step"), 1),
    "jjf-static-constant": ("js", ("static",), lambda t: t.set("output", "2500"),
                            ("every sample of test static", "stuck"), 0),
    "jjf-all-outputs-zero": ("js", ("scale_factor", "bias"), lambda t: t.set("output", "0"),
                             ("every sample of test bias",), None),
    "jjf-clipped": ("js", ("scale_factor", "bias"), _clip, ("saturated",), None),
    "iec-temperature-1e308": ("iec", ("bias_temperature",),
                              lambda t: t.set("temperature_c", "1e308", first=0),
                              ("column temperature_c", "[-100, 200]"), 0),
    "jjf-temperature-300": ("js", ("bias_temperature",),
                            lambda t: t.set("temperature_c", "300", first=0),
                            ("column temperature_c",), 0),
    "jjf-output-1e308": ("js", ("bias",), lambda t: t.set("output", "1e308", first=0),
                         ("column output",), 0),
    "jjf-freq-1e308": ("js", ("vibration",), lambda t: t.set("freq_hz", "1e308", first=0),
                       ("column freq_hz",), 0),
    "iec-supply-0-ratiometric": ("iec", ("ratiometric",),
                                 lambda t: t.set("supply_v", "0", test="ratiometric"),
                                 ("column supply_v",), 0),
    "jjf-extra-field-line": ("js", ("bias",), _extra_field, ("expected 16 fields",), 5),
}


@pytest.mark.parametrize("name", sorted(RATE_CASES))
def test_rate_rows_refused_with_line(request, name):
    """Degenerate, absurd, duplicated, reordered and clipped rate data: refused by the reader
    with the line (before: 0 ± 0 certified, silently moved results, or internal errors)."""
    fam, tests, mutate, frags, row = RATE_CASES[name]
    t = mutate(request.getfixturevalue(fam).only(*tests))
    refused(t, *frags, line=None if row is None else t.line_of(row))
    count(f"rate-rows:{name}")


META_CASES = [("room_temperature_c", "-300"), ("chamber_deviation_bound_c", "1e308"),
              ("chamber_deviation_bound_c", "-2"), ("rate_table_u_rel", "-1"),
              ("rate_table_u_rel", "1e308"), ("rate_table_u_rel", "nan"),
              ("acquisition_u_rel", "2"), ("null_output", "1e308"),
              ("nominal_scale_factor", "1e308"), ("supply_nominal_v", "0")]


@pytest.mark.parametrize("key,value", META_CASES)
def test_rate_metadata_ranges(js, key, value):
    """Absurd metadata values: refused naming the key (before: accepted, 'measured' without U
    or internal errors)."""
    refused(js.only("bias").set_meta(key, value), f"key {key}")
    count(f"rate-meta:{key}={value}")


def test_noise_free_records_still_read(js):
    """The constant-record and saturation checks do not apply to a noise-free bench."""
    t = js.only("static").set("output", "2500").set_meta("noise", "off")
    assert len(parse_rate_readings(t.text(), path="r.csv").data) == len(t.rows)
    count("rate-rows:noise-free")


def test_jjf_static_record_with_spikes_is_not_arw_zero(js, tmp_path):
    """Every third static sample a spike of 10⁶: the five-term fit finds no white noise;
    ARW is "not measured" with the reason, never 0 ± 0 (before: certified 0.0 ± 0.0 °/√h)."""
    from gonio.specs.jjf1535 import calibrate

    t = js.only("scale_factor", "static")
    k, n = t.col("output"), 0
    for r in t.rows:
        if r[0] == "static":
            n += 1
            if n % 3 == 0:
                r[k] = "1000000"
    path = t.write(tmp_path / "r.csv")
    # the screening refuses a record a third of which are spikes, naming the first (issue 24)
    with pytest.raises(GonioError, match="damaged") as exc:
        calibrate(path)
    assert exc.value.column == "output" and exc.value.line is not None
    res = calibrate(path, findings=[])             # and past the screening, the ARW fit too
    it = res.items["angle_random_walk"]
    assert not it.measured and "no angle random walk" in it.reason, it
    assert res.items["scale_factor"].measured
    count("rate:jjf-static-spikes-arw")


def test_parquet_renamed_csv(tmp_path, capsys):
    """A Parquet file named .csv is named as Parquet (before: 'not UTF-8 text (byte 7)')."""
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq
    p = tmp_path / "readings.csv"
    pq.write_table(pa.table({"a": [1.0, 2.0]}), p)
    for argv in (["calibrate", p, "--out", tmp_path / "o"], ["reduce", p, "--out", tmp_path / "r.csv"],
                 ["align", p]):
        assert "Parquet" in cli(argv, capsys)
        count(f"parquet-as-csv:{argv[0]}")


# ------------------------------------------------------------- rate calibrations, whole

def test_unknown_protocol_in_readings_is_an_error(tmp_path, js, capsys):
    """'# protocol: mylab' that cannot be found: exit 2 naming the key (before: the built-in
    protocol used silently)."""
    p = js.only("bias").set_meta("protocol", "mylab").write(tmp_path / "r.csv")
    msg = cli(["calibrate", p, "--out", tmp_path / "o"], capsys)
    assert "key protocol" in msg and "mylab" in msg, msg
    assert not (tmp_path / "o").exists()
    count("rate:protocol-not-found")


def test_spec_protocol_mismatch_blames_the_protocol_given(tmp_path, js, capsys):
    """An IEC protocol for JJF readings: the message names the protocol's spec and the
    calibration's (before: 'jjf1535-2015.toml: key threshold: unknown section')."""
    p = js.only("bias").write(tmp_path / "r.csv")
    msg = cli(["calibrate", p, "--protocol", "iec62047-20", "--out", tmp_path / "o"], capsys)
    assert "iec62047-20.toml" in msg and "'jjf1535-2015'" in msg and "protocol.spec" in msg, msg
    count("rate:protocol-spec-mismatch")


@pytest.mark.parametrize("fam,tests,item", [
    ("js", ("scale_factor", "bias_temperature"), "bias_temperature_sensitivity"),
    ("iec", ("scale_factor", "bias_temperature"), "bias_hysteresis"),
])
def test_missing_static_record_is_not_measured(request, fam, tests, item):
    """Without the static record the bias-drift term is unknown: the items that need it are
    'not measured' with the reason (before: the term was 0 and U collapsed)."""
    from gonio.specs import get

    t = request.getfixturevalue(fam).only(*tests)
    rd = parse_rate_readings(t.text(), path="r.csv")
    spec = get(t.meta[0].split(":", 1)[1].strip())
    res = spec.calibrate(rd, spec.default_protocol)
    it = res.items[item]
    assert not it.measured, (item, it.value)
    assert "static" in json.dumps(it.to_json() if hasattr(it, "to_json") else str(it)), it
    count(f"rate:no-static:{fam}")


# --------------------------------------------------------------------------- triad files

@pytest.fixture(scope="session")
def tri(sims):
    return Text(sims["TRI"] / "readings.csv")


@pytest.fixture(scope="session")
def thermal(sims):
    return Text(sims["TRI"] / "thermal.csv")


def triad_refused(text: Text, *fragments: str) -> str:
    return refused(text, *fragments, parse=parse_triad_readings, name="t.csv")


def _tri_dup(t: Text) -> Text:
    t.rows.insert(3, list(t.rows[2]))
    return t


TRIAD_CASES = {
    "alignment-duplicated-row": ("tri", _tri_dup, ("repeats line",)),
    "alignment-zero-outputs": ("tri", lambda t: [t.set(c, "0.0", test="alignment")
                                                 for c in ("out_x", "out_y", "out_z")][-1],
                               ("did not respond",)),
    "alignment-rate-1e308": ("tri", lambda t: t.set("rate_dps", "1e308", first=0),
                             ("column rate_dps",)),
    "thermal-zero-outputs": ("thermal", lambda t: [t.set(c, "0") for c in
                                                   ("out_x", "out_y", "out_z")][-1],
                             ("did not respond",)),
    "thermal-constant-times": ("thermal", lambda t: t.set("time_s", "5.0"), ("time_s",)),
    "thermal-temperatures-x1e298": ("thermal", lambda t: t.set("sensor_c",
                                                               lambda v: repr(float(v) * 1e298)),
                                    ("column sensor_c",)),
    "thermal-shuffled": ("thermal", _shuffle, ("time_s",)),
}


@pytest.mark.parametrize("name", sorted(TRIAD_CASES))
def test_triad_rows_refused(request, name):
    """Duplicated, degenerate and absurd triad rows: refused with the line (before: U(M_xx)
    shrunk by a duplicate, or internal errors in align and thermal-model)."""
    fam, mutate, frags = TRIAD_CASES[name]
    triad_refused(mutate(request.getfixturevalue(fam).only()), *frags)
    count(f"triad-rows:{name}")


def test_thermal_programme_at_one_temperature(tmp_path, capsys):
    """A thermal programme soaked at −40 °C only: thermal-model refuses it and calibrate
    states the model "not measured" with the reason (before: K_z at the 25 °C reference was
    certified 49.10 ± 0.39 against 49.69 from the whole programme)."""
    import re

    from gonio.specs import get

    text = (PROTOCOLS / "triad-alignment.toml").read_text(encoding="utf-8")
    p = tmp_path / "one.toml"
    p.write_text(re.sub(r"(?m)^setpoints_c = .*$", "setpoints_c = [-40.0]", text, count=1),
                 encoding="utf-8")
    assert main(["simulate", "--spec", "triad-alignment", "--protocol", str(p),
                 "--out", str(tmp_path / "D")]) == 0
    capsys.readouterr()
    th = tmp_path / "D" / "thermal.csv"
    msg = cli(["thermal-model", th], capsys)
    # refused by the thermal fit, or (thermal-model screens as calibrate) by the screening
    assert "one temperature" in msg or "extrapolation" in msg \
        or "a temperature model needs" in msg, msg
    try:                                  # refused whole by the screening, or not measured
        res = get("triad-alignment").calibrate(tmp_path / "D" / "readings.csv")
    except GonioError as exc:
        assert "thermal.csv" in str(exc) and "temperature" in str(exc), str(exc)
    else:
        it = res.items["thermal_model"]
        assert not it.measured and "temperature" in it.reason, it.reason
        assert not any(k.startswith("K_") for k in res.items)
    count("triad:thermal-one-temperature")


def test_triad_cli_values(sims, capsys):
    """align --seed -1 and --monte-carlo beyond the limit: one-line refusals at once."""
    r = sims["TRI"] / "readings.csv"
    for argv in (["align", r, "--seed", "-1"], ["align", r, "--monte-carlo", "100000000"],
                 ["align", r, "--monte-carlo", "-5"]):
        cli(argv, capsys)
        count(f"triad-cli:{argv[2]}={argv[3]}")


def test_align_refuses_a_sign_flipped_dwell_like_calibrate(tmp_path, tri, capsys):
    """One dwell with its rate sign flipped: align refuses it with the check calibrate uses
    (before: align printed M_xx ≈ 34)."""
    t = tri.only()
    t.set("rate_dps", lambda v: repr(-float(v)), test="alignment", first=True)
    p = t.write(tmp_path / "r.csv")
    msg = cli(["align", p, "--monte-carlo", "0"], capsys)
    assert "inconsistent" in msg and f":{t.line_of(0)}" in msg, msg
    count("triad:sign-flipped-dwell")


# ------------------------------------------------------------ inputs never replaced or lost

def test_align_and_thermal_model_never_replace_inputs(tmp_path, sims, capsys):
    """--report/--plot onto the readings, the thermal file they name, the --compensate file or
    any data file: refused before any work, the files unchanged (before: overwritten)."""
    d = tmp_path / "D"
    shutil.copytree(sims["TRI"], d)
    before = tree(d)
    r, th = d / "readings.csv", d / "thermal.csv"
    for argv in (["align", r, "--report", r], ["align", r, "--plot", th],
                 ["align", r, "--report", d / "truth.json"],
                 ["thermal-model", th, "--report", th],
                 ["thermal-model", th, "--compensate", r, "--report", r],
                 ["thermal-model", th, "--plot", r],
                 ["thermal-model", th, "--plot", d / "x.svg", "--report", d / "x.svg"]):
        cli(argv, capsys)
        assert tree(d) == before, argv
        count(f"inputs:{argv[0]}:{Path(argv[-1]).name}")


@pytest.fixture(scope="session")
def triad_calibrated(sims, tmp_path_factory):
    """``gonio calibrate D/readings.csv --out D`` on a copy of the triad folder, run twice."""
    d = tmp_path_factory.mktemp("triadcal") / "D"
    shutil.copytree(sims["TRI"], d)
    before = tree(d)
    first = main(["calibrate", str(d / "readings.csv"), "--out", str(d), "--monte-carlo", "0"])
    after_first = tree(d)
    second = main(["calibrate", str(d / "readings.csv"), "--out", str(d), "--monte-carlo", "0"])
    return d, before, after_first, (first, second)


def test_calibrate_into_the_simulated_folder_keeps_its_files(triad_calibrated):
    """The documented workflow: the thermal file the readings name and truth.json stay, and
    the identical rerun succeeds (before: both deleted, the rerun failed)."""
    d, before, after_first, rcs = triad_calibrated
    assert rcs == (0, 0)
    for name in ("readings.csv", "thermal.csv", "truth.json"):
        assert after_first[name] == before[name] and tree(d)[name] == before[name], name
    man = read_manifest(d)
    assert man["command"] == "calibrate"
    assert set(man["inputs_kept"]) >= {"readings.csv", "thermal.csv", "truth.json"}
    count("inputs:calibrate-into-simulated-folder")


def test_study_and_calibration_never_share_a_folder(tmp_path, triad_calibrated, capsys):
    """validate --out CALDIR and calibrate --out VALDIR are refused; neither deletes the
    other's files (before: mixed in one manifest, then deleted silently)."""
    d = triad_calibrated[0]
    before = tree(d)
    msg = cli(["validate", "--trials", "2", "--out", d], capsys)
    assert "gonio calibrate" in msg, msg
    assert tree(d) == before
    v = tmp_path / "V"
    v.mkdir()
    (v / "validation.json").write_text("{}\n")
    vb = tree(v)
    msg = cli(["calibrate", d / "readings.csv", "--out", v], capsys)
    assert "validate" in msg, msg
    assert tree(v) == vb
    count("mixing:validate-into-calibration")
    count("mixing:calibrate-into-study")


def test_simulate_into_a_calibration_folder_is_refused(triad_calibrated, capsys):
    """``gonio simulate --out CALDIR`` would replace a calibration's outputs (another
    command's): refused, nothing deleted."""
    d = triad_calibrated[0]
    before = tree(d)
    for extra in ([], ["--force"]):
        msg = cli(["simulate", "--spec", "triad-alignment", "--out", d, *extra], capsys)
        assert "gonio calibrate" in msg, msg
        assert tree(d) == before
    count("mixing:simulate-into-calibration")


# ------------------------------------------------------------ lab files, budgets, figures

LAB = Path(__file__).resolve().parents[1] / "protocols" / "lab-example.toml"


@pytest.mark.parametrize("value,frag", [
    ("A\\u0001B", "U+0001"), ("A\\u0000B", "U+0000"), ("A\\uFFFFB", "U+FFFF"),
    ("A\\u007fB", "U+007F"), ("X" * 1_000_000, "over the limit"),
])
def test_lab_text_fields(tmp_path, value, frag):
    """Control characters and a megabyte of name in a lab file: refused naming the key at
    once (before: the DCC writer raised, the HTML carried the characters, and a 10^6
    character name took 389 s to lay out)."""
    import time

    from gonio.formats.lab import load_lab

    p = tmp_path / "lab.toml"
    p.write_text(LAB.read_text(encoding="utf-8").replace(
        'name = "Example Angle Metrology Laboratory"', f'name = "{value}"', 1), encoding="utf-8")
    t0 = time.perf_counter()
    with pytest.raises(GonioError) as ei:
        load_lab(p)
    assert time.perf_counter() - t0 < 10
    msg = str(ei.value)
    assert "key laboratory.name" in msg and frag in msg and len(msg) < 300, msg
    count(f"lab:{frag}")


LIMIT = '[[specification_limits]]\nitem = "angle_deviation"\nmpe = 0.5\n'
#: name: (text replacing LIMIT or a (old, new) pair in the lab file, key named)
LIMIT_CASES = {
    "mpe-inf": (LIMIT.replace("0.5", "inf"), "specification_limits[0].mpe"),
    "mpe-nan": (LIMIT.replace("0.5", "nan"), "specification_limits[0].mpe"),
    "mpe-1e308": (LIMIT.replace("0.5", "1e308"), "specification_limits[0].mpe"),
    "mpe-subnormal": (LIMIT.replace("0.5", "5e-324"), "specification_limits[0].mpe"),
    "mpe-text": (LIMIT.replace("0.5", '"0.5"'), "specification_limits[0].mpe"),
    "mpe-bool": (LIMIT.replace("0.5", "true"), "specification_limits[0].mpe"),
    "mpe-zero": (LIMIT.replace("0.5", "0.0"), "specification_limits[0].mpe"),
    "lower-nan": (LIMIT.replace("mpe = 0.5", "lower = nan\nupper = 1.0"),
                  "specification_limits[0].lower"),
    "lower-minus-inf": (LIMIT.replace("mpe = 0.5", "lower = -inf\nupper = 1.0"),
                        "specification_limits[0].lower"),
    "upper-inf": (LIMIT.replace("mpe = 0.5", "upper = inf"), "specification_limits[0].upper"),
    "upper-1e999": (LIMIT.replace("mpe = 0.5", "upper = 1e999"), "specification_limits[0].upper"),
    "upper-1e20": (LIMIT.replace("mpe = 0.5", "upper = 99999999999999999999"),
                   "specification_limits[0].upper"),
    "lower-above-upper": (LIMIT.replace("mpe = 0.5", "lower = 2.0\nupper = 1.0"),
                          "specification_limits[0]"),
    "lower-equals-upper": (LIMIT.replace("mpe = 0.5", "lower = 1.0\nupper = 1.0"),
                           "specification_limits[0]"),
    "no-bound": (LIMIT.replace("mpe = 0.5\n", ""), "specification_limits[0]"),
    "mpe-and-upper": (LIMIT.replace("mpe = 0.5", "mpe = 0.5\nupper = 1.0"),
                      "specification_limits[0]"),
    "item-missing": (LIMIT.replace('item = "angle_deviation"\n', ""),
                     "specification_limits[0].item"),
    "item-number": (LIMIT.replace('"angle_deviation"', "3"), "specification_limits[0].item"),
    "item-twice": (LIMIT + "\n" + LIMIT, "specification_limits[1].item"),
    "unknown-key": (LIMIT.replace("mpe = 0.5", 'mpe = 0.5\nunits = "arcsec"'),
                    "specification_limits[0].units"),
    "guard-band-inf": (("guard_band_factor = 1.0", "guard_band_factor = inf"),
                       "decision_rule.guard_band_factor"),
    "guard-band-nan": (("guard_band_factor = 1.0", "guard_band_factor = nan"),
                       "decision_rule.guard_band_factor"),
    "guard-band-negative": (("guard_band_factor = 1.0", "guard_band_factor = -1.0"),
                            "decision_rule.guard_band_factor"),
    "rule-upper-case": (('rule = "non-binary"', 'rule = "NON-BINARY"'), "decision_rule.rule"),
    "rule-empty": (('rule = "non-binary"', 'rule = ""'), "decision_rule.rule"),
    "limits-without-rule": (("[decision_rule]", "[decision_rule_x]"), "decision_rule"),
}


@pytest.mark.parametrize("name", sorted(LIMIT_CASES))
def test_lab_conformity_limits_refused_by_key(tmp_path, name):
    """Conformity limits and the decision rule in a lab file: non-finite, absurd, empty,
    contradictory, duplicated or mistyped entries are refused when the file is read (before
    any work), one line naming file and key."""
    from gonio.formats.lab import load_lab

    change, key = LIMIT_CASES[name]
    text = LAB.read_text(encoding="utf-8")
    assert LIMIT in text
    if isinstance(change, tuple):
        assert change[0] in text
        text = text.replace(*change, 1)
    else:
        text = text.replace(LIMIT, change, 1)
    p = tmp_path / "lab.toml"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(GonioError) as ei:
        load_lab(p)
    msg = str(ei.value)
    assert msg.startswith(str(p)) and f"key {key}" in msg and "\n" not in msg, msg
    count(f"limits:{name}")


@pytest.mark.parametrize("item", ["", " scale_factor", "angle_deviation"])
def test_lab_limit_on_an_item_the_spec_lacks(sims, tmp_path, capsys, item):
    """A limit on an item the specification does not have (empty, a stray space, another
    specification's item): exit 2, one line naming the lab file, the key and the
    specification's items; no output folder (before: the key without the file)."""
    text = LAB.read_text(encoding="utf-8").replace(
        LIMIT, LIMIT.replace('"angle_deviation"', f'"{item}"'), 1).replace(
        'item = "repeatability"', 'item = "bias"', 1)
    lab = tmp_path / "lab.toml"
    lab.write_text(text, encoding="utf-8")
    out = tmp_path / "C"
    msg = cli(["calibrate", sims["JS"] / "readings.csv", "--out", out, "--lab", lab,
               "--monte-carlo", "0"], capsys)
    assert f"{lab}: key specification_limits[0].item" in msg and "scale_factor" in msg, msg
    assert not out.exists()
    count(f"limits:item:{item!r}")


@pytest.fixture(scope="module")
def jjf_computed(sims, tmp_path_factory):
    """A JJF output folder (calibrate of the simulated folder) holding its readings, and an
    initialised records database."""
    base = tmp_path_factory.mktemp("imp")
    out = base / "CJ"
    assert main(["calibrate", str(sims["JS"] / "readings.csv"), "--out", str(out),
                 "--monte-carlo", "0"]) == 0
    shutil.copy(sims["JS"] / "readings.csv", out / "readings.csv")
    data = base / "data"
    assert main(["db", "init", "--data", str(data)]) == 0
    return out, data


#: name: (edit of the results.json dict, or raw text; the key the one-line refusal names)
IMPORT_CASES = {
    "results-list": ("[]", "results"),
    "results-null": ("null", "results"),
    "not-json": ("{", None),
    "empty-file": ("", None),
    "items-empty-list": (lambda d: d.__setitem__("items", []), "items"),
    "items-empty-dict": (lambda d: d.__setitem__("items", {}), "items"),
    "items-of-numbers": (lambda d: d.__setitem__("items", {"a": 1, "b": 2}), "items"),
    "metadata-list": (lambda d: d.__setitem__("metadata", [1]), "metadata"),
    "source-list": (lambda d: d.__setitem__("source", ["x"]), "source"),
    "date-month-13": (lambda d: d["metadata"].__setitem__("date", "2026-13-45"),
                      "metadata.date"),
    "date-text": (lambda d: d["metadata"].__setitem__("date", "yesterday"), "metadata.date"),
    "spec-unknown": (lambda d: d.__setitem__("spec", "no-such-spec"), "spec"),
    # no specification named anywhere: refused, not guessed (it was taken as the optical draft)
    "spec-missing": (lambda d: [d.pop("spec"), d["metadata"].pop("spec", None)], "spec"),
    "serial-control": (lambda d: d["metadata"].__setitem__("serial", "A\u0001B"), "serial"),
    "serial-huge": (lambda d: d["metadata"].__setitem__("serial", "S" * 100_000), "serial"),
}


@pytest.mark.parametrize("name", sorted(IMPORT_CASES))
def test_records_import_of_damaged_results(jjf_computed, tmp_path, capsys, name):
    """``gonio db import`` of an output folder whose results.json is damaged: exit 2 with one
    line (before: a list as metadata or source, or a month 13, ended in an internal error,
    and an empty list of items was imported as a calibration)."""
    src, data = jjf_computed
    d = tmp_path / name
    shutil.copytree(src, d)
    edit, key = IMPORT_CASES[name]
    if isinstance(edit, str):
        text = edit
    else:
        res = json.loads((src / "results.json").read_text(encoding="utf-8"))
        edit(res)
        text = json.dumps(res)
    (d / "results.json").write_text(text, encoding="utf-8")
    msg = cli(["db", "import", d, "--data", data], capsys)
    assert key is None or f"key {key}" in msg, msg
    count(f"import:{name}")


def test_budget_of_every_spec(capsys):
    """gonio budget for every registered specification: exit 0 (before: triad-alignment
    raised AttributeError, exit 1)."""
    from gonio.specs import available

    for key in sorted(available()):
        rc = main(["budget", "--spec", key])
        out = capsys.readouterr()
        assert rc in (0, 2) and "internal error" not in out.err, (key, out.err)
        count(f"budget:{key}")


def test_figure_with_a_data_suffix_is_refused_before_the_work(tmp_path, sims, capsys):
    """--plot out.parquet: refused at once naming the formats (before: an internal error
    after the whole analysis)."""
    r = sims["TRI"] / "readings.csv"
    for argv in (["align", r, "--plot", tmp_path / "out.parquet"],
                 ["thermal-model", sims["TRI"] / "thermal.csv", "--plot", tmp_path / "f.csv"]):
        assert ".png" in cli(argv, capsys)
        count(f"figure-suffix:{argv[0]}")


def test_parquet_stream_with_a_column_named_twice(tmp_path, capsys):
    """A Parquet stream whose schema names a column twice: exit 2 naming the column in
    calibrate, reduce and noise (before: KeyError, exit 1)."""
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    t = pa.table({"time_s": np.arange(10) * 0.1, "gyro_counts": np.arange(10),
                  "table_deg": np.zeros(10)})
    t = pa.Table.from_arrays(t.columns + [t.column(1)], names=t.schema.names + ["gyro_counts"])
    p = tmp_path / "s.parquet"
    pq.write_table(t.replace_schema_metadata({"nominal_scale_factor_counts_per_deg": "1000"}), p)
    for argv in (["calibrate", p, "--out", tmp_path / "o"],
                 ["reduce", p, "--out", tmp_path / "r.csv"], ["noise", p]):
        msg = cli(argv, capsys)
        assert "gyro_counts" in msg and "twice" in msg, msg
        count(f"parquet-dup-column:{argv[0]}")


# ----------------------------------------------------------- sizes checked before the work

PROTOCOLS = Path(__file__).resolve().parents[1] / "protocols"


def _protocol(tmp_path, name: str, old: str, new: str) -> Path:
    text = (PROTOCOLS / f"{name}.toml").read_text(encoding="utf-8")
    assert old in text, old
    p = tmp_path / f"{name}.toml"
    p.write_text(text.replace(old, new, 1), encoding="utf-8")
    return p


SIZE_CASES = {
    # name: (protocol, old text, new text, loader, key named)
    "iec-divisions-1e9": ("iec62047-20", "divisions = 5", "divisions = 1000000000",
                          "gonio.specs.iec62047_20.protocol", "scale_factor.divisions"),
    "iec-step-1e-9": ("iec62047-20", "step_deg = 45.0", "step_deg = 1e-9",
                      "gonio.specs.iec62047_20.protocol", "g_sensitivity.step_deg"),
    "jjf-rates-10-10": ("jjf1535-2015", "# rates_dps = [1, 2, 5, 10, 20, 50, 100]",
                        "rates_dps = [10, 10]", "gonio.specs.jjf1535.protocol",
                        "scale_factor.rates_dps"),
    "jjf-stability-block-1e5": ("jjf1535-2015", "stability_block_samples = 10 ",
                                "stability_block_samples = 100000 ",
                                "gonio.specs.jjf1535.protocol", "bias.stability_block_samples"),
    "jjf-stability-block-half": ("jjf1535-2015", "stability_block_samples = 10 ",
                                 "stability_block_samples = 1801 ",
                                 "gonio.specs.jjf1535.protocol", "bias.stability_block_samples"),
}


@pytest.mark.parametrize("name", sorted(SIZE_CASES))
def test_protocol_sizes_refused_naming_the_key(tmp_path, name):
    """IEC divisions = 1e9, a g-sensitivity step of 1e-9°, JJF rates [10, 10]: refused when
    the protocol is read, naming file and key (before: 3 GB and 'out of memory', or an
    error naming neither file nor key)."""
    import importlib

    proto, old, new, module, key = SIZE_CASES[name]
    p = _protocol(tmp_path, proto, old, new)
    with pytest.raises(GonioError) as ei:
        importlib.import_module(module).load_protocol(p)
    msg = str(ei.value)
    assert msg.startswith(str(p)) and f"key {key}" in msg, msg
    count(f"size:{name}")


def test_triad_ramp_block_sized_before_simulating(tmp_path, capsys):
    """thermal.ramp_block_s = 0.01: refused before the first block, naming the key (before:
    the session grew 3.7 MB/s without end)."""
    import time

    p = _protocol(tmp_path, "triad-alignment", "ramp_block_s = 60.0", "ramp_block_s = 0.01")
    t0 = time.perf_counter()
    msg = cli(["simulate", "--spec", "triad-alignment", "--protocol", p, "--out", tmp_path / "o"],
              capsys)
    assert "thermal.ramp_block_s" in msg and "GONIO_MAX_READING_ROWS" in msg, msg
    assert time.perf_counter() - t0 < 120
    count("size:triad-ramp-block")


def test_monte_carlo_in_chunks_equals_the_whole(monkeypatch, sims):
    """align's Monte Carlo combines chunks of trials (bounded memory for 1e7 trials): with a
    chunk of 7 the uncertainties equal those of all 20 trials held at once (before: every
    trial was kept, and 1e7 ran out of memory)."""
    import gonio.specs.triad_alignment.analysis as A
    from gonio.specs.triad_alignment.readings import read_triad_readings

    r = read_triad_readings(sims["TRI"] / "readings.csv")
    whole = A.estimate_alignment(r, monte_carlo=20, seed=2)
    monkeypatch.setattr(A, "MC_CHUNK", 7)
    monkeypatch.setattr(A.chunked_std, "__defaults__", (7,))
    parts = A.estimate_alignment(r, monte_carlo=20, seed=2)
    np.testing.assert_allclose(parts.u_mc_theta, whole.u_mc_theta, rtol=1e-9)
    for k in whole.u_mc:
        np.testing.assert_allclose(parts.u_mc[k], whole.u_mc[k], rtol=1e-9)
    count("size:monte-carlo-chunks")


# ------------------------------------------------------------------ --resume verification

def _engine():
    """tests/test_validate_engine.py (its tiny protocol and bench), loaded by path."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "_validate_engine", Path(__file__).with_name("test_validate_engine.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="session")
def studies(tmp_path_factory):
    """Two interrupted tiny studies (seeds 3 and 4): their .validate-partial folders, each
    with the batches of trials 0-1 and 2-3, and the uninterrupted study's JSON."""
    import gonio.pipeline.validate as V

    bench, tiny_protocol = _engine().bench, _engine().tiny_protocol
    base = tmp_path_factory.mktemp("studies")
    out = {}
    for seed in (3, 4):
        part = base / f"s{seed}" / V.PARTIAL_DIR
        real = V.run_batch
        calls = []

        def flaky(job, a, b):
            calls.append(a)
            if len(calls) == 3:
                raise KeyboardInterrupt
            return real(job, a, b)
        V.run_batch = flaky
        try:
            with pytest.raises(KeyboardInterrupt):
                V.validate(6, seed=seed, bench=bench(), protocol=tiny_protocol(),
                           sample_rate_hz=10.0, show_progress=False, workers=1, batch_size=2,
                           partial_dir=part)
        finally:
            V.run_batch = real
        out[seed] = part
    return out


def _resume(part: Path, seed: int = 3):
    import gonio.pipeline.validate as V

    bench, tiny_protocol = _engine().bench, _engine().tiny_protocol
    return V.validate(6, seed=seed, bench=bench(), protocol=tiny_protocol(), sample_rate_hz=10.0,
                      show_progress=False, workers=1, batch_size=2, partial_dir=part,
                      resume=True)


B01, B23 = "default_0000000000_0000000002.npz", "default_0000000002_0000000004.npz"


def _repack(path: Path, fn, record: bool) -> None:
    """Rewrite a batch through ``fn(packed)`` with a consistent digest; ``record`` False also
    drops its entry from study.json (as if the run had been killed before recording it)."""
    import gonio.pipeline.validate as V

    with np.load(path) as z:
        packed = {k: z[k] for k in z.files}
    packed = fn(packed)
    packed["digest"] = np.array(V.batch_digest(packed))
    np.savez(path.with_suffix(""), **packed)
    if not record:
        head = path.parent / "study.json"
        info = json.loads(head.read_text())
        info["batches"].pop(path.name, None)
        head.write_text(json.dumps(info))


def _reverse(packed):
    packed = {k: (v[::-1] if getattr(v, "ndim", 0) >= 1 and k not in ("extras_symbol",
              "extras_distribution") else v) for k, v in packed.items()}
    return packed


def _edit(packed):
    packed["U_arcsec"] = packed["U_arcsec"] * 2
    return packed


def _tamper_foreign(part, other):
    shutil.copy(other / B23, part / B23)


def _tamper_bytes(part, other):
    data = bytearray((part / B23).read_bytes())
    data[-30] ^= 1
    (part / B23).write_bytes(bytes(data))


def _tamper_edit_unrecorded(part, other):
    with np.load(part / B23) as z:
        packed = {k: z[k] for k in z.files}
    packed = _edit(packed)                           # the digest is left as it was
    np.savez(part / B23.replace(".npz", ""), **packed)
    info = json.loads((part / "study.json").read_text())
    info["batches"].pop(B23)
    (part / "study.json").write_text(json.dumps(info))


RESUME_CASES = {
    "foreign-seed": (_tamper_foreign, "another study"),
    "edited-bytes": (_tamper_bytes, "differ"),
    "edited-values-unrecorded": (_tamper_edit_unrecorded, "digest"),
    "reordered": (lambda part, other: _repack(part / B23, _reverse, False), "range"),
    "renamed": (lambda part, other: (part / B23).rename(part / "default_0000000004_0000000006.npz"),
                "range"),
    "truncated": (lambda part, other: (part / B23).write_bytes((part / B23).read_bytes()[:300]),
                  "unreadable"),
    "truncated-unrecorded": (lambda part, other: (_repack(part / B23, lambda p: p, False),
                                                  (part / B23).write_bytes(
                                                      (part / B23).read_bytes()[:300]))[-1],
                             "unreadable"),
    "empty": (lambda part, other: (part / B23).write_bytes(b""), "unreadable"),
    "fifo": (lambda part, other: ((part / B23).unlink(), os.mkfifo(part / B23)), "regular"),
    "study-json-list": (lambda part, other: (part / "study.json").write_text("[]\n"),
                        "partial-study record"),
    "study-json-empty": (lambda part, other: (part / "study.json").write_text(""),
                         "unreadable partial study"),
}


@pytest.mark.parametrize("name", sorted(RESUME_CASES))
def test_resume_refuses_foreign_or_altered_batches(tmp_path, studies, name):
    """--resume verifies every batch (fingerprint with the seed, digest, checksum in
    study.json, trial range, regular file): a foreign, edited, reordered, truncated or empty
    batch, a FIFO or a damaged study.json is refused with its name, at once (before: exit 0
    with a different validation.json, internal errors, or a hang on the FIFO)."""
    import signal

    part = tmp_path / "s" / ".validate-partial"
    shutil.copytree(studies[3], part)
    tamper, frag = RESUME_CASES[name]
    tamper(part, studies[4])
    old = signal.signal(signal.SIGALRM, lambda *a: (_ for _ in ()).throw(TimeoutError(name)))
    signal.alarm(60)
    try:
        with pytest.raises(GonioError) as ei:
            _resume(part)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    msg = str(ei.value)
    assert frag in msg and "\n" not in msg, msg
    count(f"resume:{name}")


def test_resume_of_an_intact_study_and_a_killed_record(tmp_path, studies):
    """The checks pass an intact study, and a batch written but not yet recorded in
    study.json (a kill between the two) is verified by its own fingerprint and digest."""
    part = tmp_path / "s" / ".validate-partial"
    shutil.copytree(studies[3], part)
    _repack(part / B23, lambda p: p, False)
    report = _resume(part).to_dict()
    assert report["cases"][0]["trials"] == 6, report["cases"][0].keys()
    count("resume:intact-and-unrecorded")


def test_case_count_reported():
    """Kept last: the number of generated cases run in this module (README figure)."""
    assert len(CASES) > 40, len(CASES)
    print(f"\nissue-26 hostile cases: {len(CASES)}")
