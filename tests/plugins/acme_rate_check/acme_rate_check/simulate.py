"""ACME RC-1 on a virtual bench of its own: a rate gyro y = K·Ω + b + white noise on a rate
table whose rate is off by a relative error e. The truth comes from these physical
parameters, never from the estimator."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from gonio.atomic import output_dir, write_text
from gonio.errors import GonioError

from acme_rate_check.items import KEY, Readings, load_protocol

#: The built-in bench: true K (mV per °/s), bias b (mV), noise σ (mV), table error bound.
BENCHES = {"acme-bench": {"K": 25.0, "b": 12.5, "noise": 4.0, "table_u_rel": 1e-4}}


def _bench(bench) -> dict:
    if isinstance(bench, dict):
        return bench
    if bench not in BENCHES:
        raise GonioError(f"unknown bench {bench!r} (known: {', '.join(BENCHES)})", key="bench")
    return BENCHES[bench]


def truth(bench, protocol=None) -> dict:
    """The true items from the bench's parameters (the rate table's error drawn per run is
    in the readings' truth.json, not here)."""
    b = _bench(bench)
    return {"scale_factor": {"value": b["K"], "how": "bench parameter K"},
            "bias": {"value": b["b"] / b["K"], "how": "bench parameters b / K"}}


def run_trial(bench, protocol, seed: int):
    """One run held in memory: (Readings, truth dict)."""
    b, p = _bench(bench), load_protocol(protocol)
    rng = np.random.default_rng(seed)
    e = rng.uniform(-1, 1) * b["table_u_rel"] * np.sqrt(3)      # this table's rate error
    rates = [s * r for r in p["rates_dps"] for s in (1, -1)]
    x = np.repeat(rates, p["samples"])
    y = b["K"] * x * (1 + e) + b["b"] + rng.normal(0, b["noise"], x.size)
    md = {"spec": KEY, "output_unit": "mV", "rate_table_u_rel": repr(b["table_u_rel"]),
          "seed": str(seed), "table": "rate table (virtual)", "instrument": "ACME G-1"}
    t = {"items": truth(b), "rate_error_rel": e}
    return Readings(pd.DataFrame({"rate_dps": x, "output": y}), md), t


def simulate(out, *, protocol=KEY, bench="acme-bench", seed: int = 0) -> dict[str, Path]:
    """Write ``readings.csv`` and ``truth.json`` of one run into ``out``."""
    rd, t = run_trial(bench, protocol, seed)
    head = "".join(f"# {k}: {v}\n" for k, v in rd.metadata.items())
    out = Path(out)
    with output_dir(out) as stage:
        write_text(stage / "readings.csv", head + rd.data.to_csv(index=False, lineterminator="\n"))
        write_text(stage / "truth.json", json.dumps(t, indent=2) + "\n")
    return {"readings": out / "readings.csv", "truth": out / "truth.json"}
