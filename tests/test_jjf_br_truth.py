"""JJF 1535 7.2.11: the bias repeatability's truth, √(σ_b,run² + var(record mean)), against
the generator. var(record mean) of :func:`gonio.specs.jjf1535.truth.record_mean_variance`
(the closed form of the noise model: white, the Gauss–Markov sum, the rate random walk from
power-on) is checked against the spread of the means of many independent power-ups drawn by
the bench's own noise generator (:class:`gonio.bench.rate_gyro.NoiseState`, a second
computation: a recursion sample by sample), with the study's record (600 samples at 1 s,
1800 s after power-on) and with a record right at power-on. The coverage of B_r's χ²
interval then rests on the records being independent normal draws of that variance
(docs/validation-rate.md: 2000 study trials, benchmarks/study_jjf_br_bg.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.bench.rate_gyro import NoiseState, load_rate_bench
from gonio.specs.jjf1535.truth import record_mean_variance

RECORDS = 2000


def _record_means(bench, n: int, dt: float, start_s: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    out = np.empty(RECORDS)
    for i in range(RECORDS):
        ns = NoiseState(bench.gyro, rng, enabled=True)      # one power-up
        ns.skip(start_s)
        out[i] = ns.samples(n, dt, bench.gyro.reference_temperature_c).mean()
    return out


@pytest.mark.parametrize("start_s", [1800.0, 0.0])
def test_record_mean_variance_is_the_generators(start_s):
    bench = load_rate_bench("mems-adxrs610")
    vm = record_mean_variance(bench, 1.0, 600, start_s)
    means = _record_means(bench, 600, 1.0, start_s, seed=11 + int(start_s))
    s2 = float(np.var(means, ddof=1))
    # var of a sample variance of normal draws: 2σ⁴/(n − 1); 4 standard errors
    tol = 4.0 * math.sqrt(2.0 / (RECORDS - 1))
    assert abs(s2 / vm - 1.0) < tol, (s2, vm)
    assert abs(float(means.mean())) < 4.0 * math.sqrt(vm / RECORDS)
