"""The Specification protocol's own machinery: items ordered by their declared needs (and
no item writing the shared context), options a specification does not take refused,
readings naming their specification, screening findings, and lazy simulation hooks."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from gonio.errors import GonioError
from gonio.kit import item_order
from gonio.specs import get, lazy

ROOT = Path(__file__).resolve().parents[1]


def test_item_order_follows_needs_and_keeps_declared_ties():
    keys = ["bias", "noise", "scale_factor", "drift"]
    needs = {"bias": ["scale_factor"], "drift": ["bias", "noise"]}
    assert item_order(keys, needs) == ["noise", "scale_factor", "bias", "drift"]
    with pytest.raises(GonioError, match="cycle"):
        item_order(["a", "b"], {"a": ["b"], "b": ["a"]})
    with pytest.raises(GonioError, match="no item"):
        item_order(["a"], {"a": ["k"]})


@pytest.mark.parametrize("pkg", ["jjf1535", "iec62047_20"])
def test_rate_items_declare_the_scale_factor_and_never_write_the_context(pkg):
    import importlib
    items = importlib.import_module(f"gonio.specs.{pkg}.items")
    keys = [r[0] for r in items.ITEMS]
    order = item_order(keys, items.NEEDS)
    # the scale factor comes first but for what it itself needs (IEC a_BASE: 5.1.3.4's
    # chamber coefficient), each of which needs nothing
    first = order.index("scale_factor")
    assert set(order[:first]) == set(items.NEEDS.get("scale_factor", ())) \
        and sorted(order) == sorted(keys)
    assert all(not items.NEEDS.get(k) for k in order[:first])
    # every item reading K / a_BASE declares the scale factor
    src = (ROOT / "gonio" / "specs" / pkg / "items.py").read_text(encoding="utf-8")
    tree = ast.parse(src)
    fns = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    for key, _, _, fn in items.ITEMS:
        reads = {a.attr for a in ast.walk(fns[fn.__name__]) if isinstance(a, ast.Attribute)}
        if key in items.NEEDS.get("scale_factor", ()):
            # computed before the scale factor (which needs it): must not read K or a_BASE
            assert not reads & {"K", "a_base", "u_K_rel"}, key
            continue
        if reads & {"K", "a_base", "u_K_rel"} or "_need" in src or "_miss" in src:
            assert key == "scale_factor" or "scale_factor" in items.NEEDS.get(key, ()), key
    # no item function assigns an attribute of the context (ctx.K = …)
    writes = [f"{n.lineno}" for n in ast.walk(tree) if isinstance(n, (ast.Assign, ast.AugAssign))
              for t in (n.targets if isinstance(n, ast.Assign) else [n.target])
              if isinstance(t, ast.Attribute) and isinstance(t.value, ast.Name)
              and t.value.id == "ctx"]
    assert writes == []


def test_options_a_specification_does_not_take_are_refused():
    from gonio.pipeline.dispatch import refuse_options
    spec = get("jjf1535-2015")
    assert refuse_options(spec, {"protocol": None, "dcc": True, "robust": False},
                          spec.calibrate_options, "calibrate") == {"dcc": True}
    with pytest.raises(GonioError, match="--thermal, --tilt do not apply to 'gonio calibrate "
                                         "--spec jjf1535-2015'"):
        refuse_options(spec, {"tilt": "t.json", "thermal": "x.csv"}, spec.calibrate_options,
                       "calibrate")


def test_readings_name_their_specification(tmp_path):
    from gonio.specs.triad_alignment.readings import FORMAT
    from gonio.pipeline.dispatch import readings_spec
    a = tmp_path / "a.csv"
    a.write_text("# spec: jjf1535-2015\n# x: 1\ntest,run\n", encoding="utf-8")
    b = tmp_path / "b.csv"
    b.write_text(f"# format: {FORMAT}\ntest\n", encoding="utf-8")
    c = tmp_path / "c.csv"
    c.write_text("test\n# spec: jjf1535-2015\n", encoding="utf-8")
    assert readings_spec(a) == "jjf1535-2015"
    assert readings_spec(b) == "triad-alignment"          # SPEC.readings_format
    assert readings_spec(c) is None                        # metadata only at the head


def test_screen_of_the_optical_draft(tmp_path):
    """SPEC.screen gives the findings without calibrating: a reading at the wrong table angle
    is set aside, naming its line, column and clause, beside the file's other findings."""
    spec = get("ogam-draft")
    proto = ROOT / "tests" / "data" / "full.toml"
    clean = spec.screen(ROOT / "tests" / "data" / "full.csv", proto)
    bad = tmp_path / "bad.csv"
    bad.write_text((ROOT / "tests" / "data" / "full.csv").read_text(encoding="utf-8").replace(
        "scale_factor,1,2,60,up,65.0,120.0,432000,", "scale_factor,1,2,60,up,65.0,150.0,432000,"),
        encoding="utf-8")
    found = spec.screen(bad, proto)
    new = [f for f in found if f.line == 8]
    assert len(new) == 1 and new[0].action == "set_aside" and new[0].column == "table_deg"
    assert new[0].clause == "7.1" and "150" in new[0].message
    # the file's other findings stay; the clean file's median-rule statement on 7.1's three
    # readings gives way to the round's absence (incomplete-programme, K on 2 of 3 rounds)
    # and to a statement that the two readings left are judged by no rule (the median rule
    # cannot judge two), naming both, with a typo's effect per ″ at the smaller stop (60°)
    gone = {"readings-not-judged"}
    assert {(f.code, f.line) for f in clean if f.code not in gone} <= \
        {(f.code, f.line) for f in found}
    assert any(f.code == "incomplete-programme" and "(7.1)" in f.message and "round 2" in
               f.message for f in found)
    nj = [f for f in found if f.code == "readings-not-judged" and f.clause == "7.1"]
    assert len(nj) == 1 and nj[0].action == "flagged" and nj[0].line == 7
    assert "lines 7, 9 judged by no rule (2 readings" in nj[0].message
    # 1″ at 60° of 2 rounds: K by 1/(60 · 3600)/2 = 2.3 ppm, K_l by 1/(60 · 3600) = 0.00046 %
    k_ppm = 1.0 / (60.0 * 3600.0) / 2 * 1e6
    kl_pct = 1.0 / (60.0 * 3600.0) * 100.0
    assert f"moves K by up to {k_ppm:.2g} ppm and K_l by up to {kl_pct:.2g} %" in nj[0].message
    # the median rule indeed cannot judge two readings: neither departs beyond its threshold
    for d in (0.1, 3.0, 1e4):
        r = np.array([0.0, d])
        med = np.median(r)
        thr = max(5.0 * 1.4826 * np.median(np.abs(r - med)), 5.0)
        assert not (np.abs(r - med) > thr).any()


def test_lazy_hooks_import_on_call():
    f = lazy("math:hypot")
    assert repr(f) == "lazy('math:hypot')" and f(3.0, 4.0) == 5.0
    assert lazy("operator:add", 2)(3) == 5
