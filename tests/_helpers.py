"""Helpers shared by several test modules (not fixtures: plain functions)."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

REPO = Path(__file__).resolve().parents[1]


def load_by_path(path: Path | str, name: str | None = None) -> ModuleType:
    """The Python file ``path`` (relative to the repository, or absolute) loaded as a module
    named ``name`` (default: the file's stem), for a test of a script, benchmark or another
    test module that is no package's module."""
    path = REPO / path
    spec = importlib.util.spec_from_file_location(name or path.stem, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def transient_interval_means(a_dps: float, tau_s: float, t_s, dt_s: float = 1.0):
    """The power-on transient A·e^(−t/τ) as a sampling gyro reads it: its exact mean over
    each sample's interval [t, t + dt], A·τ/dt·(e^(−t/τ) − e^(−(t + dt)/τ)) (the closed form
    of the integral, computed here outside gonio's truths), for sample times ``t_s``."""
    import numpy as np

    t = np.asarray(t_s, dtype=float)
    return a_dps * tau_s / dt_s * (np.exp(-t / tau_s) - np.exp(-(t + dt_s) / tau_s))


def power_on_record(t_s, y_dps, p: int):
    """One power-on record as the IEC 5.3.3.5/5.3.3.9 items take it: (the blocks' mean
    times, the means of ``p`` consecutive samples, the samples); ``len(y_dps)`` a multiple
    of ``p``."""
    import numpy as np

    t, y = np.asarray(t_s, dtype=float), np.asarray(y_dps, dtype=float)
    return t.reshape(-1, p).mean(1), y.reshape(-1, p).mean(1), y


def tiny_ogam_protocol():
    """The smallest ogam-draft programme the validation and the screens run: a 5-s static
    record, 7.1 at two stops (180°, 360°) and 7.4 in two series of three positions (120°,
    240°, 360°), read 2 s after each stop, rests of 3 s."""
    from gonio.specs.ogam_draft.protocol import parse_protocol

    return parse_protocol({
        "protocol": {"name": "tiny"},
        "session": {"static_s": 5.0, "warm_up_s": 0.0},
        "scale_factor": {"rounds": [{"stop_deg": 180.0}, {"stop_deg": 360.0}],
                         "read_delay_s": 2.0, "rest_s": 3.0},
        "angle_deviation": {"series": 2, "rest_s": 3.0, "read_delay_s": 2.0,
                            "rounds": [{"stop_deg": 120.0 * i} for i in range(1, 4)]},
    })


def small_ogam_bench():
    """The virtual bench :func:`tiny_ogam_protocol` runs on: 76434.87 counts/°, ARW
    0.003 °/√h, counts quantised, table positioning noise 0.05″, latitude 40°, 10 Hz."""
    from gonio.specs.ogam_draft.bench import Bench, InstrumentConfig, TableConfig

    inst = InstrumentConfig(nominal_scale_factor_counts_per_deg=76434.87, arw_dpsh=0.003,
                            quantisation=True)
    return Bench("small", inst, TableConfig(positioning_random_arcsec=0.05), latitude_deg=40.0,
                 sample_rate_hz=10.0)


def plant_71_counts(readings, out, counts: int, stop_deg: float = 60.0, series: int = 1,
                    rate: str = "60.0", orientation: str = "up", test: str = "scale_factor"):
    """A copy of the optical readings file ``readings`` at ``out`` (folders made) with
    ``counts`` added to ``gyro_counts`` of the ``test`` reading (7.1, ``scale_factor``, unless
    told) of ``series`` at ``rate`` and ``orientation`` whose ``table_deg`` is ``stop_deg``: a
    typo of 3600 · ``counts`` / K ″ in one reading. Returns (the reading's 1-based line number,
    out)."""
    readings, out = Path(readings), Path(out)
    lines = readings.read_text().splitlines(keepends=True)
    i = next(n for n, ln in enumerate(lines)
             if (p := ln.split(","))[0] == test and len(p) > 7
             and p[1] == str(series) and p[3] == rate and p[4] == orientation
             and float(p[6]) == float(stop_deg))
    p = lines[i].rstrip("\n").split(",")
    p[7] = str(int(p[7]) + int(counts))
    lines[i] = ",".join(p) + "\n"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("".join(lines))
    return i + 1, out
