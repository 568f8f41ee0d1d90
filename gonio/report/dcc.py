"""The Digital Calibration Certificate's shared parts: PTB DCC 3.3.0 XML, built with lxml.

Contents
========
=========================  ==============================================================
:data:`DCC_NS`, :data:`SI_NS`  the DCC and D-SI namespaces
:func:`unit_dsi`           results.json unit → D-SI unit string (the one unit table)
:func:`dsi_decimal`        a displayed number ("4.36×10⁻⁵", "±0.15") → an si:decimal ("4.36e-5")
:func:`element`, :func:`text_element`, :func:`real`, :func:`quantity`, :func:`list_quantity`,
:func:`not_measured_quantity`, :func:`nu_quantity`, :func:`probability_quantities`  the
                           shared builders (also used by
                           :mod:`gonio.report.rate_dcc`)
:func:`new_document`, :func:`administrative_data`, :func:`measurement_result`,
:func:`influence_conditions`, :func:`tree_bytes`  the shared document parts
:func:`conformity_statements`, :func:`bilingual`,
:func:`label_translator`   statements of conformity, the Chinese beside
                           the English
=========================  ==============================================================

Each specification's DCC is built from these parts: a per-item result's in
:mod:`gonio.report.item_dcc` and :mod:`gonio.report.rate_dcc`, a specification's own
document in its rendering module ``dcc``. What a DCC holds:

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
    uncertainty with coverage factor and coverage probability, or its coverage interval
    (an item stated by its χ² interval with the ν that interval was computed with, in a
    quantity of its own: :func:`nu_quantity`); E as ± max|E_i| with the signed extreme
    and its position; the per-point tables as lists.

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

from lxml import etree

from gonio.report.header import is_draft, people_key, record_of
from gonio.report.provenance import is_virtual, virtual_lines
from gonio.report.i18n import display, finding_text, labels
from gonio.report.stated import (Num, conformity_texts, declaration_parts, interval_band_note,
                                 stated_p as item_p)
from gonio.result.statement import (DSI_UNITS, K_SOURCE_BOUND_CHI2, K_SOURCE_MAX_MAGNITUDE,
                                    p_text)

DCC_NS = "https://ptb.de/dcc"
SI_NS = "https://ptb.de/si"
_NSMAP = {"dcc": DCC_NS, "si": SI_NS}
SCHEMA_VERSION = "3.3.0"
#: Performance date of a virtual-bench example whose readings carry no date.
PLACEHOLDER_DATE = "1970-01-01"

def unit_dsi(unit: str) -> str:
    """The D-SI 2.2 form of a results.json ``unit`` whose numbers are written as they are,
    from the one unit table (:data:`gonio.result.statement.DSI_UNITS`); a unit the table
    lacks, or one whose numbers need a factor (per g), is a KeyError: the caller gives the
    D-SI string (and scales) itself.

    >>> unit_dsi("arcsec"), unit_dsi("deg/h")
    ('\\\\arcsecond', '\\\\degree\\\\hour\\\\tothe{-1}')
    """
    dsi, factor = DSI_UNITS[unit]
    if factor != 1.0:
        raise KeyError(f"{unit!r} needs the factor {factor:g}: give its D-SI form")
    return dsi


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
    if re.fullmatch(r"-?\d+(?:\.\d+)?[eE][-+]?\d+", t):      # a limit as given: "-1e-05"
        return t.lower()
    if not re.fullmatch(r"-?\d+(?:\.\d+)?", t):
        raise ValueError(f"not a displayed number: {text!r}")
    return t


def element(parent, tag: str, text: str | None = None, **attrib) -> "etree.Element":
    """A ``dcc:`` or ``si:`` child element (``tag`` with its prefix) with optional text."""
    ns, _, name = tag.partition(":")
    el = etree.SubElement(parent, f"{{{_NSMAP[ns]}}}{name}", **attrib)
    if text is not None:
        el.text = str(text)
    return el


def text_element(parent, tag: str, text: str, lang: str | None = None) -> "etree.Element":
    """A dcc:textType / richContentType element with one dcc:content."""
    el = element(parent, tag)
    c = element(el, "dcc:content", text)
    if lang:
        c.set("lang", lang)
    return el


def real(parent, value: Num | str, unit: str, *, U: Num | None = None, k: Num | None = None,
         p: float | None = None, label: str | None = None,
         dsi: str | None = None, note: str = "",
         interval: tuple[str, str] | None = None, u_std: str | None = None) -> "etree.Element":
    """si:real with the stated value, its D-SI unit and (when given) the expanded uncertainty.

    ``unit`` is a results.json unit of the one table (:func:`unit_dsi`), or ``dsi`` gives
    the D-SI string itself. Each si:value / si:valueExpandedMU carries ``refId``-free text;
    the path in results.json is recorded in an XML comment before the si:real (for the number checks),
    with ``note`` (e.g. ``factor=…`` of a unit conversion) appended. An item stated by its
    coverage interval (``interval`` the stated ends, ``u_std`` its standard uncertainty,
    ``p``) is written as si:coverageIntervalMU instead of an expanded uncertainty; its
    si:value is the stated value as the certificate rounds it, sign and digits kept, also
    where it lies outside that interval (a non-negative quantity whose bias-corrected
    estimate fell below zero is stated by its upper bound alone, "≤ upper (interval [0,
    upper])": its si:value is that signed estimate, never a 0 nobody measured; the
    statement is the interval, and the quantity's description says so)."""
    shown = dsi_decimal(str(value))
    if isinstance(value, Num):
        below = interval is not None and float(shown) < float(dsi_decimal(interval[0]))
        note += (" (the estimate, below its interval's lower end: the statement is the "
                 "interval)") if below else ""
        parent.append(etree.Comment(f" src={value.src} rule={value.rule}{note} "))
    r = element(parent, "si:real")
    if label:
        element(r, "si:label", label)
    element(r, "si:value", shown)
    element(r, "si:unit", dsi or unit_dsi(unit))
    if U is not None and k is not None and p is not None:
        mu = element(element(r, "si:measurementUncertaintyUnivariate"), "si:expandedMU")
        element(mu, "si:valueExpandedMU", dsi_decimal(str(U)))
        element(mu, "si:coverageFactor", dsi_decimal(str(k)))
        element(mu, "si:coverageProbability", stated_p(p))
    elif interval is not None and u_std is not None and p is not None:
        ci = element(element(r, "si:measurementUncertaintyUnivariate"), "si:coverageIntervalMU")
        element(ci, "si:valueStandardMU", dsi_decimal(u_std))
        element(ci, "si:intervalMin", dsi_decimal(interval[0]))
        element(ci, "si:intervalMax", dsi_decimal(interval[1]))
        element(ci, "si:coverageProbability", stated_p(p))
    return r


#: what a bound-condition interval is, in the DCC's words
BOUND_INTERVAL = ("bound-condition interval, value ± (a + k·u): the bounded errors (the "
                  "table's where no certificate u is stated for it; the item's other bounded "
                  "lines) at their bounds in their worst "
                  "combination, a, plus k·u of the other lines; no "
                  "standard uncertainty of the item is certified")

#: what a dispersion's one-sided bound-condition limit is, in the DCC's words
#: (:data:`gonio.result.statement.K_SOURCE_BOUND_CHI2`)
BOUND_CHI2_INTERVAL = ("one-sided bound-condition limit, [0, s + a + R]: the bounded errors "
                       "(the item's bounded lines) at their bounds with the sign that lowers "
                       "the reading, a, plus the reach R of the one-sided chi-square limit of "
                       "the other lines; no standard uncertainty of the item is certified")


#: what the interval of the largest magnitude with each point's bounded errors at their bounds
#: is, in the DCC's words (:func:`gonio.result.gum.max_magnitude_statement`'s ``bounded``)
MAX_ABS_BOUND_INTERVAL = ("the 95 % interval of the largest magnitude max|x_i|, each point's "
                          "reach c·u_i + b_i: u_i of the lines other than the bounded ones, "
                          "b_i their bound at the point; no standard uncertainty of the item "
                          "is certified")


def bound_interval_text(item: dict) -> str:
    """What a results.json item stated by its bound condition names its interval quantity in
    the DCC: :data:`BOUND_CHI2_INTERVAL` for a dispersion's one-sided limit,
    :data:`MAX_ABS_BOUND_INTERVAL` for the extreme of magnitudes, else :data:`BOUND_INTERVAL`.

    >>> from gonio.result.statement import K_SOURCE_BOUND_CHI2
    >>> bound_interval_text({"uncertainty": {"k_source": K_SOURCE_BOUND_CHI2}})[:16]
    'one-sided bound-'
    >>> bound_interval_text({"uncertainty": {"k_source": "bound condition"}})[:16]
    'bound-condition '
    """
    ks = (item.get("uncertainty") or {}).get("k_source")
    if ks == K_SOURCE_BOUND_CHI2:
        return BOUND_CHI2_INTERVAL
    if ks == K_SOURCE_MAX_MAGNITUDE:
        return MAX_ABS_BOUND_INTERVAL
    return BOUND_INTERVAL


#: The name of a non-negative item whose bias-corrected estimate fell below zero, written as
#: its interval [0, upper bound] alone (:func:`below_zero_quantity`).
BELOW_ZERO_INTERVAL = ("stated by its upper bound alone, the interval [0, upper bound]: the "
                       "bias-corrected estimate fell below zero; no value is stated")


def below_zero_quantity(d, name: str, ends, dsi: str, p: float,
                        description: str | None = None) -> None:
    """A non-negative item whose estimate fell below zero, as its certificate states it: by its
    upper bound alone, so the DCC writes the interval [0, upper] (:func:`interval_quantity`,
    :data:`BELOW_ZERO_INTERVAL` in the name) and no si:value — neither the bound nor the
    negative estimate is a measured value, and a consumer would read an si:value as one.
    ``description``: the certificate's statement with its note."""
    interval_quantity(d, name, ends, dsi, p, BELOW_ZERO_INTERVAL, description=description)


def interval_quantity(d, name: str, ends, dsi: str, p: float, what: str,
                      description: str | None = None) -> None:
    """An interval stated without a standard uncertainty (an item whose certificate states
    no u_c: :func:`gonio.report.item_dcc.u_c_certified` false; the optical E where each
    point's U = k·u + b carries the table's bound): a dcc:quantity holding its two ends as an si:realListXMLList labelled intervalMin,
    intervalMax, its p and what it is in the name (si:coverageIntervalMU requires an
    si:valueStandardMU, which the certificate does not state). ``description``: a
    dcc:description after the name. A non-negative item whose estimate fell below zero
    may be written so too, with no si:value: a certificate that states it by its upper
    bound alone states no value, and neither that bound nor the negative estimate is one."""
    q = element(d, "dcc:quantity", refType="basic_measurementUncertainty")
    text_element(q, "dcc:name", f"{name}: {what}; p = {p_text(p)} %")
    if description:
        text_element(q, "dcc:description", description)
    rl = element(q, "si:realListXMLList")
    element(rl, "si:labelXMLList", "intervalMin intervalMax")
    element(rl, "si:valueXMLList", " ".join(dsi_decimal(str(e)) for e in ends))
    element(rl, "si:unitXMLList", f"{dsi} {dsi}")


def probability_quantities(data, p_c, false_accept, false_reject) -> None:
    """A conformity statement's probabilities as quantities of its ``data`` (unit one), at the
    digits the certificate prints them (:func:`gonio.report.stated.conformity_texts`: the
    probability of conformance and the false-reject probability three significant digits,
    the false-accept two); None writes nothing."""
    for nm, v, rule in (("probability of conformance", p_c, "sig3"),
                        ("specific false-accept probability", false_accept, "sig2"),
                        ("specific false-reject probability", false_reject, "sig3")):
        if v is not None:
            quantity(data, nm, display(rule, v), "one")


#: What an item's degrees-of-freedom quantity is, in the DCC's words (:func:`nu_quantity`)
CHI2_NU = "degrees of freedom ν its chi-square interval was computed with"


#: ... of an item stated by another interval whose coverage factor came from a ν_eff (a
#: bound-condition interval value ± (a + k·u), a non-negative item's upper bound value + U)
INTERVAL_NU_EFF = ("effective degrees of freedom ν_eff its interval's coverage factor was "
                   "computed with")


def nu_quantity(d, name: str, nu: Num | None, chi2: bool = True) -> None:
    """The ν of an item stated by its interval, as its certificate prints it beside that
    interval (the ν_eff column): a dcc:quantity after the item's own (refType
    ``gonio_degreesOfFreedom``) holding ν as an si:real in the unit one, its path in
    results.json and its rule ("nuchi2", "nu") in the comment before it, as every stated
    number. ``chi2``: a χ² interval's ν (a standard deviation's, a dispersion's
    bound-condition limit; :data:`CHI2_NU` in its name), without which the interval's upper
    end cannot be computed again (s·√(ν/χ²_{1−p}(ν))); else the ν_eff of the coverage
    factor of a bound-condition interval or an upper bound (:data:`INTERVAL_NU_EFF`).
    si:coverageIntervalMU and the ends' list have no place for it. ``nu``:
    :func:`gonio.report.stated.item_nums`'s ``interval_nu`` (or ``chi2_nu``); None writes
    nothing, nor does a ν_eff stated "∞" (no si:real holds it: the normal k, as an item
    stated value ± U with ν_eff ∞ writes none either)."""
    if nu is None or str(nu) == "∞":
        return
    quantity(d, f"{name}: {CHI2_NU if chi2 else INTERVAL_NU_EFF}", nu, "one",
             ref_type="gonio_degreesOfFreedom")


def stated_p(p) -> str:
    """A coverage probability as the certificate states it (:func:`~gonio.result.statement.
    p_text`: "p ≈ 98 %" is 0.98 in the DCC, never 0.9823487503232564; 0.9545 stays 0.9545).

    >>> stated_p(0.9823487503232564), stated_p(0.95), stated_p(0.9545), stated_p(0.99998)
    ('0.98', '0.95', '0.9545', '0.99998')
    """
    from decimal import Decimal

    from gonio.result.statement import p_text

    return str(Decimal(p_text(float(p))).scaleb(-2))


def quantity(parent, name: str, value, unit: str, *, ref_type: str | None = None,
             description: str | None = None, **kw) -> "etree.Element":
    """dcc:quantity with a dcc:name (a ``refType``, a dcc:description) and one si:real
    (keywords of :func:`real`)."""
    q = element(parent, "dcc:quantity", **({"refType": ref_type} if ref_type else {}))
    text_element(q, "dcc:name", name)
    if description:
        text_element(q, "dcc:description", description)
    real(q, value, unit, **kw)
    return q


def conformity_statements(sts, items: dict, name_of, dsi_of, L: dict) -> None:
    """The decision rule(s) and one dcc:statement per item the pipeline decided (results.json
    ``items.<key>.conformity``), each with the rule, the outcome (dcc:conformity), the limits,
    the probability of conformance and the specific false-accept probability as dcc:data;
    ``refId`` names the item's dcc:result. ``name_of(key)`` names an item, ``dsi_of(key)``
    gives its (D-SI unit, factor)."""
    decided = [(k, it["conformity"]) for k, it in items.items() if it.get("conformity")]
    for rule in dict.fromkeys((c.get("rule") or "simple") for _, c in decided):
        r = next(c for _, c in decided if (c.get("rule") or "simple") == rule)
        st = element(sts, "dcc:statement", id=f"decision-rule-{rule}")
        text_element(st, "dcc:name", "Decision rule")
        element(st, "dcc:norm", "ILAC-G8:09/2019")
        element(st, "dcc:norm", "JCGM 106:2012")
        text_element(st, "dcc:declaration", L.get(f"rule_{rule}", rule).format(
            r=display("k", r.get("guard_factor") or 0.0)))
    # the U of w = r·U of each item decided on its 95 % interval alone, as on the certificate
    band = interval_band_note(decided, L, name_of, lambda k: band_unit(items[k]),
                              lambda k: item_p(items[k]))
    if band:
        st = element(sts, "dcc:statement", id="guard-band-interval-items")
        text_element(st, "dcc:name", "Guard band of the items stated by an interval")
        text_element(st, "dcc:declaration", band)
    for key, c in decided:
        st = element(sts, "dcc:statement", id=f"conformity-{key}", refId=f"result-{key}")
        text_element(st, "dcc:name", f"Statement of conformity: {name_of(key)}")
        if not c.get("outcome"):
            text_element(st, "dcc:declaration", f"no statement: {c.get('reason') or '—'}")
            continue
        t = conformity_texts(c, None, L)
        acc, pfa = declaration_parts(c, t)
        text_element(st, "dcc:declaration",
                     f"{t['outcome']}; rule {c.get('rule')}; limits {t['limits']}; {acc}; "
                     f"specific false-accept probability {pfa}"
                     + (f"; {t['pfr']}" if t["pfr"] else "")
                     + f"; limits from: {c.get('source') or c.get('limits_from') or '—'}"
                     + (f"; {t['measured']}" if t["measured"] else ""))
        element(st, "dcc:conformity", DCC_CONFORMITY[c["outcome"]])
        data = element(st, "dcc:data")
        dsi, factor = dsi_of(key)
        if c.get("decided_on_measured"):
            quantity(data, "measured value before rounding (decided the outcome)",
                     repr(float(c["decided_on_measured"]) * factor), "", dsi=dsi)
        for nm, v in (("lower specification limit", c.get("lower")),
                      ("upper specification limit", c.get("upper"))):
            if v is not None:
                quantity(data, nm, repr(float(v) * factor), "", dsi=dsi)
        probability_quantities(data, c.get("conformance_probability"),
                               c.get("false_accept_probability"),
                               c.get("false_reject_probability"))


def band_unit(item: dict) -> str:
    """An item's unit as the DCC's guard-band note prints it ("" for the unit one)."""
    u = item.get("unit") or ""
    return "" if u == "1" else u


def bilingual(doc: bytes, translate) -> bytes:
    """The DCC ``doc`` with Chinese beside English: every dcc:content that ``translate(text)``
    gives a Chinese form for is marked ``lang="en"`` and followed by a ``lang="zh"`` sibling;
    the core data then list both used languages (English stays mandatory)."""
    root = etree.fromstring(doc)
    for c in list(root.iter(f"{{{DCC_NS}}}content")):
        if c.get("lang") or not c.text:
            continue
        zh = translate(c.text)
        if zh and zh != c.text:
            c.set("lang", "en")
            z = etree.Element(f"{{{DCC_NS}}}content", lang="zh")
            z.text = zh
            c.addnext(z)
    core = root.find(f".//{{{DCC_NS}}}coreData")
    used = core.find(f"{{{DCC_NS}}}usedLangCodeISO639_1")
    if used is not None and core.find(f"{{{DCC_NS}}}usedLangCodeISO639_1[.='zh']") is None:
        z = etree.Element(f"{{{DCC_NS}}}usedLangCodeISO639_1")
        z.text = "zh"
        used.addnext(z)
    return tree_bytes(root)


def label_translator(extra: dict | None = None, tables=(), own: dict | None = None,
                     openings=()):
    """``translate(text)`` for :func:`bilingual` (:func:`gonio.report.i18n.translator`;
    ``own``: the specification's own labels; ``openings``: keys of ``extra`` that are the
    opening words of a longer text)."""
    from gonio.report.i18n import translator

    return translator(extra, tables, own, openings)


def _decimal_or_nan(v) -> str:
    """A shown number (Num or plain decimal text) as an si:decimal; "—" or None as NaN."""
    try:
        return dsi_decimal(str(v)) if v is not None else "NaN"
    except ValueError:
        return "NaN"


def list_quantity(parent, name: str, values: list, unit: str, dsi: str | None = None) -> None:
    """A column of a per-point table as si:realListXMLList (values as displayed, Num or
    plain decimal text; a missing one is NaN; ``dsi`` gives the D-SI unit instead of
    :func:`unit_dsi` (``unit``))."""
    q = element(parent, "dcc:quantity")
    text_element(q, "dcc:name", name)
    if any(isinstance(v, Num) for v in values):
        srcs = " ".join(v.src if isinstance(v, Num) else "-" for v in values)
        rule = next(v.rule for v in values if isinstance(v, Num))
        q.append(etree.Comment(f" src-list={srcs} rule={rule} "))
    rl = element(q, "si:realListXMLList")
    element(rl, "si:valueXMLList", " ".join(_decimal_or_nan(v) for v in values))
    element(rl, "si:unitXMLList", dsi or unit_dsi(unit))


def _contact(parent, tag: str, name: str, address: str | None, email: str | None = None):
    c = element(parent, tag)
    text_element(c, "dcc:name", name)
    if email:
        element(c, "dcc:eMail", email)
    loc = element(c, "dcc:location")
    text_element(loc, "dcc:further", address or "not stated")
    return c


def new_document() -> "etree.Element":
    """The empty dcc:digitalCalibrationCertificate root (schema version 3.3.0)."""
    return etree.Element(f"{{{DCC_NS}}}digitalCalibrationCertificate", nsmap=_NSMAP,
                         schemaVersion=SCHEMA_VERSION)


def administrative_data(root, md: dict, lab: dict | None, *, cert_id: str, norm: str,
                        clauses: list[str], readings_taken: list[str],
                        readings_name: str | None = None,
                        provenance: dict | None = None,
                        findings=None) -> "etree.Element":
    """dcc:administrativeData shared by every specification's DCC: the software, core data
    (identifier, dates, place), the item, laboratory, responsible persons, customer and the
    statements: the specification followed (``norm``, the ``clauses`` calibrated), the place
    of calibration as the laboratory file gives it, the virtual-bench notice and one statement per reading taken (already in English; named
    ``readings_name``, default "Readings taken of the specification's text"). The virtual-bench statement
    is made where the readings' ``provenance`` (or ``md``) say virtual, whatever ``lab`` holds.
    ``findings``: results.json's screening findings, each one the certificate states (all
    but "refused", the identity and other whole-file findings first) as a statement
    (:func:`finding_statements`). Returns the dcc:statements element (a specification adds its own statements)."""
    from gonio import __version__

    L = labels("en")
    prov = {"metadata": md, "provenance": provenance}
    virtual = is_virtual(prov, lab)               # the readings' provenance, not the lab file
    lab_ = lab or {}
    adm = element(root, "dcc:administrativeData")
    sw = element(element(adm, "dcc:dccSoftware"), "dcc:software")
    text_element(sw, "dcc:name", "gonio")
    element(sw, "dcc:release", __version__)
    element(sw, "dcc:type", "application")

    cert = lab_.get("certificate", {})
    core = element(adm, "dcc:coreData")
    element(core, "dcc:countryCodeISO3166_1", "CN")
    element(core, "dcc:usedLangCodeISO639_1", "en")
    element(core, "dcc:mandatoryLangCodeISO639_1", "en")
    element(core, "dcc:uniqueIdentifier", cert_id)
    if cert.get("date_of_receipt"):
        element(core, "dcc:receiptDate", cert["date_of_receipt"])
    date = cert.get("date_of_calibration") or str(md.get("date") or "")[:10] or PLACEHOLDER_DATE
    element(core, "dcc:beginPerformanceDate", date)
    element(core, "dcc:endPerformanceDate", date)
    # only a category (the schema's enumeration); the place entered is the statement "place"
    element(core, "dcc:performanceLocation",
            "other" if virtual else cert.get("location") or "laboratory")
    if cert.get("date_of_issue"):
        element(core, "dcc:issueDate", cert["date_of_issue"])
    rec = record_of(lab)
    if rec.get("replaces"):             # ISO/IEC 17025 7.8.8.3: the report it replaces
        ras = element(core, "dcc:reportAmendedSubstituted")
        element(ras, "dcc:typeOfChange", "amended")
        element(ras, "dcc:replacedUniqueIdentifier", rec["replaces"])

    inst = lab_.get("instrument") or {}
    items = element(adm, "dcc:items")
    it = element(items, "dcc:item")
    text_element(it, "dcc:name", inst.get("description") or str(md.get("instrument") or "instrument"))
    man = inst.get("manufacturer") or md.get("manufacturer")
    if man:
        text_element(element(it, "dcc:manufacturer"), "dcc:name", str(man))
    if inst.get("model") or md.get("model"):
        element(it, "dcc:model", str(inst.get("model") or md.get("model")))
    ids = element(it, "dcc:identifications")
    ident = element(ids, "dcc:identification")
    element(ident, "dcc:issuer", "manufacturer")
    element(ident, "dcc:value", str(inst.get("serial") or md.get("serial") or "not stated"))
    remark, refs = identity_remark(findings)
    text_element(ident, "dcc:name", "serial number" + remark)
    if refs:
        ident.set("refId", refs)

    la = lab_.get("laboratory") or {"name": "gonio virtual bench", "address": None,
                                     "contact": ""}
    _contact(element(adm, "dcc:calibrationLaboratory"), "dcc:contact", la["name"], la["address"],
             la.get("contact") if "@" in (la.get("contact") or "") else None)
    sig = lab_.get("signatory") or {}
    persons = element(adm, "dcc:respPersons")
    people = [(sig.get("calibrated_by"), "calibrated by", False),
              (sig.get("checked_by"), "checked by", False),
              (rec.get("amendment_asked_by"), "amendment asked for by", False),
              (sig.get("approved_by"), "approved by" + (f", {sig['approved_title']}"
                                                        if sig.get("approved_title") else ""),
               True)]
    if not any(p for p, _, _ in people):
        people = [("gonio virtual bench", "none: a virtual-bench example is signed by nobody",
                   True)]
    for who, role, main in people:
        if not who:
            continue
        rp = element(persons, "dcc:respPerson")
        text_element(element(rp, "dcc:person"), "dcc:name", who)
        element(rp, "dcc:role", role)
        element(rp, "dcc:mainSigner", "true" if main else "false")
    cust = lab_.get("customer") or {"name": "not stated", "address": None}
    _contact(adm, "dcc:customer", cust["name"], cust.get("address"))

    sts = element(adm, "dcc:statements")
    st = element(sts, "dcc:statement", id="specification")
    text_element(st, "dcc:name", L["specification"])
    element(st, "dcc:norm", norm)
    text_element(st, "dcc:declaration", "The calibration follows the specification's clauses "
          + ", ".join(clauses) + ".")
    if cert.get("place"):       # dcc:performanceLocation is only a category: the place itself
        st = element(sts, "dcc:statement", id="place")
        text_element(st, "dcc:name", L["place"])
        text_element(st, "dcc:declaration", cert["place"])
    if virtual:
        st = element(sts, "dcc:statement", id="virtual-bench")
        text_element(st, "dcc:name", L["virtual"])
        text_element(st, "dcc:declaration", L["virtual_note"] + (
            f" Performance dates are the placeholder {PLACEHOLDER_DATE}."
            if date == PLACEHOLDER_DATE else ""))
        for i, line in enumerate(virtual_lines(prov, L)[1:], 1):   # bench and seed
            st = element(sts, "dcc:statement", id=f"virtual-bench-readings-{i}")
            text_element(st, "dcc:name", L["virtual"])
            text_element(st, "dcc:declaration", line)
    record_statements(sts, lab, L)
    finding_statements(sts, findings, L)
    for i, note in enumerate(readings_taken, 1):
        st = element(sts, "dcc:statement", id=f"reading-taken-{i}")
        text_element(st, "dcc:name", readings_name or L["readings_taken_std"])
        text_element(st, "dcc:declaration", note)
    return sts


def identity_remark(findings) -> tuple[str, str]:
    """The remark the item's dcc:identification carries where the readings contradict the
    identity or conditions the certificate states (the laboratory chose to proceed), and the
    ids of the statements that state it (its ``refId``): ("", "") where none does.

    >>> identity_remark([{"code": "identity-mismatch", "action": "flagged",
    ...                   "subject": "serial", "message": "serial: the readings say 'A'"}])
    ('; remark: contradicted by the readings (serial: statement finding-1); the laboratory chose to proceed', 'finding-1')
    """
    from gonio.result.findings import identity_subjects

    subjects = identity_subjects(findings)
    if not subjects:
        return "", ""
    said = ", ".join(f"{s}: " + ", ".join(f"statement finding-{i}" for i in ns)
                     for s, ns in subjects.items())
    refs = " ".join(f"finding-{i}" for ns in subjects.values() for i in ns)
    return (f"; remark: contradicted by the readings ({said}); the laboratory chose to "
            "proceed", refs)


def finding_statements(sts, findings, L: dict) -> None:
    """One dcc:statement (dcc:name, dcc:declaration: :func:`gonio.report.i18n.finding_text`,
    the certificate's line) per screening finding the certificate states: a serial the
    readings contradict where the laboratory chose to proceed, readings set aside, planned
    points missing, conditions dropped, a sparse temperature log interpolated. A DCC that
    certifies without them would say less than the certificate."""
    from gonio.result.findings import stated_findings

    for i, f in enumerate(stated_findings(findings), 1):   # identity_remark's numbers
        st = element(sts, "dcc:statement", id=f"finding-{i}")
        text_element(st, "dcc:name", L.get("screening_h", "Screening of the readings"))
        text_element(st, "dcc:declaration", finding_text(f, L))


def record_statements(sts, lab: dict | None, L: dict) -> None:
    """The statements of the laboratory file's ``[record]``: a draft for review, the
    amendment's reason, the whole SHA-256 seal of the result the signatories signed, and the
    number of different people the laboratory requires."""
    rec = record_of(lab)
    made = []
    if is_draft(lab):
        made.append(("record-draft", L["draft_title"], L["draft"] + "."))
    if rec.get("replaces"):
        made.append(("record-amendment", L["amendment_title"],
                     L["amendment"].format(old=rec["replaces"], reason=rec.get(
                         "amendment_reason") or L["not_stated"])))
    if rec.get("seal_sha256"):
        made.append(("record-seal", L["seal"], "The result these signatories signed has the "
                     f"SHA-256 seal {rec['seal_sha256']}; the laboratory's record of it is "
                     "verified against this value."))
    if rec.get("min_people"):
        made.append(("record-people", L["people_required"], L[people_key(rec)]
                     + "."))
    for ident, name, text in made:
        st = element(sts, "dcc:statement", id=ident)
        text_element(st, "dcc:name", name)
        text_element(st, "dcc:declaration", text)


def measurement_result(root, name: str, *, method: str, norm: str,
                       standards: list[dict]) -> "etree.Element":
    """dcc:measurementResults with one dcc:measurementResult: its ``name``, the method
    (``method`` a one-line description, ``norm`` the specification) and the standards used
    (lab-file ``[[standards]]`` rows). Returns the dcc:measurementResult element."""
    L = labels("en")
    mrs = element(root, "dcc:measurementResults")
    mr = element(mrs, "dcc:measurementResult")
    text_element(mr, "dcc:name", name)
    um = element(element(mr, "dcc:usedMethods"), "dcc:usedMethod", id="method")
    text_element(um, "dcc:name", L["method"])
    text_element(um, "dcc:description", method)
    element(um, "dcc:norm", norm)
    eqs = element(mr, "dcc:measuringEquipments")
    for s in standards:
        eq = element(eqs, "dcc:measuringEquipment")
        text_element(eq, "dcc:name", s["name"])
        desc = "; ".join(x for x in (s.get("accuracy"), s.get("certificate") and
                                     f"certificate {s['certificate']}",
                                     s.get("traceability") and
                                     f"traceable to {s['traceability']}") if x)
        if desc:
            text_element(eq, "dcc:description", desc)
        if s.get("identifier"):
            ids = element(eq, "dcc:identifications")
            ident = element(ids, "dcc:identification")
            element(ident, "dcc:issuer", "calibrationLaboratory")
            element(ident, "dcc:value", s["identifier"])
    return mr


def environment_conditions(md: dict, lab: dict | None, temperature_name: str = "temperature",
                           spec: str | None = None) -> list[tuple]:
    """The (name, value, unit) influence conditions of the certificate's environment rows
    (:func:`gonio.report.header.opening_blocks`): the laboratory file's temperature and
    humidity, else the readings' metadata (the temperature under the room temperature keys
    of the specification ``spec``, :func:`gonio.report.header.room_temperature_keys`; None:
    the default keys), each with the certificate's digits
    (:func:`gonio.report.header.condition_text`). A condition neither states is left out."""
    from gonio.report.header import condition_text, room_temperature_keys, room_temperature_text

    env = (lab or {}).get("environment") or {}
    # the records' environment taken from the readings' metadata is stated as such
    tag = " (taken from the readings' metadata)" if env.get("source") == "readings" else ""
    out: list[tuple] = []
    t, tag_t = env.get("temperature_c"), tag
    if t is None:
        t, tag_t = room_temperature_text(md, room_temperature_keys(spec)), ""
    if t not in (None, ""):
        out.append((temperature_name + tag_t, condition_text(t), "degC"))
    h, tag_h = env.get("humidity_pct"), tag
    if h is None:
        h, tag_h = md.get("humidity_pct"), ""
    if h not in (None, ""):
        out.append(("relative humidity" + tag_h, condition_text(h), "%"))
    return out


def influence_conditions(mr, conds: list[tuple]) -> None:
    """dcc:influenceConditions: one per (name, value, unit[, D-SI unit]); a list value is
    written as si:realListXMLList (none: nothing)."""
    if not conds:
        return
    ics = element(mr, "dcc:influenceConditions")
    for nm, v, u, *dsi in conds:
        ic = element(ics, "dcc:influenceCondition")
        text_element(ic, "dcc:name", nm)
        data = element(ic, "dcc:data")
        if isinstance(v, list):
            list_quantity(data, nm, v, u, dsi=dsi[0] if dsi else None)
        else:
            quantity(data, nm, v, u, dsi=dsi[0] if dsi else None)


def not_measured_quantity(data, name: str, reason: str) -> "etree.Element":
    """dcc:quantity of an item not measured: its name and dcc:noQuantity with the reason."""
    q = element(data, "dcc:quantity")
    text_element(q, "dcc:name", name)
    text_element(q, "dcc:noQuantity", f"not measured: {reason}")
    return q


def tree_bytes(root) -> bytes:
    """A DCC element tree as UTF-8 XML bytes, with declaration, pretty-printed."""
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)


