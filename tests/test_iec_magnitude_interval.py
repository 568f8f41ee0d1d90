"""IEC 62047-20 5.1.3.5 and 5.3.3.3 (the largest |R_Vi| over the supplies), 5.2 (the larger
|K| of X and Y), 5.3.3.8 (max(|Out,gp|, |Out,gv|)) and 5.1.3.6 (the largest |L_i|), JJF
1535 7.2.2 (K_n, the largest |residual|) and 7.2.3 (K_a = |K+ − K−|/K̄) are magnitudes: each is stated by one
interval, that of the extreme of magnitudes (never value ± U from the GUM's
linearisation of |·|, which reached below zero: "0.0046 ± 0.0080 %"), and the interval holds
max_i |R_true,i| with at least 95 % — checked here by a Monte Carlo written in the test
(numpy draws of the supplies' R_i about a truth pattern, the interval rebuilt from each
draw), on a small noisy session of the study bench."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.formats.rate_readings import RateReadings
from gonio.result.statement import item_statement
from tests.test_rate_iec_items import exact_bench, small_protocol

#: the magnitudes max_i |x_i|: 5.1.3.5 and 5.3.3.3 (largest |R_Vi|), 5.2 (larger |K| of X,
#: Y), 5.3.3.8 (max(|Out,gp|, |Out,gv|))
KEYS = ("ratiometric_error", "bias_ratiometric_error", "cross_axis", "g_sensitivity",
        "linearity")


#: JJF 1535 7.2.12's B_g = max |B_g,axis|, 7.2.5's K_t and 7.2.14's B_t (the largest |slope|
#: over the temperatures) likewise
JJF_KEYS = ("g_sensitivity", "sf_temperature_sensitivity", "bias_temperature_sensitivity",
            "nonlinearity", "asymmetry")


@pytest.fixture(scope="module")
def iec(tmp_path_factory):
    from gonio.specs.iec62047_20 import calibrate
    from gonio.specs.iec62047_20.simulate import simulate
    tmp = tmp_path_factory.mktemp("iecmag")
    proto = small_protocol(tmp, "iec62047-20")
    res = simulate(exact_bench(), str(proto), seed=0)
    rd = RateReadings(res.data, {k: str(v) for k, v in res.metadata.items()})
    return calibrate(rd, str(proto))


@pytest.fixture(scope="module")
def jjf(tmp_path_factory):
    from gonio.specs.jjf1535 import calibrate
    from gonio.specs.jjf1535.simulate import simulate
    tmp = tmp_path_factory.mktemp("jjfmag")
    proto = small_protocol(tmp, "jjf1535-2015")
    res = simulate(exact_bench(), str(proto), seed=0)
    rd = RateReadings(res.data, {k: str(v) for k, v in res.metadata.items()})
    return calibrate(rd, str(proto))


@pytest.mark.parametrize("spec, key", [("iec", k) for k in KEYS] + [("jjf", k) for k in JJF_KEYS])
def test_magnitude_is_stated_by_one_interval_of_possible_values(request, spec, key):
    it = request.getfixturevalue(spec).items[key]
    assert it.measured, it.reason
    u = it.uncertainty
    st = item_statement(it)
    assert it.nonnegative and u.k is None and st.U is None and st.k is None
    lo, hi = u.interval
    assert 0.0 <= lo <= it.value <= hi and u.U == pytest.approx(hi - it.value)
    assert " ± " not in st.text() and st.interval is not None
    assert float(st.interval[0]) >= 0.0
    # the interval is that of the supplies' own points: upper = max_i(|x_i| + c_H u_i), + b_i
    # each point's bounded error at its bound where the item states a bound condition (JJF
    # K_t, B_t: the gyro's temperature at the set points; u_i then of the other lines)
    f = it.details["max_abs_interval"]
    x, uu = np.abs(f["x"]), np.asarray(f["u"])
    bc = it.details.get("bound_condition")
    b = np.asarray(bc["b"]) if bc else np.zeros_like(x)
    if bc:
        assert list(uu) == bc["u_rest"] and b.shape == x.shape and np.all(b > 0)
    from scipy.stats import norm, t as student
    q = norm.cdf(f["c_upper"])
    cH = np.array([f["c_upper"] if math.isinf(n) else student.ppf(q, n) for n in f["nu"]])
    assert hi == pytest.approx(float(np.max(x + cH * uu + b)), rel=1e-12)


@pytest.mark.parametrize("spec, key", [("iec", k) for k in KEYS] + [("jjf", k) for k in JJF_KEYS])
def test_interval_holds_the_extreme_with_95_percent(request, spec, key):
    """Truth patterns at the session's own u_i: the measured R_i, and all R_i at zero (where
    |·| is least linear); draws R*_i = R_i + u_i·N, the interval rebuilt from each draw."""
    from uncertainty.extreme import max_abs_interval
    f = request.getfixturevalue(spec).items[key].details["max_abs_interval"]
    uu = np.asarray(f["u"])
    rng = np.random.default_rng(7)
    for mu in (np.asarray(f["x"]), np.zeros_like(uu)):
        theta = float(np.max(np.abs(mu)))
        n, hit = 2000, 0
        for _ in range(n):
            xs = mu + uu * rng.standard_normal(uu.size)
            r = max_abs_interval(xs, uu)
            hit += r.lower <= theta <= r.upper
        # at least 95 % (3.5 binomial sd below allowed for the draws)
        assert hit / n >= 0.95 - 3.5 * math.sqrt(0.95 * 0.05 / n), (key, hit / n)


def test_linearity_points_are_the_residuals_over_full_scale(iec):
    """5.1.3.6's points are eq (8)'s L_i, recomputed here with numpy's polyfit from the
    scale-factor points (FullScale = y(CW max) − y(CCW max)); the standard's reading
    max |L_i| is kept, and the value is it less the selection midpoint, inside the interval."""
    sf, it = iec.items["scale_factor"].details, iec.items["linearity"]
    x, y = np.asarray(sf["x_dps"], float), np.asarray(sf["y"], float)
    a, b = np.polyfit(x, y, 1)
    L = 100 * (y - (a * x + b)) / abs(y[np.argmax(x)] - y[np.argmin(x)])
    f = it.details["max_abs_interval"]
    np.testing.assert_allclose(np.abs(f["x"]), np.abs(L), rtol=1e-9, atol=1e-12)
    assert it.details["max_abs_L_i_pct"] == pytest.approx(float(np.max(np.abs(L))), rel=1e-9)
    reading_less = float(np.max(np.abs(L))) - it.details["selection_midpoint_pct"]
    lo, hi = it.uncertainty.interval
    assert it.value == pytest.approx(min(max(reading_less, lo), hi), rel=1e-12)


def test_nonlinearity_points_are_the_mean_residual_profile(jjf):
    """7.2.2's points: the Q calibrations' residuals over their spans K_m(Ω+ − Ω−), averaged
    rate by rate (recomputed here from 7.2.1's details)."""
    sf, it = jjf.items["scale_factor"].details, jjf.items["nonlinearity"]
    rates = np.asarray(sf["rates_dps"], float)
    v = [np.asarray(r, float) / abs(k * (rates.max() - rates.min()))
         for r, k in zip(sf["residuals_m"], sf["K_m"])]
    np.testing.assert_allclose(it.details["max_abs_interval"]["x"], np.mean(v, axis=0),
                               rtol=1e-9, atol=1e-15)
    # eq (6)'s reading, the mean over m of the largest |v_j,m|, kept beside
    assert it.details["reading"] == pytest.approx(float(np.mean([np.abs(r).max() for r in v])),
                                                  rel=1e-9)


def test_asymmetry_interval_is_the_folded_t_interval_of_the_signed_mean(jjf):
    """7.2.3 by a closed form written here: the signed K_a,m = (K+ − K−)/((K+ + K−)/2) from
    the per-direction slopes, their mean s̄, u² = u_noise² + u_ripple² + s²(K_a,m)/Q (the
    budget's noise and ripple rows), ν by Welch–Satterthwaite, and the interval
    [max(0, |s̄| − t u), |s̄| + t u], t = t_0.975(ν)."""
    from scipy.stats import t as student

    it = jjf.items["asymmetry"]
    kp, kn = np.asarray(it.details["K_pos_m"]), np.asarray(it.details["K_neg_m"])
    sgn = (kp - kn) / (0.5 * (kp + kn))
    Q = sgn.size
    rows = {c["symbol"]: c for c in it.uncertainty.components}
    terms = [(rows["noise"]["u"], rows["noise"]["dof"]), (rows["ripple"]["u"], math.inf),
             (float(sgn.std(ddof=1)) / math.sqrt(Q), Q - 1)]
    u = math.sqrt(sum(x * x for x, _ in terms))
    nu = u ** 4 / sum(x ** 4 / n for x, n in terms if not (n is None or math.isinf(n)))
    t = student.ppf(0.975, nu)
    s = abs(float(sgn.mean()))
    lo, hi = it.uncertainty.interval
    assert (lo, hi) == pytest.approx((max(0.0, s - t * u), s + t * u), rel=1e-9)
    assert it.details["reading"] == pytest.approx(float(np.mean(np.abs(sgn))), rel=1e-12)


def test_power_on_drift_stated_by_the_interval_of_its_replicates(iec):
    """5.3.3.5: one interval (no k, no ν, no ± U), the lower end at or above 0; its coverage
    is checked by the Monte Carlo of tests/test_iec_power_on_drift.py."""
    from gonio.specs.iec62047_20.items import K_SOURCE_POWER_ON

    it = iec.items["bias_drift_after_power_on"]
    u, st = it.uncertainty, item_statement(it)
    assert it.nonnegative and u.k is None and u.nu_eff is None and st.U is None
    assert u.k_source == K_SOURCE_POWER_ON and u.coverage_probability == 0.95
    lo, hi = u.interval
    assert 0.0 <= lo <= it.value <= hi and u.U == pytest.approx(hi - it.value)
    assert " ± " not in st.text()
    assert it.details["reading_dps"] == max(it.details["per_record_dps"])
