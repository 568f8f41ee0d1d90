"""A whole 7.6 or 7.7 condition of the programme missing, through ``gonio calibrate``.

C_v and C_g are ranges of E over the programme's conditions: a range over fewer conditions is
at most as large, so a file with every reading of one condition deleted must not state C (the
reviewer's case: every 1 °/s reading deleted gave "C_v 0.50; ≤ 1.32 ppm" where the complete
file's bound is 3.4 ppm). The item is not measured, the reason names the missing condition, in
results.json, summary.txt, the certificate (en, zh) and the DCC; the screening's finding says
the item is not stated. Each file is written here from a simulated session."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from gonio.cli import main

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "data" / "small-protocol.toml"


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """The small protocol with three 7.6 rates and three 7.7 orientations, simulated."""
    out = tmp_path_factory.mktemp("missing_condition")
    proto = out / "p.toml"
    text = SMALL.read_text().replace("rates_dps = [30.0, 60.0]",
                                     "rates_dps = [10.0, 30.0, 60.0]")
    proto.write_text(text.replace('orientations = ["up", "north"]',
                                  'orientations = ["up", "north", "east"]'))
    assert main(["simulate", "--protocol", str(proto), "--seed", "2413", "--out",
                 str(out / "sim")]) == 0
    return proto, out / "sim" / "readings.csv"


def write_without(src: Path, dst: Path, drop) -> int:
    keep, n = [], 0
    for ln in src.read_text().splitlines(keepends=True):
        if not ln.startswith("#") and drop(ln.split(",")):
            n += 1
            continue
        keep.append(ln)
    dst.parent.mkdir(parents=True, exist_ok=True)
    dst.write_text("".join(keep))
    return n


def calibrate(f: Path, proto: Path, out: Path, capsys, lang="en") -> dict:
    capsys.readouterr()
    assert main(["calibrate", str(f), "--protocol", str(proto), "--out", str(out),
                 "--lang", lang, "--dcc"]) == 0
    capsys.readouterr()
    return json.loads((out / "results.json").read_text())


def page(out: Path) -> str:
    return re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", (out / "certificate.html").read_text()))


CASES = [("rate_consistency", "10.0", "up", "10 deg/s", "C_v", "2 of 3"),
         ("pointing_consistency", "60.0", "east", "axis east", "C_g", "2 of 3")]


@pytest.mark.parametrize("test, rate, orient, named, sym, count", CASES)
def test_a_whole_condition_missing_leaves_the_item_not_measured(session, tmp_path, capsys,
                                                                test, rate, orient, named,
                                                                sym, count):
    proto, clean = session
    full = calibrate(clean, proto, tmp_path / "clean", capsys)
    assert full["items"][test]["measured"]
    # the range over the conditions left is a number, smaller or equal: the item must not
    # be stated from it
    conds = full["items"][test]["details"]["table"]
    assert len(conds) == 3
    f = tmp_path / "in" / "readings.csv"
    n = write_without(clean, f, lambda p: p[0] == test and (p[3], p[4]) == (rate, orient))
    assert n >= 4
    res = calibrate(f, proto, tmp_path / "en", capsys)
    item = res["items"][test]
    assert not item["measured"] and item["value"] is None
    assert named in item["reason"] and f"({count} conditions read)" in item["reason"]
    assert "every condition of the programme" in item["reason"]
    assert not item.get("uncertainty")
    found = [x["message"] for x in res["findings"] if x.get("test") == test]
    assert any("has no reading" in m and "the item is not stated" in m for m in found), found
    summary = (tmp_path / "en" / "summary.txt").read_text()
    row = next(ln for ln in summary.splitlines() if f" {sym} " in ln and "7." in ln)
    assert "not measured" in row, row
    assert named in summary
    text = page(tmp_path / "en")
    assert f"not measured: {item['reason'][:40]}" in text
    dcc = (tmp_path / "en" / "certificate.dcc.xml").read_text()
    assert named in dcc
    # the other items do not move
    for other in ("scale_factor", "angle_deviation", "repeatability"):
        assert res["items"][other]["value"] == full["items"][other]["value"]


def test_the_missing_condition_in_chinese(session, tmp_path, capsys):
    proto, clean = session
    f = tmp_path / "in" / "readings.csv"
    write_without(clean, f, lambda p: p[0] == "rate_consistency" and p[3] == "10.0")
    calibrate(f, proto, tmp_path / "zh", capsys, lang="zh")
    text = page(tmp_path / "zh")
    assert "10 °/s 没有读数（校准方案 3 个测量条件中仅读得 2 个）" in text
    assert "该项目不予给出（7.6 要求在校准方案的每个测量条件下比较 E）" in text
    assert "compares E at every" not in text and "has no reading" not in text


def test_the_items_take_the_programme_given_and_the_conditions_read_without_one():
    """compute_characteristics: with the programme's rates a missing rate is named; without
    a programme (the items alone) the conditions read are the programme."""
    import pandas as pd

    from gonio.specs.ogam_draft.items import compute_characteristics

    rows = []
    for rate, g in ((60.0, 360.0001), (10.0, 359.9999), (30.0, 360.0)):
        rows.append({"test": "rate_consistency", "series": 1, "round": 1, "rate_dps": rate,
                     "orientation": "up", "time_s": 5.0, "table_deg": 360.0, "gyro_deg": g,
                     "gyro_counts": float("nan"), "line": len(rows) + 2})
    df = pd.DataFrame(rows)
    free = compute_characteristics(df).rate_consistency
    assert free.measured and free.value == pytest.approx(0.72 / (360.0001 * 3600) * 1e6)
    planned = compute_characteristics(df, rates_dps=(1.0, 10.0, 30.0, 60.0)).rate_consistency
    assert not planned.measured and "1 deg/s has no reading (3 of 4" in planned.reason
    ok = compute_characteristics(df, rates_dps=(10.0, 30.0, 60.0)).rate_consistency
    assert ok.measured and ok.value == free.value
