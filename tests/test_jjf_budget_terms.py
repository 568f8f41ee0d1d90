"""JJF 1535 budget terms against truths computed outside the estimators: 7.2.5's K_i noise
against the bench's own K_m noise (``sf_fit_noise_rel``: the covariance of the bench's noise
through the least-squares weights), 7.2.15's interpolation remainder against the exact error
of linear interpolation, and 7.2.6 / 7.2.7's one stated probability against the outcome
distribution in the item's details and the rendered statement."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.formats.rate_readings import RateReadings
from gonio.specs.jjf1535.formulas import interpolation_remainder


def test_interpolation_remainder_is_the_exact_error_of_a_quadratic():
    """For p quadratic in ln f, linear interpolation's largest error between two grid points
    is exactly h²/8·|p''| (at the midpoint); computed here on a fine grid."""
    lnf = np.log([10.0, 14.0, 20.0, 31.0])
    a = -3.7
    p = a * lnf ** 2 + 2.0 * lnf
    for j in (1, 2, 3):
        x = np.linspace(lnf[j - 1], lnf[j], 20001)
        lin = p[j - 1] + (p[j] - p[j - 1]) * (x - lnf[j - 1]) / (lnf[j] - lnf[j - 1])
        exact = float(np.max(np.abs(a * x ** 2 + 2.0 * x - lin)))
        assert interpolation_remainder(lnf, p, j) == pytest.approx(exact, rel=1e-6)
    assert interpolation_remainder(lnf[:2], p[:2], 1) == 0.0
    # a straight line has no remainder; a wrong formula (h²/2, or h instead of h²) fails above
    assert interpolation_remainder(lnf, 3.0 * lnf, 2) == pytest.approx(0.0, abs=1e-12)


@pytest.fixture(scope="module")
def study_runs(tmp_path_factory):
    from gonio.pipeline.coverage import reduced_protocol, study_bench
    from gonio.specs import get
    from gonio.specs.jjf1535 import calibrate
    from gonio.specs.jjf1535.protocol import load_protocol
    from gonio.specs.jjf1535.simulate import simulate
    from gonio.specs.jjf1535.truth import sf_fit_noise_rel

    tmp = tmp_path_factory.mktemp("jjfb")
    p = str(reduced_protocol("jjf1535-2015", tmp / "reduced.toml"))
    bench = study_bench(get("jjf1535-2015"))
    out = []
    for seed in range(3):
        res = simulate(bench, p, seed=seed, noise=True)
        rd = RateReadings(res.data, {k: str(v) for k, v in res.metadata.items()})
        out.append((calibrate(rd, p), res.truth["items"]))
    return out, sf_fit_noise_rel(bench, load_protocol(p))


def test_sf_temperature_sensitivity_k_noise_is_the_bench_noise(study_runs):
    """7.2.5: u(K_i)/K_i is the noise the bench's rate noise gives one least-squares K
    (its covariance through the fit's weights, computed from the bench's parameters), not
    the line's residual standard error, which holds the gyro's nonlinearity (≈ 2× on the
    study bench): the ratio of the two, averaged over the records, within 0.7–1.3."""
    runs, true_rel = study_runs
    ratios, resid = [], []
    for r, _ in runs:
        it = r.items["sf_temperature_sensitivity"]
        K = r.items["scale_factor"].value
        for c in it.uncertainty.components:
            if c["symbol"] in ("K_i", "K_rt"):
                ratios.append(c["u"] / abs(K) / true_rel)
        resid += [s / abs(K) / true_rel for s in it.details["se_K_residual"]]
    assert 0.7 < float(np.sqrt(np.mean(np.square(ratios)))) < 1.3, ratios
    assert float(np.mean(resid)) > 1.5          # the term it replaced: the residuals' scatter


def test_rule_items_state_one_probability(study_runs, tmp_path):
    """7.2.6 / 7.2.7: p is the interval's own probability under the outcome distribution in
    the item's details (whole grid steps: ≥ 95 %), results.json holds it and the one
    statement every output prints (item_statement) states it."""
    from gonio.result.statement import item_statement, p_relation, p_text

    seen = 0
    for r, _ in study_runs[0]:
        js = r.to_json()["items"]
        for key in ("threshold", "resolution"):
            it = js[key]
            iv = it["uncertainty"].get("interval")
            if iv is None:
                continue
            pmf = it["details"]["outcome_pmf"]
            top = max(float(k) for k in pmf if k != "none")
            p = sum(v for k, v in pmf.items()
                    if iv[0] - 1e-12 <= (top if k == "none" else float(k)) <= iv[1] + 1e-12)
            got = it["uncertainty"]["coverage_probability"]
            assert got == pytest.approx(p / sum(pmf.values()), rel=1e-9)
            assert got >= 0.95 - 1e-9
            assert f"p {p_relation(p_text(got))} {p_text(got)} %" in item_statement(it).text()
            seen += 1
    assert seen >= 2


def test_rule_outcome_skew_explains_the_z_mean():
    """The study's z = (value − median outcome)/u_c of 7.2.6 / 7.2.7 has mean (mean − median)/sd
    of the outcome (a discrete, right-skewed distribution); the truth states it, computed
    from the bench's noise: positive where the outcome spreads over coarser steps above its
    median."""
    from gonio.pipeline.coverage import study_bench
    from gonio.specs import get
    from gonio.specs.jjf1535.protocol import load_protocol
    from gonio.specs.jjf1535.truth import truth

    t = truth(study_bench(get("jjf1535-2015")), load_protocol("jjf1535-2015"))
    for key in ("threshold", "resolution"):
        d = t[key]
        assert d["outcome_sd_dps"] > 0
        assert d["outcome_skew_z"] == pytest.approx(
            (d["outcome_mean_dps"] - d["value"]) / d["outcome_sd_dps"])
        assert d["outcome_mean_dps"] > d["value"]
