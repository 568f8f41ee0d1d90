"""A specification is checked when it loads, and a broken one costs only its own key.

Each broken plug-in is a real package written into a temporary folder and registered as an
entry point beside gonio's own (``gonio.specs._entry_points`` patched), as a laboratory's
``pip install`` would leave it: an import error, an object that is no Specification, a key
that is not the entry point's name, a misspelt field, a field of the wrong type, a module
named by ``outputs`` or ``commands`` that does not exist, a certificate content with a typo.
"""

from __future__ import annotations

import dataclasses
import importlib
import sys
import textwrap

import pytest

import gonio.specs as specs
from gonio.cli import main
from gonio.errors import GonioError
from gonio.specs import BUILT_IN, Coverage, Specification

HEAD = textwrap.dedent("""\
    from gonio.specs import Specification
    BASE = dict(title_en="B", title_zh="B", clause_doc="", default_protocol="",
                default_bench="", calibrate=print)
    """)

#: package name → (body of its __init__.py after HEAD, what the one-line error must say)
BROKEN = {
    "brk_import": ("import no_such_dependency\n", "ModuleNotFoundError: No module named "
                   "'no_such_dependency'"),
    "brk_runtime": ("SPEC = 1 / 0\n", "ZeroDivisionError"),
    "brk_notspec": ("SPEC = dict(key='brk-notspec')\n", "is not a gonio.specs.Specification"),
    "brk_key": ("SPEC = Specification(key='another', **BASE)\n", "loads key 'another'"),
    "brk_typo": ("SPEC = Specification(key='brk-typo', calibrat=print,\n"
                 "    **{k: v for k, v in BASE.items() if k != 'calibrate'})\n",
                 "unexpected keyword argument 'calibrat' (did you mean 'calibrate'?)"),
    "brk_type": ("SPEC = Specification(key='brk-type', item_keys='bias', **BASE)\n",
                 "specification 'brk-type': field item_keys must be a tuple of str, got 'bias'"),
    "brk_outputs": ("SPEC = Specification(key='brk-outputs', outputs='brk_outputs.nope',"
                    " **BASE)\n", "field outputs names module 'brk_outputs.nope', which does "
                    "not exist"),
    "brk_command": ("SPEC = Specification(key='brk-command', commands=(('x', 'nomod:add'),),"
                    " **BASE)\n", "field commands['x'] names module 'nomod'"),
    "brk_cmdfn": ("SPEC = Specification(key='brk-cmdfn', commands=(('x', 'brk_cmdfn.cli:ad'),),"
                  " **BASE)\n", "field commands['x'] names 'brk_cmdfn.cli:ad', and "
                  "brk_cmdfn.cli defines no ad"),
    "brk_args": ("SPEC = Specification(key='brk-args', arguments={'simulate': 'brk_args.cli:ad'},"
                 " **BASE)\n", "field arguments['simulate'] names 'brk_args.cli:ad', and "
                 "brk_args.cli defines no ad"),
}


@pytest.fixture
def broken(tmp_path, monkeypatch):
    """The broken packages on sys.path and registered beside the built-ins."""
    for name, (body, _) in BROKEN.items():
        (tmp_path / name).mkdir()
        (tmp_path / name / "__init__.py").write_text(HEAD + body, encoding="utf-8")
        (tmp_path / name / "cli.py").write_text("def add(sub):\n    pass\n", encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    eps = {**BUILT_IN, **{n.replace("_", "-"): f"{n}:SPEC" for n in BROKEN}}
    monkeypatch.setattr(specs, "_entry_points", lambda: eps)
    yield eps
    for m in [m for m in sys.modules if m.startswith("brk_")]:
        del sys.modules[m]


def test_each_broken_plugin_is_one_line_naming_it(broken):
    for name, (_, says) in BROKEN.items():
        key = name.replace("_", "-")
        with pytest.raises(GonioError) as exc:
            specs.get(key)
        msg = str(exc.value)
        assert "\n" not in msg and says in msg, msg
        assert key in msg or name in msg


def test_broken_plugins_leave_the_others_available(broken):
    with pytest.warns(UserWarning) as rec:
        got = specs.available()
    assert set(got) == set(BUILT_IN)
    warned = " | ".join(str(w.message) for w in rec)
    for name in BROKEN:
        assert f"specification {name.replace('_', '-')!r} is not available" in warned


def test_gonio_help_and_another_spec_keep_working(broken, tmp_path, capsys):
    assert main(["--help"]) == 0
    out, err = capsys.readouterr()
    assert "align" in out                         # a built-in specification's own command
    lines = err.splitlines()
    assert all(line.startswith("gonio: warning: ") for line in lines)
    assert any("brk-typo" in line and "calibrat" in line for line in lines)
    # another specification works; the broken one fails alone, one line, exit 2
    assert main(["budget", "--spec", "jjf1535-2015"]) == 0
    assert "A.1 scale factor K" in capsys.readouterr().out
    assert main(["simulate", "--spec", "brk-typo", "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gonio: error: ") and err.count("\n") == 1 and "brk-typo" in err


def test_calibrate_another_specification_beside_broken_ones(broken, plugin, tmp_path,
                                                           monkeypatch, capsys):
    """gonio simulate and calibrate --spec of a working plug-in, with every broken one
    registered beside it: exit 0, results written."""
    eps = {**broken, "acme-rate-check": "acme_rate_check:SPEC"}
    monkeypatch.setattr(specs, "_entry_points", lambda: eps)
    sim, cal = tmp_path / "sim", tmp_path / "cal"
    assert main(["simulate", "--spec", "acme-rate-check", "--out", str(sim)]) == 0
    assert main(["calibrate", str(sim / "readings.csv"), "--spec", "acme-rate-check",
                 "--out", str(cal)]) == 0
    assert (cal / "results.json").is_file() and "bias B" in capsys.readouterr().out


BASE = dict(key="s", title_en="S", title_zh="S", clause_doc="", default_protocol="",
            default_bench="", calibrate=print)


@pytest.mark.parametrize("field, value, says", [
    ("title_en", 3, "field title_en must be a str"),
    ("calibrate", "calibrate", "field calibrate must be a callable"),
    ("screen", 1, "field screen must be a callable or None"),
    ("coverage", {"engine": "items"}, "field coverage must be a gonio.specs.Coverage"),
    ("calibrate_options", "dcc", "field calibrate_options must be a frozenset of str"),
    ("default_limits", ({"mpe": 1},), "field default_limits must be a tuple of dicts"),
    ("commands", (("x", "no colon"),), "field commands must be a tuple of (name, "),
    ("outputs", "not a module!", "field outputs must be a module name"),
    ("dcc_units", {"ppm": "ppm"}, "field dcc_units['ppm'] must be a D-SI unit"),
    ("recalibration_interval_months", 0, "must be a positive int or None"),
    ("key", "Bad Key", "field key must be lower-case letters"),
    ("coverage", Coverage(reduced={"rates": {"samples": 2}}),
     "field coverage.reduced must be empty unless default_protocol is a TOML file"),
])
def test_a_field_of_the_wrong_type_is_refused_naming_it(field, value, says):
    with pytest.raises(GonioError, match=None) as exc:
        Specification(**{**BASE, field: value})
    assert says in str(exc.value)


def test_collections_are_stored_as_their_declared_type():
    s = Specification(**BASE, item_keys=["a", "b"], calibrate_options={"dcc"},
                      commands=[["x", "m:f"]], dcc_units={"ppm": r"\ppm"})
    assert s.item_keys == ("a", "b") and s.calibrate_options == frozenset({"dcc"})
    assert s.commands == (("x", "m:f"),)
    # dataclasses.replace goes through the same check
    with pytest.raises(GonioError, match="field item_keys"):
        dataclasses.replace(s, item_keys=5)


@pytest.mark.parametrize("kw, says", [
    ({"engine": "item"}, "field engine must be 'items' or 'cases'"),
    ({"stream": -1}, "field stream must be a non-negative int"),
    ({"reduced": {"static": 5}}, "field reduced must be a dict {section: {key: value}}"),
    ({"engine": "cases"}, "field study must be a callable"),
    ({"options": "cases"}, "field options must be a frozenset of str"),
])
def test_coverage_settings_are_checked(kw, says):
    with pytest.raises(GonioError) as exc:
        Coverage(**kw)
    assert says in str(exc.value)


def test_certificate_content_is_checked(tmp_path, monkeypatch):
    """A figure role misspelt (the figure silently 'not measured' before), a name close to a
    content field, a value of the wrong shape: one line naming the specification."""
    monkeypatch.syspath_prepend(str(tmp_path))
    cases = {"cc_role": ("FIGURE_ITEMS = {'alan': 'noise'}\n", "field FIGURE_ITEMS must be"),
             "cc_typo": ("FIGURE_ITEM = {'allan': 'noise'}\n", "FIGURE_ITEM is not a content "
                         "field; did you mean FIGURE_ITEMS?"),
             "cc_shape": ("HEADING = 'Results'\n", "field HEADING must be an (English, Chinese)"),
             # the measurand conditions the per-item certificate prints are a content field
             # (a misspelt name was read by getattr and silently printed nothing)
             "cc_cond": ("ITEM_CONDITION = {'bias': ('a', 'b')}\n", "ITEM_CONDITION is not a "
                         "content field; did you mean ITEM_CONDITIONS?"),
             "cc_cond_shape": ("ITEM_CONDITIONS = {'bias': 'window W'}\n",
                               "field ITEM_CONDITIONS must be"),
             "cc_fine": ("FIGURE_ITEMS = {'allan': 'noise'}\nOWN_TABLE = 1\n", None)}
    for name, (body, says) in cases.items():
        (tmp_path / f"{name}.py").write_text(body, encoding="utf-8")
        s = Specification(**{**BASE, "key": name.replace("_", "-")}, certificate_content=name)
        if says is None:
            assert s.content_value("FIGURE_ITEMS") == {"allan": "noise"}
            assert s.content_value("PHRASES_ZH") == ()
            continue
        with pytest.raises(GonioError) as exc:
            s.content()
        assert says in str(exc.value) and repr(s.key) in str(exc.value)
    with pytest.raises(KeyError):
        s.content_value("FIGURE_ITEM")
    with pytest.raises(KeyError):                 # a document's clause no renderer prints
        s.content_value("RECAL")


def test_the_records_read_the_typed_interval(monkeypatch):
    """The records' default interval reads the typed field (it read a field that did not
    exist, so a specification could never state one)."""
    from gonio.records.services import default_interval

    default_interval.cache_clear()
    assert default_interval("jjf1535-2015")[1] == "clause 9: normally ≤ 12 months"
    spec = dataclasses.replace(specs.get("jjf1535-2015"), recalibration_interval_months=6)
    monkeypatch.setattr(specs, "get", lambda key: spec)
    default_interval.cache_clear()
    assert default_interval("jjf1535-2015") == (6, "the specification's clause 9")
    default_interval.cache_clear()


def test_the_outputs_module_is_checked(tmp_path, monkeypatch):
    """The renderer's functions: the required ones present, the optional ones found through
    a typed accessor (the pipeline asked hasattr(renderer, 'demo') before)."""
    monkeypatch.syspath_prepend(str(tmp_path))
    (tmp_path / "out_short.py").write_text("def write(*a, **k): pass\n"
                                           "def results_json(r, lab=None): pass\n"
                                           "summary = 'not a function'\n", encoding="utf-8")
    s = Specification(**{**BASE, "key": "out-short"}, outputs="out_short")
    with pytest.raises(GonioError, match="its outputs module out_short has no function summary"):
        s.renderer()
    assert callable(specs.get("triad-alignment").output_hook("demo"))
    assert specs.get("jjf1535-2015").output_hook("demo") is None
    with pytest.raises(KeyError):
        specs.get("jjf1535-2015").output_hook("write")


def test_the_item_renderer_needs_its_content_fields(tmp_path, monkeypatch):
    """The per-item renderer reads GROUPS, TITLES_ZH and HEADING without a default: a
    content module without one is refused naming it (an AttributeError deep in the
    certificate before)."""
    from gonio.kit import ITEM_RENDERER

    monkeypatch.syspath_prepend(str(tmp_path))
    (tmp_path / "cc_short.py").write_text("GROUPS = ()\nTITLES_ZH = {}\n", encoding="utf-8")
    s = Specification(**{**BASE, "key": "cc-short"}, outputs=ITEM_RENDERER,
                      certificate_content="cc_short")
    with pytest.raises(GonioError, match=r"cc_short\) defines no HEADING, which its outputs"):
        s.renderer()
    with pytest.raises(GonioError, match="defines no GROUPS, TITLES_ZH, HEADING"):
        Specification(**{**BASE, "key": "cc-none"}, outputs=ITEM_RENDERER).renderer()
    for key in ("jjf1535-2015", "iec62047-20", "triad-alignment"):
        specs.get(key).renderer()
