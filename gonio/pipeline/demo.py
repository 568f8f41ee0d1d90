"""The demo: the draft's whole calibration on the default virtual bench, end to end."""

from __future__ import annotations

from pathlib import Path

from gonio.bench import load_bench, run_session, write_session
from gonio.pipeline.calibrate import CalibrationReport, calibrate, write_calibration
from gonio.protocol import load_protocol


def demo(out: str | Path, seed: int = 0, bench: str = "rlg", protocol: str = "ogam-draft",
         lab: str | Path | None = None, lang: str = "en", dcc: bool = True,
         on_stage=None) -> tuple[CalibrationReport, list[Path]]:
    """Simulate ``protocol`` on ``bench``, calibrate the readings, write results, certificate
    and (``dcc``) the DCC XML.

    ``on_stage(message)``, if given, is told each stage as it starts (the CLI shows it on a
    terminal). Returns the report and the paths written (readings.csv, truth.json,
    results.json, tables/..., certificate.*).
    """
    stage = on_stage or (lambda message: None)
    from gonio.report.certificate import load_lab, write_certificate

    out = Path(out)
    lab_d = load_lab(lab) if lab else None      # validate inputs before simulating
    proto = load_protocol(protocol)
    stage("demo: simulating the session on the virtual bench")
    session = run_session(proto, load_bench(bench), seed=seed)
    written = list(write_session(session, out).values())
    stage("demo: calibrating")
    report = calibrate(out / "readings.csv", proto, static_record=session.static_record)
    written += list(write_calibration(report, out, lab=lab_d).values())
    stage("demo: writing the certificate")
    written += list(write_certificate(report, out, truth=session.truth, lab=lab_d,
                                      lang=lang, dcc=dcc).values())
    return report, written
