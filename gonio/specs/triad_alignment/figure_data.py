"""The series each triad figure draws, computed when the calibration runs and stored in
``results.json`` (``extra.figures``), so that the certificate's figures are a function of the
stored result alone (:mod:`gonio.specs.triad_alignment.figures` draws them; nothing there
computes a model).

``extra.figures`` holds ``alignment`` (None when the alignment was not measured) and
``thermal`` ({gyro: series}, empty without a thermal model):

* ``alignment`` — ``cross_axis`` and ``u_cross_axis``: S_ij and its GUM standard uncertainty
  in :data:`~gonio.specs.triad_alignment.analysis.OFFDIAG` order; ``k``: the largest coverage
  factor of the three fits; ``leakage_u``: the standard uncertainty of M̂⁻¹M − I in the same
  order; ``alignment_matrix``: M̂⁻¹ (3 × 3, full precision, for the leakage against a known
  truth); ``averaging``: the Allan deviation of the static record (``tau_s``, ``adev_dph`` per
  gyro, ``noise_limit_dps``, ``tau_needed_s``) or None.
* ``thermal[ch]`` — ``points`` (the soak points: ``theta_c``, ``u_v``, ``bias_dps``,
  ``scale``, ``arw_deg_sqrt_h``); ``grid_c``: 100 temperatures over the model's range;
  ``levels``: per supply level ``u_v`` the fitted b and K on the grid with their standard
  uncertainties; ``k0`` = K̂(0, 0); the orders (``bias``, ``scale``, ``arw``: ``n_t``,
  ``n_u``, ``criterion``); ``arw_curve`` (ARW on the grid and its u) or None. The ramp
  analysis and the before/after compensation the same figures draw are already stored, in
  ``extra.thermal_model.channels[ch]`` (``ramp``: ``theta_c``, ``bias_dps``,
  ``residual_dps``, rms, hysteresis and lag; ``compensation``: its points and rms), and are
  read from there (:func:`channel_figure` gives the same layout from the analysis objects).

Floats are stored at full precision (JSON round-trips a float exactly); NaN is stored as
null and read back as NaN by the drawing code.
"""

from __future__ import annotations

import numpy as np

from gonio.formats.jsonsafe import json_safe
from gonio.specs.triad_alignment.analysis import OFFDIAG

#: Points of the temperature grid the fitted curves are drawn on.
GRID_POINTS = 100


def _floats(a) -> list:
    return [float(v) for v in np.asarray(a, dtype=float).ravel()]


def alignment_series(al) -> dict:
    """The alignment figure's series of an
    :class:`~gonio.specs.triad_alignment.analysis.AlignmentResult` (module docstring)."""
    avg = al.averaging
    return {
        "cross_axis": _floats(al.derived["cross_axis"]),
        "u_cross_axis": _floats(al.u_derived["cross_axis"]),
        "k": float(np.max(al.coverage_factor)),
        "leakage_u": [float(al.leakage_u["xyz".index(n[0]), "xyz".index(n[1])])
                      for n in OFFDIAG],
        "alignment_matrix": np.asarray(al.alignment_matrix, dtype=float).tolist(),
        "averaging": None if avg is None else {
            "tau_s": _floats(avg.tau_s),
            "adev_dph": [_floats(a) for a in avg.adev_dph],
            "noise_limit_dps": float(avg.noise_limit_dps),
            "tau_needed_s": _floats(avg.tau_needed_s)},
    }


def _orders(fit) -> dict | None:
    if fit is None:
        return None
    return {"n_t": int(fit.n_t), "n_u": int(fit.n_u), "criterion": fit.criterion}


def channel_series(model) -> dict:
    """One gyro's fitted-model series (module docstring) of a
    :class:`~gonio.specs.triad_alignment.thermal_model.ChannelModel`."""
    pts = model.points
    grid = np.linspace(model.theta_range[0], model.theta_range[1], GRID_POINTS)
    levels = []
    for uv in sorted(pts["u_v"].unique()):
        levels.append({"u_v": float(uv),
                       "bias": _floats(model.bias.predict(grid, uv)),
                       "u_bias": _floats(model.bias.u_predict(grid, uv)),
                       "scale": _floats(model.scale.predict(grid, uv)),
                       "u_scale": _floats(model.scale.u_predict(grid, uv))})
    cols = ("theta_c", "u_v", "bias_dps", "scale", "arw_deg_sqrt_h")
    out = {"channel": model.channel,
           "points": {c: _floats(pts[c]) if c in pts else [] for c in cols},
           "grid_c": _floats(grid), "levels": levels,
           "k0": float(model.scale.predict(0.0, 0.0)[0]),
           "bias": _orders(model.bias), "scale": _orders(model.scale),
           "arw": _orders(model.arw), "arw_curve": None}
    if model.arw is not None:
        out["arw_curve"] = {"arw": _floats(model.arw.predict(grid)),
                            "u_arw": _floats(model.arw.u_predict(grid))}
    return out


def channel_figure(model, compensation=None) -> dict:
    """What :func:`~gonio.specs.triad_alignment.figures.thermal_model_panels` and
    ``thermal_check_panels`` draw for one gyro: :func:`channel_series` with the ramp analysis
    and the compensation in their ``results.json`` form (``extra.thermal_model.channels[ch]``
    ``ramp`` and ``compensation``, where the certificate reads them)."""
    return {**channel_series(model),
            "ramp": None if model.ramp is None else json_safe(model.ramp.to_json()),
            "compensation": None if compensation is None else json_safe(compensation.to_json())}


def figure_series(al, thermal) -> dict:
    """``extra.figures`` of a triad calibration: the alignment (or None) and every modelled
    gyro's fitted-model series (module docstring)."""
    return {"alignment": None if al is None else alignment_series(al),
            "thermal": {ch: channel_series(m)
                        for ch, m in (thermal.channels.items() if thermal else ())}}
