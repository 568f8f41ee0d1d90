"""The optical certificate prints ν_eff beside k where k = t_p(ν_eff) (Welch–Satterthwaite),
as the one statement rule states it (the rate certificates did already): K stated
"76434.85 ± 0.08 (k = 2.57, p = 95 %)" left the reader no ν to check k against. k from the
budget's convolution (JCGM 101) has no ν and prints none."""

from __future__ import annotations

import copy
import json

import pytest
from scipy.stats import t

from gonio.specs.ogam_draft.stated import stated_item, summary_text, u_cell
from gonio.specs.ogam_draft.phrases import LABELS
from gonio.report.i18n import labels


@pytest.fixture(scope="module")
def demo(shared_simulation, tmp_path_factory):
    from gonio.cli import main

    out = tmp_path_factory.mktemp("ogam") / "out"
    sim = shared_simulation("ogam-draft", "tests/data/small-protocol.toml")
    assert main(["calibrate", str(sim / "readings.csv"), "--protocol",
                 "tests/data/small-protocol.toml", "--out", str(out)]) == 0
    return json.loads((out / "results.json").read_text())


def _cell_text(cell) -> str:
    return cell if isinstance(cell, str) else "".join(str(x) for x in cell)


def test_k_from_welch_satterthwaite_prints_its_nu(demo):
    res = copy.deepcopy(demo)
    unc = res["items"]["scale_factor"]["uncertainty"]
    nu = 5.7                                  # stated rounded down: 5, k = t95(5) = 2.571
    unc.update(nu_eff=nu, k=float(t.ppf(0.975, 5)), k_source="welch-satterthwaite")
    unc["U"] = unc["k"] * unc["u_c"]
    st = stated_item(res, "scale_factor")
    assert str(st["nu"]) == "5" and str(st["k"]) == "2.57"
    for lang in ("en", "zh"):
        text = _cell_text(u_cell(st, labels(lang, LABELS)))
        assert "k = 2.57" in text and "ν_eff = 5" in text, text
    line = [x for x in summary_text(res).splitlines() if "scale factor K" in x][0]
    assert "(k = 2.57, ν_eff = 5, p = 95 %)" in line, line


def test_k_of_the_convolution_prints_no_nu(demo):
    unc = demo["items"]["scale_factor"]["uncertainty"]
    if unc.get("k_source") != "jcgm101-convolution":
        pytest.skip(f"K's k here is {unc.get('k_source')!r}")
    st = stated_item(demo, "scale_factor")
    assert st["nu"] is None and "ν" not in _cell_text(u_cell(st, labels("en", LABELS)))
