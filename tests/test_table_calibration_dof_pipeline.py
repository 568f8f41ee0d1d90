"""Through the pipeline (``gonio calibrate --table-calibration``): a rotary-table calibration
stated with fewer degrees of freedom never narrows the certified intervals of the range items
K_l (draft 7.2), C_v (7.6) and C_g (7.7), whose Monte Carlo draws the calibration's errors as
t_ν (JCGM 101 6.4.9). The same readings (``gonio simulate --seed 3``) and the same table
calibration with ν = ∞ (no ``dof``), 30, 5 and 3: each item's interval width is
non-decreasing along that sequence (the independent check: a less well known input cannot
make a 95 % interval of the same measurement narrower; a width is compared only with the
same item's at another ν). ν < 3 is refused (exit 2, one line).

Before the χ² scales were drawn from a stream of their own and the choice of the extreme's
spread was floored at its normal-draws value, C_g's interval at ν = 30 was narrower than at
∞ (1.942e-4 against 1.993e-4 %), and at ν = 2 half as wide."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from gonio.pipeline.dispatch import calibrate
from gonio.specs.ogam_draft.simulate import simulate

ITEMS = ("scale_factor_nonlinearity", "rate_consistency", "pointing_consistency")
NUS = (None, 30, 5, 3)
#: the table errors of the reviewer's file (a 1st and 2nd harmonic) at a fifth of their size,
#: so that they lie within the readings' table MPE 0.1″ + 3u (the file itself, to 0.46″, is
#: a table out of specification, refused by ``screen_against_mpe``); u 0.03″ at every position
ERRORS = tuple(0.2 * e for e in (0.0, 0.159808, 0.059808, -0.1, -0.259808, -0.359808, -0.2,
                                 0.159808, 0.259808, -0.1, -0.459808, -0.359808))


def _table_file(path, nu):
    head = "table_deg,error_arcsec,u_arcsec" + ("" if nu is None else ",dof")
    rows = [f"{30 * i},{e:.6f},0.03" + ("" if nu is None else f",{nu}")
            for i, e in enumerate(ERRORS)]
    path.write_text("\n".join([head, *rows]) + "\n", encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def readings(tmp_path_factory):
    d = tmp_path_factory.mktemp("sim")
    simulate(d, seed=3)
    return d / "readings.csv"


@pytest.mark.slow
def test_intervals_never_narrow_as_nu_falls(readings, tmp_path):
    widths = {it: [] for it in ITEMS}
    for nu in NUS:
        out = tmp_path / f"cal{nu}"
        calibrate(readings, out, spec_key="ogam-draft",
                  table_calibration=str(_table_file(tmp_path / f"tc{nu}.csv", nu)))
        items = json.loads((out / "results.json").read_text(encoding="utf-8"))["items"]
        for it in ITEMS:
            lo, hi = items[it]["uncertainty"]["interval"]
            widths[it].append(hi - lo)
    # K_l's belt is a Monte Carlo's: between ν = ∞ and 30 the widths agree within its
    # resolution (0.13 % apart, narrower, on the watermarked seed's file); never narrower by more
    for it, w in widths.items():
        assert all(b >= a * (1 - 2e-3) for a, b in zip(w, w[1:])), (it, dict(zip(NUS, w)))
    # ν = 3 is felt: K_l's interval clearly wider than at ∞
    assert widths["scale_factor_nonlinearity"][-1] > 1.02 * widths["scale_factor_nonlinearity"][0]


def test_dof_two_refused_exit_2(readings, tmp_path):
    f = _table_file(tmp_path / "tc2.csv", 2)
    r = subprocess.run([sys.executable, "-m", "gonio", "calibrate", str(readings),
                        "--table-calibration", str(f), "--out", str(tmp_path / "out")],
                       capture_output=True, text=True)
    assert r.returncode == 2
    err = r.stderr.strip()
    assert len(err.splitlines()) == 1 and "tc2.csv:2: column dof: dof must be >= 3" in err
    assert "Traceback" not in r.stderr
