"""``gonio simulate``: run a specification's protocol on its virtual bench → the readings a
laboratory would record and truth.json (:func:`gonio.pipeline.dispatch.simulate`).

The options every specification takes are here; a specification adds its own through its
``arguments["simulate"]`` hook (:mod:`gonio.cli.spec_options`), and an option of another
specification is refused naming it (exit 2)."""

from __future__ import annotations

from gonio.cli.checks import seed
from gonio.cli.spec_options import given, inputs as spec_inputs, no_spec_options, refuse
from gonio.specs import DEFAULT_KEY


def register(sub) -> None:
    p = sub.add_parser("simulate", help="run a protocol on the virtual bench",
                       description="Execute a specification's protocol on its virtual bench "
                                   "and write the readings file a laboratory would record "
                                   "(readings.csv) and truth.json.")
    p.add_argument("--spec", default=DEFAULT_KEY,
                   help=f"specification key (gonio.specs.available(); default {DEFAULT_KEY})")
    p.add_argument("--protocol", default=None,
                   help="protocol file or built-in name (default: the specification's)")
    p.add_argument("--bench", default=None,
                   help="bench file or built-in name (default: the specification's)")
    p.add_argument("--seed", type=seed, default=0, help="random seed (same seed → same bytes)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--force", action="store_true",
                   help="replace an --out folder that holds a readings or stream file")
    p.set_defaults(func=run)
    no_spec_options(p)


def run(args) -> int:
    from gonio.atomic import check_output_dir
    from gonio.pipeline.dispatch import simulate
    from gonio.specs import get

    opts = refuse(get(args.spec), "simulate", given(args), args)     # named as typed
    inputs = [args.protocol, args.bench] + spec_inputs(args)
    check_output_dir(args.out, inputs=inputs, force=args.force)
    paths = simulate(args.spec, args.out, bench=args.bench, protocol=args.protocol,
                     seed=args.seed, inputs=inputs, force=args.force, **opts)
    for p in paths.values():
        print(p)
    return 0
