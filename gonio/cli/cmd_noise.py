"""``gonio noise``: Allan deviation and noise-model fit of a stream file.

A thin layer over :func:`gonio.analysis.noise.analyse_record` (IEEE 952-1997 Annex C). The
stream is read with :func:`gonio.formats.streams.read_stream` (``docs/formats.md#stream-file``); its
``gyro_counts`` column is interpreted according to ``--input``:

* ``angle`` (default): the cumulative pulse counter (unwrapped), i.e. the integrated
  angle; angle = counts / scale factor;
* ``counts``: counts per sample (the counter read and reset at each sample), i.e.
  angle increments;
* ``rate``: the mean count rate over each sample interval, counts/s (a frequency
  output); rate = counts/s / scale factor.

The scale factor is ``--scale-factor`` or the metadata key
``nominal_scale_factor_counts_per_deg``. The sample interval is the mean time step;
non-uniform sampling (a step off by > 1 %) is rejected. Results are in °/h (ADEV)
and the customary units of the noise terms (°/√h, °/h, (°/h)/√h, ″).
"""

from __future__ import annotations

import json
import math

import numpy as np

from gonio.errors import GonioError
from gonio.cli.checks import float_range, json_safe
from gonio.units import dph_to_dps, dps_to_dph

_INPUTS = {"angle": "angle", "counts": "increment", "rate": "rate"}


def register(subparsers) -> None:
    """Add the ``noise`` sub-command."""
    p = subparsers.add_parser(
        "noise", help="Allan deviation and five-term noise fit of a stream file",
        description="Overlapping (or modified) Allan deviation with chi-squared intervals, "
                    "weighted non-negative fit of Q, N, B, K, R (IEEE 952 Annex C) and a "
                    "check for a sinusoidal disturbance.")
    p.add_argument("stream", metavar="STREAM", help="stream CSV (time_s,gyro_counts,...)")
    p.add_argument("--input", choices=sorted(_INPUTS), default="angle",
                   help="meaning of gyro_counts: angle = cumulative counter (default), "
                        "counts = counts per sample, rate = counts per second")
    p.add_argument("--taus", default="octave", metavar="SET", type=tau_set,
                   help="tau set: octave (default), decade:N or all")
    p.add_argument("--modified", action="store_true", help="modified Allan deviation")
    p.add_argument("--scale-factor", type=float_range(1e-6, 1e12), default=None, metavar="K",
                   help="counts per degree (default: metadata "
                        "nominal_scale_factor_counts_per_deg)")
    p.add_argument("--confidence", type=float_range(0, 1, lo_open=True, hi_open=True), default=0.683,
                   help="level of the chi-squared intervals (default 0.683)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--plot", metavar="FILE", default=None,
                   help="write ADEV, model and residual plot to FILE (png, pdf, svg)")
    p.set_defaults(func=run)


def tau_set(text: str) -> str:
    """``octave``, ``all`` or ``decade:N`` with an integer N in [1, 100]."""
    import argparse
    import re

    t = text.strip().lower()
    if t in ("octave", "all"):
        return t
    m = re.fullmatch(r"decade:([0-9]{1,3})", t)
    if m and 1 <= int(m.group(1)) <= 100:
        return t
    raise argparse.ArgumentTypeError(f"expected octave, all or decade:N with N in [1, 100], "
                                     f"got {text[:40]!r}")


#: Longest record the modified Allan deviation is computed for at every τ ("all", O(N²)).
MAX_ALL_MODIFIED_SAMPLES = 100_000


def stream_noise(path, input_kind: str = "angle", *, taus="octave", modified: bool = False,
                 scale_factor: float | None = None, confidence: float = 0.683):
    """Noise analysis of a stream file; returns a :class:`gonio.analysis.noise.StaticNoiseResult`.

    ``input_kind`` is ``angle``, ``counts`` or ``rate`` (see the module docstring);
    the Allan deviation is in °/h.
    """
    from gonio.analysis.noise import analyse_record
    from gonio.formats.streams import read_stream

    if input_kind not in _INPUTS:
        raise GonioError(f"--input must be one of {', '.join(sorted(_INPUTS))}", key="input")
    stream = read_stream(path)
    if scale_factor is None:
        text = stream.metadata.get("nominal_scale_factor_counts_per_deg")
        if text is None:
            raise GonioError("no scale factor: give --scale-factor or the metadata key",
                             file=path, key="nominal_scale_factor_counts_per_deg")
        try:
            scale_factor = float(text)
        except ValueError:
            raise GonioError(f"expected a number, got {text!r}", file=path,
                             key="nominal_scale_factor_counts_per_deg") from None
    if not (math.isfinite(scale_factor) and scale_factor > 0):
        raise GonioError(f"scale factor must be > 0, got {scale_factor}", file=path,
                         key="nominal_scale_factor_counts_per_deg")
    t = np.asarray(stream.time_s, dtype=np.float64)
    if t.size < 8:
        raise GonioError(f"need at least 8 samples, got {t.size}", file=path)
    dt = np.diff(t)
    tau0 = float((t[-1] - t[0]) / (t.size - 1))
    off = np.flatnonzero(np.abs(dt - tau0) > 0.01 * tau0)
    if off.size:
        raise GonioError("sampling is not uniform: time step differs from the mean "
                         f"{tau0:g} s by more than 1 % (sample {int(off[0]) + 2})",
                         file=path, column="time_s")
    if modified and isinstance(taus, str) and taus.strip().lower() == "all" \
            and t.size > MAX_ALL_MODIFIED_SAMPLES:
        raise GonioError(f"--taus all with --modified on {t.size} samples is O(N²) work (over "
                         f"{MAX_ALL_MODIFIED_SAMPLES} samples): use octave or decade:N",
                         file=path)
    counts = np.asarray(stream.gyro_counts, dtype=np.float64)
    kind = _INPUTS[input_kind]
    if kind == "rate":
        # counts/s / (counts/°) · 3600 s/h -> °/h
        return analyse_record(dps_to_dph(counts / scale_factor), tau0, "rate", unit="deg/h",
                              taus=taus, modified=modified, confidence=confidence)
    # counts / (counts/°) = °, and 1° = 3600 (°/h)·s: scale = counts per (°/h)·s
    return analyse_record(counts, tau0, kind, scale=dph_to_dps(scale_factor), unit="deg/h",
                          taus=taus, modified=modified, confidence=confidence)


def _table(result) -> str:
    a, f, s = result.allan, result.fit, result.sinusoid
    lines = [f"{a.method} Allan deviation, input {a.input_type}, tau0 {a.tau0_s:g} s, "
             f"{a.n_samples} samples, {a.confidence:.3g} chi-squared intervals",
             f"{'tau_s':>12} {'adev_dph':>12} {'ci_low':>12} {'ci_high':>12} {'edf':>10}"]
    for row in zip(a.tau_s, a.adev, a.ci_low, a.ci_high, a.edf):
        lines.append(" ".join(f"{v:12.6g}" if i < 4 else f"{v:10.4g}"
                              for i, v in enumerate(row)))
    d = f.to_dict()
    lines += ["noise model (weighted non-negative LS, IEEE 952 Annex C):",
              f"  quantisation Q      {d['quantisation_arcsec']:.4g} arcsec",
              f"  angle random walk N {d['arw_deg_sqrt_h']:.4g} ± {d['u_arw_deg_sqrt_h']:.2g} deg/sqrt(h)",
              f"  bias instability B  {d['bias_instability_dph']:.4g} ± "
              f"{d['u_bias_instability_dph']:.2g} deg/h "
              f"(floor/0.664: {d['bias_instability_floor_dph']:.4g} deg/h at {f.tau_floor_s:g} s)",
              f"  rate random walk K  {d['rrw_dph_sqrt_h']:.4g} ± {d['u_rrw_dph_sqrt_h']:.2g} deg/h/sqrt(h)",
              f"  rate ramp R         {d['rate_ramp_dph_per_h']:.4g} ± "
              f"{d['u_rate_ramp_dph_per_h']:.2g} deg/h/h",
              f"  reduced chi2        {f.chi2_red:.3g}"]
    if s.detected:
        lines.append(f"sinusoid: period {s.period_s:.4g} s, amplitude {s.amplitude:.4g} deg/h "
                     f"(ADEV peak at {s.tau_peak_s:.4g} s)")
    else:
        lines.append("sinusoid: none detected")
    return "\n".join(lines)


def run(args) -> int:
    """Run ``gonio noise``; prints a table or JSON, optionally writes the plot."""
    from gonio.atomic import check_output_file
    from gonio.errors import check_input_file

    check_input_file(args.stream, "stream file")
    if args.plot is not None:
        check_output_file(args.plot, what="--plot", inputs=[args.stream])
    from gonio.analysis.noise import plot_fit

    result = stream_noise(args.stream, args.input, taus=args.taus, modified=args.modified,
                          scale_factor=args.scale_factor, confidence=args.confidence)
    if args.plot:
        plot_fit(result.allan, result.fit, args.plot)
    if args.json:
        out = {"stream": str(args.stream), "input": args.input, **result.to_dict()}
        print(json.dumps(json_safe(out), indent=2, allow_nan=False))
    else:
        print(_table(result))
    return 0
