"""The covariance of Allan-family variance estimates across τ (gonio.analysis.noise.covariance)
and the five-term fit's uncertainties built on it, checked against independent results:
Greenhall's edf for the diagonal, allantools' estimates of simulated records for the
correlations, and the spread of the fitted N over simulated records for u(N)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.analysis import noise
from gonio.analysis.noise.covariance import variance_covariance

TAU0 = 0.1
MS = np.array([1, 2, 4, 8, 16, 32, 64, 128])


@pytest.mark.parametrize("kind", ["adev", "hdev"])
@pytest.mark.parametrize("term,alpha", [("N", 0), ("B", -1), ("K", -2)])
def test_diagonal_is_greenhalls_edf(kind, term, alpha):
    """Var σ̂² = 2σ⁴/edf with Greenhall's edf of the estimator at the term's noise type
    (an independent algorithm) within 15 % from m = 4 up and 6 % from m = 32 up (Greenhall's
    short-m sums and the continuous forms of flicker and random walk at small m differ
    from the exact sampled ones; a factor in the sum fails it)."""
    n = 20_000
    coef = np.zeros(5)
    coef[noise.TERMS.index(term)] = 1.0
    n_terms = n + 1 - (2 if kind == "adev" else 3) * MS
    cov = variance_covariance(kind, MS, n_terms, TAU0, coef)
    model = noise.design_matrix(MS * TAU0, kind) @ coef
    edf = noise.edf_for(kind, n + 1, MS, np.full(MS.size, alpha))
    ratio = np.diag(cov) / (2.0 * model ** 2 / edf)
    assert np.all(np.abs(ratio[MS >= 4] - 1.0) < 0.15), ratio.round(3)
    assert np.all(np.abs(ratio[MS >= 32] - 1.0) < 0.06), ratio.round(3)


def test_correlations_match_simulated_records_and_allantools():
    """The correlation of overlapping Allan variances of one record at m and 2m, 4m (white +
    flicker + rate random walk), against 300 simulated records whose ADEV allantools
    computes: within 0.1 (the Monte Carlo's own error is about 0.06), and the standard
    deviations within 12 %."""
    allantools = pytest.importorskip("allantools")
    n, q = 4000, (0.0, 1.0, 0.3, 0.02, 0.0)
    rng = np.random.default_rng(7)
    est = []
    for _ in range(300):
        y = noise.simulate_noise(n, TAU0, *q, rng=rng)
        _, dev, _, _ = allantools.oadev(y, rate=1 / TAU0, data_type="freq", taus=MS * TAU0)
        est.append(np.asarray(dev) ** 2)
    mc = np.corrcoef(np.array(est).T)
    coef = np.array(q) ** 2
    cov = variance_covariance("adev", MS, n + 1 - 2 * MS, TAU0, coef)
    d = np.sqrt(np.diag(cov))
    theory = cov / np.outer(d, d)
    for i in (2, 3, 4, 5):
        for j in (i + 1, i + 2):
            assert abs(theory[i, j] - mc[i, j]) < 0.1, (i, j, theory[i, j], mc[i, j])
    assert theory[3, 4] > 0.4          # neighbouring octaves: far from independent
    sd_mc = np.std(np.array(est), axis=0, ddof=1)
    assert np.all(np.abs(sd_mc[2:] / d[2:] - 1.0) < 0.12), (sd_mc / d).round(3)


def test_fit_u_of_n_matches_the_spread_of_fitted_n():
    """u(N) of the fit (covariance method) against the standard deviation of N over 60
    records of white + flicker + rate random walk (the JJF 1535 study's static record: 600 s
    at 10 Hz, decade:10 τ): the ratio mean u / sd within 0.8–1.25 and z = (N − N₀)/u with
    sd 0.7–1.3 and at least 95 % inside ±2. The former fixed inflation gave 1.8."""
    n0, b0, k0 = 108.0, 22.3, 0.612
    rng = np.random.default_rng(20261129)
    vals, us = [], []
    for _ in range(60):
        y = noise.simulate_noise(6000, TAU0, N=n0, B=b0, K=k0, rng=rng)
        f = noise.fit_noise_model(noise.allan_deviation(y, TAU0, "rate", "decade:10"))
        assert f.uncertainty_method == "covariance"
        vals.append(f.N)
        us.append(f.u_N)
    vals, us = np.array(vals), np.array(us)
    ratio = float(np.mean(us) / np.std(vals, ddof=1))
    assert 0.8 <= ratio <= 1.25, ratio
    z = (vals - n0) / us
    assert 0.7 <= float(np.std(z, ddof=1)) <= 1.3
    assert np.mean(np.abs(z) <= 2.0) >= 0.95


def test_white_noise_closed_form():
    """White rate noise of unit variance, τ0 = 1, worked by hand: the m = 1 terms
    d_k = y_{k+1} − y_k have autocovariance 2, −1 at lags 0, ±1, so Var σ̂² =
    2·n·(2² + 2·1²)/(2²n²) = 3/n; the m = 2 terms (y_{k+2} + y_{k+3} − y_k − y_{k+1})/2
    meet d_k with covariance 1 at lag −1 and −½ at lags −3 and +1, so Cov = 2·n·1.5/(4n²)
    = 0.75/n."""
    n = 10 ** 6
    cov = variance_covariance("adev", [1, 2], [n, n], 1.0, [0.0, 1.0, 0.0, 0.0, 0.0])
    assert cov[0, 0] * n == pytest.approx(3.0, rel=1e-5)
    assert cov[0, 1] * n == pytest.approx(0.75, rel=1e-5)


def test_long_grids_are_computed_in_pieces_with_the_same_numbers(monkeypatch):
    """K(t) on a grid longer than one piece, and the covariance built from it, are the
    same numbers element by element as in one piece (the pieces only bound memory); and
    the pieces really are used (a piece of 7 samples)."""
    from gonio.analysis.noise import covariance as cov
    coef = [0.3, 0.02, 1e-3, 1e-6, 0.0]
    markov = [(1e-4, 50.0), (2e-4, 900.0)]
    t = np.arange(1000)
    whole = cov.generalised_covariance(t, coef, 0.01, markov)
    args = ("mdev", [1, 4, 16, 64], [4000, 3990, 3950, 3800], 0.01, coef, markov)
    v_whole = variance_covariance(*args)
    calls = []
    real = cov._generalised_covariance
    monkeypatch.setattr(cov, "_PIECE", 7)
    monkeypatch.setattr(cov, "_generalised_covariance",
                        lambda *a: calls.append(1) or real(*a))
    assert np.array_equal(cov.generalised_covariance(t, coef, 0.01, markov), whole)
    assert len(calls) == math.ceil(t.size / 7)
    calls.clear()
    assert np.array_equal(variance_covariance(*args), v_whole)
    assert len(calls) > 1               # K's grid for the covariance: the same pieces
    # the shared piece helper against K on the whole grid 0 … 1000 in one call
    ref = real(np.arange(1001), np.r_[0.0, coef[1:]], 0.01, markov)
    got = cov._in_pieces(1001, lambda a, b: real(np.arange(a, b), np.r_[0.0, coef[1:]],
                                                 0.01, markov))
    assert np.array_equal(got, ref)
    # and K itself against its closed form at a few points (white rate: −N²|t|/2)
    k = cov.generalised_covariance(np.array([0, 3, 10]), [0, 0.02, 0, 0, 0], 0.01)
    assert np.allclose(k, -0.5 * 0.02 * np.array([0, 3, 10]) * 0.01, rtol=0, atol=1e-15)
