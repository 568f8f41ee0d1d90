"""Earth-rate compensation: linear sensitivities against exact residuals, the measured
compensation's scatter on the virtual bench against its predicted u, budget wiring."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.specs.ogam_draft.budget_extra import compensation_component
from gonio.specs.ogam_draft.bench import run_session
from gonio.specs.ogam_draft.bench.config import Bench, InstrumentConfig, TableConfig
from gonio.specs.ogam_draft.budget import annex_a_budget
from gonio.specs.ogam_draft.compensation import (computed_compensation, computed_residual_dps,
                                measured_compensation)
from gonio.physics.earth import OMEGA_E_ARCSEC_S
from gonio.errors import GonioError
from gonio.specs.ogam_draft.protocol import parse_protocol

D = 0.01     # degrees: small enough for the linearisation to hold to ~1e-4


@pytest.mark.parametrize("lat", [0.0, 25.0, 40.0, 80.0])
def test_latitude_sensitivity_against_exact_residual(lat):
    for axis in ("up", "north", "east", "30,20"):
        # Central difference of the exact residual (second-order terms cancel).
        exact = abs(computed_residual_dps(lat, axis, compensation_latitude_deg=lat + D)
                    - computed_residual_dps(lat, axis, compensation_latitude_deg=lat - D)) \
            / 2 * 3600
        lin = computed_compensation(lat, axis, u_latitude_deg=D).u_rate_arcsec_s
        assert lin == pytest.approx(exact, rel=1e-6, abs=1e-12)


def test_textbook_values_of_the_three_axes():
    # Up: Ω cos φ δφ; north: Ω sin φ δφ; east: Ω cos φ δA (closed forms of Ω·a).
    phi, d = math.radians(40.0), math.radians(D)
    up = computed_compensation(40.0, "up", u_latitude_deg=D)
    assert up.u_rate_arcsec_s == pytest.approx(OMEGA_E_ARCSEC_S * math.cos(phi) * d, rel=1e-12)
    north = computed_compensation(40.0, "north", u_latitude_deg=D)
    assert north.u_rate_arcsec_s == pytest.approx(OMEGA_E_ARCSEC_S * math.sin(phi) * d, rel=1e-12)
    east = computed_compensation(40.0, "east", u_azimuth_deg=D)
    assert east.u_rate_arcsec_s == pytest.approx(OMEGA_E_ARCSEC_S * math.cos(phi) * d, rel=1e-12)
    # Azimuth does not matter for a vertical axis, and only to second order due north.
    assert computed_compensation(40.0, "up", u_azimuth_deg=1.0).u_rate_arcsec_s == 0.0
    assert computed_compensation(40.0, "north", u_azimuth_deg=1.0).u_rate_arcsec_s < 1e-12
    assert abs(computed_residual_dps(40.0, "north", azimuth_error_deg=1.0) * 3600) == \
        pytest.approx(OMEGA_E_ARCSEC_S * math.cos(phi) * (1 - math.cos(math.radians(1))),
                      rel=1e-9)


def test_levelling_sensitivity_against_exact_tilted_axes():
    for lat in (10.0, 40.0, 70.0):
        # Vertical axis leaning D towards north, compensated as if vertical: exact
        # residual vs the linear levelling term ...
        exact_n = abs(computed_residual_dps(lat, (0.0, 90.0 - D), elevation_error_deg=D)) * 3600
        # ... and leaning towards east (the d_X direction of a vertical axis: 2nd order).
        exact_e = abs(computed_residual_dps(lat, (90.0, 90.0 - D), elevation_error_deg=D)) * 3600
        assert exact_n == pytest.approx(OMEGA_E_ARCSEC_S * math.cos(math.radians(lat))
                                        * math.radians(D), rel=1e-3)
        lin = computed_compensation(lat, "up", u_level_deg=D).u_rate_arcsec_s
        assert lin == pytest.approx(math.hypot(exact_n, exact_e), rel=1e-3)
        # Horizontal axis north raised by D.
        exact = abs(computed_residual_dps(lat, "north", elevation_error_deg=D)) * 3600
        lin = computed_compensation(lat, "north", u_level_deg=D).u_rate_arcsec_s
        assert lin == pytest.approx(exact, rel=1e-3)


def test_bias_stays_in_a_computed_compensation_and_angle_scales_with_time():
    r = computed_compensation(40.0, "up", bias_dph=0.01, measuring_time_s=20.0)
    assert r.rate_arcsec_s == pytest.approx(0.01)           # 1 °/h = 1″/s
    assert r.angle_arcsec == pytest.approx(0.2)
    assert r.angle_error_arcsec([10.0, 30.0]).tolist() == pytest.approx([0.1, 0.3])


def test_measured_compensation_scatter_on_the_bench():
    """comp − K·Ω·a over seeds scatters as N/√T and the counter quantum predict."""
    k, arw, lat, static = 76434.87, 0.002, 40.0, 20.0
    inst = InstrumentConfig(nominal_scale_factor_counts_per_deg=k, arw_dpsh=arw)
    bench = Bench("b", inst, TableConfig(), latitude_deg=lat, sample_rate_hz=100.0)
    proto = parse_protocol({"protocol": {"name": "m"},
                            "session": {"earth_compensation": "measured", "static_s": static},
                            "angle_deviation": {"series": 1, "rest_s": 1.0, "read_delay_s": 0.5,
                                                "rounds": [{"stop_deg": 30.0}]}})
    true_rate = OMEGA_E_ARCSEC_S * math.sin(math.radians(lat))         # ″/s on the up axis
    err = []
    for seed in range(150):
        res = run_session(proto, bench, seed=seed)
        comp = res.truth["earth_compensation_counts_per_s"][0] / k * 3600.0
        err.append(comp - true_rate)
    err = np.array(err)
    u = measured_compensation(static, arw_dpsh=arw, scale_factor_counts_per_deg=k)
    assert set(u.components_arcsec_s) == {"angle_random_walk", "bias_instability", "quantisation"}
    assert abs(err.mean()) < 4 * u.u_rate_arcsec_s / math.sqrt(err.size)
    assert 0.85 < err.std(ddof=1) / u.u_rate_arcsec_s < 1.15


def test_budget_component_is_optional_and_adds_in_quadrature():
    base = annex_a_budget()
    r = measured_compensation(60.0, arw_dpsh=0.0005, measuring_time_s=30.0)
    with_c = annex_a_budget(extra_components=[compensation_component(r)])
    assert with_c.gum.u_c == pytest.approx(math.hypot(base.gum.u_c, r.u_angle_arcsec), rel=1e-9)
    assert len(base.gum.contributions) == 4


def test_bad_inputs():
    with pytest.raises(GonioError):
        measured_compensation(0.0)
    with pytest.raises(GonioError):
        computed_compensation(40.0, "up", u_latitude_deg=-1.0)
    with pytest.raises(GonioError):
        computed_compensation(95.0, "up")
