"""A stored optical results.json written before E's per-point statement carried ``ku_arcsec``,
``nu_without_table``, ``u_c_certified`` and ``u_c_beside`` (and the budget figure its
``bound``) still renders, stating the same numbers as the same result written by the present
code (gonio.specs.ogam_draft.stored); one whose per-point statements cannot give them is refused
in one line (GonioError, exit 2), never a traceback. The full result, written by the present
calibration, is the independent reference: the derivation never sees it."""

from __future__ import annotations

import copy
import json
import tomllib
from dataclasses import replace
from pathlib import Path

import pytest
from lxml import etree

from gonio.errors import GonioError
from gonio.report.i18n import labels
from gonio.result.model import Result
from gonio.specs.ogam_draft import outputs
from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
from gonio.specs.ogam_draft.calibration import calibrate
from gonio.specs.ogam_draft.certificate_pages import certificate_blocks
from gonio.specs.ogam_draft.dcc import dcc_tree
from gonio.specs.ogam_draft.phrases import LABELS
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.specs.ogam_draft.stored import complete_stored

SMALL = tomllib.loads((Path(__file__).parent / "data" / "small-protocol.toml")
                      .read_text(encoding="utf-8"))
ADDED = ("ku_arcsec", "nu_without_table", "u_c_certified", "u_c_beside")


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    d = tmp_path_factory.mktemp("stored")
    proto = parse_protocol(SMALL)
    session = run_session(proto, replace(load_bench("rlg"), sample_rate_hz=100.0), seed=4)
    write_session(session, d)
    result = calibrate(d / "readings.csv", proto, static_record=session.static_record)
    outputs.write_calibration(result, d)
    out = json.loads((d / "results.json").read_text(encoding="utf-8"))
    assert out["extra"]["uncertainty"].get("U_bound_arcsec") is not None, \
        "this bench's E no longer carries the table's bound: the test checks nothing"
    return out


def older(res: dict) -> dict:
    """``res`` as the earlier gonio wrote it: the four fields absent, the budget figure's U
    the stated per-point U with no ``bound``."""
    old = copy.deepcopy(res)
    u = old["extra"]["uncertainty"]
    for k in ADDED:
        u.pop(k)
    fig = old["extra"]["figures"]["budget"]
    for k in ("bound", "u_c_stated"):
        fig.pop(k, None)
    fig["U_arcsec"] = u["U_bound_arcsec"]
    return old


def _text(res, lang):
    L = {**labels(lang), **{k: v[lang] for k, v in LABELS.items()}}
    blocks = certificate_blocks(res, L, lab=None, truth=None, lang=lang)["blocks"]
    return "\n".join("".join(str(x) for x in b.data) for b in blocks)


def test_an_older_result_renders_the_same_statement(full):
    old = older(full)
    # the renderer's entry points take it, and state what the present code states
    assert outputs.summary(Result.from_json(old)) == outputs.summary(Result.from_json(full))
    done = complete_stored(Result.from_json(old).to_json())
    for k in ADDED:
        assert done["extra"]["uncertainty"][k] == full["extra"]["uncertainty"][k], k
    assert done["extra"]["figures"]["budget"] == full["extra"]["figures"]["budget"]
    for lang in ("en", "zh"):
        assert _text(done, lang) == _text(full, lang), lang
    assert (etree.tostring(dcc_tree(done, lab=None, cert_id="T-1"))
            == etree.tostring(dcc_tree(full, lab=None, cert_id="T-1")))


def test_the_present_result_is_left_as_it_is(full):
    assert complete_stored(full) is full


def test_an_older_result_without_its_points_is_refused_in_one_line(full, tmp_path):
    old = older(full)
    old["extra"]["uncertainty"].pop("points")
    with pytest.raises(GonioError) as e:
        outputs.summary(Result.from_json(old))
    assert "\n" not in str(e.value) and "ku_arcsec" in str(e.value)
    bad = older(full)                    # points that do not give the stored statement
    bad["extra"]["uncertainty"]["U_bound_arcsec"] *= 1.01
    with pytest.raises(GonioError):
        outputs.write(Result.from_json(bad), tmp_path / "out")
