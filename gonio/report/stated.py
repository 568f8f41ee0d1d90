"""The results as every output states them: one rounding rule, one form, one place.

Contents
========
===========================  ================================================================
:class:`Num`                 a shown number: its text, its path in ``results.json``, its rule
:data:`ITEMS`                the draft's seven items, in Annex B order
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

from gonio.analysis.conformity import Conformity, DecisionRule, Limits, decide, limits_of  # noqa: F401
from gonio.specs.ogam_draft.items import ITEM_KEYS
from gonio.report.i18n import (ITEM_SIG_DIGITS, ITEMS_AT_U_PLACE, coverage_text, display, labels, rule_at_U)

ITEMS: tuple[str, ...] = ITEM_KEYS
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
    item = res.get(name) or {}
    iu = item.get("uncertainty") if isinstance(item, dict) else None
    if isinstance(iu, dict) and iu.get("U") is not None and iu["U"] > 0:
        return {"U": float(iu["U"]), "k": iu.get("k"), "p": iu.get("coverage_probability"),
                "src_U": f"{name}.uncertainty.U", "src_k": f"{name}.uncertainty.k",
                "src_p": f"{name}.uncertainty.coverage_probability"
                if iu.get("coverage_probability") is not None else None}
    if name == "angle_deviation" and res.get("uncertainty", {}).get("U_arcsec"):
        u = res["uncertainty"]
        return {"U": float(u["U_arcsec"]), "k": u.get("k"), "p": ANNEX_A_COVERAGE,
                "src_U": "uncertainty.U_arcsec", "src_k": "uncertainty.k", "src_p": None}
    return None


def stated_item(res: dict, name: str) -> dict:
    """Item ``name`` as every output states it.

    Keys: ``measured``, ``reason``, ``clause``, ``unit``, ``value`` (Num; E as ± max|E_i|),
    ``signed`` and ``position`` (E only, Num), ``U``, ``k`` (Num or None), ``p`` (text such
    as "95", or None), ``U_raw`` (float or None).
    """
    item = res[name]
    out = {"measured": bool(item["measured"]), "reason": item.get("reason", ""),
           "clause": item["clause"], "unit": item["unit"], "value": "—", "signed": None,
           "position": None, "U": None, "k": None, "p": None, "U_raw": None}
    if not item["measured"]:
        return out
    unc = item_uncertainty(res, name)
    U = unc["U"] if unc else None
    sig = ITEM_SIG_DIGITS.get(name, 3)
    if name == "angle_deviation" and item.get("max_abs_arcsec") is not None:
        out["value"] = num(res, f"{name}.max_abs_arcsec",
                           rule_at_U(U, sig, item["max_abs_arcsec"], "pmdec"))
        out["signed"] = num(res, f"{name}.value", rule_at_U(U, sig, item["value"], "sdec"))
        if item.get("position_deg") is not None:
            out["position"] = num(res, f"{name}.position_deg", "pos")
    elif U is None and name in ITEMS_AT_U_PLACE and item_uncertainty(res, "angle_deviation"):
        # R has no uncertainty of its own in the draft; it is stated to the decimal place of
        # E's U, as the per-position table beside E (JCGM 100 7.2.6 applied to the pair)
        out["value"] = num(res, f"{name}.value",
                           rule_at_U(item_uncertainty(res, "angle_deviation")["U"], sig))
    else:
        out["value"] = num(res, f"{name}.value", rule_at_U(U, sig))
    if unc:
        out["U_raw"] = U
        out["U"] = num(res, unc["src_U"], "U")
        out["k"] = num(res, unc["src_k"], "k") if unc["k"] is not None else None
        if unc["p"] is not None:
            out["p"] = display("k", 100.0 * float(unc["p"]))
    return out


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
    """The conformity statements the laboratory file's limits ask for (none without limits).

    One entry per ``[[specification_limits]]``: ``{"item", "limits", "rule",
    "conformity"}`` where ``conformity`` is a :class:`~gonio.analysis.conformity.Conformity`
    or None with ``reason`` (not measured, or no uncertainty to decide with). E is
    compared through its signed extreme (|E_i| ≤ MPE at every position ⇔ the signed
    extreme lies in [−MPE, +MPE]).
    """
    if not lab or not lab.get("specification_limits"):
        return []
    dr = lab.get("decision_rule") or {}
    rule = DecisionRule(dr.get("rule", "simple"), float(dr.get("guard_band_factor", 1.0)))
    out = []
    for lim in lab["specification_limits"]:
        name = lim["item"]
        limits = limits_of(lim)
        entry: dict = {"item": name, "limits": limits, "rule": rule, "conformity": None,
                       "reason": ""}
        item = res[name]
        unc = item_uncertainty(res, name)
        if not item["measured"] or item["value"] is None:
            entry["reason"] = "c_not_measured"
        elif unc is None or unc["k"] is None:
            entry["reason"] = "c_no_U"
        else:
            entry["conformity"] = decide(name, float(item["value"]), unc["U"], float(unc["k"]),
                                         limits, rule)
        out.append(entry)
    return out


def conformity_texts(c: Conformity, res: dict, L: dict) -> dict:
    """Limits, acceptance interval, outcome and probability of one statement as text,
    rounded with the item's rule (the limits to the decimal place of U)."""
    rule = rule_at_U(c.U, 3)
    f = lambda v: display(rule, v)  # noqa: E731
    lo_hi = lambda lo, hi: (f"[{f(lo) if lo is not None else '−∞'}, "  # noqa: E731
                            f"{f(hi) if hi is not None else '+∞'}]")
    acc = (lo_hi(c.acceptance_lower, c.acceptance_upper)
           if c.acceptance_lower is None or c.acceptance_upper is None
           or c.acceptance_lower <= c.acceptance_upper else "∅")
    pfa = (display("sig2", 100.0 * c.false_accept_probability) + " %"
           if c.false_accept_probability is not None else "—")
    pfr = (L["c_pfr"].format(v=display("sig2", 100.0 * c.false_reject_probability))
           if c.false_reject_probability is not None else "")
    return {"limits": lo_hi(c.lower, c.upper), "acceptance": acc, "outcome": L[c.outcome],
            "pfa": pfa, "pfr": pfr}


# --------------------------------------------------------------------------- method

def method_rows(report, res: dict, L: dict, lab: dict | None, lang: str = "en",
                cjk: bool = True) -> list[tuple[str, str]]:
    """The method statement: what was done, with which settings (issue 13, JJF 1535 8 g/h).

    From the protocol used (rates, rounds, series, read delay, time to reading,
    Earth-rate compensation and its duration, axis directions), the readings file's
    metadata (site latitude, tilt bound, temperature) and the laboratory file.
    """
    from gonio.report.i18n import specification_text

    p = report.protocol
    md = res.get("metadata", {})
    ns = L["not_stated"]
    measured = [res[n]["clause"].split(" ")[0] for n in ITEMS if res[n]["measured"]]
    spec = specification_text(res.get("specification") or ns, lang, cjk)
    rows = [(L["m_spec"], f"{spec}; " + L["m_clauses"].format(c=", ".join(measured)))]
    rates = []
    for it in (p.scale_factor, p.angle_deviation, *p.rate_consistency):
        if it is not None and it.rate_dps not in rates:
            rates.append(it.rate_dps)
    rows.append((L["m_rates"], ", ".join(display("pos", r) for r in sorted(rates)) + " °/s"
                 + f" (7.1, 7.4: {display('pos', p.angle_deviation.rate_dps)} °/s)"
                 if p.angle_deviation else ""))
    zs = p.zero_stability
    rows.append((L["m_rounds"], L["m_rounds_v"].format(
        sf=len(p.scale_factor.rounds) if p.scale_factor else 0,
        ad=len(p.angle_deviation.rounds) if p.angle_deviation else 0,
        s=p.angle_deviation.series if p.angle_deviation else 0,
        zn=zs.readings if zs else 0, zi=display("pos", zs.interval_s) if zs else "—")))
    ad = p.angle_deviation or p.scale_factor
    if ad is not None:
        rows.append((L["m_delay"], L["m_delay_v"].format(
            d=display("pos", ad.read_delay_s),
            t=display("pos", ad.max_time_to_reading_s) if ad.max_time_to_reading_s else "—")))
    ec = p.session.earth_compensation
    rows.append((L["m_earth"], L.get(f"m_earth_{ec}", ec).format(
        s=display("pos", p.session.static_s))))
    lat = md.get("latitude_deg") or p.session.compensation_latitude_deg
    rows.append((L["m_latitude"], f"{lat}°" if lat not in (None, "") else ns))
    axes = [p.pointing_reference] + [it.orientation for it in p.pointing_consistency
                                     if it.orientation != p.pointing_reference]
    rows.append((L["m_axes"], ", ".join(L.get(a, a) for a in axes)))
    tilt = md.get("tilt_bound_deg") or (res.get("uncertainty", {}).get("parameters", {}) or {}
                                        ).get("tilt_deg")
    rows.append((L["m_tilt"], L["m_tilt_v"].format(t=tilt) if tilt not in (None, "") else ns))
    cond = p.conditions
    cget = (cond.get if isinstance(cond, dict)
            else lambda key, default: getattr(cond, key, default))
    env = (lab or {}).get("environment") or {}
    t_meas = env.get("temperature_c")
    if t_meas is None and md.get("temperature_c"):
        t_meas = md["temperature_c"]
    rows.append((L["m_temp"], L["m_temp_v"].format(
        t=display("pos", cget("temperature_c", 20.0)),
        tol=display("pos", cget("temperature_tolerance_c", 1.0)),
        m=f"{t_meas} °C" if t_meas not in (None, "") else ns)))
    return rows


# --------------------------------------------------------------------------- summary

def summary_text(res: dict, lang: str = "en", lab: dict | None = None) -> str:
    """``summary.txt`` and what the CLI prints: the seven items as the certificate states
    them (same rounding, E as ± max|E_i| with its signed extreme and position, U with k and
    coverage probability), then the Annex A line and any conformity statements.
    """
    L = labels(lang)
    head = ["#", "item", "clause", "result", "U (k, p)", "unit"]
    rows, notes = [], []
    for i, name in enumerate(ITEMS, 1):
        st = stated_item(res, name)
        title = res[name].get("item", name)
        if not st["measured"]:
            rows.append([str(i), title, st["clause"], "not measured", "", ""])
            notes.append(f"{i}. {title}: {st['reason']}")
            continue
        val = str(st["value"])
        if st["signed"] is not None:
            val += " (" + L["E_note"].format(s=st["signed"], p=st["position"] or "—") + ")"
        U = "—" if st["U"] is None else f"{st['U']} (k = {st['k'] or '—'}, " \
                                         f"p ≈ {st['p'] or '—'} %)"
        rows.append([str(i), title, st["clause"], val, U, st["unit"]])
    widths = [max(len(r[j]) for r in rows + [head]) for j in range(len(head))]
    fmt = lambda r: "  ".join(s.ljust(w) for s, w in zip(r, widths)).rstrip()  # noqa: E731
    lines = [fmt(head), "  ".join("-" * w for w in widths)] + [fmt(r) for r in rows]
    if notes:
        lines += ["", "not measured:"] + ["  " + n for n in notes]
    u = res["uncertainty"]
    if u.get("U_arcsec") is None:
        lines += ["", L["no_E_U"]]
    else:
        kind = f"{u['budget_kind']} budget" if u.get("budget_kind") else "Annex A"
        lines += ["", f"Uncertainty of the angle-position deviation ({kind}): "
                      f"u_c = {num(res, 'uncertainty.u_c_arcsec', 'U')}″, "
                      f"U = {num(res, 'uncertainty.U_arcsec', 'U')}″ "
                      f"(k = {num(res, 'uncertainty.k', 'k')}, coverage probability "
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
