"""The optical draft's whole programme (7.1–7.7 and the in-situ tilt estimate's 12 rests, 261
readings) taken through the instruments at high speed, interrupted by SIGINT and resumed,
calibrates to the same seven items as ``gonio simulate`` of the same bench and seed, each
within the two results' U, K corrected by a tilt estimate that agrees with the simulation's
within U: ``benchmarks/acquire_resume_draft.py`` run as a user would (``gonio bench serve``,
``gonio acquire``, ``gonio acquire --resume``, ``gonio simulate``, ``gonio calibrate`` as
processes talking through pyvisa-py).

The programme is the draft's with shorter waits (:func:`shorter_waits`): every clause, round,
series, rate, orientation and tilt-estimate rest as the draft has them (the same 261
readings), each reading at the draft's delay after arrival, but 20 s rests instead of 60 s
and 7.3's 15 readings 1 min apart instead of 5 min: 3.6 h of planned bench time instead of
7.1 h (``programme_duration_s``), some 50 s less at ``--speed 250``. The claim (interrupted
and resumed, the instruments' readings calibrate as the simulation's) does not depend on how
long the table rests after a reading; Annex A.1's time to a reading, which the host's
latency × ``--speed`` eats into, is unchanged."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "benchmarks" / "acquire_resume_draft.py"


def shorter_waits(out: Path) -> Path:
    """protocols/ogam-draft.toml with 20 s rests (each ``rest_s = 60.0``: 7.1, 7.4/7.5, 7.6,
    7.7; still longer than every ``read_delay_s``) and 7.3's readings 60 s apart."""
    text = (ROOT / "protocols" / "ogam-draft.toml").read_text(encoding="utf-8")
    assert text.count("\nrest_s = 60.0\n") == 4 and text.count("\ninterval_s = 300.0\n") == 1
    text = text.replace("\nrest_s = 60.0\n", "\nrest_s = 20.0\n")
    text = text.replace("\ninterval_s = 300.0\n", "\ninterval_s = 60.0\n")
    out.write_text(text, encoding="utf-8")
    return out


def test_whole_draft_programme_interrupted_and_resumed(tmp_path):
    # --speed 250: the host may take 120 ms between zeroing and a reading before it misses
    # Annex A.1's 0.5 min (at --speed 500 a loaded machine did: docs/instruments.md)
    # --stop-after 140: the bench holds its clock once it has answered 140 readings (129 rows
    # where none is taken again), so the SIGINT comes mid-programme whatever the load; the
    # script's gonio processes die with it (a timeout here kills it)
    proto = shorter_waits(tmp_path / "ogam-draft-shorter-waits.toml")
    p = subprocess.run([sys.executable, str(SCRIPT), "--speed", "250", "--stop-after", "140",
                        "--protocol", str(proto), "--dir", str(tmp_path)],
                       capture_output=True, text=True, timeout=900)
    out = p.stdout
    assert p.returncode == 0, out + p.stderr
    first = re.search(r"first pass: exit (\d+) after [\d.]+ s, (\d+) readings kept, "
                      r"header '([^']*)'", out)
    assert first and first.group(1) == "130", out          # stopped by the SIGINT, not a fault
    assert 110 <= int(first.group(2)) <= 129 and "incomplete" in first.group(3), out
    # 249 readings of 7.1–7.7 and the built-in programme's 12 tilt-estimate rests (beyond the
    # draft), acquired as the simulation takes them
    assert re.search(r"resume: [\d.]+ s, 261 readings in all, header '# acquisition: complete'",
                     out), out
    assert "simulated: 261 readings" in out and "7 of 7 items within U" in out, out
    assert "OUTSIDE U" not in out
    # both calibrations correct K by their own measured tilt, and the tilts agree within U
    assert out.count("12 rests; K stated tilt_corrected") == 2, out
    assert "tilt estimates agree within U" in out, out
