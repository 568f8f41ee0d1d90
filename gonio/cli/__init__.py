"""The ``gonio`` command: a thin layer over the package's functions.

Each sub-command lives in its own module ``gonio/cli/cmd_<name>.py`` that
defines ``register(subparsers)``; the parser it adds sets ``func`` to a
function ``run(args) -> int``. A specification adds its own sub-commands the same
way through the registry (``Specification.commands``, :func:`gonio.specs.commands`:
``align`` and ``thermal-model``, say). Commands are registered in name order,
so adding one never edits a shared list.

Every way a run can end is one line on stderr, never a traceback:

* a :class:`gonio.errors.GonioError` (a user error), an ``OSError`` (a file or
  output place), ``MemoryError`` or ``RecursionError``: ``gonio: error: ...``,
  exit code 2;
* SIGINT or SIGTERM: ``gonio: interrupted`` (exit 130 / 143) after the staging
  folders are removed — the previous output set stays as it was. The commands whose stop is
  a signal (:data:`STOPPED_BY_SIGNAL`: ``gonio acquire``, ``gonio bench serve``) take
  SIGINT and SIGTERM even where the process was started with them ignored (a shell's
  background job, ``cmd &`` in a script, ignores SIGINT);
* anything else is a bug: ``gonio: internal error: ...``, exit 1 (the traceback
  with ``GONIO_DEBUG=1``).

Warnings raised during a failed run are dropped (the error line is the answer);
after a successful run each distinct one is printed once as ``gonio: warning: ...``.

A reader that closes the pipe early (``gonio calibrate ... --json | head``) ends the
command quietly (exit 0: every output file was already written).
"""

from __future__ import annotations

import argparse
import gc
import importlib
import os
import pkgutil
import signal
import sys
import warnings

from gonio.errors import GonioError


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line and exit code 2; a nested command's parser is
    found by its words (:meth:`command_parser`)."""

    subcommands = None

    def add_subparsers(self, **kwargs):
        """argparse's, the action kept as :attr:`subcommands`."""
        self.subcommands = super().add_subparsers(**kwargs)
        return self.subcommands

    def command_parser(self, words) -> argparse.ArgumentParser:
        """The parser of the (nested) command ``words`` (``["bench", "serve"]``: the parser of
        ``gonio bench serve``)."""
        p = self
        for w in words:
            p = p.subcommands.choices[w]
        return p

    def error(self, message: str) -> None:  # pragma: no cover - exercised via CLI tests
        sys.stderr.write(f"{self.prog}: error: {_short(message)}\n")
        raise SystemExit(2)


class Terminated(BaseException):
    """Raised by the SIGTERM handler so that every ``finally`` (staging clean-up) runs."""


#: The stop signals received by this process (:func:`_on_sigterm`, :func:`_on_sigint`): a
#: signal that lands inside an extension module's import surfaces as that import's error
#: ("ImportError: initialization failed"), which is then the stop, not a bug.
_RECEIVED: list[int] = []


def _on_sigterm(signum, frame):
    _RECEIVED.append(signal.SIGTERM)
    raise Terminated()


def _on_sigint(signum, frame):
    _RECEIVED.append(signal.SIGINT)
    raise KeyboardInterrupt


#: The commands (by their words) whose stop is SIGINT or SIGTERM: an acquisition stopped by
#: its operator, a served bench that runs until it is stopped. They take both signals even
#: where the process inherited them ignored: a non-interactive shell starts ``gonio bench
#: serve &`` with SIGINT ignored, and ``kill -INT`` (or a test's ``send_signal``) would be
#: lost, the server left running.
STOPPED_BY_SIGNAL = (("acquire",), ("bench", "serve"))


def _install_stop_handlers(argv: list[str], own_process: bool) -> None:
    """SIGTERM raises :class:`Terminated` where its handler is the default (every command);
    for a command of :data:`STOPPED_BY_SIGNAL` run as its own process, SIGINT raises
    ``KeyboardInterrupt`` and SIGTERM :class:`Terminated` whatever the process inherited
    (called from Python, the caller's handlers are left as they are)."""
    stopped = own_process and any(tuple(argv[:len(words)]) == words
                                  for words in STOPPED_BY_SIGNAL)
    try:
        if stopped or signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, None):
            signal.signal(signal.SIGTERM, _on_sigterm)
        if stopped or (own_process
                       and signal.getsignal(signal.SIGINT) is signal.default_int_handler):
            signal.signal(signal.SIGINT, _on_sigint)
    except ValueError:        # not the main thread (called from a test runner's thread)
        pass


def _short(text: str, limit: int = 400) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit] + f"… ({len(text)} characters)"


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The full argument parser, with every ``cmd_*`` module and every specification's
    commands registered. ``argv`` (the arguments about to be parsed) naming one of gonio's
    own commands first registers that command alone: loading every specification costs
    about a second, importing the other commands' modules a tenth, and that command needs
    neither. The options
    the specifications add to one of gonio's commands (``Specification.arguments``:
    ``gonio calibrate``, ``simulate``, ``budget``, ``validate``, ``bench serve``) are added
    when that command runs or the whole parser is built."""
    from gonio import __version__

    parser = _Parser(prog="gonio", description=(
        "Calibrate gyros and goniometers per a calibration specification (a plug-in: "
        "gonio.specs.available()): virtual bench, readings to items with their "
        "uncertainties, certificates."))
    parser.add_argument("--version", action="version", version=f"gonio {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for _, register in sorted(_commands(argv).items()):
        register(sub)
    from gonio.cli.spec_options import add_spec_options
    from gonio.specs import ARGUMENT_COMMANDS

    for command in ARGUMENT_COMMANDS:
        # the options the specifications add to a command (Specification.arguments, a nested
        # command by its words) load every specification: only for that command, or when the
        # whole parser is built
        words = command.split()
        if not argv or argv[0] == words[0]:
            add_spec_options(parser.command_parser(words), command)
    return parser


#: gonio's commands whose module adds options to another of gonio's commands, by the command
#: they extend: ``gonio db`` adds ``--record`` (with ``--database``/``--data`` and the
#: attachments) to ``gonio calibrate`` (:func:`gonio.cli.cmd_db.hook_calibrate`). Running
#: the extended command alone imports these modules too (registered after it: sorted names).
EXTENDED_BY = {"calibrate": ("db",)}


def _commands(argv: list[str] | None = None) -> dict:
    """{command name: register(subparsers)}: gonio's ``cmd_*`` modules and the commands the
    registered specifications add (:func:`gonio.specs.commands`); when ``argv`` starts
    with a built-in command, that command alone. A specification's command that takes a
    built-in name is not added, with a warning naming it."""
    import gonio.cli as pkg
    from gonio.specs import commands

    names = {info.name[4:].replace("_", "-"): info.name
             for info in pkgutil.iter_modules(pkg.__path__) if info.name.startswith("cmd_")}
    if argv and argv[0] in names:
        # one of gonio's own commands: only its module is imported (the others' imports
        # are start-up time the command does not need: a tenth of a second for serve),
        # with the modules that add options to it (EXTENDED_BY)
        wanted = (argv[0], *EXTENDED_BY.get(argv[0], ()))
        return {name: importlib.import_module(f"gonio.cli.{names[name]}").register
                for name in wanted if name in names}
    found = {name: importlib.import_module(f"gonio.cli.{module}").register
             for name, module in names.items()}
    for name, add_parser in commands():
        if name in found:
            warnings.warn(f"a specification's command {name!r} is not available: gonio has a "
                          "command by that name")
            continue
        found[name] = add_parser
    return found


def _print_warnings(caught) -> None:
    """Each distinct warning (RuntimeWarnings of numpy left out) as one line on stderr."""
    seen = set()
    for w in caught:
        if issubclass(w.category, RuntimeWarning):
            continue
        msg = _short(str(w.message), 200)
        if msg not in seen:
            seen.add(msg)
            sys.stderr.write(f"gonio: warning: {msg}\n")


def _error(msg: str) -> int:
    sys.stderr.write(f"gonio: error: {_short(msg)}\n")
    return 2


#: The cyclic garbage collector's thresholds of a command run as its own process: a command
#: allocates most of its objects once (the imports, a figure's artists) and keeps them, and
#: at Python's default (700, 10, 10) a demo spends about 0.4 s of CPU re-examining them
#: (0.2 s at these). Memory is held by arrays, which the collector does not free.
GC_THRESHOLDS = (10_000, 10, 10)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``gonio`` console script; returns the exit code. Called without
    ``argv`` (its own process) it sets :data:`GC_THRESHOLDS`."""
    if argv is None:
        gc.set_threshold(*GC_THRESHOLDS)
    _install_stop_handlers(sys.argv[1:] if argv is None else list(argv), argv is None)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                parser = build_parser(sys.argv[1:] if argv is None else list(argv))
                args = parser.parse_args(argv)
            except SystemExit:          # --help, --version: still say what was left out
                _print_warnings(caught)
                raise
            rc = _run(args)
            sys.stdout.flush()          # a closed pipe shows here, not at interpreter exit
        _print_warnings(caught)
        return rc
    except GonioError as exc:
        return _error(str(exc))
    except BrokenPipeError:
        # the reader went away: stop writing, and keep Python from complaining at exit
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except (OSError, ValueError):  # pragma: no cover - stdout without a descriptor
            pass
        return 0
    except OSError as exc:
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        return _error(f"{where}{exc.strerror or exc}")
    except MemoryError:
        return _error("out of memory; the input or the requested work is too large")
    except RecursionError:
        return _error("input nested too deeply")
    except KeyboardInterrupt:
        _quiet_shutdown()
        sys.stderr.write("gonio: interrupted\n")
        return 130
    except Terminated:
        _quiet_shutdown()
        sys.stderr.write("gonio: terminated\n")
        return 143
    except SystemExit as exc:      # argparse: --help, --version, a usage error
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    except Exception as exc:  # a bug: still one line unless asked for the traceback
        if _RECEIVED:          # the stop landed inside an import: it is the stop
            _quiet_shutdown()
            stop = _RECEIVED[-1] == signal.SIGTERM
            sys.stderr.write("gonio: terminated\n" if stop else "gonio: interrupted\n")
            return 143 if stop else 130
        if os.environ.get("GONIO_DEBUG"):
            raise
        sys.stderr.write(f"gonio: internal error: {type(exc).__name__}: {_short(exc, 300)} "
                         "(GONIO_DEBUG=1 shows the traceback)\n")
        return 1


def _run(args) -> int:
    """Run the sub-command, its name recorded for the manifests it writes
    (:func:`gonio.atomic.set_command`)."""
    from gonio.atomic import set_command

    set_command(args.command)
    try:
        return int(args.func(args) or 0)
    finally:
        set_command(None)


def _quiet_shutdown() -> None:
    """After an interrupt the one line is all that is printed: objects a library
    finalises at exit (a half-written Arrow writer, say) may not print tracebacks."""
    sys.unraisablehook = lambda unraisable: None


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
