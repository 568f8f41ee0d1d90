"""``gonio thermal-model``: identify K(ϑ, U), b(ϑ, U) and ARW(ϑ) from a triad thermal
readings file (docs/thermal-model.md); a thin layer over
:func:`gonio.specs.triad_alignment.thermal_model.identify_thermal_model`."""

from __future__ import annotations

import json

from gonio.errors import GonioError


def register(sub) -> None:
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
    p.set_defaults(func=run)


def run(args) -> int:
    from gonio.specs.triad_alignment.thermal_model import compensate_record, identify_thermal_model
    from gonio.atomic import check_output_files
    from gonio.formats.triad import json_safe, named_inputs, read_triad_readings

    inputs = [args.readings, args.compensate]
    from gonio.report.figure_files import FIGURE_FORMATS

    check_output_files({"--plot": args.plot, "--report": args.report},
                       formats={"--plot": FIGURE_FORMATS},
                       inputs=inputs + [q for i in inputs if i for q in named_inputs(i)])

    r = read_triad_readings(args.readings)
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
                  f"{ra.rms_with_ramp_term_dps:.3g}; with a lag τ = {ra.tau_s:.0f} s "
                  f"{ra.rms_with_lag_dps:.3g}; hysteresis {ra.hysteresis_dps:.3g} °/s")
        if ch in comp:
            c = comp[ch]
            print(f"  compensation: bias rms {c.rms_bias_before_dps:.3g} → {c.rms_bias_after_dps:.3g}"
                  f" °/s; scale-factor rms {c.rms_scale_before_rel:.3g} → "
                  f"{c.rms_scale_after_rel:.3g}; ramps {c.rms_ramp_before_dps:.3g} → "
                  f"{c.rms_ramp_after_dps:.3g} °/s")
    return 0
