"""One U per item: the guard-band note of an item decided on its interval alone never prints a
second "U" beside the one its results table prints.

The half-width of the printed (outward-rounded) interval that the guard band w is built from
can exceed the item's printed expanded uncertainty in its last digit (M_xy: U = 0.0067,
interval [0.8736, 0.8872], half-width 0.0068). The note names that half-width δ, shows how it
is read off the printed ends, and w stays exactly the decision's. The expected numbers are
worked here from the stored unrounded numbers with :mod:`decimal` (U to two significant
digits half up, ends rounded outward at U's place), never read from gonio's statement.
"""

from __future__ import annotations

import html as html_lib
import json
import re
from decimal import ROUND_CEILING, ROUND_FLOOR, ROUND_HALF_UP, Decimal
from pathlib import Path

import pytest

from gonio.report.i18n import labels

#: a bound-condition item as the triad's demo states M_xy (U = a + k·u, p = 95.45 %, no k)
VALUE, U, LO, HI = 0.8804008042768885, 0.006700979990979562, 0.873699824285909, 0.887101784267868


def two_sig(x: float) -> tuple[Decimal, int]:
    """``x`` to two significant digits, half up, and its decimal place."""
    d = Decimal(repr(x))
    dec = 1 - d.adjusted()
    q = d.quantize(Decimal(1).scaleb(-dec), rounding=ROUND_HALF_UP)
    if q.adjusted() > d.adjusted():
        dec -= 1
        q = d.quantize(Decimal(1).scaleb(-dec), rounding=ROUND_HALF_UP)
    return q, dec


def printed(U: float, lo: float, hi: float) -> tuple[str, str, str, Decimal]:
    """The printed U, the printed ends (outward at U's place) and their half-width."""
    Ut, dec = two_sig(U)
    step = Decimal(1).scaleb(-dec)
    lo_t = Decimal(repr(lo)).quantize(step, rounding=ROUND_FLOOR)
    hi_t = Decimal(repr(hi)).quantize(step, rounding=ROUND_CEILING)
    return f"{Ut:f}", f"{lo_t:f}", f"{hi_t:f}", (hi_t - lo_t) / 2


def second_us(note: str, U_text: str) -> list[str]:
    """Every "U = …" of the note that is not the table's U (a formula or another number)."""
    return [m.group(0) for m in re.finditer(r"\bU = (\(|[\d.]+)", note)
            if m.group(1) != U_text]


@pytest.mark.parametrize("r", [1.0, 2.0])
@pytest.mark.parametrize("lang", ["en", "zh"])
def test_band_note_names_the_printed_half_width_delta_never_a_second_u(lang, r):
    from gonio.analysis.conformity import decide_items
    from gonio.report.stated import interval_band_note
    from gonio.result.model import Item, Result, Uncertainty

    U_text, lo_t, hi_t, h = printed(U, LO, HI)
    assert (U_text, lo_t, hi_t, f"{h:f}") == ("0.0067", "0.8736", "0.8872", "0.0068")
    unc = Uncertainty([], 0.0026, U, None, 6.0, None, 0.9545, "U = a + k·u", (LO, HI))
    res = Result("s", "S", {"M": Item("M", "M", "c", "1", VALUE, uncertainty=unc)}, {}, {})
    (c,) = decide_items(res, [{"item": "M", "lower": -0.885, "upper": 0.885}],
                        {"rule": "non-binary", "guard_band_factor": r})
    # w is the decision's, from the printed ends: r·(0.8872 − 0.8736)/2
    assert c.guard_band == pytest.approx(r * float(h), rel=1e-12)
    note = interval_band_note([("M", c.to_json())], labels(lang), lambda k: "M_xy",
                              lambda k: "lsb/(°/s)", lambda k: 0.9545)
    flat = note.replace("：", ": ").replace("，", ", ")
    w = f"{(Decimal(repr(r)) * h).normalize():f}"
    assert f"M_xy: δ = ({hi_t} − {lo_t})/2 lsb/(°/s) = {h:f} lsb/(°/s), w = {w} " \
           f"lsb/(°/s)" in flat, note
    assert second_us(note, U_text) == [], note
    assert "w = r·δ" in note


@pytest.mark.parametrize("lang", ["en", "zh"])
def test_chi2_band_note_names_the_reach_delta(lang):
    """A χ² bound's δ is its reach above the printed estimate: 1.826 − 1.808 = 0.018."""
    from gonio.report.stated import interval_band_note

    c = {"acceptance_of": "interval", "rule": "guarded", "outcome": "pass", "U": 0.018,
         "guard_factor": 1.5, "stated_interval": ["0", "1.826"], "stated_value": "1.808",
         "probability_model": "chi-square, nu = 15590"}
    note = interval_band_note([("arw", c)], labels(lang), lambda k: "ARW", lambda k: "°/√h")
    flat = note.replace("：", ": ").replace("，", ", ")
    assert "ARW: δ = 1.826 − 1.808 °/√h = 0.018 °/√h, w = 0.027 °/√h" in flat, note
    assert second_us(note, "") == [], note


LAB_LIMITS = """
[[specification_limits]]
item = "M_xy"
lower = -0.885
upper = 0.885
source = "spec"

[[specification_limits]]
item = "b_z_t3_v1"
lower = -0.08
upper = 0.5
source = "spec"
"""


@pytest.fixture(scope="module")
def triad_lab(tmp_path_factory) -> Path:
    """protocols/lab-example.toml cut before its limits, with limits for two triad items."""
    src = (Path(__file__).resolve().parents[1] / "protocols" / "lab-example.toml").read_text(
        encoding="utf-8")
    head = src[:src.index("\n[[specification_limits]]") + 1]
    p = tmp_path_factory.mktemp("triadlab") / "lab.toml"
    p.write_text(head + LAB_LIMITS, encoding="utf-8")
    return p


@pytest.mark.parametrize("lang", ["en", "zh"])
def test_triad_certificate_prints_one_u_for_m_xy(shared_demo, triad_lab, lang):
    """The triad demo's certificate: the budget table's U of M_xy is the one "U" the page
    gives it; the guard-band note prints δ from the printed ends and the decision's w."""
    out = shared_demo("triad-alignment", lang=lang, lab=triad_lab)
    res = json.loads((out / "results.json").read_text(encoding="utf-8"))
    it = res["items"]["M_xy"]
    unc = it["uncertainty"]
    U_text, lo_t, hi_t, h = printed(unc["U"], *unc["interval"])
    c = it["conformity"]
    assert c["stated_interval"] == [lo_t, hi_t]
    assert c["guard_band"] == pytest.approx(c["guard_factor"] * float(h), rel=1e-12)
    raw = (out / "certificate.html").read_text(encoding="utf-8")
    # the U the budget table prints for M_xy (its bound condition's U = a + k·u)
    assert re.findall(r'data-src="items\.M_xy\.[^"]*\.U" data-rule="U">([^<]*)<', raw) \
        == [U_text]
    assert it["details"]["bound_condition"]["U"] == pytest.approx(unc["U"], rel=1e-12)
    text = html_lib.unescape(re.sub(r"<[^>]+>", "", raw))
    start = text.index(f"({hi_t} − {lo_t})/2")
    note = text[text.rindex("\n", 0, start):text.index("\n", start)]
    assert f"δ = ({hi_t} − {lo_t})/2" in note and f"= {h:f} " in note, note
    assert second_us(note, U_text) == [], note
