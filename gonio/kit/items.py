"""The item loop of the kit: a specification's items computed one by one, each after the items
it needs, none dropped.

:class:`ItemDef` declares one item (key, title, clause, unit, the function computing it, the
items it needs first); :func:`calibrate_items` runs them in :func:`~gonio.kit.item_order`'s
order, each inside :func:`~gonio.kit.monte_carlo_validation` (so that every
:func:`~gonio.kit.gum` budget of the item is also propagated by Monte Carlo when the
calibration asks for it), and reports an item whose needs were not measured, or whose
computation refused the data (a :class:`~gonio.errors.GonioError`), as not measured with the
reason. docs/kit.md describes the contract. It is the one item loop of gonio
(:func:`gonio.result.items.run_items`): the built-in specifications run the same one.
"""

from __future__ import annotations

from typing import Any

from gonio.result.model import Item
from gonio.result.items import ItemDef, run_items

__all__ = ["ItemDef", "calibrate_items"]


def calibrate_items(defs, *args: Any, monte_carlo_trials: int = 0,
                    monte_carlo_seed: int = 0) -> dict[str, Item]:
    """Every item of ``defs`` (:class:`ItemDef`, in the specification's order) computed from
    ``args``: each after the items it needs (:func:`~gonio.kit.item_order`), each inside
    :func:`~gonio.kit.monte_carlo_validation` with ``monte_carlo_trials`` draws (0: the GUM
    alone). An item whose needs are not measured, whose ``compute`` raises a
    :class:`GonioError`, or which the statement rule cannot state (a non-negative quantity
    with value + U ≤ 0), is :func:`~gonio.kit.not_measured` with the reason; any other
    exception is a bug and propagates. Returned in the order of ``defs``.

    >>> from gonio.kit import Item
    >>> defs = [ItemDef("b", "B", "2", lambda x, a: Item("b", "B", "2", "1", a.value / x),
    ...                 needs=("a",)),
    ...         ItemDef("a", "A", "1", lambda x: Item("a", "A", "1", "1", 2.0 * x))]
    >>> {k: it.value for k, it in calibrate_items(defs, 4.0).items()}
    {'b': 2.0, 'a': 8.0}
    """
    return run_items(defs, lambda d, done: d.compute(*args, **{n: done[n] for n in d.needs}),
                     monte_carlo_trials=monte_carlo_trials, monte_carlo_seed=monte_carlo_seed)
