"""Damaged optical-draft readings through ``gonio calibrate``: a reading missing from a 7.6/7.7
condition, a reading set aside with its whole condition, a typo below the old 5″ floor, a
missing or late 7.3 reading. Each file is written here from a simulated session; what
reaches results.json and the certificate is checked."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from gonio.cli import main

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "data" / "small-protocol.toml"


@pytest.fixture(scope="module")
def three_rates(tmp_path_factory):
    """The small protocol with three 7.6 rates (10, 30, 60 °/s) and its simulated session."""
    out = tmp_path_factory.mktemp("three_rates")
    proto = out / "p.toml"
    proto.write_text(SMALL.read_text().replace("rates_dps = [30.0, 60.0]",
                                               "rates_dps = [10.0, 30.0, 60.0]"))
    assert main(["simulate", "--protocol", str(proto), "--seed", "2412", "--out",
                 str(out / "sim")]) == 0
    return proto, out / "sim" / "readings.csv"


def write_without(src: Path, dst: Path, drop) -> list[str]:
    """``src`` less the lines ``drop(fields)`` is true of; returns the dropped lines."""
    keep, gone = [], []
    for ln in src.read_text().splitlines(keepends=True):
        p = ln.split(",")
        (gone if not ln.startswith("#") and drop(p) else keep).append(ln)
    dst.parent.mkdir(parents=True, exist_ok=True)
    dst.write_text("".join(keep))
    return gone


def calibrate_cli(f: Path, proto: Path, out: Path, capsys, lang: str = "en") -> dict:
    capsys.readouterr()
    assert main(["calibrate", str(f), "--protocol", str(proto), "--out", str(out),
                 "--lang", lang]) == 0
    capsys.readouterr()
    return json.loads((out / "results.json").read_text())


def page_text(out: Path) -> str:
    return re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", (out / "certificate.html").read_text()))


@pytest.mark.parametrize("test, cond, key, rnd", [
    ("rate_consistency", ("10.0", "up"), "rate_consistency", 2),
    ("pointing_consistency", ("60.0", "north"), "pointing_consistency", 3)])
def test_a_round_missing_from_a_compared_condition_refuses_the_item(three_rates, tmp_path,
                                                                    capsys, test, cond, key,
                                                                    rnd):
    """7.6/7.7 compare E over the same positions at every condition: a condition missing one
    is not set aside whole (its C from the other conditions, stated as the programme's) nor
    compared on fewer positions; the item is not measured and says why, in both languages."""
    proto, clean = three_rates
    full = calibrate_cli(clean, proto, tmp_path / "clean", capsys)
    assert full["items"][key]["measured"]
    n_cond = full["items"][key]["details"]["n_conditions"]
    assert n_cond >= 3 if test == "rate_consistency" else n_cond >= 2
    f = tmp_path / "in" / "readings.csv"
    gone = write_without(clean, f, lambda p: p[0] == test and p[2] == str(rnd)
                         and (p[3], p[4]) == cond)
    assert len(gone) == 1
    res = calibrate_cli(f, proto, tmp_path / "en", capsys)
    item = res["items"][key]
    assert not item["measured"] and item["value"] is None
    assert "lacks" in item["reason"] and "same calibration positions" in item["reason"]
    # the other items are untouched
    for other in ("angle_deviation", "repeatability", "scale_factor"):
        assert res["items"][other]["value"] == full["items"][other]["value"]
    fd = [x for x in res["findings"] if x["code"] == "incomplete-programme"]
    assert len(fd) == 1 and "is not stated" in fd[0]["message"]
    page = page_text(tmp_path / "en")
    assert "lacks" in page and "0 reading(s) set aside" in page
    calibrate_cli(f, proto, tmp_path / "zh", capsys, lang="zh")
    zh = page_text(tmp_path / "zh")
    assert "要求各测量条件在相同的校准位置上比较 E" in zh and "该项目不予给出" in zh
    assert "lacks" not in zh


def test_the_set_aside_count_counts_every_reading_of_a_condition_set_aside(three_rates,
                                                                          tmp_path, capsys):
    """A 7.6 rate outside the programme is one finding and all its readings set aside: the
    certificate counts the readings, not the findings."""
    proto, clean = three_rates
    lines = clean.read_text().splitlines(keepends=True)
    hit = [i for i, ln in enumerate(lines) if ln.startswith("rate_consistency,")
           and ln.split(",")[3] == "10.0"]
    assert len(hit) > 1
    for i in hit:
        p = lines[i].split(",")
        p[3] = "1000.0"
        lines[i] = ",".join(p)
    f = tmp_path / "in" / "readings.csv"
    f.parent.mkdir()
    f.write_text("".join(lines))
    res = calibrate_cli(f, proto, tmp_path / "o", capsys)
    aside = [u for u in res["unused_readings"] if "condition-not-in-programme" in u["reason"]]
    assert len(aside) == len(hit)
    assert res["extra"]["screening"]["set_aside_readings"] == len(hit)
    assert f"{len(hit)} reading(s) set aside" in page_text(tmp_path / "o")


@pytest.fixture(scope="module")
def six_series(tmp_path_factory):
    """The small protocol with 7.4 read in six series (screened round by round)."""
    out = tmp_path_factory.mktemp("six_series")
    proto = out / "p.toml"
    text = SMALL.read_text()
    assert "series = 3\n" in text
    proto.write_text(text.replace("series = 3\n", "series = 6\n", 1))
    assert main(["simulate", "--protocol", str(proto), "--seed", "2413", "--out",
                 str(out / "sim")]) == 0
    return proto, out / "sim" / "readings.csv"


def test_two_digits_transposed_in_a_7_4_reading_are_set_aside(six_series, tmp_path, capsys):
    """A transposition of the last two digits of a 7.4 count (≥ 18 counts, ~0.85″ on an RLG)
    sits far outside a round's spread (~0.1″) but below the former 5″ floor: set aside,
    and R and E are those of the file without that line."""
    proto, clean = six_series
    lines = clean.read_text().splitlines(keepends=True)
    k = next(float(ln.split(":")[1]) for ln in lines
             if ln.startswith("# nominal_scale_factor_counts_per_deg:"))
    pick = None
    for i, ln in enumerate(lines):
        p = ln.split(",")
        # the first reading of series 4 whose last two digits differ enough to transpose
        if p[0] == "angle_deviation" and p[1] == "4":
            c = p[7]
            swapped = c[:-2] + c[-1] + c[-2]
            if abs(int(swapped) - int(c)) >= 18:
                pick = i, swapped, abs(int(swapped) - int(c))
                break
    assert pick is not None, "the reading's last two digits are too close to transpose"
    i, swapped, d = pick
    assert d / k * 3600.0 < 5.0                  # below the former floor
    p = lines[i].split(",")
    p[7] = swapped
    damaged = lines[:i] + [",".join(p)] + lines[i + 1:]
    (tmp_path / "in").mkdir()
    f = tmp_path / "in" / "readings.csv"
    f.write_text("".join(damaged))
    (tmp_path / "ref").mkdir()
    ref = tmp_path / "ref" / "readings.csv"
    ref.write_text("".join(lines[:i] + lines[i + 1:]))
    res = calibrate_cli(f, proto, tmp_path / "o", capsys)
    without = calibrate_cli(ref, proto, tmp_path / "w", capsys)
    fd = [x for x in res["findings"] if x["line"] == i + 1]
    assert [(x["code"], x["action"], x["column"]) for x in fd] == [
        ("indicated-angle-outlier", "set_aside", "gyro_counts")]
    # besides, only the statements of what the median rule could not see in the three 7.1
    # readings and the four of 7.6 and 7.7 (tests/test_ogam_71_median_rule.py,
    # tests/test_ogam_consistency_median_rule.py)
    assert [(x["code"], x["clause"]) for x in res["findings"] if x["line"] != i + 1] == [
        ("readings-not-judged", c) for c in ("7.1", "7.6", "7.7")]
    for key in ("repeatability", "angle_deviation"):
        assert res["items"][key]["value"] == pytest.approx(without["items"][key]["value"],
                                                           rel=1e-12)
    assert "1 reading(s) set aside" in page_text(tmp_path / "o")


@pytest.mark.parametrize("bench, seed", [("fog", 3), ("rlg", 11)])
def test_clean_built_in_programme_on_each_bench_has_no_finding(tmp_path, bench, seed):
    """The round-by-round rule follows the data's spread: no good reading set aside."""
    from gonio.specs.ogam_draft.protocol import load_protocol
    from gonio.specs.ogam_draft.readings import read_readings
    from gonio.specs.ogam_draft.screen import screen
    assert main(["simulate", "--bench", bench, "--seed", str(seed), "--out",
                 str(tmp_path / "s")]) == 0
    found = screen(read_readings(tmp_path / "s" / "readings.csv"), load_protocol("ogam-draft"))
    assert [f.message for f in found] == []


def test_a_missing_and_a_late_7_3_reading_are_flagged(three_rates, tmp_path, capsys):
    """7.3 against the protocol's schedule (small protocol: 4 readings 20 s apart)."""
    proto, clean = three_rates
    f = tmp_path / "miss" / "readings.csv"
    gone = write_without(clean, f, lambda p: p[0] == "zero_stability" and p[2] == "2")
    assert len(gone) == 1
    res = calibrate_cli(f, proto, tmp_path / "o1", capsys)
    fd = [x for x in res["findings"] if x["clause"] == "7.3"]
    assert [x["code"] for x in fd] == ["incomplete-programme"]
    assert "3 of the protocol's 4 readings 20 s apart" in fd[0]["message"]
    assert res["items"]["zero_stability"]["details"]["table"][0]["n_readings"] == 3
    assert "round(s) 2 missing" in page_text(tmp_path / "o1")
    lines = clean.read_text().splitlines(keepends=True)
    i = next(n for n, ln in enumerate(lines) if ln.startswith("zero_stability,")
             and ln.split(",")[2] == "3")
    p = lines[i].split(",")
    t = float(p[5])
    p[5] = f"{t + 5.0:g}"                            # a quarter of the 20 s interval late
    f2 = tmp_path / "late" / "readings.csv"
    f2.parent.mkdir()
    f2.write_text("".join(lines[:i] + [",".join(p)] + lines[i + 1:]))
    res = calibrate_cli(f2, proto, tmp_path / "o2", capsys)
    fd = [x for x in res["findings"] if x["clause"] == "7.3"]
    assert [(x["code"], x["line"], x["column"]) for x in fd] == [
        ("off-schedule-reading", i + 1, "time_s")]
    assert f"read at {t + 5.0:g} s, the schedule's {t:g} s" in fd[0]["message"]
    assert "used as read" in page_text(tmp_path / "o2")
    calibrate_cli(f2, proto, tmp_path / "o2zh", capsys, lang="zh")
    assert f"按计划应在 {t:g} s" in page_text(tmp_path / "o2zh")
