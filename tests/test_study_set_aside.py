"""A reading the calibration's screening set aside (NaN in a study's trial) is no comparison:
R's ensemble truth and prediction are over the trials that have each position's s_i."""

import math

import numpy as np

from gonio.specs.ogam_draft.item_coverage import item_coverage


def _rec(s_points, value):
    return {"repeatability": {"value": value, "U": 1.0, "u_c": 0.5, "k": 2.0, "nu": 1.0,
                              "interval": [0.0, 3.0 * value], "s_points": s_points}}


def test_repeatability_with_a_position_read_once_neither_crashes_nor_gives_nan():
    recs = [_rec([0.6, 1.0, math.nan], 1.0), _rec([0.8, 1.2, 1.5], 1.5),
            _rec([0.7, 0.9, 1.4], 1.4)]
    c = item_coverage(recs)["repeatability"]
    # σ_i by hand: the RMS over the trials that have s_i (the third position: two trials)
    sig = [math.sqrt((0.36 + 0.64 + 0.49) / 3), math.sqrt((1.0 + 1.44 + 0.81) / 3),
           math.sqrt((2.25 + 1.96) / 2)]
    assert c["ensemble_truth"] == max(sig) == sig[2]
    assert c["positions_without_s"] == {"trial_points": 1, "positions": 0}
    p = c["predicted"]
    assert all(np.isfinite([p["z_chi2_mean"], p["z_chi2_sd"], p["interval_coverage"]]))
    assert p["points"] == 3 and "approximate" in p
    # with every s_i present: no note, and the prediction as before
    full = item_coverage([_rec([0.6, 1.0, 0.3], 1.0), _rec([0.8, 1.2, 0.4], 1.2)])
    assert "positions_without_s" not in full["repeatability"]
    assert "approximate" not in full["repeatability"]["predicted"]
