"""The optical ranges K_l, C_v and C_g are stated by a confidence belt built from M = 4000
Monte Carlo draws (``uncertainty.stdev.range_belt_interval``); the numerical standard
uncertainty of the belt's ends (JCGM 101 7.9, ``range_belt_numerical_u``) decides how many
digits the certificate states. Checked against the ends' own scatter over independent sets of
draws (not against itself): never narrower than that scatter, and not more than 2.6 times it
(the estimate takes each end as one quantile's; where several true-value patterns compete
for an end, or the belt's floor decides it, the ends scatter less: 0.48–0.77 of it here)."""

from __future__ import annotations

import json
import math
from decimal import Decimal

import numpy as np
import pytest
from scipy import stats

from gonio.result.statement import item_statement
from uncertainty.stdev import range_belt_interval, range_belt_numerical_u


@pytest.mark.parametrize("x", [[0.0, 20.0], [0.0, 20.0, 5.0, 10.0, 12.0, 3.0],
                               [0.0, 5.0, 1.0, 2.0, 2.5, 0.5]])
def test_numerical_u_bounds_the_ends_scatter_over_independent_draw_sets(x):
    x = np.asarray(x)
    ends, us = [], []
    for s in range(30):
        e = np.random.default_rng(20261204 + s).normal(0.0, 1.0, (4000, x.size))
        ends.append(range_belt_interval(x, e))
        us.append(range_belt_numerical_u(x, e))
    spread = np.std(np.array(ends), axis=0, ddof=1)
    est = np.sqrt(np.mean(np.array(us) ** 2, axis=0))
    for side in (0, 1):
        assert spread[side] > 0
        assert 1.0 <= est[side] / spread[side] <= 2.6, (side, est, spread)


def test_two_values_numerical_u_is_the_tail_quantiles():
    """One pattern: the ends' u is the quantile's closed form √(α(1 − α)/M)/φ(z_α)·√2 at the
    belt's tail α (0.025 less its allowance), averaged over draw sets within 10 %."""
    m = 4000
    a = 0.025 - 2 * math.sqrt(0.025 * 0.975 / m)
    closed = math.sqrt(a * (1 - a) / m) / stats.norm.pdf(stats.norm.ppf(a)) * math.sqrt(2)
    us = [range_belt_numerical_u([0.0, 20.0], np.random.default_rng(s).normal(0.0, 1.0, (m, 2)))
          for s in range(40)]
    assert np.allclose(np.mean(us, axis=0), closed, rtol=0.10), (np.mean(us, axis=0), closed)


def test_an_end_held_at_zero_has_no_numerical_u():
    e = np.random.default_rng(5).normal(0.0, 1.0, (4000, 6))
    x = np.zeros(6)
    assert range_belt_interval(x, e)[0] == 0.0
    u_lo, u_hi = range_belt_numerical_u(x, e)
    assert u_lo == 0.0 and u_hi > 0.0


@pytest.mark.parametrize("item", ["scale_factor_nonlinearity", "rate_consistency",
                                  "pointing_consistency"])
def test_optical_ranges_are_stated_to_the_digits_their_draws_support(shared_demo, item):
    folder = shared_demo("ogam-draft")
    res = json.loads((folder / "results.json").read_text(encoding="utf-8"))
    it = res["items"][item]
    unc = it["uncertainty"]
    assert unc["k_source"] == "neyman-belt" and unc["k"] is None
    s = unc["interval_numerical_u"]
    assert s > 0
    st = item_statement(it)
    step = Decimal(1).scaleb(-st.decimals)
    gap = unc["interval"][1] - it["value"]
    # JCGM 101 7.9.2: 2s <= δ, or one significant digit of the reach where that is all
    assert float(step) / 2 >= 2 * s * (1 - 1e-12) or step > Decimal(repr(gap)) / 10
    lo, hi = (Decimal(v) for v in st.interval)
    assert lo <= Decimal(repr(unc["interval"][0])) and hi >= Decimal(repr(unc["interval"][1]))
    # the summary and the certificate state that same upper end
    text = (folder / "summary.txt").read_text(encoding="utf-8")
    assert f"≤ {st.interval[1]}" in text
