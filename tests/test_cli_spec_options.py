"""A specification's own ``gonio calibrate`` options come through its ``calibrate_arguments``
hook (docs/kit.md#command-line-options-of-its-own): the command line holds none of them,
another specification's option is refused in one line (exit 2), and a broken hook costs only
its own options."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

import gonio.specs
from gonio.cli import build_parser, main
from gonio.errors import GonioError
from gonio.specs import Specification

ROOT = Path(__file__).resolve().parents[1]

#: The options the built-in specifications add, by key.
OWN = {"ogam-draft": {"--budget", "--tilt"}, "triad-alignment": {"--thermal", "--robust"}}


def _calibrate(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action.choices["calibrate"]
    raise AssertionError("no sub-commands")


def _options(p: argparse.ArgumentParser) -> set[str]:
    return {o for a in p._actions for o in a.option_strings}


def test_the_command_line_names_no_specification_option():
    src = "".join(p.read_text(encoding="utf-8") for p in (ROOT / "gonio/cli").glob("*.py"))
    for flags in OWN.values():
        for flag in flags:
            assert not re.search(rf"[\"']{flag}[\"']", src), flag


@pytest.mark.parametrize("argv", [None, ["calibrate", "x.csv", "--out", "o"]])
def test_each_specification_adds_its_own_group(argv):
    p = _calibrate(build_parser(argv))
    groups = {g.title: {o for a in g._group_actions for o in a.option_strings}
              for g in p._action_groups}
    for key, flags in OWN.items():
        assert groups[f"options of --spec {key}"] == flags
    assert p.get_default("spec_options") == ("budget", "tilt", "thermal", "robust")
    assert set(p.get_default("spec_inputs")) == {"tilt", "thermal"}    # metavar FILE


def test_another_command_does_not_load_them():
    assert not _options(_calibrate(build_parser(["demo", "--out", "o"]))) & {"--budget",
                                                                            "--thermal"}


def test_another_specifications_option_is_one_line_exit_2(tmp_path, capsys):
    readings = tmp_path / "r.csv"
    readings.write_text("# spec: jjf1535-2015\n")
    rc = main(["calibrate", str(readings), "--tilt", "t.json", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.count("\n") == 1 and "--tilt does not apply to 'gonio calibrate --spec " \
                                     "jjf1535-2015'" in err, err


def test_an_unknown_option_is_still_refused_by_argparse(tmp_path, capsys):
    assert main(["calibrate", "r.csv", "--budgett", "draft", "--out", str(tmp_path)]) == 2
    assert "unrecognized arguments: --budgett" in capsys.readouterr().err


def _spec(key, options):
    return Specification(key=key, title_en=key, title_zh=key, clause_doc="",
                         default_protocol="", default_bench="", calibrate=print,
                         calibrate_options=frozenset(options))


def test_a_broken_hook_costs_only_its_own_options(monkeypatch):
    def good(g):
        g.add_argument("--window", default=None, type=float)
        g.add_argument("--flag", action="store_true")

    def shares(g):                       # the same option as 'good': added once, shared
        g.add_argument("--window", default=None, type=float)

    def raises(g):
        raise RuntimeError("boom")

    def foreign_dest(g):                 # not in its calibrate_options
        g.add_argument("--other", default=None)

    def takes_out(g):                    # one of gonio calibrate's own options
        g.add_argument("--out", default=None, dest="window")

    def has_default(g):
        g.add_argument("--window2", default=3.0, dest="window2")

    hooks = [(_spec("a", {"window", "flag"}), good), (_spec("b", {"window"}), shares),
             (_spec("c", {"window"}), raises), (_spec("d", {"window"}), foreign_dest),
             (_spec("e", {"window"}), takes_out), (_spec("f", {"window2"}), has_default)]
    monkeypatch.setattr(gonio.specs, "calibrate_arguments", lambda: hooks)
    with pytest.warns(UserWarning) as caught:
        p = _calibrate(build_parser(["calibrate"]))
    said = " | ".join(str(w.message) for w in caught)
    for key, what in (("c", "RuntimeError: boom"), ("d", "'other'"),
                      ("e", "conflicting option string"), ("f", "has a default")):
        assert f"specification {key!r}" in said and what in said, (key, said)
    assert {"--window", "--flag"} <= _options(p)
    assert not {"--other", "--window2"} & _options(p)
    assert p.get_default("spec_options") == ("window", "flag")
    args = p.parse_args(["r.csv", "--out", "o", "--window", "2.5"])
    assert (args.window, args.flag) == (2.5, False)


def test_the_field_is_a_module_function_reference():
    with pytest.raises(GonioError, match="calibrate_arguments must be a 'module:function'"):
        Specification(key="s", title_en="S", title_zh="S", clause_doc="", default_protocol="",
                      default_bench="", calibrate=print, calibrate_arguments="no reference")
