"""E's physical budget per 7.4 point, each line against the bench's truth with that effect
alone, or against a Monte Carlo of the measurement chain written out here (never the
budget's own formula); and the coverage study's draws of the table's error sizes and of the
drift within their bounds. The draft's Annex A reading (one budget for every point) is
pinned elsewhere (tests/test_budget.py, `gonio budget`) and is not touched."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.budget_extra import budget_extra_components, table_line_u
from gonio.specs.ogam_draft.calibration import analyse
from gonio.specs.ogam_draft.readings import Readings
from gonio.specs.ogam_draft.study import (draw_type_b, ideal_bench, tilted,
                                          validation_protocol)

STOPS = np.array([60.0, 120.0, 180.0, 240.0, 300.0, 360.0])     # the built-in 7.1 rounds
POINTS = np.arange(30.0, 361.0, 30.0)                          # the built-in 7.4 points


def _e_chain(theta_i, err_at, k_true=76434.87):
    """E_i of the whole chain, nonlinear: the table turns from its zero to θ with error
    e(θ) − e(0) (e(360°) = e(0): one position); counts C = K (θ + e(θ) − e(0)); the 7.1 K =
    mean C_k/θ_k; E_i = C_i/K − θ_i (″)."""
    def turned(th):
        return th + (err_at(th) - err_at(0.0)) / 3600.0
    k = np.mean([k_true * turned(t) / t for t in STOPS], axis=0)
    return (k_true * turned(theta_i) / k - theta_i) * 3600.0


def test_table_line_against_a_monte_carlo_of_the_chain():
    """Independent positioning errors, uniform within ±MPE at each table position (A.4.1):
    the sd of E_i from the whole chain equals table_line_u at 30°, 180° and 360° (2 %).
    Annex A's constant P with K_P at θ_max (0.168″ at 30°) is 2.3× the chain's 0.075″."""
    rng = np.random.default_rng(11)
    mpe, n = 0.1, 200_000
    pos = sorted({0.0, *STOPS % 360.0, *POINTS % 360.0})
    draws = {p: rng.uniform(-mpe, mpe, n) for p in pos}
    err_at = lambda th: draws[th % 360.0]                                  # noqa: E731
    for th in (30.0, 180.0, 360.0):
        sd = float(np.std(_e_chain(th, err_at)))
        assert table_line_u(th, STOPS, mpe / math.sqrt(3)) == pytest.approx(sd, rel=0.02)
    old = math.hypot(mpe / math.sqrt(3), 0.158)
    assert old > 2 * float(np.std(_e_chain(30.0, err_at)))



def test_table_line_counter_clockwise_points_take_their_own_positions():
    """A counter-clockwise 7.4 point (negative θ) reaches the table position θ mod 360: −60°
    is 300°, a 7.1 stop's position, whose error then enters twice; −300° is 60°. The chain
    (the table's error keyed by position) gives the sd that table_line_u gives for the signed
    angle (2 %); taking |θ| put −60° at 60° (a different sd)."""
    rng = np.random.default_rng(12)
    mpe, n = 0.1, 200_000
    pos = sorted({0.0, *STOPS % 360.0, *(-POINTS) % 360.0})
    draws = {p: rng.uniform(-mpe, mpe, n) for p in pos}
    err_at = lambda th: draws[th % 360.0]                                  # noqa: E731
    for th in (-60.0, -150.0, -300.0):
        sd = float(np.std(_e_chain(th, err_at)))
        assert table_line_u(th, STOPS, mpe / math.sqrt(3)) == pytest.approx(sd, rel=0.02), th
    assert abs(table_line_u(60.0, STOPS, mpe / math.sqrt(3))
               - float(np.std(_e_chain(-60.0, err_at)))) > 0.01

def test_scale_factor_reading_line_grows_with_the_point():
    """K_r at θ: noise u_k on each 7.1 reading alone moves E_i by −θ δK/K; a Monte Carlo of
    the chain (counts with the readings' noise, K the mean of C_k/θ_k) gives the line at θ,
    and θ/θ_max of it at θ < θ_max (the old constant line is the θ_max value everywhere)."""
    p = validation_protocol()
    rng = np.random.default_rng(5)
    u_k = np.array([0.02, 0.025, 0.03, 0.035, 0.04, 0.045])        # ″, one per 7.1 reading
    n = 200_000
    noise = rng.normal(0.0, 1.0, (n, STOPS.size)) * u_k
    k_rel = np.mean(1.0 + noise / 3600.0 / STOPS, axis=1)          # K/K_true
    import pandas as pd
    df = pd.DataFrame({"test": ["scale_factor"] * 6 + ["angle_deviation"] * 12,
                       "table_deg": [*STOPS, *POINTS], "time_s": [12.0] * 18})
    for th in (30.0, 150.0, 360.0):
        sd = float(np.std((th / k_rel - th) * 3600.0))
        line = {c.symbol: c.half_width_arcsec for c in budget_extra_components(
            df, p, 40.0, 0.1, theta_deg=th, sf_reading_u_arcsec=u_k)}["K_r"]
        assert line == pytest.approx(sd, rel=0.02), th


@pytest.fixture(scope="module")
def tilt_only():
    """The rlg instrument on an ideal set-up (no noise, Earth rate, bias, table error),
    tilted at the A.1 bound, and untilted: the tilt's scale error alone (A.4.2)."""
    proto = validation_protocol(all_items=True)
    base = ideal_bench(replace(load_bench("rlg"), sample_rate_hz=5.0))
    out = []
    for b in (tilted(base, 0.1, 30.0), base):
        res = run_session(proto, b, seed=1)
        df = res.readings.copy()
        df["line"] = np.arange(2, len(df) + 2)
        out.append(analyse(Readings(df, dict(res.metadata)), proto, budget="physical"))
    return out


def test_phi_e_is_absorbed_by_the_7_1_k(tilt_only):
    """Tilted at the bound, E_i equals the untilted instrument's to 1 mas at every point
    (the 7.1 K, measured on the same mount, carries the cos ψ), while A.4.2's line is
    0.045″: the physical budget's φ_e is 0, the draft's stays."""
    tilt, flat = tilt_only
    d = tilt.results.angle_deviation.table["E_arcsec"].to_numpy() - \
        flat.results.angle_deviation.table["E_arcsec"].to_numpy()
    assert np.abs(d).max() < 1e-3, d
    comps = {c.symbol: c.u_xi for c in tilt.uncertainty.gum.contributions}
    assert comps["phi_e"] == 0.0
    from gonio.specs.ogam_draft.tilt import elliptic_extreme
    assert elliptic_extreme(0.1).extreme_arcsec / math.sqrt(3) > 0.04


def test_certified_u_is_the_largest_points_u(tilt_only):
    """E = ± max|E_i| is stated with the largest of the per-point U (the points' u_c differ:
    the table and K lines depend on θ, the drift on the point's time), so every point's
    interval |E_i| ± U_i lies inside the stated max|E_i| ± U, whichever point is extreme."""
    rep = tilt_only[0]
    e = rep.results.angle_deviation
    pts = rep.uncertainty.points
    assert [p["position_deg"] for p in pts] == list(e.table["position_deg"])
    U_i = np.array([p["U_arcsec"] for p in pts])
    assert rep.uncertainty.U_arcsec == U_i.max()
    E_abs = np.abs(e.table["E_arcsec"].to_numpy())
    assert np.all(E_abs + U_i <= E_abs.max() + rep.uncertainty.U_arcsec + 1e-12)
    u = np.array([p["u_c_arcsec"] for p in pts])
    assert u.min() > 0 and u.max() - u.min() > 0.01, u


def test_study_draws_table_sizes_and_drift_within_their_bounds():
    """The bench-shape draws (``table_errors="shape"``, worsttable's before its sizes are put at
    the bound) take the harmonics' sum uniform in [0, MPE − 3σ] (shape kept) and the bias
    instability uniform in [0, 0.005/√2] °/h: a Kolmogorov–Smirnov test against the
    uniform, and both reach near their bounds."""
    from scipy import stats
    p = validation_protocol()
    b = load_bench("rlg")
    t = b.table
    room = t.mpe_arcsec - 3 * t.positioning_random_arcsec
    ratio = [h.amplitude_arcsec / t.positioning_harmonics[0].amplitude_arcsec
             for h in t.positioning_harmonics]
    sums, sig = [], []
    for s in range(300):
        d = draw_type_b(b, p, s, table_errors="shape")    # worsttable's draws (typeb: per position)
        hs = d.table.positioning_harmonics
        assert [h.amplitude_arcsec / hs[0].amplitude_arcsec for h in hs] == \
            pytest.approx(ratio)
        sums.append(sum(abs(h.amplitude_arcsec) for h in hs) / room)
        sig.append(d.instrument.bias_instability_dph / (0.005 / math.sqrt(2)))
    for x in (sums, sig):
        assert stats.kstest(x, "uniform").pvalue > 0.01
        assert max(x) <= 1.0 and max(x) > 0.95 and min(x) < 0.05


def test_harmonic_table_model_against_a_monte_carlo_of_the_chain():
    """The table's error one periodic curve a·sin(h·x + φ), a uniform in [0, MPE], φ
    uniform: the chain's sd of E_i at the model's worst order equals table_harmonic_line_u
    (2 %) and no order 1 … 11 gives more; at the bound (a = MPE) the largest |E_i| reaches
    its half-width. Positions are multiples of 30°, so order 12 moves nothing."""
    from gonio.specs.ogam_draft.budget_extra import table_harmonic_line_u

    rng = np.random.default_rng(13)
    mpe, n = 0.1, 200_000
    a, ph = rng.uniform(0.0, mpe, n), rng.uniform(0.0, 2 * math.pi, n)
    for th in (30.0, 180.0, 360.0):
        m = table_harmonic_line_u(th, STOPS, mpe)
        sds = {}
        for h in range(1, 13):
            err_at = lambda x, h=h: a * np.sin(h * math.radians(x) + ph)      # noqa: E731
            sds[h] = float(np.std(_e_chain(th, err_at)))
        assert sds[m["order"]] == pytest.approx(m["u_arcsec"], rel=0.02), th
        assert max(sds.values()) <= m["u_arcsec"] * 1.02 and sds[12] < 1e-6
        at_bound = lambda x: mpe * np.sin(m["order"] * math.radians(x) + ph)  # noqa: E731
        big = float(np.max(np.abs(_e_chain(th, at_bound))))
        assert big == pytest.approx(m["half_width_at_bound_arcsec"], rel=0.01)


def test_study_checks_the_stated_maximum_against_the_truths_maximum():
    """The statement E = ± max|E_i| with its U is judged against the truth's max|E_i| (the
    intrinsic truth for the physical budget): trial 1 states −0.30″ ± 0.15″ where the truth's
    largest |E_i| is 0.20″ (inside); trial 2 states 0.50″ ± 0.20″ against 0.20″ (outside)."""
    from gonio.specs.ogam_draft.item_coverage import item_coverage

    def rec(points, value, U):
        e = {"value": value, "U": U, "u_c": U / 2, "k": 2.0, "interval": None, "truth": None,
             "points": points, "truth_points": [9.0, 9.0], "U_points": [U, U],
             "u_c_points": [U / 2, U / 2]}
        return {"angle_deviation": e}

    recs = [rec([0.1, -0.3], -0.3, 0.15), rec([0.5, 0.0], 0.5, 0.2)]
    m = item_coverage(recs, intrinsic_points=[0.05, -0.2])["angle_deviation"]["max_statement"]
    assert (m["hits"], m["n"], m["truth"]) == (1, 2, "intrinsic")
    assert m["z_mean"] == pytest.approx(((0.3 - 0.2) / 0.075 + (0.5 - 0.2) / 0.1) / 2)
