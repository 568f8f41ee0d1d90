"""Two typos in one condition of 7.6 or 7.7 (the same column, gyro_counts), from the outside.

Each departing reading widens the least-squares fit of the others and hides the other from
the condition rule's leave-one-out stage: on the built-in programme (``gonio simulate``,
RLG bench, seed 3) two +10″ typos at 10 °/s gave exit 0, no finding and C_v 10.2 ppm
[7.8, 12.3] certified (the clean file: ≤ 4.9 ppm); two +100″ typos passed too. The rule now
judges the readings two at a time where one at a time finds nothing
(``screen.pair_departures``); a set-aside 7.6/7.7 reading refuses the calibration (the
conditions are compared over the same positions). Checked here: both lines named, the
departure stated near the planted size (the counts / K planted here), the calibration
refused (exit 2, no results.json), and the pair stage's false-alarm probability on clean
normal readings against its Bonferroni bound (a Monte Carlo with numpy draws).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from gonio.cli import main
from gonio.specs.ogam_draft.protocol import load_protocol
from gonio.specs.ogam_draft.readings import read_readings
from gonio.specs.ogam_draft.screen import pair_departures, screen


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    out = tmp_path_factory.mktemp("twotypos")
    assert main(["simulate", "--seed", "3", "--out", str(out / "sim")]) == 0
    f = out / "sim" / "readings.csv"
    assert [x for x in screen(read_readings(f), load_protocol("ogam-draft"))
            if x.action != "flagged"] == []
    return f


def _plant(src: Path, dst: Path, test: str, cond: str, rounds, arcsec: float):
    """``src`` with ``arcsec`` (in whole counts at the file's nominal K) added to the
    gyro_counts of ``test``'s readings of ``rounds`` at ``cond`` (a rate for 7.6, an
    orientation for 7.7); returns their 1-based line numbers."""
    lines = src.read_text().splitlines(keepends=True)
    k = float(next(ln for ln in lines if ln.startswith(
        "# nominal_scale_factor_counts_per_deg:")).split(":")[1])
    at = []
    for rnd in rounds:
        i = next(n for n, ln in enumerate(lines) if (p := ln.split(","))[0] == test
                 and p[2] == str(rnd) and (p[3] if test == "rate_consistency" else p[4]) == cond)
        p = lines[i].split(",")
        p[7] = str(int(p[7]) + round(arcsec * k / 3600.0))
        lines[i] = ",".join(p)
        at.append(i + 1)
    dst.parent.mkdir(parents=True, exist_ok=True)
    dst.write_text("".join(lines))
    return at


@pytest.mark.parametrize("test, cond, rounds, size", [
    ("rate_consistency", "10.0", (3, 4), 10.0),
    ("rate_consistency", "10.0", (3, 9), -5.0),
    ("pointing_consistency", "north", (3, 9), 10.0),
    ("pointing_consistency", "north", (6, 12), 100.0)])
def test_two_typos_in_one_condition_are_found_and_refuse(clean, tmp_path, capsys, test, cond,
                                                          rounds, size):
    f = tmp_path / "in" / "readings.csv"
    at = _plant(clean, f, test, cond, rounds, size)
    found = [x for x in screen(read_readings(f), load_protocol("ogam-draft"))
             if x.code == "indicated-angle-outlier"]
    assert sorted(x.line for x in found) == at
    clause = "7.6" if test == "rate_consistency" else "7.7"
    for x in found:
        assert x.clause == clause and x.column == "gyro_counts" and x.action == "set_aside"
        dev = float(re.search(r"by (\S+)″ \(>", x.message).group(1))
        # the departure from the others' fit is the planted typo (within the session's
        # scatter and the whole-count rounding)
        assert dev == pytest.approx(abs(size), abs=0.5 + 0.05 * abs(size))
    rc = main(["calibrate", str(f), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert rc == 2 and not (tmp_path / "o" / "results.json").exists()
    assert f"readings.csv:{at[0]}:" in err or f"readings.csv:{at[1]}:" in err


def test_the_pair_stage_false_alarm_probability_is_within_its_bound():
    """Clean groups of 12 normal readings (unit scatter, on the 7.6 positions): the pair
    stage sets a reading aside in at most α of them (Bonferroni, ``pair_departures``)."""
    rng = np.random.default_rng(20261202)
    x = np.arange(30.0, 361.0, 30.0)
    idx = np.arange(x.size)
    alpha, n = 0.2, 300
    hits = sum(bool(pair_departures(x, rng.standard_normal(x.size), idx, np.zeros(x.size),
                                    0.0, 0.0, alpha)[0]) for _ in range(n))
    # ≤ α, with a binomial margin of 3 σ
    assert hits <= n * alpha + 3.0 * math.sqrt(n * alpha * (1 - alpha))
    # and the stage can fire: two 20σ typos are found (c₂ = t_6⁻¹(1 − 0.02/264) ≈ 9.5)
    d = rng.standard_normal(x.size)
    d[[2, 3]] += 20.0
    assert sorted(k for k, *_ in pair_departures(x, d, idx, np.zeros(x.size), 0.0, 0.0,
                                                 0.02)[0]) == [2, 3]
