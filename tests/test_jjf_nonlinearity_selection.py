"""JJF 1535 7.2.2 nonlinearity: eq (6) takes the largest of noisy residuals, which noise can
only raise. The item removes the midpoint c_m·σ/2 of that selection excess (m contending
residuals, :func:`gonio.specs._rate_family.formulas.selection_excess`) and carries ± c_m·σ/2
as a rectangular term. Checked by a Monte Carlo of the item on calibrations whose true
outputs are written out here (a cubic nonlinearity: the two ends share the largest true
residual; none at all: every residual contends), the truth eq (6) on the noise-free outputs.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from gonio.analysis.coverage import clopper_pearson
from gonio.specs._rate_family import formulas as rg
from gonio.specs.jjf1535 import formulas as jf
from gonio.specs.jjf1535 import items as I

RATES = np.array([1, 1.6, 2.5, 4, 6.3, 10, 16, 25, 40, 63, 100.0])
OMEGA = np.concatenate([RATES, -RATES])


def _ctx(means_q, u_q):
    cals = []
    for means, u in zip(means_q, u_q):
        cals.append({"rates": OMEGA, "fit": jf.fit_scale_factor(OMEGA, means), "u_means": u,
                     "n_means": [5] * OMEGA.size, "spans_s": np.full(OMEGA.size, 5.0)})
    # no table ripple in these calibrations (their outputs are written out here): bound 0
    ctx = I.Context(df=pd.DataFrame({"test": []}), output_unit="mV", null_output=0.0,
                    latitude_deg=40.0, protocol={}, room_temperature_c=20.0, K=1.0,
                    rate_table_ripple_rel=0.0)
    ctx.cache[("has", "scale_factor")] = True
    ctx.cache[("cal", "scale_factor")] = cals
    return ctx


def _study(cubic: float, sigma: float, trials: int, seed: int, slow: float = 0.0):
    """z of the item and of eq (6)'s reading, and the hits of its interval (the statement
    since K_n is stated by the interval of the extreme of magnitudes), over ``trials`` sets of
    Q = 3 calibrations (5 samples per rate point, each of standard deviation σ√5; with
    ``slow``, each point's mean also carries a slow-noise offset of standard deviation
    slow·σ, common to its samples, which their standard deviation does not show)."""
    true = OMEGA + cubic * OMEGA ** 3 / 100 ** 2
    truth = jf.nonlinearity_jjf(jf.fit_scale_factor(OMEGA, true))
    rng = np.random.default_rng(seed)
    z, z_read, hits = [], [], 0
    for _ in range(trials):
        x = true[None, :, None] + sigma * math.sqrt(5) * rng.standard_normal((3, OMEGA.size, 5))
        x = x + slow * sigma * rng.standard_normal((3, OMEGA.size, 1))
        it = I.nonlinearity(_ctx(x.mean(axis=2), x.std(axis=2, ddof=1) / math.sqrt(5)))
        u = it.uncertainty
        z.append((it.value - truth) / u.u_c)
        z_read.append((it.details["reading"] - truth) / u.u_c)
        lo, hi = u.interval        # the statement: the interval of the extreme of magnitudes
        assert u.k is None and 0.0 <= lo <= it.value <= hi
        hits += lo <= truth <= hi
    return np.array(z), np.array(z_read), hits, truth


def test_selection_excess_midpoint_is_exact_for_two_equal_contenders():
    # E[max(t + σZ1, t + σZ2)] − t = σ/√π = c_2·σ/2 (two independent normals)
    rng = np.random.default_rng(4)
    x = 5.0 + rng.standard_normal((200_000, 2))
    half, m = rg.selection_excess([5.0, 5.0], [1.0, 1.0])
    assert m == 2 and half == pytest.approx(1 / math.sqrt(math.pi), rel=1e-6)
    assert x.max(axis=1).mean() - 5.0 == pytest.approx(half, abs=4 * x.max(axis=1).std() / 450)


def test_nonlinearity_corrected_for_the_largest_residuals_selection():
    """Cubic nonlinearity about 6σ above the residual noise at both ends (the study bench's
    case): eq (6)'s reading is high by about one u_c, the item is not; U covers. The
    selection term (the two ends' excess known only within [0, c_2·σ]) keeps the spread of z
    near 0.66 (the budget before, with the spread of K_n,m beside the noise: 0.58)."""
    z, z_read, hits, truth = _study(cubic=0.0009, sigma=0.004, trials=300, seed=7)
    assert truth == pytest.approx(1.282e-4, rel=1e-3)
    assert np.mean(z_read) > 0.7                       # eq (6)'s reading reads high
    assert abs(np.mean(z)) < 0.3, np.mean(z)
    assert 0.6 <= np.std(z, ddof=1) <= 1.3, np.std(z, ddof=1)
    assert clopper_pearson(hits, z.size)[1] >= 0.95, hits


def test_nonlinearity_covers_with_no_nonlinearity():
    """No nonlinearity (truth 0, every residual contends): the interval of the extreme of
    magnitudes holds 0 in 192/200 (z +1.25, sd 0.35: a value at its bound, not a spread)."""
    z, _, hits, truth = _study(cubic=0.0, sigma=0.004, trials=200, seed=8)
    assert truth == pytest.approx(0.0, abs=1e-12)
    assert clopper_pearson(hits, z.size)[1] >= 0.95, hits


def test_nonlinearity_noise_from_the_calibrations_spread_under_slow_noise():
    """Slow noise (bias instability over a point's samples) that the points' standard errors
    s/√n miss: each point's mean carries a further offset 2.5× its standard error. With the
    means' standard errors alone the item covered 97/300 here (z mean +2.9, sd 1.72); the
    residuals' spread over the Q calibrations restores coverage (300/300, z mean −0.08,
    sd 0.46: wide, the selection term's rectangle c_m·σ with the nonlinearity now only
    about 2σ above the noise)."""
    z, _, hits, _ = _study(cubic=0.0009, sigma=0.004, trials=300, seed=9, slow=2.5)
    assert clopper_pearson(hits, z.size)[1] >= 0.95, hits
    assert abs(np.mean(z)) < 0.3 and np.std(z, ddof=1) <= 1.3, (np.mean(z), np.std(z, ddof=1))


def test_nonlinearity_noise_is_the_larger_of_model_and_spread():
    rng = np.random.default_rng(3)
    true = OMEGA + 0.0009 * OMEGA ** 3 / 100 ** 2
    means = true[None, :] + 0.01 * rng.standard_normal((3, OMEGA.size))
    u = np.full(OMEGA.size, 1e-3)
    ctx = _ctx(means, [u] * 3)
    cals = ctx.cache[("cal", "scale_factor")]
    span = np.array([abs(c["fit"].K * 200.0) for c in cals])
    u_n, nu, f, u_model = I.nonlinearity_noise(cals, span)
    v = np.array([c["fit"].residuals for c in cals]) / span[:, None]
    lev = 1 / OMEGA.size + OMEGA ** 2 / float((OMEGA ** 2).sum())
    j = [int(np.argmax(np.abs(c["fit"].residuals))) for c in cals]
    assert u_model == pytest.approx(1e-3 * math.sqrt(1 - np.mean(lev[j])) / span.mean()
                                    / math.sqrt(3), rel=2e-2)
    # the observed spread, pooled over the points, against the means' noise (σ·√(1 − h))
    f_obs = math.sqrt(sum(np.var(v[:, k], ddof=1) for k in range(OMEGA.size))
                      / sum((1e-3 / span.mean()) ** 2 * (1 - lev)))
    assert f == pytest.approx(f_obs, rel=2e-2) and f > 5
    assert u_n == pytest.approx(f * u_model) and nu == 2 * (OMEGA.size - 2)
    it = I.nonlinearity(ctx)
    assert it.details["noise_scale"] == f
    # the selection excess uses the same σ: f times the means' one
    h0 = np.mean([I.nonlinearity_selection(c)[0] / sp for c, sp in zip(cals, span)])
    assert it.details["selection_excess"] > h0
    # the means' standard errors larger than the spread: they stay the term (ν = ∞)
    wide = _ctx(means, [u * 100] * 3).cache[("cal", "scale_factor")]
    u_n2, nu2, f2, _ = I.nonlinearity_noise(wide, span)
    assert nu2 == math.inf and f2 == 1.0 and u_n2 > u_n
