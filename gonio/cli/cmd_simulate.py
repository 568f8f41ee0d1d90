"""``gonio simulate``: run a protocol on the virtual bench → readings.csv, truth.json
(and, with ``--stream``, the continuous stream the acquisition module would give:
stream.parquet by default, stream.csv with ``--stream-format csv``)."""

from __future__ import annotations

from pathlib import Path

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
    p.add_argument("--stream", action="store_true",
                   help="also write the stream (every sample: time, wrapped counter, table "
                        "angle; data-formats.md §2), chunk by chunk, with progress on a terminal")
    p.add_argument("--stream-format", choices=("parquet", "csv"), default="parquet",
                   help="stream.parquet (default; pyarrow, the metadata as Parquet key-value "
                        "metadata) or stream.csv")
    p.set_defaults(func=run)


def stream_metadata(protocol, bench, seed: int) -> dict:
    """The stream file's metadata: the readings' keys plus the counter's width and sign."""
    from gonio.bench.session import session_metadata

    md = dict(session_metadata(protocol, bench, seed))
    md["counter_bits"] = str(bench.instrument.counter_bits)
    md["counter_signed"] = "true" if bench.instrument.counter_signed else "false"
    md["sample_rate_hz"] = repr(bench.sample_rate_hz)
    return md


def run(args) -> int:
    if args.seed < 0:
        raise GonioError(f"--seed must be ≥ 0, got {args.seed}")
    proto = load_protocol(args.protocol)
    bench = load_bench(args.bench, table=args.table)
    writer = prog = sink = None
    if args.stream:
        from gonio.bench.session import plan_session
        from gonio.formats.streams import StreamWriter
        from gonio.progress import Progress

        name = "stream.parquet" if args.stream_format == "parquet" else "stream.csv"
        writer = StreamWriter(Path(args.out) / name, stream_metadata(proto, bench, args.seed),
                              table=True, fmt=args.stream_format)
        total = sum(b.k_end - b.k_start for b in plan_session(proto, bench, None))
        prog = Progress(total, label=f"simulate: {name}", unit="samples")

        def write_chunk(t, c, th):
            writer.write(t, c, th)
            prog.update(len(t))
        sink = write_chunk
    try:
        result = run_session(proto, bench, seed=args.seed, stream=sink)
    except BaseException:
        if writer is not None:
            writer.abort()
        raise
    finally:
        if prog is not None:
            prog.close()
    paths = write_session(result, args.out)
    if writer is not None:
        paths["stream"] = writer.close()
    for p in paths.values():
        print(p)
    return 0
