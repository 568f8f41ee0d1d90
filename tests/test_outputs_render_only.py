"""The per-item renderers (JJF 1535, IEC 62047-20 and the triad, ``SPEC.outputs.write``) decide
no conformity: they render the decisions the stored result carries. Checked with a decision
altered after the pipeline made it — a renderer that decided again would overwrite the altered
outcome and probability with the ones the limits give — and with a result nobody decided,
which a renderer that decided would fill in."""

from __future__ import annotations

import json

import pytest

from gonio.formats.lab import load_lab
from gonio.report.i18n import display
from gonio.result.model import Result

# the signatory test's laboratory file, limiting one item of each specification
from tests.test_certificate_signatory import ITEM, LAB  # noqa: E402


@pytest.fixture(scope="module", params=tuple(ITEM))
def decided(request, tmp_path_factory):
    """A small calibration of each specification, decided by the pipeline on a lab file that
    limits one item, written once, and its stored results.json read back."""
    from gonio.pipeline.dispatch import decide_conformity
    from gonio.specs import get
    from tests.test_zh_certificates import small_calibration

    d, result = small_calibration(request.param, tmp_path_factory)
    item, mpe = ITEM[request.param]
    (d / "lab.toml").write_text(LAB.replace("{item}", item).replace("{mpe}", mpe),
                                encoding="utf-8")
    lab = load_lab(d / "lab.toml")
    decide_conformity(result, lab)
    get(request.param).renderer().write(result, d / "first", lab=lab, lang="en")
    stored = json.loads((d / "first" / "results.json").read_text(encoding="utf-8"))
    return {"key": request.param, "item": item, "dir": d, "lab": lab, "stored": stored}


def _altered(stored: dict, item: str) -> dict:
    """The stored results.json with ``item``'s decision turned round: the other outcome, and
    a false-accept probability the limits would never give."""
    doc = json.loads(json.dumps(stored))
    c = doc["items"][item]["conformity"]
    assert c and c["outcome"] in ("pass", "fail"), c      # the simple rule decided it
    c["outcome"] = "fail" if c["outcome"] == "pass" else "pass"
    c["accepted"] = c["outcome"] == "pass"
    c["false_accept_probability"] = 0.123456
    c["conformance_probability"] = 0.876543
    return doc


def test_a_renderer_renders_the_stored_decision(decided):
    from gonio.specs import get

    doc = _altered(decided["stored"], decided["item"])
    out = decided["dir"] / "altered"
    get(decided["key"]).renderer().write(Result.from_json(doc), out, lab=decided["lab"],
                                         lang="en", dcc=True)
    written = json.loads((out / "results.json").read_text(encoding="utf-8"))
    c = written["items"][decided["item"]]["conformity"]
    want = doc["items"][decided["item"]]["conformity"]
    assert (c["outcome"], c["false_accept_probability"], c["conformance_probability"]) \
        == (want["outcome"], 0.123456, 0.876543)
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    line = next(x for x in summary.splitlines()
                if x.strip().startswith(decided["item"] + ": limits"))
    assert line.endswith(f"): {want['outcome']}, probability of conformance 87.7 %"), line
    page = (out / "certificate.html").read_text(encoding="utf-8")
    assert display("sig2", 12.3456) + " %" in page      # the altered probability, as stored


def test_a_renderer_adds_no_decision(decided):
    """A stored result nobody decided, rendered with the laboratory file that limits the
    item: still no decision in any output (deciding is the pipeline's step)."""
    from gonio.specs import get

    doc = json.loads(json.dumps(decided["stored"]))
    for it in doc["items"].values():
        it["conformity"] = None
    out = decided["dir"] / "undecided"
    get(decided["key"]).renderer().write(Result.from_json(doc), out, lab=decided["lab"],
                                         lang="en")
    written = json.loads((out / "results.json").read_text(encoding="utf-8"))
    assert all(it.get("conformity") is None for it in written["items"].values())
    assert "conformity:" not in (out / "summary.txt").read_text(encoding="utf-8")
    assert 'id="conformity"' not in (out / "certificate.html").read_text(encoding="utf-8")
