"""Layout rules of the PDF renderer seen while rendering every certificate (issue 25): a
heading followed by a short note and a table keeps the table's start on its page (the
budget heading was stranded at the bottom of page 2), and no line of a wrapped cell starts
with a closing mark (a lone ")" or "。")."""

from __future__ import annotations

from gonio.report.certificate import Block, KEEP_PARAGRAPH_LINES, _wrap, layout_pages
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
