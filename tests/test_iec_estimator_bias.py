"""IEC 62047-20 estimator biases corrected, each against something independent of gonio's
estimator: 5.1.3.7's largest of several sample spreads (the moments of the maximum against
draws of χ² variables; the estimate against Monte Carlo records of known spreads) and
5.3.3.9's start-up time count where the transient flattens (against the closed-form truth
of the bench's transient, :mod:`gonio.specs.iec62047_20.truth`). Each checks that the
uncorrected reading fails what the corrected estimate passes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.specs.iec62047_20.formulas import max_spread_estimate, max_spread_moments
from gonio.specs.iec62047_20.items import startup_time_record
from tests._helpers import power_on_record, transient_interval_means


# --------------------------------------------------------------------------- 5.1.3.7
@pytest.mark.parametrize("spreads, dofs", [([1.0, 1.0], [299, 299]), ([1.0, 0.9], [49, 49]),
                                           ([2.0, 0.1, 1.5], [3, 5, 2])])
def test_max_spread_moments_against_chi_square_draws(spreads, dofs):
    rng = np.random.default_rng(20261201)
    d = np.array(spreads) * np.sqrt(rng.chisquare(dofs, (200_000, len(spreads))) / dofs)
    m = d.max(axis=1)
    e, sd = max_spread_moments(spreads, dofs)
    se = m.std() / math.sqrt(m.size)
    assert abs(e - m.mean()) < 4 * se, (e, m.mean())
    assert sd == pytest.approx(m.std(), rel=0.01)


def _spread_records(rng, sigmas, n, trials):
    """Population spreads of ``n`` white samples at each true σ (the truth √E[pop var] =
    σ√((n − 1)/n)), ``trials`` times."""
    return [[float(np.std(s * rng.standard_normal(n))) for s in sigmas] for _ in range(trials)]


@pytest.mark.parametrize("sigmas, n", [((1.0, 1.0), 300), ((1.0, 1.0, 1.0), 50)])
def test_sf_stability_bias_of_the_maximum_removed(sigmas, n):
    """Equal true spreads (the built-in programme's ±150 °/s): the reading max δ_i reads
    high by the selection excess (≈ σ/√(2νπ) for two: +2.2 % at ν 299); the estimate removes
    at least 40 % of it (half by construction, the midpoint of its range) and the interval
    covers; the reading's own χ² interval, no correction, covers less."""
    from scipy import stats

    rng = np.random.default_rng(7 + n)
    truth = max(sigmas) * math.sqrt((n - 1) / n)
    raw, est, cov, cov_raw = [], [], [], []
    for d in _spread_records(rng, sigmas, n, 600):
        r = max_spread_estimate(d, [n - 1] * len(d))
        raw.append(r["reading"] / truth - 1)
        est.append(r["value"] / truth - 1)
        cov.append(r["interval"][0] <= truth <= r["interval"][1])
        top = max(d)
        cov_raw.append(top * math.sqrt((n - 1) / stats.chi2.ppf(0.975, n - 1)) <= truth
                       <= top * math.sqrt((n - 1) / stats.chi2.ppf(0.025, n - 1)))
    raw, est = np.array(raw), np.array(est)
    se = est.std() / math.sqrt(est.size)
    assert raw.mean() > 10 * se                                    # the reading reads high
    assert est.mean() < 0.6 * raw.mean(), (est.mean(), raw.mean())  # mostly removed
    assert np.mean(cov) >= 0.95
    assert np.mean(cov_raw) < np.mean(cov)


@pytest.mark.parametrize("sigmas, n", [((1.0, 0.8), 50), ((1.0, 0.95), 300)])
def test_sf_stability_interval_covers_where_the_spreads_differ(sigmas, n):
    """Where one spread stands (partly) clear, the correction must not push the estimate out
    of its interval: coverage ≥ 94 % on 600 records (a pivot about the corrected value with
    the maximum's distribution at the measured spreads covered 0.89 at (1, 0.8), ν 49)."""
    rng = np.random.default_rng(11 + n)
    truth = max(sigmas) * math.sqrt((n - 1) / n)
    cov = [lo <= truth <= hi for lo, hi in
           (max_spread_estimate(d, [n - 1] * len(d))["interval"]
            for d in _spread_records(rng, sigmas, n, 600))]
    assert np.mean(cov) >= 0.94, np.mean(cov)


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    """One calibration of the study programme on the study bench with its power-on
    transient (as ``gonio validate --spec iec62047-20``)."""
    from gonio.formats.rate_readings import RateReadings
    from gonio.pipeline.coverage import reduced_protocol
    from gonio.specs._rate_family.simulate import study_bench
    from gonio.specs.iec62047_20 import calibrate
    from gonio.specs.iec62047_20.simulate import simulate

    proto = reduced_protocol("iec62047-20", tmp_path_factory.mktemp("iecbias") / "p.toml")
    res = simulate(study_bench(power_on_transient=True), str(proto), seed=5)
    rd = RateReadings(res.data, {k: str(v) for k, v in res.metadata.items()})
    return calibrate(rd, str(proto))


def test_sf_stability_item_states_the_corrected_value_and_keeps_the_reading(calibrated):
    it = calibrated.items["sf_stability"]
    det = it.details
    assert det["reading_max_delta"] == max(det["delta_by_rate"].values())
    assert it.value == pytest.approx(det["reading_max_delta"] - det["max_bias"], rel=1e-12)
    assert det["max_bias"] > 0                      # two contending rates: an excess removed
    lo, hi = it.uncertainty.interval
    assert it.uncertainty.k is None and lo <= it.value <= hi
    assert it.uncertainty.U == pytest.approx(hi - it.value)


# --------------------------------------------------------------------------- 5.3.3.9
A_DPS, TAU_S, BAND_DPS, P, N = 0.12, 150.0, 0.05, 10, 1800      # the bench and the programme


def _closed_form_truth() -> float:
    """5.3.3.9's truth of the mems-adxrs610 bench on the built-in programme, from
    :mod:`gonio.specs.iec62047_20.truth` (the clause's rule on the exact interval means of
    A·e^(−t/τ))."""
    from gonio.bench.rate_gyro import load_rate_bench
    from gonio.specs.iec62047_20.protocol import load_protocol
    from gonio.specs.iec62047_20.truth import _power_on_truths

    g = load_rate_bench("mems-adxrs610").gyro
    assert (g.warmup_bias_dps, g.warmup_tau_s) == (A_DPS, TAU_S)
    proto = load_protocol("iec62047-20")
    po = proto["power_on"]
    assert (po["startup_band_dps"], po["smoothing_samples"], po["samples"]) == (BAND_DPS, P, N)
    return _power_on_truths(g, proto, 1.0)["startup_time"]["value"]


def _white_records(rng, n_rec, sigma):
    t = np.arange(N, dtype=float)
    tr = transient_interval_means(A_DPS, TAU_S, t)
    for _ in range(n_rec):
        yield power_on_record(t, tr + sigma * rng.standard_normal(N), P)


def test_startup_count_reads_late_where_the_transient_flattens():
    """On the bench's transient under white noise of 0.05 °/s per sample (σ_b 0.0158 °/s of
    a 10-s mean), 1000 records: the count reads late by the curvature term, τσ_b²/(2b²) =
    7.5 s, plus the smoothing grid's +1.3 s (the count averages the crossing at 131.3 s, the
    clause's blocks end at 130 s; within the budget's ± P/2); the corrected count is within
    the grid's offset and 3 standard errors of the closed-form truth, the count is not. (The
    correction, 9.8 s on average here, reads 1/s as the secant between band ± h, 1.18× the
    local τ/b for h = 2σ_b, and includes the reference's noise.)"""
    truth = _closed_form_truth()
    assert truth == 130.0
    rng = np.random.default_rng(20261201)
    raw, cor, bias = [], [], []
    for tt, ys, y in _white_records(rng, 1000, 0.05):
        r = startup_time_record(tt, ys, y, BAND_DPS, lambda a, b: 0.0)
        raw.append(r["count_s"] - truth)
        cor.append(r["corrected_s"] - truth)
        bias.append(r["curvature_bias_s"])
    raw, cor = np.array(raw), np.array(cor)
    se = raw.std(ddof=1) / math.sqrt(raw.size)
    grid = TAU_S * math.log(A_DPS / BAND_DPS) - truth             # +1.3 s
    assert raw.mean() - grid > 6 * se, (raw.mean(), se)         # the count: late
    assert abs(cor.mean() - grid) < 3 * se + 1.0, (cor.mean(), se)
    sigma_b = 0.05 / math.sqrt(P)               # the closed form at the local slope τ/b: 7.5 s
    assert 0.8 < np.mean(bias) / (TAU_S * sigma_b ** 2 / (2 * BAND_DPS ** 2)) < 1.5


def test_startup_correction_on_the_bench_noise():
    """The bench's own generator (white noise, the bias instability's Gauss–Markov sum, the
    rate random walk), drift terms from the generator's K² and B², 400 records: the count
    reads late (+11 s on this seed), the corrected value is centred on the closed-form
    truth within the grid offset and 2.5 standard errors."""
    from gonio.specs._rate_family import formulas as rg
    from tests.test_iec_startup_tc_ratio import _bench_noise_records

    truth = _closed_form_truth()
    recs, (k2, b2) = _bench_noise_records(np.random.default_rng(12), 400, 1.0)
    raw, cor = [], []
    for tt, ys, y in recs:
        r = startup_time_record(tt, ys, y, BAND_DPS,
                                lambda a, b: rg.record_difference_u_coef(k2, b2, a, b))
        raw.append(r["count_s"] - truth)
        cor.append(r["corrected_s"] - truth)
    raw, cor = np.array(raw), np.array(cor)
    se = raw.std(ddof=1) / math.sqrt(raw.size)
    grid = TAU_S * math.log(A_DPS / BAND_DPS) - truth
    assert raw.mean() - grid > 2.5 * se, (raw.mean(), se)
    assert abs(cor.mean() - grid) < 2.5 * se, (cor.mean(), se)


def test_startup_item_value_is_the_corrected_count(calibrated):
    it = calibrated.items["startup_time"]
    det = it.details
    assert np.allclose(det["per_record_s"], det["count_s"] - det["curvature_bias_s"])
    assert it.value == pytest.approx(float(np.mean(det["per_record_s"])))
    assert np.all(det["curvature_bias_s"] > 0)
    rows = {c["symbol"]: c for c in it.uncertainty.components}
    assert rows["curvature"]["u"] == pytest.approx(np.mean(det["curvature_bias_s"]) / math.sqrt(3))


@pytest.mark.parametrize("sigmas, dofs", [((1.0, 2.0), (299, 4)), ((1.0, 1.5), (299, 9)),
                                          ((1.0, 1.0), (4, 299)), ((1.0, 1.0), (299, 299))])
def test_sf_stability_interval_covers_with_unequal_record_lengths(sigmas, dofs):
    """The measurand is max σ_i: the interval's upper end is the largest of the records' own
    χ² upper bounds, each at its own ν (the top record's bound alone covered 0.876 at σ
    (1, 2), ν (299, 4)). 1000 draws of the scaled χ per case: each side misses at most
    2.5 % plus 3 binomial standard errors; for equal ν the width is within 1.3 × that of
    one record's exact χ² interval at that ν (not absurdly wide)."""
    from scipy import stats

    rng = np.random.default_rng(20261201)
    s, nu = np.array(sigmas), np.array(dofs, dtype=float)
    truth = float(s.max())
    below = above = 0
    width = []
    n = 1000
    for _ in range(n):
        d = s * np.sqrt(rng.chisquare(nu) / nu)
        lo, hi = max_spread_estimate(d, nu)["interval"]
        below += truth < lo
        above += truth > hi
        width.append(hi - lo)
    tol = 0.025 + 3 * math.sqrt(0.025 * 0.975 / n)
    assert below / n <= tol and above / n <= tol, (below, above)
    assert (below + above) / n <= 0.05 + 3 * math.sqrt(0.05 * 0.95 / n)
    if dofs[0] == dofs[1]:
        v = dofs[0]
        one = truth * (math.sqrt(v / stats.chi2.ppf(0.025, v))
                       - math.sqrt(v / stats.chi2.ppf(0.975, v)))
        assert np.mean(width) < 1.3 * one, (np.mean(width), one)


def test_max_spread_bounds_upper_end_is_every_records_own_bound():
    """Against the χ² quantiles directly: the upper end is the largest of each record's own
    upper bound at its ν, so a short record below the top still sets it."""
    from scipy import stats

    from gonio.specs.iec62047_20.formulas import max_spread_bounds

    d, nu = [1.0, 0.9], [299, 4]
    own = [x * math.sqrt(v / stats.chi2.ppf(0.025, v)) for x, v in zip(d, nu)]
    assert own[1] > own[0]
    assert max_spread_bounds(d, nu)[1] == pytest.approx(max(own), rel=1e-12)
    assert max_spread_estimate(d, nu)["interval"][1] == pytest.approx(max(own), rel=1e-12)


@pytest.mark.parametrize("seed, amp", [(0, 0.045), (5, 0.045)])
def test_startup_record_that_never_leaves_the_band_is_zero_not_negative(seed, amp):
    """A record whose smoothed values never leave the band (count 0 s) has no crossing: no
    curvature correction, the start-up time 0 s (a reviewer's records gave −2.22 s)."""
    rng = np.random.default_rng(seed)
    tt = np.arange(0, 3000, 10.0)
    ys = amp * np.exp(-tt / 150) + rng.normal(0, 0.0095, tt.size)
    r = startup_time_record(tt, ys, ys, 0.05, lambda a, b: 0.011)
    assert r["count_s"] == 0.0
    assert r["curvature_bias_s"] == 0.0 and r["corrected_s"] == 0.0


def test_startup_correction_never_below_zero():
    """Where a crossing exists the correction applies (t''·var/2 at ρ = 1, τ·var/(2 b²) on
    an exponential), but a corrected time is never negative."""
    from gonio.specs.iec62047_20.items import startup_curvature_corrected_s

    var = 0.0095 ** 2 + 0.011 ** 2
    b, c = startup_curvature_corrected_s(130.0, TAU_S / BAND_DPS, BAND_DPS, var)
    assert b == pytest.approx(TAU_S * var / (2 * BAND_DPS ** 2)) and c == pytest.approx(130 - b)
    assert startup_curvature_corrected_s(2.0, TAU_S / BAND_DPS, BAND_DPS, var) == (2.0, 0.0)


@pytest.mark.parametrize("lang", ["en", "zh"])
def test_certificate_prints_the_standards_reading_beside_the_corrected_estimate(calibrated, lang):
    """5.1.3.7 and 5.3.3.9 certify corrected estimates; the standard's own readings (max δ_i,
    the mean last-exceedance time without the correction) are printed beside them, labelled
    the standard's and not certified, as the Result words them (en and zh), and are the
    details' numbers (computed here from the per-rate spreads and per-record times)."""
    from gonio.report.i18n import labels
    from gonio.report.rate_certificate import rate_certificate_blocks

    res = calibrated.to_json()
    sf, st = (res["items"][k]["details"] for k in ("sf_stability", "startup_time"))
    assert sf["standard_reading"]["value"] == max(sf["delta_by_rate"].values())
    assert st["standard_reading"]["value"] == pytest.approx(float(np.mean(st["last_exceedance_s"])))
    assert st["standard_reading"]["value"] != pytest.approx(res["items"]["startup_time"]["value"])
    blocks = rate_certificate_blocks(calibrated, labels(lang), lang, lab=None)["blocks"]
    text = " ".join(str(b.data) for b in blocks)
    mark = "仅并列给出，不作校准结果" if lang == "zh" else "given beside, not certified"
    more = [(res["items"][k]["details"], c, v) for k, c, v in
            (("bias_instability", "5.4.5.3", "floor_reading_dph"),
             ("bias_hysteresis", "5.3.3.7", "reading_iec_dps"))
            if res["items"].get(k, {}).get("measured")]
    for d, _, v in more:
        assert d["standard_reading"]["value"] == d[v]
    for d, clause in [(sf, "5.1.3.7"), (st, "5.3.3.9")] + [m[:2] for m in more]:
        line = d["standard_reading"]["text_" + lang]
        assert line in text and mark in line and line.startswith(clause)
        assert d["standard_reading"]["stated"] in line
        assert ("标准的读数" if lang == "zh" else "the standard's reading") in line
