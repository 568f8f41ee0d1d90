"""A calibrated rotary table: its positioning error at stated angles, with uncertainty.

The draft knows the table only by its maximum permissible error (Table 1, ±0.1″; A.4.1), so
K's table line holds the table's error anywhere within that bound — honest for a table at
its bound, over-wide for a good one (docs/draft-readings.md, "A calibrated table"). A
laboratory that has calibrated its table (the table's own certificate, or the equal-division
comparison of IEC 62047-20 A.3, :mod:`gonio.specs.ogam_draft.equal_division`) knows the
error e(x) = indicated − true at each position x, with a standard uncertainty. With it the
7.1 reduction is corrected (the angle turned from the zeroing position z to the stop s is
θ − (e(s) − e(z))/3600) and the table line becomes the calibration's uncertainty propagated
through the same sensitivity (beyond the draft; JCGM 100 5.1.2, 5.2.2 with the covariance).

The file (docs/formats.md, "Table calibration"): CSV, ``#`` comment lines, a header with
``table_deg``, ``error_arcsec`` (indicated − true) and ``u_arcsec`` (standard uncertainty,
k = 1), optionally ``dof`` (the degrees of freedom of u; ∞ when absent). Angles are taken
modulo 360° (360° is the table's 0°). A position the session uses that the calibration does
not list is not interpolated: the item falls back to its MPE line, and says so in the line's
source (:meth:`TableCalibration.lookup`).
"""

from __future__ import annotations

import csv
import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gonio.errors import GonioError

__all__ = ["TableCalibration", "read_table_calibration", "from_equal_division",
           "turned_error_arcsec", "REQUIRED_COLUMNS", "POSITION_TOLERANCE_DEG",
           "MIN_DRAW_DOF", "draw_dof_refusal", "screen_against_mpe", "MPE_SCREEN_K",
           "U_FLOOR_OF_MPE", "position_key"]

REQUIRED_COLUMNS = ("table_deg", "error_arcsec", "u_arcsec")
#: A session's position matches a calibrated one within this (degrees, modulo 360°).
POSITION_TOLERANCE_DEG = 1e-6


def _wrap_deg(x_deg):
    """Angles modulo 360° in [0, 360), 360° − ε folded to 0.

    >>> _wrap_deg(np.array([360.0, -60.0, 359.9999999999])).tolist()
    [0.0, 300.0, 0.0]
    """
    w = np.mod(np.asarray(x_deg, dtype=float), 360.0)
    return np.where(360.0 - w < POSITION_TOLERANCE_DEG, 0.0, w)


def position_key(x_deg: float) -> float:
    """A table position as the budgets key their sensitivities to the table's errors
    ({position: c}): degrees modulo 360 rounded to 1e-6° (:data:`POSITION_TOLERANCE_DEG`),
    360° (and what rounds to it) being 0°, so that one position reached as θ, θ + 360° or
    −(360° − θ) adds to one coefficient (the table has one error there).

    >>> position_key(360.0), position_key(-60.0), position_key(359.9999999), position_key(120)
    (0.0, 300.0, 0.0, 120.0)
    """
    key = round(float(x_deg) % 360.0, 6)
    return 0.0 if key == 360.0 else key


@dataclass(frozen=True)
class TableCalibration:
    """The table's error e = indicated − true at positions, arcsec, its standard uncertainty
    and (optionally) covariance; ``source``: where it came from (printed in the lines)."""

    table_deg: np.ndarray
    error_arcsec: np.ndarray
    u_arcsec: np.ndarray
    source: str
    cov_arcsec2: np.ndarray | None = None
    dof: np.ndarray | None = None
    #: (positions × d) orthonormal basis of the table errors the calibration cannot see
    #: (zero-mean; an equal-division comparison's blind harmonics), or None: all seen.
    blind_basis: np.ndarray | None = None
    #: The harmonic orders (≤ m/2) of that subspace, for the refusal's message.
    blind_orders: tuple = ()
    #: SHA-256 of the file it was read from (None: not read from a file).
    sha256: str | None = None
    #: The file's line of each position (None: not read from a file), for the screen's
    #: messages (:func:`screen_against_mpe`).
    lines: tuple | None = None

    def __post_init__(self):
        pos = _wrap_deg(self.table_deg)
        object.__setattr__(self, "table_deg", pos)
        for name in ("error_arcsec", "u_arcsec"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=float))
        if self.dof is not None:
            object.__setattr__(self, "dof", np.asarray(self.dof, dtype=float))
        srt = np.sort(pos)
        if srt.size > 1 and np.min(np.diff(srt)) < POSITION_TOLERANCE_DEG:
            raise GonioError("table calibration lists one position twice (modulo 360 deg)",
                             file=self.source, column="table_deg")

    def covariance(self) -> np.ndarray:
        """The errors' covariance, arcsec²: the given one, else independent positions."""
        if self.cov_arcsec2 is not None:
            return np.asarray(self.cov_arcsec2, dtype=float)
        return np.diag(self.u_arcsec ** 2)

    def combine(self, c) -> tuple[float, float]:
        """(u, ν) of the linear combination Σ c_p e_p of the calibration's errors (arcsec):
        u² = cᵀVc (JCGM 100 5.1.2; 5.2.2 with the covariance). ν (JCGM 100 G.4.1): ∞
        without ``dof``; positions independent (no covariance given, each position its own
        ν_p): Welch–Satterthwaite, u⁴ / Σ (c_p u_p)⁴/ν_p; a covariance given is one joint
        estimate (an equal-division comparison's least squares: V = s²·M with one s² of ν
        degrees of freedom, so cᵀVc/cᵀ(σ²M)c is χ²_ν/ν whatever c), ν of the positions c
        uses (the smallest where they differ: conservative; Welch–Satterthwaite is for
        independent inputs and overstates ν for correlated ones).

        Two independent positions, u 0.02″ (ν 4) and 0.03″ (ν 9), c = (1, −1):
        ν = (0.02² + 0.03²)²/(0.02⁴/4 + 0.03⁴/9) = 13.0:

        >>> c = TableCalibration([0, 60], [0.0, 0.0], [0.02, 0.03], "t", dof=[4, 9])
        >>> [round(x, 4) for x in c.combine([1.0, -1.0])]
        [0.0361, 13.0]
        """
        c = np.asarray(c, dtype=float)
        u2 = max(float(c @ self.covariance() @ c), 0.0)
        used = np.abs(c) > 0
        if self.dof is None or u2 <= 0.0 or not used.any():
            return math.sqrt(u2), math.inf
        if self.cov_arcsec2 is not None:
            return math.sqrt(u2), float(np.min(self.dof[used]))
        den = float(np.sum((c[used] * self.u_arcsec[used]) ** 4 / self.dof[used]))
        return math.sqrt(u2), (u2 * u2 / den if den > 0 else math.inf)

    def lookup(self, positions_deg) -> tuple[np.ndarray | None, list[float]]:
        """Indices of ``positions_deg`` in the calibration, or (None, the positions it does
        not cover): the caller then keeps its MPE line and names the missing positions.

        >>> c = TableCalibration([0, 60, 120], [0.01, -0.02, 0.03], [0.02] * 3, "t.csv")
        >>> c.lookup([360.0, 120.0])[0].tolist(), c.lookup([60.0, 90.0])
        ([0, 2], (None, [90.0]))
        """
        x = _wrap_deg(positions_deg)
        d = np.abs(x[:, None] - self.table_deg[None, :])
        d = np.minimum(d, 360.0 - d)
        ok = d <= POSITION_TOLERANCE_DEG
        missing = sorted({float(v) for v, hit in zip(x, ok.any(axis=1)) if not hit})
        if missing:
            return None, missing
        return np.argmax(ok, axis=1), []

    def describe(self) -> str:
        """One line for a budget line's source."""
        u = self.u_arcsec
        lo, hi = float(np.min(u)), float(np.max(u))
        us = f"{lo:.3g}″" if math.isclose(lo, hi) else f"{lo:.3g}–{hi:.3g}″"
        cov = "covariance given" if self.cov_arcsec2 is not None else "positions independent"
        return f"table calibration, {self.source}, u {us} (k = 1), {cov}"


def turned_error_arcsec(calibration: TableCalibration, stop_deg, zero_deg
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[float]]:
    """The per-reading table correction, written once (beyond the draft; A.4.1 with the
    table's error known): a reading whose round zeroed the table at ``zero_deg`` and stopped
    it at ``stop_deg`` (both absolute table positions, as the protocol's rounds give them)
    turned θ = stop − zero as the table reads it, truly θ − Δ/3600 with
    Δ = e(stop) − e(zero), arcsec (e = indicated − true). Every item whose reference angle a
    calibrated table corrects takes Δ from here: E per point (7.4,
    :func:`gonio.specs.ogam_draft.calibration.angle_deviation_at_table`) and C_v, C_g per
    reading (7.6, 7.7, :func:`gonio.specs.ogam_draft.calibration.consistency_at_table`).

    Stops are looked up by their absolute position, modulo 360° (:meth:`TableCalibration.lookup`):
    a round zeroed at 90° that turned 30° reads e(120°) − e(90°), not e(30°) − e(0°). Returns
    (Δ per reading, the calibration's index of each stop and of each zero, the positions the
    calibration does not list, sorted): Δ NaN and the index −1 where a reading's stop or zero
    is not listed (nothing is interpolated).

    >>> c = TableCalibration([0, 30, 90, 120], [0.01, 0.02, -0.03, 0.05], [0.02] * 4, "t")
    >>> d, i_s, i_z, miss = turned_error_arcsec(c, [120.0, 30.0, 390.0, 45.0], [90.0, 0.0, 0.0, 0.0])
    >>> [round(float(x), 3) for x in d], i_s.tolist(), miss
    ([0.08, 0.01, 0.01, nan], [3, 1, 1, -1], [45.0])
    """
    stop = np.atleast_1d(np.asarray(stop_deg, dtype=float))
    zero = np.broadcast_to(np.asarray(zero_deg, dtype=float), stop.shape)

    def index(x):
        out = np.full(x.shape, -1, dtype=int)
        for v in np.unique(x):
            i, _ = calibration.lookup([v])
            if i is not None:
                out[x == v] = int(i[0])
        return out

    i_s, i_z = index(stop), index(zero)
    ok = (i_s >= 0) & (i_z >= 0)
    e = calibration.error_arcsec
    delta = np.where(ok, e[np.where(ok, i_s, 0)] - e[np.where(ok, i_z, 0)], np.nan)
    missing = sorted({float(v) for v in _wrap_deg(np.r_[stop[i_s < 0], zero[i_z < 0]])})
    return delta, i_s, i_z, missing


def _float(text: str, path, line: int, column: str) -> float:
    try:
        v = float(text)
    except (TypeError, ValueError):
        raise GonioError(f"expected a number, got {text!r}", file=path, line=line,
                         column=column) from None
    if not math.isfinite(v):
        raise GonioError(f"expected a finite number, got {text!r}", file=path, line=line,
                         column=column)
    return v


def read_table_calibration(path: str | Path) -> TableCalibration:
    """Read a table-calibration CSV (module docstring; docs/formats.md). Every fault is a
    :class:`GonioError` naming the file, line and column."""
    p = Path(path)
    try:
        raw = p.read_bytes()
        text = raw.decode("utf-8-sig")               # a spreadsheet's BOM is no column
    except OSError as e:
        raise GonioError(f"cannot read table calibration: {e.strerror}", file=p) from None
    except UnicodeDecodeError:
        raise GonioError("table calibration is not UTF-8 text", file=p) from None
    rows = [(n, r) for n, r in enumerate(csv.reader(text.splitlines()), 1)
            if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    if not rows:
        raise GonioError("table calibration holds no header", file=p)
    n_head, head = rows[0]
    head = [h.strip() for h in head]
    for c in REQUIRED_COLUMNS:
        if c not in head:
            raise GonioError(f"header lacks column {c} (needs {', '.join(REQUIRED_COLUMNS)})",
                             file=p, line=n_head)
    known = set(REQUIRED_COLUMNS) | {"dof"}
    for c in head:
        if c not in known:
            raise GonioError(f"unknown column (known: {', '.join(sorted(known))})", file=p,
                             line=n_head, column=c)
    if len(rows) < 2:
        raise GonioError("table calibration holds no rows", file=p, line=n_head)
    cols = {c: [] for c in head}
    seen: dict[float, int] = {}
    for n, r in rows[1:]:
        if len(r) != len(head):
            raise GonioError(f"{len(r)} fields, the header has {len(head)}", file=p, line=n)
        for c, v in zip(head, r):
            x = _float(v.strip(), p, n, c)
            if c == "u_arcsec" and not x > 0.0:
                raise GonioError("u_arcsec must be > 0", file=p, line=n, column=c)
            if c == "dof" and (why := draw_dof_refusal(x)):
                raise GonioError(why, file=p, line=n, column=c)
            cols[c].append(x)
        w = float(_wrap_deg(cols["table_deg"][-1]))
        if w in seen:
            raise GonioError(f"position {w:g} deg (modulo 360) listed again (first on line "
                             f"{seen[w]})", file=p, line=n, column="table_deg")
        seen[w] = n
    return TableCalibration(np.array(cols["table_deg"]), np.array(cols["error_arcsec"]),
                            np.array(cols["u_arcsec"]), p.name,
                            dof=np.array(cols["dof"]) if "dof" in cols else None,
                            sha256=hashlib.sha256(raw).hexdigest(),
                            lines=tuple(n for n, _ in rows[1:]))


#: A calibrated error beyond MPE + this many u is a table out of its specification.
MPE_SCREEN_K = 3.0
#: The smallest u a calibration file may state, as a fraction of the table's MPE.
U_FLOOR_OF_MPE = 0.01


def screen_against_mpe(calibration: TableCalibration, mpe_arcsec: float) -> None:
    """A calibration file's numbers against the table's maximum permissible error as the
    readings state it (``table_mpe_arcsec``, the draft's Table 1 / A.4.1): a GonioError
    naming the file, line and column of the first implausible row, else None. The one rule
    (beyond the draft; documented in docs/formats.md, "Table calibration"):

    * |e| > MPE + 3u: the calibration shows the table outside its specification beyond any
      plausible doubt (3u: a normal's 99.7 %); a table out of specification is repaired or
      its MPE restated in the readings, never certified through silently;
    * u > MPE: a calibration that cannot tell whether the table meets its MPE is no better
      than the MPE line (leave it out);
    * u < MPE/100 (0.001″ at the draft's 0.1″): below what any angle standard reaches (the
      best national comparators state some 0.005–0.01″), a typo or a unit slip, and it
      would make the table line vanish from K, E, C_v and C_g.

    A calibration not read from a file (an equal-division comparison's, whose gauge
    position has u = 0 by construction) is not screened here.

    >>> c = TableCalibration([0, 120], [0.01, 0.2], [0.02, 0.02], "t.csv", lines=(2, 3))
    >>> screen_against_mpe(c, 0.1)
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: t.csv:3: column error_arcsec: error 0.2″ at 120 deg is beyond the table's MPE 0.1″ + 3u (0.06″): the table is out of its specification (repair it, or state its MPE in the readings' table_mpe_arcsec)
    """
    if calibration.lines is None:
        return
    mpe = float(mpe_arcsec)
    floor = U_FLOOR_OF_MPE * mpe
    for x, e, u, n in zip(calibration.table_deg, calibration.error_arcsec,
                          calibration.u_arcsec, calibration.lines):
        where = dict(file=calibration.source, line=n)
        if u > mpe:
            raise GonioError(f"u {u:g}″ at {x:g} deg is above the table's MPE {mpe:g}″: "
                             "such a calibration cannot show the table within it (leave it "
                             "out: the MPE line is used)", column="u_arcsec", **where)
        if u < floor:
            raise GonioError(f"u {u:g}″ at {x:g} deg is below {floor:g}″ (the table's MPE "
                             f"{mpe:g}″ / {1 / U_FLOOR_OF_MPE:g}), beyond any angle standard: "
                             "a typo or a unit slip?", column="u_arcsec", **where)
        if abs(e) > mpe + MPE_SCREEN_K * u:
            raise GonioError(f"error {e:g}″ at {x:g} deg is beyond the table's MPE {mpe:g}″ "
                             f"+ {MPE_SCREEN_K:g}u ({MPE_SCREEN_K * u:g}″): the table is out of "
                             "its specification (repair it, or state its MPE in the readings' "
                             "table_mpe_arcsec)", column="error_arcsec", **where)


#: The smallest degrees of freedom a calibration's u may state (:func:`draw_dof_refusal`).
MIN_DRAW_DOF = 3.0


def draw_dof_refusal(dof) -> str | None:
    """Why a calibration's degrees of freedom cannot enter, or None: every ν must be ≥ 3
    (or ∞). The one rule for how a calibration of few degrees of freedom enters (beyond the
    draft).

    Its errors enter the range items' Monte Carlo as scaled-and-shifted t_ν
    (JCGM 101 6.4.9, :func:`gonio.specs.ogam_draft.item_uncertainty.calibration_error_draws`),
    whose variance ν/(ν − 2)·u² exists only for ν > 2 (no mean either for ν ≤ 1). That
    Monte Carlo is summarised by moments as JCGM 101 7.5/7.6 summarise one (the corrected
    range's bias as a mean range, its u and the choice of the extreme's u as standard
    deviations): for ν ≤ 2 these are sample noise, and the certified interval came out
    narrower, not wider, as the table became less well known (C_g's width halved at ν = 2 on
    ``gonio simulate --seed 3``). Such a calibration is refused rather than floored (a floor
    at 3 would state a better-known table than the certificate does) or summarised by
    quantiles (a second, unvalidated estimator); ν = 3, the smallest integer with a variance,
    is the floor (2 < ν < 3 has a variance, ν/(ν − 2)·u², 5·u² at 2.5, but one that grows
    without bound towards 2 and whose sample estimate has none itself: refused with the
    variance stated). A certificate with ν ≤ 2 is stated with k from t_ν; enter it without
    ``dof`` only if its u is first expanded to a normal one (u·k_ν/k_∞), which is the
    laboratory's decision, not gonio's.

    >>> draw_dof_refusal(3), draw_dof_refusal(math.inf), draw_dof_refusal([30.0, 4.0])
    (None, None, None)
    >>> draw_dof_refusal(2.0).split(";")[0]
    "dof must be >= 3, gonio's floor: a t of 2 degrees of freedom has no variance"
    >>> draw_dof_refusal(2.5).split(";")[0]
    "dof must be >= 3, gonio's floor: a t of 2.5 degrees of freedom has variance 5·u², growing without bound as ν falls to 2"
    """
    nu = np.asarray(dof, dtype=float)
    bad = nu[~(nu >= MIN_DRAW_DOF)]
    if bad.size == 0:
        return None
    low = float(np.nanmin(bad)) if np.isfinite(bad).any() else float(bad[0])
    if low > 2.0:
        why = (f"a t of {low:g} degrees of freedom has variance {low / (low - 2.0):.3g}·u², "
               "growing without bound as ν falls to 2")
    else:
        why = f"a t of {low:g} degrees of freedom has no variance"
    return (f"dof must be >= {MIN_DRAW_DOF:g}, gonio's floor: {why}; the Monte Carlo of K_l, "
            "C_v and C_g is summarised by moments, sample noise near ν = 2, so ν below 3 (the "
            "smallest integer with a variance) is refused")


def _eda_blind(eda) -> tuple[np.ndarray | None, tuple]:
    """The zero-mean table subspace an equal-division comparison cannot see (orthonormal
    basis over its m positions) and its harmonic orders ≤ m/2, from its starts and step
    (the fit's own null space, :func:`gonio.specs.ogam_draft.equal_division.harmonic_transfer`;
    IEC 62047-20 A.3: for n equally spaced starts the orders that are multiples of n)."""
    if not int(getattr(eda, "unobservable_dim", 0) or 0) > 0:
        return None, ()
    from gonio.specs.ogam_draft import equal_division as ed

    m = int(np.asarray(eda.table_position_deg).size)
    step = float(eda.step_deg)
    basis = ed.blind_table_basis(eda.start_deg, step)
    h = ed.harmonic_transfer(eda.start_deg, step, m // 2)
    orders = tuple(int(o) for o, blind in zip(h["order"], h["gonio_absorbs_table"]) if blind)
    return (basis if basis.shape[1] else None), orders


def from_equal_division(eda, source: str = "equal-division comparison (IEC 62047-20 A.3)"
                        ) -> TableCalibration:
    """The table errors of an :class:`~gonio.specs.ogam_draft.equal_division.EdaResult` with
    their covariance (its gauge's constant cancels in e(stop) − e(zero)), ν its residual dof,
    and the subspace it cannot see (its blind harmonics where its n starts are fewer than its
    m positions: ``blind_basis``, ``blind_orders``)."""
    pos = np.asarray(eda.table_position_deg, dtype=float)
    dof = np.full(pos.size, float(eda.dof)) if getattr(eda, "dof", 0) else None
    basis, orders = _eda_blind(eda)
    return TableCalibration(pos, np.asarray(eda.table_error_arcsec, dtype=float),
                            np.asarray(eda.table_u_arcsec, dtype=float), source,
                            cov_arcsec2=np.asarray(eda.table_cov_arcsec2, dtype=float), dof=dof,
                            blind_basis=basis, blind_orders=orders)
