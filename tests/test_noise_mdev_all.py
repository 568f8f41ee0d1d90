"""MDEV for every τ (``taus="all"``): the local-segment expansion against exact sums.

The reference is independent of any floating-point expansion: the rate samples are
integers, so the phase x and its cumulative sum S are exact integers (int64), each
term S[j+3m] − 3S[j+2m] + 3S[j+m] − S[j] (SP 1065 eq. 14, Σ of m second differences)
is exact, and its square is summed with math.fsum. Rate random walk is where the
whole-record expansion lost most (its cancellation grows as (N/m)⁵), so it is in
every record. allantools (peer library, tests only) checks the public result.
"""

from __future__ import annotations

import math

import allantools
import numpy as np
import pytest

import gonio.analysis.noise.allan as allan_mod
from gonio.analysis import noise


def _exact_sum(x_int: np.ndarray, m: int) -> float:
    s = np.concatenate(([0], np.cumsum(x_int)))
    t = s[3 * m:] - 3 * s[2 * m: -m] + 3 * s[m: -2 * m] - s[: -3 * m]
    return math.fsum(t.astype(np.float64) ** 2)


def _flicker(rng, n):
    """1/f noise by spectral shaping (unit-ish variance)."""
    f = np.fft.rfftfreq(2 * n)
    spec = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))
    spec[1:] /= np.sqrt(f[1:])
    spec[0] = 0.0
    v = np.fft.irfft(spec, 2 * n)[:n]
    return v / v.std()


def _rate(rng, kind: str, n: int) -> np.ndarray:
    """Integer rate samples of one power-law noise type plus rate random walk."""
    w = rng.standard_normal(n + 1)
    base = {"white_phase": np.diff(w), "flicker_phase": np.diff(_flicker(rng, n + 1)),
            "white_rate": w[:n], "flicker_rate": _flicker(rng, n),
            "rrw": np.zeros(n)}[kind]
    y = 64.0 * (base + 0.01 * np.cumsum(rng.standard_normal(n)))
    return np.round(y)


def _raw_fast_sums(monkeypatch, x: np.ndarray, ms: np.ndarray) -> np.ndarray:
    """The segment expansion with its direct fallback disabled above the direct range:
    an m it would have recomputed comes back NaN, so a loss of precision can neither
    hide behind the fallback nor pass unseen."""
    orig = allan_mod._direct_sums

    def only_small(kind, xx, mm):
        mm = np.asarray(mm)
        out = np.full(mm.size, np.nan)
        small = mm < allan_mod._MDEV_DIRECT_BELOW
        out[small] = orig(kind, xx, mm[small])
        return out

    monkeypatch.setattr(allan_mod, "_direct_sums", only_small)
    return allan_mod._mdev_local_sums(x, ms, 1e-9)


@pytest.mark.parametrize("kind", ["white_phase", "flicker_phase", "white_rate",
                                  "flicker_rate", "rrw"])
def test_mdev_all_sums_exact_for_each_noise_type(monkeypatch, kind):
    rng = np.random.default_rng(["white_phase", "flicker_phase", "white_rate",
                                 "flicker_rate", "rrw"].index(kind))
    n = 40_000
    y = _rate(rng, kind, n)
    x_int = np.concatenate(([0], np.cumsum((y - np.round(y.mean())).astype(np.int64))))
    ms = np.arange(1, (x_int.size - 1) // 3 + 1)
    fast = _raw_fast_sums(monkeypatch, x_int.astype(np.float64), ms)
    assert np.isfinite(fast).all()  # no m needed the fallback
    pick = np.unique(np.r_[1, 15, 16, 17, 31, 32, 33, 100, 1000, 2222, 6666, 6667, 9000,
                           rng.integers(1, ms[-1], 25), ms[-3:]])
    exact = np.array([_exact_sum(x_int, int(m)) for m in pick])
    np.testing.assert_allclose(fast[pick - 1], exact, rtol=1e-10, atol=0)


def test_mdev_all_long_rrw_record_against_direct_sums():
    """3·10⁵ samples of rate random walk (with white rate noise): the public result at
    every octave and at random m against the direct O(N)-per-m formula, to 1e-9."""
    rng = np.random.default_rng(7)
    n = 300_000
    y = rng.standard_normal(n) + 0.05 * np.cumsum(rng.standard_normal(n))
    r = noise.allan_deviation(y, 0.01, "rate", "all", kind="mdev", alpha=0)
    pick = np.unique(np.r_[2 ** np.arange(17), rng.integers(1, r.m[-1], 12), r.m[-2:]])
    direct = noise.allan_deviation(y, 0.01, "rate", pick, kind="mdev", alpha=0)
    np.testing.assert_allclose(r.adev[pick - 1], direct.adev, rtol=1e-9)


def test_mdev_all_matches_allantools():
    rng = np.random.default_rng(12)
    y = rng.standard_normal(3000) + 0.02 * np.cumsum(rng.standard_normal(3000))
    r = noise.allan_deviation(y, 1.0, "rate", "all", kind="mdev", alpha=0)
    assert r.m.tolist() == list(range(1, 1001))
    t, dev, _, _ = allantools.mdev(y, rate=1.0, data_type="freq", taus="all")
    common = np.isin(r.m, np.round(t).astype(int))
    assert common.sum() >= 990
    np.testing.assert_allclose(r.adev[common], dev[: common.sum()], rtol=1e-9)


def test_wedge_rows_against_their_definition():
    rng = np.random.default_rng(0)
    for rows in (1, 3):  # one row: tiled rectangles; several: batched FFTs
        z = np.zeros((rows, 901))
        z[:, :900] = rng.standard_normal((rows, 900))
        for s, c in ((1, 1), (1, 2), (2, 1)):
            for m_lo, count in ((0, 100), (37, 40), (64, 64), (100, 29), (5, 3), (1, 150)):
                w = allan_mod._wedge_rows(z, m_lo, count, s, c)
                for r in range(rows):
                    for m in range(m_lo, m_lo + count):
                        ref = sum(z[r, i] * z[r, i + c * m] for i in range(s * m)
                                  if i + c * m < 900)
                        assert w[r, m - m_lo] == pytest.approx(ref, abs=1e-9), (s, c, m)


def test_direct_mdev_sum_in_chunks_is_exact():
    rng = np.random.default_rng(5)
    y = np.round(64 * (rng.standard_normal(150_001) + 0.01 * np.cumsum(
        rng.standard_normal(150_001))))
    x_int = np.concatenate(([0], np.cumsum(y.astype(np.int64))))
    for m in (1, 2, 7, 21_000, 50_000):  # chunk boundaries and m longer than a chunk
        got = allan_mod._sum_sq_mod(x_int.astype(np.float64), m)
        assert got == pytest.approx(_exact_sum(x_int, m), rel=1e-12)
