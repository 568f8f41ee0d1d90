"""Uncertainty budget tables (JCGM 100 7.2.7: give each component, its u and c).

- :func:`budget_table` — a :class:`GumResult` as a pandas DataFrame with columns
  ``symbol, source, type, distribution, half_width, divisor, u_xi, c_i,
  contribution, dof`` (contribution = |c_i|·u(x_i), JCGM 100 5.1.3).
- :func:`render_text`, :func:`render_markdown`, :func:`render_html` — the same table
  as text; computing and reporting are separate.
"""

from __future__ import annotations

import html
import math

import pandas as pd

__all__ = ["COLUMNS", "budget_table", "render_text", "render_markdown", "render_html"]

#: Column order of every budget table.
COLUMNS = ("symbol", "source", "type", "distribution", "half_width", "divisor", "u_xi", "c_i",
           "contribution", "dof")


def budget_table(result) -> pd.DataFrame:
    """The budget of a GUM result as a DataFrame, one row per input (JCGM 100 7.2.7).

    >>> import sympy
    >>> from uncertainty.quantities import type_b
    >>> from uncertainty.propagation import propagate
    >>> x, y = sympy.symbols("x y")
    >>> t = budget_table(propagate(x - y, [type_b("x", 0, 0.1), type_b("y", 0, 0.3)]))
    >>> list(t.columns) == list(COLUMNS), round(float(t.contribution.iloc[1]), 4)
    (True, 0.1732)
    """
    rows = [{c: getattr(r, c) for c in COLUMNS} for r in result.contributions]
    return pd.DataFrame(rows, columns=list(COLUMNS))


def _fmt(v, digits: int) -> str:
    if v is None:
        return "—"
    if isinstance(v, str):
        return v
    if isinstance(v, float):
        if math.isinf(v):
            return "∞"
        if math.isnan(v):
            return "—"
        return f"{v:.{digits}g}"
    return str(v)


def _cells(df: pd.DataFrame, digits: int) -> tuple[list[str], list[list[str]]]:
    head = [str(c) for c in df.columns]
    body = [[_fmt(v, digits) for v in row] for row in df.astype(object).itertuples(index=False)]
    return head, body


def render_text(df: pd.DataFrame, digits: int = 4) -> str:
    """Plain-text table with aligned columns.

    >>> print(render_text(pd.DataFrame({"symbol": ["P"], "u_xi": [0.05773502]})))
    symbol  u_xi
    ------  -------
    P       0.05774
    """
    head, body = _cells(df, digits)
    w = [max(len(h), *(len(r[i]) for r in body)) if body else len(h) for i, h in enumerate(head)]
    line = lambda cells: "  ".join(c.ljust(w[i]) for i, c in enumerate(cells)).rstrip()
    out = [line(head), line(["-" * x for x in w])] + [line(r) for r in body]
    return "\n".join(out)


def render_markdown(df: pd.DataFrame, digits: int = 4) -> str:
    """GitHub-flavoured Markdown table (no extra dependency).

    >>> print(render_markdown(pd.DataFrame({"symbol": ["P"], "u_xi": [0.05773502]})))
    | symbol | u_xi |
    |---|---|
    | P | 0.05774 |
    """
    head, body = _cells(df, digits)
    esc = lambda s: s.replace("|", "\\|")
    out = ["| " + " | ".join(map(esc, head)) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join(map(esc, r)) + " |" for r in body]
    return "\n".join(out)


def render_html(df: pd.DataFrame, digits: int = 4) -> str:
    """An HTML ``<table>`` (escaped).

    >>> render_html(pd.DataFrame({"symbol": ["<P>"]})).splitlines()[2]
    '<tr><td>&lt;P&gt;</td></tr>'
    """
    head, body = _cells(df, digits)
    out = ["<table class=\"budget\">",
           "<tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr>"]
    out += ["<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in body]
    out.append("</table>")
    return "\n".join(out)
