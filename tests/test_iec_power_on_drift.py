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
from tests._helpers import power_on_record, transient_interval_means


def _judge(recs, truth: float, n_ref: int, coef) -> tuple[float, bool]:
    """One trial of :func:`power_on_drift_budget` on ``recs``: z = (value − truth)/u_c and
    whether the statement (the replicates' 95 % interval, no k) holds the truth; checks the
    reading is the largest contender at most, never below 0, inside its interval, the
    interval's lower end at or above 0 and 1 ≤ m ≤ the records' smoothed values."""
    val, vals, u, m, _fit = I.power_on_drift_budget(recs, n_ref, lambda sep: 0.0, coef)
    assert max(vals) >= val >= 0.0 and 1 <= m <= sum(len(r[1]) for r in recs), (val, m)
    lo, hi = u.interval
    assert u.k is None and 0.0 <= lo <= val <= hi, (lo, val, hi)
    return (val - truth) / u.u_c, bool(lo <= truth <= hi)


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
    truth = float(np.max(np.abs(tr.reshape(-1, P).mean(1) - tr[:nr].mean())))
    coef = (rrw_dps_sqrt_s ** 2, 0.0) if rrw_dps_sqrt_s else None
    z, hits = [], 0
    for _ in range(trials):
        recs = []
        for _r in range(2):
            walk = np.cumsum(rng.standard_normal(n)) * rrw_dps_sqrt_s * np.sqrt(dt)
            recs.append(power_on_record(t, 0.3 + tr + walk + sigma_dps * rng.standard_normal(n),
                                        P))
        assert sum(len(r[1]) for r in recs) == 180
        zi, hit = _judge(recs, truth, nr, coef)
        z.append(zi)
        hits += hit
    return np.array(z), hits


@pytest.mark.parametrize("a_dps,tau_s", [(1.0, 300.0), (1.0, 30.0)])
def test_power_on_drift_budget_with_transient(a_dps, tau_s):
    """400 trials: the first 100 of seed 300 hold the truth in 91 intervals (the pivot alone:
    88; value ± 1.96 u_c: 91), a run of high values (z sd 1.18 there); the 400 held 380 in
    the pivot alone (0.950, z +0.15, sd 1.00), fresh seeds 1 and 2: 384 and 382. With the
    adaptive replicates (JCGM 101 7.9.4; 5–7 blocks of 400 on the first six trials at
    τ 30 s): τ 300 s 384/400, z +0.01, sd 1.00; τ 30 s 379/400, z +0.03, sd 1.00; with two
    blocks at least (7.9.4 f): 384/400, z +0.01, sd 0.99 and 379/400, z +0.03, sd 0.99."""
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


def _bench_records(rng, gyro, n=900, dt=1.0, P=10):
    """Two power-ons of the study's programme (900 samples at 1 s, smoothing 10) on the
    bench's own noise generator (white, the Gauss–Markov sum of its bias instability, its
    rate random walk; a new noise state per power-on, as the bench powers up) and its
    transient A·e^(−t/τ) as interval means, computed here."""
    from gonio.bench.rate_gyro import NoiseState

    t = np.arange(n) * dt
    tr = transient_interval_means(gyro.warmup_bias_dps, gyro.warmup_tau_s, t, dt)
    recs = [power_on_record(t, 0.2 + tr + NoiseState(gyro, rng).samples(n, dt, 22.5), P)
            for _ in range(2)]
    return recs, tr


def test_power_on_drift_on_the_bench_noise_is_centred_and_covers():
    """The study bench's records (its transient 0.12 °/s, τ 150 s, and its noise: 1.8 °/√h,
    bias instability 22.3 °/h, walk 36.7 °/h/√h) with the walk and flicker at the bench's
    own K and B: the truth is the noise-free transient's largest |block − reference|,
    computed here. Both records share it, so the reading's excess holds the selection of
    the larger of two records; a transient fitted to each record alone carried each
    record's noise as a different drift and missed that selection (120 trials, seed 5:
    z +0.37, 110/120 intervals, 10 with the truth below)."""
    from gonio.specs._rate_family.simulate import study_bench

    g = study_bench(power_on_transient=True).gyro
    rng = np.random.default_rng(5)
    coef = ((g.rrw_dph_sqrt_h / 3600.0 / 60.0) ** 2, (g.bias_instability_dph / 3600.0) ** 2)
    z, hits = [], 0
    for _ in range(120):
        recs, tr = _bench_records(rng, g)
        blocks = tr.reshape(-1, 10).mean(1)
        truth = float(np.max(np.abs(blocks - tr[:60].mean())))
        zi, hit = _judge(recs, truth, 60, coef)
        z.append(zi)
        hits += hit
    z = np.array(z)
    assert clopper_pearson(hits, z.size)[1] >= 0.95, hits
    assert abs(z.mean()) < 0.25 and 0.7 <= z.std() <= 1.3, (z.mean(), z.std())


def test_power_on_interval_is_t_nu_times_u_for_normal_replicates():
    """Closed form: for replicates whose errors are normal with sd s (their exact quantiles),
    the pivot scaled by t95(ν)/z95 is value ± t95(ν)·s (scipy's t), at any ν; ν = ∞: ± 1.96 s."""
    from scipy.stats import norm, t as student_t

    s, n = 0.01, 20001
    d = s * norm.ppf((np.arange(n) + 0.5) / n)
    for nu in (3.0, 12.5, 66.0, float("inf")):
        lo, hi = I.power_on_interval(1.0, d, nu)
        k = float(student_t.ppf(0.975, nu))
        assert lo == pytest.approx(1.0 - k * s, abs=2e-5) and hi == pytest.approx(1.0 + k * s,
                                                                                  abs=2e-5)


def test_power_on_dof_for_white_noise_alone():
    """Records without transient and white noise alone: u_c² scales with σ_y² (every
    replicate is σ_y times a fixed draw about the fitted records, which hold only the small
    transient fitted to the noise), so σ_y²'s share of u_c² is ≈ 1 and
    ν_eff = 1/(s_w²/ν_w + 1/(n_MC − 1)), ν_w = Σ(n − 2)/Σρ² of the
    second differences (ρ₁ = −2/3, ρ₂ = 1/6: Σρ² = 1 + 2(4/9 + 1/36) = 35/18), by
    Welch–Satterthwaite; the walk and flicker, absent, hold no share."""
    rng = np.random.default_rng(3)
    n, P = 900, 10
    recs = [power_on_record(np.arange(n), 0.1 + 0.03 * rng.standard_normal(n), P)
            for _ in range(2)]
    rep = I._power_on_replicates(recs, 60, lambda s: 0.0, None)
    g = -1.0 if not rep["r_hat"] > 0 else 0.0
    shares = I._power_on_shares(recs, 60, lambda s: 0.0, None, g,
                                float(np.std(rep["r_star"] - g * rep["r_fit"], ddof=1)))
    nu_w = 2 * (n - 2) / (35.0 / 18.0)
    assert shares == pytest.approx([1.0, 0.0, 0.0], abs=0.05)
    assert rep["white_dof"] == pytest.approx(nu_w)
    nu = I.power_on_dof(shares, [nu_w, 5.0, 5.0], I.POWER_ON_MC_TRIALS)
    assert nu == pytest.approx(1.0 / (shares[0] ** 2 / nu_w + 1.0 / (I.POWER_ON_MC_TRIALS - 1)))


def _unequal_records(rng, amps, n=2000, dt=1.0, P=10, tau_s=200.0, sigma_dps=0.05):
    """Power-ons of one gyro that differ (start temperature): A_i·e^(−t/τ) per record plus
    white noise, 1-s samples, smoothing 10; the truth, the largest over the records of the
    noise-free transient's |block − reference mean|, from the generator's parameters here."""
    t = np.arange(n) * dt
    recs, truths = [], []
    for a in amps:
        e = a * np.exp(-t / tau_s)
        truths.append(float(np.max(np.abs(e.reshape(-1, P).mean(1) - e[:100].mean()))))
        recs.append(power_on_record(t, e + sigma_dps * rng.standard_normal(n), P))
    return recs, max(truths)


def test_power_on_records_of_unequal_transients_are_not_pooled():
    """Three power-ons with transients 0.2, 0.05, 0.05 °/s (τ 200 s, white 0.05 °/s, 2000
    samples): one transient fitted to all of them (the records' mean) gave every replicate
    the mean transient, so the excess removed was that of three equal contenders while the
    reading came from the largest: 63/100 intervals held the truth, z −1.20. The test of
    one transient (:func:`power_on_one_transient`) refutes it here and the records are
    fitted one by one. 24 trials, seed 57."""
    rng = np.random.default_rng(57)
    z, hits = [], 0
    for _ in range(24):
        recs, truth = _unequal_records(rng, (0.2, 0.05, 0.05))
        rep = I._power_on_replicates(recs, 100, lambda s: 0.0, (0.0, 0.0), test=True)
        assert not I.power_on_one_transient(rep["lr"], rep["lr_star"])[0]
        zi, hit = _judge(recs, truth, 100, (0.0, 0.0))
        z.append(zi)
        hits += hit
    z = np.array(z)
    assert clopper_pearson(hits, z.size)[1] >= 0.95, hits
    assert abs(z.mean()) < 0.5 and 0.6 <= z.std() <= 1.4, (z.mean(), z.std())


def test_power_on_one_transient_holds_for_equal_records_at_its_level():
    """Equal transients (0.1 °/s each, the test's null hypothesis): one transient is refuted
    at about the test's level, 5 % of the trials — here at most 4 of 30 (binomial(30, 0.05)
    exceeds 4 with probability 0.016); the p values are those of the replicates' own null
    distribution, so a statistic counted against the wrong null (e.g. an F table at the
    white noise only) shows in the count."""
    rng = np.random.default_rng(58)
    refuted = 0
    for _ in range(30):
        recs, _truth = _unequal_records(rng, (0.1, 0.1, 0.1))
        rep = I._power_on_replicates(recs, 100, lambda s: 0.0, (0.0, 0.0), test=True)
        refuted += not I.power_on_one_transient(rep["lr"], rep["lr_star"])[0]
    assert refuted <= 4, refuted
