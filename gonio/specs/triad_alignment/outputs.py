"""The gyro triad's rendering side (``SPEC.outputs``): ``results.json``, ``summary.txt``,
``tables/*.csv`` and the certificate of a triad result, and the demo (simulate + calibrate as
one staged output set).

Imported by the pipeline through the registry (it may import the report and the bench);
the calibration path never imports it.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

from gonio.atomic import output_set
from gonio.specs.triad_alignment.certificate_pages import write_triad_certificate
from gonio.result.tables import write_results
from gonio.report.item_outputs import item_titles, results_json, summary  # noqa: F401


def write(result, out, *, truth: dict | None = None, lab=None, lang: str = "en",
          dcc: bool = False) -> dict[str, Path]:
    """``results.json``, ``summary.txt``, ``tables/*.csv``
    (:func:`gonio.result.tables.write_results`; the thermal prediction bands from the stored
    ``extra.thermal_model``), the certificate (HTML, PDF; ``dcc``: its DCC XML) into ``out``
    (the caller stages the set): a function of the stored result, whose conformity decisions
    the pipeline made (:func:`gonio.pipeline.dispatch.decide_conformity`) and this renders."""
    from gonio.specs.triad_alignment.calibration import prediction_tables

    result = dataclasses.replace(result, tables=prediction_tables(
        result.extra.get("thermal_model")))
    out = Path(out)
    paths = write_results(result, out, lab, summary(result, lab))
    paths.update(write_triad_certificate(result, out, truth=truth, lab=lab, lang=lang,
                                         dcc=dcc))
    return paths


#: Monte Carlo trials of the demo's uncertainties (JCGM 101 beside the GUM).
DEMO_MONTE_CARLO = 2000


def demo(out, *, bench: str | None = None, seed: int = 0, lab=None, lang: str = "en",
         dcc: bool = False, force: bool = False, inputs=(), on_stage=None,
         monte_carlo_trials: int = DEMO_MONTE_CARLO, identity=None):
    """Simulate the triad protocol on the bench (readings.csv with the alignment session,
    thermal.csv with the chamber programme, truth.json) and calibrate it with
    ``monte_carlo_trials`` Monte Carlo draws, the whole set staged and swapped into ``out``
    together (:func:`gonio.atomic.output_set`; its manifest records ``monte_carlo_trials`` as
    ``calibrate_options``, :func:`gonio.pipeline.dispatch.manifest_record`). ``lab``: a loaded
    laboratory dict. ``identity(readings)``: the findings of comparing the simulated
    readings with it (the pipeline's), stated with the result's."""
    from gonio.specs.triad_alignment import SPEC
    from gonio.specs import decide_conformity
    from gonio.specs.triad_alignment.simulate import simulate

    inputs = [x for x in inputs if Path(x).exists()]
    # the options it calibrates with, recorded as gonio calibrate records them: the folder
    # can be computed again from its files (gonio db import)
    extra = {"calibrate_options": {"monte_carlo_trials": int(monte_carlo_trials)}} \
        if monte_carlo_trials else None
    with output_set(out, inputs=inputs, force=force, extra=extra,
                    writes=("readings.csv", "truth.json")) as stage:
        sim = simulate(SPEC.default_protocol, bench or SPEC.default_bench, seed, out)
        truth = json.loads((stage / "truth.json").read_text(encoding="utf-8"))
        result = SPEC.calibrate(stage / "readings.csv", monte_carlo_trials=monte_carlo_trials)
        if identity is not None:
            result.findings = list(result.findings) + identity(stage / "readings.csv")
        decide_conformity(result, lab)
        paths = write(result, out, truth=truth, lab=lab, lang=lang, dcc=dcc)
    return result, {**sim, **paths}
