"""One periodic table error at the A.4.1 bound: its response per order, and the worst order.

The draft bounds the rotary table's angle error by its MPE (A.4.1) and says nothing of its
shape. Beside the standard's reading (each position's error independent, rectangular), the
physical model is one error curve P(x) = a·sin(h·x + φ) of unknown order h, phase φ, size
a ≤ MPE: the errors at all positions come from the same curve and are correlated. A
quantity that is a linear combination Σ c_p P(p) of the curve's values at positions p is
then a·Im(e^{iφ} Σ c_p e^{ihp}), arcsine over φ with half-width a·|Σ c_p e^{ihp}|; the
worst order is the h with the largest |Σ c_p e^{ihp}| (or, for a range between two such
quantities, the largest difference). Three budget lines search that order:

- E_i's table line at a 7.4 point (:func:`gonio.specs.ogam_draft.budget_extra.table_harmonic_line_u`);
- K's table line at the 7.1 stops (:func:`gonio.specs.ogam_draft.item_uncertainty.scale_factor_table_line`);
- K_l's range (:func:`gonio.specs.ogam_draft.item_uncertainty.nonlinearity_table_order`).

All three take the matrix of :func:`periodic_response` and the order of :func:`worst_order`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["periodic_response", "worst_order", "WORST_ORDER_RTOL"]

#: Orders whose response is within this relative distance of the largest count as equal
#: (the lowest of them is the worst order: round-off never picks a higher one).
WORST_ORDER_RTOL = 1e-9


def periodic_response(positions_deg, max_order: int = 360) -> np.ndarray:
    """The matrix e^{i·h·p}: one row per order h = 1 … ``max_order``, one column per
    position p (degrees) — a unit periodic error's phasor at each position (A.4.1, one
    periodic error). Row ``h - 1`` is order h.

    A quantity Σ c_p P(p) has the response ``periodic_response(p) @ c`` per order; its
    modulus times the MPE is the quantity's half-width at that order.

    >>> r = periodic_response([0.0, 90.0, 180.0], 2)
    >>> r.shape, [round(complex(x).real, 12) for x in r[1]]
    ((2, 3), [1.0, -1.0, 1.0])
    """
    h = np.arange(1, int(max_order) + 1)
    return np.exp(1j * np.outer(h, np.radians(np.asarray(positions_deg, dtype=float))))


def worst_order(g) -> int:
    """The worst order of a per-order response ``g`` (``g[h - 1]`` for order h, real, ≥ 0):
    the lowest order whose response equals the largest within :data:`WORST_ORDER_RTOL`.

    >>> worst_order([0.5, 2.0, 1.0, 2.0 * (1.0 - 1e-12)])
    2
    >>> worst_order([1.0, 1.0 + 1e-12, 0.3])
    1
    """
    g = np.asarray(g, dtype=float)
    return int(np.argmax(g >= g.max() * (1.0 - WORST_ORDER_RTOL))) + 1
