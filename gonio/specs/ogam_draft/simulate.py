"""The optical draft on the virtual bench (``SPEC.simulate``): run a protocol on a table and
instrument, write the readings a laboratory records, ``truth.json`` and, on request, the
continuous stream the acquisition module would give.

The simulation side (it imports :mod:`gonio.bench`); calibrating a laboratory's file never
imports this module.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
from gonio.specs.ogam_draft.bench.session import plan_session, session_metadata
from gonio.specs.ogam_draft.protocol import load_protocol


def stream_metadata(protocol, bench, seed: int) -> dict:
    """The stream file's metadata: the readings' keys plus the counter's width and sign."""
    md = dict(session_metadata(protocol, bench, seed))
    md["counter_bits"] = str(bench.instrument.counter_bits)
    md["counter_signed"] = "true" if bench.instrument.counter_signed else "false"
    md["sample_rate_hz"] = repr(bench.sample_rate_hz)
    return md


def simulate(out, *, protocol="ogam-draft", bench="rlg", seed: int = 0, table=None,
             stream: bool = False, stream_format: str = "parquet") -> dict[str, Path]:
    """Run ``protocol`` on ``bench`` (``table``: a table file overriding the bench's) and write
    ``readings.csv`` and ``truth.json`` into ``out``; with ``stream`` also every sample (time,
    wrapped counter, table angle, and the chamber's temperature when the bench's chamber is
    off the protocol's reference; docs/formats.md#stream-file) as ``stream.parquet`` or
    ``stream.csv``, chunk by chunk, with progress on a terminal."""
    from gonio.formats.streams import StreamWriter
    from gonio.progress import Progress, status

    proto = load_protocol(protocol)
    b = load_bench(bench, table=table)
    writer = prog = sink = None
    if stream:
        name = "stream.parquet" if stream_format == "parquet" else "stream.csv"
        from gonio.atomic import active_stage
        # a chamber off the reference is logged with the samples (docs/formats.md#stream-file);
        # at the reference the metadata's temperature_c says it
        temp_c = proto.conditions.temperature_c + b.chamber_deviation_c \
            if b.chamber_deviation_c else None
        writer = StreamWriter((active_stage(out) or Path(out)) / name, stream_metadata(proto, b, seed),
                              table=True, temperature=temp_c is not None, fmt=stream_format,
                              watermark=True)   # the bench's mark in the data (watermark.py)
        total = sum(k.k_end - k.k_start for k in plan_session(proto, b, None))
        prog = Progress(total, label=f"simulate: {name}", unit="samples")

        def write_chunk(t, c, th):
            writer.write(t, c, th, None if temp_c is None else np.full(len(t), temp_c))
            prog.update(len(t))
        sink = write_chunk
    else:
        status("simulate: running the session")
    try:
        result = run_session(proto, b, seed=seed, stream=sink)
        status("")
    except BaseException:
        if writer is not None:
            writer.abort()
        raise
    finally:
        if prog is not None:
            prog.close()
    paths = write_session(result, out)
    if writer is not None:
        writer.close()
        paths["stream"] = Path(out) / name
    return paths
