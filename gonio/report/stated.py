"""Numbers as every certificate states them: one rounding rule, one form, one place.

Contents
========
===========================  ================================================================
:class:`Num`                 a shown number: its text, its path in ``results.json``, its rule
:class:`NoBreakText`         text never broken across lines (identifiers, units, intervals)
:func:`lookup`, :func:`num`  the value at a path of results.json, and that value displayed
:func:`item_nums`            one per-item result as stated by the one statement rule
:func:`conformity_texts`     limits, acceptance interval, outcome and probabilities as text
:func:`conformity_blocks`    the statement-of-conformity section of a per-item result
===========================  ================================================================

The certificates (HTML, PDF), ``summary.txt``, the CLI and the DCC XML of every specification
take their numbers from here or from a specification's own stating module built on it
(its rendering module ``stated``), so they cannot disagree. The rule is
:func:`gonio.result.statement.state` (JCGM 100 7.2.6: U to two significant digits, the value
to the same decimal place). Nothing is computed here beyond rounding.
"""

from __future__ import annotations

from dataclasses import dataclass
from decimal import ROUND_CEILING, ROUND_FLOOR
from typing import Any

from gonio.analysis.conformity import DEFAULT_LIMITS_ORIGIN
from gonio.report.i18n import display, display_uncertainty
from gonio.result.text import measured_clause
from gonio.result.statement import (K_SOURCE_BOUND_CHI2, K_SOURCE_BOUND_PREFIX,  # noqa: F401
                                    K_SOURCE_CHI2, K_SOURCE_MAX_ABS, chi2_stated_nu,
                                    K_SOURCE_SELECTED_MAX, K_SOURCE_SELECTED_MAX_BEFORE,
                                    bound_up_text, decimals_for_sig, given_text,
                                    round_half_up, u_c_certified)


class NoBreakText(str):
    """Text that is never broken across lines (identifiers, units, intervals): HTML
    ``nowrap``, one token in the PDF's wrapping (:mod:`gonio.report.render`)."""


class FlagText(str):
    """A warning beside a value (a line of the first page the readings contradict): red in
    the HTML (``class="flag"``) and the PDF (:mod:`gonio.report.render`)."""


@dataclass(frozen=True)
class Num:
    """A number shown: its text, its path in results.json, its display rule."""

    text: str
    src: str
    rule: str

    def __str__(self) -> str:
        return self.text


def lookup(res: dict, src: str) -> Any:
    """The value at a dotted path of results.json ("a.b.0.c")."""
    v: Any = res
    for part in src.split("."):
        v = v[int(part)] if isinstance(v, list) else v[part]
    return v


def num(res: dict, src: str, rule: str, U: float | None = None) -> Num | str:
    """The value at ``src`` displayed with ``rule`` (``"—"`` when it is null)."""
    v = lookup(res, src)
    if v is None:
        return "—"
    return Num(display(rule, v, U), src, rule)


# --------------------------------------------------------------------------- conformity


def interval_text(lo, hi, f) -> str:
    """[lo, hi] with ``f`` formatting each end; one open end reads "≤ hi" or "≥ lo".

    >>> interval_text(None, 0.3, given_text), interval_text(-0.5, 0.5, given_text)
    ('≤ 0.3', '[-0.5, 0.5]')
    """
    if lo is None and hi is None:
        return "—"
    if lo is None:
        return f"≤ {f(hi)}"
    if hi is None:
        return f"≥ {f(lo)}"
    return f"[{f(lo)}, {f(hi)}]"


def conformity_texts(c, res: dict | None, L: dict, nonnegative: bool | None = None) -> dict:
    """Limits (as given), acceptance interval (at U's decimal place), outcome and
    probabilities of one statement as text. ``c`` is a
    :class:`~gonio.analysis.conformity.Conformity` or its results.json dict. An empty
    acceptance interval (guard bands wider than the tolerance, the decision's
    ``acceptance_empty``) is said in words; so is the acceptance interval of a non-negative
    quantity (``nonnegative``, else the item's own flag in ``res``) whose upper end lies below
    zero: [0, -40] is empty, never "≤ -40 s". An acceptance interval that bounds the ends of
    the item's stated interval (``acceptance_of`` "interval") says so ("interval's upper end
    ≤ 0.5"); an end equal to the limit is the limit as given. ``no_p``: the reason no
    probability is given (the decision's ``probability_model`` where it gives none), or "".

    >>> L = {"c_acc_empty": "none", "accept": "conforms"}
    >>> c = {"U": 100.0, "upper": 60.0, "acceptance_upper": -40.0, "outcome": "accept"}
    >>> conformity_texts(c, None, L)["acceptance"], conformity_texts(c, None, L, True)["acceptance"]
    ('≤ -40', 'none')
    >>> c = {"U": 1.2e-4, "upper": 3.95e-5, "acceptance_upper": 3.95e-5, "outcome": "accept",
    ...      "acceptance_of": "interval"}
    >>> conformity_texts(c, None, L)["acceptance"]
    "interval's upper end ≤ 3.95×10⁻⁵"
    """
    g = (lambda k: c.get(k)) if isinstance(c, dict) else (lambda k: getattr(c, k, None))  # noqa: E731
    if nonnegative is None and res is not None:
        items = res.get("items") if isinstance(res.get("items"), dict) else res
        it = items.get(g("item")) if g("item") else None
        it = it if isinstance(it, dict) else {}
        nonnegative = bool(it.get("nonnegative") or (it.get("uncertainty") or {}).get(
            "nonnegative"))
    U = g("U")
    dec = decimals_for_sig(float(U), 2) if U else None
    lims = {x for x in (g("lower"), g("upper")) if x is not None}
    al, au = g("acceptance_lower"), g("acceptance_upper")

    texts = {id(x): t for x, t in ((al, g("acceptance_lower_text")),
                                    (au, g("acceptance_upper_text"))) if x is not None and t}

    def f(v):
        if id(v) in texts:                  # decided once in the Result: printed as stored
            return texts[id(v)]
        # (an older result) an acceptance limit rounded inward (upper down, lower up) to U's places: the printed
        # acceptance interval is never wider than the decided one, so a printed end that
        # meets the printed limit was accepted (a half-up 0.4556 printed 0.456 beside an
        # interval end 0.4558 printed 0.456 and a "fail")
        if dec is None or v in lims:
            return given_text(v)
        return round_half_up(v, dec, ROUND_FLOOR if v is au else ROUND_CEILING)
    if g("acceptance_empty") or (al is not None and au is not None and al > au) or (
            nonnegative and au is not None and au < 0):
        acc = L["c_acc_empty"]
    elif g("acceptance_of") == "interval" and (al is not None or au is not None):
        en = {"c_acc_iv_upper": "interval's upper end ≤ {hi}",
              "c_acc_iv_lower": "interval's lower end ≥ {lo}",
              "c_acc_iv_both": "interval within [{lo}, {hi}]"}
        which = ("c_acc_iv_both" if al is not None and au is not None
                 else "c_acc_iv_upper" if au is not None else "c_acc_iv_lower")
        acc = L.get(which, en[which]).format(lo=None if al is None else f(al),
                                              hi=None if au is None else f(au))
    else:
        acc = interval_text(al, au, f)
    pfa, pfr = g("false_accept_probability"), g("false_reject_probability")
    model = g("probability_model") or ""
    return {"limits": interval_text(g("lower"), g("upper"), given_text),
            "acceptance": acc, "outcome": L[g("outcome")] if g("outcome") else "—",
            "pfa": (display("sig2", 100.0 * pfa) + " %" if pfa is not None
                    else "≤ " + bound_up_text(100.0 * g("false_accept_bound")) + " %"
                    if g("false_accept_bound") is not None else "—"),
            # the probability of conformance's own digits (the column beside it, summary.txt):
            # one number, never 99 % beside 98.5 %
            "pfr": L["c_pfr"].format(v=display("sig3", 100.0 * pfr)) if pfr is not None else "",
            "no_p": model if g("outcome") and g("conformance_probability") is None
            and model.startswith("not given") else "",
            "measured": measured_clause(c)}


#: the kinds of interval an item can be stated by, in the legend's order
INTERVAL_KINDS = ("chi2", "range", "belt", "max_abs", "max_abs_bound", "sel_max", "bound",
                  "bound_chi2", "own", "upper")

#: The interval kinds of a bound condition (their clauses named with their bounded lines).
BOUND_KINDS = ("bound", "bound_chi2", "max_abs_bound")


def interval_kind(item: dict) -> str | None:
    """Which kind of 95 % interval states a results.json item (:data:`INTERVAL_KINDS`), from
    its own ``uncertainty.k_source`` (decided once, in the result): "chi2" (a standard
    deviation's χ²), "range" (a half range's normal range), "belt" (a bias-corrected range's
    confidence belt), "max_abs" (the extreme of magnitudes max_i |x_i|), "sel_max" (the
    largest σ_i less its selection bias), "bound" (value ± (a + k·u): the equipment's errors
    at their bounds plus k·u of the rest), "max_abs_bound" (the extreme of magnitudes with
    each point's bounded errors at their bounds, ``details.bound_condition``), "bound_chi2"
    (a dispersion's one-sided limit
    [0, s + a + R]: its bounded lines at their bounds, a, plus the χ² reach R of the rest),
    "own" (its own distribution: Monte Carlo, folded normal, pivot, outcome distribution),
    "upper" (a non-negative item's upper bound), or None (value ± U, or not measured).

    >>> interval_kind({"measured": True, "value": 1.0, "uncertainty": {"k": None,
    ...     "interval": [0, 2], "k_source": "max-abs-interval"}})
    'max_abs'
    >>> interval_kind({"measured": True, "value": 1.0, "upper_bound": 3.0,
    ...     "uncertainty": {"k": 2.0, "k_source": "welch-satterthwaite"}})
    'upper'
    """
    from gonio.result.gum import K_SOURCE_MAX_MAGNITUDE

    unc = item.get("uncertainty") or {}
    if not item.get("measured", True) or item.get("value") is None:
        return None
    if unc.get("k") is None and unc.get("interval") is not None:
        ks = unc.get("k_source") or ""
        if ks == K_SOURCE_BOUND_CHI2:
            return "bound_chi2"
        if ks in (K_SOURCE_MAX_ABS, K_SOURCE_MAX_MAGNITUDE) and \
                (item.get("details") or {}).get("bound_condition"):
            return "max_abs_bound"
        if ks.startswith(K_SOURCE_BOUND_PREFIX):
            return "bound"
        return {"chi-square": "chi2", "normal range": "range", "neyman-belt": "belt",
                K_SOURCE_MAX_ABS: "max_abs", K_SOURCE_MAX_MAGNITUDE: "max_abs",
                K_SOURCE_SELECTED_MAX: "sel_max",
                K_SOURCE_SELECTED_MAX_BEFORE: "sel_max"}.get(ks, "own")
    return "upper" if item.get("upper_bound") is not None else None


def bounded_lines_text(it: dict, L: dict) -> str:
    """The bounded lines of a bound-condition item (results.json
    ``details.bound_condition.a_lines``, its budget symbols) in L's words, as the legend
    names them beside the item's clause; "" where the item names none (its clause alone).
    A symbol with no words stays as written.

    >>> from gonio.report.i18n import labels
    >>> bounded_lines_text({"details": {"bound_condition": {"a_lines": {"e_table": 1e-3,
    ...     "e_TU": 5e-4}}}}, labels("en"))
    "the rate table's error and the gyro's temperature error at the set point"
    >>> bounded_lines_text({"details": {"bound_condition": {"a_lines": {"e_table": 1e-3}}}},
    ...                    labels("zh")), bounded_lines_text({}, labels("en"))
    ('转台误差', '')
    """
    bc = (it.get("details") or {}).get("bound_condition") or {}
    words = [L.get(f"bound_line_{s}", s)
             for s in (bc.get("a_lines") if isinstance(bc, dict) else None) or ()]
    if L["k_iv_head"].startswith("以"):
        return "、".join(words)
    return " and ".join([", ".join(words[:-1]), words[-1]] if len(words) > 2 else words)


def interval_legend(items: dict, L: dict) -> str:
    """The legend under a results table saying how each item stated by an interval is stated:
    one part per kind present (:func:`interval_kind`), each with the clauses of its items
    (a bound-condition item's with its bounded lines, :func:`bounded_lines_text`); "" where
    no item is stated by an interval. A pure function of the stored items."""
    zh = L["k_iv_head"].startswith("以")

    def conv(c: str) -> str:  # "7.3 (3.3)" in Chinese text: full-width brackets
        return c.replace(" (", "（").replace("(", "（").replace(")", "）") if zh else c

    kinds: dict[str, list[str]] = {}
    lines_of: dict[str, str] = {}
    p_of: dict[str, set] = {}             # each kind's stated probabilities
    for it in items.values():
        kind = interval_kind(it) if isinstance(it, dict) else None
        clause = conv(str(it.get("clause") or ""))
        if kind:
            p_of.setdefault(kind, set()).add((it.get("uncertainty") or {})
                                             .get("coverage_probability"))
        if kind in BOUND_KINDS and clause:
            lines_of.setdefault(clause, bounded_lines_text(it, L))
        if kind and clause not in kinds.setdefault(kind, []):     # each clause once
            kinds[kind].append(clause)
    if not kinds:
        return ""

    def clauses(k: str) -> str:   # the bound's clauses grouped by their bounded lines
        cs = [c for c in kinds[k] if c]
        if k not in BOUND_KINDS or not any(lines_of.get(c) for c in cs):
            return ", ".join(cs)
        groups: dict[str, list[str]] = {}
        for c in cs:
            groups.setdefault(lines_of.get(c, ""), []).append(c)
        return ("；" if zh else "; ").join(", ".join(g) + (("：" if zh else ": ") + w if w else "")
                                          for w, g in groups.items())

    def legend(k: str) -> str:    # the kind's text at its items' probability where all
        ps = p_of.get(k, set())      # state one other than 95 % (a 95.45 % convention)
        p = next(iter(ps)) if len(ps) == 1 else None
        if isinstance(p, (int, float)) and abs(p - 0.95) > 1e-9:
            return L[f"k_iv_{k}"].replace("95 %", display("sig4", 100.0 * p) + " %")
        return L[f"k_iv_{k}"]

    parts = [legend(k) + (L["k_iv_clauses"].format(c=clauses(k)) if any(kinds[k]) else "")
             for k in INTERVAL_KINDS if k in kinds]
    return L["k_iv_head"].format(kinds=("；" if zh else "; ").join(parts))


def pc_text(c) -> str:
    """A decision's probability of conformance as the conformity table's column prints it
    (three significant digits with their trailing zeros, "95.0 %", as summary.txt's
    :func:`gonio.result.text.conformance_clause` and the DCC's), "—" where none is given.
    ``c``: a Conformity or its results.json dict.

    >>> pc_text({"conformance_probability": 0.98533}), pc_text({"conformance_probability": 0.95})
    ('98.5 %', '95.0 %')
    >>> pc_text({"conformance_probability": None}), pc_text(None)
    ('—', '—')
    """
    pc = c.get("conformance_probability") if isinstance(c, dict) else getattr(
        c, "conformance_probability", None)
    return "—" if pc is None else display("sig3", 100.0 * pc) + " %"


def declaration_parts(c, t: dict) -> tuple[str, str]:
    """The acceptance and the specific false-accept probability of a DCC declaration (and
    summary line), from :func:`conformity_texts`'s ``t``: "acceptance interval [a, b]" for an
    acceptance on the value, "acceptance: interval's upper end ≤ 0.5" for one on the stated
    interval's ends (never "acceptance interval interval's …"), and "—" with its reason where
    no probability is given ("— (not given: …)"), never a bare "—"; the bound an accepted
    interval item states instead (``false_accept_bound``) with the same reason,
    "≤ 5.0 % (not given: …)".

    >>> declaration_parts({"acceptance_of": "interval"}, {"acceptance":
    ...     "interval's upper end ≤ 0.5", "pfa": "—", "no_p": "not given: why"})
    ("acceptance: interval's upper end ≤ 0.5", '— (not given: why)')
    >>> declaration_parts({}, {"acceptance": "[-0.27, 0.27]", "pfa": "0.15 %", "no_p": ""})
    ('acceptance interval [-0.27, 0.27]', '0.15 %')
    """
    of = c.get("acceptance_of") if isinstance(c, dict) else getattr(c, "acceptance_of", None)
    acc = (f"acceptance: {t['acceptance']}" if of == "interval"
           and t["acceptance"].startswith("interval") else f"acceptance interval {t['acceptance']}")
    pfa = (f"— ({t['no_p']})" if t["pfa"] == "—" and t.get("no_p")
           else f"{t['pfa']} ({t['no_p']})" if t.get("no_p") else t["pfa"])
    return acc, pfa


def no_probability_note(decided, L: dict, name_of, with_pc: bool = True) -> str:
    """The note under a conformity table explaining its "—": it names the items for which no
    probability is given (:func:`conformity_texts`'s ``no_p``) and whose row prints a "—"
    (the probability-of-conformance column, where the table has one, ``with_pc``; the
    specific false-accept probability's, where no bound is given there either), or "" (no
    "—" printed, no note). ``decided``: (key, conformity) pairs."""
    def dash(c) -> bool:
        t = conformity_texts(c, None, L)
        if not t["no_p"]:
            return False
        pc = c.get("conformance_probability") if isinstance(c, dict) else getattr(
            c, "conformance_probability", None)
        return (with_pc and pc is None) or str(t["pfa"]).strip() == "—"

    keys = [k for k, c in decided if c and c_outcome(c) and dash(c)]
    if not keys:
        return ""
    sep = "、" if "c_no_p_note" in L and L["c_no_p_note"].startswith("“—”：") else ", "
    return L.get("c_no_p_note", "“—”: no probability is stated for {items}.").format(
        items=sep.join(name_of(k) for k in keys))


def measured_note(decided, L: dict, name_of, unit_of=None) -> str:
    """The note under a conformity table for the items whose outcome the measured value before
    rounding decided (results.json ``conformity.decided_on_measured``,
    :func:`gonio.analysis.conformity.stricter_of`): their printed numbers lie inside the
    acceptance limit, the measured value beyond the acceptance interval its value and U before
    rounding give (``decided_on_measured_acceptance``, named beside it), and the stricter
    outcome is stated. ""
    where there is none. ``decided``: (key, conformity) pairs (dicts or Conformity)."""
    def of(c, name="decided_on_measured"):
        return c.get(name) if isinstance(c, dict) else getattr(c, name, None)

    def unit(k):
        return f" {unit_of(k)}" if unit_of and unit_of(k) else ""

    parts = [f"{name_of(k)} = {of(c).replace('-', '−')}{unit(k)}"
             + (L["c_measured_against"].format(acceptance=f"{acc}{unit(k)}")
                if (acc := of(c, "decided_on_measured_acceptance")) else "")
             for k, c in decided if c and of(c)]
    if not parts:
        return ""
    return L["c_measured_note"].format(items="; ".join(parts))


def skewed_note(decided, L: dict, name_of) -> str:
    """The note under a conformity table for the items decided under a χ² model whose
    probability of conformance lies on the other side of 50 % from their outcome (a pass with
    p_c < 50 %, a fail with p_c > 50 %): σ's distribution about the estimate s is skewed (its
    median lies above s), and the outcome is decided on s as printed (simple acceptance) or on
    the interval, not on p_c. "" where there is none. ``decided``: (key, conformity) pairs
    (dicts or Conformity)."""
    def of(c, name):
        return c.get(name) if isinstance(c, dict) else getattr(c, name, None)

    names = []
    for k, c in decided:
        pc, model = (of(c, "conformance_probability"), str(of(c, "probability_model") or "")) \
            if c else (None, "")
        if pc is None or not model.startswith("chi-square") or of(c, "accepted") is None:
            continue
        if (of(c, "accepted") and pc < 0.5) or (not of(c, "accepted") and pc > 0.5):
            names.append(name_of(k))
    return L["c_skewed_note"].format(items="; ".join(names)) if names else ""


def c_outcome(c):
    """A decision's outcome (a Conformity or its results.json dict), None where none."""
    return c.get("outcome") if isinstance(c, dict) else getattr(c, "outcome", None)


def stated_p(item: dict) -> float | None:
    """The coverage probability a results.json item states, None where it states none.

    >>> stated_p({"uncertainty": {"coverage_probability": 0.9545}}), stated_p({})
    (0.9545, None)
    """
    p = (item.get("uncertainty") or {}).get("coverage_probability")
    return None if p is None else float(p)


def interval_band_note(decided, L: dict, name_of, unit_of, p_of=None) -> str:
    """The note under a decision rule with a guard band naming, for each item decided on its
    95 % interval alone (``acceptance_of`` "interval", rule guarded or non-binary), the
    quantity δ of its guard band w = r·δ that takes U's place in w = r·U: the half-width of
    the interval as stated, (upper end − lower end)/2, or for a standard deviation's χ² bound
    (``probability_model`` "chi-square…") the bound's reach above the stated estimate,
    upper end − value (:func:`gonio.analysis.conformity.interval_guard_U`, the decision's
    ``U``), printed exactly from the stated ends the Result stores (``stated_interval``).
    It is called δ, never U: the item's own expanded uncertainty, where its statement prints
    one (a bound-condition U = a + k·u, an extreme's max|E_i| ± U), is another number
    (the stated ends are rounded outward, so their half-width can exceed that U in its last
    digit), and a note printing a second "U" for the same item would contradict the results
    table. "" when there is none. ``decided``: (key, conformity dict) pairs; ``unit_of(key)``
    the unit as printed; ``p_of(key)``: the coverage probability item ``key`` states (the
    note names it, 1 − p and (1 − p)/2, where the items it lists state one p: one chosen
    95.45 %; else, or without ``p_of``, 95 %)."""
    from gonio.result.statement import p_text

    rows, ps = [], set()
    for key, c in decided:
        if not c or c.get("acceptance_of") != "interval" or c.get("rule") == "simple" \
                or not c.get("outcome") or c.get("U") is None or not c.get("stated_interval"):
            continue
        ps.add(None if p_of is None else p_of(key))
        lo, hi = c["stated_interval"]
        r = c.get("guard_factor") or 1.0
        if str(c.get("probability_model") or "").startswith("chi-square") \
                and c.get("stated_value") is not None:
            # a standard deviation's χ² bound: U its reach above the estimate (interval_guard_U)
            v = c["stated_value"]
            rows.append(L.get("c_interval_band_item_chi2", "{name}: δ = {d} {unit}").format(
                name=name_of(key), unit=unit_of(key), d=_half_text(v, hi, 1.0, 1), hi=hi,
                v=v, w=_half_text(v, hi, r, 1)).replace("  ", " "))
            continue
        rows.append(L.get("c_interval_band_item", "{name}: δ = {d} {unit}").format(
            name=name_of(key), unit=unit_of(key), d=_half_text(lo, hi), hi=hi, lo=lo,
            w=_half_text(lo, hi, r)).replace("  ", " "))
    if not rows or "c_interval_band_note" not in L:
        return ""
    sep = "；" if L["c_interval_band_note"].startswith("以") else "; "
    p = (ps.pop() if len(ps) == 1 else None) or 0.95
    return L["c_interval_band_note"].format(items=sep.join(rows), p=p_text(p),
                                            q=bound_up_text(100.0 * (1.0 - p)),
                                            hq=bound_up_text(50.0 * (1.0 - p)))


def _half_text(lo: str, hi: str, r: float = 1.0, parts: int = 2) -> str:
    """r·(hi − lo)/2 of two stated ends (texts, maybe "×10⁻⁵"), exactly, as text;
    ``parts`` 1: r·(hi − lo) (a χ² bound's reach above its stated estimate).

    >>> _half_text("0.066", "0.205"), _half_text("0", "0.000014", 2.0)
    ('0.0695', '0.000014')
    >>> _half_text("1.8081", "1.8252", 1.5, 1)
    '0.02565'
    >>> _half_text("1.555×10⁻⁴", "1.723×10⁻⁴")
    '8.4×10⁻⁶'
    """
    from decimal import Decimal
    sub = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")

    def dec(t: str) -> Decimal:
        m, _, e = t.replace("−", "-").partition("×10")
        return Decimal(m) * Decimal(1).scaleb(int(e.translate(sub)) if e else 0)
    h = (dec(hi) - dec(lo)) / parts * Decimal(repr(float(r)))
    if h and ("×10" in lo + hi or abs(h.adjusted()) > 6):     # the ends' power-of-ten form
        e = h.adjusted()
        return f"{format(h.scaleb(-e).normalize(), 'f')}×10" + str(e).translate(
            str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹"))
    return format(h.normalize(), "f")


def conformity_blocks(items: dict, L: dict, name_of, unit_of, block) -> list:
    """The statement-of-conformity section of every item the pipeline decided (results.json
    ``items.<key>.conformity``; none: no section): the decision rule, one row per item
    (limits, acceptance interval, outcome, probability of conformance, specific
    false-accept probability). ``block(kind, data, extra)`` makes a block."""
    decided = [(k, it["conformity"]) for k, it in items.items() if it.get("conformity")]
    if not decided:
        return []
    out = [block("h", L["conformity"], None)]
    for rule in dict.fromkeys((c.get("rule") or "simple") for _, c in decided):
        r = next(c for _, c in decided if (c.get("rule") or "simple") == rule)
        out.append(block("p", [L.get(f"rule_{rule}", rule).format(
            r=display("k", r.get("guard_factor") or 0.0))], None))
    band = interval_band_note(decided, L, name_of, unit_of, lambda k: stated_p(items[k]))
    if band:
        out.append(block("p", [band], None))
    rows = []
    for key, c in decided:
        if not c.get("outcome"):
            rows.append([name_of(key), NoBreakText(interval_text(c.get("lower"), c.get("upper"),
                                                                 given_text)), "—",
                         L["c_no_statement"].format(r=c.get("reason") or "—"), "—", "—"])
            continue
        t = conformity_texts(c, None, L, bool(items[key].get("nonnegative")))
        u = unit_of(key)
        mark = f" {L['c_default']}" if c.get("limits_from") == DEFAULT_LIMITS_ORIGIN else ""
        rows.append([name_of(key), NoBreakText(f"{t['limits']} {u}".strip() + mark),
                     NoBreakText(t['acceptance'] if t['acceptance'] == L['c_acc_empty']
                                 else f"{t['acceptance']} {u}".strip()),
                     t["outcome"] + (L["paren"].format(x=t["pfr"]) if t["pfr"] else ""),
                     pc_text(c), t["pfa"]])
    out.append(block("table", ([L["item"], L["c_limits"], L["c_accept"], L["c_outcome"],
                                L["c_pc"], L["c_pfa"]], rows),
                     {"widths": (0.22, 0.16, 0.16, 0.16, 0.14, 0.16), "id": "conformity"}))
    for note in (no_probability_note(decided, L, name_of),
                 measured_note(decided, L, name_of, unit_of), skewed_note(decided, L, name_of)):
        if note:
            out.append(block("p", [note], None))
    sources = list(dict.fromkeys(c.get("source") or "—" for _, c in decided
                                 if c.get("limits_from") == DEFAULT_LIMITS_ORIGIN))
    if sources:
        out.append(block("p", [L["c_default_note"].format(s="; ".join(sources))], None))
    return out


# --------------------------------------------------------------------------- method


# --------------------------------------------------------------------------- summary


# --------------------------------------------------------------------------- per-item results

def item_nums(item: dict, src: str, sig: int = 3, factor: float = 1.0) -> dict:
    """One results.json item (``src`` its path, e.g. ``items.bias``) as every output states it,
    by the one statement rule (:func:`gonio.result.statement.item_statement`): ``value``,
    ``U``, ``k``, ``nu`` as :class:`Num` (or None), ``p`` (per-cent text or None), ``upper``
    (text or None), ``statement`` (the :class:`~gonio.result.statement.Statement`). An item
    stated by its interval has ``U`` and ``k`` None and ``statement.interval`` set.
    ``stated_value``: the one number an output that must write a value (the DCC's si:value)
    writes: ``value``, or for a non-negative quantity whose estimate fell below zero
    (``statement.below_zero``, stated by its upper bound alone) that bound, as every output
    prints it — never the negative estimate the statement leaves out.
    ``chi2_nu``: for an item stated by a χ² interval (a standard deviation's, or a
    dispersion's bound-condition limit: :func:`~gonio.result.statement.chi2_stated_nu`) the
    ν that interval was computed with (``nu`` itself, rule "nuchi2"), else None: every output
    that states such an item prints it beside the interval (the certificate's ν column,
    summary.txt, the DCC, the records' pages).
    ``interval_nu``: for every item stated by its interval the ν the certificate's ν_eff
    column prints beside it (``nu``: ``chi2_nu``'s, or the ν_eff its coverage factor came
    from, of a bound-condition interval value ± (a + k·u) or a non-negative item's upper
    bound; symbol :func:`~gonio.result.statement.interval_nu_symbol`), else None: summary.txt,
    the DCC and the records' pages state it beside the interval.
    ``factor`` scales value and U first (a unit conversion of the DCC).

    >>> n = item_nums({"value": 786.485, "unit": "°/h", "measured": True, "uncertainty":
    ...     {"U": 159.4, "k": 2.38068, "nu_eff": 6.2, "p": 0.95}}, "items.bias")
    >>> str(n["value"]), n["value"].rule, str(n["U"]), str(n["k"]), str(n["nu"]), n["p"]
    ('790', 'dec-1', '160', '2.38', '6', '95')
    >>> n = item_nums({"value": 0.2288, "unit": "°/h", "measured": True, "nonnegative": True,
    ...     "uncertainty": {"k": None, "nu_eff": 94.7, "coverage_probability": 0.95,
    ...                     "k_source": "chi-square", "interval": [0.0, 0.2721]}}, "items.B_s")
    >>> str(n["chi2_nu"]), n["chi2_nu"].src, n["chi2_nu"].rule, n["U"]
    ('94', 'items.B_s.uncertainty.nu_eff', 'nuchi2', None)
    >>> n = item_nums({"value": 0.8804, "unit": "1", "measured": True, "uncertainty": {"U":
    ...     0.0067, "k": None, "nu_eff": 6.0, "coverage_probability": 0.9545, "k_source":
    ...     "U = a + k·u", "interval": [0.8737, 0.8871]}}, "items.M_xy")
    >>> str(n["interval_nu"]), n["interval_nu"].rule, n["chi2_nu"]
    ('6', 'nu', None)
    """
    from gonio.result.statement import item_statement

    it = item
    if factor != 1.0:
        unc = dict(item.get("uncertainty") or {})
        for key in ("U", "u_c"):
            if unc.get(key) is not None:
                unc[key] = float(unc[key]) * factor
        if unc.get("interval") is not None:
            unc["interval"] = [float(x) * factor for x in unc["interval"]]
        it = {**item, "value": None if item.get("value") is None
              else float(item["value"]) * factor, "uncertainty": unc}
    st = item_statement(it, sig=sig)
    u_c = (it.get("uncertainty") or {}).get("u_c")
    out = {"statement": st, "value": None, "stated_value": None, "U": None, "k": None,
           "nu": None, "chi2_nu": None, "interval_nu": None, "p": st.p, "upper": st.upper,
           "interval": None}
    if st.interval is not None:     # the DCC's coverage interval: ends and u (2 digits)
        out["interval"] = {"ends": st.interval_ends,
                           "u": None if not u_c else display_uncertainty(float(u_c))}
    if st.value == "—":
        return out
    if st.exponent:
        # without U the mantissa keeps its significant digits: its own decimal places
        md = (st.decimals + st.exponent if st.decimals is not None
              else len(st.value.partition(".")[2]))
        rule = U_rule = f"sci{st.exponent}.{md}"
    else:
        rule = f"dec{st.decimals}" if st.decimals is not None else f"sig{sig}"
        U_rule = "U"
    out["value"] = out["stated_value"] = Num(st.value_text, f"{src}.value", rule)
    if st.below_zero:
        out["stated_value"] = Num(st.upper_text, f"{src}.upper_bound", rule)
    if st.U is not None:
        out["U"] = Num(st.U_text, f"{src}.uncertainty.U", U_rule)
        if st.k is not None:
            out["k"] = Num(st.k, f"{src}.uncertainty.k", "k")
    if st.nu_eff is not None and (st.U is not None or st.interval is not None):
        # a χ² interval's ν: the one it was computed with, never ∞ (display rule "nuchi2")
        chi2 = chi2_stated_nu((it.get("uncertainty") or {}).get("k_source"))
        out["nu"] = Num(st.nu_eff, f"{src}.uncertainty.nu_eff", "nuchi2" if chi2 else "nu")
        if chi2 and st.interval is not None:
            out["chi2_nu"] = out["nu"]
        if st.interval is not None:
            out["interval_nu"] = out["nu"]
    return out
