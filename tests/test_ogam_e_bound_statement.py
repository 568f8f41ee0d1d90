"""Optical E where each point's U carries the table's bound (U = k·u + b): what the
certificate (en, zh), summary.txt, the DCC and the budget figure state.

The stated U is k·u + b with u the combined standard uncertainty of the lines other than the
table's and b the table's bound at the point. The budget's u_c (the table line at MPE/√3 per
position) does not hold the corner table, so no u_c of E is stated anywhere and the DCC
writes E's interval without an si:valueStandardMU. Every check reads the rendered text and
recomputes the relation from the printed numbers; u is checked against the budget's lines
recombined here without the table line (a second computation, not the stored one).
"""

from __future__ import annotations

import json
import math
import re
import tomllib
from dataclasses import replace
from pathlib import Path

import pytest

from gonio.report.i18n import display, labels
from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
from gonio.specs.ogam_draft.calibration import calibrate
from gonio.specs.ogam_draft.certificate_pages import certificate_blocks
from gonio.specs.ogam_draft.dcc import dcc_tree
from gonio.specs.ogam_draft.figure_data import budget as budget_series
from gonio.specs.ogam_draft.outputs import write_calibration
from gonio.specs.ogam_draft.phrases import LABELS
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.specs.ogam_draft.stated import stated_item, summary_text

SMALL = tomllib.loads((Path(__file__).parent / "data" / "small-protocol.toml")
                      .read_text(encoding="utf-8"))
NUM = r"(-?\d+(?:\.\d+)?)"


@pytest.fixture(scope="module")
def res(tmp_path_factory):
    d = tmp_path_factory.mktemp("ebound")
    proto = parse_protocol(SMALL)
    session = run_session(proto, replace(load_bench("rlg"), sample_rate_hz=100.0), seed=4)
    write_session(session, d)
    result = calibrate(d / "readings.csv", proto, static_record=session.static_record)
    write_calibration(result, d)
    out = json.loads((d / "results.json").read_text(encoding="utf-8"))
    assert out["extra"]["uncertainty"].get("U_bound_arcsec") is not None, \
        "this bench's E no longer carries the table's bound: the test checks nothing"
    return out


def _half_unit(text: str) -> float:
    """Half a unit of the last printed digit of ``text``."""
    dec = len(text.partition(".")[2])
    return 0.5 * 10.0 ** -dec


def _check_relation(U: str, k: str, u: str, ku: str, b: str) -> None:
    """U = k·u + b and k·u = k × u, within the rounding of the printed numbers."""
    fU, fk, fu, fku, fb = map(float, (U, k, u, ku, b))
    assert abs(fku + fb - fU) <= _half_unit(U) + _half_unit(ku) + _half_unit(b) + 1e-12, \
        (U, ku, b)
    tol = fk * _half_unit(u) + fu * _half_unit(k) + _half_unit(ku) + 1e-12
    assert abs(fk * fu - fku) <= tol, (k, u, ku)


def _text(blocks) -> str:
    return "\n".join("".join(str(x) for x in b.data) for b in blocks if b.kind == "p")


def _u_other_lines(res: dict) -> float:
    """u of E's budget lines other than the table's, recombined here (root sum of squares of
    the contributions other than P, the table line) at the budget's point."""
    comps = res["extra"]["uncertainty"]["components"]
    return math.sqrt(sum(c["contribution_arcsec"] ** 2 for c in comps if c["symbol"] != "P"))


def test_certificate_states_U_as_k_u_plus_b_and_no_u_c(res):
    unc = res["extra"]["uncertainty"]
    for lang, pat in (
            ("en", rf"U = {NUM}″, k = {NUM}, .*?u = {NUM}″ \(ν = (∞|\d+)\) .*?"
                   rf"k·u = {NUM}″, plus the table's bound b = {NUM}″"),
            ("zh", rf"U = {NUM}″，k = {NUM}，.*?u = {NUM}″（ν = (∞|\d+)）.*?"
                   rf"k·u = {NUM}″；b = {NUM}″")):
        L = labels(lang, LABELS)
        text = _text(certificate_blocks(res, L, lab=None, truth=None, lang=lang)["blocks"])
        m = re.search(pat, text)
        assert m, (lang, text[:2000])
        U, k, u, nu, ku, b = m.groups()
        _check_relation(U, k, u, ku, b)
        assert U == display("U", unc["U_bound_arcsec"]) and k == display("k", unc["k_bound"])
        # u is the budget's lines without the table's, recombined independently
        if unc["U_position_deg"] == unc["max_abs_interval"]["position_at_max"]:
            assert abs(float(u) - _u_other_lines(res)) <= _half_unit(u) + 1e-12
        # no u_c of E stated: the budget's u_c line is gone, the "not certified" line says so
        assert L["u_c_line"].partition("{")[0] not in text, lang
        assert L["u_c_not_certified"] in text


def test_summary_states_the_same_relation_and_no_u_c(res):
    text = summary_text(res, "en")
    line = next(s for s in text.splitlines() if s.startswith("Uncertainty of each point"))
    m = re.search(rf"U = {NUM}″ \(k = {NUM},.*?u = {NUM}″ \(ν = (∞|\d+)\).*?k·u = {NUM}″"
                  rf".*?b = {NUM}″", line)
    assert m, line
    U, k, u, _, ku, b = m.groups()
    _check_relation(U, k, u, ku, b)
    assert "u_c =" not in line
    assert labels("en", LABELS)["u_c_not_certified"] in text


def test_dcc_states_no_standard_uncertainty_for_E(res):
    from lxml import etree

    root = dcc_tree(res, lab=None, cert_id="TEST-1")
    xml = etree.tostring(root, encoding="unicode")
    block = xml[xml.index('id="result-angle_deviation"'):]
    block = block[:block.index("</dcc:result>")]
    assert "<si:valueStandardMU>" not in block and "<si:coverageIntervalMU>" not in block
    lo, hi = re.search(r"<si:labelXMLList>intervalMin intervalMax</si:labelXMLList>\s*"
                       rf"<si:valueXMLList>{NUM} {NUM}</si:valueXMLList>", block).groups()
    # the ends are the ones the certificate prints, and hold the upper end stored
    ends = [str(e) for e in stated_item(res, "angle_deviation")["interval"]["interval"]["ends"]]
    assert [lo, hi] == ends
    up = res["extra"]["uncertainty"]["max_abs_interval"]["upper_arcsec"]
    assert abs(float(hi) - up) <= _half_unit(hi) + 1e-12
    assert float(lo) >= 0.0


def test_budget_figure_does_not_draw_the_bound_U_beside_u_c(res):
    d = budget_series(res["extra"]["uncertainty"])
    assert d["u_c_stated"] is False and d["U_arcsec"] is None
    bd = d["bound"]
    assert math.isclose(bd["U_arcsec"], bd["ku_arcsec"] + bd["b_arcsec"], rel_tol=1e-12)
    # k·u of the figure is k times u of the other lines, not u
    k = res["extra"]["uncertainty"]["k_bound"]
    assert math.isclose(bd["ku_arcsec"], k * bd["u_arcsec"], rel_tol=1e-12)
    assert math.isclose(bd["u_arcsec"], _u_other_lines(res), rel_tol=1e-9) or \
        res["extra"]["uncertainty"]["U_position_deg"] != \
        res["extra"]["uncertainty"]["max_abs_interval"]["position_at_max"]
