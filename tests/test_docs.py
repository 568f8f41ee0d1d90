"""The repository explains itself: every document it cites is in it (issue 11).

(a) Every path under ``docs/`` ending in ``.md`` that the code, tests, protocols, README or
    documents cite exists, and every ``#anchor`` written right after such a path is a
    heading of that file (GitHub's slug rule) or an explicit HTML anchor. Relative links
    between the documents (``[x](formats.md#y)``, ``[x](#y)``) are checked the same way.
(b) No file of the package, the protocols, the README or the documents cites the
    project's external sources (the shared digests or seed texts, or anything through a
    ``..``-relative path to the reference shelf); the package, protocols and README also do not cite them by their
    old names (the "data-formats" contract, "thesis 004", "seed 00N") or any Markdown
    file outside ``docs/``: a clone of the repository alone must explain every reading.

The checker itself is tested on hand-written cases (slugs as GitHub renders them, and a
small tree with a good and a bad citation), so that a checker that finds nothing cannot
pass unnoticed.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
THIS = Path(__file__).resolve()

#: A cited document: ``docs/<path>.md`` with an optional ``#anchor`` right after it.
CITATION = re.compile(r"(?<![\w/.-])docs/(?P<path>[\w-][\w./-]*?\.md)(?:#(?P<anchor>[\w-]+))?")
#: A Markdown link target inside a document: ``](target)``.
MD_LINK = re.compile(r"\]\((?P<target>[^)\s]+)\)")
#: External sources a clone does not have (part b). Written in pieces so this file does
#: not match its own pattern.
FORBIDDEN = re.compile("|".join(re.escape(s) for s in (
    "shared" + "/spec", "shared" + "/seeds", "shared" + "/schemas", ".." + "/shared")))
#: A test reaching for a folder beside the repository (the reference shelf a clone lacks).
BESIDE_REPO = re.compile(r"""\.parent\s*/\s*["']shared["']|\.\./""" + "shared" + r"""|["']""" + "shared" + "/schemas")
#: In the package, protocols and README (not in docs/, which may explain these names):
#: the old names of the external sources, and any Markdown file that is not a docs/ path.
FORBIDDEN_IN_CODE = re.compile(
    r"data-formats|thesis 00\d|seed 00\d|(?<![\w/.-])(?!docs/|README\.md)[\w./-]*[\w-]\.md\b",
    re.IGNORECASE)

HEADING = re.compile(r"^(#{1,6})\s+(?P<text>.+?)\s*#*\s*$")
FENCE = re.compile(r"^\s*(```|~~~)")
HTML_ANCHOR = re.compile(r"<a\s+(?:id|name)=\"(?P<id>[^\"]+)\"", re.IGNORECASE)


def github_slug(text: str) -> str:
    """The anchor GitHub gives a heading (before de-duplication).

    Lower case; inline Markdown reduced to its text; every character that is not a
    letter, digit, underscore, hyphen or space removed; spaces become hyphens.
    """
    s = text.strip()
    s = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", s)   # links and images -> their text
    s = s.lower()
    s = re.sub(r"[^\w\- ]", "", s)
    return s.replace(" ", "-")


def anchors_of(markdown: str) -> set[str]:
    """Every anchor of a Markdown text: heading slugs (with GitHub's -1, -2 suffixes for
    repeated headings) and explicit ``<a id=...>`` / ``<a name=...>`` anchors."""
    out: set[str] = set()
    seen: dict[str, int] = {}
    fenced = False
    for line in markdown.splitlines():
        if FENCE.match(line):
            fenced = not fenced
            continue
        if fenced:
            continue
        for m in HTML_ANCHOR.finditer(line):
            out.add(m.group("id"))
        m = HEADING.match(line)
        if not m:
            continue
        slug = github_slug(m.group("text"))
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        out.add(slug if n == 0 else f"{slug}-{n}")
    return out


def cited_files(root: Path) -> list[Path]:
    """Files whose citations of documents are checked (part a)."""
    files: list[Path] = []
    for sub, patterns in (("gonio", ("*.py", "*.toml")), ("uncertainty", ("*.py",)),
                          ("tests", ("*.py",)), ("protocols", ("*.toml",)),
                          ("benchmarks", ("*.py",)), ("scripts", ("*.sh", "*.py")),
                          ("docs", ("*.md",))):
        for pattern in patterns:
            files.extend(p for p in sorted((root / sub).rglob(pattern)) if p.is_file())
    if (root / "README.md").is_file():
        files.append(root / "README.md")
    return [p for p in files if p.resolve() != THIS and "__pycache__" not in p.parts]


def citation_problems(root: Path, files: list[Path]) -> list[str]:
    """One line per cited document or anchor that does not exist."""
    problems: list[str] = []
    cache: dict[Path, set[str]] = {}

    def check(src: Path, lineno: int, target: Path, anchor: str | None, shown: str) -> None:
        where = f"{src.relative_to(root)}:{lineno}"
        if not target.is_file():
            problems.append(f"{where}: {shown}: no such file")
            return
        if anchor:
            if target not in cache:
                cache[target] = anchors_of(target.read_text(encoding="utf-8"))
            if anchor not in cache[target]:
                problems.append(f"{where}: {shown}: no heading with anchor #{anchor} "
                                f"in {target.relative_to(root)}")

    for src in files:
        text = src.read_text(encoding="utf-8", errors="replace")
        for lineno, line in enumerate(text.splitlines(), 1):
            for m in CITATION.finditer(line):
                check(src, lineno, root / "docs" / m.group("path"), m.group("anchor"),
                      m.group(0))
            if src.suffix == ".md" and src.parent == root / "docs":
                for m in MD_LINK.finditer(line):
                    t = m.group("target")
                    if re.match(r"^[a-z][a-z0-9+.-]*:", t):     # http:, mailto: ...
                        continue
                    path, _, anchor = t.partition("#")
                    if path and not path.endswith(".md"):
                        target = (src.parent / path).resolve()
                        if not target.exists():
                            problems.append(f"{src.relative_to(root)}:{lineno}: {t}: "
                                            "no such file")
                        continue
                    target = (src.parent / path).resolve() if path else src
                    check(src, lineno, target, anchor or None, t)
    return problems


def forbidden_problems(root: Path) -> list[str]:
    """One line per citation of a source outside the repository (part b)."""
    files: list[Path] = []
    for sub in ("gonio", "uncertainty", "docs", "protocols"):
        files.extend(p for p in sorted((root / sub).rglob("*"))
                     if p.is_file() and p.suffix in (".py", ".md", ".toml", ".txt")
                     and "__pycache__" not in p.parts)
    if (root / "README.md").is_file():
        files.append(root / "README.md")
    out = []
    for src in files:
        in_docs = src.parent == root / "docs" or root / "docs" in src.parents
        for lineno, line in enumerate(src.read_text(encoding="utf-8",
                                                    errors="replace").splitlines(), 1):
            m = FORBIDDEN.search(line) or (None if in_docs else FORBIDDEN_IN_CODE.search(line))
            if m:
                out.append(f"{src.relative_to(root)}:{lineno}: cites {m.group(0)}")
    return out


# --------------------------------------------------------------------------- the checker

@pytest.mark.parametrize("heading, slug", [
    ("Readings file", "readings-file"),
    ("Differences from the original contract", "differences-from-the-original-contract"),
    ("7.3 Zero stability", "73-zero-stability"),
    ("A.4.2 Tilt of the sensing plane", "a42-tilt-of-the-sensing-plane"),
    ("Annex A Uncertainty of the angle-position deviation",
     "annex-a-uncertainty-of-the-angle-position-deviation"),
    ("`results.json` keys", "resultsjson-keys"),
    ("Tilt × Earth-rate coupling", "tilt--earth-rate-coupling"),
    ("3.1 bis Scale factor", "31-bis-scale-factor"),
    ("What time_s counts from", "what-time_s-counts-from"),
    ("See [the layers](architecture.md#layers)", "see-the-layers"),
    ("校准结果 Results", "校准结果-results"),
])
def test_github_slug(heading, slug):
    assert github_slug(heading) == slug


def test_anchors_dedupe_and_skip_code_blocks():
    md = ("# Title\n## Notes\n### Notes\n```\n# not a heading\n```\n"
          '<a id="custom-anchor"></a>\n## Closing ##\n')
    assert anchors_of(md) == {"title", "notes", "notes-1", "custom-anchor", "closing"}


def test_checker_finds_missing_files_and_anchors(tmp_path):
    (tmp_path / "docs").mkdir()
    (tmp_path / "gonio").mkdir()
    (tmp_path / "docs" / "a.md").write_text("# A\n## Good anchor\n[self](#good-anchor)\n"
                                            "[bad](#nope) [other](b.md#x)\n", encoding="utf-8")
    d = "doc" + "s/"
    (tmp_path / "gonio" / "m.py").write_text(
        f'"""See {d}a.md#good-anchor and {d}a.md#bad-anchor, {d}missing.md, {d}a.md."""\n',
        encoding="utf-8")
    probs = citation_problems(tmp_path, cited_files(tmp_path))
    text = "\n".join(probs)
    assert len(probs) == 4, text
    assert "#bad-anchor" in text and "missing.md: no such file" in text
    assert "#nope" in text and "b.md#x: no such file" in text
    assert not any("#good-anchor" in p for p in probs), text


def test_forbidden_checker(tmp_path):
    (tmp_path / "gonio").mkdir()
    (tmp_path / "docs").mkdir()
    d = "doc" + "s/"
    (tmp_path / "gonio" / "m.py").write_text(
        "# see " + "shared" + "/spec/x.md\n"
        f"# fine: {d}formats.md#readings-file and README.md\n"
        "# the " + "data-formats contract, section 1\n"
        "# the draft as restated in ogam-draft" + ".md\n"
        "# (thesis " + "004)\n", encoding="utf-8")
    (tmp_path / "docs" / "r.md").write_text("the thesis (" + "seed 004); " + "data-formats\n"
                                            "but not " + ".." + "/shared/x\n", encoding="utf-8")
    assert forbidden_problems(tmp_path) == [
        "gonio/m.py:1: cites " + "shared" + "/spec",
        "gonio/m.py:3: cites " + "data-formats",
        "gonio/m.py:4: cites ogam-draft" + ".md",
        "gonio/m.py:5: cites thesis " + "004",
        "docs/r.md:2: cites " + ".." + "/shared"]


# --------------------------------------------------------------------------- the repository

def test_documents_exist():
    for name in ("formats.md", "draft-readings.md", "references.md", "architecture.md"):
        assert (ROOT / "docs" / name).is_file(), name


def test_cited_documents_and_anchors_exist():
    """(a) every cited docs/ path exists, and so does every cited anchor."""
    problems = citation_problems(ROOT, cited_files(ROOT))
    assert not problems, "\n" + "\n".join(problems)


def test_no_citation_of_sources_outside_the_repository():
    """(b) nothing in the package, protocols, README or docs cites shared sources."""
    problems = forbidden_problems(ROOT)
    assert not problems, "\n" + "\n".join(problems)


def test_no_test_reads_a_folder_beside_the_repository():
    """A clone alone must pass its tests: no test builds a path to a folder beside the
    repository (the DCC schema set is carried in tests/data/dcc-3.3.0)."""
    bad = [f"{p.relative_to(ROOT)}:{n}: {line.strip()}"
           for p in sorted((ROOT / "tests").rglob("*.py")) if p != THIS
           for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
           if BESIDE_REPO.search(line)]
    assert not bad, "\n" + "\n".join(bad)
    assert BESIDE_REPO.search('SCHEMA = REPO.parent / "shared" / "schemas"')
    assert not BESIDE_REPO.search('SCHEMA = REPO / "tests" / "data"')


def test_dcc_schema_copy_is_the_published_one():
    """The carried DCC 3.3.0 schema files are the byte-for-byte copies its README lists."""
    import hashlib
    d = ROOT / "tests" / "data" / "dcc-3.3.0"
    listed = dict((m.group(2), m.group(1)) for m in re.finditer(
        r"^\s+([0-9a-f]{64})\s+(\S+)", (d / "README.md").read_text(encoding="utf-8"), re.M))
    assert set(listed) == {"dcc.xsd", "si/SI_Format.xsd", "d-sig/xmldsig-core-schema.xsd"}
    for name, digest in listed.items():
        assert hashlib.sha256((d / name).read_bytes()).hexdigest() == digest, name
    for licence in ("COPYING", "COPYING.LESSER", "W3C-LICENSE"):
        assert (d / licence).stat().st_size > 1000, licence


#: Tracker history: issue numbers, attack rounds, defect numbers, reviews of a stop. It
#: belongs in commit messages, never in the package's text (written in pieces so this file
#: does not match itself).
TRACKER = re.compile("|".join((r"\b[Ii]ssues? ?#?\d+", "hostile " + r"round", "attack " + r"round",
                               r"\b[Dd]efect \d+", r"review of (?:r-\w+|stop \d+)",
                               r"\bstop \d+\b")))


def tracker_history(root: Path) -> list[str]:
    """One line per mention of tracker history in the package, the engine and protocols."""
    out = []
    for sub in ("gonio", "uncertainty", "protocols"):
        for p in sorted((root / sub).rglob("*")):
            if p.suffix in (".py", ".toml", ".html") and "__pycache__" not in p.parts:
                for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1):
                    m = TRACKER.search(line)
                    if m:
                        out.append(f"{p.relative_to(root)}:{n}: {m.group(0)}")
    return out


def test_package_text_carries_no_tracker_history(tmp_path):
    assert tracker_history(ROOT) == []
    (tmp_path / "gonio").mkdir()
    (tmp_path / "gonio" / "m.py").write_text(
        "# fixed in issue 24\n# the first of 3 stops\n# hostile " + "round 3: x\n"
        "# (defect 5)\n# clause 7.4, round 3 of the series\n", encoding="utf-8")
    assert tracker_history(tmp_path) == [
        "gonio/m.py:1: issue 24", "gonio/m.py:3: hostile " + "round", "gonio/m.py:4: defect 5"]
