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

from gonio.report.header import room_temperature_keys
from gonio.report.rate_certificate import write_rate_certificate
from gonio.report.rate_content import item_conditions, spec_content
from gonio.specs import get
from gonio.result.tables import write_results

#: The certificate content fields this renderer reads without a default (checked by
#: ``Specification.renderer``).
CONTENT_REQUIRED = ("GROUPS", "TITLES_ZH", "HEADING")


def results_json(result, lab: dict | None = None) -> dict:
    """The ``results.json`` content."""
    return result.to_json()


def summary(result, lab: dict | None = None) -> str:
    """The summary printed and written to ``summary.txt`` (``lab``: the laboratory file the
    certificate is issued with): the result's lines
    (:meth:`~gonio.result.model.Result.summary`) with the certificate's guard-band note
    under its conformity decisions (:func:`band_notes`), then the sentences that define
    an item's measurand as the certificate states them (:func:`gonio.report.rate_content.item_conditions`,
    e.g. JJF 7.2.9's window W, block P and nominal stability)."""
    res = result.to_json()
    text = result.summary(lab, room_temperature_keys(result.spec_key), band_notes(res))
    if result.spec_key and get(result.spec_key).certificate_content:
        conditions = item_conditions(res, spec_content(result.spec_key))
        text += "".join(f"note: {t}\n" for _, t in conditions)
    return text


def band_notes(res: dict) -> tuple[str, ...]:
    """The certificate's guard-band note of the items decided on their interval alone
    (:func:`gonio.report.stated.interval_band_note`, in English, each item named and its
    unit written as the certificate's conformity table does: δ read off the printed ends,
    w = r·δ, and the "≤ q %" false-accept bound 1 − p), for summary.txt's conformity
    section; () where no such item was decided. ``res``: results.json."""
    from gonio.report.i18n import labels
    from gonio.report.stated import interval_band_note, stated_p
    from gonio.result.statement import unit_text

    items = res.get("items") or {}
    decided = [(k, it["conformity"]) for k, it in items.items() if it.get("conformity")]
    L = labels("en")
    band = interval_band_note(decided, L, lambda k: items[k].get("title") or k,
                              lambda k: unit_text(items[k].get("unit")) or L["unit_one"],
                              lambda k: stated_p(items[k]))
    return (band,) if band else ()


def item_titles(res: dict, lang: str = "en") -> dict[str, str]:
    """Each item's name as the certificate in ``lang`` names it (``res``: results.json): the
    English title, or in Chinese the specification's ``TITLES_ZH``, else its title through
    the specification's ``PHRASES_ZH`` and the shared tables (as the certificate's results
    table and the DCC's translation: :func:`gonio.report.rate_certificate.dcc_translator`);
    a title no table knows stays as written."""
    from gonio.report.i18n import labels, reason_text
    from gonio.report.rate_content import spec_content
    from gonio.specs import get

    items = res.get("items") or {}
    if lang != "zh":
        return {k: it.get("title") or k for k, it in items.items()}
    data = spec_content(res["spec"]) if get(res["spec"]).certificate_content else None
    titles = dict(getattr(data, "TITLES_ZH", None) or {})
    phrases = tuple(getattr(data, "PHRASES_ZH", None) or ())
    L = labels("zh")
    return {k: titles.get(k) or reason_text(it.get("title") or k, L, phrases)
            for k, it in items.items()}


def write(result, out, *, truth: dict | None = None, lab=None, lang: str = "en",
          dcc: bool = False) -> dict[str, Path]:
    """results.json, summary.txt, tables (:func:`gonio.result.tables.write_results`) and
    the certificate (``dcc``: its DCC XML) of the stored ``result`` into ``out``: its
    conformity decisions rendered as the pipeline made them."""
    out = Path(out)
    paths = write_results(result, out, lab, summary(result, lab))
    paths.update(write_rate_certificate(result, out, truth=truth, lab=lab, lang=lang, dcc=dcc))
    return paths
