"""Pin test: the numbers are unchanged by the refactors of issue 23 (one specification
interface, one result model), and every specification's results.json has the one documented
shape (docs/results.schema.json, checked with jsonschema).

For each specification, one virtual calibration (``gonio simulate`` then ``gonio
calibrate``, seed 7, the small programmes of tests/data/pins/) must give every item the value
and U stored in tests/data/pins/pins.json, which tests/data/pins/make_pins.py made from main
before the refactors (commit ae98dc5). Two comparisons:

- the stated numbers (value and U rounded by the one statement rule,
  :func:`gonio.result.statement.state`: what a certificate prints) must be equal, character
  for character;
- the raw floats must agree to :data:`RAW_REL_TOL` relative. The same code does not give the
  same bits on every machine: another CPU, or another BLAS kernel for the same NumPy
  (OpenBLAS picks SkylakeX, Haswell or Zen code at run time), sums in another order. On an AMD
  EPYC with OpenBLAS' SkylakeX kernel six triad U differed by 1e-12 to 8e-11 relative; 1e-9
  leaves an order of magnitude above that and is still 10⁵ times finer than any statement
  (two significant digits of U).

A deliberate change of a number regenerates the pins with that script; its commit says which
numbers changed and why.
"""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import pytest

from gonio.result.model import Result
from gonio.result.statement import state

#: Relative tolerance of the raw floats (see the module docstring: CPUs and BLAS kernels).
RAW_REL_TOL = 1e-9

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
    return math.isclose(a, b, rel_tol=RAW_REL_TOL, abs_tol=1e-300)


def stated(numbers: dict) -> str:
    """The item's value and U as the statement rule prints them."""
    return state(numbers["value"], numbers["U"]).text()


def changed_items(pinned: dict, now: dict) -> dict:
    """{item: (pinned, now)} of the items whose statement or raw floats differ."""
    return {k: (pinned[k], now.get(k)) for k in sorted(set(pinned) | set(now))
            if k not in now or k not in pinned
            or stated(now[k]) != stated(pinned[k])
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
                                         "uncertainty": {"U": 0.1 * (1 + 1e-8)}}}}
    a, b = make_pins.item_numbers(old), make_pins.item_numbers(new)
    assert changed_items(a, b) == {"K": (a["K"], b["K"])}
    # another CPU's last bits pass; a stated digit that moves does not, however small
    cpu = {"K": {"value": 1.0 * (1 + 8e-11), "U": 0.1 * (1 - 8e-11)}}
    assert changed_items(a, cpu) == {}
    edge = {"K": {"value": 1.00049999999, "U": 0.012}}
    assert changed_items(edge, {"K": {"value": 1.00050000001, "U": 0.012}}) != {}
    assert changed_items(a, {}) != {}
    bad = {"version": 1, "spec": "x", "items": {"K": {"value": "1.0"}}}
    assert len(list(validator.iter_errors(bad))) >= 3
