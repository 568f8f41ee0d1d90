"""The spread terms of three IEC 62047-20 items against independent Monte Carlo: the in-band
noise's Welch estimate (scipy.signal.welch on white noise), the linearity residuals' noise
(numpy least squares on perturbed outputs) and the frequency band's interpolation remainder
(a closed-form quadratic)."""

import math

import numpy as np
import pytest
from scipy import signal

from gonio.analysis.noise.psd import welch_band_rms_u_rel
from gonio.specs.iec62047_20.formulas import linearity_errors_iec
from gonio.specs.iec62047_20.items import interpolation_remainder, linearity_noise_sd


@pytest.mark.parametrize("n, nper", ((6000, 4096), (20000, 1024)))
def test_welch_band_rms_u_rel_matches_monte_carlo(n, nper):
    rng = np.random.default_rng(5)
    rms, preds = [], []
    for _ in range(600):
        x = rng.standard_normal(n)
        f, p = signal.welch(x - x.mean(), fs=10.0, nperseg=nper)
        sel = (f > 0) & (f <= 1.0)
        rms.append(math.sqrt(np.trapezoid(p[sel], f[sel])))
        if len(preds) < 20:                      # each from the record's own estimate
            preds.append(welch_band_rms_u_rel(n, nper, p[sel], float(f[1] - f[0])))
    rms = np.array(rms)
    pred = float(np.mean(preds))
    # 600 records: the sd's own relative sd is ≈ 1/√1200 ≈ 3 %
    assert rms.std(ddof=1) / rms.mean() == pytest.approx(pred, rel=0.10)
    # the figure used before (2/√(2·lines·n//2048)) is 1.4× to 2.9× the spread
    assert 2 / math.sqrt(2 * sel.sum() * (n // 2048)) > 1.3 * rms.std(ddof=1) / rms.mean()


def test_linearity_noise_sd_matches_monte_carlo():
    rng = np.random.default_rng(0)
    x = np.linspace(-300.0, 300.0, 11)
    y0 = 0.01 * x + 1e-7 * x ** 3 + 0.3
    u = 0.02 * (1 + np.arange(11) / 10)
    L0, _, _, fs = linearity_errors_iec(x, y0)
    Ls = np.array([linearity_errors_iec(x, y0 + rng.standard_normal(11) * u)[0]
                   for _ in range(8000)])
    sd = linearity_noise_sd(x, L0, fs, u)
    np.testing.assert_allclose(Ls.std(0, ddof=1), sd, rtol=0.05)
    assert np.all(sd < u / fs)           # a residual moves by √(1 − h_ii)·u, not √2·u


def test_interpolation_remainder_is_exact_for_a_quadratic():
    lnf = np.log(np.array([40.0, 50.0, 55.0, 60.0, 70.0]))
    p = 3.0 * lnf ** 2 - 2.0 * lnf                       # p'' = 6 everywhere
    for j in (2, 3, 4):
        h = lnf[j] - lnf[j - 1]
        assert interpolation_remainder(lnf, p, j) == pytest.approx(h * h / 8 * 6.0, rel=1e-9)
        mid = 0.5 * (lnf[j] + lnf[j - 1])            # the worst error, at the midpoint
        lin = 0.5 * (p[j] + p[j - 1])
        assert abs(lin - (3.0 * mid ** 2 - 2.0 * mid)) == pytest.approx(h * h / 8 * 6.0, rel=1e-9)
