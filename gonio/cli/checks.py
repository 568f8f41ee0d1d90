"""Argument types for the CLI: every number checked where it is typed.

Each function returns an ``argparse`` type callable; a bad value becomes the
parser's one-line usage error (exit 2) naming the option. Limits on work
(``--monte-carlo``, ``--trials``, ``--workers``) are stated in docs/formats.md
("Plausible ranges"); they can be raised with the environment variables named
in :mod:`gonio.limits`.
"""

from __future__ import annotations

import argparse
import math
import re


#: Upper bound of physical magnitudes typed on the command line (scale factors, lengths, times,
#: accelerations): beyond any quantity of these kinds in SI units (the observable universe is
#: ~1e27 m), yet low enough that products and squares of such numbers stay finite doubles.
#: Lower bounds come from physics (> 0, ≥ 0, absolute zero), or 1/LARGE where a number divides.
LARGE = 1e50

_INT = re.compile(r"^[+-]?[0-9]{1,30}$")
_FLOAT = re.compile(r"^[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]{1,4})?$")


def _show(text: str) -> str:
    text = str(text)
    return repr(text if len(text) <= 40 else text[:40] + "…")


def int_range(lo: int, hi: int | None = None, *, what: str = "an integer"):
    """An ASCII integer in ``[lo, hi]`` (``hi`` None: no upper bound)."""
    def conv(text: str) -> int:
        if not _INT.match(text.strip()):
            raise argparse.ArgumentTypeError(f"expected {what}, got {_show(text)}")
        v = int(text)
        if v < lo or (hi is not None and v > hi):
            rng = f"≥ {lo}" if hi is None else f"in [{lo}, {hi}]"
            raise argparse.ArgumentTypeError(f"expected {what} {rng}, got {_show(text)}")
        return v
    return conv


def float_range(lo: float = -math.inf, hi: float = math.inf, *, lo_open: bool = False,
                hi_open: bool = False, what: str = "a number"):
    """A finite ASCII decimal number in the range (open ends when asked)."""
    def conv(text: str) -> float:
        if not _FLOAT.match(text.strip()):
            raise argparse.ArgumentTypeError(f"expected {what}, got {_show(text)}")
        v = float(text)
        if not math.isfinite(v) or v < lo or v > hi or (lo_open and v == lo) \
                or (hi_open and v == hi):
            left = "(" if lo_open else "["
            right = ")" if hi_open else "]"
            raise argparse.ArgumentTypeError(
                f"expected {what} in {left}{lo:g}, {hi:g}{right}, got {_show(text)}")
        return v
    return conv


def positive_magnitude(text: str) -> float:
    """A physical magnitude that divides or scales data: in [1/LARGE, LARGE] (representable)."""
    return float_range(1.0 / LARGE, LARGE, what="a positive number")(text)


def json_safe(obj):
    """:func:`gonio.formats.jsonsafe.json_safe` (for the sub-commands), imported on first use:
    building the parser imports this module, and it must not import numpy."""
    from gonio.formats.jsonsafe import json_safe as convert

    return convert(obj)


def seed(text: str) -> int:
    """A random seed: an integer in [0, 2**63 - 1]."""
    return int_range(0, 2**63 - 1, what="a seed")(text)
