"""IEC 62047-20 5.3.3.7 hysteresis and the drift term of 5.3.3.6/5.3.3.7, against truths set
outside gonio's formulas.

- 5.3.3.7 is a maximum of |B_up − B_down| whose truth may be 0 (a chamber without lag): it is
  stated by one interval [0, upper] from the reading's own distribution, which must hold the
  truth set here in ≥ 95 % of the draws (Clopper–Pearson upper end) at every configuration —
  no hysteresis, one temperature's at 1–3 σ, all three equal — with the visits' drift a
  random walk shared by the differences (correlated), and must not be a bound of 100 %.
- The bound of the rate random walk K² (min over τ of the static record's 95 % limits; it
  caps 5.3.3.5's fitted K̂) must hold the generator's K² on 2-h records (numpy white noise +
  a cumulated walk) far more often than the 68 % limits used before (83–86 % of the records
  against 56–65 %); with those, the built-in trial 2460005 (K held at 0, bound² 0.309
  against the bench's 0.374 (°/h)²/s) read z +5.24.
- E[K²] of every drift term, the posterior mean of ``formulas.walk_k2_iec``: a closed form
  (one τ: a truncated inverse gamma), a quadrature of the same posterior, correlated
  duplicates counted once, and on records of the bench's own noise about the generator's
  K² (the 95 % bound's rectangle it replaced read 1.99× on average, median 2.20, and fails
  that check).
"""

from __future__ import annotations

import numpy as np
import pytest

from gonio.analysis.coverage import clopper_pearson
from gonio.specs.iec62047_20 import formulas as ief
from gonio.specs.iec62047_20 import items as I

#: The programme's visits (base → max → base → min → base), °C, one hour apart.
VISITS_C = [22.5, 53.75, 85.0, 53.75, 22.5, -8.75, -40.0, -8.75, 22.5]


def _draws(h_by_temp: dict, sigma: float, walk: float, trials: int, seed: int):
    """(truth, value, u_c, interval) of hysteresis_budget on the nine visits: each visit's
    mean with noise σ, a bias random walk of ``walk`` °/s per √h over the session (the
    differences share it), a true B_up − B_down of ``h_by_temp[T]`` (set on the falling
    visit); the truth is the largest |true difference| (computed here)."""
    rng = np.random.default_rng(seed)
    base = np.array([0.01 * (t - 22.5) / 60 for t in VISITS_C])
    fall = {53.75: 3, -8.75: 5, 22.5: 4}
    for T, h in h_by_temp.items():
        base[fall[T]] -= h
    truth = max(abs(h) for h in h_by_temp.values()) if h_by_temp else 0.0
    out = []
    for _ in range(trials):
        b = base + sigma * rng.standard_normal(base.size) + np.cumsum(walk * rng.standard_normal(base.size))
        pts = [(T, float(v), sigma, 10_000, 3600.0 * i) for i, (T, v) in enumerate(zip(VISITS_C, b))]
        val, _, _, u = I.hysteresis_budget(pts, lambda sep: walk * np.sqrt(abs(sep) / 3600.0))
        out.append((truth, val, u.u_c, u.interval, u.k))
    return out


@pytest.mark.parametrize("config", [{}, {53.75: 1.0}, {53.75: 2.0}, {22.5: 3.0},
                                    {53.75: 2.0, -8.75: 2.0, 22.5: 2.0}])
def test_hysteresis_interval_holds_the_truth(config):
    sigma, walk = 0.002, 0.002
    s_diff = np.sqrt(2 * sigma ** 2 + walk ** 2 * 4)          # the 22.5 °C pair, 4 h apart
    draws = _draws({T: a * s_diff for T, a in config.items()}, sigma, walk, 400,
                   seed=17 + len(config) + int(10 * sum(config.values())))
    hits = sum(iv[0] <= t <= iv[1] for t, _, _, iv, _ in draws)
    assert all(k is None and iv[0] == 0.0 and v <= iv[1] for _, v, _, iv, k in draws)
    lo, hi = clopper_pearson(hits, len(draws))
    assert hi >= 0.95, (hits, len(draws))
    if max(config.values(), default=0.0) >= 3.0:
        # the truth 3 sigma clear of zero: the limit is one-sided 95 % (the largest over the
        # temperatures makes it conservative, 96.75 % here), not a certainty: a limit
        # widened by a factor (wrong sds, a slip of 2) covers every draw and fails this
        assert hits / len(draws) <= 0.985, (hits, len(draws))


def test_hysteresis_upper_single_difference_closed_form():
    """One difference of σ = 1 read M: the limit h solves Φ(M − h) − Φ(−M − h) = 5 %,
    checked against a brute-force grid of the folded normal's probability by simulation."""
    rng = np.random.default_rng(5)
    for m in (0.2, 1.0, 3.0):
        h = ief.hysteresis_upper_iec(m, [1.0])
        z = np.abs(h + rng.standard_normal(400_000))
        assert np.mean(z <= m) == pytest.approx(0.05, abs=0.002)


def _rrw_record(k_dph_rts: float, n_dph_rts: float, n: int, dt: float, rng) -> np.ndarray:
    """Rate (°/h): white noise of ARW n (°/h·√s) plus a rate random walk of K (°/h/√s)."""
    white = n_dph_rts / np.sqrt(dt) * rng.standard_normal(n)
    return white + np.cumsum(k_dph_rts * np.sqrt(dt) * rng.standard_normal(n))


def test_walk_bound_holds_the_generators_walk():
    from gonio.analysis.noise import allan_deviation

    K, N, dt, n = 0.612, 1.8, 0.1, 72_000               # the bench's K² 0.374 (°/h)²/s; 2 h
    rng = np.random.default_rng(2460005)
    new = old = 0
    trials = 60
    for _ in range(trials):
        a = allan_deviation(_rrw_record(K, N, n, dt, rng), dt, "rate", "decade:10", unit="deg/h")
        new += ief.walk_coefficient_bound(a.tau_s, a.adev, a.edf) >= K * K
        old += float(np.min(np.asarray(a.ci_high) ** 2 * 3.0 / a.tau_s)) >= K * K
    assert new >= 0.75 * trials, (new, trials)      # 83–86 % (the minimum over τ: below 95 %)
    assert new >= old + 0.1 * trials, (new, old)    # the 68 % limits: 56–65 %


def test_walk_k2_single_tau_closed_form():
    """One τ, no other term, independent: K uniform ⇒ X = K² has posterior density ∝
    X^(−(ν+1)/2)·exp(−ν·y/(2cX)), an inverse gamma of shape (ν − 1)/2 and scale ν·y/(2c),
    truncated at the rule's cap; its mean by scipy's inverse-gamma CDFs."""
    from scipy.stats import chi2, invgamma

    for nu, y, c in ((6.0, 0.5, 1.0), (12.0, 2.0, 3.0), (40.0, 1.3, 0.2)):
        cap = y * nu / chi2.ppf(1e-4, nu) / c
        a, b = (nu - 1) / 2, nu * y / (2 * c)
        exact = b / (a - 1) * invgamma.cdf(cap, a - 1, scale=b) / invgamma.cdf(cap, a, scale=b)
        assert ief.walk_k2_iec([y], [nu], [0.0], [c]) == pytest.approx(exact, rel=2e-3)


def test_walk_k2_other_terms_by_quadrature():
    """Three τ with other terms, independent: the mean by scipy.integrate.quad of the same
    posterior (a second algorithm), and perfectly correlated duplicates of one τ (the same
    estimate counted twice, Σ all equal) give the one-τ answer: s = ½ undoes the count."""
    from scipy import integrate
    from scipy.stats import chi2

    y, nu = np.array([4.0, 3.0, 5.0]), np.array([40.0, 12.0, 5.0])
    a, c = np.array([3.5, 2.0, 1.5]), np.array([1.0, 3.0, 10.0])
    cap = float(np.min(y * nu / chi2.ppf(1e-4, nu) / c))

    def lik(k):
        v = a + c * k * k
        return np.exp(-0.5 * np.sum(nu * (y / v + np.log(v))) + 0.5 * np.sum(nu * (y / a + np.log(a))))
    top = integrate.quad(lambda k: k * k * lik(k), 0, np.sqrt(cap), limit=200)[0]
    bot = integrate.quad(lik, 0, np.sqrt(cap), limit=200)[0]
    assert ief.walk_k2_iec(y, nu, a, c) == pytest.approx(top / bot, rel=2e-3)
    one = ief.walk_k2_iec([3.0], [12.0], [2.0], [3.0])
    sd2 = 2 * (2.0 + 3.0 * 0.4) ** 2 / 12.0
    twice = ief.walk_k2_iec([3.0, 3.0], [12.0, 12.0], [2.0, 2.0], [3.0, 3.0], k2_fit=0.4,
                            cov=np.full((2, 2), sd2))
    assert twice == pytest.approx(one, rel=2e-3)
    naive = ief.walk_k2_iec([3.0, 3.0], [12.0, 12.0], [2.0, 2.0], [3.0, 3.0])
    assert naive < 0.95 * one             # counted twice without Σ: narrower, a smaller mean


def _old_rule(allan, fit) -> float:
    """The rule replaced (kept here to show the test fails on it): a resolved K̂ (K̂ > u_K)
    as K̂² up to the 95 % per-τ bound, else the bound's rectangle, bound/3."""
    b = ief.walk_coefficient_bound(allan.tau_s, allan.adev, allan.edf)
    k, u = float(fit.K), float(fit.u_K)
    return min(k * k, b) if k > u else b / 3.0


def test_walk_k2_is_about_the_benchs_walk():
    """Static records of the bench's own noise (mems-adxrs610: ARW 1.8 °/√h, bias instability
    22.3 °/h, K 36.7 °/h/√h; 2 h at 10 Hz, the programme's 5.4 record), simulated with those
    parameters: E[K²] must be about the generator's K² over the records (median within
    0.6–1.4 of it, mean below 1.7×) and never far below it where the fit holds K̂ at 0 (at
    least 0.3 K²: the record cannot exclude the walk). The 95 % bound's rule it replaces
    overstates K² (mean 1.99×, median 2.20×) and fails here."""
    from gonio.analysis.noise import allan_deviation, fit_noise_model
    from gonio.analysis.noise.fit import simulate_noise

    N, B, K = 1.8 * 60.0, 22.3, 36.7 / 60.0          # °/h·√s, °/h, °/h/√s
    rng = np.random.default_rng(2460005)
    new, old, zero = [], [], []
    for _ in range(24):
        x = simulate_noise(72_000, 0.1, N=N, B=B, K=K, rng=int(rng.integers(2 ** 31)))
        a = allan_deviation(x, 0.1, "rate", "decade:10", unit="deg/h")
        f = fit_noise_model(a)
        e = ief.walk_k2_iec(**I.walk_likelihood_inputs_of(a, f)) / (K * K)
        new.append(e)
        old.append(_old_rule(a, f) / (K * K))
        if f.K == 0:
            zero.append(e)

    def about(r):
        return 0.6 <= np.median(r) <= 1.4 and np.mean(r) <= 1.7
    assert about(new), (np.median(new), np.mean(new))
    assert not about(old), (np.median(old), np.mean(old))
    assert zero and min(zero) >= 0.3, zero


def test_builtin_trial_2460005_hysteresis():
    """The built-in programme's trial 2460005 (the README's study seeds): K held at 0 by the
    fit and a 0.093 °/s difference between the 22.5 °C visits 6 h apart read z +5.24 with the
    68 % bound's E[K²] = 0.103 (°/h)²/s; the truth (the bench's, from the session's true
    biases) must lie in the stated interval (the item is judged by it), and |z| on u_c stay
    below 4.5: the 68 % bound's 5.24 fails, the 95 % bound's 3.97 and the posterior mean's
    3.99 pass (a guard against the walk's E[K²] collapsing again, not a coverage claim)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    from bench_rate_coverage_builtin import bench_for
    from gonio.pipeline.coverage import trial_records

    r = trial_records("iec62047-20", bench_for("iec62047-20"), "iec62047-20", 2460005)["bias_hysteresis"]
    assert abs(r["value"] - r["truth"]) / r["u_c"] < 4.5
    lo, hi = r["interval"]
    assert lo == 0.0 and lo <= r["truth"] <= hi
