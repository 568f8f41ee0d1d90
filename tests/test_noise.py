"""Tests of gonio.analysis.noise and `gonio noise`, each against something independent:
allantools (peer library, test-only), closed-form Allan variances of simulated
noise, χ² coverage, and a second algorithm (direct sums vs the FFT expansion)."""

from __future__ import annotations

import json
import math

import allantools
import allantools.ci
import numpy as np
import pytest

from gonio import units
from gonio.analysis import noise
from gonio.cli import main
from gonio.errors import GonioError


def _white_plus_rrw(rng, n, white=1.0, rrw=0.01):
    return white * rng.standard_normal(n) + rrw * np.cumsum(rng.standard_normal(n))


# ------------------------------------------------------------------ vs allantools
@pytest.mark.parametrize("n", [1000, 100_000, 1_000_000])
@pytest.mark.parametrize("modified", [False, True])
def test_rate_input_matches_allantools(n, modified):
    rng = np.random.default_rng(n)
    y = 100.0 + _white_plus_rrw(rng, n)  # large mean rate: precision check
    tau0 = 0.01
    r = noise.allan_deviation(y, tau0, "rate", "octave", modified=modified)
    fn = allantools.mdev if modified else allantools.oadev
    t, dev, _, _ = fn(y, rate=1 / tau0, data_type="freq", taus=r.tau_s)
    np.testing.assert_allclose(t, r.tau_s, rtol=1e-12)
    np.testing.assert_allclose(r.adev, dev, rtol=1e-9)


@pytest.mark.parametrize("modified", [False, True])
def test_increment_input_matches_allantools(modified):
    rng = np.random.default_rng(7)
    scale = 3600.0  # counts per degree
    counts = np.round(500.0 + 40.0 * rng.standard_normal(100_000)
                      + np.cumsum(0.3 * rng.standard_normal(100_000)))
    tau0 = 0.001
    r = noise.allan_deviation(counts, tau0, "increment", "decade:5", scale=scale,
                              modified=modified)
    fn = allantools.mdev if modified else allantools.oadev
    # allantools: fractional "frequency" = rate in °/s
    _, dev, _, _ = fn(counts / scale / tau0, rate=1 / tau0, data_type="freq", taus=r.tau_s)
    np.testing.assert_allclose(r.adev, dev, rtol=1e-9)


@pytest.mark.parametrize("modified", [False, True])
def test_angle_input_matches_allantools(modified):
    rng = np.random.default_rng(8)
    scale = 3600.0
    inc = 500.0 + 40.0 * rng.standard_normal(200_000) + np.cumsum(0.3 * rng.standard_normal(200_000))
    counts = np.cumsum(np.round(inc))  # cumulative counter: an angle
    tau0 = 0.001
    r = noise.allan_deviation(counts, tau0, "angle", "octave", scale=scale, modified=modified)
    fn = allantools.mdev if modified else allantools.oadev
    _, dev, _, _ = fn(counts / scale, rate=1 / tau0, data_type="phase", taus=r.tau_s)
    np.testing.assert_allclose(r.adev, dev, rtol=1e-9)


def test_all_taus_matches_allantools():
    rng = np.random.default_rng(11)
    y = _white_plus_rrw(rng, 3000)
    r = noise.allan_deviation(y, 1.0, "rate", "all", rtol_all=1e-12)
    assert r.m.tolist() == list(range(1, 1501))
    t, dev, _, _ = allantools.oadev(y, rate=1.0, data_type="freq", taus=r.tau_s)
    # allantools drops the last m, which has a single second difference
    assert r.n_pairs[-1] == 1 and t.size == 1499
    np.testing.assert_allclose(r.adev[:-1], dev, rtol=1e-9)


@pytest.mark.parametrize("kind", ["white", "rrw"])
def test_all_taus_fft_path_matches_direct_sums(kind):
    """The O(N log² N) expansion against the direct O(N)-per-m definition."""
    rng = np.random.default_rng(3)
    n = 200_000
    y = rng.standard_normal(n) if kind == "white" else _white_plus_rrw(rng, n, 1.0, 0.05)
    r = noise.allan_deviation(y, 1.0, "rate", "all")  # default rtol_all = 1e-6
    pick = np.unique(np.r_[1, 2, 3, 50, 777, rng.integers(1, r.m[-1], 40), r.m[-5:]])
    direct = noise.allan_deviation(y, 1.0, "rate", pick)
    np.testing.assert_allclose(r.adev[pick - 1], direct.adev, rtol=1e-6)


def test_edf_matches_allantools_simple():
    for alpha in (2, 1, 0, -2):
        for m in (1, 3, 10, 100):
            ref = allantools.ci.edf_simple(10_000, m, alpha)
            assert noise.edf_simple(10_000, m, alpha) == pytest.approx(ref, rel=1e-12)
    # flicker rate, m >= 2 (SP 1065 Table 5; allantools' m = 1 branch differs)
    assert noise.edf_simple(10_000, 8, -1) == pytest.approx(
        allantools.ci.edf_simple(10_000, 8, -1), rel=1e-12)


# ------------------------------------------------------------------ closed forms
def test_white_rate_noise_matches_n_over_sqrt_tau_within_ci():
    rng = np.random.default_rng(21)
    tau0, n_arw = 0.01, 0.2  # rate sd = N/sqrt(tau0)
    y = n_arw / math.sqrt(tau0) * rng.standard_normal(400_000)
    r = noise.allan_deviation(y, tau0, "rate", "octave", confidence=0.997, alpha=0)
    truth = n_arw / np.sqrt(r.tau_s)
    assert np.all((r.ci_low <= truth) & (truth <= r.ci_high))


def test_rate_random_walk_matches_k_sqrt_tau_over_3_within_ci():
    rng = np.random.default_rng(22)
    tau0, k = 0.1, 0.05
    y = k * math.sqrt(tau0) * np.cumsum(rng.standard_normal(400_000))
    r = noise.allan_deviation(y, tau0, "rate", "octave", confidence=0.997, alpha=-2)
    m = r.m
    keep = r.tau_s <= 0.1 * y.size * tau0
    # exact for a discrete random walk: q (2m²+1)/(6m); → K² τ/3 for m ≫ 1
    truth = np.sqrt(k ** 2 * tau0 * (2 * m ** 2 + 1) / (6 * m))
    inside = (r.ci_low <= truth) & (truth <= r.ci_high)
    assert np.all(inside[keep])
    big = m >= 64
    np.testing.assert_allclose(truth[big], k * np.sqrt(r.tau_s[big] / 3), rtol=1e-3)


def test_confidence_interval_coverage_white_noise():
    rng = np.random.default_rng(5)
    hits = np.zeros(3)
    trials = 400
    for _ in range(trials):
        y = rng.standard_normal(1000)
        r = noise.allan_deviation(y, 1.0, "rate", [1, 4, 16], confidence=0.683, alpha=0)
        truth = 1 / np.sqrt(r.m)
        hits += (r.ci_low <= truth) & (truth <= r.ci_high)
    cover = hits / trials
    assert np.all(np.abs(cover - 0.683) < 0.08), cover


# ------------------------------------------------------------------------- fit
@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_fit_recovers_n_and_k(seed):
    rng = np.random.default_rng(seed)
    tau0, n_true, k_true = 0.01, 0.1, 0.02
    n = 500_000
    y = (n_true / math.sqrt(tau0) * rng.standard_normal(n)
         + k_true * math.sqrt(tau0) * np.cumsum(rng.standard_normal(n)))
    r = noise.allan_deviation(y, tau0, "rate", "octave", unit="deg/h")
    f = noise.fit_noise_model(r, tau_max_s=0.1 * n * tau0)
    assert abs(f.N - n_true) < 3 * f.u_N + 1e-12, (f.N, f.u_N)
    assert abs(f.K - k_true) < 3 * f.u_K + 1e-12, (f.K, f.u_K)
    assert 0 < f.u_N < 0.1 * n_true and 0 < f.u_K < 0.5 * k_true


def _flicker(rng, n, tau0, h):
    """Rate noise with one-sided PSD h/f (FFT synthesis)."""
    f = np.fft.rfftfreq(n, tau0)
    spec = rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)
    spec[0] = 0
    spec[1:] *= np.sqrt(h / f[1:] * n / (4 * tau0))
    return np.fft.irfft(spec, n)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_fit_recovers_bias_instability_of_flicker_noise(seed):
    rng = np.random.default_rng(seed)
    tau0, h, n_true = 1.0, 1e-2, 0.05
    n = 1 << 19
    y = _flicker(rng, n, tau0, h) + n_true / math.sqrt(tau0) * rng.standard_normal(n)
    r = noise.allan_deviation(y, tau0, "rate", "octave")
    # the FFT-synthesised flicker is 1/f only well below the record length
    f = noise.fit_noise_model(r, terms=("N", "B"), tau_max_s=n * tau0 / 256)
    # flicker FM: AVAR = 2 ln2 · h (SP 1065 Table) = (2 ln2/π) B²  =>  B = sqrt(π h)
    b_true = math.sqrt(math.pi * h)
    assert abs(f.B - b_true) < max(3 * f.u_B, 0.1 * b_true), (f.B, f.u_B, b_true)
    assert f.B_floor == pytest.approx(b_true, rel=0.25)


# -------------------------------------------------------------------- sinusoid
@pytest.mark.parametrize("seed", [1, 2])
def test_sinusoid_detected_with_period_and_amplitude(seed):
    rng = np.random.default_rng(seed)
    tau0, period, amp, n = 0.1, 100.0, 0.1, 100_000
    t = np.arange(n) * tau0
    phase0 = rng.uniform(0, 2 * math.pi)
    # cluster means of a sampled sinusoid ≈ the sinusoid when T ≫ τ0
    y = amp * np.sin(2 * math.pi * t / period + phase0) + 0.1 / math.sqrt(tau0) * rng.standard_normal(n)
    r = noise.allan_deviation(y, tau0, "rate", "decade:20")
    f = noise.fit_noise_model(r, tau_max_s=n * tau0 / 10)
    d = noise.detect_sinusoid(r, f)
    assert d.detected
    assert d.period_s == pytest.approx(period, rel=0.1)
    assert d.amplitude == pytest.approx(amp, rel=0.2)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_no_sinusoid_in_white_plus_rrw(seed):
    rng = np.random.default_rng(seed)
    y = _white_plus_rrw(rng, 100_000, 1.0, 0.002)
    r = noise.allan_deviation(y, 0.1, "rate", "decade:20")
    assert not noise.detect_sinusoid(r, noise.fit_noise_model(r)).detected


# --------------------------------------------------------------- static record
def test_analyse_static_recovers_arw_in_customary_units():
    rng = np.random.default_rng(9)
    tau0, arw_deg_sqrt_h = 0.05, 0.003
    n_dph_sqrt_s = arw_deg_sqrt_h * 60.0
    t = np.arange(200_000) * tau0
    rate_dph = n_dph_sqrt_s / math.sqrt(tau0) * rng.standard_normal(t.size)
    angle_deg = np.cumsum(rate_dph) * tau0 / 3600.0
    res = noise.analyse_static(t, angle_deg)
    d = res.fit.to_dict()
    assert d["arw_deg_sqrt_h"] == pytest.approx(arw_deg_sqrt_h, rel=0.05)
    assert res.allan.unit == "deg/h" and res.duration_s == pytest.approx(t[-1])
    frame = res.allan.to_frame()
    assert list(frame.columns[:3]) == ["tau_s", "m", "adev"]
    json.dumps(res.to_dict())  # plain data
    with pytest.raises(GonioError, match="not uniform"):
        noise.analyse_static(np.r_[t[:10], t[10:20] + 0.3 * tau0], angle_deg[:20])


def test_unit_conversions_round_trip_and_first_principles():
    x = 0.0123
    assert units.deg_sqrt_h_from_dph_sqrt_hz(units.dph_sqrt_hz_from_deg_sqrt_h(x)) == pytest.approx(x)
    # 1 °/√h expressed from first principles: (π/180 rad) / sqrt(3600 s)
    assert units.rad_s_sqrt_hz_from_deg_sqrt_h(1.0) == pytest.approx(math.radians(1) / 60.0)
    assert units.arcsec_sqrt_s_from_deg_sqrt_h(1.0) == pytest.approx(3600.0 / math.sqrt(3600.0))
    assert units.dph_from_rad_s(units.rad_s_from_dph(x)) == pytest.approx(x)


# ------------------------------------------------------------------ validation
@pytest.mark.parametrize("kwargs, match", [
    ({"input_type": "freq"}, "input type"),
    ({"input_type": "phase"}, "input type"),
    ({"input_type": "rate", "tau0_s": 0.0}, "tau0_s"),
    ({"input_type": "rate", "taus": "decade"}, "τ set"),
    ({"input_type": "rate", "taus": "decade:x"}, "decade:N"),
    ({"input_type": "rate", "taus": [0, 1]}, "averaging factors"),
    ({"input_type": "increment", "scale": 0.0}, "scale"),
])
def test_argument_validation_raises_gonio_error(kwargs, match):
    args = {"data": np.arange(100.0), "tau0_s": 1.0, "input_type": "rate"} | kwargs
    with pytest.raises(GonioError, match=match):
        noise.allan_deviation(**args)


def test_infinite_data_rejected():
    with pytest.raises(GonioError, match="index 3"):
        noise.allan_deviation([1.0, 2.0, 3.0, -np.inf, 1.0], 1.0, "rate")


def test_tau_sets():
    assert noise.averaging_factors(1025, "octave").tolist() == [1, 2, 4, 8, 16, 32, 64, 128, 256, 512]
    dec = noise.averaging_factors(10_001, "decade:10")
    assert np.all(np.diff(dec) > 0) and dec[0] == 1 and dec[-1] <= 5000
    ratio = np.diff(np.log10(dec[dec >= 10]))
    assert np.all(ratio < 0.2)
    assert noise.averaging_factors(11, "all").tolist() == [1, 2, 3, 4, 5]


# ------------------------------------------------------------------------ CLI
def _write_stream(path, counts, tau0=0.1, scale="3600000", extra=""):
    lines = [f"# nominal_scale_factor_counts_per_deg: {scale}"] if scale else []
    lines.append("time_s,gyro_counts")
    lines += [f"{i * tau0:.3f},{c}" for i, c in enumerate(counts)]
    path.write_text("\n".join(lines) + "\n" + extra)
    return path


def test_cli_noise_json_plot_and_input_kinds(tmp_path, capsys):
    rng = np.random.default_rng(4)
    n, tau0, scale = 3000, 0.1, 3.6e6
    rate_dph = 0.2 / math.sqrt(tau0) * rng.standard_normal(n)
    inc = np.round(rate_dph * tau0 / 3600.0 * scale).astype(np.int64)
    angle_file = _write_stream(tmp_path / "a.csv", np.cumsum(inc))
    plot = tmp_path / "adev.png"
    assert main(["noise", str(angle_file), "--json", "--plot", str(plot)]) == 0
    out = json.loads(capsys.readouterr().out)
    ref = noise.allan_deviation(np.cumsum(inc) / scale * 3600.0, tau0, "angle", "octave")
    np.testing.assert_allclose(out["allan"]["adev"], ref.adev, rtol=1e-9)
    assert out["fit"]["arw_deg_sqrt_h"] == pytest.approx(0.2 / 60, rel=0.1)
    assert plot.stat().st_size > 1000
    # the same record as per-sample increments (n-1 of them) and as a rate in counts/s
    inc_file = _write_stream(tmp_path / "i.csv", np.diff(np.cumsum(inc)))
    assert main(["noise", str(inc_file), "--input", "counts", "--json"]) == 0
    out_inc = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(out_inc["allan"]["adev"][:8], ref.adev[:8], rtol=1e-9)
    rate_file = _write_stream(tmp_path / "r.csv", np.diff(np.cumsum(inc)) * 10)  # counts/s
    assert main(["noise", str(rate_file), "--input", "rate", "--json"]) == 0
    out_rate = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(out_rate["allan"]["adev"][:8], ref.adev[:8], rtol=1e-9)
    assert main(["noise", str(angle_file), "--taus", "decade:5"]) == 0
    assert "angle random walk" in capsys.readouterr().out


def test_cli_noise_bad_files_exit_2(tmp_path, capsys):
    bad = _write_stream(tmp_path / "bad.csv", [0, 1, 2, 3, 4, 5, 6, 7, 8, 9], extra="1.000,abc\n")
    assert main(["noise", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.csv" in err and err.count("\n") == 1
    no_scale = _write_stream(tmp_path / "ns.csv", list(range(20)), scale="")
    assert main(["noise", str(no_scale)]) == 2
    assert "nominal_scale_factor_counts_per_deg" in capsys.readouterr().err
    assert main(["noise", str(no_scale), "--scale-factor", "100", "--taus", "weekly"]) == 2
