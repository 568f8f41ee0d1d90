"""The per-item specifications' rendering side (``SPEC.outputs`` of the rate specifications,
reused by the triad and by plug-ins whose result is a :class:`gonio.result.model.Result`):
conformity decided for every item a laboratory file limits, results.json, summary.txt,
tables, the certificate (HTML, PDF) and its DCC XML.

Imported by the pipeline through the registry (it may import the report); the calibration
path never imports it.
"""

from __future__ import annotations

from pathlib import Path

from gonio.analysis.conformity import DEFAULT_LIMITS_ORIGIN, decide_result
from gonio.specs import default_limits
from gonio.report.rate_certificate import write_rate_certificate
from gonio.result.tables import write_results

#: The certificate content fields this renderer reads without a default (checked by
#: ``Specification.renderer``).
CONTENT_REQUIRED = ("GROUPS", "TITLES_ZH", "HEADING")


def results_json(result, lab: dict | None = None) -> dict:
    """The ``results.json`` content."""
    return result.to_json()


def summary(result, lab: dict | None = None) -> str:
    """The summary printed and written to ``summary.txt``."""
    return result.summary()


def write(result, out, *, truth: dict | None = None, lab=None, lang: str = "en",
          dcc: bool = False) -> dict[str, Path]:
    """Conformity decided (:func:`gonio.analysis.conformity.decide_result`), then
    results.json, summary.txt, tables (:func:`gonio.result.tables.write_results`) and the
    certificate (``dcc``: its DCC XML) into ``out``."""
    decide_result(result, lab, default_limits(result.spec_key), DEFAULT_LIMITS_ORIGIN)
    out = Path(out)
    paths = write_results(result, out)
    paths.update(write_rate_certificate(result, out, truth=truth, lab=lab, lang=lang, dcc=dcc))
    return paths
