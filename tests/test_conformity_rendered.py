"""The optical draft's conformity is decided once, by the pipeline, and only rendered: the
certificate, the DCC and summary.txt state the decisions results.json carries (the
probabilities of a standard-deviation item by its chi-square model included), and a
renderer given limits nobody decided refuses instead of deciding or dropping them."""

from __future__ import annotations

import json
import tomllib
from dataclasses import replace
from pathlib import Path

import pytest

from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.formats.lab import load_lab
from gonio.report.i18n import display
from gonio.specs.ogam_draft.stated import conformity_for
from gonio.resources import protocols_dir
from gonio.specs.ogam_draft.calibration import calibrate
from gonio.pipeline.dispatch import decide_conformity
from gonio.specs.ogam_draft.outputs import write

SMALL = tomllib.loads((Path(__file__).parent / "data" / "small-protocol.toml")
                     .read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    d = tmp_path_factory.mktemp("conf")
    proto = parse_protocol(SMALL)
    session = run_session(proto, replace(load_bench("rlg"), sample_rate_hz=20.0), seed=7)
    write_session(session, d)
    result = calibrate(d / "readings.csv", proto, static_record=session.static_record)
    lab = load_lab(protocols_dir() / "lab-example.toml")       # limits E and repeatability
    decide_conformity(result, lab)                              # the pipeline decides, once
    write(result, d / "out", lab=lab, dcc=True)
    return result, lab, d / "out"


def test_certificate_dcc_and_summary_state_the_decision_of_results_json(written):
    result, lab, out = written
    items = json.loads((out / "results.json").read_text(encoding="utf-8"))["items"]
    decided = {k: it["conformity"] for k, it in items.items() if it.get("conformity")}
    assert set(decided) == {"angle_deviation", "repeatability"}
    # repeatability is a standard deviation stated with its chi-square interval: the
    # pipeline's probabilities follow that model, and so must every rendering of them
    assert decided["repeatability"]["probability_model"].startswith("chi-square")
    assert decided["repeatability"]["false_accept_probability"] is not None
    html = (out / "certificate.html").read_text(encoding="utf-8")
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    dcc = (out / "certificate.dcc.xml").read_text(encoding="utf-8")
    for key, c in decided.items():
        pfa = c["false_accept_probability"]
        if pfa is None:
            continue
        shown = display("sig2", 100.0 * pfa) + " %"
        assert shown in html, (key, shown)
        assert f"conformity {key}: " in summary and shown in summary, (key, shown)
    assert "Statement of conformity" in dcc


def test_the_report_decides_nothing(written):
    result, lab, _ = written
    res = result.to_json()
    entries = conformity_for(res, lab)
    assert [e["item"] for e in entries] == [lim["item"] for lim in lab["specification_limits"]]
    assert all(e["conformity"] == result.items[e["item"]].conformity for e in entries)
    undecided = json.loads(json.dumps(res))
    for it in undecided["items"].values():
        it["conformity"] = None
    with pytest.raises(ValueError, match="was not decided"):
        conformity_for(undecided, lab)
    other = {**lab, "specification_limits": [{"item": "repeatability", "upper": 0.9}]}
    with pytest.raises(ValueError, match="decided under other limits"):
        conformity_for(res, other)
    assert conformity_for(res, None) == []    # lab-file limits only
