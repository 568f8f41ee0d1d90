"""The optical draft's ``gonio`` sub-commands (``Specification.commands``; gonio's command
line registers them through the registry, :func:`gonio.specs.commands`): the tools around its
calibration that no other specification uses.

Its own options of gonio's commands (``SPEC.arguments``): ``gonio calibrate --budget|--tilt``
(:func:`add_calibrate_options`), ``gonio simulate --table|--stream|--stream-format``
(:func:`add_simulate_options`), the Annex A inputs of ``gonio budget``
(:func:`add_budget_options`) and the settings of its ``gonio validate`` study
(:func:`add_validate_options`). ``gonio reduce``: stream → readings file (find the table's
rests, match the protocol's rounds; :func:`gonio.specs.ogam_draft.reduce.reduce_stream`).
``gonio tilt``: the extreme tilt error over
0–360° (draft Annex A.4.2; :mod:`gonio.specs.ogam_draft.tilt`). ``gonio tilt-estimate``: ψ and α from
the static multi-position rows of a readings file
(:func:`gonio.specs.ogam_draft.tilt_estimate.tilt_estimate_from_readings`). ``gonio eda``:
equal-division averaging of a readings file's ``equal_division`` rows (IEC 62047-20 Annex A.3;
:func:`gonio.specs.ogam_draft.equal_division.equal_division_from_readings`).

This module sits on the command line's layer (it imports ``gonio.cli.checks``); nothing
imports it but the command line, when it builds its parser.
"""

from __future__ import annotations

import json
import math

from gonio.atomic import check_output_file
from gonio.cli.checks import LARGE, float_range, int_range, json_safe, positive_magnitude
from gonio.errors import GonioError, check_input_file
from gonio.units import ARCSEC_PER_DEG


# --------------------------------------------------------------------------- gonio calibrate

def add_calibrate_options(group) -> None:
    """The draft's own ``gonio calibrate`` options (``SPEC.arguments["calibrate"]``): E's budget,
    a measured tilt bound and a calibrated table."""
    group.add_argument("--budget", choices=("physical", "draft"), default=None,
                       help="E's budget: physical (default: Annex A plus the lines beyond the "
                            "draft the validation showed to matter) or draft (the annex's four "
                            "lines)")
    group.add_argument("--tilt", default=None, metavar="FILE",
                       help="a 'gonio tilt-estimate --json' result: bounds the tilt by psi + "
                            "U95 instead of the protocol's tilt bound")
    group.add_argument("--table-calibration", default=None, metavar="FILE",
                       help="the rotary table's calibration (CSV table_deg,error_arcsec,"
                            "u_arcsec[,dof]; docs/formats.md): K's 7.1 rounds corrected by it, "
                            "its table line the calibration's u instead of the MPE's; with "
                            "a --lab file naming [table_calibration] it must be that file's "
                            "content (SHA-256), else refused")


# --------------------------------------------------------------------------- gonio simulate

def add_simulate_options(group) -> None:
    """The draft's own ``gonio simulate`` options (``SPEC.arguments["simulate"]``): a table
    file overriding the bench's, and the stream of every sample."""
    group.add_argument("--table", default=None, metavar="FILE",
                       help="table file overriding the bench's (the precision table the draft's "
                            "items are measured against)")
    group.add_argument("--stream", action="store_true",
                       help="also write the stream (every sample: time, wrapped counter, table "
                            "angle; docs/formats.md#stream-file), chunk by chunk, with progress "
                            "on a terminal")
    group.add_argument("--stream-format", choices=("parquet", "csv"), default=None,
                       help="stream.parquet (default; pyarrow, the metadata as Parquet "
                            "key-value metadata) or stream.csv")


# --------------------------------------------------------------------------- gonio bench serve

def add_serve_options(group) -> None:
    """The draft's own ``gonio bench serve`` options (``SPEC.arguments["bench serve"]``): the
    served table's stated range and how long the goniometer has been on (the hook's
    defaults, ±360° and an hour, when not given)."""
    group.add_argument("--range-deg", dest="range_deg", type=positive_magnitude, default=None,
                       help="the served table's stated range, ±degrees (default 360)")
    group.add_argument("--warm-up", dest="warm_up_s", type=float_range(0, LARGE), default=None,
                       metavar="S", help="seconds the goniometer has been on when serving "
                                         "starts (default: an hour)")


# --------------------------------------------------------------------------- gonio budget

def add_budget_options(group) -> None:
    """The draft's own ``gonio budget`` options (``SPEC.arguments["budget"]``): the inputs
    of its Annex A budget of E (u(P), u(φ_e), u(B_E), u(r), U = k·u_c; defaults: the annex's)."""
    group.add_argument("--table-mpe-arcsec", type=float_range(0, ARCSEC_PER_DEG), default=None,
                       metavar="A", help="standard table MPE in arc-seconds (A.4.1; default 0.1)")
    group.add_argument("--tilt-deg", type=float_range(0, 45), default=None, metavar="PSI",
                       help="sensing-plane tilt in degrees (A.4.2; default 0.1)")
    group.add_argument("--zero-stability-dph", type=float_range(0, 1e4), default=None,
                       metavar="B", help="zero stability in °/h (A.4.3; default 0.005)")
    group.add_argument("--duration-min", type=float_range(0, 1e4), default=None, metavar="T",
                       help="time from start to reading in minutes (A.4.3; default 0.5)")
    group.add_argument("--repeatability-arcsec", type=float_range(0, ARCSEC_PER_DEG),
                       default=None, metavar="S",
                       help="repeatability u(r) in arc-seconds (A.4.4; default 0.096)")
    group.add_argument("--k", type=float_range(0, 10, lo_open=True), default=None,
                       help="coverage factor (A.7; default 2)")


# --------------------------------------------------------------------------- gonio validate

def add_validate_options(group) -> None:
    """The draft's own ``gonio validate`` options (``SPEC.arguments["validate"]``): the
    settings of its study of the Annex A budget of E over bench cases (7.1 + 7.4 with 10
    series; :func:`gonio.specs.ogam_draft.study.plan_study`)."""
    from gonio.analysis.cases import add_cases_option

    add_cases_option(group)
    group.add_argument("--truth", default=None,
                       help="truth of the printed table (all are in the JSON; an unknown one "
                            "is refused naming the known ones)")
    group.add_argument("--extra-components", nargs="?", const="all", default=None,
                       metavar="NAMES",
                       help="also evaluate the budget with the components the annex lacks: "
                            "all, or a comma-separated subset of their symbols")
    group.add_argument("--u-scale", type=float_range(0, 100, lo_open=True), default=None,
                       help="multiply U (default 1; < 1 deliberately breaks the budget)")
    group.add_argument("--sample-rate-hz", type=float_range(1, 1e5), default=None,
                       help="simulation rate (default 100 Hz; the RLG counter is exact at any "
                            "rate)")
    group.add_argument("--all-items", action="store_true",
                       help="keep 7.3, 7.6 and 7.7 so that every item's coverage is measured")
    group.add_argument("--monte-carlo", type=int_range(0), default=None, metavar="N",
                       help="also run the JCGM 101 Monte Carlo (N trials) of every item budget "
                            "of each case's first calibration and validate its GUM result "
                            "(JCGM 101 8.2: pass/fail, d_low, d_high); 0 (default) off")


# --------------------------------------------------------------------------- gonio reduce

def add_reduce(sub) -> None:
    """Add ``gonio reduce`` to the sub-parsers ``sub``."""
    p = sub.add_parser("reduce", help="reduce a stream file to a readings file",
                       description="Find the table's rests in a stream (docs/formats.md#stream-file), "
                                   "match them to the protocol's rounds and write the readings "
                                   "file (§1). Rounds that cannot be matched are listed with the "
                                   "reason; --override gives their times explicitly.")
    p.add_argument("stream", help="stream file (CSV, or Parquet: *.parquet); read in blocks, "
                   "in bounded memory")
    p.add_argument("--protocol", default=None,
                   help="protocol file or built-in name (default: the default specification's)")
    p.add_argument("--out", required=True, help="readings file to write")
    p.add_argument("--override", default=None,
                   help="CSV test,series,round,t_zero_s,t_read_s[,rate_dps,orientation]")
    p.add_argument("--force", action="store_true",
                   help="replace an existing readings file at --out")
    p.add_argument("--max-gap", type=float_range(0, LARGE, lo_open=True), default=None, metavar="S",
                   help="largest allowed time step in the stream, s (default 10× median)")
    p.add_argument("--json", action="store_true", help="print the reduction summary as JSON")
    p.set_defaults(func=run_reduce)


def run_reduce(args) -> int:
    """Reduce the stream, write the readings file, print the summary."""
    if args.max_gap is not None and not args.max_gap > 0:
        raise GonioError(f"--max-gap must be > 0, got {args.max_gap}")
    check_input_file(args.stream, "stream file")
    check_output_file(args.out, inputs=[args.stream, args.protocol, args.override],
                      force=args.force, protected=True)
    from gonio.specs.ogam_draft.override import read_override
    from gonio.specs.ogam_draft.readings import write_readings
    from gonio.formats.streams import StreamFile
    from gonio.progress import status
    from gonio.specs.ogam_draft.protocol import load_protocol
    from gonio.specs.ogam_draft.reduce import reduce_stream
    from gonio.specs.ogam_draft import SPEC

    proto = load_protocol(args.protocol or SPEC.default_protocol)
    override = read_override(args.override) if args.override else None
    status(f"reduce: reading {args.stream}")
    stream = StreamFile(args.stream, max_gap_s=args.max_gap)
    status("reduce: finding rests and matching rounds")
    red = reduce_stream(stream, proto, override=override)
    status("")
    if not len(red.readings):
        raise GonioError("no round of the protocol could be matched in the stream "
                         f"({len(red.rests)} rests found)", file=args.stream)
    reduced = red.readings.drop(columns=["t_zero_s", "t_read_s"])
    from gonio.formats.provenance import file_provenance
    if file_provenance(args.stream)["virtual"]:
        # the virtual bench's stream (by its lines or by its watermark): its readings carry
        # the mark too, whatever lines were deleted (docs/formats.md#watermark)
        from gonio.atomic import write_text
        from gonio.formats.watermark import mark_text
        from gonio.specs.ogam_draft.readings import format_readings
        write_text(args.out, mark_text(format_readings(reduced, red.metadata)))
    else:
        write_readings(reduced, args.out, red.metadata)
    if args.json:
        d = red.to_dict()
        d["out"] = str(args.out)
        print(json.dumps(d, indent=2, ensure_ascii=False, allow_nan=False))
    else:
        print(f"{args.out}: {len(red.readings)} readings from {len(red.rests)} rests")
        for u in red.unmatched:
            if u["kind"] == "round":
                print(f"  unmatched {u['test']} series {u['series']} round {u['round']}: "
                      f"{u['reason']}")
    return 0


# --------------------------------------------------------------------------- gonio tilt

def add_tilt(subparsers) -> None:
    """Add ``gonio tilt`` to the sub-parsers ``subparsers``."""
    p = subparsers.add_parser(
        "tilt", help="extreme error from a sensing-plane tilt (Annex A.4.2)",
        description="Largest error over 0-360° caused by a tilt between the gyro's sensing "
                    "plane and the table plane, and the table angles where it occurs.")
    p.add_argument("--tilt-deg", type=float_range(0, 45), default=0.1, metavar="PSI",
                   help="tilt in degrees, 0 <= PSI < 90 (default 0.1)")
    p.add_argument("--model", choices=("elliptic", "rigid"), default="elliptic",
                   help="elliptic projection (the draft's) or rigid-body rate gyro")
    p.add_argument("--uncalibrated", action="store_true",
                   help="rigid model only: before the scale-factor calibration")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=run_tilt)


def run_tilt(args) -> int:
    """Compute and print the extreme tilt error."""
    from gonio.specs.ogam_draft.tilt import elliptic_extreme, rigid_extreme

    t = args.tilt_deg
    if not (math.isfinite(t) and 0.0 <= t < 90.0):
        raise GonioError(f"--tilt-deg: must satisfy 0 <= tilt < 90 degrees, got {t}")
    if args.model == "elliptic":
        e = elliptic_extreme(t)
    else:
        e = rigid_extreme(t, calibrated=not args.uncalibrated)
    if args.json:
        print(json.dumps({"extreme_arcsec": e.extreme_arcsec, "at_deg": list(e.at_deg),
                          "model": e.model, "tilt_deg": e.tilt_deg}, indent=2))
    else:
        where = ", ".join(f"{a:.4f}°" for a in e.at_deg) or "(none: zero everywhere)"
        print(f"{e.model} model, tilt {e.tilt_deg:g}°: extreme error {e.extreme_arcsec:.4f}\u2033 "
              f"at {where}")
    return 0


# --------------------------------------------------------------------------- gonio tilt-estimate

def add_tilt_estimate(subparsers) -> None:
    """Add ``gonio tilt-estimate`` to the sub-parsers ``subparsers``."""
    p = subparsers.add_parser(
        "tilt-estimate", help="estimate the sensing-axis tilt from a static multi-position test",
        description="Fit c0 + a cos θ + b sin θ to the mean rates of the tilt_estimate rows "
                    "and report ψ = asin(hypot(a, b)/Ω_⊥) and the tilt azimuth α with their "
                    "standard uncertainties (residual-based covariance).")
    p.add_argument("file", metavar="FILE", help="readings CSV with tilt_estimate rows")
    p.add_argument("--scale-factor", type=positive_magnitude, default=None, metavar="K",
                   help="counts/° (default: the file's nominal_scale_factor_counts_per_deg)")
    p.add_argument("--latitude-deg", type=float_range(-90, 90), default=None, metavar="PHI",
                   help="site latitude (default: the file's latitude_deg)")
    p.add_argument("--u-latitude-deg", type=float_range(0, 90), default=0.0, metavar="U",
                   help="standard uncertainty of the latitude, degrees (default 0)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=run_tilt_estimate)


#: The readings' metadata a ``tilt-estimate --json`` result carries: the instrument's identity
#: (compared by :func:`gonio.pipeline.identity.check_identity`) and where the readings came
#: from (:func:`gonio.formats.provenance.provenance`).
TILT_JSON_METADATA = ("serial", "model", "manufacturer", "gyro_type", "instrument", "bench",
                      "seed", "noise", "generator")


def run_tilt_estimate(args) -> int:
    """Read the file, estimate, print."""
    from gonio.specs.ogam_draft.tilt_estimate import tilt_estimate_from_readings
    from gonio.specs.ogam_draft.readings import read_readings

    r = read_readings(args.file)
    e = tilt_estimate_from_readings(r, args.scale_factor, args.latitude_deg, args.u_latitude_deg)
    if args.json:
        # the readings' identity and provenance travel with the result: a calibration given
        # it (--tilt FILE) checks them as it checks its own readings'
        # and so do the readings' file, digest and provenance (their watermark included),
        # under a check: a result that does not show them is refused there
        from gonio.formats.provenance import result_source
        md = {k: str(r.metadata[k]) for k in TILT_JSON_METADATA if str(r.metadata.get(k) or "")}
        print(json.dumps(result_source(args.file, {**e.to_dict(), "metadata": md}), indent=2))
        return 0
    print(f"in-situ tilt estimate: {e.n_positions} positions, axis {e.orientation}, "
          f"latitude {e.latitude_deg:g}°, Ω_⊥ = {e.perpendicular_arcsec_s:.4f}″/s")
    print(f"first harmonic {e.amplitude_arcsec_s:.5f}″/s (u {e.u_amplitude_arcsec_s:.5f}), "
          f"residual s = {e.residual_sd_arcsec_s:.5f}″/s, ν = {e.dof} ({e.basis})")
    if e.left_out_deg:
        print("left out of the fit (opposite partner missing): "
              + ", ".join(f"{x:g}°" for x in e.left_out_deg))
    print(f"tilt ψ = {e.tilt_deg:.4f}°, u(ψ) = {e.u_tilt_deg:.4f}° "
          f"(U95 = {e.k95 * e.u_tilt_deg:.4f}°, k = {e.k95:.2f})")
    print(f"tilt azimuth relative to Ω_⊥ at table 0°: {e.phase_deg:.2f}°, u = {e.u_phase_deg:.2f}°")
    return 0


# --------------------------------------------------------------------------- gonio eda

def add_eda(subparsers) -> None:
    """Add ``gonio eda`` to the sub-parsers ``subparsers``."""
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
    p.set_defaults(func=run_eda)


def eda_text(res) -> str:
    """The printed form of an equal-division result (an
    :class:`~gonio.specs.ogam_draft.equal_division.EdaResult`: tables, closure, coupling)."""
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


def run_eda(args) -> int:
    """Run ``gonio eda``; returns the exit code."""
    from gonio.specs.ogam_draft.equal_division import equal_division_from_readings
    from gonio.atomic import check_output_files
    from gonio.specs.ogam_draft.readings import read_readings
    from gonio.specs.ogam_draft.protocol import load_protocol
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
        from gonio.specs.ogam_draft.pages import equal_division_figure
        from gonio.report.figure_files import save_figure
        save_figure(equal_division_figure(res), args.plot)
    if args.json:
        print(json.dumps(json_safe(res.to_dict()), indent=2, allow_nan=False))
    else:
        print(eda_text(res))
    return 0
