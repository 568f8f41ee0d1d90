"""Rate items stated by their bound condition (a readings file with no ``# rate_table_u_rel``:
JJF 1535 7.2.1 K, IEC 62047-20 5.1.3.1 a_BASE and 5.1.3.2) certify no combined standard
uncertainty, the one rule of every writer (gonio.report.stated.u_c_certified):

- the DCC states their interval's ends with no si:valueStandardMU (the budget's u_c, whose
  table line is rectangular, does not hold the table at its bound); items stated otherwise
  keep theirs;
- the certificate's budget table marks their u_c row "beside, not stated" (en, zh);
- the legend names each item's bounded lines from ``details.bound_condition.a_lines``
  (JJF K: the table's alone, no chamber term; IEC: the table's and the gyro's temperature);
- the rate-table finding says the table is added linearly in those items;
- IEC: the gyro's temperature line e_TU is the chamber's bound × (|T_c,SF/a| + U) of
  5.1.3.4's own statement (recomputed here from results.json's 5.1.3.4 item and the
  readings' chamber metadata), and without 5.1.3.4 one flagged finding names every item
  stated without the chamber's term (each whose interval narrows: never a silent 0);
- the zh DCC translates each such item's value and interval quantity whole.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from gonio.report.dcc import DCC_NS, SI_NS

PINS = Path(__file__).resolve().parent / "data" / "pins"
NS = {"dcc": DCC_NS, "si": SI_NS}
#: the items stated by a bound condition: those into which the rate table's relative error
#: enters (JJF 7.2.1, IEC 5.1.3.1, 5.1.3.2), IEC's bias items (5.3.3.1, 5.3.3.2) and IEC's noise
#: items (5.4.5.2, 5.4.5.1 b), c): the gyro's temperature during the static record, one-sided)
NOISE_ITEMS = {"arw", "inband_noise", "broadband_noise"}
#: JJF 7.2.5 and 7.2.14: the extreme of magnitudes of temperature slopes, the gyro's
#: temperature error at the chamber's set points at its bound in each slope's reach
SLOPE_ITEMS = {"sf_temperature_sensitivity", "bias_temperature_sensitivity"}
BOUND_ITEMS = {"jjf1535-2015": {"scale_factor"} | SLOPE_ITEMS,
               "iec62047-20": {"scale_factor", "initial_sf_variation", "bias",
                               "initial_bias_variation"} | NOISE_ITEMS}
#: The bounded lines of each bound item (IEC 5.3.3.1/5.3.3.2: the gyro's temperature error at
#: T_BASE, the input axis's misalignment on the Earth rate, a_BASE's bounded part).
BOUND_LINES = {"scale_factor": {"e_table", "e_TU"}, "initial_sf_variation": {"e_table", "e_TU"},
               "bias": {"e_TU", "e_align", "e_a_bnd"},
               "initial_bias_variation": {"e_TU", "e_align", "e_a_bnd"},
               **{k: {"dT_noise"} for k in NOISE_ITEMS}, **{k: {"dT"} for k in SLOPE_ITEMS}}


def gonio(*args, cwd: Path) -> None:
    r = subprocess.run([sys.executable, "-m", "gonio", *map(str, args)], cwd=cwd,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def calibrated(root: Path, spec: str, drop_test: str | None = None) -> dict:
    proto = PINS / f"{spec}-small.toml"
    gonio("simulate", "--spec", spec, "--protocol", proto, "--seed", 4, "--out", root / "sim",
          cwd=root)
    text = (root / "sim" / "readings.csv").read_text(encoding="utf-8")
    assert re.search(r"(?m)^# rate_table_u_rel:", text)
    text = re.sub(r"(?m)^# rate_table_u_rel:.*\n", "", text)
    if drop_test:
        text = re.sub(rf"(?m)^{drop_test},.*\n", "", text)
    (root / "r.csv").write_text(text, encoding="utf-8")
    gonio("calibrate", root / "r.csv", "--protocol", proto, "--dcc", "--out", root / "cal",
          cwd=root)
    out = root / "cal"
    return {"spec": spec, "text": text,
            "res": json.loads((out / "results.json").read_text(encoding="utf-8")),
            "html": (out / "certificate.html").read_text(encoding="utf-8"),
            "summary": (out / "summary.txt").read_text(encoding="utf-8"),
            "dcc": etree.parse(str(out / "certificate.dcc.xml"))}


_RUNS: dict = {}


def _run(tmp_path_factory, spec: str, drop_test: str | None = None) -> dict:
    """One calibration per specification (and dropped test) for the module (the tests only
    read it)."""
    key = (spec, drop_test)
    if key not in _RUNS:
        _RUNS[key] = calibrated(tmp_path_factory.mktemp(spec), spec, drop_test=drop_test)
    return _RUNS[key]


@pytest.fixture(scope="module", params=list(BOUND_ITEMS))
def cal(request, tmp_path_factory):
    return _run(tmp_path_factory, request.param)


def _plain(html: str) -> str:
    import html as html_lib

    return html_lib.unescape(re.sub(r"<[^>]+>", " ", html))


def test_the_table_enters_those_items_by_their_bound(cal):
    res = cal["res"]
    bound = {k for k, it in res["items"].items()
             if (it.get("details") or {}).get("bound_condition")}
    assert bound == BOUND_ITEMS[cal["spec"]]


def test_dcc_states_no_standard_uncertainty_for_a_bound_item(cal):
    res, tree = cal["res"], cal["dcc"]
    for key, it in res["items"].items():
        r = tree.find(f".//dcc:result[@id='result-{key}']", NS)
        if r is None or not it["measured"]:
            continue
        mu = r.findall(".//si:valueStandardMU", NS)
        if key in BOUND_ITEMS[cal["spec"]]:
            assert not mu, key
            vals = r.findall(".//si:realListXMLList/si:valueXMLList", NS)
            assert len(vals) == 1, key
            lo, hi = (float(v) for v in vals[0].text.split())
            jlo, jhi = it["uncertainty"]["interval"]
            # the printed ends hold the interval (rounded outward) within a rounding step each
            step = 10.0 ** -max(len(v.split(".")[1]) if "." in v else 0
                                for v in vals[0].text.split())
            assert lo <= jlo and hi >= jhi and (hi - lo) <= (jhi - jlo) + 2.0001 * step, (
                key, lo, hi)
            assert "no standard uncertainty of the item is certified" in etree.tostring(
                r, encoding="unicode")
        elif it["uncertainty"] and it["uncertainty"].get("k") is not None and \
                it.get("upper_bound") is None:
            # a GUM item stated by value ± U keeps its expanded U (nothing withheld)
            assert r.find(".//si:expandedMU", NS) is not None, key


def test_budget_marks_the_u_c_of_a_bound_item_not_stated(cal):
    from gonio.report.i18n import labels
    from gonio.report.rate_certificate import budget_rows

    res = cal["res"]
    bound_clauses = {res["items"][k]["clause"] for k in BOUND_ITEMS[cal["spec"]]}
    for lang, beside, plain in (("en", "beside, not stated", "combined standard uncertainty"),
                                ("zh", "不作声明", "合成标准不确定度")):
        rows = [r for r in budget_rows(res, labels(lang)) if r[1] == "u_c"]
        for r in rows:
            if r[0] in bound_clauses:
                assert beside in r[2], (lang, r)
            else:
                assert r[2] == plain, (lang, r)
        assert {r[0] for r in rows if beside in r[2]} == bound_clauses, lang
    page = _plain(cal["html"])
    assert page.count("beside, not stated") == len(BOUND_ITEMS[cal["spec"]])


def test_legend_names_each_items_bounded_lines(cal):
    from gonio.report.i18n import labels
    from gonio.report.stated import interval_legend

    res = cal["res"]
    page = re.sub(r"\s+", " ", _plain(cal["html"]))
    zh = interval_legend(res["items"], labels("zh"))
    for key in BOUND_ITEMS[cal["spec"]]:
        lines = set(res["items"][key]["details"]["bound_condition"]["a_lines"])
        assert lines == ({"e_table"} if key == "scale_factor" and cal["spec"] == "jjf1535-2015"
                         else BOUND_LINES[key])
    if cal["spec"] == "jjf1535-2015":
        assert "(7.2.1: the rate table's error)" in page
        assert "（7.2.1：转台误差）" in zh
        assert ("(7.2.5, 7.2.14: the gyro's temperature error at the chamber's set points)"
                in page)
        assert "（7.2.5, 7.2.14：陀螺在温箱设定点的温度误差）" in zh
    else:
        assert ("(5.1.3.1, 5.1.3.2: the rate table's error and the gyro's temperature error "
                "at the set point; 5.3.3.1, 5.3.3.2: the gyro's temperature error at the set "
                "point, the input axis's misalignment on the Earth rate and the scale "
                "factor's bounded part)") in page
        assert ("（5.1.3.1, 5.1.3.2：转台误差、陀螺在设定点的温度误差；5.3.3.1, 5.3.3.2：陀螺在设定点的"
                "温度误差、输入轴对准误差对地球自转角速度的影响、标度因数的有界部分）") in zh
        # the noise items: their own kind, the one-sided limit, with their bounded line
        assert ("one-sided bound-condition limit [0, (s + R)/(1 − g)] = [0, s + a + R]"
                in page)
        assert ("(5.4.5.1 b), 5.4.5.1 c), 5.4.5.2: the gyro's temperature during the static "
                "record × the noise's temperature coefficient)") in page
        assert "单侧界限条件上限 [0, (s + R)/(1 − g)]" in zh
        assert "（5.4.5.1 b）, 5.4.5.1 c）, 5.4.5.2：静态记录期间陀螺的温度误差 × 噪声的温度系数）" in zh
    assert "chamber's temperature error" not in page and "温箱温度误差）给出" not in zh


def test_rate_table_finding_says_the_bound_is_added_linearly(cal):
    msg, = [f["message"] for f in cal["res"]["findings"] if f["code"] == "rate-table-u-unstated"]
    assert "linearly" in msg and "as a rectangular bound" not in msg
    assert "linearly" in cal["summary"]


def _chamber_bound_c(text: str) -> float:
    md = dict(re.findall(r"(?m)^# (\w+): (.*)$", text))
    return float(md["chamber_deviation_bound_c"]) + float(md["chamber_uniformity_c"]) / 2


def test_iec_temperature_line_takes_the_coefficients_far_end(tmp_path_factory):
    c = _run(tmp_path_factory, "iec62047-20")
    items = c["res"]["items"]
    tc = items["sf_temperature_coefficient"]
    assert tc["measured"]
    reach = (abs(tc["value"]) + tc["uncertainty"]["U"]) / 100          # %/°C → 1/°C
    for key in ("scale_factor", "initial_sf_variation"):       # a_BASE's T_c,SF (the bias's
        it = items[key]                                        # β: test_rate_bound_statement)
        row, = [r for r in it["uncertainty"]["components"] if r["symbol"] == "e_TU"]
        want = abs(row["c"]) * _chamber_bound_c(c["text"]) * reach
        got = it["details"]["bound_condition"]["a_lines"]["e_TU"]
        assert got == pytest.approx(want, rel=1e-9), key
        # the estimate alone falls short of it
        assert got > abs(row["c"]) * _chamber_bound_c(c["text"]) * abs(tc["value"]) / 100
    assert not [f for f in c["res"]["findings"] if f["code"] == "chamber-effect-unbounded"]


def _width(it: dict) -> float | None:
    unc = it.get("uncertainty") or {}
    if unc.get("interval"):
        return unc["interval"][1] - unc["interval"][0]
    return 2 * unc["U"] if unc.get("U") else None


def test_iec_without_its_temperature_coefficient_names_every_item_it_narrows(tmp_path,
                                                                            tmp_path_factory):
    """The readings less their 5.1.3.4 rows, against the same readings whole: every item whose
    interval narrows by more than 0.1 % (it lost the chamber's term: a_BASE and 5.1.3.2 their
    e_TU, 5.1.3.5 and 5.1.3.6 the chamber's fluctuation × T_c,SF) is named in the one
    finding, and every item named narrowed; the finding and 5.1.3.4's reason in Chinese
    hold no English word."""
    from gonio.report.i18n import finding_text, labels, reason_text
    from gonio.specs.iec62047_20.certificate import PHRASES_ZH
    from tests.test_zh_certificates import WHITELIST, WORD

    whole = _run(tmp_path_factory, "iec62047-20")["res"]
    c = calibrated(tmp_path, "iec62047-20", drop_test="sf_temperature")
    res = c["res"]
    assert not res["items"]["sf_temperature_coefficient"]["measured"]
    assert res["items"]["scale_factor"]["measured"]
    found = [f for f in res["findings"] if f["code"] == "chamber-effect-unbounded"]
    assert len(found) == 1 and found[0]["action"] == "flagged", res["findings"]
    msg = found[0]["message"]
    assert "not bounded" in msg and "5.1.3.4" in msg and f"{_chamber_bound_c(c['text']):g} °C" in msg
    named = set(re.search(r"the intervals of (.+?) are stated without", msg).group(1).split(", "))
    narrowed = set()
    for key, it in res["items"].items():
        w0, w1 = _width(whole["items"][key]), _width(it)
        if key != "sf_temperature_coefficient" and w0 and w1 and w1 < w0 * (1 - 1e-3):
            narrowed.add(it["clause"])
    assert narrowed >= {"5.1.3.1", "5.1.3.2", "5.1.3.5", "5.1.3.6"}, narrowed
    assert named == narrowed, (named, narrowed)
    assert "temperature effect on the scale factor is not bounded" in _plain(c["html"])
    assert "temperature effect on the scale factor is not bounded" in c["summary"]
    ok = WHITELIST | {"sf_temperature"}
    zh = finding_text(found[0], labels("zh"), PHRASES_ZH)
    assert "温箱温度对标度因数的影响未给出界限" in zh and "5.1.3.6" in zh and "除以 a_BASE" in zh
    assert not [w for w in WORD.findall(zh) if w not in ok], zh
    why = reason_text(res["items"]["sf_temperature_coefficient"]["reason"], labels("zh"),
                      PHRASES_ZH)
    assert not [w for w in WORD.findall(why) if w not in ok], why


def test_zh_dcc_names_the_interval_quantity_whole(cal):
    """The zh DCC's Chinese of a bound-condition item's two quantities (its value and its
    interval): the clause kept in both, the interval's "界限条件区间" and its p in the
    second — not the item's bare title for both (a title is a whole text, never the opening
    words of a longer one)."""
    from gonio.report.dcc import bound_interval_text
    from gonio.report.rate_certificate import dcc_translator
    from gonio.result.model import Result

    res = cal["res"]
    translate = dcc_translator(Result.from_json(res), None)
    texts = [el.text for el in cal["dcc"].iter(f"{{{DCC_NS}}}content") if el.text]
    for key in BOUND_ITEMS[cal["spec"]]:
        it = res["items"][key]
        name = f"{it['title']} ({cal['spec']} {it['clause']})"
        interval = f"{name}: {bound_interval_text(it)}; p = 95 %"
        assert name in texts and interval in texts, (name, texts)
        zh_name, zh_interval = translate(name), translate(interval)
        assert f"（{it['clause']}）" in zh_name and zh_name != zh_interval, zh_name
        # a dispersion's one-sided limit [0, s + a + R], every other item's value ± (a + k·u)
        kind = "单侧界限条件上限" if key in NOISE_ITEMS else "界限条件区间"
        if key in SLOPE_ITEMS:
            assert "最大绝对值 max|x_i| 的 95 % 区间" in zh_interval, zh_interval
        assert zh_interval.startswith(zh_name) and kind in zh_interval, zh_interval
        assert ("[0, s + a + R]" in zh_interval) == (key in NOISE_ITEMS), zh_interval
        assert zh_interval.endswith("p = 95 %"), zh_interval


def test_iec_noise_items_carry_the_gyro_s_temperature_at_the_static_record(tmp_path_factory):
    """The noise items (5.4.5.2, 5.4.5.1 b), c)) are measured at the static record's
    temperature, the certificate states them at T_BASE: with the 5.3.3.6 visits each carries
    the line value·√(c² + u²(c))·ΔT/√3, c the white level's coefficient from the visits and ΔT
    the chamber's bound plus the record's logged offset from T_BASE (read here from the CSV
    text), and no finding; without the visits (the readings less their 5.3.3.6 rows) no line
    and one flagged finding naming the three items, the record's temperature and the bound,
    on the certificate (en, zh without English words) and in results.json."""
    from gonio.report.i18n import finding_text, labels
    from gonio.specs.iec62047_20.certificate import PHRASES_ZH
    from tests.test_zh_certificates import WHITELIST, WORD

    keys = ("arw", "inband_noise", "broadband_noise")
    c = _run(tmp_path_factory, "iec62047-20")
    res = c["res"]
    header = next(l for l in c["text"].splitlines() if not l.startswith("#")).split(",")
    col, tcol = header.index("test"), header.index("temperature_c")
    temps = {float(l.split(",")[tcol]) for l in c["text"].splitlines()
             if not l.startswith("#") and l.split(",")[col] == "static"}
    assert len(temps) == 1
    t_base = 0.5 * (-40.0 + 85.0)                      # the small programme's range
    dT = _chamber_bound_c(c["text"]) + abs(temps.pop() - t_base)
    tc = res["items"]["arw"]["details"]["noise_temperature_coefficient_per_c"]
    assert tc["visits"] >= 2 and abs(tc["value"]) > tc["u"] > 0
    # the coefficient against the bench's own parameter (its white level ∝ 1 + a(T − T_ref)):
    # the least-squares slope of ln(1 + a(T_i − T_ref)) over the visits' temperatures
    import tomllib

    g = tomllib.loads((Path(__file__).parents[1] / "protocols" / "benches" /
                       "mems-adxrs610.toml").read_text(encoding="utf-8"))["gyro"]
    tv = np.array([float(l.split(",")[tcol]) for l in c["text"].splitlines()
                   if not l.startswith("#") and l.split(",")[col] == "bias_temperature"])
    lt = np.log1p(g["arw_tc1_per_c"] * (tv - g["reference_temperature_c"]))
    expect = float(np.polyfit(tv, lt, 1)[0])
    assert abs(tc["value"] - expect) < 3.0 * tc["u"], (tc, expect)
    for key in keys:
        it = res["items"][key]
        line = [r for r in it["uncertainty"]["components"] if r["symbol"] == "dT_noise"]
        assert len(line) == 1, it["uncertainty"]["components"]
        c_rms = (tc["value"] ** 2 + tc["u"] ** 2) ** 0.5
        assert line[0]["u"] == pytest.approx(it["value"] * c_rms * dT / 3 ** 0.5, rel=1e-9)
        # the statement: the one-sided bound condition [0, s + a + R], recomputed here from the
        # coefficient's own 95 % reach, ΔT and the other lines (scipy's χ² quantile)
        _check_noise_bound_statement(it, tc, dT)
    assert not [f for f in res["findings"] if f["code"] == "noise-temperature-not-bounded"]

    d = _run(tmp_path_factory, "iec62047-20", drop_test="bias_temperature")
    res = d["res"]
    assert res["items"]["arw"]["details"]["noise_temperature_coefficient_per_c"] is None
    for key in keys:
        assert not [r for r in res["items"][key]["uncertainty"]["components"]
                    if r["symbol"] == "dT_noise"]
        # no coefficient, no bound condition: the χ² statement of its lines
        assert "bound_condition" not in res["items"][key]["details"]
        assert res["items"][key]["uncertainty"]["k_source"] == "chi-square"
    found = [f for f in res["findings"] if f["code"] == "noise-temperature-not-bounded"]
    assert len(found) == 1 and found[0]["action"] == "flagged", res["findings"]
    msg = found[0]["message"]
    header = next(l for l in d["text"].splitlines() if not l.startswith("#")).split(",")
    col, tcol = header.index("test"), header.index("temperature_c")
    temps = {float(l.split(",")[tcol]) for l in d["text"].splitlines()
             if not l.startswith("#") and l.split(",")[col] == "static"}
    for part in ("5.4.5.2", "5.4.5.1 b)", "5.4.5.1 c)", f"({temps.pop():g} °C",
                 f"± {_chamber_bound_c(d['text']):g} °C", "not at T_BASE", "5.3.3.6 visits"):
        assert part in msg, (part, msg)
    assert "hold at the gyro's temperature during the static record" in _plain(d["html"])
    zh = finding_text(found[0], labels("zh"), PHRASES_ZH)
    assert "噪声项" in zh and "而非 T_BASE" in zh and "5.3.3.6" in zh
    assert not [w for w in WORD.findall(zh) if w not in WHITELIST | {"temperature_c"}], zh


def _check_noise_bound_statement(it: dict, tc: dict, dT: float) -> None:
    """A noise item's one statement against its definition, computed here: g =
    (|c| + t_95(⌊ν_c⌋)·u(c))·ΔT (the coefficient's 95 % far end, the temperature at its bound:
    the reading's relative error), u_rest the root sum square of the budget's other
    contributions, ν_rest = ½(s/u_rest)² taken as its integer part,
    R = s·(√(ν/χ²_{0.05,ν}) − 1), the interval [0, (s + R)/(1 − g)], no k, ν_eff ν_rest; the
    χ² limit of the whole GUM budget (the line rectangular) would reach less."""
    from scipy import stats

    s, unc = it["value"], it["uncertainty"]
    bc = it["details"]["bound_condition"]
    # k of the coefficient's ν as stated (its integer part: gonio.result.statement.coverage_k)
    g = (abs(tc["value"]) + stats.t.ppf(0.975, np.floor(tc["nu"])) * tc["u"]) * dT
    assert bc["g_rel"]["dT_noise"] == pytest.approx(g, rel=1e-6) and set(bc["a_lines"]) == {
        "dT_noise"}
    assert bc["g"] == pytest.approx(g, rel=1e-6)
    rest = [r["contribution"] for r in unc["components"] if r["symbol"] != "dT_noise"]
    u_rest = float(np.sqrt(np.sum(np.square(rest))))
    assert bc["u_rest"] == pytest.approx(u_rest, rel=1e-9)
    nu = float(np.floor(0.5 * (s / u_rest) ** 2))
    reach = s * (np.sqrt(nu / stats.chi2.ppf(0.05, nu)) - 1.0)
    assert bc["reach_rest"] == pytest.approx(reach, rel=1e-9)
    upper = (s + reach) / (1.0 - g)
    assert unc["k"] is None and unc["interval"][0] == 0.0
    assert unc["interval"][1] == pytest.approx(upper, rel=1e-6)
    assert bc["a"] == pytest.approx(upper - s - reach, rel=1e-5)
    assert unc["nu_eff"] == pytest.approx(0.5 * (s / u_rest) ** 2, rel=1e-9)
    nu_all = float(np.floor(0.5 * (s / unc["u_c"]) ** 2))
    assert unc["interval"][1] > s * np.sqrt(nu_all / stats.chi2.ppf(0.05, nu_all))


def test_iec_without_its_bias_temperature_coefficient_names_the_bias_items(tmp_path_factory):
    """The readings less their 5.3.3.6 rows: the bias (5.3.3.1) and 5.3.3.2 lose the gyro's
    temperature error at T_BASE (e_TU 0 in their bound condition), and one flagged finding
    names both, on the certificate, in summary.txt and in Chinese without an English word;
    the whole readings give no such finding and a non-zero e_TU."""
    from gonio.report.i18n import finding_text, labels
    from gonio.specs.iec62047_20.certificate import PHRASES_ZH
    from tests.test_zh_certificates import WHITELIST, WORD

    whole = _run(tmp_path_factory, "iec62047-20")["res"]
    assert not [f for f in whole["findings"] if f["code"] == "bias-temperature-unbounded"]
    for key in ("bias", "initial_bias_variation"):
        assert whole["items"][key]["details"]["bound_condition"]["a_lines"]["e_TU"] > 0
    c = _run(tmp_path_factory, "iec62047-20", drop_test="bias_temperature")
    res = c["res"]
    assert not res["items"].get("bias_temperature_coefficient", {"measured": False})["measured"]
    for key in ("bias", "initial_bias_variation"):
        assert res["items"][key]["measured"]
        assert res["items"][key]["details"]["bound_condition"]["a_lines"].get("e_TU", 0.0) == 0.0
    found = [f for f in res["findings"] if f["code"] == "bias-temperature-unbounded"]
    assert len(found) == 1 and found[0]["action"] == "flagged", res["findings"]
    msg = found[0]["message"]
    named = set(re.search(r"the intervals of (.+?) are stated without", msg).group(1).split(", "))
    assert named == {"5.3.3.1", "5.3.3.2"} and "5.3.3.6" in msg
    assert f"{_chamber_bound_c(c['text']):g} °C" in msg
    assert "temperature effect on the bias is not bounded" in _plain(c["html"])
    assert "temperature effect on the bias is not bounded" in c["summary"]
    zh = finding_text(found[0], labels("zh"), PHRASES_ZH)
    assert "温箱温度对零偏的影响未给出界限" in zh and "5.3.3.2" in zh
    # the test's name in the readings (its reason quotes it) is no English word
    assert not [w for w in WORD.findall(zh) if w not in WHITELIST | {"bias_temperature"}], zh
