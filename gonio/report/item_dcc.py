"""The Digital Calibration Certificate (PTB DCC 3.3.0) of any per-item result, with the
matrices a specification names written as lists (its ``MATRICES``; any plug-in's DCC).

Contents
========
=========================  ==============================================================
:func:`compose_dsi`        a composed results.json unit ("lsb/(°/s)/°C^2") in D-SI form
:func:`item_dcc_tree`      the DCC document as an lxml element tree
:func:`item_dcc_bytes`     the same as UTF-8 bytes (deterministic)
=========================  ==============================================================

administrativeData is the optical and rate DCC's (:func:`gonio.report.dcc.administrative_data`,
English and Chinese side by side where the specification gives both). measurementResults
holds one dcc:result per item: a dcc:quantity with the value, D-SI unit and expanded
uncertainty (U, k, p) as the certificate states them (:func:`gonio.report.stated.item_nums`,
the one statement rule), or a dcc:noQuantity with the reason; then one dcc:result per matrix
the specification lists (``MATRICES`` of its certificate data: name, item keys row by row)
as an si:realListXMLList with its si:expandedMUXMLList. Conformity statements
(``items.<key>.conformity``) go into the statements as in the other DCCs. An item stated by
a bound-condition interval, whose u_c the certificate does not state (:func:`u_c_certified`),
has its interval's ends written without a standard uncertainty (:func:`interval_quantity`).
"""

from __future__ import annotations

import math
import re

from gonio.errors import GonioError
from gonio.report.dcc import (BOUND_INTERVAL, administrative_data, below_zero_quantity,
                              bound_interval_text,
                              conformity_statements,
                              interval_quantity, stated_p,
                              element, environment_conditions, influence_conditions,
                              measurement_result, new_document, not_measured_quantity, nu_quantity,
                              quantity, text_element, tree_bytes)
from gonio.report.i18n import labels
from gonio.report.stated import item_nums, u_c_certified
from gonio.result.statement import dsi_unit, p_text

#: Output units of a sensor (counts of its digital output) → D-SI.
_HEADS = ((r"lsb/(°/s)", r"\one\degree\tothe{-1}\second"), (r"counts/(°/s)",
          r"\one\degree\tothe{-1}\second"), (r"mV/(°/s)", r"\milli\volt\degree\tothe{-1}\second"),
          ("lsb", r"\one"), ("counts", r"\one"), ("°/s", r"\degree\second\tothe{-1}"),
          ("°/√h", r"\degree\hour\tothe{-0.5}"), ("°/h", r"\degree\hour\tothe{-1}"))
_PER = {"°C": r"\kelvin", "V": r"\volt", "s": r"\second", "h": r"\hour"}


def compose_dsi(unit: str, extra=None) -> str:
    """A results.json unit in D-SI form: a known unit (:func:`gonio.result.statement.dsi_unit`),
    one of the specification's own (``extra``: its ``Specification.dcc_units``), or a
    sensor-output head followed by "/°C^n", "/V^n" divisors (a temperature difference of
    1 °C is 1 K). An unknown unit is a GonioError naming it.

    >>> compose_dsi("lsb/(°/s)/°C^2"), compose_dsi("°/s/V"), compose_dsi("1")
    ('\\\\one\\\\degree\\\\tothe{-1}\\\\second\\\\kelvin\\\\tothe{-2}', '\\\\degree\\\\second\\\\tothe{-1}\\\\volt\\\\tothe{-1}', '\\\\one')
    """
    known = dsi_unit(unit)
    if known is not None and known[1] == 1.0:
        return known[0]
    if extra and unit in extra:
        return extra[unit]
    for head, dsi in _HEADS:
        if unit.startswith(head):
            rest, out = unit[len(head):], dsi
            for m in re.finditer(r"/([^/^]+)(?:\^(\d+))?", rest):
                if m.group(1) not in _PER:
                    break
                out += _PER[m.group(1)] + r"\tothe{-" + (m.group(2) or "1") + "}"
            else:
                if re.fullmatch(r"(?:/[^/^]+(?:\^\d+)?)*", rest):
                    return out
    raise GonioError(f"unit {unit!r} has no D-SI form for the DCC", key="unit")


def _p(it: dict) -> float | None:
    unc = it.get("uncertainty") or {}
    p = unc.get("coverage_probability")
    return unc.get("p") if p is None else p


def item_dcc_tree(result, *, lab: dict | None = None, cert_id: str, data=None,
                  coverage_probability: float | None = None) -> "etree.Element":
    """The DCC 3.3.0 document of a per-item result (module docstring). ``data`` is the
    specification's certificate data (``MATRICES``, ``HEADING``), ``coverage_probability``
    the p of items whose own record leaves it out."""
    from gonio.specs import content_field, get

    res = result.to_json()
    md = res.get("metadata", {})
    spec = get(res.get("spec") or result.spec_key)
    items = res["items"]
    norm = (content_field(data, "NORM") or (spec.title_en,))[0]
    root = new_document()
    sts = administrative_data(root, md, lab, cert_id=cert_id, norm=norm,
                              provenance=res.get("provenance"), findings=res.get("findings"),
                              clauses=list(dict.fromkeys(it["clause"] for it in items.values()
                                                         if it["measured"])),
                              readings_taken=list(res.get("readings_taken", [])),
                              readings_name="Reading taken of the sources")
    src = res["source"]
    heading = (content_field(data, "HEADING") or (spec.title_en,))[0]
    mr = measurement_result(
        root, heading, method=f"{spec.title_en}; readings {src.get('file')} (SHA-256 "
                              f"{src.get('sha256')})", norm=norm,
        standards=(lab or {}).get("standards") or [
            {"name": str(md.get("bench") or md.get("table") or "rate table"),
             "identifier": "", "accuracy": "", "certificate": "",
             "traceability": "none (virtual bench)" if lab is None else "not stated"}])
    influence_conditions(mr, environment_conditions(md, lab, spec=spec.key))
    results = element(mr, "dcc:results")
    for key, it in items.items():
        r = element(results, "dcc:result", id=f"result-{key}")
        text_element(r, "dcc:name", f"{it['title']} ({it['clause']})")
        d = element(r, "dcc:data")
        name = f"{it['title']} ({spec.key} {it['clause']})"
        if not it["measured"] or it["value"] is None or not math.isfinite(it["value"]):
            not_measured_quantity(d, name, it.get("reason") or "no finite value")
            continue
        n = item_nums(it, f"items.{key}")
        p = _p(it) if _p(it) is not None else coverage_probability
        kw, bound = {}, None
        if n["U"] is not None and n["k"] is not None and p is not None:
            kw = {"U": n["U"], "k": n["k"], "p": float(p)}
        elif n["interval"] is not None and not u_c_certified(it) and p is not None:
            bound = n["interval"]["ends"]               # its ends, no valueStandardMU
        elif n["interval"] is not None and n["interval"]["u"] and p is not None:
            kw = {"interval": n["interval"]["ends"], "u_std": n["interval"]["u"],
                  "p": float(p)}                       # stated by its coverage interval
        st = n.get("statement")
        dsi = compose_dsi(it["unit"], spec.dcc_units)
        if st is not None and st.below_zero and p is not None:
            # its upper bound alone: the interval [0, upper], no si:value
            below_zero_quantity(d, name, n["interval"]["ends"], dsi, float(p),
                                description=st.text())
            nu_quantity(d, name, n["interval_nu"], n["chi2_nu"] is not None)
            continue
        quantity(d, name, n["stated_value"], "", dsi=dsi, ref_type="basic_measuredValue",
                 description=st.text() if st is not None and st.widened is not None else None,
                 **kw)
        if bound is not None:
            interval_quantity(d, name, bound, dsi, float(p), bound_interval_text(it))
        # the ν printed beside an interval: a χ² interval's, or its k's ν_eff
        nu_quantity(d, name, n["interval_nu"], n["chi2_nu"] is not None)
    for mname, keys in content_field(data, "MATRICES"):
        flat = [k for row in keys for k in row]
        if not all(k in items and items[k]["measured"] for k in flat):
            continue
        matrix_result(results, mname, flat, items, coverage_probability)
    conformity_statements(sts, items, lambda k: items[k]["title"],
                          lambda k: (compose_dsi(items[k]["unit"], spec.dcc_units), 1.0),
                          labels("en"))
    return root


def matrix_result(results, name: str, keys: list[str], items: dict,
                  p_default: float | None) -> None:
    """One dcc:result holding a matrix (row by row) as si:realListXMLList, each element
    with its expanded uncertainty as the item states it."""
    from lxml import etree

    from gonio.report.dcc import dsi_decimal

    ns = [item_nums(items[k], f"items.{k}") for k in keys]
    r = element(results, "dcc:result", id=f"matrix-{re.sub(r'[^A-Za-z0-9]+', '-', name)}")
    text_element(r, "dcc:name", f"{name} (row by row: {', '.join(keys)})")
    q = element(element(r, "dcc:data"), "dcc:quantity", refType="basic_measuredValue")
    text_element(q, "dcc:name", name)
    q.append(etree.Comment(" src-list=" + " ".join(f"items.{k}.value" for k in keys) + " "))
    rl = element(q, "si:realListXMLList")
    element(rl, "si:labelXMLList", " ".join(keys))
    element(rl, "si:valueXMLList", " ".join(dsi_decimal(str(n["stated_value"])) for n in ns))
    element(rl, "si:unitXMLList", " ".join(compose_dsi(items[k]["unit"]) for k in keys))
    if all(n["U"] is not None and n["k"] is not None for n in ns):
        ps = [(_p(items[k]) if _p(items[k]) is not None else p_default) for k in keys]
        if all(p is not None for p in ps):
            mu = element(element(rl, "si:measurementUncertaintyUnivariateXMLList"),
                         "si:expandedMUXMLList")
            element(mu, "si:valueExpandedMUXMLList", " ".join(dsi_decimal(str(n["U"]))
                                                              for n in ns))
            element(mu, "si:coverageFactorXMLList", " ".join(dsi_decimal(str(n["k"]))
                                                             for n in ns))
            element(mu, "si:coverageProbabilityXMLList", " ".join(stated_p(p) for p in ps))
    elif all(n["interval"] is not None for n in ns) and not all(
            u_c_certified(items[k]) for k in keys):
        # bound-condition intervals: their ends as two lists, no standard uncertainty
        ps = [(_p(items[k]) if _p(items[k]) is not None else p_default) for k in keys]
        if all(p is not None for p in ps):
            d = q.getparent()
            for end, label in ((0, "intervalMin"), (1, "intervalMax")):
                qe = element(d, "dcc:quantity", refType="basic_measurementUncertainty")
                text_element(qe, "dcc:name", f"{name}: {label} of each element's "
                             f"{BOUND_INTERVAL}; p = "
                             f"{', '.join(dict.fromkeys(p_text(p) for p in ps))} %")
                el = element(qe, "si:realListXMLList")
                element(el, "si:labelXMLList", " ".join(keys))
                element(el, "si:valueXMLList", " ".join(
                    dsi_decimal(str(n["interval"]["ends"][end])) for n in ns))
                element(el, "si:unitXMLList", " ".join(compose_dsi(items[k]["unit"])
                                                       for k in keys))
    elif all(n["interval"] is not None and n["interval"]["u"] for n in ns):
        # every element stated by its coverage interval alone: the list's coverage
        # intervals, as each item's own result states it
        ps = [(_p(items[k]) if _p(items[k]) is not None else p_default) for k in keys]
        if all(p is not None for p in ps):
            mu = element(element(rl, "si:measurementUncertaintyUnivariateXMLList"),
                         "si:coverageIntervalMUXMLList")
            element(mu, "si:valueStandardMUXMLList", " ".join(
                dsi_decimal(str(n["interval"]["u"])) for n in ns))
            element(mu, "si:intervalMinXMLList", " ".join(
                dsi_decimal(str(n["interval"]["ends"][0])) for n in ns))
            element(mu, "si:intervalMaxXMLList", " ".join(
                dsi_decimal(str(n["interval"]["ends"][1])) for n in ns))
            element(mu, "si:coverageProbabilityXMLList", " ".join(stated_p(p) for p in ps))


def item_dcc_bytes(result, *, lab: dict | None = None, cert_id: str, data=None,
                   coverage_probability: float | None = None) -> bytes:
    """The DCC as UTF-8 XML bytes, with declaration, pretty-printed, deterministic."""
    return tree_bytes(item_dcc_tree(result, lab=lab, cert_id=cert_id, data=data,
                                    coverage_probability=coverage_probability))
