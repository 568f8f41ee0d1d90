"""Benchmark: gyro-triad alignment and the extended thermal model on the packaged bench.

Prints, for the ``mems-triad`` bench and the ``triad-alignment`` protocol:
- alignment: time to simulate and to estimate (with 2000 Monte Carlo trials); the largest
  |M̂ − M|/u(M); the largest cross-axis sensitivity before alignment and the largest true
  residual leakage after M⁻¹; the averaging time chosen from the Allan deviation;
- thermal model: time to simulate the chamber programme and to identify; the orders chosen;
  bias and scale-factor rms errors before/after compensation of a second record (new seed);
  the ramp error of the static-soak model on the chamber temperature, and after the lag.

Run: ``python benchmarks/bench_triad.py [--seed N]``
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout

import numpy as np  # noqa: E402

from gonio.specs.triad_alignment.thermal_model import (compensate_record,  # noqa: E402
                                                      identify_thermal_model)
from gonio.specs.triad_alignment.analysis import estimate_alignment  # noqa: E402
from gonio.specs.triad_alignment.bench import (load_triad_bench, load_triad_protocol,  # noqa: E402
                               run_alignment_session, run_thermal_session)
from gonio.specs.triad_alignment.readings import TriadReadings  # noqa: E402


def _readings(s) -> TriadReadings:
    return TriadReadings(s.readings.assign(line=np.arange(len(s.readings))), s.metadata, "bench")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    b = load_triad_bench("mems-triad")
    p = load_triad_protocol("triad-alignment")
    t0 = time.perf_counter()
    s = run_alignment_session(p, b, a.seed)
    t1 = time.perf_counter()
    res = estimate_alignment(_readings(s), monte_carlo=2000, seed=a.seed)
    t2 = time.perf_counter()
    m = b.system_matrix
    off = ~np.eye(3, dtype=bool)
    print(f"alignment: simulate {t1 - t0:.2f} s, estimate+MC {t2 - t1:.2f} s, "
          f"{res.n_dwells} dwells")
    print(f"  max |M̂ − M|/u = {np.max(np.abs(res.system_matrix - m) / res.u_system_matrix):.2f}")
    print(f"  cross-axis before: max |M_ij/M_ii| = {np.max(np.abs((m / np.diag(m)[:, None])[off])):.3e}; "
          f"after M̂⁻¹: max |leakage| = {np.max(np.abs(res.leakage_against(m)[off])):.2e} "
          f"(u ≤ {np.max(res.leakage_u[off]):.1e})")
    print(f"  GUM/MC u ratio (M, b): {np.min(np.sqrt(np.diag(res.cov_theta)) / res.u_mc_theta):.3f}"
          f" … {np.max(np.sqrt(np.diag(res.cov_theta)) / res.u_mc_theta):.3f}")
    if res.averaging is not None:
        print(f"  averaging time: τ ≥ {max(res.averaging.tau_needed_s):g} s for "
              f"{res.averaging.noise_limit_dps * 1e3:.2f} m°/s")
    t0 = time.perf_counter()
    th = run_thermal_session(p, b, a.seed)
    th2 = run_thermal_session(p, b, a.seed + 1)
    t1 = time.perf_counter()
    mod = identify_thermal_model(_readings(th)).channels["z"]
    modc = identify_thermal_model(_readings(th), temperature="chamber").channels["z"]
    t2 = time.perf_counter()
    c = compensate_record(mod, _readings(th2))
    print(f"thermal: simulate 2 programmes {t1 - t0:.2f} s, identify ×2 {t2 - t1:.2f} s")
    print(f"  orders (ϑ/U): K {mod.scale.n_t}/{mod.scale.n_u}, b {mod.bias.n_t}/{mod.bias.n_u}, "
          f"ARW {mod.arw.n_t}")
    print(f"  bias rms {c.rms_bias_before_dps:.4f} → {c.rms_bias_after_dps:.4f} °/s; "
          f"scale-factor rms {c.rms_scale_before_rel * 1e6:.0f} → {c.rms_scale_after_rel * 1e6:.1f} ppm")
    r = modc.ramp
    print(f"  ramps on chamber temperature: static-soak rms {r.rms_static_model_dps:.4f} °/s, "
          f"lag {r.lag_text()} (bench 300 s) → {r.rms_with_lag_dps:.4f} °/s; "
          f"γ·dT/dt → {r.rms_with_ramp_term_dps:.4f} °/s; hysteresis {r.hysteresis_dps:.3f} °/s")
    print(f"  ramps on the internal sensor: rms {mod.ramp.rms_static_model_dps:.4f} °/s; "
          f"lag {mod.ramp.lag_text()} (bench: none)")


if __name__ == "__main__":
    main()
