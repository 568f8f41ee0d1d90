"""The note on an outcome decided on the measurement result before rounding names the
acceptance interval that decision used. Where U's rounding moved a guarded limit, the measured
value lies inside the printed acceptance interval and beyond the one its value and U before
rounding give: before, every output said "it lies beyond the acceptance limit where the
printed value does not", false against the printed "≤ 790" beside it."""
from __future__ import annotations

import json
import re
from decimal import Decimal
from pathlib import Path

import pytest

from .test_conformity_printed_value import printed

ROOT = Path(__file__).resolve().parents[1]


def _num(t: str) -> float:
    return float(t.replace("−", "-"))


@pytest.mark.parametrize("lang", ["en", "zh"])
def test_a_guarded_limit_moved_by_u_rounding_is_named(tmp_path, capsys, lang):
    from gonio.cli import main

    assert main(["demo", "--spec", "jjf1535-2015", "--out", str(tmp_path / "a")]) == 0
    b = json.loads((tmp_path / "a" / "results.json").read_text())["items"]["bias"]
    y, U = b["value"], b["uncertainty"]["U"]
    yp, Up = printed(y, U)
    r = 2
    T = yp + r * Up                  # printed: yp + r·Up ≤ T, accepted at the boundary
    assert Decimal(repr(y)) + r * Decimal(repr(U)) > T, "the demo's U no longer rounds down"
    lab = ROOT / "protocols" / "lab-example.toml"
    head = lab.read_text(encoding="utf-8").split("[decision_rule]")[0]
    (tmp_path / "lab.toml").write_text(
        head + f'[decision_rule]\nrule = "guarded"\nguard_band_factor = {r}\n'
        f'agreed = "test"\n\n[[specification_limits]]\nitem = "bias"\nupper = {T}\n',
        encoding="utf-8")
    capsys.readouterr()
    assert main(["demo", "--spec", "jjf1535-2015", "--lang", lang, "--lab",
                 str(tmp_path / "lab.toml"), "--out", str(tmp_path / "b")]) == 0
    c = json.loads((tmp_path / "b" / "results.json").read_text())["items"]["bias"][
        "conformity"]
    assert c["outcome"] == "fail"
    # printed: the value lies inside its printed acceptance interval
    assert Decimal(c["acceptance_upper_text"].replace("−", "-")) >= yp
    m, acc = c["decided_on_measured"], c["decided_on_measured_acceptance"]
    got = re.fullmatch(r"≤ (\S+)", acc)
    assert got, acc
    # the measured value beyond the acceptance interval its value and U before rounding give
    assert _num(m) > _num(got.group(1))
    assert _num(got.group(1)) == pytest.approx(float(T) - r * U, rel=1e-9)
    html = (tmp_path / "b" / "certificate.html").read_text(encoding="utf-8")
    summary = (tmp_path / "b" / "summary.txt").read_text(encoding="utf-8")
    dcc = (tmp_path / "b" / "certificate.dcc.xml").read_text(encoding="utf-8")
    named = "acceptance interval " if lang == "en" else "接受区间 "
    assert f"{m.replace('-', '−')} °/h{', ' if lang == 'en' else '，'}{named}{acc} °/h" in html
    assert f"its value {m} against its acceptance interval {acc}" in summary
    assert f"its value {m} against its acceptance interval {acc}" in dcc
    assert "where the printed value does not" not in html + summary + dcc
