"""K_l's statement holds every table within the MPE: the table-free belt evaluated at the
measured range −/+ D, not its ends moved out by D.

Any table within its MPE moves the measured range by at most D (``range_table_bound``), so the
range the table-free measurement would have given lies in [r − D, r + D], and the sound
interval is [R_lo(r − D), R_hi(r + D)] of the table-free belt. Moving the ends out,
[R_lo(r) − D, R_hi(r) + D], is the same only where R_hi rises no faster than r; near the noise
floor it rises about twice as fast. The table-free belt is the same budget at MPE 0 (its draws
hold the count quantum alone, the table entering only by its bound), at a K_i pattern whose
range is r + D — a second evaluation, not the code path under test.
"""

from __future__ import annotations

import numpy as np
import pytest

from gonio.specs.ogam_draft.item_uncertainty import (nonlinearity_corrected_budget,
                                                     range_table_bound)

TH = [60.0, 120.0, 180.0, 240.0, 300.0, 360.0]


def _k_i(range_pct: float) -> np.ndarray:
    """Five equal K_i and the 360° round above them, the range ``range_pct`` (% of the mean)."""
    d = range_pct / 100.0 * 3600.0
    for _ in range(5):                        # the mean moves with the raised round
        k = np.array([3600.0] * 5 + [3600.0 + d])
        d = range_pct / 100.0 * float(k.mean())
    return np.array([3600.0] * 5 + [3600.0 + d])


@pytest.mark.parametrize("r_pct", [0.925e-4, 1.85e-4])
def test_the_upper_end_holds_the_table_free_belt_at_the_range_plus_d(r_pct):
    k_i = _k_i(r_pct)
    assert (k_i.max() - k_i.min()) / k_i.mean() * 100 == pytest.approx(r_pct, rel=1e-9)
    d = range_table_bound(k_i, TH, 0.1)
    assert d == pytest.approx(2 * 0.1 / (60 * 3600) * 100, rel=1e-3)   # 2·MPE/60°
    stated = nonlinearity_corrected_budget(k_i, TH, 0.1).interval
    free_at_r = nonlinearity_corrected_budget(k_i, TH, 0.0).interval
    free_above = nonlinearity_corrected_budget(_k_i(r_pct + d), TH, 0.0).interval
    assert stated[1] >= free_above[1] * (1 - 2e-3), (stated, free_above)
    if r_pct < 1e-4:
        # the case the former rule missed: the belt's upper end rises faster than r here
        assert free_at_r[1] + d < 0.9 * free_above[1], (free_at_r, d, free_above)


def test_the_lower_end_holds_the_table_free_belt_at_the_range_minus_d():
    """Far above the noise: the stated lower end is the table-free belt's at r − D."""
    r_pct = 2e-3
    k_i = _k_i(r_pct)
    d = range_table_bound(k_i, TH, 0.1)
    stated = nonlinearity_corrected_budget(k_i, TH, 0.1).interval
    free_below = nonlinearity_corrected_budget(_k_i(r_pct - d), TH, 0.0).interval
    assert stated[0] == pytest.approx(free_below[0], rel=2e-3)
    assert stated[0] < r_pct - d < r_pct + d < stated[1]


def test_a_range_below_d_has_its_lower_end_at_zero():
    k_i = _k_i(0.5e-4)
    assert nonlinearity_corrected_budget(k_i, TH, 0.1).interval[0] == 0.0
