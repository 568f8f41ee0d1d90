"""IEC 62047-20 5.3.3.7 hysteresis and 5.4.5.2 ARW: each budget checked against a Monte Carlo
of its own estimator, with truths set outside gonio's formulas.

- 5.3.3.7 is a maximum over the temperatures visited twice. Its selection term (± c_n·σ_max,
  rectangular) and its interval [0, upper] must cover on both limiting benches — one
  temperature's hysteresis far above the noise, and none at all — while z = (value − truth)/u_c keeps a spread of
  0.7–1.3 where the maximum is not a selection (a 95 % bound divided by 2, the earlier term,
  gave 0.63).
- 5.4.5.2 (the ARW on the ADXRS610 bench's own noise generator, z and the coverage of its
  χ² statement) is checked in tests/test_arw_statement.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.analysis.coverage import clopper_pearson
from gonio.specs.iec62047_20 import formulas as ief
from gonio.specs.iec62047_20 import items as I

#: The programme's visits (base → max → base → min → base), °C.
VISITS_C = [22.5, 53.75, 85.0, 53.75, 22.5, -8.75, -40.0, -8.75, 22.5]


def test_max_abs_normal_mean_against_simulation():
    rng = np.random.default_rng(11)
    for n in (1, 2, 3, 5):
        x = np.abs(rng.standard_normal((200_000, n))).max(axis=1)
        assert ief.max_abs_normal_mean(n) == pytest.approx(x.mean(), abs=4 * x.std() / math.sqrt(x.size))


def _hysteresis_study(h_dps: float, sigma_dps: float, trials: int, seed: int):
    """z = (value − truth)/u_c of :func:`hysteresis_budget` on visits with noise σ each and
    a true hysteresis h at 53.75 °C only (the falling visit h lower), no drift, and how
    often its stated interval [0, upper] holds h."""
    rng = np.random.default_rng(seed)
    true = np.array([0.01 * (t - 22.5) / 60 for t in VISITS_C])      # a bias-temperature slope
    true[3] -= h_dps                                                  # 53.75 °C falling visit
    err, uc, hits = [], [], 0
    for _ in range(trials):
        b = true + sigma_dps * rng.standard_normal(true.size)
        pts = [(T, float(v), sigma_dps, 10_000, 3600.0 * i) for i, (T, v) in enumerate(zip(VISITS_C, b))]
        val, _, _, u = I.hysteresis_budget(pts, lambda sep: 0.0)
        err.append(val - h_dps)
        uc.append(u.u_c)
        hits += u.interval[0] <= h_dps <= u.interval[1]     # stated by [0, upper] alone
    err, uc = map(np.array, (err, uc))
    return err / uc, hits, trials


@pytest.mark.parametrize("h_over_sigma", [30.0, 0.0])
def test_hysteresis_budget_monte_carlo(h_over_sigma):
    sigma = 0.002
    z, hits, n = _hysteresis_study(h_over_sigma * sigma, sigma, 600, seed=int(h_over_sigma) + 5)
    assert clopper_pearson(hits, n)[1] >= 0.95, (hits, n)
    if h_over_sigma:
        # the maximum is the one temperature: z ~ N(0, 1/(1 + c_3²/3)), sd 0.80
        assert 0.7 <= z.std(ddof=1) <= 1.3, z.std(ddof=1)
        assert abs(z.mean()) < 0.15
    else:
        # every true difference 0: the maximum of |noise| — one-sided, narrower than normal
        assert z.std(ddof=1) >= 0.3 and z.mean() > 0

