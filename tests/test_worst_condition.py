"""The optical scale factor's and nonlinearity's uncertainties at the worst condition the
draft allows (tilt at the A.1 bound, the azimuth where the tilt × Earth-rate coupling
biases the 7.1 K most), against the instrument's truth from the bench file; and the pieces
the studies rest on, each against a second calculation: the truth's closed form against an
ideal-set-up session, the worst azimuth against a brute search, the disc model's u against
a Monte Carlo of the mountings, the Type B draws against their stated distributions."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from gonio.analysis.coverage import clopper_pearson
from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.bench.instrument import harmonic_sum_arcsec
from gonio.specs.ogam_draft.readings import Readings
from gonio.specs.ogam_draft.calibration import analyse
from gonio.specs.ogam_draft.item_coverage import disc_model_u, item_record, scale_factor_truth
from gonio.specs.ogam_draft.item_uncertainty import nonlinearity_corrected_budget
from gonio.specs.ogam_draft.study import (TABLE_RATE_ERROR_BOUND, case_bench, coupling_bias,
                                          draw_type_b, ideal_bench, tilted, validation_protocol,
                                          worst_azimuth)

TRIALS = 40
CV_TRIALS = 30


@pytest.fixture(scope="module")
def proto():
    return validation_protocol()          # 7.1 and 7.4: K and K_l are measured


@pytest.fixture(scope="module")
def base():
    return replace(load_bench("rlg"), sample_rate_hz=5.0)


@pytest.fixture(scope="module")
def worst(proto, base):
    return case_bench("worst", base, proto)


def _errors(proto, bench, seeds):
    """Per trial, for K: (stated value − truth, U, u_c — K corrected by the built-in
    protocol's tilt estimate —, the draft's 7.1 mean − truth, its U with the K_tilt line at
    the bound, its u_c, that U less its K_tilt line, U disc model); for K_l: (corrected
    value − truth, U, u_c, the same corrected without the tilt coupling − truth, its u_c, the
    draft's range as measured − truth, its u_c, 1 where the stated 95 % interval — the
    range's confidence belt, not value ± U — holds the truth)."""
    out = {"K": [], "K_l": []}
    for s in seeds:
        res = run_session(proto, bench, seed=s)
        df = res.readings.copy()
        df["line"] = np.arange(2, len(df) + 2)
        rep = analyse(Readings(df, dict(res.metadata)), proto, budget="draft")
        k_true, k_i = scale_factor_truth(res.truth)
        kl_true = (k_i.max() - k_i.min()) / k_i.mean() * 100.0
        b = rep.item_uncertainty["scale_factor"]
        assert b.correction is not None                  # corrected by the measured tilt
        d = b.beside                                     # the draft's 7.1 mean, K_tilt line
        tilt2 = sum(c.u ** 2 for c in d.components if c.symbol == "K_tilt")
        assert tilt2 > 0                                 # the line is there
        out["K"].append((b.value - k_true, b.U, b.u_c, d.value - k_true, d.U, d.u_c,
                         d.k * math.sqrt(d.u_c ** 2 - tilt2), d.k * disc_model_u(d)))
        b = rep.item_uncertainty["scale_factor_nonlinearity"]
        t = rep.results.scale_factor.table
        no_tilt = nonlinearity_corrected_budget(t["K_i_counts_per_deg"], t["table_deg"],
                                                rep.uncertainty.parameters["table_mpe_arcsec"],
                                                k=b.k)
        out["K_l"].append((b.value - kl_true, b.U, b.u_c, no_tilt.value - kl_true, no_tilt.u_c,
                           b.beside.value - kl_true, b.beside.u_c,
                           float(b.interval[0] <= kl_true <= b.interval[1])))
    return {k: np.array(v) for k, v in out.items()}


@pytest.fixture(scope="module")
def at_worst(proto, worst):
    return _errors(proto, worst, range(900, 900 + TRIALS))


def _cp(err, U):
    hits = int(np.count_nonzero(np.abs(err) <= U))
    return hits, clopper_pearson(hits, err.size)


def test_scale_factor_covers_at_the_worst_condition(at_worst):
    """K as the built-in protocol states it (corrected by the measured tilt, line K_te)
    covers at the worst condition with z = (K − truth)/u_c centred (|mean| < 0.5; 40 of 40,
    z +0.34, sd 0.55 on this one set-up, whose table errors are fixed inside their MPE: the
    spread is judged where they are drawn, tests/test_k_tilt_correction.py). The draft's 7.1 mean beside it, U with the coupling at the
    bound (arcsine, worst azimuth), covers too but is biased by the coupling (z mean > 0.8,
    sd < 0.7: a deterministic bias that a bound line widens for and cannot centre); without
    that line it is biased, z mean > 0.8 (it covered < 95 % while K's table line took the
    positions independent; the worst-combination line hides the bias in U). (The disc model's narrower line covered 85 % here while K's
    table line took the stops as independent; with the table's one periodic error at the
    bound, P_K fills what the disc model leaves, so it is not asserted.)"""
    d, U, u_c, d_draft, U_draft, u_draft, U_no, U_disc = at_worst["K"].T
    hits, (lo, hi) = _cp(d, U)
    assert hi >= 0.95, (hits, lo, hi)
    z = d / u_c
    assert abs(np.mean(z)) < 0.5, np.mean(z)
    assert _cp(d_draft, U_draft)[1][1] >= 0.95
    z_draft = d_draft / u_draft
    assert np.mean(z_draft) > 0.8 and np.std(z_draft, ddof=1) < 0.7
    # without that line the draft's K is biased by the coupling (its coverage is no test
    # now: K's table line, the worst combination within the MPE, is wide enough to hide it)
    u_no = U_no * u_draft / U_draft
    assert np.mean(d_draft / u_no) > 0.8, np.mean(d_draft / u_no)
    assert np.all(U_disc < U_draft)
    assert np.mean(d_draft) > 0.5 * np.mean(U_draft - U_no)   # the bias is really there


def test_nonlinearity_covers_at_the_worst_condition(at_worst):
    """K_l corrected for the range's bias (the rounds' errors) and each round for its tilt
    coupling at the tilt the built-in programme measured covers the instrument's own K_l at
    the worst condition, z = (K_l − truth)/u_c centred (|mean| < 0.5; 40 of 40, z −0.13, sd
    0.45 on this one set-up, whose table errors are fixed inside their MPE while u holds the
    table at its bound); corrected for the table and quantisation alone, the rounds as
    measured, it is left biased (z mean > 0.5: +0.73; its U, widened by the table-at-the-bound
    line, covered anyway, where it did not before that line); the draft's range as measured is
    biased upwards by about one u_c (z mean > 0.8: the bias that its widened U hid)."""
    d, U, u_c, d_no, u_no, d_draft, u_draft, held = at_worst["K_l"].T
    hits = int(held.sum())
    lo, hi = clopper_pearson(hits, held.size)      # the stated interval holding the truth
    assert hi >= 0.95, (hits, lo, hi)
    assert abs(np.mean(d / u_c)) < 0.5, np.mean(d / u_c)
    assert np.mean(d_no / u_no) > 0.5              # without the tilt's draws it is biased
    assert np.mean(d_draft / u_draft) > 0.8


@pytest.fixture(scope="module")
def drawn_k_l(proto, base):
    """K_l's errors over TRIALS ``typeb`` trials (seeds 700–739): (z, the draft's z, hits)."""
    z, z_draft, hits = [], [], 0
    for s in range(700, 700 + TRIALS):
        d = _errors(proto, draw_type_b(base, proto, s), [s])["K_l"][0]
        z.append(d[0] / d[2])
        z_draft.append(d[5] / d[6])
        hits += d[7] > 0.5                 # the stated interval holds the truth
    return np.array(z), np.array(z_draft), int(hits)


def test_nonlinearity_z_on_drawn_type_b_effects(drawn_k_l):
    """With every Type B effect of the set-up drawn per trial (the ``typeb`` case), the
    corrected K_l's z = (K_l − truth)/u_c has its mean within ±0.5 (+0.03 here; −0.18 with the
    table at its bound in u; −0.53 with u the standard's reading alone and the measured
    range's spread; −0.93, sd 0.85, when the correction took the tilt at the bound) and sd at
    most 1.3 (0.83 here, the table's errors as K's; 0.44 with the table at its bound in u,
    over-wide); the draft's range as measured, with U widened for its bias, has z mean ≈ +1
    and sd below 0.7 (over-wide and biased)."""
    z, z_draft, _ = drawn_k_l
    assert abs(z.mean()) < 0.5 and z.std(ddof=1) <= 1.3, (z.mean(), z.std(ddof=1))
    assert z_draft.mean() > 0.8 and z_draft.std(ddof=1) < 0.7


@pytest.mark.xfail(strict=True, reason="K_l holds every table within the MPE (the table's worst "
                   "shift of the range on the belt's ends, K_tab): over-wide on drawn tables, "
                   "the price K's table line pays too (docs/validation-optical.md)")
def test_nonlinearity_z_not_over_wide_on_drawn_type_b_effects(drawn_k_l):
    """z's sd at least 0.7 on drawn Type B effects (too wide is a fault as well): 0.83 on
    seeds 700–739 (z mean +0.03, 40 of 40 covered) with the table's errors taken as K's (each
    position rectangular ±MPE, the zero shared), which missed the corner table (35/40 in the
    study); 0.44 when u held the table at its A.4.1 bound of the worst order. Since K_l takes
    the table by its bound on the belt's ends (every table within the MPE held), over-wide
    again on these drawn tables (seeds 700–739: z sd 0.51; the study's `typeb`: 0.47): a strict xfail, which
    fails once the width is regained without losing the corner."""
    z = drawn_k_l[0]
    assert z.std(ddof=1) >= 0.7, z.std(ddof=1)


def test_nonlinearity_covers_on_drawn_type_b_effects(drawn_k_l):
    """The corrected K_l's stated interval covers on drawn Type B effects (Clopper–Pearson reaching 95 %):
    its rounds' error model carries the gyro's angle noise over each round (the angle random
    walk estimated from the 7.4 series, and the measured compensation's rate error); without
    it 34 of 40 covered (with the tilt at the bound); 37 of 40 with each round corrected at
    the measured tilt; 40 of 40 with the table-at-the-bound line and the estimator's slope."""
    hits = drawn_k_l[2]
    assert clopper_pearson(hits, TRIALS)[1] >= 0.95, hits


def test_truth_closed_form_matches_an_ideal_session(proto, base):
    """scale_factor_truth's closed form against the noise-free counts of the same
    instrument, mounted with the same tilt, on a set-up with no Earth rate, bias, drift or
    table error (a second calculation: the bench's counter integrated over the session)."""
    b = ideal_bench(base)
    b = replace(tilted(b, 0.1, 77.0), earth_rate=False)
    res = run_session(proto, b, seed=0)
    tr = pd.DataFrame(res.truth["readings"])
    sf = tr[tr["test"] == "scale_factor"]
    k_sim = sf["noise_free_counts"].to_numpy(float) / sf["true_table_deg"].to_numpy(float)
    k, k_i = scale_factor_truth(res.truth)
    assert np.max(np.abs(k_i / k_sim - 1.0)) < 2e-9          # count floor: 1/K/θ ≲ 2e-7
    assert abs(k / np.mean(k_sim) - 1.0) < 1e-9
    # the angle-position error is in it (the instrument's), the tilt's cos ψ too
    assert np.ptp(k_i) > 0 and k < base.instrument.true_scale_factor_counts_per_deg


def test_worst_azimuth_beats_a_brute_search(proto, base):
    """The three-session formula's azimuth gives a noise-free bias of K at least as large
    as any of 12 azimuths tried one by one."""
    az = worst_azimuth(base, proto, 0.1)
    top = abs(coupling_bias(tilted(base, 0.1, az), proto))
    tried = [abs(coupling_bias(tilted(base, 0.1, a), proto)) for a in range(0, 360, 30)]
    assert top >= max(tried) * (1 - 1e-9) and top > 2 * min(tried)


def test_disc_model_u_is_the_projection_of_a_uniform_disc():
    """u = A/2 of the coupling A·(ψ/ψ_max)·cos(α − α₀) over tilts uniform on the disc,
    against a Monte Carlo of the mountings (and the bound's arcsine, A/√2, beside it)."""
    rng = np.random.default_rng(1)
    psi = np.sqrt(rng.uniform(size=400_000))
    x = psi * np.cos(rng.uniform(0, 2 * math.pi, psi.size) - 0.7)
    assert np.std(x) == pytest.approx(0.5, rel=0.01)
    assert np.std(np.cos(rng.uniform(0, 2 * math.pi, psi.size))) == \
        pytest.approx(1 / math.sqrt(2), rel=0.01)


def test_type_b_draws_follow_their_stated_distributions(proto):
    """draw_type_b: tilt uniform over the disc, azimuths and phases uniform, the amplitudes'
    sizes drawn within the table's MPE, the rate error uniform within Table 1's bound."""
    b = load_bench("rlg")
    d = [draw_type_b(b, proto, s) for s in range(3000)]
    bound = proto.annex_a.tilt_bound_deg
    psi = np.array([x.instrument.tilt_deg for x in d])
    assert psi.max() <= bound and np.mean(psi ** 2) / bound ** 2 == pytest.approx(0.5, abs=0.02)
    for vals in ([x.instrument.tilt_azimuth_deg for x in d],
                 [x.table.positioning_harmonics[0].phase_deg for x in d],
                 [x.table.wobble_phase_deg for x in d],
                 [x.table.axis_setup_azimuth_deg for x in d]):
        a = np.radians(vals)
        assert abs(np.mean(np.cos(a))) < 0.05 and abs(np.mean(np.sin(a))) < 0.05
    # the table's error a smooth random curve (study.drawn_table_curve): within what the MPE
    # leaves beside the scatter's 3σ (A.4.1; a constant cancels in every angle turned, so
    # the range is checked), its size drawn (not at the bound), and neighbouring 30°
    # positions correlated as one curve's (positions drawn independently give −1/11)
    room = b.table.mpe_arcsec - 3 * b.table.positioning_random_arcsec
    x = np.arange(0.0, 360.0, 30.0)
    e = np.array([harmonic_sum_arcsec(x, t.table.positioning_harmonics) for t in d[:1000]])
    half = np.ptp(e, axis=1) / 2
    assert half.max() <= room
    assert np.quantile(half, 0.05) < 0.2 * room and np.quantile(half, 0.5) < 0.6 * room
    r = np.corrcoef(e[:, 1], e[:, 2])[0, 1]
    assert r > 0.3, r
    # the bench's shape at its sizes (worstshape's draws): within the MPE, every size its own
    s = [draw_type_b(b, proto, k, table_errors="shape") for k in range(50)]
    assert all(t.table.error_bound_arcsec() <= b.table.mpe_arcsec + 1e-12 for t in s)
    assert len({round(t.table.error_bound_arcsec(), 9) for t in s}) == 50
    r = np.array([x.table.rate_error_rel for x in d])
    assert np.abs(r).max() <= TABLE_RATE_ERROR_BOUND
    assert np.var(r) == pytest.approx(TABLE_RATE_ERROR_BOUND ** 2 / 3, rel=0.08)


def test_rate_consistency_z_on_drawn_type_b_effects(base):
    """C_v (7.6) corrected for the range's bias, on the ``typeb`` case (every Type B effect
    drawn per trial): z = (C_v − truth)/u_c has sd within 0.7–1.3 and |mean| < 0.7, and U
    covers (its stated 95 % interval, the range's confidence belt, holding the truth:
    Clopper–Pearson reaching 95 %); the draft's range as measured, with U widened for
    its bias (``C_rng``), has sd z below 0.7 (over-wide) — the stated C_v of the old budget."""
    proto = validation_protocol(all_items=True)
    z, z_draft, hits = [], [], 0
    for s in range(700, 700 + CV_TRIALS):
        res = run_session(proto, draw_type_b(base, proto, s), seed=s)
        df = res.readings.copy()
        df["line"] = np.arange(2, len(df) + 2)
        rep = analyse(Readings(df, dict(res.metadata)), proto, budget="draft")
        rec = item_record(rep, res.truth)
        c, d = rec["rate_consistency"], rec["rate_consistency_draft"]
        z.append((c["value"] - c["truth"]) / c["u_c"])
        z_draft.append((d["value"] - d["truth"]) / d["u_c"])
        hits += c["interval"][0] <= c["truth"] <= c["interval"][1]   # the stated interval
    z, z_draft = np.array(z), np.array(z_draft)
    assert abs(z.mean()) < 0.7 and 0.7 <= z.std(ddof=1) <= 1.3, (z.mean(), z.std(ddof=1))
    assert clopper_pearson(hits, CV_TRIALS)[1] >= 0.95, hits
    assert z_draft.std(ddof=1) < 0.7, z_draft.std(ddof=1)
