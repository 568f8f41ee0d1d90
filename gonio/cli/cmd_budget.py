"""``gonio budget``: a specification's own uncertainty annex, reproduced
(:func:`gonio.pipeline.dispatch.budget`).

For the default specification, the Annex A budget of the angle-position deviation: the
budget table with the exact component values beside the annex's A.5 rounded ones, u_c,
U = k·u_c and the stated (two-digit) values; optionally a JCGM 101 Monte Carlo check.
"""

from __future__ import annotations

import json

from gonio.cli.checks import float_range, int_range, json_safe, seed
from gonio.errors import GonioError
from gonio.specs import DEFAULT_KEY
from gonio.units import ARCSEC_PER_DEG

#: Option name of each budget argument (a GonioError's key names the argument).
_OPTIONS = {"table_mpe_arcsec": "--table-mpe-arcsec", "tilt_deg": "--tilt-deg",
            "zero_stability_dph": "--zero-stability-dph", "duration_min": "--duration-min",
            "repeatability_arcsec": "--repeatability-arcsec", "k": "--k",
            "monte_carlo_trials": "--monte-carlo", "seed": "--seed"}


def register(subparsers) -> None:
    """Add the ``budget`` sub-command."""
    p = subparsers.add_parser(
        "budget", help="a specification's own uncertainty annex, reproduced",
        description="A specification's uncertainty annex, reproduced. The default "
                    "specification's Annex A: u(P), u(phi_e), u(B_E), u(r), u_c and U = k u_c; "
                    "exact values beside the annex's rounded ones; optional JCGM 101 Monte "
                    "Carlo. The options below are that annex's inputs (defaults: the annex's).")
    p.add_argument("--table-mpe-arcsec", type=float_range(0, ARCSEC_PER_DEG), default=None,
                   metavar="A", help="standard table MPE in arc-seconds (A.4.1; default 0.1)")
    p.add_argument("--tilt-deg", type=float_range(0, 45), default=None, metavar="PSI",
                   help="sensing-plane tilt in degrees (A.4.2; default 0.1)")
    p.add_argument("--zero-stability-dph", type=float_range(0, 1e4), default=None, metavar="B",
                   help="zero stability in °/h (A.4.3; default 0.005)")
    p.add_argument("--duration-min", type=float_range(0, 1e4), default=None, metavar="T",
                   help="time from start to reading in minutes (A.4.3; default 0.5)")
    p.add_argument("--repeatability-arcsec", type=float_range(0, ARCSEC_PER_DEG), default=None,
                   metavar="S", help="repeatability u(r) in arc-seconds (A.4.4; default 0.096)")
    p.add_argument("--k", type=float_range(0, 10, lo_open=True), default=None,
                   help="coverage factor (A.7; default 2)")
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


def run(args) -> int:
    """Compute and print the specification's budget."""
    from gonio.limits import check
    from gonio.pipeline.dispatch import budget

    check("GONIO_MAX_MONTE_CARLO", args.monte_carlo, "--monte-carlo", unit="trials")
    given = {k: getattr(args, k) for k in _OPTIONS if k != "monte_carlo_trials"}
    given["monte_carlo_trials"] = args.monte_carlo or None
    try:
        b = budget(args.spec, **given)
    except GonioError as exc:
        opt = _OPTIONS.get(exc.key or "")
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
