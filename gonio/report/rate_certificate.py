"""The certificate of a rate-gyro calibration (JJF 1535 Annex B content; IEC 62047-20 items),
rendered by the optical certificate's machinery (:mod:`gonio.report.certificate`: the same
blocks, HTML and PDF renderers, lab file, identifier, virtual-bench banner, zh/en).

The specification supplies its content as data (``gonio/specs/<name>/certificate.py``:
``GROUPS``, ``TITLES_ZH``, ``HEADING``); this module turns the results into blocks:
header (clause 8 a–j), the grouped results with U (k) beside each item that has a
budget (clause 8 k), each item's budget, the readings taken, signatures and statements,
and the figures of :mod:`gonio.report.rate_figures`.
"""

from __future__ import annotations

import math
from pathlib import Path

from gonio.atomic import output_dir, write_bytes, write_text
from gonio.report.certificate import (Block, Num, certificate_id, font_families, load_lab,
                                      render_html, render_pdf)
from gonio.report.figures import figure_svg
from gonio.report.i18n import display, labels
from gonio.report.rate_content import rate_standards, spec_content
from gonio.report.rate_figures import FIGURES
from gonio.specs import get


def _num(value, src: str, rule: str, U=None):
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "—"
    return Num(display(rule, value, U), src, rule)


def rate_certificate_blocks(result, L: dict, lang: str, *, lab: dict | None) -> dict:
    """The certificate's content: identifier, banner flag, lab name and blocks."""
    res = result.to_json()
    md = res.get("metadata", {})
    data = spec_content(result.spec_key)
    spec = get(result.spec_key)
    virtual = lab is None
    lab_ = lab or {}
    blocks: list[Block] = []
    add = lambda kind, d, extra=None: blocks.append(Block(kind, d, extra))  # noqa: E731
    ns = L["not_stated"]
    if virtual:
        add("notice", L["virtual_note"])
        add("kv", [(L["laboratory"], "gonio virtual bench"), (L["address"], "—")])
    else:
        la = lab_["laboratory"]
        add("kv", [(L["laboratory"], la["name"]), (L["address"], la["address"])])
    cert = lab_.get("certificate", {})
    cust = lab_.get("customer", {"name": ns, "address": ""})
    inst = lab_.get("instrument", {})
    add("kv", [
        (L["customer"], cust.get("name") or ns),
        (L["description"], inst.get("description") or md.get("instrument") or ns),
        (L["model"], inst.get("model") or md.get("model") or ns),
        (L["serial"], inst.get("serial") or md.get("serial") or ns),
        (L["manufacturer"], inst.get("manufacturer") or md.get("manufacturer") or ns),
        (L["date_calibration"], cert.get("date_of_calibration") or md.get("date") or ns),
        (L["place"], cert.get("place") or ("virtual bench" if virtual else ns)),
        (L["specification"], spec.title_zh if lang == "zh" else spec.title_en),
        (L["source_file"], f"{res['source']['file']} (SHA-256 {res['source']['sha256'][:16]}…, "
                           f"{res['source']['rows']} rows)"),
    ])
    add("h", L["standards"])
    std_rows = [[s["name"], s["identifier"] or "—", s["accuracy"] or "—", s["certificate"] or "—",
                 s["traceability"] or "—"] for s in rate_standards(md, lab, ns)]
    add("table", ([L["std_name"], L["std_id"], L["std_spec"], L["std_cert"], L["std_trace"]],
                  std_rows), (0.30, 0.13, 0.17, 0.15, 0.25))
    add("h", L["environment"])
    env = lab_.get("environment") or {}
    t = env.get("temperature_c")
    add("kv", [(L["temperature"], f"{t:g} °C" if t is not None else
                f"{md.get('room_temperature_c', ns)} °C")])
    # results, grouped (Annex B)
    add("h", data.HEADING[1] if lang == "zh" else data.HEADING[0])
    rows = []
    for num, en, zh, keys in data.GROUPS:
        rows.append([str(num), zh if lang == "zh" else en, "", "", "", ""])
        for key in keys:
            it = res["items"].get(key)
            if it is None:
                continue
            name = data.TITLES_ZH.get(key, it["title"]) if lang == "zh" else it["title"]
            if not it["measured"]:
                rows.append(["", name, it["clause"], f"{L['not_measured']}: {it['reason']}", "", ""])
                continue
            unc = it.get("uncertainty") or {}
            U = unc.get("U")
            rows.append(["", name, it["clause"], _num(it["value"], f"items.{key}.value", "sig4"),
                         _num(U, f"items.{key}.uncertainty.U", "U") if U else "—",
                         it["unit"]])
    add("table", ([L["no"], L["item"], L["clause"], L["result"], "U (k)", L["unit"]], rows),
        {"widths": (0.06, 0.34, 0.09, 0.22, 0.14, 0.15), "id": "results"})
    add("p", ["U: expanded uncertainty, k = t95(ν_eff) (shown per item in the budgets below); "
              "JJF 1535 clause 8 k)."])
    # budgets
    add("h", L["budget"])
    brows = []
    for key, it in res["items"].items():
        unc = it.get("uncertainty")
        if not it["measured"] or not unc:
            continue
        for j, c in enumerate(unc["components"]):
            if not c.get("u"):
                continue
            brows.append([it["clause"], c["symbol"], c["source"] or "—",
                          _num(c["u"], f"items.{key}.uncertainty.components.{j}.u", "sig3"),
                          _num(c["contribution"],
                               f"items.{key}.uncertainty.components.{j}.contribution", "sig3")])
        brows.append([it["clause"], "u_c / k", "", _num(unc["u_c"], f"items.{key}.uncertainty.u_c",
                                                        "sig3"),
                      _num(unc["k"], f"items.{key}.uncertainty.k", "sig3")])
    add("table", ([L["clause"], L["component"], L["source"], L["u_i"], "|c_i|·u_i"], brows),
        (0.09, 0.12, 0.49, 0.15, 0.15))
    add("h", L["readings_taken"])
    for note in res.get("readings_taken", []):
        add("p", ["• " + note])
    add("h", L["signatory"])
    sig = lab_.get("signatory", {})
    add("kv", [(L["calibrated_by"], sig.get("calibrated_by") or "—"),
               (L["checked_by"], sig.get("checked_by") or "—"),
               (L["approved_by"], sig.get("approved_by") or "—")])
    add("p", [L["statement_item"]])
    add("p", [L["statement_copy"]])
    add("p", [L["statement_recal"]])
    add("h", L["figures"])
    for key, cap_en, cap_zh, draw in FIGURES:
        add("fig", (key, cap_zh if lang == "zh" else cap_en, draw))
    return {"id": certificate_id(result, lab), "virtual": virtual,
            "lab_name": lab_["laboratory"]["name"] if lab else "gonio virtual bench",
            "blocks": blocks, "results": res}


def write_rate_certificate(result, out, *, truth=None, lab=None, lang: str = "en",
                           dcc: bool = False) -> dict:
    """``certificate.html`` and ``certificate.pdf`` of a rate-gyro calibration (and with
    ``dcc`` the PTB DCC 3.3.0 XML ``certificate.dcc.xml``, :mod:`gonio.report.rate_dcc`,
    always in English), written together atomically."""
    L = labels(lang)
    fonts = font_families(lang)
    font = fonts[0] if lang == "zh" else None
    lab_d = load_lab(lab) if isinstance(lab, (str, Path)) else lab
    content = rate_certificate_blocks(result, L, lang, lab=lab_d)
    content["_report"], content["_truth"] = result, truth
    svgs = {key: figure_svg(draw, result, L, truth, fonts) for key, _, _, draw in FIGURES}
    out = Path(out)
    with output_dir(out) as stage:
        write_text(stage / "certificate.html", render_html(content, svgs, L, lang, font))
        write_bytes(stage / "certificate.pdf", render_pdf(content, L, fonts))
        if dcc:
            from gonio.report.rate_dcc import rate_dcc_bytes

            write_bytes(stage / "certificate.dcc.xml",
                        rate_dcc_bytes(result, lab=lab_d, cert_id=content["id"]))
    names = ["certificate.html", "certificate.pdf"] + (["certificate.dcc.xml"] if dcc else [])
    return {n: out / n for n in names}
