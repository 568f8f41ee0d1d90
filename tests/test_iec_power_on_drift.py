"""IEC 62047-20 5.3.3.5 drift after power-on: the budget checked against a Monte Carlo of its
own estimator on records with a known exponential power-on transient, white noise and (last
test) a rate random walk drawn here with numpy's cumsum (truths computed here from the
noise-free records, outside gonio's formulas).

The reading is a maximum over 2 × 90 smoothed values, so noise raises it. The midpoint rule
(reading less c_m·σ/2) removed about half the selection excess where most smoothed values
contend (a transient that has died away): at the study bench's signal-to-noise ratio the
value read +0.55…+1.1 u_c high with z sd 0.35–0.45. The excess is now the parametric
bootstrap of the fitted records (c + A·e^(−t/τ) plus the record's noise), and u the
corrected estimate's spread in the same replicates. The statement is the 95 % interval of
the same replicates (a pivot, 2.5 % each side, its lower end at or above 0), and a hit is
the truth inside it.
"""

from __future__ import annotations

import numpy as np
import pytest

from gonio.analysis.coverage import clopper_pearson
from gonio.specs.iec62047_20 import items as I


def _study(a_dps: float, tau_s: float, trials: int, seed: int, sigma_dps: float = 0.01,
           rrw_dps_sqrt_s: float = 0.0):
    """z = (value − truth)/u_c and the interval's hits of :func:`power_on_drift_budget` over two
    power-ons of 900 samples at 0.1 s, smoothing 10, reference 60 samples; white noise
    ``sigma_dps`` per sample and a rate random walk of ``rrw_dps_sqrt_s`` (given to the
    budget as its E[K²])."""
    rng = np.random.default_rng(seed)
    n, P, nr, dt = 900, 10, 60, 0.1
    t = np.arange(n) * dt
    tr = a_dps * np.exp(-t / tau_s)
    tt = t.reshape(-1, P).mean(1)
    truth = float(np.max(np.abs(tr.reshape(-1, P).mean(1) - tr[:nr].mean())))
    coef = (rrw_dps_sqrt_s ** 2, 0.0) if rrw_dps_sqrt_s else None
    z, hits = [], 0
    for _ in range(trials):
        recs = []
        for _r in range(2):
            walk = np.cumsum(rng.standard_normal(n)) * rrw_dps_sqrt_s * np.sqrt(dt)
            y = 0.3 + tr + walk + sigma_dps * rng.standard_normal(n)
            recs.append((tt, y.reshape(-1, P).mean(1), y))
        val, vals, u, m = I.power_on_drift_budget(recs, nr, lambda sep: 0.0, coef)
        assert max(vals) >= val >= 0.0 and 1 <= m <= 180
        z.append((val - truth) / u.u_c)
        lo, hi = u.interval              # the statement: the replicates' 95 % interval
        assert u.k is None and 0.0 <= lo <= val <= hi
        hits += lo <= truth <= hi
    return np.array(z), hits


@pytest.mark.parametrize("a_dps,tau_s", [(1.0, 300.0), (1.0, 30.0)])
def test_power_on_drift_budget_with_transient(a_dps, tau_s):
    """400 trials: the first 100 of seed 300 hold the truth in 91 intervals (the pivot alone:
    88; value ± 1.96 u_c: 91), a run of high values (z sd 1.18 there); the 400 held 380 in
    the pivot alone (0.950, z +0.15, sd 1.00), fresh seeds 1 and 2: 384 and 382."""
    z, hits = _study(a_dps, tau_s, 400, seed=int(tau_s))
    assert clopper_pearson(hits, z.size)[1] >= 0.95, hits
    assert abs(z.mean()) < 0.3, z.mean()
    assert 0.7 <= z.std() <= 1.3, z.std()


def test_power_on_drift_budget_at_the_study_signal_to_noise():
    """The study bench's signal-to-noise: white noise σ_y = 0.095 °/s per 0.1-s sample (the
    ADXRS610 bench's 1.8 °/√h) and its transient (0.12 °/s, τ 150 s, about 1.7 σ of a
    smoothed value over the 90-s record): most of the 180 smoothed values contend for the
    maximum. The midpoint rule read +1.1 u_c high with z sd 0.35; the bootstrap's value is
    centred and its u the spread."""
    z, hits = _study(0.12, 150.0, 100, seed=1, sigma_dps=0.095)
    assert clopper_pearson(hits, z.size)[1] >= 0.95, hits
    assert abs(z.mean()) < 0.3 and 0.7 <= z.std() <= 1.3, (z.mean(), z.std())


def test_power_on_drift_budget_without_transient():
    """No transient: the truth is 0, the measurand's bound, and a value is never below it;
    z stays one-sided and narrow there whatever the estimator, U must cover."""
    z, hits = _study(0.0, 30.0, 100, seed=7)
    assert clopper_pearson(hits, z.size)[1] >= 0.95, hits
    assert 0.0 <= z.mean() < 1.0


def test_power_on_drift_budget_with_a_rate_random_walk():
    """A rate random walk (cumsum of white increments, 0.02 °/s/√s: 0.19 °/s end to end over
    the 90-s record, twice the white noise of a smoothed value) moves every smoothed value
    and the reference: the replicates draw it from its E[K²] (the exact covariance of the
    smoothed values less the reference). Without it the spread is the white noise's alone
    and U misses. With V* = R* − (E*[R*] − R̂*) the walk the fit absorbs counted twice
    (100 trials, seed 11: z +0.02, sd 0.63); the replicates linearised in R̂ with the
    excess's own slope: z +0.37, sd 1.05, 95/100."""
    z, hits = _study(1.0, 30.0, 100, seed=11, rrw_dps_sqrt_s=0.02)
    assert clopper_pearson(hits, z.size)[1] >= 0.95, hits
    assert abs(z.mean()) < 0.4 and 0.7 <= z.std() <= 1.3, (z.mean(), z.std())
