"""Sub-arcsecond typos in the readings of 7.1, 7.3, 7.6 and 7.7, from the outside.

A session of the built-in programme (``gonio simulate``, the RLG bench: counts, 0.047″ a
count) is damaged in one reading's ``gyro_counts`` by 0.5″, 1″ or 2″ (a mistyped digit);
the fixed 5″ floor these tests had let every one of them through. What the screening
finds, and what reaches results.json, the certificate and the command line, is checked.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import beta

from gonio.cli import main
from gonio.formats.toml import read_toml
from gonio.resources import resolve
from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.calibration import analyse
from gonio.specs.ogam_draft.protocol import load_protocol, parse_protocol
from gonio.specs.ogam_draft.readings import Readings, read_readings
from gonio.specs.ogam_draft.screen import (HARMONIC_MIN, SPREAD_FLOOR_STEPS,
                                           line_critical_value, line_departures, screen)
from gonio.specs.ogam_draft.study import study_bench
from gonio.units import ARCSEC_PER_DEG
from tests._helpers import small_ogam_bench, tiny_ogam_protocol

#: (test, rate, orientation, round) of the reading damaged in each clause.
WHERE = {"7.1": ("scale_factor", "60.0", "up", 3),
         "7.3": ("zero_stability", "", "up", 8),
         "7.6": ("rate_consistency", "100.0", "up", 5),
         "7.7": ("pointing_consistency", "60.0", "north", 7)}


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    out = tmp_path_factory.mktemp("subarc")
    assert main(["simulate", "--seed", "5", "--out", str(out / "sim")]) == 0
    f = out / "sim" / "readings.csv"
    assert screen(read_readings(f), load_protocol("ogam-draft")) == []
    return f


def nominal_k(lines) -> float:
    return float(next(ln for ln in lines if ln.startswith(
        "# nominal_scale_factor_counts_per_deg:")).split(":")[1])


def damaged(src: Path, dst: Path, clause: str, size_arcsec: float) -> int:
    """``src`` with the reading of ``WHERE[clause]`` moved by ``size_arcsec`` in its counts
    (the nearest whole count); returns its line number (1-based)."""
    test, rate, orient, rnd = WHERE[clause]
    lines = src.read_text().splitlines(keepends=True)
    i = next(n for n, ln in enumerate(lines) if ln.split(",")[:5] == [
        test, "1", str(rnd), rate, orient])
    p = lines[i].rstrip("\n").split(",")
    p[7] = str(int(p[7]) + round(size_arcsec / ARCSEC_PER_DEG * nominal_k(lines)))
    lines[i] = ",".join(p) + "\n"
    dst.parent.mkdir(parents=True, exist_ok=True)
    dst.write_text("".join(lines))
    return i + 1


@pytest.mark.parametrize("clause, size", [("7.6", 1.0), ("7.6", 2.0), ("7.7", 2.0), ("7.7", 5.0),
                                          ("7.1", 1.0), ("7.1", 2.0), ("7.3", 3.0)])
def test_a_one_and_two_arcsec_typo_is_found_on_its_line(session, tmp_path, clause, size):
    """7.3's rest wanders from the line through a reading's neighbours as the bias does:
    its rule keeps what 3 × the draft's zero-stability bound allows over half the 5-min
    spacing (2.25″); 3″ is set aside, which the former 5″ floor let through. 7.1's six
    positions alone leave its scale 3 degrees of freedom (c ≈ 18.7, a threshold near 1.5″
    on the RLG, where 1″ went through); pooled with the scatter of 7.4's ten repetitions of
    the same stops (ν ≈ 108, c ≈ 3.8) its threshold is ~0.5″: 1″ is found. 7.7 at 1″ is
    caught in 28 of 40 RLG sessions (docs/draft-readings.md, the typo sweep): a property of
    the rule's power, not of this file, so 7.7 is planted at 2″ and 5″ (40 of 40)."""
    f = tmp_path / "readings.csv"
    line = damaged(session, f, clause, size)
    found = [x for x in screen(read_readings(f), load_protocol("ogam-draft"))
             if x.action != "flagged"]
    assert [(x.line, x.column, x.clause, x.code) for x in found] == [
        (line, "gyro_counts", clause, "indicated-angle-outlier")]
    assert f"{SPREAD_FLOOR_STEPS:g} steps of resolution" in found[0].rule
    # the threshold it broke is printed, and is the rule's, not the old 5″ floor
    thr = float(re.search(r"(?:> |threshold )([0-9.]+)″", found[0].message).group(1))
    assert thr < 5.0




@pytest.mark.parametrize("clause", ["7.6", "7.7"])
def test_a_typo_in_a_round_read_once_refuses_naming_line_and_column(session, tmp_path,
                                                                    capsys, clause):
    """7.6 and 7.7 read each position once and compare the conditions over the same
    positions: setting the reading aside would drop a position, so the calibration is
    refused with the line and column, and nothing is written. (7.1's reading is set aside:
    ``test_a_7_1_typo_is_set_aside_and_k_rests_on_the_other_rounds``.)"""
    f = tmp_path / "in" / "readings.csv"
    # 5″: caught in 39-40 of 40 sessions of the typo sweep (1″: 28-32 of 40)
    line = damaged(session, f, clause, 5.0)
    capsys.readouterr()
    assert main(["calibrate", str(f), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert f"readings.csv:{line}:" in err and "gyro_counts" in err
    assert f"{clause} reading set aside" in err and "cannot stand without it" in err
    assert not (tmp_path / "o" / "results.json").exists()


def test_a_7_1_typo_is_set_aside_and_k_rests_on_the_other_rounds(session, tmp_path, capsys):
    """A 7.1 reading that disagrees with 7.4's ten readings of the same stop is set aside
    (the position is known from them); K rests on the five other rounds, which the
    certificate says, and K_l (the range over every round of the programme) is not stated."""
    f = tmp_path / "in" / "readings.csv"
    line = damaged(session, f, "7.1", 2.0)
    capsys.readouterr()
    assert main(["calibrate", str(f), "--out", str(tmp_path / "o")]) == 0
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    assert [(x["line"], x["clause"]) for x in res["findings"] if x["action"] != "flagged"] \
        == [(line, "7.1")]
    assert line in {u["line"] for u in res["unused_readings"]}
    assert len(res["items"]["scale_factor"]["details"]["table"]) == 5
    assert not res["items"]["scale_factor_nonlinearity"]["measured"]
    page = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ",
                                      (tmp_path / "o" / "certificate.html").read_text()))
    assert f"line {line}:" in page and "rests on 5 of the programme" in page


def test_a_7_3_typo_is_set_aside_and_named_on_the_certificate(session, tmp_path, capsys):
    f = tmp_path / "in" / "readings.csv"
    line = damaged(session, f, "7.3", 3.0)
    capsys.readouterr()
    assert main(["calibrate", str(f), "--out", str(tmp_path / "o")]) == 0
    err = capsys.readouterr().err
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    fd = [x for x in res["findings"] if x["action"] != "flagged"]
    assert [(x["line"], x["column"], x["clause"]) for x in fd] == [(line, "gyro_counts", "7.3")]
    assert line in {u["line"] for u in res["unused_readings"]}
    assert res["extra"]["screening"]["set_aside_readings"] == 1
    assert res["items"]["zero_stability"]["details"]["table"][0]["n_readings"] == 14
    page = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ",
                                      (tmp_path / "o" / "certificate.html").read_text()))
    assert "1 reading(s) set aside" in page and f"line {line}:" in page
    assert "gyro_counts" in page and "departs from the line through its neighbours" in page
    assert str(line) in err


# --- the condition rule's small-sample factor ---------------------------------------------

def _deleted_t(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Each reading's externally studentized residual from the full least-squares fit, by
    the closed form e_j / (s_(j) √(1 − h_jj)), s_(j)² = (Σe² − e_j²/(1 − h_jj)) / (n − p − 1)
    (no refit: a second algorithm beside the rule's leave-one-out fits). ``y``: samples ×
    n."""
    n, p = X.shape
    H = X @ np.linalg.pinv(X.T @ X) @ X.T
    e = y - y @ H.T
    h = np.diag(H)
    s2 = ((e ** 2).sum(axis=1, keepdims=True) - e ** 2 / (1 - h)) / (n - p - 1)
    return e / np.sqrt(s2 * (1 - h))


def _design(n: int) -> np.ndarray:
    x = np.arange(1, n + 1) * 360.0 / n
    cols = [np.ones(n), x / 360.0]
    if n - 1 >= HARMONIC_MIN:
        cols += [np.cos(np.radians(x)), np.sin(np.radians(x))]
    return np.column_stack(cols)


@pytest.mark.parametrize("n", [6, 12])
def test_the_critical_value_against_a_monte_carlo_of_normal_readings(n):
    """c = t_ν⁻¹(1 − α/(2n)): one reading's deleted residual exceeds it with probability
    α/n and the largest of n with at most α (Bonferroni), checked on 40 000 groups of
    normal readings (6 positions on a line: ν = 3; 12 with cos θ, sin θ: ν = 7)."""
    X = _design(n)
    nu = n - 1 - X.shape[1]
    alpha = 0.3
    c = line_critical_value(n, nu, alpha)
    t = np.abs(_deleted_t(X, np.random.default_rng(n).standard_normal((40_000, n))))
    one = float((t > c).mean())
    se = math.sqrt(alpha / n * (1 - alpha / n) / t.size) * math.sqrt(n)  # within-group cor.
    assert abs(one - alpha / n) < 4 * se, (one, alpha / n)
    worst = float((t.max(axis=1) > c).mean())
    assert 0.8 * alpha < worst <= alpha + 4 * math.sqrt(alpha * (1 - alpha) / t.shape[0])


def test_the_rule_sets_aside_a_clean_normal_group_at_most_at_its_rate():
    """line_departures on 3 000 groups of six normal readings on a line (ν = 3, no floor):
    groups with a reading set aside ≤ α = 1 % (Clopper–Pearson); the former fixed 7 · s
    set aside one in ~30 such groups."""
    X = _design(6)
    x = X[:, 1] * 360.0
    rng = np.random.default_rng(20261204)
    hits = sum(bool(line_departures(x, rng.standard_normal(6), 0.0, alpha=0.01))
               for _ in range(3000))
    lo = float(beta.ppf(0.025, hits, 3000 - hits + 1)) if hits else 0.0
    assert lo <= 0.01, hits


def small_programme(series: int, positions: int):
    """The built-in protocol with every item, 7.1, 7.4, 7.6, 7.7 read in ``series`` series
    at ``positions`` equally spaced stops (7.6 and 7.7 on 7.4's rounds)."""
    raw = read_toml(resolve("ogam-draft", "protocol"))
    step = 360.0 / positions
    for key in ("scale_factor", "angle_deviation"):
        raw[key]["rounds"] = [r for r in raw[key]["rounds"]
                              if abs(r["stop_deg"] / step - round(r["stop_deg"] / step)) < 1e-9]
    for key in ("scale_factor", "angle_deviation", "rate_consistency", "pointing_consistency"):
        raw[key]["series"] = series
    return parse_protocol(raw, resolve("ogam-draft", "protocol"))


def _sim(protocol, bench, seed):
    res = run_session(protocol, bench, seed=seed)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    return df, dict(res.metadata), res


@pytest.mark.parametrize("seed", [3340895419, 1, 2, 3, 4])
def test_a_clean_small_programme_calibrates_with_nothing_set_aside(seed):
    """Seed 3340895419 had a good 7.4 reading 1.904″ from the others' line set aside at
    7 · s = 1.06″ (s from five readings' MAD)."""
    p = tiny_ogam_protocol()        # 2 series × 3 positions of 7.4, 7.1 at two stops
    df, md, res = _sim(p, small_ogam_bench(), seed)
    assert [f.message for f in screen(Readings(df, md, None), p)
            if f.action != "flagged"] == []
    a = analyse(Readings(df, md, None), p, budget="draft", static_record=res.static_record)
    assert a.results.angle_deviation.unused is None or not len(a.results.angle_deviation.unused)


@pytest.fixture(scope="module")
def small_rlg():
    p = small_programme(2, 3)
    return p, study_bench(load_bench("rlg"), 100.0)


@pytest.mark.parametrize("seed", [11, 12, 13])
def test_a_5_arcsec_typo_in_a_small_programme_is_caught(small_rlg, seed):
    """2 series × 3 positions on the RLG bench: clean, nothing set aside; 5″ planted in one
    reading of 7.1, of 7.6 at 100 °/s and of 7.7 north is that test's only finding."""
    p, bench = small_rlg
    df, md, _ = _sim(p, bench, seed)
    assert [f.message for f in screen(Readings(df, md, None), p)
            if f.action != "flagged"] == []
    k = float(md["nominal_scale_factor_counts_per_deg"])
    for test, rate, orient in (("scale_factor", 60.0, "up"), ("rate_consistency", 100.0, "up"),
                               ("pointing_consistency", 60.0, "north")):
        i = int(np.flatnonzero((df["test"] == test) & (df["rate_dps"] == rate)
                               & (df["orientation"] == orient) & (df["series"] == 1)
                               & (df["round"] == 2))[0])
        d2 = df.copy()
        d2.at[i, "gyro_counts"] += round(5.0 / ARCSEC_PER_DEG * k)
        found = [f for f in screen(Readings(d2, md, None), p) if f.action != "flagged"]
        assert [(f.line, f.test) for f in found] == [(int(df.at[i, "line"]), test)], \
            [f.message for f in found]


@pytest.mark.parametrize("plants", [((1, 2.0), (2, -2.0)), ((1, 2.0), (2, -1.9), (3, 2.2))])
def test_several_7_1_typos_refuse_naming_their_lines(session, tmp_path, capsys, plants):
    """One 7.1 reading that departs from 7.4's repetitions is set aside; two or three are
    not: the rule judges them one at a time, and once two were gone the third (60° +2″)
    was kept unjudged, and K_l 0.00091 [0.00074, 0.00108] % and E 2.92 [2.10, 3.58]″ were
    certified from it (clean: ≤ 0.00022 %, ≤ 0.66″). The calibration is refused in one line
    naming the lines set aside, and nothing is written."""
    lines = session.read_text().splitlines(keepends=True)
    k = nominal_k(lines)
    for rnd, arcsec in plants:
        i = next(n for n, ln in enumerate(lines)
                 if ln.split(",")[:3] == ["scale_factor", "1", str(rnd)])
        p = lines[i].rstrip("\n").split(",")
        p[7] = str(int(p[7]) + round(arcsec / ARCSEC_PER_DEG * k))
        lines[i] = ",".join(p) + "\n"
    f = tmp_path / "in" / "readings.csv"
    f.parent.mkdir()
    f.write_text("".join(lines))
    capsys.readouterr()
    assert main(["calibrate", str(f), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert "depart from the repeated readings of the same stops" in err, err
    assert "the calibration is refused" in err and "readings.csv:" in err, err
    assert not (tmp_path / "o").exists()
