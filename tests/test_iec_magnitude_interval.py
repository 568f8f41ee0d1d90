"""IEC 62047-20 5.1.3.5 and 5.3.3.3 (the largest |R_Vi| over the supplies), 5.2 (the larger
|K| of X and Y) and 5.3.3.8 (max(|Out,gp|, |Out,gv|)) are magnitudes: each is stated by one
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
KEYS = ("ratiometric_error", "bias_ratiometric_error", "cross_axis", "g_sensitivity")


#: JJF 1535 7.2.12's B_g = max |B_g,axis|, 7.2.5's K_t and 7.2.14's B_t (the largest |slope|
#: over the temperatures) likewise
JJF_KEYS = ("g_sensitivity", "sf_temperature_sensitivity", "bias_temperature_sensitivity")


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
    # the interval is that of the supplies' own points: upper = max_i(|x_i| + c_H u_i)
    f = it.details["max_abs_interval"]
    x, uu = np.abs(f["x"]), np.asarray(f["u"])
    from scipy.stats import norm, t as student
    q = norm.cdf(f["c_upper"])
    cH = np.array([f["c_upper"] if math.isinf(n) else student.ppf(q, n) for n in f["nu"]])
    assert hi == pytest.approx(float(np.max(x + cH * uu)), rel=1e-12)


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
