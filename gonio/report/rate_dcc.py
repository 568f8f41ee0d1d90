"""The Digital Calibration Certificate (PTB DCC 3.3.0) of a rate-gyro calibration
(JJF 1535-2015, IEC 62047-20), built on the shared builders of :mod:`gonio.report.dcc`.

Contents
========
=========================  ==============================================================
:data:`OUTPUT_DSI`         the readings' ``output_unit`` → D-SI of the scale factor
:func:`dsi_unit`           the (D-SI unit, factor) of an item's unit
:func:`clause_ref_type`    the refType naming an item's clause
:func:`rate_dcc_tree`      the DCC document as an lxml element tree
:func:`rate_dcc_bytes`     the same as UTF-8 bytes (deterministic)
=========================  ==============================================================

What the rate DCC holds:

administrativeData
    as the optical-gyro DCC (:func:`gonio.report.dcc.administrative_data`): software,
    core data, item, laboratory, persons, customer; statements: the specification and
    the clauses calibrated, the virtual-bench notice, every reading taken, and how U is
    stated (k = t₉₅(ν_eff), p = 95 %).
measurementResults
    the method (specification, protocol, readings file and its SHA-256), the standards,
    the influence conditions (room temperature, nominal supply voltage, site latitude,
    and the settings the items were measured at: scale-factor rates, chamber temperature
    points, supply voltages, vibration frequencies — each a list with its D-SI unit), and
    one dcc:result per item in the certificate's groups (JJF 1535 Annex B; IEC 62047-20
    clause 5): a dcc:quantity whose name carries the clause and whose ``refType`` names it
    (:func:`clause_ref_type`), with the value, the D-SI unit and the expanded uncertainty
    (U, k, p), or its coverage interval (an item stated by a χ² interval with that
    interval's ν beside it, :func:`gonio.report.dcc.nu_quantity`); an item not measured is
    a dcc:noQuantity with its reason.

Numbers are the ones the certificate prints (value 4 significant digits, U 2, k 3;
:func:`gonio.report.i18n.display`); an XML comment before each si:real records its path
in results.json, its display rule and, for the per-g items, the factor applied: D-SI has
no unit for the standard acceleration of gravity, so (°/h)/g and (°/s)/g are written per
m s⁻² (value and U divided by g_n = 9.80665 m s⁻²). Temperature coefficients are per
kelvin (a difference of 1 °C is 1 K).
"""

from __future__ import annotations

import math

import numpy as np
from lxml import etree

from gonio.errors import GonioError
from gonio.report.stated import Num
from gonio.report.dcc import (administrative_data, below_zero_quantity, bound_interval_text,
                              conformity_statements,
                              element, environment_conditions, influence_conditions,
                              interval_quantity, measurement_result, new_document,
                              not_measured_quantity, nu_quantity, quantity, text_element,
                              tree_bytes)
from gonio.report.i18n import display, labels
from gonio.report.rate_content import item_conditions, rate_standards, spec_content
from gonio.report.stated import item_nums, u_c_certified
from gonio.result.statement import DSI_UNITS
from gonio.specs import get
from gonio.units import STANDARD_GRAVITY_M_S2

#: The readings' ``output_unit`` → the D-SI unit of the scale factor (output per °/s).
OUTPUT_DSI: dict[str, str] = {
    "mV": r"\milli\volt\degree\tothe{-1}\second",
    "V": r"\volt\degree\tothe{-1}\second",
    "µV": r"\micro\volt\degree\tothe{-1}\second",
    "counts/s": r"\one\degree\tothe{-1}",
    "counts": r"\one\degree\tothe{-1}\second",
    "lsb": r"\one\degree\tothe{-1}\second",
    "LSB": r"\one\degree\tothe{-1}\second",
    "°/s": r"\one",
}

#: Settings the items were measured at (influence conditions): (item, details key, name, D-SI).
SETTINGS = (
    ("scale_factor", "rates_dps", "scale-factor input rates", r"\degree\second\tothe{-1}"),
    ("scale_factor", "x_dps", "scale-factor input rates", r"\degree\second\tothe{-1}"),
    ("sf_temperature_sensitivity", "temperatures_c", "chamber temperature points",
     r"\degreecelsius"),
    ("sf_temperature_coefficient", "temperatures_c", "chamber temperature points",
     r"\degreecelsius"),
    ("ratiometric_error", "V", "supply voltages", r"\volt"),
    ("bandwidth", "freq_hz", "angular vibration frequencies", r"\hertz"),
    ("frequency_band", "freq_hz", "angular vibration frequencies", r"\hertz"),
)


def dsi_unit(unit: str, output_unit: str, file=None, extra=None) -> tuple[str, float]:
    """(D-SI unit, factor) of a rate item's results.json ``unit``: the one unit table
    (:data:`gonio.result.statement.DSI_UNITS`); the scale factor's
    ``<output>/(°/s)`` through :data:`OUTPUT_DSI`; a unit of the specification's own
    (``extra``: its ``Specification.dcc_units``, {unit: D-SI}) with factor 1. An unknown unit
    is a GonioError naming it.

    >>> dsi_unit("mV/(°/s)", "mV")
    ('\\\\milli\\\\volt\\\\degree\\\\tothe{-1}\\\\second', 1.0)
    >>> dsi_unit("(°/s)/g", "mV")[1] * 9.80665
    1.0
    """
    if unit == f"{output_unit}/(°/s)":
        if output_unit not in OUTPUT_DSI:
            raise GonioError(f"output unit {output_unit!r} has no D-SI form for the DCC "
                             f"(known: {', '.join(OUTPUT_DSI)}); calibrate without --dcc",
                             file=file, key="output_unit")
        return OUTPUT_DSI[output_unit], 1.0
    if unit in DSI_UNITS:
        return DSI_UNITS[unit]
    if extra and unit in extra:
        return extra[unit], 1.0
    raise GonioError(f"unit {unit!r} has no D-SI form for the DCC (a specification states "
                     "its own units in Specification.dcc_units)", file=file, key="unit")


def clause_ref_type(spec_key: str, clause: str) -> str:
    """The refType of an item's quantity: ``gonio_<spec>_clause_<clause>`` (no spaces).

    >>> clause_ref_type("lab-procedure", "5.4.5.1 b)")
    'gonio_lab-procedure_clause_5.4.5.1b'
    """
    c = "".join(ch for ch in clause if ch.isalnum() or ch == ".")
    return f"gonio_{spec_key}_clause_{c}"


def _plain(v: float) -> str:
    """A setting as a plain si:decimal (no exponent)."""
    return np.format_float_positional(float(v), trim="-")


def _conditions(res: dict, lab: dict | None) -> list[tuple]:
    md = res.get("metadata", {})
    out: list[tuple] = environment_conditions(md, lab, "room temperature", res.get("spec"))
    if md.get("supply_nominal_v") not in (None, ""):
        out.append(("nominal supply voltage", _plain(md["supply_nominal_v"]), "",
                    r"\volt"))
    if md.get("latitude_deg") not in (None, ""):
        out.append(("latitude of the site (Earth-rate components)", _plain(md["latitude_deg"]),
                    "deg"))
    seen = set()
    for key, det, name, dsi in SETTINGS:
        it = res["items"].get(key)
        vals = (it or {}).get("details", {}).get(det) if it and it["measured"] else None
        if name in seen or not isinstance(vals, list) or not vals:
            continue
        seen.add(name)
        out.append((name, [_plain(v) for v in vals], "", dsi))
    return out


def rate_dcc_tree(result, *, lab: dict | None = None, cert_id: str) -> "etree.Element":
    """The DCC 3.3.0 document of a rate-gyro calibration (module docstring)."""
    res = result.to_json()
    md = res.get("metadata", {})
    spec = get(result.spec_key)
    content = spec_content(result.spec_key)
    items = res["items"]
    root = new_document()
    sts = administrative_data(
        root, md, lab, cert_id=cert_id, norm=spec.title_en, provenance=res.get("provenance"), findings=res.get("findings"),
        clauses=[it["clause"] for it in items.values() if it["measured"]],
        readings_taken=list(res.get("readings_taken", [])),
        readings_name="Reading taken of the specification's text")
    st = element(sts, "dcc:statement", id="uncertainty")
    text_element(st, "dcc:name", "Uncertainty of measurement")
    text_element(st, "dcc:declaration",
                 "Each item's expanded uncertainty U = k·u_c is computed from the calibration's "
                 "own data (JCGM 100), with k = t95(ν_eff) (Welch–Satterthwaite), coverage "
                 "probability 95 %; the components are in results.json.")
    src = res["source"]
    mr = measurement_result(
        root, content.HEADING[0],
        method=f"{spec.title_en}; protocol {md.get('protocol', 'not stated')}; readings "
               f"{src['file']} (SHA-256 {src['sha256']}, {src['rows']} rows)",
        norm=spec.title_en, standards=rate_standards(md, lab))
    influence_conditions(mr, _conditions(res, lab))
    results = element(mr, "dcc:results")
    out_unit = str(md.get("output_unit", "output"))
    conditions = dict(item_conditions(res, content))    # the certificate's sentences
    for _, group_en, _, keys in content.GROUPS:
        for key in keys:
            it = items.get(key)
            if it is None:
                continue
            r = element(results, "dcc:result", id=f"result-{key}")
            text_element(r, "dcc:name", f"{group_en}: {it['title']} ({it['clause']})")
            if key in conditions:        # what defines the measurand (JJF 7.2.9: W, P, nominal)
                text_element(r, "dcc:description", conditions[key])
            data = element(r, "dcc:data")
            name = f"{it['title']} ({spec.key} {it['clause']})"
            value = it["value"]
            if not it["measured"] or value is None or not math.isfinite(value):
                not_measured_quantity(data, name, it["reason"] or "no finite value")
                continue
            dsi, factor = dsi_unit(it["unit"], out_unit, src["file"], spec.dcc_units)
            n = item_nums(it, f"items.{key}", factor=factor)     # the certificate's rule
            kw, bound = {}, None
            if n["U"] is not None and n["k"] is not None and n["p"] is not None:
                kw = {"U": n["U"], "k": n["k"], "p": float(item_p(it))}
            elif n["interval"] is not None and not u_c_certified(it) and n["p"] is not None:
                bound = n["interval"]["ends"]         # its ends, no valueStandardMU
            elif n["interval"] is not None and n["interval"]["u"] and n["p"] is not None:
                kw = {"interval": n["interval"]["ends"], "u_std": n["interval"]["u"],
                      "p": float(item_p(it))}         # stated by its coverage interval
            conv = factor != 1.0
            st = n["statement"]
            if st.below_zero:          # its upper bound alone: [0, upper], no si:value
                below_zero_quantity(data, name, n["interval"]["ends"], dsi, float(item_p(it)),
                                    description=_converted(st, it, key, factor))
                nu_quantity(data, name, n["interval_nu"], n["chi2_nu"] is not None)
                continue
            quantity(data, name, n["stated_value"], "", dsi=dsi,
                     note=f" factor={factor!r}" if conv else "",
                     ref_type=f"basic_measuredValue {clause_ref_type(spec.key, it['clause'])}",
                     description=(_converted(st, it, key, factor)
                                  if conv or st.widened is not None else None), **kw)
            if bound is not None:
                interval_quantity(data, name, bound, dsi, float(item_p(it)),
                                  bound_interval_text(it))
            # the ν printed beside an interval: a χ² interval's, or its k's ν_eff
            nu_quantity(data, name, n["interval_nu"], n["chi2_nu"] is not None)
    conformity_statements(sts, items, lambda k: items[k]["title"],
                          lambda k: dsi_unit(items[k]["unit"], out_unit, src["file"],
                                           spec.dcc_units),
                          labels("en"))
    return root


def _converted(st, it: dict, key: str, factor: float) -> str:
    """The description of an item's DCC quantity: its statement (``st``, in the DCC's unit),
    and where the DCC writes it in another unit than the certificate (a per-g item per
    m s⁻², ``factor`` ≠ 1) the certificate's statement in results.json's unit."""
    if factor == 1.0:
        return st.text()            # with the note of ends widened for the draws, if any
    return (f"{item_nums(it, f'items.{key}')['statement'].text()} in results.json, written "
            f"per m s⁻² (g_n = {STANDARD_GRAVITY_M_S2} m s⁻²)")


def item_p(it: dict) -> float | None:
    """The coverage probability of an item's U (``coverage_probability``, or ``p``)."""
    unc = it.get("uncertainty") or {}
    p = unc.get("coverage_probability")
    return unc.get("p") if p is None else p


def rate_dcc_bytes(result, *, lab: dict | None = None, cert_id: str) -> bytes:
    """The rate DCC as UTF-8 XML bytes, with declaration, pretty-printed, deterministic."""
    return tree_bytes(rate_dcc_tree(result, lab=lab, cert_id=cert_id))
