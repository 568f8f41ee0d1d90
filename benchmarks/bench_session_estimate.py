"""The optical bench's run-time estimate against the CPU time it predicts.

``estimate_session`` refuses a session whose estimated computing exceeds ``GONIO_MAX_RUN_S``
(samples / SIMULATED_SAMPLES_PER_S plus a fixed overhead, CPU time of one core). This script
simulates the draft's built-in protocol on each built-in bench and prints the estimate, the
CPU time measured and their ratio; the constant is calibrated to stay within a factor 2 on
the development machine (2 cores). A machine's speed moves the ratio, so this is a
benchmark that prints its figures, not a timed unit test.

Usage: python benchmarks/bench_session_estimate.py [SEED]
"""

from __future__ import annotations

import sys
import time

import numpy as np

from gonio.specs.ogam_draft.bench import load_bench
from gonio.specs.ogam_draft.bench.session import estimate_session, plan_session, run_session
from gonio.specs.ogam_draft.protocol import load_protocol


def main(seed: int = 0) -> int:
    proto = load_protocol("ogam-draft")
    worst = 1.0
    for name in ("rlg", "fog"):
        bench = load_bench(name)
        est = estimate_session(plan_session(proto, bench, np.random.default_rng(seed)), bench,
                               proto)
        t0 = time.process_time()
        run_session(proto, bench, seed=seed)
        cpu = time.process_time() - t0
        ratio = cpu / est.seconds
        worst = max(worst, ratio, 1.0 / ratio)
        print(f"{name}: {est.samples:.4g} samples a pass, estimate {est.seconds:.2f} s, "
              f"CPU {cpu:.2f} s, measured/estimate {ratio:.2f}")
    print(f"largest factor between estimate and measurement: {worst:.2f} (target <= 2)")
    return 0


if __name__ == "__main__":
    sys.exit(main(int(sys.argv[1]) if len(sys.argv) > 1 else 0))
