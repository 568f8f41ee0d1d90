"""The shared layers hold no specification's knowledge: the command line, the renderer, the
records, the web, the pipeline, the result and the kit name none of the optical draft's own
items or clauses in their string literals (docstrings aside: an example there is prose), and
the shared label and phrase tables hold none of its labels or phrases (its package does:
``gonio/specs/ogam_draft/phrases.py``, passed as ``own``/``table`` by its renderer).

No module of gonio outside ``gonio/specs/`` (the kit included) names a specification's
package or a family package (``gonio.specs.<package>``), in code or docstring: what a
specification uses from shared code is shared code's, and the registry's names
(``gonio.specs.get``, ``gonio.specs.ITEM_RENDERER`` …) are no package."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from gonio.specs import available

ROOT = Path(__file__).resolve().parents[1]
SHARED = ("cli", "kit", "pipeline", "records", "report", "result", "web")

#: A clause of the optical draft as its texts cite it ("7.4", "A.4.2", "Annex A").
CLAUSE = re.compile(r"(?<![\w.])(7\.[1-7]|A\.[2-7](\.\d)?|Annex A)(?![\w])")


def _optical_only_items() -> set[str]:
    """The optical draft's item keys that no other registered specification has (a key two
    specifications share, such as scale_factor, is no single specification's)."""
    specs = available()
    others = set().union(*(set(s.item_keys) for k, s in specs.items() if k != "ogam-draft"))
    return set(specs["ogam-draft"].item_keys) - others


def _literals(path: Path):
    """(line, text) of every string literal of a module that is not a docstring."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docs = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                docs.add(id(body[0].value))
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) \
                and id(node) not in docs:
            yield node.lineno, node.value


def offending_literals(root: Path, items: set[str]) -> list[str]:
    """``path:line: text`` of every literal under the shared packages of ``root`` that names
    one of ``items`` (the whole literal, or a key with an underscore inside it: a plain word
    such as "repeatability" in prose is English) or one of the draft's clauses."""
    word = re.compile(r"\b(" + "|".join(map(re.escape, sorted(items))) + r")\b")
    bad = []
    for part in SHARED:
        for path in sorted((root / "gonio" / part).rglob("*.py")):
            for line, text in _literals(path):
                if text in items or CLAUSE.search(text) or any(
                        "_" in w for w in word.findall(text)):
                    bad.append(f"{path.relative_to(root).as_posix()}:{line}: {text[:60]!r}")
    return bad


def spec_packages(root: Path) -> set[str]:
    """The packages under ``gonio/specs/`` of ``root``: every specification's and family's."""
    return {p.parent.name for p in (root / "gonio" / "specs").glob("*/__init__.py")}


def modules_naming_a_spec_package(root: Path) -> list[str]:
    """``path:line: text`` of every line of a module of ``root``'s gonio outside
    ``gonio/specs/`` that names a package under it, as a dotted or a path name."""
    pkgs = sorted(spec_packages(root))
    if not pkgs:
        return []
    name = re.compile(r"\bgonio[./]specs[./](" + "|".join(map(re.escape, pkgs)) + r")\b")
    bad = []
    for path in sorted((root / "gonio").rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        if rel.startswith("gonio/specs/"):
            continue
        for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if name.search(line):
                bad.append(f"{rel}:{i}: {line.strip()[:80]}")
    return bad


def test_the_package_check_fires(tmp_path):
    for pkg in ("_family", "acme"):
        (tmp_path / "gonio" / "specs" / pkg).mkdir(parents=True)
        (tmp_path / "gonio" / "specs" / pkg / "__init__.py").write_text("", encoding="utf-8")
    kit = tmp_path / "gonio" / "kit"
    kit.mkdir()
    (kit / "__init__.py").write_text(
        '"""Re-exports (:mod:`gonio.specs._family.records`)."""\n'
        "from gonio.specs._family.records import gum\n"
        'RENDERER = "gonio.specs._family.outputs"\n'
        "from gonio.specs import get, lazy\n"
        "KEY = gonio.specs.DEFAULT_KEY\n"
        "# see gonio/specs/acme/items.py\n", encoding="utf-8")
    (tmp_path / "gonio" / "specs" / "acme" / "items.py").write_text(
        "from gonio.specs._family.records import gum\n", encoding="utf-8")
    bad = modules_naming_a_spec_package(tmp_path)
    assert [b.split(": ")[0] for b in bad] == [f"gonio/kit/__init__.py:{n}" for n in (1, 2, 3, 6)]


def test_no_module_outside_the_specifications_names_one_of_their_packages():
    assert modules_naming_a_spec_package(ROOT) == []


def test_the_check_fires(tmp_path):
    pkg = tmp_path / "gonio" / "report"
    pkg.mkdir(parents=True)
    (pkg / "x.py").write_text('"""Docstring naming angle_deviation (7.4) is prose."""\n'
                              'A = "angle_deviation"\nB = "E (draft 7.4)"\nC = "bias"\n'
                              'D = "the repeatability of a rate"\nE = "repeatability"\n'
                              'F = "no angle_deviation rows"\n', encoding="utf-8")
    bad = offending_literals(tmp_path, {"angle_deviation", "repeatability"})
    assert [b.split(": ")[0] for b in bad] == [f"gonio/report/x.py:{n}" for n in (2, 3, 6, 7)]


def test_no_shared_module_names_the_optical_drafts_items_or_clauses():
    assert offending_literals(ROOT, _optical_only_items()) == []


def test_the_shared_tables_hold_no_optical_label_or_phrase():
    import gonio.report.i18n as i18n
    from gonio.specs.ogam_draft import phrases

    assert not hasattr(i18n, "FINDINGS_ZH") and not hasattr(i18n, "REASONS_ZH")
    assert not set(i18n.LABELS) & set(available()["ogam-draft"].item_keys)
    assert not set(i18n.LABELS) & set(phrases.LABELS)
    assert not [en for en in i18n.DCC_ZH if "draft" in en or "optical" in en]


def test_the_shared_dcc_table_holds_no_specifications_virtual_bench():
    """The names of the specifications' virtual instruments and equipment (the bench files'
    ``name`` of each section but ``[bench]``, "… (virtual)") are translated by the package of
    the specification that simulates on them (its phrases), not by the shared DCC table."""
    import tomllib

    from gonio.report.i18n import DCC_ZH

    names = set()
    for path in (ROOT / "protocols" / "benches").glob("*.toml"):
        data = tomllib.loads(path.read_text(encoding="utf-8"))
        names |= {v["name"] for k, v in data.items()
                  if k != "bench" and isinstance(v, dict) and isinstance(v.get("name"), str)}
    assert "MEMS rate gyro (virtual)" in names and "RLG goniometer (virtual)" in names
    assert not names & set(DCC_ZH)
    assert not [en for en in DCC_ZH if "(virtual)" in en]


@pytest.mark.parametrize("lang", ["en", "zh"])
def test_the_optical_labels_reach_its_pages_through_own(lang):
    from gonio.report.i18n import labels
    from gonio.specs.ogam_draft.phrases import LABELS

    L = labels(lang, LABELS)
    assert L["angle_deviation"] == LABELS["angle_deviation"][lang]
    assert L["not_measured"] == labels(lang)["not_measured"]       # the shared ones stay
    assert "angle_deviation" not in labels(lang)
