"""Pin test: the numbers are unchanged by the refactors of issue 23 (one specification
interface, one result model), and every specification's results.json has the one documented
shape (docs/results.schema.json, checked with jsonschema).

For each specification, one virtual calibration (``gonio simulate`` then ``gonio
calibrate``, seed 7, the small programmes of tests/data/pins/) must give every item the value
and U stored in tests/data/pins/pins.json, which tests/data/pins/make_pins.py made from main
before the refactors (commit ae98dc5). Compared to 1e-12 relative (the same code gives the
same bits; the margin only allows a summation reordered on purpose). A deliberate change of
a number regenerates the pins with that script; its commit says which numbers changed and
why.
"""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import pytest

from gonio.result.model import Result

ROOT = Path(__file__).resolve().parents[1]
HERE = ROOT / "tests" / "data" / "pins"
_spec = importlib.util.spec_from_file_location("make_pins", HERE / "make_pins.py")
make_pins = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(make_pins)
PINS = json.loads((HERE / "pins.json").read_text(encoding="utf-8"))
SPECS = [r[0] for r in make_pins.RUNS]


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """results.json of each specification's pinned run (made once for the module)."""
    out = {}
    for spec, protocol, seed in make_pins.RUNS:
        out[spec] = make_pins.results(spec, protocol, seed, tmp_path_factory.mktemp(spec))
    return out


@pytest.fixture(scope="module")
def validator():
    jsonschema = pytest.importorskip("jsonschema", reason="pip install '.[test]'")
    schema = json.loads((ROOT / "docs" / "results.schema.json").read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def _same(a, b) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-300)


def changed_items(pinned: dict, now: dict) -> dict:
    return {k: (pinned[k], now.get(k)) for k in sorted(set(pinned) | set(now))
            if k not in now or k not in pinned
            or not (_same(now[k]["value"], pinned[k]["value"])
                    and _same(now[k]["U"], pinned[k]["U"]))}


@pytest.mark.parametrize("spec", SPECS)
def test_numbers_unchanged(spec, results):
    pinned = PINS[spec]
    run = dict(zip(SPECS, make_pins.RUNS))[spec]
    assert (pinned["protocol"], pinned["seed"]) == run[1:]
    assert changed_items(pinned["items"], make_pins.item_numbers(results[spec])) == {}


@pytest.mark.parametrize("spec", SPECS)
def test_results_json_has_the_one_shape(spec, results, validator):
    d = results[spec]
    errors = [f"{e.json_path}: {e.message}" for e in validator.iter_errors(d)]
    assert errors == []
    assert d["spec"] == spec
    r = Result.from_json(d)
    assert r.to_json() == d                      # nothing lost on the way back
    assert all(it.measured for it in r.items.values() if it.key in PINS[spec]["items"]
               and PINS[spec]["items"][it.key]["value"] is not None)


def test_pins_and_schema_can_fail(validator):
    """The reader finds both shapes, a changed U is seen, a broken results.json refused."""
    old = {"items": {"K": {"value": 1.0, "measured": True, "uncertainty": {"U": 0.1}}}}
    new = {"version": 1, "items": {"K": {"value": 1.0, "measured": True,
                                         "uncertainty": {"U": 0.1 * (1 + 1e-9)}}}}
    a, b = make_pins.item_numbers(old), make_pins.item_numbers(new)
    assert changed_items(a, b) == {"K": (a["K"], b["K"])}
    assert changed_items(a, {}) != {}
    bad = {"version": 1, "spec": "x", "items": {"K": {"value": "1.0"}}}
    assert len(list(validator.iter_errors(bad))) >= 3
