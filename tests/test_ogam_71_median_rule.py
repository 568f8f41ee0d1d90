"""7.1 judged only by the median rule (fewer than 5 readings: tests/data/small-protocol.toml
reads 7.1 at 120°, 240°, 360°), from the outside: ``gonio simulate --protocol`` then
``gonio calibrate`` with a typo of 1″, 3″ and 6″ planted in 7.1's 120° reading.

The median rule's floor is 5″: the 1″ and 3″ typos pass (a 3″ typo at 120° moves E at 360° by
~3″), the 6″ one is refused. What the certificate must now say is the size of typo the screen
could not have seen in this programme: a flagged ``readings-not-judged`` finding in
results.json, summary.txt and on the certificate (en, zh). The stated size is checked against a
brute-force scan of the rule written here (numpy median and MAD on a 0.001″ grid, the
indicated angle computed here from the file: a second computation), and the stated K and K_l
bounds against what the planted typos did to K and K_l.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from gonio.cli import main
from gonio.specs.ogam_draft.readings import read_readings

from tests._helpers import plant_71_counts

SMALL = Path(__file__).resolve().parent / "data" / "small-protocol.toml"
ROT = ("scale_factor", "angle_deviation", "rate_consistency", "pointing_consistency")
#: counts planted on 7.1's 120° reading (76434.87 counts/° on the rlg bench: 21.2 a ″)
PLANTS = {"t1": 21, "t3": 64, "t6": 127}
STATED = re.compile(r"readings at lines ([\d, ]+) judged only by the median rule .*? of up to "
                    r"(\S+)″ \(line (\d+), (\S+)°\) would not have been seen; it would move K "
                    r"by up to (\S+) ppm and K_l by up to (\S+) %")


def _blind_by_scan(path: Path) -> float:
    """The largest typo added to one 7.1 reading (either sign) with which the median rule,
    |r − median| > max(5 · 1.4826 · MAD, 5″), finds nothing, by a scan on a 0.001″ grid;
    r = counts / K_ref − table angle, K_ref the median of counts / table_deg over every
    rotation reading (computed here from the file)."""
    df = read_readings(path).data
    rot = df[df["test"].isin(ROT)]
    k_ref = float(np.median(rot["gyro_counts"].to_numpy(float)
                            / rot["table_deg"].to_numpy(float)))
    g = df[df["test"] == "scale_factor"]
    r = (g["gyro_counts"].to_numpy(float) / k_ref - g["table_deg"].to_numpy(float)) * 3600.0
    grid = np.arange(0.0, 40.0, 0.001)
    best = 0.0
    for i in range(r.size):
        for sign in (1.0, -1.0):
            x = np.repeat(r[None, :], grid.size, axis=0)
            x[:, i] += sign * grid
            med = np.median(x, axis=1)
            dev = np.abs(x - med[:, None])
            thr = np.maximum(5.0 * 1.4826 * np.median(dev, axis=1), 5.0)
            passes = ~(dev > thr[:, None]).any(axis=1)
            best = max(best, float(grid[passes].max()))
    return best


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    out = tmp_path_factory.mktemp("median71")
    assert main(["simulate", "--protocol", str(SMALL), "--seed", "3", "--out",
                 str(out / "sim")]) == 0
    files = {"clean": out / "sim" / "readings.csv"}
    for name, counts in PLANTS.items():
        line, files[name] = plant_71_counts(files["clean"], out / name / "readings.csv",
                                            counts, stop_deg=120.0)
    return out, line, files


def _calibrate(src: Path, out: Path, capsys, *extra):
    rc = main(["calibrate", str(src), "--protocol", str(SMALL), "--out", str(out), *extra])
    return rc, capsys.readouterr().err


def test_typos_under_the_floor_pass_and_the_certificate_states_what_could_not_be_seen(
        small, capsys):
    out, line, files = small
    res, stated = {}, {}
    for name in ("clean", "t1", "t3"):
        rc, err = _calibrate(files[name], out / f"o_{name}", capsys)
        assert rc == 0, err
        res[name] = json.loads((out / f"o_{name}" / "results.json").read_text())
        fl = [f for f in res[name]["findings"] if f["code"] == "readings-not-judged"
              and f["clause"] == "7.1"]   # 7.6 and 7.7: test_ogam_consistency_median_rule
        assert len(fl) == 1 and fl[0]["action"] == "flagged" and fl[0]["clause"] == "7.1"
        assert [f for f in res[name]["findings"] if f["action"] != "flagged"] == []
        m = STATED.search(fl[0]["message"])
        assert m, fl[0]["message"]
        assert m.group(1) == f"{line}, {line + 1}, {line + 2}"
        size = float(m.group(2))
        # stated rounded up to 0.01″; the scan's grid is 0.001″
        assert _blind_by_scan(files[name]) == pytest.approx(size, abs=0.011), name
        assert size >= 5.0                 # never below the rule's floor
        stated[name] = (size, float(m.group(5)), float(m.group(6)))
        # the same words on the certificate and in summary.txt
        summary = (out / f"o_{name}" / "summary.txt").read_text(encoding="utf-8")
        page = (out / f"o_{name}" / "certificate.html").read_text(encoding="utf-8")
        assert f"of up to {m.group(2)}″" in summary and f"of up to {m.group(2)}″" in page
    # the planted typos were within what the screen says it could not see, and what they
    # did to K and K_l is within the stated bounds (K = mean of the three K_i = C_i / θ_i)
    k0 = res["clean"]["items"]["scale_factor"]["value"]
    kl0 = res["clean"]["items"]["scale_factor_nonlinearity"]["value"]
    for name in ("t1", "t3"):
        typo = PLANTS[name] / k0 * 3600.0
        assert typo < stated["clean"][0]
        k = res[name]["items"]["scale_factor"]["value"]
        dk_ppm = abs(k / k0 - 1.0) * 1e6
        assert dk_ppm == pytest.approx(typo / (120.0 * 3600.0) / 3 * 1e6, rel=0.02)
        assert dk_ppm <= stated["clean"][1] * 1.05     # printed to 2 significant digits
        dkl = abs(res[name]["items"]["scale_factor_nonlinearity"]["value"] - kl0)
        assert dkl <= stated["clean"][2] * 1.05
    # the clean file's stated K bound: 5″-ish at 120° of three stops, ≈ 4 ppm
    size, k_ppm, kl_pct = stated["clean"]
    assert k_ppm == pytest.approx(size / (120 * 3600) / 3 * 1e6, rel=0.03)
    assert kl_pct == pytest.approx(size / (120 * 3600) * 100, rel=0.03)


def test_a_six_arcsec_typo_is_refused_naming_its_line(small, capsys):
    out, line, files = small
    rc, err = _calibrate(files["t6"], out / "o_t6", capsys)
    assert rc == 2
    lines = [ln for ln in err.splitlines() if ln.startswith("gonio: error")]
    assert len(lines) == 1 and f"readings.csv:{line}: column gyro_counts" in lines[0]
    assert not (out / "o_t6" / "results.json").exists()


def test_the_statement_on_the_chinese_certificate(small, capsys, tmp_path):
    _, _, files = small
    rc, err = _calibrate(files["clean"], tmp_path / "zh", capsys, "--lang", "zh")
    assert rc == 0, err
    page = (tmp_path / "zh" / "certificate.html").read_text(encoding="utf-8")
    assert "仅按中位数规则判别" in page and "将无法被发现" in page
    assert "judged only by the median rule" not in page
    assert math.isfinite(json.loads((tmp_path / "zh" / "results.json").read_text())
                         ["items"]["scale_factor"]["value"])
