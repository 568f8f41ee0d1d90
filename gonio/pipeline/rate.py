"""Rate-gyro pipelines: simulate, calibrate, demo and budget for the rate-gyro
specifications (``jjf1535-2015``, ``iec62047-20``), looked up through :mod:`gonio.specs`.

Every function returns data (paths, results); the CLI (``gonio simulate/calibrate/demo/
budget --spec …``) is a thin layer over them.
"""

from __future__ import annotations

import importlib
import json
from pathlib import Path

from gonio.atomic import output_dir, write_text
from gonio.errors import GonioError, check_input_file, check_not_binary, read_utf8
from gonio.analysis.conformity import decide_result
from gonio.result.tables import write_results
from gonio.specs import Specification, get
from gonio.specs._rate_family.rate_records import json_safe, load_readings
from gonio.formats.triad import FORMAT as TRIAD_FORMAT

#: The specifications handled here (the optical draft keeps its own pipeline).
RATE_SPECS = ("jjf1535-2015", "iec62047-20")


def spec_module(spec: Specification):
    """The package of a specification (it holds ``calibrate``, ``SPEC``)."""
    return importlib.import_module(spec.calibrate.__module__)


def spec_simulator(spec: Specification):
    """The specification's ``simulate`` function (its ``simulate`` module, the only one that
    imports the virtual bench)."""
    return importlib.import_module(f"{spec_module(spec).__name__}.simulate").simulate


def readings_spec(path: str | Path) -> str | None:
    """The ``# spec: …`` metadata of a readings file (None when absent).

    Only the metadata lines at the top are read (a stream of gigabytes is never read
    whole); a Parquet stream's key-value metadata is looked up instead.
    """
    check_input_file(path, "readings file")     # a FIFO or /dev/zero is refused before reading
    if Path(path).suffix.lower() == ".parquet":
        from gonio.formats.streams import StreamFile
        return StreamFile(path).metadata.get("spec")
    try:
        fh = open(path, "rb")
    except OSError:
        read_utf8(path, "readings file")       # the one-line error naming the file
        raise
    with fh:
        head = b""
        while True:
            piece = fh.read(1 << 16)
            if not head:
                check_not_binary(piece, path)      # a Parquet file renamed .csv says so
            head += piece
            try:
                text = head.decode("utf-8")
            except UnicodeDecodeError as exc:
                if exc.start < len(head) - 4 or not piece:
                    raise GonioError(f"not UTF-8 text (byte {exc.start})", file=path,
                                     line=head[:exc.start].count(b"\n") + 1) from None
                continue                           # a character cut at the piece's end
            lines = text.lstrip("\ufeff").splitlines()
            complete = lines if not piece else lines[:-1]
            for line in complete:
                s = line.strip()
                if not s:
                    continue
                if not s.startswith("#"):
                    return None
                key, _, value = s[1:].partition(":")
                if key.strip() == "spec":
                    return value.strip()
                if key.strip() == "format" and value.strip() == TRIAD_FORMAT:
                    return "triad-alignment"        # a triad file without '# spec:'

            if not piece:
                return None


def simulate(spec_key: str, out: str | Path, *, bench: str | None = None,
             protocol: str | None = None, seed: int = 0, noise: bool = True) -> dict[str, Path]:
    """Run the specification's programme on a rate bench; write ``readings.csv`` (the
    rate readings format, docs/formats.md#rate-gyro-readings-file) and ``truth.json``."""
    from gonio.bench.rate_gyro import load_rate_bench
    from gonio.formats.rate_readings import write_rate_readings

    spec = get(spec_key)
    if spec.key not in RATE_SPECS:
        raise GonioError(f"{spec.key} is not a rate-gyro specification", key="--spec")
    b = load_rate_bench(bench or spec.default_bench)
    res = spec_simulator(spec)(b, protocol or spec.default_protocol, seed, noise=noise)
    out = Path(out)
    with output_dir(out) as stage:
        write_rate_readings(res.data, res.metadata, stage / "readings.csv")
        write_text(stage / "truth.json", json.dumps(json_safe(res.truth), indent=2,
                                                    ensure_ascii=False, allow_nan=False) + "\n")
    return {"readings": out / "readings.csv", "truth": out / "truth.json"}


def calibrate(readings: str | Path, out: str | Path, *, spec_key: str | None = None,
              protocol: str | None = None, lab=None, lang: str = "en",
              truth: dict | None = None, monte_carlo_trials: int = 0, dcc: bool = False):
    """Calibrate a rate readings file: ``results.json``, ``summary.txt`` and the certificate
    (HTML, PDF; with ``dcc`` also the DCC XML ``certificate.dcc.xml``) in ``out``. The
    specification is ``spec_key`` or the file's ``# spec:``."""
    from gonio.report.certificate import load_lab
    from gonio.report.rate_certificate import write_rate_certificate

    key = spec_key or readings_spec(readings)
    if key is None:
        raise GonioError("the readings name no specification (metadata '# spec: …'); "
                         "give --spec", file=readings)
    spec = get(key)
    lab_d = load_lab(lab) if isinstance(lab, (str, Path)) else lab
    rd = load_readings(readings)
    if protocol is None:                       # the readings' '# protocol:', never ignored
        from gonio.resources import readings_protocol
        protocol = readings_protocol(rd.metadata.get("protocol"), readings,
                                     spec.default_protocol)
    result = spec.calibrate(rd, protocol or spec.default_protocol,
                            monte_carlo_trials=monte_carlo_trials)
    decide_result(result, lab_d)
    out = Path(out)
    paths = write_results(result, out)
    paths.update(write_rate_certificate(result, out, truth=truth, lab=lab_d, lang=lang,
                                        dcc=dcc))
    return result, paths


def demo(spec_key: str, out: str | Path, *, bench: str | None = None, seed: int = 0,
         lab=None, lang: str = "en", dcc: bool = True, force: bool = False, inputs=()):
    """Simulate the whole programme and calibrate it: readings, truth, results, certificate
    and (``dcc``) its DCC XML.

    Like the optical demo (:func:`gonio.pipeline.demo.demo`), the whole set (readings.csv,
    truth.json, results, summary, certificate, DCC, manifest) is staged and swapped into ``out``
    together (:func:`gonio.atomic.output_set`): a run that fails at any point leaves the
    previous set as it was, and an existing readings.csv there is replaced only with
    ``force``. ``inputs`` (the lab and bench files) are never replaced.
    """
    from gonio.atomic import output_set

    lab_d = None
    if isinstance(lab, (str, Path)):
        from gonio.report.certificate import load_lab
        lab_d = load_lab(lab)                  # validate inputs before simulating
    else:
        lab_d = lab
    ins = [x for x in (*inputs, lab, bench) if isinstance(x, (str, Path)) and str(x)]
    with output_set(out, inputs=ins, force=force) as stage:
        simulate(spec_key, out, bench=bench, seed=seed)      # into the staging folder
        truth = json.loads((stage / "truth.json").read_text(encoding="utf-8"))
        result, paths = calibrate(stage / "readings.csv", out, spec_key=spec_key, lab=lab_d,
                                  lang=lang, truth=truth, dcc=dcc)
    out = Path(out)
    return result, {"readings": out / "readings.csv", "truth": out / "truth.json", **paths}


def budget(spec_key: str):
    """The specification's own annex budget, reproduced (``SPEC.budget()``)."""
    spec = get(spec_key)
    if spec.budget is None:
        raise GonioError(f"{spec.key} has no annex budget", key="--spec")
    return spec.budget()
