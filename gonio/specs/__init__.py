"""Calibration specifications as plug-ins: the :class:`Specification` protocol and its registry.

A specification (a standard, a draft, a laboratory's in-house procedure) is one package that
exposes ``SPEC``, a :class:`Specification`: its key (the ``--spec`` value), titles and
clauses, its default protocol and bench, and the hooks gonio calls — ``calibrate``
(readings → result), ``screen`` (readings → findings), ``simulate`` and ``truth`` (the
virtual bench), ``budget`` (its own uncertainty annex), ``coverage`` (the settings of its
coverage study), ``outputs`` (the module that renders a result: results.json, summary,
tables, certificate, DCC) and ``commands`` (the ``gonio`` sub-commands it adds, such as the
triad's ``align``). docs/writing-a-specification.md builds one from scratch; a specification
written outside gonio imports what it needs from :mod:`gonio.kit` (docs/kit.md).

Every field is checked when ``SPEC`` is built and when the registry loads it (one line
naming the entry point and the field); a specification that cannot be loaded is left out of
:func:`available` with a warning, so it costs only its own key.

Packages register through the entry-point group ``gonio.specs`` (``key = "pkg:SPEC"``), as
pytest plug-ins do: gonio's four built-in specifications are listed in gonio's own
``pyproject.toml`` exactly as a laboratory's package lists its procedure in its own. No
module outside ``gonio/specs/`` names a specification: the command line and the pipeline
find every one through :func:`available` and :func:`get`.

>>> [k for k in available() if k == "ogam-draft"]
['ogam-draft']
>>> get("ogam-draft").default_protocol
'ogam-draft'
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import re
from dataclasses import dataclass, field
from fnmatch import fnmatchcase
from typing import Any, Callable

from gonio.errors import GonioError

__all__ = ["Coverage", "Specification", "available", "command_arguments", "commands", "get",
           "lazy", "ARGUMENT_COMMANDS",
           "CONTENT_FIELDS", "FIGURE_ROLES", "ITEM_RENDERER", "content_field", "ENTRY_POINT_GROUP", "BUILT_IN",
           "DEFAULT_KEY"]

#: The entry-point group a specification package registers under.
ENTRY_POINT_GROUP = "gonio.specs"

#: The specification a command uses when neither ``--spec`` nor the readings name one (gonio
#: began as the optical-gyro draft's tool; its files carry no ``# spec:`` line).
DEFAULT_KEY = "ogam-draft"

#: gonio's own entry points (pyproject.toml ``[project.entry-points."gonio.specs"]``), used
#: only where gonio runs from a source tree that was never installed (no metadata to read).
BUILT_IN: dict[str, str] = {
    "ogam-draft": "gonio.specs.ogam_draft:SPEC",
    "jjf1535-2015": "gonio.specs.jjf1535:SPEC",
    "iec62047-20": "gonio.specs.iec62047_20:SPEC",
    "triad-alignment": "gonio.specs.triad_alignment:SPEC",
}

#: A specification's key; a module name; a ``"module:function"`` reference.
_KEY = re.compile(r"[a-z0-9][a-z0-9._-]*")
_MODULE = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*")
_REF = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*:[A-Za-z_]\w*(\.[A-Za-z_]\w*)*")
#: A D-SI unit (D-SI 2.x): ``\\unit`` tokens (prefixes are tokens too), each optionally
#: raised ``\\tothe{n}``.
_DSI = re.compile(r"(\\[a-z]+(\{-?[0-9]+(\.[0-9]+)?\})?)+")
#: The fields of a :class:`Specification` that are strings, and its optional hooks.
_STRING_FIELDS = ("title_en", "title_zh", "clause_doc", "default_protocol", "default_bench",
                  "outputs", "readings_format", "certificate_content")
_HOOKS = ("load_protocol", "screen", "simulate", "truth", "run_trial", "budget",
          "named_inputs", "acquisition", "acquire", "serve", "readings_columns",
          "read_table_calibration")
#: The functions an ``outputs`` module defines (``write(result, out, *, truth, lab, lang,
#: dcc)``, ``results_json(result, lab)``, ``summary(result, lab)``) and those it may define
#: (``demo(out, *, bench, seed, lab, lang, dcc, force, inputs, on_stage)``,
#: ``warnings(result)``, ``item_titles(res, lang)``: {item key: its name as the certificate
#: in ``lang`` names it}, for the web's pages in the certificate's languages). An outputs module may also list, as ``CONTENT_REQUIRED``, the
#: :data:`CONTENT_FIELDS` the certificate content must define for it.
OUTPUTS_REQUIRED = ("write", "results_json", "summary")
OUTPUTS_OPTIONAL = ("demo", "warnings", "item_titles")
#: The ``gonio`` commands a specification may add options to (``Specification.arguments``),
#: each with the field naming the keywords its hook takes beyond the common ones
#: (:meth:`Specification.accepted_options`). A nested command is named by its words, as typed
#: (``"bench serve"``: the options of ``gonio bench serve``, which its ``serve`` hook takes).
ARGUMENT_COMMANDS = {"bench serve": "serve_options", "budget": "budget_options",
                     "calibrate": "calibrate_options", "simulate": "simulate_options",
                     "validate": "coverage.options"}


@functools.lru_cache(maxsize=1)
def _builtin() -> tuple[str, ...]:
    """gonio's built-in protocol names (:func:`gonio.resources.builtin_names`)."""
    from gonio.resources import builtin_names
    return tuple(builtin_names())


def _field_error(where: str, name: str, expected: str, got) -> GonioError:
    shown = repr(got)
    shown = shown if len(shown) <= 60 else shown[:57] + "..."
    return GonioError(f"{where}: field {name} must be {expected}, got {shown}", key="--spec")


def _check_callable(obj, where: str, name: str) -> None:
    value = getattr(obj, name)
    if value is not None and not callable(value):
        raise _field_error(where, name, "a callable or None", value)


def _set_strings(obj, where: str, name: str, kind: type) -> None:
    """Check that the field ``name`` is a collection of strings and store it as ``kind``."""
    value = getattr(obj, name)
    if isinstance(value, (str, bytes, dict)) or not isinstance(
            value, (tuple, list, set, frozenset)) or not all(isinstance(v, str) for v in value):
        raise _field_error(where, name, f"a {kind.__name__} of str", value)
    object.__setattr__(obj, name, kind(value))


@dataclass(frozen=True, kw_only=True)
class Coverage:
    """How ``gonio validate --spec KEY`` studies a specification's uncertainties.

    Attributes
    ----------
    engine : str
        ``"items"``: the generic study (:mod:`gonio.pipeline.coverage`): simulate with
        noise, calibrate, count per item how often |value − truth| ≤ U over the trials.
        ``"cases"``: a study the specification describes itself (``study``), run by the
        engine of :mod:`gonio.pipeline.validate` (batches, partial results, resume).
    stream : int
        The index of the study's seed stream: trial i is seeded by
        ``SeedSequence(seed, spawn_key=(stream, i))``; distinct per specification so that two
        studies never share draws, and fixed so that a published study reproduces.
    reduced : dict
        The study's programme over the built-in protocol, ``{section: {key: value}}``
        (small sample counts, short waits, every item still measured).
    study_bench : callable or None
        (bench name or file) → the bench of the study (``simulate`` side: may switch off
        effects its truth leaves out). None: the bench as loaded.
    options : frozenset
        The ``gonio validate`` options the engine takes beyond the common ones.
    cases : dict
        ``"items"`` engine: the study's cases, name → what the bench does in it (``gonio
        validate --cases``; ``study_bench(name, case=…)`` makes each case's bench; the first
        is the default and keeps the seed stream ``stream``). Empty: one case, no ``--cases``.
    fixed_cases : frozenset
        The cases of ``cases`` at one fixed condition (each Type B effect at its bound): judged
        on coverage only, z's spread information (a Type B line is one fixed offset there).
    study : callable or None
        ``"cases"`` engine: ``study(trials, *, seed, bench, protocol, **options)`` → the
        planned study: ``settings`` (dict), ``jobs`` (part → picklable job whose
        ``run(start, stop)`` packs those trials as arrays with ``case`` and ``index``),
        ``unpack(packed)`` → {trial index: trial}, ``report(done)`` → an object with
        ``to_dict()`` (validation.json) and ``table()`` (docs/writing-a-specification.md).
    """

    engine: str = "items"
    stream: int = 0
    reduced: dict = field(default_factory=dict)
    study_bench: Callable[..., Any] | None = None
    options: frozenset = frozenset()
    study: Callable[..., Any] | None = None
    cases: dict = field(default_factory=dict)
    fixed_cases: frozenset = frozenset()

    def __post_init__(self):
        where = "Coverage"
        if self.engine not in ("items", "cases"):
            raise _field_error(where, "engine", "'items' or 'cases'", self.engine)
        if isinstance(self.stream, bool) or not isinstance(self.stream, int) or self.stream < 0:
            raise _field_error(where, "stream", "a non-negative int", self.stream)
        if not isinstance(self.reduced, dict) or not all(
                isinstance(k, str) and isinstance(v, dict) for k, v in self.reduced.items()):
            raise _field_error(where, "reduced", "a dict {section: {key: value}}", self.reduced)
        _set_strings(self, where, "options", frozenset)
        _set_strings(self, where, "fixed_cases", frozenset)
        if not isinstance(self.cases, dict) or not all(
                isinstance(k, str) and isinstance(v, str) for k, v in self.cases.items()):
            raise _field_error(where, "cases", "a dict {case: description}", self.cases)
        if not self.fixed_cases <= set(self.cases):
            raise _field_error(where, "fixed_cases", "names of cases", self.fixed_cases)
        for name in ("study_bench", "study"):
            _check_callable(self, where, name)
        if self.engine == "cases" and self.study is None:
            raise _field_error(where, "study", "a callable (engine 'cases' runs the "
                               "specification's own study)", None)


@dataclass(frozen=True, kw_only=True)
class Specification:
    """What gonio needs to know of one calibration specification (the protocol every
    specification package implements; docs/writing-a-specification.md).

    Attributes
    ----------
    key : str
        The ``--spec`` value and the ``# spec:`` metadata value (``ogam-draft``).
    title_en, title_zh : str
        The specification's title.
    clause_doc : str
        The document with the clause-by-clause reading taken.
    clauses : tuple of str
        The clauses whose items it computes (for the certificate's method statement).
    default_protocol, default_bench : str
        Names (or files) of the default protocol and virtual bench.
    load_protocol : callable
        (name, file, loaded protocol or None) → the protocol (its schema and defaults);
        None means the protocol is passed on as given.
    calibrate : callable
        ``calibrate(readings, protocol=None, *, findings=None, **options)`` → the result
        (readings: a file or the readings object the specification reads); ``options`` are
        those of ``calibrate_options`` (``monte_carlo_trials`` always); ``findings``: the
        screening the pipeline made (``screen``), applied as given (None: screen here).
    screen : callable or None
        ``screen(readings, protocol=None, **options)`` → ``list[gonio.result.Finding]``:
        the readings the specification refuses, sets aside or flags, before calibrating.
        The pipeline calls it first (:func:`gonio.pipeline.dispatch.screen_and_calibrate`)
        and hands the findings to ``calibrate``, which applies them and states every one.
    simulate : callable or None
        ``simulate(out, *, protocol=None, bench=None, seed=0, **options)`` → {name: path}:
        run the protocol on the virtual bench and write the readings a laboratory would
        record and ``truth.json`` into the folder ``out`` (staged by the caller).
    truth : callable or None
        ``truth(bench, protocol)`` → {item key: {"value": …, "how": …}} from the bench's
        physical parameters, never from an estimator.
    run_trial : callable or None
        ``run_trial(bench, protocol, seed)`` → (readings, truth dict): one simulated
        calibration held in memory, for the coverage study.
    acquisition : callable or None
        ``acquisition(protocol=None, metadata=None)`` →
        :class:`gonio.protocol.programme.Programme`: the segments ``gonio acquire`` runs on
        a laboratory's rate bench (:mod:`gonio.instruments.rate_acquire`) and the readings'
        metadata; ``metadata`` holds the laboratory's ``--meta`` values. None: the
        specification is not acquired through gonio's rate instruments.
    acquire : callable or None
        ``acquire(protocol, resources, out, *, metadata, resume, timeout_s, prompt)`` →
        :class:`gonio.instruments.run.AcquisitionResult`: runs the specification's own
        programme on its own instruments (``resources``: VISA resource strings by role),
        writing ``out``/``readings.csv`` and ``out``/``io.log``; used by ``gonio acquire``
        when the specification has no ``acquisition`` programme (the optical draft's
        goniometer: a rotary table and an acquisition module).
    serve : callable or None
        ``serve(bench, ports, *, speed, seed, faults, **options)`` → an object with
        ``resources`` (VISA resource strings by role) and ``close()``: its virtual bench
        (file or built-in name) served as instruments on 127.0.0.1 (``gonio bench serve``
        of a bench that is not a rate bench); ``ports``: TCP ports by role (0: a free one).
    budget : callable or None
        ``budget(**options)`` → the specification's own uncertainty annex, reproduced (an
        object with ``to_dict()`` and ``to_text()``).
    coverage : Coverage or None
        The settings of its coverage study (None: it has none).
    outputs : str
        The module that renders a result (the report side, imported by the pipeline only):
        ``write(result, out, *, truth, lab, lang, dcc)`` → {name: path},
        ``results_json(result)``, ``summary(result, lab)``; optionally ``demo(...)`` and
        ``warnings(result)``.
    measured_conditions : callable or None
        ``measured_conditions(readings_path)`` → ``{"temperature_c": (text, where)}``: the
        conditions the readings measured (a rate file's logged room temperature,
        :func:`gonio.formats.rate_readings.room_temperature_measured`), compared with the
        laboratory file where the readings' metadata are silent
        (:func:`gonio.pipeline.identity.check_identity`); None: nothing measured.
    room_temperature_keys : tuple of str
        The readings' metadata keys that state the room temperature, in order of preference,
        compared with the laboratory file's ``[environment] temperature_c``
        (:func:`gonio.pipeline.identity.contradictions`), recorded as the calibration's
        conditions by the records and stated as the environment's temperature by the
        certificate, the DCC and summary.txt where the laboratory file states none
        (:func:`gonio.report.header.room_temperature_keys`). A key a specification uses for another temperature is not
        among them (IEC 62047-20's ``room_temperature_c`` is its base temperature T_BASE, a
        chamber set point: not the room's).
    simulate_options, calibrate_options, budget_options, serve_options : frozenset
        The keywords the hooks ``simulate``, ``calibrate``, ``budget`` and ``serve`` (``gonio
        bench serve``) take beyond the common ones (``protocol`` and ``dcc`` among them where they apply); any other is
        refused naming the specification (:func:`gonio.pipeline.dispatch.refuse_options`).
    arguments : dict of str to str
        ``{command: "module:function"}``: the command-line options of the specification's
        own for the ``gonio`` commands of :data:`ARGUMENT_COMMANDS` (``calibrate``,
        ``simulate``, ``budget``, ``validate``, and the nested command ``"bench serve"``,
        named by its words as typed, whose options go to the ``serve`` hook),
        such as the optical draft's ``gonio
        calibrate --budget``. ``function(group)`` adds them with ``group.add_argument`` as
        argparse does; each option's ``dest`` is a keyword the command's hook takes
        (:meth:`accepted_options`), its default None (False for a flag: not given), and an
        option whose ``metavar`` is ``"FILE"`` names an input file (never replaced by an
        output). The command line imports the module only when it builds that command's
        parser, so it imports argparse-level modules only (as a ``commands`` module does);
        gonio's command line itself holds no specification's option. Empty: none.
    readings_format : str
        The ``# format:`` line its readings files carry, when that alone names it (a file
        without ``# spec:``); empty: none.
    readings_columns : callable or None
        () → the columns its readings file reads; any other column of a readings file's
        header (a stream's excepted) is stated as a flagged finding, ``unread-column``
        (:func:`gonio.pipeline.dispatch.unread_columns`), never kept silently. None: its
        reader refuses an unknown column itself.
    named_inputs : callable or None
        (readings path) → the other files the readings name as part of their data (inputs
        no output may replace; the manifest records their SHA-256, ``named_inputs``, and
        the records keep them with the readings, so that a result is computed again from
        what is stored).
    read_table_calibration : callable or None
        (path) → the rotary table's calibration read from a table-calibration file, every
        fault a GonioError in one line; what the records check a file with before they
        register it as a table's calibration. None: it reads none.
    certificate_content : str
        The module holding its certificate's content as data (its headings, groups, Chinese
        titles, ``NORM``, what its figures differ in); the shared renderers read it through
        :meth:`content`, never by guessing from a module's name. Empty: none.
    item_keys : tuple of str
        The keys of the items a result of it can hold: a laboratory file's
        ``[[specification_limits]]`` entry naming another item is refused before any work
        (:func:`gonio.pipeline.dispatch.load_lab_file`, :meth:`knows_item`). An entry may be
        a :mod:`fnmatch` pattern (``K_[xyz]_theta[1-4]``) where the names depend on the data
        (a model order chosen by a criterion); such an item absent from a result is still
        refused once calibrated (:func:`gonio.analysis.conformity.decide_items`). Empty: the
        items are checked once calibrated only.
    magnitude_extremes : tuple of str
        The keys of its items that are an extreme of magnitudes max_i |x_i| (the optical
        draft's E, 7.4): such an item takes a symmetric limit only, and a laboratory file's
        or an instrument record's other limit for it is refused before any work
        (:func:`gonio.formats.lab.check_magnitude_extremes`, called by
        :func:`gonio.pipeline.dispatch.load_lab_file` and the records' limits); conformity
        decides it as one (:func:`gonio.analysis.conformity.decide_items`). Each is one of
        :attr:`item_keys` where those are given. Empty: none.
    nonnegative_items : tuple of str
        The keys (or :mod:`fnmatch` patterns, as in :attr:`item_keys`) of its items that
        cannot be negative by their definition (a range, a dispersion, a noise level, a
        time): an upper limit below zero for one can never be met, so a laboratory file's or
        an instrument record's such limit is refused when it is read or stored
        (:func:`gonio.formats.lab.check_nonnegative_limits`, called by
        :func:`gonio.pipeline.dispatch.load_lab_file` and the records' limits), as conformity
        refuses one for an item its result marks non-negative
        (:func:`gonio.analysis.conformity.check_nonnegative_limit`). Each is one of
        :attr:`item_keys` where those are given. Empty: none declared (checked once
        calibrated only).
    commands : tuple of (str, str)
        The ``gonio`` sub-commands the specification adds: ``(name, "module:function")``
        pairs; ``function(subparsers)`` adds the parser ``name`` (argparse) and sets its
        ``func`` to ``run(args) -> int``, as gonio's own ``gonio/cli/cmd_*.py`` modules do.
        The module is imported only when the command line is built; it sits on the command
        line's layer (it may import ``gonio.cli.checks``).
    dcc_units : dict of str to str
        The D-SI form (``"\\ppm"``, ``"\\micro\\volt"``) of every unit its items state
        that gonio's DCC writers do not know (``"ppm"``); checked when the specification loads
        (a D-SI string is ``\\unit`` tokens, optionally with prefixes and ``\\tothe{n}``).
    simulated_files : tuple of str
        The names of the files its ``simulate`` writes into the output folder whatever
        happens (``("readings.csv", "truth.json")``): ``gonio simulate`` and ``gonio demo``
        refuse a folder holding a laboratory's own file of such a name before the virtual
        bench runs (:func:`gonio.atomic.output_set`'s ``writes``), not after the whole run
        at the swap. Empty: refused at the swap only.
    recalibration_interval_months : int or None
        The recalibration interval the specification's document itself recommends (the
        records' proposal shows it beside the one computed from the history); None: the
        document leaves it to the user.

    Every field is checked when the specification is built (:meth:`__post_init__`): a value
    of the wrong type is a :class:`GonioError` naming the specification and the field, and an
    unknown field (a misspelt hook) a ``TypeError`` that the registry reports the same way.
    """

    key: str
    title_en: str
    title_zh: str
    clause_doc: str
    default_protocol: str
    default_bench: str
    calibrate: Callable[..., Any]
    clauses: tuple[str, ...] = ()
    load_protocol: Callable[..., Any] | None = None
    screen: Callable[..., list] | None = None
    simulate: Callable[..., dict] | None = None
    truth: Callable[..., dict] | None = None
    run_trial: Callable[..., tuple] | None = None
    acquisition: Callable[..., Any] | None = None
    acquire: Callable[..., Any] | None = None
    serve: Callable[..., Any] | None = None
    budget: Callable[..., Any] | None = None
    coverage: Coverage | None = None
    outputs: str = ""
    simulate_options: frozenset = frozenset()
    calibrate_options: frozenset = frozenset()
    budget_options: frozenset = frozenset()
    serve_options: frozenset = frozenset()
    readings_format: str = ""
    readings_columns: Callable[[], tuple] | None = None
    named_inputs: Callable[..., list] | None = None
    read_table_calibration: Callable[..., Any] | None = None
    measured_conditions: Callable[..., dict] | None = None
    room_temperature_keys: tuple[str, ...] = ("temperature_c", "room_temperature_c")
    default_limits: tuple = ()
    certificate_content: str = ""
    commands: tuple[tuple[str, str], ...] = ()
    arguments: dict[str, str] = field(default_factory=dict)
    item_keys: tuple[str, ...] = ()
    magnitude_extremes: tuple[str, ...] = ()
    nonnegative_items: tuple[str, ...] = ()
    dcc_units: dict[str, str] = field(default_factory=dict)
    recalibration_interval_months: int | None = None
    simulated_files: tuple[str, ...] = ()

    def __post_init__(self):
        if not isinstance(self.key, str) or not _KEY.fullmatch(self.key):
            raise _field_error("Specification", "key", "lower-case letters, digits, '-', "
                               "'_' or '.'", self.key)
        where = f"specification {self.key!r}"
        for name in _STRING_FIELDS:
            if not isinstance(getattr(self, name), str):
                raise _field_error(where, name, "a str", getattr(self, name))
        for name in ("outputs", "certificate_content"):
            if getattr(self, name) and not _MODULE.fullmatch(getattr(self, name)):
                raise _field_error(where, name, "a module name", getattr(self, name))
        if not callable(self.calibrate):
            raise _field_error(where, "calibrate", "a callable", self.calibrate)
        for name in _HOOKS:
            _check_callable(self, where, name)
        if self.coverage is not None and not isinstance(self.coverage, Coverage):
            raise _field_error(where, "coverage", "a gonio.specs.Coverage or None",
                               self.coverage)
        if self.coverage is not None and self.coverage.reduced and not (
                self.default_protocol.endswith(".toml") or self.default_protocol in _builtin()):
            raise _field_error(where, "coverage.reduced", "empty unless default_protocol is "
                               "a TOML file (the study's programme is written over it)",
                               self.coverage.reduced)
        for name in ("simulate_options", "calibrate_options", "budget_options",
                     "serve_options"):
            _set_strings(self, where, name, frozenset)
        for name in ("clauses", "item_keys", "magnitude_extremes", "nonnegative_items",
                     "simulated_files"):
            _set_strings(self, where, name, tuple)
        for name in ("magnitude_extremes", "nonnegative_items"):
            unknown = [k for k in getattr(self, name) if not self.knows_item(k)]
            if unknown:
                raise _field_error(where, name, "keys of its items (item_keys)", unknown)
        self._check_tables(where)

    def _check_tables(self, where: str) -> None:
        limits = self.default_limits
        if not isinstance(limits, (tuple, list)) or not all(
                isinstance(d, dict) and isinstance(d.get("item"), str) for d in limits):
            raise _field_error(where, "default_limits", "a tuple of dicts each naming its "
                               "'item'", limits)
        object.__setattr__(self, "default_limits", tuple(limits))
        cmds = self.commands
        if not isinstance(cmds, (tuple, list)) or not all(
                isinstance(c, (tuple, list)) and len(c) == 2 and all(isinstance(x, str) for x in c)
                and _REF.fullmatch(c[1]) for c in cmds):
            raise _field_error(where, "commands", "a tuple of (name, 'module:function') pairs",
                               cmds)
        object.__setattr__(self, "commands", tuple(tuple(c) for c in cmds))
        args = self.arguments
        if not isinstance(args, dict) or not all(
                k in ARGUMENT_COMMANDS and isinstance(v, str) and _REF.fullmatch(v)
                for k, v in args.items()):
            raise _field_error(where, "arguments", "a dict {command (" + ", ".join(
                ARGUMENT_COMMANDS) + "): 'module:function'}", args)
        units = self.dcc_units
        if not isinstance(units, dict) or not all(isinstance(k, str) and k for k in units):
            raise _field_error(where, "dcc_units", "a dict {unit: D-SI unit}", units)
        for unit, dsi in units.items():
            if not isinstance(dsi, str) or not _DSI.fullmatch(dsi):
                raise _field_error(where, f"dcc_units[{unit!r}]", "a D-SI unit such as "
                                   "'\\ppm' or '\\milli\\volt\\second\\tothe{-1}'", dsi)
        months = self.recalibration_interval_months
        if months is not None and (isinstance(months, bool) or not isinstance(months, int)
                                   or months <= 0):
            raise _field_error(where, "recalibration_interval_months",
                               "a positive int or None", months)

    def accepted_options(self, command: str) -> frozenset:
        """The keywords the hook of ``gonio command`` takes beyond the common ones
        (:data:`ARGUMENT_COMMANDS`: ``calibrate_options``, ``simulate_options``,
        ``budget_options``, ``serve_options`` for ``bench serve``, the coverage study's
        ``options``).

        >>> sorted(get("ogam-draft").accepted_options("simulate"))
        ['stream', 'stream_format', 'table']
        """
        if command == "validate":
            return self.coverage.options if self.coverage is not None else frozenset()
        return getattr(self, ARGUMENT_COMMANDS[command])

    def knows_item(self, key) -> bool:
        """Whether ``key`` is one of :attr:`item_keys` or matches one of its patterns
        (:func:`fnmatch.fnmatchcase`: case-sensitive, ``[xyz]``, ``[1-4]``, ``*``). A
        specification without ``item_keys`` knows every key (checked once calibrated).

        >>> s = Specification(key="s", title_en="S", title_zh="S", clause_doc="",
        ...                   default_protocol="", default_bench="", calibrate=print,
        ...                   item_keys=("M_xx", "K_[xyz]_theta[1-4]"))
        >>> [s.knows_item(k) for k in ("M_xx", "K_y_theta2", "K_y_theta5", "m_xx", None)]
        [True, True, False, False, False]
        """
        if not self.item_keys:
            return True
        if not isinstance(key, str):
            return False
        return key in self.item_keys or any(fnmatchcase(key, k) for k in self.item_keys)

    def renderer(self):
        """The module named by ``outputs`` (imported on first use), checked: the functions of
        :data:`OUTPUTS_REQUIRED` callable, those of :data:`OUTPUTS_OPTIONAL` callable where
        defined (one GonioError naming the specification and the function)."""
        if not self.outputs:
            raise GonioError(f"specification {self.key!r} names no outputs module (it cannot "
                             "write results or a certificate)", key="--spec")
        mod = importlib.import_module(self.outputs)
        for name in OUTPUTS_REQUIRED + OUTPUTS_OPTIONAL:
            fn = getattr(mod, name, None)
            if (fn is None and name in OUTPUTS_REQUIRED) or (fn is not None and not callable(fn)):
                raise GonioError(f"specification {self.key!r}: its outputs module {self.outputs} "
                                 f"has no function {name}", key="--spec")
        needs = tuple(getattr(mod, "CONTENT_REQUIRED", ()))
        content = self.content() if needs and self.certificate_content else None
        missing = [n for n in needs if not hasattr(content, n)]
        if missing:
            raise GonioError(f"specification {self.key!r}: its certificate content "
                             f"({self.certificate_content or 'none named'}) defines no "
                             f"{', '.join(missing)}, which its outputs module {self.outputs} "
                             "needs", key="--spec")
        return mod

    def output_hook(self, name: str):
        """The outputs module's optional function ``name`` (:data:`OUTPUTS_OPTIONAL`:
        ``demo``, ``warnings``, ``item_titles``), or None where it defines none."""
        if name not in OUTPUTS_OPTIONAL:
            raise KeyError(f"{name!r} is no optional outputs function (OUTPUTS_OPTIONAL)")
        return getattr(self.renderer(), name, None)

    def content(self):
        """The module named by ``certificate_content`` (imported on first use), checked against
        :data:`CONTENT_FIELDS`: a value of the wrong shape, or an upper-case name close to one
        of them (``FIGURE_ITEM``: a typo that would silently drop a figure), is a GonioError
        naming the specification and the name."""
        if not self.certificate_content:
            raise GonioError(f"specification {self.key!r} names no certificate content "
                             "(certificate_content)", key="--spec")
        mod = importlib.import_module(self.certificate_content)
        if mod.__name__ not in _CHECKED_CONTENT:
            _check_content(self.key, mod)
            _CHECKED_CONTENT.add(mod.__name__)
        return mod

    def content_value(self, name: str):
        """The certificate content's ``name`` (one of :data:`CONTENT_FIELDS`), or its default
        when the module does not define it or the specification names no content module.

        >>> from gonio.specs import get
        >>> get("jjf1535-2015").content_value("U_CLAUSE")[0]
        'JJF 1535-2015 clause 8 k)'
        >>> get("ogam-draft").content_value("FIGURE_ITEMS")
        {}
        """
        return content_field(self.content() if self.certificate_content else None, name)


#: The figure roles a certificate content's ``FIGURE_ITEMS`` may name (each drawn by the
#: per-item renderer from the item named; docs/kit.md lists the data each reads).
FIGURE_ROLES = ("bias_temperature", "sf_temperature", "allan", "arw", "bias_instability",
                "bandwidth")

#: The ``outputs`` module that renders a per-item :class:`~gonio.result.model.Result`
#: (``gonio.kit.ITEM_RENDERER``): ``results.json``, ``summary.txt``, the tables, the
#: certificate (HTML, PDF, en/zh) with the figures its content's roles name, and the DCC
#: 3.3.0 XML of the result as the pipeline decided it. A specification whose ``calibrate``
#: returns a Result of Items sets
#: ``Specification(outputs=ITEM_RENDERER, certificate_content="pkg.certificate", …)``.
ITEM_RENDERER = "gonio.report.item_outputs"


def _strs(v, n=None) -> bool:
    return isinstance(v, tuple) and all(isinstance(x, str) for x in v) and (
        n is None or len(v) == n)


def _str_dict(v) -> bool:
    return isinstance(v, dict) and all(isinstance(k, str) and isinstance(x, str)
                                       for k, x in v.items())


def _groups(v) -> bool:
    return isinstance(v, tuple) and all(
        isinstance(g, tuple) and len(g) == 4 and isinstance(g[0], int) and _strs(g[1:3])
        and _strs(tuple(g[3])) for g in v)


#: What a certificate content module (``Specification.certificate_content``) may define for
#: gonio's shared renderers: name → (what it is, check of the value, default when absent).
#: A module may hold names of its own besides (its own renderer's), but none close to these.
CONTENT_FIELDS: dict[str, tuple[str, Callable[[Any], bool], Any]] = {
    "GROUPS": ("a tuple of (number, English heading, Chinese heading, item keys)", _groups, ()),
    "TITLES_ZH": ("a dict {item key: Chinese title}", _str_dict, {}),
    "HEADING": ("an (English, Chinese) pair: the results page's title",
                lambda v: _strs(v, 2), None),
    "U_CLAUSE": ("an (English, Chinese) pair: the clause saying how U is stated",
                 lambda v: _strs(v, 2), ("JCGM 100:2008", "JCGM 100:2008")),
    "NORM": ("a tuple of str: the norm as the certificate names it",
             lambda v: _strs(v) and len(v) > 0, None),
    "READINGS_ZH": ("a dict {clause prefix of a reading taken: its Chinese}", _str_dict, {}),
    "ITEM_CONDITIONS": ("a dict {item key: (English, Chinese) templates filled from the "
                        "item's details, or a function (details, lang) -> the sentence or "
                        "None}: what defines the item's measurand or how it was evaluated, "
                        "stated under the results table where the item was measured and its "
                        "details hold every field of the sentence",
                        lambda v: isinstance(v, dict) and all(
                            isinstance(k, str) and (_strs(t, 2) or callable(t))
                            for k, t in v.items()), {}),
    "PHRASES_ZH": ("a tuple of (English regular expression, Chinese) pairs",
                   lambda v: isinstance(v, tuple) and all(_strs(x, 2) for x in v), ()),
    "FIGURE_ITEMS": (f"a dict {{figure role ({', '.join(FIGURE_ROLES)}): item key}}",
                     lambda v: _str_dict(v) and set(v) <= set(FIGURE_ROLES), {}),
    "CW_CCW": ("a dict with 'item', 'cw', 'ccw', 'null_output_off', 'ylabel', 'title'",
               lambda v: isinstance(v, dict) and {"item", "cw", "ccw"} <= set(v), None),
    "MATRICES": ("a tuple of (name, rows of item keys): the DCC's matrices of item values",
                 lambda v: isinstance(v, tuple) and all(
                     isinstance(m, tuple) and len(m) == 2 and isinstance(m[0], str)
                     and all(_strs(r) for r in m[1]) for m in v), ()),
}

_CHECKED_CONTENT: set[str] = set()


def content_field(content, name: str):
    """``name`` (one of :data:`CONTENT_FIELDS`; another is a KeyError, a renderer's bug) of a
    certificate content module (checked by :meth:`Specification.content`), or its default
    where the module does not define it or ``content`` is None.

    >>> content_field(None, "PHRASES_ZH")
    ()
    """
    if name not in CONTENT_FIELDS:
        raise KeyError(f"{name!r} is no certificate content field (CONTENT_FIELDS)")
    return getattr(content, name, CONTENT_FIELDS[name][2])


def _check_content(key: str, mod) -> None:
    """Check a certificate content module against :data:`CONTENT_FIELDS` (one GonioError
    naming the specification and the name)."""
    import difflib

    where = f"specification {key!r}: certificate content {mod.__name__}"
    for name in [n for n in vars(mod) if n.isupper() and not n.startswith("_")]:
        if name in CONTENT_FIELDS:
            what, check, _ = CONTENT_FIELDS[name]
            if not check(getattr(mod, name)):
                raise _field_error(where, name, what, getattr(mod, name))
            continue
        close = difflib.get_close_matches(name, CONTENT_FIELDS, n=1, cutoff=0.85)
        if close:
            raise GonioError(f"{where}: {name} is not a content field; did you mean "
                             f"{close[0]}? (CONTENT_FIELDS)", key="--spec")


class lazy:
    """A hook given as ``"module:function"``, imported on its first call: the simulation side
    of a specification (``simulate``, ``truth``, ``run_trial``, ``study_bench``) imports the
    virtual bench, and loading ``SPEC`` must not (calibrating a laboratory's file never
    imports the simulator). Extra positional/keyword arguments given here are passed first.

    >>> f = lazy("math:hypot")
    >>> f(3.0, 4.0)
    5.0
    """

    def __init__(self, ref: str, *args, **kwargs):
        self.ref, self.args, self.kwargs = ref, args, kwargs

    def __call__(self, *args, **kwargs):
        mod, _, attr = self.ref.partition(":")
        fn = getattr(importlib.import_module(mod), attr)
        return fn(*self.args, *args, **{**self.kwargs, **kwargs})

    def __repr__(self) -> str:
        return f"lazy({self.ref!r})"


def default_limits(key: str) -> list[dict]:
    """The default tolerances (``SPEC.default_limits``) of the specification ``key``, as
    ``[[specification_limits]]`` entries (copies); none for a key no longer registered.

    >>> default_limits("ogam-draft")           # the draft gives no tolerance of its items
    []
    """
    try:
        spec = get(key)
    except GonioError:
        return []
    return [dict(d) for d in spec.default_limits]


def decide_conformity(result, lab: dict | None):
    """Conformity of every item the laboratory file ``lab`` limits, or the specification's
    own tolerances (:func:`default_limits`) limit, decided once, in the result's items
    (:func:`gonio.analysis.conformity.decide_result`), before anything is written: every
    output renders these decisions and none makes one. The pipeline's step
    (:func:`gonio.pipeline.dispatch.decide_conformity`); a specification's own ``demo``
    calls it as the pipeline would. Returns ``result``."""
    from gonio.analysis.conformity import DEFAULT_LIMITS_ORIGIN, decide_result

    decide_result(result, lab, default_limits(result.spec_key), DEFAULT_LIMITS_ORIGIN,
                  magnitude_extremes=magnitude_extremes(result.spec_key))
    return result


def nonnegative_items(key: str) -> tuple[str, ...]:
    """The items (keys or patterns) the specification ``key`` declares cannot be negative
    (``SPEC.nonnegative_items``); none for a key no longer registered.

    >>> nonnegative_items("ogam-draft")[:2]
    ('scale_factor_nonlinearity', 'zero_stability')
    """
    try:
        return get(key).nonnegative_items
    except GonioError:
        return ()


def magnitude_extremes(key: str) -> tuple[str, ...]:
    """The items the specification ``key`` declares extremes of magnitudes
    (``SPEC.magnitude_extremes``); none for a key no longer registered.

    >>> magnitude_extremes("ogam-draft")
    ('angle_deviation',)
    """
    try:
        return get(key).magnitude_extremes
    except GonioError:
        return ()


def _entry_points() -> dict[str, str]:
    """``{name: "module:attr"}`` of the installed ``gonio.specs`` entry points, with gonio's
    own from :data:`BUILT_IN` where gonio itself is not installed."""
    # imported here: importlib.metadata (and the email package it loads) costs every
    # command's start ~30 ms, and gonio's own commands never read the entry points
    from importlib.metadata import entry_points

    found = {ep.name: ep.value for ep in entry_points(group=ENTRY_POINT_GROUP)}
    return {**{k: v for k, v in BUILT_IN.items() if k not in found}, **found}


def _load(name: str, ref: str) -> Specification:
    """The :class:`Specification` the entry point ``name = ref`` names, checked: anything that
    goes wrong (an import error, an exception while its module runs, a field of the wrong type
    or a misspelt one, not a Specification, another key, a module it names that does not
    exist) is one :class:`GonioError` naming the entry point."""
    mod, _, attr = ref.partition(":")
    head = f"the specification entry point {name} = {ref!r}"
    try:
        obj = importlib.import_module(mod)
        for part in (attr or "SPEC").split("."):
            obj = getattr(obj, part)
    except GonioError as exc:              # a field refused by Specification.__post_init__
        raise GonioError(f"{head} is invalid: {exc.message}", key="--spec") from None
    except TypeError as exc:               # an unknown (misspelt) field, a missing one
        raise GonioError(f"{head} is invalid: {exc}{_did_you_mean(str(exc))}",
                         key="--spec") from None
    except Exception as exc:               # the plug-in's own bug: its key fails, not gonio
        raise GonioError(f"{head} cannot be loaded ({type(exc).__name__}: {exc})",
                         key="--spec") from None
    if not isinstance(obj, Specification):
        raise GonioError(f"{head} is not a gonio.specs.Specification", key="--spec")
    if obj.key != name:
        raise GonioError(f"the specification entry point {name!r} loads key {obj.key!r} "
                         "(the entry point's name must be the key)", key="--spec")
    for field_name, module in _named_modules(obj):
        if not _module_exists(module):
            raise GonioError(f"{head} is invalid: field {field_name} names module {module!r}, "
                             "which does not exist", key="--spec")
    refs = [(f"commands[{name!r}]", ref) for name, ref in obj.commands]
    refs += [(f"arguments[{cmd!r}]", ref) for cmd, ref in obj.arguments.items()]
    for field_name, ref in refs:
        module, _, function = ref.partition(":")
        if not _defines(module, function):
            raise GonioError(f"{head} is invalid: field {field_name} names {ref!r}, and "
                             f"{module} defines no {function}", key="--spec")
    return obj


def _defines(module: str, name: str) -> bool:
    """Whether the source of ``module`` binds ``name`` at its top level (read, not imported:
    a command module sits on the command line's layer). True where there is no source to
    read (the import then decides)."""
    from pathlib import Path

    origin = importlib.util.find_spec(module).origin
    if not origin or not origin.endswith(".py"):
        return True
    st = Path(origin).stat()
    return name in _bound_names(origin, st.st_mtime_ns, st.st_size)


@functools.lru_cache(maxsize=64)
def _bound_names(origin: str, mtime_ns: int, size: int) -> frozenset:
    """The names a module's source file binds at its top level (parsed once per version of
    the file: a specification's command module is named by several of its fields)."""
    import ast
    from pathlib import Path

    tree = ast.parse(Path(origin).read_text(encoding="utf-8"))
    bound = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            bound.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            bound |= {(a.asname or a.name).split(".")[0] for a in node.names}
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            bound |= {t.id for t in targets if isinstance(t, ast.Name)}
    return frozenset(bound)


def _named_modules(spec: Specification) -> list[tuple[str, str]]:
    """(field, module) of every module a specification names by string."""
    out = [(n, getattr(spec, n)) for n in ("outputs", "certificate_content") if getattr(spec, n)]
    out += [(f"arguments[{cmd!r}]", ref.partition(":")[0]) for cmd, ref in spec.arguments.items()]
    return out + [(f"commands[{name!r}]", ref.partition(":")[0]) for name, ref in spec.commands]


def _module_exists(module: str) -> bool:
    """Whether ``module`` can be found (:func:`importlib.util.find_spec`; its parent packages
    are imported, the module itself is not)."""
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def _did_you_mean(message: str) -> str:
    """`` (did you mean 'calibrate'?)`` for a TypeError naming an unknown keyword that is
    close to a field of :class:`Specification` or :class:`Coverage`."""
    import difflib
    from dataclasses import fields

    m = re.search(r"unexpected keyword argument '(\w+)'", message)
    if not m:
        return ""
    names = [f.name for cls in (Specification, Coverage) for f in fields(cls)]
    close = difflib.get_close_matches(m.group(1), names, n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def available() -> dict[str, Specification]:
    """Every registered specification that loads, by key (entry-point group ``gonio.specs``).
    One that cannot be loaded is left out with a warning naming it (``gonio --help``, the
    other specifications and the web keep working); :func:`get` of its key raises the error.
    """
    import warnings

    out = {}
    for key, ref in sorted(_entry_points().items()):
        try:
            out[key] = _load(key, ref)
        except GonioError as exc:
            warnings.warn(f"{exc.message}; specification {key!r} is not available",
                          stacklevel=2)
    return out


def get(key: str) -> Specification:
    """The specification with this key; an unknown key is a GonioError listing the known ones."""
    eps = _entry_points()
    if key not in eps:
        raise GonioError(f"unknown specification {key!r} (known: {', '.join(sorted(eps))})",
                         key="spec")
    return _load(key, eps[key])


def command_arguments(command: str) -> list[tuple[Specification, Callable[..., None]]]:
    """``(specification, add)`` of every registered specification with its own options for
    ``gonio command`` (``Specification.arguments``; ``command`` one of
    :data:`ARGUMENT_COMMANDS`), in key order: ``add(group)`` adds them to an argparse
    argument group. A specification, or a module, that cannot be loaded adds none, with a
    warning naming it (its own ``--spec`` still fails with the error).

    >>> [s.key for s, _ in command_arguments("simulate") if s.key == "ogam-draft"]
    ['ogam-draft']
    """
    import warnings

    if command not in ARGUMENT_COMMANDS:
        raise KeyError(f"{command!r} takes no options of a specification (ARGUMENT_COMMANDS)")
    out = []
    for key, ref in sorted(_entry_points().items()):
        try:
            spec = _load(key, ref)
        except GonioError as exc:
            warnings.warn(f"{exc.message}; its {command} options are not available",
                          stacklevel=2)
            continue
        if command not in spec.arguments:
            continue
        mod, _, attr = spec.arguments[command].partition(":")
        try:
            out.append((spec, getattr(importlib.import_module(mod), attr)))
        except Exception as exc:     # the plug-in's own bug costs only its own options
            warnings.warn(f"the {command} options of specification {key!r} "
                          f"({spec.arguments[command]!r}) cannot be loaded "
                          f"({type(exc).__name__}: {exc})", stacklevel=2)
    return out


def commands() -> list[tuple[str, Callable[..., None]]]:
    """``(name, add_parser)`` of every sub-command a registered specification contributes
    (``Specification.commands``), in name order. A specification (or a command module) that
    cannot be loaded adds none, and a name a second specification adds again is not added
    again: each is a warning naming it, so that a broken plug-in never takes the other
    commands down (its own ``--spec`` still fails with the error).

    >>> [name for name, _ in commands() if name == "align"]
    ['align']
    """
    import warnings

    found: dict[str, tuple[str, Callable[..., None]]] = {}
    for key, ref in sorted(_entry_points().items()):
        try:
            spec = _load(key, ref)
        except GonioError as exc:
            warnings.warn(f"{exc.message}; its commands are not available", stacklevel=2)
            continue
        for name, fn_ref in spec.commands:
            if name in found:
                warnings.warn(f"the command {name!r} of specification {key!r} is not available: "
                              f"specification {found[name][0]!r} adds one by that name",
                              stacklevel=2)
                continue
            mod, _, attr = fn_ref.partition(":")
            try:
                found[name] = (key, getattr(importlib.import_module(mod), attr))
            except (ImportError, AttributeError) as exc:
                warnings.warn(f"the command {name!r} of specification {key!r} ({fn_ref!r}) "
                              f"cannot be loaded ({type(exc).__name__}: {exc})", stacklevel=2)
    return [(name, fn) for name, (_, fn) in sorted(found.items())]
