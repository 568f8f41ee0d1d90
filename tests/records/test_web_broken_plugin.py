"""A specification plug-in that cannot be loaded leaves ``gonio serve`` working: the pages
that list the specifications list the others (tests/test_spec_loading.py has the CLI's)."""

from __future__ import annotations

import re

import pytest

import gonio.specs as specs
from gonio.records import services
from gonio.specs import BUILT_IN

PASSWORD = "correct horse battery"


def test_the_instruments_page_lists_the_working_specifications(sqlite_store, monkeypatch):
    pytest.importorskip("fastapi")
    from gonio.web.app import create_app

    services.create_user(sqlite_store, None, "tech", PASSWORD, "technician")
    app = create_app(sqlite_store)
    monkeypatch.setattr(specs, "_entry_points",
                        lambda: {**BUILT_IN, "brk-web": "no_such_module_xyz:SPEC"})
    from fastapi.testclient import TestClient
    c = TestClient(app, follow_redirects=False)
    token = re.search(r'name="csrf" value="([^"]+)"', c.get("/login").text).group(1)
    assert c.post("/login", data={"username": "tech", "password": PASSWORD,
                                  "csrf": token}).status_code == 303
    with pytest.warns(UserWarning, match="'brk-web' is not available"):
        r = c.get("/instruments")
    assert r.status_code == 200
    assert "jjf1535-2015" in r.text and "brk-web" not in r.text
