"""User text on the certificate: shown literally, safely, the same in HTML and PDF.

Text a user controls (laboratory file, customer, serial, readings metadata, file
names) passes :func:`clean_text` before it reaches HTML, a figure or the PDF:

* control characters (C0/C1) become a space; Unicode bidi overrides, embeddings
  and isolates (U+202A–U+202E, U+2066–U+2069) and the marks U+200E/U+200F/U+061C
  are removed, so the text cannot reorder what follows it;
* a field longer than :data:`MAX_FIELD_CHARS` is cut there with "…" — the same
  cut in the HTML and the PDF, which wraps long fields instead of clipping them;
* TeX is never interpreted: the certificate's matplotlib style sets
  ``text.parse_math = False`` and ``text.usetex = False`` (``$\\foo$`` prints as typed);
  HTML escaping is done where the page is built (``html.escape``).

:func:`fit_header` shortens the laboratory name in the PDF page header so that it
never runs into the certificate number on the right.
"""

from __future__ import annotations

import unicodedata

#: Longest user-supplied field shown, characters.
MAX_FIELD_CHARS: int = 2000
_BIDI = {0x202A, 0x202B, 0x202C, 0x202D, 0x202E, 0x2066, 0x2067, 0x2068, 0x2069,
         0x200E, 0x200F, 0x061C}


def clean_text(text, limit: int = MAX_FIELD_CHARS) -> str:
    """``text`` without control or bidi-override characters, at most ``limit`` characters.

    >>> clean_text("ACME\\u202eLAB\\x07 $\\\\frac{a}{b}$")
    'ACMELAB  $\\\\frac{a}{b}$'
    >>> len(clean_text("x" * 5000)), clean_text("x" * 5000)[-1]
    (2000, '…')
    """
    s = str(text)
    out = []
    for ch in s:
        o = ord(ch)
        if o in _BIDI:
            continue
        if unicodedata.category(ch) == "Cc":
            out.append(" ")
            continue
        out.append(ch)
    s = "".join(out)
    if len(s) > limit:
        s = s[:limit - 1] + "…"
    return s


#: The keys whose text keeps its line breaks on a certificate (each line cleaned): an
#: amendment's reason and the laboratory's and customer's addresses, printed as written.
KEEP_LINES = frozenset({"amendment_reason", "address"})


def clean_lines(text, limit: int = MAX_FIELD_CHARS) -> str:
    r""":func:`clean_text` of each line of ``text``, its line breaks (LF) kept; at most
    ``limit`` characters in all.

    >>> clean_lines("address corrected\r\nserial\x07 confirmed")
    'address corrected\nserial  confirmed'
    """
    lines = str(text).replace("\r\n", "\n").replace("\r", "\n").split("\n")
    out = "\n".join(clean_text(ln, limit) for ln in lines)
    return out if len(out) <= limit else out[:limit - 1] + "…"


def clean_tree(x):
    """:func:`clean_text` applied to every string (keys too) of nested dicts and lists; the
    text of a key in :data:`KEEP_LINES` keeps its line breaks (:func:`clean_lines`)."""
    if isinstance(x, dict):
        return {clean_text(k, 200) if isinstance(k, str) else k:
                clean_lines(v) if k in KEEP_LINES and isinstance(v, str) else clean_tree(v)
                for k, v in x.items()}
    if isinstance(x, list):
        return [clean_tree(v) for v in x]
    if isinstance(x, tuple):
        return tuple(clean_tree(v) for v in x)
    if isinstance(x, str):
        return clean_text(x)
    return x


def _width(s: str) -> int:
    return sum(2 if unicodedata.east_asian_width(ch) in "WF" else 1 for ch in s)


def fit_header(left: str, right: str, columns: int) -> str:
    """``left`` shortened (with "…") so that ``left``, a gap and ``right`` fit ``columns``.

    Widths count East-Asian wide characters as two columns.

    >>> fit_header("A very long laboratory name indeed", "Certificate No.: X-1", 40)
    'A very long lab…'
    >>> fit_header("Short lab", "No.: 1", 40)
    'Short lab'
    """
    room = max(columns - _width(right) - 4, 8)
    if _width(left) <= room:
        return left
    out, w = "", 0
    for ch in left:
        cw = _width(ch)
        if w + cw > room - 1:
            break
        out += ch
        w += cw
    return out.rstrip() + "…"
