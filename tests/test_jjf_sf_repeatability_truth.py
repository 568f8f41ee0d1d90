"""JJF 1535 7.2.4 eq (10): K_r is the standard deviation of Q least-squares K_m, and each K_m
carries the rate noise of its own calibration's points beside the power-cycle scatter, as
each B_0,m of 7.2.11 carries its record mean's noise. The truth is √(σ_K,run² + var(K_m)/K²)
with var(K_m) from the noise model's covariance along the plan's segments
(:func:`gonio.specs.jjf1535.truth.sf_fit_noise_rel`), checked here against the white-noise
closed form and against the bench's own noise generator (a Monte Carlo of
:class:`gonio.bench.rate_gyro.NoiseState` through numpy.polyfit)."""

from __future__ import annotations

import math
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from gonio.bench.rate_gyro import NoiseState
from gonio.pipeline.coverage import reduced_protocol
from gonio.specs import get
from gonio.specs._rate_family.simulate import study_bench
from gonio.specs.jjf1535.protocol import plan
from gonio.specs.jjf1535.truth import sf_fit_noise_rel, truth
from gonio.units import S_PER_H


@pytest.fixture(scope="module")
def setting():
    spec = get("jjf1535-2015")
    with tempfile.TemporaryDirectory() as d:
        proto = spec.load_protocol(str(reduced_protocol(spec.key, Path(d) / "r.toml")))
    return study_bench(), proto


def _first_calibration(bench, proto):
    segs = [s for s in plan(proto, bench) if s.test == "scale_factor"]
    return [s for s in segs if s.run == segs[0].run]


def _monte_carlo(bench, proto, m: int, seed: int) -> float:
    """sd of the polyfit slope of the rate points' noise means, the generator's noise."""
    segs = _first_calibration(bench, proto)
    room = proto["protocol"]["room_temperature_c"]
    rng = np.random.default_rng(seed)
    k = []
    for _ in range(m):
        ns = NoiseState(bench.gyro, rng)
        rates, means = [], []
        for s in segs:
            ns.skip(s.delay_s)
            r = ns.samples(s.samples, s.interval_s, room)
            if s.role == "rate":
                rates.append(s.rate_dps)
                means.append(r.mean())
        k.append(np.polyfit(rates, means, 1)[0])
    return float(np.std(k, ddof=1))


def test_white_noise_closed_form(setting):
    bench, proto = setting
    g = replace(bench.gyro, bias_instability_dph=0.0, rrw_dph_sqrt_h=0.0, output_lsb=0.0)
    b = replace(bench, gyro=g)
    segs = [s for s in _first_calibration(b, proto) if s.role == "rate"]
    om = np.array([s.rate_dps for s in segs])
    sxx = float(np.sum((om - om.mean()) ** 2))
    n2 = (g.arw_deg_sqrt_h / math.sqrt(S_PER_H)) ** 2 * (1 + g.arw_tc1_per_c * float(
        g.delta_t(proto["protocol"]["room_temperature_c"]))) ** 2
    var = sum(((s.rate_dps - om.mean()) / sxx) ** 2 * n2 / (s.interval_s * s.samples)
              for s in segs)
    assert sf_fit_noise_rel(b, proto) == pytest.approx(math.sqrt(var), rel=1e-9)


def test_against_the_noise_generator(setting):
    bench, proto = setting
    want = sf_fit_noise_rel(bench, proto)
    # 800 calibrations: the sd's relative standard error is 1/√1600 = 2.5 %
    assert _monte_carlo(bench, proto, 800, 3) == pytest.approx(want, rel=0.10)
    # the slow terms matter (forward rates first, then reverse: their drift tilts the fit)
    white = replace(bench.gyro, bias_instability_dph=0.0, rrw_dph_sqrt_h=0.0)
    assert want > 1.2 * sf_fit_noise_rel(replace(bench, gyro=white), proto)


def test_truth_carries_the_fit_noise(setting):
    bench, proto = setting
    t = truth(bench, proto)["sf_repeatability"]
    fit = sf_fit_noise_rel(bench, proto)
    assert t["value"] == pytest.approx(math.hypot(bench.gyro.sf_scatter_rel, fit), rel=1e-12)
    assert t["value"] > 1.04 * bench.gyro.sf_scatter_rel
    assert t["power_cycle_scatter_rel"] == bench.gyro.sf_scatter_rel
    # no noise: the truth is the scatter parameter alone
    quiet = replace(bench.gyro, arw_deg_sqrt_h=0.0, bias_instability_dph=0.0,
                    rrw_dph_sqrt_h=0.0, output_lsb=0.0)
    assert sf_fit_noise_rel(replace(bench, gyro=quiet), proto) == 0.0
