"""The rate specifications' rendering side (``SPEC.outputs``): results.json, summary.txt,
the certificate (HTML, PDF) and its DCC XML of a rate result.

Imported by the pipeline through the registry (it may import the report); the calibration
path never imports it.
"""

from __future__ import annotations

import json
from pathlib import Path

from gonio.atomic import output_dir, write_text
from gonio.report.rate_certificate import write_rate_certificate


def results_json(result) -> dict:
    """The ``results.json`` content."""
    return result.to_json()


def summary(result, lab: dict | None = None) -> str:
    """The summary printed and written to ``summary.txt``."""
    return result.summary()


def write(result, out, *, truth: dict | None = None, lab=None, lang: str = "en",
          dcc: bool = False) -> dict[str, Path]:
    """results.json, summary.txt and the certificate (``dcc``: its DCC XML) into ``out``."""
    out = Path(out)
    with output_dir(out) as stage:
        write_text(stage / "results.json", json.dumps(results_json(result), indent=2,
                                                      ensure_ascii=False, allow_nan=False) + "\n")
        write_text(stage / "summary.txt", summary(result))
    paths = {"results": out / "results.json", "summary": out / "summary.txt"}
    paths.update(write_rate_certificate(result, out, truth=truth, lab=lab, lang=lang, dcc=dcc))
    return paths
