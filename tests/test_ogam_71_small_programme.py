"""7.1 in a small programme (7.4 in fewer than 5 series: no repeated-reference prior), from the
outside: ``gonio simulate --protocol`` then ``gonio calibrate`` with 1, 2 and 3 typos planted
in the six 7.1 readings.

Without the prior the six readings are judged against each other's line (ν = 3): one typo is
found (and refuses: 7.1 reads each stop once), but two or more hide one another — before this
rule 2″ at 60° and 180° gave exit 0, no finding, K_l 0.00098 % and E 2.6″ (clean ≤ 0.00033 %,
0.2″). ``reference_agreement`` judges them together against 7.4's repetitions of the same
stops (an F test), and where no such reference exists names them as judged only against one
another. The F value is checked against numpy least squares and hand-pooled variances.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from scipy.stats import f as fisher_f

from gonio.cli import main
from gonio.specs.ogam_draft.readings import read_readings

STOPS = "[{stop_deg = 60.0}, {stop_deg = 120.0}, {stop_deg = 180.0}, {stop_deg = 240.0}, " \
        "{stop_deg = 300.0}, {stop_deg = 360.0}]"


def _protocol(path, series: int, stops74: str = STOPS):
    path.write_text(f"""[protocol]
name = "small-{series}"
[session]
static_s = 30.0
[scale_factor]
rest_s = 15.0
rounds = {STOPS}
[zero_stability]
readings = 4
interval_s = 20.0
[angle_deviation]
series = {series}
rest_s = 15.0
rounds = {stops74}
[rate_consistency]
rates_dps = [30.0, 60.0]
rest_s = 15.0
[pointing_consistency]
orientations = ["up", "north"]
rest_s = 15.0
""", encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    """seed 5 of the rlg bench, 7.4 in 3 series at 7.1's six stops."""
    out = tmp_path_factory.mktemp("small71")
    proto = _protocol(out / "p3.toml", 3)
    assert main(["simulate", "--protocol", str(proto), "--seed", "5", "--out",
                 str(out / "sim")]) == 0
    return out, proto, out / "sim" / "readings.csv"


def _plant(src, dst, plants, k=76434.87):
    """``plants``: {7.1 round: arcsec}, as whole counts; returns {round: line}."""
    lines = src.read_text().splitlines(keepends=True)
    where = {}
    for n, ln in enumerate(lines):
        p = ln.rstrip("\n").split(",")
        if p[0] == "scale_factor" and int(p[2]) in plants:
            p[7] = str(int(p[7]) + round(plants[int(p[2])] / 3600.0 * k))
            lines[n] = ",".join(p) + "\n"
            where[int(p[2])] = n + 1
    dst.parent.mkdir(parents=True, exist_ok=True)
    dst.write_text("".join(lines))
    return where


def _calibrate(readings, proto, out, capsys):
    capsys.readouterr()
    rc = main(["calibrate", str(readings), "--protocol", str(proto), "--out", str(out)])
    return rc, capsys.readouterr().err


def _f_by_hand(readings_csv, lines_kept):
    """F of the 7.1 readings against 7.4's round means, by numpy alone: counts / K_ref
    (median of counts / table over the rotation readings) less the table angle, ″; the 7.4
    rounds' means and Bessel variance pooled over rounds; the 7.1 residuals about
    np.polyfit's line."""
    r = read_readings(readings_csv)
    df = r.data
    rot = df[df["test"] != "zero_stability"]
    k_ref = float(np.median(rot["gyro_counts"] / rot["table_deg"]))
    arc = (df["gyro_counts"] / k_ref - df["table_deg"]) * 3600.0
    ad = df[(df["test"] == "angle_deviation") & (df["rate_dps"] == 60.0)
            & (df["orientation"] == "up")]
    a = arc[ad.index]
    means = a.groupby(ad["round"]).mean()
    ss = float(((a - a.groupby(ad["round"]).transform("mean")) ** 2).sum())
    nu0 = len(a) - len(means)
    n = int(ad.groupby("round").size().min())
    sf = df[(df["test"] == "scale_factor") & df["line"].isin(lines_kept)]
    d = arc[sf.index].to_numpy() - means.loc[sf["round"]].to_numpy()
    x = sf["table_deg"].to_numpy()
    e = d - np.polyval(np.polyfit(x, d, 1), x)
    ratio = float(e @ e) / (len(x) - 2) / (ss / nu0 * (1 + 1 / n))
    return ratio, len(x) - 2, nu0


def test_clean_small_programme_calibrates_with_no_71_finding(sim, tmp_path, capsys):
    out, proto, clean = sim
    rc, err = _calibrate(clean, proto, tmp_path / "c", capsys)
    assert rc == 0, err
    res = json.loads((tmp_path / "c" / "results.json").read_text())
    assert [f for f in res["findings"] if f.get("test") == "scale_factor"] == []


def test_one_typo_is_refused_by_the_condition_rule(sim, tmp_path, capsys):
    out, proto, clean = sim
    where = _plant(clean, tmp_path / "r.csv", {1: 2.0})
    rc, err = _calibrate(tmp_path / "r.csv", proto, tmp_path / "c", capsys)
    assert rc == 2 and f":{where[1]}:" in err and "7.1 reading set aside" in err


@pytest.mark.parametrize("plants", [{1: 2.0, 3: 2.0}, {1: 1.0, 2: 1.0}, {1: 3.0, 4: -3.0},
                                    {1: 2.0, 3: 2.0, 5: 2.0}, {2: 10.0, 4: 10.0, 6: 10.0}])
def test_two_or_three_typos_are_refused_naming_them(sim, tmp_path, capsys, plants):
    """Before: exit 0 and no finding for every one of these (K_l and E certified from them)."""
    out, proto, clean = sim
    where = _plant(clean, tmp_path / "r.csv", plants)
    rc, err = _calibrate(tmp_path / "r.csv", proto, tmp_path / "c", capsys)
    assert rc == 2, err
    assert "disagree with 7.4's repetitions of the same stops" in err
    assert not (tmp_path / "c" / "results.json").exists()
    head = err.split("): lines ", 1)[1]
    named = [int(x) for x in re.findall(r"(\d+) \([+-]", head)]
    # the largest departures are planted readings (the others only follow the line's pull)
    assert named[0] in where.values(), (named, where)
    ratio, dof, nu0 = _f_by_hand(tmp_path / "r.csv", list(range(1, 10_000)))
    assert ratio > fisher_f.isf(0.02, dof, nu0)


def test_the_f_value_is_the_one_numpy_computes(sim, tmp_path, capsys):
    """The refusal's F and its critical value against a second computation (numpy's line,
    pooled variances by hand); a mutated formula (1/n dropped, ν of the line) fails it."""
    out, proto, clean = sim
    _plant(clean, tmp_path / "r.csv", {1: 2.0, 3: 2.0})
    from gonio.specs.ogam_draft.readings import Readings
    from gonio.specs.ogam_draft.protocol import load_protocol
    from gonio.specs.ogam_draft.screen import screen
    r = read_readings(tmp_path / "r.csv")
    found = [f for f in screen(r, load_protocol(proto))
             if f.code == "readings-disagree-with-reference"]
    assert len(found) == 1 and found[0].action == "refused"
    m = re.search(r"F = (\S+) > (\S+), ν = (\d+), (\d+)\)", found[0].message)
    ratio, dof, nu0 = _f_by_hand(tmp_path / "r.csv", list(range(1, 10_000)))
    assert (int(m.group(3)), int(m.group(4))) == (dof, nu0) == (4, 12)
    assert float(m.group(1)) == pytest.approx(ratio, rel=5e-3)
    n_groups = 4            # 7.1, 7.4 (3 series: the line rule), 7.6 at 30 °/s, 7.7 north
    assert float(m.group(2)) == pytest.approx(fisher_f.isf(0.02 / n_groups, dof, nu0),
                                              rel=5e-3)
    assert isinstance(Readings, type)


def test_without_a_repeated_reference_the_71_readings_are_named(tmp_path, capsys):
    """7.4 at other stops (90°, 180°, 270°, 360°): no reference for 60°, 120°, …: the
    certificate and results.json say which readings were judged only against one another."""
    proto = _protocol(tmp_path / "p.toml", 3, "[{stop_deg = 90.0}, {stop_deg = 180.0}, "
                      "{stop_deg = 270.0}, {stop_deg = 360.0}]")
    assert main(["simulate", "--protocol", str(proto), "--seed", "5", "--out",
                 str(tmp_path / "sim")]) == 0
    rc, err = _calibrate(tmp_path / "sim" / "readings.csv", proto, tmp_path / "c", capsys)
    assert rc == 0, err
    res = json.loads((tmp_path / "c" / "results.json").read_text())
    fl = [f for f in res["findings"] if f["code"] == "readings-not-judged"
          and f["clause"] == "7.1"]     # 7.6 and 7.7: test_ogam_consistency_median_rule
    df = read_readings(tmp_path / "sim" / "readings.csv").data
    lines = df.loc[df["test"] == "scale_factor", "line"].astype(int).tolist()
    assert len(fl) == 1 and fl[0]["action"] == "flagged" and fl[0]["clause"] == "7.1"
    assert f"lines {', '.join(map(str, lines))} judged only against one another" in \
        fl[0]["message"]
    html = (tmp_path / "c" / "certificate.html").read_text(encoding="utf-8")
    assert "judged only against one another" in html
