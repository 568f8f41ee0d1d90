"""The one pipeline of every specification: simulate, calibrate, demo, budget and validate,
found through the registry (:func:`gonio.specs.get`) and run through the specification's
hooks (:class:`gonio.specs.Specification`). Nothing here names a specification.

Every function returns data (paths, results); the command line (``gonio simulate|calibrate|
demo|budget|validate --spec KEY``) is a thin layer over them.
"""

from __future__ import annotations

import json
from pathlib import Path

from gonio.atomic import output_set, sha256_file
from gonio.errors import GonioError, check_input_file, read_utf8
from gonio.formats.metadata import header_lines
from gonio.formats.provenance import readings_provenance
from gonio.pipeline.identity import check_identity
from gonio.specs import Specification, decide_conformity, get
from gonio.result.findings import UNREAD_CODE, Finding

__all__ = ["spec_of", "refuse_options", "readings_spec", "simulate", "load_lab_file",
           "screen_and_calibrate", "decide_conformity", "mark_provenance", "named_files",
           "calibrate", "demo", "budget"]

#: Options every ``calibrate`` hook takes (the others are in ``SPEC.calibrate_options``).
COMMON_CALIBRATE = frozenset({"monte_carlo_trials"})


def spec_of(spec_key: str | None, readings=None) -> Specification:
    """The specification named by ``spec_key``, else by the readings' ``# spec:`` metadata
    (or the format line a specification claims); a file naming none is an error."""
    key = spec_key or (readings_spec(readings) if readings is not None else None)
    if key is None:
        raise GonioError("the readings name no specification (metadata '# spec: …' or a "
                         "specification's '# format:'); give --spec", file=readings)
    return get(key)


def refuse_options(spec: Specification, given: dict, accepted: frozenset, command: str,
                   flags: dict | None = None) -> dict:
    """``given`` ({option: value}, None or False meaning not given) less the options not
    given; an option the specification's hook does not take is a GonioError naming it: by its
    command-line form in ``flags`` ({keyword: "--option"}, the command line's), else
    ``--keyword`` with dashes.

    >>> s = Specification(key="s", title_en="S", title_zh="S", clause_doc="",
    ...                   default_protocol="", default_bench="", calibrate=print)
    >>> refuse_options(s, {"monte_carlo_trials": 9, "seed": None}, frozenset(), "budget",
    ...                {"monte_carlo_trials": "--monte-carlo"})
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: --monte-carlo does not apply to 'gonio budget --spec s'
    """
    out = {k: v for k, v in given.items() if v not in (None, False)}
    bad = sorted(k for k in out if k not in accepted)
    if bad:
        names = ", ".join((flags or {}).get(k) or "--" + k.replace("_", "-") for k in bad)
        raise GonioError(f"{names} {'does' if len(bad) == 1 else 'do'} not apply to "
                         f"'gonio {command} --spec {spec.key}'")
    return out


def readings_spec(path: str | Path) -> str | None:
    """The ``# spec: …`` metadata of a readings file (None when absent), or the key of the
    specification whose ``readings_format`` the file's ``# format:`` line names.

    Only the metadata lines at the top are read; a Parquet stream's key-value metadata is
    looked up instead.
    """
    check_input_file(path, "readings file")     # a FIFO or /dev/zero is refused before reading
    if Path(path).suffix.lower() == ".parquet":
        from gonio.formats.streams import StreamFile
        return StreamFile(path).metadata.get("spec")
    try:
        open(path, "rb").close()
    except OSError:
        read_utf8(path, "readings file")       # the one-line error naming the file
        raise
    for key, value in header_lines(path):
        if key == "spec":
            return value
        if key == "format":
            from gonio.specs import available
            for spec in available().values():
                if spec.readings_format and spec.readings_format == value:
                    return spec.key
    return None


def simulate(spec_key: str, out: str | Path, *, bench: str | None = None,
             protocol: str | None = None, seed: int = 0, inputs=(), force: bool = False,
             **options) -> dict[str, Path]:
    """Run the specification's programme on its virtual bench; the files a laboratory would
    record and ``truth.json`` are written into ``out`` as one set (staged, swapped in)."""
    spec = get(spec_key)
    if spec.simulate is None:
        raise GonioError(f"{spec.key} has no virtual bench (its SPEC.simulate is None)",
                         key="--spec")
    opts = refuse_options(spec, options, spec.simulate_options, "simulate")
    with output_set(out, inputs=inputs, force=force, writes=spec.simulated_files):
        return spec.simulate(Path(out), protocol=protocol or spec.default_protocol,
                             bench=bench or spec.default_bench, seed=seed, **opts)


def load_lab_file(lab, spec: Specification | None = None):
    """The laboratory file as a dict (validated before any work), or the dict given. With
    ``spec``, a ``[[specification_limits]]`` entry naming an item the specification does not
    have (``spec.item_keys``, when it knows them before the data) is a GonioError naming the
    file, the entry and the item: refused before anything is computed, not after
    (:meth:`gonio.specs.Specification.knows_item`: exact keys or patterns); so is a limit
    that is not symmetric for an item the specification declares an extreme of magnitudes
    (``spec.magnitude_extremes``, :func:`gonio.formats.lab.check_magnitude_extremes`), and an
    upper limit below zero for an item it declares cannot be negative
    (``spec.nonnegative_items``, :func:`gonio.formats.lab.check_nonnegative_limits`)."""
    path = lab if isinstance(lab, (str, Path)) else None
    if path is not None:
        from gonio.formats.lab import load_lab
        lab = load_lab(path)
    if spec is not None and spec.item_keys and lab:
        for i, lim in enumerate(lab.get("specification_limits") or []):
            if not spec.knows_item(lim.get("item")):
                raise GonioError(f"{spec.key} has no item {lim.get('item')!r} (its items: "
                                 f"{', '.join(spec.item_keys)})", file=path,
                                 key=f"specification_limits[{i}].item")
    if spec is not None and spec.magnitude_extremes and lab:
        from gonio.formats.lab import check_magnitude_extremes
        check_magnitude_extremes(lab.get("specification_limits"), spec.magnitude_extremes,
                                 file=path)
    if spec is not None and spec.nonnegative_items and lab:
        from gonio.formats.lab import check_nonnegative_limits
        check_nonnegative_limits(lab.get("specification_limits"), spec.nonnegative_items,
                                 file=path)
    return lab


def screen_and_calibrate(spec: Specification, readings, protocol=None, *,
                         monte_carlo_trials: int = 0, **options):
    """The specification's screening (``SPEC.screen(readings, protocol, **options)``: what it
    refuses, sets aside or flags), then its calibration with those findings
    (``SPEC.calibrate(..., findings=…)``), which applies them and states every one in the
    result. A specification without a screening hook is calibrated as it is."""
    if spec.screen is None:
        return spec.calibrate(readings, protocol, monte_carlo_trials=monte_carlo_trials,
                              **options)
    findings = spec.screen(readings, protocol, **options)
    return spec.calibrate(readings, protocol, monte_carlo_trials=monte_carlo_trials,
                          findings=findings, **options)


def unread_columns(spec: Specification, readings) -> list[Finding]:
    """A flagged finding (:data:`UNREAD_CODE`) for each column of a readings file's header that
    ``spec`` does not read (``spec.readings_columns``): its cells are carried but no item uses
    them, and the certificate says so (a column misspelt past the readers' near-miss check,
    e.g. ``temp_c``, is never kept silently). A stream (Parquet, or a header without
    ``test``) and a specification without ``readings_columns`` give []."""
    from gonio.formats.streams import first_header
    if spec.readings_columns is None or Path(readings).suffix.lower() == ".parquet":
        return []
    header = first_header(readings)
    if "test" not in header:
        return []
    known = tuple(spec.readings_columns())
    return [Finding(UNREAD_CODE, f"column {name!r} is not one {spec.key} reads: its cells are "
                    "kept with the readings but no item uses them (a misspelt column? the "
                    f"columns read: {', '.join(known)})", "flagged",
                    file=Path(readings).name, column=name,
                    rule="every column of the header is one the specification reads")
            for name in header if name not in known and name != "line"]


def named_files(spec, readings) -> list[Path]:
    """The files the readings name as part of their data (``spec.named_inputs``: a second
    readings file, a static record) that exist; [] for a specification that names none. A
    named file that is missing is the specification's own refusal."""
    if spec.named_inputs is None:
        return []
    return [Path(p) for p in spec.named_inputs(readings) if Path(p).is_file()]


#: The calibrate options whose file carries the instrument's own data (thermal readings of
#: the instrument, its measured tilt): such a file is read for the calibration as a file the readings
#: name is, so it goes through the same identity and provenance checks
#: (:func:`instrument_files`). A rotary table's calibration (``table_calibration``) is the
#: table's, checked against the laboratory's register instead.
INSTRUMENT_FILE_OPTIONS = ("thermal", "tilt")


def instrument_files(spec, readings, opts: dict) -> list[Path]:
    """Every file read for a calibration that carries the instrument's own data: the files
    the readings name (:func:`named_files`) and those an option gives
    (:data:`INSTRUMENT_FILE_OPTIONS`: ``--thermal FILE``, ``--tilt FILE``) that exist (a
    missing one is the option's own refusal). Each goes through :func:`check_identity` and
    :func:`mark_provenance` alike, whichever way it came. A JSON result given so that does
    not show the readings it was computed from, or was changed after gonio wrote it, is
    refused (:func:`gonio.formats.provenance.shown_source`)."""
    from gonio.formats.provenance import json_metadata, shown_source
    given = [Path(v) for k, v in sorted(opts.items()) if k in INSTRUMENT_FILE_OPTIONS
             and isinstance(v, (str, Path)) and str(v) and Path(v).is_file()]
    # a JSON file that does not parse is its reader's to refuse, in its own words
    given = [p for p in given if p.suffix.lower() != ".json" or json_metadata(p) is not None]
    for p in given:          # a JSON result shows the readings it was computed from, or is refused
        if p.suffix.lower() == ".json":
            shown_source(p)
    named = named_files(spec, readings)
    return named + [p for p in given if p.resolve() not in {n.resolve() for n in named}]


def mark_provenance(result, readings, named=(), prov: dict | None = None) -> None:
    """Set ``result.provenance`` from the readings' own metadata and that of every file they
    name as part of their data (``named``; :func:`gonio.formats.provenance.readings_provenance`):
    readings from the virtual bench are marked virtual on every output whatever the
    laboratory file says, also where only a named file is the bench's; nothing turns it
    off. ``prov``: that provenance, read already (before the work)."""
    result.provenance = readings_provenance(readings, named) if prov is None else prov


def calibrate(readings: str | Path, out: str | Path, *, spec_key: str | None = None,
              protocol: str | None = None, lab=None, lang: str = "en", truth: dict | None = None,
              dcc: bool = False, monte_carlo_trials: int = 0, inputs=(), force: bool = False,
              record: dict | None = None, lab_file: str | Path | None = None,
              before_swap=None, **options):
    """Calibrate a readings file with its specification (``spec_key`` or the file's
    ``# spec:``): results.json, summary.txt, tables and the certificate (HTML, PDF; with
    ``dcc`` the DCC XML) in ``out``, written as one set. ``record``: the records' registered
    instrument's texts the readings and the laboratory file must not contradict
    (``calibrate --record``; :func:`gonio.pipeline.identity.record_contradictions`).
    ``lab_file``: the laboratory file's path where ``lab`` is its dict (the folder its
    ``[table_calibration] file`` is named from: a specification that takes a table calibration
    gets the file :func:`gonio.pipeline.equipment.lab_table_calibration` checked, before the
    work). ``before_swap(stage)``: called with the finished set before it replaces ``out``
    (:func:`gonio.atomic.output_set`; ``calibrate --record`` records it there, so a set the
    records refuse is never written). Returns (result, paths)."""
    spec = spec_of(spec_key, readings)
    opts = refuse_options(spec, {"protocol": protocol, "dcc": dcc, **options},
                          spec.calibrate_options, "calibrate")
    lab_d = load_lab_file(lab, spec)
    from gonio.formats.lab import check_no_issue_record
    check_no_issue_record(lab_d, lab if isinstance(lab, (str, Path)) else lab_file)
    renderer = spec.renderer()
    dcc = opts.pop("dcc", False)
    proto = opts.pop("protocol", None)         # None: the file's, else the specification's
    named = instrument_files(spec, readings, opts)     # named in the readings or by an option
    identity = check_identity(readings, lab_d, lab_file=lab if isinstance(lab, (str, Path))
                              else None, record=record, named=named,
                              measured=spec.measured_conditions,   # refused here, before the work
                              temperature_keys=spec.room_temperature_keys)
    if "table_calibration" in spec.calibrate_options and (lab_d or {}).get("table_calibration"):
        from gonio.formats.provenance import readings_metadata
        from gonio.pipeline.equipment import lab_table_calibration
        opts["table_calibration"] = lab_table_calibration(   # checked before the work
            lab_d, lab if isinstance(lab, (str, Path)) else lab_file,
            readings_metadata(readings),
            opts.get("table_calibration"))
        inputs = [*inputs, opts["table_calibration"]]          # recorded in the manifest
    gyro = ((lab_d or {}).get("instrument") or {}).get("gyro_type")
    if gyro and "gyro_type" in spec.calibrate_options:
        opts.setdefault("gyro_type", gyro)     # the instrument's type (the records' registered)
    # read before the work: the metadata and the bench's watermark in the values
    prov = readings_provenance(readings, named)
    result = screen_and_calibrate(spec, readings, proto, monte_carlo_trials=monte_carlo_trials,
                                  **opts)
    mark_provenance(result, readings, named, prov)
    result.findings = (list(result.findings) + identity       # proceeding: stated as findings
                       + unread_columns(spec, readings))
    decide_conformity(result, lab_d)
    with output_set(out, inputs=inputs, force=force,
                    source_sha256=getattr(result, "source_sha256", None),
                    extra=manifest_record(spec, readings, opts, inputs, monte_carlo_trials),
                    before_swap=before_swap):
        paths = renderer.write(result, Path(out), truth=truth, lab=lab_d, lang=lang, dcc=dcc)
    return result, paths


def option_files(opts: dict, inputs) -> dict | None:
    """The manifest's record of the specification options that named an input file the run
    read (``calibrate --table-calibration FILE``): {"option_files": {option: {"file", "sha256"}}},
    or None where none did."""
    named = {str(i) for i in inputs if i is not None}
    files = {k: {"file": Path(v).name, "sha256": sha256_file(v)} for k, v in sorted(opts.items())
             if isinstance(v, (str, Path)) and str(v) in named and Path(v).is_file()}
    return {"option_files": files} if files else None


def demo(spec_key: str, out: str | Path, *, bench: str | None = None, seed: int = 0,
         lab=None, lang: str = "en", dcc: bool = True, force: bool = False, inputs=(),
         on_stage=None):
    """Simulate the whole programme and calibrate it: readings, truth, results, certificate
    and (``dcc``) its DCC XML, the whole set staged and swapped into ``out`` together (a
    run that fails at any point leaves the previous set as it was). A specification's
    renderer may supply its own ``demo`` (same arguments); else simulate → calibrate →
    write. Returns (result, {name: path})."""
    spec = get(spec_key)
    renderer = spec.renderer()
    lab_d = load_lab_file(lab, spec)            # validate inputs before simulating
    from gonio.formats.lab import check_no_issue_record
    check_no_issue_record(lab_d, lab if isinstance(lab, (str, Path)) else None)
    ins = [x for x in (*inputs, lab, bench) if isinstance(x, (str, Path)) and str(x)]
    compare = demo_identity(spec, lab_d, lab)
    own_demo = spec.output_hook("demo")
    if own_demo is not None:
        import inspect
        more = {"identity": compare} if "identity" in inspect.signature(own_demo).parameters \
            else {}
        return own_demo(out, bench=bench or spec.default_bench, seed=seed, lab=lab_d,
                        lang=lang, dcc=dcc, force=force, inputs=ins, on_stage=on_stage, **more)
    if spec.simulate is None:
        raise GonioError(f"{spec.key} has no virtual bench (its SPEC.simulate is None)",
                         key="--spec")
    say = on_stage or (lambda message: None)
    with output_set(out, inputs=ins, force=force, writes=spec.simulated_files) as stage:
        say("demo: simulating on the virtual bench")
        sim = spec.simulate(Path(out), protocol=spec.default_protocol,
                            bench=bench or spec.default_bench, seed=seed)
        truth = json.loads((stage / sim["truth"].name).read_text(encoding="utf-8"))
        say("demo: calibrating")
        result = screen_and_calibrate(spec, stage / sim["readings"].name, None)
        mark_provenance(result, stage / sim["readings"].name)
        result.findings = list(result.findings) + compare(stage / sim["readings"].name)
        decide_conformity(result, lab_d)
        say("demo: writing the results and the certificate")
        paths = renderer.write(result, Path(out), truth=truth, lab=lab_d, lang=lang,
                               dcc=dcc and "dcc" in spec.calibrate_options)
    return result, {**sim, **paths}


def demo_identity(spec, lab_d: dict | None, lab=None):
    """The demo's comparison of its readings (and the files they name) with the laboratory
    file, as :func:`calibrate` compares them (identity and conditions,
    :func:`gonio.pipeline.identity.check_identity`): a callable taking the readings' path
    and giving the flagged findings. A contradiction is never refused, always stated (as
    ``[identity] on_mismatch = "proceed"``): the demo's readings are the virtual bench's,
    made for the example, and its certificate is marked virtual; a laboratory file naming
    another instrument then shows the contradiction on every output instead of lending the
    bench's numbers its instrument silently. Without a laboratory file: no findings."""
    if not lab_d:
        return lambda readings: []
    stated = {**lab_d, "identity": {**(lab_d.get("identity") or {}), "on_mismatch": "proceed"}}

    def compare(readings) -> list:
        return check_identity(readings, stated,
                              lab_file=lab if isinstance(lab, (str, Path)) else None,
                              named=named_files(spec, readings),
                              measured=spec.measured_conditions,
                              temperature_keys=spec.room_temperature_keys)
    return compare


def budget(spec_key: str, **options):
    """The specification's own annex budget, reproduced (``SPEC.budget(**options)``)."""
    spec = get(spec_key)
    if spec.budget is None:
        raise GonioError(f"{spec.key} has no annex budget", key="--spec")
    return spec.budget(**refuse_options(spec, options, spec.budget_options, "budget"))


def manifest_record(spec: Specification, readings, opts: dict, inputs,
                    monte_carlo_trials: int = 0) -> dict | None:
    """What the manifest records of how a calibration was computed, besides the files it
    wrote: the option files (:func:`option_files`), the other options given
    (``calibrate_options``: ``--monte-carlo N`` where N > 0, ``--budget``, ``--robust``, the
    instrument's ``gyro_type``; an option naming a file is among the option files, never
    here), and the SHA-256 of each file the readings name as part of their data
    (``named_inputs``, by the name they give it: ``Specification.named_inputs``), so that the records can compute the result again from the same inputs
    and options (:mod:`gonio.records.importer`). None where there is nothing to record."""
    out = dict(option_files(opts, inputs) or {})
    files = set(out.get("option_files") or {})
    plain = {k: v for k, v in sorted(opts.items()) if k not in files
             and isinstance(v, (bool, int, float, str))
             and not (isinstance(v, str) and Path(v).is_file())}
    if monte_carlo_trials:
        plain["monte_carlo_trials"] = int(monte_carlo_trials)
    if plain:
        out["calibrate_options"] = plain
    named = named_input_digests(spec, readings)
    if named:
        out["named_inputs"] = named
    return out or None


def named_input_digests(spec: Specification, readings) -> dict:
    """{name as the readings give it, relative to their folder: SHA-256} of the files the
    readings name as part of their data (``spec.named_inputs``) that exist; {} where none."""
    if spec.named_inputs is None:
        return {}
    base = Path(readings).parent
    out = {}
    for p in spec.named_inputs(readings):
        p = Path(p)
        if p.is_file():
            try:
                name = p.relative_to(base).as_posix()
            except ValueError:
                name = str(p)
            out[name] = sha256_file(p)
    return out
