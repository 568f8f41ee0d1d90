"""A small validator for the project's TOML files (protocols, benches, certificate details).

A schema is a mapping ``key -> Field``; :func:`validate_table` checks a parsed
table against it and returns a plain dict with defaults filled in. An unknown
key, a missing required key, a wrong type or an impossible value raises a
:class:`~gonio.errors.GonioError` naming the file and the dotted key.
"""

from __future__ import annotations

import math
import re
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from gonio.errors import GonioError, read_utf8

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

REQUIRED = object()


@dataclass(frozen=True)
class Field:
    """One key of a schema: its type, default, a check and what the check means."""

    kind: str                         # float, int, bool, str, float_list, str_list, table_list, table
    default: Any = REQUIRED
    check: Callable[[Any], bool] | None = None
    expect: str = ""                  # what a valid value is, for the error message
    choices: tuple | None = None
    schema: dict | None = None        # for table / table_list


def positive(x) -> bool:
    return x > 0


def non_negative(x) -> bool:
    return x >= 0


#: Deepest nesting of brackets/braces and longest dotted key accepted in a TOML file.
MAX_TOML_DEPTH: int = 32
MAX_TOML_KEY_PARTS: int = 32
#: Largest magnitude of any number in a TOML file (docs/formats.md, "Plausible ranges");
#: non-zero magnitudes below ``MIN_TOML_MAGNITUDE`` (subnormal-like) are refused too.
MAX_TOML_MAGNITUDE: float = 1e12
MIN_TOML_MAGNITUDE: float = 1e-15
MAX_TOML_INT: int = 10 ** 9


def _check_nesting(text: str, path) -> None:
    """Refuse brackets nested deeper than MAX_TOML_DEPTH and long dotted keys, before parsing.

    A coarse scan outside strings and comments (the parser recurses per level); the
    line of the first offence is named.
    """
    depth = 0
    line = 1
    quote = None
    dots = 0
    i, n = 0, len(text)
    while i < n:
        ch = text[i]
        if ch == "\n":
            line += 1
            dots = 0
            if quote in ('"', "'"):
                quote = None
        elif quote is not None:
            if ch == "\\" and quote in ('"', '"""'):
                i += 2
                continue
            if text.startswith(quote, i):
                i += len(quote)
                quote = None
                continue
        elif ch == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        elif ch in "\"'":
            quote = ch * 3 if text.startswith(ch * 3, i) else ch
            i += len(quote)
            continue
        elif ch in "[{":
            depth += 1
            if depth > MAX_TOML_DEPTH:
                raise GonioError(f"nested deeper than {MAX_TOML_DEPTH} levels", file=path,
                                 line=line)
        elif ch in "]}":
            depth = max(0, depth - 1)
        elif ch == "." and not (i > 0 and text[i - 1].isdigit()
                                and i + 1 < n and text[i + 1].isdigit()):   # not a float's point
            dots += 1
            if dots > MAX_TOML_KEY_PARTS * 4:
                raise GonioError(f"a line with more than {MAX_TOML_KEY_PARTS * 4} dots (dotted "
                                 "key too long)", file=path, line=line)
        i += 1


def read_toml(path: str | Path, limit_bytes: float | None = None) -> dict:
    """Parse a TOML file; a syntax error is a GonioError naming the file and line.

    Refused before parsing: a special file, a file over ``GONIO_MAX_TOML_BYTES``
    (1 MiB), nesting deeper than :data:`MAX_TOML_DEPTH`, over-long dotted keys.
    """
    from gonio.limits import limit

    path = Path(path)
    text = read_utf8(path, "TOML file", limit("GONIO_MAX_TOML_BYTES")
                     if limit_bytes is None else limit_bytes)
    _check_nesting(text, path)
    try:
        return tomllib.loads(text)
    except RecursionError:
        raise GonioError("nested too deeply", file=path) from None
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"at line (\d+)", str(exc))
        line = int(m.group(1)) if m else getattr(exc, "lineno", None)
        if line is None and "end of document" in str(exc):
            line = text.count("\n") + 1
        raise GonioError(f"TOML syntax: {exc}", file=path, line=line) from None


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:40] + f"…({len(text)} chars)"


def _coerce(value, f: Field, where: str, file):
    def bad(msg):
        raise GonioError(msg, file=file, key=where)

    k = f.kind
    if k == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            bad(f"expected a number, got {type(value).__name__} {_short(value)}")
        value = float(value)
        if not math.isfinite(value):
            bad(f"expected a finite number, got {value}")
        if abs(value) > MAX_TOML_MAGNITUDE or 0 < abs(value) < MIN_TOML_MAGNITUDE:
            bad(f"{value:g} is outside the plausible magnitudes [{MIN_TOML_MAGNITUDE:g}, "
                f"{MAX_TOML_MAGNITUDE:g}] (docs/formats.md)")
    elif k == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            bad(f"expected an integer, got {type(value).__name__} {_short(value)}")
        if abs(value) > MAX_TOML_INT:
            bad(f"{_short(value)} is outside the plausible range ±{MAX_TOML_INT:g}")
    elif k == "bool":
        if not isinstance(value, bool):
            bad(f"expected true or false, got {_short(value)}")
    elif k == "str":
        if not isinstance(value, str):
            bad(f"expected text, got {type(value).__name__} {_short(value)}")
    elif k in ("float_list", "str_list"):
        if not isinstance(value, list) or not value:
            bad(f"expected a non-empty list, got {_short(value)}")
        inner = Field("float" if k == "float_list" else "str", choices=f.choices)
        value = [_coerce(v, inner, f"{where}[{i}]", file) for i, v in enumerate(value)]
        if f.check is not None and not all(f.check(v) for v in value):
            bad(f"expected {f.expect}, got {_short(value)}")
        return value
    elif k == "table":
        if not isinstance(value, dict):
            bad(f"expected a table, got {_short(value)}")
        return validate_table(value, f.schema or {}, where, file)
    elif k == "table_list":
        if not isinstance(value, list) or not value or not all(isinstance(v, dict) for v in value):
            bad("expected a non-empty list of tables")
        return [validate_table(v, f.schema or {}, f"{where}[{i}]", file) for i, v in enumerate(value)]
    else:  # pragma: no cover - programming error
        raise AssertionError(k)
    if f.choices is not None and value not in f.choices:
        bad(f"expected one of {', '.join(map(str, f.choices))}, got {_short(value)}")
    if f.check is not None and not f.check(value):
        bad(f"expected {f.expect}, got {_short(value)}")
    return value


def validate_table(table: dict, schema: dict[str, Field], prefix: str = "",
                   file: str | Path | None = None) -> dict:
    """Check ``table`` against ``schema``; return a dict with defaults filled in.

    >>> s = {"rate_dps": Field("float", check=positive, expect="> 0"),
    ...      "series": Field("int", default=1)}
    >>> validate_table({"rate_dps": 60}, s)
    {'rate_dps': 60.0, 'series': 1}
    >>> validate_table({"rate_dps": -1}, s, "scale_factor", "p.toml")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: p.toml: key scale_factor.rate_dps: expected > 0, got -1.0
    """
    out = {}
    for key in table:
        if key not in schema:
            raise GonioError(f"unknown key (known: {', '.join(schema)})", file=file,
                             key=f"{prefix}.{key}" if prefix else key)
    for key, f in schema.items():
        where = f"{prefix}.{key}" if prefix else key
        if key in table:
            out[key] = _coerce(table[key], f, where, file)
        elif f.default is REQUIRED:
            raise GonioError("required key is missing", file=file, key=where)
        else:
            out[key] = f.default
    return out


#: Longest text a laboratory file's field may hold (a name, an address, a note): a page
#: lays it out, and a megabyte of name is a mistake, not a laboratory.
MAX_TEXT_FIELD = 2000
#: Characters a certificate never carries: C0 controls but tab and line feed, DEL, C1
#: controls, and the Unicode non-characters (U+FDD0–U+FDEF, U+xFFFE, U+xFFFF).
_BAD_TEXT = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\ufdd0-\ufdef\ufffe\uffff]")


def check_text_fields(table, path, prefix: str = "", limit: int = MAX_TEXT_FIELD) -> None:
    """Every string in a TOML table (nested tables and arrays too): at most ``limit``
    characters and no control or non-character code point; a GonioError names the key
    (``laboratory.name``, ``standards[2].id``) and the code point.

    >>> check_text_fields({"laboratory": {"name": "A\\x01B"}}, "lab.toml")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: lab.toml: key laboratory.name: control character U+0001 at position 2; certificates carry printable text only
    """
    items = table.items() if isinstance(table, dict) else enumerate(table)
    for k, v in items:
        key = f"{prefix}[{k}]" if isinstance(table, list) else (f"{prefix}.{k}" if prefix else str(k))
        if isinstance(v, (dict, list)):
            check_text_fields(v, path, key, limit)
        elif isinstance(v, str):
            if len(v) > limit:
                raise GonioError(f"text of {len(v)} characters, over the limit of {limit}",
                                 file=path, key=key)
            m = _BAD_TEXT.search(v)
            if m:
                raise GonioError(f"control character U+{ord(m.group()):04X} at position "
                                 f"{m.start() + 1}; certificates carry printable text only",
                                 file=path, key=key)
