"""The command line builds its parser without the scientific stack: each sub-command imports
its analysis when it runs, and loading a specification's ``SPEC`` imports none of its
computation (the hooks are :class:`gonio.specs.lazy` references). Checked in a fresh
interpreter through ``sys.modules``, never by timing (benchmarks/bench_cli_startup.py times
it)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: What building the parser must not import (each costs 0.1–1 s of start-up).
HEAVY = ("numpy", "scipy", "scipy.stats", "pandas", "pyarrow", "matplotlib", "sympy")


def _loaded_after(code: str) -> list[str]:
    """The modules of HEAVY that a fresh interpreter holds after running ``code``."""
    probe = f"{code}\nimport json, sys\nprint(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))"
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         env=env, cwd=ROOT, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_whole_parser_imports_no_scientific_module():
    code = "from gonio.cli import build_parser\np = build_parser()\n" \
           "assert {'calibrate', 'demo', 'align', 'thermal-model'} <= set(p._subparsers._group_actions[0].choices)"
    assert _loaded_after(code) == []


@pytest.mark.parametrize("argv", [["calibrate", "--help"], ["demo", "--help"],
                                  ["align", "--help"], ["--help"]])
def test_help_imports_no_scientific_module(argv):
    code = ("import contextlib, io\nfrom gonio.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()) as buf:\n"
            f"    rc = main({argv!r})\n"
            "assert rc == 0 and 'usage: gonio' in buf.getvalue(), (rc, buf.getvalue())")
    assert _loaded_after(code) == []


def test_loading_every_specification_imports_no_scientific_module():
    assert _loaded_after("from gonio.specs import available\nassert len(available()) >= 4") == []


def test_the_probe_sees_a_heavy_import():
    """The check above can fail: a module that imports numpy is seen."""
    assert "numpy" in _loaded_after("import gonio.formats.jsonsafe")


def test_light_constants_agree_with_the_modules_that_use_them():
    """The constants written where loading SPEC reads them are those the analysis uses."""
    from gonio.specs.triad_alignment.readings import FORMAT
    from gonio.specs import get
    from gonio.specs.iec62047_20 import items as iec_items
    from gonio.specs.jjf1535 import items as jjf_items
    from gonio.specs.ogam_draft.items import ITEM_KEYS
    from gonio.specs.triad_alignment.calibration import item_keys

    assert get("triad-alignment").readings_format == FORMAT
    assert get("triad-alignment").item_keys == item_keys()
    assert get("ogam-draft").item_keys == tuple(ITEM_KEYS)
    for key, mod in (("jjf1535-2015", jjf_items), ("iec62047-20", iec_items)):
        spec = get(key)
        assert spec.item_keys == tuple(r[0] for r in mod.ITEMS)
        assert spec.clauses == tuple(r[2] for r in mod.ITEMS)
        assert all(callable(r[3]) and r[3].__module__ == mod.__name__ for r in mod.ITEMS)
