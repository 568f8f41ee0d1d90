"""The consistencies' choice of each condition's signed extreme (7.6, 7.7): the Monte Carlo of
the draft's functional (extreme_selection) against closed forms of the expected maximum of
normal variables."""

from __future__ import annotations

import math

import pytest

from gonio.specs.ogam_draft.item_uncertainty import (ConditionDeviation, consistency_budget,
                                                     extreme_selection)


def test_bias_of_a_tie_is_the_expected_maximum_of_two_normals():
    """Condition a's curve has two equal excursions (+1″ at 30° and 60°), b one point far
    below: the draft's E_a is the larger of two N(1, σ) readings, whose expectation is
    1 + σ/√π (the expected maximum of two independent normals); b has no choice."""
    s = 0.05
    tie = [([30.0, 60.0], [1.0, 1.0]), ([30.0], [-5.0])]
    u, bias = extreme_selection(tie, [s, s], 0.0, 0.0, draws=40_000)
    assert bias == pytest.approx(s / math.sqrt(math.pi), rel=0.03)
    # the spread of the larger of two is σ√(1 − 1/π) < σ: the choice adds no variance here
    assert u == 0.0


def test_bias_of_three_ties_and_opposite_signs():
    """Three equal excursions (+2″): E[max of 3 N(0, 1)] = 3/(2√π), so a's free choice is
    3σ/(2√π) above its held point. b's curve has +1″ and −1″: the estimate holds −1″ (the
    first of the tie in magnitude), the free choice takes the signed value of larger
    magnitude of −1 + n₁ and 1 + n₂, whose mean is 0 by symmetry, so b adds −(0 − (−1))."""
    s = 0.04
    curves = [([10.0, 20.0, 30.0], [2.0, 2.0, 2.0]), ([10.0, 20.0], [-1.0, 1.0])]
    _, bias = extreme_selection(curves, [s, s], 0.0, 0.0, draws=60_000)
    expect = 3.0 / (2.0 * math.sqrt(math.pi)) * s - 1.0
    assert bias == pytest.approx(expect, abs=0.01)


def test_budget_keeps_the_value_and_states_the_choice_in_u():
    """consistency_budget does not subtract the plug-in bias (it moved the optical study's z
    the wrong way, see extreme_selection); C_sel's u is extreme_selection's u."""
    cs = [ConditionDeviation("60", 1.0, 60.0, 0.05, 1), ConditionDeviation("10", -5.0, 30.0,
                                                                              0.05, 1)]
    curves = [([30.0, 60.0], [1.0, 0.97]), ([30.0], [-5.0])]
    kw = dict(table_mpe_arcsec=0.0, drift_half_width_arcsec=0.0)
    b = consistency_budget("rate_consistency", cs, 1296000.0, 1e6, **kw, curves=curves)
    u, bias = extreme_selection(curves, [0.05, 0.05], 0.0, 0.0)
    assert b.value == pytest.approx(6.0 / 1.296)
    sel = [c for c in b.components if c.symbol == "C_sel"][0]
    assert sel.u == pytest.approx(u / 1.296, rel=1e-12) and bias > 0.005
