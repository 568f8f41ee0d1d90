"""Plain JSON values for results files: one conversion used by every output.

JSON has no NaN or infinity and no numpy types; :func:`json_safe` turns a
structure of dicts, lists, tuples, numpy arrays and scalars into plain Python,
with a non-finite number written as ``null`` (``docs/formats.md#results-file``).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["json_safe"]


def json_safe(x):
    """Plain JSON types all the way down: numpy scalars to Python, NaN/±inf to ``None``.

    >>> json_safe({"a": [1.0, float("nan")], "b": np.float64(2.5), "c": np.int64(3),
    ...            "d": np.array([True, False]), 4: float("-inf")})
    {'a': [1.0, None], 'b': 2.5, 'c': 3, 'd': [True, False], '4': None}
    """
    if isinstance(x, dict):
        return {str(k): json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_safe(v) for v in x]
    if isinstance(x, np.ndarray):
        return [json_safe(v) for v in x.tolist()]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        v = float(x)
        return v if math.isfinite(v) else None
    return x
