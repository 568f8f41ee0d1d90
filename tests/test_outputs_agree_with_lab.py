"""Every item's numbers agree across the five outputs of a calibration issued with a
laboratory file (limits under a non-binary rule with a guard band): results.json, summary.txt,
tables/items.csv, the DCC XML and the certificate's HTML, for each specification's demo.

- items.csv holds results.json's own floats (value, u_c, U, k, the interval's ends);
- the certificate, summary.txt and the DCC print the value and U/k, or the interval, as the
  statement rule rounds them from results.json (the Result decides, every output prints);
- an item stated by its interval alone (k null) says what its u_c is (``u_c_of``), and the
  DCC's si:valueStandardMU is that u_c; for the optical E it is u_c of the point where |E_i|
  is largest, found here from the per-point table (not from the value gonio stored);
- the conformity decisions: the DCC declaration states the acceptance as the certificate does
  (never "acceptance interval interval …"), a "—" probability with its reason, and the
  guard band's U of each interval item (= half-width of its stated interval, recomputed here
  from the ends as printed) in the DCC and on the certificate; summary.txt gives both guard bands where the interval is not symmetric;
- the certificate's legend names the clauses of every interval-stated item under its kind
  (the extreme of magnitudes, the corrected maximum, …), in English and in Chinese.
"""

from __future__ import annotations

import csv
import html as html_lib
import io
import json
import re

import pytest
from lxml import etree

from gonio.cli import main
from gonio.records.compute import render_folder
from gonio.report.dcc import DCC_NS, SI_NS
from gonio.resources import protocols_dir
from tests.statement_numbers import measured, stated_value

NS = {"dcc": DCC_NS, "si": SI_NS}

#: (specification, instrument table of the readings' identity, limits) — limits on items of
#: every kind of statement: ± U, χ², belt, extreme of magnitudes, corrected maximum, half
#: range, folded normal, pivot, outcome distribution
CASES = {
    "ogam-draft": (None, [("angle_deviation", "mpe = 0.5"), ("repeatability", "upper = 0.3"),
                          ("scale_factor_nonlinearity", "upper = 0.0005"),
                          ("zero_stability", "upper = 0.01"),
                          ("pointing_consistency", "upper = 0.0001"),
                          ("rate_consistency", "upper = 10.0")]),
    "jjf1535-2015": ('model = "ADXRS610-class"\nserial = "MEMS-0610-001"\n',
                     [("bias_stability", "upper = 60.0"), ("g_sensitivity", "mpe = 250.0"),
                      ("sf_repeatability", "upper = 0.001"), ("threshold", "upper = 0.2"),
                      ("scale_factor", "lower = 5.99\nupper = 6.01"),
                      ("sf_temperature_sensitivity", "mpe = 0.0002"),
                      ("bias_temperature_sensitivity", "mpe = 25.0")]),
    "iec62047-20": ('model = "ADXRS610-class"\nserial = "MEMS-0610-001"\n',
                    [("sf_stability", "upper = 0.0001"), ("cross_axis", "mpe = 1.2"),
                     ("bias_hysteresis", "upper = 0.2"), ("bias_instability", "upper = 40.0"),
                     ("bias_repeatability", "upper = 0.02"), ("ratiometric_error", "mpe = 0.06"),
                     ("bias", "mpe = 0.3"), ("g_sensitivity", "mpe = 0.1"),
                     ("bias_ratiometric_error", "mpe = 0.02")]),
    "triad-alignment": ('serial = "TRIAD-0001"\n', [("M_xx", "lower = 49.9\nupper = 50.1"),
                                                     ("b_z", "mpe = 5.0")]),
}


def lab_text(spec: str) -> str:
    """The example laboratory file with the instrument of the spec's virtual readings and the
    case's limits in place of its own."""
    base = (protocols_dir() / "lab-example.toml").read_text(encoding="utf-8")
    base = base[:base.index("\n[[specification_limits]]")]
    ident, limits = CASES[spec]
    if ident is not None:
        a, b = base.index("[instrument]"), base.index("[[standards]]")
        base = base[:a] + "[instrument]\ndescription = \"gyro\"\n" + ident + \
            'manufacturer = "gonio virtual bench"\n\n' + base[b:]
    return base + "\n" + "".join(f'\n[[specification_limits]]\nitem = "{k}"\n{v}\n'
                                 f'source = "limit of {k}"\n' for k, v in limits)


#: The demo's seed per specification where the default one does not serve: the optical
#: draft's seed 7 states two non-negative items whose bias-corrected estimate fell below
#: zero (K_l, C_v), which the sign test below needs (seed 0 has none since the tilt
#: estimate's rests are taken in opposite pairs and the timeline moved).
SEEDS = {"ogam-draft": 7}


@pytest.fixture(scope="module", params=list(CASES))
def issued(request, tmp_path_factory):
    spec = request.param
    root = tmp_path_factory.mktemp(spec)
    lab = root / "lab.toml"
    lab.write_text(lab_text(spec), encoding="utf-8")
    out = {}
    d = root / "en"
    assert main(["demo", "--spec", spec, "--seed", str(SEEDS.get(spec, 0)), "--lab", str(lab),
                 "--out", str(d)]) == 0
    # the Chinese certificate of the same stored result (the renderer is a pure function of
    # results.json and the laboratory file; the calibration is not made twice)
    render_folder((d / "results.json").read_bytes(), root / "zh", spec_key=spec, lab=lab,
                  lang="zh")
    for lang in ("en", "zh"):
        out[lang] = {
            "html": (root / lang / "certificate.html").read_text(encoding="utf-8")
            .replace("\xa0", " "),
            "dcc": etree.parse(str(root / lang / "certificate.dcc.xml")).getroot()}
    res = json.loads((d / "results.json").read_text(encoding="utf-8"))
    rows = {r["item"]: r for r in csv.DictReader(io.StringIO(
        (d / "tables" / "items.csv").read_text(encoding="utf-8")))}
    return {"spec": spec, "res": res, "rows": rows, "out": out,
            "summary": (d / "summary.txt").read_text(encoding="utf-8")}


def _ulp(text: str) -> float:
    """One unit of the last printed decimal of a plain decimal text."""
    frac = text.partition(".")[2]
    if frac:
        return 10.0 ** -len(frac)
    digits = text.lstrip("-")        # "790": rounded to tens
    return 10.0 ** (len(digits) - len(digits.rstrip("0"))) if digits.strip("0") else 1.0


def _close(text: str, x: float) -> bool:
    """``text`` is ``x`` rounded to the places it prints (half up, or outward: one unit)."""
    return abs(float(text) - x) <= _ulp(text) * (1 + 1e-9) + 1e-15 * abs(x)


def _interval_items(res: dict) -> dict:
    return {k: it for k, it in measured(res).items() if it["uncertainty"]["k"] is None
            and it["uncertainty"].get("interval") is not None}


def test_items_csv_holds_the_results_json_numbers(issued):
    """items.csv is results.json's floats, item by item (nothing rounded or recomputed)."""
    res, rows = issued["res"], issued["rows"]
    for key, it in measured(res).items():
        row, u = rows[key], it["uncertainty"]
        from gonio.report.stated import u_c_certified
        if u_c_certified(it):
            assert float(row["u"]) == pytest.approx(u["u_c"], rel=1e-12), key
        else:                 # a bound-condition item: its quadrature u_c is not stated
            assert row["u"] == "", key
        if row["value"]:
            assert float(row["value"]) == pytest.approx(it["value"], rel=1e-12), key
        else:                 # a bias-corrected range below zero: its bound alone is stated
            assert it["value"] < 0, key
        # a non-negative quantity with k whose value − U falls below zero is stated by its
        # interval [0, value + U] (the certificate's "≤ value + U"): no U or k beside it
        bound = u["k"] is not None and row["U"] == ""
        if bound:
            assert it["value"] - u["U"] < 0, key
        if u["k"] is None or bound:
            assert row["U"] == "" and row["k"] == "", key
            lo, hi = u["interval"] if u.get("interval") else (0.0, it["value"] + u["U"])
            assert (float(row["interval_low"]), float(row["interval_high"])) == \
                pytest.approx((lo, hi), rel=1e-12), key
        else:
            assert float(row["U"]) == pytest.approx(u["U"], rel=1e-12), key
            assert float(row["k"]) == pytest.approx(u["k"], rel=1e-12), key


def test_an_interval_item_says_what_its_standard_uncertainty_is(issued):
    """k null: U is the interval's reach above the stated value and u_c is labelled, so no
    reader takes U/u_c for a coverage factor; E's u_c is that of the point where |E_i| is
    largest (the law of propagation of max|E_i| at the estimates), found here from the
    per-point table and the points' budgets."""
    res = issued["res"]
    for key, it in _interval_items(res).items():
        u = it["uncertainty"]
        assert u.get("u_c_of"), key
        assert stated_value(it) + u["U"] == pytest.approx(u["interval"][1], rel=1e-9), key
    if issued["spec"] == "ogam-draft":
        e = res["items"]["angle_deviation"]
        table = e["details"]["table"]
        at = max(table, key=lambda r: abs(r["E_arcsec"]))
        pts = {p["position_deg"]: p["u_c_arcsec"]
               for p in res["extra"]["uncertainty"]["points"]}
        assert e["uncertainty"]["u_c"] == pytest.approx(pts[at["position_deg"]], rel=1e-12)
        assert f"at {at['position_deg']:g}°" in e["uncertainty"]["u_c_of"]
        assert "max|E_i|" in e["uncertainty"]["u_c_of"]


def _dcc_reals(root) -> dict:
    """(item key, results.json field) → si:real of the DCC quantity stating it."""
    out = {}
    for real in root.iter(f"{{{SI_NS}}}real"):
        prev = real.getprevious()
        if isinstance(prev, etree._Comment):
            m = re.search(r"src=items\.([A-Za-z0-9_]+)\.(value|details\.max_abs_arcsec)\b",
                          prev.text or "")
            if m and "factor=" not in (prev.text or ""):   # not a unit-converted quantity
                out[(m.group(1), m.group(2))] = real
    return out


def test_dcc_states_the_numbers_of_results_json(issued):
    """The DCC's value, U and k, or its coverage interval with u_c as si:valueStandardMU,
    are results.json's, rounded (interval ends outward by at most one printed unit)."""
    res = issued["res"]
    reals = _dcc_reals(issued["out"]["en"]["dcc"])
    seen = 0
    for key, it in measured(res).items():
        u = it["uncertainty"]
        field = "details.max_abs_arcsec" if u.get("k_source") == "max-abs-interval" \
            else "value"
        real = reals.get((key, field))
        if real is None:
            continue
        seen += 1
        assert _close(real.find("si:value", NS).text, stated_value(it)), key
        if u["k"] is None:
            ci = real.find("si:measurementUncertaintyUnivariate/si:coverageIntervalMU", NS)
            e_bound = key == "angle_deviation" and ((res.get("extra") or {}).get(
                "uncertainty") or {}).get("u_c_certified") is False   # U = k·u + b per point
            if (it.get("details") or {}).get("bound_condition") or e_bound:
                # no u_c on the certificate: the interval's ends alone, in the next quantity
                assert ci is None and real.find(".//si:valueStandardMU", NS) is None, key
                lo, hi = real.getparent().getnext().findtext(
                    "si:realListXMLList/si:valueXMLList", None, NS).split()
            else:
                assert ci is not None, key
                assert _close(ci.find("si:valueStandardMU", NS).text, u["u_c"]), key
                lo, hi = (ci.find(f"si:{t}", NS).text for t in ("intervalMin", "intervalMax"))
            assert float(lo) <= u["interval"][0] * (1 + 1e-12) + 1e-300 and \
                u["interval"][0] - float(lo) <= _ulp(lo) * (1 + 1e-9), key
            assert float(hi) >= u["interval"][1] * (1 - 1e-12) and \
                float(hi) - u["interval"][1] <= _ulp(hi) * (1 + 1e-9), key
            assert real.find(".//si:expandedMU", NS) is None, key
        elif it["value"] - u["U"] < 0 and real.find(".//si:expandedMU", NS) is None:
            # a non-negative quantity stated by [0, value + U]: its interval, no U
            ci = real.find("si:measurementUncertaintyUnivariate/si:coverageIntervalMU", NS)
            assert ci is not None, key
            hi = ci.find("si:intervalMax", NS).text
            assert float(hi) >= (it["value"] + u["U"]) * (1 - 1e-12), key
            assert float(hi) - (it["value"] + u["U"]) <= _ulp(hi) * (1 + 1e-9), key
        else:
            ex = real.find("si:measurementUncertaintyUnivariate/si:expandedMU", NS)
            assert ex is not None, key
            assert _close(ex.find("si:valueExpandedMU", NS).text, u["U"]), key
            assert _close(ex.find("si:coverageFactor", NS).text, u["k"]), key
    assert seen >= 2


def test_certificate_and_summary_print_the_statement(issued):
    """The certificate's value span and the interval's ends (or U and k), and summary.txt's
    line of the item, are the statement rule's texts of results.json's numbers."""
    from gonio.report.i18n import minus_sign
    from gonio.result.statement import item_statement

    res, html, summary = issued["res"], issued["out"]["en"]["html"], issued["summary"]
    text = re.sub(r"<[^>]+>", "", html)
    for key, it in measured(res).items():
        st = item_statement(it)
        field = "details.max_abs_arcsec" if it["uncertainty"].get("k_source") == \
            "max-abs-interval" else "value"
        spans = set(re.findall(r'data-src="items\.' + re.escape(key) + r'\.'
                               + re.escape(field) + r'" data-rule="[^"]+">([^<]*)<', html))
        if not st.below_zero:
            assert spans <= {minus_sign(st.value_text)}, (key, spans)
        if st.interval is not None:
            ends = [minus_sign(x) for x in st.interval_ends]
            assert (f"≤ {ends[1]}" if st.upper is not None or st.below_zero
                    else f"[{ends[0]}, {ends[1]}]") in text, key
            assert any(st.interval_ends[1] in ln and (st.below_zero or st.value_text in ln)
                       for ln in summary.splitlines()), key
        elif st.U is not None:
            assert any(st.U_text in ln and st.value_text in ln
                       for ln in summary.splitlines()), key


def _number(text: str) -> float:
    """A stated number as printed ("0.48", "1.4×10⁻⁵", "−0.3") as a float."""
    m, _, e = text.replace("−", "-").partition("×10")
    sub = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")
    return float(m) * 10.0 ** (int(e.translate(sub)) if e else 0)


def _declarations(root) -> dict:
    out = {}
    for st in root.iter(f"{{{DCC_NS}}}statement"):
        out[st.get("id")] = [c.text for c in st.findall("dcc:declaration/dcc:content", NS)]
    return out


def test_conformity_is_declared_as_decided(issued):
    """Each decision's DCC declaration: the acceptance as the certificate states it, no
    doubled "interval", no bare "—" probability; the guard band's δ of every item decided on
    its interval (half-width of the stated interval, U's place in w = r·U) in the DCC's own statement and on the
    certificate, en and zh; summary.txt (rate family) both guard bands where two."""

    res = issued["res"]
    decided = {k: it["conformity"] for k, it in res["items"].items()
               if it.get("conformity") and it["conformity"].get("outcome")}
    assert decided
    for lang in ("en", "zh"):
        decl = _declarations(issued["out"][lang]["dcc"])
        html = issued["out"][lang]["html"]
        band = [t for t in decl.get("guard-band-interval-items", [])]
        for key, c in decided.items():
            texts = decl[f"conformity-{key}"]
            en = texts[0]
            assert "acceptance interval interval" not in en, en
            assert "probability —;" not in en and not en.rstrip().endswith("—"), en
            if c["conformance_probability"] is None:
                # the bound an accepted interval item states (1 − p), or "—", with the reason
                bound = c.get("false_accept_bound")
                assert (re.search(r"probability ≤ [\d.]+ % \(not given", en) if bound
                        is not None else "— (not given" in en), en
            if lang == "zh":
                assert len(texts) == 2 and "接受" in texts[1], texts
            if c.get("acceptance_of") == "interval" and c["rule"] != "simple":
                lo_t, hi_t = c["stated_interval"]
                if str(c.get("probability_model") or "").startswith("chi-square"):
                    # a χ² bound: δ is its reach above the stated estimate
                    v_t = c["stated_value"]
                    assert c["U"] == pytest.approx(_number(hi_t) - _number(v_t), rel=1e-9)
                    want = f"δ = {hi_t} − {v_t}"
                else:
                    assert c["U"] == pytest.approx((_number(hi_t) - _number(lo_t)) / 2,
                                                   rel=1e-9)
                    want = f"δ = ({hi_t} − {lo_t})/2"
                assert band and all(want in b for b in band), (key, want, band)
                assert want in html_lib.unescape(re.sub(r"<[^>]+>", "", html)), (key, want)
    if issued["spec"] in ("jjf1535-2015", "iec62047-20", "triad-alignment"):
        for key, c in decided.items():
            line = next(ln for ln in issued["summary"].splitlines()
                        if ln.strip().startswith(f"{key}: limits"))
            lo = c.get("guard_band_lower")
            if lo is not None:
                it = res["items"][key]
                r = c["guard_factor"]
                assert lo == pytest.approx(r * (c["value"] - it["uncertainty"]["interval"][0]),
                                           rel=1e-9)
                assert f"guard bands {exact_band(lo)} at the lower limit, " \
                       f"{exact_band(c['guard_band'])} at the upper" in line, line
            elif c.get("guard_band"):
                assert f"guard band {exact_band(c['guard_band'])})" in line, line
            # the limits as the laboratory gave them (the lab file's text), never %g-rounded
            want = {"lower": None, "upper": None}
            for k_, v_ in CASES[issued["spec"]][1]:
                if k_ == key:
                    for part in v_.split("\n"):
                        name, val = (x.strip() for x in part.split("="))
                        val = val[:-2] if val.endswith(".0") else val   # 60.0 is 60
                        if name == "mpe":
                            want = {"lower": "-" + val, "upper": val}
                        else:
                            want[name] = val
            lims = (f"[{want['lower']}, {want['upper']}]" if want["lower"] and want["upper"]
                    else f"≤ {want['upper']}" if want["upper"] else f"≥ {want['lower']}")
            assert f"{key}: limits {lims} (" in line, (line, lims)


def exact_band(x: float, sig: int = 6) -> str:
    """A guard band as decided, exactly (w = r·U of printed numbers: a short decimal; 6
    significant digits, half up, clear the floating point's tail), written as the
    certificate writes a number (an independent writer: Decimal's own quantize, × 10 powers
    by hand)."""
    from decimal import ROUND_HALF_UP, Decimal

    d = Decimal(repr(float(x)))
    q = d.quantize(Decimal(1).scaleb(d.adjusted() - sig + 1), rounding=ROUND_HALF_UP)
    if q.adjusted() < -4:
        m, e = f"{q:e}".split("e")
        m = m.rstrip("0").rstrip(".")
        sup = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
        return f"{m}×10{str(int(e)).translate(sup)}"
    t = f"{q:f}"
    return t.rstrip("0").rstrip(".") if "." in t else t


def test_the_legend_names_each_interval_and_its_clauses(issued):
    """The legend under the results states each kind of interval present with the clauses
    of its items: the extreme of magnitudes (E; IEC 5.1.3.5, 5.2, 5.3.3.3, 5.3.3.8; JJF K_t,
    B_g, B_t) and IEC 5.1.3.7's corrected maximum among them, en and zh."""
    res = issued["res"]
    kinds = {"max-abs-interval": ("max_i |x_i|", "最大绝对值"),
             "interval of max|x_i| (uncertainty.extreme.max_abs_interval)":
                 ("max_i |x_i|", "最大绝对值"),
             "interval of the largest true spread inverting each record's own χ² test":
                 ("selection bias of the maximum", "选择偏差"),
             "chi-square": ("σ's χ² distribution", "χ² 分布"),
             "neyman-belt": ("confidence belt", "置信带")}
    items = _interval_items(res)
    if not items:
        return
    for n, lang in enumerate(("en", "zh")):
        html = issued["out"][lang]["html"]
        head = ("An item stated by an interval has that one statement" if lang == "en"
                else "以区间表述的项目只有这一个表述")
        at = html.index(head)
        legend = html_lib.unescape(re.sub(r"<[^>]+>", "", html[at:html.index("</p>", at)]))
        for key, it in items.items():
            clause = it["clause"] if lang == "en" else \
                it["clause"].replace(" (", "（").replace(")", "）")
            if lang == "zh" and issued["spec"] == "triad-alignment":
                # the triad's clauses are words ("thesis eq. 6.17"): the zh legend gives them
                # in Chinese by the triad's phrases ("论文式 6.17"), no English in a zh page
                from gonio.report.i18n import labels, reason_text
                from gonio.specs.triad_alignment.certificate import PHRASES_ZH
                clause = reason_text(it["clause"], labels("zh"), PHRASES_ZH)
            assert clause in legend, (lang, key, clause)
            phrase = kinds.get(it["uncertainty"]["k_source"])
            if (it.get("details") or {}).get("bound_condition") and phrase and \
                    phrase[0] == "max_i |x_i|":
                # the extreme of magnitudes with each point's bounded errors in its reach (JJF
                # K_t, B_t): its own kind, its clauses with its bounded lines' words in its part
                bound = ("into which bounded errors enter", "受有界误差影响的多个点")[n]
                assert bound in legend, (lang, key, bound)
                part = re.split(r"[;；]", legend[legend.index(bound):])[0]
                assert re.search(rf"[（(][^()（）]*{re.escape(clause)}[,，:：]", part), (
                    lang, key, part)
                continue
            if phrase:
                assert phrase[n] in legend, (lang, key, phrase[n])
                # the item's clause stands in the bracket after its kind's phrase (a clause
                # may hold a letter: IEC "5.4.5.1 b)"; the triad's, in zh, words: "论文式 6.20")
                part = legend[legend.index(phrase[n]):]
                bracket = re.search(r"[（(]([0-9a-z., ()（）、，\u4e00-\u9fff]+?)[)）](?:[;；.。]|$)",
                                    part)
                assert bracket and clause in bracket.group(1), (lang, key, part[:300])


def test_items_csv_nu_is_the_stated_nu(issued):
    """items.csv's ν is the ν the statement prints (the certificate's ν_eff column): empty
    where results.json's nu_eff is null and the certificate prints "—" (JJF warm-up time was
    "inf"), "inf" only where the stated ν is ∞ (ν_eff above the normal threshold; never for
    a χ² interval, whose ν is the one its bound used), else the integer part of
    results.json's nu_eff (GUM G.6.4), recomputed here."""
    import math

    from gonio.result.statement import NU_INFINITE

    res, rows = issued["res"], issued["rows"]
    for key, it in measured(res).items():
        nu, got = it["uncertainty"].get("nu_eff"), rows[key]["nu"]
        if nu is None:
            assert got == "", (key, got)
        elif got:
            # a χ² interval's ν: the one its bound is computed with, never ∞
            chi2 = it["uncertainty"].get("k_source") in ("chi-square",
                                                         "U = a + R: [0, (s + R)/(1 − g)]")
            want = (math.inf if nu > NU_INFINITE and not chi2
                    else float(max(1, math.floor(nu))))
            assert float(got) == want, (key, got, nu)


def test_dcc_coverage_probability_is_the_stated_one(issued):
    """si:coverageProbability is the p the certificate states ("p ≈ 98 %" is 0.98, never the
    computed 0.9823487503232564): at most the digits p_text keeps (its 3 decimals in per cent)
    and within a stated rounding step of a p results.json holds."""
    from decimal import Decimal

    ps = [u["coverage_probability"] for it in measured(issued["res"]).values()
          if (u := it.get("uncertainty")) and u.get("coverage_probability") is not None]
    for lang in ("en", "zh"):
        root = issued["out"][lang]["dcc"]
        for e in root.iter(f"{{{SI_NS}}}coverageProbability",
                           f"{{{SI_NS}}}coverageProbabilityXMLList"):
            for t in e.text.split():
                d = Decimal(t)
                assert -d.as_tuple().exponent <= 5, t          # 99.999 % at most
                assert any(abs(float(d) - p) <= 0.01 for p in ps), (t, ps)


def test_dcc_value_is_the_stated_value_with_its_sign(issued):
    """Every DCC quantity of an item's value holds the number the certificate states, sign
    and digits: a negative mean or bias (the triad's M_yx, b_y …) is written with its minus
    sign, worked out here from results.json's float and the printed decimals of the
    certificate's span (Decimal half-up, an independent rounding); a non-negative item whose
    bias-corrected estimate fell below zero (the optical K_l and C_v at seed 7, stated "≤ upper"
    with its note) is written as that bound, results.json's ``upper_bound`` and the end of
    its interval, never as the negative estimate the certificate does not print."""
    from decimal import ROUND_HALF_UP, Decimal

    from gonio.report.i18n import minus_sign

    res, html = issued["res"], issued["out"]["en"]["html"]
    negative = 0
    for lang in ("en", "zh"):
        for real in issued["out"][lang]["dcc"].iter(f"{{{SI_NS}}}real"):
            prev = real.getprevious()
            m = re.search(r"src=items\.([A-Za-z0-9_]+)\.value rule=s?dec(-?\d+)\b",
                          prev.text or "") if isinstance(prev, etree._Comment) else None
            if not m and isinstance(prev, etree._Comment) and ".upper_bound " in prev.text:
                key = re.search(r"src=items\.([A-Za-z0-9_]+)\.upper_bound", prev.text).group(1)
                it, got = res["items"][key], real.find("si:value", NS).text
                hi = real.find(".//si:intervalMax", NS).text
                assert it["value"] < 0 and float(got) == it["upper_bound"] and got == hi, \
                    (lang, key, got, it["value"], it["upper_bound"], hi)
                negative += 1
            if not m or "factor=" in prev.text:
                continue               # a power of ten or a unit conversion: tests above
            key, places = m.group(1), int(m.group(2))
            it = res["items"][key]
            got = real.find("si:value", NS).text
            want = Decimal(repr(it["value"])).quantize(Decimal(1).scaleb(-places),
                                                       rounding=ROUND_HALF_UP)
            assert Decimal(got) == want, (lang, key, got, it["value"])
            if it["value"] < 0 and want != 0:
                negative += 1
                assert got.startswith("-"), (lang, key, got)
                # the certificate prints the same signed digits, or states the bound alone
                span = re.findall(r'data-src="items\.' + key + r'\.value" data-rule="[^"]+">'
                                  r'([^<]*)<', html)
                assert not span or minus_sign(got) in span or got in span, (key, got, span)
    # a non-negative item whose bias-corrected estimate fell below zero, written as the
    # interval [0, upper bound] alone (no si:value: the certificate prints no estimate)
    for lang in ("en", "zh"):
        root = issued["out"][lang]["dcc"]
        for key, it in res["items"].items():
            if it.get("upper_bound") is None or not isinstance(it.get("value"), float) \
                    or it["value"] >= 0:
                continue
            result = root.find(f".//dcc:result[@id='result-{key}']", NS)
            assert result is not None, (lang, key)
            assert result.find(".//si:real/si:value", NS) is None, (lang, key)
            lists = [q for q in result.iter(f"{{{SI_NS}}}realListXMLList")
                     if (q.findtext("si:labelXMLList", namespaces=NS) or "")
                     == "intervalMin intervalMax"]
            assert len(lists) == 1, (lang, key)
            lo, hi = (Decimal(x) for x in lists[0].findtext("si:valueXMLList",
                                                             namespaces=NS).split())
            step = Decimal(1).scaleb(hi.as_tuple().exponent)
            assert lo == 0 and abs(hi - Decimal(repr(it["upper_bound"]))) <= step / 2, \
                (lang, key, lo, hi, it["upper_bound"])
            negative += 1
    if issued["spec"] in ("ogam-draft", "triad-alignment"):
        assert negative, "no negative item in this demo: the sign is not tested"


def test_dcc_real_keeps_a_value_below_its_interval():
    """gonio.report.dcc.real writes the stated value as given, also below its interval."""
    from gonio.report.dcc import new_document, real
    from gonio.report.stated import Num

    root = new_document()
    r = real(root, Num("-0.000015", "items.x.value", "dec6"), "%",
             interval=("0.000000", "0.000038"), u_std="0.000020", p=0.95)
    assert r.find("si:value", NS).text == "-0.000015"
    ci = r.find("si:measurementUncertaintyUnivariate/si:coverageIntervalMU", NS)
    assert (ci.find("si:intervalMin", NS).text, ci.find("si:intervalMax", NS).text) == \
        ("0.000000", "0.000038")


def _page_text(html: str) -> str:
    return html_lib.unescape(re.sub(r"<[^>]+>", "", html)).replace("\xa0", " ")


def _cells(row_html: str) -> list[str]:
    return [_page_text(c).strip() for c in re.findall(r"<t[dh][^>]*>(.*?)</t[dh]>", row_html,
                                                       re.S)]


def test_environment_conditions_carry_the_certificates_digits(issued):
    """The DCC's temperature and humidity are the numbers the certificate prints beside
    "Temperature" / "Relative humidity" (digits and all, as the laboratory file writes them: 20.1,
    never 20.10; 45.0 written 45.0, never 45), in both languages."""
    for lang in ("en", "zh"):
        html = issued["out"][lang]["html"]
        printed = {}
        for row in re.findall(r"<tr>(.*?)</tr>", html, re.S):
            cells = _cells(row)
            if len(cells) == 2 and cells[0] in ("Temperature", "Relative humidity", "温度",
                                                 "相对湿度"):
                m = re.match(r"(−?[\d.]+) (°C|%)", cells[1])
                if m:
                    printed["degC" if m.group(2) == "°C" else "%"] = m.group(1)
        assert set(printed) == {"degC", "%"}, (lang, printed)
        seen = {}
        for ic in issued["out"][lang]["dcc"].iter(f"{{{DCC_NS}}}influenceCondition"):
            name = ic.find("dcc:name/dcc:content", NS).text
            if "temperature" in name and "chamber" not in name or "humidity" in name:
                v = ic.find(".//si:real/si:value", NS)
                if v is not None:
                    seen["%" if "humidity" in name else "degC"] = v.text
        assert seen == {k: v.replace("−", "-") for k, v in printed.items()}, (lang, seen,
                                                                             printed)


def test_conformity_dash_note_only_where_a_dash_is_printed(issued):
    """The note '“—”: no probability is stated for …' stands under the conformity table only
    when a cell of the table prints "—", and names only items whose row prints one."""
    for lang in ("en", "zh"):
        html = issued["out"][lang]["html"]
        at = html.find('id="conformity"')
        if at < 0:
            continue
        table = html[at:html.index("</table>", at)]
        rows = {r[0]: r for r in (_cells(x) for x in re.findall(r"<tr>(.*?)</tr>", table, re.S))
                if r}
        after = _page_text(html[html.index("</table>", at):])
        head = "“—”: no probability is stated for " if lang == "en" else "“—”："
        m = re.match(r"\s*(?:<[^>]*>)*\s*" + re.escape(head) + r"(.+?)[:：]", after)
        dashed = {n for n, r in rows.items() if "—" in r[1:]}
        if m is None:
            continue
        assert dashed, (lang, "a note explains a '—' no row prints", m.group(0)[:200])
        for name in rows:
            if re.search(r"(^|, |、)" + re.escape(name) + r"(, |、|$)", m.group(1)):
                assert name in dashed, (lang, name, rows[name])


def test_p_is_stated_one_way(issued):
    """A p the procedure chooses (95 %, 95.45 %: every k and interval is computed for it) is
    "p = …" in every output, en and zh: certificate, summary.txt and the DCC's texts; never
    "p ≈ 95 %", "approximately 95 %" or "约 95 %". A computed p (98 %, 99 % of a grid) is
    "p ≈ …"."""
    from gonio.result.statement import CHOSEN_P_TEXTS

    texts = {"summary": issued["summary"]}
    for lang in ("en", "zh"):
        texts[f"html-{lang}"] = _page_text(issued["out"][lang]["html"])
        texts[f"dcc-{lang}"] = " ".join(
            c.text or "" for c in issued["out"][lang]["dcc"].iter(f"{{{DCC_NS}}}content"))
    assert "95" in CHOSEN_P_TEXTS
    seen = 0
    for where, t in texts.items():
        t = t.replace("\xa0", " ")
        assert not re.search(r"(approximately|约)\s*95(\.45)? %", t), where
        for rel, p in re.findall(r"(?<![−-] )\bp ([≈=]) ([\d.]+) %", t):   # not "1 − p"
            seen += 1
            assert rel == ("=" if p in ("95", "95.45") else "≈"), (where, rel, p)
    assert seen


def test_scale_factor_unit_text_is_one_per_page_kind(issued):
    """The scale factor's unit: one printed text (gonio.result.statement.unit_text_in) on the
    certificate in each language and on the web page, its D-SI form in the DCC; the data
    files (results.json, items.csv, summary.txt) keep the unit key."""
    from gonio.records.results import conformity_of
    from gonio.result.statement import DSI_UNITS, unit_text_in

    res = issued["res"]
    for key, it in res["items"].items():
        if not it["measured"] or it["unit"] != "counts/deg":
            continue
        for lang in ("en", "zh"):
            html = issued["out"][lang]["html"]
            row = next(r for r in re.findall(r"<tr>(.*?)</tr>", html, re.S)
                       if f'data-src="items.{key}.value"' in r)
            assert _cells(row)[-1] == unit_text_in("counts/deg", lang), (lang, _cells(row))
            text = _page_text(html)
            for other in ("counts/deg", "1/°", "counts/°" if lang == "zh" else "脉冲数/(°)"):
                assert other not in text, (lang, other)
            reals = _dcc_reals(issued["out"][lang]["dcc"])
            assert reals[(key, "value")].find("si:unit", NS).text == DSI_UNITS[it["unit"]][0]
        # the web page's conformity table of a decision on K
        doc = {"items": {key: {**it, "conformity": {
            "item": key, "U": 0.02, "lower": it["value"] - 1, "upper": it["value"] + 1,
            "rule": "simple", "guard_band": 0.0, "acceptance_lower": it["value"] - 1,
            "acceptance_upper": it["value"] + 1, "outcome": "pass", "accepted": True,
            "conformance_probability": 0.99, "false_accept_probability": 0.01}}}}
        row = conformity_of(doc)["rows"][0]
        assert row["limits"].endswith(" " + unit_text_in("counts/deg", "en")), row
        assert issued["rows"][key]["unit"] == it["unit"] == "counts/deg"
