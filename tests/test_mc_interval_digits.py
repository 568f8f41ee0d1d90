"""An interval taken from a Monte Carlo's draws is stated only to the digits its finite number
of draws supports (JCGM 101 7.9): IEC 62047-20 5.3.3.5's interval of 400 replicates and
5.4.5.3's interval of 4000 floor-rule draws. The
numerical standard uncertainty of a quantile is checked against the closed form for normal
draws and the spread of quantiles over independent draw sets (not against itself)."""

from __future__ import annotations

import json
import math
from decimal import Decimal

import numpy as np
import pytest
from scipy.stats import norm

from gonio.result.statement import item_statement, numerical_decimals, state_interval
from uncertainty import quantile_numerical_u


@pytest.mark.parametrize("s", [3e-5, 1e-4, 2.4e-4, 2.5e-4, 0.002, 0.0025, 0.0031, 0.7, 3.0, 26.0])
def test_numerical_decimals_is_the_last_place_with_two_s_within_half_a_digit(s):
    dec = numerical_decimals(s)
    assert 0.5 * 10.0 ** -dec >= 2 * s * (1 - 1e-12)           # 2s <= δ at dec
    assert 0.5 * 10.0 ** -(dec + 1) < 2 * s                     # one place right: not


def test_numerical_decimals_agrees_with_the_decimal_logarithm():
    """The exponent rule against ⌈log₁₀(4u)⌉ by ``Decimal.log10`` (60 digits: exact for a
    power of ten, and 17-digit reprs lie at least 10⁻¹⁸ from one), over random u of every
    magnitude, the powers of ten and their neighbours a float apart."""
    from decimal import ROUND_CEILING, localcontext

    rng = np.random.default_rng(20261204)
    us = [float(u) for u in 10.0 ** rng.uniform(-300, 300, 300)] + [10.0 ** e / 4 for e in range(-30, 31)]
    us += [math.nextafter(u, math.inf) for u in us[-61:]] + [math.nextafter(u, 0) for u in us[-61:]]
    for u in us:
        with localcontext(prec=60, Emax=999_999, Emin=-999_999):
            ref = -int(Decimal(repr(4.0 * u)).log10().to_integral_value(rounding=ROUND_CEILING))
        assert numerical_decimals(u) == ref, u
    with pytest.raises(ValueError):
        numerical_decimals(0.0)


def test_quantile_numerical_u_matches_the_spread_of_quantiles_and_the_closed_form():
    rng = np.random.default_rng(20261202)
    m, probs = 400, np.array([0.025, 0.975])
    sets = rng.normal(size=(600, m))
    est = np.mean([quantile_numerical_u(x, probs) for x in sets], axis=0)
    spread = np.std(np.quantile(sets, probs, axis=1), axis=1, ddof=1)
    closed = math.sqrt(0.025 * 0.975 / m) / norm.pdf(norm.ppf(0.975))
    assert np.allclose(est, closed, rtol=0.08), (est, closed)
    assert np.allclose(spread, closed, rtol=0.12), (spread, closed)


def test_state_interval_moves_the_place_left_never_narrower():
    iv = (0.0677, 0.1302)
    plain = state_interval(0.0995, iv, p=0.95)
    coarse = state_interval(0.0995, iv, p=0.95, numerical_u=0.002)
    assert plain.interval == ("0.067", "0.131")
    assert coarse.interval == ("0.06", "0.14") and coarse.value == "0.10"
    assert Decimal(coarse.interval[0]) <= Decimal(str(iv[0]))
    assert Decimal(coarse.interval[1]) >= Decimal(str(iv[1]))
    # a numerical u too small to matter changes nothing
    assert state_interval(0.0995, iv, p=0.95, numerical_u=1e-6) == plain


def test_floor_interval_numerical_u_matches_the_spread_of_the_ends_over_draw_sets():
    """5.4.5.3's pivot ends value ∓ (quantile − mean) recomputed on 300 independent sets of
    4000 draws: their spread is the numerical u the item states (within 15 %)."""
    from gonio.specs.iec62047_20.items import floor_interval, floor_interval_numerical_u

    rng = np.random.default_rng(20261203)
    sets = 20.0 + 3.0 * rng.standard_gamma(9.0, size=(300, 4000)) / 3.0   # skewed, as a floor
    ends = np.array([floor_interval(20.0, d) for d in sets])
    spread = float(np.max(np.std(ends, axis=0, ddof=1)))
    est = float(np.mean([floor_interval_numerical_u(d) for d in sets]))
    assert abs(est / spread - 1.0) < 0.15, (est, spread)


@pytest.mark.parametrize("clause", ["5.3.3.5", "5.4.5.3"])
def test_monte_carlo_interval_is_stated_to_its_supported_digits(shared_demo, clause):
    res = json.loads((shared_demo("iec62047-20") / "results.json").read_text(encoding="utf-8"))
    items = res["items"] if isinstance(res["items"], list) else list(res["items"].values())
    it = next(i for i in items if i.get("clause") == clause)
    unc = it["uncertainty"]
    s = unc["interval_numerical_u"]
    assert s > 0
    st = item_statement(it)
    step = Decimal(1).scaleb(-st.decimals)
    assert float(step) / 2 >= 2 * s * (1 - 1e-12)             # JCGM 101 7.9.2: 2s <= δ
    lo, hi = (Decimal(x) for x in st.interval)
    assert lo <= Decimal(repr(unc["interval"][0])) and hi >= Decimal(repr(unc["interval"][1]))
    # every output states that same text
    folder = shared_demo("iec62047-20")
    ends = f"[{st.interval[0]}, {st.interval[1]}]"
    assert ends in (folder / "summary.txt").read_text(encoding="utf-8")
    assert ends in (folder / "certificate.html").read_text(encoding="utf-8")
