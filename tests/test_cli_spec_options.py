"""A specification's own options of ``gonio calibrate``, ``simulate``, ``budget``,
``validate`` and the nested ``bench serve`` come through its ``arguments`` hooks (docs/kit.md#command-line-options-of-its-own):
the command line holds none of them, another specification's option is refused in one line
(exit 2), a plug-in's own option reaches its hook, and a broken hook costs only its own
options."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

import gonio.specs
from gonio.cli import build_parser, main
from gonio.errors import GonioError
from gonio.specs import Specification

ROOT = Path(__file__).resolve().parents[1]

#: The options the built-in specifications add, by command and key.
OWN = {"calibrate": {"ogam-draft": {"--budget", "--tilt", "--table-calibration"},
                     "triad-alignment": {"--thermal", "--robust"}},
       "simulate": {"ogam-draft": {"--table", "--stream", "--stream-format"}},
       "budget": {"ogam-draft": {"--table-mpe-arcsec", "--tilt-deg", "--zero-stability-dph",
                                 "--duration-min", "--repeatability-arcsec", "--k"}},
       # --cases is shared (the optical draft's bench cases, the rate studies' typeb/worst):
       # one option, in the group of the first specification that adds it
       "validate": {"iec62047-20": {"--cases"}, "jjf1535-2015": set(),
                    "ogam-draft": {"--truth", "--extra-components", "--u-scale",
                                   "--sample-rate-hz", "--all-items", "--monte-carlo"}}}


def _command(parser: argparse.ArgumentParser, name: str) -> argparse.ArgumentParser:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action.choices[name]
    raise AssertionError("no sub-commands")


def _calibrate(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    return _command(parser, "calibrate")


def _options(p: argparse.ArgumentParser) -> set[str]:
    return {o for a in p._actions for o in a.option_strings}


def _own_flags(command: str) -> set[str]:
    """The option strings gonio's own ``cmd_<command>.py`` adds (no specification's)."""
    import importlib

    mod = importlib.import_module(f"gonio.cli.cmd_{command}")
    parser = argparse.ArgumentParser()
    mod.register(parser.add_subparsers())
    return _options(_command(parser, command))


@pytest.mark.parametrize("command", sorted(OWN))
def test_the_command_line_names_no_specification_option(command):
    assert not _own_flags(command) & set().union(*OWN[command].values())


@pytest.mark.parametrize("argv", [None, ["calibrate", "x.csv", "--out", "o"]])
def test_each_specification_adds_its_own_group(argv):
    p = _calibrate(build_parser(argv))
    groups = {g.title: {o for a in g._group_actions for o in a.option_strings}
              for g in p._action_groups}
    for key, flags in OWN["calibrate"].items():
        assert groups[f"options of --spec {key}"] == flags
    assert p.get_default("spec_options") == ("budget", "tilt", "table_calibration", "thermal",
                                              "robust")
    assert set(p.get_default("spec_inputs")) == {"tilt", "table_calibration",
                                                 "thermal"}          # metavar FILE


@pytest.mark.parametrize("command", ["simulate", "budget", "validate"])
def test_every_command_gets_the_specifications_groups(command):
    p = _command(build_parser([command]), command)
    groups = {g.title: {o for a in g._group_actions for o in a.option_strings}
              for g in p._action_groups}
    for key, flags in OWN[command].items():
        assert groups[f"options of --spec {key}"] == flags


@pytest.mark.parametrize("argv, flag", [
    (["simulate", "--spec", "jjf1535-2015", "--table", "t.toml"], "--table"),
    (["simulate", "--spec", "iec62047-20", "--stream"], "--stream"),
    (["budget", "--spec", "jjf1535-2015", "--k", "3"], "--k"),
    (["validate", "--spec", "jjf1535-2015", "--trials", "2", "--u-scale", "2"], "--u-scale")])
def test_another_specifications_option_is_refused_in_every_command(argv, flag, tmp_path,
                                                                   capsys):
    if argv[0] == "simulate":
        argv = argv + ["--out", str(tmp_path / "o")]
    rc = main(argv)
    err = capsys.readouterr().err
    assert rc == 2
    assert err == f"gonio: error: {flag} does not apply to 'gonio {argv[0]} --spec {argv[2]}'\n"
    assert not (tmp_path / "o").exists()


def test_a_common_option_the_specification_does_not_take_is_named_as_typed(capsys):
    assert main(["budget", "--spec", "jjf1535-2015", "--monte-carlo", "10"]) == 2
    assert capsys.readouterr().err == ("gonio: error: --monte-carlo does not apply to "
                                       "'gonio budget --spec jjf1535-2015'\n")


def test_another_command_does_not_load_them():
    # gonio's own command first: that command alone is registered (calibrate is not there
    # to carry the specifications' calibrate options), and the full parser has them
    sub = [a for a in build_parser(["demo", "--out", "o"])._actions
           if isinstance(a, argparse._SubParsersAction)][0]
    assert set(sub.choices) == {"demo"}
    assert {"--budget", "--thermal"} <= _options(_calibrate(build_parser()))


def test_calibrate_alone_keeps_the_options_another_command_adds():
    # gonio calibrate run alone still takes gonio db's --record (and its store options):
    # the command's parser is built with the modules that extend it
    alone = _options(_calibrate(build_parser(["calibrate", "r.csv"])))
    assert {"--record", "--record-user", "--data"} <= alone
    assert alone == _options(_calibrate(build_parser()))


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
    monkeypatch.setattr(gonio.specs, "command_arguments",
                        lambda command: hooks if command == "calibrate" else [])
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


@pytest.mark.parametrize("arguments", [{"calibrate": "no reference"},
                                       {"acquire": "mod:fn"}, "mod:fn",
                                       {"bench": "mod:fn"}])    # a nested command: its words
def test_the_field_maps_commands_to_module_function_references(arguments):
    with pytest.raises(GonioError, match="field arguments must be a dict"):
        Specification(key="s", title_en="S", title_zh="S", clause_doc="", default_protocol="",
                      default_bench="", calibrate=print, arguments=arguments)


PLUGIN = '''\
import json
from pathlib import Path

from gonio.atomic import output_dir, write_text
from gonio.errors import GonioError
from gonio.specs import Specification


def simulate(out, *, protocol=None, bench=None, seed=0, gain=None):
    with output_dir(Path(out)) as stage:
        write_text(stage / "readings.csv", json.dumps({"gain": gain, "seed": seed}))
    return {"readings": Path(out) / "readings.csv"}


class Budget:
    def __init__(self, window):
        self.window = window

    def to_dict(self):
        return {"window": self.window}

    def to_text(self):
        return f"window {self.window}"


def budget(window=None, monte_carlo_trials=None, seed=None):
    if window is not None and window <= 0:
        raise GonioError(f"must be > 0, got {window}", key="window")
    return Budget(window)


def serve(bench, ports, *, speed=1.0, seed=0, faults=None, tone=None):
    raise GonioError(f"serving {bench} with tone {tone}")       # what reached the hook


SPEC = Specification(
    key="plug-opts", title_en="P", title_zh="P", clause_doc="", default_protocol="",
    default_bench="", calibrate=print, simulate=simulate, budget=budget, serve=serve,
    simulate_options=frozenset({"gain"}), budget_options=frozenset({"window"}),
    serve_options=frozenset({"tone"}),
    arguments={"simulate": "plug_opts.cli:add_simulate", "budget": "plug_opts.cli:add_budget",
               "bench serve": "plug_opts.cli:add_serve"})
'''

PLUGIN_CLI = '''\
def add_simulate(group):
    group.add_argument("--gain", type=float, default=None, help="the plug-in's gain")


def add_budget(group):
    group.add_argument("--window", "--win", dest="window", type=float, default=None,
                       help="the plug-in's window")


def add_serve(group):
    group.add_argument("--tone", type=float, default=None, help="the plug-in's served tone")
'''


@pytest.fixture
def plug_opts(tmp_path, monkeypatch):
    """A plug-in, outside gonio, that adds its own simulate and budget options."""
    import importlib
    import sys

    pkg = tmp_path / "plug_opts"
    pkg.mkdir()
    (pkg / "__init__.py").write_text(PLUGIN, encoding="utf-8")
    (pkg / "cli.py").write_text(PLUGIN_CLI, encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    monkeypatch.setattr(gonio.specs, "_entry_points",
                        lambda: {**gonio.specs.BUILT_IN, "plug-opts": "plug_opts:SPEC"})
    yield
    for m in [m for m in sys.modules if m.startswith("plug_opts")]:
        del sys.modules[m]


def test_a_plugins_own_simulate_option_reaches_its_hook(plug_opts, tmp_path, capsys):
    out = tmp_path / "sim"
    assert main(["simulate", "--spec", "plug-opts", "--gain", "2.5", "--seed", "7",
                 "--out", str(out)]) == 0
    assert json.loads((out / "readings.csv").read_text()) == {"gain": 2.5, "seed": 7}
    capsys.readouterr()
    # the plug-in's option, given to a built-in specification: one line, exit 2, nothing written
    rc = main(["simulate", "--spec", "ogam-draft", "--gain", "2", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1, err
    assert "--gain does not apply to 'gonio simulate --spec ogam-draft'" in err
    assert not (tmp_path / "o").exists()


def test_a_plugins_own_budget_option_and_its_error_name_the_option(plug_opts, capsys):
    assert main(["budget", "--spec", "plug-opts", "--window", "3", "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == {"window": 3.0}
    assert main(["budget", "--spec", "plug-opts", "--window", "-1"]) == 2
    err = capsys.readouterr().err
    assert err == "gonio: error: --window: must be > 0, got -1.0\n", err
    assert main(["budget", "--spec", "plug-opts", "--k", "2"]) == 2
    assert "--k does not apply to 'gonio budget --spec plug-opts'" in capsys.readouterr().err
    assert main(["budget", "--spec", "ogam-draft", "--win", "2"]) == 2    # its first flag
    assert capsys.readouterr().err == ("gonio: error: --window does not apply to "
                                       "'gonio budget --spec ogam-draft'\n")


def test_the_help_of_each_command_shows_the_plugins_group(plug_opts, capsys):
    for command, flag in (("simulate", "--gain"), ("budget", "--window")):
        with pytest.raises(SystemExit):
            build_parser([command]).parse_args([command, "--help"])
        out = capsys.readouterr().out
        assert "options of --spec plug-opts:" in out and flag in out


# ------------------------------------------------------------------ gonio bench serve

def _serve(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    return _command(_command(parser, "bench"), "serve")


def test_bench_serve_names_no_specification_option():
    """gonio's own ``bench serve`` holds none of the goniometer's options; the optical
    draft adds them through ``arguments["bench serve"]`` (a nested command, by its words)."""
    import importlib

    parser = argparse.ArgumentParser()
    importlib.import_module("gonio.cli.cmd_bench").register(parser.add_subparsers())
    own = _options(_serve(parser))
    assert not own & {"--range-deg", "--warm-up"}
    p = _serve(build_parser(["bench", "serve"]))
    groups = {g.title: {o for a in g._group_actions for o in a.option_strings}
              for g in p._action_groups}
    assert groups["options of --spec ogam-draft"] == {"--range-deg", "--warm-up"}


class _Served(Exception):
    pass


def test_bench_serve_options_reach_the_specifications_hook(monkeypatch):
    """Given options reach the ``serve`` hook by keyword; those not given are left to the
    hook's defaults (not passed)."""
    import gonio.specs.ogam_draft.served as served

    calls = []

    def fake(bench, ports, **kwargs):
        calls.append((bench, ports, kwargs))
        raise _Served("stop before serving")    # the command reports it; nothing is served

    monkeypatch.setattr(served, "serve", fake)
    assert main(["bench", "serve", "--table-port", "0", "--gyro-port", "0",
                 "--range-deg", "10"]) != 0
    [(bench, ports, kwargs)] = calls
    assert bench == "rlg" and ports == {"table": 0, "gyro": 0}
    assert kwargs["range_deg"] == 10.0 and "warm_up_s" not in kwargs


def test_a_rate_bench_refuses_the_goniometers_serve_options(capsys):
    rc = main(["bench", "serve", "--bench", "mems-adxrs610", "--table-port", "0",
               "--gyro-port", "0", "--warm-up", "5"])
    assert rc == 2
    assert capsys.readouterr().err == ("gonio: error: gonio bench serve: --warm-up does not "
                                       "apply to a rate bench (mems-adxrs610)\n")


def test_a_plugins_own_serve_option_reaches_its_hook_and_is_refused_elsewhere(plug_opts,
                                                                             capsys):
    """The nested command's hook (``arguments["bench serve"]``): the plug-in's option is in
    ``gonio bench serve``'s help under its group and reaches its ``serve`` hook; given with
    another specification, or another's given with it, it is refused in one line, exit 2."""
    p = _serve(build_parser(["bench", "serve"]))
    groups = {g.title: {o for a in g._group_actions for o in a.option_strings}
              for g in p._action_groups}
    assert groups["options of --spec plug-opts"] == {"--tone"}
    assert groups["options of --spec ogam-draft"] == {"--range-deg", "--warm-up"}
    ports = ["--table-port", "0", "--gyro-port", "0"]
    assert main(["bench", "serve", "--spec", "plug-opts", "--bench", "rlg", *ports,
                 "--tone", "3"]) == 2
    assert capsys.readouterr().err == "gonio: error: serving rlg with tone 3.0\n"
    for argv, flag, key in ((["--spec", "plug-opts", "--bench", "rlg", "--warm-up", "5"],
                             "--warm-up", "plug-opts"),
                            (["--tone", "3"], "--tone", "ogam-draft")):
        assert main(["bench", "serve", *ports, *argv]) == 2
        assert capsys.readouterr().err == (f"gonio: error: {flag} does not apply to "
                                           f"'gonio bench serve --spec {key}'\n")
