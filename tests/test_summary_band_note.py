"""summary.txt of a rate specification (JJF 1535, IEC 62047-20, the triad) issued with limits
under a guard band states what the certificate states of its items decided on their interval
alone: the guard-band note (δ read off the printed ends, w = r·δ, the "≤ q %" false-accept
bound 1 − p), word for word the certificate's, and on each such accepted item's line the
specific false-accept bound the certificate's false-accept column prints ("≤ 5.0 %"; the
threshold's 99.3 % interval "≤ 0.70 %"). The bound is worked out here from results.json's
coverage probability (1 − p, two significant digits rounded up), δ from the printed ends
with :mod:`decimal`, never from gonio's texts.
"""
from __future__ import annotations

import html as html_lib
import json
import math
import re
from decimal import Decimal

import pytest

from tests.test_outputs_agree_with_lab import lab_text


def bound_up(x: float) -> str:
    """``x`` (per cent) at two significant digits, rounded up."""
    e = math.floor(math.log10(x)) - 1
    m = math.ceil(round(x / 10 ** e, 9))
    return f"{m * Decimal(10) ** e:f}" if e < 0 else str(m * 10 ** e)


def page_text(html: str) -> str:
    return html_lib.unescape(re.sub(r"<[^>]+>", "", html)).replace("\xa0", " ")


@pytest.fixture(scope="module", params=["jjf1535-2015", "triad-alignment"])
def issued(request, tmp_path_factory, shared_demo):
    spec = request.param
    lab = tmp_path_factory.mktemp("lab") / "lab.toml"
    lab.write_text(lab_text(spec), encoding="utf-8")
    out = shared_demo(spec, lab=lab)
    return (spec, json.loads((out / "results.json").read_text(encoding="utf-8")),
            (out / "summary.txt").read_text(encoding="utf-8"),
            page_text((out / "certificate.html").read_text(encoding="utf-8")))


def test_summary_carries_the_certificates_band_note(issued):
    spec, res, summary, page = issued
    decided = {k: it["conformity"] for k, it in res["items"].items()
               if (it.get("conformity") or {}).get("outcome")}
    iv = {k: c for k, c in decided.items()
          if c.get("acceptance_of") == "interval" and c["rule"] != "simple"}
    assert iv, spec
    # the note as the certificate prints it, one line of summary.txt's conformity section
    start = page.index("Guard band of an item stated by its")
    note = page[start:page.index(" r = 1).", start) + len(" r = 1).")]
    lines = summary.splitlines()
    assert f"  {note}" in lines, note
    j = lines.index(f"  {note}")
    assert lines[lines.index("conformity:") + 1:j] and all(
        ln.startswith("  ") for ln in lines[lines.index("conformity:") + 1:j])
    # its numbers: δ from the printed ends, the bound 1 − p of the items' one p
    for key, c in iv.items():
        if any("×" in x for x in c["stated_interval"]):
            continue                    # a power-of-ten form: not parsed here
        lo, hi = (Decimal(x.replace("−", "-")) for x in c["stated_interval"])
        if str(c.get("probability_model") or "").startswith("chi-square"):
            d = hi - Decimal(c["stated_value"])
            assert f"δ = {c['stated_interval'][1]} − {c['stated_value']}" in note, key
        else:
            d = (hi - lo) / 2
            assert f"δ = ({c['stated_interval'][1]} − {c['stated_interval'][0]})/2" in note, key
        assert f"= {d.normalize():f}" in note, (key, d)
    ps = {res["items"][k]["uncertainty"]["coverage_probability"] for k in iv}
    p = ps.pop() if len(ps) == 1 else 0.95
    assert f"1 − p = {bound_up(100 * (1 - p))} %" in note, note


def test_summary_states_each_false_accept_bound(issued):
    spec, res, summary, page = issued
    seen = 0
    for key, it in res["items"].items():
        c = it.get("conformity") or {}
        line = next((ln for ln in summary.splitlines()
                     if ln.strip().startswith(f"{key}: limits")), None)
        if c.get("false_accept_bound") is None:
            if line is not None:
                assert "false-accept probability ≤" not in line, line
            continue
        p = it["uncertainty"]["coverage_probability"]
        assert c["false_accept_bound"] == pytest.approx(1 - p, abs=1e-12), key
        q = bound_up(100 * (1 - p))
        assert line.endswith(f"; specific false-accept probability ≤ {q} %") \
            or f"; specific false-accept probability ≤ {q} %;" in line, line
        # the certificate's false-accept column prints the same bound on the item's row
        assert f"≤ {q} %" in page, (key, q)
        seen += 1
    assert seen, spec


def test_threshold_bound_is_the_certificates():
    """The threshold's interval holds p = 99.305 %: its bound 0.695 % reads "≤ 0.70 %"."""
    assert bound_up(100 * (1 - 0.99305)) == "0.70"
    assert bound_up(5.0) == "5.0" and bound_up(4.55) == "4.6"
