"""IEC 62047-20 5.3.3.5 drift after power-on: the budget checked against a Monte Carlo of its
own estimator on records with a known exponential power-on transient and white noise (truths
computed here from the noise-free records, outside gonio's formulas).

The reading is a maximum over 2 × 90 smoothed values, so noise raises it. The earlier budget
(σ from first differences and the reference part's spread, both of which the transient's
slope enters, and a 95 % bound of the largest excursion divided by 2) left the value a
one-sided +0.2…+0.4 u_c high with z sd 0.12–0.35 where a transient is present. The value
now has the midpoint of its selection excess removed, σ is read from second differences.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.analysis.coverage import clopper_pearson
from gonio.specs.iec62047_20 import items as I


def _study(a_dps: float, tau_s: float, trials: int, seed: int, sigma_dps: float = 0.01):
    """z = (value − truth)/u_c and the U hits of :func:`power_on_drift_budget` over two
    power-ons of 900 samples at 0.1 s, smoothing 10, reference 60 samples, no drift."""
    rng = np.random.default_rng(seed)
    n, P, nr = 900, 10, 60
    t = np.arange(n) * 0.1
    tr = a_dps * np.exp(-t / tau_s)
    tt = t.reshape(-1, P).mean(1)
    truth = float(np.max(np.abs(tr.reshape(-1, P).mean(1) - tr[:nr].mean())))
    z, hits = [], 0
    for _ in range(trials):
        recs = []
        for _r in range(2):
            y = tr + sigma_dps * rng.standard_normal(n)
            recs.append((tt, y.reshape(-1, P).mean(1), y))
        val, vals, u, m = I.power_on_drift_budget(recs, nr, lambda sep: 0.0)
        assert max(vals) >= val >= 0.0 and 1 <= m <= 180
        z.append((val - truth) / u.u_c)
        hits += abs(val - truth) <= u.U
    return np.array(z), hits


@pytest.mark.parametrize("a_dps,tau_s", [(1.0, 300.0), (1.0, 30.0)])
def test_power_on_drift_budget_with_transient(a_dps, tau_s):
    z, hits = _study(a_dps, tau_s, 300, seed=int(tau_s))
    assert clopper_pearson(hits, z.size)[1] >= 0.95, hits
    assert abs(z.mean()) < 0.3, z.mean()          # was +0.39 (τ 300 s), +0.15 (τ 30 s)
    assert 0.55 <= z.std() <= 1.3, z.std()        # was 0.35, 0.12


def test_power_on_drift_budget_without_transient():
    """No transient (the coverage study's bench): the value is a maximum of |noise|, one-sided
    and narrower than a normal value, so z sd stays low whatever symmetric u; U must cover."""
    z, hits = _study(0.0, 30.0, 300, seed=7)
    assert clopper_pearson(hits, z.size)[1] >= 0.95, hits
    assert z.mean() < 1.5


@pytest.mark.parametrize("a_dps", [0.0, 0.12])
def test_power_on_drift_budget_at_the_study_signal_to_noise(a_dps):
    """The reduced study's power-on records: white noise σ_y = 0.095 °/s per 0.1-s sample
    (the ADXRS610 bench's 1.8 °/√h), with the bench file's transient (0.12 °/s, τ 150 s,
    about 1.7 σ of a smoothed value over the 90-s record) and without it. U covers in both;
    the value reads high (z mean about +0.55 and +1.1) with z sd about 0.45 and 0.35: at this
    signal-to-noise ratio most of the 180 smoothed values contend for the maximum, whose
    spread is far below σ (docs/iec62047-20-readings.md#over-wide-budgets-left). The z sd
    check pins that documented limitation: it fails when the estimator improves, and the
    docs and README tables must then follow."""
    z, hits = _study(a_dps, 150.0, 300, seed=1, sigma_dps=0.095)
    assert clopper_pearson(hits, z.size)[1] >= 0.95, hits
    assert 0.0 < z.mean() < 1.5 and z.std() < 0.7, (z.mean(), z.std())
