"""The one place the records call gonio's calibration pipeline and its renderers.

:func:`calibrate_folder` turns a readings file into gonio's output set (results.json,
summary.txt, certificate.html/.pdf and, where the specification has one, the DCC) in a
folder, for any specification, with a laboratory details file; :func:`render_folder` renders
the certificate of a stored results.json again, with the final laboratory details, and
computes nothing (the issue of a reviewed, sealed result). The worker
(:mod:`gonio.records.worker`) runs both in its own process. :func:`write_lab_toml` writes the
laboratory details the records assemble (``gonio.formats.lab.LAB_SCHEMA``) as the
TOML file the pipeline reads, so the certificate is validated exactly as on the command line.
"""

from __future__ import annotations

import contextlib
import json
import tempfile
from pathlib import Path

from gonio.atomic import write_text
from gonio.errors import GonioError

#: a readings file whose first bytes are these is a Parquet stream
PARQUET_MAGIC = b"PAR1"


def readings_suffix(head: bytes) -> str:
    """The file name suffix a stored readings file is given in a work folder (its content
    decides, never the uploaded name): ``.parquet`` for a Parquet stream, else ``.csv``.

    >>> readings_suffix(b"PAR1...."), readings_suffix(b"# spec: x")
    ('.parquet', '.csv')
    """
    return ".parquet" if head[:4] == PARQUET_MAGIC else ".csv"


@contextlib.contextmanager
def readings_file(src: str | Path):
    """A stored readings file ``src`` under the name the pipeline reads it by
    (``readings`` + :func:`readings_suffix` of its content) in a temporary folder, for as
    long as the ``with`` block runs (a link: nothing is copied)."""
    with open(src, "rb") as fh:
        suffix = readings_suffix(fh.read(4))
    with tempfile.TemporaryDirectory(prefix="gonio-readings-") as tmp:
        path = Path(tmp) / ("readings" + suffix)
        path.symlink_to(Path(src).resolve())
        yield path


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float) and _toml_number_text(v):
        return v.text            # a number written with its digits (WrittenNumber)
    if isinstance(v, (int, float)):
        return repr(float(v)) if isinstance(v, float) else str(v)
    # a JSON string is a valid TOML basic string (\uXXXX escapes for control characters)
    return json.dumps(str(v), ensure_ascii=False)


def _toml_number_text(v: float) -> bool:
    """Whether ``v`` carries a text (:class:`gonio.formats.lab.WrittenNumber`) that TOML reads
    as the number ``v`` ("20" and "20.0" both 20: the file keeps the digits written)."""
    import tomllib

    text = getattr(v, "text", None)
    if not isinstance(text, str) or not text or "\n" in text:
        return False
    try:
        return float(tomllib.loads(f"x = {text}")["x"]) == float(v)
    except (tomllib.TOMLDecodeError, TypeError, ValueError):
        return False


def lab_toml(lab: dict) -> str:
    """The laboratory details as TOML (tables and arrays of tables; None values left out).

    >>> print(lab_toml({"laboratory": {"name": 'A "B"', "x": None}, "standards": [{"name": "T"}]}))
    [laboratory]
    name = "A \\"B\\""
    <BLANKLINE>
    [[standards]]
    name = "T"
    <BLANKLINE>
    """
    lines: list[str] = []
    for section, body in lab.items():
        rows = body if isinstance(body, list) else [body]
        for row in rows:
            if row is None:
                continue
            lines.append(f"[[{section}]]" if isinstance(body, list) else f"[{section}]")
            lines += [f"{k} = {_toml_value(v)}" for k, v in row.items() if v is not None]
            lines.append("")
    return "\n".join(lines)


def write_lab_toml(lab: dict, path: str | Path) -> Path:
    """Write :func:`lab_toml` to ``path`` (atomically)."""
    return write_text(path, lab_toml(lab))


def calibrate_folder(readings: str | Path, out: str | Path, *, spec_key: str,
                     protocol: str | None = None, lab: str | Path | None = None,
                     table_calibration: str | Path | None = None,
                     gyro_type: str | None = None, options: dict | None = None,
                     record: dict | None = None) -> list[str]:
    """Calibrate ``readings`` per ``spec_key`` into ``out`` with the certificate (and the DCC
    where the specification writes one), through the one dispatch
    (:func:`gonio.pipeline.dispatch.calibrate`); ``table_calibration``: the calibration's
    stored table calibration file (its ``table_calibration`` option); ``gyro_type``: the
    optical-gyro type its ``gyro_type`` option is given (``calibrate --record``'s registered
    instrument's, where the specification takes one); ``options``: the other options it is
    computed with (an imported folder's, as its manifest records them:
    :func:`gonio.records.importer.recorded_options`; None: the defaults); ``record``: the
    registered instrument's identity the readings are checked against, as ``gonio calibrate
    --record`` gives it (its findings the same); returns the file names written."""
    from gonio.pipeline.dispatch import calibrate
    from gonio.specs import get

    spec = get(spec_key)                      # an unknown key: GonioError listing the known
    out = Path(out)
    takes = spec.calibrate_options
    extra = {"table_calibration": str(table_calibration)} if table_calibration else {}
    if gyro_type and "gyro_type" in takes:
        extra["gyro_type"] = gyro_type
    extra.update(options or {})
    calibrate(readings, out, spec_key=spec.key, lab=lab, dcc="dcc" in takes,
              protocol=protocol if "protocol" in takes else None,
              inputs=[readings, protocol, lab, table_calibration], record=record, **extra)
    return sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())


def render_folder(results: bytes, out: str | Path, *, spec_key: str, lab: str | Path,
                  lang: str = "en") -> list[str]:
    """The certificate (HTML, PDF and, where the specification writes one, the DCC) of a
    stored results.json ``results`` (its bytes), rendered into ``out`` by the
    specification's renderer (``SPEC.outputs`` ``write``) with the laboratory details file
    ``lab``, in ``lang``: a pure function of these, nothing recomputed — the conformity decisions,
    provenance and findings are the stored result's own. Returns the file names written."""
    from gonio.pipeline.dispatch import load_lab_file
    from gonio.result.model import Result
    from gonio.specs import get

    spec = get(spec_key)
    lab_d = load_lab_file(lab, spec)
    try:
        doc = json.loads(results)
    except ValueError as exc:
        raise GonioError(f"the stored results.json is not JSON ({exc})", key="results") from None
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    spec.renderer().write(Result.from_json(doc), out, lab=lab_d, lang=lang,
                          dcc="dcc" in spec.calibrate_options)
    return sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())

