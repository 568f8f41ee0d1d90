"""Issue 24: screening of optical-draft readings, from the outside.

Damaged copies of gonio's own bench files (``gonio simulate``: counts, no ``gyro_deg``) are
written into temporary folders; what reaches ``results.json`` and the certificate is checked.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gonio.cli import main
from gonio.errors import GonioError
from gonio.specs.ogam_draft.readings import Readings, read_readings
from gonio.specs.ogam_draft.calibration import calibrate
from gonio.specs.ogam_draft.protocol import load_protocol
from gonio.specs.ogam_draft.screen import ANGLE_FLOOR_ARCSEC, apply_findings, screen

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "data" / "small-protocol.toml"


@pytest.fixture(scope="session")
def bench_file(tmp_path_factory):
    """One simulated session of the small protocol (counts only, like the bench's files)."""
    out = tmp_path_factory.mktemp("screen_sim")
    assert main(["simulate", "--protocol", str(SMALL), "--seed", "2411", "--out",
                 str(out / "sim")]) == 0
    return out / "sim" / "readings.csv"


def lines_of(path: Path) -> list[str]:
    return path.read_text().splitlines(keepends=True)


def data_line(lines, test, series, rnd, rate="60.0", orient="up") -> int:
    """0-based index of a reading's line in the file."""
    for i, ln in enumerate(lines):
        p = ln.split(",")
        if p[0] == test and p[1] == str(series) and p[2] == str(rnd) and p[3] == rate \
                and p[4] == orient:
            return i
    raise KeyError((test, series, rnd))


def damage(src: Path, dst_dir: Path, edit) -> Path:
    lines = lines_of(src)
    lines = edit(lines)
    dst_dir.mkdir(parents=True, exist_ok=True)
    f = dst_dir / "readings.csv"
    f.write_text("".join(lines))
    return f


def set_col(line: str, col: int, fn) -> str:
    p = line.rstrip("\n").split(",")
    p[col] = fn(p[col])
    return ",".join(p) + "\n"


def nominal_k(lines) -> float:
    for ln in lines:
        if ln.startswith("# nominal_scale_factor_counts_per_deg:"):
            return float(ln.split(":")[1])
    raise KeyError


def run_cli(f: Path, out: Path, capsys, lang="en"):
    capsys.readouterr()
    code = main(["calibrate", str(f), "--protocol", str(SMALL), "--out", str(out),
                 "--lang", lang])
    err = capsys.readouterr().err
    return code, err


def judged(found):
    """The findings less the statements of what the median rule could not see in the small
    programme's three 7.1 readings and four of 7.6 and 7.7 (flagged ``readings-not-judged``,
    on every file of it: tests/test_ogam_71_median_rule.py,
    tests/test_ogam_consistency_median_rule.py)."""
    return [f for f in found if not (f.code == "readings-not-judged"
                                     and f.clause in ("7.1", "7.6", "7.7"))]


def test_clean_bench_file_has_no_finding(bench_file):
    """Nothing set aside or refused; the three findings state what the median rule, which
    alone judges this programme's three 7.1 readings and four at 7.6's 30 °/s and 7.7's
    north, could not have seen (tests/test_ogam_consistency_median_rule.py)."""
    found = screen(read_readings(bench_file), load_protocol(SMALL))
    assert [(f.code, f.action, f.clause) for f in found] == [
        ("readings-not-judged", "flagged", c) for c in ("7.1", "7.6", "7.7")]


@pytest.mark.parametrize("seed", [1, 7])
def test_clean_full_programme_has_no_finding(tmp_path, seed):
    """The built-in programme (1 °/s included, where a six-minute turn drifts): no false alarm."""
    assert main(["simulate", "--seed", str(seed), "--out", str(tmp_path / "s")]) == 0
    rd = read_readings(tmp_path / "s" / "readings.csv")
    assert screen(rd, load_protocol("ogam-draft")) == []


def test_one_degree_typo_in_a_7_4_reading_is_set_aside(bench_file, tmp_path, capsys):
    lines = lines_of(bench_file)
    i = data_line(lines, "angle_deviation", 2, 3)
    k = nominal_k(lines)
    f = damage(bench_file, tmp_path / "in",
               lambda ls: ls[:i] + [set_col(ls[i], 7, lambda c: str(int(c) + round(k)))]
               + ls[i + 1:])
    clean = calibrate(bench_file, SMALL).items
    code, err = run_cli(f, tmp_path / "o", capsys)
    assert code == 0
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    fd = [x for x in res["findings"] if x["line"] == i + 1]
    assert len(fd) == 1 and fd[0]["action"] == "set_aside" and fd[0]["column"] == "gyro_counts"
    assert fd[0]["clause"] == "7.4" and "t_ν⁻¹" in fd[0]["rule"] and "K_ref" in fd[0]["message"]
    assert i + 1 in {u["line"] for u in res["unused_readings"]}
    # R stays that of the healthy data (not 1 138″); E close to the clean file's
    assert res["items"]["repeatability"]["value"] < 1.0
    assert abs(res["items"]["angle_deviation"]["value"] - abs(clean["angle_deviation"].value)) < 0.5
    page = (tmp_path / "o" / "certificate.html").read_text()
    assert "1 reading(s) set aside" in page and f"line {i + 1}:" in page
    assert "excluded" in err


def test_one_degree_typo_in_a_7_1_reading_is_refused_with_its_line(bench_file, tmp_path,
                                                                     capsys):
    """7.1 has one reading per round: setting it aside would drop a round, so it is refused
    (today it was certified as E = −1797.6″ with U = 0.67″)."""
    lines = lines_of(bench_file)
    i = data_line(lines, "scale_factor", 1, 2)
    k = nominal_k(lines)
    f = damage(bench_file, tmp_path / "in",
               lambda ls: ls[:i] + [set_col(ls[i], 7, lambda c: str(int(c) - round(k)))]
               + ls[i + 1:])
    with pytest.raises(GonioError, match="departs from") as exc:
        calibrate(f, SMALL)
    assert exc.value.line == i + 1 and "cannot stand" in exc.value.message
    code, err = run_cli(f, tmp_path / "o", capsys)
    assert code == 2 and f"readings.csv:{i + 1}" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_typo_in_gyro_deg_column_is_screened_too(tmp_path):
    """Every column: a file giving angles in degrees is screened the same way."""
    rd = read_readings(ROOT / "tests" / "data" / "full.csv")
    df = rd.data.copy()
    ad = df.index[(df["test"] == "angle_deviation") & df["gyro_deg"].notna()]
    assert len(ad) >= 3
    j = ad[1]
    df.loc[j, "gyro_deg"] += 0.01                       # 36″
    found = screen(Readings(df, rd.metadata, rd.path), load_protocol(ROOT / "tests" / "data"
                                                                      / "full.toml"))
    hit = [x for x in found if x.line == int(df.loc[j, "line"])]
    assert hit and hit[0].column == "gyro_deg"


def test_reading_an_hour_late_without_the_key_is_set_aside(bench_file, tmp_path, capsys):
    assert load_protocol(SMALL).angle_deviation.max_time_to_reading_s is None
    lines = lines_of(bench_file)
    i = data_line(lines, "angle_deviation", 1, 2)
    f = damage(bench_file, tmp_path / "in",
               lambda ls: ls[:i] + [set_col(ls[i], 5, lambda t: str(float(t) + 3600.0))]
               + ls[i + 1:])
    code, _ = run_cli(f, tmp_path / "o", capsys)
    assert code == 0
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    fd = [x for x in res["findings"] if x["line"] == i + 1]
    assert fd and fd[0]["code"] == "late-reading" and fd[0]["column"] == "time_s"
    assert "Annex A.1" in fd[0]["message"] and "0.5 min" in fd[0]["message"]
    # u(B_E) from the readings used, not from one hour
    b_e = [c for c in res["extra"]["uncertainty"]["components"] if c["symbol"] == "B_E"][0]
    assert b_e["u_arcsec"] < 0.2
    assert "set aside" in (tmp_path / "o" / "certificate.html").read_text()


def test_an_explicit_key_widens_the_bound(bench_file, tmp_path):
    lines = lines_of(bench_file)
    i = data_line(lines, "angle_deviation", 1, 2)
    f = damage(bench_file, tmp_path / "in",
               lambda ls: ls[:i] + [set_col(ls[i], 5, lambda t: str(float(t) + 20.0))]
               + ls[i + 1:])
    proto = SMALL.read_text().replace("series = 3\n", "series = 3\nmax_time_to_reading_s = 60.0\n")
    (tmp_path / "p.toml").write_text(proto)
    assert judged(screen(read_readings(f), load_protocol(tmp_path / "p.toml"))) == []
    late = judged(screen(read_readings(f), load_protocol(SMALL)))
    assert [x.code for x in late] == ["late-reading"]


def test_a_7_4_point_missing_from_every_series_is_named(bench_file, tmp_path, capsys):
    def drop(ls):
        return [ln for ln in ls if not (ln.startswith("angle_deviation,")
                                        and ln.split(",")[2] == "3")]
    f = damage(bench_file, tmp_path / "in", drop)
    code, err = run_cli(f, tmp_path / "o", capsys)
    assert code == 0
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    fd = [x for x in res["findings"] if x["code"] == "incomplete-programme"]
    assert len(fd) == 1 and fd[0]["action"] == "flagged" and fd[0]["clause"] == "7.4"
    assert "round 3 (270°)" in fd[0]["message"] and "3 of the programme's 4" in fd[0]["message"]
    assert "round 3 (270°)" in err
    for lang, says in (("en", "round 3 (270°) is missing from every series"),
                       ("zh", "第 3 测回（270°）在各组中均缺失")):     # in the page's language
        code, _ = run_cli(f, tmp_path / f"o_{lang}", capsys, lang=lang)
        page = (tmp_path / f"o_{lang}" / "certificate.html").read_text()
        assert says in page


def test_a_missing_7_1_round_is_named(bench_file):
    rd = read_readings(bench_file)
    df = rd.data
    keep = df[~((df["test"] == "scale_factor") & (df["round"] == 1))].reset_index(drop=True)
    found = screen(Readings(keep, rd.metadata, rd.path), load_protocol(SMALL))
    # and the two readings left are stated as judged by no rule (the median rule needs 3)
    assert [(x.code, x.clause) for x in found] == [("readings-not-judged", "7.1"),
                                                  ("readings-not-judged", "7.6"),
                                                  ("readings-not-judged", "7.7"),
                                                  ("incomplete-programme", "7.1")]
    lines = keep.loc[keep["test"] == "scale_factor", "line"].astype(int).tolist()
    assert f"lines {lines[0]}, {lines[1]} judged by no rule (2 readings" in found[0].message


def test_rate_not_in_programme_is_set_aside(bench_file, tmp_path):
    lines = lines_of(bench_file)
    idx = [i for i, ln in enumerate(lines) if ln.startswith("rate_consistency,")
           and ln.split(",")[3] == "30.0"]
    f = damage(bench_file, tmp_path / "in",
               lambda ls: [set_col(ln, 3, lambda r: "300.0") if n in idx else ln
                           for n, ln in enumerate(ls)])
    rd = read_readings(f)
    found = judged(screen(rd, load_protocol(SMALL)))
    assert sorted(x.code for x in found) == ["condition-not-in-programme",
                                             "incomplete-programme"]
    assert [x.line for x in found if x.line] == [idx[0] + 1]
    assert f"{len(idx)} readings" in found[0].message
    _, aside = apply_findings(rd, found)
    assert list(aside["line"]) == [i + 1 for i in idx]


def test_7_3_typo_is_set_aside_identical_readings_are_not(bench_file, tmp_path):
    lines = lines_of(bench_file)
    i = data_line(lines, "zero_stability", 1, 2, rate="")
    k = nominal_k(lines)
    f = damage(bench_file, tmp_path / "a",
               lambda ls: ls[:i] + [set_col(ls[i], 7, lambda c: str(int(c) + round(k / 100)))]
               + ls[i + 1:])
    found = judged(screen(read_readings(f), load_protocol(SMALL)))
    assert [(x.line, x.clause) for x in found] == [(i + 1, "7.3")]
    same = damage(bench_file, tmp_path / "b",
                  lambda ls: [set_col(ln, 7, lambda c: "5") if ln.startswith("zero_stability,")
                              else ln for ln in ls])
    assert judged(screen(read_readings(same), load_protocol(SMALL))) == []


def test_threshold_floor_is_documented():
    doc = (ROOT / "docs" / "draft-readings.md").read_text()
    assert "## Screening" in doc and f"{ANGLE_FLOOR_ARCSEC:g}″" in doc
