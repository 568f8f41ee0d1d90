"""Coverage of the rate-gyro uncertainty budgets on the virtual bench (issue 17: "coverage
checked on the bench, ≥ 90 % per item over many seeds").

:func:`coverage_study` runs a specification's programme on a rate bench for many seeds
(noise on), calibrates each readings set, and counts per item how often the bench's true
value lies within the reported expanded uncertainty, |value − truth| ≤ U. The coverage
c = hits/n is reported with its binomial standard uncertainty √(c(1 − c)/n) and the Wilson
95 % interval, and the normalised errors |value − truth|/u_c are summarised.

The bench of the study (:func:`study_bench`) is the named bench with the three
deterministic, history-dependent effects that the truth formulas of
:mod:`gonio.specs.jjf1535.truth` and :func:`gonio.specs.iec62047_20.truth` leave out
switched off (power-on transient, thermal lag, cross-axis coupling of a turning Earth
rate); every random term (noise, power-cycle scatter, quantisation, equipment errors)
stays on. docs/jjf1535-readings.md#coverage-of-the-budgets states the truths used for the
noise-limited items.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace

from pathlib import Path

import pandas as pd

from gonio.atomic import write_text

from gonio.errors import GonioError
from gonio.formats.rate_readings import RateReadings
from gonio.pipeline.rate import RATE_SPECS, spec_module
from gonio.specs import get

#: Wilson-interval coverage factor (95 %).
_Z95 = 1.959963984540054


@dataclass(frozen=True)
class ItemCoverage:
    """One item's coverage over the seeds."""

    key: str
    clause: str
    n: int
    hits: int
    coverage: float
    u_coverage: float
    wilson_low: float
    wilson_high: float
    median_norm_error: float
    max_norm_error: float


def study_bench(name: str = "mems-adxrs610"):
    """The rate bench of the coverage study: ``name`` with the power-on transient, the thermal
    lag (τ = 1 s) and the cross-axis sensitivity switched off (see module docstring)."""
    from gonio.bench.rate_gyro import load_rate_bench

    b = load_rate_bench(name)
    g = replace(b.gyro, warmup_bias_dps=0.0, thermal_tau_s=1.0, cross_axis_x=0.0,
                cross_axis_y=0.0)
    return replace(b, gyro=g)


#: The reduced programme of the study ({section: {key: value}} over the built-in protocol):
#: small sample counts and short waits, every item still measured.
REDUCED = {
    "jjf1535-2015": {"protocol": {"warmup_s": 600.0},
                     "scale_factor": {"samples_below_100_dps": 5, "samples_from_100_dps": 5,
                                      "rest_samples": 5, "interval_s": 60.0},
                     "temperature": {"soak_s": 1800.0, "bias_samples": 100},
                     "threshold": {"samples": 5, "rest_samples": 5},
                     "resolution": {"samples": 5},
                     "bias": {"samples": 600, "off_time_s": 60.0},
                     "warmup": {"samples": 600, "window_samples": 100, "off_time_s": 60.0},
                     "g_sensitivity": {"samples": 60, "settle_s": 5.0},
                     "arw": {"samples": 6000},
                     "bandwidth": {"cycles": 8}},
    "iec62047-20": {"protocol": {"warmup_s": 600.0},
                    "scale_factor": {"samples": 5},
                    "temperature": {"soak_s": 1800.0, "bias_samples": 60},
                    "stability": {"samples": 50}, "bias": {"samples": 300, "off_time_s": 60.0},
                    "power_on": {"samples": 900, "off_time_s": 60.0},
                    "noise": {"samples": 6000}, "frequency": {"cycles": 8}},
}


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(v)


def reduced_protocol(spec_key: str, path, changes: dict | None = None) -> Path:
    """Write the built-in protocol of ``spec_key`` with the study's reduced sizes
    (:data:`REDUCED`) and ``changes`` ({section: {key: value}}) to ``path``; returns it."""
    from gonio.formats.toml import read_toml
    from gonio.resources import resolve

    if spec_key not in REDUCED:
        raise GonioError(f"no reduced protocol for {spec_key!r}", key="--spec")
    d = read_toml(resolve(spec_key, kind="protocol"))
    for sec, kv in {**REDUCED[spec_key], **(changes or {})}.items():
        d.setdefault(sec, {}).update(kv)
    lines = []
    for sec, tab in d.items():
        lines.append(f"[{sec}]")
        lines += [f"{k} = {_toml_value(v)}" for k, v in tab.items()]
    write_text(Path(path), "\n".join(lines) + "\n")
    return Path(path)


def wilson_interval(hits: int, n: int, z: float = _Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion.

    >>> [round(v, 4) for v in wilson_interval(95, 100)]
    [0.8882, 0.9785]
    """
    if n < 1:
        raise GonioError("a coverage needs at least one trial")
    p = hits / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return max(0.0, c - h), min(1.0, c + h)


def item_coverage(records: list[tuple[float, float, float, float]], key: str = "",
                  clause: str = "") -> ItemCoverage:
    """Coverage of one item from (value, truth, U, u_c) per seed.

    >>> c = item_coverage([(1.0, 1.1, 0.2, 0.1), (1.0, 1.3, 0.2, 0.1)])
    >>> c.hits, c.coverage, round(c.u_coverage, 4)
    (1, 0.5, 0.3536)
    """
    n = len(records)
    if n == 0:
        raise GonioError(f"item {key!r}: no seed gave a measured value with a truth")
    hits = sum(abs(v - t) <= U for v, t, U, _ in records)
    c = hits / n
    lo, hi = wilson_interval(hits, n)
    ne = sorted(abs(v - t) / u if u > 0 else (0.0 if v == t else math.inf)
                for v, t, _, u in records)
    return ItemCoverage(key, clause, n, hits, c, math.sqrt(c * (1 - c) / n), lo, hi,
                        ne[n // 2] if n % 2 else 0.5 * (ne[n // 2 - 1] + ne[n // 2]), ne[-1])


def coverage_study(spec_key: str, seeds, *, bench=None, protocol=None,
                   items: tuple[str, ...] | None = None) -> pd.DataFrame:
    """Simulate (noise on) and calibrate ``spec_key`` for every seed; one row per item with
    n, hits, coverage, u_coverage (binomial), the Wilson 95 % interval and the median and
    largest |value − truth|/u_c. Items without a truth value or not measured in a seed do
    not count for that seed (``n`` says how many did)."""
    spec = get(spec_key)
    if spec.key not in RATE_SPECS:
        raise GonioError(f"{spec.key} is not a rate-gyro specification", key="--spec")
    mod = spec_module(spec)
    b = bench if bench is not None else study_bench(spec.default_bench)
    proto = protocol or spec.default_protocol
    recs: dict[str, list] = {}
    clauses: dict[str, str] = {}
    for seed in seeds:
        res = mod.simulate(b, proto, int(seed), noise=True)
        rd = RateReadings(res.data, {k: str(v) for k, v in res.metadata.items()})
        result = spec.calibrate(rd, proto)
        truth = res.truth["items"]
        for key, it in result.items.items():
            if items is not None and key not in items:
                continue
            clauses[key] = it.clause
            t = truth.get(key, {}).get("value")
            if (not it.measured or it.uncertainty is None or t is None
                    or not math.isfinite(t) or it.uncertainty.U is None):
                continue
            recs.setdefault(key, []).append((float(it.value), float(t),
                                             float(it.uncertainty.U), float(it.uncertainty.u_c)))
    rows = [item_coverage(v, k, clauses[k]).__dict__ for k, v in recs.items()]
    return pd.DataFrame(rows, columns=list(ItemCoverage.__dataclass_fields__))
