"""Allan-family deviations of gyro records: overlapping Allan, modified Allan,
overlapping Hadamard and total deviation, gap-aware, with χ² intervals.

Contents
--------
=============================  ==============================================
:class:`AllanResult`           one deviation versus τ, with edf and intervals
:func:`angle_series`           rate / increment / angle input -> angle series
:func:`averaging_factors`      the τ sets "octave", "decade:N", "all"
:func:`allan_deviation`        any of the four estimators (``kind=``)
:func:`modified_allan_deviation`, :func:`hadamard_deviation`, :func:`total_deviation`
=============================  ==============================================

The input type is always an explicit argument (never guessed):

* ``"rate"``      -- rate samples (e.g. °/h), each the mean rate over one interval τ0;
* ``"increment"`` -- angle increments per sample (e.g. counts per sample), divided by
  ``scale`` (e.g. counts/°) to give an angle;
* ``"angle"``     -- the integrated angle (e.g. cumulative counts or degrees), divided by
  ``scale``.

Everything is computed from the angle (phase) series ``x`` (IEEE 952-1997 Annex C;
IEEE 1554-2005 Annex; NIST SP 1065 §5.2). With m samples per cluster, τ = mτ0:

* overlapping Allan (``adev``, SP 1065 eq. 11):
  σ² = Σ (x[n+2m] − 2x[n+m] + x[n])² / (2τ²(N−2m));
* modified Allan (``mdev``, eq. 14): the second differences averaged over m
  consecutive starts, Mod σ² = Σ_j (Σ_{i=j}^{j+m−1} Δ²x_i)² / (2m²τ²(N−3m+1));
* overlapping Hadamard (``hdev``, eq. 20):
  Hσ² = Σ (x[n+3m] − 3x[n+2m] + 3x[n+m] − x[n])² / (6τ²(N−3m)) — insensitive to a
  rate ramp;
* total (``totdev``, eq. 25): the Allan sum over the record extended at both ends by
  odd reflection, divided by 2τ²(N−2) — better confidence at long τ.

For a rate input the deviation is in the input's rate unit; for increment and angle
inputs in (angle unit)/s.

Gaps (NaN samples, e.g. dropouts) are never interpolated: a difference term is used
only when every sample it spans is valid (rate/increment: all samples between its
end points; angle: its end points, and for ``mdev`` every point it averages), and
each τ is normalised by its own number of valid terms (SP 1065 §5.15, gap-aware
sums); ``n_pairs`` reports that number. Total deviation needs a gap-free record.

Cost: per τ O(N) (chunked, vectorised; for an in-memory, gap-free record the ``adev`` and
``hdev`` terms at m ≥ 16 are BLAS matrix products of the phase's rows, one pass each, with a
stated rounding bound: :func:`_sums_by_products`); ``taus="all"`` for ``adev`` and ``hdev``
uses the correlation expansion of :func:`_expanded_sums` — O(N log² N) for every τ at
once — and for ``mdev`` the same expansion on short overlapping segments, octave by
octave (:func:`_mdev_local_sums`, O(N log³ N), exact to 1e-9; see
docs/noise-all-tau.md).

References
----------
.. [IEEE952] IEEE Std 952-1997, Annex C (Allan variance, noise terms).
.. [SP1065] W. J. Riley, NIST SP 1065 (2008), §5.2 (eqs. 11, 14, 20, 25), §5.15 (gaps).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import fft as sfft

from gonio.analysis.noise.edf import (
    chi2_interval, edf_for, noise_id_b1, noise_id_lag1, release_quadratic_basis,
    remove_quadratic, rn_ratio_of_phase,
)
from gonio.analysis.noise.stream import CumulativeSum, Record
from gonio.errors import GonioError

__all__ = [
    "INPUT_TYPES", "KIND_METHODS", "AllanResult", "angle_series", "averaging_factors",
    "allan_deviation", "modified_allan_deviation", "hadamard_deviation",
    "total_deviation",
]

#: The accepted input types (see module docstring).
INPUT_TYPES = ("rate", "increment", "angle")
#: Estimator kind -> method label.
KIND_METHODS = {"adev": "overlapping", "mdev": "modified", "hdev": "hadamard",
                "totdev": "total"}

#: Difference coefficients of each estimator's term, on x (adev, hdev) or on the
#: cumulative sum of x (mdev: Σ_{i<m} Δ²x_{j+i} is the third difference of cumsum x).
_COEF = {"adev": (1.0, -2.0, 1.0), "hdev": (-1.0, 3.0, -3.0, 1.0),
         "mdev": (-1.0, 3.0, -3.0, 1.0)}
#: Normalisation of the variance: sum / (_NORM · m_extra · τ² · terms).
_NORM = {"adev": 2.0, "mdev": 2.0, "hdev": 6.0, "totdev": 2.0}

_BLOCK = 1 << 16  # samples per chunk of the direct O(N) sums (keeps temporaries small)
_BLOCK_SHARED = 1 << 16  # chunk of the chunk-outside loop (:func:`_sums_direct_shared`)
#: Most decimated points the noise identification looks at (a central sub-record).
ID_MAX_POINTS = 1 << 16
#: Fewest decimated points from which the identified noise type is taken as it is. Below
#: them the lag-1 method (valid from 30 points, [RG2004]) errs often: on white rate noise
#: (2¹⁷ samples, 100 records) it called 0 % of the records wrong at 256 points, 2 % at 128,
#: 9 % at 64 and 26 % at 32, mostly as flicker or white phase, whose edf is 2× to 10⁴× that of
#: white rate noise (intervals far too narrow). With fewer points the type is the one last
#: identified from enough points, or the type identified there if that is lower (its edf is
#: smaller: the wider interval; random-walk rate noise appearing at long τ is kept).
ID_RELIABLE_POINTS = 256
#: τ whose decimated sub-records a streamed phase gives in one pass (memory: this many
#: times ID_MAX_POINTS points).
_ID_GROUP = 4


# --------------------------------------------------------------------- dataclass
@dataclass
class AllanResult:
    """A deviation versus averaging time, with χ² confidence intervals.

    ``adev`` is the deviation (whatever ``method``: overlapping, modified, hadamard
    or total) in ``unit``; ``tau_s`` in seconds; ``n_pairs`` the number of valid terms
    at each τ (fewer than the gap-free count when the record has gaps); ``edf`` the
    equivalent degrees of freedom (Greenhall's algorithm, :mod:`.edf`) for the
    interval ``[ci_low, ci_high]`` at level ``confidence``; ``alpha`` the noise type
    used for the edf (lag-1 autocorrelation, or given); ``alpha_b1`` the B1/R(n)
    identification (NaN where it cannot be made) as a cross-check.

    For ``taus="all"`` the per-τ arrays other than ``tau_s`` and ``adev`` are stored
    compactly (m and n_pairs int32, edf and the interval float32 — seven
    significant digits, far finer than an interval's own uncertainty) so that the
    result stays within the memory target of the issue (4× the input).
    """

    tau_s: np.ndarray
    adev: np.ndarray
    m: np.ndarray
    n_pairs: np.ndarray
    edf: np.ndarray
    alpha: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray
    input_type: str
    method: str
    tau0_s: float
    n_samples: int
    confidence: float
    unit: str = ""
    alpha_b1: np.ndarray | None = None
    n_phase: int = 0
    n_gaps: int = 0

    @property
    def kind(self) -> str:
        """``adev``, ``mdev``, ``hdev`` or ``totdev``."""
        return {v: k for k, v in KIND_METHODS.items()}[self.method]

    def to_frame(self) -> pd.DataFrame:
        """One row per τ: tau_s, m, adev, n_pairs, edf, alpha, alpha_b1, ci_low, ci_high."""
        b1 = self.alpha_b1 if self.alpha_b1 is not None else np.full(self.m.size, np.nan)
        return pd.DataFrame({"tau_s": self.tau_s, "m": self.m, "adev": self.adev,
                             "n_pairs": self.n_pairs, "edf": self.edf, "alpha": self.alpha,
                             "alpha_b1": b1, "ci_low": self.ci_low, "ci_high": self.ci_high})

    def to_dict(self) -> dict:
        """Plain, JSON-ready dict (lists of floats; NaN as None)."""
        b1 = self.alpha_b1 if self.alpha_b1 is not None else np.full(self.m.size, np.nan)
        return {"input_type": self.input_type, "method": self.method,
                "tau0_s": float(self.tau0_s), "n_samples": int(self.n_samples),
                "n_gaps": int(self.n_gaps),
                "confidence": float(self.confidence), "unit": self.unit,
                "tau_s": [float(v) for v in self.tau_s],
                "adev": [float(v) for v in self.adev],
                "m": [int(v) for v in self.m],
                "n_pairs": [int(v) for v in self.n_pairs],
                "edf": [float(v) for v in self.edf],
                "alpha": [int(v) for v in self.alpha],
                "alpha_b1": [None if not np.isfinite(v) else int(v) for v in b1],
                "ci_low": [float(v) for v in self.ci_low],
                "ci_high": [float(v) for v in self.ci_high]}


# ------------------------------------------------------------------- angle series
def _check_args(input_type, tau0_s, scale):
    if input_type not in INPUT_TYPES:
        raise GonioError(f"input type must be one of {', '.join(INPUT_TYPES)}, "
                         f"not {input_type!r}", key="input_type")
    tau0_s = float(tau0_s)
    if not (math.isfinite(tau0_s) and tau0_s > 0):
        raise GonioError(f"sample interval tau0_s must be > 0, not {tau0_s}", key="tau0_s")
    scale = float(scale)
    if not (math.isfinite(scale) and scale != 0):
        raise GonioError(f"scale must be finite and non-zero, not {scale}", key="scale")
    return tau0_s, scale


def _as_array(data) -> np.ndarray:
    arr = np.asarray(data)
    if arr.ndim != 1:
        raise GonioError(f"data must be one-dimensional, got shape {arr.shape}", key="data")
    if arr.size < 3:
        raise GonioError(f"need at least 3 samples, got {arr.size}", key="data")
    try:
        return arr.astype(np.float64, copy=False)
    except (TypeError, ValueError) as exc:
        raise GonioError(f"data must be numeric ({exc})", key="data") from None


def angle_series(data, input_type: str, tau0_s: float, scale: float = 1.0) -> np.ndarray:
    """The angle (phase) series ``x`` from which every Allan statistic is computed.

    ``rate``: ``x = [0, cumsum(y − ȳ)]·τ0`` (N+1 points, unit rate·s);
    ``increment``: ``x = [0, cumsum(d/scale − mean)]`` (N+1 points);
    ``angle``: ``x = a/scale`` minus the straight line through its end points
    (N points). Removing the mean rate (equivalently a linear ramp of ``x``) is exact
    for all four estimators, whose differences cancel a ramp (IEEE 952 C.1; SP 1065
    eq. 11; the reflection of ``totdev`` continues a ramp), and keeps the cumulative
    sums small so that long records lose no precision. Gap-free data only (the
    estimators handle NaN gaps themselves).

    >>> angle_series([1.0, 3.0, 2.0], "rate", 0.5)
    array([ 0. , -0.5,  0. ,  0. ])
    >>> angle_series([0, 10, 30, 30], "angle", 1.0, scale=10.0)
    array([0., 0., 1., 0.])
    """
    tau0_s, scale = _check_args(input_type, tau0_s, scale)
    arr = _as_array(data)
    if not np.isfinite(arr).all():
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise GonioError(f"data contains a non-finite value at index {bad}", key="data")
    x, _ = _phase(arr, input_type, tau0_s, scale)
    return x


#: Points detrended at a time (the line is formed piece by piece, not as a whole array).
_RAMP_PIECE = 1 << 16


def _phase(arr: np.ndarray, input_type: str, tau0_s: float, scale: float,
           overwrite: bool = False):
    """(x, bad) with x the detrended phase and ``bad`` None (no gaps) or the gap
    description: for rate/increment the prefix count of NaN samples (length N+1,
    x zero-filled across gaps), for angle the boolean mask of NaN points.
    ``overwrite``: an angle record (float64) is detrended in its own memory."""
    # a finite sum means every sample is finite (a NaN or ±inf makes it NaN or inf): the
    # element-wise mask only when it is not
    total = float(np.add.reduce(arr, dtype=np.float64))
    gaps = not math.isfinite(total)
    finite = np.isfinite(arr) if gaps else None
    gaps = gaps and not finite.all()
    if gaps and np.isinf(arr).any():
        bad = int(np.flatnonzero(np.isinf(arr))[0])
        raise GonioError(f"data contains an infinite value at index {bad}", key="data")
    if input_type == "angle":
        if overwrite and arr.dtype == np.float64 and arr.flags.writeable:
            a = arr
            if scale != 1.0:
                a /= scale
        else:
            a = arr / scale if scale != 1.0 else arr.copy()
        idx = np.flatnonzero(finite) if gaps else None
        i0, i1 = (0, a.size - 1) if not gaps else (int(idx[0]), int(idx[-1]))
        if i1 <= i0:
            raise GonioError("fewer than two valid angle samples", key="data")
        a0, a1 = a[i0], a[i1]
        slope = (a1 - a0) / (i1 - i0)
        for s in range(0, a.size, _RAMP_PIECE):       # a −= a0 + (k − i0)·slope
            ramp = np.arange(s, min(a.size, s + _RAMP_PIECE), dtype=np.float64)
            ramp -= i0
            ramp *= slope
            ramp += a0
            a[s: s + ramp.size] -= ramp
        return a, (~finite if gaps else None)
    y = arr / scale if (input_type == "increment" and scale != 1.0) else arr
    if gaps:
        if finite.sum() < 2:
            raise GonioError("fewer than two valid samples", key="data")
        mean = float(np.mean(y[finite]))
    elif y is arr:
        mean = total / arr.size     # np.mean's own sum and division, already done above
    else:
        mean = float(np.mean(y, dtype=np.float64))
    x = np.empty(y.size + 1, dtype=np.float64)
    x[0] = 0.0
    np.subtract(y, mean, out=x[1:])
    bad = None
    if gaps:
        x[1:][~finite] = 0.0
        bad = np.zeros(y.size + 1, dtype=np.int64)
        np.cumsum(~finite, out=bad[1:])
    np.cumsum(x[1:], out=x[1:])
    if input_type == "rate":
        x *= tau0_s
    return x, bad


def averaging_factors(n_phase: int, taus="octave", *, modified: bool = False,
                      kind: str | None = None) -> np.ndarray:
    """Cluster sizes m (τ = m·τ0) for a phase series of ``n_phase`` points.

    ``"octave"``: m = 1, 2, 4, …; ``"decade:N"``: N log-spaced per decade, rounded
    to unique integers; ``"all"``: every m. The largest m leaves at least one
    term: m ≤ (n−1)/2 (``adev``, ``totdev``; SP 1065 eq. 11), (n−1)/3 (``mdev``,
    eq. 14) or (n−1)/3 (``hdev``, eq. 20). An explicit sequence of integers is
    accepted as given (validated).

    >>> averaging_factors(100, "octave")
    array([ 1,  2,  4,  8, 16, 32])
    >>> averaging_factors(100, "decade:3")
    array([ 1,  2,  5, 10, 22, 46])
    >>> averaging_factors(10, "all", modified=True)
    array([1, 2, 3])
    """
    kind = kind or ("mdev" if modified else "adev")
    m_max = (n_phase - 1) // (3 if kind in ("mdev", "hdev") else 2)
    if m_max < 1:
        raise GonioError(f"record too short: {n_phase} angle samples", key="data")
    if isinstance(taus, str):
        spec = taus.strip().lower()
        if spec == "octave":
            ms = 2 ** np.arange(int(math.floor(math.log2(m_max))) + 1)
        elif spec == "all":
            ms = np.arange(1, m_max + 1)
        elif spec.startswith("decade:"):
            try:
                per = int(spec.split(":", 1)[1])
            except ValueError:
                per = 0
            if per < 1:
                raise GonioError(f"τ set {taus!r}: 'decade:N' needs an integer N >= 1",
                                 key="taus")
            k = np.arange(int(math.floor(per * math.log10(m_max) + 1e-9)) + 1)
            ms = np.unique(np.round(10.0 ** (k / per)).astype(np.int64))
        else:
            raise GonioError(f"τ set must be 'octave', 'decade:N' or 'all', not {taus!r}",
                             key="taus")
        return ms[(ms >= 1) & (ms <= m_max)].astype(np.int64)
    ms = np.asarray(taus)
    if ms.ndim != 1 or ms.size == 0 or not np.all(ms == np.round(ms)):
        raise GonioError("explicit averaging factors must be a 1-D sequence of integers",
                         key="taus")
    ms = np.unique(ms.astype(np.int64))
    if ms[0] < 1 or ms[-1] > m_max:
        raise GonioError(f"averaging factors must lie in 1..{m_max}", key="taus")
    return ms


# ------------------------------------------------------------- direct sums (O(N))
#: Points per BLAS dot product in :func:`_ssq`: OpenBLAS's ddot stays on one thread up to
#: 10 000 points (beyond, its threads stall on a busy machine: 16× slower at load 11).
_DOT_PIECE = 8192


def _ssq(v: np.ndarray) -> float:
    """Σ v², as BLAS dot products of pieces of :data:`_DOT_PIECE` points (single-threaded,
    so the sum does not depend on the thread count; 2–3× faster than ``einsum``)."""
    n = v.size
    if n <= _DOT_PIECE:
        return float(v.dot(v))
    total = 0.0
    full = n - n % _DOT_PIECE if n >= 4 * _DOT_PIECE else 0
    if full:
        # the whole pieces' dot products in one call: matmul of stacked 1×P by P×1 runs
        # the same ddot on each piece, so the sum is the same to the bit
        q = full // _DOT_PIECE
        rows = v[:full].reshape(q, 1, _DOT_PIECE)
        for d in np.matmul(rows, rows.reshape(q, _DOT_PIECE, 1)).ravel().tolist():
            total += d
    for a in range(full, n, _DOT_PIECE):
        w = v[a: a + _DOT_PIECE]
        total += w.dot(w)       # the ndarray method: the same ddot, less call overhead
    return float(total)


def _piece_dots(v: np.ndarray, row: np.ndarray) -> None:
    """The :data:`_DOT_PIECE`-point dot products of v with itself into ``row`` (the ddot
    of each piece, as :func:`_ssq` forms them), the whole pieces in one call."""
    q = v.size // _DOT_PIECE
    full = q * _DOT_PIECE
    if q:
        r = v[:full].reshape(q, 1, _DOT_PIECE)
        np.matmul(r, r.reshape(q, _DOT_PIECE, 1), out=row[:q].reshape(q, 1, 1))
    if full < v.size:
        w = v[full:]
        row[q] = w.dot(w)


#: Points per pass of the in-memory sums (a multiple of :data:`_DOT_PIECE`): the work of
#: a pass; the sums' order is that of chunks of :data:`_BLOCK_SHARED` whatever it is.
_PASS = 1 << 17


def _pass_layout(x, bsz: int, n_m: int, longest: int):
    """(points per pass, pieces per chunk, zeroed piece products m × piece) of the shared
    sums: passes of :data:`_PASS` points for an in-memory phase longer than a pass whose
    chunks are whole pieces, else of one chunk (a streamed phase rebuilds its pieces chunk
    by chunk; a shorter record keeps the chunk's work buffers)."""
    per = -(-bsz // _DOT_PIECE)
    step = _PASS if (type(x) is np.ndarray and bsz % _DOT_PIECE == 0
                     and bsz == _BLOCK_SHARED and longest > _PASS) else bsz
    return step, per, np.zeros((n_m, max(0, -(-longest // bsz)) * per))


def _chunk_totals(dots: np.ndarray) -> np.ndarray:
    """Σ over chunks of Σ over each chunk's pieces of ``dots`` (m × chunk × piece, unused
    places 0), both in order: :func:`_ssq` of each chunk summed chunk by chunk, to the bit."""
    if dots.shape[1] == 0:
        return np.zeros(dots.shape[0])
    return np.cumsum(np.cumsum(dots, axis=2)[:, :, -1], axis=1)[:, -1].copy()


def _sum_sq_diff(z: np.ndarray, m: int, coef, buf: np.ndarray) -> float:
    """Σ_n (Σ_p coef[p]·z[n + p·m])², n = 0 … len(z) − (P−1)m − 1, in chunks."""
    n = z.size
    p_last = len(coef) - 1
    length = n - p_last * m
    total = 0.0
    for s in range(0, length, _BLOCK):
        e = min(length, s + _BLOCK)
        v = buf[: e - s]
        np.multiply(z[s:e], coef[0], out=v)
        for p in range(1, p_last + 1):
            if coef[p] == 1.0:
                np.add(v, z[s + p * m: e + p * m], out=v)
            elif coef[p] == -1.0:
                np.subtract(v, z[s + p * m: e + p * m], out=v)
            else:
                v += coef[p] * z[s + p * m: e + p * m]
        total += _ssq(v)
    return total


def _sums_direct_shared(x: np.ndarray, ms, order: int = 2) -> np.ndarray:
    """Σ (x[n+2m] − 2x[n+m] + x[n])² for each m (SP 1065 eq. 11), chunks outside, m
    inside: for a set like the octaves the data a chunk needs for one m is largely
    what the next m needs, so each chunk of ``x`` comes from main memory about once
    for all m (the sums are bound by memory bandwidth). ``order`` 3: the third
    differences x[n+3m] − 3x[n+2m] + 3x[n+m] − x[n] of the Hadamard variance (eq. 20;
    an in-memory phase only)."""
    ms = [int(m) for m in ms]
    n = x.size
    bsz = min(_BLOCK_SHARED, n)
    if order == 3:
        return _sums_shared_third(x, ms, bsz)
    if isinstance(x, CumulativeSum) and len(ms) > 1 and max(ms) > bsz:
        # a streamed phase: each m beyond a chunk on its own (its three far pieces then
        # move along the blocks together and stay cached; all m at once would evict them);
        # every m's chunks are summed in the same order, so the sums are the same
        return _split_sums(x, ms, bsz)
    lengths = [n - 2 * m for m in ms]
    order = sorted(range(len(ms)), key=lambda i: ms[i])
    sub, add = np.subtract, np.add
    reach = 2 * max((m for m in ms if m <= bsz), default=0)
    step, per, dots = _pass_layout(x, bsz, len(ms), max(lengths))
    buf = np.empty(2 * step + bsz)
    for s in range(0, max(lengths), step):
        # one slice of x for every m within a chunk (a streamed phase: one copy per chunk)
        near = x[s: min(n, s + step + reach)] if reach else None
        at = (s // bsz) * per + (s % bsz) // _DOT_PIECE     # the chunk's first piece
        for i in order:
            m, length = ms[i], lengths[i]
            if s >= length:
                break
            e = min(length, s + step)
            k = e - s
            if m <= bsz:
                d1 = buf[: k + m]
                xs = near[: k + 2 * m]          # x[s: e + 2m]
                sub(xs[m:], xs[: k + m], out=d1)
                v = buf[k + m: 2 * k + m]
                sub(d1[m:], d1[:k], out=v)
            else:
                v = buf[:k]
                mid = x[s + m: e + m]
                sub(x[s + 2 * m: e + 2 * m], mid, out=v)
                sub(v, mid, out=v)
                add(v, x[s:e], out=v)
            _piece_dots(v, dots[i, at:])
    return _chunk_totals(dots.reshape(len(ms), -1, per))


def _sums_shared_third(x: np.ndarray, ms: list[int], bsz: int) -> np.ndarray:
    """:func:`_sums_direct_shared` of the third differences (the Hadamard variance): for
    m up to an eighth of a chunk by three successive differences at lag m of one slice of
    ``x`` (3k + 3m points written for k terms), beyond from the four far pieces (4k: the
    cheaper once m exceeds k/3; measured fastest from k/8), with two work buffers and no
    temporaries."""
    n = x.size
    lengths = [n - 3 * m for m in ms]
    order = sorted(range(len(ms)), key=lambda i: ms[i])
    sub, add = np.subtract, np.add
    near_max = bsz // 8
    reach = 3 * max((m for m in ms if m <= near_max), default=0)
    step, per, dots = _pass_layout(x, bsz, len(ms), max(lengths))
    buf = np.empty(3 * step + reach)
    tmp = np.empty(step)
    for s in range(0, max(lengths), step):
        near = x[s: min(n, s + step + reach)] if reach else None
        at = (s // bsz) * per + (s % bsz) // _DOT_PIECE
        for i in order:
            m, length = ms[i], lengths[i]
            if s >= length:
                break
            e = min(length, s + step)
            k = e - s
            if m <= near_max:
                xs = near[: k + 3 * m]          # x[s: e + 3m]
                d1 = buf[: k + 2 * m]
                sub(xs[m:], xs[: k + 2 * m], out=d1)
                d2 = buf[k + 2 * m: 2 * k + 3 * m]
                sub(d1[m:], d1[: k + m], out=d2)
                v = buf[2 * k + 3 * m: 3 * k + 3 * m]
                sub(d2[m:], d2[:k], out=v)
            else:
                v, t = buf[:k], tmp[:k]
                sub(x[s + 3 * m: e + 3 * m], x[s:e], out=v)
                sub(x[s + m: e + m], x[s + 2 * m: e + 2 * m], out=t)
                t *= 3.0
                add(v, t, out=v)
            _piece_dots(v, dots[i, at:])
    return _chunk_totals(dots.reshape(len(ms), -1, per))


# ------------------------------------- in-memory sums by matrix products (BLAS)
#: Smallest m whose in-memory sums (gap-free phase array) are formed by matrix products
#: (:func:`_sums_by_products`); below, by differences (:func:`_sums_direct_shared`).
_PRODUCT_MIN_M = 16
#: Terms per matrix product (the output block: 512 KiB, it and its input stay in cache).
_PRODUCT_BLOCK = 1 << 16
#: Bound on the relative rounding error of a sum formed by matrix products (see
#: :func:`_sums_by_products`); an m whose bound is larger is summed by differences.
PRODUCT_RTOL = 1e-12
#: Fewest phase points for the products (below, their set-up costs more than they save).
_PRODUCT_MIN_N = 1 << 18
_UNIT_ROUNDOFF = 2.0 ** -53
#: Terms from which :func:`_sums_by_products` foresees its rounding bound.
_PROBE = 4096


def _band(coef, p: int) -> np.ndarray:
    """p × (p + P − 1) matrix whose row r holds ``coef`` (P values) from column r."""
    t = np.zeros((p, p + len(coef) - 1))
    for r in range(p):
        t[r, r: r + len(coef)] = coef
    return t


def _product_rows(x: np.ndarray, m: int, coef, q0: int, rows: int, p: int,
                  buf: np.ndarray) -> float:
    """Σ of the squared terms n ∈ [q0·m, (q0 + rows)·m) (``rows`` a multiple of ``p``), the
    row q of terms (n = q·m … q·m + m − 1) being Σ_j coef[j]·X[q + j] with X[q] = x[q·m:
    q·m + m]: ``p`` rows of terms are the band matrix :func:`_band` times p + P − 1 rows of
    X (a strided view of ``x``, no copy), many such products in one ``np.matmul`` call
    (m small) or the rows taken in column strips (m large)."""
    width = len(coef) - 1 + p
    t = _band(coef, p)
    isz = x.itemsize
    total = 0.0
    nb = rows // p
    # every product's rows of X at once: nb overlapping (width × m) windows, p rows apart
    y = np.ndarray((nb, width, m), dtype=x.dtype, buffer=x, offset=q0 * m * isz,
                   strides=(p * m * isz, m * isz, isz))
    y.flags.writeable = False
    if p * m <= _PRODUCT_BLOCK:
        g_max = _PRODUCT_BLOCK // (p * m)
        for b0 in range(0, nb, g_max):
            g = min(g_max, nb - b0)
            out = buf[: g * p * m]
            np.matmul(t, y[b0: b0 + g], out=out.reshape(g, p, m))
            total += _ssq(out)
        return total
    w = _PRODUCT_BLOCK // p
    for b in range(nb):
        for c0 in range(0, m, w):
            ww = min(w, m - c0)
            out = buf[: p * ww]
            np.matmul(t, y[b, :, c0: c0 + ww], out=out.reshape(p, ww))
            total += _ssq(out)
    return total


def _sum_sq_products(x: np.ndarray, m: int, coef, buf: np.ndarray) -> float:
    """Σ_n (Σ_j coef[j]·x[n + j·m])², n = 0 … N − (P−1)m − 1, by matrix products
    (:func:`_product_rows`: blocks of 8 rows of terms for m < 64, else 4), the rows
    left over by fewer-row products and the last partial row by differences
    (:func:`_sum_sq_diff`). The terms are summed in an order fixed by N and m."""
    length = x.size - (len(coef) - 1) * m
    full = length // m
    p = 8 if m < 64 else 4
    main = full - full % p
    total = _product_rows(x, m, coef, 0, main, p, buf) if main else 0.0
    if full > main:
        total += _product_rows(x, m, coef, main, full - main, full - main, buf)
    if length > full * m:
        total += _sum_sq_diff(x[full * m:], m, coef, buf)
    return total


def _sums_by_products(x: np.ndarray, ms, order: int = 2) -> np.ndarray:
    """The sums of :func:`_sums_direct_shared` (order 2: SP 1065 eq. 11; order 3: eq. 20)
    of an in-memory, gap-free phase array: each m ≥ :data:`_PRODUCT_MIN_M` by BLAS matrix
    products of a band matrix of the coefficients with rows of ``x``
    (:func:`_sum_sq_products`: one pass that reads the phase and writes the terms, where
    the differences take two or three), with one BLAS thread (the products and sums are
    then the same bytes whatever the threads available, as in a validation worker); the
    smaller m by differences.

    Rounding: a term v = Σ_j c_j·x[n + j·m] formed from the phase itself (not from its
    differences), in whatever order the BLAS kernel adds (the zero coefficients add
    exactly), errs by at most δ + u·|v| with δ = u·max|x|·(Σ|c_j| over the c_j that are not
    powers of two (rounded products) + (P − 2)·Σ|c_j| (the P − 2 partial sums before the
    last)), P terms, unit roundoff u: ADEV (1, −2, 1) 4u·max|x|, HDEV (−1, 3, −3, 1)
    22u·max|x|. The terms' errors then move the sum S of L squares by at most
    (2r + r² + 3u)·S, r = δ·√(L/S) (Cauchy–Schwarz; δ taken 1 % larger for the
    second-order terms): this is the error the products add beyond the summation of the L
    squares, which both paths share (the same pieces and block totals; its own worst case,
    γ of a few thousand, is not in the bound), so the bound decides between the two paths
    and is not a bound on the sum's total error.
    An m where that bound exceeds :data:`PRODUCT_RTOL` (a phase far larger than its
    differences: random-walk rate noise, a strong rate ramp) is summed by differences
    instead (foreseen from :data:`_PROBE` terms, then checked on the sum itself). On white
    rate noise of 10⁷ samples the bound falls as 1/√m and is under PRODUCT_RTOL from
    m = 32 (ADEV) or m = 128 (HDEV); the errors being random, the sums differ from the
    differences' by ~10⁻¹⁶. (Bounds of sums of products: N. J. Higham, *Accuracy and
    Stability of Numerical Algorithms*, 2nd ed., §3.1, γ_n.)"""
    from threadpoolctl import threadpool_limits

    coef = _COEF["adev" if order == 2 else "hdev"]
    ms = [int(m) for m in ms]
    if x.size < _PRODUCT_MIN_N or not (x.flags.c_contiguous and x.dtype == np.float64):
        return _sums_direct_shared(x, ms, order)
    out = np.empty(len(ms))
    big = [i for i, m in enumerate(ms) if m >= _PRODUCT_MIN_M]
    small = [i for i, m in enumerate(ms) if m < _PRODUCT_MIN_M]
    redo = small
    if big:
        top = max(float(np.max(x)), -float(np.min(x)))
        inexact = sum(abs(c) for c in coef if math.frexp(abs(c))[0] != 0.5)
        delta = 1.01 * _UNIT_ROUNDOFF * top * (inexact + (len(coef) - 2) * sum(map(abs, coef)))
        buf = np.empty(max(_PRODUCT_BLOCK, _BLOCK))    # products, and _sum_sq_diff's chunks

        def bound(s, length):
            r = delta * math.sqrt(length / s) if s > 0 else math.inf
            return 2 * r + r * r + 3 * _UNIT_ROUNDOFF

        with threadpool_limits(limits=1, user_api="blas"):
            for i in big:
                m = ms[i]
                length = x.size - (len(coef) - 1) * m
                # the bound foreseen from _PROBE terms at the middle (a phase where the
                # products would be refused goes to the differences at once)
                c = max(0, (length - _PROBE) // 2)
                k = min(_PROBE, length)
                probe = _sum_sq_diff(x[c: c + k + (len(coef) - 1) * m], m, coef, buf)
                if bound(probe * length / k, length) > PRODUCT_RTOL:
                    redo = redo + [i]
                    continue
                s = _sum_sq_products(x, m, coef, buf)
                if bound(s, length) <= PRODUCT_RTOL:
                    out[i] = s
                else:
                    redo = redo + [i]
    if redo:
        out[redo] = _sums_direct_shared(x, [ms[i] for i in redo], order)
    return out


def _split_sums(x, ms: list[int], bsz: int) -> np.ndarray:
    """:func:`_sums_direct_shared` of a streamed phase: the m within a chunk together,
    each larger m alone (:func:`_sums_far`)."""
    small = [i for i, m in enumerate(ms) if m <= bsz]
    out = np.empty(len(ms))
    if small:
        out[small] = _sums_direct_shared(x, [ms[i] for i in small])
    for i, m in enumerate(ms):
        if m > bsz:
            out[i] = _sums_far(x, m, bsz)
    return out


def _sums_far(x: CumulativeSum, m: int, width: int) -> float:
    """Σ_n (x[n+2m] − 2x[n+m] + x[n])² (SP 1065 eq. 11) of a streamed phase at an m beyond
    a chunk, in bounded memory and with each point of the phase rebuilt about once.

    Taken in order of n, a chunk needs three far pieces (at n, n + m, n + 2m), each rebuilt
    from the record: three rebuilds of every point. Here the terms go in chains instead:
    for every chunk start s of [0, m), n ∈ s + qm + [0, w) for q = 0, 1, …, so that the
    pieces a chunk needs are the previous chunk's two later ones and one new piece
    (:meth:`~gonio.analysis.noise.stream.CumulativeSum.span`, from the fine checkpoints).
    The same terms as the array path, summed in another order (equal to rounding)."""
    length = x.size - 2 * m
    total = 0.0
    for s in range(0, min(m, length), width):
        w = min(width, m - s)
        p0, p1 = x.span(s, s + w), x.span(s + m, s + m + w)
        for n0 in range(s, length, m):
            k = min(w, length - n0)
            p2 = x.span(n0 + 2 * m, n0 + 2 * m + w)        # at least k points
            v = np.subtract(p2[:k], p1[:k])
            v -= p1[:k]
            v += p0[:k]
            total += _ssq(v)
            p0, p1 = p1, p2
    return total


def _sum_sq_mod(x: np.ndarray, m: int) -> float:
    """Σ_j (Σ_{i=j}^{j+m−1} x[i+2m] − 2x[i+m] + x[i])², j = 0 … N−3m (SP 1065 eq. 14).

    The second differences are formed first (small numbers), then their moving sum
    of length m by a cumulative sum, so nothing large is ever subtracted; in chunks
    of j (the cumulative sum restarts with each, temporaries stay small).
    """
    n = x.size
    n_terms = n - 3 * m + 1
    if m > _BLOCK and isinstance(x, (CumulativeSum, _Window)):
        return _sum_sq_mod_streamed(x, m, n_terms)
    chunk = max(_BLOCK, m)
    e = np.empty(chunk + m)
    d1 = np.empty(chunk + 2 * m)            # first differences, then the moving sums
    total = 0.0
    for a in range(0, n_terms, chunk):
        b = min(n_terms, a + chunk)
        k = b - a + m - 1  # second differences i = a … b + m − 2
        ee = e[1: k + 1]
        # (x[i+2m] − x[i+m]) − (x[i+m] − x[i]): two passes of first differences
        np.subtract(x[a + m: a + 2 * m + k], x[a: a + m + k], out=d1[: k + m])
        np.subtract(d1[m: k + m], d1[:k], out=ee)
        e[0] = 0.0
        np.cumsum(e[: k + 1], out=e[: k + 1])
        w = d1[: k + 1 - m]
        np.subtract(e[m: k + 1], e[: k + 1 - m], out=w)
        total += _ssq(w)
    return total


#: Phase points up to which the modified variance's octave sums take the in-memory path
#: (:func:`_mdev_octave_sums`: one more record-length array); beyond, the chunked sums.
MDEV_IN_MEMORY = 1 << 24


def _mdev_octave_sums(x: np.ndarray, ms) -> np.ndarray:
    """Σ_j (Σ_{i=j}^{j+m−1} x[i+2m] − 2x[i+m] + x[i])² (SP 1065 eq. 14) at every m of
    ``ms`` that is a power of two (NaN at the others), with no running sum.

    With y[t] = x[t+1] − x[t] and W_m[j] = Σ_{i=j}^{j+m−1} (x[i+m] − x[i]) (a triangular
    window of y of width 2m − 1), the inner sum is W_m[j+m] − W_m[j], and the windows
    double exactly: W_1 = y, W_2m[j] = W_m[j] + 2·W_m[j+m] + W_m[j+2m]. Each octave
    costs a few vectorised passes over the record where a running sum (a sequential
    loop) cost several times more; W is the same local sum of y as the chunked path's
    (no cumulative sum of the record), built in place (one record-length array)."""
    ms = np.asarray(ms, dtype=np.int64)
    out = np.full(ms.size, np.nan)
    pow2 = (ms > 0) & ((ms & (ms - 1)) == 0)
    if not pow2.any():
        return out
    n = x.size
    w = np.subtract(x[1:], x[:-1])              # W_1 = y, length n − 1
    size = n - 1
    buf = np.empty(_BLOCK)
    top = int(ms[pow2].max())
    m = 1
    while True:
        n_terms = n - 3 * m + 1
        if n_terms < 1:
            break
        hit = np.flatnonzero(ms == m)
        if hit.size:
            total = 0.0
            for a in range(0, n_terms, _BLOCK):
                b = min(n_terms, a + _BLOCK)
                v = buf[: b - a]
                np.subtract(w[a + m: b + m], w[a:b], out=v)
                total += _ssq(v)
            out[hit] = total
        if m >= top:
            break
        size -= 2 * m                           # W_2m: W_m[j] + 2 W_m[j+m] + W_m[j+2m]
        for a in range(0, size, _BLOCK):        # in place, ascending: every read lies
            b = min(size, a + _BLOCK)           # at or after what this piece writes
            v = buf[: b - a]
            np.add(w[a + m: b + m], w[a + m: b + m], out=v)
            v += w[a:b]
            v += w[a + 2 * m: b + 2 * m]
            w[a:b] = v
        m *= 2
    return out


def _sum_sq_mod_streamed(x, m: int, n_terms: int) -> float:
    """:func:`_sum_sq_mod` of a streamed phase at a large m, in bounded memory: the moving
    sums of the second differences as differences of their cumulative sum, itself
    streamed (never an array of m points)."""
    def second_differences(a, b):
        d = x[a + 2 * m: b + 2 * m]
        d -= x[a + m: b + m]
        d -= x[a + m: b + m]
        d += x[a:b]
        return d
    c = CumulativeSum(Record(n_terms + m - 1, second_differences))
    total = 0.0
    for s in range(0, n_terms, _BLOCK):
        e = min(n_terms, s + _BLOCK)
        total += _ssq(c[s + m: e + m] - c[s:e])
    return total


def _direct_sums(kind: str, x: np.ndarray, ms) -> np.ndarray:
    """The sum of squared terms of ``kind`` at each m, O(N) per m."""
    if kind in ("adev", "hdev") and isinstance(x, np.ndarray):
        return _sums_by_products(x, ms, order=2 if kind == "adev" else 3)
    if kind == "adev":
        return _sums_direct_shared(x, ms)
    if kind == "mdev":
        out = np.full(len(ms), np.nan)
        if type(x) is np.ndarray and x.size <= MDEV_IN_MEMORY:
            out = _mdev_octave_sums(x, ms)
        for i in np.flatnonzero(np.isnan(out)):
            out[i] = _sum_sq_mod(x, int(ms[i]))
        return out
    if kind == "hdev":
        buf = np.empty(min(_BLOCK, x.size))
        return np.array([_sum_sq_diff(x, int(m), _COEF["hdev"], buf) for m in ms])
    raise AssertionError(kind)


def _totdev_sums(x: np.ndarray, ms) -> np.ndarray:
    """Σ_{i=2}^{N−1} (x*[i−m] − 2x*[i] + x*[i+m])² over the record extended by odd
    reflection at both ends, x*[1−j] = 2x[1] − x[1+j], x*[N+j] = 2x[N] − x[N−j]
    (SP 1065 eq. 25, 1-based)."""
    n = x.size
    ext = np.concatenate((2 * x[0] - x[n - 2:0:-1], x, 2 * x[-1] - x[-2:0:-1]))
    off = n - 2  # ext[off + k] = x[k]
    buf = np.empty(min(_BLOCK, n))
    out = []
    for m in ms:
        m = int(m)
        seg = ext[off + 1 - m: off + n - 1 + m]  # i = 1 … n−2 (0-based) ± m
        out.append(_sum_sq_diff(seg, m, _COEF["adev"], buf))
    return np.array(out)


# ----------------------------------------------------------- gap-aware sums (O(N))
def _gap_sums(kind: str, x: np.ndarray, bad: np.ndarray, angle: bool, ms):
    """(sums, valid-term counts) with only the terms whose samples are all valid.

    Rate/increment: ``bad`` is the prefix count of NaN samples; a term spanning
    x[a] … x[b] is valid when no sample in [a, b) is NaN. Angle: ``bad`` marks NaN
    points; ``adev``/``hdev`` need their 3/4 points, ``mdev`` every point of its
    window [j, j+3m−1]. x is zero-filled at NaN so that invalid terms are finite.
    """
    z = np.where(np.isfinite(x), x, 0.0) if angle else x
    if angle:
        badc = np.zeros(x.size + 1, dtype=np.int64)
        np.cumsum(bad, out=badc[1:])
    sums, counts = [], []
    n = x.size
    for m in ms:
        m = int(m)
        if kind in ("adev", "hdev"):
            p_last = 2 if kind == "adev" else 3
            length = n - p_last * m
            coef = _COEF[kind]
            v = coef[0] * z[:length]
            for p in range(1, p_last + 1):
                v = v + coef[p] * z[p * m: p * m + length]
            if angle:
                ok = ~bad[:length]
                for p in range(1, p_last + 1):
                    ok &= ~bad[p * m: p * m + length]
            else:
                ok = bad[p_last * m: p_last * m + length] == bad[:length]
        else:  # mdev
            e = z[2 * m:] - 2 * z[m: n - m] + z[: n - 2 * m]
            c = np.concatenate(([0.0], np.cumsum(e)))
            v = c[m:] - c[:-m]
            length = v.size  # n − 3m + 1
            if angle:
                ok = (badc[3 * m: 3 * m + length] - badc[:length]) == 0
            else:
                ok = bad[3 * m - 1: 3 * m - 1 + length] == bad[:length]
        v = v[ok]
        sums.append(_ssq(v))
        counts.append(int(ok.sum()))
    return np.array(sums), np.array(counts, dtype=np.int64)


# ------------------------------------------------- all τ: the correlation expansion
def _gather(z: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """z[idx] with zeros beyond the end of z."""
    out = z[np.minimum(idx, z.size - 1)]
    out[idx >= z.size] = 0.0
    return out


def _rect_tiled(z: np.ndarray, out: np.ndarray, n_lo: int, n_len: int, m_lo: int,
                m_len: int, c: int, base: int = 0) -> None:
    """out[m − base] += Σ_{n ∈ [n_lo, n_lo + n_len)} z[n]·z[n + c·m] for
    m ∈ [m_lo, m_lo + m_len) (terms beyond the end of z are 0), as cross-correlations
    of tiles of n and m of at most max(2¹⁴, N/16) each."""
    tile = max(1 << 14, z.size // 16)
    for n_a in range(n_lo, min(n_lo + n_len, z.size), tile):
        u = z[n_a: min(n_lo + n_len, n_a + tile)]
        for m_a in range(m_lo, m_lo + m_len, tile):
            mn = min(m_lo + m_len, m_a + tile) - m_a
            v0 = n_a + c * m_a
            if v0 >= z.size:
                break
            lv = u.size + c * (mn - 1)
            v = z[v0: v0 + lv]
            nf = sfft.next_fast_len(lv + 1, real=True)
            spec = sfft.rfft(v, nf)
            spec *= np.conj(sfft.rfft(u, nf))
            corr = sfft.irfft(spec, nf)
            del spec
            out[m_a - base: m_a - base + mn] += corr[c * np.arange(mn)]
            del corr


def _wedge_corr(z: np.ndarray, m_max: int, s: int, c: int) -> np.ndarray:
    """W[m] = Σ_{n < s·m} z[n]·z[n + c·m] for m = 0 … m_max (terms beyond the end
    of z are 0), in O(M log² M).

    Divide and conquer over m: on a block m ∈ [m0, m0+w) the region is
    n ∈ [s·m0, s·m) (a wedge); its upper half m ∈ [m0+w/2, m0+w) contains the full
    rectangle n ∈ [s·m0, s·(m0+w/2)), a cross-correlation of one slice of z with
    another at lags c·m (one FFT per block, batched over the blocks of a level);
    the two half wedges recurse. Blocks of 8 are summed directly.
    (Our construction; checked in the tests against direct sums.)
    """
    width = 8
    while width < m_max + 1:
        width *= 2
    out = np.zeros(width)
    w = width
    budget = max(1 << 13, z.size // 32)  # elements of temporaries per batch
    while w > 8:
        h = w // 2
        nb = (m_max - h) // w + 1 if m_max >= h else 0  # blocks whose upper half matters
        if nb <= 0:
            w = h
            continue
        lu, lv = s * h, (s + c) * h - 1
        nf = sfft.next_fast_len(lv + 1, real=True)
        per = max(1, budget // nf)
        for b0 in range(0, nb, per):
            m0 = np.arange(b0, min(nb, b0 + per)) * w
            if m0.size == 1:  # one large block: in tiles (bounded temporaries)
                mb = int(m0[0])
                _rect_tiled(z, out, s * mb, lu, mb + h, min(h, m_max + 1 - mb - h), c)
                continue
            else:
                u = _gather(z, (s * m0)[:, None] + np.arange(lu)[None, :])
                uspec = sfft.rfft(u, nf, axis=1)
                del u
                v = _gather(z, (s * m0 + c * (m0 + h))[:, None] + np.arange(lv)[None, :])
                spec = sfft.rfft(v, nf, axis=1)
                del v
            spec *= np.conj(uspec, out=uspec)
            del uspec
            corr = sfft.irfft(spec, nf, axis=1)
            del spec
            t = c * np.arange(h)
            out[(m0 + h)[:, None] + np.arange(h)[None, :]] += corr[:, t]
            del corr
        w = h
    # base wedges of 8: m ∈ [m0, m0+8), n ∈ [s·m0, s·m)
    nb = m_max // 8 + 1
    kk, jj = np.nonzero(np.arange(8 * s)[:, None] < s * np.arange(8)[None, :])
    per = max(1, budget // max(kk.size, 1))
    for b0 in range(0, nb, per):
        m0 = np.arange(b0, min(nb, b0 + per)) * 8
        a = _gather(z, (s * m0)[:, None] + kk[None, :])
        b = _gather(z, ((s + c) * m0)[:, None] + (kk + c * jj)[None, :])
        np.add.at(out, (m0[:, None] + jj[None, :]).ravel(), (a * b).ravel())
    return out[: m_max + 1]


def _autocorr_accumulate(z: np.ndarray, m: np.ndarray, weight: dict, out: np.ndarray) -> None:
    """out += Σ_k weight[k]·A[k·m], with A[j] = Σ_n z[n] z[n+j] the autocorrelation.

    A is computed block-pair by block-pair (16 blocks: 136 FFTs of an eighth of the
    record); each pair's lags are added straight into ``out`` at the m (ascending)
    they serve, so neither A nor any temporary exceeds a fraction of the input.
    """
    n = z.size
    kmax = max(weight) * int(m[-1])
    nblk = 16 if n >= 1 << 14 else 1
    bsz = -(-n // nblk)
    nf = sfft.next_fast_len(2 * bsz, real=True)
    for p in range(nblk):
        u = z[p * bsz: (p + 1) * bsz]
        if u.size == 0:
            continue
        uspec = sfft.rfft(u, nf)
        np.conj(uspec, out=uspec)
        for q in range(p, nblk):
            v = z[q * bsz: (q + 1) * bsz]
            base = (q - p) * bsz
            if v.size == 0 or base - (bsz - 1) > kmax:
                continue
            spec = sfft.rfft(v, nf)
            spec *= uspec
            cc = sfft.irfft(spec, nf)  # cc[t mod nf] = Σ_i u_i v_{i+t}
            del spec
            lag0 = max(0, base - (u.size - 1)) if q > p else 0  # lags this pair covers
            lag1 = min(base + v.size - 1, kmax)
            for k, w in weight.items():
                i0 = int(np.searchsorted(m, -(-lag0 // k)))
                i1 = int(np.searchsorted(m, lag1 // k, side="right"))
                if i1 > i0:
                    out[i0:i1] += w * cc[(k * m[i0:i1] - base) % nf]
            del cc
        del uspec


def _subtract_at(s: np.ndarray, c: float, w: np.ndarray, m: np.ndarray) -> None:
    """s −= c·w[m], in chunks."""
    step = 1 << 16
    for a in range(0, m.size, step):
        s[a: a + step] -= c * w[m[a: a + step]]


def _expanded_sums(kind: str, x, ms: np.ndarray, rtol: float) -> np.ndarray:
    """Σ of squared terms for every m in ``ms`` (ascending) by the correlation
    expansion, O(N log² N) in all (our derivation, checked in the tests against the
    direct sums and allantools).

    The term is Σ_p c_p z[j + p·m] (z = x for adev/hdev; z = cumsum of x for mdev,
    whose term is a third difference of it). With L terms, squaring and summing gives
    Σ_p c_p² (prefix sums of z²) + 2 Σ_{p<q} c_p c_q T_pq, where
    T_pq = Σ_{n=pm}^{pm+L−1} z[n] z[n+(q−p)m] is the full autocorrelation A[(q−p)m]
    minus a head Σ_{n<pm} and a tail over the last (P−1−q)m values of n — wedges of
    :func:`_wedge_corr` on z and on z reversed. The expansion cancels large terms;
    each m whose estimated rounding error (8·ε·log₂N·Σz²·(Σ|c|)², about 4× the error
    measured on white and random-walk records) exceeds
    ``rtol``·sum is recomputed directly (the small m and the few terms near the end).

    (mdev has :func:`_mdev_local_sums`: on the whole record its cumulative sum
    loses too much.)
    """
    coef = _COEF[kind]
    p_last = len(coef) - 1
    z = x
    n = z.size
    m = ms
    q = np.empty(n + 1)
    q[0] = 0.0
    np.square(z, out=q[1:])
    np.cumsum(q[1:], out=q[1:])
    s = np.zeros(m.size)
    step = 1 << 16
    for a in range(0, m.size, step):
        mm = m[a: a + step]
        length = n - p_last * mm
        for p in range(p_last + 1):
            s[a: a + step] += coef[p] ** 2 * (q[p * mm + length] - q[p * mm])
    err = 8.0 * np.finfo(float).eps * math.log2(max(n, 2)) * q[n] * sum(map(abs, coef)) ** 2
    del q
    pairs = [(p, qq) for p in range(p_last + 1) for qq in range(p + 1, p_last + 1)]
    weight: dict[int, float] = {}
    for p, qq in pairs:
        weight[qq - p] = weight.get(qq - p, 0.0) + 2 * coef[p] * coef[qq]
    _autocorr_accumulate(z, m, weight, s)
    m_max = int(m[-1])
    zr = z[::-1]
    for p, qq in pairs:
        k = qq - p
        cc = 2 * coef[p] * coef[qq]
        if p > 0:   # head: Σ_{n < p·m} z[n] z[n + k·m]
            _subtract_at(s, cc, _wedge_corr(z, m_max, p, k), m)
        tail = p_last - qq
        if tail > 0:  # tail: the last tail·m values of n, = a head of z reversed
            _subtract_at(s, cc, _wedge_corr(zr, m_max, tail, k), m)
    del z, zr
    redo = np.flatnonzero(~(s > err / rtol))
    if redo.size:
        s[redo] = _direct_sums(kind, x, m[redo])
    return s


# ------------------------------------ mdev, all τ: local segments, octave by octave
#: Segment length over the longest term's span (``_mdev_local_sums``): the
#: cancellation grows as (segment/m)⁵ for rate random walk, so segments stay short.
_SEG_RATIO = 3
#: Below this m, ``mdev`` "all" sums are formed directly (O(N) each, cheap there).
_MDEV_DIRECT_BELOW = 16
#: Elements of the per-batch temporaries of the segment sums (bounded memory).
_SEG_BUDGET = 1 << 18
#: Blocks of m summed directly at the bottom of :func:`_wedge_rows`.
_WEDGE_BASE = 8


def _xcorr_rows(u: np.ndarray, v: np.ndarray, c: int, count: int) -> np.ndarray:
    """corr[r, j] = Σ_i u[r, i]·v[r, i + c·j] for j < count (rows of u and v; v
    zero beyond its end), by FFT along the rows."""
    nf = sfft.next_fast_len(max(v.shape[1], u.shape[1] + c * (count - 1)) + 1, real=True)
    spec = sfft.rfft(v, nf, axis=1)
    spec *= np.conj(sfft.rfft(u, nf, axis=1))
    corr = sfft.irfft(spec, nf, axis=1)
    return corr[:, c * np.arange(count)]


def _wedge_rows(z: np.ndarray, m_lo: int, count: int, s: int, c: int) -> np.ndarray:
    """W[r, m − m_lo] = Σ_{i < s·m} z[r, i]·z[r, i + c·m] for m ∈ [m_lo, m_lo + count)
    and every row r of ``z`` (whose last column is a zero: indices past it, reached
    only for m beyond the range, are clipped to it), in O(R·count·log² count).

    The rectangle i < s·m_lo is one cross-correlation per row; the rest, the wedge
    s·m_lo ≤ i < s·m, is divided and conquered over m as in :func:`_wedge_corr`
    (the upper half of a block of m holds a full rectangle, one FFT per block,
    batched over blocks and rows; blocks of _WEDGE_BASE summed directly). Our construction,
    checked in the tests against the definition.
    """
    rows, last = z.shape[0], z.shape[1] - 1
    out = np.zeros((rows, count))
    def rect(n_lo, n_len, a, n_t):  # out[:, a − m_lo + t] += Σ_{n_lo ≤ i < n_lo+n_len} z·z
        if rows == 1:  # tiles: bounded temporaries (one long segment)
            _rect_tiled(z[0, :last], out[0], n_lo, n_len, a, n_t, c, base=m_lo)
        else:
            out[:, a - m_lo: a - m_lo + n_t] += _xcorr_rows(
                z[:, n_lo: n_lo + n_len],
                z[:, n_lo + c * a: n_lo + c * a + n_len + c * (n_t - 1)], c, n_t)

    if s * m_lo > 0:
        rect(0, s * m_lo, m_lo, count)
    width = _WEDGE_BASE
    while width < count:
        width *= 2
    w = width
    while w > _WEDGE_BASE:
        h = w // 2
        nb = (count - h + w - 1) // w if count > h else 0  # blocks with an upper half
        if nb > 0:
            lu, lv = s * h, s * h + c * (h - 1)
            nf = sfft.next_fast_len(lv + 1, real=True)
            a0 = m_lo + np.arange(nb) * w  # block starts (absolute m)
            per = max(1, _SEG_BUDGET // (4 * nf * rows))
            if nb <= 8:  # few large blocks: slices (a gather would copy them)
                for a in a0.tolist():
                    n_t = min(h, m_lo + count - a - h)
                    if n_t > 0:
                        rect(s * a, lu, a + h, n_t)
                nb = 0
            for b0 in range(0, nb, per):
                a = a0[b0: b0 + per]
                iu = np.minimum((s * a)[:, None] + np.arange(lu)[None, :], last)
                iv = np.minimum((s * a + c * (a + h))[:, None] + np.arange(lv)[None, :],
                                last)
                spec = sfft.rfft(z[:, iv], nf, axis=2)
                spec *= np.conj(sfft.rfft(z[:, iu], nf, axis=2))
                corr = sfft.irfft(spec, nf, axis=2)
                del spec
                tgt = (a - m_lo + h)[:, None] + np.arange(h)[None, :]
                ok = tgt < count
                vals = corr[:, :, c * np.arange(h)]
                out[:, tgt[ok]] += vals[:, ok]
                del corr, vals
        w = h
    # base blocks of _WEDGE_BASE: m ∈ [a, a+8), i ∈ [s·a, s·m)
    kk, jj = np.nonzero(np.arange(_WEDGE_BASE * s)[:, None]
                        < s * np.arange(_WEDGE_BASE)[None, :])
    pick = (jj[:, None] == np.arange(_WEDGE_BASE)[None, :]).astype(np.float64)  # term -> m
    a_all = m_lo + np.arange(-(-count // _WEDGE_BASE)) * _WEDGE_BASE
    per = max(1, _SEG_BUDGET // max(1, 4 * kk.size * rows))
    for b0 in range(0, a_all.size, per):
        a = a_all[b0: b0 + per]
        prod = z[:, np.minimum((s * a)[:, None] + kk[None, :], last)]
        prod *= z[:, np.minimum((s * a)[:, None] + (kk + c * (a[:, None] + jj[None, :])),
                                last)]
        blk = np.einsum("rbk,kj->rbj", prod, pick).reshape(rows, -1)
        tgt = (a - m_lo)[:, None] + np.arange(_WEDGE_BASE)[None, :]
        ok = (tgt < count).ravel()
        out[:, tgt.ravel()[ok]] += blk[:, ok]
        del prod, blk
    return out


def _sq_prefix_at(v: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """Σ_{i<t} v[i]² at each t of ``pos`` (monotone, 0 ≤ t ≤ len(v)), accumulated in
    chunks (no array of all the prefix sums)."""
    if pos.size > 1 and pos[0] > pos[-1]:
        return _sq_prefix_at(v, pos[::-1])[::-1]
    sp = pos
    out = np.empty(pos.size)
    run, k, step = 0.0, 0, 1 << 16
    for a in range(0, v.size + 1, step):
        b = min(v.size, a + step)
        c = np.zeros(b - a + 1)
        np.square(v[a:b], out=c[1:])
        np.cumsum(c, out=c)
        c += run
        hi = int(np.searchsorted(sp, b, side="right"))
        out[k:hi] = c[sp[k:hi] - a]
        k = hi
        run = float(c[-1])
    return out


def _reverse_rows(z: np.ndarray) -> None:
    """Reverse each row of z in place, in chunks (no copy of the whole array)."""
    n = z.shape[1]
    half = n // 2
    step = 1 << 16
    for a in range(0, half, step):
        b = min(half, a + step)
        left = z[:, a:b].copy()
        z[:, a:b] = z[:, n - b: n - a][:, ::-1]
        z[:, n - b: n - a] = left[:, ::-1]


def _quadratic_basis(lz: int) -> np.ndarray:
    """Orthonormal basis (lz × 3) of the polynomials of degree ≤ 2 on lz points."""
    t = np.linspace(-1.0, 1.0, lz)
    basis, _ = np.linalg.qr(np.stack([np.ones(lz), t, t * t], axis=1))
    return basis


def _mdev_rows(x: np.ndarray, starts: np.ndarray, length: int, ms: np.ndarray,
               step: int | None = None):
    """(Σ over the rows of the mdev sums of each segment x[s : s + length] at each m,
    Σ over the rows of their rounding-error bounds). With ``step``, only the terms
    that start in the first ``step`` points of each segment (j < step; every such
    term must end inside the segment).

    Each segment is treated as a record of its own (the expansion of
    :func:`_expanded_sums` on z = cumsum of the segment's phase less its
    least-squares quadratic, batched over the segments), so every quantity is of
    the size of the segment's local fluctuation, not the record's. A segment too
    long to batch is done alone with temporaries bounded as in
    :func:`_expanded_sums` (blocked autocorrelation, tiled rectangles).
    """
    m_lo, count = int(ms[0]), int(ms[-1] - ms[0] + 1)
    lz = length + 1
    coef = _COEF["mdev"]
    pairs = [(p, q) for p in range(4) for q in range(p + 1, 4)]
    weight: dict[int, float] = {}
    for p, qq in pairs:
        weight[qq - p] = weight.get(qq - p, 0.0) + 2 * coef[p] * coef[qq]
    total = np.zeros(count)
    err = 0.0
    kmax = 3 * int(ms[-1])
    nf = sfft.next_fast_len(lz + kmax, real=True)
    per = _SEG_BUDGET // nf
    batched = per >= 2
    basis = _quadratic_basis(lz) if batched else None
    mm = np.arange(m_lo, m_lo + count)
    jn = lz - 3 * mm if step is None else np.full(count, step)  # terms at each m
    for r0 in range(0, starts.size, max(1, per)):
        st = starts[r0: r0 + max(1, per)]
        rows = st.size
        z = np.zeros((rows, lz + 1))  # the last column stays 0 (see _wedge_rows)
        if batched:
            seg = x[st[:, None] + np.arange(length)[None, :]]
            seg -= seg.mean(axis=1, keepdims=True)
            np.cumsum(seg, axis=1, out=z[:, 1:lz])
            del seg
            zz = z[:, :lz]
            zz -= np.einsum("rk,lk->rl", np.einsum("rl,lk->rk", zz, basis), basis)
        else:
            seg = x[int(st[0]): int(st[0]) + length]
            np.subtract(seg, seg.mean(), out=z[0, 1:lz])
            np.cumsum(z[0, 1:lz], out=z[0, 1:lz])
            zz = z[:, :lz]
            remove_quadratic(zz[0])
        acc = np.zeros((rows, count))
        if batched:
            q = np.zeros((rows, lz + 1))
            np.square(zz, out=q[:, 1:])
            np.cumsum(q[:, 1:], axis=1, out=q[:, 1:])
            err += float(q[:, -1].sum())
            for p in range(4):
                acc += coef[p] ** 2 * (q[:, p * mm + jn] - q[:, p * mm])
            del q
        else:  # one long row: the prefix sums of z² only where they are needed
            err += _ssq(zz[0])
            for p in range(4):
                acc[0] += coef[p] ** 2 * (_sq_prefix_at(zz[0], p * mm + jn)
                                          - _sq_prefix_at(zz[0], p * mm))
        if step is not None:
            # Σ_{j<step} z[j+pm]·z[j+qm] = R(km) + W_p,k(z[step:]) − W_p,k(z), with
            # R(d) = Σ_{i<step} z[i]·z[i+d] and W the head wedges
            if batched:
                spec = sfft.rfft(zz, nf, axis=1)
                spec *= np.conj(sfft.rfft(zz[:, :step], nf, axis=1))
                ac = sfft.irfft(spec, nf, axis=1)
                del spec
                for k, wk in weight.items():
                    acc += wk * ac[:, k * mm]
                del ac
            else:
                for k, wk in weight.items():
                    buf = np.zeros(count)
                    _rect_tiled(zz[0], buf, 0, step, m_lo, count, k, base=m_lo)
                    acc[0] += wk * buf
                    del buf
            for p, qq in pairs:
                if p > 0:
                    cc = 2 * coef[p] * coef[qq]
                    acc += cc * _wedge_rows(z[:, step:], m_lo, count, p, qq - p)
                    acc -= cc * _wedge_rows(z, m_lo, count, p, qq - p)
            del z, zz
            total += acc.sum(axis=0)
            continue
        if batched:
            spec = sfft.rfft(zz, nf, axis=1)
            ac = sfft.irfft(spec.real ** 2 + spec.imag ** 2, nf, axis=1)
            del spec
            for k, wk in weight.items():
                acc += wk * ac[:, k * mm]
            del ac
        else:
            _autocorr_accumulate(zz[0], mm, weight, acc[0])
        for rev in (False, True):  # heads on z, then tails as heads of z reversed
            if rev:
                _reverse_rows(zz)
            for p, qq in pairs:
                s = 3 - qq if rev else p
                if s > 0:
                    acc -= 2 * coef[p] * coef[qq] * _wedge_rows(z, m_lo, count, s, qq - p)
        del z, zz
        total += acc.sum(axis=0)
    err *= 8.0 * np.finfo(float).eps * math.log2(max(lz, 2)) * sum(map(abs, coef)) ** 2
    return total[ms - m_lo], err


def _mdev_local_sums(x: np.ndarray, ms: np.ndarray, rtol: float) -> np.ndarray:
    """Σ of squared mdev terms (SP 1065 eq. 14) at every m of ``ms`` (ascending) for
    the phase x, exact to about ``rtol`` (relative), by the correlation expansion on
    short local segments, one octave of m at a time (our construction; checked in the
    tests against exact integer sums, the direct sums and allantools; see
    docs/noise-all-tau.md).

    A term at m spans 3m phase points. For the m of one octave, m ≤ m₁, let
    V = 3m₁ and cut the record into segments of L = 3V points starting every L − V
    points. Segment k contributes the terms that start in its first L − V points
    (these j-blocks partition the record, and each such term ends inside the
    segment); the last segment contributes all its terms. Each segment is a short
    record of its own whose cumulative sum is re-centred locally
    (:func:`_mdev_rows`). That is what keeps the expansion exact: on the whole record
    the cumulative sum of the phase of rate random walk grows as N^2.5 and the
    expansion's rounding error relative to the sum as (N/m)⁵ — at 10⁶ samples beyond
    1e-9 for every m below about 10⁴ — while within a segment it is bounded by about
    (L/m)⁵ ≤ 18⁵ times the rounding unit (measured: ≤ 1e-10). m above (n − 1)/6, where
    two segments do not fit, use the whole record (N/m ≤ 6).

    Cost: per octave the segments' rectangles, O(N log m), and their head wedges,
    O(N log² m); O(N log³ N) in all (O(N log² N) would need the wedges of the whole
    record, which are what lose the precision). m < :data:`_MDEV_DIRECT_BELOW`
    directly (O(N) each). Every m whose summed error bound exceeds ``rtol``·sum is
    recomputed directly.
    """
    n = x.size
    out = np.empty(ms.size)
    err = np.zeros(ms.size, dtype=np.float32)
    cap = max(1 << 16, n // 16)  # m per call: bounds the per-m temporaries

    def rows(starts, length, mo, step=None):
        parts = [_mdev_rows(x, starts, length, mo[a: a + cap], step)
                 for a in range(0, mo.size, cap)]
        return np.concatenate([p[0] for p in parts]), max(p[1] for p in parts)

    i0 = int(np.searchsorted(ms, _MDEV_DIRECT_BELOW))
    if i0:
        out[:i0] = _direct_sums("mdev", x, ms[:i0])
    while i0 < ms.size:
        m_a = int(ms[i0])
        m_top = (n - 1) // 6  # largest m with room for two segments of 2V
        if m_a > m_top:  # the rest on the whole record, as one segment
            out[i0:], err[i0:] = rows(np.array([0]), n, ms[i0:])
            break
        i1 = int(np.searchsorted(ms, min(2 * m_a, m_top + 1)))
        mo = ms[i0:i1]
        v = 3 * int(mo[-1])
        length = min(_SEG_RATIO, (n - 1) // v) * v
        if True:
            step = length - v
            n_full = (n - length - 1) // step + 1  # full segments k·step + length < n
            starts = np.arange(n_full) * step
            s_full, e_full = rows(starts, length, mo, step)
            last = n_full * step
            s_last, e_last = rows(np.array([last]), n - last, mo)
            out[i0:i1] = s_full + s_last
            err[i0:i1] = e_full + e_last
        i0 = i1
    redo = np.flatnonzero(~(out > err / rtol))
    redo = redo[ms[redo] >= _MDEV_DIRECT_BELOW]
    if redo.size:
        out[redo] = _direct_sums("mdev", x, ms[redo])
    return out


# -------------------------------------------------------------------- public API
def _id_start(size: int, m: int) -> int:
    """First point of the central sub-record the identification looks at, at m."""
    return max(0, (size - ID_MAX_POINTS * m) // 2)


def _identify(kind: str, x: np.ndarray, bad, angle: bool, ms: np.ndarray, all_taus: bool):
    """Noise type per τ: lag-1 autocorrelation (d_max 3 for hdev, else 2) on the
    longest gap-free stretch of x (a central sub-record of at most ID_MAX_POINTS
    decimated points); where fewer than :data:`ID_RELIABLE_POINTS` decimated points remain,
    the lower of the last type identified from enough points and the type identified there
    (:func:`_settled`), the last type carried where too few remain for any; with
    ``all_taus`` the identification runs at the octaves and each τ takes the nearest
    octave's type. Returns (alpha, alpha_b1)."""
    if bad is not None:
        if angle:
            ok = ~bad
            runs = np.flatnonzero(np.diff(np.concatenate(([0], ok.astype(np.int8), [0]))))
            st, en = runs[0::2], runs[1::2]
        else:  # samples a … b−1 valid: x[a] … x[b] consistent
            nan_at = np.flatnonzero(np.diff(bad) > 0)
            st = np.concatenate(([0], nan_at + 1))
            en = np.concatenate((nan_at, [x.size - 1])) + 1
        i = int(np.argmax(en - st))
        seg = x[st[i]: en[i]]
    else:
        seg = x
    d_max = 3 if kind == "hdev" else 2
    probe = ms
    if all_taus and ms.size > 64:
        probe = np.unique(2 ** np.arange(int(math.log2(ms[-1])) + 1))
    a_lag = np.zeros(probe.size, dtype=np.int64)
    a_b1 = np.full(probe.size, np.nan)
    last, reliable = 0, None
    decs: dict[int, np.ndarray] = {}
    prev, prev_m = None, 0
    for i, m in enumerate(probe):
        if isinstance(seg, CumulativeSum) and int(m) not in decs:
            # the decimated sub-records of the next τ in one pass over the phase, as many
            # as hold _ID_GROUP sub-records of ID_MAX_POINTS points together
            group, points = [], 0
            for v in (int(v) for v in probe[i:]):
                size = min(ID_MAX_POINTS, seg.size // v + 1)
                if group and points + size > _ID_GROUP * ID_MAX_POINTS:
                    break
                group.append(v)
                points += size
            decs = dict(zip(group, seg.decimations(
                [(_id_start(seg.size, v), _id_start(seg.size, v) + ID_MAX_POINTS * v, v)
                 for v in group])))
        m = int(m)
        span = ID_MAX_POINTS * m
        c0 = _id_start(seg.size, m)
        if isinstance(seg, CumulativeSum):
            # streamed: the decimated points only (≤ ID_MAX_POINTS), R(n) from the sums
            dec = decs[m]
            r = noise_id_lag1(dec, 1, d_max=d_max)
            b = noise_id_b1(dec, m, rn_ratio=lambda: _rn_streamed(seg, c0, span, m))
        else:
            # the decimated points gathered once for both methods; where the sub-record
            # is the whole stretch at m and at m/2, every other point of the last ones
            sub = seg[c0: c0 + span] if seg.size > span else seg
            whole = sub is seg
            dec = prev[::2].copy() if whole and prev_m * 2 == m else sub[::m].copy()
            prev, prev_m = (dec, m) if whole else (None, 0)
            r = noise_id_lag1(dec, 1, d_max=d_max, keep_basis=True)
            b = noise_id_b1(dec, m, rn_ratio=lambda: rn_ratio_of_phase(sub, m))
        if r is not None:
            last, reliable = _settled(r[0], reliable, (seg.size - 1) // m)
        a_lag[i] = last
        if b is not None:
            a_b1[i] = b
    release_quadratic_basis()
    if probe is ms:
        return a_lag, a_b1
    out_a = np.empty(ms.size, dtype=np.int8)
    out_b = np.empty(ms.size, dtype=np.float32)
    step = 1 << 14
    for c0 in range(0, ms.size, step):  # nearest octave in log τ, in chunks
        pos = np.clip(np.rint(np.log2(ms[c0: c0 + step])).astype(np.int64), 0,
                      probe.size - 1)
        out_a[c0: c0 + step] = a_lag[pos]
        out_b[c0: c0 + step] = a_b1[pos]
    return out_a, out_b


def _settled(alpha: int, reliable: int | None, points: int) -> tuple[int, int | None]:
    """(the noise type used at this τ, the last type identified from enough points) given the
    type ``alpha`` identified here from ``points`` decimated points (see
    :data:`ID_RELIABLE_POINTS`).

    >>> _settled(2, 0, 32), _settled(-2, 0, 32), _settled(1, 0, 4096), _settled(2, None, 32)
    ((0, 0), (-2, 0), (1, 1), (2, None))
    """
    if points >= ID_RELIABLE_POINTS:
        return alpha, alpha
    if reliable is None:
        return alpha, None
    return min(alpha, reliable), reliable


class _Window:
    """Points c0 … c0 + size − 1 of a sliceable series, indexed from 0."""

    def __init__(self, base, c0: int, size: int):
        self.base, self.c0, self.size = base, int(c0), int(min(size, base.size - c0))

    def __getitem__(self, key):
        a, b, step = key.indices(self.size)
        return self.base[self.c0 + a: self.c0 + max(a, b): step]


def _rn_streamed(x, c0: int, span: int, m: int) -> float | None:
    """R(n) = MVAR/AVAR at m (:func:`gonio.analysis.noise.edf.noise_id_b1`) of the points
    c0 … c0 + span − 1 of a streamed phase, from the chunked sums of eqs. 11 and 14."""
    w = _Window(x, c0, span)
    n = w.size
    if n - 3 * m + 1 < 1:
        return None
    avar = float(_sums_direct_shared(w, [m])[0]) / (n - 2 * m)
    mvar = _sum_sq_mod(w, m) / (m * m * (n - 3 * m + 1))
    return mvar / avar if avar > 0 else None


def _streamed_phase(data: Record, input_type: str, taus, kind: str):
    """The phase of a :class:`~gonio.analysis.noise.stream.Record` given as a rate, as a
    :class:`~gonio.analysis.noise.stream.CumulativeSum` (never held whole), or None where
    the estimator needs the whole array (gaps, angle input, total deviation, every τ)."""
    every = isinstance(taus, str) and taus.strip().lower() == "all"
    if input_type != "rate" or kind == "totdev" or every or not data.all_finite():
        return None
    return CumulativeSum(data, data.mean())


def allan_deviation(data, tau0_s: float, input_type: str, taus="octave", *,
                    scale: float = 1.0, modified: bool = False, kind: str | None = None,
                    confidence: float = 0.683, alpha=None, unit: str = "",
                    rtol_all: float | None = None,
                    overwrite_data: bool = False) -> AllanResult:
    """An Allan-family deviation with Greenhall-edf χ² confidence intervals.

    ``kind``: ``"adev"`` overlapping Allan (default; SP 1065 eq. 11, IEEE 952
    Annex C), ``"mdev"`` modified Allan (eq. 14; also ``modified=True``), ``"hdev"``
    overlapping Hadamard (eq. 20), ``"totdev"`` total (eq. 25). ``x`` is the
    detrended angle series (:func:`angle_series`); NaN samples are gaps (module
    docstring). ``taus="all"`` (gap-free) uses for adev and hdev
    :func:`_expanded_sums`, O(N log² N) for every m, and for mdev
    :func:`_mdev_local_sums`, O(N log³ N), with every m whose estimated relative
    rounding error exceeds ``rtol_all`` (default 1e-6 for adev and hdev, 1e-9 for
    mdev) recomputed directly.

    Confidence intervals: χ² (:func:`gonio.analysis.noise.edf.chi2_interval`) with
    the edf of Greenhall's algorithm for the estimator
    (:func:`gonio.analysis.noise.edf.edf_for`) at the noise type ``alpha`` (given,
    or identified at each τ by the lag-1 autocorrelation with the B1/R(n) ratio as
    cross-check). With gaps the edf is that of a gap-free record giving the same
    number of valid terms.

    Parameters
    ----------
    data : array_like
        Samples; meaning set by ``input_type`` (``rate``, ``increment``, ``angle``).
    tau0_s : float
        Sample interval τ0, s.
    input_type : str
        ``"rate"``, ``"increment"`` or ``"angle"`` — never guessed.
    taus : str or sequence of int
        ``"octave"``, ``"decade:N"``, ``"all"`` or explicit cluster sizes m.
    scale : float
        Increment/angle units per angle unit (e.g. counts/°); ignored for rate.
    modified : bool
        Shorthand for ``kind="mdev"``.
    kind : str
        ``adev``, ``mdev``, ``hdev`` or ``totdev``.
    confidence : float
        Level of the χ² interval (default 0.683).
    alpha : int or array of int, optional
        Noise type for the edf; identified when omitted.
    unit : str
        Label of the deviation's unit, e.g. ``"deg/h"``.
    rtol_all : float, optional
        See ``taus="all"`` above.
    overwrite_data : bool
        For a float64 ``angle`` array: detrend it in its own memory instead of a copy
        (the caller's array is changed; for long records that will not be used again,
        as in the bootstrap of :func:`gonio.analysis.noise.fit.bootstrap_uncertainty`).

    Examples
    --------
    Alternating rate ±1 (°/h) at 1 s: at τ = 1 s the cluster means differ by 2,
    σ² = 2²/2 = 2; at τ = 2 s they are all 0.

    >>> r = allan_deviation([1.0, -1.0] * 8, 1.0, "rate", taus=[1, 2], alpha=0)
    >>> [round(float(v), 6) for v in r.adev]
    [1.414214, 0.0]
    """
    kind = _resolve_kind(kind, modified, confidence)
    tau0_s, scale = _check_args(input_type, tau0_s, scale)
    x = None
    if isinstance(data, Record):
        if data.size < 3:
            raise GonioError(f"need at least 3 samples, got {data.size}", key="data")
        x = _streamed_phase(data, input_type, taus, kind)
        if x is None:
            data = data.to_array()
    arr = data if x is not None else _as_array(data)
    n_samples = arr.size
    factor = 1.0
    if x is not None:
        bad, factor = None, tau0_s
    elif input_type == "rate":
        # the phase is τ0·x: applied to the deviation at the end (one pass less)
        x, bad = _phase(arr, "increment", tau0_s, 1.0)
        factor = tau0_s
    else:
        x, bad = _phase(arr, input_type, tau0_s, scale, overwrite_data)
    del arr
    angle = input_type == "angle"
    n = x.size
    ms = averaging_factors(n, taus, kind=kind)
    all_requested = isinstance(taus, str) and taus.strip().lower() == "all"
    ms, sums, n_terms, n_eff, n_gaps = _deviation_sums(kind, x, bad, angle, ms,
                                                       all_requested, rtol_all)
    if alpha is None:
        alpha_arr, alpha_b1 = _identify(kind, x, bad, angle, ms, all_requested)
    else:
        alpha_arr = np.broadcast_to(np.asarray(alpha, dtype=np.int64), ms.shape).copy()
        alpha_b1 = np.full(ms.size, np.nan)
    del x, bad
    tau, dev, ms, n_terms, edf, lo, hi = _deviation_and_interval(
        kind, ms, sums, n_terms, n_eff, alpha_arr, tau0_s, factor, n, float(confidence),
        compact=all_requested and ms.size > 64)
    return AllanResult(tau_s=tau, adev=dev, m=ms, n_pairs=np.asarray(n_terms), edf=edf,
                       alpha=alpha_arr, ci_low=lo, ci_high=hi,
                       input_type=input_type, method=KIND_METHODS[kind],
                       tau0_s=tau0_s, n_samples=int(n_samples),
                       confidence=float(confidence), unit=unit, alpha_b1=alpha_b1,
                       n_phase=int(n), n_gaps=n_gaps)


def _resolve_kind(kind: str | None, modified: bool, confidence: float) -> str:
    """The estimator's kind from ``kind``/``modified``, and the confidence level checked."""
    if not (0 < float(confidence) < 1):
        raise GonioError(f"confidence must be in (0, 1), not {confidence}", key="confidence")
    if kind is None:
        kind = "mdev" if modified else "adev"
    elif modified and kind != "mdev":
        raise GonioError(f"modified=True contradicts kind={kind!r}", key="kind")
    if kind not in KIND_METHODS:
        raise GonioError(f"kind must be one of {', '.join(KIND_METHODS)}, not {kind!r}",
                         key="kind")
    return kind


def _deviation_sums(kind: str, x, bad, angle: bool, ms, all_requested: bool,
                    rtol_all: float | None):
    """(ms, sums of squares, terms, effective lengths (gaps) or None, gap samples) of the
    estimator at every m: over the gaps, by the O(N log² N) expansion for every m, or
    directly."""
    n = x.size
    p_last = {"adev": 2, "totdev": 2, "hdev": 3, "mdev": 3}[kind]
    if bad is not None:
        n_gaps = int(bad.sum()) if angle else int(bad[-1])
        if kind == "totdev":
            raise GonioError("total deviation needs a gap-free record "
                             f"({n_gaps} NaN samples)", key="data")
        sums, n_terms = _gap_sums(kind, x, bad, angle, ms)
        keep = n_terms > 0
        if not keep.any():
            raise GonioError("no valid terms at any τ: gaps too dense", key="data")
        ms, sums, n_terms = ms[keep], sums[keep], n_terms[keep]
        return ms, sums, n_terms, n_terms + (p_last * ms if kind != "mdev" else 3 * ms - 1), \
            n_gaps
    if kind == "totdev":
        if all_requested and n > 20_000:
            raise GonioError("total deviation with 'all' τ costs O(N) per τ; use "
                             "'octave' or 'decade:N' for records over 20000 points",
                             key="taus")
        return ms, _totdev_sums(x, ms), np.full(ms.size, n - 2, dtype=np.int64), None, 0
    if all_requested and ms.size > 64 and kind == "mdev":
        sums = _mdev_local_sums(x, ms, 1e-9 if rtol_all is None else rtol_all)
    elif all_requested and ms.size > 64:
        sums = _expanded_sums(kind, x, ms, 1e-6 if rtol_all is None else rtol_all)
    else:
        sums = _direct_sums(kind, x, ms)
    return ms, sums, n - p_last * ms + (1 if kind == "mdev" else 0), None, 0


def _deviation_and_interval(kind: str, ms, sums, n_terms, n_eff, alpha_arr, tau0_s: float,
                            factor: float, n: int, confidence: float, *, compact: bool):
    """(τ, deviation, m, terms, edf, CI low, CI high): the sums normalised into the
    deviation in place, chunk by chunk (bounded temporaries for "all"), with Greenhall's
    edf and the χ² interval; a large result stored compactly (see AllanResult)."""
    n_terms = np.asarray(n_terms)
    if compact:
        ms = ms.astype(np.int32)
        n_terms = n_terms.astype(np.int32)
    ftype = np.float32 if compact else np.float64
    nt = ms.size
    tau = ms * tau0_s
    dev = sums  # overwritten chunk by chunk with the deviation
    edf = np.empty(nt, dtype=ftype)
    lo = np.empty(nt, dtype=ftype)
    hi = np.empty(nt, dtype=ftype)
    step = 1 << 14  # τ per chunk: bounded temporaries for "all"
    for c0 in range(0, nt, step):
        sl = slice(c0, c0 + step)
        mf = ms[sl].astype(np.float64)
        den = _NORM[kind] * tau[sl] ** 2 * n_terms[sl]
        if kind == "mdev":
            den *= mf ** 2
        var = dev[sl] / den
        np.maximum(var, 0.0, out=var)
        var *= factor ** 2
        if n_eff is None:
            e = edf_for(kind, n, ms[sl], alpha_arr[sl])
        else:
            e = np.array([edf_for(kind, int(ne), [mm], [a])[0]
                          for ne, mm, a in zip(n_eff[sl], ms[sl], alpha_arr[sl])])
        lo_c, hi_c = chi2_interval(var, e, confidence)
        edf[sl] = e
        lo[sl] = np.sqrt(lo_c)
        hi[sl] = np.sqrt(hi_c)
        dev[sl] = np.sqrt(var)
        del var, e, lo_c, hi_c, den, mf
    return tau, dev, ms, n_terms, edf, lo, hi


def modified_allan_deviation(data, tau0_s: float, input_type: str, taus="octave",
                             **kwargs) -> AllanResult:
    """:func:`allan_deviation` with ``kind="mdev"`` (SP 1065 eq. 14)."""
    return allan_deviation(data, tau0_s, input_type, taus, kind="mdev", **kwargs)


def hadamard_deviation(data, tau0_s: float, input_type: str, taus="octave",
                       **kwargs) -> AllanResult:
    """:func:`allan_deviation` with ``kind="hdev"``: the overlapping Hadamard
    deviation (SP 1065 eq. 20), insensitive to a rate ramp."""
    return allan_deviation(data, tau0_s, input_type, taus, kind="hdev", **kwargs)


def total_deviation(data, tau0_s: float, input_type: str, taus="octave",
                    **kwargs) -> AllanResult:
    """:func:`allan_deviation` with ``kind="totdev"`` (SP 1065 eq. 25)."""
    return allan_deviation(data, tau0_s, input_type, taus, kind="totdev", **kwargs)
