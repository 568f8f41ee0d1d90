"""Every code block of the README and of docs/ runs as written, or is checked as what it
claims to be.

- A ``python`` block runs. The blocks of one document run in order in one fresh Python
  process (a later block may use what an earlier one defined), in a temporary folder that
  holds what the document promises to be there: ``tests/data/dcc-3.3.0`` (the repository's
  schema copy) and ``demo-out/`` (what the quick start's ``gonio demo --out demo-out``
  writes). A block that raises fails the test with the document and line.
- A ``python`` block that is an excerpt of a file says so on the line before its fence,
  ``<!-- excerpt: PATH -->`` (PATH from the repository root). Its lines, cut at lines that
  hold only ``...``, must appear in that file in that order (leading whitespace kept): the
  file is what runs, in the tests that import it.
- A ``bash`` block's commands are checked against the command line itself: every ``gonio
  SUB`` names a sub-command that exists, every ``--option`` written on that line (inside
  ``[…]`` alternatives too) is one that sub-command takes, and every script or file named
  (``python benchmarks/x.py``, ``bash scripts/y.sh``) exists. Whole runs of the quick
  start's commands are made by ``.ci/run`` in a fresh clone.
- ``text``, ``toml``, ``json`` and unlabelled blocks are data or output, not code.

The checks are shown to fail on hand-written bad blocks.
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^(?P<fence>```|~~~)(?P<lang>[\w+-]*)[^\n]*$")
EXCERPT = re.compile(r"<!--\s*excerpt:\s*(?P<path>\S+)\s*-->")
OPTION = re.compile(r"(?<![\w-])(--[a-z][\w-]*)")


def blocks(text: str) -> list[dict]:
    """The fenced blocks of a Markdown text: lang, first line number, body, excerpt path."""
    out, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        start, body = i, []
        i += 1
        while i < len(lines) and not lines[i].startswith(m.group("fence")):
            body.append(lines[i])
            i += 1
        before = [s for s in lines[max(0, start - 3):start] if s.strip()]
        ex = EXCERPT.search(before[-1]) if before else None
        out.append({"lang": m.group("lang"), "line": start + 1, "body": "\n".join(body),
                    "excerpt": ex.group("path") if ex else None})
        i += 1
    return out


def excerpt_problems(body: str, source: str) -> list[str]:
    """The parts of ``body`` (cut at ``...`` lines) that do not appear in ``source`` in order."""
    parts, cur = [], []
    for line in body.splitlines():
        if line.strip() == "...":
            parts.append(cur)
            cur = []
        else:
            cur.append(line)
    parts.append(cur)
    problems, pos = [], 0
    for part in parts:
        chunk = "\n".join(part).strip("\n")
        if not chunk.strip():
            continue
        at = source.find(chunk, pos)
        if at < 0:
            problems.append(chunk.splitlines()[0])
        else:
            pos = at + len(chunk)
    return problems


def _parser() -> argparse.ArgumentParser:
    from gonio.cli import build_parser
    return build_parser()


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def command_problems(body: str, parser: argparse.ArgumentParser, root: Path) -> list[str]:
    """One line per ``gonio`` sub-command or option a bash block names that does not exist,
    and per script or file it runs that is not in the repository."""
    subs = _subparsers(parser)
    problems = []
    for line in body.replace("\\\n", " ").splitlines():
        code = line.split(" #")[0].strip()
        for part in re.split(r"&&|;|\|(?!\|)", code):
            words = [w for w in part.split() if not re.match(r"^[A-Z_]+=", w)]
            if not words:
                continue
            if words[0] == "gonio":
                sub = words[1] if len(words) > 1 else ""
                if sub.startswith("-"):
                    known = {o for a in parser._actions for o in a.option_strings}
                    problems += [f"gonio {o}: no such option" for o in OPTION.findall(part)
                                 if o not in known]
                    continue
                if sub not in subs:
                    problems.append(f"gonio {sub}: no such command")
                    continue
                p = subs[sub]
                known = {o for a in p._actions for o in a.option_strings}
                nested = _subparsers(p)
                if len(words) > 2 and words[2] in nested:
                    known |= {o for a in nested[words[2]]._actions for o in a.option_strings}
                problems += [f"gonio {sub} {o}: no such option"
                             for o in OPTION.findall(part) if o not in known]
            elif words[0] in ("python", "bash") and len(words) > 1 and not words[1].startswith("-"):
                if not (root / words[1]).is_file():
                    problems.append(f"{words[0]} {words[1]}: no such file")
    return problems


def _cases():
    for doc in DOCUMENTS:
        for b in blocks(doc.read_text(encoding="utf-8")):
            yield doc, b


# --------------------------------------------------------------------------- the checkers

def test_blocks_are_found_with_their_marks():
    text = ("x\n```python\nprint(1)\n```\n<!-- excerpt: a/b.py -->\n```python\ndef f():\n"
            "    ...\n```\n```bash\ngonio demo\n```\n")
    got = blocks(text)
    assert [(b["lang"], b["line"], b["excerpt"]) for b in got] == [
        ("python", 2, None), ("python", 6, "a/b.py"), ("bash", 10, None)]


def test_excerpt_checker_finds_what_is_not_in_the_file():
    source = "import x\n\ndef f(a):\n    return a + 1\n\n\ndef g():\n    pass\n"
    assert excerpt_problems("def f(a):\n    return a + 1\n...\ndef g():", source) == []
    assert excerpt_problems("def g():\n...\ndef f(a):", source) == ["def f(a):"]  # order
    assert excerpt_problems("def f(a):\n    return a + 2", source) == ["def f(a):"]


def test_command_checker_finds_unknown_commands_options_and_files(tmp_path):
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "ok.sh").write_text("")
    good = ("gonio demo --out d [--seed 3]   # a comment --not-an-option\n"
            "GONIO_X=1 gonio db backup records.zip && bash scripts/ok.sh\n")
    assert command_problems(good, _parser(), tmp_path) == []
    bad = ("gonio demo --outt d\ngonio frobnicate --x\npython benchmarks/none.py\n"
           "gonio db restore --no-such r.zip\n")
    assert command_problems(bad, _parser(), tmp_path) == [
        "gonio demo --outt: no such option", "gonio frobnicate: no such command",
        "python benchmarks/none.py: no such file", "gonio db --no-such: no such option"]


# --------------------------------------------------------------------------- the documents

@pytest.mark.parametrize("doc, block", [
    pytest.param(d, b, id=f"{d.name}:{b['line']}") for d, b in _cases()
    if b["lang"] == "bash"])
def test_bash_block_commands_exist(doc, block):
    problems = command_problems(block["body"], _parser(), ROOT)
    assert not problems, f"{doc.name}:{block['line']}: " + "; ".join(problems)


@pytest.mark.parametrize("doc, block", [
    pytest.param(d, b, id=f"{d.name}:{b['line']}") for d, b in _cases()
    if b["lang"] == "python" and b["excerpt"]])
def test_python_excerpt_is_in_its_file(doc, block):
    path = ROOT / block["excerpt"]
    assert path.is_file(), f"{doc.name}:{block['line']}: {block['excerpt']} does not exist"
    missing = excerpt_problems(block["body"], path.read_text(encoding="utf-8"))
    assert not missing, (f"{doc.name}:{block['line']}: not in {block['excerpt']}: "
                         + "; ".join(missing))


@pytest.fixture(scope="module")
def promised_folder(tmp_path_factory, shared_demo):
    """A folder holding what the documents' Python blocks may use: the schema copy at
    tests/data/dcc-3.3.0 and a demo-out/ with a DCC (the rate demo: the same writer), a copy
    of what ``gonio demo --spec jjf1535-2015 --seed 3`` writes (the session's shared folder:
    a block may write into its own copy)."""
    import shutil

    d = tmp_path_factory.mktemp("docs-run")
    (d / "tests" / "data").mkdir(parents=True)
    (d / "tests" / "data" / "dcc-3.3.0").symlink_to(ROOT / "tests" / "data" / "dcc-3.3.0")
    shutil.copytree(shared_demo("jjf1535-2015", seed=3), d / "demo-out", symlinks=True)
    return d


@pytest.mark.slow
@pytest.mark.parametrize("doc", [
    pytest.param(d, id=d.name) for d in DOCUMENTS
    if any(b["lang"] == "python" and not b["excerpt"]
           for b in blocks(d.read_text(encoding="utf-8")))])
def test_python_blocks_run(doc, promised_folder, tmp_path):
    runnable = [b for b in blocks(doc.read_text(encoding="utf-8"))
                if b["lang"] == "python" and not b["excerpt"]]
    work = tmp_path / "work"
    work.mkdir()
    for name in ("tests", "demo-out"):
        (work / name).symlink_to(promised_folder / name)
    script = "\n".join(
        f"# --- {doc.name}:{b['line']}\n"
        f"print('@@ block {b['line']}', flush=True)\n{b['body']}\n" for b in runnable)
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    r = subprocess.run([sys.executable, "-c", script], cwd=work, env=env,
                       capture_output=True, text=True, timeout=1200)
    started = re.findall(r"^@@ block (\d+)$", r.stdout, re.M)
    assert r.returncode == 0, (f"{doc.name}: the block at line {started[-1] if started else '?'}"
                               f" raised:\n{r.stderr[-3000:]}")
    assert len(started) == len(runnable)
