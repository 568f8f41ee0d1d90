"""Tilt × Earth-rate coupling: the analytic error (gonio.specs.ogam_draft.coupling) against the virtual bench,
the quadrature against adaptive quadrature, the worst case against a brute-force search."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.integrate import quad

from gonio.specs.ogam_draft.bench import run_session
from gonio.specs.ogam_draft.bench.config import Bench, InstrumentConfig, TableConfig
from gonio.specs.ogam_draft.bench.session import plan_session
from gonio.specs.ogam_draft.budget import annex_a_budget
from gonio.specs.ogam_draft.budget_extra import coupling_budget_component, session_coupling
from gonio.specs.ogam_draft.coupling import (coupling_error_arcsec, coupling_terms,
                            coupling_worst_case_arcsec,
                            trig_integrals)
from gonio.physics.earth import OMEGA_E_ARCSEC_S, earth_rate_split
from gonio.physics.kinematics import Timeline
from gonio.specs.ogam_draft.protocol import load_protocol, parse_protocol

K_NOM = 76434.87


def protocol(compensation="measured", rounds=(30.0, 90.0, 150.0, 210.0, 270.0, 360.0),
             orientation="up"):
    return parse_protocol({
        "protocol": {"name": "coupling"},
        "session": {"earth_compensation": compensation, "static_s": 20.0, "settle_s": 2.0},
        "angle_deviation": {"series": 1, "rest_s": 12.0, "read_delay_s": 10.0,
                            "orientation": orientation,
                            "rounds": [{"stop_deg": x} for x in rounds]},
    })


def ideal_bench(psi, alpha_table, lat, **kw):
    inst = InstrumentConfig(type="rlg", nominal_scale_factor_counts_per_deg=K_NOM,
                            quantisation=False, tilt_deg=psi, tilt_azimuth_deg=alpha_table, **kw)
    return Bench("ideal", inst, TableConfig(), latitude_deg=lat, sample_rate_hz=200.0)


def bench_errors(psi, alpha_table, lat, orientation, compensation="measured"):
    """E from the bench's truth (noise-free, the mount K) per angle_deviation reading."""
    res = run_session(protocol(compensation, orientation=orientation),
                      ideal_bench(psi, alpha_table, lat), seed=0)
    t = pd.DataFrame(res.truth["readings"])
    return t[t.test == "angle_deviation"]["systematic_deviation_arcsec"].to_numpy()


@pytest.mark.parametrize("orientation", ["up", "north", "east"])
@pytest.mark.parametrize("lat", [0.0, 40.0, 80.0])
def test_bench_shows_the_analytic_coupling(orientation, lat):
    alpha_table = 70.0
    for psi in (0.05, 0.1, 0.5):
        bench = bench_errors(psi, alpha_table, lat, orientation)
        sc = session_coupling(protocol(orientation=orientation),
                              ideal_bench(psi, alpha_table, lat))
        analytic = sc.error_arcsec
        scale = np.max(np.abs(analytic))
        perp = earth_rate_split(lat, orientation).perpendicular_dps * 3600
        if perp < 1e-6:                   # axis along the Earth's axis: nothing to couple
            assert np.max(np.abs(bench)) < 1e-7
            assert scale < 1e-9
            continue
        # Independent size check: the dwell at 180°-ish makes it about 2 Ω_⊥ sin ψ × 10 s.
        assert scale > 0.2 * perp * math.sin(math.radians(psi)) * 10
        np.testing.assert_allclose(bench, analytic, rtol=0, atol=0.01 * scale)


def test_bench_computed_compensation_matches():
    # Computed compensation leaves (cos ψ − 1)Ω·a as well; at ψ = 0.5° and 40° N.
    for orientation in ("up", "north"):
        p = protocol("computed", orientation=orientation)
        b = ideal_bench(0.5, 200.0, 40.0)
        bench = bench_errors(0.5, 200.0, 40.0, orientation, "computed")
        analytic = session_coupling(p, b).error_arcsec
        np.testing.assert_allclose(bench, analytic, rtol=0,
                                   atol=0.01 * np.max(np.abs(analytic)))


@pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")
def test_quadrature_against_adaptive_quad():
    tl = Timeline()
    tl.dwell(2.0)
    tl.move(250.0, 300.0, 60.0)         # triangular? no: 300²/60 = 1500° > 250°: triangular
    tl.dwell(3.0)
    tl.move(17.0, 10.0, 25.0)
    tl.dwell(1.0)
    for ta, tb in ((0.0, tl.end_s), (1.3, 5.7), (2.5, 2.6), (4.0, tl.end_s - 0.5)):
        c, s = trig_integrals(tl, ta, tb)
        brk = [x for x in np.linspace(0, tl.end_s, 400) if ta < x < tb]
        f_c = lambda t: math.cos(math.radians(float(tl.angle_deg(np.array([t]))[0])))
        f_s = lambda t: math.sin(math.radians(float(tl.angle_deg(np.array([t]))[0])))
        qc = quad(f_c, ta, tb, points=brk or None, limit=2000, epsabs=1e-14, epsrel=1e-13)[0]
        qs = quad(f_s, ta, tb, points=brk or None, limit=2000, epsabs=1e-14, epsrel=1e-13)[0]
        assert c == pytest.approx(qc, rel=1e-9, abs=1e-12)
        assert s == pytest.approx(qs, rel=1e-9, abs=1e-12)


def test_dwell_closed_form_and_worst_case():
    tl = Timeline()
    tl.move(120.0, 60.0, 60.0)
    t_arr = tl.end_s
    tl.dwell(30.0)
    perp = 11.522126 / 3600
    psi, alpha = 0.1, 35.0
    e1 = coupling_error_arcsec(tl, 0.0, t_arr + 5.0, psi, alpha, perp)[0]
    e2 = coupling_error_arcsec(tl, 0.0, t_arr + 15.0, psi, alpha, perp)[0]
    # At rest at 120°: slope Ω_⊥ tan ψ [cos(120°+α) − cos α], the formula of the draft notes.
    slope = perp * 3600 * math.tan(math.radians(psi)) * (
        math.cos(math.radians(120 + alpha)) - math.cos(math.radians(alpha)))
    assert (e2 - e1) / 10.0 == pytest.approx(slope, rel=1e-12)
    # Worst case over α = brute-force maximum over a fine grid.
    terms = coupling_terms(tl, 0.0, t_arr + 15.0, psi, perp)
    grid = np.linspace(0, 360, 360001)
    brute = np.max(np.abs(terms.error_arcsec(grid)))
    assert coupling_worst_case_arcsec(tl, 0.0, t_arr + 15.0, psi, perp)[0] == \
        pytest.approx(brute, rel=1e-9)


def table_frame(lat, orientation):
    sp = earth_rate_split(lat, orientation)
    return sp.parallel_dps, sp.perpendicular_dps, sp.perpendicular_direction_deg


def test_table_frame_directions():
    # Up: Ω_⊥ = Ω cos φ; north: Ω sin φ; east: Ω (all of it across the axis).
    assert table_frame(40.0, "up")[1] * 3600 == pytest.approx(
        OMEGA_E_ARCSEC_S * math.cos(math.radians(40)), rel=1e-12)
    assert table_frame(40.0, "north")[1] * 3600 == pytest.approx(
        OMEGA_E_ARCSEC_S * math.sin(math.radians(40)), rel=1e-12)
    assert table_frame(40.0, "east")[1] * 3600 == pytest.approx(OMEGA_E_ARCSEC_S, rel=1e-12)


def test_budget_component_off_by_default_and_adds_in_quadrature():
    base = annex_a_budget()
    comp = coupling_budget_component(load_protocol("ogam-draft"), 40.0, 0.1)
    with_c = annex_a_budget(extra_components=[comp])
    u_c = comp.half_width_arcsec / math.sqrt(2)            # arcsine, JCGM 101 6.4.6
    assert with_c.gum.u_c == pytest.approx(math.hypot(base.gum.u_c, u_c), rel=1e-9)
    assert len(base.gum.contributions) == 4
