"""The rate studies judge an item stated by its interval alone (K_r, B_r, B_s of JJF 1535;
IEC Noise,RMS and the half range) by that interval, and a standard deviation stated by its
one-sided χ² interval by its χ² z, with z on u_c kept beside it: for ν = 2, z = (s − σ)/u_c
with u_c = s/2 is unbounded below (s in the denominator) although the interval holds σ 95 %
of the time."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import chi2

from gonio.analysis.coverage import chi_square_z, item_coverage
from gonio.pipeline.coverage import format_coverage, reduced_protocol, trial_records
from gonio.specs import get
from gonio.specs._rate_family.simulate import study_bench


def _std_records(n: int, nu: int, sigma: float, seed: int = 1):
    """Standard deviations of ν + 1 normal values drawn by their χ² law, stated as
    std_dev_uncertainty states them: u_c = s/√(2ν), interval [0, s·√(ν/χ²_0.05,ν)]."""
    s = sigma * np.sqrt(np.random.default_rng(seed).chisquare(nu, n) / nu)
    hi = s * math.sqrt(nu / chi2.ppf(0.05, nu))
    recs = [(float(v), sigma, float(h - v), float(v / math.sqrt(2 * nu))) for v, h in zip(s, hi)]
    return recs, [{"interval": [0.0, float(h)], "nu": float(nu)} for h in hi]


def test_chi_square_stated_item_has_chi_square_z_and_interval_coverage():
    recs, stated = _std_records(4000, 2, 3.0)
    c = item_coverage(recs, "sf_repeatability", "7.2.4", stated)
    assert c.statistic == "chi-square"
    # the interval's own probability: 95 % (binomial sd 0.0034 at n = 4000)
    assert abs(c.coverage - 0.95) < 0.012
    assert c.cp_low <= 0.95 <= c.cp_high
    # χ² z is N(0, 1) under the model; z on u_c is not (s in its denominator)
    assert abs(c.z_mean) < 0.06 and 0.95 < c.z_sd < 1.05 and c.max_norm_error < 4.5
    assert c.z_uc_sd > 2.0 and c.max_norm_error_uc > 20.0 and c.z_uc_mean < -0.5
    # the interval holds σ exactly when χ² z ≥ −z₀.₉₅
    z = chi_square_z([r[0] for r in recs], 3.0, 2.0)
    assert c.hits == int(np.sum(z >= -1.6448536269514722))
    # the table prints the χ² z and z on u_c beside it
    txt = format_coverage(pd.DataFrame([c.__dict__]), "t")
    assert "[chi2 z; z on u_c: mean" in txt and f"{c.z_uc_sd:.2f}" in txt


def test_value_pm_U_unchanged_and_other_intervals_judged_by_interval():
    recs = [(1.0, 1.05, 0.1, 0.05), (1.0, 1.3, 0.1, 0.05)]
    assert item_coverage(recs).__dict__ == item_coverage(recs, stated=[None, None]).__dict__
    assert item_coverage(recs).statistic == "u_c" and item_coverage(recs).z_uc_sd is None
    # a range's interval (no χ² ν): the truth inside it, z on u_c; |v − t| > U on the low
    # side (v − t = 0.5 > U = 0.3) but the stated interval [0, v + U] holds t
    c = item_coverage([(1.5, 1.0, 0.3, 0.2)], stated=[{"interval": [0.0, 1.8], "nu": None}])
    assert c.statistic == "interval" and c.hits == 1 and c.z_mean == 2.5
    mixed = item_coverage([(1.5, 1.0, 0.3, 0.2), (1.0, 1.05, 0.1, 0.05)],
                          stated=[{"interval": [0.0, 1.8], "nu": None}, None])
    assert mixed.statistic == "mixed" and mixed.hits == 2


def test_jjf_trial_records_carry_the_stated_interval_and_its_nu():
    spec = get("jjf1535-2015")
    with tempfile.TemporaryDirectory() as d:
        proto = spec.load_protocol(str(reduced_protocol(spec.key, Path(d) / "r.toml")))
    r = trial_records(spec.key, study_bench(), proto, 7)
    for key in ("sf_repeatability", "bias_repeatability"):
        it = r[key]
        assert it["nu"] == 2.0                               # Q = 3 calibrations
        assert it["interval"][0] == 0.0
        assert math.isclose(it["interval"][1], it["value"] + it["U"], rel_tol=1e-12)
        assert math.isclose(it["interval"][1],
                            it["value"] * math.sqrt(2 / chi2.ppf(0.05, 2)), rel_tol=1e-9)
    bs = r["bias_stability"]                                  # ν = ½(B_s/u_c)², stated ν
    assert bs["nu"] == math.floor(0.5 * (bs["value"] / bs["u_c"]) ** 2)
    assert math.isclose(bs["interval"][1], bs["value"] * math.sqrt(bs["nu"] / chi2.ppf(
        0.05, bs["nu"])), rel_tol=1e-9)
    assert "interval" not in r["scale_factor"] and "nu" not in r["bias"]


def test_interval_item_judged_against_its_stated_p():
    """An outcome range states its own probability (above 95 %): the study records it and
    judges the coverage against it — 90 of 100 intervals holding the truth contradict a
    stated p of 0.99 (Clopper–Pearson upper end 0.951), not a stated 0.90."""
    from gonio.analysis.coverage import stated_record
    from gonio.result.model import Uncertainty

    u = Uncertainty([], 0.01, 0.03, None, None, None, 0.9997, "outcome distribution",
                    interval=(0.002, 0.05))
    assert stated_record(u) == {"interval": [0.002, 0.05], "nu": None, "p": 0.9997}
    recs = [(0.02, 0.02 if i < 90 else 0.2, 0.03, 0.01) for i in range(100)]
    for p, flagged in ((0.99, True), (0.90, False)):
        c = item_coverage(recs, "resolution", "5.6",
                          [{"interval": [0.002, 0.05], "nu": None, "p": p}] * 100)
        assert c.statistic == "interval" and c.hits == 90 and abs(c.p_stated - p) < 1e-12
        assert ("below its p" in c.flags) is flagged
        assert f"stated p {p:.3f}" in format_coverage(pd.DataFrame([c.__dict__]), "t")


def test_bound_condition_items_are_marked_in_the_study_table():
    """An item whose statement holds a bounded effect at its bound (details' bound_condition:
    JJF 7.2.5 K_t and 7.2.14 B_t, the chamber's temperature bound) is recorded as such per
    trial and the table says so ("[bound held]", and in how many trials where not all); an
    item stated by k·u_c of its budget is not marked."""
    from gonio.analysis.coverage import coverage_table_from

    spec = get("jjf1535-2015")
    with tempfile.TemporaryDirectory() as d:
        proto = spec.load_protocol(str(reduced_protocol(spec.key, Path(d) / "r.toml")))
    r = trial_records(spec.key, study_bench(), proto, 7)
    for key in ("sf_temperature_sensitivity", "bias_temperature_sensitivity"):
        assert r[key].get("bound") is True, key
    assert "bound" not in r["scale_factor"] and "bound" not in r["sf_repeatability"]
    plain = {k: {x: v for x, v in rec.items() if x != "bound"} for k, rec in r.items()}
    df = coverage_table_from([r, r, plain])
    rows = df.set_index("key")
    assert rows.loc["sf_temperature_sensitivity", "bound_trials"] == 2
    assert rows.loc["scale_factor", "bound_trials"] == 0
    txt = format_coverage(df, "t").splitlines()
    line = next(s for s in txt if s.startswith("sf_temperature_sensitivity"))
    assert "[bound held in 2 of 3]" in line, line
    assert "[bound held" not in next(s for s in txt if s.startswith("scale_factor "))
    full = format_coverage(coverage_table_from([r, r]), "t").splitlines()
    assert "[bound held]" in next(s for s in full
                                  if s.startswith("bias_temperature_sensitivity"))
