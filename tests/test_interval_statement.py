"""Items whose distribution is not symmetric about the estimate (a standard deviation, a
range, an extreme) are stated by one coverage interval with its probability: no "± U" and
no k. The interval's ends are rounded outward, and intervals no coverage interval can be
(reversed, not holding the value, below zero for a non-negative quantity) are refused."""

from __future__ import annotations

from decimal import Decimal

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from gonio.errors import GonioError
from gonio.result.statement import item_statement, state_interval
from gonio.kit import std_dev_uncertainty

pos = st.floats(min_value=1e-9, max_value=1e9, allow_nan=False)


def _num(text: str, exponent: int) -> Decimal:
    return Decimal(text).scaleb(exponent)


@settings(max_examples=400, deadline=None)
@given(pos, st.floats(min_value=0.0, max_value=0.999), st.floats(min_value=1e-3, max_value=50))
def test_interval_ends_rounded_outward(value, f_lo, f_hi):
    lo, hi = value * f_lo, value * (1 + f_hi)
    s = state_interval(value, (lo, hi), p=0.95, unit="°/h", nonnegative=True)
    L, H = (_num(x, s.exponent) for x in s.interval)
    assert L <= Decimal(repr(lo)) and H >= Decimal(repr(hi))        # never narrower
    assert L >= 0 and s.U is None and s.k is None
    assert " ± " not in s.text() and "p = 95 %" in s.text()


@pytest.mark.parametrize("value,iv", [(1.0, (2.0, 3.0)), (1.0, (1.0, 1.0)), (1.0, (3.0, 0.5)),
                                      (1.0, (0.0, float("inf")))])
def test_impossible_intervals_are_refused(value, iv):
    with pytest.raises(GonioError):
        state_interval(value, iv)


def test_a_dispersion_of_exactly_zero_is_stated_as_zero():
    """Readings that do not differ at all (a noise-free bench) give s = 0 with the interval
    [0, 0]: stated as the value, with no interval; a point elsewhere is still refused."""
    s = state_interval(0.0, (0.0, 0.0), nonnegative=True, unit="°/h")
    assert s.text() == "0 °/h" and s.interval is None and s.U is None
    with pytest.raises(GonioError):
        state_interval(0.0, (0.0, 0.0))                  # a signed quantity: no such interval


def test_negative_end_of_non_negative_quantity_refused():
    with pytest.raises(GonioError, match="below zero"):
        state_interval(0.5, (-0.1, 1.0), nonnegative=True)
    assert state_interval(0.5, (-0.1, 1.0)).interval == ("-0.10", "1.00")  # a signed quantity


@pytest.mark.parametrize("nu", [2, 4, 9])
def test_std_dev_item_stated_by_chi2_interval_covers(nu):
    """K_r, B_r, Noise RMS: the one statement is σ's one-sided χ² interval [0, hi] with
    p = 95 %; it covers σ in 95 % of simulated normal samples (scipy.stats.binomtest), and
    the item's text has no ± U and no k (k = U/u_c was 6.83 at ν = 2)."""
    rng = np.random.default_rng(nu)
    trials, hits = 4000, 0
    for _ in range(trials):
        s = float(rng.normal(0.0, 1.0, nu + 1).std(ddof=1))
        hits += 1.0 <= std_dev_uncertainty(s, nu, "K_r").interval[1]
    ci = stats.binomtest(hits, trials, 0.95).proportion_ci(0.95)
    assert ci.low <= 0.95 <= ci.high, (hits / trials, ci)
    u = std_dev_uncertainty(0.3, nu, "K_r")
    item = {"value": 0.3, "unit": "°/h", "measured": True, "nonnegative": True,
            "uncertainty": u.to_json()}
    text = item_statement(item).text()
    assert " ± " not in text and "k =" not in text and "upper bound: ≤" in text
    assert "p = 95 %" in text


def test_half_range_upper_limit_covers():
    """IEC 5.3.3.4: the half range of n = 3 records (ν = 2) is stated by the one-sided 95 %
    interval of the expected half range d₃σ/2, from the distribution of the normal range.
    Checked against an independent simulation: the true d₃σ/2 (d₃ from a 10⁶-draw Monte
    Carlo, not the code's integral) lies below the upper end in 95 % of simulated sets.
    The t interval it replaces (hr ± t₉₅(2)·hr/2) reached the truth in only 92.5 %."""
    from gonio.specs.iec62047_20.formulas import half_range_upper

    rng = np.random.default_rng(5334)
    d3 = float(np.ptp(rng.normal(size=(1_000_000, 3)), axis=1).mean())
    theta = d3 / 2.0
    factor = half_range_upper(1.0, 3)                 # the upper end is linear in h
    trials = 20_000
    h = np.ptp(rng.normal(size=(trials, 3)), axis=1) / 2.0
    hits = int(np.sum(theta <= h * factor))
    ci = stats.binomtest(hits, trials, 0.95).proportion_ci(0.95)
    assert ci.low <= 0.95 <= ci.high, (hits / trials, ci)
    t_hits = int(np.sum(theta <= h + stats.t.ppf(0.975, 2) * h / 2.0))
    assert t_hits / trials < 0.93                     # the statement it replaces undercovered
    s = item_statement({"value": 0.2, "unit": "°/s", "measured": True, "nonnegative": True,
                        "uncertainty": {"U": 0.2 * factor - 0.2, "k": None, "nu_eff": 2,
                                        "coverage_probability": 0.95,
                                        "interval": [0.0, 0.2 * factor]}})
    assert s.text() == "0.20 °/s; upper bound: ≤ 0.79 °/s (interval [0, 0.79], p = 95 %)"


def test_normal_range_integrals_equal_the_norm_cdf_integrands():
    """normal_range_cdf and normal_range_mean evaluate φ and Φ without scipy.stats' argument
    checks (for speed: half_range_upper's root search called them for seconds per
    calibration): the same integrals written here with scipy.stats.norm give the same
    numbers bit for bit, and so the same limit."""
    from scipy import integrate, optimize

    from gonio.specs.iec62047_20.formulas import (half_range_upper, normal_range_cdf,
                                                  normal_range_mean)

    def cdf_here(w, n):
        f = lambda x: stats.norm.pdf(x) * (stats.norm.cdf(x + w) - stats.norm.cdf(x)) ** (n - 1)  # noqa: E731
        return float(min(1.0, n * integrate.quad(f, -12.0, 12.0, limit=200)[0]))

    def mean_here(n):
        f = lambda x: 1.0 - stats.norm.cdf(x) ** n - stats.norm.sf(x) ** n  # noqa: E731
        return float(integrate.quad(f, -12.0, 12.0, limit=200)[0])

    for n in (2, 3, 5):
        for w in (0.43, 1.0, 3.314):
            assert normal_range_cdf(w, n) == cdf_here(w, n)
        assert normal_range_mean(n) == mean_here(n)
    w = optimize.brentq(lambda x: cdf_here(x, 3) - (1.0 - 0.95), 1e-9, 40.0, xtol=1e-12)
    assert half_range_upper(1.0, 3) == float(1.0 * mean_here(3) / w)
