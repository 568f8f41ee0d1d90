"""A specification plug-in from outside gonio (tests/plugins/acme_rate_check, its own
pyproject.toml) is found through its ``gonio.specs`` entry point and runs through simulate,
calibrate, demo, validate, the certificate and the DCC — the same commands, no gonio module
edited. Also: the registry loads every built-in the same way, refuses a broken entry point,
and loading a specification never imports the virtual bench."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import pytest

from gonio.cli import main

ROOT = Path(__file__).resolve().parents[1]
PLUGIN = ROOT / "tests" / "plugins" / "acme_rate_check"


def test_plugin_lives_outside_gonio_and_gonio_never_names_it():
    assert not PLUGIN.is_relative_to(ROOT / "gonio")
    hits = [p for p in (ROOT / "gonio").rglob("*.py") if "acme" in p.read_text(encoding="utf-8")]
    assert hits == []


def test_registry_finds_the_plugin_beside_the_built_ins(plugin):
    from gonio.specs import BUILT_IN, available, get

    specs = available()
    assert set(BUILT_IN) | {"acme-rate-check"} <= set(specs)
    assert get("acme-rate-check").title_en.startswith("ACME RC-1")
    assert "acme-rate-check" not in BUILT_IN


def test_simulate_calibrate_certificate(plugin, tmp_path, capsys):
    sim, cal = tmp_path / "sim", tmp_path / "cal"
    assert main(["simulate", "--spec", "acme-rate-check", "--seed", "3", "--out", str(sim)]) == 0
    assert sorted(p.name for p in sim.iterdir() if p.name != "gonio-manifest.json") == \
        ["readings.csv", "truth.json"]
    # the readings name their specification ('# spec:'): no --spec needed to calibrate
    assert main(["calibrate", str(sim / "readings.csv"), "--out", str(cal), "--dcc"]) == 0
    out = capsys.readouterr().out
    assert "ACME RC-1" in out and "scale factor K" in out
    res = json.loads((cal / "results.json").read_text(encoding="utf-8"))
    truth = json.loads((sim / "truth.json").read_text(encoding="utf-8"))["items"]
    for key in ("scale_factor", "bias"):
        it = res["items"][key]
        assert it["measured"] and abs(it["value"] - truth[key]["value"]) <= it["uncertainty"]["U"]
    assert res["spec"] == "acme-rate-check"
    html = (cal / "certificate.html").read_text(encoding="utf-8")
    assert "Rate gyro rate-table check results" in html and "ACME RC-1 clause 5" in html
    # no recalibration interval unless the laboratory file says one was agreed (17025 7.8.4.3)
    assert "Recalibration interval" not in html
    # only the figures of roles the plug-in has: no empty "not measured" panels
    import re
    assert re.findall(r'<figure id="fig-([a-z_]+)"', html) == ["io_line", "cw_ccw"]
    assert (cal / "certificate.pdf").read_bytes()[:5] == b"%PDF-"
    assert b"acme-rate-check" in (cal / "certificate.dcc.xml").read_bytes() or \
        b"ACME RC-1" in (cal / "certificate.dcc.xml").read_bytes()
    # an option the plug-in does not take is refused, naming it and the specification
    assert main(["calibrate", str(sim / "readings.csv"), "--out", str(tmp_path / "x"),
                 "--robust"]) == 2
    assert "--robust does not apply to 'gonio calibrate --spec acme-rate-check'" in \
        capsys.readouterr().err


def test_its_own_simulate_option(plugin, tmp_path, capsys):
    """``--samples`` comes from the plug-in's ``arguments["simulate"]`` hook (gonio's command
    line holds no such option): it reaches the plug-in's ``simulate``, shows under its group
    in ``--help``, and another specification refuses it in one line."""
    from gonio.cli import build_parser

    for samples, sim in ((None, tmp_path / "a"), (5, tmp_path / "b")):
        extra = [] if samples is None else ["--samples", str(samples)]
        assert main(["simulate", "--spec", "acme-rate-check", "--out", str(sim)] + extra) == 0
        rows = [ln for ln in (sim / "readings.csv").read_text().splitlines()
                if ln and not ln.startswith("#")][1:]
        assert len(rows) == 3 * 2 * (samples or 20)      # 3 rates, both ways (clause 4.1)
    capsys.readouterr()
    with pytest.raises(SystemExit):
        build_parser(["simulate"]).parse_args(["simulate", "--help"])
    shown = capsys.readouterr().out
    assert "options of --spec acme-rate-check:" in shown and "--samples" in shown
    assert main(["simulate", "--spec", "jjf1535-2015", "--samples", "5",
                 "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--samples does not apply to 'gonio simulate --spec " \
                                     "jjf1535-2015'" in err, err


def test_the_procedures_tolerance_is_the_default_limit(plugin, tmp_path, capsys):
    """``SPEC.default_limits`` (ACME RC-1 clause 6: |B| ≤ 1 °/s) is decided where the lab
    file gives no limit for the bias, labelled as the specification's default in
    results.json and on the certificate; a lab file's own limit replaces it."""
    sim = tmp_path / "sim"
    assert main(["simulate", "--spec", "acme-rate-check", "--seed", "3", "--out", str(sim)]) == 0
    assert main(["calibrate", str(sim / "readings.csv"), "--out", str(tmp_path / "a")]) == 0
    res = json.loads((tmp_path / "a" / "results.json").read_text(encoding="utf-8"))
    c = res["items"]["bias"]["conformity"]
    assert (c["limits_from"], c["source"], c["lower"], c["upper"]) == \
        ("specification default", "ACME RC-1 clause 6", -1.0, 1.0)
    assert c["outcome"] == "pass" and c["rule"] == "simple"
    assert res["items"]["scale_factor"]["conformity"] is None
    html = (tmp_path / "a" / "certificate.html").read_text(encoding="utf-8")
    assert "(default of the specification)" in html and "ACME RC-1 clause 6" in html
    lab = tmp_path / "lab.toml"
    example = (ROOT / "protocols" / "lab-example.toml").read_text(encoding="utf-8")
    lab.write_text(example.split("\n[[specification_limits]]\n")[0] + "\n"
                   '[[specification_limits]]\nitem = "bias"\nupper = 1.0e-9\n'
                   'source = "customer"\n', encoding="utf-8")
    capsys.readouterr()
    assert main(["calibrate", str(sim / "readings.csv"), "--lab", str(lab),
                 "--out", str(tmp_path / "b")]) == 0
    res = json.loads((tmp_path / "b" / "results.json").read_text(encoding="utf-8"))
    c = res["items"]["bias"]["conformity"]
    assert (c["limits_from"], c["source"], c["lower"], c["upper"]) == \
        ("lab file", "customer", None, 1.0e-9)
    html = (tmp_path / "b" / "certificate.html").read_text(encoding="utf-8")
    assert "(default of the specification)" not in html
    # gonio's four documents give no tolerance of their items (docs/certificate.md)
    from gonio.specs import BUILT_IN, default_limits
    assert all(default_limits(k) == [] for k in BUILT_IN)


def test_demo_writes_a_valid_dcc(plugin, tmp_path, dcc_schema, capsys):
    d = tmp_path / "demo"
    assert main(["demo", "--spec", "acme-rate-check", "--out", str(d)]) == 0
    wrote = capsys.readouterr().out.split("wrote ")[-1]
    for name in ("certificate.dcc.xml", "certificate.html", "certificate.pdf", "readings.csv",
                 "results.json", "summary.txt", "truth.json"):
        assert name in wrote
    dcc_schema.validate(str(d / "certificate.dcc.xml"))


def test_validate_counts_coverage_against_the_bench_truth(plugin, tmp_path, capsys):
    assert main(["validate", "--spec", "acme-rate-check", "--trials", "40", "--seed", "1",
                 "--workers", "1", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["settings"]["spec"] == "acme-rate-check"
    cov = {r["key"]: r for r in rep["items"]}
    assert set(cov) == {"scale_factor", "bias", "asymmetry"}
    for r in cov.values():             # U at ~95 %: neither far too narrow nor far too wide
        assert r["n"] == 40 and 0.8 <= r["coverage"] <= 1.0
        assert 0.3 <= r["median_norm_error"] <= 1.3
    # the bench-case options of the default specification's study are refused
    assert main(["validate", "--spec", "acme-rate-check", "--trials", "2", "--cases",
                 "all"]) == 2
    assert "--cases does not apply" in capsys.readouterr().err


def test_the_plugin_adds_its_own_command(plugin, capsys):
    """``Specification.commands``: the plug-in's ``gonio acme-programme`` is on gonio's
    command line, listed with the built-in commands, and ends like them (exit 2, one line)."""
    assert main(["--help"]) == 0
    assert "acme-programme" in capsys.readouterr().out
    assert main(["acme-programme", "--samples", "5"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines == [f"{s}{r:g} °/s  5 samples" for r in (10, 50, 100) for s in "+-"]
    assert main(["acme-programme", "--samples", "1"]) == 2
    err = capsys.readouterr().err
    assert err == "gonio: error: --samples must be at least 2 (clause 4.1), got 1\n"


def test_a_builtin_command_loads_no_specification_for_its_parser(monkeypatch):
    """``gonio earth …`` builds its parser without loading every specification (a second of
    start-up); ``gonio --help`` and a specification's own command load them."""
    import gonio.specs as specs
    from gonio.cli import build_parser

    def subcommands(parser):
        return set(next(a for a in parser._actions if a.dest == "command").choices)

    assert {"align", "thermal-model"} <= subcommands(build_parser([]))
    assert "align" in subcommands(build_parser(["align", "x.csv"]))
    monkeypatch.setattr(specs, "commands", lambda: pytest.fail("loaded the specifications"))
    got = subcommands(build_parser(["earth", "--latitude-deg", "30"]))
    assert "earth" in got and "align" not in got


def test_a_broken_command_leaves_the_others_working(monkeypatch, capsys):
    """A specification that cannot be loaded, a command module that cannot be imported and
    a command name taken twice each cost only that command, with a warning naming it."""
    import gonio.specs as specs
    from gonio.specs import BUILT_IN

    broken = {**BUILT_IN, "nope": "no_such_module:SPEC"}
    monkeypatch.setattr(specs, "_entry_points", lambda: broken)
    assert main(["earth", "--latitude-deg", "30", "--axis", "up"]) == 0
    assert capsys.readouterr().err == ""          # a built-in command loads no specification
    from gonio.cli import build_parser

    with pytest.warns(UserWarning, match="the specification entry point nope = "
                      "'no_such_module:SPEC' cannot be loaded"):
        parser = build_parser([])                  # gonio --help: every specification
    assert "align" in next(a for a in parser._actions if a.dest == "command").choices
    with pytest.warns(UserWarning, match="nope.*its commands are not available"):
        names = [n for n, _ in specs.commands()]
    assert {"align", "thermal-model"} <= set(names)
    triad = specs.get("triad-alignment")
    bad = dataclasses.replace(triad, commands=(("align", "no_such_module:add"),
                                               ("thermal-model", triad.commands[1][1]),
                                               ("thermal-model", triad.commands[1][1])))
    monkeypatch.setattr(specs, "_entry_points", lambda: {"triad-alignment": "x:SPEC"})
    monkeypatch.setattr(specs, "_load", lambda key, ref: bad)
    with pytest.warns(UserWarning) as rec:
        names = [n for n, _ in specs.commands()]
    assert names == ["thermal-model"]
    msgs = " | ".join(str(w.message) for w in rec)
    assert "'align' of specification 'triad-alignment' ('no_such_module:add') cannot be " \
        "loaded" in msgs and "adds one by that name" in msgs


def test_a_broken_entry_point_is_one_clear_error(tmp_path):
    from gonio.errors import GonioError
    from gonio.specs import _load

    with pytest.raises(GonioError, match="cannot be loaded"):
        _load("nope", "no_such_module:SPEC")
    with pytest.raises(GonioError, match="is not a gonio.specs.Specification"):
        _load("nope", "math:pi")
    with pytest.raises(GonioError, match="must be the key"):
        _load("other-key", "gonio.specs.ogam_draft:SPEC")


def test_loading_every_specification_never_imports_the_simulator():
    """Calibrating needs SPEC and its calibrate: neither imports gonio.bench (only the
    simulate/plan/truth modules do, loaded lazily; tests/test_layers.py checks the source)
    nor a module of the report, nor Matplotlib or lxml. (The registry checks that the per-item
    renderer, ``gonio.report.item_outputs``, exists with ``importlib.util.find_spec``, which
    imports its parent package, ``gonio/report/__init__.py``: a docstring.)"""
    code = ("import sys\nfrom gonio.specs import available\n"
            "for s in available().values():\n    s.calibrate\n"
            "bad = sorted(m for m in sys.modules if m.startswith(('gonio.bench', 'gonio.report.',"
            " 'matplotlib', 'lxml')))\n"
            "print(bad)\nsys.exit(1 if bad else 0)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stdout + r.stderr
