"""Readings helpers shared by the rate-gyro specifications (JJF 1535-2015, IEC 62047-20):
the context their item functions see, their item modules run through the one item loop
(:func:`gonio.result.items.run_items`), metadata and protocol of a rate readings file,
segment means, the static record.

Used by :mod:`gonio.specs.jjf1535` and :mod:`gonio.specs.iec62047_20` (one specification
never imports another, so what they share lives here and in :mod:`gonio.specs._rate_family.formulas`);
the item types, the GUM budget and the item loop they use are the shared ones of
:mod:`gonio.result` (re-exported by the kit).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from gonio.analysis.noise import stream
from gonio.errors import GonioError
from gonio.formats.metadata import metadata_float
from gonio.formats.rate_readings import RateReadings, read_rate_readings
from gonio.result.items import ItemDef, run_items
from gonio.result.model import Item
from gonio.units import S_PER_H


# --------------------------------------------------------------------------- readings

@dataclass(kw_only=True)
class RateContext:
    """What a rate specification's item functions need besides the formulas: the readings,
    the values the metadata (or protocol) state, the protocol's sections, the equipment's
    relative uncertainties. Each specification extends it with its own fields."""

    df: pd.DataFrame
    output_unit: str
    null_output: float
    latitude_deg: float
    protocol: dict
    rate_table_u_rel: float | None = None     # None: not stated (rate_table_line)
    acquisition_u_rel: float = 3.0e-5
    chamber_deviation_c: float = 2.0          # JJF Table 2: temperature deviation ±2 °C
    axis_alignment_deg: float = 0.05          # input axis to the fixture/table axis, half-width
    chamber_fluctuation_c: float = 1.0        # JJF Table 2: temperature fluctuation ±1 °C
    chamber_uniformity_c: float = 2.0         # JJF Table 2: uniformity 2 °C (gyro within ±half)
    chamber_fluctuation_period_s: float | None = None   # not stated: bounded instead
    cache: dict = field(default_factory=dict)

    def has(self, test: str) -> bool:
        """Whether the readings hold records of ``test`` (found once per test and context:
        the budgets ask at every rate and temperature, and each look scanned the readings)."""
        key = ("has", test)
        if key not in self.cache:
            self.cache[key] = bool((self.df["test"] == test).any())
        return self.cache[key]


def metadata_number(md: dict, key: str, default, path) -> float:
    """A numeric metadata value of a rate readings file (validated by
    :func:`gonio.formats.metadata.metadata_float`), or ``default`` when the key is absent or
    empty; with no default (None, or ``"bench"``: the protocol defers to the bench) an
    absent key is an error naming it."""
    value = metadata_float(md, key, file=path) if str(md.get(key, "") or "").strip() else None
    if value is None:
        if default is None or default == "bench":
            raise GonioError("required metadata key is missing", file=path, key=key)
        return float(default)
    return value


#: JJF 1535-2015 Table 2, row 1: the rate table's "rate accuracy and rate smoothness 0.05 %"
#: (relative) — a bound the laboratory's table conforms to, not a certificate's U.
TABLE2_RATE_ACCURACY_REL = 5.0e-4
#: What the rate table's line adds to its source where the readings state no certificate u.
TABLE2_RATE_SOURCE = ": no certificate u stated; JJF 1535 Table 2's 0.05 % as a rectangular bound"


def stated_rate_table_u(md: dict, path) -> float | None:
    """The rate table's relative standard uncertainty the readings state
    (``rate_table_u_rel``, its certificate's u), or None where they state none (the
    reading of that case: :func:`rate_table_line`)."""
    if not str(md.get("rate_table_u_rel", "") or "").strip():
        return None
    return metadata_number(md, "rate_table_u_rel", None, path)


def rate_table_line(symbol: str, u_stated: float | None, source: str):
    """The budget line of the rate table's relative rate error (JJF 1535 Annex A u₁, IEC
    62047-20's table term), one reading of what the laboratory knows of it:

    - the readings state ``rate_table_u_rel`` (its calibration certificate's u): a normal
      line of that u (the certificate's state of knowledge; the coverage studies draw the
      error from it);
    - they state none: all the laboratory can claim is the table's conformity to JJF 1535
      Table 2's "rate accuracy and rate smoothness 0.05 %", a BOUND — one rectangular line
      of half-width :data:`TABLE2_RATE_ACCURACY_REL` (u = 5·10⁻⁴/√3 = 2.89·10⁻⁴), which a
      table at the limit does not pass (the coverage studies' worst case puts it there).
      Before, such a file was budgeted as if a certificate stated u = 2.5·10⁻⁴, i.e. Table
      2's 0.05 % read as U at k = 2.

    >>> round(rate_table_line("e", None, "t").u, 7), rate_table_line("e", 2.5e-4, "t").u
    (0.0002887, 0.00025)
    >>> "Table 2" in rate_table_line("e", None, "rate table").source
    True
    """
    from uncertainty import from_u, type_b

    if u_stated is None:
        return type_b(symbol, 0.0, TABLE2_RATE_ACCURACY_REL, "rectangular",
                      source=f"{source}{TABLE2_RATE_SOURCE}")
    return from_u(symbol, 0.0, float(u_stated), type="B", source=source)


#: ``k_source`` of a rate item stated by its bound condition (:func:`table_bound_statement`):
#: the formula the shared legend recognises (``gonio.report.stated.K_SOURCE_BOUND_PREFIX``,
#: the triad's statement of the same kind), no words.
K_SOURCE_BOUND = "U = a + k·u"

#: What a rate item stated by its bound condition keeps in its details (the parts of U).
BOUND_CONDITION_BASIS = (
    "bound condition: the bounded lines (the rate table at JJF 1535 Table 2's 0.05 % "
    "where no certificate u is stated for it; the gyro's temperature error at the set "
    "point) at their bounds "
    "with one sign, added linearly, a = Σ|c_i|·a_i, plus k·u of the other lines, "
    "U = a + t_95(ν_rest)·u_rest (JCGM 100 4.3.7, 6.2); holds at least 95 % at every "
    "condition within the bounds")


#: The budget symbol of the rate table's relative error (:func:`table_bound_statement`).
TABLE_LINE = "e_table"


def table_bound_statement(u, value: float, u_stated: float | None, bounded: dict,
                          basis: str = BOUND_CONDITION_BASIS):
    """The one statement of a rate item into which the rate table's relative error enters
    (JJF 1535 7.2.1 K, Annex A u₁; IEC 62047-20 5.1.3.1 a_BASE, 5.1.3.2), one reading of
    what a laboratory that states no certificate u for its table can certify:

    - the readings state ``rate_table_u_rel`` (``u_stated`` not None): the table's line is
      a state of knowledge (:func:`rate_table_line`, a certificate's normal u) and stays
      among the other lines; the remaining bounded lines (``bounded`` less ``e_table``: the
      gyro's temperature error e_TU) are still bounds the procedure allows at once, so the
      statement below holds them (a budget whose only bounded line is the table's, or whose
      other bounds are 0, keeps ``u``, the GUM budget, U = k·u_c, unchanged);
    - they state none: the table's error is known only as JJF 1535 Table 2's bound, and the
      procedure allows it at that bound together with the other bounded lines of the
      budget (``bounded``: {symbol: half-width a_i in the input's unit}; the gyro's
      temperature error e_TU at its deviation + place bound) with one sign. Their bounds
      add linearly (the worst-condition rule, docs/validation-rate.md): a = Σ|c_i|·a_i, c_i
      the budget's sensitivities (first order); the other lines give u_rest (root sum
      square) and ν_rest (Welch–Satterthwaite, JCGM 100 G.4.1), so

          U = a + t_95(ν_rest)·u_rest  (k_rest from ν_rest as stated, :func:`coverage_k`),

      and P(|offset + e| ≤ U) ≥ P(|e| ≤ k_rest·u_rest) = 95 % for every offset |offset| ≤ a
      (JCGM 100 4.3.7 for the bounds, 6.2 for k) — where a root-sum-square k·u_c of a
      bounded line at its bound covers as little as 84 % (one line) and 0 % (the table and
      e_TU at once: IEC a_BASE in the worst case). Stated by its interval value ± U, ν_rest
      printed, no k (U is no multiple of u_c; u_c stays the budget's, for the budget table
      and the items computed with it); the parts in the returned dict for the details,
      ``basis`` the words they keep for what was bounded (:data:`BOUND_CONDITION_BASIS`,
      the rate table and the gyro's temperature error; an item with other bounded lines
      names its own).

    >>> from uncertainty import from_u, type_b
    >>> from gonio.result.gum import gum
    >>> ins = [from_u("x", 1.0, 0.0), type_b("e_table", 0.0, 5e-4, "rectangular"),
    ...        type_b("e_T", 0.0, 4e-4, "rectangular"), from_u("n", 0.0, 1e-4)]
    >>> g = gum(lambda x, e, f, n: x * (1 + e) * (1 + f) + n, ins)
    >>> s, d = table_bound_statement(g, 1.0, None, {"e_table": 5e-4, "e_T": 4e-4})
    >>> round(s.U, 6), s.k, round(d["k_rest"], 2), [round(v, 6) for v in s.interval]
    (0.001096, None, 1.96, [0.998904, 1.001096])
    >>> round(g.U, 6)                          # the quadrature's k·u_c, short of a = 0.0009
    0.000751
    >>> table_bound_statement(g, 1.0, 2.5e-4, {"e_table": 5e-4})[0] is g
    True
    >>> s, d = table_bound_statement(g, 1.0, 2.5e-4, {"e_table": 5e-4, "e_T": 4e-4})
    >>> sorted(d["a_lines"]), round(d["a"], 6)   # a stated table: e_T alone at its bound
    (['e_T'], 0.0004)
    """
    import dataclasses

    from gonio.result.statement import coverage_k

    if u_stated is not None:
        bounded = {s: h for s, h in bounded.items() if s != TABLE_LINE and float(h) > 0.0}
        if not bounded:
            return u, {}
    rows = {str(c.get("symbol")): c for c in u.components}
    missing = sorted(set(bounded) - set(rows))
    if missing:
        raise GonioError(f"bound-condition statement: budget has no line {missing[0]!r}")
    a = sum(abs(float(rows[s].get("c") or 0.0)) * float(h) for s, h in bounded.items())
    rest = [c for s, c in rows.items() if s not in bounded and (c.get("contribution") or 0) > 0]
    u_rest = math.sqrt(sum(float(c["contribution"]) ** 2 for c in rest))
    den = sum(float(c["contribution"]) ** 4 / float(c["dof"]) for c in rest
              if c.get("dof") is not None and math.isfinite(float(c["dof"])))
    nu_rest = u_rest ** 4 / den if den > 0 else math.inf
    p = u.coverage_probability or 0.95
    k = coverage_k(nu_rest, p) if u_rest > 0 else 0.0
    big_u = a + k * u_rest
    parts = {"a": a, "a_lines": {s: abs(float(rows[s].get("c") or 0.0)) * float(h)
                                 for s, h in bounded.items()},
             "u_rest": u_rest, "nu_rest": nu_rest, "k_rest": k, "U": big_u,
             "U_quadrature": u.U, "k_quadrature": u.k, "basis": basis}
    return dataclasses.replace(
        u, U=big_u, k=None, nu_eff=nu_rest, coverage_probability=p, k_source=K_SOURCE_BOUND,
        interval=(float(value) - big_u, float(value) + big_u),
        u_c_of="the GUM budget (the bounded lines as rectangular distributions); the "
               "bound-condition interval is the statement"), parts


def protocol_named(rd: RateReadings, protocol, default: str):
    """The protocol to use: ``protocol`` when given, else the one the readings'
    ``# protocol:`` names (:func:`gonio.resources.readings_protocol`: never ignored, an
    unknown name refused), else ``default``."""
    if protocol is not None:
        return protocol
    from gonio.resources import readings_protocol
    return readings_protocol(rd.metadata.get("protocol"), rd.path, default)


def load_readings(readings) -> RateReadings:
    """A RateReadings from a path or as given."""
    if isinstance(readings, RateReadings):
        return readings
    return read_rate_readings(readings)


def calibrate_items(ctx, items_module, monte_carlo_trials: int = 0) -> dict[str, Item]:
    """Every item of a rate specification's ``items_module`` computed on ``ctx`` by the one
    item loop (:func:`run_items`): each after the items it needs (``NEEDS``), each inside
    :func:`~gonio.result.gum.monte_carlo_validation` with ``monte_carlo_trials``; an item whose computation
    refuses the data (a :class:`GonioError`) is reported not measured with the refusal as
    its reason, nothing dropped; the items returned in ``ITEMS`` order, those in
    ``NONNEGATIVE`` marked non-negative (one the statement rule refuses, value + U ≤ 0, is
    reported not measured with the refusal). An item is computed whether or not its needs
    were measured: its function says what it lacks. ``items_module`` has ``ITEMS`` (rows
    key, title, clause, function of the context), ``NEEDS``, ``NONNEGATIVE`` and
    ``with_needs(ctx, done)`` (the context an item sees, given the items done so far)."""
    defs = [ItemDef(key, title, clause, fn, tuple(items_module.NEEDS.get(key, ())),
                    nonnegative=key in items_module.NONNEGATIVE)
            for key, title, clause, fn in items_module.ITEMS]
    return run_items(defs, lambda d, done: d.compute(items_module.with_needs(ctx, done)),
                     monte_carlo_trials=monte_carlo_trials, needs_measured=False)


@dataclass(frozen=True)
class SegmentMean:
    """Mean and spread of one (test, run, step) segment."""

    test: str
    run: int
    step: int
    role: str
    rate_dps: float
    n: int
    mean: float
    std: float
    time_s: float
    temperature_c: float
    supply_v: float
    up_axis: str
    north_axis: str
    freq_hz: float


#: Columns measured alongside the output by a sensor that may log on some rows only (a slow
#: chamber logger writes every n-th row): the blank rows are filled by :func:`fill_measured`.
MEASURED_COLUMNS = ("temperature_c", "supply_v")


def _interp_blanks(t: np.ndarray, v: np.ndarray) -> np.ndarray:
    ok = np.isfinite(v)
    if ok.all() or not ok.any():
        return v
    order = np.argsort(t[ok], kind="stable")
    out = v.copy()
    out[~ok] = np.interp(t[~ok], t[ok][order], v[ok][order])
    return out


def fill_measured(d: pd.DataFrame, col: str) -> np.ndarray:
    """``col`` of the rows ``d`` (one test) with each blank cell given the value interpolated
    linearly in time between the logged rows of its own segment (test, run, step: one set
    point), held at the segment's first or last logged value beyond them; a segment logged on
    no row takes the same interpolation over its run's logged rows (one run: one chamber set
    point of the temperature tests), a run logged on no row over the test's. A chamber temperature
    logged on every n-th row thus reads, at every row, what the logger saw then
    (docs/formats.md#which-cells-may-be-empty). A column logged on no row of the test stays
    blank (the items that need it say so).

    >>> d = pd.DataFrame({"time_s": [0.0, 1.0, 2.0, 3.0, 4.0, 5.0], "run": [0] * 6,
    ...                   "step": [0, 0, 0, 0, 1, 1],
    ...                   "temperature_c": [math.nan, 20.0, math.nan, 22.0, math.nan, 70.0]})
    >>> fill_measured(d, "temperature_c").tolist()
    [20.0, 20.0, 21.0, 22.0, 70.0, 70.0]
    """
    v = pd.to_numeric(d[col], errors="coerce").to_numpy(dtype=float)
    if np.isfinite(v).all():
        return v
    t = pd.to_numeric(d["time_s"], errors="coerce").to_numpy(dtype=float)
    out = v.copy()
    for keys in (["run", "step"], ["run"]):
        for idx in d.groupby(keys, sort=False).indices.values():
            out[idx] = _interp_blanks(t[idx], out[idx])
    return _interp_blanks(t, out)


def segment_means(df: pd.DataFrame, test: str) -> list[SegmentMean]:
    """Per-segment means of ``test``, ordered by run then step; a segment's temperature and
    supply voltage are those of its first row (blank cells filled by :func:`fill_measured`)."""
    d = df[df["test"] == test]
    if any(d[c].isna().any() for c in MEASURED_COLUMNS if c in d):
        d = d.assign(**{c: fill_measured(d, c) for c in MEASURED_COLUMNS if c in d})
    out = []
    for (run, step), g in d.groupby(["run", "step"], sort=True):
        y = g["output"].to_numpy()
        out.append(SegmentMean(test, int(run), int(step), str(g["role"].iloc[0]),
                               float(g["rate_dps"].iloc[0]), int(y.size), float(y.mean()),
                               float(y.std(ddof=1)) if y.size > 1 else math.nan,
                               float(g["time_s"].iloc[0]), float(g["temperature_c"].iloc[0]),
                               float(g["supply_v"].iloc[0]), str(g["up_axis"].iloc[0]),
                               str(g["north_axis"].iloc[0]), float(g["freq_hz"].iloc[0])))
    return out


def segment_samples(df: pd.DataFrame, test: str, run: int, step: int) -> pd.DataFrame:
    """The rows of one segment."""
    return df[(df["test"] == test) & (df["run"] == run) & (df["step"] == step)]


def _static_rows(df: pd.DataFrame) -> tuple[int, int, np.ndarray | None]:
    """The rows of the static record (test ``static``, run 0, step 0),
    :func:`gonio.analysis.noise.stream.rows_where`."""
    rows = stream.rows_where(df, lambda d: (d["test"] == "static") & (d["run"] == 0)
                             & (d["step"] == 0))
    if rows[1] == 0:
        raise GonioError("no 'static' records in the readings", key="static")
    return rows


def static_output(df: pd.DataFrame):
    """The output column of the static record, raw: an array, or for a long record a
    :class:`~gonio.analysis.noise.stream.Record` read from the frame piece by piece."""
    return stream.frame_column(df, "output", _static_rows(df))


def static_rate_dph(df: pd.DataFrame, null_output: float, scale_factor: float):
    """The static record (test ``static``) as a rate in °/h, (output − null)/K, and its
    sampling interval in s (from the first and last time stamps). A long record is a
    :class:`~gonio.analysis.noise.stream.Record` (bounded memory) with the same
    numbers, which the noise items read piece by piece."""
    # the two columns only, never a copy of the whole frame (a long static record)
    rows = first, count, idx = _static_rows(df)
    time_s = df["time_s"].to_numpy()
    last = first + count - 1 if idx is None else int(idx[-1])
    dt = float((time_s[last] - time_s[first]) / (count - 1))
    out = stream.frame_column(df, "output", rows)

    def rate(r):
        r -= null_output                     # in place: the same numbers, one array
        r /= scale_factor
        r *= S_PER_H
        return r
    if isinstance(out, stream.Record):
        return stream.Record(out.size, lambda a, b: rate(out[a:b])), dt
    return rate(out), dt


def sf_calibration_means(means: list[SegmentMean], run: int):
    """(rest before, rest after, rates, raw means, middle rest points) of one calibration."""
    seg = [m for m in means if m.run == run]
    if not seg:
        raise GonioError(f"no segments for run {run}")
    first, last = seg[0], seg[-1]
    if first.role != "rest" or last.role != "rest":
        raise GonioError(f"run {run}: a calibration starts and ends with a rest segment "
                         f"(JJF 7.2.1.1 d)) — got {first.role!r} … {last.role!r}")
    inner = seg[1:-1]
    rates = np.array([m.rate_dps for m in inner if m.role == "rate"])
    ys = np.array([m.mean for m in inner if m.role == "rate"])
    zero = [m for m in inner if m.role == "rest"]
    return first, last, rates, ys, zero
