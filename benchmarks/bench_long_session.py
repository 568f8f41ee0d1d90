"""Bounded memory for a long zero-stability record: a 24 h 7.3 rest at 1 kHz on the RLG bench.

Simulates a protocol whose zero-stability item takes 25 readings an hour apart (24 h of
rest, 8.64·10⁷ samples a pass, two passes: the noisy run and the noise-free rerun), then
runs the Allan analysis of the captured 7.3 record, and prints wall time and peak memory.

Usage: python benchmarks/bench_long_session.py [HOURS] [RATE_HZ]
Target (issue 14): < 500 MB peak RSS for 24 h at 1 kHz.
"""

from __future__ import annotations

import resource
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.calibration import analyse_zero_stability
from gonio.specs.ogam_draft.protocol import load_protocol

PROTOCOL = """
[protocol]
name = "zero-stability-{hours}h"
[session]
warm_up_s = 0.0
static_s = 60.0
[zero_stability]
readings = {readings}
interval_s = 3600.0
"""


def main(hours: float = 24.0, rate_hz: float = 1000.0) -> dict:
    """Run the benchmark; returns the figures it prints."""
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "zs.toml"
        p.write_text(PROTOCOL.format(hours=hours, readings=int(round(hours)) + 1))
        proto = load_protocol(p)
    bench = replace(load_bench("rlg"), sample_rate_hz=rate_hz)
    t0 = time.perf_counter()
    session = run_session(proto, bench, seed=1)
    t_sim = time.perf_counter() - t0
    noise, src = analyse_zero_stability(session.static_record)
    t_all = time.perf_counter() - t0
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    rec = session.static_record
    out = {"hours": hours, "rate_hz": rate_hz, "samples_per_pass": int(hours * 3600 * rate_hz),
           "record_samples_kept": int(rec.time_s.size), "simulate_s": round(t_sim, 1),
           "total_s": round(t_all, 1), "peak_rss_mb": round(peak_mb),
           "adev_points": 0 if noise is None else int(len(noise.allan.tau_s))}
    print(f"{hours:g} h zero-stability record at {rate_hz:g} Hz: "
          f"{out['samples_per_pass']:.3g} samples a pass (x2), "
          f"{out['record_samples_kept']} kept for the Allan analysis "
          f"({out['adev_points']} τ values); "
          f"simulate {t_sim:.1f} s, total {t_all:.1f} s, peak RSS {peak_mb:.0f} MB "
          f"(target < 500 MB)")
    return out


if __name__ == "__main__":
    args = [float(a) for a in sys.argv[1:3]]
    main(*args)
