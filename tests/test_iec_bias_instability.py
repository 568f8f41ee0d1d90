"""IEC 62047-20 5.4.5.3 c) bias instability: the floor rule's distribution and its bias.

- :func:`floor_rule_draws` (correlated χ² draws of the Allan variances near the floor) against
  a brute-force Monte Carlo: the same floor rule applied to records simulated at full rate
  (:func:`gonio.analysis.noise.simulate_noise`) and analysed as the calibration analyses the
  static record (decade:10 τ, ≥ 10 clusters). Mean and standard deviation must agree; drawn
  independently per τ (the covariance's diagonal only) the spread is 28–30 % too small and
  the mean 10–11 % low on both models, which fails here; the χ² interval of the floor's τ
  alone (the former budget) was 46 % wider than the floor's scatter on the built-in programme.
- :func:`floor_reading` on records whose white noise lifts the floor well above 0.664·B:
  the bias-corrected value is centred on the simulated B, the standard's reading is not
  (its u is checked by the coverage study of the built-in programme, README).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.analysis.noise import allan_deviation, fit_noise_model, simulate_noise
from gonio.specs.iec62047_20 import formulas as ief
from gonio.specs.iec62047_20 import items as I

TAU0_S = 0.1
N_SAMPLES = 72_000            # the built-in programme's static record (2 h at 10 Hz)
#: the ADXRS610 bench's noise in the fit's units: N °/h·√s (1.8 °/√h), B °/h, K °/h/√s
#: (36.7 °/h/√h); and the same with 3× the white noise (the floor lifted ~20 %)
MODELS = {"bench": (0.0, 1.8 * 60.0, 22.3, 36.7 / 60.0, 0.0),
          "white_x3": (0.0, 3 * 1.8 * 60.0, 22.3, 36.7 / 60.0, 0.0)}


def _record(coef, rng):
    y = simulate_noise(N_SAMPLES, TAU0_S, *coef, rng=rng)
    return allan_deviation(y, TAU0_S, "rate", "decade:10", alpha=0, unit="deg/h")


@pytest.mark.parametrize("model", sorted(MODELS))
def test_floor_rule_draws_match_full_rate_monte_carlo(model):
    coef = MODELS[model]
    rng = np.random.default_rng(2026 + len(model))
    floors = []
    for _ in range(160):
        a = _record(coef, rng)
        floors.append(ief.bias_instability_floor(a.adev, n_clusters=a.n_samples / a.m)[0])
    floors = np.array(floors)
    ok = np.flatnonzero(a.n_samples / a.m >= 10)
    i_model = int(ok[np.argmin(I.model_deviation(a.tau_s[ok], *coef))])
    d = I.floor_rule_draws(a, coef, i_model)
    se = floors.std(ddof=1) / math.sqrt(floors.size)
    assert abs(d.mean() - floors.mean()) <= 3.5 * se + 0.01 * floors.mean(), \
        (d.mean(), floors.mean(), se)
    assert 0.8 <= d.std(ddof=1) / floors.std(ddof=1) <= 1.25, (d.std(), floors.std())
    # the bias the item removes exists here: the mean differs from B by other terms/selection
    if model == "white_x3":
        assert floors.mean() - coef[2] > 4 * se


def test_floor_reading_removes_the_rule_bias():
    coef = MODELS["white_x3"]
    rng = np.random.default_rng(77)
    raw, val = [], []
    for _ in range(24):
        a = _record(coef, rng)
        r, _, b, _, _, _ = I.floor_reading(a, fit_noise_model(a))
        raw.append(r)
        val.append(b)
    raw, val = np.array(raw), np.array(val)
    se = val.std(ddof=1) / math.sqrt(val.size)
    assert abs(val.mean() - coef[2]) <= 3 * se, (val.mean(), se)
    assert raw.mean() - coef[2] > 4 * raw.std(ddof=1) / math.sqrt(raw.size)
