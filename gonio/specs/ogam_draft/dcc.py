"""The optical draft's Digital Calibration Certificate: PTB DCC 3.3.0 XML from a
calibration's results.json, built on the shared parts of :mod:`gonio.report.dcc`.

Contents
========
=========================  ==============================================================
:func:`method_text`        the method statement on one line (the DCC's method description)
:func:`dcc_tree`           the DCC document as an lxml element tree
:func:`dcc_bytes`          the same as UTF-8 bytes (deterministic)
:func:`write_dcc`          ``certificate.dcc.xml`` into a folder, atomically
=========================  ==============================================================

Besides what every DCC holds (:mod:`gonio.report.dcc`), E is stated as ± max|E_i| with the
signed extreme and its position, B_s and R by their χ² interval with the ν it was computed
with (:func:`~gonio.kit.render.nu_quantity`), and each item's per-point table as dcc:list
columns. Every
number is the one the printed certificate shows (:mod:`gonio.specs.ogam_draft.stated`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from gonio.atomic import write_bytes
from gonio.kit.render import (DCC_CONFORMITY, Num, administrative_data, below_zero_quantity,
                              conformity_texts, declaration_parts, display, element,
                              environment_conditions, influence_conditions, interval_quantity,
                              labels, list_quantity,
                              measurement_result, new_document,
                              not_measured_quantity, nu_quantity, num, probability_quantities,
                              quantity, text_element, tree_bytes, unit_dsi)
from gonio.specs.ogam_draft.phrases import LABELS
from gonio.specs.ogam_draft.stated import (band_note, combined_k_note, conformity_for, e_budget,
                                           e_u_c_certified,
                                           e_interval_segments, followed,
                                           item_names, item_path, item_uncertainty, k_table_note,
                                           e_table_note, k_tilt_note,
                                           method_rows, reading_note, specification_text,
                                           stated_item, range_table_note)


def method_text(res: dict, lab: dict | None, lang: str = "en") -> str:
    """The method statement (:func:`gonio.specs.ogam_draft.stated.method_rows`) of results.json ``res``
    on one line, as the optical DCC's method description (``lang`` "zh": its Chinese,
    written beside it)."""
    rows = method_rows(res, labels(lang, LABELS), lab, lang)
    if lang == "zh":
        return "；".join(f"{k}：{v}" for k, v in rows)
    return "; ".join(f"{k}: {v}" for k, v in rows)


def dcc_tree(res: dict, *, lab: dict | None = None, cert_id: str) -> Any:
    """The DCC 3.3.0 document of one calibration's results.json ``res`` (see the module
    docstring for its content)."""
    L = labels("en", LABELS)
    md = res.get("metadata", {})
    lab_ = lab or {}
    root = new_document()
    norm = specification_text(followed(res) or "not stated", "en")
    sts = administrative_data(
        root, md, lab, cert_id=cert_id, norm=norm, provenance=res.get("provenance"), findings=res.get("findings"),
        clauses=[res["items"][n]["clause"] for n in item_names(res)
                 if res["items"][n]["measured"]],
        readings_taken=[reading_note(n, "en") for n in res.get("readings_taken", [])],
        readings_name=L["readings_taken"])
    conf = conformity_for(res, lab)
    if conf:
        rule = conf[0]["rule"]
        st = element(sts, "dcc:statement", id="decision-rule")
        text_element(st, "dcc:name", "Decision rule")
        element(st, "dcc:norm", "ILAC-G8:09/2019")
        element(st, "dcc:norm", "JCGM 106:2012")
        agreed = (lab_.get("decision_rule") or {}).get("agreed")
        text_element(st, "dcc:declaration", L[f"rule_{rule.kind}"].format(
            r=display("k", rule.guard_factor)) + (f" Agreed: {agreed}." if agreed else ""))
        band = band_note(res, conf, L)
        if band:        # the U of w = r·U of each item decided on its interval, as printed
            st = element(sts, "dcc:statement", id="guard-band-interval-items")
            text_element(st, "dcc:name", "Guard band of the items stated by an interval")
            text_element(st, "dcc:declaration", band)
        for e in conf:
            c = e["conformity"]
            st = element(sts, "dcc:statement", id=f"conformity-{e['item']}",
                    refId=f"result-{e['item']}")
            text_element(st, "dcc:name", f"Statement of conformity: {L[e['item']]}")
            if c is None:
                text_element(st, "dcc:declaration", L[e["reason"]])
                continue
            t = conformity_texts(c, res, L)
            acc, pfa = declaration_parts(c, t)
            text_element(st, "dcc:declaration",
                  f"{t['outcome']}; limits {t['limits']}; {acc}; "
                  f"specific false-accept probability {pfa}"
                  + (f"; {t['pfr']}" if t["pfr"] else "") + f"; limits from: {c.source or '—'}"
                  + (f"; {t['measured']}" if t["measured"] else ""))
            element(st, "dcc:conformity", DCC_CONFORMITY[c.outcome])
            data = element(st, "dcc:data")
            unit = res["items"][e["item"]]["unit"]
            if c.decided_on_measured:
                quantity(data, "measured value before rounding (decided the outcome)",
                         c.decided_on_measured, unit)
            for nm, v in (("lower specification limit", c.lower),
                          ("upper specification limit", c.upper)):
                if v is not None:
                    quantity(data, nm, display(_limit_rule(c), v), unit)
            probability_quantities(data, c.conformance_probability,   # none: no model
                                   c.false_accept_probability, c.false_reject_probability)

    stds = lab_.get("standards") or [{"name": str(md.get("table") or "rotary table"),
                                      "identifier": "", "accuracy": (
                                          f"MPE ±{md['table_mpe_arcsec']}″"
                                          if md.get("table_mpe_arcsec") else ""),
                                      "certificate": "", "traceability": ""}]
    mr = measurement_result(
        root, "Calibration of an optical-gyroscope angle measuring instrument",
        method=method_text(res, lab, "en"),
        norm=norm, standards=stds)
    conds = environment_conditions(md, lab, spec=res.get("spec"))
    influence_conditions(mr, conds)

    results = element(mr, "dcc:results")
    for name in item_names(res):
        item = res["items"][name]
        r = element(results, "dcc:result", id=f"result-{name}")
        text_element(r, "dcc:name", f"{L[name]} ({item['clause']})")
        data = element(r, "dcc:data")
        s = stated_item(res, name)
        if not s["measured"]:
            not_measured_quantity(data, L[name], item["reason"])
            continue
        unc = item_uncertainty(res, name)
        kw = {}
        if unc and s["U"] is not None and s["k"] is not None and unc["p"] is not None:
            kw = {"U": s["U"], "k": s["k"], "p": float(unc["p"])}
        elif unc and s["interval"] is not None and s["interval"]["interval"]["u"] \
                and unc["p"] is not None:          # stated by its coverage interval alone
            kw = {"interval": s["interval"]["interval"]["ends"],
                  "u_std": s["interval"]["interval"]["u"], "p": float(unc["p"])}
        ends = None             # E's interval where no u of E is certified (U = k·u + b)
        if name == "angle_deviation" and "interval" in kw \
                and not e_u_c_certified(e_budget(res)):
            ends, kw = kw["interval"], {}
        if name == "angle_deviation" and s["signed"] is not None:
            quantity(data, "E = ± max|E_i| (draft 7.4)", s["value"], item["unit"],
                     description=_e_description(res, L, ends is not None or "interval" in kw),
                     **kw)
            if ends is not None:           # its ends, no si:valueStandardMU
                interval_quantity(data, "E = ± max|E_i| (draft 7.4)", ends,
                                  unit_dsi(item["unit"]), float(unc["p"]), E_BOUND_INTERVAL)
            quantity(data, "signed extreme of E_i", s["signed"], item["unit"])
            if isinstance(s["position"], Num):
                quantity(data, "position of the extreme", s["position"], "deg")
        elif s["below_zero"]:     # its interval [0, bound] alone, no si:value, and why
            note = (LABELS["below_zero"]["en"], _range_table_text(res, name, L))
            below_zero_quantity(data, L[name], s["interval"]["statement"].interval_ends,
                                unit_dsi(item["unit"]), float(unc["p"]),
                                description="; ".join(d for d in note if d))
        else:
            desc = ([_k_tilt_text(res, L), _k_table_text(res, L)] if name == "scale_factor"
                    else [_range_table_text(res, name, L)])
            if "k" in kw:   # a k of the item's combined distribution (JCGM 101): say so
                desc.append(combined_k_note(res, L, only=name))
            quantity(data, L[name], s["value"], item["unit"],
                     description="; ".join(d for d in desc if d) or None, **kw)
        _beside(data, res, name, s, L)
    return root


def _beside(data, res: dict, name: str, s: dict, L: dict) -> None:
    """What follows item ``name``'s quantity (``s``: its :func:`stated_item`): the ν of its χ²
    interval (B_s, R), as the certificate prints it beside that interval
    (:func:`~gonio.kit.render.nu_quantity`: none for an item stated otherwise), then its
    per-point lists (:func:`_detail_lists`)."""
    nu_quantity(data, L[name], (s["interval"] or {}).get("chi2_nu"))
    _detail_lists(data, res, name)


#: What E's interval is where each point's U carries the table's bound (its DCC quantity's
#: name; :func:`gonio.report.dcc.interval_quantity`)
E_BOUND_INTERVAL = ("the coverage interval of the largest true |E_i|, each point's reach "
                    "k·u + b: u of the lines other than the table's, b the table's bound at "
                    "the point; no standard uncertainty of E is certified")


#: What the interval of a non-negative item whose bias-corrected estimate fell below zero is
#: (its DCC quantity's name; the certificate states the item by its upper bound alone)


#: The DCC's own words around the certificate's K and E notes, in Chinese (a zh DCC writes
#: these descriptions in both languages: :func:`description_zh`).
_HELD = {"en": "; U(K) carries the correction's uncertainty (budget line K_te: u(ψ), u(α) and "
               "their correlation) in place of the tilt coupling at the A.1 bound (K_tilt)",
         "zh": "；U(K) 含该修正的不确定度（预算分量 K_te：u(ψ)、u(α) 及其相关），"
               "代替 A.1 倾斜上限处的倾斜耦合分量（K_tilt）"}
_SHA = {"en": " (SHA-256 {sha})", "zh": "（校准文件 SHA-256：{sha}）"}
_SEP = {"en": "; ", "zh": "；"}


def _lang(L: dict) -> str:
    return "zh" if L.get("scale_factor") == labels("zh", LABELS)["scale_factor"] else "en"


def _k_tilt_text(res: dict, L: dict) -> str | None:
    """K's description when the in-situ tilt estimate ([tilt_estimate]) corrected it: the
    certificate's note (ψ, α with their U95, the 7.1 mean uncorrected) and how U(K) holds the
    correction (line K_te in place of K_tilt), from results.json, in ``L``'s language; None
    otherwise."""
    if not (res["items"]["scale_factor"].get("details") or {}).get("tilt_correction"):
        return None
    lines = {c.get("symbol") for c in res["items"]["scale_factor"]["uncertainty"].get(
        "components") or []}
    held = _HELD[_lang(L)] if "K_te" in lines else ""
    return "K " + "".join(str(x) for x in k_tilt_note(res, L)) + held


def _k_table_text(res: dict, L: dict) -> str | None:
    """K's description when a calibrated rotary table corrected it: the certificate's note
    (the calibration, u(K) of it, the 7.1 mean uncorrected) and the calibration file's
    SHA-256, from results.json ``details.table_calibration``, in ``L``'s language; None
    otherwise."""
    d = (res["items"]["scale_factor"].get("details") or {}).get("table_calibration")
    if not d:
        return None
    sha = _SHA[_lang(L)].format(sha=d["sha256"]) if d.get("sha256") else ""
    return "K " + "".join(str(x) for x in k_table_note(res, L)) + sha


def _e_table_text(res: dict, L: dict) -> str | None:
    """E's description when a calibrated table corrected it: the certificate's note and the
    calibration file's SHA-256 (results.json ``details.table_calibration``), in ``L``'s
    language; None otherwise."""
    d = (res["items"]["angle_deviation"].get("details") or {}).get("table_calibration")
    if not d:
        return None
    sha = _SHA[_lang(L)].format(sha=d["sha256"]) if d.get("sha256") else ""
    return "E " + "".join(str(x) for x in e_table_note(res, L)) + sha


def _e_description(res: dict, L: dict, by_interval: bool) -> str | None:
    """E's dcc:description in ``L``'s language: the table-calibration note (when a calibrated
    table corrected E) and, when E is stated by the interval of max|E_i| (``by_interval``),
    the certificate's paragraph on it (the draft's max|E_i| ± U beside, not certified) and
    what the interval's si:valueStandardMU is (:data:`~gonio.specs.ogam_draft.phrases.LABELS`
    ``E_dcc_standard_mu``: u_c of E_i at the point where |E_i| is largest, the standard
    uncertainty of max|E_i| by the law of propagation at the estimates, results.json
    ``uncertainty.u_c``)."""
    parts = [_e_table_text(res, L)]
    if by_interval:             # two paragraphs of sentences, one after the other
        parts.append(("" if _lang(L) == "zh" else " ").join((
            "".join(str(x) for x in e_interval_segments(res, L)),
            L["E_dcc_no_standard_mu" if not e_u_c_certified(e_budget(res))
              else "E_dcc_standard_mu_draft" if e_budget(res).get("budget_kind") == "draft"
              else "E_dcc_standard_mu"].format(p=_e_max_position(res)))))
    return _SEP[_lang(L)].join(p for p in parts if p) or None


def _e_max_position(res: dict) -> str:
    """The position (°, as text) of the point where |E_i| is largest, whose u_c is E's stated
    standard uncertainty (results.json ``extra.uncertainty.max_abs_interval``), or "—"."""
    at = ((res.get("extra", {}).get("uncertainty") or {}).get("max_abs_interval")
          or {}).get("position_at_max")
    return "—" if at is None else f"{at:g}"


def _range_table_text(res: dict, name: str, L: dict) -> str | None:
    """K_l's, C_v's or C_g's description when a calibrated table corrected its readings: the
    certificate's note and the calibration file's SHA-256 (results.json
    ``details.table_calibration``); and where the statement rule widened the interval's ends
    for a Monte Carlo not settled, its note (``Statement.widened_note``); in ``L``'s
    language; None where neither applies."""
    parts, note = [], range_table_note(res, name, L)
    if note:
        d = res["items"][name]["details"]["table_calibration"]
        sha = _SHA[_lang(L)].format(sha=d["sha256"]) if d.get("sha256") else ""
        sym = {"scale_factor_nonlinearity": "K_l", "rate_consistency": "C_v",
               "pointing_consistency": "C_g"}[name]
        parts.append(f"{sym} " + "".join(str(x) for x in note) + sha)
    iv = stated_item(res, name).get("interval") if res["items"][name]["measured"] else None
    if iv is not None and iv["statement"].widened is not None:
        parts.append(iv["statement"].widened_note(_lang(L)))
    return _SEP[_lang(L)].join(parts) or None


def description_zh(res: dict, lab: dict | None = None) -> dict[str, str]:
    """The DCC descriptions of K, K_l, C_v and C_g that state a table-calibration (or
    tilt) correction, and E's (:func:`_e_description`), of results.json ``res`` — each as
    :func:`dcc_tree` joins it (with and without the JCGM 101 k note, and after the below-zero
    note) — English → Chinese, for the zh
    DCC's ``dcc:content lang="zh"`` beside the English (:func:`gonio.report.dcc.bilingual`'s
    ``extra``): each written whole in Chinese from the labels' zh, not pieced together."""
    out: dict[str, str] = {}
    L = {"en": labels("en", LABELS), "zh": labels("zh", LABELS)}
    own = {lg: {"scale_factor": [_k_tilt_text(res, L[lg]), _k_table_text(res, L[lg])]}
           for lg in L}
    for name in ("scale_factor_nonlinearity", "rate_consistency", "pointing_consistency"):
        if name in res.get("items", {}):
            for lg in L:
                own[lg][name] = [_range_table_text(res, name, L[lg])]
    for name in own["en"]:
        if not any(own["en"][name]):
            continue
        for lead in (False, True):                 # after the below-zero note
            for with_k in (False, True):           # with the JCGM 101 k note
                parts = {}
                for lg in L:
                    head = [LABELS["below_zero"][lg]] if lead else []
                    tail = [combined_k_note(res, L[lg], only=name)] if with_k else []
                    parts[lg] = [t for t in head + own[lg][name] + tail if t]
                out[_SEP["en"].join(parts["en"])] = _SEP["zh"].join(parts["zh"])
    conf = conformity_for(res, lab) if lab else []
    if conf and band_note(res, conf, L["en"]):
        out[band_note(res, conf, L["en"])] = band_note(res, conf, L["zh"])
    for by_interval in (False, True):              # E's whole description, each form
        e_en = _e_description(res, L["en"], by_interval)
        if e_en:
            out[e_en] = _e_description(res, L["zh"], by_interval)
    return out


def _limit_rule(c) -> str:
    from gonio.kit.render import rule_at_U
    return rule_at_U(c.U, 3)


def _detail_lists(data, res: dict, name: str) -> None:
    """The per-point tables of one item as dcc:list of columns, displayed as the certificate."""
    U = e_budget(res).get("U_arcsec")
    tab = res["items"][name]["details"].get("table") or []
    if not tab:
        return
    cols: list[tuple[str, str, str, str]] = []
    if name == "scale_factor":
        cols = [("round angle θ_i", "table_deg", "pos", "deg"),
                ("K_i", "K_i_counts_per_deg", "sig8", "counts/deg")]
    elif name == "angle_deviation":
        cols = [("position", "position_deg", "pos", "deg"), ("E_i", "E_arcsec", "atU", "arcsec")]
    elif name == "repeatability":
        cols = [("position", "position_deg", "pos", "deg"), ("R_i", "R_arcsec", "atU", "arcsec")]
    elif name == "rate_consistency":
        cols = [("table rate", "rate_dps", "pos", "deg/s"), ("E", "E_arcsec", "atU", "arcsec"),
                ("max |E_i|", "max_abs_arcsec", "atU", "arcsec")]
    elif name == "pointing_consistency":
        cols = [("E", "E_arcsec", "atU", "arcsec"),
                ("max |E_i|", "max_abs_arcsec", "atU", "arcsec")]
    elif name == "zero_stability":
        cols = [("B_s per series", "B_s_deg_per_h", "sig3", "deg/h"),
                ("linear drift per series", "drift_deg_per_h", "sig3", "deg/h")]
    if not cols:
        return
    lst = element(data, "dcc:list")
    text_element(lst, "dcc:name", "per-point table")
    if name == "pointing_consistency":
        lq = element(lst, "dcc:quantity")
        text_element(lq, "dcc:name", "axis direction")
        element(lq, "dcc:charsXMLList", " ".join(str(r["orientation"]) for r in tab))
    for label, key, rule, unit in cols:
        if key not in tab[0]:
            continue
        list_quantity(lst, label, [num(res, item_path(name, f"table.{i}.{key}"), rule, U)
                                    for i in range(len(tab))], unit)


def dcc_bytes(res: dict, *, lab: dict | None = None, cert_id: str) -> bytes:
    """The DCC of results.json ``res`` as UTF-8 XML bytes, with declaration, pretty-printed,
    deterministic."""
    return tree_bytes(dcc_tree(res, lab=lab, cert_id=cert_id))


def write_dcc(res: dict, out: str | Path, *, lab: dict | None = None,
              cert_id: str) -> dict[str, Path]:
    """Write ``certificate.dcc.xml`` of results.json ``res`` into ``out`` atomically;
    returns ``{name: path}``."""
    path = Path(out) / "certificate.dcc.xml"
    write_bytes(path, dcc_bytes(res, lab=lab, cert_id=cert_id))
    return {"certificate.dcc.xml": path}

