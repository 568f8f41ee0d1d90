"""The optical draft's whole programme (7.1–7.7, 249 readings, about 8 h of bench time) taken
through the instruments at high speed, interrupted by SIGINT and resumed, calibrates to the
same seven items as ``gonio simulate`` of the same bench and seed, each within the two
results' U: ``benchmarks/acquire_resume_draft.py`` run as a user would (``gonio bench serve``,
``gonio acquire``, ``gonio acquire --resume``, ``gonio simulate``, ``gonio calibrate`` as
processes talking through pyvisa-py). About 2 min."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "acquire_resume_draft.py"


def test_whole_draft_programme_interrupted_and_resumed(tmp_path):
    # --speed 250: the host may take 120 ms between zeroing and a reading before it misses
    # Annex A.1's 0.5 min (at --speed 500 a loaded machine did: docs/instruments.md)
    p = subprocess.run([sys.executable, str(SCRIPT), "--speed", "250", "--stop-after", "120",
                        "--dir", str(tmp_path)], capture_output=True, text=True, timeout=900)
    out = p.stdout
    assert p.returncode == 0, out + p.stderr
    first = re.search(r"first pass: exit (\d+) after [\d.]+ s, (\d+) readings kept, "
                      r"header '([^']*)'", out)
    assert first and first.group(1) == "130", out          # stopped by the SIGINT, not a fault
    assert 120 <= int(first.group(2)) < 249 and "incomplete" in first.group(3), out
    assert re.search(r"resume: [\d.]+ s, 249 readings in all, header '# acquisition: complete'",
                     out), out
    # the simulation also takes the built-in programme's in-situ tilt estimate (12 rests,
    # beyond the draft), which gonio acquire does not run yet and says so
    assert "[tilt_estimate] (beyond the draft) is not run" in p.stdout + p.stderr
    assert "simulated: 261 readings" in out and "7 of 7 items within U" in out, out
    assert "OUTSIDE U" not in out
