"""``gonio bench serve``: a virtual bench served as instruments on 127.0.0.1: a rate bench by
:func:`gonio.instruments.served_rate.serve_rate_bench`, any other by the ``serve`` hook of
the specification ``--spec`` names (by default :data:`gonio.specs.DEFAULT_KEY`'s: the
goniometer's table and acquisition module). It serves until SIGINT or SIGTERM, which stop it
at any point (exit 130 / 143; :data:`gonio.cli.STOPPED_BY_SIGNAL`)."""

from __future__ import annotations

import time

from gonio.cli.checks import seed
from gonio.cli.spec_options import given, no_spec_options, refuse


def register(sub) -> None:
    p = sub.add_parser("bench", help="the virtual bench as instruments (bench serve)",
                       description="The virtual bench as instruments a laboratory's software "
                                   "drives through VISA.")
    bsub = p.add_subparsers(dest="bench_command", metavar="ACTION")
    bsub.required = True
    s = bsub.add_parser("serve", help="serve the simulated table and acquisition module",
                        description="Serve a bench's rotary table and the goniometer's "
                                    "acquisition module on 127.0.0.1 over line-terminated SCPI "
                                    "sockets (the command sets of docs/instruments.md), with "
                                    "simulated time --speed times faster than real time, until "
                                    "interrupted. Prints their VISA resource strings. A rate "
                                    "bench (a [gyro] section, e.g. mems-adxrs610) serves its rate "
                                    "table, gyro output reader, chamber and supply instead.")
    s.add_argument("--bench", default=None,
                   help="bench file or built-in name (default: the specification's)")
    s.add_argument("--spec", default=None,
                   help="the specification whose virtual bench is served (gonio.specs."
                        "available(); default: gonio.specs.DEFAULT_KEY); a rate bench is "
                        "served the same for every rate specification")
    s.add_argument("--table-port", type=int, required=True,
                   help="TCP port of the table (0: a free one, printed)")
    s.add_argument("--gyro-port", type=int, required=True,
                   help="TCP port of the acquisition module (0: a free one, printed)")
    s.add_argument("--chamber-port", type=int, default=0,
                   help="a rate bench: TCP port of the temperature chamber (0: a free one)")
    s.add_argument("--supply-port", type=int, default=0,
                   help="a rate bench: TCP port of the gyro's power supply (0: a free one)")
    s.add_argument("--speed", type=float, default=1.0,
                   help="simulated seconds per real second (default 1)")
    s.add_argument("--seed", type=seed, default=0, help="random seed (default 0)")
    s.add_argument("--fault", action="append", default=[],
                   help="inject a fault for testing: table-error:N (the N-th move fails with an "
                        "axis fault; a rate bench: its N-th ROT or OSC), gyro-drop:N (the module "
                        "drops its link at its N-th READ? or FETC?; a rate bench: ACQ:DATA?), "
                        "hold:N (the bench's clock stops once its N-th reading is answered, "
                        "until the next connection to the module or reader; prints 'held: N')")
    s.set_defaults(func=run)
    no_spec_options(s)          # the specifications' own: arguments["bench serve"]


def is_rate_bench(name: str) -> bool:
    """Whether a bench file describes a rate gyro (a ``[gyro]`` section)."""
    from gonio.formats.toml import read_toml
    from gonio.resources import resolve

    return "gyro" in read_toml(resolve(name, kind="bench"))


def _serve_rate(args, faults):
    from gonio.bench.rate_gyro import load_rate_bench
    from gonio.instruments.served_rate import serve_rate_bench

    return serve_rate_bench(load_rate_bench(args.bench),
                            {"table": args.table_port, "gyro": args.gyro_port,
                             "chamber": args.chamber_port, "supply": args.supply_port},
                            speed=args.speed, seed=args.seed, faults=faults)


def _said_held(n: int) -> None:
    """``--fault hold:N``: the line a test waits for (``held: N``) once the clock stops."""
    try:
        print(f"held: {n}", flush=True)
    except (OSError, ValueError):      # the reader of stdout went away: nothing to tell
        pass


#: Wall seconds between the main thread's looks at a stop signal while serving (a signal
#: taken by another thread is acted on within this).
WAKE_S = 0.25


def run(args) -> int:
    from gonio.errors import GonioError
    from gonio.instruments.scpi import Faults
    from gonio.specs import DEFAULT_KEY, get

    spec = get(args.spec or DEFAULT_KEY)
    if args.bench is None:
        args.bench = spec.default_bench
    faults = Faults.parse(args.fault)
    faults.on_hold = _said_held
    if is_rate_bench(args.bench):
        extra = [args.spec_flags[d] for d, v in given(args).items() if v not in (None, False)]
        if extra:
            raise GonioError(f"gonio bench serve: {', '.join(extra)} does not apply to a rate "
                             f"bench ({args.bench})")
        served = _serve_rate(args, faults)
    elif spec.serve is None:
        raise GonioError(f"gonio bench serve: {spec.key} serves no virtual bench as "
                         "instruments (the specification has no serve hook)")
    else:
        opts = refuse(spec, "bench serve", given(args), args)
        served = spec.serve(args.bench, {"table": args.table_port, "gyro": args.gyro_port},
                            speed=args.speed, seed=args.seed, faults=faults, **opts)
    try:
        for name, res in served.resources.items():
            print(f"{name}: {res}", flush=True)
        while True:
            time.sleep(WAKE_S)
    finally:
        served.close()
