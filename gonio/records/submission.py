"""The checks a new calibration passes before anything is queued (docs/records.md#submission):
what the web form calls, so that a calibration that cannot give a certificate fit for
accredited work is refused at upload, in the form's own words, not by a failed run later.

:func:`submit_calibration` checks, in this order, then creates the calibration
(:func:`gonio.records.services.create_calibration`, which checks the dates, a standard, the
environment, the instrument and each standard's due date on the day of the calibration, on
every path: the web form, a bench, the Python API):

* at least one registered reference standard is named (ISO/IEC 17025 6.5: the result's
  traceability; a certificate naming none states nothing it is traceable to);
* the environment is entered: room temperature and relative humidity (17025 7.8.4.1 a);
* the table calibration: the laboratory register's entry chosen, or the one in force on the
  date of calibration of the table among the standards, or an upload — an expired, superseded
  or unregistered one refused (:func:`gonio.records.services.table_calibration_for`); only for
  a specification that takes one, and where the laboratory file names one
  (``[table_calibration]``) that file (its SHA-256), valid on the date of calibration
  (:func:`gonio.records.services.table_calibration_of`);
* the readings file is readings: a Parquet stream, or UTF-8 text whose first line after
  the ``# key: value`` metadata is a CSV header (a JSON file, a spreadsheet or an image is
  refused naming what it looks like) — :func:`readings_facts`;
* the readings are of this specification: their ``# spec:`` (or ``# format:``, or a
  ``# protocol:`` that names a registered specification) must be the calibration's;
* the readings are of this instrument in these conditions: their ``# serial:``, ``# model:``,
  ``# manufacturer:`` against the instrument's record, their temperature and humidity
  against what was entered, compared as the pipeline compares them with a laboratory file
  (:func:`gonio.pipeline.identity.contradictions`, the same tolerances): the run would be
  refused on the same grounds, later and in command-line words;
* the same readings (the same SHA-256) are not already the readings of another
  calibration that stands (any state but rejected or void): the same measurement certified
  twice is refused (:func:`gonio.records.services.check_readings_unused`, the check every
  path makes) unless the person says why it is used again (``reuse_reason``), which is
  written to the audit trail with the calibrations that used it before.
"""

from __future__ import annotations

from typing import Iterable

from sqlalchemy import select

from gonio.errors import GonioError, first_of
from gonio.records import services
from gonio.records.models import Calibration, Instrument, User

#: the states in which a calibration no longer stands for its readings (they may be used again)
CLOSED = services.CLOSED
#: bytes of a text readings file read to recognise it (its metadata and header line)
SNIFF_BYTES = 256 * 1024
#: the GonioError key of a reused readings file (the form then asks why)
REUSE_KEY = services.REUSE_KEY


def readings_facts(store, sha256: str, *, conditions: bool = True) -> dict:
    """What a stored readings file is: ``{"format": "parquet" | "csv", "metadata": {...},
    "spec": key or None, "spec_from": the metadata line that named it, "measured": what the
    readings measured of their conditions (the specification's ``measured_conditions``; {}
    where ``conditions`` is false or it measures none)}``; a file that is no readings file is
    a GonioError (key ``readings``) saying what it looks like."""
    from gonio.formats.provenance import readings_metadata
    from gonio.pipeline.dispatch import readings_spec
    from gonio.records.compute import readings_file, readings_suffix
    from gonio.records.blobs import blob_path

    src = blob_path(store.blob_root, sha256)
    if not src.is_file():
        raise GonioError("no such stored file", key="readings")
    with open(src, "rb") as fh:
        head = fh.read(SNIFF_BYTES)
    suffix = readings_suffix(head)
    if suffix == ".csv":
        _looks_like_csv(head)
    from gonio.specs import available, get

    with readings_file(src) as path:
        try:
            md = readings_metadata(path)
            spec = readings_spec(path)
            spec_from = "# spec" if md.get("spec") else "# format" if spec else ""
            if spec is None and str(md.get("protocol", "")).strip() in available():
                spec, spec_from = str(md["protocol"]).strip(), "# protocol"
            # what the readings measured of their conditions (a logged room temperature),
            # compared by check_readings as the calibration compares it
            measured = get(spec).measured_conditions if spec in available() else None
            measured = measured(path) if conditions and measured is not None and md else {}
        except GonioError as exc:
            raise GonioError(f"the readings file cannot be read: {exc.message}",
                             key="readings") from None
    return {"format": suffix[1:], "metadata": md, "spec": spec, "spec_from": spec_from,
            "measured": measured}


def _looks_like_csv(head: bytes) -> None:
    """A text readings file: UTF-8, and its first line after the metadata a CSV header."""
    if head[:2] in (b"PK", b"\xd0\xcf") or head[:4] == b"%PDF" or head[:8] == b"\x89PNG\r\n\x1a\n":
        raise GonioError("the readings file is a binary document (a spreadsheet, PDF or "
                         "image), not readings: export the readings as CSV", key="readings")
    try:
        text = head.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        if len(head) - exc.start > 4:       # not just a character cut at the sniff's end
            raise GonioError("the readings file is not UTF-8 text (CSV) nor a Parquet "
                             "stream", key="readings") from None
        text = head[:exc.start].decode("utf-8-sig")
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        if line[:1] in ("{", "["):
            raise GonioError("the readings file is JSON (a results.json?), not readings: "
                             "upload the readings CSV or Parquet stream", key="readings")
        if line[:1] == "<":
            raise GonioError("the readings file is XML or HTML (a certificate?), not "
                             "readings: upload the readings CSV or Parquet stream",
                             key="readings")
        if "," not in line:
            raise GonioError(f"the readings file's first line after the metadata "
                             f"('{line[:40]}') is no CSV header", key="readings")
        return
    raise GonioError("the readings file holds no readings (metadata lines only, or empty)",
                     key="readings")


def check_readings(facts: dict, inst: Instrument, spec_key: str, temperature_c=None,
                   humidity_pct=None) -> None:
    """The readings (:func:`readings_facts`) against the calibration: their specification,
    the instrument's serial, model, manufacturer and optical-gyro type, the environment
    entered; a GonioError
    (key ``readings``) in the form's words for the first that does not match."""
    from gonio.pipeline.identity import contradictions

    named = facts["spec"]
    if named and named != spec_key:
        raise GonioError(f"the readings are {named} readings ({facts['spec_from']}: {named}); "
                         f"this calibration is per {spec_key} (the instrument "
                         f"{inst.serial}'s specification): choose the readings of this "
                         "instrument, or the instrument these readings are of",
                         key="readings")
    record = {"instrument": {"serial": inst.serial, "model": inst.model,
                             "manufacturer": inst.manufacturer, "gyro_type": inst.gyro_type},
              "environment": {"temperature_c": temperature_c, "humidity_pct": humidity_pct}}
    from gonio.specs import get

    # the room's temperature by the specification's keys (IEC's room_temperature_c is its
    # chamber's base temperature) and by what the readings measured, as the pipeline compares
    found = contradictions(facts["metadata"], record, facts.get("measured") or None,
                           get(spec_key).room_temperature_keys)
    if found:
        c = found[0]
        where = ("the instrument's record" if c["lab_key"].startswith("instrument")
                 else "what was entered")
        tol = f" (more than {c['tolerance']} apart)" if c["tolerance"] else ""
        said = (f"{c['what']}: the readings say {c['readings']} "
                f"({c.get('where') or '# ' + c['key']}), {where} {c['lab']}{tol}")
        raise GonioError(f"{first_of([said, *found[1:]])}: these readings are not of this "
                         "instrument or these conditions", key="readings")


def reused_by(store, sha256: str) -> list[dict]:
    """The calibrations that stand (not rejected nor void) whose readings are this file
    (:func:`gonio.records.services.readings_used_by`), oldest first."""
    with store.session() as s:
        return services.readings_used_by(s, sha256)


#: the form's own fields: the dates, at least one standard, the environment entered; the
#: same checks :func:`gonio.records.services.create_calibration` makes on every path
check_form = services.submission_fields


def submit_calibration(store, actor: User, *, instrument_id: int, readings_sha256: str,
                       standard_ids: Iterable[int] = (), temperature_c=None,
                       humidity_pct=None, spec_key: str | None = None,
                       performed_on=None, received_on=None, lab_sha256: str | None = None,
                       lab_name: str = "", reuse_reason: str = "", **details):
    """A new calibration after the submission checks (module docstring), queued for the
    worker (technician): the form's fields first (dates, standards, environment), then the
    laboratory file and the table calibration
    (:func:`gonio.records.services.table_calibration_of`), then the readings. ``details``: the other arguments of
    :func:`gonio.records.services.create_calibration`. ``reuse_reason``: why readings
    already used by another calibration are used again (empty: such readings are refused)."""
    services.require(actor, "technician")
    day, received, ids, temp, hum = check_form(performed_on, received_on, standard_ids,
                                               temperature_c, humidity_pct,
                                               services.records_today(store))
    with store.session() as s:
        inst = s.get(Instrument, int(instrument_id))
        if inst is None:
            raise GonioError("no such instrument", key="instrument")
        s.expunge(inst)
    key = services.text(spec_key, "spec", max_len=64) or inst.spec_key
    lab_d = services.lab_file(store, lab_sha256, lab_name, key) if lab_sha256 is not None else {}
    from gonio.specs import get
    with store.session() as s:   # before the readings' checks: the register's, or the upload
        table_sha, _ = services.table_calibration_for(
            s, get(key), ids, day, details.get("table_calibration_sha256"),
            details.get("table_calibration_id"))
    services.table_calibration_of(get(key), lab_d, lab_name, table_sha, day)
    check_readings(readings_facts(store, readings_sha256), inst, key, temp, hum)
    reason = services.text(reuse_reason, "reuse_reason", max_len=services.MAX_TEXT,
                           multiline=True)
    with store.session() as s:          # checked again where it is recorded
        try:
            before = services.check_readings_unused(s, readings_sha256, reason=reason)
        except GonioError as exc:
            raise GonioError(f"{exc.message}; say why they are used again to go on",
                             key=exc.key) from None
    note = {"readings_sha256": readings_sha256, "used_by": [c["id"] for c in before],
            "reason": reason} if before else None
    return services.create_calibration(store, actor, instrument_id=inst.id,
                                       readings_sha256=readings_sha256, spec_key=key,
                                       standard_ids=ids, temperature_c=temp,
                                       humidity_pct=hum, performed_on=day, received_on=received,
                                       lab_sha256=lab_sha256, lab_name=lab_name,
                                       reuse_note=note, **details)
