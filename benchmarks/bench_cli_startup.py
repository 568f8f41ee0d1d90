"""Benchmark: how long the ``gonio`` command takes to answer ``--help``.

Target: every ``--help`` under 0.5 s wall on an idle machine (the parser imports only
argparse-level modules; each sub-command imports its analysis when it runs). Each command
runs ``--repeat`` times in a fresh process (``python -m gonio ... --help``, as a user's shell
would); the median wall and CPU (user + system of the child) seconds are printed with the
machine and its load average, since on a loaded machine the wall time measures the queue.
The mechanism itself is tested without timing (tests/test_cli_startup.py). Not part of the
test run. ``--peer DIR`` runs the same commands with ``PYTHONPATH=DIR`` (another checkout
of gonio, such as the tree before the imports were made lazy) in the same run, beside them.

    python benchmarks/bench_cli_startup.py [--repeat 7] [--peer DIR]
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time


def commands() -> list[list[str]]:
    """Every command line that has a ``--help``: ``gonio``, each sub-command and each nested
    sub-command (``db init``, ``bench serve``), read from the parser itself so that a new
    command is timed without editing this list."""
    from gonio.cli import build_parser

    def walk(parser, before):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, child in action.choices.items():
                    yield [*before, name]
                    yield from walk(child, [*before, name])
    return [[], *walk(build_parser(), [])]


#: The children's working folder: not a gonio checkout (``python -m`` puts it first on the
#: path), so that PYTHONPATH (or the installed gonio) decides which tree runs.
_NEUTRAL = tempfile.mkdtemp(prefix="bench-cli-")


def _one(args: list[str], env: dict | None = None) -> tuple[float, float]:
    """(wall, CPU) seconds of one fresh ``python -m gonio ARGS --help``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "gonio", *args, "--help"], check=True,
                   stdout=subprocess.DEVNULL, env=env, cwd=_NEUTRAL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--peer", default=None, metavar="DIR",
                    help="another gonio tree, timed beside this one (PYTHONPATH=DIR)")
    opts = ap.parse_args()
    load = os.getloadavg()
    print(f"machine: {platform.machine()} {platform.processor() or ''} {os.cpu_count()} CPUs, "
          f"{platform.system()} {platform.release()}, Python {platform.python_version()}")
    print(f"load average at start: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    subprocess.run([sys.executable, "-m", "gonio", "--help"], check=True,
                   stdout=subprocess.DEVNULL)                        # warm the file cache
    peer_env = None if opts.peer is None else {**os.environ, "PYTHONPATH": opts.peer}
    head = f"{'command':<32} {'median wall s':>13} {'median CPU s':>12}"
    print(head + ("" if peer_env is None else f" {'peer wall s':>11} {'peer CPU s':>10}"))
    worst = worst_cpu = 0.0
    for args in commands():
        runs = [_one(args) for _ in range(opts.repeat)]
        wall = statistics.median(r[0] for r in runs)
        cpu = statistics.median(r[1] for r in runs)
        worst = max(worst, wall)
        worst_cpu = max(worst_cpu, cpu)
        line = f"{' '.join(['gonio', *args, '--help']):<32} {wall:13.3f} {cpu:12.3f}"
        if peer_env is not None:
            peer = [_one(args, peer_env) for _ in range(opts.repeat)]
            line += (f" {statistics.median(r[0] for r in peer):11.3f}"
                     f" {statistics.median(r[1] for r in peer):10.3f}")
        print(line, flush=True)
    load = os.getloadavg()
    print(f"load average at end: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    print(f"slowest median wall {worst:.3f} s, slowest median CPU {worst_cpu:.3f} s "
          f"(target 0.5 s)")


if __name__ == "__main__":
    main()
