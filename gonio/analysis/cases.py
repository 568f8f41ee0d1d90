"""The ``gonio validate --cases`` option every specification with study cases shares
(``Coverage.cases``): one help text, in a module that imports nothing, so that a
specification's argument hook may add it while the command line's parser is built without
numpy (tests/test_cli_startup.py)."""

from __future__ import annotations

__all__ = ["CASES_HELP", "add_cases_option"]

#: The help of ``--cases``: it names no specification (each lists its own cases, which
#: ``gonio validate`` states when it refuses an unknown one).
CASES_HELP = ("comma-separated study cases of --spec, or 'all' (an unknown case is refused "
              "naming the known ones of --spec; each specification's cases and what each "
              "draws: docs/validation-optical.md, docs/validation-rate.md)")


def add_cases_option(group) -> None:
    """Add ``--cases`` (:data:`CASES_HELP`) to ``group``, an argparse argument group of
    ``gonio validate``."""
    group.add_argument("--cases", default=None, help=CASES_HELP)
