"""The certificate of a rate-gyro calibration (JJF 1535 Annex B content; IEC 62047-20 items),
rendered by the shared machinery (:mod:`gonio.report.render`: the same
blocks, HTML and PDF renderers, lab file, identifier, virtual-bench banner, zh/en).

The specification supplies its content as data (``gonio/specs/<name>/certificate.py``:
``GROUPS``, ``TITLES_ZH``, ``HEADING``); this module turns the results into blocks:
header (clause 8 a–j), the grouped results with U (k) beside each item that has a
budget (clause 8 k), each item's budget, the readings taken, signatures and statements,
and the figures of :mod:`gonio.report.rate_figures`.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

from gonio.atomic import output_dir, write_bytes, write_text
from gonio.formats.lab import load_lab
from gonio.report.dcc import bilingual
from gonio.report.figures import figure_svg
from gonio.report.header import (certificate_id, is_draft, conformity_section, opening_blocks,
                                 signature_blocks)
from gonio.report.i18n import display, finding_text, labels, reason_text, source_text
from gonio.report.provenance import is_virtual
from gonio.report.render import Block, font_families, render_html, render_pdf_figures
from gonio.report.stated import NoBreakText, Num, interval_legend, item_nums, u_c_certified
from gonio.result.findings import stated_findings
from gonio.result.statement import p_relation, unit_text
from gonio.report.rate_content import item_conditions, rate_standards, spec_content
from gonio.report.rate_figures import figures_of
from gonio.specs import content_field, get


def _num(value, src: str, rule: str, U=None):
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "—"
    return Num(display(rule, value, U), src, rule)


def _zh(text, L: dict, translate):
    """A text the virtual bench or gonio wrote (an instrument's or a table's description, a
    standard's accuracy) in the page's language where ``translate`` (the specification's
    translator) knows it (data otherwise)."""
    if not text or L.get("_lang") != "zh":
        return text
    return translate(str(text)) or text


def spec_translator(spec):
    """``translate(text)`` of the readings' descriptions on a per-item certificate: the shared
    tables and the specification's own phrases (its certificate content's ``PHRASES_ZH``:
    the names of the virtual instruments and equipment it simulates on, among them)."""
    from gonio.report.i18n import translator

    data = spec.content() if spec.certificate_content else None
    return translator(tables=tuple(content_field(data, "PHRASES_ZH")))


def header_blocks(res: dict, spec, L: dict, lang: str, lab: dict | None,
                  standard_row: list) -> list[Block]:
    """The certificate's opening blocks (:func:`gonio.report.header.opening_blocks`) for a
    specification whose results have the per-item shape, with the chamber's temperature
    points when the items were measured in one; ``standard_row``: the readings' equipment
    (four cells, translated here) when the lab file names no standard."""
    md = res.get("metadata", {})
    more = []
    temps = chamber_points(res)
    if temps:
        bound = md.get("chamber_deviation_bound_c")
        more.append((L["chamber_profile"], ", ".join(f"{x:g}" for x in temps) + " °C"
                     + (L["chamber_bound"].format(b=bound) if bound not in (None, "") else "")))
    translate = spec_translator(spec)
    return opening_blocks(res, lab, L, specification=norm_text(spec, lang),
                          standard_row=[_zh(c, L, translate) for c in standard_row],
                          environment=more, translate=translate)


def chamber_points(res: dict) -> list[float]:
    """The chamber temperature points the items were measured at (every item's
    ``details.temperatures_c``, in order of first appearance), else the result's
    ``extra.chamber_profile_c`` (a thermal programme's set points, held by the result)."""
    seen: dict[float, None] = {}
    lists = [(it.get("details") or {}).get("temperatures_c") or []
             for it in res.get("items", {}).values()]
    if not any(lists):
        lists = [(res.get("extra") or {}).get("chamber_profile_c") or []]
    for xs in lists:
        for x in xs:
            if isinstance(x, (int, float)) and math.isfinite(x):
                seen.setdefault(float(x), None)
    return list(seen)


def norm_text(spec, lang: str) -> str:
    """The normative document followed, with its number and year: the specification's
    ``NORM`` (en, zh) from its certificate data where it has one (a procedure that is not a
    published standard names the documents it follows), else its title."""
    norm = spec.content_value("NORM")
    if norm:
        return norm[1 if lang == "zh" else 0]
    return spec.title_zh if lang == "zh" else spec.title_en


def budget_rows(res: dict, L: dict, keys=None, phrases=()) -> list[list]:
    """One row per uncertainty component of every measured item (or of ``keys``), then its
    u_c, and U with k, ν_eff and p as the results table states them (JJF 1535 clause 8 k;
    JCGM 100 8). A component whose source the analysis left blank is named by its type
    (:func:`component_source`). The u_c row of an item stated by its bound condition
    (:func:`gonio.report.stated.u_c_certified` false) is marked beside, not stated."""
    brows = []
    for key, it in res["items"].items():
        unc = it.get("uncertainty")
        if (keys is not None and key not in keys) or not it["measured"] or not unc:
            continue
        for j, c in enumerate(unc["components"]):
            if not c.get("u"):
                continue
            brows.append([it["clause"], symbol_text(c["symbol"]),
                          component_source(c, L, phrases),
                          _num(c["u"], f"items.{key}.uncertainty.components.{j}.u", "sig3"),
                          _num(c["contribution"],
                               f"items.{key}.uncertainty.components.{j}.contribution", "sig3")])
        n = item_nums(it, f"items.{key}")
        brows.append([it["clause"], "u_c",
                      L["u_c_word" if u_c_certified(it) else "u_c_beside_word"], "",
                      _num(unc["u_c"], f"items.{key}.uncertainty.u_c", "sig3")])
        if n["U"] is not None:
            brows.append([it["clause"], "U", factors_cell(n, L), "", n["U"]])
        elif isinstance((it.get("details") or {}).get("bound_condition"), dict):
            brows.append(bound_condition_row(it, f"items.{key}", n))
    return brows


def bound_condition_row(it: dict, src: str, n: dict) -> list:
    """The budget table's U row of an item stated by its bound condition (results.json
    ``details.bound_condition``, written by the specification's bound-condition statement):
    "U = a + k·u_rest: a = …, k = …, ν_eff = …, p = 95 %" and U, the k and ν those of the
    other lines (the ν the results table prints beside the interval); a dispersion's one-sided
    bound condition (``reach_rest``, :func:`gonio.result.gum.dispersion_bound_statement`):
    "U = a + R: g = …, a = …, u_rest = …, R = …, ν_eff = …, p = 95 %", g the bounded relative
    error, R the one-sided χ² reach of the other lines; the extreme of magnitudes with each
    point's bound in its reach (``b``, :func:`gonio.result.gum.max_magnitude_statement`):
    "max(|x_i| + c_H·u_i + b_i) = |x_j| + c_H·u_j + b_j: b_j = …, u_j = …", j the
    point that gives it."""
    d = f"{src}.details.bound_condition"
    bc = it["details"]["bound_condition"]
    if "b" in bc:       # the extreme of magnitudes, each point's bound in its reach
        mi = it["details"].get("max_abs_interval") or {}
        x, c = mi.get("x") or [0.0] * len(bc["b"]), float(mi.get("c_upper") or 0.0)
        j = max(range(len(bc["b"])),
                key=lambda i: abs(x[i]) + c * bc["u_rest"][i] + bc["b"][i])
        seg = ["max(|x_i| + c_H·u_i + b_i) = |x_j| + c_H·u_j + b_j: b_j = ",
               _num(bc["b"][j], f"{d}.b.{j}", "sig3"),
               ", u_j = ", _num(bc["u_rest"][j], f"{d}.u_rest.{j}", "sig3")]
        if n["p"] is not None:
            seg += [f", p {p_relation(n['p'])} {n['p']} %"]
        return [it["clause"], "U", seg, "", _num(bc["U"], f"{d}.U", "U")]
    if "reach_rest" in bc:
        seg = ["U = a + R: g = ", _num(bc["g"], f"{d}.g", "sig3"),
               ", a = ", _num(bc["a"], f"{d}.a", "sig3"),
               ", u_rest = ", _num(bc["u_rest"], f"{d}.u_rest", "sig3"),
               ", R = ", _num(bc["reach_rest"], f"{d}.reach_rest", "sig3")]
    else:
        seg = ["U = a + k·u_rest: a = ", _num(bc["a"], f"{d}.a", "sig3"),
               ", u_rest = ", _num(bc["u_rest"], f"{d}.u_rest", "sig3"),
               ", k = ", _num(bc["k_rest"], f"{d}.k_rest", "k")]
    if n["nu"] is not None:
        seg += [", ν_eff = ", n["nu"]]
    if n["p"] is not None:
        seg += [f", p {p_relation(n['p'])} {n['p']} %"]
    return [it["clause"], "U", seg, "", _num(bc["U"], f"{d}.U", "U")]


#: Budget components an analysis names by a word (its machine name in results.json), written
#: on the certificate as a symbol: δ with a short subscript, in every language.
WORD_SYMBOLS: dict[str, str] = {
    "noise": "δ_n", "noise_max": "δ_n,max", "grid": "δ_g", "drift": "δ_d", "step": "δ_s",
    "detect": "δ_det", "interp": "δ_int", "fit": "δ_fit", "floor": "δ_fl", "fluct": "δ_ϑ",
    "slope": "δ_a", "corr": "δ_c", "delta": "δ_σ", "align": "δ_al", "rms": "δ_rms",
    "res": "δ_res", "resolution": "δ_res", "threshold": "δ_thr", "rule_noise": "δ_rule",
    "rule_outcome": "δ_rule",
    "other_terms": "δ_oth"}


def symbol_text(symbol: str) -> str:
    """A budget component's symbol as the certificate writes it (:data:`WORD_SYMBOLS`).

    >>> symbol_text("noise"), symbol_text("e_table")
    ('δ_n', 'e_table')
    """
    return WORD_SYMBOLS.get(symbol, symbol)


def component_source(c: dict, L: dict, phrases=()) -> str:
    """A budget component's source as the certificate names it: the analysis's own words
    (in Chinese through :func:`gonio.report.i18n.source_text`), or, where it left them
    blank, what a component of its type is (the scatter of the item's own readings for a
    Type A one)."""
    src = (c.get("source") or "").strip()
    if src:
        return source_text(src, L, phrases)
    return L["src_own_A"] if c.get("type") == "A" else L["src_own_B"]


def factors_cell(n: dict, L: dict) -> list:
    """"k = 1.97, ν_eff = 168, p = 95 %" of one item as text and Num segments (a chosen p,
    95.45 %, with "=": :func:`gonio.result.statement.p_relation`)."""
    seg: list = []
    if n["k"] is not None:
        seg += ["k = ", n["k"]]
    if n["nu"] is not None:
        seg += [", " if seg else "", "ν_eff = ", n["nu"]]
    if n["p"] is not None:
        seg += [", " if seg else "", f"p {p_relation(n['p'])} {n['p']} %"]
    return seg or ["—"]


def readings_note(note: str, table: dict, lang: str) -> str:
    """A "reading taken" note in ``lang``: the specification's Chinese by the note's clause
    prefix (``READINGS_ZH`` of its certificate data), else the note as written."""
    if lang == "zh":
        for prefix, zh in table.items():
            if note.startswith(prefix):
                return zh
    return note


def closing_blocks(res: dict, L: dict, lab: dict | None, reading_title: str | None = None,
                   notes: list | tuple | None = None) -> list[Block]:
    """The readings taken (``notes``, default results.json's), then the signatures and the
    statements (:func:`gonio.report.header.signature_blocks`)."""
    blocks = [Block("h", reading_title or L["readings_taken_std"])]
    blocks += [Block("p", ["• " + note])
               for note in (notes if notes is not None else res.get("readings_taken", []))]
    return blocks + signature_blocks(lab, L)


def figure_blocks(figures, L: dict, lang: str) -> list[Block]:
    """The figures heading and one block per (key, caption en, caption zh, draw)."""
    return [Block("h", L["figures"])] + [
        Block("fig", (key, cap_zh if lang == "zh" else cap_en, draw))
        for key, cap_en, cap_zh, draw in figures]


def results_table(res: dict, data, L: dict, lang: str) -> tuple[list, list]:
    """The grouped results (JJF 1535 Annex B; IEC 62047-20 clause 5): value and U stated by
    the one rule (:func:`gonio.report.stated.item_nums`), k and ν_eff beside U."""
    rows = []
    phrases = content_field(data, "PHRASES_ZH")
    for num, en, zh, keys in data.GROUPS:
        rows.append([str(num), zh if lang == "zh" else en, "", "", "", "", "", ""])
        for key in keys:
            it = res["items"].get(key)
            if it is None:
                continue
            name = data.TITLES_ZH.get(key, it["title"]) if lang == "zh" else it["title"]
            if not it["measured"]:
                rows.append(["", name, it["clause"], L["not_measured"], "", "", "",
                             reason_text(it["reason"], L, phrases)])
                continue
            n = item_nums(it, f"items.{key}")
            val = n["value"] or "—"
            if n["statement"].interval is not None:     # stated by its interval, with p
                # (also a non-negative item whose U exceeds its value: its upper bound;
                # one whose estimate fell below zero: that bound alone, and why)
                sep = "；" if lang == "zh" else "; "
                cell = n["statement"].interval_text(lang, short=True).replace("≤ ", "≤\u00a0")
                val = ([cell + sep + n["statement"].below_zero_note(lang)]
                       if n["statement"].below_zero else [val, sep + cell])
                if n["statement"].widened is not None:    # the draws left no digit settled
                    val[-1] += sep + n["statement"].widened_note(lang)
            rows.append(["", name, NoBreakText(it["clause"]), val, n["U"] or "—",
                         n["k"] or "—", n["nu"] or "—", unit_text(it["unit"])])
    head = [L["no"], L["item"], L["clause"], L["result"], "U", "k", "ν_eff", L["unit"]]
    return head, rows


def screening_blocks(res: dict, L: dict, phrases=(), extra: dict | None = None,
                     limit: int = 20) -> list[Block]:
    """The screening's findings (readings set aside, planned points missing): the
    count, then one line each with its place in the file, in the certificate's language
    (:func:`gonio.report.i18n.finding_text`; ``phrases`` the specification's table), those
    about the whole file (the identity, unread columns) first;
    nothing when the screening found nothing. The count of readings set aside is the rows
    results.json's ``unused_readings`` lists (a finding may set a whole step aside), else
    one per ``set_aside`` finding."""
    found = stated_findings(res.get("findings"))            # whole-file first
    if not found:
        return []
    n_aside = sum(f["action"] == "set_aside" for f in found)
    rows = len(res.get("unused_readings") or []) or n_aside
    blocks = [Block("h", L["screening_h"]),
              Block("p", [L["screening_note"].format(n=rows, m=len(found) - n_aside)])]
    blocks += [Block("p", ["• " + finding_text(f, L, phrases, extra)]) for f in found[:limit]]
    if len(found) > limit:
        blocks.append(Block("p", [L["more_findings"].format(n=len(found) - limit)]))
    return blocks


def rate_certificate_blocks(result, L: dict, lang: str, *, lab: dict | None) -> dict:
    """The certificate's content: identifier, banner flag, lab name and blocks."""
    res = result.to_json()
    md = res.get("metadata", {})
    data = spec_content(result.spec_key)
    spec = get(result.spec_key)
    std = rate_standards(md, None, L["not_stated"])[0]        # the same row as the DCC's
    blocks = header_blocks(res, spec, L, lang, lab, [std["name"], "—", std["accuracy"], "—"])
    add = lambda kind, d, extra=None: blocks.append(Block(kind, d, extra))  # noqa: E731
    # results, grouped (Annex B)
    add("h", data.HEADING[1] if lang == "zh" else data.HEADING[0])
    add("table", results_table(res, data, L, lang), {
        "widths": (0.07, 0.26, 0.11, 0.15, 0.10, 0.07, 0.08, 0.16), "id": "results"})
    # what defines an item's measurand: stated where the item was measured and its details
    # hold every field of the sentence (a record without noise has no fit to name; a result
    # stored before a field existed is rendered without that sentence)
    for _, text in item_conditions(res, data, lang):
        add("p", [text])
    u_clause = content_field(data, "U_CLAUSE")   # the spec's own
    add("p", [L["k_each_item"].format(clause=u_clause[1 if lang == "zh" else 0])])
    legend = interval_legend(res["items"], L)    # stated by an interval: say what each is
    if legend:
        add("p", [legend])
    # the standard's own reading beside a corrected estimate, as the Result words it
    for _, _, _, keys in data.GROUPS:
        for key in keys:
            it = res["items"].get(key) or {}
            beside = (it.get("details") or {}).get("standard_reading")
            if it.get("measured") and isinstance(beside, dict):
                add("p", [beside["text_zh" if lang == "zh" else "text_en"]])
    blocks += screening_blocks(res, L, content_field(data, "PHRASES_ZH"))
    blocks += conformity_section(
        res["items"], L, lambda k: (data.TITLES_ZH.get(k, res["items"][k]["title"])
                                    if lang == "zh" else res["items"][k]["title"]),
        lambda k: unit_text(res["items"][k]["unit"]), lab)
    add("h", L["budget_items"])
    add("table", ([L["clause"], L["component"], L["source"], L["u_i_item"], "|c_i|·u_i"],
                  budget_rows(res, L, phrases=content_field(data, "PHRASES_ZH"))),
        (0.11, 0.10, 0.49, 0.15, 0.15))
    notes = [readings_note(n, content_field(data, "READINGS_ZH"), lang)
             for n in res.get("readings_taken", [])]
    blocks += closing_blocks(res, L, lab, reading_title=L["readings_taken_std"], notes=notes)
    blocks += figure_blocks(figures_of(result), L, lang)
    return {"id": certificate_id(result, lab), "virtual": is_virtual(res, lab),
            "draft": is_draft(lab),
            "lab_name": lab["laboratory"]["name"] if lab else L["virtual_lab"],
            "blocks": blocks, "results": res}


def write_spec_certificate(result, out, content_fn, figures, *, truth=None, lab=None,
                           lang: str = "en", dcc_fn=None) -> dict:
    """``certificate.html`` and ``certificate.pdf`` of a per-item specification's result,
    atomically: ``content_fn(result, L, lang, lab=…)`` gives the blocks, ``figures`` the
    (key, caption en, caption zh, draw) the blocks refer to; with ``dcc_fn(result, lab=…,
    cert_id=…) -> bytes`` also ``certificate.dcc.xml``, in the same staged set."""
    L = labels(lang)
    fonts = font_families(lang)
    font = fonts[0] if lang == "zh" else None
    lab_d = load_lab(lab) if isinstance(lab, (str, Path)) else lab
    content = content_fn(result, L, lang, lab=lab_d)
    content["_report"], content["_truth"] = result, truth
    pdf, svgs = render_pdf_figures(content, L, fonts)
    svgs = {key: svgs.get(key) or figure_svg(draw, result, L, truth, fonts)
            for key, _, _, draw in figures}
    out = Path(out)
    with output_dir(out) as stage:
        write_text(stage / "certificate.html", render_html(content, svgs, L, lang, font))
        write_bytes(stage / "certificate.pdf", pdf)
        if dcc_fn is not None:
            doc = dcc_fn(result, lab=lab_d, cert_id=content["id"])
            if lang == "zh":                   # Chinese beside English
                doc = bilingual(doc, dcc_translator(result, content_fn))
            write_bytes(stage / "certificate.dcc.xml", doc)
    names = ["certificate.html", "certificate.pdf"] + (["certificate.dcc.xml"] if dcc_fn else [])
    return {n: out / n for n in names}


def dcc_translator(result, content_fn):
    """The English → Chinese of a per-item DCC: labels, the specification's title, group and
    item names, readings taken and budget phrases from its certificate data."""
    from gonio.report.dcc import label_translator

    res = result.to_json()
    key = res.get("spec") or result.spec_key
    spec = get(key)
    data = spec.content() if spec.certificate_content else None
    extra = {spec.title_en: spec.title_zh}
    titles = content_field(data, "TITLES_ZH")
    for k, it in res.get("items", {}).items():
        if k in titles:
            extra[it["title"]] = titles[k]
            # its quantity's name (rate_dcc: "<title> (<spec key> <clause>)"), whole: a
            # clause may hold a bracket of its own ("5.4.5.1 b)")
            extra[f"{it['title']} ({key} {it['clause']})"] = f"{titles[k]}（{it['clause']}）"
    for _, en, zh, keys in content_field(data, "GROUPS"):
        extra[en] = zh
        for k in keys:              # each result's name (rate_dcc: "<group>: <title> (<clause>)")
            it = res.get("items", {}).get(k)
            if it is not None and k in titles:
                extra[f"{en}: {it['title']} ({it['clause']})"] = \
                    f"{zh}：{titles[k]}（{it['clause']}）"
    heading = content_field(data, "HEADING")
    if heading:
        extra[heading[0]] = heading[1]
    extra.update(content_field(data, "READINGS_ZH"))
    zh_conditions = dict(item_conditions(res, data, "zh"))   # the items' dcc:description
    extra.update({en: zh_conditions[k] for k, en in item_conditions(res, data, "en")
                  if k in zh_conditions})
    norm = content_field(data, "NORM")
    if norm:
        extra[norm[0]] = norm[1]
    from gonio.result.statement import item_statement
    for it in res.get("items", {}).values():    # a description that is the statement itself:
        if it.get("measured") and (it.get("uncertainty") or {}).get("interval_numerical_u"):
            st = item_statement(it)             # one whose ends were widened (rate_dcc)
            if st.widened is not None:
                extra[st.text("en")] = st.text("zh")
    # the guard-band note of the items decided on their interval (conformity_statements)
    from gonio.report.dcc import band_unit
    from gonio.report.stated import interval_band_note, stated_p

    decided = [(k, it["conformity"]) for k, it in res.get("items", {}).items()
               if it.get("conformity")]
    phrases_zh = content_field(data, "PHRASES_ZH")

    def title_zh(k: str) -> str:
        """An item's Chinese title: the specification's TITLES_ZH, else its phrases."""
        return titles.get(k) or reason_text(res["items"][k]["title"], labels("zh"), phrases_zh)
    band = {lg: interval_band_note(decided, labels(lg), lambda k: (
        title_zh(k) if lg == "zh" else res["items"][k]["title"]),
        lambda k: band_unit(res["items"][k]), lambda k: stated_p(res["items"][k]))
        for lg in ("en", "zh")}
    if band["en"]:
        extra[band["en"]] = band["zh"]
    # each screening finding the DCC states (gonio.report.dcc.finding_statements): the
    # certificate's own Chinese line (screening_blocks)
    phrases = content_field(data, "PHRASES_ZH")
    for f in res.get("findings") or ():
        if f.get("action") != "refused":
            extra[finding_text(f, labels("en"))] = finding_text(f, labels("zh"), phrases)
    # "<spec key> <clause>" (an item's quantity name): the clause alone, translated
    own = ((re.escape(spec.key) + r" (.+)", "{1}"),)
    return label_translator(extra, own + tuple(content_field(data, "PHRASES_ZH")),
                            openings=frozenset(content_field(data, "READINGS_ZH")))


def write_rate_certificate(result, out, *, truth=None, lab=None, lang: str = "en",
                           dcc: bool = False) -> dict:
    """``certificate.html`` and ``certificate.pdf`` of a rate-gyro calibration (and with
    ``dcc`` the PTB DCC 3.3.0 XML ``certificate.dcc.xml``, :mod:`gonio.report.rate_dcc`,
    always in English), written together atomically."""
    dcc_fn = None
    if dcc:
        from gonio.report.rate_dcc import rate_dcc_bytes
        dcc_fn = rate_dcc_bytes
    return write_spec_certificate(result, out, rate_certificate_blocks, figures_of(result),
                                  truth=truth, lab=lab, lang=lang, dcc_fn=dcc_fn)
