"""The draft's Annex A uncertainty budget for the angle-position deviation, on :mod:`uncertainty`.

Model (draft Annex A.2, with the repeatability of A.4.4 as an additive term):
Δ = (φ_e + B_E) − P + r, all sensitivity coefficients ±1 (symbolic, sympy).

========  ===============================  ====  ===========  ==========================
symbol    source                           type  distrib.     u (defaults)
========  ===============================  ====  ===========  ==========================
P         standard table positioning       B     rectangular  0.1″/√3 = 0.0577″ (A.4.1)
phi_e     sensing plane ∦ table plane      B     rectangular  0.0785″/√3 = 0.0453″ (A.4.2)
B_E       zero drift                       B     rectangular  0.15″/√3 = 0.0866″ (A.4.3)
r         repeatability                    A     normal       0.096″ (A.4.4)
========  ===============================  ====  ===========  ==========================

u_c = 0.1487″ (A.6), U = k·u_c = 0.297″ with k = 2 (A.7), stated 0.15″ / 0.30″
(JCGM 100 7.2.6). The annex's own path rounds the components first (A.5: 0.06, 0.05,
0.09, 0.09 → u_c = 0.149″, see :func:`annex_a5_rounding`). With u(r) = 0.09″ exactly,
u_c would be 0.145″ and U 0.29″: the annex's 0.30″ rests on u(r) = 0.096″ (or on
rounding the components first).

``extra_components`` add further additive terms (e.g. Earth-rate residual,
tilt × Earth-rate coupling); none by default so the annex stays reproducible.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from decimal import ROUND_DOWN, ROUND_HALF_UP, Decimal
from typing import Any, ClassVar, Sequence

import numpy as np
import pandas as pd

from gonio.specs.ogam_draft.budget_extra import ExtraComponent
from gonio.errors import GonioError
from gonio.units import ARCSEC_PER_DEG, MIN_PER_H
from gonio.specs.ogam_draft.tilt import elliptic_extreme
from gonio.result.statement import rounded as rounded_sig, stated_gum
from uncertainty.propagation import LinearModel
from uncertainty import (GumResult, MonteCarloResult, ValidationResult, budget_table,
                         from_u, monte_carlo, propagate, render_html, render_markdown,
                         render_text, type_b, validate_gum)

__all__ = ["AnnexABudget", "annex_a_budget", "annex_a5_rounding",
           "repeatability_from_deviations", "annex_a_model", "annex_a_linear_model"]

#: Arc-seconds per minute of a drift given in °/h: 1 °/h = 3600″/60 min = 60 ″/min.
ARCSEC_PER_MIN_PER_DPH = ARCSEC_PER_DEG / MIN_PER_H


def _err(option: str, msg: str) -> GonioError:
    return GonioError(msg, key=option)


def repeatability_from_deviations(deviations_arcsec) -> float:
    """u(r): the largest, over positions, Bessel standard deviation over repeated series.

    Draft Annex A.4.4: ten runs, the experimental standard deviation (ddof = 1) of
    the deviations at each position, the largest is u(r). ``deviations_arcsec`` is
    2-D, one row per series (run), one column per position.

    >>> repeatability_from_deviations([[0.1, 0.0], [0.3, 0.0], [0.2, 0.1]])
    0.1
    """
    e = np.asarray(deviations_arcsec, dtype=float)
    if e.ndim != 2 or e.shape[0] < 2:
        raise GonioError("repeatability needs a 2-D array with at least 2 series (rows), "
                         f"got shape {e.shape}", key="deviations_arcsec")
    if not np.all(np.isfinite(e)):
        raise GonioError("deviations must be finite", key="deviations_arcsec")
    return float(np.round(np.max(np.std(e, axis=0, ddof=1)), 15))


def annex_a5_rounding(u_arcsec: float, type_: str) -> float:
    """A component as the draft's summary table A.5 prints it, to 0.01″.

    The annex rounds Type B components half up (0.0577 → 0.06, 0.0453 → 0.05,
    0.0866 → 0.09) but shows the Type A u(r) = 0.096″ as 0.09″, i.e. truncated. This
    function takes that reading (half up for B, truncation for A); the alternative,
    0.096 → 0.10, would give u_c = 0.153″.

    >>> [annex_a5_rounding(u, t) for u, t in [(0.0577, "B"), (0.0453, "B"), (0.0866, "B"), (0.096, "A")]]
    [0.06, 0.05, 0.09, 0.09]
    """
    mode = ROUND_DOWN if type_ == "A" else ROUND_HALF_UP
    return float(Decimal(repr(float(u_arcsec))).quantize(Decimal("0.01"), rounding=mode))


def annex_a_model(extra_symbols: Sequence[str] = ()) -> "sympy.Expr":
    """Δ = (φ_e + B_E) − P + r (+ extra terms) as a sympy expression (draft Annex A.2).

    >>> annex_a_model()
    B_E - P + phi_e + r
    """
    import sympy                      # lazily: the GUM path uses annex_a_linear_model
    p, phi, b, r = sympy.symbols("P phi_e B_E r", real=True)
    expr = (phi + b) - p + r
    for s in extra_symbols:
        expr = expr + sympy.Symbol(s, real=True)
    return expr


def annex_a_linear_model(extra_symbols: Sequence[str] = ()) -> LinearModel:
    """:func:`annex_a_model` as a :class:`uncertainty.propagation.LinearModel` (inputs P, φ_e,
    B_E, r, extras, each estimated 0; coefficients −1, +1, +1, +1, +1): the same GUM
    numbers without SymPy.

    >>> annex_a_linear_model(("K_P",)).coeffs
    (-1.0, 1.0, 1.0, 1.0, 1.0)
    """
    names = ("P", "phi_e", "B_E", "r", *extra_symbols)
    return LinearModel(0.0, (-1.0,) + (1.0,) * (len(names) - 1), names)


@dataclass(frozen=True)
class AnnexABudget:
    """Result of :func:`annex_a_budget`; computing and reporting are separate."""

    #: The line ``gonio budget`` prints above the text table.
    heading: ClassVar[str] = ("Annex A uncertainty budget (arc-seconds); u_annex_A5 = the "
                              "annex's rounded value")

    gum: GumResult
    stated_u_c_arcsec: float
    stated_U_arcsec: float
    annex_rounded: dict
    parameters: dict
    monte_carlo: MonteCarloResult | None = None
    validation: ValidationResult | None = None
    _rounded_components: tuple = field(default=(), repr=False)
    #: The physical budget of E per 7.4 point (dicts: position_deg, u_c_arcsec, U_arcsec,
    #: k); this budget itself is the one of the point with the largest U. Empty for the
    #: draft's reading (one budget for every point, Annex A).
    points: tuple = ()
    #: The 95 % interval of max|E_i|'s truth, max_i |E_i,true|, from the points' E_i, u_c and
    #: ν_eff (:func:`uncertainty.extreme.max_abs_interval`; valid for every pattern of the
    #: true E_i), as a dict (``lower_arcsec``, ``upper_arcsec``, ``p``, factors, ``basis``);
    #: None for the draft's reading.
    max_interval: dict | None = None

    @property
    def u_c_arcsec(self) -> float:
        return self.gum.u_c

    @property
    def U_arcsec(self) -> float:
        return self.gum.U

    @property
    def k(self) -> float:
        return self.gum.k

    def table(self) -> pd.DataFrame:
        """Budget DataFrame (arc-seconds) with the annex's A.5 rounded u beside the exact one."""
        t = budget_table(self.gum)
        t["u_annex_A5"] = list(self._rounded_components)
        return t

    def to_dict(self) -> dict[str, Any]:
        """Plain dict for ``--json`` (deterministic key order)."""
        comps = [{
            "symbol": c.symbol, "source": c.source, "type": c.type,
            "distribution": c.distribution,
            "half_width_arcsec": c.half_width, "divisor": c.divisor, "u_arcsec": c.u_xi,
            "c": c.c_i, "contribution_arcsec": c.contribution,
            "dof": None if math.isinf(c.dof) else c.dof,
        } for c in self.gum.contributions]
        mc = None
        if self.monte_carlo is not None:
            m, v = self.monte_carlo, self.validation
            mc = {"trials": m.trials, "seed": self.parameters["seed"], "mean_arcsec": m.value,
                  "u_arcsec": m.u, "p": m.p, "interval_arcsec": [m.low, m.high],
                  "gum_validation": {"d_low_arcsec": v.d_low, "d_high_arcsec": v.d_high,
                                     "delta_arcsec": v.delta, "passed": v.passed,
                                     "gum_interval_arcsec": list(v.gum_interval)}}
        out = {
            "components": comps,
            "u_c_arcsec": self.u_c_arcsec,
            "U_arcsec": self.U_arcsec,
            "k": self.k,
            "stated": {"u_c_arcsec": self.stated_u_c_arcsec, "U_arcsec": self.stated_U_arcsec},
            "annex_rounded": self.annex_rounded,
            "monte_carlo": mc,
            **({"points": [dict(p) for p in self.points]} if self.points else {}),
            **({"max_abs_interval": dict(self.max_interval)} if self.max_interval else {}),
        }
        # the points' U with the table's bound (U = k·u + b): the per-point statement
        out.update(e_point_statement(out.get("points")))
        return out

    def _summary(self) -> list[str]:
        a = self.annex_rounded
        lines = [f"u_c = {self.u_c_arcsec:.4f}\u2033 (A.6)   U = k\u00b7u_c = {self.k:g} \u00d7 "
                 f"{self.u_c_arcsec:.4f}\u2033 = {self.U_arcsec:.3f}\u2033 (A.7)",
                 f"annex path (A.5 rounded components): u_c = {a['u_c_arcsec']:.3f}\u2033, "
                 f"U = {a['U_arcsec']:.3f}\u2033",
                 f"stated: u_c = {self.stated_u_c_arcsec:.2f}\u2033, "
                 f"U = {self.stated_U_arcsec:.2f}\u2033 (k = {self.k:g})"]
        if self.monte_carlo is not None:
            m, v = self.monte_carlo, self.validation
            lines.append(f"Monte Carlo (JCGM 101, {m.trials} trials): u = {m.u:.4f}\u2033, "
                         f"95 % interval [{m.low:.4f}, {m.high:.4f}]\u2033; GUM validation "
                         f"(JCGM 101 8): d_low = {v.d_low:.4f}, d_high = {v.d_high:.4f}, "
                         f"\u03b4 = {v.delta:g} \u2192 {'passed' if v.passed else 'failed'}")
        return lines

    def to_text(self) -> str:
        """Aligned text table plus the results."""
        return render_text(self.table()) + "\n\n" + "\n".join(self._summary())

    def to_markdown(self) -> str:
        """Markdown table plus the results."""
        return render_markdown(self.table()) + "\n\n" + "\n".join(f"- {s}" for s in self._summary())

    def to_html(self) -> str:
        """HTML table plus the results."""
        import html
        return render_html(self.table()) + "\n" + "\n".join(
            f"<p>{html.escape(s)}</p>" for s in self._summary())


def _extra(e) -> ExtraComponent:
    if isinstance(e, ExtraComponent):
        return e
    if isinstance(e, dict):
        return ExtraComponent(**e)
    return ExtraComponent(*e)


_P_SOURCE = "standard table positioning (A.4.1)"
_PHI_SOURCE = "sensing plane not parallel to table plane (A.4.2)"


def _table_input(mpe_arcsec: float, u_arcsec: float | None, dof: float, source: str):
    """E's P line: the draft's rectangular ±MPE (A.4.1), or a physical budget's normal u
    with its ν (a calibrated table's, JCGM 100 G.4.1)."""
    if u_arcsec is None:
        return type_b("P", 0.0, mpe_arcsec, "rectangular", source=source)
    if math.isinf(dof):
        return type_b("P", 0.0, u_arcsec, "normal", source=source)
    return from_u("P", 0.0, u_arcsec, dof=dof, type="B", source=source)


def annex_a_budget(table_mpe_arcsec: float = 0.1, tilt_deg: float = 0.1,
                   zero_stability_dph: float = 0.005, duration_min: float = 0.5,
                   repeatability_arcsec: float = 0.096, k: float | None = 2.0,
                   extra_components: Sequence = (), monte_carlo_trials: int = 0,
                   seed: int = 0, repeatability_dof: float = math.inf,
                   repeatability_type: str = "A", repeatability_source: str = "repeatability (A.4.4)",
                   table_u_arcsec: float | None = None, table_source: str = _P_SOURCE,
                   table_dof: float = math.inf, phi_e_arcsec: float | None = None,
                   phi_e_source: str = _PHI_SOURCE
                   ) -> AnnexABudget:
    """The draft's Annex A budget (A.2–A.7), optionally checked by JCGM 101 Monte Carlo.

    Parameters
    ----------
    table_mpe_arcsec : float
        Standard table MPE, half-width of a rectangular u(P) (A.4.1).
    tilt_deg : float
        Tilt of the sensing plane; u(φ_e) = elliptic extreme / √3 (A.4.2).
    zero_stability_dph, duration_min : float
        u(B_E) = stability × time / √3, 0.005 °/h = 0.3″/min (A.4.3).
    repeatability_arcsec : float
        u(r), Type A (A.4.4); see :func:`repeatability_from_deviations`.
    k : float or None
        Coverage factor (A.7: 2). None: k = t_95(ν_eff), ν_eff by Welch–Satterthwaite
        (JCGM 100 G.4), e.g. u(r) from n series carries ν = n − 1.
    extra_components : sequence of ExtraComponent, dict or tuple
        Further additive Type B terms (symbol, source, half_width_arcsec, distribution).
    monte_carlo_trials, seed : int
        JCGM 101 trials (0: none) and the seed of its Generator.
    repeatability_dof : float
        ν of u(r); the draft gives none, so infinite (normal in MC). With a finite ν
        the MC draws a scaled t (JCGM 101 6.4.9).
    repeatability_type, repeatability_source : str
        "A" when u(r) comes from the calibration's own series, "B" when it is a stated
        value (e.g. the protocol's); the source sentence shown in the budget.
    table_u_arcsec, table_dof, phi_e_arcsec, table_source, phi_e_source : float or None, str
        Physical budget's P (normal u, ν ``table_dof``: ∞ or a calibrated table's, JCGM 100
        G.4.1), φ_e; None: the draft's A.4.1 and A.4.2 lines.

    Examples
    --------
    >>> b = annex_a_budget()
    >>> [round(c.u_xi, 4) for c in b.gum.contributions]
    [0.0577, 0.0453, 0.0866, 0.096]
    >>> round(b.u_c_arcsec, 4), round(b.U_arcsec, 3), b.stated_u_c_arcsec, b.stated_U_arcsec
    (0.1487, 0.297, 0.15, 0.3)
    >>> round(b.annex_rounded["u_c_arcsec"], 3)
    0.149

    u(r) from 5 series (ν = 4), k by Welch–Satterthwaite: ν_eff = 0.1487⁴/(0.096⁴/4) = 23.0,
    k = t_95(23) = 2.069:

    >>> w = annex_a_budget(repeatability_dof=4, k=None)
    >>> round(w.gum.dof, 1), round(w.k, 3), round(w.U_arcsec, 3)
    (23.0, 2.069, 0.308)
    """
    checks = [("table_mpe_arcsec", table_mpe_arcsec, "must be >= 0"),
              ("zero_stability_dph", zero_stability_dph, "must be >= 0"),
              ("duration_min", duration_min, "must be >= 0"),
              ("repeatability_arcsec", repeatability_arcsec, "must be >= 0")]
    for name, v, msg in checks:
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
            raise _err(name, f"{msg}, got {v}")
    if not (math.isfinite(tilt_deg) and 0 <= tilt_deg < 90):
        raise _err("tilt_deg", f"must satisfy 0 <= tilt < 90 degrees, got {tilt_deg}")
    if k is not None and not (math.isfinite(k) and k > 0):
        raise _err("k", f"coverage factor must be > 0, got {k}")
    if int(monte_carlo_trials) != monte_carlo_trials or monte_carlo_trials < 0 \
            or monte_carlo_trials == 1:
        raise _err("monte_carlo_trials", f"must be 0 or an integer >= 2, got {monte_carlo_trials}")
    if not repeatability_dof >= 1:
        raise _err("repeatability_dof", f"must be >= 1, got {repeatability_dof}")
    extras = [_extra(e) for e in extra_components]
    names = {"P", "phi_e", "B_E", "r"}
    for e in extras:
        if e.symbol in names or not e.symbol.isidentifier():
            raise _err("extra_components", f"symbol {e.symbol!r} is not a new identifier")
        if not (math.isfinite(e.half_width_arcsec) and e.half_width_arcsec >= 0):
            raise _err("extra_components", f"half-width of {e.symbol} must be >= 0")
        names.add(e.symbol)

    drift_arcsec = zero_stability_dph * ARCSEC_PER_MIN_PER_DPH * duration_min
    inputs = [
        _table_input(table_mpe_arcsec, table_u_arcsec, table_dof, table_source),
        type_b("phi_e", 0.0, elliptic_extreme(tilt_deg).extreme_arcsec if phi_e_arcsec is None
               else phi_e_arcsec, "rectangular", source=phi_e_source),
        type_b("B_E", 0.0, drift_arcsec, "rectangular", source="zero drift (A.4.3)"),
        from_u("r", 0.0, repeatability_arcsec, dof=repeatability_dof, type=repeatability_type,
               source=repeatability_source),
    ]
    for e in extras:
        try:
            inputs.append(type_b(e.symbol, 0.0, e.half_width_arcsec, e.distribution,
                                 source=e.source))
        except ValueError as exc:
            raise _err("extra_components", str(exc)) from None
    model = annex_a_linear_model(tuple(e.symbol for e in extras))
    gum = propagate(model, inputs, k=k) if k is not None else \
        stated_gum(propagate(model, inputs, k=None, p=0.95))   # k of the stated ν_eff
    k = gum.k

    rounded = tuple(annex_a5_rounding(c.u_xi, c.type) for c in gum.contributions)
    u_c_r = math.sqrt(sum(u * u for u in rounded))
    annex_rounded = {"components": {c.symbol: r for c, r in zip(gum.contributions, rounded)},
                     "u_c_arcsec": u_c_r, "U_arcsec": k * u_c_r}
    stated_u = rounded_sig(gum.u_c) if gum.u_c > 0 else 0.0
    stated_U = rounded_sig(gum.U) if gum.U > 0 else 0.0

    mc = val = None
    if monte_carlo_trials:
        mc = monte_carlo(annex_a_model(tuple(e.symbol for e in extras)), inputs,
                         int(monte_carlo_trials), seed=seed)
        val = validate_gum(gum, mc, ndig=2)
    params = dict(table_mpe_arcsec=table_mpe_arcsec, tilt_deg=tilt_deg,
                  zero_stability_dph=zero_stability_dph, duration_min=duration_min,
                  repeatability_arcsec=repeatability_arcsec, k=k, seed=seed,
                  monte_carlo_trials=int(monte_carlo_trials))
    return AnnexABudget(gum=gum, stated_u_c_arcsec=stated_u, stated_U_arcsec=stated_U,
                        annex_rounded=annex_rounded, parameters=params, monte_carlo=mc,
                        validation=val, _rounded_components=rounded)


def e_point_statement(points) -> dict:
    """``extra.uncertainty``'s per-point statement where the points carry the table's bound
    (:func:`gonio.specs.ogam_draft.calibration.point_u_with_bound`): ``U_bound_arcsec`` the
    largest U_i = k·u_i + b_i (the stated per-point U), its ``k_bound``,
    ``table_bound_arcsec`` b_i, ``u_without_table_arcsec`` u_i with its
    ``nu_without_table`` (None: ∞), ``ku_arcsec`` = k·u_i (the stated U less b_i, printed as
    such), ``U_position_deg``, and ``u_c_certified`` False with ``u_c_beside``, what the
    budget's ``u_c_arcsec`` is; {} where no point has a bound (a calibrated table, the
    draft's one budget). ``u_c_arcsec``, ``U_arcsec`` and ``k`` stay the budget's own (the
    table line at MPE/√3 per position, positions independent), beside, not stated: that
    model does not hold the corner table (:func:`~gonio.specs.ogam_draft.calibration.
    point_u_with_bound`), so no standard uncertainty of E is certified where U carries b
    (JCGM 100 4.3.7: b enters as a bound, not as a standard uncertainty).

    >>> e_point_statement([{"position_deg": 30.0, "U_bound_arcsec": 0.3, "k_bound": 1.96,
    ...     "table_bound_arcsec": 0.1, "u_without_table_arcsec": 0.1}])["U_position_deg"]
    30.0
    >>> e_point_statement([{"position_deg": 30.0, "U_arcsec": 0.3, "k": 1.96}])
    {}
    """
    pts = [p for p in points or () if p.get("U_bound_arcsec") is not None]
    if not pts:
        return {}
    w = max(pts, key=lambda p: p["U_bound_arcsec"])
    return {"U_bound_arcsec": w["U_bound_arcsec"], "k_bound": w["k_bound"],
            "table_bound_arcsec": w["table_bound_arcsec"],
            "u_without_table_arcsec": w["u_without_table_arcsec"],
            "nu_without_table": w.get("nu_without_table"),
            "ku_arcsec": float(w["k_bound"] * w["u_without_table_arcsec"]),
            "U_position_deg": w["position_deg"],
            "u_c_certified": False, "u_c_beside": E_U_C_BESIDE}


#: What E's budget ``u_c_arcsec`` is where the per-point U carries the table's bound
#: (:func:`e_point_statement`): kept in results.json, not stated.
E_U_C_BESIDE = ("the budget's u_c with the table line at MPE/sqrt(3) per position (positions "
                "independent), which does not hold the corner table; beside, not stated: the "
                "stated U = k*u + b carries the table by its bound b, and u is that of the "
                "lines other than the table's (u_without_table_arcsec, nu_without_table)")
