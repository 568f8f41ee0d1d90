"""ACME RC-1 clauses 4–5: the readings file, the protocol, and the three items.

Readings file (UTF-8 CSV): ``# key: value`` metadata lines (``spec: acme-rate-check``,
``output_unit``, ``rate_table_u_rel``, …), then the columns ``rate_dps,output`` — one row per
recorded sample. Everything gonio provides comes from the public kit, :mod:`gonio.kit`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from gonio.atomic import sha256_file
from gonio.kit import (Finding, GonioError, Item, ItemDef, Result, calibrate_items, from_u,
                       gum, set_aside)

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
    """A readings file: the rows (with ``line``, each row's line in the file) and the
    metadata (``path`` None: held in memory)."""

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
    return Readings(with_lines(df, len(md)), md, str(path))


def with_lines(df: pd.DataFrame, n_metadata: int) -> pd.DataFrame:
    """The rows with their line in the file: metadata lines, the header, then one per row."""
    return df.assign(line=np.arange(len(df)) + n_metadata + 2)


def screen(readings, protocol=None, **_options) -> list[Finding]:
    """Clause 4.1: a rate with fewer than two samples is set aside (no spread to judge), by
    line. gonio calls it before :func:`calibrate` and hands the findings over (``findings=``)."""
    rd = readings if isinstance(readings, Readings) else read_readings(readings)
    n = rd.data.groupby("rate_dps")["rate_dps"].transform("size")
    return [Finding(code="few_samples", action="set_aside", clause="4.1",
                    rule="at least two samples per rate", column="rate_dps",
                    message=f"rate {r:g} °/s has {k} sample(s)", file=rd.path, line=int(line))
            for r, k, line in zip(rd.data["rate_dps"], n, rd.data["line"]) if k < 2]


def _fit(rd: Readings):
    means = rd.data.groupby("rate_dps")["output"].agg(["mean", "count"])
    x, y = means.index.to_numpy(float), means["mean"].to_numpy(float)
    if x.size < 3:
        raise GonioError("clause 4.1 needs at least three rates")
    K, b = np.polyfit(x, y, 1)
    r = y - (K * x + b)
    s2 = float(r @ r) / (x.size - 2)
    sxx = float(((x - x.mean()) ** 2).sum())
    out = {"x": x, "y": y, "K": float(K), "b": float(b), "se_K": math.sqrt(s2 / sxx),
           "se_b": math.sqrt(s2 * (1 / x.size + x.mean() ** 2 / sxx)), "dof": x.size - 2}
    # 4.4: y = b + K̄·Ω + Δ·|Ω| (K± = K̄ ± Δ), least squares with the parameters' covariance
    X = np.column_stack([np.ones_like(x), x, np.abs(x)])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    dof3 = x.size - 3
    if dof3 >= 1:
        r3 = y - X @ coef
        cov = float(r3 @ r3) / dof3 * np.linalg.inv(X.T @ X)
        out.update(K_mean=float(coef[1]), delta=float(coef[2]), se_K_mean=math.sqrt(cov[1, 1]),
                   se_delta=math.sqrt(cov[2, 2]), cov_K_delta=float(cov[1, 2]), dof3=dof3)
    return out


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


def asymmetry(rd: Readings, fit: dict) -> Item:
    """4.4: scale-factor asymmetry A = (K+ − K−)/K̄ = 2Δ/K̄, in ppm, from the fit
    y = b + K̄·Ω + Δ·|Ω|. Budget (5.3): Δ and K̄ from the fit (type A, ν = n − 3); the rate
    table's error scales K+ and K− alike and cancels. With the programme's rates both ways
    K̄ and Δ are uncorrelated (Σ Ω·|Ω| = 0); a programme that is not symmetric is refused."""
    if "delta" not in fit:
        raise GonioError("clause 4.4 needs at least four rates")
    if abs(fit["cov_K_delta"]) > 1e-9 * fit["se_K_mean"] * fit["se_delta"]:
        raise GonioError("clause 4.4 needs every rate turned both ways")
    u = gum(lambda d, k: 2e6 * d / k,          # numbers or arrays of Monte Carlo draws
            [from_u("Delta", fit["delta"], fit["se_delta"], dof=fit["dof3"],
                    source="half the slope difference, least squares"),
             from_u("K_mean", fit["K_mean"], fit["se_K_mean"], dof=fit["dof3"],
                    source="mean slope, least squares")])
    return Item("asymmetry", "scale-factor asymmetry A", "4.4", "ppm",
                2e6 * fit["delta"] / fit["K_mean"], uncertainty=u,
                details={"K_pos": fit["K_mean"] + fit["delta"],
                         "K_neg": fit["K_mean"] - fit["delta"]})


ITEMS = (ItemDef("scale_factor", "scale factor K", "4.2", scale_factor),
         ItemDef("bias", "bias B", "4.3", bias, needs=("scale_factor",), unit="°/s"),
         ItemDef("asymmetry", "scale-factor asymmetry A", "4.4", asymmetry, unit="ppm"))


def calibrate(readings, protocol=None, *, monte_carlo_trials: int = 0,
              findings: list | None = None, **_options) -> Result:
    """Every item of ACME RC-1 from a readings file (path or :class:`Readings`); ``findings``
    the screening gonio made (:func:`screen`), else screened here: a row set aside is left out
    of the fits and every finding is stated in the result. ``monte_carlo_trials`` > 0: every
    budget also propagated by Monte Carlo (JCGM 101) and the GUM interval checked against it."""
    rd = readings if isinstance(readings, Readings) else read_readings(readings)
    findings = screen(rd) if findings is None else list(findings)
    rd = Readings(set_aside(rd.data, findings), rd.metadata, rd.path)
    spec = rd.metadata.get("spec", KEY)
    if spec != KEY:
        raise GonioError(f"the readings are for specification {spec!r}, not {KEY!r}",
                         file=rd.path, key="spec")
    load_protocol(protocol)
    items = calibrate_items(ITEMS, rd, _fit(rd), monte_carlo_trials=monte_carlo_trials)
    source = {"file": Path(rd.path).name if rd.path else "<memory>",
              "sha256": sha256_file(rd.path) if rd.path else "", "rows": int(len(rd.data))}
    return Result(KEY, "ACME RC-1 Rate-table check of a rate gyro", items, dict(rd.metadata),
                  source, ["4.3: the Earth rate is not removed from the bias."],
                  findings=findings)
