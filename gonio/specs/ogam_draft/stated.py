"""The optical draft's results as every output states them: one rounding rule, one form.

Contents
========
===========================  ================================================================
:func:`item_names`           the items of a results dict, in its order
:func:`item_uncertainty`     U, k and coverage probability of one item (or None)
:func:`stated_item`          one item as stated: value (E as ± max|E_i|), signed extreme,
                             position, U, k, p, or its one coverage interval
:func:`interval_cell`        that interval as a table cell ("≤ 0.022 (p = 95 %)")
:func:`combined_k_note`      the note naming the items whose k is their budget's combined
                             distribution's (JCGM 101), not t95(ν_eff)
:func:`conformity_for`       the conformity statements the laboratory's limits call for
:func:`method_rows`          the method statement (rates, rounds, series, delays, Earth rate,
                             latitude, axes, tilt, temperature, clauses)
:func:`summary_text`         ``summary.txt`` and the CLI's table, from the same Num texts
:func:`display_item`         how the certificate shows one of the seven items alone
:func:`reading_note`, :func:`budget_source`, :func:`specification_text`  a reading taken, a
                             budget source and the specification's name in a language
===========================  ================================================================

The optical certificate (HTML, PDF), ``summary.txt``, the CLI and the DCC XML all take their
numbers from here, so they cannot disagree. The rule is JCGM 100 7.2.6: U to two
significant digits, the value to the same decimal place (:func:`gonio.report.i18n.rule_at_U`);
an item without an uncertainty keeps the significant digits of
:data:`gonio.specs.ogam_draft.phrases.ITEM_SIG_DIGITS`; an item with its own U goes through the shared
statement rule (:func:`gonio.report.stated.item_nums`). E is stated in the draft's form (7.4)
E = ± max|E_i|, with the signed extreme and its position beside it.

The per-item uncertainty is read from ``results[item]["uncertainty"]`` (``U``, ``k``,
``coverage_probability``) when the calibration computed it; for E the Annex A budget's
``uncertainty.U_arcsec`` and ``k`` are used otherwise, with coverage probability
approximately 95 % (Annex A.7, k = 2). Nothing is computed here beyond rounding.
"""

from __future__ import annotations

from typing import Any

from gonio.analysis.conformity import Conformity, Limits, limits_of, rule_of
import math

from gonio.kit.render import (Num, condition_text, conformity_texts, coverage_text,
                              declaration_parts, display,
                              display_number, interval_band_note, item_nums, labels, num,
                              parse_display, rule_at_U, stated_p)
from gonio.result.statement import (decimals_for_sig, nu_text, p_relation, p_text,
                                    round_half_up)
from gonio.result.text import conformance_clause
from gonio.specs.ogam_draft.phrases import (BUDGET_SOURCES_PHYSICAL_ZH, BUDGET_SOURCES_ZH,
                                            ITEM_SIG_DIGITS, ITEMS_AT_U_PLACE,
                                            LABELS, READING_NOTES_ZH, TITLES_EN)


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


def e_u_c_certified(unc: dict) -> bool:
    """Whether E's budget u_c (results.json ``extra.uncertainty.u_c_arcsec``) is stated:
    not where the per-point U carries the table's bound (``u_c_certified`` False,
    :func:`gonio.specs.ogam_draft.budget.e_point_statement`), whose u_c is kept beside
    (the shared rule, :func:`gonio.report.stated.u_c_certified`)."""
    from gonio.report.stated import u_c_certified

    return u_c_certified(unc)


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


def e_by_interval(res: dict) -> bool:
    """Whether E (7.4) is stated by the 95 % interval of max|E_i| (results.json
    ``items.angle_deviation.uncertainty.interval`` with ``k_source``
    :data:`~gonio.result.statement.K_SOURCE_MAX_ABS`), the draft's max|E_i| ± U beside."""
    from gonio.result.statement import K_SOURCE_MAX_ABS

    u = (res["items"].get("angle_deviation") or {}).get("uncertainty") or {}
    return u.get("k_source") == K_SOURCE_MAX_ABS and u.get("interval") is not None


def e_signed_path(res: dict) -> str:
    """The path in results.json of E's signed extreme: ``details.signed_extreme_arcsec``
    (``value`` is max|E_i|, what is certified); a results.json written before that detail
    existed kept the signed extreme in ``value``.

    >>> e_signed_path({"items": {"angle_deviation": {"details": {"signed_extreme_arcsec": -1}}}})
    'items.angle_deviation.details.signed_extreme_arcsec'
    """
    if detail(res, "angle_deviation", "signed_extreme_arcsec") is not None:
        return item_path("angle_deviation", "signed_extreme_arcsec")
    return item_path("angle_deviation", "value")


def e_signed(res: dict) -> float:
    """E's signed extreme (:func:`e_signed_path`)."""
    d = detail(res, "angle_deviation", "signed_extreme_arcsec")
    return float(res["items"]["angle_deviation"]["value"] if d is None else d)


def stated_item(res: dict, name: str) -> dict:
    """Item ``name`` as every output states it.

    Keys: ``measured``, ``reason``, ``clause``, ``unit``, ``value`` (Num; E as ± max|E_i|),
    ``signed`` and ``position`` (E only, Num), ``U``, ``k`` (Num or None), ``nu`` (the ν_eff
    beside k where the one statement rule states it: Num or None), ``p`` (text such
    as "95", or None), ``U_raw`` (float or None), ``interval`` (the item's
    :func:`~gonio.report.stated.item_nums` when it is stated by its coverage interval alone —
    a dispersion such as B_s and R, or a non-negative item whose U exceeds its value —, then
    ``U`` and ``k`` are None: one statement), ``upper`` (its upper bound's text when that
    interval starts at 0, else None), ``below_zero`` (a non-negative item whose estimate fell
    below zero: stated by that upper bound alone, with a note,
    :func:`gonio.result.statement.below_zero_bound`; ``bound`` is then that bound as a Num of
    ``upper_bound``).
    """
    item = res["items"][name]
    out = {"measured": bool(item["measured"]), "reason": item.get("reason", ""),
           "clause": item["clause"], "unit": item["unit"], "value": "—", "signed": None,
           "position": None, "U": None, "k": None, "nu": None, "p": None, "U_raw": None,
           "upper": None, "interval": None, "below_zero": False}
    if not item["measured"]:
        return out
    unc = item_uncertainty(res, name)
    U = unc["U"] if unc else None
    sig = ITEM_SIG_DIGITS.get(name, 3)
    own = None                      # the item stated by its own U (item_nums)
    max_abs = detail(res, name, "max_abs_arcsec")
    if name == "angle_deviation" and max_abs is not None and e_by_interval(res):
        # E stated by the 95 % interval of max|E_i| (7.4 beyond the draft): max|E_i| and its
        # interval by the one statement rule, the signed extreme at the same decimal place
        own = item_nums(item, f"items.{name}", sig=sig)
        rule = own["value"].rule
        out["value"] = num(res, item_path(name, "max_abs_arcsec"), rule)
        out["signed"] = num(res, e_signed_path(res),
                            "s" + rule if rule.startswith("dec") else rule)
        if detail(res, name, "position_deg") is not None:
            out["position"] = num(res, item_path(name, "position_deg"), "pos")
    elif name == "angle_deviation" and max_abs is not None:
        out["value"] = num(res, item_path(name, "max_abs_arcsec"),
                           rule_at_U(U, sig, max_abs, "pmdec"))
        out["signed"] = num(res, e_signed_path(res),
                            rule_at_U(U, sig, e_signed(res), "sdec"))
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
            out["nu"] = own["nu"]         # a χ² interval's ν, the one it was computed with
            out["upper"] = own["statement"].upper_text
            out["below_zero"] = own["statement"].below_zero
            if out["below_zero"]:   # the bound, shown as a number of results.json
                out["bound"] = Num(out["upper"], item_path(name, "upper_bound"),
                                   own["value"].rule)
            return out
        out["U"] = own["U"] if own and own["U"] is not None else num(res, unc["src_U"], "U")
        out["k"] = num(res, unc["src_k"], "k") if unc["k"] is not None else None
        # the ν_eff k = t_p(ν_eff) was computed from, where the one statement rule states it
        out["nu"] = own["nu"] if own is not None and out["k"] is not None else None
    return out


def e_interval_segments(res: dict, L: dict, beside: bool = True) -> list:
    """The paragraph under the results saying how E is stated (:func:`e_by_interval`): the
    interval of max|E_i| as the statement gives its ends, and (``beside``) the draft's
    reading max|E_i| ± U (7.4, Annex A: ``extra.uncertainty.draft_reading``) beside, not
    certified; as :func:`segments` in ``L``'s language. [] when E is not stated by that
    interval. The certificate gives the draft's reading in its table of the readings beside
    the results (:func:`e_draft_segments`), not in this paragraph (``beside`` False)."""
    if not e_by_interval(res):
        return []
    st = stated_item(res, "angle_deviation")
    lo, hi = st["interval"]["statement"].interval_ends
    if st["interval"]["statement"].upper is not None:     # one-sided: from 0, as stated
        lo = "0"
    dr = e_budget(res).get("draft_reading") or {}
    if dr.get("U_arcsec") is None or not beside:   # the interval's sentence alone
        return [L["E_by_interval"].format(lo=lo, hi=hi, E="—", U="—", k="—")
                .partition(" The draft's")[0].partition("按规范草案")[0]]
    return segments(L["E_by_interval"].replace("{lo}", lo).replace("{hi}", hi),
                    **_e_draft_nums(res, dr))


def _e_draft_nums(res: dict, dr: dict) -> dict:
    """The draft's reading of E, max|E_i| ± U (``extra.uncertainty.draft_reading``), as the
    Nums E, U and k (max|E_i| to the decimal place of the draft's U)."""
    src = ("extra.uncertainty.draft_reading.E_arcsec" if dr.get("E_arcsec") is not None
           else item_path("angle_deviation", "max_abs_arcsec"))
    e = dr.get("E_arcsec") if dr.get("E_arcsec") is not None else detail(
        res, "angle_deviation", "max_abs_arcsec")
    return {"E": num(res, src, rule_at_U(float(dr["U_arcsec"]),
                                         ITEM_SIG_DIGITS.get("angle_deviation", 3),
                                         float(e), "pmdec")),
            "U": num(res, "extra.uncertainty.draft_reading.U_arcsec", "U"),
            "k": num(res, "extra.uncertainty.draft_reading.k", "k")}


def e_draft_segments(res: dict, L: dict) -> list:
    """The draft's reading of E as the certificate's table of the readings beside the
    results gives it, as :func:`segments`: max|E_i| ± U of the draft's Annex A budget alone
    (E stated by its interval, :func:`e_by_interval`), or that budget's U alone (E stated with
    the physical budget's U); [] without a draft reading."""
    dr = e_budget(res).get("draft_reading") or {}
    if dr.get("U_arcsec") is None:
        return []
    if e_by_interval(res):
        return segments(L["beside_E_draft"], **_e_draft_nums(res, dr))
    return segments(L["beside_U_draft"],
                    U=num(res, "extra.uncertainty.draft_reading.U_arcsec", "U"),
                    k=num(res, "extra.uncertainty.draft_reading.k", "k"))


def interval_cell(st: dict, lang: str) -> str:
    """The coverage interval of an item stated by it (:func:`stated_item` ``interval``), in
    the short form of a table cell whose unit is in another column: "≤ 0.021 (p = 95 %)" or
    "[0.066, 0.204] (p = 95 %)"; "" for an item stated by U. Where the statement rule
    widened the ends for a Monte Carlo's unsettled digit, its note follows."""
    if st.get("interval") is None:
        return ""
    stmt = st["interval"]["statement"]
    cell = stmt.interval_text(lang, short=True).replace("≤ ", "≤\u00a0")
    if stmt.widened is not None:
        cell += ("；" if lang == "zh" else "; ") + stmt.widened_note(lang)
    return cell


#: ``k_source`` of an item whose k is its budget's combined distribution's
#: (:data:`gonio.specs.ogam_draft.item_uncertainty.K_SOURCE_COMBINED`).
K_SOURCE_COMBINED = "jcgm101-convolution"


def combined_k_note(res: dict, L: dict, only: str | None = None) -> str | None:
    """The note naming the items whose k comes from their budget's combined distribution
    (``k_source`` "jcgm101-convolution",
    :func:`gonio.specs.ogam_draft.item_uncertainty.budget_k`) — stated by U or by an upper
    bound value + U — each with the largest of its lines that are not normal (its symbol
    and distribution, from results.json's components), in ``L``'s language; item ``only``
    alone when given; None when there is none.

    >>> res = {"items": {"scale_factor": {"measured": True, "clause": "7.1", "value": 3600.2,
    ...     "unit": "counts/deg", "uncertainty": {"U": 0.02, "k": 1.55, "u_c": 0.013,
    ...     "coverage_probability": 0.95, "k_source": "jcgm101-convolution", "components": [
    ...     {"symbol": "s_K", "u": 0.003, "distribution": "normal"},
    ...     {"symbol": "K_tilt", "u": 0.012, "distribution": "arcsine"},
    ...     {"symbol": "P_K", "u": 0.005, "distribution": "arcsine"}]}}}}
    >>> combined_k_note(res, {"scale_factor": "K", "k_combined": "{items}: k of JCGM 101",
    ...                       "dist_arcsine": "arcsine"})
    'K (K_tilt, arcsine): k of JCGM 101'
    """
    names = []
    for n in item_names(res):
        unc = res["items"][n].get("uncertainty") or {}
        if (only is None or n == only) and unc.get("k_source") == K_SOURCE_COMBINED:
            names.append(L[n] + _largest_non_normal(unc.get("components") or (), L))
    if not names:
        return None
    return L["k_combined"].format(items=L.get("list_sep", ", ").join(names))


def _largest_non_normal(components, L: dict) -> str:
    """" (symbol, distribution)" of the line with the largest u among those that are not
    normal (the lines that made the budget's k its combined distribution's), or ""."""
    non = [c for c in components if c.get("distribution") not in ("normal", "gaussian", "t")]
    if not non:
        return ""
    c = max(non, key=lambda c: abs(float(c.get("u") or 0.0)))
    d = c.get("distribution") or ""
    return L.get("largest_line", " ({symbol}, {dist})").format(symbol=c.get("symbol", ""),
                                                               dist=L.get("dist_" + d, d))


def k_tilt_note(res: dict, L: dict) -> list:
    """K's note when the in-situ tilt estimate corrected it, as :func:`segments`: ψ and α with
    their U95 and the 7.1 mean uncorrected (results.json ``details.tilt_correction``,
    ``details.estimates``); the certificate's K cell and the DCC's K quantity state it."""
    d = res["items"]["scale_factor"]["details"]["tilt_correction"]

    def tc(field: str, rule: str, U: float | None = None):
        return num(res, item_path("scale_factor", f"tilt_correction.{field}"), rule, U)

    # each value at its U's decimal place, U to two significant digits: the one statement
    # rule, as the K-as-mounted paragraph states ψ
    return segments(L["note_k_tilt"], p=tc("tilt_deg", "atU", d.get("U95_tilt_deg")),
                    up=tc("U95_tilt_deg", "U"),
                    a=tc("azimuth_deg", "atU", d.get("U95_azimuth_deg")),
                    ua=tc("U95_azimuth_deg", "U"),
                    v=num(res, item_path("scale_factor", "estimates.draft.value"), "atU",
                          res["items"]["scale_factor"]["uncertainty"]["U"]))


def k_table_note(res: dict, L: dict) -> list:
    """K's note when a calibrated table corrected it, as :func:`segments`: the calibration,
    u(K) of it, and (where the tilt note does not already give it) the 7.1 mean uncorrected
    (results.json ``details.table_calibration``)."""
    def tb(field: str, rule: str):
        return num(res, item_path("scale_factor", f"table_calibration.{field}"), rule, None)

    d = res["items"]["scale_factor"]["details"]["table_calibration"]
    if (res["items"]["scale_factor"].get("details") or {}).get("tilt_correction"):
        return segments(L["note_k_table"], f=str(d.get("source") or ""), u=tb("u_rel_ppm", "sig2"))
    return segments(L["note_k_table_v"], f=str(d.get("source") or ""), u=tb("u_rel_ppm", "sig2"),
                    v=num(res, item_path("scale_factor", "table_calibration.uncorrected_value"),
                          "atU", res["items"]["scale_factor"]["uncertainty"]["U"]))


def e_table_note(res: dict, L: dict) -> list:
    """E's note when a calibrated table corrected it, as :func:`segments`: the calibration
    and (where the tilt note does not already give it) the draft's E as measured
    (results.json ``angle_deviation.details.table_calibration``)."""
    item = res["items"]["angle_deviation"]
    d = (item.get("details") or {}).get("table_calibration") or {}
    k = "" if d.get("scale_factor_corrected") is True else "_nok"   # read with the corrected K
    if (item.get("details") or {}).get("tilt_correction"):
        out = segments(L["note_e_table" + k], f=str(d.get("source") or ""))
    else:
        out = segments(L["note_e_table_v" + k], f=str(d.get("source") or ""),
                       v=num(res, item_path("angle_deviation", "estimates.draft.value"), "atU",
                             item["uncertainty"]["U"]))
    if d.get("points_uncorrected_deg"):     # the points the calibration does not cover
        out.append(L["note_e_table_part"].format(
            p=", ".join(f"{x:g}" for x in d["points_uncorrected_deg"])))
    if d.get("scale_factor_corrected") is False:
        out.append(L["note_e_table_k_mpe"])
    return out


def range_table_note(res: dict, name: str, L: dict) -> list:
    """The note of K_l, C_v or C_g when a calibrated table corrected its readings, as
    :func:`segments` (results.json ``details.table_calibration``); [] otherwise."""
    d = (res["items"][name].get("details") or {}).get("table_calibration") or {}
    if not d.get("positions_used"):
        return []
    key = ("note_range_table_kl" if name == "scale_factor_nonlinearity" else
           "note_range_table_k" if d.get("read_with_table_corrected_k") else "note_range_table")
    return segments(L[key], f=str(d.get("source") or ""))


def segments(template: str, **nums) -> list:
    """Split a label template "... {x} ..." into text and Num segments.

    >>> from gonio.kit.render import Num
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
    """The "U (k = 2.02, p = 95 %)" cell of one item, as text and Num segments (p with its
    relation sign, :func:`~gonio.result.statement.p_relation`)."""
    if st["U"] is None:             # stated by its interval: the ν of a χ² interval alone
        return "—" if st.get("nu") is None else segments(L["U_cell_interval_nu"], nu=st["nu"])
    if st.get("nu") is not None:
        return segments(L["U_cell_nu"], U=st["U"], k=st["k"] or "—", nu=st["nu"],
                        p=st["p"] or "—", r=p_relation(st["p"]))
    return segments(L["U_cell"], U=st["U"], k=st["k"] or "—", p=st["p"] or "—",
                    r=p_relation(st["p"]))


def band_note(res: dict, conf: list, L: dict) -> str:
    """The certificate's guard-band note (:func:`gonio.kit.render.interval_band_note`) of the
    decisions ``conf`` (:func:`conformity_for`) in the labels ``L``' language, "" if none."""
    stored = [(e["item"], res["items"][e["item"]]["conformity"]) for e in conf]
    return interval_band_note(stored, L, lambda k: L[k], lambda k: L.get(
        "u_" + res["items"][k]["unit"], res["items"][k]["unit"]),
        lambda k: stated_p(res["items"][k]))


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


def method_rows(res: dict, L: dict, lab: dict | None, lang: str = "en",
                cjk: bool = True) -> list[tuple[str, str]]:
    """The method statement: what was done, with which settings (JJF 1535 8 g/h).

    From the protocol's settings the calibration stored (results.json ``extra.method``:
    rates, rounds, series, read delay, time to reading, Earth-rate compensation and its
    duration, axis directions), the readings file's metadata (site latitude, tilt bound,
    temperature) and the laboratory file.
    """
    m = res["extra"]["method"]
    md = res.get("metadata", {})
    ns = L["not_stated"]
    measured = [res["items"][n]["clause"].split(" ")[0] for n in item_names(res)
                if res["items"][n]["measured"]]
    spec = specification_text(followed(res) or ns, lang, cjk)
    rows = [(L["m_spec"],
             spec + L["semi"] + L["m_clauses"].format(c=L["list_sep"].join(measured)))]
    ad_rate = m["angle_deviation_rate_dps"]
    dps = L["u_deg/s"]
    rows.append((L["m_rates"], ", ".join(display("pos", r) for r in m["rates_dps"]) + f" {dps}"
                 + L["paren"].format(x="7.1" + L["list_sep"] + "7.4" + L["colon"]
                                     + f"{display('pos', ad_rate)} {dps}")
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
    tilt_v = L["m_tilt_v"].format(t=tilt) if tilt not in (None, "") else ns
    tc = ((res["items"].get("scale_factor") or {}).get("details") or {}).get("tilt_correction")
    if tc:                  # the in-situ tilt estimate measured it and K is corrected
        tilt_v += L["semi"] + L["m_tilt_measured"].format(n=tc["n_positions"])
        if ((res["items"].get("angle_deviation") or {}).get("details") or {}).get(
                "tilt_correction"):          # and every E_ij too
            tilt_v += L["m_tilt_measured_e"]
    rows.append((L["m_tilt"], tilt_v))
    env = (lab or {}).get("environment") or {}
    t_meas = env.get("temperature_c")
    if t_meas is None and md.get("temperature_c"):
        t_meas = md["temperature_c"]
    rows.append((L["m_temp"], L["m_temp_v"].format(
        t=display("pos", m["temperature_c"]), tol=display("pos", m["temperature_tolerance_c"]),
        m=f"{condition_text(t_meas)} °C" if t_meas not in (None, "") else ns)))
    return rows


def summary_text(res: dict, lang: str = "en", lab: dict | None = None) -> str:
    """``summary.txt`` and what the CLI prints, from results.json: the seven items as the
    certificate states them (same rounding, E as ± max|E_i| with its signed extreme and
    position, U with k and coverage probability), then the Annex A line and the conformity
    statements the pipeline decided (:func:`conformity_for`).
    """
    L = labels(lang, LABELS)
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
        if st["below_zero"]:                # its upper bound alone, and why
            val = interval_cell(st, "en").replace("\u00a0", " ") + "; " + L["below_zero"]
        elif st["interval"] is not None:    # stated by its interval
            val += "; " + interval_cell(st, "en").replace("\u00a0", " ")
        if st["signed"] is not None:
            val += " (" + L["E_note"].format(s=st["signed"], p=st["position"] or "—") + ")"
        nu = f"ν_eff = {st['nu']}, " if st.get("nu") is not None else ""
        U = (L["U_cell_interval_nu"].format(nu=st["nu"]) if st["U"] is None and st.get("nu")
             else "—" if st["U"] is None else f"{st['U']} (k = {st['k'] or '—'}, {nu}"
                                               f"p {p_relation(st['p'])} {st['p'] or '—'} %)")
        rows.append([str(i), title, st["clause"], val, U, st["unit"]])
    widths = [max(len(r[j]) for r in rows + [head]) for j in range(len(head))]
    fmt = lambda r: "  ".join(s.ljust(w) for s, w in zip(r, widths)).rstrip()  # noqa: E731
    lines = [fmt(head), "  ".join("-" * w for w in widths)] + [fmt(r) for r in rows]
    if notes:
        lines += ["", "not measured:"] + ["  " + n for n in notes]
    kc = combined_k_note(res, L)
    if kc:
        lines += ["", kc]
    u = e_budget(res)
    if u.get("U_arcsec") is None:
        lines += ["", L["no_E_U"]]
    else:
        kind = f"{u['budget_kind']} budget" if u.get("budget_kind") else "Annex A"
        what = ("the angle-position deviation" if not e_by_interval(res) else
                "each point's E_i (the same at every point)"
                if u.get("budget_kind") == "draft" else
                "each point's E_i (the largest of the points')")
        if u.get("table_bound_arcsec") is not None and e_by_interval(res):   # U = k·u + b
            nu = nu_text(math.inf if u.get("nu_without_table") is None
                         else u["nu_without_table"])
            lines += ["", f"Uncertainty of each point's E_i (the largest of the points', at "
                          f"{u['U_position_deg']:g}°) ({kind}): "
                          f"U = {num(res, 'extra.uncertainty.U_bound_arcsec', 'U')}″ "
                          f"(k = {num(res, 'extra.uncertainty.k_bound', 'k')}, coverage "
                          f"probability {coverage_text(ANNEX_A_COVERAGE, lang)}; "
                          f"U = k·u + b: u = "
                          f"{num(res, 'extra.uncertainty.u_without_table_arcsec', 'U')}″ "
                          f"(ν = {nu}) the combined standard uncertainty of the lines other "
                          f"than the table's, k·u = "
                          f"{num(res, 'extra.uncertainty.ku_arcsec', 'U')}″, plus the "
                          f"table's bound b = "
                          f"{num(res, 'extra.uncertainty.table_bound_arcsec', 'U')}″ at the "
                          f"point, every table within the MPE)"]
            if not e_u_c_certified(u):
                lines.append(L["u_c_not_certified"])
        else:
            lines += ["", f"Uncertainty of {what} ({kind}): "
                          f"u_c = {num(res, 'extra.uncertainty.u_c_arcsec', 'U')}″, "
                          f"U = {num(res, 'extra.uncertainty.U_arcsec', 'U')}″ "
                          f"(k = {num(res, 'extra.uncertainty.k', 'k')}, coverage probability "
                          f"{coverage_text(ANNEX_A_COVERAGE, lang)})"]
        if e_by_interval(res):
            lines.append("".join(str(x) for x in e_interval_segments(res, L)))
    for e in conformity_for(res, lab):
        c = e["conformity"]
        if c is None:
            lines.append(f"conformity {e['item']}: {L[e['reason']]}")
            continue
        t = conformity_texts(c, res, L)
        acc, pfa = declaration_parts(c, t)
        lines.append(f"conformity {e['item']}: {t['outcome']} (limits {t['limits']}, "
                     f"rule {c.rule}, {acc}{conformance_clause(c)}, specific false-accept "
                     f"probability {pfa})"
                     + (f"; {t['measured']}" if t["measured"] else ""))
    band = band_note(res, conformity_for(res, lab), L) if lab else ""
    if band:
        lines.append(band)
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- phrases

def reading_note(note: str, lang: str) -> str:
    """A "reading taken" note in ``lang`` (the English text is the one in results.json).

    >>> reading_note("7.3: x", "en"), reading_note("7.3: x", "zh")[:4]
    ('7.3: x', '7.3：')
    """
    if lang != "zh":
        return note
    for prefix, zh in READING_NOTES_ZH.items():
        if note.startswith(prefix):
            return zh
    return note


def budget_source(symbol: str, source: str, lang: str) -> str:
    """The budget's source column in ``lang`` (English from results.json when no zh form)."""
    if lang == "zh" and "[physical budget: u(r)/sqrt(n)]" in source:
        return BUDGET_SOURCES_PHYSICAL_ZH["r/sqrt(n)"]
    if lang == "zh" and "[physical budget" in source and symbol in BUDGET_SOURCES_PHYSICAL_ZH:
        return BUDGET_SOURCES_PHYSICAL_ZH[symbol]
    if lang == "zh" and symbol in BUDGET_SOURCES_ZH:
        return BUDGET_SOURCES_ZH[symbol]
    return source


def specification_text(spec: str, lang: str, cjk: bool = True) -> str:
    """The specification's name as shown: "(draft for comment)" in ``lang``; without a CJK
    font (``cjk`` False) a known Chinese title is replaced by its English form so nothing
    prints as boxes.

    >>> specification_text("JJF xxxx 光学陀螺测角仪校准规范 (draft for comment)", "zh")
    'JJF xxxx 光学陀螺测角仪校准规范（征求意见稿）'
    >>> specification_text("JJF xxxx 光学陀螺测角仪校准规范 (draft for comment)", "en", cjk=False)
    'JJF xxxx Calibration Specification for Optical Gyroscope Angle Measuring Instrument (draft for comment)'
    """
    out = spec
    if lang == "zh":
        out = out.replace(" (draft for comment)", labels("zh", LABELS)["draft_for_comment"])
    if not cjk:
        for zh, en in TITLES_EN.items():
            out = out.replace(zh, en)
    return out


def display_item(name: str, value: float | None, U: float | None = None) -> str:
    """The certificate's text for item ``name``.

    E and R are shown to the decimal place of U (JCGM 100 7.2.6) when U is given;
    every other item (and E, R without U) to :data:`ITEM_SIG_DIGITS` significant
    digits. E is shown with its sign, as "± max |E_i|" of 7.4 with the sign found.

    >>> display_item("angle_deviation", -0.11879399, U=0.35896)
    '-0.12'
    >>> display_item("repeatability", 0.13901059, U=0.35896)
    '0.14'
    >>> display_item("scale_factor", 76434.8425925926)
    '76434.843'
    >>> display_item("angle_deviation", 0.873, U=0.46)
    '+0.87'
    """
    if value is None or not math.isfinite(value):
        return "—"
    if name in ITEMS_AT_U_PLACE and U is not None and U > 0:
        s = round_half_up(value, decimals_for_sig(U, 2))
    else:
        s = display_number(value, ITEM_SIG_DIGITS.get(name, 3))
    if name == "angle_deviation" and not s.startswith("-") and parse_display(s) != 0:
        s = "+" + s            # a sign only where the rounded value has one (−0.004 → 0.00)
    return s

