"""IEC 62047-20 5.3.3.5's transient fits and wander draws, as computed for speed (the design's
pseudo-inverses computed once per record timing and kept; the variogram looked up by sorted
search), give bit-for-bit what the straightforward computation gives: the fits against a
least-squares fit written here (the pseudo-inverse of [1, e_b] recomputed for every τ and
every call, as the budget did before), the draws against a per-element lookup of the same
variogram, and the budget itself the same on a second call (the kept design reused). The
fits try only the τ the closed form of the residual sum of squares leaves in contention
(:func:`gonio.specs.iec62047_20.items._transient_candidates`); the rows here include the
study bench's low signal-to-noise, where many τ contend and some nearly tie."""
from __future__ import annotations

import math

import numpy as np

from gonio.specs.iec62047_20 import items as I
from tests._helpers import power_on_record


def _fits_here(Y, tt, n, P, nr):
    """c + A·e^(−t/τ) by least squares per row of ``Y`` over the same τ grid, the
    pseudo-inverse formed afresh for each τ; A = 0 kept where no τ does better."""
    nb = tt.size
    dt = float(tt[1] - tt[0]) / P
    t_raw = dt * np.arange(max(n, nb * P, nr)) - 0.5 * (P - 1) * dt
    span = max(float(tt[-1] - tt[0]), dt * P)
    grid = []
    for tau in np.geomspace(dt * P, 20 * span, 60):
        e = np.exp(-t_raw / tau)
        grid.append((e[: nb * P].reshape(nb, P).mean(1), float(e[:nr].mean())))
    c0 = Y.mean(1)
    best = ((Y - c0[:, None]) ** 2).sum(1)
    cb, ab, kb = c0.copy(), np.zeros(Y.shape[0]), np.full(Y.shape[0], -1)
    for k, (eb, _er) in enumerate(grid):
        A = np.column_stack([np.ones(nb), eb])
        coef = Y @ np.linalg.pinv(A).T
        sse = ((Y - coef @ A.T) ** 2).sum(1)
        better = sse < best
        best = np.where(better, sse, best)
        cb, ab, kb = (np.where(better, coef[:, 0], cb), np.where(better, coef[:, 1], ab),
                      np.where(better, k, kb))
    out = []
    for c, a, k in zip(cb, ab, kb):
        if k < 0:
            out.append((np.full(nb, c), float(c), 0.0))
        else:
            eb, er = grid[k]
            out.append((c + a * eb, float(c + a * er), float(abs(a) * np.max(np.abs(eb - er)))))
    return out


def test_transient_fits_equal_the_fit_with_a_fresh_pseudo_inverse():
    rng = np.random.default_rng(8)
    n, P, nr, dt = 900, 10, 60, 0.1
    t = np.arange(n) * dt
    tt = t[::P]
    rows = [0.3 + 1.0 * np.exp(-tt / 30.0), 0.3 + 0.0 * tt, 0.3 - 0.2 * np.exp(-tt / 300.0)]
    Y = np.array([r + 0.01 * rng.standard_normal(tt.size) for r in rows for _ in range(20)])
    # the study bench's signal-to-noise (0.12 °/s, τ 150 s, σ 0.095 °/s): rows whose best τ
    # differ, some near ties, a large offset (the screen's margin is of Σy²)
    low = np.array([0.3 + 0.12 * np.exp(-tt / 150.0) + 0.095 * rng.standard_normal(tt.size)
                    for _ in range(200)] + [100.0 + 2.0 * np.exp(-tt / 20.0)
                                            + 1e-3 * rng.standard_normal(tt.size)])
    assert len({int(np.argmin([((y - y.mean() - (y - y.mean()) @ u * u) ** 2).sum()
                               for u in I._transient_designs(tt, n, P, nr).unit]))
                for y in low}) > 10                       # many τ contend
    for Y in (Y, low):
        for _ in range(2):                                 # computed, then the kept design
            got = I._transient_fits(Y, I._transient_designs(tt, n, P, nr))
            want = _fits_here(Y, tt, n, P, nr)
            assert len(got) == len(want) == Y.shape[0]
            assert any(w[2] < 0.05 for w in want) and any(w[2] > 0.5 for w in want)
            for (m, r, d), (mw, rw, dw) in zip(got, want):
                assert np.array_equal(m, mw) and r == rw and d == dw


def test_wander_root_equals_a_per_element_variogram_lookup():
    x = np.array([0.0, 0.7, 1.3, 2.0, 5.5, 5.5 + 1e-12, 9.0, 30.0])
    for drift_u in (lambda s: 0.01 * s ** 0.3, lambda s: 1e-3 * math.sqrt(s)):
        lag = np.abs(x[:, None] - x[None, :])
        D = np.array([[drift_u(float(s)) ** 2 if s > 0 else 0.0 for s in row]
                      for row in np.round(lag, 9)])
        Dx = np.array([drift_u(float(s)) ** 2 if s > 0 else 0.0 for s in np.round(x, 9)])
        C = 0.5 * (Dx[:, None] + Dx[None, :] - D)
        # the covariance built element by element, drawn through its symmetric root
        assert np.array_equal(I._wander_root(x, drift_u), I._symmetric_root(C))
    assert I._wander_root(x, lambda s: 0.0) is None          # no wander: nothing drawn


def test_budget_is_the_same_with_the_design_kept():
    rng = np.random.default_rng(4)
    t = np.arange(900) * 0.1
    recs = [power_on_record(t, 0.3 + np.exp(-t / 30.0) + 0.01 * rng.standard_normal(900), 10)
            for _ in range(2)]
    I._transient_designs_cached.cache_clear()
    first = I.power_on_drift_budget(recs, 60, lambda s: 0.0, None)
    assert I._transient_designs_cached.cache_info().currsize  # the design kept
    second = I.power_on_drift_budget(recs, 60, lambda s: 0.0, None)
    I._transient_designs_cached.cache_clear()
    third = I.power_on_drift_budget(recs, 60, lambda s: 0.0, None)
    for other in (second, third):
        assert first[0] == other[0] and first[1] == other[1] and first[3] == other[3]
        assert repr(first[2]) == repr(other[2]) and first[4] == other[4]
