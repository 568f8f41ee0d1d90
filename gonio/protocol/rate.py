"""Reading the rate-gyro protocols (JJF 1535-2015, IEC 62047-20): every section checked
against its schema, numbers that may be the word "bench", the R5 rate series.

The specification packages hold the schemas; this module holds what they share.
"""

from __future__ import annotations

import math
from pathlib import Path

from gonio.errors import GonioError
from gonio.formats.rate_readings import COLUMN_RANGES
from gonio.formats.toml import Field, non_negative, positive, read_toml, validate_table
from gonio.resources import resolve


def r5_rates(lowest_dps: float, highest_dps: float) -> list[float]:
    """The R5 preferred-number rates of JJF 1535 7.2.1.1 c) (GB/T 321) from ``lowest`` up
    to ``highest``, with ``highest`` itself appended when it is not an R5 value.

    >>> r5_rates(1, 100)
    [1.0, 1.6, 2.5, 4.0, 6.3, 10.0, 16.0, 25.0, 40.0, 63.0, 100.0]
    >>> r5_rates(0.1, 75)[-3:]
    [40.0, 63.0, 75.0]
    """
    if not (0 < lowest_dps < highest_dps):
        raise GonioError(f"R5 rates need 0 < lowest < highest, got {lowest_dps}, {highest_dps}")
    base = (1.0, 1.6, 2.5, 4.0, 6.3)
    out: list[float] = []
    e = math.floor(math.log10(lowest_dps)) - 1
    while True:
        for b in base:
            v = float(f"{b * 10.0 ** e:.6g}")
            if v > highest_dps * (1 + 1e-12):
                if not out or abs(out[-1] - highest_dps) > 1e-9 * highest_dps:
                    out.append(float(highest_dps))
                return out
            if v >= lowest_dps * (1 - 1e-12):
                out.append(v)
        e += 1


def bench_or_float(x, where: str, file) -> float | str:
    """A protocol value that is a number or the word "bench" (taken from the bench)."""
    if x == "bench":
        return "bench"
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
        raise GonioError(f'expected a number or "bench", got {x!r}', file=file, key=where)
    return float(x)


def read_sections(path, schemas: dict[str, dict], spec_key: str,
                  bench_keys: tuple[tuple[str, str], ...] = ()) -> tuple[dict, Path]:
    """Read a rate protocol TOML: every section in ``schemas`` validated (unknown sections and
    keys refused), ``protocol.spec`` must equal ``spec_key``. The (section, key) pairs in
    ``bench_keys`` take a number or the word "bench" (default "bench")."""
    p = resolve(path, kind="protocol")
    raw = read_toml(p)
    head = raw.get("protocol")
    if isinstance(head, dict) and isinstance(head.get("spec"), str) and head["spec"] != spec_key:
        raise GonioError(f"this protocol is for {head['spec']!r}, but the calibration is for "
                         f"{spec_key!r} (--spec or the readings' '# spec:'): give a protocol "
                         f"for {spec_key!r}", file=p, key="protocol.spec")
    for sec in raw:
        if sec not in schemas:
            raise GonioError(f"unknown section (known: {', '.join(schemas)})", file=p, key=sec)
    held = {}
    for sec, key in bench_keys:
        tab = raw.get(sec)
        if isinstance(tab, dict) and key in tab:
            tab = dict(tab)
            held[(sec, key)] = bench_or_float(tab.pop(key), f"{sec}.{key}", p)
            raw = {**raw, sec: tab}
        else:
            held[(sec, key)] = "bench"
    out = {}
    for sec, schema in schemas.items():
        tab = raw.get(sec, {})
        if not isinstance(tab, dict):
            raise GonioError("expected a table", file=p, key=sec)
        out[sec] = validate_table(tab, schema, sec, p)
    if out["protocol"]["spec"] != spec_key:
        raise GonioError(f"this protocol is for {out['protocol']['spec']!r}, not {spec_key!r}",
                         file=p, key="protocol.spec")
    for (sec, key), v in held.items():
        out[sec][key] = v
    return out, p


PINT = Field("int", check=lambda x: x >= 1, expect="an integer ≥ 1")
PFLOAT = Field("float", check=positive, expect="> 0")
NNFLOAT = Field("float", default=0.0, check=non_negative, expect="≥ 0")


def _reader_temperature(x) -> bool:
    lo, hi, _ = COLUMN_RANGES["temperature_c"]
    return lo <= x <= hi


#: A chamber or room temperature of a rate protocol: within the range the readings reader
#: accepts (-300 °C was planned, simulated and then refused by the reader).
TEMP_C = Field("float", check=_reader_temperature,
               expect=COLUMN_RANGES["temperature_c"][2] + " (the readings' range)")


def rate_series(rates, highest: float, lowest: float):
    """One direction's rates: the explicit list, or R5 from lowest to highest."""
    if rates:
        return [float(r) for r in rates]
    return r5_rates(lowest, highest)


