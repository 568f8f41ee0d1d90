"""``gonio reduce``: stream → readings file (find the table's rests, match the protocol's rounds)."""

from __future__ import annotations

import json

from gonio.errors import GonioError, check_input_file
from gonio.atomic import check_output_file
from gonio.cli.checks import LARGE, float_range


def register(sub) -> None:
    p = sub.add_parser("reduce", help="reduce a stream file to a readings file",
                       description="Find the table's rests in a stream (docs/formats.md#stream-file), "
                                   "match them to the protocol's rounds and write the readings "
                                   "file (§1). Rounds that cannot be matched are listed with the "
                                   "reason; --override gives their times explicitly.")
    p.add_argument("stream", help="stream file (CSV, or Parquet: *.parquet); read in blocks, "
                   "in bounded memory")
    p.add_argument("--protocol", default=None,
                   help="protocol file or built-in name (default: the default specification's)")
    p.add_argument("--out", required=True, help="readings file to write")
    p.add_argument("--override", default=None,
                   help="CSV test,series,round,t_zero_s,t_read_s[,rate_dps,orientation]")
    p.add_argument("--force", action="store_true",
                   help="replace an existing readings file at --out")
    p.add_argument("--max-gap", type=float_range(0, LARGE, lo_open=True), default=None, metavar="S",
                   help="largest allowed time step in the stream, s (default 10× median)")
    p.add_argument("--json", action="store_true", help="print the reduction summary as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.max_gap is not None and not args.max_gap > 0:
        raise GonioError(f"--max-gap must be > 0, got {args.max_gap}")
    check_input_file(args.stream, "stream file")
    check_output_file(args.out, inputs=[args.stream, args.protocol, args.override],
                      force=args.force, protected=True)
    from gonio.formats.override import read_override
    from gonio.formats.readings import write_readings
    from gonio.formats.streams import StreamFile
    from gonio.progress import status
    from gonio.protocol import load_protocol
    from gonio.reduce import reduce_stream

    from gonio.specs import DEFAULT_KEY, get
    proto = load_protocol(args.protocol or get(DEFAULT_KEY).default_protocol)
    override = read_override(args.override) if args.override else None
    status(f"reduce: reading {args.stream}")
    stream = StreamFile(args.stream, max_gap_s=args.max_gap)
    status("reduce: finding rests and matching rounds")
    red = reduce_stream(stream, proto, override=override)
    status("")
    if not len(red.readings):
        raise GonioError("no round of the protocol could be matched in the stream "
                         f"({len(red.rests)} rests found)", file=args.stream)
    write_readings(red.readings.drop(columns=["t_zero_s", "t_read_s"]), args.out, red.metadata)
    if args.json:
        d = red.to_dict()
        d["out"] = str(args.out)
        print(json.dumps(d, indent=2, ensure_ascii=False, allow_nan=False))
    else:
        print(f"{args.out}: {len(red.readings)} readings from {len(red.rests)} rests")
        for u in red.unmatched:
            if u["kind"] == "round":
                print(f"  unmatched {u['test']} series {u['series']} round {u['round']}: "
                      f"{u['reason']}")
    return 0
