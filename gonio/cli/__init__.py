"""The ``gonio`` command: a thin layer over the package's functions.

Each sub-command lives in its own module ``gonio/cli/cmd_<name>.py`` that
defines ``register(subparsers)``; the parser it adds sets ``func`` to a
function ``run(args) -> int``. Modules are discovered in name order, so adding
a command never edits a shared list.

A :class:`gonio.errors.GonioError` (a user error) is printed on one line to
stderr as ``gonio: error: ...`` and the exit code is 2, with no traceback. A reader
that closes the pipe early (``gonio calibrate ... --json | head``) ends the command
quietly (exit 0: every output file was already written).
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys

from gonio.errors import GonioError


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line and exit code 2."""

    def error(self, message: str) -> None:  # pragma: no cover - exercised via CLI tests
        sys.stderr.write(f"{self.prog}: error: {message}\n")
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser, with every ``cmd_*`` module registered."""
    from gonio import __version__

    parser = _Parser(prog="gonio", description=(
        "Calibrate optical-gyro goniometers per the draft JJF specification "
        "(virtual bench, seven characteristics, Annex A uncertainty)."))
    parser.add_argument("--version", action="version", version=f"gonio {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    import gonio.cli as pkg

    for info in sorted(pkgutil.iter_modules(pkg.__path__), key=lambda m: m.name):
        if info.name.startswith("cmd_"):
            importlib.import_module(f"gonio.cli.{info.name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``gonio`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        rc = int(args.func(args) or 0)
        sys.stdout.flush()          # a closed pipe shows here, not at interpreter exit
        return rc
    except GonioError as exc:
        sys.stderr.write(f"gonio: error: {exc}\n")
        return 2
    except BrokenPipeError:
        # the reader went away: stop writing, and keep Python from complaining at exit
        import os

        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except (OSError, ValueError):  # pragma: no cover - stdout without a descriptor
            pass
        return 0
    except KeyboardInterrupt:  # pragma: no cover
        sys.stderr.write("gonio: interrupted\n")
        return 130


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
