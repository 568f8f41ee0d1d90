"""The results as every output states them: one rounding rule, one form, one place.

Contents
========
===========================  ================================================================
:class:`Num`                 a shown number: its text, its path in ``results.json``, its rule
:func:`item_names`           the items of a results dict, in its order
:func:`item_uncertainty`     U, k and coverage probability of one item (or None)
:func:`stated_item`          one item as stated: value (E as ± max|E_i|), signed extreme,
                             position, U, k, p
:func:`conformity_for`       the conformity statements the laboratory's limits call for
:func:`method_rows`          the method statement (rates, rounds, series, delays, Earth rate,
                             latitude, axes, tilt, temperature, clauses)
:func:`summary_text`         ``summary.txt`` and the CLI's table, from the same Num texts
===========================  ================================================================

The certificate (HTML, PDF), ``summary.txt``, the CLI and the DCC XML all take their
numbers from here, so they cannot disagree. The rule is JCGM 100 7.2.6: U to two
significant digits, the value to the same decimal place (:func:`gonio.report.i18n.rule_at_U`);
an item without an uncertainty keeps the significant digits of
:data:`gonio.report.i18n.ITEM_SIG_DIGITS`. E is stated in the draft's form (7.4)
E = ± max|E_i|, with the signed extreme and its position beside it.

The per-item uncertainty is read from ``results[item]["uncertainty"]`` (``U``, ``k``,
``coverage_probability``) when the calibration computed it; for E the Annex A budget's
``uncertainty.U_arcsec`` and ``k`` are used otherwise, with coverage probability
approximately 95 % (Annex A.7, k = 2). Nothing is computed here beyond rounding.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from gonio.analysis.conformity import (DEFAULT_LIMITS_ORIGIN, Conformity, DecisionRule,  # noqa: F401
                                      Limits, limits_of, rule_of)
from gonio.report.i18n import (ITEM_SIG_DIGITS, ITEMS_AT_U_PLACE, coverage_text, display,
                               display_uncertainty, labels, rule_at_U)
from gonio.result.statement import decimals_for_sig, p_text, round_half_up


class NoBreakText(str):
    """Text that is never broken across lines (identifiers, units, intervals): HTML
    ``nowrap``, one token in the PDF's wrapping (``gonio.report.certificate.NoBreak``)."""




def item_names(res: dict) -> list[str]:
    """The items of a results.json, in its own order (the specification's); the renderer
    lists what the result holds and names no specification's items itself.

    >>> item_names({"items": {"b": {"clause": "7.2"}, "a": {"clause": "7.1"}}})
    ['b', 'a']
    """
    return list(res["items"])


#: The fields a results.json item holds itself; every other field is under its ``details``.
ITEM_FIELDS = ("key", "title", "clause", "unit", "value", "measured", "reason", "uncertainty",
               "conformity", "nonnegative", "upper_bound", "details")


def item_path(name: str, field: str) -> str:
    """The path in results.json of ``field`` of item ``name`` (an item's own field, else one
    of its details).

    >>> item_path("angle_deviation", "value"), item_path("angle_deviation", "table.0.E_arcsec")
    ('items.angle_deviation.value', 'items.angle_deviation.details.table.0.E_arcsec')
    """
    head = field.partition(".")[0]
    return f"items.{name}.{field}" if head in ITEM_FIELDS else f"items.{name}.details.{field}"


def detail(res: dict, name: str, field: str, default: Any = None) -> Any:
    """Detail ``field`` of item ``name`` (``default`` when it has none)."""
    return (res["items"][name].get("details") or {}).get(field, default)


def followed(res: dict) -> str:
    """The specification the calibration followed, as its protocol names it (results.json
    ``extra.method.specification``; empty when the protocol names none)."""
    return (res["extra"].get("method") or {}).get("specification") or ""


def e_budget(res: dict) -> dict:
    """E's Annex A budget (results.json ``extra.uncertainty``; empty when there is none)."""
    return (res.get("extra") or {}).get("uncertainty") or {}

#: Coverage probability of the Annex A budget's U (k = 2, normal; Annex A.7).
ANNEX_A_COVERAGE: float = 0.95


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


def item_uncertainty(res: dict, name: str) -> dict | None:
    """U, k, coverage probability of item ``name`` and their paths, or None.

    Returns ``{"U", "k", "p", "src_U", "src_k", "src_p"}``; ``src_p`` is None when the
    probability is the Annex A convention rather than a number in results.json.
    """
    item = res["items"].get(name) or {}
    iu = item.get("uncertainty") if isinstance(item, dict) else None
    if isinstance(iu, dict) and iu.get("U") is not None and iu["U"] > 0:
        return {"U": float(iu["U"]), "k": iu.get("k"), "p": iu.get("coverage_probability"),
                "src_U": f"items.{name}.uncertainty.U", "src_k": f"items.{name}.uncertainty.k",
                "src_p": f"items.{name}.uncertainty.coverage_probability"
                if iu.get("coverage_probability") is not None else None}
    if name == "angle_deviation" and e_budget(res).get("U_arcsec"):
        u = e_budget(res)
        return {"U": float(u["U_arcsec"]), "k": u.get("k"), "p": ANNEX_A_COVERAGE,
                "src_U": "extra.uncertainty.U_arcsec", "src_k": "extra.uncertainty.k",
                "src_p": None}
    return None


def stated_item(res: dict, name: str) -> dict:
    """Item ``name`` as every output states it.

    Keys: ``measured``, ``reason``, ``clause``, ``unit``, ``value`` (Num; E as ± max|E_i|),
    ``signed`` and ``position`` (E only, Num), ``U``, ``k`` (Num or None), ``p`` (text such
    as "95", or None), ``U_raw`` (float or None), ``interval`` (the item's
    :func:`item_nums` when it is stated by its coverage interval alone — a dispersion such
    as B_s and R, or a non-negative item whose U exceeds its value —, then ``U`` and ``k``
    are None: one statement), ``upper`` (its upper bound's text when that interval starts
    at 0, else None).
    """
    item = res["items"][name]
    out = {"measured": bool(item["measured"]), "reason": item.get("reason", ""),
           "clause": item["clause"], "unit": item["unit"], "value": "—", "signed": None,
           "position": None, "U": None, "k": None, "p": None, "U_raw": None, "upper": None,
           "interval": None}
    if not item["measured"]:
        return out
    unc = item_uncertainty(res, name)
    U = unc["U"] if unc else None
    sig = ITEM_SIG_DIGITS.get(name, 3)
    own = None                      # the item stated by its own U (item_nums)
    max_abs = detail(res, name, "max_abs_arcsec")
    if name == "angle_deviation" and max_abs is not None:
        out["value"] = num(res, item_path(name, "max_abs_arcsec"),
                           rule_at_U(U, sig, max_abs, "pmdec"))
        out["signed"] = num(res, item_path(name, "value"),
                            rule_at_U(U, sig, item["value"], "sdec"))
        if detail(res, name, "position_deg") is not None:
            out["position"] = num(res, item_path(name, "position_deg"), "pos")
    elif U is None and name in ITEMS_AT_U_PLACE and item_uncertainty(res, "angle_deviation"):
        # R has no uncertainty of its own in the draft; it is stated to the decimal place of
        # E's U, as the per-position table beside E (JCGM 100 7.2.6 applied to the pair)
        out["value"] = num(res, item_path(name, "value"),
                           rule_at_U(item_uncertainty(res, "angle_deviation")["U"], sig))
    else:                           # the item's own U: the one statement rule, power of ten
        own = (item_nums(item, f"items.{name}", sig=sig)
               if unc and unc["src_U"].startswith(f"items.{name}.") else None)
        out["value"] = own["value"] if own else num(res, item_path(name, "value"),
                                                    rule_at_U(U, sig))
    if unc:
        out["U_raw"] = U
        if unc["p"] is not None:
            out["p"] = p_text(float(unc["p"]))
        if own is not None and own["statement"].interval is not None:
            out["interval"] = own         # its one statement: no U, no k beside it
            out["upper"] = own["statement"].upper_text
            return out
        out["U"] = own["U"] if own and own["U"] is not None else num(res, unc["src_U"], "U")
        out["k"] = num(res, unc["src_k"], "k") if unc["k"] is not None else None
    return out


def interval_cell(st: dict, lang: str) -> str:
    """The coverage interval of an item stated by it (:func:`stated_item` ``interval``), in
    the short form of a table cell whose unit is in another column: "≤ 0.021 (p ≈ 95 %)" or
    "[0.066, 0.204] (p ≈ 95 %)"; "" for an item stated by U."""
    if st.get("interval") is None:
        return ""
    return st["interval"]["statement"].interval_text(lang, short=True).replace("≤ ", "≤\u00a0")


def segments(template: str, **nums) -> list:
    """Split a label template "... {x} ..." into text and Num segments.

    >>> segments("U = {U}″", U=Num("0.34", "uncertainty.U_arcsec", "U"))
    ['U = ', Num(text='0.34', src='uncertainty.U_arcsec', rule='U'), '″']
    """
    out: list = []
    rest = template
    while "{" in rest:
        pre, _, tail = rest.partition("{")
        key, _, rest = tail.partition("}")
        if pre:
            out.append(pre)
        out.append(nums[key])
    if rest:
        out.append(rest)
    return out


def u_cell(st: dict, L: dict) -> list | str:
    """The "U (k = 2, p ≈ 95 %)" cell of one item, as text and Num segments."""
    if st["U"] is None:
        return "—"
    return segments(L["U_cell"], U=st["U"], k=st["k"] or "—", p=st["p"] or "—")


# --------------------------------------------------------------------------- conformity

def conformity_for(res: dict, lab: dict | None) -> list[dict]:
    """The conformity statements the pipeline decided, as the certificate, the DCC and
    summary.txt list them (none without limits); the report decides nothing.

    The decisions are those the pipeline stored in the result (results.json
    ``items.<key>.conformity``). One entry per limit of the laboratory file ``lab``, in its order, then
    any item decided against a specification's own tolerance: ``{"item", "limits", "rule",
    "conformity"}`` where ``conformity`` is the decision, or None with ``reason`` (not
    measured, or no uncertainty to decide with). A lab limit the pipeline did not decide, or
    decided under other limits, is a programming error (ValueError), never a missing or
    stale statement.
    """
    decided = {k: Conformity.from_json(it["conformity"]) for k, it in res["items"].items()
               if it.get("conformity")}
    lab_limits = list((lab or {}).get("specification_limits") or [])
    rule = rule_of((lab or {}).get("decision_rule"))
    named = [lim["item"] for lim in lab_limits]
    out = []
    for name in named + [k for k, c in decided.items()
                         if k not in named and c.limits_from != "lab file"]:
        c = decided.get(name)
        if c is None:
            raise ValueError(f"the conformity of {name!r} was not decided: the pipeline decides "
                             "it (decide_result) before the report renders it")
        if name in named:
            want = limits_of(lab_limits[named.index(name)])
            if (c.lower, c.upper) != (want.lower, want.upper):
                raise ValueError(f"the conformity of {name!r} was decided under other limits "
                                 f"({c.lower}, {c.upper}) than the laboratory file's")
        entry: dict = {"item": name, "limits": Limits(c.lower, c.upper, c.source or ""),
                       "rule": rule, "conformity": c if c.outcome else None, "reason": ""}
        if not c.outcome:
            item = res["items"][name]
            entry["reason"] = ("c_not_measured" if not item["measured"] or item["value"] is None
                               else "c_no_U")
        out.append(entry)
    return out


def given_text(v: float) -> str:
    """A specification limit as the laboratory gave it (no rounding: it is not measured).

    >>> given_text(0.3), given_text(-0.5), given_text(1e-05), given_text(-2.5e6)
    ('0.3', '-0.5', '1×10⁻⁵', '-2.5×10⁶')
    """
    text = f"{float(v):g}"
    if "e" not in text:
        return text
    mant, exp = text.split("e")           # the certificate's power-of-ten form, never "1e-05"
    return f"{mant}×10{str(int(exp)).translate(str.maketrans('-0123456789', '⁻⁰¹²³⁴⁵⁶⁷⁸⁹'))}"


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
    acceptance interval (guard bands wider than the tolerance) is said in words; so is the
    acceptance interval of a non-negative quantity (``nonnegative``, else the item's own flag
    in ``res``) whose upper end lies below zero: [0, -40] is empty, never "≤ -40 s".

    >>> L = {"c_acc_empty": "none", "accept": "conforms"}
    >>> c = {"U": 100.0, "upper": 60.0, "acceptance_upper": -40.0, "outcome": "accept"}
    >>> conformity_texts(c, None, L)["acceptance"], conformity_texts(c, None, L, True)["acceptance"]
    ('≤ -40', 'none')
    """
    g = (lambda k: c.get(k)) if isinstance(c, dict) else (lambda k: getattr(c, k, None))  # noqa: E731
    if nonnegative is None and res is not None:
        it = res.get(g("item")) if g("item") else None
        it = it if isinstance(it, dict) else {}
        nonnegative = bool(it.get("nonnegative") or (it.get("uncertainty") or {}).get(
            "nonnegative"))
    U = g("U")
    dec = decimals_for_sig(float(U), 2) if U else None
    f = (lambda v: round_half_up(v, dec)) if dec is not None \
        else given_text  # noqa: E731
    al, au = g("acceptance_lower"), g("acceptance_upper")
    if (al is not None and au is not None and al > au) or (nonnegative and au is not None
                                                           and au < 0):
        acc = L["c_acc_empty"]
    else:
        acc = interval_text(al, au, f)
    pfa, pfr = g("false_accept_probability"), g("false_reject_probability")
    return {"limits": interval_text(g("lower"), g("upper"), given_text),
            "acceptance": acc, "outcome": L[g("outcome")] if g("outcome") else "—",
            "pfa": display("sig2", 100.0 * pfa) + " %" if pfa is not None else "—",
            "pfr": L["c_pfr"].format(v=display("sig2", 100.0 * pfr)) if pfr is not None else ""}


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
    rows = []
    for key, c in decided:
        if not c.get("outcome"):
            rows.append([name_of(key), NoBreakText(interval_text(c.get("lower"), c.get("upper"),
                                                                 given_text)), "—",
                         L["c_no_statement"].format(r=c.get("reason") or "—"), "—", "—"])
            continue
        t = conformity_texts(c, None, L, bool(items[key].get("nonnegative")))
        pc = c.get("conformance_probability")
        u = unit_of(key)
        mark = f" {L['c_default']}" if c.get("limits_from") == DEFAULT_LIMITS_ORIGIN else ""
        rows.append([name_of(key), NoBreakText(f"{t['limits']} {u}".strip() + mark),
                     NoBreakText(t['acceptance'] if t['acceptance'] == L['c_acc_empty']
                                 else f"{t['acceptance']} {u}".strip()),
                     t["outcome"] + (L["paren"].format(x=t["pfr"]) if t["pfr"] else ""),
                     display("sig3", 100.0 * pc) + " %" if pc is not None else "—", t["pfa"]])
    out.append(block("table", ([L["item"], L["c_limits"], L["c_accept"], L["c_outcome"],
                                L["c_pc"], L["c_pfa"]], rows),
                     {"widths": (0.22, 0.16, 0.16, 0.16, 0.14, 0.16), "id": "conformity"}))
    sources = list(dict.fromkeys(c.get("source") or "—" for _, c in decided
                                 if c.get("limits_from") == DEFAULT_LIMITS_ORIGIN))
    if sources:
        out.append(block("p", [L["c_default_note"].format(s="; ".join(sources))], None))
    return out


# --------------------------------------------------------------------------- method

def method_rows(res: dict, L: dict, lab: dict | None, lang: str = "en",
                cjk: bool = True) -> list[tuple[str, str]]:
    """The method statement: what was done, with which settings (JJF 1535 8 g/h).

    From the protocol's settings the calibration stored (results.json ``extra.method``:
    rates, rounds, series, read delay, time to reading, Earth-rate compensation and its
    duration, axis directions), the readings file's metadata (site latitude, tilt bound,
    temperature) and the laboratory file.
    """
    from gonio.report.i18n import specification_text

    m = res["extra"]["method"]
    md = res.get("metadata", {})
    ns = L["not_stated"]
    measured = [res["items"][n]["clause"].split(" ")[0] for n in item_names(res)
                if res["items"][n]["measured"]]
    spec = specification_text(followed(res) or ns, lang, cjk)
    rows = [(L["m_spec"], f"{spec}; " + L["m_clauses"].format(c=", ".join(measured)))]
    ad_rate = m["angle_deviation_rate_dps"]
    rows.append((L["m_rates"], ", ".join(display("pos", r) for r in m["rates_dps"]) + " °/s"
                 + f" (7.1, 7.4: {display('pos', ad_rate)} °/s)"
                 if ad_rate is not None else ""))
    zi = m["zero_stability_interval_s"]
    rows.append((L["m_rounds"], L["m_rounds_v"].format(
        sf=m["scale_factor_rounds"], ad=m["angle_deviation_rounds"], s=m["series"],
        zn=m["zero_stability_readings"], zi=display("pos", zi) if zi is not None else "—")))
    if m["read_delay_s"] is not None:
        rows.append((L["m_delay"], L["m_delay_v"].format(
            d=display("pos", m["read_delay_s"]),
            t=display("pos", m["max_time_to_reading_s"]) if m["max_time_to_reading_s"] else "—")))
    ec = m["earth_compensation"]
    rows.append((L["m_earth"], L.get(f"m_earth_{ec}", ec).format(
        s=display("pos", m["static_s"]))))
    lat = md.get("latitude_deg") or m["compensation_latitude_deg"]
    rows.append((L["m_latitude"], f"{lat}°" if lat not in (None, "") else ns))
    rows.append((L["m_axes"], ", ".join(L.get(a, a) for a in m["axes"])))
    tilt = md.get("tilt_bound_deg") or (e_budget(res).get("parameters", {}) or {}).get("tilt_deg")
    rows.append((L["m_tilt"], L["m_tilt_v"].format(t=tilt) if tilt not in (None, "") else ns))
    env = (lab or {}).get("environment") or {}
    t_meas = env.get("temperature_c")
    if t_meas is None and md.get("temperature_c"):
        t_meas = md["temperature_c"]
    rows.append((L["m_temp"], L["m_temp_v"].format(
        t=display("pos", m["temperature_c"]), tol=display("pos", m["temperature_tolerance_c"]),
        m=f"{t_meas} °C" if t_meas not in (None, "") else ns)))
    return rows


# --------------------------------------------------------------------------- summary

def summary_text(res: dict, lang: str = "en", lab: dict | None = None) -> str:
    """``summary.txt`` and what the CLI prints, from results.json: the seven items as the
    certificate states them (same rounding, E as ± max|E_i| with its signed extreme and
    position, U with k and coverage probability), then the Annex A line and the conformity
    statements the pipeline decided (:func:`conformity_for`).
    """
    L = labels(lang)
    head = ["#", "item", "clause", "result", "U (k, p)", "unit"]
    rows, notes = [], []
    for i, name in enumerate(item_names(res), 1):
        st = stated_item(res, name)
        title = res["items"][name].get("title") or name
        if not st["measured"]:
            rows.append([str(i), title, st["clause"], "not measured", "", ""])
            notes.append(f"{i}. {title}: {st['reason']}")
            continue
        val = str(st["value"])
        if st["signed"] is not None:
            val += " (" + L["E_note"].format(s=st["signed"], p=st["position"] or "—") + ")"
        if st["interval"] is not None:      # stated by its interval alone
            val += "; " + interval_cell(st, "en").replace("\u00a0", " ")
        U = "—" if st["U"] is None else f"{st['U']} (k = {st['k'] or '—'}, " \
                                         f"p ≈ {st['p'] or '—'} %)"
        rows.append([str(i), title, st["clause"], val, U, st["unit"]])
    widths = [max(len(r[j]) for r in rows + [head]) for j in range(len(head))]
    fmt = lambda r: "  ".join(s.ljust(w) for s, w in zip(r, widths)).rstrip()  # noqa: E731
    lines = [fmt(head), "  ".join("-" * w for w in widths)] + [fmt(r) for r in rows]
    if notes:
        lines += ["", "not measured:"] + ["  " + n for n in notes]
    u = e_budget(res)
    if u.get("U_arcsec") is None:
        lines += ["", L["no_E_U"]]
    else:
        kind = f"{u['budget_kind']} budget" if u.get("budget_kind") else "Annex A"
        lines += ["", f"Uncertainty of the angle-position deviation ({kind}): "
                      f"u_c = {num(res, 'extra.uncertainty.u_c_arcsec', 'U')}″, "
                      f"U = {num(res, 'extra.uncertainty.U_arcsec', 'U')}″ "
                      f"(k = {num(res, 'extra.uncertainty.k', 'k')}, coverage probability "
                      f"{coverage_text(ANNEX_A_COVERAGE, lang)})"]
    for e in conformity_for(res, lab):
        c = e["conformity"]
        if c is None:
            lines.append(f"conformity {e['item']}: {L[e['reason']]}")
            continue
        t = conformity_texts(c, res, L)
        lines.append(f"conformity {e['item']}: {t['outcome']} (limits {t['limits']}, "
                     f"rule {c.rule}, acceptance {t['acceptance']}, specific false-accept "
                     f"probability {t['pfa']})")
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- per-item results

def item_nums(item: dict, src: str, sig: int = 3, factor: float = 1.0) -> dict:
    """One results.json item (``src`` its path, e.g. ``items.bias``) as every output states it,
    by the one statement rule (:func:`gonio.result.statement.item_statement`): ``value``,
    ``U``, ``k``, ``nu`` as :class:`Num` (or None), ``p`` (per-cent text or None), ``upper``
    (text or None), ``statement`` (the :class:`~gonio.result.statement.Statement`). An item
    stated by its interval has ``U`` and ``k`` None and ``statement.interval`` set.
    ``factor`` scales value and U first (a unit conversion of the DCC).

    >>> n = item_nums({"value": 786.485, "unit": "°/h", "measured": True, "uncertainty":
    ...     {"U": 159.4, "k": 2.38068, "nu_eff": 6.2, "p": 0.95}}, "items.bias")
    >>> str(n["value"]), n["value"].rule, str(n["U"]), str(n["k"]), str(n["nu"]), n["p"]
    ('790', 'dec-1', '160', '2.38', '6', '95')
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
    out = {"statement": st, "value": None, "U": None, "k": None, "nu": None, "p": st.p,
           "upper": st.upper, "interval": None}
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
    out["value"] = Num(st.value_text, f"{src}.value", rule)
    if st.U is not None:
        out["U"] = Num(st.U_text, f"{src}.uncertainty.U", U_rule)
        if st.k is not None:
            out["k"] = Num(st.k, f"{src}.uncertainty.k", "k")
    if st.nu_eff is not None and (st.U is not None or st.interval is not None):
        out["nu"] = Num(st.nu_eff, f"{src}.uncertainty.nu_eff", "nu")
    return out
