"""The public plug-in kit (gonio.kit, docs/kit.md) and the guide built on it.

- the guide's code blocks and the example package import nothing private (no module path
  with a segment starting with ``_``) and name no private module in a string;
- every name of the kit is documented (a docstring, and docs/kit.md names it);
- the example, followed as the guide says, runs end to end: simulate → calibrate with a
  Monte Carlo check → certificate with its own forward/reverse figure → DCC with its ppm
  item, valid against the DCC 3.3.0 schema; the items against the bench's truth;
- the kit's own helpers (the item loop, set_aside, DCC units) against independent results.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gonio.kit as kit
from gonio.cli import main
from gonio.errors import GonioError

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "writing-a-specification.md"
PLUGIN = ROOT / "tests" / "plugins" / "acme_rate_check"
#: A private module path: a dotted name under gonio or uncertainty with a segment "_x".
PRIVATE = re.compile(r"\b(?:gonio|uncertainty)(?:\.\w+)*\.(_[A-Za-z]\w*)")
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.M | re.S)


def private_references(text: str) -> list[str]:
    return [m.group(0) for m in PRIVATE.finditer(text)]


def test_the_private_checker_fires():
    assert private_references("from gonio.specs._rate_family.rate_records import gum") == \
        ["gonio.specs._rate_family"]
    assert private_references('outputs="gonio.specs._rate_family.outputs"') != []
    assert private_references("from gonio.kit import gum, ITEM_RENDERER") == []


def test_the_guide_and_the_example_use_nothing_private():
    blocks = [body for lang, body in FENCE.findall(GUIDE.read_text(encoding="utf-8"))
              if lang in ("python", "")]
    assert len(blocks) >= 5
    files = sorted((PLUGIN / "acme_rate_check").glob("*.py"))
    assert len(files) >= 5
    hits = [(i, r) for i, b in enumerate(blocks) for r in private_references(b)]
    hits += [(f.name, r) for f in files for r in private_references(f.read_text("utf-8"))]
    assert hits == []
    imports = {m for f in files for m in re.findall(r"^from (gonio[\w.]*) import",
                                                     f.read_text("utf-8"), re.M)}
    assert imports <= {"gonio.kit", "gonio.atomic"}, imports


def test_every_kit_name_is_documented():
    doc = (ROOT / "docs" / "kit.md").read_text(encoding="utf-8")
    for name in kit.__all__:
        assert f"`{name}`" in doc or f"`{name}(" in doc, name
        obj = getattr(kit, name)
        if callable(obj):
            assert (obj.__doc__ or "").strip(), name
    assert (kit.__doc__ or "").count(":func:") >= 20


def test_every_rendering_kit_name_is_documented():
    from gonio.kit import render

    doc = (ROOT / "docs" / "kit.md").read_text(encoding="utf-8")
    section = doc.partition("## The rendering kit")[2].partition("\n## ")[0]
    for name in render.__all__:
        assert f"`{name}`" in section, name
        assert name in (render.__doc__ or ""), name
        obj = getattr(render, name)
        if callable(obj):
            assert (obj.__doc__ or "").strip(), name


def test_the_kit_loads_neither_the_bench_nor_the_report():
    code = ("import sys, gonio.kit\n"
            "bad = sorted(m for m in sys.modules if m.startswith(('gonio.bench', "
            "'gonio.report', 'gonio.pipeline')))\nprint(bad)\nsys.exit(1 if bad else 0)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stdout + r.stderr


def test_the_guide_end_to_end(plugin, tmp_path, dcc_schema, capsys):
    """simulate → calibrate --monte-carlo --dcc: three items within U of the bench's truth,
    every budget checked by Monte Carlo, the certificate with the procedure's own figure,
    the ppm item in the DCC as \\ppm, the DCC valid."""
    sim, cal = tmp_path / "sim", tmp_path / "cal"
    assert main(["simulate", "--spec", "acme-rate-check", "--seed", "5", "--out", str(sim)]) == 0
    assert main(["calibrate", str(sim / "readings.csv"), "--out", str(cal),
                 "--monte-carlo", "20000", "--dcc"]) == 0
    capsys.readouterr()
    res = json.loads((cal / "results.json").read_text(encoding="utf-8"))
    truth = json.loads((sim / "truth.json").read_text(encoding="utf-8"))["items"]
    assert set(res["items"]) == {"scale_factor", "bias", "asymmetry"}
    for key, it in res["items"].items():
        unc = it["uncertainty"]
        assert it["measured"] and abs(it["value"] - truth[key]["value"]) <= unc["U"], key
        mc = unc["monte_carlo"]
        assert mc["trials"] == 20000 and isinstance(mc["validated"], bool), key
        assert mc["low"] < it["value"] < mc["high"], key
        # the models are near-linear: Monte Carlo's u is √Σ (c·u)²·ν/(ν − 2), the variance
        # of the scaled-shifted t_ν each input with ν degrees of freedom is drawn from
        var = sum(c["contribution"] ** 2 * (1 if c["dof"] is None else c["dof"] / (c["dof"] - 2))
                  for c in unc["components"])
        assert mc["u"] == pytest.approx(var ** 0.5, rel=0.03), key
    a = res["items"]["asymmetry"]
    assert a["unit"] == "ppm"
    # the fit's K± against a second algorithm: a separate least-squares line per direction
    # through the mean outputs, sharing the intercept
    import pandas as pd
    df = pd.read_csv(sim / "readings.csv", comment="#")
    m = df.groupby("rate_dps")["output"].mean()
    x, y = m.index.to_numpy(float), m.to_numpy(float)
    X = np.column_stack([np.ones_like(x), np.where(x > 0, x, 0), np.where(x < 0, x, 0)])
    _, kp, kn = np.linalg.lstsq(X, y, rcond=None)[0]
    assert a["details"]["K_pos"] == pytest.approx(kp, rel=1e-12)
    assert a["details"]["K_neg"] == pytest.approx(kn, rel=1e-12)
    assert a["value"] == pytest.approx(2e6 * (kp - kn) / (kp + kn), rel=1e-9)
    html = (cal / "certificate.html").read_text(encoding="utf-8")
    assert "scale-factor asymmetry A" in html and "Forward (CW) and reverse (CCW) fits" in html
    assert "asymmetry not measured" not in html       # the figure is drawn, not empty
    xml = (cal / "certificate.dcc.xml").read_bytes()
    dcc_schema.validate(str(cal / "certificate.dcc.xml"))
    assert b"<si:unit>\\ppm</si:unit>" in xml


def test_the_item_loop_orders_refuses_and_checks_by_monte_carlo():
    def first(x):
        u = kit.gum(lambda a, b: a + b, [kit.from_u("a", x, 0.3), kit.from_u("b", 1.0, 0.4)])
        return kit.Item("first", "First", "1", "1", x + 1.0, uncertainty=u)

    def second(x, first):
        if x < 0:
            raise GonioError("x must be non-negative")
        return kit.Item("second", "Second", "2", "1", 2 * first.value)

    defs = [kit.ItemDef("second", "Second", "2", second, needs=("first",)),
            kit.ItemDef("first", "First", "1", first),
            kit.ItemDef("third", "Third", "3", lambda x, second: None, needs=("second",))]
    with pytest.raises(TypeError, match="item 'third': compute returned None"):
        kit.calibrate_items(defs, 2.0)
    got = kit.calibrate_items(defs[:2], 2.0, monte_carlo_trials=100_000)
    assert list(got) == ["second", "first"] and got["second"].value == 6.0
    u = got["first"].uncertainty
    assert u.u_c == pytest.approx(0.5, rel=1e-9)            # √(0.3² + 0.4²), closed form
    assert u.monte_carlo["u"] == pytest.approx(0.5, rel=0.01) and u.monte_carlo["validated"]
    refused = kit.calibrate_items(defs[:2] + [kit.ItemDef("third", "Third", "3",
                                                          lambda x, second: second,
                                                          needs=("second",))], -1.0)
    assert not refused["second"].measured
    assert refused["second"].reason == "the data were refused: x must be non-negative"
    assert refused["third"].reason == "needs second, not measured"
    assert kit.calibrate_items(defs[:2], 2.0)["first"].uncertainty.monte_carlo is None


def test_set_aside_refuses_and_flags():
    import pandas as pd

    df = pd.DataFrame({"line": [4, 5, 6], "v": [1.0, 2.0, 3.0]})
    flag = kit.Finding("drift", "drifts", "flagged", line=5)
    assert kit.set_aside(df, [flag]) is df
    aside = kit.Finding("spike", "a spike", "set_aside", line=5)
    assert kit.set_aside(df, [aside, flag])["line"].tolist() == [4, 6]
    assert df["line"].tolist() == [4, 5, 6]                  # the input is not modified
    with pytest.raises(GonioError, match="r.csv:6: refused by the screening: broken"):
        kit.set_aside(df, [kit.Finding("x", "broken", "refused", file="r.csv", line=6)])
    with pytest.raises(GonioError, match="no 'line' column"):
        kit.set_aside(df.drop(columns="line"), [aside])


def test_dcc_units_of_a_specification():
    from gonio.report.item_dcc import compose_dsi
    from gonio.report.rate_dcc import dsi_unit

    # the one unit table (ppm included), then a specification's own units
    assert dsi_unit("ppm", "mV") == (r"\ppm", 1.0)
    assert dsi_unit("mm", "mV", extra={"mm": r"\milli\metre"}) == (r"\milli\metre", 1.0)
    assert dsi_unit("°/h", "mV", extra={"°/h": r"\one"}) == (r"\degree\hour\tothe{-1}", 1.0)
    with pytest.raises(GonioError, match="unit 'mm' has no D-SI form .*dcc_units"):
        dsi_unit("mm", "mV")
    assert compose_dsi("furlong", {"furlong": r"\metre"}) == r"\metre"
    with pytest.raises(GonioError, match="unit 'furlong' has no D-SI form"):
        compose_dsi("furlong")


def test_item_loop_reports_an_unstateable_item_as_not_measured():
    """The kit's item loop keeps the built-ins' rule: a non-negative item whose value + U ≤ 0
    has no interval the statement rule can state, so it is not measured with the reason (it
    is never handed to a renderer that would then fail)."""
    unc = kit.Uncertainty([], 0.5, 1.0, 2.0, None)
    defs = [kit.ItemDef("n", "noise", "4.5", lambda: kit.Item("n", "noise", "4.5", "mV", -5.0,
                                                                    uncertainty=unc),
                        nonnegative=True),
            kit.ItemDef("s", "signed", "4.6", lambda: kit.Item("s", "signed", "4.6", "mV", -5.0,
                                                                     uncertainty=unc))]
    got = kit.calibrate_items(defs)
    assert not got["n"].measured and "no statement possible" in got["n"].reason
    assert got["n"].nonnegative
    assert got["s"].measured and got["s"].value == -5.0          # a signed quantity is stated
