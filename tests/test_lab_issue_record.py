"""A laboratory file's ``[record]`` issue keys (a seal, the people required, an amendment)
are the records' to write for the sealed result they issue: given to a calibration computed
now (``gonio calibrate``, ``gonio demo``) they are refused in one line, exit 2, nothing
written; before, a made-up seal was printed as "the laboratory's record of this result is
verified against it". A draft's ``status = "draft"`` stays allowed."""
from __future__ import annotations

import contextlib
import io

import pytest

from gonio.cli import main
from gonio.resources import protocols_dir

LAB = protocols_dir() / "lab-example.toml"


def _lab(tmp_path, record: str) -> str:
    text = LAB.read_text(encoding="utf-8")
    cut = text.index("[[specification_limits]]")      # limits name optical items
    p = tmp_path / "lab.toml"
    p.write_text(text[:cut] + "\n[record]\n" + record, encoding="utf-8")
    return str(p)


def _run(argv) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(argv)
    return rc, err.getvalue()


@pytest.mark.parametrize("record, key", [
    (f'status = "issued"\nseal_sha256 = "{"ab" * 32}"\n', "seal_sha256"),
    ('min_people = 2\n', "min_people"),
    ('replaces = "GON-2026-0001"\namendment_reason = "typo"\n', "replaces"),
])
@pytest.mark.parametrize("command", ["calibrate", "demo"])
def test_an_issue_record_is_refused_for_a_certificate_computed_now(
        tmp_path, shared_simulation, record, key, command):
    lab = _lab(tmp_path, record)
    out = tmp_path / "out"
    if command == "calibrate":
        readings = shared_simulation("jjf1535-2015") / "readings.csv"
        argv = ["calibrate", str(readings), "--lab", lab, "--out", str(out)]
    else:
        argv = ["demo", "--spec", "ogam-draft", "--lab", lab, "--out", str(out)]
    rc, err = _run(argv)
    assert rc == 2, err
    assert f"key record.{key}: " in err and "lab.toml" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_a_draft_record_is_rendered_as_a_draft(tmp_path):
    lab = _lab(tmp_path, 'status = "draft"\n')
    rc, err = _run(["demo", "--spec", "jjf1535-2015", "--lab", lab, "--out", str(tmp_path / "o")])
    assert rc == 0, err
    html = (tmp_path / "o" / "certificate.html").read_text(encoding="utf-8")
    assert "DRAFT" in html and "verified against it" not in html
