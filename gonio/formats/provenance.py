"""Where readings come from (docs/formats.md#provenance): the virtual bench's readings and
streams say so in their own metadata (``# bench:``, ``# seed:``, ``# generator: gonio …``,
the instrument "… (virtual)");
:func:`provenance` reads it, :func:`result_provenance` gives it for a results.json."""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

from gonio.formats.metadata import header_lines

#: Metadata keys only gonio's virtual bench writes (``gonio simulate``, ``gonio demo``, a
#: stream from the bench): their presence marks the readings virtual (docs/formats.md#provenance).
VIRTUAL_BENCH_KEYS: tuple[str, ...] = ("bench", "seed", "noise")

#: Identity and equipment keys whose value names the virtual bench ("gonio virtual bench",
#: "RLG goniometer (virtual)", an instrument's ``*_idn`` "gonio,virtual rotary table"): the
#: bench writes them too, so readings keep the mark when its bench and seed lines are deleted.
VIRTUAL_NAME_KEYS: tuple[str, ...] = ("instrument", "manufacturer", "model", "table", "operator")
_VIRTUAL_WORD = re.compile(r"\bvirtual\b", re.IGNORECASE)


def provenance(metadata: Mapping[str, object] | None) -> dict:
    """Where readings come from, from their metadata: ``{"virtual": bool, "bench", "seed",
    "generator", "evidence"}``. Readings are virtual when their metadata name the virtual
    bench (``# bench:``), its seed (``# seed:``) or noise switch (``# noise:``), gonio's
    simulator as their generator (``# generator: gonio …``; not ``gonio … acquire``, gonio's
    acquisition from instruments), or the virtual bench as the instrument, its manufacturer,
    model, table or operator, or as an instrument's identification (a ``*_idn`` key), by the
    word "virtual"; ``evidence`` lists the keys that said so. Nothing else (a laboratory file,
    an option) can make readings that say so non-virtual.

    >>> provenance({"bench": "rlg-typical", "seed": "3", "serial": "X"})["virtual"]
    True
    >>> provenance({"serial": "X", "generator": "LabVIEW 2021"})
    {'virtual': False, 'bench': None, 'seed': None, 'generator': 'LabVIEW 2021', 'evidence': []}
    >>> provenance({"instrument": "MEMS rate gyro (virtual)"})["evidence"]
    ['instrument']
    >>> provenance({"generator": "gonio 0.1.0 acquire", "gyro_idn": "ACME,G1,7,2"})["virtual"]
    False
    """
    md = {str(k).strip().lower(): v for k, v in (metadata or {}).items()}

    def text(key):
        v = md.get(key)
        return None if v is None or str(v).strip() == "" else str(v).strip()

    generator = text("generator")
    evidence = [k for k in VIRTUAL_BENCH_KEYS if text(k) is not None]
    words = [] if generator is None else generator.lower().split()
    if words and words[0] == "gonio" and "acquire" not in words:
        evidence.append("generator")
    evidence += [k for k in md if (k in VIRTUAL_NAME_KEYS or k.endswith("_idn"))
                 and _VIRTUAL_WORD.search(text(k) or "")]
    return {"virtual": bool(evidence), "bench": text("bench"), "seed": text("seed"),
            "generator": generator, "evidence": evidence}


def readings_metadata(path) -> dict[str, str]:
    """A readings file's or a stream's metadata: the ``# key: value`` lines at the top of a
    CSV file (the first of a key given twice), a Parquet stream's key-value metadata."""
    if Path(path).suffix.lower() == ".parquet":
        from gonio.formats.streams import StreamFile
        return dict(StreamFile(path).metadata)
    if Path(path).suffix.lower() == ".json":
        return json_metadata(path) or {}
    out: dict[str, str] = {}
    for key, value in header_lines(path):
        out.setdefault(key, value)
    return out


def json_metadata(path) -> dict[str, str] | None:
    """A JSON result's ``metadata`` object (a ``gonio tilt-estimate --json`` result: the
    identity and provenance of the readings it was computed from) as texts; {} where it has
    none; None where the file is not JSON at all (its reader refuses it in its own words).

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "t.json").write_text('{"tilt_deg": 0.04, "metadata": {"serial": "R-1", "seed": 7}}')
    >>> json_metadata(d / "t.json"), json_metadata(d / "r.json")
    ({'serial': 'R-1', 'seed': '7'}, None)
    """
    import json
    try:
        d = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return None
    md = d.get("metadata") if isinstance(d, dict) else None
    if not isinstance(md, dict):
        return {}
    return {str(k): str(v) for k, v in md.items() if isinstance(v, (str, int, float))}


def readings_provenance(path, named=()) -> dict:
    """:func:`provenance` of a readings file's or a stream's metadata
    (:func:`readings_metadata`), and of each file the readings name as part of their data
    (``named``: a triad's thermal readings, the optical static record): the calibration is
    virtual when any file it reads is. Readings that say so themselves give their own
    provenance; else the first virtual named file's, ``evidence`` naming its keys as
    ``file:key``.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "r.csv").write_text(chr(10).join(["# serial: X", "t,v", ""]))
    >>> _ = (d / "th.csv").write_text(chr(10).join(["# bench: b", "# seed: 3", "t,v", ""]))
    >>> p = readings_provenance(d / "r.csv", [d / "th.csv"])
    >>> p["virtual"], p["seed"], p["evidence"]
    (True, '3', ['th.csv:bench', 'th.csv:seed'])
    """
    out = file_provenance(path)
    if out["virtual"]:              # the readings say so themselves: their own evidence
        return out
    for other in named:
        more = file_provenance(other)
        if not more["virtual"]:
            continue
        out = {**out, **{k: more[k] for k in ("bench", "seed", "generator") if not out.get(k)},
               "virtual": True,
               "evidence": [*out["evidence"], *(f"{Path(other).name}:{k}"
                                                for k in more["evidence"])]}
    return out


def file_provenance(path) -> dict:
    """:func:`provenance` of one file's metadata, made virtual also where its measured values
    carry the virtual bench's watermark (:func:`gonio.formats.watermark.detect`: readings or
    a stream whose ``#`` lines or Parquet metadata were deleted or edited, rows deleted or
    reordered, the file renamed or re-saved by a spreadsheet; read row by row, block by
    block, up to its first 400 000 rows);
    ``evidence`` then names ``watermark`` and ``watermark`` holds the test (cells, matching,
    p_value). The watermark is read only where the metadata do not already say virtual.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "r.csv").write_text(chr(10).join(["# serial: X", "t,output", "1,2.5", ""]))
    >>> file_provenance(d / "r.csv")["virtual"]
    False
    """
    out = provenance(readings_metadata(path))
    if out["virtual"]:
        return out
    if Path(path).suffix.lower() == ".json":     # a derived result: its source's provenance
        src = _json_source(path)
        if src.get("virtual") is True:
            out = {**out, "virtual": True, "evidence": [*out["evidence"], SOURCE]}
        return out
    from gonio.formats.watermark import detect
    wm = detect(path)
    if wm["virtual"]:
        out = {**out, "virtual": True, "evidence": [*out["evidence"], "watermark"],
               "watermark": {k: wm[k] for k in ("cells", "matching", "p_value")}}
    return out


#: The key of a JSON result computed from readings (``gonio tilt-estimate --json``) that
#: shows them (:func:`result_source`).
SOURCE = "source"
_SOURCE_KEY = b"gonio derived result source v1"


def _source_check(doc: Mapping) -> str:
    """The keyed digest of a derived JSON result: every key but ``metadata`` (which the
    identity check reads and reports itself) and the check itself, in canonical JSON."""
    import hashlib
    import json
    body = {k: v for k, v in doc.items() if k != "metadata"}
    body[SOURCE] = {k: v for k, v in dict(body.get(SOURCE) or {}).items() if k != "check"}
    text = json.dumps(body, sort_keys=True, ensure_ascii=True, allow_nan=True)
    return hashlib.blake2b(text.encode(), key=_SOURCE_KEY, digest_size=16).hexdigest()


def result_source(readings, doc: Mapping) -> dict:
    """``doc`` (a result computed from ``readings``) with its ``source``: the readings' file
    name and SHA-256, whether they are the virtual bench's (:func:`file_provenance`: their
    metadata and their values' watermark) and the keys that said so, and a keyed ``check``
    over the result's numbers and that source (docs/formats.md#derived-results).

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "r.csv").write_text(chr(10).join(["# seed: 3", "t,v", ""]))
    >>> s = result_source(d / "r.csv", {"tilt_deg": 0.04})["source"]
    >>> s["file"], s["virtual"], s["evidence"], len(s["check"])
    ('r.csv', True, ['seed'], 32)
    """
    from gonio.atomic import sha256_file
    p = file_provenance(readings)
    out = {k: v for k, v in doc.items() if k != SOURCE}
    out[SOURCE] = {"file": Path(readings).name, "sha256": sha256_file(readings),
                   "virtual": bool(p["virtual"]), "evidence": list(p["evidence"])}
    out[SOURCE]["check"] = _source_check(out)
    return out


def shown_source(path) -> dict:
    """The ``source`` a derived JSON result (:func:`result_source`) shows, checked: a
    result that does not show its readings (no ``source``, or one without their SHA-256 and
    whether they are virtual), or whose numbers or source were changed after gonio wrote
    them (its ``check`` does not match), is refused (GonioError naming the file).
    Where the source says virtual, :func:`file_provenance` marks the calibration virtual."""
    import json
    from gonio.errors import GonioError
    name = Path(path).name
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        doc = None
    src = doc.get(SOURCE) if isinstance(doc, dict) else None
    if not (isinstance(src, dict) and isinstance(src.get("virtual"), bool)
            and re.fullmatch(r"[0-9a-f]{64}", str(src.get("sha256") or ""))):
        raise GonioError(f"{name}: does not show the readings it was computed from (no "
                         "'source' with their sha256 and provenance): compute it again with "
                         "gonio from the readings (tilt-estimate --json)")
    if src.get("check") != _source_check(doc):
        raise GonioError(f"{name}: its numbers or its 'source' were changed after gonio wrote "
                         "it (the source check does not match): compute it again from the "
                         "readings")
    return src


def result_provenance(res: Mapping) -> dict:
    """The provenance of a results.json dict (or a result's ``to_dict``): its ``provenance``
    as the pipeline set it, made virtual also where the metadata it carries say so (a result
    made outside the pipeline, an older results.json)."""
    given = dict(res.get("provenance") or {})
    from_md = provenance(res.get("metadata") or {})
    if not given:
        return from_md
    if from_md["virtual"] and not given.get("virtual"):
        return {**given, **{k: from_md[k] for k in ("bench", "seed", "generator")
                            if not given.get(k)}, "virtual": True,
                "evidence": sorted(set(given.get("evidence") or []) | set(from_md["evidence"]))}
    return given


def _json_source(path) -> dict:
    """A JSON result's ``source`` object as it stands ({} where none; unchecked)."""
    import json
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return {}
    src = doc.get(SOURCE) if isinstance(doc, dict) else None
    return src if isinstance(src, dict) else {}


def metadata_evidence(prov: Mapping) -> list[str]:
    """The metadata keys among a provenance's evidence (not the values' watermark, nor a
    derived result's source, :func:`source_evidence`)."""
    return [k for k in prov.get("evidence") or []
            if k.rsplit(":", 1)[-1] not in ("watermark", SOURCE)]


def source_evidence(prov: Mapping) -> list[str]:
    """The files among a provenance's evidence that are derived results whose ``source``
    (:func:`result_source`) says they were computed from the virtual bench's readings.

    >>> source_evidence({"evidence": ["tilt.json:source", "seed", "r.csv:watermark"]})
    ['tilt.json']
    """
    return [k.rsplit(":", 1)[0] for k in prov.get("evidence") or []
            if ":" in k and k.rsplit(":", 1)[-1] == SOURCE]


def watermark_chance(p) -> str:
    """The watermark test's tail probability as the notice prints it ("< 10⁻³⁰⁰" below
    that).

    >>> watermark_chance(7.46e-9), watermark_chance(0.0), watermark_chance(None)
    ('7.5×10⁻⁹', '< 10⁻³⁰⁰', '?')
    """
    if p is None:
        return "?"
    if p <= 1e-300:
        return "< 10⁻³⁰⁰"
    import math
    e = math.floor(math.log10(p))
    m = p / 10 ** e
    if round(m, 1) >= 10:
        m, e = m / 10, e + 1
    sup = str(e).translate(str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹"))
    return f"{m:.1f}×10{sup}"
