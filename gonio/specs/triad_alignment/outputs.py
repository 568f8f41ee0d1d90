"""The gyro triad's rendering side (``SPEC.outputs``): ``results.json``, ``summary.txt``,
``tables/*.csv`` and the certificate of a triad result, and the demo (simulate + calibrate as
one staged output set).

Imported by the pipeline through the registry (it may import the report and the bench);
the calibration path never imports it.
"""

from __future__ import annotations

import json
from pathlib import Path

from gonio.atomic import output_dir, output_set, write_text
from gonio.report.triad_certificate import write_triad_certificate
from gonio.specs._rate_family.outputs import results_json, summary  # noqa: F401  (per-item result)


def write(result, out, *, truth: dict | None = None, lab=None, lang: str = "en",
          dcc: bool = False) -> dict[str, Path]:
    """``results.json``, ``summary.txt``, ``tables/*.csv``, ``certificate.html`` and
    ``certificate.pdf`` into ``out`` (each atomically; the caller stages the set). Returns
    the paths."""
    out = Path(out)
    tables = result_tables(result)
    with output_dir(out) as stage:
        write_text(stage / "results.json", json.dumps(results_json(result), indent=2,
                                                      ensure_ascii=False, allow_nan=False) + "\n")
        write_text(stage / "summary.txt", summary(result))
        for name, df in tables.items():
            write_text(stage / "tables" / name, df.to_csv(index=False,
                                                          lineterminator="\n"))
    paths = {"results": out / "results.json", "summary": out / "summary.txt"}
    paths.update({f"tables/{n}": out / "tables" / n for n in tables})
    paths.update(write_triad_certificate(result, out, truth=truth, lab=lab, lang=lang,
                                         dcc=dcc))
    return paths


def result_tables(result) -> dict:
    """The result's tables as DataFrames, by file name (``tables/*.csv`` beside results.json):
    ``items.csv`` (every measured item: key, value, unit, u, U, k, ν) and, per
    modelled gyro, ``thermal_prediction_<gyro>.csv`` (the prediction band)."""
    import pandas as pd

    rows = []
    for key, it in result.items.items():
        if not it.measured:
            continue
        u = it.uncertainty
        rows.append({"item": key, "clause": it.clause, "value": it.value, "unit": it.unit,
                     "u": None if u is None else u.u_c, "U": None if u is None else u.U,
                     "k": None if u is None else u.k, "nu": None if u is None else u.nu_eff})
    out = {"items.csv": pd.DataFrame(rows, columns=["item", "clause", "value", "unit", "u", "U",
                                                    "k", "nu"])}
    tm = result.extra.get("thermal_model") or {}
    for ch, pr in (tm.get("prediction_U") or {}).items():
        out[f"thermal_prediction_{ch}.csv"] = pd.DataFrame(
            {k: v for k, v in pr.items() if isinstance(v, list)})
    return out


#: Monte Carlo trials of the demo's uncertainties (JCGM 101 beside the GUM).
DEMO_MONTE_CARLO = 2000


def demo(out, *, bench: str | None = None, seed: int = 0, lab=None, lang: str = "en",
         dcc: bool = False, force: bool = False, inputs=(), on_stage=None,
         monte_carlo_trials: int = DEMO_MONTE_CARLO):
    """Simulate the triad protocol on the bench (readings.csv with the alignment session,
    thermal.csv with the chamber programme, truth.json) and calibrate it with
    ``monte_carlo_trials`` Monte Carlo draws, the whole set staged and swapped into ``out``
    together (:func:`gonio.atomic.output_set`). ``lab``: a loaded laboratory dict."""
    from gonio.specs.triad_alignment import SPEC
    from gonio.specs.triad_alignment.simulate import simulate

    inputs = [x for x in inputs if Path(x).exists()]
    with output_set(out, inputs=inputs, force=force) as stage:
        sim = simulate(SPEC.default_protocol, bench or SPEC.default_bench, seed, out)
        truth = json.loads((stage / "truth.json").read_text(encoding="utf-8"))
        result = SPEC.calibrate(stage / "readings.csv", monte_carlo_trials=monte_carlo_trials)
        paths = write(result, out, truth=truth, lab=lab, lang=lang)
    return result, {**sim, **paths}
