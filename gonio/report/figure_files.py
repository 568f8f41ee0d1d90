"""Writing a figure to a file: one format by suffix, the same bytes for the same figure.

Figures are built on :class:`matplotlib.figure.Figure` objects (no pyplot state,
no backend switch: a notebook user's backend is left alone). PNG carries no
software tag, SVG a fixed id salt and no date, PDF no creation date, so a plot
written twice is byte-identical (``docs/architecture.md#determinism``).
"""

from __future__ import annotations

import io
from pathlib import Path

import matplotlib
from matplotlib.figure import Figure

from gonio.atomic import check_output_file, write_bytes
from gonio.errors import GonioError

#: Salt of matplotlib's SVG element ids: fixed, so that the same figure gives the same bytes.
SVG_HASHSALT: str = "gonio"
#: Formats a figure may be written in (by file suffix).
FIGURE_FORMATS: tuple[str, ...] = ("png", "svg", "pdf")

_METADATA = {"png": {"Software": None}, "svg": {"Date": None},
             "pdf": {"CreationDate": None, "ModDate": None, "Producer": None}}


def figure_bytes(fig: Figure, fmt: str) -> bytes:
    """The figure encoded as ``fmt`` (png, svg or pdf), deterministic.

    >>> fig = Figure(figsize=(2, 1)); _ = fig.add_subplot().plot([0, 1])
    >>> figure_bytes(fig, "svg") == figure_bytes(fig, "svg")
    True
    """
    fmt = fmt.lower()
    if fmt not in FIGURE_FORMATS:
        raise GonioError(f"unknown figure format {fmt!r} (known: {', '.join(FIGURE_FORMATS)})")
    buf = io.BytesIO()
    with matplotlib.rc_context({"svg.hashsalt": SVG_HASHSALT, "text.usetex": False}):
        fig.savefig(buf, format=fmt, metadata=_METADATA[fmt])
    return buf.getvalue()


def save_figure(fig: Figure, path: str | Path) -> Path:
    """Write ``fig`` to ``path`` atomically, in the format its suffix names.

    A suffix that is not png, svg or pdf is a GonioError naming the file; so is a place
    that is not a regular file (folder, FIFO, device, symlink) — refused, never replaced.
    """
    path = check_output_file(path, what="figure file")   # no folder, FIFO, device, link
    fmt = path.suffix.lstrip(".").lower()
    if fmt not in FIGURE_FORMATS:
        raise GonioError(f"cannot write a figure of type {path.suffix or '(none)'!r}: use "
                         f"{', '.join('.' + f for f in FIGURE_FORMATS)}", file=path)
    return write_bytes(path, figure_bytes(fig, fmt))
