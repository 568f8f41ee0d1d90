"""The certificate's figures, drawn on matplotlib Figure objects from a calibration report.

Contents
========
=====================  =================================================================
:data:`FIGURES`        (key, caption label, draw function), in the certificate's order
:func:`draw_deviation`    E_ij of every series against position, mean E_i (draft Fig. A.4)
:func:`draw_repeatability`  Bessel s_i per position and R = max (draft Fig. A.5, 7.5)
:func:`draw_tilt`      elliptic-projection error at the tilt bound (Annex A.4.2, Fig. A.3),
                       rigid-body model beside it (:mod:`gonio.physics.tilt`)
:func:`draw_scale_factor`   K_i per round and K (7.1)
:func:`draw_zero_stability` readings M_n against time and the drift results.json states (7.3)
:func:`draw_rate`      E_i per position for each rate (7.6)
:func:`draw_pointing`  E_i per position for each axis direction (7.7)
:func:`draw_budget`    |c_i|·u_i of the Annex A components, u_c and U
:func:`figure_svg`     one figure as deterministic SVG text
:func:`mpl_style`      the rc settings (font, SVG salt, no dates) used for every figure
=====================  =================================================================

Each ``draw_*`` takes ``(fig, spec, report, L, truth)``: a matplotlib Figure, a
SubplotSpec to draw in, the calibration report the specification's ``calibrate`` returned, the
label mapping of :func:`gonio.report.i18n.labels`, and the virtual-bench truth
(or None). The same function draws into the HTML's SVG and into a PDF page.
An item that was not measured gives an empty panel saying so.

Rules every figure keeps (issue 13): no pyplot and no backend switch (a
``matplotlib.figure.Figure`` is drawn and saved directly, so importing this module
changes nothing global); no offset or scientific axis labels; legends outside the
axes, above them, so they never hide data; every number in a legend rounded by the
certificate's rule (:mod:`gonio.report.stated`); nothing computed here that
``results.json`` does not hold (the 7.3 drift is the calibration's).
"""

from __future__ import annotations

import contextlib
import io
import math
from typing import Callable, Iterator

import matplotlib
import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from gonio.physics.tilt import elliptic_error_arcsec, rigid_error_arcsec
from gonio.report.i18n import display, display_number, display_uncertainty
from gonio.units import S_PER_MIN, deg_to_arcsec, s_to_h

#: Salt of matplotlib's SVG ids: fixed, so the same report gives the same bytes.
SVG_HASHSALT: str = "gonio-certificate"
#: Figure size in the HTML (inches).
HTML_FIGSIZE: tuple[float, float] = (7.0, 3.4)


@contextlib.contextmanager
def mpl_style(fonts: tuple[str, ...] = ("DejaVu Sans",)) -> Iterator[None]:
    """rc settings of every certificate figure: deterministic SVG, the font families in
    order (matplotlib falls back along the list glyph by glyph, e.g. a CJK font)."""
    only_ttf = tuple(fonts) == ("DejaVu Sans",)
    rc = {"svg.hashsalt": SVG_HASHSALT, "svg.fonttype": "path", "font.family": list(fonts),
          "font.size": 8.5, "axes.titlesize": 9,
          "axes.unicode_minus": False, "pdf.fonttype": 42 if only_ttf else 3,
          "axes.grid": True, "grid.alpha": 0.3, "legend.fontsize": 7,
          "path.simplify": False,
          "text.parse_math": False, "text.usetex": False}   # user text literally (no TeX)
    with matplotlib.rc_context(rc):
        yield


def _legend(ax, ncol: int = 3) -> None:
    """The legend above the axes, outside the data area (it never hides a curve)."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.01, 1.0, 0.2), mode="expand",
                  ncol=ncol, borderaxespad=0.0, frameon=False)


def _plain_axes(ax) -> None:
    """No offset ("+7.64348e4") and no scientific notation on either axis."""
    for axis in ("x", "y"):
        try:
            ax.ticklabel_format(axis=axis, useOffset=False, style="plain")
        except AttributeError:       # a categorical or log axis has no such formatter
            pass


def _empty(ax, L) -> None:
    ax.text(0.5, 0.5, L["no_data"], ha="center", va="center", transform=ax.transAxes,
            fontsize=11, color="0.4")
    ax.set_xticks([])
    ax.set_yticks([])


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


#: Series drawn one by one in a figure; more are drawn as their range and mean.
FIGURE_SERIES: int = 20
#: Points drawn one by one (7.1 rounds); more are drawn as their range and mean per angle.
FIGURE_POINTS: int = 400


def _range_band(ax, df, x: str, y: str, label: str, label_mean: str | None = None) -> None:
    """The range (min … max) and the mean of ``y`` at each ``x`` (rounded to 1e-9), for a
    large file whose every series or round would not be readable (nor small) one by one."""
    g = df.assign(_x=np.round(df[x].to_numpy(float), 9)).groupby("_x", sort=True)[y]
    st = g.agg(["min", "max", "mean"])
    xs = st.index.to_numpy(float)
    ax.vlines(xs, st["min"], st["max"], color="C0", lw=3, alpha=0.35, label=label)
    ax.plot(xs, st["mean"], "o", color="C0", ms=3, label=label_mean)


def draw_deviation(fig, spec, report, L, truth=None) -> None:
    """Deviation curves E_ij of every series against position (draft 7.4, Fig. A.4)."""
    ax = fig.add_subplot(spec)
    c = report.results.angle_deviation
    if not c.measured:
        return _empty(ax, L)
    rd = c.tables["readings"]
    if rd["series"].nunique() > FIGURE_SERIES:      # a large file: the range of all series
        _range_band(ax, rd, "table_deg", "E_arcsec",
                    L["lg_all_series"].format(n=rd["series"].nunique()))
    else:
        for s, g in rd.groupby("series", sort=True):
            g = g.sort_values("table_deg")
            ax.plot(g["table_deg"], g["E_arcsec"], "-o", lw=0.8, ms=2.5, alpha=0.6,
                    label=f"{L['lg_series']} {s}" if rd["series"].nunique() <= 10 else None)
    t = c.table.sort_values("position_deg")
    ax.plot(t["position_deg"], t["E_arcsec"], "k-", lw=2.0, label=L["lg_mean"])
    tr = _truth_by_position(truth, "angle_deviation")
    if tr is not None:
        ax.plot(tr[0], tr[1], "r--", lw=1.2, label=L["truth"])
    ax.axhline(0, color="0.3", lw=0.6)
    ax.set_xlabel(L["ax_position"])
    ax.set_ylabel(L["ax_deviation"])
    _plain_axes(ax)
    _legend(ax, ncol=6)


def draw_repeatability(fig, spec, report, L, truth=None) -> None:
    """Bessel standard deviation per position and R = max (draft 7.5, Fig. A.5)."""
    ax = fig.add_subplot(spec)
    c = report.results.repeatability
    if not c.measured:
        return _empty(ax, L)
    from gonio.report.stated import stated_item

    t = c.table.sort_values("position_deg")
    ax.plot(t["position_deg"], t["R_arcsec"], "o-", color="C0", lw=1.2, ms=4,
            label=L["ax_std"])
    shown = str(stated_item(report.to_dict(), "repeatability")["value"])
    ax.axhline(c.value, color="C3", ls="--", lw=1, label=f"{L['lg_R']} {shown}″")
    ax.set_ylim(bottom=0)
    ax.set_xlabel(L["ax_position"])
    ax.set_ylabel(L["ax_std"])
    _plain_axes(ax)
    _legend(ax, ncol=2)


def draw_tilt(fig, spec, report, L, truth=None) -> None:
    """Tilt error at the budget's tilt bound: elliptic model (Annex A.4.2) and rigid model."""
    psi = float(report.uncertainty.parameters["tilt_deg"])
    sub = spec.subgridspec(1, 2, wspace=0.35)
    theta = np.linspace(0.0, 360.0, 721)
    ax = fig.add_subplot(sub[0])
    ax.plot(theta, elliptic_error_arcsec(theta, psi), "C0-", lw=1.5,
            label=L["lg_elliptic"].format(psi=display_number(psi, 3)))
    ax.plot(theta, rigid_error_arcsec(theta, psi), "C2--", lw=1.2, label=L["lg_rigid"])
    ax.set_xlabel(L["ax_position"])
    ax.set_ylabel(L["ax_tilt"])
    ax.set_xticks(np.arange(0, 361, 90))
    _legend(ax, ncol=1)
    ax2 = fig.add_subplot(sub[1])
    ax2.plot(theta, rigid_error_arcsec(theta, psi, calibrated=False), "C1-", lw=1.5,
             label=L["lg_rigid_uncal"])
    ax2.set_xlabel(L["ax_position"])
    ax2.set_ylabel(L["ax_tilt"])
    ax2.set_xticks(np.arange(0, 361, 90))
    _legend(ax2, ncol=1)


def draw_scale_factor(fig, spec, report, L, truth=None) -> None:
    """K_i of each round against its angle, with K (draft 7.1)."""
    ax = fig.add_subplot(spec)
    c = report.results.scale_factor
    if not c.measured:
        return _empty(ax, L)
    from gonio.report.stated import stated_item

    t = c.table
    if len(t) > FIGURE_POINTS:                      # a large file: range and mean per angle
        _range_band(ax, t, "table_deg", "K_i_counts_per_deg",
                    L["lg_all_rounds"].format(n=len(t)), label_mean="K_i")
    else:
        ax.plot(t["table_deg"], t["K_i_counts_per_deg"], "o", color="C0", ms=5, label="K_i")
    shown = str(stated_item(report.to_dict(), "scale_factor")["value"])
    ax.axhline(c.value, color="C3", ls="--", lw=1, label=f"{L['lg_mean_K']} {shown}")
    ax.set_xlabel(L["ax_round_angle"])
    ax.set_ylabel(L["ax_K"])
    _plain_axes(ax)
    _legend(ax, ncol=2)


def draw_zero_stability(fig, spec, report, L, truth=None) -> None:
    """Zero-stability readings M_n against time and their linear drift (draft 7.3)."""
    ax = fig.add_subplot(spec)
    c = report.results.zero_stability
    if not c.measured or "readings" not in c.tables:
        return _empty(ax, L)
    rd = c.tables["readings"]
    if rd["series"].nunique() > FIGURE_SERIES:      # a large file: range over the series
        t0 = rd.groupby("series")["time_s"].transform("min")
        band = pd.DataFrame({"t_min": (rd["time_s"] - t0).to_numpy(float) / S_PER_MIN,
                             "m_arcsec": deg_to_arcsec(rd["angle_deg"].to_numpy(float))})
        _range_band(ax, band, "t_min", "m_arcsec",
                    L["lg_all_series"].format(n=rd["series"].nunique()))
        ax.set_xlabel(L["ax_time_min"])
        ax.set_ylabel(L["ax_angle_arcsec"])
        _plain_axes(ax)
        _legend(ax, ncol=2)
        return
    drift = {int(r["series"]): r for _, r in c.table.iterrows()} \
        if "drift_deg_per_h" in c.table else {}
    for i, (s, g) in enumerate(rd.groupby("series", sort=True)):
        g = g.sort_values("time_s")
        t_s = (g["time_s"] - g["time_s"].iloc[0]).to_numpy(dtype=float)
        m_arcsec = deg_to_arcsec(g["angle_deg"].to_numpy())
        ax.plot(t_s / S_PER_MIN, m_arcsec, "o", color=f"C{i}", ms=4,
                label=f"{L['lg_series']} {s}")
        d = drift.get(int(s))
        if d is not None and math.isfinite(d["drift_deg_per_h"]):
            line_deg = d["drift_intercept_deg"] + d["drift_deg_per_h"] * s_to_h(t_s)
            ax.plot(t_s / S_PER_MIN, deg_to_arcsec(line_deg), "-", color=f"C{i}", lw=1,
                    label=L["lg_drift"].format(v=display_number(d["drift_deg_per_h"], 3)))
    ax.set_xlabel(L["ax_time_min"])
    ax.set_ylabel(L["ax_angle_arcsec"])
    _plain_axes(ax)
    _legend(ax, ncol=2)


def _consistency(ax, c, col, L, fmt) -> None:
    if not c.measured or "points" not in c.tables:
        return _empty(ax, L)
    pts = c.tables["points"]
    ref = set(c.table.loc[c.table["reference"].astype(bool), col]) if "reference" in c.table else set()
    groups = sorted(pts.groupby(col, sort=True), key=lambda vg: vg[0] not in ref)
    for i, (v, g) in enumerate(groups):
        g = g.sort_values("position_deg")
        lab = fmt(v) + (" " + L["lg_reference"] if v in ref else "")
        ax.plot(g["position_deg"], g["E_arcsec"], "-o", lw=1.6 if v in ref else 0.9,
                ms=2.5, color=f"C{i % 10}", label=lab)
    ax.axhline(0, color="0.3", lw=0.6)
    ax.set_xlabel(L["ax_position"])
    ax.set_ylabel(L["ax_deviation"])
    _plain_axes(ax)
    _legend(ax, ncol=4)


def draw_rate(fig, spec, report, L, truth=None) -> None:
    """E_i per position at each table rate (draft 7.6)."""
    _consistency(fig.add_subplot(spec), report.results.rate_consistency, "rate_dps", L,
                 lambda v: f"{display('pos', float(v))} °/s")


def draw_pointing(fig, spec, report, L, truth=None) -> None:
    """E_i per position for each axis direction (draft 7.7)."""
    _consistency(fig.add_subplot(spec), report.results.pointing_consistency, "orientation", L,
                 lambda v: L.get(str(v), str(v)))


def draw_budget(fig, spec, report, L, truth=None) -> None:
    """Contributions |c_i|·u_i of the Annex A budget as bars, with u_c and U (Annex A.5–A.7)."""
    ax = fig.add_subplot(spec)
    d = report.uncertainty.to_dict()
    comps = d["components"]
    names = [f"u({c['symbol'].replace('phi_e', 'φ_e')})" for c in comps] + ["u_c", "U"]
    vals = [abs(c["contribution_arcsec"]) for c in comps] + [d["u_c_arcsec"], d["U_arcsec"]]
    colors = ["C0" if c["type"] == "B" else "C1" for c in comps] + ["C2", "C3"]
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


def plain_log_ticks(fig) -> None:
    """Label every log-scaled axis of ``fig`` in plain numbers ("0.1", "100", "1e-05"):
    matplotlib's log labels are mathtext, which :func:`mpl_style` turns off (user text is
    shown literally), so they would print as ``$\\mathdefault{10^{2}}$``."""
    from matplotlib.ticker import FuncFormatter, LogFormatter

    for ax in fig.axes:
        for axis, scale in ((ax.xaxis, ax.get_xscale()), (ax.yaxis, ax.get_yscale())):
            if scale == "log":
                axis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))
                # minor ticks labelled (plain text) only on an axis of about a decade or less
                axis.set_minor_formatter(LogFormatter(labelOnlyBase=False,
                                                      minor_thresholds=(1, 0.4)))


def figure_svg(draw: Callable, report, L: dict, truth=None,
               fonts: tuple[str, ...] = ("DejaVu Sans",),
               figsize: tuple[float, float] = HTML_FIGSIZE) -> str:
    """One figure as SVG text, byte-stable for the same inputs (no date, fixed id salt).

    The XML prolog and DOCTYPE are dropped so the text can be inlined in HTML.
    """
    with mpl_style(fonts):
        fig = Figure(figsize=figsize)
        spec = fig.add_gridspec(1, 1)[0]
        draw(fig, spec, report, L, truth)
        plain_log_ticks(fig)
        fig.tight_layout()
        buf = io.StringIO()
        fig.savefig(buf, format="svg", metadata={"Date": None}, bbox_inches="tight",
                    pad_inches=0.05)
    svg = buf.getvalue()
    return svg[svg.index("<svg"):]
