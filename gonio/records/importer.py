"""Command-line work into the records: an output folder of ``gonio calibrate`` or
``gonio demo`` (results.json, certificate, the readings) becomes a computed calibration,
ready for review, of the instrument its readings name.

The readings file must be the one results.json was computed from (its SHA-256 is checked
against ``source.sha256``): the records never hold a result without its readings. The
folder's files must match its ``gonio-manifest.json`` (:func:`check_manifest`), and the
result is computed again from the stored readings, protocol, laboratory file and table
calibration as a records calibration is (:func:`recomputed`): an imported results.json that
differs from what its readings give is refused, nothing recorded. The
instrument is found by (manufacturer, model, serial) from the readings' metadata, else
registered under the customer given (default ``(imported)``). The folder is only read.
"""

from __future__ import annotations

import datetime as _dt
import getpass
import json
import tempfile
from pathlib import Path

from sqlalchemy import func, select

from gonio.errors import GonioError
from gonio.formats.metadata import identity_text
from gonio.records import blobs, services
from gonio.records.models import (Blob, Calibration, CalibrationFile, CalibrationStandard,
                                  Customer, Instrument, Standard, User)
from gonio.records.results import result_items

#: readings file names looked for in a folder when none is given
READINGS_NAMES = ("readings.csv", "readings.parquet", "stream.csv", "stream.parquet")


def _readings_in(folder: Path, sha: str, given: Path | None) -> Path:
    cands = [given] if given else [folder / n for n in READINGS_NAMES]
    for p in cands:
        if p is not None and p.is_file() and blobs_sha(p) == sha:
            return p
    raise GonioError("no readings file matching results.json's source SHA-256 "
                     f"({sha[:12]}…); give it with --readings", file=folder)


def blobs_sha(path: Path) -> str:
    from gonio.atomic import sha256_file
    return sha256_file(path)


def _identity(meta: dict) -> tuple[str, str, str]:
    """(manufacturer, model, serial) the readings' metadata name an instrument by (the model,
    else the instrument's description; an unknown serial said so)."""
    def field(k):
        return services.text(str(meta.get(k, "") or ""), k)

    return (field("manufacturer"), field("model") or field("instrument"),
            field("serial") or "(unknown serial)")


def folded(text: str) -> str:
    """A name as compared for identity: the one identity normaliser,
    :func:`gonio.formats.metadata.identity_text` (case, Unicode compatibility forms and
    spacing folded), as the laboratory file is compared with the readings
    (:mod:`gonio.pipeline.identity`).

    >>> folded("  RLG-0001 ") == folded("rlg-0001") == folded("ＲＬＧ－０００１")
    True
    >>> folded("Gyro  Works")
    'gyro works'
    """
    return identity_text(text)


def registered_instrument(s, meta: dict) -> Instrument | None:
    """The registered instrument the readings' metadata ``meta`` name, or None: the one of
    the same manufacturer, model and serial, else the one they name with case and spacing
    folded (:func:`folded`: ``rlg-0001`` is the registered ``RLG-0001``, whose gyro type and
    customer then hold, never a second registration of one instrument)."""
    manufacturer, model, serial = _identity(meta)
    same = s.scalar(select(Instrument).where(Instrument.manufacturer == manufacturer,
                                             Instrument.model == model,
                                             Instrument.serial == serial))
    if same is not None:
        return same
    want = (folded(manufacturer), folded(model), folded(serial))
    found = [i for i in s.scalars(select(Instrument).where(
        func.lower(Instrument.serial) == serial.lower()).order_by(Instrument.id))
        if (folded(i.manufacturer), folded(i.model), folded(i.serial)) == want]
    if not found:
        found = [i for i in s.scalars(select(Instrument).order_by(Instrument.id))
                 if (folded(i.manufacturer), folded(i.model), folded(i.serial)) == want]
    return found[0] if found else None


def _instrument(s, meta: dict, spec_key: str, customer: str, actor) -> Instrument:
    def field(k):
        return services.text(str(meta.get(k, "") or ""), k)

    inst = registered_instrument(s, meta)
    if inst is not None:
        return inst
    manufacturer, model, serial = _identity(meta)
    cust = s.scalar(select(Customer).where(Customer.name == customer))
    if cust is None:
        cust = Customer(name=customer, address="")
        s.add(cust)
        s.flush()
        services.audit(s, actor, "create", "customer", cust.id, None, services.state(cust))
    inst = Instrument(customer_id=cust.id, kind=field("instrument"), manufacturer=manufacturer,
                      gyro_type=services.gyro_type_value(field("gyro_type")),
                      model=model, serial=serial, spec_key=spec_key, limits_json="[]")
    s.add(inst)
    s.flush()
    services.audit(s, actor, "create", "instrument", inst.id, None, services.state(inst))
    return inst


def _protocol_file(results: dict, given: str | Path | None, folder: Path) -> Path | None:
    """The protocol file the folder's calibration used: ``given`` (a file or built-in name),
    else what results.json names (``settings.protocol``, the readings' ``# protocol:``),
    checked against ``settings.protocol_sha256`` when results.json has it; None when
    results.json names none (the specification's default protocol was used)."""
    from gonio.resources import resolve
    settings = results.get("settings") or {}
    meta = results.get("metadata") or {}
    name = given or settings.get("protocol") or meta.get("protocol") or results.get("protocol")
    if not name:
        return None
    try:
        path = resolve(str(name))
    except GonioError:
        cand = folder / str(name)
        if not cand.is_file():
            raise GonioError(f"results.json was computed with protocol {str(name)!r}, which is "
                             "neither a built-in protocol nor a file here; give the file with "
                             "--protocol", file=folder, key="protocol") from None
        path = cand
    want = settings.get("protocol_sha256")
    if want and blobs_sha(path) != want:
        raise GonioError(f"protocol {str(path)!r} is not the one results.json was computed "
                         f"with (SHA-256 {str(want)[:12]}…)", file=folder, key="protocol")
    return path


def _lab_file(store, lab, spec_key: str) -> tuple[str | None, int, dict, list]:
    """(sha256, size) of the laboratory file stored, or (None, 0): none given, or one that
    gives no limits (it decides nothing the records keep); the calibration's columns it
    gives: the environment (:func:`lab_environment`), the place and its DCC category
    (``[certificate] place``, ``location``); and its ``[[standards]]`` (dicts)."""
    if lab is None:
        return None, 0, {}, []
    from gonio.pipeline.dispatch import load_lab_file
    from gonio.specs import get
    details = load_lab_file(lab, get(spec_key))
    cert = details.get("certificate") or {}
    env = dict(lab_environment(details), place=services.text(cert.get("place"), "place"),
               location=services.location_value(cert.get("location")))
    stds = list(details.get("standards") or [])
    if not details.get("specification_limits"):
        return None, 0, env, stds
    return (*blobs.put_file(store.blob_root, Path(lab)), env, stds)


def _table_calibration(store, lab, spec_key: str, rd: Path, results: dict, res_path: Path,
                       given: str | Path | None = None) -> tuple[str | None, int, str]:
    """(sha256, size, file name) of the table calibration the folder's run used, stored; (None,
    0, "") where results.json records none (then none may be given). The file is the laboratory
    file's ``[table_calibration]``, checked as the command line checks it
    (:func:`gonio.pipeline.equipment.lab_table_calibration`: its SHA-256, its validity on the
    readings' and the certificate's dates; ``given`` must then be the same content), else
    ``given`` (``gonio db import --table-calibration FILE``), else a copy in the folder under the
    name the run recorded (the manifest's ``option_files``, results.json's ``source``). Its
    SHA-256 must be the one results.json records (``details.table_calibration.sha256``: the run
    used it); a result whose table calibration is not supplied is refused (one line): the
    records never hold a result without the table calibration it was computed with."""
    from gonio.formats.lab import load_lab
    from gonio.formats.provenance import readings_metadata
    from gonio.pipeline.equipment import lab_table_calibration
    from gonio.specs import get
    used = services.recorded_table_calibrations(results)
    takes = "table_calibration" in get(spec_key).calibrate_options
    lab_d = load_lab(lab) if lab is not None else {}
    if given is not None and not takes:
        raise GonioError(f"{spec_key} takes no table calibration", file=given,
                         key="table_calibration")
    if takes and lab_d.get("table_calibration"):
        path = Path(lab_table_calibration(lab_d, lab, readings_metadata(rd), given))
        sha = lab_d["table_calibration"]["sha256"]
        if used != {sha}:
            raise GonioError(f"the laboratory file's table calibration {path.name} (SHA-256 "
                             f"{sha[:16]}…) is not the one results.json was computed with "
                             f"({', '.join(sorted(u[:16] + '…' for u in used)) or 'none'})",
                             file=res_path, key="table_calibration")
        return (*blobs.put_file(store.blob_root, path), path.name)
    if not used:
        if given is not None:
            raise GonioError(f"--table-calibration {Path(given).name}: results.json records no "
                             "table calibration (the run used none); leave the option out",
                             file=res_path, key="table_calibration")
        return None, 0, ""
    if len(used) > 1:
        raise GonioError("results.json records more than one table calibration ("
                         + ", ".join(u[:16] + "…" for u in sorted(used)) + ")",
                         file=res_path, key="table_calibration")
    (want,) = used
    names = _recorded_table_names(results, res_path.parent)
    if given is not None:
        path = Path(given)
        if not path.is_file():
            raise GonioError("no such table calibration file", file=path,
                             key="table_calibration")
        got = blobs_sha(path)
        if got != want:
            raise GonioError(f"the table calibration {path.name} has SHA-256 {got[:16]}…, not "
                             f"the {want[:16]}… results.json was computed with"
                             + (f" ({names[0]})" if names else ""), file=path,
                             key="table_calibration.sha256")
    else:
        here = [res_path.parent / n for n in names]
        path = next((p for p in here if p.is_file() and blobs_sha(p) == want), None)
        if path is None:
            raise GonioError(f"results.json was computed with the table calibration "
                             f"{names[0] if names else '(unnamed)'} (SHA-256 {want[:16]}…), "
                             "which is not in the folder: give it with --table-calibration "
                             "FILE (or the --lab file naming it)", file=res_path,
                             key="table_calibration")
    return (*blobs.put_file(store.blob_root, path), path.name)


def _recorded_table_names(results: dict, folder: Path) -> list[str]:
    """The file names the run recorded for its table calibration: the manifest's
    ``option_files.table_calibration.file`` (``gonio calibrate --table-calibration FILE``),
    then each item's ``details.table_calibration.source``; plain names only, in that order."""
    from gonio.atomic import MANIFEST
    names = []
    try:
        man = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
        names.append(str(((man.get("option_files") or {}).get("table_calibration") or {})
                         .get("file") or ""))
    except (OSError, ValueError, RecursionError, AttributeError):
        pass
    items = (results or {}).get("items") or {}
    for it in (items.values() if isinstance(items, dict) else items):
        d = ((it.get("details") or {}).get("table_calibration") or {}) \
            if isinstance(it, dict) else {}
        names.append(str(d.get("source") or "") if isinstance(d, dict) else "")
    out = []
    for n in names:
        if n and n == Path(n).name and n not in (".", "..") and n not in out:
            out.append(n)
    return out


def lab_standard_ids(s, standards: list, day: _dt.date, lab) -> list[int]:
    """The registered standards a laboratory file's ``[[standards]]`` name, matched by
    ``identifier``, each valid on the calibration date ``day``
    (:func:`gonio.records.services.unusable_standard`); a standard of the file without an
    identifier, not registered, retired or past its due date is a GonioError naming it
    (one line; the import records nothing)."""
    ids = []
    for i, std in enumerate(standards, 1):
        ident = str(std.get("identifier") or "").strip()
        name = str(std.get("name") or "")[:80]
        if not ident:
            raise GonioError(f"[[standards]] {i} ({name!r}) has no identifier to match a "
                             "registered standard", file=lab, key="standards")
        st = s.scalar(select(Standard).where(Standard.identifier == ident))
        if st is None:
            raise GonioError(f"[[standards]] {i}: {ident[:80]!r} is not a registered standard "
                             "(register it in the records first, or leave it out)", file=lab,
                             key="standards")
        why = services.unusable_standard(st, day)
        if why:
            raise GonioError(f"[[standards]] {i}: {why}", file=lab, key="standards")
        ids.append(st.id)
    return ids


def _check_lab_standards(store, standards: list, day: _dt.date | None, lab) -> None:
    """:func:`lab_standard_ids` before an import's recomputation (checked again when it is
    recorded): a laboratory file's standard that is not registered or not valid on ``day``
    (None: the import day) refuses the import before any work."""
    if standards:
        with store.session() as s:
            lab_standard_ids(s, standards, day or import_day(store), lab)


def lab_environment(details: dict) -> dict:
    """The environment a laboratory file's ``[environment]`` gives, as a calibration's
    columns: the numbers with the digits the file writes them with
    (:func:`services.environment_columns`) and the source stated (``environment_from``:
    ``"lab file"``; ``"readings"`` where the file says ``source = "readings"``), or
    {} when it gives not both values (review needs both: nothing half is recorded).

    >>> from gonio.formats.lab import WrittenNumber
    >>> lab_environment({"environment": {"temperature_c": WrittenNumber(20.0, "20.0"),
    ...                                  "humidity_pct": 41.0, "source": "entered"}})
    ... # doctest: +NORMALIZE_WHITESPACE
    {'temperature_c': 20.0, 'humidity_pct': 41.0, 'temperature_text': '20.0',
     'humidity_text': '41', 'environment_from': 'lab file'}
    >>> lab_environment({"environment": {"temperature_c": 20.5}}), lab_environment({})
    ({}, {})
    """
    env = details.get("environment") or {}
    temp, hum = env.get("temperature_c"), env.get("humidity_pct")
    if temp is None or hum is None:
        return {}
    return {**services.environment_columns(temp, hum),
            "environment_from": "readings" if env.get("source") == "readings" else "lab file"}


def _check_identity(rd: Path, lab, spec_key: str, results: dict, record: dict | None,
                    res_path: Path, option_paths=(), meta: dict | None = None) -> dict:
    """The readings ``rd`` (and the files they name as part of their data, and those an
    option gave, ``option_paths``: ``--thermal FILE``, ``--tilt FILE``) against the
    laboratory file ``lab`` and the registered instrument's ``record`` as ``gonio calibrate``
    compares them
    (:func:`gonio.pipeline.identity.check_identity`): a contradiction is refused (one line)
    unless the laboratory file proceeds, and then results.json must state it (a folder computed
    without this laboratory file, or before the instrument's record said otherwise, states
    none: calibrate it again). Returns the identity the certificate states where the
    laboratory file proceeds past a contradiction of the readings' serial, model or
    manufacturer, and where the readings' metadata ``meta`` state none of them (a serial the
    readings do not give is the laboratory file's, as the certificate states it):
    ``{metadata key: the laboratory file's value}`` (:func:`lab_identity`), else {}."""
    from gonio.pipeline.dispatch import load_lab_file, named_files
    from gonio.pipeline.identity import MISMATCH_CODE, check_identity
    from gonio.specs import get
    named = named_files(get(spec_key), rd)
    named += [Path(p) for p in option_paths if Path(p).resolve() not in
              {n.resolve() for n in named}]      # --thermal FILE, --tilt FILE: the same checks
    if lab is None and record is None and not named:
        return {}
    details = load_lab_file(lab, get(spec_key)) if lab is not None else None
    found = check_identity(rd, details, lab_file=lab, record=record, named=named,
                           measured=get(spec_key).measured_conditions,
                           temperature_keys=get(spec_key).room_temperature_keys)
    stated = {str(f.get("message")) for f in results.get("findings") or []
              if isinstance(f, dict) and f.get("code") == MISMATCH_CODE}
    missing = [f.message for f in found if f.message not in stated]
    if missing:
        raise GonioError(f"{missing[0].split(';')[0]}: results.json does not state this "
                         "contradiction (computed without this laboratory file or record); "
                         "calibrate the readings again with it", file=res_path, key="identity")
    def says(*keys):
        return any(str((meta or {}).get(k) or "").strip() for k in keys)
    # the fields the records name the instrument by (:func:`_identity`: the model, else the
    # instrument's description) that the readings leave blank
    silent = {what for what, keys in (("serial", ("serial",)),
                                      ("model", ("model", "instrument")),
                                      ("manufacturer", ("manufacturer",))) if not says(*keys)}
    return lab_identity(details, {str(f.subject) for f in found} | silent)


#: The contradicted identity fields (a finding's subject) whose laboratory file value the
#: certificate states where the laboratory proceeds: its ``[instrument]`` key.
LAB_IDENTITY = {"serial": "serial", "model": "model", "manufacturer": "manufacturer"}


def lab_identity(details: dict | None, contradicted: set[str]) -> dict:
    """The laboratory file's ``[instrument]`` values of the ``contradicted`` identity fields
    (:data:`LAB_IDENTITY`; those the readings leave blank too), as the readings' metadata
    keys: the instrument the records
    register the calibration under, so that the issued certificate names what the command
    line's certificate and its finding ("the certificate's identity and conditions are the
    laboratory file's") name.

    >>> lab_identity({"instrument": {"serial": "RLG-0002", "model": "M"}}, {"serial"})
    {'serial': 'RLG-0002'}
    >>> lab_identity(None, {"serial"}), lab_identity({"instrument": {}}, {"temperature"})
    ({}, {})
    """
    inst = (details or {}).get("instrument") or {}
    return {key: str(inst[key]) for what, key in LAB_IDENTITY.items()
            if what in contradicted and str(inst.get(key) or "").strip()}


def _keep_table_calibration(s, cal: Calibration, actor, sha: str, name: str,
                            res_path: Path) -> None:
    """The table calibration ``sha`` an imported run used, kept as the calibration's
    :data:`~gonio.records.services.TABLE_CALIBRATION` with its audit event; the laboratory's
    register must hold that file for a table among the calibration's standards, in force on
    the calibration's date, and that entry is recorded as the one used
    (:func:`gonio.records.services.table_calibration_for`: else — a file the register does not
    hold included — a one-line GonioError naming results.json, and nothing is recorded)."""
    from gonio.specs import get

    tables = s.scalars(select(CalibrationStandard.standard_id).where(
        CalibrationStandard.calibration_id == cal.id)).all()
    try:
        _, entry = services.table_calibration_for(s, get(cal.spec_key), tables,
                                                  cal.performed_on, sha)
    except GonioError as exc:
        raise GonioError(exc.message, file=res_path, key=exc.key) from None
    cal.table_calibration_id = entry.id if entry is not None else None
    s.add(CalibrationFile(calibration_id=cal.id, name=services.TABLE_CALIBRATION, sha256=sha))
    services.audit(s, actor, "table-calibration", "calibration", cal.id, None,
                   {"sha256": sha, "name": services.text(name, "table calibration file name",
                                                         max_len=255)}
                   | ({"register_id": entry.id} if entry is not None else {}))


def check_manifest(folder: Path) -> dict:
    """The folder's files against its ``gonio-manifest.json`` (the SHA-256 of each file gonio
    wrote), returned: a listed file missing or changed since, or a results.json the manifest
    does not list, is a GonioError naming it. A folder without a manifest is not checked here
    (the recomputation still is, :func:`recomputed`): {}; a manifest that cannot be read is
    refused."""
    from gonio.atomic import MANIFEST
    path = folder / MANIFEST
    if not path.exists():
        return {}
    try:
        man = json.loads(path.read_text(encoding="utf-8"))
        files = man["files"]
        if not isinstance(files, dict):
            raise TypeError
    except (OSError, ValueError, RecursionError, KeyError, TypeError):
        raise GonioError("unreadable manifest (no JSON object with its files)",
                         file=path) from None
    if "results.json" not in files:
        raise GonioError("the manifest does not list results.json: not one gonio output set",
                         file=path)
    for name, sha in sorted(files.items()):
        p = folder / str(name)
        if not p.is_file():
            raise GonioError(f"{str(name)[:80]} is listed in the manifest but missing",
                             file=path)
        if blobs_sha(p) != sha:
            raise GonioError(f"{str(name)[:80]} was changed after gonio wrote it (its SHA-256 "
                             "is not the manifest's)", file=folder / str(name))
    return man


def first_difference(a, b, where: str = "") -> str | None:
    """The first place two JSON documents differ, as a dotted path with both values (short),
    or None where they are equal (NaN equal to NaN, as JSON writes them).

    >>> first_difference({"items": {"K": {"value": 1.5}}}, {"items": {"K": {"value": 1.25}}})
    'items.K.value: 1.5 here, 1.25 recomputed'
    >>> first_difference([1, {"a": None}], [1, {"a": None}]) is None
    True
    """
    def dump(v):
        return json.dumps(v, sort_keys=True, ensure_ascii=False)

    if dump(a) == dump(b):
        return None
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b), key=str):
            if k not in a or k not in b:
                return (f"{where + '.' if where else ''}{k}: "
                        + ("absent here" if k not in a else "absent when recomputed"))
            got = first_difference(a[k], b[k], f"{where + '.' if where else ''}{k}")
            if got:
                return got
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b)):
            got = first_difference(x, y, f"{where}[{i}]")
            if got:
                return got
    return f"{where or '(the whole file)'}: {dump(a)[:40]} here, {dump(b)[:40]} recomputed"


#: The options a folder's manifest may record (``calibrate_options``,
#: :func:`gonio.pipeline.dispatch.manifest_record`) that its recomputation is given; any other
#: is refused (the records would compute something else).
RECOMPUTED_OPTIONS = ("monte_carlo_trials", "budget", "robust", "gyro_type")


def recorded_options(man: dict, spec, res_path: Path) -> dict:
    """The options the folder's calibration was computed with, as its manifest records them
    (``calibrate_options``; {} where it records none: the default options), each one
    :data:`RECOMPUTED_OPTIONS` takes and the specification takes, with a plain value (the
    Monte Carlo trials within ``GONIO_MAX_MONTE_CARLO``). An option not known here is
    refused in one line: nothing recorded. The options that named a file (the manifest's
    ``option_files``: ``--tilt FILE``, ``--thermal FILE``) are :func:`option_inputs`'."""
    from gonio.limits import check
    from gonio.pipeline.dispatch import COMMON_CALIBRATE
    opts = man.get("calibrate_options") or {}
    if not isinstance(opts, dict):
        raise GonioError("the manifest's calibrate_options is not a JSON object",
                         file=res_path.parent / "gonio-manifest.json", key="calibrate_options")
    takes = set(spec.calibrate_options) | set(COMMON_CALIBRATE)
    out = {}
    for k, v in sorted(opts.items()):
        ok = k in RECOMPUTED_OPTIONS and k in takes and (
            isinstance(v, str) if k in ("budget", "gyro_type") else
            isinstance(v, bool) if k == "robust" else
            isinstance(v, int) and not isinstance(v, bool) and v >= 0)
        if not ok:
            raise GonioError(f"the manifest records the option {str(k)[:40]!r} = "
                             f"{json.dumps(v)[:40]}, which a calibration cannot be computed "
                             f"again with ({spec.key} takes "
                             f"{', '.join(sorted(takes & set(RECOMPUTED_OPTIONS)))})",
                             file=res_path.parent / "gonio-manifest.json",
                             key="calibrate_options")
        out[k] = v
    if "monte_carlo_trials" in out:
        check("GONIO_MAX_MONTE_CARLO", out["monte_carlo_trials"], "calibrate_options."
              "monte_carlo_trials", unit="trials")
    return out


def option_inputs(spec, man: dict, res_path: Path, rd: Path,
                  given: dict | None = None) -> list[tuple[str, str, Path]]:
    """The files the folder's calibration was given by an option (the manifest's
    ``option_files`` but the table calibration, :func:`_table_calibration`'s: ``--tilt FILE``,
    ``--thermal FILE``), as (option, the file name the run read it under, path), so that the
    records keep each with the calibration and its recomputation reads the same bytes under
    the same name. Each is ``given[option]`` (``calibrate --record``'s own, ``gonio db import
    --option-file OPTION=FILE``), else a file of that name in the folder, else beside the
    readings ``rd``; its SHA-256 must be the manifest's. An option the specification does not
    take, a file not found or one with other bytes is refused in one line naming it: nothing
    recorded."""
    files = man.get("option_files") or {}
    if not isinstance(files, dict):
        raise GonioError("the manifest's option_files is not a JSON object",
                         file=res_path.parent / "gonio-manifest.json", key="option_files")
    given = {k: v for k, v in (given or {}).items() if v}
    out = []
    for option, rec in sorted(files.items()):
        if option == "table_calibration":
            continue
        flag = f"--{str(option)[:40].replace('_', '-')}"
        name = str(rec.get("file") or "") if isinstance(rec, dict) else ""
        want = str(rec.get("sha256") or "") if isinstance(rec, dict) else ""
        if option not in spec.calibrate_options or option in RECOMPUTED_OPTIONS or \
                option in ("protocol", "dcc") or name != Path(name).name or \
                name in ("", ".", ".."):
            raise GonioError(f"the manifest records {flag} {name[:80]!r}, which a "
                             f"calibration by {spec.key} cannot be computed again with",
                             file=res_path.parent / "gonio-manifest.json", key="option_files")
        if len(services.option_file_name(option, name)) > 64:
            raise GonioError(f"{flag} {name[:80]!r}: a file name longer than "
                             f"{64 - len(services.option_file_name(option, ''))} characters; "
                             "rename it and calibrate again", file=res_path, key=option)
        path = Path(given[option]) if option in given else next(
            (p for p in (res_path.parent / name, rd.parent / name) if p.is_file()), None)
        if path is None or not path.is_file():
            raise GonioError(f"results.json was computed with {flag} {name} (SHA-256 "
                             f"{want[:16]}…), which is not here: the records keep every file "
                             f"the calibration read; give it with --option-file "
                             f"{option}=FILE (or put it beside the readings)", file=res_path,
                             key=option)
        got = blobs_sha(path)
        if got != want:
            raise GonioError(f"{path.name} has SHA-256 {got[:16]}…, not the {want[:16]}… the "
                             f"run read as {flag} {name}: not the file results.json was "
                             "computed with", file=path, key=option)
        out.append((str(option), name, path))
    unused = sorted(set(given) - {o for o, _, _ in out} - {"table_calibration"})
    if unused:
        raise GonioError(f"--option-file {unused[0]}=…: results.json was computed without "
                         f"--{unused[0].replace('_', '-')} FILE; leave it out", file=res_path,
                         key=unused[0])
    return out


def named_inputs(spec, rd: Path, man: dict, res_path: Path) -> list[tuple[str, Path]]:
    """The files the readings ``rd`` name as part of their data (``spec.named_inputs``: a
    triad's ``# thermal_readings:``, the optical ``# static_record:``), as (name relative to
    the readings' folder, path): each must lie in the readings' folder (or below it), exist,
    and have the SHA-256 the manifest records for it (``named_inputs``, or ``files`` where
    the readings are in the folder); else a GonioError in one line, nothing recorded. The
    records keep them with the readings (:data:`gonio.records.services.INPUT_PREFIX`): the
    result is computed again from them, on import and later."""
    if spec.named_inputs is None:
        return []
    base = rd.parent.resolve()
    listed = dict(man.get("files") or {}) if rd.parent.resolve() == res_path.parent.resolve() \
        else {}
    listed.update(man.get("named_inputs") or {})
    out = []
    for p in spec.named_inputs(rd):
        p = Path(p)
        try:
            name = p.resolve().relative_to(base).as_posix()
        except ValueError:
            raise GonioError(f"the readings name {str(p)[:80]!r} as part of their data, outside "
                             "their folder: the records keep a named file beside the readings "
                             "only; put it there and name it relatively", file=rd) from None
        if len(services.INPUT_PREFIX + name) > 64:
            raise GonioError(f"the readings name {name[:80]!r}: a name longer than "
                             f"{64 - len(services.INPUT_PREFIX)} characters", file=rd)
        if not p.is_file():
            raise GonioError(f"{name[:80]}, which the readings name as part of their data, is "
                             "missing beside them: the result cannot be computed again; "
                             "nothing recorded", file=rd)
        want = listed.get(name)
        if want and blobs_sha(p) != want:
            raise GonioError(f"{name[:80]} is not the file the run read (its SHA-256 is not "
                             "the manifest's)", file=p)
        out.append((name, p))
    return out


def recomputed(store, spec_key: str, rd_name: str, rsha: str, proto, psha: str | None,
               lab, tsha: str | None, tname: str, gyro_type: str | None, work: Path,
               inputs: list[tuple[str, str]] = (), options: dict | None = None,
               option_files: list[tuple[str, str, str]] = ()) -> Path:
    """The folder's result computed again into ``work``/out (returned) from the stored
    readings (blob ``rsha``, under the name ``rd_name`` the run read it by) and the files
    they name (``inputs``: (name, blob), written beside them under those names), protocol
    (the built-in name, else the stored file under its name), laboratory file and table
    calibration (blob ``tsha`` under the name ``tname`` the run recorded), with the
    ``options`` the folder's manifest records (:func:`recorded_options`), the files options
    named (``option_files``: (option, name, blob), each written under the name the run read it
    by, :func:`option_inputs`) and the registered
    instrument's ``gyro_type`` where the run had it (``gonio calibrate --record``) and
    neither those options nor the laboratory file state one, through the records' one call
    of the pipeline (:func:`gonio.records.compute.calibrate_folder`)."""
    from gonio.formats.lab import naming_lab_file
    from gonio.pipeline.dispatch import load_lab_file
    from gonio.records.compute import calibrate_folder
    from gonio.specs import get
    src = work / "in"
    src.mkdir()
    readings = src / rd_name
    readings.symlink_to(blobs.blob_path(store.blob_root, rsha).resolve())
    for name, sha in inputs:
        target = src / name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(blobs.get_bytes(store.blob_root, sha))
    from gonio.resources import protocols_dir
    protocol = None
    if proto is not None:
        protocol = str(proto)
        if psha is not None and Path(proto).resolve().parent != protocols_dir().resolve():
            (work / "protocol").mkdir()   # a built-in protocol is named as the run named it
            protocol = str(work / "protocol" / Path(proto).name)
            Path(protocol).write_bytes(blobs.get_bytes(store.blob_root, psha))
    table = None
    if tsha is not None:
        (work / "table").mkdir()
        table = work / "table" / (tname or services.TABLE_CALIBRATION)
        table.write_bytes(blobs.get_bytes(store.blob_root, tsha))
    spec = get(spec_key)
    lab_d = load_lab_file(lab, spec) if lab is not None else None
    options = dict(options or {})
    for option, name, sha in option_files:         # --tilt FILE, --thermal FILE, stored
        target = work / "option" / option / name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(blobs.get_bytes(store.blob_root, sha))
        options[option] = str(target)
    if gyro_type and not ((lab_d or {}).get("instrument") or {}).get("gyro_type"):
        options.setdefault("gyro_type", gyro_type)     # calibrate --record's registered type
    with naming_lab_file(lab):
        calibrate_folder(readings, work / "out", spec_key=spec_key, protocol=protocol,
                         lab=lab, table_calibration=table if not (
                             lab_d or {}).get("table_calibration") else None,
                         options=options,
                         record={"gyro_type": gyro_type} if gyro_type else None)
    return work / "out"


def check_recomputed(results: dict, out: Path, res_path: Path) -> None:
    """The imported results.json against the one recomputed into ``out`` (the protocol
    file's path, ``settings.protocol``, taken as the run named it where the SHA-256 of its
    content, ``settings.protocol_sha256``, is the same)
    (:func:`recomputed`): any difference is refused, naming the first (an edited number, or
    a folder computed with other options, inputs or another gonio version: calibrate it
    again with this gonio). Equal, the folder's results.json replaces the recomputed one in
    ``out`` (the same values; the protocol named as the run named it)."""
    again = json.loads((out / "results.json").read_text(encoding="utf-8"))
    mine, theirs = again.get("settings"), results.get("settings")
    if isinstance(mine, dict) and isinstance(theirs, dict) and "protocol" in theirs and \
            mine.get("protocol_sha256") and \
            mine.get("protocol_sha256") == theirs.get("protocol_sha256"):
        # a protocol file is named by the path the run was given (resources.
        # protocol_provenance); the recomputation reads the same bytes from elsewhere
        mine["protocol"] = theirs["protocol"]
    # a finding names the readings file by the path the run was given; the recomputation
    # reads the same readings from its temporary folder (same file name)
    for f_mine, f_theirs in zip(again.get("findings") or [], results.get("findings") or []):
        if isinstance(f_mine, dict) and isinstance(f_theirs, dict) and \
                isinstance(f_mine.get("file"), str) and isinstance(f_theirs.get("file"), str) \
                and Path(f_mine["file"]).name == Path(f_theirs["file"]).name:
            f_mine["file"] = f_theirs["file"]
    diff = first_difference(results, again)
    if diff:
        raise GonioError(f"results.json is not what its readings give ({diff}); nothing "
                         "recorded: calibrate the readings again (with this gonio) and "
                         "import that folder", file=res_path, key="results")
    # equal in every value: the folder's own bytes are kept (they name the protocol file by
    # the path the run was given, not the recomputation's temporary one)
    (out / "results.json").write_bytes(res_path.read_bytes())


def import_output_folder(store, folder: str | Path, *, readings: str | Path | None = None,
                         spec_key: str | None = None, customer: str = "(imported)",
                         actor: User | None = None,
                         protocol: str | Path | None = None,
                         lab: str | Path | None = None,
                         table_calibration: str | Path | None = None,
                         registered_gyro_type: str | None = None,
                         shown: str | Path | None = None,
                         option_files: dict | None = None) -> int:
    """Import one output folder as a computed calibration; returns its id.
    ``registered_gyro_type``: the registered instrument's optical-gyro type the run was given
    (``gonio calibrate --record``), which its recomputation is given too. ``shown``: the
    folder as the records name it (``calibrate --record`` imports its set from the staging
    folder, before it is moved into ``--out``: that name); default ``folder``.
    ``option_files``: {option: path} of the files the run was given by an option (``--tilt
    FILE``, ``--thermal FILE``), else found in the folder or beside the readings
    (:func:`option_inputs`): each stored with the calibration under
    :data:`~gonio.records.services.OPTION_PREFIX` and read by the recomputation. Readings
    another calibration that stands holds are refused before the (costly) recomputation.

    The folder's files are checked against its manifest (:func:`check_manifest`) and the
    result is computed again from what is stored (:func:`recomputed`): the imported
    results.json must be what its readings give, byte for byte in its JSON values
    (:func:`check_recomputed`), else nothing is recorded; the records keep the folder's
    results.json (equal in every value to the recomputed one) and the recomputed summary.txt.

    The protocol is stored with the readings (its file, as a blob), so that a later
    computation of the calibration uses the very protocol the result was computed with
    (the issue computes nothing: it renders the sealed result): ``protocol`` (a file
    or built-in name), else the one results.json names; a protocol that cannot be found, or
    whose SHA-256 differs from results.json's, is an error. ``lab``: the laboratory file the
    folder was computed with (``--lab``), validated as on the command line; when it gives
    limits it is stored as the calibration's laboratory file
    (:func:`gonio.records.services.lab_file`), so that the issue decides with the same limits
    and rule as the run reviewed; its ``[environment]`` is recorded as the calibration's,
    stated as from the laboratory file (:func:`lab_environment`), its place with the
    place's DCC category (``[certificate] place``, ``location``), and its ``[[standards]]``
    as the standards used (:func:`lab_standard_ids`: each registered and valid on the
    calibration date, else a GonioError and nothing is recorded); its ``[table_calibration]``
    file, where it names one, as the calibration's table calibration. The table calibration a
    run used (results.json records its SHA-256) is stored with the calibration: the laboratory
    file's, else ``table_calibration`` (``--table-calibration FILE``), else a copy in the folder
    under the name the run recorded; its SHA-256 must be the recorded one, and a result whose
    table calibration is not supplied is refused, nothing recorded
    (:func:`_table_calibration`)."""
    folder = Path(folder)
    res_path = folder / "results.json"
    try:
        results = json.loads(res_path.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError) as exc:    # RecursionError: '[' 10⁵ deep
        raise GonioError(f"no readable results.json ({str(exc)[:120] or 'nested too deeply'})",
                         file=folder) from None
    try:
        result_items(results)                  # a folder without items is refused here
    except GonioError as exc:
        raise GonioError(exc.message, file=res_path, key=exc.key) from None
    source = results.get("source") or {}
    meta = results.get("metadata") or {}
    for name, v in (("source", source), ("metadata", meta)):
        if not isinstance(v, dict):
            raise GonioError(f"results.json's {name} is not a JSON object", file=res_path,
                             key=name)
    day = None
    if meta.get("date"):
        try:
            day = _dt.date.fromisoformat(str(meta["date"])[:10])
        except ValueError:
            raise GonioError(f"not a date (YYYY-MM-DD): {str(meta['date'])[:40]!r}",
                             file=res_path, key="metadata.date") from None
        try:                         # named before the (costly) recomputation
            services.plausible_dates(day, None, services.records_today(store))
        except GonioError as exc:
            raise GonioError(exc.message, file=res_path, key="metadata.date") from None
    key = spec_key or results.get("spec") or meta.get("spec")
    if not key:      # every results.json gonio writes names its specification: no guessing
        raise GonioError("results.json names no specification (no 'spec'); give the "
                         "specification's key (--spec)", file=res_path, key="spec")
    from gonio.specs import get
    get(key)
    rd = _readings_in(folder, str(source.get("sha256", "")), Path(readings) if readings else None)
    with store.session() as s:
        inst = registered_instrument(s, meta)
        record = {"gyro_type": inst.gyro_type} if inst is not None and inst.gyro_type else None
        try:                       # one measurement, one calibration: before the work
            services.check_readings_unused(s, str(source.get("sha256", "")), path=rd)
        except GonioError as exc:
            raise GonioError(exc.message, file=rd, key=exc.key) from None
    from gonio.pipeline.dispatch import INSTRUMENT_FILE_OPTIONS
    given = [p for option, _, p in option_inputs(get(key), check_manifest(folder), res_path, rd,
                                                 option_files)
             if option in INSTRUMENT_FILE_OPTIONS]   # checked like the files the readings name
    meta = {**meta, **_check_identity(rd, lab, key, results, record, res_path, given, meta)}
    rsha, rsize = blobs.put_file(store.blob_root, rd)
    proto = _protocol_file(results, protocol, folder)
    psha = None
    if proto is not None:
        psha, psize = blobs.put_file(store.blob_root, proto)
    lsha, lsize, env, lab_stds = _lab_file(store, lab, key)
    _check_lab_standards(store, lab_stds, day, lab)     # before the (costly) recomputation
    tsha, tsize, tname = _table_calibration(store, lab, key, rd, results, res_path,
                                            table_calibration)
    man = check_manifest(folder)    # the folder as gonio wrote it, then what it says checked
    options = recorded_options(man, get(key), res_path)
    inputs = [(name, *blobs.put_file(store.blob_root, p))
              for name, p in named_inputs(get(key), rd, man, res_path)]
    by_option = [(option, name, *blobs.put_file(store.blob_root, p))
                 for option, name, p in option_inputs(get(key), man, res_path, rd,
                                                      option_files)]
    with tempfile.TemporaryDirectory(prefix="gonio-import-") as tmp:
        again = recomputed(store, key, rd.name, rsha, proto, psha, lab, tsha, tname,
                           registered_gyro_type, Path(tmp),
                           [(n, sha) for n, sha, _ in inputs], options,
                           [(o, n, sha) for o, n, sha, _ in by_option])
        inputs = [(services.INPUT_PREFIX + n, sha, size) for n, sha, size in inputs] + \
            [(services.option_file_name(o, n), sha, size) for o, n, sha, size in by_option]
        check_recomputed(results, again, res_path)
        return _record_import(store, Path(shown or folder), again, actor, meta, key, customer,
                              day, rd,
                              rsha, rsize, proto, psha, psize if psha else 0, lab, lsha, lsize,
                              env, lab_stds, tsha, tsize, tname, res_path, inputs, options)


def import_day(store) -> _dt.date:
    """The calibration date of an imported run whose readings give no ``date`` (so neither
    does its results.json, which the recomputation checks): the day of the import, the
    laboratory's date (:func:`~gonio.records.models.records_today` of the records ``store``) — never a file's modification time, which anyone can set (``touch -d``)
    and which would choose the standards and the table calibration in force on that day
    (docs/records.md, importing an output folder)."""
    return services.records_today(store)


def _record_import(store, folder, again, actor, meta, key, customer, day, rd, rsha, rsize,
                   proto, psha, psize, lab, lsha, lsize, env, lab_stds, tsha, tsize, tname,
                   res_path, inputs=(), options=None) -> int:
    """The checked import recorded: the calibration, its standards, files (``inputs``: (name
    kept under, sha256, size): the files the readings name, under
    :data:`~gonio.records.services.INPUT_PREFIX`, and the files options named, under
    :data:`~gonio.records.services.OPTION_PREFIX`) and audit events (the ``options`` it was
    computed with named) in one transaction, then its result (the recomputed folder
    ``again``'s files) stored."""
    try:
        os_user = getpass.getuser()
    except (KeyError, OSError):            # no name for the uid
        os_user = "(unknown)"
    who = actor.username if actor else f"command line ({os_user})"
    with store.writing() as s:
        for sha, size in ((rsha, rsize), (psha, psize), (lsha, lsize),
                          (tsha, tsize), *((i[1], i[2]) for i in inputs)):
            if sha and s.get(Blob, sha) is None:
                s.add(Blob(sha256=sha, size=size))
                s.flush()
        inst = _instrument(s, meta, key, customer, actor)
        dated = "the readings' date" if day else "the import day (the readings give no date)"
        if day:     # checked before the recomputation too; the import day is today
            try:
                services.plausible_dates(day, None, services.records_today(s))
            except GonioError as exc:
                raise GonioError(exc.message, file=res_path, key="metadata.date") from None
        day = day or import_day(s)
        cal = Calibration(instrument_id=inst.id, spec_key=key, readings_sha256=rsha,
                          readings_name=rd.name,
                          protocol=services.text(proto.name if proto else "", "protocol",
                                                 max_len=200),
                          protocol_sha256=psha, lab_sha256=lsha,
                          lab_name=services.text(Path(lab).name if lsha else "",
                                                 "laboratory file name", max_len=255),
                          performed_on=day, status="running", created_by_id=actor.id
                          if actor else None, progress=f"imported from {folder.name} by {who}",
                          **env)
        s.add(cal)
        s.flush()
        services.use_standards(s, cal, lab_standard_ids(s, lab_stds, day, lab))
        try:                       # one measurement, one calibration: else nothing committed
            services.check_readings_unused(s, rsha, other_than=cal.id, path=rd)
        except GonioError as exc:
            raise GonioError(exc.message, file=rd, key=exc.key) from None
        services.audit(s, actor, "import", "calibration", cal.id, None,
                       dict(services.state(cal), folder=str(folder), os_user=os_user,
                            standards=services.standard_names(s, cal.id),
                            options=dict(options or {}), date_from=dated,
                            inputs={n: sha for n, sha, _ in inputs}))
        for name, sha, _ in inputs:     # the files the readings and the options name, kept
            s.add(CalibrationFile(calibration_id=cal.id, name=name, sha256=sha))
        if tsha is not None:        # the table calibration the run used, kept
            _keep_table_calibration(s, cal, actor, tsha, tname, res_path)
        s.commit()
        cal_id = cal.id
    try:
        # the result and its items as a worker's run stores them; not the command line's
        # certificate files (its number and title, no DRAFT mark: not the records' draft)
        services.store_run(store, cal_id, again, kept=services.KEPT_IMPORTED)
    except Exception as exc:
        services.fail(store, cal_id, f"import failed: {exc}")
        raise
    return cal_id


def record_output_folder(store, folder: str | Path, *, actor: User | None = None,
                         standard_identifiers=(), temperature_c=None, humidity_pct=None,
                         environment_from_readings: bool = False, **import_options) -> int:
    """Put one output folder into the records with what the command line names (``gonio
    calibrate --record``, ``gonio db import``); returns the calibration's id.

    The folder is imported (:func:`import_output_folder` with ``import_options``: readings,
    spec_key, customer, protocol, lab, table_calibration; the laboratory file's
    ``[environment]`` carried, its
    source stated, and its ``[[standards]]`` matched by identifier to registered standards
    valid on the calibration date, :func:`lab_standard_ids` — one that is not refuses the
    whole import); then the registered standards named by their identifiers (besides the
    laboratory file's) and the environment given (entered, or
    ``environment_from_readings``; either replaces the laboratory file's) are attached by
    ``actor`` (:func:`gonio.records.services.attach_by_identifiers`), and the draft
    certificate is rendered at once from the stored result with them
    (:func:`gonio.records.worker.run_now`: nothing computed again) — also when only the
    laboratory file names standards. Attaching needs ``actor``; the import is kept when an
    attach is refused (the GonioError names the calibration)."""
    attach = dict(standard_identifiers=standard_identifiers, temperature_c=temperature_c,
                  humidity_pct=humidity_pct,
                  environment_from_readings=environment_from_readings)
    check_attach_actor(actor, **attach)
    cid = import_output_folder(store, folder, actor=actor, **import_options)
    attach_recorded(store, cid, actor, **attach)
    return cid


def _attach_given(standard_identifiers=(), temperature_c=None, humidity_pct=None,
                  environment_from_readings: bool = False) -> tuple[list, dict]:
    environment = {}
    if temperature_c is not None or humidity_pct is not None:
        environment = {"temperature_c": temperature_c, "humidity_pct": humidity_pct}
    if environment_from_readings:
        environment["environment_from_readings"] = True
    return list(standard_identifiers or ()), environment


def check_attach_actor(actor: User | None, **attach) -> None:
    """Attaching standards or the environment (``attach``: :func:`record_output_folder`'s
    keywords) needs the records user ``actor``: refused in one line before any work."""
    standards, environment = _attach_given(**attach)
    if (standards or environment) and actor is None:
        raise GonioError("give the records user attaching standards or the environment "
                         "(--user or --record-user, or $GONIO_USER)", key="user")


def attach_recorded(store, cid: int, actor: User | None, **attach) -> None:
    """The second half of :func:`record_output_folder`: the registered standards (the
    laboratory file's matched at import, and those ``attach`` names) and the environment
    given attached to the recorded calibration ``cid`` by ``actor``, and its draft rendered
    at once; the import is kept when an attach is refused (the GonioError names the
    calibration)."""
    standards, environment = _attach_given(**attach)
    with store.session() as s:
        from_lab = services.standard_names(s, cid)      # the lab file's, matched at import
    if standards or environment or (from_lab and actor is not None):
        named = sorted(set(from_lab) | set(standards))
        try:
            services.attach_by_identifiers(store, actor, cid, standard_identifiers=named
                                           or None, **environment)
        except GonioError as exc:
            raise GonioError(f"calibration {cid} recorded, nothing attached: {exc.message}",
                             key=exc.key) from None
        from gonio.records.worker import run_now
        run_now(store, cid)
