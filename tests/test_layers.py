"""The house rules of docs/architecture.md, checked on the source text (AST and tokens).

- imports run one way, down the layers; no import cycles between modules;
- ``uncertainty`` never imports ``gonio``; one specification never imports another;
- no module imports another module's ``_private`` name or reads a ``_private``
  attribute of an object it did not define;
- unit constants (3600, 206264.8…) are written only in ``gonio/units.py``;
- every package folder is installed (listed in ``pyproject.toml``);
- plotting lives in ``gonio/report`` and a specification's rendering modules, on Figure
  objects: nothing imports pyplot or calls ``matplotlib.use`` (a notebook user's backend is
  never switched).

Each rule is also checked to fire on a small bad example, so that the test can fail.
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Layer of each top-level group, low to high; a module may import only its own group or a
#: lower layer (docs/architecture.md#layers). Groups on one layer may not import each other.
LAYERS: dict[str, int] = {
    "gonio": 0, "gonio.units": 0, "gonio.errors": 0, "gonio.atomic": 0, "gonio.progress": 0,
    "gonio.resources": 0,
    "gonio.physics": 1, "gonio.formats": 1,
    "gonio.protocol": 2, "gonio.result": 2,
    "gonio.bench": 3, "gonio.reduce": 3,
    "gonio.analysis": 4, "gonio.instruments": 4,
    "gonio.specs": 6,
    "gonio.kit": 6.5,            # the public plug-in kit: re-exports, above the specifications
    "gonio.kit.render": 7.25,    # its rendering part: re-exports of the report, above it
    "gonio.report": 7,
    "gonio.pipeline": 8,
    "gonio.records": 9,
    "gonio.web": 10,
    "gonio.cli": 11, "gonio.__main__": 12,
}


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def group(mod: str) -> str | None:
    best = None
    for g in LAYERS:
        if (mod == g or mod.startswith(g + ".")) and (best is None or len(g) > len(best)):
            best = g
    return best


def imports_of(tree: ast.AST, mod: str, is_pkg: bool) -> list[tuple[str, list[str], int]]:
    """(imported module, names, line) for every import in a module, relative ones resolved."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                out.append((a.name, [], node.lineno))
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                pkg = mod.split(".") if is_pkg else mod.split(".")[:-1]
                pkg = pkg[:len(pkg) - node.level + 1]
                base = ".".join(pkg + ([base] if base else []))
            out.append((base, [a.name for a in node.names], node.lineno))
    return out


def python_files(*tops: str) -> list[Path]:
    files = []
    for top in tops:
        files += [p for p in (ROOT / top).rglob("*.py") if "__pycache__" not in p.parts]
    return sorted(files)


#: A specification's rendering modules (``SPEC.outputs`` and what it draws with: its
#: certificate pages, figures, standalone pages): they sit between the report and the pipeline
#: (they render the specification's results with the report; the pipeline loads ``outputs``
#: through the registry, never by name). Its data module ``certificate`` is not one.
RENDERING_MODULES = ("outputs", "certificate_pages", "figures", "pages", "dcc", "stated")
RENDERING_LAYER = LAYERS["gonio.report"] + 0.5


def is_rendering(mod: str) -> bool:
    parts = mod.split(".")
    return parts[:2] == ["gonio", "specs"] and len(parts) == 4 and parts[3] in RENDERING_MODULES


#: A specification's command-line module (``Specification.commands``): it sits on the
#: command line's layer (it may import anything gonio's own ``gonio/cli/cmd_*.py`` may).
COMMAND_MODULES = ("commands",)


def is_command(mod: str) -> bool:
    parts = mod.split(".")
    return parts[:2] == ["gonio", "specs"] and len(parts) == 4 and parts[3] in COMMAND_MODULES


def layer_violations(files: list[Path]) -> list[str]:
    bad = []
    for path in files:
        mod = module_name(path)
        tree = ast.parse(path.read_text(encoding="utf-8"))
        g = group(mod)
        if is_command(mod):
            g = "gonio.cli"              # the command line's layer, below nothing
        elif is_rendering(mod):
            for target, _, line in imports_of(tree, mod, False):
                tg = group(target) if target.startswith("gonio") else None
                if tg is not None and LAYERS[tg] > RENDERING_LAYER:
                    bad.append(f"{mod}:{line}: imports {target} (a specification's rendering "
                               "module sits below the pipeline)")
            continue
        for target, names, line in imports_of(tree, mod, path.name == "__init__.py"):
            if mod.startswith("uncertainty") and target.split(".")[0] == "gonio":
                bad.append(f"{path.name}:{line}: uncertainty imports gonio")
                continue
            if g is None or not target.startswith("gonio"):
                continue
            candidates = [target] + [f"{target}.{n}" for n in names]
            tg = group(candidates[0])
            if tg is None:
                continue
            if LAYERS[tg] > LAYERS[g] or (LAYERS[tg] == LAYERS[g] and tg != g and LAYERS[g] > 0):
                bad.append(f"{mod}:{line}: imports {target} (layer {tg} above or beside {g})")
            if tg == "gonio.specs" and mod.startswith("gonio.specs."):
                a = mod.split(".")[:3]
                b = target.split(".")[:3]
                # a family package (specs/_rate_family/) is the shared ground of several
                if len(a) == 3 and len(b) == 3 and a != b and not b[2].startswith("_"):
                    bad.append(f"{mod}:{line}: one specification imports another ({target})")
    return bad


#: What a specification may import (docs/architecture.md#layers), besides itself, a
#: family package (``gonio.specs._rate_family``), the registry and the layer-0 modules.
SPEC_MAY_IMPORT = ("gonio.physics", "gonio.formats", "gonio.protocol", "gonio.result",
                   "gonio.reduce", "gonio.analysis", "uncertainty")
#: A specification's modules that run the virtual bench: the only ones that may import it
#: (``study``: its coverage study of ``gonio validate``, which simulates every trial;
#: ``served``: its virtual bench served as instruments, ``SPEC.serve``).
SIMULATION_MODULES = ("simulate", "plan", "truth", "study", "served")
#: A specification's modules that drive instruments: the only ones that may import
#: ``gonio.instruments`` (``acquisition``: its programme on a laboratory's instruments,
#: ``SPEC.acquire``; ``acquisition_module``: the driver of an instrument of its own;
#: ``served``: its virtual bench served as those instruments).
INSTRUMENT_MODULES = ("acquisition", "acquisition_module", "served")


def spec_import_violations(files: list[Path]) -> list[str]:
    """A specification imports only what calibrating needs; the simulator (gonio.bench)
    only from its ``simulate``/``plan``/``truth`` modules, so that calibrating a
    laboratory's file never imports the virtual bench; its rendering module (``outputs``)
    may also import the report (:func:`layer_violations`)."""
    bad = []
    for path in files:
        mod = module_name(path)
        parts = mod.split(".")
        if parts[:2] != ["gonio", "specs"]:
            continue
        if is_rendering(mod) or is_command(mod):
            continue                     # checked by layer_violations (report, bench allowed)
        sim = len(parts) > 3 and parts[3] in SIMULATION_MODULES
        drives = len(parts) > 3 and parts[3] in INSTRUMENT_MODULES
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for target, names, line in imports_of(tree, mod, path.name == "__init__.py"):
            top = target.split(".")[0]
            if top not in ("gonio", "uncertainty"):
                continue
            tg = group(target) if top == "gonio" else "uncertainty"
            if (tg == "gonio.bench" and sim) or (tg == "gonio.instruments" and drives):
                continue
            if tg == "gonio.specs" or LAYERS.get(tg, -1) == 0 or tg in SPEC_MAY_IMPORT:
                continue
            bad.append(f"{mod}:{line}: a specification imports {target}"
                       + (" (only its simulate/plan/truth/study modules may)" if tg == "gonio.bench"
                          else ""))
    return bad


#: A specification named outside gonio/specs/: its key, its package or its family (issue 23's
#: "done when" pattern; the registry, gonio/specs/__init__.py, may list the built-ins).
NAMES_A_SPEC = re.compile(r"ogam|jjf|iec62047|triad")
#: Generic words the pattern would catch: an instrument, not a specification (the issue
#: allows generic words; this list stays that narrow).
GENERIC_WORDS = re.compile(r"gyro triad")
#: Modules that still name one (not yet through the registry; docs/architecture.md).
STILL_NAMING: set[str] = set()


def spec_naming_violations(files: list[Path]) -> list[str]:
    """The command line, the pipeline, the report and the analyses find specifications through
    the registry only: no key, no specification package or family in their source."""
    bad = []
    for path in files:
        rel = path.relative_to(ROOT).as_posix()
        if rel in STILL_NAMING:
            continue
        for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if NAMES_A_SPEC.search(GENERIC_WORDS.sub("", line)):
                bad.append(f"{rel}:{i}: names a specification: {line.strip()[:80]}")
    return bad


def import_graph(files: list[Path]) -> dict[str, set[str]]:
    mods = {module_name(p): p for p in files}
    graph: dict[str, set[str]] = {m: set() for m in mods}
    for m, p in mods.items():
        tree = ast.parse(p.read_text(encoding="utf-8"))
        for target, names, _ in imports_of(tree, m, p.name == "__init__.py"):
            for cand in [f"{target}.{n}" for n in names] + [target]:
                if cand in mods and cand != m:
                    graph[m].add(cand)
                    break
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def private_violations(files: list[Path]) -> list[str]:
    bad = []
    for path in files:
        mod = module_name(path)
        tree = ast.parse(path.read_text(encoding="utf-8"))
        defined = {n.name for n in ast.walk(tree)
                   if isinstance(n, (ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))}
        for target, names, line in imports_of(tree, mod, path.name == "__init__.py"):
            for n in names:
                if n.startswith("_") and not n.startswith("__"):
                    bad.append(f"{mod}:{line}: imports private {target}.{n}")
        classes_here = {n.name for n in ast.walk(tree) if isinstance(n, ast.ClassDef)}
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and node.attr.startswith("_")
                    and not node.attr.startswith("__")):
                base = node.value
                if isinstance(base, ast.Name) and base.id in ("self", "cls", "np", "sys", "os"):
                    continue
                if isinstance(base, ast.Name) and base.id in classes_here | defined:
                    continue
                # attributes set in this module (self._x = ... in its classes) may be read here
                own = {t.attr for t in ast.walk(tree) if isinstance(t, ast.Attribute)
                       and isinstance(t.ctx, ast.Store)}
                if node.attr in own:
                    continue
                bad.append(f"{mod}:{node.lineno}: reads private attribute .{node.attr}")
    return bad


#: Literals that are unit conversions and belong in gonio/units.py.
UNIT_LITERALS = {3600.0, 206264.8, 206264.806, 206264.80624709636, 86400.0}


def unit_literal_violations(files: list[Path]) -> list[str]:
    bad = []
    for path in files:
        if path == ROOT / "gonio" / "units.py":
            continue
        toks = tokenize.generate_tokens(io.StringIO(path.read_text(encoding="utf-8")).readline)
        for tok in toks:
            if tok.type == tokenize.NUMBER:
                try:
                    v = float(tok.string.replace("_", ""))
                except ValueError:
                    continue
                if v in UNIT_LITERALS:
                    bad.append(f"{path.relative_to(ROOT)}:{tok.start[0]}: bare unit literal "
                               f"{tok.string} (use gonio.units)")
    return bad


GONIO = python_files("gonio")
ALL = python_files("gonio", "uncertainty")


def test_imports_run_down_the_layers():
    assert layer_violations(ALL) == []


def test_specifications_import_no_simulator_outside_simulation():
    assert spec_import_violations(GONIO) == []


def test_cli_pipeline_report_and_analysis_name_no_specification():
    assert spec_naming_violations(python_files("gonio/cli", "gonio/pipeline", "gonio/report",
                                               "gonio/analysis")) == []


#: The keys and packages of the specifications (not the instrument words "triad", "optical"):
#: the layers below the specifications hold a protocol model, readers, benches and records
#: that name none of them (leftover 3 of the last stop: a default protocol name, a triad
#: protocol's spec default, the records importer's fallback, a reader's doctest).
SPEC_KEYS = re.compile(r"ogam|jjf|iec62047|triad[-_]alignment")


def test_protocol_formats_bench_and_records_name_no_specification():
    files = python_files("gonio/protocol", "gonio/formats", "gonio/bench", "gonio/records")
    bad = [f"{p.relative_to(ROOT).as_posix()}:{i}: {line.strip()[:80]}" for p in files
           for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
           if SPEC_KEYS.search(line)]
    assert bad == []
    assert SPEC_KEYS.search('key = spec_key or "ogam-draft"')        # the rule can fire


def test_no_import_cycles():
    assert cycles(import_graph(ALL)) == []


def test_no_private_names_across_modules():
    assert private_violations(ALL) == []


def test_unit_literals_only_in_units_module():
    assert unit_literal_violations(GONIO) == []


def test_every_package_is_installed():
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    listed = set(re.findall(r'"([a-z0-9_.]+)"', text.split("packages = [", 1)[1].split("]", 1)[0]))
    pkgs = {module_name(p.parent / "__init__.py") for p in ROOT.glob("gonio/**/__init__.py")}
    pkgs |= {"uncertainty"}
    assert sorted(pkgs - listed) == []


def plotting_violations(files: list[Path]) -> list[str]:
    bad = []
    for path in files:
        mod = module_name(path)
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for target, names, line in imports_of(tree, mod, path.name == "__init__.py"):
            full = [target] + [f"{target}.{n}" for n in names]
            if any(f.startswith("matplotlib.pyplot") for f in full):
                bad.append(f"{mod}:{line}: imports matplotlib.pyplot")
            elif (target.startswith("matplotlib") and not mod.startswith("gonio.report")
                  and not is_rendering(mod)):
                bad.append(f"{mod}:{line}: imports matplotlib outside the report")
        for node in ast.walk(tree):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                    and node.func.attr == "use" and isinstance(node.func.value, ast.Name)
                    and node.func.value.id == "matplotlib"):
                bad.append(f"{mod}:{node.lineno}: switches the matplotlib backend")
    return bad


def test_plotting_only_in_report_without_pyplot():
    assert plotting_violations(ALL) == []


# ----------------------------------------------------------- the rules can fail
def _write(tmp: Path, rel: str, text: str) -> Path:
    p = tmp / rel
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(text, encoding="utf-8")
    return p


@pytest.fixture()
def fake_root(tmp_path, monkeypatch):
    monkeypatch.setitem(globals(), "ROOT", tmp_path)
    return tmp_path


def test_rules_fire_on_bad_examples(fake_root):
    physics = _write(fake_root, "gonio/physics/x.py", "from gonio.bench.session import run\n")
    unc = _write(fake_root, "uncertainty/y.py", "import gonio.units\n")
    spec = _write(fake_root, "gonio/specs/a/items.py", "from gonio.specs.b.items import f\n"
                  "from gonio.specs._family.formulas import g\n")
    beside = _write(fake_root, "gonio/reduce/z.py", "from gonio.bench import load_bench\n")
    ok = _write(fake_root, "gonio/pipeline/ok.py", "from gonio.bench import load_bench\n")
    bad = layer_violations([physics, unc, spec, beside, ok])
    assert len(bad) == 4 and not any("pipeline.ok" in b for b in bad)
    items = _write(fake_root, "gonio/specs/a/items.py", "from gonio.bench.rate_gyro import x\n"
                   "from gonio.report.i18n import y\nfrom gonio.reduce import r\nfrom gonio.physics.alignment import z\n"
                   "import uncertainty\nfrom gonio.units import S_PER_H\n")
    sim = _write(fake_root, "gonio/specs/a/simulate.py", "from gonio.bench.rate_gyro import x\n")
    assert len(spec_import_violations([items, sim])) == 2     # the bench and the report
    drives = _write(fake_root, "gonio/specs/a/acquisition.py", "from gonio.instruments.link import L\n")
    served = _write(fake_root, "gonio/specs/a/served.py", "from gonio.instruments.scpi import S\n"
                    "from gonio.bench import b\n")
    not_driving = _write(fake_root, "gonio/specs/a/screen.py", "from gonio.instruments.link import L\n")
    assert len(spec_import_violations([drives, served, not_driving])) == 1   # the screen's
    render = _write(fake_root, "gonio/specs/a/outputs.py", "from gonio.report.x import y\n"
                    "from gonio.bench import z\nfrom gonio.pipeline.dispatch import w\n")
    report_in_items = _write(fake_root, "gonio/specs/a/certificate.py", "from gonio.report import y\n")
    assert len(layer_violations([render, report_in_items])) == 2
    command = _write(fake_root, "gonio/specs/a/commands.py", "from gonio.cli.checks import seed\n"
                     "from gonio.specs.a.pages import p\nfrom gonio.specs.b.items import q\n")
    cli_in_items = _write(fake_root, "gonio/specs/a/items.py", "from gonio.cli.checks import seed\n")
    assert len(layer_violations([command, cli_in_items])) == 2    # b's items, the cli in items
    cli = _write(fake_root, "gonio/cli/cmd_x.py", "if spec == 'jjf1535-2015':\n    pass\n"
                 "from gonio.specs.iec62047_20 import calibrate\nfrom gonio.specs import get\n")
    assert len(spec_naming_violations([cli])) == 2
    report = _write(fake_root, "gonio/report/x.py", '"""The triad\'s pages."""\n'
                    "from gonio.specs.ogam_draft.items import ITEM_KEYS\nkeys = 'generic'\n"
                    "name = 'MEMS gyro triad (virtual)'\n")
    assert len(spec_naming_violations([report])) == 2
    a = _write(fake_root, "gonio/p/a.py", "from gonio.p.b import g\n")
    b = _write(fake_root, "gonio/p/b.py", "from gonio.p.a import f\n")
    assert cycles(import_graph([a, b])) == [["gonio.p.a", "gonio.p.b"]]
    priv = _write(fake_root, "gonio/q.py",
                  "from gonio.r import _hidden\n\ndef f(t):\n    return t._t0\n")
    assert len(private_violations([priv])) == 2
    lit = _write(fake_root, "gonio/s.py", "x = 1.0 / 3600.0\ny = '3600'  # 3600\n")
    assert len(unit_literal_violations([lit])) == 1
    plot = _write(fake_root, "gonio/analysis/p.py",
                  "import matplotlib\nmatplotlib.use('Agg')\nimport matplotlib.pyplot as plt\n")
    ok_plot = _write(fake_root, "gonio/report/f.py", "from matplotlib.figure import Figure\n")
    spec_plot = _write(fake_root, "gonio/specs/a/figures.py", "from matplotlib.figure import Figure\n")
    data_plot = _write(fake_root, "gonio/specs/a/items.py", "from matplotlib.figure import Figure\n")
    assert len(plotting_violations([plot, ok_plot, spec_plot, data_plot])) == 4


#: Functions allowed over the length limit: straight tables of data (the database
#: migration's table definitions).
LONG_TABLES = {("gonio/records/migrations/versions/0001_initial_schema.py", "upgrade")}
MAX_FUNCTION_LINES = 120


def test_no_function_over_120_lines():
    long = []
    for path in python_files("gonio", "uncertainty"):
        rel = path.relative_to(ROOT).as_posix()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_FUNCTION_LINES and (rel, node.name) not in LONG_TABLES:
                    long.append(f"{rel}:{node.lineno} {node.name} ({n} lines)")
    assert long == []
