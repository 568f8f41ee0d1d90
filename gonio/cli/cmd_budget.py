"""``gonio budget``: the draft's Annex A uncertainty budget (A.2–A.7).

Prints the budget table with the exact component values beside the annex's A.5
rounded ones, u_c, U = k·u_c and the stated (two-digit) values; optionally a
JCGM 101 Monte Carlo check. A thin layer over :func:`gonio.specs.ogam_draft.budget.annex_a_budget`.
"""

from __future__ import annotations

import json

from gonio.specs.ogam_draft.budget import annex_a_budget
from gonio.cli.checks import LARGE, json_safe
from gonio.units import ARCSEC_PER_DEG
from gonio.errors import GonioError
from gonio.cli.checks import float_range, int_range, seed

_OPTIONS = {"table_mpe_arcsec": "--table-mpe-arcsec", "tilt_deg": "--tilt-deg",
            "zero_stability_dph": "--zero-stability-dph", "duration_min": "--duration-min",
            "repeatability_arcsec": "--repeatability-arcsec", "k": "--k",
            "monte_carlo_trials": "--monte-carlo"}


def register(subparsers) -> None:
    """Add the ``budget`` sub-command."""
    p = subparsers.add_parser(
        "budget", help="Annex A uncertainty budget of the angle-position deviation",
        description="The draft's Annex A budget: u(P), u(phi_e), u(B_E), u(r), u_c and U = k u_c; "
                    "exact values beside the annex's rounded ones; optional JCGM 101 Monte Carlo.")
    p.add_argument("--table-mpe-arcsec", type=float_range(0, ARCSEC_PER_DEG), default=0.1, metavar="A",
                   help="standard table MPE in arc-seconds (A.4.1; default 0.1)")
    p.add_argument("--tilt-deg", type=float_range(0, 45), default=0.1, metavar="PSI",
                   help="sensing-plane tilt in degrees (A.4.2; default 0.1)")
    p.add_argument("--zero-stability-dph", type=float_range(0, LARGE), default=0.005, metavar="B",
                   help="zero stability in °/h (A.4.3; default 0.005)")
    p.add_argument("--duration-min", type=float_range(0, LARGE), default=0.5, metavar="T",
                   help="time from start to reading in minutes (A.4.3; default 0.5)")
    p.add_argument("--repeatability-arcsec", type=float_range(0, ARCSEC_PER_DEG), default=0.096,
                   metavar="S",
                   help="repeatability u(r) in arc-seconds (A.4.4; default 0.096)")
    p.add_argument("--k", type=float_range(0, 10, lo_open=True), default=2.0,
                   help="coverage factor (A.7; default 2)")
    p.add_argument("--monte-carlo", type=int_range(0), default=0, metavar="N",
                   help="JCGM 101 Monte Carlo trials (0: none)")
    p.add_argument("--seed", type=seed, default=0, help="seed of the Monte Carlo generator")
    p.add_argument("--spec", default="ogam-draft",
                   help="specification whose annex budget to reproduce (ogam-draft, "
                        "jjf1535-2015)")
    fmt = p.add_mutually_exclusive_group()
    fmt.add_argument("--json", action="store_true", help="print the result as JSON")
    fmt.add_argument("--format", choices=("text", "markdown", "html"), default="text",
                     help="table format when not --json")
    p.set_defaults(func=run)


def run(args) -> int:
    """Compute and print the Annex A budget."""
    from gonio.limits import check
    check("GONIO_MAX_MONTE_CARLO", args.monte_carlo, "--monte-carlo", unit="trials")
    if args.spec != "ogam-draft":
        from gonio.pipeline.rate import budget

        b = budget(args.spec)
        print(json.dumps(json_safe(b.to_dict()), indent=2, ensure_ascii=False, allow_nan=False)
              if args.json else b.to_text(),
              end="\n" if args.json else "")
        return 0
    try:
        b = annex_a_budget(table_mpe_arcsec=args.table_mpe_arcsec, tilt_deg=args.tilt_deg,
                           zero_stability_dph=args.zero_stability_dph,
                           duration_min=args.duration_min,
                           repeatability_arcsec=args.repeatability_arcsec, k=args.k,
                           monte_carlo_trials=args.monte_carlo, seed=args.seed)
    except GonioError as exc:
        opt = _OPTIONS.get(exc.key or "")
        if opt is None:
            raise
        raise GonioError(f"{opt}: {exc.message}") from None
    if args.json:
        print(json.dumps(json_safe(b.to_dict()), indent=2, allow_nan=False))
    elif args.format == "markdown":
        print(b.to_markdown())
    elif args.format == "html":
        print(b.to_html())
    else:
        print("Annex A uncertainty budget (arc-seconds); u_annex_A5 = the annex's rounded value")
        print(b.to_text())
    return 0
