"""The one writer of a result: ``results.json``, ``summary.txt`` and ``tables/*.csv``.

``items.csv`` lists every item (key, clause, value, unit, u, U, k, ν_eff, p, measured,
conformity outcome); a result's own tables (``Result.tables``: name → DataFrame, e.g. the
optical draft's per-item tables or a triad's thermal prediction band) follow under their
names. Written in a fixed order with ``\\n`` line ends (byte-identical on every platform).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pandas as pd

from gonio.atomic import output_dir, write_text

ITEM_COLUMNS = ["item", "clause", "value", "unit", "u", "U", "k", "nu", "p", "measured",
                "conformity"]


def items_table(result) -> pd.DataFrame:
    """One row per item (not-measured items with empty numbers)."""
    rows = []
    for key, it in result.items.items():
        unc = it.uncertainty if it.measured else None
        rows.append({"item": key, "clause": it.clause,
                     "value": it.value if it.measured else None, "unit": it.unit,
                     "u": None if unc is None else unc.u_c, "U": None if unc is None else unc.U,
                     "k": None if unc is None else unc.k,
                     # ν_eff None and inf are both infinite (Uncertainty): one form, "inf",
                     # as results.json (null) read back gives the same table
                     "nu": None if unc is None else (math.inf if unc.nu_eff is None
                                                     else unc.nu_eff),
                     "p": None if unc is None else unc.coverage_probability,
                     "measured": bool(it.measured),
                     "conformity": None if it.conformity is None else it.conformity.outcome})
    return pd.DataFrame(rows, columns=ITEM_COLUMNS)


def result_tables(result) -> dict[str, pd.DataFrame]:
    """``items.csv`` and the result's own tables, by file name (sorted after items.csv)."""
    out = {"items.csv": items_table(result)}
    for name in sorted(result.tables):
        df = result.tables[name]
        if df is not None and len(df):
            out[name if name.endswith(".csv") else f"{name}.csv"] = df
    return out


def write_tables(result, folder: str | Path) -> dict[str, Path]:
    """Write :func:`result_tables` into ``folder/tables`` (each file atomically); paths by
    ``tables/<name>``."""
    folder = Path(folder) / "tables"
    paths = {}
    for name, df in result_tables(result).items():
        write_text(folder / name, df.to_csv(index=False, lineterminator="\n"))
        paths[f"tables/{name}"] = folder / name
    return paths


def results_json_text(result) -> str:
    """``results.json`` as written: indented, UTF-8, no NaN (strict JSON), ``\\n`` ends."""
    return json.dumps(result.to_json(), indent=2, ensure_ascii=False, allow_nan=False) + "\n"


def write_results(result, out: str | Path) -> dict[str, Path]:
    """``results.json``, ``summary.txt`` and ``tables/*.csv`` of ``result`` into ``out``,
    swapped in together (:func:`gonio.atomic.output_dir`). Paths by name (``results``,
    ``summary``, ``tables/<name>``)."""
    out = Path(out)
    with output_dir(out) as stage:
        write_text(stage / "results.json", results_json_text(result))
        write_text(stage / "summary.txt", result.summary())
        tables = write_tables(result, stage)
    paths = {"results": out / "results.json", "summary": out / "summary.txt"}
    paths.update({n: out / n for n in tables})
    return paths
