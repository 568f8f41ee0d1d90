"""An interval taken from a Monte Carlo's draws whose finite number leaves not even one
digit of its reach settled (a capped adaptive procedure): the statement rule moves both ends
out by twice their numerical standard uncertainty and says so, and every output — the
certificate (en, zh), summary.txt, the DCC — states the widened ends with that note, from
the stored result. The ends are checked here against the computed ends ± 2·s, not against
the rule's own rounding."""

from __future__ import annotations

import json
import re

import pytest

from gonio.result.model import Result
from gonio.result.statement import (WIDENED_NOTE, interval_reach, numerical_decimals,
                                    decimals_for_sig, state_interval)


def _f(text: str) -> float:
    return float(text.replace("−", "-"))


@pytest.mark.parametrize("value,lo,hi,s,nonneg", [
    (0.0995, 0.0677, 0.1302, 0.006, False),
    (0.0995, 0.0677, 0.1302, 0.02, False),
    (0.006, 0.0, 0.0191, 0.004, True),
    (0.03, 0.02, 0.05, 0.01, True),          # the lower end widened to 0: one-sided
    (23.7, 18.4, 31.1, 3.0, True),
    (-1.2e-6, -3.4e-6, 2.0e-6, 1.5e-6, False),
])
def test_unsettled_ends_are_widened_by_twice_the_numerical_u(value, lo, hi, s, nonneg):
    gap = interval_reach(value, (lo, hi), nonnegative=nonneg)
    assert numerical_decimals(s) < decimals_for_sig(gap, 1)      # not one digit settled
    st = state_interval(value, (lo, hi), p=0.95, nonnegative=nonneg, numerical_u=s)
    a, b = (_f(x) * 10.0 ** st.exponent for x in st.interval)
    assert a <= max(lo - 2 * s, 0.0) + 1e-15 if nonneg else a <= lo - 2 * s + 1e-15
    assert b >= hi + 2 * s - 1e-15
    assert st.widened is not None and _f(st.widened) * 10.0 ** st.exponent >= 2 * s - 1e-15
    assert "ends widened by" in st.text() and "端点已各向外放宽" in st.text("zh")


@pytest.mark.parametrize("s", [0.0, 0.001, 0.0024, None])
def test_settled_ends_are_not_widened(s):
    """Where one digit is settled (4·s ≤ 0.01 here) the computed ends stand, rounded
    outward, and no note is printed."""
    st = state_interval(0.0995, (0.0677, 0.1302), p=0.95, numerical_u=s)
    assert st.widened is None and "widened" not in st.text()
    assert _f(st.interval[0]) <= 0.0677 and _f(st.interval[1]) >= 0.1302
    assert _f(st.interval[1]) - 0.1302 < 0.01          # rounded outward, no more


#: per specification: the item whose interval comes from a Monte Carlo's draws
ITEMS = {"iec62047-20": "bias_drift_after_power_on", "ogam-draft": "rate_consistency"}


@pytest.fixture(scope="module", params=tuple(ITEMS))
def unsettled(request, tmp_path_factory):
    """A small calibration's stored result with the item's numerical u raised to its reach
    (as a Monte Carlo capped far short of settling would leave it), rendered en and zh."""
    from gonio.specs import get
    from tests.test_zh_certificates import small_calibration

    key, item = request.param, ITEMS[request.param]
    d, result = small_calibration(key, tmp_path_factory)
    doc = result.to_json()
    items = doc["items"] if isinstance(doc["items"], dict) else {
        i["key"]: i for i in doc["items"]}
    it = items[item]
    unc = it["uncertainty"]
    assert unc.get("interval_numerical_u") and unc.get("interval"), unc
    # how many draws the ends come from, beside their numerical u (JCGM 101's M)
    assert isinstance(unc.get("interval_draws"), int) and unc["interval_draws"] >= 400, unc
    for other in items.values():        # every Monte Carlo interval says both
        o = other.get("uncertainty") or {}
        assert ("interval_numerical_u" in o) == ("interval_draws" in o), (other["title"], o)
    value = it["value"]
    unc["interval_numerical_u"] = interval_reach(value, unc["interval"], nonnegative=True)
    out = {}
    for lang in ("en", "zh"):
        get(key).renderer().write(Result.from_json(json.loads(json.dumps(doc))),
                                  d / lang, lang=lang, dcc=True)
        out[lang] = d / lang
    return {"key": key, "item": item, "doc": doc, "dir": out,
            "lo": unc["interval"][0], "hi": unc["interval"][1],
            "s": unc["interval_numerical_u"]}


def test_every_output_states_the_widened_ends(unsettled):
    u = unsettled
    res = json.loads((u["dir"]["en"] / "results.json").read_text(encoding="utf-8"))
    items = res["items"] if isinstance(res["items"], dict) else {
        i["key"]: i for i in res["items"]}
    # results.json keeps the computed ends and their numerical u, unchanged
    assert items[u["item"]]["uncertainty"]["interval"] == [u["lo"], u["hi"]]
    assert items[u["item"]]["uncertainty"]["interval_numerical_u"] == u["s"]
    summary = (u["dir"]["en"] / "summary.txt").read_text(encoding="utf-8")
    line = next(x for x in summary.splitlines() if "ends widened by" in x)
    upper = re.search(r"≤ ([0-9.]+)|, ([0-9.]+)\]", line)
    hi = _f(upper.group(1) or upper.group(2))
    exp = re.search(r"×10([⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+)", line)
    scale = 1.0
    if exp:
        scale = 10.0 ** int(exp.group(1).translate(str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")))
    assert hi * scale >= u["hi"] + 2 * u["s"] - 1e-15, (line, u)
    html = (u["dir"]["en"] / "certificate.html").read_text(encoding="utf-8")
    assert html.count("ends widened by") >= 1
    zh = (u["dir"]["zh"] / "certificate.html").read_text(encoding="utf-8")
    assert WIDENED_NOTE["zh"].split("{w}")[0] in zh
    # items.csv: the numbers of the one statement, unrounded: the widened ends
    import pandas as pd
    csv = pd.read_csv(u["dir"]["en"] / "tables" / "items.csv").set_index("item")
    lo_w = max(u["lo"] - 2 * u["s"], 0.0)
    assert csv.loc[u["item"], "interval_low"] == pytest.approx(lo_w, abs=1e-15)
    assert csv.loc[u["item"], "interval_high"] == pytest.approx(u["hi"] + 2 * u["s"], rel=1e-12)
    dcc = next(u["dir"]["en"].glob("*.xml")).read_text(encoding="utf-8")
    assert "ends widened by" in dcc
    zh_dcc = next(u["dir"]["zh"].glob("*.xml")).read_text(encoding="utf-8")
    assert "ends widened by" in zh_dcc and WIDENED_NOTE["zh"].split("{w}")[0] in zh_dcc
