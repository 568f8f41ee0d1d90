"""The item loop of the kit: a specification's items computed one by one, each after the items
it needs, none dropped.

:class:`ItemDef` declares one item (key, title, clause, unit, the function computing it, the
items it needs first); :func:`calibrate_items` runs them in :func:`gonio.specs.item_order`'s
order, each inside :func:`~gonio.kit.monte_carlo_validation` (so that every
:func:`~gonio.kit.gum` budget of the item is also propagated by Monte Carlo when the
calibration asks for it), and reports an item whose needs were not measured, or whose
computation refused the data (a :class:`~gonio.errors.GonioError`), as not measured with the
reason. docs/kit.md describes the contract.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from gonio.errors import GonioError
from gonio.result.model import Item, not_measured
from gonio.specs import item_order
from gonio.specs._rate_family.rate_records import monte_carlo_validation, stateable

__all__ = ["ItemDef", "calibrate_items"]


@dataclass(frozen=True)
class ItemDef:
    """One item of a specification.

    Attributes
    ----------
    key, title, clause, unit : str
        As the :class:`~gonio.kit.Item` it computes states them (the title, clause and unit
        are those of the "not measured" item when it cannot be computed).
    compute : callable
        ``compute(*args, **needed)`` → :class:`~gonio.kit.Item`: ``args`` are those given
        to :func:`calibrate_items` (the readings, a fit, …), ``needed`` the items it needs,
        by key.
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


def calibrate_items(defs, *args: Any, monte_carlo_trials: int = 0,
                    monte_carlo_seed: int = 0) -> dict[str, Item]:
    """Every item of ``defs`` (:class:`ItemDef`, in the specification's order) computed from
    ``args``: each after the items it needs (:func:`gonio.specs.item_order`), each inside
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
    defs = {d.key: d for d in defs}
    done: dict[str, Item] = {}
    for key in item_order(defs, {k: d.needs for k, d in defs.items()}):
        d = defs[key]
        missing = [n for n in d.needs if not done[n].measured]
        if missing:
            done[key] = not_measured(key, d.title, d.clause, d.unit,
                                     f"needs {', '.join(missing)}, not measured")
            continue
        try:
            with monte_carlo_validation(monte_carlo_trials, monte_carlo_seed):
                item = d.compute(*args, **{n: done[n] for n in d.needs})
        except GonioError as exc:
            item = not_measured(key, d.title, d.clause, d.unit,
                                f"the data were refused: {exc.message}")
        if not isinstance(item, Item) or item.key != key:
            raise TypeError(f"item {key!r}: compute returned {item!r}, not Item {key!r}")
        done[key] = stateable(item, nonnegative=d.nonnegative)   # as the built-ins do
    return {k: done[k] for k in defs}
