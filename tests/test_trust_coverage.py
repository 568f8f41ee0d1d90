"""Every item's uncertainty covers the bench's truth (issue 12, clause 8).

The draft's whole protocol (7.1–7.7) on the default virtual bench, many seeds, the
laboratory's k = 2 (the validation protocol fixes the draft's A.7 k): for each item the
fraction of trials whose result lies within U of the truth
(:mod:`gonio.specs.ogam_draft.item_coverage`); for the two standard deviations, B_s and
R, the fraction whose 95 % χ² interval holds the ensemble truth.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.calibration import analyse
from gonio.specs.ogam_draft.readings import Readings
from gonio.specs.ogam_draft.item_coverage import item_coverage, trial_items
from gonio.specs.ogam_draft.study import ideal_bench, trial_bench, validation_protocol

SEEDS = 24
#: Items whose U this study finds over-wide (sd of z = (result − truth)/u_c < 0.3), with why.
#: None today. U(K) was listed while K's truth was the noise-free rerun's own 7.1 K, which
#: holds the tilt × Earth-rate coupling that U(K)'s K_tilt line is there to cover; against
#: the instrument's K from the bench file (item_coverage.scale_factor_truth) the line is
#: part of the error, and on benches whose Type B effects are drawn per trial sd z ≈ 0.7.
KNOWN_OVER_WIDE: dict = {
    # None. E under the physical budget was listed (sd z ≈ 0.25: one u_c for every point)
    # until the budget was given per point; on the drawn set-ups it now has sd z ≈ 0.6–0.7
    # (README, docs/draft-readings.md): its table and drift lines are bounds the study's
    # draws sit inside, not over-wide by this test's 0.3.
}
@pytest.fixture(scope="module")
def proto():
    return validation_protocol(all_items=True)


@pytest.fixture(scope="module")
def base():
    return replace(load_bench("rlg"), sample_rate_hz=5.0)


@pytest.fixture(scope="module")
def intrinsic(proto, base):
    """E's truth per point on the ideal set-up (no tilt, Earth rate, bias, table error)."""
    tr = pd.DataFrame(run_session(proto, ideal_bench(base), seed=0).truth["readings"])
    ad = tr[tr["test"] == "angle_deviation"]
    return ad.groupby("round")["systematic_deviation_arcsec"].mean().sort_index().to_numpy()


@pytest.fixture(scope="module")
def records(proto, base):
    out = []
    for seed in range(SEEDS):
        bench = trial_bench("typeb", base, proto, 500 + seed)   # every Type B effect drawn
        res = run_session(proto, bench, seed=500 + seed)
        df = res.readings.copy()
        df["line"] = np.arange(2, len(df) + 2)
        rep = analyse(Readings(df, dict(res.metadata)), proto, budget="draft")
        assert rep.uncertainty.k == 2.0
        out.append(trial_items(rep, res.truth))
    return out


@pytest.mark.slow
def test_every_item_covers_its_truth(records, intrinsic):
    cov = item_coverage(records, intrinsic)
    # scale_factor_bound: the draft's 7.1 mean beside K corrected by the built-in tilt estimate
    assert set(cov) == {"scale_factor", "scale_factor_disc", "scale_factor_bound",
                        "scale_factor_nonlinearity",
                        "scale_factor_nonlinearity_draft", "zero_stability",
                        "angle_deviation", "angle_deviation_draft", "repeatability",
                        "rate_consistency", "rate_consistency_draft",
                        "pointing_consistency", "pointing_consistency_draft"}
    for name, c in cov.items():
        assert c["trials"] == SEEDS
        if name in ("zero_stability", "repeatability"):
            assert c["interval_holds_truth"]["fraction"] >= 0.90, (name, c)
        elif name == "angle_deviation":
            # the physical budget is about the instrument (E corrected at the measured tilt,
            # per-point U): judged against the intrinsic truth, not the as-mounted one
            assert c["two_sided"]["truth"] == "intrinsic"
            assert c["within_U_intrinsic"]["fraction"] >= 0.90, (name, c)
        else:
            assert c["within_U"]["fraction"] >= 0.90, (name, c)
    # the other side: U not over-wide (sd z ≥ 0.3) where the budget is gonio's own; the items
    # found over-wide today are listed (each with why), and the list must be exact
    wide = {n: round(c["two_sided"]["z_sd"], 3) for n, c in cov.items()
            if "over-wide" in c["two_sided"]["flags"]}
    assert set(wide) == set(KNOWN_OVER_WIDE), wide
    # the items stated by a χ² interval are also judged against that model (z of the pivot):
    # B_s's model holds on these drawn set-ups; R, the largest of m standard deviations stated
    # with the interval of one, is biased upwards (a known finding, README)
    zb, zr = cov["zero_stability"]["z_chi2"], cov["repeatability"]["z_chi2"]
    assert abs(zb["mean"]) < 0.6 and 0.6 <= zb["sd"] <= 1.4, zb
    assert zr["mean"] > 0.5, zr
    # ... and by as much as R's exact distribution at the ensemble σ_i says (the largest of
    # twelve alike s_i: z mean ≈ +1.3, sd ≈ 0.6; a second computation, closed form)
    pr = cov["repeatability"]["predicted"]
    assert abs(zr["mean"] - pr["z_chi2_mean"]) < 3.0 * pr["z_chi2_sd"] / SEEDS ** 0.5 + 0.1, \
        (zr, pr)
    assert cov["repeatability"]["interval_holds_truth"]["clopper_pearson"][1] >= 0.95


@pytest.mark.slow
def test_over_wide_check_can_fail(records, intrinsic):
    """The same records with every U ×20: each item with gonio's own budget is flagged."""
    def times20(it):
        out = dict(it, U=it["U"] * 20.0, u_c=(it.get("u_c") or 0.0) * 20.0)
        for key in ("U_points", "u_c_points"):          # E's per-point budget
            if key in it:
                out[key] = [x * 20.0 for x in it[key]]
        return out

    wide = [{n: times20(it) for n, it in r.items()} for r in records]
    cov = item_coverage(wide, intrinsic)
    flagged = {n for n, c in cov.items() if "over-wide" in c["two_sided"]["flags"]}
    assert flagged == {n for n, c in cov.items() if c["two_sided"]["own_budget"]}, cov
    assert "angle_deviation_draft" not in flagged      # the draft's prescribed annex budget


@pytest.mark.slow
def test_coverage_check_can_fail(records):
    """The same records with every U (and interval) shrunk 20-fold: coverage collapses."""
    shrunk = []
    for r in records:
        s = {}
        for name, it in r.items():
            it = dict(it, U=it["U"] / 20.0)
            if it.get("interval"):
                v = it["value"]
                it["interval"] = [v - (v - it["interval"][0]) / 20,
                                  v + (it["interval"][1] - v) / 20]
            s[name] = it
        shrunk.append(s)
    cov = item_coverage(shrunk)
    low = [n for n, c in cov.items()
           if (c.get("interval_holds_truth") or c["within_U"])["fraction"] < 0.9]
    assert {"scale_factor", "angle_deviation", "zero_stability", "repeatability"} <= set(low), cov


@pytest.mark.slow
def test_physical_budget_covers_the_intrinsic_truth_at_the_tilt_bound():
    """Sensing plane tilted at the A.1 bound (0.1°) at 40.2° N: against the instrument's
    intrinsic deviation (ideal set-up), the draft's four lines miss part of the tilt ×
    Earth-rate coupling, the physical budget (gonio calibrate's default) does not."""
    from gonio.pipeline.validate import validate

    r = validate(12, seed=3, cases=["tilt"], sample_rate_hz=5.0, workers=1,
                 show_progress=False)
    items = r.cases[0].summary["items"]
    phys = items["angle_deviation"]["within_U_intrinsic"]["fraction"]
    draft = items["angle_deviation_draft"]["within_U_intrinsic"]["fraction"]
    assert phys >= 0.95 and draft < phys, (phys, draft)


def test_mounted_tilt_is_uniform_over_the_bound_disc(proto, base):
    """The drawn tilt vector is uniform over the disc ψ ≤ bound: E[ψ²] = bound²/2, the
    azimuth uniform (E[cos α] = E[sin α] = 0), and the draw is the trial seed's alone."""
    b = proto.annex_a.tilt_bound_deg
    inst = [trial_bench("mounted", base, proto, s).instrument for s in range(4000)]
    psi = np.array([i.tilt_deg for i in inst])
    az = np.radians([i.tilt_azimuth_deg for i in inst])
    assert psi.max() <= b and np.mean(psi ** 2) / b ** 2 == pytest.approx(0.5, abs=0.02)
    assert abs(np.mean(np.cos(az))) < 0.05 and abs(np.mean(np.sin(az))) < 0.05
    assert trial_bench("mounted", base, proto, 7) == trial_bench("mounted", base, proto, 7)
