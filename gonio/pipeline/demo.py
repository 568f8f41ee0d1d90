"""The demo: the draft's whole calibration on the default virtual bench, end to end."""

from __future__ import annotations

from pathlib import Path

from gonio.bench import load_bench, run_session, write_session
from gonio.pipeline.calibrate import CalibrationReport, calibrate, write_calibration
from gonio.protocol import load_protocol


def demo(out: str | Path, seed: int = 0, bench: str = "rlg", protocol: str = "ogam-draft",
         lab: str | Path | None = None, lang: str = "en") -> tuple[CalibrationReport, list[Path]]:
    """Simulate ``protocol`` on ``bench``, calibrate the readings, write results and certificate.

    Returns the report and the paths written (readings.csv, truth.json, results.json, ...).
    """
    from gonio.report.certificate import load_lab, write_certificate

    out = Path(out)
    lab_d = load_lab(lab) if lab else None      # validate inputs before simulating
    proto = load_protocol(protocol)
    session = run_session(proto, load_bench(bench), seed=seed)
    written = list(write_session(session, out).values())
    report = calibrate(out / "readings.csv", proto, static_record=session.static_record)
    written += list(write_calibration(report, out).values())
    written += list(write_certificate(report, out, truth=session.truth, lab=lab_d,
                                      lang=lang).values())
    return report, written
