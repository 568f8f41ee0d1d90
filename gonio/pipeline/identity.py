"""The instrument's identity and the conditions of the readings against the laboratory file
(docs/formats.md#identity-and-conditions).

The readings' own metadata (``# serial:``, ``# model:``, ``# manufacturer:``, an optical
gyro's ``# gyro_type:``, the
temperature ``# temperature_c:`` or ``# room_temperature_c:``, ``# humidity_pct:``) are
compared with the laboratory file's ``[instrument]`` and ``[environment]``: a text that
differs (compared without regard to case, Unicode compatibility forms and runs of white
space: :func:`gonio.formats.metadata.identity_text`) or a temperature or
humidity further apart than the tolerance (both numbers named as written, the
certificate's :func:`~gonio.report.header.condition_text`: a laboratory file's ``25.0`` is
"25.0 °C") (``[identity]`` ``temperature_tolerance_c``, default
:data:`TEMPERATURE_TOLERANCE_C`; ``humidity_tolerance_pct``, default
:data:`HUMIDITY_TOLERANCE_PCT`) is a contradiction. Where either side is silent nothing is
compared. A contradiction refuses the calibration with one line (``GonioError``, exit 2)
unless the laboratory file says ``[identity] on_mismatch = "proceed"``: then each one is a
flagged finding (code ``identity-mismatch``, its ``subject`` what it contradicts) stated on
the certificate, in summary.txt and in results.json; the certificate's first page, summary.txt
and the DCC's identification flag the contradicted line beside it
(:func:`gonio.result.findings.identity_subjects`).
"""

from __future__ import annotations

import math
from pathlib import Path

from gonio.errors import GonioError, first_of
from gonio.formats.metadata import identity_text, parse_number
from gonio.formats.provenance import readings_metadata
from gonio.report.header import condition_text
from gonio.result.findings import IDENTITY_CODE, Finding

#: Default largest difference, °C, between the readings' and the laboratory file's temperature.
TEMPERATURE_TOLERANCE_C = 1.0
#: Default largest difference, percentage points, between the two relative humidities.
HUMIDITY_TOLERANCE_PCT = 10.0
#: (what, laboratory file section and key, the readings' metadata keys in order of preference)
TEXT_FIELDS = (("serial", "instrument", "serial", ("serial",)),
               ("model", "instrument", "model", ("model",)),
               ("manufacturer", "instrument", "manufacturer", ("manufacturer",)),
               ("gyro type", "instrument", "gyro_type", ("gyro_type",)))
NUMBER_FIELDS = (("temperature", "environment", "temperature_c",
                  ("temperature_c", "room_temperature_c"), "temperature_tolerance_c", "°C"),
                 ("humidity", "environment", "humidity_pct", ("humidity_pct",),
                  "humidity_tolerance_pct", "%"))


def _norm(text) -> str:
    """An identity text (serial, model, manufacturer, gyro type) as compared: the one
    identity normaliser, :func:`gonio.formats.metadata.identity_text` (case, Unicode
    compatibility forms and runs of white space folded)."""
    return identity_text(text)


def _first(md: dict, keys) -> tuple[str | None, str | None]:
    for k in keys:
        v = md.get(k)
        if v is not None and str(v).strip():
            return k, str(v).strip()
    return None, None


def contradictions(metadata: dict, lab: dict | None, measured: dict | None = None,
                   temperature_keys: tuple[str, ...] | None = None) -> list[dict]:
    """Each contradiction between the readings' ``metadata`` and ``lab`` (a loaded laboratory
    file): ``{"what", "key" (the metadata key), "readings", "lab", "lab_key", "tolerance"}``.

    >>> lab = {"instrument": {"serial": "SN-0001", "model": ""},
    ...        "environment": {"temperature_c": 20.1}}
    >>> [c["what"] for c in contradictions({"serial": "MEMS-0610-001", "model": "M",
    ...                                      "room_temperature_c": "22.5"}, lab)]
    ['serial', 'temperature']
    >>> contradictions({"serial": " sn-0001 ", "temperature_c": "20.9"}, lab)
    []
    >>> [c["lab_key"] for c in contradictions({"gyro_type": "fog"},
    ...                                       {"instrument": {"gyro_type": "RLG"}})]
    ['instrument.gyro_type']

    ``measured``: what the readings measured (``{"temperature_c": (text, where)}``, a
    specification's ``measured_conditions``): compared as well as the metadata line, and in
    place of a missing one, named by ``where`` — a logged room temperature that contradicts
    the laboratory file is one whatever the metadata line says:

    >>> [c["where"] for c in contradictions({}, lab, {"temperature_c": ("25.0", "the column")})]
    ['the column']
    >>> [c["where"] for c in contradictions({"temperature_c": "20.0"}, lab,
    ...                                     {"temperature_c": ("25.0", "col")})]
    ['col']
    >>> contradictions({"temperature_c": "20.0"}, lab, {"temperature_c": ("20.4", "col")})
    []

    ``temperature_keys``: the readings' metadata keys that state the room temperature (a
    specification's ``room_temperature_keys``; None: those of :data:`NUMBER_FIELDS`). A key
    not among them is not the room's and is not compared (IEC 62047-20's
    ``room_temperature_c`` is its chamber's base temperature):

    >>> contradictions({"room_temperature_c": "22.5"}, lab, None, ("temperature_c",))
    []

    Both keys given: each is compared (a room line of 35 °C below an agreeing
    ``temperature_c`` is a contradiction too):

    >>> [c["key"] for c in contradictions({"temperature_c": "20.0",
    ...                                    "room_temperature_c": "35"}, lab)]
    ['room_temperature_c']

    A stated condition that is no number is refused, never passed as silent:

    >>> contradictions({"temperature_c": "30,0"}, lab)
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key temperature_c: expected a number (°C), got '30,0': the temperature the readings state cannot be compared with the laboratory file's
    """
    if not lab:
        return []
    out = []
    rules = lab.get("identity") or {}
    for what, section, key, md_keys in TEXT_FIELDS:
        theirs = ((lab.get(section) or {}).get(key) or "").strip()
        k, ours = _first(metadata, md_keys)
        if theirs and ours is not None and _norm(theirs) != _norm(ours):
            out.append({"what": what, "key": k, "readings": f"'{ours}'", "lab": f"'{theirs}'",
                        "lab_key": f"{section}.{key}", "tolerance": None})
    for what, section, key, md_keys, tol_key, unit in NUMBER_FIELDS:
        if what == "temperature" and temperature_keys is not None:
            md_keys = tuple(temperature_keys)
        theirs = (lab.get(section) or {}).get(key)
        if theirs is None:
            continue
        # every key that states it (a "# temperature_c" and a "# room_temperature_c" line
        # both: each is compared, never the first alone)
        stated = [(k, str(metadata[k]).strip(), None) for k in md_keys
                  if metadata.get(k) is not None and str(metadata[k]).strip()]
        if md_keys and md_keys[0] in (measured or {}):    # what the readings measured too
            stated.append((md_keys[0], *measured[md_keys[0]]))
        default = TEMPERATURE_TOLERANCE_C if what == "temperature" else HUMIDITY_TOLERANCE_PCT
        tol = rules.get(tol_key)
        tol = default if tol is None else float(tol)
        for k, text, where in stated:
            ours = parse_number(text)
            if ours is None or not math.isfinite(ours):
                # a condition that cannot be read cannot be compared: never passed unread
                raise GonioError(f"expected a number ({unit}), got {text!r}: the {what} the "
                                 "readings state cannot be compared with the laboratory "
                                 "file's", key=k)
            if abs(float(theirs) - ours) <= tol:
                continue
            out.append({"what": what, "key": k, "readings": f"{condition_text(text)} {unit}",
                        "lab": f"{condition_text(theirs)} {unit}", "lab_key": f"{section}.{key}",
                        "tolerance": f"{tol:g} {unit}", **({"where": where} if where else {})})
            break                     # one contradiction of the lab file's value: the first
    return out


#: where the records' registered instrument is named in a message (``calibrate --record``)
RECORD = "the instrument's record"


def record_contradictions(metadata: dict, lab: dict | None, record: dict | None) -> list[dict]:
    """``calibrate --record``: each contradiction of the readings' ``metadata`` and of the
    laboratory file ``lab`` with ``record``, the registered instrument's texts by the
    laboratory file's ``[instrument]`` key (e.g. ``{"gyro_type": "rlg"}``; an empty value is
    silent), as :func:`contradictions` gives them, with ``by`` naming who says the first
    value and ``lab`` the record's.

    >>> [(c["by"], c["readings"]) for c in record_contradictions(
    ...     {"gyro_type": "FOG"}, {"instrument": {"gyro_type": "fog"}}, {"gyro_type": "rlg"})]
    [('the readings say', "'FOG'"), ('the laboratory file says', "'fog'")]
    >>> record_contradictions({"gyro_type": " RLG "}, None, {"gyro_type": "rlg"})
    []
    """
    out = []
    inst = (lab or {}).get("instrument") or {}
    for what, section, key, md_keys in TEXT_FIELDS:
        theirs = str((record or {}).get(key) or "").strip()
        if section != "instrument" or not theirs:
            continue
        k, ours = _first(metadata, md_keys)
        said = [("the readings say", f"# {k}", ours)] if ours is not None else []
        lab_says = str(inst.get(key) or "").strip()
        if lab_says:
            said.append(("the laboratory file says", f"[{section}] {key}", lab_says))
        out += [{"what": what, "key": where, "readings": f"'{v}'", "lab": f"'{theirs}'",
                 "lab_key": f"{section}s.{key}", "tolerance": None, "by": by, "of": RECORD}
                for by, where, v in said if _norm(v) != _norm(theirs)]
    return out


def _message(c: dict) -> str:
    if c.get("message"):
        return c["message"]
    tol = f" (more than {c['tolerance']} apart)" if c["tolerance"] else ""
    where = c.get("where") or (c["key"] if "by" in c else f"# {c['key']}")
    return (f"{c['what']}: {c.get('by', 'the readings say')} {c['readings']} ({where}), "
            f"{c.get('of', 'the laboratory file')} {c['lab']} ({c['lab_key']}){tol}")


#: the code of the finding that states a contradiction the laboratory file proceeded with
MISMATCH_CODE = IDENTITY_CODE


def named_contradictions(metadata: dict, named: dict, lab: dict | None,
                         record: dict | None, readings_name: str) -> list[dict]:
    """Each contradiction of the identity texts (serial, model, manufacturer, gyro type: not
    the conditions, which a chamber programme changes on purpose) of the files the readings
    name as part of their data (``named``: {file name: its metadata}) with the readings'
    own ``metadata``, with ``lab`` and with ``record`` (a text the readings state too with
    the readings' only: their own contradiction with the laboratory file is stated once):
    a thermal programme or a static record of another instrument is not this calibration's,
    whatever file it came in.

    >>> [(c["by"], c["lab"]) for c in named_contradictions(
    ...     {"serial": "T-1"}, {"thermal.csv": {"serial": "T-9"}}, None, None, "readings.csv")]
    [('thermal.csv says', "'T-1'")]
    >>> named_contradictions({"serial": "T-1"}, {"thermal.csv": {"serial": " t-1"}}, None,
    ...                      None, "readings.csv")
    []
    """
    out = []
    own = {"instrument": {key: v for _, _, key, md_keys in TEXT_FIELDS
                          for v in [_first(metadata, md_keys)[1]] if v}}
    out += unstated_identity(named, [
        (own["instrument"].get("serial"), f"{readings_name} says", "# serial"),
        (str(((lab or {}).get("instrument") or {}).get("serial") or "").strip(),
         "the laboratory file", "[instrument] serial"),
        (str((record or {}).get("serial") or "").strip(), RECORD, "the records' serial")])
    for name, md in named.items():
        for other, of, lab_key in ((own, f"{readings_name} says", "# {k}"),
                                   ({**(lab or {}), "environment": {}}, "the laboratory file",
                                    "[instrument] {k}"),
                                   ({"instrument": record or {}}, RECORD,
                                    "the records' {k}")):
            for c in contradictions(md, other):
                # a text the readings state too is compared with theirs only: the readings'
                # own contradiction with the laboratory file or the record is stated once
                said = c["what"] in {w for w, _, key, _ in TEXT_FIELDS if own["instrument"]
                                     .get(key)}
                if c["tolerance"] is None and (other is own or not said):
                    out.append({**c, "key": f"# {c['key']}", "by": f"{name} says",
                                "of": of, "lab_key": lab_key.format(
                                    k=c["lab_key"].split(".")[-1])})
    return out


#: what an unstated identity is called in a contradiction (:func:`unstated_identity`)
UNSTATED = "identity not stated"


def unstated_identity(named: dict, known) -> list[dict]:
    """Each file read for the calibration that carries the instrument's own data (``named``:
    {file name: its metadata}; a file the readings name, or one an option gives: a thermal
    programme, a measured tilt, a static record) and states no serial (``# serial:``, or a
    JSON result's ``metadata.serial``) while the instrument's serial is known (``known``:
    (serial, who says it, where) of the readings, the laboratory file, the record; the
    first stated): nothing ties the file to the instrument the certificate names, so it is
    treated as a contradiction (refused, or stated on the certificate where the laboratory
    file proceeds: :func:`check_identity`). Where no one states a serial there is nothing
    to tie it to: nothing is said.

    >>> [c["message"] for c in unstated_identity({"th.csv": {"kind": "thermal"}},
    ...                                          [("T-1", "readings.csv says", "# serial")])]
    ["identity not stated in th.csv: it carries the instrument's data and states no serial (# serial), readings.csv says 'T-1' (# serial)"]
    >>> unstated_identity({"th.csv": {"serial": "T-1"}}, [("T-1", "r.csv says", "# serial")])
    []
    >>> unstated_identity({"th.csv": {}}, [(None, "r.csv says", "# serial"), ("", "lab", "x")])
    []
    """
    serial, by, where = next(((v, b, w) for v, b, w in known if v), (None, None, None))
    if not serial:
        return []
    return [{"what": "serial", "key": "# serial", "readings": "not stated", "lab": f"'{serial}'",
             "lab_key": where, "tolerance": None, "by": f"{name} says", "of": by,
             "message": f"{UNSTATED} in {name}: it carries the instrument's data and states no "
                        f"serial (# serial), {by} '{serial}' ({where})"}
            for name, md in named.items() if _first(md, ("serial",))[1] is None]


def check_identity(readings, lab: dict | None, *, lab_file=None,
                   record: dict | None = None, named=(), measured=None,
                   temperature_keys: tuple[str, ...] | None = None) -> list[Finding]:
    """Compare the readings' identity and conditions with ``lab`` (module docstring), and,
    with ``record`` (``calibrate --record``: the registered instrument's texts, see
    :func:`record_contradictions`), the readings and the laboratory file with the records;
    the identity texts of each file the readings name as part of their data (``named``:
    paths; :func:`named_contradictions`) with the readings, the laboratory file and the
    record: no contradiction gives ``[]``; one refuses (GonioError naming the readings and
    the key) unless ``lab["identity"]["on_mismatch"] == "proceed"``, where the flagged
    findings are returned for the result. ``measured(readings)``: what the readings measured
    of their conditions, compared beside their metadata and in place of a missing line (a
    specification's
    ``measured_conditions``; :func:`contradictions`); ``temperature_keys``: the metadata keys
    that state the room temperature (a specification's ``room_temperature_keys``)."""
    md = readings_metadata(readings) if lab or record or named else {}
    seen = measured(readings) if measured is not None and lab else None
    try:
        found = contradictions(md, lab, seen, temperature_keys)
    except GonioError as exc:            # a condition no number: named with its file
        raise GonioError(exc.message, file=Path(readings).name, key=exc.key) from None
    found += record_contradictions(md, lab, record)
    found += named_contradictions(md, {Path(p).name: readings_metadata(p) for p in named},
                                  lab, record, Path(readings).name)
    if not found:
        return []
    if (((lab or {}).get("identity") or {}).get("on_mismatch") or "refuse") != "proceed":
        c = found[0]
        first = first_of([_message(c), *found[1:]])
        where = f" ({lab_file})" if lab_file else ""
        if c.get("message", "").startswith(UNSTATED):
            raise GonioError(f"{first}: nothing ties the file to the instrument "
                             f"the laboratory file{where} or the readings name; state its serial "
                             "(# serial:), or set [identity] on_mismatch = \"proceed\" to state "
                             "it on the certificate", file=Path(readings).name)
        if c.get("of") == RECORD:
            named = f"the records and the laboratory file{where} name"
        elif "by" in c:
            named = f"the readings and the laboratory file{where} name (a file of another " \
                "instrument among the files the readings name)"
        else:
            named = f"the laboratory file{where} names"
        raise GonioError(f"{first}: the readings are not of the instrument or "
                         f"conditions {named}; correct one of them, "
                         "or set [identity] on_mismatch = \"proceed\" to state it on the "
                         "certificate", file=Path(readings).name)
    name = Path(readings).name
    return [Finding(MISMATCH_CODE, _message(c) + "; the laboratory file chose to proceed "
                    "([identity] on_mismatch = \"proceed\"): the certificate's identity and "
                    "conditions are the laboratory file's", "flagged", file=name,
                    rule="identity and conditions of the readings = the laboratory file's",
                    subject=c["what"])
            for c in found]
