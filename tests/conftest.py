"""Fixtures shared by several test modules."""

from __future__ import annotations

import importlib
import os
import sys
import tomllib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
#: The DCC 3.3.0 schema set: the offline copy the repository carries (tests/data/dcc-3.3.0,
#: with its licences), or $GONIO_DCC_SCHEMA_DIR.
SCHEMA_DIR = Path(os.environ.get("GONIO_DCC_SCHEMA_DIR",
                                 REPO / "tests" / "data" / "dcc-3.3.0")).resolve()
QUDT_URL = "https://www.ptb.de/si/v2.2.1/qudt/quantitykind.xsd"


def pytest_xdist_auto_num_workers(config):
    """pytest-xdist's ``-n auto``: the CPUs this process may run on (``os.sched_getaffinity``,
    a container's or ``taskset``'s share), where pytest-xdist would ask psutil for physical
    cores (1 on many 2-vCPU machines: no parallelism at all). ``$PYTEST_XDIST_AUTO_NUM_WORKERS``
    still wins where set. The README's test command caps it with ``--maxprocesses 4``: each
    worker starts its own PostgreSQL server, ``gonio serve`` processes and Chromium."""
    env = os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS", "").strip()
    if env.isdigit() and int(env) > 0:
        return int(env)
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


@pytest.fixture(scope="session")
def dcc_schema():
    """The DCC 3.3.0 XSD loaded offline with xmlschema (XSD 1.1), remote access refused."""
    xmlschema = pytest.importorskip("xmlschema", reason="pip install '.[test]'")
    assert (SCHEMA_DIR / "dcc.xsd").is_file(), (
        f"DCC 3.3.0 schema set not found at {SCHEMA_DIR} (set GONIO_DCC_SCHEMA_DIR)")
    return xmlschema.XMLSchema11(
        str(SCHEMA_DIR / "dcc.xsd"),
        uri_mapper={QUDT_URL: (SCHEMA_DIR / "si" / "qudt" / "quantitykind.xsd").as_uri()},
        allow="local")


#: The guide's example specification package (docs/writing-a-specification.md).
PLUGIN = REPO / "tests" / "plugins" / "acme_rate_check"


def install_entry_points(site: Path, project: Path) -> None:
    """What ``pip install project`` leaves for importlib.metadata: a dist-info with the
    entry points the project's pyproject.toml declares (the package itself on sys.path)."""
    meta = tomllib.loads((project / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    di = site / f"{meta['name'].replace('-', '_')}-{meta['version']}.dist-info"
    di.mkdir(parents=True)
    (di / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {meta['name']}\n"
                                 f"Version: {meta['version']}\n", encoding="utf-8")
    lines = []
    for group, eps in meta["entry-points"].items():
        lines.append(f"[{group}]")
        lines += [f"{name} = {ref}" for name, ref in eps.items()]
    (di / "entry_points.txt").write_text("\n".join(lines) + "\n", encoding="utf-8")


@pytest.fixture(scope="module")
def plugin(tmp_path_factory):
    """The example specification package (tests/plugins/acme_rate_check) installed as pip
    leaves it, for the tests of one module; removed again after them."""
    site = tmp_path_factory.mktemp("site")
    install_entry_points(site, PLUGIN)
    sys.path[:0] = [str(site), str(PLUGIN)]
    importlib.invalidate_caches()
    yield site
    for p in (str(site), str(PLUGIN)):
        sys.path.remove(p)
    for m in [m for m in sys.modules if m.split(".")[0] == "acme_rate_check"]:
        del sys.modules[m]
    importlib.invalidate_caches()


# ------------------------------------------- simulate + calibrate on the command line
@pytest.fixture(scope="session")
def calibrate_readings():
    """``calibrate(readings, protocol, out)``: ``gonio calibrate`` of a readings file with a
    protocol into ``out`` (exit 0 asserted, stderr shown otherwise); returns the items of its
    ``results.json``."""
    import contextlib
    import io
    import json

    from gonio.cli import main

    def calibrate(readings, protocol, out) -> dict:
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            rc = main(["calibrate", str(readings), "--protocol", str(protocol),
                       "--out", str(out)])
        assert rc == 0, err.getvalue()
        return json.loads((Path(out) / "results.json").read_text(encoding="utf-8"))["items"]
    return calibrate


@pytest.fixture(scope="session")
def simulate_calibrate(calibrate_readings):
    """``run(folder, protocol, bench, seed)``: ``gonio simulate`` of ``protocol`` on ``bench``
    (a name or file) with ``seed`` into ``folder/sim``, then ``gonio calibrate`` of its
    readings into ``folder/cal``; returns (the readings file, the results' items). The
    reference the instrument tests compare an acquisition against."""
    from gonio.cli import main

    def run(folder, protocol, bench, seed: int):
        folder = Path(folder)
        assert main(["simulate", "--protocol", str(protocol), "--bench", str(bench), "--seed",
                     str(seed), "--out", str(folder / "sim")]) == 0
        readings = folder / "sim" / "readings.csv"
        return readings, calibrate_readings(readings, protocol, folder / "cal")
    return run


# ------------------------------------------- runs made once per test session, all workers
def _tree_digest(folder: Path) -> str:
    """SHA-256 over the relative names and bytes of every file under ``folder``."""
    import hashlib

    h = hashlib.sha256()
    for p in sorted(q for q in folder.rglob("*") if q.is_file()):
        h.update(p.relative_to(folder).as_posix().encode() + b"\0")
        h.update(hashlib.sha256(p.read_bytes()).digest())
    return h.hexdigest()


@pytest.fixture(scope="session")
def shared_run(tmp_path_factory):
    """``shared_run(key, make) -> Path``: the folder ``make(folder)`` filled, made once per
    test session whatever the number of xdist workers (the first worker to ask makes it
    under a file lock in the session's shared temporary root; the others wait and read it).

    For the expensive runs many test modules read and none changes (the built-in demo of a
    specification, say): ``key`` names the run completely (every argument ``make`` uses). A
    test that changes a file copies the folder into its own ``tmp_path`` first; at the end of
    the session every shared folder a worker used must hold the bytes it was made with (the
    fixture's teardown errs otherwise, naming the folder)."""
    import fcntl
    import re
    import shutil

    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent                       # shared by the session's workers
    root = root / "shared-runs"
    root.mkdir(exist_ok=True)

    def get(key: str, make) -> Path:
        name = re.sub(r"[^A-Za-z0-9._=-]+", "_", key)
        final, done = root / name, root / f"{name}.done"
        with open(root / f"{name}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not done.exists():
                work = root / f"{name}.partial"
                shutil.rmtree(work, ignore_errors=True)
                shutil.rmtree(final, ignore_errors=True)
                work.mkdir()
                make(work)
                digest = _tree_digest(work)
                work.rename(final)
                done.write_text(digest, encoding="utf-8")
        used[final] = done.read_text(encoding="utf-8")
        return final

    used: dict[Path, str] = {}
    yield get
    changed = [str(p) for p, d in used.items() if _tree_digest(p) != d]
    assert not changed, f"shared runs changed by a test (copy before writing): {changed}"


def _gonio_in_process(argv: list[str]) -> None:
    """``gonio ARGV`` through :func:`gonio.cli.main` in this process, its output kept quiet;
    exit 0 asserted (stderr shown otherwise)."""
    import contextlib
    import io

    from gonio.cli import main

    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(argv)
    assert rc == 0, f"gonio {' '.join(argv)}: exit {rc}: {err.getvalue()}"


@pytest.fixture(scope="session")
def shared_demo(shared_run):
    """``shared_demo(spec, lang="en", seed=0, lab=None) -> Path``: the folder ``gonio demo
    --spec SPEC --lang LANG --seed SEED [--lab LAB]`` writes (readings, truth, results,
    certificate, DCC), made once per session (:func:`shared_run`; a laboratory file is keyed
    by its bytes): read it, never write into it."""
    import hashlib

    def get(spec: str, lang: str = "en", seed: int = 0, lab: Path | str | None = None) -> Path:
        def make(folder: Path) -> None:
            _gonio_in_process(["demo", "--spec", spec, "--lang", lang, "--seed", str(seed),
                               "--out", str(folder / "out")]
                              + ([] if lab is None else ["--lab", str(lab)]))

        tag = "" if lab is None else "-lab" + hashlib.sha256(Path(lab).read_bytes()).hexdigest()[:16]
        return shared_run(f"demo-{spec}-{lang}-seed{seed}{tag}", make) / "out"
    return get


@pytest.fixture(scope="session")
def shared_simulation(shared_run):
    """``shared_simulation(spec, protocol=None, seed=3) -> Path``: the folder ``gonio simulate
    --spec SPEC [--protocol PROTOCOL] --seed SEED`` writes (readings, truth, the files they
    name, the manifest), made once per session (:func:`shared_run`; a protocol file keyed by
    its bytes). ``gonio simulate`` writes the same bytes into any folder, so a test that needs
    the simulated set in its own folder copies it (:func:`shutil.copytree`) where it would
    have simulated again; never write into the shared one."""
    import hashlib

    def get(spec: str, protocol: Path | str | None = None, seed: int = 3) -> Path:
        def make(folder: Path) -> None:
            _gonio_in_process(["simulate", "--spec", spec, "--seed", str(seed),
                               "--out", str(folder / "sim")]
                              + ([] if protocol is None else ["--protocol", str(protocol)]))

        tag = ("" if protocol is None else
               "-proto" + hashlib.sha256(Path(protocol).read_bytes()).hexdigest()[:16])
        return shared_run(f"simulate-{spec}-seed{seed}{tag}", make) / "sim"
    return get
