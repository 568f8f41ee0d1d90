"""Progress on a terminal, silence otherwise.

Long runs (validation studies, large streams) call :func:`progress`; it writes a
self-overwriting line to stderr only when stderr is a terminal, so logs and CI
output stay clean.
"""

from __future__ import annotations

import sys
from typing import Iterable, Iterator, TypeVar

T = TypeVar("T")


def is_terminal(stream=None) -> bool:
    """True when ``stream`` (default stderr) is an interactive terminal."""
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def progress(items: Iterable[T], total: int | None = None, label: str = "",
             stream=None) -> Iterator[T]:
    """Yield from ``items``, showing ``label k/total`` on a terminal only.

    >>> list(progress([1, 2, 3], label="x"))   # not a terminal under doctest
    [1, 2, 3]
    """
    stream = sys.stderr if stream is None else stream
    show = is_terminal(stream)
    if total is None and hasattr(items, "__len__"):
        total = len(items)  # type: ignore[arg-type]
    k = 0
    for k, item in enumerate(items, 1):
        if show:
            stream.write(f"\r{label} {k}/{total if total is not None else '?'}")
            stream.flush()
        yield item
    if show and k:
        stream.write("\n")
        stream.flush()


def status(message: str, stream=None) -> None:
    """Show ``message`` as a self-overwriting status line on a terminal; nothing otherwise.

    An empty message ends the line (clears it).

    >>> status("simulating")          # not a terminal under doctest: prints nothing
    """
    stream = sys.stderr if stream is None else stream
    if not is_terminal(stream):
        return
    if message:
        stream.write("\r\033[K" + message)
    else:
        stream.write("\r\033[K")
    stream.flush()
