"""Coverage of every rate-gyro item's expanded uncertainty on the virtual bench (issue 17:
"≥ 90 % per item over many seeds").

The default run uses GONIO_COVERAGE_SEEDS (default 10) seeds per specification on the
reduced programme of SPEC.coverage.reduced and requires, per item, that the
coverage is not significantly below 90 % (the upper Clopper–Pearson 95 % limit reaches
0.90) and that U is not over-wide (sd of z = (value − truth)/u_c ≥ 0.3): both sides. The
benchmark benchmarks/bench_rate_coverage.py runs 100–200 seeds (figures in
docs/jjf1535-readings.md#coverage-of-the-budgets); set GONIO_COVERAGE_SEEDS=100 to run
the same here.
"""

from __future__ import annotations

import os

import pytest

from gonio.pipeline.coverage import (coverage_study, item_coverage, reduced_protocol,
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


#: Items whose U the coverage study finds over-wide today (sd z < 0.3), each with the
#: issue that fixes it; the test fails if the list is wrong either way.
KNOWN_OVER_WIDE: dict[tuple[str, str], str] = {}


def two_sided_failures(df, spec) -> dict:
    """Rows failing either side: coverage significantly below 90 % (upper Clopper–Pearson
    limit < 0.90) or flagged over-wide (sd z < 0.3; gonio's own budgets)."""
    low = set(df.loc[df["cp_high"] < 0.90, "key"])
    wide = {r.key for r in df.itertuples() if "over-wide" in r.flags}
    return {"under": low, "over-wide": wide - {k for s, k in KNOWN_OVER_WIDE if s == spec}}


@pytest.mark.slow
@pytest.mark.parametrize("spec", ("jjf1535-2015", "iec62047-20"))
def test_coverage_per_item(spec, tmp_path):
    from gonio.pipeline.coverage import coverage_table_from, trial_records
    from gonio.specs import get

    proto = reduced_protocol(spec, tmp_path / "reduced.toml")
    # IEC: cross-axis on; JJF: the power-on transient on (its warm-up time is measured)
    bench = get(spec).coverage.study_bench(get(spec).default_bench)
    if spec == "jjf1535-2015":
        assert bench.gyro.warmup_bias_dps != 0.0
    trials = [trial_records(spec, bench, str(proto), s) for s in range(500, 500 + SEEDS)]
    df = coverage_table_from(trials)
    assert len(df) >= (15 if spec == "jjf1535-2015" else 20)
    assert (df["n"] == SEEDS).all()
    bad = two_sided_failures(df, spec)
    assert bad == {"under": set(), "over-wide": set()}, df.to_string()
    known = {k for s, k in KNOWN_OVER_WIDE if s == spec}
    assert known <= {r.key for r in df.itertuples() if "over-wide" in r.flags}, \
        "an item listed as over-wide is no longer: remove it from KNOWN_OVER_WIDE"
    # the check fails on both sides: every U (and u_c) ×20 → over-wide, ÷20 → under-covers;
    # the scaled records state value ± U (an item stated by its interval alone loses it: its
    # χ² z does not depend on U, and a one-sided [0, value + U/20] still holds the truth
    # whenever the value is above it)
    def scale(r, f):
        if r["U"] is None:
            return r
        return {**{k: v for k, v in r.items() if k not in ("interval", "nu")},
                "U": r["U"] * f, "u_c": r["u_c"] * f}

    for factor, side in ((20.0, "over-wide"), (1 / 20, "under")):
        scaled = [{k: scale(r, factor) for k, r in t.items()} for t in trials]
        sdf = coverage_table_from(scaled)
        zsd = df["z_uc_sd"].fillna(df["z_sd"]).astype(float)
        # ×20 can flag only a z_sd under 6: a standard deviation of Q = 3 values (K_r, B_r)
        # has z = 2(1 − σ/s) on u_c, of unbounded spread (u_c = s/√(2ν) ∝ s; 8.6 on 10
        # seeds; the study states their χ² z, z_sd, and keeps this one as z_uc_sd)
        reach = (zsd < 0.3 * factor) if factor > 1 else (zsd > 0)
        spread = set(df.loc[(zsd > 0) & reach, "key"])
        assert two_sided_failures(sdf, spec)[side] >= spread - known, side
