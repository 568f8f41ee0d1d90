"""The gyro-triad pipeline (``triad-alignment``): calibrate a triad readings file into
``results.json``, ``summary.txt`` and the certificate, and the demo (simulate + calibrate as
one staged output set, like the optical demo).

Every function returns data (the result, the paths); ``gonio calibrate`` and ``gonio demo
--spec triad-alignment`` are thin layers over them.
"""

from __future__ import annotations

import json
from pathlib import Path

from gonio.atomic import output_set
from gonio.report.certificate import load_lab
from gonio.report.triad_certificate import write_triad_certificate
from gonio.analysis.conformity import decide_result
from gonio.result.tables import write_results
from gonio.specs import get

KEY = "triad-alignment"


def calibrate(readings, out, *, thermal=None, lab=None, lang: str = "en", truth=None,
              monte_carlo_trials: int = 0, robust: bool = False, dcc: bool = False):
    """Calibrate a triad readings file (:func:`gonio.specs.triad_alignment.calibration.calibrate`;
    the thermal programme from ``thermal`` or the readings' ``# thermal_readings:``) and write
    ``results.json``, ``summary.txt``, ``certificate.html`` and ``certificate.pdf`` into
    ``out`` (each atomically). Returns (result, paths)."""
    lab_d = load_lab(lab) if isinstance(lab, (str, Path)) else lab
    result = get(KEY).calibrate(readings, monte_carlo_trials=monte_carlo_trials, robust=robust,
                                thermal=thermal)
    decide_result(result, lab_d)
    out = Path(out)
    paths = write_results(result, out)
    paths.update(write_triad_certificate(result, out, truth=truth, lab=lab_d, lang=lang,
                                         dcc=dcc))
    return result, paths


#: Monte Carlo trials of the demo's uncertainties (JCGM 101 beside the GUM).
DEMO_MONTE_CARLO = 2000


def demo(out, *, bench: str | None = None, seed: int = 0, lab=None, lang: str = "en",
         force: bool = False, monte_carlo_trials: int = DEMO_MONTE_CARLO):
    """Simulate the triad protocol on the bench (readings.csv with the alignment session,
    thermal.csv with the chamber programme, truth.json) and calibrate it, the whole set
    staged and swapped into ``out`` together (:func:`gonio.atomic.output_set`)."""
    from gonio.specs.triad_alignment.simulate import simulate

    spec = get(KEY)
    lab_d = load_lab(lab) if lab else None          # validate inputs before simulating
    inputs = [x for x in (lab, bench) if isinstance(x, (str, Path)) and Path(x).exists()]
    with output_set(out, inputs=inputs, force=force) as stage:
        sim = simulate(spec.default_protocol, bench or spec.default_bench, seed, out)
        truth = json.loads((stage / "truth.json").read_text(encoding="utf-8"))
        result, paths = calibrate(stage / "readings.csv", out, lab=lab_d, lang=lang,
                                  truth=truth, monte_carlo_trials=monte_carlo_trials)
    return result, {**sim, **paths}
