"""Closed forms of the virtual rate gyro's noise-free responses (the truths of JJF 1535 and
IEC 62047-20 items), written from the model's parameters (:class:`.rate_gyro.RateGyroConfig`)
and never through the estimators the rate specifications calibrate with: a formula mutated in
an estimator changes the estimate, not the truth, so the noise-off tests see it.

The response of the model to a steady input ω (°/s equivalent, before the scale factor) is
f(ω) = ω(1 ± α/2) + c₃ω³ for ω ≷ 0 (threshold d and saturation aside). On a rate table the
input is Ω + e, e the Earth-rate component on the input axis. Over symmetric rates ±r_i
(and, for IEC 62047-20, the rest point 0) the least-squares slopes have closed forms
(S(a, b) = Σ(a − ā)(b − b̄) over the positive rates r):

* both directions:  Σx f(x + e)/Σx² = 1 + eαΣr/(2Σr²) + c₃(Σr⁴/Σr² + 3e²);
* one direction:    (1 ± α/2) + c₃[S(r, r³) ± 3e S(r, r²)]/S(r, r) + 3c₃e²  (+ forward);
  so K₊ − K₋ = α + 6c₃e S(r, r²)/S(r, r) and (K₊ + K₋)/2 = 1 + c₃[S(r, r³)/S(r, r) + 3e²].

They hold while every |r_i ± e| is above the threshold d and below saturation;
:func:`closed_form_valid` says whether they do, and the callers fall back to a
numerical least-squares fit (``numpy.polyfit``, a second algorithm) of the model's exact
outputs otherwise.
"""

from __future__ import annotations

import math

import numpy as np


def _S(a: np.ndarray, b: np.ndarray) -> float:
    return float(((a - a.mean()) * (b - b.mean())).sum())


def closed_form_valid(g, rates_dps, e_dps: float) -> bool:
    """Whether the closed forms apply at the positive ``rates_dps`` with Earth component e:
    every |r ± e| above the threshold and the largest response inside saturation."""
    r = np.abs(np.asarray(rates_dps, float))
    low = float(r.min()) - abs(e_dps)
    top = float(r.max()) + abs(e_dps)
    big = top * (1 + abs(g.sf_asymmetry) / 2) + abs(g.sf_cubic_per_dps2) * top ** 3
    return low > g.dead_band_dps and low > 0 and (g.range_dps <= 0 or big < 1.5 * g.range_dps)


def response_at(g, w_dps) -> np.ndarray:
    """f(ω) of the model written out (threshold, asymmetry, cubic term, saturation): the
    physics the bench simulates, for the fall-back fits and the 50 % rule truths."""
    w = np.asarray(w_dps, float)
    wd = np.where(np.abs(w) < g.dead_band_dps, 0.0, w)
    out = wd * (1 + 0.5 * g.sf_asymmetry * np.sign(wd)) + g.sf_cubic_per_dps2 * wd ** 3
    return np.clip(out, -1.5 * g.range_dps, 1.5 * g.range_dps) if g.range_dps > 0 else out


def slope_both_directions(g, rates_dps, e_dps: float) -> tuple[float, str]:
    """Least-squares slope (per unit K) of f(x + e) over x = ±r_i (the rest point, if the
    clause fits it, adds nothing: x = 0). Returns (slope, how)."""
    r = np.abs(np.asarray(rates_dps, float))
    if closed_form_valid(g, r, e_dps):
        s2, s4 = float((r ** 2).sum()), float((r ** 4).sum())
        return (1 + e_dps * g.sf_asymmetry * float(r.sum()) / (2 * s2)
                + g.sf_cubic_per_dps2 * (s4 / s2 + 3 * e_dps ** 2)), "closed form"
    x = np.concatenate([-r, r])
    return float(np.polyfit(x, response_at(g, x + e_dps), 1)[0]), "numpy.polyfit of f(x + e)"


def slopes_per_direction(g, rates_dps, e_dps: float) -> tuple[float, float, str]:
    """Least-squares slopes (per unit K) of each direction's own fit (own intercept, no rest
    point): (K₊, K₋, how)."""
    r = np.abs(np.asarray(rates_dps, float))
    if closed_form_valid(g, r, e_dps):
        srr = _S(r, r)
        c3, a = g.sf_cubic_per_dps2, g.sf_asymmetry
        common = c3 * _S(r, r ** 3) / srr + 3 * c3 * e_dps ** 2
        odd = 3 * c3 * e_dps * _S(r, r ** 2) / srr
        return 1 + a / 2 + common + odd, 1 - a / 2 + common - odd, "closed form"
    kp = float(np.polyfit(r, response_at(g, r + e_dps), 1)[0])
    kn = float(np.polyfit(-r, response_at(g, -r + e_dps), 1)[0])
    return kp, kn, "numpy.polyfit of each direction"


def ls_slope_of_poly(x, c1: float, c2: float) -> float:
    """Least-squares slope of c₁x + c₂x² over the points x (x centred on nothing):
    c₁ + c₂·S(x, x²)/S(x, x) — the slope of a quadratic temperature model over a grid."""
    x = np.asarray(x, float)
    return c1 + c2 * _S(x, x ** 2) / _S(x, x)


def exponential_interval_mean(A: float, tau_s: float, t0: float, t1: float) -> float:
    """Mean of A·e^(−t/τ) over [t0, t1] (the warm-up / power-on transient's interval means)."""
    return A * tau_s / (t1 - t0) * (math.exp(-t0 / tau_s) - math.exp(-t1 / tau_s))


def log_grid_crossing(freq_hz, ratio, target: float) -> float:
    """First crossing of ``ratio`` (normalised to its first point) below ``target``,
    interpolated linearly in dB against ln f between the bracketing grid points (NaN if it
    never falls that far). Written here, apart from the estimator's own interpolation."""
    f = np.asarray(freq_hz, float)
    db = 20 * np.log10(np.asarray(ratio, float) / float(ratio[0]))
    tdb = 20 * math.log10(target)
    below = np.flatnonzero(db <= tdb)
    if below.size == 0 or below[0] == 0:
        return math.nan
    i = int(below[0])
    w = (tdb - db[i - 1]) / (db[i] - db[i - 1])
    return float(math.exp(math.log(f[i - 1]) + w * (math.log(f[i]) - math.log(f[i - 1]))))


def rule_walk(steps, passed) -> float | None:
    """The 50 % rules' walk (JJF 7.2.6, 7.2.7; IEC 5.6.3) on noise-free responses: the steps in
    the order given (decreasing), the last one that passes before the first that fails;
    None when the first fails. ``passed`` holds the truth of each step's criterion."""
    out = None
    for s, ok in zip(steps, passed):
        if not ok:
            break
        out = abs(float(s))
    return out
