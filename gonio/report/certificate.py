"""The calibration certificate: HTML (self-contained) and PDF, from a calibration report.

Contents
========
=========================  ==============================================================
:func:`write_certificate`  ``certificate.html`` and ``certificate.pdf`` into a folder, atomically
:func:`load_lab`           laboratory / customer / signatory details from a TOML file
:data:`LAB_SCHEMA`         what that file may hold (:mod:`gonio.formats.toml`)
:func:`certificate_blocks` the certificate's content as plain blocks (both renderers use them)
:func:`render_html`        blocks + figures → one HTML page (figures inline as SVG)
:func:`render_pdf`         blocks + figures → A4 PDF pages (matplotlib PdfPages)
:func:`certificate_id`     the identifier: the lab file's, else ``VB-`` + readings hash
=========================  ==============================================================

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

import contextlib
import datetime as _dt
import html
import io
import math
import re
import unicodedata
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from gonio.atomic import output_dir, write_bytes, write_text
from gonio.report.text import clean_tree, fit_header
from gonio.report.provenance import is_virtual, virtual_lines
from gonio.errors import GonioError
from gonio.analysis.conformity import RULES, check_one_limit_per_item
from gonio.report.figures import FIGURES, figure_svg, mpl_style, plain_log_ticks
from gonio.report.i18n import (budget_source, cjk_font, coverage_text, display, finding_text,
                               labels,
                               reading_note, reason_text, rule_at_U, specification_text)
from gonio.report.stated import NoBreakText as NoBreak  # noqa: E402  (one class)
from gonio.report.stated import (ANNEX_A_COVERAGE, Num, conformity_for,
                                 conformity_texts, limits_of, method_rows, num, segments,
                                 item_names, stated_item, u_cell)
from gonio.formats.toml import Field, check_text_fields, non_negative, read_toml, validate_table

# --------------------------------------------------------------------------- lab file


def _iso_date(x: str) -> bool:
    try:
        _dt.date.fromisoformat(x)
    except ValueError:
        return False
    return True


_S = Field("str", default="")
_DATE = Field("str", default="", check=lambda s: s == "" or _iso_date(s),
              expect="a date YYYY-MM-DD")

#: The laboratory details file (``--lab FILE``): every key, its type and default.
LAB_SCHEMA: dict[str, Field] = {
    "laboratory": Field("table", schema={
        "name": Field("str"), "address": Field("str"), "accreditation": _S, "contact": _S}),
    "certificate": Field("table", schema={
        "number": Field("str"), "date_of_issue": _DATE, "date_of_receipt": _DATE,
        "date_of_calibration": _DATE, "place": _S}),
    "customer": Field("table", schema={"name": Field("str"), "address": _S}),
    "instrument": Field("table", default=None, schema={
        "description": _S, "model": _S, "serial": _S, "manufacturer": _S}),
    "standards": Field("table_list", default=None, schema={
        "name": Field("str"), "identifier": _S, "accuracy": _S, "certificate": _S,
        "traceability": _S}),
    "environment": Field("table", default=None, schema={
        "temperature_c": Field("float", default=None),
        "humidity_pct": Field("float", default=None, check=lambda h: 0 <= h <= 100,
                              expect="0–100 %")}),
    # the readings' identity and conditions against [instrument] and [environment]
    # (gonio.pipeline.identity): a contradiction is refused unless on_mismatch = "proceed"
    "identity": Field("table", default=None, schema={
        "on_mismatch": Field("str", default="refuse", choices=("refuse", "proceed")),
        "temperature_tolerance_c": Field("float", default=None, check=non_negative,
                                         expect="≥ 0"),
        "humidity_tolerance_pct": Field("float", default=None, check=non_negative,
                                        expect="≥ 0")}),
    "signatory": Field("table", schema={
        "calibrated_by": _S, "checked_by": _S, "approved_by": Field("str"),
        "approved_title": _S}),
    # ISO/IEC 17025 7.1.3 / 7.8.6: the decision rule agreed with the customer, and the
    # specification limits of the items a statement of conformity is asked for
    "decision_rule": Field("table", default=None, schema={
        "rule": Field("str", choices=RULES),
        "guard_band_factor": Field("float", default=1.0, check=non_negative, expect="≥ 0"),
        "agreed": _S}),
    "specification_limits": Field("table_list", default=None, schema={
        "item": Field("str"),       # checked against the specification's items when decided
        "lower": Field("float", default=None), "upper": Field("float", default=None),
        "mpe": Field("float", default=None, check=lambda x: x > 0, expect="> 0"),
        "source": _S}),
}


def _dates_to_text(x):
    if isinstance(x, dict):
        return {k: _dates_to_text(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_dates_to_text(v) for v in x]
    if isinstance(x, (_dt.date, _dt.datetime)):
        return x.isoformat()[:10]
    return x


def load_lab(path: str | Path) -> dict:
    """Read and validate a laboratory details file (see ``protocols/lab-example.toml``).

    TOML dates are accepted as well as "YYYY-MM-DD" text. An unknown key, a
    missing required key or a wrong type raises a GonioError naming the file and
    the key.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "lab.toml"
    >>> _ = p.write_text('[laboratory]\\nname = "L"\\naddress = "A"\\nfax = "1"\\n')
    >>> load_lab(p)
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: ...lab.toml: key laboratory.fax: unknown key (known: name, address, accreditation, contact)
    """
    raw = _dates_to_text(read_toml(path))
    check_text_fields(raw, path)          # no control characters, no megabyte of name
    lab = validate_table(raw, LAB_SCHEMA, "", path)
    for key in ("instrument", "environment"):
        if lab[key] is None:
            lab[key] = validate_table({}, LAB_SCHEMA[key].schema, key, path)
    if lab["standards"] is None:
        lab["standards"] = []
    limits = lab["specification_limits"] or []
    check_one_limit_per_item(limits, file=path)
    for i, lim in enumerate(limits):
        key = f"specification_limits[{i}]"
        if lim["mpe"] is not None and (lim["lower"] is not None or lim["upper"] is not None):
            raise GonioError("give mpe or lower/upper, not both", file=path, key=key)
        try:
            limits_of(lim)
        except GonioError as exc:
            raise GonioError(exc.message, file=path, key=key) from None
    if limits and lab["decision_rule"] is None:
        raise GonioError("specification limits need the decision rule agreed "
                         "([decision_rule] rule = simple | guarded | non-binary)", file=path,
                         key="decision_rule")
    return lab


@contextlib.contextmanager
def naming_lab_file(path):
    """Errors about the lab file's limits raised while its limits are decided (an item the
    specification does not have: known only once the calibration ran) name the lab file
    ``path`` as well as the key.

    >>> try:
    ...     with naming_lab_file("lab.toml"):
    ...         raise GonioError("s has no item 'K'", key="specification_limits[0].item")
    ... except GonioError as e:
    ...     print(e)
    lab.toml: key specification_limits[0].item: s has no item 'K'
    """
    try:
        yield
    except GonioError as exc:
        if path is None or exc.file is not None or exc.line is not None \
                or not str(exc.key or "").startswith(("specification_limits", "decision_rule")):
            raise
        raise GonioError(exc.message, file=path, key=exc.key) from None


def certificate_id(report, lab: dict | None = None) -> str:
    """The certificate's identifier: the lab file's number, else ``VB-`` + readings hash.

    >>> class R: source_sha256 = "adf7d70bf7f73fcbe3e7897ae81a78dd"
    >>> certificate_id(R()), certificate_id(R(), {"certificate": {"number": "GON-2026-017"}})
    ('VB-ADF7D70BF7', 'GON-2026-017')
    """
    if lab:
        return lab["certificate"]["number"]
    sha = report.source_sha256 or "0" * 10
    return "VB-" + sha[:10].upper()


# --------------------------------------------------------------------------- content blocks

@dataclass
class Block:
    """One piece of content: kind is h (heading), sub (sub-heading), p, kv, table, fig,
    notice. Headings and sub-headings are kept on the page of what follows them."""

    kind: str
    data: Any
    extra: Any = None


def _num(results: dict, src: str, rule: str, U: float | None) -> Num | str:
    return num(results, src, rule, U)


def _meta(md: dict, key: str, L) -> str:
    """A readings metadata value as shown (the virtual bench's own descriptions in the page's
    language where the tables know them; data otherwise)."""
    v = md.get(key)
    if v in (None, ""):
        return L["not_stated"]
    if L.get("_lang") == "zh":
        from gonio.report.i18n import translator
        return translator()(str(v)) or str(v)
    return str(v)


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
    (results.json ``findings``; issue 24): the count, then one line per finding."""
    found = [f for f in res.get("findings") or () if f["action"] != "refused"]
    if not found:
        return
    aside = sum(f["action"] == "set_aside" for f in found)
    flagged = len(found) - aside
    add("notice", L["screening_note"].format(n=aside, m=flagged))
    names = {k: L[k] for k in item_names(res) if k in L}   # a test named by its item
    for f in found[:MAX_FINDING_LINES]:
        add("p", [finding_text(f, L, extra=names)])
    if len(found) > MAX_FINDING_LINES:
        add("p", [L["more_findings"].format(n=len(found) - MAX_FINDING_LINES)])


def certificate_blocks(report, L: dict, *, lab: dict | None, truth: dict | None,
                       lang: str = "en", cjk: bool = True) -> dict:
    """The certificate's content: header fields and the list of blocks, in order.

    Returns a dict with ``id``, ``virtual`` (bool), ``lab_name``, ``blocks`` and
    ``results``. ``cjk`` False (no CJK font installed) writes the specification's
    Chinese title in English so that nothing prints as boxes.
    """
    res = clean_tree(report.to_dict())          # user text shown literally (report/text.py)
    lab = clean_tree(lab) if lab else lab
    unc = res["uncertainty"]
    U = float(unc["U_arcsec"]) if unc.get("U_arcsec") is not None else None
    virtual = is_virtual(res, lab)              # the readings' provenance, not the lab file
    lab_ = lab or {}
    blocks: list[Block] = []
    add = lambda kind, data, extra=None: blocks.append(  # noqa: E731
        Block(kind, _summarised(kind, data), extra))

    _admin_blocks(add, res, lab_, L, lang=lang, cjk=cjk, virtual=virtual)

    # method
    add("h", L["method"])
    add("kv", method_rows(report, res, L, lab, lang, cjk))
    add("p", [L["m_readings"]])

    # results: Annex B, each item with its U, k and coverage probability
    add("h", L["results"])
    rrows = _result_rows(res, L, U)
    add("table", ([L["no"], L["item"], L["clause"], L["result"], L["U_col"], L["unit"]], rrows),
        {"widths": (0.07, 0.20, 0.075, 0.325, 0.24, 0.09), "id": "results"})
    if U is not None:
        add("p", segments(L["U_line_p"], U=_num(res, "uncertainty.U_arcsec", "U", U),
                          k=_num(res, "uncertainty.k", "k", U),
                          p=coverage_text(ANNEX_A_COVERAGE, lang)), "U")
        add("p", segments(L["u_c_line"], u=_num(res, "uncertainty.u_c_arcsec", "U", U)))
        ks = unc.get("k_source")                 # issue 12, defect 3: say where k comes from
        if ks:
            add("p", [L["k_fixed"] if ks == "fixed by laboratory" else L["k_welch"]])
    else:
        add("p", [L["no_E_U"]], "U")
    screening_notes(res, L, add)
    if res["scale_factor"].get("measurand"):
        sf = res["scale_factor"]
        ppm = (sf["instrument_own_upper_counts_per_deg"] / sf["value"] - 1) * 1e6
        add("p", [L["K_as_mounted"].format(psi=display("pos", sf["tilt_bound_deg"]),
                                           ppm=f"{ppm:.2g}")])

    _conformity_blocks(add, res, lab, report.conformity, L)

    _budget_blocks(add, res, U, L, lang)

    # readings taken
    add("h", L["readings_taken"])
    for note in res.get("readings_taken", []):
        add("p", ["• " + reading_note(note, lang)])

    _signatory_blocks(add, lab_, L)

    # details of the measurements
    add("h", L["details"])
    _detail_tables(res, L, U, add)

    # table calibration by equal-division averaging, when the readings hold it
    if res.get("equal_division"):
        _eda_section(res, L, U, add)

    # figures
    add("h", L["figures"])
    for key, cap, draw in FIGURES:
        add("fig", (key, L[cap], draw))
    return {"id": certificate_id(report, lab), "virtual": virtual,
            "lab_name": (lab_["laboratory"]["name"] if lab else L["virtual_lab"]),
            "blocks": blocks, "results": res}


def _admin_blocks(add, res: dict, lab_: dict, L: dict, *, lang: str, cjk: bool,
                  virtual: bool) -> None:
    """Laboratory, customer, instrument, dates, document and readings; standards and their
    traceability; the environment (ISO/IEC 17025 7.8.2.1 a–h)."""
    md = res.get("metadata", {})
    # a, b, c: title, laboratory, place; d: identifier (header of every page)
    if virtual:
        add("notice", " ".join(virtual_lines(res, L)))
    if not lab_.get("laboratory"):
        lab_rows = [(L["laboratory"], L["virtual_lab"]), (L["address"], "—")]
    else:
        la = lab_["laboratory"]
        lab_rows = [(L["laboratory"], la["name"]), (L["address"], la["address"])]
        if la["accreditation"]:
            lab_rows.append((L["accreditation"], la["accreditation"]))
        if la["contact"]:
            lab_rows.append((L["contact"], NoBreak(la["contact"])))
    add("kv", lab_rows)
    cert = lab_.get("certificate", {})
    cust = lab_.get("customer", {"name": L["not_stated"], "address": ""})
    inst = lab_.get("instrument", {})
    ns = L["not_stated"]
    rows = [(L["customer"], cust["name"] or ns)]
    if cust.get("address"):
        rows.append((L["customer_address"], cust["address"]))
    rows += [
        (L["description"], inst.get("description") or _meta(md, "instrument", L)),
        (L["model"], NoBreak(inst.get("model") or _meta(md, "model", L))),
        (L["serial"], NoBreak(inst.get("serial") or _meta(md, "serial", L))),
        (L["manufacturer"], inst.get("manufacturer") or _meta(md, "manufacturer", L)),
        (L["date_receipt"], cert.get("date_of_receipt") or ns),
        (L["date_calibration"], cert.get("date_of_calibration") or _meta(md, "date", L)),
        (L["date_issue"], cert.get("date_of_issue") or ns),
        (L["place"], cert.get("place") or (L["virtual_place"] if virtual else ns)),
        (L["specification"], specification_text(res.get("specification") or ns, lang, cjk)),
        (L["source_file"], f"{res['source']['file']} (SHA-256 {res['source']['sha256'][:16]}…, "
                           + L["rows_word"].format(n=res['source']['rows']) + ")"),
    ]
    add("kv", rows)

    # standards and traceability
    add("h", L["standards"])
    std_rows = []
    for s in lab_.get("standards") or []:
        std_rows.append([s["name"], NoBreak(s["identifier"] or "—"), s["accuracy"] or "—",
                         NoBreak(s["certificate"] or "—"), s["traceability"] or "—"])
    if not std_rows:
        mpe = md.get("table_mpe_arcsec")
        std_rows.append([_meta(md, "table", L), "—",
                         L["std_mpe"].format(v=mpe) if mpe else ns, "—",
                         L["virtual_trace"] if virtual else ns])
    add("table", ([L["std_name"], L["std_id"], L["std_spec"], L["std_cert"], L["std_trace"]],
                  std_rows), (0.30, 0.13, 0.17, 0.15, 0.25))

    # environment
    env = lab_.get("environment") or {}
    t = env.get("temperature_c")
    h = env.get("humidity_pct")
    t_txt = f"{t:g} °C" if t is not None else (f"{md['temperature_c']} °C"
                                               if md.get("temperature_c") else ns)
    h_txt = f"{h:g} %" if h is not None else (f"{md['humidity_pct']} %"
                                             if md.get("humidity_pct") else ns)
    add("h", L["environment"])
    add("kv", [(L["temperature"], t_txt), (L["humidity"], h_txt)])



def _result_rows(res: dict, L: dict, U: float | None) -> list:
    """The results table's rows (Annex B): each item with its U, k and coverage
    probability, or the reason it was not measured."""
    rrows = []
    for i, name in enumerate(item_names(res), 1):
        item = res[name]
        unit = NoBreak(L.get("u_" + item["unit"], item["unit"]))
        st = stated_item(res, name)
        if not st["measured"]:
            rrows.append([str(i), L[name], item["clause"],
                          f"{L['not_measured']}: "
                          f"{reason_text(item['reason'], L, extra={k: L[k] for k in item_names(res) if k in L})}",
                          "—", ""])
            continue
        cell: list = [st["value"]]
        if st["signed"] is not None:
            cell += ["; ", *segments(L["E_note"], s=st["signed"], p=st["position"] or "—")]
        elif name == "zero_stability" and item.get("range_deg_per_h") is not None:
            cell += ["; ", *segments(L["note_zero_range"],
                                     v=_num(res, f"{name}.range_deg_per_h", "sig3", U))]
            iu = item.get("uncertainty") or {}
            if iu.get("interval") and iu.get("nu_eff"):
                cell += ["; ", *segments(L["note_zero_interval"],
                                         n=_num(res, f"{name}.uncertainty.nu_eff", "k", U),
                                         lo=_num(res, f"{name}.uncertainty.interval.0", "sig3", U),
                                         hi=_num(res, f"{name}.uncertainty.interval.1", "sig3",
                                                 U))]
            if item.get("stated") == "draft" and (item.get("estimates") or {}).get("model"):
                cell += ["; ", *segments(L["note_zero_model"],
                                         v=_num(res, f"{name}.estimates.model.value", "sig3", U))]
        elif name in ("rate_consistency", "pointing_consistency"):
            cell += ["; ", *segments(L["note_spread"],
                                     v=_num(res, f"{name}.spread_arcsec", "atU", U))]
        elif name == "repeatability" and item.get("position_deg") is not None:
            cell += [" (", *segments(L["note_at"], p=_num(res, f"{name}.position_deg", "pos", U)),
                     ")"]
        if st["upper"] is not None:       # B_s: U exceeds the value (statement rule)
            cell += ["; ", *segments(L["note_upper"].replace("{u}", str(unit)), b=st["upper"])]
        rrows.append([str(i), L[name], item["clause"], cell, u_cell(st, L), unit])
    return rrows


def _conformity_blocks(add, res: dict, lab: dict | None, decided, L: dict) -> None:
    """The decision rule and the conformity table: the decisions the pipeline made."""
    lab_ = lab or {}
    # decision rule and conformity: the decisions the pipeline made (results.json), rendered
    conf = conformity_for(res, lab, decided)
    if conf:
        add("h", L["conformity"])
        rule = conf[0]["rule"]
        add("p", [L[f"rule_{rule.kind}"].format(r=display("k", rule.guard_factor))])
        agreed = (lab_.get("decision_rule") or {}).get("agreed")
        if agreed:
            add("p", [L["rule_agreed"].format(a=agreed)])
        crow = []
        for e in conf:
            unit = L.get("u_" + res[e["item"]]["unit"], res[e["item"]]["unit"])
            c = e["conformity"]
            if c is None:
                crow.append([L[e["item"]], "—", "—", L[e["reason"]], "—"])
                continue
            t = conformity_texts(c, res, L)
            out_txt = t["outcome"] + (f" ({t['pfr']})" if t["pfr"] else "")
            crow.append([L[e["item"]], NoBreak(f"{t['limits']} {unit}"),
                         NoBreak(t['acceptance'] if t['acceptance'] == L['c_acc_empty']
                                 else f"{t['acceptance']} {unit}"), out_txt, t["pfa"]])
        add("table", ([L["item"], L["c_limits"], L["c_accept"], L["c_outcome"], L["c_pfa"]],
                      crow), {"widths": (0.26, 0.19, 0.19, 0.20, 0.16), "id": "conformity"})



def _budget_blocks(add, res: dict, U: float | None, L: dict, lang: str) -> None:
    """The uncertainty budget of E (Annex A), each component with its source."""
    unc = res["uncertainty"]
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
                      _num(res, f"uncertainty.components.{j}.u_arcsec", "U", U),
                      _num(res, f"uncertainty.components.{j}.contribution_arcsec", "U", U)])
    add("table", ([L["component"], L["source"], L["type"], L["u_i"], L["d_contrib"]], brows),
        (0.14, 0.50, 0.08, 0.14, 0.14))



def _signatory_blocks(add, lab_: dict, L: dict) -> None:
    """Signatories and the certificate's statements."""
    # statements and signatures
    add("h", L["signatory"])
    sig = lab_.get("signatory", {})
    approved = sig.get("approved_by") or "—"
    if sig.get("approved_title"):
        approved += f", {sig['approved_title']}"
    add("kv", [(L["calibrated_by"], sig.get("calibrated_by") or "—"),
               (L["checked_by"], sig.get("checked_by") or "—"),
               (L["approved_by"], approved)])
    add("p", [L["statement_item"]])
    add("p", [L["statement_copy"]])
    add("p", [L["statement_recal"]])


def _eda_section(res: dict, L: dict, U: float, add) -> None:
    """The table-calibration page: table and goniometer errors with their uncertainties;
    each error to the decimal place of its own u (JCGM 100 7.2.6)."""
    e = res["equal_division"]
    add("h", L["eda"])
    add("p", [L["eda_note"].format(n=e["n_starts"], m=e["m_points"], r=e["repeats"],
                                   noise=e["noise"])])
    rows = []
    for i in range(e["m_points"]):
        ut = e["table"]["u_arcsec"][i]
        ug = e["goniometer"]["u_arcsec"][i]
        rows.append([_num(res, f"equal_division.table.position_deg.{i}", "pos", U),
                     _num(res, f"equal_division.table.error_arcsec.{i}", rule_at_U(ut), U),
                     _num(res, f"equal_division.table.u_arcsec.{i}", "U", U),
                     _num(res, f"equal_division.goniometer.angle_deg.{i}", "pos", U),
                     _num(res, f"equal_division.goniometer.error_arcsec.{i}", rule_at_U(ug), U),
                     _num(res, f"equal_division.goniometer.u_arcsec.{i}", "U", U)])
    add("table", ([L["eda_position"], L["eda_table"], "u (″)", L["eda_turned"], L["eda_gonio"],
                   "u (″)"], rows), (0.18, 0.17, 0.15, 0.18, 0.17, 0.15))
    cl = e["closure"]
    add("p", segments(L["eda_closure"],
                      v=_num(res, "equal_division.closure.full_turn_arcsec",
                             rule_at_U(cl.get("u_full_turn_arcsec")), U),
                      u=_num(res, "equal_division.closure.u_full_turn_arcsec", "U", U)))
    cp = e.get("coupling")                   # tilt × Earth-rate coupling (issue 12, defect 6)
    if cp:
        txt = cp["note"]
        if cp.get("separable"):
            txt += (f" (Ω⊥ tan ψ = {cp['amplitude_arcsec_s']:.2g}″/s, largest effect on a "
                    f"reading {cp['max_effect_arcsec']:.2g}″)")
        add("p", [txt])


def _detail_tables(res: dict, L: dict, U: float, add) -> None:
    sf = res["scale_factor"]
    if sf["measured"]:
        rows = [[_num(res, f"scale_factor.table.{i}.round", "int", U),
                 _num(res, f"scale_factor.table.{i}.table_deg", "pos", U),
                 _num(res, f"scale_factor.table.{i}.gyro_counts", "int", U),
                 _num(res, f"scale_factor.table.{i}.K_i_counts_per_deg", "sig8", U)]
                for i in range(len(sf["table"]))]
        add("sub", L["scale_factor"] + " (7.1)")
        add("table", ([L["d_round"], L["d_theta"], L["d_counts"], L["d_K"]], rows),
            (0.15, 0.25, 0.30, 0.30))
        sm = sf.get("table_summary")
        if sm:
            add("p", [L["d_listed"].format(name="scale_factor", **{
                k: (f"{sm[k]:.9g}" if isinstance(sm.get(k), float) else sm.get(k))
                for k in ("rows", "listed", "column", "min", "max")})])
    ad, rp = res["angle_deviation"], res["repeatability"]
    if ad["measured"]:
        rmap = {r["position_deg"]: j for j, r in enumerate(rp["table"])} if rp["measured"] else {}
        rows = []
        for i, r in enumerate(ad["table"]):
            j = rmap.get(r["position_deg"])
            rows.append([_num(res, f"angle_deviation.table.{i}.position_deg", "pos", U),
                         _num(res, f"angle_deviation.table.{i}.E_arcsec", "atU", U),
                         _num(res, f"repeatability.table.{j}.R_arcsec", "atU", U)
                         if j is not None else "—",
                         _num(res, f"angle_deviation.table.{i}.n_series", "int", U)])
        add("sub", L["angle_deviation"] + " / " + L["repeatability"] + " (7.4, 7.5)")
        add("table", ([L["d_position"], L["d_E"], L["d_R"], L["d_n"]], rows),
            (0.25, 0.25, 0.25, 0.25))
    for name, col, fmt in (("rate_consistency", "rate_dps", "pos"),
                           ("pointing_consistency", "orientation", None)):
        c = res[name]
        if not c["measured"]:
            continue
        order = sorted(range(len(c["table"])), key=lambda i: (not c["table"][i].get("reference"),
                                                              i))
        rows = []
        for i in order:
            r = c["table"][i]
            cond = (_num(res, f"{name}.table.{i}.{col}", fmt, U) if fmt
                    else L.get(str(r[col]), str(r[col])))
            rows.append([cond, L["d_reference"] if r.get("reference") else L["d_compared"],
                         _num(res, f"{name}.table.{i}.E_arcsec", "atU", U),
                         _num(res, f"{name}.table.{i}.max_abs_arcsec", "atU", U)])
        add("sub", L[name] + f" ({c['clause']})")
        head = L["d_rate"] if col == "rate_dps" else L["d_axis"]
        add("table", ([head, L["d_role"], L["d_Ev"], L["d_maxabs"]], rows),
            {"widths": (0.25, 0.25, 0.25, 0.25), "id": f"table-{name}"})


# --------------------------------------------------------------------------- HTML

_CSS = """
body{font-family:%(font)s;max-width:1040px;margin:0 auto;padding:16px 24px;color:#111;font-size:14px}
header.page{display:flex;justify-content:space-between;border-bottom:2px solid #333;padding:4px 0;margin-bottom:8px}
h1{text-align:center;font-size:24px;margin:10px 0 4px}
h2{font-size:16px;border-bottom:1px solid #999;margin:18px 0 6px;padding-bottom:2px}
h3{font-size:14px;margin:12px 0 4px}
h2,h3{break-after:avoid;page-break-after:avoid}
table{border-collapse:collapse;width:100%%;margin:4px 0 8px}
tr{break-inside:avoid}
div.keep{break-inside:avoid;page-break-inside:avoid}
thead{display:table-header-group}
td,th{border:1px solid #888;padding:3px 6px;text-align:left;vertical-align:top}
th{background:#eee}
.nb{white-space:nowrap}
table.kv td:first-child{width:32%%;background:#f6f6f6}
.banner{background:#b00020;color:#fff;font-weight:bold;text-align:center;padding:8px;font-size:18px;letter-spacing:1px;margin:6px 0}
.watermark{position:fixed;top:45%%;left:0;width:100%%;text-align:center;transform:rotate(-30deg);font-size:64px;font-weight:bold;color:rgba(176,0,32,0.10);pointer-events:none;z-index:10}
.notice{border:2px solid #b00020;padding:6px;color:#b00020}
figure{margin:10px 0;break-inside:avoid;page-break-inside:avoid}
figure svg{width:100%%;height:auto}
figcaption{font-size:13px;color:#333;text-align:center}
.u{font-weight:bold;font-size:15px}
footer{border-top:1px solid #333;margin-top:16px;font-size:12px;color:#333}
@page{size:A4;margin:20mm 14mm 18mm 14mm;
 @top-left{content:%(lab)s;font-family:%(font)s;font-size:9pt}
 @top-right{content:%(cid)s;font-family:%(font)s;font-size:9pt}
 @bottom-left{content:%(cid)s;font-family:%(font)s;font-size:8pt}
 @bottom-right{content:%(pageword)s;font-family:%(font)s;font-size:8pt}}
@media print{header.page,footer{display:none}body{max-width:none;padding:0;font-size:12px}
 figure svg{width:92%%}}
"""


def css_string(text: str) -> str:
    """``text`` as a quoted CSS string inside ``<style>``: backslash and quote escaped, and
    ``<``, ``>``, ``&`` as CSS hex escapes, so user text can never close the style element.

    >>> print(css_string('say "hi"'))
    "say \\"hi\\""
    >>> print(css_string("</style><script>"))
    "\\3c /style\\3e \\3c script\\3e "
    """
    text = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", " ")
    for ch, esc in (("<", "\\3c "), (">", "\\3e "), ("&", "\\26 ")):
        text = text.replace(ch, esc)
    return '"' + text + '"'


#: A lone relation sign in a table cell's text, bound to its sides with no-break spaces (and
#: a per-cent sign to the number segment before it), so a browser never wraps "p ≈ / 95 %"
#: (the PDF: :func:`_glue`). A plain "27 %" keeps its space.
_BIND = re.compile(r" (≈|=|≤|≥|&lt;|&gt;) ")


def _h(x, cell: bool = False) -> str:
    """HTML of a text, a number (its span with the rule it was rounded by), a NoBreak or a
    list of them; ``cell``: a table cell's text, relations bound (:data:`_BIND`)."""
    if isinstance(x, Num):
        return (f'<span class="num" data-src="{html.escape(x.src)}" '
                f'data-rule="{html.escape(x.rule)}">{html.escape(x.text)}</span>')
    if isinstance(x, NoBreak):
        return f'<span class="nb">{html.escape(str(x))}</span>'
    if isinstance(x, list):
        return "".join(_h(s, cell) for s in x)
    s = html.escape(str(x))
    if cell:
        s = _BIND.sub(lambda m: f"\u00a0{m[1]}\u00a0", s)
        if s.startswith(" %"):                  # "95 %" whose number is the segment before
            s = "\u00a0" + s[1:]
    return s


def render_html(content: dict, svgs: dict[str, str], L: dict, lang: str, font: str | None) -> str:
    """The certificate as one self-contained HTML page (no external resources).

    On screen the page has a header with the laboratory and the identifier (a web page
    has no page numbers). Printed (print CSS, ``@page`` margin boxes) every page carries
    the laboratory, the identifier and "Page x of y".
    """
    cid = content["id"]
    ff = (f"'{font}', " if font else "") + "'DejaVu Sans', 'Noto Sans CJK SC', Arial, sans-serif"
    pageword = " ".join(
        css_string(part) if i % 2 == 0 else part for i, part in enumerate(
            L["page_of"].replace("{x}", "\0counter(page)\0").replace(
                "{y}", "\0counter(pages)\0").split("\0")) if part)
    css = _CSS % {"font": ff, "pageword": pageword, "lab": css_string(content["lab_name"]),
                  "cid": css_string(f"{L['certificate_no']}: {cid}")}
    out = ["<!DOCTYPE html>", f'<html lang="{"zh-CN" if lang == "zh" else "en"}">', "<head>",
           '<meta charset="utf-8">', f"<title>{html.escape(L['title'])} {html.escape(cid)}</title>",
           f"<style>{css}</style>", "</head>", "<body>"]
    if content["virtual"]:
        out.append(f'<div class="watermark" aria-hidden="true">{html.escape(L["virtual_short"])}</div>')
        out.append(f'<div class="banner" id="virtual-banner">{html.escape(L["virtual"])}</div>')
    out.append(f'<header class="page"><span>{html.escape(content["lab_name"])}</span>'
               f'<span id="cert-id" class="nb">{html.escape(L["certificate_no"])}: '
               f'{html.escape(cid)}</span></header>')
    out.append(f"<h1>{html.escape(L['title'])}</h1>")
    for b in content["blocks"]:
        if b.kind == "h":
            out.append(f"<h2>{html.escape(b.data)}</h2>")
        elif b.kind == "sub":
            out.append(f"<h3>{html.escape(b.data)}</h3>")
        elif b.kind == "notice":
            out.append(f'<p class="notice">{html.escape(b.data)}</p>')
        elif b.kind == "p":
            cls = ' class="u" id="U-line"' if b.extra == "U" else ""
            out.append(f"<p{cls}>{_h(b.data)}</p>")
        elif b.kind == "kv":
            out.append('<table class="kv">' + "".join(
                f"<tr><td>{_h(k)}</td><td>{_h(v)}</td></tr>" for k, v in b.data) + "</table>")
        elif b.kind == "table":
            head, rows = b.data
            tid = f' id="{b.extra["id"]}"' if isinstance(b.extra, dict) else ""
            keep = html_keep_whole(head, rows, b.extra)   # kept whole on a printed page
            out.append(('<div class="keep">' if keep else "")
                       + f"<table{tid}><thead><tr>" + "".join(f"<th>{_h(c)}</th>" for c in head)
                       + "</tr></thead><tbody>"
                       + "".join("<tr>" + "".join(f"<td>{_h(c, True)}</td>" for c in r) + "</tr>"
                                 for r in rows) + "</tbody></table>" + ("</div>" if keep else ""))
        elif b.kind == "fig":
            key, cap, _ = b.data
            out.append(f'<figure id="fig-{key}">{svgs[key]}<figcaption>{html.escape(cap)}'
                       f"</figcaption></figure>")
    out.append(f"<footer>{html.escape(L['certificate_no'])}: {html.escape(cid)} — "
               f"{html.escape(L['statement_copy'])}</footer>")
    if content["virtual"]:
        out.append(f'<div class="banner">{html.escape(L["virtual"])}</div>')
    out += ["</body>", "</html>", ""]
    return "\n".join(out)


# --------------------------------------------------------------------------- PDF

#: A4 portrait, inches.
A4_IN: tuple[float, float] = (8.27, 11.69)
_PT = 1.0 / 72.0 / A4_IN[1]          # one point as a fraction of the page height
_LEFT, _RIGHT, _TOP, _BOTTOM = 0.08, 0.92, 0.90, 0.08
_FIG_H = 0.33                        # a figure's height, fraction of the page


def _width(s: str) -> int:
    return sum(2 if unicodedata.east_asian_width(ch) in "WF" else 1 for ch in s)


#: Characters that never begin a line (closing brackets and punctuation, GB/T 15834 4.1)
#: and that never end one (opening brackets).
_NO_START = set("。，、；：？！）」』】〉》)]}%,;:")
_NO_END = set("（「『【〈《([{")


#: A relation standing alone between spaces binds its two sides: "p ≈ 95 %", "k = 2.07".
_RELATIONS = frozenset("≈=≤≥<>")


def _glue(tokens: list[str]) -> list[str]:
    """Wrapping tokens with a closing mark joined to the token before it and an opening mark
    to the token after it, so no line starts with ")" or "。" nor ends with "("; a lone
    relation sign is joined to both its sides (no line ends with "p ≈").

    >>> _glue(["k", "）", "。"]), _glue(["（", "a", "b"]), _glue(["≈ ", "95 ", "%)"])
    (['k）。'], ['（a', 'b'], ['≈ 95 %)'])
    >>> _glue(["0.012 ", "(k ", "= ", "2.07, ", "p ", "≈ ", "95 ", "%)"])
    ['0.012 ', '(k = 2.07, ', 'p ≈ 95 %)']
    """
    out: list[str] = []
    carry = ""
    bind = False
    for tok in tokens:
        tok = carry + tok
        carry = ""
        relation = tok.strip() in _RELATIONS and len(tok.strip()) == 1
        if out and (bind or relation):
            out[-1] += tok
            bind = relation
            continue
        bind = relation
        if out and tok and tok[0] in _NO_START and (not out[-1].endswith(" ")
                                                      or tok[0] == "%"):   # "95 %" whole
            out[-1] += tok
        elif tok and tok[-1] in _NO_END and len(tok) == 1:
            carry = tok
        else:
            out.append(tok)
    if carry:
        out.append(carry)
    return out


def _tokens(para: str) -> list[str]:
    """The unbreakable pieces of one paragraph: words with their trailing space, each CJK
    character alone, glued (:func:`_glue`)."""
    tokens: list[str] = []
    word = ""
    for ch in para:
        if ch == " ":
            tokens.append(word + " ")
            word = ""
        elif unicodedata.east_asian_width(ch) in "WF":
            if word:
                tokens.append(word)
            tokens.append(ch)
            word = ""
        else:
            word += ch
    if word:
        tokens.append(word)
    return _glue(tokens)


def _wrap(text: str, width: int) -> list[str]:
    """Wrap ``text`` to ``width`` columns (CJK characters count two; breaks at spaces or CJK)."""
    lines: list[str] = []
    for para in str(text).split("\n"):
        line, w = "", 0
        for tok in _tokens(para):
            tw = _width(tok)
            if w + tw > width and line:
                lines.append(line.rstrip())
                line, w = "", 0
            while tw > width:                      # a single over-long token
                lines.append(tok[:width])
                tok = tok[width:]
                tw = _width(tok)
            line += tok
            w += tw
        lines.append(line.rstrip())
    return lines


def _text(x) -> str:
    if isinstance(x, Num):
        return x.text
    if isinstance(x, list):
        return "".join(_text(s) for s in x)
    return str(x)


def _cell_lines(c, cols: int) -> list[str]:
    """A table cell's lines: a NoBreak cell (identifier, unit) is never split."""
    if isinstance(c, NoBreak):
        return [str(c)]
    return _wrap(_text(c), cols)


def _longest_token(c) -> int:
    """Width (columns) of the longest unbreakable piece of a cell."""
    if isinstance(c, NoBreak):
        return _width(str(c))
    return max((_width(t.rstrip()) for para in _text(c).split("\n") for t in _tokens(para)),
               default=0)


def fit_widths(widths, head, rows, cols_per_frac: float) -> tuple[float, ...]:
    """Column widths (fractions summing to 1) widened so that no identifier, unit or word
    is broken: each column gets at least its longest token, taken from columns with slack.

    >>> fit_widths((0.5, 0.5), ["a", "b"], [["x" * 30, "y"]], 40.0)
    (0.7875, 0.2125)
    """
    need = [0.0] * len(widths)
    for r in [head, *rows]:
        for j, c in enumerate(r):
            need[j] = max(need[j], (_longest_token(c) + 1.5) / cols_per_frac)
    w = [max(a, b) for a, b in zip(widths, need)]
    excess = sum(w) - 1.0
    if excess > 1e-12:
        slack = [max(0.0, wi - ni) for wi, ni in zip(w, need)]
        total = sum(slack)
        if total > 0:
            w = [wi - excess * si / total if total >= excess else wi - si
                 for wi, si in zip(w, slack)]
        ssum = sum(w)
        w = [wi / ssum for wi in w]
    return tuple(round(x, 6) for x in w)


class _Layout:
    """Places blocks on A4 pages; each page is a list of (y_top, op)."""

    def __init__(self, fontsize: float):
        self.fs = fontsize
        self.line = fontsize * 1.45 * _PT
        self.pages: list[list] = [[]]
        self.y = _TOP

    def fits(self, h: float) -> bool:
        return self.y - h >= _BOTTOM or not self.pages[-1]

    def need(self, h: float) -> None:
        if not self.fits(h):
            self.pages.append([])
            self.y = _TOP

    def put(self, h: float, op: Callable) -> None:
        self.need(h)
        self.pages[-1].append((self.y, op))
        self.y -= h

    def cols(self, frac: float) -> int:
        """Characters of the body font that fit in ``frac`` of the text width."""
        width_pt = (_RIGHT - _LEFT) * A4_IN[0] * 72.0 * frac
        return max(4, int(width_pt / (self.fs * 0.56)))


_H_H = 22 * _PT          # a heading's height
_SUB_H = 16 * _PT        # a sub-heading's height


#: A table of at most this many rows is kept on one page (when it fits on one).
KEEP_WHOLE_ROWS: int = 8
#: A longer table starts on a page with its head and at least this many rows; its head is
#: repeated on every continuation page.
KEEP_FIRST_ROWS: int = 3
#: A short table is not kept whole when moving it to the next page would leave more than this
#: fraction of the page's text height blank (the optical certificate's page 1 was left with a
#: fifth of it blank): it starts where it is, with its head and first
#: :data:`SPLIT_FIRST_ROWS` rows, and goes on under its repeated head.
MAX_BLANK_FRACTION: float = 1 / 8
#: The rows a short table split by :data:`MAX_BLANK_FRACTION` starts with (no lone row).
SPLIT_FIRST_ROWS: int = 2
#: The HTML (laid out by the browser) keeps a short table whole when it is at most this
#: fraction of a page's text height (:func:`html_keep_whole`).
HTML_KEEP_WHOLE_FRACTION: float = 1 / 4


def html_keep_whole(head, rows, extra) -> bool:
    """Whether the HTML keeps a table whole on a printed page (the browser lays it out, so
    PDF's rule of :func:`table_start` cannot be applied): at most :data:`KEEP_WHOLE_ROWS` rows
    and, counted in lines at the PDF's column widths, at most
    :data:`HTML_KEEP_WHOLE_FRACTION` of a page, so that moving it whole never leaves more
    than that blank."""
    if len(rows) > KEEP_WHOLE_ROWS:
        return False
    lay = _Layout(8.5)
    widths = extra["widths"] if isinstance(extra, dict) else extra
    widths = fit_widths(widths, head, rows, lay.cols(1.0) * 1.0)
    lines = sum(max(len(_cell_lines(c, lay.cols(w) - 1)) for c, w in zip(r, widths))
                for r in [head, *rows])
    return lines * lay.line <= HTML_KEEP_WHOLE_FRACTION * (_TOP - _BOTTOM)


def table_start(units: list, room: float | None = None) -> float:
    """Height a table needs where it starts: its head with its first rows — all of them for a
    table of at most :data:`KEEP_WHOLE_ROWS` rows, else :data:`KEEP_FIRST_ROWS` — so a head
    never ends a page with its rows on the next one. ``room``: the height left on the page;
    a short table that does not fit there is still started there (head and
    :data:`SPLIT_FIRST_ROWS` rows) when keeping it whole would leave more than
    :data:`MAX_BLANK_FRACTION` of the page blank."""
    rows = [u for u in units if u[2] == "row"]
    n = len(rows) if len(rows) <= KEEP_WHOLE_ROWS else KEEP_FIRST_ROWS
    whole = units[0][0] + sum(u[0] for u in rows)
    if (room is not None and n == len(rows) and whole > room
            and room > MAX_BLANK_FRACTION * (_TOP - _BOTTOM)):
        n = min(n, SPLIT_FIRST_ROWS)
    h = units[0][0] + sum(u[0] for u in rows[:n])
    return h if h <= _TOP - _BOTTOM - 40 * _PT else units[0][0] + sum(u[0] for u in rows[:1])


#: A paragraph of at most this many lines is not split across pages.
KEEP_PARAGRAPH_LINES: int = 4


def block_start(block: Block, units: list, room: float | None = None) -> float:
    """Height a block needs on the page where it starts: a table's :func:`table_start` (with
    the ``room`` left), a short paragraph whole (at most :data:`KEEP_PARAGRAPH_LINES` lines),
    else its first unit."""
    if not units:
        return 0.0
    if block.kind == "table":
        return table_start(units, room)
    lines = [u[0] for u in units if u[2] == "line"]
    if block.kind in ("p", "notice") and len(lines) <= KEEP_PARAGRAPH_LINES:
        return sum(u[0] for u in units)         # its lines and the gap after them
    return units[0][0]


def layout_pages(content: dict, L: dict) -> list[list]:
    """Lay the blocks out on pages. A heading (h, sub) is kept on the page of the first
    unit of the block after it (:func:`block_start`: a table's head and first rows, a short
    paragraph whole, a figure, a long paragraph's first line), and of a table's start when a
    short note stands between them, so no page ends with a heading."""
    lay = _Layout(8.5)
    fs, ln = lay.fs, lay.line
    title_h = 30 * _PT

    def title(fig, y):
        fig.text(0.5, y - 20 * _PT, L["title"], ha="center", va="baseline", fontsize=18,
                 weight="bold")
    lay.put(title_h, title)
    blocks = content["blocks"]
    units = [_units(b, lay, content, L) for b in blocks]
    room_at: dict[int, float] = {}     # a table's room as judged where its heading was placed
    for i, b in enumerate(blocks):
        if b.kind in ("h", "sub"):
            # keep with the next block's first unit (and every following heading's)
            keep = 0.0
            j = i + 1
            while j < len(blocks) and blocks[j].kind in ("h", "sub"):
                keep += units[j][0][0]
                j += 1
            if j < len(blocks):
                room = lay.y - _BOTTOM - units[i][0][0] - keep
                room_at[j] = room
                keep += block_start(blocks[j], units[j], room)
                # a short note between a heading and its table: keep the table's start too
                if (blocks[j].kind == "p" and j + 1 < len(blocks)
                        and blocks[j + 1].kind == "table"
                        and len(units[j]) <= KEEP_PARAGRAPH_LINES):
                    room_at[j + 1] = room - keep
                    keep += block_start(blocks[j + 1], units[j + 1], room - keep)
            lay.need(units[i][0][0] + keep)
        elif b.kind in ("p", "notice"):
            lay.need(block_start(b, units[i]))
        for k, (h, op, kind) in enumerate(units[i]):
            if kind == "row" and not lay.fits(h):          # repeat the table head
                head_h, head_op, _ = units[i][0]
                lay.need(h + head_h)
                lay.put(head_h, head_op)
            elif kind == "head":      # decided as for its heading: it stays with it
                lay.need(table_start(units[i], room_at.get(i, lay.y - _BOTTOM)))
            if kind == "gap":
                lay.y -= h
                continue
            lay.put(h, op)
    return lay.pages


def _units(b: Block, lay: _Layout, content: dict, L: dict) -> list[tuple[float, Callable, str]]:
    """A block as (height, draw op, kind) units that are never split across pages."""
    fs, ln = lay.fs, lay.line
    out: list[tuple[float, Callable, str]] = []
    if b.kind in ("h", "sub"):
        big = b.kind == "h"

        def op(fig, y, t=b.data, big=big):
            fig.text(_LEFT, y - (13 if big else 11) * _PT, t, fontsize=10.5 if big else 9.2,
                     weight="bold", va="baseline")
            if big:
                fig.add_artist(_hline(fig, y - 16 * _PT, 0.6))
        out.append((_H_H if big else _SUB_H, op, "h"))
    elif b.kind in ("p", "notice"):
        big = b.extra == "U"
        lines = _wrap(_text(b.data), lay.cols(1.0) - (8 if big else 0))
        size = 10 if big else fs
        color = "#b00020" if b.kind == "notice" else "black"
        for line in lines:
            def op(fig, y, t=line, s=size, c=color, w="bold" if big else "normal"):
                fig.text(_LEFT, y - ln * 0.8, t, fontsize=s, va="baseline", color=c, weight=w)
            out.append((ln * (1.15 if big else 1.0), op, "line"))
        out.append((3 * _PT, None, "gap"))
    elif b.kind == "kv":
        for k, v in b.data:
            vl = _cell_lines(v, lay.cols(0.66))

            def op(fig, y, k=_text(k), vl=vl):
                fig.text(_LEFT, y - ln * 0.8, k, fontsize=fs, va="baseline", color="0.25")
                for i, t in enumerate(vl):
                    fig.text(_LEFT + 0.32 * (_RIGHT - _LEFT), y - ln * (0.8 + i), t,
                             fontsize=fs, va="baseline")
            out.append((ln * len(vl), op, "line"))
        out.append((4 * _PT, None, "gap"))
    elif b.kind == "table":
        head, rows = b.data
        widths = b.extra["widths"] if isinstance(b.extra, dict) else b.extra
        widths = fit_widths(widths, head, rows, lay.cols(1.0) * 1.0)
        xs = [_LEFT]
        for w in widths[:-1]:
            xs.append(xs[-1] + w * (_RIGHT - _LEFT))

        def row_unit(cells, bold=False, shade=False):
            wrapped = [_cell_lines(c, lay.cols(w) - 1) for c, w in zip(cells, widths)]
            n = max(len(w) for w in wrapped)

            def op(fig, y, wrapped=wrapped, n=n, xs=tuple(xs)):
                if shade:
                    fig.add_artist(_rect(fig, y, ln * n + 2 * _PT))
                for x, ls in zip(xs, wrapped):
                    for i, t in enumerate(ls):
                        fig.text(x + 0.004, y - ln * (0.8 + i), t, fontsize=fs - 0.5,
                                 va="baseline", weight="bold" if bold else "normal")
                fig.add_artist(_hline(fig, y - ln * n - 2 * _PT, 0.3))
            return ln * n + 2 * _PT, op
        h, op = row_unit(head, bold=True, shade=True)
        out.append((h, op, "head"))
        for r in rows:
            h2, op2 = row_unit(r)
            out.append((h2, op2, "row"))
        out.append((6 * _PT, None, "gap"))
    elif b.kind == "fig":
        key, cap, draw = b.data
        cap_lines = _wrap(cap, lay.cols(1.0))
        h = _FIG_H + ln * len(cap_lines) + 6 * _PT

        def op(fig, y, draw=draw, cap_lines=cap_lines):
            # the legend sits above the axes (figures._legend): leave it room below y
            gs = fig.add_gridspec(1, 1, left=_LEFT + 0.06, right=_RIGHT - 0.01,
                                  top=y - 0.05, bottom=y - _FIG_H + 0.035)
            draw(fig, gs[0], content["_report"], L, content["_truth"])
            plain_log_ticks(fig)
            for i, t in enumerate(cap_lines):
                fig.text(0.5, y - _FIG_H - ln * (0.8 + i), t, ha="center", fontsize=fs,
                         va="baseline")
        out.append((h, op, "fig"))
    return out


def _hline(fig, y, lw):
    from matplotlib.lines import Line2D
    return Line2D([_LEFT, _RIGHT], [y, y], transform=fig.transFigure, color="0.3", lw=lw)


def _rect(fig, y, h):
    from matplotlib.patches import Rectangle
    return Rectangle((_LEFT, y - h), _RIGHT - _LEFT, h, transform=fig.transFigure,
                     color="0.92", zorder=-1)


def render_pdf(content: dict, L: dict, fonts: tuple[str, ...] = ("DejaVu Sans",)) -> bytes:
    """The certificate as A4 PDF pages; each page has the identifier and "page x of y"."""
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure

    buf = io.BytesIO()
    with mpl_style(fonts):
        pages = layout_pages(content, L)
        n = len(pages)
        with PdfPages(buf, metadata={"CreationDate": None, "ModDate": None,
                                     "Creator": "gonio", "Title": f"{L['title']} {content['id']}"}
                      ) as pdf:
            for p, ops in enumerate(pages, 1):
                fig = Figure(figsize=A4_IN)
                _page_frame(fig, content, L, p, n)
                for y, op in ops:
                    op(fig, y)
                pdf.savefig(fig)
    return buf.getvalue()


def _page_frame(fig, content, L, p, n) -> None:
    page = L["page_of"].format(x=p, y=n)
    cid = f"{L['certificate_no']}: {content['id']}"
    # the lab name never runs into the certificate number (9 pt: ~0.56 em a character)
    cols = int((_RIGHT - _LEFT) * A4_IN[0] * 72.0 / (9 * 0.6))
    fig.text(_LEFT, 0.955, fit_header(content["lab_name"], cid, cols), fontsize=9,
             va="baseline")
    fig.text(_RIGHT, 0.955, cid, fontsize=9, va="baseline", ha="right")
    fig.text(_RIGHT, 0.94, page, fontsize=9, va="baseline", ha="right")
    fig.add_artist(_hline(fig, 0.932, 1.0))
    fig.add_artist(_hline(fig, 0.055, 0.6))
    fig.text(_LEFT, 0.04, f"{cid}   {page}", fontsize=7.5, va="baseline")
    fig.text(_LEFT, 0.027, L["statement_copy"], fontsize=6.5, va="baseline", color="0.3")
    if content["virtual"]:
        fig.text(0.5, 0.915, L["virtual"], ha="center", va="baseline", fontsize=11,
                 weight="bold", color="white",
                 bbox={"boxstyle": "square,pad=0.35", "fc": "#b00020", "ec": "none"})
        fig.text(0.5, 0.5, L["virtual_short"], ha="center", va="center", fontsize=54,
                 weight="bold", color="#b00020", alpha=0.10, rotation=35, zorder=-5)


# --------------------------------------------------------------------------- entry point

def has_cjk_font() -> bool:
    """True when a CJK font is installed (see :func:`gonio.report.i18n.cjk_font`)."""
    try:
        cjk_font()
    except GonioError:
        return False
    return True


def cjk_notice(lang: str) -> str | None:
    """The one line a command prints when the English certificate falls back to the English
    title because no CJK font is installed (None when there is one, or for zh)."""
    if lang != "en" or has_cjk_font():
        return None
    return labels("en")["cjk_missing"]


def font_families(lang: str) -> tuple[str, ...]:
    """Font families of the figures and the PDF, in fallback order.

    "zh": the CJK font first (GonioError naming the package when none is installed);
    "en": DejaVu Sans, then a CJK font if one is installed (the specification's title
    is Chinese).
    """
    if lang == "zh":
        return (cjk_font(), "DejaVu Sans")
    try:
        return ("DejaVu Sans", cjk_font())
    except GonioError:
        return ("DejaVu Sans",)


def write_certificate(report, out: str | Path, *, truth: dict | None = None,
                      lab: str | Path | dict | None = None, lang: str = "en",
                      dcc: bool = False) -> dict[str, Path]:
    """Write ``certificate.html`` and ``certificate.pdf`` (and with ``dcc`` the PTB DCC
    3.3.0 XML ``certificate.dcc.xml``, :mod:`gonio.report.dcc`) for ``report`` into ``out``.

    Parameters
    ----------
    report : the specification's calibration report
        What the specification's ``calibrate`` returned (``results.json`` is written by its
        ``outputs`` module, not here).
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
    L = labels(lang)
    fonts = font_families(lang)
    font = fonts[0] if lang == "zh" else None
    lab_d = load_lab(lab) if isinstance(lab, (str, Path)) else lab
    cjk = len(fonts) > 1 or lang == "zh"
    content = certificate_blocks(report, L, lab=lab_d, truth=truth, lang=lang, cjk=cjk)
    content["_report"], content["_truth"] = report, truth
    svgs = {key: figure_svg(draw, report, L, truth, fonts) for key, _, draw in FIGURES}
    out = Path(out)
    with output_dir(out) as stage:
        write_text(stage / "certificate.html", render_html(content, svgs, L, lang, font))
        write_bytes(stage / "certificate.pdf", render_pdf(content, L, fonts))
        if dcc:
            from gonio.report.dcc import bilingual, dcc_bytes, label_translator, method_text
            from gonio.report.i18n import READING_NOTES_ZH

            doc = dcc_bytes(report, lab=lab_d, cert_id=content["id"])
            if lang == "zh":                   # Chinese beside English (issue 25)
                extra = {**READING_NOTES_ZH,
                         **{k: L[k] for k in item_names(report.to_dict()) if k in L},
                         method_text(report, lab_d, "en"): method_text(report, lab_d, "zh")}
                doc = bilingual(doc, label_translator(extra))
            write_bytes(stage / "certificate.dcc.xml", doc)
    names = ["certificate.html", "certificate.pdf"] + (["certificate.dcc.xml"] if dcc else [])
    return {n: out / n for n in names}
