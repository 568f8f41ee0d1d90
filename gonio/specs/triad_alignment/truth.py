"""``SPEC.truth`` of the triad alignment: the true value of every alignment item from the
virtual triad's physical parameters (:class:`gonio.bench.triad.TriadBench`), never from the
estimator (:mod:`gonio.specs.triad_alignment.analysis`).

The bench's output is y = M ω + b (at the reference temperature and supply), with
M = diag(K)·(A + C) built from the scale factors K, the sensing-axis matrix A (the
non-orthogonality and mounting angles, exact forms) and the cross-coupling C
(:func:`gonio.physics.alignment.system_matrix`, the one copy of that model), and b = K·b_dps.
So:

========================  ===============================================================
``M_ij``                  M[i, j]
``b_i``                   K_i·b_i (output units)
``S_ij``                  M[i, j]/M[i, i] (IEC 62047-20 5.2: cross-axis sensitivity)
``L_ij``                  0: the leakage M̂⁻¹M − I with the true M is exactly zero
========================  ===============================================================

and the temperature/supply model's coefficients (thesis eq. 6.17–6.20, the certified
``K_<ch>_<term>``, ``b_<ch>_<term>``, ``ARW_<ch>_<term>``) from
:func:`gonio.bench.triad.true_thermal_coefficients` — the bench's polynomials re-expanded in
closed form into the model's coordinates (the gyro's sensor temperature, the default of
``calibrate``) — for every gyro and every term an identified model may select (orders up to
the identification's caps: ϑ⁴ and U² for K and b, ϑ² for ARW); a term the bench lacks is 0.

The averaging time has no entry: it is a property of the noise and the target, not a
parameter.
"""

from __future__ import annotations

from gonio.bench.triad import TriadBench, load_triad_bench, true_thermal_coefficients

#: Off-diagonal pairs (gyro, about) in the items' order.
PAIRS = ("xy", "xz", "yx", "yz", "zx", "zy")
AXES = "xyz"
#: The terms an identified thermal model can certify (the caps of
#: :func:`gonio.specs.triad_alignment.thermal_model.identify_thermal_model`).
THERMAL_TERMS = {"K": ("c0", "theta1", "theta2", "theta3", "theta4", "u1", "u2"),
                 "b": ("c0", "theta1", "theta2", "theta3", "theta4", "u1", "u2"),
                 "ARW": ("c0", "theta1", "theta2")}


def truth(bench: str | TriadBench = "mems-triad", protocol=None) -> dict:
    """{item key: {"value": …, "how": …}} of the alignment and thermal items (module
    docstring) from the bench's parameters; ``protocol`` is accepted for the interface (the
    truth does not depend on the programme).

    >>> t = truth("mems-triad")
    >>> t["L_xy"]["value"], round(t["S_xy"]["value"] * t["M_xx"]["value"] - t["M_xy"]["value"], 15)
    (0.0, 0.0)
    >>> t["b_z_theta4"]["value"], round(t["b_z_u1"]["value"] * t["M_zz"]["value"] / 49.7, 12)
    (0.0, 0.4)
    """
    b = bench if isinstance(bench, TriadBench) else load_triad_bench(bench)
    m = b.system_matrix
    out: dict[str, dict] = {}
    for i, a in enumerate(AXES):
        for j, c in enumerate(AXES):
            out[f"M_{a}{c}"] = {"value": float(m[i, j]),
                                "how": "M = diag(K)(A + C) of the bench's scale factors, "
                                       "non-orthogonality, mounting and cross-coupling"}
    bias = b.bias_output
    for i, a in enumerate(AXES):
        out[f"b_{a}"] = {"value": float(bias[i]), "how": "K_i·b_i of the bench (output units)"}
    for p in PAIRS:
        i, j = AXES.index(p[0]), AXES.index(p[1])
        out[f"S_{p}"] = {"value": float(m[i, j] / m[i, i]), "how": "M_ij/M_ii of the bench's M"}
        out[f"L_{p}"] = {"value": 0.0, "how": "M⁻¹M − I with the true M: zero"}
    for ch in AXES:
        true = true_thermal_coefficients(b, ch)
        for name, terms in THERMAL_TERMS.items():
            for term in terms:
                out[f"{name}_{ch}_{term}"] = {
                    "value": float(true[name].get(term, 0.0)),
                    "how": "the bench's thermal polynomial re-expanded in closed form about "
                           "the sensor's offset (true_thermal_coefficients); 0 where the bench "
                           "has no such term"}
    return out
