"""From a readings file to results: the seven characteristics and the Annex A budget.

:func:`calibrate` is the specification's ``SPEC.calibrate`` (what ``gonio calibrate`` and
``gonio demo`` run); it returns the one sealed :class:`~gonio.result.model.Result`
(:func:`analyse` keeps the analysis objects in memory, :class:`Analysis`), and
:func:`gonio.specs.ogam_draft.outputs.write_calibration` writes ``results.json``,
``summary.txt`` and the detail tables as CSV, atomically. The uncertainty of the angle-position deviation is the
Annex A budget with u(r) taken from the calibration's own repeatability data
(7.5) when present, else the protocol's Annex A value; the table MPE and tilt
bound come from the file's metadata when given, else from the protocol.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from gonio.formats.jsonsafe import json_safe
from gonio import __version__
from gonio.atomic import sha256_file
from gonio.resources import protocol_provenance
from gonio.specs.ogam_draft.budget import ARCSEC_PER_MIN_PER_DPH, AnnexABudget, annex_a_budget
from gonio.units import ARCSEC_PER_DEG, PPM, S_PER_MIN
from gonio.specs.ogam_draft.items import (LISTED_ROWS, CalibrationResults,
                                          compute_characteristics)
from gonio.formats.metadata import header_lines
from gonio.specs.ogam_draft.readings import (Readings, metadata_float, metadata_gyro_type,
                                             read_readings)
from gonio.errors import GonioError
from gonio.specs.ogam_draft.static_record import StaticRecord
from gonio.result import Finding
from gonio.specs.ogam_draft.protocol import Protocol, load_protocol
from gonio.result.model import Item, Result, Uncertainty
from gonio.result.statement import round_half_up, state
from gonio.specs.ogam_draft.chamber import logged_chamber_temperature
from gonio.specs.ogam_draft.item_uncertainty import EXTRA_CLAUSES, chamber_temperature_line
from gonio.specs.ogam_draft import table_calibration as tcal

#: The readings taken of the draft's ambiguities (shown in results and certificate). The
#: u(r) sentence is not here: it follows the source actually used (:func:`readings_taken`).
READINGS_TAKEN = (
    "7.3: the protocol sets the count and spacing of the zero-stability readings (default 15 "
    "readings 5 min apart); B_s = s(M)/T is the result, (max M − min M)/T (definition 3.3) is "
    "reported beside it; T = time between first and last reading.",
    "7.4: each round starts from 0° with both readings zeroed; the reading is taken a fixed delay "
    "after arrival, within 0.5 min of the start (Annex A.1); E_i is the mean over the series "
    "present and E = ± max|E_i| is reported with its sign.",
    "7.6/7.7: the garbled denominator is read as the angle measured in the reference state "
    "(60 °/s, axis up) on the full 360° round; the spread max E − min E in ″ is always given.",
    "Annex A.4.2: the elliptic-projection tilt model of the draft is used for u(φ_e); the "
    "rigid-body model (tilt is a cos ψ factor absorbed by the scale factor) is shown beside it.",
    "Annex A.4.3: u(B_E) uses the longest time from zeroing to reading of the 7.4 readings "
    "actually used (not the 0.5 min bound) in the draft's Annex A budget; the physical "
    "budget takes each point's own time.",
)

#: The one precedence rule for settings given in more than one place (docs/formats.md).
PRECEDENCE_RULE = ("command line over readings-file metadata over protocol over built-in "
                   "default; every disagreement is reported")

#: Budget kinds of the angle-position deviation E.
BUDGET_KINDS = ("physical", "draft")

#: Labels of the two readings of B_s (results.json ``zero_stability.estimates``).
ZERO_STABILITY_READINGS = {
    "draft": "the draft's reading (7.3): B_s = s(M)/T of the 15 readings, stated by its "
             "one-sided 95 % chi-square interval with the readings' effective degrees of "
             "freedom",
    "model": "physical model: the expected B_s of these readings (sqrt(E[s(M)^2])/T) from the "
             "five-term noise fit of the instrument's continuous record over the 7.3 rest",
}


#: Labels of the two readings of each range item stated corrected for its bias (results.json
#: ``<item>.details.estimates``): K_l (7.2), C_v (7.6) and C_g (7.7).
RANGE_READINGS = {
    "scale_factor_nonlinearity": {
        "draft": "the draft's reading (7.2): K_l = (max K_i - min K_i)/K of the rounds as "
                 "measured, biased upwards by the rounds' errors; its u includes that bias "
                 "(line K_rng)",
        "corrected": "stated: the range corrected for its bias by the rounds' errors (table, "
                     "quantisation, tilt coupling at the A.1 bound; JCGM 101 Monte Carlo), "
                     "u the spread of the measured range"},
    "rate_consistency": {
        "draft": "the draft's reading (7.6): C_v = (max E_v - min E_v)/reference of the rates "
                 "as measured, biased upwards by the E_v's errors; its u includes that bias "
                 "(line C_rng)",
        "corrected": "stated: the range corrected for its bias by the E_v's errors (means, "
                     "table, zero drift, K and its tilt bias; JCGM 101 Monte Carlo) and for "
                     "the choice of each extreme (line C_sel), u the spread of the measured "
                     "range and the choice of each extreme"},
    "pointing_consistency": {
        "draft": "the draft's reading (7.7): C_g = (max E_g - min E_g)/reference of the "
                 "orientations as measured, each E_g the signed extreme of its curve, biased "
                 "by that choice; its u includes the choice's spread (line C_sel)",
        "corrected": "stated: the draft's reading less the expected shift of the choice of "
                     "each extreme (JCGM 101 Monte Carlo of the readings' noise through the "
                     "draft's functional), with the draft's u"},
}


#: What E's U under the draft's own Annex A budget is when the physical budget is certified.
DRAFT_E_READING = ("the draft's reading: U of Annex A's four lines alone (A.4.1-A.4.4), given "
                   "beside and not certified; it leaves out the lines marked beyond the draft "
                   "(the tilt x Earth-rate coupling, the errors of the 7.1 K), which the "
                   "conditions the draft allows contain (docs/draft-readings.md)")

#: What E's max|E_i| ± U is when the draft's own Annex A budget (``--budget draft``) is used:
#: E is stated by the interval of max|E_i| from that budget at every point.
DRAFT_E_READING_ONE_POINT = (
    "the draft's reading (7.4, Annex A): max|E_i| +- U, U of Annex A's one budget, a statement "
    "about one point; given beside and not certified: for the extreme of the points it covers "
    "the largest true |E_i| only about 0.95^m of the time where every true E_i is 0 (m points, "
    "54 % at 12); E is stated by the 95 % interval of max|E_i| from the same budget at every "
    "point (docs/draft-readings.md)")


#: E's readings when the in-situ tilt estimate corrects it (results.json ``details.stated``
#: "tilt_corrected", ``details.estimates``, ``details.tilt_correction`` of angle_deviation).
E_TILT_CORRECTED = {
    "note": "beyond the draft: every E_ij is corrected for the tilt x Earth-rate coupling at "
            "the tilt psi and azimuth alpha measured by the in-situ tilt estimate "
            "([tilt_estimate]): the coupling of the reading itself and of the 7.1 K it is "
            "converted with (JCGM 100 3.2.4); the physical budget's line tilt_Em is the "
            "correction's uncertainty from the estimate's covariance of (psi, alpha), in place "
            "of tilt_E at the A.1 bound",
    "draft": "the draft's reading (Annex A): E as measured, uncorrected, with U of Annex A's "
             "four lines; given beside, not certified",
    "corrected": "certified: E corrected at the measured tilt, with the physical budget",
}


#: Which reading of B_s is stated unless the caller asks otherwise (docs/draft-readings.md).
ZERO_STABILITY_STATED = "draft"


def readings_taken(repeatability_source: str) -> list[str]:
    """The readings-taken notes of this calibration, with the u(r) sentence that is true for it.

    u(r) from this calibration's own series: "Annex A.4.4: u(r) is …" (the certificate has
    its translation); from the protocol: "Annex A.4.4 (not applied): …", a different
    sentence that no translation of the first can stand for.
    """
    if "this calibration's own" in repeatability_source:
        note = (f"Annex A.4.4: u(r) is {repeatability_source} in the draft's Annex A budget; "
                "the physical budget takes the noise of each point's mean of n series (the "
                "7.4 series' noise model at the point's time, or this u(r)/sqrt(n)).")
    else:
        note = (f"Annex A.4.4 (not applied): this calibration has no repeated series; u(r) is "
                f"{repeatability_source}.")
    return list(READINGS_TAKEN[:3]) + [note] + list(READINGS_TAKEN[3:])


#: results.json ``scale_factor.details.table_calibration.label``.
TABLE_CALIBRATED_NOTE = (
    "beyond the draft: the table's angle error at K's 7.1 stops and zeroing positions "
    "corrected by the laboratory's table calibration (K_i = C_i/(theta_i - (e(stop) - "
    "e(zero))/3600)); U(K) carries the calibration's uncertainty propagated through the same "
    "sensitivity (line P_Kc) instead of the MPE line (P_K). E is corrected with it where the "
    "calibration covers E's positions (angle_deviation.details.table_calibration), and K_l, "
    "C_v and C_g where it covers theirs (their details.table_calibration; an item whose "
    "positions it does not cover keeps its MPE line and says so in "
    "details.table_calibration_not_used)")

#: Appended to the stated label of K_l, C_v, C_g (``details.estimates.corrected``) where a
#: calibrated table corrected them (:data:`RANGE_TABLE_CALIBRATED_NOTE`): K_l's 7.1 rounds
#: (K_i = counts over the corrected angle, nothing read with K), C_v's and C_g's readings, read
#: with the table-corrected 7.1 K only where their angles are read through the 7.1 K
#: (:data:`RANGE_TABLE_K`).
RANGE_TABLE_CORRECTED = {
    "scale_factor_nonlinearity": "; the 7.1 rounds corrected by the calibrated table, its "
                                 "errors drawn in place of the table's MPE",
    "rate_consistency": "; the readings corrected by the calibrated table{k}, its errors drawn "
                        "in place of the table's MPE",
    "pointing_consistency": "; the readings corrected by the calibrated table{k}, its errors "
                            "drawn in place of the table's MPE"}
#: C_v's, C_g's angles read through the 7.1 K (7.4) with a calibrated table: read with its
#: table-corrected value.
RANGE_TABLE_K = " and read with the table-corrected 7.1 K"


def range_table_text(template: str, through_k: bool) -> str:
    """A K_l/C_v/C_g table-calibration label with the K reading claimed only where the
    item's angles are read through the 7.1 K (``through_k``)."""
    return template.replace("{k}", RANGE_TABLE_K if through_k else "")

#: results.json ``angle_deviation.details.table_calibration.label``.
E_TABLE_CALIBRATED_NOTE = (
    "beyond the draft: every E_ij's reference angle corrected by the laboratory's table "
    "calibration, theta_i - (e(theta_i) - e(zero))/3600 (e = indicated - true, zero the 7.4 "
    "zeroing position), and E_ij read from counts with the table-corrected 7.1 K where K is "
    "corrected (scale_factor_corrected); each "
    "point's table line (P) is the calibration's uncertainty at the point, its zero and the "
    "7.1 stops and zeros propagated through E_i = C_i/K - theta_true (JCGM 100 5.1.2, 5.2.2 "
    "with the covariance; a position shared counted once; nu by Welch-Satterthwaite, JCGM 100 "
    "G.4.1), in place of the MPE line (P, K_P); per point: a point or zero the calibration "
    "does not list keeps its own table error and the MPE line for it, a 7.1 stop it does not "
    "list leaves K, and K's share of every E_i, as measured (points_uncorrected_deg, "
    "scale_factor_corrected)")
#: ``angle_deviation.details.estimates.corrected.label`` where the table corrected E.
E_TABLE_CORRECTED = ("certified: E corrected by the calibrated table (and read with the "
                     "table-corrected K), with the physical budget")
#: The same where E is not read with a table-corrected K (``scale_factor_corrected`` not true:
#: the readings' own gyro_deg, a nominal K, or a 7.1 stop the calibration does not list).
E_TABLE_CORRECTED_NOK = "certified: E corrected by the calibrated table, with the physical budget"

#: K's readings when the in-situ tilt estimate corrects it (results.json ``details.stated``
#: "tilt_corrected", ``details.estimates``, ``details.tilt_correction``).
TILT_CORRECTED = {
    "note": "beyond the draft: K is corrected for the tilt x Earth-rate coupling of the 7.1 "
            "rounds at the tilt psi and azimuth alpha measured by the in-situ tilt estimate "
            "([tilt_estimate]); U(K) carries the correction's uncertainty (line K_te: u(psi), "
            "u(alpha) and their correlation) instead of the coupling at the A.1 bound (K_tilt)",
    "draft": "the draft's reading (7.1): K = mean K_i of the rounds as measured, U with the "
             "coupling at the A.1 tilt bound, arcsine (line K_tilt)",
    "corrected": "stated: K corrected by the measured tilt, U with the correction's "
                 "uncertainty (line K_te)",
    "ranges": "; beyond the draft: the tilt x Earth-rate coupling taken at the tilt the "
              "in-situ estimate measured (each K_i, or each E read with the 7.1 K, corrected), "
              "with the correction's uncertainty (K_te), not at the A.1 bound",
    "pointing_consistency": "stated: the range of the E_g corrected, as C_v's, for its bias "
                            "by the E_g's errors (means, table, zero drift, K and the tilt "
                            "correction; JCGM 101 Monte Carlo) and for the choice of each "
                            "extreme (line C_sel), u the spread of the measured range and the "
                            "choice of each extreme"}


@dataclass(frozen=True)
class Conflict:
    """A setting given differently in two places, and which value was used."""

    setting: str
    file_value: object
    protocol_value: object
    used: object
    rule: str

    def to_dict(self) -> dict:
        return {"setting": self.setting, "file_value": self.file_value,
                "protocol_value": self.protocol_value, "used": self.used, "rule": self.rule}

    def warning(self) -> str:
        """The one-line warning the CLI prints on stderr."""
        return (f"gonio: warning: {self.setting}: readings file says {self.file_value!r}, "
                f"protocol/command line says {self.protocol_value!r}; using {self.used!r} "
                f"({self.rule})")


@dataclass
class Analysis:
    """One optical calibration in memory, before it is sealed into the one Result.

    ``results`` the seven items with their DataFrames; ``uncertainty`` E's budget
    (:class:`~gonio.specs.ogam_draft.budget.AnnexABudget`; the draft's four lines, or the
    physical budget with the lines beyond the draft); when E is not measured it is kept for
    reference but nothing of it is reported (no item, no U). ``item_uncertainty`` maps each
    measured item to its :class:`~gonio.specs.ogam_draft.item_uncertainty.ItemUncertainty`.
    :func:`calibrate` returns :meth:`result`; the coverage study (:mod:`.study`,
    :mod:`.item_coverage`) reads the analysis objects themselves (:func:`analyse`).
    """

    results: CalibrationResults
    uncertainty: AnnexABudget
    readings: Readings
    protocol: Protocol
    source_sha256: str
    repeatability_source: str
    noise: object | None = None          # gonio.analysis.noise.StaticNoiseResult of the 7.3 record
    noise_source: str = ""
    eda: object | None = None            # gonio.specs.ogam_draft.equal_division.EdaResult of the equal_division rows
    item_uncertainty: dict = field(default_factory=dict)
    budget_kind: str = "physical"
    conflicts: list = field(default_factory=list)
    budget_notes: list = field(default_factory=list)
    excluded: object = None              # DataFrame of readings excluded by the checks
    zero_stability_readings: dict = field(default_factory=dict)   # zero_stability_readings()
    findings: list = field(default_factory=list)   # gonio.result.Finding of the screening
    gyro_type: str | None = None         # the laboratory file's [instrument] gyro_type
    table_calibration: object = None     # table_calibration.TableCalibration, or None
    #: K_l, C_v, C_g with a table calibration: the rows used, or why the MPE line is kept
    table_record: dict = field(default_factory=dict)

    @property
    def e_measured(self) -> bool:
        e = self.results.angle_deviation
        return bool(e.measured and e.value is not None)

    def uncertainty_dict(self) -> dict:
        """``results.json``'s ``extra.uncertainty``: E's budget, or no U when E is not
        measured."""
        if not self.e_measured:
            return {"budget_kind": self.budget_kind, "measured": False,
                    "reason": "the angle-position deviation E (7.4) was not measured: "
                              "no item, no uncertainty",
                    "components": [], "u_c_arcsec": None, "U_arcsec": None, "k": None,
                    "nu_eff": None, "k_source": None, "stated": None, "annex_rounded": None,
                    "monte_carlo": None, "repeatability_source": None, "notes": []}
        unc = self.uncertainty.to_dict()
        ia = self.item_uncertainty.get("angle_deviation")
        unc.update({"budget_kind": self.budget_kind, "measured": True,
                    "repeatability_source": self.repeatability_source,
                    "nu_eff": ia.to_dict()["nu_eff"] if ia else None,
                    "k_source": ia.k_source if ia else None,
                    "notes": list(self.budget_notes)})
        for c, ic in zip(unc["components"], ia.components if ia else ()):
            c["beyond_draft"], c["clause"] = ic.beyond_draft, ic.clause
        if self.budget_kind == "physical":       # the draft's Annex A reading, beside
            settings, _ = session_settings(self.readings, self.protocol)
            d = deviation_budget(self.results, self.readings, self.protocol, settings,
                                 kind="draft")[0].to_dict()
            unc["draft_reading"] = {"label": DRAFT_E_READING, "U_arcsec": d["U_arcsec"],
                                    "k": d["k"], "u_c_arcsec": d["u_c_arcsec"]}
            est = (self.results.angle_deviation.details.get("estimates") or {}).get("draft")
            if est:              # E itself corrected at the measured tilt: the draft's E beside
                unc["draft_reading"]["E_arcsec"] = est["value"]
        elif self.budget_kind == "draft" and self.uncertainty.max_interval:
            # the draft's own budget: E stated by the interval from it at every point, the
            # draft's max|E_i| ± U (a statement about one point) beside, not certified
            unc["draft_reading"] = {"label": DRAFT_E_READING_ONE_POINT,
                                    "U_arcsec": unc["U_arcsec"], "k": unc["k"],
                                    "u_c_arcsec": unc["u_c_arcsec"]}
        return unc

    def item_details(self, c) -> dict:
        """The details of item ``c`` in results.json (its own fields beyond the Item's:
        tables listed, the 7.1 measurand, the two readings of B_s and the noise analysis)."""
        d = {k: v for k, v in c.to_dict().items() if k not in ITEM_FIELDS}
        if d.get("scale_factor_for_angles_counts_per_deg") is not None and \
                self.results.scale_factor_for_angles_source == "metadata":
            # no 7.1 readings: the angles read with the metadata's nominal K, whose error
            # is in no budget (the certificate says so beside the item)
            d["scale_factor_for_angles_source"] = "metadata"
        if c.name == "scale_factor" and c.measured:
            iu = self.item_uncertainty.get(c.name)
            tc = None if iu is None else iu.correction
            d.update(scale_factor_as_mounted(
                float(c.value if tc is None and not table_corrected(iu) else iu.value),
                session_settings(self.readings, self.protocol)[0]["tilt_bound_deg"], tc))
            d["temperature_coeff_bound"] = chamber_temperature(self.readings, self.protocol,
                                                               self.gyro_type)[1]
            if tc is not None:
                d["stated"] = "tilt_corrected"
                d["tilt_correction"] = {"label": TILT_CORRECTED["note"], **tc.to_dict()}
                d["estimates"] = {
                    "draft": {"label": TILT_CORRECTED["draft"], "value": _plain_value(c),
                              "uncertainty": beside_uncertainty(iu.beside.to_dict())},
                    "corrected": {"label": TILT_CORRECTED["corrected"],
                                  "value": float(iu.value)}}
            if table_corrected(iu):
                line = next(x for x in iu.components if x.symbol == "P_Kc")
                d.setdefault("stated", "table_corrected")
                d["table_calibration"] = {
                    "label": TABLE_CALIBRATED_NOTE,
                    "source": getattr(self.table_calibration, "source", ""),
                    "sha256": getattr(self.table_calibration, "sha256", None),
                    "positions_used": table_positions_used(c.table, self.protocol,
                                                           self.table_calibration),
                    "line": line.source, "u_counts_per_deg": float(line.u),
                    "u_rel_ppm": float(line.u / abs(iu.value) / PPM),
                    "uncorrected_value": _plain_value(c)}
        if c.name in RANGE_READINGS and c.measured:
            iu = self.item_uncertainty.get(c.name)
            sf_iu = self.item_uncertainty.get("scale_factor")
            tilt = sf_iu is not None and sf_iu.correction is not None
            rec = self.table_record.get(c.name) or {}
            if iu is not None and iu.beside is not None:
                d["stated"] = "corrected"
                d["estimates"] = {
                    "draft": {"label": RANGE_READINGS[c.name]["draft"], "value": _plain_value(c),
                              "uncertainty": beside_uncertainty(iu.beside.to_dict())},
                    "corrected": {"label": (TILT_CORRECTED["pointing_consistency"]
                                            if tilt and c.name == "pointing_consistency"
                                            else RANGE_READINGS[c.name]["corrected"])
                                  + (TILT_CORRECTED["ranges"] if tilt else "")
                                  + (range_table_text(RANGE_TABLE_CORRECTED[c.name],
                                                      rec.get("through_k", False))
                                     if "positions_used" in rec else ""),
                                  "value": float(iu.value)}}
            if iu is not None and "positions_used" in rec:
                d["stated"] = "table_corrected"
                d["table_calibration"] = {
                    "label": range_table_text(RANGE_TABLE_CALIBRATED_NOTE[c.name],
                                              rec.get("through_k", False)),
                    "source": getattr(self.table_calibration, "source", ""),
                    "sha256": getattr(self.table_calibration, "sha256", None),
                    "positions_used": rec["positions_used"],
                    "line": iu.components[0].source, "u_c": float(iu.u_c),
                    "measured_value": rec["measured_value"],
                    "uncorrected_value": _plain_value(c)}
                if "measured_value_without_tilt_correction" in rec:
                    d["table_calibration"]["measured_value_without_tilt_correction"] = \
                        rec["measured_value_without_tilt_correction"]
                if c.name != "scale_factor_nonlinearity":
                    d["table_calibration"]["read_with_table_corrected_k"] = bool(
                        rec.get("through_k", False))
            elif rec.get("reason"):
                d["table_calibration_not_used"] = rec["reason"]
        if c.name != "zero_stability":
            return d
        zr = self.zero_stability_readings
        if zr:
            d["stated"], d["stated_note"] = zr["stated"], zr["note"]
            d["estimates"] = {
                "draft": {"label": ZERO_STABILITY_READINGS["draft"], "value": _plain_value(c),
                          "uncertainty": zr["draft"].to_dict()},
                "model": None if zr["model"] is None else
                {"label": ZERO_STABILITY_READINGS["model"], "value": float(zr["model"].value),
                 "uncertainty": (zr["model"].to_dict() if zr["stated"] == "model" else
                                 beside_uncertainty(zr["model"].to_dict())),
                 "variance_shares": zr["expected"].to_dict()["variance_shares"]}}
        if self.noise is not None:
            d["noise"] = {"source": self.noise_source, **self.noise.to_dict()}
        else:
            d["noise"] = None
            d["noise_reason"] = ("the Allan analysis of 7.3 needs the instrument's continuous "
                                 "record (a stream); a readings file holds only the 15 readings")
        return d

    def item(self, c) -> Item:
        """Item ``c`` of the seven as the one result model holds it."""
        iu = self.item_uncertainty.get(c.name)
        unc = None if iu is None else iu.to_dict()
        value = c.value
        if c.name == "zero_stability" and self.zero_stability_readings:
            value = float(iu.value)               # the stated reading of B_s
        if c.name in RANGE_READINGS and iu is not None and iu.beside is not None:
            value = float(iu.value)               # the bias-corrected range
        if c.name == "scale_factor" and iu is not None and (
                iu.correction is not None or table_corrected(iu)):
            value = float(iu.value)               # K corrected by the measured tilt, the table
        if c.name == "angle_deviation" and unc is not None and self.e_measured:
            unc = e_stated_uncertainty(unc, getattr(self.uncertainty, "max_interval", None))
        details = json_safe(self.item_details(c))
        if c.name == "angle_deviation" and c.measured and value is not None:
            # the value certified: E = ± max|E_i| (7.4), the magnitude its U or interval is
            # of; the signed extreme beside it, under its own name
            details = e_certified_details(details, float(value))
            value = details["max_abs_arcsec"]
        return Item(c.name, c.title, c.clause, c.unit, _plain_value(c, value), bool(c.measured),
                    c.reason or "",
                    None if unc is None else Uncertainty(
                        unc["components"], unc["u_c"], unc["U"], unc["k"], unc["nu_eff"],
                        unc.get("monte_carlo"), unc.get("coverage_probability"),
                        unc.get("k_source") or "", unc.get("interval"), unc.get("u_c_of"),
                        unc.get("interval_numerical_u"), unc.get("interval_draws")),
                    details, nonnegative=bool((unc or {}).get("nonnegative")))

    def result(self) -> Result:
        """The sealed Result of this calibration: the seven items (each item's own fields
        under ``details``); under ``extra`` E's full budget, the conflicts, the precedence
        rule, the equal-division analysis, the method's settings (:func:`method_settings`),
        the series every figure draws (:mod:`.figure_data`) and the warnings; the detail
        tables as ``tables``."""
        from gonio.specs.ogam_draft.figure_data import figure_series

        rd = self.results.to_dict()
        items = {c.name: self.item(c) for c in self.results.items()}
        extra = {"uncertainty": self.uncertainty_dict(),
                 "conflicts": [c.to_dict() for c in self.conflicts],
                 "precedence_rule": PRECEDENCE_RULE}
        if self.eda is not None:
            extra["equal_division"] = {"clause": "IEC 62047-20 Annex A.3", **self.eda.to_dict()}
        if "unused_readings_summary" in rd:
            extra["unused_readings_summary"] = rd["unused_readings_summary"]
        extra["screening"] = {"set_aside_readings": 0 if self.excluded is None
                              else int(len(self.excluded))}
        extra["method"] = method_settings(self.protocol)
        extra["figures"] = figure_series(self.results, self.uncertainty)
        extra["warnings"] = self.warnings()
        src = {"file": Path(self.readings.path).name if self.readings.path else None,
               "sha256": self.source_sha256, "rows": int(len(self.readings.data))}
        return Result(
            SPEC_KEY, self.protocol.specification or spec_title(SPEC_KEY), items,
            dict(self.readings.metadata), src,
            readings_taken(self.repeatability_source) if self.e_measured else list(READINGS_TAKEN),
            extra,
            settings={"protocol": self.protocol.name,
                      "protocol_sha256": protocol_provenance(
                          self.protocol.path or None).get("protocol_sha256"),
                      "budget_kind": self.budget_kind,
                      "repeatability_source": self.repeatability_source or None},
            unused_readings=list(rd.get("unused_readings") or []),
            findings=list(self.findings), gonio_version=__version__,
            tables=self.detail_tables())

    def detail_tables(self) -> dict:
        """The tables written beside results.json (``tables/*.csv``)."""
        out = {}
        for item in self.results.items():
            for tname, df in (getattr(item, "tables", None) or {}).items():
                if df is not None and len(df):
                    out[f"{item.name}_{tname}.csv"] = df
            if len(item.table) > LISTED_ROWS:       # summarised in results.json: all here
                out[f"{item.name}_table.csv"] = item.table
        if len(self.results.unused_readings) > LISTED_ROWS:
            out["unused_readings.csv"] = self.results.unused_readings
        out["uncertainty_budget.csv"] = self.uncertainty.table()
        return out

    def warnings(self) -> list[str]:
        """One line per conflict and per excluded reading group (for stderr)."""
        out = [c.warning() for c in self.conflicts]
        ex = self.excluded
        if ex is not None and len(ex):
            for test, g in ex.groupby("test", sort=True):
                out.append(f"gonio: warning: {len(g)} {test} reading(s) excluded (lines "
                           f"{', '.join(str(int(x)) for x in g['line'][:5])}"
                           f"{', …' if len(g) > 5 else ''}): {g['reason'].iloc[0]}")
        out += [f"gonio: warning: {f.message}" for f in self.findings if f.action == "flagged"]
        return out


#: The specification's key in results.json.
SPEC_KEY = "ogam-draft"
#: The fields of an optical item that the one result model's Item holds itself (the rest
#: go under the item's ``details``).
ITEM_FIELDS = ("item", "value", "unit", "clause", "measured", "reason")


def e_certified_details(details: dict, signed_arcsec: float) -> dict:
    """E's details with the signed extreme of the E_i under its own name: results.json
    ``items.angle_deviation.value`` is what every output certifies, max|E_i| (7.4:
    E = ± max|E_i|, the magnitude E's 95 % interval or U is of; ``details.max_abs_arcsec``),
    and ``details.signed_extreme_arcsec`` the E_i of largest magnitude with its sign, at
    ``details.position_deg``.

    >>> d = e_certified_details({"max_abs_arcsec": 0.9, "position_deg": 60.0}, -0.9)
    >>> d["signed_extreme_arcsec"], d["max_abs_arcsec"]
    (-0.9, 0.9)
    """
    out = dict(details)
    out["signed_extreme_arcsec"] = float(signed_arcsec)
    out["max_abs_arcsec"] = float(out.get("max_abs_arcsec", abs(signed_arcsec)))
    return out


def _plain_value(c, value=None):
    """An item's value as results.json writes it (None when not a finite number)."""
    v = c.value if value is None else value
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def method_settings(protocol: Protocol) -> dict:
    """The protocol's settings the certificate states (JJF 1535 8 g/h): the specification it
    follows (as the protocol names it), the rates, the rounds and series, the zero-stability readings, the read delay and time to reading, the
    Earth-rate compensation, the axis directions and the reference conditions."""
    p = protocol
    rates = []
    for it in (p.scale_factor, p.angle_deviation, *p.rate_consistency):
        if it is not None and it.rate_dps not in rates:
            rates.append(it.rate_dps)
    zs = p.zero_stability
    ad = p.angle_deviation or p.scale_factor
    cond = p.conditions
    cget = (cond.get if isinstance(cond, dict)
            else lambda key, default: getattr(cond, key, default))
    return {"specification": p.specification or "",
            "rates_dps": sorted(float(r) for r in rates),
            "angle_deviation_rate_dps": (float(p.angle_deviation.rate_dps)
                                         if p.angle_deviation else None),
            "scale_factor_rounds": len(p.scale_factor.rounds) if p.scale_factor else 0,
            "angle_deviation_rounds": len(p.angle_deviation.rounds) if p.angle_deviation else 0,
            "series": p.angle_deviation.series if p.angle_deviation else 0,
            "zero_stability_readings": zs.readings if zs else 0,
            "zero_stability_interval_s": zs.interval_s if zs else None,
            "read_delay_s": ad.read_delay_s if ad is not None else None,
            "max_time_to_reading_s": ad.max_time_to_reading_s if ad is not None else None,
            "earth_compensation": p.session.earth_compensation,
            "static_s": p.session.static_s,
            "compensation_latitude_deg": p.session.compensation_latitude_deg,
            "axes": [p.pointing_reference] + [it.orientation for it in p.pointing_consistency
                                              if it.orientation != p.pointing_reference],
            "temperature_c": cget("temperature_c", 20.0),
            "temperature_tolerance_c": cget("temperature_tolerance_c", 1.0)}


def scale_factor_as_mounted(k_counts_per_deg: float, tilt_bound_deg: float,
                            tilt_correction=None) -> dict:
    """What K of 7.1 is (docs/draft-readings.md, 7.1): the scale factor *as mounted*.

    Tilted by ψ the instrument senses θ̇ cos ψ, so 7.1 measures K_own cos ψ; the draft
    bounds ψ (A.1) and lets the calibration on the mount fix k (A.4.2), so K is stated as
    mounted and the instrument's own K as the one-sided bound K ≤ K_own ≤ K / cos ψ_max.

    Where the in-situ tilt estimate measured ψ (``tilt_correction``, a
    :class:`gonio.specs.ogam_draft.budget_extra.TiltCorrection`; beyond the draft), the
    ratio is stated at the measured tilt: K_own/K − 1 = 1/cos ψ − 1, with the 95 % interval
    its monotone image of ψ's interval ψ ± U(ψ) (ψ ≥ 0; JCGM 101 5.3.3's propagation of an
    interval through a monotone function), under ``tilt_measured``. The bound stays beside.

    >>> d = scale_factor_as_mounted(76434.84, 0.1)
    >>> round((d["instrument_own_upper_counts_per_deg"] / 76434.84 - 1) * 1e6, 2)
    1.52
    >>> from types import SimpleNamespace
    >>> tc = SimpleNamespace(tilt_deg=0.05, u_tilt_deg=0.002, k95=2.5)
    >>> m = scale_factor_as_mounted(76434.84, 0.1, tc)["tilt_measured"]
    >>> round(m["own_rel_ppm"], 4), [round(x, 4) for x in m["own_rel_interval_ppm"]]
    (0.3808, [0.3084, 0.4607])
    """
    c = math.cos(math.radians(tilt_bound_deg))
    out = {"measurand": (f"K as mounted: the instrument on the table with its sensing plane "
                         f"within {tilt_bound_deg:g}° of the table plane (Annex A.1); the "
                         "instrument's own K (sensing axis along the rotation axis) lies "
                         f"between K and K/cos ψ, up to {(1 / c - 1) * 1e6:.2g} ppm above K, "
                         "not included in U"),
           "tilt_bound_deg": float(tilt_bound_deg),
           "instrument_own_upper_counts_per_deg": float(k_counts_per_deg / c)}
    if tilt_correction is None:
        return out
    psi = float(tilt_correction.tilt_deg)
    big_u = float(tilt_correction.k95) * float(tilt_correction.u_tilt_deg)
    rel = lambda x: (1.0 / math.cos(math.radians(x)) - 1.0) / PPM  # noqa: E731
    lo, hi = rel(max(psi - big_u, 0.0)), rel(psi + big_u)
    out["tilt_measured"] = {"tilt_deg": psi, "U95_tilt_deg": big_u,
                            "k95": float(tilt_correction.k95), "own_rel_ppm": rel(psi),
                            "own_rel_interval_ppm": [lo, hi]}
    st = state(psi, big_u)                  # ψ at U's decimal place, as the certificate
    out["measurand"] = (f"K as mounted: the tilt of the sensing axis from the rotation axis "
                        f"measured in situ (beyond the draft), psi = {st.value_text}° (U95 "
                        f"{st.U_text}°); the instrument's own K (sensing axis along the "
                        f"rotation axis) is K/cos psi, {rel(psi):.2g} ppm above K (95 % "
                        f"interval [{lo:.2g}, {hi:.2g}] ppm), not included in U; A.1's bound "
                        f"{tilt_bound_deg:g}° would allow up to {(1 / c - 1) * 1e6:.2g} ppm")
    return out




# --------------------------------------------------------------------------- settings

def spec_title(key: str) -> str:
    """The registered specification's English title (its key if none is registered)."""
    from gonio.specs import available

    spec = available().get(key)
    return spec.title_en if spec is not None else key


def file_protocol_name(path: str | Path) -> str | None:
    """The ``# protocol: NAME`` metadata of a readings file or stream, read from its head
    (:func:`gonio.formats.metadata.header_lines`; the first such line). None when absent or
    when the file cannot be read as text: the readings reader then says why."""
    try:
        for key, value in header_lines(path):
            if key == "protocol":
                return value or None
    except (OSError, GonioError):
        pass
    return None


def resolve_protocol(readings_path: str | Path | None, metadata_name: str | None,
                     protocol: str | Path | Protocol | None) -> tuple[Protocol, list[Conflict]]:
    """The protocol to use, by :data:`PRECEDENCE_RULE`.

    An explicit ``protocol`` (the command line's ``--protocol``) wins; a different
    ``# protocol:`` in the readings file is reported as a conflict. Without one, the
    file's protocol is loaded (a built-in name, a path, or a file of that name next to
    the readings file); a named protocol that cannot be found is an error, never
    silently replaced by the default. Neither: ``ogam-draft``.
    """
    conflicts: list[Conflict] = []
    if protocol is not None:
        proto = protocol if isinstance(protocol, Protocol) else load_protocol(protocol)
        if metadata_name and metadata_name != proto.name:
            conflicts.append(Conflict("protocol", metadata_name, proto.name, proto.name,
                                      "command line over readings-file metadata"))
        return proto, conflicts
    if not metadata_name:
        return load_protocol("ogam-draft"), conflicts
    from gonio.resources import readings_protocol     # one rule for every readings file
    return load_protocol(readings_protocol(metadata_name, readings_path, None)), conflicts


#: The factor by which the readings' table MPE may depart from the protocol's, either way
#: (:func:`table_mpe_plausible`).
TABLE_MPE_FACTOR: float = 10.0


def table_mpe_plausible(readings_arcsec: float, protocol_arcsec: float, file=None) -> None:
    """Refuse a readings file's ``table_mpe_arcsec`` more than :data:`TABLE_MPE_FACTOR` times
    above or below the protocol's ``annex_a.table_mpe_arcsec`` (the table the programme is
    planned for: the draft's Table 1 ±0.1″), naming the key and both values.

    Where they differ within the factor the readings' value is used and the difference
    stated (:func:`session_settings`, a Conflict: stderr, results.json ``conflicts``). The
    value used sets every table line and bound of the budgets (u(P), E's b, K's table line),
    so a contradiction beyond the factor is refused, never stated beside a U it made: a
    table ten times worse than the one the programme (and the laboratory's list of
    standards, whose accuracy text the certificate prints) names is another table or
    another unit (″ for ′ or µrad), and 100″ where 0.1″ is meant would make E's U 460″. A
    protocol MPE of 0 (a calibrated table's programme) sets no bound.

    >>> table_mpe_plausible(0.2, 0.1)
    >>> table_mpe_plausible(100.0, 0.1)
    Traceback (most recent call last):
    gonio.errors.GonioError: key table_mpe_arcsec: the readings' table MPE 100″ is 1000× the protocol's annex_a.table_mpe_arcsec 0.1″ (beyond 10× either way: another table, or another unit?); state the table's MPE in ″ as its certificate gives it, or a protocol for that table
    """
    from gonio.errors import GonioError

    if protocol_arcsec <= 0:
        return
    ratio = readings_arcsec / protocol_arcsec
    if 1.0 / TABLE_MPE_FACTOR <= ratio <= TABLE_MPE_FACTOR:
        return
    raise GonioError(f"the readings' table MPE {readings_arcsec:g}″ is {ratio:.4g}× the "
                     f"protocol's annex_a.table_mpe_arcsec {protocol_arcsec:g}″ (beyond "
                     f"{TABLE_MPE_FACTOR:g}× either way: another table, or another unit?); "
                     "state the table's MPE in ″ as its certificate gives it, or a protocol "
                     "for that table", file=file, key="table_mpe_arcsec")


def session_settings(readings: Readings, protocol: Protocol) -> tuple[dict, list[Conflict]]:
    """Table MPE and tilt bound of this session, by :data:`PRECEDENCE_RULE`.

    The readings file's metadata (``table_mpe_arcsec``, ``tilt_bound_deg``) describes
    the equipment actually used and wins over the protocol's ``annex_a`` values; a
    difference is a :class:`Conflict`, never silent.

    >>> from gonio.specs.ogam_draft.readings import Readings
    >>> import pandas as pd
    >>> s, c = session_settings(Readings(pd.DataFrame(), {"table_mpe_arcsec": "0.2"}),
    ...                         load_protocol("ogam-draft"))
    >>> s["table_mpe_arcsec"], c[0].to_dict()["protocol_value"], c[0].used
    (0.2, 0.1, 0.2)
    """
    a = protocol.annex_a
    md, file = readings.metadata, readings.path
    out, conflicts = {}, []
    for key in ("table_mpe_arcsec", "tilt_bound_deg"):
        v = metadata_float(md, key, file=file)
        if v is None:
            out[key] = getattr(a, key)
            continue
        if key == "table_mpe_arcsec":
            table_mpe_plausible(v, a.table_mpe_arcsec, file)
        out[key] = v
        if v != getattr(a, key):
            conflicts.append(Conflict(key, v, getattr(a, key), v,
                                      "readings-file metadata over protocol annex_a"))
    return out, conflicts


def temperature_coeff_bound(readings: Readings, protocol: Protocol,
                            gyro_type: str | None = None) -> dict:
    """The bound |α_K|max (ppm/°C) on the instrument's scale-factor temperature coefficient
    that K's chamber-temperature line ``K_T`` takes, and where it comes from (results.json
    ``items.scale_factor.details.temperature_coeff_bound``; the certificate says it).

    The bound belongs to the instrument under calibration (its specification), never to the
    bench that made the readings. The rule, in this order:

    1. ``metadata``: the readings state it (``sf_temperature_coeff_bound_ppm_per_c``);
    2. ``protocol-rlg`` / ``protocol-fog``: the readings state the gyro type (``gyro_type``),
       else ``gyro_type`` (the laboratory file's ``[instrument] gyro_type``, or the type of
       the instrument registered in the records for ``calibrate --record``) states it, and the protocol's default for that type is
       taken (``annex_a.sf_temperature_coeff_bound_rlg_ppm_per_c`` or ``…_fog_…``); ``how``
       says which of the two stated the type;
    3. ``protocol-larger``: neither is stated; the larger of the two defaults is taken, so a
       FOG is never given an RLG's bound without a word.

    >>> from gonio.specs.ogam_draft.readings import Readings
    >>> import pandas as pd
    >>> p = load_protocol("ogam-draft")
    >>> b = lambda md: temperature_coeff_bound(Readings(pd.DataFrame(), md), p)
    >>> [(d["bound_ppm_per_c"], d["source"]) for d in (b({"gyro_type": "rlg"}),
    ...  b({"gyro_type": "fog"}), b({}), b({"gyro_type": "fog",
    ...                                   "sf_temperature_coeff_bound_ppm_per_c": "0.4"}))]
    [(0.1, 'protocol-rlg'), (1.0, 'protocol-fog'), (1.0, 'protocol-larger'), (0.4, 'metadata')]
    >>> d = temperature_coeff_bound(Readings(pd.DataFrame(), {}), p, "RLG")
    >>> d["bound_ppm_per_c"], d["source"], "[instrument] gyro_type" in d["how"]
    (0.1, 'protocol-rlg', True)
    """
    a = protocol.annex_a
    md, file = readings.metadata, readings.path
    gyro = metadata_gyro_type(md, file=file)
    from_lab = gyro is None and bool(gyro_type)
    if from_lab:
        gyro = metadata_gyro_type({"gyro_type": gyro_type}, file="the laboratory file")
    stated = metadata_float(md, "sf_temperature_coeff_bound_ppm_per_c", file=file)
    defaults = {"rlg": a.sf_temperature_coeff_bound_rlg_ppm_per_c,
                "fog": a.sf_temperature_coeff_bound_fog_ppm_per_c}
    if stated is not None:
        bound, source, how = stated, "metadata", "stated by the readings (the instrument's " \
            "specification)"
    elif gyro is not None:
        bound, source = defaults[gyro], f"protocol-{gyro}"
        how = f"the protocol's default for a{'n' if gyro == 'rlg' else ''} {gyro.upper()} " \
              f"(annex_a.sf_temperature_coeff_bound_{gyro}_ppm_per_c" + (
                  "; the readings state no type: the instrument's as the laboratory file's "
                  "[instrument] gyro_type or the records' registered instrument states it)"
                  if from_lab else ")")
    else:
        bound, source = max(defaults.values()), "protocol-larger"
        how = "gyro type not stated: the larger of the protocol's RLG and FOG defaults"
    return {"bound_ppm_per_c": float(bound), "source": source, "gyro_type": gyro,
            "temperature_tolerance_c": float(protocol.conditions.temperature_tolerance_c),
            "how": how}


def chamber_temperature(readings: Readings, protocol: Protocol, gyro_type: str | None = None):
    """K's chamber line ``K_T`` for these readings: the
    :class:`~gonio.specs.ogam_draft.item_uncertainty.ChamberLine` of
    :func:`~gonio.specs.ogam_draft.item_uncertainty.chamber_temperature_line` at the bound of
    :func:`temperature_coeff_bound`, and that function's dict with what the line took
    (results.json ``items.scale_factor.details.temperature_coeff_bound``).

    Where the readings log the chamber's temperature
    (:func:`~gonio.specs.ogam_draft.chamber.logged_chamber_temperature`: the mean of a
    ``temperature_c`` column over the 7.1 rounds, interpolated in time where a slow logger
    left cells blank; else the metadata ``temperature_c``; a stream's column and metadata
    are carried into its reduced readings) ΔT is the logged value minus the protocol's
    reference (``conditions.temperature_c``, Table 2's 20 °C; the difference rounded to
    10⁻⁹ °C, so that 19.4 − 20 reads −0.6), ``basis`` ``logged``, ``logged_from`` ``column``
    or ``metadata``, and the thermometer's error δ within ± its MPE (the readings'
    ``thermometer_mpe_c``, else the protocol's ``conditions.thermometer_mpe_c``;
    ``thermometer_from`` says which) enters the line; else ΔT is known only within
    ± ``conditions.temperature_tolerance_c``, ``basis`` ``tolerance``.

    >>> import pandas as pd
    >>> from gonio.specs.ogam_draft.readings import Readings
    >>> p = load_protocol("ogam-draft")
    >>> line, d = chamber_temperature(Readings(pd.DataFrame(), {"gyro_type": "fog",
    ...                                                         "temperature_c": "19.4"}), p)
    >>> d["basis"], d["deviation_c"], round(d["u_ppm"], 4), d["distribution"]
    ('logged', -0.6, 0.3528, 'rectangular-shifted-product')
    >>> d["thermometer_mpe_c"], d["thermometer_from"], d["logged_from"]
    (0.2, 'protocol', 'metadata')
    >>> d = chamber_temperature(Readings(pd.DataFrame(), {"gyro_type": "fog"}), p)[1]
    >>> d["basis"], d["logged_temperature_c"], round(d["u_ppm"], 4), d["distribution"]
    ('tolerance', None, 0.3333, 'rectangular-product')
    """
    bound = temperature_coeff_bound(readings, protocol, gyro_type)
    logged, logged_from = logged_chamber_temperature(readings)
    stated = metadata_float(readings.metadata, "thermometer_mpe_c", file=readings.path)
    mpe = float(protocol.conditions.thermometer_mpe_c) if stated is None else stated
    ref = float(protocol.conditions.temperature_c)
    line = chamber_temperature_line(bound["bound_ppm_per_c"], bound["temperature_tolerance_c"],
                                    None if logged is None else round(logged - ref, 9), mpe)
    return line, {**bound, "reference_temperature_c": ref, "logged_temperature_c": logged,
                  "logged_from": logged_from,
                  "thermometer_from": None if logged is None else (
                      "protocol" if stated is None else "metadata"),
                  **line.to_dict()}


# --------------------------------------------------------------------------- checks

def screen_readings(readings: Readings, protocol: Protocol, findings: list | None = None
                    ) -> tuple[Readings, "pd.DataFrame", list]:
    """Screen the readings (:func:`gonio.specs.ogam_draft.screen.screen`: every column against
    the protocol and the other readings) and set aside or refuse what it finds; ``findings``:
    the screening already made (``SPEC.screen``, called by the pipeline), applied as given.

    Returns the readings kept, a DataFrame of the rows set aside (line, test, series,
    round, rate_dps, orientation, reason) and the findings (``results.json`` ``findings``).
    A refused reading, or setting aside the last reading of a round, is a GonioError
    naming the line.
    """
    from gonio.specs.ogam_draft.screen import apply_findings, screen

    if findings is None:
        findings = screen(readings, protocol)
    kept, excluded = apply_findings(readings, findings, protocol)
    return kept, excluded, list(findings)


_ITEM_TESTS = {"scale_factor": ("scale_factor",), "scale_factor_nonlinearity": ("scale_factor",),
               "angle_deviation": ("angle_deviation",), "repeatability": ("angle_deviation",),
               "rate_consistency": ("rate_consistency", "angle_deviation"),
               "pointing_consistency": ("pointing_consistency", "angle_deviation")}


def screen(readings, protocol: str | Path | Protocol | None = None, **_options) -> list[Finding]:
    """``SPEC.screen``: every finding on a readings file or stream (refused, set aside,
    flagged; :func:`gonio.specs.ogam_draft.screen.screen`) under the protocol the file names
    (or ``protocol``), without calibrating. The pipeline hands them to :func:`calibrate`
    (``findings=``); a file read here is kept for that calibration (:func:`_load`: a stream
    is reduced once)."""
    from gonio.specs.ogam_draft.screen import screen as findings_of

    if isinstance(readings, Readings):
        proto, _ = resolve_protocol(readings.path, readings.metadata.get("protocol"), protocol)
        rd = readings
    else:
        from gonio.errors import check_input_file
        check_input_file(readings, "readings or stream file")   # before any byte is read
        proto, _ = resolve_protocol(readings, file_protocol_name(readings), protocol)
        rd, _ = _load(readings, proto, keep=True)
    return findings_of(rd, proto)


def _note_exclusions(results: CalibrationResults, excluded) -> None:
    """Excluded readings join ``unused_readings``; each item they belonged to says so."""
    import pandas as pd

    if excluded is None or not len(excluded):
        return
    un = results.unused_readings
    results.unused_readings = pd.concat([un, excluded[un.columns]], ignore_index=True) \
        .sort_values("line", kind="stable").reset_index(drop=True) if len(un) else \
        excluded.reset_index(drop=True)
    for name, tests in _ITEM_TESTS.items():
        item = getattr(results, name)
        n = int(excluded["test"].isin(tests[:1]).sum())
        if item.measured and n:
            item.details["excluded_readings"] = n
            item.details["excluded_note"] = (f"based on fewer readings: {n} {tests[0]} "
                                             "reading(s) excluded by the protocol checks "
                                             "(see unused_readings)")


# --------------------------------------------------------------------------- E's budget

def _time_to_reading_s(results: CalibrationResults, readings: Readings) -> float | None:
    used = results.angle_deviation.used_lines
    df = readings.data
    t = df.loc[df["line"].isin(list(used)), "time_s"].to_numpy(dtype=float)
    t = t[np.isfinite(t)]
    return float(t.max()) if t.size else None


def _load_tilt(tilt) -> tuple[float, str]:
    """ψ bound from a ``gonio tilt-estimate --json`` result: ψ + U95(ψ)."""
    from gonio.errors import GonioError

    if isinstance(tilt, (str, Path)):
        try:
            d = json.loads(Path(tilt).read_text(encoding="utf-8"))
        except OSError as exc:
            raise GonioError(f"cannot read tilt file: {exc.strerror}", file=tilt) from None
        except json.JSONDecodeError as exc:
            raise GonioError(f"not JSON: {exc.msg}", file=tilt, line=exc.lineno) from None
        except (ValueError, RecursionError) as exc:   # a 5000-digit number, '[' 10⁵ deep
            raise GonioError(f"not a tilt result: {str(exc)[:80] or 'nested too deeply'}",
                             file=tilt) from None
        src = Path(tilt).name
    else:
        d, src = dict(tilt), "tilt estimate"
    for key in ("tilt_deg", "U95_tilt_deg"):
        v = d.get(key) if isinstance(d, dict) else None
        if not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
            raise GonioError("expected a gonio tilt-estimate --json result with a number "
                             f"≥ 0 here, got {v!r}", file=tilt if src != "tilt estimate"
                             else None, key=key)
    return float(d["tilt_deg"]) + float(d["U95_tilt_deg"]), (
        f"measured tilt ψ = {d['tilt_deg']:.4g}° (U95 {d['U95_tilt_deg']:.2g}°, {src})")


def deviation_budget(results: CalibrationResults, readings: Readings, protocol: Protocol,
                     settings: dict, *, kind: str = "physical", tilt=None,
                     monte_carlo_trials: int = 0, seed: int = 0, tilt_measured=None,
                     table_measured=None) -> tuple[AnnexABudget, str, list[str]]:
    """E's budget: the draft's four Annex A lines, plus, for ``kind="physical"``, the lines
    the validation showed to matter:

    - ``tilt_E``: the tilt × Earth-rate coupling at the site's latitude (metadata
      ``latitude_deg``; the equator's, the worst case, when not stated) with the tilt
      bound, or ψ + U95 of a measured tilt (``tilt``: a ``gonio tilt-estimate --json``
      file or dict), arcsine (clause 7 preamble, A.1);
    - ``K_P``, ``K_r``: the error of the 7.1 scale factor carried into E (7.1), when E's
      angles come from counts through that K.

    u(r): this calibration's own 7.5 result (Type A, ν = n − 1) when measured, else the
    protocol's ``annex_a.repeatability_arcsec`` (Type B: not this calibration's data).
    u(B_E): the longest actual time from zeroing to reading. k: the protocol's
    ``annex_a.coverage_factor`` when set (fixed by the laboratory), else t_95(ν_eff).
    ``tilt_measured`` (an :class:`gonio.specs.ogam_draft.budget_extra.AngleTiltCorrection`,
    :func:`angle_deviation_at_measured_tilt`): E's readings were corrected at the measured
    tilt, and the physical budget's ``tilt_E`` (the bound's worst case) is replaced by
    ``tilt_Em``, the correction's u (normal; the largest over the readings).
    ``table_measured`` (:func:`angle_deviation_at_table`'s info): E's readings were corrected
    by a calibrated table, and each point's table line is the calibration's (or the MPE
    line with the reason it was kept).
    Returns the budget, the u(r) source sentence and notes.
    """
    from gonio.errors import GonioError

    if kind not in BUDGET_KINDS:
        raise GonioError(f"budget must be one of {', '.join(BUDGET_KINDS)}, got {kind!r}",
                         key="budget")
    a = protocol.annex_a
    notes: list[str] = []
    rep = results.repeatability
    if rep.measured and rep.value is not None and math.isfinite(rep.value):
        n = int(rep.details.get("n_series"))
        u_r, dof, typ = float(rep.value), n - 1, "A"
        src = (f"the largest Bessel standard deviation over the points of this calibration's "
               f"own {n} series (7.5; Type A, ν = {n - 1})")
    else:
        u_r, dof, typ = a.repeatability_arcsec, math.inf, "B"
        src = (f"the protocol's annex_a.repeatability_arcsec = {u_r:g}″ (Type B: this "
               "calibration has no repeated series of its own; "
               f"{rep.reason or 'repeatability not measured'})")
    t_read = _time_to_reading_s(results, readings)
    dur_min = t_read / S_PER_MIN if t_read is not None else a.duration_min
    if t_read is not None:
        notes.append(f"u(B_E) over the longest time to reading, {t_read:g} s (A.4.3)")
    tilt_deg = settings["tilt_bound_deg"]
    if tilt is not None:
        tilt_deg, txt = _load_tilt(tilt)
        notes.append(f"{txt}: ψ + U95 = {tilt_deg:.4g}° bounds the tilt")
    extras = []
    if kind == "physical" and results.angle_deviation.measured:
        return _physical_point_budgets(results, readings, protocol, settings, tilt_deg, u_r,
                                       dof, typ, src, dur_min, notes, tilt_measured,
                                       monte_carlo_trials, seed, table_measured), src, notes
    budget = annex_a_budget(table_mpe_arcsec=settings["table_mpe_arcsec"], tilt_deg=tilt_deg,
                            zero_stability_dph=a.zero_stability_dph, duration_min=dur_min,
                            repeatability_arcsec=u_r, k=a.coverage_factor,
                            extra_components=extras, monte_carlo_trials=monte_carlo_trials,
                            seed=seed, repeatability_dof=dof, repeatability_type=typ,
                            repeatability_source=f"repeatability (A.4.4): {src}")
    e = results.angle_deviation
    if e.measured and e.value is not None and len(e.table):
        # E = ± max|E_i| stated by the interval of the extreme (beyond the draft) from this
        # one budget at every point; the draft's max|E_i| ± U is given beside (Annex A)
        budget = dataclasses.replace(budget, max_interval=e_max_interval(
            e.table["E_arcsec"], [budget] * len(e.table), one_budget=True,
            positions=e.table["position_deg"]))
    return budget, src, notes


def _point_reading_noise(t_s: float, n: int, noise, u_r, dof, typ, src):
    """(u, ν, type, source) of the r line of one 7.4 point whose E_i is the mean of ``n``
    series (7.4, 7.5): with the round-noise model ``noise`` = (u_q, fit) of the 7.4 series,
    one reading's noise at the point's time t from zeroing to reading,
    √(u_q² + N²(t + t²/T_s)) (ν the fit's pooled ν, Type A); without it the draft's u(r)
    (A.4.4; ``u_r``, ``dof``, ``typ``, ``src``); either over √n [physical budget]."""
    if noise is not None:
        u_q, nz = noise
        r_one = math.sqrt(u_q * u_q + nz.n2_arcsec2_per_s * (
            t_s + (t_s ** 2 / nz.static_s if nz.static_s else 0.0)))
        r_src = (f"reading noise at this point's time from zeroing to reading, {t_s:g} s: "
                 f"sqrt(u_q^2 + N^2 (t + t^2/T_s)), N^2 from the 7.4 series (7.5; nu = "
                 f"{nz.dof}); E_i is the mean of {n} series (7.4): /sqrt({n}) [physical "
                 "budget; the draft's A.4.4 takes the largest s]")
        return r_one / math.sqrt(n), max(int(nz.dof), 1), "A", r_src
    r_src = (f"repeatability (A.4.4): {src}; E_i is the mean of {n} series (7.4, 7.5): "
             f"u(r)/sqrt({n}) [physical budget: u(r)/sqrt(n)]")
    return u_r / math.sqrt(n), dof, typ, r_src


def _refuse_negative_times(readings, lines) -> None:
    """The physical budget takes each 7.4 (and 7.1) reading's time from zeroing to reading
    (docs/formats.md, "Time of a reading"): a negative ``time_s`` there is refused, naming
    the file and line, rather than reaching the square root of the reading noise."""
    df = readings.data
    bad = df[df["line"].isin(list(lines)) & (df["time_s"] < 0)]
    if len(bad):
        row = bad.iloc[0]
        raise GonioError(f"{float(row['time_s']):g} s is negative: on a rotation test time_s "
                         "is the time from the zeroing to the reading",
                         file=readings.path, line=int(row["line"]), column="time_s")


def _point_table_line(i: int, theta: float, extras: list, from_counts: bool, stops,
                      mpe_arcsec: float, table_measured) -> tuple:
    """(u or None, source, extras, ν) of the table line of 7.4 point ``i``: the calibrated
    table's (``table_measured`` of :func:`angle_deviation_at_table`: P and K_P replaced, ν
    propagated from the calibration's),
    else P and K_P as one line at MPE/√3 where E's angles come from counts through the 7.1 K
    (:func:`~gonio.specs.ogam_draft.budget_extra.table_line_u`), else Annex A's P."""
    from gonio.specs.ogam_draft.budget_extra import table_line_u

    why = ""
    if table_measured is not None and "u_arcsec" in table_measured and \
            table_measured["u_arcsec"][i] is not None:
        return (float(table_measured["u_arcsec"][i]), table_measured["sources"][i],
                [x for x in extras if x.symbol != "K_P"], float(table_measured["dof"][i]))
    if table_measured is not None and table_measured.get("reason"):
        why = f"; {table_measured['reason']}"
    if from_counts and any(x.symbol == "K_P" for x in extras):
        return (table_line_u(theta, stops, mpe_arcsec / math.sqrt(3.0)),
                "table positioning at the point, the common zero and the 7.1 stops, one "
                "error per position, each MPE/sqrt(3) (A.4.1; through K, 7.1) "
                "[physical budget: P and K_P as one line]" + why,
                [x for x in extras if x.symbol != "K_P"], math.inf)
    return None, "standard table positioning (A.4.1)" + why, extras, math.inf


def _physical_point_budgets(results, readings, protocol, settings, tilt_deg, u_r, dof, typ,
                            src, dur_min, notes, tilt_measured, monte_carlo_trials, seed,
                            table_measured=None):
    """E's physical budget per 7.4 point (beyond the draft; the draft's Annex A reading is
    :func:`deviation_budget` with ``kind="draft"``, one budget for every point). Returned:
    the budget of the point with the largest U (what E = ± max|E_i| is stated with: every
    point's interval |E_i| ± U_i then lies within max|E_i| ± U), the per-point budgets in its
    ``points``. Against Annex A's one budget:

    - ``r``: E_i is the mean over the n series present at the point (7.4, 7.5), so u/√n,
      u of one reading at this point's time t from zeroing to reading, √(u_q² + N²(t +
      t²/T_s)) with N² pooled from the 7.4 series
      (:func:`~gonio.specs.ogam_draft.item_uncertainty.round_noise`; ν its pooled ν), not
      the largest point's s (A.4.4); u(r)/√n where the noise cannot be estimated;
    - ``B_E``: the drift bound over this point's own time from zeroing to reading (A.4.3),
      not the longest;
    - ``K_P``, ``K_r``: an error δK of the 7.1 K is shared by the points and moves E_i by
      θ_i·δK/K (7.1, 7.4), so the lines are given at θ_i
      (:func:`~gonio.specs.ogam_draft.budget_extra.budget_extra_components`);
    - ``P`` and ``K_P`` as one line where E's angles come from counts through the 7.1 K: the
      table's error at the point, at the common zero and at the 7.1 stops, one error per
      table position (a stop that is also the point, 360° that is 0°), each u(P) = MPE/√3
      (A.4.1, 7.1; :func:`~gonio.specs.ogam_draft.budget_extra.table_line_u`); with a
      calibrated table covering E's positions (``table_measured``), the calibration's u at
      the point, its zero and the 7.1 stops instead (:func:`angle_deviation_at_table`);
    - ``K_r`` takes u of each 7.1 reading at its own time from zeroing to reading
      (u_q² + N²(t + t²/T_s), :func:`~gonio.specs.ogam_draft.item_uncertainty.round_noise`
      from the 7.4 series), not 7.4's u(r) at its longer read delay; u(r) where the round
      noise cannot be estimated (one series);
    - ``phi_e`` (A.4.2, a scale error θ(1 − cos) of the tilted sensing plane) is 0 where E's
      angles come from counts through the 7.1 K measured on the same mount and axis
      orientation: that K is the mount's and absorbs it.
    """
    import dataclasses

    from gonio.specs.ogam_draft.item_uncertainty import COUNT_QUANTUM_U

    e = results.angle_deviation
    pts = e.table
    pos = pts["position_deg"].to_numpy(dtype=float)
    long = e.tables["readings"]
    n_by_round = long.dropna(subset=["E_arcsec"]).groupby("round")["E_arcsec"].count()
    n_i = n_by_round.reindex(pts["round"]).fillna(1).clip(lower=1).to_numpy(dtype=float)
    from_counts = results.scale_factor_for_angles_source == "7.1" and \
        e.details.get("scale_factor_for_angles_counts_per_deg") is not None
    same_mount = from_counts and protocol.scale_factor is not None and \
        protocol.angle_deviation is not None and \
        protocol.angle_deviation.orientation == protocol.scale_factor.orientation
    sf_u = None
    _refuse_negative_times(readings, set(long["line"]) | (
        set(results.scale_factor.used_lines) if from_counts else set()))
    rn = _round_noise(results, readings, protocol) if from_counts else {}
    if rn:
        k_cnt = abs(float(np.mean(results.scale_factor.table["K_i_counts_per_deg"])))
        u_q = COUNT_QUANTUM_U / k_cnt * ARCSEC_PER_DEG
        df = readings.data
        t_k = df.loc[df["line"].isin(list(results.scale_factor.used_lines)),
                     "time_s"].to_numpy(dtype=float)
        nz = rn["noise"]
        grow = t_k + (t_k * t_k / nz.static_s if nz.static_s else 0.0)
        sf_u = np.sqrt(u_q * u_q + nz.n2_arcsec2_per_s * grow)
        notes.append("K_r: u of each 7.1 reading at its own time from zeroing to reading, "
                     f"from the angle noise of the 7.4 series (N^2 = {nz.n2_arcsec2_per_s:.3g} "
                     f"arcsec^2/s, nu = {nz.dof}) [beyond the draft]")
    notes[:] = [n for n in notes if not n.startswith("u(B_E) over the longest time")]
    notes.append("u(B_E) over each point's own time from zeroing to reading (A.4.3)")
    t_line = readings.data.set_index("line")["time_s"]
    t_long = pd.Series(t_line.reindex(long["line"]).to_numpy(dtype=float), index=long.index)
    t_i = t_long.groupby(long["round"]).max().reindex(pts["round"]).to_numpy(dtype=float)
    phi_e = 0.0 if same_mount else None
    phi_src = ("sensing plane not parallel to table plane (A.4.2): a scale error the 7.1 K, "
               "measured on the same mount, absorbs (0) [physical budget]") if same_mount \
        else "sensing plane not parallel to table plane (A.4.2)"
    df = readings.data
    stops = df.loc[df["line"].isin(list(results.scale_factor.used_lines)),
                   "table_deg"].to_numpy(dtype=float) if from_counts else np.array([])
    a = protocol.annex_a

    def point_budget(i: int, theta: float, point_notes: list, mc_trials: int):
        extras = _physical_extras(results, readings, protocol, settings, tilt_deg, u_r,
                                  point_notes, tilt_measured, theta_deg=theta,
                                  sf_reading_u_arcsec=sf_u)
        r_i, r_dof, r_typ, r_src = _point_reading_noise(
            t_i[i], int(n_i[i]), (u_q, nz) if rn else None, u_r, dof, typ, src)
        d_i = t_i[i] / S_PER_MIN if math.isfinite(t_i[i]) else dur_min
        table_u, t_src, extras, t_dof = _point_table_line(
            i, theta, extras, from_counts, stops, settings["table_mpe_arcsec"], table_measured)
        return annex_a_budget(
            table_mpe_arcsec=settings["table_mpe_arcsec"], tilt_deg=tilt_deg,
            zero_stability_dph=a.zero_stability_dph, duration_min=d_i,
            repeatability_arcsec=r_i, k=a.coverage_factor, extra_components=extras,
            monte_carlo_trials=mc_trials, seed=seed,
            repeatability_dof=r_dof, repeatability_type=r_typ, repeatability_source=r_src,
            phi_e_arcsec=phi_e, phi_e_source=phi_src, table_u_arcsec=table_u,
            table_source=t_src, table_dof=t_dof)

    sub = [point_budget(i, theta, [], 0) for i, theta in enumerate(pos)]
    # E = ± max|E_i| is stated with the LARGEST of the points' U (its point's budget, notes
    # and Monte Carlo): every point's |E_i| + U_i then lies within max|E_i| + U and every
    # |E_i| − U_i above max|E_i| − U, whichever point is the extreme; the extreme point's
    # own U could leave another point's interval outside the stated one (U grows with θ_i
    # and the point's time)
    at = int(np.argmax([b.U_arcsec for b in sub]))
    sub[at] = point_budget(at, float(pos[at]), notes, monte_carlo_trials)
    notes.append(f"physical budget per 7.4 point; E's U is the largest of the points' U, at "
                 f"{pos[at]:g} deg [beyond the draft]")
    points = tuple({"position_deg": float(p), "u_c_arcsec": float(b.u_c_arcsec),
                    "U_arcsec": float(b.U_arcsec), "k": float(b.k),
                    "nu_eff": None if math.isinf(b.gum.dof) else float(b.gum.dof)}
                   for p, b in zip(pos, sub))
    # the parameters other items take from E's budget (C_v, C_g: one reading's u(r), A.4.4;
    # the longest time to reading) stay those of Annex A's reading, not this point's
    params = dict(sub[at].parameters, repeatability_arcsec=u_r, duration_min=dur_min)
    prog = programme_rounds(protocol) if from_counts else None
    points, bounds = _with_table_bounds(points, pos, sub, stops, settings["table_mpe_arcsec"],
                                        None if prog is None else prog[0])
    return dataclasses.replace(sub[at], points=points, parameters=params,
                               max_interval=e_max_interval(pts["E_arcsec"], sub,
                                                           positions=pos, table=bounds))


#: The source marking a 7.4 point's table line at the MPE where E's angles come from counts
#: through the 7.1 K (:func:`_point_table_line`), which E's extreme takes by its bound.
_MPE_TABLE_LINE = "[physical budget: P and K_P as one line]"


def _with_table_bounds(points, pos, budgets, stops, mpe_arcsec: float, programme_stops=None):
    """The per-point dicts ``points`` with the table's bound, u and ν without the table line
    (:func:`_point_table_bounds`) where some point has one, and those bounds."""
    bounds = _point_table_bounds(pos, budgets, stops, mpe_arcsec, programme_stops)
    if any(b > 0 for b in bounds[0]):
        points = tuple(dict(d, table_bound_arcsec=b, u_without_table_arcsec=u,
                            nu_without_table=None if math.isinf(n) else n,
                            **point_u_with_bound(b, u, n))
                       for d, b, u, n in zip(points, *bounds))
    return points, bounds


def point_u_with_bound(b_arcsec: float, u_arcsec: float, nu: float) -> dict:
    """E_i's stated U where the table enters by its bound b_i (:func:`_point_table_bounds`):
    U_i = k·u_i + b_i, k = t95(ν_i) of the point's other lines (u_i, ν_i without the table
    line; :func:`gonio.result.statement.coverage_k`, ν as stated). For every table within its
    MPE the error of E_i is δ + ε with |δ| ≤ b_i and ε of u_i, so P(|δ + ε| ≤ k·u_i + b_i) ≥
    P(|ε| ≤ k·u_i) = 95 % (JCGM 100 4.3.7 for δ, as E's extreme takes it,
    :func:`e_max_interval`); the table line at MPE/√3 per position (positions independent)
    does not hold the corner table (b = 0.457″ at 360° where that U was 0.36″). Its k is the
    one of u_i. Each point's ``U_arcsec``/``k`` stay the table line's at MPE/√3 per position
    (positions independent; E_i's decimals follow them), beside, not stated.

    >>> d = point_u_with_bound(0.457, 0.1, math.inf)
    >>> round(d["U_bound_arcsec"], 4), round(d["k_bound"], 2)
    (0.653, 1.96)
    """
    from gonio.result.statement import coverage_k

    k = coverage_k(nu)
    return {"U_bound_arcsec": float(k * u_arcsec + b_arcsec), "k_bound": float(k)}


def _point_table_bounds(pos, budgets, stops, mpe_arcsec: float, programme_stops=None):
    """Per 7.4 point (the physical budgets ``budgets``): the table's bound b_i on E_i, and u
    and ν of the point's budget without its table line, for E's extreme
    (:func:`e_max_interval`). Where the point's table line is the MPE's through the 7.1 K
    (P and K_P as one line, :func:`_point_table_line`), the table's error at the point is
    Σ_p c_p e_p (:func:`~gonio.specs.ogam_draft.budget_extra.table_error_coefficients`) with
    every |e_p| ≤ MPE (A.4.1), so |δ_i| ≤ b_i = MPE·Σ_p |c_p| at a vertex of the box (JCGM 100
    4.3.7; the analogue of K's MPE·Σ|c_p|): one table — the corner, the zero at −MPE and every
    stop at +MPE — moves every point at once, which per-point lines at MPE/√3 combined
    with the other points' noise do not hold. u without it: √(u_c² − u_P²), ν by
    Welch–Satterthwaite over the other lines (JCGM 100 G.4.1). A calibrated table's line or
    Annex A's P stays in u (b_i = 0). ``programme_stops``: the programme's 7.1 stops, b_i
    the larger over them and over the stops read (a 7.1 reading set aside never lowers it:
    :func:`~gonio.specs.ogam_draft.table_periodic.programme_bound`); the box's vertex in the
    stated reading of the MPE at the zero (:func:`~gonio.specs.ogam_draft.table_periodic.
    table_worst_bound`)."""
    from gonio.specs.ogam_draft.budget_extra import table_error_coefficients
    from gonio.specs.ogam_draft.table_periodic import programme_bound, table_worst_bound

    out_b, out_u, out_n = [], [], []
    for theta, b in zip(pos, budgets):
        tab = [c for c in b.gum.contributions
               if c.symbol == "P" and _MPE_TABLE_LINE in c.source]
        if not tab:
            out_b.append(0.0)
            out_u.append(float(b.u_c_arcsec))
            out_n.append(float(b.gum.dof))
            continue
        rest = [x for x in b.gum.contributions if x is not tab[0]]
        u2 = sum(x.contribution ** 2 for x in rest)
        den = sum(x.contribution ** 4 / x.dof for x in rest if math.isfinite(x.dof) and x.dof > 0)
        out_b.append(programme_bound(lambda st, th=float(theta): table_worst_bound(
            table_error_coefficients(th, st), mpe_arcsec), stops, programme_stops))
        out_u.append(math.sqrt(u2))
        out_n.append(math.inf if den == 0 else u2 * u2 / den)
    return out_b, out_u, out_n


def e_stated_uncertainty(unc: dict, max_interval: dict | None) -> dict:
    """E's stated uncertainty (results.json ``items.angle_deviation.uncertainty``): the 95 %
    interval of max|E_i| (:func:`e_max_interval`; from the physical budget's per-point figures,
    or from the draft's one Annex A budget at every point under ``--budget draft``) is E's one
    statement — ``interval`` [lower, upper], ``k`` None, ``U`` = upper − max|E_i| (the guard
    band of a decision against +MPE), ``k_source``
    :data:`gonio.result.statement.K_SOURCE_MAX_ABS` — and the draft's max|E_i| ± U (7.4,
    Annex A) is given beside (``extra.uncertainty.draft_reading``), not certified. Without
    an interval (E not measured) ``unc`` as it is.

    >>> u = e_stated_uncertainty({"u_c": 0.1, "U": 0.2, "k": 2.0, "nu_eff": 50.0,
    ...     "k_source": "welch-satterthwaite"}, {"lower_arcsec": 0.0, "upper_arcsec": 0.5,
    ...     "max_abs_arcsec": 0.25, "p": 0.95})
    >>> u["interval"], u["U"], u["k"], u["k_source"], u["nu_eff"]
    ([0.0, 0.5], 0.25, None, 'max-abs-interval', None)
    """
    from gonio.result.statement import K_SOURCE_MAX_ABS

    if not max_interval:
        return unc
    lo, hi = float(max_interval["lower_arcsec"]), float(max_interval["upper_arcsec"])
    out = {**unc, "U": hi - float(max_interval["max_abs_arcsec"]), "k": None, "nu_eff": None,
           "coverage_probability": float(max_interval["p"]), "k_source": K_SOURCE_MAX_ABS,
           "interval": [lo, hi]}
    if max_interval.get("u_at_max_arcsec") is not None:
        # u_c: the standard uncertainty of max|E_i| by the law of propagation at the
        # estimates (JCGM 100 5.1.2: ∂max|E_i|/∂E_j = ±1 at the point j where |E_i| is
        # largest, 0 elsewhere), not one point's largest u_c
        out["u_c"] = float(max_interval["u_at_max_arcsec"])
        at = max_interval.get("position_at_max")
        out["u_c_of"] = E_U_C_OF.format(p="—" if at is None else f"{at:g}")
    return out


#: results.json ``items.angle_deviation.uncertainty.u_c_of`` (the position as ``{p}``)
E_U_C_OF = ("max|E_i|: the law of propagation at the estimates (JCGM 100 5.1.2), u_c of E_i at "
            "{p}°, the point where |E_i| is largest; the 95 % interval is the statement and U is "
            "its upper end minus max|E_i|, not k·u_c")


def e_max_interval(e_arcsec, budgets, one_budget: bool = False, positions=None,
                   table=None) -> dict:
    """The 95 % interval of E's extreme, max_i |E_i,true| (7.4's E = ± max|E_i|), from the
    points' E_i and their physical budgets' u_c and ν_eff: [max(0, max_i(|E_i| − c_L u_i)),
    max_i(|E_i| + c_H u_i)] (:func:`uncertainty.extreme.max_abs_interval`; beyond the draft).
    It holds the truth with probability ≥ 95 % for every pattern of the true E_i and any
    correlation between the points (the shared K and zero), and its factors are the
    smallest of that form that do (the upper one's worst case: one point far out; the
    lower one's: every E_i zero). Each point's ν is taken as stated
    (:func:`gonio.result.statement.stated_nu`: the integer part, ∞ above 1000), as its k.

    ``one_budget``: ``budgets`` is the draft's one Annex A budget repeated at every point
    (``--budget draft``): every u_i is its u_c, every ν_i its ν_eff, which the dict then
    records (``u_c_arcsec``, ``nu_eff``: None for ∞) so the interval is recomputed from
    results.json alone. ``u_at_max_arcsec``/``position_at_max``: u_c of the point where |E_i|
    is largest and its position (``positions``, the points' table positions in degrees),
    the standard uncertainty of max|E_i| by the law of propagation at the estimates. The
    draft's U is a statement about one point: max|E_i| ± U covers
    max|E_i,true| only about 0.95^12 ≈ 54 % of the time where every true E_i is 0.

    ``table``: (b_i, u_i, ν_i) of :func:`_point_table_bounds` — the table's bound on each
    E_i and u, ν of each point without its table line — for the physical budget: the
    interval from the points' other lines, each point's reach widened by its b_i
    (:func:`uncertainty.extreme.max_abs_interval`'s ``bound``), which holds every table
    within its MPE (the corner included). The draft's one budget (``one_budget``) keeps its
    table lines in u (Annex A's reading, reproducible).
    """
    from gonio.result.statement import stated_nu
    from uncertainty.extreme import max_abs_interval

    # each point's ν as stated and as its k is computed (the integer part, ∞ above 1000;
    # GUM G.6.4): the interval is never narrower than one recomputed from the printed ν
    if table is not None and any(b > 0 for b in table[0]):
        r = max_abs_interval(np.asarray(e_arcsec, dtype=float), table[1],
                             [stated_nu(n) for n in table[2]], bound=table[0])
    else:
        table = None
        r = max_abs_interval(np.asarray(e_arcsec, dtype=float), [b.u_c_arcsec for b in budgets],
                             [stated_nu(b.gum.dof) for b in budgets])
    e = np.abs(np.asarray(e_arcsec, dtype=float))
    at = int(np.argmax(e))                   # the first of equal largest |E_i|
    out = {"u_at_max_arcsec": float(budgets[at].u_c_arcsec),
           "position_at_max": (None if positions is None
                               else float(np.asarray(positions, dtype=float)[at])),
           "lower_arcsec": r.lower, "upper_arcsec": r.upper, "max_abs_arcsec": r.estimate,
           "p": r.p, "c_lower": r.c_lower, "c_upper": r.c_upper, "points": r.m,
           "basis": "max_i(|E_i| + c_H u_i) above, max(0, max_i(|E_i| - c_L u_i)) below, "
                    + ("u_c and nu_eff of the draft's one Annex A budget at every point"
                       if one_budget else "per point u_c and nu_eff")
                    + " (Student t at nu as stated: its integer part, normal above 1000); "
                      ">= 95 % for every pattern of the true E_i "
                      "(Sidak below, the extreme point above) [beyond the draft]"}
    if table is not None:
        out["basis"] = out["basis"].replace(
            "per point u_c and nu_eff",
            "per point u and nu_eff without the table line, each reach widened by the "
            "table's bound at the point, MPE*sum|c_p| (every table within the A.4.1 MPE, the "
            "common zero and the 7.1 stops' errors shared by the points; JCGM 100 4.3.7)")
        out["table_bound_arcsec"] = [float(b) for b in table[0]]
    if one_budget:
        b = budgets[0]
        out["u_c_arcsec"] = float(b.u_c_arcsec)
        out["nu_eff"] = None if math.isinf(b.gum.dof) else float(b.gum.dof)
    return out


def _scale_factor_tilt(results, readings, protocol, budget) -> float:
    """A_K of :func:`gonio.specs.ogam_draft.budget_extra.scale_factor_tilt_bias` for this calibration's 7.1
    rounds, at the budget's tilt bound and the file's latitude (the equator's, the worst
    case, when not stated); 0 when K does not come from 7.1."""
    from gonio.specs.ogam_draft.budget_extra import scale_factor_tilt_bias

    if not results.scale_factor.measured or protocol.scale_factor is None:
        return 0.0
    lat = metadata_float(readings.metadata, "latitude_deg", file=readings.path)
    df = readings.data
    sf = df[df["line"].isin(list(results.scale_factor.used_lines))]
    return scale_factor_tilt_bias(sf, protocol, 0.0 if lat is None else lat,
                                  float(budget.parameters["tilt_deg"]))


def tilt_correction(results, readings, protocol):
    """(correction, why): K's tilt correction from the in-situ tilt estimate
    (:func:`gonio.specs.ogam_draft.budget_extra.scale_factor_tilt_correction`) when the protocol
    has ``[tilt_estimate]``, the readings hold its rows, K comes from 7.1 and the file states
    ``latitude_deg`` (the estimate's Ω_⊥); else (None, the reason, or "" when the protocol
    has no tilt estimate). Counts of the estimate are converted with the 7.1 K."""
    from gonio.errors import GonioError
    from gonio.specs.ogam_draft.budget_extra import scale_factor_tilt_correction
    from gonio.specs.ogam_draft.tilt_estimate import tilt_estimate_from_readings

    if protocol.tilt_estimate is None:
        return None, ""
    df = readings.data
    if not results.scale_factor.measured or protocol.scale_factor is None:
        return None, "K not measured by 7.1: no tilt correction"
    if not (df["test"] == "tilt_estimate").any():
        return None, ("the protocol has [tilt_estimate] but the readings hold no tilt_estimate "
                      "rows: K carries the coupling at the A.1 bound (K_tilt)")
    lat = metadata_float(readings.metadata, "latitude_deg", file=readings.path)
    if lat is None:
        return None, ("the readings do not state latitude_deg: the tilt estimate needs it, "
                      "K carries the coupling at the A.1 bound (K_tilt)")
    sf = df[df["line"].isin(list(results.scale_factor.used_lines))]
    try:
        est = tilt_estimate_from_readings(readings, float(results.scale_factor.value), lat)
        return scale_factor_tilt_correction(sf, protocol, lat, est), ""
    except GonioError as exc:
        return None, (f"the tilt estimate could not correct K ({exc.args[0] if exc.args else exc}):"
                      " K carries the coupling at the A.1 bound (K_tilt)")


def tilt_beyond_bound(results, readings, protocol, settings: dict) -> tuple[dict, list]:
    """(settings, findings): the rule where the in-situ tilt estimate contradicts the stated
    tilt bound (Annex A.1 bounds the sensing plane's tilt; the readings' or protocol's
    ``tilt_bound_deg``; beyond the draft).

    Where the estimate's 95 % interval lies wholly beyond the bound (ψ − U95(ψ) > bound),
    the mounting did not meet the condition the bound states, and the certificate says so
    (a ``tilt-beyond-bound`` finding, flagged). What is done:

    * the correction at the measured ψ stays applied (K and E corrected, U with the
      correction's uncertainty, lines K_te and tilt_Em): the measurement is the better
      knowledge of the tilt;
    * every line the budget takes at the bound (the coupling of C_v, C_g, K_l, and of E
      and K where the correction cannot be made) is taken at ψ + U95(ψ), the measured
      tilt's upper 95 % limit, in place of the stated bound (``settings`` returned with
      ``tilt_bound_deg`` widened); the measurand's text keeps the stated bound.

    An interval that straddles the bound (ψ − U95 ≤ bound < ψ + U95) does not contradict it,
    but the bound no longer bounds what was measured (ψ = 0.16° ± 0.06° against 0.1°: a line
    at 0.1° would hold the coupling with well under 95 %): no finding, and the lines taken at
    the bound are taken at ψ + U95 all the same (the calibration notes it). An interval wholly
    within the bound (ψ + U95 ≤ bound) changes nothing. No estimate (no
    ``[tilt_estimate]``, no rows, K not measured): nothing changes.

    >>> from types import SimpleNamespace as N
    >>> tc = N(tilt_deg=0.17, u_tilt_deg=0.1, k95=2.0)
    >>> beyond_bound(tc, 0.1), beyond_bound(N(tilt_deg=0.17, u_tilt_deg=0.02, k95=2.0), 0.1)
    (False, True)
    """
    tc, _ = tilt_correction(results, readings, protocol)
    bound = float(settings["tilt_bound_deg"])
    if tc is None:
        return settings, []
    psi, big_u = float(tc.tilt_deg), float(tc.k95) * float(tc.u_tilt_deg)
    if psi + big_u <= bound:
        return settings, []
    if not beyond_bound(tc, bound):         # the bound may hold, and may not: the lines at
        return {**settings, "tilt_bound_deg": psi + big_u}, []   # the tilt's upper limit
    rows = readings.data[readings.data["test"] == "tilt_estimate"]
    line = int(rows["line"].min()) if len(rows) else None
    st = state(psi, big_u)                  # ψ, U and the ends at U's decimal place
    at = lambda x: round_half_up(x, st.decimals)  # noqa: E731
    msg = (f"the in-situ tilt estimate measured psi = {at(psi)}° (U95 {st.U}°, interval "
           f"[{at(psi - big_u)}, {at(psi + big_u)}]°), beyond the stated tilt bound "
           f"{bound:g}° (tilt_bound_deg, Annex A.1): the mounting does not meet the bound; K "
           "and E stay corrected at the measured tilt, and every line taken at the bound is "
           f"taken at psi + U95 = {at(psi + big_u)}°")
    return ({**settings, "tilt_bound_deg": psi + big_u},
            [Finding("tilt-beyond-bound", msg, "flagged", file=None if readings.path is None
                     else str(readings.path), line=line, test="tilt_estimate", clause="A.1",
                     rule="psi - U95(psi) > tilt_bound_deg: flagged, bound lines at psi + U95")])


def _tilt_bound_settings(res, kept, proto, settings: dict, findings) -> tuple[dict, list, str]:
    """:func:`tilt_beyond_bound` for :func:`analyse`: (settings, findings with its finding,
    the calibration note where the bound lines are widened without a finding, else "")."""
    stated_bound = settings["tilt_bound_deg"]
    settings, beyond = tilt_beyond_bound(res, kept, proto, settings)
    note = ""
    if not beyond and settings["tilt_bound_deg"] != stated_bound:
        note = (f"the lines taken at the tilt bound are taken at the measured tilt's upper "
                f"95 % limit psi + U95 = {settings['tilt_bound_deg']:.3g} deg, above the "
                f"stated bound {float(stated_bound):g} deg (A.1) [beyond the draft]")
    return settings, list(findings) + beyond, note


def tilt_text(psi_deg: float, U95_psi_deg: float, azimuth_deg: float | None = None,
              U95_azimuth_deg: float | None = None) -> str:
    """The calibration's notes' text of a measured tilt: "psi = ψ deg (U95 U deg)" and, with
    an azimuth, ", azimuth α deg (U95 U deg)" — each value at its U's decimal place, U to two
    significant digits (:func:`gonio.result.statement.state`, the rule the certificate
    states them by, so a note and the certificate print the same ψ).

    >>> tilt_text(0.04512, 0.00661, 29.61, 8.43)
    'psi = 0.0451 deg (U95 0.0066 deg), azimuth 29.6 deg (U95 8.4 deg)'
    >>> tilt_text(0.04512, 0.0203)
    'psi = 0.045 deg (U95 0.020 deg)'
    """
    p = state(float(psi_deg), float(U95_psi_deg))
    out = f"psi = {p.value_text} deg (U95 {p.U_text} deg)"
    if azimuth_deg is not None:
        a = state(float(azimuth_deg), float(U95_azimuth_deg))
        out += f", azimuth {a.value_text} deg (U95 {a.U_text} deg)"
    return out


def beyond_bound(tc, bound_deg: float) -> bool:
    """Whether a measured tilt's 95 % interval lies wholly beyond ``bound_deg``:
    ψ − k95 · u(ψ) > bound (:func:`tilt_beyond_bound`)."""
    return float(tc.tilt_deg) - float(tc.k95) * float(tc.u_tilt_deg) > float(bound_deg)


def _nonlinearity_tilt(results, readings, protocol, budget) -> float:
    """A_l of :func:`gonio.specs.ogam_draft.budget_extra.nonlinearity_tilt_bias` for the largest and smallest
    of this calibration's 7.1 rounds, at the budget's tilt bound and the file's latitude
    (the equator's when not stated, as :func:`_scale_factor_tilt`)."""
    from gonio.specs.ogam_draft.budget_extra import nonlinearity_tilt_bias

    if not results.scale_factor.measured or protocol.scale_factor is None:
        return 0.0
    lat = metadata_float(readings.metadata, "latitude_deg", file=readings.path)
    t = results.scale_factor.table
    df = readings.data
    sf = df.set_index("line").loc[t["line"].to_numpy()]       # in the table's round order
    k_i = t["K_i_counts_per_deg"].to_numpy(dtype=float)
    return nonlinearity_tilt_bias(sf, protocol, 0.0 if lat is None else lat,
                                  float(budget.parameters["tilt_deg"]),
                                  int(np.argmax(k_i)), int(np.argmin(k_i)))


def _round_coupling(results, readings, protocol, budget):
    """(a_k, b_k) of :func:`gonio.specs.ogam_draft.budget_extra.scale_factor_round_coupling` for this
    calibration's 7.1 rounds in the table's order, at the budget's tilt bound and the file's
    latitude (the equator's when not stated, as :func:`_scale_factor_tilt`); None without 7.1."""
    from gonio.specs.ogam_draft.budget_extra import scale_factor_round_coupling

    if not results.scale_factor.measured or protocol.scale_factor is None:
        return None
    lat = metadata_float(readings.metadata, "latitude_deg", file=readings.path)
    sf = readings.data.set_index("line").loc[results.scale_factor.table["line"].to_numpy()]
    return scale_factor_round_coupling(sf, protocol, 0.0 if lat is None else lat,
                                       float(budget.parameters["tilt_deg"]))


def _measured_round_tilt(results, readings, protocol, correction):
    """Each 7.1 round's tilt coupling at the measured tilt
    (:func:`gonio.specs.ogam_draft.budget_extra.measured_round_tilt`), rounds in the table's
    order, at the file's latitude (the tilt estimate needs it stated); None without a
    correction (K_l then allows for the A.1 bound, :func:`_round_coupling`)."""
    from gonio.specs.ogam_draft.budget_extra import measured_round_tilt

    if correction is None:
        return None
    lat = metadata_float(readings.metadata, "latitude_deg", file=readings.path)
    sf = readings.data.set_index("line").loc[results.scale_factor.table["line"].to_numpy()]
    return measured_round_tilt(sf, protocol, lat, correction)


def _round_noise(results, readings, protocol) -> dict:
    """The gyro's noise over the 7.1 rounds for K_l's Monte Carlo: ``noise``
    (:func:`gonio.specs.ogam_draft.item_uncertainty.round_noise` from the 7.4 series that 7.5
    uses, the quantum of one count through K, the static phase when the Earth-rate
    compensation is measured) and ``time_s`` (each round's time from zeroing to reading);
    empty without repeated 7.4 series or without the rounds' times."""
    from gonio.specs.ogam_draft.item_uncertainty import COUNT_QUANTUM_U, round_noise

    rp = results.repeatability
    if not rp.measured or not results.angle_deviation.measured \
            or "time_s" not in readings.data.columns:
        return {}
    df = readings.data.set_index("line")
    t_sf = df.loc[results.scale_factor.table["line"].to_numpy(), "time_s"].to_numpy(dtype=float)
    ad = results.angle_deviation.tables["readings"]
    ad = ad[ad["line"].isin(list(rp.used_lines))]
    t_ad = df.loc[ad["line"].to_numpy(), "time_s"].to_numpy(dtype=float)
    if not np.isfinite(t_sf).all() or not np.isfinite(t_ad).any():
        return {}
    k = abs(float(np.mean(results.scale_factor.table["K_i_counts_per_deg"])))
    static = protocol.session.static_s if protocol.session.earth_compensation == "measured" \
        else None
    noise = round_noise(ad["E_arcsec"], ad["round"], t_ad, COUNT_QUANTUM_U / k * ARCSEC_PER_DEG,
                        static)
    return {"noise": noise, "time_s": t_sf}


def _physical_extras(results, readings, protocol, settings, tilt_deg, u_r, notes,
                     tilt_measured=None, theta_deg=None, sf_reading_u_arcsec=None):
    """The beyond-the-draft lines of the physical budget (see :func:`deviation_budget`)."""
    from dataclasses import replace

    from gonio.specs.ogam_draft.budget_extra import (ExtraComponent, budget_extra_components,
                                    tilt_coupling_coefficients)
    from gonio.physics.earth import earth_rate_split
    from gonio.units import dps_to_arcsec_s

    df = readings.data
    lat = metadata_float(readings.metadata, "latitude_deg", file=readings.path)
    if lat is None:
        lat = 0.0
        notes.append("latitude not stated in the readings file: the coupling line uses the "
                     "equator's Earth rate (the worst case for a vertical axis)")
    used = results.angle_deviation.used_lines
    ad = df[df["line"].isin(list(used))]
    sf = df[df["line"].isin(list(results.scale_factor.used_lines))]
    from_counts = results.scale_factor_for_angles_source == "7.1" and \
        results.angle_deviation.details.get("scale_factor_for_angles_counts_per_deg") is not None
    adi = protocol.angle_deviation
    if adi is None:
        notes.append("the protocol has no angle_deviation item: no coupling line")
        return []
    proto = replace(protocol, annex_a=replace(protocol.annex_a, tilt_bound_deg=tilt_deg,
                                              table_mpe_arcsec=settings["table_mpe_arcsec"]))
    if from_counts and len(sf) and protocol.scale_factor is not None:
        extras = budget_extra_components(pd_concat(sf, ad), proto, lat, u_r, truth="intrinsic",
                                         theta_deg=theta_deg,
                                         sf_reading_u_arcsec=sf_reading_u_arcsec)
    else:
        th = np.abs(ad["table_deg"].to_numpy(dtype=float))
        ci, si = tilt_coupling_coefficients(th, ad["time_s"].to_numpy(dtype=float),
                                            adi.rate_dps, adi.read_delay_s)
        omega = dps_to_arcsec_s(earth_rate_split(lat, adi.orientation).perpendicular_dps) * \
            math.sin(math.radians(tilt_deg))
        extras = [ExtraComponent("tilt_E", "tilt x Earth-rate coupling to the reading",
                                 float(omega * np.max(np.hypot(ci, si))), "arcsine")]
        if results.scale_factor_for_angles_source == "metadata":
            notes.append("E's angles use the nominal scale factor of the metadata, whose "
                         "error is not known to this calibration and is not in the budget")
    if tilt_measured is not None:    # E corrected at the measured tilt: the correction's u
        tm = tilt_measured
        extras = [e if e.symbol != "tilt_E" else ExtraComponent(
            "tilt_Em", f"tilt x Earth-rate coupling corrected at the measured tilt "
            f"({tilt_text(tm.tilt_deg, tm.U95_tilt_deg, tm.azimuth_deg, tm.U95_azimuth_deg)}):"
            f" the correction's "
            f"u from the tilt estimate's covariance (nu = {tm.dof})",
            float(np.max(tm.u_arcsec)) if tm.u_arcsec.size else 0.0, "normal")
            for e in extras]
        notes.append("E corrected for the tilt x Earth-rate coupling at the measured tilt "
                     + tilt_text(tm.tilt_deg, tm.U95_tilt_deg, tm.azimuth_deg,
                                 tm.U95_azimuth_deg) + " (largest "
                     f"correction {float(np.max(np.abs(tm.error_arcsec))):.3g} arcsec) "
                     "[beyond the draft]")
    return [ExtraComponent(e.symbol, e.source.replace(" (validation)", "") +
                           f" [beyond the draft: {EXTRA_CLAUSES.get(e.symbol, '')}]",
                           e.half_width_arcsec, e.distribution) for e in extras]


def angle_deviation_at_measured_tilt(results: CalibrationResults, readings: Readings,
                                     protocol: Protocol):
    """(results, correction): E's readings corrected for the tilt × Earth-rate coupling at
    the tilt the in-situ estimate measured (beyond the draft;
    :func:`gonio.specs.ogam_draft.budget_extra.angle_tilt_correction`), or
    (``results`` unchanged, None) where no tilt was measured, E's angles do not come from
    counts through the 7.1 K, or 7.4 is not in 7.1's orientation (E then keeps the bound's
    line ``tilt_E``).

    Every E_ij minus its coupling; E_i, E and the matrix recomputed from them as 7.4 does
    (:func:`gonio.specs.ogam_draft.items.angle_deviation`); the draft's reading (as
    measured) is kept in ``details.estimates.draft`` and the per-point column
    ``E_draft_arcsec``."""
    from gonio.specs.ogam_draft.budget_extra import angle_tilt_correction

    e = results.angle_deviation
    if protocol.tilt_estimate is None or not e.measured or \
            results.scale_factor_for_angles_source != "7.1" or \
            e.details.get("scale_factor_for_angles_counts_per_deg") is None or \
            protocol.angle_deviation is None or protocol.scale_factor is None or \
            protocol.angle_deviation.orientation != protocol.scale_factor.orientation:
        return results, None
    tc, _ = tilt_correction(results, readings, protocol)
    if tc is None:
        return results, None
    df = readings.data
    long = e.tables["readings"].copy()
    t_by_line = df.set_index("line")["time_s"]
    rows = pd.DataFrame({"table_deg": long["table_deg"].to_numpy(dtype=float),
                         "time_s": t_by_line.loc[long["line"]].to_numpy(dtype=float)})
    sf = df[df["line"].isin(list(results.scale_factor.used_lines))]
    lat = metadata_float(readings.metadata, "latitude_deg", file=readings.path)
    atc = angle_tilt_correction(sf, rows, protocol, float(lat), tc)
    long["E_draft_arcsec"] = long["E_arcsec"]
    long["tilt_error_arcsec"] = atc.error_arcsec
    long["E_arcsec"] = long["E_draft_arcsec"] - atc.error_arcsec
    points = e.table.copy()
    points["E_draft_arcsec"] = points["E_arcsec"]
    value, at, matrix = _e_points_from_readings(points, long)
    details = dict(e.details, max_abs_arcsec=abs(value),
                   position_deg=float(points["position_deg"][at]), stated="tilt_corrected")
    details["estimates"] = {
        "draft": {"label": E_TILT_CORRECTED["draft"], "value": float(e.value),
                  "max_abs_arcsec": float(e.details["max_abs_arcsec"]),
                  "position_deg": float(e.details["position_deg"])},
        "corrected": {"label": E_TILT_CORRECTED["corrected"], "value": float(value)}}
    details["tilt_correction"] = {
        "label": E_TILT_CORRECTED["note"], "tilt_deg": atc.tilt_deg,
        "azimuth_deg": atc.azimuth_deg, "dof": atc.dof,
        "max_abs_correction_arcsec": float(np.max(np.abs(atc.error_arcsec))),
        "u_max_arcsec": float(np.max(atc.u_arcsec))}
    e2 = dataclasses.replace(e, value=float(value), details=details, table=points,
                             tables={**e.tables, "readings": long,
                                     "matrix": matrix.reset_index()})
    return dataclasses.replace(results, angle_deviation=e2), atc


def _e_points_from_readings(points: pd.DataFrame, long: pd.DataFrame):
    """E_i (the mean over the series, 7.4) and s_i of each 7.4 point from the corrected
    readings ``long`` (``round``, ``series``, ``E_arcsec``), set in ``points`` (the caller's
    copy); returns the signed extreme E (7.4), the row it is at, and the series matrix."""
    from gonio.specs.ogam_draft.items import signed_extreme

    g = long.groupby("round", sort=True)
    points["E_arcsec"] = g["E_arcsec"].mean().reindex(points["round"]).to_numpy()
    points["s_arcsec"] = g["E_arcsec"].std(ddof=1).reindex(points["round"]).to_numpy()
    value = signed_extreme(points["E_arcsec"])
    at = int(np.argmax(np.abs(points["E_arcsec"].to_numpy()) == abs(value)))
    matrix = long.pivot(index="round", columns="series", values="E_arcsec")
    matrix.columns = [f"series_{c}" for c in matrix.columns]
    matrix.insert(0, "position_deg", points.set_index("round")["position_deg"])
    return value, at, matrix


def e_table_rule(point_listed: bool, sees_point: bool, through_k: bool,
                 k_corrected: bool) -> dict:
    """Which of E_i's table terms a laboratory's table calibration corrects (beyond the
    draft; the one rule of :func:`angle_deviation_at_table`). E_ij = C_ij/K − θ_i (7.4)
    carries the table's errors in two parts: its own, e(θ_i) − e(z_i) (A.4.1: the point and
    its 7.4 zeroing position), and, where E's angles come from counts through the 7.1 K
    (7.4), −θ_i·δK/K from the errors at K's 7.1 stops and zeros (7.1).

    - own part: corrected where the calibration lists the point and its zero
      (``point_listed``) and sees the part (``sees_point``: no blind harmonic of an
      equal-division comparison in it); else kept, with the MPE line (A.4.1), at this
      point only;
    - K's part: E is read with the K the Result states (7.4). That K is corrected exactly
      when the calibration lists every 7.1 stop and zero (``k_corrected``; K's own rule);
      then E_ij is read with it and K's part is the calibration's. A 7.1 stop or zero the
      calibration does not list leaves K as measured with its MPE line (P_K), so K's part of
      every E_i stays at the MPE (u MPE/√3 per position, A.4.1), also at a point whose own
      part is corrected. Without counts (``through_k`` False) there is no K part.

    Returns ``{"own": bool, "k": "corrected" | "mpe" | None}``.

    >>> e_table_rule(True, True, True, False)
    {'own': True, 'k': 'mpe'}
    >>> e_table_rule(False, True, True, True)
    {'own': False, 'k': 'corrected'}
    """
    return {"own": bool(point_listed and sees_point),
            "k": None if not through_k else ("corrected" if k_corrected else "mpe")}


def _e_k_part_coefficients(theta_deg: float, stops_deg) -> dict:
    """E_i's sensitivities to the table's errors at the 7.1 stops and common zero through
    K alone ({position: c}): :func:`~gonio.specs.ogam_draft.budget_extra.table_error_coefficients`
    less E_i's own +1 at θ_i and −1 at 0 (7.1, 7.4)."""
    from gonio.specs.ogam_draft.budget_extra import table_error_coefficients

    c = dict(table_error_coefficients(theta_deg, stops_deg))
    for pos, own in ((theta_deg, 1.0), (0.0, -1.0)):
        k = tcal.position_key(pos)
        c[k] = c.get(k, 0.0) - own
    return {p: v for p, v in c.items() if abs(v) > 1e-15}


def _e_scale_factor_terms(results, protocol, calibration):
    """(through_k, K's sensitivity c_K to the calibration's errors, K as read, K corrected,
    7.1 stops as read) for :func:`angle_deviation_at_table`: c_K and K corrected None where
    the calibration does not list every 7.1 stop and zero (K then keeps its MPE line)."""
    from gonio.specs.ogam_draft import item_uncertainty as iu

    e = results.angle_deviation
    through_k = (results.scale_factor_for_angles_source == "7.1" and
                 results.scale_factor.measured and
                 e.details.get("scale_factor_for_angles_counts_per_deg") is not None)
    if not through_k:
        return False, None, None, None, np.array([])
    k_old = float(e.details["scale_factor_for_angles_counts_per_deg"])
    stops = results.scale_factor.table["table_deg"].to_numpy(dtype=float)
    k_c, s, _, _ = _k_rounds_at_table(results, protocol, calibration)
    if k_c is None:
        return True, None, k_old, None, stops
    return True, s.mean(axis=0), k_old, float(np.mean(k_c)), stops


def _e_point_table(calibration, p_deg, z_deg, theta_deg, through_k, c_k, k_new, stops,
                   u_mpe_arcsec) -> dict:
    """One 7.4 point's table terms under :func:`e_table_rule`: ``own`` (its own part
    corrected), ``i_p``/``i_z`` (the calibration's indices, None where not listed), and the
    point's table line: u² = cᵀVc over the corrected terms (c = δ(point) − δ(zero) for the
    own part, −(3600 θ_i/K_c)·c_K for K's, a position reached twice counted once; JCGM 100
    5.1.2, 5.2.2) + (MPE/√3)² Σ c_p² over the kept ones (A.4.1: each position independent);
    ν by Welch–Satterthwaite of the calibration's ν (:meth:`TableCalibration.combine`)
    against the MPE part's ∞ (JCGM 100 G.4.1). ``u_arcsec`` None where nothing is corrected
    (the caller keeps the MPE line as it was)."""
    n = calibration.table_deg.size
    i_p, _ = calibration.lookup([p_deg])
    i_z, _ = calibration.lookup([z_deg])
    listed = i_p is not None and i_z is not None
    c_own = np.zeros(n)
    if listed:
        c_own[int(i_p[0])] += 1.0
        c_own[int(i_z[0])] -= 1.0
    basis = getattr(calibration, "blind_basis", None)
    sees = not (listed and basis is not None and np.linalg.norm(np.asarray(basis).T @ c_own)
                > 1e-9 * max(np.linalg.norm(c_own), 1e-300))
    rule = e_table_rule(listed, sees, through_k, k_new is not None)
    c_cal = c_own if rule["own"] else np.zeros(n)
    kept: dict = {}
    if not rule["own"]:
        for pos, c in ((p_deg, 1.0), (z_deg, -1.0)):
            kept[tcal.position_key(pos)] = kept.get(tcal.position_key(pos), 0.0) + c
    if rule["k"] == "corrected":
        c_cal = c_cal - ARCSEC_PER_DEG * theta_deg / k_new * c_k
    elif rule["k"] == "mpe":
        for pos, c in _e_k_part_coefficients(theta_deg, stops).items():
            kept[pos] = kept.get(pos, 0.0) + c
    out = {"rule": rule, "own": rule["own"], "i_p": int(i_p[0]) if listed else None,
           "i_z": int(i_z[0]) if listed else None, "listed": listed, "sees": sees}
    if not rule["own"] and rule["k"] != "corrected":
        return dict(out, u_arcsec=None, dof=math.inf)
    u_c, nu_c = calibration.combine(c_cal)
    u_m2 = u_mpe_arcsec ** 2 * sum(c * c for c in kept.values())
    u2 = u_c * u_c + u_m2
    nu = u2 * u2 / (u_c ** 4 / nu_c) if u_c > 0 and math.isfinite(nu_c) else math.inf
    return dict(out, u_arcsec=math.sqrt(u2), dof=nu, u_calibration_arcsec=u_c,
                dof_calibration=nu_c, u_mpe_arcsec=math.sqrt(u_m2))


def _e_table_reasons(results, protocol, calibration, theta, terms, rows, stop, zero,
                     k_not_corrected: bool) -> str:
    """What :func:`angle_deviation_at_table` leaves uncorrected, and why (one sentence per
    cause; "" where every term is corrected)."""
    keep = ("keeps the MPE line for the point and its zero and is not corrected "
            "[beyond the draft]")
    not_listed = [float(th) for th, t in zip(theta, terms) if not t["listed"]]
    blind = [float(th) for th, t in zip(theta, terms) if t["listed"] and not t["sees"]]
    k_missing = []
    if k_not_corrected:
        k_missing = _k_rounds_at_table(results, protocol, calibration)[3]
    why = []
    if not_listed:
        gone = calibration.lookup([x for r in rows for x in (stop[r[0]], zero[r[0]])])[1]
        why.append(f"the {calibration.source} does not cover {', '.join(f'{x:g}' for x in gone)}"
                   f" deg: E at {', '.join(f'{x:g}' for x in not_listed)} deg {keep}")
    if blind:
        why.append(f"the {calibration.source} cannot see the table's harmonics of order "
                   f"{', '.join(map(str, calibration.blind_orders))} at E's points "
                   f"{', '.join(f'{x:g}' for x in blind)} deg: E there {keep}")
    if k_missing:
        why.append(f"the {calibration.source} does not cover K's 7.1 positions "
                   f"{', '.join(f'{x:g}' for x in k_missing)} deg: K is not corrected, E is "
                   "read with K as measured and K's part of every E_i keeps the MPE line "
                   "[beyond the draft]")
    return "; ".join(why)


def _e_table_sources(calibration, terms) -> list:
    """Each point's table-line source (None where it keeps the MPE line as it was)."""
    sources = []
    for t in terms:
        if t["u_arcsec"] is None:
            sources.append(None)
            continue
        part = [("the point and its zero" if t["own"] else None),
                ("the 7.1 stops and zeros" if t["rule"]["k"] == "corrected" else None)]
        kept = [("the point and its zero (not in the calibration)" if not t["own"] else None),
                ("the 7.1 stops (K not corrected)" if t["rule"]["k"] == "mpe" else None)]
        txt = (f"table calibration at {' and '.join(x for x in part if x)} "
               f"({calibration.describe()}), through E_i = C_i/K_c - theta_true")
        if any(kept):
            txt += (f"; MPE/sqrt(3) per position (A.4.1) at {' and '.join(x for x in kept if x)}")
        if math.isfinite(t["dof"]):
            txt += f"; nu = {t['dof']:.3g} (Welch-Satterthwaite, JCGM 100 G.4.1)"
        sources.append(txt + " [beyond the draft: in place of P and K_P at the MPE]")
    return sources


def angle_deviation_at_table(results: CalibrationResults, readings: Readings,
                             protocol: Protocol, calibration) -> tuple:
    """(results, info): E's readings corrected by a calibrated table per point (beyond the
    draft; :data:`E_TABLE_CALIBRATED_NOTE`), or (``results`` unchanged, info saying why not;
    None without a calibration or E).

    Reading j at point i turned the table from its 7.4 zeroing position z_i to θ_i with the
    error e(θ_i) − e(z_i) (A.4.1, now known): the true angle is θ_i − (e(θ_i) − e(z_i))/3600.
    Where E's angles come from counts through the 7.1 K (7.4) they are read with the
    table-corrected K (:func:`~gonio.specs.ogam_draft.item_uncertainty.scale_factor_table_correction`,
    the K the Result states): M_c = M·K/K_c. So E_ij,c = E_ij + 3600·M_ij·(K/K_c − 1) +
    (e(θ_i) − e(z_i)); E_i, E and the matrix recomputed as 7.4 does. Which terms each point
    gets: :func:`e_table_rule` (a point the calibration does not list keeps its own part and
    the MPE line; a 7.1 stop it does not list keeps K's part at the MPE for every point).
    u and ν of each point's table line: :func:`_e_point_table`. ``info``: ``u_arcsec`` and
    ``dof`` per point (E's table order; None: the MPE line as without a calibration),
    ``sources`` per point, ``uncovered_deg`` and ``reason`` (what was not corrected, or
    why nothing was)."""

    e = results.angle_deviation
    if calibration is None or not e.measured:
        return results, None
    settings, _ = session_settings(readings, protocol)
    u_pos = settings["table_mpe_arcsec"] / math.sqrt(3.0)
    long = e.tables["readings"].copy()
    stop, zero = round_positions(long, protocol, "angle_deviation")
    through_k, c_k, k_old, k_new, stops = _e_scale_factor_terms(results, protocol, calibration)
    pts = e.table.copy()
    theta = pts["position_deg"].to_numpy(dtype=float)
    rows = [np.flatnonzero(long["round"].to_numpy() == r) for r in pts["round"]]
    terms = [_e_point_table(calibration, stop[r[0]], zero[r[0]], th, through_k, c_k, k_new,
                            stops, u_pos) for r, th in zip(rows, theta)]
    reason = _e_table_reasons(results, protocol, calibration, theta, terms, rows, stop, zero,
                              through_k and k_new is None)
    if not any(t["u_arcsec"] is not None for t in terms):
        return results, {"reason": reason}
    err = calibration.error_arcsec
    own_rows = np.zeros(len(long), dtype=bool)
    for r, t in zip(rows, terms):
        own_rows[r] = t["own"]
    # e(stop) − e(zero) of each reading (the one per-reading correction, also C_v's and C_g's)
    corr = np.where(own_rows, tcal.turned_error_arcsec(calibration, stop, zero)[0], 0.0)
    if k_new is not None:        # rows read through K (no gyro_deg of their own)
        own = readings.data.set_index("line")["gyro_deg"].reindex(long["line"]).to_numpy(float)
        corr = corr + np.where(np.isnan(own), ARCSEC_PER_DEG * long["M_deg"].to_numpy(float)
                               * (k_old / k_new - 1.0), 0.0)
    if "E_draft_arcsec" not in long:
        long["E_draft_arcsec"] = long["E_arcsec"]
    long["table_correction_arcsec"] = corr
    long["E_arcsec"] = long["E_arcsec"] + corr
    if "E_draft_arcsec" not in pts:
        pts["E_draft_arcsec"] = pts["E_arcsec"]
    value, at, matrix = _e_points_from_readings(pts, long)
    u_pts = [t["u_arcsec"] for t in terms]
    pts["u_table_arcsec"] = [math.nan if u is None else u for u in u_pts]
    pts["table_corrected"] = [t["own"] for t in terms]
    details = dict(e.details, max_abs_arcsec=abs(value),
                   position_deg=float(pts["position_deg"][at]))
    details.setdefault("stated", "table_corrected")
    est = dict(details.get("estimates") or {})
    est.setdefault("draft", {"label": E_TILT_CORRECTED["draft"], "value": float(e.value),
                             "max_abs_arcsec": float(e.details["max_abs_arcsec"]),
                             "position_deg": float(e.details["position_deg"])})
    est["corrected"] = {"label": (est["corrected"]["label"] + "; and " if "corrected" in est
                                  else "") + (E_TABLE_CORRECTED if k_new is not None
                                              else E_TABLE_CORRECTED_NOK), "value": float(value)}
    details["estimates"] = est
    used = sorted({i for t in terms if t["own"] for i in (t["i_p"], t["i_z"])})
    details["table_calibration"] = {
        "label": E_TABLE_CALIBRATED_NOTE, "source": calibration.source,
        "sha256": calibration.sha256, "scale_factor_counts_per_deg": k_new,
        "positions_used": {"table_deg": [float(calibration.table_deg[i]) for i in used],
                           "error_arcsec": [float(err[i]) for i in used],
                           "u_arcsec": [float(calibration.u_arcsec[i]) for i in used]},
        "u_points_arcsec": [None if u is None else float(u) for u in u_pts],
        "dof_points": [None if t["u_arcsec"] is None or math.isinf(t["dof"])
                       else float(t["dof"]) for t in terms],
        "points_corrected_deg": [float(th) for th, t in zip(theta, terms) if t["own"]],
        "points_uncorrected_deg": [float(th) for th, t in zip(theta, terms) if not t["own"]],
        "scale_factor_corrected": None if not through_k else k_new is not None,
        "not_corrected": reason or None, "uncorrected_value": float(e.value)}
    e2 = dataclasses.replace(e, value=float(value), details=details, table=pts,
                             tables={**e.tables, "readings": long,
                                     "matrix": matrix.reset_index()})
    sources = _e_table_sources(calibration, terms)
    return dataclasses.replace(results, angle_deviation=e2), {
        "u_arcsec": u_pts, "dof": [t["dof"] for t in terms], "sources": sources,
        "uncovered_deg": [float(th) for th, t in zip(theta, terms) if not t["own"]],
        "reason": reason}


def pd_concat(*frames):
    import pandas as pd
    return pd.concat(frames, ignore_index=True)


def annex_a_for(results: CalibrationResults, readings: Readings, protocol: Protocol,
                monte_carlo_trials: int = 0, seed: int = 0) -> tuple[AnnexABudget, str]:
    """The draft's Annex A budget of this calibration (kept for callers of the old API)."""
    settings, _ = session_settings(readings, protocol)
    b, src, _ = deviation_budget(results, readings, protocol, settings, kind="draft",
                                 monte_carlo_trials=monte_carlo_trials, seed=seed)
    return b, src


# --------------------------------------------------------------------------- items

def round_positions(table: pd.DataFrame, protocol: Protocol, test: str, item=None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(stop, zeroing position) of each reading row of a rotation item, degrees, from the
    protocol's rounds (the zeroing position is the round's start, or the series' first
    start where the item does not re-zero; as the bench and the reduction plan them).
    The reading's own angle turned is checked against them. ``item``: the protocol's
    :class:`RotationItem` the rows belong to (one condition of 7.6/7.7), else the first of
    ``test``."""
    item = item or next(it for it in protocol.items() if it.test == test)
    rnd = table["round"].to_numpy(dtype=int)
    stop = np.array([item.rounds[r - 1].stop_deg for r in rnd], dtype=float)
    zero = np.array([(item.rounds[r - 1].start_deg if item.rezero else item.rounds[0].start_deg)
                     for r in rnd], dtype=float)
    th = table["table_deg"].to_numpy(dtype=float)
    bad = np.abs(stop - zero - th) > 1e-6
    if bad.any():
        raise GonioError(f"{test} round {int(rnd[np.argmax(bad)])}: table angle "
                         f"{th[np.argmax(bad)]:g} deg is not the protocol's stop − start; the "
                         "table calibration needs the positions",
                         line=int(table["line"].to_numpy()[np.argmax(bad)]), column="table_deg")
    return stop, zero


def table_positions_used(t: pd.DataFrame, protocol: Protocol, table_calibration) -> dict:
    """The calibration's rows K's correction used (its rounds' stops and zeroing positions,
    modulo 360°): position, error and u as read, for the record (results.json)."""
    stop, zero = round_positions(t, protocol, "scale_factor")
    idx, _ = table_calibration.lookup(np.r_[np.asarray(stop, float), np.asarray(zero, float)])
    return _positions_record(table_calibration, idx if idx is not None else [])


def _scale_factor_positions(t: pd.DataFrame, protocol: Protocol):
    """(stop, zeroing position, note) of the 7.1 rounds for K's table line at the MPE
    (:func:`round_positions`). Where the readings' angles are not the protocol's stop − start
    (or the protocol has no such rounds): (None, None, the note saying so) — every round
    zeroed at 0° and stopped at its angle, the draft's 7.1. The note goes into the line's
    source and the budget's notes: the line is then not the one of the rounds' own positions,
    but where every round turns one way it is not narrower: the worst combination MPE·Σ|c_p|
    is largest where no stop falls on another round's zero, as with one zero shared by all,
    2·MPE·Σ 1/(n|θ_i|) over the rounds that do not turn a full circle
    (:func:`~gonio.specs.ogam_draft.item_uncertainty.scale_factor_table_bound_rel`)."""
    try:
        stop, zero = round_positions(t, protocol, "scale_factor")
        return stop, zero, ""
    except (GonioError, StopIteration, IndexError, KeyError) as e:
        why = str(e) if isinstance(e, GonioError) else \
            "the protocol's 7.1 rounds do not match the readings' rounds"
        return None, None, (f"K's table line takes the draft's 7.1 positions (every round "
                            f"zeroed at 0 deg), not the rounds' own ({why}); not narrower than "
                            f"theirs where every round turns one way")


def _scale_factor_table(t: pd.DataFrame, protocol: Protocol, table_calibration):
    """K's table correction from a calibrated table, or (None, the note why not)."""
    from gonio.specs.ogam_draft import item_uncertainty as iu

    if table_calibration is None:
        return None, ""
    stop, zero = round_positions(t, protocol, "scale_factor")
    corr, missing = iu.scale_factor_table_correction(
        t["K_i_counts_per_deg"], t["table_deg"], stop, zero, table_calibration)
    if corr is None:
        return None, (f"the {table_calibration.source} does not cover "
                      f"{', '.join(f'{x:g}' for x in missing)} deg: the MPE line kept")
    return corr, ""


#: results.json ``details.table_calibration.label`` of K_l, C_v and C_g where a calibrated
#: table corrected them (beyond the draft; docs/draft-readings.md 7.1 "A calibrated table").
RANGE_TABLE_CALIBRATED_NOTE = {
    "scale_factor_nonlinearity": (
        "beyond the draft: the 7.1 rounds corrected by the laboratory's table calibration as K "
        "is (K_i = C_i/(theta_i - (e(stop) - e(zero))/3600)); the stated K_l is the range of the "
        "corrected K_i, bias corrected, its Monte Carlo and belt drawn with the calibration's "
        "errors (their covariance, as t with its dof where it states them; a position shared "
        "by rounds one draw) in place of the table's MPE (A.4.1); the draft's reading (the "
        "range as measured, MPE) is kept beside"),
    "rate_consistency": (
        "beyond the draft: every 7.6 reading's reference angle corrected by the laboratory's "
        "table calibration, theta - (e(zero + theta) - e(zero))/3600 (theta the angle turned "
        "from the zeroing position zero){k}; the stated C_v is the range of the corrected E_v, bias "
        "corrected, its Monte Carlo drawing the calibration's errors (their covariance, as t "
        "with its dof where it states them, with K's; a position shared one draw) in place of "
        "the table's MPE (A.4.1); the draft's "
        "reading (the range as measured, MPE) is kept beside"),
    "pointing_consistency": (
        "beyond the draft: every 7.7 reading's reference angle corrected by the laboratory's "
        "table calibration, theta - (e(zero + theta) - e(zero))/3600 (theta the angle turned "
        "from the zeroing position zero){k}; the stated C_g is the range of the corrected E_g, bias "
        "corrected (range and choice of each extreme), its Monte Carlo drawing the "
        "calibration's errors (their covariance, as t with its dof where it states them, with "
        "K's; a position shared one draw) in place of the table's MPE (A.4.1); the draft's "
        "reading (the range as measured, MPE) "
        "is kept beside"),
}


def _positions_record(calibration, idx) -> dict:
    """The calibration's rows an item's correction used (indices ``idx``), for results.json."""
    used = sorted({int(i) for i in idx})
    return {"table_deg": [float(calibration.table_deg[i]) for i in used],
            "error_arcsec": [float(calibration.error_arcsec[i]) for i in used],
            "u_arcsec": [float(calibration.u_arcsec[i]) for i in used]}


def _k_rounds_at_table(results, protocol, calibration):
    """(K_i corrected, the rounds' sensitivity matrix, the calibration's indices of their
    stops and zeros, the positions it does not list) of the 7.1 rounds, corrected by the one
    per-reading rule e(stop) − e(zero) (``item_uncertainty.table_round_sensitivity``, through
    ``table_calibration.turned_error_arcsec``); the first two None where the calibration does
    not list a stop or zero."""
    from gonio.specs.ogam_draft import item_uncertainty as iu

    t = results.scale_factor.table
    stop, zero = round_positions(t, protocol, "scale_factor")
    return iu.table_round_sensitivity(t["K_i_counts_per_deg"], t["table_deg"], stop, zero,
                                      calibration)


def nonlinearity_at_table(results, readings, protocol, budget, calibration, tc, k):
    """(K_l's stated budget from the 7.1 rounds corrected by a calibrated table, the rows
    used, the draft's range of the corrected K_i) (beyond the draft;
    ``item_uncertainty.nonlinearity_calibrated_budget``), or None where the calibration does
    not cover K's positions."""
    from gonio.specs.ogam_draft import item_uncertainty as iu

    k_c, sens, idx, _ = _k_rounds_at_table(results, protocol, calibration)
    if k_c is None:
        return None
    measured = float((k_c.max() - k_c.min()) / np.mean(k_c) * 100.0)     # 7.2 on them
    b = iu.nonlinearity_calibrated_budget(
        k_c, results.scale_factor.table["table_deg"], sens, calibration, k=k,
        tilt_round_coupling=_round_coupling(results, readings, protocol, budget),
        tilt_measured=_measured_round_tilt(results, readings, protocol, tc),
        **_round_noise(results, readings, protocol))
    return b, _positions_record(calibration, idx), measured


def _condition_item(protocol: Protocol, test: str, rate_dps: float, orientation: str):
    """The protocol's rotation item of one 7.6/7.7 condition (or 7.4's for its reference)."""
    its = [it for it in protocol.items() if it.test == test]
    return next((it for it in its if math.isclose(it.rate_dps, float(rate_dps))
                 and it.orientation == orientation), its[0] if its else None)


def _consistency_row_positions(rows: pd.DataFrame, protocol: Protocol):
    """(stop, zeroing position) of each row of a consistency (its conditions' own rounds)."""
    stop = pd.Series(np.nan, index=rows.index)
    zero = pd.Series(np.nan, index=rows.index)
    for (test, rate, orient), g in rows.groupby(["test", "rate_dps", "orientation"], sort=False):
        s_, z_ = round_positions(g, protocol, test, _condition_item(protocol, test, rate, orient))
        stop[g.index], zero[g.index] = s_, z_
    return stop.to_numpy(dtype=float), zero.to_numpy(dtype=float)


def consistency_at_table(results, readings, protocol, name: str, calibration):
    """C_v (7.6) or C_g (7.7) from readings corrected by a calibrated table (beyond the draft;
    :data:`RANGE_TABLE_CALIBRATED_NOTE`): ((the Characteristic recomputed, its
    :class:`~gonio.specs.ogam_draft.item_uncertainty.CalibratedTable`, {condition: zeroing
    position}, the rows used), "") or (None, why the MPE line is kept).

    Each reading turned the table from its round's zeroing position z to θ with the error
    e(θ) − e(z) (A.4.1, now known): its reference angle becomes θ − (e(θ) − e(z))/3600, and
    where its angle is read through the 7.1 K (7.4) it is read with K's own table-corrected
    value (:func:`_k_rounds_at_table`), so E_ij,c = E_ij + (e(θ) − e(z)) + 3600·M(K/K_c − 1) as
    E's (:func:`angle_deviation_at_table`); E_v, the spread and the ratio are then 7.6/7.7's
    own (:func:`~gonio.specs.ogam_draft.items.rate_consistency`)."""
    from gonio.specs.ogam_draft import item_uncertainty as iu
    from gonio.specs.ogam_draft import items as its

    c = getattr(results, name)
    label = "C_v" if name == "rate_consistency" else "C_g"
    keep = f"{label} keeps the MPE line and is not corrected [beyond the draft]"
    rows = readings.data[readings.data["line"].isin(list(c.used_lines))]
    stop, zero = _consistency_row_positions(rows, protocol)
    # e(stop) − e(zero) of each reading (the one per-reading correction, also E's)
    delta_arcsec, i_s, i_z, m_s = tcal.turned_error_arcsec(calibration, stop, zero)
    # angles read through the 7.1 K: only then are its rounds (and their positions) used
    through_k = results.scale_factor_for_angles_source == "7.1" and \
        results.scale_factor.measured and \
        c.details.get("scale_factor_for_angles_counts_per_deg") is not None
    k_got = _k_rounds_at_table(results, protocol, calibration) if through_k else None
    missing = sorted(set(m_s) | set(k_got[3] if through_k else ()))   # with K's stops, zeros
    if missing:
        return None, (f"the {calibration.source} does not cover "
                      f"{', '.join(f'{x:g}' for x in missing)} deg: {keep}")
    col = "rate_dps" if name == "rate_consistency" else "orientation"
    zeros = {}
    for v, z in pd.Series(zero, index=rows.index).groupby(rows[col].to_numpy()):
        if np.ptp(z.to_numpy()) > 1e-6:
            return None, f"a {label} condition's rounds are zeroed at different positions: {keep}"
        zeros[v] = float(z.iloc[0])
    k_c = c_k = None
    if through_k:
        k_c = float(np.mean(k_got[0]))
        c_k = k_got[1].mean(axis=0)
    cal = iu.CalibratedTable(calibration, c_k, k_c)
    # M + (e(θ) − e(z))/3600 against θ is M against the true angle θ − (e(θ) − e(z))/3600:
    # the reading's own angle shifted, or its counts read through K_c shifted by K_c times it
    d_deg = delta_arcsec / ARCSEC_PER_DEG
    k_use = k_c if through_k else results.scale_factor_for_angles_counts_per_deg
    fixed = readings.data.copy()
    for col_ in ("gyro_deg", "gyro_counts"):
        if col_ in fixed:
            fixed[col_] = fixed[col_].astype(float)
    own = rows["gyro_deg"].notna().to_numpy() if "gyro_deg" in rows else np.zeros(len(rows), bool)
    at = rows.index.to_numpy()
    if own.any():
        fixed.loc[at[own], "gyro_deg"] = rows["gyro_deg"].to_numpy(float)[own] + d_deg[own]
    if (~own).any():
        fixed.loc[at[~own], "gyro_counts"] = (rows["gyro_counts"].to_numpy(float)[~own]
                                              + float(k_use) * d_deg[~own])
    func = its.rate_consistency if name == "rate_consistency" else its.pointing_consistency
    c2 = func(fixed, k_use, reference_rate_dps=protocol.rate_reference_dps,
              reference_orientation=protocol.pointing_reference)
    pts = c2.tables["points"]
    for v in c2.table[col]:
        p = pts.loc[pts[col] == v, "position_deg"].to_numpy(dtype=float)
        if cal.blind(cal.coefficients(p, zeros[v])):
            return None, (f"the {calibration.source} cannot see the table's harmonics of order "
                          f"{', '.join(map(str, calibration.blind_orders))} at {label}'s "
                          f"points: {keep}")
    idx = np.r_[i_s, i_z, k_got[2]] if through_k else np.r_[i_s, i_z]
    return (c2, cal, zeros, _positions_record(calibration, idx)), ""


def item_uncertainties(results: CalibrationResults, budget: AnnexABudget, protocol: Protocol,
                       settings: dict, readings: Readings, gyro_type: str | None = None,
                       table_calibration=None, table_record: dict | None = None) -> dict:
    """The uncertainty of every measured item (clause 8), by
    :mod:`gonio.specs.ogam_draft.item_uncertainty`; items not measured get none.
    ``table_calibration``: a :class:`~gonio.specs.ogam_draft.table_calibration.TableCalibration`
    (K, K_l, C_v and C_g corrected by it, their table lines the calibration's; beyond the
    draft), or None. ``table_record``: filled per item K_l, C_v, C_g with the calibration's
    rows used (``positions_used``) or why the MPE line is kept (``reason``)."""
    from gonio.specs.ogam_draft import item_uncertainty as iu

    table_record = {} if table_record is None else table_record
    k_fixed = protocol.annex_a.coverage_factor
    mpe = settings["table_mpe_arcsec"]
    out = {}
    sf = results.scale_factor
    k_tilt = _scale_factor_tilt(results, readings, protocol, budget)   # A_K at the A.1 bound
    tc = None               # K's correction by the measured tilt (the in-situ estimate)
    k_u_rel_e = None        # u(K)/K of the uncorrected K where K's table was corrected
    if sf.measured:
        t = sf.table
        t_corr, t_note = _scale_factor_table(t, protocol, table_calibration)
        stop, zero, p_note = _scale_factor_positions(t, protocol)
        kw = dict(k=k_fixed, tilt_bias_arcsec_per_deg=k_tilt,
                  chamber=chamber_temperature(readings, protocol, gyro_type)[0],
                  table_correction=t_corr, table_note="; ".join(x for x in (t_note, p_note) if x),
                  stop_deg=stop, zero_deg=zero, programme=programme_rounds(protocol))
        # the draft's reading: the 7.1 mean as measured, the MPE's table line
        draft_k = iu.scale_factor_budget(t["K_i_counts_per_deg"], t["table_deg"], mpe,
                                         **dict(kw, table_correction=None))
        out["scale_factor"] = draft_k if t_corr is None else \
            iu.scale_factor_budget(t["K_i_counts_per_deg"], t["table_deg"], mpe, **kw)
        if t_corr is not None:   # E, K_l, C_v, C_g read with the uncorrected 7.1 K: its MPE u
            k_u_rel_e = iu.without_tilt_u_rel(draft_k)
        tc, _ = tilt_correction(results, readings, protocol)
        if tc is not None:       # stated corrected by the measured tilt, the draft's K beside
            out["scale_factor"] = dataclasses.replace(
                iu.scale_factor_budget(t["K_i_counts_per_deg"], t["table_deg"], mpe,
                                       tilt_correction=tc, **kw),
                beside=draft_k, correction=tc)
        if results.scale_factor_nonlinearity.measured:
            draft = iu.nonlinearity_budget(
                t["K_i_counts_per_deg"], t["table_deg"], mpe, k=k_fixed,
                tilt_bias_arcsec_per_deg=_nonlinearity_tilt(results, readings, protocol, budget))
            at_table = None if t_corr is None else nonlinearity_at_table(
                results, readings, protocol, budget, table_calibration, tc, k_fixed)
            if at_table is not None:
                table_record["scale_factor_nonlinearity"] = {
                    "positions_used": at_table[1], "measured_value": at_table[2]}
                _record_measured(table_record["scale_factor_nonlinearity"], at_table[0], tc)
            elif table_calibration is not None:
                table_record["scale_factor_nonlinearity"] = {"reason": t_note.replace(
                    "the MPE line kept", "K_l keeps the MPE line and is not corrected")}
            out["scale_factor_nonlinearity"] = dataclasses.replace(
                at_table[0] if at_table is not None else iu.nonlinearity_corrected_budget(
                    t["K_i_counts_per_deg"], t["table_deg"], mpe, k=k_fixed,
                    tilt_round_coupling=_round_coupling(results, readings, protocol, budget),
                    tilt_measured=_measured_round_tilt(results, readings, protocol, tc),
                    stop_deg=stop, zero_deg=zero, **_round_noise(results, readings, protocol)),
                beside=draft)
    zs = results.zero_stability
    if zs.measured:
        rd = zs.tables["readings"]
        t_zs = rd.loc[rd["series"] == zs.details["series"], "time_s"].to_numpy(dtype=float)
        comp = protocol.session.static_s if protocol.session.earth_compensation == "measured" \
            else None
        zlines = rd.loc[rd["series"] == zs.details["series"], "line"]
        zrows = readings.data[readings.data["line"].isin(list(zlines))]
        res_deg = iu.reading_resolution_deg(
            zrows["gyro_deg"].to_numpy(dtype=float),
            None if zrows["gyro_deg"].notna().all() else results.scale_factor_for_angles_counts_per_deg
            or metadata_float(readings.metadata, "nominal_scale_factor_counts_per_deg"))
        out["zero_stability"] = iu.zero_stability_budget(
            float(zs.value), int(zs.details["n_readings"]), time_s=t_zs,
            compensation_time_s=comp, k=k_fixed, resolution_deg=res_deg)
    e = results.angle_deviation
    if e.measured:
        out["angle_deviation"] = iu.angle_deviation_budget(
            budget, float(e.value),
            k_source="fixed by laboratory" if k_fixed is not None else "welch-satterthwaite")
    rp = results.repeatability
    if rp.measured:
        used = rp.table["n_series"] >= 2
        n_pts = int(used.sum())
        # a point with fewer series (fewer ν) may hold the largest σ_i: its ν bounds R's
        # interval valid for every point (repeatability_budget)
        n_ser = min(int(rp.details["n_series"]), int(rp.table.loc[used, "n_series"].min()))
        out["repeatability"] = iu.repeatability_budget(float(rp.value), n_ser, n_pts,
                                                       k=k_fixed)
    # the tilt bias of K enters the consistencies by their own K_tilt line, not through u(K)
    k_u_rel = iu.without_tilt_u_rel(out["scale_factor"]) if "scale_factor" in out else 0.0
    if k_u_rel_e is not None:
        k_u_rel = k_u_rel_e
    for name, scale in (("rate_consistency", 1e6), ("pointing_consistency", 100.0)):
        if getattr(results, name).measured:
            out[name] = _consistency_item(
                results, budget, protocol, readings, name, scale, k_u_rel=k_u_rel,
                k_tilt=k_tilt, tc=tc, mpe=mpe, k_fixed=k_fixed, sf_budget=out.get("scale_factor"),
                table_calibration=table_calibration, table_record=table_record)
    return out


def _record_measured(rec: dict, b, tc) -> None:
    """K_l's, C_v's or C_g's table record: ``measured_value`` the range the stated value is
    built from (``b.measured``: the table-corrected readings, and corrected at the measured
    tilt where ``tc``), the table-corrected range without the tilt correction beside it
    (``measured_value_without_tilt_correction``) where the tilt corrected them."""
    without = rec["measured_value"]
    if b.measured is not None:
        rec["measured_value"] = float(b.measured)
    if tc is not None:
        rec["measured_value_without_tilt_correction"] = float(without)


def _k_u_rel_without_table(sf_budget) -> float:
    """u(K)/K less the tilt, chamber and calibrated-table lines (``P_Kc``): the part of K's u an
    item drawing the calibration's errors jointly with K's (:class:`~gonio.specs.ogam_draft.
    item_uncertainty.CalibratedTable`) takes as independent normal."""
    from gonio.specs.ogam_draft import item_uncertainty as iu

    k = abs(float(sf_budget.value))
    p_kc = sum(c.u ** 2 for c in sf_budget.components if c.symbol == "P_Kc")
    return math.sqrt(max((iu.without_tilt_u_rel(sf_budget) * k) ** 2 - p_kc, 0.0)) / k


def _consistency_item(results, budget, protocol, readings, name: str, scale: float, *, k_u_rel,
                      k_tilt, tc, mpe, k_fixed, sf_budget, table_calibration, table_record):
    """The stated budget of C_v (7.6) or C_g (7.7), the draft's reading beside it: corrected
    for the range's bias (C_g: for the choice of its extremes; both ranges where the tilt was
    measured), and by a calibrated table where one is given and covers the positions
    (:func:`consistency_at_table`; beyond the draft)."""
    from gonio.specs.ogam_draft import item_uncertainty as iu

    c = getattr(results, name)
    u_r = float(budget.parameters["repeatability_arcsec"])
    drift = float(budget.parameters["zero_stability_dph"]) * ARCSEC_PER_MIN_PER_DPH  # A.4.3
    df = readings.data
    conds, curves = _consistency_conditions(c, name, u_r)
    t = df.loc[df["line"].isin(list(c.used_lines)), "time_s"].to_numpy(dtype=float)
    t_min = float(np.nanmax(t)) / S_PER_MIN if t.size else protocol.annex_a.duration_min
    ref = float(c.details["reference_angle_arcsec"])
    kw = dict(table_mpe_arcsec=mpe, drift_half_width_arcsec=drift * t_min,
              scale_factor_u_rel=k_u_rel, scale_factor_tilt=k_tilt, curves=curves, k=k_fixed)
    draft = iu.consistency_budget(name, conds, ref, scale, **kw)   # as measured, A.1 bound
    delta = None if tc is None else tc.delta_rel
    if tc is not None:        # the E_v corrected for K's tilt bias at the measured tilt
        kw["tilt_te"] = (tc.u_delta_rel, tc.dof)
    if table_calibration is not None:
        got, why = consistency_at_table(results, readings, protocol, name, table_calibration)
        table_record[name] = {"reason": why} if got is None else {
            "positions_used": got[3], "measured_value": float(got[0].value),
            "through_k": got[1].c_k is not None, "corrected": got[0]}
        if got is not None:     # the E_v of the corrected readings; the table's draws the
            c2, cal, zeros, _ = got                                  # calibration's
            col = "rate_dps" if name == "rate_consistency" else "orientation"
            conds, curves = _consistency_conditions(c2, name, u_r, delta)
            conds = [dataclasses.replace(x, zero_deg=zeros[v])
                     for x, v in zip(conds, c2.table[col])]
            if cal.c_k is not None and sf_budget is not None:
                kw["scale_factor_u_rel"] = _k_u_rel_without_table(sf_budget)
            kw.update(curves=curves, table_cal=cal)
            b = iu.consistency_corrected_budget(
                name, conds, float(c2.details["reference_angle_arcsec"]), scale, **kw)
            _record_measured(table_record[name], b, tc)
            return dataclasses.replace(b, beside=draft)
    if tc is not None:
        conds, curves = _consistency_conditions(c, name, u_r, delta)
        kw.update(curves=curves)
    if name == "rate_consistency" or tc is not None:
        # stated corrected for the range's bias and the choice of each extreme, the
        # draft's range beside (C_g too where the tilt was measured: its draft's linear
        # u, with no tilt error left to fill it, is over-wide)
        return dataclasses.replace(
            iu.consistency_corrected_budget(name, conds, ref, scale, **kw), beside=draft)
    # C_g: stated corrected for the choice of its extremes
    return dataclasses.replace(iu.selection_corrected_budget(
        draft, curves, [x.u_single_arcsec / math.sqrt(max(x.n_series, 1)) for x in conds],
        reference_angle_arcsec=ref, scale=scale, table_mpe_arcsec=mpe,
        drift_half_width_arcsec=kw["drift_half_width_arcsec"],
        scale_factor_u_rel=k_u_rel, k=k_fixed), beside=draft)


def _consistency_conditions(c, name: str, u_r: float, delta_rel: float | None = None):
    """(conditions, curves) of a consistency item (7.6 by rate, 7.7 by orientation) for
    :func:`gonio.specs.ogam_draft.item_uncertainty.consistency_budget`: per condition its
    curve (positions, E) and its signed extreme E_v where it lies. ``delta_rel``: K's relative
    bias δ by the tilt × Earth-rate coupling at the measured tilt; every E read with the 7.1
    K is then corrected by +δ·θ (K(1 + δ) reads θ(1 − δ); JCGM 100 3.2.4) and E_v taken on
    the corrected curve (the correction may move the extreme)."""
    from gonio.specs.ogam_draft import item_uncertainty as iu

    col = "rate_dps" if name == "rate_consistency" else "orientation"
    pts = c.tables["points"]
    conds, curves = [], []
    for row in c.table.itertuples(index=False):
        v = getattr(row, col)
        p = pts[pts[col] == v]
        pos = p["position_deg"].to_numpy(dtype=float)
        e = p["E_arcsec"].to_numpy(dtype=float)
        if delta_rel is None:
            e_v = float(row.E_arcsec)
            at = p.loc[(p["E_arcsec"] - row.E_arcsec).abs().idxmin(), "position_deg"]
        else:
            e = e + delta_rel * pos * ARCSEC_PER_DEG
            j = int(np.nanargmax(np.abs(e)))
            e_v, at = float(e[j]), pos[j]
        curves.append((pos, e))
        conds.append(iu.ConditionDeviation(f"{v:g} deg/s" if col == "rate_dps" else f"axis {v}",
                                           e_v, float(at), u_r, int(row.n_series)))
    return conds, curves


#: The last file :func:`screen` read, for the :func:`calibrate` that follows it in the pipeline
#: (one entry, taken by that calibration): {key: (readings, static record)}, the key the
#: file's path, size, modification time and the protocol (a changed file is read again).
_KEPT: dict = {}


def _load_key(path: str | Path, protocol: Protocol) -> tuple:
    import os

    st = os.stat(path)
    return (os.path.realpath(path), st.st_size, st.st_mtime_ns, repr(protocol))


def _load(path: str | Path, protocol: Protocol, keep: bool = False):
    """(readings, static record or None) of a readings file or stream; ``keep``: also keep
    them for the next call on the same, unchanged file (screen, then calibrate)."""
    from gonio.errors import check_input_file

    check_input_file(path, "readings or stream file")
    key = _load_key(path, protocol)
    kept = _KEPT.pop(key, None)
    if kept is None:
        kept = _read(path, protocol)
    _KEPT.clear()
    if keep:
        _KEPT[key] = kept
    return kept


def _read(path: str | Path, protocol: Protocol):
    from gonio.formats.streams import StreamFile, sniff_kind

    if sniff_kind(path) == "readings":
        return read_readings(path), None
    from gonio.specs.ogam_draft.readings import format_readings, parse_readings
    from gonio.specs.ogam_draft.reduce import reduce_stream

    stream = StreamFile(path)               # read in blocks: bounded memory
    red = reduce_stream(stream, protocol)
    if not len(red.readings):
        raise GonioError("no round of the protocol could be matched in the stream", file=path)
    # validated exactly as a readings file is, in memory (no temporary file)
    rd = parse_readings(format_readings(red.readings.drop(columns=["t_zero_s", "t_read_s"]),
                                        red.metadata), path=path)
    return rd, static_record_from_stream(stream, red.readings)


def static_record_from_stream(stream, reduced) -> StaticRecord | None:
    """The instrument's continuous record over the 7.3 rest, cut from a stream.

    From the zeroing of the first zero-stability reading to the last one (the
    reduction's ``t_zero_s``/``t_read_s``); counts divided by the nominal scale
    factor. ``None`` when the stream holds no 7.3 rest or no nominal K. ``stream``
    is a :class:`gonio.formats.streams.Stream` in memory or a
    :class:`gonio.formats.streams.StreamFile`
    (only the rest's samples are read).
    """
    zs = reduced[reduced["test"] == "zero_stability"]
    k = metadata_float(stream.metadata, "nominal_scale_factor_counts_per_deg")
    if len(zs) < 2 or not k:
        return None
    t0, t1 = float(zs["t_zero_s"].min()), float(zs["t_read_s"].max())
    if hasattr(stream, "window"):
        a, b = stream.search(t0, "left"), stream.search(t1, "right")
        ch = stream.window(a, b, columns=("time_s", "gyro_counts"))
        t, c = ch.time_s, ch.gyro_counts
        del ch
        stream.release()
    else:
        m = (stream.time_s >= t0) & (stream.time_s <= t1)
        t, c = stream.time_s[m], stream.gyro_counts[m]
    t = t - t0
    angle = c / k
    del c
    return StaticRecord(t, angle, source="stream, 7.3 rest")


#: Most samples of the 7.3 record the noise analysis uses. A longer record is decimated
#: to every d-th angle (d the smallest that fits): the angle is the cumulative counter, so
#: that is an exact record at d·τ0 and the Allan deviation starts at τ = d·τ0. The fit and
#: its parametric bootstrap (20 synthesised records of the same length) then cost the same
#: for any sample rate and rest length.
ZERO_STABILITY_NOISE_SAMPLES = 1 << 18


def analyse_zero_stability(record: StaticRecord | None,
                           max_samples: int = ZERO_STABILITY_NOISE_SAMPLES):
    """Allan analysis of the 7.3 static record (:func:`gonio.analysis.noise.analyse_static`,
    uncertainties by its parametric bootstrap of 20 records) on at most ``max_samples``
    samples (every d-th, :data:`ZERO_STABILITY_NOISE_SAMPLES`), or why not. Returns
    ``(result or None, source)``; the source names the decimation when there is one.

    >>> import numpy as np
    >>> t = np.arange(1001) * 0.01
    >>> rng = np.random.default_rng(0)
    >>> rec = StaticRecord(t, np.cumsum(rng.standard_normal(1001)) * 1e-6, source="test")
    >>> r, src = analyse_zero_stability(rec, max_samples=300)
    >>> round(r.tau0_s, 3), src
    (0.04, 'test; one sample in 4 analysed (at most 300)')
    """
    from gonio.analysis.noise import analyse_static

    if record is None:
        return None, ""
    n = int(np.size(record.time_s))
    d = max(1, -(-n // int(max_samples)))
    source = record.source if d == 1 else \
        f"{record.source}; one sample in {d} analysed (at most {int(max_samples)})"
    try:
        return analyse_static(record.time_s[::d], record.angle_deg[::d]), source
    except GonioError as exc:
        return None, f"not analysed: {exc}"


def calibrate(readings: str | Path | Readings, protocol: str | Path | Protocol | None = None,
              *, monte_carlo_trials: int = 0, seed: int = 0,
              static_record: StaticRecord | None = None, budget: str = "physical",
              tilt=None, zero_stability: str = ZERO_STABILITY_STATED,
              findings: list | None = None, gyro_type: str | None = None,
              table_calibration=None) -> Result:
    """``SPEC.calibrate``: the seven characteristics and their uncertainties from a readings
    file or stream, as the one sealed :class:`~gonio.result.model.Result` (:func:`analyse`,
    then :meth:`Analysis.result`; the arguments are :func:`analyse`'s). Conformity is not
    decided here: the pipeline decides it once, on the laboratory file's limits."""
    return analyse(readings, protocol, monte_carlo_trials=monte_carlo_trials, seed=seed,
                   static_record=static_record, budget=budget, tilt=tilt,
                   zero_stability=zero_stability, findings=findings,
                   gyro_type=gyro_type, table_calibration=table_calibration).result()


def programme_rounds(proto: Protocol):
    """(θ, stops, zeros) of the programme's 7.1 rounds, in degrees, the positions the table
    bounds of K and E take beside the rounds read (a set-aside never lowers a bound:
    :func:`~gonio.specs.ogam_draft.table_periodic.programme_bound`); None without 7.1.

    >>> [a.tolist() for a in programme_rounds(load_protocol("ogam-draft"))][0]
    [60.0, 120.0, 180.0, 240.0, 300.0, 360.0]
    """
    if proto.scale_factor is None:
        return None
    stop = np.array([float(r.stop_deg) for r in proto.scale_factor.rounds])
    zero = np.array([float(r.start_deg) for r in proto.scale_factor.rounds])
    return stop - zero, stop, zero


def programme_conditions(proto: Protocol) -> dict:
    """The programme's 7.6 rates and 7.7 orientations, each with its reference (7.4's run
    when the protocol reuses it), and its 7.1 angles (K_l's rounds), as
    :func:`~gonio.specs.ogam_draft.items.compute_characteristics` takes them; an item the
    protocol does not plan: None (the conditions read).

    >>> p = load_protocol("ogam-draft")
    >>> c = programme_conditions(p)
    >>> c["rates_dps"], c["orientations"], c["scale_factor_deg"]
    ((1.0, 10.0, 60.0, 100.0, 150.0, 200.0, 250.0, 300.0), ('up', 'north', 'east'), (60.0, 120.0, 180.0, 240.0, 300.0, 360.0))
    """
    rates = orients = None
    if proto.rate_consistency:
        rates = tuple(sorted({float(it.rate_dps) for it in proto.rate_consistency}
                             | {float(proto.rate_reference_dps)}))
    if proto.pointing_consistency:
        have = [it.orientation for it in proto.pointing_consistency]
        orients = tuple(dict.fromkeys([proto.pointing_reference] + have))
    sf = None if proto.scale_factor is None else tuple(
        float(r.stop_deg - r.start_deg) for r in proto.scale_factor.rounds)
    return {"rates_dps": rates, "orientations": orients, "scale_factor_deg": sf}



def tilt_correction_note(tc) -> str:
    """The calibration's note on K corrected by the measured tilt
    (:class:`~gonio.specs.ogam_draft.budget_extra.TiltCorrection`): ψ, α and their U95;
    the rests left out of the fit (outside a complete opposite pair); and, where fewer than
    three complete pairs remain, that their u is the fit residuals'
    (:func:`gonio.specs.ogam_draft.tilt_estimate.fit_first_harmonic`)."""
    from gonio.specs.ogam_draft.tilt_estimate import BASIS_PAIRS

    lone = ", ".join(f"{x:g}" for x in tc.left_out_deg)
    return (f"K corrected by the measured tilt "
            + tilt_text(tc.tilt_deg, tc.k95 * tc.u_tilt_deg, tc.azimuth_deg,
                        tc.k95 * tc.u_azimuth_deg) + " [beyond the draft]"
            + ((f"; the rest at {lone} deg is left out of the fit: its opposite partner was "
                if len(tc.left_out_deg) == 1 else
                f"; the rests at {lone} deg are left out of the fit: their opposite partners "
                "were ")
               + f"set aside, and the pairs' u (nu = {tc.dof}) holds complete pairs only"
               if tc.basis == BASIS_PAIRS and tc.left_out_deg else "")
            + ("" if tc.basis == BASIS_PAIRS else
               "; the rests do not form three complete opposite pairs (taken in another "
               "order, or rests set aside): u(psi) and u(azimuth) are the fit residuals', which "
               "assume the rests' errors uncorrelated (a bias that wanders over several "
               "rests makes them too small)"))


def analyse(readings: str | Path | Readings, protocol: str | Path | Protocol | None = None,
            *, monte_carlo_trials: int = 0, seed: int = 0,
            static_record: StaticRecord | None = None, budget: str = "physical",
            tilt=None, zero_stability: str = ZERO_STABILITY_STATED,
            findings: list | None = None, gyro_type: str | None = None,
            table_calibration=None) -> Analysis:
    """Compute the seven characteristics and their uncertainties from a readings file or stream.

    ``protocol``: explicit (the command line's ``--protocol``), else the file's
    ``# protocol:``, else ``ogam-draft`` (:func:`resolve_protocol`; conflicts are
    reported in ``conflicts``). The readings are checked against the protocol
    (:func:`screen_readings`). Items whose readings the file does not hold are
    reported as not measured, without uncertainty. ``budget``: ``"physical"`` (the
    default: the draft's Annex A lines plus those beyond it, :func:`deviation_budget`)
    or ``"draft"`` (the annex's four lines only). ``tilt``: a ``gonio tilt-estimate
    --json`` result (path or dict) bounding the tilt instead of the protocol's bound.
    The zero-stability result (7.3) comes with the Allan analysis of the instrument's
    record over the 7.3 rest when there is one: cut from the stream, given as
    ``static_record`` (the virtual bench's), or the static record file the readings name
    (``# static_record:``, :func:`~gonio.specs.ogam_draft.static_record.named_static_record`). ``zero_stability``: which reading of B_s is
    stated, ``"draft"`` (default) or ``"model"`` (:func:`zero_stability_readings`).
    ``findings``: the screening of these readings already made (``SPEC.screen``, the
    pipeline's first step), applied as given; None: screened here. ``gyro_type``: the
    instrument's type as the laboratory file states it (``[instrument] gyro_type``, passed by
    the pipeline), taken for K's temperature-coefficient bound when the readings state none
    (:func:`temperature_coeff_bound`). ``table_calibration``: the rotary table's calibrated
    errors (:mod:`gonio.specs.ogam_draft.table_calibration`: a CSV path, or a
    ``TableCalibration`` such as ``from_equal_division(eda)``); K's 7.1 rounds are corrected
    by it and its table line is the calibration's (beyond the draft); None: the MPE lines.
    """
    if isinstance(table_calibration, (str, Path)):
        from gonio.specs.ogam_draft.table_calibration import read_table_calibration
        table_calibration = read_table_calibration(table_calibration)
    if isinstance(readings, Readings):
        proto, conflicts = resolve_protocol(readings.path, readings.metadata.get("protocol"),
                                            protocol)
        rd, sha = readings, ""
        if rd.path:
            sha = sha256_file(rd.path)
    else:
        from gonio.errors import check_input_file
        check_input_file(readings, "readings or stream file")   # before any byte is read
        proto, conflicts = resolve_protocol(readings, file_protocol_name(readings), protocol)
        rd, from_stream = _load(readings, proto)
        static_record = static_record or from_stream
        sha = sha256_file(readings)
    if static_record is None:        # the file the readings name (the demo writes one)
        from gonio.specs.ogam_draft.static_record import named_static_record
        static_record = named_static_record(rd.path, rd.metadata)
    settings, more = session_settings(rd, proto)
    conflicts += more
    if table_calibration is not None:
        from gonio.specs.ogam_draft.table_calibration import screen_against_mpe
        screen_against_mpe(table_calibration, settings["table_mpe_arcsec"])
    kept, excluded, findings = screen_readings(rd, proto, findings)
    res = compute_characteristics(kept, reference_rate_dps=proto.rate_reference_dps,
                                  reference_orientation=proto.pointing_reference,
                                  **programme_conditions(proto))
    _note_exclusions(res, excluded)
    bound_note = ""
    if tilt is None:            # a tilt file given (--tilt) states the bound itself
        settings, findings, bound_note = _tilt_bound_settings(res, kept, proto, settings,
                                                              findings)
    e_tilt = None       # E corrected at the measured tilt: the physical reading only
    if budget == "physical" and tilt is None:
        res, e_tilt = angle_deviation_at_measured_tilt(res, kept, proto)
    e_table = None      # E corrected by a calibrated table: the physical reading only
    if budget == "physical":
        res, e_table = angle_deviation_at_table(res, kept, proto, table_calibration)
    e_budget, src, notes = deviation_budget(res, kept, proto, settings, kind=budget, tilt=tilt,
                                            monte_carlo_trials=monte_carlo_trials, seed=seed,
                                            tilt_measured=e_tilt, table_measured=e_table)
    if bound_note:
        notes.append(bound_note)
    if e_table is not None:
        notes.append("; ".join(x for x in (
            f"E corrected by the {table_calibration.describe()} [beyond the draft]"
            if "u_arcsec" in e_table else "", e_table.get("reason")) if x))
    noise, noise_src = analyse_zero_stability(static_record)
    table_record: dict = {}
    items = item_uncertainties(res, e_budget, proto, settings, kept, gyro_type,
                               table_calibration=table_calibration, table_record=table_record)
    for name in ("rate_consistency", "pointing_consistency"):
        c2 = (table_record.get(name) or {}).pop("corrected", None)
        if c2 is not None:          # the published tables: the corrected readings'
            res = dataclasses.replace(res, **{name: with_corrected_tables(getattr(res, name),
                                                                          c2)})
    if proto.tilt_estimate is not None and "scale_factor" in items:
        tc = items["scale_factor"].correction
        notes.append(tilt_correction(res, kept, proto)[1] if tc is None else
                     tilt_correction_note(tc))
    if "scale_factor" in items and res.scale_factor.measured:
        p_note = _scale_factor_positions(res.scale_factor.table, proto)[2]
        if p_note:
            notes.append(p_note)
    if table_calibration is not None and "scale_factor" in items:
        used = any(c.symbol == "P_Kc" for c in items["scale_factor"].components)
        notes.append(f"K corrected by the {table_calibration.describe()} [beyond the draft]"
                     if used else f"the {table_calibration.source} does not cover K's "
                     "positions: K keeps the MPE line [beyond the draft]")
    for name, sym in (("scale_factor_nonlinearity", "K_l"), ("rate_consistency", "C_v"),
                      ("pointing_consistency", "C_g")):
        rec = table_record.get(name)
        if rec:
            notes.append(rec.get("reason") or f"{sym} corrected by the "
                         f"{table_calibration.describe()} [beyond the draft]")
    zs_readings = zero_stability_readings(res, items, noise, proto, zero_stability)
    eda, unused = equal_division_for(res.unused_readings, kept, proto)
    res = dataclasses.replace(res, unused_readings=unused)
    return Analysis(res, e_budget, rd, proto, sha, src, noise, noise_src, eda,
                    item_uncertainty=items, budget_kind=budget, conflicts=conflicts,
                    budget_notes=notes, excluded=excluded,
                    zero_stability_readings=zs_readings, findings=findings, gyro_type=gyro_type,
                    table_calibration=table_calibration, table_record=table_record)


#: Details of C_v/C_g (7.6, 7.7) taken from the table-corrected readings where a calibrated
#: table corrected them (:func:`with_corrected_tables`).
CORRECTED_DETAILS = ("spread_arcsec", "reference_angle_arcsec", "reference_position_deg",
                     "scale_factor_for_angles_counts_per_deg")


def with_corrected_tables(c, c2):
    """C_v or C_g ``c`` (the draft's functional of the readings as measured) publishing the
    tables of ``c2``, the same functional of the readings a calibrated table corrected
    (:func:`consistency_at_table`; beyond the draft): E_v per condition (``table``), the
    points, the spread and the reference angle are the corrected readings', as the stated
    value is; the readings as measured are kept beside, labelled: ``table_uncorrected``,
    ``points_uncorrected``, ``spread_uncorrected_arcsec``. ``c.value`` (the draft's range as
    measured, given beside the stated one) is unchanged."""
    details = {**c.details, **{k: c2.details[k] for k in CORRECTED_DETAILS if k in c2.details},
               "spread_uncorrected_arcsec": c.details["spread_arcsec"]}
    tables = {**c.tables, "points": c2.tables["points"], "table_uncorrected": c.table,
              "points_uncorrected": c.tables["points"]}
    return dataclasses.replace(c, details=details, table=c2.table, tables=tables)


def table_corrected(iu) -> bool:
    """Whether an item budget's K was corrected by a calibrated table (its ``P_Kc`` line)."""
    return iu is not None and any(x.symbol == "P_Kc" for x in iu.components)


def beside_uncertainty(unc: dict) -> dict:
    """The stored uncertainty of an estimate given *beside* the stated one (not stated):
    its standard uncertainty, ν and components, without any coverage statement.

    The item keeps one 95 % statement (its stated interval); an estimate beside it is a
    reading with its standard uncertainty. Given beside B_s, the noise model's expected
    value has intervals that under-cover on the study bench (the five-term fit has no
    Gauss-Markov term; ``benchmarks/zero_stability_model_coverage.py``,
    docs/draft-readings.md), so no U, k, interval or coverage probability is kept for it.

    >>> beside_uncertainty({"u_c": 1e-5, "U": 2e-5, "k": 2.0, "nu_eff": 19.0,
    ...                     "coverage_probability": 0.95, "k_source": "t", "unit": "deg/h"})
    {'u_c': 1e-05, 'nu_eff': 19.0, 'unit': 'deg/h', 'coverage': 'none claimed (given beside the stated value)'}
    """
    out = {k: v for k, v in unc.items()
           if k not in ("U", "k", "k_source", "interval", "coverage_probability")}
    out["coverage"] = "none claimed (given beside the stated value)"
    return out


def zero_stability_readings(results: CalibrationResults, items: dict, noise,
                            protocol: Protocol, stated: str = ZERO_STABILITY_STATED) -> dict:
    """Both readings of B_s and which one is stated (docs/draft-readings.md, 7.3).

    The draft's s(M)/T with its one-sided 95 % χ² interval [0, upper limit] (its one
    statement, :func:`gonio.specs.ogam_draft.item_uncertainty.chi_square_statement`) is
    always evaluated and is stated by default. With the continuous
    record of the 7.3 rest analysed (``noise``) and a measured Earth-rate compensation,
    the expected B_s of the same readings from the fitted noise model
    (:func:`gonio.specs.ogam_draft.zero_stability_noise.expected_zero_stability`) is given
    beside it,
    labelled; ``stated="model"`` states it instead (``items["zero_stability"]`` then
    becomes its budget). It is not the default because the five-term model cannot
    represent a Gauss–Markov bias whose correlation time lies inside the record, and on
    the bench its U then misses the population value too often (``gonio validate
    --all-items``, item ``zero_stability_model``). Returns ``{"stated", "note", "draft",
    "model"}`` (budgets; ``model`` None when not possible), or ``{}`` when B_s was not
    measured.
    """
    if stated not in ZERO_STABILITY_READINGS:
        raise GonioError(f"zero-stability reading must be one of "
                         f"{', '.join(ZERO_STABILITY_READINGS)}, got {stated!r}",
                         key="zero_stability")
    from gonio.specs.ogam_draft.zero_stability_noise import expected_zero_stability
    from gonio.specs.ogam_draft.item_uncertainty import zero_stability_model_budget

    zs = results.zero_stability
    draft = items.get("zero_stability")
    if draft is None or not zs.measured:
        return {}
    out = {"stated": "draft", "draft": draft, "model": None}
    if noise is None:
        out["note"] = ("B_s is the draft's s(M)/T of the readings, stated by its one-sided 95 % "
                       "chi-square interval (no continuous record of the 7.3 rest: no noise "
                       "model)")
        return out
    if protocol.session.earth_compensation != "measured":
        out["note"] = ("B_s is the draft's s(M)/T: the noise model's expected B_s needs the "
                       "measured compensation's static phase (session.earth_compensation = "
                       f"{protocol.session.earth_compensation!r})")
        return out
    rd = zs.tables["readings"]
    t = rd.loc[rd["series"] == zs.details["series"], "time_s"].to_numpy(dtype=float)
    ez = expected_zero_stability(noise.fit, t, protocol.session.static_s)
    model = zero_stability_model_budget(ez, k=protocol.annex_a.coverage_factor)
    out.update(model=model, expected=ez)
    if stated == "model":
        items["zero_stability"] = model
        out.update(stated="model",
                   note=("B_s is the expected value of the draft's statistic from the noise "
                         "model of the 7.3 record (physical model, stated on request); the "
                         "draft's s(M)/T of the 15 readings is given beside it, not "
                         "stated"))
    else:
        out["note"] = ("B_s is the draft's s(M)/T of the readings, stated by its one-sided 95 % "
                       "chi-square interval; the noise model's expected B_s is given "
                       "beside it (not stated: the five-term model cannot represent a "
                       "Gauss-Markov bias, see docs/draft-readings.md)")
    return out


def equal_division_for(unused: pd.DataFrame, readings: Readings,
                       protocol: Protocol | None = None):
    """Analyse the file's ``equal_division`` rows (table calibration, IEC 62047-20 A.3), if any.

    Returns ``(result or None, unused readings)``: a new ``unused_readings`` table
    (the input is not modified) without the rows the analysis used; when they do
    not form a complete measurement the analysis is skipped and the rows stay
    unused, with the reason.
    """
    from gonio.specs.ogam_draft.equal_division import equal_division_from_readings

    rows = readings.data[readings.data["test"] == "equal_division"]
    if not len(rows):
        return None, unused
    lines = set(rows["line"])
    try:
        out = equal_division_from_readings(
            readings, protocol=protocol.equal_division if protocol is not None else None,
            compensation_time_s=(protocol.session.static_s if protocol is not None
                                 and protocol.session.earth_compensation == "measured"
                                 else None))
    except GonioError as exc:
        # Not a complete equal-division measurement: the rest of the calibration goes
        # on; the rows stay listed as unused, with the reason.
        un = unused.copy()
        if len(un) and "reason" in un.columns:
            un.loc[un["line"].isin(lines), "reason"] = \
                f"equal-division analysis not possible: {exc.message}"
        return None, un
    if len(unused):
        unused = unused[~unused["line"].isin(lines)].reset_index(drop=True)
    return out, unused
