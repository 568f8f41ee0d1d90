"""The laboratory's settings form refuses a guard-band factor r < 1 for a rule with a guard
band (guarded, non-binary) when it is saved, as a laboratory file's ``[decision_rule]`` is
refused (ILAC-G8:09/2019 4.2.2), not when a calibration is decided with it; and a calibration
page names its instrument's owner once, also the import's placeholder customer
``(imported)`` (it read "((imported))").

Through HTTP (Starlette's TestClient) and the Python function behind the form
(:func:`gonio.records.services.set_settings`), on SQLite and PostgreSQL. The truths: r ≥ 1 is
the rule's bound, written here; the owner's name is the one registered here."""

from __future__ import annotations

import html
import re

import pytest

from gonio.errors import GonioError
from gonio.records import services

from .conftest import make_people
from .test_web_numbers import web_client


def _form(client, **changed) -> dict:
    """The settings form as the users page fills it (its csrf and every setting's current
    value), with ``changed``."""
    page = client.get("/users").text
    data = {"csrf": re.search(r'name="csrf" value="([^"]+)"', page).group(1)}
    for k in services.SETTINGS:
        m = re.search(rf'name="{k}"(?: value="([^"]*)"| rows="2">([^<]*)</textarea>)', page)
        data[k] = html.unescape(m.group(1) if m.group(1) is not None else m.group(2))
    return data | changed


@pytest.mark.parametrize("factor", ["0.5", "0.999", "0"])
def test_settings_form_refuses_a_guard_band_below_one(store, factor):
    """r < 1 with the default non-binary rule: the form comes back (400) with one line naming
    guard_band_factor; nothing is stored, the factor stays 1.0."""
    make_people(store)
    admin = web_client(store, "admin")
    r = admin.post("/settings", data=_form(admin, guard_band_factor=factor))
    assert r.status_code == 400
    shown = html.unescape(r.text)
    assert "guard_band_factor" in shown and "r ≥ 1" in shown and f"got {float(factor):g}" in shown
    assert services.settings(store)["guard_band_factor"] == "1.0"
    ok = admin.post("/settings", data=_form(admin, guard_band_factor="1"))
    assert ok.status_code == 303, ok.text
    assert services.settings(store)["guard_band_factor"] == "1"


def test_set_settings_checks_rule_and_factor_together(store):
    """The Python function behind the form: r < 1 is taken with the simple rule (which has no
    guard band) and then refused as soon as the rule would become guarded or non-binary,
    naming the field changed; either way the settings stay as they were."""
    admin = make_people(store)["admin"]
    with pytest.raises(GonioError) as exc:
        services.set_settings(store, admin, guard_band_factor="0.5")
    assert exc.value.key == "guard_band_factor" and "\n" not in str(exc.value)
    services.set_settings(store, admin, decision_rule="simple", guard_band_factor="0.5")
    for rule in ("guarded", "non-binary"):
        with pytest.raises(GonioError) as exc:
            services.set_settings(store, admin, decision_rule=rule)
        assert exc.value.key == "decision_rule" and f"{rule} needs guard_band_factor r ≥ 1" \
            in exc.value.message
    assert {k: services.settings(store)[k] for k in ("decision_rule", "guard_band_factor")} \
        == {"decision_rule": "simple", "guard_band_factor": "0.5"}
    services.set_settings(store, admin, decision_rule="guarded", guard_band_factor="2")
    assert services.settings(store)["guard_band_factor"] == "2"


def test_calibration_page_names_the_imported_owner_once(store, bench_readings):
    """An instrument of the import's placeholder customer ``(imported)``: its calibration
    page names the owner as registered, never in doubled parentheses."""
    people = make_people(store)
    tech = people["tech"]
    cust = services.add_customer(store, tech, "(imported)")
    inst = services.register_instrument(store, tech, customer_id=cust.id, serial="RLG-0001",
                                        spec_key="ogam-draft")
    std = services.add_standard(store, tech, name="rotary table", identifier="RT-07",
                                due_on="2099-01-01")
    with open(bench_readings[0], "rb") as fh:
        sha, _ = services.store_file(store, fh)
    cal = services.create_calibration(store, tech, instrument_id=inst.id, readings_sha256=sha,
                                      standard_ids=[std.id], temperature_c=20.0,
                                      humidity_pct=45.0)
    text = html.unescape(web_client(store).get(f"/calibrations/{cal.id}").text)
    assert "RLG-0001" in text and "owner (imported)" in text
    assert "((" not in text
