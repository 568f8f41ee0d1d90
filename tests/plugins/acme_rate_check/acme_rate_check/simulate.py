"""ACME RC-1 on a virtual bench of its own: a rate gyro y = K±·Ω(1 + e) + b + white noise,
K± = K(1 ± a/2) for Ω ≷ 0 (a: the gyro's scale-factor asymmetry), on a rate table whose rate
is off by a relative error e. The truth comes from these physical parameters and the
programme, never from the estimator."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from gonio.atomic import output_dir, write_text
from gonio.kit import GonioError

from acme_rate_check.items import KEY, Readings, load_protocol, with_lines

#: The built-in bench: true K (mV per °/s), bias b (mV), noise σ (mV), table error bound,
#: scale-factor asymmetry a (ppm).
BENCHES = {"acme-bench": {"K": 25.0, "b": 12.5, "noise": 1.0, "table_u_rel": 1e-4,
                          "asym_ppm": 800.0}}


def _bench(bench) -> dict:
    if isinstance(bench, dict):
        return bench
    if bench not in BENCHES:
        raise GonioError(f"unknown bench {bench!r} (known: {', '.join(BENCHES)})", key="bench")
    return BENCHES[bench]


def truth(bench, protocol=None) -> dict:
    """The true items from the bench's parameters and the programme (the rate table's error
    drawn per run is in the readings' truth.json, not here). The line through outputs taken
    at ±Ω_j has slope (K+ + K−)/2 = K and intercept b + (K+ − K−)/2 · mean Ω_j, so the
    bias B (4.3: intercept / K) is b/K + (a/2)·mean Ω_j."""
    b, p = _bench(bench), load_protocol(protocol)
    a = b["asym_ppm"] * 1e-6
    return {"scale_factor": {"value": b["K"], "how": "bench parameter K"},
            "bias": {"value": b["b"] / b["K"] + a / 2 * float(np.mean(p["rates_dps"])),
                     "how": "bench parameters b / K + (a/2)·mean rate of the programme"},
            "asymmetry": {"value": b["asym_ppm"], "how": "bench parameter a"}}


def run_trial(bench, protocol, seed: int):
    """One run held in memory: (Readings, truth dict)."""
    b, p = _bench(bench), load_protocol(protocol)
    rng = np.random.default_rng(seed)
    e = rng.uniform(-1, 1) * b["table_u_rel"] * np.sqrt(3)      # this table's rate error
    rates = [s * r for r in p["rates_dps"] for s in (1, -1)]
    x = np.repeat(rates, p["samples"])
    k = b["K"] * (1 + np.sign(x) * b["asym_ppm"] * 1e-6 / 2)        # K+ and K−
    y = k * x * (1 + e) + b["b"] + rng.normal(0, b["noise"], x.size)
    md = {"spec": KEY, "output_unit": "mV", "rate_table_u_rel": repr(b["table_u_rel"]),
          "seed": str(seed), "table": "rate table (virtual)", "instrument": "ACME G-1"}
    t = {"items": truth(b, p), "rate_error_rel": e}
    return Readings(with_lines(pd.DataFrame({"rate_dps": x, "output": y}), len(md)), md), t


def simulate(out, *, protocol=KEY, bench="acme-bench", seed: int = 0,
             samples: int | None = None) -> dict[str, Path]:
    """Write ``readings.csv`` and ``truth.json`` of one run into ``out`` (``samples``: per
    rate, overriding the protocol's; ``gonio simulate --samples``)."""
    if samples is not None:
        protocol = {**load_protocol(protocol), "samples": samples}
    rd, t = run_trial(bench, protocol, seed)
    head = "".join(f"# {k}: {v}\n" for k, v in rd.metadata.items())
    out = Path(out)
    with output_dir(out) as stage:
        rows = rd.data.drop(columns="line").to_csv(index=False, lineterminator="\n")
        write_text(stage / "readings.csv", head + rows)
        write_text(stage / "truth.json", json.dumps(t, indent=2) + "\n")
    return {"readings": out / "readings.csv", "truth": out / "truth.json"}
