"""``gonio validate --spec triad-alignment``: the triad's coverage study over its three cases
of the rate table (``typeb`` drawn per trial, ``worst`` at the bounds, ``worst-axes`` the
bounded axis errors at their bounds and the rate error drawn).

Checked: validation.json is byte-identical on one worker and on two (one trial per batch);
the ``worst`` bench sits at the bounds (the drawn values themselves) with signs no draw within
the bounds beats; the simulated calibrations of the worst case are offset as the table's
first-order model says (the bench's rotation of the spin axis and its rate error, against
the closed form of ``table_bias``: the mean z of every diagonal M_ii equals the closed-form
offset in u_c); ``typeb`` draws another table per trial; unknown cases are refused.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from gonio.analysis.coverage import MIN_SD_Z, coverage_table_from, spawn_seed
from gonio.cli import main
from gonio.errors import GonioError
from gonio.specs.triad_alignment.analysis import table_type_b_cov
from gonio.specs.triad_alignment.bench import load_triad_bench
from gonio.specs.triad_alignment.study import (CASE_KEYS, CASES, FIXED_CONDITION_CASES,
                                               RATE_ERROR_BOUND_K,
                                               case_bench, plan_study, table_bias,
                                               worst_table)

TRIALS = 3
SEED = 7


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The study (every case, 3 trials each) on one worker and on two workers."""
    out = {}
    for w in (1, 2):
        d = tmp_path_factory.mktemp(f"w{w}")
        argv = ["validate", "--spec", "triad-alignment", "--trials", str(TRIALS), "--seed",
                str(SEED), "--workers", str(w), "--out", str(d / "v")]
        if w == 2:
            argv += ["--batch", "1"]
        assert main(argv) == 0
        out[w] = (d / "v" / "validation.json").read_bytes()
    return out


def test_the_study_is_byte_identical_on_one_and_two_workers(runs):
    assert runs[1] == runs[2]


def test_every_case_reports_every_item_with_its_statistics(runs):
    d = json.loads(runs[1])
    assert list(d["cases"]) == list(CASES)
    for case, c in d["cases"].items():
        keys = {r["key"] for r in c["items"]}
        assert {f"M_{a}{b}" for a in "xyz" for b in "xyz"} <= keys
        assert {"b_x", "b_y", "b_z", "S_xy", "L_zy"} <= keys
        assert any(k.startswith("K_z_t") for k in keys) and any(k.startswith("b_z_t")
                                                                 for k in keys)
        for r in c["items"]:
            assert r["n"] == TRIALS and 0.0 <= r["cp_low"] <= r["coverage"] <= r["cp_high"]
            assert r["z_mean"] is not None and r["z_sd"] is not None


def test_the_worst_table_sits_at_the_bounds():
    b = load_triad_bench("mems-triad")
    w = worst_table(b)
    bound = math.radians(b.orientation_bound_deg)
    assert w.rate_error_rel == pytest.approx(RATE_ERROR_BOUND_K * b.rate_table_u_rel, rel=1e-15)
    d = np.asarray(w.orientation_error_rad)
    assert np.all(np.diag(d) == 0.0)                      # δ_a ⊥ e_a
    off = d[~np.eye(3, dtype=bool)]
    assert np.allclose(np.abs(off), bound, rtol=1e-15, atol=0)
    # no table within the bounds biases M more, in the table's own u (random corners and
    # interior draws, both signs of the rate error)
    m = b.system_matrix
    u = np.sqrt(np.diag(table_type_b_cov(m, b.rate_table_u_rel, bound / math.sqrt(3))))
    u_m = u[[4 * i + j for i in range(3) for j in range(3)]].reshape(3, 3)

    def score(eps, dd):
        return float(np.sum((table_bias(m, eps, dd) / u_m) ** 2))

    best = score(w.rate_error_rel, d)
    rng = np.random.default_rng(0)
    for _ in range(300):
        dd = rng.uniform(-bound, bound, (3, 3)) * (1 - np.eye(3))
        if rng.random() < 0.5:
            dd = np.sign(dd) * bound
        eps = rng.choice([-1.0, 1.0]) * rng.uniform(0.0, 1.0) * w.rate_error_rel
        assert score(eps, dd) <= best * (1 + 1e-12)
    # the axis case keeps those bounds, its signs fixed, the rate error drawn per trial
    wa = [case_bench("worst-axes", b, s) for s in (11, 12)]
    assert wa[0].rate_error_rel != wa[1].rate_error_rel
    assert np.array_equal(wa[0].orientation_error_rad, wa[1].orientation_error_rad)
    assert np.allclose(np.abs(wa[0].orientation_error_rad[~np.eye(3, dtype=bool)]), bound)


def test_the_worst_case_is_offset_as_the_table_model_says(runs):
    """The simulated calibrations (the bench turns its table at r(1 + ε) about its rotated
    axis) against the first-order closed form: z mean of M_ii = table_bias/u_c, the noise's
    share of u_c being small there (z sd ≤ 0.1)."""
    d = json.loads(runs[1])
    for case in ("worst", "worst-axes"):
        c = d["cases"][case]
        rows = {r["key"]: r for r in c["items"]}
        offs = c["table"]["table_offset_z"]
        for a in "xyz":
            r = rows[f"M_{a}{a}"]
            tol = 0.1 + 4 * r["z_sd"] / math.sqrt(r["n"])
            assert r["z_mean"] == pytest.approx(offs[f"M_{a}{a}"], abs=tol), (case, a)
    w = d["cases"]["worst"]
    assert w["table"]["rate_error_rel"] == pytest.approx(2 * 2.5e-4)
    assert all(abs(w["table"]["table_offset_z"][f"M_{a}{a}"]) > 1.5 for a in "xyz")


def test_the_spread_is_judged_only_where_the_condition_is_drawn(runs):
    """At one fixed condition (worst, worst-axes) z's spread is the noise's: no over-wide flag
    there; in typeb the flag follows sd z < MIN_SD_Z (recomputed here from the printed z sd)."""
    assert set(FIXED_CONDITION_CASES) == {"worst", "worst-axes"}
    d = json.loads(runs[1])
    for case, c in d["cases"].items():
        for r in c["items"]:
            judged = case not in FIXED_CONDITION_CASES
            assert ("over-wide" in r["flags"]) == (judged and r["z_sd"] < MIN_SD_Z), (case, r)


def test_judge_spread_drops_only_the_over_wide_flag():
    """Two trials with z = 0.10 and 0.11 (sd 0.007 < 0.3), one outside U: the judged table
    flags both sides, the fixed-condition one keeps the coverage flag alone."""
    tr = [{"a": {"clause": "c", "value": 1.0 + dz, "truth": 1.0, "U": 0.105, "u_c": 1.0}}
          for dz in (0.10, 0.11)]
    assert coverage_table_from(tr)["flags"][0] == ("under-covers", "over-wide")
    assert coverage_table_from(tr, judge_spread=False)["flags"][0] == ("under-covers",)


def test_typeb_draws_another_table_per_trial():
    seeds = [spawn_seed(SEED, CASE_KEYS["typeb"], i) for i in range(TRIALS)]
    tables = [case_bench("typeb", "mems-triad", s) for s in seeds]
    assert len({t.rate_error_rel for t in tables}) == TRIALS
    assert len({np.asarray(t.orientation_error_rad).tobytes() for t in tables}) == TRIALS


def test_an_unknown_case_is_refused(capsys):
    with pytest.raises(GonioError, match="unknown case nope.*typeb, worst, worst-axes"):
        plan_study(2, seed=0, cases="typeb,nope")
    assert main(["validate", "--spec", "triad-alignment", "--trials", "2",
                 "--cases", "nope"]) == 2
    assert "unknown case nope" in capsys.readouterr().err
