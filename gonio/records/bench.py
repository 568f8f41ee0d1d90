"""A calibration started from a connected bench: the worker acquires the readings first.

:func:`create_bench_calibration` (technician) queues a calibration whose readings are still
to be taken: the bench's VISA resources and the laboratory's metadata lines are stored as
the calibration's file ``bench-request.json`` (content-addressed, like every input), which
also stands as its readings until they exist. The worker
(:func:`gonio.records.worker.execute`) sees a pending request (:func:`pending_request`) and
runs the same acquisition engine as ``gonio acquire``
(:func:`gonio.pipeline.acquire.acquire`) into its private work folder before calibrating;
:func:`store_acquisition` then puts ``readings.csv`` into the store as the calibration's
readings and the raw I/O log as its file ``io.log`` — both under the review's seal with
the other files — with an audit event. A failed acquisition fails the calibration with
the reason; run again, it acquires again from the start.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Iterable

from gonio.errors import GonioError
from gonio.records import blobs, services
from gonio.records.models import Blob, Calibration, CalibrationFile

#: The stored request and the stored raw I/O log, by their names among the calibration's files.
REQUEST, IO_LOG = "bench-request.json", "io.log"
#: The instrument roles (``gonio acquire --table/--gyro/--chamber/--supply``).
ROLES = ("table", "gyro", "chamber", "supply")
#: A VISA resource string as the records accept it (the interface, then ``::`` parts).
_RESOURCE = re.compile(r"(TCPIP|ASRL|GPIB|USB|VXI|PXI)[^\s]{0,190}", re.IGNORECASE)
#: The readings name shown while the readings are still to be taken.
PENDING_NAME = "(to be acquired from the bench)"


def check_request(resources: dict, metadata: dict) -> dict:
    """The request checked: resource strings by role (table and gyro required), metadata
    ``KEY=VALUE`` lines as a dict of one-line strings; GonioError naming the field."""
    res = {}
    for role in ROLES:
        v = services.text(resources.get(role), role)
        if not v:
            if role in ("table", "gyro"):
                raise GonioError(f"give the {role}'s VISA resource "
                                 "(e.g. TCPIP0::192.168.1.20::5025::SOCKET)", key=role)
            continue
        if not _RESOURCE.fullmatch(v):
            raise GonioError(f"not a VISA resource string: {v!r} (TCPIP0::host::port::SOCKET, "
                             "ASRL/dev/ttyUSB0::INSTR, GPIB0::12::INSTR, USB0::…::INSTR)",
                             key=role)
        res[role] = v
    md = {}
    for k, v in (metadata or {}).items():
        key = services.text(k, "metadata key", max_len=64)
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", key):
            raise GonioError(f"metadata key {key!r}: letters, digits and '_'", key="metadata")
        if key.endswith("_idn") or key == "generator":
            raise GonioError(f"metadata key {key!r}: the instruments' own answer and the "
                             "acquisition write it, never the form "
                             "(gonio.instruments.run.with_given_metadata)", key="metadata")
        md[key] = services.text(v, f"metadata {key}")
    return {"gonio_bench_request": 1, "resources": res, "metadata": md}


def parse_metadata_lines(text: str) -> dict:
    """``KEY=VALUE`` lines (a form's text area) as a dict; blank lines skipped."""
    md = {}
    for n, line in enumerate(str(text or "").splitlines(), 1):
        if not line.strip():
            continue
        k, sep, v = line.partition("=")
        if not sep or not k.strip():
            raise GonioError(f"metadata line {n}: expected KEY=VALUE, got {line.strip()!r}",
                             key="metadata")
        md[k.strip()] = v.strip()
    return md


def create_bench_calibration(store, actor, *, instrument_id: int, resources: dict,
                             metadata: dict | None = None, standard_ids: Iterable[int] = (),
                             temperature_c=None, humidity_pct=None, performed_on=None,
                             received_on=None, **fields) -> Calibration:
    """Queue a calibration whose readings the worker acquires from the bench at
    ``resources`` (by role) with the laboratory's ``metadata`` lines, after the form's own
    submission checks (:func:`gonio.records.submission.check_form`: a standard, the
    environment, the dates); ``fields`` as :func:`gonio.records.services.create_calibration`
    takes them (protocol, place, laboratory file). The readings' checks (specification,
    instrument, conditions) run on the readings once taken (:func:`store_acquisition`)."""
    from gonio.records.submission import check_form

    services.require(actor, "technician")
    day, received, ids, temp, hum = check_form(performed_on, received_on, standard_ids,
                                               temperature_c, humidity_pct,
                                               services.records_today(store))
    request = check_request(resources, metadata or {})
    data = json.dumps(request, sort_keys=True, indent=1).encode("utf-8") + b"\n"
    sha = blobs.put_bytes(store.blob_root, data)
    with store.writing() as s:
        if s.get(Blob, sha) is None:
            s.add(Blob(sha256=sha, size=len(data)))
            s.commit()
    cal = services.create_calibration(store, actor, instrument_id=instrument_id,
                                      readings_sha256=sha, readings_name=PENDING_NAME,
                                      standard_ids=ids, temperature_c=temp, humidity_pct=hum,
                                      performed_on=day, received_on=received,
                                      check_reuse=False, **fields)
    with store.writing() as s:
        s.add(CalibrationFile(calibration_id=cal.id, name=REQUEST, sha256=sha))
        s.commit()
    services.set_progress(store, cal.id, "waiting for a worker (then the bench)")
    return services.calibration(store, cal.id)


def pending_request(store, cal: Calibration) -> dict | None:
    """The bench request of a calibration whose readings are still to be acquired (its
    readings are the request itself), else None."""
    with store.session() as s:
        f = s.get(CalibrationFile, (cal.id, REQUEST))
    if f is None or f.sha256 != cal.readings_sha256:
        return None
    return json.loads(services.file_bytes(store, f.sha256))


def acquire_for(store, cal: Calibration, request: dict, work: Path,
                protocol: str | None) -> Path:
    """Take the readings of ``cal`` from its bench into ``work``/``acq`` with the engine of
    ``gonio acquire``; store them (:func:`store_acquisition`); the readings' path."""
    from gonio.pipeline.acquire import acquire
    from gonio.specs import get

    services.set_progress(store, cal.id, "acquiring the readings from the bench")
    res = acquire(protocol or get(cal.spec_key).default_protocol, request["resources"],
                  work / "acq", spec_key=cal.spec_key, metadata=request.get("metadata", {}),
                  prompt=_no_operator)
    store_acquisition(store, cal, res.readings, res.io_log)
    return res.readings


def _no_operator(message: str) -> str:
    raise GonioError(f"the programme needs an operator ({message.strip()}); a calibration "
                     "started from the records runs unattended: use an instrument that sets "
                     "it, or gonio acquire at the bench")


def store_acquisition(store, cal: Calibration, readings: Path, io_log: Path) -> None:
    """The raw I/O log becomes the calibration's file ``io.log``; the readings taken, once
    they pass the submission's readings checks against the calibration
    (:func:`gonio.records.submission.check_readings`: specification, the instrument's
    serial, model and manufacturer, the environment entered) and are no other standing
    calibration's (:func:`gonio.records.services.check_readings_unused`), its readings; one
    audit event. Readings that fail are kept in the store, the calibration keeps its request (run
    again, it acquires again) and fails with the reason."""
    from gonio.records.submission import check_readings, readings_facts

    r_sha, r_size = blobs.put_file(store.blob_root, readings)
    l_sha, l_size = blobs.put_file(store.blob_root, io_log)
    with store.writing() as s:
        for sha, size in ((r_sha, r_size), (l_sha, l_size)):
            if s.get(Blob, sha) is None:
                s.add(Blob(sha256=sha, size=size))
        s.flush()
        old = s.get(CalibrationFile, (cal.id, IO_LOG))
        if old is None:
            s.add(CalibrationFile(calibration_id=cal.id, name=IO_LOG, sha256=l_sha))
        else:
            old.sha256 = l_sha
        s.commit()
    check_readings(readings_facts(store, r_sha), cal.instrument, cal.spec_key,
                   *services.environment_shown(cal))      # as entered: "25.0", not 25
    with store.writing() as s:
        row = s.get(Calibration, cal.id)
        services.check_readings_unused(s, r_sha, other_than=row.id)
        before = services.state(row)
        row.readings_sha256, row.readings_name = r_sha, "readings.csv"
        services.audit(s, None, "acquired", "calibration", row.id, before, services.state(row))
        s.commit()
