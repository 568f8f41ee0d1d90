"""Time ``gonio validate --trials 200`` (default case, 100 Hz, 2 workers) and print it.

Target (issue 3): under 2 minutes on a 2-core machine. Runs the command as a user
would (``python -m gonio validate``) from the source tree, so start-up is included.

    python benchmarks/bench_validate.py [--trials 200] [--cases default]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--cases", default="default")
    ap.add_argument("--workers", type=int, default=2)
    a = ap.parse_args()
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    with tempfile.TemporaryDirectory() as d:
        cmd = [sys.executable, "-m", "gonio", "validate", "--trials", str(a.trials),
               "--cases", a.cases, "--workers", str(a.workers), "--out", d]
        t0 = time.perf_counter()
        out = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if out.returncode:
            sys.stderr.write(out.stderr)
            return out.returncode
        data = json.loads((Path(d) / "validation.json").read_text())
    n_cal = a.trials * len(data["cases"])
    print(out.stdout, end="")
    print(f"gonio validate --trials {a.trials} --cases {a.cases} --workers {a.workers}: "
          f"{wall:.1f} s wall, {n_cal} calibrations, {wall / n_cal * 1e3:.0f} ms each "
          f"(target < 120 s for 200 trials of the default case): "
          f"{'OK' if wall < 120 or a.trials != 200 else 'SLOW'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
