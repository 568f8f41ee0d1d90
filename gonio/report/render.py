"""Certificate pages from content blocks: one self-contained HTML page and A4 PDF pages.

Every certificate (each specification's) is a list of :class:`Block` (heading, paragraph,
key–value rows, table, figure, notice) with its identifier and laboratory name; this module
lays them out. The content is made elsewhere (:mod:`gonio.report.header` for the ISO/IEC
17025 7.8 parts every certificate shares; the specification's own pages).

Contents
========
=========================  ==============================================================
:class:`Block`             one piece of content
:func:`render_html`        blocks + figures → one HTML page (figures inline as SVG)
:func:`render_pdf`         blocks + figures → A4 PDF pages (matplotlib PdfPages)
:func:`layout_pages`       the PDF's page layout (headings kept with what follows them)
:func:`font_families`      the fonts of a page's language
=========================  ==============================================================

Every page carries the laboratory, the certificate's identifier and "page x of y"; the last
page ends with the end-of-certificate mark.
"""

from __future__ import annotations

import html
import io
import re
import unicodedata
from dataclasses import dataclass
from typing import Any, Callable

from gonio.errors import GonioError
from gonio.report.figures import (SVG_PAD_IN, first_family, font_fallback, minus_signs,
                                  mpl_style, plain_log_ticks)
from gonio.report.i18n import cjk_font, labels, minus_sign
from gonio.report.stated import FlagText
from gonio.report.stated import NoBreakText as NoBreak
from gonio.report.stated import Num
from gonio.report.text import fit_header


@dataclass
class Block:
    """One piece of content: kind is h (heading), sub (sub-heading), p, kv, table, fig,
    notice, or keep (its data: a list of blocks kept together on one page, in the PDF and in
    the browser's print). Headings and sub-headings are kept on the page of what follows
    them."""

    kind: str
    data: Any
    extra: Any = None


# --------------------------------------------------------------------------- HTML

_CSS = """
body{font-family:%(font)s;max-width:1040px;margin:0 auto;padding:16px 24px;color:#111;font-size:14px}
header.page{display:flex;justify-content:space-between;border-bottom:2px solid #333;padding:4px 0;margin-bottom:8px}
h1{text-align:center;font-size:24px;margin:10px 0 4px}
h2{font-size:16px;border-bottom:1px solid #999;margin:18px 0 6px;padding-bottom:2px}
h3{font-size:14px;margin:12px 0 4px}
h2,h3{break-after:avoid;page-break-after:avoid}
table{border-collapse:collapse;width:100%%;margin:4px 0 8px}
tr{break-inside:avoid}
div.keep{break-inside:avoid;page-break-inside:avoid}
thead{display:table-header-group}
td,th{border:1px solid #888;padding:3px 6px;text-align:left;vertical-align:top}
th{background:#eee}
.nb{white-space:nowrap}
.flag{color:#b00020;font-weight:bold}
table.kv td:first-child{width:32%%;background:#f6f6f6}
.banner{background:#b00020;color:#fff;font-weight:bold;text-align:center;padding:8px;font-size:18px;letter-spacing:1px;margin:6px 0}
.watermark{position:fixed;top:45%%;left:0;width:100%%;text-align:center;transform:rotate(-30deg);font-size:64px;font-weight:bold;color:rgba(176,0,32,0.10);pointer-events:none;z-index:10}
.watermark.draft{top:22%%;font-size:110px;color:rgba(0,0,0,0.10);z-index:11}
.notice{border:2px solid #b00020;padding:6px;color:#b00020}
figure{margin:10px 0;break-inside:avoid;page-break-inside:avoid}
figure svg{width:100%%;height:auto}
figcaption{font-size:13px;color:#333;text-align:center}
.u{font-weight:bold;font-size:15px}
p.end{text-align:center;font-weight:bold;margin-top:18px}
div.closing{break-before:avoid;page-break-before:avoid;break-inside:avoid;page-break-inside:avoid}
footer{border-top:1px solid #333;margin-top:16px;font-size:12px;color:#333}
@page{size:A4;margin:20mm 14mm 18mm 14mm;
 @top-left{content:%(lab)s;font-family:%(font)s;font-size:9pt}
 @top-right{content:%(cid)s;font-family:%(font)s;font-size:9pt}
 @bottom-left{content:%(cid)s;font-family:%(font)s;font-size:8pt}
 @bottom-right{content:%(pageword)s;font-family:%(font)s;font-size:8pt}%(mark)s}
@media print{header.page,footer{display:none}body{max-width:none;padding:0;font-size:12px}
 figure svg{width:82%%}}
"""


def css_string(text: str) -> str:
    """``text`` as a quoted CSS string inside ``<style>``: backslash and quote escaped, and
    ``<``, ``>``, ``&`` as CSS hex escapes, so user text can never close the style element.

    >>> print(css_string('say "hi"'))
    "say \\"hi\\""
    >>> print(css_string("</style><script>"))
    "\\3c /style\\3e \\3c script\\3e "
    """
    text = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", " ")
    for ch, esc in (("<", "\\3c "), (">", "\\3e "), ("&", "\\26 ")):
        text = text.replace(ch, esc)
    return '"' + text + '"'


#: A lone relation sign in a table cell's text, bound to its sides with no-break spaces (and
#: a per-cent sign to the number segment before it), so a browser never wraps "p ≈ / 95 %"
#: (the PDF: :func:`_glue`). A plain "27 %" keeps its space.
_BIND = re.compile(r" (≈|=|≤|≥|&lt;|&gt;) ")


def _h(x, cell: bool = False) -> str:
    """HTML of a text, a number (its span with the rule it was rounded by), a NoBreak or a
    list of them; ``cell``: a table cell's text, relations bound (:data:`_BIND`)."""
    if isinstance(x, Num):
        return (f'<span class="num" data-src="{html.escape(x.src)}" '
                f'data-rule="{html.escape(x.rule)}">{html.escape(minus_sign(x.text))}</span>')
    if isinstance(x, NoBreak):
        return f'<span class="nb">{html.escape(minus_sign(str(x)))}</span>'
    if isinstance(x, FlagText):
        return f'<span class="flag">{html.escape(str(x))}</span>'
    if isinstance(x, list):
        return "".join(_h(s, cell) for s in x)
    s = html.escape(minus_sign(str(x)))
    if cell:
        s = _BIND.sub(lambda m: f"\u00a0{m[1]}\u00a0", s)
        if s.startswith(" %"):                  # "95 %" whose number is the segment before
            s = "\u00a0" + s[1:]
    return s


#: A caption that already begins with its figure number ("Fig. 1 …", "图1 …").
_NUMBERED = re.compile(r"^(Fig\.|Figure|图)\s*\d")


def figure_captions(blocks, L: dict) -> dict[str, str]:
    """Each figure's caption by its key, numbered in the order of the certificate ("Fig. 3 …",
    "图 3 …") unless its specification numbered it already.

    >>> figure_captions([Block("fig", ("a", "Allan deviation", None)),
    ...                  Block("fig", ("b", "Fig. 2 Bias", None))], {"fig_no": "Fig. {n}"})
    {'a': 'Fig. 1 Allan deviation', 'b': 'Fig. 2 Bias'}
    """
    out: dict[str, str] = {}
    figs = [b.data for b in blocks if b.kind == "fig"]
    for n, (key, cap, _) in enumerate(figs, 1):
        out[key] = cap if _NUMBERED.match(cap) else f"{L['fig_no'].format(n=n)} {cap}"
    return out


def title_of(content: dict, L: dict) -> str:
    """The title at the head of a certificate: "Calibration Certificate", or for a draft
    rendered for review (``content["draft"]``) one that says it is none.

    >>> title_of({"draft": True}, {"title": "Calibration Certificate", "draft_title": "Draft"})
    'Draft'
    """
    return L["draft_title"] if content.get("draft") else L["title"]


def _block_html(b: Block, svgs: dict[str, str], caps: dict[str, str]) -> str:
    """One block as HTML; a "keep" block (its data: blocks) is kept on one printed page."""
    if b.kind == "keep":
        return ('<div class="keep">' + "\n".join(_block_html(c, svgs, caps) for c in b.data)
                + "</div>")
    if b.kind == "h":
        return f"<h2>{html.escape(b.data)}</h2>"
    if b.kind == "sub":
        return f"<h3>{html.escape(b.data)}</h3>"
    if b.kind == "notice":           # its line breaks kept (an amendment's reason)
        return '<p class="notice">' + html.escape(b.data).replace("\n", "<br>") + "</p>"
    if b.kind == "p":
        cls = ' class="u" id="U-line"' if b.extra == "U" else ""
        return f"<p{cls}>{_h(b.data)}</p>"
    if b.kind == "kv":               # a value's line breaks kept (an address), as in the PDF
        return ('<table class="kv">' + "".join(
            f"<tr><td>{_h(k)}</td><td>{_h(v).replace(chr(10), '<br>')}</td></tr>"
            for k, v in b.data) + "</table>")
    if b.kind == "table":
        head, rows = b.data
        tid = f' id="{b.extra["id"]}"' if isinstance(b.extra, dict) else ""
        keep = html_keep_whole(head, rows, b.extra)   # kept whole on a printed page
        return (('<div class="keep">' if keep else "")
                + f"<table{tid}><thead><tr>" + "".join(f"<th>{_h(c)}</th>" for c in head)
                + "</tr></thead><tbody>"
                + "".join("<tr>" + "".join(f"<td>{_h(c, True)}</td>" for c in r) + "</tr>"
                          for r in rows) + "</tbody></table>" + ("</div>" if keep else ""))
    if b.kind == "fig":
        key = b.data[0]
        return (f'<figure id="fig-{key}">{svgs[key]}<figcaption>'
                f"{html.escape(caps[key])}</figcaption></figure>")
    return ""


def render_html(content: dict, svgs: dict[str, str], L: dict, lang: str, font: str | None) -> str:
    """The certificate as one self-contained HTML page (no external resources).

    On screen the page has a header with the laboratory and the identifier (a web page
    has no page numbers). Printed (print CSS, ``@page`` margin boxes) every page carries
    the laboratory, the identifier and "Page x of y".
    """
    cid = content["id"]
    ff = (f"'{font}', " if font else "") + "'DejaVu Sans', 'Noto Sans CJK SC', Arial, sans-serif"
    pageword = " ".join(
        css_string(part) if i % 2 == 0 else part for i, part in enumerate(
            L["page_of"].replace("{x}", "\0counter(page)\0").replace(
                "{y}", "\0counter(pages)\0").split("\0")) if part)
    # a virtual bench's certificate says so in every printed page's own text, not only in the
    # watermark's picture (a PDF reader's text layer drops rotated text): a margin box
    mark = ("\n @bottom-center{content:%s;font-family:%s;font-size:9pt;font-weight:bold;"
            "color:#b00020}" % (css_string(L["virtual_short"]), ff)) if content["virtual"] else ""
    css = _CSS % {"font": ff, "pageword": pageword, "lab": css_string(content["lab_name"]),
                  "cid": css_string(f"{L['certificate_no']}{L['colon']}{cid}"), "mark": mark}
    out = ["<!DOCTYPE html>", f'<html lang="{"zh-CN" if lang == "zh" else "en"}">', "<head>",
           '<meta charset="utf-8">', f"<title>{html.escape(title_of(content, L))} {html.escape(cid)}</title>",
           f"<style>{css}</style>", "</head>", "<body>"]
    if content["virtual"]:
        out.append(f'<div class="watermark" aria-hidden="true">{html.escape(L["virtual_short"])}</div>')
        out.append(f'<div class="banner" id="virtual-banner">{html.escape(L["virtual"])}</div>')
    if content.get("draft"):           # every printed page (position: fixed repeats)
        out.append(f'<div class="watermark draft" id="draft-watermark" aria-hidden="true">'
                   f'{html.escape(L["draft_short"])}</div>')
    out.append(f'<header class="page"><span>{html.escape(content["lab_name"])}</span>'
               f'<span id="cert-id" class="nb">{html.escape(L["certificate_no"] + L["colon"])}'
               f'{html.escape(cid)}</span></header>')
    out.append(f"<h1>{html.escape(title_of(content, L))}</h1>")
    caps = figure_captions(content["blocks"], L)
    out += [_block_html(b, svgs, caps) for b in content["blocks"]]
    # the end mark, footer and closing banner travel together and stay with the last block,
    # so a printed certificate never ends with a page holding only its end mark
    out.append('<div class="closing">')
    out.append(f'<p class="end" id="end-of-certificate">— {html.escape(L["end_mark"])} —</p>')
    out.append(f"<footer>{html.escape(L['certificate_no'] + L['colon'])}{html.escape(cid)} — "
               f"{html.escape(L['statement_copy'])}</footer>")
    if content["virtual"]:
        out.append(f'<div class="banner">{html.escape(L["virtual"])}</div>')
    out.append("</div>")
    out += ["</body>", "</html>", ""]
    return "\n".join(out)


# --------------------------------------------------------------------------- PDF

#: A4 portrait, inches.
A4_IN: tuple[float, float] = (8.27, 11.69)
_PT = 1.0 / 72.0 / A4_IN[1]          # one point as a fraction of the page height
_LEFT, _RIGHT, _TOP, _BOTTOM = 0.08, 0.92, 0.90, 0.08
_FIG_H = 0.33                        # a figure's height, fraction of the page
_TWIN_RIGHT = 0.075                  # room for a figure's right-hand y axis, of the width


def _width(s: str) -> int:
    return sum(2 if unicodedata.east_asian_width(ch) in "WF" else 1 for ch in s)


#: Characters that never begin a line (closing brackets and punctuation, GB/T 15834 4.1)
#: and that never end one (opening brackets).
_NO_START = set("。，、；：？！）」』】〉》)]}%,;:")
_NO_END = set("（「『【〈《([{")


#: A relation standing alone between spaces binds its two sides: "p = 95 %", "k = 2.07".
_RELATIONS = frozenset("≈=≤≥<>")


def _glue(tokens: list[str]) -> list[str]:
    """Wrapping tokens with a closing mark joined to the token before it and an opening mark
    to the token after it, so no line starts with ")" or "。" nor ends with "("; a lone
    relation sign is joined to both its sides (no line ends with "p ≈").

    >>> _glue(["k", "）", "。"]), _glue(["（", "a", "b"]), _glue(["≈ ", "95 ", "%)"])
    (['k）。'], ['（a', 'b'], ['≈ 95 %)'])
    >>> _glue(["0.012 ", "(k ", "= ", "2.07, ", "p ", "≈ ", "95 ", "%)"])
    ['0.012 ', '(k = 2.07, ', 'p ≈ 95 %)']
    """
    out: list[str] = []
    carry = ""
    bind = False
    for tok in tokens:
        tok = carry + tok
        carry = ""
        relation = tok.strip() in _RELATIONS and len(tok.strip()) == 1
        if out and (bind or relation):
            out[-1] += tok
            bind = relation
            continue
        bind = relation
        if out and tok and tok[0] in _NO_START and (not out[-1].endswith(" ")
                                                      or tok[0] == "%"):   # "95 %" whole
            out[-1] += tok
        elif tok and tok[-1] in _NO_END and len(tok) == 1:
            carry = tok
        else:
            out.append(tok)
    if carry:
        out.append(carry)
    return out


def _tokens(para: str) -> list[str]:
    """The unbreakable pieces of one paragraph: words with their trailing space, each CJK
    character alone, glued (:func:`_glue`)."""
    tokens: list[str] = []
    word = ""
    for ch in para:
        if ch == " ":
            tokens.append(word + " ")
            word = ""
        elif unicodedata.east_asian_width(ch) in "WF":
            if word:
                tokens.append(word)
            tokens.append(ch)
            word = ""
        else:
            word += ch
    if word:
        tokens.append(word)
    return _glue(tokens)


def _wrap(text: str, width: int) -> list[str]:
    """Wrap ``text`` to ``width`` columns (CJK characters count two; breaks at spaces or CJK)."""
    lines: list[str] = []
    for para in str(text).split("\n"):
        line, w = "", 0
        for tok in _tokens(para):
            tw = _width(tok)
            if w + tw > width and line:
                lines.append(line.rstrip())
                line, w = "", 0
            while tw > width:                      # a single over-long token
                lines.append(tok[:width])
                tok = tok[width:]
                tw = _width(tok)
            line += tok
            w += tw
        lines.append(line.rstrip())
    return lines


def _text(x) -> str:
    """A block's text as the PDF prints it (numbers with the minus sign, :func:`minus_sign`)."""
    if isinstance(x, Num):
        return minus_sign(x.text)
    if isinstance(x, list):
        return "".join(_text(s) for s in x)
    return minus_sign(str(x))


def _cell_lines(c, cols: int) -> list[str]:
    """A table cell's lines: a NoBreak cell (identifier, unit) is never split."""
    if isinstance(c, NoBreak):
        return [minus_sign(str(c))]
    return _wrap(_text(c), cols)


def _longest_token(c) -> int:
    """Width (columns) of the longest unbreakable piece of a cell."""
    if isinstance(c, NoBreak):
        return _width(str(c))
    return max((_width(t.rstrip()) for para in _text(c).split("\n") for t in _tokens(para)),
               default=0)


#: Smallest font (pt) a table is set in so that its longest words fit their columns.
MIN_TABLE_FONT: float = 6.0


def table_font(head, rows, lay: "_Layout") -> float:
    """The body font size of a table whose columns each fit their longest word (a cell wraps
    only between words: no "Probabilit|y"): the page's size, or smaller — down to
    :data:`MIN_TABLE_FONT` — when the longest words of all columns together do not fit the
    text width at it."""
    need = [0] * len(head)
    for r in [head, *rows]:
        for j, c in enumerate(r):
            need[j] = max(need[j], _longest_token(c) + 2.5)
    total = sum(need)
    have = lay.cols(1.0)
    return lay.fs if total <= have else max(MIN_TABLE_FONT, lay.fs * have / total)


def fit_widths(widths, head, rows, cols_per_frac: float) -> tuple[float, ...]:
    """Column widths (fractions summing to 1) widened so that no identifier, unit or word
    is broken: each column gets at least its longest token, taken from columns with slack.

    >>> fit_widths((0.5, 0.5), ["a", "b"], [["x" * 30, "y"]], 40.0)
    (0.7875, 0.2125)
    """
    need = [0.0] * len(widths)
    for r in [head, *rows]:
        for j, c in enumerate(r):
            need[j] = max(need[j], (_longest_token(c) + 1.5) / cols_per_frac)
    w = [max(a, b) for a, b in zip(widths, need)]
    excess = sum(w) - 1.0
    if excess > 1e-12:
        slack = [max(0.0, wi - ni) for wi, ni in zip(w, need)]
        total = sum(slack)
        if total > 0:
            w = [wi - excess * si / total if total >= excess else wi - si
                 for wi, si in zip(w, slack)]
        ssum = sum(w)
        w = [wi / ssum for wi in w]
    return tuple(round(x, 6) for x in w)


class _Layout:
    """Places blocks on A4 pages; each page is a list of (y_top, op)."""

    def __init__(self, fontsize: float):
        self.fs = fontsize
        self.line = fontsize * 1.45 * _PT
        self.pages: list[list] = [[]]
        self.y = _TOP

    def fits(self, h: float) -> bool:
        return self.y - h >= _BOTTOM or not self.pages[-1]

    def need(self, h: float) -> None:
        if not self.fits(h):
            self.pages.append([])
            self.y = _TOP

    def put(self, h: float, op: Callable) -> None:
        self.need(h)
        self.pages[-1].append((self.y, op))
        self.y -= h

    def cols(self, frac: float) -> int:
        """Characters of the body font that fit in ``frac`` of the text width."""
        width_pt = (_RIGHT - _LEFT) * A4_IN[0] * 72.0 * frac
        return max(4, int(width_pt / (self.fs * 0.56)))


_H_H = 22 * _PT          # a heading's height
_SUB_H = 16 * _PT        # a sub-heading's height


#: A table of at most this many rows is kept on one page (when it fits on one).
KEEP_WHOLE_ROWS: int = 8
#: A longer table starts on a page with its head and at least this many rows; its head is
#: repeated on every continuation page.
KEEP_FIRST_ROWS: int = 3
#: A short table is not kept whole when moving it to the next page would leave more than this
#: fraction of the page's text height blank (the optical certificate's page 1 was left with a
#: fifth of it blank): it starts where it is, with its head and first
#: :data:`SPLIT_FIRST_ROWS` rows, and goes on under its repeated head.
MAX_BLANK_FRACTION: float = 1 / 8
#: The rows a short table split by :data:`MAX_BLANK_FRACTION` starts with (no lone row).
SPLIT_FIRST_ROWS: int = 2
#: The HTML (laid out by the browser) keeps a short table whole when it is at most this
#: fraction of a page's text height (:func:`html_keep_whole`).
HTML_KEEP_WHOLE_FRACTION: float = 1 / 4


def html_keep_whole(head, rows, extra) -> bool:
    """Whether the HTML keeps a table whole on a printed page (the browser lays it out, so
    PDF's rule of :func:`table_start` cannot be applied): at most :data:`KEEP_WHOLE_ROWS` rows
    and, counted in lines at the PDF's column widths, at most
    :data:`HTML_KEEP_WHOLE_FRACTION` of a page, so that moving it whole never leaves more
    than that blank."""
    if len(rows) > KEEP_WHOLE_ROWS:
        return False
    lay = _Layout(8.5)
    widths = extra["widths"] if isinstance(extra, dict) else extra
    widths = fit_widths(widths, head, rows, lay.cols(1.0) * 1.0)
    lines = sum(max(len(_cell_lines(c, lay.cols(w) - 1)) for c, w in zip(r, widths))
                for r in [head, *rows])
    return lines * lay.line <= HTML_KEEP_WHOLE_FRACTION * (_TOP - _BOTTOM)


def table_start(units: list, room: float | None = None) -> float:
    """Height a table needs where it starts: its head with its first rows — all of them for a
    table of at most :data:`KEEP_WHOLE_ROWS` rows, else :data:`KEEP_FIRST_ROWS` — so a head
    never ends a page with its rows on the next one. ``room``: the height left on the page;
    a short table that does not fit there is still started there (head and
    :data:`SPLIT_FIRST_ROWS` rows) when keeping it whole would leave more than
    :data:`MAX_BLANK_FRACTION` of the page blank."""
    rows = [u for u in units if u[2] == "row"]
    n = len(rows) if len(rows) <= KEEP_WHOLE_ROWS else KEEP_FIRST_ROWS
    whole = units[0][0] + sum(u[0] for u in rows)
    if (room is not None and n == len(rows) and whole > room
            and room > MAX_BLANK_FRACTION * (_TOP - _BOTTOM)):
        n = min(n, SPLIT_FIRST_ROWS)
    h = units[0][0] + sum(u[0] for u in rows[:n])
    return h if h <= _TOP - _BOTTOM - 40 * _PT else units[0][0] + sum(u[0] for u in rows[:1])


#: A paragraph of at most this many lines is not split across pages.
KEEP_PARAGRAPH_LINES: int = 4


def block_start(block: Block, units: list, room: float | None = None) -> float:
    """Height a block needs on the page where it starts: a table's :func:`table_start` (with
    the ``room`` left), a short paragraph whole (at most :data:`KEEP_PARAGRAPH_LINES` lines),
    else its first unit."""
    if not units:
        return 0.0
    if block.kind == "table":
        return table_start(units, room)
    lines = [u[0] for u in units if u[2] == "line"]
    if block.kind in ("p", "notice") and len(lines) <= KEEP_PARAGRAPH_LINES:
        return sum(u[0] for u in units)         # its lines and the gap after them
    return units[0][0]


def layout_pages(content: dict, L: dict) -> list[list]:
    """Lay the blocks out on pages. A heading (h, sub) is kept on the page of the first
    unit of the block after it (:func:`block_start`: a table's head and first rows, a short
    paragraph whole, a figure, a long paragraph's first line), and of a table's start when a
    short note stands between them, so no page ends with a heading."""
    lay = _Layout(8.5)
    fs, ln = lay.fs, lay.line
    title_h = 30 * _PT

    def title(fig, y):
        fig.text(0.5, y - 20 * _PT, title_of(content, L), ha="center", va="baseline", fontsize=18,
                 weight="bold")
    lay.put(title_h, title)

    def end_mark(fig, y):
        fig.text(0.5, y - ln * 1.6, f"— {L['end_mark']} —", ha="center", va="baseline",
                 fontsize=fs, weight="bold")
    blocks = content["blocks"]
    units = [_units(b, lay, content, L) for b in blocks]
    room_at: dict[int, float] = {}     # a table's room as judged where its heading was placed
    for i, b in enumerate(blocks):
        if b.kind in ("h", "sub"):
            # keep with the next block's first unit (and every following heading's)
            keep = 0.0
            j = i + 1
            while j < len(blocks) and blocks[j].kind in ("h", "sub"):
                keep += units[j][0][0]
                j += 1
            if j < len(blocks):
                room = lay.y - _BOTTOM - units[i][0][0] - keep
                room_at[j] = room
                keep += block_start(blocks[j], units[j], room)
                # a short note between a heading and its table: keep the table's start too
                if (blocks[j].kind == "p" and j + 1 < len(blocks)
                        and blocks[j + 1].kind == "table"
                        and len(units[j]) <= KEEP_PARAGRAPH_LINES):
                    room_at[j + 1] = room - keep
                    keep += block_start(blocks[j + 1], units[j + 1], room - keep)
            lay.need(units[i][0][0] + keep)
        elif b.kind in ("p", "notice"):
            lay.need(block_start(b, units[i]))
        elif b.kind == "keep":                   # on one page (when it fits on one)
            lay.need(sum(u[0] for u in units[i]))
        for k, (h, op, kind) in enumerate(units[i]):
            if kind == "row" and not lay.fits(h):          # repeat the table head
                head_h, head_op, _ = units[i][0]
                lay.need(h + head_h)
                lay.put(head_h, head_op)
            elif kind == "head":      # decided as for its heading: it stays with it
                lay.need(table_start(units[i], room_at.get(i, lay.y - _BOTTOM)))
            if kind == "gap":
                lay.y -= h
                continue
            lay.put(h, op)
    lay.put(ln * 2.5, end_mark)
    return lay.pages


def _units(b: Block, lay: _Layout, content: dict, L: dict) -> list[tuple[float, Callable, str]]:
    """A block as (height, draw op, kind) units that are never split across pages."""
    fs, ln = lay.fs, lay.line
    out: list[tuple[float, Callable, str]] = []
    if b.kind == "keep":
        return [u for c in b.data for u in _units(c, lay, content, L)]
    if b.kind in ("h", "sub"):
        big = b.kind == "h"

        def op(fig, y, t=b.data, big=big):
            fig.text(_LEFT, y - (13 if big else 11) * _PT, t, fontsize=10.5 if big else 9.2,
                     weight="bold", va="baseline")
            if big:
                fig.add_artist(_hline(fig, y - 16 * _PT, 0.6))
        out.append((_H_H if big else _SUB_H, op, "h"))
    elif b.kind in ("p", "notice"):
        big = b.extra == "U"
        lines = _wrap(_text(b.data), lay.cols(1.0) - (8 if big else 0))
        size = 10 if big else fs
        color = "#b00020" if b.kind == "notice" else "black"
        for line in lines:
            def op(fig, y, t=line, s=size, c=color, w="bold" if big else "normal"):
                fig.text(_LEFT, y - ln * 0.8, t, fontsize=s, va="baseline", color=c, weight=w)
            out.append((ln * (1.15 if big else 1.0), op, "line"))
        out.append((3 * _PT, None, "gap"))
    elif b.kind == "kv":
        for k, v in b.data:
            vl = _cell_lines(v, lay.cols(0.66))

            flag = isinstance(v, list) and any(isinstance(x, FlagText) for x in v)

            def op(fig, y, k=_text(k), vl=vl, flag=flag):   # a flagged value all in red
                fig.text(_LEFT, y - ln * 0.8, k, fontsize=fs, va="baseline", color="0.25")
                for i, t in enumerate(vl):
                    fig.text(_LEFT + 0.32 * (_RIGHT - _LEFT), y - ln * (0.8 + i), t,
                             fontsize=fs, va="baseline", color="#b00020" if flag else "black",
                             weight="bold" if flag else "normal")
            out.append((ln * len(vl), op, "line"))
        out.append((4 * _PT, None, "gap"))
    elif b.kind == "table":
        head, rows = b.data
        tl = _Layout(table_font(head, rows, lay))   # smaller where a word would not fit
        fs, ln = tl.fs, tl.line
        widths = b.extra["widths"] if isinstance(b.extra, dict) else b.extra
        widths = fit_widths(widths, head, rows, tl.cols(1.0) * 1.0)
        xs = [_LEFT]
        for w in widths[:-1]:
            xs.append(xs[-1] + w * (_RIGHT - _LEFT))

        def row_unit(cells, bold=False, shade=False):
            wrapped = [_cell_lines(c, tl.cols(w) - 1) for c, w in zip(cells, widths)]
            n = max(len(w) for w in wrapped)

            def op(fig, y, wrapped=wrapped, n=n, xs=tuple(xs)):
                if shade:
                    fig.add_artist(_rect(fig, y, ln * n + 2 * _PT))
                for x, ls in zip(xs, wrapped):
                    for i, t in enumerate(ls):
                        fig.text(x + 0.004, y - ln * (0.8 + i), t, fontsize=fs - 0.5,
                                 va="baseline", weight="bold" if bold else "normal")
                fig.add_artist(_hline(fig, y - ln * n - 2 * _PT, 0.3))
            return ln * n + 2 * _PT, op
        h, op = row_unit(head, bold=True, shade=True)
        out.append((h, op, "head"))
        for r in rows:
            h2, op2 = row_unit(r)
            out.append((h2, op2, "row"))
        out.append((6 * _PT, None, "gap"))
    elif b.kind == "fig":
        key, _, draw = b.data
        cap_lines = _wrap(figure_captions(content["blocks"], L)[key], lay.cols(1.0))
        h = _FIG_H + ln * len(cap_lines) + 6 * _PT

        def op(fig, y, key=key, draw=draw, cap_lines=cap_lines):
            # the legend sits above the axes (figures._legend): leave it room below y
            gs = fig.add_gridspec(1, 1, left=_LEFT + 0.06, right=_RIGHT - 0.01,
                                  top=y - 0.05, bottom=y - _FIG_H + 0.035)
            before = set(fig.axes)
            draw(fig, gs[0], content["_report"], L, content["_truth"])
            axes = [ax for ax in fig.axes if ax not in before]
            if any(ax.yaxis.get_label_position() == "right" and ax.yaxis.label.get_text()
                   for ax in axes):
                gs.update(right=_RIGHT - _TWIN_RIGHT)    # room for a right-hand y axis
            plain_log_ticks(fig)
            for ax in axes:                  # this figure's texts (not the page's again)
                minus_signs(ax)
            for i, t in enumerate(cap_lines):
                fig.text(0.5, y - _FIG_H - ln * (0.8 + i), t, ha="center", fontsize=fs,
                         va="baseline")
            return key, axes, y
        out.append((h, op, "fig"))
    return out


def _hline(fig, y, lw):
    from matplotlib.lines import Line2D
    return Line2D([_LEFT, _RIGHT], [y, y], transform=fig.transFigure, color="0.3", lw=lw)


def _rect(fig, y, h):
    from matplotlib.patches import Rectangle
    return Rectangle((_LEFT, y - h), _RIGHT - _LEFT, h, transform=fig.transFigure,
                     color="0.92", zorder=-1)


def render_pdf(content: dict, L: dict, fonts: tuple[str, ...] = ("DejaVu Sans",)) -> bytes:
    """The certificate as A4 PDF pages; each page has the identifier and "page x of y"."""
    return render_pdf_figures(content, L, fonts, svg=False)[0]


def render_pdf_figures(content: dict, L: dict, fonts: tuple[str, ...] = ("DejaVu Sans",),
                       svg: bool = True) -> tuple[bytes, dict[str, str]]:
    """The certificate as A4 PDF pages (:func:`render_pdf`) and, with ``svg``, each figure
    of the pages as SVG text (``{figure key: svg}``, for :func:`render_html`).

    A figure is drawn once, into its page: its SVG is that page saved with every artist but
    the figure's axes hidden, cut to the figure (:func:`_figure_box`) — the same layout as
    on the PDF page, fixed (no tight-layout pass), the axes, ticks and legends built once for
    both outputs. The XML prolog and DOCTYPE are dropped so the text can be inlined in
    HTML."""
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure

    buf = io.BytesIO()
    svgs: dict[str, str] = {}
    with mpl_style(fonts), first_family(fonts):
        pages = layout_pages(content, L)
        n = len(pages)
        with PdfPages(buf, metadata={"CreationDate": None, "ModDate": None,
                                     "Creator": "gonio",
                                     "Title": f"{title_of(content, L)} {content['id']}"}
                      ) as pdf:
            for p, ops in enumerate(pages, 1):
                fig = Figure(figsize=A4_IN, dpi=72)     # a PDF's and an SVG's own unit
                _page_frame(fig, content, L, p, n)
                drawn = [op(fig, y) for y, op in ops]
                font_fallback(fig, fonts)
                pdf.savefig(fig)
                if svg:
                    for key, axes, y in (d for d in drawn if d is not None):
                        svgs[key] = _figure_cut_svg(fig, axes,
                                                    _figure_box(fig, axes, y))
    return buf.getvalue(), svgs


def _side_extent(ax, renderer) -> tuple[float, float]:
    """Left and right edge (display units) of ``ax`` with its axis labels, tick labels,
    titles and texts as the last drawing placed them (the texts left and right of an axes; a
    legend above it spans its width)."""
    from matplotlib.text import Text

    bb = ax.bbox
    texts = [ax.xaxis.label, ax.yaxis.label] + [
        c for c in ax.get_children() if isinstance(c, Text)]      # titles, ax.text
    for axis, i in ((ax.xaxis, 0), (ax.yaxis, 1)):
        lo, hi = (bb.x0, bb.x1) if i == 0 else (bb.y0, bb.y1)
        for tick in axis.get_major_ticks() + axis.get_minor_ticks():
            # a tick outside the view keeps a label that is not drawn
            texts += [t for t in (tick.label1, tick.label2)
                      if lo - 1.0 <= t.get_transform().transform(t.get_position())[i]
                      <= hi + 1.0]
    boxes = [bb] + [t.get_window_extent(renderer) for t in texts
                    if t.get_visible() and t.get_text()]
    return min(b.x0 for b in boxes), max(b.x1 for b in boxes)


def _svg_measure(fig):
    """A renderer that measures text as an SVG of ``fig`` draws it (paths of the glyphs,
    no hinting; a raster renderer's hinted widths differ by several per cent)."""
    from matplotlib.backends.backend_svg import RendererSVG

    return RendererSVG(fig.bbox.width, fig.bbox.height, io.StringIO(), image_dpi=fig.dpi)


def _figure_box(fig, axes: list, y: float):
    """The part of the page ``fig`` (drawn) an SVG of ``axes`` is cut to, in inches: the
    figure block whose top is at ``y`` (fraction of the page height) and :data:`SVG_PAD_IN`
    below it, from the leftmost to the rightmost text of the axes (:func:`_side_extent`) or
    the page's text margins, whichever is wider, plus :data:`SVG_PAD_IN`."""
    from matplotlib.transforms import Bbox

    w, h = A4_IN
    r = _svg_measure(fig)
    x0, x1 = zip(*(_side_extent(ax, r) for ax in axes))
    x0 = min(min(x0) / fig.dpi, _LEFT * w) - SVG_PAD_IN
    x1 = max(max(x1) / fig.dpi, _RIGHT * w) + SVG_PAD_IN
    # below the block: room for the x label's descenders, which reach just under it
    return Bbox.from_extents(x0, (y - _FIG_H) * h - SVG_PAD_IN, x1, y * h)


def _figure_cut_svg(fig, axes: list, box) -> str:
    """The page ``fig`` as SVG text with only ``axes`` shown, cut to ``box`` (inches)."""
    keep = set(axes)
    hidden = [a for a in fig.get_children()
              if a is not fig.patch and a not in keep and a.get_visible()]
    for a in hidden:
        a.set_visible(False)
    try:
        out = io.StringIO()
        fig.savefig(out, format="svg", bbox_inches=box, metadata={"Date": None})
    finally:
        for a in hidden:
            a.set_visible(True)
    text = out.getvalue()
    return text[text.index("<svg"):]


def _page_frame(fig, content, L, p, n) -> None:
    page = L["page_of"].format(x=p, y=n)
    cid = f"{L['certificate_no']}{L['colon']}{content['id']}"
    # the lab name never runs into the certificate number (9 pt: ~0.56 em a character)
    cols = int((_RIGHT - _LEFT) * A4_IN[0] * 72.0 / (9 * 0.6))
    fig.text(_LEFT, 0.955, fit_header(content["lab_name"], cid, cols), fontsize=9,
             va="baseline")
    fig.text(_RIGHT, 0.955, cid, fontsize=9, va="baseline", ha="right")
    fig.text(_RIGHT, 0.94, page, fontsize=9, va="baseline", ha="right")
    fig.add_artist(_hline(fig, 0.932, 1.0))
    fig.add_artist(_hline(fig, 0.055, 0.6))
    fig.text(_LEFT, 0.04, f"{cid}   {page}", fontsize=7.5, va="baseline")
    fig.text(_LEFT, 0.027, L["statement_copy"], fontsize=6.5, va="baseline", color="0.3")
    if content.get("draft"):
        fig.text(0.5, 0.62, L["draft_short"], ha="center", va="center", fontsize=96,
                 weight="bold", color="black", alpha=0.10, rotation=35, zorder=-5)
    if content["virtual"]:
        fig.text(0.5, 0.915, L["virtual"], ha="center", va="baseline", fontsize=11,
                 weight="bold", color="white",
                 bbox={"boxstyle": "square,pad=0.35", "fc": "#b00020", "ec": "none"})
        fig.text(0.5, 0.5, L["virtual_short"], ha="center", va="center", fontsize=54,
                 weight="bold", color="#b00020", alpha=0.10, rotation=35, zorder=-5)


# --------------------------------------------------------------------------- fonts

def has_cjk_font() -> bool:
    """True when a CJK font is installed (see :func:`gonio.report.i18n.cjk_font`)."""
    try:
        cjk_font()
    except GonioError:
        return False
    return True


def cjk_notice(lang: str) -> str | None:
    """The one line a command prints when the English certificate falls back to the English
    title because no CJK font is installed (None when there is one, or for zh)."""
    if lang != "en" or has_cjk_font():
        return None
    return labels("en")["cjk_missing"]


def font_families(lang: str) -> tuple[str, ...]:
    """Font families of the figures and the PDF, in fallback order.

    "zh": the CJK font first (GonioError naming the package when none is installed);
    "en": DejaVu Sans, then a CJK font if one is installed (the specification's title
    is Chinese).
    """
    if lang == "zh":
        return (cjk_font(), "DejaVu Sans")
    try:
        return ("DejaVu Sans", cjk_font())
    except GonioError:
        return ("DejaVu Sans",)
