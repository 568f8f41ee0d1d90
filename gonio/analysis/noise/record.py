"""Noise analysis of a whole record: deviation, model fit and sinusoid check, and the
choice of the static windows of a stream (the table must be at rest).

Contents
--------
=============================  ==============================================
:class:`StaticNoiseResult`     deviation + fit + sinusoid (+ the window used)
:func:`analyse_record`         any input type (used by ``gonio noise``)
:func:`analyse_static`         draft 7.3 static record (time, angle in degrees)
:class:`StaticWindow`          one interval of a stream where the table rests
:func:`static_windows`         the rests of a stream, or the operator's window
:func:`select_window`          the window to analyse (longest by default)
:func:`source_windows`         :func:`static_windows` of a stream file, read in pieces
:func:`window_record`          one window's counts, in memory or memory-mapped
=============================  ==============================================

Memory: ``gonio noise`` never holds a whole stream. The file is read once in
blocks to find the rests (:func:`source_windows`, the reducer's own rest finder on the
same samples), then only the chosen window's counts are read, piece by piece, into one
float64 array — in memory up to :data:`MEMMAP_SAMPLES` samples, beyond that in a
memory-mapped temporary file — and analysed in place (the estimators work in blocks).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gonio.analysis.noise.allan import AllanResult, allan_deviation
from gonio.analysis.noise.fit import (
    NoiseFit, SinusoidDetection, detect_sinusoid, fit_noise_model,
)
from gonio.errors import GonioError
from gonio.units import S_PER_H

__all__ = ["StaticNoiseResult", "StaticWindow", "analyse_record", "analyse_static",
           "static_windows", "select_window", "MOTION_THRESHOLD_DPS", "source_windows",
           "window_record", "MEMMAP_SAMPLES"]

#: Table rate above which a sample counts as motion, °/s (the reducer's default rest
#: threshold on the encoder, gonio.reduce.rests.TABLE_RATE_THRESHOLD_DPS).
MOTION_THRESHOLD_DPS = 0.01


@dataclass
class StaticWindow:
    """Samples ``i_start`` … ``i_end`` (inclusive) of a stream, times in s."""

    i_start: int
    i_end: int
    t_start_s: float
    t_end_s: float
    source: str  # "rest" (found by the reducer) or "option" (--window)

    @property
    def duration_s(self) -> float:
        """Length of the window, s."""
        return self.t_end_s - self.t_start_s

    def to_dict(self) -> dict:
        """Plain dict."""
        return {"i_start": int(self.i_start), "i_end": int(self.i_end),
                "t_start_s": float(self.t_start_s), "t_end_s": float(self.t_end_s),
                "duration_s": float(self.duration_s), "source": self.source}


@dataclass
class StaticNoiseResult:
    """Result of :func:`analyse_record` / :func:`analyse_static`."""

    allan: AllanResult
    fit: NoiseFit
    sinusoid: SinusoidDetection
    tau0_s: float
    duration_s: float
    window: StaticWindow | None = None
    windows_found: int = 0

    def to_dict(self) -> dict:
        """Plain, JSON-ready dict."""
        out = {"tau0_s": float(self.tau0_s), "duration_s": float(self.duration_s),
               "allan": self.allan.to_dict(), "fit": self.fit.to_dict(),
               "sinusoid": self.sinusoid.to_dict()}
        if self.window is not None:
            out["window"] = self.window.to_dict()
            out["windows_found"] = int(self.windows_found)
        return out


def analyse_record(data, tau0_s: float, input_type: str, *, scale: float = 1.0,
                   unit: str = "", taus="octave", modified: bool = False,
                   kind: str | None = None, confidence: float = 0.683,
                   tau_max_s: float | None = None, sinusoid_threshold: float = 3.0,
                   bootstrap: int = 20, seed: int = 0,
                   overwrite_data: bool = False) -> StaticNoiseResult:
    """Deviation (:func:`allan_deviation`, ``kind`` adev/mdev/hdev/totdev), the
    five-term fit with that variance's own model (:func:`fit_noise_model`, optional
    parametric ``bootstrap`` of the uncertainties) and the sinusoid check
    (:func:`detect_sinusoid`) of a uniformly sampled record (IEEE 952-1997 Annex C).

    >>> rng = np.random.default_rng(2)
    >>> r = analyse_record(0.3 * rng.standard_normal(50000), 1.0, "rate", unit="deg/h")
    >>> bool(abs(r.fit.N - 0.3) < 0.03), r.sinusoid.detected
    (True, False)

    ``overwrite_data``: the record (float64, writeable, the caller's own) may be detrended
    in its own memory (:func:`allan_deviation`); the numbers are the same.
    """
    allan = allan_deviation(data, tau0_s, input_type, taus, scale=scale, modified=modified,
                            kind=kind, confidence=confidence, unit=unit,
                            overwrite_data=overwrite_data)
    fit = fit_noise_model(allan, tau_max_s=tau_max_s, bootstrap=bootstrap, seed=seed)
    sine = detect_sinusoid(allan, fit, threshold=sinusoid_threshold)
    n = allan.n_samples
    return StaticNoiseResult(allan=allan, fit=fit, sinusoid=sine, tau0_s=float(tau0_s),
                             duration_s=float(tau0_s) * (n - 1 if input_type == "angle" else n))


#: Samples checked at a time by :func:`_uniform_tau0` (bounded temporaries).
_CHECK_PIECE = 1 << 18


def _uniform_tau0(t: np.ndarray, key: str = "time_s", file=None) -> float:
    tau0 = float((t[-1] - t[0]) / (t.size - 1))
    for a in range(0, t.size - 1, _CHECK_PIECE):
        dt = np.diff(t[a: a + _CHECK_PIECE + 1])
        if not np.all(np.isfinite(dt)) or np.any(dt <= 0):
            bad = a + int(np.flatnonzero(~(dt > 0))[0]) + 1
            raise GonioError(f"time must be strictly increasing (sample {bad})", key=key,
                             file=file)
    for a in range(0, t.size - 1, _CHECK_PIECE):
        dt = np.diff(t[a: a + _CHECK_PIECE + 1])
        off = np.flatnonzero(np.abs(dt - tau0) > 0.01 * tau0)
        if off.size:
            raise GonioError("sampling is not uniform: a step differs from the mean "
                             f"{tau0:g} s by more than 1 % (sample {a + int(off[0]) + 1})",
                             key=key, file=file)
    return tau0


def analyse_static(time_s, angle_deg, *, taus="octave", modified: bool = False,
                   kind: str | None = None, confidence: float = 0.683,
                   tau_max_s: float | None = None, sinusoid_threshold: float = 3.0,
                   bootstrap: int = 20, seed: int = 0) -> StaticNoiseResult:
    """Noise analysis of a static (zero-stability) record, draft 7.3.

    The angle record (degrees, uniformly sampled, instrument at rest) is analysed as
    an ``angle`` input: deviation in °/h (IEEE 952 Annex C), the five-term fit and
    the sinusoid check (:func:`analyse_record`). The sample interval is the mean time
    step; a record whose steps differ from it by more than 1 % is rejected (the
    estimators assume uniform sampling).

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> t = np.arange(20000) * 0.1
    >>> rate_dph = 0.05 * rng.standard_normal(t.size) / np.sqrt(0.1)  # N = 0.05 (°/h)√s
    >>> angle = np.cumsum(rate_dph) * 0.1 / S_PER_H
    >>> r = analyse_static(t, angle)
    >>> r.allan.unit, bool(abs(r.fit.N - 0.05) < 0.005)
    ('deg/h', True)
    """
    t = np.asarray(time_s, dtype=np.float64)
    a = np.asarray(angle_deg, dtype=np.float64)
    if t.ndim != 1 or a.shape != t.shape:
        raise GonioError(f"time_s and angle_deg must be 1-D of equal length, got "
                         f"{t.shape} and {a.shape}", key="angle_deg")
    if t.size < 8:
        raise GonioError(f"need at least 8 samples, got {t.size}", key="time_s")
    tau0 = _uniform_tau0(t)
    # 1° = 3600 (°/h)·s, so with scale 1/3600 the deviation comes out in °/h
    return analyse_record(a, tau0, "angle", scale=1.0 / S_PER_H, unit="deg/h", taus=taus,
                          modified=modified, kind=kind, confidence=confidence,
                          tau_max_s=tau_max_s, sinusoid_threshold=sinusoid_threshold,
                          bootstrap=bootstrap, seed=seed)


# ------------------------------------------------------------------ static windows
def _parse_window(window) -> tuple[float, float]:
    if isinstance(window, str):
        parts = window.split(":")
        try:
            if len(parts) != 2:
                raise ValueError
            lo, hi = float(parts[0]), float(parts[1])
        except ValueError:
            raise GonioError(f"window must be START:END in seconds, not {window!r}",
                             key="window") from None
    else:
        lo, hi = (float(v) for v in window)
    if not (math.isfinite(lo) and math.isfinite(hi) and hi > lo):
        raise GonioError(f"window end must be after its start, got {lo}:{hi}", key="window")
    return lo, hi


def static_windows(time_s, table_deg=None, counts=None, *,
                   scale_factor_counts_per_deg: float | None = None,
                   min_duration_s: float = 1.0, window=None) -> list[StaticWindow]:
    """The intervals of a stream in which the table rests.

    With ``window`` (``"START:END"`` in s, or a pair) that interval only, checked:
    it must lie within the record and, when ``table_deg`` is present, the table must
    not move in it (rate above :data:`MOTION_THRESHOLD_DPS` between any two samples),
    else a one-line GonioError. Without it, the rests found by the reducer's rest
    finder (:func:`gonio.reduce.find_rests`: on ``table_deg``, or on the gyro rate
    when there is no encoder column) longer than ``min_duration_s``.
    """
    from gonio.reduce import find_rests

    t = np.asarray(time_s, dtype=np.float64)
    if window is not None:
        lo, hi = _parse_window(window)
        if lo < t[0] - 1e-9 or hi > t[-1] + 1e-9:
            raise GonioError(f"window {lo:g}:{hi:g} s is outside the record "
                             f"({t[0]:g} to {t[-1]:g} s)", key="window")
        i0 = int(np.searchsorted(t, lo, side="left"))
        i1 = int(np.searchsorted(t, hi, side="right")) - 1
        if i1 - i0 < 8:
            raise GonioError(f"window {lo:g}:{hi:g} s holds fewer than 8 samples",
                             key="window")
        if table_deg is not None:
            a = np.asarray(table_deg, dtype=np.float64)[i0: i1 + 1]
            rate = np.abs(np.diff(a)) / np.diff(t[i0: i1 + 1])
            moving = np.flatnonzero(rate > MOTION_THRESHOLD_DPS)
            if moving.size:
                raise GonioError(f"the table moves inside window {lo:g}:{hi:g} s "
                                 f"(at t = {t[i0 + moving[0]]:g} s); choose a rest",
                                 key="window")
        return [StaticWindow(i0, i1, float(t[i0]), float(t[i1]), "option")]
    rests = find_rests(t, table_deg, counts, scale_factor_counts_per_deg=scale_factor_counts_per_deg,
                       min_rest_s=min_duration_s)
    out = []
    for r in rests:
        # stay clear of the refined edges: only samples fully inside the rest
        i0, i1 = int(r.i_start), int(r.i_end)
        if math.isfinite(r.t_arrive_s):
            i0 = max(i0, int(np.searchsorted(t, r.t_arrive_s, side="left")))
        if math.isfinite(r.t_depart_s):
            i1 = min(i1, int(np.searchsorted(t, r.t_depart_s, side="right")) - 1)
        if i1 - i0 >= 8 and t[i1] - t[i0] >= min_duration_s:
            out.append(StaticWindow(i0, i1, float(t[i0]), float(t[i1]), "rest"))
    return out


def select_window(windows: list[StaticWindow], n_samples: int) -> StaticWindow | None:
    """The window to analyse: None when the only window is the whole record (no
    motion), the longest otherwise; a GonioError when there is none."""
    if not windows:
        raise GonioError("no static window: the table is never at rest long enough for "
                         "a noise analysis (give --window START:END)", key="window")
    best = max(windows, key=lambda w: (w.duration_s, -w.i_start))
    return best


#: Windows longer than this are read into a memory-mapped temporary file, not RAM.
MEMMAP_SAMPLES = 1 << 24

#: Samples read from a stream file at a time when a window is copied or checked.
_READ_PIECE = 1 << 20


def _window_by_option(src, window) -> StaticWindow:
    """The operator's ``START:END`` on a sample source, checked as :func:`static_windows`."""
    lo, hi = _parse_window(window)
    t_first, t_last = src.t_first, src.t_last
    if lo < t_first - 1e-9 or hi > t_last + 1e-9:
        raise GonioError(f"window {lo:g}:{hi:g} s is outside the record "
                         f"({t_first:g} to {t_last:g} s)", key="window")
    i0 = src.search(lo, side="left")
    i1 = src.search(hi, side="right") - 1
    if i1 - i0 < 8:
        raise GonioError(f"window {lo:g}:{hi:g} s holds fewer than 8 samples", key="window")
    if "table_deg" in src.columns:
        for a in range(i0, i1, _READ_PIECE):       # pieces overlap by one sample
            ch = src.window(a, min(i1 + 1, a + _READ_PIECE + 1),
                            columns=("time_s", "table_deg"))
            rate = np.abs(np.diff(ch.table_deg)) / np.diff(ch.time_s)
            moving = np.flatnonzero(rate > MOTION_THRESHOLD_DPS)
            if moving.size:
                raise GonioError(f"the table moves inside window {lo:g}:{hi:g} s "
                                 f"(at t = {ch.time_s[moving[0]]:g} s); choose a rest",
                                 key="window")
    return StaticWindow(i0, i1, src.time_at(i0), src.time_at(i1), "option")


def source_windows(src, *, scale_factor_counts_per_deg: float | None = None,
                   min_duration_s: float = 1.0, window=None) -> list[StaticWindow]:
    """:func:`static_windows` of a sample source (:class:`gonio.formats.streams.StreamFile`)
    in bounded memory: the same rests (the reducer's :func:`gonio.reduce.rests.rests_of`
    on the same samples, read once in blocks) and the same edge clipping, so the same
    windows as :func:`static_windows` on the whole arrays."""
    from gonio.reduce.rests import rests_of

    if window is not None:
        return [_window_by_option(src, window)]
    on_table = "table_deg" in src.columns
    if not on_table and scale_factor_counts_per_deg is None:
        raise GonioError("without table_deg the rests are found from the gyro rate: give "
                         "nominal_scale_factor_counts_per_deg",
                         key="nominal_scale_factor_counts_per_deg")
    rests, _ = rests_of(src, on_table=on_table,
                        scale_factor_counts_per_deg=None if on_table
                        else scale_factor_counts_per_deg, min_rest_s=min_duration_s)
    out = []
    for r in rests:
        i0, i1 = int(r.i_start), int(r.i_end)
        if math.isfinite(r.t_arrive_s):
            i0 = max(i0, src.search(r.t_arrive_s, side="left"))
        if math.isfinite(r.t_depart_s):
            i1 = min(i1, src.search(r.t_depart_s, side="right") - 1)
        if i1 - i0 >= 8:
            t0, t1 = src.time_at(i0), src.time_at(i1)
            if t1 - t0 >= min_duration_s:
                out.append(StaticWindow(i0, i1, t0, t1, "rest"))
    return out


def window_record(src, w: StaticWindow, *, scale: float = 1.0, tmpdir=None,
                  progress=None) -> tuple[np.ndarray, float]:
    """(counts × ``scale`` as float64, τ0) of window ``w`` of a sample source, read in
    pieces; the sampling checked uniform (each step within 1 % of the mean, as
    :func:`analyse_static`). More than :data:`MEMMAP_SAMPLES` samples go into a
    memory-mapped ``.npy`` in ``tmpdir`` (which the caller removes). ``progress``:
    a :class:`gonio.progress.Progress` advanced by the samples read."""
    n = w.i_end - w.i_start + 1
    tau0 = float((w.t_end_s - w.t_start_s) / (n - 1))
    if n > MEMMAP_SAMPLES and tmpdir is not None:
        from pathlib import Path
        out = np.lib.format.open_memmap(Path(tmpdir) / "window.npy", mode="w+",
                                        dtype=np.float64, shape=(n,))
    else:
        out = np.empty(n, dtype=np.float64)
    for a in range(0, n, _READ_PIECE):
        b = min(n, a + _READ_PIECE)
        # one sample before the piece (when there is one) for the step across the seam
        lo = w.i_start + a - (1 if a else 0)
        ch = src.window(lo, w.i_start + b, columns=("time_s", "gyro_counts"))
        dt = np.diff(ch.time_s)
        off = np.flatnonzero(np.abs(dt - tau0) > 0.01 * tau0)
        if off.size:
            raise GonioError("sampling is not uniform: time step differs from the mean "
                             f"{tau0:g} s by more than 1 % (sample {lo + int(off[0]) + 2})",
                             column="time_s")
        counts = ch.gyro_counts[1:] if a else ch.gyro_counts
        if scale != 1.0:     # as float64(counts) * scale, element by element
            np.multiply(counts.astype(np.float64, copy=False), scale, out=out[a:b])
        else:
            out[a:b] = counts
        if progress is not None:
            progress.update(b - a)
    return out, tau0
