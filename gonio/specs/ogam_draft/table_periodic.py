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

The same three quantities' worst linear combination within the MPE (K's ``P_K``, K_l's D, E's
b_i) is :func:`table_worst_bound`, whose reading of the MPE at the rounds' zero is one
documented ambiguity (:data:`TABLE_ZERO_READINGS`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["periodic_response", "worst_order", "WORST_ORDER_RTOL", "TABLE_ZERO_READINGS",
           "TABLE_ZERO_STATED", "table_worst_bound", "programme_bound"]

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


#: *Ambiguity* (A.4.1 applied to 7.1 and 7.4): what the table's MPE bounds at the rounds'
#: common zero, 0° (the readings :func:`table_worst_bound` takes, labelled).
TABLE_ZERO_READINGS: dict[str, str] = {
    "draft": ("the draft's reading (A.4.1: u(P) = MPE/sqrt(3) per measured angle, every angle "
              "measured from the table's zero): the MPE bounds the angle turned from the zero, "
              "the zero's own error is 0"),
    "physical": ("the physical reading: the MPE bounds the table's deviation at every position "
                 "it reaches, its zero included (the deviation curve about its reference, as a "
                 "table calibration states it), so an angle turned from the zero errs by up to "
                 "2 MPE"),
}
#: The reading stated on the certificate: the physical one holds for every table either
#: reading allows (its bound is never the smaller); the draft's is named beside it.
TABLE_ZERO_STATED = "physical"


def table_worst_bound(coefficients: dict, mpe_arcsec: float,
                      reading: str = TABLE_ZERO_STATED) -> float:
    """*Ambiguity* (A.4.1): the largest |Σ_p c_p e(p)| over the tables within their MPE, for a
    quantity with sensitivities ``coefficients`` {position (° mod 360): c_p} to the table's
    errors e(p) at the positions the rounds reach (K's :func:`~gonio.specs.ogam_draft.
    item_uncertainty.scale_factor_table_coefficients`, a pair of K_l's rounds'
    difference in :func:`~gonio.specs.ogam_draft.item_uncertainty.range_table_bound`, E_i's
    :func:`~gonio.specs.ogam_draft.budget_extra.table_error_coefficients`). The box |e(p)| ≤
    MPE is largest at its vertex sign(c_p) (JCGM 100 4.3.7: a quantity known by its bounds):

    - ``"physical"`` (stated): every position, the common zero 0° included, errs within
      ±MPE: MPE·Σ_p |c_p|;
    - ``"draft"``: A.4.1 bounds each angle measured from the table's zero, e(0°) = 0:
      MPE·Σ_{p ≠ 0°} |c_p|.

    (:data:`TABLE_ZERO_READINGS`.) The draft's stops 60°…360° zeroed at 0°, MPE 0.1″, K's
    coefficients (1/(6θ_k), the zero −Σ 1/(6θ_k), θ in arcseconds): 0.3524 ppm in the
    physical reading, 0.1762 ppm in the draft's (the zero's term is the stops' sum):

    >>> th = [60.0, 120.0, 180.0, 240.0, 300.0]
    >>> c = {t: 1.0 / (6 * t * 3600.0) for t in th}
    >>> c[0.0] = -sum(c.values())
    >>> [round(table_worst_bound(c, 0.1, r) * 1e6, 4) for r in ("physical", "draft")]
    [0.3524, 0.1762]
    """
    if reading not in TABLE_ZERO_READINGS:
        raise ValueError(f"table zero reading must be one of {', '.join(TABLE_ZERO_READINGS)}, "
                         f"got {reading!r}")
    return float(mpe_arcsec) * float(sum(abs(float(c)) for p, c in coefficients.items()
                                         if reading == "physical" or float(p) != 0.0))


def programme_bound(bound_of, read, programme) -> float:
    """A table bound (``bound_of(positions)``) over the rounds read and over the programme's
    rounds, the larger: a round set aside (or not read) never lowers a bound (the 60° round
    carries the largest table term of K and E; without it their bounds would shrink while
    the instrument's and the table's errors did not). ``programme`` None: the rounds read.

    >>> programme_bound(lambda th: 1.0 / min(th), [120.0, 180.0], [60.0, 120.0, 180.0])
    0.016666666666666666
    >>> programme_bound(lambda th: 1.0 / min(th), [120.0, 180.0], None)
    0.008333333333333333
    """
    b = float(bound_of(read))
    return b if programme is None else max(b, float(bound_of(programme)))
