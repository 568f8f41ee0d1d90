"""The options a specification adds to one of gonio's commands (``Specification.arguments``:
``gonio calibrate``, ``simulate``, ``budget``, ``validate``, ``bench serve``): one argument
group per specification, titled ``options of --spec KEY``.

gonio's command line holds none of them. The parser builder (:func:`gonio.cli.build_parser`)
calls :func:`add_spec_options` on the parser of each command of
:data:`gonio.specs.ARGUMENT_COMMANDS` (a nested one found by its words), only for the command
about to run, or when the whole parser is built (it loads every specification); the command's
module sets :func:`no_spec_options` for a parser built without them. The command reads the
options given with :func:`given`; the pipeline refuses one the ``--spec`` in use does not
take, naming it (one line, exit 2).
"""

from __future__ import annotations

import argparse


class _Group:
    """An argparse argument group as a specification's hook sees it: ``add_argument`` records
    each option's dest; an option string another specification already added with the same
    dest is shared, not added twice."""

    def __init__(self, group, spec, command: str, taken: dict):
        self.group, self.spec, self.command, self.taken = group, spec, command, taken
        self.dests: list[str] = []
        self.inputs: list[str] = []
        self.flags: dict[str, str] = {}

    def add_argument(self, *flags, **kwargs):
        dest = kwargs.get("dest") or next(
            (f.lstrip("-").replace("-", "_") for f in flags if f.startswith("--")), None)
        where = f"the {self.command} option {flags[0]} of specification {self.spec.key!r}"
        if dest not in self.spec.accepted_options(self.command):
            raise ValueError(f"{where} has dest {dest!r}, which the keywords its {self.command} "
                             "takes (Specification.accepted_options) do not list")
        if kwargs.get("default", False if kwargs.get("action") == "store_true" else None) \
                not in (None, False):
            raise ValueError(f"{where} has a default; the default is its hook's (None: "
                             "not given)")
        owner = {self.taken.get(f) for f in flags}
        if owner == {dest}:                      # another specification's, the same option
            self._record(dest, flags[0], None)
            return None
        if owner != {None}:
            raise ValueError(f"{where} is taken by another option")
        try:
            action = self.group.add_argument(*flags, **kwargs)
        except argparse.ArgumentError as exc:    # one of the command's own options
            raise ValueError(f"{where}: {exc}") from None
        self.taken.update({f: action.dest for f in flags})
        self._record(action.dest, flags[0], action.metavar)
        return action

    def _record(self, dest: str, flag: str, metavar) -> None:
        self.dests.append(dest)
        self.flags.setdefault(dest, flag)
        if metavar == "FILE":
            self.inputs.append(dest)


def add_spec_options(p, command: str) -> None:
    """Add every registered specification's own options of ``gonio command`` to its parser
    ``p`` (:func:`gonio.specs.command_arguments`), one argument group each, and record their
    dests (``spec_options``), those naming input files (``spec_inputs``) and each dest's
    option string (``spec_flags``) as the parser's defaults. A hook that fails adds nothing
    of its specification's, with a warning naming it."""
    import warnings

    from gonio.specs import command_arguments

    taken: dict[str, str] = {}          # option string → dest, over the specifications
    dests, inputs, flags = [], [], {}
    for spec, add in command_arguments(command):
        group = _Group(p.add_argument_group(f"options of --spec {spec.key}"), spec, command,
                       taken)
        try:
            add(group)
        except Exception as exc:        # a plug-in's bug costs only its own options
            warnings.warn(f"the {command} options of specification {spec.key!r} are not all "
                          f"available ({type(exc).__name__}: {exc})")
        dests += [d for d in group.dests if d not in dests]
        inputs += [d for d in group.inputs if d not in inputs]
        flags = {**group.flags, **flags}
    p.set_defaults(spec_options=tuple(dests), spec_inputs=tuple(inputs), spec_flags=flags)


def no_spec_options(p) -> None:
    """The defaults :func:`add_spec_options` sets, none added (a parser built for another
    command: its specifications' options are not loaded)."""
    p.set_defaults(spec_options=(), spec_inputs=(), spec_flags={})


def given(args) -> dict:
    """{dest: value} of the specification options ``args`` holds (every one added, given or
    not: the pipeline drops those not given and refuses a foreign one given)."""
    return {d: getattr(args, d) for d in args.spec_options}


def inputs(args) -> list:
    """The values of the specification options that name input files."""
    return [getattr(args, d) for d in args.spec_inputs]


def refuse(spec, command: str, given_: dict, args, flags: dict | None = None) -> dict:
    """``given_`` less the options not given, refused as the pipeline does
    (:func:`gonio.pipeline.dispatch.refuse_options`) but naming each option as it was typed
    (``flags`` {keyword: option} of the command's own, and the specifications' options)."""
    from gonio.pipeline.dispatch import refuse_options

    return refuse_options(spec, given_, spec.accepted_options(command), command,
                          {**(flags or {}), **args.spec_flags})


def flag_of(args, key: str | None) -> str | None:
    """The option string of the specification option whose dest is ``key`` (a GonioError's
    key), or None."""
    return args.spec_flags.get(key or "")
