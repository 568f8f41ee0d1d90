"""``SPEC.truth`` of the triad alignment: the true value of every alignment item from the
virtual triad's physical parameters (:class:`gonio.specs.triad_alignment.bench.TriadBench`), never from the
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

and the temperature/supply model's certified values (thesis eq. 6.17–6.20):
``K_<ch>_t<i>_v<j>``, ``b_<ch>_t<i>_v<j>``, ``ARW_<ch>_t<i>`` — the bench's K, b, ARW of the
gyro soaked at the programme's i-th chamber set point (ascending; soaked, the die is at the
set point) and j-th supply level (ascending), from the bench's polynomials in the die's
temperature (:func:`gonio.specs.triad_alignment.bench.true_thermal_coefficients` with ``chamber``
coordinates), for every gyro the programme puts on the table axis. The set points and
supply levels are the protocol's; the truth never sees an estimate or the data.

The averaging time has no entry: it is a property of the noise and the target, not a
parameter.
"""

from __future__ import annotations

from gonio.specs.triad_alignment.bench import (TriadBench, TriadProtocol, load_triad_bench, load_triad_protocol,
                               true_thermal_coefficients)

#: Off-diagonal pairs (gyro, about) in the items' order.
PAIRS = ("xy", "xz", "yx", "yz", "zx", "zy")
AXES = "xyz"
#: The default programme whose set points the thermal truths are for.
DEFAULT_PROTOCOL = "triad-alignment"


def truth(bench: str | TriadBench = "mems-triad", protocol=None) -> dict:
    """{item key: {"value": …, "how": …}} of the alignment and thermal items (module
    docstring) from the bench's parameters; ``protocol`` (a TriadProtocol or its name;
    default ``triad-alignment``) gives the thermal programme's set points and supply levels.

    >>> t = truth("mems-triad")
    >>> t["L_xy"]["value"], round(t["S_xy"]["value"] * t["M_xx"]["value"] - t["M_xy"]["value"], 15)
    (0.0, 0.0)
    >>> round(t["b_z_t5_v2"]["value"] * t["M_zz"]["value"] / 49.7, 12)  # 25 °C, 5 V: b_z
    0.08
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
    out.update(thermal_truth(b, protocol))
    return out


def thermal_truth(bench: TriadBench, protocol=None) -> dict:
    """The thermal items' truths (module docstring): each model's polynomial in the die's ϑ
    evaluated at (set point − reference, supply − reference)."""
    p = protocol if isinstance(protocol, TriadProtocol) else load_triad_protocol(
        protocol or DEFAULT_PROTOCOL, "triad-alignment")
    th = p.thermal
    if not th.get("enabled"):
        return {}
    ref_c, ref_v = bench.thermal.reference_c, bench.thermal.reference_v
    setpoints = sorted({round(float(t), 1) for t in th["setpoints_c"]})
    levels = sorted({round(float(v) - ref_v, 6) for v in th["supply_v"]})
    how = ("the bench's thermal polynomial in the die's temperature (true_thermal_coefficients, "
           "chamber coordinates) at the soaked set point and the supply level")
    out: dict[str, dict] = {}
    for ch in sorted({code[1] for code in th["up"]}):
        true = true_thermal_coefficients(bench, ch, temperature="chamber")

        def at(c, theta, u):
            return (sum(v * theta ** int(k[5:]) for k, v in c.items() if k.startswith("theta"))
                    + c["c0"] + sum(v * u ** int(k[1:]) for k, v in c.items()
                                    if k.startswith("u")))
        for i, t_set in enumerate(setpoints, 1):
            theta = t_set - ref_c
            for name in ("K", "b"):
                for j, u in enumerate(levels, 1):
                    out[f"{name}_{ch}_t{i}_v{j}"] = {"value": float(at(true[name], theta, u)),
                                                     "how": how}
            out[f"ARW_{ch}_t{i}"] = {"value": float(at(true["ARW"], theta, 0.0)), "how": how}
    return out
