"""The optical draft's certificate figures, drawn on matplotlib Figure objects from a
calibration's results.json (the series ``extra.figures`` holds, computed when the calibration
ran: :mod:`gonio.specs.ogam_draft.figure_data`).

Contents
========
=====================  =================================================================
:data:`FIGURES`        (key, caption label, draw function), in the certificate's order
:func:`draw_deviation`    E_ij of every series against position, mean E_i (draft Fig. A.4)
:func:`draw_repeatability`  Bessel s_i per position and R = max (draft Fig. A.5, 7.5)
:func:`draw_tilt`      elliptic-projection error at the tilt bound (Annex A.4.2, Fig. A.3),
                       rigid-body model beside it
:func:`draw_scale_factor`   K_i per round and K (7.1)
:func:`draw_zero_stability` readings M_n against time and the drift results.json states (7.3)
:func:`draw_rate`      E_i per position for each rate (7.6)
:func:`draw_pointing`  E_i per position for each axis direction (7.7)
:func:`draw_budget`    |c_i|·u_i of the Annex A components, u_c and U
=====================  =================================================================

Each ``draw_*`` takes ``(fig, spec, res, L, truth)`` (the figure contract of
:mod:`gonio.report.figures`). An item that was not measured gives an empty panel saying so.
Every number in a legend is rounded by the certificate's rule
(:mod:`gonio.specs.ogam_draft.stated`); nothing is computed here that ``results.json`` does
not hold (the 7.3 drift and the tilt curves are the calibration's).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from gonio.kit.render import (display, display_number, display_uncertainty, empty_panel,
                              legend_above, plain_axes)


def _truth_by_position(truth: dict | None, test: str) -> tuple[np.ndarray, np.ndarray] | None:
    """Mean systematic deviation per position of the virtual bench's truth, if given."""
    if not truth or not truth.get("readings"):
        return None
    pos, val = [], []
    for r in truth["readings"]:
        if r.get("test") == test and r.get("table_deg") is not None and \
                r.get("systematic_deviation_calibrated_arcsec") is not None and \
                (test != "angle_deviation" or
                 (r.get("orientation", "up") == "up" and r.get("rate_dps") == 60.0)):
            pos.append(float(r["table_deg"]))
            val.append(float(r["systematic_deviation_calibrated_arcsec"]))
    if not pos:
        return None
    pos, val = np.asarray(pos), np.asarray(val)
    u = np.unique(pos)
    return u, np.array([val[pos == p].mean() for p in u])


def _band(ax, b: dict, label: str, label_mean: str | None = None) -> None:
    """The range (min … max) and the mean at each abscissa (``b``: a figure series' ``band``),
    for a large file whose every series or round would not be readable one by one."""
    xs = np.asarray(b["x"], dtype=float)
    ax.vlines(xs, b["min"], b["max"], color="C0", lw=3, alpha=0.35, label=label)
    ax.plot(xs, b["mean"], "o", color="C0", ms=3, label=label_mean)


def _series(res: dict, key: str) -> dict:
    """The series figure ``key`` draws (results.json ``extra.figures``, computed when the
    calibration ran)."""
    return res["extra"]["figures"][key]


def _shown(res: dict, name: str) -> str:
    """Item ``name``'s value as the certificate states it (for a legend)."""
    from gonio.specs.ogam_draft.stated import stated_item

    return str(stated_item(res, name)["value"])


def draw_deviation(fig, spec, res, L, truth=None) -> None:
    """Deviation curves E_ij of every series against position (draft 7.4, Fig. A.4)."""
    ax = fig.add_subplot(spec)
    f = _series(res, "deviation")
    if not f["measured"]:
        return empty_panel(ax, L)
    if "band" in f:                                 # a large file: the range of all series
        _band(ax, f["band"], L["lg_all_series"].format(n=f["n_series"]))
    else:
        for g in f["series"]:
            ax.plot(g["x"], g["y"], "-o", lw=0.8, ms=2.5, alpha=0.6,
                    label=f"{L['lg_series']} {g['series']}" if f["n_series"] <= 10 else None)
    ax.plot(f["mean"]["x"], f["mean"]["y"], "k-", lw=2.0, label=L["lg_mean"])
    tr = _truth_by_position(truth, "angle_deviation")
    if tr is not None:
        ax.plot(tr[0], tr[1], "r--", lw=1.2, label=L["truth"])
    ax.axhline(0, color="0.3", lw=0.6)
    ax.set_xlabel(L["ax_position"])
    ax.set_ylabel(L["ax_deviation"])
    plain_axes(ax)
    legend_above(ax, ncol=6)


def draw_repeatability(fig, spec, res, L, truth=None) -> None:
    """Bessel standard deviation per position and R = max (draft 7.5, Fig. A.5)."""
    ax = fig.add_subplot(spec)
    f = _series(res, "repeatability")
    if not f["measured"]:
        return empty_panel(ax, L)
    ax.plot(f["x"], f["y"], "o-", color="C0", lw=1.2, ms=4, label=L["ax_std"])
    ax.axhline(res["items"]["repeatability"]["value"], color="C3", ls="--", lw=1,
               label=f"{L['lg_R']} {_shown(res, 'repeatability')}″")
    ax.set_ylim(bottom=0)
    ax.set_xlabel(L["ax_position"])
    ax.set_ylabel(L["ax_std"])
    plain_axes(ax)
    legend_above(ax, ncol=2)


def draw_tilt(fig, spec, res, L, truth=None) -> None:
    """Tilt error at the budget's tilt bound: elliptic model (Annex A.4.2) and rigid model
    (the curves :mod:`gonio.specs.ogam_draft.tilt` gave when the calibration ran)."""
    f = _series(res, "tilt")
    sub = spec.subgridspec(1, 2, wspace=0.35)
    theta = f["theta_deg"]
    ax = fig.add_subplot(sub[0])
    ax.plot(theta, f["elliptic_arcsec"], "C0-", lw=1.5,
            label=L["lg_elliptic"].format(psi=display_number(f["psi_deg"], 3)))
    ax.plot(theta, f["rigid_arcsec"], "C2--", lw=1.2, label=L["lg_rigid"])
    ax.set_xlabel(L["ax_position"])
    ax.set_ylabel(L["ax_tilt"])
    ax.set_xticks(np.arange(0, 361, 90))
    legend_above(ax, ncol=1)
    ax2 = fig.add_subplot(sub[1])
    ax2.plot(theta, f["rigid_uncalibrated_arcsec"], "C1-", lw=1.5, label=L["lg_rigid_uncal"])
    ax2.set_xlabel(L["ax_position"])
    ax2.set_ylabel(L["ax_tilt"])
    ax2.set_xticks(np.arange(0, 361, 90))
    legend_above(ax2, ncol=1)


def draw_scale_factor(fig, spec, res, L, truth=None) -> None:
    """K_i of each round against its angle, with K (draft 7.1)."""
    ax = fig.add_subplot(spec)
    f = _series(res, "scale_factor")
    if not f["measured"]:
        return empty_panel(ax, L)
    if "band" in f:                                 # a large file: range and mean per angle
        _band(ax, f["band"], L["lg_all_rounds"].format(n=f["n_rounds"]), label_mean="K_i")
    else:
        ax.plot(f["x"], f["y"], "o", color="C0", ms=5, label="K_i")
    ax.axhline(res["items"]["scale_factor"]["value"], color="C3", ls="--", lw=1,
               label=f"{L['lg_mean_K']} {_shown(res, 'scale_factor')}")
    ax.set_xlabel(L["ax_round_angle"])
    ax.set_ylabel(L["ax_K"])
    plain_axes(ax)
    legend_above(ax, ncol=2)


def draw_zero_stability(fig, spec, res, L, truth=None) -> None:
    """Zero-stability readings M_n against time and their linear drift (draft 7.3)."""
    ax = fig.add_subplot(spec)
    f = _series(res, "zero_stability")
    if not f["measured"]:
        return empty_panel(ax, L)
    if "band" in f:                                 # a large file: range over the series
        _band(ax, f["band"], L["lg_all_series"].format(n=f["n_series"]))
    for i, g in enumerate(f.get("series") or ()):
        ax.plot(g["t_min"], g["m_arcsec"], "o", color=f"C{i}", ms=4,
                label=f"{L['lg_series']} {g['series']}")
        d = g["drift"]
        if d is not None:
            ax.plot(g["t_min"], d["line_arcsec"], "-", color=f"C{i}", lw=1,
                    label=L["lg_drift"].format(v=display_number(d["drift_deg_per_h"], 3)))
    ax.set_xlabel(L["ax_time_min"])
    ax.set_ylabel(L["ax_angle_arcsec"])
    plain_axes(ax)
    legend_above(ax, ncol=2)


def _consistency(ax, f: dict, L, fmt) -> None:
    if not f["measured"]:
        return empty_panel(ax, L)
    for i, g in enumerate(f["groups"]):
        ref = g["reference"]
        lab = fmt(g["value"]) + (" " + L["lg_reference"] if ref else "")
        ax.plot(g["x"], g["y"], "-o", lw=1.6 if ref else 0.9, ms=2.5, color=f"C{i % 10}",
                label=lab)
    ax.axhline(0, color="0.3", lw=0.6)
    ax.set_xlabel(L["ax_position"])
    ax.set_ylabel(L["ax_deviation"])
    plain_axes(ax)
    legend_above(ax, ncol=4)


def draw_rate(fig, spec, res, L, truth=None) -> None:
    """E_i per position at each table rate (draft 7.6)."""
    _consistency(fig.add_subplot(spec), _series(res, "rate"), L,
                 lambda v: f"{display('pos', float(v))} °/s")


def draw_pointing(fig, spec, res, L, truth=None) -> None:
    """E_i per position for each axis direction (draft 7.7)."""
    _consistency(fig.add_subplot(spec), _series(res, "pointing"), L,
                 lambda v: L.get(str(v), str(v)))


def draw_budget(fig, spec, res, L, truth=None) -> None:
    """Contributions |c_i|·u_i of the Annex A budget as bars, with u_c and U (Annex A.5–A.7)."""
    ax = fig.add_subplot(spec)
    d = _series(res, "budget")
    comps = d["components"]
    names = [f"u({c['symbol'].replace('phi_e', 'φ_e')})" for c in comps]
    vals = [abs(c["contribution_arcsec"]) for c in comps]
    colors = ["C0" if c["type"] == "B" else "C1" for c in comps]
    bd = d.get("bound")
    if bd:      # U = k·u + b: u_c (the table at MPE/√3) beside, not stated; u, k·u, b, U
        names += [L["fig_u_c_beside"], L["fig_u_other"], "k·u", L["fig_b"], "U = k·u + b"]
        vals += [d["u_c_arcsec"], bd["u_arcsec"], bd["ku_arcsec"], bd["b_arcsec"],
                 bd["U_arcsec"]]
        colors += ["0.7", "C2", "C2", "C4", "C3"]
    else:
        names += ["u_c", "U"]
        vals += [d["u_c_arcsec"], d["U_arcsec"]]
        colors += ["C2", "C3"]
    y = np.arange(len(vals))[::-1]
    ax.barh(y, vals, color=colors, height=0.6)
    for yi, v, n in zip(y, vals, names):
        ax.text(v, yi, " " + display_uncertainty(v) + "″", va="center", fontsize=7.5)
    ax.ticklabel_format(axis="x", useOffset=False, style="plain")
    ax.set_yticks(y)
    ax.set_yticklabels(names)
    ax.set_xlim(0, max(vals) * 1.25 if max(vals) > 0 else 1)
    ax.set_xlabel(L["ax_contribution"])
    ax.grid(axis="y", visible=False)


#: The figures of the certificate in order: (key, caption label key, draw function).
FIGURES: tuple[tuple[str, str, Callable], ...] = (
    ("deviation", "fig_deviation", draw_deviation),
    ("repeatability", "fig_repeat", draw_repeatability),
    ("tilt", "fig_tilt", draw_tilt),
    ("scale_factor", "fig_sf", draw_scale_factor),
    ("zero_stability", "fig_zero", draw_zero_stability),
    ("rate", "fig_rate", draw_rate),
    ("pointing", "fig_pointing", draw_pointing),
    ("budget", "fig_budget", draw_budget),
)

