"""The rendering side of a per-item result (``SPEC.outputs`` of every specification whose
``calibrate`` returns a :class:`gonio.result.model.Result` of items, built in or a plug-in:
the kit's ``gonio.kit.ITEM_RENDERER``):
results.json, summary.txt, tables, the certificate (HTML, PDF) and its DCC XML, a function
of the stored result (the conformity decisions in it are the pipeline's,
:func:`gonio.pipeline.dispatch.decide_conformity`; nothing here decides).

Loaded by the pipeline through the registry (``SPEC.outputs``), never by name; the
calibration path never imports it.
"""

from __future__ import annotations

from pathlib import Path

from gonio.report.rate_certificate import write_rate_certificate
from gonio.result.tables import write_results

#: The certificate content fields this renderer reads without a default (checked by
#: ``Specification.renderer``).
CONTENT_REQUIRED = ("GROUPS", "TITLES_ZH", "HEADING")


def results_json(result, lab: dict | None = None) -> dict:
    """The ``results.json`` content."""
    return result.to_json()


def summary(result, lab: dict | None = None) -> str:
    """The summary printed and written to ``summary.txt`` (``lab``: the laboratory file the
    certificate is issued with)."""
    return result.summary(lab)


def write(result, out, *, truth: dict | None = None, lab=None, lang: str = "en",
          dcc: bool = False) -> dict[str, Path]:
    """results.json, summary.txt, tables (:func:`gonio.result.tables.write_results`) and
    the certificate (``dcc``: its DCC XML) of the stored ``result`` into ``out``: its
    conformity decisions rendered as the pipeline made them."""
    out = Path(out)
    paths = write_results(result, out, lab)
    paths.update(write_rate_certificate(result, out, truth=truth, lab=lab, lang=lang, dcc=dcc))
    return paths
