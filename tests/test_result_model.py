"""The one result model (gonio.result.model): results.json round trip and schema, the table
writer and summary, and conformity decided for any specification's items (issue 23)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pandas as pd
import pytest

from gonio.analysis.conformity import decide_result
from gonio.errors import GonioError
from gonio.result.findings import Finding
from gonio.result.model import (Covariance, Item, Result, Uncertainty, budget_row,
                                not_measured)
from gonio.result.tables import write_results

SCHEMA = Path(__file__).resolve().parents[1] / "docs" / "results.schema.json"


def rate_like() -> Result:
    """A small result shaped like a rate specification's (a JJF item name among them)."""
    unc = Uncertainty([budget_row("s_B", "repeatability of the bias", 0.02, 1.0, dof=4,
                                  type="A", clause="7.2.8")], 0.02, 0.0555, 2.776, 4.0,
                      coverage_probability=0.95, k_source="welch-satterthwaite")
    items = {"bias": Item("bias", "bias B_0", "7.2.8", "°/h", 0.40, uncertainty=unc,
                          details={"per_run": [0.39, 0.41]}),
             "scale_factor": Item("scale_factor", "scale factor K", "7.2.1", "mV/(°/s)", 6.0,
                                  uncertainty=Uncertainty([], 0.001, 0.002, 2.0, None)),
             "threshold": not_measured("threshold", "threshold", "7.2.6", "°/s",
                                       "no threshold rows")}
    return Result("jjf-like", "a JJF-like specification", items, {"serial": "A-1"},
                  {"file": "r.csv", "sha256": "a" * 64, "rows": 10}, ["a reading taken"],
                  {"annex_a": {"U": 1.0}},
                  findings=[Finding("late", "read 40 s after arrival", "flagged",
                                    file="r.csv", line=7)],
                  covariances=[Covariance(["bias", "scale_factor"], [[4e-4, 1e-6],
                                                                     [1e-6, 1e-6]])])


LAB = {"decision_rule": {"rule": "guarded", "guard_band_factor": 1.0},
       "specification_limits": [{"item": "bias", "mpe": 0.5, "source": "datasheet"},
                                {"item": "threshold", "upper": 0.1}]}


def test_round_trip_and_schema():
    jsonschema = pytest.importorskip("jsonschema")
    r = rate_like()
    decide_result(r, LAB)
    d = json.loads(json.dumps(r.to_json(), allow_nan=False))
    jsonschema.validate(d, json.loads(SCHEMA.read_text(encoding="utf-8")))
    assert Result.from_json(d).to_json() == d
    assert d["items"]["threshold"]["value"] is None and d["items"]["threshold"]["reason"]
    assert d["items"]["bias"]["uncertainty"]["components"][0]["contribution"] == 0.02
    assert d["items"]["bias"]["details"]["per_run"] == [0.39, 0.41]
    assert d["extra"]["annex_a"] == {"U": 1.0}
    with pytest.raises(GonioError, match="version"):
        Result.from_json({**d, "version": 0})
    with pytest.raises(GonioError, match="reason"):
        not_measured("x", "x", "1", "1", "")


def test_schema_refuses_a_wrong_shape():
    jsonschema = pytest.importorskip("jsonschema")
    schema = json.loads(SCHEMA.read_text(encoding="utf-8"))
    d = rate_like().to_json()
    for broken in ({**d, "items": {"bias": {**d["items"]["bias"], "unit": None}}},
                   {k: v for k, v in d.items() if k != "version"},
                   {**d, "items": {"t": {**d["items"]["threshold"], "value": 1.0}}}):
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(broken, schema)


def test_conformity_for_any_specification_item():
    r = rate_like()
    out = decide_result(r, LAB)
    b = r.items["bias"].conformity
    # guarded, decided on the printed U (0.0555 is stated 0.056, two significant digits):
    # acceptance interval [−0.5 + U, 0.5 − U] = [−0.444, 0.444]; 0.40 inside
    assert (b.rule, b.outcome, b.limits_from, b.source) == ("guarded", "pass", "lab file",
                                                            "datasheet")
    assert b.guard_band == pytest.approx(0.056) and b.acceptance_upper == pytest.approx(0.444)
    u = 0.056 / 2.776
    p_c = 0.5 * (math.erf((0.5 - 0.40) / u / math.sqrt(2)) - math.erf((-0.5 - 0.40) / u / math.sqrt(2)))
    assert b.conformance_probability == pytest.approx(p_c, rel=1e-12)
    t = r.items["threshold"].conformity
    assert t.outcome is None and "not measured" in t.reason and len(out) == 2
    assert r.items["scale_factor"].conformity is None          # no limit: no statement
    assert "bias: limits [-0.5, 0.5] (guarded" in r.summary()


def test_limit_on_an_item_the_specification_lacks_names_its_items():
    r = rate_like()
    with pytest.raises(GonioError, match=r"jjf-like has no item 'angle_deviation' \(its items: "
                                         r"bias, scale_factor, threshold\)"):
        decide_result(r, {"decision_rule": {"rule": "simple"},
                          "specification_limits": [{"item": "angle_deviation", "mpe": 0.5}]})


def test_value_on_the_limit_is_accepted_and_defaults_yield_to_the_lab_file():
    r = rate_like()
    decide_result(r, None, defaults=[{"item": "scale_factor", "upper": 6.0}])
    c = r.items["scale_factor"].conformity
    assert (c.outcome, c.rule, c.limits_from) == ("pass", "simple", "specification's tolerance")
    r = rate_like()
    decide_result(r, {"decision_rule": {"rule": "simple"},
                      "specification_limits": [{"item": "scale_factor", "lower": 6.0005}]},
                  defaults=[{"item": "scale_factor", "upper": 6.0}])
    c = r.items["scale_factor"].conformity
    assert (c.outcome, c.limits_from, c.lower, c.upper) == ("fail", "lab file", 6.0005, None)


def test_write_results_tables_and_summary(tmp_path):
    r = rate_like()
    decide_result(r, LAB)
    r.tables = {"extra_table": pd.DataFrame({"a": [1, 2]})}
    paths = write_results(r, tmp_path / "o")
    assert sorted(paths) == ["results", "summary", "tables/extra_table.csv", "tables/items.csv"]
    items = pd.read_csv(paths["tables/items.csv"])
    assert list(items["item"]) == ["bias", "scale_factor", "threshold"]
    assert items.loc[0, "conformity"] == "pass" and pd.isna(items.loc[2, "value"])
    d = json.loads(paths["results"].read_text(encoding="utf-8"))
    assert d["items"]["bias"]["conformity"]["outcome"] == "pass"
    text = paths["summary"].read_text(encoding="utf-8")
    assert "threshold: not measured (no threshold rows)" in text
    assert "flagged: r.csv line 7: read 40 s after arrival" in text
