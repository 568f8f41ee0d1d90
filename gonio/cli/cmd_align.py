"""``gonio align``: electrical alignment of a gyro triad from a triad readings file.

A thin layer over :func:`gonio.specs.triad_alignment.analysis.estimate_alignment` (format:
docs/formats-triad.md; method: docs/alignment.md).
"""

from __future__ import annotations

import json

import numpy as np

from gonio.cli.checks import int_range, seed
from gonio.errors import GonioError


def register(sub) -> None:
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
    p.set_defaults(func=run)


def _fmt_matrix(m, u, digits=6) -> list[str]:
    return ["  ".join(f"{m[i][j]: .{digits}g} ± {u[i][j]:.2g}" for j in range(3)) for i in range(3)]


def run(args) -> int:
    from gonio.specs.triad_alignment.analysis import cross_axis_table, estimate_alignment
    from gonio.formats.triad import json_safe, read_triad_readings

    if args.monte_carlo < 0:
        raise GonioError(f"--monte-carlo must be ≥ 0, got {args.monte_carlo}")
    if not 0 < args.target_deg < 90:
        raise GonioError(f"--target-deg must be in (0, 90), got {args.target_deg}")
    from gonio.atomic import check_output_files
    from gonio.formats.triad import named_inputs
    from gonio.limits import check
    from gonio.specs.triad_alignment.calibration import consistency_check

    check("GONIO_MAX_MONTE_CARLO", args.monte_carlo, "--monte-carlo", unit="trials")
    from gonio.report.figure_files import FIGURE_FORMATS

    check_output_files({"--plot": args.plot, "--report": args.report},
                       formats={"--plot": FIGURE_FORMATS},
                       inputs=[args.readings, *named_inputs(args.readings)])
    r = read_triad_readings(args.readings)
    res = estimate_alignment(r, robust=args.robust, monte_carlo=args.monte_carlo,
                             seed=args.seed, target_deg=args.target_deg)
    if not args.robust:
        consistency_check(res, r)              # the check calibrate makes, the same function
    if args.plot or args.report:
        from gonio.report.figure_files import save_figure
        from gonio.specs.triad_alignment.figures import alignment_figure

        fig = alignment_figure(res)
        if args.plot:
            save_figure(fig, args.plot)
        if args.report:
            from gonio.specs.triad_alignment.pages import alignment_page, write_report

            write_report(args.report, [alignment_page(res, fig)],
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
