"""JJF 1535-2015 Table 3: the fifteen calibration items, one function each.

Each function takes a :class:`Context` (the readings and what the calibration already
knows: K, null output, latitude, protocol values) and returns an
:class:`~gonio.result.model.Item` with its value, unit, clause, and an uncertainty
computed from the calibration's own data with the GUM engine (:mod:`uncertainty`),
k = t₉₅(ν_eff). The formulas are in :mod:`gonio.specs.jjf1535.formulas` (JJF alone) and
:mod:`gonio.specs._rate_family.formulas` (shared with IEC 62047-20); the readings taken
are documented in ``docs/jjf1535-readings.md``.

Rates are reported in °/h (bias family) or °/s (threshold, resolution) as JJF Table 1
allows; the scale factor in the gyro's output unit per °/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy import stats

from gonio.specs._rate_family import formulas as rg
from gonio.specs.jjf1535 import formulas as jf
from gonio.errors import GonioError
from gonio.physics.alignment import input_axis_enu
from gonio.analysis.noise import allan_deviation, fit_markov_model, fit_noise_model
from gonio.analysis.noise.stream import value_range
from gonio.result.gum import (budget_nu, dispersion_uncertainty, gum,
                              max_magnitude_statement, std_dev_uncertainty)
from gonio.result.model import Item, Uncertainty, not_measured
from gonio.specs._rate_family.rate_records import (RateContext, static_rate_dph, segment_means,
                                                   segment_samples, sf_calibration_means,
                                                   rate_table_line, table_bound_statement,
                                                   TABLE2_RATE_ACCURACY_REL)
from gonio.units import S_PER_H
from gonio.specs.jjf1535.keys import ITEM_ROWS, NONNEGATIVE  # noqa: F401 (rate_records reads it here)
from uncertainty import DOF_U_WITHIN_10PCT, from_u, type_b


@dataclass(kw_only=True)
class Context(RateContext):
    """The shared rate context with JJF 1535's room temperature, cross-axis bound, and K̄
    of 7.2.1 once computed."""

    room_temperature_c: float
    cross_axis_bound: float = 0.03            # assumed |cross-axis sensitivity| bound (7.2.12)
    K: float | None = None                    # K̄ of 7.2.1 once computed
    u_K_rel: float | None = None
    u_K_nu: float = math.inf                  # ν of u_c(K) (Welch–Satterthwaite of its budget)
    rate_table_ripple_rel: float = 5.0e-4     # Table 2's rate smoothness 0.05 % (7.2.3)


def _need(ctx: Context, test: str, key: str, title: str, clause: str, unit: str):
    if not ctx.has(test):
        return not_measured(key, title, clause, unit, f"no '{test}' records in the readings")
    if ctx.K is None and key not in ("scale_factor",):
        return not_measured(key, title, clause, unit, "needs the scale factor of 7.2.1")
    return None


def _e_K(ctx: Context):
    """The budget line of K̄'s relative error in an item computed with K (7.2.1): u_c(K)/|K̄|
    with the ν of u_c(K) (``u_K_nu``), so that the item's ν_eff, and the k computed from it,
    carry the few calibrations K rests on (JCGM 100 G.4.1: every line with its own ν; as a
    line of ν = ∞ a short programme's K, ν 2, gave its items a normal k)."""
    return from_u("e_K", 0.0, ctx.u_K_rel or 0.0, dof=ctx.u_K_nu, type="B",
                  source="scale factor, relative: u_c(K)/K̄ of 7.2.1, with its ν_eff")


def _block_std_of_mean(y: np.ndarray, block: int = 10) -> tuple[float, float]:
    """Standard uncertainty of a record mean from its block means (robust to correlated
    noise at lags < block): s(block means)/√n_blocks, ν = n_blocks − 1."""
    n = y.size // block
    if n < 2:
        return (float(np.std(y, ddof=1) / math.sqrt(y.size)) if y.size > 1 else math.nan,
                max(y.size - 1, 1))
    m = y[: n * block].reshape(n, block).mean(axis=1)
    return float(m.std(ddof=1) / math.sqrt(n)), n - 1


def drift_u_dph(ctx: Context, first: tuple[float, float], second: tuple[float, float]) -> float:
    """Standard uncertainty (°/h) that the bias drift gives the difference of the means of two
    records, ``first`` and ``second`` = (start, duration) in s, from the calibration's own
    Allan fit (7.2.13): the rate random walk and the bias instability of the fitted model,
    exactly for the two records' spans (:func:`gonio.specs._rate_family.formulas.
    record_difference_u`: the flicker part grows with the separation, where the Allan floor
    √2·0.664·B held at every separation read it low by half at 7.2.14's hour between
    records), K² and B² each increased by the square of its fit uncertainty, an unresolved
    RRW bounded by the Allan deviation's upper limits (:func:`gonio.specs._rate_family.
    formulas.drift_coefficients`). Without a static record the term is
    not known, never 0: a GonioError, so the item is "not measured" with the reason; 0 for a
    static record that does not vary (a noise-free bench)."""
    noise, found = None, False
    if ctx.has("static") and ctx.K is not None:
        try:
            noise, found = static_noise(ctx), True
        except GonioError:                  # the ARW item reports why
            pass
    if found and noise is None:
        return 0.0                                   # a noise-free bench: no drift
    if noise is None:
        raise GonioError("the budget's bias-drift term needs the static Allan record "
                         "(7.2.13), which the readings lack or which could not be analysed")
    allan, fit = noise["allan"], noise["fit"]
    return rg.record_difference_u(fit.K, fit.u_K, fit.B, fit.u_B, allan.tau_s, allan.ci_high,
                                  first, second)


def record_span_s(time_s: np.ndarray) -> tuple[float, float]:
    """(start, duration) in s of a record of samples at ``time_s`` (each sample's start;
    duration n·Δt with Δt the mean interval, one sample: 1 s)."""
    t = np.asarray(time_s, float)
    dt = float((t[-1] - t[0]) / (t.size - 1)) if t.size > 1 else 1.0
    return float(t[0]), t.size * dt


def static_noise(ctx: Context) -> dict | None:
    """The static record (7.2.13) in °/h with its overlapping Allan deviation, five-term
    fit and the fit with the Gauss–Markov set (the ARW's), computed once per calibration (a
    pure function of the readings and K, kept in ``ctx.cache``); None when the record does
    not vary."""
    if "static_noise" in ctx.cache:
        return ctx.cache["static_noise"]
    rate_dph, dt = static_rate_dph(ctx.df, ctx.null_output, ctx.K)
    out = None
    if value_range(rate_dph) != 0:
        allan = allan_deviation(rate_dph, dt, "rate", "decade:10", unit="deg/h")
        out = {"rate_dph": rate_dph, "allan": allan, "fit": fit_noise_model(allan),
               "fit_markov": fit_markov_model(allan)}
    ctx.cache["static_noise"] = out
    return out


# --------------------------------------------------------------------------- 7.2.1 – 7.2.4
def calibrations(ctx: Context, test: str = "scale_factor") -> list[dict]:
    """Each calibration m of 7.2.1.2: F_r, fit (K_m, F_0,m, residuals), K±, standard error
    (``se_K``: from the line's residuals, which hold the gyro's nonlinearity; ``se_K_noise``:
    the least-squares slope's noise from the rate points' means alone,
    √(Σ (Ω_j − Ω̄)² u_j²)/Σ (Ω_j − Ω̄)², u_j = s_j/√n_j)."""
    if ("cal", test) in ctx.cache:
        return ctx.cache[("cal", test)]
    means = segment_means(ctx.df, test)
    spans = _sampled_spans_s(ctx, test)
    out = []
    for run in sorted({m.run for m in means}):
        first, last, rates, ys, _ = sf_calibration_means(means, run)
        fr = jf.rest_level(first.mean, last.mean)
        fit = jf.fit_scale_factor(rates, ys, rest=fr)
        asym = jf.asymmetry_jjf(rates, fit.means)
        n = rates.size
        se = math.sqrt(float((fit.residuals ** 2).sum()) / (n - 2)
                       / float(((rates - rates.mean()) ** 2).sum())) if n > 2 else math.nan
        seg = [m for m in means if m.run == run]
        u_mean = np.array([m.std / math.sqrt(m.n) for m in seg[1:-1] if m.role == "rate"])
        n_means = [m.n for m in seg[1:-1] if m.role == "rate"]
        dx = rates - rates.mean()
        se_noise = (math.sqrt(float((dx ** 2 * u_mean ** 2).sum())) / float((dx ** 2).sum())
                    if u_mean.size == rates.size and n > 1 else math.nan)
        out.append({"run": run, "rest": fr, "fit": fit, "asym": asym, "se_K": se,
                    "se_K_noise": se_noise,
                    "u_means": u_mean, "n_means": n_means, "temperature_c": first.temperature_c,
                    "supply_v": first.supply_v, "rates": rates,
                    "spans_s": np.array([spans[(run, m.step)] for m in seg[1:-1]
                                         if m.role == "rate"])})
    if not out:
        raise GonioError(f"no calibrations in '{test}'")
    ctx.cache[("cal", test)] = out
    return out


def _sampled_spans_s(ctx: Context, test: str) -> dict[tuple[int, int], float]:
    """{(run, step): the time a segment's samples cover}, n·Δt with Δt the spacing of its
    samples' times (each sample a mean over its interval); for a segment of one sample the
    protocol's sampling period."""
    d = ctx.df[ctx.df["test"] == test]
    g = d.groupby(["run", "step"], sort=True)["time_s"].agg(["min", "max", "size"])
    dt0 = float(ctx.protocol.get("protocol", {}).get("sample_interval_s", 1.0))
    return {(int(r), int(st)): (float(row["max"] - row["min"]) * row["size"] / (row["size"] - 1)
                                if row["size"] > 1 else dt0)
            for (r, st), row in g.iterrows()}


def scale_factor(ctx: Context) -> Item:
    """JJF 1535 7.2.1: K̄ = mean of the Q least-squares scale factors K_m (eqs (4), (5)),
    rests before and after removed, rest points not fit points (readings taken).

    Budget (Annex A.1 structure, from the calibration's own data): u₁ rate table
    (relative, its certificate), u₂ acquisition (relative), u₃ repeatability of the mean
    s(K_m)/√Q (type A, ν = Q − 1). Where the readings state no certificate u for the table
    (its Table 2 bound alone), stated by the bound condition U = a + k·u of the rest
    (:func:`gonio.specs._rate_family.rate_records.table_bound_statement`).
    """
    title, clause, unit = "scale factor K", "7.2.1", f"{ctx.output_unit}/(°/s)"
    miss = _need(ctx, "scale_factor", "scale_factor", title, clause, unit)
    if miss:
        return miss
    cals = calibrations(ctx)
    Ks = np.array([c["fit"].K for c in cals])
    Q = Ks.size
    Kbar = float(Ks.mean())
    if Q >= 2:
        u3 = from_u("s_K", 0.0, float(Ks.std(ddof=1)) / math.sqrt(Q), dof=Q - 1,
                    source="repeatability of the mean of Q calibrations, s(K_m)/√Q")
    else:
        u3 = from_u("s_K", 0.0, cals[0]["se_K"], dof=len(cals[0]["rates"]) - 2,
                    source="least-squares standard error of K (one calibration)")
    inputs = [from_u("K_m", Kbar, 0.0, type="A", source="mean of K_m"),
              rate_table_line("e_table", ctx.rate_table_u_rel, "rate table, relative (u1)"),
              from_u("e_acq", 0.0, ctx.acquisition_u_rel, type="B",
                     source="data acquisition, relative (u2)"),
              u3]
    u = gum(lambda k, et, ea, s: (k + s) * (1 + ea) / (1 + et), inputs)
    # no certificate u for the table: its Table 2 bound added linearly to k·u of the rest
    u, bc = table_bound_statement(u, Kbar, ctx.rate_table_u_rel,
                                  {"e_table": TABLE2_RATE_ACCURACY_REL})
    return Item("scale_factor", title, clause, unit, Kbar, uncertainty=u, details={
        **({"bound_condition": bc} if bc else {}),
        "K_m": Ks, "F0_m": [c["fit"].F0 for c in cals], "rest_m": [c["rest"] for c in cals],
        "se_K_m": [c["se_K"] for c in cals], "Q": Q,
        "rates_dps": cals[0]["rates"], "means_m": [c["fit"].means for c in cals],
        "rates_m": [c["rates"] for c in cals],
        "residuals_m": [c["fit"].residuals for c in cals]})


def nonlinearity(ctx: Context) -> Item:
    """JJF 1535 7.2.2 eqs (6), (7): K_n = mean over m of max|v_j| / [K_m(Ω_max+ − Ω_max−)],
    less the noise's selection excess: eq (6) takes the largest of noisy residuals, which
    noise raises by between 0 and c_n·σ (:func:`nonlinearity_selection`); the midpoint is
    removed, eq (6)'s reading is kept in the details (``reading``, ``K_n_m``).

    Uncertainty: the noise of the largest residual, σ·√(1 − h_jj)/[K(Ω+ − Ω−)] per
    calibration over √Q (σ pooled from the rate-point means' standard errors, h_jj the
    leverage; scaled up to the residuals' spread over the Q calibrations where that is
    larger beyond chance, :func:`nonlinearity_noise`), the selection excess (rectangular), and the rate table's once-per-revolution
    ripple within its stated bound (``rate_table_ripple_rel``, as 7.2.3) in the largest
    residual (:func:`gonio.specs.jjf1535.formulas.ripple_residual_sd`; root mean square over
    the calibrations, not over √Q: every calibration meets the ripple at the same phases,
    see :func:`asymmetry`). Without the ripple term the study, its phase drawn per trial,
    covered 0.930 (z sd 1.07). The spread of the Q values K_n,m (ν = Q − 1) evaluates the
    same noise and is kept in the details only: with both in the budget the study's z had
    sd 0.58.

    A magnitude, stated by one interval: that of the extreme of magnitudes over the signed
    residuals (:func:`nonlinearity_points`, :func:`gonio.result.gum.max_magnitude_statement`),
    not value ± U (the budget above, the value's, stays in the budget table); the value
    within that interval."""
    title, clause, unit = "scale-factor nonlinearity K_n", "7.2.2", "1"
    miss = _need(ctx, "scale_factor", "nonlinearity", title, clause, unit)
    if miss:
        return miss
    cals = calibrations(ctx)
    kn = np.array([jf.nonlinearity_jjf(c["fit"]) for c in cals])
    span = np.array([abs(c["fit"].K * (c["rates"].max() - c["rates"].min())) for c in cals])
    u_noise, nu, scale, u_model = nonlinearity_noise(cals, span)
    sel = [nonlinearity_selection(c, scale) for c in cals]
    half = float(np.mean([h / sp for (h, _, _), sp in zip(sel, span)]))
    value = max(float(kn.mean()) - half, 0.0)
    rip = [jf.ripple_residual_sd(c["rates"], c["spans_s"], ctx.rate_table_ripple_rel, c["fit"].K)
           [int(np.argmax(np.abs(c["fit"].residuals)))] / sp for c, sp in zip(cals, span)]
    u_ripple = float(np.sqrt(np.mean(np.square(rip))))
    inputs = [from_u("K_n", float(kn.mean()), 0.0, source="mean of K_n,m"),
              from_u("noise", 0.0, u_noise, dof=nu,
                     source="noise of the largest residual (rate-point means, leverage)"
                     if scale == 1.0 else "noise of the largest residual (rate-point means, "
                     "leverage) scaled to the residuals' spread over the Q calibrations"),
              type_b("selection", -half, half, "rectangular",
                     source="selection excess of the largest of the noisy residuals "
                            "(midpoint ± c_m·σ/2 removed)"),
              from_u("ripple", 0.0, u_ripple, type="B",
                     source=f"rate-table ripple ≤ {ctx.rate_table_ripple_rel:.2g}·|Ω| "
                            "(once per revolution, unknown phase) in the largest residual")]
    u = gum(lambda a, b, c, d: a + b + c + d, inputs)
    # a magnitude (the largest |residual|): the interval of the extreme of magnitudes
    x, pts = nonlinearity_points(ctx, cals, span, scale, nu)
    value, u, iv = max_magnitude_statement(u, x, pts, value)
    return Item("nonlinearity", title, clause, unit, value, uncertainty=u,
                details={**iv, "K_n_m": kn, "span_m": span, "reading": float(kn.mean()),
                         "selection_excess": half, "contending_residuals_m": [m for _, m, _ in sel],
                         "spread_of_K_n_m": float(kn.std(ddof=1)) if kn.size > 1 else None,
                         "noise_from_means": u_model, "noise_scale": scale})


def nonlinearity_points(ctx: Context, cals: list, span, scale: float, nu: float
                        ) -> tuple[np.ndarray, list[Uncertainty]]:
    """JJF 1535 7.2.2: the signed points whose largest magnitude K_n is, with their budgets,
    for its interval (:func:`gonio.result.gum.max_magnitude_statement`): where the Q
    calibrations share their rates, each rate's residual v_j,m/span_m averaged over m (the
    nonlinearity's shape at that rate), u_j its noise σ_j,m·f (:func:`residual_noise_sd`,
    f the spread's scale of :func:`nonlinearity_noise`, root mean square over m, over √Q,
    ν as that noise term) and the rate table's ripple in that residual (root mean square
    over m, not over √Q: every calibration meets it at the same phases); where the rates
    differ (reading taken), every calibration's residuals as points, each with its own
    noise and ripple — the interval then holds the largest over every calibration's rates."""
    rows = []
    for c, sp in zip(cals, span):
        rip = jf.ripple_residual_sd(c["rates"], c["spans_s"], ctx.rate_table_ripple_rel,
                                    c["fit"].K) / sp
        rows.append((c["fit"].residuals / sp, scale * residual_noise_sd(c) / sp, rip))
    if len({c["rates"].tobytes() for c in cals}) == 1:
        v, sd, rip = (np.array([r[k] for r in rows]) for k in range(3))
        Q = len(cals)
        rows = [(v.mean(0), np.sqrt(np.mean(sd ** 2, 0)) / math.sqrt(Q),
                 np.sqrt(np.mean(rip ** 2, 0)))]
    x, pts = [], []
    for v, sd, rip in rows:
        for j in range(v.size):
            x.append(float(v[j]))
            pts.append(gum(lambda a, b, c: a + b + c, [
                from_u("v_j", float(v[j]), 0.0, source="residual / span"),
                from_u("noise", 0.0, float(sd[j]), dof=nu, source="noise of the residual"),
                from_u("ripple", 0.0, float(rip[j]), type="B",
                       source="rate-table ripple in the residual")]))
    return np.array(x), pts


def nonlinearity_noise(cals: list, span) -> tuple[float, float, float, float]:
    """JJF 1535 7.2.2: the noise of eq (6)'s largest residual, relative to the fitted span
    K_m(Ω_max+ − Ω_max−), as (u, ν, f, u_means), u the noise term of the mean of the Q
    values (over √Q).

    u_means is the rate-point means' noise, σ_j,m = σ_m·√(1 − h_jj) at each calibration's
    largest residual (:func:`residual_noise_sd`), root mean square over the calibrations,
    over √Q, ν = ∞. Those standard errors s/√n miss the slow noise (bias instability, rate
    random walk) of a point's n correlated samples; the Q repeated calibrations show it, as
    7.2.3 carries the spread of K_a,m (:func:`asymmetry`): with Q ≥ 2 calibrations of one
    rate series, the residuals v_j,m/span_m spread over m about their mean (the
    nonlinearity's shape) by s_j, and f² = Σ_j s_j² / Σ_j mean_m σ_j,m² (pooled over the
    rate points, ν = (Q − 1)(n − 2), the residuals' n − 2 degrees of freedom per
    calibration; one point's spread, ν = Q − 1, would put an overwide term on every
    calibration without slow noise). Where f² exceeds the F distribution's 95 % point
    F(ν, Σ(n_j − 1)) — the spread larger than the means' noise beyond chance; otherwise the
    spread's own scatter, taken whenever f > 1, lowered the study's z spread from 0.66 to
    0.58 — the term is f·u_means; f also scales the σ_j of the selection excess
    (:func:`nonlinearity_selection`), so that the excess and the noise term use the same
    σ."""
    Q = len(cals)
    sds = [residual_noise_sd(c) / sp for c, sp in zip(cals, span)]
    at = [sd[int(np.argmax(np.abs(c["fit"].residuals)))] for c, sd in zip(cals, sds)]
    u_means = float(np.sqrt(np.mean(np.square(at))) / math.sqrt(Q))
    if Q < 2 or len({c["rates"].tobytes() for c in cals}) != 1 or not u_means > 0:
        return u_means, math.inf, 1.0, u_means
    v = np.array([c["fit"].residuals for c in cals]) / np.asarray(span)[:, None]
    f = math.sqrt(float(v.var(axis=0, ddof=1).sum() / np.mean(np.square(sds), axis=0).sum()))
    nu = (Q - 1) * (v.shape[1] - 2)
    nu_means = sum(int(m) - 1 for c in cals for m in c["n_means"])
    if nu < 1 or f * f <= (stats.f.ppf(0.95, nu, nu_means) if nu_means > 0 else 1.0):
        return u_means, math.inf, 1.0, u_means
    return f * u_means, float(nu), f, u_means


def residual_noise_sd(cal: dict) -> np.ndarray:
    """JJF 1535 7.2.2: each residual's noise of the line (5) in one calibration ``cal``,
    σ_j = σ·√(1 − h_jj) in output units, σ the root mean square of the rate-point means'
    standard errors (their pooled noise) and h_jj the leverage of rate j."""
    x = cal["rates"]
    dx = x - x.mean()
    h = 1.0 / x.size + dx ** 2 / float((dx ** 2).sum())
    return float(np.sqrt(np.mean(cal["u_means"] ** 2))) * np.sqrt(1.0 - h)


def nonlinearity_selection(cal: dict, scale: float = 1.0) -> tuple[float, int, float]:
    """The selection excess of eq (6)'s largest |residual| of one calibration ``cal``, in
    output units (:func:`gonio.specs._rate_family.formulas.selection_excess`: midpoint
    c_m·σ/2, m contenders), and the largest residual's noise: (c_m·σ/2, m, σ_j), σ_j the
    residuals' noise (:func:`residual_noise_sd`) times ``scale`` (:func:`nonlinearity_noise`'s
    f, where the calibrations' spread shows more noise than the means' standard errors)."""
    sd = scale * residual_noise_sd(cal)
    r = np.abs(cal["fit"].residuals)
    half, m = rg.selection_excess(r, sd)
    return half, m, float(sd[int(np.argmax(r))])


def asymmetry(ctx: Context) -> Item:
    """JJF 1535 7.2.3 eqs (8), (9): K_a = mean of |K+,m − K−,m| / ((K+,m + K−,m)/2).

    Uncertainty (:func:`gonio.specs.jjf1535.formulas.asymmetry_slope_u`, per calibration,
    root mean square over the Q calibrations): the rate-point means' noise through the two
    slopes (σ pooled from their standard errors, ν = Σ(n_j − 1); independent between
    calibrations, over √Q) and the rate table's once-per-revolution ripple within its
    stated bound (``rate_table_ripple_rel``, Table 2's rate smoothness 0.05 % where the
    readings state none), each point's share attenuated by the turn its samples cover —
    not over √Q: a programme whose forward and reverse turns cancel brings the table back
    to its starting angle, so every calibration meets the ripple at the same phases. With
    Q ≥ 2 the spread of the Q values K_a,m, s/√Q (ν = Q − 1), as well: the points' standard
    errors miss the slow noise, a drift along the ascending rates that tilts K+ and K− in
    opposite senses (the study's errors spread 1.1–1.2× the noise term). The two-direction
    fit's standard error is kept in the details: its residuals are mostly the
    nonlinearity's shape, and with it the study's z had sd 0.43.

    A magnitude, stated by one interval: that of |μ| from the mean of the signed K_a,m with
    the same budget (the spread that of the signed values;
    :func:`gonio.result.gum.max_magnitude_statement`, one point: the two-sided interval
    folded at 0), not value ± U, which reached below zero for a symmetric gyro. The value
    is eq (9)'s mean of |K_a,m| (``reading`` in the details) within that interval."""
    title, clause, unit = "scale-factor asymmetry K_a", "7.2.3", "1"
    miss = _need(ctx, "scale_factor", "asymmetry", title, clause, unit)
    if miss:
        return miss
    cals = calibrations(ctx)
    Q = len(cals)
    ka = np.array([c["asym"].value for c in cals])
    terms = np.array([jf.asymmetry_slope_u(c["rates"], float(np.sqrt(np.mean(c["u_means"] ** 2))),
                                           c["spans_s"], ctx.rate_table_ripple_rel, ctx.K)
                      for c in cals])
    u_noise, u_ripple = np.sqrt(np.mean(terms ** 2, axis=0)) / np.array([math.sqrt(Q), 1.0])
    nu = sum(int(m) - 1 for c in cals for m in c["n_means"]) or math.inf
    inputs = [from_u("K_a", float(ka.mean()), 0.0),
              from_u("noise", 0.0, float(u_noise), dof=nu,
                     source="rate-point means' noise through K+ and K−"),
              from_u("ripple", 0.0, float(u_ripple), type="B",
                     source=f"rate-table ripple ≤ {ctx.rate_table_ripple_rel:.2g}·|Ω| "
                            "(once per revolution, unknown phase) through K+ and K−")]
    if Q > 1:       # the rates' slow noise (drift along a direction's ascending rates)
        inputs.append(from_u("s_Ka", 0.0, float(ka.std(ddof=1) / math.sqrt(Q)), dof=Q - 1,
                             source="spread of K_a,m"))
    u = gum(lambda a, *d: a + sum(d), inputs)
    # a magnitude |K+ − K−|/K̄: the interval of |μ| from the signed mean (one point) with
    # the same budget, the spread that of the signed K_a,m
    signed = np.array([c["asym"].signed for c in cals])
    pt = gum(lambda a, *d: a + sum(d), [from_u("K_a,signed", float(signed.mean()), 0.0)]
             + inputs[1:3] + ([from_u("s_Ka", 0.0, float(signed.std(ddof=1) / math.sqrt(Q)),
                                      dof=Q - 1, source="spread of the signed K_a,m")]
                              if Q > 1 else []))
    value, u, iv = max_magnitude_statement(u, [float(signed.mean())], [pt], float(ka.mean()))
    se = float(np.mean([c["se_K"] for c in cals])) * 2.0 / abs(ctx.K) / math.sqrt(Q)
    return Item("asymmetry", title, clause, unit, value, uncertainty=u, details={
        **iv, "reading": float(ka.mean()), "signed_mean": float(signed.mean()),
        "K_a_m": ka, "signed_m": [c["asym"].signed for c in cals],
        "K_pos_m": [c["asym"].K_pos for c in cals], "K_neg_m": [c["asym"].K_neg for c in cals],
        "fit_standard_error": se})


def sf_repeatability(ctx: Context) -> Item:
    """JJF 1535 7.2.4 eq (10): K_r = s(K_m)/K̄ over Q calibrations with power off between.

    Uncertainty of a standard deviation from Q values: u_c = K_r/√(2(Q − 1)), ν = Q − 1,
    U to the χ² 95 % upper limit (:func:`std_dev_uncertainty`)."""
    title, clause, unit = "scale-factor repeatability K_r", "7.2.4", "1"
    miss = _need(ctx, "scale_factor", "sf_repeatability", title, clause, unit)
    if miss:
        return miss
    cals = calibrations(ctx)
    if len(cals) < 2:
        return not_measured("sf_repeatability", title, clause, unit,
                            f"needs Q ≥ 2 calibrations, the readings hold {len(cals)}")
    _, _, kr = jf.relative_std([c["fit"].K for c in cals])
    Q = len(cals)
    u = std_dev_uncertainty(kr, Q - 1, "K_r")
    return Item("sf_repeatability", title, clause, unit, kr, uncertainty=u, details={"Q": Q})


def _temperature_bound_c(ctx: Context) -> float:
    """Half-width (°C) of the gyro's temperature error at a chamber set point, JJF 1535 Table 2
    (:func:`gonio.specs._rate_family.formulas.gyro_temperature_bound_c`): the readings'
    ``chamber_deviation_bound_c`` plus half their ``chamber_uniformity_c`` (absent: Table 2's
    2 °C). The room point of 7.2.5 and 7.2.14 is not in the chamber; its temperature is the
    room's, read as stated."""
    return rg.gyro_temperature_bound_c(ctx.chamber_deviation_c, ctx.chamber_uniformity_c)


#: What 7.2.5 and 7.2.14 keep in ``details.bound_condition.basis``.
TEMPERATURE_SLOPE_BOUND_BASIS = (
    "bound condition: the gyro's temperature error at each chamber set point at its bound "
    "B (the chamber's deviation plus half its uniformity, Table 2; the room point read as "
    "stated), each slope's reach b_i = |x_i|·B/(|T_i − T_rt| − B) added to the interval of "
    "the largest magnitude from the other lines (JCGM 100 4.3.7): it holds for every "
    "temperature error within the bound")


def temperature_slope_bound(x: float, d_c: float, bound_c: float) -> float:
    """The reach b of a temperature slope x = ΔY/(T_i − T_rt) (7.2.5's relative ΔK, 7.2.14's
    ΔB) read with the gyro's temperature at the set point off by up to ``bound_c`` (the room
    point read as stated): the response over the true span d + δ was divided by the nominal
    d, so x = β·(d + δ)/d and |β − x| = |x|·|δ|/|d + δ| ≤ |x|·B/(|d| − B) for a response
    linear in T (a curvature k₂ adds k₂·B against the chord's k₁ + k₂·d: 0.4 % of K_t on the
    MEMS bench, inside the noise's u). ∞ where |d| ≤ B (no span is certain).

    >>> round(temperature_slope_bound(1.6e-4, 50.0, 3.0), 9), temperature_slope_bound(1.0, 2.0, 3.0)
    (1.0213e-05, inf)
    """
    return abs(x) * bound_c / (abs(d_c) - bound_c) if abs(d_c) > bound_c else math.inf


def _slope_bounds(slopes, temps, rt: int, others: list[int], bound_c: float) -> dict | None:
    """The ``bounded`` argument of :func:`gonio.result.gum.max_magnitude_statement` for
    7.2.5/7.2.14's slopes: the line ``dT`` at its bound at every point
    (:func:`temperature_slope_bound`; each point's other lines are its budget less ``dT``);
    None where a span is not longer than the bound or no bound is stated (the root-sum-square
    line then)."""
    b = [temperature_slope_bound(slopes[j], temps[j] - temps[rt], bound_c) for j in others]
    if not bound_c > 0 or not all(math.isfinite(v) for v in b):
        return None
    return {"symbol": "dT", "b": b, "basis": TEMPERATURE_SLOPE_BOUND_BASIS}


def sf_temperature_sensitivity(ctx: Context) -> Item:
    """JJF 1535 7.2.5 eq (11): K_t = max_i |(K_i − K_rt)/(K_rt (T_i − T_rt))|.

    Uncertainty: the noise of K_i and K_rt (type A) and the gyro's temperature error at T_i
    (:func:`_temperature_bound_c`: the chamber's deviation, Table 2 ±2 °C, and the gyro's
    place in the volume, ± half the uniformity, bounds added; rectangular in the budget, at
    its bound in the statement: :func:`temperature_slope_bound`, the gyro cold at the hot set
    point shortens the span it divides by). K_i's noise is the least-squares slope's noise from
    its rate points' means (``se_K_noise`` of :func:`calibrations`), not the line's residual
    standard error: the residuals hold the gyro's nonlinearity, the same at every
    temperature of the model, which biases K_i and K_rt alike and cancels in their ratio —
    with the residual standard error the budget was over-wide (z sd 0.62 in the study). The
    residual standard error stays in the details."""
    title, clause, unit = "scale-factor temperature sensitivity K_t", "7.2.5", "1/°C"
    miss = _need(ctx, "sf_temperature", "sf_temperature_sensitivity", title, clause, unit)
    if miss:
        return miss
    cals = calibrations(ctx, "sf_temperature")
    Ks = [c["fit"].K for c in cals]
    Ts = [c["temperature_c"] for c in cals]
    rt = int(np.argmin(np.abs(np.array(Ts) - ctx.room_temperature_c)))
    value, slopes = jf.temperature_sensitivity(Ks, Ts, rt, relative=True)
    i = int(np.nanargmax(np.abs(slopes)))
    def se(c):                                   # the points' noise; residuals without means
        v = c["se_K_noise"]
        return (v, sum(int(n) - 1 for n in c["n_means"])) if math.isfinite(v) else \
            (c["se_K"], len(c["rates"]) - 2)

    def point(j):           # the signed slope at temperature j with its budget
        (u_j, nu_j), (u_rt, nu_rt) = se(cals[j]), se(cals[rt])
        return gum(lambda a, b, d: (a - b) / (b * d), [
            from_u("K_i", cals[j]["fit"].K, u_j, dof=nu_j,
                   source=f"K at {Ts[j]:g} °C (noise of its rate points' means)"),
            from_u("K_rt", cals[rt]["fit"].K, u_rt, dof=nu_rt,
                   source=f"K at room temperature {Ts[rt]:g} °C"),
            type_b("dT", Ts[j] - Ts[rt], _temperature_bound_c(ctx), "rectangular",
                   source=rg.TEMPERATURE_BOUND_SOURCE)])

    # a magnitude, the largest |slope|: the interval of the extreme of magnitudes, the gyro's
    # temperature error at each set point at its bound
    others = [j for j in range(len(Ts)) if j != rt]
    pts = [point(j) for j in others]
    value, u, iv = max_magnitude_statement(
        pts[others.index(i)], [slopes[j] for j in others], pts, value,
        bounded=_slope_bounds(slopes, Ts, rt, others, _temperature_bound_c(ctx)))
    return Item("sf_temperature_sensitivity", title, clause, unit, value, uncertainty=u, details={
        "temperatures_c": Ts, "K_i": Ks, "slopes_per_c": slopes, "room_index": rt,
        "se_K_residual": [c["se_K"] for c in cals], **iv})


# --------------------------------------------------------------------------- 7.2.6, 7.2.7
def referred_mean_u(terms: list[tuple[float, int, float]]) -> tuple[float, float]:
    """(σ, ν) of a referred mean Σ w_i·ȳ_i from (weight w_i, samples n_i, standard deviation
    s_i) of its segments: σ² = Σ w_i² s_i²/n_i, ν by Welch–Satterthwaite (JCGM 100 G.4.1)
    with n_i − 1 each (∞ for a segment whose s_i is 0).

    >>> [round(x, 4) for x in referred_mean_u([(1.0, 5, 1.0), (0.5, 5, 1.0), (0.5, 5, 1.0)])]
    [0.5477, 8.0]
    """
    v = [(w * w * sd * sd / n, n - 1) for w, n, sd in terms]
    var = sum(x for x, _ in v)
    den = sum(x * x / d for x, d in v if d > 0)
    return math.sqrt(var), (var * var / den if den > 0 else math.inf)


def _candidate_item(key, title, clause, cands, details, pmfs) -> Item:
    if any(c is None for c in cands):
        return not_measured(key, title, clause, "°/s",
                            "the largest step already fails the 50 % criterion; start higher")
    value = max(cands)
    u, pmf = rg.rule_outcome_uncertainty(pmfs, value)
    grid = sorted({abs(r) for d in details.values() for r in d["steps_dps"]}, reverse=True)
    details = {**details, "grid_dps": ", ".join(f"{g:g}" for g in grid),
               "samples": next(iter(details.values()))["samples"],
               "outcome_pmf": {("none" if k is None else repr(k)): v for k, v in pmf.items()},
               # the stated distribution ("above the grid" as the largest step, as u_c)
               "level_distribution": {"atoms": _topped_atoms(pmf, grid[0]), "normal": None}}
    return Item(key, title, clause, "°/s", value, uncertainty=u, details=details)


def _topped_atoms(pmf: dict, top: float) -> list:
    """[[outcome, probability], …] of the rule's outcome with "above the grid" (None)
    counted as the largest tested step."""
    out: dict = {}
    for k, w in pmf.items():
        kk = float(top if k is None else k)
        out[kk] = out.get(kk, 0.0) + float(w)
    return [[k, w] for k, w in out.items()]


def _rule_run(steps, meas, exp, sig, cands: list, pmfs: list):
    """One run of 7.2.6 / 7.2.7: its candidate by the 50 % rule (eqs (13), (14)) appended to
    ``cands`` and its outcome distribution under the data's noise (``sig``: (σ, ν) of each
    referred mean, :func:`referred_mean_u`) to ``pmfs``; returns (candidate, deviations)."""
    c, dev = jf.fifty_percent_candidate(steps, meas, exp)
    cands.append(c)
    pmfs.append(rg.fifty_percent_outcome_pmf(
        steps, rg.fifty_percent_pass_probability(meas, [x for x, _ in sig], exp,
                                                dof=[n for _, n in sig])))
    return c, dev


def threshold(ctx: Context) -> Item:
    """JJF 1535 7.2.6 eqs (12), (13): forward and reverse candidates by the two-sided 50 % rule
    on the rest-referred output (F̄_0,j: mean of the rests just before and after the point);
    the threshold is the larger candidate."""
    title, clause = "threshold", "7.2.6"
    miss = _need(ctx, "threshold", "threshold", title, clause, "°/s")
    if miss:
        return miss
    means = segment_means(ctx.df, "threshold")
    cands, dets, pmfs = [], {}, []
    for run in sorted({m.run for m in means}):
        seg = [m for m in means if m.run == run]
        rates, meas, exp, sig = [], [], [], []
        for j, m in enumerate(seg):
            if m.role != "rate":
                continue
            before = next((s for s in reversed(seg[:j]) if s.role == "rest"), None)
            after = next((s for s in seg[j + 1:] if s.role == "rest"), None)
            if before is None:
                raise GonioError(f"threshold run {run} step {m.step}: no rest before the point")
            f0 = before.mean if after is None else 0.5 * (before.mean + after.mean)
            rests = [(1.0, before.n, before.std)] if after is None else \
                [(0.5, before.n, before.std), (0.5, after.n, after.std)]
            rates.append(m.rate_dps)
            meas.append(m.mean - f0)
            exp.append(ctx.K * m.rate_dps)
            sig.append(referred_mean_u([(1.0, m.n, m.std)] + rests))
        c, dev = _rule_run(rates, meas, exp, sig, cands, pmfs)
        dets[f"run{run}"] = {"rates_dps": rates, "steps_dps": rates, "deviation": dev,
                             "candidate_dps": c,
                             "samples": int(next(m.n for m in seg if m.role == "rate"))}
    return _candidate_item("threshold", title, clause, cands, dets, pmfs)


def resolution(ctx: Context) -> Item:
    """JJF 1535 7.2.7 eq (14): base rate Ω_b, increments ΔΩ_j; ΔF_j = F̄(Ω_b + ΔΩ_j) −
    F̄(Ω_b) with the base re-measured before each increment; two-sided 50 % rule against
    ΔF*_j = K ΔΩ_j; the larger of the forward and reverse candidates."""
    title, clause = "resolution", "7.2.7"
    miss = _need(ctx, "resolution", "resolution", title, clause, "°/s")
    if miss:
        return miss
    means = segment_means(ctx.df, "resolution")
    cands, dets, pmfs = [], {}, []
    for run in sorted({m.run for m in means}):
        seg = [m for m in means if m.run == run]
        steps, meas, exp, sig = [], [], [], []
        for j, m in enumerate(seg):
            if m.role != "increment":
                continue
            base = next((s for s in reversed(seg[:j]) if s.role == "base"), None)
            if base is None:
                raise GonioError(f"resolution run {run} step {m.step}: no base rate before it")
            d = float(f"{m.rate_dps - base.rate_dps:.12g}")     # the tested increment
            steps.append(d)
            meas.append(m.mean - base.mean)
            exp.append(ctx.K * d)
            sig.append(referred_mean_u([(1.0, m.n, m.std), (1.0, base.n, base.std)]))
        c, dev = _rule_run(steps, meas, exp, sig, cands, pmfs)
        dets[f"run{run}"] = {"increments_dps": steps, "steps_dps": steps, "deviation": dev,
                             "candidate_dps": c,
                             "samples": int(next(m.n for m in seg if m.role == "increment"))}
    return _candidate_item("resolution", title, clause, cands, dets, pmfs)


# --------------------------------------------------------------------------- bias family
def bias_records(ctx: Context) -> list[dict]:
    """B_0,m of each bias record (eqs (15), (16)) in °/h with the Earth rate removed, and the
    uncorrected F̄/K beside it."""
    if "bias" in ctx.cache:
        return ctx.cache["bias"]
    out = []
    remove = ctx.protocol.get("bias", {}).get("remove_earth_rate", True)
    for m in segment_means(ctx.df, "bias"):
        y = segment_samples(ctx.df, "bias", m.run, m.step)["output"].to_numpy()
        earth = rg.earth_rate_projection_dps(ctx.latitude_deg, input_axis_enu(m.up_axis, m.north_axis))
        raw = (m.mean - ctx.null_output) / ctx.K
        u_mean, nu = _block_std_of_mean(y, int(ctx.protocol.get("bias", {}).get(
            "stability_block_samples", 10)))
        out.append({"run": m.run, "F_mean": m.mean, "uncorrected_dph": raw * S_PER_H,
                    "earth_dph": earth * S_PER_H,
                    "B0_dph": (raw - (earth if remove else 0.0)) * S_PER_H,
                    "u_mean_dph": u_mean / abs(ctx.K) * S_PER_H, "nu": nu, "samples": y})
    ctx.cache["bias"] = out
    return out


def bias(ctx: Context) -> Item:
    """JJF 1535 7.2.8 eqs (15)–(17): B_0 = mean over m of (F̄ − F_null)/K − Ω_E,proj, in °/h.

    Readings taken: F referred to the gyro's nominal null output; the Earth-rate projection on
    the input axis (Ω_E sin λ, axis up) removed. Budget: repeatability of the mean over the Q
    records (type A), scale factor (relative, from 7.2.1), input-axis alignment on the
    horizontal Earth rate (rectangular), and the acquisition's relative gain uncertainty acting
    on the whole output F̄ (the null output included: 3×10⁻⁵ of 2.5 V is 0.0125 °/s at
    6 mV/(°/s))."""
    title, clause, unit = "bias B_0", "7.2.8", "°/h"
    miss = _need(ctx, "bias", "bias", title, clause, unit)
    if miss:
        return miss
    recs = bias_records(ctx)
    b = np.array([r["B0_dph"] for r in recs])
    Q = b.size
    s_mean = float(b.std(ddof=1) / math.sqrt(Q)) if Q > 1 else recs[0]["u_mean_dph"]
    nu = Q - 1 if Q > 1 else recs[0]["nu"]
    align = rg.OMEGA_E_DPS * S_PER_H * math.cos(math.radians(ctx.latitude_deg)) \
        * math.sin(math.radians(ctx.axis_alignment_deg))
    inputs = [from_u("B", float(b.mean()), s_mean, dof=nu,
                     source="mean of the Q records (type A)"),
              _e_K(ctx),
              type_b("E_align", 0.0, align, "rectangular",
                     source="input-axis alignment × horizontal Earth rate"),
              from_u("e_acq_null", 0.0, ctx.acquisition_u_rel * abs(float(np.mean(
                  [r["F_mean"] for r in recs]))) / abs(ctx.K) * S_PER_H, type="B",
                  source="acquisition gain on the whole output (null included)")]
    u = gum(lambda B, eK, ea, en: B * (1 + eK) + ea + en, inputs)
    return Item("bias", title, clause, unit, float(b.mean()), uncertainty=u, details={
        "B0_m_dph": b, "uncorrected_m_dph": [r["uncorrected_dph"] for r in recs],
        "earth_rate_removed_dph": recs[0]["earth_dph"], "latitude_deg": ctx.latitude_deg,
        "null_output": ctx.null_output})


#: The one-sided level at which 7.2.10's ν takes the fitted flicker and random-walk
#: coefficients (:func:`gonio.specs._rate_family.formulas.bias_stability_dof`).
BIAS_STABILITY_CORRELATED_UPPER_P = 0.95


def bias_stability(ctx: Context) -> Item:
    """JJF 1535 7.2.10 eqs (18), (19): B_s,m = s(P-sample block means)/K of each record, °/h,
    combined as their root mean square √(mean B_s,m²) (reading taken). Eq (19) as printed
    averages the standard deviations, and a mean of standard deviations reads low, E[s] ≈
    σ(1 − 1/(4ν_m)) (0.6 % at the study's ν_m ≈ 40); the mean of the variances is unbiased
    for σ², which the χ² statement below assumes. Eq (19)'s mean is kept in the details
    (``reading_eq19_dph``) and stated under the results table.

    Uncertainty: the sampling of B_s, a mean of Q standard deviations of correlated block
    means, u = B_s/√(2ν) with the effective ν of its own records
    (:func:`gonio.specs._rate_family.formulas.bias_stability_dof`: the block means'
    variogram fitted by white, flicker and random-walk noise; Satterthwaite), the flicker
    and random-walk coefficients at their one-sided 95 % upper confidence limits
    (:data:`BIAS_STABILITY_CORRELATED_UPPER_P`: the estimate's ν is large where B_s reads
    low, and its limit held σ 91–94 % of the time; the estimate is kept in the details,
    ``nu_records_estimate``), and the scale factor. B_s is a dispersion and is stated as one, by its one-sided χ² 95 % interval alone
    with ν = ½(B_s/u_c)² (:func:`gonio.result.gum.dispersion_uncertainty`), as K_r and B_r are: no k, no
    "± U". The spread of the Q = 3 values (ν = 2) is kept in the details; it does not set the
    interval."""
    title, clause, unit = "bias stability B_s", "7.2.10", "°/h"
    miss = _need(ctx, "bias", "bias_stability", title, clause, unit)
    if miss:
        return miss
    P = int(ctx.protocol.get("bias", {}).get("stability_block_samples", 10))
    recs = bias_records(ctx)
    bs = np.array([rg.block_mean_stability(r["samples"], ctx.K, P) * S_PER_H for r in recs])
    nblk = recs[0]["samples"].size // P
    value = float(np.sqrt(np.mean(bs ** 2)))
    nu_b, nu_est = rg.bias_stability_dofs([r["samples"] for r in recs], P,
                                          BIAS_STABILITY_CORRELATED_UPPER_P)
    u_a = from_u("s_Bs", 0.0, value / math.sqrt(2.0 * nu_b) if math.isfinite(nu_b) else 0.0,
                 dof=nu_b, source="sampling of B_s: effective ν of the records' correlated "
                                  "block means (variogram: white, flicker, random walk; "
                                  "flicker and random walk at their upper 95 % limits)")
    u = gum(lambda a, b, e: (a + b) * (1 + e), [from_u("B_s", value, 0.0), u_a,
                                                _e_K(ctx)])
    u = dispersion_uncertainty(value, u)
    return Item("bias_stability", title, clause, unit, value, uncertainty=u,
                details={"B_s_m_dph": bs, "P_samples": P, "blocks": nblk,
                         "nu_records": nu_b,
                         "nu_records_estimate": nu_est,
                         "reading_eq19_dph": float(bs.mean()),
                         "spread_of_records_dph": float(bs.std(ddof=1)) if bs.size > 1
                         else None})


def bias_repeatability(ctx: Context) -> Item:
    """JJF 1535 7.2.11 eq (20): B_r = s(B_0,m) over Q power-ups, °/h; the Earth rate cancels.
    Uncertainty of a standard deviation of Q values: u_c = B_r/√(2(Q − 1)), U to the χ²
    95 % upper limit (:func:`std_dev_uncertainty`)."""
    title, clause, unit = "bias repeatability B_r", "7.2.11", "°/h"
    miss = _need(ctx, "bias", "bias_repeatability", title, clause, unit)
    if miss:
        return miss
    b = [r["B0_dph"] for r in bias_records(ctx)]
    if len(b) < 2:
        return not_measured("bias_repeatability", title, clause, unit,
                            f"needs ≥ 2 bias records, the readings hold {len(b)}")
    br = jf.sample_std(b)
    Q = len(b)
    u = std_dev_uncertainty(br, Q - 1, "B_r")
    return Item("bias_repeatability", title, clause, unit, br, uncertainty=u, details={"Q": Q})


def warmup_time(ctx: Context) -> Item:
    """JJF 1535 7.2.9, reading taken: per record (from power-on) the earliest time after which
    every window of W samples has a block-mean stability ≤ the nominal value; the mean over
    the N records.

    Uncertainty: the records' spread (Type A, s/√N on ν = N − 1), the window step and the
    detection: a window's stability s is an estimate
    with relative standard deviation r = 1/√(2(n_b − 1)) (n_b blocks per window), so the
    crossing of the nominal value can lie anywhere between the last exceedance of
    nominal·(1 + z·r) and of nominal·(1 − z·r), z = 1.96 (95 % for one window near the
    crossing) (:func:`gonio.specs.jjf1535.formulas.detection_interval`); that interval's
    width over 2z is the record's standard uncertainty, and the records' detections are
    independent (u = rms(width/2z)/√N). The spread of the N records' times evaluates
    partly the same noise, but it is what the power-ups showed: it is the Type A line (a
    certificate cannot show u = 0 beside records that differ), and k comes from its ν by
    Welch–Satterthwaite (ν_eff stated). On the study bench (100 trials, seed 20261301, the
    detection as the interval's width over 2z): z sd 0.94 with the detection alone (k 1.96),
    0.80 with both, coverage 0.96 at k = t₉₅(ν_eff) (median ν_eff 18, k 2.10); the records'
    times spread 21 s (rms) about the truth against a detection term of 24 s (rms); with the
    detection as the larger distance to the interval's ends and both in, z sd 0.55 (an
    earlier study, 60 trials). The reading is not corrected: its mean
    error over those 180 records is 0.0 s (standard error 1.6 s), the truth being the time
    the expected stability, noise included, meets the nominal
    (``gonio.specs.jjf1535.truth``)."""
    from scipy.stats import norm
    title, clause, unit = "warm-up time", "7.2.9", "s"
    miss = _need(ctx, "warmup", "warmup_time", title, clause, unit)
    if miss:
        return miss
    w = ctx.protocol["warmup"]
    nominal = w["nominal_stability_dph"] / S_PER_H
    nb = w["window_samples"] // w["block_samples"]
    r = 1.0 / math.sqrt(2 * (nb - 1))
    times, halves, widths = [], [], []
    for m in segment_means(ctx.df, "warmup"):
        g = segment_samples(ctx.df, "warmup", m.run, m.step)
        ts, st = jf.window_stabilities(g["time_s"].to_numpy(), g["output"].to_numpy() / ctx.K,
                                       window=w["window_samples"], block=w["block_samples"])
        t_n = rg.last_exceedance_time(ts, st, nominal)
        z = float(norm.ppf(0.975))
        lo, hi = jf.detection_interval(ts, st, nominal, nominal * r, z)
        hi = hi if math.isfinite(hi) else float(ts[-1] - ts[0])
        times.append(t_n)
        halves.append(max(t_n - lo, hi - t_n))
        widths.append((hi - lo) / (2.0 * z))
    t = np.array(times)
    if np.any(~np.isfinite(t)):
        return not_measured("warmup_time", title, clause, unit,
                            "the stability never met the nominal value within a record")
    dt = float(np.median(np.diff(segment_samples(ctx.df, "warmup", 0, 0)["time_s"])))
    step = w["block_samples"] * dt
    # the records' spread is the Type A evaluation of their mean (ν = N − 1, JCGM 100 4.2)
    s_a = float(t.std(ddof=1) / math.sqrt(t.size)) if t.size > 1 else 0.0
    inputs = [from_u("t_w", float(t.mean()), s_a, dof=(t.size - 1 if s_a > 0 else math.inf),
                     source=f"spread of the {t.size} records' times, s/√N"),
              type_b("step", 0.0, step / 2.0, "rectangular", source="window start step P·t0"),
              from_u("detect", 0.0, float(np.sqrt(np.mean(np.square(widths)) / t.size)),
                     type="B",
                     source="detection: where the stability crosses nominal·(1 ± z·r), "
                            "r the relative sampling deviation of a window's stability")]
    u = gum(lambda a, b, c: a + b + c, inputs)
    return Item("warmup_time", title, clause, unit, float(t.mean()), uncertainty=u,
                details={"t_n_s": t, "detection_half_width_s": halves,
                         "detection_u_s": widths,
                         "spread_s": float(t.std(ddof=1)) if t.size > 1 else None,
                         "nominal_stability_dph": w["nominal_stability_dph"],
                         # the measurand's definition, stated on the certificate: W, P, t0
                         "window_samples": int(w["window_samples"]),
                         "block_samples": int(w["block_samples"]),
                         "sample_interval_s": dt, "window_s": w["window_samples"] * dt,
                         "block_s": step, "records": int(t.size)})


def g_sensitivity(ctx: Context) -> Item:
    """JJF 1535 7.2.12.2: B_g,axis = [ω̄(+axis up) − ω̄(−axis up)]/2 per g for X, Y, Z with the
    Earth-rate projection on the input axis removed in each position (reading taken);
    B_g = max |B_g,axis|, (°/h)/g. The literal value (Earth rate left in) is kept."""
    title, clause, unit = "bias acceleration sensitivity B_g", "7.2.12", "(°/h)/g"
    miss = _need(ctx, "g_sensitivity", "g_sensitivity", title, clause, unit)
    if miss:
        return miss
    pos = {}
    for m in segment_means(ctx.df, "g_sensitivity"):
        seg = segment_samples(ctx.df, "g_sensitivity", m.run, m.step)
        y, y_t = seg["output"].to_numpy(), seg["time_s"].to_numpy()
        um, nu = _block_std_of_mean(y)
        earth = rg.earth_rate_projection_dps(ctx.latitude_deg, input_axis_enu(m.up_axis, m.north_axis))
        pos[m.up_axis] = {"w": (m.mean - ctx.null_output) / ctx.K, "earth": earth,
                          "u": um / abs(ctx.K), "nu": nu, "span": record_span_s(y_t)}
    res, lit, us = {}, {}, {}
    for ax in "xyz":
        p, n = pos.get("+" + ax), pos.get("-" + ax)
        if p is None or n is None:
            continue
        res[ax] = jf.g_sensitivity_axis(p["w"], n["w"], p["earth"], n["earth"]) * S_PER_H
        lit[ax] = jf.g_sensitivity_axis(p["w"], n["w"]) * S_PER_H
        us[ax] = (p, n)
    if not res:
        return not_measured("g_sensitivity", title, clause, unit,
                            "no pair of opposite positions (+axis up, −axis up)")
    ax = max(res, key=lambda a: abs(res[a]))
    xbound = ctx.cross_axis_bound * rg.OMEGA_E_DPS * S_PER_H

    def point(a_):          # the signed B_g of one axis with its budget
        p, n = us[a_]
        inputs = [from_u("w_p", p["w"] * S_PER_H, p["u"] * S_PER_H, dof=p["nu"],
                         source="+axis up mean"),
                  from_u("w_n", n["w"] * S_PER_H, n["u"] * S_PER_H, dof=n["nu"],
                         source="−axis up mean"),
                  from_u("E_p", p["earth"] * S_PER_H, 0.0, type="B"),
                  from_u("E_n", n["earth"] * S_PER_H, 0.0, type="B"),
                  type_b("x_E", 0.0, xbound, "rectangular",
                         source="cross-axis coupling of the Earth rate (bound)"),
                  _e_K(ctx),
                  from_u("drift", 0.0, drift_u_dph(ctx, n["span"], p["span"]), dof=DOF_U_WITHIN_10PCT,
                         source="bias drift between the two positions (Allan fit: RRW, BI)")]
        return gum(lambda a, b, c, d, x, e, dr: (((a - c) - (b - d) + dr) / 2.0 + x) * (1 + e),
                   inputs)

    axes = list(res)
    pts = [point(a_) for a_ in axes]
    # a magnitude, max |B_g,axis|: stated by the interval of the extreme of magnitudes
    value, u, iv = max_magnitude_statement(pts[axes.index(ax)], [res[a_] for a_ in axes],
                                           pts, abs(res[ax]))
    return Item("g_sensitivity", title, clause, unit, value, uncertainty=u, details={
        "per_axis_dph_per_g": res, "literal_per_axis_dph_per_g": lit, "axis": ax, **iv})


def angle_random_walk(ctx: Context) -> Item:
    """JJF 1535 7.2.13: ARW N in °/√h from the **overlapping** Allan variance of the static
    record (reading taken). The value certified is N of the five-term model whose bias
    instability has a realistic shape — the flat (2 ln 2/π)B² of formula (25) plus
    first-order Gauss–Markov terms at fixed correlation times
    (:func:`gonio.analysis.noise.fit_markov_model`): formula (25)'s flat B, fitted to a
    band-limited bias instability, reads N low. The standard's reading (formula (25),
    (26): the five-term fit) stays beside it in the details (``formula_25_reading``). The
    printed statistic of eqs (22)–(24) is computed too, labelled, with its ratio to the
    AVAR (it falls as 2/k²).

    Uncertainty: the fit's standard uncertainty of N (the least-squares covariance with the
    full covariance of the Allan estimates across τ under the fitted model, which share
    their data) and the scale factor. N is a dispersion (σ(τ)·√τ of white rate noise) and is
    stated as one, as K_r, B_r and B_s are: by its one-sided χ² 95 % interval alone with
    ν = ½(N/u_c)² (:func:`gonio.result.gum.dispersion_uncertainty`): no k, no "± U"."""
    title, clause, unit = "angle random walk ARW", "7.2.13", "°/√h"
    miss = _need(ctx, "static", "angle_random_walk", title, clause, unit)
    if miss:
        return miss
    noise = static_noise(ctx)
    if noise is None:
        return Item("angle_random_walk", title, clause, unit, 0.0,
                    uncertainty=gum(lambda n: n, [from_u("N", 0.0, 0.0)]),
                    details={"note": "the static record does not vary: no noise to analyse"})
    rate_dph, allan, fit = noise["rate_dph"], noise["allan"], noise["fit"]
    shaped = noise["fit_markov"]
    if not (fit.N > 0 and fit.u_N > 0 and shaped.N > 0 and shaped.u_N > 0):
        # a record that varies but whose fit holds no white rate noise (spikes, a periodic
        # disturbance): never certified as 0 ± 0
        raise GonioError("the five-term Allan fit of the static record (7.2.13) finds no "
                         "angle random walk although the record varies (N = 0 with u(N) = 0): "
                         "the record is not gyro noise (spikes, a periodic disturbance?)",
                         key="static")
    arw = shaped.N / math.sqrt(S_PER_H)
    u_arw = shaped.u_N / math.sqrt(S_PER_H)
    printed = {}
    if ctx.protocol.get("arw", {}).get("print_standard_statistic", True):
        ks = [k for k in (1, 2, 4, 8, 16) if rate_dph.size >= 2 * k + 3]
        for k, (pv, av) in (jf.allan_variances_jjf(rate_dph, ks) if ks else {}).items():
            printed[str(k)] = {"printed_eq24_dph2": pv, "overlapping_avar_dph2": av,
                               "ratio": pv / av if av > 0 else None}
    u = gum(lambda n, e: n * (1 + e), [from_u("N", arw, u_arw, dof=DOF_U_WITHIN_10PCT,
                                              source="five-term AVAR fit with band-limited "
                                                     "flicker, u(N)"),
                                       _e_K(ctx)])
    u = dispersion_uncertainty(arw, u)   # a dispersion: its one-sided χ² interval alone
    return Item("angle_random_walk", title, clause, unit, arw, uncertainty=u, details={
        "fit": fit.to_dict(), "fit_markov": shaped.to_dict(),
        "formula_25_arw_deg_sqrt_h": fit.N / math.sqrt(S_PER_H),
        "flicker_band_t_lo_s": shaped.t_lo_s,
        "formula_25_reading": {
            "arw_deg_sqrt_h": fit.N / math.sqrt(S_PER_H),
            "u_arw_deg_sqrt_h": fit.u_N / math.sqrt(S_PER_H),
            "note": "JJF 1535 formulas (25), (26): the five-term fit with a flat bias "
                    "instability; not certified (a band-limited bias instability makes it "
                    "read N low)"},
        "allan": {"tau_s": allan.tau_s, "adev_dph": allan.adev,
                                        "ci_low": allan.ci_low, "ci_high": allan.ci_high},
        "bias_instability_dph": fit.B, "rate_random_walk_dph_sqrt_h": fit.K * math.sqrt(S_PER_H),
        "quantisation": fit.Q, "rate_ramp_dph_per_h": fit.R * S_PER_H,
        "printed_eq22_24_statistic": printed,
        "printed_statistic_note": "JJF 1535 eqs (22)-(24) as printed: means one sample apart; "
                                  "for white noise 3 at k = 1 and 2/k^2 of the sample variance "
                                  "for k >= 2 - not an Allan variance; not used for the ARW"})


def bias_temperature_sensitivity(ctx: Context) -> Item:
    """JJF 1535 7.2.14 eq (27): B_t = max_i |(B_i − B_rt)/(T_i − T_rt)|, (°/h)/°C, each B_i =
    (F̄_i − F_null)/K_i with K_i from the scale-factor calibration at the same temperature
    (reading taken; K̄ of 7.2.1 when absent). Earth rate and g cancel (same mounting).

    Uncertainty: the record means (block type A), the gyro's temperature error on T_i
    (:func:`_temperature_bound_c`, as 7.2.5: at its bound in the statement), the bias drift
    between the records."""
    title, clause, unit = "bias temperature sensitivity B_t", "7.2.14", "(°/h)/°C"
    miss = _need(ctx, "bias_temperature", "bias_temperature_sensitivity", title, clause, unit)
    if miss:
        return miss
    kmap = {}
    if ctx.has("sf_temperature"):
        kmap = {c["run"]: c["fit"].K for c in calibrations(ctx, "sf_temperature")}
    B, T, U, tm = [], [], [], []
    for m in segment_means(ctx.df, "bias_temperature"):
        seg = segment_samples(ctx.df, "bias_temperature", m.run, m.step)
        y = seg["output"].to_numpy()
        tm.append(record_span_s(seg["time_s"].to_numpy()))
        K = kmap.get(m.run, ctx.K)
        um, nu = _block_std_of_mean(y)
        B.append((m.mean - ctx.null_output) / K * S_PER_H)
        T.append(m.temperature_c)
        U.append((um / abs(K) * S_PER_H, nu))
    rt = int(np.argmin(np.abs(np.array(T) - ctx.room_temperature_c)))
    value, slopes = jf.temperature_sensitivity(B, T, rt, relative=False)
    i = int(np.nanargmax(np.abs(slopes)))

    def point(j):           # the signed slope at temperature j with its budget
        return gum(lambda a, b, d, dr: (a - b + dr) / d, [
            from_u("B_i", B[j], U[j][0], dof=U[j][1], source=f"bias at {T[j]:g} °C"),
            from_u("B_rt", B[rt], U[rt][0], dof=U[rt][1], source=f"bias at {T[rt]:g} °C"),
            type_b("dT", T[j] - T[rt], _temperature_bound_c(ctx), "rectangular",
                   source=rg.TEMPERATURE_BOUND_SOURCE),
            from_u("drift", 0.0, drift_u_dph(ctx, tm[rt], tm[j]), dof=DOF_U_WITHIN_10PCT,
                   source="bias drift between the two records (Allan fit: RRW, BI)")])

    # a magnitude, the largest |slope|: the interval of the extreme of magnitudes, the gyro's
    # temperature error at each set point at its bound (as 7.2.5)
    others = [j for j in range(len(T)) if j != rt]
    pts = [point(j) for j in others]
    value, u, iv = max_magnitude_statement(
        pts[others.index(i)], [slopes[j] for j in others], pts, value,
        bounded=_slope_bounds(slopes, T, rt, others, _temperature_bound_c(ctx)))
    return Item("bias_temperature_sensitivity", title, clause, unit, value, uncertainty=u,
                details={"temperatures_c": T, "bias_dph": B, "slopes": slopes, "room_index": rt,
                         **iv})


# --------------------------------------------------------------------------- 7.2.15
def frequency_response(ctx: Context) -> dict:
    """Gain and phase at each vibration frequency: sine fits (known f) of the gyro output and
    of the reference rate; gain K(f) = A_out/A_ref, phase φ_out − φ_ref."""
    if "freq" in ctx.cache:
        return ctx.cache["freq"]
    f, K, ph, u_rel = [], [], [], []
    for m in segment_means(ctx.df, "vibration"):
        g = segment_samples(ctx.df, "vibration", m.run, m.step)
        t = g["time_s"].to_numpy()
        ao, po, _ = rg.sine_fit(t, g["output"].to_numpy(), m.freq_hz)
        ar, pr, _ = rg.sine_fit(t, g["reference_dps"].to_numpy(), m.freq_hz)
        # noise on the amplitude: residual rms · √(2/n) relative
        fit_o = g["output"].to_numpy()
        resid = fit_o - fit_o.mean() - ao * np.sin(2 * math.pi * m.freq_hz * t + math.radians(po))
        u_rel.append(float(np.std(resid) * math.sqrt(2.0 / t.size) / ao))
        f.append(m.freq_hz)
        K.append(ao / ar)
        ph.append(((po - pr + 180.0) % 360.0) - 180.0)
    ph = np.unwrap(np.radians(ph))
    if ph.size and ph[0] > math.pi / 2:
        ph -= 2 * math.pi
    out = {"freq_hz": np.array(f), "K_f": np.array(K), "phase_deg": np.degrees(ph),
           "u_rel": np.array(u_rel)}
    ctx.cache["freq"] = out
    return out


def bandwidth(ctx: Context) -> Item:
    """JJF 1535 7.2.15.2: the frequency where K(f), normalised to the lowest test frequency,
    falls by 3 dB (ratio 10^(−3/20)), by linear interpolation of dB against log f (readings
    taken). The 90° phase-lag frequency (IEC 62047-20 5.5.3) is reported beside it.

    Uncertainty: the noise of the bracketing gains through the local slope, weighted as
    the interpolation weights them, and of the 0 dB gain; and the remainder of linear
    interpolation in ln f, h²/8·|p''| (:func:`gonio.specs.jjf1535.formulas.
    interpolation_remainder`, rectangular), p'' over points at least h/2 apart. The
    difference to a quadratic through the three nearest points, taken before, was mostly the
    gains' noise over the grid's 1 % spacing near f_est, not the curve's (z sd 0.38–0.43)."""
    title, clause, unit = "bandwidth B_w", "7.2.15", "Hz"
    if not ctx.has("vibration"):
        return not_measured("bandwidth", title, clause, unit, "no 'vibration' records in the readings")
    fr = frequency_response(ctx)
    f, K = fr["freq_hz"], fr["K_f"]
    fb = rg.minus3db_frequency(f, K)
    f90 = rg.phase90_frequency(f, fr["phase_deg"])
    if not math.isfinite(fb):
        return not_measured("bandwidth", title, clause, unit,
                            f"the gain did not fall by 3 dB up to {f.max():g} Hz; raise the "
                            "estimated bandwidth")
    db = 20 * np.log10(K / K[0])
    i = int(np.searchsorted(-db, 3.0))            # first point at or below −3 dB
    i = min(max(i, 1), f.size - 1)
    # the crossing ln f* = ln f_{i−1} + w·h, w = (−3 − p_{i−1})/(p_i − p_{i−1}): it moves with
    # the bracketing points' gain errors weighted (1 − w) and w (not their root sum square),
    # and with the 0 dB gain's error by the full step (it shifts every p_j alike)
    h = math.log(f[i] / f[i - 1])
    dp = db[i] - db[i - 1]
    w = math.log(fb / f[i - 1]) / h
    to_db = 20 / math.log(10)
    u_db = to_db * math.sqrt(((1 - w) * fr["u_rel"][i - 1]) ** 2 + (w * fr["u_rel"][i]) ** 2
                             + fr["u_rel"][0] ** 2)
    # the slope the noise moves the crossing along: the secant over the bracketing pair, or
    # over the curvature's wider points where that is flatter (7.2.15.1 b)'s grid packs points
    # 1 % apart near f_est, and a secant over those is steepened by the gains' noise)
    slope = abs(dp) / h
    if f.size >= 3:
        a3, _, c3 = jf.curvature_points(np.log(f), i)
        slope = min(slope, abs(db[c3] - db[a3]) / math.log(f[c3] / f[a3]))
    u_f_noise = fb * u_db / slope if slope > 0 else 0.0
    half_interp = fb * h / abs(dp) * jf.interpolation_remainder(np.log(f), db, i) \
        if dp != 0 else 0.0
    inputs = [from_u("f_-3dB", fb, u_f_noise, dof=DOF_U_WITHIN_10PCT,
                     source="noise of the bracketing gains (weighted by the interpolation) "
                            "and of the 0 dB gain"),
              type_b("interp", 0.0, half_interp, "rectangular",
                     source="linear interpolation in ln f: h²/8·|p''| from a second "
                            "difference over points at least h/2 apart")]
    u = gum(lambda a, b: a + b, inputs)
    return Item("bandwidth", title, clause, unit, fb, uncertainty=u, details={
        "freq_hz": f, "gain_ratio": K / K[0], "gain_db": db, "phase_deg": fr["phase_deg"],
        "phase90_hz_iec": f90, "reference": "lowest test frequency (0 dB)"})


#: What each item needs computed before it (gonio.result.items.item_order orders them): every item
#: that divides by K (7.2.1) needs the scale factor; the others need nothing.
NEEDS = {key: ("scale_factor",) for key in (
    "nonlinearity", "asymmetry", "sf_repeatability", "sf_temperature_sensitivity", "threshold",
    "resolution", "bias", "warmup_time", "bias_stability", "bias_repeatability",
    "g_sensitivity", "angle_random_walk", "bias_temperature_sensitivity", "bandwidth")}


def with_needs(ctx: Context, done: dict[str, Item]) -> Context:
    """The context of an item: the calibration's, with K̄, its relative standard
    uncertainty and that uncertainty's ν (:func:`gonio.result.gum.budget_nu`: Welch–
    Satterthwaite over K's budget lines, also where K is stated by its bound condition)
    from the scale-factor item when it was measured (items read them; none writes them)."""
    sf = done.get("scale_factor")
    if sf is None or not sf.measured or sf.uncertainty is None:
        return ctx
    return replace(ctx, K=sf.value, u_K_rel=sf.uncertainty.u_c / abs(sf.value),
                   u_K_nu=budget_nu(sf.uncertainty))


#: Table 3 in order: (key, title, clause, function).
#: (key, title, clause, function): each item's function has the item's name.
ITEMS = tuple((key, title, clause, globals()[key]) for key, title, clause in ITEM_ROWS)

