"""Long static records in bounded pieces (issue 26): the ARW / noise items of JJF 1535 and
IEC 62047-20 and the triad's averaging-time step read a long record as a
:class:`gonio.analysis.noise.stream.Record` and its Allan phase as a
:class:`~gonio.analysis.noise.stream.CumulativeSum`, never a record-long array.

Checked: the pieces give the numbers of the whole arrays (the cumulative sum bit for bit;
the deviations, identified noise types and every item's value and details to 1e-12 of the
array path, the code used below the streaming threshold), the overlapping ADEV against
allantools, and the memory does not grow with the record."""

from __future__ import annotations

import json
import math
import tracemalloc

import allantools
import numpy as np
import pandas as pd
import pytest

from gonio.analysis.noise import allan_deviation, stream
from gonio.specs.triad_alignment.bench import TriadBench, TriadProtocol, ThermalModel, run_alignment_session
from gonio.specs.triad_alignment.readings import format_triad_readings, parse_triad_readings
from gonio.specs.iec62047_20 import items as I
from gonio.specs.iec62047_20.protocol import load_protocol as load_iec
from gonio.specs.jjf1535 import items as J
from gonio.specs.jjf1535.protocol import load_protocol as load_jjf
from gonio.specs.triad_alignment.analysis import estimate_alignment


def record_of(y: np.ndarray) -> stream.Record:
    return stream.Record(y.size, lambda a, b: y[a:b].copy())


def noisy(n: int, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return 3.0 + 0.5 * rng.standard_normal(n) + 1e-3 * np.cumsum(rng.standard_normal(n))


@pytest.mark.parametrize("block", [1, 7, 64, 1000])
def test_cumulative_sum_slices_are_the_whole_arrays(block):
    y = noisy(10_001)
    c = np.empty(y.size + 1)
    c[0] = 0.0
    np.subtract(y, 2.5, out=c[1:])
    np.cumsum(c, out=c)
    cs = stream.CumulativeSum(record_of(y), 2.5, block=block, cache_blocks=2)
    assert cs.size == c.size
    for a, b, step in [(0, None, 1), (5, 9000, 1), (999, 1003, 1), (3, None, 7),
                       (17, 9999, 1000), (0, 10_002, 65536), (10_000, 10_002, 1)]:
        assert np.array_equal(cs[a:b:step], c[a:b:step]), (a, b, step)
    ranges = [(0, 10_002, 3), (17, 5000, 100), (9000, 9001, 1)]
    for got, (a, b, m) in zip(cs.decimations(ranges), ranges):
        assert np.array_equal(got, c[a:b:m])


def test_record_helpers_are_the_array_forms(monkeypatch):
    monkeypatch.setattr(stream, "PIECE", 100)
    y = noisy(1234)
    r = record_of(y)
    assert np.array_equal(r[3:1200:7], y[3:1200:7])
    assert r.mean() == pytest.approx(y.mean(), rel=1e-14)
    assert stream.value_range(r) == np.ptp(y)
    assert np.array_equal(r.block_means(30), y[:1230].reshape(41, 30).mean(axis=1))
    assert np.array_equal((r / 7.0)[0:1234], y / 7.0)
    assert r.all_finite() and not record_of(np.array([1.0, np.nan, 2.0])).all_finite()


@pytest.mark.parametrize("kind", ["adev", "hdev", "mdev"])
@pytest.mark.parametrize("taus", ["decade:10", "octave"])
def test_streamed_deviation_equals_the_array_path(monkeypatch, kind, taus):
    monkeypatch.setattr(stream, "PIECE", 997)
    y = noisy(150_001)
    r0 = allan_deviation(y, 0.1, "rate", taus, kind=kind)
    r1 = allan_deviation(record_of(y), 0.1, "rate", taus, kind=kind)
    np.testing.assert_allclose(r1.adev, r0.adev, rtol=1e-12, atol=0)
    assert np.array_equal(r1.alpha, r0.alpha) and np.array_equal(r1.edf, r0.edf)
    assert np.array_equal(np.isnan(r1.alpha_b1), np.isnan(r0.alpha_b1))
    assert np.array_equal(r1.alpha_b1[~np.isnan(r0.alpha_b1)], r0.alpha_b1[~np.isnan(r0.alpha_b1)])
    np.testing.assert_allclose(r1.ci_high, r0.ci_high, rtol=1e-12, atol=0)


def test_streamed_deviation_against_allantools(monkeypatch):
    monkeypatch.setattr(stream, "PIECE", 4096)
    y = noisy(60_000, seed=9)
    r = allan_deviation(record_of(y), 0.1, "rate", "decade:10")
    _, dev, _, _ = allantools.oadev(y, rate=10.0, data_type="freq", taus=r.tau_s)
    np.testing.assert_allclose(r.adev, dev, rtol=1e-12, atol=0)


def test_phase_noise_identification_r_n_branch(monkeypatch):
    """White phase noise takes the R(n) branch of the B1 identification: the streamed
    R(n) (chunked sums) gives the same types."""
    monkeypatch.setattr(stream, "PIECE", 1000)
    y = np.diff(np.random.default_rng(5).standard_normal(40_001))     # white PM as a rate
    r0 = allan_deviation(y, 1.0, "rate", "octave")
    r1 = allan_deviation(record_of(y), 1.0, "rate", "octave")
    assert np.nanmax(r0.alpha_b1) == 2
    assert np.array_equal(np.nan_to_num(r1.alpha_b1, nan=-9), np.nan_to_num(r0.alpha_b1, nan=-9))
    np.testing.assert_allclose(r1.adev, r0.adev, rtol=1e-12, atol=0)


def test_streamed_deviation_memory_does_not_grow():
    peaks = []
    for n in (1 << 18, 1 << 21):
        # white-like noise as a function of the sample index (any slice, the same values)
        rec = stream.Record(n, lambda a, b: np.modf(np.sin(np.arange(a, b) * 12.9898)
                                                    * 43758.5453)[0])
        tracemalloc.start()
        allan_deviation(rec, 0.1, "rate", "decade:10")
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    # 2^21 samples are 16 MB a column: the estimator holds a few blocks, not the record
    assert peaks[1] < 1.5 * peaks[0] + (1 << 20) and peaks[1] < 14e6, peaks


# ------------------------------------------------------------- the specifications' items
def static_frame(n: int, seed: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    dt = 0.1
    y = 2.5 + 0.006 * (0.05 * rng.standard_normal(n) / math.sqrt(dt)
                       + 0.02 * np.cumsum(rng.standard_normal(n)) / math.sqrt(n)) / 3600
    lead = 50                       # other rows before the static record
    return pd.DataFrame({
        "test": pd.Categorical(["bias"] * lead + ["static"] * n),
        "run": np.zeros(n + lead, np.int64), "step": np.zeros(n + lead, np.int64),
        "time_s": np.arange(n + lead) * dt, "output": np.concatenate([np.full(lead, 2.5), y])})


def jsonable(item) -> dict:
    return json.loads(json.dumps({"value": float(item.value), "u": item.uncertainty.u,
                                  "details": item.details},
                                 default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o)))


def assert_close(a, b, path=""):
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            assert_close(a[k], b[k], f"{path}/{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (u, v) in enumerate(zip(a, b)):
            assert_close(u, v, f"{path}[{i}]")
    elif isinstance(a, float) and isinstance(b, float) and math.isfinite(a):
        # relative, or absolute against the record's scale for values that are ~0
        assert b == pytest.approx(a, rel=1e-12, abs=1e-12 * max(1e-6, abs(a))), path
    else:
        assert a == b or (a != a and b != b), (path, a, b)


def spec_items(df):
    cj = J.Context(df=df, output_unit="V", null_output=2.5, latitude_deg=45.0,
                   protocol=load_jjf("jjf1535-2015").sections, room_temperature_c=20.0,
                   K=0.006, u_K_rel=1e-4)
    ci = I.Context(df=df, output_unit="V", null_output=2.5, latitude_deg=45.0,
                   protocol=load_iec("iec62047-20").sections, a_typ=0.006, t_base_c=25.0,
                   v_base=5.0)
    ci.a_base = 0.006
    return {"jjf_arw": jsonable(J.angle_random_walk(cj)), "iec_arw": jsonable(I.arw(ci)),
            "iec_bi": jsonable(I.bias_instability(ci)),
            "iec_inband": jsonable(I.inband_noise(ci)),
            "iec_broadband": jsonable(I.broadband_noise(ci)),
            "jjf_drift_u": J.drift_u_dph(cj, (0.0, 100.0), (3600.0, 100.0)), "iec_drift_u": I.drift_u_dps(ci, 3600.0)}


def test_spec_noise_items_streamed_equal_the_array_path(monkeypatch):
    df = static_frame(70_001)
    whole = spec_items(df)                          # below the threshold: arrays, as before
    monkeypatch.setattr(stream, "STREAM_MIN_SAMPLES", 1000)
    monkeypatch.setattr(stream, "PIECE", 4096)
    from gonio.specs._rate_family.rate_records import static_rate_dph
    rate, _ = static_rate_dph(df, 2.5, 0.006)
    assert isinstance(rate, stream.Record)          # the streamed path is the one taken
    streamed = spec_items(df)
    assert whole["jjf_arw"]["value"] > 0 and whole["iec_bi"]["value"] > 0
    assert_close(whole, streamed)


def test_quiet_static_record_streamed(monkeypatch):
    """A static record that does not vary: 0 with the note, streamed or not."""
    df = static_frame(5000)
    df.loc[df.test == "static", "output"] = 2.5
    monkeypatch.setattr(stream, "STREAM_MIN_SAMPLES", 1000)
    ci = I.Context(df=df, output_unit="V", null_output=2.5, latitude_deg=45.0,
                   protocol=load_iec("iec62047-20").sections, a_typ=0.006, t_base_c=25.0,
                   v_base=5.0)
    ci.a_base = 0.006
    assert I.arw(ci).value == 0.0


def triad_session():
    bench = TriadBench(
        name="t", latitude_deg=49.2, sample_rate_hz=50.0, instrument="t", serial="s",
        output_unit="lsb", scale_per_dps=(50.0, 50.4, 49.7),
        nonorthogonality_rad=np.zeros((3, 3)), mounting_rad=(4.5e-3, -3.0e-3, 14.6e-3),
        cross_coupling=np.zeros((3, 3)), bias_dps=(0.2, -0.15, 0.08),
        arw_deg_sqrt_h=(0.5,) * 3, bias_instability_dph=(2.0,) * 3,
        rate_random_walk_dph_sqrt_h=(0.0,) * 3, thermal=ThermalModel())
    proto = TriadProtocol("t", "triad-alignment", (50.0, 100.0), 1, 0.5, True, 10.0,
                          {"x": "+y", "y": "+z", "z": "+x"}, 200.0, {})
    return run_alignment_session(proto, bench, seed=4)


def test_triad_averaging_time_streamed(monkeypatch):
    s = triad_session()
    text = format_triad_readings(s.readings, s.metadata)
    whole = estimate_alignment(parse_triad_readings(text, "r.csv")).averaging
    monkeypatch.setattr(stream, "STREAM_MIN_SAMPLES", 1000)
    monkeypatch.setattr(stream, "PIECE", 999)
    streamed = estimate_alignment(parse_triad_readings(text, "r.csv")).averaging
    assert streamed.tau_needed_s == whole.tau_needed_s
    assert streamed.tau_min_adev_s == whole.tau_min_adev_s
    np.testing.assert_allclose(streamed.adev_dph, whole.adev_dph, rtol=1e-12, atol=0)
    np.testing.assert_allclose(streamed.min_adev_dph, whole.min_adev_dph, rtol=1e-12, atol=0)


def test_streamed_modified_sums_at_large_m(monkeypatch):
    """mdev at m beyond a block: the moving sums from a streamed cumulative sum (no array of
    m points) equal the chunked sums of the array path."""
    from gonio.analysis.noise import allan
    monkeypatch.setattr(allan, "_BLOCK", 64)
    monkeypatch.setattr(stream, "PIECE", 500)
    y = noisy(20_001, seed=2)
    r0 = allan_deviation(y, 0.1, "rate", "decade:10", kind="mdev")
    r1 = allan_deviation(record_of(y), 0.1, "rate", "decade:10", kind="mdev")
    assert r0.m[-1] > 64
    np.testing.assert_allclose(r1.adev, r0.adev, rtol=1e-12, atol=0)


# ------------------------------------------------ the streamed path's CPU cost (issue 26)
def whole_phase(y: np.ndarray, offset: float) -> np.ndarray:
    c = np.empty(y.size + 1)
    c[0] = 0.0
    np.subtract(y, offset, out=c[1:])
    np.cumsum(c, out=c)
    return c


@pytest.mark.parametrize("block,fine", [(4096, 64), (1000, 4096), (64, 64)])
def test_span_and_lazy_checkpoints_are_the_whole_array(monkeypatch, block, fine):
    """:meth:`CumulativeSum.span` (from the fine checkpoints, found lazily as the blocks are
    first built, with no pass of their own) and the point-by-point decimations give the
    whole cumulative sum bit for bit, also when the far end is asked for first."""
    monkeypatch.setattr(stream, "FINE", fine)
    y = noisy(20_003, seed=4)
    c = whole_phase(y, 2.9)
    cs = stream.CumulativeSum(record_of(y), 2.9, block=block, cache_blocks=2)
    assert cs._done == 0                                  # nothing built by the constructor
    for a, b in [(19_990, 20_004), (0, 20_004), (4095, 4097), (63, 64), (17, 9000),
                 (20_003, 20_004), (5, 5)]:
        assert np.array_equal(cs.span(a, b), c[a:b]), (a, b)
    ranges = [(5, 20_004, 64), (0, 20_004, 5000), (17, 9000, 3), (100, 101, 4096)]
    for got, (a, b, m) in zip(cs.decimations(ranges), ranges):
        assert np.array_equal(got, c[a:b:m]), (a, b, m)


def direct_sum(x: np.ndarray, m: int) -> float:
    v = x[2 * m:] - 2 * x[m:-m] + x[:-2 * m]
    return float(np.sum(v * v))


@pytest.mark.parametrize("m", [1001, 1999, 2000, 2001, 7777, 9999, 10_000])
def test_far_sums_in_chains_equal_the_direct_sum(monkeypatch, m):
    """The chained far sums (each point rebuilt about once) hold every term once: equal to
    the plain sum over the whole phase, for m just past the chunk, a multiple of it, a
    chunk width that does not divide m, and the largest m (one term)."""
    from gonio.analysis.noise import allan
    monkeypatch.setattr(stream, "FINE", 64)
    y = noisy(20_000, seed=6)
    c = whole_phase(y, float(y.mean()))
    cs = stream.CumulativeSum(record_of(y), float(y.mean()), block=4096)
    assert allan._sums_far(cs, m, 1000) == pytest.approx(direct_sum(c, m), rel=1e-13)


def test_streamed_far_taus_equal_the_array_path_and_allantools(monkeypatch):
    """With chunks of 1000 points most decade τ are 'far' (the chained sums): the streamed
    ADEV, identified noise types and intervals equal the array path, and allantools."""
    from gonio.analysis.noise import allan
    monkeypatch.setattr(allan, "_BLOCK_SHARED", 1000)
    monkeypatch.setattr(stream, "PIECE", 4096)
    monkeypatch.setattr(stream, "FINE", 256)
    y = noisy(60_000, seed=9)
    r0 = allan_deviation(y, 0.1, "rate", "decade:10")
    r1 = allan_deviation(record_of(y), 0.1, "rate", "decade:10")
    assert (r1.m > 1000).sum() >= 10
    np.testing.assert_allclose(r1.adev, r0.adev, rtol=1e-12, atol=0)
    assert np.array_equal(r1.alpha, r0.alpha) and np.array_equal(r1.edf, r0.edf)
    _, dev, _, _ = allantools.oadev(y, rate=10.0, data_type="freq", taus=r1.tau_s)
    np.testing.assert_allclose(r1.adev, dev, rtol=1e-12, atol=0)


def test_jjf_statistics_in_one_pass_equal_the_per_k_forms():
    """JJF 1535's eq (22)–(24) statistic and the overlapping AVAR for all k from one
    cumulative sum equal the per-k functions bit for bit, for an array and a streamed
    record, across piece boundaries."""
    from gonio.specs.jjf1535 import formulas as jf
    ks = [1, 2, 4, 8, 16]
    for n in (35, 65_536 + 20, 2 * 65_536 - 30):
        x = noisy(n, seed=n)
        want = {k: (jf.allan_variance_printed_jjf(x, k), jf.allan_variance_overlapping(x, k))
                for k in ks}
        assert jf.allan_variances_jjf(x, ks) == want
        assert jf.allan_variances_jjf(record_of(x), ks) == want
