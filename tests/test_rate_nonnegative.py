"""Rate items that are non-negative by definition (review of stop 28: "threshold 0.010 ±
0.088 °/s" stated with no bound): each is declared in its specification's NONNEGATIVE, is ≥ 0
on simulated readings, and where U exceeds the value results.json and the statement carry
the upper bound value + U rounded up."""

from __future__ import annotations

import importlib
from decimal import Decimal

import pytest

from gonio.pipeline.coverage import reduced_protocol
from gonio.pipeline.dispatch import simulate as simulate_files
from gonio.specs import get

PACKAGES = {"jjf1535-2015": "gonio.specs.jjf1535.items",
            "iec62047-20": "gonio.specs.iec62047_20.items"}


@pytest.fixture(scope="module", params=sorted(PACKAGES))
def calibrated(request, tmp_path_factory):
    spec = request.param
    tmp = tmp_path_factory.mktemp(spec)
    proto = reduced_protocol(spec, tmp / "p.toml", {"arw" if spec.startswith("jjf") else "noise":
                                                    {"samples": 3000}})
    files = simulate_files(spec, tmp / "sim", protocol=str(proto), seed=5)
    return spec, get(spec).calibrate(str(files["readings"]), str(proto)).to_json()


def test_declared_items_exist_and_are_non_negative(calibrated):
    spec, js = calibrated
    nonneg = importlib.import_module(PACKAGES[spec]).NONNEGATIVE
    assert nonneg <= set(js["items"]), nonneg - set(js["items"])
    for key, it in js["items"].items():
        assert it["nonnegative"] == (key in nonneg), key
        if key in nonneg and it["measured"]:
            assert it["value"] >= 0, (key, it["value"])


def test_upper_bound_where_U_exceeds_the_value(calibrated):
    spec, js = calibrated
    # U above the value, or a dispersion stated by its χ² interval [0, value + U] (k null);
    # an interval above 0 (JJF 7.2.6/7.2.7: the 50 % rule's outcome range) is two-sided
    def from_zero(u):
        return u["k"] is None and (u.get("interval") is None or u["interval"][0] == 0)
    wide = [(k, it) for k, it in js["items"].items() if it["nonnegative"] and it["measured"]
            and it["uncertainty"] and ((it["uncertainty"]["U"] > it["value"]
                                        and it["uncertainty"]["k"] is not None)
                                       or from_zero(it["uncertainty"]))]
    for key, it in js["items"].items():
        if (key, it) not in wide:
            assert it.get("upper_bound") in (None, {}) or not it["upper_bound"].get("upper"), key
    for key, it in wide:
        ub = it["upper_bound"]
        bound = Decimal(str(ub["upper"] if isinstance(ub, dict) else ub).split()[0])
        assert bound >= Decimal(repr(it["value"])) + Decimal(repr(it["uncertainty"]["U"])) \
            - Decimal("1e-12"), key
