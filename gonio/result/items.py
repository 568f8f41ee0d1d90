"""A specification's items computed one by one: their order (:func:`item_order`), the
definition of one item (:class:`ItemDef`) and the one item loop (:func:`run_items`) that
the kit's ``gonio.kit.calibrate_items`` and every built-in per-item specification run, each
item inside :func:`gonio.result.gum.monte_carlo_validation`, none dropped.
"""

from __future__ import annotations

from dataclasses import dataclass
from graphlib import CycleError, TopologicalSorter
from typing import Callable

from gonio.errors import GonioError
from gonio.result.gum import monte_carlo_validation
from gonio.result.model import Item, not_measured
from gonio.result.statement import item_statement


def item_order(keys, needs) -> list[str]:
    """The items ``keys`` (in the specification's order) ordered so that each comes after the
    items it needs (``needs``: {key: keys it needs}, e.g. a scale factor before the items
    that divide by it): :class:`graphlib.TopologicalSorter`, ties kept in the declared
    order, so that the order is written down, never implied. A cycle or a need that is no
    item is a GonioError.

    >>> item_order(["bias", "scale_factor", "noise"], {"bias": ["scale_factor"]})
    ['scale_factor', 'noise', 'bias']
    """
    keys = list(keys)
    unknown = sorted({n for k in keys for n in needs.get(k, ()) if n not in keys})
    if unknown:
        raise GonioError(f"an item needs {', '.join(unknown)}, which is no item")
    ts = TopologicalSorter({k: tuple(needs.get(k, ())) for k in keys})
    try:
        ts.prepare()
    except CycleError as exc:
        raise GonioError(f"the items' needs form a cycle: {' -> '.join(exc.args[1])}") from None
    out: list[str] = []
    while ts.is_active():
        ready = sorted(ts.get_ready(), key=keys.index)
        out += ready
        ts.done(*ready)
    return out


@dataclass(frozen=True)
class ItemDef:
    """One item of a specification (the kit's ``gonio.kit.ItemDef``).

    Attributes
    ----------
    key, title, clause, unit : str
        As the :class:`~gonio.kit.Item` it computes states them (the title, clause and unit
        are those of the "not measured" item when it cannot be computed).
    compute : callable
        ``compute(*args, **needed)`` → :class:`~gonio.kit.Item`: ``args`` are those given
        to :func:`gonio.kit.calibrate_items` (the readings, a fit, …), ``needed`` the items
        it needs, by key.
    needs : tuple of str
        The keys of the items it needs (computed first; one not measured makes this one not
        measured, with the reason).
    nonnegative : bool
        A quantity that cannot be negative (a noise level, a time): stated with an upper
        bound where U exceeds the value (:func:`gonio.kit.state`).
    """

    key: str
    title: str
    clause: str
    compute: Callable[..., Item]
    needs: tuple[str, ...] = ()
    unit: str = ""
    nonnegative: bool = False


def run_items(defs, compute, *, monte_carlo_trials: int = 0, monte_carlo_seed: int = 0,
              needs_measured: bool = True) -> dict[str, Item]:
    """The one item loop (the kit's :func:`gonio.kit.calibrate_items` and the built-in
    per-item specifications' own): every :class:`ItemDef` of ``defs`` computed by
    ``compute(item_def, done)`` (``done``: the items computed so far, by key), each after
    the items it needs (:func:`item_order`), each inside
    :func:`~gonio.result.gum.monte_carlo_validation` with ``monte_carlo_trials`` draws. An
    item whose computation refuses the data (a :class:`GonioError`), or which the statement
    rule cannot state (:func:`stateable`), is reported not measured with the reason; with
    ``needs_measured`` so is an item one of whose needs is not measured (without it the item
    is computed and says itself what it lacks); any other exception is a bug and propagates.
    Returned in the order of ``defs``."""
    defs = {d.key: d for d in defs}
    done: dict[str, Item] = {}
    for key in item_order(defs, {k: d.needs for k, d in defs.items()}):
        d = defs[key]
        missing = [n for n in d.needs if not done[n].measured] if needs_measured else []
        if missing:
            done[key] = not_measured(key, d.title, d.clause, d.unit,
                                     f"needs {', '.join(missing)}, not measured")
            continue
        try:
            with monte_carlo_validation(monte_carlo_trials, monte_carlo_seed):
                item = compute(d, done)
        except GonioError as exc:
            item = not_measured(key, d.title, d.clause, d.unit,
                                f"the data were refused: {exc.message}")
        if not isinstance(item, Item) or item.key != key:
            raise TypeError(f"item {key!r}: compute returned {item!r}, not Item {key!r}")
        done[key] = stateable(item, nonnegative=d.nonnegative)
    return {k: done[k] for k in defs}


def stateable(item: Item, *, nonnegative: bool = False) -> Item:
    """``item`` as the item loop keeps it: marked non-negative where declared, and reported
    not measured, with the refusal as its reason, where the statement rule can state no
    interval for it (a non-negative quantity with value + U ≤ 0)."""
    item.nonnegative = item.nonnegative or nonnegative
    if not item.measured:
        return item
    try:
        item_statement(item, nonnegative=item.nonnegative)
    except GonioError as exc:
        out = not_measured(item.key, item.title, item.clause, item.unit,
                           f"no statement possible: {exc.message}")
        out.nonnegative = item.nonnegative
        return out
    return item
