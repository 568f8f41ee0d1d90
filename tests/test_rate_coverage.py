"""Coverage of every rate-gyro item's expanded uncertainty on the virtual bench (issue 17:
"≥ 90 % per item over many seeds").

The default run uses GONIO_COVERAGE_SEEDS (default 10) seeds per specification on the
reduced programme of gonio.pipeline.rate_coverage.REDUCED and requires, per item, that the
coverage is not significantly below 90 %: the upper Wilson 95 % limit reaches 0.90. The
benchmark benchmarks/bench_rate_coverage.py runs 100–200 seeds (figures in
docs/jjf1535-readings.md#coverage-of-the-budgets); set GONIO_COVERAGE_SEEDS=100 to run
the same here.
"""

from __future__ import annotations

import os

import pytest

from gonio.pipeline.rate_coverage import (coverage_study, item_coverage, reduced_protocol,
                                          wilson_interval)

SEEDS = int(os.environ.get("GONIO_COVERAGE_SEEDS", "10"))


def test_wilson_and_item_coverage_by_hand():
    # Wilson score interval against scipy's binomtest (peer implementation)
    from scipy.stats import binomtest
    for k, n in ((95, 100), (0, 10), (17, 20)):
        ci = binomtest(k, n).proportion_ci(method="wilson")
        assert wilson_interval(k, n) == pytest.approx((ci.low, ci.high), abs=1e-12)
    c = item_coverage([(1.0, 1.05, 0.1, 0.05), (1.0, 1.2, 0.1, 0.05), (2.0, 2.0, 0.0, 0.0),
                       (0.0, 0.09, 0.1, 0.04)], "k", "1")
    assert (c.n, c.hits, c.coverage) == (4, 3, 0.75)
    assert c.u_coverage == pytest.approx((0.75 * 0.25 / 4) ** 0.5)
    assert c.max_norm_error == pytest.approx(4.0) and c.median_norm_error == pytest.approx(1.625)
    # Clopper–Pearson against scipy's exact interval; z = e/u_c of the trials with u_c > 0
    from scipy.stats import binomtest
    ci = binomtest(3, 4).proportion_ci(method="exact")
    assert (c.cp_low, c.cp_high) == pytest.approx((ci.low, ci.high), abs=1e-12)
    z = [-0.05 / 0.05, -0.2 / 0.05, -0.09 / 0.04]
    assert c.z_mean == pytest.approx(sum(z) / 3) and c.flags == ("under-covers",)


@pytest.mark.slow
@pytest.mark.parametrize("spec", ("jjf1535-2015", "iec62047-20"))
def test_coverage_per_item(spec, tmp_path):
    proto = reduced_protocol(spec, tmp_path / "reduced.toml")
    df = coverage_study(spec, range(500, 500 + SEEDS), protocol=str(proto))
    assert len(df) >= (15 if spec == "jjf1535-2015" else 20)
    low = df[df["wilson_high"] < 0.90]
    assert low.empty, "coverage significantly below 90 %:\n" + low.to_string()
    assert (df["n"] == SEEDS).all()
