"""The series each figure of the optical certificate draws, computed once at calibration time
and sealed in ``results.json`` (``extra.figures``): the renderer (``gonio.specs.ogam_draft.figures``)
draws them and computes nothing, so a certificate can be drawn again from the stored file.

One entry per figure key (``deviation``, ``repeatability``, ``tilt``, ``scale_factor``,
``zero_stability``, ``rate``, ``pointing``, ``budget``); an item not measured gives
``{"measured": False}``. A file with more series than :data:`FIGURE_SERIES` (or more 7.1
rounds than :data:`FIGURE_POINTS`) gives the range and mean at each abscissa (``band``)
instead of every series.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from gonio.specs.ogam_draft.tilt import elliptic_error_arcsec, rigid_error_arcsec
from gonio.units import S_PER_MIN, deg_to_arcsec, s_to_h

#: Series drawn one by one in a figure; more are drawn as their range and mean.
FIGURE_SERIES: int = 20
#: Points drawn one by one (7.1 rounds); more are drawn as their range and mean per angle.
FIGURE_POINTS: int = 400
#: Abscissae of the tilt figure: 0° to 360° in half degrees (Annex A.4.2).
TILT_POINTS: int = 721


def _scalar(v):
    """A numpy scalar as the Python scalar it holds (JSON-able)."""
    return v.item() if hasattr(v, "item") else v


def _floats(x) -> list[float]:
    return [float(v) for v in np.asarray(x, dtype=float)]


def band(df: pd.DataFrame, x: str, y: str) -> dict:
    """The range (min … max) and the mean of ``y`` at each ``x`` (rounded to 1e-9)."""
    g = df.assign(_x=np.round(df[x].to_numpy(float), 9)).groupby("_x", sort=True)[y]
    st = g.agg(["min", "max", "mean"])
    return {"x": _floats(st.index.to_numpy(float)), "min": _floats(st["min"]),
            "max": _floats(st["max"]), "mean": _floats(st["mean"])}


def deviation(c) -> dict:
    """E_ij of every series against position and the mean E_i (draft 7.4, Fig. A.4)."""
    if not c.measured:
        return {"measured": False}
    rd = c.tables["readings"]
    n = int(rd["series"].nunique())
    out: dict = {"measured": True, "n_series": n}
    if n > FIGURE_SERIES:
        out["band"] = band(rd, "table_deg", "E_arcsec")
    else:
        out["series"] = []
        for s, g in rd.groupby("series", sort=True):
            g = g.sort_values("table_deg")
            out["series"].append({"series": _scalar(s), "x": _floats(g["table_deg"]),
                                  "y": _floats(g["E_arcsec"])})
    t = c.table.sort_values("position_deg")
    out["mean"] = {"x": _floats(t["position_deg"]), "y": _floats(t["E_arcsec"])}
    return out


def repeatability(c) -> dict:
    """The Bessel standard deviation per position (draft 7.5, Fig. A.5)."""
    if not c.measured:
        return {"measured": False}
    t = c.table.sort_values("position_deg")
    return {"measured": True, "x": _floats(t["position_deg"]), "y": _floats(t["R_arcsec"])}


def tilt(psi_deg: float) -> dict:
    """The tilt error at the budget's tilt bound ψ: the elliptic model (Annex A.4.2), the
    rigid model after the scale factor's calibration and before it
    (:mod:`gonio.specs.ogam_draft.tilt`)."""
    theta = np.linspace(0.0, 360.0, TILT_POINTS)
    return {"psi_deg": float(psi_deg), "theta_deg": _floats(theta),
            "elliptic_arcsec": _floats(elliptic_error_arcsec(theta, psi_deg)),
            "rigid_arcsec": _floats(rigid_error_arcsec(theta, psi_deg)),
            "rigid_uncalibrated_arcsec": _floats(rigid_error_arcsec(theta, psi_deg,
                                                                    calibrated=False))}


def scale_factor(c) -> dict:
    """K_i of each round against its angle (draft 7.1)."""
    if not c.measured:
        return {"measured": False}
    t = c.table
    if len(t) > FIGURE_POINTS:
        return {"measured": True, "n_rounds": int(len(t)),
                "band": band(t, "table_deg", "K_i_counts_per_deg")}
    return {"measured": True, "n_rounds": int(len(t)), "x": _floats(t["table_deg"]),
            "y": _floats(t["K_i_counts_per_deg"])}


def zero_stability(c) -> dict:
    """The readings M_n against time (min, ″) and each series' linear drift (draft 7.3)."""
    if not c.measured or "readings" not in c.tables:
        return {"measured": False}
    rd = c.tables["readings"]
    n = int(rd["series"].nunique())
    if n > FIGURE_SERIES:
        t0 = rd.groupby("series")["time_s"].transform("min")
        b = pd.DataFrame({"t_min": (rd["time_s"] - t0).to_numpy(float) / S_PER_MIN,
                          "m_arcsec": deg_to_arcsec(rd["angle_deg"].to_numpy(float))})
        return {"measured": True, "n_series": n, "band": band(b, "t_min", "m_arcsec")}
    drift = {int(r["series"]): r for _, r in c.table.iterrows()} \
        if "drift_deg_per_h" in c.table else {}
    series = []
    for s, g in rd.groupby("series", sort=True):
        g = g.sort_values("time_s")
        t_s = (g["time_s"] - g["time_s"].iloc[0]).to_numpy(dtype=float)
        entry = {"series": _scalar(s), "t_min": _floats(t_s / S_PER_MIN),
                 "m_arcsec": _floats(deg_to_arcsec(g["angle_deg"].to_numpy())), "drift": None}
        d = drift.get(int(s))
        if d is not None and math.isfinite(d["drift_deg_per_h"]):
            line_deg = d["drift_intercept_deg"] + d["drift_deg_per_h"] * s_to_h(t_s)
            entry["drift"] = {"drift_deg_per_h": float(d["drift_deg_per_h"]),
                              "line_arcsec": _floats(deg_to_arcsec(line_deg))}
        series.append(entry)
    return {"measured": True, "n_series": n, "series": series}


def consistency(c, col: str) -> dict:
    """E_i per position for each condition of 7.6 (``col`` rate_dps) or 7.7 (orientation),
    the reference condition first."""
    if not c.measured or "points" not in c.tables:
        return {"measured": False}
    pts = c.tables["points"]
    ref = set(c.table.loc[c.table["reference"].astype(bool), col]) \
        if "reference" in c.table else set()
    groups = sorted(pts.groupby(col, sort=True), key=lambda vg: vg[0] not in ref)
    out = []
    for v, g in groups:
        g = g.sort_values("position_deg")
        out.append({"value": _scalar(v), "reference": v in ref,
                    "x": _floats(g["position_deg"]), "y": _floats(g["E_arcsec"])})
    return {"measured": True, "groups": out}


def budget(d: dict) -> dict:
    """|c_i|·u_i of E's budget components with u_c and U (Annex A.5–A.7): ``d`` the budget's
    ``to_dict()`` (kept even when E was not measured, for reference). Where the points carry
    the table's bound (``U_bound_arcsec``), the stated U = k·u + b is not the budget's
    k·u_c: ``bound`` then holds u of the lines other than the table's, k·u, b and U, and
    ``u_c_stated`` is False (the bars' u_c, the table line at MPE/√3, is beside, not stated);
    ``U_arcsec`` is the budget's own U only where no point has a bound."""
    out = {"components": [{"symbol": c["symbol"], "type": c["type"],
                           "contribution_arcsec": c["contribution_arcsec"]}
                          for c in d["components"]],
           "u_c_arcsec": d["u_c_arcsec"], "U_arcsec": d["U_arcsec"], "u_c_stated": True}
    if d.get("U_bound_arcsec") is not None:
        out.update(u_c_stated=False, U_arcsec=None,
                   bound={"u_arcsec": d["u_without_table_arcsec"],
                          "ku_arcsec": d["ku_arcsec"],
                          "b_arcsec": d["table_bound_arcsec"],
                          "U_arcsec": d["U_bound_arcsec"]})
    return out


def figure_series(results, e_budget) -> dict:
    """Every figure's series of one calibration (``results`` the seven items,
    ``e_budget`` E's :class:`~gonio.specs.ogam_draft.budget.AnnexABudget`)."""
    return {"deviation": deviation(results.angle_deviation),
            "repeatability": repeatability(results.repeatability),
            "tilt": tilt(float(e_budget.parameters["tilt_deg"])),
            "scale_factor": scale_factor(results.scale_factor),
            "zero_stability": zero_stability(results.zero_stability),
            "rate": consistency(results.rate_consistency, "rate_dps"),
            "pointing": consistency(results.pointing_consistency, "orientation"),
            "budget": budget(e_budget.to_dict())}
