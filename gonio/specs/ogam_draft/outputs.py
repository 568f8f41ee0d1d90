"""The optical draft's rendering side: results.json, summary.txt, the detail tables, the
certificate and its DCC from a :class:`~gonio.specs.ogam_draft.calibration.CalibrationReport`,
and the demo (simulate + calibrate + write, end to end).

This module is ``SPEC.outputs``: the pipeline imports it through the registry (it may import
the report and the bench; the calibration path never imports it).
"""

from __future__ import annotations

from pathlib import Path

from gonio.atomic import output_dir, output_set, write_text
from gonio.bench import load_bench, run_session, write_session
from gonio.protocol import load_protocol
from gonio.report.certificate import write_certificate
from gonio.report.stated import summary_text
from gonio.result.tables import results_json_text, write_tables
from gonio.result.text import virtual_line
from gonio.specs.ogam_draft.calibration import CalibrationReport, calibrate
from gonio.specs.ogam_draft.items import ITEM_KEYS

ITEM_NAMES = ITEM_KEYS


def results_json(report: CalibrationReport, lab: dict | None = None) -> dict:
    """The ``results.json`` content (the one result model, conformity decided)."""
    return report.decided_result(lab).to_json()


def warnings(report: CalibrationReport) -> list[str]:
    """One line per conflict and per excluded reading group (for stderr)."""
    return report.warnings()


def write(report: CalibrationReport, out, *, truth: dict | None = None, lab=None,
          lang: str = "en", dcc: bool = False) -> dict[str, Path]:
    """results.json, summary.txt, tables/*.csv and the certificate (``dcc``: its DCC XML)
    into ``out`` (the caller stages the set). Conformity is decided once, for results.json
    (:meth:`CalibrationReport.decided_result`); the certificate renders that decision."""
    paths = dict(write_calibration(report, out, lab=lab))
    paths.update(write_certificate(report, out, truth=truth, lab=lab, lang=lang, dcc=dcc))
    return paths


def summary(report: CalibrationReport, lab: dict | None = None) -> str:
    """The seven items, U (k, coverage probability) and any conformity statements as a
    fixed-width text table, rounded as the certificate (:func:`gonio.report.stated.summary_text`),
    then the 95 % intervals of the standard-deviation items and the budget's notes."""
    if (lab or {}).get("specification_limits") and not report.conformity:
        report.decided_result(lab)          # the pipeline's decision, kept in report.conformity
    res = report.to_dict()
    lines = virtual_line(res) + [summary_text(res, "en", lab, report.conformity).rstrip("\n")]
    for name in ITEM_NAMES:
        iu = report.item_uncertainty.get(name)
        if iu is not None and iu.interval is not None:
            lines.append(f"{name}: 95 % interval [{iu.interval[0]:.3g}, "
                         f"{iu.interval[1]:.3g}] {iu.unit} (chi-square)")
    zr = report.zero_stability_readings
    if zr:
        if zr["stated"] == "model":
            d = zr["draft"]
            lines.append(f"zero_stability: the draft's s(M)/T = {d.value:.3g} deg/h, 95 % "
                         f"interval [{d.interval[0]:.3g}, {d.interval[1]:.3g}] deg/h "
                         "(chi-square)")
        elif zr["model"] is not None:
            m = zr["model"]
            lines.append(f"zero_stability (noise model, not stated): {m.value:.3g} deg/h, "
                         f"U = {m.U:.2g} deg/h (k = {m.k:.3g}, coverage probability "
                         "approximately 95 %)")
        lines.append(f"note: {zr['note']}")
    if report.e_measured:
        lines += [f"note: {n}" for n in report.budget_notes]
    lines += [f"flagged: {f.location()}: {f.message}" for f in report.findings
              if f.code == "identity-mismatch"]       # the readings against the lab file
    return "\n".join(lines) + "\n"


def write_outputs(report: CalibrationReport, out: str | Path, *, truth: dict | None = None,
                  lab=None, lang: str = "en", session=None, inputs=(),
                  force: bool = False, dcc: bool = False) -> dict[str, Path]:
    """One run's whole output set into ``out``: results, summary, tables, certificate (and
    readings + truth of a simulated ``session``), swapped in together.

    Through :func:`gonio.atomic.output_set`: every part is written into a staging
    folder and the folder replaces ``out`` only when all are written, with
    ``gonio-manifest.json`` carrying the source's SHA-256; a failed run leaves the
    previous set untouched; ``out`` holding one of ``inputs`` is refused.
    """
    out = Path(out) if str(out).strip() else out
    with output_set(out, inputs=inputs, force=force, source_sha256=report.source_sha256) as st:
        if session is not None:
            write_session(session, out)
        write_calibration(report, out, lab=lab)
        write_certificate(report, out, truth=truth, lab=lab, lang=lang, dcc=dcc)
        names = sorted(p.relative_to(st).as_posix() for p in st.rglob("*") if p.is_file())
    return {n: Path(out) / n for n in names}


def write_calibration(report: CalibrationReport, out: str | Path,
                      lab: dict | None = None) -> dict[str, Path]:
    """Write ``results.json``, ``summary.txt`` and ``tables/*.csv`` into ``out`` atomically.

    ``lab`` (a :func:`gonio.formats.lab.load_lab` dict) adds its conformity statements
    to ``summary.txt``, as the certificate and the CLI show them.
    """
    out = Path(out)
    result = report.decided_result(lab)
    with output_dir(out) as stage:
        write_text(stage / "results.json", results_json_text(result))
        write_text(stage / "summary.txt", summary(report, lab))
        write_tables(result, stage)
        names = {p.name: out / p.relative_to(stage) for p in stage.rglob("*") if p.is_file()}
    return names


def demo(out: str | Path, *, bench: str = "rlg", seed: int = 0, lab=None, lang: str = "en",
         dcc: bool = True, force: bool = False, inputs=(), on_stage=None,
         protocol: str = "ogam-draft") -> tuple[CalibrationReport, dict[str, Path]]:
    """Simulate ``protocol`` on ``bench``, calibrate the readings (with the session's static
    record for the Allan analysis of 7.3), write results, certificate and (``dcc``) the DCC
    XML. ``lab``: a loaded laboratory dict (or a file).

    The whole set (readings.csv, truth.json, results, tables, certificate, DCC, manifest)
    is staged and swapped into ``out`` together (:func:`gonio.atomic.output_set`); an
    existing readings.csv there is replaced only with ``force``. ``on_stage(message)``,
    if given, is told each stage as it starts (the CLI shows it on a terminal). Returns
    the report and the paths written, by their names relative to ``out``.
    """
    say = on_stage or (lambda message: None)
    if isinstance(lab, (str, Path)):
        from gonio.formats.lab import load_lab
        lab = load_lab(lab)                     # validate inputs before simulating
    out = Path(out) if str(out).strip() else out
    proto = load_protocol(protocol)
    bench_cfg = load_bench(bench)
    inputs = [x for x in (*inputs, bench, protocol)
              if isinstance(x, (str, Path)) and Path(x).exists()]
    with output_set(out, inputs=inputs, force=force) as stage:
        say("demo: simulating the session on the virtual bench")
        session = run_session(proto, bench_cfg, seed=seed)
        write_session(session, out)
        say("demo: calibrating")
        report = calibrate(stage / "readings.csv", proto, static_record=session.static_record)
        report.readings.path = Path(out) / "readings.csv"
        write_calibration(report, out, lab=lab)
        say("demo: writing the certificate")
        write_certificate(report, out, truth=session.truth, lab=lab, lang=lang, dcc=dcc)
        names = sorted(p.relative_to(stage).as_posix() for p in stage.rglob("*") if p.is_file())
    return report, {n: Path(out) / n for n in names}
