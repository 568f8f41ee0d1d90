"""The Digital Calibration Certificate: PTB DCC 3.3.0 XML, built with lxml.

Contents
========
=========================  ==============================================================
:data:`DCC_NS`, :data:`SI_NS`  the DCC and D-SI namespaces
:data:`DSI_UNITS`          results.json unit → D-SI unit string (D-SI 2.2 syntax)
:func:`dsi_decimal`        a displayed number ("4.36×10⁻⁵", "±0.15") → an si:decimal ("4.36e-5")
:func:`dcc_tree`           the DCC document as an lxml element tree
:func:`dcc_bytes`          the same as UTF-8 bytes (deterministic)
:func:`write_dcc`          ``certificate.dcc.xml`` into a folder, atomically
=========================  ==============================================================

What the DCC holds (issue 13):

administrativeData
    the software (gonio and its version); core data (country, languages, the
    certificate's unique identifier, receipt / performance / issue dates, location);
    the item (description, manufacturer, model, serial); the laboratory, the
    responsible persons (calibrated, checked, approved = main signer), the customer;
    statements: the specification followed, each reading taken of its ambiguities,
    the decision rule and one conformity statement per item that has limits
    (``pass``, ``fail``, ``conditionalPass``, ``conditionalFail``; none without limits).
measurementResults
    the method (clauses, with the method statement's settings), the standards used
    (measuring equipment), the influence conditions (temperature, humidity), and one
    result per item: its value, D-SI unit and, where the item has one, the expanded
    uncertainty with coverage factor and coverage probability; E as ± max|E_i| with
    the signed extreme and its position; the per-point tables as lists.

Every number is the one the printed certificate shows (:mod:`gonio.report.stated`,
the GUM 7.2.6 rounding), written in the si:decimal form. The virtual bench's DCC is
an example: its identifier starts ``VB-``, a statement says it certifies nothing, and
when the readings carry no date the performance dates are the placeholder
:data:`PLACEHOLDER_DATE`, said so in that statement.

The schema set is not needed at run time; ``tests/test_dcc.py`` validates the output
against the DCC 3.3.0 XSD offline (xmlschema, XSD 1.1), with the D-SI unit strings checked by
a D-SI parser.
"""

from __future__ import annotations

import re
from pathlib import Path

from lxml import etree

from gonio.atomic import write_bytes
from gonio.report.i18n import display, labels, reading_note, specification_text
from gonio.report.stated import (ITEMS, Num, conformity_for, conformity_texts, item_uncertainty,
                                 method_rows, num, stated_item)

DCC_NS = "https://ptb.de/dcc"
SI_NS = "https://ptb.de/si"
_NSMAP = {"dcc": DCC_NS, "si": SI_NS}
SCHEMA_VERSION = "3.3.0"
#: Performance date of a virtual-bench example whose readings carry no date.
PLACEHOLDER_DATE = "1970-01-01"

#: results.json units → D-SI (D-SI 2.2: \\arcsecond, \\degree, \\hour, \\tothe{-1}, \\percent, \\ppm).
DSI_UNITS: dict[str, str] = {
    "arcsec": r"\arcsecond",
    "deg": r"\degree",
    "deg/h": r"\degree\hour\tothe{-1}",
    "deg/s": r"\degree\second\tothe{-1}",
    "counts/deg": r"\one\degree\tothe{-1}",
    "%": r"\percent",
    "ppm": r"\ppm",
    "degC": r"\degreecelsius",
    "s": r"\second",
    "one": r"\one",
}

#: Conformity outcomes → the DCC's stringConformityStatementStatusType.
DCC_CONFORMITY: dict[str, str] = {"pass": "pass", "fail": "fail",
                                  "conditional pass": "conditionalPass",
                                  "conditional fail": "conditionalFail"}

_SUP = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")


def dsi_decimal(text: str) -> str:
    """A number as the certificate shows it, in the si:decimal form (same digits).

    >>> dsi_decimal("4.36×10⁻⁵"), dsi_decimal("±0.15"), dsi_decimal("+0.15"), dsi_decimal("76434.845")
    ('4.36e-5', '0.15', '0.15', '76434.845')
    """
    t = str(text).strip().lstrip("±+")
    m = re.fullmatch(r"(-?\d+(?:\.\d+)?)×10([⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+)", t)
    if m:
        return f"{m.group(1)}e{m.group(2).translate(_SUP)}"
    if not re.fullmatch(r"-?\d+(?:\.\d+)?", t):
        raise ValueError(f"not a displayed number: {text!r}")
    return t


def _e(parent, tag: str, text: str | None = None, **attrib) -> "etree.Element":
    ns, _, name = tag.partition(":")
    el = etree.SubElement(parent, f"{{{_NSMAP[ns]}}}{name}", **attrib)
    if text is not None:
        el.text = str(text)
    return el


def _text(parent, tag: str, text: str, lang: str | None = None) -> "etree.Element":
    """A dcc:textType / richContentType element with one dcc:content."""
    el = _e(parent, tag)
    c = _e(el, "dcc:content", text)
    if lang:
        c.set("lang", lang)
    return el


def _real(parent, value: Num | str, unit: str, *, U: Num | None = None, k: Num | None = None,
          p: float | None = None, label: str | None = None) -> "etree.Element":
    """si:real with the stated value, its D-SI unit and (when given) the expanded uncertainty.

    Each si:value / si:valueExpandedMU carries ``refId``-free text; the path in results.json
    is recorded in an XML comment before the si:real (for the number checks)."""
    if isinstance(value, Num):
        parent.append(etree.Comment(f" src={value.src} rule={value.rule} "))
    r = _e(parent, "si:real")
    if label:
        _e(r, "si:label", label)
    _e(r, "si:value", dsi_decimal(str(value)))
    _e(r, "si:unit", DSI_UNITS[unit])
    if U is not None and k is not None and p is not None:
        mu = _e(_e(r, "si:measurementUncertaintyUnivariate"), "si:expandedMU")
        _e(mu, "si:valueExpandedMU", dsi_decimal(str(U)))
        _e(mu, "si:coverageFactor", dsi_decimal(str(k)))
        _e(mu, "si:coverageProbability", repr(float(p)))
    return r


def _quantity(parent, name: str, value, unit: str, **kw) -> "etree.Element":
    q = _e(parent, "dcc:quantity")
    _text(q, "dcc:name", name)
    _real(q, value, unit, **kw)
    return q


def _list_quantity(parent, name: str, values: list, unit: str) -> None:
    """A column of a per-point table as si:realListXMLList (values as displayed)."""
    q = _e(parent, "dcc:quantity")
    _text(q, "dcc:name", name)
    srcs = " ".join(v.src if isinstance(v, Num) else "-" for v in values)
    rule = next((v.rule for v in values if isinstance(v, Num)), "")
    q.append(etree.Comment(f" src-list={srcs} rule={rule} "))
    rl = _e(q, "si:realListXMLList")
    _e(rl, "si:valueXMLList", " ".join(dsi_decimal(str(v)) if isinstance(v, Num) else "NaN"
                                        for v in values))
    _e(rl, "si:unitXMLList", DSI_UNITS[unit])


def _contact(parent, tag: str, name: str, address: str | None, email: str | None = None):
    c = _e(parent, tag)
    _text(c, "dcc:name", name)
    if email:
        _e(c, "dcc:eMail", email)
    loc = _e(c, "dcc:location")
    _text(loc, "dcc:further", address or "not stated")
    return c


def dcc_tree(report, *, lab: dict | None = None, cert_id: str) -> "etree.Element":
    """The DCC 3.3.0 document of one calibration (see the module docstring for its content)."""
    from gonio import __version__

    L = labels("en")
    res = report.to_dict()
    md = res.get("metadata", {})
    virtual = lab is None
    lab_ = lab or {}
    root = etree.Element(f"{{{DCC_NS}}}digitalCalibrationCertificate", nsmap=_NSMAP,
                         schemaVersion=SCHEMA_VERSION)
    adm = _e(root, "dcc:administrativeData")
    sw = _e(_e(adm, "dcc:dccSoftware"), "dcc:software")
    _text(sw, "dcc:name", "gonio")
    _e(sw, "dcc:release", __version__)
    _e(sw, "dcc:type", "application")

    cert = lab_.get("certificate", {})
    core = _e(adm, "dcc:coreData")
    _e(core, "dcc:countryCodeISO3166_1", "CN")
    _e(core, "dcc:usedLangCodeISO639_1", "en")
    _e(core, "dcc:mandatoryLangCodeISO639_1", "en")
    _e(core, "dcc:uniqueIdentifier", cert_id)
    if cert.get("date_of_receipt"):
        _e(core, "dcc:receiptDate", cert["date_of_receipt"])
    date = cert.get("date_of_calibration") or str(md.get("date") or "")[:10] or PLACEHOLDER_DATE
    _e(core, "dcc:beginPerformanceDate", date)
    _e(core, "dcc:endPerformanceDate", date)
    _e(core, "dcc:performanceLocation", "other" if virtual else "laboratory")
    if cert.get("date_of_issue"):
        _e(core, "dcc:issueDate", cert["date_of_issue"])

    inst = lab_.get("instrument") or {}
    items = _e(adm, "dcc:items")
    it = _e(items, "dcc:item")
    _text(it, "dcc:name", inst.get("description") or str(md.get("instrument") or "instrument"))
    man = inst.get("manufacturer") or md.get("manufacturer")
    if man:
        _text(_e(it, "dcc:manufacturer"), "dcc:name", str(man))
    if inst.get("model") or md.get("model"):
        _e(it, "dcc:model", str(inst.get("model") or md.get("model")))
    ids = _e(it, "dcc:identifications")
    ident = _e(ids, "dcc:identification")
    _e(ident, "dcc:issuer", "manufacturer")
    _e(ident, "dcc:value", str(inst.get("serial") or md.get("serial") or "not stated"))
    _text(ident, "dcc:name", "serial number")

    la = lab_.get("laboratory") or {"name": "gonio virtual bench", "address": None,
                                     "contact": ""}
    _contact(_e(adm, "dcc:calibrationLaboratory"), "dcc:contact", la["name"], la["address"],
             la.get("contact") if "@" in (la.get("contact") or "") else None)
    sig = lab_.get("signatory") or {}
    persons = _e(adm, "dcc:respPersons")
    people = [(sig.get("calibrated_by"), "calibrated by", False),
              (sig.get("checked_by"), "checked by", False),
              (sig.get("approved_by"), "approved by" + (f", {sig['approved_title']}"
                                                        if sig.get("approved_title") else ""),
               True)]
    if not any(p for p, _, _ in people):
        people = [("gonio virtual bench", "none: a virtual-bench example is signed by nobody",
                   True)]
    for who, role, main in people:
        if not who:
            continue
        rp = _e(persons, "dcc:respPerson")
        _text(_e(rp, "dcc:person"), "dcc:name", who)
        _e(rp, "dcc:role", role)
        _e(rp, "dcc:mainSigner", "true" if main else "false")
    cust = lab_.get("customer") or {"name": "not stated", "address": None}
    _contact(adm, "dcc:customer", cust["name"], cust.get("address"))

    sts = _e(adm, "dcc:statements")
    st = _e(sts, "dcc:statement", id="specification")
    _text(st, "dcc:name", L["specification"])
    _e(st, "dcc:norm", specification_text(res.get("specification") or "not stated", "en"))
    _text(st, "dcc:declaration", "The calibration follows the specification's clauses "
          + ", ".join(res[n]["clause"] for n in ITEMS if res[n]["measured"]) + ".")
    if virtual:
        st = _e(sts, "dcc:statement", id="virtual-bench")
        _text(st, "dcc:name", L["virtual"])
        _text(st, "dcc:declaration", L["virtual_note"] + (
            f" Performance dates are the placeholder {PLACEHOLDER_DATE}."
            if date == PLACEHOLDER_DATE else ""))
    for i, note in enumerate(res.get("readings_taken", []), 1):
        st = _e(sts, "dcc:statement", id=f"reading-taken-{i}")
        _text(st, "dcc:name", L["readings_taken"])
        _text(st, "dcc:declaration", reading_note(note, "en"))
    conf = conformity_for(res, lab)
    if conf:
        rule = conf[0]["rule"]
        st = _e(sts, "dcc:statement", id="decision-rule")
        _text(st, "dcc:name", "Decision rule")
        _e(st, "dcc:norm", "ILAC-G8:09/2019")
        _e(st, "dcc:norm", "JCGM 106:2012")
        agreed = (lab_.get("decision_rule") or {}).get("agreed")
        _text(st, "dcc:declaration", L[f"rule_{rule.kind}"].format(
            r=display("k", rule.guard_factor)) + (f" Agreed: {agreed}." if agreed else ""))
        for e in conf:
            c = e["conformity"]
            st = _e(sts, "dcc:statement", id=f"conformity-{e['item']}",
                    refId=f"result-{e['item']}")
            _text(st, "dcc:name", f"Statement of conformity: {L[e['item']]}")
            if c is None:
                _text(st, "dcc:declaration", L[e["reason"]])
                continue
            t = conformity_texts(c, res, L)
            _text(st, "dcc:declaration",
                  f"{t['outcome']}; limits {t['limits']}; acceptance interval {t['acceptance']}; "
                  f"specific false-accept probability {t['pfa']}"
                  + (f"; {t['pfr']}" if t["pfr"] else "") + f"; limits from: {c.source or '—'}")
            _e(st, "dcc:conformity", DCC_CONFORMITY[c.outcome])
            data = _e(st, "dcc:data")
            unit = res[e["item"]]["unit"]
            for nm, v in (("lower specification limit", c.lower),
                          ("upper specification limit", c.upper)):
                if v is not None:
                    _quantity(data, nm, display(_limit_rule(c), v), unit)
            if c.false_accept_probability is not None:
                _quantity(data, "specific false-accept probability",
                          display("sig2", c.false_accept_probability), "one")
            else:
                _quantity(data, "specific false-reject probability",
                          display("sig2", c.false_reject_probability), "one")

    mrs = _e(root, "dcc:measurementResults")
    mr = _e(mrs, "dcc:measurementResult")
    _text(mr, "dcc:name", "Calibration of an optical-gyroscope angle measuring instrument")
    um = _e(_e(mr, "dcc:usedMethods"), "dcc:usedMethod", id="method")
    _text(um, "dcc:name", L["method"])
    _text(um, "dcc:description", "; ".join(f"{k}: {v}" for k, v in
                                           method_rows(report, res, L, lab, "en")))
    _e(um, "dcc:norm", specification_text(res.get("specification") or "not stated", "en"))
    eqs = _e(mr, "dcc:measuringEquipments")
    stds = lab_.get("standards") or [{"name": str(md.get("table") or "rotary table"),
                                      "identifier": "", "accuracy": (
                                          f"MPE ±{md['table_mpe_arcsec']}″"
                                          if md.get("table_mpe_arcsec") else ""),
                                      "certificate": "", "traceability": ""}]
    for s in stds:
        eq = _e(eqs, "dcc:measuringEquipment")
        _text(eq, "dcc:name", s["name"])
        desc = "; ".join(x for x in (s.get("accuracy"), s.get("certificate") and
                                     f"certificate {s['certificate']}",
                                     s.get("traceability") and
                                     f"traceable to {s['traceability']}") if x)
        if desc:
            _text(eq, "dcc:description", desc)
        if s.get("identifier"):
            ids = _e(eq, "dcc:identifications")
            ident = _e(ids, "dcc:identification")
            _e(ident, "dcc:issuer", "calibrationLaboratory")
            _e(ident, "dcc:value", s["identifier"])
    env = lab_.get("environment") or {}
    conds = []
    if env.get("temperature_c") is not None:
        conds.append(("temperature", display("sig4", env["temperature_c"]), "degC"))
    elif md.get("temperature_c"):
        conds.append(("temperature", display("sig4", float(md["temperature_c"])), "degC"))
    if env.get("humidity_pct") is not None:
        conds.append(("relative humidity", display("sig3", env["humidity_pct"]), "%"))
    if conds:
        ics = _e(mr, "dcc:influenceConditions")
        for nm, v, u in conds:
            ic = _e(ics, "dcc:influenceCondition")
            _text(ic, "dcc:name", nm)
            _quantity(_e(ic, "dcc:data"), nm, v, u)

    results = _e(mr, "dcc:results")
    for name in ITEMS:
        item = res[name]
        r = _e(results, "dcc:result", id=f"result-{name}")
        _text(r, "dcc:name", f"{L[name]} ({item['clause']})")
        data = _e(r, "dcc:data")
        s = stated_item(res, name)
        if not s["measured"]:
            q = _e(data, "dcc:quantity")
            _text(q, "dcc:name", L[name])
            _text(q, "dcc:noQuantity", f"not measured: {item['reason']}")
            continue
        unc = item_uncertainty(res, name)
        kw = {}
        if unc and s["U"] is not None and s["k"] is not None and unc["p"] is not None:
            kw = {"U": s["U"], "k": s["k"], "p": float(unc["p"])}
        if name == "angle_deviation" and s["signed"] is not None:
            _quantity(data, "E = ± max|E_i| (draft 7.4)", s["value"], item["unit"], **kw)
            _quantity(data, "signed extreme of E_i", s["signed"], item["unit"])
            if isinstance(s["position"], Num):
                _quantity(data, "position of the extreme", s["position"], "deg")
        else:
            _quantity(data, L[name], s["value"], item["unit"], **kw)
        _detail_lists(data, res, name)
    return root


def _limit_rule(c) -> str:
    from gonio.report.i18n import rule_at_U
    return rule_at_U(c.U, 3)


def _detail_lists(data, res: dict, name: str) -> None:
    """The per-point tables of one item as dcc:list of columns, displayed as the certificate."""
    item = res[name]
    U = res["uncertainty"]["U_arcsec"]
    tab = item.get("table") or []
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
    lst = _e(data, "dcc:list")
    _text(lst, "dcc:name", "per-point table")
    if name == "pointing_consistency":
        lq = _e(lst, "dcc:quantity")
        _text(lq, "dcc:name", "axis direction")
        _e(lq, "dcc:charsXMLList", " ".join(str(r["orientation"]) for r in tab))
    for label, key, rule, unit in cols:
        if key not in tab[0]:
            continue
        _list_quantity(lst, label, [num(res, f"{name}.table.{i}.{key}", rule, U)
                                    for i in range(len(tab))], unit)


def dcc_bytes(report, *, lab: dict | None = None, cert_id: str) -> bytes:
    """The DCC as UTF-8 XML bytes, with declaration, pretty-printed, deterministic."""
    return etree.tostring(dcc_tree(report, lab=lab, cert_id=cert_id), xml_declaration=True,
                          encoding="UTF-8", pretty_print=True)


def write_dcc(report, out: str | Path, *, lab: dict | None = None,
              cert_id: str) -> dict[str, Path]:
    """Write ``certificate.dcc.xml`` into ``out`` atomically; returns ``{name: path}``."""
    path = Path(out) / "certificate.dcc.xml"
    write_bytes(path, dcc_bytes(report, lab=lab, cert_id=cert_id))
    return {"certificate.dcc.xml": path}
