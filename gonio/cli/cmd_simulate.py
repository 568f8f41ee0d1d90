"""``gonio simulate``: run a protocol on the virtual bench → readings.csv, truth.json
(and, with ``--stream``, the continuous stream the acquisition module would give:
stream.parquet by default, stream.csv with ``--stream-format csv``)."""

from __future__ import annotations

from pathlib import Path

from gonio.bench import load_bench, run_session, write_session
from gonio.errors import GonioError
from gonio.protocol import load_protocol
from gonio.cli.checks import seed


def register(sub) -> None:
    p = sub.add_parser("simulate", help="run a protocol on the virtual bench",
                       description="Execute a protocol on a virtual bench and write the readings "
                                   "file a laboratory would record (readings.csv) and truth.json.")
    p.add_argument("--spec", default="ogam-draft",
                   help="specification (ogam-draft, jjf1535-2015, iec62047-20, triad-alignment)")
    p.add_argument("--protocol", default=None,
                   help="protocol file or built-in name (default: the specification's)")
    p.add_argument("--bench", default=None,
                   help="bench file or built-in name (default: rlg; rate specs: mems-adxrs610; "
                        "triad-alignment: mems-triad)")
    p.add_argument("--table", default=None, help="table file overriding the bench's")
    p.add_argument("--seed", type=seed, default=0, help="random seed (same seed → same bytes)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--force", action="store_true",
                   help="replace an --out folder that holds readings.csv or stream.csv")
    p.add_argument("--stream", action="store_true",
                   help="also write the stream (every sample: time, wrapped counter, table "
                        "angle; docs/formats.md#stream-file), chunk by chunk, with progress on a "
                        "terminal")
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
    from gonio.atomic import check_output_dir, output_set

    inputs = [args.protocol, args.bench, args.table]
    check_output_dir(args.out, inputs=inputs, force=args.force)
    if args.spec in SPEC_SIMULATORS:
        with output_set(args.out, inputs=inputs, force=args.force):
            return _run_spec(args)
    if args.spec != "ogam-draft":
        from gonio.pipeline.rate import simulate

        if args.stream or args.table:
            raise GonioError("--stream and --table apply to the ogam-draft specification only")
        with output_set(args.out, inputs=inputs, force=args.force):
            paths = simulate(args.spec, args.out, bench=args.bench, protocol=args.protocol,
                             seed=args.seed)
        for p in paths.values():
            print(p)
        return 0
    proto = load_protocol(args.protocol or "ogam-draft")
    bench = load_bench(args.bench or "rlg", table=args.table)
    with output_set(args.out, inputs=inputs, force=args.force) as stage:
        writer = prog = sink = None
        if args.stream:
            from gonio.bench.session import plan_session
            from gonio.formats.streams import StreamWriter
            from gonio.progress import Progress

            name = "stream.parquet" if args.stream_format == "parquet" else "stream.csv"
            writer = StreamWriter(stage / name, stream_metadata(proto, bench, args.seed),
                                  table=True, fmt=args.stream_format)
            total = sum(b.k_end - b.k_start for b in plan_session(proto, bench, None))
            prog = Progress(total, label=f"simulate: {name}", unit="samples")

            def write_chunk(t, c, th):
                writer.write(t, c, th)
                prog.update(len(t))
            sink = write_chunk
        from gonio.progress import status

        if sink is None:
            status("simulate: running the session")
        try:
            result = run_session(proto, bench, seed=args.seed, stream=sink)
            status("")
        except BaseException:
            if writer is not None:
                writer.abort()
            raise
        finally:
            if prog is not None:
                prog.close()
        paths = write_session(result, args.out)
        if writer is not None:
            writer.close()
            paths["stream"] = Path(args.out) / name
    for p in paths.values():
        print(p)
    return 0


#: Specifications with their own session simulator (module with ``simulate``).
SPEC_SIMULATORS = {"triad-alignment": "gonio.specs.triad_alignment.simulate"}


def _run_spec(args) -> int:
    """A specification with its own simulator (the gyro triad: readings.csv, thermal.csv,
    truth.json)."""
    import importlib

    from gonio.specs import get

    spec = get(args.spec)
    if args.stream or args.table:
        raise GonioError(f"--stream and --table apply to ogam-draft only, not {spec.key}",
                         key="--spec")
    sim = importlib.import_module(SPEC_SIMULATORS[spec.key]).simulate
    paths = sim(args.protocol or spec.default_protocol, args.bench or spec.default_bench,
                args.seed, args.out)
    for p in paths.values():
        print(p)
    return 0
