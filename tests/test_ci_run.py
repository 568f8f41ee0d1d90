"""`.ci/run`: in a fresh clone of the repository in a temporary folder (nothing beside it), it
runs the README's two quick-start commands (the demo, whose outputs it checks, and the test
command), fails on any non-zero pytest exit (5 = no tests collected included) and fails when
the tests leave the clone's working tree unclean (untracked files included). Exercised on a
throw-away git repository holding a copy of the script, with `pip`, `gonio` and `python`
replaced by stubs on PATH, so nothing of the real suite runs."""
import os
import re
import shutil
import stat
import subprocess
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CI = ROOT / ".ci" / "run"

pytestmark = pytest.mark.skipif(shutil.which("git") is None, reason="git not installed")


def test_ci_run_holds_the_readme_test_command():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    ci = CI.read_text(encoding="utf-8")
    for pattern in (r"^pip install \. && gonio demo --out demo-out",
                    r"^bash scripts/install-test-system-deps\.sh && .*$"):
        cmd = re.search(pattern, readme, re.M).group(0).split("   #")[0].rstrip()
        assert cmd in ci, cmd


def test_the_test_command_runs_on_capped_xdist_workers():
    """The README's test command runs in parallel (pytest-xdist, in the test extras) with at
    most four workers (each starts its own PostgreSQL server, gonio serve and Chromium), one
    file per worker."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    cmd = re.search(r"^bash scripts/install-test-system-deps\.sh && .*$", readme, re.M).group(0)
    pytest_args = cmd.split("python -m pytest", 1)[1].split("   #")[0].split()
    assert pytest_args[pytest_args.index("-n") + 1] == "auto"
    assert int(pytest_args[pytest_args.index("--maxprocesses") + 1]) == 4
    assert pytest_args[pytest_args.index("--dist") + 1] == "loadfile"
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert any(r.startswith("pytest-xdist") for r in
               extras["project"]["optional-dependencies"]["test"])


def _stub(path: Path, body: str) -> None:
    path.write_text("#!/usr/bin/env bash\n" + body + "\n", encoding="utf-8")
    path.chmod(path.stat().st_mode | stat.S_IEXEC)


DEMO_FILES = ("readings.csv", "truth.json", "results.json", "summary.txt", "certificate.html",
              "certificate.pdf", "certificate.dcc.xml", "gonio-manifest.json")
GONIO_STUB = "mkdir -p demo-out && for f in " + " ".join(DEMO_FILES) + "; do echo x > demo-out/$f; done"


def _run_ci(tmp_path: Path, python_body: str, gonio_body: str = GONIO_STUB
            ) -> subprocess.CompletedProcess:
    repo = tmp_path / "repo"
    (repo / ".ci").mkdir(parents=True)
    (repo / "scripts").mkdir()
    shutil.copy(CI, repo / ".ci" / "run")
    shutil.copy(ROOT / ".gitignore", repo / ".gitignore")
    _stub(repo / "scripts" / "install-test-system-deps.sh", "exit 0")
    env = {**os.environ, "GIT_AUTHOR_NAME": "t", "GIT_AUTHOR_EMAIL": "t@t",
           "GIT_COMMITTER_NAME": "t", "GIT_COMMITTER_EMAIL": "t@t"}
    for args in (["init", "-q"], ["add", "-A"], ["commit", "-q", "-m", "x"]):
        subprocess.run(["git", *args], cwd=repo, check=True, env=env)
    stubs = tmp_path / "bin"
    stubs.mkdir()
    _stub(stubs / "pip", "exit 0")
    _stub(stubs / "python", python_body)
    _stub(stubs / "gonio", gonio_body)
    env["PATH"] = f"{stubs}{os.pathsep}{env['PATH']}"
    return subprocess.run(["bash", str(repo / ".ci" / "run")], cwd=repo, env=env,
                          capture_output=True, text=True, timeout=60)


def test_ci_run_passes_when_tests_pass_and_tree_is_clean(tmp_path):
    r = _run_ci(tmp_path, "exit 0")
    assert r.returncode == 0, r.stderr


def test_ci_run_fails_on_untracked_output(tmp_path):
    # a test that writes into the working tree, as the folder named three spaces once was
    r = _run_ci(tmp_path, "mkdir -p '   /.validate-partial' && touch '   /.validate-partial/b0.npz'")
    assert r.returncode != 0
    assert "not clean" in r.stderr and "validate-partial" in r.stderr


def test_ci_run_fails_on_modified_tracked_file(tmp_path):
    r = _run_ci(tmp_path, "echo changed >> scripts/install-test-system-deps.sh")
    assert r.returncode != 0 and "not clean" in r.stderr


def test_ci_run_fails_when_no_tests_were_collected(tmp_path):
    r = _run_ci(tmp_path, "exit 5")
    assert r.returncode == 5 and "no tests collected" in r.stderr


def test_ci_run_tests_a_clone_with_nothing_beside_it(tmp_path):
    (tmp_path / "shared").mkdir()               # the reference shelf beside the checkout
    beside = "[ -e ../" + "shared ] && exit 9; "     # split: the repository names no such path
    r = _run_ci(tmp_path, beside + "[ -f .ci/run ] || exit 8; exit 0")
    assert r.returncode == 0, r.stderr
    assert "fresh clone" in r.stdout


def test_ci_run_fails_when_the_demo_fails_or_writes_too_little(tmp_path):
    r = _run_ci(tmp_path, "exit 0", gonio_body="exit 1")
    assert r.returncode != 0
    r = _run_ci(tmp_path / "b", "exit 0",
                gonio_body="mkdir -p demo-out && echo x > demo-out/results.json")
    assert r.returncode != 0 and "wrote no demo-out/" in r.stderr
