"""An instrument's calibration history as a figure: one panel per item, value ± U at each
calibration date, the specification limits as horizontal lines (gonio serve's instrument
page; the data come from :func:`gonio.records.services.history`).

>>> import datetime as dt
>>> svg = history_svg({"K": [{"date": dt.date(2025, 1, 1), "value": 1.0, "U": 0.1,
...     "unit": "counts/deg", "title": "scale factor K", "status": "issued"}]}, {"K": (0.5, 1.5)})
>>> svg.startswith("<svg")
True
"""

from __future__ import annotations

import io

from matplotlib.dates import AutoDateLocator, ConciseDateFormatter
from matplotlib.figure import Figure

from gonio.report.figures import mpl_style


def history_figure(history: dict, limits: dict | None = None, *, columns: int = 2) -> Figure:
    """The figure: ``history`` maps item key → rows {date, value, U, unit, title, status}
    (oldest first); ``limits`` maps key → (lower, upper) (either None)."""
    limits = limits or {}
    keys = [k for k, rows in history.items() if any(r["value"] is not None for r in rows)]
    n = max(1, len(keys))
    cols = min(columns, n)
    rows_n = -(-n // cols)
    fig = Figure(figsize=(5.2 * cols, 2.3 * rows_n))
    if not keys:
        ax = fig.add_subplot(1, 1, 1)
        ax.text(0.5, 0.5, "no calibration results yet", ha="center", va="center",
                transform=ax.transAxes)
        ax.set_axis_off()
        return fig
    for i, key in enumerate(keys):
        ax = fig.add_subplot(rows_n, cols, i + 1)
        pts = [r for r in history[key] if r["value"] is not None]
        issued = [r for r in pts if r.get("status") == "issued"]
        other = [r for r in pts if r.get("status") != "issued"]
        for sel, style, label in ((issued, dict(fmt="o", color="C0"), "issued"),
                                  (other, dict(fmt="o", mfc="white", color="C1"),
                                   "not issued")):
            if sel:
                ax.errorbar([r["date"] for r in sel], [r["value"] for r in sel],
                            yerr=[r["U"] or 0.0 for r in sel], capsize=3, ms=4, label=label,
                            **style)
        lo, hi = limits.get(key, (None, None))
        for lim in (lo, hi):
            if lim is not None:
                ax.axhline(lim, color="C3", ls="--", lw=1)
        if lo is not None or hi is not None:
            ax.plot([], [], color="C3", ls="--", lw=1, label="specification limit")
        unit = pts[0].get("unit") or ""
        ax.set_title(f"{pts[0].get('title') or key} [{unit}]")
        loc = AutoDateLocator(minticks=2, maxticks=5)
        ax.xaxis.set_major_locator(loc)
        ax.xaxis.set_major_formatter(ConciseDateFormatter(loc))
        ax.margins(x=0.15)
        ax.legend(loc="upper left", fontsize=7)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.3 / rows_n, top=1 - 0.32 / rows_n,
                        wspace=0.25, hspace=0.55)
    return fig


def history_svg(history: dict, limits: dict | None = None) -> str:
    """:func:`history_figure` as SVG text (no XML prolog: it can be served or inlined)."""
    import matplotlib

    # text as SVG text (the browser's fonts): a tenth of the time of glyph paths
    with mpl_style(), matplotlib.rc_context({"svg.fonttype": "none"}):
        fig = history_figure(history, limits)
        buf = io.StringIO()
        fig.savefig(buf, format="svg")
    text = buf.getvalue()
    return text[text.index("<svg"):]
