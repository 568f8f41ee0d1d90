"""The laboratory details file (``--lab FILE``): laboratory, certificate, customer,
instrument, standards, environment, signatories, the decision rule and specification limits
agreed with the customer, and a recalibration interval where one was agreed with the customer.

Contents
========
===============================  ==========================================================
:data:`LAB_SCHEMA`               every key of the file, its type and default
:data:`DECISION_RULES`           the decision rules the file may name
:func:`load_lab`                 read and validate the file (example ``protocols/lab-example.toml``)
:func:`naming_lab_file`          errors about its limits found later name the file
:func:`check_one_limit_per_item` one limit per item, never a silent override
:func:`check_interval`           a limit's lower end below its upper end, one end at least
:func:`check_symmetric`          an extreme of magnitudes takes a symmetric limit only
:func:`check_magnitude_extremes` every limit of such an item symmetric, before any work
:func:`check_guard_factor`       a guard band's factor r ≥ 1
:func:`check_date_order`         received, calibrated, issued: the certificate's dates in order
===============================  ==========================================================

The certificate renders what this file holds (ISO/IEC 17025 7.8.2.1, 7.8.4, 7.8.6); the
decisions on its limits are taken by :mod:`gonio.analysis.conformity`.
"""

from __future__ import annotations

import contextlib
from fractions import Fraction
import datetime as _dt
from pathlib import Path

from gonio.errors import GonioError
from gonio.units import same_unit, unit_factor, unit_powers
from gonio.formats.toml import (Field, check_text_fields, non_negative, positive, read_toml,
                                validate_table)

__all__ = ["LAB_SCHEMA", "DECISION_RULES", "RECORD_STATUSES", "LOCATIONS", "load_lab",
           "naming_lab_file", "check_one_limit_per_item", "check_interval", "check_symmetric",
           "check_magnitude_extremes", "check_guard_factor"]

#: Decision rules a laboratory file may name (``[decision_rule] rule = ...``; ILAC-G8:09/2019
#: clause 4, :mod:`gonio.analysis.conformity`).
DECISION_RULES: tuple[str, ...] = ("simple", "guarded", "non-binary")


#: The widest ``[identity] temperature_tolerance_c`` (°C) and ``humidity_tolerance_pct``
#: (percentage points): two statements of one room's conditions further apart are a
#: contradiction, which the laboratory refuses or states (``on_mismatch = "proceed"``),
#: never hides behind a tolerance as wide as the scale.
MAX_TEMPERATURE_TOLERANCE_C = 5.0
MAX_HUMIDITY_TOLERANCE_PCT = 30.0
#: How a certificate stands in the records (``[record] status``): a draft rendered for
#: review (watermarked DRAFT on every page), or issued.
RECORD_STATUSES: tuple[str, ...] = ("draft", "issued")
#: Where a calibration was performed (``[certificate] location``), the categories of the DCC's
#: dcc:performanceLocation (DCC 3.3.0 stringPerformanceLocationType); the place itself is
#: ``[certificate] place``, as text.
LOCATIONS: tuple[str, ...] = ("laboratory", "customer", "laboratoryBranch", "customerBranch",
                              "other")


def _is_sha256(x: str) -> bool:
    return len(x) == 64 and all(c in "0123456789abcdef" for c in x)


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
        "date_of_calibration": _DATE, "place": _S, "procedure": _S,
        "location": Field("str", default="laboratory", choices=LOCATIONS)}),
    "customer": Field("table", schema={"name": Field("str"), "address": _S}),
    "instrument": Field("table", default=None, schema={
        "description": _S, "model": _S, "serial": _S, "manufacturer": _S,
        # an optical gyro's type, compared with the readings' gyro_type (identity)
        "gyro_type": Field("str", default="", check=lambda v: v.strip().lower() in
                           ("", "rlg", "fog"), expect="rlg or fog")}),
    "standards": Field("table_list", default=None, schema={
        "name": Field("str"), "identifier": _S, "accuracy": _S, "certificate": _S,
        "traceability": _S}),
    "environment": Field("table", default=None, schema={
        "temperature_c": Field("float", default=None),
        "humidity_pct": Field("float", default=None, check=lambda h: 0 <= h <= 100,
                              expect="0–100 %"),
        # "readings": the values were taken from the readings' metadata (stated so)
        "source": Field("str", default="entered", choices=("entered", "readings"))}),
    # the readings' identity and conditions against [instrument] and [environment]
    # (gonio.pipeline.identity): a contradiction is refused unless on_mismatch = "proceed"
    "identity": Field("table", default=None, schema={
        "on_mismatch": Field("str", default="refuse", choices=("refuse", "proceed")),
        "temperature_tolerance_c": Field(
            "float", default=None, check=lambda v: 0 <= v <= MAX_TEMPERATURE_TOLERANCE_C,
            expect=f"0–{MAX_TEMPERATURE_TOLERANCE_C:g} °C (a wider one switches the check off: "
                   "state a contradiction with on_mismatch = \"proceed\" instead)"),
        "humidity_tolerance_pct": Field(
            "float", default=None, check=lambda v: 0 <= v <= MAX_HUMIDITY_TOLERANCE_PCT,
            expect=f"0–{MAX_HUMIDITY_TOLERANCE_PCT:g} % (a wider one switches the check off: "
                   "state a contradiction with on_mismatch = \"proceed\" instead)")}),
    "signatory": Field("table", schema={
        "calibrated_by": _S, "checked_by": _S, "approved_by": Field("str"),
        "approved_title": _S}),
    # ISO/IEC 17025 7.1.3 / 7.8.6: the decision rule agreed with the customer, and the
    # specification limits of the items a statement of conformity is asked for
    "decision_rule": Field("table", default=None, schema={
        "rule": Field("str", choices=DECISION_RULES),
        "guard_band_factor": Field("float", default=1.0, check=non_negative, expect="≥ 0"),
        "agreed": _S}),
    "specification_limits": Field("table_list", default=None, schema={
        "item": Field("str"),       # checked against the specification's items when decided
        "lower": Field("float", default=None), "upper": Field("float", default=None),
        "mpe": Field("float", default=None, check=lambda x: x > 0, expect="> 0"),
        # the limit's unit: must be the item's as results.json states it (check_limit_unit)
        "unit": Field("str", default=None,
                      check=lambda s: 0 < len(s.strip()) <= 40 and unit_powers(s) is not None,
                      expect="a unit as results.json states the item's (\"°/h\", \"%\")"),
        "source": _S}),
    # ISO/IEC 17025 7.8.4.3: a certificate recommends a recalibration interval only where
    # one was agreed with the customer; without this table it states none
    "recalibration": Field("table", default=None, schema={
        "interval_months": Field("int", check=positive, expect="> 0"),
        "agreed": Field("str", check=lambda s: s.strip() != "",
                        expect="how and when it was agreed with the customer")}),
    # the rotary table's own calibration (equipment knowledge; a specification that takes a
    # table calibration reads it: gonio.pipeline.equipment), the file relative to this file
    "table_calibration": Field("table", default=None, schema={
        "file": Field("str", check=lambda s: s.strip() != "", expect="a file name"),
        "sha256": Field("str", check=_is_sha256,
                        expect="64 lower-case hexadecimal digits (SHA-256)"),
        "id": _S, "calibrated_on": _DATE,
        "due_on": Field("str", check=_iso_date, expect="a date YYYY-MM-DD")}),
    # how the certificate stands in the laboratory's records (written by ``gonio serve``'s
    # records for every certificate they render): a draft for review, or the issue of a
    # sealed result with the people it required and, for an amendment (ISO/IEC 17025 7.8.8),
    # the certificate it replaces and why
    "record": Field("table", default=None, schema={
        "status": Field("str", default="issued", choices=RECORD_STATUSES),
        "seal_sha256": Field("str", default="", check=lambda s: s == "" or _is_sha256(s),
                             expect="64 lower-case hexadecimal digits (SHA-256)"),
        "min_people": Field("int", default=None, check=lambda n: n in (2, 3),
                            expect="2 or 3"),
        "amendment_asked_by": _S, "replaces": _S, "amendment_reason": _S}),
}


def _dates_to_text(x):
    if isinstance(x, dict):
        return {k: _dates_to_text(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_dates_to_text(v) for v in x]
    if isinstance(x, (_dt.date, _dt.datetime)):
        return x.isoformat()[:10]
    return x


def check_interval(lower: float | None, upper: float | None) -> None:
    """A tolerance interval has one end at least, and its lower end below its upper end.

    >>> check_interval(1.0, 0.5)
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: lower limit 1.0 is not below upper limit 0.5
    """
    if lower is None and upper is None:
        raise GonioError("a specification limit needs lower, upper or mpe")
    if lower is not None and upper is not None and not lower < upper:
        raise GonioError(f"lower limit {lower} is not below upper limit {upper}")


def check_guard_factor(rule: str | None, factor: float | None) -> None:
    """A guard band factor r (w = r·U) of a rule with a guard band ("guarded",
    "non-binary") is at least 1. ILAC-G8:09/2019 4.2.2 guards acceptance with w > 0 inside
    the tolerance; an item stated by its 95 % interval alone is accepted on the interval's
    ends (:func:`gonio.analysis.conformity.interval_guard_U`), and r < 1 would accept an
    interval reaching past the limit by (1 − r)·U (an acceptance limit outside the
    tolerance). r = 0 is simple acceptance: ``rule = "simple"`` says so. None: the default,
    1.

    >>> check_guard_factor("guarded", 1.0), check_guard_factor("simple", 0.0)
    (None, None)
    >>> check_guard_factor("guarded", 0.5)
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: guarded needs guard_band_factor r ≥ 1 (w = r·U, ILAC-G8:09/2019 4.2.2; r < 1 would accept a 95 % interval reaching past the limit; r = 0 is rule = "simple"); got 0.5
    """
    if rule in ("guarded", "non-binary") and factor is not None and not factor >= 1.0:
        raise GonioError(f"{rule} needs guard_band_factor r ≥ 1 (w = r·U, ILAC-G8:09/2019 "
                         "4.2.2; r < 1 would accept a 95 % interval reaching past the limit; "
                         f"r = 0 is rule = \"simple\"); got {factor:g}")


def check_one_limit_per_item(limits, where: str = "specification_limits", *,
                             file=None) -> None:
    """One limit per item: a second entry for the same item is an error naming both, never
    a silent override (the last decision would win in results.json while the certificate
    showed both).

    >>> check_one_limit_per_item([{"item": "R", "mpe": 0.3}, {"item": "R", "mpe": 0.5}])
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key specification_limits[1].item: 'R' has a limit already (specification_limits[0]); give one limit per item
    """
    first: dict = {}
    for i, lim in enumerate(limits or []):
        key = lim.get("item")
        if key in first:
            raise GonioError(f"{key!r} has a limit already ({where}[{first[key]}]); give one "
                             f"limit per item", file=file, key=f"{where}[{i}].item")
        first[key] = i



def check_symmetric(item: str, lower: float | None, upper: float | None, *, file=None,
                    key: str | None = None) -> None:
    """An extreme of magnitudes max_i |x_i| (an item a specification declares so:
    ``Specification.magnitude_extremes``) takes a symmetric limit only (``mpe = M``, or
    ``lower = -M`` with ``upper = M``): max_i |x_i| ≤ M is |x_i| ≤ M at every point, while
    against [T_L, T_U] with T_L ≠ −T_U neither the magnitude nor the signed extreme tells
    whether some x_i of the other sign lies below T_L. Any other limit is a GonioError naming
    ``file`` and ``key``, never a decision on one side.

    >>> check_symmetric("E", -0.4, 0.6, key="specification_limits[0]")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key specification_limits[0]: E is an extreme of magnitudes (max_i |x_i|): its limit must be symmetric (mpe = M, or lower = -M with upper = M); got lower -0.4, upper 0.6
    >>> check_symmetric("E", -0.5, 0.5)
    """
    if lower is None or upper is None or lower != -upper:
        raise GonioError(
            f"{item} is an extreme of magnitudes (max_i |x_i|): its limit must be symmetric "
            f"(mpe = M, or lower = -M with upper = M); got lower {lower}, upper {upper}",
            file=file, key=key)


def check_magnitude_extremes(limits, extremes, *, file=None,
                             where: str = "specification_limits") -> None:
    """Every ``[[specification_limits]]`` entry (``limits``) of an item in ``extremes`` (the
    keys a specification declares extremes of magnitudes) symmetric (:func:`check_symmetric`),
    checked on the file before anything is computed; the error names ``file`` and
    ``where[i]``.

    >>> check_magnitude_extremes([{"item": "E", "mpe": 0.5}, {"item": "R", "upper": 0.3}],
    ...                          ("E",))
    >>> check_magnitude_extremes([{"item": "E", "upper": 0.5}], ("E",), file="lab.toml")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: lab.toml: key specification_limits[0]: E is an extreme of magnitudes (max_i |x_i|): its limit must be symmetric (mpe = M, or lower = -M with upper = M); got lower None, upper 0.5
    """
    for i, lim in enumerate(limits or []):
        if lim.get("item") in extremes and lim.get("mpe") is None:
            check_symmetric(lim["item"], lim.get("lower"), lim.get("upper"), file=file,
                            key=f"{where}[{i}]")


def check_nonnegative(item: str, upper: float | None, *, file=None,
                      key: str | None = None) -> None:
    """An upper limit below zero for an item that cannot be negative (a range, a
    dispersion, a noise level, a time): no value of it can conform, so the limit is a
    mistake of the file (a sign, a unit), a GonioError naming ``file``, ``key`` and the
    item, never a "fail" on a certificate.

    >>> check_nonnegative("B_s", 0.01, key="specification_limits[0].upper")
    >>> check_nonnegative("B_s", -0.01, key="specification_limits[0].upper")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key specification_limits[0].upper: B_s cannot be negative, so its upper limit -0.01 below zero can never be met; check the limit's sign and unit
    """
    if upper is not None and upper < 0:
        raise GonioError(f"{item} cannot be negative, so its upper limit {upper:g} "
                         "below zero can never be met; check the limit's sign and unit",
                         file=file, key=key)


def check_nonnegative_limits(limits, nonnegative, *, file=None,
                             where: str = "specification_limits") -> None:
    """Every ``[[specification_limits]]`` entry (``limits``) of an item in ``nonnegative``
    (the keys, or :mod:`fnmatch` patterns, a specification declares cannot be negative:
    ``Specification.nonnegative_items``) with no ``upper`` below zero
    (:func:`check_nonnegative`), checked when the limits are read or stored, before anything
    is computed; the error names ``file`` and ``where[i].upper``.

    >>> check_nonnegative_limits([{"item": "B_s", "upper": 0.3}, {"item": "E", "upper": -1}],
    ...                          ("B_s",))
    >>> check_nonnegative_limits([{"item": "ARW_x_t2", "upper": -0.1}], ("ARW_[xyz]_t[1-9]",),
    ...                          where="limits")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key limits[0].upper: ARW_x_t2 cannot be negative, so its upper limit -0.1 below zero can never be met; check the limit's sign and unit
    """
    from fnmatch import fnmatchcase

    for i, lim in enumerate(limits or []):
        item = lim.get("item")
        if isinstance(item, str) and any(fnmatchcase(item, k) for k in nonnegative):
            check_nonnegative(item, lim.get("upper"), file=file, key=f"{where}[{i}].upper")

def _limit_text(x: float) -> str:
    """A limit's number as a message writes it back: %g where that keeps it, else repr."""
    text = f"{x:g}"
    return text if float(text) == x else repr(x)


def check_limit_unit(item: str, lim: dict, item_unit: str | None, *, file=None,
                     key: str | None = None) -> None:
    """A limit's stated ``unit`` (``lim["unit"]``) must be the item's unit as results.json
    states it (``item_unit``), however spelt (:func:`gonio.units.same_unit`: "°/h", "deg/h"
    and "º/h" are one unit). A limit is compared with the value as given, never converted, so
    any other unit is a GonioError naming ``key`` (the entry's ``.unit``), the limit's unit
    and the item's: one the item's converts to exactly (:func:`gonio.units.unit_factor`:
    °/s and °/h, % and ppm, ″ and °) with the limit written in the item's unit, one that
    does not ("mV/(°/s)" for "%") as not the item's. Without ``unit`` the limit is in the
    item's unit (nothing to check).

    >>> check_limit_unit("bias", {"unit": "deg/h", "mpe": 36}, "°/h")
    >>> check_limit_unit("bias", {"unit": "°/s", "mpe": 0.01}, "deg/h", key="limits[0].unit")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key limits[0].unit: bias: limit in °/s for an item in deg/h (1 °/s = 3600 deg/h): write mpe = 36 with unit = "deg/h" (a limit is compared as given, never converted)
    >>> check_limit_unit("K_n", {"unit": "ppm", "upper": 5}, "%")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: K_n: limit in ppm for an item in % (1 ppm = 0.0001 %): write upper = 0.0005 with unit = "%" (a limit is compared as given, never converted)
    >>> check_limit_unit("K", {"unit": "mV/(°/s)", "mpe": 1}, "%")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: K: limit in mV/(°/s) for an item in %: not the item's unit as results.json states it, and not convertible to it; give the limit in %
    """
    unit = lim.get("unit")
    if unit is None or same_unit(unit, item_unit):
        return
    shown = item_unit or "1"
    factor = unit_factor(unit, item_unit)
    if factor is None:
        raise GonioError(f"{item}: limit in {unit} for an item in {shown}: not the item's unit "
                         f"as results.json states it, and not convertible to it; give the "
                         f"limit in {shown}", file=file, key=key)
    ends = ", ".join(f"{k} = {_limit_text(float(Fraction(repr(float(lim[k]))) * factor))}"
                     for k in ("mpe", "lower", "upper") if lim.get(k) is not None)
    raise GonioError(f"{item}: limit in {unit} for an item in {shown} (1 {unit} = "
                     f"{_limit_text(float(factor))} {shown}): write {ends} with unit = "
                     f"\"{shown}\" (a limit is compared as given, never converted)",
                     file=file, key=key)


#: ``[record]`` keys only the records write, for the sealed result they issue and render again
#: (:func:`gonio.records.compute.render_folder`): a seal, the people the issue required, an
#: amendment's certificate replaced, its reason and who asked for it.
ISSUE_RECORD_KEYS: tuple[str, ...] = ("seal_sha256", "min_people", "replaces",
                                      "amendment_reason", "amendment_asked_by")


def check_no_issue_record(lab: dict | None, file=None) -> None:
    """Refuse a laboratory file whose ``[record]`` states an issue (a seal, the people
    required, an amendment) for a certificate computed now (``gonio calibrate``, ``gonio
    demo``): those are written by the records for the result they sealed and issue, and a
    certificate would print "the laboratory's record of this result is verified against it"
    beside a seal that no record holds. ``[record] status = "draft"`` (the review copy) stays.

    >>> check_no_issue_record({"record": {"status": "draft", "seal_sha256": ""}})
    >>> check_no_issue_record({"record": {"status": "issued", "seal_sha256": "ab" * 32}},
    ...                       "lab.toml")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: lab.toml: key record.seal_sha256: written by the records for a result they sealed and issue, never given to a calibration computed now (it would print a seal no record holds): remove it, or issue through the records
    """
    rec = (lab or {}).get("record") or {}
    for key in ISSUE_RECORD_KEYS:
        if rec.get(key) not in (None, ""):
            raise GonioError("written by the records for a result they sealed and issue, "
                             "never given to a calibration computed now (it would print a "
                             "seal no record holds): remove it, or issue through the records",
                             file=None if file is None else str(file), key=f"record.{key}")


#: The certificate's dates in the order they must fall (each given one on or after the
#: one before it): the item is received, then calibrated, then the certificate issued.
DATE_ORDER: tuple[str, ...] = ("date_of_receipt", "date_of_calibration", "date_of_issue")


def check_date_order(certificate: dict, file=None) -> None:
    """The ``[certificate]`` dates given in :data:`DATE_ORDER`: a certificate issued before
    the calibration, or an item received after it was calibrated, is a GonioError naming
    both keys and dates (an empty date is not compared).

    >>> check_date_order({"date_of_receipt": "2026-11-02", "date_of_calibration": "",
    ...                   "date_of_issue": "2026-11-20"})
    >>> check_date_order({"date_of_calibration": "2026-11-20", "date_of_issue": "2026-11-10"},
    ...                  "lab.toml")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: lab.toml: key certificate.date_of_issue: date_of_issue 2026-11-10 is before date_of_calibration 2026-11-20; the certificate is issued on or after the calibration
    """
    given = [(k, str(certificate.get(k) or "")) for k in DATE_ORDER]
    given = [(k, v) for k, v in given if v]
    for (ka, va), (kb, vb) in zip(given, given[1:]):
        if _dt.date.fromisoformat(vb) < _dt.date.fromisoformat(va):
            why = ("the certificate is issued on or after the "
                   + ("calibration" if ka == "date_of_calibration" else "receipt")
                   if kb == "date_of_issue" else "the item is calibrated on or after its receipt")
            raise GonioError(f"{kb} {vb} is before {ka} {va}; {why}",
                             file=None if file is None else str(file),
                             key=f"certificate.{kb}")


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
    check_date_order(lab["certificate"], path)
    limits = lab["specification_limits"] or []
    check_one_limit_per_item(limits, file=path)
    for i, lim in enumerate(limits):
        key = f"specification_limits[{i}]"
        if lim["mpe"] is not None and (lim["lower"] is not None or lim["upper"] is not None):
            raise GonioError("give mpe or lower/upper, not both", file=path, key=key)
        try:
            if lim["mpe"] is None:
                check_interval(lim["lower"], lim["upper"])
        except GonioError as exc:
            raise GonioError(exc.message, file=path, key=key) from None
    if lab["decision_rule"] is not None:
        try:
            check_guard_factor(lab["decision_rule"].get("rule"),
                               lab["decision_rule"].get("guard_band_factor"))
        except GonioError as exc:
            raise GonioError(exc.message, file=path,
                             key="decision_rule.guard_band_factor") from None
    if limits and lab["decision_rule"] is None:
        raise GonioError("specification limits need the decision rule agreed "
                         "([decision_rule] rule = simple | guarded | non-binary)", file=path,
                         key="decision_rule")
    _keep_condition_digits(lab["environment"], path)
    return lab


class WrittenNumber(float):
    """A number of a file that keeps the text it was written as (``text``): a laboratory
    file's ``temperature_c = 20.0`` states its resolution as a logger's "20.0" does, so the
    certificate and the DCC print "20.0", not "20" (:func:`gonio.report.header.condition_text`).
    It is the float everywhere else, pickled and copied with its text.

    >>> t = WrittenNumber(20.0, "20.0")
    >>> t == 20.0, t.text, __import__("copy").deepcopy(t).text, __import__("json").dumps(t)
    (True, '20.0', '20.0', '20.0')
    """

    text: str

    def __new__(cls, value: float, text: str):
        obj = super().__new__(cls, value)
        obj.text = text
        return obj

    def __reduce__(self):
        return (WrittenNumber, (float(self), self.text))


def _keep_condition_digits(env: dict, path) -> None:
    """The ``[environment]`` numbers of laboratory file ``path`` as :class:`WrittenNumber`
    with their text in the file (TOML's own number text, underscores dropped)."""
    import tomllib

    from gonio.errors import read_utf8

    if not env or all(env.get(k) is None for k in ("temperature_c", "humidity_pct")):
        return
    try:
        raw = tomllib.loads(read_utf8(Path(path), "TOML file"),
                            parse_float=lambda t: t).get("environment") or {}
    except (tomllib.TOMLDecodeError, GonioError, OSError):
        return                                # already read once: keep the numbers as read
    for key in ("temperature_c", "humidity_pct"):
        text = raw.get(key)
        if isinstance(text, int) and not isinstance(text, bool):
            text = str(text)          # an integer ("20"): its digits, no decimal
        if env.get(key) is not None and isinstance(text, str):
            text = text.replace("_", "")
            if float(text) == env[key]:
                env[key] = WrittenNumber(env[key], text)


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
