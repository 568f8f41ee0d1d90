"""An instrument's calibration history as an SVG figure: one panel per item, value ± U at
each calibration date (an item stated by one coverage interval: that interval), the
specification limits as dashed horizontal lines (gonio serve's
instrument page; the data come from :func:`gonio.records.services.history`).

Written directly as SVG text (no Matplotlib): a hundred calibrations of seven items take a
few milliseconds instead of half a second of Matplotlib's layout, and the web server never
imports a plotting library. The text is the browser's own font.

>>> import datetime as dt
>>> svg = history_svg({"K": [{"date": dt.date(2025, 1, 1), "value": 1.0, "U": 0.1,
...     "unit": "counts/deg", "title": "scale factor K", "status": "issued"}]}, {"K": (0.5, 1.5)})
>>> svg.startswith("<svg") and "scale factor K [counts/deg]" in svg
True
"""

from __future__ import annotations

import datetime as dt
import math
from html import escape

#: panel size and the plot area's margins within it (px)
PANEL_W, PANEL_H = 520, 230
LEFT, RIGHT, TOP, BOTTOM = 64, 12, 26, 30
#: the colours of issued points, other points and limits (Matplotlib's C0, C1, C3)
ISSUED, OTHER, LIMIT = "#1f77b4", "#ff7f0e", "#d62728"
#: the ring around an amended point (issued, then replaced or being amended)
AMENDED_RING = "#000"
_CAP = 3.0                                   # half the width of an error bar's cap (px)


def nice_ticks(lo: float, hi: float, target: int = 5) -> list[float]:
    """Tick values within [lo, hi] at a step of 1, 2, 2.5 or 5 × 10ᵏ, at most ``target``
    of them.

    >>> nice_ticks(0.93, 1.07)
    [0.95, 1.0, 1.05]
    >>> nice_ticks(0.0, 10.0)
    [0.0, 2.5, 5.0, 7.5, 10.0]
    """
    raw = (hi - lo) / max(1, target - 1)
    power = 10.0 ** math.floor(math.log10(raw))
    step = next(f * power for f in (1.0, 2.0, 2.5, 5.0, 10.0) if f * power >= raw * 0.999)
    first = math.ceil(lo / step - 1e-9)
    last = math.floor(hi / step + 1e-9)
    return [round(i * step, 12) for i in range(first, last + 1)]


def _tick_label(v: float, step: float) -> str:
    """A tick value with the decimals its step needs (one more for a step of 2.5·10ᵏ)."""
    exp = math.floor(math.log10(step) + 1e-9)
    digits = max(0, -exp + (1 if round(step / 10.0 ** exp, 6) == 2.5 else 0))
    return f"{v:.{digits}f}" if digits <= 9 and abs(v) < 1e9 else f"{v:.6g}"


def date_ticks(lo: dt.date, hi: dt.date) -> tuple[list[dt.date], str]:
    """(tick dates within [lo, hi], label format): first days of years, of months or days,
    at most six ticks.

    >>> date_ticks(dt.date(2019, 11, 5), dt.date(2024, 2, 1))[0][0]
    datetime.date(2020, 1, 1)
    """
    days = (hi - lo).days
    if days > 3 * 365:
        step = next((s for s in (1, 2, 5, 10, 20, 50) if days / 365.25 / s <= 5), 100)
        ticks = [dt.date(y, 1, 1) for y in range(lo.year, hi.year + 1) if y % step == 0]
        return [t for t in ticks if lo <= t <= hi], "%Y"
    if days > 90:
        step = next(s for s in (1, 2, 3, 6, 12) if days / 30.44 / s <= 5)
        ticks = []
        y, m = lo.year, lo.month
        while dt.date(y, m, 1) <= hi:
            if (m - 1) % step == 0:
                ticks.append(dt.date(y, m, 1))
            y, m = (y + 1, 1) if m == 12 else (y, m + 1)
        return [t for t in ticks if lo <= t <= hi], "%Y-%m"
    step = next(s for s in (1, 2, 7, 14, 30) if max(days, 1) / s <= 5)
    return [lo + dt.timedelta(days=i) for i in range(0, days + 1, step)], "%Y-%m-%d"


def bar_ends(r: dict) -> tuple[float, float]:
    """(low, high) of a point's error bar: the coverage interval of an item its certificate
    states by one interval (the row's ``interval``, as the statement rule gives it), else
    value ± U."""
    iv = r.get("interval")
    if iv is not None:
        return float(iv[0]), float(iv[1])
    u = r["U"] or 0.0
    return r["value"] - u, r["value"] + u


def drawn_value(r: dict) -> float:
    """Where a point is drawn: its value; for a row stated by the interval of an extreme of
    magnitudes (``max_abs``, from its result's ``k_source``: E, 7.4, the interval of
    max_i |E_i| beside the signed extreme) the value's magnitude, which its bar belongs to.
    Any other value is drawn as it is, a non-negative item's bias-corrected estimate below
    zero too (C_g −1.58×10⁻⁵ below its bar [0, 3.9×10⁻⁵]), never mirrored into its bar."""
    v = float(r["value"])
    return abs(v) if r.get("max_abs") and r.get("interval") is not None else v


def _ranges(pts: list[dict], lo_hi) -> tuple[float, float, dt.date, dt.date]:
    """(y low, y high, first date, last date) of a panel, with margins (x: 15 %)."""
    ys = [v for r in pts for v in bar_ends(r)] + [drawn_value(r) for r in pts]
    ys += [v for v in lo_hi if v is not None]
    y0, y1 = min(ys), max(ys)
    pad = (y1 - y0) * 0.05 or max(abs(y0) * 0.01, 1e-12)
    d0, d1 = min(r["date"] for r in pts), max(r["date"] for r in pts)
    span = max((d1 - d0).days, 60)
    widen = dt.timedelta(days=math.ceil(span * 0.15))
    return y0 - pad, y1 + pad, d0 - widen, d1 + widen


def _panel(key: str, pts: list[dict], lo_hi, ox: float, oy: float) -> list[str]:
    """The SVG elements of one item's panel with its top-left corner at (ox, oy)."""
    y0, y1, d0, d1 = _ranges(pts, lo_hi)
    yt = nice_ticks(y0, y1)
    w, h = PANEL_W - LEFT - RIGHT, PANEL_H - TOP - BOTTOM
    x_of = lambda d: ox + LEFT + w * (d - d0).days / (d1 - d0).days   # noqa: E731
    y_of = lambda v: oy + TOP + h * (y1 - v) / (y1 - y0)                # noqa: E731
    unit = pts[0].get("unit") or ""
    out = [f'<g class="panel" data-key="{escape(key)}">',
           f'<text class="title" x="{ox + LEFT}" y="{oy + 17:.1f}" font-weight="bold">'
           f'{escape(str(pts[0].get("title") or key))} [{escape(unit)}]</text>',
           f'<rect x="{ox + LEFT}" y="{oy + TOP}" width="{w}" height="{h}" fill="none" '
           'stroke="#333"/>']
    step = yt[1] - yt[0] if len(yt) > 1 else 1.0
    for v in yt:
        y = y_of(v)
        out.append(f'<line x1="{ox + LEFT - 4}" y1="{y:.2f}" x2="{ox + LEFT}" y2="{y:.2f}" '
                   'stroke="#333"/>')
        out.append(f'<text class="ytick" x="{ox + LEFT - 6}" y="{y + 3.5:.2f}" '
                   f'text-anchor="end" data-v="{v!r}">{_tick_label(v, step)}</text>')
    ticks, form = date_ticks(d0, d1)
    for t in ticks:
        x = x_of(t)
        out.append(f'<line x1="{x:.2f}" y1="{oy + TOP + h}" x2="{x:.2f}" '
                   f'y2="{oy + TOP + h + 4}" stroke="#333"/>')
        out.append(f'<text class="xtick" x="{x:.2f}" y="{oy + TOP + h + 16}" '
                   f'text-anchor="middle" data-v="{t.isoformat()}">{t.strftime(form)}</text>')
    for lim in lo_hi:
        if lim is not None:
            y = y_of(lim)
            out.append(f'<line class="limit" x1="{ox + LEFT}" y1="{y:.2f}" '
                       f'x2="{ox + LEFT + w}" y2="{y:.2f}" stroke="{LIMIT}" '
                       'stroke-dasharray="5 3"/>')
    for r in pts:
        drawn = drawn_as(r)
        x, y = x_of(r["date"]), y_of(drawn_value(r))
        low, high = bar_ends(r)
        top, bot = y_of(high), y_of(low)
        colour = OTHER if drawn == "other" else ISSUED
        out.append(f'<path class="bar" d="M{x:.2f} {top:.2f}V{bot:.2f}M{x - _CAP:.2f} '
                   f'{top:.2f}h{2 * _CAP}M{x - _CAP:.2f} {bot:.2f}h{2 * _CAP}" '
                   f'stroke="{colour}"/>')
        out.append(f'<circle class="{drawn}" cx="{x:.2f}" cy="{y:.2f}" r="3" '
                   f'{_MARKER[drawn]}/>')
    title = f'{pts[0].get("title") or key} [{unit}]'
    out += _legend(pts, lo_hi, ox + PANEL_W - RIGHT, oy + 17,
                   left=ox + LEFT + _BOLD_CHAR_PX * len(title) + 8)
    out.append("</g>")
    return out


#: a point's marker (fill and stroke) by how it is drawn (:func:`drawn_as`)
_MARKER = {"issued": f'fill="{ISSUED}" stroke="{ISSUED}"',
           "amended": f'fill="{ISSUED}" stroke="{AMENDED_RING}" stroke-width="1.5"',
           "other": f'fill="#fff" stroke="{OTHER}"'}


def drawn_as(row: dict) -> str:
    """How a history row is drawn: 'issued' (it has a certificate), 'amended' (it has one,
    and one was replaced by an amendment or an amendment is under way) or 'other' (never
    issued). Rows without the ``issued`` key count as issued in the state 'issued' only.

    >>> drawn_as({"status": "amending", "issued": True, "amended": True})
    'amended'
    >>> drawn_as({"status": "computed"})
    'other'
    """
    if not row.get("issued", row.get("status") == "issued"):
        return "other"
    return "amended" if row.get("amended") else "issued"


#: about how wide a character of the 10 px text is, plain and bold (px)
_CHAR_PX, _BOLD_CHAR_PX = 6.0, 6.6


def _legend(pts: list[dict], lo_hi, right: float, y: float, left: float = 0.0) -> list[str]:
    """The panel's legend in its header, right-aligned at ``right`` (never over the data):
    only what the panel shows; where it would reach left of ``left`` (the title's end),
    the limit's label is shortened."""
    entries = []
    drawn = {drawn_as(r) for r in pts}
    for kind, label in (("issued", "issued"), ("amended", "amended"),
                        ("other", "not issued")):
        if kind in drawn:
            entries.append((label, _MARKER[kind]))
    if any(v is not None for v in lo_hi):
        entries.append(("specification limit", None))
        if right - sum(_CHAR_PX * len(e[0]) + 28 for e in entries) < left:
            entries[-1] = ("limit", None)
    out, x = [], right
    for label, style in reversed(entries):
        x -= _CHAR_PX * len(label) + 28
        if style:
            out.append(f'<circle cx="{x + 6}" cy="{y - 3.5}" r="3" {style}/>')
        else:
            out.append(f'<line x1="{x}" y1="{y - 3.5}" x2="{x + 14}" y2="{y - 3.5}" '
                       f'stroke="{LIMIT}" stroke-dasharray="5 3"/>')
        out.append(f'<text class="legend" x="{x + 17}" y="{y}">{label}</text>')
    return out


def history_svg(history: dict, limits: dict | None = None, *, columns: int = 2) -> str:
    """The figure as SVG text (no XML prolog: it can be served or inlined): ``history`` maps
    item key → rows {date, value, U, unit, title, status, issued, amended} (oldest first;
    :func:`drawn_as`); ``limits`` maps
    key → (lower, upper) (either None)."""
    limits = limits or {}
    keys = [k for k, rows in history.items() if any(r["value"] is not None for r in rows)]
    cols = min(columns, max(1, len(keys)))
    rows_n = max(1, -(-len(keys) // cols))
    width, height = PANEL_W * cols, PANEL_H * rows_n
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="10">',
           f'<rect width="{width}" height="{height}" fill="#fff"/>']
    if not keys:
        out.append(f'<text x="{width / 2}" y="{height / 2}" text-anchor="middle">'
                   'no calibration results yet</text>')
    for i, key in enumerate(keys):
        pts = [r for r in history[key] if r["value"] is not None]
        out += _panel(key, pts, limits.get(key, (None, None)),
                      PANEL_W * (i % cols), PANEL_H * (i // cols))
    out.append("</svg>")
    return "\n".join(out)
