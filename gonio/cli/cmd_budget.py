"""``gonio budget``: a specification's own uncertainty annex, reproduced
(:func:`gonio.pipeline.dispatch.budget`).

The options every budget may take are here (its Monte Carlo check and its seed, the output
form); the annex's own inputs are options the specification adds through its
``arguments["budget"]`` hook (:mod:`gonio.cli.spec_options`), and an option of another
specification is refused naming it (exit 2).
"""

from __future__ import annotations

import json

from gonio.cli.checks import int_range, json_safe, seed
from gonio.cli.spec_options import flag_of, given as spec_given, no_spec_options, refuse
from gonio.errors import GonioError
from gonio.specs import DEFAULT_KEY

#: Option name of each common budget argument (a GonioError's key names the argument).
_OPTIONS = {"monte_carlo_trials": "--monte-carlo", "seed": "--seed"}


def register(subparsers) -> None:
    """Add the ``budget`` sub-command."""
    p = subparsers.add_parser(
        "budget", help="a specification's own uncertainty annex, reproduced",
        description="A specification's uncertainty annex, reproduced: its budget table, the "
                    "exact values beside the annex's rounded ones where it states them, and "
                    "an optional JCGM 101 Monte Carlo check. The annex's inputs are the "
                    "options its specification adds (defaults: the annex's).")
    p.add_argument("--monte-carlo", type=int_range(0), default=0, metavar="N",
                   help="JCGM 101 Monte Carlo trials (0: none)")
    p.add_argument("--seed", type=seed, default=None,
                   help="seed of the Monte Carlo generator (default 0)")
    p.add_argument("--spec", default=DEFAULT_KEY,
                   help=f"specification whose annex budget to reproduce (default {DEFAULT_KEY})")
    fmt = p.add_mutually_exclusive_group()
    fmt.add_argument("--json", action="store_true", help="print the result as JSON")
    fmt.add_argument("--format", choices=("text", "markdown", "html"), default="text",
                     help="table format when not --json (markdown, html: where the budget "
                          "has them)")
    p.set_defaults(func=run)
    no_spec_options(p)


def run(args) -> int:
    """Compute and print the specification's budget."""
    from gonio.limits import check
    from gonio.pipeline.dispatch import budget
    from gonio.specs import get

    check("GONIO_MAX_MONTE_CARLO", args.monte_carlo, "--monte-carlo", unit="trials")
    given = {**spec_given(args), "seed": args.seed,
             "monte_carlo_trials": args.monte_carlo or None}
    refuse(get(args.spec), "budget", given, args, _OPTIONS)     # named as typed
    try:
        b = budget(args.spec, **given)
    except GonioError as exc:
        opt = _OPTIONS.get(exc.key or "") or flag_of(args, exc.key)
        if opt is None:
            raise
        raise GonioError(f"{opt}: {exc.message}") from None      # the option, not the argument
    if args.json:
        print(json.dumps(json_safe(b.to_dict()), indent=2, ensure_ascii=False, allow_nan=False))
    elif args.format != "text":
        if not hasattr(b, f"to_{args.format}"):
            raise GonioError(f"--format {args.format}: the {args.spec} budget has no "
                             f"{args.format} form", key="--format")
        print(getattr(b, f"to_{args.format}")())
    else:
        if getattr(b, "heading", None):
            print(b.heading)
        print(b.to_text(), end="" if b.to_text().endswith("\n") else "\n")
    return 0
