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

import datetime as _dt
import html
import io
import math
import unicodedata
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from gonio.atomic import output_dir, write_bytes, write_text
from gonio.report.text import clean_tree, fit_header
from gonio.errors import GonioError
from gonio.report.figures import FIGURES, figure_svg, mpl_style
from gonio.report.i18n import cjk_font, display, labels
from gonio.formats.toml import Field, read_toml, validate_table

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
    "signatory": Field("table", schema={
        "calibrated_by": _S, "checked_by": _S, "approved_by": Field("str"),
        "approved_title": _S}),
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
    lab = validate_table(raw, LAB_SCHEMA, "", path)
    for key in ("instrument", "environment"):
        if lab[key] is None:
            lab[key] = validate_table({}, LAB_SCHEMA[key].schema, key, path)
    if lab["standards"] is None:
        lab["standards"] = []
    return lab


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

@dataclass(frozen=True)
class Num:
    """A number shown on the certificate: its text, its path in results.json, its rule."""

    text: str
    src: str
    rule: str


@dataclass
class Block:
    """One piece of content: kind is h, p, kv, table, fig, notice."""

    kind: str
    data: Any
    extra: Any = None


def _num(results: dict, src: str, rule: str, U: float | None) -> Num | str:
    v: Any = results
    for part in src.split("."):
        v = v[int(part)] if isinstance(v, list) else v[part]
    if v is None:
        return "—"
    return Num(display(rule, v, U), src, rule)


def _meta(md: dict, key: str, L) -> str:
    v = md.get(key)
    return str(v) if v not in (None, "") else L["not_stated"]


#: Longest table printed on the certificate; the rest is in tables/*.csv and results.json.
MAX_TABLE_ROWS: int = 200


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


def certificate_blocks(report, L: dict, *, lab: dict | None, truth: dict | None) -> dict:
    """The certificate's content: header fields and the list of blocks, in order.

    Returns a dict with ``id``, ``virtual`` (bool), ``lab_name`` and ``blocks``.
    """
    res = clean_tree(report.to_dict())          # user text shown literally (report/text.py)
    lab = clean_tree(lab) if lab else lab
    md = res.get("metadata", {})
    unc = res["uncertainty"]
    U = float(unc["U_arcsec"])
    virtual = lab is None
    lab_ = lab or {}
    blocks: list[Block] = []
    add = lambda kind, data, extra=None: blocks.append(  # noqa: E731
        Block(kind, _summarised(kind, data), extra))

    # a, b, c: title, laboratory, place; d: identifier (header of every page)
    if virtual:
        add("notice", L["virtual_note"])
        lab_rows = [(L["laboratory"], "gonio virtual bench"), (L["address"], "—")]
    else:
        la = lab_["laboratory"]
        lab_rows = [(L["laboratory"], la["name"]), (L["address"], la["address"])]
        if la["accreditation"]:
            lab_rows.append((L["accreditation"], la["accreditation"]))
        if la["contact"]:
            lab_rows.append((L["contact"], la["contact"]))
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
        (L["model"], inst.get("model") or _meta(md, "model", L)),
        (L["serial"], inst.get("serial") or _meta(md, "serial", L)),
        (L["manufacturer"], inst.get("manufacturer") or _meta(md, "manufacturer", L)),
        (L["date_receipt"], cert.get("date_of_receipt") or ns),
        (L["date_calibration"], cert.get("date_of_calibration") or _meta(md, "date", L)),
        (L["date_issue"], cert.get("date_of_issue") or ns),
        (L["place"], cert.get("place") or ("virtual bench" if virtual else ns)),
        (L["specification"], res.get("specification") or ns),
        (L["source_file"], f"{res['source']['file']} (SHA-256 {res['source']['sha256'][:16]}…, "
                           f"{res['source']['rows']} rows)"),
    ]
    add("kv", rows)

    # standards and traceability
    add("h", L["standards"])
    std_rows = []
    for s in lab_.get("standards") or []:
        std_rows.append([s["name"], s["identifier"] or "—", s["accuracy"] or "—",
                         s["certificate"] or "—", s["traceability"] or "—"])
    if not std_rows:
        mpe = md.get("table_mpe_arcsec")
        std_rows.append([_meta(md, "table", L), "—",
                         f"MPE ±{mpe}″" if mpe else ns, "—",
                         "none (virtual bench)" if virtual else ns])
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

    # results: Annex B
    add("h", L["results"])
    rrows = []
    for i, name in enumerate(("scale_factor", "scale_factor_nonlinearity", "zero_stability",
                              "angle_deviation", "repeatability", "rate_consistency",
                              "pointing_consistency"), 1):
        item = res[name]
        unit = L.get("u_" + item["unit"], item["unit"])
        if not item["measured"]:
            rrows.append([str(i), L[name], item["clause"], f"{L['not_measured']}: {item['reason']}",
                          ""])
            continue
        cell: list = [_num(res, f"{name}.value", f"item:{name}", U)]
        if name == "zero_stability" and item.get("range_deg_per_h") is not None:
            cell += ["; ", _seg(L["note_zero_range"], v=_num(res, f"{name}.range_deg_per_h",
                                                             "sig3", U))]
        elif name in ("angle_deviation", "repeatability") and item.get("position_deg") is not None:
            cell += [" (", _seg(L["note_at"], p=_num(res, f"{name}.position_deg", "pos", U)), ")"]
        elif name in ("rate_consistency", "pointing_consistency"):
            cell += ["; ", _seg(L["note_spread"], v=_num(res, f"{name}.spread_arcsec", "atU", U))]
        rrows.append([str(i), L[name], item["clause"], cell, unit])
    add("table", ([L["no"], L["item"], L["clause"], L["result"], L["unit"]], rrows),
        {"widths": (0.06, 0.33, 0.10, 0.41, 0.10), "id": "results"})
    add("p", _seg(L["U_line"], U=_num(res, "uncertainty.U_arcsec", "U", U),
                  k=_num(res, "uncertainty.k", "pos", U)), "U")
    add("p", _seg(L["u_c_line"], u=_num(res, "uncertainty.u_c_arcsec", "U", U)))

    # budget
    add("h", L["budget"])
    brows = []
    for j, c in enumerate(unc["components"]):
        brows.append([f"u({c['symbol'].replace('phi_e', 'φ_e')})", c["source"], c["type"],
                      _num(res, f"uncertainty.components.{j}.u_arcsec", "U", U),
                      _num(res, f"uncertainty.components.{j}.contribution_arcsec", "U", U)])
    add("table", ([L["component"], L["source"], L["type"], L["u_i"], "|c_i|·u_i (″)"], brows),
        (0.14, 0.50, 0.08, 0.14, 0.14))

    # readings taken
    add("h", L["readings_taken"])
    for note in res.get("readings_taken", []):
        add("p", ["• " + note])

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
            "lab_name": (lab_["laboratory"]["name"] if lab else "gonio virtual bench"),
            "blocks": blocks, "results": res}


def _eda_section(res: dict, L: dict, U: float, add) -> None:
    """The table-calibration page: table and goniometer errors with their uncertainties."""
    e = res["equal_division"]
    add("h", L["eda"])
    add("p", [L["eda_note"].format(n=e["n_starts"], m=e["m_points"], r=e["repeats"],
                                   noise=e["noise"])])
    rows = []
    for i in range(e["m_points"]):
        rows.append([_num(res, f"equal_division.table.position_deg.{i}", "pos", U),
                     _num(res, f"equal_division.table.error_arcsec.{i}", "sig3", U),
                     _num(res, f"equal_division.table.u_arcsec.{i}", "U", U),
                     _num(res, f"equal_division.goniometer.angle_deg.{i}", "pos", U),
                     _num(res, f"equal_division.goniometer.error_arcsec.{i}", "sig3", U),
                     _num(res, f"equal_division.goniometer.u_arcsec.{i}", "U", U)])
    add("table", ([L["eda_position"], L["eda_table"], "u (″)", L["eda_turned"], L["eda_gonio"],
                   "u (″)"], rows), (0.18, 0.17, 0.15, 0.18, 0.17, 0.15))
    add("p", _seg(L["eda_closure"],
                  v=_num(res, "equal_division.closure.full_turn_arcsec", "sig3", U),
                  u=_num(res, "equal_division.closure.u_full_turn_arcsec", "U", U)))


def _seg(template: str, **nums) -> list:
    """Split a label template "... {x} ..." into text and Num segments."""
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


def _detail_tables(res: dict, L: dict, U: float, add) -> None:
    sf = res["scale_factor"]
    if sf["measured"]:
        rows = [[_num(res, f"scale_factor.table.{i}.round", "int", U),
                 _num(res, f"scale_factor.table.{i}.table_deg", "pos", U),
                 _num(res, f"scale_factor.table.{i}.gyro_counts", "int", U),
                 _num(res, f"scale_factor.table.{i}.K_i_counts_per_deg", "sig8", U)]
                for i in range(len(sf["table"]))]
        add("p", [L["scale_factor"] + " (7.1)"])
        add("table", (["round", "θ_i (°)", "C_i", "K_i (counts/°)"], rows),
            (0.15, 0.25, 0.30, 0.30))
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
        add("p", [L["angle_deviation"] + " / " + L["repeatability"] + " (7.4, 7.5)"])
        add("table", (["position (°)", "E_i (″)", "R_i (″)", "n"], rows),
            (0.25, 0.25, 0.25, 0.25))
    for name, col, fmt in (("rate_consistency", "rate_dps", "pos"),
                           ("pointing_consistency", "orientation", None)):
        c = res[name]
        if not c["measured"]:
            continue
        rows = []
        for i, r in enumerate(c["table"]):
            cond = (_num(res, f"{name}.table.{i}.{col}", fmt, U) if fmt
                    else L.get(str(r[col]), str(r[col])))
            rows.append([cond, L["lg_reference"] if r.get("reference") else "",
                         _num(res, f"{name}.table.{i}.E_arcsec", "atU", U),
                         _num(res, f"{name}.table.{i}.max_abs_arcsec", "atU", U)])
        add("p", [L[name] + f" ({c['clause']})"])
        head = "rate (°/s)" if col == "rate_dps" else "axis"
        add("table", ([head, "", "E (″)", "max |E_i| (″)"], rows), (0.25, 0.25, 0.25, 0.25))


# --------------------------------------------------------------------------- HTML

_CSS = """
body{font-family:%(font)s;max-width:1040px;margin:0 auto;padding:16px 24px;color:#111;font-size:14px}
header.page{display:flex;justify-content:space-between;border-bottom:2px solid #333;padding:4px 0;margin-bottom:8px}
h1{text-align:center;font-size:24px;margin:10px 0 4px}
h2{font-size:16px;border-bottom:1px solid #999;margin:18px 0 6px;padding-bottom:2px}
table{border-collapse:collapse;width:100%%;margin:4px 0 8px}
td,th{border:1px solid #888;padding:3px 6px;text-align:left;vertical-align:top}
th{background:#eee}
table.kv td:first-child{width:32%%;background:#f6f6f6}
.banner{background:#b00020;color:#fff;font-weight:bold;text-align:center;padding:8px;font-size:18px;letter-spacing:1px;margin:6px 0}
.watermark{position:fixed;top:45%%;left:0;width:100%%;text-align:center;transform:rotate(-30deg);font-size:64px;font-weight:bold;color:rgba(176,0,32,0.10);pointer-events:none;z-index:10}
.notice{border:2px solid #b00020;padding:6px;color:#b00020}
figure{margin:10px 0;page-break-inside:avoid}
figure svg{width:100%%;height:auto}
figcaption{font-size:13px;color:#333;text-align:center}
.u{font-weight:bold;font-size:15px}
footer{border-top:1px solid #333;margin-top:16px;font-size:12px;color:#333}
@page{size:A4;margin:18mm 14mm;@bottom-right{content:"%(pageword)s"}}
"""


def _h(x) -> str:
    if isinstance(x, Num):
        return (f'<span class="num" data-src="{html.escape(x.src)}" '
                f'data-rule="{html.escape(x.rule)}">{html.escape(x.text)}</span>')
    if isinstance(x, list):
        return "".join(_h(s) for s in x)
    return html.escape(str(x))


def render_html(content: dict, svgs: dict[str, str], L: dict, lang: str, font: str | None) -> str:
    """The certificate as one self-contained HTML page (no external resources)."""
    cid = content["id"]
    ff = (f"'{font}', " if font else "") + "'DejaVu Sans', Arial, sans-serif"
    pageword = L["page_of"].replace("{x}", '" counter(page) "').replace("{y}", '" counter(pages) "')
    css = _CSS % {"font": ff, "pageword": pageword}
    out = ["<!DOCTYPE html>", f'<html lang="{"zh-CN" if lang == "zh" else "en"}">', "<head>",
           '<meta charset="utf-8">', f"<title>{html.escape(L['title'])} {html.escape(cid)}</title>",
           f"<style>{css}</style>", "</head>", "<body>"]
    if content["virtual"]:
        out.append(f'<div class="watermark" aria-hidden="true">{html.escape(L["virtual_short"])}</div>')
        out.append(f'<div class="banner" id="virtual-banner">{html.escape(L["virtual"])}</div>')
    out.append(f'<header class="page"><span>{html.escape(content["lab_name"])}</span>'
               f'<span id="cert-id">{html.escape(L["certificate_no"])}: {html.escape(cid)}</span>'
               f'<span id="page-of">{html.escape(L["page_of"].format(x=1, y=1))}</span></header>')
    out.append(f"<h1>{html.escape(L['title'])}</h1>")
    for b in content["blocks"]:
        if b.kind == "h":
            out.append(f"<h2>{html.escape(b.data)}</h2>")
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
            out.append(f"<table{tid}><tr>" + "".join(f"<th>{_h(c)}</th>" for c in head) + "</tr>"
                       + "".join("<tr>" + "".join(f"<td>{_h(c)}</td>" for c in r) + "</tr>"
                                 for r in rows) + "</table>")
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
_FIG_H = 0.30                        # a figure's height, fraction of the page


def _width(s: str) -> int:
    return sum(2 if unicodedata.east_asian_width(ch) in "WF" else 1 for ch in s)


def _wrap(text: str, width: int) -> list[str]:
    """Wrap ``text`` to ``width`` columns (CJK characters count two; breaks at spaces or CJK)."""
    lines: list[str] = []
    for para in str(text).split("\n"):
        line, w = "", 0
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
        for tok in tokens:
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


class _Layout:
    """Places blocks on A4 pages; each page is a list of (y_top, height, op)."""

    def __init__(self, fontsize: float):
        self.fs = fontsize
        self.line = fontsize * 1.45 * _PT
        self.pages: list[list] = [[]]
        self.y = _TOP

    def need(self, h: float) -> None:
        if self.y - h < _BOTTOM and self.pages[-1]:
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


def _layout(content: dict, L: dict) -> list[list]:
    lay = _Layout(8.5)
    fs, ln = lay.fs, lay.line
    title_h = 30 * _PT

    def title(fig, y):
        fig.text(0.5, y - 20 * _PT, L["title"], ha="center", va="baseline", fontsize=18,
                 weight="bold")
    lay.put(title_h, title)
    for b in content["blocks"]:
        if b.kind == "h":
            def op(fig, y, t=b.data):
                fig.text(_LEFT, y - 13 * _PT, t, fontsize=10.5, weight="bold", va="baseline")
                fig.add_artist(_hline(fig, y - 16 * _PT, 0.6))
            lay.need(22 * _PT + 3 * ln)            # keep a heading with what follows
            lay.put(22 * _PT, op)
        elif b.kind in ("p", "notice"):
            txt = _text(b.data)
            big = b.extra == "U"
            lines = _wrap(txt, lay.cols(1.0) - (8 if big else 0))
            size = 10 if big else fs
            color = "#b00020" if b.kind == "notice" else "black"
            for i, line in enumerate(lines):
                def op(fig, y, t=line, s=size, c=color, w="bold" if big else "normal"):
                    fig.text(_LEFT, y - ln * 0.8, t, fontsize=s, va="baseline", color=c, weight=w)
                lay.put(ln * (1.15 if big else 1.0), op)
            lay.y -= 3 * _PT
        elif b.kind == "kv":
            for k, v in b.data:
                vl = _wrap(_text(v), lay.cols(0.66))
                h = ln * len(vl)

                def op(fig, y, k=_text(k), vl=vl):
                    fig.text(_LEFT, y - ln * 0.8, k, fontsize=fs, va="baseline", color="0.25")
                    for i, t in enumerate(vl):
                        fig.text(_LEFT + 0.32 * (_RIGHT - _LEFT), y - ln * (0.8 + i), t,
                                 fontsize=fs, va="baseline")
                lay.put(h, op)
            lay.y -= 4 * _PT
        elif b.kind == "table":
            head, rows = b.data
            widths = b.extra["widths"] if isinstance(b.extra, dict) else b.extra
            xs = [_LEFT]
            for w in widths[:-1]:
                xs.append(xs[-1] + w * (_RIGHT - _LEFT))

            def row_op(cells, bold=False, shade=False, xs=tuple(xs), widths=tuple(widths)):
                wrapped = [_wrap(_text(c), lay.cols(w) - 1) for c, w in zip(cells, widths)]
                n = max(len(w) for w in wrapped)

                def op(fig, y, wrapped=wrapped, n=n, xs=xs):
                    if shade:
                        fig.add_artist(_rect(fig, y, ln * n + 2 * _PT))
                    for x, ls in zip(xs, wrapped):
                        for i, t in enumerate(ls):
                            fig.text(x + 0.004, y - ln * (0.8 + i), t, fontsize=fs - 0.5,
                                     va="baseline", weight="bold" if bold else "normal")
                    fig.add_artist(_hline(fig, y - ln * n - 2 * _PT, 0.3))
                return ln * n + 2 * _PT, op
            h, op = row_op(head, bold=True, shade=True)
            lay.need(h + ln * 2)
            lay.put(h, op)
            for r in rows:
                h2, op2 = row_op(r)
                if lay.y - h2 < _BOTTOM:           # repeat the head on the next page
                    lay.need(h2 + h)
                    lay.put(h, row_op(head, bold=True, shade=True)[1])
                lay.put(h2, op2)
            lay.y -= 6 * _PT
        elif b.kind == "fig":
            key, cap, draw = b.data
            cap_lines = _wrap(cap, lay.cols(1.0))
            h = _FIG_H + ln * len(cap_lines) + 6 * _PT

            def op(fig, y, draw=draw, cap_lines=cap_lines):
                gs = fig.add_gridspec(1, 1, left=_LEFT + 0.06, right=_RIGHT - 0.01,
                                      top=y - 0.01, bottom=y - _FIG_H + 0.035)
                draw(fig, gs[0], content["_report"], L, content["_truth"])
                for i, t in enumerate(cap_lines):
                    fig.text(0.5, y - _FIG_H - ln * (0.8 + i), t, ha="center", fontsize=fs,
                             va="baseline")
            lay.put(h, op)
    return lay.pages


def _hline(fig, y, lw):
    from matplotlib.lines import Line2D
    return Line2D([_LEFT, _RIGHT], [y, y], transform=fig.transFigure, color="0.3", lw=lw)


def _rect(fig, y, h):
    from matplotlib.patches import Rectangle
    return Rectangle((_LEFT, y - h), _RIGHT - _LEFT, h, transform=fig.transFigure,
                     color="0.92", zorder=-1)


def render_pdf(content: dict, L: dict, fonts: tuple[str, ...] = ("DejaVu Sans",)) -> bytes:
    """The certificate as A4 PDF pages; each page has the identifier and "page x of y"."""
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_pdf import PdfPages

    buf = io.BytesIO()
    with mpl_style(fonts):
        pages = _layout(content, L)
        n = len(pages)
        with PdfPages(buf, metadata={"CreationDate": None, "ModDate": None,
                                     "Creator": "gonio", "Title": f"{L['title']} {content['id']}"}
                      ) as pdf:
            for p, ops in enumerate(pages, 1):
                fig = plt.figure(figsize=A4_IN)
                try:
                    _page_frame(fig, content, L, p, n)
                    for y, op in ops:
                        op(fig, y)
                    pdf.savefig(fig)
                finally:
                    plt.close(fig)
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
                      lab: str | Path | dict | None = None, lang: str = "en") -> dict[str, Path]:
    """Write ``certificate.html`` and ``certificate.pdf`` for ``report`` into ``out``.

    Parameters
    ----------
    report : gonio.pipeline.calibrate.CalibrationReport
        What :func:`gonio.pipeline.calibrate.calibrate` returned (``results.json`` is written
        by :func:`gonio.pipeline.calibrate.write_calibration`, not here).
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

    Returns
    -------
    dict of str to Path
        ``{"certificate.html": ..., "certificate.pdf": ...}``.
    """
    L = labels(lang)
    fonts = font_families(lang)
    font = fonts[0] if lang == "zh" else None
    lab_d = load_lab(lab) if isinstance(lab, (str, Path)) else lab
    content = certificate_blocks(report, L, lab=lab_d, truth=truth)
    content["_report"], content["_truth"] = report, truth
    svgs = {key: figure_svg(draw, report, L, truth, fonts) for key, _, draw in FIGURES}
    out = Path(out)
    with output_dir(out) as stage:
        write_text(stage / "certificate.html", render_html(content, svgs, L, lang, font))
        write_bytes(stage / "certificate.pdf", render_pdf(content, L, fonts))
    return {"certificate.html": out / "certificate.html", "certificate.pdf": out / "certificate.pdf"}
