"""``gonio noise``: Allan-family deviation and noise-model fit of a stream's static part.

A thin layer over :func:`stream_noise` (IEEE 952-1997 Annex C; NIST SP 1065). The
stream is read with :func:`gonio.formats.streams.read_stream`
(``docs/formats.md#stream-file``); its metadata with the readers' public
:func:`gonio.formats.metadata.metadata_float`. The ``gyro_counts`` column is interpreted
according to ``--input``:

* ``angle`` (default): the cumulative pulse counter (unwrapped), i.e. the integrated
  angle; angle = counts / scale factor;
* ``counts``: counts per sample (the counter read and reset at each sample), i.e.
  angle increments;
* ``rate``: the mean count rate over each sample interval, counts/s (a frequency
  output); rate = counts/s / scale factor.

Only a static record is analysed: the table's rests (the reducer's rest finder, on
``table_deg`` or, without it, on the gyro rate) — the longest by default, or each
with ``--each-window`` — or the interval given with ``--window START:END`` (s),
which is refused when the table moves inside it. A readings file is refused (the
noise analysis needs the sampled stream). Results are in °/h and the customary
units of the noise terms (°/√h, °/h, (°/h)/√h, ″).
"""

from __future__ import annotations

import json
import math

from gonio.errors import GonioError
from gonio.units import S_PER_H
from gonio.cli.checks import (float_range, int_range, json_safe, positive_magnitude,
                               seed as seed_type)

_INPUTS = {"angle": "angle", "counts": "increment", "rate": "rate"}
_KINDS = ("adev", "mdev", "hdev", "totdev")


def tau_set(text: str) -> str:
    """``octave``, ``all`` or ``decade:N`` with an integer N in [1, 100] (a bigger N would
    ask for more τ values than any record has)."""
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


def register(subparsers) -> None:
    """Add the ``noise`` sub-command."""
    p = subparsers.add_parser(
        "noise", help="Allan deviation and five-term noise fit of a stream's static part",
        description="Overlapping/modified Allan, Hadamard or total deviation of the "
                    "table's longest rest (or --window), chi-squared intervals with "
                    "Greenhall's edf, the five-term fit (Q, N, B, K, R; IEEE 952 Annex C) "
                    "with that variance's own model, and a sinusoid check.")
    p.add_argument("stream", metavar="STREAM", help="stream CSV (time_s,gyro_counts,...)")
    p.add_argument("--input", choices=sorted(_INPUTS), default="angle",
                   help="meaning of gyro_counts: angle = cumulative counter (default), "
                        "counts = counts per sample, rate = counts per second")
    p.add_argument("--taus", default="octave", metavar="SET", type=tau_set,
                   help="tau set: octave (default), decade:N or all")
    p.add_argument("--kind", choices=_KINDS, default=None,
                   help="estimator: adev (overlapping Allan, default), mdev, hdev, totdev")
    p.add_argument("--modified", action="store_true", help="same as --kind mdev")
    p.add_argument("--window", default=None, metavar="START:END",
                   help="analyse this interval (s) only; refused if the table moves in it")
    p.add_argument("--each-window", action="store_true",
                   help="analyse every rest found, not only the longest")
    p.add_argument("--bootstrap", type=int_range(0, 10_000), default=0, metavar="B",
                   help="parameter uncertainties by a parametric bootstrap of B records "
                        "(e.g. 20; its time and memory grow with the window: "
                        "B records of its length); default 0: the weighted "
                        "least-squares covariance, conservative (1.4-1.8x too wide)")
    p.add_argument("--seed", type=seed_type, default=0, help="seed of the bootstrap")
    p.add_argument("--scale-factor", type=positive_magnitude, default=None, metavar="K",
                   help="counts per degree (default: metadata "
                        "nominal_scale_factor_counts_per_deg)")
    p.add_argument("--confidence", type=float_range(0, 1, lo_open=True, hi_open=True), default=0.683,
                   help="level of the chi-squared intervals (default 0.683)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--plot", metavar="FILE", default=None,
                   help="write deviation, model and residual plot to FILE (png, pdf, svg)")
    p.set_defaults(func=run)


class _Counted:
    """A sample source whose block-by-block pass advances a progress counter."""

    def __init__(self, src, prog):
        self._src, self._prog = src, prog

    def __getattr__(self, name):
        return getattr(self._src, name)

    def __len__(self) -> int:
        return len(self._src)

    def chunks(self, *args, **kwargs):
        for ch in self._src.chunks(*args, **kwargs):
            if self._prog is not None:
                self._prog.update(ch.time_s.size)
            yield ch


def stream_noise(path, input_kind: str = "angle", *, taus="octave", modified: bool = False,
                 kind: str | None = None, scale_factor: float | None = None,
                 confidence: float = 0.683, window=None, each_window: bool = False,
                 bootstrap: int = 0, seed: int = 0, show_progress: bool = True) -> list:
    """Noise analysis of the static part of a stream file, in bounded memory.

    Returns a list of :class:`gonio.analysis.noise.StaticNoiseResult` — one (the
    longest rest, or ``window``) unless ``each_window``; each carries the window it
    used. ``input_kind`` is ``angle``, ``counts`` or ``rate`` (module docstring); the
    deviation is in °/h. Raises GonioError (one line) for a readings file, a stream
    without a usable scale factor, non-uniform sampling, or a window with motion.

    Memory: the file is read once in blocks to find the rests, then only the
    analysed window's counts, piece by piece, into one array (memory-mapped beyond
    :data:`gonio.analysis.noise.record.MEMMAP_SAMPLES` samples) analysed in place; the
    numbers are those of the whole stream read into memory (tests/test_noise_memory.py).
    The parameters' uncertainties are the fit's covariance unless ``bootstrap`` > 0 asks
    for the parametric bootstrap (B records of the window's length, each synthesised
    whole: its memory and time grow with the window, see the README's noise section).
    Progress on a terminal (``show_progress``), quiet otherwise.
    """
    import tempfile

    from gonio.analysis.noise import analyse_record
    from gonio.analysis.noise.record import source_windows, window_record
    from gonio.formats.streams import StreamFile, sniff_kind
    from gonio.progress import Progress, status

    if input_kind not in _INPUTS:
        raise GonioError(f"--input must be one of {', '.join(sorted(_INPUTS))}", key="input")
    if sniff_kind(path) != "stream":
        raise GonioError("this is a readings file; the noise analysis needs the sampled "
                         "stream (time_s,gyro_counts,...)", file=path)
    src = StreamFile(path)
    if scale_factor is None:
        scale_factor = src.k_nominal
        if scale_factor is None:
            raise GonioError("no scale factor: give --scale-factor or the metadata key",
                             file=path, key="nominal_scale_factor_counts_per_deg")
    if not (math.isfinite(scale_factor) and scale_factor > 0):
        raise GonioError(f"scale factor must be > 0, got {scale_factor}", file=path,
                         key="nominal_scale_factor_counts_per_deg")
    show = (lambda m: status(m)) if show_progress else (lambda m: None)
    prog = Progress(None, label="noise: reading the stream, finding rests", unit="samples",
                    force=False) if show_progress else None
    try:
        wins = source_windows(_Counted(src, prog), scale_factor_counts_per_deg=scale_factor,
                              window=window)
    except GonioError as exc:
        if exc.file is not None:        # the stream reader's own (line, column) errors
            raise
        raise GonioError(exc.message, file=path, key="window") from None
    finally:
        if prog is not None:
            prog.close()
    if len(src) < 8:
        raise GonioError(f"need at least 8 samples, got {len(src)}", file=path)
    if not wins:
        raise GonioError("the table never rests long enough for a noise analysis "
                         "(give --window START:END)", file=path, key="window")
    wins = sorted(wins, key=lambda w: (-w.duration_s, w.i_start))
    chosen = wins if each_window else wins[:1]
    kind_in = _INPUTS[input_kind]
    out = []
    for w in chosen:
        with tempfile.TemporaryDirectory(prefix="gonio-noise-") as tmp:
            prog = Progress(w.i_end - w.i_start + 1, label="noise: reading the window",
                            unit="samples", force=False) if show_progress else None
            try:
                if kind_in == "rate":
                    # counts/s / (counts/°) · 3600 s/h -> °/h
                    data, tau0 = window_record(src, w, scale=S_PER_H / scale_factor,
                                               tmpdir=tmp, progress=prog)
                    scale = 1.0
                else:
                    # counts / (counts/°) = °, and 1° = 3600 (°/h)·s
                    data, tau0 = window_record(src, w, tmpdir=tmp, progress=prog)
                    scale = scale_factor / S_PER_H
            except GonioError as exc:
                raise GonioError(exc.message, file=path, column=exc.column) from None
            finally:
                if prog is not None:
                    prog.close()
            show(f"noise: {kind or ('mdev' if modified else 'adev')} and fit of "
                 f"{data.size} samples" + (f", bootstrap of {bootstrap}" if bootstrap else ""))
            res = analyse_record(data, tau0, kind_in, scale=scale, unit="deg/h", taus=taus,
                                 modified=modified, kind=kind, confidence=confidence,
                                 bootstrap=bootstrap, seed=seed, overwrite_data=True)
            del data
            show("")
        res.window = w
        res.windows_found = len(wins)
        out.append(res)
    return out


def _fmt(v, spec):
    return "n/a" if v is None else format(v, spec)


def _table(result) -> str:
    a, f, s, w = result.allan, result.fit, result.sinusoid, result.window
    lines = []
    if w is not None:
        lines.append(f"window {w.t_start_s:g} to {w.t_end_s:g} s ({w.duration_s:g} s, "
                     f"{'the longest of ' + str(result.windows_found) + ' rests' if w.source == 'rest' else 'from --window'})")
    lines += [f"{a.method} deviation, input {a.input_type}, tau0 {a.tau0_s:g} s, "
              f"{a.n_samples} samples, {a.confidence:.3g} chi-squared intervals "
              "(Greenhall edf)",
              f"{'tau_s':>12} {'dev_dph':>12} {'ci_low':>12} {'ci_high':>12} {'edf':>10} "
              f"{'alpha':>5} {'terms':>9}"]
    for row in zip(a.tau_s, a.adev, a.ci_low, a.ci_high, a.edf, a.alpha, a.n_pairs):
        lines.append(" ".join(f"{v:12.6g}" for v in row[:4])
                     + f" {row[4]:10.4g} {int(row[5]):5d} {int(row[6]):9d}")
    d = f.to_dict()
    u_note = (f"bootstrap of {f.n_bootstrap}" if f.uncertainty_method == "bootstrap"
              else "LS covariance, tau taken as independent")
    lines += [f"noise model fitted to the {a.method} variance (IEEE 952 Annex C; "
              f"u: {u_note}):",
              f"  quantisation Q      {_fmt(d['quantisation_arcsec'], '.4g')} arcsec",
              f"  angle random walk N {_fmt(d['arw_deg_sqrt_h'], '.4g')} ± "
              f"{_fmt(d['u_arw_deg_sqrt_h'], '.2g')} deg/sqrt(h)",
              f"  bias instability B  {_fmt(d['bias_instability_dph'], '.4g')} ± "
              f"{_fmt(d['u_bias_instability_dph'], '.2g')} deg/h",
              f"  rate random walk K  {_fmt(d['rrw_dph_sqrt_h'], '.4g')} ± "
              f"{_fmt(d['u_rrw_dph_sqrt_h'], '.2g')} deg/h/sqrt(h)",
              f"  rate ramp R         {_fmt(d['rate_ramp_dph_per_h'], '.4g')} ± "
              f"{_fmt(d['u_rate_ramp_dph_per_h'], '.2g')} deg/h/h"
              + ("  (not seen by the Hadamard variance)" if a.method == "hadamard" else ""),
              f"  reduced chi2        {f.chi2_red:.3g}"]
    if a.method == "overlapping":
        lines.append(f"  ADEV floor/0.6643   {d['bias_instability_floor_dph']:.4g} deg/h "
                     f"at {f.tau_floor_s:g} s")
    if s.detected:
        lines.append(f"sinusoid: period {s.period_s:.4g} s, amplitude {s.amplitude:.4g} deg/h "
                     f"(ADEV peak at {s.tau_peak_s:.4g} s)")
    else:
        lines.append("sinusoid: none detected")
    return "\n".join(lines)


def run(args) -> int:
    """Run ``gonio noise``; prints a table or JSON, optionally writes the plot."""
    from gonio.atomic import check_output_files
    from gonio.errors import check_input_file
    from gonio.report.noise_figures import write_noise_figure

    check_input_file(args.stream, "stream file")
    if args.plot is not None:
        from gonio.report.figure_files import FIGURE_FORMATS

        check_output_files({"--plot": args.plot}, inputs=[args.stream],
                           formats={"--plot": FIGURE_FORMATS})

    results = stream_noise(args.stream, args.input, taus=args.taus, modified=args.modified,
                           kind=args.kind, scale_factor=args.scale_factor,
                           confidence=args.confidence, window=args.window,
                           each_window=args.each_window, bootstrap=args.bootstrap,
                           seed=args.seed)
    if args.plot:
        write_noise_figure(args.plot, results[0].allan, results[0].fit)
    if args.json:
        body = [r.to_dict() for r in results]
        out = {"stream": str(args.stream), "input": args.input,
               **(body[0] if len(body) == 1 else {"windows": body})}
        print(json.dumps(json_safe(out), indent=2, allow_nan=False))
    else:
        print("\n\n".join(_table(r) for r in results))
    return 0
