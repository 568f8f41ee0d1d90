"""Layout rules of the PDF renderer seen while rendering every certificate (issue 25): a
heading followed by a short note and a table keeps the table's start on its page (the
budget heading was stranded at the bottom of page 2), and no line of a wrapped cell starts
with a closing mark (a lone ")" or "。")."""

from __future__ import annotations

from gonio.report.render import Block, KEEP_PARAGRAPH_LINES, _wrap, layout_pages
from gonio.report.i18n import labels


def _where(pages, token):
    for p, ops in enumerate(pages):
        for _, op in ops:
            for d in (op.__defaults__ or ()):
                if token in repr(d):
                    return p
    return None


def test_heading_note_and_table_start_stay_together():
    L = labels("en")
    moved = 0
    for n_lines in range(40, 75):
        blocks = [Block("p", [f"filler line {i}"]) for i in range(n_lines)]
        blocks += [Block("h", "THE BUDGET"), Block("p", ["a short NOTE on the budget"]),
                   Block("table", (["HEADCOL", "b"], [[f"ROW{i}", "x"] for i in range(30)]),
                         (0.5, 0.5))]
        pages = layout_pages({"blocks": blocks, "id": "X", "virtual": False, "lab_name": "L"}, L)
        head = _where(pages, "THE BUDGET")
        assert _where(pages, "NOTE") == head == _where(pages, "HEADCOL") == \
            _where(pages, "ROW0"), n_lines
        moved += head > 0
    assert moved > 0 and KEEP_PARAGRAPH_LINES >= 1


def test_no_line_starts_with_a_closing_mark():
    for text, width in (("参见 JJF 1535-2015 第8章 k)。", 24), ("5.4.5.1 b)", 8),
                        ("微机电(MEMS)陀螺仪校准结果", 10), ("a (b) c", 3)):
        for line in _wrap(text, width)[1:]:
            assert line[:1] not in set("。，、；：）)]"), (text, width, _wrap(text, width))


def test_a_relation_is_never_left_at_a_line_end():
    """The optical results table's U cell wrapped as "p ≈ / 95 %)" (leftover 5): "k = 2.07,"
    and "p = 95 %)" are wrapped whole, in the PDF (_wrap) and the HTML (no-break spaces)."""
    from gonio.report.render import Num, _h

    text = "0.012 (k = 2.07, p = 95 %)"
    for width in range(10, 30):
        lines = _wrap(text, width)
        assert "".join(lines).replace(" ", "") == text.replace(" ", "")
        assert not any(line.rstrip().endswith(("≈", "=", "p", "(k")) for line in lines), lines
        assert any("p = 95 %)" in line for line in lines), (width, lines)
    cell = _h([Num("0.012", "U", "r"), " (k = ", Num("2.07", "k", "r"), ", p ≈ ",
               Num("95", "p", "r"), " %)"], True)
    assert "(k\u00a0=\u00a0<span" in cell and "p\u00a0≈\u00a0<span" in cell, cell
    assert "</span>\u00a0%)" in cell and "\u00a0" not in _h(", p ≈ ")    # cells only
    assert _h("27 %", True) == "27 %"             # a plain text keeps its space


def _table_block(tall_row_lines: int) -> Block:
    rows = [[f"ROW{i}", "x\ny" if i != 2 else "\n".join(["long"] * tall_row_lines)]
            for i in range(7)]
    return Block("table", (["HEADCOL", "b"], rows), (0.5, 0.5))


def test_short_table_starts_where_it_is_rather_than_leave_half_a_page_blank():
    """Page 1 of the optical certificate was half blank: its 7-row results table (one row
    of 7 lines) was kept whole on page 2. A table of at most KEEP_WHOLE_ROWS rows still moves
    whole when that leaves at most MAX_BLANK_FRACTION of the page blank; otherwise it starts
    on the page with its head and first rows and goes on under its repeated head (the
    filler is one line a block, a line and a gap: about 45 blocks fill a page)."""
    from gonio.report.render import (_BOTTOM, _TOP, MAX_BLANK_FRACTION, SPLIT_FIRST_ROWS,
                                          _Layout)

    L = labels("en")
    line = _Layout(8.5).line
    split = whole_moved = 0
    for n_lines in range(5, 60):
        blocks = [Block("p", [f"filler line {i}"]) for i in range(n_lines)]
        blocks += [Block("h", "RESULTS"), _table_block(9)]      # as the optical results
        pages = layout_pages({"blocks": blocks, "id": "X", "virtual": False, "lab_name": "L"}, L)
        last_filler = _where(pages, f"filler line {n_lines - 1}")
        head, row0, row6 = _where(pages, "RESULTS"), _where(pages, "ROW0"), _where(pages, "ROW6")
        assert head == _where(pages, "HEADCOL") == row0                  # never a lone head
        if row0 == last_filler and row6 > row0:
            split += 1
            assert _where(pages, f"ROW{SPLIT_FIRST_ROWS - 1}") == row0
            heads = sum(1 for ops in pages for _, op in ops
                        if "HEADCOL" in repr(op.__defaults__ or ()))
            assert heads == 2                                              # repeated head
        elif row0 > last_filler:
            whole_moved += 1
            # the blank it left: at most the allowed fraction, or too little for its start
            y_last = min(y for y, _ in pages[last_filler])
            blank = y_last - line - _BOTTOM
            assert blank <= MAX_BLANK_FRACTION * (_TOP - _BOTTOM) + 6 * line, n_lines
    assert split > 0 and whole_moved > 0
    # a short table still moves whole rather than split (at most 8 rows, fits on a page)
    blocks = [Block("p", [f"filler line {i}"]) for i in range(50)]
    blocks += [Block("h", "RESULTS"), _table_block(1)]
    pages = layout_pages({"blocks": blocks, "id": "X", "virtual": False, "lab_name": "L"}, L)
    assert _where(pages, "ROW0") == _where(pages, "ROW6")


def test_heading_note_and_short_table_stay_together():
    """The triad's cross-axis heading and note ended page 1 with their 6-row table on page 2:
    the heading judged the table splittable, the table's head then wanted it whole. Judged
    once, at the heading: the three stay together wherever the page ends."""
    L = labels("en")
    for n_lines in range(5, 60):
        blocks = [Block("p", [f"filler line {i}"]) for i in range(n_lines)]
        blocks += [Block("h", "THE CROSS"), Block("p", ["a short NOTE on it"]), _table_block(9)]
        pages = layout_pages({"blocks": blocks, "id": "X", "virtual": False, "lab_name": "L"}, L)
        assert _where(pages, "THE CROSS") == _where(pages, "NOTE") == \
            _where(pages, "HEADCOL") == _where(pages, "ROW0") == _where(pages, "ROW1"), n_lines
