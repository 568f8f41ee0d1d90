"""The demo: the draft's whole calibration on the default virtual bench, end to end."""

from __future__ import annotations

from pathlib import Path

from gonio.bench import load_bench, run_session, write_session
from gonio.calibrate import CalibrationReport, calibrate, write_calibration
from gonio.protocol import load_protocol


def demo(out: str | Path, seed: int = 0, bench: str = "rlg",
         protocol: str = "ogam-draft") -> tuple[CalibrationReport, list[Path]]:
    """Simulate ``protocol`` on ``bench`` and calibrate the readings; write everything to ``out``.

    Returns the report and the paths written (readings.csv, truth.json, results.json, ...).
    """
    out = Path(out)
    proto = load_protocol(protocol)
    session = run_session(proto, load_bench(bench), seed=seed)
    written = list(write_session(session, out).values())
    report = calibrate(out / "readings.csv", proto, static_record=session.static_record)
    written += list(write_calibration(report, out).values())
    try:
        from gonio.report.certificate import write_certificate
    except ImportError:  # the certificate module is optional until it lands
        write_certificate = None
    if write_certificate is not None:
        written += list(write_certificate(report, out, truth=session.truth).values())
    return report, written
