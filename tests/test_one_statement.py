"""One 95 % statement per item, in every output of every specification's demo.

For each specification ``gonio demo --spec KEY --seed 3`` writes results.json, summary.txt,
the certificate's HTML and the DCC. Every measured item must carry exactly one statement:

- either value ± U with its k (results.json ``k`` set, U not above the value when the
  item cannot be negative), shown once as U in the certificate and once as an expanded
  uncertainty in the DCC;
- or one coverage interval (a dispersion stated by its χ² interval — ``k`` null, ``U`` the
  distance to the upper end —, or a non-negative item whose U exceeds its value, stated by
  [0, value + U]): no U span in the certificate, no "±" beside it in summary.txt, one
  si:coverageIntervalMU in the DCC, no expanded uncertainty and no separate upper-bound
  quantity anywhere.

The expected statement is worked out here from results.json's numbers (not from the
statement rule), so a second statement written anywhere, or the wrong one, fails.
"""

from __future__ import annotations

import json
import math
import re

import pytest
from lxml import etree

from gonio.report.dcc import DCC_NS, SI_NS
from tests.statement_numbers import (by_interval, certificate_spans, check_k, measured,
                                     stated_value, value_field)

NS = {"dcc": DCC_NS, "si": SI_NS}
SPECS = ("ogam-draft", "jjf1535-2015", "iec62047-20", "triad-alignment")


@pytest.fixture(scope="module", params=SPECS)
def demo(request, shared_demo):
    """``gonio demo --spec KEY --seed 3``'s folder, made once per session (read only)."""
    d = shared_demo(request.param, seed=3)
    return {"spec": request.param, "dir": d,
            "res": json.loads((d / "results.json").read_text(encoding="utf-8")),
            "summary": (d / "summary.txt").read_text(encoding="utf-8"),
            "html": (d / "certificate.html").read_text(encoding="utf-8"),
            "dcc": etree.parse(str(d / "certificate.dcc.xml")).getroot()}


def test_results_json_holds_one_statement_per_item(demo):
    items = measured(demo["res"])
    assert items
    for key, it in items.items():
        u = it["uncertainty"]
        if u["k"] is None:           # the interval is the statement; U reaches its upper end
            lo, hi = u["interval"]   # (of max|E_i| for E, 7.4: its value is the signed extreme)
            v = stated_value(it)
            assert lo == 0.0 or lo <= v, key
            assert v + u["U"] == pytest.approx(hi, rel=1e-9), key
        if by_interval(it):
            assert it.get("upper_bound") is None or it["upper_bound"] >= it["value"] + u["U"] \
                - 1e-12 * abs(it["value"] + u["U"]), key
        else:
            assert it.get("upper_bound") is None, key     # no bound beside ± U
            assert u["U"] > 0 and u["k"] > 0, key
        if u["k"] is not None:
            assert u.get("interval") is None, key         # no interval beside ± U


def test_certificate_html_states_each_item_once(demo):
    html = demo["html"]
    for key, it in measured(demo["res"]).items():
        spans = set(re.findall(r'data-src="items\.' + re.escape(key) + r'\.uncertainty\.U"'
                               r' data-rule="[^"]+">([^<]*)<', html))
        if by_interval(it):
            assert spans == set(), key        # no U beside the interval
        else:
            assert len(spans) <= 1, (key, spans)


def test_summary_has_no_second_statement(demo):
    res, lines = demo["res"], demo["summary"].splitlines()
    for key, it in measured(res).items():
        title = it.get("title") or key
        rows = [ln for ln in lines if title + ":" in ln or (title in ln and it["clause"] in ln)]
        for ln in rows:
            assert ln.count("p ≈") + ln.count("p = ") <= 1, (key, ln)
            if by_interval(it):
                assert " ± " not in ln and "k = " not in ln, (key, ln)
                iv = it["uncertainty"].get("interval")
                # two-sided: JJF 7.2.6/7.2.7's outcome, or a signed quantity's interval (the
                # triad's bound-condition statement of M, S, L, K); an interval from 0 (a
                # magnitude's, e.g. the optical E's max |E_i|) is stated by its bound
                if iv is not None and iv[0] != 0:
                    assert "interval [" in ln and "≤ " not in ln, (key, ln)
                else:
                    assert "≤ " in ln, (key, ln)
    # the optical draft's extra lines: no second interval of B_s or R
    assert not re.search(r"^(zero_stability|repeatability): 95 % interval", demo["summary"],
                         re.M)


def _beside_estimates(res: dict):
    """(item, name, estimate) of every estimate given beside an item's stated value."""
    for key, it in res["items"].items():
        details = it.get("details") or {}
        stated = details.get("stated")
        for name, est in (details.get("estimates") or {}).items():
            if est is not None and name != stated:
                yield key, name, est


def test_an_estimate_beside_the_statement_claims_no_coverage(demo):
    """An estimate given beside the stated value (the optical draft's noise-model B_s)
    carries its standard uncertainty only: no U, k, interval or 95 % anywhere."""
    for key, name, est in _beside_estimates(demo["res"]):
        u = est.get("uncertainty") or {}
        for field in ("U", "k", "interval", "coverage_probability"):
            assert u.get(field) is None, (key, name, field)
    for ln in demo["summary"].splitlines():
        if "not stated)" in ln and not ln.startswith("note:"):   # an estimate's own line
            assert "95" not in ln and "k = " not in ln and "U = " not in ln, ln


def _real_uncertainties(root) -> dict:
    """item key → list of (kind, si:real) for every si:real whose value is the item's."""
    out: dict = {}
    for real in root.iter(f"{{{SI_NS}}}real"):
        prev = real.getprevious()
        if not isinstance(prev, etree._Comment):
            continue
        m = re.search(r"src=items\.([A-Za-z0-9_]+)\.(value|details\.max_abs_arcsec)\b",
                      prev.text or "")
        if not m:
            continue
        mu = real.find("si:measurementUncertaintyUnivariate", NS)
        kinds = [] if mu is None else [etree.QName(c).localname for c in mu]
        out.setdefault(m.group(1), []).append((kinds, real, m.group(2)))
    return out


def test_dcc_states_each_item_once(demo):
    root = demo["dcc"]
    assert root.find(".//dcc:quantity[@refType='gonio_upperBound']", NS) is None
    reals = _real_uncertainties(root)
    for key, it in measured(demo["res"]).items():
        if key not in reals:
            continue                 # an item the DCC writes in a matrix of its own form
        for kinds, real, field in reals[key]:
            assert len(kinds) <= 1, (key, kinds)
            if field != value_field(it):     # E's signed extreme beside its statement
                assert kinds == [], (key, field, kinds)
                continue
            e_bound = key == "angle_deviation" and ((demo["res"].get("extra") or {}).get(
                "uncertainty") or {}).get("u_c_certified", True) is False
            if by_interval(it) and ((it.get("details") or {}).get("bound_condition")
                                    or e_bound):
                # certified by value ± (a + k·u) (the optical E: each point's k·u + b), no
                # u_c on the certificate: the interval's ends in the next quantity, no
                # standard uncertainty (item_dcc.u_c_certified, ogam stated.e_u_c_certified)
                assert kinds == [], (key, kinds)
                nxt = real.getparent().getnext()
                assert nxt.find("si:realListXMLList/si:labelXMLList", NS).text == \
                    "intervalMin intervalMax", key
                lo_text, hi_text = nxt.find("si:realListXMLList/si:valueXMLList", NS).text.split()
                ulp = 10.0 ** -len(hi_text.partition(".")[2]) if "." in hi_text else 1.0
                want = stated_value(it) + it["uncertainty"]["U"]
                assert want * (1 - 1e-12) <= float(hi_text) < want + ulp * (1 + 1e-9), key
                assert float(lo_text) <= stated_value(it), key
                continue
            if by_interval(it):
                assert kinds == ["coverageIntervalMU"], (key, kinds)
                if it["unit"].endswith("/g"):     # written per m s⁻² (tests/test_rate_dcc.py)
                    continue
                ci = real.find("si:measurementUncertaintyUnivariate/si:coverageIntervalMU", NS)
                hi_text = ci.find("si:intervalMax", NS).text
                hi = float(hi_text)
                want = stated_value(it) + it["uncertainty"]["U"]
                # rounded up, by less than one unit of its last decimal (the statement's
                # decimals are U's, so a bound below U can move by more than a few per cent)
                ulp = 10.0 ** -len(hi_text.partition(".")[2]) if "." in hi_text else 1.0
                assert want * (1 - 1e-12) <= hi < want + ulp * (1 + 1e-9), (key, hi, want)
                lo = float(ci.find("si:intervalMin", NS).text)
                # a non-negative item's interval starts at 0 even where its estimate is below
                # (K_l corrected for its range's bias can be negative)
                assert lo <= stated_value(it) or (it.get("nonnegative") and lo == 0.0), key
            elif kinds:
                assert kinds == ["expandedMU"], (key, kinds)


def test_numbers_agree_across_outputs(demo):
    """The same numbers of every measured item in results.json, the certificate (its spans
    carrying data-src), summary.txt and the DCC: value, U, k and ν as the statement rule
    states them from results.json; the interval's ends; one coverage probability. k is
    t_p of the ν it states (the integer part of ν_eff, GUM G.6.4), checked with scipy."""
    from gonio.report.dcc import dsi_decimal
    from gonio.report.i18n import minus_sign
    from gonio.result.statement import item_statement, k_text, nu_text, p_text

    res, summary = demo["res"], demo["summary"]
    html = demo["html"].replace("\xa0", " ")
    spans = certificate_spans(html)
    reals = _real_uncertainties(demo["dcc"])
    lines = summary.splitlines()
    for key, it in measured(res).items():
        st, u = item_statement(it), it["uncertainty"]
        check_k(key, it)
        p = u["coverage_probability"]
        assert st.p == p_text(p), key
        # the certificate (a negative number printed with U+2212, as the pages print it)
        shown = minus_sign(st.value_text)
        assert spans.get((key, value_field(it)), {shown}) == {shown}, key
        if st.U is not None:
            assert spans.get((key, "uncertainty.U"), {st.U_text}) == {st.U_text}, key
        if st.k is not None:
            assert spans.get((key, "uncertainty.k"), {st.k}) == {st.k}, key
        if st.nu_eff is not None:
            assert spans.get((key, "uncertainty.nu_eff"), {st.nu_eff}) == {st.nu_eff}, key
        if st.interval is not None and (key, value_field(it)) in spans:
            lo, hi = (minus_sign(e) for e in st.interval_ends)   # negative ends print U+2212
            assert (f"≤ {hi}" if st.upper is not None else f"[{lo}, {hi}]") in html, key
        # summary.txt: one line holds the value with its U and k, or with its interval
        # (a non-negative item whose estimate fell below zero: its upper bound alone)
        want = [f"≤ {st.interval_ends[1]}"] if st.below_zero else \
            [st.value_text] + ([st.U_text, f"k = {st.k}"] if st.U is not None else
                               [st.interval_ends[1]] if st.interval is not None else [])
        assert any(all(w in ln for w in want) for ln in lines), (key, want)
        own = re.compile(rf"(?<![\d.]){re.escape(st.value_text)}(?![\d])")  # a whole number
        for ln in lines:
            if own.search(ln) and (st.U_text or "≤") in ln:
                for m in re.finditer(r"ν_eff = (\S+?)[,)]", ln):
                    assert m.group(1) == nu_text(u["nu_eff"]), (key, ln)
                for m in re.finditer(r"p [≈=] (\S+) %", ln):
                    assert m.group(1) == st.p, (key, ln)
        # the DCC (a per-g item is written per m s⁻² there: tests/test_rate_dcc.py)
        for kinds, real, field in ([] if it["unit"].endswith("/g") else reals.get(key, [])):
            if field != value_field(it):     # E's signed extreme: its own number
                continue
            # the stated value with its sign and digits, also for an item stated by its bound
            # alone (its bias-corrected estimate fell below zero): never a 0 in its place
            assert real.find("si:value", NS).text == dsi_decimal(st.value_text), key
            mu = real.find("si:measurementUncertaintyUnivariate/*", NS)
            if mu is None and (it.get("details") or {}).get("bound_condition"):
                nxt = real.getparent().getnext()        # its interval's ends, no u
                assert tuple(nxt.find("si:realListXMLList/si:valueXMLList", NS).text.split()) \
                    == tuple(dsi_decimal(x) for x in st.interval_ends), key
                assert f"p = {st.p} %" in "".join(nxt.find("dcc:name", NS).itertext()), key
                continue
            if mu is None:
                continue
            # the p the certificate states ("p ≈ 98 %" is 0.98), never more digits than it
            dp = mu.find("si:coverageProbability", NS).text
            assert p_text(float(dp)) == st.p and abs(float(dp) - p) <= 0.005, (key, dp, p)
            assert len(dp.split(".")[1]) <= len(st.p.replace(".", "")) + 2, (key, dp, st.p)
            if kinds == ["expandedMU"]:
                assert mu.find("si:valueExpandedMU", NS).text == dsi_decimal(st.U_text), key
                # the stated k, digits and all ("2.00" for a t-factor 1.9955, never "2")
                kt = mu.find("si:coverageFactor", NS).text
                assert kt == dsi_decimal(st.k) and k_text(float(kt)) in (st.k, kt.rstrip(
                    "0").rstrip(".")), key
            elif kinds == ["coverageIntervalMU"]:
                assert (mu.find("si:intervalMin", NS).text, mu.find("si:intervalMax", NS).text) \
                    == tuple(dsi_decimal(x) for x in st.interval_ends), key


def test_items_csv_states_the_certificates_numbers(demo):
    """tables/items.csv carries each item's one statement: value ± U with k and the ν k was
    computed from (k = t_p(ν) checked with scipy; ν empty where k came from elsewhere, a JCGM
    101 convolution's k), or the interval's ends with U and k empty (no reach that reads as
    value ± U beside the interval); worked out here from results.json's numbers."""
    import pandas as pd
    from scipy import stats

    rows = pd.read_csv(demo["dir"] / "tables" / "items.csv", keep_default_na=False,
                       na_values=[""]).set_index("item")
    assert {"interval_low", "interval_high"} <= set(rows.columns)
    for key, it in measured(demo["res"]).items():
        row, u = rows.loc[key], it["uncertainty"]
        p = u["coverage_probability"]
        if by_interval(it):
            assert pd.isna(row["U"]) and pd.isna(row["k"]), key
            lo, hi = u["interval"] if u.get("interval") is not None else \
                (0.0, it["value"] + u["U"])
            assert (row["interval_low"], row["interval_high"]) == pytest.approx((lo, hi)), key
            assert row["value"] == pytest.approx(stated_value(it)) or (
                pd.isna(row["value"]) and it["value"] < 0), key
            nu = u["nu_eff"]
            # a χ² interval's ν (also the χ² reach of a dispersion's one-sided bound
            # condition): the one its limit is computed with, never ∞
            chi2 = u.get("k_source") in ("chi-square", "U = a + R: [0, (s + R)/(1 − g)]")
            assert (pd.isna(row["nu"]) if nu is None else
                    row["nu"] == (math.inf if nu > 1000 and not chi2
                                  else max(1, math.floor(nu)))), key
            # u only where the certificate states u_c (not a bound-condition item's)
            from gonio.report.stated import u_c_certified
            assert (row["u"] == pytest.approx(u["u_c"]) if u_c_certified(it)
                    else pd.isna(row["u"])), key
            continue
        assert pd.isna(row["interval_low"]) and pd.isna(row["interval_high"]), key
        assert row["U"] == pytest.approx(u["U"]) and row["k"] == pytest.approx(u["k"]), key
        if pd.isna(row["nu"]) and u["nu_eff"] is None and math.isclose(
                u["k"], stats.norm.ppf(0.5 + p / 2), rel_tol=1e-6):
            pass    # an infinite ν_eff, stored null: no ν stated (the certificate's "—")
        elif pd.isna(row["nu"]):    # k did not come from a ν: no t-factor of any ν
            nu = u["nu_eff"]
            nu_s = math.inf if nu is None or nu > 1000 else max(1, math.floor(nu))
            assert not math.isclose(u["k"], stats.t.ppf(0.5 + p / 2, nu_s), rel_tol=1e-6), key
        else:                       # ν as stated, and k = t_p(ν) of it
            assert u["k"] == pytest.approx(stats.t.ppf(0.5 + p / 2, row["nu"]), rel=1e-6), key
            nu = u["nu_eff"]
            assert row["nu"] == (math.inf if nu is None or nu > 1000
                                 else max(1, math.floor(nu))), key
