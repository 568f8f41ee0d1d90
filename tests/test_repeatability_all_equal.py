"""The optical repeatability R (draft 7.5) from series that agree to the last count at every
point: not measured, said why, in every output — before, "R = 0.00″" was certified with no
interval and no probability (results.json kept [0, 0] and "p = 95 %"), as the rate
specifications refuse a record with one output in every sample. The angle deviation E of the
same readings is still measured."""

from __future__ import annotations

import json
import shutil

import pandas as pd

from gonio.cli import main

SMALL = "tests/data/small-protocol.toml"


def _copied_series(src, dst):
    """``src``'s readings with every angle_deviation round's counts those of its first series
    (a column filled down), written to ``dst``."""
    lines = src.read_text(encoding="utf-8").splitlines(True)
    head = [x for x in lines if x.startswith("#")]
    df = pd.read_csv(src, comment="#", keep_default_na=False, dtype=str)
    m = df["test"] == "angle_deviation"
    df.loc[m, "gyro_counts"] = df[m].groupby("round")["gyro_counts"].transform("first")
    with open(dst, "w", encoding="utf-8", newline="") as f:
        f.writelines(head)
        df.to_csv(f, index=False, lineterminator="\n")


def test_series_equal_to_the_count_are_no_repeatability(shared_simulation, tmp_path, capsys):
    sim = shared_simulation("ogam-draft", SMALL)
    folder = tmp_path / "in"
    shutil.copytree(sim, folder)
    _copied_series(sim / "readings.csv", folder / "readings.csv")
    assert main(["calibrate", str(folder / "readings.csv"), "--protocol", SMALL, "--out",
                 str(tmp_path / "out")]) == 0
    items = json.loads((tmp_path / "out" / "results.json").read_text())["items"]
    R = items["repeatability"]
    assert not R["measured"] and "R would be certified as 0" in R["reason"], R
    assert items["angle_deviation"]["measured"]
    summary = (tmp_path / "out" / "summary.txt").read_text()
    assert "repeatability R: the series agree to the last digit at every point" in summary
    csv_row = [x for x in (tmp_path / "out" / "tables" / "items.csv").read_text().splitlines()
               if x.startswith("repeatability,")][0]
    assert "0.0" not in csv_row.split(",")[2:4], csv_row
    assert main(["calibrate", str(folder / "readings.csv"), "--protocol", SMALL, "--out",
                 str(tmp_path / "zh"), "--lang", "zh"]) == 0
    html = (tmp_path / "zh" / "certificate.html").read_text(encoding="utf-8")
    assert "R 将被定为 0" in html and "R would be certified as 0" not in html
