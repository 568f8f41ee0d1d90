"""The demo: the draft's whole calibration on the default virtual bench, end to end."""

from __future__ import annotations

from pathlib import Path

from gonio.bench import load_bench, run_session, write_session
from gonio.pipeline.calibrate import CalibrationReport, calibrate, write_calibration
from gonio.protocol import load_protocol


def demo(out: str | Path, seed: int = 0, bench: str = "rlg", protocol: str = "ogam-draft",
         lab: str | Path | None = None, lang: str = "en", dcc: bool = True,
         on_stage=None, force: bool = False) -> tuple[CalibrationReport, list[Path]]:
    """Simulate ``protocol`` on ``bench``, calibrate the readings, write results, certificate
    and (``dcc``) the DCC XML.

    The whole set (readings.csv, truth.json, results, tables, certificate, DCC, manifest)
    is staged and swapped into ``out`` together (:func:`gonio.atomic.output_set`); an
    existing readings.csv there is replaced only with ``force``. ``on_stage(message)``,
    if given, is told each stage as it starts (the CLI shows it on a terminal). Returns
    the report and the paths written.
    """
    from gonio.atomic import output_set

    say = on_stage or (lambda message: None)
    from gonio.report.certificate import load_lab, write_certificate

    out = Path(out) if str(out).strip() else out
    lab_d = load_lab(lab) if lab else None      # validate inputs before simulating
    proto = load_protocol(protocol)
    bench_cfg = load_bench(bench)
    inputs = [x for x in (lab, bench, protocol) if isinstance(x, (str, Path)) and Path(x).exists()]
    with output_set(out, inputs=inputs, force=force) as stage:
        say("demo: simulating the session on the virtual bench")
        session = run_session(proto, bench_cfg, seed=seed)
        write_session(session, out)
        say("demo: calibrating")
        report = calibrate(stage / "readings.csv", proto, static_record=session.static_record)
        report.readings.path = Path(out) / "readings.csv"
        write_calibration(report, out, lab=lab_d)
        say("demo: writing the certificate")
        write_certificate(report, out, truth=session.truth, lab=lab_d, lang=lang, dcc=dcc)
        names = sorted(p.relative_to(stage).as_posix() for p in stage.rglob("*") if p.is_file())
    return report, [Path(out) / n for n in names]
