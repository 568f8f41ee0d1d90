"""Fixtures shared by several test modules."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
#: The DCC 3.3.0 schema set: the offline copy the repository carries (tests/data/dcc-3.3.0,
#: with its licences), or $GONIO_DCC_SCHEMA_DIR.
SCHEMA_DIR = Path(os.environ.get("GONIO_DCC_SCHEMA_DIR",
                                 REPO / "tests" / "data" / "dcc-3.3.0")).resolve()
QUDT_URL = "https://www.ptb.de/si/v2.2.1/qudt/quantitykind.xsd"


@pytest.fixture(scope="session")
def dcc_schema():
    """The DCC 3.3.0 XSD loaded offline with xmlschema (XSD 1.1), remote access refused."""
    xmlschema = pytest.importorskip("xmlschema", reason="pip install '.[test]'")
    assert (SCHEMA_DIR / "dcc.xsd").is_file(), (
        f"DCC 3.3.0 schema set not found at {SCHEMA_DIR} (set GONIO_DCC_SCHEMA_DIR)")
    return xmlschema.XMLSchema11(
        str(SCHEMA_DIR / "dcc.xsd"),
        uri_mapper={QUDT_URL: (SCHEMA_DIR / "si" / "qudt" / "quantitykind.xsd").as_uri()},
        allow="local")
