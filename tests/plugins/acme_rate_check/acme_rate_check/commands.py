"""ACME RC-1's own ``gonio`` sub-command (``Specification.commands``): ``gonio acme-programme``
prints the rate-table programme of clause 4.1, the settings a technician keys in before
recording; and its own ``gonio simulate --samples`` (``Specification.arguments``). gonio's
command line finds both through the registry; nothing in gonio names them."""

from __future__ import annotations

from gonio.kit import GonioError

from acme_rate_check.items import load_protocol


def add_programme(sub) -> None:
    """Add ``gonio acme-programme`` to the sub-parsers ``sub``."""
    p = sub.add_parser("acme-programme", help="the ACME RC-1 rate-table programme (clause 4.1)",
                       description="Print the table rates, both ways, and the samples to "
                                   "record at each (ACME RC-1 clause 4.1).")
    p.add_argument("--samples", type=int, default=None,
                   help="samples per rate (default: the protocol's)")
    p.set_defaults(func=run_programme)


def run_programme(args) -> int:
    """One line per table setting: the rate (°/s, signed) and the samples to record."""
    protocol = load_protocol({"samples": args.samples} if args.samples is not None else None)
    if protocol["samples"] < 2:
        raise GonioError(f"--samples must be at least 2 (clause 4.1), got {protocol['samples']}")
    for rate in protocol["rates_dps"]:
        for sign in (1, -1):
            print(f"{sign * rate:+g} °/s  {protocol['samples']} samples")
    return 0


def add_simulate_options(group) -> None:
    """ACME RC-1's own ``gonio simulate`` option (``SPEC.arguments["simulate"]``)."""
    group.add_argument("--samples", type=int, default=None,
                       help="samples per rate of the virtual run (default: the protocol's)")
