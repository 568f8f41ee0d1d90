"""A study's set-asides are visible (gonio.analysis.coverage.coverage): a NaN error (a reading
the screening set aside) is no comparison, so the coverage over the readings used cannot see a
false set-aside; the count per point and the coverage with each set-aside counted as a miss
and as a hit are reported beside it, checked here by counting by hand."""

import numpy as np

from gonio.analysis.coverage import coverage
from gonio.specs.ogam_draft.study import set_aside_lines


def test_set_asides_counted_per_point_with_both_bounds():
    rng = np.random.default_rng(4)
    err = np.abs(rng.normal(0.0, 1.0, (50, 3, 4)))
    err[rng.random(err.shape) < 0.1] = np.nan
    U = np.full(50, 1.96)
    c = coverage(err, U)
    aside = np.isnan(err)
    hits = int((err <= 1.96).sum())          # NaN compares False
    assert c["set_aside"] == int(aside.sum())
    assert c["set_aside_per_point"] == [int(aside[..., j].sum()) for j in range(4)]
    assert c["fraction"] == hits / (err.size - aside.sum())
    assert c["fraction_set_aside_as_miss"] == hits / err.size
    assert c["fraction_set_aside_as_hit"] == (hits + aside.sum()) / err.size
    assert c["fraction_set_aside_as_miss"] <= c["fraction"] <= c["fraction_set_aside_as_hit"]


def test_no_set_aside_adds_no_key():
    c = coverage(np.array([[0.1, 0.5]]), np.array([0.3]))
    assert "set_aside" not in c and "fraction_set_aside_as_miss" not in c


def test_the_study_table_states_them():
    class Case:
        name = "typical"
        summary = {"annex_a": {"systematic": {"coverage_E_ij": coverage(
            np.array([[0.1, np.nan], [0.2, 0.5]]), np.array([0.3, 0.3]))}}}
    (line,) = set_aside_lines([Case()], "systematic")
    assert "set aside 1 of 4" in line and "[0, 1]" in line
    assert "without them 66.7 %" in line and "misses 50.0 %" in line and "hits 75.0 %" in line
