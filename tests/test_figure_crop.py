"""The HTML's figures are cut from the PDF pages (one drawing of each figure for both
outputs, :func:`gonio.report.render.render_pdf_figures`): the cut must hold everything the
figure draws. Checked against matplotlib's own tight box of each figure's axes (every
text, tick label and legend, computed anew, not the cut's own measure), for every
specification's figures in English and Chinese; and the figure block must hold it on the
PDF page too (a legend above the axes or a label below them never runs into the text
around the figure)."""

from __future__ import annotations

import io
import re

import pytest

from gonio.report import render
from tests.test_zh_certificates import small_result

#: Tolerance of the comparison (inches): a hundredth of a point of rounding.
TOL_IN = 1e-3
#: How far below its block a figure may draw on the page (inches): 2 pt, less than the
#: room above the caption's first line (0.8 of an 8.5 pt line less its cap height).
BELOW_IN = 2.0 / 72.0


@pytest.fixture(scope="module", params=("ogam-draft", "jjf1535-2015", "iec62047-20",
                                        "triad-alignment"))
def calibrated(request, tmp_path_factory):
    d = tmp_path_factory.mktemp(request.param)
    return request.param, small_result(request.param, d)[0]


def _render(key, result, out, lang, monkeypatch) -> list:
    """Write the certificate; the (figure's tight box, cut box, block box) of each figure."""
    from matplotlib.backends.backend_svg import RendererSVG
    from matplotlib.transforms import Bbox

    from gonio.specs import get

    seen = []
    cut = render._figure_box

    def spy(fig, axes, y):
        box = cut(fig, axes, y)
        r = RendererSVG(fig.bbox.width, fig.bbox.height, io.StringIO())   # the SVG's metrics
        tight = Bbox.union([ax.get_tightbbox(r) for ax in axes]).transformed(
            fig.dpi_scale_trans.inverted())
        w, h = render.A4_IN
        block = Bbox.from_extents(0.0, (y - render._FIG_H) * h, w, y * h)
        seen.append((tight, box, block))
        return box

    monkeypatch.setattr(render, "_figure_box", spy)
    get(key).renderer().write(result, out, lang=lang)
    return seen


@pytest.mark.parametrize("lang", ("en", "zh"))
def test_every_figure_lies_inside_its_svg_and_its_block(calibrated, lang, tmp_path,
                                                        monkeypatch):
    key, result = calibrated
    seen = _render(key, result, tmp_path, lang, monkeypatch)
    html = (tmp_path / "certificate.html").read_text(encoding="utf-8")
    assert seen and len(seen) == html.count("<svg"), key
    for tight, box, block in seen:
        assert tight.x0 >= box.x0 - TOL_IN and tight.x1 <= box.x1 + TOL_IN, (key, tight, box)
        assert tight.y0 >= box.y0 - TOL_IN and tight.y1 <= box.y1 + TOL_IN, (key, tight, box)
        # on the page: nothing above the block's top; below it at most the x label's
        # descenders (BELOW_IN), above the caption's first line
        assert tight.y1 <= block.y1 + TOL_IN and tight.y0 >= block.y0 - BELOW_IN, \
            (key, tight, block)
    # the SVG's size is the cut box's
    sizes = re.findall(r'<svg[^>]*width="([\d.]+)pt" height="([\d.]+)pt"', html)
    for (w, h), (_, box, _) in zip(sizes, seen):
        assert abs(float(w) - box.width * 72) < 0.01 and abs(float(h) - box.height * 72) < 0.01


def test_the_check_can_fail(calibrated, tmp_path, monkeypatch):
    """A cut to the axes alone (no room for tick labels) is caught by the comparison."""
    from matplotlib.transforms import Bbox

    key, result = calibrated
    monkeypatch.setattr(render, "_side_extent", lambda ax, r: (ax.bbox.x0, ax.bbox.x1))
    seen = _render(key, result, tmp_path, "en", monkeypatch)
    assert any(tight.x0 < box.x0 - TOL_IN for tight, box, _ in seen), key
    assert isinstance(seen[0][1], Bbox)
