"""Draft 7.3 with its Allan analysis: on the bench, the noise parameters are recovered."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.bench.instrument import uniform_hash
from gonio.specs.ogam_draft.calibration import (ZERO_STABILITY_NOISE_SAMPLES,
                                               analyse_zero_stability, calibrate)
from gonio.specs.ogam_draft.protocol import parse_protocol

ZS = parse_protocol({"protocol": {"name": "zs"},
                     "zero_stability": {"readings": 15, "interval_s": 300.0}})


def test_dither_hash_is_white_and_uniform():
    u = uniform_hash(np.arange(200_000), key=12345)
    assert abs(u.mean() - 0.5) < 0.005 and abs(u.var() - 1 / 12) < 0.002
    assert abs(np.corrcoef(u[:-1], u[1:])[0, 1]) < 0.01           # white
    assert not np.array_equal(u[:100], uniform_hash(np.arange(100), key=12346))


@pytest.mark.parametrize("seed", range(5))
def test_arw_and_quantisation_recovered_within_uncertainty(seed):
    bench = load_bench("rlg")
    bench = replace(bench, sample_rate_hz=100.0,
                    instrument=replace(bench.instrument, bias_instability_dph=0.0,
                                       warmup_drift_dph=0.0))
    res = run_session(ZS, bench, seed=seed)
    noise, src = analyse_zero_stability(res.static_record)
    # the 70-min rest at 100 Hz holds more than ZERO_STABILITY_NOISE_SAMPLES: every 2nd
    # angle of the cumulative counter is analysed (an exact record at 2·τ0)
    n = res.static_record.time_s.size
    d = -(-n // ZERO_STABILITY_NOISE_SAMPLES)
    assert d == 2 and src == "virtual bench, 7.3 block; one sample in 2 analysed (at most 262144)"
    assert noise.tau0_s == pytest.approx(2 * float(np.diff(res.static_record.time_s).mean()))
    fit = noise.fit
    # ARW N (°/√h) ↔ white rate (°/h)·√s: ×60.
    n_true = bench.instrument.arw_dpsh * 60.0
    assert abs(fit.N - n_true) < 3.0 * fit.u_N + 1e-12, (fit.N, fit.u_N, n_true)
    # Dithered quantisation floor(Kφ + u): error variance q²/6 per reading (closed form),
    # q = 1/K degrees = 3600/K arcsec; the Q term is in (°/h)·s = arcsec.
    q_true = 3600.0 / bench.instrument.true_scale_factor_counts_per_deg / math.sqrt(6.0)
    assert abs(fit.Q - q_true) < 3.0 * fit.u_Q + 1e-4 * q_true, (fit.Q, fit.u_Q, q_true)
    assert not noise.sinusoid.detected


def test_readings_file_alone_says_why_there_is_no_allan(tmp_path):
    bench = replace(load_bench("rlg"), sample_rate_hz=50.0)
    from gonio.specs.ogam_draft.bench import write_session

    write_session(run_session(ZS, bench, seed=0), tmp_path)
    d = calibrate(tmp_path / "readings.csv", ZS).to_json()["items"]["zero_stability"]["details"]
    assert d["noise"] is None and "stream" in d["noise_reason"]
