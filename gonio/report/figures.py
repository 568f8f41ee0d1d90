"""What every certificate figure shares: the rc style, the panel helpers and the SVG writer.

Contents
========
=======================  =================================================================
:func:`mpl_style`        the rc settings (font, SVG salt, no dates) used for every figure
:func:`legend_above`     a legend above the axes, outside the data area
:func:`plain_axes`       no offset and no scientific notation on either axis
:func:`empty_panel`      the panel of an item that was not measured ("not measured")
:func:`plain_log_ticks`  log axes labelled in plain numbers
:func:`first_family`     texts made inside: the first font family alone (no per-text fallback)
:func:`font_fallback`    the whole family list back to each text the first family does not cover
:func:`figure_svg`       one figure as deterministic SVG text
=======================  =================================================================

A specification's figures (its rendering module ``figures``) draw with these; each ``draw`` takes ``(fig, spec,
res, L, truth)``: a matplotlib Figure, a SubplotSpec to draw in, the stored result, the label
mapping of :func:`gonio.report.i18n.labels` and the virtual-bench truth (or None), so the same
function draws into the HTML's SVG and into a PDF page.

Rules every figure keeps: no pyplot and no backend switch (a
``matplotlib.figure.Figure`` is drawn and saved directly, so importing this module
changes nothing global); no offset or scientific axis labels; legends outside the
axes, above them, so they never hide data; nothing computed that the stored result does
not hold.
"""

from __future__ import annotations

import contextlib
import functools
import io
from typing import Callable, Iterator

import matplotlib
from matplotlib.figure import Figure

#: Salt of matplotlib's SVG ids: fixed, so the same report gives the same bytes.
SVG_HASHSALT: str = "gonio-certificate"
#: Figure size in the HTML (inches).
HTML_FIGSIZE: tuple[float, float] = (7.0, 3.4)
#: Margin around an SVG figure's content (inches).
SVG_PAD_IN: float = 0.05


@contextlib.contextmanager
def mpl_style(fonts: tuple[str, ...] = ("DejaVu Sans",)) -> Iterator[None]:
    """rc settings of every certificate figure: deterministic SVG, the font families in
    order (matplotlib falls back along the list glyph by glyph, e.g. a CJK font); negative
    tick labels with the minus sign U+2212, as the certificate's text
    (:func:`gonio.report.i18n.minus_sign`)."""
    only_ttf = tuple(fonts) == ("DejaVu Sans",)
    rc = {"svg.hashsalt": SVG_HASHSALT, "svg.fonttype": "path", "font.family": list(fonts),
          "font.size": 8.5, "axes.titlesize": 9,
          "axes.unicode_minus": True, "pdf.fonttype": 42 if only_ttf else 3,
          "axes.grid": True, "grid.alpha": 0.3, "legend.fontsize": 7,
          "path.simplify": False,
          "text.parse_math": False, "text.usetex": False}   # user text literally (no TeX)
    with matplotlib.rc_context(rc):
        yield


@contextlib.contextmanager
def first_family(fonts: tuple[str, ...]) -> Iterator[None]:
    """Inside :func:`mpl_style`: texts made here (tick labels too) get the first family
    alone; :func:`font_fallback` gives the whole list back to each text that needs it.

    The glyphs are the same: matplotlib takes a glyph from the first family that has it, so a
    text the first family covers has every glyph from it either way; what goes is the look-up
    of every further family for every text (on the certificate, thousands of look-ups of the
    CJK font for Latin text)."""
    with matplotlib.rc_context({"font.family": [fonts[0]]}):
        yield


@functools.lru_cache(maxsize=16)
def _charmap(path) -> frozenset[int]:
    """The character codes a font file has a glyph for."""
    from matplotlib.font_manager import get_font

    return frozenset(c for c, g in get_font(path).get_charmap().items() if g)


@functools.lru_cache(maxsize=8)
def _ascii_ok(family: str) -> bool:
    """True when every file of ``family`` (each weight and style) has every printable
    ASCII glyph (then an ASCII text needs no fallback whatever its weight)."""
    from matplotlib import font_manager as fm

    files = {f.fname for f in fm.fontManager.ttflist if f.name == family}
    need = set(range(0x20, 0x7F))
    return bool(files) and all(need <= _charmap(f) for f in files)


def font_fallback(fig, fonts: tuple[str, ...]) -> None:
    """Each text of ``fig`` with a character its first-family font file (at the text's
    weight and style) has no glyph for gets the whole family list of ``fonts`` (the fallback
    glyph by glyph); the others keep the first family alone (:func:`first_family`). Call it
    when every text but the tick labels exists; tick labels given as strings
    (``set_ticklabels``: names, possibly Chinese) are checked the same way, per axis; the
    others are numbers, which every font of the list has."""
    if len(fonts) < 2:
        return
    from matplotlib.font_manager import FontProperties
    from matplotlib.text import Text
    from matplotlib.ticker import FixedFormatter

    for t in fig.findobj(Text):
        if _uncovered(t.get_text(), fonts, t.get_fontproperties()):
            t.set_fontfamily(list(fonts))
    tick = FontProperties()                      # a tick label's font (the rc settings)
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            for which, fmt in (("major", axis.get_major_formatter()),
                               ("minor", axis.get_minor_formatter())):
                if isinstance(fmt, FixedFormatter) and any(
                        _uncovered(str(x), fonts, tick) for x in fmt.seq):
                    axis.set_tick_params(which=which, labelfontfamily=list(fonts))


def _uncovered(s: str, fonts: tuple[str, ...], prop) -> bool:
    """True when the font file of ``prop`` (first family) lacks a glyph of ``s``."""
    from matplotlib import font_manager as fm

    if not s or (s.isascii() and _ascii_ok(fonts[0])):
        return False
    have = _charmap(fm.findfont(prop))
    return any(ord(c) not in have for c in s if c != "\n")


def legend_above(ax, ncol: int = 3) -> None:
    """The legend above the axes, outside the data area (it never hides a curve)."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.01, 1.0, 0.2), mode="expand",
                  ncol=ncol, borderaxespad=0.0, frameon=False)


def plain_axes(ax) -> None:
    """No offset ("+7.64348e4") and no scientific notation on either axis."""
    for axis in ("x", "y"):
        try:
            ax.ticklabel_format(axis=axis, useOffset=False, style="plain")
        except AttributeError:       # a categorical or log axis has no such formatter
            pass


def empty_panel(ax, L) -> None:
    """An empty panel saying the item was not measured (``L["no_data"]``)."""
    ax.text(0.5, 0.5, L["no_data"], ha="center", va="center", transform=ax.transAxes,
            fontsize=11, color="0.4")
    ax.set_xticks([])
    ax.set_yticks([])


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


def minus_signs(fig) -> None:
    """Every text a specification drew on ``fig`` (a Figure, or one of its Axes: legend
    entries, labels, notes) with the minus sign of its negative numbers
    (:func:`gonio.report.i18n.minus_sign`), as the certificate's text; tick labels get it
    from ``axes.unicode_minus`` (:func:`mpl_style`)."""
    from matplotlib.text import Text

    from gonio.report.i18n import minus_sign

    for t in fig.findobj(Text):
        s = t.get_text()
        if s and "-" in s:
            t.set_text(minus_sign(s))


def figure_svg(draw: Callable, res: dict, L: dict, truth=None,
               fonts: tuple[str, ...] = ("DejaVu Sans",),
               figsize: tuple[float, float] = HTML_FIGSIZE) -> str:
    """One figure as SVG text, byte-stable for the same inputs (no date, fixed id salt).

    ``figsize`` is the size of a figure laid out with matplotlib's default margin (1.08
    font sizes) and cropped to its content plus :data:`SVG_PAD_IN`; the figure is drawn at
    that cropped size with :data:`SVG_PAD_IN` as its layout margin, so the layout is done
    once (``tight_layout`` on the figure's Agg canvas) and the SVG drawn once (a crop by
    ``bbox_inches="tight"`` would draw the whole figure a second time to measure it).
    The XML prolog and DOCTYPE are dropped so the text can be inlined in HTML.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    with mpl_style(fonts), first_family(fonts):
        size_pt = matplotlib.rcParams["font.size"]
        shrink = 2.0 * (1.08 * size_pt / 72.0 - SVG_PAD_IN)
        fig = Figure(figsize=(figsize[0] - shrink, figsize[1] - shrink))
        # tight_layout measures the text on this figure's own Agg canvas instead of
        # asking a bare canvas for a renderer (a print through the default backend)
        FigureCanvasAgg(fig)
        spec = fig.add_gridspec(1, 1)[0]
        draw(fig, spec, res, L, truth)
        plain_log_ticks(fig)
        minus_signs(fig)
        font_fallback(fig, fonts)
        fig.tight_layout(pad=SVG_PAD_IN * 72.0 / size_pt)
        buf = io.StringIO()
        fig.savefig(buf, format="svg", metadata={"Date": None})
    svg = buf.getvalue()
    return svg[svg.index("<svg"):]
