"""``gonio eda READINGS``: equal-division averaging of a readings file (IEC 62047-20 Annex A.3).

Reads the ``equal_division`` rows of a readings file (with the readings reader
and its checks), separates the table's positioning error from the goniometer's
error (:func:`gonio.analysis.equal_division.equal_division_from_readings`) and
prints both with their standard uncertainties, the residual standard deviation,
the full-turn closure check and the harmonic transfer table.
"""

from __future__ import annotations

import json

from gonio.cli.checks import int_range, json_safe


def register(subparsers) -> None:
    """Add the ``eda`` sub-command."""
    p = subparsers.add_parser(
        "eda", help="equal-division averaging: table and goniometer errors (IEC 62047-20 A.3)",
        description="Separate a rotary table's positioning error from the goniometer's own "
                    "error with equal-division averaging (IEC 62047-20 Annex A.3).")
    p.add_argument("readings", metavar="READINGS", help="readings CSV with equal_division rows")
    p.add_argument("--starts", type=int_range(1, 10000), default=None, metavar="N",
                   help="number of starts n (required when the file has no start_deg column; "
                        "checked against the file otherwise)")
    p.add_argument("--gauge", choices=("closure", "zero"), default="closure",
                   help="table-error convention: sum zero over the circle, or zero at 0°")
    p.add_argument("--noise", choices=("random_walk", "white"), default="random_walk",
                   help="reading-error model: random_walk (a gyro's angle random walk from each "
                        "zeroing, the default) or white (independent readings)")
    p.add_argument("--protocol", default="eda", metavar="PROTOCOL",
                   help="protocol with the [equal_division] section (rate and reading delay "
                        "for the coupling's timing; default: the built-in eda)")
    p.add_argument("--no-coupling", action="store_true",
                   help="do not estimate the tilt × Earth-rate coupling (plain IEC 62047-20 "
                        "A.3 fit)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--plot", metavar="FILE", default=None,
                   help="write a figure (PNG/PDF/SVG by suffix) of both error curves")
    p.set_defaults(func=run)


def _text(res) -> str:
    """The result (an :class:`~gonio.analysis.equal_division.EdaResult`) as text."""
    out = [f"equal-division averaging (IEC 62047-20 Annex A.3): n = {res.n_starts} starts, "
           f"m = {res.m_points} points ({res.step_deg:g}° step), {res.repeats} repeat(s)",
           f"residual std {res.residual_std_arcsec:.4f}″, dof {res.dof}, gauge {res.gauge}, "
           f"unobservable table dimensions {res.unobservable_dim}", "",
           f"{'position':>10} {'table err':>10} {'u':>8}   {'turned':>8} {'gonio err':>10} {'u':>8}"]
    for i in range(res.m_points):
        out.append(f"{res.table_position_deg[i]:9.4f}° {res.table_error_arcsec[i]:9.4f}″ "
                   f"{res.table_u_arcsec[i]:7.4f}″   {res.gonio_angle_deg[i]:7.3f}° "
                   f"{res.gonio_error_arcsec[i]:9.4f}″ {res.gonio_u_arcsec[i]:7.4f}″")
    c = res.closure
    out += ["", f"closure: sum of table errors {c.table_sum_arcsec:.4f}″; full-turn goniometer "
                f"error {c.full_turn_arcsec:.4f}″ ± {c.u_full_turn_arcsec:.4f}″ (z = {c.z:.2f}, "
                f"{'consistent with 0' if c.consistent else 'NOT consistent with 0'})"]
    cp = res.coupling
    if cp is not None and cp.separable:
        out.append(f"tilt × Earth-rate coupling (estimated, removed): Ω⊥ tan ψ = "
                   f"{cp.amplitude_arcsec_s:.5f} ± {cp.u_amplitude_arcsec_s:.5f}″/s, largest "
                   f"effect on a reading {cp.max_effect_arcsec:.3f}″")
    elif cp is not None:
        out.append(f"WARNING: {cp.note}")
    else:
        out.append("tilt × Earth-rate coupling not estimated (--no-coupling)")
    bad = res.harmonics[res.harmonics.table_status == "unobservable"].order.tolist()
    if bad:
        out.append("table harmonics not separable from the goniometer (multiples of n): "
                   + ", ".join(map(str, bad)))
    return "\n".join(out)


def run(args) -> int:
    """Run ``gonio eda``; returns the exit code."""
    from gonio.analysis.equal_division import equal_division_from_readings
    from gonio.atomic import check_output_files
    from gonio.formats.readings import read_readings
    from gonio.protocol import load_protocol
    from gonio.report.figure_files import FIGURE_FORMATS

    if args.plot is not None:      # before the work: place, suffix, data file, another set's
        check_output_files({"--plot": args.plot}, inputs=[args.readings],
                           formats={"--plot": FIGURE_FORMATS})
    proto = load_protocol(args.protocol)
    sess = proto.session
    res = equal_division_from_readings(
        read_readings(args.readings), starts=args.starts, gauge=args.gauge, noise=args.noise,
        protocol=proto.equal_division, coupling=not args.no_coupling,
        compensation_time_s=sess.static_s if sess.earth_compensation == "measured" else None)
    if args.plot:
        from gonio.report.eda_figure import equal_division_figure
        from gonio.report.figure_files import save_figure
        save_figure(equal_division_figure(res), args.plot)
    if args.json:
        print(json.dumps(json_safe(res.to_dict()), indent=2, allow_nan=False))
    else:
        print(_text(res))
    return 0
