"""k and the printed ν_eff agree: k is t_p of the ν_eff as stated (its integer part, ∞ above
NU_INFINITE), checked against scipy's t and normal quantiles, on the rate family's GUM
wrapper, and by the coverage of the intervals it gives on simulated normal samples."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from gonio.result.statement import NU_INFINITE, coverage_k, nu_text, state, stated_nu
from gonio.kit import gum
from uncertainty import from_u, type_b


@settings(max_examples=300, deadline=None)
@given(st.floats(min_value=1.0, max_value=1e9), st.sampled_from([0.95, 0.9545, 0.99]))
def test_k_is_t_of_the_printed_nu(nu, p):
    printed = nu_text(nu)
    if printed == "∞":
        assert nu > NU_INFINITE
        want = stats.norm.ppf(0.5 + p / 2)
    else:
        assert int(printed) == math.floor(nu) and nu <= NU_INFINITE
        want = stats.t.ppf(0.5 + p / 2, int(printed))
    assert coverage_k(nu, p) == pytest.approx(want, rel=1e-12)
    assert state(1.0, 0.1, k=coverage_k(nu, p), nu_eff=nu).nu_eff == printed


def test_startup_nu_2_gives_k_4_30():
    """IEC start-up: a Type A term of three readings (ν = 2) with a small Type B term gives
    ν_eff a little above 2; it is stated 2 and k = t_95(2) = 4.30 (k = 3.78 was t of 2.5)."""
    u = gum(lambda a, b: a + b, [from_u("a", 0.0, 1.0, dof=2, type="A"),
                                 type_b("b", 0.0, 0.5, "normal", k=2)])
    assert 2.0 < u.nu_eff < 3.0
    assert nu_text(u.nu_eff) == "2"
    assert u.k == pytest.approx(stats.t.ppf(0.975, 2), rel=1e-12)
    assert state(0.0, u.U, k=u.k, nu_eff=u.nu_eff).k == "4.30"     # 3 significant digits
    assert u.U == pytest.approx(u.k * u.u_c, rel=1e-15)


def test_huge_nu_is_stated_infinite_with_the_normal_k():
    u = gum(lambda a, b: a + b, [from_u("a", 0.0, 0.01, dof=3, type="A"),
                                 type_b("b", 0.0, 1.0, "normal", k=2)])
    assert u.nu_eff > 1e6
    assert nu_text(u.nu_eff) == "∞" and stated_nu(u.nu_eff) == math.inf
    assert u.k == pytest.approx(stats.norm.ppf(0.975), rel=1e-12)


def _coverage(u_b: float, trials: int, seed: int) -> tuple[int, int]:
    """Hits of y ± U over ``trials`` draws: mean of 3 normal readings (σ unknown, Type A,
    ν = 2) plus a Type B normal effect of known u ``u_b`` drawn per trial; (hits with k of the
    stated ν_eff, hits with k = t_95 of the unrounded ν_eff, scipy's, on the same draws)."""
    rng = np.random.default_rng(seed)
    n, new, old = 3, 0, 0
    for _ in range(trials):
        x = rng.normal(0.0, 1.0, n)
        err = abs(x.mean() + (rng.normal(0.0, u_b) if u_b else 0.0))
        s_mean = x.std(ddof=1) / math.sqrt(n)
        inputs = [from_u("a", 0.0, s_mean, dof=n - 1, type="A")]
        if u_b:
            inputs.append(type_b("c", 0.0, 2 * u_b, "normal", k=2))
        u = gum(lambda *v: sum(v), inputs)
        k_old = stats.t.ppf(0.975, u.nu_eff) if math.isfinite(u.nu_eff) else stats.norm.ppf(0.975)
        assert u.k >= k_old or u.nu_eff > NU_INFINITE
        new += err <= u.U
        old += err <= k_old * u.u_c
    return new, old


def test_interval_with_stated_nu_covers_95_percent():
    """Where ν is exact (Type A alone, ν = 2) y ± t_95(2)·s/√3 covers 95 % (the
    Clopper–Pearson interval of scipy.stats.binomtest holds 0.95); with a Type B term
    (ν_eff between 2 and ∞, Welch–Satterthwaite) the k of the stated ν_eff covers at least
    as often as the k of the unrounded one on the same draws, and closer to 95 % (W–S itself
    undercovers at ν = 2: the GUM's approximation, not the statement's)."""
    trials = 3000
    hits, _ = _coverage(0.0, trials, 20261129)
    ci = stats.binomtest(hits, trials, 0.95).proportion_ci(0.95)
    assert ci.low <= 0.95 <= ci.high, (hits / trials, ci)
    new, old = _coverage(0.3, trials, 20261130)
    assert new > old, (new, old)
