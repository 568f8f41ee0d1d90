"""Simulate the triad-alignment protocol on a virtual triad bench."""

from __future__ import annotations

import json
import math
from pathlib import Path

from gonio.atomic import output_dir
from gonio.formats.watermark import mark_text
import numpy as np

from gonio.specs.triad_alignment.bench import (load_triad_bench, load_triad_protocol, run_alignment_session,
                               run_thermal_session)
from gonio.specs.triad_alignment.readings import TriadReadings, format_triad_readings
from gonio.specs.triad_alignment.calibration import KEY


def simulate(protocol: str = "triad-alignment", bench="mems-triad", seed: int = 0,
             out: str | Path = ".") -> dict:
    """Run the alignment session (→ ``readings.csv``) and, when the protocol's [thermal]
    table is enabled, the chamber programme (→ ``thermal.csv``, named by the readings'
    ``# thermal_readings:`` metadata); ``truth.json`` holds the
    bench's true values. All files are written atomically; same seed → same bytes."""
    p = load_triad_protocol(protocol, KEY)
    b = load_triad_bench(bench)
    al = run_alignment_session(p, b, seed)
    md = dict(al.metadata)
    files = {}
    if p.thermal.get("enabled"):
        th = run_thermal_session(p, b, seed)
        md["thermal_readings"] = "thermal.csv"     # the readings name their thermal programme
        files["thermal.csv"] = mark_text(format_triad_readings(th.readings, th.metadata))
    # the bench's watermark in its measured values (gonio.formats.watermark)
    files = {"readings.csv": mark_text(format_triad_readings(al.readings, md)), **files}
    files["truth.json"] = json.dumps(al.truth, indent=2, sort_keys=True) + "\n"
    with output_dir(out) as stage:
        for name, text in files.items():
            (stage / name).write_text(text, encoding="utf-8")
    return {name: Path(out) / name for name in files}


def for_trial(bench, seed: int):
    """The triad bench (a name, path or :class:`~gonio.specs.triad_alignment.bench.TriadBench`)
    one coverage trial runs on: the rate table's Type B errors drawn from ``seed`` — its rate
    error by :func:`gonio.bench.equipment.draw_equipment` (normal with the certificate's u,
    as the rate benches draw it) and its spin axis at each of the three orientations, each
    component of δ_a uniform in ±``orientation_bound_deg`` (the fixture's bound, as the rate
    benches draw a gyro in its fixture) from a stream of its own. The triad itself (the
    measurand) is unchanged, and so is its truth.

    >>> b = for_trial("mems-triad", 5)
    >>> b.rate_error_rel != 0, float(np.max(np.abs(b.orientation_error_rad))) <= math.radians(b.orientation_bound_deg)
    (True, True)
    >>> float(np.max(np.abs(np.diag(b.orientation_error_rad)))), for_trial(b, 5).rate_error_rel == b.rate_error_rel
    (0.0, True)
    """
    from dataclasses import replace

    from gonio.bench.equipment import EQUIPMENT_STREAM, Equipment, draw_equipment

    b = load_triad_bench(bench)
    eq = draw_equipment(Equipment(rate_table_u_rel=b.rate_table_u_rel,
                                  axis_alignment_bound_deg=b.orientation_bound_deg), int(seed))
    rng = np.random.default_rng([int(seed), EQUIPMENT_STREAM, 3])
    bound = math.radians(b.orientation_bound_deg)
    d = rng.uniform(-bound, bound, (3, 3)) * (1.0 - np.eye(3))
    return replace(b, rate_error_rel=eq.rate_table.rate_error_rel, orientation_error_rad=d)


def thermal_trial(seed: int, *, protocol: str = "triad-alignment", bench: str = "mems-triad",
                  criterion: str = "bic", draw: bool = True) -> dict[str, dict]:
    """One simulated programme (the chamber programme and, for its static record, the
    alignment session) identified as ``calibrate`` does, every certified thermal value
    (``K_z_t1_v2``, ``b_z_t3_v1``, ``ARW_z_t2`` …; an ARW value stated by its one-sided χ²
    interval carries {interval, nu}, :func:`gonio.analysis.coverage.stated_record`) against
    the bench's closed-form truth
    (``SPEC.truth``, :mod:`gonio.specs.triad_alignment.truth`, from
    :func:`gonio.specs.triad_alignment.bench.true_thermal_coefficients`): {key: {clause, value, truth, U,
    u_c}}, the records of :func:`gonio.pipeline.coverage.coverage_table_from`. ``draw``: the
    rate table's errors drawn from the seed (:func:`for_trial`; its rate error scales every
    K) and the K values carry the table's Type B line as ``calibrate`` gives it; False: the
    bench file's table in every trial."""
    from gonio.analysis.coverage import bound_record, stated_record
    from gonio.specs.triad_alignment.calibration import (fit_alignment, thermal_flicker,
                                                         thermal_items, thermal_long_term)
    from gonio.specs.triad_alignment.thermal_model import identify_thermal_model

    from gonio.specs.triad_alignment.truth import truth

    p = load_triad_protocol(protocol, KEY)
    b = for_trial(bench, int(seed)) if draw else load_triad_bench(bench)
    s = run_thermal_session(p, b, int(seed))
    r = TriadReadings(s.readings.assign(line=np.arange(len(s.readings)) + 1), s.metadata, None)
    th = identify_thermal_model(r, criterion=criterion, ramps=False)
    a = run_alignment_session(p, b, int(seed))       # its static record: the long-term term
    ra = TriadReadings(a.readings.assign(line=np.arange(len(a.readings)) + 1), a.metadata, None)
    al = fit_alignment(ra)                      # calibrate's call
    true = truth(b, p)                          # SPEC.truth: one truth hook
    out = {}
    for key, it in thermal_items(th, "", thermal_long_term(al, ra, th),
                                 r.table_metadata("rate_table_u_rel"),
                                 flicker=thermal_flicker(al, ra, th)).items():
        out[key] = {"clause": it.clause, "value": float(it.value),
                    "truth": float(true[key]["value"]),
                    "U": float(it.uncertainty.U), "u_c": float(it.uncertainty.u_c),
                    **stated_record(it.uncertainty), **bound_record(it)}
    return out
