"""``SPEC.truth`` of the optical draft: the true value of the items from the virtual bench's
physical parameters (:mod:`gonio.bench`), never from the estimators of
:mod:`gonio.specs.ogam_draft.items`.

The bench's session carries its own noise-free rerun (``truth["readings"]``: the counts the
instrument would give without noise and the true table angle of every reading, from the
instrument's scale factor, nonlinearity, position harmonics, tilt, Earth rate and the table's
positioning errors, with the instrument at the chamber's temperature), and the noise and
temperature parameters it was run with (``truth["bench"]``).
From those alone:

===============================  ===========================================================
``scale_factor``                 mean over the 7.1 rounds of noise-free counts / true angle,
                                 at the protocol's reference temperature (the chamber's
                                 1 + α_K ΔT divided out, :func:`chamber_scale_factor_ratio`)
``scale_factor_nonlinearity``    (max − min)/mean of those K_i, %
``zero_stability``               √E[s²(M)]/T of the draft's statistic for this instrument's
                                 noise (:func:`~gonio.specs.ogam_draft.item_coverage.zero_stability_truth`)
``angle_deviation``              per point (``points``): mean over the series of the noise-free
                                 deviation at the reference rate; value: the point of largest
                                 magnitude, sign kept (as the item states it)
===============================  ===========================================================

Repeatability (7.5) and the two consistencies (7.6, 7.7) have no entry: R is a property of
the noise over many runs (the study's ensemble truth), and the consistencies' truths depend
on which points a calibration pairs (the study computes them per trial,
:func:`~gonio.specs.ogam_draft.item_coverage.item_record`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from gonio.specs.ogam_draft.bench import Bench, load_bench, run_session
from gonio.specs.ogam_draft.protocol import Protocol, load_protocol
from gonio.specs.ogam_draft.item_coverage import zero_stability_truth
from gonio.specs.ogam_draft.items import signed_extreme


def chamber_scale_factor_ratio(bench: dict) -> float:
    """K in the chamber over K at the reference temperature, 1 + α_K ΔT, from the bench's
    parameters (``truth["bench"]``: the instrument's ``sf_temperature_coeff_ppm_per_c``,
    the chamber's ``chamber_deviation_c``; 1 for a bench file without them).

    >>> chamber_scale_factor_ratio({"chamber_deviation_c": -0.5,
    ...                             "instrument": {"sf_temperature_coeff_ppm_per_c": 2.0}})
    0.999999
    """
    alpha = float(bench.get("instrument", {}).get("sf_temperature_coeff_ppm_per_c", 0.0))
    return 1.0 + 1e-6 * alpha * float(bench.get("chamber_deviation_c", 0.0))


def truth_from_session(session_truth: dict, protocol: Protocol) -> dict:
    """{item: {"value", "how"}} from a session's truth dict (``run_session(...).truth``)."""
    tr = pd.DataFrame(session_truth["readings"])
    out: dict[str, dict] = {}
    if not len(tr):
        return out
    sf = tr[tr["test"] == "scale_factor"]
    if len(sf):
        k_i = sf["noise_free_counts"].to_numpy(float) / sf["true_table_deg"].to_numpy(float) \
            / chamber_scale_factor_ratio(session_truth["bench"])
        out["scale_factor"] = {"value": float(k_i.mean()),
                               "how": "mean over the 7.1 rounds of noise-free counts / true "
                                      "table angle, at the reference temperature (divided by "
                                      "the chamber's 1 + alpha_K dT)"}
        out["scale_factor_nonlinearity"] = {
            "value": float((k_i.max() - k_i.min()) / k_i.mean() * 100.0),
            "how": "(max - min)/mean of the noise-free K_i, %"}
    comp = protocol.session.static_s if protocol.session.earth_compensation == "measured" \
        else None
    b_s = zero_stability_truth(session_truth, comp)
    if b_s is not None:
        out["zero_stability"] = {"value": float(b_s),
                                 "how": "sqrt(E[s(M)^2])/T from the bench's noise parameters "
                                        "and the noise-free readings"}
    ad = tr[(tr["test"] == "angle_deviation")
            & np.isclose(tr["rate_dps"].to_numpy(float), float(protocol.rate_reference_dps))]
    if len(ad):
        t_i = ad.groupby("round")["systematic_deviation_arcsec"].mean().sort_index()
        out["angle_deviation"] = {"value": signed_extreme(t_i.to_numpy()),
                                  "points": [float(x) for x in t_i],
                                  "how": "per point: mean over the series of the noise-free "
                                         "deviation; value the point of largest magnitude"}
    return out


def truth(bench: str | Bench = "rlg", protocol: str | Protocol = "ogam-draft",
          seed: int = 0) -> dict:
    """{item key: {"value": …, "how": …}} of the optical draft's items on ``bench`` under
    ``protocol`` (module docstring): the session's noise-free rerun and noise parameters."""
    proto = protocol if isinstance(protocol, Protocol) else load_protocol(protocol)
    b = bench if isinstance(bench, Bench) else load_bench(bench)
    return truth_from_session(run_session(proto, b, seed=seed).truth, proto)
