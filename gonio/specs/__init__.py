"""Calibration specifications as plug-ins: the :class:`Specification` protocol and its registry.

A specification (a standard, a draft, a laboratory's in-house procedure) is one package that
exposes ``SPEC``, a :class:`Specification`: its key (the ``--spec`` value), titles and
clauses, its default protocol and bench, and the hooks gonio calls — ``calibrate``
(readings → result), ``screen`` (readings → findings), ``simulate`` and ``truth`` (the
virtual bench), ``budget`` (its own uncertainty annex), ``coverage`` (the settings of its
coverage study), ``outputs`` (the module that renders a result: results.json, summary,
tables, certificate, DCC) and ``commands`` (the ``gonio`` sub-commands it adds, such as the
triad's ``align``). docs/writing-a-specification.md builds one from scratch.

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

import importlib
from dataclasses import dataclass, field
from fnmatch import fnmatchcase
from graphlib import CycleError, TopologicalSorter
from importlib.metadata import entry_points
from typing import Any, Callable

from gonio.errors import GonioError

__all__ = ["Coverage", "Specification", "available", "commands", "get", "item_order", "lazy",
           "ENTRY_POINT_GROUP", "BUILT_IN", "DEFAULT_KEY"]

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
    simulate_options, calibrate_options, budget_options : frozenset
        The command-line options of ``gonio simulate|calibrate|budget`` the hooks take
        beyond the common ones (``protocol`` and ``dcc`` among them where they apply); any
        other is refused naming the specification.
    readings_format : str
        The ``# format:`` line its readings files carry, when that alone names it (a file
        without ``# spec:``); empty: none.
    named_inputs : callable or None
        (readings path) → the other files the readings name as part of their data (inputs
        no output may replace).
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
    commands : tuple of (str, str)
        The ``gonio`` sub-commands the specification adds: ``(name, "module:function")``
        pairs; ``function(subparsers)`` adds the parser ``name`` (argparse) and sets its
        ``func`` to ``run(args) -> int``, as gonio's own ``gonio/cli/cmd_*.py`` modules do.
        The module is imported only when the command line is built; it sits on the command
        line's layer (it may import ``gonio.cli.checks``).
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
    budget: Callable[..., Any] | None = None
    coverage: Coverage | None = None
    outputs: str = ""
    simulate_options: frozenset = frozenset()
    calibrate_options: frozenset = frozenset()
    budget_options: frozenset = frozenset()
    readings_format: str = ""
    named_inputs: Callable[..., list] | None = None
    default_limits: tuple = ()
    certificate_content: str = ""
    commands: tuple[tuple[str, str], ...] = ()
    item_keys: tuple[str, ...] = ()

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
        """The module named by ``outputs`` (imported on first use)."""
        if not self.outputs:
            raise GonioError(f"specification {self.key!r} names no outputs module (it cannot "
                             "write results or a certificate)", key="--spec")
        return importlib.import_module(self.outputs)

    def content(self):
        """The module named by ``certificate_content`` (imported on first use)."""
        if not self.certificate_content:
            raise GonioError(f"specification {self.key!r} names no certificate content "
                             "(certificate_content)", key="--spec")
        return importlib.import_module(self.certificate_content)


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


def item_order(keys, needs) -> list[str]:
    """The items ``keys`` (in the specification's order) ordered so that each comes after the
    items it needs (``needs``: {key: keys it needs}, e.g. the JJF scale factor before the
    items that divide by it): :class:`graphlib.TopologicalSorter`, ties kept in the declared
    order, so that the order is written down, never implied. A cycle or a need that is no
    item is a GonioError.

    >>> item_order(["bias", "scale_factor", "noise"], {"bias": ["scale_factor"]})
    ['scale_factor', 'noise', 'bias']
    """
    keys = list(keys)
    unknown = sorted({n for k in keys for n in needs.get(k, ()) if n not in keys})
    if unknown:
        raise GonioError(f"an item needs {', '.join(unknown)}, which is no item")
    ts = TopologicalSorter({k: tuple(needs.get(k, ())) for k in keys})
    try:
        ts.prepare()
    except CycleError as exc:
        raise GonioError(f"the items' needs form a cycle: {' -> '.join(exc.args[1])}") from None
    out: list[str] = []
    while ts.is_active():
        ready = sorted(ts.get_ready(), key=keys.index)
        out += ready
        ts.done(*ready)
    return out


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


def _entry_points() -> dict[str, str]:
    """``{name: "module:attr"}`` of the installed ``gonio.specs`` entry points, with gonio's
    own from :data:`BUILT_IN` where gonio itself is not installed."""
    found = {ep.name: ep.value for ep in entry_points(group=ENTRY_POINT_GROUP)}
    return {**{k: v for k, v in BUILT_IN.items() if k not in found}, **found}


def _load(name: str, ref: str) -> Specification:
    mod, _, attr = ref.partition(":")
    try:
        obj = importlib.import_module(mod)
        for part in (attr or "SPEC").split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError) as exc:
        raise GonioError(f"the specification entry point {name} = {ref!r} cannot be loaded "
                         f"({type(exc).__name__}: {exc})", key="--spec") from None
    if not isinstance(obj, Specification):
        raise GonioError(f"the specification entry point {name} = {ref!r} is not a "
                         "gonio.specs.Specification", key="--spec")
    if obj.key != name:
        raise GonioError(f"the specification entry point {name!r} loads key {obj.key!r} "
                         "(the entry point's name must be the key)", key="--spec")
    return obj


def available() -> dict[str, Specification]:
    """Every registered specification, by key (entry-point group ``gonio.specs``)."""
    return {k: _load(k, ref) for k, ref in sorted(_entry_points().items())}


def get(key: str) -> Specification:
    """The specification with this key; an unknown key is a GonioError listing the known ones."""
    eps = _entry_points()
    if key not in eps:
        raise GonioError(f"unknown specification {key!r} (known: {', '.join(sorted(eps))})",
                         key="spec")
    return _load(key, eps[key])


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
