"""Every item budget of a whole virtual calibration, validated by JCGM 101 Monte Carlo
(the GUM interval y ± U against the Monte Carlo 95 % interval of the same inputs)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.readings import Readings
from gonio.specs.ogam_draft.calibration import analyse, calibrate
from gonio.specs.ogam_draft.protocol import load_protocol
from gonio.specs.ogam_draft.item_uncertainty import monte_carlo_check


@pytest.fixture(scope="module")
def report():
    proto = load_protocol("ogam-draft")
    res = run_session(proto, replace(load_bench("rlg"), sample_rate_hz=5.0), seed=11)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    return analyse(Readings(df, dict(res.metadata)), proto)   # the item budgets themselves


def test_every_item_has_a_budget_and_monte_carlo_agrees(report):
    iu = report.item_uncertainty
    assert set(iu) == {"scale_factor", "scale_factor_nonlinearity", "zero_stability",
                       "angle_deviation", "repeatability", "rate_consistency",
                       "pointing_consistency"}
    assert iu["scale_factor"].k_source == "jcgm101-convolution"
    for name, b in iu.items():
        if b.model is None:           # E: the Annex A budget's own JCGM 101 check (--monte-carlo)
            continue
        mc, _ = monte_carlo_check(b, 200_000, seed=1)
        half = (mc.high - mc.low) / 2
        # the budget's U (B_s, R are stated by their χ² interval instead); K's, whose arcsine
        # table line at the MPE bound dominates u_c, has k from its combined distribution
        U = b.k * b.u_c
        assert half / U == pytest.approx(1.0, abs=0.12), (name, half, U)
        assert mc.value == pytest.approx(b.value, abs=0.05 * U)


def test_E_budget_monte_carlo_through_the_api(tmp_path):
    """--monte-carlo N propagates E's budget (physical, with its arcsine coupling line)
    by JCGM 101 and compares it with the GUM interval."""
    proto = load_protocol("ogam-draft")
    res = run_session(proto, replace(load_bench("rlg"), sample_rate_hz=5.0), seed=12)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    rep = calibrate(Readings(df, dict(res.metadata)), proto, monte_carlo_trials=100_000)
    unc = rep.extra["uncertainty"]
    mc = unc["monte_carlo"]
    half = (mc["interval_arcsec"][1] - mc["interval_arcsec"][0]) / 2
    assert half / unc["U_arcsec"] == pytest.approx(1.0, abs=0.1)
