"""Coverage of every item's uncertainty on the virtual bench (clause 8): what the
optical draft's study (:mod:`gonio.specs.ogam_draft.study`) feeds the generic coverage
statistics (:mod:`gonio.analysis.coverage`).

:func:`item_record` takes one virtual calibration (its report and the bench's truth)
and keeps, per item, the result, its U (and interval) and what the truth is;
:func:`item_coverage` pools the records of many seeds into, per item, the fraction of
trials whose result lies within U of the truth (and, for the two standard-deviation
items, whose 95 % interval holds the truth). ``gonio validate`` calls both.

Truths (from the bench's noise-free rerun, ``truth.json``):

========================  ===============================================================
K                         the instrument's own K at the 7.1 rounds, from the bench file
                          (:func:`scale_factor_truth`): K through the mount, K(1+ε(ω cos ψ))
                          cos ψ, times the mean over the rounds of 1 + g(θ_k)/(3600 θ_k)
                          (g the instrument's angle-position error); no set-up error (the
                          tilt × Earth-rate coupling, the table's errors) is part of it
K_l                       (max − min)/mean of those K_i, %
B_s                       population value √E[s²(M)]/T of the draft's statistic for this
                          instrument's noise (:func:`zero_stability_truth`: the bench's own
                          ARW, Gauss–Markov bias, RRW and quantisation through the readings'
                          covariance, plus the noise-free readings' own spread)
E                         per point: mean over the series of the noise-free deviation
                          (``systematic_deviation_arcsec``); every point counts
R                         ensemble value: max over points of √(mean over trials of s_i²)
C_v, C_g                  the same formula as the result, on the noise-free deviations
                          (results: the stated, bias-corrected readings; the draft's beside)
========================  ===============================================================
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from gonio.analysis.coverage import (chi_square_z, clopper_pearson, coverage_flags, two_sided,
                                     within)
from gonio.units import ARCSEC_PER_DEG
from gonio.specs.ogam_draft.items import RECORD_KEYS

__all__ = ["item_record", "trial_items", "item_coverage", "ITEM_TRUTHS", "scale_factor_truth",
           "chi_square_z",
           "disc_model_u", "repeatability_prediction",
           "zero_stability_truth", "item_monte_carlo", "PRESCRIBED"]

#: Items whose U is a standard's prescribed annex budget (stated as prescribed: not flagged
#: as over-wide): E under the draft's four Annex A lines.
PRESCRIBED = ("angle_deviation_draft",)


ITEM_TRUTHS = {
    "scale_factor": "the instrument's K at the 7.1 rounds from the bench file: K through the "
                    "mount times mean(1 + g(theta_k)/(3600 theta_k)), no set-up error",
    "scale_factor_disc": "as scale_factor; U with the tilt coupling's line for a tilt uniform "
                         "over the A.1 disc (semicircle, u = A/2) instead of the bound's "
                         "arcsine (u = A/sqrt 2)",
    "scale_factor_bound": "as scale_factor; result the 7.1 mean uncorrected, U with the "
                          "coupling at the A.1 bound (not stated when the tilt estimate "
                          "corrects K)",
    "scale_factor_nonlinearity": "(max - min)/mean of the instrument's own K_i at the 7.1 "
                                 "rounds (as scale_factor), %; result the bias-corrected range",
    "scale_factor_nonlinearity_draft": "as scale_factor_nonlinearity; result the draft's range "
                                       "as measured, U widened for its bias (not stated)",
    "zero_stability": "population: sqrt(E[s(M)^2])/T from the bench's noise parameters "
                      "(gonio.specs.ogam_draft.zero_stability_noise) and the noise-free readings",
    "zero_stability_draft": "as zero_stability; the draft's s(M)/T from the 15 readings",
    "zero_stability_model": "as zero_stability; the noise model's expected B_s (not stated)",
    "angle_deviation": "per point: mean over series of systematic_deviation_arcsec",
    "angle_deviation_draft": "as angle_deviation; U of the draft's four Annex A lines",
    "repeatability": "ensemble: max over points of sqrt(mean over trials of s_i^2)",
    "rate_consistency": "spread of the noise-free E_v over the reference angle, ppm; result "
                        "the bias-corrected range",
    "rate_consistency_draft": "as rate_consistency; result the draft's range as measured, U "
                              "widened for its bias (not stated)",
    "pointing_consistency": "spread of the noise-free E_g over the reference angle, %; result "
                            "corrected for the choice of each extreme",
    "pointing_consistency_draft": "as pointing_consistency; result the draft's range as "
                                  "measured (not stated)",
}


def _signed_extreme(v) -> float:
    """The value of largest magnitude, sign kept; NaN (a round with no reading) is left out
    (np.argmax would pick it), NaN only when nothing is left.

    >>> _signed_extreme([1.0, float("nan"), -3.0]), _signed_extreme([float("nan")])
    (-3.0, nan)
    """
    v = np.asarray(v, dtype=float)
    v = v[~np.isnan(v)]
    return float(v[int(np.argmax(np.abs(v)))]) if v.size else math.nan


def _consistency_truth(tr: pd.DataFrame, c, col: str, scale: float) -> float:
    """Spread of the noise-free per-condition extremes, at the result's points (as mounted:
    the mount's closed-form K; the tilt bias of 7.1's K is the budget's ``K_tilt`` line)."""
    pts = c.tables["points"]
    e = []
    for row in c.table.itertuples(index=False):
        v, src = getattr(row, col), row.source_test
        keep = pts.loc[pts[col] == v, "round"]
        rows = tr[(tr["test"] == src) & tr["round"].isin(keep)]
        if col == "rate_dps":
            rows = rows[np.isclose(rows["rate_dps"].to_numpy(dtype=float), float(v))]
        else:
            rows = rows[rows["orientation"] == v]
        if src == "angle_deviation":     # the reference condition taken from 7.4
            rows = rows[np.isclose(rows["rate_dps"].to_numpy(dtype=float), 60.0)]
        e.append(_signed_extreme(rows.groupby("round")["systematic_deviation_arcsec"].mean()))
    e = np.array(e)
    return float((e.max() - e.min()) / float(c.details["reference_angle_arcsec"]) * scale)


def zero_stability_truth(truth: dict, compensation_time_s: float | None) -> float | None:
    """B_s,pop = √E[s²(M)]/T (°/h) of the session's 7.3 readings on the bench it ran on.

    E[s²] (:func:`gonio.specs.ogam_draft.zero_stability_noise.expected_sample_variance`) from the
    bench's true noise parameters in ``truth["bench"]`` — angle random walk, the
    Gauss–Markov bias instability (σ, τ_c), rate random walk and the counter's dithered
    quantisation (1/12 count² per counter sample) — at the readings' times with the
    measured compensation's static phase, plus the spread of the noise-free readings
    (warm-up drift and whatever else the noise-free rerun holds). ``None`` without 7.3.
    """
    from gonio.specs.ogam_draft.zero_stability_noise import expected_sample_variance
    from gonio.units import S_PER_H, deg_sqrt_h_from_dph_sqrt_hz, \
        dph_per_sqrt_h_from_dph_sqrt_hz_per_s

    rows = [r for r in truth["readings"] if r["test"] == "zero_stability"]
    if len(rows) < 2:
        return None
    inst = truth["bench"]["instrument"]
    k = float(inst["nominal_scale_factor_counts_per_deg"])
    t = np.array([float(r["time_s"]) for r in rows])
    det = np.array([float(r["noise_free_counts"]) for r in rows]) / k * S_PER_H  # (°/h)·s
    q = S_PER_H / k / math.sqrt(12.0) if inst.get("quantisation") else 0.0
    S = expected_sample_variance(
        t, compensation_time_s, deterministic=det, Q=q,
        N=float(inst["arw_dpsh"]) / deg_sqrt_h_from_dph_sqrt_hz(1.0),
        K=float(inst["rrw_dphsh"]) / dph_per_sqrt_h_from_dph_sqrt_hz_per_s(1.0),
        gm_sigma=float(inst["bias_instability_dph"]),
        gm_tau_s=float(inst["bias_instability_tau_s"]))
    return math.sqrt(S) / float(t.max() - t.min())


def scale_factor_truth(truth: dict) -> tuple[float, np.ndarray]:
    """(K, K_i) of the instrument itself at the session's 7.1 rounds, counts/°, from the
    bench's parameters (never from a reading): the true K through the mount
    (``scale_factor_through_mount_counts_per_deg``, K(1+ε(ω cos ψ)) cos ψ) and the
    instrument's angle-position error g (its ``position_harmonics``, the error of the
    indicated angle after turning θ from the zeroing, draft 4.2): an instrument on an ideal
    set-up counts K(θ + (g(θ) − g(0))/3600) for θ turned, so K_i = K(1 + (g(θ_k) −
    g(0))/(3600 θ_k)) and K = mean K_i (draft 7.1). The tilt × Earth-rate coupling, the
    table's errors and the zero's drift are errors of the calibration, not of the instrument.
    """
    inst = truth["bench"]["instrument"]
    th = np.array([float(r["table_deg"]) for r in truth["readings"]
                   if r["test"] == "scale_factor"])

    def g(x_deg):     # Σ a_h sin(h·x + p_h), arcsec (the bench file's definition)
        return sum(float(h["amplitude_arcsec"]) * np.sin(int(h["order"]) * np.radians(x_deg)
                                                         + math.radians(float(h["phase_deg"])))
                   for h in inst.get("position_harmonics") or ()) + 0.0 * x_deg

    g = g(th) - g(np.zeros(1))[0]
    k_i = float(truth["scale_factor_through_mount_counts_per_deg"]) * (1.0 + g / (ARCSEC_PER_DEG * th))
    return float(np.mean(k_i)) if k_i.size else math.nan, k_i


def disc_model_u(b) -> float:
    """u_c of a :func:`~gonio.specs.ogam_draft.item_uncertainty.scale_factor_budget` with its
    ``K_tilt`` line (arcsine, half-width A: u = A/√2, the bound ψ_max at the worst azimuth)
    replaced by the distribution of the coupling over the mountings A.1 allows: the tilt
    vector uniform over the disc ψ ≤ ψ_max (azimuth uniform), so the coupling A·(ψ/ψ_max)·
    cos(α − α₀) is the projection of a uniform disc of radius A on one axis — the
    semicircle (Wigner) density 2√(A² − x²)/(πA²), variance A²/4 (the second moment of a
    uniform disc of radius A about a diameter per unit area, πA⁴/4 / πA²), u = A/2.

    >>> from gonio.specs.ogam_draft.item_uncertainty import scale_factor_budget
    >>> b = scale_factor_budget([3600.0, 3600.0], [180.0, 360.0], 0.0,
    ...                         tilt_bias_arcsec_per_deg=36.0)   # A = 3600·36/3600 counts/°
    >>> round(b.u_c * math.sqrt(2.0) / 36.0, 4), round(disc_model_u(b) * 2.0 / 36.0, 4)
    (1.0, 1.0)
    """
    tilt2 = sum(c.u ** 2 for c in b.components if c.symbol == "K_tilt")
    return math.sqrt(max(b.u_c ** 2 - tilt2 / 2.0, 0.0))


def item_record(report, truth: dict) -> dict:
    """Per measured item: value, U, interval, truth (None for ensemble truths) and the
    per-trial data the ensemble truths need.

    ``report`` is an :class:`gonio.specs.ogam_draft.calibration.Analysis`, ``truth`` the session's
    truth dict (``run_session(...).truth``).
    """
    tr = pd.DataFrame(truth["readings"])
    res = report.results
    out: dict = {}
    for name, iu in report.item_uncertainty.items():
        out[name] = {"value": float(getattr(res, name).value), "U": float(iu.U), "k": float(iu.k),
                     "u_c": float(iu.u_c),
                     "interval": list(iu.interval) if iu.interval is not None else None,
                     "truth": None}
        if iu.stated_by_interval:       # ν of its χ² interval (the Type A line of s)
            out[name]["nu"] = float(iu.components[0].dof)
    zr = getattr(report, "zero_stability_readings", None) or {}
    if "zero_stability" in out:
        comp = report.protocol.session.static_s \
            if report.protocol.session.earth_compensation == "measured" else None
        t_bs = zero_stability_truth(truth, comp)
        out["zero_stability"]["value"] = float(report.item_uncertainty["zero_stability"].value)
        out["zero_stability"]["truth"] = t_bs
        out["zero_stability"]["stated"] = zr.get("stated", "draft")
        other = "draft" if zr.get("stated") == "model" else "model"
        d = zr.get(other)
        if d is not None:
            out[f"zero_stability_{other}"] = {
                "value": float(d.value), "U": float(d.U), "k": float(d.k),
                "u_c": float(d.u_c), "interval": list(d.interval) if d.interval is not None else None,
                "truth": t_bs, "stated": other}
    if "scale_factor" in out:
        k_true, k_i = scale_factor_truth(truth)
        out["scale_factor"]["truth"] = k_true
        b = report.item_uncertainty["scale_factor"]
        bound = b.beside if b.correction is not None else b   # K_tilt at the A.1 bound
        u_disc = disc_model_u(bound)
        # the K each budget is about: the value of the budget whose U it checks
        out["scale_factor_disc"] = dict(out["scale_factor"], value=float(bound.value),
                                        U=float(bound.k) * u_disc, u_c=float(u_disc))
        if b.correction is not None:    # stated: K corrected by the measured tilt
            out["scale_factor_bound"] = dict(out["scale_factor"], value=float(bound.value),
                                             U=float(bound.U), k=float(bound.k),
                                             u_c=float(bound.u_c))
        # the value the sealed Result states (corrected by the measured tilt, a calibrated table)
        out["scale_factor"]["value"] = float(report.item(res.scale_factor).value)
        if "scale_factor_nonlinearity" in out:
            kl = out["scale_factor_nonlinearity"]
            kl["truth"] = float((k_i.max() - k_i.min()) / k_i.mean() * 100.0)
            d = report.item_uncertainty["scale_factor_nonlinearity"].beside
            if d is not None:       # the draft's range as measured, kept beside the stated one
                out["scale_factor_nonlinearity_draft"] = dict(
                    kl, value=float(d.value), U=float(d.U), k=float(d.k), u_c=float(d.u_c),
                    interval=None)
            kl["value"] = float(report.item_uncertainty["scale_factor_nonlinearity"].value)
    if "angle_deviation" in out:
        e = res.angle_deviation.table
        ad = tr[(tr["test"] == "angle_deviation")
                & np.isclose(tr["rate_dps"].to_numpy(dtype=float), 60.0)]
        t_i = ad.groupby("round")["systematic_deviation_arcsec"].mean()
        out["angle_deviation"]["points"] = [float(x) for x in e["E_arcsec"]]
        out["angle_deviation"]["truth_points"] = [float(t_i[r]) for r in e["round"]]
    if "repeatability" in out:
        out["repeatability"]["s_points"] = [float(x) for x in res.repeatability.table["R_arcsec"]]
    for name, col, scale in (("rate_consistency", "rate_dps", 1e6),
                             ("pointing_consistency", "orientation", 100.0)):
        if name in out:
            out[name]["truth"] = _consistency_truth(tr, getattr(res, name), col, scale)
            d = report.item_uncertainty[name].beside
            if d is not None:       # the draft's range as measured, kept beside the stated one
                out[name + "_draft"] = dict(out[name], value=float(d.value), U=float(d.U),
                                            k=float(d.k), u_c=float(d.u_c), interval=None)
                out[name]["value"] = float(report.item_uncertainty[name].value)
    return out


def trial_items(report, truth: dict) -> dict:
    """:func:`item_record` with E's U from the physical budget (what ``gonio calibrate``
    certifies by default), and the draft budget's as ``angle_deviation_draft``.

    ``report`` may have been made with either budget kind; the other is evaluated here
    from the same results (:func:`gonio.calibrate.deviation_budget`).
    """
    from gonio.specs.ogam_draft.calibration import (angle_deviation_at_measured_tilt,
                                                    angle_deviation_at_table,
                                                    deviation_budget, session_settings)

    rec = item_record(report, truth)
    if "angle_deviation" not in rec:
        return rec
    settings, _ = session_settings(report.readings, report.protocol)
    other = "physical" if report.budget_kind == "draft" else "draft"
    res, e_tilt, e_table = report.results, None, None
    if other == "physical":     # the physical E: corrected where the tilt was measured, and
        res, e_tilt = angle_deviation_at_measured_tilt(res, report.readings, report.protocol)
        res, e_table = angle_deviation_at_table(        # by a calibrated table
            res, report.readings, report.protocol, getattr(report, "table_calibration", None))
    b, _, _ = deviation_budget(res, report.readings, report.protocol, settings,
                               kind=other, tilt_measured=e_tilt, table_measured=e_table)
    mine = dict(rec["angle_deviation"])
    own = getattr(report.uncertainty, "max_interval", None)
    if own:             # the interval of max|E_i| this analysis states (either budget)
        mine["max_interval"] = [float(own["lower_arcsec"]), float(own["upper_arcsec"])]
    alt = {**mine, "U": float(b.U_arcsec), "u_c": float(b.u_c_arcsec), "k": float(b.k)}
    if b.points:        # the physical budget per point: each E_i judged on its own U
        alt["U_points"] = [float(p["U_arcsec"]) for p in b.points]
        alt["u_c_points"] = [float(p["u_c_arcsec"]) for p in b.points]
    if b.max_interval:  # the interval of max|E_i|'s truth (every pattern)
        alt["max_interval"] = [float(b.max_interval["lower_arcsec"]),
                               float(b.max_interval["upper_arcsec"])]
    e = res.angle_deviation
    if "E_draft_arcsec" in e.table:    # E corrected at the measured tilt: the draft's as measured
        pts = e.table["E_arcsec" if other == "physical" else "E_draft_arcsec"]
        alt["points"] = [float(x) for x in pts]
        alt["value"] = float(e.value if other == "physical"
                             else e.details["estimates"]["draft"]["value"])
    rec["angle_deviation"], rec["angle_deviation_draft"] = (alt, mine) if other == "physical" \
        else (mine, alt)
    return rec


def item_coverage(records: list[dict], intrinsic_points=None,
                  judge_spread: bool = True) -> dict:
    """Per item, over the trials: coverage of |result − truth| ≤ U (k as stated), and for
    B_s and R of the truth by the 95 % interval; ``two_sided`` (:func:`two_sided`): the
    coverage with its Clopper–Pearson interval, the spread of z = (result − truth)/u_c and
    the flags (under-covers, over-wide).

    ``intrinsic_points``: E's truth per point on an ideal set-up (no tilt, Earth rate,
    bias or table error: what a certificate is about); E's items then also get
    ``within_U_intrinsic``, and E under gonio's physical budget (``angle_deviation``) is
    judged two-sided against it (``two_sided["truth"] = "intrinsic"``): that budget's
    tilt × Earth-rate line allows for a tilt the laboratory only bounds, which the
    as-mounted truth already contains. The draft's budget keeps the as-mounted truth.

    >>> recs = [{"scale_factor": {"value": v, "U": 0.2, "interval": None, "truth": 0.0}}
    ...         for v in (0.1, -0.1, 0.3, 0.0)]
    >>> c = item_coverage(recs)["scale_factor"]
    >>> c["within_U"]["fraction"], c["within_U"]["n"]
    (0.75, 4)
    """
    names = [n for n in RECORD_KEYS if any(n in r for r in records)]
    out = {}
    for name in names:
        rs = [r[name] for r in records if name in r]
        vals = np.array([r["value"] for r in rs])
        U = np.array([r["U"] for r in rs])
        # z on u_c (an item stated by its interval has U = distance to the upper limit)
        u_c = np.array([r["u_c"] if r.get("u_c") else U_i / (r.get("k") or math.nan)
                        for r, U_i in zip(rs, U)], dtype=float)
        item = {"trials": len(rs), "truth": ITEM_TRUTHS[name], "mean_U": float(U.mean())}
        own = name not in PRESCRIBED
        if name.startswith("angle_deviation"):
            d = np.array([np.subtract(r["points"], r["truth_points"]) for r in rs])
            if all("U_points" in r for r in rs):     # a U per point (the physical budget)
                U = np.array([r["U_points"] for r in rs], dtype=float)
                u_c = np.array([r["u_c_points"] for r in rs], dtype=float)
                item["mean_U"] = float(U.mean())
            else:
                U, u_c = U[:, None], u_c[:, None]
            item["within_U"] = within(np.abs(d) <= U)
            item["two_sided"] = two_sided(d, U, u_c, own)
            if intrinsic_points is not None:
                di = np.array([np.subtract(r["points"], intrinsic_points) for r in rs])
                item["within_U_intrinsic"] = within(np.abs(di) <= U)
                if own:      # the physical budget is about the instrument: judged on that
                    item["two_sided"] = dict(two_sided(di, U, u_c, own),
                                             truth="intrinsic")
            # the draft's Annex A form, E = ± max|E_i| with the budget's U (the largest
            # point's), against the truth's max|E_i| (the intrinsic one where E is judged on
            # it): not the statement — E is certified by its interval (max_interval below)
            tp = np.array([intrinsic_points if intrinsic_points is not None and own
                           else r["truth_points"] for r in rs], dtype=float)
            d_max = np.abs(vals) - np.abs(tp).max(axis=1)
            u_max = np.array([r["u_c"] for r in rs], dtype=float)
            item["max_statement"] = dict(two_sided(d_max, np.array([r["U"] for r in rs]),
                                                   u_max, own),
                                         truth="intrinsic" if intrinsic_points is not None
                                         and own else "as mounted")
            if rs and all(r.get("max_interval") for r in rs):
                item["max_interval"] = max_interval_coverage(
                    np.abs(vals), np.array([r["max_interval"] for r in rs], dtype=float),
                    np.abs(tp).max(axis=1), own,
                    points=[r["points"] for r in rs] if all("u_c_points" in r for r in rs)
                    else None,
                    u_points=[r.get("u_c_points") for r in rs])
        elif name == "repeatability":
            _repeatability_item(item, rs, vals, U, u_c, own)
        else:
            t = np.array([r["truth"] for r in rs])
            item["within_U"] = within(np.abs(vals - t) <= U)
            item["two_sided"] = two_sided(vals - t, U, u_c, own)
            if (not name.startswith("zero_stability") and rs
                    and all(r.get("interval") is not None for r in rs)):
                # a range stated by its confidence interval (K_l, C_v, C_g): the interval
                # holding the truth is its coverage, with its Clopper–Pearson interval
                iv = np.array([r["interval"] for r in rs])
                hold = (iv[:, 0] <= t) & (t <= iv[:, 1])
                item["interval_holds_truth"] = dict(
                    within(hold), clopper_pearson=list(clopper_pearson(int(hold.sum()),
                                                                       int(hold.size))),
                    mean_width=float(np.mean(iv[:, 1] - iv[:, 0])))
            if name.startswith("zero_stability"):
                item["population_truth"] = float(np.mean(t))
                item["k_mean"] = float(np.mean([r.get("k", math.nan) for r in rs]))
                if all(r.get("interval") is not None for r in rs):
                    iv = np.array([r["interval"] for r in rs])
                    item["interval_holds_truth"] = within((iv[:, 0] <= t) & (t <= iv[:, 1]))
                    _chi_square_spread(item, rs, vals, t)
                st = sorted({r.get("stated", "draft") for r in rs})
                if st:
                    item["stated"] = st
        if not judge_spread:
            ts = item["two_sided"]
            ts["flags"] = [f for f in ts["flags"] if f != "over-wide"]
            ts["spread_judged"] = False
            for key in ("max_statement", "max_interval"):
                if key in item:
                    item[key]["flags"] = [f for f in item[key]["flags"] if f != "over-wide"]
        out[name] = item
    return out


def max_interval_coverage(m, iv, theta, own: bool = True, points=None, u_points=None) -> dict:
    """Coverage of E's extreme by its interval (:func:`uncertainty.extreme.max_abs_interval`)
    over the trials: ``m`` = max|E_i|, ``iv`` the [lower, upper] per trial, ``theta`` the
    truth's max|E_i|. The interval holding θ is the coverage (with its Clopper–Pearson
    interval); z scales each side to a standard normal one, z = (m − θ)/((upper − m)/1.96)
    where θ lies above m, (m − θ)/((m − lower)/1.96) below (an interval exact at its
    worst pattern has z sd ≈ 1 there; an every-pattern interval is wider elsewhere).

    That z scales each side by its half-width over 1.96, as if the interval were ± 1.96 sd of
    a normal estimate; it is not (its factors are c_H = 1.666 above and the Šidák c_L = 2.858
    below at twelve points), so with ``points`` (the E_i, per trial) and ``u_points`` (their
    u_c) the statement's own z is given beside it, ``z_level``
    (:func:`uncertainty.extreme.max_abs_level_z`: the level at which the interval's own family
    just holds θ, as a normal quantile, signed; root mean square 1 at each side's worst pattern,
    less elsewhere), and the misses on each side, ``miss_above`` (θ above the upper end) and
    ``miss_below`` (θ below the lower end), each with its Clopper–Pearson interval.

    >>> r = max_interval_coverage([1.0, 1.0], [[0.5, 1.4], [0.8, 1.2]], [1.1, 0.7])
    >>> r["hits"], round(r["z_mean"], 3)
    (1, 1.225)
    """
    m, iv, theta = (np.asarray(m, dtype=float), np.asarray(iv, dtype=float),
                    np.asarray(theta, dtype=float))
    hold = (iv[:, 0] <= theta) & (theta <= iv[:, 1])
    half = np.where(theta >= m, iv[:, 1] - m, m - iv[:, 0]) / 1.959963984540054
    z = np.where(half > 0, (m - theta) / np.where(half > 0, half, 1.0), np.nan)
    ok = np.isfinite(z)
    out = two_sided(np.where(hold, 0.0, np.inf), np.ones(m.size), np.ones(m.size), own)
    z_sd = float(np.std(z[ok], ddof=1)) if ok.sum() > 1 else None
    out.update(z_mean=float(np.mean(z[ok])) if ok.any() else None, z_sd=z_sd,
               flags=coverage_flags(out["coverage"], z_sd, own),
               mean_width=float(np.mean(iv[:, 1] - iv[:, 0])))
    n = int(m.size)
    for key, miss in (("miss_above", theta > iv[:, 1]), ("miss_below", theta < iv[:, 0])):
        k = int(miss.sum())
        out[key] = {"n": k, "fraction": k / n if n else None,
                    "clopper_pearson": list(clopper_pearson(k, n))}
    if points is not None and u_points is not None:
        from uncertainty.extreme import max_abs_level_z

        zl = np.array([max_abs_level_z(x, u, t) for x, u, t in zip(points, u_points, theta)])
        out["z_level"] = {"mean": float(zl.mean()),
                          "sd": float(zl.std(ddof=1)) if zl.size > 1 else None,
                          "rms": float(np.sqrt(np.mean(zl * zl)))}
    return out


def repeatability_prediction(sigma, nu: float, n: int = 400) -> dict:
    """What R's exact distribution (draft 7.5's R = max_i s_i; P(R ≤ x) = Π_i F_χ²(ν x²/σ_i²;
    ν), :func:`uncertainty.stdev.max_stdev_cdf`) gives at the points' σ_i ``sigma`` (the
    study's ensemble values), independently of the trials' own z: the mean and sd of the
    χ² z, Φ⁻¹(F_χ²(ν R²/θ²; ν)) with θ = max σ_i (midpoint quadrature over n quantiles of
    R), and the probability that the stated interval (its one-sided limit,
    :func:`uncertainty.stdev.max_stdev_union_interval`) holds θ.

    Twelve equal σ_i: z = Φ⁻¹(U^{1/12}), U uniform, mean +1.63, sd 0.57; the interval
    fails only when all twelve s_i fall below θ/1.645: 1 − 0.05¹²:

    >>> p = repeatability_prediction([1.0] * 12, 9)
    >>> round(p["z_chi2_mean"], 2), round(p["z_chi2_sd"], 2), p["interval_coverage"] > 0.9999
    (1.63, 0.57, True)
    """
    from scipy.stats import chi2, norm

    from uncertainty.stdev import max_stdev_cdf, max_stdev_quantile, max_stdev_union_interval

    sig = np.asarray(sigma, dtype=float)
    theta = float(sig.max())
    r = np.array([max_stdev_quantile((k + 0.5) / n, sig, nu) for k in range(n)])
    z = norm.isf(chi2.sf(nu * (r / theta) ** 2, nu))
    factor = max_stdev_union_interval(1.0, nu, sig.size)[1]
    return {"z_chi2_mean": float(z.mean()), "z_chi2_sd": float(z.std()),
            "interval_coverage": float(1.0 - max_stdev_cdf(theta / factor, sig, nu)),
            "nu": float(nu), "points": int(sig.size),
            "source": "R's exact distribution at the study's ensemble sigma_i"}


def _repeatability_item(item: dict, rs: list, vals, U, u_c, own: bool) -> None:
    """R in :func:`item_coverage`: judged against the ensemble truth max_i σ_i (σ_i the
    RMS of the trials' s_i), its interval's coverage, and R's predicted distribution."""
    # a position read in one series of a trial (the other set aside by the
    # screening) has no s_i there (NaN, 7.5): σ_i is the RMS over the trials that
    # have it; a position no trial has is left out (``positions_without_s``)
    s2 = np.array([r["s_points"] for r in rs], dtype=float) ** 2
    has = np.isfinite(s2)
    n_has = has.sum(axis=0)
    sigma_i = np.sqrt(np.where(has, s2, 0.0).sum(axis=0)[n_has > 0] / n_has[n_has > 0])
    if (~has).any():
        item["positions_without_s"] = {
            "trial_points": int((~has).sum()), "positions": int((n_has == 0).sum())}
    truth = float(sigma_i.max())
    item["ensemble_truth"] = truth
    item["within_U"] = within(np.abs(vals - truth) <= U)
    item["two_sided"] = two_sided(vals - truth, U, u_c, own)
    iv = np.array([r["interval"] for r in rs])
    hold = (iv[:, 0] <= truth) & (truth <= iv[:, 1])
    item["interval_holds_truth"] = dict(
        within(hold), clopper_pearson=list(clopper_pearson(int(hold.sum()),
                                                           int(hold.size))),
        mean_width=float(np.mean(iv[:, 1] - iv[:, 0])))
    _chi_square_spread(item, rs, vals, truth)
    if rs and all(r.get("nu") for r in rs):
        # R's distribution over the positions with a σ_i, each with the trials' ν:
        # where a trial lacks a position its R is the max over fewer s_i (at most
        # as large), so with ``positions_without_s`` the prediction is approximate
        item["predicted"] = repeatability_prediction(sigma_i, min(r["nu"] for r in rs))
        if (~has).any():
            item["predicted"]["approximate"] = ("a trial lacks s_i at some positions "
                                                "(readings set aside)")


def _chi_square_spread(item: dict, rs: list, vals, truth) -> None:
    """``z_chi2`` (mean, sd) of :func:`chi_square_z` for an item stated by its χ² interval."""
    if rs and all(r.get("nu") for r in rs):
        z = chi_square_z(vals, truth, [r["nu"] for r in rs])
        z = z[np.isfinite(z)]
        if z.size > 1:
            item["z_chi2"] = {"mean": float(z.mean()), "sd": float(z.std(ddof=1)),
                              "rms": float(np.sqrt(np.mean(z * z)))}


def item_monte_carlo(report, trials: int, seed: int = 0) -> dict:
    """JCGM 101 Monte Carlo of every item budget of one calibration, each compared with its
    GUM result by the numerical tolerance test (JCGM 101 8.2; d_low, d_high, δ, passed).

    K, K_l, R, C_v, C_g: :func:`gonio.specs.ogam_draft.item_uncertainty.monte_carlo_item`
    on the additive budget; B_s: through its own model (both readings, the stated one as
    ``zero_stability``); E: the Annex A budget of both kinds (``angle_deviation`` the
    physical one, ``angle_deviation_draft`` the annex's four lines), drawn by
    :func:`gonio.specs.ogam_draft.calibration.deviation_budget` with ``monte_carlo_trials``.
    """
    from gonio.specs.ogam_draft.calibration import deviation_budget, session_settings
    from gonio.specs.ogam_draft.item_uncertainty import monte_carlo_item

    out: dict = {}
    for name, b in report.item_uncertainty.items():
        if name == "angle_deviation":
            continue
        out[name] = monte_carlo_item(b, trials, seed).to_dict()
    zr = getattr(report, "zero_stability_readings", None) or {}
    other = "draft" if zr.get("stated") == "model" else "model"
    if zr.get(other) is not None:
        out[f"zero_stability_{other}"] = monte_carlo_item(zr[other], trials, seed).to_dict()
    if "angle_deviation" in report.item_uncertainty:
        settings, _ = session_settings(report.readings, report.protocol)
        for kind, key in (("physical", "angle_deviation"), ("draft", "angle_deviation_draft")):
            b, _, _ = deviation_budget(report.results, report.readings, report.protocol,
                                       settings, kind=kind, monte_carlo_trials=trials,
                                       seed=seed)
            mc, v = b.monte_carlo, b.validation
            out[key] = {"item": "angle_deviation", "model": "linear", "trials": int(trials),
                        "mc_value": float(mc.value), "mc_u": float(mc.u),
                        "mc_interval": [float(mc.low), float(mc.high)],
                        "gum_interval": [float(x) for x in v.gum_interval],
                        "d_low": float(v.d_low), "d_high": float(v.d_high),
                        "delta": float(v.delta), "ndig": 2, "passed": bool(v.passed),
                        "gum_contains_mc": bool(v.gum_interval[0] <= mc.low
                                                and mc.high <= v.gum_interval[1])}
    return {k: out[k] for k in RECORD_KEYS if k in out}
