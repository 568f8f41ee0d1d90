"""The records' calibration page states the conformity decisions its stored result holds.

A JJF 1535-2015 run of the virtual bench (``gonio simulate --seed 3``) is calibrated with a
laboratory file that gives limits and a non-binary decision rule (``gonio calibrate --lab
FILE --record --data DIR``, SQLite), and its page ``/calibrations/N`` read through the
application. Checked against the stored results.json and the laboratory file, not against
the page's own renderer:

- one row per item results.json decided, in its order, and none for an item without limits;
- the decision is the stored outcome;
- the limits are the laboratory file's numbers as it wrote them;
- the acceptance interval's ends are the stored acceptance limits rounded inward (never
  wider than the one decided on), or "none" exactly where the stored decision says the
  guard bands empty it;
- the guard band is the stored w as decided, exactly (w = r·U of printed numbers: six
  significant digits, half up, clear the floating point's tail; an independent Decimal
  rounding), as the certificate's guard-band note derives it.
"""

from __future__ import annotations

import html as html_module
import json
import re
from decimal import ROUND_HALF_UP, Decimal
from pathlib import Path

import pytest

from gonio.cli import main
from gonio.report.i18n import labels

REPO = Path(__file__).resolve().parents[2]
EXAMPLE = (REPO / "protocols" / "lab-example.toml").read_text(encoding="utf-8")

#: the limits the laboratory file gives: (item, TOML lines)
LIMITS = (("scale_factor", "lower = 5.997\nupper = 6.003"), ("nonlinearity", "mpe = 0.0004"),
          ("sf_repeatability", "upper = 0.001"), ("sf_temperature_sensitivity", "mpe = 0.00016"),
          ("threshold", "upper = 0.05"), ("bias", "mpe = 1000"), ("warmup_time", "upper = 30"),
          ("bias_stability", "upper = 60"), ("g_sensitivity", "mpe = 230"))
_SUP = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹−", "-0123456789-")
_NUMBER = re.compile(r"[−-]?\d+(?:\.\d+)?(?:×10[⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+)?")


def lab_toml(readings: Path) -> str:
    """The example laboratory file naming the simulated instrument and room (the identity
    check compares them with the readings), with a non-binary rule and :data:`LIMITS`."""
    from gonio.formats.provenance import readings_metadata

    md = readings_metadata(readings)
    head = EXAMPLE[:EXAMPLE.index("\n[[specification_limits]]")]
    for key in ("model", "serial", "manufacturer"):
        if md.get(key):
            head = re.sub(rf'(?m)^{key} = ".*"$', f'{key} = "{md[key]}"', head, count=1)
    if md.get("temperature_c"):
        head = re.sub(r"(?m)^temperature_c = .*$", f"temperature_c = {md['temperature_c']}",
                      head, count=1)
    head = re.sub(r'(?m)^rule = ".*"$', 'rule = "non-binary"', head, count=1)
    return head + "".join(f'\n[[specification_limits]]\nitem = "{k}"\n{v}\nsource = "spec"\n'
                          for k, v in LIMITS)


def number(text: str) -> Decimal:
    """A number as the page prints it ("−0.00016", "6.2×10⁻⁵") as a Decimal."""
    m, _, e = text.translate(_SUP).partition("×10")
    return Decimal(m).scaleb(int(e) if e else 0)


def ulp(text: str) -> Decimal:
    """One unit of the last printed digit of a number as printed."""
    return Decimal(1).scaleb(number(text).as_tuple().exponent)


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    """The calibration page (its conformity rows), results.json and the laboratory file."""
    from gonio.records import services
    from gonio.records.db import open_store

    from .conftest import PASSWORD, make_people
    from .test_web_numbers import web_client

    root = tmp_path_factory.mktemp("conformity")
    sim, data = root / "sim", root / "data"
    assert main(["simulate", "--spec", "jjf1535-2015", "--seed", "3", "--out", str(sim)]) == 0
    lab = root / "lab.toml"
    lab.write_text(lab_toml(sim / "readings.csv"), encoding="utf-8")
    store = open_store(None, data)
    assert store.engine.dialect.name == "sqlite"
    tech = make_people(store)["tech"]
    services.add_standard(store, tech, name="rotary table", identifier="RT-07",
                          due_on="2099-01-01")
    store.close()
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("GONIO_PASSWORD", PASSWORD)
        assert main(["calibrate", str(sim / "readings.csv"), "--lab", str(lab), "--record",
                     "--data", str(data), "--record-user", "tech",
                     "--out", str(root / "out")]) == 0
    store = open_store(None, data)
    try:
        cal = services.calibration(store, 1)
        doc = json.loads(services.file_bytes(store, cal.results_sha256))
        client = web_client(store)
        text = client.get("/calibrations/1").text
        text_zh = client.get("/calibrations/1?lang=zh").text
    finally:
        store.close()
    table = re.search(r'<table id="conformity">(.*?)</table>', text, re.S)
    assert table, "the page shows no statement of conformity"
    rows = [(key, [html_module.unescape(re.sub(r"<[^>]+>", "", c)) for c in
                   re.findall(r"<td[^>]*>(.*?)</td>", body, re.S)])
            for key, body in re.findall(r'<tr data-item="([^"]+)">(.*?)</tr>', table.group(1),
                                        re.S)]
    return {"rows": rows, "doc": doc, "text": text, "text_zh": text_zh}


def test_the_page_shows_the_decisions_results_json_holds(page):
    decided = {k: it["conformity"] for k, it in page["doc"]["items"].items()
               if it.get("conformity")}
    assert [k for k, _ in page["rows"]] == list(decided) == [k for k, _ in LIMITS]
    L = labels("en")
    outcomes = []
    for key, (title, outcome, *_rest) in page["rows"]:
        c = decided[key]
        assert title == page["doc"]["items"][key]["title"]
        assert outcome.split(" (")[0] == L[c["outcome"]], (key, outcome, c["outcome"])
        outcomes.append(c["outcome"])
    assert "conditional fail" in outcomes, outcomes      # the case the reviewer could not see


def test_limits_are_the_laboratory_files(page):
    given = {k: v for k, v in LIMITS}
    for key, cells in page["rows"]:
        shown = [number(x) for x in _NUMBER.findall(cells[2])][:2]
        lines = dict(x.split(" = ") for x in given[key].splitlines())
        if "mpe" in lines:
            want = [-Decimal(lines["mpe"]), Decimal(lines["mpe"])]
        else:
            want = [Decimal(lines[x]) for x in ("lower", "upper") if x in lines]
        assert shown[:len(want)] == want, (key, cells[2], want)


def test_acceptance_interval_and_guard_band_as_decided(page):
    for key, cells in page["rows"]:
        c = page["doc"]["items"][key]["conformity"]
        acc, band = cells[3], cells[4]
        empty = c.get("acceptance_empty") or (
            c["acceptance_lower"] is not None and c["acceptance_upper"] is not None
            and c["acceptance_lower"] > c["acceptance_upper"])
        assert acc.startswith("none") == bool(empty), (key, acc, c)
        if not empty:
            ends = _NUMBER.findall(acc)
            want = [(x, c[f"acceptance_{x}"]) for x in ("lower", "upper")
                    if c[f"acceptance_{x}"] is not None]
            assert len(ends) >= len(want), (key, acc)
            for (side, stored), printed in zip(want, ends):
                p, s = number(printed), Decimal(repr(stored))
                inward = s - p if side == "upper" else p - s     # never wider than decided
                assert Decimal(0) <= inward < ulp(printed), (key, side, printed, stored)
        w = Decimal(repr(c["guard_band"]))
        e = w.adjusted() - 5                                   # the w decided, exactly
        assert number(band.split(" ")[0]) == w.quantize(Decimal(1).scaleb(e),
                                                         ROUND_HALF_UP), (key, band, w)


def test_the_chinese_page_states_conformity_in_chinese(page):
    """``?lang=zh``: the statement of conformity in Chinese as the zh certificate states it —
    its headings, each item's Chinese name (the specification's ``item_titles``), the outcome
    and the notes; no English item title is left (before: the table and its notes named the
    items by their stored English titles, and its headings were English)."""
    from gonio.specs import get

    text = page["text_zh"]
    table = re.search(r'<table id="conformity">(.*?)</table>', text, re.S)
    assert table
    L = labels("zh")
    for key in ("c_outcome", "c_limits", "c_accept", "c_guard_w", "c_pc", "c_pfa"):
        assert f"<th>{L[key]}</th>" in table.group(1), key
    assert f"<h2>{L['conformity']}</h2>" in text
    titles = get("jjf1535-2015").output_hook("item_titles")(page["doc"], "zh")
    decided = {k: it["conformity"] for k, it in page["doc"]["items"].items()
               if it.get("conformity")}
    for key, body in re.findall(r'<tr data-item="([^"]+)">(.*?)</tr>', table.group(1), re.S):
        cells = [html_module.unescape(re.sub(r"<[^>]+>", "", c))
                 for c in re.findall(r"<td[^>]*>(.*?)</td>", body, re.S)]
        assert cells[0] == titles[key] and re.search(r"[\u4e00-\u9fff]", cells[0]), cells
        assert cells[1].split("（")[0].split(" (")[0] == L[decided[key]["outcome"]], cells
    section = text[text.index('<table id="conformity">'):]
    section = section[:section.index("<h2", 1)] if "<h2" in section else section
    shown = html_module.unescape(re.sub(r"<[^>]+>", " ", section))     # its words, no tags
    for key in decided:
        assert page["doc"]["items"][key]["title"] not in shown, key
