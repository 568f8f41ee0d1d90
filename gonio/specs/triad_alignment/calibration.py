"""The triad-alignment calibration: readings → items (results.json shape) with the alignment
and, when the readings include a thermal programme, the extended temperature / supply model.

The items have the shape of every other specification's (value, unit, clause, measured,
reason, uncertainty {components, u_c, U, k, nu_eff}; :class:`~gonio.result.model.Item`):

* ``M_ij`` — the nine elements of the system matrix M (output per °/s), alignment §4;
* ``b_i`` — the bias vector (output units), the ± rates cancelling it (article eq. 28–30a);
* ``S_ij`` — cross-axis sensitivities M_ij/M_ii (IEC 62047-20 5.2);
* ``L_ij`` — residual cross-axis leakage after alignment, M̂⁻¹M − I: 0 by construction, with
  its uncertainty (what the alignment leaves);
* ``averaging_time`` — the averaging time chosen from the Allan deviation (article eq. 30b);
* ``K_<gyro>_t<i>_v<j>``, ``b_<gyro>_t<i>_v<j>``, ``ARW_<gyro>_t<i>`` — the identified
  K(ϑ, U), b(ϑ, U), ARW(ϑ) (thesis eq. 6.17–6.20) at the programme's chamber set points and
  supply levels, the model order's effect inside U (the polynomial coefficients, whose
  order the criterion chooses, are information in ``thermal_model``).

Each uncertainty is the fit's Type A evaluation (JCGM 100 4.2: white dwell noise plus a bias
offset per orientation block, σ_w²(XᵀWX)⁻¹ + σ_B²(PZ)(PZ)ᵀ,
:func:`gonio.specs.triad_alignment.analysis.variance_components`; k = t_0.9545(ν)); the
items the rate table enters (M, S, L, K) are stated by the bound-condition interval
(:func:`bound_condition`, :func:`certified`), one statement per item. With Monte Carlo
trials (JCGM 101 7) the Monte Carlo standard uncertainty, and the JCGM 100 U of the
table-dominated items, are kept in the item's details as not certified (:func:`not_certified`).
A readings file without alignment (or thermal) rows, or one whose dwells
do not determine M and b, gives those items not measured with the reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from fnmatch import fnmatchcase
from pathlib import Path

import numpy as np
from scipy import stats

from gonio.formats.jsonsafe import json_safe
from gonio.result.model import (Covariance, Item, Result, Uncertainty, not_measured,
                                source_info)
from gonio.specs.triad_alignment.thermal_model import (Compensation, ThermalModelResult,
                                                      compensate_record, flicker_lift_var,
                                                      identify_thermal_model)
from gonio.specs.triad_alignment.analysis import (BIAS_HORIZON_S, COVERAGE, FLICKER_FLOOR,
                                                 OFFDIAG,
                                                 RATE_ERROR_BOUND_K,
                                                 AlignmentResult, bias_instability_u_dps,
                                                 cross_axis_table, estimate_alignment)
from gonio.errors import GonioError
from gonio.specs.triad_alignment.readings import OUT, TriadReadings, read_triad_readings
from gonio.physics.alignment import ARTICLE_WORKED_EXAMPLE, MisalignmentBudget, misalignment_budget
from gonio.result.gum import dispersion_uncertainty
from gonio.result.statement import coverage_k, p_text
from gonio.units import deg_sqrt_s_from_deg_sqrt_h, dph_to_dps, dps_to_dph
from gonio.specs.triad_alignment.figure_data import figure_series
from gonio.specs.triad_alignment.keys import (ALIGNMENT_KEYS, AXES, NONNEGATIVE_KEYS,
                                              THERMAL_POINT_KEYS)

#: Where k of a Welch–Satterthwaite combination comes from: t_0.9545 of ν_eff as stated (its
#: integer part, GUM G.6.4), so the k a statement prints is the one of the ν it prints.
K_SOURCE_WS = "Student's t for 95.45 % at the Welch–Satterthwaite ν_eff (integer part)"

KEY = "triad-alignment"
TITLE_EN = ("Gyro triad: mechanical misalignment budget, electrical alignment and extended "
            "temperature / supply model")
#: Largest ratio of the alignment fit's residual noise to the noise the dwells' own sample
#: deviations imply before the dwells are called inconsistent (a wrong orientation or sign).
CONSISTENCY_RATIO = 20.0

#: The readings taken that every results.json lists.
READINGS_TAKEN = (
    "Alignment: one least-squares fit of G = M ω + b over every dwell (± rates about each "
    "axis and the static positions), the Earth rate of every orientation averaged over the "
    "swept table angle; for one ± pair it reduces to the article's difference formula.",
    "Uncertainties: Type A from the fit residuals, k = t(ν), coverage probability "
    "p = " + p_text(COVERAGE) + " %; the items the rate table enters (M, S, L, K) are stated "
    "by the bound-condition interval, value ± (a + k·u): the table's errors at their bounds "
    "in their worst combination, a, plus k·u of the other lines; one statement per item. "
    "The JCGM 100 U of those items and the Monte Carlo (JCGM 101) u, when trials were run, "
    "are in results.json's details, not certified.",
    "Residual leakage after alignment: M̂⁻¹M − I is zero for the estimate itself; its "
    "uncertainty is what the alignment leaves.",
    "Averaging time: the shortest octave τ at which every gyro's Allan deviation of the "
    "static record is below ω sin ψ_T / 10 (article eq. 30b).",
    "Temperature model: polynomial orders chosen by the stated criterion, not fixed; the "
    "model is fed with the gyro's internal temperature sensor (thesis §6.1); the certified "
    "values are K, b and ARW at the programme's set points and supply levels, the order "
    "choice inside U; the coefficients are information.",
    "ARW at the set points: a dispersion (the static dwells' sample standard deviations), "
    "stated by its one-sided χ² interval alone, [0, N·√(ν/χ²_(1−p),ν)], p = " + p_text(COVERAGE)
    + " % as every item, no k: ν from "
    "the χ² of the dwells under white rate noise (ν = n − 1 each) through the fit, with the "
    "model order and the temperature reading, ν = ½(N/u_c)²; the bias instability's lift of "
    "the dwells' variance (B̂ from the static record's Allan floor) corrected by half its "
    "full-band flicker value, the other half inside u_c.",
)


@dataclass
class TriadCalibration(Result):
    """The items and the analysis objects they came from (for the certificate's pages)."""

    alignment: AlignmentResult | None = None
    thermal: ThermalModelResult | None = None
    compensation: dict = field(default_factory=dict)


def _as_readings(readings) -> TriadReadings:
    if isinstance(readings, TriadReadings):
        return readings
    if isinstance(readings, (str, Path)):
        return read_triad_readings(readings)
    raise GonioError(f"triad-alignment needs a triad readings file or TriadReadings, got "
                     f"{type(readings).__name__}")


def _type_a(symbol: str, source: str, u: float, nu: float, u_mc: float | None = None,
            trials: int = 0) -> Uncertainty:
    """A one-component Type A uncertainty with k = t_0.9545(ν) (JCGM 100 4.2, G.3), ν as
    stated (:func:`gonio.result.statement.coverage_k`)."""
    k = coverage_k(nu, COVERAGE) if nu > 0 else math.nan
    comp = [{"symbol": symbol, "source": source, "type": "A", "u": float(u), "c": 1.0,
             "contribution": float(u), "dof": float(nu)}]
    mc = None if u_mc is None or not math.isfinite(u_mc) else {"trials": trials, "u": float(u_mc)}
    return Uncertainty(comp, float(u), k * float(u), k, float(nu), mc, COVERAGE,
                       "Student's t for 95.45 % at the fit's ν")


def _with_bias_instability(unc: Uncertainty, key: str, u_long: float, nu_long: float
                           ) -> Uncertainty:
    """The fit's in-run u(b) plus the long-term bias-instability term
    (:func:`gonio.specs.triad_alignment.analysis.bias_instability_u_dps`), k = t_0.9545 of
    the Welch–Satterthwaite ν_eff (JCGM 100 G.4)."""
    comp = list(unc.components) + [{
        "symbol": f"{key}_BI", "type": "B", "u": u_long, "c": 1.0, "contribution": u_long,
        "dof": nu_long,
        "source": "bias instability over the bias's horizon: B̂ √(ln(τ_L/τ_d)/π), B̂ from the "
                  "static record's Allan floor (IEEE 952 Annex C)"}]
    u_c = math.hypot(unc.u_c, u_long)
    nu = u_c ** 4 / (unc.u_c ** 4 / unc.nu_eff + u_long ** 4 / nu_long)
    k = coverage_k(nu, COVERAGE)
    return Uncertainty(comp, u_c, k * u_c, k, float(nu), long_term_monte_carlo(
        unc.monte_carlo, u_long), COVERAGE, K_SOURCE_WS)


#: What the table's Type B line of an alignment item stands for.
TABLE_SOURCE = ("rate table: its rate error (certificate, relative u {rate:.3g}) and its axis "
                "in the reference frame at each orientation (fixture face, table-top squareness; "
                "each component rectangular within ±{bound:.3g}°), first order "
                "(table_type_b_cov, JCGM 100 5.1.2, 4.3.7)")


def with_table_type_b(unc: Uncertainty, key: str, u_b: float, al: AlignmentResult
                      ) -> Uncertainty:
    """``unc`` (the fit's Type A line, its u the fit's part alone) plus the rate table's Type
    B line of standard uncertainty ``u_b`` (:func:`gonio.specs.triad_alignment.analysis.table_type_b_cov`
    propagated to the item; ν = ∞: a certificate's u and a stated bound, JCGM 100 G.4.2);
    k = t_0.9545 of the Welch–Satterthwaite ν_eff (JCGM 100 G.4). Unchanged when u_b = 0.

    >>> a = Uncertainty([{"symbol": "M", "type": "A", "u": 3.0, "c": 1.0, "contribution": 3.0,
    ...                   "dof": 6.0}], 3.0, 3.0 * 2.52, 2.52, 6.0, None, 0.9545, "t")
    >>> u = with_table_type_b(a, "M", 4.0, AlignmentResult.__new__(AlignmentResult))
    >>> u.u_c, round(u.nu_eff, 3)                 # 5² = 3² + 4²; ν = 5⁴/(3⁴/6)
    (5.0, 46.296)
    """
    if not u_b > 0:
        return unc
    tb = getattr(al, "type_b", None) or {"rate_u_rel": math.nan, "orientation_u_rad": math.nan}
    src = TABLE_SOURCE.format(rate=tb["rate_u_rel"],
                              bound=math.degrees(tb["orientation_u_rad"]) * math.sqrt(3.0))
    comp = list(unc.components) + [{"symbol": f"{key}_table", "type": "B", "u": float(u_b),
                                    "c": 1.0, "contribution": float(u_b), "dof": math.inf,
                                    "source": src}]
    u_c = math.hypot(unc.u_c, u_b)
    nu = nu_with_table(unc.u_c, unc.nu_eff, u_b)
    k = coverage_k(nu, COVERAGE)
    return Uncertainty(comp, u_c, k * u_c, k, float(nu), unc.monte_carlo, COVERAGE, K_SOURCE_WS)


#: The two readings of a table-dominated item's uncertainty (M_ij, S_ij, L_ij, the thermal K
#: values). The certificate states one: "bound", the statement that covers at every table
#: error the procedure allows (docs/alignment.md, the coverage study's ``worst`` cases, where
#: the JCGM 100 U covered 40–65 %). The JCGM 100 U stays in results.json's details under
#: ``not_certified`` (:data:`NOT_CERTIFIED`), labelled so.
STATEMENTS = {
    "gum": "JCGM 100: the table's errors as distributions (rate error normal with its "
           "certificate's u, axis components rectangular u = a/√3) in u_c, U = k·u_c; holds "
           "95.45 % over the distribution of the table's errors",
    "bound": "bound condition: the table's errors at their bounds (rate error at its "
             "certificate's expanded uncertainty, k = 2; every axis component at the "
             "fixture's bound), their worst combination propagated linearly, a = Σ|c_k|·a_k, "
             "plus k·u of the other lines, U = a + t_0.9545(ν)·u_rest; holds at least 95.45 % "
             "at every table error within its bounds",
}


#: ``k_source`` of a bound-condition statement: a formula, no words (it is quoted in every
#: language's conformity texts); its parts in ``details.bound_condition``. The shared
#: legend recognises it (``gonio.report.stated.K_SOURCE_BOUND_PREFIX``).
K_SOURCE_BOUND = "U = a + k·u"

#: The label of every reading results.json keeps beside the certified statement.
NOT_CERTIFIED = "not certified"


def not_certified(unc: Uncertainty, gum: Uncertainty | None = None
                  ) -> tuple[Uncertainty, dict]:
    """The certified uncertainty ``unc`` without its Monte Carlo standard uncertainty, and
    the readings that are not the certified statement, labelled :data:`NOT_CERTIFIED`, for
    the item's details: the Monte Carlo u (JCGM 101; it redraws the fit's noise, not the
    table) and, for an item the rate table enters, the JCGM 100 U (``gum``). One statement per
    item reaches the certificate, summary, items.csv, the DCC and the web page; these stay
    in results.json only.

    >>> u = Uncertainty([], 1.0, 2.0, 2.0, math.inf, {"trials": 10, "u": 1.1}, COVERAGE, "t")
    >>> c, d = not_certified(u)
    >>> c.monte_carlo is None, d["monte_carlo"]["u"], d["monte_carlo"]["status"]
    (True, 1.1, 'not certified')
    """
    out: dict = {}
    if unc.monte_carlo:
        out["monte_carlo"] = {**unc.monte_carlo, "status": NOT_CERTIFIED,
                              "basis": "JCGM 101 Monte Carlo of the fit's noise (the rate "
                                       "table's errors not redrawn): information beside the "
                                       "certified statement"}
    if gum is not None:
        out["gum"] = {"U": gum.U, "k": gum.k, "u_c": gum.u_c, "nu_eff": gum.nu_eff,
                      "status": NOT_CERTIFIED, "basis": STATEMENTS["gum"]}
    return replace(unc, monte_carlo=None), out


def bound_condition(value: float, a_table: float, u_rest: float, nu_rest: float) -> dict:
    """The bound-condition statement of an item whose table errors are bounded: the table's
    errors at their bounds in their worst combination move the estimate by at most
    ``a_table`` (first order, :func:`gonio.specs.triad_alignment.analysis.table_bound`); the
    other lines (the fit's noise, ν = ``nu_rest``) give u_rest, so

        U_bound = a_table + t_0.9545(ν_rest) · u_rest,

    and P(|offset + e| ≤ U_bound) ≥ P(|e| ≤ t·u_rest) = 0.9545 for every offset |offset| ≤
    a_table (JCGM 100 4.3.7 for the bounds, 6.2 for k; the bounds added linearly as in a
    worst-case budget, not in quadrature). Stated by its interval value ± U_bound.

    >>> b = bound_condition(1.0, 0.5, 0.1, math.inf)
    >>> round(b["U"], 4), round(b["k_rest"], 4), [round(x, 4) for x in b["interval"]]
    (0.7, 2.0, [0.3, 1.7])
    """
    k = coverage_k(nu_rest, COVERAGE) if u_rest > 0 else 0.0
    big_u = float(a_table) + k * float(u_rest)
    return {"U": big_u, "a_table": float(a_table), "u_rest": float(u_rest),
            "nu_rest": float(nu_rest), "k_rest": float(k),
            "interval": [float(value) - big_u, float(value) + big_u],
            "coverage_probability": COVERAGE, "basis": STATEMENTS["bound"]}


def certified(unc: Uncertainty, bc: dict, statement: str = "bound") -> Uncertainty:
    """The uncertainty the certificate states: the GUM budget ``unc`` stated by the
    bound-condition interval ``bc`` (:func:`bound_condition`): no coverage factor (U_bound is
    no multiple of u_c; u_c stays the budget's combined standard uncertainty), the interval
    is the statement with probability at least 0.9545 at every table error within its
    bounds. ``statement`` "gum" (the JCGM 100 U itself) is for studies only: the protocol
    refuses it (:data:`gonio.specs.triad_alignment.bench._BOUND_ONLY_TXT`)."""
    if statement != "bound":
        return unc
    return Uncertainty(list(unc.components), unc.u_c, bc["U"], None, bc["nu_rest"],
                       unc.monte_carlo, COVERAGE, K_SOURCE_BOUND, tuple(bc["interval"]),
                       u_c_of="the JCGM 100 budget (the table's errors as distributions); "
                              "the bound-condition interval is the statement")


def nu_with_table(u_fit: float, nu_fit: float, u_b: float) -> float:
    """The Welch–Satterthwaite ν_eff (JCGM 100 G.4.1) of the fit's part (u, ν) plus the
    table's Type B part ``u_b`` (ν = ∞): (u_fit² + u_b²)² / (u_fit⁴/ν_fit).

    >>> round(nu_with_table(3.0, 6.0, 4.0), 3), nu_with_table(0.0, 6.0, 1.0)
    (46.296, inf)
    """
    u_c2 = u_fit ** 2 + u_b ** 2
    return u_c2 ** 2 / (u_fit ** 4 / nu_fit) if u_fit > 0 else math.inf


def total_coverage_factor(u_total: float, u_b: float, nu_fit: float) -> float:
    """k = t_0.9545(ν_eff) of a total standard uncertainty ``u_total`` whose table part is
    ``u_b`` and whose fit part has ν = ``nu_fit`` (the k an item's budget gives,
    :func:`with_table_type_b`), for the values that are not items (the report page's M⁻¹,
    scale factors, angles)."""
    return coverage_k(nu_with_table(fit_part(u_total, u_b), nu_fit, u_b), COVERAGE)


def table_inputs(readings: TriadReadings) -> dict:
    """The rate table's Type B inputs that the readings state (or their defaults,
    :data:`gonio.specs.triad_alignment.readings.TABLE_METADATA`), as
    :func:`gonio.specs.triad_alignment.analysis.estimate_alignment` takes them: the rate's
    relative u and the standard uncertainty of each axis component, the stated bound over √3
    (rectangular, JCGM 100 4.3.7)."""
    return {"rate_u_rel": readings.table_metadata("rate_table_u_rel"),
            "orientation_u_rad": math.radians(readings.table_metadata("orientation_bound_deg"))
            / math.sqrt(3.0)}


def fit_alignment(readings: TriadReadings, **options) -> AlignmentResult:
    """The alignment estimate with the rate table's Type B part (:func:`table_inputs`): the
    one call of ``gonio calibrate`` and ``gonio align``; ``options`` go to
    :func:`gonio.specs.triad_alignment.analysis.estimate_alignment`."""
    return estimate_alignment(readings, **options, **table_inputs(readings))


def fit_part(u_total: float, u_b: float) -> float:
    """The fit's part of a total standard uncertainty whose table part is ``u_b`` (the two
    covariances add, so do the variances of any first-order propagation)."""
    return math.sqrt(max(u_total ** 2 - u_b ** 2, 0.0))


def long_term_monte_carlo(mc: dict | None, u_long: float) -> dict | None:
    """The Monte Carlo record of a long-term bias: the fit's Monte Carlo refits the record's
    outputs, so its u is the in-run u(b) only (``u_fit``); the long-term bias adds the bias
    instability, independent of this record's noise, so the Monte Carlo of the stated
    quantity (fit + wander) has the variance of the sum, u² = u_fit² + u_BI² (the variance
    of a sum of independent inputs, JCGM 101 5.1 with the linear model b_long = b_fit + δ_BI).
    Without it the certificate printed u_GUM(b) ≈ 0.11 beside u_MC(b) ≈ 0.02: one with the
    long-term term, one without — not a disagreement between the methods.

    >>> r = long_term_monte_carlo({"trials": 100, "u": 0.03}, 0.04)
    >>> round(r["u"], 6), r["u_fit"], r["u_long_term"]
    (0.05, 0.03, 0.04)
    >>> long_term_monte_carlo(None, 0.04) is None
    True
    """
    if not mc or mc.get("u") is None:
        return mc
    return {**mc, "u": math.hypot(float(mc["u"]), float(u_long)), "u_fit": float(mc["u"]),
            "u_long_term": float(u_long),
            "scope": "the fit's Monte Carlo (in-run) with the bias-instability term added in "
                     "quadrature (independent of the record)"}


def _nu(al: AlignmentResult, i: int, j: int) -> float:
    """ν of M_ij (j < 3) or b_i (j = 3): the Welch–Satterthwaite ν of the fit's two noise
    components (:func:`gonio.specs.triad_alignment.analysis.variance_components`), rounded
    down (the ν that k is computed from and the certificate prints, JCGM 100 G.6.4)."""
    nu = float(al.dof[i] if al.dof_theta is None else al.dof_theta[i, j])
    return float(math.floor(nu + 1e-9)) if math.isfinite(nu) else nu


def static_record_s(r: TriadReadings) -> float:
    """Length of the readings' static record (rows ``test = static``), in s; 0 without one:
    the T of the bias-instability term of b_i (:func:`alignment_items`)."""
    st = r.rows("static")
    return float(st["duration_s"].sum()) if len(st) else 0.0


def alignment_items(al: AlignmentResult, trials: int, static_s: float = 0.0,
                    statement: str = "bound") -> dict[str, Item]:
    """The alignment items (module docstring) from an :class:`AlignmentResult`. The items the
    rate table enters (M, S, L) state the bound-condition interval (:func:`certified`; its
    parts in ``details.bound_condition``); every item's other readings (the JCGM 100 U, the
    Monte Carlo u) are in ``details.not_certified`` (:func:`not_certified`), labelled so.
    ``statement`` "gum" is for studies only (the protocol refuses it)."""
    unit = al.output_unit or "output"
    items: dict[str, Item] = {}
    um = al.u_system_matrix
    ub = al.u_bias_output
    mc_m = None if al.u_mc_theta is None else al.u_mc_theta.reshape(3, 4)
    fit = ("weighted least-squares fit of all dwells; dwell noise white (σ_w² from the "
           "scatter about each orientation's own bias) plus a bias offset per orientation "
           "block and static dwell (σ_B²): σ_w²(XᵀWX)⁻¹ + σ_B²(PZ)(PZ)ᵀ")
    tb = al.type_b or {}
    ub_m = tb["u_theta"].reshape(3, 4)[:, :3] if tb else np.zeros((3, 3))
    ub_s = tb["u_derived"]["cross_axis"] if tb else np.zeros(6)
    ub_l = tb["leakage_u"] if tb else np.zeros((3, 3))
    a_m = tb["a_theta"].reshape(3, 4)[:, :3] if tb else np.zeros((3, 3))
    a_s = tb["a_derived"]["cross_axis"] if tb else np.zeros(6)
    a_l = tb["a_leakage"] if tb else np.zeros((3, 3))

    def both(key, clause, name, unit_, value, fit_unc, u_b, a, details=None):
        gum = with_table_type_b(fit_unc, key, u_b, al)
        bc = bound_condition(value, a, fit_unc.u_c, fit_unc.nu_eff)
        unc, other = not_certified(certified(gum, bc, statement), gum)
        return Item(key, name, clause, unit_, value, uncertainty=unc,
                    details={**(details or {}), "statement": statement,
                             "bound_condition": bc, "not_certified": other})
    for i in range(3):
        for j in range(3):
            key = f"M_{AXES[i]}{AXES[j]}"
            items[key] = both(key, "§4 eq. 14", f"system matrix {key}", f"{unit}/(°/s)",
                              float(al.system_matrix[i, j]),
                              _type_a(key, fit, fit_part(um[i, j], ub_m[i, j]),
                                      _nu(al, i, j), None if mc_m is None else mc_m[i, j],
                                      trials), float(ub_m[i, j]), float(a_m[i, j]))
    u_bi, nu_bi = bias_instability_u_dps(al.averaging, static_s)
    for i in range(3):
        key = f"b_{AXES[i]}"
        unc = _type_a(key, fit, ub[i], _nu(al, i, 3), None if mc_m is None else mc_m[i, 3],
                      trials)
        u_long = float(u_bi[i] * abs(al.system_matrix[i, i]))
        if u_long > 0:
            unc = _with_bias_instability(unc, key, u_long, float(nu_bi[i]))
        unc, other = not_certified(unc)
        items[key] = Item(key, f"bias {key}", "§4 eq. 28–30a", unit, float(al.bias_output[i]),
                          uncertainty=unc,
                          details={**({"not_certified": other} if other else {}),
                                   "bias_dps": float(al.derived["bias_dps"][i]),
                                   "u_bias_dps": float(al.u_derived["bias_dps"][i]),
                                   "u_bias_in_run_dps": float(al.u_derived["bias_dps"][i]),
                                   "u_bias_instability_dps": float(u_bi[i]),
                                   "bias_horizon_s": BIAS_HORIZON_S,
                                   "stated": ("long-term bias: the in-run fit plus the bias "
                                              "instability from the shortest dwell to "
                                              f"{BIAS_HORIZON_S / 3600:g} h" if u_long > 0
                                              else "in-run bias over this record (no static "
                                              "record: no bias-instability term)")})
    tab = cross_axis_table(al)
    nu_min = float(np.min(al.dof))
    for n, r in enumerate(tab.itertuples(index=False)):
        i, j = AXES.index(r.gyro), AXES.index(r.about)
        key = f"S_{r.gyro}{r.about}"
        items[key] = both(key, "IEC 62047-20 5.2", f"cross-axis sensitivity {key} = "
                          f"M_{r.gyro}{r.about}/M_{r.gyro}{r.gyro}", "1", float(r.sensitivity),
                          _type_a(key, "first-order propagation of the fit (JCGM 100 5.1.2)",
                                  fit_part(r.u_gum, float(ub_s[n])), al.dof[i], r.u_mc,
                                  trials), float(ub_s[n]), float(a_s[n]))
    for name in OFFDIAG:
        i, j = AXES.index(name[0]), AXES.index(name[1])
        key = f"L_{name}"
        items[key] = both(key, "§4 M̂⁻¹M − I", f"residual leakage after alignment {key} "
                          "(M̂⁻¹M − I)", "1", 0.0,
                          _type_a(key, "δL = −M̂⁻¹ δM, first order",
                                  fit_part(al.leakage_u[i, j], ub_l[i, j]), nu_min),
                          float(ub_l[i, j]), float(a_l[i, j]))
    av = al.averaging
    if av is None:
        items["averaging_time"] = not_measured(
            "averaging_time", "averaging time from the Allan deviation", "§4 eq. 30b", "s",
            "the readings have no static record (rows test = static)")
    else:
        need = [t for t in av.tau_needed_s if math.isfinite(t)]
        if len(need) < 3:
            items["averaging_time"] = not_measured(
                "averaging_time", "averaging time from the Allan deviation", "§4 eq. 30b", "s",
                f"the Allan deviation of the static record never falls below the limit "
                f"{av.noise_limit_dps:.3g} °/s")
        else:
            items["averaging_time"] = Item(
                "averaging_time", "averaging time from the Allan deviation", "§4 eq. 30b", "s",
                float(max(need)), details={
                    "noise_limit_dps": av.noise_limit_dps, "target_deg": av.target_deg,
                    "test_rate_dps": av.test_rate_dps, "tau_needed_s": av.tau_needed_s,
                    "shortest_dwell_s": av.shortest_dwell_s, "sufficient": av.sufficient})
    return items


def inverse_bound(al: AlignmentResult) -> list[dict]:
    """The certificate's statement of the alignment matrix M⁻¹ (derived, not an item), row by
    row, as M's: the bound-condition interval (:func:`bound_condition`) with a the first-order
    offset of M⁻¹ at the table's bounds (``type_b.a_derived.alignment_matrix``) and the fit's
    part of its u with the smallest ν of the fit; without a table budget, the fit's U
    (a = 0). One statement per cell, decided here, not in the renderer."""
    minv = np.ravel(al.derived["alignment_matrix"])
    u_tot = np.ravel(al.u_derived["alignment_matrix"])
    tb = al.type_b or {}
    u_b = np.ravel(tb["u_derived"]["alignment_matrix"]) if tb else np.zeros(9)
    a = np.ravel(tb["a_derived"]["alignment_matrix"]) if tb else np.zeros(9)
    nu = float(np.min(al.dof))
    return [{"value": float(minv[n]),
             **bound_condition(float(minv[n]), float(a[n]),
                               fit_part(float(u_tot[n]), float(u_b[n])), nu)}
            for n in range(9)]


def item_keys() -> tuple[str, ...]:
    """Every item a triad result can hold, for ``SPEC.item_keys`` (a laboratory file's limit
    on any other key is refused before the calibration): the alignment's keys, then the
    thermal model's values at the programme's set points as :mod:`fnmatch` patterns, since
    which gyros the chamber exercised and how many set points and supply levels the programme
    has depend on the data (``K_[xyz]_t[1-9]_v[1-9]`` …). The polynomial coefficients are
    information in ``thermal_model``, not items; the ``thermal_model`` placeholder item (no
    value: the reason the model is missing) is no quantity to limit.

    >>> [k for k in item_keys() if k.startswith("ARW")]
    ['ARW_[xyz]_t[1-9]', 'ARW_[xyz]_t[1-9][0-9]']
    """
    return tuple(ALIGNMENT_KEYS) + THERMAL_POINT_KEYS


def _alignment_not_measured(reason: str, unit: str) -> dict[str, Item]:
    out = {}
    for key in ALIGNMENT_KEYS:
        u = {"M": f"{unit}/(°/s)", "b": unit, "S": "1", "L": "1", "a": "s"}[key[0]]
        clause = {"M": "§4 eq. 14", "b": "§4 eq. 28–30a", "S": "IEC 62047-20 5.2",
                  "L": "§4 M̂⁻¹M − I", "a": "§4 eq. 30b"}[key[0]]
        out[key] = not_measured(key, key.replace("_", " "), clause, u, reason)
    return out


def fit_setting_aside(r: TriadReadings, *, robust: bool, monte_carlo: int, seed,
                      target_deg) -> tuple[AlignmentResult, TriadReadings, list]:
    """The alignment fit (:func:`fit_alignment`) of dwells consistent with one M and b
    (:func:`consistency_check`), as the rate specifications treat a reading that departs from
    its segment (a typo: set aside, named, the rest calibrated, ``_rate_family.screening``):
    where the check names one dwell, that dwell is set aside (a ``set_aside`` finding naming
    its line) and the rest fitted and checked again. Refused (GonioError naming the line, the
    CLI's exit 2): dwells still inconsistent, or not fitted, with that one set aside — never
    a certificate whose M, b, S and L are "not measured" for a typo. A fit that fails naming
    no line (a programme that cannot determine M, e.g. no rotation about z) is raised as it
    is (the caller states M and b not measured). ``robust``: no check (the robust fit
    down-weights such a dwell itself). Returns (fit, readings used, findings)."""
    import dataclasses

    from gonio.result.findings import Finding

    def fit(rr):
        al = fit_alignment(rr, robust=robust, monte_carlo=monte_carlo, seed=seed,
                           target_deg=target_deg)
        if not robust:
            consistency_check(al, rr)
        return al

    try:
        return fit(r), r, []
    except GonioError as exc:
        if robust or exc.line is None:
            raise
        first = exc
    d = r.data
    kept = dataclasses.replace(r, data=d[~((d["test"] == "alignment") & (d["line"] == first.line))]
                               .reset_index(drop=True))
    try:
        al = fit(kept)
    except GonioError as exc:
        raise GonioError(f"{first.message}; with line {first.line} set aside the rest are "
                         f"still refused: {exc.message}", file=r.path, line=first.line) from None
    return al, kept, [Finding("dwell-inconsistent", f"{first.message} — set aside; M and b "
                              "fitted from the other dwells", "set_aside", file=r.path,
                              line=first.line, test="alignment")]


def consistency_check(al: AlignmentResult, readings: TriadReadings) -> None:
    """GonioError when the fit's residual noise is more than :data:`CONSISTENCY_RATIO` times
    what the dwells' own sample deviations give (sd/√n): one M and b cannot explain the
    dwells — an orientation (``up``, ``north0``) or a rate sign is wrong. Names the line of
    the largest residual."""
    rows = readings.rows("alignment")
    n = rows["n_samples"].to_numpy(float)
    for c, ch in enumerate(OUT):
        sd = rows[f"sd_{AXES[c]}"].to_numpy(float)
        ok = np.isfinite(sd) & (sd > 0)
        if not ok.any() or al.residuals is None:
            continue
        expect = np.median(sd[ok] / np.sqrt(n[ok]))
        # a dwell without a usable sd (0: a filled column) is not divided by (no warning)
        r = np.zeros(sd.size)
        r[ok] = np.abs(al.residuals[ok, c]) / (sd[ok] / np.sqrt(n[ok]))
        rms = float(np.sqrt(np.mean((al.residuals[:, c] / expect) ** 2)))
        if rms > CONSISTENCY_RATIO:
            k = int(np.argmax(r))
            raise GonioError(
                f"the dwells are inconsistent with one M and b: gyro {AXES[c]}'s fit residuals "
                f"are {rms:.0f}× the dwell noise, largest at line {int(rows['line'].iloc[k])} "
                f"({r[k]:.0f}×) — a wrong orientation (up, north0) or rate sign?",
                file=readings.path, line=int(rows["line"].iloc[k]))


def _point_budget(key: str, fit, pt: dict, long_term: tuple | None = None,
                  rate_u_rel: float = 0.0) -> Uncertainty:
    """A certified point value's budget: the fit at the point (Type A, soak-components
    variance of xᵀĉ, :func:`gonio.specs.triad_alignment.thermal_model.linear_variance`), the
    model order (the criterion-weighted spread of the candidate orders' values at the point;
    none with fixed orders), the temperature reading of the set point (slope × the Type A
    uncertainty of the soak's mean sensor − chamber difference) and, for the bias,
    ``long_term`` = (u, ν) of the bias instability over the horizon
    (:func:`thermal_long_term`): a soak's bias is the gyro's bias plus its wander at that
    hour, and the wander common to several soaks is invisible in the fit's residuals (the
    alignment's b_i carry the same term). k = t_0.9545 of the
    Welch–Satterthwaite ν_eff (JCGM 100 G.4); the order term is given the fit's ν (it is
    estimated from the same points). ``rate_u_rel`` > 0 (a scale factor: the ± rate dwells
    read K(1 + ε) with ε the rate table's relative rate error) adds |K|·``rate_u_rel``,
    Type B from the table's certificate, ν = ∞ (JCGM 100 G.4.2)."""
    lines = [(f"{key}_fit", "A", pt["u_fit"], pt["nu"],
              f"least-squares fit of the soak points at this point, order ϑ {fit.n_t} / U "
              f"{fit.n_u} by {fit.criterion} ({fit.cov_method})")]
    if fit.criterion != "fixed":
        lines.append((f"{key}_order", "B", pt["u_order"], pt["nu"],
                      f"model order: {fit.criterion.upper()}-weighted spread of the candidate "
                      "orders' values at this point about the selected one (Burnham & "
                      "Anderson 2002 §4.3)"))
    if long_term is not None and long_term[0] > 0:
        lines.append((f"{key}_BI", "B", long_term[0], long_term[1],
                      "bias instability over the bias's horizon: B̂ √(ln(τ_L/τ_d)/π), B̂ from "
                      "the static record's Allan floor (IEEE 952 Annex C), τ_d the spacing "
                      "of the soaks (faster wander is in the fit)"))
    if pt["nu_theta"] > 0:
        lines.append((f"{key}_T", "A", abs(pt["slope"]) * pt["u_theta_c"], pt["nu_theta"],
                      "temperature reading of the soaked set point: slope × u of the soak's "
                      "mean (sensor − chamber)"))
    if rate_u_rel > 0:
        lines.append((f"{key}_table", "B", abs(pt["value"]) * rate_u_rel, math.inf,
                      f"rate table's rate error: |K| × its certificate's relative u "
                      f"{rate_u_rel:.3g}"))
    comp = [{"symbol": sym, "type": typ, "u": float(u), "c": 1.0, "contribution": float(u),
             "dof": float(nu), "source": src} for sym, typ, u, nu, src in lines]
    u_c = math.sqrt(sum(c["u"] ** 2 for c in comp))
    den = sum(c["u"] ** 4 / c["dof"] for c in comp if c["u"] > 0)
    nu_eff = u_c ** 4 / den if den > 0 else math.inf
    k = coverage_k(nu_eff, COVERAGE)
    return Uncertainty(comp, u_c, k * u_c, k, float(nu_eff), None, COVERAGE, K_SOURCE_WS)


def _arw_budget(key: str, fit, pt: dict, flicker: tuple | None = None
                ) -> tuple[float, Uncertainty, dict]:
    """A certified ARW(ϑ) value (a dispersion: the white-noise density read from the static
    dwells' sample standard deviations) and its one statement: the value corrected for the
    bias instability's lift, and its one-sided χ² interval alone at the certificate's p
    (:data:`COVERAGE`, as every triad item; :func:`gonio.result.gum.dispersion_uncertainty`:
    [0, N·√(ν/χ²_{1−p},ν)], ν = ½(N/u_c)²; no k, no "± U").

    Budget: the χ² of the dwells under the white rate noise the procedure assumes
    (:meth:`~gonio.specs.triad_alignment.thermal_model.ChannelModel.arw_chi2`, ``u_chi2``),
    the model order and the temperature reading (as :func:`_point_budget`), and the lift.
    A bias instability B adds to a dwell's sample variance; how much depends on where its
    flicker band ends, which the static record's Allan floor does not show: between none
    (band ending below 1/dwell) and the full-band lift L
    (:func:`~gonio.specs.triad_alignment.thermal_model.flicker_lift_var`). ``flicker`` = (B̂ in
    °/s, ν) from the alignment's static record (:func:`thermal_flicker`): the variance is
    corrected by the midpoint L/2, N = ARW·√(1 − x/2) with x = L/σ̂² (σ̂ the dwell's rate sd
    the fitted ARW gives), and the line is that correction's rectangular half-width
    ARW·x/(4√3) together with B̂'s own spread (B̂² relative √(2/ν)). Without ``flicker``
    nothing is corrected (the value then reads high by the lift, if any).
    Returns (value, uncertainty, details)."""
    value = float(pt["value"])
    details: dict = {"arw_uncorrected": value, "chi2_edf": pt.get("nu_chi2")}
    lines = [(f"{key}_chi2", "A", pt["u_chi2"], pt["nu_chi2"],
              f"white rate noise: each static dwell's sample standard deviation of "
              f"{pt['n_samples']} samples a χ² of ν = n − 1, through the least-squares fit of "
              f"order ϑ {fit.n_t} by {fit.criterion}")]
    if flicker is not None and flicker[0] > 0 and value > 0:
        sigma2 = (float(deg_sqrt_s_from_deg_sqrt_h(value)) ** 2) * pt["fs_hz"]
        x = min(flicker_lift_var(flicker[0], pt["n_samples"], pt["fs_hz"]) / sigma2, 1.0)
        corrected = value * math.sqrt(1.0 - x / 2.0)
        shift = value - corrected
        u_lift = math.hypot(value * x / (4.0 * math.sqrt(3.0)),
                            shift * math.sqrt(2.0 / flicker[1]) if flicker[1] > 0 else 0.0)
        lines.append((f"{key}_BI", "B", u_lift, math.inf,
                      "bias instability's lift of the dwells' variance: corrected by half the "
                      "full-band flicker lift of B̂ (the static record's Allan floor / 0.664), "
                      "rectangular over none … full, with B̂'s own spread"))
        details.update({"flicker_b_dph": float(dps_to_dph(flicker[0])), "flicker_b_nu": flicker[1],
                        "lift_full_rel_var": x, "lift_correction": shift})
        value = corrected
    if fit.criterion != "fixed":
        lines.append((f"{key}_order", "B", pt["u_order"], pt["nu"],
                      f"model order: {fit.criterion.upper()}-weighted spread of the candidate "
                      "orders' values at this point about the selected one"))
    if pt["nu_theta"] > 0:
        lines.append((f"{key}_T", "A", abs(pt["slope"]) * pt["u_theta_c"], pt["nu_theta"],
                      "temperature reading of the soaked set point: slope × u of the soak's "
                      "mean (sensor − chamber)"))
    comp = [{"symbol": sym, "type": typ, "u": float(u), "c": 1.0, "contribution": float(u),
             "dof": float(nu), "source": src} for sym, typ, u, nu, src in lines]
    u_c = math.sqrt(sum(c["u"] ** 2 for c in comp))
    # the certificate's one p (COVERAGE) for the χ² interval too
    return value, dispersion_uncertainty(value, Uncertainty(comp, u_c, None, None, None, None,
                                                            COVERAGE, "chi-square"),
                                         COVERAGE), details


def thermal_flicker(al: AlignmentResult | None, readings: TriadReadings,
                    th: ThermalModelResult) -> dict[str, tuple[float, float]]:
    """Per gyro (B̂ °/s, ν) of the bias instability from the alignment's static record (its
    Allan floor / 0.664, IEEE 952 Annex C; ν = T/τ_min − 1 as
    :func:`gonio.specs.triad_alignment.analysis.bias_instability_u_dps` counts it), for the ARW
    values' lift correction (:func:`_arw_budget`). Empty without a static record."""
    st = readings.rows("static")
    if al is None or al.averaging is None or not len(st):
        return {}
    av = al.averaging
    static_s = float(st["duration_s"].sum())
    out = {}
    for ch in th.channels:
        i = AXES.index(ch)
        a_dph = float(np.asarray(av.min_adev_dph, float)[i])
        if math.isfinite(a_dph) and a_dph > 0:
            nu = max(static_s / float(np.asarray(av.tau_min_adev_s, float)[i]) - 1.0, 1.0)
            out[ch] = (float(dph_to_dps(a_dph)) / FLICKER_FLOOR, nu)
    return out


def thermal_long_term(al: AlignmentResult | None, readings: TriadReadings,
                      th: ThermalModelResult) -> dict[str, tuple[float, float]]:
    """Per gyro (u, ν) of the long-term bias term of the thermal model's bias values, from
    the alignment's static record (:func:`gonio.specs.triad_alignment.analysis.bias_instability_u_dps`)
    with τ_d the median spacing of consecutive soaks: the wander faster than that is
    independent between soaks and shows in the fit's between-soak scatter (MS_b); the slower
    wander moves neighbouring soaks together — with the set points run in order it is
    confounded with the temperature polynomial and invisible in the residuals — and is
    counted here up to the horizon τ_L. Empty without a static record or with one soak (the
    bias values are then in-run, as the alignment's b_i are)."""
    st = readings.rows("static")
    if al is None or not len(st):
        return {}
    out = {}
    for ch, m in th.channels.items():
        starts = np.sort(m.points.groupby("soak")["time_s"].min().to_numpy(float))
        if starts.size < 2:
            continue
        u, nu = bias_instability_u_dps(al.averaging, float(st["duration_s"].sum()),
                                       tau_d_s=float(np.median(np.diff(starts))))
        i = AXES.index(ch)
        if u[i] > 0:
            out[ch] = (float(u[i]), float(nu[i]))
    return out


def _rest_of(unc: Uncertainty, drop: str) -> tuple[float, float]:
    """u and Welch–Satterthwaite ν (JCGM 100 G.4.1) of a budget's lines other than ``drop``."""
    rows = [c for c in unc.components if c["symbol"] != drop and c["u"] > 0]
    u = math.sqrt(sum(c["u"] ** 2 for c in rows))
    den = sum(c["u"] ** 4 / c["dof"] for c in rows)
    return u, (u ** 4 / den if den > 0 else math.inf)


def _arw_one_sample(ch: str, m, clause: str, unit: str) -> dict[str, Item]:
    """ARW(ϑ) of gyro ``ch`` not measured at the set points when its model has no ARW fit
    because static soak dwells hold one sample (``n_samples`` = 1: no standard deviation, so
    no white-noise density); empty otherwise (no static dwells: no ARW items, as before)."""
    pts = m.points
    one = (pts["arw_n"] > 0) & (pts["arw_n"] < 2)
    if m.arw is not None or not one.any():
        return {}
    sp = sorted(set(np.round(pts["chamber_c"].to_numpy(float), 1).tolist()))
    reason = (f"{int(one.sum())} static soak dwells hold one sample (n_samples = 1): one "
              "sample gives no standard deviation; ARW(ϑ) needs at least 3 dwells of 2 or "
              "more samples")
    return {f"ARW_{ch}_t{i}": not_measured(f"ARW_{ch}_t{i}",
                                           f"angle random walk ARW_{ch} at {t:g} °C",
                                           clause, unit, reason)
            for i, t in enumerate(sp, 1)}


def thermal_items(th: ThermalModelResult, unit: str, long_term: dict | None = None,
                  rate_u_rel: float = 0.0, statement: str = "bound",
                  flicker: dict | None = None) -> dict[str, Item]:
    """The certified values of the identified K(ϑ, U), b(ϑ, U), ARW(ϑ) at the programme's
    set points and supply levels (:meth:`ChannelModel.certified_points`), in physical units:
    a fixed measurand per item, whatever orders the criterion chose (the coefficients are
    information in ``thermal_model``). ``long_term`` ({gyro: (u, ν)}, :func:`thermal_long_term`)
    makes the bias values long-term; without it they are in-run (details ``bias``).
    ``rate_u_rel``: the rate table's relative standard uncertainty, a Type B line of every
    K value (:func:`_point_budget`); the K values also carry the bound-condition statement
    (:func:`bound_condition`: |K| × the rate error at its bound, k = 2 × ``rate_u_rel``, plus
    k·u of the other lines) and ``statement`` says which one is certified (:func:`certified`).
    The ARW values are dispersions, stated by their one-sided χ² interval alone
    (:func:`_arw_budget`; ``flicker`` {gyro: (B̂, ν)}, :func:`thermal_flicker`, corrects their
    bias-instability lift; without it they are not corrected)."""
    long_term = long_term or {}
    flicker = flicker or {}
    items: dict[str, Item] = {}
    units = {"K": f"{unit}/(°/s)", "b": "°/s", "ARW": "°/√h"}
    names = {"K": "scale factor", "b": "bias", "ARW": "angle random walk"}
    clauses = {"K": "thesis eq. 6.17", "b": "thesis eq. 6.18", "ARW": "thesis eq. 6.20"}
    for ch, m in th.channels.items():
        items.update(_arw_one_sample(ch, m, clauses["ARW"], units["ARW"]))
        fits = {"K": m.scale, "b": m.bias, "ARW": m.arw}
        for pt in m.certified_points(th.reference_c, th.reference_v):
            name, fit = pt["model"], fits[pt["model"]]
            at = f"{pt['setpoint_c']:g} °C"
            if name == "ARW":
                key = f"ARW_{ch}_t{pt['t']}"
            else:
                key = f"{name}_{ch}_t{pt['t']}_v{pt['v']}"
                at += f", {pt['supply_v']:g} V"
            both, value = {}, pt["value"]
            if name == "ARW":
                value, unc, both = _arw_budget(key, fit, pt, flicker.get(ch))
            else:
                unc = _point_budget(key, fit, pt, long_term.get(ch) if name == "b" else None,
                                    rate_u_rel if name == "K" else 0.0)
            if name == "K" and rate_u_rel > 0:
                u_rest, nu_rest = _rest_of(unc, f"{key}_table")
                bc = bound_condition(pt["value"], abs(pt["value"]) * RATE_ERROR_BOUND_K
                                     * rate_u_rel, u_rest, nu_rest)
                unc, other = not_certified(certified(unc, bc, statement), unc)
                both = {"statement": statement, "bound_condition": bc, "not_certified": other}
            items[key] = Item(key, f"{names[name]} {name}_{ch} at {at}", clauses[name],
                              units[name], value, uncertainty=unc,
                              nonnegative=any(fnmatchcase(key, p) for p in NONNEGATIVE_KEYS),
                              details={**both, "setpoint_c": pt["setpoint_c"],
                                       "supply_v": pt["supply_v"],
                                       "theta_c": pt["theta_c"], "u_v": pt["u_v"],
                                       "temperature_source": m.temperature,
                                       "order_temperature": fit.n_t, "order_supply": fit.n_u,
                                       "criterion": fit.criterion,
                                       "covariance": fit.cov_method,
                                       **({"bias": "long-term" if ch in long_term
                                           else "in-run"} if name == "b" else {})})
    return items


def prediction_table(th: ThermalModelResult, n: int = 7) -> dict:
    """Per gyro: predicted K and b with expanded uncertainties U = k u (k = t_0.9545(ν) of each
    fit) at ``n`` temperatures across the identified range, at the lowest, nominal and
    highest supply — the model's prediction band (parameter uncertainty only)."""
    out = {}
    for ch, m in th.channels.items():
        g = m.prediction_grid(n)
        ks = float(stats.t.ppf(0.5 + COVERAGE / 2, m.scale.dof))
        kb = float(stats.t.ppf(0.5 + COVERAGE / 2, m.bias.dof))
        out[ch] = {"theta_c": g["theta_c"].tolist(), "u_v": g["u_v"].tolist(),
                   "scale": g["scale"].tolist(), "U_scale": (ks * g["u_scale"]).tolist(),
                   "bias_dps": g["bias_dps"].tolist(), "U_bias_dps": (kb * g["u_bias_dps"]).tolist(),
                   "k_scale": ks, "k_bias": kb}
    return out


def _thermal_readings(r: TriadReadings, thermal) -> TriadReadings | None:
    """The thermal programme: ``thermal`` (path or readings) if given, else the file the
    readings' ``# thermal_readings:`` metadata names (relative to the readings' folder), else
    the readings themselves when they hold thermal rows, else None."""
    if thermal is not None:
        return _as_readings(thermal)
    name = r.metadata.get("thermal_readings", "").strip()
    if name:
        p = Path(name)
        if not p.is_absolute() and r.path:
            p = Path(r.path).parent / p
        if not p.is_file():
            raise GonioError(f"the thermal readings {name!r} it names are not there ({p})",
                             file=r.path, key="thermal_readings")
        return read_triad_readings(p)
    return r if (r.data["test"] == "thermal").any() else None


def screen_files(readings, protocol=None, *, thermal=None, **_options) -> list:
    """``SPEC.screen``: the findings (:func:`gonio.specs.triad_alignment.screen.screen`) on the
    readings and on the thermal programme they name (or ``thermal``), refused ones included;
    the pipeline hands them to :func:`calibrate` (``findings=``)."""
    from gonio.specs.triad_alignment.screen import screen

    r = _as_readings(readings)
    found = screen(r, protocol)
    tr = _thermal_readings(r, thermal)
    if tr is not None and tr is not r:
        found += screen(tr, protocol)
    return found


def without_set_aside(r: TriadReadings, findings) -> TriadReadings:
    """``r`` without the rows the ``set_aside`` findings on its file name (by line), their
    lines kept in :attr:`TriadReadings.aside`; ``r`` itself when there are none."""
    from gonio.result.findings import set_aside

    file = None if r.path is None else str(r.path)
    mine = [f for f in findings if f.action == "set_aside" and f.file == file
            and f.line is not None and f.line not in r.aside]
    if not mine:
        return r
    return replace(r, data=set_aside(r.data, mine),
                   aside=r.aside | frozenset(int(f.line) for f in mine))


def unused_readings(findings, *readings: TriadReadings | None) -> list[dict]:
    """results.json's ``unused_readings``: one row per line a ``set_aside`` finding took out
    of the readings (screening, an inconsistent dwell), in the file's order — ``file``,
    ``line``, the row's ``test``, ``step`` and ``phase``, the ``column`` the rule judged and
    the finding's message as ``reason`` (a row set aside is a finding and a reading no item
    used: results.json names it in both, docs/results.schema.json)."""
    rows = {}
    for r in readings:
        if r is None:
            continue
        file = None if r.path is None else str(r.path)
        for rec in r.data[["line", "test", "step", "phase"]].itertuples(index=False):
            rows[(file, int(rec.line))] = rec
    out, seen = [], set()
    for f in findings:
        if f.action != "set_aside" or f.line is None or (f.file, f.line) in seen:
            continue
        seen.add((f.file, f.line))
        rec = rows.get((f.file, int(f.line)))
        out.append({"file": f.file, "line": int(f.line),
                    "test": f.test if rec is None else str(rec.test),
                    "step": None if rec is None else int(rec.step),
                    "phase": None if rec is None else str(rec.phase),
                    "column": f.column, "reason": f.message})
    return sorted(out, key=lambda u: (str(u["file"]), u["line"]))


def refuse(findings) -> list:
    """The findings, after raising the first refused one as a GonioError naming its file and
    line (the readings stop there)."""
    for f in findings:
        if f.action == "refused":
            raise GonioError(f.message, file=f.file, line=f.line, column=f.column)
    return list(findings)


def calibrate(readings, protocol=None, *, monte_carlo_trials: int = 0, robust: bool = False,
              seed: int = 0, target_deg: float = 0.1, criterion: str = "bic",
              temperature: str = "sensor", thermal=None, findings: list | None = None,
              **_options) -> TriadCalibration:
    """Every item of the module docstring from a triad readings file (path or TriadReadings).

    Alignment from the ``alignment`` (and ``static``) rows
    (:func:`gonio.specs.triad_alignment.analysis.estimate_alignment`), Monte Carlo with
    ``monte_carlo_trials`` draws; the extended model from the thermal programme
    (:func:`_thermal_readings`; :func:`gonio.specs.triad_alignment.thermal_model.identify_thermal_model`),
    applied back to the same record for the before/after comparison. ``protocol`` (a name or
    file; None: the built-in one's) gives the statement the table-dominated items
    certify (``[alignment] uncertainty_statement``: "bound", the only one it accepts,
    :data:`STATEMENTS`); everything else
    the analysis uses is in the readings file.
    ``findings``: the screening of both files already made (:func:`screen_files`, the
    pipeline's ``SPEC.screen``); None: screened here.
    """

    from gonio.specs.triad_alignment.bench import load_triad_protocol
    from gonio.specs.triad_alignment.screen import check

    # which statement the table-dominated items certify: the protocol's choice (STATEMENTS)
    statement = load_triad_protocol(protocol, KEY).uncertainty_statement if protocol \
        else "bound"
    r = _as_readings(readings)
    screened = findings is not None
    # refused readings stop here, naming the line
    findings = refuse(findings) if screened else check(r)
    given = r
    r = without_set_aside(r, findings)
    unit = r.metadata.get("output_unit", "output")
    items: dict[str, Item] = {}
    al = None
    if (r.data["test"] == "alignment").any():
        try:        # one inconsistent dwell is set aside; a dwell refused stops here (exit 2)
            al, r, aside = fit_setting_aside(r, robust=robust, monte_carlo=monte_carlo_trials,
                                             seed=seed, target_deg=target_deg)
        except GonioError as exc:
            if exc.line is not None:
                raise
            al = None         # a programme that cannot determine M and b (no line to name)
            items.update(_alignment_not_measured(f"the data were refused: {exc.message}", unit))
        else:
            findings = list(findings) + aside
            items.update(alignment_items(al, monte_carlo_trials, static_record_s(r),
                                         statement))
    else:
        items.update(_alignment_not_measured("the readings have no alignment rows", unit))
    tr = _thermal_readings(r, thermal)
    if tr is not None and tr is not r and not screened:
        findings += check(tr)
    given_thermal = tr
    if tr is not None:
        tr = without_set_aside(tr, findings)
    th = None
    comp: dict[str, Compensation] = {}
    extra = {"alignment": None if al is None else al.to_json(), "thermal_model": None}
    if tr is None:
        items["thermal_model"] = not_measured(
            "thermal_model", "temperature / supply model K(ϑ, U), b(ϑ, U)", "thesis eq. 6.14",
            "", "the readings include no thermal programme (no thermal rows, no "
                "'# thermal_readings:' file)")
    else:
        extra["chamber_profile_c"] = chamber_set_points(tr)    # the certificate's environment
        try:
            th = identify_thermal_model(tr, criterion=criterion, temperature=temperature)
            comp = {ch: compensate_record(m, tr) for ch, m in th.channels.items()}
        except GonioError as exc:
            th = None
            items["thermal_model"] = not_measured(
                "thermal_model", "temperature / supply model K(ϑ, U), b(ϑ, U)",
                "thesis eq. 6.14", "", f"the data were refused: {exc.message}")
        else:
            items.update(thermal_items(th, unit, thermal_long_term(al, r, th),
                                       tr.table_metadata("rate_table_u_rel"), statement,
                                       thermal_flicker(al, r, th)))
            tj = th.to_json()
            for ch, c in comp.items():
                tj["channels"][ch]["compensation"] = c.to_json()
            tj["source"] = source_info(tr)
            tj["prediction_U"] = prediction_table(th)
            extra["thermal_model"] = tj
    if al is not None:
        extra["cross_axis"] = cross_axis_table(al).to_dict(orient="records")
        extra["alignment_inverse"] = inverse_bound(al)
    extra["figures"] = figure_series(al, th)      # what the certificate's figures draw
    src = source_info(r)
    return TriadCalibration(KEY, TITLE_EN, items, dict(r.metadata), src, list(READINGS_TAKEN),
                            extra=json_safe(extra), alignment=al, thermal=th, compensation=comp,
                            covariances=alignment_covariances(al), findings=list(findings),
                            unused_readings=unused_readings(findings, given, given_thermal),
                            tables=prediction_tables(extra["thermal_model"]))


def chamber_set_points(readings: TriadReadings) -> list[float]:
    """The chamber temperatures the thermal programme soaked at (°C, 0.1 °C), in the order
    first held: the mean ``chamber_c`` of each run of consecutive soak rows, whatever the
    readings' metadata says of the programme.

    >>> import pandas as pd
    >>> rows = pd.DataFrame({"test": "thermal", "phase": ["soak", "soak", "ramp", "soak", "soak"],
    ...                      "chamber_c": [-40.02, -39.98, -30.0, 20.04, 20.0]})
    >>> chamber_set_points(TriadReadings(rows, {}, None))
    [-40.0, 20.0]
    """
    th = readings.rows("thermal")
    if th.empty:
        return []
    run = (th["phase"] != th["phase"].shift()).cumsum()
    soak = th[th["phase"] == "soak"]
    out: list[float] = []
    for _, g in soak.groupby(run[soak.index], sort=False):
        t = round(float(g["chamber_c"].mean()), 1) + 0.0       # no −0.0
        if math.isfinite(t) and t not in out:
            out.append(t)
    return out


def alignment_covariances(al: AlignmentResult | None) -> list[Covariance]:
    """Per gyro, the covariance of its row of M and its bias (one fit: M_i·, b_i),
    σ_w²(XᵀWX)⁻¹ + σ_B²(PZ)(PZ)ᵀ in the items' units (the fits of the three gyros are
    independent)."""
    if al is None:
        return []
    out = []
    for i in range(3):
        keys = [f"M_{AXES[i]}{AXES[j]}" for j in range(3)] + [f"b_{AXES[i]}"]
        block = np.asarray(al.cov_theta)[4 * i:4 * i + 4, 4 * i:4 * i + 4]
        out.append(Covariance(keys, block.tolist(), f"gyro {AXES[i]}: weighted least-squares "
                              "fit of all dwells, σ_w²(XᵀWX)⁻¹ + σ_B²(PZ)(PZ)ᵀ (JCGM 100 4.2)"))
    return out


def prediction_tables(thermal_json: dict | None) -> dict:
    """Per modelled gyro, ``thermal_prediction_<gyro>.csv``: the prediction band."""
    import pandas as pd

    tm = thermal_json or {}
    return {f"thermal_prediction_{ch}.csv": pd.DataFrame(
        {k: v for k, v in pr.items() if isinstance(v, list)})
        for ch, pr in (tm.get("prediction_U") or {}).items()}


def article_budget() -> MisalignmentBudget:
    """The alignment article's worked mechanical budget (eq. 5a–5c), exact values:
    ADIS16485 on ledges with 0.2 mm height tolerance over W = 44 mm, M2 screws in 2.85 mm
    holes spaced 39.6 mm × 42.6 mm, IMU axis-to-frame misalignment 1°. The article's
    printed values and where they differ: :data:`gonio.physics.alignment.ARTICLE_WORKED_EXAMPLE`."""
    return misalignment_budget(ledge_tolerance_mm=0.2, width_mm=44.0, hole_diameter_mm=2.85,
                               screw_diameter_mm=2.0, hole_spacing_mm=(39.6, 42.6),
                               psi_imu_deg=1.0)


__all__ = ["TriadCalibration", "calibrate", "article_budget", "ARTICLE_WORKED_EXAMPLE",
           "ALIGNMENT_KEYS", "KEY"]
