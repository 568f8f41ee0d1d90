"""``gonio simulate``: run a specification's protocol on its virtual bench → the readings a
laboratory would record and truth.json (:func:`gonio.pipeline.dispatch.simulate`)."""

from __future__ import annotations

from gonio.cli.checks import seed
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
    p.add_argument("--table", default=None,
                   help="table file overriding the bench's (specifications on a precision "
                        "table)")
    p.add_argument("--seed", type=seed, default=0, help="random seed (same seed → same bytes)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--force", action="store_true",
                   help="replace an --out folder that holds readings.csv or stream.csv")
    p.add_argument("--stream", action="store_true",
                   help="also write the stream (every sample: time, wrapped counter, table "
                        "angle; docs/formats.md#stream-file), chunk by chunk, with progress on a "
                        "terminal (specifications whose instrument gives one)")
    p.add_argument("--stream-format", choices=("parquet", "csv"), default=None,
                   help="stream.parquet (default; pyarrow, the metadata as Parquet key-value "
                        "metadata) or stream.csv")
    p.set_defaults(func=run)


def run(args) -> int:
    from gonio.atomic import check_output_dir
    from gonio.pipeline.dispatch import simulate

    inputs = [args.protocol, args.bench, args.table]
    check_output_dir(args.out, inputs=inputs, force=args.force)
    paths = simulate(args.spec, args.out, bench=args.bench, protocol=args.protocol,
                     seed=args.seed, inputs=inputs, force=args.force, table=args.table,
                     stream=args.stream, stream_format=args.stream_format)
    for p in paths.values():
        print(p)
    return 0
