"""Certificate figures: each text in the first font family alone where that family has
every glyph, the whole family list (glyph-by-glyph fallback) where it does not.

The truth the fast path is checked against is matplotlib's own fallback: the same figure
drawn with the whole family list on every text (what :func:`mpl_style` alone gives) must
give the same bytes, and no glyph may be missing (matplotlib warns of each)."""

from __future__ import annotations

import contextlib
import warnings

import pytest

from gonio.report import figures as F
from gonio.report.render import has_cjk_font

pytestmark = pytest.mark.skipif(not has_cjk_font(), reason="needs a CJK font")


def _draw(fig, spec, res, L, truth):
    ax = fig.add_subplot(spec)
    ax.barh([0, 1, 2], [1.0, -2.0, 0.5], label="K (counts/°) ± U")
    ax.set_yticks([0, 1, 2])
    ax.set_yticklabels(["中文名称", "θ cos ψ", "abc"])     # string tick labels
    ax.set_title("标题 title")
    from matplotlib.ticker import FixedFormatter, FixedLocator
    ax.xaxis.set_major_locator(FixedLocator([-1.0, 1.0]))   # labels made when drawn
    ax.xaxis.set_major_formatter(FixedFormatter(["左", "右"]))
    ax.set_xlabel("deviation (″), −1.5 ‰")
    F.legend_above(ax)


def _full_list_svg(fonts):
    """The figure with the whole family list on every text (no first-family path)."""
    @contextlib.contextmanager
    def whole(_fonts):
        yield

    mp = pytest.MonkeyPatch()
    mp.setattr(F, "first_family", whole)
    mp.setattr(F, "font_fallback", lambda fig, fonts: None)
    try:
        return F.figure_svg(_draw, {}, {}, None, fonts)
    finally:
        mp.undo()


@pytest.mark.parametrize("lang", ["en", "zh"])
def test_first_family_same_bytes_as_whole_list(lang):
    from gonio.report.render import font_families

    fonts = font_families(lang)
    assert len(fonts) == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")            # a missing glyph warns: fail on it
        fast = F.figure_svg(_draw, {}, {}, None, fonts)
    assert fast == _full_list_svg(fonts)


def test_first_family_alone_would_miss_cjk_glyphs():
    """The negative control: without the fallback walk, the English list's first family
    (DejaVu Sans) has no CJK glyph; the walk is what keeps them."""
    from gonio.report.render import font_families

    fonts = font_families("en")
    mp = pytest.MonkeyPatch()
    mp.setattr(F, "font_fallback", lambda fig, fonts: None)
    try:
        with pytest.warns(UserWarning, match="missing from font"):
            F.figure_svg(_draw, {}, {}, None, fonts)
    finally:
        mp.undo()
