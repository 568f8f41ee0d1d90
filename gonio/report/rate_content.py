"""What the rate-gyro certificate and its DCC both take from a calibration: the
specification's certificate content (its groups and titles) and the standards used."""

from __future__ import annotations

from gonio.specs import get


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
             "accuracy": f"rate U_rel = {2 * float(md.get('rate_table_u_rel', 'nan')):.2g} (k = 2)",
             "certificate": "", "traceability": "none (virtual bench)" if lab is None else not_stated}]
