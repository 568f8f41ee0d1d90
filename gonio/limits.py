"""Stated limits on inputs and work, each configurable by an environment variable.

A run that would exceed a limit is refused before the work starts, with a
GonioError naming the key or option, the estimate and the variable that raises
the limit. The values and the physically plausible ranges of every numeric
input are listed in docs/formats.md ("Plausible ranges").

=========================  ============================  =====================
limit                      environment variable          default
=========================  ============================  =====================
readings / stream file     GONIO_MAX_INPUT_BYTES         2 GiB
TOML file (protocol...)    GONIO_MAX_TOML_BYTES          1 MiB
simulated samples/session  GONIO_MAX_SAMPLES             4e8
simulated session time     GONIO_MAX_SESSION_S           2 days (172 800 s)
estimated simulation time  GONIO_MAX_RUN_S               300 s of computing
items (rounds x series..)  GONIO_MAX_READINGS            1e6 readings
rows of a readings file    GONIO_MAX_READING_ROWS        1e6 rows (memory: ~0.9 GB)
Monte Carlo trials         GONIO_MAX_MONTE_CARLO         1e7
validate trials per case   GONIO_MAX_TRIALS              1e5
worker processes           GONIO_MAX_WORKERS             the machine's cores
readings upload (web)      GONIO_MAX_UPLOAD_BYTES        256 MiB (plus 3 MiB for the form)
backup archive (expanded)  GONIO_MAX_BACKUP_BYTES        8 GiB (an upload and all members)
records.json of a backup   GONIO_MAX_RECORDS_JSON_BYTES  1 GiB (read into memory)
replaced SQLite files kept GONIO_KEEP_REPLACED           3 (the newest; a whole number ≥ 1)
=========================  ============================  =====================
"""

from __future__ import annotations

import os

from gonio.errors import MAX_INPUT_BYTES, GonioError

_DEFAULTS: dict[str, float] = {
    "GONIO_MAX_INPUT_BYTES": MAX_INPUT_BYTES,
    "GONIO_MAX_TOML_BYTES": 1024 ** 2,
    "GONIO_MAX_SAMPLES": 4e8,
    "GONIO_MAX_SESSION_S": 172_800.0,
    "GONIO_MAX_RUN_S": 300.0,
    "GONIO_MAX_READINGS": 1e6,
    "GONIO_MAX_READING_ROWS": 1e6,
    "GONIO_MAX_MONTE_CARLO": 1e7,
    "GONIO_MAX_TRIALS": 1e5,
    "GONIO_MAX_UPLOAD_BYTES": 256 * 1024 ** 2,
    "GONIO_MAX_BACKUP_BYTES": 8 * 1024 ** 3,
    "GONIO_MAX_RECORDS_JSON_BYTES": 1024 ** 3,
}


def limit(name: str) -> float:
    """The limit ``name`` (an environment variable overrides the default).

    >>> limit("GONIO_MAX_MONTE_CARLO")
    10000000.0
    """
    if name == "GONIO_MAX_WORKERS":
        default = float(os.cpu_count() or 1)
    else:
        default = _DEFAULTS[name]
    text = os.environ.get(name, "").strip()
    if not text:
        return float(default)
    try:
        v = float(text)
    except ValueError:
        raise GonioError(f"environment variable {name} must be a number, got {text[:40]!r}") \
            from None
    if not v > 0:
        raise GonioError(f"environment variable {name} must be > 0, got {text[:40]!r}")
    return v


def check(name: str, value: float, what: str, *, unit: str = "") -> None:
    """GonioError when ``value`` exceeds the limit ``name``; names ``what`` and the variable."""
    lim = limit(name)
    if value > lim:
        u = f" {unit}" if unit else ""
        raise GonioError(f"{what}: {value:.4g}{u} exceeds the limit of {lim:.4g}{u} "
                         f"(set {name} to raise it)")


#: How many replaced SQLite files (``records.sqlite3.replaced-STAMP``) a restore over the
#: live records keeps, the newest, unless ``GONIO_KEEP_REPLACED`` says otherwise.
KEEP_REPLACED = 3


def keep_replaced() -> int:
    """How many replaced SQLite files a restore keeps: ``GONIO_KEEP_REPLACED`` (a whole number
    ≥ 1), else :data:`KEEP_REPLACED`; another value is a GonioError naming the variable.

    >>> keep_replaced() if not os.environ.get("GONIO_KEEP_REPLACED") else 3
    3
    """
    import re

    value = os.environ.get("GONIO_KEEP_REPLACED", "").strip()
    if not value:
        return KEEP_REPLACED
    if not re.fullmatch(r"[0-9]{1,6}", value) or int(value) < 1:
        raise GonioError("environment variable GONIO_KEEP_REPLACED must be a whole number "
                         f"≥ 1, got {value[:40]!r}")
    return int(value)
