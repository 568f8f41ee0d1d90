"""IEC 62047-20:2014 measured characteristics, one function each (clause in the docstring).

The IEC formulas are in :mod:`gonio.specs.iec62047_20.formulas`; shared formulas are in
:mod:`gonio.specs._rate_family.formulas` (the least-squares line, the
Earth-rate projection, sine fits and crossings are the same as for JJF 1535); the
readings taken are in ``docs/iec62047-20-readings.md``. Uncertainties come from the
calibration's own data (GUM, k = t₉₅(ν_eff)).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from gonio.specs._rate_family import formulas as rg
from gonio.specs.iec62047_20 import formulas as ief
from gonio.analysis.noise import allan_deviation, fit_markov_model, fit_noise_model, model_deviation
from gonio.analysis.noise.covariance import variance_covariance
from gonio.analysis.noise.psd import welch_band_rms_u_rel, welch_psd
from gonio.analysis.noise.stream import value_range
from gonio.errors import GonioError
from gonio.physics.alignment import input_axis_enu
from gonio.result.gum import (budget_nu, dispersion_bound_statement, dispersion_uncertainty,
                              gum, max_magnitude_statement,
                              std_dev_uncertainty)
from gonio.result.model import Item, Uncertainty, not_measured
from gonio.result.statement import K_SOURCE_SELECTED_MAX
from gonio.specs._rate_family.rate_records import (RateContext, static_output, static_rate_dph,
                                                   segment_means, segment_samples, rate_table_line,
                                                   table_bound_statement,
                                                   TABLE2_RATE_ACCURACY_REL)
from gonio.units import S_PER_H
from gonio.specs.iec62047_20.keys import ITEM_ROWS, NONNEGATIVE  # noqa: F401 (rate_records reads it here)
from uncertainty import DOF_U_WITHIN_10PCT, from_u, type_b, welch_satterthwaite


@dataclass(kw_only=True)
class Context(RateContext):
    """The shared rate context with IEC 62047-20's typical scale factor, base temperature and
    supply, and a_BASE once computed (with its relative u_c and that u_c's ν)."""

    a_typ: float
    t_base_c: float
    v_base: float
    a_base: float | None = None
    a_base_u_rel: float | None = None
    a_base_nu: float = math.inf
    a_base_bound_rel: float = 0.0
    a_base_rest_u_rel: float | None = None
    a_base_rest_nu: float = math.inf
    sf_tc_item: Item | None = None      # 5.1.3.4's item once computed (chamber_coefficient)


def supply_correction(df: pd.DataFrame, ratiometric: bool) -> tuple[pd.DataFrame, int]:
    """IEC 62047-20 5.1.4.1 e) eq (18) (and (19), (31) of 5.1.4.2 e), 5.6.4 e)): for a
    ratiometric gyro every output recorded with a set voltage (``supply_set_v``) beside the
    actual one (``supply_v``) becomes y = y_RAW·V_set/V_actual
    (:func:`gonio.specs.iec62047_20.formulas.voltage_corrected`), and ``supply_v`` then holds the set
    voltage the corrected output refers to (reading taken: each run to its own set voltage,
    never to V_BASE, which would cancel what 5.1.3.5 measures). Returns a corrected copy
    (the input is not modified) and the number of rows corrected; a non-ratiometric gyro's
    outputs are returned unchanged.

    >>> d = pd.DataFrame({"output": [1000.0, 7.0], "supply_v": [4.9998, 5.0],
    ...                   "supply_set_v": [5.0, float("nan")]})
    >>> c, n = supply_correction(d, True)
    >>> round(float(c["output"][0]), 2), float(c["supply_v"][0]), n, float(d["output"][0])
    (1000.04, 5.0, 1, 1000.0)
    """
    if not ratiometric or "supply_set_v" not in df:
        return df, 0
    vs = df["supply_set_v"].to_numpy(dtype=float)
    ok = np.isfinite(vs)
    if not ok.any():
        return df, 0
    va = df["supply_v"].to_numpy(dtype=float)
    if np.any(~(va[ok] > 0)):
        raise GonioError("IEC 62047-20 eq (18): an actual supply voltage is missing or ≤ 0",
                         column="supply_v")
    out = df.copy()
    y = out["output"].to_numpy(dtype=float).copy()
    y[ok] = ief.voltage_corrected(y[ok], vs[ok], va[ok])
    out["output"] = y
    out.loc[ok, "supply_v"] = vs[ok]
    return out, int(ok.sum())


def _miss(ctx, test, key, title, clause, unit, need_a=True):
    if not ctx.has(test):
        return not_measured(key, title, clause, unit, f"no '{test}' records in the readings")
    if need_a and ctx.a_base is None:
        return not_measured(key, title, clause, unit, "needs the scale factor of 5.1.3.1")
    return None


def _sf_runs(ctx: Context, test: str) -> list[dict]:
    """Each 2n + 1-point calibration of ``test`` (5.1.3.1): rates (rest included), means, fit."""
    if ("sf", test) in ctx.cache:
        return ctx.cache[("sf", test)]
    means = segment_means(ctx.df, test)
    out = []
    for run in sorted({m.run for m in means}):
        seg = [m for m in means if m.run == run]
        pts = [m for m in seg if m.role == "rate"]
        if test == "scale_factor" and run != 0:
            continue
        x = np.array([m.rate_dps for m in pts])
        y = np.array([m.mean for m in pts])
        a, b = rg.least_squares_line(x, y)
        r = y - (a * x + b)
        se = math.sqrt(float(r @ r) / (x.size - 2) / float(((x - x.mean()) ** 2).sum())) \
            if x.size > 2 else math.nan
        u_y, nu_y = [], []
        for m in pts:
            yy = segment_samples(ctx.df, test, m.run, m.step)["output"].to_numpy()
            nb = yy.size // 5
            u_y.append(float(yy[: nb * 5].reshape(nb, 5).mean(1).std(ddof=1) / math.sqrt(nb))
                       if nb >= 2 else m.std / math.sqrt(m.n))
            nu_y.append(nb - 1 if nb >= 2 else max(m.n - 1, 1))
        u_y, nu_y = np.array(u_y), np.array(nu_y, dtype=float)
        tt = np.array([m.time_s for m in pts])
        a0 = a if test == "scale_factor" else _sf_runs(ctx, "scale_factor")[0]["a"]
        cw, ccw = x > 0, x < 0
        (u_a, nu_a), (u_cw, nu_cw), (u_ccw, nu_ccw) = (
            _slope_u(ctx, x[k], u_y[k], nu_y[k], tt[k], se * f, a0)
            for k, f in ((slice(None), 1.0), (cw, math.sqrt(2)), (ccw, math.sqrt(2))))
        out.append({"run": run, "x": x, "y": y, "a": a, "b": b, "se": se,
                    "u_a": u_a, "nu_a": nu_a, "u_a_cw": u_cw, "nu_a_cw": nu_cw,
                    "u_a_ccw": u_ccw, "nu_a_ccw": nu_ccw, "t": tt, "T": pts[0].temperature_c, "V": pts[0].supply_v, "u_y": u_y,
                    "n": np.array([m.n for m in pts])})
    ctx.cache[("sf", test)] = out
    return out


def _slope_u(ctx: Context, x: np.ndarray, u_y: np.ndarray, nu_y: np.ndarray, t: np.ndarray,
             se: float, a_guess: float) -> tuple[float, float]:
    """(u(a), ν) of a least-squares slope: the noise of its point means
    (:func:`slope_noise_u`, ν by :func:`slope_noise_dof` from each point's blocks) and the
    bias's drift between them (:func:`slope_drift_u`, from the static record's noise fit,
    taken as exact: that fit rests on the whole static record); without a static record the
    drift is not known and the fit's residual standard error ``se`` (an upper bound: it
    holds the nonlinearity too) is used instead, ν = points − 2. ``a_guess``: the scale
    factor that converts the drift to output units when a_BASE is not yet known (the slope
    being computed is a_BASE itself)."""
    try:
        base = ctx if ctx.a_base is not None else replace(ctx, a_base=a_guess)
        drift = slope_drift_u(x, t, lambda dt: drift_u_dps(base, dt) * abs(base.a_base))
    except (GonioError, IndexError, KeyError):
        return se, float(max(x.size - 2, 1))
    un = slope_noise_u(x, u_y)
    u = math.hypot(un, drift)
    nu = slope_noise_dof(x, u_y, nu_y) * (u / un) ** 4 if un > 0 else math.inf
    return u, nu


def _ws(us, nus) -> float:
    """ν_eff of a sum of independent terms (JCGM 100 G.4.1)."""
    return welch_satterthwaite(math.sqrt(sum(u * u for u in us)), us, nus)


def slope_noise_dof(x: np.ndarray, u_y: np.ndarray, nu_y: np.ndarray) -> float:
    """Welch–Satterthwaite degrees of freedom (JCGM 100 G.4.1) of :func:`slope_noise_u`:
    (Σ w_i² u_i²)² / Σ (w_i² u_i²)²/ν_i, ν_i = the blocks of point i less one (not a fixed
    ν = 50 whatever the points hold).

    >>> round(slope_noise_dof(np.array([-1.0, 0.0, 1.0]), np.array([0.1, 0.1, 0.1]),
    ...                       np.array([5.0, 5.0, 5.0])), 9)
    10.0
    """
    w = (x - x.mean()) / float(((x - x.mean()) ** 2).sum())
    c = w ** 2 * u_y ** 2                     # each point's variance contribution
    return welch_satterthwaite(math.sqrt(float(np.sum(c))), np.sqrt(c), nu_y)


def slope_drift_u(x: np.ndarray, t: np.ndarray, u_diff) -> float:
    """Standard uncertainty of a least-squares slope a = Σ w_i y_i from a drift d(t) of the
    bias while the points are taken: Σ w_i = 0, so var(Σ w_i d(t_i)) = −½ Σ_ij w_i w_j
    D(|t_i − t_j|) with D(τ) = E[(d(t + τ) − d(t))²] = ``u_diff``(τ)², the structure
    function of the drift (for stationary increments; Yaglom 1987). A drift linear in the
    points' order reads directly as a slope, which the noise of the point means misses.

    >>> round(slope_drift_u(np.array([-1.0, 1.0]), np.array([0.0, 10.0]), lambda dt: 0.1), 6)
    0.05
    """
    if x.size < 2:
        return math.nan
    w = (x - x.mean()) / float(((x - x.mean()) ** 2).sum())
    dt = np.abs(t[:, None] - t[None, :])
    d = np.vectorize(lambda v: u_diff(float(v)) ** 2 if v > 0 else 0.0)(dt)
    return math.sqrt(max(0.0, -0.5 * float(w @ d @ w)))


def slope_noise_u(x: np.ndarray, u_y: np.ndarray) -> float:
    """Standard uncertainty of a least-squares slope from the noise of its point means:
    a = Σ w_i y_i, w_i = (x_i − x̄)/Sxx, so u(a) = √(Σ w_i² u(y_i)²) (JCGM 100 eq. (10)).

    The slope's residual standard error √(RSS/(n − 2)/Sxx) is not used: the residuals of the
    2n + 1 points are mostly the gyro's nonlinearity, which the clause's a_BASE (a
    least-squares slope over those rates, by definition) contains and does not err by;
    on the bench it made U(a_BASE) ≈ 5× the spread (docs/iec62047-20-readings.md).

    >>> round(slope_noise_u(np.array([-1.0, 0.0, 1.0]), np.array([0.1, 0.1, 0.1])), 6)
    0.070711
    """
    if x.size < 2:
        return math.nan
    w = (x - x.mean()) / float(((x - x.mean()) ** 2).sum())
    return float(math.sqrt(float(np.sum(w ** 2 * u_y ** 2))))


def _u_rel_sf(ctx: Context, c: dict) -> list:
    return [from_u("a", c["a"], c["u_a"], dof=c["nu_a"],
                   source="least-squares slope, from the noise of the point means"),
            rate_table_line("e_table", ctx.rate_table_u_rel, "rate table, relative"),
            from_u("e_acq", 0.0, ctx.acquisition_u_rel, type="B", source="acquisition, relative"),
            type_b("e_TU", 0.0, gyro_temperature_bound_c(ctx)
                   * abs(chamber_coefficient(ctx.sf_tc_item).rel or 0.0),
                   "rectangular", source=TEMPERATURE_BOUND_SOURCE + " × T_c,SF/a of 5.1.3.4's "
                                                                    "runs (0 without them)")]


#: The source text of the gyro's temperature error at a chamber set point (the budgets' one
#: line for the chamber's deviation and the gyro's place in the volume).
TEMPERATURE_BOUND_SOURCE = rg.TEMPERATURE_BOUND_SOURCE


def gyro_temperature_bound_c(ctx) -> float:
    """:func:`gonio.specs._rate_family.formulas.gyro_temperature_bound_c` of the readings'
    stated chamber deviation bound and uniformity."""
    return rg.gyro_temperature_bound_c(ctx.chamber_deviation_c, ctx.chamber_uniformity_c)


@dataclass(frozen=True)
class ChamberCoefficient:
    """T_c,SF/a_BASE of 5.1.3.4 (1/°C) as every budget that needs it takes it
    (:func:`chamber_coefficient`): ``rel`` the estimate (the budgets' lines for the
    chamber's deviation and fluctuation), ``bound`` |rel| + U (the bound condition's e_TU),
    both None, with ``reason``, when 5.1.3.4 gives none."""

    rel: float | None
    bound: float | None
    reason: str = ""


def chamber_coefficient(tc: Item | None) -> ChamberCoefficient:
    """The one decision whether the chamber's temperature effect on the scale factor is
    bounded: from 5.1.3.4's item ``tc`` (:func:`sf_temperature`, computed once, before
    5.1.3.1, and handed to every item in the context, :func:`with_needs`), in one form, the
    item's 100·T_c,SF/a_BASE / 100, with its bound |T_c,SF/a_BASE| + U(T_c,SF/a_BASE) (its
    95 % interval's far end: the estimate alone is no bound). None (and why) when 5.1.3.4 is
    not measured (no runs, or the item refuses them), states no finite value or no
    uncertainty: the items of :data:`CHAMBER_ITEMS` then hold no term for it, which the
    calibration states as a finding naming each of them (:func:`chamber_effect_finding`,
    from this same None), never a silent 0.

    >>> chamber_coefficient(None).reason
    '5.1.3.4 not computed'
    """
    if tc is None:
        return ChamberCoefficient(None, None, "5.1.3.4 not computed")
    if not tc.measured or tc.value is None or not math.isfinite(tc.value):
        return ChamberCoefficient(None, None, tc.reason or "no finite value")
    unc = tc.uncertainty
    if unc is not None and unc.U is not None:
        reach = abs(tc.value) + float(unc.U)
    elif unc is not None and unc.interval is not None:
        reach = max(abs(float(e)) for e in unc.interval)
    else:
        return ChamberCoefficient(None, None, "5.1.3.4 states no uncertainty")
    return ChamberCoefficient(tc.value / 100.0, reach / 100.0)   # the item is in %/°C


#: The finding of an IEC calibration whose scale-factor items lack the chamber's term.
CHAMBER_EFFECT_UNBOUNDED_CODE = "chamber-effect-unbounded"

#: The items whose budgets take 5.1.3.4's coefficient (:func:`chamber_coefficient`) and
#: hold no term for the chamber without it: a_BASE and 5.1.3.2 (the gyro's temperature
#: error at T_BASE, e_TU), 5.1.3.5 and 5.1.3.6 (the chamber's fluctuation between the supply
#: runs, between the points). 5.1.3.8 takes the fits' residual standard error instead (an
#: upper bound that holds the fluctuation too), so it is not among them.
CHAMBER_ITEMS = ("scale_factor", "initial_sf_variation", "ratiometric_error", "linearity")


def chamber_effect_finding(items: dict, chamber_bound_c: float):
    """A flagged finding where 5.1.3.4 gives no coefficient (:func:`chamber_coefficient`
    None, the same decision the budgets took) and items of :data:`CHAMBER_ITEMS` are
    measured: it names each of them, their intervals stated without the chamber's term
    (the gyro's temperature error at T_BASE, ± ``chamber_bound_c``: the chamber's deviation
    and its place in the volume; its fluctuation between the points), and that the items
    divided by a_BASE take its u without it (a share below 0.1 % of their U on the small
    programme: not named one by one); None otherwise."""
    from gonio.result.findings import Finding

    cc = chamber_coefficient(items.get("sf_temperature_coefficient"))
    hit = [items[k].clause for k in CHAMBER_ITEMS if k in items and items[k].measured]
    if cc.bound is not None or not hit:
        return None
    return Finding(CHAMBER_EFFECT_UNBOUNDED_CODE,
                   f"the chamber's temperature effect on the scale factor is not bounded: the "
                   f"scale-factor temperature coefficient of 5.1.3.4 is not measured "
                   f"({cc.reason}), so the intervals of {', '.join(hit)} are stated without a "
                   f"term for it (the gyro's temperature error at T_BASE, ± "
                   f"{chamber_bound_c:g} °C: the chamber's deviation and its place in the "
                   f"volume; the chamber's fluctuation between the points), nor do the items "
                   f"divided by a_BASE through its u — measure 5.1.3.4 or state the "
                   f"coefficient's bound", "flagged", clause="5.1.3.1",
                   rule="the scale-factor items' chamber term bounded by 5.1.3.4's T_c,SF")


#: The finding of an IEC calibration whose bias items lack the gyro's temperature error.
BIAS_TEMPERATURE_UNBOUNDED_CODE = "bias-temperature-unbounded"

#: The items whose bound condition takes 5.3.3.6's coefficient for the gyro's temperature
#: error at T_BASE (e_TU, :func:`bias_tc_bound_dps_per_c`), 0 without it.
BIAS_TEMPERATURE_ITEMS = ("bias", "initial_bias_variation")


def bias_temperature_finding(items: dict, chamber_bound_c: float):
    """A flagged finding where 5.3.3.6 gives no coefficient (not measured or not in the
    readings: :func:`bias_tc_bound_dps_per_c` then 0, the same decision the budgets took) and
    items of :data:`BIAS_TEMPERATURE_ITEMS` are measured: it names each of them, their
    intervals stated without the gyro's temperature error at T_BASE (± ``chamber_bound_c``:
    the chamber's deviation and its place in the volume) times the bias's temperature
    coefficient; None otherwise."""
    from gonio.result.findings import Finding

    tc = items.get("bias_temperature_coefficient")
    hit = [items[k].clause for k in BIAS_TEMPERATURE_ITEMS if k in items and items[k].measured]
    if (tc is not None and tc.measured) or not hit:
        return None
    why = (tc.reason if tc is not None and tc.reason else "the readings hold no 5.3.3.6 visits")
    return Finding(BIAS_TEMPERATURE_UNBOUNDED_CODE,
                   f"the chamber's temperature effect on the bias is not bounded: the bias "
                   f"temperature coefficient of 5.3.3.6 is not measured ({why}), so the "
                   f"intervals of {', '.join(hit)} are stated without a term for it (the "
                   f"gyro's temperature error at T_BASE, ± {chamber_bound_c:g} °C: the "
                   f"chamber's deviation and its place in the volume) — measure 5.3.3.6 or "
                   f"state the coefficient's bound", "flagged", clause="5.3.3.1",
                   rule="the bias items' temperature term bounded by 5.3.3.6's β")


#: The code of :func:`noise_temperature_finding`.
NOISE_TEMPERATURE_CODE = "noise-temperature-not-bounded"

#: The noise items stated at the static record's temperature: their budget line for the
#: gyro's temperature error at T_BASE (:func:`noise_temperature_line`) needs the 5.3.3.6
#: visits; without them the finding (:func:`noise_temperature_finding`).
NOISE_ITEMS = ("arw", "inband_noise", "broadband_noise")


def static_record_temperature_c(df: pd.DataFrame) -> float | None:
    """The static record's temperature (°C) as the readings state it (its rows'
    ``temperature_c``, their median); None where the readings carry no such column."""
    from gonio.analysis.noise.stream import rows_where
    if "temperature_c" not in df.columns:
        return None
    first, count, idx = rows_where(df, lambda d: (d["test"] == "static") & (d["run"] == 0)
                                   & (d["step"] == 0))
    if count == 0:
        return None
    col = df["temperature_c"].to_numpy()
    t = col[first:first + count] if idx is None else col[idx]
    t = np.asarray(t, float)
    t = t[np.isfinite(t)]
    return float(np.median(t)) if t.size else None


def has_noise_temperature_line(item) -> bool:
    """Whether a noise item's budget carries :func:`noise_temperature_line` (``dT_noise``)."""
    u = getattr(item, "uncertainty", None)
    return any(c.get("symbol") == "dT_noise" for c in (getattr(u, "components", None) or ()))


def noise_temperature_finding(items: dict, record_c: float | None, bound_c: float):
    """A flagged finding where any of :data:`NOISE_ITEMS` is measured without a temperature
    line (:func:`has_noise_temperature_line`): the noise items
    (5.4.5.2, 5.4.5.1 b), c)) are stated at the gyro's temperature during the static record
    (``record_c``, the readings' ``temperature_c``), which the chamber holds within
    ± ``bound_c`` (:func:`gyro_temperature_bound_c`: its deviation bound and the gyro's
    place in the volume, Table 2), not at T_BASE: the white level moves with temperature
    and the readings give no coefficient for it (no 5.3.3.6 visits at two temperatures:
    :func:`noise_temperature_coefficient` is None; with them the items carry
    :func:`noise_temperature_line` and are not named), so their intervals carry no term
    for it."""
    from gonio.result.findings import Finding

    hit = [items[k].clause for k in NOISE_ITEMS if k in items and items[k].measured
           and not has_noise_temperature_line(items[k])]
    if not hit:
        return None
    at = "its stated temperature" if record_c is None else f"{record_c:g} °C"
    return Finding(NOISE_TEMPERATURE_CODE,
                   f"the noise items {', '.join(hit)} hold at the gyro's temperature during "
                   f"the static record ({at}, the readings' temperature_c, with the gyro "
                   f"within ± {bound_c:g} °C of it: the chamber's deviation and its place in "
                   f"the volume), not at T_BASE: their intervals carry no term for the "
                   f"noise's temperature dependence (the readings hold no 5.3.3.6 visits at "
                   f"two temperatures, which give its coefficient)",
                   "flagged", test="static", column="temperature_c", clause="5.4.5",
                   rule="the noise items at the static record's temperature")


@dataclass(frozen=True)
class NoiseTemperatureCoefficient:
    """The relative temperature coefficient of the gyro's white noise level (1/°C) from the
    5.3.3.6 visits (:func:`noise_temperature_coefficient`): ``value`` the weighted
    least-squares slope of ln σ_i against T_i, ``u`` its standard uncertainty, ``nu`` its
    Welch–Satterthwaite ν, ``visits`` how many records; ``rms`` √(value² + u²), the
    coefficient's magnitude a GUM line takes for a product with a zero-mean temperature
    error (JCGM 100 5.1.2 to second order: u²(cΔT) = (c² + u²(c))·u²(ΔT))."""

    value: float
    u: float
    nu: float
    visits: int

    @property
    def rms(self) -> float:
        return math.hypot(self.value, self.u)

    @property
    def bound(self) -> float:
        """|c| + U(c), U(c) = t_95(ν)·u (the far end of the coefficient's 95 % interval): the
        coefficient's bound the noise items' bound condition takes, as the bias's takes
        |β| + U(β) (:func:`bias_tc_bound_dps_per_c`)."""
        from gonio.result.statement import coverage_k
        return abs(self.value) + coverage_k(self.nu, 0.95) * self.u


def noise_temperature_coefficient(ctx: Context) -> NoiseTemperatureCoefficient | None:
    """The white noise level's relative temperature coefficient from the 5.3.3.6 visits'
    records (IEC 62047-20 5.3.3.6 takes them at m + 1 temperatures for the bias; their
    sample-to-sample scatter is the gyro's white noise at each temperature): per visit
    σ_i = sd(first differences)/√2 of its output in °/s (divided by a(T_i) of 5.1.3.4 where
    measured at that temperature, else a_BASE — the output's noise scales with K too), which
    drops the bias's slow drift and settling; the slope c of ln σ_i against T_i by weighted
    least squares, each ln σ_i of variance 3/(4n_i) (the sample variance of n differences
    of white noise: var(s²_d)/E[s²_d]² = 3/n, the lag-one correlation −½ counted), ν_i =
    2n_i/3, ν of c by Welch–Satterthwaite (JCGM 100 G.4.1). Reading taken (the standard
    states no noise coefficient; docs/iec62047-20-readings.md): the white level's
    coefficient stands for the noise items' (5.4.5.2 is the white level; 5.4.5.1 b), c)
    are mostly white on a rate gyro). None where the readings hold no visits at two
    stated temperatures (a visit whose temperature_c is not stated is left out) or no
    a_BASE: the noise items then carry the finding
    (:func:`noise_temperature_finding`)."""
    key = ("noise_tc", ctx.a_base)
    if key in ctx.cache:
        return ctx.cache[key]
    out = None
    if ctx.has("bias_temperature") and ctx.a_base is not None:
        kmap = {round(c["T"], 6): c["a"] for c in _sf_runs(ctx, "sf_temperature")} \
            if ctx.has("sf_temperature") else {}
        T, ln_s, var, nus = [], [], [], []
        for s in segment_means(ctx.df, "bias_temperature"):
            if not math.isfinite(s.temperature_c):      # a visit at no stated temperature
                continue
            y = segment_samples(ctx.df, "bias_temperature", s.run, s.step)["output"].to_numpy()
            d = np.diff(y.astype(float))
            d = d[np.isfinite(d)]
            if d.size < 10:
                continue
            sd = float(np.std(d, ddof=1)) / math.sqrt(2.0) / abs(kmap.get(round(s.temperature_c, 6), ctx.a_base))
            if not sd > 0:
                continue
            T.append(s.temperature_c)
            ln_s.append(math.log(sd))
            var.append(3.0 / (4.0 * d.size))
            nus.append(2.0 * d.size / 3.0)
        if len(set(T)) >= 2:
            T, ln_s, w = np.array(T), np.array(ln_s), 1.0 / np.array(var)
            tm = float((w * T).sum() / w.sum())
            sxx = float((w * (T - tm) ** 2).sum())
            c = float((w * (T - tm) * ln_s).sum()) / sxx
            parts = w * (T - tm) / sxx * np.sqrt(np.array(var))    # each visit's share of u(c)
            u = math.sqrt(1.0 / sxx)
            nu = welch_satterthwaite(u, list(parts), nus)
            if math.isfinite(c) and math.isfinite(u):
                out = NoiseTemperatureCoefficient(c, u, nu, len(T))
    ctx.cache[key] = out
    return out


#: The source of the noise items' temperature line (en; the zh certificate translates it).
NOISE_TEMPERATURE_SOURCE = ("the gyro's temperature during the static record against T_BASE "
                            "(± the chamber's deviation and place bounds, and the record's "
                            "logged offset) × the white level's coefficient from the 5.3.3.6 "
                            "visits, √(c² + u²(c))")


def noise_record_offset_c(ctx: Context, record_c: float | None) -> float:
    """ΔT (°C), the bound of the gyro's temperature during the static record against T_BASE:
    :func:`gyro_temperature_bound_c` (the chamber's deviation and the gyro's place, added)
    + |record_c − T_BASE| (the record's logged temperature, where the readings hold it; 0
    where not)."""
    return gyro_temperature_bound_c(ctx) + (abs(record_c - ctx.t_base_c) if record_c is not None
                                            and math.isfinite(record_c) else 0.0)


def noise_temperature_line(ctx: Context, value: float, record_c: float | None):
    """The noise items' line (rectangular, the item's unit) for the gyro's temperature during
    the static record against T_BASE, or None where :func:`noise_temperature_coefficient`
    gives no coefficient (the finding then says so): half-width value·√(c² + u²(c))·ΔT
    (the product of the uncertain coefficient and the zero-mean temperature error, JCGM 100
    5.1.2 to second order) with ΔT = :func:`noise_record_offset_c` — the chamber's deviation
    and the gyro's place added linearly into one rectangular, as every chamber line of the
    rate specifications takes them. A GUM line, for u_c (beside the statement); the statement
    holds the same error at its bound (:func:`noise_temperature_bound_rel`)."""
    tc = noise_temperature_coefficient(ctx)
    if tc is None:
        return None
    return type_b("dT_noise", 0.0, abs(value) * tc.rms * noise_record_offset_c(ctx, record_c),
                  "rectangular", source=NOISE_TEMPERATURE_SOURCE)


def noise_temperature_bound_rel(ctx: Context, record_c: float | None) -> float | None:
    """The bound g of the relative error of the noise items' reading from the gyro's
    temperature during the static record: (|c| + U(c))·ΔT
    (:attr:`NoiseTemperatureCoefficient.bound`, :func:`noise_record_offset_c`). The white
    level at T_BASE + δ is σ·exp(c·δ) ≥ σ·(1 − |c|·|δ|) (c the slope of ln σ against T), so
    a reading at any temperature within ΔT is at least σ·(1 − g): the factor the noise items'
    bound condition takes (:func:`noise_statement`); None without a coefficient."""
    tc = noise_temperature_coefficient(ctx)
    if tc is None:
        return None
    return tc.bound * noise_record_offset_c(ctx, record_c)


#: What the noise items keep in ``details.bound_condition.basis``.
NOISE_BOUND_BASIS = (
    "bound condition: the gyro's temperature during the static record at the chamber's "
    "deviation and place bounds (Table 2) plus the record's logged offset from T_BASE, ΔT, "
    "times |c| + U(c) of the white level's coefficient from the 5.3.3.6 visits, g, the "
    "reading's relative error at its bound with the sign that lowers it; and the one-sided "
    "χ² 95 % limit of the other lines, ν_rest = ½(s/u_rest)² (JCGM 100 4.3.7, E.4.3): "
    "[0, (s + R)/(1 − g)] = [0, s + a + R], which holds at least 95 % at every temperature "
    "within the bounds")


def noise_statement(ctx: Context, value: float, u):
    """The one statement of a noise item (5.4.5.2, 5.4.5.1 b), c)) from its budget ``u``
    (its lines and :func:`noise_temperature_line`): with the 5.3.3.6 visits' coefficient, the
    one-sided bound condition of the gyro's temperature during the static record
    (:func:`gonio.result.gum.dispersion_bound_statement` with ``dT_noise`` at
    :func:`noise_temperature_bound_rel`: Table 2 lets the chamber sit at its bound for the whole
    record, the gyro cold, the white level low; the GUM line alone covered 5 of 8 such
    trials); without one, the χ² statement (:func:`gonio.result.gum.dispersion_uncertainty`,
    and the finding :func:`noise_temperature_finding`). Returns (uncertainty, the bound
    condition's parts for ``details.bound_condition`` or {})."""
    g = None if noise_temperature_coefficient(ctx) is None else \
        noise_temperature_bound_rel(ctx, _static_record_c(ctx))
    if not g:
        return dispersion_uncertainty(value, u), {}
    return dispersion_bound_statement(value, u, {"dT_noise": g}, basis=NOISE_BOUND_BASIS)


def scale_factor(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.1 eqs (1), (2): a_BASE, least squares over the 2n + 1 points (rest
    included) at T_BASE, V_BASE. Budget (:func:`_u_rel_sf`): the slope's noise and drift,
    the rate table and the voltmeter (relative), and the gyro's temperature error at T_BASE
    (:func:`gyro_temperature_bound_c`: the chamber's deviation and the gyro's place in its
    volume, bounds added) times T_c,SF/a (:func:`chamber_coefficient`). Stated by the bound
    condition (:func:`_bound_statement`: e_TU, and the table where no certificate u is
    stated)."""
    t, cl, un = "scale factor a_BASE", "5.1.3.1", f"{ctx.output_unit}/(°/s)"
    m = _miss(ctx, "scale_factor", "scale_factor", t, cl, un, need_a=False)
    if m:
        return m
    c = _sf_runs(ctx, "scale_factor")[0]
    u = gum(lambda a, et, ea, eTU: a * (1 + ea) * (1 + eTU) / (1 + et), _u_rel_sf(ctx, c))
    u, bc = _bound_statement(ctx, u, c["a"])
    return Item("scale_factor", t, cl, un, c["a"], uncertainty=u,
                details={"b_BASE": c["b"], "x_dps": c["x"], "y": c["y"],
                         **({"bound_condition": bc} if bc else {})})


def _bound_statement(ctx: Context, u, value: float):
    """The statement of an item with :func:`_u_rel_sf`'s budget, by the bound condition
    (:func:`gonio.specs._rate_family.rate_records.table_bound_statement`): the gyro's
    temperature error at T_BASE (e_TU: the chamber's bound × :func:`chamber_coefficient`'s
    bound, |T_c,SF/a| + its U) is a bound the procedure allows (the chamber anywhere within its
    deviation and uniformity, Table 2), so it is added linearly, not as a rectangular line
    (which covers as little as 84 % with the chamber at its bound); where the readings state
    no certificate u for the rate table, the table's bound (e_table) is added with it. With
    the table's u stated and e_TU 0 (5.1.3.4 not measured, which the calibration states as
    a finding, :func:`chamber_effect_finding`) the GUM budget's U = k·u_c."""
    tc_bound = chamber_coefficient(ctx.sf_tc_item).bound
    return table_bound_statement(u, value, ctx.rate_table_u_rel, {
        "e_table": TABLE2_RATE_ACCURACY_REL,
        "e_TU": gyro_temperature_bound_c(ctx) * (tc_bound or 0.0)})


def initial_sf_variation(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.2 eq (3): (a_BASE − a_TYP)/a_TYP, in %."""
    t, cl, un = "initial scale-factor variation", "5.1.3.2", "%"
    m = _miss(ctx, "scale_factor", "initial_sf_variation", t, cl, un)
    if m:
        return m
    c = _sf_runs(ctx, "scale_factor")[0]
    ins = _u_rel_sf(ctx, c)
    u = gum(lambda a, et, ea, eTU: 100 * (a * (1 + ea) * (1 + eTU) / (1 + et)
                                          - ctx.a_typ) / ctx.a_typ, ins)
    value = 100 * (c["a"] - ctx.a_typ) / ctx.a_typ
    u, bc = _bound_statement(ctx, u, value)
    return Item("initial_sf_variation", t, cl, un, value, uncertainty=u,
                details={"a_TYP": ctx.a_typ, **({"bound_condition": bc} if bc else {})})


def linearity(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.6 eqs (8), (9): L_i = [y_i − (a x_i + b)]/FullScale per point,
    FullScale = y(CW max) − y(CCW max) measured; the characteristic max |L_i|, in %.

    A magnitude, stated by one interval: that of the extreme of magnitudes over the signed
    points L_i (:func:`gonio.result.gum.max_magnitude_statement`, ≥ 95 % for every pattern
    of the true L_i and any correlation between them), each point with its own budget — the
    pooled noise of the point means through the line's residual / FullScale
    (:func:`linearity_noise_sd`), the bias drift between the points (:func:`linearity_drift_sd`,
    from the static record's noise fit) and the chamber's fluctuation × T_c,SF
    (:func:`linearity_fluctuation_sd`; none where 5.1.3.4 gives no coefficient,
    :func:`chamber_coefficient`, the item then named in its finding). The value is the
    reading less the selection midpoint (the largest of noisy |L_i| is raised by noise), within the interval; the
    standard's reading max |L_i| is kept in the details (``max_abs_L_i_pct``), and the
    GUM budget of the value at the largest point (its linearisation, value ± U, reached
    below zero for a linear gyro) stays in the budget table only."""
    t, cl, un = "linearity (max |L_i|)", "5.1.3.6", "%"
    m = _miss(ctx, "scale_factor", "linearity", t, cl, un)
    if m:
        return m
    c = _sf_runs(ctx, "scale_factor")[0]
    L, a, b, fs = ief.linearity_errors_iec(c["x"], c["y"])
    u_pool = np.full(c["x"].size, float(np.sqrt(np.mean(c["u_y"] ** 2))))   # ν ≈ Σ ν_i
    sd = 100 * linearity_noise_sd(c["x"], L, fs, u_pool)
    i = int(np.argmax(np.abs(L)))
    excess, m_sel = rg.selection_excess(100 * np.abs(L), sd)
    extra, u_dr, u_fl = {}, None, None
    try:        # the bias's drift between the points, from the static record's noise fit
        u_dr = 100 * linearity_drift_sd(
            c["x"], c["t"], fs, lambda dt: drift_u_dps(ctx, dt) * abs(ctx.a_base))
        extra["u_drift_pct"] = float(u_dr[i])
    except (GonioError, IndexError, KeyError):
        pass                            # no static record: the drift is not known
    k_rel = chamber_coefficient(ctx.sf_tc_item).rel
    if k_rel is not None:       # T_c,SF known: the chamber's fluctuation moves K
        u_fl = 100 * linearity_fluctuation_sd(
            c["x"], c["t"], fs, ctx.a_base, k_rel * ctx.chamber_fluctuation_c,
            ctx.chamber_fluctuation_period_s)
        extra["u_fluctuation_pct"] = float(u_fl[i])

    def terms(j, v0):       # the budget of point j's L_j (in %) about v0
        out = [from_u("L", v0, 0.0),
               from_u("noise", 0.0, float(sd[j]), dof=DOF_U_WITHIN_10PCT,
                      source="pooled noise of the point means through the line's residual / "
                             "FullScale")]
        if u_dr is not None:
            out.append(from_u("drift", 0.0, float(u_dr[j]), type="B",
                              source="bias drift between the points through the line's "
                                     "residual / FullScale (static record's noise fit)"))
        if u_fl is not None:
            out.append(from_u("fluct", 0.0, float(u_fl[j]), type="B",
                              source="chamber fluctuation (± amplitude, period) × T_c,SF "
                                     "through the line's residual / FullScale"))
        return out

    u = gum(lambda v, *e: v + sum(e), terms(i, 100 * abs(L[i])) + [
        type_b("noise_max", -excess, excess, "rectangular",
               source="selection excess of the largest |L_i| (midpoint ± c_m·σ/2 removed)")])
    pts = [gum(lambda v, *e: v + sum(e), terms(j, 100 * float(L[j]))) for j in range(L.size)]
    value, u, iv = max_magnitude_statement(u, 100 * L, pts, 100 * abs(float(L[i])) - excess)
    return Item("linearity", t, cl, un, value, uncertainty=u, details={
        "L_i_pct": 100 * L, "x_dps": c["x"], "full_scale": fs, "at_dps": float(c["x"][i]),
        "selection_contenders": m_sel, "max_abs_L_i_pct": 100 * abs(float(L[i])),
        "selection_midpoint_pct": excess, **extra, **iv})


def _residual_maker(x: np.ndarray) -> np.ndarray:
    """I − H of the least-squares line y = a·x + b over the points x (H its hat matrix)."""
    X = np.column_stack([np.ones_like(x), x])
    return np.eye(x.size) - X @ np.linalg.solve(X.T @ X, X.T)


def linearity_drift_sd(x: np.ndarray, t: np.ndarray, fs: float, u_diff) -> np.ndarray:
    """Standard deviation of each L_i of 5.1.3.6 eq (8) from a drift d(t) of the bias while
    the points are taken (point i at time t_i): r = (I − H)(y + d) and each row of I − H sums
    to 0, so var(r_i) = −½ Σ_jk M_ij M_ik D(|t_j − t_k|), M = I − H, D(τ) = ``u_diff``(τ)²
    the drift's structure function (as :func:`slope_drift_u`); sd_i = √var(r_i)/|FullScale|.
    A drift constant in τ (D ≡ u²) acts as extra independent noise of variance u²/2 per point.

    >>> x = np.array([-1.0, 0.0, 1.0])
    >>> [round(float(v), 6) for v in linearity_drift_sd(x, np.arange(3.0), 1.0, lambda dt: 0.1)]
    [0.028868, 0.057735, 0.028868]
    """
    M = _residual_maker(x)
    dt = np.abs(t[:, None] - t[None, :])
    d = np.vectorize(lambda v: u_diff(float(v)) ** 2 if v > 0 else 0.0)(dt)
    var = -0.5 * np.einsum("ij,ik,jk->i", M, M, d)
    return np.sqrt(np.maximum(var, 0.0)) / abs(fs)


def linearity_fluctuation_sd(x: np.ndarray, t: np.ndarray, fs: float, a: float,
                             amp_rel: float, period_s: float | None) -> np.ndarray:
    """Standard deviation of each L_i of 5.1.3.6 eq (8) from the chamber's periodic
    fluctuation moving K by T_c,SF while the points are taken: y_j gains a·x_j·A·sin(ωt_j + φ)
    (A = ``amp_rel``, T_c,SF/a times the fluctuation's amplitude, ω = 2π/P), so r_i gains
    a·A·Im(e^{iφ} Z_i), Z_i = Σ_j M_ij x_j e^{iωt_j} (M = I − H), of standard deviation
    |a·A·Z_i|/√2 for φ unknown (uniform); sd_i = that /|FullScale|. The readings log the set
    point, not the chamber's temperature, so it cannot be corrected. Period not stated: the
    bound |Z_i| ≤ Σ_j |M_ij x_j|.

    >>> x = np.array([-1.0, 0.0, 1.0])
    >>> [round(float(v), 6) for v in linearity_fluctuation_sd(x, np.arange(3.0), 1.0, 1.0, 1e-3, None)]
    [0.000236, 0.000471, 0.000236]
    """
    M = _residual_maker(x)
    if period_s:
        mag = np.abs(M @ (x * np.exp(2j * math.pi * t / period_s)))
    else:
        mag = np.abs(M) @ np.abs(x)
    return abs(a * amp_rel) * mag / math.sqrt(2.0) / abs(fs)


def linearity_noise_sd(x: np.ndarray, L: np.ndarray, fs: float, u_y: np.ndarray) -> np.ndarray:
    """Standard deviation of each L_i = r_i/FullScale of 5.1.3.6 eq (8) from the point means'
    independent noise u_y: r = (I − H)y with H the straight line's hat matrix and FullScale =
    y(CW max) − y(CCW max), so ∂L_i/∂y_j = [(I − H)_ij − L_i(δ_j,CW − δ_j,CCW)]/FullScale and
    sd_i = √(Σ_j (∂L_i/∂y_j)² u_j²). A residual moves by √(1 − h_ii)·u, less than u."""
    X = np.column_stack([np.ones_like(x), x])
    M = np.eye(x.size) - X @ np.linalg.solve(X.T @ X, X.T)
    G = M.copy()
    hi, lo = int(np.argmax(x)), int(np.argmin(x))
    G[:, hi] -= L * np.sign(fs)
    G[:, lo] += L * np.sign(fs)
    return np.sqrt((G / fs) ** 2 @ (np.asarray(u_y, float) ** 2))


def symmetry(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.8 eqs (13)–(17): (a_CW − a_CCW)/a_TYP from separate fits without the
    rest point, signed, in %. Budget: the two slopes' noise of the point means and bias
    drift, and the chamber's temperature fluctuation moving K by T_c,SF between the CW and
    CCW points (:func:`fluctuation_u_rel`; amplitude and period from the readings'
    metadata, JJF Table 2's ±1 °C and a bound over any period when absent); without the
    5.1.3.4 runs (T_c,SF unknown) the fits' residual standard error instead."""
    t, cl, un = "scale-factor symmetry", "5.1.3.8", "%"
    m = _miss(ctx, "scale_factor", "symmetry", t, cl, un)
    if m:
        return m
    c = _sf_runs(ctx, "scale_factor")[0]
    s, aw, bw, ac, bc = ief.symmetry_iec(c["x"], c["y"], ctx.a_typ)
    k_rel = chamber_coefficient(ctx.sf_tc_item).rel
    if k_rel is not None and math.isfinite(c["u_a_cw"]) and math.isfinite(c["u_a_ccw"]):
        # the two slopes' noise and drift, and the chamber's fluctuation moving K between
        # the CW and the CCW points (:func:`fluctuation_u_rel`)
        u_fl = fluctuation_u_rel(c["x"], c["t"], k_rel * ctx.chamber_fluctuation_c,
                                 ctx.chamber_fluctuation_period_s) * abs(ctx.a_base)
        u = gum(lambda d, f: 100 * (d + f) / ctx.a_typ, [
            from_u("a_CW-a_CCW", aw - ac, math.hypot(c["u_a_cw"], c["u_a_ccw"]),
                   dof=_ws((c["u_a_cw"], c["u_a_ccw"]), (c["nu_a_cw"], c["nu_a_ccw"])),
                   source="the two slopes' noise of the point means and bias drift"),
            from_u("fluct", 0.0, u_fl, type="B",
                   source="chamber fluctuation (± amplitude, period) × T_c,SF between the "
                          "CW and CCW points")])
    else:
        # without 5.1.3.4's runs T_c,SF is not known: the residual standard error (an
        # upper bound that holds the fluctuation too)
        u_dir = c["se"] * math.sqrt(2.0) * 2.0   # each direction's slope: ~2× the full fit's se
        u = gum(lambda d: 100 * d / ctx.a_typ, [
            from_u("a_CW-a_CCW", aw - ac, u_dir, dof=2 * len(c["x"]) // 2 - 4,
                   source="slope standard errors of the two fits")])
    return Item("symmetry", t, cl, un, 100 * s, uncertainty=u, details={
        "a_CW": aw, "b_CW": bw, "a_CCW": ac, "b_CCW": bc})


def _fluctuation_phasor(x: np.ndarray, t: np.ndarray, period_s: float | None) -> tuple[complex, float]:
    """(Z, B) of one least-squares slope through the points (x_i, t_i) under a periodic
    fluctuation of K, K(t) = K̄(1 + A sin(2πt/P + φ)): the slope is K̄(1 + A·Im(e^{iφ}Z))
    with Z = Σ v_i e^{iωt_i}, v_i = (x_i − x̄)x_i/Sxx (Σ v_i = 1), ω = 2π/P; B = Σ|v_i|
    bounds |Z| over any period (Z = 0 when ``period_s`` is None). NaN when fewer than two
    points.

    >>> z, b = _fluctuation_phasor(np.array([1.0, 2.0]), np.array([0.0, 1.0]), None)
    >>> z, b
    (0j, 3.0)
    """
    if x.size < 2:
        return complex(math.nan, math.nan), math.nan
    v = (x - x.mean()) * x / float(((x - x.mean()) ** 2).sum())
    z = complex(np.sum(v * np.exp(2j * math.pi * t / period_s))) if period_s else 0j
    return z, float(np.abs(v).sum())


def _fluctuation_u(parts: list[tuple[complex, float]], amp_rel: float,
                   period_s: float | None) -> float:
    """A|Σ ± Z|/√2 of slopes combined with signs (their Z already signed), φ uniform
    (Im(e^{iφ}Z) has standard deviation |Z|/√2); A·Σ B/√2 when the period is not stated."""
    mag = abs(sum(z for z, _ in parts)) if period_s else sum(b for _, b in parts)
    return abs(amp_rel) * mag / math.sqrt(2.0)


def fluctuation_u_rel(x: np.ndarray, t: np.ndarray, amp_rel: float,
                      period_s: float | None) -> float:
    """Relative standard uncertainty of a_CW − a_CCW (5.1.3.8) from a periodic fluctuation
    of K, K(t) = K̄(1 + A sin(2πt/P + φ)), φ unknown (uniform): each half's slope is
    K̄(1 + Σ v_i A sin(ωt_i + φ)) with v_i = (x_i − x̄)x_i/Sxx (Σ v_i = 1, the points of
    that half; :func:`_fluctuation_phasor`), so the difference is A·Im(e^{iφ} Z), Z =
    Σ_CW v_i e^{iωt_i} − Σ_CCW v_j e^{iωt_j}, of standard deviation A|Z|/√2. ``amp_rel`` = A
    (T_c,SF/a times the chamber's fluctuation amplitude); ``period_s`` None: the period is
    not stated and |Z| is bounded by Σ|v_CW| + Σ|v_CCW|.

    >>> round(fluctuation_u_rel(np.array([-2.0, -1.0, 1.0, 2.0]), np.array([0.0, 1.0, 2.0, 3.0]),
    ...                         1e-4, None), 9)
    0.000424264
    """
    parts = []
    for half, sign in ((x > 0, 1.0), (x < 0, -1.0)):
        z, b = _fluctuation_phasor(x[half], t[half], period_s)
        if not math.isfinite(b):
            return math.nan
        parts.append((sign * z, b))
    return _fluctuation_u(parts, amp_rel, period_s)


def fluctuation_ratio_u_rel(x_i: np.ndarray, t_i: np.ndarray, x_b: np.ndarray,
                            t_b: np.ndarray, amp_rel: float, period_s: float | None) -> float:
    """Relative standard uncertainty of the ratio a_i/a_b of two scale-factor runs made one
    after the other at the same set temperature (5.1.3.5: a_Vi over a_BASE) from the
    chamber's periodic fluctuation moving K by T_c,SF during each: a_i/a_b = (K̄_i/K̄_b)·
    (1 + A·Im(e^{iφ}(Z_i − Z_b))) to first order in A (:func:`_fluctuation_phasor` for each
    run's Z), φ unknown (uniform), so the standard deviation is A|Z_i − Z_b|/√2; without a
    stated period the bound A(B_i + B_b)/√2. The readings log the set point, not the
    chamber's temperature, so the fluctuation cannot be corrected: it is budgeted.

    >>> x = np.array([-2.0, -1.0, 0.0, 1.0, 2.0])
    >>> round(fluctuation_ratio_u_rel(x, np.arange(5.0), x, np.arange(5.0) + 5, 1e-4, None), 9)
    0.000141421
    >>> fluctuation_ratio_u_rel(x, np.arange(5.0), x, np.arange(5.0) + 900, 1e-4, 900.0) < 1e-18
    True
    """
    zi, bi = _fluctuation_phasor(x_i, t_i, period_s)
    zb, bb = _fluctuation_phasor(x_b, t_b, period_s)
    if not (math.isfinite(bi) and math.isfinite(bb)):
        return math.nan
    return _fluctuation_u([(zi, bi), (-zb, bb)], amp_rel, period_s)


def sf_stability(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.7 eqs (10)–(12): δ_i = population std of s samples at a constant
    rate / FullScale (rest skipped); the standard's reading is the largest δ_i (kept in the
    details, ``reading_max_delta``, labelled "reading taken").

    The value stated is the physically right estimate beside it, the largest TRUE spread
    max σ_i (the bench's truth: √E[population variance] at each rate): the reading less
    the bias of a maximum of noisy spreads (each δ_i = σ_i·√(χ²_ν/ν), ν = s − 1), by
    :func:`gonio.specs.iec62047_20.formulas.max_spread_estimate` — the midpoint of the
    bias's range between Jensen's alone (one rate's spread stands clear) and the full
    selection excess of the contending rates (they share the largest), that range
    rectangular in the budget (the correction's own uncertainty) — and stated by its ONE
    95 % interval (no k, no ν): the test inversion of the spreads' own scaled-χ
    distribution (:func:`gonio.specs.iec62047_20.formulas.max_spread_bounds`; its level at
    a given max σ_i, ``level_z_grid`` in the details, is what a study judges). u_c: the
    largest spread's own sampling spread and the correction's. A noise-free bench (static record without variation): no correction."""
    t, cl, un = "scale-factor stability (max σ_i)", "5.1.3.7", "1"
    m = _miss(ctx, "scale_factor", "sf_stability", t, cl, un)
    if m:
        return m
    fs = ief.linearity_errors_iec(*(_sf_runs(ctx, "scale_factor")[0][k] for k in ("x", "y")))[3]
    d = ctx.df[(ctx.df["test"] == "scale_factor") & (ctx.df["run"] == 1)]
    if d.empty:
        return not_measured("sf_stability", t, cl, un, "no constant-rate records (run 1)")
    deltas, sizes = {}, {}
    for step, g in d.groupby("step"):
        y = g["output"].to_numpy()
        w = float(g["rate_dps"].iloc[0])
        deltas[w] = float(np.std(y, ddof=0) / fs)
        sizes[w] = y.size
    if min(sizes.values()) < 2:
        return not_measured("sf_stability", t, cl, un,
                            "a constant-rate record of fewer than 2 samples")
    r = max(deltas, key=deltas.get)
    size, varies = _static_extent(ctx) if ctx.has("static") else (0, True)
    rates = list(deltas)
    est = ief.max_spread_estimate([deltas[w] for w in rates], [sizes[w] - 1 for w in rates],
                                  noise=not (size and not varies))
    lo, hi = est["interval"]
    half = 0.5 * (est["bias_bounds"][1] - est["bias_bounds"][0])
    u = gum(lambda v, b: v - b,
            [from_u("delta", deltas[r], est["sd_max"], dof=sizes[r] - 1,
                    source="sampling of the largest standard deviation (scaled χ)"),
             type_b("max_bias", est["bias"], half, "rectangular",
                    source="bias of the largest spread, E[max δ_i] − max σ_i, removed "
                           "(midpoint of Jensen's alone … the contenders' full selection "
                           "excess)")])
    # one statement: the interval of the estimate's distribution (JCGM 101 7.7), no k, no ν
    u = replace(u, U=hi - est["value"], k=None, nu_eff=None, coverage_probability=0.95,
                k_source=K_SOURCE_SELECTED_MAX,
                interval=(lo, hi))
    return Item("sf_stability", t, cl, un, est["value"], uncertainty=u,
                details={"delta_by_rate": deltas, "full_scale": fs,
                         # the interval's level z against a true max σ_i (for a study)
                         "level_z_grid": ief.max_spread_level_grid(
                             [deltas[w] for w in rates], [sizes[w] - 1 for w in rates],
                             (lo, hi)) if hi > 0 else None,
                         "reading_max_delta": est["reading"], "reading_rate_dps": r,
                         "max_bias": est["bias"], "max_bias_bounds": list(est["bias_bounds"]),
                         "contenders": est["contenders"], "samples_by_rate": sizes,
                         "standard_reading": standard_reading_beside(
                             "5.1.3.7", est["reading"], "",
                             ("the standard's reading max δ_i = {v} (the largest population "
                              "spread at the constant rates; reads high by the selection of "
                              "a maximum)", "the estimate of the largest true spread max σ_i"),
                             ("标准的读数 max δ_i = {v}（各恒定角速率下总体标准偏差的最大值；"
                              "因取最大值而偏高）", "最大真实分散值 max σ_i 的估计"))})


def sf_temperature(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.3 eq (4) and 5.1.3.4 eqs (5), (6): a(T_i) at the m + 1 temperatures,
    S_F,VAR,Ti = (a_Ti − a_BASE)/a_BASE, and the temperature coefficient T_c,SF = least-squares
    slope of a against T; reported as 100·T_c,SF/a_BASE in %/°C (reading taken), the slope
    and the per-point variations in the details. Computed before 5.1.3.1 (``NEEDS``): the
    scale-factor items take their chamber term from it (:func:`chamber_coefficient`)."""
    t, cl, un = "scale-factor temperature coefficient", "5.1.3.4", "%/°C"
    m = _miss(ctx, "sf_temperature", "sf_temperature_coefficient", t, cl, un, need_a=False) \
        or _miss(ctx, "scale_factor", "sf_temperature_coefficient", t, cl, un, need_a=False)
    if m:           # the runs' drift converts by the 5.1.3.1 run's slope (_sf_runs)
        return m
    runs = _sf_runs(ctx, "sf_temperature")
    T = np.array([c["T"] for c in runs])
    a = np.array([c["a"] for c in runs])
    ib = int(np.argmin(np.abs(T - ctx.t_base_c)))
    slope, icpt = rg.least_squares_line(T, a)
    var = 100 * (a - a[ib]) / a[ib]
    sxx = float(((T - T.mean()) ** 2).sum())
    parts = [c["u_a"] * abs(Ti - T.mean()) / sxx for c, Ti in zip(runs, T)]
    u_slope = math.sqrt(sum(p ** 2 for p in parts))
    u_T_indep = ctx.chamber_deviation_c / math.sqrt(3) * abs(slope) / math.sqrt(sxx)
    h_T = correlated_deviation_slope_bound(T, slope, gyro_temperature_bound_c(ctx))
    u = gum(lambda s, e, ab: 100 * (s + e) / ab,
            [from_u("T_c", slope, u_slope, dof=_ws(parts, [c["nu_a"] for c in runs]),
                    source="slope from the K_i's noise u(a_i)"),
             type_b("dT", 0.0, h_T, "rectangular", source=SLOPE_TEMPERATURE_SOURCE),
             from_u("a_BASE", a[ib], runs[ib]["u_a"], dof=runs[ib]["nu_a"])])
    return Item("sf_temperature_coefficient", t, cl, un, 100 * slope / a[ib], uncertainty=u,
                details={"T_c_SF": slope, "c": icpt, "temperatures_c": T, "K_i": a,
                         "S_F_VAR_pct": var,
                         "u_dT_independent": {
                             "u": u_T_indep,
                             "basis": "the set points' chamber deviations independent, each "
                                      "± bound rectangular, the place in the volume left out "
                                      "(not certified: Table 2 bounds each deviation and the "
                                      "uniformity, not their correlation)"}})


#: The source of the temperature line of a slope over the set points (5.1.3.4, 5.3.3.6).
SLOPE_TEMPERATURE_SOURCE = ("the gyro's temperature error at the set points, any pattern "
                            "within ± (chamber deviation bound + half the uniformity) (the "
                            "errors may follow the set point: the slope's bound "
                            "(δ + U/2)·|T_c|·Σ|T_i − T̄|/Σ(T_i − T̄)²)")


def correlated_deviation_slope_bound(T, slope: float, bound_c: float) -> float:
    """Bound of the least-squares slope's error (same unit as ``slope``) when the chamber
    realises each set point T_i at T_i + d_i, |d_i| ≤ ``bound_c`` in ANY pattern (IEC
    62047-20 5.1.3.4 takes the slope against the set points; JJF 1535 Table 2 bounds each
    deviation, not their correlation — a chamber sensor with a gain error deviates in
    proportion to T − T_cal, all the set points in one direction). The fit of a(T_i + d_i)
    against T_i moves the slope by slope·Σ(T_i − T̄)d_i/Σ(T_i − T̄)², largest at
    d_i = bound·sign(T_i − T̄):

        h = bound·|slope|·Σ|T_i − T̄| / Σ(T_i − T̄)²

    5.1.3.4 passes ``bound_c`` = :func:`gyro_temperature_bound_c` (the chamber's deviation
    bound + half its uniformity, as a_BASE, the bias and JJF K_t do): the gyro's place in
    the volume is bounded at each set point too, and it follows the set point for the
    stronger physical reason (wall losses make the volume's gradient grow with T − ambient),
    so both may take the sign pattern at once.

    The budget carries it as one rectangular line of half-width h (u = h/√3). With the set
    points' deviations independent the slope's u is bound·|slope|/(√3·√Σ(T_i − T̄)²) —
    h/√3 divided by Σ|T_i − T̄|/√Σ(T_i − T̄)² = 1.90 over five points from −40 to 85 °C,
    while the pattern at the bound moves the slope by h = 3.3 of that u: the study's worst
    case (every deviation at its bound, + above T_BASE and − below) covered 0.000 with it.

    >>> round(correlated_deviation_slope_bound([-40, -8.75, 22.5, 53.75, 85], 1.0, 2.0), 6)
    0.0384
    """
    t = np.asarray(T, float)
    d = t - t.mean()
    sxx = float((d * d).sum())
    return float(bound_c) * abs(float(slope)) * float(np.abs(d).sum()) / sxx if sxx > 0 else 0.0


def ratiometric(ctx: Context) -> Item:
    """IEC 62047-20 5.1.3.5 eq (7): R_Vi = [a_Vi − a_BASE·V_i/V_BASE]/a_BASE with a_BASE the
    fit at V_BASE of the supply runs; the largest |R_Vi| in % (the plain supply sensitivity
    (a_Vi − a_BASE)/a_BASE kept in the details, for a regulated gyro). Budget: the two
    slopes' noise and drift, and the chamber's temperature fluctuation moving K by T_c,SF
    between the supply runs, which follow one another at the one set point T_BASE
    (:func:`fluctuation_ratio_u_rel`; amplitude and period from the readings' metadata,
    JJF Table 2's ±1 °C and a bound over any period when absent; none where 5.1.3.4 gives
    no coefficient, :func:`chamber_coefficient`, the item then named in its finding)."""
    t, cl, un = "scale-factor ratiometric error (max |R|)", "5.1.3.5", "%"
    m = _miss(ctx, "ratiometric", "ratiometric_error", t, cl, un)
    if m:
        return m
    runs = _sf_runs(ctx, "ratiometric")
    k_rel = chamber_coefficient(ctx.sf_tc_item).rel or 0.0   # None: named in the finding
    V = np.array([c["V"] for c in runs])
    a = np.array([c["a"] for c in runs])
    ib = int(np.argmin(np.abs(V - ctx.v_base)))
    R = np.array([ief.ratiometric_error_iec(a[i], a[ib], V[i], V[ib]) for i in range(V.size)])
    def point(j):       # the signed R_Vj in % with its budget
        u_fl = 0.0 if j == ib else fluctuation_ratio_u_rel(
            runs[j]["x"], runs[j]["t"], runs[ib]["x"], runs[ib]["t"],
            k_rel * ctx.chamber_fluctuation_c, ctx.chamber_fluctuation_period_s)
        return gum(lambda ai, ab, f: 100 * ief.ratiometric_error_iec(ai * (1 + f), ab, V[j],
                                                                     V[ib]),
                   [from_u("a_Vi", a[j], runs[j]["u_a"], dof=runs[j]["nu_a"]),
                    from_u("a_Vb", a[ib], runs[ib]["u_a"], dof=runs[ib]["nu_a"]),
                    from_u("fluct", 0.0, u_fl, type="B",
                           source="chamber fluctuation (± amplitude, period) × T_c,SF between "
                                  "the supply runs")])

    # the base supply's R is 0 by definition (no point of the extreme)
    others = [j for j in range(V.size) if j != ib] or [ib]
    pts = [point(j) for j in others]
    i = int(np.argmax(np.abs(R[others])))
    value, u, iv = max_magnitude_statement(pts[i], 100 * R[others], pts,
                                           100 * abs(float(R[others[i]])))
    return Item("ratiometric_error", t, cl, un, value, uncertainty=u,
                details={"V": V, "a_V": a, "R_pct": 100 * R,
                         "supply_sensitivity_pct": 100 * (a - a[ib]) / a[ib], **iv})


def cross_axis(ctx: Context) -> Item:
    """IEC 62047-20 5.2.3 eqs (20)–(23), reading taken: ω_x = (Out,x − Out,rest)/SF over whole
    revolutions (the printed ×SF is dimensionally wrong), K = ω_x/ω; with +ω and −ω applied,
    half their difference (bias-free refinement, flagged). Largest of X, Y in %. Budget: the
    noise of the rotating means and the input-axis alignment (a tilt ε of the input axis
    towards the rotation axis reads as a cross-axis sensitivity sin ε, rectangular within
    ± ``axis_alignment_deg``)."""
    t, cl, un = "cross-axis sensitivity (max of X, Y)", "5.2", "%"
    m = _miss(ctx, "cross_axis", "cross_axis", t, cl, un)
    if m:
        return m
    per, us = {}, {}
    for run, name in ((0, "X"), (1, "Y")):
        seg = [s for s in segment_means(ctx.df, "cross_axis") if s.run == run]
        if not seg:
            continue
        rest = np.mean([s.mean for s in seg if s.role == "rest"])
        pos = [s for s in seg if s.role == "rate" and s.rate_dps > 0]
        neg = [s for s in seg if s.role == "rate" and s.rate_dps < 0]
        w = pos[0].rate_dps
        kp = ief.cross_axis_iec(pos[0].mean, rest, ctx.a_base, w)
        kd = (pos[0].mean - neg[0].mean) / 2.0 / ctx.a_base / w if neg else kp
        per[name] = {"rest_corrected": kp, "plus_minus": kd}
        us[name] = math.hypot(pos[0].std / math.sqrt(pos[0].n),
                              neg[0].std / math.sqrt(neg[0].n) if neg else 0.0) / 2 / ctx.a_base / w
    if not per:
        return not_measured("cross_axis", t, cl, un, "no rotation about X or Y")
    ax = max(per, key=lambda k: abs(per[k]["plus_minus"]))
    align = math.sin(math.radians(ctx.axis_alignment_deg))

    def point(name):        # the signed K of one axis in % with its budget
        return gum(lambda k, al: 100 * (k + al),
                   [from_u("K_" + name, per[name]["plus_minus"], us[name], dof=DOF_U_WITHIN_10PCT,
                           source="noise of the rotating means"),
                    type_b("align", 0.0, align, "rectangular",
                           source="alignment of the input axis to the plane perpendicular to "
                                  "the rotation axis (table axis and fixture): "
                                  "sin(half-width)")])

    names = list(per)
    pts = [point(n) for n in names]
    # a magnitude, the larger |K| of X and Y: the interval of the extreme of magnitudes
    value, u, iv = max_magnitude_statement(pts[names.index(ax)],
                                           [100 * per[n]["plus_minus"] for n in names], pts,
                                           100 * abs(per[ax]["plus_minus"]))
    return Item("cross_axis", t, cl, un, value, uncertainty=u,
                details={"per_axis": per, "axis": ax, **iv})


def bias_tc_dps_per_c(ctx: Context) -> float:
    """The bias temperature coefficient (°/s/°C): the least-squares slope of the 5.3.3.6
    visits' bias against temperature; 0 when the readings hold no such visits (or the
    5.3.3.6 item itself refuses them: no coefficient to use)."""
    try:
        pts = _bias_temperature_points(ctx) if ctx.has("bias_temperature") else []
        return float(rg.least_squares_line(np.array([p[0] for p in pts]),
                                           np.array([p[1] for p in pts]))[0]) \
            if len({p[0] for p in pts}) >= 2 else 0.0
    except (GonioError, ValueError, IndexError, KeyError):
        return 0.0


def bias_tc_bound_dps_per_c(ctx: Context) -> float:
    """The bound of |β| ((°/s)/°C) the bias's bound condition takes for the gyro's
    temperature error at T_BASE: |β| + U(β) of 5.3.3.6's statement (:func:`bias_temperature`,
    its 95 % interval's far end: the estimate alone is no bound, as for a_BASE's
    :func:`chamber_coefficient`); 0 when the readings hold no 5.3.3.6 visits or the item refuses
    them (no coefficient to bound with: the line is then 0, as before)."""
    if not ctx.has("bias_temperature"):
        return 0.0
    try:
        it = bias_temperature(ctx)
    except (GonioError, ValueError, IndexError, KeyError):
        return 0.0
    if not it.measured or it.value is None or not math.isfinite(it.value):
        return 0.0
    unc = it.uncertainty
    if unc is not None and unc.U is not None and math.isfinite(float(unc.U)):
        return abs(float(it.value)) + float(unc.U)
    if unc is not None and unc.interval is not None:
        return max(abs(float(e)) for e in unc.interval)
    return abs(float(it.value))


#: What the bias (5.3.3.1) and 5.3.3.2 keep in ``details.bound_condition.basis``.
BIAS_BOUND_BASIS = (
    "bound condition: the bounded lines (the gyro's temperature error at T_BASE, the "
    "chamber's deviation and place bounds × |β| + U(β) of 5.3.3.6; the input axis's "
    "misalignment bound on the horizontal Earth rate; a_BASE's own bounded part, where "
    "5.1.3.1 is stated by its bound condition) at their bounds with one sign, added "
    "linearly, a = Σ|c_i|·a_i, plus k·u of the other lines, U = a + t_95(ν_rest)·u_rest "
    "(JCGM 100 4.3.7, 6.2); holds at least 95 % at every condition within the bounds")


def _bias_budget(ctx: Context) -> tuple[float, list, list, float, dict]:
    """The budget of the 5.3.3.1 bias (:func:`bias`): (value °/s, the records' values, the
    budget's inputs, the records' mean Earth component °/s, the bounded lines {symbol:
    half-width}). N_bias = (Out,ave − null)/a_BASE − Ω_E,proj (eq. (24) with the reading
    taken: computed in output units and divided by a_BASE), so a relative error e_a of
    a_BASE moves it by −(N_bias + Ω_E,proj)·e_a: the line of a_BASE's u (:func:`_e_a`:
    u_c(a_BASE)/a_BASE, or, where 5.1.3.1 is stated by its bound condition, its other
    lines' u_rest/a_BASE with ν_rest) and, bounded, a_BASE's bounded part a/a_BASE
    (``e_a_bnd``)."""
    vals, earths, raw = [], [], []
    for s in segment_means(ctx.df, "bias"):
        earth = rg.earth_rate_projection_dps(ctx.latitude_deg, input_axis_enu(s.up_axis, s.north_axis))
        vals.append((s.mean - ctx.null_output - ctx.a_base * earth) / ctx.a_base)
        earths.append(earth)
        raw.append(s.mean)
    v = np.array(vals)
    h_tu = gyro_temperature_bound_c(ctx) * bias_tc_bound_dps_per_c(ctx)
    h_al = rg.OMEGA_E_DPS * math.cos(math.radians(ctx.latitude_deg)) \
        * math.sin(math.radians(ctx.axis_alignment_deg))
    ins = [from_u("N_bias", float(v.mean()),
                  float(v.std(ddof=1) / math.sqrt(v.size)) if v.size > 1 else 0.0,
                  dof=max(v.size - 1, 1), source="spread of the records"),
           from_u("e_acq_null", 0.0, ctx.acquisition_u_rel * abs(float(np.mean(raw)))
                  / abs(ctx.a_base), type="B",
                  source="acquisition gain on the whole output (null included)"),
           type_b("e_TU", 0.0, h_tu, "rectangular",
                  source=TEMPERATURE_BOUND_SOURCE + " × (|β| + U(β)) of 5.3.3.6 (0 without "
                                                    "its visits)"),
           type_b("e_align", 0.0, h_al, "rectangular",
                  source="input-axis alignment × horizontal Earth rate"),
           _e_a_rest(ctx),
           type_b("e_a_bnd", 0.0, ctx.a_base_bound_rel, "rectangular",
                  source="scale factor, relative: a_BASE's bounded part a/a_BASE of 5.1.3.1 "
                         "(0 where it has none)")]
    return float(v.mean()), v, ins, float(np.mean(earths)), \
        {"e_TU": h_tu, "e_align": h_al, "e_a_bnd": ctx.a_base_bound_rel}


def _bias_statement(u, value: float, bounded: dict):
    """The bias's (and 5.3.3.2's) statement: by the bound condition (:func:`table_bound_statement`
    with :data:`BIAS_BOUND_BASIS`) over the lines of ``bounded`` that are not 0 (the gyro's
    temperature error, the alignment, a_BASE's bounded part: Table 2 and the fixture let
    each sit at its bound, where a rectangular line in the quadrature covers about 92 % on
    the demo); the GUM budget's U = k·u_c where every bound is 0."""
    bounded = {s: h for s, h in bounded.items() if float(h) > 0.0}
    if not bounded:
        return u, {}
    return table_bound_statement(u, value, None, bounded, basis=BIAS_BOUND_BASIS)


def bias(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.1 eq (24): N_bias = Out,ave − Earth-rate component (°/s), computed in
    output units then divided by a_BASE (reading taken). The Earth component uses the
    physics (axis up Ω_E sin λ, horizontal Ω_E cos λ cos φ); the printed sin/cos are swapped
    (erratum). Mean over the records. Budget (:func:`_bias_budget`): the records' spread
    (type A), the acquisition's relative gain uncertainty on the whole output, null
    included, the gyro's temperature error at T_BASE (:func:`gyro_temperature_bound_c`: the
    chamber's deviation and the gyro's place in its volume, both bounded, bounds added
    linearly) times |β| + U(β) of the 5.3.3.6 visits (e_TU), the input axis's alignment on
    the horizontal Earth rate, and a_BASE (the division of the reading taken for eq. (24)).
    Stated by the bound condition (:func:`_bias_statement`)."""
    t, cl, un = "bias N_bias", "5.3.3.1", "°/s"
    m = _miss(ctx, "bias", "bias", t, cl, un)
    if m:
        return m
    value, v, ins, earth, bounded = _bias_budget(ctx)
    u = gum(lambda b, en, eTU, eal, ea, eab: (b + earth) / ((1 + ea) * (1 + eab)) - earth
            + en + eTU + eal, ins)
    u, bc = _bias_statement(u, value, bounded)
    return Item("bias", t, cl, un, value, uncertainty=u, details={
        "records_dps": v, "earth_component_dps": earth,
        "printed_formula_earth_dps": rg.OMEGA_E_DPS * math.cos(math.radians(ctx.latitude_deg)),
        "erratum": "5.3.3.1 prints Ω cos λ for a vertical axis and Ω sin λ cos φ for a "
                   "horizontal one; physically they are Ω sin λ and Ω cos λ cos φ",
        **({"bound_condition": bc} if bc else {})})


def bias_repeatability(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.4, reading taken: the records' deviations from their mean as
    +max/−min and the half range (max − min)/2 (°/s) as the single ± value. Stated by the
    one-sided 95 % interval of the expected half range from the distribution of the range of
    n normal records (:func:`gonio.specs.iec62047_20.formulas.half_range_upper`): no k and
    no ν (the interval is the range distribution's for n records, not a t or χ² of some ν;
    the budget row keeps n − 1 as the records' count less one, and u_c = hr/√(2(n − 1)))."""
    t, cl, un = "bias repeatability (half range)", "5.3.3.4", "°/s"
    m = _miss(ctx, "bias", "bias_repeatability", t, cl, un)
    if m:
        return m
    v = np.array([(s.mean - ctx.null_output) / ctx.a_base for s in segment_means(ctx.df, "bias")])
    if v.size < 2:
        return not_measured("bias_repeatability", t, cl, un, "needs ≥ 2 records")
    hr = float((v.max() - v.min()) / 2)
    # stated by one interval from the distribution of the range of n normal records:
    # [0, upper limit of the expected half range] (no k: the range is skewed; t was used)
    hi = ief.half_range_upper(hr, v.size, 0.95)
    u_c = hr / math.sqrt(2 * (v.size - 1))
    u = Uncertainty([{"symbol": "hr", "source": f"half range of {v.size} records; interval "
                      "from the distribution of the range of normal values (Tippett)",
                      "type": "A", "u": u_c, "c": 1.0, "contribution": u_c,
                      "dof": float(v.size - 1)}], u_c, hi - hr, None, None, None,
                    0.95, "normal range", interval=(0.0, hi))
    return Item("bias_repeatability", t, cl, un, hr, uncertainty=u, details={
        "plus_dps": float(v.max() - v.mean()), "minus_dps": float(v.min() - v.mean())})


def bias_temperature(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.6 b): bias temperature coefficient, the least-squares slope of bias
    against temperature through every visit (up and down passes), (°/s)/°C; a) the largest
    departures from the base-temperature bias and 5.3.3.7 the hysteresis (largest
    |B_up(T) − B_down(T)|) in the details. Input axis horizontal east: zero Earth input.
    Uncertainty: :func:`bias_tc_budget` (the residual scatter about the line is in the
    details: it holds the curvature of b(T), which moves the residuals and not the slope)."""
    t, cl, un = "bias temperature coefficient", "5.3.3.6", "(°/s)/°C"
    m = _miss(ctx, "bias_temperature", "bias_temperature_coefficient", t, cl, un)
    if m:
        return m
    pts = _bias_temperature_points(ctx)
    T, B = np.array([p[0] for p in pts]), np.array([p[1] for p in pts])
    slope, c0 = rg.least_squares_line(T, B)
    r = B - (slope * T + c0)
    se = math.sqrt(float(r @ r) / (T.size - 2) / float(((T - T.mean()) ** 2).sum())) if T.size > 2 else 0.0
    base = B[np.abs(T - ctx.t_base_c) < 1e-9]
    # hysteresis: same temperature on the rising and the falling pass
    hyst = 0.0
    for Tv in np.unique(T):
        b = B[T == Tv]
        if b.size >= 2:
            hyst = max(hyst, float(b.max() - b.min()))
    u = bias_tc_budget(pts, lambda sep: visit_drift_u_dps(ctx, sep), ctx.chamber_deviation_c,
                       ctx.chamber_fluctuation_c, ctx.chamber_fluctuation_period_s,
                       ctx.chamber_uniformity_c)
    return Item("bias_temperature_coefficient", t, cl, un, slope, uncertainty=u, details={
        "temperatures_c": T, "bias_dps": B, "bias_dph": B * S_PER_H,
        "residual_scatter_u": se,
        "variation_max_dps": float((B - base.mean()).max()),
        "variation_min_dps": float((B - base.mean()).min()), "hysteresis_dps": hyst})


def bias_tc_budget(pts, drift_u, deviation_bound_c: float, fluctuation_c: float,
                   period_s: float | None, uniformity_c: float) -> Uncertainty:
    """Budget of the 5.3.3.6 slope β = Σ w_i B_i, w_i = (T_i − T̄)/S_TT over the visits
    ``pts`` ((T set point °C, B °/s, u(B) °/s, ν, mid-time s) in visit order), from the
    physics of each visit's bias error e_i (β − β_true = Σ w_i e_i):

    - the noise of the visit means: Σ w_i² u(B_i)² (type A, ν Welch–Satterthwaite);
    - the bias drift over the session, a process of stationary increments with
      D(s) = ``drift_u``(s)² (the variance of the difference of two visits' means s apart:
      :func:`visit_drift_u_dps`, the static record's Allan fit through the generalised
      covariance): with Σ w_i = 0 its variance is
      −½ Σ_ij w_i w_j D(|t_i − t_j|), exact for any such process (variogram form);
    - the gyro's temperature error at each set point — the chamber's deviation (±
      ``deviation_bound_c``) and the gyro's place in the volume (± ``uniformity_c``/2), both
      bounded per set point and shared by the visits to it (the readings log the set point),
      in ANY pattern (as 5.1.3.4's :func:`correlated_deviation_slope_bound`: a chamber
      sensor's gain error and the volume's gradient both grow with the set point's distance
      from ambient): one rectangular line of half-width (δ + U/2)·Σ_T |b′(T)·Σ_{i∈T} w_i|,
      the largest slope change over every sign pattern, b′(T) = c₁ + 2c₂T from a quadratic
      fit of the visits' biases;
    - the chamber's periodic fluctuation (amplitude ``fluctuation_c``, period ``period_s``,
      phase unknown, uniform): A·|Σ w_i b′(T_i) e^{2πi t_i/P}|/√2 (the record's mean of
      the sinusoid bounded by its mid-time value); A·Σ|w_i b′(T_i)|/√2 without a period;
    The residual scatter about the line is not used: a curved b(T) spreads the residuals by
    b₂(T − T̄)² and leaves the slope through points symmetric about T_BASE unbiased."""
    T = np.array([p[0] for p in pts], float)
    B = np.array([p[1] for p in pts], float)
    uB = np.array([p[2] for p in pts], float)
    tm = np.array([p[4] for p in pts], float)
    if T.size < 3 or np.ptp(T) <= 0:
        raise GonioError(f"5.3.3.6: {T.size} visits at {np.unique(T).size} temperatures; "
                         "the slope's budget needs at least 3 visits at 2 temperatures")
    slope, _ = rg.least_squares_line(T, B)
    w = (T - T.mean()) / float(((T - T.mean()) ** 2).sum())
    c = np.polyfit(T, B, 2) if np.unique(T).size >= 3 else np.array([0.0, slope, 0.0])
    db = c[1] + 2 * c[0] * T                                     # b′(T_i), (°/s)/°C
    parts = w * uB
    D = np.array([[drift_u(abs(ti - tj)) ** 2 if ti != tj else 0.0 for tj in tm] for ti in tm])
    u_drift = math.sqrt(max(-0.5 * float(w @ D @ w), 0.0))
    dev = [db[T == Tv][0] * float(w[T == Tv].sum()) for Tv in np.unique(T)]
    h_tu = rg.gyro_temperature_bound_c(deviation_bound_c, uniformity_c) * float(np.abs(dev).sum())
    wd = w * db
    mag = abs(complex(np.sum(wd * np.exp(2j * math.pi * tm / period_s)))) if period_s \
        else float(np.abs(wd).sum())
    u_fl = abs(fluctuation_c) * mag / math.sqrt(2.0)
    return gum(lambda s, d, dv, fl: s + d + dv + fl, [
        from_u("slope", slope, math.sqrt(float(parts @ parts)),
               dof=_ws(parts, [p[3] for p in pts]), source="noise of the visits' bias means"),
        from_u("drift", 0.0, u_drift, dof=DOF_U_WITHIN_10PCT,
               source="bias drift over the session (Allan fit: RRW, BI), variogram form"),
        type_b("dT_set", 0.0, h_tu, "rectangular", source=SLOPE_TEMPERATURE_SOURCE),
        from_u("dT_fluct", 0.0, u_fl, type="B", source="chamber's periodic fluctuation")])


def _static(ctx: Context):
    """(Allan deviation, rate °/h, Δt s) of the static record (5.4), cached per scale factor
    and null output: a context copied with a provisional a_BASE (while a_BASE itself is being
    fitted) shares the cache dict and must not hand its record to the final one."""
    key = ("allan", ctx.a_base, ctx.null_output)
    if key not in ctx.cache:
        rate_dph, dt = static_rate_dph(ctx.df, ctx.null_output, ctx.a_base)
        allan = allan_deviation(rate_dph, dt, "rate", "decade:10", unit="deg/h")
        ctx.cache[key] = (allan, rate_dph, dt)
    return ctx.cache[key]


def _static_extent(ctx: Context) -> tuple[int, bool]:
    """(samples, whether it varies) of the static record, found once per calibration (the
    budgets ask for every rate and temperature: each look was a scan of the readings)."""
    if "static_extent" not in ctx.cache:
        y = static_output(ctx.df)
        ctx.cache["static_extent"] = (int(y.size), bool(y.size) and value_range(y) != 0)
    return ctx.cache["static_extent"]


def _quiet(ctx: Context, key: str, title: str, clause: str, unit: str) -> Item | None:
    """A static record without any variation (noise-free bench): the noise terms are 0."""
    size, varies = _static_extent(ctx)
    if size and not varies:
        return Item(key, title, clause, unit, 0.0, uncertainty=gum(lambda v: v, [from_u(key, 0.0, 0.0)]),
                    details={"note": "the static record does not vary: no noise to analyse"})
    return None


def _noise_fit(ctx: Context):
    """The five-term Allan fit of the static record (cached; IEEE 952 Annex C)."""
    key = ("noise_fit", ctx.a_base, ctx.null_output)
    if key not in ctx.cache:
        ctx.cache[key] = fit_noise_model(_static(ctx)[0])
    return ctx.cache[key]


def _noise_fit_shaped(ctx: Context):
    """The fit with band-limited flicker of the static record (cached; the ARW's lift)."""
    key = ("noise_fit_shaped", ctx.a_base, ctx.null_output)
    if key not in ctx.cache:
        ctx.cache[key] = fit_markov_model(_static(ctx)[0])
    return ctx.cache[key]


def arw(ctx: Context) -> Item:
    """IEC 62047-20 5.4.5.2: the −½ line through the short-τ part of the Allan deviation read
    at τ = 1 h (°/√h); (29): 1 °/√h = 60 (°/h)/√Hz.

    The line's τ may also carry bias instability and quantisation, which lift the reading.
    The noise model fitted to the same record gives that lift at the same τ, the factor
    N_line(model)/N_fit, and the value certified is the line reading divided by it. The
    model is the five-term model with its flicker band-limited below a fitted correlation
    time (:func:`gonio.analysis.noise.fit_markov_model`): the five-term flat flicker holds
    its floor down to the line's shortest τ, where a gyro's bias instability fades, and
    overstates the lift (it was therefore applied only halfway, the midpoint of the
    uncorrected and the corrected reading; the five-term factor and that midpoint stay in
    the details).

    The ARW is a dispersion (N = σ(τ)·√τ on the line) and is stated as one, by its one-sided
    χ² 95 % interval alone (:func:`arw_uncertainty`): the line reading's spread from the
    equivalent degrees of freedom of its Allan variances under the five-term model fitted to
    the same record (:func:`arw_line_edf`; the noise types the fit assumes, not those
    identified τ by τ), the correction's model (the band-limited against the five-term
    factor, rectangular) and the gyro's temperature during the record against T_BASE
    (:func:`noise_temperature_line`, where the 5.3.3.6 visits give the coefficient; without
    them a finding says the items hold at the record's temperature); no k, no "± U".

    The line's τ range is 5.4.5.2 e)'s reading taken (from the shortest τ to the first whose
    local slope leaves −½ ± 0.05) applied to the fitted model's curve, not to the data
    (:func:`arw_reading`): on the data the range ends where the record's own scatter first
    flattens a slope, so the points kept are those the scatter lowered, and the line read
    low (−0.06 % on the built-in record, docs/iec62047-20-readings.md). The standard's
    reading — the range the data's slope gives, no lift correction — is given beside
    (``standard_reading``), not certified."""
    t, cl, un = "angular random walk", "5.4.5.2", "°/√h"
    m = _miss(ctx, "static", "arw", t, cl, un) or _quiet(ctx, "arw", t, cl, un)
    if m:
        return m
    allan, _, _ = _static(ctx)
    fit = _noise_fit(ctx)
    shaped = _noise_fit_shaped(ctx)
    value, val, ratio, u_rel, mask = arw_reading(allan, shaped)
    midpoint_five_term, _, ratio_five, _, _ = arw_reading_midpoint(allan, fit)
    edf = arw_line_edf(allan, mask, fit)
    ratio_five_same = arw_lift_factor(allan.tau_s, mask, fit)
    u, bc = noise_statement(ctx, value, arw_budget(
        value, ratio, edf, ratio_five_same, temperature=_noise_temperature_line(ctx, value)))
    std_val, std_mask = ief.arw_minus_half_line(allan.tau_s, allan.adev)
    return Item("arw", t, cl, un, value, uncertainty=u, details={
        **({"bound_condition": bc} if bc else {}),
        "dph_per_sqrt_hz": value * math.sqrt(S_PER_H), "tau_used_s": allan.tau_s[mask],
        "line_edf": edf,
        "line_reading_uncorrected": val, "line_bias_factor_model": ratio,
        "standard_line_tau_s": allan.tau_s[std_mask],
        "standard_reading": standard_reading_beside(
            "5.4.5.2", std_val, " °/√h",
            ("the standard's reading, the −½ line over the short-τ range the data's own "
             "slope gives, read at 1 h, {v}",
             "the line over the range the fitted noise model's slope gives, divided by "
             "the model's lift factor"),
            ("标准的读数（由数据自身斜率确定的短 τ 区间内斜率 −½ 的直线，在 1 小时处读取）{v}",
             "由拟合噪声模型的斜率确定区间的直线读数，除以模型的抬升因子")),
        "noise_temperature_coefficient_per_c": _noise_tc_details(ctx),
        "flicker_band_t_lo_s": shaped.t_lo_s,
        "five_term_line_bias_factor": ratio_five,
        "five_term_lift_same_tau": ratio_five_same,
        "five_term_midpoint_reading": midpoint_five_term,
        "five_term_fit_arw": fit.N / math.sqrt(S_PER_H),
        "band_limited_fit_arw": shaped.N / math.sqrt(S_PER_H)})


def arw_reading(allan, fit) -> tuple[float, float, float, float, np.ndarray]:
    """The ARW of :func:`arw` from an Allan deviation (°/h) and a fitted model (anything with
    ``N`` and ``adev(tau)``): (value °/√h = the −½ line reading / the model's lift factor,
    uncorrected −½ line reading, the lift factor N_line(model)/N_fit, relative u of the
    line's points, mask of the τ used). The line's τ are those 5.4.5.2 e)'s rule
    (:func:`gonio.specs.iec62047_20.formulas.arw_minus_half_line`) gives on the model's
    curve (:func:`arw_model_range`), read on the data."""
    model = fit.adev(allan.tau_s)
    mask = arw_model_range(allan, model)
    s = allan.adev[mask] * np.sqrt(allan.tau_s[mask])
    val = math.exp(float(np.mean(np.log(s)))) / math.sqrt(S_PER_H)
    rel = np.abs(np.log(allan.ci_high[mask] / allan.adev[mask]))
    u_rel = float(np.sqrt(np.mean(rel ** 2)) / math.sqrt(mask.sum())) * 2.0   # correlated τ
    ratio = arw_lift_factor(allan.tau_s, mask, fit)
    return val / ratio, val, ratio, u_rel, mask


def arw_lift_factor(tau_s, mask, fit) -> float:
    """The lift of the −½ line over the τ in ``mask`` under a fitted model (anything with
    ``N`` and ``adev(tau)``): N_line(model)/N_fit, the geometric mean of σ_model(τ)·√τ over
    those τ divided by the model's N (1 where the model has no N)."""
    tau = np.asarray(tau_s, float)[mask]
    model = np.asarray(fit.adev(tau), float)
    if not (fit.N > 0) or not np.all(np.isfinite(model) & (model > 0)):
        return 1.0
    return math.exp(float(np.mean(np.log(model) + 0.5 * np.log(tau)))) / fit.N


def arw_model_range(allan, model_adev) -> np.ndarray:
    """The τ of the −½ line (mask over ``allan.tau_s``): 5.4.5.2 e)'s rule of
    :func:`gonio.specs.iec62047_20.formulas.arw_minus_half_line` applied to a fitted model's
    Allan deviation at the same τ, where the data are finite and positive. The rule on the
    data ends the range at the first τ whose noisy local slope leaves −½ ± 0.05, an event
    the scatter of the points kept helps trigger (a low σ̂ just before the end flattens the
    slope there), so the kept points read low; the model's curve has no scatter. Where the
    model has no −½ range (nothing fitted), the data's own range."""
    ok = np.isfinite(allan.adev) & (allan.adev > 0)
    m = np.asarray(model_adev, float)
    good = ok & np.isfinite(m) & (m > 0)
    if good.any():
        idx = np.flatnonzero(good)
        try:
            _, sub = ief.arw_minus_half_line(allan.tau_s[idx], m[idx])
        except GonioError:
            sub = None
        if sub is not None and sub.any():
            mask = np.zeros(allan.tau_s.size, bool)
            mask[idx[sub]] = True
            return mask
    return ief.arw_minus_half_line(allan.tau_s, allan.adev)[1]


def arw_line_edf(allan, mask, fit) -> float:
    """Equivalent degrees of freedom of the −½ line reading of :func:`arw_reading` (the
    geometric mean of σ̂(τ_i)·√τ_i over the τ in ``mask``) under the five-term model ``fit``
    (anything with ``Q, N, B, K, R``) fitted to the same record: the noise types are the
    model's, not identified from the data τ by τ. With c_ij the covariance of the Allan
    variance estimates σ̂²(τ_i), σ̂²(τ_j) of one record under the model
    (:func:`gonio.analysis.noise.covariance.variance_covariance`: overlapping terms,
    neighbouring τ) and σ_i² the model's variances, the mean of ln σ̂²(τ_i) has variance
    v = Σ_ij c_ij/(σ_i² σ_j²)/n² (delta method), and a χ² with ν degrees of freedom has
    Var(ln χ²_ν/ν) ≈ 2/ν, so ν = 2/v; N̂²/N² is then read as χ²_ν/ν (one τ: Greenhall's
    edf, the covariance's diagonal 2σ⁴/edf). Where the model gives no variance at those τ
    (nothing fitted): the smallest Greenhall edf of the points (the points read as one)."""
    ok = np.asarray(mask, bool) & np.isfinite(allan.adev) & (allan.adev > 0)
    fallback = float(np.min(allan.edf[ok])) if ok.any() else math.nan
    coef = np.array([0.0 if not math.isfinite(float(x)) else float(x) ** 2
                     for x in (fit.Q, fit.N, fit.B, fit.K, fit.R)])
    if not ok.any() or not coef[:4].any():
        return fallback
    from gonio.analysis.noise.fit import design_matrix

    tau, m = np.asarray(allan.tau_s[ok], float), np.asarray(allan.m[ok], np.int64)
    var = design_matrix(tau, allan.kind, allan.tau0_s) @ coef        # E[σ̂²(τ_i)]
    cov = variance_covariance("hdev" if allan.kind == "hdev" else "adev", m,
                              np.asarray(allan.n_pairs[ok], np.int64), allan.tau0_s, coef)
    v = float((cov / np.outer(var, var)).sum()) / ok.sum() ** 2 if (var > 0).all() else math.nan
    return 2.0 / v if math.isfinite(v) and v > 0 else fallback


def arw_budget(value: float, ratio: float, edf: float, ratio_alt: float | None = None,
               temperature=None) -> Uncertainty:
    """The GUM budget of 5.4.5.2's ARW (:func:`arw_uncertainty`'s lines, before the
    statement): what :func:`noise_statement` states."""
    u_n = value / math.sqrt(2.0 * edf) if edf > 0 and math.isfinite(edf) else 0.0
    alt = ratio if ratio_alt is None or not math.isfinite(ratio_alt) or ratio_alt <= 0 \
        else ratio_alt
    lines = [from_u("N", value, u_n, dof=edf if u_n > 0 else DOF_U_WITHIN_10PCT,
                    source="χ² of the −½ line's Allan variances: edf of the line reading "
                           "under the fitted five-term model"),
             type_b("corr", 0.0, abs(ratio / alt - 1.0), "rectangular",
                    source="lift correction's model: band-limited against the five-term "
                           "fit's factor over the same τ (bound)")]
    if temperature is None:
        return gum(lambda n, c: n * (1 + c), lines)
    return gum(lambda n, c, t: n * (1 + c) + t, lines + [temperature])


def arw_uncertainty(value: float, ratio: float, edf: float,
                    ratio_alt: float | None = None, temperature=None) -> Uncertainty:
    """The one statement of 5.4.5.2's ARW (:func:`arw`): a dispersion, stated as the noise rms
    is (:func:`gonio.result.gum.dispersion_uncertainty`), by its one-sided χ² 95 % interval
    [0, N·√(ν/χ²_0.05,ν)] with ν = ½(N/u_c)². The budget: the line reading, u = N/√(2·edf)
    with ν = edf (JCGM 100 E.4.3: the u of a standard deviation of edf degrees of freedom;
    ``edf`` from :func:`arw_line_edf`), and the lift correction's model: the correction by
    the band-limited fit's factor ``ratio`` lies within the one by the five-term fit's
    factor ``ratio_alt`` over the same τ (flat flicker, the most lift) of it, a rectangular
    half-width |ratio/ratio_alt − 1| (JCGM 100 4.3.7); none where the two agree (the
    band-limited fit fell back to the five-term one) or ``ratio_alt`` is None. The
    correction's own scatter is not a further line: the fitted lift follows the record's
    own bias instability, so the corrected value scatters less than the line (0.45 % against
    the line's u 0.52 % on the built-in record). Without the correction ν = edf and the
    upper end is N·√(edf/χ²_0.05,edf), the χ² interval of the Allan deviations the line
    reads. ``temperature``: the line for the gyro's temperature during the record against
    T_BASE (:func:`noise_temperature_line`, °/√h), added where given; the calibration states
    the ARW by :func:`noise_statement` over the same budget (:func:`arw_budget`), by the
    bound condition of that temperature where the coefficient is known."""
    return dispersion_uncertainty(value, arw_budget(value, ratio, edf, ratio_alt, temperature))


def arw_reading_midpoint(allan, fit) -> tuple[float, float, float, float, np.ndarray]:
    """The former reading under the five-term (flat-flicker) fit, kept in the details: the
    midpoint of the uncorrected and the fully corrected −½ line reading (the same tuple as
    :func:`arw_reading`)."""
    full, val, ratio, u_rel, mask = arw_reading(allan, fit)
    return (val + full) / 2.0, val, ratio, u_rel, mask


def bias_instability(ctx: Context) -> Item:
    """IEC 62047-20 5.4.5.3 c): Allan-deviation floor / 0.664 (°/h), over τ with ≥ 10
    independent clusters (reading taken), less the rule's bias; the standard's reading (the
    floor / 0.664 itself) and the five-term fit's B in the details.

    The floor is a minimum over τ of correlated Allan deviations that also hold the other
    noise terms (ARW, RRW, quantisation) at the floor τ: other terms lift it above
    0.664·B, the minimum over noisy values lowers it, and the χ² interval of one τ
    overstates its spread. Both are taken from the rule's own distribution
    (:func:`floor_rule_draws`) under the five-term model fitted to the record, its B varied
    (a parametric bootstrap; Efron & Tibshirani 1993, ch. 10): the value is the B whose
    rule has the reading as its mean (:func:`floor_reading`). The item is stated by one
    coverage interval from that distribution, p = 95 %, no k and no ν (GUM Suppl. 1 =
    JCGM 101 7.7, the probabilistically symmetric interval): B̂ − B is distributed as the
    draws about their mean, so [B̂ − (q₉₇.₅ − m), B̂ + (m − q₂.₅)] (the pivot, "basic"
    bootstrap interval, Davison & Hinkley 1997 eq 5.6), its lower end at least 0; the draws'
    quantiles shifted to B̂ would put the long side where the estimate's tail is, not the
    truth's. u_c is the draws' standard deviation (JCGM 101 7.6; z, budget line). The
    standard's reading is kept in the details (``floor_reading_dph``) beside the value.
    A value below 0 (a reading that is all other terms) is stated as 0, the bound. The
    interval's digits: no finer than the draws settle (JCGM 101 7.9,
    :func:`floor_interval_numerical_u`; :data:`BIAS_INSTABILITY_DRAWS` leave its ends about
    0.03·u uncertain, within half a unit of the reach's first significant digit: a u of a
    few °/h is stated to the unit)."""
    t, cl, un = "bias instability", "5.4.5.3", "°/h"
    m = _miss(ctx, "static", "bias_instability", t, cl, un) or _quiet(ctx, "bias_instability", t, cl, un)
    if m:
        return m
    allan = _static(ctx)[0]
    fit = _noise_fit(ctx)
    val, i, value, u_b, slope, n_draws, (lo, hi), num_u = floor_reading(allan, fit)
    u = gum(lambda r, e: r - e,
            [from_u("floor", val, u_b, source=f"spread of the floor rule: standard deviation "
                    f"of {n_draws} seeded draws under the five-term fit (correlated Allan "
                    "variances)"),
             from_u("rule_bias", val - value, 0.0,
                    source="bias of the floor rule, E*[B*] − B, removed (other noise terms "
                           "at the floor τ, minimum over τ)")])
    # one statement: the interval of the rule's own distribution (JCGM 101 7.7), no k, no ν
    u = replace(u, U=hi - value, k=None, nu_eff=None, coverage_probability=0.95,
                k_source="floor rule's distribution (pivot)", interval=(lo, hi),
                interval_numerical_u=num_u, interval_draws=n_draws)
    return Item("bias_instability", t, cl, un, value, uncertainty=u, details={
        "tau_floor_s": float(allan.tau_s[i]), "fit": fit.to_dict(),
        "floor_reading_dph": val, "floor_rule_bias_dph": val - value,
        "standard_reading": standard_reading_beside(
            "5.4.5.3", val, " °/h",
            ("the standard's reading, the Allan-deviation floor / 0.664, {v}",
             "that reading less the floor rule's bias"),
            ("标准的读数（Allan 偏差底值 / 0.664）{v}", "该读数减去底值规则的偏差")),
        "floor_rule_slope": slope, "interval_dph": [lo, hi],
        "allan": {"tau_s": allan.tau_s, "adev_dph": allan.adev, "ci_low": allan.ci_low,
                  "ci_high": allan.ci_high}})


def floor_reading(allan, fit) -> tuple[float, int, float, float, float, int,
                                       tuple[float, float], float]:
    """5.4.5.3 c) from an Allan deviation and the five-term fit of the same record: (the
    standard's reading R = floor/0.664, index of the floor τ, the value B̂, u(B̂), the slope
    g' = dE*[B*]/dB, draws per evaluation, the 95 % interval (lo, hi), the interval ends'
    numerical standard uncertainty from the finite draws, :func:`floor_interval_numerical_u`)
    (:func:`bias_instability`).

    B̂ solves E*[B* | B] = R, E* the mean of :func:`floor_rule_draws` under the fit with its B
    replaced: a first step B₁ = R − (E*[B* | R] − R), then one secant step through (R, B₁)
    with the same seeded draws (the mean is smooth in B); B̂ ≥ 0. u(B̂) = the standard
    deviation of the draws at B₁, the reading's own spread (JCGM 101 7.6). The interval is
    the pivot of the same draws (m their mean, q their 2.5 % and 97.5 % quantiles):
    B̂ − B ~ B* − m, so B ∈ [B̂ − (q₉₇.₅ − m), B̂ + (m − q₂.₅)] with 95 %, 2.5 % each side
    (JCGM 101 7.7 probabilistically symmetric), the lower end at least 0. Neither u nor the
    ends are divided by g' (< 1: other noise terms make the floor move less than B), the
    delta method with the other terms held: they are fitted to the same record and follow the
    floor's fluctuation, and B̂ scattered as the reading does (ADXRS610 bench noise, 40 records
    of 2 h: sd of B̂ 2.67 °/h, of the reading 3.04 °/h, g' 0.80; divided by g', u was
    4.08 °/h and z sd 0.69)."""
    val, i = ief.bias_instability_floor(allan.adev, n_clusters=allan.n_samples / allan.m)
    coef = np.nan_to_num([fit.Q, fit.N, val, fit.K, fit.R])

    def draws_at(b: float) -> np.ndarray:
        coef[2] = b
        return floor_rule_draws(allan, coef, i)

    g0 = float(draws_at(val).mean())
    b1 = max(2.0 * val - g0, 0.0)
    d1 = draws_at(b1)
    u_f = float(d1.std(ddof=1))
    g1 = float(d1.mean())
    slope = (g1 - g0) / (b1 - val) if abs(b1 - val) > 0.01 * u_f else 1.0
    slope = min(max(slope, BIAS_INSTABILITY_SLOPE_MIN), 1.0)
    b2 = max(b1 + (val - g1) / slope, 0.0)
    return val, i, b2, u_f, slope, int(d1.size), floor_interval(b2, d1), \
        floor_interval_numerical_u(d1)


def floor_interval(value: float, draws: np.ndarray, p: float = 0.95) -> tuple[float, float]:
    """The probabilistically symmetric ``p`` interval (JCGM 101 7.7) of the 5.4.5.3 value
    from the floor rule's draws about their mean m (the pivot: value − B ~ B* − m):
    [value − (q_(1+p)/2 − m), value + (m − q_(1−p)/2)], the lower end at least 0 (B ≥ 0)."""
    m = float(draws.mean())
    q_lo, q_hi = (float(q) for q in np.quantile(draws, [(1.0 - p) / 2.0, (1.0 + p) / 2.0]))
    return max(value - (q_hi - m), 0.0), value + (m - q_lo)


def floor_interval_numerical_u(draws: np.ndarray, p: float = 0.95) -> float:
    """The standard uncertainty of :func:`floor_interval`'s ends from the finite number of
    draws (JCGM 101 7.9): each end is the value ∓ (a quantile − the draws' mean), so its
    numerical u is √(u(quantile)² + u(mean)²), the quantile's from
    :func:`uncertainty.quantile_numerical_u`, the mean's s/√M; the larger of the two ends.
    It decides the decimal place the interval is stated at (no digit a rerun of the draws
    would change; :func:`gonio.result.statement.state_interval`, as 5.3.3.5's
    :func:`power_on_interval_numerical_u`).

    >>> d = np.random.default_rng(0).normal(20.0, 3.0, 4000)
    >>> round(floor_interval_numerical_u(d), 2)    # ≈ √(0.025·0.975/4000)/φ(1.96)·3 = 0.13
    0.12
    """
    from uncertainty import quantile_numerical_u

    d = np.asarray(draws, float)
    q = (1.0 + p) / 2.0
    s_q = quantile_numerical_u(d, [1.0 - q, q])
    s_m = float(d.std(ddof=1)) / math.sqrt(d.size)
    return float(np.sqrt(np.max(s_q) ** 2 + s_m ** 2))


#: Draws of the floor rule per evaluation: enough that the interval's ends are settled at
#: the reach's first significant digit whatever its size (JCGM 101 7.9.2, 2s ≤ δ: s ≈ 0.024
#: of the reach at 25 000 draws; 4000 left 0.06, more than δ = 0.05·10^d where the reach is
#: near 9·10^d), about 10 ms a call.
BIAS_INSTABILITY_DRAWS = 25000
BIAS_INSTABILITY_SEED = 6204720553      # fixed: the same records give the same value
BIAS_INSTABILITY_CONTENDER = 1.5        # τ whose model deviation is ≤ 1.5× the least contend
BIAS_INSTABILITY_SLOPE_MIN = 0.2        # g' floor: a reading almost all other terms


def floor_rule_draws(allan, coef, i_floor: int, *, n_draws: int = BIAS_INSTABILITY_DRAWS,
                     seed: int = BIAS_INSTABILITY_SEED) -> np.ndarray:
    """Draws (°/h or ``allan``'s unit) of the 5.4.5.3 c) floor rule — min over the τ with ≥ 10
    clusters of σ̂(τ), / 0.664 — for a record of ``allan``'s length, τ0 and τ grid under the
    five-term model ``coef`` = (Q, N, B, K, R) (:mod:`gonio.analysis.noise.fit` units).

    The τ that can hold the floor are those whose model deviation is within
    :data:`BIAS_INSTABILITY_CONTENDER` of the least (and the record's floor ``i_floor``);
    elsewhere the estimates' spread is far below that margin. Their variance estimates have
    the model's means and the exact covariance of one record
    (:func:`gonio.analysis.noise.covariance.variance_covariance`: Isserlis over the model's
    generalised covariance; its diagonal is Greenhall's edf); each is drawn as a χ²_ν/ν
    multiple of its mean (ν = 2σ⁴/Var; Wilson–Hilferty 1931 cube of a normal) from
    normals with the estimates' correlation (a Gaussian copula), and the rule applied to
    every draw. Checked against the rule on simulated records at full rate (tests). Seeded:
    the same inputs give the same draws."""
    coef = np.asarray(coef, dtype=np.float64)
    elig = np.flatnonzero(allan.n_samples / allan.m >= 10)
    mv = model_deviation(allan.tau_s[elig], *coef, kind="adev", tau0_s=allan.tau0_s) ** 2
    if not (mv > 0).all():
        return np.full(n_draws, float(np.sqrt(mv.min())) / rg.FLICKER_FLOOR_EXACT)
    keep = (mv <= BIAS_INSTABILITY_CONTENDER ** 2 * mv.min()) | (elig == i_floor)
    sel, mv = elig[keep], mv[keep]
    cov = variance_covariance("adev", allan.m[sel], allan.n_pairs[sel], allan.tau0_s,
                              coef ** 2)
    sd = np.sqrt(np.diag(cov))
    nu = 2.0 * mv ** 2 / sd ** 2
    w, vec = np.linalg.eigh(cov / np.outer(sd, sd))
    root = vec * np.sqrt(np.clip(w, 0.0, None))
    z = np.random.default_rng(seed).standard_normal((n_draws, sel.size)) @ root.T
    a = 2.0 / (9.0 * nu)
    v = mv * np.clip(1.0 - a + z * np.sqrt(a), 0.0, None) ** 3
    return np.sqrt(v.min(axis=1)) / rg.FLICKER_FLOOR_EXACT


def fluctuation_band_power(n: int, dt: float, nper: int, amp: float, period_s: float | None,
                           f_lo: float, f_hi: float, *, include_lo: bool = False) -> float:
    """The largest power (unit² of ``amp``) that a periodic fluctuation amp·sin(2πt/P + φ)
    of the record, over every phase φ, adds to the Welch estimate's integral over the band
    (f_lo, f_hi] (``include_lo``: [f_lo, f_hi]) — the chamber's fluctuation moving the bias
    through its temperature coefficient during the static record (IEC 62047-20 5.4.5.1 b),
    c): the rms is taken as the gyro's noise, and the chamber's share cannot be told from it
    in one record). The Welch estimate of s = cos φ·s₁ + sin φ·s₂ (s₁, s₂ the sine and
    cosine at φ = 0) over the band is the quadratic form [cos φ, sin φ]·M·[cos φ, sin φ]ᵀ,
    M from the estimates of s₁, s₂ and s₁ + s₂ through the same estimator
    (:func:`gonio.analysis.noise.psd.welch_psd`, ``nper`` points, the trapezoid over the
    band's lines); its maximum over φ is M's largest eigenvalue. Period not stated (None or
    0): the largest over periods from 4Δt to the record's length (40, log-spaced).

    >>> round(fluctuation_band_power(20000, 0.1, 1000, 1.0, 20.0, 0.0, 5.0) / 0.5, 2)
    1.0
    """
    if amp == 0 or n < 2:
        return 0.0
    if not period_s:
        return max(fluctuation_band_power(n, dt, nper, amp, float(P), f_lo, f_hi,
                                          include_lo=include_lo)
                   for P in np.geomspace(4 * dt, n * dt, 40))
    t = np.arange(n) * dt
    w = 2 * math.pi * t / period_s
    s1, s2 = amp * np.sin(w), amp * np.cos(w)

    def band(x):
        f, p = welch_psd(x, 1.0 / dt, nper)
        sel = ((f >= f_lo) if include_lo else (f > f_lo)) & (f <= f_hi)
        return float(np.trapezoid(p[sel], f[sel])) if sel.sum() > 1 else 0.0

    p11, p22, p_sum = band(s1), band(s2), band(s1 + s2)
    p12 = 0.5 * (p_sum - p11 - p22)
    return float(max(np.linalg.eigvalsh(np.array([[p11, p12], [p12, p22]]))))


def fluctuation_rms_bound(rms: float, added_power: float) -> float:
    """Half-width of the chamber-fluctuation line on a noise rms (same unit): the reading
    √(σ² + ΔP) less σ at the largest ΔP the fluctuation adds (:func:`fluctuation_band_power`),
    σ = √(rms² − ΔP) (the gyro's own); the line is one-sided (the fluctuation only adds) and
    is carried rectangular ± this half-width, the value kept as read (the reading taken).

    >>> fluctuation_rms_bound(5.0, 9.0)
    1.0
    """
    if added_power <= 0:
        return 0.0
    return float(rms - math.sqrt(max(rms * rms - added_power, 0.0)))


def _fluctuation_noise_line(ctx: Context, x, dt: float, nper: int, f_lo: float, f_hi: float,
                            rms: float, *, include_lo: bool = False):
    """The noise items' chamber-fluctuation line (rectangular, °/s): the bias temperature
    coefficient of the 5.3.3.6 visits (:func:`bias_tc_dps_per_c`; 0 without them) times the
    readings' stated fluctuation amplitude, over its stated period (every period where not
    stated), through the item's own band (:func:`fluctuation_band_power`,
    :func:`fluctuation_rms_bound`)."""
    amp = abs(bias_tc_dps_per_c(ctx)) * ctx.chamber_fluctuation_c
    h = fluctuation_rms_bound(rms, fluctuation_band_power(
        len(x), dt, nper, amp, ctx.chamber_fluctuation_period_s or None, f_lo, f_hi,
        include_lo=include_lo))
    return type_b("fluct", 0.0, h, "rectangular",
                  source="chamber's fluctuation (± amplitude, period) × the bias temperature "
                         "coefficient, through the band's Welch estimate (one-sided: it adds "
                         "power)")


def _noise_budget(lines: list, temperature):
    """The GUM sum of a noise rms's lines (the estimate and its fluctuation line), with the
    temperature line (:func:`noise_temperature_line`) where there is one."""
    if temperature is None:
        return gum(lambda r, e: r + e, lines)
    return gum(lambda r, e, t: r + e + t, lines + [temperature])


def _static_record_c(ctx: Context) -> float | None:
    """The static record's logged temperature (:func:`static_record_temperature_c`), once."""
    key = ("static_record_c",)
    if key not in ctx.cache:
        ctx.cache[key] = static_record_temperature_c(ctx.df)
    return ctx.cache[key]


def _noise_temperature_line(ctx: Context, value: float):
    """:func:`noise_temperature_line` at the static record's logged temperature (None
    without a coefficient, :func:`noise_temperature_coefficient`)."""
    if noise_temperature_coefficient(ctx) is None:
        return None
    return noise_temperature_line(ctx, value, _static_record_c(ctx))


def _noise_tc_details(ctx: Context) -> dict | None:
    """:func:`noise_temperature_coefficient` for the details (None without visits)."""
    tc = noise_temperature_coefficient(ctx)
    return None if tc is None else {"value": tc.value, "u": tc.u, "nu": tc.nu,
                                    "visits": tc.visits}


def inband_noise(ctx: Context) -> Item:
    """IEC 62047-20 5.4.5.1 b), reading taken: the rms output noise below ``band_hz`` (°/s) from
    the Welch one-sided density, and the amplitude density ((°/s)/√Hz) at stated frequencies
    in the details. The broadband "20 dB/dec" figure of c) is :func:`broadband_noise`.

    Uncertainty: the Welch estimate's own scatter
    (:func:`gonio.analysis.noise.psd.welch_band_rms_u_rel`: correlated Hann lines and
    overlapping segments), the chamber's fluctuation and the gyro's temperature during the
    record against T_BASE (:func:`noise_temperature_line`, where the 5.3.3.6 visits give the
    coefficient). The rms is a dispersion and is
    stated as one, by its one-sided χ² 95 % interval alone with ν = ½(rms/u_c)²
    (:func:`gonio.result.gum.dispersion_uncertainty`): no k, no "± U"."""
    t, cl, un = "in-band noise (rms)", "5.4.5.1 b)", "°/s"
    m = _miss(ctx, "static", "inband_noise", t, cl, un) or _quiet(ctx, "inband_noise", t, cl, un)
    if m:
        return m
    _, x, dt = _static(ctx)                  # °/h; the density in °/s, in bounded pieces
    nper = min(4096, x.size)
    f, p = welch_psd(x, 1.0 / dt, nper, divisor=S_PER_H)
    band = ctx.protocol["noise"]["band_hz"]
    sel = (f > 0) & (f <= band)
    rms = math.sqrt(float(np.trapezoid(p[sel], f[sel])))
    dens = {str(fq): float(np.sqrt(np.interp(fq, f, p))) for fq in ctx.protocol["noise"]["density_at_hz"]}
    u_rel = welch_band_rms_u_rel(x.size, nper, p[sel], float(f[1] - f[0])) if sel.sum() > 1 \
        else math.nan
    u_rel = u_rel if math.isfinite(u_rel) else 0.0           # no noise in the band
    nu = max(1.0, 0.5 / u_rel ** 2) if u_rel > 0 else 50     # Welch: ν = 2/var_rel(rms²)
    u = _noise_budget([from_u("rms", rms, rms * u_rel, dof=nu,
                              source="Welch estimate: correlated Hann lines and "
                                     "overlapping segments"),
                       _fluctuation_noise_line(ctx, x, dt, nper, 0.0, band, rms)],
                      _noise_temperature_line(ctx, rms))
    u, bc = noise_statement(ctx, rms, u)
    return Item("inband_noise", t, cl, un, rms, uncertainty=u,
                details={"density_dps_per_sqrt_hz": dens, "band_hz": band,
                         **({"bound_condition": bc} if bc else {})})


def frequency_band(ctx: Context) -> Item:
    """IEC 62047-20 5.5.3, 5.5.5: gain and phase by sine fits against the reference; the band
    is the lower of the −3 dB frequency and the 90° ± 5° lag frequency (reading taken: both
    reported); gain peak (dB, frequency) in the details."""
    t, cl, un = "frequency band", "5.5", "Hz"
    if not ctx.has("vibration"):
        return not_measured("frequency_band", t, cl, un, "no 'vibration' records in the readings")
    f, K, ph, uph = [], [], [], []
    for s in segment_means(ctx.df, "vibration"):
        g = segment_samples(ctx.df, "vibration", s.run, s.step)
        tt = g["time_s"].to_numpy()
        yo = g["output"].to_numpy()
        ao, po, co = rg.sine_fit(tt, yo, s.freq_hz)
        ar, pr, _ = rg.sine_fit(tt, g["reference_dps"].to_numpy(), s.freq_hz)
        res = yo - co - ao * np.sin(2 * math.pi * s.freq_hz * tt + math.radians(po))
        uph.append(math.degrees(float(np.std(res)) * math.sqrt(2.0 / tt.size) / ao))
        f.append(s.freq_hz)
        K.append(ao / ar)
        ph.append(((po - pr + 180.0) % 360.0) - 180.0)
    f, K = np.array(f), np.array(K)
    ph = np.degrees(np.unwrap(np.radians(ph)))
    f3 = rg.minus3db_frequency(f, K)
    f90 = rg.phase90_frequency(f, ph)
    cands = [v for v in (f3, f90) if math.isfinite(v)]
    if not cands:
        return not_measured("frequency_band", t, cl, un, "neither −3 dB nor 90° lag reached")
    band = min(cands)
    db = 20 * np.log10(K / K[0])
    ip = int(np.argmax(db))
    j = min(max(int(np.searchsorted(f, band)), 1), f.size - 1)
    # the crossing f* = f_{j−1}^(1−w)·f_j^w, w = (target − p_{j−1})/(p_j − p_{j−1}), moves with
    # the two bracketing points' errors weighted (1 − w) and w (not by their root sum square)
    w = math.log(band / f[j - 1]) / math.log(f[j] / f[j - 1])
    if band == f90:
        dp, up = ph[j] - ph[j - 1], (uph[j - 1], uph[j])                # degrees
    else:                                               # gain error σ_A/A = phase error in rad
        dp = db[j] - db[j - 1]
        up = tuple(20 / math.log(10) * math.radians(v) for v in (uph[j - 1], uph[j]))
    h = math.log(f[j] / f[j - 1])
    u_f = band * h / abs(dp) * math.hypot((1 - w) * up[0], w * up[1]) if dp != 0 else 0.0
    half_interp = band * h / abs(dp) * interpolation_remainder(
        np.log(f), ph if band == f90 else db, j) if dp != 0 else 0.0
    u = gum(lambda b, n, i: b + n + i,
            [from_u("f", band, 0.0), from_u("noise", 0.0, u_f, dof=DOF_U_WITHIN_10PCT,
                                            source="phase/gain noise of the bracketing points"),
             type_b("interp", 0.0, half_interp, "rectangular",
                    source="linear interpolation in ln f: h²/8·|p''| from the neighbouring "
                           "point's second difference")])
    return Item("frequency_band", t, cl, un, band, uncertainty=u, details={
        "freq_hz": f, "gain_db": db, "phase_deg": ph, "minus3db_hz": f3, "phase90_hz": f90,
        "phase90_hz_iec": f90, "criterion": "-3 dB" if band == f3 else "90 deg lag",
        "gain_peak_db": float(db[ip]), "gain_peak_hz": float(f[ip])})


def interpolation_remainder(lnf: np.ndarray, p: np.ndarray, j: int) -> float:
    """Bound of linear interpolation's error between points j − 1 and j of p(ln f):
    h²/8·|p''| (the remainder of linear interpolation, h = ln f_j − ln f_{j−1}), p'' from the
    second divided difference over j − 1, j and the next point (j + 1, or j − 2 at the
    grid's end); 0 with fewer than three points."""
    if lnf.size < 3:
        return 0.0
    k = (j - 1, j, j + 1) if j + 1 < lnf.size else (j - 2, j - 1, j)
    a, b, c = (float(lnf[i]) for i in k)
    d2 = 2 * ((p[k[2]] - p[k[1]]) / (c - b) - (p[k[1]] - p[k[0]]) / (b - a)) / (c - a)
    h = float(lnf[j] - lnf[j - 1])
    return h * h / 8 * abs(float(d2))


def _power_on_records(ctx: Context):
    po = ctx.protocol["power_on"]
    for s in segment_means(ctx.df, "warmup"):
        g = segment_samples(ctx.df, "warmup", s.run, s.step)
        y = (g["output"].to_numpy() - ctx.null_output) / ctx.a_base      # °/s (Earth included)
        P = po["smoothing_samples"]
        n = y.size // P
        t = g["time_s"].to_numpy()[: n * P].reshape(n, P).mean(1)
        ys = y[: n * P].reshape(n, P).mean(1)
        yield s.run, t, ys, y


def initial_bias_variation(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.2 eq (25): bias (Earth rate removed, 5.3.3.1) minus the nominal bias
    Out,typ, in °/s (reading taken: divided by a_BASE when the output is in V or bit). The
    bias's budget and statement (:func:`_bias_budget`, :func:`_bias_statement`: the bound
    condition), shifted by Out,typ."""
    t, cl, un = "initial bias variation", "5.3.3.2", "°/s"
    m = _miss(ctx, "bias", "initial_bias_variation", t, cl, un)
    if m:
        return m
    value, _, ins, earth, bounded = _bias_budget(ctx)
    typ = ctx.protocol["power_on"]["nominal_bias_dps"]
    u = gum(lambda b, en, eTU, eal, ea, eab: (b + earth) / ((1 + ea) * (1 + eab)) - earth
            + en + eTU + eal - typ, ins)
    u, bc = _bias_statement(u, value - typ, bounded)
    return Item("initial_bias_variation", t, cl, un, value - typ, uncertainty=u,
                details={"nominal_bias_dps": typ, **({"bound_condition": bc} if bc else {})})


def bias_drift_after_power_on(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.5 eq (27): Out,ave = mean over the reference part just after
    power-on; the drift is max_t |Out(t) − Out,ave| over the record, Out(t) averaged over
    ``smoothing_samples`` (the literal max|Out| − Out,ave misbehaves for negative outputs);
    the largest over the records, °/s, less the noise's selection excess
    (:func:`power_on_drift_budget`). A magnitude (a largest absolute difference), stated by
    one interval, that of its replicates' distribution (:func:`power_on_interval`): no k,
    no ν; u_c the replicates' standard deviation. The standard's reading (the largest
    difference itself) is kept in the details (``reading_dps``)."""
    t, cl, un = "bias drift after power on", "5.3.3.5", "°/s"
    m = _miss(ctx, "warmup", "bias_drift_after_power_on", t, cl, un)
    if m:
        return m
    recs = [(tt, ys, y) for _, tt, ys, y in _power_on_records(ctx)]
    coef, coef_dof = drift_coef_power_on_dps(ctx)
    val, vals, u, m_sel, fit = power_on_drift_budget(
        recs, ctx.protocol["power_on"]["reference_samples"], lambda sep: drift_u_dps(ctx, sep),
        coef, coef_dof)
    return Item("bias_drift_after_power_on", t, cl, un, val, uncertainty=u,
                details={"per_record_dps": vals, "reading_dps": max(vals),
                         "contending_values": m_sel, **fit})


def _one_blas_thread(fn):
    """``fn`` run with one BLAS/LAPACK thread (threadpoolctl): its eigendecompositions and
    matrix products then sum in the same order in the calling process as in a validation
    worker (which runs under the same limit), so a record's numbers are the same bytes
    wherever it is computed."""
    import functools

    @functools.wraps(fn)
    def wrapped(*args, **kwargs):
        from threadpoolctl import threadpool_limits

        with threadpool_limits(limits=1):
            return fn(*args, **kwargs)
    return wrapped


def power_on_records_pooled(recs) -> bool:
    """IEC 62047-20 5.3.3.5, reading taken (docs/iec62047-20-readings.md, 5.3.3.5): whether the
    records CAN be fitted with one transient — the same samples, smoothing and times from
    power-on. This is the precondition of :func:`power_on_one_transient`, not the decision:
    repeated power-ons of a real gyro differ (start temperature), and one transient is
    fitted only where the records' own fits do not refute it. Records that differ in length
    or timing are fitted one by one."""
    if len(recs) < 2:
        return False
    t0, ys0, y0 = recs[0]
    span = max(1.0, abs(float(t0[-1] - t0[0]))) if t0.size else 1.0
    return all(ys.size == ys0.size and y.size == y0.size and tt.size == t0.size
               and np.allclose(tt - tt[0], t0 - t0[0], rtol=0.0, atol=1e-9 * span)
               for tt, ys, y in recs[1:])


#: Level of 5.3.3.5's test that the power-on records share one transient
#: (:func:`power_on_one_transient`): one transient is refuted at p < 0.05.
POWER_ON_POOL_LEVEL = 0.05


def power_on_lr_statistic(Y: np.ndarray, pooled_model: np.ndarray, own_models) -> np.ndarray:
    """The likelihood-ratio statistic of 5.3.3.5's one-transient test for Gaussian noise of
    one covariance (up to its scale): T = Σ_i ‖r_i^pooled‖² − Σ_i ‖r_i^own‖², the records'
    residual sums of squares under one transient c_i + A·e^(−t/τ) (the level c_i each
    record's own: the fit of the records' mean, less each record's mean) less those of each
    record's own fit c_i + A_i·e^(−t/τ_i). ``Y``: (…, records, blocks) smoothed values;
    ``pooled_model``: (…, blocks) the fit of their mean; ``own_models``: (…, records,
    blocks). T ≥ 0 up to rounding (the own fits nest the pooled one on the τ grid)."""
    Yc = Y - Y.mean(-1, keepdims=True)
    pc = pooled_model - pooled_model.mean(-1, keepdims=True)
    oc = own_models - own_models.mean(-1, keepdims=True)
    return (((Yc - pc[..., None, :]) ** 2).sum((-2, -1))
            - ((Yc - oc) ** 2).sum((-2, -1)))


def power_on_one_transient(t_obs: float, t_star: np.ndarray,
                           level: float = POWER_ON_POOL_LEVEL) -> tuple[bool, float]:
    """IEC 62047-20 5.3.3.5, reading taken (docs/iec62047-20-readings.md, 5.3.3.5): the
    measurand is the largest drift over the records, and repeated power-ons differ, so one
    transient is fitted to all records only where a test does not refute it. The test:
    each record's own fit against the one-transient fit by the likelihood ratio
    ``t_obs`` (:func:`power_on_lr_statistic`), its null distribution ``t_star`` that of the
    same statistic in the replicates of the one-transient fit at the noise found (white σ_y
    and the bias drift, :func:`_power_on_replicates`: the smoothed values' correlation under
    the walk and flicker is in it, as an F table would not have it); p = (1 + #{T* ≥ T})/
    (1 + n). Returns (one transient, p): one transient where p ≥ ``level``
    (:data:`POWER_ON_POOL_LEVEL`), else the records are fitted one by one (each record's
    replicates then carry its own transient, and the selection among records of unequal
    drift is that of the records' actual fitted transients).

    >>> power_on_one_transient(97.5, np.arange(99.0))
    (False, 0.02)
    >>> power_on_one_transient(0.5, np.arange(99.0))
    (True, 0.99)
    """
    t_star = np.asarray(t_star, float)
    p = float((1 + np.count_nonzero(t_star >= t_obs)) / (1 + t_star.size))
    return p >= level, round(p, 12)


def _power_on_replicates(recs, nr: int, drift_u, drift_coef, scale=(1.0, 1.0, 1.0),
                         pooled=None, test: bool = False, blocks=(0,), cache=None) -> dict:
    """The parametric bootstrap of 5.3.3.5 (:func:`power_on_drift_budget`): the records'
    readings, their fitted transient(s) and :data:`POWER_ON_MC_TRIALS` replicates of the
    fitted records per block of ``blocks`` (block indices), each read (R*) and fitted (R̂*)
    as the data are; block b draws from :func:`power_on_block_rng` (b), so a block's
    replicates are the same whichever blocks it is drawn with, and ``cache`` (a dict, or
    None) keeps each block's normal numbers and replicates for the next call on the same
    records. ``pooled``:
    one transient for all records (True), one per record (False), or None: one where the
    records can share it (:func:`power_on_records_pooled`) — the caller decides by
    :func:`power_on_one_transient`, for which ``test`` (with one transient) adds the
    likelihood ratio of the records ("lr") and of each replicate of the first block listed
    ("lr_star"). ``scale`` multiplies the three noise variances (white σ_y², walk K²,
    flicker B²; the wander of ``drift_u`` by the second) with the same random numbers: the
    sensitivities of u_c² for its degrees of freedom."""
    P = max(recs[0][2].size // max(recs[0][1].size, 1), 1)
    sw, sk, sb = (float(x) for x in scale)
    pooled = power_on_records_pooled(recs) if pooled is None else bool(pooled)
    test = test and pooled
    vals, dists, sig, designs = [], [], [], []
    for tt, ys, y in recs:
        d = np.abs(ys - float(y[:nr].mean()))
        vals.append(float(d.max()))
        dists.append(d)
        sig.append(float(np.std(np.diff(y, 2), ddof=1) / math.sqrt(6)) if y.size > 3 else 0.0)
        designs.append(_transient_designs(tt, y.size, P, nr))
    if pooled:
        fits = _transient_fits(np.mean([ys for _, ys, _ in recs], axis=0)[None, :],
                               designs[0]) * len(recs)
    else:
        fits = [_transient_fits(ys[None, :], dz)[0] for (_, ys, _), dz in zip(recs, designs)]
    cache = {} if cache is None else cache
    noise = cache.setdefault("noise", {})
    roots, parts = None, []
    for b in blocks:
        key = (sw, sk, sb, pooled, int(b))
        want_lr = test and b == blocks[0]
        if key not in cache or (want_lr and "lr" not in cache[key]):
            if roots is None:
                roots = [_drift_root(ys.size, P, nr, float(tt[1] - tt[0]) / P
                                     if ys.size > 1 else 1.0,
                                     (drift_coef[0] * sk, drift_coef[1] * sb))
                         if drift_coef is not None else
                         _wander_root(tt - tt[0], lambda x: math.sqrt(sk) * drift_u(x))
                         for tt, ys, _ in recs]
            cache[key] = _power_on_block(recs, nr, drift_coef is None, P, sw, pooled, sig,
                                         fits, designs, roots, int(b), want_lr, noise)
        parts.append(cache[key])
    out = {k: parts[0][k] for k in ("lr", "lr_star")} if test else {}
    kept = [(np.concatenate([pt["devs"][j] for pt in parts]), mb - mr)
            for j, (mb, mr, _) in enumerate(fits)]
    return {"vals": vals, "dists": dists, "sig": sig, "P": P, "pooled": pooled,
            "r_hat": max(f[2] for f in fits),
            "r_star": np.concatenate([pt["r_star"] for pt in parts]),
            "r_fit": np.concatenate([pt["r_fit"] for pt in parts]),
            "kept": kept, "n_mc": POWER_ON_MC_TRIALS * len(blocks),
            "white_dof": float(sum(max(y.size - 2, 1) for _, _, y in recs))
            / SECOND_DIFFERENCE_RHO2, **out}


def _power_on_block(recs, nr: int, wander: bool, P: int, sw: float, pooled: bool, sig, fits,
                    designs, roots, block: int, test: bool, noise: dict) -> dict:
    """One block of :func:`_power_on_replicates`: :data:`POWER_ON_MC_TRIALS` replicates of
    the fitted records (``fits``) with white noise σ_y = ``sig`` (variance × ``sw``) and the
    drift drawn through ``roots`` (the first values' wander in the reference where
    ``wander``), from the block's standard normal numbers (:func:`_power_on_block_noise`,
    kept in ``noise`` by block: every scale of the variances uses the same numbers); their
    readings R* ("r_star"), fitted readings R̂* ("r_fit"), each record's replicates less
    their reference ("devs"), and with ``test`` the likelihood ratios (:func:`_power_on_lr`)."""
    n_mc = POWER_ON_MC_TRIALS
    if block not in noise:
        noise[block] = _power_on_block_noise(recs, nr, P, [r is not None for r in roots], block)
    rs, rf, ys_sum, stars, devs = np.zeros(n_mc), np.zeros(n_mc), 0.0, [], []
    for (tt, ys, y), s_y, (mb, mr, _), dz, root, (wb, wr, z) in zip(
            recs, sig, fits, designs, roots, noise[block]):
        sd_w = s_y * math.sqrt(sw)
        ys_star = mb[None, :] + sd_w * wb
        ref_star = mr + sd_w * wr
        if root is not None:
            w = z @ root
            ys_star += w
            if wander:                          # the wander's reference: its first values
                ref_star += w[:, :max(int(math.ceil(nr / P)), 1)].mean(1)
        dev = ys_star - ref_star[:, None]
        rs = np.maximum(rs, np.abs(dev).max(1))
        devs.append(dev)
        if pooled:
            ys_sum = ys_sum + ys_star
            if test:
                stars.append(ys_star)
        else:
            rf = np.maximum(rf, np.array([f[2] for f in _transient_fits(ys_star, dz)]))
    out = {"r_star": rs, "r_fit": rf, "devs": devs}
    if pooled:
        pf = _transient_fits(ys_sum / len(recs), designs[0])
        out["r_fit"] = np.array([f[2] for f in pf])
        if test:
            out.update(_power_on_lr(recs, designs, fits, pf, stars))
    return out


def _power_on_block_noise(recs, nr: int, P: int, drift, block: int) -> list:
    """The standard normal numbers of one block of 5.3.3.5's replicates
    (:func:`power_on_block_rng` (``block``)), per record in order: the white samples' block
    means (replicates × smoothed values) and reference means, then, where ``drift`` (per
    record) says a drift is drawn, the drift's normal rows (replicates × smoothed values, None
    otherwise)."""
    n_mc = POWER_ON_MC_TRIALS
    rng = power_on_block_rng(block)
    out = []
    for (_, ys, _), d in zip(recs, drift):
        nb = ys.size
        white = rng.standard_normal((n_mc, nb * P))
        out.append((white.reshape(n_mc, nb, P).mean(2), white[:, :nr].mean(1),
                    rng.standard_normal((n_mc, nb)) if d else None))
    return out


def _power_on_lr(recs, designs, fits, pf, stars) -> dict:
    """The likelihood ratio of the records against one transient ("lr") and of each
    replicate ("lr_star", from its own fits ``pf`` and the replicates ``stars``, one array
    per record) for :func:`power_on_one_transient`."""
    own = [_transient_fits(ys[None, :], dz)[0][0] for (_, ys, _), dz in zip(recs, designs)]
    lr = float(power_on_lr_statistic(np.array([ys for _, ys, _ in recs]), fits[0][0],
                                     np.array(own)))
    Ys = np.stack(stars, axis=1)                                      # (n_mc, records, blocks)
    own_star = np.stack([np.array([f[0] for f in _transient_fits(Ys[:, j], designs[j])])
                         for j in range(len(recs))], axis=1)
    return {"lr": lr, "lr_star": power_on_lr_statistic(Ys, np.array([f[0] for f in pf]),
                                                       own_star)}


def power_on_block_rng(block: int) -> np.random.Generator:
    """The random numbers of block ``block`` of 5.3.3.5's replicates: the first from
    :data:`POWER_ON_MC_SEED` alone, block b > 0 from the seed sequence (seed, b) —
    independent streams, fixed, so the same records give the same value and more blocks
    add replicates without changing the first ones (the fitting decision is block 0's).

    >>> float(power_on_block_rng(0).random()) == float(np.random.default_rng(POWER_ON_MC_SEED).random())
    True
    """
    return np.random.default_rng(POWER_ON_MC_SEED if block == 0 else [POWER_ON_MC_SEED, block])


#: Σ ρ_k² of white noise's second differences (ρ₁ = −2/3, ρ₂ = 1/6): σ_y² from m second
#: differences has m/Σρ² degrees of freedom (var s² = 2σ⁴Σρ²/m for a Gaussian series).
SECOND_DIFFERENCE_RHO2 = 1.0 + 2.0 * ((2.0 / 3.0) ** 2 + (1.0 / 6.0) ** 2)


def power_on_dof(shares, dofs, n_mc: int = 0) -> float:
    """5.3.3.5's ν_eff by Welch–Satterthwaite (JCGM 100 G.4.1) over the components of u_c²:
    ``shares`` s_i = ∂ln u_c²/∂ln v_i, the sensitivity of u_c² to each noise variance v_i
    (white σ_y², walk K², flicker B²; for a Gaussian model, linear in the v_i, the share of
    u_c² each holds), ``dofs`` ν_i of each v_i's estimate, and the replicates' own count
    (u_c from ``n_mc`` draws: share 1, ν = n_mc − 1): ν_eff = 1/Σ s_i²/ν_i, i.e. u_c⁴/Σ
    u_i⁴/ν_i with u_i = √s_i·u_c.

    >>> round(power_on_dof([0.5, 0.5, 0.0], [20.0, 20.0, 3.0]), 6)
    40.0
    >>> round(power_on_dof([1.0], [math.inf], 401), 6)
    400.0
    """
    s = [max(float(x), 0.0) for x in shares] + ([1.0] if n_mc > 1 else [])
    nu = [float(x) for x in dofs] + ([float(n_mc - 1)] if n_mc > 1 else [])
    return welch_satterthwaite(1.0, [math.sqrt(x) for x in s], nu)


@_one_blas_thread
def power_on_drift_budget(recs, nr: int, drift_u, drift_coef=None,
                          coef_dof=(math.inf, math.inf)
                          ) -> tuple[float, list, Uncertainty, int]:
    """5.3.3.5 from the power-on records ``recs`` ((block times s, smoothed output °/s, raw
    output °/s) each), the reference part's ``nr`` samples and ``drift_u`` (separation s →
    standard uncertainty °/s of the bias drift): (value, per-record readings, Uncertainty,
    number of contending smoothed values).

    The measurand: the largest |Out(t) − Out,ave| of the gyro's noise-free power-on output
    (its transient's smoothed values less its reference mean), the largest over the
    records. The reading R = max over the records and their smoothed values of
    |Out(t) − Out,ave| is an extreme of noisy values, so noise raises it by a selection
    excess that depends on how many values share the largest true distance (up to the whole
    settled part of every record). The excess and the estimate's spread are evaluated as
    JCGM 101 propagates a distribution, by a parametric bootstrap of the fitted model
    (:func:`_power_on_replicates`): one transient c_i + A·e^(−t/τ) fitted to the records
    together (:func:`power_on_records_pooled`; one by one where their timing differs;
    :func:`_transient_fits`: least squares on the smoothed values, τ on a grid, A = 0
    included), giving R̂, the reading of the fitted records; blocks of
    :data:`POWER_ON_MC_TRIALS` seeded replicates of the fitted records are drawn with the
    record's noise — white samples of σ_y = √(var Δ²y/6) (second differences: a transient smooth on the sample
    interval does not enter them) and the bias drift — with ``drift_coef`` = (K² (°/s)²/s,
    B² (°/s)²) from the static record (:func:`drift_coef_power_on_dps`) the exact covariance of the smoothed values less the
    reference under the rate random walk and the flicker (the five-term model's generalised
    covariance: flicker differences grow as ln of the separation, IEEE 952 C.1), else a
    Gaussian process of stationary increments with variogram D(s) = ``drift_u``(s)² — and
    each replicate is read and fitted as the data are. The first estimate is V = R − e(R̂),
    e(R̂) = E*[R*] − R̂ the selection excess; its replicates, linearised in the fitted
    reading (a double bootstrap to first order), V* = R* − e(R̂) − g·(R̂* − R̂) estimate V's
    distribution about R̂, with g = de/dR̂ at the reading less the fit's bias
    (:func:`_excess_slope`; g = −1, the excess not following the signal, where that reading
    is not above :data:`POWER_ON_RESOLVED` sd of R̂*): the value is V less the residual bias
    E*[V*] − R̂ (the fit's own selection at small signals), u_c the standard deviation of
    V*. A value below 0 (records without a transient, whose reading is all excess) is
    stated as 0, the measurand's bound.

    ν_eff (:func:`power_on_dof`, Welch–Satterthwaite): u_c rests on three estimated noise
    variances — σ_y² (second differences, :data:`SECOND_DIFFERENCE_RHO2`), K² and B² with
    ``coef_dof`` = (ν_K, ν_B) from the Allan fit (:func:`drift_coef_power_on_dps`) — and on
    the replicates' count; each enters by its share of u_c²,
    s_i = ∂ln u_c²/∂ln v_i, a central difference (± :data:`POWER_ON_SHARE_STEP`) with the
    same random numbers. The statement is the 95 % interval of the same replicates
    (:func:`power_on_interval`): the pivot of V*'s quantiles, each side scaled by
    t₉₅(ν_eff)/z₉₅ (the replicates' quantiles are those of the fitted noise; the factor
    carries the noise estimates' own uncertainty, as t does in the GUM), not value ± U: a
    drift is non-negative, and V's distribution is skewed near 0. The contenders (details)
    are the smoothed values within 2√2·σ of the largest (σ of one smoothed value less the
    reference).

    The number of replicates is JCGM 101 7.9's adaptive procedure (:func:`power_on_adaptive`):
    two blocks of :data:`POWER_ON_MC_TRIALS` (7.9.4 f: stability is judged on the scatter of
    h ≥ 2 sequences, never on one alone), then as many more as the interval's ends need to
    be settled at the digit stated, up to :data:`POWER_ON_MC_MAX_BLOCKS`; the fitting
    decision (one transient or one per record) is the first block's."""
    cache: dict = {}                     # each block's replicates, drawn once
    first = _power_on_budget_at(recs, nr, drift_u, drift_coef, coef_dof, (0,), cache=cache)
    return power_on_adaptive(
        first, lambda blocks: _power_on_budget_at(recs, nr, drift_u, drift_coef, coef_dof,
                                                  blocks, first[4], cache))


def power_on_adaptive(first, evaluate):
    """JCGM 101 7.9.4's adaptive Monte Carlo for 5.3.3.5, reading taken. ``first``: the
    budget (value, readings, Uncertainty, contenders, fit) from block 0 alone;
    ``evaluate`` (block indices → the same from those blocks). Block 1 is always evaluated
    too (7.9.4 f: with h = 1 the procedure draws another sequence; one block's own quantile
    estimate misses the scatter ν_eff's shares add, and read it low on records the blocks
    showed unsettled), then blocks 2, 3, … one by one, each a whole budget on its own
    replicates, until :func:`power_on_block_numerical_u` of the h block results is settled
    at the digit of the budget on all h·:data:`POWER_ON_MC_TRIALS` replicates together
    (7.9.4 e: the result stated), or h reaches :data:`POWER_ON_MC_MAX_BLOCKS` (a cap of one
    block returns ``first``); that budget is returned, its ends' numerical u that of the
    blocks (every numerical source in it: the quantiles, the excess, the slope g, ν_eff's
    shares)."""
    results, out = [first], first
    if POWER_ON_MC_MAX_BLOCKS >= 2:     # 7.9.4 f: never judged on one sequence alone
        results.append(evaluate((1,)))
        out = evaluate((0, 1))
    while True:
        h = len(results)
        s = power_on_block_numerical_u([r[2].interval for r in results],
                                       [r[2].interval_numerical_u for r in results])
        more = power_on_blocks_needed(out[0], out[2].interval, s, h)
        if more <= h:
            break
        results += [evaluate((b,)) for b in range(h, more)]
        out = evaluate(tuple(range(more)))     # the blocks' replicates again, not redrawn
    if h == 1:
        return first
    return (*out[:2], replace(out[2], interval_numerical_u=s), *out[3:])


def power_on_block_numerical_u(ends, quantile_u) -> float:
    """The numerical standard uncertainty of 5.3.3.5's interval ends from h blocks of
    replicates evaluated one by one (JCGM 101 7.9.4 c: the standard deviation of the h
    block results over √h), the larger end's; never below the blocks' own quantile
    estimates ``quantile_u`` (:func:`power_on_interval_numerical_u`, their rms over √h),
    which a few blocks' standard deviation can miss by chance. ``ends``: each block's
    (lower, upper).

    >>> round(power_on_block_numerical_u([(1.0, 2.0)], [0.1]), 6)
    0.1
    >>> round(power_on_block_numerical_u([(1.0, 2.0), (1.2, 2.0), (1.1, 2.1)], [0.01] * 3), 6)
    0.057735
    """
    e = np.asarray(ends, float)
    h = e.shape[0]
    sd = float(e.std(axis=0, ddof=1).max()) if h > 1 else 0.0
    q = float(np.sqrt(np.mean(np.square(np.asarray(quantile_u, float)))))
    return max(sd, q) / math.sqrt(h)


def power_on_blocks_needed(value: float, interval, numerical_u, blocks: int) -> int:
    """JCGM 101 7.9's adaptive Monte Carlo for 5.3.3.5, reading taken: the number of blocks
    of :data:`POWER_ON_MC_TRIALS` replicates the statement needs, given the value, its
    ``interval`` and the ends' ``numerical_u`` from ``blocks`` of them. The interval is
    stated at two significant digits of its reach where the replicates settle them, at one
    at least (:func:`gonio.result.statement.state_interval`); one digit is settled where
    the ends' numerical standard uncertainty s (``numerical_u``) meets 2·s ≤ δ, δ half a
    unit of that digit (:func:`gonio.result.statement.settled_numerical_u`). Where it does
    not, the count grows as s² falls, 1/M: blocks × (s/s_settled)² × 1.5 (a margin for s's
    own scatter), at least one block more, at most :data:`POWER_ON_MC_MAX_BLOCKS`. Returns
    ``blocks`` where the digit is settled or the cap reached (the interval is then stated
    with its numerical u; where even one digit is then unsettled the statement rule widens
    the ends by 2·s and says so).

    >>> power_on_blocks_needed(0.1, (0.07, 0.13), 0.003, 1)    # one digit at 0.01: s ≤ 0.0025
    3
    >>> power_on_blocks_needed(0.1, (0.07, 0.13), 0.002, 1), power_on_blocks_needed(0.1, (0.07, 0.13), 0.02, 1)
    (1, 16)
    """
    from gonio.result.statement import settled_numerical_u

    s = numerical_u
    if blocks >= POWER_ON_MC_MAX_BLOCKS or s is None or not s > 0 or interval is None:
        return blocks
    target = settled_numerical_u(value, interval, nonnegative=True, ndig=1)
    if s <= target:
        return blocks
    return min(POWER_ON_MC_MAX_BLOCKS,
               max(blocks + 1, math.ceil(blocks * 1.5 * (s / target) ** 2)))


#: The most blocks of :data:`POWER_ON_MC_TRIALS` replicates 5.3.3.5 draws (6400 replicates;
#: each block costs about what the first does): the ends' numerical u falls as 1/√M, so the
#: cap is reached only where 400 replicates leave s about three times the settled value.
POWER_ON_MC_MAX_BLOCKS = 16


def _power_on_budget_at(recs, nr: int, drift_u, drift_coef, coef_dof, blocks, fit=None,
                        cache=None):
    """:func:`power_on_drift_budget` from the replicates of ``blocks`` (block indices,
    ``cache`` as :func:`_power_on_replicates`); the fitting decision ``fit``
    (:func:`power_on_fit_decision`) made here where None, else taken as given (the first
    block's, for the blocks that follow it)."""
    if fit is None:
        rep = _power_on_replicates(recs, nr, drift_u, drift_coef, test=True, blocks=blocks,
                                   cache=cache)
        fit = power_on_fit_decision(recs, rep)
        if rep["pooled"] and not fit["transient_one"]:
            rep = _power_on_replicates(recs, nr, drift_u, drift_coef, pooled=False,
                                       blocks=blocks, cache=cache)
    else:
        rep = _power_on_replicates(recs, nr, drift_u, drift_coef,
                                   pooled=fit["transient_one"], blocks=blocks, cache=cache)
    vals, r_hat, r_star, r_fit = rep["vals"], rep["r_hat"], rep["r_star"], rep["r_fit"]
    excess = float(r_star.mean() - r_hat)
    r_at = r_hat - float(r_fit.mean() - r_hat)
    g = (_excess_slope(rep["kept"], r_hat, r_at)
         if r_at > POWER_ON_RESOLVED * float(r_fit.std(ddof=1)) else -1.0)
    v_star = r_star - excess - g * (r_fit - r_hat)
    resid = float(v_star.mean() - r_hat)
    u_v = float(v_star.std(ddof=1))
    shares = _power_on_shares(recs, nr, drift_u, drift_coef, g, u_v, rep["pooled"], blocks,
                              cache)
    nu = power_on_dof(shares, [rep["white_dof"], *coef_dof], rep["n_mc"])
    i = int(np.argmax(vals))
    sd_i = rep["sig"][i] * math.sqrt(1.0 / rep["P"] + 1.0 / nr)
    cont = np.concatenate(rep["dists"])
    m_sel = int(np.sum(cont >= cont.max() - 2 * math.sqrt(2) * sd_i))
    src = (f"{rep['n_mc']} seeded replicates of the fitted records (c + A·e^(−t/τ)"
           f"{', one transient for all records' if rep['pooled'] else ''}, white noise σ_y, "
           "bias drift from the Allan fit)")
    u = gum(lambda v, e, b: v - e - b,
            [from_u("R", vals[i], u_v, dof=nu,
                    source="largest |Out(t) − Out,ave| over the records; u: the estimate's "
                           "spread in " + src + "; ν: Welch–Satterthwaite over σ_y², K², "
                           "B² and the replicates' count"),
             from_u("excess", excess, 0.0,
                    source="selection excess of the largest smoothed value, E*[R*] − R̂, "
                           "removed"),
             from_u("fit_bias", resid, 0.0,
                    source="residual bias of the corrected reading, E*[V*] − R̂, removed")])
    raw = vals[i] - excess - resid
    lo, hi = power_on_interval(raw, v_star - v_star.mean(), nu)
    value = max(raw, 0.0)
    # one statement: the interval of the replicates' own distribution (JCGM 101 7.7), no k,
    # its ends stated to the digits the replicates' number supports (JCGM 101 7.9)
    u = replace(u, U=hi - value, k=None, nu_eff=None, coverage_probability=0.95,
                k_source=K_SOURCE_POWER_ON, interval=(lo, hi),
                interval_numerical_u=power_on_interval_numerical_u(v_star - v_star.mean(), nu),
                interval_draws=int(v_star.size))
    return value, vals, u, m_sel, fit


#: why the power-on records were fitted as they were (:func:`power_on_fit_decision`)
POWER_ON_FIT_BASES = ("one_record", "timing_differs", "not_refuted", "refuted")


def power_on_fit_decision(recs, rep: dict) -> dict:
    """IEC 62047-20 5.3.3.5, reading taken: the pooling decision of
    :func:`power_on_drift_budget` as the item's details record it and the certificate,
    summary.txt and the DCC state it (``transient_one``: one transient fitted to all
    records, else one per power-on; ``transient_basis``, one of
    :data:`POWER_ON_FIT_BASES`: one record only, records of different length or timing
    (:func:`power_on_records_pooled` false), or the likelihood-ratio test of one transient
    not refuted / refuted at :data:`POWER_ON_POOL_LEVEL` (:func:`power_on_one_transient`);
    ``transient_test_p`` its p, None where no test was possible; ``transient_test_level``;
    ``power_on_records`` the number of records). ``rep``: the first replicates
    (:func:`_power_on_replicates` with ``test=True``)."""
    out = {"power_on_records": len(recs), "transient_test_level": POWER_ON_POOL_LEVEL,
           "transient_test_p": None}
    if not rep["pooled"]:
        return {**out, "transient_one": False,
                "transient_basis": "one_record" if len(recs) < 2 else "timing_differs"}
    one, p = power_on_one_transient(rep["lr"], rep["lr_star"])
    return {**out, "transient_one": bool(one), "transient_test_p": float(p),
            "transient_basis": "not_refuted" if one else "refuted"}


#: Relative step of the noise variances for the shares of u_c² (:func:`_power_on_shares`).
POWER_ON_SHARE_STEP = 0.2


def _power_on_shares(recs, nr: int, drift_u, drift_coef, g: float, u_v: float,
                     pooled=None, blocks=(0,), cache=None) -> list:
    """s_i = ∂ln u_c²/∂ln v_i of 5.3.3.5's u_c² = var(R* − g·R̂*) for the white, walk and
    flicker variances (in that order), by a central difference of ± :data:`POWER_ON_SHARE_STEP`
    with the same random numbers (:func:`_power_on_replicates`'s ``scale``, the same
    ``blocks``); 0 for a variance that is 0."""
    if not u_v > 0:
        return [0.0, 0.0, 0.0]
    span = float(recs[0][0][-1] - recs[0][0][0]) if recs[0][0].size > 1 else 0.0
    k2, b2 = drift_coef if drift_coef is not None else (float(drift_u(span) > 0), 0.0)
    out = []
    for j, v in enumerate((1.0, k2, b2)):
        if not v > 0:
            out.append(0.0)
            continue
        var = []
        for f in (1.0 + POWER_ON_SHARE_STEP, 1.0 - POWER_ON_SHARE_STEP):
            sc = [1.0, 1.0, 1.0]
            sc[j] = f
            rep = _power_on_replicates(recs, nr, drift_u, drift_coef, sc, pooled,
                                       blocks=blocks, cache=cache)
            var.append(float(np.var(rep["r_star"] - g * rep["r_fit"], ddof=1)))
        out.append((var[0] - var[1]) / (2.0 * POWER_ON_SHARE_STEP * u_v ** 2))
    return out


#: ``k_source`` of 5.3.3.5, stated by the interval of its replicates (:func:`power_on_interval`).
K_SOURCE_POWER_ON = ("replicates' distribution (pivot, 2.5 % each side, scaled by "
                     "t95(ν_eff)/z95, ν_eff by Welch–Satterthwaite)")


def power_on_interval(raw: float, d: np.ndarray, nu: float = math.inf,
                      p: float = 0.95) -> tuple[float, float]:
    """The 95 % interval of 5.3.3.5's drift θ ≥ 0 from the corrected estimate ``raw`` (the
    reading less the selection excess and the fit's residual bias; below 0 where the
    reading is all excess) and ``d``, the replicates of the estimate's error (V* less its
    mean): the pivot [raw − f·q_{1−α/2}(d), raw − f·q_{α/2}(d)], α = 1 − p, 2.5 % each side
    (JCGM 101 7.7, as 5.4.5.3's floor rule), each side scaled by f = t_{1−α/2}(ν)/z_{1−α/2}
    (``nu``: ν_eff of u_c, :func:`power_on_dof`; the replicates are drawn at the fitted
    noise, and f carries those estimates' uncertainty as the GUM's t does — for normal
    replicates the interval is value ± t₉₅(ν)·u_c exactly), with raw taken at 0 where it is
    below (θ ≥ 0: raising the estimate to the measurand's bound only raises the upper end)
    and the lower end at 0 where it falls below (θ ≥ 0: no probability is lost).

    >>> d = np.linspace(-1.0, 1.0, 401)
    >>> [round(x, 3) for x in power_on_interval(2.0, d)]
    [1.05, 2.95]
    >>> [round(x, 3) for x in power_on_interval(2.0, d, 4.0)]
    [0.654, 3.346]
    >>> [round(x, 3) for x in power_on_interval(-0.5, d)]
    [0.0, 0.95]
    """
    q = (1.0 + p) / 2.0
    q_lo, q_hi = np.quantile(np.asarray(d, float), [1.0 - q, q])
    f = _power_on_pivot_factor(nu, p)
    est = max(float(raw), 0.0)
    return max(est - f * float(q_hi), 0.0), est - f * float(q_lo)


def _power_on_pivot_factor(nu: float, p: float) -> float:
    """f = t_{(1+p)/2}(ν)/z_{(1+p)/2} of :func:`power_on_interval` (1 for ν infinite)."""
    from scipy.stats import norm, t as student_t

    q = (1.0 + p) / 2.0
    return float(student_t.ppf(q, nu) / norm.ppf(q)) if math.isfinite(nu) else 1.0


def power_on_interval_numerical_u(d: np.ndarray, nu: float = math.inf,
                                  p: float = 0.95) -> float:
    """The standard uncertainty of :func:`power_on_interval`'s ends from the finite number of
    replicates (:data:`POWER_ON_MC_TRIALS`): the larger of the two ends' quantile
    uncertainties (:func:`uncertainty.quantile_numerical_u`), scaled by the same factor f.
    It decides the decimal place the interval is stated at (JCGM 101 7.9: no digit a rerun
    of the replicates would change; :func:`gonio.result.statement.state_interval`).

    >>> d = np.linspace(-1.0, 1.0, 401)
    >>> round(power_on_interval_numerical_u(d), 4)    # √(0.025·0.975/401)/f, density f = ½
    0.0156
    """
    from uncertainty import quantile_numerical_u

    q = (1.0 + p) / 2.0
    s = quantile_numerical_u(np.asarray(d, float), [1.0 - q, q])
    return _power_on_pivot_factor(nu, p) * float(np.max(s))


POWER_ON_MC_TRIALS = 400
# Neither constant is a fitted one: the linearisation needs a reading well clear of the fit's
# own scatter, and a central-difference step small against the excess's curvature. On the
# built-in programme's 40 seeds every reading is resolved (g from −0.041 to −0.007), a
# threshold of 2 or 8 gives the same values, and δ = 0.05 or 0.2 moves them by ≤ 1e-4 u_c
# (docs/iec62047-20-readings.md, 5.3.3.5–5.3.3.7 diagnosis).
POWER_ON_RESOLVED = 4.0                # a transient resolved: its reading > 4 sd of R̂*
POWER_ON_SLOPE_STEP = 0.1              # δ of the excess's slope in R̂ (central difference)


def _excess_slope(kept, r_hat: float, r_at: float) -> float:
    """d(excess)/dR̂ of the selection excess E*[R*] − R̂ at the reading ``r_at`` (the fitted
    reading ``r_hat`` less the fit's bias), by a central difference ± δ =
    :data:`POWER_ON_SLOPE_STEP` with the same replicates (common random numbers): every
    fitted transient scaled by r_at/r_hat·(1 ± δ). In [−1, 0]: −1 (the excess does not
    follow the signal) where no transient is fitted or r_at ≤ 0; towards 0 where one value
    stands out."""
    if r_hat <= 0 or r_at <= 0:
        return -1.0
    s0, means = r_at / r_hat, []
    for sgn in (1.0, -1.0):
        s = s0 * (1.0 + sgn * POWER_ON_SLOPE_STEP)
        r = np.zeros(kept[0][0].shape[0])
        for dev, tr in kept:
            r = np.maximum(r, np.abs(dev + (s - 1.0) * tr[None, :]).max(1))
        means.append(float(r.mean()))
    slope = (means[0] - means[1]) / (2.0 * POWER_ON_SLOPE_STEP * r_at)
    return float(np.clip(slope - 1.0, -1.0, 0.0))
POWER_ON_MC_SEED = 6204720535           # fixed: the same records give the same value


def _transient_designs(tt: np.ndarray, n: int, P: int, nr: int):
    """Per τ on a log grid from the step to 20 record lengths: (the smoothed values of
    e^(−t/τ) over the blocks at ``tt``, its mean over the first ``nr`` samples, the design
    matrix [1, smoothed values] and its pseudo-inverse), the design of
    :func:`_transient_fits` (block and reference means of the model, not its values at the
    block centres); the pseudo-inverse is computed once here, not per fit, and so are each
    τ's reach max|e_b − e_ref| and the unit vectors of the centred e_b (the screen of
    :func:`_transient_candidates`). The same timing's design is computed once
    (:func:`functools.lru_cache` of the last 32 timings: the replicates of one budget, its
    shares' reruns and repeated budgets reuse it; read-only arrays, shared)."""
    return _transient_designs_cached(np.asarray(tt, float).tobytes(), int(n), int(P), int(nr))


@functools.lru_cache(maxsize=32)
def _transient_designs_cached(tt_bytes: bytes, n: int, P: int, nr: int):
    """:func:`_transient_designs` by the block times' bytes (hashable)."""
    return _transient_designs_new(np.frombuffer(tt_bytes, float), n, P, nr)


class _TauGrid(tuple):
    """The τ grid of :func:`_transient_designs`: a tuple of (e_b, e_ref, A, A⁺) per τ, with
    ``reach`` (each τ's max|e_b − e_ref|) and ``unit`` (rows: e_b less its mean, of unit
    norm; 0 where e_b is constant)."""

    reach: np.ndarray
    unit: np.ndarray


def _transient_designs_new(tt: np.ndarray, n: int, P: int, nr: int):
    """:func:`_transient_designs` computed afresh."""
    nb = tt.size
    dt = float(tt[1] - tt[0]) / P if nb > 1 else 1.0
    t_raw = dt * np.arange(max(n, nb * P, nr)) - 0.5 * (P - 1) * dt
    span = max(float(tt[-1] - tt[0]), dt * P)
    out, reach, unit = [], [], []
    ones = np.ones(nb)
    for tau in np.geomspace(dt * P, 20 * span, 60):
        e = np.exp(-t_raw / tau)
        eb = e[: nb * P].reshape(nb, P).mean(1)
        A = np.column_stack([ones, eb])
        A_pinv = np.linalg.pinv(A)
        for arr in (eb, A, A_pinv):
            arr.setflags(write=False)
        er = float(e[:nr].mean())
        out.append((eb, er, A, A_pinv))
        reach.append(np.max(np.abs(eb - er)))
        ec = eb - eb.mean()
        norm = float(np.sqrt(ec @ ec))
        unit.append(ec / norm if norm > 0 else np.zeros(nb))
    grid = _TauGrid(out)
    grid.reach, grid.unit = np.array(reach), np.array(unit).reshape(len(out), nb)
    for arr in (grid.reach, grid.unit):
        arr.setflags(write=False)
    return grid


#: Relative margin of :func:`_transient_candidates` (of Σy² of a row): far above the rounding
#: of either residual sum of squares (about 1e-13 of it), far below their spread over τ.
TRANSIENT_SCREEN_MARGIN = 1e-9


def _transient_candidates(Y: np.ndarray, best: np.ndarray, design) -> np.ndarray:
    """The τ of ``design`` that can win :func:`_transient_fits` for some row of ``Y``: the
    residual sum of squares of c + A·e_b is Σ(y − ȳ)² − ((y − ȳ)·ê)², ê the unit vector of
    the centred e_b (the closed form of a two-parameter least-squares fit), evaluated for
    every τ at once; a τ is kept where it is within 2·:data:`TRANSIENT_SCREEN_MARGIN`·Σy²
    of the row's least. The fit's own sums (through A⁺) differ from the closed form by
    rounding alone, far below the margin, so the τ the fit picks is always kept; the rest
    cannot be picked. τ whose e_b is constant are kept (the closed form does not see them)."""
    Yc = Y - Y.mean(1, keepdims=True)
    approx = best[:, None] - (Yc @ design.unit.T) ** 2
    margin = 2.0 * TRANSIENT_SCREEN_MARGIN * (Y * Y).sum(1)
    near = approx <= np.minimum(approx.min(1), best)[:, None] + margin[:, None]
    near |= ~np.any(design.unit, axis=1)[None, :]
    return np.flatnonzero(near.any(0))


def _transient_fits(Y: np.ndarray, design) -> list[tuple[np.ndarray, float, float]]:
    """Least-squares c + A·e^(−t/τ) through each row of ``Y`` (smoothed values), τ from
    ``design`` (:func:`_transient_designs`), A = 0 kept where no τ does better: per row
    (the model's smoothed values, its reference mean, its reading max|model − reference|).
    The τ tried are those :func:`_transient_candidates` keeps, in the grid's order, each
    fitted to every row as the full grid would be: the same τ, coefficients and bytes."""
    nrow, nb = Y.shape
    c0 = Y.mean(1)
    best = ((Y - c0[:, None]) ** 2).sum(1)
    cb, ab, kb = c0.copy(), np.zeros(nrow), np.full(nrow, -1)
    for k in _transient_candidates(Y, best, design):
        _eb, _er, A, A_pinv = design[k]
        coef = Y @ A_pinv.T                                                # (nrow, 2)
        sse = ((Y - coef @ A.T) ** 2).sum(1)
        better = sse < best
        best = np.where(better, sse, best)
        cb, ab, kb = (np.where(better, coef[:, 0], cb), np.where(better, coef[:, 1], ab),
                      np.where(better, k, kb))
    out = []
    for c, a, k in zip(cb, ab, kb):
        if k < 0:
            out.append((np.full(nb, c), float(c), 0.0))
        else:
            eb, er = design[k][:2]
            out.append((c + a * eb, float(c + a * er), float(abs(a) * design.reach[k])))
    return out


def _drift_root(nb: int, P: int, nr: int, dt: float, coef):
    """The draws of the ``nb`` smoothed values (``P`` samples of ``dt`` s each) less the
    mean of the first ``nr`` samples under the rate random walk and flicker of ``coef`` =
    (E[K²], E[B²]) are z·S, z standard normal rows, with S this function's return, the
    symmetric root of their covariance (None where neither noise is present): each value
    is a combination of four angle values, (θ(s+d) − θ(s))/d − (θ(r) − θ(0))/r, whose
    covariance is Σ c_a c_b G(|t_a − t_b|) with the five-term model's generalised
    covariance G (:func:`gonio.analysis.noise.covariance.generalised_covariance`)."""
    from gonio.analysis.noise.covariance import generalised_covariance

    k2, b2 = coef
    if k2 <= 0 and b2 <= 0:
        return None
    d, r = P * dt, nr * dt
    pts = np.concatenate([d * np.arange(nb + 1), [r]])
    M = np.zeros((nb, pts.size))
    j = np.arange(nb)
    M[j, j], M[j, j + 1] = -1.0 / d, 1.0 / d
    M[:, 0] += 1.0 / r                                   # − (θ(r) − θ(0))/r
    M[:, -1] -= 1.0 / r
    lag = np.abs(pts[:, None] - pts[None, :]) / dt
    G = generalised_covariance(lag, [0.0, 0.0, b2, k2], dt)
    return _symmetric_root(M @ G @ M.T)


def _symmetric_root(C: np.ndarray) -> np.ndarray:
    """The symmetric square root S = V √Λ Vᵀ of the covariance ``C`` (negative eigenvalues
    of rounding clipped to 0), so that z·S, z standard normal rows, has covariance C.

    Why not V √Λ (the eigenvectors scaled): its columns are whatever basis ``eigh`` returns,
    and where eigenvalues nearly coincide a change of C in its ninth digit turns that basis,
    so the same normal numbers give other draws — the Monte Carlo's replicates are then no
    longer common random numbers across two nearly equal inputs: a 1 ns change of the times
    moved 5.3.3.5's U by 4.7 %, and ν_eff's shares (central differences that scale one noise
    variance, which turns the basis) were differences of unrelated draws
    (docs/formats.md, "watermark"). S is unique and continuous in C: the same numbers give
    nearly the same draws.

    >>> C = np.array([[2.0, 1e-12], [1e-12, 2.0 + 1e-13]])
    >>> S, S2 = _symmetric_root(C), _symmetric_root(C + 1e-12 * np.eye(2)[::-1])
    >>> bool(np.allclose(S @ S, C)), float(np.abs(S - S2).max()) < 1e-11
    (True, True)
    """
    ev, V = np.linalg.eigh(0.5 * (C + C.T))
    return (V * np.sqrt(np.clip(ev, 0.0, None))) @ V.T


def _wander_root(x: np.ndarray, drift_u):
    """The symmetric root S of the covariance at times ``x`` (s from the record's start) of
    a Gaussian process of stationary increments with variogram D(s) = ``drift_u``(s)², zero
    at x = 0 — cov(w_i, w_j) = ½[D(x_i) + D(x_j) − D(|x_i − x_j|)] — so that z·S, z standard
    normal rows, are its draws; None where the covariance is zero."""
    lag = np.abs(x[:, None] - x[None, :])
    ul = np.unique(np.round(np.concatenate([lag.ravel(), x]), 9))
    Dm = {float(s): (drift_u(float(s)) ** 2 if s > 0 else 0.0) for s in ul}
    Dx = np.array([Dm[float(s)] for s in np.round(x, 9)])
    Dl = np.array([Dm[float(s)] for s in ul])[np.searchsorted(ul, np.round(lag, 9))]
    C = 0.5 * (Dx[:, None] + Dx[None, :] - Dl)
    return _symmetric_root(C) if np.any(C) else None


def startup_time(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.9, reading taken: the first time after power-on after which the
    smoothed output stays within ± ``startup_band_dps`` of the reference output (the settled
    bias: mean of the last fifth of the record); per record, the mean over the records, s.

    The literal rule reads the LAST excursion beyond the band, and the noise of the smoothed
    output adds late excursions while the transient is still within a few σ of the band: a
    one-sided, late bias (tests/test_iec_startup_tc_ratio.py measures it on the bench's
    transient). Its reading is kept per record in the details (``last_exceedance_s``). The
    time spent outside the band (the number of smoothed values beyond it × their step,
    ``count_s`` per record in the details) is the same time without noise for a transient
    that settles monotonically and, with noise, misses as many values before the crossing
    as it adds after it where the deviation is linear in t; where the transient flattens
    (the crossing time convex in the level crossed) the jitter of that level — the smoothed
    values' noise and the reference's error — still makes it late, by t''·var/2
    (:func:`startup_curvature_bias_s`, +6 to +28 s on the bench's transient). The value is
    the count less that bias, per record (:func:`startup_time_record`'s ``corrected_s``). A
    transient that leaves the band again after settling (an overshoot) is not what this
    estimate is for: the details keep both readings, and where they differ by more than the
    uncertainty the literal reading is the one to look at.

    Uncertainty: per record (:func:`startup_time_record`) the count's binomial spread and
    the reference's error (its noise and the bias drift between the crossing's neighbourhood
    and the last fifth, from the static record's Allan fit through the five-term model's
    generalised covariance, :func:`window_drift_u_dps`) through the local slope; independent
    between records (u = rms/√N); the smoothing step (rectangular ± step/2); the curvature
    correction's own uncertainty, its shape factor anywhere in [0, 2] (rectangular ± the
    mean correction; common to the records). The spread of the records' times evaluates
    the same noise and is kept in the details (``spread_s``)."""
    t, cl, un = "start-up time", "5.3.3.9", "s"
    m = _miss(ctx, "warmup", "startup_time", t, cl, un)
    if m:
        return m
    band = ctx.protocol["power_on"]["startup_band_dps"]
    recs, step = [], 0.0
    for run, tt, ys, y in _power_on_records(ctx):
        recs.append(startup_time_record(tt, ys, y, band,
                                        lambda a, b: window_drift_u_dps(ctx, a, b)))
        step = float(np.median(np.diff(tt))) if tt.size > 1 else 0.0
    if not recs or np.any(~np.isfinite(np.array([r["last_exceedance_s"] for r in recs]))):
        return not_measured("startup_time", t, cl, un, "the output never settled within the band")
    count = np.array([r["count_s"] for r in recs])
    corr = np.array([r["curvature_bias_s"] for r in recs])
    v = count - corr
    us = [r["u_s"] for r in recs]
    c_mean = float(corr.mean())
    u = gum(lambda a, b, c, d: a + b + c - d,
            [from_u("t", float(count.mean()), 0.0),
             type_b("step", 0.0, step / 2, "rectangular", source="smoothing step"),
             from_u("count", 0.0, float(np.sqrt(np.mean(np.square(us)) / v.size)), dof=DOF_U_WITHIN_10PCT,
                    source="time outside the band: the count's spread and the reference's "
                           "error (noise, bias drift) through the local slope"),
             type_b("curvature", c_mean, c_mean, "rectangular",
                    source="late bias of the count where the transient flattens, "
                           "t''·var(level)/2, removed (shape factor 0 … 2)")])
    return Item("startup_time", t, cl, un, float(v.mean()), uncertainty=u,
                details={"per_record_s": v, "band_dps": band,
                         "last_exceedance_s": np.array([r["last_exceedance_s"] for r in recs]),
                         "count_s": count, "curvature_bias_s": corr,
                         "standard_reading": standard_reading_beside(
                             "5.3.3.9", float(np.mean([r["last_exceedance_s"] for r in recs])),
                             " s",
                             ("the standard's reading, the last excursion beyond the band, "
                              "{v} (mean of %d records; without the curvature correction)"
                              % len(recs), "the time outside the band less its late bias"),
                             ("标准的读数（最后一次超出带宽的时间）{v}（%d 次记录的平均值；"
                              "未作曲率修正）" % len(recs), "带外时间减去其滞后偏差")),
                         "u_per_record_s": np.array(us),
                         "spread_s": float(v.std(ddof=1)) if v.size > 1 else None})


def standard_reading_beside(clause: str, value: float, unit_text: str, en: tuple[str, str],
                            zh: tuple[str, str]) -> dict:
    """The standard's own reading of an item whose certified value is a corrected estimate,
    decided once here for the certificate to print beside the results (labelled the
    standard's, not certified; as the optical draft's E reading beside its interval):
    ``value`` (in the item's unit), ``stated`` (3 significant digits), and the sentence in
    English and Chinese (``en``/``zh``: (the reading with ``{v}``, what is certified)).

    >>> standard_reading_beside("5.3.3.9", 141.25, " s", ("the standard's reading {v}", "x"),
    ...                         ("标准的读数 {v}", "x"))["text_en"]
    "5.3.3.9: the standard's reading 141 s; given beside, not certified (certified: x)."
    """
    v = float(value)
    stated = (np.format_float_positional(v, precision=3, unique=False, fractional=False,
                                         trim="-") if math.isfinite(v) else "—") + unit_text
    return {"clause": clause, "value": v, "stated": stated,
            "text_en": f"{clause}: {en[0].format(v=stated)}; given beside, not certified "
                       f"(certified: {en[1]}).",
            "text_zh": f"{clause}：{zh[0].format(v=stated)}；仅并列给出，不作校准结果"
                       f"（校准结果：{zh[1]}）。"}


def startup_time_by_count(tt: np.ndarray, ys: np.ndarray, y: np.ndarray, band: float,
                          drift_u) -> tuple[float, float, float]:
    """One power-on record's start-up time by the count (5.3.3.9): (time outside the band s,
    the literal last-exceedance reading s, standard uncertainty of the first s) —
    :func:`startup_time_record`'s ``count_s``, ``last_exceedance_s`` and ``u_s``; the count
    is not corrected for the transient's curvature (:func:`startup_curvature_bias_s`)."""
    r = startup_time_record(tt, ys, y, band, drift_u)
    return r["count_s"], r["last_exceedance_s"], r["u_s"]


def startup_time_record(tt: np.ndarray, ys: np.ndarray, y: np.ndarray, band: float,
                          drift_u) -> dict:
    """One power-on record's start-up time (5.3.3.9) from the smoothed values
    ``ys`` at times ``tt``, the raw samples ``y`` (°/s) and ``drift_u`` ((start s, duration
    s), (start s, duration s) from the record's start → standard uncertainty °/s of the
    difference of the bias drift's means over the two windows).

    With d_j = |ys_j − ref| (ref the mean of the last fifth), P the step, σ_b the noise of one
    smoothed value (√(var Δ²ys/6): a transient smooth on the step does not enter it) and
    N(L) the number of d_j > L: the estimate is P·N(band). Near the crossing the deviation
    falls with slope s, so each value is beyond the band with probability Φ((t* − t_j)s/σ_b)
    and var N = Σ p(1 − p) = σ_b/(sP)·∫Φ(1 − Φ) = σ_b/(sP√π). The reference's error e (its
    own noise u_ref, and the bias drift u_drift) moves the crossing by e/s; 1/s is
    :func:`crossing_slope_s_per_dps`, the time between the crossings of band ± h near the
    crossing, h = 2√(σ_b² + u_ref²). u_drift is ``drift_u`` of the window of that width
    centred on the crossing (the part of the drift the crossing's values share; faster
    parts are in σ_b) against the last fifth: for a rate random walk K²(Δ + (w + L)/3), and
    the flicker's difference, which grows as ln of the separation (IEEE 952 C.1), not its
    adjacent-record floor. u² = P·σ_b/(s√π) + (u_ref² + u_drift²)/s²."""
    n5 = max(y.size // 5, 1)
    ref = float(y[-n5:].mean())
    d = np.abs(ys - ref)
    t_lit = rg.last_exceedance_time(tt, d, band)
    step = float(np.median(np.diff(tt))) if tt.size > 1 else 0.0
    s_b = float(np.std(np.diff(ys, 2), ddof=1) / math.sqrt(6)) if ys.size > 3 else 0.0
    t_c = step * float(np.count_nonzero(d > band))
    tail = ys[-max(ys.size // 5, 1):]
    u_ref = s_b / math.sqrt(tail.size)
    span = tail.size * step                           # the last fifth's duration
    end = float(tt[-1] - tt[0]) + step                # the record's duration
    out = {"count_s": t_c, "last_exceedance_s": t_lit, "u_s": 0.0, "slope_s_per_dps": 0.0,
           "level_var_dps2": 0.0, "curvature_bias_s": 0.0, "corrected_s": t_c}
    if step == 0:                                     # one smoothed value: nothing to read
        return out
    h = 2 * math.sqrt(s_b ** 2 + u_ref ** 2) or \
        2 * drift_u((max(min(t_c, end - span - step), 0.0), step), (end - span, span))
    if h == 0:                                        # no noise and no drift: no spread
        return out
    slope_t = crossing_slope_s_per_dps(tt - tt[0], d, band, h, s_b, step)
    w = max(2 * h * slope_t, step)                    # the crossing's neighbourhood, s
    a = max(min(t_c - w / 2, end - span - w), 0.0)
    u_dr = drift_u((a, w), (end - span, span))
    var = s_b ** 2 + u_ref ** 2 + u_dr ** 2
    bias, corrected = startup_curvature_corrected_s(t_c, slope_t, band, var)
    out.update(u_s=math.sqrt(step * s_b * slope_t / math.sqrt(math.pi)
                             + slope_t ** 2 * (u_ref ** 2 + u_dr ** 2)),
               slope_s_per_dps=slope_t, level_var_dps2=var, curvature_bias_s=bias,
               corrected_s=corrected)
    return out


def startup_curvature_corrected_s(count_s: float, slope_s_per_dps: float, band: float,
                                  level_var_dps2: float) -> tuple[float, float]:
    """5.3.3.9, one record: (the curvature correction applied s, the corrected start-up time
    s) from the count ``count_s`` — the reading of where the correction applies (the
    standard has none; gonio's one function for it). The correction t''·var/2
    (:func:`startup_curvature_bias_s`) is the second-order term of the crossing time's
    expectation under the level's jitter (the Taylor expansion of JCGM 100 5.1.2's note;
    E[t(L + e)] ≥ t(L) for a convex t, Jensen, as JCGM 101 propagates it): it exists only
    where the record has a crossing. A record whose smoothed values never leave the band
    (count 0 s) has none: its start-up time is stated 0 s, uncorrected (no value of the
    record lay outside the band; the correction is 0 and enters no budget). Where a
    crossing exists the correction is applied but never below 0 s: a start-up time is not
    negative, and the correction is capped at the count (the record's corrected time 0 s).

    >>> startup_curvature_corrected_s(0.0, 1041.0, 0.05, 0.011 ** 2 + 0.0095 ** 2)
    (0.0, 0.0)
    >>> b, c = startup_curvature_corrected_s(130.0, 150 / 0.05, 0.05, 0.0095 ** 2 + 0.011 ** 2)
    >>> round(b, 2), round(c, 2)
    (6.34, 123.66)
    >>> startup_curvature_corrected_s(10.0, 3000.0, 0.05, 0.04 ** 2)
    (10.0, 0.0)
    """
    if count_s <= 0.0:
        return 0.0, 0.0
    bias = min(startup_curvature_bias_s(slope_s_per_dps, band, level_var_dps2), count_s)
    return bias, count_s - bias


def startup_curvature_bias_s(slope_s_per_dps: float, band: float, level_var_dps2: float) -> float:
    """The late bias (s) of 5.3.3.9's count (and of any reading of the crossing) on a
    transient that flattens, reading taken: the time t(L) at which the deviation d(t) from
    the settled output crosses a level L is convex in L (t'' = d''/|d'|³ > 0 for a
    deviation that decays and flattens), and the level actually crossed is jittered — each
    smoothed value's noise σ_b and the reference's error (its noise u_ref and the bias
    drift u_drift between the crossing and the last fifth) move it by e with
    var e = ``level_var_dps2`` —, so E[t(band + e)] − t(band) = t''·var e/2 (second order;
    for the count with white noise the same, ∫ of the noise's step against the curvature).
    t'' is read from the slope, t'' = ρ·|t'|/band with |t'| = 1/s (``slope_s_per_dps``,
    :func:`crossing_slope_s_per_dps`) and ρ = band·d''/d'² at the crossing, the transient's
    shape factor: ρ = 1 for a first-order (exponential) settling to the reference, the
    power-on transient IEC 62047-20 5.3.3.5 describes and the bench's A·e^(−t/τ) (t(L) =
    τ ln(A/L), t'' = τ/L²); 0 for a ramp, 2 for a 1/t decay. The correction takes ρ = 1;
    its own uncertainty, ρ anywhere in [0, 2], is ± the correction, rectangular
    (:func:`startup_time`). On the bench's transient (0.12 °/s, τ 150 s, band 0.05 °/s,
    10-s smoothing) with its noise the count read +6 to +28 s late (the walk × 1 to × 3);
    this is 6.5 s at the generator's noise (σ_b 0.0095 °/s, u_drift 0.011 °/s).

    >>> round(startup_curvature_bias_s(150 / 0.05, 0.05, 0.0095 ** 2 + 0.011 ** 2), 2)
    6.34
    """
    if not (band > 0) or not (slope_s_per_dps >= 0) or not (level_var_dps2 >= 0):
        return 0.0
    return slope_s_per_dps * level_var_dps2 / (2.0 * band)


def crossing_slope_s_per_dps(x: np.ndarray, d: np.ndarray, band: float, h: float, s_b: float,
                             step: float) -> float:
    """1/s (s per °/s) of the deviation ``d`` (°/s, at times ``x`` s from the record's start,
    ``step`` apart) where it crosses ``band``: the time between its crossings of band ± h,
    read by counts as the start-up time is, P·(N(band − h) − N(band + h))/(2h), counting only
    the values up to t_c + 2Δ₊ + 3(σ_b/h)Δ₊ — t_c = P·N(band), Δ₊ = P·(N(band) −
    N(band + h)) ≥ P the upper half's time (≈ h/s; values that far above the band are not
    reached by the settled output's noise), so the window holds the lower crossing at twice
    the upper half's time (a transient that flattens, e.g. 1.26× for e^(−t/τ) at h = 0.39
    band) and three standard deviations of its jitter, σ_b/s. Counting over the whole record
    took in the settled part's excursions beyond band − h (the noise and the bias drift
    relative to the reference reach it: on the study bench 5 values a record on average,
    +50 % on 1/s and on every term it propagates)."""
    n_up = np.count_nonzero(d > band + h)
    dp = max(step * float(np.count_nonzero(d > band) - n_up), step)
    t_c = step * float(np.count_nonzero(d > band))
    keep = x < t_c + 2 * dp + 3 * (s_b / h) * dp
    return step * float(np.count_nonzero((d > band - h) & keep)
                        - np.count_nonzero((d > band + h) & keep)) / (2 * h)


# --------------------------------------------------------------------------- added items
def _drift_varies(ctx: Context) -> bool:
    """Whether the static record (5.4) the drift terms come from varies; a GonioError naming
    what is missing when there is none of at least 100 samples or no a_BASE to convert it."""
    why = ("the budget's bias-drift term needs the static noise record (5.4) of at least "
           "100 samples")
    if not ctx.has("static"):
        raise GonioError(f"{why}; the readings have none")
    if ctx.a_base is None:
        raise GonioError(f"{why} and the scale factor of 5.1.3.1")
    size, varies = _static_extent(ctx)
    if size < 100:
        raise GonioError(f"{why}; it has {size} samples")
    return bool(varies)


def drift_u_dps(ctx: Context, separation_s: float) -> float:
    """Standard uncertainty (°/s) of a bias difference between two records ``separation_s``
    apart from the calibration's own static record (5.4): the rate random walk √(E[K²]·Δt)
    and the bias instability's flicker at the adjacent records' floor, √2·0.664·√E[B²]
    (IEEE 952 C.1: the walk's Allan variance K²τ/3, the flicker's (2 ln 2/π)B²), with E[K²]
    and E[B²] of :func:`drift_coef_dps` — the one rule for the walk of every IEC item.
    Without a static record of at least 100 samples the term is not known, never 0: a
    GonioError, so the item is "not measured" with the reason. A record that does not vary
    comes only from a noise-free bench (``noise: off``; the reader refuses it otherwise):
    its drift term is 0."""
    k2, b2 = drift_coef_dps(ctx)
    return math.sqrt(k2 * abs(float(separation_s)) + 2.0 * rg.FLICKER_FLOOR_EXACT ** 2 * b2)


def window_drift_u_dps(ctx: Context, first: tuple[float, float],
                       second: tuple[float, float]) -> float:
    """Standard uncertainty (°/s) of the difference of the bias drift's means over two windows
    of one record, ``first`` and ``second`` = (start s, duration s): the rate random walk and
    the flicker of :func:`drift_coef_dps` through the five-term model's generalised
    covariance (:func:`gonio.specs._rate_family.formulas.record_difference_u_coef`; IEEE 952
    C.1: the flicker's difference grows as ln of the separation). The same refusals as
    :func:`drift_u_dps`; a record that does not vary: 0."""
    if not _drift_varies(ctx):
        return 0.0
    k2, b2 = drift_coef_dps(ctx)
    return rg.record_difference_u_coef(k2, b2, first, second)


def visit_drift_u_dps(ctx: Context, separation_s: float) -> float:
    """Standard uncertainty (°/s) of the difference of two bias_temperature visits' means
    ``separation_s`` apart (mid-time to mid-time), each of the protocol's ``bias_samples``:
    the rate random walk and the flicker of :func:`drift_coef_dps` through the five-term
    model's generalised covariance
    (:func:`gonio.specs._rate_family.formulas.record_difference_u_coef`): the flicker part
    grows as ln of the separation (IEEE 952 C.1), where :func:`drift_u_dps` holds it at the
    adjacent records' floor — hours apart, about twice too small."""
    if not _drift_varies(ctx):
        return 0.0
    d = ctx.protocol["temperature"]["bias_samples"] * ctx.protocol["protocol"]["sample_interval_s"]
    k2, b2 = drift_coef_dps(ctx)
    sep = abs(float(separation_s))
    return rg.record_difference_u_coef(k2, b2, (0.0, d), (sep, d))


def walk_k2_bound_dps(ctx: Context) -> float:
    """The largest rate random walk K² ((°/s)²/s) the static record (5.4) allows, by
    :func:`gonio.specs.iec62047_20.formulas.walk_coefficient_bound` (min over τ of the 95 %
    one-sided χ² limits σ̂(τ)²·ν/χ²_0.05(ν)·3/τ). Not finite when no τ bounds it."""
    key = ("walk_k2_bound", ctx.a_base, ctx.null_output)
    if key not in ctx.cache:
        allan = _static(ctx)[0]
        ctx.cache[key] = ief.walk_coefficient_bound(allan.tau_s, allan.adev, allan.edf) \
            / S_PER_H ** 2
    return ctx.cache[key]


def walk_likelihood_inputs(ctx: Context) -> dict:
    """:func:`walk_likelihood_inputs_of` the static record (5.4) and its five-term fit."""
    return walk_likelihood_inputs_of(_static(ctx)[0], _noise_fit(ctx))


def walk_likelihood_inputs_of(allan, fit) -> dict:
    """The arguments of :func:`gonio.specs.iec62047_20.formulas.walk_k2_iec` from an Allan
    result and its five-term fit, in the record's rate unit squared (and per s): the Allan
    variances, the edf of the walk's own noise type at each τ (Greenhall, α = −2), the
    five-term fit's other terms (quantisation, white noise, bias instability, ramp) at each τ, the walk's response τ/3 (IEEE 952 C.1),
    the fitted K̂², and the covariance of the variance estimates across τ under the fitted
    model (:func:`gonio.analysis.noise.covariance.variance_covariance`)."""
    from gonio.analysis.noise.fit import design_matrix, edf_memo

    ok = np.isfinite(allan.adev) & (allan.adev > 0)
    tau, m = np.asarray(allan.tau_s[ok], float), np.asarray(allan.m[ok], np.int64)
    kind = allan.kind
    a_full = design_matrix(tau, kind, allan.tau0_s)
    coef = np.array([0.0 if not math.isfinite(float(x)) else float(x) ** 2
                     for x in (fit.Q, fit.N, fit.B, fit.K, fit.R)])
    n_phase = allan.n_phase or (allan.n_samples + (0 if allan.input_type == "angle" else 1))
    nu = np.asarray(edf_memo(kind, n_phase, m, np.full(m.size, -2, dtype=np.int64)), float)
    cov = variance_covariance("hdev" if kind == "hdev" else "adev", m,
                              np.asarray(allan.n_pairs[ok], np.int64), allan.tau0_s, coef)
    return {"avar": np.asarray(allan.adev[ok], float) ** 2, "edf": nu,
            "other_avar": a_full @ np.r_[coef[:3], 0.0, coef[4]], "k_column": a_full[:, 3],
            "k2_fit": float(coef[3]), "cov": cov}


def drift_coef_dps(ctx: Context) -> tuple[float, float]:
    """(E[K²] (°/s)²/s, E[B²] (°/s)²) of the bias drift, the ONE rule of every IEC 62047-20
    item whose budget carries the drift as a standard uncertainty (5.1.3 slope and
    linearity, 5.3.3.3, 5.3.3.6, 5.3.3.7, 5.3.3.8, 5.3.3.9): the rate random walk by
    :func:`gonio.specs.iec62047_20.formulas.walk_k2_iec` — reading taken: the posterior
    mean of K² given the static record's Allan variances with their χ² distributions and
    the walk's edf, the other terms as fitted, the τ's correlation by the magnitude-adjusted
    composite likelihood (:func:`walk_likelihood_inputs`), K uniform up to the record's
    99.99 % limit; the flicker as B̂² + u_B². The standard itself states no drift term
    (5.3.3 reads each item from its own records), so the rule is gonio's reading,
    documented in docs/iec62047-20-readings.md. 5.3.3.5's bootstrap draws its replicates
    at this E[K²] and the fitted B̂² (:func:`drift_coef_power_on_dps`). Where the posterior has no finite mean (no usable τ), the
    record's 95 % bound, else the fitted K̂², else refused (never 0 by default). The same
    refusals as :func:`drift_u_dps`; a record that does not vary: (0, 0)."""
    if not _drift_varies(ctx):
        return 0.0, 0.0         # a noise-free bench (the reader refuses a stuck record)
    key = ("drift_coef", ctx.a_base, ctx.null_output)
    if key not in ctx.cache:
        fit = _noise_fit(ctx)
        b = float(fit.B) if math.isfinite(float(fit.B)) else 0.0
        ub = float(fit.u_B) if math.isfinite(float(fit.u_B)) else 0.0
        k2 = ief.walk_k2_iec(**walk_likelihood_inputs(ctx)) / S_PER_H ** 2  # (°/s)²/s
        if not math.isfinite(k2):   # no posterior (no τ usable): the record's 95 % bound,
            k2 = walk_k2_bound_dps(ctx)       # else the fit's K̂² — never 0 by default
        if not math.isfinite(k2):
            k2 = float(fit.K) ** 2 / S_PER_H ** 2 if math.isfinite(float(fit.K)) else math.nan
        if not math.isfinite(k2):
            raise GonioError("the static record (5.4) bounds no rate random walk: no τ of "
                             "its Allan deviation is usable, so the drift term has no E[K²]")
        ctx.cache[key] = (k2, (b * b + ub * ub) / S_PER_H ** 2)
    return ctx.cache[key]


def drift_coef_power_on_dps(ctx: Context) -> tuple[tuple[float, float], tuple[float, float]]:
    """((K² (°/s)²/s, B² (°/s)²), (ν_K, ν_B)): the bias drift 5.3.3.5's parametric bootstrap
    (JCGM 101 style) draws its replicates from, with the degrees of freedom of each for its
    ν_eff (:func:`power_on_dof`). The walk: E[K²] of the one rule (:func:`drift_coef_dps`,
    the posterior mean given the static record) — the replicates' variance is linear in K²,
    so drawing at E[K²] propagates K's state of knowledge where the record does not resolve
    the walk (the fitted K̂ is then 0 in about half the study's records, and a walk drawn at
    K̂ = 0 leaves the bench's walk out of u_c); ν_K = K̂²/(2u_K²) of the five-term fit where
    it resolves K̂ (K̂ > u_K), else 1. The flicker: the fit's B̂² (resolved on any record
    this item meets: B̂/B 0.74–1.19 on 90 study records), ν_B = B̂²/(2u_B²). The same
    refusals as :func:`drift_u_dps`; a record that does not vary: ((0, 0), (∞, ∞))."""
    if not _drift_varies(ctx):
        return (0.0, 0.0), (math.inf, math.inf)
    fit = _noise_fit(ctx)

    def ok(x):
        return abs(float(x)) if math.isfinite(float(x)) else 0.0

    def dof(x, ux):                     # ν of x² from u(x); an unresolved x: 1
        if not x > ux:
            return 1.0
        return x * x / (2.0 * ux * ux) if ux > 0 else math.inf
    k2 = drift_coef_dps(ctx)[0]
    b = ok(fit.B)
    return (k2, b * b / S_PER_H ** 2), (max(dof(ok(fit.K), ok(fit.u_K)), 1.0),
                                        max(dof(b, ok(fit.u_B)), 1.0))


def _bias_temperature_points(ctx: Context):
    """(T, B °/s, u(B) °/s, ν, mid-time s) of every bias_temperature visit, in visit order."""
    key = ("bt", ctx.a_base, ctx.null_output)
    if key in ctx.cache:
        return ctx.cache[key]
    kmap = {round(c["T"], 6): c["a"] for c in _sf_runs(ctx, "sf_temperature")} \
        if ctx.has("sf_temperature") else {}
    out = []
    for s in segment_means(ctx.df, "bias_temperature"):
        a = kmap.get(round(s.temperature_c, 6), ctx.a_base)
        earth = rg.earth_rate_projection_dps(ctx.latitude_deg, input_axis_enu(s.up_axis, s.north_axis))
        y = segment_samples(ctx.df, "bias_temperature", s.run, s.step)["output"].to_numpy()
        nb = y.size // 10
        if nb >= 2:
            um, nu = float(y[: nb * 10].reshape(nb, 10).mean(1).std(ddof=1) / math.sqrt(nb)), nb - 1
        else:
            um, nu = s.std / math.sqrt(s.n), max(s.n - 1, 1)
        out.append((s.temperature_c, (s.mean - ctx.null_output) / a - earth, um / abs(a), nu,
                    s.time_s + 0.5 * s.n))
    ctx.cache[key] = out
    return out


def bias_hysteresis(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.7: the largest difference between the biases at one temperature on
    the rising and the falling pass (:func:`gonio.specs.iec62047_20.formulas.hysteresis_iec`: a
    visit is "up" when reached from below, "down" from above), °/s.

    Two readings, both kept: the standard's, the largest |B_up − B_down| itself
    (``reading_iec_dps`` in the details), and the value stated, that reading less the
    midpoint of the selection excess of a maximum over n noisy differences (JCGM 100 4.3.7:
    between 0 when one temperature's true difference stands clear and c_m·σ when m share
    the largest; :func:`gonio.specs._rate_family.formulas.selection_excess`), the term
    rectangular ± c_m·σ/2. u_c: that term, the two record means (block type A) and the bias
    drift between the two visits (:func:`visit_drift_u_dps`). Statement: one interval,
    [0, the one-sided 95 % upper limit of the largest true difference] from the reading's
    own distribution (:func:`gonio.specs.iec62047_20.formulas.hysteresis_upper_iec`), no k:
    a maximum of |·| whose truth may be 0 (a chamber without lag) has no symmetric ± U."""
    t, cl, un = "bias hysteresis", "5.3.3.7", "°/s"
    m = _miss(ctx, "bias_temperature", "bias_hysteresis", t, cl, un)
    if m:
        return m
    pts = _bias_temperature_points(ctx)
    drift = lambda sep: visit_drift_u_dps(ctx, sep)  # noqa: E731
    val, diffs, Tm, u = hysteresis_budget(pts, drift)
    reading = max(abs(v) for v in diffs.values())
    return Item("bias_hysteresis", t, cl, un, val, uncertainty=u, details={
        "up_minus_down_dps": diffs, "temperature_c": Tm,
        # the statement's level z against the largest true difference (for a study)
        "level_z_grid": ief.hysteresis_level_grid(reading, hysteresis_sds(pts, drift),
                                                  u.interval[1]),
        "reading_iec_dps": max(abs(v) for v in diffs.values()),
        "standard_reading": standard_reading_beside(
            "5.3.3.7", max(abs(v) for v in diffs.values()), " °/s",
            ("the standard's reading max |B_up − B_down| = {v}",
             "that reading less the midpoint of a maximum's selection excess"),
            ("标准的读数 max |B_up − B_down| = {v}", "该读数减去最大值选择超出量的中点"))})


def _visit_pairs(T) -> list[tuple[int, int]]:
    """(rising, falling) visit indices of each temperature visited both ways, in the order
    of :func:`gonio.specs.iec62047_20.formulas.hysteresis_iec`'s differences."""
    _, diffs = ief.hysteresis_iec(T, [0.0] * len(T))
    return [(max(i for i in range(1, len(T)) if T[i] == Tv and T[i] > T[i - 1]),
             max(i for i in range(1, len(T)) if T[i] == Tv and T[i] < T[i - 1])) for Tv in diffs]


def hysteresis_sds(pts, drift_u) -> list[float]:
    """5.3.3.7: σ of each difference B_up − B_down (the two record means and the bias drift
    between the visits, ``drift_u`` of their separation), in the differences' order."""
    T = [p[0] for p in pts]
    return [math.sqrt(pts[ju][2] ** 2 + pts[jd][2] ** 2 + drift_u(pts[ju][4] - pts[jd][4]) ** 2)
            for ju, jd in _visit_pairs(T)]


def hysteresis_budget(pts, drift_u) -> tuple[float, dict, float, Uncertainty]:
    """5.3.3.7 from the visits ``pts`` ((T °C, B °/s, u(B) °/s, ν, mid-time s) in visit
    order) and ``drift_u`` (separation s → standard uncertainty °/s of the bias drift):
    (value, {T: B_up − B_down}, the temperature of the largest, its Uncertainty stated by
    the interval [0, upper] of :func:`gonio.specs.iec62047_20.formulas.hysteresis_upper_iec`
    with each difference's σ from its two record means and the drift between them)."""
    T = [p[0] for p in pts]
    val, diffs = ief.hysteresis_iec(T, [p[1] for p in pts])

    def visits(Tv):
        return (max(i for i in range(1, len(T)) if T[i] == Tv and T[i] > T[i - 1]),
                max(i for i in range(1, len(T)) if T[i] == Tv and T[i] < T[i - 1]))

    Tm = max(diffs, key=lambda k: abs(diffs[k]))
    pu, pd_ = (pts[i] for i in visits(Tm))
    inputs = [from_u("B_up", pu[1], pu[2], dof=pu[3], source=f"rising visit at {Tm:g} °C"),
              from_u("B_down", pd_[1], pd_[2], dof=pd_[3], source=f"falling visit at {Tm:g} °C"),
              from_u("drift", 0.0, drift_u(pu[4] - pd_[4]), dof=DOF_U_WITHIN_10PCT,
                     source="bias drift between the visits (Allan fit: RRW, BI)")]
    # the value is a maximum over the temperatures visited twice: noise inflates it
    sds = hysteresis_sds(pts, drift_u)
    excess, _ = rg.selection_excess(np.abs(np.array(list(diffs.values()))), np.array(sds))
    inputs.append(type_b("noise_max", -excess, excess, "rectangular",
                         source="selection excess of the largest of the noisy differences "
                                "over the temperatures visited twice (midpoint ± c_m·σ/2 "
                                "removed)"))
    u = gum(lambda a, b, d, mx: abs(a - b + d) + mx, inputs)
    # stated by one interval from the reading's own distribution (a maximum of |·| whose
    # truth may be 0): [0, the one-sided 95 % upper limit], no k
    hi = ief.hysteresis_upper_iec(val, sds, 0.95)
    v = val - excess
    return v, diffs, Tm, replace(u, U=hi - v, k=None, nu_eff=None, coverage_probability=0.95,
                                 k_source="folded-normal maximum", interval=(0.0, hi))


def bias_ratiometric(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.3 eq (26): with the rest outputs a_Vi (the bias in output units, null
    included) of the supply runs of 5.1.3.5, R_Vi = [a_Vi − a_BASE·V_i/V_BASE]/a_BASE; the
    largest |R_Vi| in %, and (reading taken: Table 4's unit V) the absolute departure
    a_Vi − a_BASE·V_i/V_BASE in output units in the details. Analog ratiometric outputs only.

    Uncertainty: the noise of the two rest means (block type A), the bias drift between
    them (RRW, bias instability from the static record, through the five-term model's
    covariance of the two rest windows, :func:`window_drift_u_dps`: the runs are minutes
    apart, where the flicker's difference has grown past the adjacent records' floor that
    :func:`drift_u_dps` holds — 22 % more on the demo's 520 s), and the selection excess of the
    largest |R_Vi| over the supplies (JCGM 100 4.3.7, the rule of 5.3.3.5 and 5.3.3.7,
    :func:`gonio.specs._rate_family.formulas.selection_excess`): a supply below and one above
    V_BASE usually carry departures of equal size and opposite sign (a bias linear in V), so
    noise raises the larger |R| by up to c_m·σ; the value is the reading less the midpoint
    c_m·σ/2, the term rectangular ± c_m·σ/2."""
    t, cl, un = "bias ratiometric error (max |R|)", "5.3.3.3", "%"
    m = _miss(ctx, "ratiometric", "bias_ratiometric_error", t, cl, un)
    if m:
        return m
    runs = _sf_runs(ctx, "ratiometric")
    V = np.array([c["V"] for c in runs])
    a, ua, window = [], [], []
    dt = float(ctx.protocol["protocol"]["sample_interval_s"])
    for c in runs:
        k = np.flatnonzero(c["x"] == 0)
        if k.size != 1:
            raise GonioError(f"ratiometric run {c['run']}: needs exactly one rest point (0 °/s)")
        a.append(float(c["y"][k[0]]))
        ua.append(float(c["u_y"][k[0]]))
        window.append((float(c["t"][k[0]]), float(c["n"][k[0]]) * dt))    # (start s, span s)
    a = np.array(a)
    ib = int(np.argmin(np.abs(V - ctx.v_base)))
    R = np.array([ief.ratiometric_error_iec(a[i], a[ib], V[i], V[ib]) for i in range(V.size)])

    def inputs(i):
        u_dr = window_drift_u_dps(ctx, window[i], window[ib]) * abs(ctx.a_base)  # output units
        return [from_u("a_Vi", a[i], ua[i], dof=DOF_U_WITHIN_10PCT, source=f"rest output at {V[i]:g} V"),
                from_u("a_Vb", a[ib], ua[ib], dof=DOF_U_WITHIN_10PCT, source=f"rest output at {V[ib]:g} V"),
                from_u("drift", 0.0, u_dr, dof=DOF_U_WITHIN_10PCT,
                       source="bias drift between the two rest points (Allan fit: RRW, BI)")]

    def model(i):
        return lambda ai, ab, d: 100 * ief.ratiometric_error_iec(ai + d, ab, V[i], V[ib])

    others = [j for j in range(V.size) if j != ib] or [ib]
    pts = [gum(model(j), inputs(j)) for j in others]
    sds = [q.u_c for q in pts]
    pct = np.abs(100 * R[others])
    i = others[int(np.argmax(pct))]
    excess, m_sel = rg.selection_excess(pct, np.array(sds))
    u = gum(lambda ai, ab, d, mx: abs(model(i)(ai, ab, d)) + mx,
            inputs(i) + [type_b("noise_max", -excess, excess, "rectangular",
                                source="selection excess of the largest |R| over the supplies "
                                       "(midpoint ± c_m·σ/2 removed)")])
    # one statement: the interval of the extreme of magnitudes (never value ± U of |·|)
    value, u, iv = max_magnitude_statement(u, 100 * R[others], pts,
                                           100 * abs(float(R[i])) - excess)
    return Item("bias_ratiometric_error", t, cl, un, value,
                uncertainty=u,
                details={"V": V, "rest_output": a, "R_pct": 100 * R, "reading_pct": float(pct.max()),
                         "contending_values": m_sel,
                         "departure_output_units": a - a[ib] * V / V[ib], **iv})


def g_sensitivity(ctx: Context) -> Item:
    """IEC 62047-20 5.3.3.8 on the tilting stand (5.3.4.5), readings taken: the acceleration
    along the input axis is g cos γ (γ = 0 at input axis up; eq (28)'s sin γ holds only for γ
    from the horizontal); the Earth-rate projection at each angle is removed first. Parallel
    set-up (run 0): slope Out,gp of ω against g cos γ (the transverse g sin γ fitted jointly);
    perpendicular set-up (run 1, input axis horizontal, the stand turning about it): Out,gv
    = the larger of the slopes against the two transverse components g cos γ, g sin γ. The
    characteristic is max(|Out,gp|, |Out,gv|), (°/s)/g.

    Uncertainty: the slope's least-squares standard error (ν = points − 3), the bias drift
    over the turn (correlated from angle to angle, so the residuals miss it) projected on
    the regressor (:func:`slope_drift_projection_u_dps`), and a_BASE's relative u_c with its ν (:func:`_e_a`; the rate table's
    line alone was a part of it, of ν = ∞)."""
    t, cl, un = "linear g sensitivity", "5.3.3.8", "(°/s)/g"
    m = _miss(ctx, "g_sensitivity", "g_sensitivity", t, cl, un)
    if m:
        return m
    from gonio.physics.alignment import body_rotation, mount_matrix
    res = {}
    for run, name in ((0, "parallel"), (1, "perpendicular")):
        seg = [s for s in segment_means(ctx.df, "g_sensitivity") if s.run == run]
        if len(seg) < 4:
            continue
        w, e, a1, a2 = [], [], [], []
        for s in seg:
            g = segment_samples(ctx.df, "g_sensitivity", s.run, s.step)
            gam, axis = float(g["stand_deg"].iloc[0]), str(g["stand_axis"].iloc[0])
            R = mount_matrix(s.up_axis, s.north_axis) @ body_rotation(axis, gam)
            fb = R.T @ np.array([0.0, 0.0, 1.0])              # specific force, body axes, g
            w.append((s.mean - ctx.null_output) / ctx.a_base)
            e.append(rg.earth_rate_projection_dps(ctx.latitude_deg, R @ np.array([0, 0, 1.0])))
            a1.append(fb[2] if name == "parallel" else fb[0])   # along the input axis / body x
            a2.append(fb[1])                                      # the other transverse one
        w, e, a1, a2 = map(np.array, (w, e, a1, a2))
        s1, s2 = ief.g_slope_iec(a1, w, e, a2)
        A = np.column_stack([np.ones_like(a1), a1, a2])
        r = (w - e) - A @ np.linalg.lstsq(A, w - e, rcond=None)[0]
        dof = max(w.size - 3, 1)
        cov = float(r @ r) / dof * np.linalg.inv(A.T @ A)
        k = 1 if name == "parallel" or abs(s1) >= abs(s2) else 2
        u_dr = slope_drift_projection_u_dps(ctx, seg, A, k)
        res[name] = ((s1, s2)[k - 1], math.sqrt(cov[k, k]), dof, u_dr)
    if not res:
        return not_measured("g_sensitivity", t, cl, un, "no tilting-stand set-up with ≥ 4 angles")
    key = max(res, key=lambda k: abs(res[k][0]))
    v, se, dof, u_dr = res[key]

    def point(name):        # the signed slope of one set-up with its budget
        s_, se_, dof_, u_dr_ = res[name]
        return gum(lambda s, d, e: (s + d) * (1 + e),
                   [from_u("slope", s_, se_, dof=dof_, source=f"least-squares slope ({name})"),
                    from_u("drift", 0.0, u_dr_, dof=DOF_U_WITHIN_10PCT,
                           source="bias drift over the turn projected on the regressor "
                                  "(the slope's weights on the records' windows under the "
                                  "walk and flicker of the static record)"),
                    _e_a(ctx)])

    names = list(res)
    pts = [point(n) for n in names]
    # a magnitude, max(|Out,gp|, |Out,gv|): the interval of the extreme of magnitudes
    value, u, iv = max_magnitude_statement(pts[names.index(key)], [res[n][0] for n in names],
                                           pts, abs(v))
    return Item("g_sensitivity", t, cl, un, value, uncertainty=u, details={**iv,
        "out_gp_dps_per_g": res.get("parallel", (math.nan,))[0],
        "out_gv_dps_per_g": res.get("perpendicular", (math.nan,))[0], "set_up": key})


def slope_drift_projection_u_dps(ctx: Context, seg, A: np.ndarray, col: int) -> float:
    """Standard uncertainty (°/s per regressor unit) that the bias drift gives the
    least-squares coefficient ``col`` of the design ``A`` (an intercept column first) fitted
    to the means of the records ``seg`` (:class:`SegmentMean`, each from its ``time_s`` for
    its ``n`` samples): the coefficient is Σ c_i·m_i with c the row of (AᵀA)⁻¹Aᵀ, Σ c_i = 0
    (the intercept takes the level), so its drift part has the variance of that combination
    of window means under the rate random walk and flicker of :func:`drift_coef_dps`
    (:func:`gonio.specs._rate_family.formulas.window_combination_u_coef`, the five-term
    model's generalised covariance; IEEE 952 C.1). The same refusals as
    :func:`drift_u_dps`; a record that does not vary: 0."""
    if not _drift_varies(ctx):
        return 0.0
    dt = ctx.protocol["protocol"]["sample_interval_s"]
    c = np.linalg.pinv(np.asarray(A, float))[col]
    k2, b2 = drift_coef_dps(ctx)
    return rg.window_combination_u_coef(k2, b2, [(s.time_s, s.n * dt) for s in seg], c)


def broadband_noise(ctx: Context) -> Item:
    """IEC 62047-20 5.4.5.1 c), reading taken (:func:`gonio.specs.iec62047_20.formulas.broadband_noise_iec`):
    the rms noise (°/s, Table 4) of the static record's one-sided Welch density over the
    broadband region from the in-band limit ``band_hz`` to ``broadband_high_hz`` (0: the
    Nyquist frequency); the "20 dB/dec value" c of an amplitude density c/f (°/s^1.5) and the
    free slope in the details.

    Uncertainty: the Welch estimate, u_rel = 1/√(segments × lines) (the estimate's own
    scatter, :func:`gonio.analysis.noise.psd.welch_band_rms_u_rel`, is smaller and alone
    under-covered the study on the 2-h record: docs/iec62047-20-readings.md), with the ν of
    a standard deviation of that spread, ½/u_rel², the chamber's fluctuation and the gyro's
    temperature during the record against T_BASE (:func:`noise_temperature_line`). The rms
    is a dispersion and is stated as one, by its one-sided χ² 95 % interval alone with
    ν = ½(rms/u_c)² (:func:`gonio.result.gum.dispersion_uncertainty`): no k, no "± U"."""
    t, cl, un = "broadband noise (rms)", "5.4.5.1 c)", "°/s"
    m = _miss(ctx, "static", "broadband_noise", t, cl, un) or _quiet(ctx, "broadband_noise", t, cl, un)
    if m:
        return m
    _, x, dt = _static(ctx)                  # °/h; the density in °/s, in bounded pieces
    nper = min(4096, x.size)
    f, p = welch_psd(x, 1.0 / dt, nper, divisor=S_PER_H)
    nz = ctx.protocol["noise"]
    hi = nz.get("broadband_high_hz", 0.0) or 0.5 / dt
    f_hi = min(hi, 0.5 / dt)
    d = ief.broadband_noise_iec(f, p, nz["band_hz"], f_hi)
    nseg = max(1, 2 * x.size // nper - 1)
    u_rel = 1.0 / math.sqrt(nseg * d["lines"])
    u = _noise_budget([
        from_u("rms", d["rms_dps"], d["rms_dps"] * u_rel, dof=0.5 / u_rel ** 2,
               source="Welch estimate over the broadband lines"),
        _fluctuation_noise_line(ctx, x, dt, nper, nz["band_hz"], f_hi,
                                d["rms_dps"], include_lo=True)],
        _noise_temperature_line(ctx, d["rms_dps"]))
    u, bc = noise_statement(ctx, d["rms_dps"], u)
    return Item("broadband_noise", t, cl, un, d["rms_dps"], uncertainty=u, details={
        **d, "band_low_hz": nz["band_hz"], "band_high_hz": f_hi,
        **({"bound_condition": bc} if bc else {})})


def resolution(ctx: Context) -> Item:
    """IEC 62047-20 5.6.3: Out,resolution by the 50 % rule on rate steps from rest
    (:func:`gonio.specs.iec62047_20.formulas.resolution_iec`; each step referred to the mean of the
    rests before and after it, the larger of the two directions), and resolution =
    max(Out,resolution, Noise,RMS). Reading taken: the "filter" is the mean over the step's
    samples (T = samples × interval) and Noise,RMS the standard deviation of T-second means
    of the static record (5.4), i.e. the in-band noise seen through that filter.

    Uncertainty, each stated by its interval: Out,resolution is a value of the tested grid
    (the grid belongs to the measurand: no step term), its true value the median outcome
    under the gyro's noise, stated by the central 95 % range of the rule's outcome under the
    data's noise (:func:`gonio.specs._rate_family.formulas.rule_outcome_uncertainty`, u_c its
    standard deviation, no k); Noise,RMS, a standard deviation of the block means, u_c =
    s/√(2ν), by its one-sided χ² 95 % interval (:func:`gonio.result.gum.std_dev_uncertainty`).
    The maximum's interval is [max of the lower ends, max of the upper ends] (the true
    maximum lies there when each true value lies in its own interval), u_c the standard
    deviation of max(A, B) (:func:`max_outcome_normal_sd`), and its p the interval's own
    probability under max(A, B), B normal about Noise,RMS with its u_c
    (:func:`max_outcome_interval_probability`; the upper end raised where that falls below
    95 %) — the one p every output states, as the rule's interval alone states its own."""
    t, cl, un = "resolution", "5.6", "°/s"
    m = _miss(ctx, "resolution", "resolution", t, cl, un)
    if m:
        return m
    means = segment_means(ctx.df, "resolution")
    cands, dets, T, pmfs, runs_data = [], {}, None, [], []
    for run in sorted({s.run for s in means}):
        seg = [s for s in means if s.run == run]
        steps, resp, sig = [], [], []
        for j, s in enumerate(seg):
            if s.role != "increment":
                continue
            if j == 0 or j + 1 >= len(seg) or seg[j - 1].role != "rest" or seg[j + 1].role != "rest":
                raise GonioError(f"resolution run {run} step {s.step}: a step needs a rest before "
                                 "and after it")
            rest = 0.5 * (seg[j - 1].mean + seg[j + 1].mean)
            sig.append(math.sqrt(s.std ** 2 / s.n + 0.25 * (seg[j - 1].std ** 2 / seg[j - 1].n
                                                            + seg[j + 1].std ** 2 / seg[j + 1].n))
                       / abs(ctx.a_base))
            steps.append(abs(s.rate_dps))
            resp.append(math.copysign(1.0, s.rate_dps) * (s.mean - rest) / ctx.a_base)
            T = s.n * float(np.median(np.diff(segment_samples(ctx.df, "resolution", s.run,
                                                              s.step)["time_s"])))
        c, ratio = ief.resolution_iec(steps, resp)
        cands.append(c)
        runs_data.append((steps, resp, sig))
        dets[f"run{run}"] = {"steps_dps": steps, "ratio": ratio, "candidate_dps": c}
    if any(c is None for c in cands):
        return not_measured("resolution", t, cl, un, "the largest step already fails the 50 % rule")
    out_res = max(cands)
    noise, nb, s_ref = math.nan, 0, 0.0
    if ctx.has("static") and T:
        _, rate_dph, dt = _static(ctx)
        P = int(round(T / dt))
        nb = rate_dph.size // P
        if nb >= 2:
            noise = rg.block_mean_stability(rate_dph / S_PER_H, 1.0, P)
        if nb >= 3:
            s_ref = referred_step_sd(rate_dph / S_PER_H, P)
    # the rule's outcome under the data's noise: each referred step's σ at least the static
    # record's for a T-second mean less its two neighbours' mean (the samples' own s/√n
    # takes them as white; the gyro's flicker and walk make a T-mean noisier)
    for steps, resp, sig in runs_data:
        pmfs.append(rg.fifty_percent_outcome_pmf(steps, rg.fifty_percent_pass_probability(
            resp, [max(x, s_ref) for x in sig], steps, two_sided=False)))
    dets["referred_step_sd_static_dps"] = s_ref
    # Out,resolution: a grid value, stated by the central 95 % range of the rule's outcome
    # under the data's noise (its standard deviation u_c, no k, no step term)
    u_rule, pmf = rg.rule_outcome_uncertainty(pmfs, out_res)
    if math.isfinite(noise) and nb >= 2:     # one-sided χ² upper limit of a std (JJF's K_r)
        u_noise = std_dev_uncertainty(noise, nb - 1, "Noise,RMS")
    else:
        u_noise = None
    if u_noise is not None and noise > out_res:
        value, by = noise, "Noise,RMS"
    else:
        value, by = out_res, "Out,resolution"
    # max(a, b) with a_t ∈ [lo_a, hi_a], b_t ∈ [lo_b, hi_b] lies in [max lo, max hi]; u_c is
    # the standard deviation of max(A, B), A the rule's outcome, B ~ N(Noise,RMS, u_c(B)²)
    lo_r, hi_r = u_rule.interval if u_rule.interval is not None else (out_res, out_res)
    if u_noise is None:
        u = u_rule
    else:
        lo = min(max(lo_r, u_noise.interval[0]), value)
        hi = max(hi_r, u_noise.interval[1])
        top = max(k for p in pmfs for k in p if k is not None)
        pmf_top = outcome_pmf_topped(pmf, top)
        u_c = max_outcome_normal_sd(pmf_top, noise, u_noise.u_c)
        # p: the combined interval's own probability under the distribution of max(A, B)
        # (as the rule's interval states its own, JCGM 101 7.7); where it falls below 95 %
        # (each part's 95 % does not make the maximum's), the upper end is raised to 95 %
        p_iv = max_outcome_interval_probability(pmf_top, noise, u_noise.u_c, lo, hi)
        if p_iv < 0.95:
            hi = max_outcome_upper_end(pmf_top, noise, u_noise.u_c, lo, hi, 0.95)
            p_iv = max_outcome_interval_probability(pmf_top, noise, u_noise.u_c, lo, hi)
        u = replace(u_rule, components=u_rule.components + u_noise.components, u_c=u_c,
                    U=hi - value, interval=(lo, hi) if hi > lo else None,
                    coverage_probability=min(p_iv, 1.0))
    top = max(k for p in pmfs for k in p if k is not None)
    return Item("resolution", t, cl, un, value, uncertainty=u, details={
        **dets, "out_resolution_dps": out_res, "noise_rms_dps": noise, "filter_s": T,
        "decided_by": by,
        # the stated distribution, max(A, B): A the rule's outcome, B ~ N(Noise,RMS, u_c)
        "level_distribution": {
            "atoms": [[float(k), float(w)] for k, w in outcome_pmf_topped(pmf, top).items()],
            "normal": None if u_noise is None else [float(noise), float(u_noise.u_c)]},
        "outcome_pmf": {("none" if k is None else repr(k)): v for k, v in pmf.items()}})


def referred_step_sd(rate, block: int) -> float:
    """5.6: the standard deviation of a step's mean referred to the mean of the rests before
    and after it, m_k − (m_(k−1) + m_(k+1))/2, from a static record's (5.4) means of
    ``block`` samples (non-overlapping, adjacent): the root mean square of that second
    difference over the record (no mean removed: a constant or a linear drift cancels).
    For white noise it is σ_T·√1.5 (σ_T the T-mean's); the gyro's flicker and walk make it
    larger than the samples' own s/√n suggests. Reading taken: the rests and the step are
    taken as adjacent blocks of the step's length (the settling gaps between them left out).

    >>> rng = np.random.default_rng(1)
    >>> round(referred_step_sd(rng.standard_normal(400_000), 100) / (0.1 * 1.5 ** 0.5), 1)
    1.0
    """
    x = np.asarray(rate, float)
    P = int(block)
    n = x.size // P
    if P < 1 or n < 3:
        raise GonioError(f"5.6: a referred step's noise needs ≥ 3 blocks of {P} samples, "
                         f"got {x.size} samples")
    m = x[: n * P].reshape(n, P).mean(axis=1)
    d = m[1:-1] - 0.5 * (m[:-2] + m[2:])
    return float(np.sqrt(np.mean(d * d)))


def max_outcome_normal_sd(pmf: dict, m_b: float, s_b: float) -> float:
    """Standard deviation of max(A, B) for A discrete ({value: probability}) and B ~ N(m_b,
    s_b²) independent (5.6: the rule's outcome and Noise,RMS): for each a, with α = (a −
    m_b)/s_b, E[max] = aΦ(α) + m_b(1 − Φ(α)) + s_b·φ(α) and E[max²] = a²Φ(α) + (m_b² +
    s_b²)(1 − Φ(α)) + s_b(a + m_b)φ(α), mixed over A's probabilities.

    >>> round(max_outcome_normal_sd({0.0: 1.0}, 0.0, 1.0), 6)      # max(0, Z): √(1/2 − 1/(2π))
    0.583819
    >>> round(max_outcome_normal_sd({0.1: 0.5, 0.05: 0.5}, 0.0, 0.0), 6)
    0.025
    """
    from scipy.stats import norm

    w = np.array(list(pmf.values()), float)
    w = w / w.sum()
    a = np.array(list(pmf.keys()), float)
    if s_b <= 0:
        mx = np.maximum(a, m_b)
        e1, e2 = float(w @ mx), float(w @ mx ** 2)
    else:
        al = (a - m_b) / s_b
        P, f = norm.cdf(al), norm.pdf(al)
        e1 = float(w @ (a * P + m_b * (1 - P) + s_b * f))
        e2 = float(w @ (a * a * P + (m_b ** 2 + s_b ** 2) * (1 - P) + s_b * (a + m_b) * f))
    return math.sqrt(max(e2 - e1 * e1, 0.0))


def outcome_pmf_topped(pmf: dict, top: float) -> dict:
    """The rule's outcome distribution with "above the grid" (None) counted as the largest
    tested step ``top``: its probability added to that step's, not replacing it.

    >>> outcome_pmf_topped({0.1: 0.2, 0.05: 0.7, None: 0.1}, 0.1)
    {0.1: 0.30000000000000004, 0.05: 0.7}
    """
    out: dict = {}
    for k, w in pmf.items():
        kk = top if k is None else k
        out[kk] = out.get(kk, 0.0) + w
    return out


def max_outcome_interval_probability(pmf: dict, m_b: float, s_b: float, lo: float,
                                     hi: float) -> float:
    """P(lo ≤ max(A, B) ≤ hi) for A discrete ({value: probability}) and B ~ N(m_b, s_b²)
    independent (5.6: the interval of the maximum of the rule's outcome and Noise,RMS, its
    own probability): P(max ≤ x) = F_A(x)·Φ((x − m_b)/s_b), and B continuous, so
    P(max < lo) = P(A < lo)·Φ((lo − m_b)/s_b).

    >>> max_outcome_interval_probability({0.02: 0.5, 0.05: 0.5}, 0.0, 0.0, 0.02, 0.05)
    1.0
    >>> round(max_outcome_interval_probability({0.0: 1.0}, 0.0, 1.0, 0.0, 1.96), 4)  # Φ(1.96)
    0.975
    """
    from scipy.stats import norm

    w = np.array(list(pmf.values()), float)
    w = w / w.sum()
    a = np.array(list(pmf.keys()), float)

    def phi(x):
        return float(x >= m_b) if s_b <= 0 else float(norm.cdf((x - m_b) / s_b))

    tol_lo, tol_hi = 1e-12 * abs(lo), 1e-12 * abs(hi)
    below_hi = float(w[a <= hi + tol_hi].sum()) * phi(hi)
    below_lo = float(w[a < lo - tol_lo].sum()) * (phi(lo) if s_b > 0 else float(lo > m_b))
    return max(below_hi - below_lo, 0.0)


def max_outcome_upper_end(pmf: dict, m_b: float, s_b: float, lo: float, hi: float,
                          p: float) -> float:
    """The smallest upper end ≥ ``hi`` at which [lo, end] holds probability ``p`` of max(A,
    B) (:func:`max_outcome_interval_probability`; bisection, the tested values of A as
    candidates first).

    >>> round(max_outcome_upper_end({0.0: 1.0}, 0.0, 1.0, -10.0, 0.0, 0.95), 3)   # Φ⁻¹(0.95)
    1.645
    """
    def prob(x):
        return max_outcome_interval_probability(pmf, m_b, s_b, lo, x)

    if prob(hi) >= p:
        return hi
    x0 = hi
    for a in sorted(k for k in pmf if k > hi):
        if prob(a) >= p:
            below = a - 1e-9 * max(abs(a), 1e-300)
            if prob(below) < p:          # reached at the tested value itself
                return a
            x1 = below
            break
        x0 = a
    else:
        x1 = max(max(pmf), m_b) + 10.0 * max(s_b, 0.0) + 1e-12
    for _ in range(80):
        xm = 0.5 * (x0 + x1)
        x0, x1 = (x0, xm) if prob(xm) >= p else (xm, x1)
    return x1


def with_needs(ctx: Context, done: dict[str, Item]) -> Context:
    """The context of an item: the calibration's, with 5.1.3.4's item once computed (the
    one source of :func:`chamber_coefficient`) and a_BASE from the scale-factor item
    (5.1.3.1) when it was measured, its relative u_c and the ν of that u_c
    (:func:`gonio.result.gum.budget_nu`: Welch–Satterthwaite over a_BASE's budget lines,
    also where a_BASE is stated by its bound condition); items read them, none writes them."""
    if "sf_temperature_coefficient" in done:
        ctx = replace(ctx, sf_tc_item=done["sf_temperature_coefficient"])
    sf = done.get("scale_factor")
    if sf is None or not sf.measured:
        return ctx
    if sf.uncertainty is None or not sf.value:
        return replace(ctx, a_base=sf.value)
    bc = (sf.details or {}).get("bound_condition")
    if bc:
        return replace(ctx, a_base=sf.value, a_base_u_rel=sf.uncertainty.u_c / abs(sf.value),
                       a_base_nu=budget_nu(sf.uncertainty),
                       a_base_rest_u_rel=float(bc["u_rest"]) / abs(sf.value),
                       a_base_rest_nu=float(bc["nu_rest"]),
                       a_base_bound_rel=float(bc["a"]) / abs(sf.value))
    return replace(ctx, a_base=sf.value, a_base_u_rel=sf.uncertainty.u_c / abs(sf.value),
                   a_base_nu=budget_nu(sf.uncertainty))


def _e_a(ctx: Context):
    """The budget line of a_BASE's relative error in an item divided by it (5.1.3.1):
    u_c(a_BASE)/|a_BASE| with the ν of u_c (``a_base_nu``), so that the item's ν_eff carries
    the slope's noise a_BASE rests on (JCGM 100 G.4.1). Where a_BASE's u_c is not known (an
    item computed alone), the rate table's line (:func:`rate_table_line`) stands for it."""
    if ctx.a_base_u_rel is None:
        return rate_table_line("e_K", ctx.rate_table_u_rel, "scale factor, relative: the "
                               "rate table's line alone (a_BASE's u_c not known)")
    return from_u("e_K", 0.0, ctx.a_base_u_rel, dof=ctx.a_base_nu, type="B",
                  source="scale factor, relative: u_c(a_BASE)/a_BASE of 5.1.3.1, with its ν_eff")


def _e_a_rest(ctx: Context):
    """The line of a_BASE's relative error in the bias (5.3.3.1, :func:`_bias_budget`): where
    5.1.3.1 is stated by its bound condition, its other lines' u_rest/a_BASE with ν_rest (the
    bounded part, a/a_BASE, is the bias's bounded line ``e_a_bnd``, not counted twice);
    else :func:`_e_a`'s u_c(a_BASE)/a_BASE."""
    if ctx.a_base_rest_u_rel is None:
        return _e_a(ctx)
    return from_u("e_a", 0.0, ctx.a_base_rest_u_rel, dof=ctx.a_base_rest_nu, type="B",
                  source="scale factor, relative: u_rest/a_BASE of 5.1.3.1's lines other "
                         "than its bounded ones, with their ν_rest")


#: The characteristics in the order of Table 4: (key, title, clause, function).
#: The function of each item whose name is not its key.
_FUNCTION_OF = {"sf_temperature_coefficient": sf_temperature, "ratiometric_error": ratiometric, "bias_temperature_coefficient": bias_temperature, "bias_ratiometric_error": bias_ratiometric}
ITEMS = tuple((key, title, clause, _FUNCTION_OF.get(key) or globals()[key])
              for key, title, clause in ITEM_ROWS)

#: What each item needs computed before it (gonio.result.items.item_order orders them): every
#: characteristic in °/s or relative to a_BASE needs the scale factor (5.1.3.1), which needs
#: 5.1.3.4's coefficient (:func:`chamber_coefficient`; 5.1.3.4 itself needs neither).
NEEDS = {row[0]: ("scale_factor",) for row in ITEMS
         if row[0] not in ("scale_factor", "sf_temperature_coefficient")}
NEEDS["scale_factor"] = ("sf_temperature_coefficient",)

