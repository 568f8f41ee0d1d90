"""The one writer of a result: ``results.json``, ``summary.txt`` and ``tables/*.csv``.

``items.csv`` lists every item (key, clause, value, unit, u, U, k, ν, p, the coverage
interval's ends, measured, conformity outcome) with the numbers of the item's one 95 %
statement (:func:`item_row`); a result's own tables (``Result.tables``: name → DataFrame,
e.g. the optical draft's per-item tables or a triad's thermal prediction band) follow under
their names. Written in a fixed order with ``\\n`` line ends (byte-identical on every
platform).
"""

from __future__ import annotations

import json
import math
from decimal import Decimal
from pathlib import Path

import pandas as pd

from gonio.atomic import output_dir, write_text
from gonio.errors import GonioError
from gonio.result.statement import (K_SOURCE_MAX_ABS, chi2_nu, chi2_stated_nu, coverage_k,
                                    item_statement, numerically_widened, p_text, stated_nu,
                                    u_c_certified)

ITEM_COLUMNS = ["item", "clause", "value", "unit", "u", "U", "k", "nu", "p", "interval_low",
                "interval_high", "measured", "conformity"]


def _k_from_nu(unc) -> bool:
    """Whether ``unc``'s k is the t-factor of its ν_eff as stated (ν_eff None or ∞: the
    normal quantile) — not a k of a convolution, a Monte Carlo or a laboratory's choice."""
    k, p = unc.k, unc.coverage_probability
    if k is None or p is None or not math.isfinite(float(k)):
        return False
    return math.isclose(float(k), coverage_k(unc.nu_eff, float(p)), rel_tol=1e-6)


def stated_p(p: float | None) -> float | None:
    """items.csv's ``p``: the coverage probability as every output states it
    (:func:`~gonio.result.statement.p_text` / 100: a chosen p as chosen, 0.95, 0.9545; a
    computed p rounded down at the digits stated, 0.9823… → 0.98, never overstated); the
    unrounded value and the stated text with its relation ("p ≈ 98 %") are results.json's
    ``uncertainty.coverage_probability`` and ``uncertainty.p_stated``.

    >>> stated_p(0.95), stated_p(0.9545), stated_p(0.9823487503232564), stated_p(None)
    (0.95, 0.9545, 0.98, None)
    """
    t = p_text(p)
    return None if t is None else float(Decimal(t).scaleb(-2))


def item_row(key: str, it) -> dict:
    """The ``items.csv`` row of item ``it``: the numbers of its one statement
    (:func:`~gonio.result.statement.item_statement`), unrounded.

    * stated as value ± U: ``U`` and ``k``; ``nu`` the ν_eff as stated and as k was
      computed from (:func:`~gonio.result.statement.stated_nu`: its integer part, ∞ above
      the threshold or where ν_eff is infinite), empty where the statement states none (ν_eff
      infinite, stored null in results.json, "—" on the certificate) or where k did not
      come from ν (a JCGM 101 convolution's k, a fixed k): a ν beside such a k would read as its source;
    * stated by an interval (a dispersion's χ² interval, an extreme's Monte Carlo or
      max|x| interval, a non-negative quantity's [0, value + U]): ``interval_low`` and
      ``interval_high``, ``U`` and ``k`` empty (a reach beside an empty k reads as value ±
      U, a second statement); ``nu`` the interval's ν where the statement states a finite
      one (an infinite ν, stored as None, leaves it empty; a standard deviation's χ² interval:
      the ν it was computed with, :func:`~gonio.result.statement.chi2_nu`, never ∞); for an
      extreme of magnitudes (:data:`~gonio.result.statement.K_SOURCE_MAX_ABS`) ``value`` is
      the extreme max|x_i| the interval is of (the signed one stays in results.json); a
      non-negative quantity whose estimate fell below zero, stated by its upper bound
      alone, has ``value`` empty, as the certificate states no value (the signed estimate
      stays in results.json); where the statement widened a Monte Carlo interval's ends
      for draws that settle no digit (``Statement.widened``), the widened ends
      (:func:`~gonio.result.statement.numerically_widened`; results.json keeps the computed
      ones).
    ``u`` is the combined standard uncertainty u_c where the certificate states it, empty for
    a bound-condition item (:func:`~gonio.result.statement.u_c_certified`: its quadrature
    u_c is not certified; its ``nu`` is then the ν of the rest, ν_rest, as the certificate
    prints it beside the interval). ``p`` is the coverage probability as stated (:func:`stated_p`), the unrounded one stays
    in results.json. A not-measured item has empty numbers."""
    row = {"item": key, "clause": it.clause, "value": None, "unit": it.unit, "u": None,
           "U": None, "k": None, "nu": None, "p": None, "interval_low": None,
           "interval_high": None, "measured": bool(it.measured),
           "conformity": None if it.conformity is None else it.conformity.outcome}
    if not it.measured:
        return row
    row["value"] = it.value
    unc = it.uncertainty
    if unc is None:
        return row
    try:
        st = item_statement(it)
    except GonioError:          # unstateable items are reported not measured (run_items)
        st = None
    # u_c only where the certificate states it (u_c_certified: not the quadrature u_c of a
    # bound-condition item, which the certificate marks "beside, not stated", nor the u_c of
    # one point beside the interval of an extreme of magnitudes)
    row.update(u=unc.u_c if u_c_certified(it) else None,
               p=stated_p(unc.coverage_probability))
    if st is not None and st.interval is not None:
        if unc.interval is not None:
            lo, hi = float(unc.interval[0]), float(unc.interval[1])
            if st.widened is not None:  # the ends as stated: out by the draws' 2·s
                lo, hi, _ = numerically_widened(it.value, (lo, hi),
                                                numerical_u=unc.interval_numerical_u,
                                                nonnegative=bool(it.nonnegative))
        else:                   # a non-negative quantity's [0, value + U] (state())
            lo, hi = 0.0, float(it.value) + float(unc.U)
        if unc.k is None and unc.k_source == K_SOURCE_MAX_ABS:
            row["value"] = hi - float(unc.U)
        elif st.below_zero:     # stated by its bound alone: no estimate outside [0, upper]
            row["value"] = None
        # the interval's ν where it states a finite one (an infinite ν is stored as None in
        # results.json: the same row from the stored result)
        finite = (st.nu_eff is not None and unc.nu_eff is not None
                  and math.isfinite(float(unc.nu_eff)))
        nu = chi2_nu(unc.nu_eff) if chi2_stated_nu(unc.k_source) else stated_nu(unc.nu_eff)
        row.update(interval_low=lo, interval_high=hi, nu=nu if finite else None)
        return row
    if st is not None and st.U is None:      # stated without an uncertainty
        return row
    row.update(U=unc.U, k=unc.k)
    if _k_from_nu(unc):
        # the ν the statement prints: empty where none is stated (an infinite ν_eff is
        # stored null in results.json, the certificate prints "—": the same row from the
        # stored result as from the run), "inf" only where the certificate prints ∞
        finite = unc.nu_eff is not None and math.isfinite(float(unc.nu_eff))
        row["nu"] = stated_nu(unc.nu_eff) if finite else None
    return row


def items_table(result) -> pd.DataFrame:
    """One row per item (:func:`item_row`; not-measured items with empty numbers)."""
    return pd.DataFrame([item_row(key, it) for key, it in result.items.items()],
                        columns=ITEM_COLUMNS)


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


def write_results(result, out: str | Path, lab: dict | None = None,
                  summary: str | None = None) -> dict[str, Path]:
    """``results.json``, ``summary.txt`` and ``tables/*.csv`` of ``result`` into ``out``,
    swapped in together (:func:`gonio.atomic.output_dir`). Paths by name (``results``,
    ``summary``, ``tables/<name>``). ``summary``: the renderer's summary.txt text (None:
    :meth:`~gonio.result.model.Result.summary` with ``lab``)."""
    out = Path(out)
    with output_dir(out) as stage:
        write_text(stage / "results.json", results_json_text(result))
        write_text(stage / "summary.txt", result.summary(lab) if summary is None else summary)
        tables = write_tables(result, stage)
    paths = {"results": out / "results.json", "summary": out / "summary.txt"}
    paths.update({n: out / n for n in tables})
    return paths
