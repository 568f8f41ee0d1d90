"""What the rate-gyro certificate and its DCC both take from a calibration: the
specification's certificate content (its groups and titles) and the standards used."""

from __future__ import annotations

import string

from gonio.specs import content_field, get


def spec_content(spec_key: str):
    """The specification's certificate data module (GROUPS, TITLES_ZH, HEADING, …), the one
    it names (``Specification.certificate_content``); none named is a GonioError."""
    return get(spec_key).content()


def rate_standards(md: dict, lab: dict | None, not_stated: str = "not stated") -> list[dict]:
    """The standards used: the lab file's ``[[standards]]``, else the readings' equipment
    (``table`` metadata, the rate table's U_rel at k = 2) — the certificate's and the DCC's."""
    if lab and lab.get("standards"):
        return list(lab["standards"])
    return [{"name": md.get("table", not_stated), "identifier": "",
             "accuracy": (f"rate U_rel = {2 * float(md['rate_table_u_rel']):.2g} (k = 2)"
                          if str(md.get("rate_table_u_rel", "") or "").strip() else
                          "rate accuracy within 0.05 % (JJF 1535 Table 2; no certificate u stated)"),
             "certificate": "", "traceability": "none (virtual bench)" if lab is None else not_stated}]


def item_conditions(res: dict, content, lang: str = "en") -> list[tuple[str, str]]:
    """(item key, sentence) of every item whose measurand the specification's certificate
    ``content`` defines in its ``ITEM_CONDITIONS`` (JJF 7.2.9's warm-up time: the window W,
    the block P and the nominal stability), filled from the item's stored details in
    ``lang`` ("en", "zh"): the certificate, summary.txt and the DCC state the same
    sentences. An item not measured, or whose details lack a field of its sentence (a
    result stored before the field existed), has none. An entry may be a function of the
    item's details and ``lang`` instead (a sentence that depends on a decision stored
    there, IEC 5.3.3.5's pooling of the power-on records), returning None where the details
    do not hold it."""
    out = []
    for key, text in content_field(content, "ITEM_CONDITIONS").items():
        it = res["items"].get(key) or {}
        if callable(text):
            s = text(it.get("details") or {}, lang) if it.get("measured") else None
            if s:
                out.append((key, s))
            continue
        tmpl = text[1 if lang == "zh" else 0]
        fields = {f for _, f, _, _ in string.Formatter().parse(tmpl) if f}
        if it.get("measured") and fields <= set(it.get("details") or {}):
            out.append((key, tmpl.format(**it["details"])))
    return out
