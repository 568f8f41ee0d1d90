"""The budget lines the rate studies' worst-condition case found missing or mis-modelled,
each checked by a second route: the IEC 62047-20 5.1.3.4 slope's bound over any pattern of
the chamber's set-point deviations (every sign pattern enumerated, numpy.polyfit), and the
noise items' chamber-fluctuation line (the Welch estimate of the fluctuation at every phase
on a grid, and Parseval where the whole sinusoid lies in the band)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy import signal

from gonio.specs.iec62047_20.items import (correlated_deviation_slope_bound,
                                           fluctuation_band_power, fluctuation_rms_bound)


@pytest.mark.parametrize("T", [[-40.0, -8.75, 22.5, 53.75, 85.0], [-40.0, 0.0, 25.0, 85.0],
                               [10.0, 20.0, 60.0]])
def test_slope_bound_is_the_largest_over_every_sign_pattern(T):
    T = np.array(T)
    a0, k = 100.0, -0.37                          # a(T) = a0 + k·T, read at T + d
    best = 0.0
    for signs in itertools.product((-1.0, 1.0), repeat=T.size):
        d = 2.0 * np.array(signs)
        best = max(best, abs(np.polyfit(T, a0 + k * (T + d), 1)[0] - k))
    # any pattern inside the bounds moves it no more (the extreme points of the box)
    rng = np.random.default_rng(4)
    inner = max(abs(np.polyfit(T, a0 + k * (T + rng.uniform(-2, 2, T.size)), 1)[0] - k)
                for _ in range(2000))
    h = correlated_deviation_slope_bound(T, k, 2.0)
    assert h == pytest.approx(best, rel=1e-9) and inner <= h
    # the independent-deviation u is smaller than this line's u = h/√3
    assert 2.0 / math.sqrt(3) * abs(k) / math.sqrt(((T - T.mean()) ** 2).sum()) < h / math.sqrt(3)


def _band(x, dt, nper, lo, hi, include_lo):
    f, p = signal.welch(x - x.mean(), fs=1.0 / dt, nperseg=nper)
    sel = ((f >= lo) if include_lo else (f > lo)) & (f <= hi)
    return float(np.trapezoid(p[sel], f[sel]))


@pytest.mark.parametrize("period, lo, hi, include_lo", [(900.0, 0.0, 1.0, False),
                                                        (37.0, 0.0, 1.0, False),
                                                        (3.3, 1.0, 5.0, True)])
def test_fluctuation_power_is_the_largest_over_the_phase(period, lo, hi, include_lo):
    n, dt, nper, amp = 18000, 0.1, 1024, 0.004
    t = np.arange(n) * dt
    grid = [_band(amp * np.sin(2 * np.pi * t / period + ph), dt, nper, lo, hi, include_lo)
            for ph in np.linspace(0, np.pi, 73)]
    got = fluctuation_band_power(n, dt, nper, amp, period, lo, hi, include_lo=include_lo)
    assert got == pytest.approx(max(grid), rel=2e-3)
    assert got >= max(grid) * (1 - 1e-9)


def test_fluctuation_in_band_is_parseval_and_the_rms_line_bounds_the_reading():
    n, dt, nper, amp = 20000, 0.1, 2000, 0.01
    # a period short against the segment, well inside the band: its power A²/2
    assert fluctuation_band_power(n, dt, nper, amp, 13.0, 0.0, 5.0) == \
        pytest.approx(amp ** 2 / 2, rel=0.02)
    # the reading of noise + fluctuation exceeds the noise's by at most the line's half-width
    rng = np.random.default_rng(2)
    x = 0.02 * rng.standard_normal(n)
    t = np.arange(n) * dt
    r0 = math.sqrt(_band(x, dt, nper, 0.0, 1.0, False))
    dp = fluctuation_band_power(n, dt, nper, amp, 900.0, 0.0, 1.0)
    reads = [math.sqrt(_band(x + amp * np.sin(2 * np.pi * t / 900.0 + ph), dt, nper, 0.0, 1.0,
                             False)) for ph in np.linspace(0, 2 * np.pi, 13)]
    h = fluctuation_rms_bound(max(reads), dp)
    assert max(reads) - r0 == pytest.approx(h, rel=0.25)
    assert fluctuation_band_power(n, dt, nper, 0.0, 900.0, 0.0, 1.0) == 0.0
    # the period not stated: the largest over periods, never below the stated one's
    assert fluctuation_band_power(n, dt, nper, amp, None, 0.0, 1.0) >= dp
