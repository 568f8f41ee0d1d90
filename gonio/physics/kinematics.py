"""Table motion profiles and the tilted sensing axis on a turning table.

A rotary-table session is a :class:`Timeline`: a sequence of segments, each a
rest (dwell) or a trapezoidal move (constant acceleration, cruise at the set
rate, constant deceleration; triangular when the move is too short to reach
the rate). Angle and rate are closed-form in each segment, so the truth can be
evaluated exactly at any instant, vectorised over many instants.

The sensing axis of a goniometer mounted with a tilt ψ (its azimuth α in the
table frame) cones around the table axis as the table turns (draft Annex A.1;
``docs/draft-readings.md#a-tilted-axis-on-a-rotating-table``):

    n(θ) = cos ψ · a + sin ψ · (cos(θ+α) e₁ + sin(θ+α) e₂)

so a rate gyro senses ω·n = θ̇ cos ψ + Ω·n(θ).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from gonio.errors import GonioError


def trapezoid_duration_s(distance_deg: float, rate_dps: float, accel_dps2: float) -> float:
    """Time of a rest-to-rest trapezoidal move of ``distance_deg``, s.

    Cruise at ``rate_dps`` if the move is long enough (|D| ≥ ω²/a), else a
    triangular profile with peak rate sqrt(a|D|).

    >>> trapezoid_duration_s(360.0, 60.0, 60.0)     # 6 s cruise-equivalent + ω/a
    7.0
    >>> round(trapezoid_duration_s(1.0, 60.0, 60.0), 6)   # triangular: 2·sqrt(D/a)
    0.258199
    """
    d = abs(distance_deg)
    if d == 0.0:
        return 0.0
    if d >= rate_dps * rate_dps / accel_dps2:
        return d / rate_dps + rate_dps / accel_dps2
    return 2.0 * math.sqrt(d / accel_dps2)


@dataclass(frozen=True)
class Segment:
    """One segment of a :class:`Timeline`: a dwell, or a trapezoidal (or triangular) move.

    The move starts at ``t0_s`` from ``theta0_deg`` and turns ``sign·distance_deg``
    with peak rate ``peak_rate_dps``, accelerating at ``accel_dps2`` for
    ``accel_time_s`` at each end, in ``duration_s``.
    """

    t0_s: float
    theta0_deg: float
    sign: float
    distance_deg: float
    peak_rate_dps: float
    accel_dps2: float
    accel_time_s: float
    duration_s: float


#: Fewest times per run of one segment (on average) for :meth:`Timeline.angle_rate` to
#: evaluate run by run rather than element-wise.
_RUN_MIN = 256


@dataclass
class Timeline:
    """Piecewise closed-form motion of a table (angles in degrees, times in s).

    Build with :meth:`dwell` and :meth:`move`; evaluate with :meth:`angle_deg`
    and :meth:`rate_dps` on arrays of times.

    >>> tl = Timeline(start_angle_deg=0.0)
    >>> _ = tl.dwell(1.0); arrive = tl.move(90.0, rate_dps=30.0, accel_dps2=60.0)
    >>> arrive                                   # 1 s rest + 3 s + 0.5 s
    4.5
    >>> tl.angle_deg(np.array([0.5, 4.5, 10.0])).tolist()
    [0.0, 90.0, 90.0]
    >>> float(tl.rate_dps(np.array([2.5]))[0])
    30.0
    """

    start_angle_deg: float = 0.0
    t0_s: float = 0.0
    _t0: list = field(default_factory=list)
    _theta0: list = field(default_factory=list)
    _sign: list = field(default_factory=list)
    _dist: list = field(default_factory=list)
    _vpk: list = field(default_factory=list)
    _acc: list = field(default_factory=list)
    _tacc: list = field(default_factory=list)
    _dur: list = field(default_factory=list)
    _arrays: tuple | None = None

    @property
    def end_s(self) -> float:
        """Time at the end of the last segment."""
        return self.t0_s if not self._t0 else self._t0[-1] + self._dur[-1]

    @property
    def end_angle_deg(self) -> float:
        """Angle at the end of the last segment."""
        if not self._t0:
            return self.start_angle_deg
        return self._theta0[-1] + self._sign[-1] * self._dist[-1]

    def segments(self) -> list["Segment"]:
        """The motion as segments (a dwell has distance 0), for exact integrals over it.

        >>> tl = Timeline(); _ = tl.dwell(1.0); _ = tl.move(90.0, 30.0, 60.0)
        >>> [(s.t0_s, s.duration_s, s.distance_deg, s.accel_time_s) for s in tl.segments()]
        [(0.0, 1.0, 0.0, 0.0), (1.0, 3.5, 90.0, 0.5)]
        """
        return [Segment(*v) for v in zip(self._t0, self._theta0, self._sign, self._dist,
                                         self._vpk, self._acc, self._tacc, self._dur)]

    def _append(self, duration, dist, vpk, acc, tacc, sign):
        t_start, theta_start = self.end_s, self.end_angle_deg
        self._t0.append(t_start)
        self._theta0.append(theta_start)
        self._sign.append(sign)
        self._dist.append(dist)
        self._vpk.append(vpk)
        self._acc.append(acc)
        self._tacc.append(tacc)
        self._dur.append(duration)
        self._arrays = None

    def dwell(self, duration_s: float) -> float:
        """Rest for ``duration_s``; returns the time at its end."""
        if duration_s < 0 or not math.isfinite(duration_s):
            raise GonioError(f"dwell duration must be ≥ 0 s, got {duration_s}")
        if duration_s > 0:
            self._append(duration_s, 0.0, 0.0, 1.0, 0.0, 1.0)
        return self.end_s

    def move(self, to_deg: float, rate_dps: float, accel_dps2: float) -> float:
        """Trapezoidal move to ``to_deg``; returns the arrival time."""
        if not (rate_dps > 0 and accel_dps2 > 0):
            raise GonioError(f"move needs rate > 0 and acceleration > 0, got {rate_dps}, {accel_dps2}")
        d = to_deg - self.end_angle_deg
        dist = abs(d)
        if dist == 0.0:
            return self.end_s
        sign = 1.0 if d > 0 else -1.0
        if dist >= rate_dps * rate_dps / accel_dps2:
            vpk, tacc = rate_dps, rate_dps / accel_dps2
        else:
            tacc = math.sqrt(dist / accel_dps2)
            vpk = accel_dps2 * tacc
        self._append(trapezoid_duration_s(dist, rate_dps, accel_dps2), dist, vpk,
                     accel_dps2, tacc, sign)
        return self.end_s

    def _arr(self):
        if self._arrays is None:
            self._arrays = tuple(np.asarray(v, dtype=float) for v in (
                self._t0, self._theta0, self._sign, self._dist, self._vpk, self._acc,
                self._tacc, self._dur))
        return self._arrays

    def _locate(self, t):
        t0, th0, sg, dist, vpk, acc, tacc, dur = self._arr()
        t = np.asarray(t, dtype=float)
        if t0.size == 0:
            z = np.zeros_like(t)
            return t, None, z
        i = np.clip(np.searchsorted(t0, t, side="right") - 1, 0, t0.size - 1)
        tau = np.clip(t - t0[i], 0.0, dur[i])
        return t, i, tau

    def angle_deg(self, t) -> np.ndarray:
        """Table angle at times ``t`` (s), degrees (closed form)."""
        t, i, tau = self._locate(t)
        if i is None:
            return np.full_like(t, self.start_angle_deg)
        return self._angle(self._segment(t, i, tau), tau)

    def rate_dps(self, t) -> np.ndarray:
        """Table rate at times ``t`` (s), °/s (closed form)."""
        t, i, tau = self._locate(t)
        if i is None:
            return np.zeros_like(t)
        return self._rate(self._segment(t, i, tau), tau)

    def angle_rate(self, t) -> tuple[np.ndarray, np.ndarray]:
        """``(angle_deg(t), rate_dps(t))``: the same values, each time's segment and
        phase (accelerating, cruising, braking) found once for both.

        Times that fall in one segment in a row (sorted times: each segment's times) are
        evaluated together with that segment's parameters as scalars, each phase's formula
        on its own times only (:meth:`_angle_rate_runs`); times that change segment at
        nearly every step, a scalar and a grid of times take the element-wise form. Both give the values of
        :meth:`angle_deg` and :meth:`rate_dps`, bit for bit (the same operations on the
        same operands)."""
        t, i, tau = self._locate(t)
        if i is None:
            return np.full_like(t, self.start_angle_deg), np.zeros_like(t)
        if t.ndim != 1:                        # a scalar or a grid: element-wise
            seg = self._segment(t, i, tau)
            return self._angle(seg, tau), self._rate(seg, tau)
        cut = np.flatnonzero(i[1:] != i[:-1]) + 1
        if (cut.size + 1) * _RUN_MIN > t.size:
            seg = self._segment(t, i, tau)
            return self._angle(seg, tau), self._rate(seg, tau)
        return self._angle_rate_runs(t, i, tau, cut)

    def _angle_rate_runs(self, t, i, tau, cut) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`angle_rate` run by run: ``cut`` the indices where the segment ``i``
        changes. Per run, the formulas of :meth:`_angle` and :meth:`_rate` on the times of
        each phase, with the segment's values as Python floats (IEEE doubles, as the
        array elements they were read from: the same products and sums)."""
        t0, th0, sg, dist, vpk, acc, tacc, dur = (x.tolist() for x in self._arr())
        first, end_s = t0[0], self.end_s
        n = t.size
        ang, rate = np.empty(n), np.empty(n)
        starts = [0] + cut.tolist()
        for p, q, j in zip(starts, starts[1:] + [n], i[starts].tolist()):
            s, r = np.zeros(q - p), np.zeros(q - p)
            d = dist[j]
            if d != 0.0:                       # a move (a dwell's angle and rate are nil)
                a, ta, T, v = acc[j], tacc[j], dur[j], vpk[j]
                tj = tau[p:q]
                up = tj < ta
                cruise = ~up & (tj <= T - ta)
                down = ~(up | cruise)
                x = tj[up]
                s[up] = 0.5 * a * x * x
                r[up] = a * x
                s[cruise] = 0.5 * a * ta * ta + v * (tj[cruise] - ta)
                r[cruise] = v
                x = T - tj[down]
                s[down] = d - 0.5 * a * x ** 2
                r[down] = a * x
                ts = t[p:q]
                if j == 0:                     # before the first segment: at rest
                    before = ts < first
                    s[before] = 0.0
                    r[before] = 0.0
                r[ts > end_s] = 0.0            # after the last: at rest at its end
            ang[p:q] = th0[j] + sg[j] * s
            rate[p:q] = sg[j] * r
        return ang, rate

    def _segment(self, t, i, tau) -> dict:
        """The segment of each time (its start angle, sign, acceleration a, acceleration
        time ta, duration T, peak rate v, distance D) and the phase masks."""
        t0, th0, sg, dist, vpk, acc, tacc, dur = self._arr()
        a, ta, T = acc[i], tacc[i], dur[i]
        D = dist[i]
        return {"th0": th0[i], "sg": sg[i], "a": a, "ta": ta, "T": T, "v": vpk[i], "D": D,
                "nil": D == 0.0, "up": tau < ta, "cruise": tau <= T - ta,
                "before": t < t0[0], "t": t}

    def _angle(self, g: dict, tau) -> np.ndarray:
        a, ta, T, v, D = g["a"], g["ta"], g["T"], g["v"], g["D"]
        up = 0.5 * a * tau * tau
        cruise = 0.5 * a * ta * ta + v * (tau - ta)
        down = D - 0.5 * a * (T - tau) ** 2
        s = np.where(g["up"], up, np.where(g["cruise"], cruise, down))
        s = np.where(g["nil"], 0.0, s)
        s = np.where(g["before"], 0.0, s)
        return g["th0"] + g["sg"] * s

    def _rate(self, g: dict, tau) -> np.ndarray:
        a, T, v = g["a"], g["T"], g["v"]
        r = np.where(g["up"], a * tau, np.where(g["cruise"], v, a * (T - tau)))
        r = np.where(g["nil"] | g["before"] | (g["t"] > self.end_s), 0.0, r)
        return g["sg"] * r


def sensing_axis_basis(axis_enu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors e₁, e₂ completing the table axis ``a`` to a right-handed frame.

    e₁ is the horizontal direction nearest east for a vertical axis; in general
    e₁ ⟂ a is chosen deterministically, e₂ = a × e₁.

    >>> e1, e2 = sensing_axis_basis(np.array([0.0, 0.0, 1.0]))
    >>> e1.tolist(), e2.tolist()
    ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    """
    a = np.asarray(axis_enu, dtype=float)
    a = a / np.linalg.norm(a)
    ref = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    e1 = ref - (ref @ a) * a
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    return e1, e2


def sensing_axis(theta_deg, axis_enu: np.ndarray, tilt_deg: float,
                 tilt_azimuth_deg: float) -> np.ndarray:
    """Sensing-axis unit vectors n(θ) in ENU, shape (len(θ), 3).

    >>> n = sensing_axis(np.array([0.0, 90.0]), np.array([0.0, 0.0, 1.0]), 90.0, 0.0)
    >>> n.round(12).tolist()
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    """
    a = np.asarray(axis_enu, dtype=float)
    a = a / np.linalg.norm(a)
    e1, e2 = sensing_axis_basis(a)
    psi = math.radians(tilt_deg)
    ang = np.radians(np.asarray(theta_deg, dtype=float) + tilt_azimuth_deg)
    return (math.cos(psi) * a[None, :]
            + math.sin(psi) * (np.cos(ang)[:, None] * e1[None, :]
                               + np.sin(ang)[:, None] * e2[None, :]))
