"""Bench truth of IEC 62047-20 5.4.5.1 b) (in-band noise) and 5.1.3.7 (scale-factor
stability): the truth against closed forms, and the items' recovery of it on the bench —
noise off to numerical precision, noise on within the item's U over several seeds."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from gonio.bench.rate_session import constant_rate_spread_dps
from gonio.formats.rate_readings import RateReadings
from gonio.pipeline.coverage import reduced_protocol
from gonio.specs._rate_family.simulate import study_bench
from gonio.specs.iec62047_20 import calibrate
from gonio.specs.iec62047_20.simulate import simulate
from gonio.specs.iec62047_20.truth import truth
from gonio.specs.iec62047_20.protocol import load_protocol

OMEGA_E_DPS = math.degrees(7.292115e-5)       # IERS, independent of gonio.physics


def white_only(bench, arw=1.8):
    """``bench`` with white rate noise only (ARW at every temperature), ideal equipment."""
    nb = bench.without_noise()
    return replace(nb, gyro=replace(nb.gyro, arw_deg_sqrt_h=arw, arw_tc1_per_c=0.0))


def test_inband_truth_white_closed_form():
    """White noise N (°/√h): one-sided density 2N² ((°/s)²/Hz, N in °/√s); the rms from the
    first Welch line 1/(4096 Δt) to band_hz is √(2N²(band − f₁))."""
    proto = load_protocol("iec62047-20")
    nz = proto["noise"]
    t = truth(white_only(study_bench()), proto)["inband_noise"]["value"]
    n_s = 1.8 / 60.0
    f1 = 1.0 / (4096 * nz["sample_interval_s"])
    assert t == pytest.approx(math.sqrt(2 * n_s ** 2 * (nz["band_hz"] - f1)), rel=1e-5)   # grid 2.5e-5 Hz


def test_stability_truth_closed_forms():
    """White noise: E[population variance of s samples] = σ²(1 − 1/s), σ² = N²/Δt; over the
    noise-free FullScale. A once-per-revolution term of amplitude A over whole revolutions:
    A_eff²/2 with A_eff = A·|sin(Δ/2)/(16 sin(Δ/32))| (the bench's 16 sub-samples)."""
    b = white_only(study_bench())
    s, dt = 300, 1.0
    r = constant_rate_spread_dps(b, 150.0, dt, s, 22.5)
    n_s = 1.8 / 60.0
    assert r["std_dps"] == pytest.approx(n_s / math.sqrt(dt) * math.sqrt(1 - 1 / s), rel=1e-4)
    assert r["periodic_amplitude_dps"] == 0.0
    # cross-axis only, noise off: A = Ω_E cos λ √(cx² + cy²); 150 °/s × 1 s = 150° per sample
    nb = study_bench().without_noise()
    nb = replace(nb, gyro=replace(nb.gyro, cross_axis_x=0.05, cross_axis_y=-0.03))
    r = constant_rate_spread_dps(nb, 150.0, dt, s, 22.5)
    A = OMEGA_E_DPS * math.cos(math.radians(nb.latitude_deg)) * math.hypot(0.05, 0.03)
    d16 = math.sin(math.radians(75.0)) / (16 * math.sin(math.radians(150.0 / 32)))
    assert r["std_dps"] == pytest.approx(A * d16 / math.sqrt(2), rel=1e-12)
    # not whole revolutions (s = 7: 1050°): the start-angle average A²/2·(1 − D_7²)
    r7 = constant_rate_spread_dps(nb, 150.0, dt, 7, 22.5)
    d7 = math.sin(7 * math.radians(75.0)) / (7 * math.sin(math.radians(75.0)))
    assert r7["std_dps"] == pytest.approx(A * d16 * math.sqrt((1 - d7 ** 2) / 2), rel=1e-12)
    # brute force over start angles of the sampled, sub-sampled sinusoid
    th0 = np.linspace(0, 2 * np.pi, 720, endpoint=False)[:, None, None]
    j = np.arange(7)[None, :, None]
    k = (np.arange(16)[None, None, :] + 0.5) / 16
    y = (A * np.cos(th0 + np.radians(150.0) * (j + k))).mean(axis=2)
    assert math.sqrt(y.var(axis=1).mean()) == pytest.approx(r7["std_dps"], rel=1e-9)


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("iectruth")
    # whole revolutions at ±150 °/s: 300 samples × 1 s = 125 turns (as the built-in protocol)
    return reduced_protocol("iec62047-20", tmp / "small.toml",
                            {"g_sensitivity": {"samples": 20}, "stability": {"samples": 300},
                             "resolution": {"samples": 10, "rest_samples": 10}})


def run(bench, proto, seed, noise):
    res = simulate(bench, str(proto), seed=seed, noise=noise)
    rd = RateReadings(res.data, {k: str(v) for k, v in res.metadata.items()})
    return calibrate(rd, str(proto)), res.truth["items"]


def test_noise_off_recovery_exact(small):
    """Noise off, cross-axis on: the stability is the sampled Earth-rate × cross-axis
    sinusoid (not zero), recovered to 1e-7 (the FullScale's segment means keep a 1e-8
    residue of that sinusoid); the in-band noise is zero on both sides."""
    b = study_bench()
    b = replace(b, gyro=replace(b.gyro, cross_axis_x=0.05, cross_axis_y=-0.03))
    result, tr = run(b, small, 3, False)
    it = result.items["sf_stability"]
    assert tr["sf_stability"]["value"] > 1e-7
    assert it.value == pytest.approx(tr["sf_stability"]["value"], rel=1e-7)
    for w, d in it.details["delta_by_rate"].items():
        assert d == pytest.approx(tr["sf_stability"]["by_rate"][str(float(w))], rel=1e-7)
    assert result.items["inband_noise"].value == tr["inband_noise"]["value"] == 0.0


NOISE_SEEDS = (11, 12, 13, 14)
_NOISY: dict = {}


def noisy_run(proto, seed):
    """:func:`run` on the study bench with noise, once per seed in this process."""
    if (str(proto), seed) not in _NOISY:
        _NOISY[str(proto), seed] = run(study_bench(), proto, seed, True)
    return _NOISY[str(proto), seed]


@pytest.mark.parametrize("seed", NOISE_SEEDS)
def test_noise_on_recovery_within_U(small, seed):
    """Noise on (study bench: noise, rate ripple, power-cycle scatter): the scale-factor
    stability within U; the in-band noise rms (stated by its one-sided χ² interval [0, b])
    measured, its bound above the value (its coverage over the seeds: the test below)."""
    result, tr = noisy_run(small, seed)
    it = result.items["sf_stability"]
    assert it.measured, it.reason
    assert abs(it.value - tr["sf_stability"]["value"]) <= it.uncertainty.U, (it.value, tr)
    it = result.items["inband_noise"]
    assert it.measured, it.reason
    assert it.uncertainty.interval[0] == 0.0 < it.value < it.uncertainty.interval[1]
    # the ripple is in the truth: without it the truth would be ≥ 5 % lower
    b = study_bench()
    nr = replace(b, equipment=replace(b.equipment, rate_table=replace(
        b.equipment.rate_table, ripple_rel=0.0)))
    assert truth(nr, load_protocol(str(small)))["sf_stability"]["value"] < \
        0.95 * tr["sf_stability"]["value"]


def test_noise_rms_bound_holds_the_truth_over_the_seeds(small):
    """The in-band noise rms's one-sided 95 % interval [0, b] holds the bench's truth (from its
    noise model, not the estimator) in at least 3 of the 4 seeds: with 95 % intervals, 2 or
    more misses of 4 has probability 1.4 % (binomial), so a narrower statement fails here.
    (Seed 11 misses: truth 0.04332 above b = 0.04328 °/s, 1.8 u above the value.)"""
    from scipy.stats import binom

    misses = [s for s in NOISE_SEEDS
              if noisy_run(small, s)[1]["inband_noise"]["value"]
              > noisy_run(small, s)[0].items["inband_noise"].uncertainty.interval[1]]
    assert binom.sf(1, len(NOISE_SEEDS), 0.05) < 0.02
    assert len(misses) <= 1, misses

