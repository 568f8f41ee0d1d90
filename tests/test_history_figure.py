"""The instrument's history figure (gonio serve), written as SVG without Matplotlib: every
point and error bar must sit where the axis ticks printed beside it say its value and date
are (the axes read back from the tick labels, an independent path from the drawing)."""

from __future__ import annotations

import datetime as dt
import random
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from gonio.report.history_figure import date_ticks, history_svg, nice_ticks

NS = {"s": "http://www.w3.org/2000/svg"}


def _history(n: int, items: int, seed: int = 1) -> dict:
    r = random.Random(seed)
    return {f"K{j}": [{"date": dt.date(2001, 3, 1) + dt.timedelta(days=r.randint(20, 90) * i),
                       "value": 10.0 ** j * (1 + 0.1 * r.random()), "U": 10.0 ** j * 0.02,
                       "unit": "u", "title": f"item {j} <&>",
                       "status": r.choice(["issued", "computed"])} for i in range(n)]
            for j in range(items)}


def _fit(ticks, attr, value) -> np.ndarray:
    """Pixel = a·value + b from the tick labels' positions (least squares)."""
    pos = np.array([float(t.get(attr)) for t in ticks])
    val = np.array([value(t.get("data-v")) for t in ticks])
    assert len(pos) >= 2
    return np.polyfit(val, pos, 1)


def test_points_and_bars_sit_at_their_values_and_dates():
    hist = _history(100, 7)
    limits = {"K0": (1.0, 1.2), "K3": (None, 1100.0)}
    root = ET.fromstring(history_svg(hist, limits))
    panels = root.findall("s:g[@class='panel']", NS)
    assert [p.get("data-key") for p in panels] == list(hist)
    for panel in panels:
        key = panel.get("data-key")
        rows = hist[key]
        ay, by = _fit(panel.findall("s:text[@class='ytick']", NS), "y", float)
        ax, bx = _fit(panel.findall("s:text[@class='xtick']", NS), "x",
                      lambda v: dt.date.fromisoformat(v).toordinal())
        circles = panel.findall("s:circle[@class='issued']", NS) + \
            panel.findall("s:circle[@class='other']", NS)
        assert len(circles) == len(rows)
        got = sorted(((float(c.get("cx")) - bx) / ax, (float(c.get("cy")) + 3.5 - by) / ay)
                     for c in circles)
        want = sorted((r["date"].toordinal(), r["value"]) for r in rows)
        span = max(r["value"] for r in rows) - min(r["value"] for r in rows)
        for (gd, gv), (wd, wv) in zip(got, want):
            assert abs(gd - wd) < 1.0                     # within a day
            assert abs(gv - wv) < 0.01 * span             # within 1 % of the data's span
        issued = sum(r["status"] == "issued" for r in rows)
        assert len(panel.findall("s:circle[@class='issued']", NS)) == issued
        # each error bar spans 2U
        for bar, r in zip(panel.findall("s:path[@class='bar']", NS), rows):
            v = bar.get("d").split("M")[1]
            y_top, y_bot = float(v.split()[1].split("V")[0]), float(v.split("V")[1])
            assert abs(abs(y_bot - y_top) / abs(ay) - 2 * r["U"]) < 1e-3 * r["U"] + 0.02 / abs(ay)
        lines = panel.findall("s:line[@class='limit']", NS)
        want_lim = [v for v in limits.get(key, (None, None)) if v is not None]
        assert sorted((float(l.get("y1")) + 3.5 - by) / ay for l in lines) == \
            [pytest.approx(v, abs=0.01 * span) for v in sorted(want_lim)]
    assert "item 0 &lt;&amp;&gt;" in history_svg(hist, limits)   # text escaped


def test_empty_history_and_ticks():
    assert "no calibration results yet" in history_svg({}, {})
    assert nice_ticks(0.93, 1.07) == [0.95, 1.0, 1.05]
    ticks, form = date_ticks(dt.date(2020, 2, 3), dt.date(2020, 11, 30))
    assert form == "%Y-%m" and all(t.day == 1 for t in ticks) and 2 <= len(ticks) <= 5
    ticks, form = date_ticks(dt.date(1990, 1, 1), dt.date(2026, 1, 1))
    assert form == "%Y" and 2 <= len(ticks) <= 5


def test_drawn_without_matplotlib():
    code = ("import sys, datetime as dt; from gonio.report.history_figure import history_svg; "
            "history_svg({'K': [{'date': dt.date(2020, 1, 1), 'value': 1.0, 'U': 0.1, "
            "'unit': '', 'title': 'K', 'status': 'issued'}]}); "
            "print('matplotlib' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout.split() == ["False"]


def test_an_item_stated_by_its_interval_is_drawn_with_that_interval():
    """A dispersion stated by its χ² interval [lo, hi] (asymmetric about the value), and a
    non-negative item stated by [0, value + U]: each bar spans that interval, not value ± U
    (which would be a second, different statement of the item)."""
    days = [dt.date(2024, 1, 10), dt.date(2024, 7, 3), dt.date(2025, 2, 1)]
    rows = [{"date": d, "value": v, "U": hi - v, "interval": (lo, hi), "unit": "″",
             "title": "repeatability R", "status": "issued"}
            for d, v, lo, hi in zip(days, (0.112, 0.130, 0.101), (0.066, 0.080, 0.058),
                                    (0.204, 0.230, 0.190))]
    rows.append({"date": dt.date(2025, 8, 1), "value": 0.02, "U": 0.05, "interval": (0.0, 0.07),
                 "unit": "″", "title": "repeatability R", "status": "computed"})
    root = ET.fromstring(history_svg({"R": rows}, {}))
    panel = root.find("s:g[@class='panel']", NS)
    ay, by = _fit(panel.findall("s:text[@class='ytick']", NS), "y", float)
    bars = panel.findall("s:path[@class='bar']", NS)
    assert len(bars) == len(rows)
    for bar, r in zip(bars, rows):
        v = bar.get("d").split("M")[1]
        y_top, y_bot = float(v.split()[1].split("V")[0]), float(v.split("V")[1])
        got = sorted(((y_top + 3.5 - by) / ay, (y_bot + 3.5 - by) / ay))  # tick text: +3.5 px
        assert got == [pytest.approx(x, abs=0.002) for x in r["interval"]], r
