"""``gonio simulate``: run a protocol on the virtual bench → readings.csv, truth.json."""

from __future__ import annotations

from gonio.bench import load_bench, run_session, write_session
from gonio.errors import GonioError
from gonio.protocol import load_protocol


def register(sub) -> None:
    p = sub.add_parser("simulate", help="run a protocol on the virtual bench",
                       description="Execute a protocol on a virtual bench and write the readings "
                                   "file a laboratory would record (readings.csv) and truth.json.")
    p.add_argument("--protocol", default="ogam-draft", help="protocol file or built-in name")
    p.add_argument("--bench", default="rlg", help="bench file or built-in name (rlg, fog)")
    p.add_argument("--table", default=None, help="table file overriding the bench's")
    p.add_argument("--seed", type=int, default=0, help="random seed (same seed → same bytes)")
    p.add_argument("--out", required=True, help="output folder")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.seed < 0:
        raise GonioError(f"--seed must be ≥ 0, got {args.seed}")
    proto = load_protocol(args.protocol)
    bench = load_bench(args.bench, table=args.table)
    paths = write_session(run_session(proto, bench, seed=args.seed), args.out)
    for p in paths.values():
        print(p)
    return 0
