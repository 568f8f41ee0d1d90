"""What the tests comparing one item's numbers across outputs share (tests/test_one_statement.py:
results.json, the certificate, summary.txt, the DCC; tests/records/test_web_numbers.py: the
records' web pages): which items are measured, which are stated by one interval (worked out
from results.json's numbers, not from the statement rule), the certificate's number spans,
k checked against scipy's t quantile of the stated ν, and one statement cell's numbers parsed
back from its text."""

from __future__ import annotations

import math
import re

import pytest

from gonio.result.statement import chi2_stated_nu


def by_interval(it: dict) -> bool:
    """Whether the item must be stated by one interval (worked out from its numbers)."""
    u = it["uncertainty"]
    if u["k"] is None:
        return True
    return bool(it.get("nonnegative")) and u["U"] > it["value"]


#: k_source of an item stated by the interval of an extreme of magnitudes (E, 7.4): its
#: interval belongs to max|E_i| (``details.max_abs_arcsec``), its value is the signed extreme.
MAX_ABS = "max-abs-interval"


def value_field(it: dict) -> str:
    """The results.json field (under the item) the item's statement belongs to: ``value``,
    or ``details.max_abs_arcsec`` for the interval of an extreme of magnitudes."""
    return "details.max_abs_arcsec" if it["uncertainty"].get("k_source") == MAX_ABS \
        else "value"


def stated_value(it: dict) -> float:
    """The number the item's statement belongs to (:func:`value_field`)."""
    return it["details"]["max_abs_arcsec"] if value_field(it) != "value" else it["value"]


def measured(res: dict) -> dict:
    """The items of results.json ``res`` measured with a value and a U."""
    return {k: it for k, it in res["items"].items()
            if it["measured"] and it["value"] is not None and it.get("uncertainty")
            and it["uncertainty"].get("U")}


_NUM_SPAN = re.compile(r'<span class="num" data-src="items\.([A-Za-z0-9_]+)\.'
                       r'(value|details\.max_abs_arcsec|uncertainty\.U|uncertainty\.k|'
                       r'uncertainty\.nu_eff)"'
                       r' data-rule="[^"]+">([^<]*)</span>')


def certificate_spans(html: str) -> dict:
    """(item key, "value" | "uncertainty.U" | "uncertainty.k" | "uncertainty.nu_eff") → the set
    of texts the certificate's HTML prints in its number spans (no-break spaces as spaces)."""
    spans: dict = {}
    for key, what, text in _NUM_SPAN.findall(html.replace("\xa0", " ")):
        spans.setdefault((key, what), set()).add(text)
    return spans


def check_k(key: str, it: dict) -> None:
    """results.json's k is t_p of the ν it states (the integer part of ν_eff, GUM G.6.4; the
    normal quantile for ν_eff ∞), checked with scipy, and U = k u_c; p is stated."""
    from scipy.stats import norm, t

    from gonio.result.statement import stated_nu

    u = it["uncertainty"]
    p = u.get("coverage_probability")
    assert p is not None, f"{key}: no coverage probability in results.json"
    if u["k"] is None or u.get("k_source") == "fixed":
        return
    if u.get("k_source") == "jcgm101-convolution":
        assert u["nu_eff"] is None, f"{key}: a k of the combined distribution states no ν"
        want = combined_k_of_components(u["components"], u["u_c"], p)
        assert u["k"] == pytest.approx(want, rel=0.01), (key, u["k"], want)
        assert u["U"] == pytest.approx(u["k"] * u["u_c"], rel=1e-9), key
        return
    nu = stated_nu(u["nu_eff"])
    q = 0.5 + p / 2
    want = norm.ppf(q) if nu is None or math.isinf(nu) else t.ppf(q, nu)
    assert u["k"] == pytest.approx(want, rel=1e-9), (key, u["k"], u["nu_eff"], want)
    assert u["U"] == pytest.approx(u["k"] * u["u_c"], rel=1e-9), key


def combined_k_of_components(components, u_c: float, p: float, m: int = 400_000,
                             seed: int = 11) -> float:
    """k = U_p/u_c of the sum of results.json's budget lines, each drawn here in its stated
    distribution with its stated u (the lines uncorrelated, as every budget whose k is its
    combined distribution's): a second Monte Carlo, written apart from gonio's sampler, with
    its own seed (JCGM 101 6.4: normal; t with ν as scaled and shifted t, 6.4.9; arcsine
    A sin φ, u = A/√2; rectangular, u = a/√3; triangular, u = a/√6; the product of two zero-mean
    rectangulars, u = ab/3)."""
    import numpy as np

    rng = np.random.default_rng(seed)
    y = np.zeros(m)
    for c in components:
        u, d = abs(float(c["u"])), c["distribution"]
        if d in ("normal", "gaussian") or (d == "t" and c.get("dof") is None):
            y += rng.normal(0.0, u, m)
        elif d == "t":
            y += u * rng.standard_t(float(c["dof"]), m)
        elif d in ("arcsine", "u-shaped"):
            y += u * math.sqrt(2.0) * np.sin(rng.uniform(0.0, 2.0 * math.pi, m))
        elif d in ("rectangular", "uniform"):
            y += rng.uniform(-1.0, 1.0, m) * u * math.sqrt(3.0)
        elif d == "triangular":
            y += rng.triangular(-1.0, 0.0, 1.0, m) * u * math.sqrt(6.0)
        elif d == "rectangular-product":
            y += rng.uniform(-1.0, 1.0, m) * rng.uniform(-1.0, 1.0, m) * 3.0 * u
        else:
            raise AssertionError(f"no test sampler for distribution {d!r}")
    return float(np.quantile(np.abs(y), p)) / float(u_c)


_CELL_FIELDS = {"U": r" ± (\S+)", "k": r"\bk = ([^,)\s]+)", "nu_eff": r"ν_eff = ([^,)\s]+)",
                "p": r"p [≈=] (\S+) %", "interval": r"\[(\S+), (\S+)\]", "upper": r"≤ (\S+)"}


def cell_numbers(text: str) -> dict:
    """The numbers of one statement written on one line ("−0.7224 ± 0.0020 lsb/(°/s) (k = 2.2,
    ν_eff = 14, p = 95 %)", "0.112 ″; interval [0.066, 0.204] ″ (p = 95 %)", "upper bound: ≤
    0.53 °/h (interval [0, 0.53], p = 95 %); …"): field → its text, or the list of its texts
    where the line holds it more than once (a second statement); ``value`` is the first word
    unless the line opens with an upper bound. A Chinese line (the certificate's zh form:
    "0.0006；上限：≤ 0.0028（区间 [0, 0.0028]，p = 95 %）") is read with its full-width
    punctuation as the English line's."""
    for zh, en in (("；", "; "), ("：", ": "), ("（", " ("), ("）", ")"), ("，", ", ")):
        text = text.replace(zh, en)
    out: dict = {}
    first = text.split(" ", 1)[0]
    if not text.startswith(("upper bound", "上限")):
        out["value"] = first.rstrip(";；")
    for field, pat in _CELL_FIELDS.items():
        found = re.findall(pat, text)
        if found:
            out[field] = found[0] if len(found) == 1 else found
    return out


def expected_cell(it: dict) -> dict:
    """The fields :func:`cell_numbers` must find in a page's statement of results.json item
    ``it``: the statement rule's texts (:func:`gonio.result.statement.item_statement`), each
    negative number with U+2212 as the pages print it."""
    from gonio.report.i18n import minus_sign
    from gonio.result.statement import item_statement

    st = item_statement(it)
    want: dict = {} if st.below_zero else {"value": minus_sign(st.value_text)}
    if st.U is not None:
        want["U"] = st.U_text
    if st.k is not None:
        want["k"] = st.k
    if st.nu_eff is not None and (st.interval is None or not chi2_stated_nu(
            (it.get("uncertainty") or {}).get("k_source"))):
        # beside U, or beside an interval that is not χ² ("; ν_eff = 7"; a χ² one's "; ν =")
        want["nu_eff"] = st.nu_eff
    if st.p is not None:
        want["p"] = st.p
    if st.interval is not None:
        ends = tuple(minus_sign(x) for x in st.interval_ends)
        if st.upper is not None or st.below_zero:      # one-sided from the natural bound 0
            want["upper"], ends = ends[1], ("0", ends[1])
        want["interval"] = ends
    return want


def nu_eff_interval_items(res: dict) -> dict:
    """Measured items whose printed statement is an interval (an upper bound: U above the
    value of a non-negative item; or a stated interval without k) that is not χ², with a
    ν_eff: {key: ν as stated, worked out here: the integer part (GUM G.6.4), "∞" above
    1000 (gonio's NU_INFINITE, where k is the normal quantile)}."""
    out = {}
    for key, it in res["items"].items():
        unc = it.get("uncertainty") or {}
        nu = unc.get("nu_eff")
        if not it.get("measured") or nu is None \
                or chi2_stated_nu(unc.get("k_source")):
            continue
        upper_bound = (it.get("nonnegative") and unc.get("k") is not None
                       and unc.get("U") is not None and unc["U"] > it["value"] >= 0)
        if upper_bound or (unc.get("interval") is not None and unc.get("k") is None):
            out[key] = "∞" if not math.isfinite(nu) or nu > 1000 else str(math.floor(nu))
    return out
