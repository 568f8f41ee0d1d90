"""ACME RC-1 clauses 4–5: the readings file, the protocol, and the two items.

Readings file (UTF-8 CSV): ``# key: value`` metadata lines (``spec: acme-rate-check``,
``output_unit``, ``rate_table_u_rel``, …), then the columns ``rate_dps,output`` — one row per
recorded sample.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from gonio.atomic import sha256_file
from gonio.errors import GonioError
from gonio.result import Finding
from gonio.specs import item_order
from gonio.specs._rate_family.rate_records import (Item, RateCalibrationResult, gum,
                                                   monte_carlo_validation, not_measured)
from uncertainty import from_u

KEY = "acme-rate-check"

#: The protocol's defaults (clause 4.1): rates one way, samples per rate.
DEFAULT_PROTOCOL = {"rates_dps": [10.0, 50.0, 100.0], "samples": 20}


def load_protocol(protocol=None) -> dict:
    """The protocol: the defaults, or a dict overriding some of them."""
    if isinstance(protocol, dict):
        return {**DEFAULT_PROTOCOL, **protocol}
    if protocol in (None, KEY):
        return dict(DEFAULT_PROTOCOL)
    raise GonioError(f"unknown protocol {protocol!r} (this procedure has one: {KEY})",
                     key="protocol")


@dataclass
class Readings:
    """A readings file: the rows and the metadata (``path`` None: held in memory)."""

    data: pd.DataFrame
    metadata: dict = field(default_factory=dict)
    path: str | None = None


def read_readings(path) -> Readings:
    """Read a readings file; a missing column or a non-number is a GonioError naming it."""
    text = Path(path).read_text(encoding="utf-8")
    md = {}
    for line in text.splitlines():
        if not line.startswith("#"):
            break
        key, _, value = line[1:].partition(":")
        md[key.strip()] = value.strip()
    df = pd.read_csv(path, comment="#")
    for col in ("rate_dps", "output"):
        if col not in df.columns:
            raise GonioError(f"no column {col!r}", file=path, column=col)
        if not pd.api.types.is_numeric_dtype(df[col]):
            raise GonioError("expected numbers", file=path, column=col)
    return Readings(df, md, str(path))


def screen(readings, protocol=None, **_options) -> list[Finding]:
    """Clause 4.1: a rate with fewer than two samples is set aside (no spread to judge).
    gonio calls it before :func:`calibrate` and hands the findings over (``findings=``)."""
    rd = readings if isinstance(readings, Readings) else read_readings(readings)
    counts = rd.data.groupby("rate_dps").size()
    return [Finding(code="few_samples", action="set_aside", clause="4.1",
                    rule="at least two samples per rate",
                    message=f"rate {r:g} °/s has {n} sample(s)", file=rd.path)
            for r, n in counts.items() if n < 2]


def _fit(rd: Readings):
    means = rd.data.groupby("rate_dps")["output"].agg(["mean", "count"])
    x, y = means.index.to_numpy(float), means["mean"].to_numpy(float)
    if x.size < 3:
        raise GonioError("clause 4.1 needs at least three rates")
    K, b = np.polyfit(x, y, 1)
    r = y - (K * x + b)
    s2 = float(r @ r) / (x.size - 2)
    sxx = float(((x - x.mean()) ** 2).sum())
    return {"x": x, "y": y, "K": float(K), "b": float(b), "se_K": math.sqrt(s2 / sxx),
            "se_b": math.sqrt(s2 * (1 / x.size + x.mean() ** 2 / sxx)), "dof": x.size - 2}


def scale_factor(rd: Readings, fit: dict) -> Item:
    """4.2: K = least-squares slope of the mean outputs on the rates. Budget (5.1): the fit's
    standard error (type A, ν = n − 2) and the rate table's relative uncertainty (type B)."""
    u_table = float(rd.metadata.get("rate_table_u_rel", "1e-4"))
    u = gum(lambda k, e: k / (1 + e),
            [from_u("K_fit", fit["K"], fit["se_K"], dof=fit["dof"], source="least-squares slope"),
             from_u("e_table", 0.0, u_table, type="B", source="rate table, relative")])
    return Item("scale_factor", "scale factor K", "4.2", f"{rd.metadata.get('output_unit', 'output')}/(°/s)",
                fit["K"], uncertainty=u, details={"x_dps": fit["x"], "y": fit["y"],
                                                  "b_BASE": fit["b"]})


def bias(rd: Readings, fit: dict, scale_factor: Item) -> Item:
    """4.3: B = intercept / K (°/s). Budget (5.2): the intercept's standard error and K's."""
    uk = scale_factor.uncertainty
    u = gum(lambda b, k: b / k,
            [from_u("b", fit["b"], fit["se_b"], dof=fit["dof"], source="least-squares intercept"),
             from_u("K", scale_factor.value, uk.u_c, dof=uk.nu_eff, source="scale factor (4.2)")])
    return Item("bias", "bias B", "4.3", "°/s", fit["b"] / scale_factor.value, uncertainty=u)


@dataclass(frozen=True)
class ItemDef:
    """One item: key, title, clause, the function, and the items it needs first."""

    key: str
    title: str
    clause: str
    compute: object
    needs: tuple = ()


ITEMS = (ItemDef("scale_factor", "scale factor K", "4.2", scale_factor),
         ItemDef("bias", "bias B", "4.3", bias, needs=("scale_factor",)))


def calibrate(readings, protocol=None, *, monte_carlo_trials: int = 0,
              findings: list | None = None, **_options) -> RateCalibrationResult:
    """Every item of ACME RC-1 from a readings file (path or :class:`Readings`); ``findings``
    the screening gonio made (:func:`screen`), else screened here: a rate set aside is left out
    of the fit and the finding is stated in the result."""
    rd = readings if isinstance(readings, Readings) else read_readings(readings)
    findings = screen(rd) if findings is None else list(findings)
    if any(f.action == "set_aside" for f in findings):
        n = rd.data.groupby("rate_dps")["rate_dps"].transform("size")
        rd = Readings(rd.data[n >= 2].reset_index(drop=True), rd.metadata, rd.path)
    spec = rd.metadata.get("spec", KEY)
    if spec != KEY:
        raise GonioError(f"the readings are for specification {spec!r}, not {KEY!r}",
                         file=rd.path, key="spec")
    load_protocol(protocol)
    fit = _fit(rd)
    defs = {d.key: d for d in ITEMS}
    done: dict[str, Item] = {}
    for key in item_order(defs, {k: d.needs for k, d in defs.items()}):
        d = defs[key]
        missing = [n for n in d.needs if not done[n].measured]
        if missing:
            done[key] = not_measured(key, d.title, d.clause, "", f"needs {', '.join(missing)}")
            continue
        try:
            with monte_carlo_validation(monte_carlo_trials):
                done[key] = d.compute(rd, fit, **{n: done[n] for n in d.needs})
        except GonioError as exc:
            done[key] = not_measured(key, d.title, d.clause, "",
                                     f"the data were refused: {exc.message}")
    source = {"file": Path(rd.path).name if rd.path else "<memory>",
              "sha256": sha256_file(rd.path) if rd.path else "", "rows": int(len(rd.data))}
    return RateCalibrationResult(KEY, "ACME RC-1 Rate-table check of a rate gyro",
                                 {k: done[k] for k in defs}, dict(rd.metadata), source,
                                 ["4.3: the Earth rate is not removed from the bias."],
                                 findings=findings)
