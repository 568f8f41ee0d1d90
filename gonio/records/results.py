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


# ------------------------------------------------ the stored result as the pages state it


def stored_result(store, results_sha256: str):
    """The stored results.json (the sealed result) as read from its blob."""
    import json

    from gonio.records.blobs import get_bytes

    return json.loads(get_bytes(store.blob_root, results_sha256))


def stated_items(store, results_sha256: str) -> dict:
    """Item key → its statement by the one statement rule
    (:func:`gonio.result.statement.item_statement`), from the stored results.json itself
    (the sealed result), as every certificate states it; an item the rule refuses to state
    is left out (the page then says "not stated")."""
    return statements_of(stored_result(store, results_sha256))


def statements_of(doc) -> dict:
    """:func:`stated_items` of a results.json already read (a dict; anything else: none)."""
    from gonio.errors import GonioError
    from gonio.result.statement import item_statement

    items = doc.get("items") if isinstance(doc, dict) else None
    if isinstance(items, list):
        items = {str(it.get("key")): it for it in items if isinstance(it, dict)}
    if not isinstance(items, dict):        # the optical draft's older shape: one per key
        items = {k: v for k, v in (doc or {}).items()
                 if isinstance(v, dict) and "value" in v and "unit" in v}
    out = {}
    for key, it in items.items():
        if not isinstance(it, dict):
            continue
        if "uncertainty" not in it:          # the unified list's U and k beside the value
            it = dict(it, uncertainty={"U": it.get("U"), "k": it.get("k")})
        try:
            out[key] = item_statement(it)
        except (GonioError, TypeError, ValueError):
            continue
    return out


def stated_intervals(store, results_sha256: str) -> dict:
    """Item key → (low, high) of each item the stored result states by one coverage interval
    (:func:`stated_items`: the statement rule's interval, its rounded ends as numbers), for
    the history figure's bars; read once per stored result (a stored file never changes)."""
    from decimal import Decimal

    from gonio.errors import GonioError

    at = (str(store.blob_root), results_sha256)
    got = _INTERVALS.get(at)
    if got is None:
        try:
            stated = stated_items(store, results_sha256)
        except (GonioError, ValueError, RecursionError):
            stated = {}
        got = _INTERVALS[at] = {
            key: tuple(float(Decimal(x).scaleb(st.exponent)) for x in st.interval)
            for key, st in stated.items() if st.interval is not None}
        while len(_INTERVALS) > 1024:
            _INTERVALS.pop(next(iter(_INTERVALS)))
    return got


_INTERVALS: dict[tuple[str, str], dict] = {}
