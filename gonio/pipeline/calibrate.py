"""From a readings file to results: the seven characteristics and the Annex A budget.

:func:`calibrate` is what ``gonio calibrate`` and ``gonio demo`` run; it returns
a :class:`CalibrationReport` (usable from a notebook) and
:func:`write_calibration` writes ``results.json``, ``summary.txt`` and the detail
tables as CSV, atomically. The uncertainty of the angle-position deviation is the
Annex A budget with u(r) taken from the calibration's own repeatability data
(7.5) when present, else the protocol's Annex A value; the table MPE and tilt
bound come from the file's metadata when given, else from the protocol.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from gonio.formats.jsonsafe import json_safe  # noqa: F401  (re-exported)
from gonio import __version__
from gonio.atomic import output_dir, output_set, sha256_file, write_text
from gonio.specs.ogam_draft.budget import AnnexABudget, annex_a_budget
from gonio.specs.ogam_draft.items import CalibrationResults, compute_characteristics
from gonio.formats.readings import Readings, metadata_float, read_readings
from gonio.errors import GonioError
from gonio.formats.records import StaticRecord
from gonio.protocol import Protocol, load_protocol

#: The readings taken of the draft's ambiguities (shown in results and certificate).
READINGS_TAKEN = (
    "7.3: the protocol sets the count and spacing of the zero-stability readings (default 15 "
    "readings 5 min apart); B_s = s(M)/T is the result, (max M − min M)/T (definition 3.3) is "
    "reported beside it; T = time between first and last reading.",
    "7.4: each round starts from 0° with both readings zeroed; the reading is taken a fixed delay "
    "after arrival, within 0.5 min of the start (Annex A.1); E_i is the mean over the series "
    "present and E = ± max|E_i| is reported with its sign.",
    "7.6/7.7: the garbled denominator is read as the angle measured in the reference state "
    "(60 °/s, axis up) on the full 360° round; the spread max E − min E in ″ is always given.",
    "Annex A.4.4: u(r) is the largest Bessel standard deviation over the calibration points of "
    "this calibration's own repeated series (7.5).",
    "Annex A.4.2: the elliptic-projection tilt model of the draft is used for u(φ_e); the "
    "rigid-body model (tilt is a cos ψ factor absorbed by the scale factor) is shown beside it.",
)


@dataclass
class CalibrationReport:
    """Everything one calibration produced."""

    results: CalibrationResults
    uncertainty: AnnexABudget
    readings: Readings
    protocol: Protocol
    source_sha256: str
    repeatability_source: str
    noise: object | None = None          # gonio.analysis.noise.StaticNoiseResult of the 7.3 record
    noise_source: str = ""
    eda: object | None = None            # gonio.analysis.equal_division.EdaResult of the equal_division rows

    def to_dict(self) -> dict:
        """The ``results.json`` content (plain JSON types, deterministic)."""
        d = self.results.to_dict()
        unc = self.uncertainty.to_dict()
        unc["repeatability_source"] = self.repeatability_source
        out = {
            "gonio_version": __version__,
            "specification": self.protocol.specification,
            "protocol": self.protocol.name,
            "source": {"file": Path(self.readings.path).name if self.readings.path else None,
                       "sha256": self.source_sha256,
                       "rows": int(len(self.readings.data))},
            "metadata": dict(self.readings.metadata),
        }
        out.update(d)
        if self.noise is not None:
            zs = dict(out["zero_stability"])
            zs["noise"] = {"source": self.noise_source, **self.noise.to_dict()}
            out["zero_stability"] = zs
        else:
            out["zero_stability"] = {**out["zero_stability"], "noise": None,
                                     "noise_reason": "the Allan analysis of 7.3 needs the "
                                     "instrument's continuous record (a stream); a readings "
                                     "file holds only the 15 readings"}
        if self.eda is not None:
            out["equal_division"] = {"clause": "IEC 62047-20 Annex A.3", **self.eda.to_dict()}
        out["uncertainty"] = unc
        out["readings_taken"] = list(READINGS_TAKEN)
        return json_safe(out)

    def summary(self, lab: dict | None = None) -> str:
        """The seven items, U (k, coverage probability) and any conformity statements as a
        fixed-width text table, rounded as the certificate (:func:`gonio.report.stated.summary_text`)."""
        from gonio.report.stated import summary_text

        return summary_text(self.to_dict(), "en", lab)


def annex_a_for(results: CalibrationResults, readings: Readings, protocol: Protocol,
                monte_carlo_trials: int = 0, seed: int = 0) -> tuple[AnnexABudget, str]:
    """The Annex A budget of this calibration (u(r) from its own 7.5 data when present)."""
    a = protocol.annex_a
    md, file = readings.metadata, readings.path
    mpe = metadata_float(md, "table_mpe_arcsec", file=file)
    tilt = metadata_float(md, "tilt_bound_deg", file=file)
    rep = results.repeatability
    if rep.measured and rep.value is not None and math.isfinite(rep.value):
        u_r, src = float(rep.value), "7.5: largest Bessel standard deviation over the points"
        n = rep.details.get("n_series") if isinstance(rep.details, dict) else None
        dof = (int(n) - 1) if n else math.inf
    else:
        u_r, src, dof = a.repeatability_arcsec, "protocol annex_a.repeatability_arcsec", math.inf
    budget = annex_a_budget(table_mpe_arcsec=mpe if mpe is not None else a.table_mpe_arcsec,
                            tilt_deg=tilt if tilt is not None else a.tilt_bound_deg,
                            zero_stability_dph=a.zero_stability_dph,
                            duration_min=a.duration_min, repeatability_arcsec=u_r,
                            k=a.coverage_factor, monte_carlo_trials=monte_carlo_trials,
                            seed=seed, repeatability_dof=dof)
    return budget, src


def load_readings_or_stream(path: str | Path, protocol: Protocol) -> Readings:
    """A readings file as is, or a stream reduced with the protocol (told apart by the header).

    A header with a ``test`` column is a readings file (docs/formats.md#readings-file); one with
    ``time_s`` and ``gyro_counts`` but no ``test`` is a stream (§2), reduced by
    :func:`gonio.reduce.reduce_stream` before calibration.
    """
    return _load(path, protocol)[0]


def _load(path: str | Path, protocol: Protocol):
    from gonio.errors import check_input_file
    from gonio.formats.streams import read_stream, sniff_kind

    check_input_file(path, "readings or stream file")

    if sniff_kind(path) == "readings":
        return read_readings(path), None
    from gonio.reduce import reduce_stream

    stream = read_stream(path)
    red = reduce_stream(stream, protocol)
    if not len(red.readings):
        raise GonioError("no round of the protocol could be matched in the stream", file=path)
    import tempfile

    from gonio.formats.readings import write_readings
    with tempfile.TemporaryDirectory() as tmp:   # through the file format: same validation
        rd = read_readings(write_readings(red.readings.drop(columns=["t_zero_s", "t_read_s"]),
                                          Path(tmp) / "reduced.csv", red.metadata))
    rd.path = Path(path)
    return rd, static_record_from_stream(stream, red.readings)


def static_record_from_stream(stream, reduced) -> StaticRecord | None:
    """The instrument's continuous record over the 7.3 rest, cut from a stream.

    From the zeroing of the first zero-stability reading to the last one (the
    reduction's ``t_zero_s``/``t_read_s``); counts divided by the nominal scale
    factor. ``None`` when the stream holds no 7.3 rest or no nominal K.
    """
    zs = reduced[reduced["test"] == "zero_stability"]
    k = metadata_float(stream.metadata, "nominal_scale_factor_counts_per_deg")
    if len(zs) < 2 or not k:
        return None
    t0, t1 = float(zs["t_zero_s"].min()), float(zs["t_read_s"].max())
    m = (stream.time_s >= t0) & (stream.time_s <= t1)
    return StaticRecord(stream.time_s[m] - t0, stream.gyro_counts[m] / k,
                        source="stream, 7.3 rest")


def analyse_zero_stability(record: StaticRecord | None):
    """Allan analysis of the 7.3 static record (:func:`gonio.analysis.noise.analyse_static`), or why not."""
    from gonio.analysis.noise import analyse_static

    if record is None:
        return None, ""
    try:
        return analyse_static(record.time_s, record.angle_deg), record.source
    except GonioError as exc:
        return None, f"not analysed: {exc}"


#: A row giving both gyro_deg and gyro_counts must agree through K within this
#: relative tolerance of the angle, or :data:`COUNTS_AGREE_ABS_DEG`, whichever is larger.
COUNTS_AGREE_REL: float = 1e-4
COUNTS_AGREE_ABS_DEG: float = 1e-3


def check_counts_agree(readings: Readings, results: CalibrationResults) -> None:
    """Refuse a row whose ``gyro_deg`` contradicts its ``gyro_counts`` through K.

    K is the scale factor calibrated by 7.1 in the same file, else the metadata's
    nominal one; without K nothing can be compared. Tolerance: the larger of
    :data:`COUNTS_AGREE_REL` × |angle| and :data:`COUNTS_AGREE_ABS_DEG`.
    """
    import numpy as np

    from gonio.errors import GonioError

    sf = results.scale_factor
    k = sf.value if sf.measured and sf.value else metadata_float(
        readings.metadata, "nominal_scale_factor_counts_per_deg", file=readings.path)
    if not k:
        return
    df = readings.data
    deg = df["gyro_deg"].to_numpy(dtype=float)
    cnt = df["gyro_counts"].to_numpy(dtype=float)
    both = ~np.isnan(deg) & ~np.isnan(cnt)
    if not both.any():
        return
    diff = np.abs(deg - cnt / k)
    tol = np.maximum(COUNTS_AGREE_REL * np.abs(deg), COUNTS_AGREE_ABS_DEG)
    bad = both & (diff > tol)
    if bad.any():
        i = int(np.argmax(bad))
        raise GonioError(f"gyro_deg {deg[i]:.9g} contradicts gyro_counts {cnt[i]:.0f} / K "
                         f"{k:.9g} = {cnt[i] / k:.9g} by {diff[i]:.3g}°", file=readings.path,
                         line=int(df["line"].iat[i]), column="gyro_deg")


def calibrate(readings: str | Path | Readings, protocol: str | Path | Protocol = "ogam-draft",
              *, monte_carlo_trials: int = 0, seed: int = 0,
              static_record: StaticRecord | None = None) -> CalibrationReport:
    """Compute the seven characteristics and the Annex A budget from a readings file or stream.

    Items whose readings the file does not hold are reported as not measured. The
    zero-stability result (7.3) comes with the Allan analysis of the instrument's
    record over the 7.3 rest when there is one: cut from the stream, or given as
    ``static_record`` (the virtual bench's).
    """
    proto = protocol if isinstance(protocol, Protocol) else load_protocol(protocol)
    if isinstance(readings, Readings):
        rd, sha = readings, ""
        if rd.path:
            sha = sha256_file(rd.path)
    else:
        rd, from_stream = _load(readings, proto)
        static_record = static_record or from_stream
        sha = sha256_file(readings)
    ref_orient = proto.pointing_reference
    res = compute_characteristics(rd, reference_rate_dps=proto.rate_reference_dps,
                                  reference_orientation=ref_orient)
    check_counts_agree(rd, res)
    budget, src = annex_a_for(res, rd, proto, monte_carlo_trials, seed)
    noise, noise_src = analyse_zero_stability(static_record)
    eda, unused = equal_division_for(res.unused_readings, rd)
    res = dataclasses.replace(res, unused_readings=unused)
    return CalibrationReport(res, budget, rd, proto, sha, src, noise, noise_src, eda)


def equal_division_for(unused: pd.DataFrame, readings: Readings):
    """Analyse the file's ``equal_division`` rows (table calibration, IEC 62047-20 A.3), if any.

    Returns ``(result or None, unused readings)``: a new ``unused_readings`` table
    (the input is not modified) without the rows the analysis used; when they do
    not form a complete measurement the analysis is skipped and the rows stay
    unused, with the reason.
    """
    from gonio.analysis.equal_division import equal_division_from_readings

    rows = readings.data[readings.data["test"] == "equal_division"]
    if not len(rows):
        return None, unused
    lines = set(rows["line"])
    try:
        out = equal_division_from_readings(readings)
    except GonioError as exc:
        # Not a complete equal-division measurement: the rest of the calibration goes
        # on; the rows stay listed as unused, with the reason.
        un = unused.copy()
        if len(un) and "reason" in un.columns:
            un.loc[un["line"].isin(lines), "reason"] = \
                f"equal-division analysis not possible: {exc.message}"
        return None, un
    if len(unused):
        unused = unused[~unused["line"].isin(lines)].reset_index(drop=True)
    return out, unused


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
    from gonio.report.certificate import write_certificate

    out = Path(out) if str(out).strip() else out
    with output_set(out, inputs=inputs, force=force, source_sha256=report.source_sha256) as st:
        if session is not None:
            from gonio.bench import write_session
            write_session(session, out)
        write_calibration(report, out, lab=lab)
        write_certificate(report, out, truth=truth, lab=lab, lang=lang, dcc=dcc)
        names = sorted(p.relative_to(st).as_posix() for p in st.rglob("*") if p.is_file())
    return {n: Path(out) / n for n in names}


def write_calibration(report: CalibrationReport, out: str | Path,
                      lab: dict | None = None) -> dict[str, Path]:
    """Write ``results.json``, ``summary.txt`` and ``tables/*.csv`` into ``out`` atomically.

    ``lab`` (a :func:`gonio.report.certificate.load_lab` dict) adds its conformity statements
    to ``summary.txt``, as the certificate and the CLI show them.
    """
    out = Path(out)
    names = {}
    with output_dir(out) as stage:
        d = report.to_dict()
        write_text(stage / "results.json", json.dumps(d, indent=2, ensure_ascii=False,
                                                      allow_nan=False) + "\n")
        write_text(stage / "summary.txt", report.summary(lab))
        tables = stage / "tables"
        for item in report.results.items():
            for tname, df in (getattr(item, "tables", None) or {}).items():
                if df is not None and len(df):
                    write_text(tables / f"{item.name}_{tname}.csv",
                               df.to_csv(index=False, lineterminator="\n"))
        write_text(tables / "uncertainty_budget.csv",
                   report.uncertainty.table().to_csv(index=False, lineterminator="\n"))
        names = {p.name: out / p.relative_to(stage) for p in stage.rglob("*") if p.is_file()}
    return names
