"""A typo below the tilt-estimate screen's floor (3 × the A.4.3 drift over the dwell: 1.8″ at
120 s) is used: what it does to ψ, its azimuth and K's tilt correction is bounded in closed
form (docs/draft-readings.md, "A tilt-estimate typo below the floor"): the rest's rate moves
by δ/T, the first harmonic's (a, b) by (2/N)(δ/T)(cos θ_k, sin θ_k), so the tilt vector
(ψ cos α, ψ sin α) by at most 2δ / (N T Ω_⊥ cos ψ). Checked on rests drawn with numpy
against ``estimate_tilt`` at every position and sign (the bound is reached where θ_k is the
tilt's phase, so a wrong factor fails it both ways)."""

from __future__ import annotations

import math

import numpy as np

from gonio.physics.earth import earth_rate_split
from gonio.specs.ogam_draft.tilt_estimate import estimate_tilt
from gonio.units import ARCSEC_PER_DEG


def _vec(e):
    p, a = math.radians(e.tilt_deg), math.radians(e.tilt_azimuth_table_deg)
    return np.array([p * math.cos(a), p * math.sin(a)])


def test_tilt_vector_shift_is_the_closed_form_bound_and_reaches_it():
    rng = np.random.default_rng(20261206)
    lat, n, dwell = 40.2, 12, 120.0
    perp = earth_rate_split(lat, "up").perpendicular_dps * ARCSEC_PER_DEG
    th = np.arange(n) * 360.0 / n
    amp = perp * math.sin(math.radians(0.04))
    y = 9.7 + amp * np.cos(np.radians(th + 25.0)) + rng.normal(0, 0.131 / dwell, n)
    e0 = estimate_tilt(th, y, lat)
    v0 = _vec(e0)
    for delta in (0.5, 1.0, 1.8):
        bound = 2 * delta / (n * dwell * perp * math.cos(math.radians(e0.tilt_deg)))
        shifts = []
        for k in range(n):
            for sgn in (1, -1):
                y2 = y.copy()
                y2[k] += sgn * delta / dwell
                shifts.append(float(np.hypot(*(_vec(estimate_tilt(th, y2, lat)) - v0))))
        # every shift within the bound (the small-angle and cos ψ factors: 1 %), the largest
        # at it: the bound is the effect, not a loose ceiling
        assert max(shifts) <= bound * 1.01
        assert max(shifts) >= bound * 0.97
