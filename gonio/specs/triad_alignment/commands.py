"""The triad's ``gonio`` sub-commands (``Specification.commands``; gonio's command line
registers them through the registry, :func:`gonio.specs.commands`).

``gonio align``: electrical alignment of a gyro triad from a triad readings file, a thin
layer over :func:`gonio.specs.triad_alignment.analysis.estimate_alignment` (format:
docs/formats-triad.md; method: docs/alignment.md). ``gonio thermal-model``: identify
K(ϑ, U), b(ϑ, U) and ARW(ϑ) from a triad thermal readings file (docs/thermal-model.md), a
thin layer over :func:`gonio.specs.triad_alignment.thermal_model.identify_thermal_model`.
Its own ``gonio calibrate`` options (``--thermal``, ``--robust``): :func:`add_calibrate_options`
(``SPEC.arguments["calibrate"]``); its ``gonio validate`` option (``--cases``):
:func:`add_validate_options`.

This module sits on the command line's layer (it imports ``gonio.cli.checks``); nothing
imports it but the command line, when it builds its parser.
"""

from __future__ import annotations

import json

from gonio.cli.checks import int_range, seed
from gonio.errors import GonioError


def add_calibrate_options(group) -> None:
    """The triad's own ``gonio calibrate`` options (``SPEC.arguments["calibrate"]``): the
    thermal-programme readings and the robust fit."""
    group.add_argument("--thermal", default=None, metavar="FILE",
                       help="the thermal-programme readings (default: the file the readings' "
                            "'# thermal_readings:' metadata names, or their own thermal rows)")
    group.add_argument("--robust", action="store_true",
                       help="robust alignment fit (IRLS), outlying dwells down-weighted and "
                            "listed")


def add_validate_options(group) -> None:
    """The triad's own ``gonio validate`` option (``SPEC.arguments["validate"]``): the cases
    of its study (:data:`gonio.specs.triad_alignment.study.CASES`: ``typeb``, ``worst``)."""
    group.add_argument("--cases", default=None,
                       help="comma-separated cases, or 'all' (an unknown case is refused "
                            "naming the known ones)")


def add_align(sub) -> None:
    """Add ``gonio align`` to the sub-parsers ``sub``."""
    p = sub.add_parser("align", help="electrical alignment of a gyro triad (M, bias, M⁻¹)",
                       description="Estimate the 3×3 system matrix M and the bias vector of a "
                                   "gyro triad from ± rates about each axis and static "
                                   "positions (Earth rate in every orientation), with GUM and "
                                   "Monte Carlo uncertainties, the alignment matrix M⁻¹, the "
                                   "residual leakage and the averaging time from the Allan "
                                   "deviation.")
    p.add_argument("readings", metavar="READINGS", help="triad readings CSV")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--plot", metavar="FILE", default=None,
                   help="write the cross-axis / Allan figure (png, pdf, svg)")
    p.add_argument("--report", metavar="FILE", default=None,
                   help="write the alignment-matrix page (self-contained HTML)")
    p.add_argument("--robust", action="store_true",
                   help="iteratively reweighted least squares (Tukey bisquare): outlying "
                        "dwells are down-weighted and listed")
    p.add_argument("--monte-carlo", type=int_range(0), default=2000, metavar="N",
                   help="Monte Carlo trials for the uncertainties (0: GUM only; default 2000)")
    p.add_argument("--seed", type=seed, default=0, help="Monte Carlo seed")
    p.add_argument("--target-deg", type=float, default=0.1,
                   help="alignment target ψ_T for the averaging time (default 0.1°)")
    p.set_defaults(func=run_align)


def _fmt_matrix(m, u, digits=6) -> list[str]:
    return ["  ".join(f"{m[i][j]: .{digits}g} ± {u[i][j]:.2g}" for j in range(3)) for i in range(3)]


def screened(path):
    """The triad readings at ``path``, screened as calibrate screens them: a refused finding
    raises (the line named), the rows set aside are dropped and each is said on stderr."""
    import sys

    from gonio.specs.triad_alignment.calibration import without_set_aside
    from gonio.specs.triad_alignment.readings import read_triad_readings
    from gonio.specs.triad_alignment.screen import check

    r = read_triad_readings(path)
    found = check(r)
    for f in found:
        if f.action == "set_aside":
            print(f"set aside: {f.location()}: {f.message}", file=sys.stderr)
    return without_set_aside(r, found)


def run_align(args) -> int:
    """``gonio align``: the alignment estimate printed (or ``--json``), with the optional
    figure (``--plot``) and page (``--report``); exit code 0."""
    import numpy as np

    from gonio.specs.triad_alignment.analysis import cross_axis_table
    from gonio.formats.jsonsafe import json_safe

    if args.monte_carlo < 0:
        raise GonioError(f"--monte-carlo must be ≥ 0, got {args.monte_carlo}")
    if not 0 < args.target_deg < 90:
        raise GonioError(f"--target-deg must be in (0, 90), got {args.target_deg}")
    from gonio.atomic import check_output_files
    from gonio.specs.triad_alignment.readings import named_inputs
    from gonio.limits import check
    from gonio.specs.triad_alignment.calibration import consistency_check, fit_alignment

    check("GONIO_MAX_MONTE_CARLO", args.monte_carlo, "--monte-carlo", unit="trials")
    from gonio.report.figure_files import FIGURE_FORMATS

    check_output_files({"--plot": args.plot, "--report": args.report},
                       formats={"--plot": FIGURE_FORMATS},
                       inputs=[args.readings, *named_inputs(args.readings)])
    r = screened(args.readings)
    res = fit_alignment(r, robust=args.robust, monte_carlo=args.monte_carlo,
                        seed=args.seed, target_deg=args.target_deg)   # calibrate's call
    if not args.robust:
        consistency_check(res, r)              # the check calibrate makes, the same function
    if args.plot or args.report:
        from gonio.report.figure_files import save_figure
        from gonio.specs.triad_alignment.figures import alignment_figure

        fig = alignment_figure(res)
        if args.plot:
            save_figure(fig, args.plot)
        if args.report:
            from gonio.specs.triad_alignment.calibration import static_record_s
            from gonio.specs.triad_alignment.pages import alignment_page, write_report

            write_report(args.report, [alignment_page(res, fig, static_record_s(r))],
                         f"Gyro-triad alignment — {r.metadata.get('instrument', '')} "
                         f"{r.metadata.get('serial', '')}".strip())
    if args.json:
        print(json.dumps(json_safe(res.to_json()), indent=2, sort_keys=True, allow_nan=False,
                         ensure_ascii=False))
        return 0
    unit = res.output_unit or "output"
    print(f"system matrix M ({unit} per °/s), standard uncertainties (GUM):")
    for line in _fmt_matrix(res.system_matrix, res.u_system_matrix):
        print("  " + line)
    print(f"bias ({unit}): " + "  ".join(f"{b:.6g} ± {u:.2g}" for b, u in
                                        zip(res.bias_output, res.u_bias_output)))
    print("alignment matrix M⁻¹ (°/s per unit):")
    a = res.alignment_matrix
    ua = np.asarray(res.u_derived["alignment_matrix"]).reshape(3, 3)
    for line in _fmt_matrix(a, ua):
        print("  " + line)
    print("cross-axis sensitivity S_ij = M_ij/M_ii (IEC 62047-20 5.2), with GUM / MC u:")
    for row in cross_axis_table(res).itertuples(index=False):
        print(f"  gyro {row.gyro} about {row.about}: {row.sensitivity: .3e}  u {row.u_gum:.2e}"
              f" / {row.u_mc:.2e}")
    print("residual leakage after alignment, standard uncertainty (max): "
          f"{np.max(res.leakage_u[~np.eye(3, dtype=bool)]):.2e}")
    if res.averaging is not None:
        av = res.averaging
        print(f"averaging time: noise limit {av.noise_limit_dps:.4g} °/s at {av.test_rate_dps:g} °/s "
              f"and ψ_T = {av.target_deg:g}°: τ ≥ {max(av.tau_needed_s):g} s; shortest dwell "
              f"{av.shortest_dwell_s:g} s ({'sufficient' if av.sufficient else 'NOT sufficient'})")
    if res.robust:
        print(f"outliers (weight < 0.5): {len(res.outliers)}")
        for o in res.outliers:
            print(f"  line {o['line']} {o['channel']}: weight {o['weight']:.3f}")
    return 0


def add_thermal_model(sub) -> None:
    """Add ``gonio thermal-model`` to the sub-parsers ``sub``."""
    p = sub.add_parser("thermal-model",
                       help="identify the extended temperature / supply model of a MEMS gyro",
                       description="Fit K(ϑ, U), b(ϑ, U) and ARW(ϑ) polynomials with orders "
                                   "chosen by a criterion, their uncertainties, the error of the "
                                   "static-soak model on ramps and its remedies; optionally "
                                   "compensate a second record.")
    p.add_argument("readings", metavar="READINGS", help="triad readings CSV with thermal rows")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--plot", metavar="FILE", default=None, help="write the figure (png, pdf, svg)")
    p.add_argument("--report", metavar="FILE", default=None,
                   help="write the temperature-model page (self-contained HTML)")
    p.add_argument("--criterion", choices=("bic", "aic", "ftest"), default="bic",
                   help="order-selection criterion (default bic)")
    p.add_argument("--temperature", choices=("sensor", "chamber"), default="sensor",
                   help="temperature the model uses (default: the gyro's internal sensor)")
    p.add_argument("--gyro", choices=("x", "y", "z"), default=None,
                   help="the gyro --plot draws when the file exercises several")
    p.add_argument("--compensate", metavar="READINGS2", default=None,
                   help="apply the model to this second thermal record: before/after residuals")
    p.set_defaults(func=run_thermal_model)


def run_thermal_model(args) -> int:
    """``gonio thermal-model``: the model printed (or ``--json``), with the optional figure
    (``--plot``), page (``--report``) and compensation of a second record; exit code 0."""
    from gonio.specs.triad_alignment.thermal_model import compensate_record, identify_thermal_model
    from gonio.atomic import check_output_files
    from gonio.formats.jsonsafe import json_safe
    from gonio.specs.triad_alignment.readings import named_inputs, read_triad_readings

    inputs = [args.readings, args.compensate]
    from gonio.report.figure_files import FIGURE_FORMATS

    check_output_files({"--plot": args.plot, "--report": args.report},
                       formats={"--plot": FIGURE_FORMATS},
                       inputs=inputs + [q for i in inputs if i for q in named_inputs(i)])

    r = screened(args.readings)
    res = identify_thermal_model(r, criterion=args.criterion, temperature=args.temperature)
    comp = {}
    if args.compensate:
        r2 = read_triad_readings(args.compensate)
        comp = {ch: compensate_record(m, r2) for ch, m in res.channels.items()}
    if args.plot:
        from gonio.report.figure_files import save_figure
        from gonio.specs.triad_alignment.figures import thermal_figure

        ch = args.gyro
        if ch is None:
            if len(res.channels) != 1:
                raise GonioError("--plot draws one gyro; the file has "
                                 f"{', '.join(res.channels)}: choose with --gyro", key="--plot")
            ch = next(iter(res.channels))
        if ch not in res.channels:
            raise GonioError(f"gyro {ch} is not in the file (it has {', '.join(res.channels)})",
                             key="--gyro")
        save_figure(thermal_figure(res.channels[ch], comp.get(ch)), args.plot)
    if args.report:
        from gonio.specs.triad_alignment.figures import thermal_figure
        from gonio.specs.triad_alignment.pages import thermal_page, write_report

        figs = {ch: thermal_figure(m, comp.get(ch)) for ch, m in res.channels.items()}
        write_report(args.report, [thermal_page(res, comp, figs)],
                     f"Temperature model — {r.metadata.get('instrument', '')} "
                     f"{r.metadata.get('serial', '')}".strip())
    if args.json:
        out = res.to_json()
        out["compensation"] = {k: v.to_json() for k, v in comp.items()} or None
        print(json.dumps(json_safe(out), indent=2, sort_keys=True, allow_nan=False,
                         ensure_ascii=False))
        return 0
    for ch, m in res.channels.items():
        print(f"gyro {ch} (temperature: {m.temperature}, ϑ {m.theta_range[0]:.1f} … "
              f"{m.theta_range[1]:.1f} °C, criterion {res.criterion}):")
        for name, f in (("K", m.scale), ("b (°/s)", m.bias), ("ARW (°/√h)", m.arw)):
            if f is None:
                continue
            c = f.coefficients()
            terms = "  ".join(f"{k}={v:.4g}" for k, v in c.items() if not k.startswith("u_"))
            print(f"  {name}: order ϑ {f.n_t}, U {f.n_u}; {terms}; s = {f.s:.3g}")
        if m.ramp is not None:
            ra = m.ramp
            print(f"  ramps: static-soak model rms error {ra.rms_static_model_dps:.3g} °/s; "
                  f"with γ·dϑ/dt (γ = {ra.gamma_dps_per_c_per_s:.3g} (°/s)/(°C/s)) "
                  f"{ra.rms_with_ramp_term_dps:.3g}; with a lag ({ra.lag_text()}) "
                  f"{ra.rms_with_lag_dps:.3g}; hysteresis {ra.hysteresis_dps:.3g} °/s")
        if ch in comp:
            c = comp[ch]
            print(f"  compensation: bias rms {c.rms_bias_before_dps:.3g} → {c.rms_bias_after_dps:.3g}"
                  f" °/s; scale-factor rms {c.rms_scale_before_rel:.3g} → "
                  f"{c.rms_scale_after_rel:.3g}; ramps {c.rms_ramp_before_dps:.3g} → "
                  f"{c.rms_ramp_after_dps:.3g} °/s")
    return 0
