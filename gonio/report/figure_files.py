"""Writing a figure to a file: one format by suffix, the same bytes for the same figure.

Figures are built on :class:`matplotlib.figure.Figure` objects (no pyplot state,
no backend switch: a notebook user's backend is left alone). PNG carries no
software tag, SVG a fixed id salt and no date, PDF no creation date, so a plot
written twice is byte-identical (``docs/architecture.md#determinism``).
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

import gonio.atomic as _atomic

#: Salt of matplotlib's SVG element ids: fixed, so that the same figure gives the same bytes.
SVG_HASHSALT: str = _atomic.SVG_HASHSALT
#: Formats a figure may be written in (by file suffix).
FIGURE_FORMATS: tuple[str, ...] = _atomic.FIGURE_FORMATS


def figure_bytes(fig: Figure, fmt: str) -> bytes:
    """The figure encoded as ``fmt`` (png, svg or pdf), deterministic.

    The one implementation is :func:`gonio.atomic.figure_bytes` (shared with the
    analysis layer's plots, which cannot import this module).

    >>> fig = Figure(figsize=(2, 1)); _ = fig.add_subplot().plot([0, 1])
    >>> figure_bytes(fig, "svg") == figure_bytes(fig, "svg")
    True
    """
    return _atomic.figure_bytes(fig, fmt)


def save_figure(fig: Figure, path: str | Path) -> Path:
    """Write ``fig`` to ``path`` atomically, in the format its suffix names.

    A suffix that is not png, svg or pdf is a GonioError naming the file; so is a
    place that is not a regular file (folder, FIFO, device, symlink).
    """
    return _atomic.save_figure(fig, path)
