"""The confidence belt of max σ_i from the largest of m sample standard deviations (draft 7.5's
R = max_i R_i): :func:`uncertainty.stdev.max_stdev_cdf` (R's exact distribution),
:func:`~uncertainty.stdev.max_stdev_belt_interval` (the belt along one pattern of the σ_i)
and :func:`~uncertainty.stdev.max_stdev_union_interval` (the union over every pattern, R's
statement). Checked against brute force (the s_i drawn point by point, their maximum taken:
a second algorithm) and against the closed forms of one s and of m equal s (Šidák), at true
patterns the procedure allows: twelve equal σ_i, one poorer position, two levels, a σ growing
with time, and the least favourable (one σ_i, the others far below).

What must fail: a belt that leaves out the choice of the largest (one χ² in place of the
product) is 100 % instead of 95 % at its own pattern; the equal-σ or measured-pattern belt
(the selection corrected as if the pattern were known) under-covers a poorer position."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from gonio.specs.ogam_draft.item_uncertainty import repeatability_budget
from uncertainty.stdev import (max_stdev_belt_interval, max_stdev_cdf, max_stdev_interval,
                               max_stdev_union_interval, stdev_interval, stdev_upper)

NU, M, DRAWS = 9, 12, 4000
PATTERNS = {
    "equal": np.ones(M),
    "one poor position": np.r_[1.0, np.full(M - 1, 0.6)],
    "two levels": np.r_[np.ones(3), np.full(M - 3, 0.7)],
    "growing with time": np.sqrt(np.linspace(0.67, 1.0, M)),
    "least favourable": np.r_[1.0, np.full(M - 1, 1e-6)],
}
SE = math.sqrt(0.95 * 0.05 / DRAWS)


def _draws(sigma, rng, n=DRAWS):
    """s_i of every point, drawn as a sample of ν + 1 normal values each (not from χ²)."""
    x = rng.normal(0.0, 1.0, (n, M, NU + 1)) * np.asarray(sigma)[None, :, None]
    return x.std(axis=2, ddof=1)


@pytest.mark.parametrize("name", list(PATTERNS))
def test_closed_form_distribution_of_the_largest_against_brute_force(name):
    sigma = PATTERNS[name]
    t = _draws(sigma, np.random.default_rng(11)).max(axis=1)
    for q in (0.025, 0.05, 0.5, 0.95, 0.975):
        x = float(np.quantile(t, q))
        assert max_stdev_cdf(x, sigma, NU) == pytest.approx(q, abs=3 * math.sqrt(q * (1 - q) / DRAWS) + 0.003)


def test_belt_reduces_to_the_closed_forms_of_one_and_of_m_equal():
    s = [0.3, 0.9, 0.5]
    assert max_stdev_belt_interval([0.9], NU)[1] == pytest.approx(stdev_upper(0.9, NU), rel=1e-9)
    assert max_stdev_belt_interval([0.9], NU, lower=True) == pytest.approx(
        stdev_interval(0.9, NU), rel=1e-9)
    assert max_stdev_belt_interval(s, NU, pattern=[1, 1, 1], lower=True) == pytest.approx(
        max_stdev_interval(0.9, NU, 3), rel=1e-9)
    # the union: its upper limit is one s's, its lower limit m equal s's
    lo, hi = max_stdev_union_interval(0.9, NU, 3, lower=True)
    assert hi == pytest.approx(stdev_interval(0.9, NU)[1], rel=1e-12)
    assert lo == pytest.approx(max_stdev_interval(0.9, NU, 3)[0], rel=1e-12)


@pytest.mark.parametrize("name", list(PATTERNS))
def test_belt_along_the_true_pattern_is_exact(name):
    """Exactly 95 % (both tails 2.5 %) at its own pattern: neither under- nor over-wide. One χ²
    in place of the maximum's product would hold the equal pattern 100 % of the time."""
    sigma = PATTERNS[name]
    s = _draws(sigma, np.random.default_rng(5))
    t = s.max(axis=1)
    lo1, hi1 = max_stdev_belt_interval(t[:1], NU, pattern=sigma, lower=True)
    lo, hi = t / t[0] * lo1, t / t[0] * hi1            # the belt is scale-invariant
    assert np.allclose([max_stdev_belt_interval([v], NU, pattern=sigma, lower=True)
                        for v in t[:5]], np.c_[lo[:5], hi[:5]], rtol=1e-9)
    theta = sigma.max()
    tail_se = math.sqrt(0.025 * 0.975 / DRAWS)
    assert abs(np.mean(hi < theta) - 0.025) < 3 * tail_se, name
    assert abs(np.mean(lo > theta) - 0.025) < 3 * tail_se, name
    up = t / t[0] * max_stdev_belt_interval(t[:1], NU, pattern=sigma)[1]
    assert abs(np.mean(up >= theta) - 0.95) < 3 * SE, name


def test_belt_along_the_measured_pattern_under_covers_a_poor_position():
    """The pattern must not be taken from the data: one poorer position's s scatters with
    the others', the measured pattern looks flatter, the selection is over-corrected."""
    rng = np.random.default_rng(9)
    hits = {}
    for name in ("equal", "one poor position"):
        s = _draws(PATTERNS[name], rng, 1500)
        hits[name] = np.mean([max_stdev_belt_interval(row, NU)[1] >= 1.0 for row in s])
    assert hits["equal"] >= 0.95
    assert hits["one poor position"] < 0.85, hits


@pytest.mark.parametrize("name", list(PATTERNS))
def test_union_interval_holds_the_largest_sigma_at_every_pattern(name):
    sigma = PATTERNS[name]
    t = _draws(sigma, np.random.default_rng(17)).max(axis=1)
    up = t * max_stdev_union_interval(1.0, NU, M)[1]
    lo, hi = (t * v for v in max_stdev_union_interval(1.0, NU, M, lower=True))
    theta = sigma.max()
    assert np.mean(up >= theta) >= 0.95 - 3 * SE, name
    assert np.mean((lo <= theta) & (theta <= hi)) >= 0.95 - 3 * SE, name
    tail_se = math.sqrt(0.025 * 0.975 / DRAWS)
    if name == "least favourable":     # exact there: no interval valid for all is narrower
        assert abs(np.mean(up >= theta) - 0.95) < 3 * SE
        assert abs(np.mean(hi < theta) - 0.025) < 3 * tail_se
    if name == "equal":                # the lower limit's own extreme: exact there
        assert abs(np.mean(lo > theta) - 0.025) < 3 * tail_se


def test_union_contains_every_patterns_belt_and_no_more():
    """The union's ends are the extremes of the pattern belts' ends (the cdf is monotone in
    every σ_i), reached at one σ_i alone (upper) and at m equal (lower)."""
    rng = np.random.default_rng(23)
    lo_u, hi_u = max_stdev_union_interval(1.0, NU, M, lower=True)
    ends = []
    for _ in range(40):
        pat = rng.uniform(0.0, 1.0, M)
        lo, hi = max_stdev_belt_interval([1.0], NU, pattern=pat, lower=True)
        assert lo_u <= lo * (1 + 1e-9) and hi <= hi_u * (1 + 1e-9)
        ends.append((lo, hi))
    for pat, end in ((PATTERNS["least favourable"], 1), (PATTERNS["equal"], 0)):
        assert max_stdev_belt_interval([1.0], NU, pattern=pat, lower=True)[end] == pytest.approx(
            (lo_u, hi_u)[end], rel=1e-6)


def test_repeatability_statement_is_the_union_over_patterns():
    """R's stated interval (7.5): the union's one-sided limit, which holds the largest σ_i at
    a poor position (brute force) where the equal-σ maximum's would not."""
    b = repeatability_budget(0.2, NU + 1, M)
    assert b.interval == pytest.approx(max_stdev_union_interval(0.2, NU, M), rel=1e-12)
    t = _draws(PATTERNS["one poor position"], np.random.default_rng(31), 2000).max(axis=1)
    stated = np.array([repeatability_budget(float(v), NU + 1, M).interval[1] for v in t[:200]])
    assert np.allclose(stated, t[:200] * b.interval[1] / 0.2, rtol=1e-12)
    assert np.mean(t * b.interval[1] / 0.2 >= 1.0) >= 0.95 - 3 * math.sqrt(0.95 * 0.05 / 2000)
    eq_hi = t * max_stdev_interval(1.0, NU, M)[1]
    assert np.mean(eq_hi >= 1.0) < 0.5


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="pattern"):
        max_stdev_belt_interval([1.0, 2.0], NU, pattern=[0.0, 0.0])
    with pytest.raises(ValueError, match="m must be"):
        max_stdev_union_interval(1.0, NU, 0)
    with pytest.raises(ValueError, match="sigma"):
        max_stdev_cdf(1.0, [-1.0], NU)
    assert max_stdev_cdf(0.0, [1.0], NU) == 0.0
    assert max_stdev_cdf(1.0, [0.0, 1.0], NU) == pytest.approx(stats.chi2.cdf(NU, NU))


@pytest.mark.parametrize("name", ["equal", "one poor position", "growing with time"])
def test_study_prediction_of_the_chi_square_z_against_brute_force(name):
    """The study prints, beside R's χ² z, what R's exact distribution gives at the ensemble
    σ_i (item_coverage.repeatability_prediction); brute force: the z of drawn maxima."""
    from gonio.analysis.coverage import chi_square_z
    from gonio.specs.ogam_draft.item_coverage import repeatability_prediction

    sigma = PATTERNS[name]
    t = _draws(sigma, np.random.default_rng(41)).max(axis=1)
    z = chi_square_z(t, sigma.max(), NU)
    pr = repeatability_prediction(sigma, NU)
    assert pr["z_chi2_mean"] == pytest.approx(z.mean(), abs=4 * z.std() / math.sqrt(DRAWS))
    assert pr["z_chi2_sd"] == pytest.approx(z.std(), rel=0.05)
    hold = np.mean(t * max_stdev_union_interval(1.0, NU, M)[1] >= sigma.max())
    assert pr["interval_coverage"] == pytest.approx(hold, abs=3 * SE + 1e-3)
