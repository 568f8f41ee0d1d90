"""The specifications' own noise items in bounded pieces (issue 26): the Welch density of
IEC 62047-20 5.4.5.1 b)/c) (:func:`gonio.analysis.noise.psd.welch_psd`), JJF 1535's printed
eq (22)–(24) statistic and the overlapping AVAR beside it, and the static record's rate
(no copy of the whole frame) give the numbers of the one-shot forms — scipy.signal.welch on
the whole record, the statistics written out here on whole arrays — to rounding, whatever
the piece size; and the pieces are bounded (the temporaries do not grow with the record)."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pandas as pd
import pytest
from scipy import signal

from gonio.analysis.noise import psd
from gonio.specs.jjf1535 import formulas as jf
from gonio.specs._rate_family.rate_records import static_rate_dph
from gonio.units import S_PER_H


@pytest.mark.parametrize("n,nper,seg", [(100_000, 4096, 7), (50_000, 4096, 256),
                                        (4096, 4096, 3), (9_999, 512, 1), (123_457, 1000, 50)])
def test_welch_in_pieces_equals_scipy(n, nper, seg):
    rng = np.random.default_rng(n)
    x = 30.0 * rng.standard_normal(n) + 5.0 + 1e-3 * np.arange(n)      # °/h, offset, ramp
    f, p = psd.welch_psd(x, 10.0, nper, divisor=S_PER_H, segments=seg)
    y = x / S_PER_H
    f0, p0 = signal.welch(y - y.mean(), fs=10.0, nperseg=nper)
    assert np.array_equal(f, f0)
    np.testing.assert_allclose(p, p0, rtol=1e-11, atol=0)


def test_welch_pieces_are_bounded():
    """The temporaries of a piece do not depend on the record's length."""
    peaks = []
    for n in (1 << 20, 1 << 22):
        x = np.random.default_rng(1).standard_normal(n)
        tracemalloc.start()
        psd.welch_psd(x, 10.0, 4096, segments=16)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert peaks[1] < 1.3 * peaks[0] and peaks[1] < 8 * (1 << 20), peaks


def printed_whole(x, k):
    c = np.concatenate([[0.0], np.cumsum(x)])
    means = (c[k:] - c[:-k]) / k
    d2 = means[2:] - 2 * means[1:-1] + means[:-2]
    return float((d2 ** 2).sum() / (2.0 * (x.size - k - 1)))


def avar_whole(x, k):
    c = np.concatenate([[0.0], np.cumsum(x)])
    means = (c[k:] - c[:-k]) / k
    d = means[k:] - means[:-k]
    return float((d ** 2).sum() / (2.0 * d.size))


@pytest.mark.parametrize("piece", [1, 7, 1000, 1 << 16])
@pytest.mark.parametrize("k", [1, 2, 4, 16])
def test_printed_and_overlapping_statistics_in_pieces(monkeypatch, piece, k):
    monkeypatch.setattr(jf, "_PIECE", piece)
    x = np.random.default_rng(k).standard_normal(5003) * 0.3 + 2.0
    assert jf.allan_variance_printed_jjf(x, k) == pytest.approx(printed_whole(x, k), rel=1e-12)
    assert jf.allan_variance_overlapping(x, k) == pytest.approx(avar_whole(x, k), rel=1e-12)
    # white noise of unit variance: AVAR(k) ≈ 1/k, the printed statistic 3 at k = 1, 2/k²
    w = np.random.default_rng(0).standard_normal(200_000)
    assert jf.allan_variance_overlapping(w, k) == pytest.approx(1.0 / k, rel=0.05)


def test_static_rate_is_the_segment_rate():
    rng = np.random.default_rng(3)
    n = 1000
    df = pd.DataFrame({"test": ["bias"] * 10 + ["static"] * n + ["static"] * 5,
                       "run": [0] * (10 + n) + [1] * 5, "step": 0,
                       "time_s": np.arange(n + 15) * 0.1,
                       "output": 2.5 + 0.01 * rng.standard_normal(n + 15)})
    rate, dt = static_rate_dph(df, 2.5, 0.006)
    g = df[(df["test"] == "static") & (df["run"] == 0) & (df["step"] == 0)]
    assert np.array_equal(rate, (g["output"].to_numpy() - 2.5) / 0.006 * S_PER_H)
    assert dt == pytest.approx(0.1, rel=1e-12) and rate.size == n
