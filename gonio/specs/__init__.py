"""Calibration specifications as plug-ins: one package per specification.

Each subpackage ``gonio.specs.<name>`` exposes ``SPEC``, a
:class:`Specification`: its key (the ``--spec`` value), titles, the document in
``docs/`` that reads it clause by clause, its default protocol and bench, the
function that computes its items from readings, and the function that
reproduces its own uncertainty annex. :func:`available` finds them by scanning
this package, so adding a specification never edits another one.

>>> [k for k in available() if k == "ogam-draft"]
['ogam-draft']
>>> get("ogam-draft").default_protocol
'ogam-draft'
"""

from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass
from typing import Any, Callable

from gonio.errors import GonioError

__all__ = ["Specification", "available", "get"]


@dataclass(frozen=True)
class Specification:
    """What gonio needs to know of one calibration specification.

    Attributes
    ----------
    key : str
        The ``--spec`` value and the ``# spec:`` metadata value (``ogam-draft``).
    title_en, title_zh : str
        The specification's title.
    clause_doc : str
        The repository document with the clause-by-clause reading taken.
    default_protocol, default_bench : str
        Names of ``protocols/<name>.toml`` and ``protocols/benches/<name>.toml``.
    calibrate : callable
        Readings (a :class:`~gonio.formats.readings.Readings` or DataFrame) → the
        items' results dataclass (with ``to_json()`` or ``to_dict()``).
    budget : callable or None
        () → the specification's own uncertainty annex, reproduced.
    """

    key: str
    title_en: str
    title_zh: str
    clause_doc: str
    default_protocol: str
    default_bench: str
    calibrate: Callable[..., Any]
    budget: Callable[..., Any] | None = None


def available() -> dict[str, Specification]:
    """Every installed specification, by key (scans the subpackages of :mod:`gonio.specs`)."""
    out: dict[str, Specification] = {}
    for mod in pkgutil.iter_modules(__path__):
        if not mod.ispkg:
            continue
        spec = getattr(importlib.import_module(f"{__name__}.{mod.name}"), "SPEC", None)
        if isinstance(spec, Specification):
            out[spec.key] = spec
    return dict(sorted(out.items()))


def get(key: str) -> Specification:
    """The specification with this key; an unknown key is a GonioError listing the known ones."""
    specs = available()
    if key not in specs:
        raise GonioError(f"unknown specification {key!r} (known: {', '.join(specs)})",
                         key="spec")
    return specs[key]
