"""Budget terms and decision boundaries that a formula mutation must not get past (issue 24,
scripts/mutation.py): each number is recomputed here from the readings by a second route
(pandas group means and numpy.polyfit, not the items' code), and each boundary is probed
exactly on it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.result.statement import item_statement

from gonio.analysis.conformity import DecisionRule, Limits, decide
from gonio.formats.rate_readings import RateReadings
from gonio.pipeline.coverage import reduced_protocol
from gonio.specs._rate_family.simulate import study_bench


def _comp(item, symbol):
    return next(c for c in item.uncertainty.components if c["symbol"] == symbol)


@pytest.fixture(scope="module")
def jjf(tmp_path_factory):
    from gonio.specs.jjf1535 import calibrate
    from gonio.specs.jjf1535.simulate import simulate
    p = reduced_protocol("jjf1535-2015", tmp_path_factory.mktemp("u3") / "p.toml",
                         {"arw": {"samples": 3000}, "bias": {"samples": 300}})
    res = simulate(study_bench(), str(p), seed=4242, noise=True)
    rd = RateReadings(res.data, {k: str(v) for k, v in res.metadata.items()})
    return calibrate(rd, str(p)), res.data


def _k_by_polyfit(df) -> np.ndarray:
    """K_m of each calibration: rest-removed rate-point means, numpy.polyfit (second route)."""
    d = df[df["test"] == "scale_factor"]
    Ks = []
    for _, run in d.groupby("run"):
        means = run.groupby("step").agg(rate=("rate_dps", "first"), role=("role", "first"),
                                        y=("output", "mean"))
        pts = means[means["role"] == "rate"]
        Ks.append(np.polyfit(pts["rate"].to_numpy(), pts["y"].to_numpy(), 1)[0])
    return np.array(Ks)


def test_jjf_scale_factor_budget_u3_and_combination(jjf):
    """7.2.1 budget: K̄ = mean of K_m; u3 = s(K_m)/√Q (ν = Q − 1); u1, u2 relative × K̄;
    u_c = √(u1² + u2² + u3²) to first order; U = t₉₅(ν_eff)·u_c with Welch–Satterthwaite."""
    from scipy.stats import t as student
    r, df = jjf
    it = r.items["scale_factor"]
    Ks = _k_by_polyfit(df)
    Q = Ks.size
    assert Q == 3
    assert it.value == pytest.approx(Ks.mean(), rel=1e-12)
    u3 = Ks.std(ddof=1) / math.sqrt(Q)
    assert u3 > 0
    c3 = _comp(it, "s_K")
    assert c3["u"] == pytest.approx(u3, rel=1e-9)
    assert c3["dof"] == Q - 1
    u1 = 2.5e-4 * Ks.mean()
    u2 = 3.0e-5 * Ks.mean()
    uc = math.sqrt(u1 ** 2 + u2 ** 2 + u3 ** 2)
    assert it.uncertainty.u_c == pytest.approx(uc, rel=1e-6)
    nu = uc ** 4 / (u3 ** 4 / (Q - 1))
    assert it.uncertainty.nu_eff == pytest.approx(nu, rel=1e-6)
    assert it.uncertainty.U == pytest.approx(student.ppf(0.975, math.floor(nu)) * uc, rel=1e-6)


def _std_dev_budget(it, s, Q):
    """u_c = s/√(2ν) (GUM E.4.3), U = s·(√(ν/χ²_0.05,ν) − 1), the one-sided 95 % interval
    [0, s·√(ν/χ²_0.05,ν)], ν = Q − 1 (scipy's χ², not the item's code)."""
    from scipy.stats import chi2
    nu = Q - 1
    assert it.value == pytest.approx(s, rel=1e-9)
    assert it.uncertainty.u_c == pytest.approx(s / math.sqrt(2 * nu), rel=1e-9)
    assert it.uncertainty.U == pytest.approx(s * (math.sqrt(nu / chi2.ppf(0.05, nu)) - 1),
                                             rel=1e-9)
    assert it.uncertainty.nu_eff == nu and it.uncertainty.coverage_probability == 0.95
    assert it.uncertainty.k is None             # stated by its interval: no coverage factor
    st = item_statement(it)
    assert st.U is None and st.k is None and st.interval is not None and " ± " not in st.text()
    (row,) = it.uncertainty.components             # one type-A row: u = contribution = u_c
    assert (row["type"], row["c"], row["dof"]) == ("A", 1.0, nu)
    assert row["u"] == row["contribution"] == pytest.approx(s / math.sqrt(2 * nu), rel=1e-9)
    lo, hi = it.uncertainty.interval
    assert lo == 0.0 and hi == pytest.approx(s * math.sqrt(nu / chi2.ppf(0.05, nu)), rel=1e-9)


@pytest.mark.parametrize("nu", [1, 2, 4, 9])
def test_std_dev_uncertainty_covers_95_percent(nu):
    """Review of stop 30: s ± U must hold σ with the probability it states (95 %). Normal
    samples of ν + 1 values, σ = 1: the fraction of s − U ≤ σ ≤ s + U (for ν ≤ 5 the lower
    side is below 0) against scipy's binomial test. The two-sided χ² limit it had covered
    97.5 %."""
    from scipy.stats import binomtest
    from gonio.kit import std_dev_uncertainty
    rng = np.random.default_rng(nu)
    n = 20000
    s = rng.standard_normal((n, nu + 1)).std(axis=1, ddof=1)
    U = np.array([std_dev_uncertainty(float(v), nu, "x").U for v in s[:50]])
    assert np.all(s[:50] - U < 0) == (nu <= 5)
    ratio = U[0] / s[0]                            # U is proportional to s
    hits = int(np.sum((s * (1.0 - ratio) <= 1.0) & (1.0 <= s * (1.0 + ratio))))
    ci = binomtest(hits, n).proportion_ci(0.999)
    assert ci.low <= 0.95 <= ci.high, (hits / n, ci)


def test_jjf_sf_repeatability_chi2_upper_limit(jjf):
    """7.2.4: K_r = s(K_m)/K̄; u_c = K_r/√(2ν) (before issue 24 the χ² half-width was a
    normal term expanded again: u_c 5.3× too large), U the distance to the χ² 95 % upper
    limit, ν = Q − 1."""
    r, df = jjf
    Ks = _k_by_polyfit(df)
    _std_dev_budget(r.items["sf_repeatability"], Ks.std(ddof=1) / Ks.mean(), Ks.size)


def test_jjf_repeatabilities_with_two_and_one_power_ups(jjf, tmp_path):
    """Q = 2 is a standard deviation with ν = 1; Q = 1 is not measured (the guard Q ≥ 2)."""
    from gonio.specs.jjf1535 import calibrate
    r, df = jjf
    p = reduced_protocol("jjf1535-2015", tmp_path / "p.toml",
                         {"arw": {"samples": 3000}, "bias": {"samples": 300}})
    for runs in ((0, 1), (0,)):
        keep = ~df["test"].isin(["scale_factor", "bias"]) | df["run"].isin(runs)
        rq = calibrate(RateReadings(df[keep].reset_index(drop=True), {
            k: str(v) for k, v in r.metadata.items()}), str(p))
        Ks = _k_by_polyfit(df[keep])
        d = df[keep & (df["test"] == "bias")]
        b = d.groupby("run")["output"].mean().to_numpy() / rq.items["scale_factor"].value * 3600
        if len(runs) == 2:
            _std_dev_budget(rq.items["sf_repeatability"], Ks.std(ddof=1) / Ks.mean(), 2)
            _std_dev_budget(rq.items["bias_repeatability"], b.std(ddof=1), 2)
        else:
            assert not rq.items["sf_repeatability"].measured
            assert not rq.items["bias_repeatability"].measured


def test_jjf_bias_repeatability_and_stability_by_hand(jjf):
    """7.2.8, 7.2.10, 7.2.11: B_0 the mean of the record biases, B_r their Bessel standard
    deviation (°/h), B_s the root mean square of the records' block-mean standard deviations."""
    r, df = jjf
    d = df[df["test"] == "bias"]
    K = r.items["scale_factor"].value
    P = 10
    rec_b, rec_s = [], []
    for _, g in d.groupby("run"):
        y = g["output"].to_numpy()
        rec_b.append(y.mean())
        n = y.size // P
        rec_s.append(y[: n * P].reshape(n, P).mean(1).std(ddof=1) / K * 3600)
    br = np.std(np.array(rec_b) / K * 3600, ddof=1)
    _std_dev_budget(r.items["bias_repeatability"], br, len(rec_b))
    bs = r.items["bias_stability"]
    # the records' root mean square (eq (19)'s mean of standard deviations reads low; kept)
    assert bs.value == pytest.approx(math.sqrt(np.mean(np.square(rec_s))), rel=1e-9)
    assert bs.details["reading_eq19_dph"] == pytest.approx(np.mean(rec_s), rel=1e-9)
    # one interval, from the records' effective ν (not the spread of the Q = 3 values; the
    # flicker and random walk at their upper 95 % limits):
    # u_c² = B_s²/(2ν_rec) + (B_s·u(K)/K)², ν = ½(B_s/u_c)², [0, B_s·√(ν/χ²_0.05,ν)]
    from scipy.stats import chi2
    from gonio.specs._rate_family.formulas import bias_stability_dof
    runs = [g["output"].to_numpy() for _, g in d.groupby("run")]
    nu_rec = bias_stability_dof(runs, P, 0.95)
    assert bs.details["nu_records_estimate"] == pytest.approx(bias_stability_dof(runs, P))
    assert nu_rec < bs.details["nu_records_estimate"]
    u_c = bs.value * math.sqrt(1 / (2 * nu_rec) + r.items["scale_factor"].uncertainty.u_c ** 2
                               / K ** 2)
    assert bs.uncertainty.u_c == pytest.approx(u_c, rel=1e-6)
    nu = int(0.5 * (bs.value / u_c) ** 2)
    assert bs.uncertainty.k is None and bs.uncertainty.interval[0] == 0.0
    assert bs.uncertainty.interval[1] == pytest.approx(
        bs.value * math.sqrt(nu / chi2.ppf(0.05, nu)), rel=1e-6)


LIM = Limits(-0.5, 0.5)


def test_conformity_value_exactly_on_a_limit_is_accepted():
    """JCGM 106 3.3.9: the limits belong to the interval (y >= lo, y <= hi, not > / <)."""
    r = DecisionRule("simple")
    for y in (-0.5, 0.5):
        d = decide("E", y, 0.25, 2.0, LIM, r)
        assert d.outcome == "pass" and d.accepted, (y, d.outcome)
    assert decide("E", -0.5000001, 0.25, 2.0, LIM, r).outcome == "fail"
    assert decide("E", 0.5000001, 0.25, 2.0, LIM, r).outcome == "fail"


def test_conformity_guard_band_edges_are_exact():
    """Non-binary, w = U = 0.25 (exact in binary): acceptance [−0.25, 0.25]; on its edges
    'pass'; just beyond a limit by exactly w 'conditional fail', further 'fail'."""
    r = DecisionRule("non-binary")
    d = decide("E", -0.25, 0.25, 2.0, LIM, r)
    assert d.guard_band == 0.25 and d.acceptance_lower == -0.25 and d.acceptance_upper == 0.25
    assert d.outcome == "pass"
    assert decide("E", 0.25, 0.25, 2.0, LIM, r).outcome == "pass"
    assert decide("E", -0.2500001, 0.25, 2.0, LIM, r).outcome == "conditional pass"
    assert decide("E", -0.5, 0.25, 2.0, LIM, r).outcome == "conditional pass"
    assert decide("E", -0.75, 0.25, 2.0, LIM, r).outcome == "conditional fail"
    assert decide("E", 0.75, 0.25, 2.0, LIM, r).outcome == "conditional fail"
    assert decide("E", 0.7500001, 0.25, 2.0, LIM, r).outcome == "fail"
    assert decide("E", -0.7500001, 0.25, 2.0, LIM, r).outcome == "fail"


def test_iec_symmetry_sign_follows_the_gyro():
    """5.1.3.8: S = (a_CW − a_CCW)/a_TYP is signed: a gyro stronger clockwise (α > 0) gives
    S > 0, the mirror gyro (α < 0) S < 0, each equal to the closed form 100·K·α/a_TYP
    (no cubic term: K± = K(1 ± α/2) exactly)."""
    from dataclasses import replace

    from gonio.specs.iec62047_20 import calibrate
    from gonio.specs.iec62047_20.simulate import simulate
    from gonio.specs.iec62047_20.protocol import load_protocol
    proto = load_protocol("iec62047-20")
    for alpha in (3e-3, -3e-3):
        b = study_bench()
        b = replace(b, gyro=replace(b.gyro, sf_asymmetry=alpha, sf_cubic_per_dps2=0.0))
        res = simulate(b, proto, seed=1, noise=False)
        sf = res.data[res.data["test"] == "scale_factor"]
        rd = RateReadings(sf, {k: str(v) for k, v in res.metadata.items()})
        s = calibrate(rd, proto).items["symmetry"].value
        K = float(b.gyro.scale_factor_at(22.5, 5.0))
        assert s == pytest.approx(100 * K * alpha / b.gyro.scale_factor, rel=1e-6)
        assert math.copysign(1, s) == math.copysign(1, alpha)


def test_conformity_single_point_acceptance_interval():
    """A guard band leaving exactly one point (T_U − T_L = 2w): the closed interval [0, 0]
    still holds 0 (the limits belong to it); a guard band one ulp wider passes nothing.
    (The lo <= hi clause of the interval test is observable only here.)"""
    r = DecisionRule("guarded")
    assert decide("E", 0.0, 0.5, 2.0, LIM, r).outcome == "pass"
    assert decide("E", 0.0, 0.5000000001, 2.0, LIM, r).outcome == "fail"
