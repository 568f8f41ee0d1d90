"""A measured column logged by a real (noisy) chamber logger: every logged temperature differs
from the others, and the first logged row of each temperature segment is still on the ramp
from the previous level. The segment's setting is then the median of its logged values, not
the "most common" one (which, with all values different, is only the first logged row), so no
planned temperature is named missing, for JJF 1535 and IEC 62047-20
(gonio.specs._rate_family.screening.segment_values)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

PINS = Path(__file__).resolve().parent / "data" / "pins"
RAMP_TESTS = ("sf_temperature", "bias_temperature")
TOL_C = 2.5     # the plan-match tolerance of temperature_c (screening.MATCH_TOL), stated apart


def noisy_ramp_copy(src: Path, dst: Path, seed: int = 3) -> int:
    """``src`` with temperature_c of the temperature tests noisy (σ 0.05 °C, every value a
    different float) and the first row of each segment at the temperature of the same test's
    previous segment (the chamber's ramp from there). Returns how many segments start more
    than TOL_C from their level."""
    rng = np.random.default_rng(seed)
    lines = src.read_text(encoding="utf-8").splitlines(keepends=True)
    out, cols, prev_key, far, last = [], None, None, 0, {}
    for line in lines:
        if line.startswith("#") or cols is None:
            if not line.startswith("#"):
                cols = line.rstrip("\n").split(",")
            out.append(line)
            continue
        f = line.rstrip("\n").split(",")
        it = cols.index("temperature_c")
        key = tuple(f[cols.index(c)] for c in ("test", "run", "step"))
        level = float(f[it]) if f[it] else None
        test = f[cols.index("test")]
        if test in RAMP_TESTS and level is not None:
            if key != prev_key and test in last:
                value = last[test]                   # still on the ramp from the last level
                far += abs(value - level) > TOL_C
            else:
                value = level + rng.normal(0.0, 0.05)
            f[it] = f"{value:.4f}"
            last[test] = level
        prev_key = key
        out.append(",".join(f) + "\n")
    dst.write_text("".join(out), encoding="utf-8")
    return far


@pytest.mark.parametrize("spec_key", ["jjf1535-2015", "iec62047-20"])
def test_noisy_temperature_on_the_ramp_names_no_planned_point_missing(spec_key, tmp_path):
    from gonio.specs import get

    proto = PINS / f"{spec_key}-small.toml"
    r = subprocess.run([sys.executable, "-m", "gonio", "simulate", "--spec", spec_key,
                        "--protocol", str(proto), "--seed", "5", "--out", str(tmp_path / "sim")],
                       capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    noisy = tmp_path / "noisy.csv"
    far = noisy_ramp_copy(tmp_path / "sim" / "readings.csv", noisy)
    assert far >= 2, far          # the ramp rows are far enough off to be seen as another level
    spec = get(spec_key)
    import pandas as pd

    d = pd.read_csv(noisy, comment="#")
    t = d.loc[d["test"].isin(RAMP_TESTS), "temperature_c"].dropna()
    assert t.nunique() > 0.75 * len(t)    # a real logger: only the ramp rows repeat a value
    found = spec.screen(noisy, proto)
    miss = [f for f in found if f.code == "programme-point-missing"]
    assert not miss, [f.message for f in miss]
    # the clean simulated file gives none either (the copy only adds noise and ramp rows)
    clean = spec.screen(tmp_path / "sim" / "readings.csv", proto)
    assert not [f for f in clean if f.code == "programme-point-missing"]
