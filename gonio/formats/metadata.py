"""The ``# key: value`` metadata lines shared by readings files and streams.

One place for the keys gonio understands, their plausible ranges, and the
number syntax every reader accepts (see ``docs/formats.md#metadata``).
"""

from __future__ import annotations

import csv
import math
import re
import unicodedata
from collections.abc import Mapping
from pathlib import Path

from gonio.errors import GonioError, check_not_binary
from gonio.units import ARCSEC_PER_DEG

def identity_text(text) -> str:
    """A person's name or an instrument's identifier (serial, model, manufacturer, a
    certificate's identifier) as compared for identity, everywhere gonio tells two such texts
    apart or matches them: Unicode compatibility forms folded (NFKC: full-width ``ＡＬＩＣＥ``
    is ``ALICE``, a ligature its letters), case folded (:meth:`str.casefold`, then NFKC
    again, as Unicode's compatibility caseless matching does), format characters that print
    as nothing removed (zero-width spaces, soft hyphens: category Cf), and runs of white space
    (any Unicode space, an ideographic one too) collapsed to one space, ends stripped; None
    is the empty text. Two
    texts that print the same to a reader are the same here, so a name or serial typed in
    another form neither passes as another person's or instrument's nor hides a match.

    >>> identity_text("  ＡＬＩＣＥ\u3000 Smith ") == identity_text("alice smith")
    True
    >>> identity_text("RLG\u200b-0001"), identity_text("Stra\u00dfe"), identity_text(None)
    ('rlg-0001', 'strasse', '')
    """
    folded = unicodedata.normalize("NFKC", unicodedata.normalize(
        "NFKC", "" if text is None else str(text)).casefold())
    shown = "".join(ch for ch in folded if unicodedata.category(ch) != "Cf")
    return " ".join(shown.split())


#: Metadata keys the package understands (others are kept).
KNOWN_METADATA: tuple[str, ...] = (
    "instrument", "serial", "manufacturer", "nominal_scale_factor_counts_per_deg",
    "latitude_deg", "temperature_c", "humidity_pct", "operator", "date", "table",
    "table_mpe_arcsec", "tilt_bound_deg", "counts_quantised", "table_accel_dps2",
    "gyro_type", "sf_temperature_coeff_bound_ppm_per_c", "thermometer_mpe_c",
    "static_record",
)
#: The readings' metadata keys that state the instrument's identity and the conditions, which
#: a laboratory file is compared with (:mod:`gonio.pipeline.identity`): every readings format
#: knows them, so a misspelt or wrongly cased one is refused, never kept aside uncompared.
IDENTITY_METADATA: tuple[str, ...] = ("serial", "model", "manufacturer", "gyro_type",
                                      "temperature_c", "room_temperature_c", "humidity_pct")
#: Other names a laboratory's logger writes for an identity or condition key (compared case
#: and separators folded: ``Serial-Number``, ``S/N``): a readings file using one is refused,
#: naming the key gonio compares, never kept aside uncompared beside it
#: (:func:`check_identity_synonyms`).
IDENTITY_SYNONYMS: dict[str, str] = {
    **{k: "serial" for k in ("serial_number", "serialnumber", "serial_no", "sn", "s_n",
                             "instrument_serial", "device_serial", "gyro_serial")},
    **{k: "model" for k in ("model_number", "model_no", "modelnumber", "instrument_model",
                            "type_designation")},
    **{k: "manufacturer" for k in ("maker", "make", "vendor", "mfr", "brand")},
    **{k: "temperature_c" for k in ("temperature", "temp", "temp_c", "ambient_temperature",
                                    "ambient_temperature_c", "room_temp", "room_temp_c",
                                    "lab_temperature_c", "t_c")},
    **{k: "humidity_pct" for k in ("humidity", "rh", "rh_pct", "relative_humidity",
                                   "relative_humidity_pct", "humidity_percent")},
}


def check_identity_synonyms(keys, file=None) -> None:
    """Refuse a metadata key that is another name for an identity or condition key
    (:data:`IDENTITY_SYNONYMS`, case, spaces, ``-`` and ``/`` folded to ``_``): a
    ``# serial_number: RLG-0999`` beside the laboratory file's RLG-0001 would otherwise be
    kept in results.json and compared with nothing.

    >>> check_identity_synonyms(["serial", "operator"])
    >>> check_identity_synonyms(["Serial-Number"], "r.csv")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: r.csv: key Serial-Number: another name for 'serial', which gonio compares with the laboratory file and the records: write it as '# serial: …' (a second name is never kept aside uncompared)
    """
    import re

    for key in keys:
        folded = re.sub(r"[\s/\-]+", "_", str(key).strip().casefold())
        want = IDENTITY_SYNONYMS.get(folded)
        if want is not None and key != want:
            raise GonioError(f"another name for {want!r}, which gonio compares with the "
                             f"laboratory file and the records: write it as '# {want}: …' "
                             "(a second name is never kept aside uncompared)",
                             file=None if file is None else str(file), key=str(key))


# numeric metadata: key -> (lower bound, lower inclusive, upper bound, description). Bounds come
# from physics (absolute zero, a percentage, a latitude, half a turn) and representability
# (1e-50 .. 1e50 where a number divides or scales data), not from the instruments one has in
# mind (UG-2's 834 m² ring was refused by such a bound).
NUMERIC_METADATA: dict[str, tuple[float, bool, float, str]] = {
    "nominal_scale_factor_counts_per_deg": (1e-50, True, 1e50, "a number in [1e-50, 1e50]"),
    "latitude_deg": (-90.0, True, 90.0, "a number in [-90, 90]"),
    "temperature_c": (-273.15, False, 1000.0, "a number in (-273.15, 1000]"),
    # the room's temperature where a file states it apart from the instrument's (compared
    # with the laboratory file's: a text that is no number would pass unread)
    "room_temperature_c": (-273.15, False, 1000.0, "a number in (-273.15, 1000]"),
    "humidity_pct": (0.0, True, 100.0, "a number in [0, 100]"),
    "table_mpe_arcsec": (0.0, True, 180 * ARCSEC_PER_DEG, "a number in [0, 648000]"),
    "tilt_bound_deg": (0.0, True, 45.0, "a number in [0, 45]"),
    "table_accel_dps2": (1e-50, True, 1e50, "a number in [1e-50, 1e50]"),
    # a bound of K's temperature coefficient: zero would claim a perfect instrument
    "sf_temperature_coeff_bound_ppm_per_c": (0.0, False, 1e4, "a number in (0, 1e4]"),
    # the chamber thermometer's maximum permissible error, °C (0: taken as exact)
    "thermometer_mpe_c": (0.0, True, 100.0, "a number in [0, 100]"),
}
_TRUE = ("true", "yes", "1")
_FALSE = ("false", "no", "0")
_NUMBER = re.compile(r"^[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?$")
_NONFINITE = re.compile(r"^[+-]?(nan|inf|infinity)$", re.IGNORECASE)


def is_comment(line: str) -> bool:
    """Whether ``line`` is a ``#`` metadata line: ``#`` first (after a byte-order mark and
    blanks), or the same line as a spreadsheet re-saves it, quoted as one cell (``"# …"``).

    >>> is_comment("  # serial: A"), is_comment('"# table: a, b",,'), is_comment("t,#")
    (True, True, False)
    """
    s = line.lstrip("\ufeff \t")
    return s.startswith("#") or s.startswith('"#')


def comment_body(line: str) -> str:
    """The text after the ``#`` of a metadata line (:func:`is_comment`), as it was written
    before a spreadsheet re-saved the file: one level of CSV quoting taken off (the line as
    one quoted cell) and the empty cells a spreadsheet pads every row with to the widest row
    (trailing commas) dropped. The one reading of a ``#`` line shared by every reader
    (docs/formats.md#metadata: files re-saved by a spreadsheet).

    >>> comment_body("# serial: RLG-0001,,,,,,")
    'serial: RLG-0001'
    >>> comment_body('"# table: a, b",,,')
    'table: a, b'
    >>> comment_body("# table: rotary table, 0.1 arcsec,,")
    'table: rotary table, 0.1 arcsec'
    """
    s = line.strip().lstrip("\ufeff").strip()
    if s.startswith('"#'):
        try:
            s = next(csv.reader([s]))[0]
        except (csv.Error, StopIteration):
            pass
    s = s.rstrip(", \t")
    return (s[1:] if s.startswith("#") else s).strip()


def header_lines(path):
    """The leading ``# key: value`` lines of a text file (a stream of gigabytes is never
    read whole), as (key, value) pairs in file order (a line without ``:`` gives the value
    ``""``). A binary file or one that is not UTF-8 is a GonioError naming it.

    >>> import tempfile, os
    >>> with tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False) as f:
    ...     _ = f.write(chr(0xFEFF) + "# spec: x" + 2 * chr(10) + "# protocol : p" + chr(10)
    ...                 + "t,v" + chr(10) + "# not: metadata" + chr(10))
    >>> list(header_lines(f.name))
    [('spec', 'x'), ('protocol', 'p')]
    >>> os.remove(f.name)
    """
    fh = open(path, "rb")
    with fh:
        head = b""
        done = 0                                   # complete lines already yielded
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
            for line in complete[done:]:
                s = line.strip()
                if not s:
                    continue
                if not is_comment(s):
                    return
                key, _, value = comment_body(s).partition(":")
                yield key.strip(), value.strip()
            done = len(complete)
            if not piece:
                return


def metadata_block(lines, file=None) -> tuple[dict[str, str], int]:
    """The ``# key: value`` lines at the top of a file's ``lines`` (blank lines and a bare
    ``#`` among them allowed) as a dict, and the index of the first line after them (the
    header row). The one parser of a metadata block held in memory, shared by the triad's
    readings and the optical draft's static record; a line without ``:`` or a key given
    twice is a GonioError naming ``file`` and the line (nothing silently overridden).

    >>> metadata_block(["# format: x", "", "#", "# k : v ", "t,v", "1,2"])
    ({'format': 'x', 'k': 'v'}, 4)
    >>> metadata_block(["# a: 1", "# a: 2"], "f.csv")
    Traceback (most recent call last):
    gonio.errors.GonioError: f.csv:2: metadata key 'a' given twice
    """
    meta: dict[str, str] = {}
    i = 0
    while i < len(lines) and (is_comment(lines[i]) or not lines[i].strip()):
        body = comment_body(lines[i]).strip() if is_comment(lines[i]) else ""
        if body:
            if ":" not in body:
                raise GonioError("metadata line must be '# key: value'", file=file, line=i + 1)
            k, v = body.split(":", 1)
            k = k.strip()
            if k in meta:
                raise GonioError(f"metadata key {k!r} given twice", file=file, line=i + 1)
            meta[k] = v.strip()
        i += 1
    return meta, i


def named_files(path, key: str) -> list[Path]:
    """The files a readings file names as part of its data by its ``# key:`` metadata line
    (relative to its folder), read from its leading metadata lines (:func:`header_lines`;
    a stream is never read whole). An unreadable or binary file names nothing: its reader
    reports it (the triad's ``# thermal_readings:``, the optical draft's
    ``# static_record:``)."""
    out: list[Path] = []
    try:
        pairs = list(header_lines(path))
    except (OSError, GonioError):
        return out
    for k, v in pairs:
        if k == key and v:
            p = Path(v)
            out.append(p if p.is_absolute() else Path(path).parent / p)
    return out


def metadata_float(metadata: Mapping[str, str], key: str, *,
                   file: str | Path | None = None) -> float | None:
    """The numeric metadata value ``key``, validated, or None when absent.

    >>> metadata_float({"latitude_deg": "39.9"}, "latitude_deg")
    39.9
    >>> metadata_float({}, "latitude_deg") is None
    True
    """
    if key not in metadata:
        return None
    text = str(metadata[key]).strip()
    lo, lo_incl, hi, expected = NUMERIC_METADATA.get(
        key, (-math.inf, True, math.inf, "a finite number"))
    value = parse_number(text)
    if value is None or not math.isfinite(value):
        raise GonioError(f"expected {expected}, got {show_value(text)}", file=file, key=key)
    if value < lo or (value == lo and not lo_incl) or value > hi:
        raise GonioError(f"expected {expected}, got {show_value(text)}", file=file, key=key)
    return value


#: Gyro types a readings file may state (metadata ``gyro_type``): ring-laser, fibre-optic.
GYRO_TYPES: tuple[str, ...] = ("rlg", "fog")


def metadata_gyro_type(metadata: Mapping[str, str], *,
                       file: str | Path | None = None) -> str | None:
    """The instrument's gyro type stated by the metadata (``gyro_type``: ``rlg`` or ``fog``,
    case ignored), or None when absent; any other value is a GonioError naming the key.

    >>> metadata_gyro_type({"gyro_type": " FOG"}), metadata_gyro_type({}) is None
    ('fog', True)
    """
    if "gyro_type" not in metadata:
        return None
    v = str(metadata["gyro_type"]).strip().lower()
    if v not in GYRO_TYPES:
        raise GonioError(f"expected one of {', '.join(GYRO_TYPES)}, got "
                         f"{show_value(str(metadata['gyro_type']))}", file=file, key="gyro_type")
    return v


def metadata_bool(metadata: Mapping[str, str], key: str, default: bool, *,
                  file: str | Path | None = None) -> bool:
    """The boolean metadata value ``key`` (true/false, yes/no, 1/0), or ``default``.

    >>> metadata_bool({"counts_quantised": "false"}, "counts_quantised", True)
    False
    """
    if key not in metadata:
        return default
    text = str(metadata[key]).strip().lower()
    if text in _TRUE:
        return True
    if text in _FALSE:
        return False
    raise GonioError(f"expected true or false, got {show_value(metadata[key])}", file=file,
                     key=key)


def show_value(text) -> str:
    """A value for an error message: quoted, at most 40 characters (a 5000-digit value is
    not echoed whole).

    >>> show_value("9" * 50)
    "'9999999999999999999999999999999999999999…(50 chars)'"
    """
    text = str(text)
    return repr(text if len(text) <= 40 else text[:40] + f"…({len(text)} chars)")


def parse_number(text: str) -> float | None:
    """float of a plain decimal number text, inf/nan for those words, else None.

    Only ASCII digits count (``str.isdigit`` would also accept other scripts' digits).

    >>> parse_number("-1.5e3"), parse_number("inf"), parse_number("1,5")
    (-1500.0, inf, None)
    """
    if _NONFINITE.match(text):
        return float(text)
    if not _NUMBER.match(text):
        return None
    return float(text)



def logged_median(path, column: str = "temperature_c", skip=None) -> tuple[float, int] | None:
    r"""The median of the finite values a CSV table (``#`` comment lines above or among its
    rows) or a Parquet stream logged in ``column``, and how many rows gave one: (median, n);
    None where the table has no such column or no finite value in it (a blank between a slow
    logger's rows, a null, is no value; a Parquet file that cannot be read gives None, its
    reader then names the fault). ``skip(header, row)``: CSV rows left out (a rate file's
    chamber tests). Read row by row, for the identity check's ``measured_conditions``.

    >>> import tempfile, os
    >>> d = tempfile.mkdtemp(); f = os.path.join(d, "r.csv")
    >>> _ = open(f, "w").write("# serial: A-1\ntest,temperature_c\nb,20.0\nb,\nb,20.4\n")
    >>> logged_median(f)
    (20.2, 2)
    """
    import csv
    import math
    import statistics
    from pathlib import Path

    values = []
    if Path(path).suffix.lower() == ".parquet":
        if skip is not None:
            raise ValueError("skip applies to CSV rows only")
        import pyarrow.parquet as pq

        try:
            if column not in pq.read_schema(path).names:
                return None
            col = pq.read_table(path, columns=[column]).column(0).to_pylist()
        except (OSError, ValueError):
            return None
        values = [float(v) for v in col if isinstance(v, (int, float)) and math.isfinite(v)]
        return (statistics.median(values), len(values)) if values else None
    with open(path, encoding="utf-8-sig", newline="") as fh:
        rows = csv.reader(line for line in fh if line.strip() and not is_comment(line))
        header = [h.strip() for h in next(rows, [])]
        if column not in header:
            return None
        ic = header.index(column)
        for row in rows:
            if len(row) <= ic or not row[ic].strip() or (skip is not None and skip(header, row)):
                continue
            v = parse_number(row[ic])
            if v is not None and math.isfinite(v):
                values.append(v)
    return (statistics.median(values), len(values)) if values else None
