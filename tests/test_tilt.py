"""Tilt errors (draft Annex A.4.2): three evaluations agree; the annex's extreme; rigid model."""

import math

import numpy as np
import pytest
import sympy
from scipy import integrate

from gonio.specs.ogam_draft.tilt import (ARCSEC_PER_RAD, elliptic_error_arcsec, elliptic_extreme,
                        elliptic_series, rigid_error_arcsec, rigid_extreme)

THETA = np.linspace(0.0, 360.0, 97)


def _direct_error_arcsec(theta_deg, tilt_deg):
    """Straight from the annex's formula with the annex's integrand, by quadrature."""
    psi = math.radians(tilt_deg)
    g = lambda t: 1.0 / math.sqrt(math.cos(psi) ** 2 * math.cos(t) ** 2 + math.sin(t) ** 2)
    full = integrate.quad(g, 0, 2 * math.pi, epsabs=0, epsrel=1e-13, limit=200)[0]
    th = math.radians(theta_deg)
    part = integrate.quad(g, 0, th, epsabs=0, epsrel=1e-13, limit=200)[0]
    return (2 * math.pi * part / full - th) * ARCSEC_PER_RAD


@pytest.mark.parametrize("tilt", [0.1, 1.0, 10.0, 45.0, 80.0])
def test_closed_form_matches_quadrature(tilt):
    c = elliptic_error_arcsec(THETA, tilt, method="closed")
    q = elliptic_error_arcsec(THETA, tilt, method="quad")
    scale = max(1.0, np.max(np.abs(c)))
    np.testing.assert_allclose(c, q, atol=1e-8 * scale)


@pytest.mark.parametrize("theta", [17.0, 100.0, 200.0, 300.0, 359.0])
def test_closed_form_matches_annex_integrand(theta):
    # beyond pi/2 the closed form relies on F(phi + n pi) = F(phi) + 2nK
    for tilt in (5.0, 30.0):
        assert elliptic_error_arcsec(theta, tilt) == pytest.approx(
            _direct_error_arcsec(theta, tilt), abs=1e-6)


def test_series_leading_term_symbolic():
    th, ps = sympy.symbols("theta psi", real=True)
    s = elliptic_series(4)
    lead = sympy.series(s, ps, 0, 3).removeO()
    assert sympy.simplify(lead - ps ** 2 * sympy.sin(2 * th) / 8) == 0
    assert sympy.simplify(elliptic_series(2) - ps ** 2 * sympy.sin(2 * th) / 8) == 0


def test_series_error_is_order_psi4():
    # |closed - (psi^2/8) sin 2theta| / psi^4 stays bounded as psi shrinks (O(psi^4))
    ratios = []
    for tilt in (4.0, 2.0, 1.0, 0.5):
        psi = math.radians(tilt)
        d = np.max(np.abs(elliptic_error_arcsec(THETA, tilt) -
                          elliptic_error_arcsec(THETA, tilt, method="series", order=2)))
        ratios.append(d / ARCSEC_PER_RAD / psi ** 4)
    assert max(ratios) / min(ratios) < 1.01
    # and the psi^4 series is better by a further psi^2
    tilt = 2.0
    e2 = np.max(np.abs(elliptic_error_arcsec(THETA, tilt) -
                       elliptic_error_arcsec(THETA, tilt, method="series", order=2)))
    e4 = np.max(np.abs(elliptic_error_arcsec(THETA, tilt) -
                       elliptic_error_arcsec(THETA, tilt, method="series", order=4)))
    assert e4 < e2 * math.radians(tilt) ** 2 * 10


def test_annex_extreme_at_0p1_degree():
    e = elliptic_extreme(0.1)
    psi = math.radians(0.1)
    assert e.extreme_arcsec == pytest.approx(psi ** 2 / 8 * ARCSEC_PER_RAD, rel=1e-5)
    assert round(e.extreme_arcsec, 4) == 0.0785 and round(e.extreme_arcsec, 2) == 0.08
    np.testing.assert_allclose(e.at_deg, [45, 135, 225, 315], atol=1e-4)
    vals = elliptic_error_arcsec(np.array(e.at_deg), 0.1)
    assert np.all(np.sign(vals) == [1, -1, 1, -1])
    # a dense grid never beats the reported extreme; it is reached at the reported angles
    grid = np.linspace(0, 360, 360 * 200 + 1)
    assert np.max(np.abs(elliptic_error_arcsec(grid, 0.1))) <= e.extreme_arcsec * (1 + 1e-12)


def test_extreme_location_large_tilt_matches_grid():
    e = elliptic_extreme(30.0)
    grid = np.linspace(0, 90, 90_001)
    v = elliptic_error_arcsec(grid, 30.0)
    assert e.at_deg[0] == pytest.approx(grid[np.argmax(v)], abs=2e-3)
    assert e.extreme_arcsec == pytest.approx(v.max(), rel=1e-9)


def test_vectorised_and_scalar():
    v = elliptic_error_arcsec(np.array([[45.0, 90.0], [180.0, 360.0]]), 1.0)
    assert v.shape == (2, 2)
    np.testing.assert_allclose(v[0, 1:], 0, atol=1e-9)
    np.testing.assert_allclose(v[1], 0, atol=1e-9)
    assert isinstance(elliptic_error_arcsec(45.0, 1.0), float)


def test_rigid_model():
    psi = math.radians(0.1)
    assert rigid_error_arcsec(360.0, 0.1, calibrated=False) == pytest.approx(
        360 * 3600 * (math.cos(psi) - 1), rel=1e-9)
    np.testing.assert_array_equal(rigid_error_arcsec(THETA, 0.1), 0.0)
    assert rigid_extreme(0.1).extreme_arcsec == 0.0
    u = rigid_extreme(0.1, calibrated=False)
    assert u.at_deg == (360.0,) and u.extreme_arcsec == pytest.approx(1.9739, abs=1e-4)


def test_invalid_tilt():
    with pytest.raises(ValueError):
        elliptic_error_arcsec(10.0, 90.0)
    with pytest.raises(ValueError):
        elliptic_error_arcsec(10.0, 1.0, method="simpson")
