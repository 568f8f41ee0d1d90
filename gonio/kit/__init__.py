"""The public plug-in kit: everything a specification package written outside gonio uses.

A laboratory's procedure imports from here only (``from gonio.kit import …``); the modules
the names come from may move, these names stay. Each name is gonio's own object,
re-exported, not a copy; docs/kit.md is the reference (contracts, figure roles, the Allan
API, DCC units, coverage settings) and docs/writing-a-specification.md builds a complete
specification with it.

==============================  ==========================================================
The specification               :class:`Specification`, :class:`Coverage`,
                                :class:`lazy`, :func:`item_order`, :func:`get`,
                                :func:`available`, :data:`CONTENT_FIELDS`,
                                :data:`FIGURE_ROLES`, :data:`ITEM_RENDERER`
Results and items               :class:`Result`, :class:`Item`,
                                :class:`Uncertainty`, :class:`Covariance`,
                                :func:`not_measured`, :func:`budget_row`
The item loop                   :class:`ItemDef`, :func:`calibrate_items`
Uncertainty (GUM, Monte Carlo)  :func:`gum`, :func:`monte_carlo_validation`,
                                :func:`std_dev_uncertainty`,
                                :func:`dispersion_uncertainty`,
                                :func:`dispersion_bound_statement`, :func:`from_u`,
                                :func:`type_a`, :func:`type_b`,
                                :class:`InputQuantity`
The statement rule              :func:`state`, :func:`item_statement`,
                                :class:`Statement`
Screening                       :class:`Finding`, :data:`ACTIONS`,
                                :func:`set_aside`, :func:`hampel_residuals`,
                                :func:`too_many_outliers`, :func:`moderate_tail`,
                                :data:`HAMPEL_MIN_ROWS`, :data:`DENSE_SHARE`, :data:`K_TAIL`
Allan deviation and its edf     :func:`allan_deviation`,
                                :func:`modified_allan_deviation`,
                                :func:`hadamard_deviation`,
                                :func:`total_deviation`, :class:`AllanResult`,
                                :func:`averaging_factors`, :func:`edf_for`,
                                :func:`chi2_interval`, :func:`noise_id_lag1`
Coverage studies                :func:`spawn_seed`, :func:`two_sided`,
                                :func:`coverage`
Errors                          :class:`GonioError`
==============================  ==========================================================

Loading the kit imports neither the virtual bench nor the report (calibrating a laboratory's
file stays light; tests/test_kit.py checks it in a fresh interpreter).
"""

from __future__ import annotations

from gonio.analysis.coverage import coverage, spawn_seed, two_sided
from gonio.analysis.noise import (AllanResult, allan_deviation, averaging_factors,
                                  chi2_interval, edf_for, hadamard_deviation,
                                  modified_allan_deviation, noise_id_lag1, total_deviation)
from gonio.analysis.outliers import (DENSE_SHARE, HAMPEL_MIN_ROWS, K_TAIL, hampel_residuals,
                                     moderate_tail, too_many_outliers)
from gonio.errors import GonioError
from gonio.kit.items import ItemDef, calibrate_items
from gonio.result.findings import ACTIONS, Finding, set_aside
from gonio.result.gum import (dispersion_bound_statement, dispersion_uncertainty, gum,
                              monte_carlo_validation, std_dev_uncertainty)
from gonio.result.items import item_order
from gonio.result.model import (Covariance, Item, Result, Uncertainty, budget_row,
                                not_measured)
from gonio.result.statement import Statement, item_statement, state
from gonio.specs import (CONTENT_FIELDS, FIGURE_ROLES, ITEM_RENDERER, Coverage,
                         Specification, available, get, lazy)
from uncertainty import InputQuantity, from_u, type_a, type_b

__all__ = [
    "ACTIONS", "AllanResult", "CONTENT_FIELDS", "Coverage", "Covariance", "DENSE_SHARE",
    "FIGURE_ROLES", "Finding", "GonioError", "HAMPEL_MIN_ROWS", "ITEM_RENDERER", "K_TAIL", "InputQuantity", "Item", "ItemDef", "Result",
    "Specification", "Statement", "Uncertainty", "allan_deviation", "available",
    "averaging_factors", "budget_row", "calibrate_items", "chi2_interval", "coverage",
    "dispersion_bound_statement", "dispersion_uncertainty",
    "edf_for", "from_u", "get", "gum", "hadamard_deviation", "hampel_residuals", "item_order",
    "item_statement",
    "lazy", "moderate_tail", "modified_allan_deviation", "monte_carlo_validation",
    "noise_id_lag1",
    "not_measured", "set_aside", "spawn_seed", "state", "std_dev_uncertainty",
    "too_many_outliers", "total_deviation", "two_sided", "type_a", "type_b",
]
