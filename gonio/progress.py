"""Progress on a terminal, silence otherwise.

Long runs (validation studies, large streams) report how far they are: items
done of the total, the rate, and the estimated time left. The line is written
to stderr (overwriting itself) only when stderr is an interactive terminal, so
logs, pipes and CI output stay clean.

:class:`Progress`   a counter advanced by any amount (``update(n)``)
:func:`progress`    wrap an iterable, one step per item
"""

from __future__ import annotations

import math
import sys
import time
from typing import Iterable, Iterator, TypeVar

T = TypeVar("T")


def is_terminal(stream=None) -> bool:
    """True when ``stream`` (default stderr) is an interactive terminal."""
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def format_duration(seconds: float) -> str:
    """Short human duration: ``42 s``, ``3 min 05 s``, ``2 h 07 min``.

    >>> format_duration(42.4), format_duration(185), format_duration(7625), format_duration(math.inf)
    ('42 s', '3 min 05 s', '2 h 07 min', '?')
    """
    if not math.isfinite(seconds) or seconds < 0:
        return "?"
    m, s = divmod(int(round(seconds)), 60)
    h, m = divmod(m, 60)
    if not (h or m):
        return f"{s} s"
    if not h:
        return f"{m} min {s:02d} s"
    return f"{h} h {m:02d} min"


class Progress:
    """Counter of work done, drawn as ``label done/total unit  rate/s  ETA`` on a terminal.

    ``done`` may start above zero (a resumed run); the rate counts only what this
    run did. Redraws at most every ``min_interval_s``. ``force=True`` draws even when
    the stream is not a terminal (tests).

    >>> import io
    >>> buf = io.StringIO()
    >>> p = Progress(10, label="trials", stream=buf, force=True, clock=iter([0.0, 2.0, 2.0]).__next__)
    >>> p.update(4); p.close()
    >>> buf.getvalue().split("\\r")[-1].strip()
    'trials 4/10  2.00/s  ETA 3 s'
    """

    def __init__(self, total: int | None, *, label: str = "", unit: str = "", done: int = 0,
                 stream=None, force: bool = False, min_interval_s: float = 0.2, clock=None):
        self.total, self.label, self.unit = total, label, unit
        self.stream = sys.stderr if stream is None else stream
        self.show = force or is_terminal(self.stream)
        self.clock = clock or time.monotonic
        self.start_done = self.done = int(done)
        self.t0 = self.clock()
        self.min_interval_s = min_interval_s
        self._last_draw = -math.inf
        self._drawn = False
        self._width = 0

    def rate(self, now: float | None = None) -> float:
        """Items per second done by this run so far."""
        now = self.clock() if now is None else now
        el = now - self.t0
        return (self.done - self.start_done) / el if el > 0 else math.nan

    def text(self, now: float | None = None) -> str:
        """The status line (without the carriage return)."""
        r = self.rate(now)
        tot = "?" if self.total is None else str(self.total)
        unit = f" {self.unit}" if self.unit else ""
        out = f"{self.label} {self.done}/{tot}{unit}".strip()
        if math.isfinite(r) and r > 0:
            out += f"  {r:.2f}/s" if r < 100 else f"  {r:,.0f}/s"
            if self.total is not None:
                out += f"  ETA {format_duration((self.total - self.done) / r)}"
        return out

    def update(self, n: int = 1) -> None:
        """Advance by ``n`` and redraw if due."""
        self.done += int(n)
        if not self.show:
            return
        now = self.clock()
        if now - self._last_draw >= self.min_interval_s or \
                (self.total is not None and self.done >= self.total):
            line = self.text(now)
            self.stream.write("\r" + line + " " * max(0, self._width - len(line)))
            self._width = len(line)
            self.stream.flush()
            self._last_draw = now
            self._drawn = True

    def close(self) -> None:
        """End the line (only if something was drawn)."""
        if self.show and self._drawn:
            self.stream.write("\n")
            self.stream.flush()
            self._drawn = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def progress(items: Iterable[T], total: int | None = None, label: str = "",
             stream=None) -> Iterator[T]:
    """Yield from ``items``, showing ``label k/total  rate  ETA`` on a terminal only.

    >>> list(progress([1, 2, 3], label="x"))   # not a terminal under doctest
    [1, 2, 3]
    """
    if total is None and hasattr(items, "__len__"):
        total = len(items)  # type: ignore[arg-type]
    with Progress(total, label=label, stream=stream) as p:
        for item in items:
            yield item
            p.update(1)


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
