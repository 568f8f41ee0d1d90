"""The records' items of a ``results.json``, read through the one reader of the stored result
(:meth:`gonio.result.model.Result.from_json`): a document that reader refuses (another
version, a malformed shape) is refused here too, with its message.

>>> from gonio.result.model import RESULTS_VERSION
>>> items = result_items({"version": RESULTS_VERSION, "spec": "x", "items": {"K": {
...     "title": "scale factor", "clause": "7.1", "value": 2.0, "unit": "counts/deg",
...     "measured": True, "uncertainty": {"u_c": 0.05, "U": 0.1, "k": 2.0}}}})
>>> [(i.key, i.value, i.U) for i in items]
[('K', 2.0, 0.1)]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gonio.errors import GonioError
from gonio.result.model import Result


@dataclass(frozen=True)
class Item:
    """One result item as the records keep it."""

    key: str
    title: str
    clause: str
    unit: str
    measured: bool
    value: float | None
    U: float | None
    k: float | None
    limits: tuple[float | None, float | None] | None = None   # (lower, upper) if stated
    outcome: str | None = None           # the conformity decision, if limits were given
    rule: str | None = None              # its decision rule


def _num(x) -> float | None:
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def _item(it) -> Item:
    """The records' view of a :class:`gonio.result.model.Item`."""
    c = it.conformity
    limits = None
    if c is not None and (_num(c.lower) is not None or _num(c.upper) is not None):
        limits = (_num(c.lower), _num(c.upper))
    return Item(key=str(it.key), title=str(it.title or it.key), clause=str(it.clause or ""),
                unit=str(it.unit or ""), measured=bool(it.measured), value=_num(it.value),
                U=_num(it.U), k=_num(it.k), limits=limits,
                outcome=None if c is None or c.outcome is None else str(c.outcome),
                rule=None if c is None or c.rule is None else str(c.rule))


def result_items(results: dict) -> list[Item]:
    """The items of a results.json, in its order (:meth:`Result.from_json`); a document
    with no items is refused."""
    if not isinstance(results, dict):
        raise GonioError("results.json is not a JSON object", key="results")
    items = [_item(it) for it in Result.from_json(results).items.values()]
    if not items:                        # an empty list of items: nothing to record
        raise GonioError("results.json holds no items", key="items")
    return items
