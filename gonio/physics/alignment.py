"""Rotations, misalignment matrices and the mechanical misalignment budget of a gyro triad.

Conventions (used by the triad specification's virtual bench and analysis)
--------------------------------------------------------------------------
* The *reference frame* is the fixture's (rate table's) frame, axes x, y, z. A triad's
  outputs obey G = M ω + b ([Looney-alignment] eq. 14, docs/references.md): ω the rate vector in
  the reference frame, M the 3×3 system matrix, b the bias vector.
* A *sensing-axis matrix* A has as row i the unit vector of gyro i's sensing axis in
  the reference frame, so gyro i sees u_i·ω. With scale factors K_i and a dimensionless
  electrical cross-coupling X (zero diagonal), M = diag(K) (A + X).
* Gyro i's axis leans towards the two other reference axes j, k by the angles φ_ij,
  φ_ik (article eq. 8): u_i has sin φ_ij on axis j, sin φ_ik on axis k and cos ψ_i on its
  own axis, where sin²ψ_i = sin²φ_ij + sin²φ_ik (the *exact* form). The *small-angle*
  form is (1, φ_ij, φ_ik): errors of order φ²/2 (:func:`small_angle_error`).
* A mounting rotation R (case → reference, rotation vector r) turns sensing axes given
  in the case frame, rows of N, into A = N Rᵀ. Exact R = Rz(r_z) Ry(r_y) Rx(r_x);
  small-angle R = I + [r]×.

Mechanical budget (article, "predicting the misalignment after deployment")
---------------------------------------------------------------------------
:func:`ledge_tilt_rad` (eq. 2/3), :func:`screw_clearance_skew_rad` (eq. 4),
:func:`rotation_radius_mm`, :func:`total_misalignment_rad` (eq. 1),
:func:`misalignment_budget` (the worked example, eq. 5a–5c), :func:`misalignment_effect`
(eq. 5–7: cos ψ on the wanted axis, sin ψ leakage), :func:`allowed_cross_axis_angle_rad`
and :func:`allowed_axis_angle_rad` (the platform-stabilisation example, eq. 13b–13d),
:func:`alignment_noise_limit_dps` (eq. 30b).

Where the article's printed numbers differ from exact arithmetic is stated in
:data:`ARTICLE_WORKED_EXAMPLE` and ``docs/alignment.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, asdict

import numpy as np

from gonio.errors import GonioError

AXES = ("x", "y", "z")


# ----------------------------------------------------------------------- rotations
def skew(v) -> np.ndarray:
    """Cross-product matrix [v]×, so that [v]× w = v × w.

    >>> skew([1.0, 2.0, 3.0]) @ np.array([0.0, 0.0, 1.0])
    array([ 2., -1.,  0.])
    """
    x, y, z = (float(c) for c in np.asarray(v, dtype=float).reshape(3))
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def rotation_about_axis(axis, angle_rad: float) -> np.ndarray:
    """Exact rotation by ``angle_rad`` about a unit ``axis`` (Rodrigues' formula).

    R = I + sin θ [a]× + (1 − cos θ) [a]×² — a right-handed (counter-clockwise seen from
    the tip of ``axis``) rotation of vectors.

    >>> rotation_about_axis([0, 0, 1], math.pi / 2).round(12) @ np.array([1.0, 0, 0])
    array([0., 1., 0.])
    """
    a = np.asarray(axis, dtype=float).reshape(3)
    n = float(np.linalg.norm(a))
    if not math.isfinite(n) or n == 0.0:
        raise GonioError(f"rotation axis must be a non-zero finite vector, got {a.tolist()}")
    s = skew(a / n)
    return np.eye(3) + math.sin(angle_rad) * s + (1.0 - math.cos(angle_rad)) * (s @ s)


def rotation_xyz(rx_rad: float, ry_rad: float, rz_rad: float) -> np.ndarray:
    """Exact rotation Rz(rz) Ry(ry) Rx(rx) (roll about x first, then y, then z).

    >>> np.allclose(rotation_xyz(0.1, 0, 0), rotation_about_axis([1, 0, 0], 0.1))
    True
    """
    return (rotation_about_axis([0, 0, 1], rz_rad) @ rotation_about_axis([0, 1, 0], ry_rad)
            @ rotation_about_axis([1, 0, 0], rx_rad))


def small_angle_rotation(rx_rad: float, ry_rad: float, rz_rad: float) -> np.ndarray:
    """First-order rotation I + [r]× (all three angles small, order of application lost).

    >>> float(small_angle_rotation(0, 0, 0.01)[1, 0])
    0.01
    """
    return np.eye(3) + skew([rx_rad, ry_rad, rz_rad])


def small_angle_error(rx_rad: float, ry_rad: float, rz_rad: float) -> float:
    """Largest element of |exact − small-angle| rotation: ≈ θ²/2 for a single angle θ.

    >>> round(small_angle_error(0.0, 0.0, 0.01) / (0.01 ** 2 / 2), 4)
    1.0
    """
    return float(np.max(np.abs(rotation_xyz(rx_rad, ry_rad, rz_rad)
                               - small_angle_rotation(rx_rad, ry_rad, rz_rad))))


def sensing_axes_exact(phi_rad) -> np.ndarray:
    """Sensing-axis matrix (rows unit vectors) from the lean angles φ_ij (exact form).

    ``phi_rad`` is a 3×3 array whose off-diagonal element [i, j] is φ_ij, the lean of
    gyro i towards reference axis j (article eq. 8–10); the diagonal is ignored. Row i
    is (sin φ_ij on j ≠ i, cos ψ_i on i) with cos ψ_i = sqrt(1 − Σ_j sin²φ_ij).

    >>> a = sensing_axes_exact([[0, 0.01, 0.02], [0, 0, 0], [0, 0, 0]])
    >>> round(float(np.linalg.norm(a[0])), 15), round(float(a[0, 1]), 12)
    (1.0, 0.009999833334)
    """
    phi = np.asarray(phi_rad, dtype=float).reshape(3, 3)
    a = np.sin(phi)
    np.fill_diagonal(a, 0.0)
    s2 = np.sum(a * a, axis=1)
    if np.any(s2 >= 1.0) or not np.all(np.isfinite(a)):
        raise GonioError("lean angles too large: Σ sin²φ_ij must be < 1 for every axis")
    a[np.diag_indices(3)] = np.sqrt(1.0 - s2)
    return a


def sensing_axes_small(phi_rad) -> np.ndarray:
    """Small-angle sensing-axis matrix I + φ (off-diagonal φ_ij, diagonal 1).

    >>> sensing_axes_small([[9, 0.01, 0], [0, 9, 0], [0, 0, 9]])[0].tolist()
    [1.0, 0.01, 0.0]
    """
    phi = np.asarray(phi_rad, dtype=float).reshape(3, 3).copy()
    np.fill_diagonal(phi, 0.0)
    return np.eye(3) + phi


def sensing_axis_matrix(nonorth_rad, mount_rad, *, exact: bool = True) -> np.ndarray:
    """A = N Rᵀ: case-frame lean angles ``nonorth_rad`` (3×3, as in
    :func:`sensing_axes_exact`) and mounting rotation vector ``mount_rad`` (x, y, z).

    >>> a = sensing_axis_matrix(np.zeros((3, 3)), [0.0, 0.0, 0.1])
    >>> np.allclose(a, rotation_about_axis([0, 0, 1], 0.1).T)
    True
    """
    if exact:
        n = sensing_axes_exact(nonorth_rad)
        r = rotation_xyz(*mount_rad)
    else:
        n = sensing_axes_small(nonorth_rad)
        r = small_angle_rotation(*mount_rad)
    return n @ r.T


def system_matrix(scale, axes, cross_coupling=None) -> np.ndarray:
    """M = diag(K) (A + X) (article eq. 14, 16): output per unit rate, row per gyro.

    >>> system_matrix([2.0, 3.0, 4.0], np.eye(3)).diagonal().tolist()
    [2.0, 3.0, 4.0]
    """
    k = np.asarray(scale, dtype=float).reshape(3)
    a = np.asarray(axes, dtype=float).reshape(3, 3)
    x = np.zeros((3, 3)) if cross_coupling is None else np.asarray(cross_coupling, float).reshape(3, 3)
    if np.any(np.diag(x) != 0.0):
        raise GonioError("cross-coupling matrix must have a zero diagonal")
    return k[:, None] * (a + x)


def decompose_system_matrix(m) -> dict:
    """Scale factors, unit sensing axes and misalignment angles from a system matrix M.

    K_i = |row i| (the output per unit rate along the gyro's own sensing direction),
    u_i = row_i / K_i, ψ_i = acos(u_ii) (total misalignment of gyro i, article eq. 5–7),
    φ_ij = asin(u_ij) (its lean towards reference axis j, eq. 8), and the cross-axis
    sensitivities S_ij = M_ij / M_ii (IEC 62047-20 5.2: output for a rate about a
    non-input axis, divided by the scale factor and the rate).

    >>> d = decompose_system_matrix(np.diag([2.0, 2.0, 2.0]))
    >>> d["scale"], d["psi_rad"]
    ([2.0, 2.0, 2.0], [0.0, 0.0, 0.0])
    """
    d = decompose_system_matrices(np.asarray(m, dtype=float).reshape(1, 3, 3))
    return {k: v[0].tolist() for k, v in d.items()}


def decompose_system_matrices(m: np.ndarray) -> dict:
    """:func:`decompose_system_matrix` of a stack of system matrices (shape (k, 3, 3)), as
    arrays with the stack first (a Monte Carlo chunk at once)."""
    m = np.asarray(m, dtype=float)
    k = np.linalg.norm(m, axis=2)
    if np.any(k == 0):
        raise GonioError("system matrix has a zero row (a gyro with no output)")
    u = m / k[:, :, None]
    eye = np.eye(3, dtype=bool)
    diag = np.diagonal(m, axis1=1, axis2=2)
    psi = np.arccos(np.clip(np.abs(np.diagonal(u, axis1=1, axis2=2)), -1.0, 1.0))
    phi = np.where(eye, 0.0, np.arcsin(np.clip(u, -1.0, 1.0)))
    s = np.where(eye, 0.0, m / diag[:, :, None])
    return {"scale": k, "axes": u, "psi_rad": psi, "phi_rad": phi, "cross_axis": s}


def first_column_from_orthogonality(col_y, col_z) -> np.ndarray:
    """The x column of a normalised (unit scale factors, orthogonal axes) M from its y and
    z columns (article eq. 35–38): with M a rotation, column x = column y × column z.

    Use only when the axes are known to be orthogonal: a non-orthogonality goes
    straight into the result.

    >>> r = rotation_xyz(0.01, -0.02, 0.03)
    >>> np.allclose(first_column_from_orthogonality(r[:, 1], r[:, 2]), r[:, 0])
    True
    """
    return np.cross(np.asarray(col_y, float).reshape(3), np.asarray(col_z, float).reshape(3))


# ---------------------------------------------------------------- the mechanical budget
def ledge_tilt_rad(height_difference_mm: float, span_mm: float) -> float:
    """Tilt of a module whose mounting ledges differ in height (article eq. 2, eq. 3).

    ψ = atan(ΔH / W): ΔH = H2 − H1, W the distance between the two contact points
    (eq. 2, x axis; eq. 3 uses the package length L for the y axis).

    >>> round(math.degrees(ledge_tilt_rad(0.2, 44.0)), 4)
    0.2604
    """
    if not (span_mm > 0 and math.isfinite(span_mm)):
        raise GonioError(f"span between contact points must be > 0 mm, got {span_mm}")
    if not math.isfinite(height_difference_mm):
        raise GonioError(f"ledge height difference must be finite, got {height_difference_mm}")
    return math.atan(abs(height_difference_mm) / span_mm)


def rotation_radius_mm(hole_spacing_a_mm: float, hole_spacing_b_mm: float) -> float:
    """Half the diagonal between opposite mounting holes (article, worked example).

    >>> round(rotation_radius_mm(39.6, 42.6), 4)
    29.0814
    """
    if hole_spacing_a_mm <= 0 or hole_spacing_b_mm <= 0:
        raise GonioError("hole spacings must be > 0 mm")
    return 0.5 * math.hypot(hole_spacing_a_mm, hole_spacing_b_mm)


def screw_clearance_skew_rad(hole_diameter_mm: float, screw_diameter_mm: float,
                             radius_mm: float) -> float:
    """Skew about the mounting normal allowed by screw/hole clearance (article eq. 4).

    Each of two diagonal screws can move (D_H − D_M)/2 in its hole, in opposite senses,
    on a circle of radius R_S: ψ_Z = atan((D_H − D_M) / (2 R_S)).

    >>> round(math.degrees(screw_clearance_skew_rad(2.85, 2.0, 29.1)), 4)
    0.8367
    """
    if radius_mm <= 0:
        raise GonioError(f"rotation radius must be > 0 mm, got {radius_mm}")
    clearance = hole_diameter_mm - screw_diameter_mm
    if clearance < 0:
        raise GonioError(f"hole diameter {hole_diameter_mm} mm is smaller than the screw "
                         f"diameter {screw_diameter_mm} mm")
    return math.atan(clearance / (2.0 * radius_mm))


def total_misalignment_rad(psi_imu_rad: float, psi_sys_rad: float) -> float:
    """Root-sum-square of the IMU's own and the mounting's misalignment (article eq. 1);
    the two are independent.

    >>> round(math.degrees(total_misalignment_rad(math.radians(1.0), math.radians(0.83))), 4)
    1.2996
    """
    return math.hypot(psi_imu_rad, psi_sys_rad)


def misalignment_effect(psi_rad: float) -> tuple[float, float]:
    """(wanted-axis scale cos ψ, leakage sin ψ) of a misalignment ψ (article eq. 5–7).

    >>> [round(v, 6) for v in misalignment_effect(math.radians(1.0))]
    [0.999848, 0.017452]
    """
    return math.cos(psi_rad), math.sin(psi_rad)


def allowed_cross_axis_angle_rad(max_gyro_angle_deg: float, motion_angle_deg: float) -> float:
    """Largest lean φ keeping the leaked angle θ_motion sin φ within ``max_gyro_angle``
    (article eq. 13c: the y gyro during a 30° heading change, limit 1°).

    >>> round(math.degrees(allowed_cross_axis_angle_rad(1.0, 30.0)), 3)
    1.91
    """
    r = max_gyro_angle_deg / motion_angle_deg
    if not 0 <= r <= 1:
        raise GonioError("the allowed angle must be between 0 and the motion angle")
    return math.asin(r)


def allowed_axis_angle_rad(max_error_deg: float, motion_angle_deg: float) -> float:
    """Largest misalignment ψ keeping θ − θ cos ψ within ``max_error`` (article eq. 13d).

    >>> round(math.degrees(allowed_axis_angle_rad(1.0, 30.0)), 3)
    14.835
    """
    r = 1.0 - max_error_deg / motion_angle_deg
    if not 0 <= r <= 1:
        raise GonioError("the allowed error must be between 0 and the motion angle")
    return math.acos(r)


def alignment_noise_limit_dps(test_rate_dps: float, target_rad: float,
                              fraction: float = 0.1) -> float:
    """Largest noise (rms, °/s) of an averaged reading for an alignment target ψ_T
    (article eq. 30b): the leakage a ψ_T misalignment gives at the test rate,
    ω_TR sin ψ_T, times the allowed ``fraction`` (1/10 in the article).

    >>> from gonio.units import S_PER_H
    >>> round(alignment_noise_limit_dps(100.0, math.radians(0.1)) * S_PER_H, 2)   # °/h
    62.83
    """
    if test_rate_dps <= 0 or target_rad <= 0 or not 0 < fraction <= 1:
        raise GonioError("test rate and target must be > 0 and the fraction in (0, 1]")
    return test_rate_dps * math.sin(target_rad) * fraction


@dataclass(frozen=True)
class MisalignmentBudget:
    """The worked example's chain (article eq. 5a–5c), exact values, in degrees."""

    tilt_x_deg: float            # eq. 5a: ledge height tolerance over W
    rotation_radius_mm: float    # half the hole diagonal
    skew_z_deg: float            # eq. 5b: clearance over 2 R_S
    psi_sys_deg: float           # largest mounting term
    psi_imu_deg: float           # the IMU's axis-to-frame specification
    total_deg: float             # eq. 5c, RSS
    wanted_scale: float          # cos ψ_total
    leakage: float               # sin ψ_total

    def to_dict(self) -> dict:
        return asdict(self)

    def to_text(self) -> str:
        """The chain as printed by ``gonio budget --spec KEY`` of the triad specification (one line a term)."""
        rows = [("ψ_x, ledge tilt (eq. 5a)", self.tilt_x_deg, "°"),
                ("R_S, rotation radius", self.rotation_radius_mm, "mm"),
                ("ψ_z, skew in the holes (eq. 5b)", self.skew_z_deg, "°"),
                ("ψ_sys, largest mounting term", self.psi_sys_deg, "°"),
                ("ψ_IMU, axis-to-frame specification", self.psi_imu_deg, "°"),
                ("ψ_total, RSS (eq. 5c)", self.total_deg, "°"),
                ("cos ψ_total, wanted scale", self.wanted_scale, ""),
                ("sin ψ_total, leakage", self.leakage, "")]
        return "Misalignment budget of the mounting (article eq. 5a–5c)\n" + "".join(
            f"  {name:38s} {v:.6g} {unit}".rstrip() + "\n" for name, v, unit in rows)


def misalignment_budget(*, ledge_tolerance_mm: float, width_mm: float,
                        hole_diameter_mm: float, screw_diameter_mm: float,
                        hole_spacing_mm: tuple[float, float] | None = None,
                        rotation_radius: float | None = None,
                        psi_imu_deg: float) -> MisalignmentBudget:
    """The article's worked budget: ledge tilt (eq. 2), screw-clearance skew (eq. 4),
    ψ_SYS = the larger of the two, total = RSS with the IMU's own ψ_IMU (eq. 1).

    Give the rotation radius directly or the two hole spacings (radius = half the
    diagonal).

    >>> b = misalignment_budget(ledge_tolerance_mm=0.2, width_mm=44.0, hole_diameter_mm=2.85,
    ...                         screw_diameter_mm=2.0, rotation_radius=29.1, psi_imu_deg=1.0)
    >>> round(b.tilt_x_deg, 4), round(b.skew_z_deg, 4), round(b.total_deg, 4)
    (0.2604, 0.8367, 1.3039)
    """
    if (hole_spacing_mm is None) == (rotation_radius is None):
        raise GonioError("give exactly one of hole_spacing_mm and rotation_radius")
    rs = rotation_radius if rotation_radius is not None else rotation_radius_mm(*hole_spacing_mm)
    tilt = math.degrees(ledge_tilt_rad(ledge_tolerance_mm, width_mm))
    skew_z = math.degrees(screw_clearance_skew_rad(hole_diameter_mm, screw_diameter_mm, rs))
    psi_sys = max(tilt, skew_z)
    total = math.degrees(total_misalignment_rad(math.radians(psi_imu_deg), math.radians(psi_sys)))
    c, s = misalignment_effect(math.radians(total))
    return MisalignmentBudget(tilt, rs, skew_z, psi_sys, float(psi_imu_deg), total, c, s)


#: The article's printed values next to the exact ones (see docs/alignment.md).
ARTICLE_WORKED_EXAMPLE = {
    "tilt_x_deg": {"printed": 0.3, "exact": "atan(0.2/44) = 0.2604°",
                   "note": "rounded up to one decimal"},
    "rotation_radius_mm": {"printed": 29.1, "exact": "hypot(39.6, 42.6)/2 = 29.0814 mm"},
    "skew_z_deg": {"printed": 0.83, "exact": "atan(0.85/58.2) = 0.8367° (0.8373° with R_S = 29.0814)",
                   "note": "truncated; rounding gives 0.84°"},
    "total_deg": {"printed": 1.28,
                  "exact": "sqrt(1² + 0.8367²) = 1.3039° (1.2996° even with the printed 0.83)",
                  "note": "1.28° is sqrt(1² + 0.8²): the article's arithmetic used 0.8°"},
    "noise_limit_dph": {"printed": 62, "exact": "100 °/s · sin 0.1° / 10 = 62.83 °/h"},
    "cross_axis_limit_deg": {"printed": 1.9, "exact": "asin(1/30) = 1.910°"},
    "axis_limit_deg": {"printed": 14.8, "exact": "acos(29/30) = 14.835°"},
}


# ------------------------------------------------------- the reference frame on the table
#: Signed reference axes a fixture can point up or north.
SIGNED_AXES = ("+x", "-x", "+y", "-y", "+z", "-z")


def signed_axis(code: str) -> np.ndarray:
    """Unit vector of a signed reference axis ``+x`` … ``-z``.

    >>> signed_axis("-y").tolist()
    [0.0, -1.0, 0.0]
    """
    c = str(code).strip().lower()
    if c not in SIGNED_AXES:
        raise GonioError(f"axis code {code!r} must be one of {', '.join(SIGNED_AXES)}")
    v = np.zeros(3)
    v[AXES.index(c[1])] = 1.0 if c[0] == "+" else -1.0
    return v


def ref_to_enu(up: str, north0: str, table_deg: float = 0.0) -> np.ndarray:
    """Matrix C taking reference-frame vectors to ENU for a fixture with reference axis
    ``up`` along the (vertical) table axis and ``north0`` pointing north at table angle 0,
    the table turned by ``table_deg`` (right-handed about up, i.e. counter-clockwise seen
    from above).

    >>> c = ref_to_enu("+z", "+y")
    >>> np.allclose(c, np.eye(3))
    True
    >>> (ref_to_enu("+z", "+y", 90.0) @ np.array([0.0, 1.0, 0.0])).round(12).tolist()
    [-1.0, 0.0, 0.0]
    """
    u, n = signed_axis(up), signed_axis(north0)
    if abs(float(u @ n)) > 0.5:
        raise GonioError(f"north0 axis {north0} must be perpendicular to the up axis {up}")
    return rotation_about_axis([0, 0, 1], math.radians(table_deg)) @ _to_enu(u, n)


def _to_enu(u: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Rows east, north, up in body (reference) coordinates, for the body vectors ``u``
    pointing up and ``n`` pointing north: the rotation body → ENU (orthonormal)."""
    e = np.cross(n, u)                       # body vector that maps to east
    return np.column_stack([e, n, u]).T


def mount_matrix(up_axis: str, north_axis: str) -> np.ndarray:
    """Rotation body → ENU for a rate gyro's mounting (columns: ENU images of body x, y, z);
    the same frame as :func:`ref_to_enu` at table angle 0, with the rate readings' keys in
    its messages.

    >>> mount_matrix("+z", "+x") @ np.array([0, 0, 1.0])
    array([0., 0., 1.])
    >>> (mount_matrix("+z", "+x") @ np.array([1.0, 0, 0])).tolist()
    [0.0, 1.0, 0.0]
    """
    if up_axis not in SIGNED_AXES or north_axis not in SIGNED_AXES:
        raise GonioError(f"mounting axes must be ±x, ±y, ±z, got {up_axis!r}, {north_axis!r}",
                         key="up_axis")
    u, n = signed_axis(up_axis), signed_axis(north_axis)
    if abs(u @ n) > 0:
        raise GonioError(f"up axis {up_axis} and north axis {north_axis} must be perpendicular",
                         key="north_axis")
    return _to_enu(u, n)


def body_rotation(axis: str, angle_deg: float) -> np.ndarray:
    """Rotation of the gyro body by ``angle_deg`` about its own ``axis`` (±x, ±y, ±z): the
    tilting stand of IEC 62047-20 5.3.3.8. The mounting becomes R = mount_matrix · this.

    >>> np.round(body_rotation("+x", 90.0) @ np.array([0, 0, 1.0]), 12).tolist()
    [0.0, -1.0, 0.0]
    """
    if axis not in SIGNED_AXES:
        raise GonioError(f"stand axis must be ±x, ±y, ±z, got {axis!r}", key="stand_axis")
    a = signed_axis(axis)
    t = math.radians(angle_deg)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(t) * k + (1 - math.cos(t)) * (k @ k)


def input_axis_enu(up_axis: str, north_axis: str) -> np.ndarray:
    """The gyro's input axis (body +z) in ENU for a mounting.

    >>> input_axis_enu("+x", "+y").tolist()
    [-1.0, 0.0, 0.0]
    """
    return mount_matrix(up_axis, north_axis) @ np.array([0.0, 0.0, 1.0])


def mean_earth_rate_ref(earth_enu, up: str, north0: str, table_deg: float,
                        rate_dps: float, duration_s: float) -> np.ndarray:
    """Earth-rate vector in the reference frame averaged over a dwell (same unit as
    ``earth_enu``, the Earth-rate vector in ENU, e.g. from
    :func:`gonio.physics.earth.earth_rate_enu`).

    The vertical part is fixed along ``up``; the horizontal part turns with the table
    and is averaged exactly over the swept angle (zero over whole revolutions; thesis
    [Vagner2015] §5.3: averaging over whole turns cancels the horizontal Earth rate).

    >>> w = np.array([0.0, 1.0, 2.0])
    >>> (mean_earth_rate_ref(w, "+z", "+y", 0.0, 10.0, 36.0).round(12) + 0.0).tolist()
    [0.0, 0.0, 2.0]
    >>> mean_earth_rate_ref(w, "+z", "+y", 0.0, 0.0, 5.0).round(12).tolist()
    [0.0, 1.0, 2.0]
    """
    w = np.asarray(earth_enu, dtype=float).reshape(3)
    c0 = ref_to_enu(up, north0, 0.0)
    h = math.hypot(w[0], w[1])
    az = math.atan2(w[0], w[1])              # azimuth of the horizontal part from north
    t0 = math.radians(table_deg) + az
    sweep = math.radians(rate_dps * duration_s)
    if abs(sweep) < 1e-9:
        ms, mc = math.sin(t0), math.cos(t0)
    else:
        t1 = t0 + sweep
        ms = (math.cos(t0) - math.cos(t1)) / sweep
        mc = (math.sin(t1) - math.sin(t0)) / sweep
    # Rz(-θ)(horizontal of magnitude h at azimuth az) in ENU, averaged, then to the frame
    mean_enu = np.array([h * ms, h * mc, w[2]])
    return c0.T @ mean_enu
