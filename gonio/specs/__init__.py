"""Calibration specifications as plug-ins.

Each specification is a package ``gonio/specs/<name>/`` exposing ``SPEC``, a
:class:`Specification`; :func:`available` finds them by scanning this package, so
adding a specification never edits the others. :func:`get` looks one up by key.
"""

from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass
from typing import Callable

from gonio.errors import GonioError


@dataclass(frozen=True)
class Specification:
    key: str               # "ogam-draft", "jjf1535-2015", "iec62047-20"  (the --spec value)
    title_en: str
    title_zh: str
    clause_doc: str        # docs/<file>.md with the clause-by-clause reading
    default_protocol: str  # name of protocols/<name>.toml
    default_bench: str     # name of protocols/benches/<name>.toml
    calibrate: Callable    # (readings, protocol, **options) -> results with .to_json() -> dict
    budget: Callable | None = None   # () -> the standard's own annex budget, reproduced


def available() -> dict[str, Specification]:
    """Every specification package's ``SPEC``, by key (sorted)."""
    import gonio.specs as pkg

    found: dict[str, Specification] = {}
    for info in sorted(pkgutil.iter_modules(pkg.__path__), key=lambda m: m.name):
        if not info.ispkg:
            continue
        mod = importlib.import_module(f"gonio.specs.{info.name}")
        spec = getattr(mod, "SPEC", None)
        if isinstance(spec, Specification):
            found[spec.key] = spec
    return dict(sorted(found.items()))


def get(key: str) -> Specification:
    """The specification with ``key``; GonioError listing the available keys otherwise."""
    specs = available()
    if key not in specs:
        raise GonioError(f"unknown specification {key!r} (available: {', '.join(specs)})",
                         key="--spec")
    return specs[key]
