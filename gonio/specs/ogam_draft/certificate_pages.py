"""The optical draft's calibration certificate: HTML (self-contained) and PDF, from a
calibration's ``results.json`` (a pure function of it, the laboratory file and the truth of a virtual run).

Contents
========
=========================  ==============================================================
:func:`write_certificate`  ``certificate.html`` and ``certificate.pdf`` into a folder, atomically
:func:`certificate_blocks` the certificate's content as plain blocks (both renderers use them)
=========================  ==============================================================

The laboratory file is read by :mod:`gonio.formats.lab`; the opening and closing content
every certificate shares is :mod:`gonio.report.header`; the HTML and PDF renderers are
:mod:`gonio.report.render`.

The content follows JJF 1535 clause 8 a–n (title; laboratory; place; identifier and
"page x of y" on every page; customer; instrument and serial; dates; the
specification; standards and traceability; environment; the results with their
units and U with k; signatures; the statements on scope and reproduction) with
the draft's Annex B inner page: the seven items in order, then "Uncertainty of
the angle-position deviation: U = …, k = 2". Items not measured are shown as
such with the reason. Without a laboratory file the certificate is an example
of the virtual bench and every page says so (banner and watermark).

Every number shown goes through :func:`gonio.report.i18n.display` (one rounding
rule, half up); in the HTML each carries ``data-src`` (its path in
``results.json``) and ``data-rule`` so it can be checked against the file.
"""

from __future__ import annotations

import math
from pathlib import Path

from gonio.atomic import output_dir, write_bytes, write_text
from gonio.formats.lab import load_lab
from gonio.kit.render import (Block, Num, certificate_id, clause_text, clean_tree,
                              interval_band_note, interval_legend, stated_p,
                              conformity_texts, coverage_text, decision_rule_blocks, display,
                              figure_svg, finding_text, font_families, is_draft, is_virtual,
                              label_translator, labels, measured_note, meta_text, no_probability_note, num,
                              pc_text,
                              skewed_note,
                              opening_blocks,
                              reason_text, render_html,
                              render_pdf_figures, rule_at_U, signature_blocks)
from gonio.kit.render import NoBreakText as NoBreak
from gonio.specs.ogam_draft.figures import FIGURES
from gonio.specs.ogam_draft.phrases import BENCH_NAMES_ZH, FINDINGS_ZH, LABELS, REASONS_ZH
from gonio.result.findings import stated_findings
from gonio.result.statement import nu_text, signed_text
from gonio.specs.ogam_draft.stated import (ANNEX_A_COVERAGE, budget_source, combined_k_note,
                                           conformity_for, detail, e_budget, e_by_interval,
                                           e_u_c_certified,
                                           e_draft_segments, e_interval_segments, followed,
                                           interval_cell, item_names, item_path, k_table_note,
                                           e_table_note, k_tilt_note,
                                           method_rows, reading_note, segments,
                                           specification_text, stated_item, u_cell,
                                           range_table_note)


# --------------------------------------------------------------------------- content blocks


def _num(results: dict, src: str, rule: str, U: float | None) -> Num | str:
    return num(results, src, rule, U)


#: Longest table printed on the certificate; the rest is in tables/*.csv and results.json.
MAX_TABLE_ROWS: int = 200
#: Findings listed one per line on the certificate (the rest in results.json).
MAX_FINDING_LINES: int = 20


def _summarised(kind: str, data):
    """A table block cut to :data:`MAX_TABLE_ROWS` rows plus a row saying how many follow."""
    if kind != "table":
        return data
    head, rows = data
    rows = list(rows)
    if len(rows) <= MAX_TABLE_ROWS:
        return data
    note = [f"… {len(rows) - MAX_TABLE_ROWS} more rows in tables/*.csv"] + [""] * (len(head) - 1)
    return head, rows[:MAX_TABLE_ROWS] + [note]


def screening_notes(res: dict, L: dict, add) -> None:
    """A notice when the screening set data aside or found the programme incomplete
    (results.json ``findings``): the count, then one line per finding."""
    found = stated_findings(res.get("findings"))     # the identity's first, as the DCC's
    if not found:
        return
    flagged = sum(f["action"] == "flagged" for f in found)
    # every reading set aside (a condition outside the programme is one finding, all its
    # readings aside): the count the calibration stored, else one per finding
    aside = ((res.get("extra") or {}).get("screening") or {}).get(
        "set_aside_readings", len(found) - flagged)
    add("notice", L["screening_note"].format(n=aside, m=flagged))
    names = {k: L[k] for k in item_names(res) if k in L}   # a test named by its item
    for f in found[:MAX_FINDING_LINES]:
        add("p", [finding_text(f, L, FINDINGS_ZH + REASONS_ZH, extra=names, own=LABELS)])
    if len(found) > MAX_FINDING_LINES:
        add("p", [L["more_findings"].format(n=len(found) - MAX_FINDING_LINES)])


def _e_u_line(res: dict, unc: dict, L: dict, U: float, lang: str, by_iv: bool, one: bool):
    """The segments of E's U line under the results: the per-point U with the table's bound
    (U = k·u + b, results.json ``extra.uncertainty.table_bound_arcsec``) where the points
    carry it, else U and k (the draft's one budget, or E stated by max|E_i| ± U)."""
    bound = by_iv and not one and unc.get("table_bound_arcsec") is not None
    key = ("U_line_one_budget" if one else "U_line_points_bound" if bound
           else "U_line_points") if by_iv else "U_line_p"
    more = dict(u=_num(res, "extra.uncertainty.u_without_table_arcsec", "U", U),
                ku=_num(res, "extra.uncertainty.ku_arcsec", "U", U),
                nu=nu_text(math.inf if unc.get("nu_without_table") is None
                           else unc["nu_without_table"]),
                b=_num(res, "extra.uncertainty.table_bound_arcsec", "U", U),
                pos=f"{unc['U_position_deg']:g}") if bound else {}
    pre = "extra.uncertainty." + ("U_bound_arcsec" if bound else "U_arcsec")
    return segments(L[key], U=_num(res, pre, "U", U),
                    k=_num(res, "extra.uncertainty." + ("k_bound" if bound else "k"), "k", U),
                    p=coverage_text(ANNEX_A_COVERAGE, lang), **more)


def certificate_blocks(results: dict, L: dict, *, lab: dict | None, truth: dict | None,
                       lang: str = "en", cjk: bool = True) -> dict:
    """The certificate's content from ``results`` (results.json): header fields and the list
    of blocks, in order.

    Returns a dict with ``id``, ``virtual`` (bool), ``lab_name``, ``blocks`` and
    ``results``. ``cjk`` False (no CJK font installed) writes the specification's
    Chinese title in English so that nothing prints as boxes.
    """
    res = clean_tree(results)                   # user text shown literally (report/text.py)
    lab = clean_tree(lab) if lab else lab
    unc = e_budget(res)
    U = float(unc["U_arcsec"]) if unc.get("U_arcsec") is not None else None
    virtual = is_virtual(res, lab)              # the readings' provenance, not the lab file
    lab_ = lab or {}
    blocks: list[Block] = []
    add = lambda kind, data, extra=None: blocks.append(  # noqa: E731
        Block(kind, _summarised(kind, data), extra))

    _admin_blocks(add, res, lab, L, lang=lang, cjk=cjk)

    # method
    add("h", L["method"])
    add("kv", method_rows(res, L, lab, lang, cjk))
    add("p", [L["m_readings"]])

    # results: Annex B, each item with its U, k and coverage probability
    add("h", L["results"])
    rrows, beside = _result_rows(res, L, U, lang)
    add("table", ([L["no"], L["item"], L["clause"], L["result"], L["U_col"], L["unit"]], rrows),
        {"widths": (0.07, 0.20, 0.075, 0.325, 0.24, 0.09), "id": "results"})
    if U is not None:
        by_iv = e_by_interval(res)
        one = unc.get("budget_kind") == "draft"      # the draft's one budget at every point
        add("p", _e_u_line(res, unc, L, U, lang, by_iv, one), "U")
        if e_u_c_certified(unc):
            add("p", segments(L["u_c_line"],
                              u=_num(res, "extra.uncertainty.u_c_arcsec", "U", U)))
        else:           # U = k·u + b: the table by its bound, no u_c of E stated
            add("p", [L["u_c_not_certified"]])
        dr = unc.get("draft_reading")
        if by_iv:        # E's one statement, its interval (the draft's reading: beside table)
            add("p", e_interval_segments(res, L, beside=False))
        if unc.get("budget_kind") == "physical" and dr:      # which budget U is of
            add("p", [L["U_certified_physical"]])
        elif unc.get("budget_kind") == "draft":
            add("p", [L["U_certified_draft_interval" if by_iv else "U_certified_draft"]])
        ks = unc.get("k_source")                 # say where k comes from
        if ks:
            add("p", [L["k_fixed"] if ks == "fixed by laboratory" else L["k_welch"]])
    else:
        add("p", [L["no_E_U"]], "U")
    if beside:                  # every reading beside the results: one table, not certified
        add("sub", L["beside_title"])
        add("table", ([L["item"], L["beside_reading"]], beside),
            {"widths": (0.26, 0.74), "id": "beside"})
    legend = interval_legend(res["items"], L)  # what each item's interval is
    if legend:
        add("p", [legend])
    kc = combined_k_note(res, L)               # K: k of its budget's combined distribution
    if kc:
        add("p", [kc])
    screening_notes(res, L, add)
    if detail(res, "scale_factor", "measurand"):
        sf = res["items"]["scale_factor"]["details"]
        ppm = (sf["instrument_own_upper_counts_per_deg"] / res["items"]["scale_factor"]["value"]
               - 1) * 1e6
        tm = sf.get("tilt_measured")
        if tm:                                  # ψ measured in situ: stated at the measured ψ
            add("p", [L["K_as_mounted_measured"].format(
                psi=display("atU", tm["tilt_deg"], U=tm["U95_tilt_deg"]),
                U=display("U", tm["U95_tilt_deg"]), k=display("k", tm["k95"]),
                ppm=display("dec2", tm["own_rel_ppm"]),
                lo=display("dec2", tm["own_rel_interval_ppm"][0]),
                hi=display("dec2", tm["own_rel_interval_ppm"][1]),
                bound=display("pos", sf["tilt_bound_deg"]), bppm=f"{ppm:.2g}")])
        else:
            add("p", [L["K_as_mounted"].format(psi=display("pos", sf["tilt_bound_deg"]),
                                               ppm=f"{ppm:.2g}")])
        tb = sf.get("temperature_coeff_bound")
        if tb and tb.get("basis") == "logged":  # K's chamber line at the logged temperature
            add("p", [L["K_temperature_logged"].format(
                t=f"{tb['logged_temperature_c']:g}", dt=signed_text(tb["deviation_c"]),
                ref=f"{tb['reference_temperature_c']:g}", b=f"{tb['bound_ppm_per_c']:g}",
                m=f"{tb.get('thermometer_mpe_c') or 0:g}",
                over=L["K_T_over_column"] if tb.get("logged_from") == "column" else "",
                src=L["K_T_source_" + tb["source"]])])
        elif tb:                                # K's chamber-temperature line: which bound
            add("p", [L["K_temperature_bound"].format(
                tol=f"{tb['temperature_tolerance_c']:g}", b=f"{tb['bound_ppm_per_c']:g}",
                src=L["K_T_source_" + tb["source"]])])

    _conformity_blocks(add, res, lab, L)

    _budget_blocks(add, res, U, L, lang)

    # readings taken
    add("h", L["readings_taken"])
    for note in res.get("readings_taken", []):
        add("p", ["• " + reading_note(note, lang)])

    for b in signature_blocks(lab, L):
        add(b.kind, b.data, b.extra)

    # details of the measurements
    add("h", L["details"])
    _detail_tables(res, L, U, add)

    # table calibration by equal-division averaging, when the readings hold it
    if res["extra"].get("equal_division"):
        _eda_section(res, L, U, add, lang)

    # figures
    add("h", L["figures"])
    for key, cap, draw in FIGURES:
        add("fig", (key, L[cap], draw))
    return {"id": certificate_id(res, lab), "virtual": virtual, "draft": is_draft(lab),
            "lab_name": (lab_["laboratory"]["name"] if lab else L["virtual_lab"]),
            "blocks": blocks, "results": res}


def _admin_blocks(add, res: dict, lab: dict | None, L: dict, *, lang: str, cjk: bool) -> None:
    """The shared opening (:func:`gonio.report.header.opening_blocks`) with the draft's own
    standard when the lab file names none: the table of the readings with its MPE."""
    md = res.get("metadata", {})
    ns = L["not_stated"]
    mpe = md.get("table_mpe_arcsec")
    translate = label_translator(BENCH_NAMES_ZH)       # its virtual instruments' names
    for b in opening_blocks(
            res, lab, L, specification=specification_text(followed(res) or ns,
                                                          lang, cjk),
            standard_row=[meta_text(md, "table", L, translate), "—",
                          L["std_mpe"].format(v=mpe) if mpe else ns, "—"],
            translate=translate):
        add(b.kind, b.data, b.extra)


def _result_rows(res: dict, L: dict, U: float | None, lang: str = "en") -> tuple[list, list]:
    """The results table's rows (Annex B): each item with its U, k and coverage
    probability (an item stated by its coverage interval: that interval beside the value and
    no U), or the reason it was not measured; and the rows of the table beside it (item, its
    readings and notes given beside and not certified: the draft's readings, the corrections
    beyond the draft, :func:`_beside_notes`). A result cell holds the item's one statement
    alone (with E's sign and point, R's point, and why a range is stated by its bound)."""
    rrows, beside = [], []
    for i, name in enumerate(item_names(res), 1):
        item = res["items"][name]
        unit = NoBreak(L.get("u_" + item["unit"], item["unit"]))
        st = stated_item(res, name)
        if not st["measured"]:
            names = {k: L[k] for k in item_names(res) if k in L}
            rrows.append([str(i), L[name], clause_text(item["clause"], L),
                          f"{L['not_measured']}: "
                          f"{reason_text(item['reason'], L, REASONS_ZH, names, LABELS)}",
                          "—", ""])
            continue
        cell: list = [st["value"]]
        if st["signed"] is not None:
            cell += [L["semi"], *segments(L["E_note"], s=st["signed"], p=st["position"] or "—")]
        elif name == "repeatability" and detail(res, name, "position_deg") is not None:
            opening, _, closing = L["paren"].partition("{x}")
            cell += [opening, *segments(L["note_at"],
                                        p=_num(res, item_path(name, "position_deg"), "pos", U)),
                     closing]
        if st["below_zero"]:    # a corrected range below zero: its upper bound alone, and why
            pre, _, post = interval_cell(st, lang).partition(st["upper"])
            cell[0:1] = [pre, st["bound"], post + L["semi"] + L["below_zero"]]
        elif st["interval"] is not None:    # B_s, R: the one statement, its χ² interval
            cell[1:1] = [L["semi"] + interval_cell(st, lang)]
        rrows.append([str(i), L[name], clause_text(item["clause"], L), cell, u_cell(st, L), unit])
        notes = _beside_notes(res, name, L, U)
        if notes:
            beside.append([L[name], notes])
    return rrows, beside


def _beside_notes(res: dict, name: str, L: dict, U: float | None) -> list:
    """Item ``name``'s readings and notes given beside its statement and not certified, as
    :func:`segments` joined by L["semi"]: angles read with the metadata's nominal K (no
    7.1 readings; its error in no budget), the draft's own reading (K_l, C_v, C_g, E, the 7.1
    mean uncorrected), B_s's range/T and noise model, C_v's and C_g's spread, and the
    corrections beyond the draft (tilt, table calibration). [] where there is none."""
    parts: list[list] = []
    if detail(res, name, "scale_factor_for_angles_source") == "metadata":
        parts.append(segments(L["note_nominal_k"]))     # first: it qualifies the value
    e_draft = (e_draft_segments(res, L)        # max|E_i| ± U of Annex A alone
               if name == "angle_deviation" and U is not None and (
                   e_by_interval(res) or e_budget(res).get("budget_kind") == "physical")
               else [])
    if name == "angle_deviation" and detail(res, name, "tilt_correction"):
        parts.append(segments(L["note_e_tilt_only"]) if e_draft else segments(
            L["note_e_tilt"], v=_num(res, item_path(name, "estimates.draft.value"), "atU", U)))
    if name == "angle_deviation" and detail(res, name, "table_calibration"):
        parts.append(e_table_note(res, L))
    parts.append(e_draft)
    if name == "zero_stability" and detail(res, name, "range_deg_per_h") is not None:
        parts.append(segments(L["note_zero_range"],
                              v=_num(res, item_path(name, "range_deg_per_h"), "sig3", U)))
        if detail(res, name, "stated") == "draft" and \
                (detail(res, name, "estimates") or {}).get("model"):
            parts.append(segments(L["note_zero_model"], v=_num(
                res, item_path(name, "estimates.model.value"), "sig3", U)))
    if name == "scale_factor" and detail(res, name, "tilt_correction"):
        parts.append(k_tilt_note(res, L))
    if name == "scale_factor" and detail(res, name, "table_calibration"):
        parts.append(k_table_note(res, L))
    if name in ("rate_consistency", "pointing_consistency"):
        parts.append(segments(L["note_spread"],
                              v=_num(res, item_path(name, "spread_arcsec"), "atU", U)))
    if name in ("scale_factor_nonlinearity", "rate_consistency", "pointing_consistency") \
            and detail(res, name, "estimates"):
        note = {"scale_factor_nonlinearity": "note_kl_draft",
                "rate_consistency": "note_cv_draft"}.get(name, "note_cg_draft")
        parts.append(segments(L[note], v=_num(
            res, item_path(name, "estimates.draft.value"), "sig3", U)))
    if name in ("scale_factor_nonlinearity", "rate_consistency", "pointing_consistency"):
        parts.append(range_table_note(res, name, L))
    out: list = []
    for p in (p for p in parts if p):
        out += ([L["semi"]] if out else []) + list(p)
    return out


def _conformity_blocks(add, res: dict, lab: dict | None, L: dict) -> None:
    """The decision rule and the conformity table: the decisions the pipeline made."""
    # decision rule and conformity: the decisions the pipeline made (results.json), rendered
    conf = conformity_for(res, lab)
    if conf:
        add("h", L["conformity"])
        rule = conf[0]["rule"]
        add("p", [L[f"rule_{rule.kind}"].format(r=display("k", rule.guard_factor))])
        stored = [(e["item"], res["items"][e["item"]]["conformity"]) for e in conf]
        band = interval_band_note(stored, L, lambda k: L[k], lambda k: L.get(
            "u_" + res["items"][k]["unit"], res["items"][k]["unit"]),
            lambda k: stated_p(res["items"][k]))
        if band:
            add("p", [band])
        for b in decision_rule_blocks(lab, stored, L, lambda k: L[k]):
            add(b.kind, b.data, b.extra)
        crow = []
        for e in conf:
            item_unit = res["items"][e["item"]]["unit"]
            unit = L.get("u_" + item_unit, item_unit)
            c = e["conformity"]
            if c is None:
                crow.append([L[e["item"]], "—", "—", L[e["reason"]], "—", "—"])
                continue
            t = conformity_texts(c, res, L)
            out_txt = t["outcome"] + (L["paren"].format(x=t["pfr"]) if t["pfr"] else "")
            crow.append([L[e["item"]], NoBreak(f"{t['limits']} {unit}"),
                         NoBreak(t['acceptance'] if t['acceptance'] == L['c_acc_empty']
                                 else f"{t['acceptance']} {unit}"), out_txt, pc_text(c),
                         t["pfa"]])
        add("table", ([L["item"], L["c_limits"], L["c_accept"], L["c_outcome"], L["c_pc"],
                       L["c_pfa"]], crow),
            {"widths": (0.22, 0.16, 0.16, 0.16, 0.14, 0.16), "id": "conformity"})
        pairs = [(e["item"], e["conformity"]) for e in conf]
        for note in (no_probability_note(pairs, L, lambda k: L[k]),
                     measured_note(pairs, L, lambda k: L[k]),
                     skewed_note(pairs, L, lambda k: L[k])):
            if note:
                add("p", [note])



def _budget_blocks(add, res: dict, U: float | None, L: dict, lang: str) -> None:
    """The uncertainty budget of E (Annex A), each component with its source."""
    unc = e_budget(res)
    # budget
    add("h", L["budget"])
    kind = unc.get("budget_kind")
    if kind in ("draft", "physical"):
        add("p", [L[f"budget_kind_{kind}"]])
    brows = []
    for j, c in enumerate(unc["components"]):
        brows.append([NoBreak(f"u({c['symbol'].replace('phi_e', 'φ_e')})"),
                      budget_source(c["symbol"], c["source"].partition(" [beyond the draft")[0],
                                    lang)
                      + ((f"（{L['beyond_draft']}）" if lang == "zh" else f" ({L['beyond_draft']})")
                         if c.get("beyond_draft") else ""), c["type"],
                      _num(res, f"extra.uncertainty.components.{j}.u_arcsec", "U", U),
                      _num(res, f"extra.uncertainty.components.{j}.contribution_arcsec", "U",
                           U)])
    add("table", ([L["component"], L["source"], L["type"], L["u_i"], L["d_contrib"]], brows),
        (0.14, 0.50, 0.08, 0.14, 0.14))



def _eda_section(res: dict, L: dict, U: float, add, lang: str = "en") -> None:
    """The table-calibration page: table and goniometer errors with their uncertainties;
    each error to the decimal place of its own u (JCGM 100 7.2.6)."""
    e = res["extra"]["equal_division"]
    add("h", L["eda"])
    add("p", [L["eda_note"].format(n=e["n_starts"], m=e["m_points"], r=e["repeats"],
                                   noise=e["noise"])])
    rows = []
    for i in range(e["m_points"]):
        ut = e["table"]["u_arcsec"][i]
        ug = e["goniometer"]["u_arcsec"][i]
        rows.append([_num(res, f"extra.equal_division.table.position_deg.{i}", "pos", U),
                     _num(res, f"extra.equal_division.table.error_arcsec.{i}", rule_at_U(ut), U),
                     _num(res, f"extra.equal_division.table.u_arcsec.{i}", "U", U),
                     _num(res, f"extra.equal_division.goniometer.angle_deg.{i}", "pos", U),
                     _num(res, f"extra.equal_division.goniometer.error_arcsec.{i}", rule_at_U(ug), U),
                     _num(res, f"extra.equal_division.goniometer.u_arcsec.{i}", "U", U)])
    add("table", ([L["eda_position"], L["eda_table"], "u (″)", L["eda_turned"], L["eda_gonio"],
                   "u (″)"], rows), (0.18, 0.17, 0.15, 0.18, 0.17, 0.15))
    cl = e["closure"]
    add("p", segments(L["eda_closure"],
                      v=_num(res, "extra.equal_division.closure.full_turn_arcsec",
                             rule_at_U(cl.get("u_full_turn_arcsec")), U),
                      u=_num(res, "extra.equal_division.closure.u_full_turn_arcsec", "U", U)))
    cp = e.get("coupling")                   # tilt × Earth-rate coupling
    if cp:
        add("p", [coupling_text(cp, lang)])


def coupling_text(cp: dict, lang: str = "en") -> str:
    """The tilt × Earth-rate coupling's sentence in the page's language, from the stored
    coupling (``extra.equal_division.coupling``: its ``reason`` and numbers; a results.json
    written before ``reason`` was stored falls back to the analysis' English ``note``).

    >>> coupling_text({"separable": False, "reason": "no_times", "max_effect_arcsec": 0.0123,
    ...                "note": ""}, "zh")
    '倾斜×地球自转耦合无法估计：等分平均法读数没有 time_s 列，未计入结果（在倾斜限值下最大约 0.0123″）'
    """
    from gonio.specs.ogam_draft.phrases import COUPLING_TEXT as T
    reason = cp.get("reason") or ("estimated" if cp.get("separable") else None)
    if reason is None:
        return cp["note"]
    if reason == "estimated":
        return T[reason][lang].format(amp=f"{cp['amplitude_arcsec_s']:.2g}",
                                      eff=f"{cp['max_effect_arcsec']:.2g}")
    size = cp.get("max_effect_arcsec")
    txt = T[reason][lang].format(cond=f"{cp.get('condition_number') or float('nan'):.2g}")
    if size is not None and size == size:
        key = "size_no_times" if reason == "no_times" else "size"
        txt += T[key][lang].format(size=f"{size:.3g}")
    return txt


def _detail_tables(res: dict, L: dict, U: float, add) -> None:
    sf = res["items"]["scale_factor"]
    if sf["measured"]:
        rows = [[_num(res, item_path("scale_factor", f"table.{i}.{col}"), rule, U)
                 for col, rule in (("round", "int"), ("table_deg", "pos"),
                                   ("gyro_counts", "int"), ("K_i_counts_per_deg", "sig8"))]
                for i in range(len(sf["details"]["table"]))]
        add("sub", L["scale_factor"] + L["paren"].format(x="7.1"))
        add("table", ([L["d_round"], L["d_theta"], L["d_counts"], L["d_K"]], rows),
            (0.15, 0.25, 0.30, 0.30))
        sm = sf["details"].get("table_summary")
        if sm:
            add("p", [L["d_listed"].format(name="scale_factor", **{
                k: (f"{sm[k]:.9g}" if isinstance(sm.get(k), float) else sm.get(k))
                for k in ("rows", "listed", "column", "min", "max")})])
    ad, rp = res["items"]["angle_deviation"], res["items"]["repeatability"]
    if ad["measured"]:
        rmap = ({r["position_deg"]: j for j, r in enumerate(rp["details"]["table"])}
                if rp["measured"] else {})
        rows = []
        for i, r in enumerate(ad["details"]["table"]):
            j = rmap.get(r["position_deg"])
            rows.append([_num(res, item_path("angle_deviation", f"table.{i}.position_deg"),
                              "pos", U),
                         _num(res, item_path("angle_deviation", f"table.{i}.E_arcsec"), "atU",
                              U),
                         _num(res, item_path("repeatability", f"table.{j}.R_arcsec"), "atU", U)
                         if j is not None else "—",
                         _num(res, item_path("angle_deviation", f"table.{i}.n_series"), "int",
                              U)])
        add("sub", L["angle_deviation"] + " / " + L["repeatability"]
            + L["paren"].format(x="7.4" + L["list_sep"] + "7.5"))
        add("table", ([L["d_position"], L["d_E"], L["d_R"], L["d_n"]], rows),
            (0.25, 0.25, 0.25, 0.25))
    for name, col, fmt in (("rate_consistency", "rate_dps", "pos"),
                           ("pointing_consistency", "orientation", None)):
        c = res["items"][name]
        if not c["measured"]:
            continue
        table = c["details"]["table"]
        order = sorted(range(len(table)), key=lambda i: (not table[i].get("reference"), i))
        rows = []
        for i in order:
            r = table[i]
            cond = (_num(res, item_path(name, f"table.{i}.{col}"), fmt, U) if fmt
                    else L.get(str(r[col]), str(r[col])))
            rows.append([cond, L["d_reference"] if r.get("reference") else L["d_compared"],
                         _num(res, item_path(name, f"table.{i}.E_arcsec"), "atU", U),
                         _num(res, item_path(name, f"table.{i}.max_abs_arcsec"), "atU", U)])
        add("sub", L[name] + L["paren"].format(x=c["clause"]))
        head = L["d_rate"] if col == "rate_dps" else L["d_axis"]
        add("table", ([head, L["d_role"], L["d_Ev"], L["d_maxabs"]], rows),
            {"widths": (0.25, 0.25, 0.25, 0.25), "id": f"table-{name}"})


# --------------------------------------------------------------------------- entry point

def write_certificate(results: dict, out: str | Path, *, truth: dict | None = None,
                      lab: str | Path | dict | None = None, lang: str = "en",
                      dcc: bool = False) -> dict[str, Path]:
    """Write ``certificate.html`` and ``certificate.pdf`` (and with ``dcc`` the PTB DCC
    3.3.0 XML ``certificate.dcc.xml``, :mod:`gonio.specs.ogam_draft.dcc`) of ``results`` into ``out``:
    a pure function of its arguments, so the stored results.json gives the same files again.

    Parameters
    ----------
    results : dict
        The calibration's ``results.json`` (``Result.to_json()``, conformity decided by the
        pipeline; written by the specification's ``outputs`` module, not here).
    out : path
        Output folder; both files appear together or not at all (staged, then renamed).
    truth : dict, optional
        The virtual bench's truth (``truth.json``); its systematic deviation is drawn
        beside the measured curves.
    lab : path or dict, optional
        Laboratory details file (:data:`LAB_SCHEMA`, example ``protocols/lab-example.toml``)
        or its :func:`load_lab` dict. Without it the certificate is a virtual-bench
        example and every page says so.
    lang : {"en", "zh"}
        Language of the labels; "zh" needs a CJK font (GonioError naming the package).

    dcc : bool
        Also write ``certificate.dcc.xml`` (always in English, the DCC's mandatory language).

    Returns
    -------
    dict of str to Path
        ``{"certificate.html": ..., "certificate.pdf": ...}`` (and ``certificate.dcc.xml``).
    """
    L = labels(lang, LABELS)
    fonts = font_families(lang)
    font = fonts[0] if lang == "zh" else None
    lab_d = load_lab(lab) if isinstance(lab, (str, Path)) else lab
    cjk = len(fonts) > 1 or lang == "zh"
    content = certificate_blocks(results, L, lab=lab_d, truth=truth, lang=lang, cjk=cjk)
    content["_report"], content["_truth"] = results, truth     # what the figures draw from
    pdf, svgs = render_pdf_figures(content, L, fonts)
    svgs = {key: svgs.get(key) or figure_svg(draw, results, L, truth, fonts)
            for key, _, draw in FIGURES}
    out = Path(out)
    with output_dir(out) as stage:
        write_text(stage / "certificate.html", render_html(content, svgs, L, lang, font))
        write_bytes(stage / "certificate.pdf", pdf)
        if dcc:
            from gonio.kit.render import bilingual
            from gonio.specs.ogam_draft.phrases import DCC_NAMES_ZH, READING_NOTES_ZH
            from gonio.specs.ogam_draft.dcc import dcc_bytes, description_zh, method_text

            doc = dcc_bytes(results, lab=lab_d, cert_id=content["id"])
            if lang == "zh":                   # Chinese beside English
                extra = {**READING_NOTES_ZH, **BENCH_NAMES_ZH, **DCC_NAMES_ZH,
                         **{k: L[k] for k in item_names(results) if k in L},
                         method_text(results, lab_d, "en"): method_text(results, lab_d, "zh"),
                         **description_zh(results, lab_d)}
                names = {k: L[k] for k in item_names(results) if k in L}
                for f in results.get("findings") or ():   # the DCC's finding statements
                    if f["action"] != "refused":
                        extra[finding_text(f, labels("en", LABELS))] = finding_text(
                            f, L, FINDINGS_ZH + REASONS_ZH, extra=names, own=LABELS)
                doc = bilingual(doc, label_translator(extra, REASONS_ZH, LABELS))
            write_bytes(stage / "certificate.dcc.xml", doc)
    names = ["certificate.html", "certificate.pdf"] + (["certificate.dcc.xml"] if dcc else [])
    return {n: out / n for n in names}
