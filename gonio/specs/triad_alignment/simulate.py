"""Simulate the triad-alignment protocol on a virtual triad bench."""

from __future__ import annotations

import json
from pathlib import Path

from gonio.atomic import output_dir
from gonio.bench.triad import (load_triad_bench, load_triad_protocol, run_alignment_session,
                               run_thermal_session)
from gonio.formats.triad import format_triad_readings


def simulate(protocol: str = "triad-alignment", bench: str = "mems-triad", seed: int = 0,
             out: str | Path = ".") -> dict:
    """Run the alignment session (→ ``readings.csv``) and, when the protocol's [thermal]
    table is enabled, the chamber programme (→ ``thermal.csv``, named by the readings'
    ``# thermal_readings:`` metadata); ``truth.json`` holds the
    bench's true values. All files are written atomically; same seed → same bytes."""
    p = load_triad_protocol(protocol)
    b = load_triad_bench(bench)
    al = run_alignment_session(p, b, seed)
    md = dict(al.metadata)
    files = {}
    if p.thermal.get("enabled"):
        th = run_thermal_session(p, b, seed)
        md["thermal_readings"] = "thermal.csv"     # the readings name their thermal programme
        files["thermal.csv"] = format_triad_readings(th.readings, th.metadata)
    files = {"readings.csv": format_triad_readings(al.readings, md), **files}
    files["truth.json"] = json.dumps(al.truth, indent=2, sort_keys=True) + "\n"
    with output_dir(out) as stage:
        for name, text in files.items():
            (stage / name).write_text(text, encoding="utf-8")
    return {name: Path(out) / name for name in files}
