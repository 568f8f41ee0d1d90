"""Records and readings helpers shared by the rate-gyro specifications (JJF 1535-2015,
IEC 62047-20): the item and result dataclasses (results.json shape), the per-item GUM
wrapper, segment means of a rate readings file.

Used by :mod:`gonio.specs.jjf1535` and :mod:`gonio.specs.iec62047_20` (one specification
never imports another, so what they share lives here and in :mod:`gonio.specs._rate_family.formulas`).
"""

from __future__ import annotations

import contextlib
import contextvars
import hashlib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from gonio.formats.jsonsafe import json_safe  # noqa: F401  (re-exported)
from gonio.analysis.noise import stream
from gonio.atomic import sha256_file
from gonio.errors import GonioError
from gonio.formats.metadata import metadata_float
from gonio.formats.rate_readings import RateReadings, read_rate_readings
from gonio.result.model import Item, Result, Uncertainty, not_measured  # noqa: F401
from gonio.result.statement import item_statement, stated_gum
from gonio.units import S_PER_H
from uncertainty import monte_carlo, propagate, validate_gum


# --------------------------------------------------------------------------- results
#
# The items and the result are the one result model's (gonio.result.model): a rate
# specification's calibrate() returns a Result of Items, written as the one results.json shape.

#: A rate-gyro calibration result is the one :class:`~gonio.result.model.Result`.
RateCalibrationResult = Result


def _f(x):
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


_MC = contextvars.ContextVar("rate_gyro_monte_carlo", default=(0, 0))


@contextlib.contextmanager
def monte_carlo_validation(trials: int, seed: int = 0):
    """Within this block every :func:`gum` budget is also propagated by JCGM 101 Monte Carlo
    with ``trials`` draws and the GUM interval validated against it (JCGM 101 8)."""
    token = _MC.set((int(trials), int(seed)))
    try:
        yield
    finally:
        _MC.reset(token)


def gum(value_fn, inputs, *, p: float | None = 0.95, k: float = 2.0) -> Uncertainty:
    """Propagate ``inputs`` (uncertainty.InputQuantity) through ``value_fn`` (a callable of
    the inputs in order, or a sympy expression) with the GUM engine (JCGM 100): by default
    k = t_95(ν_eff) (Welch–Satterthwaite), since several items rest on Q = 3 repeats, of the
    ν_eff as stated (:func:`gonio.result.statement.coverage_k`: its integer part, ∞ above
    1000); ``p=None`` uses the fixed ``k``."""
    r = stated_gum(propagate(value_fn, inputs, k=None if p is not None else k, p=p))
    comps = [{"symbol": c.symbol, "source": c.source, "type": c.type, "u": _f(c.u_xi),
              "c": _f(c.c_i), "contribution": _f(c.contribution), "dof": _f(c.dof)}
             for c in r.contributions]
    mc = None
    trials, seed = _MC.get()
    if trials > 0 and r.u_c > 0:
        m = monte_carlo(value_fn, inputs, trials, seed=seed, p=p or 0.95)
        v = validate_gum(r, m)
        mc = {"trials": trials, "u": m.u, "low": m.low, "high": m.high,
              "gum_low": v.gum_interval[0], "gum_high": v.gum_interval[1],
              "d_low": v.d_low, "d_high": v.d_high, "delta": v.delta, "validated": v.passed}
    return Uncertainty(comps, r.u_c, r.U, r.k, r.dof, mc, p,
                       "welch-satterthwaite" if p is not None else "fixed")


# --------------------------------------------------------------------------- readings

def std_dev_uncertainty(s: float, nu: int, what: str) -> Uncertainty:
    """Uncertainty of a standard deviation ``s`` of ν + 1 values (JJF 7.2.4 K_r,
    7.2.11 B_r; IEC 5.6 Noise,RMS of the resolution): u_c = s/√(2ν), the GUM's standard
    uncertainty of an experimental standard deviation (JCGM 100 E.4.3; type A, ν degrees of
    freedom), and the one-sided χ² 95 % interval of σ, [0, s·√(ν/χ²_0.05,ν)]
    (P(σ ≤ upper end) = 95 %), which is the item's statement
    (:func:`gonio.result.statement.state_interval`): no k (σ's distribution is not symmetric
    about s, so no coverage factor exists; k = U/u_c, 6.83 for ν = 2, was one). U is the
    distance from s to the upper end (:func:`gonio.specs._rate_family.formulas.std_upper_half_width`),
    the guard band of the decision rule, so a guarded upper limit is the upper end.

    Two readings this rule replaces: the χ² half-width entered as a normal type-B term with
    k = 2 and expanded again by t₉₅ (u_c = 2.64·s for ν = 2, 5.3× the GUM's s/2; the coverage
    study's sd z 0.17), and U reaching the two-sided limit s·√(ν/χ²_0.025,ν), which σ stays
    below 97.5 % of the time, under a label of 95 % (for ν = 2, U 5.285·s → 3.415·s).

    >>> u = std_dev_uncertainty(1.0, 2, "K_r")
    >>> round(u.u_c, 3), round(u.U, 3), u.k, [round(x, 3) for x in u.interval]
    (0.5, 3.415, None, [0.0, 4.415])
    """
    u_c = float(s / math.sqrt(2.0 * nu))
    from gonio.specs._rate_family.formulas import std_upper_half_width
    U = std_upper_half_width(s, nu)
    row = {"symbol": f"s({what})", "source": f"sampling of a standard deviation of "
           f"{nu + 1} values, s/√(2ν) (GUM E.4.3); U to the one-sided χ² 95 % upper limit",
           "type": "A", "u": u_c, "c": 1.0, "contribution": u_c, "dof": float(nu)}
    return Uncertainty([row], u_c, U, None, float(nu), None, 0.95,
                       "chi-square", interval=(0.0, s + U))


def dispersion_uncertainty(s: float, u: Uncertainty) -> Uncertainty:
    """A dispersion whose standard uncertainty comes from its own budget ``u`` (JJF 7.2.10
    bias stability: the mean of Q records' standard deviations of block means, its sampling
    term with the records' effective ν, and the scale factor), stated as a standard deviation
    is: by its one-sided χ² 95 % interval [0, s·√(ν/χ²_0.05,ν)] alone, as
    :func:`std_dev_uncertainty` states one, with ν = ½ (s/u_c)² (JCGM 100 E.4.3,
    u(s)/s = 1/√(2ν), read backwards: the ν of a standard deviation whose χ² spread is u_c).
    ν is stated as its integer part (∞ above 1000, the limit then keeps the computed ν). No
    k; U is the distance to the upper limit (the guard band of the decision,
    :func:`gonio.analysis.conformity.decide_items`, which takes σ's χ² distribution with that
    ν). The budget's rows and u_c are kept.

    >>> u = dispersion_uncertainty(48.0, Uncertainty([], 3.1, 13.3, 4.3, 2.0, None, 0.95))
    >>> round(u.nu_eff, 1), u.k, [round(x, 2) for x in u.interval], u.k_source
    (119.9, None, [0.0, 53.78], 'chi-square')
    """
    from gonio.result.statement import stated_nu
    from gonio.specs._rate_family.formulas import std_upper_half_width

    if not (s > 0 and u.u_c > 0):
        return u
    nu = 0.5 * (s / u.u_c) ** 2
    nu_s = stated_nu(nu)
    U = std_upper_half_width(s, nu if math.isinf(nu_s) else max(nu_s, 1.0))
    return Uncertainty(u.components, u.u_c, U, None, nu, None, 0.95, "chi-square",
                       interval=(0.0, s + U))


def source_info(rd: RateReadings) -> dict:
    """File name, SHA-256 and row count of the readings."""
    if rd.path is not None and Path(rd.path).is_file():
        sha = sha256_file(rd.path)
        name = Path(rd.path).name
    else:
        sha = hashlib.sha256(pd.util.hash_pandas_object(rd.data, index=False).values.tobytes()).hexdigest()
        name = "<memory>"
    return {"file": name, "sha256": sha, "rows": int(len(rd.data))}


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
    rate_table_u_rel: float = 2.5e-4
    acquisition_u_rel: float = 3.0e-5
    chamber_deviation_c: float = 2.0          # JJF Table 2: temperature deviation ±2 °C
    axis_alignment_deg: float = 0.05          # input axis to the fixture/table axis, half-width
    chamber_fluctuation_c: float = 1.0        # JJF Table 2: temperature fluctuation ±1 °C
    chamber_uniformity_c: float = 2.0         # JJF Table 2: uniformity 2 °C (gyro within ±half)
    chamber_fluctuation_period_s: float | None = None   # not stated: bounded instead
    cache: dict = field(default_factory=dict)

    def has(self, test: str) -> bool:
        """Whether the readings hold records of ``test``."""
        return bool((self.df["test"] == test).any())


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


@dataclass(frozen=True)
class ItemDef:
    """One item of a specification (the kit's ``gonio.kit.ItemDef``).

    Attributes
    ----------
    key, title, clause, unit : str
        As the :class:`~gonio.kit.Item` it computes states them (the title, clause and unit
        are those of the "not measured" item when it cannot be computed).
    compute : callable
        ``compute(*args, **needed)`` → :class:`~gonio.kit.Item`: ``args`` are those given
        to :func:`gonio.kit.calibrate_items` (the readings, a fit, …), ``needed`` the items
        it needs, by key.
    needs : tuple of str
        The keys of the items it needs (computed first; one not measured makes this one not
        measured, with the reason).
    nonnegative : bool
        A quantity that cannot be negative (a noise level, a time): stated with an upper
        bound where U exceeds the value (:func:`gonio.kit.state`).
    """

    key: str
    title: str
    clause: str
    compute: Callable[..., Item]
    needs: tuple[str, ...] = ()
    unit: str = ""
    nonnegative: bool = False


def run_items(defs, compute, *, monte_carlo_trials: int = 0, monte_carlo_seed: int = 0,
              needs_measured: bool = True) -> dict[str, Item]:
    """The one item loop (the kit's :func:`gonio.kit.calibrate_items` and the rate
    specifications' :func:`calibrate_items`): every :class:`ItemDef` of ``defs`` computed by
    ``compute(item_def, done)`` (``done``: the items computed so far, by key), each after
    the items it needs (:func:`gonio.specs.item_order`), each inside
    :func:`monte_carlo_validation` with ``monte_carlo_trials`` draws. An item whose
    computation refuses the data (a :class:`GonioError`), or which the statement rule cannot
    state (:func:`stateable`), is reported not measured with the reason; with
    ``needs_measured`` so is an item one of whose needs is not measured (without it the item
    is computed and says itself what it lacks); any other exception is a bug and propagates.
    Returned in the order of ``defs``."""
    from gonio.specs import item_order

    defs = {d.key: d for d in defs}
    done: dict[str, Item] = {}
    for key in item_order(defs, {k: d.needs for k, d in defs.items()}):
        d = defs[key]
        missing = [n for n in d.needs if not done[n].measured] if needs_measured else []
        if missing:
            done[key] = not_measured(key, d.title, d.clause, d.unit,
                                     f"needs {', '.join(missing)}, not measured")
            continue
        try:
            with monte_carlo_validation(monte_carlo_trials, monte_carlo_seed):
                item = compute(d, done)
        except GonioError as exc:
            item = not_measured(key, d.title, d.clause, d.unit,
                                f"the data were refused: {exc.message}")
        if not isinstance(item, Item) or item.key != key:
            raise TypeError(f"item {key!r}: compute returned {item!r}, not Item {key!r}")
        done[key] = stateable(item, nonnegative=d.nonnegative)
    return {k: done[k] for k in defs}


def calibrate_items(ctx, items_module, monte_carlo_trials: int = 0) -> dict[str, Item]:
    """Every item of a rate specification's ``items_module`` computed on ``ctx`` by the one
    item loop (:func:`run_items`): each after the items it needs (``NEEDS``), each inside
    :func:`monte_carlo_validation` with ``monte_carlo_trials``; an item whose computation
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


def stateable(item: Item, *, nonnegative: bool = False) -> Item:
    """``item`` as the item loop keeps it: marked non-negative where declared, and reported
    not measured, with the refusal as its reason, where the statement rule can state no
    interval for it (a non-negative quantity with value + U ≤ 0)."""
    item.nonnegative = item.nonnegative or nonnegative
    if not item.measured:
        return item
    try:
        item_statement(item, nonnegative=item.nonnegative)
    except GonioError as exc:
        out = not_measured(item.key, item.title, item.clause, item.unit,
                           f"no statement possible: {exc.message}")
        out.nonnegative = item.nonnegative
        return out
    return item


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
