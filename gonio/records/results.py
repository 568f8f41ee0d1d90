"""One adapter from a ``results.json`` to the records' items: the only place that knows the
shapes results.json has had, so the rest of the records never cares.

Shapes read:

* the unified result (``{"version": …, "items": [{key, title, clause, value, unit, measured,
  U, k, …}]}``);
* the per-item specifications' (rate gyros, triads): ``{"items": {key: {value, unit, clause,
  title, measured, uncertainty: {U, k, …}}}}``;
* the optical draft's: one top-level object per item (``{"scale_factor": {"item", "value",
  "unit", "clause", "measured", "uncertainty": {"U", "k"}}, …}``).

>>> items = result_items({"items": [{"key": "K", "title": "scale factor", "clause": "7.1",
...     "value": 2.0, "unit": "counts/deg", "measured": True, "U": 0.1, "k": 2.0}]})
>>> [(i.key, i.value, i.U) for i in items]
[('K', 2.0, 0.1)]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gonio.errors import GonioError


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


def _limits(d: dict):
    c = d.get("conformity")
    if not isinstance(c, dict):
        return None
    lim = c.get("limits") if isinstance(c.get("limits"), dict) else c
    lo, hi = _num(lim.get("lower")), _num(lim.get("upper"))
    return None if lo is None and hi is None else (lo, hi)


def _decision(d: dict) -> tuple[str | None, str | None]:
    c = d.get("conformity")
    if not isinstance(c, dict):
        return None, None
    return (None if c.get("outcome") is None else str(c["outcome"]),
            None if c.get("rule") is None else str(c["rule"]))


def _item(key: str, d: dict, unc: dict | None) -> Item:
    unc = unc if isinstance(unc, dict) else {}
    outcome, rule = _decision(d)
    return Item(key=str(key), title=str(d.get("title") or d.get("item") or key),
                clause=str(d.get("clause") or ""), unit=str(d.get("unit") or ""),
                measured=bool(d.get("measured", d.get("value") is not None)),
                value=_num(d.get("value")), U=_num(d.get("U", unc.get("U"))),
                k=_num(d.get("k", unc.get("k"))), limits=_limits(d), outcome=outcome,
                rule=rule)


def result_items(results: dict) -> list[Item]:
    """The items of a results.json (any shape gonio has written), in its order."""
    if not isinstance(results, dict):
        raise GonioError("results.json is not a JSON object", key="results")
    items = results.get("items")
    out = []
    if isinstance(items, list):
        out = [_item(d.get("key", f"item{i}"), d, d.get("uncertainty"))
               for i, d in enumerate(items) if isinstance(d, dict)]
    elif isinstance(items, dict):
        out = [_item(k, d, d.get("uncertainty")) for k, d in items.items()
               if isinstance(d, dict)]
    if items is not None:
        if not out:                      # an empty or damaged list of items: nothing to record
            raise GonioError("results.json holds no items", key="items")
        return out
    for k, d in results.items():
        if isinstance(d, dict) and "value" in d and "unit" in d and "clause" in d:
            out.append(_item(k, d, d.get("uncertainty")))
    if not out:
        raise GonioError("results.json holds no items", key="results")
    return out
