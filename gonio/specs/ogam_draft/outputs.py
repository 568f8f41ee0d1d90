"""The optical draft's rendering side: results.json, summary.txt, the detail tables, the
certificate and its DCC from the one sealed :class:`~gonio.result.model.Result` its
``calibrate`` returns, and the demo (simulate + calibrate + write, end to end).

This module is ``SPEC.outputs``: the pipeline imports it through the registry (it may import
the report and the bench; the calibration path never imports it). Conformity is decided by
the pipeline before anything is written (:func:`gonio.specs.decide_conformity`; the demo
and :func:`write_outputs`, which do not go through the pipeline, call it as the pipeline
would); everything here renders it.
"""

from __future__ import annotations

from pathlib import Path

from gonio.atomic import output_dir, output_set, write_text
from gonio.kit.render import display
from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
from gonio.specs.ogam_draft.protocol import load_protocol
from gonio.specs import decide_conformity
from gonio.specs.ogam_draft.certificate_pages import write_certificate
from gonio.specs.ogam_draft.stated import summary_text
from gonio.specs.ogam_draft.stored import complete_stored
from gonio.report.header import room_temperature_keys
from gonio.report.i18n import finding_text, labels
from gonio.result.findings import stated_findings
from gonio.result.model import Result
from gonio.result.statement import signed_text
from gonio.result.tables import results_json_text, write_tables
from gonio.result.text import identity_lines, virtual_line
from gonio.specs.ogam_draft.calibration import calibrate


def _and(names: list) -> str:
    """'a', 'a and b', 'a, b and c'."""
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def results_json(result: Result, lab: dict | None = None) -> dict:
    """The ``results.json`` content."""
    return result.to_json()


def warnings(result: Result) -> list[str]:
    """One line per conflict and per excluded reading group (for stderr)."""
    return list(result.extra.get("warnings") or [])


def write(result: Result, out, *, truth: dict | None = None, lab=None,
          lang: str = "en", dcc: bool = False) -> dict[str, Path]:
    """results.json, summary.txt, tables/*.csv and the certificate (``dcc``: its DCC XML)
    into ``out`` (the caller stages the set and has decided conformity). A stored result
    written by an earlier gonio renders with the fields it lacks derived
    (:func:`gonio.specs.ogam_draft.stored.complete_stored`), or is refused in one line."""
    paths = dict(write_calibration(result, out, lab=lab))
    paths.update(write_certificate(complete_stored(result.to_json()), out, truth=truth,
                                   lab=lab, lang=lang, dcc=dcc))
    return paths


def item_titles(res: dict, lang: str = "en") -> dict[str, str]:
    """Each item's name as the certificate in ``lang`` names it (``res``: results.json):
    the draft's own labels (its results table's names), else the item's title."""
    from gonio.specs.ogam_draft.phrases import LABELS

    return {k: (LABELS.get(k) or {}).get(lang) or it.get("title") or k
            for k, it in (res.get("items") or {}).items()}


def summary(result: Result | dict, lab: dict | None = None) -> str:
    """The seven items, U (k, coverage probability) and any conformity statements as a
    fixed-width text table, rounded as the certificate (:func:`gonio.specs.ogam_draft.stated.summary_text`),
    then the budget's notes (an item stated by its interval, B_s and R, has that one
    statement in the table); from the result or its results.json."""
    result = result if isinstance(result, Result) else Result.from_json(result)
    d = complete_stored(result.to_json())
    lines = virtual_line(d) + identity_lines(d.get("findings"), d.get("metadata") or {}, lab,
                                           room_temperature_keys(d.get("spec"))) \
        + [summary_text(d, "en", lab).rstrip("\n")]
    kl = (d["items"].get("scale_factor_nonlinearity") or {}).get("details") or {}
    if kl.get("estimates"):
        lines.append("scale_factor_nonlinearity (the draft's range as measured, not stated): "
                     f"{kl['estimates']['draft']['value']:.3g} %")
    for name, unit in (("rate_consistency", "ppm"), ("pointing_consistency", "%")):
        cv = (d["items"].get(name) or {}).get("details") or {}
        if cv.get("estimates"):
            lines.append(f"{name} (the draft's range as measured, not stated): "
                         f"{cv['estimates']['draft']['value']:.3g} {unit}")
    kd = (d["items"].get("scale_factor") or {}).get("details") or {}
    if kd.get("tilt_correction"):
        tc = kd["tilt_correction"]
        lines.append(f"scale_factor (the draft's 7.1 mean, uncorrected, not stated): "
                     f"{kd['estimates']['draft']['value']:.10g} counts/deg")
        # the estimate's line has no U; ψ, α and their U95 by the certificate's rules
        # (stated.k_tilt_note)
        lines.append(f"note: the stated K is corrected "
                     f"by the measured tilt psi = "
                     f"{display('atU', tc['tilt_deg'], tc['U95_tilt_deg'])} deg (U95 "
                     f"{display('U', tc['U95_tilt_deg'])} deg) at azimuth "
                     f"{display('atU', tc['azimuth_deg'], tc['U95_azimuth_deg'])} deg (U95 "
                     f"{display('U', tc['U95_azimuth_deg'])} deg), beyond the draft")
    tk = kd.get("table_calibration")
    e_table = ((d["items"].get("angle_deviation") or {}).get("details") or {}).get(
        "table_calibration")
    ranges = {n: ((d["items"].get(n) or {}).get("details") or {})
              for n in ("scale_factor_nonlinearity", "rate_consistency", "pointing_consistency")}
    fixed = [s for n, s in (("scale_factor_nonlinearity", "K_l"), ("rate_consistency", "C_v"),
                            ("pointing_consistency", "C_g"))
             if (ranges[n].get("table_calibration") or {}).get("positions_used")]
    kept = [s for n, s in (("angle_deviation", "E"), ("scale_factor_nonlinearity", "K_l"),
                           ("rate_consistency", "C_v"), ("pointing_consistency", "C_g"))
            if (n != "angle_deviation" or not e_table) and s not in fixed
            and (d["items"].get(n) or {}).get("measured")]
    if tk:
        lines.append(f"note: the stated K is corrected by the table calibration {tk['source']} "
                     f"(u(K) of it {tk['u_rel_ppm']:.2g} ppm, line P_Kc; the 7.1 mean uncorrected "
                     f"{tk['uncorrected_value']:.10g} counts/deg), beyond the draft"
                     + ("; E is corrected by it too (its table line the calibration's)"
                        if e_table else "")
                     + (f"; {_and(fixed)} too (the range of the corrected readings, the table's "
                        "draws the calibration's)" if fixed else "")
                     + (f"; {_and(kept)} {'keeps' if len(kept) == 1 else 'keep'} the table's "
                        "MPE lines" if kept else ""))
    for n, sym in (("scale_factor_nonlinearity", "K_l"), ("rate_consistency", "C_v"),
                   ("pointing_consistency", "C_g")):
        if ranges[n].get("table_calibration_not_used"):
            lines.append(f"note: {ranges[n]['table_calibration_not_used']}")
    if e_table:
        lines.append(f"note: E's reference angles are corrected by the table calibration "
                     f"{e_table['source']}"
                     + (" and E read with the table-corrected K"
                        if e_table.get("scale_factor_corrected") is True else "")
                     + ", beyond the "
                     f"draft (E without the table correction: "
                     f"{e_table['uncorrected_value']:.3g} arcsec)")
    tb = kd.get("temperature_coeff_bound")
    if tb and tb.get("basis") == "logged":   # K's chamber line at the logged temperature
        lines.append(f"note: U(K) holds for the chamber temperature the readings log, "
                     f"{tb['logged_temperature_c']:g} °C"
                     + (" (mean over the 7.1 rounds)" if tb.get("logged_from") == "column" else "")
                     + f" ({signed_text(tb['deviation_c'])} °C from the reference "
                     f"{tb['reference_temperature_c']:g} °C; thermometer MPE "
                     f"±{tb.get('thermometer_mpe_c') or 0:g} °C), and |α_K| ≤ "
                     f"{tb['bound_ppm_per_c']:g} ppm/°C: {tb['how']}")
    elif tb:                                 # which bound K's chamber line took, and whence
        lines.append(f"note: U(K) holds for a chamber within ±{tb['temperature_tolerance_c']:g} "
                     f"°C of the reference and |α_K| ≤ {tb['bound_ppm_per_c']:g} ppm/°C:"
                     f" {tb['how']}")
    zs = d["items"]["zero_stability"]["details"]
    est = zs.get("estimates")
    if est:
        if zs["stated"] == "model":
            dr, iv = est["draft"], est["draft"]["uncertainty"]["interval"]
            lines.append(f"zero_stability (the draft's s(M)/T, not stated): {dr['value']:.3g} "
                         f"deg/h, one-sided 95 % chi-square upper limit {iv[1]:.3g} deg/h")
        elif est["model"] is not None:
            m = est["model"]
            lines.append(f"zero_stability (noise model, not stated): {m['value']:.3g} deg/h, "
                         f"standard uncertainty u = {m['uncertainty']['u_c']:.2g} deg/h (no "
                         "coverage interval claimed: the five-term model's intervals "
                         "under-cover, docs/draft-readings.md)")
        lines.append(f"note: {zs['stated_note']}")
    unc = d["extra"]["uncertainty"]
    if unc.get("measured"):
        lines += [f"note: {n}" for n in unc.get("notes") or []]
    lines += finding_lines(d.get("findings"))
    return "\n".join(lines) + "\n"


def finding_lines(findings) -> list[str]:
    """Every finding the certificate states (:func:`gonio.result.findings.stated_findings`:
    all but the refused ones, those about the whole file first), each as the English
    certificate's line (:func:`gonio.report.i18n.finding_text`) after ``finding: `` —
    summary.txt lists all of them, where the certificate stops after its first few.

    >>> finding_lines([{"code": "incomplete-programme", "action": "flagged", "clause": "7.1",
    ...                 "message": "the item rests on 5 of the programme's 6 rounds"},
    ...                {"code": "x", "action": "refused", "message": "not stated"}])
    ["finding: [flagged] 7.1: the item rests on 5 of the programme's 6 rounds"]
    """
    en = labels("en")
    return [f"finding: {finding_text(f if isinstance(f, dict) else f.to_json(), en)}"
            for f in stated_findings(findings)]


def write_outputs(result: Result, out: str | Path, *, truth: dict | None = None,
                  lab=None, lang: str = "en", session=None, inputs=(),
                  force: bool = False, dcc: bool = False) -> dict[str, Path]:
    """One run's whole output set into ``out``: results, summary, tables, certificate (and
    readings + truth of a simulated ``session``), swapped in together; conformity decided
    on ``lab``'s limits first by the one decision
    (:func:`gonio.specs.decide_conformity`), as the pipeline does.

    Through :func:`gonio.atomic.output_set`: every part is written into a staging
    folder and the folder replaces ``out`` only when all are written, with
    ``gonio-manifest.json`` carrying the source's SHA-256; a failed run leaves the
    previous set untouched; ``out`` holding one of ``inputs`` is refused.
    """
    out = Path(out) if str(out).strip() else out
    if isinstance(lab, (str, Path)):
        from gonio.formats.lab import load_lab
        lab = load_lab(lab)
    decide_conformity(result, lab)
    with output_set(out, inputs=inputs, force=force, source_sha256=result.source_sha256) as st:
        if session is not None:
            write_session(session, out)
        write(result, out, truth=truth, lab=lab, lang=lang, dcc=dcc)
        names = sorted(p.relative_to(st).as_posix() for p in st.rglob("*") if p.is_file())
    return {n: Path(out) / n for n in names}


def write_calibration(result: Result, out: str | Path,
                      lab: dict | None = None) -> dict[str, Path]:
    """Write ``results.json``, ``summary.txt`` and ``tables/*.csv`` into ``out`` atomically.

    ``lab`` (a :func:`gonio.formats.lab.load_lab` dict) adds the conformity statements
    decided on its limits to ``summary.txt``, as the certificate and the CLI show them.
    """
    out = Path(out)
    with output_dir(out) as stage:
        write_text(stage / "results.json", results_json_text(result))
        write_text(stage / "summary.txt", summary(result, lab))
        write_tables(result, stage)
        names = {p.name: out / p.relative_to(stage) for p in stage.rglob("*") if p.is_file()}
    return names


def _with_static_record_file(session, stage: Path):
    """``session`` whose readings name the static record file (``# static_record:``) written
    into ``stage`` from its record (:func:`gonio.specs.ogam_draft.static_record.
    static_record_text`, decimated as the noise analysis decimates); the session as it is
    where it captured no record."""
    import dataclasses

    from gonio.specs.ogam_draft.calibration import ZERO_STABILITY_NOISE_SAMPLES
    from gonio.specs.ogam_draft.static_record import FILE_NAME, METADATA_KEY, static_record_text

    rec = session.static_record
    if rec is None or rec.counts is None:
        return session
    write_text(Path(stage) / FILE_NAME, static_record_text(rec, ZERO_STABILITY_NOISE_SAMPLES,
                                                            session.metadata))
    return dataclasses.replace(session, metadata={**session.metadata, METADATA_KEY: FILE_NAME})


def demo(out: str | Path, *, bench: str = "rlg", seed: int = 0, lab=None, lang: str = "en",
         dcc: bool = True, force: bool = False, inputs=(), on_stage=None,
         protocol: str = "ogam-draft", identity=None) -> tuple[Result, dict[str, Path]]:
    """Simulate ``protocol`` on ``bench``, calibrate the readings (with the session's static
    record for the Allan analysis of 7.3, written beside them as ``static_record.csv`` and
    named by their ``# static_record:`` line, :func:`_with_static_record_file`: the folder is
    what ``gonio calibrate readings.csv`` gives, so the records can compute it again from
    its files), write results, certificate and (``dcc``) the DCC XML. ``lab``: a loaded
    laboratory dict (or a file).

    The whole set (readings.csv, truth.json, results, tables, certificate, DCC, manifest)
    is staged and swapped into ``out`` together (:func:`gonio.atomic.output_set`); an
    existing readings.csv there is replaced only with ``force``. ``on_stage(message)``,
    if given, is told each stage as it starts (the CLI shows it on a terminal). Returns
    the result (conformity decided on ``lab``) and the paths written, by their names
    relative to ``out``. ``identity(readings)``: the findings of comparing the simulated
    readings with the laboratory file (the pipeline's), stated with the result's.
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
    with output_set(out, inputs=inputs, force=force,
                    writes=("readings.csv", "truth.json")) as stage:
        say("demo: simulating the session on the virtual bench")
        session = run_session(proto, bench_cfg, seed=seed)
        session = _with_static_record_file(session, stage)
        write_session(session, out)
        say("demo: calibrating")
        result = calibrate(stage / "readings.csv", proto)
        if identity is not None:
            result.findings = list(result.findings) + identity(stage / "readings.csv")
        result = decide_conformity(result, lab)
        write_calibration(result, out, lab=lab)
        say("demo: writing the certificate")
        write_certificate(result.to_json(), out, truth=session.truth, lab=lab, lang=lang,
                          dcc=dcc)
        names = sorted(p.relative_to(stage).as_posix() for p in stage.rglob("*") if p.is_file())
    return result, {n: Path(out) / n for n in names}
