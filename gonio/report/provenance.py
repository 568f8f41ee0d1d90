"""The virtual-bench marking of every output (certificate pages in HTML and PDF, summary.txt,
the DCC): driven by the result's provenance (:func:`gonio.formats.provenance.result_provenance`:
the readings' own metadata), not by whether a laboratory file was given. Readings from the
virtual bench are marked whatever the laboratory file says; no option turns the mark off
(docs/formats.md#provenance).
"""

from __future__ import annotations

from collections.abc import Mapping

from gonio.formats.provenance import (metadata_evidence, result_provenance, source_evidence,
                                      watermark_chance)


def is_virtual(res: Mapping, lab: dict | None) -> bool:
    """Whether the outputs of results ``res`` (a results.json dict) are marked virtual: the
    readings come from the virtual bench, or no laboratory file was given (an example)."""
    return lab is None or bool(result_provenance(res)["virtual"])


def virtual_lines(res: Mapping, L: dict) -> list[str]:
    """The notice's sentences: what a virtual-bench output is and, where the readings say
    so, which bench and seed made them (``L``: the page's labels)."""
    prov = result_provenance(res)
    out = [L["virtual_note"]]
    if prov["virtual"] and prov["bench"] and prov["seed"]:
        out.append(L["virtual_source"].format(bench=prov["bench"], seed=prov["seed"]))
    elif prov["virtual"] and metadata_evidence(prov):   # the bench's or seed's line deleted
        keys = ", ".join(f"# {k}" for k in metadata_evidence(prov))
        out.append(L["virtual_evidence"].format(keys=keys))
    elif prov["virtual"] and source_evidence(prov):    # a derived result's source: the bench's
        out.append(L["virtual_derived"].format(files=", ".join(source_evidence(prov))))
    elif prov["virtual"]:                      # every bench line deleted: the values' watermark
        wm = prov.get("watermark") or {}
        out.append(L["virtual_watermark"].format(cells=wm.get("cells", "?"),
                                                 p=watermark_chance(wm.get("p_value"))))
    return out


def virtual_text(res: Mapping, L: dict, lab: dict | None) -> str:
    """The mark as one paragraph (banner, then the notice), or "" for measured readings with
    a laboratory file."""
    if not is_virtual(res, lab):
        return ""
    return " ".join([L["virtual"] + "."] + virtual_lines(res, L))
